/* Run-time choice of the batch kernels (simd/).  The ISAs are the lines of
 * simd/isa_list.h that the compiler's target keeps (the Makefile compiles the
 * same list); each context records its table at creation.  The CPU checks run
 * once (pthread_once). */
#include "internal.h"
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#if defined(__x86_64__)
#include <cpuid.h>
#endif

#ifndef SHL_BUILD_CFLAGS
#define SHL_BUILD_CFLAGS "unknown"
#endif
#ifdef __VERSION__
#define SHL_COMPILER __VERSION__
#else
#define SHL_COMPILER "unknown"
#endif

#if defined(__x86_64__)
/* AVX2 and FMA usable: CPUID.1:ECX reports FMA (bit 12), OSXSAVE (27) and AVX (28),
 * XGETBV(0) shows the OS saves XMM and YMM state (bits 1, 2), CPUID.7.0:EBX reports AVX2 (5). */
static int shl__cpu_avx2(void)
{
    unsigned a, b, c, d;
    if (!__get_cpuid(1, &a, &b, &c, &d)) return 0;
    if (!((c >> 12) & 1) || !((c >> 27) & 1) || !((c >> 28) & 1)) return 0;
    unsigned xcr0_lo, xcr0_hi;
    __asm__ volatile("xgetbv" : "=a"(xcr0_lo), "=d"(xcr0_hi) : "c"(0));
    (void)xcr0_hi;
    if ((xcr0_lo & 6u) != 6u) return 0;
    if (__get_cpuid_max(0, NULL) < 7) return 0;
    __cpuid_count(7, 0, a, b, c, d);
    return (b >> 5) & 1;
}

#ifdef SHL_AVX512_EMULATE
/* make AVX512_EMULATE=1: the avx512 kernels are SIMDe's emulation of AVX-512
 * in AVX2 + FMA code (simd/isa_list.h), so they run where avx2 does. */
static int shl__cpu_avx512(void) { return shl__cpu_avx2(); }
#else
/* AVX-512 F, DQ, VL and BW usable (with AVX2 and FMA): CPUID.7.0:EBX reports
 * them (bits 16, 17, 31, 30), XGETBV(0) shows the OS saves XMM, YMM, opmask,
 * ZMM_Hi256 and Hi16_ZMM state (bits 1, 2, 5, 6, 7). */
static int shl__cpu_avx512(void)
{
    if (!shl__cpu_avx2()) return 0;
    unsigned a, b, c, d, xcr0_lo, xcr0_hi;
    __asm__ volatile("xgetbv" : "=a"(xcr0_lo), "=d"(xcr0_hi) : "c"(0));
    (void)xcr0_hi;
    if ((xcr0_lo & 0xE6u) != 0xE6u) return 0;
    __cpuid_count(7, 0, a, b, c, d);
    const unsigned need = 1u << 16 | 1u << 17 | 1u << 30 | 1u << 31;
    return (b & need) == need;
}
#endif /* SHL_AVX512_EMULATE */
#endif

#define SHL_ISA(name, flags, cpu) SHL__DECLARE_KERNELS(name)
#include "../simd/isa_list.h"
#undef SHL_ISA

static const shl__isa isas[] = {
#define SHL_ISA(isa, flags, cpu)                                                                       \
    {                                                                                                  \
        .name = #isa,                                                                                  \
        .poly_work_bytes = shl__poly_work_bytes_##isa,                                                 \
        .poly_batch = shl__poly_batch_##isa,                                                           \
        .poly_acc_floats = shl__poly_acc_floats_##isa,                                                 \
        .poly_batch_acc = shl__poly_batch_acc_##isa,                                                   \
        .poly_acc_finish = shl__poly_acc_finish_##isa,                                                 \
        .sphere_work_bytes = shl__sphere_work_bytes_##isa,                                             \
        .sphere_batch = shl__sphere_batch_##isa,                                                       \
        .interp_f = shl__interp_f_##isa,                                                               \
        .interp_ff = shl__interp_ff_##isa,                                                             \
        .interp_setup_ff = shl__interp_setup_ff_##isa,                                                 \
        .accumulate = shl__accumulate_##isa,                                                           \
        .poly_zh = shl__poly_zh_##isa,                                                                 \
        .poly_grad_sh = shl__poly_grad_sh_##isa,                                                       \
        .poly_sh = shl__poly_sh_##isa,                                                                 \
        .poly_hess = shl__poly_hess_##isa,                                                             \
    },
#include "../simd/isa_list.h"
#undef SHL_ISA
};
enum { NISA = sizeof isas / sizeof isas[0] };

static pthread_once_t init_once = PTHREAD_ONCE_INIT;
static int supported[NISA]; /* written once under init_once */

static void init(void)
{
    int i = 0;
#define SHL_ISA(name, flags, cpu) supported[i++] = (cpu) != 0;
#include "../simd/isa_list.h"
#undef SHL_ISA
}

const shl__isa *shl__isa_find(const char *name)
{
    pthread_once(&init_once, init);
    for (int i = 0; i < NISA; ++i)
        if (supported[i] && !strcmp(name, isas[i].name)) return &isas[i];
    return NULL;
}

/* The last supported line of simd/isa_list.h, unless SHLIGHT_ISA names a
 * compiled-in one this CPU supports; any other value (unknown, not compiled
 * in, unsupported) is ignored. */
const shl__isa *shl__isa_select(void)
{
    const char *want = getenv("SHLIGHT_ISA");
    const shl__isa *isa = want ? shl__isa_find(want) : NULL;
    if (isa) return isa;
    pthread_once(&init_once, init);
    for (int i = NISA - 1; i > 0; --i)
        if (supported[i]) return &isas[i];
    return &isas[0];
}

const char *shl_ctx_isa(const shl_ctx *ctx) { return ctx ? ctx->isa->name : ""; }

const char *shl_build_info(void)
{
    return "shlight " SHL_VERSION_STRING "; compiler: " SHL_COMPILER "; flags: " SHL_BUILD_CFLAGS "; batch ISAs:"
#define SHL_ISA(name, flags, cpu) " " #name " (" flags ")"
#include "../simd/isa_list.h"
#undef SHL_ISA
        ;
}

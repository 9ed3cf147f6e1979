/* Runtime choice of the batch kernels (simd/).  The Makefile compiles the
 * AVX2 kernel on x86-64 (SHL_HAVE_AVX2) and the NEON kernel on AArch64
 * (SHL_HAVE_NEON); the scalar kernel always.  Each context records its table
 * at creation; the CPU check and the float lobe tables are done once
 * (pthread_once). */
#include "../simd/batch.h"
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#if defined(SHL_HAVE_AVX2) && (defined(__x86_64__) || defined(__i386__))
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
#ifdef SHL_HAVE_AVX2
#define SHL_ISAS_AVX2 " avx2 (-mavx2 -mfma)"
#else
#define SHL_ISAS_AVX2 ""
#endif
#ifdef SHL_HAVE_NEON
#define SHL_ISAS_NEON " neon"
#else
#define SHL_ISAS_NEON ""
#endif

float shl__zh_dir_f[SHL__ZH_NDIR][3];
float shl__zh_even_w_f[SHL__ZH_EVEN_SIZE];
float shl__zh_odd_w_f[SHL__ZH_ODD_SIZE];

const shl__isa shl__isa_scalar = {
    .name = "scalar",
    .vlen = 1,
    .poly_work_bytes = shl__poly_work_bytes_scalar,
    .poly_batch = shl__poly_batch_scalar,
    .sphere_work_bytes = shl__sphere_work_bytes_scalar,
    .sphere_batch = shl__sphere_batch_scalar,
    .interp_f = shl__interp_ref_f,
    .accumulate = shl__accumulate_scalar,
};
#ifdef SHL_HAVE_AVX2
const shl__isa shl__isa_avx2 = {
    .name = "avx2",
    .vlen = 8,
    .poly_work_bytes = shl__poly_work_bytes_avx2,
    .poly_batch = shl__poly_batch_avx2,
    .sphere_work_bytes = shl__sphere_work_bytes_avx2,
    .sphere_batch = shl__sphere_batch_avx2,
    .interp_f = shl__interp_f_avx2,
    .accumulate = shl__accumulate_avx2,
};
#endif
#ifdef SHL_HAVE_NEON
const shl__isa shl__isa_neon = {
    .name = "neon",
    .vlen = 4,
    .poly_work_bytes = shl__poly_work_bytes_neon,
    .poly_batch = shl__poly_batch_neon,
    .sphere_work_bytes = shl__sphere_work_bytes_neon,
    .sphere_batch = shl__sphere_batch_neon,
    .interp_f = shl__interp_f_neon,
    .accumulate = shl__accumulate_neon,
};
#endif

static pthread_once_t init_once = PTHREAD_ONCE_INIT;
static int cpu_avx2; /* written once under init_once */

#if defined(SHL_HAVE_AVX2) && (defined(__x86_64__) || defined(__i386__))
/* AVX2 and FMA usable: CPUID.1:ECX reports FMA (bit 12), OSXSAVE (27) and AVX (28),
 * XGETBV(0) shows the OS saves XMM and YMM state (bits 1, 2), CPUID.7.0:EBX reports AVX2 (5). */
static int detect_avx2(void)
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
#else
static int detect_avx2(void) { return 0; }
#endif

static void init(void)
{
    cpu_avx2 = detect_avx2();
    for (int d = 0; d < SHL__ZH_NDIR; ++d)
        for (int k = 0; k < 3; ++k) shl__zh_dir_f[d][k] = (float)shl__zh_dir[d][k];
    for (int i = 0; i < SHL__ZH_EVEN_SIZE; ++i) shl__zh_even_w_f[i] = (float)shl__zh_even_w[i];
    for (int i = 0; i < SHL__ZH_ODD_SIZE; ++i) shl__zh_odd_w_f[i] = (float)shl__zh_odd_w[i];
}

const shl__isa *shl__isa_find(const char *name)
{
    pthread_once(&init_once, init);
    if (!strcmp(name, "scalar")) return &shl__isa_scalar;
#ifdef SHL_HAVE_AVX2
    if (!strcmp(name, "avx2") && cpu_avx2) return &shl__isa_avx2;
#endif
#ifdef SHL_HAVE_NEON
    if (!strcmp(name, "neon")) return &shl__isa_neon;
#endif
    return NULL;
}

/* Best supported table, unless SHLIGHT_ISA names a compiled-in one this CPU
 * supports; any other value (unknown, not compiled in, unsupported) is ignored. */
const shl__isa *shl__isa_select(void)
{
    const char *want = getenv("SHLIGHT_ISA");
    const shl__isa *isa = want ? shl__isa_find(want) : NULL;
    if (isa) return isa;
    if ((isa = shl__isa_find("avx2")) || (isa = shl__isa_find("neon"))) return isa;
    return &shl__isa_scalar;
}

const char *shl_ctx_isa(const shl_ctx *ctx) { return ctx ? ctx->isa->name : ""; }

const char *shl_build_info(void)
{
    return "shlight " SHL_VERSION_STRING "; compiler: " SHL_COMPILER "; flags: " SHL_BUILD_CFLAGS
           "; batch ISAs: scalar" SHL_ISAS_AVX2 SHL_ISAS_NEON;
}

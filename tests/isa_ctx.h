/* The ISAs compiled into this build (the lines of simd/isa_list.h the target
 * keeps) and a context whose batch kernels are those of one of them, for the
 * SIMD tests. */
#ifndef SHL_TEST_ISA_CTX_H
#define SHL_TEST_ISA_CTX_H

#include "harness.h"
#include "shlight.h"
#include <string.h>

static const char *const isas[] = {
#define SHL_ISA(name, flags, cpu) #name,
#include "../simd/isa_list.h"
#undef SHL_ISA
};
enum { NISA = sizeof isas / sizeof isas[0] };

/* Context whose batch kernels are isa, or NULL when this CPU cannot run it. */
static inline shl_ctx *isa_ctx(const char *isa, int lmax)
{
    shl_ctx *ctx = NULL;
    const int st = shl_ctx_create_isa(lmax, isa, &ctx);
    CHECK(st == SHL_OK || st == SHL_EDOMAIN);
    CHECK((st == SHL_OK) == (ctx != NULL));
    if (ctx) CHECK(strcmp(shl_ctx_isa(ctx), isa) == 0);
    return ctx;
}

#endif

/* A context whose batch kernels are those of one ISA (SHLIGHT_ISA set while it
 * is created, then restored), for the SIMD tests. */
#ifndef SHL_TEST_ISA_CTX_H
#define SHL_TEST_ISA_CTX_H

#include "harness.h"
#include "shlight.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const isas[] = {"scalar", "avx2", "neon"};
enum { NISA = sizeof isas / sizeof isas[0] };

/* Context whose batch kernels are isa, or NULL when this machine cannot run it. */
static inline shl_ctx *isa_ctx(const char *isa, int lmax)
{
    const char *old = getenv("SHLIGHT_ISA");
    char saved[64] = "";
    if (old) snprintf(saved, sizeof saved, "%s", old);
    setenv("SHLIGHT_ISA", isa, 1);
    shl_ctx *ctx = NULL;
    CHECK(shl_ctx_create(lmax, &ctx) == SHL_OK);
    if (old) setenv("SHLIGHT_ISA", saved, 1);
    else unsetenv("SHLIGHT_ISA");
    if (ctx && strcmp(shl_ctx_isa(ctx), isa) != 0) {
        shl_ctx_destroy(ctx);
        return NULL;
    }
    return ctx;
}

#endif

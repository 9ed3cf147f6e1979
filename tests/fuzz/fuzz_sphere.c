/* libFuzzer target: shl_sphere, shl_sphere_grad, shl_sphere_f, shl_sphere_grad_f
 * (and shl_zh_cap on the same cap).
 *
 * Input: lmax byte, flags byte (bit 0: float, bits 1-3: NULL argument), mode byte,
 * then x, centre and radius: any values, or the centre at an exact offset from
 * x and a radius relative to the distance (tiny, near tangent from either side,
 * exactly tangent, inside, at the centre).
 * Properties:
 *  - status SHL_OK or the documented code (NULL, non-finite x / centre /
 *    radius, radius <= 0); nothing written on error;
 *  - finite outputs (gradient: unless its bound exceeds DBL_MAX / 1e10, resp.
 *    FLT_MAX / 1e4);
 *  - inside the sphere (long-double distance < radius by a margin): exactly
 *    L_00 = sqrt(4 pi), every other coefficient 0, gradient 0 (documented);
 *  - outside (by a margin), with the cap's 1 - cos a = t computed in long double
 *    (t = s^2 / (1 + sqrt(1 - s^2)), s = r / d):
 *      |L_lm| <= K_l 2 pi t + slack,   |L_00 - K_0 2 pi t| <= slack_0,
 *      |dL_lm/dx_a| <= K_l 2 pi s (1 + s/c) / d (1 + 1e-9) + ...   (moving boundary:
 *        the cap's rim, of length 2 pi sin a, moves at most (1 + tan a)/d per unit move)
 *    slack = K_l 2 pi (1e-9 t + dt) + K_l 2 pi t (l+1)^2 du, with dt = 4 eps S s^2 / (c d)
 *    the change of t and du = 4 eps S / d the turn of the axis under the rounding of
 *    c - x (S = largest coordinate): the input's own conditioning; 1e-9 is 1e5 times
 *    the measured 1.2e-14 (test_sphere.c); slack_0 uses 1e-11.  Float: 1e-4 relative
 *    (test_sphere.c measures 3.5e-6 of max|coeff|) plus 1e-36 for underflow, and
 *    against shl_sphere on the same float input within that slack;
 *  - shl_zh_cap(lmax, a): |zh_l| <= K_l 2 pi t, zh_0 = K_0 2 pi t. */
#include "fuzz_common.h"

typedef struct {
    long double d, t, s, c, scale;
    int inside, outside; /* decided with a margin; neither: either answer is accepted */
} sph_geom;

static void sphere_geom(const double x[3], const double cen[3], double r, sph_geom *G)
{
    long double v[3], d2 = 0.0L;
    G->scale = 0.0L;
    for (int k = 0; k < 3; ++k) {
        v[k] = (long double)cen[k] - (long double)x[k];
        d2 += v[k] * v[k];
        G->scale = fmaxl(G->scale, fmaxl(fabsl(cen[k]), fabsl(x[k])));
    }
    G->d = sqrtl(d2);
    const long double margin = 8.0L * DBL_EPSILON * (G->scale + r);
    G->inside = G->d < (long double)r - margin;
    G->outside = G->d > (long double)r + margin;
    G->s = G->c = G->t = 0.0L;
    if (G->outside) {
        G->s = r / G->d;
        G->c = sqrtl((G->d - r) * (G->d + r)) / G->d;
        G->t = G->s * G->s / (1.0L + G->c);
    }
}

static void decode(fz_in *in, double x[3], double cen[3], double *r)
{
    const uint8_t mode = fz_u8(in);
    for (int k = 0; k < 3; ++k) x[k] = fz_real(in);
    if (mode % 4 == 0) { /* anything */
        for (int k = 0; k < 3; ++k) cen[k] = fz_real(in);
        *r = fz_real(in);
        return;
    }
    /* centre = x + offset (exact small integers times 2^e), radius relative to the distance */
    const int e = (int)(int8_t)fz_u8(in) * 4;
    double off[3];
    for (int k = 0; k < 3; ++k) off[k] = ldexp((int8_t)fz_u8(in), e);
    if (mode & 4) off[0] = ldexp(3.0, e), off[1] = ldexp(4.0, e), off[2] = 0.0; /* distance 5 * 2^e exactly */
    for (int k = 0; k < 3; ++k) cen[k] = x[k] + off[k];
    const long double d = sqrtl((long double)off[0] * off[0] + (long double)off[1] * off[1] + (long double)off[2] * off[2]);
    const uint8_t rel = fz_u8(in);
    switch (rel % 8) {
    case 0: *r = (double)(d * (1.0L - ldexpl(1.0L, -(int)(fz_u8(in) % 64)))); break; /* tangent from outside */
    case 1: *r = (double)(d * (1.0L + ldexpl(1.0L, -(int)(fz_u8(in) % 64)))); break; /* just inside */
    case 2: *r = (double)d; break;                                                     /* on the surface */
    case 3: *r = (double)(d * ldexpl(1.0L, -(int)(fz_u8(in) % 255) * 4)); break;       /* tiny */
    case 4: *r = (double)d * (1.0 + (int8_t)fz_u8(in) * DBL_EPSILON); break;           /* a few ulps */
    case 5: *r = ldexp(5.0, e); break;                                                 /* exact 3-4-5 */
    default: *r = (double)(d * (fz_u8(in) + 1) / 257.0L); break;
    }
    if (rel & 0x80) *r = -*r;
}

static long double grad_bound(const sph_geom *G, int l)
{
    if (!G->outside) return 0.0L;
    return fz_kl(l) * 2.0L * M_PI * G->s * (1.0L + G->s / G->c) / G->d;
}

static void check_double(const shl_ctx *ctx, int lmax, const double x[3], const double cen[3], double r, uint8_t flags)
{
    const int nc = SHL_NCOEFFS(lmax);
    double *c = fz_guarded(sizeof(double) * nc), *c2 = fz_guarded(sizeof(double) * nc);
    double *g = fz_guarded(sizeof(double) * 3 * nc);
    const int nul = (flags >> 1) & 7;
    const double *xx = nul == 1 ? NULL : x, *cc = nul == 2 ? NULL : cen;
    double *co = nul == 3 ? NULL : c, *go = nul == 4 ? NULL : g;
    int want = SHL_OK;
    if (!xx || !cc || !co) want = SHL_ENULL;
    else if (!all_finite_d(x, 3) || !all_finite_d(cen, 3) || !isfinite(r)) want = SHL_ENONFINITE;
    else if (!(r > 0.0)) want = SHL_EDOMAIN;
    const int st = shl_sphere(ctx, xx, cc, r, co);
    const int sg = shl_sphere_grad(ctx, xx, cc, r, nul == 3 ? NULL : c2, go);
    const int want_g = go ? want : SHL_ENULL; /* NULL is checked first */
    FUZZ_CHECK(st == want && sg == want_g, "status %d %d, want %d %d", st, sg, want, want_g);
    if (want != SHL_OK || want_g != SHL_OK) {
        FUZZ_CHECK(fz_untouched(c2, sizeof(double) * nc) && fz_untouched(g, sizeof(double) * 3 * nc),
                   "grad output written on error");
        if (want != SHL_OK) FUZZ_CHECK(fz_untouched(c, sizeof(double) * nc), "output written on error");
        goto done;
    }
    FUZZ_CHECK(all_finite_d(c, nc) && all_finite_d(c2, nc), "non-finite coefficient");
    FUZZ_CHECK(memcmp(c, c2, sizeof(double) * nc) == 0, "coefficients differ with the gradient");
    sph_geom G;
    sphere_geom(x, cen, r, &G);
    if (fz_is_verbose())
        fprintf(stderr, "d %.17Lg r %.17g inside %d outside %d t %.17Lg\n", G.d, r, G.inside, G.outside, G.t);
    if (G.inside) {
        FUZZ_CHECK(c[0] == sqrt(4.0 * M_PI), "inside: L00 %.17g", c[0]);
        for (int k = 1; k < nc; ++k) FUZZ_CHECK(c[k] == 0.0, "inside: L[%d] = %g", k, c[k]);
        for (int k = 0; k < 3 * nc; ++k) FUZZ_CHECK(g[k] == 0.0, "inside: grad[%d] = %g", k, g[k]);
        goto done;
    }
    if (!G.outside) goto done;
    if (grad_bound(&G, lmax) < DBL_MAX / 1e10)
        FUZZ_CHECK(all_finite_d(g, 3 * nc), "non-finite gradient");
    const long double eps = DBL_EPSILON, tp = 2.0L * M_PI;
    const long double rnd = 4.0L * (eps * G.scale + 0x1p-1074L); /* rounding of c - x, denormals included */
    const long double dt = rnd * G.s * G.s / (G.c * G.d), du = rnd / G.d;
    const long double gcond = rnd * grad_bound(&G, lmax) / (G.d * G.c * G.c); /* |d grad / dx| ~ grad / (d c^2) */
    for (int l = 0; l <= lmax; ++l) {
        const long double kl = fz_kl(l), slack = kl * tp * (1e-9L * G.t + dt + G.t * (l + 1) * (l + 1) * du) + 1e-300L;
        const long double gb = grad_bound(&G, l) * (1.0L + 1e-9L) + gcond * (l + 1) * (l + 1) + 1e-300L;
        for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
            FUZZ_CHECK(fabsl(c[k]) <= kl * tp * G.t + slack, "|L[%d]| = %.17g > K_l 2 pi t %.17Lg + %.3Lg", k, c[k],
                       kl * tp * G.t, slack);
            for (int a = 0; a < 3; ++a)
                if (isfinite(g[a * nc + k]) || !(gb < DBL_MAX / 1e10)) /* the true gradient may overflow */
                    FUZZ_CHECK(!isfinite(g[a * nc + k]) || fabsl(g[a * nc + k]) <= gb, "|dL[%d]/dx%d| = %.17g > bound %.17Lg",
                               k, a, g[a * nc + k], gb);
        }
    }
    const long double s0 = fz_kl(0) * tp * (1e-11L * G.t + dt) + 1e-300L;
    FUZZ_CHECK(fabsl(c[0] - fz_kl(0) * tp * G.t) <= s0, "L00 %.17g vs K0 2 pi t %.17Lg (slack %.3Lg)", c[0],
               fz_kl(0) * tp * G.t, s0);
    { /* the cap's ZH: shl_zh_cap at the same half-angle */
        const double a = (double)atan2l(G.s, G.c);
        double *zh = fz_guarded(sizeof(double) * (lmax + 1));
        FUZZ_CHECK(shl_zh_cap(lmax, a, zh) == SHL_OK, "shl_zh_cap(%d, %g)", lmax, a);
        const long double ta = 2.0L * sinl(0.5L * a) * sinl(0.5L * a); /* 1 - cos a of the rounded angle */
        for (int l = 0; l <= lmax; ++l)
            FUZZ_CHECK(fabsl(zh[l]) <= fz_kl(l) * tp * ta * (1.0L + 1e-9L) + 1e-300L, "zh_cap[%d] = %g > %Lg", l, zh[l],
                       fz_kl(l) * tp * ta);
        FUZZ_CHECK(fabsl(zh[0] - fz_kl(0) * tp * ta) <= 1e-12L * fz_kl(0) * tp * ta + 1e-300L, "zh_cap[0] = %.17g vs %.17Lg",
                   zh[0], fz_kl(0) * tp * ta);
        free(zh);
    }
done:
    free(c);
    free(c2);
    free(g);
}

static void check_float(const shl_ctx *ctx, int lmax, const double xd0[3], const double cd0[3], double rd0)
{
    const int nc = SHL_NCOEFFS(lmax);
    const float xf[3] = {fz_to_float(xd0[0]), fz_to_float(xd0[1]), fz_to_float(xd0[2])};
    const float cf[3] = {fz_to_float(cd0[0]), fz_to_float(cd0[1]), fz_to_float(cd0[2])}, rf = fz_to_float(rd0);
    const double x[3] = {xf[0], xf[1], xf[2]}, cen[3] = {cf[0], cf[1], cf[2]}, r = rf;
    float *c = fz_guarded(sizeof(float) * nc), *c2 = fz_guarded(sizeof(float) * nc);
    float *g = fz_guarded(sizeof(float) * 3 * nc);
    double *cd = fz_guarded(sizeof(double) * nc);
    int want = SHL_OK;
    if (!all_finite_f(xf, 3) || !all_finite_f(cf, 3) || !isfinite(rf)) want = SHL_ENONFINITE;
    else if (!(rf > 0.0f)) want = SHL_EDOMAIN;
    const int st = shl_sphere_f(ctx, xf, cf, rf, c), sg = shl_sphere_grad_f(ctx, xf, cf, rf, c2, g);
    FUZZ_CHECK(st == want && sg == want, "float status %d %d, want %d", st, sg, want);
    if (want != SHL_OK) {
        FUZZ_CHECK(fz_untouched(c, sizeof(float) * nc) && fz_untouched(c2, sizeof(float) * nc) &&
                       fz_untouched(g, sizeof(float) * 3 * nc),
                   "float output written on error");
        goto done;
    }
    FUZZ_CHECK(all_finite_f(c, nc) && all_finite_f(c2, nc), "non-finite float coefficient");
    FUZZ_CHECK(shl_sphere(ctx, x, cen, r, cd) == SHL_OK, "double path");
    sph_geom G;
    sphere_geom(x, cen, r, &G);
    if (G.inside) {
        FUZZ_CHECK(c[0] == (float)sqrt(4.0 * M_PI), "float inside: L00 %.9g", c[0]);
        for (int k = 1; k < nc; ++k) FUZZ_CHECK(c[k] == 0.0f, "float inside: L[%d] = %g", k, c[k]);
        for (int k = 0; k < 3 * nc; ++k) FUZZ_CHECK(g[k] == 0.0f, "float inside: grad[%d] = %g", k, g[k]);
        goto done;
    }
    if (!G.outside) goto done;
    if (grad_bound(&G, lmax) < FLT_MAX / 1e4) FUZZ_CHECK(all_finite_f(g, 3 * nc), "non-finite float gradient");
    const long double eps = DBL_EPSILON, tp = 2.0L * M_PI;
    const long double rnd = 4.0L * (eps * G.scale + 0x1p-1074L); /* rounding of c - x, denormals included */
    const long double dt = rnd * G.s * G.s / (G.c * G.d), du = rnd / G.d;
    for (int l = 0; l <= lmax; ++l) {
        const long double kl = fz_kl(l);
        const long double slack = kl * tp * (1e-4L * G.t + dt + G.t * (l + 1) * (l + 1) * du) + kl * 1e-36L;
        const long double gcond = rnd * grad_bound(&G, l) / (G.d * G.c * G.c); /* as in double */
        const long double gb = grad_bound(&G, l) * (1.0L + 1e-4L) + gcond * (l + 1) * (l + 1) + kl * 1e-36L;
        for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
            FUZZ_CHECK(fabsl(c[k]) <= kl * tp * G.t + slack, "float |L[%d]| = %.9g > K_l 2 pi t %.9Lg + %.3Lg", k, c[k],
                       kl * tp * G.t, slack);
            FUZZ_CHECK(fabsl((long double)c[k] - cd[k]) <= slack, "float L[%d] %.9g vs double %.17g (slack %.3Lg)", k, c[k],
                       cd[k], slack);
            FUZZ_CHECK(c2[k] == c[k], "float coefficients differ with the gradient");
            for (int a = 0; a < 3; ++a)
                if (isfinite(g[a * nc + k]))
                    FUZZ_CHECK(fabsl(g[a * nc + k]) <= gb, "float |dL[%d]/dx%d| = %.9g > bound %.9Lg", k, a, g[a * nc + k], gb);
        }
    }
done:
    free(c);
    free(c2);
    free(g);
    free(cd);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_target_name = "fuzz_sphere";
    fz_in in = {data, size, 0};
    const int lmax = fz_lmax(&in);
    const uint8_t flags = fz_u8(&in);
    double x[3], cen[3], r;
    decode(&in, x, cen, &r);
    if (lmax < 0 || lmax > SHL_LMAX_MAX) {
        double zh[SHL_LMAX_MAX + 2];
        memset(zh, FZ_GUARD_BYTE, sizeof zh);
        FUZZ_CHECK(shl_zh_cap(lmax, 0.5, zh) == SHL_ELMAX && fz_untouched(zh, sizeof zh), "zh_cap lmax %d", lmax);
        return 0;
    }
    fz_dump_vec("x", x, 3);
    fz_dump_vec("center", cen, 3);
    fz_dump_vec("radius", &r, 1);
    const shl_ctx *ctx = fz_ctx(lmax);
    if (flags & 1) check_float(ctx, lmax, x, cen, r);
    else check_double(ctx, lmax, x, cen, r, flags);
    return 0;
}

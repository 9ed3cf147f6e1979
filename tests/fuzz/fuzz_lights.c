/* libFuzzer target: light sets -- shl_lights_create / add_polygon / add_sphere /
 * count / eval / eval_batch / eval_batch_f / destroy.
 *
 * Input: lmax byte, flags byte (bit 0: gradients, bit 1: a NaN point in the
 * batch, bit 2: allocation failures, bit 3: NULL arguments), light count, per
 * light a kind byte, its geometry (fuzz_common.h polygon, or a sphere), rgb and
 * two_sided, then point count and points.
 * Properties:
 *  - every call returns SHL_OK or the documented code for its input (NULL,
 *    vertex count, two_sided not 0/1, non-finite, radius <= 0, SHL_ENOMEM when an
 *    allocation is made to fail); on error the set is unchanged (count) and, for
 *    eval / eval_batch, nothing is written (all batch points checked first);
 *  - eval_batch equals eval point by point, bit for bit;
 *  - the set equals the sum over its lights of rgb_c x shl_polygon_grad /
 *    shl_sphere_grad (one-sided polygons: only where n . (x - v_0) > 0, n the
 *    documented Newell normal), to 1e-9 of sum_i |rgb_ic| x (light i's scale):
 *    the set reconstructs accumulated lobe integrals once (reconstruction
 *    condition <= 22.8), test_lights.c measures 1.5e-15; plus, for lights whose
 *    L_00 (their solid angle) is in gradual underflow, |rgb_ic| x (light i's
 *    scale) x 4096 DBL_TRUE_MIN / |L_00,i|: their lobe integrals are subnormal,
 *    each accurate only to a few DBL_TRUE_MIN per operation (O(100) operations,
 *    times the reconstruction's condition number 22.8), and so are their
 *    gradients, however large the scaling back to x units makes these (a
 *    sphere of radius 1e-312 seen from 1e-154); 0 above L_00 ~ 1e-311; and
 *    sum_i |rgb_ic| 16 DBL_MIN absolute, which a huge rgb magnifies;
 *  - finite outputs whenever sum |rgb| 4 pi K_30 (n for raw polygons) stays
 *    below 1e290 (any coordinates: the geometry is scaled by powers of two);
 *    each polygon's shl_polygon_grad gradient finite whenever its moving-boundary
 *    bound K_l sum_e gamma_e / d_e (fz_raw_grad_bound: planar or not) is below 1e290;
 *  - with structured polygons and spheres: |rgb_c,lm| <= sum_i |rgb_ic| (K_l
 *    Omega_i + slack_i + 16 DBL_MIN) (the bounds of fuzz_polygon.c /
 *    fuzz_sphere.c, and the underflow floor above);
 *  - eval_batch_f on the float-rounded points: SHL_ENONFINITE (nothing written)
 *    iff a rounded point is not finite, SHL_ENOMEM under an allocation failure,
 *    zeros for an empty set, finite rgb whenever sum |rgb| 4 pi K_30 n stays below
 *    1e30, and each point's result independent of the batch (equal, bit for
 *    bit, to a call with that point alone). */
#include "fuzz_common.h"

enum { MAXL = 6, MAXP = 4 };

typedef struct {
    int kind; /* 1 polygon, 2 sphere */
    fz_poly P;
    double c[3], r, rgb[3];
    int two_sided;
    int added;
} light;

static light L[MAXL];

static int sphere_inside(const light *li, const double x[3], int *ambiguous)
{
    long double d2 = 0.0L, s = 0.0L;
    for (int k = 0; k < 3; ++k) {
        const long double v = (long double)li->c[k] - x[k];
        d2 += v * v;
        s = fmaxl(s, fmaxl(fabsl(li->c[k]), fabsl(x[k])));
    }
    const long double d = sqrtl(d2), m = 8.0L * DBL_EPSILON * (s + li->r);
    *ambiguous = fabsl(d - li->r) <= m;
    return d <= li->r;
}

/* front test as documented, n . (x - v_0) > 0 with the Newell normal n, in long
 * double (no over/underflow for any double input; lights.c scales by powers of two).
 * Ambiguous where the library's double evaluation may decide the other way: its normal
 * (src/internal.h shl__newell_scaled: rounded edge differences, cross products and an
 * n-term sum) is off by at most (n + 4) eps A_k per component, A_k the sum of the
 * cross products' term magnitudes |e_j f_l| + |e_l f_j|, and the dot product with the
 * rounded x - v_0 adds 4 eps sum_k |n_k (x_k - v_0k)|: at most (n + 5) eps (amag + mag)
 * <= 69 eps < 1e-12 of (amag + mag) for n <= 64 (amag = sum_k A_k |x_k - v_0k|); plus
 * the scaled differences' gradual underflow, at most 2^-1074 per operation in units of
 * the largest edge (2^(2 ee)) and of x - v_0 (2^ex): 64 n 2^-1074 2^(2 ee + ex). */
static int polygon_front(const light *li, const double x[3], int *ambiguous)
{
    const double *v = li->P.v;
    long double n[3] = {0.0L, 0.0L, 0.0L}, A[3] = {0.0L, 0.0L, 0.0L}, se = 0.0L, sx = 0.0L;
    for (int i = 1; i + 1 < li->P.n; ++i) {
        const double *p = v + 3 * i, *q = v + 3 * (i + 1);
        const long double e[3] = {(long double)p[0] - v[0], (long double)p[1] - v[1], (long double)p[2] - v[2]};
        const long double f[3] = {(long double)q[0] - v[0], (long double)q[1] - v[1], (long double)q[2] - v[2]};
        n[0] += e[1] * f[2] - e[2] * f[1];
        n[1] += e[2] * f[0] - e[0] * f[2];
        n[2] += e[0] * f[1] - e[1] * f[0];
        A[0] += fabsl(e[1] * f[2]) + fabsl(e[2] * f[1]);
        A[1] += fabsl(e[2] * f[0]) + fabsl(e[0] * f[2]);
        A[2] += fabsl(e[0] * f[1]) + fabsl(e[1] * f[0]);
        for (int k = 0; k < 3; ++k) se = fmaxl(se, fmaxl(fabsl(e[k]), fabsl(f[k])));
    }
    long double fd = 0.0L, mag = 0.0L, amag = 0.0L;
    for (int k = 0; k < 3; ++k) {
        const long double dx = (long double)x[k] - v[k];
        fd += n[k] * dx;
        mag += fabsl(n[k] * dx);
        amag += A[k] * fabsl(dx);
        sx = fmaxl(sx, fabsl(dx));
    }
    const long double underflow = 64.0L * li->P.n * 0x1p-1074L * (2.0L * se) * (2.0L * se) * (2.0L * sx);
    *ambiguous = fabsl(fd) <= 1e-12L * (mag + amag) + underflow;
    return fd > 0.0L;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_target_name = "fuzz_lights";
    fz_in in = {data, size, 0};
    const int lmax = fz_lmax(&in);
    const uint8_t flags = fz_u8(&in);
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return 0;
    const shl_ctx *ctx = fz_ctx(lmax);
    const int nc = SHL_NCOEFFS(lmax), with_grad = flags & 1, allocs = (flags >> 2) & 1;
    shl_lights *set = NULL;
    if (allocs) {
        shl__alloc_fail_after = 0;
        shl_lights *tmp = (shl_lights *)&in;
        FUZZ_CHECK(shl_lights_create(&tmp) == SHL_ENOMEM && tmp == NULL, "create: ENOMEM and *out = NULL expected");
        shl__alloc_fail_after = -1;
    }
    FUZZ_CHECK(shl_lights_create(&set) == SHL_OK && set, "create");
    FUZZ_CHECK(shl_lights_count(set) == 0, "empty count");
    const int nl = fz_u8(&in) % (MAXL + 1);
    int count = 0, all_structured = 1;
    long double magnitude = 0.0L;
    for (int i = 0; i < nl; ++i) {
        light *li = &L[i];
        memset(li, 0, sizeof *li);
        const uint8_t kind = fz_u8(&in);
        li->kind = kind & 1 ? 2 : 1;
        for (int c = 0; c < 3; ++c) li->rgb[c] = (kind & 2) ? fz_real(&in) : (int8_t)fz_u8(&in) / 16.0;
        int want = SHL_OK, st;
        const long fail = allocs ? fz_u8(&in) % 3 : -1;
        if (li->kind == 1) {
            fz_polygon(&in, &li->P);
            const uint8_t ts = fz_u8(&in);
            li->two_sided = ts < 250 ? ts & 1 : ts == 250 ? 2 : -1;
            if (!(li->P.n >= 3 && li->P.n <= SHL_MAX_VERTS)) want = SHL_ENVERTS;
            else if (li->two_sided != 0 && li->two_sided != 1) want = SHL_EDOMAIN;
            else if (!all_finite_d(li->P.v, 3 * li->P.n) || !all_finite_d(li->rgb, 3)) want = SHL_ENONFINITE;
            shl__alloc_fail_after = fail;
            st = shl_lights_add_polygon(set, li->P.v, li->P.n, li->rgb, li->two_sided);
        } else {
            const double *v0 = L[0].kind == 1 && i > 0 ? L[0].P.v : NULL;
            for (int k = 0; k < 3; ++k) li->c[k] = v0 && (kind & 4) ? v0[k] + fz_real(&in) : fz_real(&in);
            li->r = fz_real(&in);
            if (!all_finite_d(li->c, 3) || !all_finite_d(li->rgb, 3) || !isfinite(li->r)) want = SHL_ENONFINITE;
            else if (!(li->r > 0.0)) want = SHL_EDOMAIN;
            shl__alloc_fail_after = fail;
            st = shl_lights_add_sphere(set, li->c, li->r, li->rgb);
        }
        shl__alloc_fail_after = -1;
        FUZZ_CHECK(st == want || (st == SHL_ENOMEM && want == SHL_OK && fail >= 0), "add light %d (kind %d): %d, want %d",
                   i, li->kind, st, want);
        if (st == SHL_OK) ++count;
        FUZZ_CHECK(shl_lights_count(set) == count, "count %d, want %d", shl_lights_count(set), count);
        li->added = st == SHL_OK;
        if (!li->added) continue;
        const long double rgbmax = fmaxl(fabsl(li->rgb[0]), fmaxl(fabsl(li->rgb[1]), fabsl(li->rgb[2])));
        magnitude += rgbmax * 4.0L * M_PI * fz_kl(SHL_LMAX_MAX) * (li->kind == 1 ? li->P.n : 1);
        if (li->kind == 1 && !(li->P.structured && li->P.exact)) all_structured = 0;
    }
    /* points */
    const int np = 1 + fz_u8(&in) % MAXP;
    double pts[3 * MAXP];
    fz_poly dummy;
    memset(&dummy, 0, sizeof dummy);
    for (int p = 0; p < np; ++p) fz_point(&in, L[0].kind == 1 && nl > 0 ? &L[0].P : &dummy, pts + 3 * p);
    const int nul = (flags >> 3) & 1 ? 1 + fz_u8(&in) % 4 : 0;
    const size_t rb = sizeof(double) * 3 * nc, gbb = sizeof(double) * 9 * nc;
    double *rgb = fz_guarded(rb * np), *grad = fz_guarded(gbb * np);
    double *brgb = fz_guarded(rb * np), *bgrad = fz_guarded(gbb * np);
    if (nul) { /* NULL arguments: SHL_ENULL, nothing written */
        const shl_ctx *cx = nul == 1 ? NULL : ctx;
        const shl_lights *ls = nul == 2 ? NULL : set;
        const double *xp = nul == 3 ? NULL : pts;
        double *out = nul == 4 ? NULL : rgb;
        FUZZ_CHECK(shl_lights_eval(cx, ls, xp, out, grad) == SHL_ENULL, "eval NULL %d", nul);
        FUZZ_CHECK(shl_lights_eval_batch(cx, ls, np, xp, out, grad) == SHL_ENULL, "eval_batch NULL %d", nul);
        FUZZ_CHECK(fz_untouched(rgb, rb * np) && fz_untouched(grad, gbb * np), "written on NULL");
        FUZZ_CHECK(shl_lights_add_polygon(NULL, pts, 3, pts, 1) == SHL_ENULL && shl_lights_count(NULL) == SHL_ENULL,
                   "NULL set");
        goto done;
    }
    const int want_eval = all_finite_d(pts, 3) ? SHL_OK : SHL_ENONFINITE; /* eval below uses point 0 */
    /* batch: optionally poison one point (all points are checked before anything is written) */
    double bpts[3 * MAXP];
    memcpy(bpts, pts, sizeof bpts);
    if ((flags & 2) && np > 1) bpts[3 * (np - 1) + fz_u8(&in) % 3] = NAN;
    const int want_batch = all_finite_d(bpts, 3 * np) ? SHL_OK : SHL_ENONFINITE;
    if (allocs) { /* the workspace allocation fails: ENOMEM, nothing written */
        shl__alloc_fail_after = 0;
        const int s1 = shl_lights_eval(ctx, set, pts, rgb, with_grad ? grad : NULL);
        shl__alloc_fail_after = 0;
        const int s2 = shl_lights_eval_batch(ctx, set, np, bpts, brgb, with_grad ? bgrad : NULL);
        shl__alloc_fail_after = -1;
        FUZZ_CHECK(s1 == (want_eval == SHL_OK ? SHL_ENOMEM : want_eval), "eval under ENOMEM: %d", s1);
        FUZZ_CHECK(s2 == (want_batch == SHL_OK ? SHL_ENOMEM : want_batch), "eval_batch under ENOMEM: %d", s2);
        FUZZ_CHECK(fz_untouched(rgb, rb * np) && fz_untouched(brgb, rb * np) && fz_untouched(grad, gbb * np) &&
                       fz_untouched(bgrad, gbb * np),
                   "written on ENOMEM");
    }
    const int sb = shl_lights_eval_batch(ctx, set, np, bpts, brgb, with_grad ? bgrad : NULL);
    FUZZ_CHECK(sb == want_batch, "eval_batch %d, want %d", sb, want_batch);
    if (sb != SHL_OK)
        FUZZ_CHECK(fz_untouched(brgb, rb * np) && fz_untouched(bgrad, gbb * np), "batch written on error");
    {   /* float batch through the SIMD kernels */
        float fpts[3 * MAXP];
        for (int k = 0; k < 3 * np; ++k) fpts[k] = (float)bpts[k];
        int ffinite = 1;
        for (int k = 0; k < 3 * np; ++k) ffinite &= isfinite(fpts[k]) != 0;
        const size_t frb = sizeof(float) * 3 * nc, fgb = sizeof(float) * 9 * nc;
        float *frgb = fz_guarded(frb * np), *fgrad = fz_guarded(fgb * np);
        float *one = fz_guarded(frb), *one_g = fz_guarded(fgb);
        if (allocs) {
            shl__alloc_fail_after = 0;
            const int sf = shl_lights_eval_batch_f(ctx, set, np, fpts, frgb, with_grad ? fgrad : NULL);
            shl__alloc_fail_after = -1;
            FUZZ_CHECK(sf == (!ffinite ? SHL_ENONFINITE : count ? SHL_ENOMEM : SHL_OK), "eval_batch_f under ENOMEM: %d", sf);
            if (sf != SHL_OK) FUZZ_CHECK(fz_untouched(frgb, frb * np) && fz_untouched(fgrad, fgb * np), "written on ENOMEM");
        }
        const int sf = shl_lights_eval_batch_f(ctx, set, np, fpts, frgb, with_grad ? fgrad : NULL);
        FUZZ_CHECK(sf == (ffinite ? SHL_OK : SHL_ENONFINITE), "eval_batch_f %d", sf);
        if (sf != SHL_OK) FUZZ_CHECK(fz_untouched(frgb, frb * np) && fz_untouched(fgrad, fgb * np), "batch_f written on error");
        for (int p = 0; p < np && sf == SHL_OK; ++p) {
            const float *o = frgb + (size_t)3 * nc * p, *og = fgrad + (size_t)9 * nc * p;
            FUZZ_CHECK(shl_lights_eval_batch_f(ctx, set, 1, fpts + 3 * p, one, with_grad ? one_g : NULL) == SHL_OK,
                       "eval_batch_f, one point");
            FUZZ_CHECK(memcmp(one, o, frb) == 0, "eval_batch_f depends on the batch at point %d", p);
            if (with_grad) FUZZ_CHECK(memcmp(one_g, og, fgb) == 0, "eval_batch_f gradient depends on the batch, point %d", p);
            for (int k = 0; k < 3 * nc; ++k) {
                if (count == 0) FUZZ_CHECK(o[k] == 0.0f, "empty set, float: rgb[%d] = %g", k, o[k]);
                if (magnitude < 1e30L) FUZZ_CHECK(isfinite(o[k]), "non-finite float rgb[%d] at point %d", k, p);
            }
        }
        free(frgb);
        free(fgrad);
        free(one);
        free(one_g);
    }
    for (int p = 0; p < np; ++p) {
        double *o = rgb + (size_t)3 * nc * p, *og = grad + (size_t)9 * nc * p;
        const int st = shl_lights_eval(ctx, set, pts + 3 * p, o, with_grad ? og : NULL);
        const int want = all_finite_d(pts + 3 * p, 3) ? SHL_OK : SHL_ENONFINITE;
        FUZZ_CHECK(st == want, "eval point %d: %d, want %d", p, st, want);
        if (st != SHL_OK) {
            FUZZ_CHECK(fz_untouched(o, rb) && fz_untouched(og, gbb), "eval written on error");
            continue;
        }
        if (!with_grad) FUZZ_CHECK(fz_untouched(og, gbb), "gradient written although NULL");
        if (sb == SHL_OK) {
            FUZZ_CHECK(memcmp(o, brgb + (size_t)3 * nc * p, rb) == 0, "batch differs from eval at point %d", p);
            if (with_grad) FUZZ_CHECK(memcmp(og, bgrad + (size_t)9 * nc * p, gbb) == 0, "batch gradient differs, point %d", p);
        }
        if (count == 0) {
            for (int k = 0; k < 3 * nc; ++k) FUZZ_CHECK(o[k] == 0.0, "empty set: rgb[%d] = %g", k, o[k]);
            for (int k = 0; with_grad && k < 9 * nc; ++k) FUZZ_CHECK(og[k] == 0.0, "empty set: grad[%d] = %g", k, og[k]);
            continue;
        }
        if (!(magnitude < 1e290L)) continue;
        FUZZ_CHECK(all_finite_d(o, 3 * nc), "non-finite rgb at point %d", p);
        /* sum of the single-light entry points */
        const double *x = pts + 3 * p;
        long double *sum = calloc((size_t)12 * nc, sizeof(long double)), *scale = calloc(4 * 3, sizeof(long double));
        long double floor_c[3] = {1e-300L, 1e-300L, 1e-300L}; /* + sum_i |rgb_ic| 16 DBL_MIN: underflowed unit results */
        long double under[6] = {0.0L, 0.0L, 0.0L, 0.0L, 0.0L, 0.0L}; /* coefficients, gradients per colour: subnormal lights */
        double *lc = malloc(sizeof(double) * nc), *lg = malloc(sizeof(double) * 3 * nc);
        int comparable = 1, bounded = all_structured;
        long double *bound = calloc((size_t)3 * nc, sizeof(long double)), gfinite = 0.0L;
        for (int i = 0; i < nl; ++i) {
            const light *li = &L[i];
            if (!li->added) continue;
            int amb = 0;
            if (li->kind == 1) {
                if (!li->two_sided && !polygon_front(li, x, &amb) && !amb) continue;
                if (amb) comparable = 0;
                FUZZ_CHECK(shl_polygon_grad(ctx, x, li->P.v, li->P.n, lc, lg) == SHL_OK, "polygon %d", i);
                /* finite where K_l sum_e gamma_e / d_e is, with room (planar or not: from the vertices) */
                if (fz_kl(lmax) * fz_raw_grad_bound(li->P.v, li->P.n, x) < 1e290L)
                    FUZZ_CHECK(all_finite_d(lg, 3 * nc), "polygon %d: non-finite gradient", i);
            } else {
                sphere_inside(li, x, &amb);
                if (amb) comparable = 0;
                FUZZ_CHECK(shl_sphere_grad(ctx, x, li->c, li->r, lc, lg) == SHL_OK, "sphere %d", i);
            }
            long double sc = 0.0L, gsc = 0.0L;
            for (int k = 0; k < nc; ++k) sc = fmaxl(sc, fabsl(lc[k]));
            for (int k = 0; k < 3 * nc; ++k) gsc = isfinite(lg[k]) ? fmaxl(gsc, fabsl(lg[k])) : INFINITY;
            /* light i's scale: its largest coefficient, or its solid angle K_0^-1 L_00 (spheres: L_00 / K_0) */
            sc = fmaxl(sc, fabsl(lc[0]) / fz_kl(0) * fz_kl(lmax));
            const long double rel_under = lc[0] != 0.0 ? fminl(1.0L, 4096.0L * 0x1p-1074L / fabsl(lc[0])) : 1.0L;
            for (int c = 0; c < 3; ++c) {
                under[c] += fabsl(li->rgb[c]) * sc * rel_under;
                under[3 + c] += li->rgb[c] == 0.0 ? 0.0L : fabsl(li->rgb[c]) * gsc * rel_under;
                for (int k = 0; k < nc; ++k) sum[c * nc + k] += (long double)li->rgb[c] * lc[k];
                for (int k = 0; k < 3 * nc; ++k) sum[3 * nc + c * 3 * nc + k] += (long double)li->rgb[c] * lg[k];
                scale[c] += fabsl(li->rgb[c]) * sc;
                floor_c[c] += fabsl(li->rgb[c]) * 16.0L * DBL_MIN;
                scale[3 + c] += li->rgb[c] == 0.0 ? 0.0L : fabsl(li->rgb[c]) * gsc;
            }
            gfinite += gsc * fmaxl(fabsl(li->rgb[0]), fmaxl(fabsl(li->rgb[1]), fabsl(li->rgb[2])));
            if (bounded) { /* |L_i,lm| <= K_l Omega_i + slack_i */
                long double om = 0.0L, sl = 0.0L;
                if (li->kind == 1) {
                    fz_geom G;
                    if (!fz_poly_geom(&li->P, x, &G)) {
                        bounded = 0;
                        continue;
                    }
                    const long double eps = DBL_EPSILON;
                    om = G.omega;
                    sl = 1e-9L * om + 300.0L * eps * G.perim + 8.0L * eps * G.scale * G.gsum;
                } else {
                    om = 4.0L * M_PI; /* the whole sphere of directions bounds any cap */
                }
                for (int c = 0; c < 3; ++c)
                    for (int l = 0; l <= lmax; ++l)
                        for (int k = l * l; k < (l + 1) * (l + 1); ++k)
                            bound[c * nc + k] += fabsl(li->rgb[c]) * fz_kl(l) * (om + sl);
            }
        }
        if (with_grad && gfinite < 1e290L) FUZZ_CHECK(all_finite_d(og, 9 * nc), "non-finite gradient at point %d", p);
        for (int c = 0; c < 3 && comparable; ++c)
            for (int k = 0; k < nc; ++k)
                FUZZ_CHECK(fabsl(o[c * nc + k] - sum[c * nc + k]) <= 1e-9L * scale[c] + under[c] + floor_c[c],
                           "set vs sum of lights: rgb[%d][%d] %.17g vs %.17Lg (scale %.3Lg)", c, k, o[c * nc + k],
                           sum[c * nc + k], scale[c]);
        for (int c = 0; c < 3 && comparable && with_grad; ++c)
            for (int k = 0; k < 3 * nc; ++k)
                if (isfinite(og[c * 3 * nc + k]) && isfinite(scale[3 + c]))
                    FUZZ_CHECK(fabsl(og[c * 3 * nc + k] - sum[3 * nc + c * 3 * nc + k]) <= 1e-9L * scale[3 + c] + under[3 + c] + floor_c[c],
                               "set vs sum of lights: grad[%d][%d] %.17g vs %.17Lg (scale %.3Lg)", c, k, og[c * 3 * nc + k],
                               sum[3 * nc + c * 3 * nc + k], scale[3 + c]);
        for (int k = 0; bounded && k < 3 * nc; ++k)
            FUZZ_CHECK(fabsl(o[k]) <= bound[k] * (1.0L + 1e-12L) + floor_c[k / nc], "|rgb[%d]| = %.17g > bound %.17Lg", k,
                       o[k], bound[k]);
        free(sum);
        free(scale);
        free(lc);
        free(lg);
        free(bound);
    }
done:
    free(rgb);
    free(grad);
    free(brgb);
    free(bgrad);
    shl_lights_destroy(set);
    return 0;
}

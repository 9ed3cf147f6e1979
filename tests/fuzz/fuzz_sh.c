/* libFuzzer target: SH basis and SH-vector operations -- shl_eval_basis,
 * shl_eval_basis_f, shl_sh_eval, shl_zh_to_sh, shl_sh_rotate.
 *
 * Input: lmax byte, op byte, then directions / matrices / coefficient vectors.
 * Properties:
 *  - SHL_OK or the documented code (NULL, lmax, non-finite, zero direction or
 *    axis, matrix not orthogonal within 1e-6, SHL_ENOMEM under an injected
 *    failure); nothing written on error (including out == in for shl_sh_rotate);
 *  - Y_lm: finite, |Y_lm| <= K_l (1 + 1e-12), and per band sum_m Y_lm^2 =
 *    (2l+1)/(4 pi) to 1e-12 (float: 1e-5) -- the addition theorem, for any
 *    direction length, denormal to DBL_MAX;
 *  - shl_sh_eval = sum_k c_k Y_k(dir) (to 1e-12 of sum |c_k Y_k|);
 *  - shl_zh_to_sh: |sh_lm| <= |zh_l| (1 + 1e-12) and sum_m sh_lm^2 = zh_l^2 (1e-12),
 *    since sqrt(4 pi/(2l+1)) Y_lm(axis) is a unit vector over m;
 *  - shl_sh_rotate: the status agrees with the measured orthogonality error
 *    (OK below 0.99e-6, EDOMAIN above 1.01e-6); outputs finite when the input's
 *    band norms are below 1e300; band norms preserved to (l+1)^2 (1e-13 + 4 err)
 *    (err = max |R R^T - I|); out == in gives the same result bit for bit. */
#include "fuzz_common.h"

#define GUARD_VALUE_D 1234.5678

static double band_norm(const double *v, int l)
{
    long double s = 0.0L;
    for (int k = l * l; k < (l + 1) * (l + 1); ++k) s += (long double)v[k] * v[k];
    return (double)sqrtl(s);
}

static void dir3(fz_in *in, double d[3])
{
    const uint8_t m = fz_u8(in);
    if (m & 1) { /* a near-pole or axis-aligned direction with tiny perturbations */
        for (int k = 0; k < 3; ++k) d[k] = 0.0;
        d[(m >> 1) % 3] = (m & 8) ? -1.0 : 1.0;
        for (int k = 0; k < 3; ++k) d[k] += (m & 16) ? fz_real(in) * 1e-12 : 0.0;
        const double sc = (m & 32) ? fz_real(in) : 1.0;
        for (int k = 0; k < 3; ++k) d[k] *= sc;
        return;
    }
    for (int k = 0; k < 3; ++k) d[k] = fz_real(in);
}

static void op_basis(fz_in *in, int lmax)
{
    const int nc = SHL_NCOEFFS(lmax);
    double d[3];
    dir3(in, d);
    double *y = fz_guarded(sizeof(double) * nc);
    float *yf = fz_guarded(sizeof(float) * nc);
    const float df[3] = {(float)d[0], (float)d[1], (float)d[2]};
    int want = SHL_OK;
    if (!all_finite_d(d, 3)) want = SHL_ENONFINITE;
    else if (d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0) want = SHL_EDOMAIN;
    int want_f = SHL_OK;
    if (!all_finite_f(df, 3)) want_f = SHL_ENONFINITE;
    else if (df[0] == 0.0f && df[1] == 0.0f && df[2] == 0.0f) want_f = SHL_EDOMAIN;
    const int st = shl_eval_basis(lmax, d, y), sf = shl_eval_basis_f(lmax, df, yf);
    FUZZ_CHECK(st == want && sf == want_f, "eval_basis %d %d, want %d %d", st, sf, want, want_f);
    if (st != SHL_OK) FUZZ_CHECK(fz_untouched(y, sizeof(double) * nc), "written on error");
    if (sf != SHL_OK) FUZZ_CHECK(fz_untouched(yf, sizeof(float) * nc), "float written on error");
    for (int l = 0; l <= lmax; ++l) {
        const double kl = fz_kl(l), k2 = (2.0 * l + 1.0) / (4.0 * M_PI);
        if (st == SHL_OK) {
            long double s = 0.0L;
            for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
                FUZZ_CHECK(isfinite(y[k]) && fabs(y[k]) <= kl * (1.0 + 1e-12), "|Y[%d]| = %g > K_l %g", k, y[k], kl);
                s += (long double)y[k] * y[k];
            }
            FUZZ_CHECK(fabsl(s - k2) <= 1e-12L * k2, "band %d: sum Y^2 = %.17Lg, want %.17g", l, s, k2);
        }
        if (sf == SHL_OK) {
            long double s = 0.0L;
            for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
                FUZZ_CHECK(isfinite(yf[k]) && fabsf(yf[k]) <= kl * (1.0 + 1e-6), "|Yf[%d]| = %g > K_l %g", k, yf[k], kl);
                s += (long double)yf[k] * yf[k];
            }
            FUZZ_CHECK(fabsl(s - k2) <= 1e-5L * k2, "float band %d: sum Y^2 = %.9Lg, want %.9g", l, s, k2);
        }
    }
    if (st == SHL_OK) { /* shl_sh_eval of random coefficients at the same direction */
        double *c = malloc(sizeof(double) * nc), v = GUARD_VALUE_D;
        long double sum = 0.0L, mag = 0.0L;
        for (int k = 0; k < nc; ++k) {
            c[k] = (int8_t)fz_u8(in) / 8.0;
            sum += (long double)c[k] * y[k];
            mag += fabsl((long double)c[k] * y[k]);
        }
        FUZZ_CHECK(shl_sh_eval(lmax, c, d, &v) == SHL_OK, "sh_eval");
        FUZZ_CHECK(fabsl(v - sum) <= 1e-12L * mag + 1e-300L, "sh_eval %.17g vs %.17Lg", v, sum);
        c[nc - 1] = NAN;
        v = GUARD_VALUE_D;
        FUZZ_CHECK(shl_sh_eval(lmax, c, d, &v) == SHL_ENONFINITE && v == GUARD_VALUE_D, "sh_eval NaN");
        free(c);
    }
    free(y);
    free(yf);
}

static void op_zh_to_sh(fz_in *in, int lmax)
{
    const int nc = SHL_NCOEFFS(lmax);
    double zh[SHL_LMAX_MAX + 1], axis[3];
    for (int l = 0; l <= lmax; ++l) zh[l] = (fz_u8(in) & 1) ? fz_real(in) : (int8_t)fz_u8(in) / 16.0;
    dir3(in, axis);
    double *sh = fz_guarded(sizeof(double) * nc);
    int want = SHL_OK;
    if (!all_finite_d(zh, lmax + 1) || !all_finite_d(axis, 3)) want = SHL_ENONFINITE;
    else if (axis[0] == 0.0 && axis[1] == 0.0 && axis[2] == 0.0) want = SHL_EDOMAIN;
    const int st = shl_zh_to_sh(lmax, zh, axis, sh);
    FUZZ_CHECK(st == want, "zh_to_sh %d, want %d", st, want);
    if (st != SHL_OK) {
        FUZZ_CHECK(fz_untouched(sh, sizeof(double) * nc), "written on error");
        goto done;
    }
    for (int l = 0; l <= lmax; ++l) {
        const long double z = fabsl(zh[l]);
        if (z < 1e300L) FUZZ_CHECK(all_finite_d(sh + l * l, 2 * l + 1), "non-finite sh, band %d", l);
        for (int k = l * l; k < (l + 1) * (l + 1); ++k)
            if (isfinite(sh[k])) FUZZ_CHECK(fabsl(sh[k]) <= z * (1.0L + 1e-12L) + 0x1p-1072L, "|sh[%d]| = %g > |zh_%d| = %Lg", k, sh[k], l, z);
        if (z > 1e-150L && z < 1e150L)
            FUZZ_CHECK(fabsl(band_norm(sh, l) - z) <= 1e-12L * z, "band %d norm %.17g vs |zh| %.17Lg", l, band_norm(sh, l), z);
    }
    { /* aliasing: zh may be the start of sh */
        double *al = malloc(sizeof(double) * nc);
        memcpy(al, zh, sizeof(double) * (lmax + 1));
        FUZZ_CHECK(shl_zh_to_sh(lmax, al, axis, al) == SHL_OK, "aliased zh_to_sh");
        FUZZ_CHECK(memcmp(al, sh, sizeof(double) * nc) == 0, "aliased zh_to_sh differs");
        free(al);
    }
done:
    free(sh);
}

/* A rotation: exact signed permutation, quaternion-built, or raw entries. */
static void rotation(fz_in *in, double R[9])
{
    const uint8_t m = fz_u8(in);
    switch (m % 4) {
    case 0: { /* signed permutation (det +-1), exact */
        static const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
        const int *p = perm[(m >> 2) % 6];
        for (int i = 0; i < 9; ++i) R[i] = 0.0;
        for (int i = 0; i < 3; ++i) R[3 * i + p[i]] = (m >> (5 + i % 3)) & 1 ? -1.0 : 1.0;
        return;
    }
    case 1:
    case 2: { /* unit quaternion; optionally a reflection; optionally perturbed */
        double q[4], n = 0.0;
        for (int k = 0; k < 4; ++k) n += (q[k] = (int16_t)fz_u16(in) + 0.5) * q[k];
        n = sqrt(n);
        for (int k = 0; k < 4; ++k) q[k] /= n;
        const double w = q[0], x = q[1], y = q[2], z = q[3];
        const double M[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                             2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                             2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)};
        const double sg = (m & 4) ? -1.0 : 1.0;
        for (int i = 0; i < 9; ++i) R[i] = sg * M[i];
        if (m % 4 == 2) R[fz_u8(in) % 9] += fz_real(in) * 1e-6;
        return;
    }
    default:
        for (int i = 0; i < 9; ++i) R[i] = fz_real(in);
    }
}

static void op_rotate(fz_in *in, int lmax)
{
    const int nc = SHL_NCOEFFS(lmax);
    double R[9];
    rotation(in, R);
    double *v = malloc(sizeof(double) * nc);
    const uint8_t vm = fz_u8(in);
    for (int k = 0; k < nc; ++k) v[k] = (vm & 1) ? fz_real(in) : (int8_t)fz_u8(in) / 16.0;
    const long fail = (vm & 2) ? 0 : -1;
    /* orthogonality error, as documented: max |R R^T - I| */
    long double err = 0.0L;
    int finite = all_finite_d(R, 9) && all_finite_d(v, nc);
    for (int i = 0; i < 3 && finite; ++i)
        for (int j = 0; j < 3; ++j) {
            const long double d = (long double)R[3 * i] * R[3 * j] + (long double)R[3 * i + 1] * R[3 * j + 1] +
                                  (long double)R[3 * i + 2] * R[3 * j + 2] - (i == j);
            err = fmaxl(err, fabsl(d));
        }
    double *out = fz_guarded(sizeof(double) * nc), *al = malloc(sizeof(double) * nc);
    memcpy(al, v, sizeof(double) * nc);
    shl__alloc_fail_after = fail;
    const int st = shl_sh_rotate(lmax, R, v, out);
    shl__alloc_fail_after = fail;
    const int sa = shl_sh_rotate(lmax, R, al, al);
    shl__alloc_fail_after = -1;
    if (!finite) FUZZ_CHECK(st == SHL_ENONFINITE && sa == SHL_ENONFINITE, "rotate non-finite: %d %d", st, sa);
    else if (err > 1.01e-6L) FUZZ_CHECK(st == SHL_EDOMAIN && sa == SHL_EDOMAIN, "rotate err %.3Lg: %d", err, st);
    else if (err < 0.99e-6L) FUZZ_CHECK(st == (fail >= 0 ? SHL_ENOMEM : SHL_OK) && sa == st, "rotate err %.3Lg: %d %d", err, st, sa);
    else FUZZ_CHECK(st == sa && (st == SHL_OK || st == SHL_EDOMAIN || st == SHL_ENOMEM), "rotate at the threshold: %d", st);
    if (st != SHL_OK) {
        FUZZ_CHECK(fz_untouched(out, sizeof(double) * nc), "rotate wrote on error");
        FUZZ_CHECK(memcmp(al, v, sizeof(double) * nc) == 0, "aliased rotate changed its input on error");
        goto done;
    }
    FUZZ_CHECK(memcmp(al, out, sizeof(double) * nc) == 0, "aliased rotate differs");
    for (int l = 0; l <= lmax; ++l) {
        const double ni = band_norm(v, l), no = band_norm(out, l);
        if (ni < 1e300) FUZZ_CHECK(all_finite_d(out + l * l, 2 * l + 1), "non-finite rotated band %d (norm %g)", l, ni);
        if (ni < 1e300 && ni > 1e-280) {
            const long double tol = (l + 1.0L) * (l + 1.0L) * (1e-13L + 4.0L * err) * ni;
            FUZZ_CHECK(fabsl((long double)no - ni) <= tol, "band %d norm %.17g -> %.17g (err %.3Lg)", l, ni, no, err);
        }
    }
done:
    free(v);
    free(out);
    free(al);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_target_name = "fuzz_sh";
    fz_in in = {data, size, 0};
    const int lmax = fz_lmax(&in);
    const uint8_t op = fz_u8(&in);
    if (lmax < 0 || lmax > SHL_LMAX_MAX) {
        double buf[8], R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, d[3] = {0, 0, 1};
        memset(buf, FZ_GUARD_BYTE, sizeof buf);
        FUZZ_CHECK(shl_eval_basis(lmax, d, buf) == SHL_ELMAX && shl_sh_rotate(lmax, R, buf, buf) == SHL_ELMAX &&
                       shl_zh_to_sh(lmax, buf, d, buf) == SHL_ELMAX && fz_untouched(buf, sizeof buf),
                   "lmax %d accepted", lmax);
        return 0;
    }
    switch (op % 3) {
    case 0: op_basis(&in, lmax); break;
    case 1: op_zh_to_sh(&in, lmax); break;
    default: op_rotate(&in, lmax); break;
    }
    return 0;
}

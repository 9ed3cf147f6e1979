/* libFuzzer target: shl_hvl_overlap (HVL Eq. 22, the cap-hemisphere overlap H).
 *
 * Input: flags byte (bit 0: NULL output), mode byte, then the half-angle a and
 * cos_theta: any values (fz_real), or a structured a = m 2^-k (any exponent down
 * to denormals, capped at pi/2) with c = sin(f a) for f = int16 / 4096 (across
 * and beyond the band), c = +-sin(a) moved by a signed number of ulps (the
 * edges), or c = 0, +-1 moved by ulps; then a second cos_theta c2: c moved by
 * 1..255 ulps up, or any value.
 * Properties:
 *  - status SHL_OK or the documented code (NULL; non-finite; |c| > 1, a < 0 or
 *    a > 0.5 * M_PI: SHL_EDOMAIN); nothing written on error;
 *  - H in [0, 1]; a = 0: 1, 0, 1/2 for c > 0, c < 0, c = +-0;
 *  - |H - S(clamp((a + asin c) / (2a), 0, 1))| <= 3 DBL_EPSILON + 16 LDBL_EPSILON,
 *    asin by its Taylor series in long double (tests/test_hvl.c has the error
 *    analysis: asin within 1 ulp, two roundings of the argument, S' <= 3/2, the
 *    final roundings: < 2.4 DBL_EPSILON);
 *  - the cap beyond an edge (long-double asin(c) beyond +-a by more than 8
 *    LDBL_EPSILON a): exactly 1 above, exactly 0 below;
 *  - monotone: c <= c2 implies H(c) <= H(c2);
 *  - symmetry: |H(c) + H(-c) - 1| <= DBL_EPSILON (asin is odd). */
#include "asin_ref.h"
#include "fuzz_common.h"

#define H_TOL (3.0 * DBL_EPSILON + 16.0 * LDBL_EPSILON)

static long double h_ref(double c, double a)
{
    const long double x = ((long double)a + asin_ref(c)) / (2.0L * a);
    return x <= 0.0L ? 0.0L : (x >= 1.0L ? 1.0L : x * x * (3.0L - 2.0L * x));
}

static double step_ulps(double c, int k)
{
    for (; k > 0; --k) c = nextafter(c, 2.0);
    for (; k < 0; ++k) c = nextafter(c, -2.0);
    return c;
}

static void decode(fz_in *in, double *c, double *a)
{
    const uint8_t mode = fz_u8(in);
    if (mode % 4 == 0) {
        *a = fz_real(in);
        *c = fz_real(in);
        return;
    }
    const int k = fz_u16(in) % 1080; /* a = m 2^-k, m in [1/2, 2) */
    *a = fmin(0.5 * M_PI, ldexp(0.5 + fz_u16(in) / 43690.0, -k));
    if (fz_u8(in) == 0) *a = 0.0;
    const int ulps = (int8_t)fz_u8(in);
    switch (mode % 4) {
    case 1: *c = sin(*a * ((int16_t)fz_u16(in) / 4096.0)); break;
    case 2: *c = step_ulps((mode & 4) ? -sin(*a) : sin(*a), ulps); break;
    default: *c = step_ulps((mode & 4) ? 0.0 : ((mode & 8) ? -1.0 : 1.0), ulps); break;
    }
}

static double overlap_ok(double c, double a)
{
    double h = -1.0;
    const int st = shl_hvl_overlap(c, a, &h);
    FUZZ_CHECK(st == SHL_OK, "H(%a, %a): status %d", c, a, st);
    FUZZ_CHECK(h >= 0.0 && h <= 1.0, "H(%a, %a) = %a", c, a, h);
    if (a == 0.0) {
        FUZZ_CHECK(h == (c > 0.0 ? 1.0 : (c < 0.0 ? 0.0 : 0.5)), "a = 0: H(%a) = %a", c, h);
        return h;
    }
    const long double e = asin_ref(c), margin = 8.0L * LDBL_EPSILON * a;
    const double err = (double)fabsl((long double)h - h_ref(c, a));
    FUZZ_CHECK(err <= H_TOL, "H(%a, %a) = %.17g, |err| %.3g", c, a, h, err);
    if (e > a + margin) FUZZ_CHECK(h == 1.0, "cap above: H(%a, %a) = %.17g", c, a, h);
    if (e < -a - margin) FUZZ_CHECK(h == 0.0, "cap below: H(%a, %a) = %.17g", c, a, h);
    return h;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_target_name = "fuzz_hvl";
    fz_in in = {data, size, 0};
    const uint8_t flags = fz_u8(&in);
    double c, a;
    decode(&in, &c, &a);
    const uint8_t up = fz_u8(&in);
    const double c2 = up ? step_ulps(c, up) : fz_real(&in);
    fz_dump_vec("cos_theta, a, c2", (const double[]){c, a, c2}, 3);
    int want = SHL_OK;
    if (flags & 1) want = SHL_ENULL;
    else if (!isfinite(c) || !isfinite(a)) want = SHL_ENONFINITE;
    else if (fabs(c) > 1.0 || a < 0.0 || a > 0.5 * M_PI) want = SHL_EDOMAIN;
    if (want != SHL_OK) {
        double g;
        memset(&g, FZ_GUARD_BYTE, sizeof g);
        const int st = shl_hvl_overlap(c, a, (flags & 1) ? NULL : &g);
        FUZZ_CHECK(st == want && fz_untouched(&g, sizeof g), "H(%a, %a): status %d, want %d", c, a, st, want);
        return 0;
    }
    const double h = overlap_ok(c, a);
    const double hm = overlap_ok(-c, a);
    FUZZ_CHECK(fabs(h + hm - 1.0) <= DBL_EPSILON, "H(%a) + H(-%a) = %.17g (a %a)", c, c, h + hm, a);
    if (isfinite(c2) && fabs(c2) <= 1.0) {
        const double h2 = overlap_ok(c2, a);
        FUZZ_CHECK(c < c2 ? h <= h2 : (c > c2 ? h >= h2 : h == h2), "not monotone: H(%a) = %a, H(%a) = %a (a %a)", c,
                   h, c2, h2, a);
    }
    return 0;
}

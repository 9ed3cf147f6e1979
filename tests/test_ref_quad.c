/* Self-checks of the numerical reference (ref_quad.c): closed forms (solid angle,
 * irradiance vector), agreement of its two independent quadrature paths,
 * additivity, winding independence, and its gradient against 8th-order central
 * differences.  Errors are reported relative to the solid angle (coefficients) or
 * to the largest gradient entry. */
#include "harness.h"
#include "internal.h"
#include "ref_quad.h"
#include "sh_basis.h"
#include <math.h>
#include <string.h>
#include <time.h>

#define NC(l) (((l) + 1) * ((l) + 1))
#define NC30 NC(30)

static double now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return 1e3 * (double)t.tv_sec + 1e-6 * (double)t.tv_nsec;
}

static double maxdiff(const double *a, const double *b, int n)
{
    double m = 0.0;
    for (int k = 0; k < n; ++k) m = fmax(m, fabs(a[k] - b[k]));
    return m;
}

static double maxabs(const double *a, int n)
{
    double m = 0.0;
    for (int k = 0; k < n; ++k) m = fmax(m, fabs(a[k]));
    return m;
}

/* Axis-aligned rectangle [x0,x1] x [y0,y1] in the plane z = 0, counter-clockwise. */
static void rect(double x0, double x1, double y0, double y1, double v[12])
{
    const double r[12] = {x0, y0, 0, x1, y0, 0, x1, y1, 0, x0, y1, 0};
    memcpy(v, r, sizeof r);
}

/* Solid angle of that rectangle seen from p (p[2] != 0, foot point on no edge
 * line), by corners: F(a,b) = atan(ab / (h sqrt(a^2+b^2+h^2))) =
 * sign(ab) pi/2 - atan(h R / (ab)), the pi/2 parts summing to 2 pi inside the
 * footprint and 0 outside (no cancellation near the plane). */
static double rect_omega(double x0, double x1, double y0, double y1, const double p[3])
{
    const double h = fabs(p[2]), a[2] = {x0 - p[0], x1 - p[0]}, b[2] = {y0 - p[1], y1 - p[1]};
    double s = (a[0] < 0 && a[1] > 0 && b[0] < 0 && b[1] > 0) ? 2.0 * M_PI : 0.0;
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j)
            s -= ((i + j) & 1 ? -1.0 : 1.0) * atan(h * sqrt(a[i] * a[i] + b[j] * b[j] + h * h) / (a[i] * b[j]));
    return s;
}

static void sub3(const double *a, const double *b, double out[3])
{
    for (int k = 0; k < 3; ++k) out[k] = a[k] - b[k];
}

static void cross(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Unit direction from x toward the polygon's plane (Newell normal, oriented). */
static void nadir(const double x[3], const double *v, int n, double out[3])
{
    double nn[3] = {0, 0, 0}, c[3], d[3];
    for (int i = 0; i < n; ++i) {
        cross(v + 3 * i, v + 3 * ((i + 1) % n), c);
        for (int k = 0; k < 3; ++k) nn[k] += c[k];
    }
    sub3(v, x, d);
    const double s = (dot(nn, d) > 0 ? 1.0 : -1.0) / sqrt(dot(nn, nn));
    for (int k = 0; k < 3; ++k) out[k] = s * nn[k];
}

/* Van Oosterom-Strackee over the fan from vertex 0, plain world-space formula. */
static double vos(const double x[3], const double *v, int n)
{
    double a[3], s = 0.0;
    sub3(v, x, a);
    const double la = sqrt(dot(a, a));
    for (int i = 1; i + 1 < n; ++i) {
        double b[3], c[3], bc[3];
        sub3(v + 3 * i, x, b);
        sub3(v + 3 * (i + 1), x, c);
        cross(b, c, bc);
        const double lb = sqrt(dot(b, b)), lc = sqrt(dot(c, c));
        s += 2.0 * atan2(dot(a, bc), la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la);
    }
    return fabs(s);
}

/* Band 1 in closed form: int w dw = 1/2 sum_e gamma_e mu_e (Arvo), oriented toward
 * the polygon; Y1-1 = -c y, Y10 = c z, Y11 = -c x. */
static void band1(const double x[3], const double *v, int n, double out[3])
{
    double s[3] = {0, 0, 0}, nd[3];
    for (int i = 0; i < n; ++i) {
        double a[3], b[3], ab[3];
        sub3(v + 3 * i, x, a);
        sub3(v + 3 * ((i + 1) % n), x, b);
        cross(a, b, ab);
        const double l = sqrt(dot(ab, ab));
        if (l == 0.0) continue;
        const double g = atan2(l, dot(a, b));
        for (int k = 0; k < 3; ++k) s[k] += 0.5 * g * ab[k] / l;
    }
    nadir(x, v, n, nd);
    const double c = sqrt(3.0 / (4.0 * M_PI)) * (dot(s, nd) > 0 ? 1.0 : -1.0);
    out[0] = -c * s[1];
    out[1] = c * s[2];
    out[2] = -c * s[0];
}

/* Rigid motion: rotation by Euler angles (z, y, z) then translation. */
static void rigid(const double ang[3], const double t[3], const double *in, int n, double *out)
{
    const double ca = cos(ang[0]), sa = sin(ang[0]), cb = cos(ang[1]), sb = sin(ang[1]);
    const double cg = cos(ang[2]), sg = sin(ang[2]);
    const double r[3][3] = {{ca * cb * cg - sa * sg, -ca * cb * sg - sa * cg, ca * sb},
                            {sa * cb * cg + ca * sg, -sa * cb * sg + ca * cg, sa * sb},
                            {-sb * cg, sb * sg, cb}};
    for (int i = 0; i < n; ++i) {
        const double p[3] = {in[3 * i], in[3 * i + 1], in[3 * i + 2]};
        for (int k = 0; k < 3; ++k) out[3 * i + k] = r[k][0] * p[0] + r[k][1] * p[1] + r[k][2] * p[2] + t[k];
    }
}

static void reverse(const double *in, int n, double *out)
{
    for (int i = 0; i < n; ++i) memcpy(out + 3 * i, in + 3 * (n - 1 - i), 3 * sizeof *out);
}

/* Gradient of rect_omega with respect to p, from the corner terms
 * F(a,b,h) = atan(ab / (h R)), a = x_i - p[0], b = y_j - p[1], h = |p[2]|. */
static void rect_omega_grad(double x0, double x1, double y0, double y1, const double p[3], double g[3])
{
    const double h = fabs(p[2]), a[2] = {x0 - p[0], x1 - p[0]}, b[2] = {y0 - p[1], y1 - p[1]};
    g[0] = g[1] = g[2] = 0.0;
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) {
            const double s = (i + j) & 1 ? -1.0 : 1.0, A = a[i], B = b[j];
            const double r2 = A * A + B * B + h * h, r = sqrt(r2), d = r * (h * h * r2 + A * A * B * B);
            g[0] -= s * B * h * (B * B + h * h) / d;
            g[1] -= s * A * h * (A * A + h * h) / d;
            g[2] -= s * A * B * (r2 + h * h) / d;
        }
    if (p[2] < 0.0) g[2] = -g[2];
}

/* 8th-order central difference weights: f' ~ sum_j fd8[j-1] (f(x+jh) - f(x-jh)) / h */
static const double fd8[4] = {4.0 / 5.0, -1.0 / 5.0, 4.0 / 105.0, -1.0 / 280.0};

/* d coeffs / dx by 8th-order central differences of ref_polygon_sh (x +- j*step exact). */
static int fd_grad(int lmax, const double x[3], const double *v, int n, double step, double *g)
{
    const int nc = NC(lmax);
    double cp[NC30], cm[NC30];
    memset(g, 0, sizeof *g * 3 * (size_t)nc);
    for (int a = 0; a < 3; ++a)
        for (int j = 1; j <= 4; ++j) {
            double xp[3], xm[3];
            memcpy(xp, x, sizeof xp);
            memcpy(xm, x, sizeof xm);
            xp[a] += j * step;
            xm[a] -= j * step;
            if (ref_polygon_sh(lmax, xp, v, n, cp, NULL) || ref_polygon_sh(lmax, xm, v, n, cm, NULL)) return -1;
            for (int k = 0; k < nc; ++k) g[a * nc + k] += fd8[j - 1] * (cp[k] - cm[k]) / step;
        }
    return 0;
}

/* Moderate configurations (both paths converge quickly). */
static const double tri_v[9] = {0, 0, 0, 1.2, 0.1, 0, 0.3, 0.9, 0};
static const double lhex_v[18] = {0, 0, 0, 2, 0, 0, 2, 1, 0, 1, 1, 0, 1, 2, 0, 0, 2, 0};
static double star_v[24];

static void make_star(void)
{
    for (int i = 0; i < 8; ++i) {
        const double r = (i & 1) ? 0.45 : 1.0, t = M_PI * i / 4.0;
        star_v[3 * i] = r * cos(t);
        star_v[3 * i + 1] = r * sin(t);
        star_v[3 * i + 2] = 0.0;
    }
}

struct cfg {
    const double *v;
    int n;
    double x[3];
};

static int moderate(struct cfg *c, double *buf)
{
    static const double ang[3] = {0.7, 1.1, -0.4}, tr[3] = {0.3, -1.7, 2.2};
    double sq[12];
    rect(0, 1, 0, 1, sq);
    make_star();
    const struct cfg base[] = {{sq, 4, {0.5, 0.5, 1.0}},  {sq, 4, {0.3, 0.2, 0.5}},   {sq, 4, {2.0, 0.5, 1.0}},
                               {tri_v, 3, {2.0, 1.5, -1.0}}, {tri_v, 3, {0.5, 0.3, 0.8}}, {lhex_v, 6, {1.5, 1.5, 1.5}},
                               {lhex_v, 6, {0.5, 0.7, -1.2}}, {star_v, 8, {0.1, 0.2, 1.0}}, {star_v, 8, {0.8, 0.8, 0.6}}};
    const int nb = (int)(sizeof base / sizeof base[0]);
    double *p = buf;
    for (int i = 0; i < nb; ++i) {
        /* each configuration as given and rigidly moved to a generic position */
        memcpy(p, base[i].v, sizeof *p * 3 * (size_t)base[i].n);
        c[2 * i] = (struct cfg){p, base[i].n, {base[i].x[0], base[i].x[1], base[i].x[2]}};
        p += 3 * base[i].n;
        rigid(ang, tr, base[i].v, base[i].n, p);
        c[2 * i + 1].v = p;
        c[2 * i + 1].n = base[i].n;
        rigid(ang, tr, base[i].x, 1, c[2 * i + 1].x);
        p += 3 * base[i].n;
    }
    return 2 * nb;
}

SHL_TEST(ref_basis_gradient)
{
    /* ref_sh_eval_grad: values equal shl__sh_eval; derivatives match 8th-order
     * central differences of the same polynomial extension. */
    const int lmax = 30, nc = NC30;
    static double y[NC30], y2[NC30], g[3 * NC30], yp[NC30], ym[NC30];
    double worst_v = 0.0, worst_d = 0.0;
    for (int t = 0; t < 6; ++t) {
        const double th = 0.3 + 0.47 * t, ph = 1.1 * t - 2.0;
        const double d[3] = {sin(th) * cos(ph), sin(th) * sin(ph), cos(th)};
        ref_sh_eval_grad(lmax, d, y, g);
        shl__sh_eval(lmax, d[0], d[1], d[2], y2);
        worst_v = fmax(worst_v, maxdiff(y, y2, nc));
        const double step = 0x1p-9;
        for (int a = 0; a < 3; ++a) {
            double fd[NC30] = {0};
            for (int j = 1; j <= 4; ++j) {
                double dp[3] = {d[0], d[1], d[2]}, dm[3] = {d[0], d[1], d[2]};
                dp[a] += j * step;
                dm[a] -= j * step;
                shl__sh_eval(lmax, dp[0], dp[1], dp[2], yp);
                shl__sh_eval(lmax, dm[0], dm[1], dm[2], ym);
                for (int k = 0; k < nc; ++k) fd[k] += fd8[j - 1] * (yp[k] - ym[k]) / ((dp[a] - dm[a]) / (2.0 * j));
            }
            worst_d = fmax(worst_d, maxdiff(fd, g + a * nc, nc) / maxabs(g + a * nc, nc));
        }
    }
    harness_note("values vs shl__sh_eval %.1e", worst_v);
    harness_note("d/dxyz vs FD8 %.1e rel", worst_d);
    CHECK(worst_v <= 1e-15);
    CHECK(worst_d <= 1e-8);
}

SHL_TEST(ref_solid_angle_closed_forms)
{
    /* ref_polygon_solid_angle vs plain VOS and the rectangle corner formula; the
     * Y00 coefficient of both paths vs Omega / (2 sqrt(pi)). */
    struct cfg c[32];
    double buf[512], co[NC(2)];
    const int nc = moderate(c, buf);
    double e_vos = 0.0, e_y00 = 0.0;
    for (int i = 0; i < nc; ++i) {
        const double om = ref_polygon_solid_angle(c[i].x, c[i].v, c[i].n);
        e_vos = fmax(e_vos, fabs(om - vos(c[i].x, c[i].v, c[i].n)) / om);
        for (int m = REF_POLAR; m <= REF_AREA; ++m) {
            CHECK(ref_polygon_sh_method(m, 2, c[i].x, c[i].v, c[i].n, co, NULL, NULL) == 0);
            e_y00 = fmax(e_y00, fabs(co[0] * 2.0 * sqrt(M_PI) - om) / om);
        }
    }
    /* hard positions against the corner formula (exact in double for these inputs) */
    static const double hp[][3] = {{0.5, 0.5, 1e-7}, {2.0, 0.5, 1e-7},  {0.3125, -0x1p-21, 0x1p-21},
                                   {0.3125, 0x1p-21, 0x1p-21}, {0.5, 1e-12, 1e-6}, {1e-9, 1e-9, 1e-9},
                                   {5000.0, 5000.0, 1.0}, {1234.5, 9000.0, -1.0}};
    double sq[12], big[12], e_rect = 0.0;
    rect(0, 1, 0, 1, sq);
    rect(0, 1e4, 0, 1e4, big);
    for (int i = 0; i < 8; ++i) {
        const double *v = i < 6 ? sq : big, s = i < 6 ? 1.0 : 1e4;
        const double want = rect_omega(0, s, 0, s, hp[i]);
        const double om = ref_polygon_solid_angle(hp[i], v, 4);
        CHECK(ref_polygon_sh(0, hp[i], v, 4, co, NULL) == 0);
        e_rect = fmax(e_rect, fmax(fabs(om - want), fabs(co[0] * 2.0 * sqrt(M_PI) - want)) / want);
    }
    /* generic triangle in the plane z = 0.5, x within ~1e-5 of a vertex: 50-digit VOS */
    static const double tv[9] = {0.13, 0.21, 0.5, 1.37, 0.29, 0.5, 0.71, 1.13, 0.5};
    static const double tx[3][3] = {{1.37 - 1.3e-5, 0.29 + 0.7e-5, 0.5 + 1e-4},
                                    {0.71 + 2e-6, 1.13 - 3e-6, 0.5 - 2e-5},
                                    {0.13 - 1e-5, 0.21 - 1e-5, 0.5 + 1e-6}};
    static const double tom[3] = {1.1149528957662211015, 1.412783654956066883, 0.034522824233103005676};
    for (int i = 0; i < 3; ++i) {
        CHECK(ref_polygon_sh(2, tx[i], tv, 3, co, NULL) == 0);
        const double om = ref_polygon_solid_angle(tx[i], tv, 3);
        e_rect = fmax(e_rect, fmax(fabs(om - tom[i]), fabs(co[0] * 2.0 * sqrt(M_PI) - tom[i])) / tom[i]);
    }
    harness_note("VOS %.1e", e_vos);
    harness_note("Y00 %.1e", e_y00);
    harness_note("hard vs corner formula / 50-digit VOS %.1e", e_rect);
    CHECK(e_vos <= 1e-14);
    CHECK(e_y00 <= 1e-14);
    CHECK(e_rect <= 1e-14);
}

SHL_TEST(ref_hard_vs_high_precision)
{
    /* Bands 0-2 for the unit square [0,1]^2 at hard positions, against the
     * area integral evaluated offline with 24-digit tanh-sinh quadrature
     * (mpmath, domain split at the foot point) for these exact double inputs. */
    static const struct {
        double x[3], c[9];
    } hp[] = {
        {{0.5, 0.5, 1e-7},
         {1.7724535317516917062, 0.0, -1.5349900619196824888, 0.0, 0.0, 0.0, 3.5682482323053559318e-7, 0.0, 0.0}},
        {{2.0, 0.5, 1e-7},
         {9.8459638089759623201e-9, 0.0, -1.2892440792010271203e-15, 1.666907913123722351e-8, 0.0, 0.0,
          -1.1008122190436308155e-8, -2.8157135518592309921e-15, 1.7385227933736389795e-8}},
        {{0.3, -7e-7, 7e-7},
         {0.44311243118374267034, -0.54269997229831132983, -0.22479409003985851889, -4.9472247560431443902e-7,
          4.5024555930409929324e-7, 0.36418281019603260131, -0.31539041195279174012, 1.6007978166155679872e-12,
          -0.18209185151108226506}},
        {{0.3, 7e-7, 7e-7},
         {1.3293393566344447663, -0.54269997229791696248, -1.3101959718772600032, -4.9472458820539619997e-7,
          4.5024544191296149779e-7, 0.36418281019603260072, 0.3153927185545468578, 1.6008062096616707727e-12,
          0.18209095868314205018}},
    };
    double sq[12], worst = 0.0;
    static double co[NC30];
    rect(0, 1, 0, 1, sq);
    for (int i = 0; i < 4; ++i) {
        const double om = hp[i].c[0] * 2.0 * sqrt(M_PI);
        CHECK(ref_polygon_sh(30, hp[i].x, sq, 4, co, NULL) == 0);
        worst = fmax(worst, maxdiff(co, hp[i].c, 9) / om);
    }
    harness_note("max |err|/Omega %.1e (lmax 30, bands 0-2)", worst);
    CHECK(worst <= 1e-14);
}

SHL_TEST(ref_band1_closed_form)
{
    /* Band 1 of both paths vs the irradiance vector. */
    struct cfg c[32];
    double buf[512], co[NC(1)], want[3], worst = 0.0;
    const int nc = moderate(c, buf);
    for (int i = 0; i < nc; ++i) {
        const double om = ref_polygon_solid_angle(c[i].x, c[i].v, c[i].n);
        band1(c[i].x, c[i].v, c[i].n, want);
        for (int m = REF_POLAR; m <= REF_AREA; ++m) {
            CHECK(ref_polygon_sh_method(m, 1, c[i].x, c[i].v, c[i].n, co, NULL, NULL) == 0);
            worst = fmax(worst, maxdiff(co + 1, want, 3) / om);
        }
    }
    harness_note("max |err|/Omega %.1e", worst);
    CHECK(worst <= 1e-14);
}

SHL_TEST(ref_polar_vs_area)
{
    /* The two paths share no parametrization: spherical fan about a centre vs
     * plane-area integral.  lmax 30. */
    struct cfg c[32];
    double buf[512];
    static double a[NC30], b[NC30];
    const int nc = moderate(c, buf);
    double worst = 0.0, est = 0.0, tp = 0.0, ta = 0.0;
    for (int i = 0; i < nc; ++i) {
        const double om = ref_polygon_solid_angle(c[i].x, c[i].v, c[i].n);
        double ea, eb;
        const double t0 = now_ms();
        CHECK(ref_polygon_sh_method(REF_POLAR, 30, c[i].x, c[i].v, c[i].n, a, NULL, &ea) == 0);
        const double t1 = now_ms();
        CHECK(ref_polygon_sh_method(REF_AREA, 30, c[i].x, c[i].v, c[i].n, b, NULL, &eb) == 0);
        tp += t1 - t0;
        ta += now_ms() - t1;
        worst = fmax(worst, maxdiff(a, b, NC30) / om);
        est = fmax(est, fmax(ea, eb) / om);
    }
    harness_note("lmax 30 max|diff|/Omega %.1e", worst);
    harness_note("err_est/Omega %.1e", est);
    harness_note("ms/call polar %.0f area %.0f", tp / nc, ta / nc);
    CHECK(worst <= 1e-14);
}

SHL_TEST(ref_winding_independence)
{
    struct cfg c[32];
    double buf[512], rv[24];
    static double a[NC30], b[NC30];
    const int nc = moderate(c, buf);
    double worst = 0.0;
    for (int i = 0; i < nc; i += 3) {
        const double om = ref_polygon_solid_angle(c[i].x, c[i].v, c[i].n);
        reverse(c[i].v, c[i].n, rv);
        for (int m = REF_POLAR; m <= REF_AREA; ++m) {
            CHECK(ref_polygon_sh_method(m, 30, c[i].x, c[i].v, c[i].n, a, NULL, NULL) == 0);
            CHECK(ref_polygon_sh_method(m, 30, c[i].x, rv, c[i].n, b, NULL, NULL) == 0);
            worst = fmax(worst, maxdiff(a, b, NC30) / om);
        }
    }
    harness_note("reversed vs given max|diff|/Omega %.1e", worst);
    CHECK(worst <= 1e-14);
}

SHL_TEST(ref_gradient_vs_fd)
{
    /* Analytic gradients (boundary integral on the polar path, differentiated
     * integrand on the area path) vs 8th-order central differences. */
    double sq[12], tiny[12], big[12];
    rect(0, 1, 0, 1, sq);
    rect(0, 1e4, 0, 1e4, big);
    static const double ang[3] = {0.4, 1.0, 0.25}, tr[3] = {3.0, 1.0, 9.0};
    double t0[12];
    rect(-0.5e-4, 0.5e-4, -0.5e-4, 0.5e-4, t0);
    rigid(ang, tr, t0, 4, tiny);
    make_star();
    const struct {
        const double *v;
        int n, lmax;
        double x[3], step;
    } cs[] = {
        {sq, 4, 14, {0.3125, 0.1875, 0.5}, 0x1p-10},
        {tri_v, 3, 14, {2.0, 1.5, -1.0}, 0x1p-10},
        {star_v, 8, 14, {0.8125, 0.8125, 0.625}, 0x1p-10},
        {lhex_v, 6, 8, {1.5, 1.5, 1.5}, 0x1p-10},
        {tiny, 4, 14, {0.0, 0.0, 0.0}, 0x1p-8},                       /* area path */
        {sq, 4, 14, {0.3125, 0.4375, 0x1p-13}, 0x1p-16},              /* h ~ 1.2e-4, inside */
        {sq, 4, 14, {2.0, 0.5, 0x1p-23}, 0x1p-28},                    /* h ~ 1.2e-7, outside */
        {sq, 4, 14, {0.3125, -0x1p-21, 0x1p-21}, 0x1p-28},            /* ~7e-7 from an edge, outside */
        {sq, 4, 14, {0.3125, 0x1p-21, 0x1p-21}, 0x1p-28},             /* ~7e-7 from an edge, inside */
        {sq, 4, 8, {0.3125, 0.0, 0x1p-20}, 0x1p-28},                  /* ~1e-6 above an edge */
        {big, 4, 8, {1234.5, 2000.25, 1.0}, 0x1p-6},
        {sq, 4, 30, {0.3125, 0.1875, 0.5}, 0x1p-10},
    };
    static double co[NC30], g[3 * NC30], fd[3 * NC30];
    double worst = 0.0;
    for (unsigned i = 0; i < sizeof cs / sizeof cs[0]; ++i) {
        const int nc = NC(cs[i].lmax);
        CHECK(ref_polygon_sh_grad(cs[i].lmax, cs[i].x, cs[i].v, cs[i].n, co, g, NULL) == 0);
        CHECK(fd_grad(cs[i].lmax, cs[i].x, cs[i].v, cs[i].n, cs[i].step, fd) == 0);
        const double e = maxdiff(g, fd, 3 * nc) / maxabs(g, 3 * nc);
        worst = fmax(worst, e);
        if (!(e <= 1e-9)) harness_note("case %u: %.1e", i, e);
    }
    harness_note("max |grad - FD8| / max|grad| %.1e", worst);
    CHECK(worst <= 1e-9);
}

SHL_TEST(ref_gradient_near_plane)
{
    /* Within 1e-7 of the plane the coefficients vary on the scale h, so central
     * differences resolve the normal derivative only to ~eps Omega / h: check
     * grad Y00 against the derivative of the corner formula, and all
     * coefficients against FD8 with the step h/64. */
    double sq[12], g3[3];
    rect(0, 1, 0, 1, sq);
    static const double xs[][3] = {{0.5, 0.5, 1e-7}, {0.3, 0.7, -1e-7}, {2.0, 0.5, 1e-7},
                                   {0.3125, -0x1p-21, 0x1p-21}, {0.3125, 0x1p-21, 0x1p-21}, {0.5, 1e-7, 1e-7}};
    static double co[NC(8)], g[3 * NC(8)], fd[3 * NC(8)];
    const int nc = NC(8);
    double e_y00 = 0.0, e_fd = 0.0;
    for (int i = 0; i < 6; ++i) {
        CHECK(ref_polygon_sh_grad(8, xs[i], sq, 4, co, g, NULL) == 0);
        rect_omega_grad(0, 1, 0, 1, xs[i], g3);
        const double gm = fmax(fabs(g3[0]), fmax(fabs(g3[1]), fabs(g3[2])));
        for (int a = 0; a < 3; ++a) e_y00 = fmax(e_y00, fabs(g[a * nc] * 2.0 * sqrt(M_PI) - g3[a]) / gm);
        CHECK(fd_grad(8, xs[i], sq, 4, fabs(xs[i][2]) / 64.0, fd) == 0);
        e_fd = fmax(e_fd, maxdiff(g, fd, 3 * nc) / maxabs(g, 3 * nc));
    }
    harness_note("grad Y00 vs corner formula %.1e", e_y00);
    harness_note("vs FD8 (step h/64) %.1e", e_fd);
    CHECK(e_y00 <= 1e-13);
    CHECK(e_fd <= 1e-6);
}

SHL_TEST(ref_gradient_polar_vs_area)
{
    struct cfg c[32];
    double buf[512];
    static double a[NC(14)], b[NC(14)], ga[3 * NC(14)], gb[3 * NC(14)];
    const int nc = moderate(c, buf), n3 = 3 * NC(14);
    double worst = 0.0;
    for (int i = 0; i < nc; i += 2) {
        CHECK(ref_polygon_sh_method(REF_POLAR, 14, c[i].x, c[i].v, c[i].n, a, ga, NULL) == 0);
        CHECK(ref_polygon_sh_method(REF_AREA, 14, c[i].x, c[i].v, c[i].n, b, gb, NULL) == 0);
        worst = fmax(worst, maxdiff(ga, gb, n3) / maxabs(ga, n3));
    }
    harness_note("lmax 14 max|diff| / max|grad| %.1e", worst);
    CHECK(worst <= 1e-13);
}

SHL_TEST(ref_hard_near_plane)
{
    /* x 1e-7 above the plane inside / outside the footprint, and 7e-7 from an edge:
     * corner formula, irradiance vector (inside), both paths (outside), and
     * additivity over a split of the square. */
    double sq[12], lo[12], hi[12];
    rect(0, 1, 0, 1, sq);
    rect(0, 1, 0, 0.5, lo);
    rect(0, 1, 0.5, 1, hi);
    static const double xs[][3] = {{0.5, 0.5, 1e-7},       {0.3, 0.7, -1e-7},         {2.0, 0.5, 1e-7},
                                   {-0.75, -1.25, 1e-7},   {0.3125, -0x1p-21, 0x1p-21}, {0.3125, 0x1p-21, 0x1p-21},
                                   {0.5, 0.5 + 1e-9, 1e-7}};
    static double a[NC30], b[NC30], s[NC30];
    double e_om = 0.0, e_b1 = 0.0, e_add = 0.0, e_paths = 0.0, tmax = 0.0;
    for (int i = 0; i < 7; ++i) {
        const double want = rect_omega(0, 1, 0, 1, xs[i]);
        double w1[3];
        const double t0 = now_ms();
        CHECK(ref_polygon_sh(30, xs[i], sq, 4, a, NULL) == 0);
        tmax = fmax(tmax, now_ms() - t0);
        e_om = fmax(e_om, fabs(a[0] * 2.0 * sqrt(M_PI) - want) / want);
        if (want > 1.0) { /* no cancellation in the closed form */
            band1(xs[i], sq, 4, w1);
            e_b1 = fmax(e_b1, maxdiff(a + 1, w1, 3) / want);
        }
        if (want < 1e-6) { /* far outside: the area path is well conditioned */
            CHECK(ref_polygon_sh_method(REF_AREA, 30, xs[i], sq, 4, b, NULL, NULL) == 0);
            e_paths = fmax(e_paths, maxdiff(a, b, NC30) / want);
        }
        CHECK(ref_polygon_sh(30, xs[i], lo, 4, b, NULL) == 0);
        CHECK(ref_polygon_sh(30, xs[i], hi, 4, s, NULL) == 0);
        for (int k = 0; k < NC30; ++k) s[k] += b[k];
        e_add = fmax(e_add, maxdiff(a, s, NC30) / want);
    }
    harness_note("Y00 %.1e", e_om);
    harness_note("band 1 %.1e", e_b1);
    harness_note("polar vs area %.1e", e_paths);
    harness_note("split additivity %.1e (lmax 30)", e_add);
    harness_note("max %.0f ms/call", tmax);
    CHECK(e_om <= 1e-14);
    CHECK(e_b1 <= 1e-14);
    CHECK(e_paths <= 1e-14);
    CHECK(e_add <= 1e-14);
}

SHL_TEST(ref_hard_tiny)
{
    /* Square of side 1e-4 at distance ~10, facing x and oblique: auto (area) vs
     * polar path, Y00 vs VOS.  Band 1 by the irradiance vector cancels ~5 digits
     * (perimeter/area), hence its looser bound. */
    double t0[12], v[12], w1[3];
    rect(-0.5e-4, 0.5e-4, -0.5e-4, 0.5e-4, t0);
    static const double angs[][3] = {{0.0, 0.0, 0.3}, {0.4, 1.0, 0.25}, {2.0, 1.45, -1.0}};
    static double a[NC30], b[NC30];
    double e_paths = 0.0, e_om = 0.0, e_b1 = 0.0, ta = 0.0;
    for (int i = 0; i < 3; ++i) {
        const double tr[3] = {0.0, 0.0, 10.0}, x[3] = {0.0, 0.0, 0.0};
        rigid(angs[i], tr, t0, 4, v);
        const double om = ref_polygon_solid_angle(x, v, 4);
        const double t1 = now_ms();
        CHECK(ref_polygon_sh(30, x, v, 4, a, NULL) == 0);
        ta = fmax(ta, now_ms() - t1);
        CHECK(ref_polygon_sh_method(REF_POLAR, 30, x, v, 4, b, NULL, NULL) == 0);
        e_paths = fmax(e_paths, maxdiff(a, b, NC30) / om);
        e_om = fmax(e_om, fabs(a[0] * 2.0 * sqrt(M_PI) - om) / om);
        band1(x, v, 4, w1);
        e_b1 = fmax(e_b1, maxdiff(a + 1, w1, 3) / om);
    }
    harness_note("area vs polar %.1e", e_paths);
    harness_note("Y00 %.1e", e_om);
    harness_note("band 1 %.1e", e_b1);
    harness_note("%.1f ms/call", ta);
    CHECK(e_paths <= 1e-14);
    CHECK(e_om <= 1e-14);
    CHECK(e_b1 <= 1e-9);
}

SHL_TEST(ref_hard_huge)
{
    /* Square of side 1e4 at distance 1: corner formula, irradiance vector, and
     * additivity over four quadrants split away from the foot point (lmax 30). */
    double big[12], q[4][12];
    rect(-5e3, 5e3, -5e3, 5e3, big);
    rect(-5e3, 100.0, -5e3, -50.0, q[0]);
    rect(100.0, 5e3, -5e3, -50.0, q[1]);
    rect(100.0, 5e3, -50.0, 5e3, q[2]);
    rect(-5e3, 100.0, -50.0, 5e3, q[3]);
    static const double xs[][3] = {{0.0, 0.0, 1.0}, {1234.5, -2000.0, -1.0}, {4999.0, 0.0, 1.0}};
    static double a[NC30], s[NC30], b[NC30];
    double e_om = 0.0, e_b1 = 0.0, e_add = 0.0, tmax = 0.0;
    for (int i = 0; i < 3; ++i) {
        double w1[3];
        const double want = rect_omega(-5e3, 5e3, -5e3, 5e3, xs[i]);
        const double t0 = now_ms();
        CHECK(ref_polygon_sh(30, xs[i], big, 4, a, NULL) == 0);
        tmax = fmax(tmax, now_ms() - t0);
        e_om = fmax(e_om, fabs(a[0] * 2.0 * sqrt(M_PI) - want) / want);
        band1(xs[i], big, 4, w1);
        e_b1 = fmax(e_b1, maxdiff(a + 1, w1, 3) / want);
        memset(s, 0, sizeof s);
        for (int j = 0; j < 4; ++j) {
            CHECK(ref_polygon_sh(30, xs[i], q[j], 4, b, NULL) == 0);
            for (int k = 0; k < NC30; ++k) s[k] += b[k];
        }
        e_add = fmax(e_add, maxdiff(a, s, NC30) / want);
    }
    harness_note("Y00 %.1e", e_om);
    harness_note("band 1 %.1e", e_b1);
    harness_note("quadrant additivity %.1e", e_add);
    harness_note("max %.0f ms/call", tmax);
    CHECK(e_om <= 1e-14);
    CHECK(e_b1 <= 1e-14);
    CHECK(e_add <= 1e-14);
}

SHL_TEST(ref_hard_concave)
{
    /* L-shaped hexagon = union of two rectangles (additivity, lmax 30), including
     * x near the plane in the notch; star octagon: both paths and winding. */
    double r1[12], r2[12], rv[24];
    rect(0, 2, 0, 1, r1);
    rect(0, 1, 1, 2, r2);
    static const double xs[][3] = {{1.5, 1.5, 0.5}, {1.5, 1.5, 1e-7}, {0.5, 0.5, 1e-7}, {0.5, 1.5, -0.2}, {-1.0, 3.0, 2.0}};
    static double a[NC30], b[NC30], s[NC30];
    double e_add = 0.0, e_star = 0.0, e_om = 0.0;
    for (int i = 0; i < 5; ++i) {
        const double om = ref_polygon_solid_angle(xs[i], lhex_v, 6);
        e_om = fmax(e_om, fabs(om - rect_omega(0, 2, 0, 1, xs[i]) - rect_omega(0, 1, 1, 2, xs[i])) / om);
        CHECK(ref_polygon_sh(30, xs[i], lhex_v, 6, a, NULL) == 0);
        CHECK(ref_polygon_sh(30, xs[i], r1, 4, b, NULL) == 0);
        CHECK(ref_polygon_sh(30, xs[i], r2, 4, s, NULL) == 0);
        for (int k = 0; k < NC30; ++k) s[k] += b[k];
        e_add = fmax(e_add, maxdiff(a, s, NC30) / om);
    }
    make_star();
    reverse(star_v, 8, rv);
    static const double xst[][3] = {{0.9, 0.0, 0.7}, {0.6, 0.6, 1.5}, {0.0, 0.0, -2.0}};
    for (int i = 0; i < 3; ++i) {
        const double om = ref_polygon_solid_angle(xst[i], star_v, 8);
        e_om = fmax(e_om, fabs(om - vos(xst[i], star_v, 8)) / om);
        CHECK(ref_polygon_sh_method(REF_POLAR, 30, xst[i], star_v, 8, a, NULL, NULL) == 0);
        CHECK(ref_polygon_sh_method(REF_AREA, 30, xst[i], rv, 8, b, NULL, NULL) == 0);
        e_star = fmax(e_star, maxdiff(a, b, NC30) / om);
    }
    harness_note("L additivity %.1e", e_add);
    harness_note("star polar vs area(reversed) %.1e", e_star);
    harness_note("Omega %.1e", e_om);
    CHECK(e_add <= 1e-14);
    CHECK(e_star <= 1e-14);
    CHECK(e_om <= 1e-14);
}

SHL_TEST(ref_edge_cases)
{
    double sq[12], co[NC(4)], g[3 * NC(4)];
    rect(0, 1, 0, 1, sq);
    static const double inplane[][3] = {{0.5, 0.5, 0.0}, {3.0, -1.0, 0.0}};
    for (int i = 0; i < 2; ++i) {
        co[0] = 1.0;
        CHECK(ref_polygon_sh(4, inplane[i], sq, 4, co, NULL) == 0);
        CHECK(maxabs(co, NC(4)) == 0.0);
        CHECK(ref_polygon_sh_grad(4, inplane[i], sq, 4, co, g, NULL) == REF_EINPLANE);
        CHECK(ref_polygon_solid_angle(inplane[i], sq, 4) == 0.0);
    }
    const double x[3] = {0.2, 0.3, 1.0}, line[9] = {0, 0, 0, 1, 1, 1, 2, 2, 2};
    CHECK(ref_polygon_sh(4, x, line, 3, co, NULL) == REF_EDEGEN);
    CHECK(ref_polygon_sh(4, x, sq, 2, co, NULL) == REF_EARG);
    CHECK(ref_polygon_sh(31, x, sq, 4, co, NULL) == REF_EARG);
    CHECK(ref_polygon_sh(-1, x, sq, 4, co, NULL) == REF_EARG);
    CHECK(ref_polygon_sh_method(3, 4, x, sq, 4, co, NULL, NULL) == REF_EARG);
    CHECK(ref_polygon_sh_grad(4, x, sq, 4, co, NULL, NULL) == REF_EARG);
    const double bad[3] = {0.2, NAN, 1.0};
    CHECK(ref_polygon_sh(4, bad, sq, 4, co, NULL) == REF_EARG);
    CHECK(isnan(ref_polygon_solid_angle(bad, sq, 4)));
    /* repeated vertex: same result as without it */
    const double rep[15] = {0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    double c2[NC(4)];
    CHECK(ref_polygon_sh(4, x, sq, 4, co, NULL) == 0);
    CHECK(ref_polygon_sh(4, x, rep, 5, c2, NULL) == 0);
    CHECK(maxdiff(co, c2, NC(4)) <= 1e-15);
}

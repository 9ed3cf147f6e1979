/* Polygonal lights: per-edge geometry, solid angle, and the ZH recurrence of
 * Wang & Ramamoorthi 2018 (Sec. 4.1).  The recurrence is written once in
 * polygon_zh.h and instantiated for double and float. */
#include "polygon.h"
#include "quad.h"
#include "zh_tables.h"
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <string.h>

static inline int imax(int a, int b) { return a > b ? a : b; }

/* shl__norm3 with its plain branch inline (the set-up takes ~10 norms per call): the
 * same value, the scaled fallback out of line */
static inline double norm3(const double v[3])
{
    const double d = shl__dot3(v, v);
    return d >= 0x1p-896 && d <= 0x1p900 ? sqrt(d) : shl__norm3(v);
}

/* (a - b) 2^e per component (internal.h) */
static inline void scaled_sub3(const double a[3], const double b[3], int e, double out[3])
{
    for (int k = 0; k < 3; ++k) out[k] = shl__diff_scaled(a[k], b[k], e);
}

/* Double-double arithmetic (value hi + lo, |lo| <= ulp(hi)/2) for the plane
 * distance; C11 without FP contraction keeps two_sum exact, fma gives the exact
 * product error (Ogita, Rump & Oishi 2005, TwoSum / TwoProduct). */
typedef struct {
    double hi, lo;
} dd;

static inline dd two_sum(double a, double b)
{
    const double s = a + b, bb = s - a;
    return (dd){s, (a - (s - bb)) + (b - bb)};
}
static inline dd fast_two_sum(double a, double b) /* |a| >= |b| or a == 0 */
{
    const double s = a + b;
    return (dd){s, b - (s - a)};
}
static inline dd dd_add(dd x, dd y)
{
    const dd s = two_sum(x.hi, y.hi);
    return fast_two_sum(s.hi, s.lo + x.lo + y.lo);
}
static inline dd dd_mul(dd x, dd y)
{
    const double p = x.hi * y.hi;
    return fast_two_sum(p, fma(x.hi, y.hi, -p) + (x.hi * y.lo + x.lo * y.hi));
}
static inline dd dd_neg(dd x) { return (dd){-x.hi, -x.lo}; }

/* (a - b) 2^e exactly as a double-double (up to underflow of the low part):
 * with a != b, |a - b| >= ulp(a) / 2 and |a - b| 2^e <= 2, so neither a 2^e nor
 * b 2^e overflows. */
static inline dd dd_diff_scaled(double a, double b, int e)
{
    if (a == b) return (dd){0.0, 0.0};
    if (isinf(a - b)) return (dd){shl__diff_scaled(a, b, e), 0.0}; /* |a|, |b| > 2^969: halves exact, 0.5 a - 0.5 b rounded */
    const dd s = two_sum(shl__ldexp(a, e), -shl__ldexp(b, e));
    return s;
}

/* Newell normal N = sum_i (v_i - v_0) x (v_{i+1} - v_0) (counter-clockwise seen
 * from its tip), with the vertex differences scaled by 2^-e that brings the
 * largest near 1 (no over/underflow), in double-double: the differences are
 * exact, each product carries a relative error <= ~2 eps^2, so N_k is accurate to
 * ~4 eps^2 sum_i |terms of N_k| (n <= SHL_MAX_VERTS).  Returns the unit normal in
 * nrm, N itself in big (scale 2^-2e) and |N| in len_out; 0 for a zero-area polygon (also vertices
 * equal up to the sign of zero). */
static int newell_normal(const double *verts, int n, double nrm[3], dd big[3], double *len_out, int *escale)
{
    int e = INT_MIN;
    for (int i = 1; i < n; ++i)
        for (int k = 0; k < 3; ++k) e = imax(e, shl__ilogb_diff(verts[3 * i + k], verts[k]));
    nrm[0] = nrm[1] = nrm[2] = 0.0;
    big[0] = big[1] = big[2] = (dd){0.0, 0.0};
    *escale = e;
    if (e == INT_MIN) return 0;
    dd prev[3];
    for (int k = 0; k < 3; ++k) prev[k] = dd_diff_scaled(verts[3 + k], verts[k], -e);
    for (int i = 1; i + 1 < n; ++i) {
        dd next[3];
        for (int k = 0; k < 3; ++k) next[k] = dd_diff_scaled(verts[3 * (i + 1) + k], verts[k], -e);
        for (int k = 0; k < 3; ++k) {
            const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
            big[k] = dd_add(big[k], dd_add(dd_mul(prev[k1], next[k2]), dd_neg(dd_mul(prev[k2], next[k1]))));
        }
        memcpy(prev, next, sizeof prev);
    }
    const double hi[3] = {big[0].hi, big[1].hi, big[2].hi};
    const double len = norm3(hi);
    *len_out = len;
    if (!(len > 0.0)) return 0;
    for (int k = 0; k < 3; ++k) nrm[k] = hi[k] / len;
    return 1;
}

/* Signed distance of x from the polygon's plane, along +nrm from x to the plane, in
 * the scaled units of rel (2^-ex):
 *   h = N . (v_0 - x) / |N|,
 * N . (v_0 - x) = sum_i det(v_i - v_0, v_{i+1} - v_0, v_0 - x) in double-double from
 * exact differences.  Guarantee (any finite input, no underflow): with cond =
 * sum |each of the 6 (n-2) triple products of coordinate differences| / |N . (v_0 - x)|
 * (the componentwise condition number of that sum), the relative error is
 *   |h_computed - h| / |h| <= 3 eps + 16 n eps^2 cond,      eps = 2^-53,
 * (one rounding of the double-double to double, |N| to 2 eps); cond ~ distance / |h| for
 * a tilted plane, so h is accurate to a few ulps while |h| >= ~1e-14 x distance.  An
 * axis-aligned plane is exact (cond = 1). */
static double plane_height(const double *verts, const double x[3], const dd big[3], double len, int ex)
{
    dd acc = {0.0, 0.0};
    for (int k = 0; k < 3; ++k) acc = dd_add(acc, dd_mul(big[k], dd_diff_scaled(verts[k], x[k], -ex)));
    return acc.hi / len; /* len = |N| (newell_normal), N in units 2^-2e: the ratio is in units 2^-ex */
}

/* In-plane offsets from the foot F of x of the vertices (e[i] = rel_i minus its
 * normal component). */
static void plane_offsets(const double (*rel)[3], int n, const double nrm[3], double (*e)[3])
{
    for (int i = 0; i < n; ++i) {
        const double h = shl__dot3(nrm, rel[i]);
        for (int k = 0; k < 3; ++k) e[i][k] = rel[i][k] - h * nrm[k];
    }
}

/* Solid angle of the polygon (magnitude) as a fan of Van Oosterom-Strackee
 * triangles, tan(omega/2) = N / D.  Unlike the sum-of-angles formula (Wang 2018
 * Eq. 24) this keeps full relative accuracy for tiny polygons and handles
 * concave ones.  Two fans, each used where its D is a sum of positive terms, so
 * no term crosses atan2's branch cut:
 *  - far from the plane (|h| >= 2 x extent) the fan from vertex 0: all vertex
 *    directions lie within 60 degrees of each other;
 *  - otherwise the fan from the foot F of x on the plane, where with e_i the
 *    in-plane offsets of the vertices from F, s_i = |e_i|, r_i = |v_i - x| and a = |h|,
 *    N and D divided by a are n.(e_i x e_j) and r_i r_j + a (r_i + r_j) + a^2 + e_i.e_j,
 *    and for e_i.e_j < 0  r_i r_j + e_i.e_j = (a^2 (a^2 + s_i^2 + s_j^2) + |e_i x e_j|^2) / (r_i r_j - e_i.e_j).
 * Near the plane with F outside the polygon the triangle angles omega_i tend to the
 * planar angles theta_i of the edges at F, which sum to 0: the sum of O(1) terms
 * cancels down to O(a).  So the fan is also summed as
 *   omega = 2 pi k + sum_i (omega_i - theta_i),   k = round(sum_i theta_i / 2 pi),
 * with tan(theta_i/2) = n.(e_i x e_j) / D0, D0 = s_i s_j + e_i.e_j >= 0, and
 *   tan((omega_i - theta_i)/2) = -a n.(e_i x e_j) P / (D D0 + (n.(e_i x e_j))^2),
 *   P = (D - D0)/a = a (s_i^2 + s_j^2 + a^2) / (r_i r_j + s_i s_j) + r_i + r_j + a > 0,
 * (tan(x - y) = (tan x - tan y) / (1 + tan x tan y), both half-angles of one sign,
 * |omega_i| < |theta_i|): every term carries the factor a explicitly and is computed
 * to a few ulps from a (plane_height) and the in-plane geometry, so the cancellation
 * left is that of the planar picture (~ distance of F / depth of the polygon), not
 * 1/a.  The form whose terms have the smaller magnitude sum is returned (that sum
 * times a few eps bounds its rounding error).  *extent_out = the polygon's size;
 * edges[i] = (v_{i+1} - v_i) 2^e. */
static double solid_angle(const double (*rel)[3], const double *dist, const double (*edges)[3], const double *verts,
                          int n, int e, const double nrm[3], double height, double *extent_out)
{
    double ext2 = 0.0, total = 0.0;
    for (int i = 1; i < n; ++i) {
        double d[3];
        scaled_sub3(verts + 3 * i, verts, e, d);
        const double d2 = shl__dot3(d, d);
        ext2 = d2 > ext2 ? d2 : ext2;
    }
    const double extent = sqrt(ext2); /* = the largest sqrt(d . d): sqrt is monotone and correctly rounded */
    *extent_out = extent;
    if (fabs(height) >= 2.0 * extent) {
        for (int i = 1; i + 1 < n; ++i) {
            double e1[3], e2[3], c[3];
            scaled_sub3(verts + 3 * i, verts, e, e1);
            scaled_sub3(verts + 3 * (i + 1), verts, e, e2);
            shl__cross3(e1, e2, c);
            const double num = shl__dot3(rel[0], c);
            const double den = dist[0] * dist[i] * dist[i + 1] + shl__dot3(rel[0], rel[i]) * dist[i + 1] +
                               shl__dot3(rel[0], rel[i + 1]) * dist[i] + shl__dot3(rel[i], rel[i + 1]) * dist[0];
            total += 2.0 * atan2(num, den);
        }
        return fabs(total);
    }
    const double a = fabs(height);
    double abs_total = 0.0, theta = 0.0, delta = 0.0, abs_delta = 0.0;
    double num_i[SHL_MAX_VERTS], den_i[SHL_MAX_VERTS], dot_i[SHL_MAX_VERTS], s_i[SHL_MAX_VERTS];
    double off[SHL_MAX_VERTS][3]; /* in-plane offsets e_i from the foot, s_i = |e_i| */
    plane_offsets(rel, n, nrm, off);
    for (int i = 0; i < n; ++i) s_i[i] = norm3(off[i]);
    int npos = 0, nneg = 0;
    for (int i = 0; i < n; ++i) {
        const int j = (i + 1 == n) ? 0 : i + 1;
        const double *ei = off[i], *ej = off[j], si = s_i[i], sj = s_i[j];
        double c[3];
        /* e_i x e_j = e_i x (v_j - v_i) = e_j x (v_j - v_i): from the shorter offset (as cv in geom_init) */
        shl__cross3(si <= sj ? ei : ej, edges[i], c);
        const double num = shl__dot3(nrm, c), dot = shl__dot3(ei, ej), ri = dist[i], rj = dist[j];
        const double pair = dot >= 0.0 ? ri * rj + dot
                                       : (a * a * (a * a + si * si + sj * sj) + num * num) / (ri * rj - dot);
        const double den = pair + a * (ri + rj) + a * a;
        const double term = 2.0 * atan2(num, den);
        total += term;
        abs_total += fabs(term);
        npos += term > 0.0, nneg += term < 0.0;
        num_i[i] = num, den_i[i] = den, dot_i[i] = dot;
    }
    /* Terms of one sign: the direct sum's magnitude sum is |total|, the least any form
     * can have, so the split below could not be chosen for a smaller one.  Within 4x
     * of that least (the direct sum loses at most 2 bits to cancellation, as at a
     * moderate height) the split's n more atan2 calls are not spent either. */
    if (npos == 0 || nneg == 0 || abs_total <= 4.0 * fabs(total)) return fabs(total);
    for (int i = 0; i < n; ++i) {
        const int j = (i + 1 == n) ? 0 : i + 1;
        const double *ei = off[i], *ej = off[j];
        /* The split omega_i = theta_i + (omega_i - theta_i) below needs the foot well
         * inside or outside: on an edge or a vertex theta_i is +-pi or atan2(0, 0), and
         * within ~a of one theta_i turns by O(1) over distances where omega_i barely
         * changes (fuzz_polygon: foot 1.4e-12 from a vertex at a = 1e-9 gave 4e-5
         * relative).  There the direct sum is used: its error is the conditioning of a
         * point near an edge, eps S / d. */
        double f[3], t = 0.0;
        for (int k = 0; k < 3; ++k) f[k] = ej[k] - ei[k];
        const double ff = shl__dot3(f, f);
        if (ff > 0.0) t = fmin(1.0, fmax(0.0, -shl__dot3(ei, f) / ff));
        double q[3];
        for (int k = 0; k < 3; ++k) q[k] = ei[k] + t * f[k]; /* the edge's point nearest the foot */
        if (!(shl__dot3(q, q) > a * a) || /* |q| > a; q, a in scaled units: no underflow of a^2 */
            (num_i[i] == 0.0 && dot_i[i] <= 0.0) || s_i[i] == 0.0 || s_i[j] == 0.0)
            return fabs(total);
    }
    for (int i = 0; i < n; ++i) {
        const int j = (i + 1 == n) ? 0 : i + 1;
        const double num = num_i[i], den = den_i[i], dot = dot_i[i], si = s_i[i], sj = s_i[j];
        const double ri = dist[i], rj = dist[j];
        const double den0 = dot >= 0.0 ? si * sj + dot : num * num / (si * sj - dot);
        theta += 2.0 * atan2(num, den0);
        const double p = a * (si * si + sj * sj + a * a) / (ri * rj + si * sj) + ri + rj + a;
        const double dterm = 2.0 * atan2(-a * num * p, den * den0 + num * num);
        delta += dterm;
        abs_delta += fabs(dterm);
    }
    const double k = nearbyint(theta / (2.0 * M_PI));
    if (2.0 * M_PI * fabs(k) + abs_delta < abs_total) return fabs(2.0 * M_PI * k + delta);
    return fabs(total);
}

/* In-plane distance from F (the origin of the offsets) to the triangle (p0, p1, p2),
 * 0 when F is inside or on it; *diam = its longest side. */
static double triangle_distance(const double *const p[3], const double nrm[3], double *diam)
{
    double best = HUGE_VAL, longest = 0.0;
    int pos = 0, neg = 0;
    for (int s = 0; s < 3; ++s) {
        const double *a = p[s], *b = p[(s + 1) % 3];
        double c[3], d[3], f[3];
        shl__cross3(a, b, c);
        const double side = shl__dot3(nrm, c);
        pos += side > 0.0, neg += side < 0.0;
        for (int k = 0; k < 3; ++k) d[k] = b[k] - a[k];
        const double dd2 = shl__dot3(d, d);
        const double u = dd2 > 0.0 ? fmin(1.0, fmax(0.0, -shl__dot3(a, d) / dd2)) : 0.0;
        for (int k = 0; k < 3; ++k) f[k] = a[k] + u * d[k];
        best = fmin(best, shl__norm3(f));
        longest = fmax(longest, sqrt(dd2));
    }
    *diam = longest;
    return pos == 0 || neg == 0 ? 0.0 : best;
}

/* In-plane distance from F to the union of the triangles (v_0, v_i, v_{i+1}) of the
 * vertex fan, 0 when F is inside one of them. */
static double fan_distance(const double (*rel)[3], int n, const double nrm[3])
{
    double e[SHL_MAX_VERTS][3], best = HUGE_VAL, diam;
    plane_offsets(rel, n, nrm, e);
    for (int t = 1; t + 1 < n; ++t) {
        const double *const tri[3] = {e[0], e[t], e[t + 1]};
        best = fmin(best, triangle_distance(tri, nrm, &diam));
    }
    return best;
}

/* with_grad = 0: the gradient terms (gvec, fprime1, f_integral) are left unset;
 * everything else is computed as with with_grad = 1, bit for bit. */
static void geom_init(shl__poly_geom *g, const double x[3], const double *verts, int n, int with_grad)
{
    double kept[SHL_MAX_VERTS * 3];
    const int m = shl__drop_repeated(verts, n, kept); /* zero-length edges */
    g->n = 0;
    g->sliver = 0;
    g->solid_angle = 0.0;
    g->grad_scale[0] = g->grad_scale[1] = 1.0;
    g->gvec_max = 0.0;
    if (m < 3) return;

    /* scaled units: v - x times 2^-ex, largest component in [1, 2) (internal.h) */
    const int ex = shl__scale_exponent(x, kept, m);
    if (ex == INT_MIN) return; /* x on a vertex: in the plane */
    for (int i = 0; i < m; ++i) {
        scaled_sub3(kept + 3 * i, x, -ex, g->rel[i]);
        g->dist[i] = norm3(g->rel[i]); /* norm3: a vertex within 2^-537 of x would underflow rel . rel */
        if (!(g->dist[i] > 0.0)) return; /* within 2^-1074 of the farthest vertex: on it, in the plane */
    }
    double nrm[3], rmax = 0.0, nlen = 0.0;
    dd big[3];
    int ev;
    if (!newell_normal(kept, m, nrm, big, &nlen, &ev)) return; /* zero-area polygon: sees nothing */
    for (int i = 0; i < m; ++i) rmax = fmax(rmax, g->dist[i]);
    const double height = plane_height(kept, x, big, nlen, ex); /* signed: > 0 when the polygon lies along +nrm */
    /* Below a few ulps of the distances the side of the plane is decided by rounding. */
    if (fabs(height) <= 8.0 * DBL_EPSILON * rmax) return;
    /* Seen from x, the polygon is counter-clockwise from outside the unit sphere
     * (positive solid angle) exactly when it lies along +nrm: otherwise reverse. */
    if (height < 0.0) {
        for (int i = 0, j = m - 1; i < j; ++i, --j)
            for (int k = 0; k < 3; ++k) {
                const double t = kept[3 * i + k];
                kept[3 * i + k] = kept[3 * j + k];
                kept[3 * j + k] = t;
            }
        for (int i = 0, j = m - 1; i < j; ++i, --j) { /* rel, dist of the reversed vertices: the same rows */
            double t[3];
            memcpy(t, g->rel[i], sizeof t);
            memcpy(g->rel[i], g->rel[j], sizeof t);
            memcpy(g->rel[j], t, sizeof t);
            const double d = g->dist[i];
            g->dist[i] = g->dist[j];
            g->dist[j] = d;
        }
    }
    double edges[SHL_MAX_VERTS][3]; /* from the input vertices: exact for nearby ones */
    for (int e = 0; e < m; ++e) scaled_sub3(kept + 3 * (e + 1 == m ? 0 : e + 1), kept + 3 * e, -ex, edges[e]);
    double extent;
    const double omega = solid_angle((const double(*)[3])g->rel, g->dist, (const double(*)[3])edges, kept, m, -ex,
                                     nrm, height, &extent);
    g->n = m;
    g->solid_angle = omega;
    shl__pow2_split(-ex, g->grad_scale); /* d/dx = 2^-ex d/dx_scaled */
    memcpy(g->nrm, nrm, sizeof g->nrm);
    g->height = fabs(height);
    /* dmin <= the in-plane distance of vertex 0 from the foot <= rmax (up to a few ulps):
     * beyond 64 |h| > 2 rmax no fan distance can reach 64 |h| */
    const double dmin = 64.0 * g->height <= 2.0 * rmax ? fan_distance((const double(*)[3])g->rel, m, nrm) : 0.0;
    g->sliver = 64.0 * g->height <= dmin && 4.0 * dmin >= extent;

    for (int e = 0; e < m; ++e)
        for (int k = 0; k < 3; ++k) g->w[e][k] = g->rel[e][k] / g->dist[e];
    /* Loops by stage (cross products, atan2 calls, divisions): the edges' chains overlap. */
    double cv[SHL_MAX_VERTS][3], clen_e[SHL_MAX_VERTS], dotp_e[SHL_MAX_VERTS];
    for (int e = 0; e < m; ++e) {
        const int f = e + 1 == m ? 0 : e + 1;
        /* rel_e x rel_f = rel_e x edge = rel_f x edge, the edge exact for nearby vertices: from the
         * nearer vertex, the error is eps min(r_e, r_f) |edge|, i.e. eps min(r) / d_e relative (d_e the
         * distance from x to the edge's line); from the farther one it was eps max(r) / d_e, all of c
         * for x near the nearer vertex (fuzz_lights-far-edge-near-vertex-grad-inf: gamma pi, not pi/2) */
        shl__cross3(g->dist[f] < g->dist[e] ? g->rel[f] : g->rel[e], edges[e], cv[e]);
        clen_e[e] = norm3(cv[e]);
        dotp_e[e] = shl__dot3(g->rel[e], g->rel[f]);
    }
    /* Wang 2018 Eq. 20: gamma from atan2 is accurate for tiny and near-pi arcs */
    for (int e = 0; e < m; ++e) g->gamma[e] = atan2(clen_e[e], dotp_e[e]);
    for (int e = 0; e < m; ++e) {
        const int f = e + 1 == m ? 0 : e + 1;
        const double *edge = edges[e], *c = cv[e];
        const double clen = clen_e[e], dotp = dotp_e[e], rr = g->dist[e] * g->dist[f];
        if (rr >= 0x1p-900) { /* |c| = r_e r_f sin(gamma), rel_e . rel_f = r_e r_f cos(gamma): a few ulps */
            g->sin_gamma[e] = clen / rr;
            g->cos_gamma[e] = dotp / rr;
            /* 1 - cos = sin^2 / (1 + cos) without cancellation where cos > 0 */
            g->omc_gamma[e] = dotp > 0.0 ? g->sin_gamma[e] * g->sin_gamma[e] / (1.0 + g->cos_gamma[e])
                                         : 1.0 - g->cos_gamma[e];
        } else {
            g->sin_gamma[e] = sin(g->gamma[e]);
            g->cos_gamma[e] = cos(g->gamma[e]);
            const double half = sin(0.5 * g->gamma[e]);
            g->omc_gamma[e] = 2.0 * half * half;
        }
        /* w_f - w_e = edge/r_f + w_e (r_e - r_f)/r_f, r_e - r_f = -edge.(rel_e + rel_f)/(r_e + r_f):
         * no cancellation for an edge short against the distances; for a longer one its terms
         * can reach |edge| / min(r) (and overflow), while w_f - w_e itself is then accurate */
        const double rmin = g->dist[e] < g->dist[f] ? g->dist[e] : g->dist[f];
        /* |edge| <= min r: squared where rmin^2 is normal (an |edge|^2 that underflows is below
         * it too); by the norms below, where both squares underflow (x within 2^-500 of a
         * vertex in scaled units: there edge / r_f of a longer edge reached 1e151, and inf in
         * the float recurrence, fuzz_lights-subnormal-vertex-distance-float-nan) */
        if (rmin >= 0x1p-500 ? shl__dot3(edge, edge) <= rmin * rmin : norm3(edge) <= rmin) {
            double sum[3];
            for (int k = 0; k < 3; ++k) sum[k] = g->rel[e][k] + g->rel[f][k];
            const double dr = -shl__dot3(edge, sum) / (g->dist[e] + g->dist[f]);
            for (int k = 0; k < 3; ++k) g->dw[e][k] = edge[k] / g->dist[f] + g->w[e][k] * (dr / g->dist[f]);
        } else {
            for (int k = 0; k < 3; ++k) g->dw[e][k] = g->w[f][k] - g->w[e][k];
        }
        if (clen > 0.0) {
            for (int k = 0; k < 3; ++k) g->mu[e][k] = c[k] / clen;
            shl__cross3(g->mu[e], g->w[e], g->lam[e]);
        } else { /* underflowed arc: contributes nothing (gamma = 0, c_e = 0) */
            for (int k = 0; k < 3; ++k) g->mu[e][k] = g->lam[e][k] = 0.0;
        }
    }
    if (!with_grad) return;
    /* |gvec_e| = |edge| / |c| = 1 / (distance of x from the edge's line): beyond DBL_MAX in
     * scaled units for a non-planar polygon whose point is within ~2^-1020 of an edge's line
     * (scaled units; x near a vertex: fuzz_lights-subnormal-vertex-distance-float-nan), where
     * g x mu, f' and I_0 became inf and NaN.  The gradient is linear in (gvec, f', I_0), so they
     * are all kept times 2^-shift, shift > 0 only where some |gvec_e| would exceed 2^1000, and
     * shift is added to grad_scale: the result, 2^(shift - E) times finite numbers, is finite
     * wherever the gradient in x units is representable (to rounding; beyond, +-inf from the
     * unscaling).  The Hessian (polygon_hess.c) is quadratic in them and unscales by grad_scale
     * twice: consistent too.  |edge| <= 4 and |c| >= 2^-1074 bound the shift by 77. */
    int shift = 0;
    for (int e = 0; e < m; ++e) /* edge components below 4: ilogb |edge| <= 2, so |c| >= 2^-996 adds no shift */
        if (clen_e[e] > 0.0 && clen_e[e] < 0x1p-996)
            shift = imax(shift, shl__ilogb(norm3(edges[e])) - shl__ilogb(clen_e[e]) + 1 - 1000);
    if (shift > 0) shl__pow2_split(shift - ex, g->grad_scale);
    /* A loop of its own: the edges' division chains (mu, then gvec) overlap. */
    for (int e = 0; e < m; ++e) {
        const int f = e + 1 == m ? 0 : e + 1;
        const double clen = clen_e[e];
        if (clen > 0.0) {
            /* foot of x on the edge's line: q = edge x c / |edge|^2, so q/|q|^2 = (edge x mu) / |c|
             * (no product of two edge lengths: nothing underflows for a tiny, distant polygon);
             * times 2^-shift: |c| 2^shift is exact (shift = 0 but for the rare case above) */
            double q[3], gxmu[3];
            shl__cross3(edges[e], g->mu[e], q);
            const double clen_shifted = shl__ldexp(clen, shift);
            for (int k = 0; k < 3; ++k) {
                g->gvec[e][k] = q[k] / clen_shifted;
                g->gvec_max = fmax(g->gvec_max, fabs(g->gvec[e][k]));
            }
            shl__cross3(g->gvec[e], g->mu[e], gxmu); /* f'(t) = w(t) . (g x mu) since w' = mu x w */
            g->fprime1[e] = shl__dot3(g->w[f], gxmu);
            /* I_0 = g . int_0^gamma w(t) dt = g . (w_e sin(gamma) + lambda_e (1 - cos(gamma))) */
            g->f_integral[e] = shl__dot3(g->gvec[e], g->w[e]) * g->sin_gamma[e] +
                               shl__dot3(g->gvec[e], g->lam[e]) * g->omc_gamma[e];
        } else {
            for (int k = 0; k < 3; ++k) g->gvec[e][k] = 0.0;
            g->fprime1[e] = g->f_integral[e] = 0.0;
        }
    }
}

void shl__poly_geom_init(shl__poly_geom *g, const double x[3], const double *verts, int n)
{
    geom_init(g, x, verts, n, 1);
}

void shl__poly_geom_init_values(shl__poly_geom *g, const double x[3], const double *verts, int n)
{
    geom_init(g, x, verts, n, 0);
}

/* Near-plane sliver regime (g->sliver: the foot F of x lies outside the triangles
 * of the vertex fan, at in-plane distance dmin >= extent / 4 from them, and
 * |h| <= dmin / 64).  The boundary recurrence sums O(1) edge terms to O(|h|) there
 * (relative error ~ eps dmin / |h|: <= 1e-13 at the switch), so the ZH integrals are
 * taken over the plane instead:
 *   int_Q P_l(d . w) dw = int_polygon P_l(d . p / |p|) |h| / |p|^3 dA,   p = point - x,
 * with the explicit factor |h| (accurate, plane_height) and integrand values
 * accurate to a few ulps, on the signed fan of triangles with the collapsed
 * N x N Gauss-Legendre product p = A + u (B - A) + u v (C - B), dA = 2 |T| u du dv
 * (as irradiance.c's area_rule).  Error bound: every line of the rule is a segment
 * of length <= L (the triangle's longest side) at in-plane distance >= d_T from F;
 * the integrand's singularities are the complex points where |p|^2 = 0, at
 * imaginary offset sqrt(p_perp^2 + h^2) >= d_T from the real point nearest F, so
 * outside the Bernstein ellipse rho = s + sqrt(s^2 + 1), s = 2 d_T / L, of the
 * segment; Gauss-Legendre then errs by <= 64 M / (15 (rho^2 - 1) rho^(2N)) (Trefethen,
 * ATAP Thm. 19.3), where M = max |integrand| on the ellipse grows with l like the
 * Legendre polynomials off [-1, 1].  A triangle with s < 1 is split at its side
 * midpoints (L halves, d_T does not shrink) up to AREA_DEPTH times, which reaches
 * s >= 2^(AREA_DEPTH+1) dmin / extent >= 1 in the regime; then N is the least with
 * rho^(2N) >= 1e16 10^(lmax/4) (capped at 24: rho^48 >= 2e18 for rho >= 1 + sqrt 2; the
 * l-term is empirical: 1e16 alone leaves 3e-12 at lmax 14).  The result's error is
 * then rounding, measured <= 1e-13 of the solid angle up to lmax 14
 * (tests/test_polygon_nearplane.c).  S_0 is the exact solid angle.  Cost: (number of
 * triangles) N^2 nodes x (2 lmax + 1) lobes x lmax bands: ~40x the recurrence for a
 * quad at dmin ~ extent, ~170x at dmin = extent / 4 (the depth grows the cost ~4x
 * per level, so closer feet keep the recurrence). */
enum { NAREA_MAX = 24, AREA_DEPTH = 1 };

typedef struct {
    double p[3][3], e[3][3]; /* corners: rel (scaled v - x) and in-plane offset from F */
    int depth;
} area_tri;

void shl__poly_zh_area(const shl__poly_geom *g, int lmax, double *zh)
{
    enum { ND = 2 * SHL__AREA_LMAX + 1 };
    const int ndir = 2 * lmax + 1;
    double acc[SHL__AREA_LMAX + 1][ND], lx[ND], ly[ND], lz[ND], rec_a[SHL__AREA_LMAX + 1], rec_b[SHL__AREA_LMAX + 1];
    double e[SHL_MAX_VERTS][3];
    for (int l = 2; l <= lmax; ++l) {
        rec_a[l] = (2.0 * l - 1.0) / l; /* P_l = ((2l-1) z P_{l-1} - (l-1) P_{l-2}) / l */
        rec_b[l] = (l - 1.0) / l;
    }
    for (int d = 0; d < ndir; ++d) {
        lx[d] = shl__zh_dir[d][0], ly[d] = shl__zh_dir[d][1], lz[d] = shl__zh_dir[d][2];
        for (int l = 0; l <= lmax; ++l) acc[l][d] = 0.0;
    }
    plane_offsets((const double(*)[3])g->rel, g->n, g->nrm, e);
    double sgn_area = 0.0;
    for (int t = 1; t + 1 < g->n; ++t) {
        double ab[3], bc[3], c[3];
        for (int k = 0; k < 3; ++k) {
            ab[k] = g->rel[t][k] - g->rel[0][k];
            bc[k] = g->rel[t + 1][k] - g->rel[t][k];
        }
        shl__cross3(ab, bc, c);
        sgn_area += shl__dot3(g->nrm, c);
    }
    const double orient = sgn_area < 0.0 ? -1.0 : 1.0; /* signed fan: concave polygons too */
    for (int t = 1; t + 1 < g->n; ++t) {
        /* depth-first midpoint subdivision: corners (rel, in-plane offset) and depth */
        area_tri stack[3 * AREA_DEPTH + 1];
        int top = 0;
        for (int k = 0; k < 3; ++k) {
            const int vi = k == 0 ? 0 : t + k - 1;
            memcpy(stack[0].p[k], g->rel[vi], sizeof stack[0].p[k]);
            memcpy(stack[0].e[k], e[vi], sizeof stack[0].e[k]);
        }
        stack[0].depth = 0;
        while (top >= 0) {
            const area_tri tr = stack[top--];
            double diam, gx[NAREA_MAX], gw[NAREA_MAX];
            const double *const te[3] = {tr.e[0], tr.e[1], tr.e[2]};
            const double s = 2.0 * triangle_distance(te, g->nrm, &diam) / diam;
            if (s < 1.0 && tr.depth < AREA_DEPTH) { /* split into 4, orientation kept */
                area_tri mid;
                for (int k = 0; k < 3; ++k)
                    for (int c = 0; c < 3; ++c) {
                        mid.p[k][c] = 0.5 * (tr.p[k][c] + tr.p[(k + 1) % 3][c]);
                        mid.e[k][c] = 0.5 * (tr.e[k][c] + tr.e[(k + 1) % 3][c]);
                    }
                mid.depth = tr.depth + 1;
                for (int k = 0; k < 3; ++k) { /* corner k with the midpoints of its two sides */
                    area_tri *child = &stack[++top];
                    const int prev = (k + 2) % 3;
                    memcpy(child->p[0], tr.p[k], sizeof child->p[0]);
                    memcpy(child->e[0], tr.e[k], sizeof child->e[0]);
                    memcpy(child->p[1], mid.p[k], sizeof child->p[1]);
                    memcpy(child->e[1], mid.e[k], sizeof child->e[1]);
                    memcpy(child->p[2], mid.p[prev], sizeof child->p[2]);
                    memcpy(child->e[2], mid.e[prev], sizeof child->e[2]);
                    child->depth = mid.depth;
                }
                stack[++top] = mid;
                continue;
            }
            const double rho = s + sqrt(s * s + 1.0);
            const int nq = imax(2, (int)fmin(NAREA_MAX, ceil((8.0 + 0.125 * lmax) * log(10.0) / log(rho))));
            shl__gauss_legendre(nq, gx, gw);
            double ab[3], bc[3], c[3];
            for (int k = 0; k < 3; ++k) {
                ab[k] = tr.p[1][k] - tr.p[0][k];
                bc[k] = tr.p[2][k] - tr.p[1][k];
            }
            shl__cross3(ab, bc, c);
            const double scale = 0.25 * orient * shl__dot3(g->nrm, c) * g->height; /* du dv = dgx dgy / 4, |h| */
            for (int i = 0; i < nq; ++i) {
                const double u = 0.5 * (gx[i] + 1.0);
                for (int j = 0; j < nq; ++j) {
                    const double v = 0.5 * (gx[j] + 1.0);
                    double q[3], z[ND], p0[ND], p1[ND];
                    for (int k = 0; k < 3; ++k) q[k] = tr.p[0][k] + u * ab[k] + u * v * bc[k];
                    const double inv = 1.0 / shl__norm3(q);
                    const double wt = scale * gw[i] * gw[j] * u * inv * inv * inv;
                    for (int k = 0; k < 3; ++k) q[k] *= inv;
                    for (int d = 0; d < ndir; ++d) {
                        z[d] = lx[d] * q[0] + ly[d] * q[1] + lz[d] * q[2];
                        p0[d] = 1.0, p1[d] = z[d];
                        acc[1][d] += wt * z[d];
                    }
                    for (int l = 2; l <= lmax; ++l)
                        for (int d = 0; d < ndir; ++d) {
                            const double p2 = rec_a[l] * z[d] * p1[d] - rec_b[l] * p0[d];
                            p0[d] = p1[d], p1[d] = p2;
                            acc[l][d] += wt * p2;
                        }
                }
            }
        }
    }
    for (int d = 0; d < ndir; ++d) {
        zh[d * SHL__ZH_STRIDE] = sqrt(1.0 / (4.0 * M_PI)) * g->solid_angle;
        for (int l = 1; l <= lmax; ++l) zh[d * SHL__ZH_STRIDE + l] = sqrt((2.0 * l + 1.0) / (4.0 * M_PI)) * acc[l][d];
    }
}

static shl__zh_band_consts zh_bands;
static pthread_once_t zh_bands_once = PTHREAD_ONCE_INIT;

static void make_zh_bands(void)
{
    for (int l = 0; l <= SHL_LMAX_MAX; ++l) {
        const double den = l + (l == 0); /* l, 1 at l = 0 (the recurrences start at l = 2) */
        zh_bands.twol_m1[l] = 2 * l - 1;
        zh_bands.leg_a[l] = (2.0 * l - 1.0) / den; /* each one correctly rounded division */
        zh_bands.leg_b[l] = (l - 1.0) / den;
        zh_bands.b_alpha[l] = (2.0 * l - 1.0) / (den * den);
        zh_bands.b_beta[l] = (l - 1.0) * (l - 1.0) / (den * den);
        zh_bands.norm[l] = sqrt((2.0 * l + 1.0) / (4.0 * M_PI));
        zh_bands.inv_l[l] = 1.0 / (l + (l == 0));
        zh_bands.s_b[l] = (2.0 * l - 1.0) / (l * (l + 1.0) + (l == 0));
        zh_bands.s_s[l] = (l - 2.0) * (l - 1.0) / (l * (l + 1.0) + (l == 0));
    }
    zh_bands.inv_l[SHL_LMAX_MAX + 1] = 1.0 / (SHL_LMAX_MAX + 1); /* zh_lanes' I_{lmax} step */
}

const shl__zh_band_consts *shl__zh_bands(void)
{
    pthread_once(&zh_bands_once, make_zh_bands);
    return &zh_bands;
}

/* The double recurrence is the scalar ISA's kernel (simd/poly_zh_batch.h, lobes
 * two side by side); shl_polygon and shl_polygon_grad call their context's ISA. */
void shl__poly_zh_scalar(const shl__poly_geom *g, int lmax, double *zh);
void shl__poly_zh_grad_scalar(const shl__poly_geom *g, int lmax, double *zh, double *zh_grad);
void shl__poly_zh_d(const shl__poly_geom *g, int lmax, double *zh) { shl__poly_zh_scalar(g, lmax, zh); }
void shl__poly_zh_grad_d(const shl__poly_geom *g, int lmax, double *zh, double *zh_grad)
{
    shl__poly_zh_grad_scalar(g, lmax, zh, zh_grad);
}

/* Float instances of the recurrence (fk: float kernel), wrapped below. */
void shl__poly_zh_fk(const shl__poly_geom *g, int lmax, float *zh);
void shl__poly_zh_grad_fk(const shl__poly_geom *g, int lmax, float *zh, float *zh_grad);
#define REAL float
#define WITH_GRAD 0
#define SUFFIX(name) name##_fk
#include "polygon_zh.h"
#undef SUFFIX
#undef WITH_GRAD
#define WITH_GRAD 1
#define SUFFIX(name) name##_grad_fk
#include "polygon_zh.h"
#undef SUFFIX
#undef WITH_GRAD
#undef REAL

/* Small or grazing polygons: the boundary sums of Eq. 14 and Eq. 24 add O(gamma_e)
 * edge terms that cancel down to O(omega), so float rounding of the terms costs
 * about FLT_EPSILON sum_e gamma_e / omega relative to omega (measured: 1.5e-5 for a
 * square 1e-2 rad across, sum gamma / omega = 400; 2e-2 at 1e-5 rad).  Beyond
 * sum gamma / omega = 2^7 (a square 1/32 rad across; float error there <= 6e-6)
 * the float entry points run the double recurrence and round its result: for
 * scalar code the cost is about the float one's. */
#define SHL__FLOAT_CANCEL_MAX 0x1p7
static int float_cancels(const shl__poly_geom *g)
{
    double perimeter = 0.0;
    for (int e = 0; e < g->n; ++e) perimeter += g->gamma[e];
    return !(perimeter <= SHL__FLOAT_CANCEL_MAX * fabs(g->solid_angle));
}

static void round_block(int lmax, const double *zh, float *out)
{
    for (int dir = 0; dir < 2 * lmax + 1; ++dir)
        for (int l = 0; l <= lmax; ++l) out[dir * SHL__ZH_STRIDE + l] = (float)zh[dir * SHL__ZH_STRIDE + l];
}

void shl__poly_zh_f(const shl__poly_geom *g, int lmax, float *zh)
{
    if (!float_cancels(g)) {
        shl__poly_zh_fk(g, lmax, zh);
        return;
    }
    double zd[SHL__ZH_BLOCK];
    shl__poly_zh_d(g, lmax, zd);
    round_block(lmax, zd, zh);
}

void shl__poly_zh_grad_f(const shl__poly_geom *g, int lmax, float *zh, float *zh_grad)
{
    if (!float_cancels(g)) {
        shl__poly_zh_grad_fk(g, lmax, zh, zh_grad);
        return;
    }
    double zd[4 * SHL__ZH_BLOCK]; /* zh, then the 3 gradient blocks */
    shl__poly_zh_grad_d(g, lmax, zd, zd + SHL__ZH_BLOCK);
    round_block(lmax, zd, zh);
    for (int a = 0; a < 3; ++a) round_block(lmax, zd + (a + 1) * SHL__ZH_BLOCK, zh_grad + a * SHL__ZH_BLOCK);
}

/* ---- public entry points: every check before any output is written ---- */

static int check_polygon_args(const void *x, const void *verts, int n, const void *out)
{
    if (!x || !verts || !out) return SHL_ENULL;
    if (n < 3 || n > SHL_MAX_VERTS) return SHL_ENVERTS;
    return SHL_OK;
}

int shl_polygon(const shl_ctx *ctx, const double x[3], const double *verts, int n, double *coeffs)
{
    if (!ctx) return SHL_ENULL;
    int st = check_polygon_args(x, verts, n, coeffs);
    if (st) return st;
    if (shl__check_finite(x, 3) || shl__check_finite(verts, 3 * n)) return SHL_ENONFINITE;
    shl__poly_geom g;
    shl__poly_geom_init_values(&g, x, verts, n);
    ctx->isa->poly_sh(&g, ctx->lmax, coeffs);
    return SHL_OK;
}

/* Float entry points: the geometry is set up in double from the float input,
 * the recurrences run in float (the near-plane planar rule in double, polygon.c),
 * the ZH -> SH reconstruction accumulates in double. */
static int float_polygon_input(const float x[3], const float *verts, int n, double xd[3], double *vd)
{
    if (shl__check_finite_f(x, 3) || shl__check_finite_f(verts, 3 * n)) return SHL_ENONFINITE;
    for (int k = 0; k < 3; ++k) xd[k] = x[k];
    for (int i = 0; i < 3 * n; ++i) vd[i] = verts[i];
    return SHL_OK;
}

int shl_polygon_f(const shl_ctx *ctx, const float x[3], const float *verts, int n, float *coeffs)
{
    if (!ctx) return SHL_ENULL;
    int st = check_polygon_args(x, verts, n, coeffs);
    double xd[3], vd[3 * SHL_MAX_VERTS];
    if (!st) st = float_polygon_input(x, verts, n, xd, vd);
    if (st) return st;
    shl__poly_geom g;
    float zh[SHL__ZH_BLOCK];
    shl__poly_geom_init_values(&g, xd, vd, n);
    shl__poly_zh_f(&g, ctx->lmax, zh);
    shl__zh_to_sh_f(ctx->lmax, zh, coeffs);
    return SHL_OK;
}

int shl_polygon_grad(const shl_ctx *ctx, const double x[3], const double *verts, int n,
                     double *coeffs, double *grad)
{
    if (!ctx || !grad) return SHL_ENULL;
    int st = check_polygon_args(x, verts, n, coeffs);
    if (st) return st;
    if (shl__check_finite(x, 3) || shl__check_finite(verts, 3 * n)) return SHL_ENONFINITE;
    shl__poly_geom g;
    shl__poly_geom_init(&g, x, verts, n);
    ctx->isa->poly_grad_sh(&g, ctx->lmax, coeffs, grad, ctx->nc);
    return SHL_OK;
}

int shl_polygon_grad_f(const shl_ctx *ctx, const float x[3], const float *verts, int n,
                       float *coeffs, float *grad)
{
    if (!ctx || !grad) return SHL_ENULL;
    int st = check_polygon_args(x, verts, n, coeffs);
    double xd[3], vd[3 * SHL_MAX_VERTS];
    if (!st) st = float_polygon_input(x, verts, n, xd, vd);
    if (st) return st;
    shl__poly_geom g;
    float zh[SHL__ZH_BLOCK], zh_grad[3 * SHL__ZH_BLOCK];
    shl__poly_geom_init(&g, xd, vd, n);
    shl__poly_zh_grad_f(&g, ctx->lmax, zh, zh_grad);
    shl__zh_to_sh_f(ctx->lmax, zh, coeffs);
    for (int a = 0; a < 3; ++a) shl__zh_to_sh_f(ctx->lmax, zh_grad + a * SHL__ZH_BLOCK, grad + a * ctx->nc);
    shl__poly_grad_unscale_f(&g, grad, 3 * ctx->nc);
    return SHL_OK;
}

int shl_polygon_solid_angle(const double x[3], const double *verts, int n, double *omega)
{
    int st = check_polygon_args(x, verts, n, omega);
    if (st) return st;
    if (shl__check_finite(x, 3) || shl__check_finite(verts, 3 * n)) return SHL_ENONFINITE;
    shl__poly_geom g;
    shl__poly_geom_init_values(&g, x, verts, n);
    *omega = g.solid_angle;
    return SHL_OK;
}

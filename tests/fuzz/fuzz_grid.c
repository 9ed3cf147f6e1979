/* libFuzzer target: SH grids -- shl_grid_bytes_per_node / create / fill (1
 * thread) / node_position / get_node / set_node / interp (all methods) / destroy.
 *
 * Input: lmax byte (0..6 used), flags byte (bit 0: double storage, bit 1:
 * allocation failures, bit 2: set_node), lo[3], hi[3], res bytes, light count and
 * lights (polygons and spheres), nthreads byte, then interpolation requests
 * (method, taylor_b, points).
 * Properties:
 *  - SHL_OK or the documented code (lo >= hi, res outside 2..1024, a spacing
 *    (hi - lo) / (res - 1) that overflows or underflows to 0, bad storage,
 *    non-finite, nthreads outside 1..256, bad method, taylor_b non-finite or
 *    <= 0, npts < 0, SHL_ENOMEM under injected failures); nothing written on
 *    error (the grid keeps its nodes when fill fails);
 *  - double grids, and float grids outside the float path: every node equals
 *    shl_lights_eval at shl_grid_node_position, rounded to the storage type (bit for
 *    bit); the last node of an axis is exactly hi;
 *  - float grids on the float path (every axis: max(|lo|, |hi|) <= 2^126, spacing
 *    h >= 2^-10 max(|lo|, |hi|) and >= 2^-100; include/shlight.h): every node equals
 *    shl_lights_eval_batch_f at its position rounded to float (moved by at most
 *    2^-24 max(|lo|, |hi|)), bit for bit, and, when every light is a structured
 *    polygon with float-exact vertices or a sphere not within 1e-6 r of the node,
 *    lies within the batch slack of shl_lights_eval at that rounded position:
 *    per band l, sum_i |rgb_i| e_il + 4 eps_f sum_i |rgb_i| B_il, where e_il is light
 *    i's float-batch slack (polygons: fuzz_batch.c's, which holds for the light
 *    set's polygon path because it prepares the same double vertices; spheres: 1e-4
 *    of K_0 2 pi t, five times test_simd_sphere_interp.c's 2e-5 |L00|, plus the
 *    conditioning dt, du of fuzz_sphere.c; gradients 1e-4 of the moving-boundary
 *    bound, ten times that test's 1e-5) and the last term the float sum of at most
 *    3 lights and the rounding of rgb to float (B_il: K_l 4 pi for values, the
 *    gradient bound for gradients);
 *  - interpolation outputs are finite when the nodes are;
 *  - trilinear values lie within [min, max] of the cell's corner values (checked
 *    against all nodes), up to 1e-12 relative;
 *  - at a node position, trilinear, Hermite and Taylor return the node's values
 *    (to 1e-9 of the values' and gradients' scale);
 *  - a point outside the box gives the same result, bit for bit, as the point
 *    clamped to the box (documented);
 *  - interp with 1 or 2 threads gives identical results (documented);
 *  - shl_grid_interp_clamped: the values of shl_grid_interp (bit for bit), and a
 *    clamped count equal to the number of points with a coordinate outside [lo, hi];
 *  - shl_grid_interp_f: its error codes, nothing written on error, else within its
 *    documented bound of shl_grid_interp at the same float points;
 *  - shl_grid_lights_in_box: 0 <= in-box count <= near-box count <= lights added,
 *    indices ascending, in-box ones also near; 0 before the first fill and after a
 *    failed one; a sphere whose (long double) distance to the box, resp. the box grown
 *    by h, is below / above its radius by more than rounding is in / out; a polygon
 *    with a vertex strictly inside is in; an exactly planar one whose bounding box is
 *    disjoint from the box (by more than rounding of the coordinates) is out (same
 *    for the grown box). */
#include "fuzz_common.h"

enum { MAXL = 3, MAXPTS = 6 };

/* the lights added, to bound the gradient: sum_i |rgb_i| x (polygon: K_l G_i, the
 * moving-boundary bound of fuzz_polygon.c; sphere: K_l 2 pi s (1 + s/c) / d) */
typedef struct {
    int sphere;
    fz_poly P;
    double c[3], r, rgbmax;
} glight;
static glight GL[MAXL];
static int ngl;

static long double grad_bound_weighted(const double x[3], int lmax, int unit)
{
    long double b = 0.0L;
    for (int i = 0; i < ngl; ++i) {
        const glight *li = &GL[i];
        const long double w = unit ? 1.0L : li->rgbmax;
        if (li->sphere) {
            long double d2 = 0.0L;
            for (int k = 0; k < 3; ++k) d2 += ((long double)li->c[k] - x[k]) * ((long double)li->c[k] - x[k]);
            const long double d = sqrtl(d2), r = li->r;
            if (d <= r * (1.0L - 1e-12L)) continue;         /* inside: gradient 0 */
            if (d < r * (1.0L + 1e-12L)) return INFINITY;  /* at the surface: unbounded */
            const long double s = r / d, c = sqrtl((d - r) * (d + r)) / d;
            b += w * fz_kl(lmax) * 2.0L * M_PI * s * (1.0L + s / c) / d;
        } else {
            fz_geom G;
            if (!(li->P.structured && li->P.exact) || !fz_poly_geom(&li->P, x, &G)) return INFINITY;
            b += w * fz_kl(lmax) * G.gsum;
        }
    }
    return b;
}
static long double grad_bound(const double x[3], int lmax) { return grad_bound_weighted(x, lmax, 0); }

static int node_count(const int res[3]) { return res[0] * res[1] * res[2]; }

/* Float grids: the float batch path of shl_grid_fill (include/shlight.h). */
static int float_path(const double lo[3], const double hi[3], const int res[3])
{
    for (int a = 0; a < 3; ++a) {
        const double m = fmax(fabs(lo[a]), fabs(hi[a])), h = (hi[a] - lo[a]) / (res[a] - 1);
        if (!(m <= 0x1p126 && h >= 0x1p-10 * m && h >= 0x1p-100)) return 0;
    }
    return 1;
}

/* Slack of a float-path node at the float-rounded position x against shl_lights_eval
 * there, per band l: sc[l] for coefficients, sg[l] for gradients (see the top of the
 * file).  Returns 0 when a light is outside the bounded cases. */
static int float_node_slack(int lmax, const double x[3], long double *sc, long double *sg)
{
    const long double epsf = FLT_EPSILON, epsd = DBL_EPSILON, gb = grad_bound(x, lmax);
    if (!(gb < 1e30L)) return 0;
    for (int l = 0; l <= lmax; ++l) {
        sc[l] = 0.0L;
        sg[l] = 4.0L * epsf * gb;
    }
    for (int i = 0; i < ngl; ++i) {
        const glight *li = &GL[i];
        const long double w = li->rgbmax;
        if (li->sphere) {
            long double d2 = 0.0L, S = li->r;
            for (int k = 0; k < 3; ++k) {
                d2 += ((long double)li->c[k] - x[k]) * ((long double)li->c[k] - x[k]);
                S = fmaxl(S, fmaxl(fabsl((long double)li->c[k]), fabsl((long double)x[k])));
            }
            const long double d = sqrtl(d2), r = li->r;
            if (fabsl(d - r) <= 1e-6L * r) return 0;
            for (int l = 0; l <= lmax; ++l) sc[l] += w * 4.0L * epsf * fz_kl(l) * 4.0L * M_PI;
            if (d < r) continue; /* inside: sqrt(4 pi), zero elsewhere, in both */
            const long double s = r / d, c = sqrtl((d - r) * (d + r)) / d, t = s * s / (1.0L + c);
            const long double dt = 4.0L * epsd * S * s * s / (c * d), du = 4.0L * epsd * S / d;
            for (int l = 0; l <= lmax; ++l) {
                sc[l] += w * (1e-4L * fz_kl(0) * 2.0L * M_PI * t + fz_kl(l) * 2.0L * M_PI * (dt + t * (l + 1) * (l + 1) * du) + 1e-36L);
                sg[l] += w * (1e-4L * fz_kl(lmax) * 2.0L * M_PI * s * (1.0L + s / c) / d + 1e-36L);
            }
        } else {
            const fz_poly *P = &li->P;
            fz_geom G;
            if (!(P->structured && P->exact) || !fz_poly_geom(P, x, &G) || !(G.rmax > 0.0L)) return 0;
            for (int l = 0; l <= lmax; ++l) sc[l] += w * 4.0L * epsf * fz_kl(l) * 4.0L * M_PI;
            if (G.height == 0.0L) continue; /* in the plane: zeros in both (the same double test) */
            long double ext = 0.0L, dmin = INFINITY;
            for (int v = 0; v < P->n; ++v) {
                long double dv2 = 0.0L;
                for (int k = 0; k < 3; ++k) {
                    ext = fmaxl(ext, fabsl((long double)P->v[3 * v + k] - P->v[k]));
                    dv2 += ((long double)P->v[3 * v + k] - x[k]) * ((long double)P->v[3 * v + k] - x[k]);
                }
                dmin = fminl(dmin, sqrtl(dv2));
            }
            if (dmin > ldexpl(ext, 39)) return 0; /* documented: the batch may give zeros */
            const long double condf = 8.0L * epsf * G.scale * G.gsum, gcondf = 8.0L * epsf * G.scale * G.g2sum;
            const long double conddbl = 8.0L * (epsd * G.scale + 0x1p-1074L) * G.gsum;
            for (int l = 0; l <= lmax; ++l) { /* fuzz_batch.c: sf + sd, gs */
                const long double kl = fz_kl(l);
                sc[l] += w * (kl * (1e-9L * G.omega + 300.0L * epsd * G.perim + conddbl) + 1e-300L +
                              kl * (1e-4L * G.omega + 64.0L * (l + 1) * epsf * G.perim + condf + 1e-36L));
                sg[l] += w * kl * (2e-4L * G.gsum + 64.0L * (l + 1) * epsf * G.gsum + 2.0L * gcondf + 1e-36L);
            }
        }
    }
    return 1;
}

/* Independent expectation for light i against the closed box [lo, hi]: 1 in, 0 out, -1 undecided. */
static int expect_in_box(const glight *li, const double lo[3], const double hi[3])
{
    if (li->sphere) {
        long double d2 = 0.0L, s = fabsl((long double)li->r);
        for (int k = 0; k < 3; ++k) {
            const long double c = li->c[k], d = c < lo[k] ? lo[k] - c : c > hi[k] ? c - hi[k] : 0.0L;
            d2 += d * d;
            s = fmaxl(s, fmaxl(fabsl(c), fmaxl(fabsl((long double)lo[k]), fabsl((long double)hi[k]))));
        }
        const long double d = sqrtl(d2), tol = 16.0L * DBL_EPSILON * s + 0x1p-1070L;
        return d < li->r - tol ? 1 : d > li->r + tol ? 0 : -1;
    }
    const fz_poly *P = &li->P;
    double vmin[3] = {INFINITY, INFINITY, INFINITY}, vmax[3] = {-INFINITY, -INFINITY, -INFINITY}, s = 0.0;
    int vertex_inside = 0;
    for (int i = 0; i < P->n; ++i) {
        int in = 1;
        for (int k = 0; k < 3; ++k) {
            const double x = P->v[3 * i + k];
            in &= lo[k] < x && x < hi[k];
            vmin[k] = fmin(vmin[k], x);
            vmax[k] = fmax(vmax[k], x);
            s = fmax(s, fmax(fabs(x), fmax(fabs(lo[k]), fabs(hi[k]))));
        }
        vertex_inside |= in;
    }
    if (vertex_inside) return 1;
    if (!(P->structured && P->exact)) return -1; /* the plane test assumes a planar polygon */
    const double tol = 1e-9 * s + 0x1p-1070;
    for (int k = 0; k < 3; ++k)
        if (vmax[k] < lo[k] - tol || vmin[k] > hi[k] + tol) return 0;
    return -1;
}

/* The lights-in-box report after a successful fill of the nl lights GL[0..nl). */
static void check_lights_in_box(const shl_grid *grid, int nl, const double lo[3], const double hi[3], const int res[3])
{
    int idx[2][MAXL + 1], cnt[2] = {-1, -1};
    double glo[3], ghi[3];
    for (int a = 0; a < 3; ++a) { /* the library's grown box */
        const double h = (hi[a] - lo[a]) / (res[a] - 1);
        glo[a] = fmax(lo[a] - h, -DBL_MAX);
        ghi[a] = fmin(hi[a] + h, DBL_MAX);
    }
    for (int b = 0; b < 2; ++b) {
        const int st = shl_grid_lights_in_box(grid, b ? SHL_GRID_NEAR_BOX : SHL_GRID_IN_BOX, MAXL + 1, idx[b], &cnt[b]);
        FUZZ_CHECK(st == SHL_OK && cnt[b] >= 0 && cnt[b] <= nl, "lights_in_box(%d) %d, count %d of %d", b, st, cnt[b], nl);
        if (st != SHL_OK || cnt[b] < 0 || cnt[b] > nl) return;
        for (int k = 0; k < cnt[b]; ++k)
            FUZZ_CHECK(idx[b][k] >= 0 && idx[b][k] < nl && (k == 0 || idx[b][k] > idx[b][k - 1]), "index %d: %d", k, idx[b][k]);
    }
    FUZZ_CHECK(cnt[0] <= cnt[1], "in box %d > near box %d", cnt[0], cnt[1]);
    for (int i = 0; i < nl; ++i) {
        int got[2] = {0, 0};
        for (int b = 0; b < 2; ++b)
            for (int k = 0; k < cnt[b]; ++k) got[b] |= idx[b][k] == i;
        FUZZ_CHECK(!got[0] || got[1], "light %d in the box but not near it", i);
        const int want_in = expect_in_box(&GL[i], lo, hi), want_near = expect_in_box(&GL[i], glo, ghi);
        if (fz_is_verbose()) fprintf(stderr, "light %d: in %d (want %d), near %d (want %d)\n", i, got[0], want_in, got[1], want_near);
        FUZZ_CHECK(want_in < 0 || got[0] == want_in, "light %d (sphere %d): in box %d, want %d", i, GL[i].sphere, got[0], want_in);
        FUZZ_CHECK(want_near < 0 || got[1] == want_near, "light %d (sphere %d): near box %d, want %d", i, GL[i].sphere, got[1],
                   want_near);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_target_name = "fuzz_grid";
    fz_in in = {data, size, 0};
    const int lsel = fz_lmax(&in);
    const int lmax = lsel < 0 || lsel > SHL_LMAX_MAX ? lsel : lsel % 7;
    const uint8_t flags = fz_u8(&in);
    int storage = flags & 1 ? SHL_GRID_DOUBLE : SHL_GRID_FLOAT;
    if ((flags & 0x30) == 0x30) storage = 2 + (flags >> 6); /* invalid */
    const int allocs = (flags >> 1) & 1;
    double lo[3], hi[3];
    int res[3];
    for (int a = 0; a < 3; ++a) {
        const uint8_t m = fz_u8(&in);
        lo[a] = fz_real(&in);
        hi[a] = m & 1 ? fz_real(&in) : lo[a] + ((m >> 1) & 1 ? fz_real(&in) : (double)(m >> 2) / 16.0); /* hi = lo + extent */
    }
    for (int a = 0; a < 3; ++a) {
        const uint8_t b = fz_u8(&in);
        res[a] = b < 250 ? 2 + b % 3 : b == 250 ? 1 : b == 251 ? 0 : b == 252 ? SHL_GRID_RES_MAX + 1 : -5;
    }
    { /* bytes per node */
        int bytes = -1;
        const int st = shl_grid_bytes_per_node(lmax, storage, &bytes);
        const int want = lmax < 0 || lmax > SHL_LMAX_MAX ? SHL_ELMAX
                         : storage != SHL_GRID_FLOAT && storage != SHL_GRID_DOUBLE ? SHL_EDOMAIN : SHL_OK;
        FUZZ_CHECK(st == want, "bytes_per_node %d, want %d", st, want);
        if (st == SHL_OK)
            FUZZ_CHECK(bytes == 12 * SHL_NCOEFFS(lmax) * (storage == SHL_GRID_DOUBLE ? 8 : 4), "bytes %d", bytes);
        else FUZZ_CHECK(bytes == -1, "bytes written on error");
    }
    if (lmax < 0 || lmax > SHL_LMAX_MAX) return 0;
    const shl_ctx *ctx = fz_ctx(lmax);
    const int nc = SHL_NCOEFFS(lmax), nv = 3 * nc, node_len = 12 * nc;

    int want = SHL_OK;
    if (storage != SHL_GRID_FLOAT && storage != SHL_GRID_DOUBLE) want = SHL_EDOMAIN;
    else if (!all_finite_d(lo, 3) || !all_finite_d(hi, 3)) want = SHL_ENONFINITE;
    else
        for (int a = 0; a < 3; ++a)
            if (res[a] < 2 || res[a] > SHL_GRID_RES_MAX || !(lo[a] < hi[a]) || !isfinite((hi[a] - lo[a]) / (res[a] - 1)) ||
                !((hi[a] - lo[a]) / (res[a] - 1) > 0.0)) /* spacing overflows or underflows to 0 */
                want = SHL_EDOMAIN;
    fz_dump_vec("lo", lo, 3);
    fz_dump_vec("hi", hi, 3);
    if (fz_is_verbose()) fprintf(stderr, "res %d %d %d storage %d lmax %d\n", res[0], res[1], res[2], storage, lmax);
    shl_grid *grid = (shl_grid *)&in;
    if (allocs && want == SHL_OK) {
        for (long f = 0; f < 2; ++f) {
            grid = (shl_grid *)&in;
            shl__alloc_fail_after = f;
            const int st = shl_grid_create(ctx, lo, hi, res, storage, &grid);
            shl__alloc_fail_after = -1;
            FUZZ_CHECK(st == SHL_ENOMEM && grid == NULL, "create under ENOMEM (%ld): %d", f, st);
        }
    }
    grid = (shl_grid *)&in;
    const int st = shl_grid_create(ctx, lo, hi, res, storage, &grid);
    FUZZ_CHECK(st == want, "create %d, want %d", st, want);
    if (st != SHL_OK) {
        FUZZ_CHECK(grid == NULL, "*out not set to NULL on error");
        return 0;
    }
    const int nn = node_count(res);
    double *node = malloc(sizeof(double) * (size_t)node_len * nn);
    double *direct = malloc(sizeof(double) * node_len);
    float *fnode = malloc(sizeof(float) * node_len);
    /* a fresh grid is zero-filled */
    {
        const int idx[3] = {res[0] - 1, 0, res[2] / 2};
        FUZZ_CHECK(shl_grid_get_node(grid, idx, direct, direct + nv) == SHL_OK, "get_node");
        for (int k = 0; k < node_len; ++k) FUZZ_CHECK(direct[k] == 0.0, "fresh grid not zero");
    }
    /* lights */
    shl_lights *set = NULL;
    FUZZ_CHECK(shl_lights_create(&set) == SHL_OK, "lights");
    const int nl = fz_u8(&in) % (MAXL + 1);
    ngl = 0;
    long double magnitude = 0.0L;
    for (int i = 0; i < nl; ++i) {
        const uint8_t kind = fz_u8(&in);
        double rgb[3];
        for (int c = 0; c < 3; ++c) rgb[c] = (int8_t)fz_u8(&in) / 16.0;
        if (kind & 1) {
            double c[3];
            for (int k = 0; k < 3; ++k) c[k] = lo[k] + fz_real(&in);
            const double r = fz_real(&in);
            fz_dump_vec("sphere centre", c, 3);
            fz_dump_vec("sphere radius", &r, 1);
            if (shl_lights_add_sphere(set, c, r, rgb) != SHL_OK) continue;
            GL[ngl].sphere = 1;
            memcpy(GL[ngl].c, c, sizeof c);
            GL[ngl].r = r;
            GL[ngl++].rgbmax = fmax(fabs(rgb[0]), fmax(fabs(rgb[1]), fabs(rgb[2])));
            magnitude += 8.0L * 4.0L * M_PI * fz_kl(lmax);
        } else {
            fz_poly P;
            fz_polygon(&in, &P);
            fz_dump_poly(&P);
            if (shl_lights_add_polygon(set, P.v, P.n, rgb, (kind >> 1) & 1) != SHL_OK) continue;
            GL[ngl].sphere = 0;
            GL[ngl].P = P;
            GL[ngl++].rgbmax = fmax(fabs(rgb[0]), fmax(fabs(rgb[1]), fabs(rgb[2])));
            magnitude += 8.0L * 4.0L * M_PI * fz_kl(lmax) * P.n;
        }
    }
    /* fill */
    const uint8_t tb = fz_u8(&in);
    const int nthreads = tb < 250 ? 1 : tb == 250 ? 0 : tb == 251 ? SHL_MAX_THREADS + 1 : -1;
    const int want_fill = nthreads == 1 ? SHL_OK : SHL_EDOMAIN;
    if (allocs && want_fill == SHL_OK) {
        shl__alloc_fail_after = 0;
        const int sf = shl_grid_fill(grid, set, nthreads);
        shl__alloc_fail_after = -1;
        /* an empty set on the float path allocates nothing (no box flags, no batch workspace) */
        FUZZ_CHECK(sf == (ngl == 0 && storage == SHL_GRID_FLOAT && float_path(lo, hi, res) ? SHL_OK : SHL_ENOMEM),
                   "fill under ENOMEM: %d", sf);
        const int idx[3] = {0, 0, 0};
        FUZZ_CHECK(shl_grid_get_node(grid, idx, direct, direct + nv) == SHL_OK && direct[0] == 0.0, "fill failed but wrote");
    }
    const int sf = shl_grid_fill(grid, set, nthreads);
    FUZZ_CHECK(sf == want_fill, "fill %d, want %d", sf, want_fill);
    {
        int nin = -1;
        const int sq = shl_grid_lights_in_box(grid, SHL_GRID_NEAR_BOX, 0, NULL, &nin);
        FUZZ_CHECK(sq == SHL_OK && (sf == SHL_OK || nin == 0), "lights_in_box %d after fill %d: %d", sq, sf, nin);
    }
    if (sf != SHL_OK) goto out;
    check_lights_in_box(grid, ngl, lo, hi, res);
    /* nodes: equal to the direct evaluation at their positions, rounded to the storage */
    int nodes_finite = 1;
    double vmax = 0.0, gmax = 0.0;
    const int batch = storage == SHL_GRID_FLOAT && float_path(lo, hi, res);
    long double sc[SHL_LMAX_MAX + 1], sg[SHL_LMAX_MAX + 1];
    for (int n = 0; n < nn; ++n) {
        const int idx[3] = {n % res[0], n / res[0] % res[1], n / res[0] / res[1]};
        double pos[3];
        FUZZ_CHECK(shl_grid_node_position(grid, idx, pos) == SHL_OK, "node_position");
        for (int a = 0; a < 3; ++a)
            if (idx[a] == res[a] - 1) FUZZ_CHECK(pos[a] == hi[a], "last node %d of axis %d at %.17g, hi %.17g", idx[a], a, pos[a], hi[a]);
            else if (idx[a] == 0) FUZZ_CHECK(pos[a] == lo[a], "first node at %.17g, lo %.17g", pos[a], lo[a]);
        double *nd = node + (size_t)node_len * n;
        FUZZ_CHECK(shl_grid_get_node(grid, idx, nd, nd + nv) == SHL_OK, "get_node");
        if (batch) { /* the float batch at the rounded position, bit for bit; within its slack of the double path */
            const float xf[3] = {(float)pos[0], (float)pos[1], (float)pos[2]};
            const double xr[3] = {xf[0], xf[1], xf[2]};
            for (int a = 0; a < 3; ++a)
                FUZZ_CHECK(fabs(xr[a] - pos[a]) <= 0x1p-24 * fmax(fabs(lo[a]), fabs(hi[a])), "node %d axis %d rounds far", n, a);
            FUZZ_CHECK(shl_lights_eval_batch_f(ctx, set, 1, xf, fnode, fnode + nv) == SHL_OK, "lights_eval_batch_f");
            for (int k = 0; k < node_len; ++k)
                FUZZ_CHECK(memcmp(&nd[k], &(double){fnode[k]}, sizeof(double)) == 0 || (isnan(nd[k]) && isnan(fnode[k])),
                           "node %d value %d: %.9g, float batch %.9g", n, k, nd[k], fnode[k]);
            FUZZ_CHECK(shl_lights_eval(ctx, set, xr, direct, direct + nv) == SHL_OK, "lights_eval");
            if (magnitude < 1e30L && float_node_slack(lmax, xr, sc, sg))
                for (int k = 0; k < node_len; ++k) {
                    const int m = k % nc, l = (int)sqrt((double)m), isg = k >= nv;
                    if (isg && !isfinite(nd[k])) continue; /* a gradient beyond float range (checked below) */
                    FUZZ_CHECK(fabsl((long double)nd[k] - direct[k]) <= (isg ? sg[l] : sc[l]),
                               "node %d %s %d (band %d): float %.9g, double %.17g, slack %.3Lg", n, isg ? "gradient" : "value", k,
                               l, nd[k], direct[k], isg ? sg[l] : sc[l]);
                }
        } else {
            FUZZ_CHECK(shl_lights_eval(ctx, set, pos, direct, direct + nv) == SHL_OK, "lights_eval");
            for (int k = 0; k < node_len; ++k) {
                const double want_v = storage == SHL_GRID_FLOAT ? (double)(float)direct[k] : direct[k];
                FUZZ_CHECK(memcmp(&nd[k], &want_v, sizeof(double)) == 0 || (isnan(nd[k]) && isnan(want_v)),
                           "node %d value %d: %.17g, direct %.17g", n, k, nd[k], want_v);
            }
        }
        if (fz_is_verbose() && !all_finite_d(nd, node_len)) fz_dump_vec("non-finite node at", pos, 3);
        nodes_finite &= all_finite_d(nd, node_len);
        if (magnitude < 1e30L) {
            FUZZ_CHECK(all_finite_d(nd, nv), "non-finite node value (node %d)", n);
            /* at the position evaluated: the float batch's is the node rounded to float, which
             * can lie outside a tiny sphere whose centre is the node (gradient beyond float range) */
            const double at[3] = {batch ? (double)(float)pos[0] : pos[0], batch ? (double)(float)pos[1] : pos[1],
                                  batch ? (double)(float)pos[2] : pos[2]};
            /* each light's gradient is formed before its colour weighs it: beyond the storage's
             * range it is +-inf there, and a zero colour channel makes 0 x inf = NaN (README,
             * Known issues), so every light's unweighted bound must be in range too (a sphere of
             * zero radiance 1e-265 from a float node: fuzz_grid-zero-radiance-sphere-float-overflow) */
            const long double gb = fmaxl(grad_bound(at, lmax), grad_bound_weighted(at, lmax, 1));
            if (gb < (storage == SHL_GRID_DOUBLE ? DBL_MAX / 1e10 : FLT_MAX / 1e4))
                FUZZ_CHECK(all_finite_d(nd + nv, node_len - nv), "non-finite node gradient (node %d, bound %.3Lg)", n, gb);
        }
        for (int k = 0; k < nv; ++k) vmax = fmax(vmax, fabs(nd[k]));
        for (int k = nv; k < node_len; ++k) gmax = fmax(gmax, fabs(nd[k]));
    }
    if (!nodes_finite) goto out; /* a gradient too large for the storage type (checked above) */
    {   /* set_node / get_node round trip */
        const int idx[3] = {fz_u8(&in) % res[0], fz_u8(&in) % res[1], fz_u8(&in) % res[2]};
        if (flags & 4) {
            double *w = node + (size_t)node_len * (idx[0] + res[0] * (idx[1] + res[1] * idx[2]));
            const int sw = shl_grid_set_node(grid, idx, w, w + nv);
            FUZZ_CHECK(sw == SHL_OK, "set_node %d", sw);
            FUZZ_CHECK(shl_grid_get_node(grid, idx, direct, direct + nv) == SHL_OK, "get_node");
            FUZZ_CHECK(memcmp(direct, w, sizeof(double) * node_len) == 0, "set/get round trip");
            w[0] = NAN;
            FUZZ_CHECK(shl_grid_set_node(grid, idx, w, w + nv) == SHL_ENONFINITE, "set_node NaN");
            FUZZ_CHECK(shl_grid_get_node(grid, idx, direct, NULL) == SHL_OK && !isnan(direct[0]), "NaN stored");
            w[0] = direct[0];
        }
        const int bad[3] = {idx[0], -1, res[2]};
        FUZZ_CHECK(shl_grid_get_node(grid, bad, direct, NULL) == SHL_EDOMAIN, "get_node out of range");
    }
    /* interpolation */
    const int nreq = 1 + fz_u8(&in) % 3;
    for (int q = 0; q < nreq; ++q) {
        const uint8_t mb = fz_u8(&in);
        const int method = (mb & 15) < 15 ? (mb & 15) % 3 : 3 + mb; /* 15: an invalid method */
        const double b = (mb & 0x40) ? fz_real(&in) : 0.5 + (mb >> 4);
        const int np = fz_u8(&in) % (MAXPTS + 1);
        double pts[3 * MAXPTS + 3], clamped[3 * MAXPTS + 3];
        for (int p = 0; p < np; ++p) {
            const uint8_t pm = fz_u8(&in);
            for (int a = 0; a < 3; ++a) {
                if (pm % 4 == 0) pts[3 * p + a] = fz_real(&in);                          /* anywhere */
                else if (pm % 4 == 1) pts[3 * p + a] = lo[a] + (hi[a] - lo[a]) * (fz_u8(&in) / 255.0);
                else { /* a node position */
                    const int i = fz_u8(&in) % res[a];
                    pts[3 * p + a] = i == res[a] - 1 ? hi[a] : lo[a] + i * ((hi[a] - lo[a]) / (res[a] - 1));
                }
                clamped[3 * p + a] = fmin(fmax(pts[3 * p + a], lo[a]), hi[a]);
            }
        }
        int wi = SHL_OK;
        if (method != SHL_INTERP_TRILINEAR && method != SHL_INTERP_TAYLOR && method != SHL_INTERP_HERMITE) wi = SHL_EDOMAIN;
        else if (method == SHL_INTERP_TAYLOR && !isfinite(b)) wi = SHL_ENONFINITE;
        else if (method == SHL_INTERP_TAYLOR && !(b > 0.0)) wi = SHL_EDOMAIN;
        else if (!all_finite_d(pts, 3 * np)) wi = SHL_ENONFINITE;
        const size_t ob = sizeof(double) * nv * (np > 0 ? np : 1);
        double *out = fz_guarded(ob), *out2 = fz_guarded(ob), *outc = fz_guarded(ob);
        const int si = shl_grid_interp(grid, method, b, np, pts, out, 1);
        FUZZ_CHECK(si == wi, "interp %d, want %d (method %d, b %g)", si, wi, method, b);
        if (si != SHL_OK) {
            FUZZ_CHECK(fz_untouched(out, ob), "interp wrote on error");
            int nclamped = -1;
            const int sc = shl_grid_interp_clamped(grid, method, b, np, pts, out, 1, &nclamped);
            FUZZ_CHECK(sc == si && nclamped == -1 && fz_untouched(out, ob), "interp_clamped %d (interp %d) wrote on error", sc, si);
            goto next;
        }
        if (np == 0) goto next;
        { /* Taylor and Hermite add (p - p_j) . grad_j, resp. h grad terms: finite while those are */
            double hmax = 0.0;
            for (int a = 0; a < 3; ++a) hmax = fmax(hmax, (hi[a] - lo[a]) / (res[a] - 1));
            if (method == SHL_INTERP_TRILINEAR || vmax + 4.0 * gmax * hmax < 1e300)
                FUZZ_CHECK(all_finite_d(out, nv * np), "non-finite interpolation (method %d)", method);
        }
        FUZZ_CHECK(shl_grid_interp(grid, method, b, np, pts, out2, 2) == SHL_OK, "interp 2 threads");
        FUZZ_CHECK(memcmp(out, out2, ob) == 0, "interp depends on the thread count");
        {
            int outside = 0, nclamped = -1;
            for (int p = 0; p < np; ++p) {
                int o = 0;
                for (int a = 0; a < 3; ++a) o |= !(lo[a] <= pts[3 * p + a] && pts[3 * p + a] <= hi[a]);
                outside += o;
            }
            const int sc = shl_grid_interp_clamped(grid, method, b, np, pts, out2, 1 + (mb & 1), &nclamped);
            FUZZ_CHECK(sc == SHL_OK && nclamped == outside, "interp_clamped %d: %d clamped, want %d", sc, nclamped, outside);
            FUZZ_CHECK(memcmp(out, out2, ob) == 0, "interp_clamped differs from interp");
        }
        FUZZ_CHECK(shl_grid_interp(grid, method, b, np, clamped, outc, 1) == SHL_OK, "interp clamped");
        FUZZ_CHECK(memcmp(out, outc, ob) == 0, "outside point differs from the clamped point (method %d)", method);
        { /* shl_grid_interp_f: its error codes (double grid; Taylor and Hermite spacings outside [2^-100, 2^127];
           * points beyond float range), nothing written on error, else within its bound (global M, at least
           * every cell's) of shl_grid_interp at the same float points */
            float ptf[3 * MAXPTS + 3];
            double ptd[3 * MAXPTS + 3], hmax = 0.0;
            for (int k = 0; k < 3 * np; ++k) ptd[k] = ptf[k] = (float)pts[k];
            int want = storage == SHL_GRID_DOUBLE ? SHL_EDOMAIN : SHL_OK;
            for (int a = 0; a < 3; ++a) {
                const double h = (hi[a] - lo[a]) / (res[a] - 1);
                hmax = fmax(hmax, h);
                if (want == SHL_OK && method != SHL_INTERP_TRILINEAR && !(h >= 0x1p-100 && h <= 0x1p127)) want = SHL_EDOMAIN;
            }
            if (want == SHL_OK && !all_finite_d(ptd, 3 * np)) want = SHL_ENONFINITE;
            const size_t fb = sizeof(float) * nv * np;
            float *outf = fz_guarded(fb);
            const int sf = shl_grid_interp_f(grid, method, b, np, ptf, outf, 1 + (mb & 1));
            FUZZ_CHECK(sf == want, "interp_f %d, want %d (method %d, storage %d)", sf, want, method, storage);
            if (sf != SHL_OK) FUZZ_CHECK(fz_untouched(outf, fb), "interp_f wrote on error");
            if (sf == SHL_OK) {
                FUZZ_CHECK(shl_grid_interp(grid, method, b, np, ptd, out2, 1) == SHL_OK, "interp at the float points");
                const double u = 0x1p-24, n = method == SHL_INTERP_TRILINEAR ? 9.0 : 18.0;
                const double L = method == SHL_INTERP_TRILINEAR ? 1.0 : method == SHL_INTERP_TAYLOR ? 4.0 : 1.75;
                const double M = method == SHL_INTERP_TRILINEAR ? vmax : fmax(vmax, gmax * hmax);
                const double bound = n * u / (1.0 - n * u) * L * M + (16.0 * DBL_EPSILON + 0x1p-45) * M + 0x1p-144;
                if (L * M * (1.0 + 2.0 * n * u) <= FLT_MAX)
                    for (int k = 0; k < nv * np; ++k)
                        FUZZ_CHECK(fabs(outf[k] - out2[k]) <= bound, "interp_f entry %d: %.9g, double %.17g, bound %.3g (method %d)",
                                   k, outf[k], out2[k], bound, method);
            }
            free(outf);
        }
        for (int p = 0; p < np; ++p) {
            const double *o = out + (size_t)nv * p;
            if (method == SHL_INTERP_TRILINEAR)
                for (int k = 0; k < nv; ++k) {
                    double mn = INFINITY, mx = -INFINITY;
                    for (int n = 0; n < nn; ++n) mn = fmin(mn, node[(size_t)node_len * n + k]), mx = fmax(mx, node[(size_t)node_len * n + k]);
                    const double tol = 1e-12 * fmax(fabs(mn), fabs(mx)) + 1e-300;
                    FUZZ_CHECK(o[k] >= mn - tol && o[k] <= mx + tol, "trilinear value %d = %.17g outside [%.17g, %.17g]", k, o[k], mn, mx);
                }
            /* at a node: its values */
            int at[3], is_node = 1;
            for (int a = 0; a < 3; ++a) {
                at[a] = -1;
                for (int i = 0; i < res[a]; ++i) {
                    const double pos = i == res[a] - 1 ? hi[a] : lo[a] + i * ((hi[a] - lo[a]) / (res[a] - 1));
                    if (clamped[3 * p + a] == pos) at[a] = i;
                }
                is_node &= at[a] >= 0;
            }
            if (!is_node) continue;
            if (method == SHL_INTERP_TAYLOR) { /* weights ~ dist^-b: only an exact hit (t == i) pins the node */
                int exact_hit = 1;
                for (int a = 0; a < 3; ++a) {
                    const double h = (hi[a] - lo[a]) / (res[a] - 1), t = (clamped[3 * p + a] - lo[a]) / h;
                    exact_hit &= t == (double)at[a];
                }
                if (!exact_hit) continue;
            }
            const double *nd = node + (size_t)node_len * (at[0] + res[0] * (at[1] + res[1] * at[2]));
            /* a node's position lo + i h is rounded: the library sees it at t = i + delta / h in the
             * cell, |delta| <= ulp(max(|lo|, |hi|)) (at least a denormal ulp), and interpolates there */
            double tol = 1e-300;
            for (int a = 0; a < 3; ++a) {
                const double h = (hi[a] - lo[a]) / (res[a] - 1);
                const double du = (2.0 * DBL_EPSILON * fmax(fabs(lo[a]), fabs(hi[a])) + 0x1p-1073) / h;
                tol += du < 1e300 ? 1e-9 * (vmax + gmax * h) + 4.0 * du * (2.0 * vmax + gmax * h) : INFINITY;
            }
            if (fz_is_verbose())
                fprintf(stderr, "method %d b %g at node (%d %d %d): vmax %g gmax %g tol %g point %.17g %.17g %.17g\n", method, b,
                        at[0], at[1], at[2], vmax, gmax, tol, pts[3 * p], pts[3 * p + 1], pts[3 * p + 2]);
            for (int k = 0; k < nv; ++k)
                FUZZ_CHECK(fabs(o[k] - nd[k]) <= tol, "method %d at node (%d,%d,%d): value %d = %.17g, node %.17g", method,
                           at[0], at[1], at[2], k, o[k], nd[k]);
        }
    next:
        free(out);
        free(out2);
        free(outc);
    }
out:
    free(node);
    free(direct);
    free(fnode);
    shl_lights_destroy(set);
    shl_grid_destroy(grid);
    return 0;
}

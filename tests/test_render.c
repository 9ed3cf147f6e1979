/* The benchmark harness (bench/common) end to end on a tiny scene, 64x64:
 *  - rasterizer: perspective-correct interpolation reproduces an affine colour
 *    exactly, and each pixel shows the nearest triangle (brute-force ray casting);
 *  - per-vertex analytic shading (unshadowed diffuse, lmax 8 and 14) against an
 *    exact reference independent of the library's SH code (bench/common/lambert.c):
 *    Lambert's closed form for the irradiance of a polygon clipped to the receiver's
 *    horizon, E = 1/2 |sum_e Theta_e n . Gamma_e|, rasterized through the same
 *    visibility buffer.  Tolerance: a rigorous bound on
 *    the SH truncation error.  With T the clamped cosine about n and L the
 *    radiance, E - E_lmax = sum_{l > lmax} L_l . T_l, so by Cauchy-Schwarz and
 *    Parseval |E - E_lmax| <= ||L|| sqrt(tail), tail = sum_{l > lmax} t_l^2 =
 *    2pi/3 - sum_{l <= lmax} t_l^2 (t_l: ZH of max(t,0), integrated here by
 *    quadrature), ||L|| <= sum_j |L_j| sqrt(Omega_j) (Omega_j: solid angle of light
 *    j, Van Oosterom-Strackee).  A pixel is a convex combination of three vertices, so the per-vertex
 *    bound, interpolated the same way, bounds the pixel;
 *  - grid 8^3 + Hermite: the image error against the exact reference may exceed the
 *    analytic one by at most 1% of the mean radiance (its own error against the
 *    analytic image measures 2e-4 of the mean), and it converges: halving the spacing (4^3 -> 8^3) divides the
 *    error against per-vertex analytic shading by more than 4 (order > 2, i.e.
 *    beyond trilinear; tricubic Hermite with linearly carried gradients is order 3);
 *  - the rendered image does not depend on the thread count;
 *  - the VPL and VSL baselines of HVL Table 2 (bench/common/hvlpass.c): VSL's cone estimate
 *    against a midpoint quadrature of the same cone integral, and VSL's small-sphere limit
 *    against VPL (error analyses at the tests);
 *  - the harness's parallel loop (bench/common/parfor.c on the library's shl__parallel_for)
 *    visits every item once in chunks of at most `grain`, also when a thread cannot be
 *    created (then on the calling thread, returning -1). */
#include "harness.h"
#include "internal.h" /* shl__thread_fail_after: the test hook of the SHL_ALLOC_HOOKS build */
#include "image.h"
#include "mesh.h"
#include "lambert.h"
#include "parfor.h"
#include "prt.h"
#include "vec3.h"
#include "testutil.h"
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static const char tiny_scene[] =
    "name tiny\n"
    "lmax 14\n"
    "image 64 64\n"
    "camera 0 1.9 3.4  0 0.3 0  40\n"
    "effects direct\n"
    "material floor diffuse 0.8 0.8 0.8\n"
    "material ball diffuse 0.6 0.5 0.4\n"
    "object floor plane 3 12\n"
    "object ball sphere 0.5 2 translate 0 0.5 0\n"
    "light polygon one-sided 4 3 2  -1 2 -1  1 2 -1  1 2 1  -1 2 1\n"
    "light polygon two-sided 1 2 4  2 0.1 -0.5  2 0.1 0.5  2 1.2 0\n";

/* sum_{l > lmax} t_l^2 for the clamped cosine max(t, 0): t_l = 2 pi K_l int_0^1 t P_l(t) dt. */
static double clamped_cosine_tail(int lmax)
{
    double kept = 0.0;
    const int N = 4000; /* Simpson, the integrand is a polynomial of degree <= lmax + 1 */
    for (int l = 0; l <= lmax; ++l) {
        double integral = 0.0;
        for (int i = 0; i <= N; ++i) {
            const double t = (double)i / N, w = (i == 0 || i == N) ? 1 : (i % 2 ? 4 : 2);
            integral += w * t * legendre_p(l, t);
        }
        integral /= 3.0 * N;
        const double tl = 2 * M_PI * sqrt((2 * l + 1) / (4 * M_PI)) * integral;
        kept += tl * tl;
    }
    return 2 * M_PI / 3 - kept;
}

typedef struct {
    scene s;
    prt p;
    float *exact, *bound8, *bound14; /* per vertex, 3 each */
} fixture;

static int setup(fixture *f, int nthreads)
{
    char err[256];
    memset(f, 0, sizeof *f);
    if (scene_parse(tiny_scene, "tiny", ".", &f->s, err, sizeof err)) {
        harness_fail(__FILE__, __LINE__, "scene: %s", err);
        return -1;
    }
    if (prt_init(&f->p, &f->s, nthreads, NULL, NULL)) {
        scene_free(&f->s);
        harness_fail(__FILE__, __LINE__, "prt_init failed");
        return -1;
    }
    const mesh *g = &f->s.geom;
    f->exact = calloc(3 * (size_t)g->nv, sizeof(float));
    f->bound8 = calloc(3 * (size_t)g->nv, sizeof(float));
    f->bound14 = calloc(3 * (size_t)g->nv, sizeof(float));
    const double tail8 = sqrt(clamped_cosine_tail(8)), tail14 = sqrt(clamped_cosine_tail(14));
    lambert_scene(&f->s, f->exact);
    for (int v = 0; v < g->nv; ++v) {
        const double *x = g->pos + 3 * v, *alb = f->s.mats[g->mat[v]].albedo;
        for (int j = 0; j < f->s.npolys; ++j) {
            const scene_polygon *q = &f->s.polys[j];
            if (!lambert_lit(q, x)) continue;
            const double om = sqrt(lambert_solid_angle(q->v, q->n, x));
            for (int c = 0; c < 3; ++c) {
                f->bound8[3 * v + c] += (float)(alb[c] / M_PI * fabs(q->rgb[c]) * om * tail8);
                f->bound14[3 * v + c] += (float)(alb[c] / M_PI * fabs(q->rgb[c]) * om * tail14);
            }
        }
    }
    return 0;
}

static void teardown(fixture *f)
{
    prt_free(&f->p);
    scene_free(&f->s);
    free(f->exact);
    free(f->bound8);
    free(f->bound14);
}

static float *resolve(const fixture *f, const float *per_vertex)
{
    const size_t n = 3 * (size_t)f->s.width * (size_t)f->s.height;
    float *img = malloc(sizeof(float) * n);
    const float *colors[3] = {per_vertex, f->p.emit_rgb[0], f->p.emit_rgb[1]};
    raster_resolve(&f->p.fb, f->p.rm, colors, img, 1);
    return img;
}

static float *render(fixture *f, lighting_kind kind, int lmax, int res)
{
    lighting_method m;
    memset(&m, 0, sizeof m);
    m.kind = kind;
    m.lmax = lmax;
    m.grid_res = res;
    m.interp = SHL_INTERP_HERMITE;
    m.grid_storage = SHL_GRID_DOUBLE;
    m.mc_samples = 16;
    prt_times t;
    float *img = malloc(sizeof(float) * 3 * (size_t)f->s.width * (size_t)f->s.height);
    if (prt_render(&f->p, &m, NULL, 0, img, &t)) {
        harness_fail(__FILE__, __LINE__, "prt_render failed");
        free(img);
        return NULL;
    }
    return img;
}

SHL_TEST(render_lambert_reference)
{
    fixture f;
    if (setup(&f, 2)) return;
    const int w = f.s.width, h = f.s.height;
    float *ref = resolve(&f, f.exact), *b8 = resolve(&f, f.bound8), *b14 = resolve(&f, f.bound14);
    float *a8 = render(&f, LM_ANALYTIC, 8, 0), *a14 = render(&f, LM_ANALYTIC, 14, 0);
    float *g4 = render(&f, LM_GRID, 8, 4), *g8 = render(&f, LM_GRID, 8, 8);
    if (!a8 || !a14 || !g4 || !g8) goto done;
    long over8 = 0, over14 = 0;
    double worst8 = 0, worst14 = 0;
    for (size_t i = 0; i < 3 * (size_t)w * h; ++i) {
        if (!f.p.mask[i / 3]) continue;
        const double d8 = fabs(a8[i] - ref[i]), d14 = fabs(a14[i] - ref[i]), slack = 1e-5 * ref[i] + 1e-7;
        over8 += d8 > b8[i] + slack;
        over14 += d14 > b14[i] + slack;
        worst8 = fmax(worst8, d8 / (b8[i] + slack));
        worst14 = fmax(worst14, d14 / (b14[i] + slack));
    }
    CHECK(over8 == 0);
    CHECK(over14 == 0);
    const image_error e8 = image_compare(w, h, a8, ref, f.p.mask, 1.0), e14 = image_compare(w, h, a14, ref, f.p.mask, 1.0);
    const image_error eg8 = image_compare(w, h, g8, ref, f.p.mask, 1.0);
    const image_error c4 = image_compare(w, h, g4, a8, f.p.mask, 1.0), c8 = image_compare(w, h, g8, a8, f.p.mask, 1.0);
    CHECK(e8.pixels > 2000);
    CHECK(e14.mae < e8.mae);                                 /* SH(lmax) converges to Lambert */
    CHECK(eg8.mae <= e8.mae + 0.01 * e8.mean_ref);           /* Hermite adds < 1% of the mean */
    CHECK(c8.mae * 4 < c4.mae);                              /* and converges faster than h^2 */
    harness_note("%ld px; rel. MAE vs Lambert: analytic lmax 8 %.2e, lmax 14 %.2e, grid 8^3 Hermite %.2e; "
                 "max error / bound %.2f (lmax 8), %.2f (14); Hermite vs analytic 4^3 -> 8^3: %.2e -> %.2e",
                 e8.pixels, e8.mae / e8.mean_ref, e14.mae / e14.mean_ref, eg8.mae / eg8.mean_ref, worst8, worst14,
                 c4.mae / c4.mean_ref, c8.mae / c8.mean_ref);
done:
    free(ref);
    free(b8);
    free(b14);
    free(a8);
    free(a14);
    free(g4);
    free(g8);
    teardown(&f);
}

/* Ray from the camera through pixel (x, y) centre, the camera model of raster.c. */
static void pixel_ray(const camera *c, int w, int h, int x, int y, double d[3])
{
    double fwd[3], right[3], up[3];
    for (int k = 0; k < 3; ++k) fwd[k] = c->target[k] - c->eye[k];
    v3_normalize(fwd);
    v3_cross(right, fwd, c->up);
    v3_normalize(right);
    v3_cross(up, right, fwd);
    const double focal = 0.5 * h / tan(0.5 * c->fov_deg * M_PI / 180);
    for (int k = 0; k < 3; ++k) d[k] = fwd[k] + (x + 0.5 - 0.5 * w) / focal * right[k] - (y + 0.5 - 0.5 * h) / focal * up[k];
}

/* Distance along d to the triangle's plane, and whether the hit is inside it. */
static double ray_tri(const double o[3], const double d[3], const double *a, const double *b, const double *c, int *inside)
{
    double e1[3], e2[3], p[3], s[3], q[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = b[k] - a[k];
        e2[k] = c[k] - a[k];
        s[k] = o[k] - a[k];
    }
    v3_cross(p, d, e2);
    const double det = v3_dot(e1, p), u = v3_dot(s, p) / det;
    v3_cross(q, s, e1);
    const double v = v3_dot(d, q) / det, t = v3_dot(e2, q) / det;
    *inside = u >= 0 && v >= 0 && u + v <= 1 && t > 0;
    return t;
}

SHL_TEST(render_raster_affine_and_depth)
{
    fixture f;
    if (setup(&f, 2)) return;
    const mesh *g = &f.s.geom;
    const int w = f.s.width, h = f.s.height;
    float *col = malloc(sizeof(float) * 3 * (size_t)g->nv);
    for (int v = 0; v < g->nv; ++v)
        for (int c = 0; c < 3; ++c) col[3 * v + c] = (float)(g->pos[3 * v + c] + 2.0 * c + 3.0);
    float *img = resolve(&f, col);
    double worst = 0;
    long mismatch = 0, covered = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t p = (size_t)y * w + x;
            if (f.p.fb.mesh[p] != 0) continue;
            ++covered;
            double d[3];
            int inside;
            pixel_ray(&f.p.cam, w, h, x, y, d);
            const int *t = g->tri + 3 * (size_t)f.p.fb.tri[p];
            const double tp = ray_tri(f.p.cam.eye, d, g->pos + 3 * t[0], g->pos + 3 * t[1], g->pos + 3 * t[2], &inside);
            for (int c = 0; c < 3; ++c) /* the affine colour at the surface point seen through the pixel */
                worst = fmax(worst, fabs(img[3 * p + c] - (f.p.cam.eye[c] + tp * d[c] + 2.0 * c + 3.0)));
            double best = INFINITY;
            for (int k = 0; k < g->nt; ++k) {
                const int *q = g->tri + 3 * k;
                const double tk = ray_tri(f.p.cam.eye, d, g->pos + 3 * q[0], g->pos + 3 * q[1], g->pos + 3 * q[2], &inside);
                if (inside && tk < best) best = tk;
            }
            mismatch += fabs(best - tp) > 1e-4 * tp;
        }
    CHECK(covered > 2000);
    CHECK(worst < 1e-4);
    CHECK(mismatch == 0);
    harness_note("%ld px; max |interpolated - exact affine colour| %.1e; nearest-surface mismatches %ld", covered, worst,
                 mismatch);
    free(col);
    free(img);
    teardown(&f);
}

/* A flat grid facing the camera, 64x64 pixels: column edges at screen x = 8.25, 8.5 + k/3
 * (k = 1..140) and 55.75, rows alike, so every third interior grid line passes through pixel
 * centres (up to the projection's rounding) and most of its 2 x 142^2 triangles hold no pixel
 * centre.  world: eye + depth (fwd + (sx - 32) / f right - (sy - 32) / f up), the camera of
 * raster.c.  diag: which diagonal splits the cells. */
enum { GRID_N = 142 };

static double grid_line(int k) { return k == 0 ? 8.25 : k == GRID_N ? 55.75 : 8.5 + k / 3.0; }

static void grid_mesh(const camera *cam, double depth, int diag, double *pos, int *tri)
{
    double fwd[3], right[3], up[3];
    for (int k = 0; k < 3; ++k) fwd[k] = cam->target[k] - cam->eye[k];
    v3_normalize(fwd);
    v3_cross(right, fwd, cam->up);
    v3_normalize(right);
    v3_cross(up, right, fwd);
    const double f = 0.5 * 64 / tan(0.5 * cam->fov_deg * M_PI / 180);
    for (int j = 0; j <= GRID_N; ++j)
        for (int i = 0; i <= GRID_N; ++i)
            for (int k = 0; k < 3; ++k)
                pos[3 * (j * (GRID_N + 1) + i) + k] =
                    cam->eye[k] + depth * (fwd[k] + (grid_line(i) - 32) / f * right[k] - (grid_line(j) - 32) / f * up[k]);
    for (int j = 0, t = 0; j < GRID_N; ++j)
        for (int i = 0; i < GRID_N; ++i, t += 2) {
            const int a = j * (GRID_N + 1) + i, b = a + 1, c = a + GRID_N + 1, d = c + 1;
            const int q[2][6] = {{a, b, d, a, d, c}, {a, b, c, b, d, c}};
            memcpy(tri + 3 * t, q[diag], sizeof q[diag]);
        }
}


/* Morton key of x in [lo, hi]: 10 bits per axis, bit b of axis a at bit 3 b + a (a bit loop,
 * independent of mesh.c's shifts and masks). */
static uint64_t morton_key(const double x[3], const double lo[3], const double hi[3])
{
    uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
        const double u = hi[a] > lo[a] ? (x[a] - lo[a]) / (hi[a] - lo[a]) * 1024.0 : 0.0;
        const uint64_t q = u < 0.0 ? 0 : u >= 1023.0 ? 1023 : (uint64_t)u;
        for (int b = 0; b < 10; ++b) key |= ((q >> b) & 1) << (3 * b + a);
    }
    return key;
}

/* mesh_vertex_order (prt_init's first stage) on the tiny scene's receivers: every triangle
 * keeps its place and its corners' positions, normals and materials bit for bit, the vertices
 * are a permutation of the old ones (each used once as the image of one old vertex), and
 * their Morton keys do not decrease. */
SHL_TEST(render_vertex_order_permutes_vertices)
{
    scene a, b;
    char err[256];
    CHECK(!scene_parse(tiny_scene, "tiny", ".", &a, err, sizeof err));
    CHECK(!scene_parse(tiny_scene, "tiny", ".", &b, err, sizeof err));
    CHECK(!mesh_vertex_order(&b.geom));
    const mesh *m0 = &a.geom, *m1 = &b.geom;
    CHECK(m0->nv == m1->nv && m0->nt == m1->nt);
    int *old_of = malloc(sizeof(int) * (size_t)m1->nv);
    CHECK(old_of != NULL);
    for (int v = 0; v < m1->nv; ++v) old_of[v] = -1;
    long mismatched = 0, conflicts = 0, moved = 0, decreasing = 0;
    for (size_t k = 0; k < 3 * (size_t)m0->nt; ++k) {
        const int v0 = m0->tri[k], v1 = m1->tri[k];
        mismatched += memcmp(m0->pos + 3 * (size_t)v0, m1->pos + 3 * (size_t)v1, sizeof(double) * 3) != 0 ||
                      memcmp(m0->nrm + 3 * (size_t)v0, m1->nrm + 3 * (size_t)v1, sizeof(double) * 3) != 0 ||
                      m0->mat[v0] != m1->mat[v1];
        conflicts += old_of[v1] >= 0 && old_of[v1] != v0;
        old_of[v1] = v0;
    }
    double lo[3], hi[3];
    mesh_bounds(m0, lo, hi);
    for (int v = 0; v < m1->nv; ++v) {
        moved += old_of[v] != v;
        decreasing += v > 0 && morton_key(m1->pos + 3 * (size_t)v, lo, hi) < morton_key(m1->pos + 3 * (size_t)(v - 1), lo, hi);
    }
    CHECK(mismatched == 0 && conflicts == 0 && decreasing == 0 && moved > 0);
    harness_note("%d vertices, %ld moved; %d triangles: corners identical; Morton keys non-decreasing", m1->nv, moved,
                 m1->nt);
    free(old_of);
    scene_free(&a);
    scene_free(&b);
}
/* The raster's pixel-centre rule on a watertight mesh: the grid above covers exactly the
 * 48 x 48 pixel centres inside it, each once - a triangle rejected by raster.c's per-vertex keys
 * while holding a centre (on a vertex or an edge) would leave a hole.  Then the locality
 * reordering (mesh_locality_order + tri_id): the grid twice, coplanar with the other diagonal
 * (depths equal up to rounding, so the z-buffer's order decides ties), triangles shuffled, plus
 * a triangle crossing the near plane (clipped into 2 records): the reordered draw's buffer equals
 * the unreordered one bit for bit on 1 and 2 threads, and drawing the copies the other way
 * round changes it (the ties are real). */
SHL_TEST(render_raster_watertight_and_reorder)
{
    const camera cam = {{0.3, 1.0, 4.0}, {0.1, 0.8, 0.0}, {0, 1, 0}, 50.0};
    const int nv1 = (GRID_N + 1) * (GRID_N + 1), nt1 = 2 * GRID_N * GRID_N, nv = 2 * nv1 + 3, nt = 2 * nt1 + 1;
    double *pos = malloc(sizeof(double) * 3 * (size_t)nv), *rpos = NULL;
    int *tri = malloc(sizeof(int) * 3 * (size_t)nt), *swapped = malloc(sizeof(int) * 3 * (size_t)nt), *rtri = NULL, *rid = NULL;
    framebuf fb[2];
    CHECK(pos && tri && swapped && !framebuf_init(&fb[0], 64, 64) && !framebuf_init(&fb[1], 64, 64));
    grid_mesh(&cam, 3.0, 0, pos, tri);
    raster_mesh rm = {nv1, nt1, pos, tri, 0, NULL};
    CHECK(!raster_draw(&fb[0], &cam, &rm, 1, 2));
    long covered = 0, wrong = 0;
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
            const int inside = x >= 8 && x <= 55 && y >= 8 && y <= 55; /* centres 8.5 .. 55.5 */
            covered += fb[0].mesh[64 * y + x] == 0;
            wrong += (fb[0].mesh[64 * y + x] == 0) != inside;
        }
    CHECK(covered == 48 * 48 && wrong == 0);

    grid_mesh(&cam, 3.0, 1, pos + 3 * (size_t)nv1, tri + 3 * (size_t)nt1);
    for (int i = 3 * nt1; i < 6 * nt1; ++i) tri[i] += nv1;
    const double clip[9] = {-2.0, 0.2, 6.0, 1.5, 1.4, 1.0, -0.5, 2.0, -3.0}; /* the last corner is behind the eye */
    memcpy(pos + 6 * (size_t)nv1, clip, sizeof clip);
    const int ct[3] = {2 * nv1, 2 * nv1 + 1, 2 * nv1 + 2};
    memcpy(tri + 6 * (size_t)nt1, ct, sizeof ct);
    uint64_t st = 12345;
    for (int t = nt - 1; t > 0; --t) { /* Fisher-Yates */
        st = st * 6364136223846793005ull + 1442695040888963407ull;
        const int u = (int)((st >> 33) % (uint64_t)(t + 1));
        int tmp[3];
        memcpy(tmp, tri + 3 * t, sizeof tmp);
        memcpy(tri + 3 * t, tri + 3 * u, sizeof tmp);
        memcpy(tri + 3 * u, tmp, sizeof tmp);
    }
    rm = (raster_mesh){nv, nt, pos, tri, 0, NULL};
    CHECK(!raster_draw(&fb[0], &cam, &rm, 1, 1));
    int rnv = 0;
    mesh m = {nv, nt, pos, NULL, tri, NULL};
    CHECK(!mesh_locality_order(&m, &rpos, &rtri, &rid, &rnv));
    long moved = 0;
    for (int t = 0; t < nt; ++t) moved += rid[t] != t;
    const size_t npx = 64 * 64;
    for (int nth = 1; nth <= 2; ++nth) {
        const raster_mesh ro = {rnv, nt, rpos, rtri, 0, rid};
        CHECK(!raster_draw(&fb[1], &cam, &ro, 1, nth));
        CHECK(!memcmp(fb[0].depth, fb[1].depth, sizeof(float) * npx) && !memcmp(fb[0].mesh, fb[1].mesh, sizeof(int) * npx));
        CHECK(!memcmp(fb[0].tri, fb[1].tri, sizeof(int) * npx));
        long differ = 0; /* back and bary are defined where a triangle is seen */
        for (size_t q = 0; q < npx; ++q)
            differ += fb[0].tri[q] >= 0 && (fb[0].back[q] != fb[1].back[q] || memcmp(fb[0].bary + 3 * q, fb[1].bary + 3 * q, sizeof(float) * 3));
        CHECK(differ == 0);
    }
    long clipped = 0, by_order = 0, first = 0;
    for (size_t q = 0; q < npx; ++q) {
        clipped += fb[0].tri[q] >= 0 && tri[3 * fb[0].tri[q]] == 2 * nv1;
        first += fb[0].tri[q] >= 0 && tri[3 * fb[0].tri[q]] < nv1;
    }
    /* the same triangles drawn in reverse order: triangle t becomes nt - 1 - t */
    for (int t = 0; t < nt; ++t) memcpy(swapped + 3 * (nt - 1 - t), tri + 3 * t, sizeof(int) * 3);
    rm = (raster_mesh){nv, nt, pos, swapped, 0, NULL};
    CHECK(!raster_draw(&fb[1], &cam, &rm, 1, 1));
    for (size_t q = 0; q < npx; ++q) by_order += fb[0].mesh[q] == 0 && nt - 1 - fb[1].tri[q] != fb[0].tri[q];
    CHECK(moved > nt / 2 && clipped > 0 && by_order > 0);
    harness_note("grid: %ld px covered of 48 x 48, %ld wrong; reordered (%ld of %d triangles moved): buffers identical; "
                 "%ld px of the clipped triangle, %ld px decided by draw order, %ld px won by the first copy",
                 covered, wrong, moved, nt, clipped, by_order, first);
    framebuf_free(&fb[0]);
    framebuf_free(&fb[1]);
    free(pos);
    free(tri);
    free(swapped);
    free(rpos);
    free(rtri);
    free(rid);
}

SHL_TEST(render_threads_bit_identical)
{
    fixture f1, f2;
    if (setup(&f1, 1)) return;
    if (setup(&f2, 2)) {
        teardown(&f1);
        return;
    }
    float *a = render(&f1, LM_GRID, 8, 8), *b = render(&f2, LM_GRID, 8, 8);
    float *c = render(&f1, LM_MC, 4, 0), *d = render(&f2, LM_MC, 4, 0);
    const size_t n = sizeof(float) * 3 * (size_t)f1.s.width * (size_t)f1.s.height;
    CHECK(a && b && !memcmp(a, b, n));
    CHECK(c && d && !memcmp(c, d, n));
    CHECK(!memcmp(f1.p.fb.tri, f2.p.fb.tri, sizeof(int) * (size_t)f1.s.width * (size_t)f1.s.height));
    free(a);
    free(b);
    free(c);
    free(d);
    teardown(&f1);
    teardown(&f2);
}

/* VSL (Hasan 2009 Eq. 5) with k^2 = 2500 jittered strata against a 1000 x 1000 midpoint rule
 * over the cone in (cos theta, phi), dw = dcos dphi.  Tolerance: 5 sigma of plain uniform cone
 * sampling, sigma^2 = (Omega^2 E[g^2] - I^2) / N (jittered stratification has at most that
 * variance), plus the quadrature's error: the integrand g = cos+_x cos+_y is smooth except on the
 * two curves where a cosine crosses 0; a curve crosses at most 4 x 1000 cells, each off by at
 * most its area x max g, so the error is <= 8000 Omega max g / 1e6 (the smooth cells' O(h^2)
 * error is far smaller).  Two configurations: the cone fully above both horizons, and cut by both. */
SHL_TEST(render_vsl_cone_quadrature)
{
    const double cfg[2][4][3] = {
        {{0.1, 0.2, -1.0}, {0.0, 0.0, 1.0}, {0.3, -0.2, -1.0}, {0.4, 0, 0}}, /* x, n, HVL normal, radius; HVL at 0 */
        {{-0.2, 0.0, 1.0}, {1.0, 0.0, 0.0}, {0.6, 0.0, 0.8}, {0.9, 0, 0}},
    };
    for (int c = 0; c < 2; ++c) {
        shl_hvl h;
        memset(&h, 0, sizeof h);
        double n[3], a[3], t[3], b[3];
        memcpy(n, cfg[c][1], sizeof n);
        memcpy(h.normal, cfg[c][2], sizeof h.normal);
        v3_normalize(n);
        v3_normalize(h.normal);
        h.radius = cfg[c][3][0];
        v3_sub(a, h.pos, cfg[c][0]);
        const double d = v3_normalize(a), ca = sqrt(1 - h.radius * h.radius / (d * d)), omega = 2 * M_PI * (1 - ca);
        v3_basis(a, t, b);
        const int m = 1000;
        double sum = 0.0, sum2 = 0.0, gmax = 0.0;
        for (int i = 0; i < m; ++i)
            for (int j = 0; j < m; ++j) {
                const double co = ca + (1 - ca) * (i + 0.5) / m, si = sqrt(1 - co * co), ph = 2 * M_PI * (j + 0.5) / m;
                double w[3];
                for (int q = 0; q < 3; ++q) w[q] = co * a[q] + si * (cos(ph) * t[q] + sin(ph) * b[q]);
                const double g = fmax(0.0, v3_dot(n, w)) * fmax(0.0, -v3_dot(h.normal, w));
                sum += g;
                sum2 += g * g;
                gmax = fmax(gmax, g);
            }
        const double I = sum * omega / ((double)m * m), Eg2 = sum2 / ((double)m * m), N = 2500;
        const double sigma = sqrt(fmax(0.0, omega * omega * Eg2 - I * I) / N), quad = 8000 * omega * gmax / 1e6;
        const double est = vsl_radiance(&h, cfg[c][0], n, 50, 12345u) * M_PI * M_PI * M_PI * h.radius * h.radius;
        harness_note("config %d: VSL %.6e, quadrature %.6e, |diff| %.2e, tol %.2e", c, est, I, fabs(est - I), 5 * sigma + quad);
        CHECK(I > 0);
        CHECK(fabs(est - I) <= 5 * sigma + quad);
    }
}

/* A VSL of radius r at distance d tends to the VPL at its centre: the cone's solid angle is
 * pi r^2 / d^2 (1 + O(r^2/d^2)), and over a cone of half-angle alpha = asin(r/d) the integrand
 * cos_x cos_y (each a unit-gradient function of w, both >= 0.5 here) changes by at most 2 alpha,
 * i.e. relatively by at most 2 alpha / 0.25 = 8 alpha.  With r/d = 1e-4 the tolerance is 1e-3. */
SHL_TEST(render_vsl_point_limit)
{
    shl_hvl h;
    memset(&h, 0, sizeof h);
    const double x[3] = {0.3, -0.1, -2.0}, n[3] = {0, 0, 1};
    double nh[3] = {0.2, 0.1, -1.0}, w[3];
    v3_normalize(nh);
    memcpy(h.normal, nh, sizeof nh);
    v3_sub(w, h.pos, x);
    const double d = v3_normalize(w);
    h.radius = 1e-4 * d;
    CHECK(v3_dot(n, w) >= 0.5 && -v3_dot(nh, w) >= 0.5);
    const double vpl = vpl_radiance(&h, x, n), vsl = vsl_radiance(&h, x, n, 3, 7u);
    harness_note("VPL %.9e, VSL (r/d 1e-4, 9 samples) %.9e, rel. diff %.2e", vpl, vsl, fabs(vsl / vpl - 1));
    CHECK(vpl > 0 && fabs(vsl / vpl - 1) <= 1e-3);
}

typedef struct {
    long grain;
    int nthreads;
    unsigned char *seen;
    unsigned char *chunk_bad; /* per chunk: longer than grain, misaligned, or a worker index out of range */
} parfor_probe;

static void parfor_visit(void *arg, int worker, long begin, long end)
{
    parfor_probe *q = arg;
    for (long i = begin; i < end; ++i) ++q->seen[i];
    q->chunk_bad[begin / q->grain] = end - begin > q->grain || begin % q->grain || worker < 0 || worker >= q->nthreads;
}

SHL_TEST(render_parfor_library_loop)
{
    enum { N = 1000, GRAIN = 7 };
    unsigned char seen[N], chunk_bad[N / GRAIN + 1];
    for (int fail = -1; fail <= 0; ++fail)
        for (int nt = 1; nt <= 3; ++nt) {
            parfor_probe q = {GRAIN, nt, seen, chunk_bad};
            memset(seen, 0, sizeof seen);
            memset(chunk_bad, 0, sizeof chunk_bad);
            shl__thread_fail_after = fail; /* 0: the first thread creation fails */
            const int st = par_for(N, GRAIN, nt, parfor_visit, &q);
            shl__thread_fail_after = -1;
            CHECK(st == (fail == 0 && nt > 1 ? -1 : 0));
            for (int i = 0; i < N; ++i) CHECK(seen[i] == 1);
            for (int c = 0; c < N / GRAIN + 1; ++c) CHECK(!chunk_bad[c]);
        }
}

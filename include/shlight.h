/*
 * shlight -- analytic spherical-harmonic lighting from near-field area lights.
 *
 * Conventions (all entry points):
 *  - Real SH with the Condon-Shortley phase, flat index k = l*(l+1) + m,
 *    Y00 = 1/(2 sqrt(pi)), Y1-1 = -c y, Y10 = c z, Y11 = -c x, c = sqrt(3/(4 pi))
 *    (Dr.Jit sh_eval, DirectXSH, Sloan).
 *  - "lmax" is the highest band; a vector of bands 0..lmax has
 *    SHL_NCOEFFS(lmax) = (lmax+1)^2 entries.
 *  - Every function returns an int status: SHL_OK (0) or a negative SHL_E*
 *    code (shl_strerror() names it).  On error no output is written, with one
 *    deliberate exception: the *_create functions (shl_ctx_create,
 *    shl_lights_create, shl_grid_create, shl_brdf_table_create) set *out = NULL
 *    on every failure when out itself is non-NULL (bad arguments, SHL_ENOMEM),
 *    so cleanup code may call the matching *_destroy on it unconditionally.
 *    The library never prints, never aborts, never calls exit().
 *  - Gradients use the layout grad[a*nc + k] = d coeffs[k] / d x[a],
 *    a = 0,1,2 (x, y, z), nc = SHL_NCOEFFS(lmax).
 */
#ifndef SHLIGHT_H
#define SHLIGHT_H

#ifdef __cplusplus
extern "C" {
#endif

/* Symbol visibility.  The library is built with -fvisibility=hidden, so only what
 * this header declares is exported from libshlight.so: every declaration between
 * this push and the pop at the end of the file is default-visible (gcc and clang;
 * a definition inherits the visibility of its first declaration).  A pragma region
 * has the effect of SLEEF's EXPORT macro on each declaration, without one on every
 * line, so a new declaration placed anywhere in this header is exported.  Internal
 * functions and tables (shl__*, declared in src/internal.h and the other headers of src/)
 * stay hidden: programs reach them only by linking the static archive (README
 * "Layout", internal boundary). */
#if defined(__GNUC__)
#pragma GCC visibility push(default)
#endif

/* The one place the version is written: the Makefile reads it for the shared
 * library's file name (libshlight.so.MAJOR.MINOR.PATCH, SONAME libshlight.so.MAJOR)
 * and for shlight.pc. */
#define SHL_VERSION_STRING "0.1.0"

/** Highest band supported by every entry point. */
#define SHL_LMAX_MAX 30
/** Largest polygon vertex count accepted. */
#define SHL_MAX_VERTS 64
/** Number of SH coefficients for bands 0..lmax. */
#define SHL_NCOEFFS(lmax) (((lmax) + 1) * ((lmax) + 1))

/* ---- status codes ---------------------------------------------------- */
#define SHL_OK             0
#define SHL_ENULL         -1  /* a required pointer argument is NULL              */
#define SHL_ELMAX         -2  /* lmax outside 0..SHL_LMAX_MAX (or above ctx lmax)  */
#define SHL_ENVERTS       -3  /* vertex count outside 3..SHL_MAX_VERTS            */
#define SHL_ENONFINITE    -4  /* a coordinate or parameter is NaN or infinite     */
#define SHL_ENOMEM        -5  /* memory allocation failed                         */
#define SHL_EDOMAIN       -6  /* argument outside its domain (zero direction, radius <= 0, ...) */
#define SHL_ETHREAD       -7  /* thread creation failed                           */

/** Human-readable name of a status code (never NULL). */
const char *shl_strerror(int status);

/* ---- context ----------------------------------------------------------- */
/** Opaque evaluation context: immutable after creation, share freely across threads. */
typedef struct shl_ctx shl_ctx;

/** Create a context for bands 0..lmax (0 <= lmax <= SHL_LMAX_MAX).
 *  On failure *out = NULL (if out != NULL). */
int shl_ctx_create(int lmax, shl_ctx **out);
/** As shl_ctx_create, with the batch kernels of the instruction set named isa
 *  ("scalar", "avx2", "avx512", "neon": see shl_ctx_isa), whatever SHLIGHT_ISA says.
 *  isa NULL: SHL_ENULL; not compiled in or not supported by this CPU and OS:
 *  SHL_EDOMAIN ("scalar" always succeeds).  On failure *out = NULL (if out != NULL). */
int shl_ctx_create_isa(int lmax, const char *isa, shl_ctx **out);
/** Destroy a context (NULL is accepted and ignored). */
void shl_ctx_destroy(shl_ctx *ctx);
/** Highest band of the context, or SHL_ENULL. */
int shl_ctx_lmax(const shl_ctx *ctx);

/* ---- SH basis ---------------------------------------------------------- */
/**
 * Evaluate Y_lm(dir) for all l <= lmax into y[SHL_NCOEFFS(lmax)].
 * dir need not be unit length; it must be finite and non-zero (SHL_EDOMAIN).
 */
int shl_eval_basis(int lmax, const double dir[3], double *y);
int shl_eval_basis_f(int lmax, const float dir[3], float *y);

/* ---- polygonal lights (Wang & Ramamoorthi 2018) ------------------------ */
/**
 * SH projection of a uniform, unit-radiance planar polygon seen from x:
 *   coeffs[l*(l+1)+m] = integral over the solid angle of the polygon at x of Y_lm(w) dw,
 * for l <= shl_ctx_lmax(ctx); coeffs has SHL_NCOEFFS(lmax) entries.
 * verts: n*3 doubles, xyz interleaved; 3 <= n <= SHL_MAX_VERTS; planar and simple,
 * convex or concave, either winding (both give the same result).
 * A point in the polygon's plane sees no solid angle: all coefficients are 0.
 * Zero-length edges (repeated vertices) are skipped.
 * Near the plane (distance h from it), with the foot of x outside the polygon at
 * in-plane distance dmin >= 1/4 of the polygon's size from its vertex fan and
 * h <= dmin/64, lmax <= 16: the integrals are taken by a Gauss rule on the
 * polygon's plane (dw = h dA / r^3, h as an explicit factor), so the error stays
 * below ~1e-13 of the solid angle however small h is (the boundary recurrence used
 * elsewhere loses ~eps dmin / h there); 40x (dmin ~ size) to 170x (dmin = size/4)
 * the cost of the recurrence for a quad at lmax 8, in that regime only.  Closer to
 * an edge the recurrence stays, with its error ~eps dmin / h of the solid angle.
 */
int shl_polygon(const shl_ctx *ctx, const double x[3],
                const double *verts, int n, double *coeffs);
/** Float version: same semantics; the per-edge geometry is set up in double,
 *  the band recurrences run in float (the near-plane planar rule above in double).
 *  Where float would lose the boundary sums (sum of the edges' arc angles above
 *  2^7 solid angles: polygons under ~1/32 rad, or seen at grazing angles) the
 *  recurrence runs in double and the result is rounded: error ~1e-7 of the
 *  solid angle down to 1e-5 rad (float recurrence: ~2.5e-7 / angular size).
 *  The same for shl_polygon_grad_f. */
int shl_polygon_f(const shl_ctx *ctx, const float x[3],
                  const float *verts, int n, float *coeffs);

/**
 * Coefficients (as shl_polygon) and their spatial gradient, computed jointly
 * (Wu et al. 2020): grad[a*nc + k] = d coeffs[k] / d x[a], a = 0,1,2, nc = SHL_NCOEFFS(lmax);
 * grad has 3*nc entries.  The gradient grows like 1/distance near an edge and
 * stays finite off the plane.  In the polygon's plane the coefficients are 0 and
 * not differentiable (two-sided emission makes them ~|height|): grad is set to 0.
 */
int shl_polygon_grad(const shl_ctx *ctx, const double x[3], const double *verts, int n,
                     double *coeffs, double *grad);
int shl_polygon_grad_f(const shl_ctx *ctx, const float x[3], const float *verts, int n,
                       float *coeffs, float *grad);

/** Solid angle (steradians, >= 0) of the polygon seen from x; 0 in its plane
 *  (within 8 eps x the largest vertex distance of it).  Relative accuracy a few
 *  ulps times the planar conditioning (~ distance / depth of the polygon) also
 *  near the plane: the plane distance h is computed in double-double from exact
 *  coordinate differences, relative error <= 3 eps + 16 n eps^2 cond with cond the
 *  componentwise condition number of N . (v_0 - x) (N the Newell normal; exact,
 *  cond = 1, for an axis-aligned plane), and every fan term carries h as a factor. */
int shl_polygon_solid_angle(const double x[3], const double *verts, int n, double *omega);

/* ---- light sets (Wu et al. 2020, Alg. 1) ------------------------------- */
/**
 * A set of lights with RGB radiance; contributions add linearly.  Evaluation
 * only reads the set (share it across threads); adding is not thread-safe.
 */
typedef struct shl_lights shl_lights;

/** Create an empty light set.  On failure *out = NULL (if out != NULL). */
int shl_lights_create(shl_lights **out);
/** Destroy a light set (NULL is accepted and ignored). */
void shl_lights_destroy(shl_lights *lights);
/**
 * Add (copy) a uniform polygon light: verts and n as for shl_polygon, rgb[3]
 * finite radiance per colour channel (any sign).  two_sided = 1: emits on both
 * sides.  two_sided = 0: emits only toward its front, the side from which the
 * vertices appear counter-clockwise, i.e. toward the Newell normal
 * n = sum_i (v_i - v_0) x (v_i+1 - v_0) (a triangle: (v1 - v0) x (v2 - v0));
 * x receives light only if n . (x - v_0) > 0 (on or behind the plane: nothing).
 * two_sided other than 0/1: SHL_EDOMAIN.  On error the set is unchanged.
 */
int shl_lights_add_polygon(shl_lights *lights, const double *verts, int n, const double rgb[3],
                           int two_sided);
/**
 * Add (copy) a uniform spherical light: centre center[3], radius, rgb[3] finite
 * radiance per colour channel (any sign).  Validated as shl_sphere: NULL pointer
 * SHL_ENULL; center, rgb or radius NaN/infinite SHL_ENONFINITE; radius <= 0
 * SHL_EDOMAIN.  On error the set is unchanged.
 * In shl_lights_eval (and hence shl_lights_eval_batch and shl_grid_fill) it adds
 *   rgb[c*nc + k] += rgb_c * coeffs[k],  grad[(c*3 + a)*nc + k] += rgb_c * grad_s[a*nc + k],
 * with coeffs, grad_s those of shl_sphere_grad(ctx, x, center, radius, ..) (agreeing
 * to rounding: the set goes through its shared lobe integrals, zh_l(d) =
 * K_l P_l(d . axis) times the cap's ZH, Funk-Hecke).  A sphere emits in every
 * direction (there is no one-sided option).  A point inside or on the sphere
 * (|center - x| <= radius) is surrounded by it: coefficient 0 gets
 * rgb_c sqrt(4 pi), every other coefficient and the gradient 0.
 */
int shl_lights_add_sphere(shl_lights *lights, const double center[3], double radius,
                          const double rgb[3]);
/** Number of lights in the set, or SHL_ENULL. */
int shl_lights_count(const shl_lights *lights);
/**
 * RGB SH coefficients of the whole set at x, nc = SHL_NCOEFFS(shl_ctx_lmax(ctx)):
 *   rgb[c*nc + k]        = sum over lights of rgb_c * coeffs[k]        (3*nc entries, c = 0,1,2),
 *   grad[(c*3 + a)*nc + k] = d rgb[c*nc + k] / d x[a]                    (9*nc entries; NULL: skipped).
 * A workspace is allocated per call (SHL_ENOMEM).
 */
int shl_lights_eval(const shl_ctx *ctx, const shl_lights *lights, const double x[3], double *rgb,
                    double *grad);
/** shl_lights_eval at npts >= 0 points pts[3*p .. 3*p+2]: point p writes rgb + 3*nc*p and
 *  (if grad != NULL) grad + 9*nc*p.  All points are checked before anything is written. */
int shl_lights_eval_batch(const shl_ctx *ctx, const shl_lights *lights, int npts, const double *pts,
                          double *rgb, double *grad);

/* ---- SH grids and interpolation (Wu 2020 Alg. 1 and 4; Annen 2004) ---- */
/**
 * A regular grid of res[0] x res[1] x res[2] nodes spanning the box [lo, hi]
 * (node (i,j,k) at lo + (i,j,k) * (hi - lo) / (res - 1)), storing at every node
 * the RGB coefficients and their gradients, in the layouts of shl_lights_eval.
 * Filling writes nodes; interpolation only reads (share it across threads).
 */
typedef struct shl_grid shl_grid;

#define SHL_GRID_FLOAT  0   /* node storage: float (default) */
#define SHL_GRID_DOUBLE 1   /* node storage: double */
/** Largest node count per axis. */
#define SHL_GRID_RES_MAX 1024
/**
 * Largest thread count of the threaded entry points.  Their threads (all but the
 * calling one) come from one process-wide pool: created when a call first needs
 * them, parked between calls (a call wakes them instead of creating threads, and
 * does not wait for one that has not started when all the work is taken), joined
 * at exit; a forked child starts an empty pool.  While one threaded call
 * runs, a threaded call from another thread runs on its calling thread alone
 * (same results: they never depend on nthreads).
 */
#define SHL_MAX_THREADS 256

/** Bytes per grid node: 3 colours x (value + 3 gradient components) x nc x
 *  sizeof(float or double); e.g. lmax 4, float: 1200 bytes. */
int shl_grid_bytes_per_node(int lmax, int storage, int *bytes);
/**
 * Create a zero-filled grid for bands 0..shl_ctx_lmax(ctx).  Needs lo[a] < hi[a]
 * (finite) and 2 <= res[a] <= SHL_GRID_RES_MAX, storage SHL_GRID_FLOAT or
 * SHL_GRID_DOUBLE (else SHL_EDOMAIN).  Memory: nodes x shl_grid_bytes_per_node.
 * On failure *out = NULL (if out != NULL).
 */
int shl_grid_create(const shl_ctx *ctx, const double lo[3], const double hi[3], const int res[3],
                    int storage, shl_grid **out);
/** Destroy a grid (NULL is accepted and ignored). */
void shl_grid_destroy(shl_grid *grid);
/** Position of node idx = (i, j, k), 0 <= idx[a] < res[a] (else SHL_EDOMAIN). */
int shl_grid_node_position(const shl_grid *grid, const int idx[3], double pos[3]);
/** Read node idx: rgb[3*nc] and (if grad != NULL) grad[9*nc], layouts of shl_lights_eval. */
int shl_grid_get_node(const shl_grid *grid, const int idx[3], double *rgb, double *grad);
/** Write node idx from rgb[3*nc] and grad[9*nc] (finite; rounded to float storage). */
int shl_grid_set_node(shl_grid *grid, const int idx[3], const double *rgb, const double *grad);
/**
 * Set every node to the light set's coefficients and gradients at its position
 * (Wu 2020 Alg. 1 lines 2-8), on 1 <= nthreads <= SHL_MAX_THREADS threads (1: the
 * calling thread only, no thread is created); the result does not depend on
 * nthreads, bit for bit.  It also records which lights meet the box
 * (shl_grid_lights_in_box).  SHL_ETHREAD if a thread cannot be created (the grid
 * is then unchanged).
 * Double grids: every node is shl_lights_eval at shl_grid_node_position, bit for bit.
 * Float grids: nodes go in blocks of 64 (in node order) through the float SIMD
 * light-set batch, gradients included: every node is, bit for bit,
 * shl_lights_eval_batch_f at its position rounded to float, so its error against
 * shl_lights_eval is that batch's (per light, its batch tolerance times |rgb|,
 * plus the float sum: README "Batch evaluation and SIMD") plus the move of the
 * position by the rounding, at most 2^-24 max(|lo[a]|, |hi[a]|) per axis (times
 * the gradient).  That path is taken when every axis has max(|lo[a]|, |hi[a]|)
 * <= 2^126 and a spacing h[a] >= 2^-10 max(|lo[a]|, |hi[a]|) and >= 2^-100 (the
 * rounding then moves a node by at most 2^-14 h[a]); other float grids take the
 * double path, rounded to float.
 */
int shl_grid_fill(shl_grid *grid, const shl_lights *lights, int nthreads);

#define SHL_GRID_IN_BOX   0  /* lights whose geometry meets the closed box [lo, hi] */
#define SHL_GRID_NEAR_BOX 1  /* ... meets the box grown by one node spacing h[a] on every side (includes IN_BOX) */
/**
 * Lights of the last successful shl_grid_fill (indices in its light set, in the
 * order added) whose geometry meets the closed box [lo, hi] (which =
 * SHL_GRID_IN_BOX), or the box [lo - h, hi + h], h[a] = (hi[a] - lo[a]) / (res[a] - 1)
 * (SHL_GRID_NEAR_BOX).  *count = their number (0 before the first fill; lights
 * added to the set later count from the next fill); the first min(*count, cap)
 * indices, ascending, go to index[] (NULL allowed when cap = 0).
 * Geometry: a polygon is its planar region (edges included, any rgb, one- or
 * two-sided alike), tested exactly -- an edge crossing the box, or the box's
 * section by the polygon's plane inside the polygon (concave polygons too; a
 * polygon whose bounding box overlaps the box but which misses it does not count);
 * collinear vertices: the segments.  A sphere is its solid ball: it meets the box
 * iff the distance from its centre to the box is <= radius (a box inside the ball
 * counts).  Touching counts.  Decided in floating point: a vertex on the box and a
 * polygon in a face's plane count exactly; other contacts (an edge grazing the box,
 * a sphere tangent to it, a plane through a corner) are decided to rounding.
 * Why it matters: the grid samples a field that is smooth only away from the
 * lights; a light in the box (a sphere's surface, a polygon's plane and edges)
 * puts kinks and discontinuities inside cells, and every interpolant is wrong near
 * it (measured: a sphere of radius 0.3 in an 8^3 box of side 2, L00 within 0.3 of
 * its surface off by up to 56-69% of its in-ball value sqrt(4 pi), all three
 * methods).  A light within one spacing of the box is in no cell, but the field's
 * derivatives (and the node gradients Taylor and Hermite carry) grow like inverse
 * powers of the distance to it (the same sphere half a spacing outside the box: up
 * to 8% Hermite, 26% Taylor, 33% trilinear of max |L00| nearby; tests/test_grid.c,
 * grid_sphere_in_box_reported).  Evaluate points near such lights directly
 * (shl_lights_eval_batch).
 * cap < 0 or another which: SHL_EDOMAIN.  Reads only (thread-safe with interp).
 */
int shl_grid_lights_in_box(const shl_grid *grid, int which, int cap, int *index, int *count);

#define SHL_INTERP_TRILINEAR 0  /* values only */
#define SHL_INTERP_TAYLOR    1  /* Annen 2004 Eq. (15)-(16): first-order Taylor from the 8 corners, inverse-distance^b weights */
#define SHL_INTERP_HERMITE   2  /* Wu 2020 Alg. 4: tricubic Hermite (x, then y, then z), gradients carried linearly */
/**
 * Interpolate the grid's RGB coefficients at npts >= 0 points pts[3*p .. 3*p+2]
 * into rgb + 3*nc*p (layout rgb[c*nc + k]), with the cell's 8 corner nodes.
 * Points outside the box are clamped to it (each coordinate to [lo[a], hi[a]]):
 * they get the value at the nearest point of the box, never an extrapolation
 * (shl_grid_interp_clamped counts them).
 * taylor_b: the exponent b of SHL_INTERP_TAYLOR (finite, > 0; ignored otherwise).
 * 1 <= nthreads <= SHL_MAX_THREADS as for shl_grid_fill; results do not depend on it.
 * Exactness: trilinear reproduces trilinear fields; Taylor reproduces linear fields
 * (with exact node gradients); Hermite reproduces node values and every field whose
 * monomials x^i y^j z^k (i, j, k <= 3) satisfy: i >= 2 => j = k = 0, j >= 2 => k = 0
 * (e.g. any cubic in one variable, xyz, x y^3, x y z^3, but not x^2 y).
 * Float grids interpolate with the SIMD kernel of the context that created the
 * grid (shl_ctx_isa; sums in double, within a few DBL_EPSILON times the data's
 * scale of the scalar reference, which SHLIGHT_ISA=scalar selects; README
 * "Grid interpolation"); double grids always use the reference.
 */
int shl_grid_interp(const shl_grid *grid, int method, double taylor_b, int npts, const double *pts,
                    double *rgb, int nthreads);
/**
 * shl_grid_interp that also sets *nclamped (non-NULL, else SHL_ENULL) to the number
 * of points that were clamped: those with some coordinate pts[3*p + a] < lo[a] or
 * > hi[a] (a point on a face or edge of the box is inside: not clamped).  Same
 * results as shl_grid_interp, bit for bit; the count does not depend on nthreads;
 * nothing is written on error.
 */
int shl_grid_interp_clamped(const shl_grid *grid, int method, double taylor_b, int npts, const double *pts,
                            double *rgb, int nthreads, int *nclamped);
/**
 * shl_grid_interp for float consumers (shaders), on float grids: float points
 * pts[3*p .. 3*p+2] (finite) into float rgb + 3*nc*p, summed in float by the SIMD
 * kernel of the grid's context (8 coefficients per AVX2 vector, 16 per AVX-512, 4
 * per NEON; SHLIGHT_ISA=scalar: the plain C reference).  The cell and weights are
 * those of shl_grid_interp at the point (x, y, z widened to double), formed in
 * double and rounded to float once (Hermite: multiplied out into one weight per
 * corner row).  Error model (README "Grid interpolation"): every output is within
 * gamma_n L M of the exact interpolant, gamma_n = n 2^-24 / (1 - n 2^-24), where
 * M is the largest |value| and |gradient_a| h[a] among the 8 corner entries it
 * reads and n, L = 9, 1 (trilinear), 18, 4 (Taylor), 18, 1.75 (Hermite): about
 * 4.5, 36 and 15.8 FLT_EPSILON M (plus at most 2^-45 M + 2^-144 from float
 * underflow).  So trilinear can leave its corners' range by that much; a point on
 * a node gets the node's value exactly; results are finite when L M (1 + gamma_n)
 * <= FLT_MAX.  Same clamping, same taylor_b and nthreads rules as shl_grid_interp;
 * results do not depend on nthreads.  Errors before anything is written: those of
 * shl_grid_interp (SHL_ENULL, SHL_EDOMAIN, SHL_ENONFINITE for a non-finite
 * coordinate or taylor_b); SHL_EDOMAIN for a double grid (use shl_grid_interp)
 * and, for Taylor and Hermite, whose weights carry the spacing, for a grid with
 * some spacing h[a] outside [2^-100, 2^127]; SHL_ETHREAD as shl_grid_interp.
 */
int shl_grid_interp_f(const shl_grid *grid, int method, double taylor_b, int npts, const float *pts, float *rgb,
                      int nthreads);

/* ---- adaptive multi-level SH grids (beyond Wu 2020 Sec. 7.3; issue 19) ---- */
/**
 * An adaptive grid over the box [lo, hi]: a coarse uniform grid of res[0] x res[1]
 * x res[2] nodes (level 0, as shl_grid) and finer levels l = 1, 2, ... (spacing
 * h_0 / 2^l) where an a-posteriori error estimate exceeds a tolerance; float nodes
 * (coefficients and gradients, layouts of shl_lights_eval) filled through the float
 * SIMD light-set batch; interpolated with Wu 2020 Alg. 4 (tricubic Hermite) per level.
 *
 * Refinement (shl_agrid_fill): every cell of level 0, and the children of refined
 * cells when they come up for refinement (below), get the estimate
 *   e = max over its two samples s = lo + (c + q) h_l, q = (1/4, 1/4, 1/4) and (3/4, 3/4, 3/4),
 *       and over the colours, of || A(s) - L(s) ||_2 over the nc coefficients,
 * A the adaptive interpolant built so far and L the light set by the float batch
 * (|| ||_2 of an SH vector is the L2 norm of its function on the sphere).  The two
 * samples are points of no symmetry of the cell: the leading error term of Alg. 4 is
 * odd in some axes (the gradients carried linearly) and vanishes at the centre and
 * at every node of level l + 1.  The criterion compares with tol either e
 * (SHL_AGRID_MAX: a pointwise target) or e 8^-l, the estimate times the cell's
 * volume in coarse-cell units (SHL_AGRID_MEAN: equal shares of the mean error, as
 * an image's mean absolute error weighs it; near a discontinuity, such as a
 * two-sided light in the box, e stays ~|L| at every level and MAX refines to the
 * budget or the finest level, MEAN to about log_8(|L| / tol) levels).  Cells whose
 * criterion value exceeds tol are refined while the total node count stays
 * <= max_nodes (ring included, below), best first over all levels: by priority
 * p = e 8^-l (the estimate times the cell's volume: its share of the mean error,
 * for both criteria; the receivers' share instead of the volume if receivers are
 * set, shl_agrid_set_receivers), in rounds that each take the entries within a factor 2 of
 * the largest priority waiting.  A refined cell's children wait unestimated, as one
 * entry with the bounds that the assumption below gives (e_child <= e, so priority
 * <= p / 8 and, for SHL_AGRID_MEAN, criterion <= e 8^-l / 8: dropped if that is
 * <= tol); when that entry is taken they are estimated and those above tol queued.
 * The fill stops when nothing above tol waits or the budget refuses the next
 * refinement: a tight budget goes where it lowers the mean error most, and children
 * whose bound never reaches the head cost no estimate.  Cells on the finest level
 * allowed are not estimated (no refinement can follow).  Assuming that refinement
 * does not increase e, some cells keep a verdict instead of being estimated (and are
 * never refined): the ring cells of level l >= 1 (below; each lies in an unrefined
 * level-(l-1) cell, criterion within tol) and the children dropped above.
 * An a-posteriori estimate is a measurement at two points per cell, not a bound:
 * the error elsewhere in a cell may exceed it (tests/test_agrid.c measures the
 * ratio at random points), and a feature smaller than a cell (a light's edge, a
 * small sphere) can fall between the samples of every cell of a level.
 *
 * Continuity: the interpolant is C0 everywhere in the box (to rounding).  Level l
 * alone, I_l, is Alg. 4 on its cells, C0 across their faces (on a face it depends
 * only on the face's 4 nodes).  The levels are blended as
 *   A_0 = I_0,   A_l = w_l I_l + (1 - w_l) A_{l-1},
 * w_l the trilinear interpolant on the level-l lattice of 1 at the level-l nodes in
 * (or on) refined level-(l-1) cells and 0 at the others: continuous, 1 on the
 * refined cells, 0 on the boundary of level l's cells (which are the refined cells'
 * children and a ring of one level-l cell around them).  So A is C0 but not C1
 * across the ring, where it is a convex blend of two levels (its error there is at
 * most the larger of theirs).  A point with w_l = 1 at its finest level costs one
 * Alg. 4 evaluation; in a ring, one per level blended.
 */
typedef struct shl_agrid shl_agrid;

/** Largest number of levels (level 0 included). */
#define SHL_AGRID_LEVELS_MAX 8
#define SHL_AGRID_MAX  0 /* refinement criterion: estimate e > tol */
#define SHL_AGRID_MEAN 1 /* refinement criterion: e 8^-l > tol on level l */

/** State of an adaptive grid (shl_agrid_get_stats). */
typedef struct {
    long nodes;          /* nodes over all levels (<= max_nodes) */
    long cells;          /* cells over all levels */
    long long bytes;     /* memory held: node data, cell records, hash tables */
    int levels;          /* levels built, 1 = the coarse grid only */
    long samples;        /* estimate samples of the last fill (2 per cell estimated) */
    long unresolved;     /* cells estimated > tol and left unrefined (budget hit); -1: unknown,
                            cells on the finest level allowed, or children still waiting when
                            the budget stopped the fill, were not estimated; 0: every sample
                            of the last fill within tol */
    double max_estimate; /* largest criterion value (e or e 8^-l) of an estimated cell left unrefined
                            (0 before any fill) */
    int budget_hit;      /* 1 if the node budget stopped a refinement */
} shl_agrid_stats;

/**
 * Create an adaptive grid for bands 0..shl_ctx_lmax(ctx), level 0 zero-filled.
 * lo, hi, res as shl_grid_create (else SHL_EDOMAIN, SHL_ENONFINITE); criterion
 * SHL_AGRID_MAX or SHL_AGRID_MEAN (else SHL_EDOMAIN); tol finite
 * (SHL_ENONFINITE) and > 0 (SHL_EDOMAIN), in the units of the coefficients (see the
 * estimate above); max_nodes >= res[0] res[1] res[2] and <= 2^31 - 1 (SHL_EDOMAIN).
 * The box must allow the float fill of shl_grid_fill on level 0 (every axis
 * max(|lo[a]|, |hi[a]|) <= 2^126, h[a] >= 2^-10 max(|lo[a]|, |hi[a]|) and
 * >= 2^-100; else SHL_EDOMAIN); finer levels are used while their spacing still
 * does, up to SHL_AGRID_LEVELS_MAX.  On failure *out = NULL (if out != NULL).
 */
int shl_agrid_create(const shl_ctx *ctx, const double lo[3], const double hi[3], const int res[3], int criterion,
                     double tol, long max_nodes, shl_agrid **out);
/** Destroy an adaptive grid (NULL is accepted and ignored). */
void shl_agrid_destroy(shl_agrid *grid);
/**
 * Rebuild the grid from the light set: level 0's nodes, then level by level the
 * estimate, the refinement and the new level's nodes (each node, bit for bit,
 * shl_lights_eval_batch_f at its position rounded to float, as in shl_grid_fill),
 * on 1 <= nthreads <= SHL_MAX_THREADS threads (else SHL_EDOMAIN); the result does
 * not depend on nthreads, bit for bit.  Errors (SHL_ENULL, SHL_ENOMEM, SHL_ETHREAD)
 * leave the grid unchanged.  Cost: one light-set evaluation with gradients per node
 * and two without per cell estimated (stats.samples counts the latter).
 */
int shl_agrid_fill(shl_agrid *grid, const shl_lights *lights, int nthreads);
/**
 * The adaptive interpolant A (above) at npts >= 0 points pts[3*p .. 3*p+2] into
 * rgb + 3*nc*p (layout of shl_lights_eval); points outside the box are clamped to
 * it as in shl_grid_interp.  One point: npts = 1, nthreads = 1 (no thread, no
 * allocation).  Sums in double over float nodes, with the context's interpolation
 * kernel (shl_grid_interp).  Errors before anything is written: NULL pointers
 * (SHL_ENULL; pts and rgb may be NULL when npts = 0), npts < 0 or nthreads outside
 * 1..SHL_MAX_THREADS (SHL_EDOMAIN), a non-finite point (SHL_ENONFINITE);
 * SHL_ETHREAD as shl_grid_interp.  Results do not depend on nthreads.  Reads only.
 */
int shl_agrid_interp(const shl_agrid *grid, int npts, const double *pts, double *rgb, int nthreads);
/** Node count, bytes, levels and the last fill's estimate summary (shl_agrid_stats). */
int shl_agrid_get_stats(const shl_agrid *grid, shl_agrid_stats *stats);
/**
 * Optional receivers: the npts >= 0 points pts[3*p .. 3*p+2] the grid will be
 * interpolated at (e.g. a scene's mesh vertices), for the next fills; npts = 0
 * removes them (pts may then be NULL).  With receivers, the weight of a cell of
 * level l in the refinement (above) is the fraction of the receivers it holds,
 * instead of its volume 8^-l: priority p = e n_cell / n, the SHL_AGRID_MEAN
 * criterion e n_cell / n (the cell's share of the mean error over the receivers),
 * pending children bounded by e max_j n_child_j / n; a cell holding no receiver
 * is never estimated nor refined (it keeps level 0's, or its ring's, data); the
 * estimate's two samples are the cell's receivers at 1/4 and 3/4 of its list (in
 * Morton order of their finest-level cells), rounded to float, instead of the
 * fixed points (the error where the grid is used, not off the surfaces).  A
 * receiver belongs to the half-open cells containing it, points outside the box
 * to those their clamped position falls in (as shl_agrid_interp clamps); the grid
 * keeps a copy (a key, the float point and its weight, and a prefix sum: 32 bytes per
 * receiver, in stats.bytes).  Errors
 * leave the grid unchanged: SHL_ENULL (grid, or pts with npts > 0), SHL_EDOMAIN
 * (npts < 0), SHL_ENONFINITE, SHL_ENOMEM.
 */
int shl_agrid_set_receivers(shl_agrid *grid, int npts, const double *pts);
/**
 * shl_agrid_set_receivers with a weight >= 0 per receiver (weights[p], NULL: all 1,
 * which is shl_agrid_set_receivers bit for bit): a cell's weight is the share of the
 * receivers' total weight it holds (the priority p = e W_cell / W, the SHL_AGRID_MEAN
 * criterion e W_cell / W: its share of the weighted mean error), and the estimate's
 * two samples are the cell's receivers at 1/4 and 3/4 of its cumulative weight (in
 * the same Morton order).  For an image's mean absolute error, the weight of a mesh
 * vertex is the sum over the pixels showing it of its barycentric weight there (the
 * image is linear in the vertex values with those weights).  Receivers of weight 0
 * are dropped (a cell holding only those is never refined); weights are stored as
 * float (32 bytes per receiver kept, with a double prefix sum, in stats.bytes).
 * Errors leave the grid unchanged: those of shl_agrid_set_receivers, and a
 * non-finite weight (SHL_ENONFINITE), a weight < 0 or > 2^100, or npts > 0 with
 * every weight 0 (SHL_EDOMAIN).
 */
int shl_agrid_set_weighted_receivers(shl_agrid *grid, int npts, const double *pts, const double *weights);

/* ---- spherical lights (Mezieres et al. 2022, "HVL", Sec. 4.2) ---------- */
/**
 * SH projection of a uniform, unit-radiance sphere seen from x:
 *   coeffs[l*(l+1)+m] = integral over the cap of directions subtended by the
 *   sphere (center, radius) at x of Y_lm(w) dw,   l <= shl_ctx_lmax(ctx).
 * The cap has half-angle a, sin a = radius / |center - x|.  Its ZH coefficients
 * (HVL Eq. 14) are evaluated in a form without cancellation, so tiny or distant
 * spheres keep full relative accuracy, then rotated to the axis (Eq. 15).
 * A point inside or on the sphere (|center - x| <= radius) is surrounded by it:
 * coeffs[0] = sqrt(4 pi) and every other coefficient is 0.
 * radius must be finite (SHL_ENONFINITE) and > 0 (SHL_EDOMAIN).
 */
int shl_sphere(const shl_ctx *ctx, const double x[3], const double center[3], double radius,
               double *coeffs);
/** Float version: the geometry is set up in double, the band recurrences run in float. */
int shl_sphere_f(const shl_ctx *ctx, const float x[3], const float center[3], float radius,
                 float *coeffs);
/**
 * Coefficients (as shl_sphere) and their gradient with respect to the shading
 * point: grad[a*nc + k] = d coeffs[k] / d x[a], a = 0,1,2, nc = SHL_NCOEFFS(lmax);
 * grad has 3*nc entries.  Outside the sphere the gradient is analytic; it grows
 * like 1/sqrt(|center - x| - radius) as x approaches the surface.  Inside or on
 * the sphere the coefficients are constant and grad is 0.
 */
int shl_sphere_grad(const shl_ctx *ctx, const double x[3], const double center[3], double radius,
                    double *coeffs, double *grad);
int shl_sphere_grad_f(const shl_ctx *ctx, const float x[3], const float center[3], float radius,
                      float *coeffs, float *grad);

/* ---- second derivatives (Hessians) -------------------------------------- */
/**
 * Coefficients, gradient (layouts of shl_polygon_grad / shl_sphere_grad) and the six
 * second derivatives hess[i*nc + k] = d^2 coeffs[k] / dx_a dx_b, i = 0..5 for
 * (a,b) = xx, xy, xz, yy, yz, zz (hess has 6*nc entries), derived analytically:
 * the polygon's boundary formulation (Wu et al. 2020 gradients) extended one order,
 * the sphere's cap w_l(cos a) Y_lm(axis) differentiated twice through its lobe
 * integrals (derivation in README, "Hessians").  Same validation and statuses as
 * the gradient functions (all pointers required); nothing is written on error.
 * Polygon: the Hessian grows like 1/distance^2 near an edge (rounding error ~eps times
 * that growth, as the gradient's); in the polygon's plane coeffs, grad and hess are 0 (not
 * differentiable there); near the plane the Hessian is taken from the boundary sums (error
 * ~eps dmin / height of its scale) while the coefficients use shl_polygon's planar rule;
 * edges seen nearly end-on (x much closer to an edge's line than to the edge) take their
 * new edge integrals from a Gauss rule on the arc, so no (distance ratio)^2 loss there.
 * Sphere: analytic outside, growing like (|center - x| - radius)^(-3/2) towards the
 * surface; inside or on it the coefficients are constant and grad, hess are 0.
 */
int shl_polygon_hess(const shl_ctx *ctx, const double x[3], const double *verts, int n,
                     double *coeffs, double *grad, double *hess);
int shl_sphere_hess(const shl_ctx *ctx, const double x[3], const double center[3], double radius,
                    double *coeffs, double *grad, double *hess);
/**
 * shl_lights_eval with second derivatives: rgb and grad as there (grad required here),
 *   hess[(c*6 + i)*nc + k] = d^2 rgb[c*nc + k] / dx_a dx_b,  i as in shl_polygon_hess  (18*nc entries).
 * Each light adds rgb_c times its shl_polygon_hess / shl_sphere_hess values (to
 * rounding: the set reconstructs its summed lobe integrals once); a one-sided
 * polygon adds nothing on or behind its plane.  A workspace is allocated per call
 * (SHL_ENOMEM).
 */
int shl_lights_eval_hess(const shl_ctx *ctx, const shl_lights *lights, const double x[3], double *rgb,
                         double *grad, double *hess);

/* ---- zonal harmonics (ZH) and SH operations ----------------------------- */
/*
 * A ZH vector zh[0..lmax] (lmax+1 entries) describes a function circularly
 * symmetric about an axis u:  f(w) = sum_l zh[l] K_l P_l(u . w),
 * K_l = sqrt((2l+1)/(4 pi)), i.e. zh[l] is the coefficient of Y_l0 in a frame
 * whose z axis is u.  SH vectors have SHL_NCOEFFS(lmax) entries.
 */

/** ZH of the indicator of the cap {w : u . w >= cos a}, 0 <= half_angle a <= pi
 *  (HVL Eq. 14), with full relative accuracy for small a. */
int shl_zh_cap(int lmax, double half_angle, double *zh);

/** SH coefficients of the ZH function zh about axis (HVL Eq. 15):
 *  sh[l*(l+1)+m] = sqrt(4 pi/(2l+1)) zh[l] Y_lm(axis/|axis|); axis finite, non-zero. */
int shl_zh_to_sh(int lmax, const double *zh, const double axis[3], double *sh);

/**
 * Rotate an SH vector: out describes g(w) = f(R^T w), f described by in (a lobe
 * of f at direction v moves to R v; rotating by R1 then by R2 equals rotating by
 * R2 R1).  rot: row-major 3x3 orthogonal matrix, max |R R^T - I| <= 1e-6
 * (SHL_EDOMAIN otherwise); det = -1 (a reflection) is allowed.  O(lmax^3)
 * (Ivanic-Ruedenberg recurrences); out may equal in.  Allocates
 * 8 (lmax+1)(2 lmax+1)(2 lmax+3)/3 bytes (SHL_ENOMEM).
 */
int shl_sh_rotate(int lmax, const double rot[9], const double *in, double *out);

/** *value = sum_k coeffs[k] Y_k(dir) (HVL Eq. 6); dir finite, non-zero. */
int shl_sh_eval(int lmax, const double *coeffs, const double dir[3], double *value);

/**
 * Convolution with a circularly symmetric kernel k(w . n) given by its ZH:
 * out describes g(n) = integral f(w) k(w . n) dw, f described by sh:
 *   out[l*(l+1)+m] = sqrt(4 pi/(2l+1)) kernel_zh[l] sh[l*(l+1)+m].
 * O(lmax^2); out may equal sh.
 */
int shl_sh_convolve(int lmax, const double *sh, const double *kernel_zh, double *out);

/**
 * The same convolution when f is circularly symmetric too (ZH zh about axis u),
 * evaluated at n in O(lmax) (HVL Sec. 6.3):
 *   *value = integral f(w) k(w . n) dw = sum_l zh[l] kernel_zh[l] P_l(cos_angle),
 * cos_angle = u . n, |cos_angle| <= 1 (SHL_EDOMAIN).  With the clamped cosine
 * and lmax = 2 this is the 2x2 irradiance form of HVL App. B.
 */
int shl_zh_convolve(int lmax, const double *zh, const double *kernel_zh, double cos_angle,
                    double *value);

/** Kernel k(t) = max(t, 0): convolving radiance with it gives irradiance. */
int shl_zh_clamped_cosine(int lmax, double *zh);
/** Normalized Phong lobe k(t) = (n+1)/(2 pi) max(t, 0)^n (integral 1), any real
 *  0 <= n <= 1e6; exact (ratio recurrence, no quadrature). */
int shl_zh_phong(int lmax, double exponent, double *zh);
/**
 * GGX lobe: the density of mirror directions of GGX microfacets at normal
 * incidence, k(t) = D(h)/4 with cos^2 theta_h = (1+t)/2 and
 * D = alpha^2 / (pi (cos^2 theta_h (alpha^2 - 1) + 1)^2) (integral 1): the usual
 * circularly symmetric stand-in for a GGX specular lobe about the mirror
 * direction.  1e-3 <= alpha <= 1.  Projected by Gauss-Legendre quadrature on
 * panels graded towards the peak (relative accuracy ~1e-14).
 */
int shl_zh_ggx(int lmax, double alpha, double *zh);

/* ---- Irradiance ------------------------------------------------------------ */
/**
 * Exact unshadowed irradiance at x, surface normal `normal` (any finite, non-zero
 * length; SHL_EDOMAIN if zero), from a unit-radiance polygon (verts, n as for
 * shl_polygon: either winding, repeated vertices dropped):
 *   *irradiance = integral over the polygon's solid angle at x of max(0, n . w) dw  (>= 0).
 * The polygon is clipped to the half-space n . (p - x) >= 0 (Sutherland-Hodgman against
 * the tangent plane at x), then Lambert's formula E = 1/2 sum_e gamma_e (n . u_e)
 * (gamma_e: the edge's angle seen from x, u_e: unit normal of the plane through x and
 * the edge).  A polygon entirely on or below the horizon gives exactly 0, as does a
 * point in the polygon's plane.  E <= pi (to rounding); multiply by the radiance for a
 * coloured light (outgoing Lambertian radiance: albedo / pi * E).
 * Accuracy: a clipped polygon whose size is below 1/16 of its distance is integrated
 * over its plane by a 25-point Gauss rule per fan triangle (relative error ~1e-18 from
 * the rule, plus rounding), so tiny polygons keep full relative accuracy; larger ones
 * use Lambert's sum, whose terms cancel by at most a factor ~ tan(angle(n, polygon)) /
 * size in radians (<= 16 tan(...)); tests measure <= 5e-15 relative (sizes 1e-12..1,
 * tilts <= 80 degrees).  Where the polygon crosses the horizon the clip line's position
 * is known to ~eps x distance, so the relative error is ~eps x distance / size (tests:
 * <= 19 eps / size).
 */
int shl_polygon_irradiance(const double x[3], const double normal[3], const double *verts, int n,
                           double *irradiance);

/**
 * Irradiance from SH radiance (Funk-Hecke with the clamped cosine; Ramamoorthi &
 * Hanrahan 2001):  *irradiance = sum_l A_l sum_m coeffs[l*(l+1)+m] Y_lm(n/|n|),
 * A_l = 2 pi int_0^1 P_l(t) t dt = sqrt(4 pi/(2l+1)) zh_l of shl_zh_clamped_cosine
 * (pi, 2 pi/3, pi/4, 0, -pi/24, 0, pi/64, ...; 0 for odd l >= 3).  coeffs has
 * SHL_NCOEFFS(lmax) finite entries; normal finite, non-zero (SHL_EDOMAIN).  With
 * shl_polygon's coefficients the truncation error is at most
 * sum_{l > lmax} |A_l| (2l+1)/(4 pi) x solid angle (|A_l| ~ l^(-5/2)); it can make the
 * result negative (ringing: see shl_sh_window).
 */
int shl_sh_irradiance(int lmax, const double *coeffs, const double normal[3], double *irradiance);
/** The three channels of an RGB SH vector in the layout of shl_lights_eval
 *  (rgb[c*nc + k], 3*nc finite entries, nc = SHL_NCOEFFS(lmax)): irradiance[c] equals
 *  shl_sh_irradiance(lmax, rgb + c*nc, normal, ..) bit for bit; the basis is evaluated once. */
int shl_sh_irradiance_rgb(int lmax, const double *rgb, const double normal[3], double irradiance[3]);

/*
 * Ringing control: SH windowing multiplies band l by a factor h_l (h_0 = 1, the
 * function's mean is kept), trading sharpness for smaller negative lobes.
 *  - SHL_WINDOW_HANNING, param = width w > 0:
 *      h_l = (1 + cos(pi l / w)) / 2 for l < w, 0 for l >= w;
 *  - SHL_WINDOW_LANCZOS, param = width w > 0 (Lanczos sigma factors):
 *      h_l = sin(pi l / w) / (pi l / w) for 0 < l < w, h_0 = 1, 0 for l >= w;
 *    for both, w = lmax + 1 is the usual choice (every band kept, the last one damped most);
 *  - SHL_WINDOW_LAPLACIAN, param = lambda >= 0 (Sloan 2008, "Stupid Spherical Harmonics
 *    Tricks", windowing): h_l = 1 / (1 + lambda l^2 (l+1)^2), the minimizer g of
 *    ||g - f||^2 + lambda ||Laplacian g||^2 (Y_lm is an eigenfunction of the
 *    Laplacian with eigenvalue -l(l+1)); lambda = 0 keeps f;
 *  - SHL_WINDOW_POUSSIN, param = integer degree 0 <= p <= SHL_LMAX_MAX (spherical de la
 *    Vallee Poussin kernel): h_l = p! (p+1)! / ((p-l)! (p+l+1)!) for l <= p, 0 beyond;
 *    the window is the convolution with the non-negative zonal kernel ((1 + w.n)/2)^p,
 *    which has bands 0..p only, so for p <= lmax a non-negative function keeps a
 *    non-negative windowed SH vector and non-negative shl_sh_irradiance: ringing is
 *    removed exactly, at the price of a blur of ~2/sqrt(p) radians (use p = lmax).
 * param must be finite (SHL_ENONFINITE) and in its domain (SHL_EDOMAIN), window one of
 * the four (SHL_EDOMAIN).
 * Windows shrink the negative lobes of SH *radiance* (a truncated delta: tests).  SH
 * irradiance rings for another reason: the clamped cosine truncated at lmax has a negative
 * lobe itself (min of its kernel: -0.040 at lmax 2, -0.0098 at lmax 10).  Windowing the
 * radiance makes that kernel non-negative (so every non-negative radiance gives E >= 0)
 * only with heavy damping (Laplacian lambda >= ~0.18 at every lmax; Hanning or Lanczos
 * width <= ~2) or with SHL_WINDOW_POUSSIN: bench/bench_ringing.c measures the
 * trade-off; clamping max(0, E) costs less accuracy there.
 */
#define SHL_WINDOW_HANNING   1
#define SHL_WINDOW_LANCZOS   2
#define SHL_WINDOW_LAPLACIAN 3
#define SHL_WINDOW_POUSSIN   4
/** The factors h[0..lmax] (lmax + 1 entries) of a window. */
int shl_sh_window_factors(int lmax, int window, double param, double *h);
/** Window an SH vector in place: coeffs[l*(l+1)+m] *= h_l, SHL_NCOEFFS(lmax) entries
 *  (finite: SHL_ENONFINITE, then nothing is written). */
int shl_sh_window(int lmax, int window, double param, double *coeffs);

/* ---- isotropic BRDF SH tables (HVL Sec. 4.2, Eq. 16-18) -------------------- */
#define SHL_BRDF_GGX   1 /* kd/pi + ks D G2 F / (4 cos_i cos_o): GGX D, height-correlated
                            Smith G2, Schlick Fresnel F with reflectance f0 */
#define SHL_BRDF_PHONG 2 /* kd/pi + ks (n+2)/(2 pi) max(0, r . wi)^n, r = mirror of wo */

/** Parametric isotropic BRDF (local frame: z = normal). */
typedef struct {
    int model;       /* SHL_BRDF_GGX or SHL_BRDF_PHONG                      */
    double kd;       /* diffuse albedo, >= 0                                */
    double ks;       /* specular weight, >= 0                               */
    double alpha;    /* GGX roughness, 1e-3 <= alpha <= 1 (GGX only)        */
    double f0;       /* GGX Fresnel reflectance at normal incidence, 0..1   */
    double exponent; /* Phong exponent, 0 <= n <= 1e6 (Phong only)          */
} shl_brdf;

/** *value = f_s(wi, wo) in the local frame (z = normal; wi, wo finite, non-zero,
 *  normalized here); 0 unless both are strictly above the horizon. */
int shl_brdf_eval(const shl_brdf *brdf, const double wi[3], const double wo[3], double *value);

/** Opaque table of BRDF SH projections; immutable after creation, share freely. */
typedef struct shl_brdf_table shl_brdf_table;

/**
 * Tabulate, for the ntheta outgoing angles theta_j = j (pi/2) / ntheta
 * (j = 0..ntheta-1; one degree apart for the paper's ntheta = 90) and phi_o = 0
 * (Eq. 17-18), the SH projections over wi (local frame) of
 *   F  = cos(theta_i) f_s(wi, wo)  (Eq. 16)   and   F' = f_s(wi, wo),
 * bands 0..lmax.  2 <= ntheta <= 1024 (SHL_EDOMAIN).  By the symmetry of an
 * isotropic BRDF the m < 0 coefficients are 0.  Quadrature in a frame about the
 * mirror direction (Gauss-Legendre panels graded towards the lobe, horizon
 * clipped exactly), then an SH rotation.  Stores 16 ntheta (lmax+1)^2 bytes.
 * On failure *out = NULL (if out != NULL).
 */
int shl_brdf_table_create(int lmax, const shl_brdf *brdf, int ntheta, shl_brdf_table **out);
/** Destroy a table (NULL is accepted and ignored). */
void shl_brdf_table_destroy(shl_brdf_table *table);
/** Highest band of the table, or SHL_ENULL. */
int shl_brdf_table_lmax(const shl_brdf_table *table);

/**
 * Local shading frame of HVL Sec. 4.2 (phi_o = 0): rows of frame (row-major 3x3)
 * are the local x, y, z axes in world coordinates: z = n/|n|, x = the part of wo
 * orthogonal to n, normalized (any unit vector orthogonal to n if wo is parallel
 * to n), y = z cross x.  A world direction v has local coordinates frame v.
 * n and wo finite and non-zero.
 */
int shl_brdf_frame(const double n[3], const double wo[3], double frame[9]);

/**
 * F and F' for the outgoing direction wo at a point of normal n, in the local
 * frame (written to frame, as shl_brdf_frame): the frame change of HVL Sec. 4.2
 * replaces an SH rotation (express the light in the frame, e.g. with
 * shl_zh_to_sh(.., frame * axis, ..), then dot with F).  theta_o = angle(n, wo);
 * linear interpolation between the tabulated angles, the last one held up to
 * pi/2; wo at or below the horizon gives zero vectors.  f_cos (F) and f (F')
 * have SHL_NCOEFFS(lmax) entries; either may be NULL.
 */
int shl_brdf_table_lookup(const shl_brdf_table *table, const double n[3], const double wo[3],
                          double frame[9], double *f_cos, double *f);

/* ---- Harmonics Virtual Lights (HVL Sec. 5) --------------------------------- */
/** One HVL: a spherical secondary light on a surface, lit by a primary light. */
typedef struct {
    double pos[3];      /* y_j: centre                                            */
    double normal[3];   /* n_j: normal of the surface at y_j (non-zero)            */
    double to_light[3]; /* w_l: direction from y_j to the primary light (non-zero) */
    double radius;      /* r_j > 0                                                 */
    double power;       /* Phi_j, finite                                           */
    const shl_brdf_table *brdf; /* material at y_j: F' gives the emission (Eq. 20)  */
} shl_hvl;

/**
 * Overlap factor H of HVL Eq. 22: smoothstep approximation (Oat & Sander 2007)
 * of the fraction of a cap of half-angle a (0 <= a <= pi/2) whose axis makes
 * the angle acos(cos_theta) with the normal that lies above the horizon:
 *   H = S((a + pi/2 - clamp(theta, pi/2 - a, pi/2 + a)) / (2a)),  S(x) = 3x^2 - 2x^3.
 * (The paper prints the lower clamp bound as a - pi/2; pi/2 - a is the bound
 * that keeps the argument of S in [0, 1].)  Evaluated as S((a + asin(cos_theta)) / (2a))
 * (pi/2 - theta = asin(cos_theta): no cancellation for small a), within 1e-12 (in
 * fact ~5e-16) of S at the exact argument, monotone non-decreasing in cos_theta,
 * in [0, 1]; exactly 1 when the cap is entirely above the horizon
 * (asin(cos_theta) >= a) and exactly 0 when entirely below, whatever a.  a = 0
 * (a point): 1 for cos_theta > 0, 0 for cos_theta < 0, 1/2 for cos_theta = +-0 (the
 * limit a -> 0, as H = 1/2 at cos_theta = 0 for every a).  Errors (nothing
 * written): SHL_ENULL, SHL_ENONFINITE, SHL_EDOMAIN for |cos_theta| > 1 or a outside
 * [0, pi/2] (pi/2 as the double 0.5 * M_PI).
 */
int shl_hvl_overlap(double cos_theta, double half_angle, double *h);

/**
 * Radiance leaving x (normal n, material table) towards wo, summed over the
 * HVLs (HVL Eq. 1, 19-22):  sum_j L_j * (L . F), with L the SH vector of the cap
 * subtended by HVL j at x (in the local frame of x, bands of material), F the
 * material's F at wo, and L_j = Phi_j (F'_j . Y(-w_j)) G_j (Eq. 20), F'_j the
 * HVL's own table looked up with its normal and w_l, evaluated towards x, and
 * G_j = max(0, n_j . -w_j) H(n . w_j, a_j) / (pi r_j^2) (Eq. 21).  The emission
 * is not clamped (SH ringing can make it negative, as in the paper).  When x is
 * inside or on an HVL's sphere its cap is clamped to the hemisphere about w_j
 * (the limit from outside); an HVL centred exactly at x contributes 0.
 * count >= 0 (hvls may be NULL when count is 0).
 */
int shl_hvl_shade(const shl_hvl *hvls, int count, const double x[3], const double n[3],
                  const double wo[3], const shl_brdf_table *material, double *radiance);

/**
 * Radius heuristic 1 (HVL Eq. 23) for the width x height HVLs of a reflective
 * shadow map (row-major; pos 3 doubles per HVL, dist = distance to the primary
 * light): radius[i] = scale * sum_n w_n |p_i - p_n| / sum_n w_n over the
 * 8-connected neighbours n, w_n = 1 / (|d_i - d_n| + eps).  eps > 0, scale > 0,
 * width, height >= 1, width * height >= 2.
 */
int shl_hvl_radius_grid(int width, int height, const double *pos, const double *dist, double eps,
                        double scale, double *radius);

/**
 * Radius heuristic 2 (HVL Eq. 24, 26) for count HVLs distributed by a square
 * RSM of full field-of-view angle fov (0 < fov < pi):
 * gamma = sqrt(2) fov / sqrt(count), radius[i] = scale * dist[i] (gamma + gamma^3/3)
 * (the Taylor form of dist tan gamma, Eq. 25; within 0.01 dist for gamma <= 0.58).
 * dist[i] >= 0, scale > 0, count >= 1.
 */
int shl_hvl_radius_fov(int count, const double *dist, double fov, double scale, double *radius);

/* ---- batched evaluation, SIMD dispatch ---------------------------------- */
/**
 * shl_polygon_f / shl_polygon_grad_f of one polygon at npts >= 0 points
 * pts[3*p .. 3*p+2], vectorized across points (AVX2: 8 points per vector,
 * NEON: 4):  point p writes coeffs + nc*p (nc entries) and, if grad != NULL,
 * grad + 3*nc*p (3*nc entries, layout of shl_polygon_grad_f), nc = SHL_NCOEFFS(lmax).
 * Same semantics as the single-point calls (either winding, repeated vertices
 * dropped, a point in the polygon's plane gets zeros, by the same test in
 * double); a point farther than 2^40 times the polygon's extent gets zeros
 * (float range).  Accuracy is that of float arithmetic on the whole geometry:
 * see README "Batch evaluation and SIMD" (the error relative to L00 grows like
 * 1/angular size); points from which the polygon's perimeter is below 1/32 of
 * the distance (a square under 1/128 rad) or which lie very close to its plane
 * take the scalar path of shl_polygon_grad_f, so small lights keep ~1e-7 of the
 * solid angle.  pts and coeffs may be NULL when npts is 0.
 * All points are checked before anything is written.  Allocates one workspace
 * per call of 4 vlen (3 nq (lmax+1)^2 + 14 lmax + 1825) + 64 bytes, nq = 4 with
 * gradients, 1 without (AVX2, lmax 30, gradients: 441 KB; SHL_ENOMEM);
 * npts < 0: SHL_EDOMAIN.
 */
int shl_polygon_batch_f(const shl_ctx *ctx, const float *verts, int n, int npts, const float *pts,
                        float *coeffs, float *grad);

/**
 * shl_sphere_f / shl_sphere_grad_f of one sphere (center, radius) at npts >= 0
 * points pts[3*p .. 3*p+2], vectorized across points (AVX2: 8 per vector,
 * NEON: 4): point p writes coeffs + nc*p (nc entries) and, if grad != NULL,
 * grad + 3*nc*p (3*nc entries, grad[a*nc + k] = d coeffs[k] / d x[a]).  Same
 * semantics as the single-point calls: each point's cap is set up in double,
 * the band recurrences run in float; a point inside or on the sphere gets
 * coeffs[0] = sqrt(4 pi), 0 elsewhere and a zero gradient.  Coefficients are
 * always finite; the gradient grows like 1/sqrt(|center - x| - radius) near
 * the surface and overflows float only where shl_sphere_grad_f does (distances
 * below ~1e-38).  Accuracy: README "Batch evaluation and SIMD".  pts and coeffs
 * may be NULL when npts is 0.  Errors, before anything is written: NULL
 * pointers (SHL_ENULL), npts < 0 or radius <= 0 (SHL_EDOMAIN), a non-finite
 * center, radius or point (SHL_ENONFINITE); allocates one workspace per call
 * of 4 (vlen (q nc + 10) + 3 nc) + 64 bytes, q = 4 with gradients, 1 without
 * (AVX2, lmax 30, gradients: 135 KB; SHL_ENOMEM).
 */
int shl_sphere_batch_f(const shl_ctx *ctx, const float center[3], float radius, int npts, const float *pts,
                       float *coeffs, float *grad);

/**
 * shl_lights_eval_batch in float through the batch kernels above: the light set
 * at npts >= 0 points pts[3*p .. 3*p+2]; point p writes rgb + 3*nc*p (3*nc
 * entries) and, if grad != NULL, grad + 9*nc*p (9*nc entries), layouts of
 * shl_lights_eval.  Each light is evaluated as by shl_polygon_batch_f /
 * shl_sphere_batch_f (from its double vertices, centre and radius; a one-sided
 * polygon reaches a point by the same double test as in shl_lights_eval), times
 * its rgb rounded to float, and the lights are summed in float; so each light
 * adds its own float error, scaled by |rgb| (README "Batch evaluation and SIMD").
 * Lights beyond float's normal range (a polygon coordinate above 2^126 or an
 * extent below 2^-126; a sphere centre coordinate outside 2^-126..2^126 in
 * magnitude other than 0, a radius outside 2^-126..2^126) take the scalar float
 * path (shl_polygon_grad_f, shl_sphere_grad_f: geometry in double) at every
 * point.  pts and rgb may be NULL when npts is 0; an empty set gives zeros.
 * Errors, before anything is written: NULL pointers (SHL_ENULL), npts < 0
 * (SHL_EDOMAIN), a non-finite point (SHL_ENONFINITE); allocates one workspace
 * per call (unless the set is empty) of the larger of the two kernels'
 * workspaces plus 256 (nq nc + 3) bytes, nq = 4 with gradients, 1 without
 * (SHL_ENOMEM).
 */
int shl_lights_eval_batch_f(const shl_ctx *ctx, const shl_lights *lights, int npts, const float *pts, float *rgb,
                            float *grad);

/**
 * Threaded batches: the four batch entry points above on 1 <= nthreads <=
 * SHL_MAX_THREADS threads (as shl_grid_fill: 1 runs on the calling thread and
 * creates none; the plain entry points are these with nthreads = 1).  Same
 * arguments, semantics and errors otherwise, plus nthreads outside 1..SHL_MAX_THREADS:
 * SHL_EDOMAIN, and SHL_ETHREAD if a thread cannot be created (all threads are
 * created before any work starts: nothing is written).  The points are split
 * into fixed blocks (256 points for one polygon or sphere, 64 for a light set,
 * one for the double set), each evaluated by the same calls whatever the
 * thread count: results are bit for bit independent of nthreads.  Threads are
 * used up to the number of blocks, each with its own workspace, all in one
 * allocation (the plain call's workspace, rounded up to 64 bytes, per thread;
 * SHL_ENOMEM, nothing written).  The context and the light set are only read.
 */
int shl_lights_eval_batch_mt(const shl_ctx *ctx, const shl_lights *lights, int npts, const double *pts,
                             double *rgb, double *grad, int nthreads);
int shl_lights_eval_batch_f_mt(const shl_ctx *ctx, const shl_lights *lights, int npts, const float *pts,
                               float *rgb, float *grad, int nthreads);
int shl_polygon_batch_f_mt(const shl_ctx *ctx, const float *verts, int n, int npts, const float *pts,
                           float *coeffs, float *grad, int nthreads);
int shl_sphere_batch_f_mt(const shl_ctx *ctx, const float center[3], float radius, int npts, const float *pts,
                          float *coeffs, float *grad, int nthreads);

/**
 * Instruction set of the context's batch kernels: "scalar", "avx2" (x86-64 with
 * AVX2 and FMA, YMM state enabled by the OS), "avx512" (x86-64 with AVX-512 F,
 * DQ, VL and BW besides, opmask and ZMM state enabled by the OS) or "neon"
 * (AArch64); "" for NULL.
 * Chosen at shl_ctx_create: the best one compiled in and supported, unless the
 * environment variable SHLIGHT_ISA names another compiled-in, supported one
 * (scalar | avx2 | avx512 | neon); any other value of SHLIGHT_ISA is ignored.  Or
 * given explicitly to shl_ctx_create_isa.
 */
const char *shl_ctx_isa(const shl_ctx *ctx);
/** Build description: version, compiler, flags, batch ISAs compiled in (never NULL). */
const char *shl_build_info(void);

#if defined(__GNUC__)
#pragma GCC visibility pop
#endif

#ifdef __cplusplus
}
#endif
#endif /* SHLIGHT_H */

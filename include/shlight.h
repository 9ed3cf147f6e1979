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
 *    code (shl_strerror() names it).  On error no output is written.
 *    The library never prints, never aborts, never calls exit().
 *  - Gradients use the layout grad[a*nc + k] = d coeffs[k] / d x[a],
 *    a = 0,1,2 (x, y, z), nc = SHL_NCOEFFS(lmax).
 */
#ifndef SHLIGHT_H
#define SHLIGHT_H

#ifdef __cplusplus
extern "C" {
#endif

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

/** Create a context for bands 0..lmax (0 <= lmax <= SHL_LMAX_MAX). */
int shl_ctx_create(int lmax, shl_ctx **out);
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
 */
int shl_polygon(const shl_ctx *ctx, const double x[3],
                const double *verts, int n, double *coeffs);
/** Float version: same semantics; the per-edge geometry is set up in double,
 *  the band recurrences run in float. */
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

/** Solid angle (steradians, >= 0) of the polygon seen from x; 0 in its plane. */
int shl_polygon_solid_angle(const double x[3], const double *verts, int n, double *omega);

#ifdef __cplusplus
}
#endif
#endif /* SHLIGHT_H */

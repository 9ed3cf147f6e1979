/* Light sets: internal records and the accumulation kernel shared with the grid. */
#ifndef SHL_LIGHTS_H
#define SHL_LIGHTS_H

#include "internal.h"
#include "polygon.h"

/* Kind tag of a light record; each kind has a case in light_zh() (lights.c). */
enum { SHL__LIGHT_POLYGON = 1, SHL__LIGHT_SPHERE = 2 };

typedef struct {
    int kind;
    int two_sided;     /* polygon, 0: emits only toward `normal`; sphere: 1 (emits everywhere) */
    double rgb[3];     /* radiance per colour channel */
    int n;             /* polygon: vertex count */
    size_t vofs;       /* polygon: first coordinate in shl_lights.verts */
    double normal[3];  /* polygon: Newell normal sum_i (v_i - v_0) x (v_i+1 - v_0), differences times 2^-E (internal.h) */
    double center[3];  /* sphere: centre */
    double radius;     /* sphere: radius, finite and > 0 */
} shl__light;

struct shl_lights {
    shl__light *items;
    int count, cap;
    double *verts;     /* polygon vertices, xyz interleaved */
    size_t nverts, vcap; /* doubles used / allocated */
};

/* normal . (x - v_0) of polygon light li (v_0 its first vertex), the difference
 * scaled by a power of two (internal.h): the sign of the unscaled formula
 * wherever that does not over/underflow; x receives li (one-sided) iff > 0. */
double shl__light_front_distance(const shl__light *li, const double *v0, const double x[3]);

/* The geometry of polygon light li seen from x into g; 0 (g not set) if li is
 * one-sided and x is behind it or in its plane. */
static inline int shl__light_poly_geom(const shl_lights *lights, const shl__light *li, const double x[3],
                                       shl__poly_geom *g)
{
    const double *v = lights->verts + li->vofs;
    if (!li->two_sided && !(shl__light_front_distance(li, v, x) > 0.0)) return 0;
    shl__poly_geom_init(g, x, v, li->n);
    return 1;
}

/* Doubles of workspace shl__lights_eval needs at lmax. */
size_t shl__lights_ws_size(int lmax);

/* Sum of all lights at x into rgb[3*nc] and, if grad != NULL, grad[9*nc]
 * (layouts of shl_lights_eval); inputs already validated. */
void shl__lights_eval(const shl_lights *lights, int lmax, double *ws, const double x[3],
                      double *rgb, double *grad);

/* shl__lights_eval with the second derivatives hess[(c*6 + i)*nc + k] (layout of
 * shl_lights_eval_hess; grad and hess required) and its workspace in doubles
 * (lights_hess.c); inputs already validated. */
size_t shl__lights_hess_ws_size(int lmax);
void shl__lights_eval_hess(const shl_lights *lights, int lmax, double *ws, const double x[3], double *rgb,
                           double *grad, double *hess);

/* Float light-set batch (lights_batch.c), shared with the grid fill: points go
 * in blocks of at most SHL__LIGHTS_BLOCK, each block through the same calls
 * whatever the thread count (results bit for bit independent of it). */
enum { SHL__LIGHTS_BLOCK = 64 }; /* a multiple of every vector length */

/* Bytes of one worker's buffer for shl__lights_batch_f_block (0 for an empty set). */
size_t shl__lights_batch_f_bytes(const shl_ctx *ctx, const shl_lights *lights, int with_grad);

/* The set at m <= SHL__LIGHTS_BLOCK finite float points: point j writes
 * rgb + j*rgb_stride (3 nc floats) and, if grad != NULL, grad + j*grad_stride
 * (9 nc), overwriting them; buf: shl__lights_batch_f_bytes bytes (NULL if 0). */
void shl__lights_batch_f_block(const shl_ctx *ctx, const shl_lights *lights, int m, const float *pts, float *rgb,
                               size_t rgb_stride, float *grad, size_t grad_stride, void *buf);

#endif

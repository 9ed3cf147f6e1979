/* Small inline 3-vector helpers (double) for the harness. */
#ifndef SHL_BENCH_VEC3_H
#define SHL_BENCH_VEC3_H

#include <math.h>

static inline void v3_set(double *o, double x, double y, double z) { o[0] = x; o[1] = y; o[2] = z; }
static inline void v3_sub(double *o, const double *a, const double *b) { o[0] = a[0] - b[0]; o[1] = a[1] - b[1]; o[2] = a[2] - b[2]; }
static inline void v3_add(double *o, const double *a, const double *b) { o[0] = a[0] + b[0]; o[1] = a[1] + b[1]; o[2] = a[2] + b[2]; }
static inline void v3_scale(double *o, const double *a, double s) { o[0] = a[0] * s; o[1] = a[1] * s; o[2] = a[2] * s; }
static inline void v3_madd(double *o, const double *a, const double *b, double s) /* o = a + s b */
{
    o[0] = a[0] + s * b[0]; o[1] = a[1] + s * b[1]; o[2] = a[2] + s * b[2];
}
static inline double v3_dot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static inline void v3_cross(double *o, const double *a, const double *b)
{
    const double x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2], z = a[0] * b[1] - a[1] * b[0];
    o[0] = x; o[1] = y; o[2] = z;
}
static inline double v3_len(const double *a) { return sqrt(v3_dot(a, a)); }
static inline double v3_normalize(double *a) /* returns the former length; zero vectors stay zero */
{
    const double l = v3_len(a);
    if (l > 0) v3_scale(a, a, 1.0 / l);
    return l;
}
/* An orthonormal pair (t, b) completing the unit vector n (Duff et al. 2017). */
static inline void v3_basis(const double *n, double *t, double *b)
{
    const double s = n[2] >= 0 ? 1.0 : -1.0, a = -1.0 / (s + n[2]), c = n[0] * n[1] * a;
    v3_set(t, 1.0 + s * n[0] * n[0] * a, s * c, -s * n[0]);
    v3_set(b, c, s + n[1] * n[1] * a, -n[1]);
}

#endif

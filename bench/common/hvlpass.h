/* One-bounce indirect light by Harmonics Virtual Lights (Mezieres et al. 2022):
 * distribution as a reflective shadow map per primary light (rays from the
 * light's centre through a k x k grid of cosine-weighted -- spheres: uniform --
 * directions, hits against the BVH), radii by heuristic 1 (Eq. 23) on that grid,
 * gathering by shl_hvl_shade at every receiver vertex.  Materials reflect and
 * receive indirect light by their diffuse albedo (Lambertian tables, kd = 1,
 * scaled per colour); HVL visibility is ignored, as in the paper. */
#ifndef SHL_BENCH_HVLPASS_H
#define SHL_BENCH_HVLPASS_H

#include "bvh.h"
#include "scene.h"

typedef struct {
    int count;
    shl_hvl *h;              /* power 1; rgb holds the coloured power */
    double *rgb;             /* 3 per HVL */
    shl_brdf_table *emit;    /* emission bands: scene hvl_lmax (the paper: 2) */
    shl_brdf_table *recv;    /* convolution bands */
} hvl_set;

/* About s->hvl_count HVLs in total, shared among the primary lights by power. 0 or -1. */
int hvl_distribute(const scene *s, const bvh *b, int recv_lmax, hvl_set *out);
/* indirect[3 * v + c] += the HVLs' radiance at the receiver vertices idx[0 .. n)
 * (idx NULL: every vertex). 0 or -1. */
int hvl_gather(const scene *s, const hvl_set *h, const int *idx, long n, float *indirect, int nthreads);
void hvl_free(hvl_set *h);

/* The baselines of HVL Table 2 on the same virtual lights (position, normal, coloured power,
 * radius), unshadowed like the HVLs.  Both virtual and receiving surfaces are Lambertian with
 * unit albedo here (f = 1 / pi; the gathers scale by the power's colour and the receiver's albedo).
 * VPL (Keller 1997): Phi cos_x cos_y / (pi^2 d^2) per unit power, unclamped.
 * VSL (Hasan et al. 2009, Eq. 5): Phi / (pi r^2) * integral over the cone the sphere subtends of
 * (1/pi) cos+_x (1/pi) cos+_y dw, estimated with samples = k^2 jittered strata of uniform cone
 * sampling (the cone is the hemisphere about the direction to the centre when x is inside the
 * sphere); seed picks the jitter (deterministic). */
double vpl_radiance(const shl_hvl *h, const double x[3], const double n[3]);
double vsl_radiance(const shl_hvl *h, const double x[3], const double n[3], int k, unsigned long long seed);
/* indirect[3 * v + c] += the virtual lights' radiance at idx[0 .. n) (NULL: every vertex);
 * vsl_k 0: VPL, else VSL with vsl_k^2 samples per light and vertex.  0 or -1. */
int vl_gather(const scene *s, const hvl_set *h, int vsl_k, const int *idx, long n, float *indirect, int nthreads);

#endif

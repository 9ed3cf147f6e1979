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

#endif

/* PRT transfer vectors per vertex (diffuse): T_k = (1/pi) int V(w) max(n.w, 0) Y_k(w) dw,
 * so that a Lambertian vertex of albedo a under lighting L (SH vector per colour)
 * leaves radiance a * (L . T) -- the albedo/pi of the BRDF times the cosine-weighted
 * integral.  Unshadowed: V = 1, T is the rotated clamped-cosine ZH divided by pi.
 * Shadowed: the unshadowed T minus the occluded part, estimated by ray casting
 * against a BVH (cosine-weighted rays), cached on disk. */
#ifndef SHL_BENCH_TRANSFER_H
#define SHL_BENCH_TRANSFER_H

#include "bvh.h"
#include "mesh.h"

typedef struct {
    int lmax, nc, nv;
    float *t; /* nv * nc */
} transfer;

void transfer_free(transfer *t);
int transfer_unshadowed(const mesh *m, int lmax, int nthreads, transfer *out);
/* rays per vertex (stratified, cosine-weighted); cache_dir NULL: no cache.
 * *cached = 1 when the result was read from the cache.  0 or -1. */
int transfer_shadowed(const mesh *m, const bvh *b, int lmax, int rays, const char *cache_dir, int nthreads,
                      transfer *out, int *cached);

#endif

/* Bounding volume hierarchy over a mesh's triangles (binned SAH, float),
 * for shadow rays (any hit) and HVL placement (closest hit). */
#ifndef SHL_BENCH_BVH_H
#define SHL_BENCH_BVH_H

#include "mesh.h"

typedef struct bvh bvh;

bvh *bvh_build(const mesh *m); /* NULL if out of memory */
void bvh_free(bvh *b);
/* Does the ray o + t d, 0 < t < tmax, hit any triangle? */
int bvh_occluded(const bvh *b, const float o[3], const float d[3], float tmax);
/* Closest hit with 0 < t < tmax: returns the triangle index (t and barycentrics
 * u, v of vertices 1 and 2 written) or -1. */
int bvh_closest(const bvh *b, const float o[3], const float d[3], float tmax, float *t, float *u, float *v);

#endif

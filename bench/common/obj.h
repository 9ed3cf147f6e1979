/* Wavefront OBJ loader: `v` and `f` records (polygons fan-triangulated,
 * negative indices allowed, texture/normal indices ignored); smooth
 * area-weighted normals are computed from the faces. */
#ifndef SHL_BENCH_OBJ_H
#define SHL_BENCH_OBJ_H

#include "mesh.h"
#include <stddef.h>

/* 0 on success; -1 with a message in err (size errlen) otherwise. */
int obj_load(const char *path, mesh *out, char *err, size_t errlen);

#endif

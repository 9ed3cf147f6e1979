/* Triangle meshes for the harness: procedural shapes, affine transforms,
 * merging, subdivision to a target triangle count, normals, hashing. */
#ifndef SHL_BENCH_MESH_H
#define SHL_BENCH_MESH_H

#include <stdint.h>

typedef struct {
    int nv, nt;
    double *pos; /* 3*nv */
    double *nrm; /* 3*nv, unit */
    int *tri;    /* 3*nt, counter-clockwise seen from the side the normals point to */
    int *mat;    /* nv material indices (mesh_append sets them; NULL before) */
} mesh;

void mesh_free(mesh *m);
/* Allocate nv vertices and nt triangles (contents undefined); 0 or -1. */
int mesh_alloc(mesh *m, int nv, int nt);

/* Square of side `size` in the plane y = 0 (normal +y), n x n quads. */
int mesh_plane(mesh *m, double size, int n);
/* Icosphere of radius r: the icosahedron subdivided `level` times (20 * 4^level triangles). */
int mesh_sphere(mesh *m, double r, int level);
/* Torus about the y axis: ring radius R, tube radius r, nu x nv quads. */
int mesh_torus(mesh *m, double R, double r, int nu, int nv);
/* Box [-sx/2, sx/2] x [0, sy] x [-sz/2, sz/2] (standing on y = 0), n x n quads per face, flat normals. */
int mesh_box(mesh *m, double sx, double sy, double sz, int n);

/* x -> A x + t with A = a[0..8] row-major, t = a[9..11]; normals by the inverse transpose. */
void mesh_transform(mesh *m, const double a[12]);
/* Append src to dst, tagging src's vertices with material `mat`; 0 or -1. */
int mesh_append(mesh *dst, const mesh *src, int mat);
/* Area-weighted vertex normals from the faces. */
void mesh_compute_normals(mesh *m);
/* Subdivide until at least `target` triangles: uniform 1-to-4 midpoint splits while
 * they fit, then longest-edge bisection (conforming, +2 triangles per interior edge)
 * for the remainder.  Midpoints interpolate positions and normals linearly.  0 or -1. */
int mesh_subdivide_to(mesh *m, long target);
/* The mesh reordered for memory locality (what a renderer's index buffer does): triangles
 * sorted by the Morton code of their centroid (10 bits per axis over the bounding box; ties in
 * index order), vertices renumbered by first use.  Allocates *pos (3 *nv doubles), *tri (3 nt)
 * and *tri_id (nt: each triangle's index in m, corners in m's order); 0 or -1. */
int mesh_locality_order(const mesh *m, double **pos, int **tri, int **tri_id, int *nv);
/* Vertices renumbered in place in the Morton order of their positions (10 bits per axis over the
 * bounding box; ties in index order): pos, nrm and mat permuted, triangle corners remapped,
 * triangle order kept.  Per-vertex work in index order then walks space coherently.  0 or -1
 * (m unchanged). */
int mesh_vertex_order(mesh *m);
/* dir/name as the oracle reads it (tools/oracle_images.py): positions, normals (3 nv doubles
 * each), the per-triangle albedo alb (3 nt doubles), triangles (3 nt ints); 0 or -1. */
int mesh_write_oracle(const mesh *m, const double *alb, const char *dir, const char *name);
/* Bounding box of the vertices. */
void mesh_bounds(const mesh *m, double lo[3], double hi[3]);
/* FNV-1a hash of positions, normals and triangles. */
uint64_t mesh_hash(const mesh *m);

#endif

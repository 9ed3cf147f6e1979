/* The PRT pipeline of the harness on one scene: the stages the scene calls for
 * (BVH and shadowed transfer only for `shadows`, HVLs only for `hvl-indirect`),
 * a visibility raster, then per lighting method: lighting (prepare + per-vertex
 * coefficients), shading (diffuse transfer dot product; the view-dependent
 * glossy lobe only for `glossy`) and resolving the image.
 * Radiance leaving a vertex of material (albedo a, glossy weight ks, lobe k):
 *   a_c (L_c . T)  +  ks int L_c(w) k(r . w) dw  (+ HVL indirect),
 * r the mirror direction of the view; k is the normalized Phong lobe
 * (shl_zh_phong) or the GGX mirror-direction lobe (shl_zh_ggx), about r. */
#ifndef SHL_BENCH_PRT_H
#define SHL_BENCH_PRT_H

#include "hvlpass.h"
#include "lighting.h"
#include "raster.h"
#include "scene.h"
#include "transfer.h"
#include <stdio.h>

typedef struct {
    char name[64];
    double seconds;
    char note[160];
} prt_stage;

typedef struct {
    scene *s;
    int nthreads;
    double lo[3], hi[3];      /* receiver bounding box */
    camera cam;
    bvh *bvh;                 /* shadows or hvl-indirect only */
    transfer T;               /* diffuse transfer at s->lmax */
    mesh emit[2];             /* display geometry of the lights: one-sided polygons; two-sided and spheres */
    float *emit_rgb[2];
    raster_mesh rm[3];        /* receivers, emit[0], emit[1] */
    raster_mesh rdraw[3];     /* what raster_draw reads: rm with the receivers in locality order
                                 (mesh_locality_order: the same visibility buffer, faster) */
    double *rpos;             /* their positions, triangles and source triangles */
    int *rtri, *rtri_id;
    framebuf fb;
    double raster_seconds;    /* the visibility raster of prt_init */
    unsigned char *mask;      /* pixels showing receivers */
    hvl_set hvl;
    float *indirect;          /* per-vertex HVL radiance, or NULL */
    float *vrad;              /* per-vertex radiance of the last render, 3 nv */
    prt_stage stage[16];
    int nstages;
    FILE *report;             /* stage lines as they finish, or NULL */
} prt;

typedef struct {
    double prepare;  /* lighting_prepare: grid fill, single sample */
    double lighting; /* per-vertex coefficients } run fused per block of vertices: their wall */
    double shade;    /* transfer dot products (+ glossy lobes) } time split by the workers' time in each */
    double resolve;  /* per-vertex radiance through the visibility buffer */
} prt_times;

/* Run the precomputation stages.  The first renumbers s->geom's vertices (mesh_vertex_order):
 * per-vertex data of s must be taken after prt_init.  cache_dir: shadowed-transfer cache
 * (NULL: none).  0 or -1. */
int prt_init(prt *p, scene *s, int nthreads, const char *cache_dir, FILE *report);
void prt_free(prt *p);
/* Render with method m into img (3 w h floats).  subset (nsub vertices) limits
 * lighting and shading to those vertices (the others get 0); NULL: all.  0 or -1. */
int prt_render(prt *p, const lighting_method *m, const int *subset, long nsub, float *img, prt_times *t);
/* Receiver vertices used by visible pixels, ascending, into idx (nv entries); returns the count. */
long prt_visible_vertices(const prt *p, int *idx);
/* The scene's exposure, or the automatic one for img. */
double prt_exposure(const prt *p, const float *img);
/* Table of the precomputation stages that ran and of those skipped. */
void prt_print_stages(const prt *p, FILE *out);

#endif

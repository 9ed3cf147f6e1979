/* Software rasterizer: perspective camera, near-plane clipping, z-buffer,
 * multi-threaded 32x32 tiles.  raster_draw computes a visibility buffer
 * (mesh, triangle and perspective-correct barycentrics per pixel centre);
 * raster_resolve then interpolates any per-vertex colours through it, so one
 * visibility pass serves every lighting method compared on a scene.  A pixel is
 * covered when its centre is inside the triangle; a centre on an edge goes to
 * exactly one of the edge's two triangles (watertight: the two evaluate the edge
 * function with the same operands and get exactly opposite values). */
#ifndef SHL_BENCH_RASTER_H
#define SHL_BENCH_RASTER_H

#include <stddef.h>

typedef struct {
    double eye[3], target[3], up[3];
    double fov_deg; /* vertical field of view */
} camera;

typedef struct {
    int nv, nt;
    const double *pos; /* 3*nv */
    const int *tri;    /* 3*nt */
    int back_black;    /* resolve: triangles seen from behind (clockwise on screen) are black */
    const int *tri_id; /* NULL, or per triangle its index in the mesh the caller sees: tri is that mesh's
                          triangles reordered for memory locality (pos and tri renumbered alike);
                          fb->tri reports tri_id[t], and raster_draw resolves depth ties in tri_id
                          order, so the buffer is the one of the unreordered mesh, bit for bit */
} raster_mesh;

typedef struct {
    int w, h;
    float *depth;          /* 1 / view depth; 0: background */
    int *mesh, *tri;       /* mesh index and triangle per pixel (-1: background) */
    float *bary;           /* 3 per pixel: weights of the triangle's vertices */
    unsigned char *back;   /* 1: the triangle is seen from behind */
    void *work[6];         /* raster_draw's buffers, kept from one draw to the next */
    size_t work_len[6];    /* their sizes in bytes */
} framebuf;

int framebuf_init(framebuf *fb, int w, int h); /* 0 or -1 */
void framebuf_free(framebuf *fb);

/* Visibility of the meshes (clears fb first).  0 or -1 (out of memory). */
int raster_draw(framebuf *fb, const camera *cam, const raster_mesh *meshes, int nmeshes, int nthreads);

/* rgb[3*w*h] from per-vertex colours: colors[m] holds 3*nv floats for mesh m;
 * background pixels are black. */
void raster_resolve(const framebuf *fb, const raster_mesh *meshes, const float *const *colors, float *rgb, int nthreads);

/* mask[w*h] = 1 where mesh `m` is visible. */
void raster_mask(const framebuf *fb, int m, unsigned char *mask);

#endif

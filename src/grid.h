/* Regular SH grids: internal layout shared by grid.c and interp.c. */
#ifndef SHL_GRID_H
#define SHL_GRID_H

#include "internal.h"

/* Node (i, j, k) is number i + res[0] * (j + res[1] * k); its node_len =
 * 12 nc elements are the values rgb[c*nc + k] (3 nc) followed by the gradients
 * grad[(c*3 + a)*nc + k] (9 nc), the layout of shl_lights_eval. */
struct shl_grid {
    int lmax, nc, storage;   /* storage: SHL_GRID_FLOAT or SHL_GRID_DOUBLE */
    int res[3];
    double lo[3], hi[3], h[3]; /* h: node spacing (hi - lo) / (res - 1) */
    size_t nnodes, node_len;
    const shl__isa *isa;     /* interpolation kernel: the creating context's (dispatch.c) */
    void *data;
    int nlights;             /* lights of the last successful shl_grid_fill (0 before any) */
    unsigned char *light_box; /* per light of that fill: SHL__BOX_* bits; NULL if nlights == 0 */
};

/* Bits of shl_grid.light_box: the light's geometry meets the closed box [lo, hi],
 * resp. the box grown by one node spacing h on every side. */
enum { SHL__BOX_IN = 1, SHL__BOX_NEAR = 2 };

/* Position of node idx (the last node of an axis is exactly hi). */
void shl__grid_node_pos(const shl_grid *g, const int idx[3], double pos[3]);

#endif

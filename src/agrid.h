/* Adaptive multi-level SH grids: internal layout of agrid.c.
 *
 * Level l is the uniform lattice of the box with (res[a] - 1) 2^l cells per axis
 * (spacing h_l = h_0 / 2^l), of which only some cells exist.  Level 0 has all of
 * them.  Level l + 1 has the 8 children of every level-l lattice cell that has a
 * corner flagged: a level-l node is flagged when it is a corner of a refined
 * level-l cell (one whose error estimate exceeded the tolerance).  Nodes and
 * cells of a level are found by hashing their lattice indices. */
#ifndef SHL_AGRID_H
#define SHL_AGRID_H

#include "internal.h"
#include <stdint.h>

/* Open-addressing hash from lattice keys (agrid.c: key()) to indices. */
typedef struct {
    uint64_t *key;     /* 0: empty slot */
    uint32_t *val;
    size_t cap, count; /* cap: a power of two, count <= cap / 2 */
} shl__ahash;

/* A cell: its 8 corner nodes (corner j = ix + 2 iy + 4 iz, index in the level's
 * nodes) and, bit j of flags, whether corner j is flagged (all set on level 0). */
typedef struct {
    uint32_t node[8];
    unsigned char flags;
} shl__acell;

typedef struct {
    int n[3];              /* lattice cells per axis */
    double h[3];           /* spacing (hi - lo) / n */
    shl__ahash nodes, cells;
    uint64_t *node_key;    /* per node: its lattice key (position) */
    float *data;           /* per node: node_len floats, layout of grid.h */
    unsigned char *flag;   /* per node: flagged (in a refined cell of the level above) */
    size_t nnodes, node_cap, data_cap; /* data_cap: nodes data holds (node_cap, or nnodes after fill) */
    shl__acell *cell;
    uint64_t *cell_key;
    size_t ncells, cell_cap;
} shl__alevel;

struct shl__arecv {
    uint64_t key;
    float x[3];
    float w; /* its weight (> 0; 1 without weights) */
};

struct shl_agrid {
    int lmax, nc, res[3];
    double lo[3], hi[3], tol;
    int criterion;         /* SHL_AGRID_MAX or SHL_AGRID_MEAN */
    long max_nodes;
    int max_levels;        /* levels the float path allows (<= SHL_AGRID_LEVELS_MAX) */
    const shl__isa *isa;   /* interpolation and batch kernels: the creating context's */
    size_t node_len;       /* 12 nc */
    int nlevels;
    shl__alevel lev[SHL_AGRID_LEVELS_MAX];
    shl_agrid_stats stats;
    struct shl__arecv *recv; /* shl_agrid_set_receivers: Morton keys of the receivers' cells on level
                              max_levels - 1 and the receivers (float, clamped to the box), ascending (NULL: none) */
    double *recv_cum;        /* nrecv + 1 prefix sums of the receivers' weights, in recv's order */
    size_t nrecv;
};

#endif

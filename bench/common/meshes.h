/* The public test meshes the paper scenes read (the bench/scenes files, `object ... mesh`):
 * where to get them, their SHA-256, and the check bench_tables runs before measuring. */
#ifndef SHL_BENCH_MESHES_H
#define SHL_BENCH_MESHES_H

#include <stddef.h>

/* Where a fresh clone gets the meshes (the checkout's ../shared/meshes holds a copy). */
#define MESHES_SOURCE "https://github.com/alecjacobson/common-3d-test-models" /* folder data/ */
#define MESHES_DEFAULT_DIR "../shared/meshes"
#define MESHES_ENV "SHLIGHT_MESHES"

typedef struct {
    const char *file;   /* e.g. "cow.obj" */
    const char *sha256; /* 64 lowercase hex digits */
} mesh_file;

extern const mesh_file meshes_known[];
extern const int meshes_count;

/* The entry of meshes_known named file (a base name), or NULL. */
const mesh_file *meshes_find(const char *file);

/* SHA-256 (FIPS 180-4) of the file at path as 64 hex digits plus NUL; 0 ok, -1 unreadable. */
int sha256_file(const char *path, char hex[65]);

/* Checks that dir holds every known mesh with its SHA-256.  0 ok; otherwise -1 with a
 * message (each missing or mismatching file, the source, the checksums) in err. */
int meshes_verify(const char *dir, char *err, size_t errlen);

#endif

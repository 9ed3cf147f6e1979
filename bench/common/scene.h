/* Scenes for the PRT harness: the text format of bench/scenes/README.md,
 * parsed into one merged receiver mesh (per-vertex material), materials,
 * camera, polygon and spherical lights, and the effects the scene calls for. */
#ifndef SHL_BENCH_SCENE_H
#define SHL_BENCH_SCENE_H

#include "mesh.h"
#include "shlight.h"
#include <stddef.h>

enum { FX_DIRECT = 1, FX_SHADOWS = 2, FX_GLOSSY = 4, FX_HVL = 8 };
enum { MAT_DIFFUSE = 0, MAT_PHONG = SHL_BRDF_PHONG, MAT_GGX = SHL_BRDF_GGX };

typedef struct {
    char name[32];
    int kind;          /* MAT_DIFFUSE, MAT_PHONG or MAT_GGX */
    double albedo[3];  /* diffuse albedo */
    double ks;         /* glossy weight */
    double exponent;   /* Phong exponent */
    double alpha;      /* GGX roughness */
} scene_material;

typedef struct {
    int n, two_sided;
    double v[3 * SHL_MAX_VERTS];
    double rgb[3];     /* radiance */
} scene_polygon;

typedef struct {
    double center[3], radius, rgb[3];
} scene_sphere;

typedef struct {
    char name[128];
    int lmax, width, height;
    double eye[3], target[3], fov_deg; /* up is +y */
    double exposure;                   /* <= 0: automatic */
    int effects;                       /* FX_* */
    int shadow_rays, grid_res, mc_samples;
    int hvl_count, hvl_lmax;           /* HVLs per primary light; emission and convolution bands - 1 */
    double hvl_scale;                  /* radius factor (HVL Sec. 5.3) */
    mesh geom;                         /* all objects; geom.mat[v] indexes mats */
    scene_material *mats;
    int nmats;
    scene_polygon *polys;
    int npolys;
    scene_sphere *spheres;
    int nspheres;
    int light_statements;              /* `light` lines (textured lights count once) */
} scene;

#define SCENE_ERROR   (-1)
#define SCENE_MISSING (-2) /* a mesh file does not exist */

/* The embedded default scene of `make demo` (procedural, needs no file). */
extern const char scene_default_text[];

/* Parse scene text; mesh paths are relative to basedir.  0, SCENE_ERROR or
 * SCENE_MISSING with a message in err.  On error *s is left empty. */
int scene_parse(const char *text, const char *name, const char *basedir, scene *s, char *err, size_t errlen);
/* Read and parse a scene file (mesh paths relative to its directory). */
int scene_load(const char *path, scene *s, char *err, size_t errlen);

/* NULL (default): a mesh statement's file is read at its path.  Set (bench_tables sets it to the
 * checksum-verified mesh directory): the file is read from this directory by its base name, and
 * only the meshes of bench/common/meshes.h are accepted. */
extern const char *scene_mesh_dir;
void scene_free(scene *s);

/* All lights (polygons and spheres) as a light set; NULL on failure. */
shl_lights *scene_light_set(const scene *s);
/* "direct shadows glossy" etc. into buf. */
const char *scene_effects_str(int effects, char *buf, size_t len);

#endif

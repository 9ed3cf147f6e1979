#include "scene.h"
#include "meshes.h"
#include "obj.h"
#include "vec3.h"
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char scene_default_text[] =
    "# make demo: procedural objects on a floor, four polygonal area lights (one of them\n"
    "# textured: 24 uniform triangles) and one spherical light, all outside the receivers' box.\n"
    "name default\n"
    "lmax 8\n"
    "image 720 450\n"
    "camera 0 3.6 8.8  0 0.8 0  38\n"
    "exposure auto\n"
    "effects direct shadows glossy\n"
    "shadow_rays 256\n"
    "grid 8\n"
    "mc_samples 128\n"
    "material floor diffuse 0.7 0.7 0.68\n"
    "material clay diffuse 0.85 0.5 0.35\n"
    "material chalk diffuse 0.8 0.8 0.85\n"
    "material jade phong 0.12 0.4 0.25 0.5 8\n"
    "material steel ggx 0.25 0.25 0.3 0.7 0.35\n"
    "object floor plane 9 112\n"
    "object clay sphere 0.8 4 translate -2.0 0.8 0.3\n"
    "object jade torus 0.75 0.28 96 48 rotate x 90 rotate y 20 translate 0.1 1.03 -1.0\n"
    "object steel sphere 0.55 4 translate 0.4 0.55 1.5\n"
    "object chalk box 1.1 1.7 1.1 16 rotate y 30 translate 2.2 0 -0.4\n"
    "light polygon one-sided 7 5 3  -3.2 3.4 -1.2  -1.4 3.4 -1.2  -1.4 3.4 0.8  -3.2 3.4 0.8\n"
    "light polygon one-sided 1.5 3 7  5.0 0.2 -1.2  5.0 0.2 1.2  5.0 2.2 1.2  5.0 2.2 -1.2\n"
    "light polygon two-sided 1.5 6 2  -1.5 0.1 -4.9  0.5 0.1 -4.9  -0.5 2.0 -4.9\n"
    "light textured one-sided 24 8 1.5 1  1.5 1.5 8  1.2 2.6 -3.6  3.6 2.6 -3.6  3.6 4.0 -2.6  1.2 4.0 -2.6\n"
    "light sphere 9 8 7  -0.8 2.6 1.8  0.25\n";

typedef struct {
    char *tok[96];
    int n, pos;
    int lineno;
    const char *name;
    char *err;
    size_t errlen;
} line_t;

static int fail(line_t *L, const char *msg)
{
    snprintf(L->err, L->errlen, "%s:%d: %s", L->name, L->lineno, msg);
    return SCENE_ERROR;
}

static const char *next_tok(line_t *L) { return L->pos < L->n ? L->tok[L->pos++] : NULL; }

static int num(line_t *L, double *out)
{
    const char *t = next_tok(L);
    char *e;
    if (!t) return fail(L, "missing number");
    errno = 0;
    *out = strtod(t, &e);
    if (*e || e == t || errno) return fail(L, "bad number");
    return 0;
}

static int is_num(const char *t)
{
    char *e;
    strtod(t, &e);
    return e != t && !*e;
}

static int nums(line_t *L, double *out, int n)
{
    for (int i = 0; i < n; ++i)
        if (num(L, out + i)) return SCENE_ERROR;
    return 0;
}

static int inum(line_t *L, int *out, int lo, int hi)
{
    double d;
    if (num(L, &d)) return SCENE_ERROR;
    if (d != (double)(long)d || d < lo || d > hi) return fail(L, "integer out of range");
    *out = (int)d;
    return 0;
}

static void *push(void **arr, int *count, size_t elem)
{
    void *a = realloc(*arr, elem * (size_t)(*count + 1));
    if (!a) return NULL;
    *arr = a;
    memset((char *)a + elem * (size_t)*count, 0, elem);
    return (char *)a + elem * (size_t)(*count)++;
}

static int sidedness(line_t *L, int *two_sided)
{
    const char *t = next_tok(L);
    if (t && !strcmp(t, "one-sided")) *two_sided = 0;
    else if (t && !strcmp(t, "two-sided")) *two_sided = 1;
    else return fail(L, "expected one-sided or two-sided");
    return 0;
}

static int add_polygon(scene *s, const double *v, int n, const double rgb[3], int two_sided)
{
    scene_polygon *p = push((void **)&s->polys, &s->npolys, sizeof *p);
    if (!p) return -1;
    p->n = n;
    p->two_sided = two_sided;
    memcpy(p->v, v, sizeof(double) * 3 * (size_t)n);
    memcpy(p->rgb, rgb, sizeof p->rgb);
    return 0;
}

/* Quad p0 p1 p2 p3 (bilinear patch) split into N >= 2 triangles: rows of zigzag
 * strips; each triangle's radiance is c0 -> c1 linearly along p0 -> p1 at its centroid. */
static int textured_light(scene *s, const double p[12], int N, const double c0[3], const double c1[3], int two_sided)
{
    const double w = sqrt((p[3] - p[0]) * (p[3] - p[0]) + (p[4] - p[1]) * (p[4] - p[1]) + (p[5] - p[2]) * (p[5] - p[2]));
    const double h = sqrt((p[9] - p[0]) * (p[9] - p[0]) + (p[10] - p[1]) * (p[10] - p[1]) + (p[11] - p[2]) * (p[11] - p[2]));
    int rows = (int)lround(sqrt(N * h / (2.0 * w)));
    rows = rows < 1 ? 1 : rows > N / 2 ? N / 2 : rows;
    for (int r = 0; r < rows; ++r) {
        const int k = N / rows + (r < N % rows), a = (k + 1) / 2, b = k - a;
        const double v0 = (double)r / rows, v1 = (double)(r + 1) / rows;
        int i = 0, j = 0;
        while (i < a || j < b) {
            const int bottom = j == b || (i < a && (double)(i + 1) / a <= (double)(j + 1) / b);
            double uv[3][2], tri[9], rgb[3];
            if (bottom) {
                const double t[3][2] = {{(double)i / a, v0}, {(double)(i + 1) / a, v0}, {(double)j / b, v1}};
                memcpy(uv, t, sizeof t);
                ++i;
            } else {
                const double t[3][2] = {{(double)i / a, v0}, {(double)(j + 1) / b, v1}, {(double)j / b, v1}};
                memcpy(uv, t, sizeof t);
                ++j;
            }
            for (int q = 0; q < 3; ++q)
                for (int c = 0; c < 3; ++c) {
                    const double u = uv[q][0], v = uv[q][1];
                    tri[3 * q + c] = (1 - v) * ((1 - u) * p[c] + u * p[3 + c]) + v * ((1 - u) * p[9 + c] + u * p[6 + c]);
                }
            const double uc = (uv[0][0] + uv[1][0] + uv[2][0]) / 3.0;
            for (int c = 0; c < 3; ++c) rgb[c] = (1 - uc) * c0[c] + uc * c1[c];
            if (add_polygon(s, tri, 3, rgb, two_sided)) return -1;
        }
    }
    return 0;
}

static int find_material(const scene *s, const char *name)
{
    for (int i = 0; i < s->nmats; ++i)
        if (!strcmp(s->mats[i].name, name)) return i;
    return -1;
}

static int parse_material(line_t *L, scene *s)
{
    const char *name = next_tok(L), *kind = next_tok(L);
    if (!name || !kind) return fail(L, "material needs a name and a kind");
    if (strlen(name) >= sizeof s->mats[0].name) return fail(L, "material name too long");
    if (find_material(s, name) >= 0) return fail(L, "material defined twice");
    scene_material m = {{0}, MAT_DIFFUSE, {0, 0, 0}, 0, 0, 0};
    snprintf(m.name, sizeof m.name, "%s", name);
    if (nums(L, m.albedo, 3)) return SCENE_ERROR;
    if (!strcmp(kind, "phong")) {
        m.kind = MAT_PHONG;
        if (num(L, &m.ks) || num(L, &m.exponent)) return SCENE_ERROR;
        if (m.exponent < 0 || m.exponent > 1e6) return fail(L, "Phong exponent outside 0..1e6");
    } else if (!strcmp(kind, "ggx")) {
        m.kind = MAT_GGX;
        if (num(L, &m.ks) || num(L, &m.alpha)) return SCENE_ERROR;
        if (m.alpha < 1e-3 || m.alpha > 1) return fail(L, "GGX alpha outside 1e-3..1");
    } else if (strcmp(kind, "diffuse"))
        return fail(L, "material kind must be diffuse, phong or ggx");
    if (m.albedo[0] < 0 || m.albedo[1] < 0 || m.albedo[2] < 0 || m.ks < 0) return fail(L, "negative reflectance");
    scene_material *d = push((void **)&s->mats, &s->nmats, sizeof *d);
    if (!d) return fail(L, "out of memory");
    *d = m;
    return 0;
}

static void affine_apply(mesh *m, const double lin[9], const double t[3])
{
    double a[12];
    memcpy(a, lin, sizeof(double) * 9);
    memcpy(a + 9, t, sizeof(double) * 3);
    mesh_transform(m, a);
}

const char *scene_mesh_dir;

static int parse_object(line_t *L, scene *s, const char *basedir)
{
    const char *mname = next_tok(L), *shape = next_tok(L);
    if (!mname || !shape) return fail(L, "object needs a material and a shape");
    const int mat = find_material(s, mname);
    if (mat < 0) return fail(L, "unknown material (define it before the object)");
    mesh m = {0};
    int st = 0;
    double d[4];
    int k[2];
    if (!strcmp(shape, "plane")) {
        if (num(L, d) || inum(L, k, 1, 4096)) return SCENE_ERROR;
        st = mesh_plane(&m, d[0], k[0]);
    } else if (!strcmp(shape, "sphere")) {
        if (num(L, d) || inum(L, k, 0, 9)) return SCENE_ERROR;
        st = mesh_sphere(&m, d[0], k[0]);
    } else if (!strcmp(shape, "torus")) {
        if (nums(L, d, 2) || inum(L, k, 3, 4096) || inum(L, k + 1, 3, 4096)) return SCENE_ERROR;
        st = mesh_torus(&m, d[0], d[1], k[0], k[1]);
    } else if (!strcmp(shape, "box")) {
        if (nums(L, d, 3) || inum(L, k, 1, 1024)) return SCENE_ERROR;
        st = mesh_box(&m, d[0], d[1], d[2], k[0]);
    } else if (!strcmp(shape, "mesh")) {
        const char *file = next_tok(L);
        char path[1024], err[512];
        if (!file) return fail(L, "mesh needs a file");
        snprintf(path, sizeof path, "%s%s%s", file[0] == '/' ? "" : basedir, file[0] == '/' ? "" : "/", file);
        if (scene_mesh_dir) {
            const char *base = strrchr(file, '/') ? strrchr(file, '/') + 1 : file;
            if (!meshes_find(base)) return fail(L, "not one of the checksummed test meshes (bench/common/meshes.c)");
            snprintf(path, sizeof path, "%s/%s", scene_mesh_dir, base);
        }
        FILE *f = fopen(path, "rb");
        if (!f) {
            snprintf(L->err, L->errlen, "%s:%d: mesh file %s not found", L->name, L->lineno, path);
            return SCENE_MISSING;
        }
        fclose(f);
        if (obj_load(path, &m, err, sizeof err)) return fail(L, err);
    } else
        return fail(L, "shape must be plane, sphere, torus, box or mesh");
    if (st) return fail(L, "out of memory building the shape");
    static const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, zero[3] = {0, 0, 0};
    for (const char *op; (op = next_tok(L));) {
        double lin[9], t[3] = {0, 0, 0};
        memcpy(lin, I, sizeof lin);
        if (!strcmp(op, "translate")) {
            if (nums(L, t, 3)) goto bad;
            affine_apply(&m, I, t);
        } else if (!strcmp(op, "scale")) {
            if (num(L, d)) goto bad;
            d[1] = d[2] = d[0];
            if (L->pos < L->n && is_num(L->tok[L->pos]) && nums(L, d + 1, 2)) goto bad;
            lin[0] = d[0];
            lin[4] = d[1];
            lin[8] = d[2];
            affine_apply(&m, lin, zero);
        } else if (!strcmp(op, "rotate")) {
            const char *ax = next_tok(L);
            if (!ax || strlen(ax) != 1 || !strchr("xyz", ax[0])) {
                mesh_free(&m);
                return fail(L, "rotate needs an axis x, y or z");
            }
            if (num(L, d)) goto bad;
            const int a = ax[0] - 'x', i = (a + 1) % 3, j = (a + 2) % 3;
            const double c = cos(d[0] * M_PI / 180), sn = sin(d[0] * M_PI / 180);
            lin[3 * i + i] = c;
            lin[3 * i + j] = -sn;
            lin[3 * j + i] = sn;
            lin[3 * j + j] = c;
            affine_apply(&m, lin, zero);
        } else if (!strcmp(op, "fit")) {
            double lo[3], hi[3];
            if (num(L, d)) goto bad;
            mesh_bounds(&m, lo, hi);
            const double ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
            const double sc = ext > 0 ? d[0] / ext : 1.0;
            lin[0] = lin[4] = lin[8] = sc;
            v3_set(t, -sc * 0.5 * (lo[0] + hi[0]), -sc * lo[1], -sc * 0.5 * (lo[2] + hi[2]));
            affine_apply(&m, lin, t);
        } else if (!strcmp(op, "triangles")) {
            if (num(L, d)) goto bad;
            if (d[0] > 2e8 || mesh_subdivide_to(&m, (long)d[0])) {
                mesh_free(&m);
                return fail(L, "subdivision failed (out of memory or target above 2e8)");
            }
        } else {
            mesh_free(&m);
            return fail(L, "unknown object option (translate, scale, rotate, fit, triangles)");
        }
    }
    st = mesh_append(&s->geom, &m, mat);
    mesh_free(&m);
    return st ? fail(L, "out of memory") : 0;
bad:
    mesh_free(&m);
    return SCENE_ERROR;
}

static int parse_light(line_t *L, scene *s)
{
    const char *kind = next_tok(L);
    double rgb[3], rgb1[3], v[3 * SHL_MAX_VERTS];
    int two_sided = 1, n;
    if (!kind) return fail(L, "light needs a kind");
    if (!strcmp(kind, "polygon")) {
        if (sidedness(L, &two_sided) || nums(L, rgb, 3)) return SCENE_ERROR;
        if ((L->n - L->pos) % 3 || (n = (L->n - L->pos) / 3) < 3 || n > SHL_MAX_VERTS)
            return fail(L, "polygon needs 3..64 vertices (x y z each)");
        if (nums(L, v, 3 * n)) return SCENE_ERROR;
        if (add_polygon(s, v, n, rgb, two_sided)) return fail(L, "out of memory");
    } else if (!strcmp(kind, "textured")) {
        if (sidedness(L, &two_sided) || inum(L, &n, 2, 1 << 20) || nums(L, rgb, 3) || nums(L, rgb1, 3) || nums(L, v, 12))
            return SCENE_ERROR;
        const double w = (v[3] - v[0]) * (v[3] - v[0]) + (v[4] - v[1]) * (v[4] - v[1]) + (v[5] - v[2]) * (v[5] - v[2]);
        const double h = (v[9] - v[0]) * (v[9] - v[0]) + (v[10] - v[1]) * (v[10] - v[1]) + (v[11] - v[2]) * (v[11] - v[2]);
        if (!(w > 0) || !(h > 0)) return fail(L, "degenerate textured quad (p0 p1 or p0 p3 of zero length)");
        if (textured_light(s, v, n, rgb, rgb1, two_sided)) return fail(L, "out of memory");
    } else if (!strcmp(kind, "sphere")) {
        scene_sphere sp;
        if (nums(L, sp.rgb, 3) || nums(L, sp.center, 3) || num(L, &sp.radius)) return SCENE_ERROR;
        if (!(sp.radius > 0)) return fail(L, "sphere radius must be > 0");
        scene_sphere *d = push((void **)&s->spheres, &s->nspheres, sizeof *d);
        if (!d) return fail(L, "out of memory");
        *d = sp;
    } else
        return fail(L, "light kind must be polygon, textured or sphere");
    ++s->light_statements;
    return L->pos == L->n ? 0 : fail(L, "extra tokens after the light");
}

static int parse_effects(line_t *L, scene *s)
{
    s->effects = 0;
    for (const char *t; (t = next_tok(L));) {
        if (!strcmp(t, "direct")) s->effects |= FX_DIRECT;
        else if (!strcmp(t, "shadows")) s->effects |= FX_SHADOWS;
        else if (!strcmp(t, "glossy")) s->effects |= FX_GLOSSY;
        else if (!strcmp(t, "hvl-indirect")) s->effects |= FX_HVL;
        else return fail(L, "effects are direct, shadows, glossy, hvl-indirect");
    }
    return 0;
}

static int parse_line(line_t *L, scene *s, const char *basedir)
{
    const char *key = next_tok(L);
    if (!strcmp(key, "name")) {
        const char *t = next_tok(L);
        if (!t) return fail(L, "name needs a value");
        snprintf(s->name, sizeof s->name, "%s", t);
        return 0;
    }
    if (!strcmp(key, "lmax")) return inum(L, &s->lmax, 0, SHL_LMAX_MAX);
    if (!strcmp(key, "image")) return inum(L, &s->width, 1, 16384) || inum(L, &s->height, 1, 16384) ? SCENE_ERROR : 0;
    if (!strcmp(key, "camera")) {
        if (nums(L, s->eye, 3) || nums(L, s->target, 3) || num(L, &s->fov_deg)) return SCENE_ERROR;
        return s->fov_deg > 0 && s->fov_deg < 170 ? 0 : fail(L, "fov outside (0, 170) degrees");
    }
    if (!strcmp(key, "exposure")) {
        if (L->pos < L->n && !strcmp(L->tok[L->pos], "auto")) {
            ++L->pos;
            s->exposure = 0;
            return 0;
        }
        return num(L, &s->exposure);
    }
    if (!strcmp(key, "effects")) return parse_effects(L, s);
    if (!strcmp(key, "shadow_rays")) return inum(L, &s->shadow_rays, 1, 1 << 20);
    if (!strcmp(key, "grid")) return inum(L, &s->grid_res, 2, SHL_GRID_RES_MAX);
    if (!strcmp(key, "mc_samples")) return inum(L, &s->mc_samples, 1, 1 << 24);
    if (!strcmp(key, "hvl")) {
        if (inum(L, &s->hvl_count, 4, 1 << 20) || inum(L, &s->hvl_lmax, 0, SHL_LMAX_MAX) || num(L, &s->hvl_scale))
            return SCENE_ERROR;
        return s->hvl_scale > 0 ? 0 : fail(L, "HVL radius scale must be > 0");
    }
    if (!strcmp(key, "material")) return parse_material(L, s);
    if (!strcmp(key, "object")) return parse_object(L, s, basedir);
    if (!strcmp(key, "light")) return parse_light(L, s);
    return fail(L, "unknown keyword");
}

int scene_parse(const char *text, const char *name, const char *basedir, scene *s, char *err, size_t errlen)
{
    memset(s, 0, sizeof *s);
    snprintf(s->name, sizeof s->name, "%s", name);
    s->lmax = 8;
    s->width = 640;
    s->height = 400;
    v3_set(s->eye, 0, 2, 8);
    s->fov_deg = 40;
    s->effects = FX_DIRECT;
    s->shadow_rays = 256;
    s->grid_res = 8;
    s->mc_samples = 256;
    s->hvl_count = 256;
    s->hvl_lmax = 2;
    s->hvl_scale = 1.5;
    char *copy = malloc(strlen(text) + 1);
    if (!copy) {
        snprintf(err, errlen, "out of memory");
        return SCENE_ERROR;
    }
    strcpy(copy, text);
    int st = 0;
    line_t L = {{0}, 0, 0, 0, name, err, errlen};
    for (char *line = copy, *next; !st && line; line = next) {
        next = strchr(line, '\n');
        if (next) *next++ = '\0';
        ++L.lineno;
        char *hash = strchr(line, '#');
        if (hash) *hash = '\0';
        L.n = L.pos = 0;
        char *save = NULL;
        for (char *t = strtok_r(line, " \t\r", &save); t; t = strtok_r(NULL, " \t\r", &save)) {
            if (L.n == (int)(sizeof L.tok / sizeof L.tok[0])) {
                st = fail(&L, "too many tokens");
                break;
            }
            L.tok[L.n++] = t;
        }
        if (!st && L.n) st = parse_line(&L, s, basedir);
        if (!st && L.pos < L.n) st = fail(&L, "extra tokens");
    }
    free(copy);
    if (!st && s->geom.nt == 0) st = fail(&L, "the scene has no object");
    if (!st && s->npolys + s->nspheres == 0) st = fail(&L, "the scene has no light");
    if (!st && !(s->effects & FX_DIRECT))
        st = fail(&L, "effects must include `direct`: the other effects modify or add to the direct pass");
    if (st) scene_free(s);
    return st;
}

int scene_load(const char *path, scene *s, char *err, size_t errlen)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(err, errlen, "cannot open %s: %s", path, strerror(errno));
        return SCENE_ERROR;
    }
    char text[1 << 16];
    const size_t len = fread(text, 1, sizeof text - 1, f);
    const int too_long = !feof(f);
    fclose(f);
    if (too_long) {
        snprintf(err, errlen, "%s: longer than %zu bytes", path, sizeof text - 1);
        return SCENE_ERROR;
    }
    text[len] = '\0';
    char dir[1024];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash) *slash = '\0';
    else snprintf(dir, sizeof dir, ".");
    const char *base = strrchr(path, '/');
    char name[128];
    snprintf(name, sizeof name, "%s", base ? base + 1 : path);
    char *dot = strrchr(name, '.');
    if (dot) *dot = '\0';
    return scene_parse(text, name, dir, s, err, errlen);
}

void scene_free(scene *s)
{
    mesh_free(&s->geom);
    free(s->mats);
    free(s->polys);
    free(s->spheres);
    memset(s, 0, sizeof *s);
}

shl_lights *scene_light_set(const scene *s)
{
    shl_lights *l;
    if (shl_lights_create(&l) != SHL_OK) return NULL;
    for (int i = 0; i < s->npolys; ++i)
        if (shl_lights_add_polygon(l, s->polys[i].v, s->polys[i].n, s->polys[i].rgb, s->polys[i].two_sided) != SHL_OK) {
            shl_lights_destroy(l);
            return NULL;
        }
    for (int i = 0; i < s->nspheres; ++i)
        if (shl_lights_add_sphere(l, s->spheres[i].center, s->spheres[i].radius, s->spheres[i].rgb) != SHL_OK) {
            shl_lights_destroy(l);
            return NULL;
        }
    return l;
}

const char *scene_effects_str(int effects, char *buf, size_t len)
{
    snprintf(buf, len, "%s%s%s%s", effects & FX_DIRECT ? "direct " : "", effects & FX_SHADOWS ? "shadows " : "",
             effects & FX_GLOSSY ? "glossy " : "", effects & FX_HVL ? "hvl-indirect " : "");
    const size_t n = strlen(buf);
    if (n) buf[n - 1] = '\0';
    return buf;
}

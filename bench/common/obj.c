#include "obj.h"
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    void *data;
    size_t len, cap, elem;
} vec;

static int vec_push(vec *v, const void *item)
{
    if (v->len == v->cap) {
        const size_t cap = v->cap ? 2 * v->cap : 1024;
        void *d = realloc(v->data, cap * v->elem);
        if (!d) return -1;
        v->data = d;
        v->cap = cap;
    }
    memcpy((char *)v->data + v->len++ * v->elem, item, v->elem);
    return 0;
}

static char *read_file(const char *path, char *err, size_t errlen)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(err, errlen, "cannot open %s: %s", path, strerror(errno));
        return NULL;
    }
    char *buf = NULL;
    size_t len = 0, cap = 0, got;
    do {
        if (len + 65536 + 1 > cap) {
            cap = 2 * cap + 65536 + 1;
            char *b = realloc(buf, cap);
            if (!b) {
                free(buf);
                fclose(f);
                snprintf(err, errlen, "out of memory reading %s", path);
                return NULL;
            }
            buf = b;
        }
        got = fread(buf + len, 1, cap - len - 1, f);
        len += got;
    } while (got > 0);
    fclose(f);
    buf[len] = '\0';
    return buf;
}

int obj_load(const char *path, mesh *out, char *err, size_t errlen)
{
    char *text = read_file(path, err, errlen);
    if (!text) return -1;
    vec pos = {NULL, 0, 0, sizeof(double) * 3}, tri = {NULL, 0, 0, sizeof(int) * 3};
    int ok = 1, lineno = 0;
    for (char *line = text, *next; ok && line && *line; line = next) {
        next = strchr(line, '\n');
        if (next) *next++ = '\0';
        ++lineno;
        while (*line == ' ' || *line == '\t') ++line;
        if (line[0] == 'v' && (line[1] == ' ' || line[1] == '\t')) {
            double p[3];
            char *s = line + 2, *e;
            for (int a = 0; a < 3; ++a, s = e) {
                p[a] = strtod(s, &e);
                if (e == s) ok = 0;
            }
            if (ok && vec_push(&pos, p)) ok = 0;
        } else if (line[0] == 'f' && (line[1] == ' ' || line[1] == '\t')) {
            int idx[3], n = 0;
            char *s = line + 2, *e;
            for (;;) {
                const long v = strtol(s, &e, 10);
                if (e == s) break;
                const long i = v < 0 ? (long)pos.len + v : v - 1;
                if (v == 0 || i < 0 || i >= (long)pos.len) {
                    ok = 0;
                    break;
                }
                while (*e && *e != ' ' && *e != '\t' && *e != '\r') ++e; /* skip /vt/vn */
                s = e;
                if (n < 2)
                    idx[n++] = (int)i;
                else {
                    idx[2] = (int)i;
                    if (vec_push(&tri, idx)) ok = 0;
                    idx[1] = (int)i;
                }
            }
        }
        if (!ok) snprintf(err, errlen, "%s:%d: malformed record or index out of range", path, lineno);
    }
    free(text);
    if (ok && tri.len == 0) {
        snprintf(err, errlen, "%s: no triangles", path);
        ok = 0;
    }
    if (ok && mesh_alloc(out, (int)pos.len, (int)tri.len)) {
        snprintf(err, errlen, "out of memory loading %s", path);
        ok = 0;
    }
    if (ok) {
        memcpy(out->pos, pos.data, pos.elem * pos.len);
        memcpy(out->tri, tri.data, tri.elem * tri.len);
        mesh_compute_normals(out);
    }
    free(pos.data);
    free(tri.data);
    return ok ? 0 : -1;
}

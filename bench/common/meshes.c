#include "meshes.h"
#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* SHA-256 of the files in ../shared/meshes (its README), which are the repository's data/ files. */
const mesh_file meshes_known[] = {
    {"cow.obj", "69afce548640bc2beb0c44894d1a24d5766cc9cd3fd74f3ec55b4e229104b23f"},
    {"spot.obj", "0738b5e8608fed74e5e8c7aa8dd0af97b4b74f9f6cbf7aac84cd7e40b2e44a75"},
    {"stanford-bunny.obj", "1eb35d1e21ce99e5ce911353b6be278990713448dd9e8f5c9387f9de39b32205"},
    {"suzanne.obj", "d8684326f9bd8cfc24d3d302c1042fa16f63d2e66e49ed56b413fa20bed271e6"},
    {"teapot.obj", "1b5396fedd74b577e32cef41146582c2f2e1a050d5b4915193c0ac1ad4187ed4"},
};
const int meshes_count = (int)(sizeof meshes_known / sizeof meshes_known[0]);

const mesh_file *meshes_find(const char *file)
{
    for (int i = 0; i < meshes_count; ++i)
        if (!strcmp(meshes_known[i].file, file)) return &meshes_known[i];
    return NULL;
}

/* ---- SHA-256, FIPS 180-4 Sec. 6.2 ---- */

static const uint32_t K[64] = {
    0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5, 0xd807aa98, 0x12835b01,
    0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174, 0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc,
    0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da, 0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147,
    0x06ca6351, 0x14292967, 0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
    0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070, 0x19a4c116, 0x1e376c08,
    0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3, 0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208,
    0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2};

static uint32_t rotr(uint32_t x, int n) { return (x >> n) | (x << (32 - n)); }

static void block(uint32_t h[8], const unsigned char *p)
{
    uint32_t w[64];
    for (int t = 0; t < 16; ++t)
        w[t] = (uint32_t)p[4 * t] << 24 | (uint32_t)p[4 * t + 1] << 16 | (uint32_t)p[4 * t + 2] << 8 | p[4 * t + 3];
    for (int t = 16; t < 64; ++t) {
        const uint32_t s0 = rotr(w[t - 15], 7) ^ rotr(w[t - 15], 18) ^ (w[t - 15] >> 3);
        const uint32_t s1 = rotr(w[t - 2], 17) ^ rotr(w[t - 2], 19) ^ (w[t - 2] >> 10);
        w[t] = w[t - 16] + s0 + w[t - 7] + s1;
    }
    uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4], f = h[5], g = h[6], k = h[7];
    for (int t = 0; t < 64; ++t) {
        const uint32_t t1 = k + (rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25)) + ((e & f) ^ (~e & g)) + K[t] + w[t];
        const uint32_t t2 = (rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
        k = g;
        g = f;
        f = e;
        e = d + t1;
        d = c;
        c = b;
        b = a;
        a = t1 + t2;
    }
    h[0] += a, h[1] += b, h[2] += c, h[3] += d, h[4] += e, h[5] += f, h[6] += g, h[7] += k;
}

int sha256_file(const char *path, char hex[65])
{
    FILE *f = fopen(path, "rb");
    if (!f) return -1;
    uint32_t h[8] = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a, 0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
    unsigned char buf[128];
    uint64_t bytes = 0;
    size_t n;
    while ((n = fread(buf, 1, 64, f)) == 64) {
        block(h, buf);
        bytes += 64;
    }
    const int bad = ferror(f);
    fclose(f);
    if (bad) return -1;
    bytes += n;
    /* padding: 0x80, zeros, the bit length big-endian in the last 8 bytes of the last block */
    memset(buf + n, 0, sizeof buf - n);
    buf[n] = 0x80;
    const size_t total = n + 9 <= 64 ? 64 : 128;
    for (int i = 0; i < 8; ++i) buf[total - 1 - i] = (unsigned char)((bytes * 8) >> (8 * i));
    block(h, buf);
    if (total == 128) block(h, buf + 64);
    for (int i = 0; i < 8; ++i) snprintf(hex + 8 * i, 9, "%08x", (unsigned)h[i]);
    return 0;
}

int meshes_verify(const char *dir, char *err, size_t errlen)
{
    size_t len = 0;
    err[0] = '\0';
    for (int i = 0; i < meshes_count; ++i) {
        char path[1024], hex[65];
        snprintf(path, sizeof path, "%s/%s", dir, meshes_known[i].file);
        const int missing = sha256_file(path, hex) != 0;
        if ((!missing && !strcmp(hex, meshes_known[i].sha256)) || len >= errlen) continue;
        len += (size_t)snprintf(err + len, errlen - len, "  %s: %s%s%s\n", path,
                                missing ? "missing or unreadable" : "SHA-256 mismatch, got ", missing ? "" : hex,
                                missing ? "" : " (a different or modified file)");
    }
    return err[0] ? -1 : 0;
}

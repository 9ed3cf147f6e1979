#include "image.h"
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

unsigned char image_srgb8(double x)
{
    x = x > 0 ? (x < 1 ? x : 1) : 0;
    const double s = x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
    return (unsigned char)lround(255.0 * s);
}

static uint32_t crc32_update(uint32_t crc, const unsigned char *p, size_t n)
{
    uint32_t table[256];
    for (uint32_t i = 0; i < 256; ++i) {
        uint32_t c = i;
        for (int k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320u ^ (c >> 1) : c >> 1;
        table[i] = c;
    }
    for (size_t i = 0; i < n; ++i) crc = table[(crc ^ p[i]) & 0xff] ^ (crc >> 8);
    return crc;
}

static void be32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v >> 24);
    p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

static int chunk(FILE *f, const char *type, const unsigned char *data, size_t n)
{
    unsigned char hdr[8], tail[4];
    be32(hdr, (uint32_t)n);
    memcpy(hdr + 4, type, 4);
    uint32_t crc = crc32_update(0xffffffffu, hdr + 4, 4);
    crc = crc32_update(crc, data, n) ^ 0xffffffffu;
    be32(tail, crc);
    return fwrite(hdr, 1, 8, f) == 8 && fwrite(data, 1, n, f) == n && fwrite(tail, 1, 4, f) == 4 ? 0 : -1;
}

int image_write_png(const char *path, int w, int h, const float *rgb, double exposure)
{
    const size_t row = 1 + 3 * (size_t)w, raw_len = row * (size_t)h;
    const size_t nblocks = (raw_len + 65534) / 65535;
    unsigned char *raw = malloc(raw_len), *z = malloc(2 + raw_len + 5 * nblocks + 4);
    FILE *f = NULL;
    int st = -1;
    if (!raw || !z) goto done;
    for (int y = 0; y < h; ++y) {
        unsigned char *r = raw + row * (size_t)y;
        r[0] = 0; /* filter: none */
        for (size_t x = 0; x < (size_t)w; ++x) {
            const float *c = rgb + 3 * ((size_t)w * y + x);
            const double mx = fmax(c[0], fmax(c[1], c[2])) * exposure;
            const double s = mx > 1.0 ? exposure / mx : exposure; /* clip keeping the hue (bright emitters) */
            for (int k = 0; k < 3; ++k) r[1 + 3 * x + k] = image_srgb8(s * c[k]);
        }
    }
    size_t n = 0;
    z[n++] = 0x78; /* zlib: deflate, 32K window */
    z[n++] = 0x01;
    for (size_t off = 0; off < raw_len; off += 65535) {
        const size_t len = raw_len - off < 65535 ? raw_len - off : 65535;
        z[n++] = off + len >= raw_len; /* BFINAL, BTYPE 00: stored */
        z[n++] = (unsigned char)len;
        z[n++] = (unsigned char)(len >> 8);
        z[n++] = (unsigned char)~len;
        z[n++] = (unsigned char)(~len >> 8);
        memcpy(z + n, raw + off, len);
        n += len;
    }
    uint32_t a = 1, b = 0; /* Adler-32 */
    for (size_t i = 0; i < raw_len; ++i) {
        a = (a + raw[i]) % 65521;
        b = (b + a) % 65521;
    }
    be32(z + n, b << 16 | a);
    n += 4;
    unsigned char ihdr[13];
    be32(ihdr, (uint32_t)w);
    be32(ihdr + 4, (uint32_t)h);
    ihdr[8] = 8;  /* bit depth */
    ihdr[9] = 2;  /* RGB */
    ihdr[10] = ihdr[11] = ihdr[12] = 0;
    static const unsigned char srgb[1] = {0}; /* sRGB chunk: perceptual intent */
    f = fopen(path, "wb");
    if (!f) goto done;
    st = fwrite("\x89PNG\r\n\x1a\n", 1, 8, f) == 8 && !chunk(f, "IHDR", ihdr, 13) && !chunk(f, "sRGB", srgb, 1) &&
                 !chunk(f, "IDAT", z, n) && !chunk(f, "IEND", NULL, 0)
             ? 0
             : -1;
done:
    if (f && fclose(f)) st = -1;
    free(raw);
    free(z);
    return st;
}

int image_write_pfm(const char *path, int w, int h, const float *rgb)
{
    FILE *f = fopen(path, "wb");
    if (!f) return -1;
    int ok = fprintf(f, "PF\n%d %d\n-1.0\n", w, h) > 0; /* negative scale: little-endian */
    const uint16_t probe = 1;
    unsigned char little;
    memcpy(&little, &probe, 1);
    for (int y = h - 1; ok && y >= 0; --y) { /* PFM rows run bottom to top */
        const float *r = rgb + 3 * (size_t)w * y;
        if (little)
            ok = fwrite(r, sizeof(float), 3 * (size_t)w, f) == 3 * (size_t)w;
        else
            for (size_t i = 0; ok && i < 3 * (size_t)w; ++i) {
                unsigned char b[4], s[4];
                memcpy(b, r + i, 4);
                s[0] = b[3];
                s[1] = b[2];
                s[2] = b[1];
                s[3] = b[0];
                ok = fwrite(s, 1, 4, f) == 4;
            }
    }
    return fclose(f) == 0 && ok ? 0 : -1;
}

static int cmp_float(const void *a, const void *b)
{
    const float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

double image_auto_exposure(int w, int h, const float *rgb, const unsigned char *mask)
{
    float *lum = malloc(sizeof(float) * (size_t)w * (size_t)h + 1);
    if (!lum) return 1.0;
    size_t n = 0;
    for (size_t i = 0; i < (size_t)w * (size_t)h; ++i)
        if (!mask || mask[i]) lum[n++] = 0.2126f * rgb[3 * i] + 0.7152f * rgb[3 * i + 1] + 0.0722f * rgb[3 * i + 2];
    double e = 1.0;
    if (n) {
        qsort(lum, n, sizeof *lum, cmp_float);
        const double p = lum[(size_t)(0.97 * (double)(n - 1))];
        if (p > 0) e = 0.9 / p;
    }
    free(lum);
    return e;
}

image_error image_compare(int w, int h, const float *img, const float *ref, const unsigned char *mask, double exposure)
{
    image_error e = {0, 0, 0, 0, 0, 0};
    double sum = 0, sum2 = 0, sref = 0, ssrgb = 0;
    for (size_t i = 0; i < (size_t)w * (size_t)h; ++i) {
        if (mask && !mask[i]) continue;
        ++e.pixels;
        for (int c = 0; c < 3; ++c) {
            const double d = fabs((double)img[3 * i + c] - ref[3 * i + c]);
            sum += d;
            sum2 += d * d;
            sref += fabs(ref[3 * i + c]);
            e.max_abs = fmax(e.max_abs, d);
            ssrgb += abs((int)image_srgb8(exposure * img[3 * i + c]) - (int)image_srgb8(exposure * ref[3 * i + c])) / 255.0;
        }
    }
    if (e.pixels) {
        const double n = 3.0 * (double)e.pixels;
        e.mae = sum / n;
        e.rmse = sqrt(sum2 / n);
        e.mean_ref = sref / n;
        e.mae_srgb = ssrgb / n;
    }
    return e;
}

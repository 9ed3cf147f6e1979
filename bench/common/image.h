/* Images: PNG (8-bit sRGB; zlib stream of stored deflate blocks) and PFM
 * (linear float) writers, exposure, and image error metrics. */
#ifndef SHL_BENCH_IMAGE_H
#define SHL_BENCH_IMAGE_H

/* rgb: w*h*3 linear floats, rows top to bottom.  PNG: exposure * rgb, a pixel whose
 * largest channel exceeds 1 scaled down to 1 (keeps the hue), sRGB-encoded.  0 or -1. */
int image_write_png(const char *path, int w, int h, const float *rgb, double exposure);
int image_write_pfm(const char *path, int w, int h, const float *rgb);
/* 8-bit sRGB value of exposure * linear value (clamped). */
unsigned char image_srgb8(double linear);

/* Exposure mapping the 97th percentile of the luminance of the masked pixels to 0.9. */
double image_auto_exposure(int w, int h, const float *rgb, const unsigned char *mask);

typedef struct {
    long pixels;        /* masked pixels compared */
    double mae, rmse;   /* linear radiance, over pixels and channels */
    double mean_ref;    /* mean |reference| */
    double mae_srgb;    /* mean |difference| of the 8-bit sRGB images, in [0, 1] units */
    double max_abs;     /* largest linear difference */
} image_error;

/* Compare img with ref on the pixels where mask != 0 (all if mask is NULL). */
image_error image_compare(int w, int h, const float *img, const float *ref, const unsigned char *mask, double exposure);

#endif

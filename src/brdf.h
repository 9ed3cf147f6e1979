/* Internal declarations of the BRDF tables (brdf.c). */
#ifndef SHL_BRDF_H
#define SHL_BRDF_H

#include "internal.h"

struct shl_brdf_table {
    int lmax, nc, ntheta;
    double *data; /* sample j: F at data + 2 j nc, F' at data + (2 j + 1) nc */
};

/* Local frame (rows x, y, z) from the unit normal and unit outgoing direction. */
void shl__brdf_frame(const double n[3], const double wo[3], double frame[9]);
/* F and F' (either may be NULL) at the outgoing angle with cosine cos_o and
 * sine sin_o >= 0: interpolated; zero when cos_o <= 0. */
void shl__brdf_table_at(const shl_brdf_table *t, double cos_o, double sin_o, double *f_cos,
                        double *f);

#endif

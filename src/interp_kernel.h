/* Interpolation of all 3 nc coefficients at one point from the 8 corners of
 * its cell, for grid storage ELEM (float or double; interp.c instantiates
 * this file once per type, SUFFIX names the instance).  Arithmetic in double.
 * Corner j = ix + 2 iy + 4 iz (Wu 2020 Alg. 4 numbering); node data layout in
 * grid.h: value of channel c nc + k at [c nc + k], d/dx_a at [3 nc + (3 c + a) nc + k].
 * The loops run over k with unit stride in every array (vectorizable). */

static void SUFFIX(trilinear)(const ELEM *const f[8], const point_setup *s, int nc, double *restrict out)
{
    double w[8];
    for (int j = 0; j < 8; ++j) w[j] = s->w[j];
    for (int i = 0; i < 3 * nc; ++i) {
        double v = 0.0;
        for (int j = 0; j < 8; ++j) v += w[j] * f[j][i];
        out[i] = v;
    }
}

/* Annen 2004 Eq. (15): sum_j w_j (c_j + grad c_j . d_j), d_j = p - p_j, weights of Eq. (16). */
static void SUFFIX(taylor)(const ELEM *const f[8], const point_setup *s, int nc, double *restrict out)
{
    for (int c = 0; c < 3; ++c) {
        double *restrict o = out + c * nc;
        for (int k = 0; k < nc; ++k) o[k] = 0.0;
        for (int j = 0; j < 8; ++j) {
            const ELEM *restrict v = f[j] + c * nc, *restrict gx = f[j] + 3 * nc + 3 * c * nc;
            const ELEM *restrict gy = gx + nc, *restrict gz = gx + 2 * nc;
            const double w = s->w[j], dx = s->wd[j][0], dy = s->wd[j][1], dz = s->wd[j][2];
            for (int k = 0; k < nc; ++k) o[k] += w * v[k] + dx * gx[k] + dy * gy[k] + dz * gz[k];
        }
    }
}

/* Wu 2020 Alg. 4: 1D cubic Hermite along x, then y, then z (Eq. 33-35 in the
 * Hermite basis hw); the gradients carried to the next axis are interpolated
 * linearly (lines 6 and 10). */
static void SUFFIX(hermite)(const ELEM *const f[8], const point_setup *s, int nc, double *restrict out)
{
    const double x0 = s->hw[0][0], x1 = s->hw[0][1], x2 = s->hw[0][2], x3 = s->hw[0][3];
    const double y0 = s->hw[1][0], y1 = s->hw[1][1], y2 = s->hw[1][2], y3 = s->hw[1][3];
    const double z0 = s->hw[2][0], z1 = s->hw[2][1], z2 = s->hw[2][2], z3 = s->hw[2][3];
    const double ux = s->u[0], uy = s->u[1], vx = 1.0 - ux, vy = 1.0 - uy;
    for (int c = 0; c < 3; ++c) {
        const ELEM *restrict v[8], *restrict gx[8];
        for (int j = 0; j < 8; ++j) {
            v[j] = f[j] + c * nc;
            gx[j] = f[j] + 3 * nc + 3 * c * nc; /* d/dy at gx + nc, d/dz at gx + 2 nc */
        }
        for (int k = 0; k < nc; ++k) {
            double g[4], g_y[4], g_z[4];
            for (int q = 0; q < 4; ++q) { /* lines 4-7: along x, corners 2q and 2q+1 */
                const int a = 2 * q, b = 2 * q + 1;
                g[q] = x0 * v[a][k] + x1 * gx[a][k] + x2 * v[b][k] + x3 * gx[b][k];
                g_y[q] = vx * gx[a][k + nc] + ux * gx[b][k + nc];
                g_z[q] = vx * gx[a][k + 2 * nc] + ux * gx[b][k + 2 * nc];
            }
            /* lines 8-11: along y; line 12: along z */
            const double h0 = y0 * g[0] + y1 * g_y[0] + y2 * g[1] + y3 * g_y[1];
            const double h1 = y0 * g[2] + y1 * g_y[2] + y2 * g[3] + y3 * g_y[3];
            const double h0_z = vy * g_z[0] + uy * g_z[1], h1_z = vy * g_z[2] + uy * g_z[3];
            out[c * nc + k] = z0 * h0 + z1 * h0_z + z2 * h1 + z3 * h1_z;
        }
    }
}

/* The next point's rows (ahead) are all requested first: one block. */
static void SUFFIX(interp)(const ELEM *data, int method, int nc, const point_setup *s, shl__interp_ahead *ahead,
                           double *restrict out)
{
    shl__interp_ahead_plan(ahead, 1);
    shl__interp_ahead_step(ahead);
    const ELEM *f[8];
    for (int j = 0; j < 8; ++j) f[j] = data + s->ofs[j];
    if (method == SHL_INTERP_TRILINEAR)
        SUFFIX(trilinear)(f, s, nc, out);
    else if (method == SHL_INTERP_TAYLOR)
        SUFFIX(taylor)(f, s, nc, out);
    else
        SUFFIX(hermite)(f, s, nc, out);
}

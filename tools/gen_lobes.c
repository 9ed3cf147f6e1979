/* Generates src/zh_tables.c on stdout (lobe directions and weights of the
 * sparse ZH rotation, layout in src/zh_tables.h) and a report on stderr.
 *
 * Band l's matrix A_l[d][m] = Y_lm(d_d), d < 2l+1, is orthogonally equivalent
 * (rows of a mirror pair -> their sum and difference over sqrt2) to
 * diag(E', O'): E' has rows Y_lm(d_0), sqrt2 Y_lm(d_2k-1) (m >= 0), O' rows
 * sqrt2 Y_l,-m(d_2k-1) (m >= 1); cond(A_l) comes from the two blocks.
 *
 * Search, for each of NSTART angles of d_0 in the xz-plane: greedy choice of
 * pair k (band k's cond) from a candidate set, then L-BFGS on a smooth
 * surrogate of max_l cond(A_l) (soft maxima over bands and singular values)
 * whose sharpness doubles stage by stage.  The best start is kept; the whole
 * search is deterministic. */
#include "internal.h"
#include "zh_tables.h"
#include "sh_basis.h"
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#define LMAX SHL_LMAX_MAX
#define NSH SHL_NCOEFFS(LMAX)
#define NB (LMAX + 1)           /* pairs + 1 = largest block size */
#define NFULL SHL__ZH_NDIR      /* largest full band matrix size */
#define NPAR (1 + 3 * LMAX)     /* d_0 angle, then one 3-vector per pair */
#define NCAND 400               /* Fibonacci sphere points; those with y > 0 are candidates */
#define NSTART 4                /* angles of d_0 tried */
#define NSTAGE 5                /* surrogate sharpness 8, 16, ..., 128 */
#define MEM 8                   /* L-BFGS memory */
#define JTOL 1e-12              /* Jacobi: columns orthogonal to this relative level */

/* One-sided Jacobi SVD of the n x n column-major a.  On return sig holds the
 * singular values, a = U diag(sig) and, if v is not NULL, v = V (column-major). */
static void svd(int n, double *a, double *v, double *sig)
{
    if (v)
        for (int i = 0; i < n * n; ++i) v[i] = (i % (n + 1) == 0);
    for (int sweep = 0, rotated = 1; rotated && sweep < 100; ++sweep) {
        rotated = 0;
        for (int i = 0; i < n - 1; ++i) {
            double *ai = a + i * n;
            for (int j = i + 1; j < n; ++j) {
                double *aj = a + j * n, al = 0.0, be = 0.0, ga = 0.0;
                for (int r = 0; r < n; ++r) {
                    al += ai[r] * ai[r];
                    be += aj[r] * aj[r];
                    ga += ai[r] * aj[r];
                }
                if (fabs(ga) <= JTOL * sqrt(al * be)) continue;
                rotated = 1;
                const double zeta = (be - al) / (2.0 * ga);
                const double t = copysign(1.0, zeta) / (fabs(zeta) + sqrt(1.0 + zeta * zeta));
                const double c = 1.0 / sqrt(1.0 + t * t), s = c * t;
                for (int r = 0; r < n; ++r) {
                    const double x = ai[r], y = aj[r];
                    ai[r] = c * x - s * y;
                    aj[r] = s * x + c * y;
                }
                for (int r = 0; v && r < n; ++r) {
                    const double x = v[i * n + r], y = v[j * n + r];
                    v[i * n + r] = c * x - s * y;
                    v[j * n + r] = s * x + c * y;
                }
            }
        }
    }
    for (int i = 0; i < n; ++i) {
        double s = 0.0;
        for (int r = 0; r < n; ++r) s += a[i * n + r] * a[i * n + r];
        sig[i] = sqrt(s);
    }
}

static double sig_ratio(int n, const double *sig)
{
    double lo = HUGE_VAL, hi = 0.0;
    for (int i = 0; i < n; ++i) {
        lo = fmin(lo, sig[i]);
        hi = fmax(hi, sig[i]);
    }
    return hi / lo;
}

/* SVD of band l's blocks E' (into e, ve) and O' (into o, vo); ys[0] = Y(d_0),
 * ys[k] = Y(d_2k-1).  sig gets E''s l+1 singular values, then O''s l. */
static void band_svd(int l, const double (*ys)[NSH], double *e, double *ve, double *o, double *vo,
                     double *sig)
{
    const int b = l * (l + 1), n = l + 1;
    for (int m = 0; m <= l; ++m)
        for (int k = 0; k <= l; ++k) e[m * n + k] = (k ? M_SQRT2 : 1.0) * ys[k][b + m];
    for (int m = 1; m <= l; ++m)
        for (int k = 1; k <= l; ++k) o[(m - 1) * l + k - 1] = M_SQRT2 * ys[k][b - m];
    svd(n, e, ve, sig);
    svd(l, o, vo, sig + n);
}

static double band_cond(int l, const double (*ys)[NSH])
{
    double e[NB * NB], o[NB * NB], sig[NFULL];
    band_svd(l, ys, e, NULL, o, NULL, sig);
    return sig_ratio(2 * l + 1, sig);
}

/* cond(A_l) from the full matrix over all 2l+1 directions (cross-check). */
static double band_cond_full(int l, const double (*dirs)[3])
{
    static double a[NFULL * NFULL];
    double y[NSH], sig[NFULL];
    const int n = 2 * l + 1, b = l * (l + 1);
    for (int d = 0; d < n; ++d) {
        shl__sh_eval(l, dirs[d][0], dirs[d][1], dirs[d][2], y);
        for (int m = -l; m <= l; ++m) a[(m + l) * n + d] = y[b + m];
    }
    svd(n, a, NULL, sig);
    return sig_ratio(n, sig);
}

/* Orthonormal tangent directions at the unit vector d; for rep 0 (d_0, kept
 * in the xz-plane) only t[0] is used. */
static void tangents(int k, const double d[3], double t[2][3])
{
    if (k == 0) {
        const double t0[2][3] = {{d[2], 0.0, -d[0]}, {0.0, 0.0, 0.0}};
        memcpy(t, t0, sizeof t0);
        return;
    }
    const int a = fabs(d[0]) < fabs(d[1]) ? (fabs(d[0]) < fabs(d[2]) ? 0 : 2) : (fabs(d[1]) < fabs(d[2]) ? 1 : 2);
    double e[3] = {0.0, 0.0, 0.0};
    e[a] = 1.0;
    t[0][0] = e[1] * d[2] - e[2] * d[1];
    t[0][1] = e[2] * d[0] - e[0] * d[2];
    t[0][2] = e[0] * d[1] - e[1] * d[0];
    const double r = sqrt(t[0][0] * t[0][0] + t[0][1] * t[0][1] + t[0][2] * t[0][2]);
    for (int i = 0; i < 3; ++i) t[0][i] /= r;
    t[1][0] = d[1] * t[0][2] - d[2] * t[0][1];
    t[1][1] = d[2] * t[0][0] - d[0] * t[0][2];
    t[1][2] = d[0] * t[0][1] - d[1] * t[0][0];
}

/* Y at normalize(d + h t). */
static void eval_moved(const double d[3], const double t[3], double h, double *y)
{
    double v[3], r = 0.0;
    for (int i = 0; i < 3; ++i) {
        v[i] = d[i] + h * t[i];
        r += v[i] * v[i];
    }
    r = sqrt(r);
    shl__sh_eval(LMAX, v[0] / r, v[1] / r, v[2] / r, y);
}

/* Smooth surrogate of log sum_l cond(A_l)^p, with band l's cond replaced by
 * (sum_i s_i^p)^(1/p) (sum_i s_i^-p)^(1/p) over its singular values s_i, and
 * its derivative w.r.t. the tangent coordinates of each rep (SVD perturbation
 * d s_i = u_i^T dA v_i, dY by central differences). */
static double surrogate(const double (*dirs)[3], const double (*ys)[NSH], double p, double (*grad)[2])
{
    static double dy[NB][2][NSH], gband[NB][NB][2];
    double lc[NB];
    for (int k = 0; k < NB; ++k) {
        double t[2][3], yp[NSH], ym[NSH];
        const double h = 1e-5;
        tangents(k, dirs[k], t);
        for (int j = 0; j < 2; ++j) {
            eval_moved(dirs[k], t[j], h, yp);
            eval_moved(dirs[k], t[j], -h, ym);
            for (int i = 0; i < NSH; ++i) dy[k][j][i] = (yp[i] - ym[i]) / (2.0 * h);
        }
    }
    lc[0] = 0.0;
    for (int l = 1; l <= LMAX; ++l) {
        double e[NB * NB], o[NB * NB], ve[NB * NB], vo[NB * NB], sig[NFULL], w[NFULL];
        const int b = l * (l + 1), n = l + 1, ns = 2 * l + 1;
        band_svd(l, ys, e, ve, o, vo, sig);
        double smax = 0.0, smin = HUGE_VAL, sa = 0.0, sb = 0.0;
        for (int i = 0; i < ns; ++i) {
            smax = fmax(smax, sig[i]);
            smin = fmin(smin, sig[i]);
        }
        for (int i = 0; i < ns; ++i) {
            sa += pow(sig[i] / smax, p);
            sb += pow(smin / sig[i], p);
        }
        lc[l] = log(smax / smin) + (log(sa) + log(sb)) / p;
        /* d lc / d s_i, over s_i once more: e, o hold U diag(s), not U */
        for (int i = 0; i < ns; ++i)
            w[i] = (pow(sig[i] / smax, p) / sa - pow(smin / sig[i], p) / sb) / (sig[i] * sig[i]);
        for (int k = 0; k <= l; ++k)
            for (int j = 0; j < 2; ++j) {
                double g = 0.0;
                for (int i = 0; i < n; ++i) {
                    double dv = 0.0;
                    for (int m = 0; m <= l; ++m) dv += ve[i * n + m] * dy[k][j][b + m];
                    g += w[i] * e[i * n + k] * dv;
                }
                for (int i = 0; k > 0 && i < l; ++i) {
                    double dv = 0.0;
                    for (int m = 1; m <= l; ++m) dv += vo[i * l + m - 1] * dy[k][j][b - m];
                    g += w[n + i] * o[i * l + k - 1] * dv;
                }
                gband[l][k][j] = (k ? M_SQRT2 : 1.0) * g;
            }
    }
    double mx = 0.0, sum = 0.0;
    for (int l = 0; l <= LMAX; ++l) mx = fmax(mx, p * lc[l]);
    for (int l = 0; l <= LMAX; ++l) sum += exp(p * lc[l] - mx);
    const double f = mx + log(sum);
    for (int k = 0; k < NB; ++k)
        for (int j = 0; j < 2; ++j) {
            grad[k][j] = 0.0;
            for (int l = k > 1 ? k : 1; l <= LMAX; ++l) grad[k][j] += p * exp(p * lc[l] - f) * gband[l][k][j];
        }
    return f;
}

/* Directions and their Y from the parameter vector x. */
static void unpack(const double *x, double (*dirs)[3], double (*ys)[NSH])
{
    dirs[0][0] = sin(x[0]);
    dirs[0][1] = 0.0;
    dirs[0][2] = cos(x[0]);
    for (int k = 1; k < NB; ++k) {
        const double *v = x + 3 * k - 2;
        const double r = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (int i = 0; i < 3; ++i) dirs[k][i] = v[i] / r;
    }
    for (int k = 0; k < NB; ++k) shl__sh_eval(LMAX, dirs[k][0], dirs[k][1], dirs[k][2], ys[k]);
}

static double objective(const double *x, double p, double *gx)
{
    static double dirs[NB][3], ys[NB][NSH];
    double g[NB][2];
    unpack(x, dirs, ys);
    const double f = surrogate((const double(*)[3])dirs, (const double(*)[NSH])ys, p, g);
    gx[0] = g[0][0];
    for (int k = 1; k < NB; ++k) {
        double t[2][3];
        const double *v = x + 3 * k - 2;
        const double r = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        tangents(k, dirs[k], t);
        for (int i = 0; i < 3; ++i) gx[3 * k - 2 + i] = (g[k][0] * t[0][i] + g[k][1] * t[1][i]) / r;
    }
    return f;
}

static double dot(const double *a, const double *b)
{
    double s = 0.0;
    for (int i = 0; i < NPAR; ++i) s += a[i] * b[i];
    return s;
}

/* Minimize the surrogate with sharpness p from x: L-BFGS, backtracking Armijo
 * line search; stops after 5 steps with relative decrease < 1e-7. */
static void lbfgs(double *x, double p)
{
    static double sm[MEM][NPAR], ym[MEM][NPAR];
    double rho[MEM], al[MEM], g[NPAR], gn[NPAR], d[NPAR], xn[NPAR];
    int nmem = 0, head = 0, stall = 0;
    double f = objective(x, p, g);
    for (int it = 0; it < 2000 && stall < 5; ++it) {
        memcpy(d, g, sizeof d);
        for (int j = 0; j < nmem; ++j) {
            const int i = (head - 1 - j + MEM) % MEM;
            al[i] = rho[i] * dot(sm[i], d);
            for (int c = 0; c < NPAR; ++c) d[c] -= al[i] * ym[i][c];
        }
        const int last = (head - 1 + MEM) % MEM;
        const double gamma = nmem ? dot(sm[last], ym[last]) / dot(ym[last], ym[last]) : 1e-3 / sqrt(dot(g, g));
        for (int c = 0; c < NPAR; ++c) d[c] *= gamma;
        for (int j = nmem - 1; j >= 0; --j) {
            const int i = (head - 1 - j + MEM) % MEM;
            const double be = rho[i] * dot(ym[i], d);
            for (int c = 0; c < NPAR; ++c) d[c] += (al[i] - be) * sm[i][c];
        }
        const double slope = -dot(g, d);
        double t = 1.0, fn = f;
        int ok = 0;
        for (int ls = 0; ls < 40 && !ok && slope < 0.0; ++ls, t *= 0.5) {
            for (int c = 0; c < NPAR; ++c) xn[c] = x[c] - t * d[c];
            fn = objective(xn, p, gn);
            ok = fn <= f + 1e-4 * t * slope;
        }
        if (!ok) {
            if (nmem == 0) break;
            nmem = 0; /* retry along the gradient */
            continue;
        }
        for (int c = 0; c < NPAR; ++c) {
            sm[head][c] = xn[c] - x[c];
            ym[head][c] = gn[c] - g[c];
        }
        const double sy = dot(sm[head], ym[head]);
        if (sy > 0.0) {
            rho[head] = 1.0 / sy;
            head = (head + 1) % MEM;
            if (nmem < MEM) ++nmem;
        }
        stall = f - fn < 1e-7 * fabs(f) ? stall + 1 : 0;
        memcpy(x, xn, sizeof xn);
        memcpy(g, gn, sizeof gn);
        f = fn;
    }
}

/* Given d_0, choose pair k = 1..LMAX from the candidates minimizing cond(A_k). */
static void greedy(int ncand, const double (*cand)[3], const double *cand_y, double (*dirs)[3],
                   double (*ys)[NSH])
{
    for (int l = 1; l <= LMAX; ++l) {
        int best = 0;
        double best_cond = HUGE_VAL;
        for (int c = 0; c < ncand; ++c) {
            memcpy(ys[l], cand_y + (size_t)c * NSH, sizeof ys[l]);
            const double cn = band_cond(l, (const double(*)[NSH])ys);
            if (cn < best_cond) {
                best_cond = cn;
                best = c;
            }
        }
        memcpy(dirs[l], cand[best], sizeof dirs[l]);
        memcpy(ys[l], cand_y + (size_t)best * NSH, sizeof ys[l]);
    }
}

static double max_cond(const double (*ys)[NSH], double *cond)
{
    double mx = 0.0;
    for (int l = 0; l <= LMAX; ++l) {
        cond[l] = band_cond(l, ys);
        mx = fmax(mx, cond[l]);
    }
    return mx;
}

/* In-place inverse of the n x n row-major a (Gauss-Jordan, partial pivoting). */
static void invert(int n, double *a)
{
    int piv[NB];
    for (int c = 0; c < n; ++c) {
        int p = c;
        for (int r = c + 1; r < n; ++r)
            if (fabs(a[r * n + c]) > fabs(a[p * n + c])) p = r;
        piv[c] = p;
        for (int j = 0; j < n; ++j) {
            const double tmp = a[c * n + j];
            a[c * n + j] = a[p * n + j];
            a[p * n + j] = tmp;
        }
        const double inv = 1.0 / a[c * n + c];
        a[c * n + c] = 1.0;
        for (int j = 0; j < n; ++j) a[c * n + j] *= inv;
        for (int r = 0; r < n; ++r) {
            if (r == c) continue;
            const double f = a[r * n + c];
            a[r * n + c] = 0.0;
            for (int j = 0; j < n; ++j) a[r * n + j] -= f * a[c * n + j];
        }
    }
    for (int c = n - 1; c >= 0; --c)
        for (int r = 0; piv[c] != c && r < n; ++r) {
            const double tmp = a[r * n + c];
            a[r * n + c] = a[r * n + piv[c]];
            a[r * n + piv[c]] = tmp;
        }
}

/* w = (c_l M)^-1 for the n x n row-major m; returns max |(c_l M) w - I|. */
static double weights(int n, double cl, const double *m, double *w)
{
    double res = 0.0;
    for (int i = 0; i < n * n; ++i) w[i] = cl * m[i];
    invert(n, w);
    for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c) {
            double s = -(double)(r == c);
            for (int k = 0; k < n; ++k) s += cl * m[r * n + k] * w[k * n + c];
            res = fmax(res, fabs(s));
        }
    return res;
}

static void print_values(const double *v, int n)
{
    for (int i = 0; i < n; ++i) printf("%s%.17g,%s", i % 4 ? " " : "    ", v[i], i % 4 == 3 || i == n - 1 ? "\n" : "");
}

/* v[i] as X(v[i]), four to a line, each line continuing a macro definition. */
static void print_list(const double *v, int n)
{
    for (int i = 0; i < n; ++i)
        printf("%sX(%.17g),%s", i % 4 ? " " : "    ", v[i], i % 4 == 3 || i == n - 1 ? " \\\n" : "");
}

int main(void)
{
    const clock_t t_start = clock();
    static double cand[NCAND][3], cand_y[NCAND * NSH], dirs[NB][3], ys[NB][NSH];
    static double even_w[SHL__ZH_EVEN_SIZE], odd_w[SHL__ZH_ODD_SIZE];
    double x[NPAR], best_x[NPAR], cond[NB], best = HUGE_VAL;

    int ncand = 0;
    for (int i = 0; i < NCAND; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / NCAND, s = sqrt(1.0 - z * z);
        const double phi = i * M_PI * (3.0 - sqrt(5.0));
        if (s * sin(phi) < 1e-3) continue;
        cand[ncand][0] = s * cos(phi);
        cand[ncand][1] = s * sin(phi);
        cand[ncand][2] = z;
        shl__sh_eval(LMAX, cand[ncand][0], cand[ncand][1], cand[ncand][2], cand_y + (size_t)ncand * NSH);
        ++ncand;
    }
    for (int s = 0; s < NSTART; ++s) {
        x[0] = s * M_PI / (2 * NSTART);
        dirs[0][0] = sin(x[0]);
        dirs[0][1] = 0.0;
        dirs[0][2] = cos(x[0]);
        shl__sh_eval(LMAX, dirs[0][0], dirs[0][1], dirs[0][2], ys[0]);
        greedy(ncand, (const double(*)[3])cand, cand_y, dirs, ys);
        const double c0 = max_cond((const double(*)[NSH])ys, cond);
        for (int k = 1; k < NB; ++k) memcpy(x + 3 * k - 2, dirs[k], sizeof dirs[k]);
        for (int st = 0; st < NSTAGE; ++st) lbfgs(x, 8.0 * (1 << st));
        unpack(x, dirs, ys);
        const double c1 = max_cond((const double(*)[NSH])ys, cond);
        fprintf(stderr, "start %d (d_0 at %.4f rad): max cond greedy %.3f, refined %.3f (%.1f s)\n", s, x[0], c0, c1,
                (double)(clock() - t_start) / CLOCKS_PER_SEC);
        if (c1 < best) {
            best = c1;
            memcpy(best_x, x, sizeof x);
        }
    }

    /* Final table: pair reps with y > 0, mirrors with exactly -y. */
    unpack(best_x, dirs, ys);
    double dir[SHL__ZH_NDIR][3];
    memcpy(dir[0], dirs[0], sizeof dir[0]);
    for (int k = 1; k < NB; ++k) {
        if (dirs[k][1] < 0.0) dirs[k][1] = -dirs[k][1];
        memcpy(dir[2 * k - 1], dirs[k], sizeof dir[0]);
        dir[2 * k][0] = dirs[k][0];
        dir[2 * k][1] = -dirs[k][1];
        dir[2 * k][2] = dirs[k][2];
        shl__sh_eval(LMAX, dirs[k][0], dirs[k][1], dirs[k][2], ys[k]);
    }
    best = max_cond((const double(*)[NSH])ys, cond);

    double max_res = 0.0, max_diff = 0.0;
    int total_nz = 0;
    fprintf(stderr, " l   cond      nonzero  max|w|\n");
    for (int l = 0; l <= LMAX; ++l) {
        double e[NB * NB], o[NB * NB];
        const int b = l * (l + 1), n = l + 1;
        const double cl = sqrt(4.0 * M_PI / (2.0 * l + 1.0));
        double *we = even_w + SHL__ZH_EVEN_OFS(l), *wo = odd_w + SHL__ZH_ODD_OFS(l);
        for (int k = 0; k <= l; ++k)
            for (int m = 0; m <= l; ++m) e[k * n + m] = (k ? 2.0 : 1.0) * ys[k][b + m];
        for (int k = 1; k <= l; ++k)
            for (int m = 1; m <= l; ++m) o[(k - 1) * l + m - 1] = 2.0 * ys[k][b - m];
        max_res = fmax(max_res, weights(n, cl, e, we));
        if (l > 0) max_res = fmax(max_res, weights(l, cl, o, wo));
        int nz = 0;
        double wmax = 0.0;
        for (int i = 0; i < n * n; ++i) {
            nz += we[i] != 0.0;
            wmax = fmax(wmax, fabs(we[i]));
        }
        for (int i = 0; i < l * l; ++i) {
            nz += wo[i] != 0.0;
            wmax = fmax(wmax, fabs(wo[i]));
        }
        total_nz += nz;
        const double full = band_cond_full(l, (const double(*)[3])dir);
        max_diff = fmax(max_diff, fabs(full - cond[l]) / cond[l]);
        fprintf(stderr, "%2d %9.4f %8d  %.4g\n", l, cond[l], nz, wmax);
    }
    fprintf(stderr, "max cond %.4f; %d nonzero weights; max |(cM)W - I| %.3g;\n"
                    "block vs full-matrix cond: max relative difference %.3g; %.1f s\n",
            best, total_nz, max_res, max_diff, (double)(clock() - t_start) / CLOCKS_PER_SEC);

    printf("/* Generated by tools/gen_lobes.c -- do not edit; regenerate with `make lobes`.\n"
           " * Lobe directions and sparse ZH rotation weights (double, and their float copies), layout in zh_tables.h.\n"
           " * cond(A_l), A_l[d][m] = Y_lm(dir[d]), d < 2l+1, for l = 0..%d (max %.4f):\n *",
           LMAX, best);
    for (int l = 0; l <= LMAX; ++l) printf(" %.2f%s", cond[l], l == LMAX ? "\n" : l % 10 == 9 ? "\n *" : "");
    /* Each list once, instantiated as double and as its float rounding (the float kernels'
     * copies: simd/, src/polygon.c); a double literal converted to float is the float
     * rounding of the double it denotes. */
    printf(" */\n#include \"zh_tables.h\"\n\n#define DIR_LIST(X) \\\n");
    for (int d = 0; d < SHL__ZH_NDIR; ++d)
        printf("    {X(%.17g), X(%.17g), X(%.17g)}, \\\n", dir[d][0], dir[d][1], dir[d][2]);
    printf("\n#define EVEN_LIST(X) \\\n");
    for (int l = 0; l <= LMAX; ++l) {
        printf("    /* l = %d */ \\\n", l);
        print_list(even_w + SHL__ZH_EVEN_OFS(l), (l + 1) * (l + 1));
    }
    printf("\n#define ODD_LIST(X) \\\n");
    for (int l = 1; l <= LMAX; ++l) {
        printf("    /* l = %d */ \\\n", l);
        print_list(odd_w + SHL__ZH_ODD_OFS(l), l * l);
    }
    printf("\n#define AS_DOUBLE(v) v\n#define AS_FLOAT(v) (float)(v)\n\n"
           "const double shl__zh_dir[SHL__ZH_NDIR][3] = {DIR_LIST(AS_DOUBLE)};\n"
           "const double shl__zh_even_w[SHL__ZH_EVEN_SIZE] = {EVEN_LIST(AS_DOUBLE)};\n"
           "const double shl__zh_odd_w[SHL__ZH_ODD_SIZE] = {ODD_LIST(AS_DOUBLE)};\n"
           "const float shl__zh_dir_f[SHL__ZH_NDIR][3] = {DIR_LIST(AS_FLOAT)};\n"
           "const float shl__zh_even_w_f[SHL__ZH_EVEN_SIZE] = {EVEN_LIST(AS_FLOAT)};\n"
           "const float shl__zh_odd_w_f[SHL__ZH_ODD_SIZE] = {ODD_LIST(AS_FLOAT)};\n\n"
           "const double shl__zh_cond[SHL_LMAX_MAX + 1] = {\n");
    print_values(cond, NB);
    printf("};\n");
    return 0;
}

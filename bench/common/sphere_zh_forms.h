/* ZH of a cap (half-angle a, c = cos a) three ways, for bench_sphere.c: every
 * arithmetic operation goes through ADD/SUB/MUL so that one instantiation
 * counts them (HVL Fig. 6 convention: per-band constants are precomputed and
 * cost nothing; a multiplication by a constant counts).  Included twice, with
 * FN(name) naming the instance.  Tables rec_a, rec_b, k14, kst and SQRT_PI come
 * from bench_sphere.c. */

/* HVL Eq. (14) as printed: Legendre recurrence, then the difference. */
static void FN(zh_eq14)(int lmax, double c, double *z)
{
    double p_prev = 1.0, p = c;
    z[0] = SUB(SQRT_PI, MUL(SQRT_PI, c));
    for (int l = 1; l <= lmax; ++l) {
        const double p_next = SUB(MUL(rec_a[l], MUL(c, p)), MUL(rec_b[l], p_prev));
        z[l] = MUL(k14[l], SUB(p_prev, p_next));
        p_prev = p;
        p = p_next;
    }
}

/* The library's cancellation-free form: z_l = sqrt(pi(2l+1))/(l(l+1)) sin^2 a P_l'(c),
 * with 1 - c and sin^2 a given (t, s2). */
static void FN(zh_stable)(int lmax, double c, double t, double s2, double *z)
{
    double p_prev = 1.0, p = c, dp_prev = 0.0, dp = 1.0;
    z[0] = MUL(SQRT_PI, t);
    for (int l = 1; l <= lmax; ++l) {
        z[l] = MUL(MUL(kst[l], s2), dp);
        const double p_next = SUB(MUL(rec_a[l], MUL(c, p)), MUL(rec_b[l], p_prev));
        const double dp_next = ADD(dp_prev, MUL(2.0 * l + 1.0, p));
        p_prev = p;
        p = p_next;
        dp_prev = dp;
        dp = dp_next;
    }
}

/* Closed forms per band (Sloan 2008 style: prefactor x sin^2 a x a polynomial in
 * cos a, c^2 and sin^2 a shared), written out for bands 0..9. */
static void FN(zh_closed)(int lmax, double c, double *z)
{
    const double c2 = MUL(c, c), s2 = SUB(1.0, c2);
    z[0] = SUB(SQRT_PI, MUL(SQRT_PI, c));
    if (lmax < 1) return;
    z[1] = MUL(cf[1], s2);
    if (lmax < 2) return;
    z[2] = MUL(MUL(cf[2], c), s2);
    if (lmax < 3) return;
    z[3] = MUL(MUL(cf[3], SUB(MUL(5.0, c2), 1.0)), s2);
    if (lmax < 4) return;
    z[4] = MUL(MUL(MUL(cf[4], c), SUB(MUL(7.0, c2), 3.0)), s2);
    if (lmax < 5) return;
    z[5] = MUL(MUL(cf[5], ADD(MUL(SUB(MUL(21.0, c2), 14.0), c2), 1.0)), s2);
    if (lmax < 6) return;
    z[6] = MUL(MUL(MUL(cf[6], c), ADD(MUL(SUB(MUL(33.0, c2), 30.0), c2), 5.0)), s2);
    if (lmax < 7) return;
    z[7] = MUL(MUL(cf[7], SUB(MUL(ADD(MUL(SUB(MUL(429.0, c2), 495.0), c2), 135.0), c2), 5.0)), s2);
    if (lmax < 8) return;
    z[8] = MUL(MUL(MUL(cf[8], c), SUB(MUL(ADD(MUL(SUB(MUL(715.0, c2), 1001.0), c2), 385.0), c2), 35.0)), s2);
    if (lmax < 9) return;
    z[9] = MUL(MUL(cf[9], ADD(MUL(SUB(MUL(ADD(MUL(SUB(MUL(2431.0, c2), 4004.0), c2), 2002.0), c2), 308.0), c2), 7.0)),
               s2);
}

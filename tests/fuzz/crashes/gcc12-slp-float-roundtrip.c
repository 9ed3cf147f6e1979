/* GCC 12.2 (Debian 12.2.0-14) -O2 on x86-64: the SLP vectorizer drops the rounding of
 * a double -> float -> double round trip done in a 3-element loop (x below stays
 * unrounded; verts, 18 elements, is rounded).  gcc -O2 gcc12-slp-float-roundtrip.c && ./a.out
 * prints x 0x1.4802d606cbd67p+0 instead of 0x1.4802d6p+0; -O0, -fno-tree-slp-vectorize
 * and clang give the rounded value.  tests/test_polygon.c (polygon_float_vs_reference)
 * and tests/test_sphere.c (sphere_float_random) used this idiom to build their
 * float-rounded references; they, the fuzz targets and tests/stress/stress.c now round
 * through a volatile float (round_to_float, fz_to_float). */
#include <stdio.h>
__attribute__((noinline)) void use(const float *xf, const float *vf, const double *x, const double *v) { printf("x %a (float %a) v %a (float %a)\n", x[0], (double)xf[0], v[0], (double)vf[0]); }
int main(int argc, char **argv)
{
    (void)argv;
    double x[3], verts[18];
    float xf[3], vf[18];
    for (int k = 0; k < 3; ++k) x[k] = 0x1.4802d606cbd67p+0 * (argc + k);
    for (int k = 0; k < 18; ++k) verts[k] = 0x1.8cdcc4b11ca8ep+0 * (argc + k);
    int n = 6;
    /* test_polygon.c polygon_float_vs_reference */
    for (int k = 0; k < 3 * n; ++k) vf[k] = (float)verts[k];
    for (int k = 0; k < 3; ++k) xf[k] = (float)x[k];
    for (int k = 0; k < 3 * n; ++k) verts[k] = vf[k];
    for (int k = 0; k < 3; ++k) x[k] = xf[k];
    use(xf, vf, x, verts);
    /* test_sphere.c sphere_float_random */
    double c[3], xs[3]; float xsf[3], cf[3];
    for (int k = 0; k < 3; ++k) xs[k] = 0x1.4802d606cbd67p+0 * (argc + k), c[k] = 0x1.8cdcc4b11ca8ep+0 * (argc + k);
    for (int k = 0; k < 3; ++k) {
        xsf[k] = (float)xs[k];
        cf[k] = (float)c[k];
        xs[k] = xsf[k];
        c[k] = cf[k];
    }
    use(xsf, cf, xs, c);
}

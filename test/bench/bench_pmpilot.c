/* bench_pmpilot — photon count and bandwidth for a target error from a
 * pilot run (issue 10, parameter choice; model in include/heliodon/compare.h,
 * hd_compare_pm_fit / hd_compare_pm_choose).
 *   bench_pmpilot n0 target < table
 * table: one line per pilot bandwidth "k var dbias2" (k = photons per lookup
 * and source, ascending; var = relative noise variance from two seeds;
 * dbias2 = noise-corrected mean squared relative difference to the smallest
 * k).  Prints "C B N k predicted_error". */
#include "heliodon/compare.h"

#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
    if (argc != 3) { fprintf(stderr, "usage: %s n0 target < table\n", argv[0]); return 2; }
    double n0 = atof(argv[1]), target = atof(argv[2]);
    double k[64], v[64], d[64];
    int n = 0;
    while (n < 64 && scanf("%lf %lf %lf", &k[n], &v[n], &d[n]) == 3) n++;
    hd_pm_model m;
    if (hd_compare_pm_fit(k, v, d, n, n0, &m)) { fprintf(stderr, "%s: cannot fit the model to %d lines\n", argv[0], n); return 1; }
    double N, kk;
    if (hd_compare_pm_choose(&m, target, &N, &kk)) { fprintf(stderr, "%s: bad target %g\n", argv[0], target); return 1; }
    printf("%.6g %.6g %.0f %.2f %.4f\n", m.C, m.B, N, kk, hd_compare_pm_error(&m, N, kk));
    return 0;
}

/* Sky functions natively and through the .cal module: evaluations per
 * second of perezlum.cal skybright and skybright.cal skybr (gendaylit and
 * gensky skies) for the same directions, and the largest difference.
 *   build/bench/bench_skycal [n]      (default 2e6 directions) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "heliodon/material.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static int run(const char *name, char **sargs, const double *args, int nargs, long n)
{
    hd_tmat nat, cal;
    hd_tmat_init(&nat, HD_MAT_GLOW, "sky");
    hd_tmat_init(&cal, HD_MAT_GLOW, "sky");
    unsetenv("HELIODON_SKY_CAL");
    if (hd_tmat_set_brightfunc(&nat, sargs, 2, args, nargs, "bench")) { fprintf(stderr, "%s\n", hd_errmsg()); return 1; }
    setenv("HELIODON_SKY_CAL", "1", 1);
    if (hd_tmat_set_brightfunc(&cal, sargs, 2, args, nargs, "bench")) { fprintf(stderr, "%s\n", hd_errmsg()); return 1; }
    hd_vec3 *d = malloc((size_t)n * sizeof *d);
    if (!d) return 1;
    srand(1);
    for (long i = 0; i < n; i++) {
        double z = 2.0 * rand() / RAND_MAX - 1, a = 6.283185307179586 * rand() / RAND_MAX, r = sqrt(1 - z * z);
        d[i] = hd_v3(r * cos(a), r * sin(a), z);
    }
    double s0 = 0, s1 = 0, maxrel = 0;
    double t0 = now();
    for (long i = 0; i < n; i++) s0 += hd_pattern_eval(&nat, d[i]);
    double t1 = now();
    for (long i = 0; i < n; i++) s1 += hd_pattern_eval(&cal, d[i]);
    double t2 = now();
    for (long i = 0; i < n; i += 97) {
        double a = hd_pattern_eval(&nat, d[i]), b = hd_pattern_eval(&cal, d[i]);
        double r = fabs(a - b) / (fabs(a) > 1e-300 ? fabs(a) : 1);
        if (r > maxrel) maxrel = r;
    }
    printf("%-22s native %.3g eval/s   .cal %.3g eval/s   ratio %.1f   max rel diff %.2g   (sums %.6g %.6g)\n",
           name, n / (t1 - t0), n / (t2 - t1), (t2 - t1) / (t1 - t0), maxrel, s0, s1);
    hd_tmat_release(&cal);
    free(d);
    return 0;
}

int main(int argc, char **argv)
{
    long n = argc > 1 ? atol(argv[1]) : 2000000;
    char *perez[2] = {"skybright", "perezlum.cal"}, *skyb[2] = {"skybr", "skybright.cal"};
    /* a gendaylit clear sky and a gensky +s sky (arguments as they write them) */
    double pa[10] = {1.9, 0.17, -1.0, -0.32, 10.0, -3.0, 0.45, 0.55, -0.62, 0.56};
    double sa[7] = {1, 11.4, 2.3, 3.2, 0.55, -0.62, 0.56};
    double oa[3] = {2, 5.5, 1.1};
    if (run("perezlum.cal skybright", perez, pa, 10, n)) return 1;
    if (run("skybright.cal clear", skyb, sa, 7, n)) return 1;
    if (run("skybright.cal overcast", skyb, oa, 3, n)) return 1;
    return 0;
}

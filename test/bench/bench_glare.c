/* Benchmark: glare evaluation of 180-degree fisheye images (-vta) at
 * 256^2, 512^2 and 1024^2: geometry set-up (once per view and size) and
 * per-image evaluation with the geometry reused, as an annual run does.
 * The synthetic scene is an office-like field: 300 cd/m2 background with
 * noise, a 6000 cd/m2 window of ~1.2 sr with scattered 2500 cd/m2
 * speckles (many small sources, the worst case for source merging) and a
 * 200000 cd/m2 sun-reflection peak.  Prints one line per size. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "heliodon/glare.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(void)
{
    int sizes[] = {256, 512, 1024};
    hd_glare_view v;
    hd_view_default(&v);
    if (hd_view_parse_line(&v, "-vta -vd 1 0 0 -vu 0 0 1 -vh 180 -vv 180") < 0 || hd_view_setup(&v)) return 1;
    printf("%-9s %12s %14s %12s %9s %8s\n", "size", "geometry ms", "eval ms/image", "images/min", "sources", "DGP");
    for (int si = 0; si < 3; si++) {
        int n = sizes[si];
        float *lum = malloc(sizeof(float) * n * n);
        if (!lum) return 1;
        unsigned s = 12345;
        for (int row = 0; row < n; row++)
            for (int x = 0; x < n; x++) {
                hd_vec3 d;
                float L = 0;
                s = s * 1103515245u + 12345u;
                double u = (s >> 8) / 16777216.0;
                hd_vec3 o;
                if (hd_view_ray(&v, (x + 0.5) / n, (n - 1 - row + 0.5) / n, &o, &d) >= 0) {
                    double az = atan2(-d.y, d.x), el = asin(d.z);   /* window to the right */
                    L = (float)(300 * (0.8 + 0.4 * u));
                    if (az > 0.5 && az < 1.4 && el > -0.3 && el < 0.6) L = (float)(6000 * (0.9 + 0.2 * u));
                    else if (u < 0.01) L = 2500;
                    if (fabs(az - 1.0) < 0.03 && fabs(el + 0.2) < 0.03) L = 200000;
                }
                lum[row * n + x] = L;
            }
        hd_glare_opts o;
        hd_glare_opts_default(&o);
        double t0 = now();
        hd_glare_geom *g;
        if (hd_glare_geom_new(&g, &v, n, n)) { fprintf(stderr, "%s\n", hd_errmsg()); return 1; }
        double tg = now() - t0;
        int rep = n <= 256 ? 20 : n <= 512 ? 6 : 3;
        double best = 1e30;
        hd_glare_result r;
        for (int k = 0; k < rep; k++) {
            t0 = now();
            if (hd_glare_eval_lum(g, lum, &o, &r)) { fprintf(stderr, "%s\n", hd_errmsg()); return 1; }
            double t = now() - t0;
            if (t < best) best = t;
            if (k < rep - 1) hd_glare_result_free(&r);
        }
        printf("%4dx%-4d %12.1f %14.1f %12.0f %9d %8.4f\n", n, n, 1e3 * tg, 1e3 * best, 60.0 / best, r.nsources,
               r.dgp);
        hd_glare_result_free(&r);
        hd_glare_geom_free(g);
        free(lum);
    }
    return 0;
}

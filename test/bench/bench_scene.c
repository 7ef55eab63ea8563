/* Benchmark (CPU time of this process, so that other load on the machine
 * does not distort it): Radiance scene text parsing vs heliodon scene cache loading,
 * and polygon triangulation, on a generated scene (no reference data
 * needed).  Prints primitives/s and the speed-up of the cache. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "heliodon/scene.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv)
{
    long n = argc > 1 ? atol(argv[1]) : 200000;
    const char *dir = getenv("HD_TEST_TMP") ? getenv("HD_TEST_TMP") : "/tmp";
    char rad[512], cache[512];
    snprintf(rad, sizeof rad, "%s/bench_scene.rad", dir);
    snprintf(cache, sizeof cache, "%s/bench_scene.oct", dir);
    FILE *fp = fopen(rad, "w");
    if (!fp) { perror(rad); return 1; }
    fprintf(fp, "void plastic m 0 0 5 .5 .5 .5 0 0\n");
    for (long i = 0; i < n; i++) {
        double x = (double)(i % 1000), y = (double)(i / 1000);
        if (i % 4 == 0)
            fprintf(fp, "m sphere s%ld 0 0 4 %g %g 0 .4\n", i, x, y);
        else
            fprintf(fp, "m polygon p%ld\n0\n0\n15\n%g %g 0\n%g %g 0\n%g %g 0\n%g %g 0\n%g %g 0\n\n", i,
                    x, y, x + .9, y, x + .9, y + .9, x + .45, y + .3, x, y + .9);
    }
    fclose(fp);
    hd_scene s;
    hd_scene_init(&s);
    double t0 = now();
    if (hd_scene_load_rad(&s, rad, NULL)) { fprintf(stderr, "%s\n", hd_errmsg()); return 1; }
    double t1 = now();
    char *av[] = {"bench_scene"};
    if (hd_scene_write_cache(&s, cache, 1, av)) { fprintf(stderr, "%s\n", hd_errmsg()); return 1; }
    double t2 = now();
    hd_scene c;
    hd_scene_init(&c);
    if (hd_scene_read_cache(&c, cache)) { fprintf(stderr, "%s\n", hd_errmsg()); return 1; }
    double t3 = now();
    long ntri = 0;
    uint32_t tri[3 * 16];
    hd_vec3 v[16];
    for (size_t i = 0; i < c.nprims; i++) {
        const hd_prim *p = &c.prims[i];
        if (p->type != HD_T_POLYGON) continue;
        uint32_t nv = hd_polygon_nverts(p), nt;
        for (uint32_t k = 0; k < nv && k < 16; k++) v[k] = hd_polygon_vertex(p, k);
        if (hd_polygon_triangulate(v, nv, tri, &nt) == HD_OK) ntri += nt;
    }
    double t4 = now();
    printf("primitives: %zu\n", s.nprims);
    printf("parse .rad: %.3f s (%.0f primitives/s)\n", t1 - t0, s.nprims / (t1 - t0));
    printf("write cache: %.3f s\n", t2 - t1);
    printf("read cache: %.3f s (%.0f primitives/s), %.1fx faster than parsing\n", t3 - t2,
           c.nprims / (t3 - t2), (t1 - t0) / (t3 - t2));
    printf("triangulate: %ld triangles in %.3f s (%.0f polygons/s)\n", ntri, t4 - t3,
           (double)(c.nprims - c.nprims / 4) / (t4 - t3));
    hd_scene_free(&s);
    hd_scene_free(&c);
    remove(rad);
    remove(cache);
    return 0;
}

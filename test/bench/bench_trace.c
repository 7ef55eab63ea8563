/* Benchmark: ray casting speed and a 512 x 512 fisheye picture of the
 * shared "box" scene.  Usage: bench_trace [refdir] [nthreads] [ad]
 * (refdir defaults to $HELIODON_REF or ../shared/ref). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "heliodon/parallel.h"
#include "progress.h"
#include "heliodon/render.h"
#include "heliodon/rng.h"
#include "heliodon/scene.h"

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

typedef struct cast_job { const hd_tscene *ts; long per_chunk; long hits; } cast_job;

static hd_status cast_chunk(void *ctx, size_t b, size_t e, size_t ci, int worker)
{
    cast_job *j = ctx;
    (void)worker;
    hd_rng rng;
    hd_rng_init(&rng, 99, ci);
    long hits = 0;
    for (size_t k = b; k < e; k++) {
        hd_vec3 o = hd_v3(0.1 + 2.8 * hd_rng_uniform(&rng), 0.1 + 3.8 * hd_rng_uniform(&rng), 0.1 + 2.8 * hd_rng_uniform(&rng));
        double z = 1 - 2 * hd_rng_uniform(&rng), ph = 2 * HD_PI * hd_rng_uniform(&rng), s = sqrt(1 - z * z);
        hd_hit h;
        hits += hd_tscene_intersect(j->ts, o, hd_v3(s * cos(ph), s * sin(ph), z), 0, 0, &h);
    }
    __atomic_fetch_add(&j->hits, hits, __ATOMIC_RELAXED);
    return HD_OK;
}

int main(int argc, char **argv)
{
    setvbuf(stdout, NULL, _IOLBF, 0);
    const char *ref = argc > 1 ? argv[1] : getenv("HELIODON_REF");
    if (!ref || !*ref) ref = "../shared/ref";
    int nthreads = argc > 2 ? atoi(argv[2]) : 2;
    int ad = argc > 3 ? atoi(argv[3]) : 1024;
    char f[4][512];
    snprintf(f[0], sizeof f[0], "%s/scenes/box/box_room.rad", ref);
    snprintf(f[1], sizeof f[1], "%s/scenes/box/box_window.rad", ref);
    snprintf(f[2], sizeof f[2], "%s/scenes/box/sky_clear_0101_1030.rad", ref);
    snprintf(f[3], sizeof f[3], "%s/scenes/box/skyglow.rad", ref);
    char *files[4] = {f[0], f[1], f[2], f[3]};
    hd_scene sc;
    hd_scene_init(&sc);
    hd_tscene *ts;
    double t0 = hd_seconds();
    if (hd_render_load_scene(4, files, &sc, &ts, NULL, 0, NULL) != HD_OK) {
        fprintf(stderr, "bench_trace: %s\n", hd_errmsg());
        return 1;
    }
    printf("scene load + Embree build: %.3f s\n", hd_seconds() - t0);
    /* 1. bare intersection speed */
    long n = 4000000;
    for (int nt = 1; nt <= nthreads; nt *= 2) {
        cast_job j = {ts, 0, 0};
        t0 = hd_seconds();
        double c0 = cpu_seconds();
        hd_parallel_for((size_t)n, 10000, nt, cast_chunk, &j);
        double dt = hd_seconds() - t0, dc = cpu_seconds() - c0;
        printf("closest-hit rays, %d thread%s: %.2f Mrays/s wall, %.2f Mrays per CPU-second (%ld rays, %.2f s wall, %.2f s CPU)\n",
               nt, nt > 1 ? "s" : "", n / dt / 1e6, n / dc / 1e6, n, dt, dc);
    }
    /* 2. a 512 x 512 angular fisheye (fish.vf) with the A2 settings */
    hd_renderer r;
    r.scene = ts;
    hd_render_defaults(&r.o);
    r.o.ab = 6;
    r.o.ad = ad;
    r.o.lw = 1e-4;
    r.o.lr = 12;
    r.o.dj = 0;
    r.o.st = 0;
    hd_rpict_opts o;
    memset(&o, 0, sizeof o);
    hd_view_default(&o.view);
    char vf[512];
    snprintf(vf, sizeof vf, "%s/scenes/box/fish.vf", ref);
    if (hd_view_read_file(&o.view, vf) != HD_OK) { fprintf(stderr, "bench_trace: %s\n", hd_errmsg()); return 1; }
    o.xres = o.yres = 512;
    o.pa = 1;
    o.nthreads = nthreads;
    float *pix;
    t0 = hd_seconds();
    double c0 = cpu_seconds();
    if (hd_rpict_render(&r, &o, &pix) != HD_OK) { fprintf(stderr, "bench_trace: %s\n", hd_errmsg()); return 1; }
    double dt = hd_seconds() - t0, dc = cpu_seconds() - c0;
    double sum = 0;
    for (long k = 0; k < 512L * 512; k++) sum += 179 * (0.265 * pix[3 * k] + 0.670 * pix[3 * k + 1] + 0.065 * pix[3 * k + 2]);
    printf("512x512 fisheye (-ab 6 -ad %d -lw 1e-4 -lr 12, %d threads): %.1f s wall, %.1f s CPU, mean luminance %.1f cd/m2\n",
           ad, nthreads, dt, dc, sum / (512.0 * 512));
    free(pix);
    hd_tscene_free(ts);
    hd_scene_free(&sc);
    return 0;
}

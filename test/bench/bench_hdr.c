/* bench_hdr — Radiance HDR read and write throughput.
 *
 *   bench_hdr [size] [reference.hdr]
 *
 * 1. A synthetic size x size picture (default 2048) that looks like a
 *    rendering: smooth gradients, a noisy region and flat areas.  Writes it
 *    (float -> RGBE -> run-length scanlines) into a pre-touched memory
 *    buffer and to a file (page cache), and
 *    reads it back (file bytes -> RGBE -> float), several times; prints
 *    Mpixel/s and MB/s (MB of file bytes, 10^6) for the best run.
 * 2. If a reference picture is given (default: $HELIODON_REF or
 *    ../shared/ref, scenes/box/a2_clear_fish.hdr) the same on it.
 * The read is checked against the written pixels, so the benchmark fails
 * (exit 1) rather than report a number for a wrong result. */
#include "heliodon/picture.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static int run(const char *label, const hd_picture *p, int reps)
{
    double best_w = 1e30, best_r = 1e30, best_fr = 1e30, best_fw = 1e30;
    size_t n = 0;
    /* a pre-touched output buffer, so that page faults of a growing buffer
     * are not counted as codec time */
    size_t cap = (size_t)p->yres * hd_scanline_maxbytes(p->xres) + 65536;
    char *buf = malloc(cap);
    if (!buf) return 1;
    memset(buf, 1, cap);
    double npix = (double)p->xres * p->yres;
    char path[512];
    const char *tmp = getenv("HD_TEST_TMP");
    snprintf(path, sizeof path, "%s/bench_hdr.hdr", tmp && *tmp ? tmp : "/tmp");
    for (int r = 0; r < reps; r++) {
        FILE *fp = fmemopen(buf, cap, "w");
        double t0 = now();
        if (hd_picture_write(fp, p, &p->hdr, HD_RES_STANDARD)) { hd_report_error(); return 1; }
        fflush(fp);
        n = (size_t)ftell(fp);
        fclose(fp);
        double t1 = now();
        hd_istream *s;
        hd_picture q;
        if (hd_istream_memory(&s, buf, n, "bench")) { hd_report_error(); return 1; }
        if (hd_picture_read_stream(s, &q)) { hd_report_error(); return 1; }
        double t2 = now();
        hd_istream_close(s);
        if (q.xres != p->xres || q.yres != p->yres) { fprintf(stderr, "size mismatch\n"); return 1; }
        /* written pixels are quantised: compare to the RGBE precision */
        for (size_t i = 0; i < (size_t)npix * 3; i += 3) {
            float m = p->pix[i];
            if (p->pix[i + 1] > m) m = p->pix[i + 1];
            if (p->pix[i + 2] > m) m = p->pix[i + 2];
            for (int c = 0; c < 3; c++)
                if (fabsf(q.pix[i + c] - p->pix[i + c]) > m / 128 + 1e-30f) {
                    fprintf(stderr, "%s: pixel %zu differs: %g vs %g\n", label, i / 3, q.pix[i + c], p->pix[i + c]);
                    return 1;
                }
        }
        hd_picture_free(&q);
        /* through a file on disk (page cache) */
        double t25 = now();
        if (hd_picture_save(path, p, &p->hdr)) { hd_report_error(); return 1; }
        double t3 = now();
        if (t3 - t25 < best_fw) best_fw = t3 - t25;
        if (hd_picture_read(path, &q)) { hd_report_error(); return 1; }
        double t4 = now();
        hd_picture_free(&q);
        if (t1 - t0 < best_w) best_w = t1 - t0;
        if (t2 - t1 < best_r) best_r = t2 - t1;
        if (t4 - t3 < best_fr) best_fr = t4 - t3;
    }
    remove(path);
    printf("%s: %d x %d, %zu bytes (%.2f bytes/pixel), best of %d\n", label, p->xres, p->yres, n,
           n / npix, reps);
    printf("  write (memory): %7.1f Mpixel/s %7.1f MB/s\n", npix / best_w * 1e-6, n / best_w * 1e-6);
    printf("  read  (memory): %7.1f Mpixel/s %7.1f MB/s\n", npix / best_r * 1e-6, n / best_r * 1e-6);
    printf("  write (file)  : %7.1f Mpixel/s %7.1f MB/s\n", npix / best_fw * 1e-6, n / best_fw * 1e-6);
    printf("  read  (file)  : %7.1f Mpixel/s %7.1f MB/s\n", npix / best_fr * 1e-6, n / best_fr * 1e-6);
    printf("  read+write    : %7.1f MB/s (file bytes / (best write + best read), memory)\n",
           n / (best_w + best_r) * 1e-6);
    free(buf);
    return 0;
}

int main(int argc, char **argv)
{
    int size = argc > 1 ? atoi(argv[1]) : 2048;
    if (size < 16 || size > 16384) { fprintf(stderr, "bench_hdr: size 16..16384\n"); return 1; }
    hd_picture p;
    if (hd_picture_alloc(&p, size, size)) { hd_report_error(); return 1; }
    uint32_t seed = 12345;
    for (int y = 0; y < size; y++)
        for (int x = 0; x < size; x++) {
            float *d = p.pix + 3 * ((size_t)y * size + x);
            double u = (double)x / size, v = (double)y / size;
            if (v < 0.3) {                           /* sky-like smooth gradient */
                d[0] = (float)(0.5 + u); d[1] = (float)(0.7 + u); d[2] = (float)(1.5 + v);
            } else if (u < 0.5) {                    /* noisy indirect light */
                seed = seed * 1664525u + 1013904223u;
                float n = (float)(seed >> 8) / 16777216.0f;
                d[0] = 0.1f + 0.05f * n; d[1] = 0.09f + 0.05f * n; d[2] = 0.08f + 0.04f * n;
            } else if (u < 0.6) {                    /* sunlit patch */
                d[0] = 40.0f; d[1] = 38.0f; d[2] = 30.0f;
            } else {                                 /* walls: slow shading */
                d[0] = d[1] = d[2] = (float)(0.2 + 0.1 * sin(10 * u) * cos(7 * v));
            }
        }
    hd_header_append(&p.hdr, "bench_hdr synthetic");
    char label[64];
    snprintf(label, sizeof label, "synthetic %dx%d", size, size);
    if (run(label, &p, 5)) return 1;
    hd_picture_free(&p);

    char refpath[1024];
    const char *ref = getenv("HELIODON_REF");
    if (argc > 2) snprintf(refpath, sizeof refpath, "%s", argv[2]);
    else snprintf(refpath, sizeof refpath, "%s/scenes/box/a2_clear_fish.hdr", ref && *ref ? ref : "../shared/ref");
    struct stat st;
    if (stat(refpath, &st) == 0) {
        if (hd_picture_read(refpath, &p)) { hd_report_error(); return 1; }
        if (run(refpath, &p, 20)) return 1;
        hd_picture_free(&p);
    } else {
        printf("reference picture %s not found: skipped\n", refpath);
    }
    return 0;
}

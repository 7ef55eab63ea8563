/* Benchmark helper for test/bench/dctimestep.sh.
 *
 *   bench_dctimestep stream
 *       STREAM-like memory bandwidth of this machine: copy (a[i] = b[i]) and
 *       triad (a[i] = b[i] + s*c[i]) over 3 x 256 MiB arrays, best of 5, with
 *       1 thread and with all processors; bytes counted as STREAM does
 *       (copy 2 x 4 B per element, triad 3 x 4 B).
 *   bench_dctimestep mkdc OUT K XRES YRES
 *       A synthetic daylight-coefficient matrix of XRES*YRES rows and K
 *       columns (float, RGB), the same smooth functions as
 *       bench_mkcomponents' pictures (for the matrix-mode case).
 *   bench_dctimestep compare PATTERN_A PATTERN_B T0 T1
 *       Compare pictures A%d and B%d for steps T0..T1-1: per channel value
 *       the relative difference (values above 1e-3 of the picture maximum),
 *       its maximum, the share of values differing by more than one RGBE
 *       mantissa unit (2^-7 relative), and the mean relative difference.
 *   bench_dctimestep foldspeed
 *       hd_dcts_fold with 146 components x 48 steps x 65536 pixels, one
 *       thread, per kernel level (0 portable C, 1 AVX2, 2 AVX-512).
 *   bench_dctimestep comparemtx A B
 *       The same for two matrices (elements above 1e-3 of the maximum). */
#include "heliodon/dctimestep.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/matrix.h"
#include "heliodon/parallel.h"
#include "heliodon/picture.h"
#include "progress.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct sctx {
    float *a, *b, *c;
    size_t n;
    int triad;
} sctx;

static hd_status stream_chunk(void *vctx, size_t b, size_t e, size_t chunk, int worker)
{
    sctx *s = vctx;
    (void)chunk;
    (void)worker;
    if (s->triad)
        for (size_t i = b; i < e; i++) s->a[i] = s->b[i] + 3.0f * s->c[i];
    else
        for (size_t i = b; i < e; i++) s->a[i] = s->b[i];
    return HD_OK;
}

static double stream_run(sctx *s, int triad, int nthreads)
{
    s->triad = triad;
    double best = 1e30;
    for (int r = 0; r < 5; r++) {
        double t0 = hd_seconds();
        hd_parallel_for(s->n, s->n / (size_t)(nthreads * 4), nthreads, stream_chunk, s);
        double dt = hd_seconds() - t0;
        if (dt < best) best = dt;
    }
    return (double)s->n * sizeof(float) * (triad ? 3 : 2) / best / 1e9;
}

static int stream(void)
{
    sctx s;
    s.n = ((size_t)256 << 20) / sizeof(float);
    s.a = malloc(s.n * sizeof(float));
    s.b = malloc(s.n * sizeof(float));
    s.c = malloc(s.n * sizeof(float));
    if (!s.a || !s.b || !s.c) return 1;
    for (size_t i = 0; i < s.n; i++) { s.a[i] = 0; s.b[i] = (float)i; s.c[i] = 1; }
    int nt = hd_ncpus();
    printf("stream_copy_1thread_GBps %.2f\n", stream_run(&s, 0, 1));
    printf("stream_triad_1thread_GBps %.2f\n", stream_run(&s, 1, 1));
    printf("stream_copy_%dthreads_GBps %.2f\n", nt, stream_run(&s, 0, nt));
    printf("stream_triad_%dthreads_GBps %.2f\n", nt, stream_run(&s, 1, nt));
    free(s.a);
    free(s.b);
    free(s.c);
    return 0;
}

static int mkdc(const char *out, int K, int xr, int yr)
{
    hd_ofile *f;
    if (hd_ofile_open(&f, out)) hd_die();
    FILE *fp = hd_ofile_fp(f);
    fprintf(fp, "#?RADIANCE\nbench_dctimestep mkdc\nNROWS=%d\nNCOLS=%d\nNCOMP=3\nBigEndian=0\nFORMAT=float\n\n",
            xr * yr, K);
    float *row = malloc((size_t)K * 3 * sizeof(float));
    if (!row) return 1;
    for (int y = 0; y < yr; y++)
        for (int x = 0; x < xr; x++) {
            for (int k = 0; k < K; k++) {
                double cx = 0.5 + 0.4 * cos(k * 0.7), cy = 0.5 + 0.4 * sin(k * 1.3);
                double dx = (x + 0.5) / xr - cx, dy = (y + 0.5) / yr - cy;
                float v = (float)(1e-3 * exp(-(dx * dx + dy * dy) * 20) + 1e-5);
                row[3 * k] = v;
                row[3 * k + 1] = v * 0.9f;
                row[3 * k + 2] = v * 0.8f;
            }
            fwrite(row, sizeof(float), (size_t)K * 3, fp);
        }
    free(row);
    if (hd_ofile_commit(f)) hd_die();
    return 0;
}

static int compare(const char *pa, const char *pb, int t0, int t1)
{
    double maxrel = 0, sumrel = 0;
    long n = 0, over = 0, black_a = 0, black_b = 0, pics = 0;
    for (int t = t0; t < t1; t++) {
        char na[4096], nb[4096];
        if (hd_pattern_format(na, sizeof na, pa, NULL, t) || hd_pattern_format(nb, sizeof nb, pb, NULL, t)) hd_die();
        hd_picture A, B;
        if (hd_picture_read(na, &A)) hd_die();
        if (hd_picture_read(nb, &B)) hd_die();
        if (A.xres != B.xres || A.yres != B.yres) {
            fprintf(stderr, "%s and %s differ in size\n", na, nb);
            return 1;
        }
        size_t np = (size_t)A.xres * (size_t)A.yres * 3;
        float mx = 0;
        for (size_t i = 0; i < np; i++) mx = fmaxf(mx, fmaxf(A.pix[i], B.pix[i]));
        if (mx == 0) { black_a++; black_b++; }
        for (size_t i = 0; i < np; i++) {
            double a = A.pix[i], b = B.pix[i], m = fmax(a, b);
            if (mx == 0 || m < 1e-3 * mx) continue;
            double rel = (a - b) / m;
            sumrel += rel;
            if (fabs(rel) > maxrel) maxrel = fabs(rel);
            if (fabs(rel) > 1.0 / 128) over++;
            n++;
        }
        pics++;
        hd_picture_free(&A);
        hd_picture_free(&B);
    }
    printf("pictures %ld (black in both %ld) values %ld max_rel %.3g mean_rel %+.3g over_1_rgbe_unit %ld\n", pics,
           black_a < black_b ? black_a : black_b, n, maxrel, n ? sumrel / (double)n : 0.0, over);
    return 0;
}

/* fold kernel speed: K=146 components, 48 steps, 65536 pixels, 1 thread,
 * best of 5, per kernel level. */
static int foldspeed(void)
{
    enum { K = 146, T = 48 };
    size_t np = 65536;
    float *comp[K];
    double *coef = malloc((size_t)K * T * 3 * sizeof(double));
    float *out = malloc((size_t)T * 3 * np * sizeof(float));
    if (!coef || !out) return 1;
    for (int k = 0; k < K; k++) {
        comp[k] = malloc(3 * np * sizeof(float));
        if (!comp[k]) return 1;
        for (size_t i = 0; i < 3 * np; i++) comp[k][i] = (float)((i * 7 + (size_t)k) % 100) * 1e-3f;
    }
    for (size_t i = 0; i < (size_t)K * T * 3; i++) coef[i] = 1.0 + (double)(i % 13);
    int maxl = hd_dcts_set_kernel(-1);
    for (int l = 0; l <= maxl; l++) {
        hd_dcts_set_kernel(l);
        double best = 1e30;
        for (int r = 0; r < 5; r++) {
            double t0 = hd_seconds();
            hd_dcts_fold(comp, K, coef, T, np, out, 1);
            double dt = hd_seconds() - t0;
            if (dt < best) best = dt;
        }
        printf("fold_kernel_level %d: %.3f s for %.3g multiply-adds = %.2f G/s\n", l, best, (double)K * T * 3 * (double)np,
               (double)K * T * 3 * (double)np / best / 1e9);
    }
    return 0;
}

static int comparemtx(const char *pa, const char *pb)
{
    hd_matrix A, B;
    if (hd_matrix_read(pa, &A, NULL) || hd_matrix_read(pb, &B, NULL)) hd_die();
    if (A.nrows != B.nrows || A.ncols != B.ncols || A.ncomp != B.ncomp) {
        fprintf(stderr, "%s and %s differ in size\n", pa, pb);
        return 1;
    }
    size_t n = (size_t)A.nrows * (size_t)A.ncols * (size_t)A.ncomp, cnt = 0;
    double mx = 0, maxrel = 0, sum = 0;
    for (size_t i = 0; i < n; i++) mx = fmax(mx, fmax(fabs(A.data[i]), fabs(B.data[i])));
    for (size_t i = 0; i < n; i++) {
        double m = fmax(fabs(A.data[i]), fabs(B.data[i]));
        if (m < 1e-3 * mx || m == 0) continue;
        double rel = (A.data[i] - B.data[i]) / m;
        sum += rel;
        if (fabs(rel) > maxrel) maxrel = fabs(rel);
        cnt++;
    }
    printf("%dx%dx%d elements %zu max_rel %.3g mean_rel %+.3g\n", A.nrows, A.ncols, A.ncomp, cnt, maxrel,
           cnt ? sum / (double)cnt : 0.0);
    hd_matrix_free(&A);
    hd_matrix_free(&B);
    return 0;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    if (argc >= 2 && !strcmp(argv[1], "stream")) return stream();
    if (argc >= 2 && !strcmp(argv[1], "foldspeed")) return foldspeed();
    if (argc == 6 && !strcmp(argv[1], "mkdc")) return mkdc(argv[2], atoi(argv[3]), atoi(argv[4]), atoi(argv[5]));
    if (argc == 4 && !strcmp(argv[1], "comparemtx")) return comparemtx(argv[2], argv[3]);
    if (argc == 6 && !strcmp(argv[1], "compare")) return compare(argv[2], argv[3], atoi(argv[4]), atoi(argv[5]));
    fprintf(stderr, "usage: %s stream | mkdc OUT K XRES YRES | foldspeed | compare PATTERN_A PATTERN_B T0 T1 | comparemtx A B\n", argv[0]);
    return 1;
}

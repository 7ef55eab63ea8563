/* bench_3pm — helpers for test/bench/3pm.sh (the full-sample 3PM
 * comparisons against ../shared/ref/scenes/box):
 *   bench_3pm stats A B          matrix A vs reference B: totals, column sums,
 *                                element RMS (RGB mean per element)
 *   bench_3pm pics PATA PATB N   per-bin pictures (printf patterns, bins
 *                                0..N-1): picture sums compared like columns
 *   bench_3pm tmatrix XML OUT    Klems transmission matrix (tb) of a BSDF XML
 *   bench_3pm fold V T D S A1clear A1overcast R3
 *                                V·T·D·S at the clear (10) and overcast (59)
 *                                steps vs rtrace and Radiance's 3PM */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/bsdf.h"
#include "heliodon/io.h"
#include "heliodon/matrix.h"
#include "heliodon/picture.h"

static double el(const hd_matrix *m, int r, int c)
{
    const double *v = hd_matrix_at(m, r, c);
    return (v[0] + v[1] + v[2]) / 3;
}

static void stats(const hd_matrix *a, const hd_matrix *b)
{
    double ta = 0, tb = 0, mx = 0, mxc = 0;
    for (int r = 0; r < b->nrows; r++)
        for (int c = 0; c < b->ncols; c++) {
            ta += el(a, r, c);
            tb += el(b, r, c);
            if (el(b, r, c) > mx) mx = el(b, r, c);
        }
    double *ca = calloc((size_t)b->ncols, sizeof *ca), *cb = calloc((size_t)b->ncols, sizeof *cb);
    for (int c = 0; c < b->ncols; c++) {
        for (int r = 0; r < b->nrows; r++) { ca[c] += el(a, r, c); cb[c] += el(b, r, c); }
        if (cb[c] > mxc) mxc = cb[c];
    }
    printf("total: %.6g vs %.6g (rel %+.4f)\n", ta, tb, (ta - tb) / tb);
    static const double cf[] = {0, 0.01, 0.05};
    for (int k = 0; k < 3; k++) {
        double worst = 0, sum = 0;
        int n = 0, within3 = 0;
        for (int c = 0; c < b->ncols; c++) {
            if (cb[c] <= cf[k] * mxc || cb[c] <= 0) continue;
            double d = (ca[c] - cb[c]) / cb[c];
            if (fabs(d) > worst) worst = fabs(d);
            if (fabs(d) <= 0.03) within3++;
            sum += d * d;
            n++;
        }
        printf("column sums (cols > %g of max, n=%d): max|rel| %.4f, rms %.4f, within 3%%: %d\n", cf[k], n, worst,
               n ? sqrt(sum / n) : 0, within3);
    }
    static const double ef[] = {1e-3, 1e-2, 1e-1};
    for (int k = 0; k < 3; k++) {
        double ss = 0;
        int n = 0;
        for (int r = 0; r < b->nrows; r++)
            for (int c = 0; c < b->ncols; c++) {
                double vb = el(b, r, c);
                if (vb <= ef[k] * mx) continue;
                double d = (el(a, r, c) - vb) / vb;
                ss += d * d;
                n++;
            }
        printf("element RMS rel (elements > %g of max, n=%d): %.4f\n", ef[k], n, n ? sqrt(ss / n) : 0);
    }
    free(ca);
    free(cb);
}

static int load(const char *p, hd_matrix *m)
{
    hd_matrix_init(m);
    if (hd_matrix_read(p, m, NULL) != HD_OK) { fprintf(stderr, "bench_3pm: %s\n", hd_errmsg()); return 0; }
    return 1;
}

static double lux(const double *v) { return 179 * (0.265 * v[0] + 0.670 * v[1] + 0.065 * v[2]); }

int main(int argc, char **argv)
{
    hd_set_progname("bench_3pm");
    if (argc == 4 && !strcmp(argv[1], "stats")) {
        hd_matrix a, b;
        if (!load(argv[2], &a) || !load(argv[3], &b)) return 1;
        if (a.nrows != b.nrows || a.ncols != b.ncols) { fprintf(stderr, "dimension mismatch\n"); return 1; }
        stats(&a, &b);
        return 0;
    }
    if (argc == 5 && !strcmp(argv[1], "pics")) {
        int n = atoi(argv[4]);
        hd_matrix a, b;
        hd_matrix_alloc(&a, 1, n, 3);
        hd_matrix_alloc(&b, 1, n, 3);
        for (int k = 0; k < n; k++) {
            for (int w = 0; w < 2; w++) {
                char path[1024];
                if (hd_pattern_format(path, sizeof path, argv[2 + w], NULL, k) != HD_OK) return 1;
                hd_picture p;
                hd_picture_init(&p);
                if (hd_picture_read(path, &p) != HD_OK) { fprintf(stderr, "bench_3pm: %s\n", hd_errmsg()); return 1; }
                double s[3] = {0, 0, 0};
                for (size_t i = 0; i < (size_t)p.xres * p.yres; i++)
                    for (int c = 0; c < 3; c++) s[c] += p.pix[3 * i + c];
                double *d = hd_matrix_at(w ? &b : &a, 0, k);
                for (int c = 0; c < 3; c++) d[c] = s[c] / ((double)p.xres * p.yres);
                hd_picture_free(&p);
            }
        }
        stats(&a, &b);
        return 0;
    }
    if (argc == 4 && !strcmp(argv[1], "tmatrix")) {
        hd_bsdf *bs;
        if (hd_bsdf_load(argv[2], &bs) != HD_OK) { fprintf(stderr, "bench_3pm: %s\n", hd_errmsg()); return 1; }
        hd_matrix T;
        hd_matrix_init(&T);
        if (hd_bsdf_klems_matrix(bs, HD_BSDF_TB, NULL, 0, 3, &T) != HD_OK) { fprintf(stderr, "bench_3pm: %s\n", hd_errmsg()); return 1; }
        FILE *fp = fopen(argv[3], "wb");
        hd_header h;
        hd_header_init(&h);
        hd_header_append(&h, "bench_3pm tmatrix (Klems tb of the BSDF XML)");
        if (!fp || hd_matrix_write(fp, &T, &h, 1, HD_MTX_FLOAT) != HD_OK) { fprintf(stderr, "bench_3pm: cannot write\n"); return 1; }
        fclose(fp);
        return 0;
    }
    if (argc == 9 && !strcmp(argv[1], "fold")) {
        hd_matrix V, T, D, S, DS, TDS, R, AC, AO, R3;
        if (!load(argv[2], &V) || !load(argv[3], &T) || !load(argv[4], &D) || !load(argv[5], &S) || !load(argv[8], &R3))
            return 1;
        hd_matrix_readopts ro = {0, 1, 3, -1};
        hd_matrix_init(&AC);
        hd_matrix_init(&AO);
        if (hd_matrix_read(argv[6], &AC, &ro) != HD_OK || hd_matrix_read(argv[7], &AO, &ro) != HD_OK) {
            fprintf(stderr, "bench_3pm: %s\n", hd_errmsg());
            return 1;
        }
        hd_matrix_init(&DS);
        hd_matrix_init(&TDS);
        hd_matrix_init(&R);
        if (hd_matrix_multiply(&DS, &D, &S) || hd_matrix_multiply(&TDS, &T, &DS) || hd_matrix_multiply(&R, &V, &TDS)) {
            fprintf(stderr, "bench_3pm: %s\n", hd_errmsg());
            return 1;
        }
        /* overcast: step 59; clear: step 10 */
        double o = 0, oa = 0, or3 = 0, c = 0, ca = 0, cr3 = 0, sh = 0, sha = 0, shr3 = 0;
        int nsh = 0;
        for (int p = 0; p < 25; p++) {
            o += lux(hd_matrix_at(&R, p, 59));
            or3 += lux(hd_matrix_at(&R3, p, 59));
            oa += lux(AO.data + 3 * p);
            c += lux(hd_matrix_at(&R, p, 10));
            cr3 += lux(hd_matrix_at(&R3, p, 10));
            ca += lux(AC.data + 3 * p);
        }
        /* shaded floor points: not sunlit in a1_clear_ab0 (Radiance's 18) */
        static const int sunlit[] = {10, 11, 12, 15, 16, 20, 21};
        for (int p = 0; p < 25; p++) {
            int lit = 0;
            for (int k = 0; k < 7; k++) if (sunlit[k] == p) lit = 1;
            if (lit) continue;
            sh += lux(hd_matrix_at(&R, p, 10));
            shr3 += lux(hd_matrix_at(&R3, p, 10));
            sha += lux(AC.data + 3 * p);
            nsh++;
        }
        o /= 25; oa /= 25; or3 /= 25; c /= 25; ca /= 25; cr3 /= 25; sh /= nsh; sha /= nsh; shr3 /= nsh;
        printf("overcast floor mean: rtrace conv %.1f | Radiance 3PM %.1f (%+.3f) | heliodon 3PM %.1f (%+.3f; vs Radiance 3PM %+.3f)\n",
               oa, or3, (or3 - oa) / oa, o, (o - oa) / oa, (o - or3) / or3);
        printf("clear floor mean:    rtrace conv %.1f | Radiance 3PM %.1f (%+.3f) | heliodon 3PM %.1f (%+.3f)\n", ca, cr3,
               (cr3 - ca) / ca, c, (c - ca) / ca);
        printf("clear shaded floor points (%d): rtrace conv %.1f | Radiance 3PM %.1f (%+.3f) | heliodon 3PM %.1f (%+.3f)\n",
               nsh, sha, shr3, (shr3 - sha) / sha, sh, (sh - sha) / sha);
        double worst = 0;
        for (int p = 0; p < 28; p++)
            for (int t = 0; t < R.ncols; t++) {
                double a = lux(hd_matrix_at(&R, p, t)), b = lux(hd_matrix_at(&R3, p, t));
                if (b > 1 && fabs(a - b) / b > worst) worst = fabs(a - b) / b;
            }
        printf("all 28 points x %d steps vs Radiance's 3PM result: max |rel| %.4f (points > 1 lux)\n", R.ncols, worst);
        return 0;
    }
    fprintf(stderr, "usage: bench_3pm stats A B | pics PATA PATB N | tmatrix XML OUT | fold V T D S A1clear A1overcast R3\n");
    return 1;
}

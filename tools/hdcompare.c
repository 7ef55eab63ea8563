/* hdcompare — error measures between a result and a reference (see
 * docs/man/hdcompare.1): pictures (relative RMS of luminance over lit
 * pixels, E_v and DGP of fisheye views) or matrices / rtrace outputs (-m). */
#include "heliodon/common.h"
#include "heliodon/compare.h"
#include "heliodon/glare.h"
#include "heliodon/io.h"
#include "heliodon/matrix.h"
#include "heliodon/picture.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void usage(void)
{
    fprintf(stderr,
            "usage: %s [-m [-p]] [-s factor] [-r k] [-R k] [-f floor] [-vf file | -vt? -vp x y z ...] test reference\n"
            "  -m        compare matrices / rtrace outputs instead of pictures\n"
            "  -r k, -R k  box-filter the test / reference picture by k first (k*k samples\n"
            "            per pixel from a picture rendered k times larger)\n"
            "  -s factor multiply the test values by factor first (e.g. a unit-radiance\n"
            "            daylight coefficient times the sun's radiance)\n"
            "  -p        also print the relative row-sum difference of every row (-m)\n"
            "  -f floor  reference values <= floor are not lit (negative: fraction of the\n"
            "            reference mean; default -0.01)\n"
            "  -v...     fisheye view for E_v and DGP (default: VIEW of the reference)\n",
            hd_progname());
    exit(2);
}

static void stats(const hd_cmp_stats *s, const char *unit)
{
    printf("values %ld\nlit %ld\nfloor %.6g\n", s->n, s->nused, s->floor);
    printf("rms_rel %.6g\nmean_rel %.6g\nmean_abs_rel %.6g\nmax_rel %.6g\nmax_index %ld\n", s->rms_rel,
           s->mean_rel, s->mean_abs_rel, s->max_rel, s->imax);
    printf("mean_test %.6g\nmean_ref %.6g\ntotal_rel %.6g\n", s->n ? s->sum_a / (double)s->n : 0,
           s->n ? s->sum_b / (double)s->n : 0, s->total_rel);
    printf("nonfinite_test %ld\nnonfinite_ref %ld\nunit %s\n", s->nonfinite_a, s->nonfinite_b, unit);
}

static char *read_view_file(const char *path)
{
    hd_istream *s;
    if (hd_istream_open(&s, path)) return NULL;
    char *buf = hd_malloc(65536);
    if (!buf) { hd_istream_close(s); return NULL; }
    size_t n = hd_istream_read(s, buf, 65535);
    buf[n] = 0;
    hd_istream_close(s);
    return buf;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int mtx = 0, rows = 0, haveview = 0, ka = 1, kb = 1;
    double floor = -0.01, scale = 1;
    hd_glare_view view;
    hd_view_default(&view);
    int i = 1;
    while (i < argc && argv[i][0] == '-' && argv[i][1]) {
        const char *w = argv[i];
        if (!strcmp(w, "-m")) { mtx = 1; i++; }
        else if ((!strcmp(w, "-r") || !strcmp(w, "-R")) && i + 1 < argc) {
            int k = atoi(argv[i + 1]);
            if (k < 1 || k > 64) {
                fprintf(stderr, "%s: %s expects a factor 1..64, got '%s'\n", hd_progname(), w, argv[i + 1]);
                return 2;
            }
            if (w[1] == 'r') ka = k; else kb = k;
            i += 2;
        }
        else if (!strcmp(w, "-p")) { rows = 1; i++; }
        else if (!strcmp(w, "-s")) {
            if (i + 1 >= argc) usage();
            char *end;
            scale = strtod(argv[i + 1], &end);
            if (*end || end == argv[i + 1] || !(scale >= 0) || scale > 1e30) {
                fprintf(stderr, "%s: -s expects a finite factor >= 0, got '%s'\n", hd_progname(), argv[i + 1]);
                return 2;
            }
            i += 2;
        }
        else if (!strcmp(w, "-f")) {
            if (i + 1 >= argc) usage();
            char *end;
            floor = strtod(argv[i + 1], &end);
            if (*end || end == argv[i + 1]) {
                fprintf(stderr, "%s: -f expects a number, got '%s'\n", hd_progname(), argv[i + 1]);
                return 2;
            }
            i += 2;
        } else if (!strcmp(w, "-vf")) {
            if (i + 1 >= argc) usage();
            char *t = read_view_file(argv[i + 1]);
            int k = 0;
            if (!t || (k = hd_view_parse_line(&view, t)) < 0) { free(t); hd_report_error(); return 1; }
            free(t);
            if (!k) { fprintf(stderr, "%s: %s: no view options found\n", hd_progname(), argv[i + 1]); return 1; }
            haveview = 1;
            i += 2;
        } else if (w[1] == 'v') {
            int k = hd_view_parse_arg(&view, argc, argv, i);
            if (k < 0) { hd_report_error(); return 2; }
            if (k == 0) usage();
            haveview = 1;
            i += k;
        } else usage();
    }
    if (argc - i != 2) usage();
    const char *fa = argv[i], *fb = argv[i + 1];
    if (mtx) {
        hd_matrix a, b;
        hd_matrix_readopts ro = {0, 1, 3, -1};   /* rtrace output: no NROWS/NCOLS */
        if (hd_matrix_read(fa, &a, &ro)) { hd_report_error(); return 1; }
        if (hd_matrix_read(fb, &b, &ro)) { hd_report_error(); hd_matrix_free(&a); return 1; }
        if (scale != 1)
            for (size_t k = 0; k < (size_t)a.nrows * a.ncols * a.ncomp; k++) a.data[k] *= scale;
        hd_cmp_stats s;
        double *pr = rows ? hd_malloc_array(a.nrows > 0 ? (size_t)a.nrows : 1, sizeof *pr) : NULL;
        if ((rows && !pr) || hd_compare_matrices(&a, &b, floor, &s, pr)) {
            hd_report_error();
            free(pr);
            hd_matrix_free(&a);
            hd_matrix_free(&b);
            return 1;
        }
        printf("rows %d\ncolumns %d\n", a.nrows, a.ncols);
        stats(&s, "grey");
        if (pr)
            for (int r = 0; r < a.nrows; r++) printf("row %d %.6g\n", r, pr[r]);
        free(pr);
        hd_matrix_free(&a);
        hd_matrix_free(&b);
        return (s.nonfinite_a || s.nonfinite_b) ? 3 : 0;
    }
    hd_picture a, b;
    if (hd_picture_read(fa, &a)) { hd_report_error(); return 1; }
    if (hd_picture_read(fb, &b)) { hd_report_error(); hd_picture_free(&a); return 1; }
    if (scale != 1)
        for (size_t k = 0; k < (size_t)a.xres * a.yres * 3; k++) a.pix[k] = (float)(a.pix[k] * scale);
    for (int t = 0; t < 2; t++) {
        int k = t ? kb : ka;
        hd_picture *p = t ? &b : &a, red;
        if (k == 1) continue;
        if (hd_compare_reduce(p, k, &red)) { hd_report_error(); hd_picture_free(&a); hd_picture_free(&b); return 1; }
        hd_picture_free(p);
        *p = red;
    }
    hd_piccmp r;
    hd_status st = hd_compare_pictures(&a, &b, haveview ? &view : NULL, floor, &r);
    hd_picture_free(&a);
    hd_picture_free(&b);
    if (st) { hd_report_error(); return 1; }
    stats(&r.lum, "cd/m2");
    if (r.have_glare) {
        printf("ev_test %.6g\nev_ref %.6g\nev_rel %.6g\n", r.ev_a, r.ev_b, r.ev_b > 0 ? r.ev_a / r.ev_b - 1 : 0);
        printf("dgp_test %.6g\ndgp_ref %.6g\ndgp_diff %.6g\n", r.dgp_a, r.dgp_b, r.dgp_a - r.dgp_b);
    }
    return (r.lum.nonfinite_a || r.lum.nonfinite_b) ? 3 : 0;
}

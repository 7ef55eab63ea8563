/* dcglare — imageless annual glare from daylight-coefficient matrices
 * (Radiance-compatible).  See docs/man/dcglare.1 and dcglare.h. */
#include <stdlib.h>
#include <string.h>

#include "heliodon/dcglare.h"
#include "heliodon/dctimestep.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/options.h"

typedef struct cli {
    int sky_fmt, out_fmt, view_fmt;
} cli;

/* -if -id -ia (sky), -of -od -oa (output), -vif -vid -via (view file) */
static int opt_fmt(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    cli *c = vctx;
    (void)opt;
    (void)argc;
    const char *w = argv[i];
    const char *f = w[1] == 'v' ? w + 3 : w + 2;
    int fmt = f[0] == 'f' ? HD_MTX_FLOAT : f[0] == 'd' ? HD_MTX_DOUBLE : f[0] == 'a' ? HD_MTX_ASCII : -1;
    if (fmt < 0 || f[1]) {
        hd_fail(HD_ERR_USAGE, "unknown format option %s (expected a, f or d after %.*s)", w, (int)(f - w), w);
        return -1;
    }
    if (w[1] == 'i') c->sky_fmt = fmt;
    else if (w[1] == 'o') c->out_fmt = fmt;
    else c->view_fmt = fmt;
    return 0;
}

int main(int argc, char **argv)
{
    hd_dcglare_opts go;
    hd_dcglare_opts_default(&go);
    cli c = {-1, HD_MTX_ASCII, HD_MTX_ASCII};
    int nsteps = 0, noheader = 0, start_hour = 0, end_hour = 24, verbose = 0;
    double vd[3] = {0, 0, 0}, vu[3] = {0, 0, 1};
    const char *schedule = NULL, *viewfile = NULL;
    const hd_opt table[] = {
        {"n", HD_OPT_INT, &nsteps, 0, 0, "nsteps", "time steps of a headerless sky"},
        {"h", HD_OPT_TOGGLE, &noheader, 0, 0, NULL, "no information header on output"},
        {"l", HD_OPT_REAL, &go.limit, 0, 0, "dgp", "glare limit: write the glare autonomy instead of hourly DGP"},
        {"b", HD_OPT_REAL, &go.threshold, 0, 0, "val", "glare-source threshold: cd/m2 if > 100, else x E_v/pi (2000)"},
        {"sf", HD_OPT_STRING, &schedule, 0, 0, "file", "occupancy schedule (last CSV field > 0 = occupied)"},
        {"ss", HD_OPT_INT, &start_hour, 0, 0, "h", "occupancy start hour (24 steps a day)"},
        {"se", HD_OPT_INT, &end_hour, 0, 0, "h", "occupancy end hour"},
        {"vd", HD_OPT_REAL3, vd, 0, 0, "dx dy dz", "view direction of every view"},
        {"vu", HD_OPT_REAL3, vu, 0, 0, "dx dy dz", "view up vector (0 0 1)"},
        {"vf", HD_OPT_STRING, &viewfile, 0, 0, "file", "views, x y z dx dy dz per line (the rcontrib input)"},
        {"vi", HD_OPT_FUNC, &c, opt_fmt, 1, NULL, "-via/-vif/-vid: view file format"},
        {"i", HD_OPT_FUNC, &c, opt_fmt, 1, NULL, "-ia/-if/-id: headerless sky format"},
        {"o", HD_OPT_FUNC, &c, opt_fmt, 1, NULL, "-oa/-of/-od: output format"},
        {"t", HD_OPT_TOGGLE, &verbose, 0, 0, NULL, "report the matrix sizes on standard error"},
        HD_OPT_END};
    const char *syn = "[options] {-vd dx dy dz | -vf views} DCdirect DCtotal [sky]\n"
                      "       dcglare [options] {-vd dx dy dz | -vf views} DCdirect Vmat Tbsdf Dmat [sky]";
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, syn);
    int n = p.argc - p.first;
    char **in = p.argv + p.first;
    if (n < 2 || n > 5) {
        hd_fail(HD_ERR_USAGE, "expected DCdirect DCtotal [sky] or DCdirect Vmat Tbsdf Dmat [sky]");
        hd_report_error();
        hd_opt_usage(table, syn);
        return 1;
    }
    int three = n >= 4;
    const char *skypath = (three ? n == 5 : n == 3) ? in[n - 1] : NULL;
    go.vdir = hd_v3(vd[0], vd[1], vd[2]);
    go.vup = hd_v3(vu[0], vu[1], vu[2]);
    if (hd_vlen2(go.vup) == 0) hd_die_msg("-vu: zero-length up vector");
    if (!viewfile && hd_vlen2(go.vdir) == 0) hd_die_msg("missing view direction: give -vd dx dy dz or -vf views");
    if (c.sky_fmt < 0 && nsteps > 0) c.sky_fmt = HD_MTX_ASCII;

    /* the sky; then E_v = DCtotal . S or V . T . D . S; the direct DC */
    hd_dcts_opts dopts;
    hd_dcts_opts_init(&dopts);
    dopts.nsteps = nsteps;
    dopts.sky_fmt = c.sky_fmt;
    hd_matrix S, V, T, D, E, DC;
    hd_matrix_init(&V);
    hd_matrix_init(&T);
    hd_matrix_init(&D);
    hd_matrix_init(&E);
    hd_matrix_init(&DC);
    if (hd_dcts_coefficients(NULL, NULL, skypath, &dopts, 0, &S)) hd_die();
    if (hd_matrix_read(in[1], &V, NULL)) hd_die();
    if (three) {
        if (hd_matrix_read(in[2], &T, NULL) || hd_matrix_read(in[3], &D, NULL)) hd_die();
        const hd_matrix *chain[4] = {&V, &T, &D, &S};
        if (hd_matrix_chain(&E, chain, 4, 0, NULL, NULL)) hd_die();
    } else {
        if (V.ncols != S.nrows)
            hd_die_msg("%s has %d columns but the sky has %d rows (patches)", in[1], V.ncols, S.nrows);
        if (hd_matrix_multiply(&E, &V, &S)) hd_die();
    }
    if (hd_matrix_read(in[0], &DC, NULL)) hd_die();
    if (verbose)
        fprintf(stderr, "%s: %d views x %d time steps, %d sky bins\n", hd_progname(), E.nrows, E.ncols, S.nrows);

    unsigned char *occ = hd_malloc(S.ncols > 0 ? (size_t)S.ncols : 1);
    hd_vec3 *views = NULL;
    if (!occ) hd_die();
    if (schedule) {
        if (hd_dcglare_read_schedule(schedule, S.ncols, occ)) hd_die();
    } else {
        for (int t = 0; t < S.ncols; t++) occ[t] = t % 24 >= start_hour && t % 24 < end_hour;
    }
    go.occupied = occ;
    if (viewfile) {
        if (!(views = hd_malloc_array(E.nrows > 0 ? (size_t)E.nrows : 1, sizeof(hd_vec3)))) hd_die();
        if (hd_dcglare_read_views(viewfile, c.view_fmt, E.nrows, views)) hd_die();
        go.views = views;
    }
    float *res;
    if (hd_dcglare_eval(&DC, &E, &S, &go, &res)) hd_die();

    int ncols = go.limit < 0 ? E.ncols : 1;
    hd_header h;
    hd_header_init(&h);
    hd_header_add_command(&h, argc, argv);
    hd_header_add_software(&h);
    hd_mtxwriter w;
    double *row = hd_malloc_array((size_t)ncols, sizeof(double));
    if (!row) hd_die();
    if (hd_mtxwriter_begin(&w, stdout, &h, !noheader, (hd_mtxfmt)c.out_fmt, E.nrows, ncols, 1)) hd_die();
    w.ascii_style = HD_MTXASCII_DCTIMESTEP;
    for (int r = 0; r < E.nrows; r++) {
        for (int k = 0; k < ncols; k++) row[k] = res[(size_t)r * (size_t)ncols + (size_t)k];
        if (hd_mtxwriter_row(&w, row)) hd_die();
    }
    if (hd_mtxwriter_end(&w)) hd_die();
    if (fflush(stdout) != 0 || ferror(stdout)) hd_die_msg("write error on standard output");
    hd_header_free(&h);
    free(row);
    free(res);
    free(views);
    free(occ);
    hd_matrix_free(&S);
    hd_matrix_free(&V);
    hd_matrix_free(&T);
    hd_matrix_free(&D);
    hd_matrix_free(&E);
    hd_matrix_free(&DC);
    hd_optparse_free(&p);
    return 0;
}

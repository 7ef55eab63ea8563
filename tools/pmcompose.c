/* pmcompose — annual PM-CBDM composition (I = I_sun + I_sky outside the
 * fenestration mask, I_sun + I_sky,fen inside) streamed into the glare
 * evaluation; writes the glarestats CSV and, on request, hourly images. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/annual.h"
#include "heliodon/io.h"
#include "heliodon/options.h"

typedef struct ctx_t {
    hd_annual_opts *a;
    const char *sched[4]; /* -schedule open.csv open.log closed.csv closed.log */
    hd_glare_viewargs va; /* va.view = &a->view */
    long recs[100000];
} ctx_t;

static int opt_view(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt;
    ctx_t *c = vctx;
    return hd_glare_view_option(&c->va, argc, argv, i);
}

static int opt_term(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt;
    ctx_t *c = vctx;
    if (i + 2 >= argc) { hd_fail(HD_ERR_USAGE, "option -V expects a view-matrix picture pattern and a T*D matrix"); return -1; }
    if (c->a->nterms >= HD_ANNUAL_MAXTERMS) { hd_fail(HD_ERR_USAGE, "at most %d -V terms", HD_ANNUAL_MAXTERMS); return -1; }
    c->a->v_pattern[c->a->nterms] = argv[i + 1];
    c->a->td_matrix[c->a->nterms] = argv[i + 2];
    c->a->nterms++;
    return 2;
}

static int opt_dterm(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt;
    ctx_t *c = vctx;
    if (i + 2 >= argc) {
        hd_fail(HD_ERR_USAGE, "option -Vd expects a direct view-matrix picture pattern and a T*D matrix");
        return -1;
    }
    if (c->a->ndterms >= HD_ANNUAL_MAXTERMS) { hd_fail(HD_ERR_USAGE, "at most %d -Vd terms", HD_ANNUAL_MAXTERMS); return -1; }
    c->a->vd_pattern[c->a->ndterms] = argv[i + 1];
    c->a->tdd_matrix[c->a->ndterms] = argv[i + 2];
    c->a->ndterms++;
    return 2;
}

static int opt_piece(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt;
    ctx_t *c = vctx;
    long k, n;
    if (i + 2 >= argc || hd_parse_long(argv[i + 1], &k) || hd_parse_long(argv[i + 2], &n) || n < 1 || k < 0 || k >= n ||
        n > 1000000) {
        hd_fail(HD_ERR_USAGE, "option -H expects a piece k and a count n (0 <= k < n)");
        return -1;
    }
    c->a->piece_k = (int)k;
    c->a->piece_n = (int)n;
    return 2;
}

static int opt_schedule(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt;
    ctx_t *c = vctx;
    if (i + 4 >= argc) {
        hd_fail(HD_ERR_USAGE, "option -schedule expects open.csv open.log closed.csv closed.log");
        return -1;
    }
    for (int k = 0; k < 4; k++) c->sched[k] = argv[i + 1 + k];
    return 4;
}

static int opt_records(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt;
    ctx_t *c = vctx;
    if (i + 1 >= argc) { hd_fail(HD_ERR_USAGE, "option -r expects a list of record indices (e.g. 1716,1717)"); return -1; }
    char *s = argv[i + 1], *end;
    while (*s) {
        long v = strtol(s, &end, 10);
        if (end == s || v < 0) { hd_fail(HD_ERR_USAGE, "-r: bad record index at '%s'", s); return -1; }
        if (c->a->nrecords >= (int)(sizeof c->recs / sizeof c->recs[0])) { hd_fail(HD_ERR_USAGE, "-r: too many records"); return -1; }
        c->recs[c->a->nrecords++] = v;
        s = end;
        if (*s == ',' || *s == ' ') s++;
        else if (*s) { hd_fail(HD_ERR_USAGE, "-r: expected ',' at '%s'", s); return -1; }
    }
    c->a->records = c->recs;
    return 1;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    static hd_annual_opts a;
    static ctx_t c;
    hd_annual_opts_default(&a);
    c.a = &a;
    c.va.view = &a.view;
    const char *weather = NULL, *schedule_out = NULL;
    int join = 0;
    const hd_opt table[] = {
        {"w", HD_OPT_STRING, &weather, 0, 0, "file", "weather file (WEA or EPW), required"},
        {"m", HD_OPT_INT, &a.sun_mf, 0, 0, "MF", "Reinhart subdivision of the sun patches (1)"},
        {"ms", HD_OPT_INT, &a.sky_mf, 0, 0, "MF", "Reinhart subdivision of the sky coefficients (1)"},
        {"s", HD_OPT_STRING, &a.sun_pattern, 0, 0, "pattern", "DC_sun pictures, %d = sun patch"},
        {"k", HD_OPT_STRING, &a.sky_pattern, 0, 0, "pattern", "sky DC pictures, %d = sky bin"},
        {"V", HD_OPT_FUNC, &c, opt_term, 0, "pattern TD", "3PM term: V pictures (%d = Klems patch) and T*D matrix"},
        {"Vd", HD_OPT_FUNC, &c, opt_dterm, 0, "pattern TD",
         "5PM: direct-sun 3PM term (black-interior V x reflectance map, T*Ddirect) folded with the sun-only vector, subtracted"},
        {"sunsky", HD_OPT_TOGGLE, &a.sky_sun, 0, 0, NULL,
         "sky vectors keep the direct sun in their patches (gendaymtx without -s: plain 3PM with -V)"},
        {"F", HD_OPT_STRING, &a.fen_pattern, 0, 0, "pattern", "refined fenestration DC pictures, %d = sky bin"},
        {"Fs", HD_OPT_STRING, &a.fensun_pattern, 0, 0, "pattern",
         "refined sun DC for the masked pixels (replaces -s there), %d = sun patch"},
        {"K", HD_OPT_STRING, &a.mask, 0, 0, "mask.hdr", "fenestration mask picture (value > 0.5 inside)"},
        {"G", HD_OPT_STRING, &a.ground_sun, 0, 0, "file",
         "sunlit fraction of the exterior ground per sun patch ('patch fraction' lines): scales the sun term of the ground bin"},
        {"v", HD_OPT_FUNC, &c, opt_view, 1, "...", "view: -vf file or -vta -vp ... -vh 180 -vv 180"},
        {"b", HD_OPT_REAL, &a.glare.threshold, 0, 0, "value", "glare-source threshold as evalglare -b (2000)"},
        {"c", HD_OPT_REAL, &a.shade_limit, 0, 0, "dgp", "operated shade closes when DGP >= this (0.40)"},
        {"o", HD_OPT_STRING, &a.csv, 0, 0, "file.csv", "glare CSV (default: standard output)"},
        {"S", HD_OPT_STRING, &a.summary, 0, 0, "file", "summary (95th percentiles, classes, timings)"},
        {"L", HD_OPT_STRING, &a.hourlog, 0, 0, "file", "per-hour log (sun patch, sun radiance, mean luminance, DGP)"},
        {"I", HD_OPT_STRING, &a.image_pattern, 0, 0, "pattern", "write hourly images, %d = record index"},
        {"e", HD_OPT_TOGGLE, &a.image_exr, 0, 0, NULL, "hourly images as OpenEXR (half, ZIP) instead of RGBE"},
        {"r", HD_OPT_FUNC, &c, opt_records, 0, "i,j,...", "evaluate only these weather records (0-based)"},
        {"n", HD_OPT_INT, &a.nthreads, 0, 0, "N", "threads (default: all processors)"},
        {"schedule", HD_OPT_FUNC, &c, opt_schedule, 0, "oc ol cc cl",
         "two-pass shade: merge the open and closed runs' CSVs and hour logs"},
        {"Y", HD_OPT_STRING, &schedule_out, 0, 0, "file.csv", "with -schedule: the shade schedule CSV"},
        {"H", HD_OPT_FUNC, &c, opt_piece, 0, "k n", "compose only piece k of n contiguous slices of the daylight hours"},
        {"J", HD_OPT_TOGGLE, &join, 0, 0, NULL, "join the hour pieces in the folders given as arguments (-o -L -E -S)"},
        {"noglare", HD_OPT_TOGGLE, &a.no_glare, 0, 0, NULL,
         "compose only (hourly images -I, hour log -L; DGP column 0): any view, no glare evaluation"},
        {"E", HD_OPT_STRING, &a.illum_csv, 0, 0, "file.csv",
         "sensor points: pictures of irradiance coefficients (one pixel per point); write lux per point and hour"},
        {"P", HD_OPT_TOGGLE, &a.preflight, 0, 0, NULL, "preflight: check view, patterns and weather, then stop"},
        {"t", HD_OPT_TOGGLE, &a.verbose, 0, 0, NULL, "report progress and timings on standard error"},
        HD_OPT_END};
    const char *syn = "-w weather -vf view [-s sunpat][-k skypat][-V vpat TD ...][-F fenpat -K mask][-o out.csv]\n"
                      "       pmcompose -w weather -vf view -sunsky -V vpat TD ... -Vd vdpat TDd ... -s sunpat -m 6 (5PM)\n"
                      "       pmcompose -schedule open.csv open.log closed.csv closed.log -o out.csv [-Y sched.csv]"
                      "[-L out.log][-S summary][-c dgp]\n"
                      "       pmcompose ... -H k n  |  pmcompose -J -o out.csv -L out.log -S summary [-E ill.csv] piecedir ...";
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, syn);
    if (join) {   /* the hour pieces of -H runs, joined */
        if (p.argc == p.first) hd_die_msg("-J: give the piece folders");
        hd_annual_join_opts jo = {(const char *const *)p.argv + p.first, p.argc - p.first, a.csv, a.hourlog,
                                  a.illum_csv, a.summary, a.shade_limit};
        if (hd_annual_join(&jo)) hd_die();
        hd_optparse_free(&p);
        return 0;
    }
    if (p.argc != p.first) {
        hd_opt_usage(table, syn);
        return 1;
    }
    if (c.sched[0]) {
        if (!a.csv) hd_die_msg("-schedule needs the composite CSV (-o file.csv)");
        hd_annual_sched_opts so;
        hd_annual_sched_opts_default(&so);
        so.open_csv = c.sched[0];
        so.open_log = c.sched[1];
        so.closed_csv = c.sched[2];
        so.closed_log = c.sched[3];
        so.shade_limit = a.shade_limit;
        so.csv = a.csv;
        so.schedule = schedule_out;
        so.hourlog = a.hourlog;
        so.summary = a.summary;
        hd_annual_sched_stats ss;
        if (hd_annual_schedule(&so, &ss)) hd_die();
        if (a.verbose)
            fprintf(stderr, "%s: %ld hours, shade closed %ld h (open DGP >= %.2f); DGP p95 %.3f (open only %.3f), "
                    "DGI p95 %.2f (open only %.2f)\n", hd_progname(), ss.nhours, ss.nclosed, so.shade_limit, ss.dgp_p95,
                    ss.dgp_p95_open, ss.dgi_p95, ss.dgi_p95_open);
        hd_optparse_free(&p);
        return 0;
    }
    if (schedule_out) hd_die_msg("-Y is for the two-pass mode (-schedule)");
    if (c.va.nview && !a.no_glare && !a.illum_csv && (!c.va.has_t || !c.va.has_h || !c.va.has_v))
        hd_die_msg("the view must contain -vt?, -vh and -vv (e.g. -vf v1.vf with -vta -vh 180 -vv 180)");
    a.have_view = c.va.nview > 0;
    a.weather = weather;
    a.argc = argc;
    a.argv = argv;
    hd_annual_stats st;
    if (hd_annual_run(&a, &st)) hd_die();
    if (a.preflight) {
        printf("%s: %ld daylight hours of %ld records\n", weather, st.ndaylight, st.nrecords);
        hd_optparse_free(&p);
        return 0;
    }
    if (a.verbose && (a.no_glare || a.illum_csv))
        fprintf(stderr, "%s: %ld hours composed (no glare evaluation), largest mean %s %.4g; load %.2f s, compose %.2f s\n",
                hd_progname(), st.ndaylight, a.illum_csv ? "illuminance" : "luminance", st.mean_lum_max,
                st.t_load, st.t_loop);
    else if (a.verbose)
        fprintf(stderr, "%s: %ld hours, DGP p95 %.3f, DGI p95 %.2f, shade closed %ld h; load %.2f s, compose+glare %.2f s\n",
                hd_progname(), st.ndaylight, st.dgp_p95, st.dgi_p95, st.shade_closed, st.t_load, st.t_loop);
    hd_optparse_free(&p);
    return 0;
}

/* dctimestep — compute annual results from daylight coefficients and sky
 * vectors/matrices (Radiance-compatible).  See docs/man/dctimestep.1. */
#include "heliodon/dctimestep.h"
#include "heliodon/options.h"

#include <stdlib.h>
#include <string.h>

static int opt_fmt(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    hd_dcts_opts *o = ctx;
    (void)opt;
    (void)argc;
    const char *w = argv[i];
    if (w[1] == 'i') { /* -if -id -ia: headerless sky format */
        int f = w[2] == 'f' ? HD_MTX_FLOAT : w[2] == 'd' ? HD_MTX_DOUBLE : w[2] == 'a' ? HD_MTX_ASCII : -1;
        if (f < 0 || w[3]) { hd_fail(HD_ERR_USAGE, "unknown input format option %s (use -ia, -if or -id)", w); return -1; }
        o->sky_fmt = f;
    } else {
        int f = w[2] == 'f' ? HD_MTX_FLOAT : w[2] == 'd' ? HD_MTX_DOUBLE : w[2] == 'a' ? HD_MTX_ASCII
              : w[2] == 'c' ? HD_MTX_RGBE : -1;
        if (f < 0 || w[3]) { hd_fail(HD_ERR_USAGE, "unknown output format option %s (use -oa, -of, -od or -oc)", w); return -1; }
        o->out_fmt = f;
    }
    return 0;
}

int main(int argc, char **argv)
{
    hd_dcts_opts o;
    hd_dcts_opts_init(&o);
    int noheader = 0;
    double mcache_gb = 0;      /* -m: Radiance's cache size for DC pictures */
    const hd_opt table[] = {
        {"n", HD_OPT_INT, &o.nsteps, 0, 0, "nsteps", "time steps in a headerless sky"},
        {"h", HD_OPT_TOGGLE, &noheader, 0, 0, NULL, "no information header on output"},
        {"o", HD_OPT_STRING, &o.outspec, 0, 0, "spec", "one output file per time step (printf %d pattern)"},
        {"x", HD_OPT_INT, &o.xres, 0, 0, "xres", "shape result vectors as pictures of this width"},
        {"y", HD_OPT_INT, &o.yres, 0, 0, "yres", "... and this height"},
        {"N", HD_OPT_INT, &o.nthreads, 0, 0, "nproc", "threads (default: all processors)"},
        {"m", HD_OPT_REAL, &mcache_gb, 0, 0, "GB", "memory for cached DC pictures (accepted; not needed)"},
        {"v", HD_OPT_TOGGLE, &o.verbose, 0, 0, NULL, "report what is computed"},
        {"r", HD_OPT_TOGGLE, &o.resume, 0, 0, NULL, "with -o: keep the step files of an interrupted run, write the rest"},
        {"i", HD_OPT_FUNC, &o, opt_fmt, 1, NULL, "-ia/-if/-id: headerless sky format"},
        {"o", HD_OPT_FUNC, &o, opt_fmt, 1, NULL, "-oa/-of/-od/-oc: output format"},
        HD_OPT_END};
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, "[options] DCspec [sky] | Vspec Tbsdf Dmat [sky]");
    o.header = !noheader;
    /* headers record the command without -r: a resumed series is that of
     * an uninterrupted run */
    char **hargv = hd_calloc((size_t)argc + 1, sizeof *hargv);
    if (!hargv) hd_die();
    int hargc = 0;
    for (int i = 0; i < argc; i++)
        if (!(o.resume && (!strcmp(argv[i], "-r") || !strcmp(argv[i], "-r+")))) hargv[hargc++] = argv[i];
    o.cmd_argc = hargc;
    o.cmd_argv = hargv;
    if (o.resume && !o.outspec) hd_die_msg("-r needs -o (one file per time step)");
    int n = p.argc - p.first;
    if (n < 1 || n > 4) {
        hd_fail(HD_ERR_USAGE, "expected DCspec [sky] or Vspec Tbsdf Dmat [sky]");
        hd_report_error();
        hd_opt_usage(table, "[options] DCspec [sky] | Vspec Tbsdf Dmat [sky]");
        return 1;
    }
    if (hd_dctimestep(n, p.argv + p.first, &o) != HD_OK) hd_die();
    hd_optparse_free(&p);
    free(hargv);
    return 0;
}

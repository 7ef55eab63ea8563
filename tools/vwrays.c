/* vwrays — compute the rays of a view, for rtrace/rcontrib (heliodon). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/common.h"
#include "heliodon/options.h"
#include "heliodon/render.h"
#include "heliodon/view.h"

static hd_view V;
static int xres = 512, yres = 512, dims;
static double pa = 1, pj = 0;
static int repeat = 1;
static char fmt = 'a';

static int opt_view(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)opt; (void)ctx;
    int k = hd_view_parse_arg(&V, argc, argv, i);
    if (k == 0) { hd_fail(HD_ERR_USAGE, "unknown view option %s", argv[i]); return -1; }
    return k < 0 ? -1 : k - 1;
}

static int opt_format(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)opt; (void)argc; (void)ctx;
    const char *f = argv[i] + 2;
    if (strlen(f) != 1 || !strchr("afd", f[0])) {
        hd_fail(HD_ERR_USAGE, "option %s: expected -fa, -ff or -fd", argv[i]);
        return -1;
    }
    fmt = f[0];
    return 0;
}

int main(int argc, char **argv)
{
    hd_view_default(&V);
    hd_opt table[] = {
        {"v", HD_OPT_FUNC, 0, opt_view, 1, "...", "view options -vt? -vp -vd -vu -vh -vv -vo -va -vs -vl -vf"},
        {"x", HD_OPT_INT, &xres, 0, 0, "N", "maximum x resolution"},
        {"y", HD_OPT_INT, &yres, 0, 0, "N", "maximum y resolution"},
        {"pa", HD_OPT_REAL, &pa, 0, 0, "f", "pixel aspect ratio (0 = keep -x -y)"},
        {"pj", HD_OPT_REAL, &pj, 0, 0, "f", "pixel jitter (default 0)"},
        {"c", HD_OPT_INT, &repeat, 0, 0, "N", "write every pixel's ray N times (jittered apart with -pj; rcontrib -c N)"},
        {"f", HD_OPT_FUNC, 0, opt_format, 1, 0, "-fa | -ff | -fd: output format"},
        {"d", HD_OPT_TOGGLE, &dims, 0, 0, 0, "print the resolution options (-x X -y Y [-ld+]) and exit"},
        HD_OPT_END
    };
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, "[view options] [-x X -y Y] [-pa A] [-pj J] [-c N] [-f{a|f|d}] [-d]");
    if (p.first < p.argc) hd_die_msg("unexpected argument '%s' (vwrays -i is not supported)", p.argv[p.first]);
    if (hd_view_setup(&V) != HD_OK) hd_die();
    if (dims) {
        int x = xres, y = yres;
        double a = pa;
        if (x <= 0 || y <= 0) hd_die_msg("resolution %d x %d out of range", x, y);
        hd_view_normaspect(hd_view_aspect(&V), &a, &x, &y);
        printf("-x %d -y %d%s\n", x, y, V.va > 0 ? " -ld+" : "");
        hd_optparse_free(&p);
        return 0;
    }
    if (hd_vwrays_run(&V, xres, yres, pa, pj, repeat, fmt, 1, stdout) != HD_OK) hd_die();
    hd_optparse_free(&p);
    return 0;
}

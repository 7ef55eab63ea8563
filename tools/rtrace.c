/* rtrace — trace rays (radiance or irradiance) through a Radiance scene (heliodon). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/common.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/options.h"
#include "heliodon/render.h"
#include "heliodon/scene.h"

static hd_rtrace_opts O;
static int Iflag, iflag, warn = 1;

static int opt_format(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)opt; (void)argc; (void)ctx;
    const char *f = argv[i] + 2;   /* after "-f" */
    size_t n = strlen(f);
    if (n < 1 || n > 2 || !strchr("afd", f[0]) || (n == 2 && !strchr("afd", f[1]))) {
        hd_fail(HD_ERR_USAGE, "option %s: expected -f[afd] or -f[afd][afd] (ascii, float, double)", argv[i]);
        return -1;
    }
    O.fin = f[0];
    O.fout = n == 2 ? f[1] : f[0];
    return 0;
}

static int opt_output(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)opt; (void)argc; (void)ctx;
    const char *s = argv[i] + 2;
    if (strlen(s) >= sizeof O.outspec) { hd_fail(HD_ERR_USAGE, "option %s: specification too long", argv[i]); return -1; }
    snprintf(O.outspec, sizeof O.outspec, "%s", s);
    return 0;
}

int main(int argc, char **argv)
{
    hd_rtrace_defaults(&O);
    O.r.as = 512;   /* Radiance rtrace's -as */
    hd_opt render_tab[HD_RENDER_NOPTS];
    hd_render_option_table(render_tab, &O.r);
    hd_opt table[] = {
        {"I", HD_OPT_TOGGLE, &Iflag, 0, 0, 0, "irradiance at the input points (direction = surface normal)"},
        {"i", HD_OPT_TOGGLE, &iflag, 0, 0, 0, "irradiance at the surfaces hit by the rays"},
        {"h", HD_OPT_TOGGLE, &O.header, 0, 0, 0, "write an information header (default on)"},
        {"w", HD_OPT_TOGGLE, &warn, 0, 0, 0, "warnings (default on)"},
        {"f", HD_OPT_FUNC, 0, opt_format, 1, 0, "-f[afd][afd]: input/output format (ascii, float, double)"},
        {"o", HD_OPT_FUNC, 0, opt_output, 1, 0, "-o[odvpnNlLwmMs]: output specification (default -ov)"},
        {"x", HD_OPT_INT, &O.xres, 0, 0, "N", "x resolution (recorded in the header)"},
        {"y", HD_OPT_INT, &O.yres, 0, 0, "N", "y resolution (recorded in the header)"},
        {"n", HD_OPT_INT, &O.nthreads, 0, 0, "N", "number of threads (0 = all processors)"},
        {"", HD_OPT_TABLE, render_tab, 0, 0, 0, "rendering options (render.h)"},
        HD_OPT_END
    };
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, "[options] scene.rad|scene.oct ... < rays");
    hd_set_warnings(warn);
    if (Iflag && iflag) hd_die_msg("-I and -i cannot be used together");
    O.irrad = Iflag ? 1 : iflag ? 2 : 0;
    if (O.r.ad < 0 || O.r.ab < 0) hd_die_msg("-ab and -ad must not be negative");
    if (hd_rtrace_check_spec(O.outspec, O.fout != 'a', NULL) != HD_OK) hd_die();
    hd_scene sc;
    hd_scene_init(&sc);
    hd_tscene *ts = NULL;
    hd_header hdr;
    hd_header_init(&hdr);
    if (hd_render_load_scene(p.argc - p.first, p.argv + p.first, &sc, &ts, &hdr, argc, argv) != HD_OK) hd_die();
    hd_header_add_date(&hdr);
    hd_renderer r = {ts, O.r};
    hd_istream *in;
    if (hd_istream_open(&in, "-") != HD_OK) hd_die();
    if (hd_rtrace_run(&r, &O, &sc, in, stdout, &hdr) != HD_OK) hd_die();
    hd_istream_close(in);
    hd_header_free(&hdr);
    hd_tscene_free(ts);
    hd_scene_free(&sc);
    hd_optparse_free(&p);
    return 0;
}

/* rpict — render a Radiance picture of a scene (heliodon). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/common.h"
#include "heliodon/header.h"
#include "heliodon/options.h"
#include "heliodon/picture.h"
#include "heliodon/render.h"
#include "heliodon/scene.h"
#include "heliodon/view.h"

static hd_rpict_opts O;
static hd_render_opts R;
static int warn = 1;
static const char *outname;
static double ignored_d;
static int ignored_i;

static int opt_view(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)opt; (void)ctx;
    int k = hd_view_parse_arg(&O.view, argc, argv, i);
    if (k == 0) { hd_fail(HD_ERR_USAGE, "unknown view option %s", argv[i]); return -1; }
    return k < 0 ? -1 : k - 1;
}

int main(int argc, char **argv)
{
    hd_render_defaults(&R);
    R.as = 128;   /* Radiance rpict's -as */
    hd_view_default(&O.view);
    O.xres = O.yres = 512;
    O.pa = 1;
    O.pj = 0.67;
    O.nthreads = 1;
    hd_opt render_tab[HD_RENDER_NOPTS];
    hd_render_option_table(render_tab, &R);
    hd_opt table[] = {
        {"v", HD_OPT_FUNC, 0, opt_view, 1, "...", "view options -vt? -vp -vd -vu -vh -vv -vo -va -vs -vl -vf"},
        {"x", HD_OPT_INT, &O.xres, 0, 0, "N", "maximum x resolution"},
        {"y", HD_OPT_INT, &O.yres, 0, 0, "N", "maximum y resolution"},
        {"pa", HD_OPT_REAL, &O.pa, 0, 0, "f", "pixel aspect ratio (0 = keep -x -y)"},
        {"pj", HD_OPT_REAL, &O.pj, 0, 0, "f", "pixel jitter (0 = pixel centres)"},
        {"spp", HD_OPT_INT, &O.spp, 0, 0, "N", "independent samples per pixel, averaged (heliodon extension)"},
        {"ps", HD_OPT_INT, &ignored_i, 0, 0, "N", "ignored (every pixel is traced)"},
        {"pt", HD_OPT_REAL, &ignored_d, 0, 0, "f", "ignored"},
        {"t", HD_OPT_REAL, &O.report, 0, 0, "s", "progress report interval (seconds)"},
        {"o", HD_OPT_STRING, &outname, 0, 0, "file", "output picture (default standard output)"},
        {"w", HD_OPT_TOGGLE, &warn, 0, 0, 0, "warnings (default on)"},
        {"n", HD_OPT_INT, &O.nthreads, 0, 0, "N", "number of threads (0 = all processors)"},
        {"", HD_OPT_TABLE, render_tab, 0, 0, 0, "rendering options (render.h)"},
        HD_OPT_END
    };
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, "[options] scene.rad|scene.oct ... > picture.hdr");
    hd_set_warnings(warn);
    if (R.ad < 0 || R.ab < 0) hd_die_msg("-ab and -ad must not be negative");
    if (O.spp < 0 || O.spp > 100000) hd_die_msg("-spp %d out of range", O.spp);
    if (hd_view_setup(&O.view) != HD_OK) hd_die();
    hd_scene sc;
    hd_scene_init(&sc);
    hd_tscene *ts = NULL;
    hd_header hdr;
    hd_header_init(&hdr);
    if (hd_render_load_scene(p.argc - p.first, p.argv + p.first, &sc, &ts, &hdr, argc, argv) != HD_OK) hd_die();
    hd_renderer r = {ts, R};
    float *pix = NULL;
    if (hd_rpict_render(&r, &O, &pix) != HD_OK) hd_die();
    char vline[1024];
    hd_view_format(&O.view, vline, sizeof vline);
    hd_header_appendf(&hdr, "VIEW= %s", vline);
    hd_header_add_date(&hdr);
    hd_header_append(&hdr, "PRIMARIES= 0.6400 0.3300 0.2900 0.6000 0.1500 0.0600 0.3333 0.3333");
    if (O.pa > 0 && O.pa != 1) hd_header_appendf(&hdr, "PIXASPECT=%f", O.pa);
    hd_picture pic;
    hd_picture_init(&pic);
    pic.xres = O.xres;
    pic.yres = O.yres;
    pic.pix = pix;
    pic.fmt = HD_PIC_RGBE;
    if (hd_picture_save(outname ? outname : "-", &pic, &hdr) != HD_OK) hd_die();
    free(pix);
    hd_header_free(&hdr);
    hd_tscene_free(ts);
    hd_scene_free(&sc);
    hd_optparse_free(&p);
    return 0;
}

/* evalglare — glare evaluation of a 180-degree fisheye picture (Radiance
 * compatible options and output).  See docs/man/evalglare.1. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/common.h"
#include "heliodon/glare.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/options.h"
#include "heliodon/picture.h"

typedef struct ctx_t {
    hd_glare_view view;
    hd_glare_viewargs va; /* view options given on the command line (va.view = &view) */
    hd_glare_opts o;
    int detail, ev_only, fast, verbose;
    const char *checkfile;
} ctx_t;

static int opt_view(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt;
    ctx_t *c = vctx;
    if (!strcmp(argv[i], "-v")) { c->verbose = 1; return 0; }
    return hd_glare_view_option(&c->va, argc, argv, i);
}

static int opt_task(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt;
    ctx_t *c = vctx;
    double v[3];
    if (i + 3 >= argc) { hd_fail(HD_ERR_USAGE, "option %s expects xpos ypos angle", argv[i]); return -1; }
    for (int k = 0; k < 3; k++)
        if (hd_parse_double(argv[i + 1 + k], &v[k])) {
            hd_fail(HD_ERR_USAGE, "option %s: expected a number, found \"%s\"", argv[i], argv[i + 1 + k]);
            return -1;
        }
    c->o.task = 1;
    c->o.task_x = v[0];
    c->o.task_y = v[1];
    c->o.task_angle = v[2];
    return 3;
}

static int opt_corr(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt;
    ctx_t *c = vctx;
    if (i + 1 >= argc) { hd_fail(HD_ERR_USAGE, "option -C expects a correction mode (l+ or l-)"); return -1; }
    const char *m = argv[i + 1];
    if (!strcmp(m, "l+") || !strcmp(m, "l")) c->o.lowlight = 1;
    else if (!strcmp(m, "l-")) c->o.lowlight = 0;
    else {
        hd_fail(HD_ERR_USAGE, "option -C: unsupported correction mode \"%s\" (heliodon knows l+ and l-)", m);
        return -1;
    }
    return 1;
}

static int opt_nopeak(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt; (void)argc; (void)argv; (void)i;
    ((ctx_t *)vctx)->o.peak_extract = 0;
    return 0;
}

static int opt_peak(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt; (void)argc; (void)argv; (void)i;
    ((ctx_t *)vctx)->o.peak_extract = 1;
    return 0;
}

static int opt_peakval(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt;
    ctx_t *c = vctx;
    if (i + 1 >= argc || hd_parse_double(argv[i + 1], &c->o.peak_value) || !(c->o.peak_value > 0)) {
        hd_fail(HD_ERR_USAGE, "option -Y expects a positive luminance");
        return -1;
    }
    c->o.peak_extract = 1;
    return 1;
}

static int opt_unsupported(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt; (void)argc; (void)vctx;
    hd_fail(HD_ERR_UNSUPPORTED, "option %s of Radiance's evalglare is not supported by heliodon", argv[i]);
    return -1;
}

int main(int argc, char **argv)
{
    ctx_t c;
    memset(&c, 0, sizeof c);
    hd_view_default(&c.view);
    c.va.view = &c.view;
    hd_glare_opts_default(&c.o);
    int smooth = 0;
    const hd_opt table[] = {
        {"b", HD_OPT_REAL, &c.o.threshold, 0, 0, "value", "threshold: > 100 cd/m2 absolute, else factor x mean (2000)"},
        {"r", HD_OPT_REAL, &c.o.search_radius, 0, 0, "angle", "search opening angle in radians (0.2)"},
        {"y", HD_OPT_FUNC, &c, opt_peak, 0, NULL, "peak extraction on (default)"},
        {"Y", HD_OPT_FUNC, &c, opt_peakval, 0, "lum", "peak extraction with this luminance (50000)"},
        {"x", HD_OPT_FUNC, &c, opt_nopeak, 0, NULL, "no peak extraction"},
        {"d", HD_OPT_TOGGLE, &c.detail, 0, 0, NULL, "detailed output: source table and 23 values"},
        {"V", HD_OPT_TOGGLE, &c.ev_only, 0, 0, NULL, "print the vertical illuminance only"},
        {"1", HD_OPT_TOGGLE, &c.fast, 0, 0, NULL, "print DGP only"},
        {"i", HD_OPT_REAL, &c.o.ev_external, 0, 0, "Ev", "use this vertical illuminance (lux)"},
        {"q", HD_OPT_INT, &c.o.bg_mode, 0, 0, "mode", "background luminance: 0 (Ev-Edir)/pi, 1 mean, 2 Ev/pi"},
        {"C", HD_OPT_FUNC, &c, opt_corr, 0, "l+|l-", "low-light DGP correction on/off (off)"},
        {"c", HD_OPT_STRING, &c.checkfile, 0, 0, "file", "write a check picture with the sources coloured"},
        {"t", HD_OPT_FUNC, &c, opt_task, 0, "x y angle", "task area: centre pixel and opening angle (rad)"},
        {"T", HD_OPT_FUNC, &c, opt_task, 0, "x y angle", "same as -t"},
        {"s", HD_OPT_TOGGLE, &smooth, 0, 0, NULL, "smoothing (not supported)"},
        {"v", HD_OPT_FUNC, &c, opt_view, 1, "...", "view options -vt? -vp -vd -vu -vh -vv -vs -vl -vf file; -v verbose"},
        {"A", HD_OPT_FUNC, &c, opt_unsupported, 0, NULL, "(not supported)"},
        {"B", HD_OPT_FUNC, &c, opt_unsupported, 0, NULL, "(not supported)"},
        {"G", HD_OPT_FUNC, &c, opt_unsupported, 0, NULL, "(not supported)"},
        {"g", HD_OPT_FUNC, &c, opt_unsupported, 0, NULL, "(not supported)"},
        {"I", HD_OPT_FUNC, &c, opt_unsupported, 0, NULL, "(not supported)"},
        {"2", HD_OPT_FUNC, &c, opt_unsupported, 0, NULL, "(not supported)"},
        {"3", HD_OPT_FUNC, &c, opt_unsupported, 0, NULL, "(not supported)"},
        HD_OPT_END};
    const char *syn = "[-b thr][-r angle][-y|-Y lum|-x][-d][-V][-1][-i Ev][-q mode][-C l+][-c check.hdr]"
                      "[-t x y angle][-vf file][-vt? -vh h -vv v ...] [picture.hdr]";
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, syn);
    if (smooth) hd_die_msg("option -s (smoothing) is not supported by heliodon");
    if (p.argc - p.first > 1) hd_die_msg("at most one picture expected, got %d operands", p.argc - p.first);
    const char *path = p.first < p.argc ? p.argv[p.first] : "-";

    hd_picture pic;
    hd_picture_init(&pic);
    if (hd_picture_read(path, &pic)) hd_die();

    /* view: command line (which then must be complete), else the header */
    hd_glare_view view = c.view;
    if (c.va.nview) {
        if (!c.va.has_t || !c.va.has_h || !c.va.has_v)
            hd_die_msg("a view given on the command line must contain at least -vt?, -vh and -vv "
                       "(e.g. -vta -vh 180 -vv 180), or use -vf file");
    } else {
        int found = 0;
        hd_view_default(&view);
        if (hd_view_from_header(&view, &pic.hdr, &found)) hd_die();
        if (!found)
            hd_die_msg("%s: no VIEW= line in the picture header; give the view with -vf file or "
                       "-vta -vh 180 -vv 180", path);
    }
    if (hd_glare_view_check(&view)) {
        hd_fail_context(HD_ERR_UNSUPPORTED, "%s", path);
        hd_die();
    }
    if (pic.xres != pic.yres)
        hd_warn("%s: picture is %d x %d; a 180-degree fisheye is normally square", path, pic.xres, pic.yres);

    float *lum;
    if (hd_glare_picture_lum(&pic, &lum)) {
        hd_fail_context(HD_ERR_FORMAT, "%s", path);
        hd_die();
    }
    hd_glare_geom *g;
    if (hd_glare_geom_new(&g, &view, pic.xres, pic.yres)) hd_die();
    if (c.ev_only) {
        printf("%f\n", hd_glare_ev_lum(g, lum));
        hd_glare_geom_free(g);
        free(lum);
        hd_picture_free(&pic);
        hd_optparse_free(&p);
        return fflush(stdout) == 0 ? 0 : 1;
    }
    c.o.want_map = c.checkfile != NULL;
    hd_glare_result r;
    if (hd_glare_eval_lum(g, lum, &c.o, &r)) hd_die();
    if (r.ev < 100)
        hd_warn("vertical illuminance %.1f lux is below 100 lux: the glare metrics are not meant for it", r.ev);
    else if (r.ev < 380 && !c.o.lowlight)
        hd_warn("vertical illuminance %.1f lux is below 380 lux: DGP is unreliable (see -C l+)", r.ev);
    if (c.verbose)
        fprintf(stderr, "%s: threshold %g cd/m2, %d glare source(s), E_v %.1f lux\n", hd_progname(), r.threshold,
                r.nsources, r.ev);

    if (c.checkfile) {
        /* sources painted in cycling colours, the rest unchanged */
        static const float pal[6][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}, {1, 0, 1}, {0, 1, 1}};
        size_t np = (size_t)pic.xres * pic.yres;
        for (size_t k = 0; k < np; k++) {
            int s = r.source_map[k];
            if (s < 0) continue;
            double L = hd_glare_luminance(pic.pix + 3 * k) / 179.0;
            for (int ch = 0; ch < 3; ch++) pic.pix[3 * k + ch] = (float)(pal[s % 6][ch] * L);
        }
        hd_header h;
        if (hd_header_copy(&h, &pic.hdr) || hd_header_add_command(&h, argc, argv) || hd_header_add_software(&h))
            hd_die();
        if (hd_picture_save(c.checkfile, &pic, &h)) hd_die();
        hd_header_free(&h);
    }
    if (c.fast) printf("%f\n", r.dgp);
    else if (c.detail) hd_glare_write_detail(stdout, &r);
    else hd_glare_write_line(stdout, &r);
    if (fflush(stdout) != 0) hd_die_msg("error writing the standard output");
    hd_glare_result_free(&r);
    hd_glare_geom_free(g);
    free(lum);
    hd_picture_free(&pic);
    hd_optparse_free(&p);
    return 0;
}

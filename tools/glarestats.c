/* glarestats — annual glare statistics over a sequence of hourly fisheye
 * pictures: CSV (hour, Ev, DGP, DGI, ...), 95th percentiles, comfort
 * classes and the operated-shade schedule.  See docs/man/glarestats.1. */
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
    hd_glare_viewargs va; /* va.view = &view */
    hd_glare_opts o;
} ctx_t;

static int opt_view(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt;
    ctx_t *c = vctx;
    return hd_glare_view_option(&c->va, argc, argv, i);
}

static int opt_nopeak(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt; (void)argc; (void)argv; (void)i;
    ((ctx_t *)vctx)->o.peak_extract = 0;
    return 0;
}

static int opt_corr(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)opt;
    ctx_t *c = vctx;
    if (i + 1 >= argc || (strcmp(argv[i + 1], "l+") && strcmp(argv[i + 1], "l-"))) {
        hd_fail(HD_ERR_USAGE, "option -C expects l+ or l-");
        return -1;
    }
    c->o.lowlight = argv[i + 1][1] == '+';
    return 1;
}

typedef struct item_t { double hour; char *path; } item_t;

/* "hour path" lines; '#' comments and blank lines skipped. */
static hd_status read_list(const char *name, item_t **out, size_t *n)
{
    hd_istream *s;
    hd_status st = hd_istream_open(&s, name);
    if (st) return st;
    char line[4096];
    long len;
    size_t cap = 0;
    *out = NULL;
    *n = 0;
    while ((len = hd_istream_getline(s, line, sizeof line)) != -1) {
        unsigned long ln = hd_istream_lineno(s) - 1;
        if (len == -2) { st = hd_fail(HD_ERR_FORMAT, "%s: line %lu: line too long", name, ln); break; }
        char *p = line;
        while (*p == ' ' || *p == '\t') p++;
        if (!*p || *p == '#') continue;
        char *end;
        double h = strtod(p, &end);
        if (end == p || (*end != ' ' && *end != '\t')) {
            st = hd_fail(HD_ERR_FORMAT, "%s: line %lu: expected \"hour picture\", found \"%s\"", name, ln, line);
            break;
        }
        while (*end == ' ' || *end == '\t') end++;
        size_t l = strlen(end);
        while (l && (end[l - 1] == ' ' || end[l - 1] == '\t' || end[l - 1] == '\r')) end[--l] = 0;
        if (!l) { st = hd_fail(HD_ERR_FORMAT, "%s: line %lu: missing picture name after the hour", name, ln); break; }
        if (*n == cap) {
            size_t nc = cap ? 2 * cap : 256;
            item_t *t = hd_realloc_array(*out, nc, sizeof(item_t));
            if (!t) { st = HD_ERR_NOMEM; break; }
            *out = t;
            cap = nc;
        }
        (*out)[*n].hour = h;
        if (!((*out)[*n].path = hd_strdup(end))) { st = HD_ERR_NOMEM; break; }
        (*n)++;
    }
    hd_status cs = hd_istream_close(s);
    return st ? st : cs;
}

int main(int argc, char **argv)
{
    ctx_t c;
    memset(&c, 0, sizeof c);
    hd_view_default(&c.view);
    c.va.view = &c.view;
    hd_glare_opts_default(&c.o);
    double limit = HD_GLARE_SHADE_LIMIT;
    const char *csv = NULL, *summary = NULL, *list = NULL;
    const hd_opt table[] = {
        {"b", HD_OPT_REAL, &c.o.threshold, 0, 0, "value", "threshold as evalglare -b (2000)"},
        {"r", HD_OPT_REAL, &c.o.search_radius, 0, 0, "angle", "search opening angle, radians (0.2)"},
        {"Y", HD_OPT_REAL, &c.o.peak_value, 0, 0, "lum", "peak extraction luminance (50000)"},
        {"x", HD_OPT_FUNC, &c, opt_nopeak, 0, NULL, "no peak extraction"},
        {"q", HD_OPT_INT, &c.o.bg_mode, 0, 0, "mode", "background luminance mode as evalglare -q"},
        {"C", HD_OPT_FUNC, &c, opt_corr, 0, "l+|l-", "low-light DGP correction"},
        {"s", HD_OPT_REAL, &limit, 0, 0, "dgp", "shade closes when DGP >= this (0.40)"},
        {"l", HD_OPT_STRING, &list, 0, 0, "list", "file of \"hour picture\" lines (- = stdin)"},
        {"o", HD_OPT_STRING, &csv, 0, 0, "file.csv", "CSV output (default: standard output)"},
        {"S", HD_OPT_STRING, &summary, 0, 0, "file", "summary output (default: standard error)"},
        {"v", HD_OPT_FUNC, &c, opt_view, 1, "...", "view override: -vf file or -vt? -vh -vv ..."},
        HD_OPT_END};
    const char *syn = "[options] {-l list | picture ...}";
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, syn);
    if (c.va.nview && (!c.va.has_t || !c.va.has_h || !c.va.has_v))
        hd_die_msg("a view given on the command line must contain -vt?, -vh and -vv (or use -vf file)");
    if (!(limit > 0 && limit <= 1)) hd_die_msg("-s %g: the shade limit must be a DGP in (0, 1]", limit);

    item_t *items = NULL;
    size_t n = 0;
    if (list) {
        if (p.first < p.argc) hd_die_msg("give either -l list or pictures, not both");
        if (read_list(list, &items, &n)) hd_die();
    } else {
        n = (size_t)(p.argc - p.first);
        items = hd_calloc(n ? n : 1, sizeof(item_t));
        if (!items) hd_die();
        for (size_t k = 0; k < n; k++) {
            items[k].hour = (double)k;
            items[k].path = hd_strdup(p.argv[p.first + (int)k]);
            if (!items[k].path) hd_die();
        }
    }
    if (n == 0) hd_die_msg("no pictures to evaluate (give pictures or -l list)");

    /* every picture must be readable before the (long) evaluation starts */
    for (size_t k = 0; k < n; k++) {
        if (!strcmp(items[k].path, "-")) hd_die_msg("pictures cannot come from standard input");
        FILE *t = fopen(items[k].path, "rb");
        if (!t) hd_die_msg("%s: cannot open picture (hour %g)", items[k].path, items[k].hour);
        fclose(t);
    }
    hd_ofile *of = NULL;
    if (hd_ofile_open(&of, csv)) hd_die();
    FILE *fp = hd_ofile_fp(of);
    hd_glare_annual a;
    hd_glare_annual_init(&a, limit);
    hd_glare_geom *g = NULL;
    hd_glare_view gview;
    int gx = 0, gy = 0;
    for (size_t k = 0; k < n; k++) {
        hd_picture pic;
        hd_picture_init(&pic);
        if (hd_picture_read(items[k].path, &pic)) hd_die();
        hd_glare_view v = c.view;
        if (!c.va.nview) {
            int found = 0;
            hd_view_default(&v);
            if (hd_view_from_header(&v, &pic.hdr, &found)) hd_die();
            if (!found)
                hd_die_msg("%s: no VIEW= line in the picture header (give the view with -vf or -vta -vh 180 -vv 180)",
                           items[k].path);
        }
        if (hd_glare_view_check(&v)) {
            hd_fail_context(HD_ERR_UNSUPPORTED, "%s", items[k].path);
            hd_die();
        }
        if (!g || gx != pic.xres || gy != pic.yres || memcmp(&gview, &v, sizeof v)) {
            hd_glare_geom_free(g);
            if (hd_glare_geom_new(&g, &v, pic.xres, pic.yres)) hd_die();
            gview = v;
            gx = pic.xres;
            gy = pic.yres;
        }
        float *lum;
        if (hd_glare_picture_lum(&pic, &lum)) { hd_fail_context(HD_ERR_FORMAT, "%s", items[k].path); hd_die(); }
        hd_glare_result r;
        if (hd_glare_eval_lum(g, lum, &c.o, &r)) { hd_fail_context(HD_ERR_FORMAT, "%s", items[k].path); hd_die(); }
        int closed = 0;
        if (k == 0) hd_glare_csv_header(fp);
        if (hd_glare_annual_add(&a, items[k].hour, r.ev, r.dgp, r.dgi, &closed)) hd_die();
        hd_glare_csv_row(fp, items[k].hour, &r, closed);
        hd_glare_result_free(&r);
        free(lum);
        hd_picture_free(&pic);
    }
    if (hd_ofile_commit(of)) hd_die();
    if (summary) {
        hd_ofile *sf;
        if (hd_ofile_open(&sf, summary)) hd_die();
        hd_glare_annual_write_summary(hd_ofile_fp(sf), &a);
        if (hd_ofile_commit(sf)) hd_die();
    } else {
        hd_glare_annual_write_summary(stderr, &a);
    }
    hd_glare_annual_free(&a);
    hd_glare_geom_free(g);
    for (size_t k = 0; k < n; k++) free(items[k].path);
    free(items);
    hd_optparse_free(&p);
    return 0;
}

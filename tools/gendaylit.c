/* gendaylit — Perez all-weather sky description (Radiance compatible). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/options.h"
#include "heliodon/sky.h"
#include "heliodon/skytime.h"

static const char *syn = "month day hour [-y year] {-W DNI DHI|-G DirHoriz DHI|-L DNIlux DHIlux|-P eps delta|-E GHI} "
                         "[-s][-g rfl][-O 0|1|2][-d dewpoint][-a lat][-o lon][-m mer][-w]\n"
                         "       gendaylit -ang altitude azimuth {-W|-G|-L|-P ...} [options]";

typedef struct modectx { hd_daylit_opts *o; int set; } modectx;

static int mode_opt(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    modectx *m = vctx;
    int n = opt->name[0] == 'E' ? 1 : 2;
    if (i + n >= argc) { hd_fail(HD_ERR_USAGE, "option %s expects %d values", argv[i], n); return -1; }
    double v[2] = {0, 0};
    for (int k = 0; k < n; k++)
        if (hd_parse_double(argv[i + 1 + k], &v[k])) {
            hd_fail(HD_ERR_USAGE, "option %s: expected a number, found \"%s\"", argv[i], argv[i + 1 + k]);
            return -1;
        }
    if (v[0] < 0 || v[1] < 0) { hd_fail(HD_ERR_USAGE, "option %s: negative value", argv[i]); return -1; }
    m->o->mode = opt->name[0];
    m->o->v1 = v[0];
    m->o->v2 = v[1];
    m->set = 1;
    return n;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    hd_daylit_opts o;
    hd_daylit_opts_default(&o);
    int first;
    hd_skywhen w;
    hd_status wst = argc >= 4 ? hd_skywhen_parse(argv, &w) : HD_ERR_USAGE;
    if (wst == HD_ERR_USAGE) {
        if (argc >= 4) hd_report_error();
        hd_opt_usage(NULL, syn);
        return 1;
    }
    if (wst) hd_die();
    first = 4;
    if (w.use_angles) {
        o.alt_deg = w.alt_deg;
        o.azi_deg = w.azi_deg;
        o.use_angles = 1;
    } else {
        o.month = w.t.month;
        o.day = w.t.day;
        o.hour = w.t.hour;
        o.solar_time = w.t.solar;
        o.jd = hd_julian_day(w.t.month, w.t.day);
        if (w.t.has_zone) o.site.meridian = w.t.meridian;
    }
    double lat = 37.8, lon = 122.0, mer = 120.0;   /* Radiance's defaults (San Francisco) */
    int year = 0, nowarn = 0, nosun = 0, outtype = 0, mer_set = 0;
    modectx mc = {&o, 0};
    hd_opt table[] = {
        {"W", HD_OPT_FUNC, &mc, mode_opt, 0, "DNI DHI", "direct normal and diffuse horizontal irradiance (W/m2)"},
        {"G", HD_OPT_FUNC, &mc, mode_opt, 0, "DirH DHI", "direct horizontal and diffuse horizontal irradiance (W/m2)"},
        {"L", HD_OPT_FUNC, &mc, mode_opt, 0, "DNI DHI", "direct normal and diffuse horizontal illuminance (lux)"},
        {"P", HD_OPT_FUNC, &mc, mode_opt, 0, "eps delta", "Perez clearness and brightness"},
        {"E", HD_OPT_FUNC, &mc, mode_opt, 0, "GHI", "global horizontal irradiance, split with the Erbs model"},
        {"a", HD_OPT_REAL, &lat, 0, 0, "lat", "site latitude (degrees north)"},
        {"o", HD_OPT_REAL, &lon, 0, 0, "lon", "site longitude (degrees WEST)"},
        {"m", HD_OPT_FUNC, &mer_set, NULL, 0, "mer", "standard meridian (degrees WEST)"},
        {"y", HD_OPT_INT, &year, 0, 0, "year", "year (accepted, not used)"},
        {"s", HD_OPT_TOGGLE, &nosun, 0, 0, 0, "no sun"},
        {"g", HD_OPT_REAL, &o.ground_refl, 0, 0, "rfl", "ground reflectance (0.2)"},
        {"O", HD_OPT_INT, &outtype, 0, 0, "0|1|2", "visible radiance, solar radiance, luminance"},
        {"d", HD_OPT_REAL, &o.dewpoint, 0, 0, "Td", "dew point (C) for the precipitable water"},
        {"w", HD_OPT_TOGGLE, &nowarn, 0, 0, 0, "no warnings"},
        HD_OPT_END};
    table[7].kind = HD_OPT_REAL;
    table[7].dest = &mer;
    /* options after the date: parse them as their own vector */
    int sub_argc = argc - first + 1;
    char **sub = hd_malloc_array((size_t)sub_argc + 1, sizeof(char *));
    if (!sub) hd_die();
    sub[0] = argv[0];
    for (int i = first; i < argc; i++) sub[i - first + 1] = argv[i];
    sub[sub_argc] = NULL;
    hd_optparse p;
    if (hd_opt_parse(&p, sub_argc, sub, table)) { hd_report_error(); hd_opt_usage(table, syn); return 1; }
    if (p.first < p.argc) { fprintf(stderr, "%s: unexpected argument '%s'\n", hd_progname(), p.argv[p.first]); return 1; }
    if (!mc.set) { fprintf(stderr, "%s: one of -W, -G, -L, -P or -E is required\n", hd_progname()); hd_opt_usage(table, syn); return 1; }
    if (outtype < 0 || outtype > 2) hd_die_msg("-O %d: expected 0, 1 or 2", outtype);
    if (lat < -90 || lat > 90) hd_die_msg("-a %g: latitude out of range", lat);
    if (nowarn) hd_set_warnings(0);
    o.output = outtype;
    o.with_sun = !nosun;
    o.site.lat = lat;
    o.site.lon = lon;
    /* the meridian of a zone suffix wins unless -m is given after it */
    int i_m = 0;
    for (int i = 1; i < p.argc; i++) if (!strcmp(p.argv[i], "-m")) i_m = 1;
    if (i_m || !o.site.meridian) o.site.meridian = i_m ? mer : (o.site.meridian ? o.site.meridian : mer);
    hd_header h;
    hd_header_init(&h);
    hd_header_add_command(&h, argc, argv);
    char *cmd = h.text ? hd_strdup(h.text) : hd_strdup("gendaylit");
    if (cmd && *cmd && cmd[strlen(cmd) - 1] == '\n') cmd[strlen(cmd) - 1] = 0;
    hd_ofile *of;
    if (hd_ofile_open(&of, NULL)) hd_die();
    char warn[256];
    if (hd_gendaylit(hd_ofile_fp(of), &o, cmd, warn, sizeof warn)) hd_die();
    if (warn[0] && hd_warnings_enabled()) fprintf(stderr, "%s\n", warn);
    if (hd_ofile_commit(of)) hd_die();
    free(cmd);
    free(sub);
    hd_header_free(&h);
    hd_optparse_free(&p);
    return 0;
}

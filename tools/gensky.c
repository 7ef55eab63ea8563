/* gensky — CIE sky descriptions (Radiance compatible). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/options.h"
#include "heliodon/sky.h"
#include "heliodon/skytime.h"

static const char *syn = "month day hour [+s|-s|+i|-i|-c|-u][-g rfl][-t turb][-b zenbr|-B zenirr][-r solrad|-R solirr]"
                         "[-a lat][-o lon][-m mer]\n       gensky -ang altitude azimuth [options]";

typedef struct typectx { hd_gensky_opts *o; } typectx;

static int type_opt(const hd_opt *opt, int argc, char **argv, int i, void *vctx)
{
    (void)argc;
    typectx *t = vctx;
    int plus = argv[i][0] == '+';
    switch (opt->name[0]) {
    case 's': t->o->type = HD_SKY_CIE_CLEAR; t->o->with_sun = plus; break;
    case 'i': t->o->type = HD_SKY_CIE_INTERMEDIATE; t->o->with_sun = plus; break;
    case 'c': t->o->type = HD_SKY_CIE_OVERCAST; t->o->with_sun = 0; break;
    case 'u': t->o->type = HD_SKY_UNIFORM; t->o->with_sun = 0; break;
    }
    return 0;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    hd_gensky_opts o;
    hd_gensky_opts_default(&o);
    double lat = 37.8, lon = 122.0, mer = 120.0;   /* Radiance's defaults */
    int first, zone = 0;
    double zone_mer = 0;
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
        o.jd = hd_julian_day(w.t.month, w.t.day);
        o.hour = w.t.hour;
        o.solar_time = w.t.solar;
        zone = w.t.has_zone;
        zone_mer = w.t.meridian;
    }
    typectx tc = {&o};
    int mer_given = 0;
    hd_opt table[] = {
        {"s", HD_OPT_FUNC, &tc, type_opt, 0, 0, "+s CIE clear sky with sun, -s without"},
        {"i", HD_OPT_FUNC, &tc, type_opt, 0, 0, "+i CIE intermediate sky with sun, -i without"},
        {"c", HD_OPT_FUNC, &tc, type_opt, 0, 0, "CIE overcast sky"},
        {"u", HD_OPT_FUNC, &tc, type_opt, 0, 0, "uniform sky"},
        {"g", HD_OPT_REAL, &o.ground_refl, 0, 0, "rfl", "ground reflectance (0.2)"},
        {"t", HD_OPT_REAL, &o.turbidity, 0, 0, "turb", "turbidity (2.45)"},
        {"b", HD_OPT_REAL, &o.zenith_br, 0, 0, "W/sr/m2", "zenith brightness"},
        {"B", HD_OPT_REAL, &o.horiz_irr, 0, 0, "W/m2", "zenith brightness from diffuse horizontal irradiance"},
        {"r", HD_OPT_REAL, &o.solar_rad, 0, 0, "W/sr/m2", "solar radiance"},
        {"R", HD_OPT_REAL, &o.solar_irr, 0, 0, "W/m2", "solar radiance from direct normal irradiance"},
        {"a", HD_OPT_REAL, &lat, 0, 0, "lat", "site latitude (degrees north)"},
        {"o", HD_OPT_REAL, &lon, 0, 0, "lon", "site longitude (degrees WEST)"},
        {"m", HD_OPT_REAL, &mer, 0, 0, "mer", "standard meridian (degrees WEST)"},
        HD_OPT_END};
    int sub_argc = argc - first + 1;
    char **sub = hd_malloc_array((size_t)sub_argc + 1, sizeof(char *));
    if (!sub) hd_die();
    sub[0] = argv[0];
    for (int i = first; i < argc; i++) {
        sub[i - first + 1] = argv[i];
        if (!strcmp(argv[i], "-m")) mer_given = 1;
    }
    sub[sub_argc] = NULL;
    hd_optparse p;
    if (hd_opt_parse(&p, sub_argc, sub, table)) { hd_report_error(); hd_opt_usage(table, syn); return 1; }
    if (p.first < p.argc) { fprintf(stderr, "%s: unexpected argument '%s'\n", hd_progname(), p.argv[p.first]); return 1; }
    if (lat < -90 || lat > 90) hd_die_msg("-a %g: latitude out of range", lat);
    if (o.ground_refl < 0 || o.ground_refl > 1) hd_die_msg("-g %g: reflectance out of range 0..1", o.ground_refl);
    if (o.turbidity < 1) hd_die_msg("-t %g: turbidity must be >= 1", o.turbidity);
    o.site.lat = lat;
    o.site.lon = lon;
    o.site.meridian = (zone && !mer_given) ? zone_mer : mer;
    hd_header h;
    hd_header_init(&h);
    hd_header_add_command(&h, argc, argv);
    char *cmd = h.text ? hd_strdup(h.text) : hd_strdup("gensky");
    if (cmd && *cmd && cmd[strlen(cmd) - 1] == '\n') cmd[strlen(cmd) - 1] = 0;
    hd_ofile *of;
    if (hd_ofile_open(&of, NULL)) hd_die();
    if (hd_gensky(hd_ofile_fp(of), &o, cmd) || hd_ofile_commit(of)) hd_die();
    free(cmd);
    free(sub);
    hd_header_free(&h);
    hd_optparse_free(&p);
    return 0;
}

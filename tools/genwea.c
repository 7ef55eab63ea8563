/* genwea — deterministic synthetic weather year as a WEA file (heliodon
 * extension; not a Radiance program).  See docs/man/genwea.1. */
#include <stdio.h>
#include <string.h>

#include "heliodon/io.h"
#include "heliodon/options.h"
#include "heliodon/weather.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    hd_synth_opts o;
    hd_synth_opts_default(&o);
    double lat = 1000, lon = 1000, mer = 1000;
    uint64_t seed = 1;
    const char *name = NULL;
    const hd_opt table[] = {
        {"a", HD_OPT_REAL, &lat, 0, 0, "lat", "site latitude (degrees north, required)"},
        {"o", HD_OPT_REAL, &lon, 0, 0, "lon", "site longitude (degrees WEST, Radiance convention, required)"},
        {"m", HD_OPT_REAL, &mer, 0, 0, "mer", "standard meridian (degrees WEST: UTC+2 is -30; required)"},
        {"e", HD_OPT_REAL, &o.site.elev, 0, 0, "m", "site elevation (0)"},
        {"s", HD_OPT_COUNT, &seed, 0, 0, "seed", "random seed (1)"},
        {"t", HD_OPT_REAL, &o.tl_mean, 0, 0, "TL", "mean Linke turbidity (3.5)"},
        {"ta", HD_OPT_REAL, &o.tl_amp, 0, 0, "amp", "seasonal turbidity amplitude (0.5, highest in July)"},
        {"c", HD_OPT_REAL, &o.cloud_mean, 0, 0, "prob", "mean probability of a cloudy day 0..1 (0.4)"},
        {"ca", HD_OPT_REAL, &o.cloud_amp, 0, 0, "amp", "its seasonal amplitude (0.3, cloudiest in January)"},
        {"n", HD_OPT_STRING, &name, 0, 0, "name", "name added to the place line"},
        HD_OPT_END};
    const char *syn = "-a lat -o lon -m meridian [-e elev][-s seed][-t TL][-ta amp][-c prob][-ca amp][-n name] [out.wea]";
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, syn);
    if (lat == 1000 || lon == 1000 || mer == 1000) {
        fprintf(stderr, "%s: -a, -o and -m are required\n", hd_progname());
        hd_opt_usage(table, syn);
        return 1;
    }
    if (lat < -90 || lat > 90) hd_die_msg("-a %g: latitude out of range -90..90", lat);
    if (lon < -180 || lon > 180) hd_die_msg("-o %g: longitude out of range -180..180 (degrees WEST)", lon);
    if (mer < -180 || mer > 180) hd_die_msg("-m %g: meridian out of range -180..180 (degrees WEST)", mer);
    if (o.cloud_mean < 0 || o.cloud_mean > 1) hd_die_msg("-c %g: probability out of range 0..1", o.cloud_mean);
    if (p.argc - p.first > 1) hd_die_msg("too many arguments");
    o.site.lat = lat;
    o.site.lon = lon;
    o.site.meridian = mer;
    o.seed = seed;
    o.name = name;
    hd_weather w;
    if (hd_weather_synth(&w, &o)) hd_die();
    hd_ofile *of;
    if (hd_ofile_open(&of, p.first < p.argc ? p.argv[p.first] : NULL)) hd_die();
    if (hd_weather_write_wea(hd_ofile_fp(of), &w) || hd_ofile_commit(of)) hd_die();
    hd_weather_free(&w);
    hd_optparse_free(&p);
    return 0;
}

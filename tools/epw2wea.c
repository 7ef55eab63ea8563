/* epw2wea — convert an EnergyPlus weather file to Radiance's WEA format
 * (direct normal and diffuse horizontal irradiance, W/m2). */
#include <stdio.h>
#include <string.h>

#include "heliodon/io.h"
#include "heliodon/options.h"
#include "heliodon/weather.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    const hd_opt table[] = {HD_OPT_END};
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, "input.epw [output.wea]");
    int nargs = p.argc - p.first;
    if (nargs < 1 || nargs > 2) {
        hd_opt_usage(table, "input.epw [output.wea]");
        return 1;
    }
    hd_weather w;
    if (hd_weather_read(p.argv[p.first], &w)) hd_die();
    if (!w.is_epw) hd_die_msg("%s: not an EPW file (it is already in WEA format)", p.argv[p.first]);
    hd_ofile *of;
    if (hd_ofile_open(&of, nargs == 2 ? p.argv[p.first + 1] : NULL)) hd_die();
    if (hd_weather_write_wea(hd_ofile_fp(of), &w) || hd_ofile_commit(of)) hd_die();
    hd_weather_free(&w);
    hd_optparse_free(&p);
    return 0;
}

/* gensuns — sun sources at the centres of the Reinhart MF:n patches that
 * the sun visits in the daylight hours of a weather file (PM-CBDM DC_sun). */
#include <stdio.h>
#include <string.h>

#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/options.h"
#include "heliodon/suns.h"
#include "heliodon/weather.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int mf = 1, keep_all = 0, verbose = 0;
    const char *modfile = NULL, *outfile = NULL;
    const hd_opt table[] = {
        {"m", HD_OPT_INT, &mf, 0, 0, "MF", "Reinhart subdivision (1 = Tregenza patches; paper: 6)"},
        {"a", HD_OPT_TOGGLE, &keep_all, 0, 0, NULL, "keep all sky patches, not only those the sun visits"},
        {"M", HD_OPT_STRING, &modfile, 0, 0, "file", "write the modifier list (one per line) to file"},
        {"o", HD_OPT_STRING, &outfile, 0, 0, "file", "write the sun sources to file (default stdout)"},
        {"v", HD_OPT_TOGGLE, &verbose, 0, 0, NULL, "report the number of patches and daylight hours"},
        HD_OPT_END};
    const char *syn = "[-m MF][-a][-M mods.txt][-o suns.rad] weather.wea|weather.epw";
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, syn);
    if (p.argc - p.first != 1) {
        hd_opt_usage(table, syn);
        return 1;
    }
    hd_weather w;
    if (hd_weather_read(p.argv[p.first], &w)) hd_die();
    hd_sunlist s;
    if (hd_suns_select(&w, mf, keep_all, &s)) hd_die();
    char cmd[1024];
    size_t k = 0;
    cmd[0] = 0;
    for (int i = 0; i < argc && k + 2 < sizeof cmd; i++) {
        size_t l = strlen(argv[i]);
        if (k + l + 2 >= sizeof cmd) break;
        if (i) cmd[k++] = ' ';
        memcpy(cmd + k, argv[i], l);
        k += l;
        cmd[k] = 0;
    }
    hd_ofile *orad, *omod = NULL;
    if (hd_ofile_open(&orad, outfile)) hd_die();
    if (modfile && hd_ofile_open(&omod, modfile)) hd_die();
    if (hd_suns_write(&s, hd_ofile_fp(orad), omod ? hd_ofile_fp(omod) : NULL, cmd)) hd_die();
    if (hd_ofile_commit(orad) || (omod && hd_ofile_commit(omod))) hd_die();
    if (verbose)
        fprintf(stderr, "%s: MF:%d, %d sun patches of %d, %ld daylight records\n", hd_progname(), s.mf, s.n,
                s.nbins - 1, s.ndaylight);
    hd_sunlist_free(&s);
    hd_weather_free(&w);
    hd_optparse_free(&p);
    return 0;
}

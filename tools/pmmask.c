/* pmmask — keep only the rays of the pixels inside a fenestration mask
 * (vwrays -ff stream in, one or -n N rays per pixel, same stream out with
 * the other directions zeroed),
 * for the refined backward DC of PM-CBDM's I_sky,fen. */
#include <stdio.h>

#include "heliodon/annual.h"
#include "heliodon/io.h"
#include "heliodon/options.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int verbose = 0, repeat = 1, per_pixel = 1;
    const hd_opt table[] = {
        {"c", HD_OPT_INT, &repeat, 0, 0, "N", "write every ray N times (for rcontrib -c N: mean of N estimates)"},
        {"n", HD_OPT_INT, &per_pixel, 0, 0, "N", "the stream holds N rays per pixel (vwrays -c N -pj J), kept or zeroed together"},
        {"t", HD_OPT_TOGGLE, &verbose, 0, 0, NULL, "report the number of rays kept"},
        HD_OPT_END};
    const char *syn = "mask.hdr [rays.ff] > masked.ff";
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, syn);
    int n = p.argc - p.first;
    if (n < 1 || n > 2) {
        hd_opt_usage(table, syn);
        return 1;
    }
    const char *inname = n == 2 ? p.argv[p.first + 1] : "-";
    hd_istream *in;
    if (hd_istream_open(&in, inname)) hd_die();
    long kept = 0;
    if (hd_annual_mask_rays(p.argv[p.first], in, inname, stdout, per_pixel, repeat, &kept)) hd_die();
    hd_istream_close(in);
    if (fflush(stdout)) hd_die_msg("write error on standard output");
    if (verbose) fprintf(stderr, "%s: %ld rays inside the mask\n", hd_progname(), kept);
    hd_optparse_free(&p);
    return 0;
}

/* checkBSDF — report on BSDF XML files (Radiance-compatible report).
 * See docs/man/checkBSDF.1. */
#include <stdio.h>

#include "heliodon/bsdf.h"
#include "heliodon/options.h"

int main(int argc, char **argv)
{
    const hd_opt table[] = {HD_OPT_END};
    hd_optparse p;
    hd_set_progname(argv[0]);
    hd_opt_parse_or_exit(&p, argc, argv, table, "bsdf.xml ..");
    if (p.first >= p.argc) {
        hd_fail(HD_ERR_USAGE, "no BSDF file given");
        hd_report_error();
        hd_opt_usage(table, "bsdf.xml ..");
        return 1;
    }
    int bad = 0;
    for (int i = p.first; i < p.argc; i++) {
        hd_bsdf *b;
        if (hd_bsdf_load(p.argv[i], &b) != HD_OK) { hd_report_error(); bad = 1; continue; }
        if (hd_bsdf_check_report(stdout, p.argv[i], b) != HD_OK) { hd_report_error(); bad = 1; }
        /* energy conservation within the data tolerance: warnings on stderr */
        hd_bsdf_check_energy(b, p.argv[i], 0.05, 4, NULL);
        hd_bsdf_free(b);
    }
    hd_optparse_free(&p);
    if (fflush(stdout)) { hd_fail(HD_ERR_IO, "write error on standard output"); hd_die(); }
    return bad;
}

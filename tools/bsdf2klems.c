/* bsdf2klems — convert a BSDF XML (tensor tree or Klems) to a Klems-basis
 * XML on standard output.  See docs/man/bsdf2klems.1. */
#include <stdio.h>
#include <string.h>

#include "heliodon/bsdf.h"
#include "heliodon/header.h"
#include "heliodon/options.h"

int main(int argc, char **argv)
{
    int nsamp = 4096, half = 0, quarter = 0, progress = 0;
    const hd_opt table[] = {
        {"n", HD_OPT_INT, &nsamp, 0, 0, "nsamp", "samples per patch pair where the data is not integrated exactly (default 4096)"},
        {"h", HD_OPT_TOGGLE, &half, 0, 0, NULL, "LBNL/Klems Half basis"},
        {"q", HD_OPT_TOGGLE, &quarter, 0, 0, NULL, "LBNL/Klems Quarter basis"},
        {"p", HD_OPT_TOGGLE, &progress, 0, 0, NULL, "accepted for compatibility (no effect)"},
        HD_OPT_END};
    hd_optparse p;
    hd_set_progname(argv[0]);
    hd_opt_parse_or_exit(&p, argc, argv, table, "[-n nsamp][-h|-q] bsdf.xml");
    if (p.argc - p.first != 1) {
        hd_fail(HD_ERR_USAGE, "expected exactly one input BSDF XML file");
        hd_report_error();
        hd_opt_usage(table, "[-n nsamp][-h|-q] bsdf.xml");
        return 1;
    }
    if (nsamp < 1 || nsamp > 1000000) hd_die_msg("-n %d: expected 1 to 1000000 samples", nsamp);
    hd_klems_basis kb;
    hd_klems_standard(&kb, quarter ? HD_KLEMS_QUARTER : half ? HD_KLEMS_HALF : HD_KLEMS_FULL);
    hd_bsdf *b;
    if (hd_bsdf_load(p.argv[p.first], &b) != HD_OK) hd_die();
    hd_header h;
    hd_header_init(&h);
    if (hd_header_add_command(&h, argc, argv) != HD_OK) hd_die();
    char comment[1024];
    size_t n = h.len < sizeof comment ? h.len : sizeof comment - 1;
    memcpy(comment, h.text, n);
    while (n && (comment[n - 1] == '\n' || comment[n - 1] == ' ')) n--;
    comment[n] = 0;
    hd_ofile *of;
    if (hd_ofile_open(&of, "-") != HD_OK) hd_die();
    if (hd_bsdf_write_klems_xml(hd_ofile_fp(of), b, &kb, nsamp, comment) != HD_OK) hd_die();
    if (hd_ofile_commit(of) != HD_OK) hd_die();
    hd_header_free(&h);
    hd_bsdf_free(b);
    hd_optparse_free(&p);
    return 0;
}

/* genskyvec — sky vector (patch radiances) from a gensky/gendaylit sky
 * description read on standard input (Radiance compatible). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/options.h"
#include "heliodon/sky.h"

#define MAXDESC (16u << 20)

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int mf = 4, sun_only = 0, noheader = 0, five = 0, nsamp = 0;
    hd_skyvec_opts o;
    memset(&o, 0, sizeof o);
    o.skycolor[0] = 0.960; o.skycolor[1] = 1.004; o.skycolor[2] = 1.118;
    const hd_opt table[] = {
        {"m", HD_OPT_INT, &mf, 0, 0, "N", "Reinhart subdivision MF:N (default 4)"},
        {"c", HD_OPT_REAL3, o.skycolor, 0, 0, "r g b", "sky colour (default 0.960 1.004 1.118)"},
        {"d", HD_OPT_TOGGLE, &sun_only, 0, 0, 0, "direct sun only"},
        {"h", HD_OPT_TOGGLE, &noheader, 0, 0, 0, "no header"},
        {"5", HD_OPT_TOGGLE, &five, 0, 0, 0, "put the sun radiance into the single nearest patch"},
        {"ns", HD_OPT_INT, &nsamp, 0, 0, "N",
         "N x N stratified samples per patch (default: Radiance's 16 fixed rays)"},
        HD_OPT_END};
    const char *syn = "[-m N][-c r g b][-d][-h][-5][-ns N] < sky.rad";
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, syn);
    if (p.argc - p.first > 1) hd_die_msg("too many arguments (the sky description is read from standard input)");
    if (mf < 1 || mf > HD_SKY_MAXMF) hd_die_msg("-m %d: subdivision must be 1..%d", mf, HD_SKY_MAXMF);
    if (nsamp < 0 || nsamp > 64) hd_die_msg("-ns %d: must be 1..64 (0: Radiance's 16 rays)", nsamp);
    o.sun_only = sun_only;
    o.five_phase = five;
    o.nsamp = nsamp;
    const char *in = p.first < p.argc ? p.argv[p.first] : "-";
    hd_istream *s;
    if (hd_istream_open(&s, in)) hd_die();
    char *text = hd_malloc(MAXDESC + 1);
    if (!text) hd_die();
    size_t len = hd_istream_read(s, text, MAXDESC + 1);
    if (len > MAXDESC) hd_die_msg("%s: sky description larger than %u bytes", hd_istream_name(s), MAXDESC);
    text[len] = 0;
    if (hd_istream_close(s)) hd_die();
    hd_skydesc d;
    if (hd_skydesc_parse(text, strcmp(in, "-") ? in : "<stdin>", &d)) hd_die();
    free(text);
    hd_skybasis b;
    if (hd_skybasis_init(&b, mf)) hd_die();
    double *v = hd_malloc_array((size_t)b.nbins * 3, sizeof(double));
    if (!v || hd_skyvec_compute(&b, &d, &o, v)) hd_die();
    hd_ofile *of;
    if (hd_ofile_open(&of, NULL)) hd_die();
    FILE *fp = hd_ofile_fp(of);
    if (!noheader) {
        hd_header h;
        hd_header_init(&h);
        hd_header_add_command(&h, argc, argv);
        hd_header_dims d = {b.nbins, 1, 3, HD_ENDIAN_NONE};
        if (hd_header_put(fp, &h, &d, "ascii", NULL)) hd_die();
        hd_header_free(&h);
    }
    for (int i = 0; i < b.nbins; i++) fprintf(fp, "%.9g\t%.9g\t%.9g\n", v[3 * i], v[3 * i + 1], v[3 * i + 2]);
    if (hd_ofile_commit(of)) hd_die();
    free(v);
    hd_skybasis_free(&b);
    hd_optparse_free(&p);
    return 0;
}

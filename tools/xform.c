/* xform — transform a Radiance scene description (heliodon). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/io.h"
#include "heliodon/xform.h"

static void usage(void)
{
    fprintf(stderr, "usage: %s [-c|-e][-I][-n name][-m newmod] [xf0] [-a n xf1 ..] [-i n xf ..] [file ..]\n",
            hd_progname());
    exit(1);
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    hd_xform_opts o = {NULL, NULL, 0};
    int expand = 1, i = 1;
    for (; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "-c")) expand = 0;
        else if (!strcmp(a, "-e")) expand = 1;
        else if (!strcmp(a, "-I")) o.invert = 1;
        else if (!strcmp(a, "-n") && i + 1 < argc) o.prefix = argv[++i];
        else if (!strcmp(a, "-m") && i + 1 < argc) o.newmod = argv[++i];
        else if (!strcmp(a, "-n") || !strcmp(a, "-m")) hd_die_msg("%s: missing argument", a);
        else if (!strcmp(a, "-f")) hd_die_msg("-f argfile is not supported by heliodon xform");
        else break;
    }
    hd_xf_spec spec;
    if (hd_xf_parse(&spec, argc - i, argv + i)) { hd_report_error(); usage(); }
    char **xfargv = argv + i;
    i += spec.nwords;
    for (int j = i; j < argc; j++)
        if (argv[j][0] == '-' && argv[j][1]) {
            fprintf(stderr, "%s: unexpected option '%s' after the transform or a file name\n", hd_progname(), argv[j]);
            usage();
        }
    if (hd_xform_files(stdout, argc - i, argv + i, &spec, xfargv, &o, expand, argc, argv)) {
        hd_xf_spec_free(&spec);
        hd_die();
    }
    hd_xf_spec_free(&spec);
    if (fflush(stdout)) hd_die_msg("write error on standard output");
    return 0;
}

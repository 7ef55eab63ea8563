/* gensurf — generate a parametric surface as Radiance polygons (heliodon).
 *   gensurf mat name 'x(s,t)' 'y(s,t)' 'z(s,t)' m n [-e expr] [-f file] [-s] [-i] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/cal.h"
#include "heliodon/common.h"
#include "heliodon/xform.h"

static int grid(hd_cal *c, const char *text)
{
    double v;
    if (hd_cal_eval(c, text, &v)) hd_die();
    if (!(v + .5 >= 1) || v > 1e7) hd_die_msg("bad number of divisions '%s'", text);
    return (int)(v + .5);
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    if (argc < 8)
        hd_die_msg("usage: %s material name x(s,t) y(s,t) z(s,t) m n [-s][-i][-e expr][-f file]", hd_progname());
    hd_cal *c = hd_cal_new();
    if (!c || hd_gen_define_curves(c)) hd_die();
    hd_gensurf_opts o = {argv[1], argv[2], argv[3], argv[4], argv[5], 0, 0, 0, 0};
    for (int i = 8; i < argc; i++) {
        if (!strcmp(argv[i], "-e") && i + 1 < argc) {
            if (hd_cal_parse(c, argv[++i], "-e")) hd_die();
        } else if (!strcmp(argv[i], "-f") && i + 1 < argc) {
            if (hd_cal_load(c, argv[++i])) hd_die();
        } else if (!strcmp(argv[i], "-s")) {
            o.smooth = 1;
        } else if (!strcmp(argv[i], "-i")) {
            o.rev = 1;
        } else if (!strcmp(argv[i], "-o")) {
            hd_die_msg("-o (Wavefront .OBJ output) is not supported");
        } else {
            hd_die_msg("unknown or incomplete option '%s'", argv[i]);
        }
    }
    if (!strcmp(argv[5], "-"))
        hd_die_msg("z values from a data file are not supported (give z(s,t) as an expression)");
    FILE *probe = fopen(argv[5], "r");
    if (probe) {
        fclose(probe);
        hd_die_msg("'%s' is a file: z values from a data file are not supported", argv[5]);
    }
    o.m = grid(c, argv[6]);
    o.n = grid(c, argv[7]);
    hd_gen_print_command(stdout, hd_progname(), argc, argv);
    if (hd_gensurf_write(stdout, c, &o)) hd_die();
    hd_cal_free(c);
    if (fflush(stdout)) hd_die_msg("write error on standard output");
    return 0;
}

/* genrev — a surface of revolution about z as Radiance cones, cylinders
 * and rings (Radiance's genrev; docs/man/genrev.1):
 *   genrev mat name 'z(t)' 'r(t)' nseg [-e expr] [-f file] [-s]
 * The work is hd_genrev_write (src/scene_gensurf.c). */
#include <stdio.h>
#include <string.h>
#include "heliodon/cal.h"
#include "heliodon/common.h"
#include "heliodon/xform.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    const char *usage = "usage: %s material name z(t) r(t) nseg [-e expr] [-f file] [-s]";
    if (argc < 6) hd_die_msg(usage, hd_progname());
    hd_cal *c = hd_cal_new();
    if (!c || hd_gen_define_curves(c)) hd_die();
    int smooth = 0;
    for (int i = 6; i < argc; i++) {
        if (!strcmp(argv[i], "-e") && i + 1 < argc) {
            if (hd_cal_parse(c, argv[++i], "-e")) hd_die();
        } else if (!strcmp(argv[i], "-f") && i + 1 < argc) {
            if (hd_cal_load(c, argv[++i])) hd_die();
        } else if (!strcmp(argv[i], "-s")) {
            smooth = 1;
        } else {
            hd_die_msg(usage, hd_progname());
        }
    }
    double v;
    if (hd_cal_eval(c, argv[5], &v)) hd_die();
    if (!(v + .5 >= 1) || v > 1e7) hd_die_msg(usage, hd_progname());
    hd_gen_print_command(stdout, hd_progname(), argc, argv);
    if (hd_genrev_write(stdout, c, argv[1], argv[2], argv[3], argv[4], (int)(v + .5), smooth)) hd_die();
    hd_cal_free(c);
    if (fflush(stdout)) hd_die_msg("write error on standard output");
    return 0;
}

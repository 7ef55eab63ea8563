/* genbox — generate a box as Radiance polygons (heliodon). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/io.h"
#include "heliodon/xform.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    if (argc < 6)
        hd_die_msg("usage: %s material name xsize ysize zsize [-i] [-r radius | -b bevel]", hd_progname());
    double s[3], round = 0, bevel = 0;
    int invert = 0;
    for (int k = 0; k < 3; k++)
        if (hd_parse_double(argv[3 + k], &s[k]))
            hd_die_msg("size '%s' is not a number", argv[3 + k]);
    for (int i = 6; i < argc; i++) {
        if (!strcmp(argv[i], "-i")) invert = 1;
        else if ((!strcmp(argv[i], "-r") || !strcmp(argv[i], "-b")) && i + 1 < argc) {
            double v;
            if (hd_parse_double(argv[i + 1], &v) || v <= 0)
                hd_die_msg("%s: expected a positive number, got '%s'", argv[i], argv[i + 1]);
            if (argv[i][1] == 'r') round = v; else bevel = v;
            i++;
        } else if (!strcmp(argv[i], "-n") && i + 1 < argc) {
            i++;   /* number of segments for rounded boxes: not needed (exact cylinders/spheres) */
        } else {
            hd_die_msg("unknown or incomplete option '%s'", argv[i]);
        }
    }
    if (hd_genbox_write(stdout, argv[1], argv[2], s[0], s[1], s[2], invert, round, bevel, argc, argv))
        hd_die();
    if (fflush(stdout)) hd_die_msg("write error on standard output");
    return 0;
}

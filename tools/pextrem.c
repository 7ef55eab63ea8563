/* pextrem — the darkest and brightest pixel of a Radiance picture, as
 * Radiance's pextrem (docs/man/pextrem.1); the search is hd_pextrem
 * (src/pictools.c), shared with falsecolor -e. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/pictools.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int orig = 0, i;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "-o")) orig = 1;
        else if (!strcmp(argv[i], "-O")) orig = -1;
        else break;
    }
    if (i < argc - 1) hd_die_msg("usage: pextrem [-o|-O] [picture]");
    hd_istream *s;
    if (hd_istream_open(&s, i < argc ? argv[i] : "-")) hd_die();
    hd_extrema e;
    if (hd_pextrem(s, orig, &e)) hd_die();
    printf("%d %d\t%.2e %.2e %.2e\n", e.xmin, e.ymin, e.min[0], e.min[1], e.min[2]);
    printf("%d %d\t%.2e %.2e %.2e\n", e.xmax, e.ymax, e.max[0], e.max[1], e.max[2]);
    if (fflush(stdout)) hd_die_msg("write error on standard output");
    hd_istream_close(s);
    return 0;
}

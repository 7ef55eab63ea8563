/* pflip — flip a Radiance picture left-right (-h) and/or top-bottom (-v),
 * as Radiance's pflip (docs/man/pflip.1). */
#include <stdio.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/pictools.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int h = 0, v = 0, c = 0, i;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "-h")) h = 1;
        else if (!strcmp(argv[i], "-v")) v = 1;
        else if (!strcmp(argv[i], "-c")) c = 1;
        else break;
    }
    if (i < argc - 2 || (i < argc && argv[i][0] == '-' && argv[i][1]))
        hd_die_msg("usage: pflip [-h][-v][-c] infile [outfile]");
    if (!h && !v) hd_warn("no operation");
    hd_rawpic p;
    if (hd_rawpic_read(i < argc ? argv[i] : "-", &p)) hd_die();
    if (hd_rawpic_flip(&p, h, v, c) || hd_header_add_command(&p.hdr, i, argv)) hd_die();
    if (hd_rawpic_save(i + 1 < argc ? argv[i + 1] : NULL, &p)) hd_die();
    hd_rawpic_free(&p);
    return 0;
}

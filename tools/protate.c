/* protate — turn a Radiance picture 90 degrees clockwise (-r: counter-
 * clockwise), as Radiance's protate (docs/man/protate.1). */
#include <stdio.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/pictools.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int ccw = 0, c = 0, i;
    for (i = 1; i < argc - 1 && argv[i][0] == '-'; i++) {
        if (!strcmp(argv[i], "-r")) ccw = 1;
        else if (!strcmp(argv[i], "-c")) c = 1;
        else hd_die_msg("usage: protate [-r][-c] infile [outfile]");
    }
    if (i >= argc || i < argc - 2) hd_die_msg("usage: protate [-r][-c] infile [outfile]");
    hd_rawpic p;
    if (hd_rawpic_read(argv[i], &p)) hd_die();
    char *words[3] = {argv[0], ccw ? "-r" : NULL, NULL};
    int nw = 1;
    if (ccw) words[nw++] = "-r";
    if (c) words[nw++] = "-c";
    if (hd_rawpic_rotate(&p, ccw, c) || hd_header_add_command(&p.hdr, nw, words)) hd_die();
    if (hd_rawpic_save(i + 1 < argc ? argv[i + 1] : NULL, &p)) hd_die();
    hd_rawpic_free(&p);
    return 0;
}

/* rcmerge — join the pieces of an rcontrib output (rcontrib -R) into the
 * output of one full run, byte for byte (heliodon). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/common.h"
#include "heliodon/options.h"
#include "heliodon/rcmerge.h"

static const char synopsis[] = "rcmerge output piece ...  |  rcmerge -d outdir piecedir ...";

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int dirs = 0, first = 0;
    const hd_opt table[] = {
        {"d", HD_OPT_TOGGLE, &dirs, 0, 0, 0, "join every file of the piece folders into outdir"},
        HD_OPT_END};
    if (hd_opt_parse_args(argc, argv, table, &first) != HD_OK) hd_die();
    if (argc - first < 2) hd_die_msg("usage: %s", synopsis);
    const char *const *rest = (const char *const *)argv + first + 1;
    hd_status st = dirs ? hd_rcmerge_dirs(argv[first], rest, argc - first - 1)
                        : hd_rcmerge(argv[first], rest, argc - first - 1);
    if (st != HD_OK) hd_die();
    return 0;
}

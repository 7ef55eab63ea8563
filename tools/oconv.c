/* oconv — compile Radiance scene files into a heliodon scene cache. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/io.h"
#include "heliodon/options.h"
#include "heliodon/scene.h"

static int bound_opt(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)opt;
    double *b = ctx;
    for (int k = 0; k < 4; k++)
        if (i + 1 + k >= argc || hd_parse_double(argv[i + 1 + k], &b[k])) {
            hd_fail(HD_ERR_USAGE, "-b: expected 4 numbers (xmin ymin zmin size)");
            return -1;
        }
    return 4;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int frozen = 0, nowarn = 0, skip = 0, print = 0;
    long res = 0, objlim = 0;
    const char *incr = NULL;
    double bound[4];
    hd_opt table[] = {
        {"f", HD_OPT_TOGGLE, &frozen, 0, 0, NULL, "frozen output (always: the cache holds the whole scene)"},
        {"w", HD_OPT_TOGGLE, &nowarn, 0, 0, NULL, "suppress warnings"},
        {"i", HD_OPT_STRING, &incr, 0, 0, "scene", "start from an existing heliodon scene cache"},
        {"r", HD_OPT_LONG, &res, 0, 0, "N", "octree resolution (accepted, not used)"},
        {"n", HD_OPT_LONG, &objlim, 0, 0, "N", "objects per octree leaf (accepted, not used)"},
        {"b", HD_OPT_FUNC, bound, bound_opt, 0, "x y z size", "bounding cube (accepted, not used)"},
        {"k", HD_OPT_TOGGLE, &skip, 0, 0, NULL,
         "skip in-line commands whose program is not on PATH (listed as warnings)"},
        {"p", HD_OPT_TOGGLE, &print, 0, 0, NULL, "print the parsed scene as Radiance text instead"},
        HD_OPT_END};
    hd_optparse op;
    hd_opt_parse_or_exit(&op, argc, argv, table, "[-f][-w][-k][-p][-i scene.oct] file ..");
    if (nowarn) hd_set_warnings(0);
    if (op.first >= op.argc) hd_die_msg("no scene files given (use - for standard input)");
    hd_scene s;
    hd_scene_init(&s);
    if (incr && hd_scene_read_cache(&s, incr)) hd_die();
    hd_scene_opts so = {0, skip, 0, NULL};
    for (int i = op.first; i < op.argc; i++) {
        size_t skipped0 = s.nskipped;
        int cached = op.argv[i][0] != '!' && strcmp(op.argv[i], "-") && hd_scene_is_cache(op.argv[i]) == 1;
        if (hd_scene_load_files(&s, 1, op.argv + i, &so)) hd_die();
        for (size_t k = skipped0; k < s.nskipped && !cached; k++) {
            char w[1200];
            const hd_skipped_cmd *c = &s.skipped[k];
            hd_warn("skipped in-line command (program not found) at %s: !%s",
                    hd_scene_where(&s, c->file, c->line, w, sizeof w), c->command);
        }
    }
    if (print) {
        if (hd_scene_write_rad(stdout, &s) || fflush(stdout)) hd_die();
    } else if (hd_scene_write_cache(&s, NULL, argc, argv)) {
        hd_die();
    }
    hd_scene_free(&s);
    hd_optparse_free(&op);
    return 0;
}

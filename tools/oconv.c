/* oconv — compile Radiance scene files into a Radiance octree (readable by
 * Radiance's programs), with heliodon's parsed scene embedded after it. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/io.h"
#include "heliodon/octree.h"
#include "heliodon/options.h"
#include "heliodon/scene.h"

static int bound_opt(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)opt;
    hd_octree_opts *o = ctx;
    for (int k = 0; k < 4; k++)
        if (i + 1 + k >= argc || hd_parse_double(argv[i + 1 + k], &o->bound[k])) {
            hd_fail(HD_ERR_USAGE, "-b: expected 4 numbers (xmin ymin zmin size)");
            return -1;
        }
    o->have_bound = 1;
    return 4;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int frozen = 0, nowarn = 0, skip = 0, print = 0;
    const char *incr = NULL;
    hd_octree_opts oo;
    hd_octree_opts_default(&oo);
    hd_opt table[] = {
        {"f", HD_OPT_TOGGLE, &frozen, 0, 0, NULL, "frozen octree: the scene data inside instead of file names"},
        {"w", HD_OPT_TOGGLE, &nowarn, 0, 0, NULL, "suppress warnings"},
        {"i", HD_OPT_STRING, &incr, 0, 0, "octree", "add to an existing octree"},
        {"r", HD_OPT_LONG, &oo.resolu, 0, 0, "N", "octree resolution limit (default 16384)"},
        {"n", HD_OPT_LONG, &oo.objlim, 0, 0, "N", "objects per octree leaf before a split (default 6)"},
        {"b", HD_OPT_FUNC, &oo, bound_opt, 0, "x y z size", "bounding cube"},
        {"k", HD_OPT_TOGGLE, &skip, 0, 0, NULL,
         "skip in-line commands whose program is not on PATH (listed as warnings)"},
        {"p", HD_OPT_TOGGLE, &print, 0, 0, NULL, "print the parsed scene as Radiance text instead"},
        HD_OPT_END};
    hd_optparse op;
    hd_opt_parse_or_exit(&op, argc, argv, table, "[-f][-w][-k][-p][-r N][-n N][-b x y z s|-i octree] file ..");
    if (nowarn) hd_set_warnings(0);
    if (op.first >= op.argc && !incr) hd_die_msg("no scene files given (use - for standard input)");
    if (incr && oo.have_bound) hd_die_msg("only one of '-b' or '-i'");
    hd_scene s;
    hd_scene_init(&s);
    hd_scene_opts so = {0, skip, 0, NULL};
    /* scene file names for an unfrozen octree: those of the -i octree, then ours */
    char **files = NULL;
    int nfiles = 0;
    if (incr) {
        double org[3], size;
        if (hd_octree_read_head(incr, org, &size, &files, &nfiles)) hd_die();
        if (!nfiles && !frozen) {
            hd_warn("frozen octree");
            frozen = 1;
        }
        char *one[1] = {(char *)incr};
        if (hd_scene_load_files(&s, 1, one, &so)) hd_die();
    }
    char **all = hd_malloc_array((size_t)(nfiles + op.argc - op.first + 1), sizeof *all);
    if (!all) hd_die();
    for (int k = 0; k < nfiles; k++) all[k] = files[k];
    int nall = nfiles;
    for (int i = op.first; i < op.argc; i++) {
        size_t skipped0 = s.nskipped;
        int cached = op.argv[i][0] != '!' && strcmp(op.argv[i], "-") && hd_scene_is_cache(op.argv[i]) == 1;
        if (hd_scene_load_files(&s, 1, op.argv + i, &so)) hd_die();
        if (!strcmp(op.argv[i], "-")) frozen = 1;     /* standard input: nothing to list */
        all[nall++] = op.argv[i];
        for (size_t k = skipped0; k < s.nskipped && !cached; k++) {
            char w[1200];
            const hd_skipped_cmd *c = &s.skipped[k];
            hd_warn("skipped in-line command (program not found) at %s: !%s",
                    hd_scene_where(&s, c->file, c->line, w, sizeof w), c->command);
        }
    }
    oo.frozen = frozen;
    if (print) {
        if (hd_scene_write_rad(stdout, &s) || fflush(stdout)) hd_die();
    } else if (hd_octree_write(&s, NULL, argc, argv, all, nall, &oo)) {
        hd_die();
    }
    for (int k = 0; k < nfiles; k++) free(files[k]);
    free(files);
    free(all);
    hd_scene_free(&s);
    hd_optparse_free(&op);
    return 0;
}

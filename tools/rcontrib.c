/* rcontrib — contributions of tracked modifiers to rays (heliodon; backward
 * mode, or photon-map mode with -ap). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/common.h"
#include "heliodon/contrib.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/options.h"
#include "heliodon/rcmerge.h"
#include "heliodon/render.h"
#include "heliodon/scene.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int nargc;
    char **nargv;
    void *storage;
    if (hd_expand_args(argc, argv, &nargc, &nargv, &storage) != HD_OK) hd_die();
    hd_contrib c = {0};
    hd_rcontrib_opts o;
    hd_rcontrib_defaults(&o, &c.o);
    int first;
    if (hd_rcontrib_parse_args(nargc, nargv, &c, &o, &first) != HD_OK) hd_die();
    if (first >= nargc) hd_die_msg("usage: rcontrib [options] -m mod|-M file ... scene.rad|scene.oct ... < rays");
    hd_scene sc;
    hd_scene_init(&sc);
    hd_tscene *ts = NULL;
    hd_header hdr;
    hd_header_init(&hdr);
    /* the headers record the command without -r: a resumed run's files are
     * those of an uninterrupted run */
    char **hargv = hd_calloc((size_t)argc + 1, sizeof *hargv);
    if (!hargv) hd_die();
    int hargc = 0;
    for (int i = 0; i < argc; i++) {
        if (o.recover && (!strcmp(argv[i], "-r") || !strcmp(argv[i], "-r+"))) continue;
        /* nor -R: every piece of a run carries the full run's header */
        if ((!strcmp(argv[i], "-R") || !strcmp(argv[i], "-apR")) && i + 2 < argc) { i += 2; continue; }
        hargv[hargc++] = argv[i];
    }
    if (hd_render_load_scene(nargc - first, nargv + first, &sc, &ts, &hdr, hargc, hargv) != HD_OK) hd_die();
    free(hargv);
    hd_header_add_date(&hdr);
    c.ts = ts;
    if (hd_contrib_prepare(&c) != HD_OK) hd_die();
    hd_istream *in;
    if (hd_istream_open(&in, "-") != HD_OK) hd_die();
    hd_raysrc src = {in, NULL, NULL, 0};
    if (hd_rcontrib_run(&c, &o, &src, &hdr) != HD_OK) hd_die();
    hd_istream_close(in);
    hd_header_free(&hdr);
    hd_contrib_free(&c);
    hd_tscene_free(ts);
    hd_scene_free(&sc);
    hd_expand_args_free(storage);
    return 0;
}

/* heliodon — rfluxmtx program logic (tools/rfluxmtx.c is a thin wrapper). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/options.h"
#include "heliodon/rfluxmtx.h"
#include "heliodon/scene.h"

static void print_equivalent(const hd_contrib *c, const hd_rcontrib_opts *o, int nsys, char **sys, const char *recv)
{
    fprintf(stderr, "%s: equivalent: rcontrib -fo+ -ab %d -ad %d -lw %g -f%c%c -c %d", hd_progname(), c->o.ab, c->o.ad,
            c->o.lw, o->fin, o->fout, o->accum);
    if (o->yres) fprintf(stderr, " -y %d", o->yres);
    for (int i = 0; i < c->nmods; i++) {
        const hd_binfn *b = &c->mods[i].bin;
        if (c->mods[i].outspec) fprintf(stderr, " -o %s", c->mods[i].outspec);
        switch (b->kind) {
        case HD_BIN_CONST: fprintf(stderr, " -bn 1 -b 0"); break;
        case HD_BIN_HEMI: fprintf(stderr, " -bn 1 -b 'if(-Dx*%g-Dy*%g-Dz*%g,0,-1)'", b->n.x, b->n.y, b->n.z); break;
        case HD_BIN_CAL: if (b->rcargs) fprintf(stderr, " %s", b->rcargs); break;
        default: break;
        }
        fprintf(stderr, " -m %s", c->mods[i].name);
    }
    for (int i = 0; i < nsys; i++) fprintf(stderr, " %s", sys[i]);
    fprintf(stderr, " %s\n", recv);
}

int hd_rfluxmtx_main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int nargc;
    char **nargv;
    void *storage;
    if (hd_expand_args(argc, argv, &nargc, &nargv, &storage) != HD_OK) hd_die();
    hd_contrib c = {0};
    hd_rcontrib_opts o;
    hd_rcontrib_defaults(&o, &c.o);
    o.rflux = 1;
    int first, nf = nargc;
    char **fa = nargv;
    if (hd_rcontrib_parse_args(nf, fa, &c, &o, &first) != HD_OK) hd_die();
    int verbose = o.verbose, cgiven = o.cgiven, xygiven = o.xygiven;
    double bj = o.bj;
    o.force = 1;
    if (nf - first < 2)
        hd_die_msg("usage: rfluxmtx [-v][-bj frac][rcontrib options] {sender.rad|-} receivers.rad [-i system.oct] [system.rad ...]");
    const char *sender = fa[first], *recv = fa[first + 1];
    int passthru = !strcmp(sender, "-");
    /* system files (an "-i octree" is just another scene input here) */
    char **sys = hd_malloc_array((size_t)nf + 1, sizeof *sys);
    if (!sys) hd_die();
    int nsys = 0;
    for (int k = first + 2; k < nf; k++) {
        if (!strcmp(fa[k], "-i")) {
            if (k + 1 >= nf) hd_die_msg("option -i: expected an octree or scene file");
            continue;
        }
        sys[nsys++] = fa[k];
    }
    if (!passthru) {
        if (o.irrad) hd_die_msg("-I/-i are only allowed in pass-through mode ('-' as sender)");
        if (xygiven) hd_die_msg("-x/-y are only allowed in pass-through mode ('-' as sender)");
        if (!cgiven) o.accum = 10000;
        if (o.accum <= 0) hd_die_msg("-c must be positive with a sender");
    }
    hd_rffile rf;
    if (hd_rffile_read(&rf, recv) != HD_OK) hd_die();
    if (hd_rf_receivers(&rf, bj, &c) != HD_OK) hd_die();
    /* the scene: system files then the receivers */
    sys[nsys] = (char *)recv;
    hd_scene sc;
    hd_scene_init(&sc);
    hd_tscene *ts = NULL;
    if (hd_render_load_scene(nsys + 1, sys, &sc, &ts, NULL, argc, argv) != HD_OK) hd_die();
    hd_header hdr;
    hd_header_init(&hdr);
    if (hd_header_add_command(&hdr, argc, argv) != HD_OK || hd_header_add_software(&hdr) != HD_OK ||
        hd_header_add_date(&hdr) != HD_OK)
        hd_die();
    c.ts = ts;
    if (hd_contrib_prepare(&c) != HD_OK) hd_die();
    hd_raysrc src = {NULL, NULL, NULL, 0};
    hd_rfsender *snd = NULL;
    hd_istream *in = NULL;
    hd_rffile sf;
    memset(&sf, 0, sizeof sf);
    if (passthru) {
        if (hd_istream_open(&in, "-") != HD_OK) hd_die();
        src.in = in;
    } else {
        if (hd_rffile_read(&sf, sender) != HD_OK) hd_die();
        if (hd_rf_sender_create(&snd, &sf, o.accum, c.o.seed) != HD_OK) hd_die();
        src.gen = hd_rf_sender_ray;
        src.genctx = snd;
        src.ngen = (uint64_t)hd_rf_sender_nbins(snd) * (uint64_t)o.accum;
        o.xres = 0;
        o.yres = hd_rf_sender_nbins(snd);
    }
    if (verbose) print_equivalent(&c, &o, nsys, sys, recv);
    if (hd_rcontrib_run(&c, &o, &src, &hdr) != HD_OK) hd_die();
    if (in) hd_istream_close(in);
    hd_rf_sender_free(snd);
    hd_rffile_free(&sf);
    hd_rffile_free(&rf);
    hd_header_free(&hdr);
    hd_contrib_free(&c);
    hd_tscene_free(ts);
    hd_scene_free(&sc);
    free(sys);
    hd_expand_args_free(storage);
    return 0;
}

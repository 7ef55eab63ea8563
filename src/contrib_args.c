/* heliodon — rcontrib command-line parsing (order-dependent -o -b -bn -p -f -e -m -M). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/contrib.h"
#include "heliodon/options.h"

void hd_rcontrib_defaults(hd_rcontrib_opts *o, hd_render_opts *r)
{
    memset(o, 0, sizeof *o);
    o->irrad = 0;
    o->fin = o->fout = 'a';
    o->accum = 1;
    o->header = 1;
    o->nthreads = 1;
    if (r) {
        hd_render_defaults(r);
        /* rcontrib's defaults */
        r->ab = 1;
        r->ad = 350;
        r->lw = 2e-3;
        r->lr = -10;
        r->dj = 0.9;
        r->ss = 1;
        r->st = 0.02;
    }
}

static int need(int argc, char **argv, int i, int n)
{
    if (i + n >= argc) {
        hd_fail(HD_ERR_USAGE, "option %s: expected %d argument%s", argv[i], n, n > 1 ? "s" : "");
        return 0;
    }
    return 1;
}

static int getint(const char *opt, const char *s, int *v)
{
    long l;
    if (hd_parse_long(s, &l) || l < -2000000000L || l > 2000000000L) {
        hd_fail(HD_ERR_USAGE, "option %s: expected an integer, got '%s'", opt, s);
        return 0;
    }
    *v = (int)l;
    return 1;
}

static int getreal(const char *opt, const char *s, double *v)
{
    if (hd_parse_double(s, v)) {
        hd_fail(HD_ERR_USAGE, "option %s: expected a number, got '%s'", opt, s);
        return 0;
    }
    return 1;
}

/* ignored rendering options (no ambient cache, no source subdivision) */
static const struct { const char *name; int nargs; } ignored[] = {
    {"-aa", 1}, {"-ar", 1}, {"-as", 1}, {"-dt", 1}, {"-dc", 1}, {"-ds", 1}, {"-dr", 1},
    {"-dp", 1}, {"-ps", 1}, {"-pj", 1}, {"-pt", 1}, {"-ms", 1}, {NULL, 0}
};
static const char *ignored_toggles[] = {"dv", "u", "bv", NULL};

typedef struct argstate {
    hd_calctx cal;
    const char *bexpr, *bn, *params, *outspec;
} argstate;

static hd_status add_mod(hd_contrib *c, argstate *a, const char *name)
{
    hd_cmod *nm = hd_realloc_array(c->mods, (size_t)c->nmods + 1, sizeof *nm);
    if (!nm) return HD_ERR_NOMEM;
    c->mods = nm;
    hd_cmod *m = &c->mods[c->nmods];
    memset(m, 0, sizeof *m);
    if (strlen(name) >= sizeof m->name) return hd_fail(HD_ERR_USAGE, "modifier name too long: %.40s...", name);
    hd_strlcpy(m->name, name, sizeof m->name);
    hd_status st = hd_binfn_parse(&m->bin, &a->cal, a->params, a->bexpr, a->bn);
    if (st != HD_OK) return hd_fail_context(st, "modifier %s", name);
    if (a->outspec) {
        if (hd_pattern_kind(a->outspec) < 0) { hd_binfn_free(&m->bin); return hd_fail_context(HD_ERR_USAGE, "-o %s", a->outspec); }
        m->outspec = hd_strdup(a->outspec);
        if (!m->outspec) { hd_binfn_free(&m->bin); return HD_ERR_NOMEM; }
    }
    c->nmods++;
    return HD_OK;
}

static hd_status add_modfile(hd_contrib *c, argstate *a, const char *path)
{
    hd_istream *in;
    hd_status st = hd_istream_open(&in, path);
    if (st != HD_OK) return hd_fail_context(st, "-M");
    char w[256];
    long n;
    int count = 0;
    while ((n = hd_istream_word(in, w, sizeof w)) > 0) {
        st = add_mod(c, a, w);
        if (st != HD_OK) { hd_istream_close(in); return st; }
        count++;
    }
    hd_istream_close(in);
    if (n == -2) return hd_fail(HD_ERR_FORMAT, "-M %s: modifier name too long", path);
    if (count == 0) return hd_fail(HD_ERR_FORMAT, "-M %s: no modifier names in the file", path);
    return HD_OK;
}

hd_status hd_rcontrib_parse_args(int argc, char **argv, hd_contrib *c, hd_rcontrib_opts *o, int *first)
{
    argstate a;
    memset(&a, 0, sizeof a);
    hd_calctx_init(&a.cal);
    int i;
    for (i = 1; i < argc; i++) {
        char *w = argv[i];
        if ((w[0] != '-' && w[0] != '+') || !w[1]) break;
        if (!strcmp(w, "--")) { i++; break; }
        const char *n = w + 1;
        int done = 0;
        if (o->rflux) {
            static const char *ctl[] = {"p", "b", "bn", "m", "M", "o", "e", "f", "fo", "fo+", "fo-", NULL};
            for (int k = 0; ctl[k]; k++)
                if (!strcmp(n, ctl[k]))
                    return hd_fail(HD_ERR_USAGE, "option %s is controlled by rfluxmtx (bins and outputs come from the "
                                   "#@rfluxmtx comments)", w);
            if (!strcmp(n, "v")) { o->verbose = 1; continue; }
            if (!strcmp(n, "bj")) {
                if (!need(argc, argv, i, 1) || hd_parse_double(argv[i + 1], &o->bj) || o->bj < 0 || o->bj > 1)
                    return hd_fail(HD_ERR_USAGE, "option -bj: expected a fraction in [0,1]");
                i++;
                continue;
            }
            if (!strcmp(n, "c")) o->cgiven = 1;
            if (!strcmp(n, "x") || !strcmp(n, "y")) o->xygiven = 1;
        }
        for (int k = 0; ignored[k].name; k++)
            if (!strcmp(w, ignored[k].name)) {
                if (!need(argc, argv, i, ignored[k].nargs)) return HD_ERR_USAGE;
                i += ignored[k].nargs;
                done = 1;
            }
        if (done) continue;
        for (int k = 0; ignored_toggles[k]; k++) {
            size_t l = strlen(ignored_toggles[k]);
            if (!strncmp(n, ignored_toggles[k], l) && (!n[l] || ((n[l] == '+' || n[l] == '-') && !n[l + 1]))) done = 1;
        }
        if (done) continue;
#define TOGGLE(nm, var) \
        if (!strncmp(n, nm, strlen(nm)) && (!n[strlen(nm)] || ((n[strlen(nm)] == '+' || n[strlen(nm)] == '-') && !n[strlen(nm) + 1]))) { \
            var = hd_opt_toggle_value(w, var); continue; }
        int Iv = o->irrad == 1, iv = o->irrad == 2;
        if (!strncmp(n, "I", 1) && (!n[1] || ((n[1] == '+' || n[1] == '-') && !n[2]))) {
            Iv = hd_opt_toggle_value(w, Iv);
            o->irrad = Iv ? 1 : (o->irrad == 1 ? 0 : o->irrad);
            continue;
        }
        if (!strncmp(n, "i", 1) && (!n[1] || ((n[1] == '+' || n[1] == '-') && !n[2]))) {
            iv = hd_opt_toggle_value(w, iv);
            o->irrad = iv ? 2 : (o->irrad == 2 ? 0 : o->irrad);
            continue;
        }
        TOGGLE("V", c->vflag)
        TOGGLE("h", o->header)
        TOGGLE("ld", o->ld)
        TOGGLE("fo", o->force)
        if (!strcmp(n, "w") || !strcmp(n, "w+") || !strcmp(n, "w-")) {
            hd_set_warnings(hd_opt_toggle_value(w, hd_warnings_enabled()));
            continue;
        }
        if (!strcmp(n, "f")) {
            if (!need(argc, argv, i, 1)) return HD_ERR_USAGE;
            hd_status st = hd_calctx_file(&a.cal, argv[++i]);
            if (st != HD_OK) return st;
            continue;
        }
        if (n[0] == 'f') {
            const char *f = n + 1;
            size_t l = strlen(f);
            if (l < 1 || l > 2 || !strchr("afd", f[0]) || (l == 2 && !strchr("afdc", f[1])) || (l == 1 && f[0] == 'c')) {
                if (l == 1 && f[0] == 'c') { o->fin = 'f'; o->fout = 'c'; continue; }
                return hd_fail(HD_ERR_USAGE, "option %s: expected -f[afd][afdc] (input/output format) or -f file.cal", w);
            }
            o->fin = f[0];
            o->fout = l == 2 ? f[1] : f[0];
            continue;
        }
        if (!strcmp(n, "e")) {
            if (!need(argc, argv, i, 1)) return HD_ERR_USAGE;
            hd_status st = hd_calctx_assign(&a.cal, argv[++i], 0);
            if (st != HD_OK) return st;
            continue;
        }
        if (!strcmp(n, "p")) {
            if (!need(argc, argv, i, 1)) return HD_ERR_USAGE;
            a.params = argv[++i];
            continue;
        }
        if (!strcmp(n, "b")) {
            if (!need(argc, argv, i, 1)) return HD_ERR_USAGE;
            a.bexpr = argv[++i];
            continue;
        }
        if (!strcmp(n, "bn")) {
            if (!need(argc, argv, i, 1)) return HD_ERR_USAGE;
            a.bn = argv[++i];
            continue;
        }
        if (!strcmp(n, "o")) {
            if (!need(argc, argv, i, 1)) return HD_ERR_USAGE;
            a.outspec = argv[++i];
            continue;
        }
        if (!strcmp(n, "m")) {
            if (!need(argc, argv, i, 1)) return HD_ERR_USAGE;
            hd_status st = add_mod(c, &a, argv[++i]);
            if (st != HD_OK) return st;
            continue;
        }
        if (!strcmp(n, "M")) {
            if (!need(argc, argv, i, 1)) return HD_ERR_USAGE;
            hd_status st = add_modfile(c, &a, argv[++i]);
            if (st != HD_OK) return st;
            continue;
        }
#define INTOPT(nm, var) if (!strcmp(n, nm)) { if (!need(argc, argv, i, 1) || !getint(w, argv[i + 1], &(var))) return HD_ERR_USAGE; i++; continue; }
#define REALOPT(nm, var) if (!strcmp(n, nm)) { if (!need(argc, argv, i, 1) || !getreal(w, argv[i + 1], &(var))) return HD_ERR_USAGE; i++; continue; }
        INTOPT("c", o->accum)
        INTOPT("x", o->xres)
        INTOPT("y", o->yres)
        INTOPT("n", o->nthreads)
        REALOPT("t", o->report)
        INTOPT("ab", c->o.ab)
        INTOPT("ad", c->o.ad)
        INTOPT("lr", c->o.lr)
        REALOPT("lw", c->o.lw)
        REALOPT("ss", c->o.ss)
        REALOPT("st", c->o.st)
        REALOPT("dj", c->o.dj)
        if (!strcmp(n, "seed")) {
            long s;
            if (!need(argc, argv, i, 1) || hd_parse_long(argv[i + 1], &s))
                return hd_fail(HD_ERR_USAGE, "option -seed: expected an integer");
            c->o.seed = (uint64_t)s;
            i++;
            continue;
        }
        if (!strcmp(n, "av")) {
            if (!need(argc, argv, i, 3)) return HD_ERR_USAGE;
            for (int k = 0; k < 3; k++)
                if (!getreal(w, argv[i + 1 + k], &c->o.av[k])) return HD_ERR_USAGE;
            hd_warn("-av is ignored by rcontrib (contributions only come from tracked modifiers)");
            i += 3;
            continue;
        }
        if (!strncmp(n, "ap", 2) || !strcmp(n, "am") || !strcmp(n, "ac") || !strcmp(n, "aC"))
            return hd_fail(HD_ERR_UNSUPPORTED, "option %s: photon maps are not supported by this rcontrib", w);
        if (!strcmp(n, "r"))
            return hd_fail(HD_ERR_UNSUPPORTED, "option -r (recover) is not supported");
        return hd_fail(HD_ERR_USAGE, "unknown option %s", w);
    }
    if (o->accum < 0) return hd_fail(HD_ERR_USAGE, "-c %d: must not be negative", o->accum);
    if (o->xres < 0 || o->yres < 0) return hd_fail(HD_ERR_USAGE, "-x/-y must not be negative");
    if (c->o.ab < 0) return hd_fail(HD_ERR_UNSUPPORTED, "-ab %d: negative -ab (photon-map mode) is not supported", c->o.ab);
    if (c->o.ad < 0) return hd_fail(HD_ERR_USAGE, "-ad must not be negative");
    if (o->fout == 'c' && (o->xres <= 0 || o->yres <= 0))
        return hd_fail(HD_ERR_USAGE, "-f?c (picture output) needs -x and -y");
    *first = i;
    return HD_OK;
}

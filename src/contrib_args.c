/* heliodon — rcontrib command-line parsing (order-dependent -o -b -bn -p -f -e -m -M). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/contrib.h"
#include "heliodon/options.h"
#include "heliodon/rcmerge.h"

void hd_rcontrib_defaults(hd_rcontrib_opts *o, hd_render_opts *r)
{
    memset(o, 0, sizeof *o);
    o->irrad = 0;
    o->fin = o->fout = 'a';
    o->accum = 1;
    o->header = 1;
    o->nthreads = 1;
    o->pm.cache = 4000000;
    o->pm.exact_direct = 1;
    if (r) {
        hd_render_defaults(r);
        /* rcontrib's defaults where they differ from rtrace's */
        r->ab = 1;
        r->ad = 350;
        r->dj = 0.9;
        r->st = 0.02;
    }
}

typedef struct argstate {
    hd_calctx cal;
    const char *bexpr, *bn, *params, *outspec;   /* in force for the next -m / -M */
    hd_contrib *c;
    hd_rcontrib_opts *o;
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

/* "-X", "+X", "-X+", "-X-" (also "+X+"...) for toggle name X. */
static int toggle_word(const char *w, const char *name)
{
    size_t l = strlen(name);
    if ((w[0] != '-' && w[0] != '+') || strncmp(w + 1, name, l)) return 0;
    const char *t = w + 1 + l;
    return !t[0] || ((t[0] == '+' || t[0] == '-') && !t[1]);
}

static int refuse_controlled(const char *w)
{
    hd_fail(HD_ERR_USAGE, "option %s is controlled by rfluxmtx (bins and outputs come from the #@rfluxmtx comments)", w);
    return -1;
}

/* -p -b -bn -o -e -m -M: order-dependent; -m and -M take the -p/-b/-bn/-o
 * in force at their position (the parser applies options in order). */
static int opt_positional(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    argstate *a = ctx;
    const char *n = opt->name;
    if (a->o->rflux) return refuse_controlled(argv[i]);
    if (i + 1 >= argc) { hd_fail(HD_ERR_USAGE, "option %s expects %s", argv[i], opt->args); return -1; }
    const char *v = argv[i + 1];
    hd_status st = HD_OK;
    if (!strcmp(n, "p")) a->params = v;
    else if (!strcmp(n, "b")) a->bexpr = v;
    else if (!strcmp(n, "bn")) a->bn = v;
    else if (!strcmp(n, "o")) a->outspec = v;
    else if (!strcmp(n, "e")) st = hd_calctx_assign(&a->cal, v, 0);
    else if (!strcmp(n, "m")) st = add_mod(a->c, a, v);
    else st = add_modfile(a->c, a, v);
    return st == HD_OK ? 1 : -1;
}

/* -f file.cal, or -f[afd][afdc] / -fc formats */
static int opt_f(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    argstate *a = ctx;
    (void)opt;
    const char *w = argv[i], *f = w + 2;
    if (!f[0]) {
        if (a->o->rflux) return refuse_controlled(w);
        if (i + 1 >= argc) { hd_fail(HD_ERR_USAGE, "option %s expects file.cal", w); return -1; }
        return hd_calctx_file(&a->cal, argv[i + 1]) == HD_OK ? 1 : -1;
    }
    size_t l = strlen(f);
    if (l == 1 && f[0] == 'c') { a->o->fin = 'f'; a->o->fout = 'c'; return 0; }
    if (l > 2 || !strchr("afd", f[0]) || (l == 2 && !strchr("afdc", f[1]))) {
        hd_fail(HD_ERR_USAGE, "option %s: expected -f[afd][afdc] (input/output format) or -f file.cal", w);
        return -1;
    }
    a->o->fin = f[0];
    a->o->fout = l == 2 ? f[1] : f[0];
    return 0;
}

/* -I / -i toggles: the last one given decides between -I, -i and neither */
static int opt_irrad(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)argc;
    hd_rcontrib_opts *o = ((argstate *)ctx)->o;
    if (!toggle_word(argv[i], opt->name)) { hd_fail(HD_ERR_USAGE, "unknown option %s", argv[i]); return -1; }
    int mode = opt->name[0] == 'I' ? 1 : 2;
    int on = hd_opt_toggle_value(argv[i], o->irrad == mode);
    o->irrad = on ? mode : (o->irrad == mode ? 0 : o->irrad);
    return 0;
}

/* -c -x -y: integers (parsed by the common parser) that rfluxmtx needs to
 * know were given */
static int opt_int_seen(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    hd_rcontrib_opts *o = ((argstate *)ctx)->o;
    int *dest = opt->name[0] == 'c' ? &o->accum : opt->name[0] == 'x' ? &o->xres : &o->yres;
    const hd_opt one[2] = {{opt->name, HD_OPT_INT, dest, 0, 0, "N", 0}, HD_OPT_END};
    int n = hd_opt_parse_one(one, argc, argv, i);
    if (n < 0) return -1;
    if (opt->name[0] == 'c') o->cgiven = 1;
    else o->xygiven = 1;
    return n - 1;
}

static int opt_bj(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)opt;
    hd_rcontrib_opts *o = ((argstate *)ctx)->o;
    if (i + 1 >= argc || hd_parse_double(argv[i + 1], &o->bj) || o->bj < 0 || o->bj > 1) {
        hd_fail(HD_ERR_USAGE, "option -bj: expected a fraction in [0,1]");
        return -1;
    }
    return 1;
}

static int opt_verbose(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)opt; (void)argc; (void)argv; (void)i;
    ((argstate *)ctx)->o->verbose = 1;
    return 0;
}

static int opt_controlled(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)opt; (void)argc; (void)ctx;
    return refuse_controlled(argv[i]);
}

static int opt_unsupported(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)argc; (void)ctx; (void)opt;
    hd_fail(HD_ERR_UNSUPPORTED, "option %s: photon maps are not supported by rfluxmtx", argv[i]);
    return -1;
}

/* -ap file [bandwidth [bandwidth2]]: photon-map mode (the photon gather) */
static int opt_ap(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)opt;
    hd_rc_pmap_opts *p = &((argstate *)ctx)->o->pm;
    if (i + 1 >= argc) {
        hd_fail(HD_ERR_USAGE, "-ap: expected a photon map file");
        return -1;
    }
    p->file = argv[i + 1];
    p->bw = 0;
    if (i + 2 >= argc || hd_parse_double(argv[i + 2], &p->bw)) return 1;
    if (i + 3 >= argc || argv[i + 3][0] == '-' || hd_parse_double(argv[i + 3], &p->bw2)) return 2;
    return 3;
}

/* -R first count: a piece of the output (records first ... first+count-1) */
static int opt_range(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)opt;
    hd_rcontrib_opts *o = ((argstate *)ctx)->o;
    long a, b;
    if (i + 2 >= argc || hd_parse_long(argv[i + 1], &a) || hd_parse_long(argv[i + 2], &b) || a < 0 || b <= 0) {
        hd_fail(HD_ERR_USAGE, "option -R: expected the first record (>= 0) and a record count (> 0)");
        return -1;
    }
    o->ranged = 1;
    o->rec_first = (uint64_t)a;
    o->rec_count = (uint64_t)b;
    return 2;
}

/* Targets of rcontrib's own compatibility options without effect. */
static double ignored_d;

hd_status hd_rcontrib_parse_args(int argc, char **argv, hd_contrib *c, hd_rcontrib_opts *o, int *first)
{
    argstate a;
    memset(&a, 0, sizeof a);
    hd_calctx_init(&a.cal);
    a.c = c;
    a.o = o;
    int warn = hd_warnings_enabled();
    int rf = o->rflux;
    /* the rendering options (-ab -ad -lw -lr -ss -st -dj -av -seed and the
     * ignored ambient-cache / source options) are rtrace's group */
    hd_opt render_tab[HD_RENDER_NOPTS];
    hd_render_option_table(render_tab, &c->o);
    const hd_opt fo_toggle = {"fo", HD_OPT_TOGGLE, &o->force, 0, 0, 0, "force overwriting of output files"};
    const hd_opt fo_refused = {"fo", HD_OPT_FUNC, &a, opt_controlled, 1, 0, "(set by rfluxmtx)"};
    static const hd_opt empty[1] = {HD_OPT_END};
    const hd_opt none = {"", HD_OPT_TABLE, (void *)empty, 0, 0, 0, 0};
    const hd_opt v_opt = {"v", HD_OPT_FUNC, &a, opt_verbose, 0, 0, "print the equivalent rcontrib command"};
    const hd_opt bj_opt = {"bj", HD_OPT_FUNC, &a, opt_bj, 0, "frac", "bin jitter"};
    const hd_opt r_opt = {"R", HD_OPT_FUNC, &a, opt_range, 0, "first count", "compute these records only, as a piece for rcmerge"};
    /* photon-map mode (rcontrib only) */
    const hd_opt ap_opt = {"ap", HD_OPT_FUNC, &a, opt_ap, 0, "file [bw [bw2]]", "photon gather from a contribution photon map"};
    const hd_opt ap_refused = {"ap", HD_OPT_FUNC, &a, opt_unsupported, 1, 0, "(not with rfluxmtx)"};
    const hd_opt am_opt = {"am", HD_OPT_REAL, &o->pm.am, 0, 0, "r", "-ap: maximum search radius"};
    const hd_opt ac_opt = {"ac", HD_OPT_REAL, &o->pm.ac, 0, 0, "N", "-ap: accepted (pages are fixed by mkpmap)"};
    const hd_opt aC_opt = {"aC", HD_OPT_COUNT, &o->pm.cache, 0, 0, "N", "-ap: photons held in the page cache"};
    const hd_opt apd_opt = {"apd", HD_OPT_TOGGLE, &o->pm.exact_direct, 0, 0, 0, "-ap: direct light through glass by shadow rays"};
    const hd_opt apR_opt = {"apR", HD_OPT_FUNC, &a, opt_range, 0, "first count", "-R's older photon-mode name"};
    const hd_opt table[] = {
        {"m", HD_OPT_FUNC, &a, opt_positional, 0, "mod", "track modifier mod (with the -b/-bn/-o/-p in force)"},
        {"M", HD_OPT_FUNC, &a, opt_positional, 0, "file", "track the modifiers listed in file"},
        {"b", HD_OPT_FUNC, &a, opt_positional, 0, "expr", "bin expression for the following -m/-M"},
        {"bn", HD_OPT_FUNC, &a, opt_positional, 0, "N", "number of bins for the following -m/-M"},
        {"o", HD_OPT_FUNC, &a, opt_positional, 0, "spec", "output file pattern for the following -m/-M"},
        {"p", HD_OPT_FUNC, &a, opt_positional, 0, "a=v,...", "parameters for the following -m/-M"},
        {"e", HD_OPT_FUNC, &a, opt_positional, 0, "expr", ".cal definitions (bin functions and parameters)"},
        {"f", HD_OPT_FUNC, &a, opt_f, 1, 0, "-f file.cal: bin functions; -f[afd][afdc]: input/output format"},
        rf ? fo_refused : fo_toggle,
        {"I", HD_OPT_FUNC, &a, opt_irrad, 1, 0, "[+-]I: irradiance at the input points"},
        {"i", HD_OPT_FUNC, &a, opt_irrad, 1, 0, "[+-]i: irradiance at the surfaces hit"},
        {"V", HD_OPT_TOGGLE, &c->vflag, 0, 0, 0, "contributions (coefficients times emitted radiance)"},
        {"h", HD_OPT_TOGGLE, &o->header, 0, 0, 0, "write information headers (default on)"},
        {"ld", HD_OPT_TOGGLE, &o->ld, 0, 0, 0, "limit ray length to the length of its direction"},
        {"w", HD_OPT_TOGGLE, &warn, 0, 0, 0, "warnings (default on)"},
        {"c", HD_OPT_FUNC, &a, opt_int_seen, 0, "N", "rays accumulated per record (0 = all)"},
        {"x", HD_OPT_FUNC, &a, opt_int_seen, 0, "N", "x resolution"},
        {"y", HD_OPT_FUNC, &a, opt_int_seen, 0, "N", "y resolution"},
        {"n", HD_OPT_INT, &o->nthreads, 0, 0, "N", "number of threads"},
        {"t", HD_OPT_REAL, &o->report, 0, 0, "s", "progress report interval (seconds)"},
        {"dn", HD_OPT_INT, &c->dn, 0, 0, "N", "sources sampled per vertex after a diffuse bounce (0 = all; heliodon extension)"},
        {"stats", HD_OPT_TOGGLE, &c->stats, 0, 0, 0, "print counts of the direct-source work (heliodon extension)"},
        /* compatibility, no effect */
        {"ps", HD_OPT_REAL, &ignored_d, 0, 0, "N", "ignored"},
        {"pj", HD_OPT_REAL, &ignored_d, 0, 0, "f", "ignored"},
        {"pt", HD_OPT_REAL, &ignored_d, 0, 0, "f", "ignored"},
        {"ms", HD_OPT_REAL, &ignored_d, 0, 0, "f", "ignored"},
        rf ? ap_refused : ap_opt,
        rf ? none : am_opt,
        rf ? none : ac_opt,
        rf ? none : aC_opt,
        rf ? none : apd_opt,
        rf ? none : apR_opt,
        {"r", HD_OPT_TOGGLE, &o->recover, 0, 0, 0, "recover: continue the outputs of an interrupted run"},
        /* rfluxmtx only (the names are unknown options to rcontrib) */
        rf ? v_opt : none,
        rf ? bj_opt : none,
        rf ? none : r_opt,
        {"", HD_OPT_TABLE, render_tab, 0, 0, 0, "rendering options (rtrace's, render.h)"},
        HD_OPT_END};
    hd_status st = hd_opt_parse_args(argc, argv, table, first);
    hd_calctx_free(&a.cal);       /* each modifier keeps its own reference */
    hd_set_warnings(warn);
    if (st != HD_OK) return st;
    if (o->accum < 0) return hd_fail(HD_ERR_USAGE, "-c %d: must not be negative", o->accum);
    if (o->xres < 0 || o->yres < 0) return hd_fail(HD_ERR_USAGE, "-x/-y must not be negative");
    if (c->o.ab < 0 && !o->pm.file)
        return hd_fail(HD_ERR_UNSUPPORTED, "-ab %d: negative -ab needs a photon map (-ap)", c->o.ab);
    if (c->o.ad < 0) return hd_fail(HD_ERR_USAGE, "-ad must not be negative");
    if (c->o.av[0] != 0 || c->o.av[1] != 0 || c->o.av[2] != 0)
        hd_warn("-av is ignored by rcontrib (contributions only come from tracked modifiers)");
    if (o->fout == 'c' && (o->xres <= 0 || o->yres <= 0))
        return hd_fail(HD_ERR_USAGE, "-f?c (picture output) needs -x and -y");
    if (o->fout == 'c' && o->accum == 0)
        return hd_fail(HD_ERR_USAGE, "-c 0 and picture output (-f?c): the sum of all records is not a picture");
    return hd_rcontrib_check_range(o);
}

/* -R: the range must lie in the output the full run writes */
hd_status hd_rcontrib_check_range(const hd_rcontrib_opts *o)
{
    if (!o->ranged) return HD_OK;
    if (o->rec_count == 0) return hd_fail(HD_ERR_USAGE, "-R: the record count must be positive");
    if (o->recover) return hd_fail(HD_ERR_USAGE, "-R with -r: a piece is not recovered, run it again without -r");
    if (o->accum == 0) return hd_fail(HD_ERR_USAGE, "-R with -c 0: the sum of all records has no range");
    if (o->yres <= 0) return hd_fail(HD_ERR_USAGE, "-R needs -y (and -x): the number of records of the full output");
    uint64_t total = hd_rcontrib_nrecords(o);
    if (o->rec_first >= total || o->rec_count > total - o->rec_first)
        return hd_fail(HD_ERR_USAGE, "-R %llu %llu: records beyond the %llu of -x %d -y %d",
                       (unsigned long long)o->rec_first, (unsigned long long)o->rec_count,
                       (unsigned long long)total, o->xres, o->yres);
    return HD_OK;
}

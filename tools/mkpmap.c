/* mkpmap — build a contribution photon map (heliodon). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

#include "heliodon/common.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/options.h"
#include "heliodon/pmap.h"
#include "heliodon/scene.h"
#include "heliodon/trace.h"

static const char *Synopsis =
    "-apC file N [-apo[+|-|0] mod] [-apO[+|-|0] file] [-apr seed] [-n N] [-t s]\n"
    "              [-fo[+|-]] [-lr N] [-ld d] [-bv[+|-]] [-apB membudget] [-apZ photons/page]\n"
    "              [-apH k n] [-e file] scene.oct|scene.rad ...\n"
    "       mkpmap [-fo] -apJ merged.pm shard0.pm shard1.pm ...";

typedef struct mkopts {
    hd_pmap_build_opts o;
    const char *out, *join;
} mkopts;

static int fail(const char *fmt, const char *a, const char *b)
{
    hd_fail(HD_ERR_USAGE, fmt, a, b);
    return -1;
}

static int need(int argc, char **argv, int i, int n)
{
    if (i + n < argc) return 0;
    hd_fail(HD_ERR_USAGE, "option %s: expected %d argument%s", argv[i], n, n > 1 ? "s" : "");
    return -1;
}

/* -apo, -apo+, -apo-, -apo0 (likewise -apO): the orientation suffix */
static int orient_of(const char *opt, char *orient)
{
    const char *suffix = opt + 4;
    *orient = !*suffix || !strcmp(suffix, "+") ? '+' : !strcmp(suffix, "-") ? '-' : !strcmp(suffix, "0") ? '0' : 0;
    if (*orient) return 0;
    hd_fail(HD_ERR_USAGE, "option %s: expected -%.3s, -%.3s+, -%.3s- or -%.3s0", opt, opt + 1, opt + 1, opt + 1,
            opt + 1);
    return -1;
}

static int add_port(hd_pmap_build_opts *o, const char *mod, char orient)
{
    if (o->nports >= HD_PMAP_MAXPORTS) {
        hd_fail(HD_ERR_USAGE, "too many photon port modifiers (at most %d)", HD_PMAP_MAXPORTS);
        return -1;
    }
    o->ports[o->nports].modifier = mod;
    o->ports[o->nports].orient = orient;
    o->nports++;
    return 0;
}

static int opt_apC(const hd_opt *t, int argc, char **argv, int i, void *ctx)
{
    (void)t;
    mkopts *m = ctx;
    uint64_t cnt;
    if (need(argc, argv, i, 2)) return -1;
    m->out = argv[i + 1];
    if (hd_parse_count(argv[i + 2], &cnt) || cnt == 0)
        return fail("-apC %s %s: expected a positive photon count (k/m/g suffixes allowed)", argv[i + 1], argv[i + 2]);
    m->o.nphotons = cnt;
    return 2;
}

static int opt_port(const hd_opt *t, int argc, char **argv, int i, void *ctx)
{
    (void)t;
    mkopts *m = ctx;
    char orient;
    if (orient_of(argv[i], &orient) || need(argc, argv, i, 1)) return -1;
    if (argv[i][3] == 'o') return add_port(&m->o, argv[i + 1], orient) ? -1 : 1;
    FILE *fp = fopen(argv[i + 1], "r");   /* -apO: a file of port modifiers */
    if (!fp) return fail("%s: cannot open port modifier file%s", argv[i + 1], "");
    char w[256];
    int rc = 1;
    while (rc > 0 && fscanf(fp, "%255s", w) == 1) {
        char *d = hd_strdup(w);   /* kept for the program's lifetime */
        if (!d || add_port(&m->o, d, orient)) rc = -1;
    }
    fclose(fp);
    return rc;
}

static int opt_num(const hd_opt *t, int argc, char **argv, int i, void *ctx)
{
    mkopts *m = ctx;
    const char *a = argv[i];
    uint64_t cnt;
    long lv, lv2;
    double dv;
    if (need(argc, argv, i, !strcmp(t->name, "apH") ? 2 : 1)) return -1;
    const char *v = argv[i + 1];
    if (!strcmp(t->name, "apr")) {
        if (hd_parse_long(v, &lv)) return fail("-apr %s: expected an integer seed%s", v, "");
        m->o.seed = (uint64_t)lv;
    } else if (!strcmp(t->name, "apH")) {
        if (hd_parse_long(v, &lv) || lv < 0 || hd_parse_long(argv[i + 2], &lv2) || lv2 < 1 || lv >= lv2)
            return fail("-apH %s %s: expected shard k of n (0 <= k < n)", v, argv[i + 2]);
        m->o.shard = (int)lv;
        m->o.nshards = (int)lv2;
        return 2;
    } else if (!strcmp(t->name, "apB")) {
        if (hd_parse_count(v, &cnt) || cnt < 65536)
            return fail("-apB %s: expected a memory budget in bytes >= 64k (k/m/g suffixes)%s", v, "");
        m->o.mem_budget = cnt;
    } else if (!strcmp(t->name, "apZ")) {
        if (hd_parse_count(v, &cnt) || cnt < 64 || cnt > (1u << 20))
            return fail("-apZ %s: expected 64 to 1m photons per page%s", v, "");
        m->o.page_photons = (uint32_t)cnt;
    } else if (!strcmp(t->name, "n")) {
        if (hd_parse_long(v, &lv) || lv < 0 || lv > 4096) return fail("-n %s: expected 0..4096%s", v, "");
        m->o.nthreads = (int)lv;
    } else if (!strcmp(t->name, "t")) {
        if (hd_parse_double(v, &dv) || dv < 0) return fail("-t %s: expected seconds >= 0%s", v, "");
        m->o.report_interval = dv;
    } else if (!strcmp(t->name, "ld")) {
        if (hd_parse_double(v, &dv)) return fail("-ld %s: expected a distance%s", v, "");
        m->o.maxdist = dv;
    } else {   /* -lr, -apm */
        if (hd_parse_long(v, &lv)) return fail("%s %s: expected an integer", a, v);
        m->o.maxbounce = lv <= 0 ? 5000 : (int)(lv > 1000000 ? 1000000 : lv);
    }
    return 1;
}

static int opt_stderr(const hd_opt *t, int argc, char **argv, int i, void *ctx)
{
    (void)t; (void)ctx;
    if (need(argc, argv, i, 1)) return -1;
    if (!freopen(argv[i + 1], "a", stderr)) return fail("-e %s: cannot open diagnostics file%s", argv[i + 1], "");
    return 1;
}

static int opt_warn(const hd_opt *t, int argc, char **argv, int i, void *ctx)
{
    (void)t; (void)argc; (void)ctx;
    if (argv[i][2] && strcmp(argv[i] + 2, "+") && strcmp(argv[i] + 2, "-"))
        return fail("unknown option %s%s", argv[i], "");
    hd_set_warnings(hd_opt_toggle_value(argv[i], hd_warnings_enabled()));   /* at once: -w -apD x is quiet */
    return 0;
}

static int opt_ignored(const hd_opt *t, int argc, char **argv, int i, void *ctx)
{
    (void)t; (void)ctx;
    if (need(argc, argv, i, 1)) return -1;
    hd_warn("%s %s ignored: heliodon emits each source in fixed batches until its stored-photon "
            "budget is met and samples the port area by stratification", argv[i], argv[i + 1]);
    return 1;
}

static int opt_refused(const hd_opt *t, int argc, char **argv, int i, void *ctx)
{
    (void)argc; (void)ctx;
    if (!strcmp(t->help, "other photon maps"))
        return fail("%s: only contribution photon maps (-apC) are supported%s", argv[i], "");
    return fail("%s: not supported by heliodon's mkpmap (regions of interest, antimatter receivers, "
                "storage include/exclude lists and participating media are not implemented)%s", argv[i], "");
}

int main(int argc, char **argv)
{
    mkopts m;
    memset(&m, 0, sizeof m);
    hd_pmap_build_opts_init(&m.o);
    hd_pmap_build_opts *o = &m.o;
    int force = 0, verbose = 0;
    const hd_opt table[] = {
        {"apC", HD_OPT_FUNC, &m, opt_apC, 0, "file N", "contribution photon map: file and photon count (k/m/g)"},
        {"apo", HD_OPT_FUNC, &m, opt_port, 1, "mod", "-apo[+|-|0]: photon port modifier and orientation"},
        {"apO", HD_OPT_FUNC, &m, opt_port, 1, "file", "-apO[+|-|0]: file of photon port modifiers"},
        {"apr", HD_OPT_FUNC, &m, opt_num, 0, "seed", "random seed"},
        {"apH", HD_OPT_FUNC, &m, opt_num, 0, "k n", "trace shard k of n (merge with -apJ)"},
        {"apJ", HD_OPT_STRING, &m.join, 0, 0, "merged.pm", "merge the shard maps given as operands into this file"},
        {"apB", HD_OPT_FUNC, &m, opt_num, 0, "bytes", "memory budget of the build (k/m/g)"},
        {"apZ", HD_OPT_FUNC, &m, opt_num, 0, "N", "photons per page (64..1m)"},
        {"n", HD_OPT_FUNC, &m, opt_num, 0, "N", "threads (0: all processors)"},
        {"t", HD_OPT_FUNC, &m, opt_num, 0, "s", "progress report interval"},
        {"lr", HD_OPT_FUNC, &m, opt_num, 0, "N", "maximum bounces (<= 0: 5000)"},
        {"apm", HD_OPT_FUNC, &m, opt_num, 0, "N", "same as -lr"},
        {"ld", HD_OPT_FUNC, &m, opt_num, 0, "d", "maximum photon path length"},
        {"bv", HD_OPT_TOGGLE, &o->backvis, 0, 0, NULL, "back faces visible"},
        {"fo", HD_OPT_TOGGLE, &force, 0, 0, NULL, "overwrite existing output"},
        {"v", HD_OPT_TOGGLE, &verbose, 0, 0, NULL, "report the build"},
        {"w", HD_OPT_FUNC, &m, opt_warn, 1, NULL, "[+-]w: warnings on/off (-w alone flips)"},
        {"e", HD_OPT_FUNC, &m, opt_stderr, 0, "file", "diagnostics to this file"},
        {"apD", HD_OPT_FUNC, &m, opt_ignored, 0, "f", "accepted, ignored"},
        {"apM", HD_OPT_FUNC, &m, opt_ignored, 0, "n", "accepted, ignored"},
        {"dp", HD_OPT_FUNC, &m, opt_ignored, 0, "n", "accepted, ignored"},
        {"ds", HD_OPT_FUNC, &m, opt_ignored, 0, "f", "accepted, ignored"},
        {"apg", HD_OPT_FUNC, &m, opt_refused, 0, NULL, "other photon maps"},
        {"apc", HD_OPT_FUNC, &m, opt_refused, 0, NULL, "other photon maps"},
        {"apv", HD_OPT_FUNC, &m, opt_refused, 0, NULL, "other photon maps"},
        {"apd", HD_OPT_FUNC, &m, opt_refused, 0, NULL, "other photon maps"},
        {"app", HD_OPT_FUNC, &m, opt_refused, 0, NULL, "other photon maps"},
        {"api", HD_OPT_FUNC, &m, opt_refused, 0, NULL, "not supported"},
        {"apI", HD_OPT_FUNC, &m, opt_refused, 0, NULL, "not supported"},
        {"aps", HD_OPT_FUNC, &m, opt_refused, 0, NULL, "not supported"},
        {"apS", HD_OPT_FUNC, &m, opt_refused, 0, NULL, "not supported"},
        {"ae", HD_OPT_FUNC, &m, opt_refused, 0, NULL, "not supported"},
        {"aE", HD_OPT_FUNC, &m, opt_refused, 0, NULL, "not supported"},
        {"ai", HD_OPT_FUNC, &m, opt_refused, 0, NULL, "not supported"},
        {"aI", HD_OPT_FUNC, &m, opt_refused, 0, NULL, "not supported"},
        {"ma", HD_OPT_FUNC, &m, opt_refused, 1, NULL, "not supported"},
        {"me", HD_OPT_FUNC, &m, opt_refused, 1, NULL, "not supported"},
        {"mg", HD_OPT_FUNC, &m, opt_refused, 1, NULL, "not supported"},
        HD_OPT_END};
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, Synopsis);
    argc = p.argc;   /* @file words expanded: recorded in the headers */
    argv = p.argv;
    int i = p.first;
    if (m.join) {   /* merge shards */
        if (argc - i < 1) hd_die_msg("-apJ %s: expected the shard maps to merge", m.join);
        if (!force && access(m.join, F_OK) == 0) hd_die_msg("%s: file exists (use -fo to overwrite)", m.join);
        hd_header h;
        hd_header_init(&h);
        if (hd_header_add_command(&h, argc, argv)) hd_die();
        if (hd_pmap_merge((const char *const *)(argv + i), argc - i, m.join, h.text)) hd_die();
        hd_header_free(&h);
        hd_optparse_free(&p);
        return 0;
    }
    const char *out = m.out;
    if (!out) { hd_fail(HD_ERR_USAGE, "no contribution photon map (-apC file N)"); hd_report_error(); hd_opt_usage(table, Synopsis); return 1; }
    if (i >= argc) { hd_fail(HD_ERR_USAGE, "missing scene (octree or .rad files)"); hd_report_error(); hd_opt_usage(table, Synopsis); return 1; }
    if (o->nports == 0) hd_die_msg("no photon port (-apo modifier): heliodon emits distant-source photons only through ports");
    if (!force && access(out, F_OK) == 0) hd_die_msg("%s: file exists (use -fo to overwrite)", out);

    hd_scene sc;
    hd_scene_init(&sc);
    if (hd_scene_load_files(&sc, argc - i, argv + i, NULL)) hd_die();
    hd_tscene *ts;
    if (hd_tscene_from_scene(&ts, &sc)) hd_die();

    hd_header h;
    hd_header_init(&h);
    if (hd_header_add_command(&h, argc, argv)) hd_die();
    if (o->nshards > 1) {
        /* what -apJ checks: every piece a shard of the same run (count, seed, scene bytes) */
        uLong crc = crc32(0L, Z_NULL, 0);
        for (int k = i; k < argc; k++) {
            FILE *fp = fopen(argv[k], "rb");
            if (!fp) continue;
            unsigned char buf[65536];
            size_t nb;
            while ((nb = fread(buf, 1, sizeof buf, fp)) > 0) crc = crc32(crc, buf, (uInt)nb);
            fclose(fp);
        }
        if (hd_header_appendf(&h, "PMAPSHARD= %d %d", o->shard, o->nshards) ||
            hd_header_appendf(&h, "PMAPRUN= %llu %llu %08lx", (unsigned long long)o->nphotons,
                              (unsigned long long)o->seed, (unsigned long)crc))
            hd_die();
    }
    hd_pmap_build_stats st;
    if (hd_pmap_build(ts, o, out, h.text, &st, NULL)) hd_die();
    if (verbose || o->report_interval > 0)
        fprintf(stderr, "mkpmap: %llu photons stored from %llu emitted, %d of %d sources (%d emit nothing "
                        "through the ports; their share went to the others); %llu bytes "
                        "(%.2f per photon); trace %.2f s, sort+write %.2f s (%d runs)\n",
                (unsigned long long)st.stored, (unsigned long long)st.emitted, st.nactive, st.nsources,
                st.nsources - st.nlive,
                (unsigned long long)st.file_bytes, st.stored ? (double)st.file_bytes / (double)st.stored : 0.0,
                st.seconds_trace, st.seconds_write, st.nruns);
    hd_header_free(&h);
    hd_tscene_free(ts);
    hd_scene_free(&sc);
    hd_optparse_free(&p);
    return 0;
}

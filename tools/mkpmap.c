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

static const char *Usage =
    "usage: mkpmap -apC file N [-apo[+|-|0] mod] [-apO[+|-|0] file] [-apr seed] [-n N] [-t s]\n"
    "              [-fo[+|-]] [-lr N] [-ld d] [-bv[+|-]] [-apB membudget] [-apZ photons/page]\n"
    "              [-apH k n] [-e file] scene.oct|scene.rad ...\n"
    "       mkpmap [-fo] -apJ merged.pm shard0.pm shard1.pm ...\n";

static int need(int argc, char **argv, int i, int n)
{
    if (i + n >= argc) hd_die_msg("option %s: expected %d argument%s", argv[i], n, n > 1 ? "s" : "");
    return 1;
}

static char orient_of(const char *opt, const char *suffix)
{
    if (!*suffix || !strcmp(suffix, "+")) return '+';
    if (!strcmp(suffix, "-")) return '-';
    if (!strcmp(suffix, "0")) return '0';
    hd_die_msg("option %s: expected -%.3s, -%.3s+, -%.3s- or -%.3s0", opt, opt + 1, opt + 1, opt + 1, opt + 1);
}

static void add_port(hd_pmap_build_opts *o, const char *mod, char orient)
{
    if (o->nports >= HD_PMAP_MAXPORTS) hd_die_msg("too many photon port modifiers (at most %d)", HD_PMAP_MAXPORTS);
    o->ports[o->nports].modifier = mod;
    o->ports[o->nports].orient = orient;
    o->nports++;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    hd_pmap_build_opts o;
    hd_pmap_build_opts_init(&o);
    const char *out = NULL;
    int force = 0, verbose = 0;
    int i;
    for (i = 1; i < argc && argv[i][0] == '-' && argv[i][1]; i++) {
        const char *a = argv[i];
        uint64_t cnt;
        long lv, lv2;
        double dv;
        if (!strcmp(a, "-apC")) {
            need(argc, argv, i, 2);
            out = argv[++i];
            if (hd_parse_count(argv[++i], &cnt) || cnt == 0)
                hd_die_msg("-apC %s %s: expected a positive photon count (k/m/g suffixes allowed)", out, argv[i]);
            o.nphotons = cnt;
        } else if (!strncmp(a, "-apO", 4)) {
            char orient = orient_of(a, a + 4);
            need(argc, argv, i, 1);
            FILE *fp = fopen(argv[++i], "r");
            if (!fp) hd_die_msg("%s: cannot open port modifier file", argv[i]);
            char w[256];
            while (fscanf(fp, "%255s", w) == 1) {
                char *d = hd_strdup(w);
                if (!d) hd_die();
                add_port(&o, d, orient);   /* kept for the program's lifetime */
            }
            fclose(fp);
        } else if (!strncmp(a, "-apo", 4)) {
            char orient = orient_of(a, a + 4);
            need(argc, argv, i, 1);
            add_port(&o, argv[++i], orient);
        } else if (!strcmp(a, "-apr")) {
            need(argc, argv, i, 1);
            if (hd_parse_long(argv[++i], &lv)) hd_die_msg("-apr %s: expected an integer seed", argv[i]);
            o.seed = (uint64_t)lv;
        } else if (!strcmp(a, "-apH")) {
            need(argc, argv, i, 2);
            if (hd_parse_long(argv[i + 1], &lv) || lv < 0 || hd_parse_long(argv[i + 2], &lv2) || lv2 < 1 || lv >= lv2)
                hd_die_msg("-apH %s %s: expected shard k of n (0 <= k < n)", argv[i + 1], argv[i + 2]);
            o.shard = (int)lv;
            o.nshards = (int)lv2;
            i += 2;
        } else if (!strcmp(a, "-apJ")) {
            need(argc, argv, i, 2);
            const char *dst = argv[i + 1];
            if (!force && access(dst, F_OK) == 0) hd_die_msg("%s: file exists (use -fo before -apJ to overwrite)", dst);
            hd_header h;
            hd_header_init(&h);
            if (hd_header_add_command(&h, argc, argv)) hd_die();
            if (hd_pmap_merge((const char *const *)(argv + i + 2), argc - i - 2, dst, h.text)) hd_die();
            hd_header_free(&h);
            return 0;
        } else if (!strcmp(a, "-apB")) {
            need(argc, argv, i, 1);
            if (hd_parse_count(argv[++i], &cnt) || cnt < 65536)
                hd_die_msg("-apB %s: expected a memory budget in bytes >= 64k (k/m/g suffixes)", argv[i]);
            o.mem_budget = cnt;
        } else if (!strcmp(a, "-apZ")) {
            need(argc, argv, i, 1);
            if (hd_parse_count(argv[++i], &cnt) || cnt < 64 || cnt > (1u << 20))
                hd_die_msg("-apZ %s: expected 64 to 1m photons per page", argv[i]);
            o.page_photons = (uint32_t)cnt;
        } else if (!strcmp(a, "-n")) {
            need(argc, argv, i, 1);
            if (hd_parse_long(argv[++i], &lv) || lv < 0 || lv > 4096) hd_die_msg("-n %s: expected 0..4096", argv[i]);
            o.nthreads = (int)lv;
        } else if (!strcmp(a, "-t")) {
            need(argc, argv, i, 1);
            if (hd_parse_double(argv[++i], &dv) || dv < 0) hd_die_msg("-t %s: expected seconds >= 0", argv[i]);
            o.report_interval = dv;
        } else if (!strcmp(a, "-lr") || !strcmp(a, "-apm")) {
            need(argc, argv, i, 1);
            if (hd_parse_long(argv[++i], &lv)) hd_die_msg("%s %s: expected an integer", a, argv[i]);
            o.maxbounce = lv <= 0 ? 5000 : (int)(lv > 1000000 ? 1000000 : lv);
        } else if (!strcmp(a, "-ld")) {
            need(argc, argv, i, 1);
            if (hd_parse_double(argv[++i], &dv)) hd_die_msg("-ld %s: expected a distance", argv[i]);
            o.maxdist = dv;
        } else if (!strncmp(a, "-bv", 3)) {
            o.backvis = hd_opt_toggle_value(a + 3, o.backvis);
        } else if (!strncmp(a, "-fo", 3)) {
            force = hd_opt_toggle_value(a + 3, force);
        } else if (!strcmp(a, "-v")) {
            verbose = 1;
        } else if (!strcmp(a, "-e")) {
            need(argc, argv, i, 1);
            if (!freopen(argv[++i], "a", stderr)) hd_die_msg("-e %s: cannot open diagnostics file", argv[i]);
        } else if (!strcmp(a, "-apD") || !strcmp(a, "-apM") || !strcmp(a, "-dp") || !strcmp(a, "-ds")) {
            need(argc, argv, i, 1);
            hd_warn("%s %s ignored: heliodon emits each source in fixed batches until its stored-photon "
                    "budget is met and samples the port area by stratification", a, argv[i + 1]);
            i++;
        } else if (!strcmp(a, "-apg") || !strcmp(a, "-apc") || !strcmp(a, "-apv") || !strcmp(a, "-apd") ||
                   !strcmp(a, "-app")) {
            hd_die_msg("%s: only contribution photon maps (-apC) are supported", a);
        } else if (!strcmp(a, "-api") || !strcmp(a, "-apI") || !strcmp(a, "-aps") || !strcmp(a, "-apS") ||
                   !strcmp(a, "-ae") || !strcmp(a, "-aE") || !strcmp(a, "-ai") || !strcmp(a, "-aI") ||
                   !strncmp(a, "-ma", 3) || !strncmp(a, "-me", 3) || !strncmp(a, "-mg", 3)) {
            hd_die_msg("%s: not supported by heliodon's mkpmap (regions of interest, antimatter receivers, "
                       "storage include/exclude lists and participating media are not implemented)", a);
        } else if (!strcmp(a, "-w") || !strcmp(a, "-w-") || !strcmp(a, "-w+")) {
            hd_set_warnings(a[2] == '+' || (a[2] == 0 && !hd_warnings_enabled()));
        } else {
            fprintf(stderr, "mkpmap: unknown option %s\n%s", a, Usage);
            return 1;
        }
    }
    if (!out) { fprintf(stderr, "mkpmap: no contribution photon map (-apC file N)\n%s", Usage); return 1; }
    if (i >= argc) { fprintf(stderr, "mkpmap: missing scene (octree or .rad files)\n%s", Usage); return 1; }
    if (o.nports == 0) hd_die_msg("no photon port (-apo modifier): heliodon emits distant-source photons only through ports");
    if (!force && access(out, F_OK) == 0) hd_die_msg("%s: file exists (use -fo to overwrite)", out);

    hd_scene sc;
    hd_scene_init(&sc);
    if (hd_scene_load_files(&sc, argc - i, argv + i, NULL)) hd_die();
    hd_tscene *ts;
    if (hd_tscene_from_scene(&ts, &sc)) hd_die();

    hd_header h;
    hd_header_init(&h);
    if (hd_header_add_command(&h, argc, argv)) hd_die();
    if (o.nshards > 1) {
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
        if (hd_header_appendf(&h, "PMAPSHARD= %d %d", o.shard, o.nshards) ||
            hd_header_appendf(&h, "PMAPRUN= %llu %llu %08lx", (unsigned long long)o.nphotons,
                              (unsigned long long)o.seed, (unsigned long)crc))
            hd_die();
    }
    hd_pmap_build_stats st;
    if (hd_pmap_build(ts, &o, out, h.text, &st, NULL)) hd_die();
    if (verbose || o.report_interval > 0)
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
    return 0;
}

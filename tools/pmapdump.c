/* pmapdump — show a heliodon contribution photon map: header, statistics,
 * photons, checks, and density lookups at points (heliodon). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/common.h"
#include "heliodon/io.h"
#include "heliodon/pmap.h"
#include "heliodon/scene.h"
#include "heliodon/trace.h"

static const char *Usage =
    "usage: pmapdump [-c] [-s] [-p src] [-l k [-K flat|epan] [-am r] [-aC n] [-S scene]] map.pm\n"
    "  (default: header and statistics; -c check every page; -s per-source table;\n"
    "   -p print the photons of source src; -l k: read 'x y z nx ny nz' lines from stdin and\n"
    "   print the irradiance coefficient of every source (RGB triples) per line, k neighbours per source;\n"
    "   -S scene: direct light through glass by shadow rays instead of the direct photons)\n";

static int print_photon(void *ctx, const hd_photon *ph)
{
    (void)ctx;
    printf("%.6g %.6g %.6g\t%.4f %.4f %.4f\t%.4f %.4f %.4f\t%.5g %.5g %.5g\n", ph->p.x, ph->p.y, ph->p.z, ph->n.x,
           ph->n.y, ph->n.z, ph->dir.x, ph->dir.y, ph->dir.z, ph->w[0], ph->w[1], ph->w[2]);
    return 0;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int check = 0, table = 0;
    long psrc = -1;
    uint64_t k = 0, cache = 0;
    double maxr = 0;
    hd_pmap_kernel kern = HD_PMAP_KERNEL_FLAT;
    const char *scene = NULL;
    int i;
    for (i = 1; i < argc && argv[i][0] == '-'; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "-c")) check = 1;
        else if (!strcmp(a, "-s")) table = 1;
        else if (!strcmp(a, "-p") && i + 1 < argc) {
            if (hd_parse_long(argv[++i], &psrc) || psrc < 0) hd_die_msg("-p %s: expected a source index", argv[i]);
        } else if (!strcmp(a, "-l") && i + 1 < argc) {
            if (hd_parse_count(argv[++i], &k) || k < 2) hd_die_msg("-l %s: expected k >= 2", argv[i]);
        } else if (!strcmp(a, "-aC") && i + 1 < argc) {
            if (hd_parse_count(argv[++i], &cache)) hd_die_msg("-aC %s: expected a photon count", argv[i]);
        } else if (!strcmp(a, "-am") && i + 1 < argc) {
            if (hd_parse_double(argv[++i], &maxr) || maxr < 0) hd_die_msg("-am %s: expected a radius", argv[i]);
        } else if (!strcmp(a, "-S") && i + 1 < argc) {
            scene = argv[++i];
        } else if (!strcmp(a, "-K") && i + 1 < argc) {
            i++;
            if (!strcmp(argv[i], "flat")) kern = HD_PMAP_KERNEL_FLAT;
            else if (!strcmp(argv[i], "epan")) kern = HD_PMAP_KERNEL_EPAN;
            else hd_die_msg("-K %s: expected flat or epan", argv[i]);
        } else {
            fprintf(stderr, "pmapdump: bad option %s\n%s", a, Usage);
            return 1;
        }
    }
    if (i != argc - 1) { fprintf(stderr, "%s", Usage); return 1; }
    hd_pmap *m;
    if (hd_pmap_open(&m, argv[i], cache)) hd_die();
    const hd_pmap_info *I = hd_pmap_get_info(m);
    if (k) {
        hd_pmap_lookup_opts lo;
        hd_pmap_lookup_opts_init(&lo);
        lo.k = (uint32_t)k;
        lo.max_radius = maxr;
        lo.kernel = kern;
        hd_scene sc;
        hd_tscene *ts = NULL;
        if (scene) {
            hd_scene_init(&sc);
            char *sv[1] = {(char *)scene};
            if (hd_scene_load_files(&sc, 1, sv, NULL) || hd_tscene_from_scene(&ts, &sc)) hd_die();
            lo.direct_scene = ts;
        }
        hd_pmap_lookup *l;
        if (hd_pmap_lookup_create(m, &lo, &l)) hd_die();
        double v[6];
        unsigned long line = 0;
        char buf[1024];
        while (fgets(buf, sizeof buf, stdin)) {
            line++;
            if (sscanf(buf, "%lf %lf %lf %lf %lf %lf", v, v + 1, v + 2, v + 3, v + 4, v + 5) != 6)
                hd_die_msg("stdin: line %lu: expected x y z nx ny nz", line);
            hd_vec3 p = hd_v3(v[0], v[1], v[2]), n = hd_vnorm(hd_v3(v[3], v[4], v[5]));
            for (uint32_t s = 0; s < I->nsources; s++) {
                double e[3];
                if (hd_pmap_irradiance(l, s, p, n, e, NULL, NULL)) hd_die();
                printf("%s%.6e\t%.6e\t%.6e", s ? "\t" : "", e[0], e[1], e[2]);
            }
            printf("\n");
        }
        hd_pmap_lookup_free(l);
        if (ts) { hd_tscene_free(ts); hd_scene_free(&sc); }
        hd_pmap_close(m);
        return 0;
    }
    if (psrc >= 0) {
        if (hd_pmap_foreach(m, (uint32_t)psrc, print_photon, NULL)) hd_die();
        hd_pmap_close(m);
        return 0;
    }
    fputs(hd_pmap_header_text(m), stdout);
    uint64_t emitted = 0, active = 0, minst = UINT64_MAX, maxst = 0;
    for (uint32_t s = 0; s < I->nsources; s++) {
        const hd_pmap_source *S = hd_pmap_get_source(m, s);
        emitted += S->emitted;
        if (S->stored) {
            active++;
            if (S->stored < minst) minst = S->stored;
            if (S->stored > maxst) maxst = S->stored;
        }
    }
    printf("\nformat version      %u\n", I->version);
    printf("photons             %llu\n", (unsigned long long)I->nphotons);
    printf("emitted             %llu\n", (unsigned long long)emitted);
    printf("sources             %u (%llu with photons; stored per source %llu .. %llu)\n", I->nsources,
           (unsigned long long)active, (unsigned long long)(active ? minst : 0), (unsigned long long)maxst);
    printf("pages               %llu of up to %u photons\n", (unsigned long long)I->npages, I->page_photons);
    printf("Morton cube         origin %g %g %g size %g (cell %.3g)\n", I->org.x, I->org.y, I->org.z, I->size,
           I->size / 2097152.0);
    printf("file bytes          %llu (photon pages %llu = %.2f bytes per photon)\n",
           (unsigned long long)I->file_bytes, (unsigned long long)I->data_bytes,
           I->nphotons ? (double)I->data_bytes / (double)I->nphotons : 0.0);
    if (table) {
        printf("\n# src\tmodifier\temitted\tstored\tflux/photon\tpages\tdirection\n");
        for (uint32_t s = 0; s < I->nsources; s++) {
            const hd_pmap_source *S = hd_pmap_get_source(m, s);
            printf("%u\t%s\t%llu\t%llu\t%.6g\t%llu\t%.5f %.5f %.5f\n", s, S->modifier,
                   (unsigned long long)S->emitted, (unsigned long long)S->stored, S->flux,
                   (unsigned long long)S->npages, S->dir.x, S->dir.y, S->dir.z);
        }
    }
    if (check) {
        uint64_t bad = 0;
        if (hd_pmap_verify(m, &bad)) hd_die();
        printf("check               all %llu pages read, checksums and sizes correct\n",
               (unsigned long long)I->npages);
    }
    hd_pmap_close(m);
    return 0;
}

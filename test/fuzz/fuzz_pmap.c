/* Fuzz harness: heliodon contribution photon-map files (docs/design/
 * pmap.md): open (text header, binary header, source table, page index),
 * verify every page (inflate, decode, kd order), visit every photon, and
 * look up irradiance per source (single points, with direction bins, and
 * point groups) through the resident and the bounded page cache.
 *
 * Before the map is read, the harness recomputes what a mutated file
 * would get wrong at once — the file length in the binary header and the
 * CRC-32s of the pages, the page index, the source table and the binary
 * header — so that mutations reach the decoders behind the checksums.
 * The map is written to a memory file and opened through its path. */
#define _GNU_SOURCE
#include <stdio.h>
#include <sys/mman.h>
#include <unistd.h>

#include "fuzz.h"
#include "heliodon/pmap.h"
#include "pmap_fix.h"

static int bin_by_side(void *ctx, uint32_t src, hd_vec3 from)
{
    (void)ctx; (void)src;
    return from.z >= 0 ? 0 : 1;
}

static int count_photon(void *ctx, const hd_photon *ph)
{
    double *acc = ctx;
    *acc += ph->w[0] + ph->p.x + ph->n.z + ph->dir.y;
    return 0;
}

static void exercise(const char *path, uint64_t cache_photons)
{
    hd_pmap *m = NULL;
    if (hd_pmap_open(&m, path, cache_photons) != HD_OK) return;
    const hd_pmap_info *I = hd_pmap_get_info(m);
    double acc = 0;
    (void)hd_pmap_header_text(m);
    uint64_t bad = 0;
    if (hd_pmap_verify(m, &bad) == HD_OK) {
        uint32_t ns = I->nsources < 4 ? I->nsources : 4;
        for (uint32_t s = 0; s < ns; s++) {
            (void)hd_pmap_get_source(m, s);
            (void)hd_pmap_foreach(m, s, count_photon, &acc);
        }
        hd_pmap_lookup_opts lo;
        hd_pmap_lookup_opts_init(&lo);
        lo.k = 8;
        lo.kernel = I->nphotons & 1 ? HD_PMAP_KERNEL_EPAN : HD_PMAP_KERNEL_FLAT;
        hd_pmap_lookup *l = NULL;
        if (hd_pmap_lookup_create(m, &lo, &l) == HD_OK) {
            double sz = I->size;
            hd_vec3 pts[3] = {hd_vadd(I->org, hd_v3(sz / 2, sz / 2, sz / 100)),
                              hd_vadd(I->org, hd_v3(sz / 4, sz / 3, sz / 2)),
                              hd_vadd(I->org, hd_v3(sz * .9, sz * .1, 0))};
            for (uint32_t s = 0; s < ns; s++) {
                double out[9] = {0};
                (void)hd_pmap_irradiance(l, s, pts[0], hd_v3(0, 0, 1), out, NULL, NULL);
                (void)hd_pmap_irradiance(l, s, pts[1], hd_v3(1, 0, 0), out, bin_by_side, NULL);
                (void)hd_pmap_irradiance_group(l, s, pts, 3, hd_v3(0, 0, 1), out);
                acc += out[0] + out[3] + out[8];
            }
            acc += hd_pmap_lookup_radius(l, 1);
            hd_pmap_lookup_free(l);
        }
    }
    uint64_t reads, peak;
    hd_pmap_cache_stats(m, &reads, &peak);
    hd_pmap_close(m);
    volatile double sink = acc;
    (void)sink;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static int fd = -1;
    static char path[64];
    hd_fuzz_setup();
    if (size > (1 << 20)) return 0;
    if (fd < 0) {
        fd = memfd_create("fuzz.pm", 0);
        if (fd < 0) abort();
        snprintf(path, sizeof path, "/proc/self/fd/%d", fd);
    }
    uint8_t *b = malloc(size ? size : 1);
    if (!b) abort();
    memcpy(b, data, size);
    hd_fuzz_pmap_fix(b, size);
    if (ftruncate(fd, 0) != 0 || pwrite(fd, b, size, 0) != (ssize_t)size) abort();
    free(b);
    exercise(path, 0);   /* every page resident */
    exercise(path, 1);   /* the smallest page cache (16 pages) */
    return 0;
}

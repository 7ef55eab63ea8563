/* heliodon — contribution photon maps (mkpmap -apC, rcontrib -ap).
 *
 * Build side (hd_pmap_build): every distant light source of a trace scene
 * emits photons through the photon-port surfaces (stratified over the
 * port area, within the source's solid angle); photons are traced through
 * the scene (glass, specular and diffuse reflection/transmission with
 * Russian roulette) and stored at diffuse hits after at least one
 * scattering or transmission event, as Radiance stores contribution
 * photons (so direct sun through glass becomes a stored photon).  Each
 * source is traced in fixed batches until its own stored count reaches
 * its share of the target: every source gets the same number of stored
 * photons (within one batch).  Random streams are keyed by (seed, source,
 * batch), so the map does not depend on the thread count.
 *
 * Storage: heliodon's own portable file (docs/design/pmap.md): a Radiance
 * text header, then a little-endian binary header, a source table and a
 * page index, each with a CRC-32, then zlib-compressed pages of photons
 * sorted by (source, direct flag, Morton code).  Pages never mix sources
 * (or direct and indirect photons), so a per-source nearest-neighbour
 * search only reads that source's pages.
 * Built by an external merge sort under a memory budget.
 *
 * Gather side (hd_pmap_open + hd_pmap_lookup): per-source k nearest
 * photons with compatible normals, through an LRU page cache of bounded
 * size; the out-of-core and fully loaded gathers give identical numbers
 * (the cache size only changes what is read when). */
#ifndef HELIODON_PMAP_H
#define HELIODON_PMAP_H

#include <stdint.h>
#include "common.h"
#include "vec.h"

struct hd_tscene;

#define HD_PMAP_MAXPORTS 64

/* Port orientation: '+' emit along the port's front normal, '-' against
 * it, '0' both ways. */
typedef struct hd_pmap_port_spec {
    const char *modifier;
    char orient;
} hd_pmap_port_spec;

typedef struct hd_pmap_build_opts {
    uint64_t nphotons;        /* target stored photons (all sources) */
    uint64_t seed;            /* -apr */
    int nthreads;             /* -n */
    int nports;
    hd_pmap_port_spec ports[HD_PMAP_MAXPORTS];
    int maxbounce;            /* -lr (<= 0: 5000) */
    double maxdist;           /* -ld (<= 0: unlimited) */
    int backvis;              /* -bv */
    uint64_t mem_budget;      /* bytes of photons held before spilling a sorted run */
    uint32_t page_photons;    /* photons per page (0: 2048) */
    const char *tmpdir;       /* for run files (NULL: next to the output) */
    double report_interval;   /* -t seconds, 0 = none */
    uint32_t batch;           /* photons emitted per batch (0: from the target) */
    /* Emission shard k of n (nshards <= 1: everything): this run traces the
     * sources with index % n == k, with the budgets of the whole run; the
     * shard maps merged by hd_pmap_merge equal the single-run map. */
    int shard, nshards;
} hd_pmap_build_opts;

void hd_pmap_build_opts_init(hd_pmap_build_opts *o);

/* Per-source energy bookkeeping (flux for unit source radiance, i.e. the
 * coefficient of the source's radiance; sums over emitted photons). */
typedef struct hd_pmap_energy {
    double emitted;           /* flux leaving the ports */
    double absorbed;          /* absorbed at hits (all surfaces) */
    double escaped;           /* left the scene */
    double stored;            /* flux of the stored photons (incident at their hits) */
    double lost;              /* terminated by -lr / -ld */
} hd_pmap_energy;

typedef struct hd_pmap_build_stats {
    uint64_t emitted, stored;
    uint64_t file_bytes;
    double seconds_trace, seconds_write;
    int nsources, nactive;    /* sources, and sources that stored photons */
    int nlive;                /* sources that can emit (the asked count is shared among them) */
    int nruns;                /* sorted runs spilled (external sort) */
} hd_pmap_build_stats;

/* Trace and write the map to path (written through a temporary name +
 * rename).  header_lines: extra Radiance header text (command line etc.,
 * lines ending in '\n'; may be NULL).  energy (may be NULL) receives
 * nsources entries (hd_pmap_count_sources). */
hd_status hd_pmap_build(const struct hd_tscene *ts, const hd_pmap_build_opts *o,
                        const char *path, const char *header_lines,
                        hd_pmap_build_stats *stats, hd_pmap_energy **energy);

/* Number of distant light sources (photon emitters) in a trace scene. */
int hd_pmap_count_sources(const struct hd_tscene *ts);

/* ---- reading ---- */
typedef struct hd_pmap hd_pmap;

typedef struct hd_pmap_source {
    char modifier[128];       /* light modifier name */
    hd_vec3 dir;              /* direction towards the source */
    double half_angle;        /* radians */
    double radiance[3];       /* light material radiance */
    uint64_t emitted, stored;
    double flux;              /* flux per emitted photon for unit radiance */
    uint64_t first_page;
    uint64_t npages;
} hd_pmap_source;

typedef struct hd_pmap_info {
    uint32_t version;
    uint64_t nphotons, npages;
    uint32_t nsources, page_photons;
    hd_vec3 org; double size; /* Morton cube */
    uint64_t file_bytes, data_bytes;
} hd_pmap_info;

/* Open a map; cache_photons = photons held in the decoded page cache
 * (0: the whole map).  Checks the header, source table and index CRCs;
 * page CRCs are checked when a page is read. */
hd_status hd_pmap_open(hd_pmap **out, const char *path, uint64_t cache_photons);
void hd_pmap_close(hd_pmap *m);
const hd_pmap_info *hd_pmap_get_info(const hd_pmap *m);
const hd_pmap_source *hd_pmap_get_source(const hd_pmap *m, uint32_t i);
/* Text header of the file (NUL-terminated). */
const char *hd_pmap_header_text(const hd_pmap *m);
/* Read and verify every page (pmapdump -c). */
hd_status hd_pmap_verify(hd_pmap *m, uint64_t *bad_pages);
/* Peak decoded-cache bytes and page reads so far. */
void hd_pmap_cache_stats(const hd_pmap *m, uint64_t *page_reads, uint64_t *cache_bytes_peak);
/* Decoded pages evicted from the cache so far (0 while everything the
 * lookups asked for stayed decoded). */
uint64_t hd_pmap_cache_evictions(const hd_pmap *m);

/* A decoded photon. */
typedef struct hd_photon {
    hd_vec3 p, n;             /* position, surface normal (front side photon arrived on) */
    hd_vec3 dir;              /* direction of travel of the incident photon */
    double w[3];              /* flux = source flux × w */
    uint32_t src;
    int direct;               /* first diffuse hit after only glass transmissions */
} hd_photon;

/* Visit every photon of a source in file order (pmapdump -p, tests). */
typedef int (*hd_photon_fn)(void *ctx, const hd_photon *ph);
hd_status hd_pmap_foreach(hd_pmap *m, uint32_t src, hd_photon_fn fn, void *ctx);

/* ---- density estimates ---- */
typedef enum hd_pmap_kernel {
    HD_PMAP_KERNEL_FLAT = 0,  /* sum of k-1 nearest / (pi r_k^2) */
    HD_PMAP_KERNEL_EPAN       /* Epanechnikov (2/pi r^2)(1 - d^2/r^2) weights */
} hd_pmap_kernel;

typedef struct hd_pmap_lookup_opts {
    uint32_t k;               /* neighbours per source */
    double max_radius;        /* <= 0: unlimited */
    double normal_tol;        /* minimum photon-normal · lookup-normal (default 0.9) */
    hd_pmap_kernel kernel;
    /* Non-NULL: photons flagged direct (first diffuse hit after only glass
     * transmissions from the port) are left out of the density estimate and
     * the direct irradiance is computed exactly by a shadow ray through the
     * glass of this scene instead (heliodon's default in rcontrib -ap and
     * pmapdump -l with a scene; Radiance estimates it from the photons). */
    const struct hd_tscene *direct_scene;
} hd_pmap_lookup_opts;

void hd_pmap_lookup_opts_init(hd_pmap_lookup_opts *o);

/* Binning of photons within a source by incident direction: bin function
 * called with the direction towards where the photon came from (-travel)
 * and the source index; returns the bin in [0, nbins) or < 0 to drop. */
typedef int (*hd_pmap_binfn)(void *ctx, uint32_t src, hd_vec3 from_dir);

/* Per-thread lookup scratch. */
typedef struct hd_pmap_lookup hd_pmap_lookup;
hd_status hd_pmap_lookup_create(hd_pmap *m, const hd_pmap_lookup_opts *o, hd_pmap_lookup **out);
void hd_pmap_lookup_free(hd_pmap_lookup *l);
/* Mean k-th neighbour distance of this lookup's full lookups since the
 * last reset (0 if none); reset != 0 starts a new tally. */
double hd_pmap_lookup_radius(hd_pmap_lookup *l, int reset);
/* Points of this lookup's group lookups whose k-th-neighbour ball left
 * the collected candidates, so that they were searched alone (statistics,
 * tests). */
uint64_t hd_pmap_lookup_misses(const hd_pmap_lookup *l);

/* Irradiance at point p with normal n from source src (unit source
 * radiance, i.e. the irradiance coefficient), RGB into out[3]; with a bin
 * function, adds into out[3*bin..] instead (out has 3*nbins entries,
 * not cleared).  Without one, out is set. */
hd_status hd_pmap_irradiance(hd_pmap_lookup *l, uint32_t src, hd_vec3 p, hd_vec3 n,
                             double *out, hd_pmap_binfn binfn, void *binctx);

/* Irradiance of source src at np points that share the normal n (no
 * bins): out[3i..3i+2] is set to exactly what hd_pmap_irradiance(l, src,
 * p[i], n, out + 3i, NULL, NULL) gives, but the points' neighbours come
 * from one traversal of the map (coherent points: pixels of one surface). */
hd_status hd_pmap_irradiance_group(hd_pmap_lookup *l, uint32_t src, const hd_vec3 *p, size_t np, hd_vec3 n,
                                   double *out);

/* Kernel of the group lookups' per-point selection: 0 portable C, 1 AVX2,
 * 2 AVX-512F (the best the CPU has by default).  All levels give identical
 * results; level < 0 or above the CPU's best selects the best.  Returns
 * the level in use.  Set it before lookups start (tests, benchmarks). */
int hd_pmap_set_kernel(int level);

/* Final gather (-ab >= 1): irradiance at p (normal n) from nrays
 * cosine-distributed rays traced in ts; at each diffuse hit the photon
 * irradiance times the surface's diffuse reflectance; rays through glass
 * are followed.  Direct light from the sources through glass and openings
 * is added by shadow rays.  out[3] is set for source src. */
struct hd_rng;
hd_status hd_pmap_final_gather(hd_pmap_lookup *l, const struct hd_tscene *ts, uint32_t src,
                               hd_vec3 p, hd_vec3 n, int nrays, struct hd_rng *rng, double out[3]);

/* Merge shard maps (same scene, target, seed; shards 0..n-1 of n) into one
 * map whose binary part is identical to the single-run map. */
hd_status hd_pmap_merge(const char *const *inputs, int n, const char *path, const char *header_lines);

/* ---- encodings (exposed for tests) ---- */
uint64_t hd_pmap_morton(uint32_t x, uint32_t y, uint32_t z);
void hd_pmap_unmorton(uint64_t k, uint32_t *x, uint32_t *y, uint32_t *z);
uint16_t hd_pmap_oct_encode(hd_vec3 v);
hd_vec3 hd_pmap_oct_decode(uint16_t c);
uint32_t hd_pmap_crc32(uint32_t crc, const void *data, size_t n);

#endif

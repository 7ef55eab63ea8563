/* heliodon — private definitions shared by the photon-map sources. */
#ifndef HELIODON_PMAP_INTERNAL_H
#define HELIODON_PMAP_INTERNAL_H

#include <math.h>
#include <stdio.h>
#include <stdatomic.h>
#include <pthread.h>
#include <string.h>
#include "heliodon/pmap.h"

#define PM_MAGIC "HDPMAPC\0"
#define PM_VERSION 1u
#define PM_BINHDR 128u
#define PM_IDXREC 56u
#define PM_LEAF 64u           /* photons per leaf of a decoded page's kd-tree (8 -> 64: 256^2 group gather
                               * -7 % CPU, fewer levels to build and traverse, 5.5 -> 0.7 node bytes per
                               * photon; point lookups unchanged; results identical whatever the leaf) */
#define PM_MAXNAME 127u

/* In-memory photon record of the build (sorted by src, key): 20 bytes, the
 * 63-bit Morton code of the quantised position in two 32-bit halves so that
 * the record needs no 8-byte alignment (24 bytes with a uint64_t). */
typedef struct pm_rec {
    uint32_t klo, khi;        /* Morton code: pm_rec_key / pm_rec_setkey */
    uint32_t rgbe;            /* relative weight w (RGBE) */
    uint16_t src, nrm, dir, flags; /* flags: PM_F_DIRECT */
} pm_rec;
static inline uint64_t pm_rec_key(const pm_rec *r) { return (uint64_t)r->khi << 32 | r->klo; }
static inline void pm_rec_setkey(pm_rec *r, uint64_t k) { r->klo = (uint32_t)k; r->khi = (uint32_t)(k >> 32); }

#define PM_F_DIRECT 1u        /* first diffuse hit after only glass transmissions from the port */
#define PM_F_CAUSTIC 2u       /* first diffuse hit after only glass, specular and BSDF events from the
                               * port, at least one of them not a glass transmission (per photon only;
                               * maps built before this bit existed have it clear) */

typedef struct pm_page_ent {
    uint64_t offset;
    uint32_t csize, usize, count, src;
    float lo[3], hi[3];
    uint32_t crc;
    uint32_t flags;           /* PM_F_DIRECT: every photon of the page is direct */
} pm_page_ent;

/* Implicit balanced tree over index ranges: the root covers [0, n); a node
 * [b, e) with more than `leaf` items splits at b + leaf * ceil(nleaves / 2);
 * children of node i are 2i+1 and 2i+2.  pm_tree_nodes(n, leaf) slots. */
static inline uint32_t pm_tree_split(uint32_t b, uint32_t e, uint32_t leaf)
{
    uint32_t nl = (e - b + leaf - 1) / leaf;
    uint32_t m = b + leaf * ((nl + 1) / 2);
    return m < e ? m : e;
}
size_t pm_tree_nodes(uint64_t n, uint32_t leaf);

typedef struct pm_box { float lo[3], hi[3]; } pm_box;

/* Tree node: bounding box and normal cone (axis, cos and sin of the half
 * angle; cos = -1: any normal). */
typedef struct pm_node {
    float lo[3], hi[3];
    float ax[3], cmin, smin;
} pm_node;

/* Decoded page: photons reordered into a kd-tree (median splits on the
 * longest box axis, leaves of PM_LEAF photons), node boxes and normal cones. */
typedef struct pm_page {
    uint32_t count, nnodes;
    void *blk;                /* the arrays below in one block (NULL: they live in the map's arena) */
    float *pos;               /* 3 per photon */
    uint32_t *wcode;          /* weight, RGBE as stored (pm_rgbe_decode) */
    uint16_t *ncode;          /* surface normal, octahedral code as stored (pm_nrm_decode) */
    uint16_t *dir;
    uint8_t *flags;
    pm_node *node;            /* nnodes, implicit layout (pm_tree_split) */
} pm_page;
/* hd_pmap_oct_encode, inline where photons are stored (pmap_build.c: its
 * division overlaps other work there).  lround clamped to [0, 254] without
 * the libm call (x - trunc(x) is exact) and without branches (NaN -> 0). */
static inline int pm_oct_round(double x)
{
    x = x > 0 ? x : 0;
    x = x < 254 ? x : 254;
    int r = (int)x;
    return r + (x - r >= 0.5);
}
static inline uint16_t pm_oct_encode(hd_vec3 v)
{
    double l = fabs(v.x) + fabs(v.y) + fabs(v.z);
    if (l <= 0) return 0x7F7F;
    /* scaled to [-127, 127] with one division; the lower hemisphere folded
     * without branches (the sign of z is unpredictable for directions):
     * copysign(t, p + 0.0) = t * (p < 0 ? -1 : 1), -0 folding like +0 */
    double s = 127.0 / l, px = v.x * s, py = v.y * s;
    double tx = copysign(127.0 - fabs(py), px + 0.0), ty = copysign(127.0 - fabs(px), py + 0.0);
    uint64_t m = -(uint64_t)(v.z < 0), a, b;   /* bitwise select: no branch */
    memcpy(&a, &px, 8); memcpy(&b, &tx, 8); a = (a & ~m) | (b & m); memcpy(&px, &a, 8);
    memcpy(&a, &py, 8); memcpy(&b, &ty, 8); a = (a & ~m) | (b & m); memcpy(&py, &a, 8);
    int ix = pm_oct_round(px + 127.0), iy = pm_oct_round(py + 127.0);
    return (uint16_t)(ix | iy << 8);
}

/* Decoded pages keep a photon's normal and weight as their codes (21
 * instead of 39 bytes per photon: less memory to fault in and to read);
 * the lookups decode them where they need the values, always through the
 * same functions, so every test sees the same floats. */
static inline void pm_nrm_decode(uint16_t code, float nv[3])
{
    hd_vec3 v = hd_pmap_oct_decode(code);
    nv[0] = (float)v.x;
    nv[1] = (float)v.y;
    nv[2] = (float)v.z;
}

typedef struct pm_cache_ent {
    uint64_t page;            /* UINT64_MAX = empty */
    pm_page *data;
    int pins;
    uint64_t stamp;
} pm_cache_ent;

struct hd_pmap {
    char *path;
    int fd;
    uint64_t base;            /* file offset of the binary header (all offsets are relative to it) */
    char *header_text;
    hd_pmap_info info;
    hd_pmap_source *src;
    pm_page_ent *pages;
    /* per source: page trees over its indirect pages [first, first + nind)
     * and its direct pages [first + nind, first + npages) */
    uint64_t *src_nind;
    size_t *src_tree;         /* node offsets into ptree: 2 per source (indirect, direct) */
    pm_box *ptree;
    /* cache */
    pthread_mutex_t lock;
    pm_cache_ent *cache;
    size_t ncache, capcache;  /* entries in use, nominal capacity (pages) */
    size_t nslots;            /* capcache + room for pinned overflow */
    int64_t *slot_of;         /* page -> slot or -1 */
    uint64_t clock, page_reads, evictions, bytes_now, bytes_peak;
    /* resident mode (the cache holds every page: nothing is ever evicted):
     * decoded pages are published in res[] and read without the lock; their
     * memory comes from an arena of prefaulted chunks, freed at close */
    int resident;
    _Atomic(pm_page *) *res;
    unsigned char **chunk;
    size_t nchunk, capchunk;
    unsigned char *acur;
    size_t aleft;
    size_t aneed;             /* arena bytes of the pages not yet decoded (chunk size for small maps) */
    struct pm_scratch **scr;  /* decode scratch buffers not in use */
    size_t nscr;
};

/* encodings */
void pm_rgbe_encode(const double w[3], uint32_t *out);
/* RGBE weight code -> floats (inline: decoded pages keep the codes) */
static inline void pm_rgbe_decode(uint32_t v, float w[3])
{
    unsigned e = v >> 24;
    if (!e) { w[0] = w[1] = w[2] = 0; return; }
    /* exact for the common w = 1 (128,128,128,129) */
    uint64_t bits = (uint64_t)((int)e - (128 + 8) + 1023) << 52;   /* 2^(e-136), exact */
    double f;
    memcpy(&f, &bits, sizeof f);
    w[0] = (float)((v & 0xFF) * f);
    w[1] = (float)(((v >> 8) & 0xFF) * f);
    w[2] = (float)(((v >> 16) & 0xFF) * f);
}

double pm_quant_scale(void);  /* 2^21 */

/* page coding: records -> raw bytes (caller frees), and raw -> page */
/* Raw page bytes of n records into b (room for PM_RAWMAX(n) bytes); returns the length,
 * *keylen (if not NULL) the length of the leading position-code part. */
#define PM_RAWMAX(n) ((size_t)(n) * (10 + 9))
size_t pm_page_encode_into(const pm_rec *r, uint32_t n, unsigned char *b, size_t *keylen);
/* Position (floats) of a quantised Morton key in a map of origin org and extent size. */
void pm_key_to_pos(uint64_t key, hd_vec3 org, double size, float p[3]);
hd_status pm_page_decode(const unsigned char *raw, size_t len, uint32_t count,
                         hd_vec3 org, double size, pm_page *pg, const char *where);
void pm_page_free(pm_page *pg);
/* Memory for n photons' decoded arrays (pm_page_layout), and the layout. */
size_t pm_page_block_bytes(uint32_t n);
void pm_page_layout(pm_page *pg, uint32_t n, void *blk);
/* Decode into pg whose arrays are already laid out (pm_page_layout);
 * scratch: grown as needed, kept by the caller (may be NULL on entry). */
hd_status pm_page_decode_into(const unsigned char *raw, size_t len, uint32_t n, hd_vec3 org, double size,
                              pm_page *pg, const char *where, void **scratch, size_t *scratch_cap);
/* Fault in fresh anonymous memory [p, p + n) at once (one call instead of a
 * page fault per 4 KB; a no-op where the kernel cannot). */
void pm_prefault(void *p, size_t n);

/* little-endian helpers */
static inline void pm_put32(unsigned char *b, uint32_t v)
{
    b[0] = (unsigned char)v; b[1] = (unsigned char)(v >> 8);
    b[2] = (unsigned char)(v >> 16); b[3] = (unsigned char)(v >> 24);
}
static inline void pm_put64(unsigned char *b, uint64_t v)
{
    pm_put32(b, (uint32_t)v);
    pm_put32(b + 4, (uint32_t)(v >> 32));
}
static inline uint32_t pm_get32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}
static inline uint64_t pm_get64(const unsigned char *b)
{
    return (uint64_t)pm_get32(b) | (uint64_t)pm_get32(b + 4) << 32;
}
void pm_putf64(unsigned char *b, double v);
double pm_getf64(const unsigned char *b);
void pm_putf32(unsigned char *b, float v);
float pm_getf32(const unsigned char *b);

/* Writer: sorted records in, file out. */
typedef struct pm_writer pm_writer;
hd_status pm_writer_open(pm_writer **out, const char *path, const char *header_lines,
                         uint32_t nsources, uint32_t page_photons, hd_vec3 org, double size,
                         int nthreads);
hd_status pm_writer_add(pm_writer *w, const pm_rec *r, size_t n);   /* sorted, in order */
/* Append an already compressed page (merging shards); e->offset is ignored. */
hd_status pm_writer_add_raw(pm_writer *w, const pm_page_ent *e, const unsigned char *comp);
/* sources: table to write (first_page/npages/stored filled in by the writer) */
hd_status pm_writer_close(pm_writer *w, hd_pmap_source *sources, uint64_t *file_bytes);
void pm_writer_abort(pm_writer *w);

/* cache access */
/* n bytes at file offset off of map m (what: named in the message) */
hd_status pm_pread_all(hd_pmap *m, void *buf, size_t n, uint64_t off, const char *what);
hd_status pm_page_get(hd_pmap *m, uint64_t page, const pm_page **out);
void pm_page_release(hd_pmap *m, uint64_t page);

#endif

/* heliodon — photon-map file: encodings, page coding, writer, reader and
 * the LRU page cache.  Layout documented in docs/design/pmap.md. */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/mman.h>
#include <zlib.h>

#include "heliodon/io.h"
#include "heliodon/parallel.h"
#include "pmap_internal.h"

#define QBITS 21
#define QMAX ((1u << QBITS) - 1u)

double pm_quant_scale(void) { return (double)(1u << QBITS); }

/* ---- CRC-32 (IEEE, reflected) ---- */
/* zlib's crc32 is this CRC (same polynomial, pre/post inversion and
 * chaining) computed several bytes at a time: ~4x faster than the byte-wise
 * table loop it replaces (the writer checksums ~60 MB per 10 M photons). */
uint32_t hd_pmap_crc32(uint32_t crc, const void *data, size_t n)
{
    const unsigned char *p = data;
    uLong c = crc;
    while (n > 0) {
        uInt k = n > (size_t)1 << 30 ? (uInt)1 << 30 : (uInt)n;
        c = crc32(c, p, k);
        p += k;
        n -= k;
    }
    return (uint32_t)c;
}

/* ---- Morton ---- */
static uint64_t spread3(uint32_t v)
{
    uint64_t x = v & 0x1FFFFF;
    x = (x | x << 32) & 0x1F00000000FFFFULL;
    x = (x | x << 16) & 0x1F0000FF0000FFULL;
    x = (x | x << 8) & 0x100F00F00F00F00FULL;
    x = (x | x << 4) & 0x10C30C30C30C30C3ULL;
    x = (x | x << 2) & 0x1249249249249249ULL;
    return x;
}
static uint32_t compact3(uint64_t x)
{
    x &= 0x1249249249249249ULL;
    x = (x ^ (x >> 2)) & 0x10C30C30C30C30C3ULL;
    x = (x ^ (x >> 4)) & 0x100F00F00F00F00FULL;
    x = (x ^ (x >> 8)) & 0x1F0000FF0000FFULL;
    x = (x ^ (x >> 16)) & 0x1F00000000FFFFULL;
    x = (x ^ (x >> 32)) & 0x1FFFFF;
    return (uint32_t)x;
}
uint64_t hd_pmap_morton(uint32_t x, uint32_t y, uint32_t z)
{
    return spread3(x) | spread3(y) << 1 | spread3(z) << 2;
}
void hd_pmap_unmorton(uint64_t k, uint32_t *x, uint32_t *y, uint32_t *z)
{
    *x = compact3(k);
    *y = compact3(k >> 1);
    *z = compact3(k >> 2);
}

/* ---- octahedral unit vectors in 16 bits (8 + 8) ---- */
static double signnz(double v) { return v < 0 ? -1.0 : 1.0; }
/* lround(x) clamped to [0, 254], without the libm call (x - trunc(x) is
 * exact) and without branches (NaN -> 0) */
static inline int oct_round(double x)
{
    x = x > 0 ? x : 0;
    x = x < 254 ? x : 254;
    int r = (int)x;
    return r + (x - r >= 0.5);
}
uint16_t hd_pmap_oct_encode(hd_vec3 v)
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
    int ix = oct_round(px + 127.0), iy = oct_round(py + 127.0);
    return (uint16_t)(ix | iy << 8);
}
hd_vec3 hd_pmap_oct_decode(uint16_t c)
{
    double px = (c & 0xFF) / 254.0 * 2 - 1, py = (c >> 8) / 254.0 * 2 - 1;
    double pz = 1 - fabs(px) - fabs(py);
    if (pz < 0) {
        double tx = (1 - fabs(py)) * signnz(px), ty = (1 - fabs(px)) * signnz(py);
        px = tx; py = ty;
    }
    return hd_vnorm(hd_v3(px, py, pz));
}

/* ---- RGBE weights ---- */
void pm_rgbe_encode(const double w[3], uint32_t *out)
{
    /* the common weight of grey scenes, w = 1: (128, 128, 128, 129) as below, without frexp */
    if (w[0] == 1 && w[1] == 1 && w[2] == 1) { *out = 128u | 128u << 8 | 128u << 16 | 129u << 24; return; }
    double m = w[0] > w[1] ? w[0] : w[1];
    if (w[2] > m) m = w[2];
    if (!(m > 1e-32)) { *out = 0; return; }
    int e;
    double f = frexp(m, &e) * 256.0 / m;
    unsigned r = (unsigned)(w[0] > 0 ? w[0] * f : 0), g = (unsigned)(w[1] > 0 ? w[1] * f : 0),
             b = (unsigned)(w[2] > 0 ? w[2] * f : 0);
    if (r > 255) r = 255;
    if (g > 255) g = 255;
    if (b > 255) b = 255;
    if (e + 128 < 0 || e + 128 > 255) { *out = 0; return; }
    *out = r | g << 8 | b << 16 | (uint32_t)(e + 128) << 24;
}

void pm_putf64(unsigned char *b, double v) { uint64_t u; memcpy(&u, &v, 8); pm_put64(b, u); }
double pm_getf64(const unsigned char *b) { uint64_t u = pm_get64(b); double v; memcpy(&v, &u, 8); return v; }
void pm_putf32(unsigned char *b, float v) { uint32_t u; memcpy(&u, &v, 4); pm_put32(b, u); }
float pm_getf32(const unsigned char *b) { uint32_t u = pm_get32(b); float v; memcpy(&v, &u, 4); return v; }

static void key_to_pos(uint64_t key, hd_vec3 org, double size, float p[3])
{
    uint32_t x, y, z;
    hd_pmap_unmorton(key, &x, &y, &z);
    double s = size / pm_quant_scale();
    p[0] = (float)(org.x + (x + 0.5) * s);
    p[1] = (float)(org.y + (y + 0.5) * s);
    p[2] = (float)(org.z + (z + 0.5) * s);
}

/* ---- page coding ---- */
/* Raw page bytes of n records into b (room for PM_RAWMAX(n) bytes); returns the length,
 * *keylen (if not NULL) the length of the leading position-code part. */
#define PM_RAWMAX(n) ((size_t)(n) * (10 + 9))
static size_t page_encode_into(const pm_rec *r, uint32_t n, unsigned char *b, size_t *keylen)
{
    size_t o = 0;
    uint64_t prev = 0;
    for (uint32_t i = 0; i < n; i++) {
        uint64_t k = pm_rec_key(&r[i]), d = k - prev;   /* sorted: non-negative */
        prev = k;
        while (d >= 0x80) { b[o++] = (unsigned char)(d | 0x80); d >>= 7; }
        b[o++] = (unsigned char)d;
    }
    unsigned char *nl = b + o, *nh = nl + n, *dl = nh + n, *dh = dl + n, *c0 = dh + n, *c1 = c0 + n, *c2 = c1 + n,
                  *c3 = c2 + n, *fl = c3 + n;
    for (uint32_t i = 0; i < n; i++) {
        const pm_rec *q = &r[i];
        nl[i] = (unsigned char)q->nrm;
        nh[i] = (unsigned char)(q->nrm >> 8);
        dl[i] = (unsigned char)q->dir;
        dh[i] = (unsigned char)(q->dir >> 8);
        c0[i] = (unsigned char)q->rgbe;
        c1[i] = (unsigned char)(q->rgbe >> 8);
        c2[i] = (unsigned char)(q->rgbe >> 16);
        c3[i] = (unsigned char)(q->rgbe >> 24);
        fl[i] = (unsigned char)q->flags;
    }
    if (keylen) *keylen = o;
    return o + (size_t)n * 9;
}

hd_status pm_page_encode(const pm_rec *r, uint32_t n, unsigned char **out, size_t *len)
{
    unsigned char *b = hd_malloc(n ? PM_RAWMAX(n) : 1);
    if (!b) return HD_ERR_NOMEM;
    *out = b;
    *len = page_encode_into(r, n, b, NULL);
    return HD_OK;
}

void pm_page_free(pm_page *pg)
{
    if (!pg) return;
    free(pg->blk);
    memset(pg, 0, sizeof *pg);
}

/* One block per decoded page: positions (floats), weight codes, nodes,
 * normal codes, direction codes, flags (pm_page_layout). */
size_t pm_page_block_bytes(uint32_t n)
{
    size_t nn = pm_tree_nodes(n, PM_LEAF);
    size_t b = (size_t)n * (3 * sizeof(float) + sizeof(uint32_t)) + nn * sizeof(pm_node) +
               (size_t)n * (2 * sizeof(uint16_t) + 1);
    return (b + 63) & ~(size_t)63;
}

void pm_page_layout(pm_page *pg, uint32_t n, void *blk)
{
    memset(pg, 0, sizeof *pg);
    pg->count = n;
    pg->nnodes = (uint32_t)pm_tree_nodes(n, PM_LEAF);
    pg->pos = blk;
    pg->wcode = (uint32_t *)(void *)(pg->pos + 3 * (size_t)n);
    pg->node = (pm_node *)(void *)(pg->wcode + n);
    pg->ncode = (uint16_t *)(void *)(pg->node + pg->nnodes);
    pg->dir = pg->ncode + n;
    pg->flags = (uint8_t *)(pg->dir + n);
}

void pm_prefault(void *p, size_t n)
{
#if defined(__linux__)
#ifndef MADV_POPULATE_WRITE
#define MADV_POPULATE_WRITE 23
#endif
    long ps = sysconf(_SC_PAGESIZE);
    if (ps <= 0) return;
    uintptr_t a = ((uintptr_t)p + (uintptr_t)ps - 1) & ~((uintptr_t)ps - 1), e = ((uintptr_t)p + n) & ~((uintptr_t)ps - 1);
    if (e > a) (void)madvise((void *)a, e - a, MADV_POPULATE_WRITE);
#else
    (void)p; (void)n;
#endif
}

size_t pm_tree_nodes(uint64_t n, uint32_t leaf)
{
    uint64_t nl = (n + leaf - 1) / leaf, s = 1;
    while (s < nl) s <<= 1;   /* leaves of a complete tree of the same depth */
    return (size_t)(2 * s - 1);
}

/* Photon position with its original index, for the kd build. */
typedef struct kp { float p[3]; uint32_t i; } kp;

/* kd-build keys: the coordinate on the split axis as order-preserving bits
 * (high 32) and the photon's index (low 32), so keys are distinct and one
 * integer comparison orders them (ties of the coordinate by index). */
static inline uint64_t kd_key(const kp *t, uint32_t i, int ax)
{
    uint32_t u;
    memcpy(&u, &t[i].p[ax], sizeof u);
    u ^= (uint32_t)(-(int32_t)(u >> 31)) | 0x80000000u;
    return (uint64_t)u << 32 | i;
}

/* Partial sort of distinct keys v[b, e) so that position m holds the key of
 * rank m - b, smaller ones before it: quickselect, median-of-three pivot,
 * branch-free partition (the comparisons of a kd build are unpredictable). */
static void select_nth(uint64_t *v, uint32_t b, uint32_t e, uint32_t m)
{
    while (e - b > 16) {
        uint64_t x = v[b], y = v[b + (e - b) / 2], z = v[e - 1];
        uint64_t lo = x < y ? x : y, hi = x < y ? y : x;
        uint64_t piv = z < lo ? lo : z > hi ? hi : z;   /* median of three: one key below, one above */
        uint32_t s = b;
        for (uint32_t i = b; i < e; i++) {
            uint64_t t = v[i];
            uint32_t c = t < piv;
            v[i] = v[s];
            v[s] = t;
            s += c;
        }
        /* [b, s) < piv <= [s, e), both non-empty */
        if (m < s) e = s;
        else b = s;
    }
    /* at most 16 left: sort them by rank (counting comparisons, no branches) */
    uint64_t tmp[16];
    uint32_t n = e - b;
    for (uint32_t i = 0; i < n; i++) {
        uint64_t t = v[b + i];
        uint32_t r = 0;
        for (uint32_t j = 0; j < n; j++) r += v[b + j] < t;
        tmp[r] = t;
    }
    memcpy(v + b, tmp, n * sizeof *tmp);
}

static void box_of(const float *pos, const uint32_t *idx, uint32_t b, uint32_t e, float lo[3], float hi[3])
{
    lo[0] = lo[1] = lo[2] = 3e38f;
    hi[0] = hi[1] = hi[2] = -3e38f;
    for (uint32_t i = b; i < e; i++) {
        const float *q = pos + 3 * (idx ? idx[i] : i);
        for (int k = 0; k < 3; k++) {
            if (q[k] < lo[k]) lo[k] = q[k];
            if (q[k] > hi[k]) hi[k] = q[k];
        }
    }
}

/* Split axis from a box bounding the range: the root's true box, below it
 * the parent's box cut at the median (conservative; the exact node boxes
 * are computed bottom-up by kd_nodes). */
static void kd_split(const kp *t, uint64_t *v, uint32_t b, uint32_t e, const float lo[3], const float hi[3])
{
    if (e - b <= PM_LEAF) return;
    int ax = 0;
    if (hi[1] - lo[1] > hi[ax] - lo[ax]) ax = 1;
    if (hi[2] - lo[2] > hi[ax] - lo[ax]) ax = 2;
    uint32_t m = pm_tree_split(b, e, PM_LEAF);
    for (uint32_t i = b; i < e; i++) v[i] = kd_key(t, (uint32_t)v[i], ax);
    select_nth(v, b, e, m);
    float mv = t[(uint32_t)v[m]].p[ax], clo[3], chi[3];
    memcpy(clo, lo, sizeof clo);
    memcpy(chi, hi, sizeof chi);
    chi[ax] = mv;
    kd_split(t, v, b, m, lo, chi);
    clo[ax] = mv;
    kd_split(t, v, m, e, clo, hi);
}

/* Node boxes and normal cones over the (reordered) photons, bottom-up:
 * leaves from their photons, inner nodes from their children (the cone of
 * an inner node contains both child cones). */
static void kd_nodes(pm_page *pg, size_t node, uint32_t b, uint32_t e)
{
    pm_node *N = &pg->node[node];
    double ax = 0, ay = 0, az = 0, cmin = 1;
    if (e - b <= PM_LEAF) {
        box_of(pg->pos, NULL, b, e, N->lo, N->hi);
        float nv[PM_LEAF][3];   /* the leaf's normals (codes repeat: decode each run once) */
        uint32_t lastc = UINT32_MAX;
        for (uint32_t i = b; i < e; i++) {
            float *v = nv[i - b];
            if (pg->ncode[i] != lastc) { pm_nrm_decode(pg->ncode[i], v); lastc = pg->ncode[i]; }
            else memcpy(v, nv[i - b - 1], sizeof nv[0]);
            ax += v[0]; ay += v[1]; az += v[2];
        }
        double l = sqrt(ax * ax + ay * ay + az * az);
        if (l > 1e-9) { ax /= l; ay /= l; az /= l; } else { ax = 1; ay = 0; az = 0; cmin = -1; }
        for (uint32_t i = b; i < e && cmin > -1; i++) {
            const float *v = nv[i - b];
            double c = ax * v[0] + ay * v[1] + az * v[2];
            if (c < cmin) cmin = c;
        }
    } else {
        uint32_t m = pm_tree_split(b, e, PM_LEAF);
        kd_nodes(pg, 2 * node + 1, b, m);
        kd_nodes(pg, 2 * node + 2, m, e);
        const pm_node *A = &pg->node[2 * node + 1], *B = &pg->node[2 * node + 2];
        for (int k = 0; k < 3; k++) {
            N->lo[k] = A->lo[k] < B->lo[k] ? A->lo[k] : B->lo[k];
            N->hi[k] = A->hi[k] > B->hi[k] ? A->hi[k] : B->hi[k];
        }
        double wa = (double)(m - b), wb = (double)(e - m);
        ax = wa * A->ax[0] + wb * B->ax[0];
        ay = wa * A->ax[1] + wb * B->ax[1];
        az = wa * A->ax[2] + wb * B->ax[2];
        double l = sqrt(ax * ax + ay * ay + az * az);
        if (!memcmp(A->ax, B->ax, sizeof A->ax) && A->cmin == B->cmin) {
            /* both children have one cone (e.g. photons of one plane): the
             * parent's is the same (already widened by the margin) */
            memcpy(N->ax, A->ax, sizeof N->ax);
            N->cmin = A->cmin;
            N->smin = A->smin;
            return;
        }
        if (l > 1e-9 && A->cmin > -1 && B->cmin > -1) {
            ax /= l; ay /= l; az /= l;
            /* cos(angle to the child's axis + its half angle), for both children */
            const pm_node *C[2] = {A, B};
            for (int c = 0; c < 2; c++) {
                double ca = ax * C[c]->ax[0] + ay * C[c]->ax[1] + az * C[c]->ax[2];
                if (ca > 1) ca = 1;
                if (ca < -1) ca = -1;
                double t = acos(ca) + acos(C[c]->cmin > 1 ? 1 : C[c]->cmin);
                double cc = t >= HD_PI ? -1 : cos(t);
                if (cc < cmin) cmin = cc;
            }
        } else { ax = 1; ay = 0; az = 0; cmin = -1; }
    }
    cmin -= 1e-6;   /* rounding margin: never skip a compatible photon */
    if (cmin < -1) cmin = -1;
    N->ax[0] = (float)ax; N->ax[1] = (float)ay; N->ax[2] = (float)az;
    N->cmin = (float)cmin;
    N->smin = (float)sqrt(1 - cmin * cmin);
}

hd_status pm_page_decode(const unsigned char *raw, size_t len, uint32_t n,
                         hd_vec3 org, double size, pm_page *pg, const char *where)
{
    void *blk = hd_malloc(pm_page_block_bytes(n));
    if (!blk) return HD_ERR_NOMEM;
    pm_page_layout(pg, n, blk);
    pg->blk = blk;
    void *scr = NULL;
    size_t cap = 0;
    hd_status st = pm_page_decode_into(raw, len, n, org, size, pg, where, &scr, &cap);
    free(scr);
    if (st) pm_page_free(pg);
    return st;
}

hd_status pm_page_decode_into(const unsigned char *raw, size_t len, uint32_t n, hd_vec3 org, double size,
                              pm_page *pg, const char *where, void **scratch, size_t *scratch_cap)
{
    if (*scratch_cap < (size_t)n) {
        free(*scratch);
        *scratch_cap = 0;
        *scratch = hd_malloc_array(n ? n : 1, sizeof(kp) + sizeof(uint64_t));
        if (!*scratch) return HD_ERR_NOMEM;
        *scratch_cap = n ? n : 1;
    }
    kp *tpos = *scratch;
    uint64_t *ord = (uint64_t *)(void *)(tpos + *scratch_cap);   /* kd order: photon index in the low 32 bits */
    size_t o = 0;
    uint64_t key = 0;
    for (uint32_t i = 0; i < n; i++) {
        uint64_t d = 0;
        int sh = 0;
        for (;;) {
            if (o >= len || sh > 63) {
                return hd_fail(HD_ERR_FORMAT, "%s: bad position code of photon %u", where, i);
            }
            unsigned char c = raw[o++];
            d |= (uint64_t)(c & 0x7F) << sh;
            sh += 7;
            if (!(c & 0x80)) break;
        }
        key += d;
        key_to_pos(key, org, size, tpos[i].p);
        tpos[i].i = i;
    }
    if (len - o != (size_t)n * 9) {
        return hd_fail(HD_ERR_FORMAT, "%s: page holds %zu bytes after the positions, expected %zu",
                       where, len - o, (size_t)n * 9);
    }
    /* kd-tree order (depends only on the page's content) */
    {
        float lo[3] = {3e38f, 3e38f, 3e38f}, hi[3] = {-3e38f, -3e38f, -3e38f};
        for (uint32_t i = 0; i < n; i++)
            for (int k = 0; k < 3; k++) {
                if (tpos[i].p[k] < lo[k]) lo[k] = tpos[i].p[k];
                if (tpos[i].p[k] > hi[k]) hi[k] = tpos[i].p[k];
            }
        for (uint32_t i = 0; i < n; i++) ord[i] = i;
        kd_split(tpos, ord, 0, n, lo, hi);
    }
    const unsigned char *nl = raw + o, *nh = nl + n, *dl = nh + n, *dh = dl + n, *c0 = dh + n;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t s = (uint32_t)ord[i];
        memcpy(pg->pos + 3 * i, tpos[s].p, 3 * sizeof(float));
        pg->ncode[i] = (uint16_t)(nl[s] | nh[s] << 8);
        pg->dir[i] = (uint16_t)(dl[s] | dh[s] << 8);
        pg->wcode[i] = (uint32_t)c0[s] | (uint32_t)c0[n + s] << 8 | (uint32_t)c0[2 * n + s] << 16 |
                       (uint32_t)c0[3 * n + s] << 24;
        pg->flags[i] = c0[4 * n + s];
    }
    kd_nodes(pg, 0, 0, n);
    return HD_OK;
}

/* ---- writer ---- */
#define PM_GROUP 256
#ifndef PM_ZLEVEL
#define PM_ZLEVEL 1
#endif
#ifndef PM_STORE_DIRS
#define PM_STORE_DIRS 1   /* incident directions in stored blocks (see compress_one) */
#endif

typedef struct pm_pend {
    const pm_rec *recs;       /* the caller's records (pages are flushed before pm_writer_add returns) or w->carry */
    uint32_t n, src, flags;
    unsigned char *comp;
    size_t clen, ulen;
    float lo[3], hi[3];
    uint32_t crc;
    size_t compcap;
} pm_pend;

/* per compression worker: a deflate stream reused page after page
 * (deflateReset instead of compress2's allocation of ~270 kB of state per
 * page) and a raw-page buffer */
typedef struct pm_zctx {
    z_stream z;
    int live;
    unsigned char *raw;
} pm_zctx;

struct pm_writer {
    hd_ofile *of;
    FILE *fp;
    uint32_t nsources, page_photons;
    hd_vec3 org;
    double size;
    int nthreads;
    uint64_t offset, nphotons;
    pm_page_ent *pages;
    size_t npages, cappages;
    pm_pend group[PM_GROUP];
    int ngroup;
    pm_rec *carry;            /* the open page at the end of an add call (copied: the caller's buffer goes) */
    uint32_t ncarry, csrc, cflag;
    pm_zctx *zc;
    int nzc;
    uint64_t hdr_off;
    uint64_t *src_stored, *src_first, *src_np;
    int last_src;
};

static hd_status write_all(pm_writer *w, const void *b, size_t n)
{
    if (n && fwrite(b, 1, n, w->fp) != n)
        return hd_fail(HD_ERR_IO, "%s: write failed: %s", hd_ofile_name(w->of), strerror(errno));
    w->offset += n;
    return HD_OK;
}

hd_status pm_writer_open(pm_writer **out, const char *path, const char *header_lines,
                         uint32_t nsources, uint32_t page_photons, hd_vec3 org, double size,
                         int nthreads)
{
    pm_writer *w = hd_calloc(1, sizeof *w);
    if (!w) return HD_ERR_NOMEM;
    w->nsources = nsources;
    w->page_photons = page_photons;
    w->org = org;
    w->size = size;
    w->nthreads = hd_resolve_threads(nthreads);   /* one deflate stream per worker index */
    w->last_src = -1;
    w->nzc = w->nthreads;
    w->zc = hd_calloc((size_t)w->nzc, sizeof *w->zc);
    if (!w->zc) { free(w); return HD_ERR_NOMEM; }
    for (int k = 0; k < w->nzc; k++) {
        pm_zctx *z = &w->zc[k];
        z->raw = hd_malloc(PM_RAWMAX(page_photons) + 1);
        if (!z->raw) { pm_writer_abort(w); return HD_ERR_NOMEM; }
        if (deflateInit(&z->z, PM_ZLEVEL) != Z_OK) { pm_writer_abort(w); return HD_ERR_NOMEM; }
        z->live = 1;
    }
    w->src_stored = hd_calloc(nsources ? nsources : 1, sizeof(uint64_t));
    w->src_first = hd_calloc(nsources ? nsources : 1, sizeof(uint64_t));
    w->src_np = hd_calloc(nsources ? nsources : 1, sizeof(uint64_t));
    if (!w->src_stored || !w->src_first || !w->src_np) { pm_writer_abort(w); return HD_ERR_NOMEM; }
    w->carry = hd_malloc_array(page_photons ? page_photons : 1, sizeof(pm_rec));
    if (!w->carry) { pm_writer_abort(w); return HD_ERR_NOMEM; }
    hd_status st = hd_ofile_open(&w->of, path);
    if (st) { pm_writer_abort(w); return st; }
    w->fp = hd_ofile_fp(w->of);
    const char *hl = header_lines ? header_lines : "";
    char tail[256];
    int tl = snprintf(tail, sizeof tail, "SOFTWARE= %s\nFORMAT=heliodon_contrib_pmap\n\n", HD_SOFTWARE);
    if (tl < 0 || tl >= (int)sizeof tail) { pm_writer_abort(w); return hd_fail(HD_ERR_INTERNAL, "header"); }
    if ((st = write_all(w, "#?RADIANCE\n", 11)) || (st = write_all(w, hl, strlen(hl))) ||
        (st = write_all(w, tail, (size_t)tl))) {
        pm_writer_abort(w);
        return st;
    }
    w->hdr_off = w->offset;
    unsigned char zero[PM_BINHDR];
    memset(zero, 0, sizeof zero);
    if ((st = write_all(w, zero, sizeof zero))) { pm_writer_abort(w); return st; }
    *out = w;
    return HD_OK;
}

void pm_writer_abort(pm_writer *w)
{
    if (!w) return;
    if (w->of) hd_ofile_abort(w->of);
    for (int g = 0; g < PM_GROUP; g++) free(w->group[g].comp);
    free(w->carry);
    for (int k = 0; w->zc && k < w->nzc; k++) {
        if (w->zc[k].live) deflateEnd(&w->zc[k].z);
        free(w->zc[k].raw);
    }
    free(w->zc);
    free(w->pages);
    free(w->src_stored);
    free(w->src_first);
    free(w->src_np);
    free(w);
}

static hd_status compress_one(void *ctx, size_t b, size_t e, size_t ci, int wk)
{
    (void)ci;
    pm_writer *w = ctx;
    if (wk < 0 || wk >= w->nzc) return hd_fail(HD_ERR_INTERNAL, "compression worker %d of %d", wk, w->nzc);
    pm_zctx *z = &w->zc[wk];
    for (size_t g = b; g < e; g++) {
        pm_pend *p = &w->group[g];
        size_t kl, rl = page_encode_into(p->recs, p->n, z->raw, &kl);
        /* The page's sections go into one standard zlib stream (any
         * inflate reads it; the raw bytes are unchanged) at two levels:
         * stored blocks (level 0) for the sections deflate barely shrinks —
         * the position codes (LEB128 deltas of Morton keys, ~3.8 bytes per
         * photon, -7 % at level 1) and, with PM_STORE_DIRS, the incident
         * directions (2 bytes, -60 %) — and level 1 for the others (normals,
         * weights, flags: long runs).  2M photons of the A4 box: deflate
         * time 0.21 -> 0.12 s (keys) -> 0.09 s (+ directions), inflate
         * 0.075 -> 0.045 -> 0.033 s; 5.47 -> 5.45 -> 6.56 bytes per photon. */
        size_t nn = p->n, sec[4] = {kl, 2 * nn, 2 * nn, rl - kl - 4 * nn};
        int lev[4] = {0, PM_ZLEVEL, PM_STORE_DIRS ? 0 : PM_ZLEVEL, PM_ZLEVEL};
        if (deflateReset(&z->z) != Z_OK) return hd_fail(HD_ERR_INTERNAL, "zlib: deflateReset failed");
        /* stored blocks: 5 bytes per 64 kB (and per section) on top of deflateBound's estimate */
        size_t cb = deflateBound(&z->z, (uLong)rl) + rl / 16384 + 64;
        if (cb > p->compcap) {
            free(p->comp);
            p->comp = hd_malloc(cb);
            p->compcap = p->comp ? cb : 0;
            if (!p->comp) return HD_ERR_NOMEM;
        }
        z->z.next_out = p->comp;
        z->z.avail_out = (uInt)p->compcap;
        const unsigned char *in = z->raw;
        for (int k = 0, cur = -1; k < 4; k++) {
            if (lev[k] != cur && deflateParams(&z->z, lev[k], Z_DEFAULT_STRATEGY) != Z_OK)
                return hd_fail(HD_ERR_INTERNAL, "zlib compression failed");
            cur = lev[k];
            z->z.next_in = (unsigned char *)in;
            z->z.avail_in = (uInt)sec[k];
            in += sec[k];
            if (deflate(&z->z, k == 3 ? Z_FINISH : Z_NO_FLUSH) != (k == 3 ? Z_STREAM_END : Z_OK))
                return hd_fail(HD_ERR_INTERNAL, "zlib compression failed");
        }
        p->clen = z->z.total_out;
        p->ulen = rl;
        p->crc = hd_pmap_crc32(0, p->comp, p->clen);
        /* bounding box: positions grow with the quantised coordinates, so
         * the box of the cell centres is that of the extreme cells */
        /* ... and the bits of one axis, masked out of the Morton codes,
         * compare as that axis's coordinates: no de-interleaving per photon */
        const uint64_t M0 = 0x1249249249249249ULL, M1 = M0 << 1, M2 = M0 << 2;
        uint64_t lo0 = UINT64_MAX, lo1 = UINT64_MAX, lo2 = UINT64_MAX, hi0 = 0, hi1 = 0, hi2 = 0;
        for (uint32_t i = 0; i < p->n; i++) {
            uint64_t k = pm_rec_key(&p->recs[i]), a0 = k & M0, a1 = k & M1, a2 = k & M2;
            lo0 = a0 < lo0 ? a0 : lo0;
            lo1 = a1 < lo1 ? a1 : lo1;
            lo2 = a2 < lo2 ? a2 : lo2;
            hi0 = a0 > hi0 ? a0 : hi0;
            hi1 = a1 > hi1 ? a1 : hi1;
            hi2 = a2 > hi2 ? a2 : hi2;
        }
        if (!p->n) {
            p->lo[0] = p->lo[1] = p->lo[2] = 3e38f;
            p->hi[0] = p->hi[1] = p->hi[2] = -3e38f;
        } else {
            key_to_pos(lo0 | lo1 | lo2, w->org, w->size, p->lo);
            key_to_pos(hi0 | hi1 | hi2, w->org, w->size, p->hi);
        }
    }
    return HD_OK;
}

/* Append page e (its offset set here) and its compressed bytes to the file. */
static hd_status append_page(pm_writer *w, const pm_page_ent *e, const unsigned char *comp)
{
    if (w->npages == w->cappages) {
        size_t nc = w->cappages ? 2 * w->cappages : 256;
        pm_page_ent *np = hd_realloc_array(w->pages, nc, sizeof *np);
        if (!np) return HD_ERR_NOMEM;
        w->pages = np;
        w->cappages = nc;
    }
    pm_page_ent *d = &w->pages[w->npages];
    *d = *e;
    d->offset = w->offset - w->hdr_off;   /* relative to the binary header */
    if (w->src_np[e->src] == 0) w->src_first[e->src] = w->npages;
    w->src_np[e->src]++;
    w->src_stored[e->src] += e->count;
    w->npages++;
    return write_all(w, comp, e->csize);
}

static hd_status flush_group(pm_writer *w)
{
    if (!w->ngroup) return HD_OK;
    hd_status st = hd_parallel_for((size_t)w->ngroup, 1, w->nthreads, compress_one, w);
    if (st) return st;
    for (int g = 0; g < w->ngroup; g++) {
        pm_pend *p = &w->group[g];
        pm_page_ent e;
        memset(&e, 0, sizeof e);
        e.csize = (uint32_t)p->clen;
        e.usize = (uint32_t)p->ulen;
        e.count = p->n;
        e.src = p->src;
        e.flags = p->flags;
        memcpy(e.lo, p->lo, sizeof e.lo);
        memcpy(e.hi, p->hi, sizeof e.hi);
        e.crc = p->crc;
        if ((st = append_page(w, &e, p->comp))) return st;
    }
    w->ngroup = 0;
    return HD_OK;
}

/* Queue a page (compressed with the group); a full group is flushed. */
static hd_status queue_page(pm_writer *w, const pm_rec *r, uint32_t n, uint32_t src, uint32_t flag)
{
    pm_pend *p = &w->group[w->ngroup++];
    p->recs = r;
    p->n = n;
    p->src = src;
    p->flags = flag;
    return w->ngroup == PM_GROUP ? flush_group(w) : HD_OK;
}

/* Close the open (carried) page and write every queued page. */
static hd_status close_page(pm_writer *w)
{
    hd_status st;
    if (w->ncarry) {
        if ((st = queue_page(w, w->carry, w->ncarry, w->csrc, w->cflag))) return st;
        w->ncarry = 0;
    }
    return flush_group(w);
}

/* Pages are cut as records arrive: a page ends at a change of source or
 * direct flag, or after page_photons records.  Pages lying in r are
 * compressed from r itself (no copy); all are written before returning, and
 * the last, possibly unfinished, page is carried over to the next call (so
 * the pages do not depend on how the records are split between calls). */
hd_status pm_writer_add(pm_writer *w, const pm_rec *r, size_t n)
{
    hd_status st;
    size_t i = 0;
    uint32_t pp = w->page_photons;
    if (w->ncarry) {
        while (i < n && w->ncarry < pp && r[i].src == w->csrc && (r[i].flags & PM_F_DIRECT) == w->cflag)
            w->carry[w->ncarry++] = r[i++];
        w->nphotons += i;
        if (i == n) return HD_OK;
        /* closed by r[i]: the carry buffer stays queued until the flush below */
        if ((st = queue_page(w, w->carry, w->ncarry, w->csrc, w->cflag))) return st;
    }
    size_t tail = n;
    while (i < n) {
        uint32_t s = r[i].src, f = r[i].flags & PM_F_DIRECT;
        if (s >= w->nsources) return hd_fail(HD_ERR_INTERNAL, "photon source %u out of range", s);
        if ((int)s < w->last_src) return hd_fail(HD_ERR_INTERNAL, "photons not sorted by source");
        w->last_src = (int)s;
        size_t j = i + 1, lim = n - i > pp ? i + pp : n;
        while (j < lim && r[j].src == s && (r[j].flags & PM_F_DIRECT) == f) j++;
        if (j == n && j - i < pp) { tail = i; break; }   /* may go on in the next call */
        if ((st = queue_page(w, r + i, (uint32_t)(j - i), s, f))) return st;
        w->nphotons += j - i;
        i = j;
    }
    if ((st = flush_group(w))) return st;
    w->ncarry = 0;
    if (tail < n) {
        memcpy(w->carry, r + tail, (n - tail) * sizeof *r);
        w->ncarry = (uint32_t)(n - tail);
        w->csrc = r[tail].src;
        w->cflag = r[tail].flags & PM_F_DIRECT;
        w->nphotons += n - tail;
    }
    return HD_OK;
}

hd_status pm_writer_add_raw(pm_writer *w, const pm_page_ent *e, const unsigned char *comp)
{
    hd_status st;
    if ((st = close_page(w))) return st;
    if (e->src >= w->nsources || (int)e->src < w->last_src) return hd_fail(HD_ERR_INTERNAL, "pages not in source order");
    w->nphotons += e->count;
    w->last_src = (int)e->src;
    return append_page(w, e, comp);
}

hd_status pm_writer_close(pm_writer *w, hd_pmap_source *src, uint64_t *file_bytes)
{
    hd_status st;
    if ((st = close_page(w))) { pm_writer_abort(w); return st; }
    /* source table */
    uint64_t tab_off = w->offset - w->hdr_off;
    size_t tcap = (size_t)w->nsources * (2 + PM_MAXNAME + 8 * 13) + 4;
    unsigned char *t = hd_malloc(tcap), *q = t;
    if (!t) { pm_writer_abort(w); return HD_ERR_NOMEM; }
    for (uint32_t s = 0; s < w->nsources; s++) {
        hd_pmap_source *S = &src[s];
        S->stored = w->src_stored[s];
        S->first_page = w->src_first[s];
        S->npages = w->src_np[s];
        size_t nl = strlen(S->modifier);
        if (nl > PM_MAXNAME) nl = PM_MAXNAME;
        q[0] = (unsigned char)nl; q[1] = 0;
        memcpy(q + 2, S->modifier, nl);
        q += 2 + nl;
        pm_putf64(q, S->dir.x); pm_putf64(q + 8, S->dir.y); pm_putf64(q + 16, S->dir.z);
        pm_putf64(q + 24, S->half_angle);
        pm_putf64(q + 32, S->radiance[0]); pm_putf64(q + 40, S->radiance[1]); pm_putf64(q + 48, S->radiance[2]);
        pm_put64(q + 56, S->emitted);
        pm_put64(q + 64, S->stored);
        pm_putf64(q + 72, S->flux);
        pm_put64(q + 80, S->first_page);
        pm_put64(q + 88, S->npages);
        q += 96;
    }
    pm_put32(q, hd_pmap_crc32(0, t, (size_t)(q - t)));
    q += 4;
    uint64_t tab_len = (uint64_t)(q - t);
    st = write_all(w, t, (size_t)tab_len);
    free(t);
    if (st) { pm_writer_abort(w); return st; }
    /* page index */
    uint64_t idx_off = w->offset - w->hdr_off;
    uint32_t icrc = 0;
    unsigned char e[PM_IDXREC];
    for (size_t i = 0; i < w->npages; i++) {
        pm_page_ent *p = &w->pages[i];
        pm_put64(e, p->offset);
        pm_put32(e + 8, p->csize);
        pm_put32(e + 12, p->usize);
        pm_put32(e + 16, p->count);
        pm_put32(e + 20, p->src);
        for (int k = 0; k < 3; k++) { pm_putf32(e + 24 + 4 * k, p->lo[k]); pm_putf32(e + 36 + 4 * k, p->hi[k]); }
        pm_put32(e + 48, p->crc);
        pm_put32(e + 52, p->flags);
        icrc = hd_pmap_crc32(icrc, e, PM_IDXREC);
        if ((st = write_all(w, e, PM_IDXREC))) { pm_writer_abort(w); return st; }
    }
    pm_put32(e, icrc);
    if ((st = write_all(w, e, 4))) { pm_writer_abort(w); return st; }
    uint64_t idx_len = w->offset - w->hdr_off - idx_off;
    /* binary header */
    unsigned char h[PM_BINHDR];
    memset(h, 0, sizeof h);
    memcpy(h, PM_MAGIC, 8);
    pm_put32(h + 8, PM_VERSION);
    pm_put32(h + 12, PM_BINHDR);
    pm_put64(h + 16, w->nphotons);
    pm_put64(h + 24, w->npages);
    pm_put32(h + 32, w->nsources);
    pm_put32(h + 36, w->page_photons);
    pm_putf64(h + 40, w->org.x); pm_putf64(h + 48, w->org.y); pm_putf64(h + 56, w->org.z);
    pm_putf64(h + 64, w->size);
    pm_put64(h + 72, tab_off);
    pm_put64(h + 80, tab_len);
    pm_put64(h + 88, idx_off);
    pm_put64(h + 96, idx_len);
    pm_put64(h + 104, PM_BINHDR);
    pm_put64(h + 112, w->offset - w->hdr_off);
    pm_put32(h + 124, hd_pmap_crc32(0, h, 124));
    if (fseek(w->fp, (long)w->hdr_off, SEEK_SET) != 0 || fwrite(h, 1, sizeof h, w->fp) != sizeof h) {
        st = hd_fail(HD_ERR_IO, "%s: cannot write the binary header", hd_ofile_name(w->of));
        pm_writer_abort(w);
        return st;
    }
    if (file_bytes) *file_bytes = w->offset;
    st = hd_ofile_commit(w->of);
    w->of = NULL;
    pm_writer_abort(w);
    return st;
}

/* ---- reader ---- */
/* arena bytes of a decoded page of n photons: its header, then its block */
#define PM_PAGE_HDR_BYTES ((sizeof(pm_page) + 63) & ~(size_t)63)
static size_t pm_arena_bytes(uint32_t n) { return PM_PAGE_HDR_BYTES + pm_page_block_bytes(n); }

static hd_status pread_all(hd_pmap *m, void *buf, size_t n, uint64_t off, const char *what)
{
    size_t got = 0;
    while (got < n) {
        ssize_t r = pread(m->fd, (char *)buf + got, n - got, (off_t)(off + got));
        if (r < 0 && errno == EINTR) continue;
        if (r < 0) return hd_fail(HD_ERR_IO, "%s: read error at byte %llu: %s", m->path,
                                  (unsigned long long)(off + got), strerror(errno));
        if (r == 0)
            return hd_fail(HD_ERR_FORMAT, "%s: truncated: %s at byte %llu needs %zu bytes, file ends after %zu",
                           m->path, what, (unsigned long long)off, n, got);
        got += (size_t)r;
    }
    return HD_OK;
}

static void ptree_build(const pm_page_ent *pages, pm_box *t, size_t node, uint64_t b, uint64_t e)
{
    pm_box *N = &t[node];
    for (int k = 0; k < 3; k++) { N->lo[k] = 3e38f; N->hi[k] = -3e38f; }
    for (uint64_t i = b; i < e; i++)
        for (int k = 0; k < 3; k++) {
            if (pages[i].lo[k] < N->lo[k]) N->lo[k] = pages[i].lo[k];
            if (pages[i].hi[k] > N->hi[k]) N->hi[k] = pages[i].hi[k];
        }
    if (e - b <= 1) return;
    uint64_t m = pm_tree_split((uint32_t)b, (uint32_t)e, 1);
    ptree_build(pages, t, 2 * node + 1, b, m);
    ptree_build(pages, t, 2 * node + 2, m, e);
}

/* Per source: the indirect pages come first, then the direct ones; a tree
 * of page boxes over each of the two ranges (implicit layout, leaves =
 * pages; ranges are page indices relative to the range start). */
static hd_status build_page_trees(hd_pmap *m)
{
    uint32_t ns = m->info.nsources;
    m->src_nind = hd_calloc(ns ? ns : 1, sizeof *m->src_nind);
    m->src_tree = hd_calloc(2 * (size_t)(ns ? ns : 1) + 1, sizeof *m->src_tree);
    if (!m->src_nind || !m->src_tree) return HD_ERR_NOMEM;
    size_t tot = 0;
    for (uint32_t s = 0; s < ns; s++) {
        const hd_pmap_source *S = &m->src[s];
        if (S->npages > UINT32_MAX) return hd_fail(HD_ERR_RANGE, "%s: source %u has too many pages", m->path, s);
        uint64_t k = 0;
        while (k < S->npages && !(m->pages[S->first_page + k].flags & PM_F_DIRECT)) k++;
        for (uint64_t i = k; i < S->npages; i++)
            if (!(m->pages[S->first_page + i].flags & PM_F_DIRECT) || m->pages[S->first_page + i].src != s)
                return hd_fail(HD_ERR_FORMAT, "%s: source %u: pages not ordered (indirect, then direct)", m->path, s);
        for (uint64_t i = 0; i < k; i++)
            if (m->pages[S->first_page + i].src != s)
                return hd_fail(HD_ERR_FORMAT, "%s: page %llu does not belong to source %u", m->path,
                               (unsigned long long)(S->first_page + i), s);
        m->src_nind[s] = k;
        m->src_tree[2 * s] = tot;
        tot += k ? pm_tree_nodes(k, 1) : 0;
        m->src_tree[2 * s + 1] = tot;
        tot += S->npages - k ? pm_tree_nodes(S->npages - k, 1) : 0;
    }
    m->src_tree[2 * (size_t)ns] = tot;
    m->ptree = hd_calloc(tot ? tot : 1, sizeof *m->ptree);
    if (!m->ptree) return HD_ERR_NOMEM;
    for (uint32_t s = 0; s < ns; s++) {
        const hd_pmap_source *S = &m->src[s];
        uint64_t k = m->src_nind[s];
        if (k) ptree_build(m->pages + S->first_page, m->ptree + m->src_tree[2 * s], 0, 0, k);
        if (S->npages > k) ptree_build(m->pages + S->first_page + k, m->ptree + m->src_tree[2 * s + 1], 0, 0, S->npages - k);
    }
    return HD_OK;
}

static void scratch_free(struct pm_scratch *s);

void hd_pmap_close(hd_pmap *m)
{
    if (!m) return;
    if (m->fd >= 0) close(m->fd);
    for (size_t i = 0; i < m->nslots; i++)
        if (m->cache && m->cache[i].data) { pm_page_free(m->cache[i].data); free(m->cache[i].data); }
    free(m->cache);
    free(m->slot_of);
    free((void *)m->res);
    for (size_t i = 0; i < m->nchunk; i++) free(m->chunk[i]);
    free(m->chunk);
    for (size_t i = 0; i < m->nscr; i++) scratch_free(m->scr[i]);
    free(m->scr);
    pthread_mutex_destroy(&m->lock);
    free(m->path);
    free(m->header_text);
    free(m->src);
    free(m->pages);
    free(m->src_nind);
    free(m->src_tree);
    free(m->ptree);
    free(m);
}

hd_status hd_pmap_open(hd_pmap **out, const char *path, uint64_t cache_photons)
{
    *out = NULL;
    hd_pmap *m = hd_calloc(1, sizeof *m);
    if (!m) return HD_ERR_NOMEM;
    m->fd = -1;
    pthread_mutex_init(&m->lock, NULL);
    m->path = hd_strdup(path);
    if (!m->path) { hd_pmap_close(m); return HD_ERR_NOMEM; }
    m->fd = open(path, O_RDONLY);
    if (m->fd < 0) {
        hd_status st = hd_fail(HD_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
        hd_pmap_close(m);
        return st;
    }
    off_t fsz = lseek(m->fd, 0, SEEK_END);
    /* text header: up to the first empty line */
    size_t cap = 65536, n = 0;
    char *txt = hd_malloc(cap + 1);
    if (!txt) { hd_pmap_close(m); return HD_ERR_NOMEM; }
    ssize_t r;
    while (n < cap && (r = pread(m->fd, txt + n, cap - n, (off_t)n)) > 0) n += (size_t)r;
    txt[n] = 0;
    hd_status st;
    char *end = NULL;
    if (n < 11 || memcmp(txt, "#?RADIANCE\n", 11) != 0) {
        st = hd_fail(HD_ERR_FORMAT, "%s: not a photon map (no #?RADIANCE header)", path);
        free(txt); hd_pmap_close(m); return st;
    }
    end = strstr(txt, "\n\n");
    if (!end) {
        st = hd_fail(HD_ERR_FORMAT, "%s: header not terminated by an empty line within %zu bytes", path, n);
        free(txt); hd_pmap_close(m); return st;
    }
    end[1] = 0;
    if (!strstr(txt, "\nFORMAT=heliodon_contrib_pmap\n")) {
        st = hd_fail(HD_ERR_FORMAT, "%s: FORMAT is not heliodon_contrib_pmap (Radiance photon maps are not read)", path);
        free(txt); hd_pmap_close(m); return st;
    }
    uint64_t hoff = (uint64_t)(end - txt) + 2;
    m->header_text = txt;
    unsigned char h[PM_BINHDR];
    if ((st = pread_all(m, h, sizeof h, hoff, "binary header"))) { hd_pmap_close(m); return st; }
    if (memcmp(h, PM_MAGIC, 8) != 0) {
        st = hd_fail(HD_ERR_FORMAT, "%s: byte %llu: bad magic in the binary header", path, (unsigned long long)hoff);
        hd_pmap_close(m); return st;
    }
    if (hd_pmap_crc32(0, h, 124) != pm_get32(h + 124)) {
        st = hd_fail(HD_ERR_FORMAT, "%s: byte %llu: binary header checksum mismatch (corrupt file)", path,
                     (unsigned long long)hoff);
        hd_pmap_close(m); return st;
    }
    hd_pmap_info *I = &m->info;
    I->version = pm_get32(h + 8);
    if (I->version != PM_VERSION || pm_get32(h + 12) != PM_BINHDR) {
        st = hd_fail(HD_ERR_UNSUPPORTED, "%s: photon map version %u, this program reads version %u", path,
                     I->version, PM_VERSION);
        hd_pmap_close(m); return st;
    }
    I->nphotons = pm_get64(h + 16);
    I->npages = pm_get64(h + 24);
    I->nsources = pm_get32(h + 32);
    I->page_photons = pm_get32(h + 36);
    I->org = hd_v3(pm_getf64(h + 40), pm_getf64(h + 48), pm_getf64(h + 56));
    I->size = pm_getf64(h + 64);
    uint64_t tab_off = pm_get64(h + 72), tab_len = pm_get64(h + 80), idx_off = pm_get64(h + 88),
             idx_len = pm_get64(h + 96), data_off = pm_get64(h + 104), flen = pm_get64(h + 112);
    I->file_bytes = hoff + flen;
    I->data_bytes = tab_off - data_off;
    m->base = hoff;
    if ((uint64_t)fsz != hoff + flen) {
        st = hd_fail(HD_ERR_FORMAT, "%s: file has %llu bytes, its header says %llu (truncated or extended)", path,
                     (unsigned long long)fsz, (unsigned long long)(hoff + flen));
        hd_pmap_close(m); return st;
    }
    /* every offset and length against the file (no sum may wrap), the page
     * count against the index that must hold it, before anything is sized
     * from them */
    if (I->nsources > 65535 || flen < 4 || I->npages > (flen - 4) / PM_IDXREC || idx_len != I->npages * PM_IDXREC + 4 ||
        tab_off > flen || tab_len > flen - tab_off || idx_off > flen || idx_len > flen - idx_off ||
        data_off > tab_off || I->page_photons == 0 || I->page_photons > (1u << 24) || !(I->size > 0) ||
        !isfinite(I->size) || !isfinite(I->org.x) || !isfinite(I->org.y) || !isfinite(I->org.z)) {
        st = hd_fail(HD_ERR_FORMAT, "%s: byte %llu: inconsistent binary header", path, (unsigned long long)hoff);
        hd_pmap_close(m); return st;
    }
    /* source table */
    unsigned char *t = hd_malloc(tab_len ? tab_len : 1);
    if (!t) { hd_pmap_close(m); return HD_ERR_NOMEM; }
    if ((st = pread_all(m, t, tab_len, hoff + tab_off, "source table"))) { free(t); hd_pmap_close(m); return st; }
    if (tab_len < 4 || hd_pmap_crc32(0, t, tab_len - 4) != pm_get32(t + tab_len - 4)) {
        free(t);
        st = hd_fail(HD_ERR_FORMAT, "%s: byte %llu: source table checksum mismatch (corrupt file)", path,
                     (unsigned long long)(hoff + tab_off));
        hd_pmap_close(m); return st;
    }
    m->src = hd_calloc(I->nsources ? I->nsources : 1, sizeof *m->src);
    if (!m->src) { free(t); hd_pmap_close(m); return HD_ERR_NOMEM; }
    const unsigned char *q = t, *qe = t + tab_len - 4;
    for (uint32_t s = 0; s < I->nsources; s++) {
        hd_pmap_source *S = &m->src[s];
        if (qe - q < 2 || qe - q < 2 + q[0] + 96) {
            free(t);
            st = hd_fail(HD_ERR_FORMAT, "%s: source table too short for %u sources", path, I->nsources);
            hd_pmap_close(m); return st;
        }
        size_t nl = q[0];
        if (nl > PM_MAXNAME) {   /* the name field holds PM_MAXNAME bytes and a NUL */
            st = hd_fail(HD_ERR_FORMAT, "%s: byte %llu: source %u: modifier name of %zu bytes (at most %u)", path,
                         (unsigned long long)(hoff + tab_off + (uint64_t)(q - t)), s, nl, PM_MAXNAME);
            free(t);
            hd_pmap_close(m); return st;
        }
        memcpy(S->modifier, q + 2, nl);
        S->modifier[nl] = 0;
        q += 2 + nl;
        S->dir = hd_v3(pm_getf64(q), pm_getf64(q + 8), pm_getf64(q + 16));
        S->half_angle = pm_getf64(q + 24);
        for (int k = 0; k < 3; k++) S->radiance[k] = pm_getf64(q + 32 + 8 * k);
        S->emitted = pm_get64(q + 56);
        S->stored = pm_get64(q + 64);
        S->flux = pm_getf64(q + 72);
        S->first_page = pm_get64(q + 80);
        S->npages = pm_get64(q + 88);
        q += 96;
        if (S->npages > I->npages || S->first_page > I->npages - S->npages) {
            free(t);
            st = hd_fail(HD_ERR_FORMAT, "%s: source %u: page range out of bounds", path, s);
            hd_pmap_close(m); return st;
        }
    }
    free(t);
    /* page index */
    unsigned char *ib = hd_malloc(idx_len);
    if (!ib) { hd_pmap_close(m); return HD_ERR_NOMEM; }
    if ((st = pread_all(m, ib, idx_len, hoff + idx_off, "page index"))) { free(ib); hd_pmap_close(m); return st; }
    if (hd_pmap_crc32(0, ib, idx_len - 4) != pm_get32(ib + idx_len - 4)) {
        free(ib);
        st = hd_fail(HD_ERR_FORMAT, "%s: byte %llu: page index checksum mismatch (corrupt file)", path,
                     (unsigned long long)(hoff + idx_off));
        hd_pmap_close(m); return st;
    }
    m->pages = hd_calloc(I->npages ? I->npages : 1, sizeof *m->pages);
    if (!m->pages) { free(ib); hd_pmap_close(m); return HD_ERR_NOMEM; }
    uint64_t total = 0;
    for (uint64_t i = 0; i < I->npages; i++) {
        const unsigned char *e = ib + i * PM_IDXREC;
        pm_page_ent *p = &m->pages[i];
        p->offset = pm_get64(e);
        p->csize = pm_get32(e + 8);
        p->usize = pm_get32(e + 12);
        p->count = pm_get32(e + 16);
        p->src = pm_get32(e + 20);
        for (int k = 0; k < 3; k++) { p->lo[k] = pm_getf32(e + 24 + 4 * k); p->hi[k] = pm_getf32(e + 36 + 4 * k); }
        p->crc = pm_get32(e + 48);
        p->flags = pm_get32(e + 52);
        total += p->count;
        if (p->offset < data_off || p->offset > tab_off || p->csize > tab_off - p->offset || p->count > I->page_photons ||
            p->usize > (uint64_t)p->count * 19 || p->src >= I->nsources) {
            free(ib);
            st = hd_fail(HD_ERR_FORMAT, "%s: page %llu: index entry out of range", path, (unsigned long long)i);
            hd_pmap_close(m); return st;
        }
    }
    free(ib);
    if (total != I->nphotons) {
        st = hd_fail(HD_ERR_FORMAT, "%s: pages hold %llu photons, header says %llu", path,
                     (unsigned long long)total, (unsigned long long)I->nphotons);
        hd_pmap_close(m); return st;
    }
    if ((st = build_page_trees(m))) { hd_pmap_close(m); return st; }
    /* cache */
    uint64_t np = cache_photons ? cache_photons / I->page_photons : I->npages;
    if (np < 16) np = 16;
    if (np > I->npages) np = I->npages ? I->npages : 1;
    m->capcache = (size_t)np;
    m->nslots = m->capcache + 256;   /* room for pages pinned by concurrent lookups */
    m->cache = hd_calloc(m->nslots, sizeof *m->cache);
    m->slot_of = hd_malloc_array(I->npages ? I->npages : 1, sizeof *m->slot_of);
    if (!m->cache || !m->slot_of) { hd_pmap_close(m); return HD_ERR_NOMEM; }
    for (size_t i = 0; i < m->nslots; i++) m->cache[i].page = UINT64_MAX;
    for (uint64_t i = 0; i < I->npages; i++) m->slot_of[i] = -1;
    if (I->npages && m->capcache >= I->npages) {   /* every page fits: resident mode */
        m->res = hd_malloc_array(I->npages, sizeof *m->res);
        if (!m->res) { hd_pmap_close(m); return HD_ERR_NOMEM; }
        for (uint64_t i = 0; i < I->npages; i++) {
            atomic_init(&m->res[i], NULL);
            m->aneed += pm_arena_bytes(m->pages[i].count);
        }
        m->resident = 1;
    }
    *out = m;
    return HD_OK;
}

const hd_pmap_info *hd_pmap_get_info(const hd_pmap *m) { return &m->info; }
const hd_pmap_source *hd_pmap_get_source(const hd_pmap *m, uint32_t i)
{
    return i < m->info.nsources ? &m->src[i] : NULL;
}
const char *hd_pmap_header_text(const hd_pmap *m) { return m->header_text; }

void hd_pmap_cache_stats(const hd_pmap *m, uint64_t *page_reads, uint64_t *peak)
{
    if (page_reads) *page_reads = m->page_reads;
    if (peak) *peak = m->bytes_peak;
}

/* Decode scratch (compressed and raw bytes, kd-build keys), pooled so that
 * pages are decoded without allocating. */
typedef struct pm_scratch {
    unsigned char *c, *u;
    size_t capc, capu;
    void *kp;
    size_t capkp;
    z_stream z;               /* raw inflate state, reset per page */
    int zok;
} pm_scratch;
#define PM_MAXSCR 64

static void scratch_free(pm_scratch *s)
{
    if (!s) return;
    if (s->zok) inflateEnd(&s->z);
    free(s->c);
    free(s->u);
    free(s->kp);
    free(s);
}

static pm_scratch *scratch_get(hd_pmap *m)
{
    pm_scratch *s = NULL;
    pthread_mutex_lock(&m->lock);
    if (m->nscr) s = m->scr[--m->nscr];
    pthread_mutex_unlock(&m->lock);
    return s ? s : hd_calloc(1, sizeof *s);
}

static void scratch_put(hd_pmap *m, pm_scratch *s)
{
    if (!s) return;
    pthread_mutex_lock(&m->lock);
    if (!m->scr) m->scr = hd_calloc(PM_MAXSCR, sizeof *m->scr);
    if (m->scr && m->nscr < PM_MAXSCR) { m->scr[m->nscr++] = s; s = NULL; }
    pthread_mutex_unlock(&m->lock);
    scratch_free(s);
}

static int grow(unsigned char **b, size_t *cap, size_t n)
{
    if (n <= *cap) return 1;
    free(*b);
    *cap = 0;
    *b = hd_malloc(n ? n : 1);
    if (!*b) return 0;
    *cap = n ? n : 1;
    return 1;
}

/* Inflate a page's zlib stream into sc->u.  The CRC-32 of the compressed
 * bytes is already checked, so the deflate data are inflated raw (no
 * second, Adler-32 check); streams with a preset dictionary or another
 * method go through uncompress(). */
static hd_status page_inflate(pm_scratch *sc, const pm_page_ent *e, uLongf *ul)
{
    const unsigned char *c = sc->c;
    if (e->csize < 6 || (c[0] & 0x0F) != 8 || (c[0] >> 4) > 7 || (c[1] & 0x20) || ((c[0] << 8) | c[1]) % 31) {
        *ul = e->usize;
        return uncompress(sc->u, ul, c, e->csize) == Z_OK && *ul == e->usize ? HD_OK : HD_ERR_FORMAT;
    }
    if (!sc->zok) {
        memset(&sc->z, 0, sizeof sc->z);
        if (inflateInit2(&sc->z, -15) != Z_OK) return HD_ERR_NOMEM;
        sc->zok = 1;
    } else if (inflateReset(&sc->z) != Z_OK) return HD_ERR_FORMAT;
    sc->z.next_in = (unsigned char *)sc->c + 2;
    sc->z.avail_in = (uInt)(e->csize - 6);
    sc->z.next_out = sc->u;
    sc->z.avail_out = (uInt)e->usize;
    int r = inflate(&sc->z, Z_FINISH);
    *ul = e->usize - sc->z.avail_out;
    return r == Z_STREAM_END && *ul == e->usize ? HD_OK : HD_ERR_FORMAT;
}

/* Block of n bytes (64-byte aligned) from the resident arena: chunks of
 * at least 16 MB, faulted in at once.  Called with the lock held. */
static void *arena_alloc(hd_pmap *m, size_t n)
{
    if (n > m->aleft) {
        /* 16 MB chunks, or what the whole map still needs if less (a small
         * map does not take 16 MB) */
        size_t want = m->aneed < ((size_t)16 << 20) ? m->aneed : ((size_t)16 << 20);
        size_t cs = n > want ? n : want;
        if (m->nchunk == m->capchunk) {
            size_t nc = m->capchunk ? 2 * m->capchunk : 16;
            unsigned char **a = hd_realloc_array(m->chunk, nc, sizeof *a);
            if (!a) return NULL;
            m->chunk = a;
            m->capchunk = nc;
        }
        /* 2 MB aligned with transparent huge pages asked for (hd_big_alloc):
         * the gather reads the resident pages at random, and 4 kB pages
         * cost a TLB miss per access */
        void *p = hd_big_alloc(cs, 1, 0);
        if (!p) return NULL;
        m->chunk[m->nchunk++] = p;
        m->acur = p;
        m->aleft = cs;
    }
    void *r = m->acur;
    m->acur += n;
    m->aleft -= n;
    m->aneed -= n < m->aneed ? n : m->aneed;
    return r;
}

/* Read, check and decode page `page` into a new pm_page (*out): in the
 * arena if asked (resident map), else one malloc'ed block. */
static hd_status load_page(hd_pmap *m, uint64_t page, int arena, pm_page **out)
{
    *out = NULL;
    const pm_page_ent *e = &m->pages[page];
    pm_scratch *sc = scratch_get(m);
    if (!sc) return HD_ERR_NOMEM;
    char where[512];
    snprintf(where, sizeof where, "%s: page %llu (byte %llu)", m->path, (unsigned long long)page,
             (unsigned long long)(m->base + e->offset));
    hd_status st = HD_OK;
    pm_page *pg = NULL;
    if (!grow(&sc->c, &sc->capc, e->csize) || !grow(&sc->u, &sc->capu, e->usize)) { st = HD_ERR_NOMEM; goto done; }
    if ((st = pread_all(m, sc->c, e->csize, m->base + e->offset, "photon page"))) goto done;
    /* zlib's crc32 is the same CRC-32 as hd_pmap_crc32, several times faster */
    if ((uint32_t)crc32(0L, sc->c, (uInt)e->csize) != e->crc) {
        st = hd_fail(HD_ERR_FORMAT, "%s: checksum mismatch (corrupt file)", where);
        goto done;
    }
    uLongf ul = e->usize;
    if ((st = page_inflate(sc, e, &ul))) {
        st = hd_fail(HD_ERR_FORMAT, "%s: cannot decompress", where);
        goto done;
    }
    size_t hb = PM_PAGE_HDR_BYTES, bb = pm_page_block_bytes(e->count);
    if (arena) {
        pthread_mutex_lock(&m->lock);
        unsigned char *a = arena_alloc(m, pm_arena_bytes(e->count));
        pthread_mutex_unlock(&m->lock);
        if (!a) { st = HD_ERR_NOMEM; goto done; }
        /* fault the block in at once just before it is written (its lines
         * are still in the cache when the decode fills them) */
        pm_prefault(a, hb + bb);
        pg = (pm_page *)(void *)a;
        pm_page_layout(pg, e->count, a + hb);
    } else {
        pg = hd_malloc(sizeof *pg);
        void *blk = pg ? hd_malloc(bb) : NULL;
        if (!blk) { free(pg); pg = NULL; st = HD_ERR_NOMEM; goto done; }
        pm_page_layout(pg, e->count, blk);
        pg->blk = blk;
    }
    st = pm_page_decode_into(sc->u, ul, e->count, m->info.org, m->info.size, pg, where, &sc->kp, &sc->capkp);
    if (st && !arena) { pm_page_free(pg); free(pg); }
    if (st) pg = NULL;
done:
    scratch_put(m, sc);
    *out = pg;
    return st;
}

/* memory of a decoded page (cache statistics): its block and header */
static size_t page_bytes(const pm_page *pg)
{
    return pm_page_block_bytes(pg->count) + sizeof *pg;
}

static void cache_put(hd_pmap *m, size_t slot, uint64_t page, pm_page *pg)
{
    m->cache[slot].page = page;
    m->cache[slot].data = pg;
    m->cache[slot].pins = 1;
    m->cache[slot].stamp = ++m->clock;
    m->slot_of[page] = (int64_t)slot;
    m->ncache++;
    m->bytes_now += page_bytes(pg);
    if (m->bytes_now > m->bytes_peak) m->bytes_peak = m->bytes_now;
}

static void cache_evict(hd_pmap *m, size_t slot)
{
    m->bytes_now -= page_bytes(m->cache[slot].data);
    pm_page_free(m->cache[slot].data);
    free(m->cache[slot].data);
    m->slot_of[m->cache[slot].page] = -1;
    m->cache[slot].data = NULL;
    m->cache[slot].page = UINT64_MAX;
    m->ncache--;
}

hd_status pm_page_get(hd_pmap *m, uint64_t page, const pm_page **out)
{
    if (page >= m->info.npages) return hd_fail(HD_ERR_INTERNAL, "page %llu out of range", (unsigned long long)page);
    if (m->resident) {   /* never evicted: no pins, no lock once decoded */
        pm_page *r = atomic_load_explicit(&m->res[page], memory_order_acquire);
        if (r) { *out = r; return HD_OK; }
        pm_page *pg;
        hd_status st = load_page(m, page, 1, &pg);
        if (st) return st;
        pthread_mutex_lock(&m->lock);
        m->page_reads++;
        r = atomic_load_explicit(&m->res[page], memory_order_relaxed);
        if (!r) {   /* else another thread decoded it meanwhile (its arena block stays unused) */
            atomic_store_explicit(&m->res[page], pg, memory_order_release);
            m->bytes_now += page_bytes(pg);
            if (m->bytes_now > m->bytes_peak) m->bytes_peak = m->bytes_now;
            r = pg;
        }
        pthread_mutex_unlock(&m->lock);
        *out = r;
        return HD_OK;
    }
    pthread_mutex_lock(&m->lock);
    int64_t sl = m->slot_of[page];
    if (sl >= 0) {
        m->cache[sl].pins++;
        m->cache[sl].stamp = ++m->clock;
        *out = m->cache[sl].data;
        pthread_mutex_unlock(&m->lock);
        return HD_OK;
    }
    pthread_mutex_unlock(&m->lock);
    /* decode outside the lock */
    pm_page *pg;
    hd_status st = load_page(m, page, 0, &pg);
    if (st) return st;
    pthread_mutex_lock(&m->lock);
    m->page_reads++;
    sl = m->slot_of[page];
    if (sl >= 0) {   /* another thread loaded it meanwhile */
        m->cache[sl].pins++;
        m->cache[sl].stamp = ++m->clock;
        *out = m->cache[sl].data;
        pthread_mutex_unlock(&m->lock);
        pm_page_free(pg);
        free(pg);
        return HD_OK;
    }
    size_t slot = SIZE_MAX;
    if (m->ncache >= m->capcache) {   /* evict least recently used unpinned pages */
        while (m->ncache >= m->capcache) {
            uint64_t best = UINT64_MAX;
            size_t b = SIZE_MAX;
            for (size_t i = 0; i < m->nslots; i++)
                if (m->cache[i].page != UINT64_MAX && !m->cache[i].pins && m->cache[i].stamp < best) {
                    best = m->cache[i].stamp;
                    b = i;
                }
            if (b == SIZE_MAX) break;   /* all pinned: overflow slots */
            cache_evict(m, b);
        }
    }
    for (size_t i = 0; i < m->nslots; i++) if (m->cache[i].page == UINT64_MAX) { slot = i; break; }
    if (slot == SIZE_MAX) {
        pthread_mutex_unlock(&m->lock);
        pm_page_free(pg);
        free(pg);
        return hd_fail(HD_ERR_INTERNAL, "photon page cache: all pages pinned");
    }
    cache_put(m, slot, page, pg);
    *out = pg;
    pthread_mutex_unlock(&m->lock);
    return HD_OK;
}

void pm_page_release(hd_pmap *m, uint64_t page)
{
    if (m->resident) return;
    pthread_mutex_lock(&m->lock);
    int64_t sl = page < m->info.npages ? m->slot_of[page] : -1;
    if (sl >= 0 && m->cache[sl].pins > 0) m->cache[sl].pins--;
    pthread_mutex_unlock(&m->lock);
}

hd_status hd_pmap_verify(hd_pmap *m, uint64_t *bad)
{
    uint64_t nb = 0;
    hd_status first = HD_OK;
    char msg[1024] = "";
    for (uint64_t i = 0; i < m->info.npages; i++) {
        pm_page *pg;
        hd_status st = load_page(m, i, 0, &pg);
        if (st) {
            if (!nb) { first = st; hd_strlcpy(msg, hd_errmsg(), sizeof msg); }
            nb++;
            continue;
        }
        pm_page_free(pg);
        free(pg);
    }
    if (bad) *bad = nb;
    if (nb) return hd_fail(first, "%s (%llu bad pages of %llu)", msg, (unsigned long long)nb,
                           (unsigned long long)m->info.npages);
    return HD_OK;
}

hd_status hd_pmap_foreach(hd_pmap *m, uint32_t src, hd_photon_fn fn, void *ctx)
{
    if (src >= m->info.nsources) return hd_fail(HD_ERR_RANGE, "source %u out of range", src);
    const hd_pmap_source *S = &m->src[src];
    for (uint64_t p = S->first_page; p < S->first_page + S->npages; p++) {
        const pm_page *pg;
        hd_status st = pm_page_get(m, p, &pg);
        if (st) return st;
        for (uint32_t i = 0; i < pg->count; i++) {
            hd_photon ph;
            ph.p = hd_v3(pg->pos[3 * i], pg->pos[3 * i + 1], pg->pos[3 * i + 2]);
            float nv[3], wv[3];
            pm_nrm_decode(pg->ncode[i], nv);
            pm_rgbe_decode(pg->wcode[i], wv);
            ph.n = hd_v3(nv[0], nv[1], nv[2]);
            ph.dir = hd_pmap_oct_decode(pg->dir[i]);
            for (int k = 0; k < 3; k++) ph.w[k] = wv[k];
            ph.src = src;
            ph.direct = pg->flags[i] & PM_F_DIRECT;
            if (fn(ctx, &ph)) { pm_page_release(m, p); return HD_OK; }
        }
        pm_page_release(m, p);
    }
    return HD_OK;
}

/* The value of header line NAME= of a map's text header, up to the line's end, or NULL. */
static const char *pm_header_value(const hd_pmap *m, const char *name, size_t *len)
{
    size_t nl = strlen(name);
    for (const char *p = m->header_text; p && *p;) {
        const char *e = strchr(p, '\n');
        size_t ll = e ? (size_t)(e - p) : strlen(p);
        if (ll >= nl && !memcmp(p, name, nl)) {
            const char *v = p + nl;
            while (*v == ' ') v++;
            *len = ll - (size_t)(v - p);
            return v;
        }
        p = e ? e + 1 : NULL;
    }
    return NULL;
}

/* Shards written by mkpmap -apH carry "PMAPSHARD= k n" and "PMAPRUN= photons seed scene-crc":
 * the pieces of one merge must all be shards of the same run, each k of 0..n-1 exactly once. */
static hd_status pm_check_shards(hd_pmap **m, const char *const *inputs, int n)
{
    size_t l0, l;
    const char *run0 = pm_header_value(m[0], "PMAPRUN=", &l0);
    int have = 0, ns = 0;
    char *seen = NULL;
    hd_status st = HD_OK;
    for (int i = 0; i < n && !st; i++) {
        const char *sh = pm_header_value(m[i], "PMAPSHARD=", &l);
        if (!sh) {
            if (have) st = hd_fail(HD_ERR_FORMAT, "%s: not a shard (no PMAPSHARD= line), %s is one", inputs[i], inputs[0]);
            continue;
        }
        if (i > 0 && !have)
            return hd_fail(HD_ERR_FORMAT, "%s: a shard (PMAPSHARD=), %s is not one", inputs[i], inputs[0]);
        have = 1;
        long k = -1, nk = -1;
        if (sscanf(sh, "%ld %ld", &k, &nk) != 2 || nk < 1 || nk > 1000000 || k < 0 || k >= nk)
            st = hd_fail(HD_ERR_FORMAT, "%s: header line PMAPSHARD=: expected shard k of n (0 <= k < n)", inputs[i]);
        else if (i == 0) {
            ns = (int)nk;
            seen = hd_calloc((size_t)ns, 1);
            if (!seen) st = HD_ERR_NOMEM;
        } else if (nk != ns)
            st = hd_fail(HD_ERR_FORMAT, "%s: shard %ld of %ld, %s is a shard of %d", inputs[i], k, nk, inputs[0], ns);
        if (st) break;
        const char *run = pm_header_value(m[i], "PMAPRUN=", &l);
        if (!run || !run0 || l != l0 || memcmp(run, run0, l) != 0)
            st = hd_fail(HD_ERR_FORMAT, "%s: a shard of another run than %s (photon count, seed or scene differ: "
                         "PMAPRUN= %.*s against %.*s)", inputs[i], inputs[0], run ? (int)l : 4, run ? run : "none",
                         run0 ? (int)l0 : 4, run0 ? run0 : "none");
        else if (seen[k])
            st = hd_fail(HD_ERR_FORMAT, "%s: shard %ld of %d is given twice", inputs[i], k, ns);
        else
            seen[k] = 1;
    }
    for (int k = 0; !st && have && k < ns; k++)
        if (!seen[k]) st = hd_fail(HD_ERR_FORMAT, "shard %d of %d is missing (merging %d file%s)", k, ns, n, n > 1 ? "s" : "");
    free(seen);
    return st;
}

hd_status hd_pmap_merge(const char *const *inputs, int n, const char *path, const char *header_lines)
{
    if (n < 1) return hd_fail(HD_ERR_USAGE, "nothing to merge");
    hd_pmap **m = hd_calloc((size_t)n, sizeof *m);
    if (!m) return HD_ERR_NOMEM;
    hd_status st = HD_OK;
    hd_pmap_source *tab = NULL;
    pm_writer *w = NULL;
    for (int i = 0; i < n && !st; i++) st = hd_pmap_open(&m[i], inputs[i], 1);
    if (st) goto done;
    if ((st = pm_check_shards(m, inputs, n))) goto done;
    const hd_pmap_info *I0 = &m[0]->info;
    for (int i = 1; i < n; i++) {
        const hd_pmap_info *I = &m[i]->info;
        if (I->nsources != I0->nsources || I->page_photons != I0->page_photons || I->size != I0->size ||
            I->org.x != I0->org.x || I->org.y != I0->org.y || I->org.z != I0->org.z) {
            st = hd_fail(HD_ERR_FORMAT, "%s: not a shard of the same scene and settings as %s", inputs[i], inputs[0]);
            goto done;
        }
        for (uint32_t s = 0; s < I->nsources; s++)
            if (strcmp(m[i]->src[s].modifier, m[0]->src[s].modifier) != 0) {
                st = hd_fail(HD_ERR_FORMAT, "%s: source %u is %s, %s has %s", inputs[i], s, m[i]->src[s].modifier,
                             inputs[0], m[0]->src[s].modifier);
                goto done;
            }
    }
    tab = hd_calloc(I0->nsources ? I0->nsources : 1, sizeof *tab);
    if (!tab) { st = HD_ERR_NOMEM; goto done; }
    if ((st = pm_writer_open(&w, path, header_lines, I0->nsources, I0->page_photons, I0->org, I0->size, 1))) goto done;
    for (uint32_t s = 0; s < I0->nsources; s++) {
        int from = -1;
        for (int i = 0; i < n; i++)
            if (m[i]->src[s].emitted) {
                if (from >= 0) {
                    st = hd_fail(HD_ERR_FORMAT, "source %s was traced in both %s and %s", m[i]->src[s].modifier,
                                 inputs[from], inputs[i]);
                    goto done;
                }
                from = i;
            }
        tab[s] = m[from >= 0 ? from : 0]->src[s];
        if (from < 0) continue;
        const hd_pmap_source *S = &m[from]->src[s];
        for (uint64_t p = S->first_page; p < S->first_page + S->npages; p++) {
            const pm_page_ent *e = &m[from]->pages[p];
            unsigned char *c = hd_malloc(e->csize ? e->csize : 1);
            if (!c) { st = HD_ERR_NOMEM; goto done; }
            st = pread_all(m[from], c, e->csize, m[from]->base + e->offset, "photon page");
            if (!st && hd_pmap_crc32(0, c, e->csize) != e->crc)
                st = hd_fail(HD_ERR_FORMAT, "%s: page %llu: checksum mismatch (corrupt file)", inputs[from],
                             (unsigned long long)p);
            if (!st) st = pm_writer_add_raw(w, e, c);
            free(c);
            if (st) goto done;
        }
    }
    st = pm_writer_close(w, tab, NULL);
    w = NULL;
done:
    if (w) pm_writer_abort(w);
    free(tab);
    for (int i = 0; i < n; i++) hd_pmap_close(m[i]);
    free(m);
    return st;
}

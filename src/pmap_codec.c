/* heliodon — photon-map file, the codec: CRC-32, Morton keys, octahedral
 * normals, RGBE weights, page coding (records <-> compressed bytes) and the
 * kd-tree of a decoded page.  Layout documented in docs/design/pmap.md;
 * the writer is pmap_write.c, the reader and its page cache pmap_read.c. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <zlib.h>

#include "pmap_internal.h"

#define QBITS 21

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
uint16_t hd_pmap_oct_encode(hd_vec3 v) { return pm_oct_encode(v); }
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

void pm_key_to_pos(uint64_t key, hd_vec3 org, double size, float p[3])
{
    uint32_t x, y, z;
    hd_pmap_unmorton(key, &x, &y, &z);
    double s = size / pm_quant_scale();
    p[0] = (float)(org.x + (x + 0.5) * s);
    p[1] = (float)(org.y + (y + 0.5) * s);
    p[2] = (float)(org.z + (z + 0.5) * s);
}

/* ---- page coding ---- */
size_t pm_page_encode_into(const pm_rec *r, uint32_t n, unsigned char *b, size_t *keylen)
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
        pm_key_to_pos(key, org, size, tpos[i].p);
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


/* heliodon — photon-map file, the writer: pages compressed in groups on
 * the thread pool, written in order with the page table, the sources and
 * the header; shard merging (mkpmap -apJ).  Layout in docs/design/pmap.md. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/parallel.h"
#include "pmap_internal.h"

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
    hd_header h;
    hd_header_init(&h);
    size_t hn = 0;
    st = hd_header_append_lines(&h, header_lines);
    if (!st) st = hd_header_add_software(&h);
    if (!st) st = hd_header_put(w->fp, &h, NULL, "heliodon_contrib_pmap", &hn);
    hd_header_free(&h);
    if (st) {
        pm_writer_abort(w);
        return hd_fail_context(st, "%s", hd_ofile_name(w->of));
    }
    w->offset += hn;
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
        size_t kl, rl = pm_page_encode_into(p->recs, p->n, z->raw, &kl);
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
            pm_key_to_pos(lo0 | lo1 | lo2, w->org, w->size, p->lo);
            pm_key_to_pos(hi0 | hi1 | hi2, w->org, w->size, p->hi);
        }
    }
    return HD_OK;
}

/* Append page e (its offset set here) and its compressed bytes to the file. */
static hd_status append_page(pm_writer *w, const pm_page_ent *e, const unsigned char *comp)
{
    if (HD_GROW(w->pages, w->npages + 1, w->cappages, 256)) return HD_ERR_NOMEM;
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
            st = pm_pread_all(m[from], c, e->csize, m[from]->base + e->offset, "photon page");
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

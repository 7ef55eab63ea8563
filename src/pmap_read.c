/* heliodon — photon-map file, the reader: open and check a map, the page
 * trees, the LRU page cache shared by the lookups (pm_page_get), verify
 * and foreach.  Layout in docs/design/pmap.md. */
#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

#include "pmap_internal.h"

/* ---- reader ---- */
/* arena bytes of a decoded page of n photons: its header, then its block */
#define PM_PAGE_HDR_BYTES ((sizeof(pm_page) + 63) & ~(size_t)63)
static size_t pm_arena_bytes(uint32_t n) { return PM_PAGE_HDR_BYTES + pm_page_block_bytes(n); }

hd_status pm_pread_all(hd_pmap *m, void *buf, size_t n, uint64_t off, const char *what)
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

/* A block of the file (what: named in messages) that ends with the CRC-32
 * of the rest: len bytes at off into a new buffer *out, checked. */
static hd_status read_checked(hd_pmap *m, const char *path, uint64_t off, size_t len, const char *what,
                              unsigned char **out)
{
    unsigned char *b = hd_malloc(len ? len : 1);
    if (!b) return HD_ERR_NOMEM;
    hd_status st = pm_pread_all(m, b, len, off, what);
    if (!st && (len < 4 || hd_pmap_crc32(0, b, len - 4) != pm_get32(b + len - 4)))
        st = hd_fail(HD_ERR_FORMAT, "%s: byte %llu: %s checksum mismatch (corrupt file)", path,
                     (unsigned long long)off, what);
    if (st) { free(b); return st; }
    *out = b;
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
    if ((st = pm_pread_all(m, h, sizeof h, hoff, "binary header"))) { hd_pmap_close(m); return st; }
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
    unsigned char *t;
    if ((st = read_checked(m, path, hoff + tab_off, tab_len, "source table", &t))) { hd_pmap_close(m); return st; }
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
    unsigned char *ib;
    if ((st = read_checked(m, path, hoff + idx_off, idx_len, "page index", &ib))) { hd_pmap_close(m); return st; }
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

uint64_t hd_pmap_cache_evictions(const hd_pmap *m) { return m->evictions; }

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
        if (HD_GROW(m->chunk, m->nchunk + 1, m->capchunk, 16)) return NULL;
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
    if ((st = pm_pread_all(m, sc->c, e->csize, m->base + e->offset, "photon page"))) goto done;
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
    m->evictions++;
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

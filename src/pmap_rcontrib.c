/* heliodon — rcontrib -ap: photon-map contributions (see pmap_rcontrib.h). */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "heliodon/exr.h"
#include "heliodon/io.h"
#include "heliodon/material.h"
#include "heliodon/matrix.h"
#include "heliodon/parallel.h"
#include "heliodon/picture.h"
#include "pmprimary.h"
#include "heliodon/pmap.h"
#include "heliodon/pmap_rcontrib.h"
#include "heliodon/rcmerge.h"
#include "progress.h"
#include "heliodon/rng.h"
#include "heliodon/trace.h"
#include "pmap_internal.h"

static void drop(int *argc, char **argv, int i, int n)
{
    for (int k = i; k + n <= *argc; k++) argv[k] = argv[k + n];
    *argc -= n;
}

static int is_number(const char *s)
{
    double v;
    return s && hd_parse_double(s, &v) == 0;
}

hd_status hd_pmap_rc_extract(int *argc, char **argv, hd_pmap_rc_opts *po)
{
    memset(po, 0, sizeof *po);
    po->cache = 4000000;
    po->exact_direct = 1;
    static char one[] = "1";
    for (int i = 1; i < *argc;) {
        const char *a = argv[i];
        if (!strcmp(a, "-ap")) {
            if (i + 1 >= *argc) return hd_fail(HD_ERR_USAGE, "-ap: expected a photon map file");
            po->file = argv[i + 1];
            int n = 2;
            po->bw = 0;
            if (i + 2 < *argc && is_number(argv[i + 2])) {
                hd_parse_double(argv[i + 2], &po->bw);
                n = 3;
                if (i + 3 < *argc && is_number(argv[i + 3]) && argv[i + 3][0] != '-') {
                    hd_parse_double(argv[i + 3], &po->bw2);
                    n = 4;
                }
            }
            drop(argc, argv, i, n);
        } else if (!strcmp(a, "-aC") || !strcmp(a, "-ac") || !strcmp(a, "-am")) {
            if (i + 1 >= *argc) return hd_fail(HD_ERR_USAGE, "%s: expected a value", a);
            if (!strcmp(a, "-aC")) {
                if (hd_parse_count(argv[i + 1], &po->cache))
                    return hd_fail(HD_ERR_USAGE, "-aC %s: expected a photon count (k/m/g suffixes)", argv[i + 1]);
            } else if (hd_parse_double(argv[i + 1], !strcmp(a, "-ac") ? &po->ac : &po->am)) {
                return hd_fail(HD_ERR_USAGE, "%s %s: expected a number", a, argv[i + 1]);
            }
            drop(argc, argv, i, 2);
        } else if (!strncmp(a, "-apd", 4) && (!a[4] || ((a[4] == '+' || a[4] == '-') && !a[5]))) {
            po->exact_direct = a[4] != '-';
            drop(argc, argv, i, 1);
        } else if (!strcmp(a, "-apR")) {
            long r0, nr;
            if (i + 2 >= *argc || hd_parse_long(argv[i + 1], &r0) || hd_parse_long(argv[i + 2], &nr) || r0 < 0 ||
                nr < 0)
                return hd_fail(HD_ERR_USAGE, "-apR: expected first record and record count (>= 0)");
            po->row0 = (uint64_t)r0;
            po->nrows = (uint64_t)nr;
            drop(argc, argv, i, 3);
        } else if (!strcmp(a, "-ab") && i + 1 < *argc) {
            long v;
            if (!hd_parse_long(argv[i + 1], &v)) {
                po->ab = (int)v;
                po->ab_given = 1;
                if (v < 0) argv[i + 1] = one;
            }
            i += 2;
        } else {
            i++;
        }
    }
    return HD_OK;
}

/* ---- per-modifier source lists and bins ---- */
typedef struct rcmod {
    uint32_t *src;
    int nsrc;
} rcmod;

typedef struct binctx { const hd_binfn *b; } binctx;
static int binfn_cb(void *ctx, uint32_t src, hd_vec3 from)
{
    (void)src;
    const binctx *bc = ctx;
    int b = hd_binfn_eval(bc->b, from, 0.5, 0.5);
    return b >= 0 && b < bc->b->nbins ? b : -1;
}

struct outset;
static void spool_encode(struct outset *os, int q, const double *out, size_t nrec, size_t us, size_t cs);

typedef struct rcjob {
    const hd_contrib *c;
    const hd_rcontrib_opts *o;
    const hd_pmap_rc_opts *po;
    hd_pmap *m;
    rcmod *mods;
    hd_pmap_lookup **lk;      /* per worker */
    double **tmp;             /* per worker, 3 * max bins */
    const hd_vec3 *org, *dir;
    uint64_t rec0;            /* global record index of the first record of the batch */
    int per;
    size_t rlen;
    double *out;
    /* value (record u, column c) at out + u * us + c * cs: record-major
     * (us = rlen, cs = 3), or column-major for pictures at -ab < 0 (us = 3,
     * cs = 3 x batch: a source's column is written contiguously) */
    size_t us, cs;
    /* column-major pictures: each worker zeroes its modifiers' columns and,
     * once they are complete, encodes them into the spool block (stream
     * colstream[col]) */
    struct outset *os;
    const int *colstream;
    double **colbuf;          /* per worker: 3 x batch doubles per bin of one modifier */
    /* source-major -ab < 0 */
    hd_pmprim *gpp;           /* primary hit of every ray of the batch */
    size_t nrec;              /* records in the batch */
    /* coherent groups of lookup points (same normal, nearby): point ids
     * (ray index * HD_PMPRIM_PTS + point) in group order, group starts */
    uint32_t *gid;
    size_t *gstart, ngroups;
    hd_vec3 *gpt, *gn;        /* lookup points in group order, normal of each group */
    uint8_t *pnpt, *pnana;    /* per ray: lookup points, analytic records */
    double *pf;               /* per point id: the weight f[3] of its irradiance */
    double **gval;            /* per worker: 3 values per point id */
} rcjob;

/* Analytic part (pmap_primary.c) of source S for the ray resolved in pp,
 * added to the source's direction bin. */
static void add_analytic(const rcjob *j, const hd_cmod *cm, binctx *bc, uint32_t s, const hd_pmap_source *S,
                         const hd_pmprim *pp, double *rec, size_t cs, size_t col0)
{
    if (!pp->nana || !j->po->exact_direct) return;
    double d[3] = {0, 0, 0};
    if (!hd_pmprim_direct(j->c->ts, pp, S->dir, S->half_angle, j->c->o.ss, d)) return;
    int b = cm->bin.kind == HD_BIN_CONST ? 0 : binfn_cb(bc, s, S->dir);
    if (b < 0) return;
    for (int q = 0; q < 3; q++) {
        double v = d[q];
        if (j->c->vflag) v *= S->radiance[q];
        rec[cs * (col0 + (size_t)b) + q] += v;
    }
}

/* Coefficients of the ray resolved in pp into rec: irradiance at each lookup
 * point (scaled by its weight per channel) plus the analytic terms. */
static hd_status gather_ray(rcjob *j, int w, const hd_pmprim *pp, hd_rng *rng, double *rec)
{
    const hd_contrib *c = j->c;
    double *tmp = j->tmp[w];
    for (int mi = 0; mi < c->nmods; mi++) {
        const hd_cmod *cm = &c->mods[mi];
        int nb = cm->bin.nbins > 0 ? cm->bin.nbins : 1;
        binctx bc = {&cm->bin};
        for (int k = 0; k < j->mods[mi].nsrc; k++) {
            uint32_t s = j->mods[mi].src[k];
            const hd_pmap_source *S = hd_pmap_get_source(j->m, s);
            for (int t = 0; t < pp->npt; t++) {
                hd_vec3 p = pp->pt[t].p, n = pp->pt[t].n;
                const double *f = pp->pt[t].f;
                memset(tmp, 0, sizeof(double) * 3 * (size_t)nb);
                hd_status st;
                if (j->po->ab < 0) {
                    st = cm->bin.kind == HD_BIN_CONST ? hd_pmap_irradiance(j->lk[w], s, p, n, tmp, NULL, NULL)
                                                      : hd_pmap_irradiance(j->lk[w], s, p, n, tmp, binfn_cb, &bc);
                } else {
                    double e[3];
                    st = hd_pmap_final_gather(j->lk[w], c->ts, s, p, n, c->o.ad, rng, e);
                    int b = binfn_cb(&bc, s, S->dir);
                    if (!st && b >= 0) for (int q = 0; q < 3; q++) tmp[3 * b + q] += e[q];
                }
                if (st) return st;
                for (int b = 0; b < nb; b++)
                    for (int q = 0; q < 3; q++) {
                        double v = tmp[3 * b + q] * f[q];
                        if (c->vflag) v *= S->radiance[q];
                        rec[3 * ((size_t)cm->first + (size_t)b) + q] += v;
                    }
            }
            add_analytic(j, cm, &bc, s, S, pp, rec, 3, (size_t)cm->first);
        }
    }
    return HD_OK;
}

/* The primary hit of a ray (pmap_primary.c): the -I point, or the diffuse
 * lookups behind glass / mirrors (f = scale x path weight, x rho_d / pi for
 * radiance) and the analytic records (specular highlights, BSDF data, rays
 * escaping towards a source).  -apd- (Radiance's behaviour) follows glass
 * transmission only. */
static int resolve_ray(const rcjob *j, hd_vec3 org, hd_vec3 dir, double scale, hd_pmprim *pp)
{
    int depth = j->po->exact_direct ? 2 : 0;
    return hd_pmap_primary(j->c->ts, org, dir, j->o->irrad, scale, depth, 1e-4, pp);
}

static hd_status trace_ray(rcjob *j, int w, hd_vec3 org, hd_vec3 dir, double scale, hd_rng *rng, double *rec)
{
    hd_pmprim pp;
    if (!resolve_ray(j, org, dir, scale, &pp)) return HD_OK;
    return gather_ray(j, w, &pp, rng, rec);
}

/* -ab < 0, source-major: first the lookup points of a batch, then for each
 * source all records (the pages of one source stay in the cache; per record
 * the columns receive their terms in the same order as gather_point). */
static hd_status rc_points(void *ctx, size_t b, size_t e, size_t ci, int w)
{
    (void)ci; (void)w;
    rcjob *j = ctx;
    for (size_t u = b; u < e; u++) {
        if (!j->colstream) memset(j->out + u * j->rlen, 0, j->rlen * sizeof(double));   /* record-major only */
        for (int k = 0; k < j->per; k++) {
            size_t idx = u * (size_t)j->per + (size_t)k;
            const hd_pmprim *pp = &j->gpp[idx];
            resolve_ray(j, j->org[idx], j->dir[idx], 1.0 / j->per, &j->gpp[idx]);
            if (j->pf) {   /* compact copies for the per-source accumulation */
                j->pnpt[idx] = (uint8_t)pp->npt;
                j->pnana[idx] = (uint8_t)(pp->nana > 0);
                for (int t = 0; t < pp->npt; t++) memcpy(j->pf + 3 * (idx * HD_PMPRIM_PTS + (size_t)t), pp->pt[t].f, 3 * sizeof(double));
            }
        }
    }
    return HD_OK;
}

/* All records of the batch for source src of modifier mi (worker w). */
static hd_status source_records(rcjob *j, int w, int mi, uint32_t src)
{
    const hd_cmod *cm = &j->c->mods[mi];
    int nb = cm->bin.nbins > 0 ? cm->bin.nbins : 1;
    binctx bc = {&cm->bin};
    const hd_pmap_source *S = hd_pmap_get_source(j->m, src);
    double *tmp = j->tmp[w];
    /* columns: the modifier's own buffer (column-major pictures) or out */
    double *ob = j->colstream ? j->colbuf[w] : j->out;
    size_t cf = j->colstream ? 0 : (size_t)cm->first;
    if (cm->bin.kind == HD_BIN_CONST && j->gid) {
        /* coherent groups: every point's irradiance first, then the same
         * accumulation order as below (bit-identical records) */
        double *gv = j->gval[w];
        for (size_t g = 0; g < j->ngroups; g++) {
            size_t b = j->gstart[g], e = j->gstart[g + 1];
            double *gout = gv + 3 * j->nrec * (size_t)j->per * HD_PMPRIM_PTS;   /* scratch after the ids */
            hd_status st = hd_pmap_irradiance_group(j->lk[w], src, j->gpt + b, e - b, j->gn[g], gout);
            if (st) return st;
            for (size_t i = b; i < e; i++) memcpy(gv + 3 * (size_t)j->gid[i], gout + 3 * (i - b), 3 * sizeof(double));
        }
        for (size_t u = 0; u < j->nrec; u++) {
            double *rec = ob + u * j->us;
            for (int k = 0; k < j->per; k++) {
                size_t idx = u * (size_t)j->per + (size_t)k;
                for (int t = 0; t < j->pnpt[idx]; t++) {
                    const double *v3 = gv + 3 * (idx * HD_PMPRIM_PTS + (size_t)t);
                    const double *f = j->pf + 3 * (idx * HD_PMPRIM_PTS + (size_t)t);
                    for (int q = 0; q < 3; q++) {
                        double v = v3[q] * f[q];
                        if (j->c->vflag) v *= S->radiance[q];
                        rec[j->cs * cf + q] += v;
                    }
                }
                if (j->pnana[idx]) add_analytic(j, cm, &bc, src, S, &j->gpp[idx], rec, j->cs, cf);
            }
        }
        return HD_OK;
    }
    for (size_t u = 0; u < j->nrec; u++) {
        double *rec = ob + u * j->us;
        for (int k = 0; k < j->per; k++) {
            size_t idx = u * (size_t)j->per + (size_t)k;
            const hd_pmprim *pp = &j->gpp[idx];
            for (int t = 0; t < pp->npt; t++) {
                memset(tmp, 0, sizeof(double) * 3 * (size_t)nb);
                hd_status st = cm->bin.kind == HD_BIN_CONST
                                   ? hd_pmap_irradiance(j->lk[w], src, pp->pt[t].p, pp->pt[t].n, tmp, NULL, NULL)
                                   : hd_pmap_irradiance(j->lk[w], src, pp->pt[t].p, pp->pt[t].n, tmp, binfn_cb, &bc);
                if (st) return st;
                const double *f = pp->pt[t].f;
                for (int bb = 0; bb < nb; bb++)
                    for (int q = 0; q < 3; q++) {
                        double v = tmp[3 * bb + q] * f[q];
                        if (j->c->vflag) v *= S->radiance[q];
                        rec[j->cs * (cf + (size_t)bb) + q] += v;
                    }
            }
            add_analytic(j, cm, &bc, src, S, pp, rec, j->cs, cf);
        }
    }
    return HD_OK;
}

/* ---- coherent groups of lookup points ----
 * The batch's lookup points sorted by (normal, Morton code of the
 * position); a group is a run with the same normal in one cell of about
 * the search radius, at most GROUP_MAX points.  Groups only change which
 * photons one traversal collects, never a result. */
#ifndef GROUP_MAX
#define GROUP_MAX 64
#endif
#ifndef GCELLF
#define GCELLF 2.5    /* group extent: GCELLF x the mean k-th distance (h-gather3: 1.0 -> 1.75, -7 % instructions;
                       * session 5, with the cheap AVX-512 per-point filter: 1.75 -> 2.5, -7 % CPU at 256^2) */
#endif

typedef struct gkey { uint32_t nb[3]; uint32_t id; uint64_t key; } gkey;

static int gkey_cmp(const void *a, const void *b)
{
    const gkey *x = a, *y = b;
    for (int k = 0; k < 3; k++) if (x->nb[k] != y->nb[k]) return x->nb[k] < y->nb[k] ? -1 : 1;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->id < y->id ? -1 : x->id > y->id;
}

static uint32_t fbits(double v)
{
    float f = (float)v;
    uint32_t u;
    memcpy(&u, &f, 4);
    return u;
}

static hd_status build_groups(rcjob *j, const hd_pmap_info *I, double cell)
{
    size_t nray = j->nrec * (size_t)j->per, npt = 0;
    for (size_t r = 0; r < nray; r++) npt += (size_t)j->gpp[r].npt;
    j->ngroups = 0;
    if (!npt) { j->gstart[0] = 0; return HD_OK; }
    gkey *g = hd_malloc_array(npt, sizeof *g);
    if (!g) return HD_ERR_NOMEM;
    double sc = 2097152.0 / I->size;
    size_t n = 0;
    for (size_t r = 0; r < nray; r++)
        for (int t = 0; t < j->gpp[r].npt; t++) {
            const hd_pmprim_point *pt = &j->gpp[r].pt[t];
            double v[3] = {(pt->p.x - I->org.x) * sc, (pt->p.y - I->org.y) * sc, (pt->p.z - I->org.z) * sc};
            uint32_t qv[3];
            for (int k = 0; k < 3; k++) qv[k] = v[k] < 0 ? 0 : v[k] > 2097151 ? 2097151 : (uint32_t)v[k];
            g[n].nb[0] = fbits(pt->n.x); g[n].nb[1] = fbits(pt->n.y); g[n].nb[2] = fbits(pt->n.z);
            g[n].id = (uint32_t)(r * HD_PMPRIM_PTS + (size_t)t);
            g[n].key = hd_pmap_morton(qv[0], qv[1], qv[2]);
            n++;
        }
    qsort(g, n, sizeof *g, gkey_cmp);
    /* greedy in Morton order: a group ends at a new normal, at GROUP_MAX
     * points, or at a point farther than the cell size from its first */
    size_t ng = 0;
    hd_vec3 first = hd_v3(0, 0, 0);
    double c2 = cell * cell;
    for (size_t i = 0; i < n; i++) {
        hd_vec3 pi = j->gpp[g[i].id / HD_PMPRIM_PTS].pt[g[i].id % HD_PMPRIM_PTS].p;
        int cut = i == 0 || i - j->gstart[ng - 1] >= GROUP_MAX || memcmp(g[i].nb, g[i - 1].nb, sizeof g[i].nb);
        if (!cut) {
            hd_vec3 d = hd_vsub(pi, first);
            cut = hd_vdot(d, d) > c2;
        }
        if (cut) {
            j->gn[ng] = j->gpp[g[i].id / HD_PMPRIM_PTS].pt[g[i].id % HD_PMPRIM_PTS].n;
            j->gstart[ng++] = i;
            first = pi;
        }
        j->gid[i] = g[i].id;
        j->gpt[i] = pi;
    }
    j->gstart[ng] = n;
    j->ngroups = ng;

    free(g);
    return HD_OK;
}

/* -ab < 0: workers take whole modifiers (their columns are disjoint), each
 * source for all records of the batch (the source's pages stay in the
 * cache, and one barrier per batch instead of one per source). */
static hd_status rc_mods(void *ctx, size_t b, size_t e, size_t ci, int w)
{
    (void)ci;
    rcjob *j = ctx;
    for (size_t mi = b; mi < e; mi++) {
        const hd_cmod *cm = &j->c->mods[mi];
        size_t c0 = (size_t)cm->first, nb = (size_t)(cm->bin.nbins > 0 ? cm->bin.nbins : 1);
        if (j->colstream)   /* the worker's column buffer (stays in cache from one modifier to the next) */
            for (size_t b2 = 0; b2 < nb; b2++) memset(j->colbuf[w] + b2 * j->cs, 0, 3 * j->nrec * sizeof(double));
        for (int k = 0; k < j->mods[mi].nsrc; k++) {
            uint32_t src = j->mods[mi].src[k];
            if (!hd_pmap_get_source(j->m, src)->npages) continue;
            hd_status st = source_records(j, w, (int)mi, src);
            if (st) return st;
        }
        if (j->colstream)
            for (size_t b2 = 0; b2 < nb; b2++)
                if (j->colstream[c0 + b2] >= 0)
                    spool_encode(j->os, j->colstream[c0 + b2], j->colbuf[w] + b2 * j->cs, j->nrec, 3, 0);
    }
    return HD_OK;
}

static hd_status rc_units(void *ctx, size_t b, size_t e, size_t ci, int w)
{
    (void)ci;
    rcjob *j = ctx;
    for (size_t u = b; u < e; u++) {
        double *rec = j->out + u * j->rlen;
        memset(rec, 0, j->rlen * sizeof *rec);
        for (int k = 0; k < j->per; k++) {
            size_t idx = u * (size_t)j->per + (size_t)k;
            hd_rng rng;
            hd_rng_init(&rng, j->c->o.seed, (j->rec0 + u) * (uint64_t)j->per + (uint64_t)k);
            hd_status st = trace_ray(j, w, j->org[idx], j->dir[idx], 1.0 / j->per, &rng, rec);
            if (st) return st;
        }
    }
    return HD_OK;
}

/* ---- output streams ----
 * As in backward mode: one stream per -o name (per modifier with %s, per
 * bin with %d).  Pictures (-fc) are not held in memory: every batch of
 * records appends each picture's pixels (RGBE, or float for .exr names) to
 * an anonymous spool file, and the pictures are written one at a time at
 * the end, so memory does not grow with the number of modifiers. */
typedef struct ostream {
    char name[1024];          /* "" = standard output */
    hd_ofile *of;
    FILE *fp;
    int *cols, ncols;
    int mod, multimod, has_s, has_d;
    long bin;
    int exr;                  /* picture written as OpenEXR (name ends in .exr) */
    size_t esz, soff;         /* spool bytes per pixel, offset per record within a batch block */
    hd_mtxwriter w;           /* matrix output (-fa, -ff, -fd) */
} ostream;

typedef struct outset {
    ostream *s;
    int n, cap;
    int spool_fd;
    size_t rec_bytes;         /* spool bytes per record (all picture streams) */
    uint64_t *boff, *bn;      /* spool blocks: file offset, records */
    size_t nblk, capblk;
    unsigned char *blk;       /* one block being written */
} outset;

static ostream *find_stream(outset *os, const char *name)
{
    for (int i = 0; i < os->n; i++) if (!strcmp(os->s[i].name, name)) return &os->s[i];
    if (os->n == os->cap) {
        int nc = os->cap ? 2 * os->cap : 16;
        ostream *p = hd_realloc_array(os->s, (size_t)nc, sizeof *p);
        if (!p) return NULL;
        os->s = p;
        os->cap = nc;
    }
    ostream *s = &os->s[os->n++];
    memset(s, 0, sizeof *s);
    s->mod = -1;
    hd_strlcpy(s->name, name, sizeof s->name);
    return s;
}

static hd_status add_col(ostream *s, int mod, int col)
{
    int *p = hd_realloc_array(s->cols, (size_t)s->ncols + 1, sizeof *p);
    if (!p) return HD_ERR_NOMEM;
    s->cols = p;
    s->cols[s->ncols++] = col;
    if (s->mod < 0) s->mod = mod;
    else if (s->mod != mod) s->multimod = 1;
    return HD_OK;
}

static int ends_with(const char *s, const char *suf)
{
    size_t a = strlen(s), b = strlen(suf);
    return a >= b && !strcmp(s + a - b, suf);
}

static hd_status build_streams(const hd_contrib *c, outset *os)
{
    char name[1024];
    for (int mi = 0; mi < c->nmods; mi++) {
        const hd_cmod *cm = &c->mods[mi];
        int nb = cm->bin.nbins > 0 ? cm->bin.nbins : 1;
        int kind = cm->outspec ? hd_pattern_kind(cm->outspec) : 0;
        if (kind < 0) return HD_ERR_USAGE;
        for (int b = 0; b < nb; b++) {
            hd_status st;
            if (!cm->outspec) name[0] = 0;
            else if ((st = hd_pattern_format(name, sizeof name, cm->outspec, kind & 2 ? cm->name : NULL, kind & 1 ? b : 0)))
                return st;
            ostream *s = find_stream(os, name);
            if (!s) return HD_ERR_NOMEM;
            s->has_s = (kind & 2) != 0;
            if (kind & 1) { s->has_d = 1; s->bin = b; }
            if ((st = add_col(s, mi, cm->first + b))) return st;
        }
    }
    return HD_OK;
}

static hd_status spool_open(outset *os)
{
    const char *dir = getenv("TMPDIR");
    char path[4096];
    if (snprintf(path, sizeof path, "%s/hdpmapXXXXXX", dir && *dir ? dir : "/tmp") >= (int)sizeof path)
        return hd_fail(HD_ERR_RANGE, "TMPDIR too long");
    int fd = mkstemp(path);
    if (fd < 0) return hd_fail(HD_ERR_IO, "%s: cannot create the picture spool file: %s", path, strerror(errno));
    unlink(path);   /* anonymous: goes away with the process */
    os->spool_fd = fd;
    return HD_OK;
}

static hd_status pwrite_all(int fd, const void *b, size_t n, uint64_t off)
{
    size_t done = 0;
    while (done < n) {
        ssize_t r = pwrite(fd, (const char *)b + done, n - done, (off_t)(off + done));
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) return hd_fail(HD_ERR_IO, "picture spool file: write failed (disk full?): %s", strerror(errno));
        done += (size_t)r;
    }
    return HD_OK;
}

static hd_status pread_all(int fd, void *b, size_t n, uint64_t off)
{
    size_t done = 0;
    while (done < n) {
        ssize_t r = pread(fd, (char *)b + done, n - done, (off_t)(off + done));
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) return hd_fail(HD_ERR_IO, "picture spool file: read failed at byte %llu",
                                   (unsigned long long)(off + done));
        done += (size_t)r;
    }
    return HD_OK;
}

/* Picture stream q's pixels of records [0, nrec) of out, encoded into the
 * spool block. */
static void spool_encode(outset *os, int q, const double *out, size_t nrec, size_t us, size_t cs)
{
    ostream *s = &os->s[q];
    unsigned char *d = os->blk + s->soff * nrec;
    for (size_t r = 0; r < nrec; r++) {
        const double *v = out + r * us + cs * (size_t)s->cols[0];
        float f[3] = {(float)v[0], (float)v[1], (float)v[2]};
        if (s->exr) memcpy(d + 12 * r, f, 12);
        else hd_rgbe_encode(d + 4 * r, f[0], f[1], f[2]);
    }
}

/* Append the picture pixels of records [0, nrec) of out to the spool
 * (encoded = 1: the block is already filled by the workers). */
static hd_status spool_batch(outset *os, const double *out, size_t nrec, size_t us, size_t cs, int encoded)
{
    if (os->nblk == os->capblk) {
        size_t nc = os->capblk ? 2 * os->capblk : 64;
        uint64_t *a = hd_realloc_array(os->boff, nc, sizeof *a);
        if (!a) return HD_ERR_NOMEM;
        os->boff = a;
        uint64_t *b = hd_realloc_array(os->bn, nc, sizeof *b);
        if (!b) return HD_ERR_NOMEM;
        os->bn = b;
        os->capblk = nc;
    }
    uint64_t off = os->nblk ? os->boff[os->nblk - 1] + os->bn[os->nblk - 1] * os->rec_bytes : 0;
    if (!encoded)
        for (int q = 0; q < os->n; q++) spool_encode(os, q, out, nrec, us, cs);
    hd_status st = pwrite_all(os->spool_fd, os->blk, nrec * os->rec_bytes, off);
    if (st) return st;
    os->boff[os->nblk] = off;
    os->bn[os->nblk] = nrec;
    os->nblk++;
    return HD_OK;
}

static hd_status stream_header(const hd_contrib *c, const hd_rcontrib_opts *o, const ostream *s, const hd_header *hdr,
                               hd_header *h)
{
    hd_header_init(h);
    hd_status st = hd_header_copy(h, hdr);
    if (!st && o->fout != 'c') st = hd_header_append(h, "NCOMP=3");
    if (!st && (s->has_s || s->ncols == 1) && !s->multimod)
        st = hd_header_appendf(h, "MODIFIER=%s", c->mods[s->mod].name);
    if (!st && s->has_d) st = hd_header_appendf(h, "BIN=%ld", s->bin);
    return st;
}

/* Stream s's pixels of batch block b (esz spool bytes each) read into *seg,
 * grown as needed. */
static hd_status spool_block(const outset *os, const ostream *s, size_t b, size_t esz, unsigned char **seg,
                             size_t *segcap)
{
    size_t n = (size_t)os->bn[b];
    if (n * esz > *segcap) {
        free(*seg);
        *segcap = n * esz;
        *seg = hd_malloc(*segcap);
        if (!*seg) { *segcap = 0; return HD_ERR_NOMEM; }
    }
    return pread_all(os->spool_fd, *seg, n * esz, os->boff[b] + s->soff * n);
}

/* Write picture stream q from the spool (one picture in memory at a time
 * for EXR, one scanline for RGBE). */
static hd_status write_picture(const hd_contrib *c, const hd_rcontrib_opts *o, outset *os, int q, const hd_header *hdr)
{
    ostream *s = &os->s[q];
    int xr = o->xres, yr = o->yres;
    uint64_t npix = (uint64_t)xr * (uint64_t)yr;
    hd_header h;
    hd_status st = stream_header(c, o, s, hdr, &h);
    if (!st && !s->exr) st = hd_rcontrib_piece_line(o, &h);
    if (st) { hd_header_free(&h); return st; }
    unsigned char *seg = NULL;
    size_t segcap = 0;
    if (s->exr) {
        hd_exr_image img;
        hd_exr_init(&img);
        int ci[3];
        if (!(st = hd_exr_set_size(&img, xr, yr)) && !(st = hd_exr_add_channel(&img, "R", HD_EXR_FLOAT, &ci[0])) &&
            !(st = hd_exr_add_channel(&img, "G", HD_EXR_FLOAT, &ci[1])) &&
            !(st = hd_exr_add_channel(&img, "B", HD_EXR_FLOAT, &ci[2])) &&
            !(st = hd_exr_set_attr(&img, HD_EXR_HEADER_ATTR, h.text ? h.text : ""))) {
            img.has_chroma = 1;
            memcpy(img.chroma, hd_exr_chroma_radiance, sizeof img.chroma);
            uint64_t px = 0;
            for (size_t b = 0; b < os->nblk && !st && px < npix; b++) {
                size_t n = (size_t)os->bn[b];
                if ((st = spool_block(os, s, b, 12, &seg, &segcap))) break;
                for (size_t r = 0; r < n && px < npix; r++, px++) {
                    float f[3];
                    memcpy(f, seg + 12 * r, 12);
                    for (int k = 0; k < 3; k++) img.chan[ci[k]].data[px] = f[k];
                }
            }
            if (!st) st = hd_exr_save(s->name[0] ? s->name : "-", &img, HD_EXR_ZIP);
        }
        hd_exr_free(&img);
        hd_header_free(&h);
        free(seg);
        return st;
    }
    hd_ofile *of = NULL;
    FILE *fp = stdout;
    if (s->name[0]) {
        if ((st = hd_ofile_open(&of, s->name))) { hd_header_free(&h); return st; }
        fp = hd_ofile_fp(of);
    }
    size_t nw = 0;
    st = hd_header_write(fp, &h, &nw);
    hd_header_free(&h);
    if (!st) st = hd_header_write_format(fp, "32-bit_rle_rgbe", nw);
    if (!st) fprintf(fp, "-Y %8d +X %8d\n", yr, xr);   /* padded, as Radiance and backward mode */
    if (!st && o->ranged) {   /* a piece: its pixels flat (rcmerge encodes the scanlines) */
        npix = o->rec_count;
        uint64_t px = 0;
        for (size_t b = 0; b < os->nblk && !st && px < npix; b++) {
            size_t n = (size_t)os->bn[b];
            if ((st = spool_block(os, s, b, 4, &seg, &segcap))) break;
            if (n > npix - px) n = (size_t)(npix - px);
            if (fwrite(seg, 4, n, fp) != n) st = hd_fail(HD_ERR_IO, "%s: write failed: %s", s->name, strerror(errno));
            px += n;
        }
        if (!st && px < npix) st = hd_fail(HD_ERR_INTERNAL, "%s: %llu of %llu piece pixels", s->name,
                                            (unsigned long long)px, (unsigned long long)npix);
        npix = 0;   /* nothing left for the scanline loop */
    }
    unsigned char *line = hd_malloc_array((size_t)xr, 4);
    if (!line && !st) st = HD_ERR_NOMEM;
    uint64_t px = 0;
    int fill = 0;
    for (size_t b = 0; b < os->nblk && !st && px < npix; b++) {
        size_t n = (size_t)os->bn[b];
        if ((st = spool_block(os, s, b, 4, &seg, &segcap))) break;
        for (size_t r = 0; r < n && px < npix && !st; r++, px++) {
            memcpy(line + 4 * fill, seg + 4 * r, 4);
            if (++fill == xr) { st = hd_scanline_write(fp, line, xr); fill = 0; }
        }
    }
    if (!st && px < npix) {   /* input ended early: the rest stays black */
        memset(line + 4 * fill, 0, (size_t)(xr - fill) * 4);
        for (; px < npix && !st; px += (uint64_t)(xr - fill), fill = 0) {
            st = hd_scanline_write(fp, line, xr);
            memset(line, 0, (size_t)xr * 4);
        }
    }
    free(line);
    free(seg);
    if (of) {
        if (st) hd_ofile_abort(of);
        else st = hd_ofile_commit(of);
    } else if (!st) fflush(stdout);
    return st;
}

typedef struct wpjob {
    const hd_contrib *c;
    const hd_rcontrib_opts *o;
    outset *os;
    const hd_header *hdr;
} wpjob;

static hd_status write_pictures(void *ctx, size_t b, size_t e, size_t ci, int w)
{
    (void)ci; (void)w;
    wpjob *wj = ctx;
    for (size_t q = b; q < e; q++) {
        hd_status st = write_picture(wj->c, wj->o, wj->os, (int)q, wj->hdr);
        if (st) return st;
    }
    return HD_OK;
}

static hd_status read_ray(hd_raysrc *src, char fin, hd_vec3 *org, hd_vec3 *dir, int *eof)
{
    double v[6];
    *eof = 0;
    if (fin == 'a') {
        for (int k = 0; k < 6; k++) {
            int e = 0;
            hd_status st = hd_istream_real(src->in, &v[k], &e);
            if (st) return st;
            if (e) {
                if (k) return hd_fail(HD_ERR_FORMAT, "%s: incomplete ray at the end", hd_istream_name(src->in));
                *eof = 1;
                return HD_OK;
            }
        }
    } else if (fin == 'f') {
        float f[6];
        size_t n = hd_istream_read(src->in, f, sizeof f);
        if (n == 0) { *eof = 1; return HD_OK; }
        if (n != sizeof f) return hd_fail(HD_ERR_FORMAT, "%s: incomplete float ray", hd_istream_name(src->in));
        for (int k = 0; k < 6; k++) v[k] = f[k];
    } else {
        size_t n = hd_istream_read(src->in, v, sizeof v);
        if (n == 0) { *eof = 1; return HD_OK; }
        if (n != sizeof v) return hd_fail(HD_ERR_FORMAT, "%s: incomplete double ray", hd_istream_name(src->in));
    }
    *org = hd_v3(v[0], v[1], v[2]);
    *dir = hd_v3(v[3], v[4], v[5]);
    return HD_OK;
}

hd_status hd_pmap_rc_run(const hd_contrib *c, const hd_rcontrib_opts *o, hd_raysrc *src, const hd_header *hdr,
                         const hd_pmap_rc_opts *po)
{
    if (!src->in) return hd_fail(HD_ERR_UNSUPPORTED, "photon-map mode reads rays from a stream only");
    hd_pmap *m;
    hd_status st = hd_pmap_open(&m, po->file, po->cache);
    if (st) return st;
    const hd_pmap_info *I = hd_pmap_get_info(m);
    rcmod *mods = hd_calloc((size_t)c->nmods, sizeof *mods);
    outset os;
    memset(&os, 0, sizeof os);
    os.spool_fd = -1;
    rcjob j;
    memset(&j, 0, sizeof j);
    hd_progress *pr = NULL;
    hd_vec3 *org = NULL, *dir = NULL;
    double *out = NULL, *sum = NULL;
    int *colstream = NULL;
    unsigned char *keep = NULL;   /* -r: the stream's header is kept */
    int nth = hd_resolve_threads(o->nthreads);
    if (!mods) { hd_pmap_close(m); return HD_ERR_NOMEM; }
    uint32_t nactive = 0;
    int maxbins = 1;
    for (int mi = 0; mi < c->nmods; mi++) {
        mods[mi].src = hd_calloc(I->nsources ? I->nsources : 1, sizeof(uint32_t));
        if (!mods[mi].src) { st = HD_ERR_NOMEM; goto done; }
        for (uint32_t s = 0; s < I->nsources; s++)
            if (!strcmp(hd_pmap_get_source(m, s)->modifier, c->mods[mi].name)) {
                mods[mi].src[mods[mi].nsrc++] = s;
            }
        if (!mods[mi].nsrc) {
            st = hd_fail(HD_ERR_USAGE, "%s: modifier %s is not a light source of the photon map", po->file,
                         c->mods[mi].name);
            goto done;
        }
        if (c->mods[mi].bin.nbins > maxbins) maxbins = c->mods[mi].bin.nbins;
    }
    double bw = po->bw > 0 ? po->bw : 40;
    if (!(po->bw > 0)) hd_warn("-ap %s: no bandwidth given, using 40", po->file);
    if (po->bw2 > 0) hd_warn("-ap second bandwidth %g ignored: heliodon uses per-source neighbours", po->bw2);
    if (po->ac > 0) hd_warn("-ac %g ignored: the page size is fixed when the map is built (mkpmap -apZ)", po->ac);
    hd_pmap_lookup_opts lo;
    hd_pmap_lookup_opts_init(&lo);
    /* the bandwidth is shared by the map's sources that stored photons, whichever of them this run
     * asks for (-M), as Radiance's lookup shares it: a source's DC does not depend on the others
     * in the run, so a run split by modifiers gives the pictures of the whole run */
    for (uint32_t s = 0; s < I->nsources; s++)
        if (hd_pmap_get_source(m, s)->stored) nactive++;
    uint32_t k = (uint32_t)ceil(bw / (nactive ? nactive : 1));
    lo.k = k < 2 ? 2 : k;
    /* default search limit: 0.5 % of the photon map's extent (lookups far
     * from any photon of a source, e.g. on the distant ground, would
     * otherwise scan every page of that source) */
    lo.max_radius = po->am > 0 ? po->am : 0.005 * I->size;
    lo.direct_scene = po->exact_direct ? c->ts : NULL;
    double gcell = 0;   /* group extent: GCELLF x the mean k-th distance of the previous batch */
    j.lk = hd_calloc((size_t)nth, sizeof *j.lk);
    j.tmp = hd_calloc((size_t)nth, sizeof *j.tmp);
    if (!j.lk || !j.tmp) { st = HD_ERR_NOMEM; goto done; }
    for (int w = 0; w < nth; w++) {
        if ((st = hd_pmap_lookup_create(m, &lo, &j.lk[w]))) goto done;
        j.tmp[w] = hd_malloc_array((size_t)maxbins * 3, sizeof(double));
        if (!j.tmp[w]) { st = HD_ERR_NOMEM; goto done; }
    }
    /* streams */
    if ((st = build_streams(c, &os))) goto done;
    uint64_t expect = hd_rcontrib_nrecords(o);
    uint64_t nout = o->ranged ? o->rec_count : expect;   /* -R: the piece's records */
    if (o->fout == 'c') {
        if (o->xres <= 0 || o->yres <= 0) { st = hd_fail(HD_ERR_USAGE, "-fc needs -x and -y"); goto done; }
        if (o->accum == 0) { st = hd_fail(HD_ERR_USAGE, "-c 0 (sum of all records) cannot be written as pictures"); goto done; }
    }
    uint64_t done_recs = 0;   /* -r: records an earlier run wrote */
    {   /* sizes checked; -r: the files of the earlier run taken up */
        keep = hd_calloc((size_t)os.n + 1, 1);
        hd_rc_resume *r = hd_calloc((size_t)os.n + 1, sizeof *r);
        if (!r || !keep) { free(r); st = HD_ERR_NOMEM; goto done; }
        for (int q = 0; q < os.n; q++) { r[q].name = os.s[q].name; r[q].ncols = os.s[q].ncols; r[q].cols = os.s[q].cols; }
        sum = o->accum == 0 ? hd_calloc(3 * (size_t)c->ncols, sizeof(double)) : NULL;   /* -r: from the files */
        if (o->accum == 0 && !sum) st = HD_ERR_NOMEM;
        else if (o->recover) st = hd_rcontrib_resume(o, r, os.n, nout, &done_recs, sum);
        if (!st) st = hd_rcontrib_check_size(o, r, os.n, nout, done_recs, 0);
        if (!st && o->fout == 'c' && nout) {   /* the picture spool */
            const char *td = getenv("TMPDIR");
            char sp[4200];
            snprintf(sp, sizeof sp, "%s/spool", td && *td ? td : "/tmp");
            st = hd_check_disk(sp, nout * (uint64_t)os.n * 12, "rcontrib -fc picture spool (TMPDIR)");
        }
        for (int q = 0; q < os.n; q++) { os.s[q].of = r[q].of; keep[q] = (unsigned char)r[q].has_header; }
        free(r);
        if (st) goto done;
        if (o->recover && nout && done_recs >= nout) {   /* nothing left to do */
            for (int q = 0; q < os.n && !st; q++) {
                if (os.s[q].of) st = hd_ofile_commit(os.s[q].of);
                os.s[q].of = NULL;
            }
            goto done;
        }
    }
    for (int q = 0; q < os.n; q++) {
        ostream *s = &os.s[q];
        if (s->of) {   /* resumed (-r) */
            s->fp = hd_ofile_fp(s->of);
            if (keep[q] && o->fout == 'c') continue;
        } else if (s->name[0] && !o->force && !o->recover && access(s->name, F_OK) == 0) {
            st = hd_fail(HD_ERR_USAGE, "%s: output file exists (use -fo to overwrite)", s->name);
            goto done;
        }
        if (o->fout == 'c') {
            if (s->ncols != 1) {
                st = hd_fail(HD_ERR_USAGE, "%s: picture output (-fc) needs one value per stream, this one has %d "
                             "(use an -o pattern with %%d per bin)", s->name[0] ? s->name : "standard output", s->ncols);
                goto done;
            }
            s->exr = s->name[0] && ends_with(s->name, ".exr");
            if (s->exr && o->ranged) {
                st = hd_fail(HD_ERR_USAGE, "%s: -R pieces are Radiance pictures or matrices, not OpenEXR", s->name);
                goto done;
            }
            s->esz = s->exr ? 12 : 4;
            s->soff = os.rec_bytes;
            os.rec_bytes += s->esz;
            if (s->name[0]) {   /* check the path now (a bad one fails before the work) */
                hd_ofile *probe;
                if ((st = hd_ofile_open(&probe, s->name))) goto done;
                hd_ofile_abort(probe);
            }
            continue;
        }
        if (s->of) {
        } else if (!s->name[0]) s->fp = stdout;
        else {
            if ((st = hd_ofile_open(&s->of, s->name))) goto done;
            if (o->accum > 0) hd_ofile_keep_on_signal(s->of);   /* -r can continue it */
            s->fp = hd_ofile_fp(s->of);
        }
        /* the caller's lines, NCOMP, MODIFIER, BIN, NROWS, NCOLS; the
         * writer adds BigEndian and FORMAT.  Rows are not counted by the
         * writer: -r continues a partial file. */
        int header = o->header && !(s->of && keep[q]);
        hd_header h;
        hd_header_init(&h);
        if (header) {
            st = stream_header(c, o, s, hdr, &h);
            if (!st && expect) st = hd_header_appendf(&h, "NROWS=%llu", (unsigned long long)expect);
            if (!st) st = hd_header_appendf(&h, "NCOLS=%d", s->ncols);
            if (!st) st = hd_rcontrib_piece_line(o, &h);   /* -R: a piece */
        }
        hd_mtxfmt f = o->fout == 'f' ? HD_MTX_FLOAT : o->fout == 'd' ? HD_MTX_DOUBLE : HD_MTX_ASCII;
        if (!st) st = hd_mtxwriter_begin(&s->w, s->fp, &h, header ? HD_MTXW_HEADER : 0, f, 0, s->ncols, 3);
        hd_header_free(&h);
        if (st) goto done;
        s->w.ascii_style = HD_MTXASCII_RCONTRIB;
    }
    /* rays in batches of up to 16384 records (fewer when records are long,
     * so that the batch stays within ~64 MB): with a small page cache, every
     * batch decodes each source's pages again, so batches are large */
    int per = o->accum > 0 ? o->accum : 1;
    size_t rlen = 3 * (size_t)c->ncols, batch = (size_t)(8u << 20) / (rlen ? rlen : 1);
    if (batch > 16384) batch = 16384;   /* each batch visits every source's pages once */
    if (batch < 16) batch = 16;
    if (o->fout == 'c') {
        if ((st = spool_open(&os))) goto done;
        os.blk = hd_malloc_array(batch, os.rec_bytes ? os.rec_bytes : 1);
        if (!os.blk) { st = HD_ERR_NOMEM; goto done; }
    }
    org = hd_malloc_array(batch * (size_t)per, sizeof *org);
    dir = hd_malloc_array(batch * (size_t)per, sizeof *dir);
    int cmaj = po->ab < 0 && o->fout == 'c' && o->accum != 0;   /* column-major pictures: no record buffer */
    out = cmaj ? NULL : hd_malloc_array(batch, rlen * sizeof(double));
    j.gpp = hd_malloc_array(batch * (size_t)per, sizeof *j.gpp);
    if (po->ab < 0) {
        size_t nid = batch * (size_t)per * HD_PMPRIM_PTS;
        j.gid = hd_malloc_array(nid, sizeof *j.gid);
        j.gstart = hd_malloc_array(nid + 1, sizeof *j.gstart);
        j.gpt = hd_malloc_array(nid, sizeof *j.gpt);
        j.gn = hd_malloc_array(nid, sizeof *j.gn);
        j.pnpt = hd_malloc(batch * (size_t)per);
        j.pnana = hd_malloc(batch * (size_t)per);
        j.pf = hd_malloc_array(nid, 3 * sizeof(double));
        if (!j.gpt || !j.gn || !j.pnpt || !j.pnana || !j.pf) { st = HD_ERR_NOMEM; goto done; }
        j.gval = hd_calloc((size_t)nth, sizeof *j.gval);
        if (!j.gid || !j.gstart || !j.gval) { st = HD_ERR_NOMEM; goto done; }
        for (int w = 0; w < nth; w++) {
            j.gval[w] = hd_malloc_array(nid + GROUP_MAX, 3 * sizeof(double));
            if (!j.gval[w]) { st = HD_ERR_NOMEM; goto done; }
        }
    }
    if (!j.gpp || !org || !dir || (!out && !cmaj) || (o->accum == 0 && !sum)) {
        st = HD_ERR_NOMEM;
        goto done;
    }
    /* the large batch buffers are written in full by every batch: fault them
     * in at once rather than page by page */
    if (out) pm_prefault(out, batch * rlen * sizeof(double));
    pm_prefault(j.gpp, batch * (size_t)per * sizeof *j.gpp);
    if (os.blk) pm_prefault(os.blk, batch * os.rec_bytes);
    j.c = c; j.o = o; j.po = po; j.m = m; j.mods = mods; j.org = org; j.dir = dir; j.per = per; j.rlen = rlen; j.out = out;
    j.us = rlen; j.cs = 3;
    if (cmaj) {
        j.us = 3;
        j.cs = 3 * batch;
        j.colbuf = hd_calloc((size_t)nth, sizeof *j.colbuf);
        if (!j.colbuf) { st = HD_ERR_NOMEM; goto done; }
        for (int w = 0; w < nth; w++)
            if (!(j.colbuf[w] = hd_malloc_array(3 * batch * (size_t)maxbins, sizeof(double)))) { st = HD_ERR_NOMEM; goto done; }
        colstream = hd_malloc_array((size_t)c->ncols ? (size_t)c->ncols : 1, sizeof *colstream);
        if (!colstream) { st = HD_ERR_NOMEM; goto done; }
        for (int q = 0; q < c->ncols; q++) colstream[q] = -1;
        for (int q = 0; q < os.n; q++) colstream[os.s[q].cols[0]] = q;   /* -fc: one column per stream */
        j.os = &os;
        j.colstream = colstream;
    }
    if (o->report > 0 && nout) pr = hd_progress_start("rcontrib -ap: records", nout, o->report, 0);
    uint64_t rec = 0;
    int eof = 0;
    while (!eof && !st) {
        size_t nrec = 0;
        while (nrec < batch) {
            size_t kk;
            for (kk = 0; kk < (size_t)per; kk++) {
                if ((st = read_ray(src, o->fin, &org[nrec * per + kk], &dir[nrec * per + kk], &eof))) break;
                if (eof) break;
            }
            if (st || eof) {
                if (!st && kk && o->accum > 0)
                    st = hd_fail(HD_ERR_FORMAT, "input ends within a record of %d rays", per);
                break;
            }
            if (rec + nrec < (o->ranged ? o->rec_first : done_recs)) { rec++; continue; }   /* before the piece, or done (-r) */
            if (o->ranged && rec + nrec >= o->rec_first + o->rec_count) { eof = 1; break; }
            nrec++;
        }
        if (st || !nrec) break;
        j.rec0 = rec;
        if (po->ab < 0) {
            if ((st = hd_parallel_for(nrec, 8, nth, rc_points, &j))) break;
            j.nrec = nrec;
            if (!(gcell > 0)) {
                /* first batch: probe the mean k-th distance at up to 64 of its
                 * points for the first source with photons */
                uint32_t ps = UINT32_MAX;
                for (int mi = 0; mi < c->nmods && ps == UINT32_MAX; mi++)
                    for (int q = 0; q < mods[mi].nsrc; q++)
                        if (hd_pmap_get_source(m, mods[mi].src[q])->npages) { ps = mods[mi].src[q]; break; }
                size_t nray = nrec * (size_t)per, stepr = nray / 64 + 1;
                double e3[3];
                for (size_t r = 0; ps != UINT32_MAX && r < nray && !st; r += stepr)
                    if (j.gpp[r].npt) st = hd_pmap_irradiance(j.lk[0], ps, j.gpp[r].pt[0].p, j.gpp[r].pt[0].n, e3, NULL, NULL);
                if (st) break;
                gcell = GCELLF * hd_pmap_lookup_radius(j.lk[0], 1);
                if (!(gcell > 0)) gcell = 0.1 * lo.max_radius;
            }
            if ((st = build_groups(&j, I, gcell))) break;
            if ((st = hd_parallel_for((size_t)c->nmods, 1, nth, rc_mods, &j))) break;
            {   /* next batch's group cell from this batch's radii */
                double rs = 0, rn = 0;
                for (int w = 0; w < nth; w++) {
                    double r = hd_pmap_lookup_radius(j.lk[w], 0);
                    if (r > 0) { rs += r; rn += 1; }
                    hd_pmap_lookup_radius(j.lk[w], 1);
                }
                if (rn > 0) gcell = GCELLF * rs / rn;
            }
        } else if ((st = hd_parallel_for(nrec, 8, nth, rc_units, &j))) break;
        if (sum) {
            for (size_t r = 0; r < nrec; r++)
                for (size_t q = 0; q < rlen; q++) sum[q] += out[r * rlen + q];
        } else if (o->fout == 'c') {
            if ((st = spool_batch(&os, out, nrec, j.us, j.cs, j.colstream != NULL))) break;
        } else {
            for (size_t r = 0; r < nrec && !st; r++)
                for (int q = 0; q < os.n && !st; q++)
                    if ((st = hd_mtxwriter_row_cols(&os.s[q].w, out + r * rlen, os.s[q].cols)))
                        hd_fail_context(st, "%s", os.s[q].name[0] ? os.s[q].name : "standard output");
        }
        if (pr) hd_progress_add(pr, nrec);
        rec += nrec;
    }
    if (pr) { hd_progress_finish(pr); pr = NULL; }
    if (!st && o->ranged && rec != o->rec_first + o->rec_count)
        st = hd_fail(HD_ERR_FORMAT, "-R %llu %llu: the input ends after %llu records, inside the piece",
                     (unsigned long long)o->rec_first, (unsigned long long)o->rec_count, (unsigned long long)rec);
    if (!st && sum) {
        for (int q = 0; q < os.n && !st; q++)
            if ((st = hd_mtxwriter_row_cols(&os.s[q].w, sum, os.s[q].cols)))
                hd_fail_context(st, "%s", os.s[q].name[0] ? os.s[q].name : "standard output");
    }
    if (st) goto done;
    if (o->fout == 'c') {   /* pictures from the spool, several at a time */
        wpjob wj = {c, o, &os, hdr};
        if ((st = hd_parallel_for((size_t)os.n, 1, nth, write_pictures, &wj))) goto done;
    }
    for (int q = 0; q < os.n; q++) {
        ostream *s = &os.s[q];
        if (o->fout == 'c') continue;
        if ((st = hd_mtxwriter_end(&s->w))) {
            hd_fail_context(st, "%s", s->name[0] ? s->name : "standard output");
            goto done;
        }
        if (s->of) {
            st = hd_ofile_commit(s->of);
            s->of = NULL;
            if (st) goto done;
        } else fflush(stdout);
    }
done:
    if (pr) hd_progress_finish(pr);
    free(keep);
    free(org); free(dir); free(out); free(sum);
    free(colstream);
    for (int w = 0; j.colbuf && w < nth; w++) free(j.colbuf[w]);
    free(j.colbuf);
    free(j.gpp);
    free(j.gid);
    free(j.gstart);
    free(j.gpt);
    free(j.gn);
    free(j.pnpt);
    free(j.pnana);
    free(j.pf);
    for (int w = 0; j.gval && w < nth; w++) free(j.gval[w]);
    free(j.gval);
    for (int q = 0; q < os.n; q++) {
        if (os.s[q].of) hd_ofile_abort(os.s[q].of);
        free(os.s[q].cols);
        free(os.s[q].w.scratch);
    }
    free(os.s);
    free(os.boff);
    free(os.bn);
    free(os.blk);
    if (os.spool_fd >= 0) close(os.spool_fd);
    for (int w = 0; j.lk && w < nth; w++) hd_pmap_lookup_free(j.lk[w]);
    for (int w = 0; j.tmp && w < nth; w++) free(j.tmp[w]);
    free(j.lk);
    free(j.tmp);
    for (int mi = 0; mi < c->nmods; mi++) free(mods[mi].src);
    free(mods);
    hd_pmap_close(m);
    return st;
}

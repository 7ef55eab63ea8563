/* heliodon — contribution photon map construction: emission from distant
 * sources through photon ports, photon tracing, per-source budgets,
 * sorting (in memory or external merge under a memory budget), writing. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <pthread.h>
#include <unistd.h>

#include "heliodon/io.h"
#include "heliodon/material.h"
#include "heliodon/parallel.h"
#include "progress.h"
#include "heliodon/rng.h"
#include "scatter.h"
#include "heliodon/trace.h"
#include "pmap_internal.h"

/* Large buffers (the photon store, the slab of the batches' records, the
 * sort's work arrays): hd_big_alloc, released with free(). */

void hd_pmap_build_opts_init(hd_pmap_build_opts *o)
{
    memset(o, 0, sizeof *o);
    o->nphotons = 1000000;
    o->nthreads = 1;
    o->maxbounce = 5000;
    o->backvis = 1;
    o->mem_budget = (uint64_t)512 << 20;
    o->page_photons = 2048;
}

static int is_emitter(const hd_tscene *ts, const hd_surface *f)
{
    if (f->kind != HD_SURF_SOURCE) return 0;
    const hd_tmat *m = hd_tscene_material(ts, f->mat);
    return m && m->type == HD_MAT_LIGHT;
}

int hd_pmap_count_sources(const hd_tscene *ts)
{
    int n = 0;
    for (int i = 0; i < hd_tscene_nsurfaces(ts); i++)
        if (is_emitter(ts, hd_tscene_surface(ts, i))) n++;
    return n;
}

/* A port as one source uses it.  tlo > 0: the port is grey glass seen from
 * the front (or -bv on) and every transmittance over the source's cone of
 * incidence angles exceeds tlo, so a photon drawing u < tlo is transmitted
 * without evaluating the Fresnel terms (see port_step). */
typedef struct port_use { int surf; double sign, w, tlo; } port_use;

typedef struct src_state {
    int surf;
    hd_vec3 dir, d0;          /* towards source; travel direction */
    double half, omega, flux; /* flux through the ports for unit radiance */
    port_use *pu;
    int npu;
    double *cdf;
    uint64_t batches, emitted, stored;
    int done, empty_rounds;
    hd_pmap_energy en;        /* in photon units, scaled at the end */
} src_state;

typedef struct item {
    int s;
    uint64_t batch;
    pm_rec *recs;             /* a slice of the build's slab, or (own) malloc'd after overflowing it */
    size_t n, cap;
    size_t dst;               /* offset of its records in the store */
    int own;
    hd_pmap_energy en;
    uint64_t emitted;
    hd_vec3 lastn;            /* the last stored normal and its code (surfaces repeat: */
    uint16_t lastc;           /* the octahedral coding is a pure function, memoised) */
    int haslast;
} item;

typedef struct bctx {
    const hd_tscene *ts;
    const hd_pmap_build_opts *o;
    src_state *S;
    item *items;
    uint32_t B;
    hd_vec3 org;
    double size, eps;
    hd_scatter_cache **wc;    /* per worker: BSDF sampling caches (kept across batches) */
    int nwc;
    double qscale, qtop;      /* quantisation: cells per unit length, last cell index */
    pm_rec *slab;             /* W items x slab_per_item records, reused chunk after chunk */
    size_t slab_per_item;
    const struct mat_fast *mf;   /* per material index (mat_fast_build) */
    int nmf;
    const int *ncode;         /* per polygon surface: codes of its normal, back (2 s) and front (2 s + 1); -1 else */
} bctx;

static hd_status push_rec(item *it, const pm_rec *r)
{
    if (it->n == it->cap) {
        size_t nc = it->cap ? 2 * it->cap : 1024;
        pm_rec *p = it->own ? hd_realloc_array(it->recs, nc, sizeof *p) : hd_malloc_array(nc, sizeof *p);
        if (!p) return HD_ERR_NOMEM;
        if (!it->own && it->n) memcpy(p, it->recs, it->n * sizeof *p);
        it->recs = p;
        it->cap = nc;
        it->own = 1;
    }
    it->recs[it->n++] = *r;
    return HD_OK;
}

/* hd_pmap_morton by table: the 8-bit pieces of a coordinate spread to every
 * third bit, pre-shifted for x, y and z (same keys, fewer instructions) */
static uint32_t mort_tab[3][256];
static pthread_once_t mort_once = PTHREAD_ONCE_INIT;
static void mort_init(void)
{
    for (uint32_t v = 0; v < 256; v++) {
        uint32_t s = 0;
        for (int b = 0; b < 8; b++) s |= (v >> b & 1u) << (3 * b);
        for (int k = 0; k < 3; k++) mort_tab[k][v] = s << k;
    }
}
static inline uint64_t morton_tab(uint32_t x, uint32_t y, uint32_t z)
{
    x &= 0x1FFFFF; y &= 0x1FFFFF; z &= 0x1FFFFF;
    uint64_t lo = mort_tab[0][x & 255] | mort_tab[1][y & 255] | mort_tab[2][z & 255];
    uint64_t mi = mort_tab[0][x >> 8 & 255] | mort_tab[1][y >> 8 & 255] | mort_tab[2][z >> 8 & 255];
    uint64_t hi = mort_tab[0][x >> 16] | mort_tab[1][y >> 16] | mort_tab[2][z >> 16];
    return lo | mi << 24 | hi << 48;
}

static uint64_t quant_key(const bctx *c, hd_vec3 p)
{
    double sc = c->qscale, top = c->qtop;
    double v[3] = {(p.x - c->org.x) * sc, (p.y - c->org.y) * sc, (p.z - c->org.z) * sc};
    uint32_t q[3];
    for (int k = 0; k < 3; k++)   /* floor clamped to [0, top]; truncation = floor for v >= 0 */
        q[k] = !(v[k] > 0) ? 0 : v[k] >= top ? (uint32_t)top : (uint32_t)v[k];
    return morton_tab(q[0], q[1], q[2]);
}

static double avg3(const double *v) { return (v[0] + v[1] + v[2]) / 3.0; }

/* One photon in flight. */
typedef struct pstate {
    hd_vec3 org, d;
    double w[3], path, tmin;
    int level, passes, spec_only, no_diffuse, bounce;
} pstate;

static void pstate_init(pstate *p, hd_vec3 org, hd_vec3 d)
{
    p->org = org;
    p->d = d;
    p->w[0] = p->w[1] = p->w[2] = 1;
    p->path = 0;
    p->tmin = 0;
    p->level = p->passes = p->bounce = 0;
    p->spec_only = 1;
    p->no_diffuse = 1;
}

/* Materials whose scattering the photon tracer resolves from tables made
 * once per build instead of per hit (same results as hd_scatter_at and
 * hd_scatter_photon):
 * - MF_NORMAL: plastic/metal/trans whose coefficients (hd_normal_coeffs) do
 *   not depend on the incidence angle (no Fresnel term: not pure specular
 *   above the threshold) — ns and the storing flag kept;
 * - MF_GLASS: grey glass; per bin of the incidence cosine, bounds of the
 *   transmittance T and of T + R (the lobe thresholds of hd_scatter_photon:
 *   the factors T/T and R/R are exactly 1); a photon whose u falls between
 *   the bounds of a threshold gets the exact coefficients. */
enum { MF_GENERIC = 0, MF_NORMAL, MF_GLASS };
#define MF_NBIN 256
typedef struct mat_fast {
    int kind, stores;
    const hd_tmat *m;
    hd_nshade ns;
    double pd, pall, fd[3];   /* MF_NORMAL: hd_scatter_photon's diffuse and total lobe thresholds, diffuse factors */
    float *tb;                /* MF_GLASS: MF_NBIN x {tlo, thi, slo, shi} */
} mat_fast;

/* scatter.c's colour mean (exact for grey) */
static double mf_avg(const double c[3]) { return c[0] == c[1] && c[1] == c[2] ? c[0] : (c[0] + c[1] + c[2]) / 3; }

static void mat_fast_free(mat_fast *mf, int n)
{
    for (int i = 0; mf && i < n; i++) free(mf[i].tb);
    free(mf);
}

static mat_fast *mat_fast_build(const hd_tscene *ts)
{
    int n = hd_tscene_nmaterials(ts);
    mat_fast *mf = hd_calloc((size_t)n + 1, sizeof *mf);
    if (!mf) return NULL;
    for (int i = 0; i < n; i++) {
        const hd_tmat *m = hd_tscene_material(ts, i);
        mf[i].m = m;
        if (!m || m->chain) continue;   /* patterns: resolved per hit (hd_scatter_at) */
        if (m->type == HD_MAT_PLASTIC || m->type == HD_MAT_METAL || m->type == HD_MAT_TRANS) {
            hd_nshade a, b;
            hd_normal_coeffs(m, 0.25, &a);
            hd_normal_coeffs(m, 0.75, &b);
            if (memcmp(&a, &b, sizeof a) != 0) continue;   /* depends on the angle */
            hd_scatter sc;
            sc.kind = HD_SC_NORMAL;
            sc.ns = a;
            mf[i].ns = a;
            mf[i].stores = hd_scatter_photon_stores(&sc);
            /* the same expressions as hd_scatter_photon's */
            double pd = mf_avg(a.rdiff), ps = mf_avg(a.scol), ptd = mf_avg(a.tdiff), pts = mf_avg(a.tscol);
            mf[i].pd = pd;
            mf[i].pall = pd + ps + ptd + pts;
            for (int k = 0; k < 3; k++) mf[i].fd[k] = pd > 0 ? a.rdiff[k] / pd : 1;
            mf[i].kind = MF_NORMAL;
        } else if (m->type == HD_MAT_GLASS && m->color[0] == m->color[1] && m->color[1] == m->color[2]) {
            float *tb = hd_malloc_array(4 * MF_NBIN, sizeof *tb);
            if (!tb) { mat_fast_free(mf, n); return NULL; }
            int bad = 0;   /* a NaN (odd refractive index): the general path */
            for (int b = 0; b < MF_NBIN && !bad; b++) {
                double tmn = 2, tmx = -1, smn = 3, smx = -1;
                for (int j = 0; j <= 16; j++) {
                    double c = (b + j / 16.0) / MF_NBIN, R[3], T[3];
                    hd_glass_coeffs(m->color, m->rindex, c, R, T);
                    double sm = T[0] + R[0];
                    if (!(T[0] >= 0 && sm >= 0 && sm <= 2)) bad = 1;
                    tmn = fmin(tmn, T[0]); tmx = fmax(tmx, T[0]);
                    smn = fmin(smn, sm); smx = fmax(smx, sm);
                }
                /* widened by the variation over the bin (smooth, monotone
                 * in practice) and a little more; float rounding outwards */
                double mt = (tmx - tmn) + 1e-6, ms = (smx - smn) + 1e-6;
                tb[4 * b] = (float)(tmn - mt) - 1e-6f;
                tb[4 * b + 1] = (float)(tmx + mt) + 1e-6f;
                tb[4 * b + 2] = (float)(smn - ms) - 1e-6f;
                tb[4 * b + 3] = (float)(smx + ms) + 1e-6f;
            }
            mf[i].tb = tb;
            mf[i].kind = bad ? MF_GENERIC : MF_GLASS;
        }
    }
    return mf;
}

/* Codes of the two normals of every polygon surface (-1: not a polygon). */
static int *normal_codes(const hd_tscene *ts)
{
    int n = hd_tscene_nsurfaces(ts);
    int *nc = hd_malloc_array(2 * (size_t)n + 2, sizeof *nc);
    if (!nc) return NULL;
    for (int i = 0; i < n; i++) {
        const hd_surface *f = hd_tscene_surface(ts, i);
        if (f->kind != HD_SURF_POLYGON) { nc[2 * i] = nc[2 * i + 1] = -1; continue; }
        nc[2 * i] = hd_pmap_oct_encode(hd_vneg(f->n));
        nc[2 * i + 1] = hd_pmap_oct_encode(f->n);
    }
    return nc;
}

/* The part of a photon's step after its scattering event is known (sc
 * resolved, u drawn): storing, the lobe choice, the bookkeeping. */
static int photon_event(const bctx *c, item *it, pstate *p, const hd_hit *h, hd_scevent ev, hd_vec3 nd,
                        const double *fac);
/* stores: hd_scatter_photon_stores(sc) if known, else -1; ncode: the code
 * of sc->nf if known, else -1 */
static int photon_scatter(const bctx *c, item *it, uint16_t src, pstate *p, const hd_hit *h, const hd_scatter *sc,
                          double u, const mat_fast *mf, int ncode, hd_rng *rng, hd_scatter_cache **cache,
                          hd_status *st)
{
    int nrm = mf && mf->kind == MF_NORMAL;
    if (p->level > 0 && (nrm ? mf->stores : hd_scatter_photon_stores(sc))) {
        pm_rec r;
        pm_rec_setkey(&r, quant_key(c, h->p));
        if (p->w[0] == 1 && p->w[1] == 1 && p->w[2] == 1) r.rgbe = 128u | 128u << 8 | 128u << 16 | 129u << 24;
        else pm_rgbe_encode(p->w, &r.rgbe);   /* (its code for w = 1 above) */
        r.src = src;
        if (ncode >= 0) r.nrm = (uint16_t)ncode;
        else {
            if (!it->haslast || sc->nf.x != it->lastn.x || sc->nf.y != it->lastn.y || sc->nf.z != it->lastn.z) {
                it->lastn = sc->nf;
                it->lastc = hd_pmap_oct_encode(sc->nf);
                it->haslast = 1;
            }
            r.nrm = it->lastc;
        }
        r.dir = pm_oct_encode(p->d);
        r.flags = p->spec_only ? PM_F_DIRECT : p->no_diffuse ? PM_F_CAUSTIC : 0;
        if ((*st = push_rec(it, &r))) return 0;
        it->en.stored += avg3(p->w);
    }
    if (nrm) {   /* hd_scatter_photon's diffuse reflection and absorption, from the table */
        if (u < mf->pd) {
            /* in hd_scatter_photon's order (scatter.c's cosdir_draw) */
            double u2 = hd_rng_uniform(rng), u1 = hd_rng_uniform(rng);
            return photon_event(c, it, p, h, HD_SCE_DIFFUSE, hd_scatter_photon_cosdir(sc->nf, u1, u2), mf->fd);
        }
        if (!(u < mf->pall)) return photon_event(c, it, p, h, HD_SCE_ABSORB, p->d, NULL);
    }
    if (sc->kind == HD_SC_BSDF && !*cache) *cache = hd_scatter_cache_new();
    hd_vec3 nd;
    double fac[3];
    hd_scevent ev = hd_scatter_photon(sc, *cache, u, rng, &nd, fac);
    return photon_event(c, it, p, h, ev, nd, fac);
}

/* The event ev (new direction nd, weight factors fac; NULL: all exactly 1)
 * applied to the photon. */
static int photon_event(const bctx *c, item *it, pstate *p, const hd_hit *h, hd_scevent ev, hd_vec3 nd,
                        const double *fac)
{
    if (ev == HD_SCE_ABSORB) { it->en.absorbed += avg3(p->w); return 0; }
    if (fac) {
        double before = avg3(p->w);
        for (int k = 0; k < 3; k++) p->w[k] *= fac[k];
        /* coloured surfaces change the mean weight: book the change so
         * that the per-path balance stays exact (a BSDF lobe chosen with
         * a probability below its albedo adds weight: negative absorption) */
        it->en.absorbed += before - avg3(p->w);
    }
    p->level++;
    if (ev != HD_SCE_GLASS_T) p->spec_only = 0;
    if (ev == HD_SCE_DIFFUSE) p->no_diffuse = 0;
    int maxb = c->o->maxbounce > 0 ? c->o->maxbounce : 5000;
    if (++p->bounce > maxb) { it->en.lost += avg3(p->w); return 0; }
    p->org = h->p;
    p->d = nd;   /* unit: every lobe of hd_scatter_photon returns a normalised direction */
    p->tmin = c->eps;
    return 1;
}

/* Advance a photon by its next hit h (NULL: it escaped); tallies in it->en
 * (units of one emitted photon).  Returns 1 while the photon goes on (from
 * p->org along p->d beyond p->tmin), 0 when its path ended (or *st holds an
 * error).  The scattering rules (lobe choice by Russian roulette with the
 * lobe albedos, forward sampling of BSDF data from the incident direction)
 * are scatter.c's hd_scatter_photon. */
static const mat_fast *mat_of(const bctx *c, const hd_hit *h)
{
    const hd_surface *f = hd_tscene_surface(c->ts, h->surf);
    return &c->mf[f->mat >= 0 && f->mat < c->nmf ? f->mat : c->nmf];   /* [nmf]: generic */
}

/* sc resolved for the hit h of a photon travelling along d on a surface of
 * material mf: the fields hd_scatter_material sets for the table kinds
 * (not ns, R, T), hd_scatter_at_sel for the others (a mixture of different
 * materials: one side drawn with rng, with its probability). */
static void resolve(const bctx *c, const mat_fast *mf, const hd_hit *h, hd_vec3 d, hd_rng *rng, hd_scatter *sc)
{
    if (mf->kind == MF_GENERIC) { hd_scatter_at_sel(c->ts, h, d, HD_SC_ILLUM_ANYALT, rng, 0, sc); return; }
    sc->m = mf->m;
    sc->p = h->p;
    sc->n = h->n;
    sc->dir = d;
    sc->nf = h->front ? h->n : hd_vneg(h->n);
    sc->cosi = -hd_vdot(d, sc->nf);
    if (sc->cosi < 0) sc->cosi = 0;
    sc->kind = mf->kind == MF_NORMAL ? HD_SC_NORMAL : HD_SC_GLASS;
}

/* The rest of a step once u is drawn. */
static int photon_after_u(const bctx *c, item *it, uint16_t src, pstate *p, const hd_hit *h, hd_scatter *sc,
                          const mat_fast *mf, double u, hd_rng *rng, hd_scatter_cache **cache, hd_status *st)
{
    if (mf->kind == MF_NORMAL) {
        sc->ns = mf->ns;
        return photon_scatter(c, it, src, p, h, sc, u, mf, c->ncode[2 * h->surf + (h->front != 0)], rng, cache, st);
    }
    if (mf->kind == MF_GLASS) {
        int b = (int)(sc->cosi * MF_NBIN);
        if (b > MF_NBIN - 1) b = MF_NBIN - 1;
        const float *tb = mf->tb + 4 * b;
        if (u < tb[0]) return photon_event(c, it, p, h, HD_SCE_GLASS_T, p->d, NULL);
        if (u >= tb[1] && u < tb[2]) return photon_event(c, it, p, h, HD_SCE_SPECULAR, hd_scatter_mirror(sc), NULL);
        if (u >= tb[3]) return photon_event(c, it, p, h, HD_SCE_ABSORB, p->d, NULL);
        hd_glass_coeffs(sc->m->color, sc->m->rindex, sc->cosi, sc->R, sc->T);   /* u near a threshold: exact */
    }
    return photon_scatter(c, it, src, p, h, sc, u, NULL, -1, rng, cache, st);
}

/* Advance a photon by its next hit h (NULL: it escaped); tallies in it->en
 * (units of one emitted photon).  Returns 1 while the photon goes on (from
 * p->org along p->d beyond p->tmin), 0 when its path ended (or *st holds an
 * error).  The scattering rules (lobe choice by Russian roulette with the
 * lobe albedos, forward sampling of BSDF data from the incident direction)
 * are scatter.c's hd_scatter_photon. */
static int photon_step(const bctx *c, item *it, uint16_t src, pstate *p, const hd_hit *h, hd_rng *rng,
                       hd_scatter_cache **cache, hd_status *st)
{
    if (!h) { it->en.escaped += avg3(p->w); return 0; }
    p->path += h->t;
    if (c->o->maxdist > 0 && p->path > c->o->maxdist) { it->en.lost += avg3(p->w); return 0; }
    hd_scatter sc;
    const mat_fast *mf = mat_of(c, h);
    resolve(c, mf, h, p->d, rng, &sc);
    if (sc.kind == HD_SC_PASS || (!c->o->backvis && !h->front)) {
        if (++p->passes > 10000) { it->en.lost += avg3(p->w); return 0; }
        p->org = h->p;
        p->tmin = c->eps;
        return 1;
    }
    if (sc.kind == HD_SC_EMIT) { it->en.absorbed += avg3(p->w); return 0; }
    double u = hd_rng_uniform(rng);
    return photon_after_u(c, it, src, p, h, &sc, mf, u, rng, cache, st);
}

/* The step of a photon just emitted at its port, by the hit h on the port
 * itself.  For a grey glass port (pu->tlo > 0) a photon drawing u < tlo is
 * transmitted straight on with its weight unchanged, exactly as
 * photon_step would do it (transmittance >= tlo, factor T/T = 1), without
 * resolving the material; otherwise photon_step's own path. */
static int port_step(const bctx *c, item *it, uint16_t src, pstate *p, const hd_hit *h, const port_use *pu,
                     hd_rng *rng, hd_scatter_cache **cache, hd_status *st)
{
    if (!(pu->tlo > 0)) return photon_step(c, it, src, p, h, rng, cache, st);
    p->path += h->t;
    if (c->o->maxdist > 0 && p->path > c->o->maxdist) { it->en.lost += avg3(p->w); return 0; }
    double u = hd_rng_uniform(rng);
    if (u < pu->tlo) return photon_event(c, it, p, h, HD_SCE_GLASS_T, p->d, NULL);
    hd_scatter sc;
    const mat_fast *mf = mat_of(c, h);
    resolve(c, mf, h, p->d, rng, &sc);   /* glass (pu->tlo > 0): never passed */
    return photon_after_u(c, it, src, p, h, &sc, mf, u, rng, cache, st);
}

/* The lower bound tlo of port_use for source direction d0 (travel) and
 * half angle half, or 0 when the shortcut does not apply. */
static double port_tlo(const hd_tscene *ts, const hd_pmap_build_opts *o, const port_use *pu, hd_vec3 d0,
                       double half)
{
    const hd_surface *pf = hd_tscene_surface(ts, pu->surf);
    const hd_tmat *m = hd_tscene_material(ts, pf->mat);
    if (!m || m->type != HD_MAT_GLASS || m->color[0] != m->color[1] || m->color[1] != m->color[2]) return 0;
    if (!o->backvis && !(pu->sign < 0)) return 0;   /* photons arrive on the back of a '+' port */
    /* incidence cosines over the source's cone, widened a little */
    double c0 = hd_vdot(d0, hd_vscale(pf->n, pu->sign));
    if (c0 > 1) c0 = 1;
    double th = acos(c0), tlo_a = th - half - 1e-6, thi_a = th + half + 1e-6;
    if (tlo_a < 0) tlo_a = 0;
    if (thi_a > 1.55) return 0;   /* near grazing: no shortcut */
    double cmin = cos(thi_a), cmax = cos(tlo_a), tmin = 2, tmax = -1;
    for (int i = 0; i <= 32; i++) {
        double cc = cmin + (cmax - cmin) * i / 32, R[3], T[3];
        hd_glass_coeffs(m->color, m->rindex, cc, R, T);
        if (!(T[0] >= 0)) return 0;   /* NaN (odd refractive index): no shortcut */
        if (T[0] < tmin) tmin = T[0];
        if (T[0] > tmax) tmax = T[0];
    }
    double t = tmin - (tmax - tmin) - 1e-4;
    return t > 0 ? t : 0;
}

/* Trace the nl photons ps[live[..]] of one packet, which have passed their
 * port, to the end of their paths.  The first PM_PACKET_SEGS segments of
 * the photons still in flight are traced as Embree packets (photons of one
 * source leave the ports nearly parallel and stay so through the glazing),
 * the photons' hits then handled one after the other in packet order; the
 * rest of each path ray by ray.  The order of the random numbers depends
 * only on the batch, not on threads. */
#ifndef PM_PACKET_SEGS
#define PM_PACKET_SEGS 1
#endif
static hd_status trace_packet(const bctx *c, item *it, uint16_t src, pstate *ps, int *live, int nl, hd_rng *rng,
                              hd_scatter_cache **cache)
{
    hd_status st = HD_OK;
    for (int seg = 0; seg < PM_PACKET_SEGS && nl > 0; seg++) {
        hd_vec3 o[HD_TPACKET], d[HD_TPACKET];
        hd_hit h[HD_TPACKET];
        double tmin = ps[live[0]].tmin;
        int k = 0;
        /* one tmin per packet: photons whose tmin differs go on alone */
        for (int j = 0; j < nl; j++)
            if (ps[live[j]].tmin == tmin) { o[k] = ps[live[j]].org; d[k] = ps[live[j]].d; k++; }
        if (k < nl) break;
        uint32_t hits = hd_tscene_intersect_packet(c->ts, nl, o, d, tmin, 0, h);
        int nn = 0;
        for (int j = 0; j < nl; j++) {
            int q = live[j];
            if (photon_step(c, it, src, &ps[q], hits >> j & 1 ? &h[j] : NULL, rng, cache, &st)) live[nn++] = q;
            if (st) return st;
        }
        nl = nn;
    }
    for (int j = 0; j < nl; j++) {
        pstate *p = &ps[live[j]];
        for (;;) {
            hd_hit h;
            int hit = hd_tscene_intersect(c->ts, p->org, p->d, p->tmin, 0, &h);
            if (!photon_step(c, it, src, p, hit ? &h : NULL, rng, cache, &st)) break;
        }
        if (st) return st;
    }
    return HD_OK;
}

static hd_status run_batch(void *ctx, size_t b, size_t e, size_t ci, int wk)
{
    (void)ci;
    bctx *c = ctx;
    /* the worker's BSDF sampling caches (created on first use; results do
     * not depend on them, so the map does not depend on the thread count) */
    hd_scatter_cache *tmpcache = NULL, **cache = wk >= 0 && wk < c->nwc ? &c->wc[wk] : &tmpcache;
    hd_status res = HD_OK;
    for (size_t ii = b; ii < e && !res; ii++) {
        /* the batch works on a copy of its item on this thread's stack: the
         * items of neighbouring batches (other threads) share cache lines,
         * and the energy counters and record count change with every photon */
        item loc = c->items[ii], *it = &loc;
        src_state *S = &c->S[it->s];
        if (S->done) continue;   /* finished by an earlier chunk of this round */
        it->recs = c->slab + ii * c->slab_per_item;
        it->cap = c->slab_per_item;
        it->own = 0;
        hd_rng rng;
        hd_rng_init(&rng, c->o->seed, hd_hash64((uint64_t)it->s + 1, it->batch));
        uint32_t B = c->B, g = (uint32_t)sqrt((double)B);
        if (g < 1) g = 1;
        hd_vec3 a, bb;
        hd_vbasis(S->d0, &a, &bb);
        double cosh = cos(S->half);
        /* photons leave the ports in packets: emission of HD_TPACKET photons
         * (random numbers drawn photon after photon), their first segments
         * traced together (nearly parallel rays), then each photon on its own */
        uint32_t jx = 0, jy = 0;   /* i % g and i / g (i < B = g * g) */
        for (uint32_t i0 = 0; i0 < B && !res; i0 += HD_TPACKET) {
            uint32_t np = B - i0 < HD_TPACKET ? B - i0 : HD_TPACKET;
            pstate ps[HD_TPACKET];
            hd_vec3 xo[HD_TPACKET], xd[HD_TPACKET], xl[HD_TPACKET];
            int xk[HD_TPACKET], mk[HD_TPACKET], live[HD_TPACKET], nl = 0, m = 0, nc = 0;
            for (uint32_t i = i0; i < i0 + np; i++) {
                double u0 = (jx + hd_rng_uniform(&rng)) / g;
                double u1 = (jy + hd_rng_uniform(&rng)) / g;
                if (++jx == g) { jx = 0; if (++jy == g) jy = 0; }
                double u2 = hd_rng_uniform(&rng);
                double up = hd_rng_uniform(&rng);
                int k = 0;
                while (k < S->npu - 1 && up >= S->cdf[k]) k++;
                hd_vec3 x = hd_tscene_sample_polygon(c->ts, S->pu[k].surf, u0, u1, u2);
                double ct = 1 - hd_rng_uniform(&rng) * (1 - cosh);
                double st = sqrt(1 - ct * ct > 0 ? 1 - ct * ct : 0), sp, cp;
                hd_scatter_sincos2pi(hd_rng_uniform(&rng), &sp, &cp);
                /* unit up to rounding (d0, a, bb orthonormal): no normalisation */
                hd_vec3 d = hd_vadd(hd_vscale(S->d0, ct), hd_vadd(hd_vscale(a, st * cp), hd_vscale(bb, st * sp)));
                const hd_surface *pf = hd_tscene_surface(c->ts, S->pu[k].surf);
                hd_vec3 pn = hd_vscale(pf->n, S->pu[k].sign);
                it->emitted++;
                it->en.emitted += 1;
                if (hd_vdot(d, pn) <= 0) { it->en.escaped += 1; continue; }
                /* start just before the port so that the port's own material acts */
                xo[nc] = hd_vsub(x, hd_vscale(d, 4 * c->eps));
                xd[nc] = d;
                xl[nc] = hd_vneg(d);
                xk[nc] = k;
                nc++;
            }
            /* is the port seen from the source in this direction?  Geometry
             * outside (a building opposite, an overhang, a reveal) blocks
             * the photon, glass in front of the port attenuates it
             * (Radiance tests port occlusion too, per emission sample).  The
             * first segments of the photons' shadow rays are one packet;
             * those that hit something are followed by hd_scatter_shadow
             * (which starts again with the same first hit). */
            hd_hit sh[HD_TPACKET];
            uint32_t hit = nc ? hd_tscene_intersect_packet(c->ts, nc, xo, xl, c->eps, 0, sh) : 0;
            for (int q = 0; q < nc; q++) {
                double tr[3] = {1, 1, 1};
                if ((hit >> q & 1) && !hd_scatter_shadow(c->ts, xo[q], xl[q], 0, S->surf, 0, tr)) {
                    it->en.absorbed += 1;
                    continue;
                }
                pstate_init(&ps[m], xo[q], xd[q]);
                if (tr[0] != 1 || tr[1] != 1 || tr[2] != 1) {
                    for (int u = 0; u < 3; u++) ps[m].w[u] = tr[u];
                    it->en.absorbed += 1 - avg3(tr);
                }
                mk[m] = xk[q];
                m++;
            }
            /* each photon's first hit is its port at the sample point, 4 eps
             * ahead: made here as hd_tscene_intersect would make it (the
             * plane intersection it refines Embree's t with), without
             * tracing the ray; the photons' steps in emission order */
            for (int q = 0; q < m && !res; q++) {
                const port_use *pu = &S->pu[mk[q]];
                const hd_surface *pf = hd_tscene_surface(c->ts, pu->surf);
                hd_hit ph;
                double dn = hd_vdot(ps[q].d, pf->n), tt = 0;
                if (fabs(dn) > 1e-12) tt = (pf->d - hd_vdot(ps[q].org, pf->n)) / dn;
                int go;
                if (tt > 0) {
                    ph.t = tt;
                    ph.p = hd_vmadd(ps[q].org, ps[q].d, tt);
                    ph.n = pf->n;
                    ph.surf = pu->surf;
                    ph.front = dn < 0;
                    go = port_step(c, it, (uint16_t)it->s, &ps[q], &ph, pu, &rng, cache, &res);
                } else {   /* parallel to the port (rounding): trace it */
                    int hit = hd_tscene_intersect(c->ts, ps[q].org, ps[q].d, 0, 0, &ph);
                    go = photon_step(c, it, (uint16_t)it->s, &ps[q], hit ? &ph : NULL, &rng, cache, &res);
                }
                if (go) live[nl++] = q;
            }
            if (!res) res = trace_packet(c, it, (uint16_t)it->s, ps, live, nl, &rng, cache);
        }
        c->items[ii] = loc;
    }
    hd_scatter_cache_free(tmpcache);
    return res;
}

/* Copy the records of merged batches into the store, in parallel (the
 * first touches of the store's pages are a large part of the build's
 * system time); offsets were assigned in batch order. */
typedef struct copyctx { item *items; const size_t *idx; pm_rec *store; } copyctx;
static hd_status copy_items(void *ctx, size_t b, size_t e, size_t ci, int wk)
{
    (void)ci; (void)wk;
    const copyctx *cc = ctx;
    for (size_t k = b; k < e; k++) {
        const item *it = &cc->items[cc->idx[k]];
        if (it->n) memcpy(cc->store + it->dst, it->recs, it->n * sizeof(pm_rec));
    }
    return HD_OK;
}
static hd_status flush_copies(item *items, size_t *idx, size_t *npend, pm_rec *store, hd_pool *pool)
{
    if (!*npend) return HD_OK;
    copyctx cc = {items, idx, store};
    hd_status st = hd_pool_for(pool, *npend, 4, copy_items, &cc);
    for (size_t k = 0; k < *npend; k++) {
        item *it = &items[idx[k]];
        if (it->own) free(it->recs);
        it->recs = NULL;
        it->own = 0;
    }
    *npend = 0;
    return st;
}

/* ---- sorting ---- */
/* Stable LSD radix sort by key, 11-bit digits (6 passes over the 63-bit
 * Morton codes; passes whose digit is the same for all records skipped). */
#define RBITS 11
#define RSIZE (1u << RBITS)
static void radix_sort_key(pm_rec *a, pm_rec *tmp, size_t n)
{
    if (n < 2) return;
    pm_rec *src = a, *dst = tmp;
    size_t cnt[RSIZE + 1];   /* 16 kB on the worker's stack */
    for (int sh = 0; sh < 64; sh += RBITS) {
        memset(cnt, 0, sizeof cnt);
        for (size_t i = 0; i < n; i++) cnt[((pm_rec_key(&src[i]) >> sh) & (RSIZE - 1)) + 1]++;
        if (cnt[((pm_rec_key(&src[0]) >> sh) & (RSIZE - 1)) + 1] == n) continue;   /* all equal: skip */
        for (unsigned k = 0; k < RSIZE; k++) cnt[k + 1] += cnt[k];
        for (size_t i = 0; i < n; i++) dst[cnt[(pm_rec_key(&src[i]) >> sh) & (RSIZE - 1)]++] = src[i];
        pm_rec *t = src; src = dst; dst = t;
    }
    if (src != a) memcpy(a, src, n * sizeof *a);
}

/* Sort the n records of a (all of sources [s0, s1)) into out by (source,
 * direct flag, key), stably: a counting sort by (source, flag) bucket, the
 * records scanned in SG_K fixed slices in parallel (slice k writes bucket
 * j's records from pos[k][j] = j's offset + j's count in slices < k, so the
 * order is that of a serial scan), then each bucket's LSD radix sort by key
 * in parallel with a as the scratch.  a is overwritten.  Both arrays are
 * the build's reused buffers: no fresh memory is touched. */
#define SG_K 8
typedef struct sgctx {
    const pm_rec *a;
    pm_rec *out, *scr;
    size_t n, nb;
    uint32_t s0;
    size_t *cnt;              /* SG_K x nb counts, then write positions */
    size_t *off;              /* nb + 1 bucket offsets */
} sgctx;
static inline size_t sg_bucket(const sgctx *g, const pm_rec *r)
{
    return 2 * (size_t)(r->src - g->s0) + (r->flags & PM_F_DIRECT);
}
static hd_status sg_count(void *ctx, size_t b, size_t e, size_t ci, int wk)
{
    (void)ci; (void)wk;
    sgctx *g = ctx;
    for (size_t k = b; k < e; k++) {
        size_t *c = g->cnt + k * g->nb;
        for (size_t i = g->n * k / SG_K; i < g->n * (k + 1) / SG_K; i++) {
            size_t j = sg_bucket(g, &g->a[i]);
            if (j >= g->nb) return hd_fail(HD_ERR_INTERNAL, "photon source %u outside the group", g->a[i].src);
            c[j]++;
        }
    }
    return HD_OK;
}
static hd_status sg_scatter(void *ctx, size_t b, size_t e, size_t ci, int wk)
{
    (void)ci; (void)wk;
    sgctx *g = ctx;
    for (size_t k = b; k < e; k++) {
        size_t *p = g->cnt + k * g->nb;
        for (size_t i = g->n * k / SG_K; i < g->n * (k + 1) / SG_K; i++) g->out[p[sg_bucket(g, &g->a[i])]++] = g->a[i];
    }
    return HD_OK;
}
static hd_status sg_radix(void *ctx, size_t b, size_t e, size_t ci, int wk)
{
    (void)ci; (void)wk;
    sgctx *g = ctx;
    for (size_t j = b; j < e; j++) radix_sort_key(g->out + g->off[j], g->scr + g->off[j], g->off[j + 1] - g->off[j]);
    return HD_OK;
}
static hd_status sort_group(pm_rec *a, pm_rec *out, size_t n, uint32_t s0, uint32_t s1, int nthreads)
{
    if (!n) return HD_OK;
    sgctx g = {a, out, a, n, 2 * (size_t)(s1 - s0), s0, NULL, NULL};
    g.cnt = hd_calloc(SG_K * g.nb, sizeof *g.cnt);
    g.off = hd_calloc(g.nb + 1, sizeof *g.off);
    hd_status st = HD_OK;
    if (!g.cnt || !g.off) { st = HD_ERR_NOMEM; goto done; }
    if ((st = hd_parallel_for(SG_K, 1, nthreads, sg_count, &g))) goto done;
    size_t acc = 0;
    for (size_t j = 0; j < g.nb; j++) {
        g.off[j] = acc;
        for (size_t k = 0; k < SG_K; k++) {
            size_t c = g.cnt[k * g.nb + j];
            g.cnt[k * g.nb + j] = acc;
            acc += c;
        }
    }
    g.off[g.nb] = acc;
    if ((st = hd_parallel_for(SG_K, 1, nthreads, sg_scatter, &g))) goto done;
    st = hd_parallel_for(g.nb, 1, nthreads, sg_radix, &g);
done:
    free(g.cnt);
    free(g.off);
    return st;
}

/* ---- runs (external sort) ---- */
#ifndef PM_CHUNK
#define PM_CHUNK 64                          /* batches traced per parallel call (their slab is reused) */
#endif
#ifndef PM_GROUP_RECS
#define PM_GROUP_RECS ((uint64_t)1 << 19)   /* records of a group of sources (10 MB) */
#endif
typedef struct runset {
    char **names;
    int n;
    size_t cap;
    char dir[4096];
} runset;

typedef struct fwctx { FILE *fp; const char *name; } fwctx;
static hd_status emit_file(void *ctx, const pm_rec *r, size_t n)
{
    fwctx *f = ctx;
    if (n && fwrite(r, sizeof *r, n, f->fp) != n) return hd_fail(HD_ERR_IO, "%s: write failed (disk full?)", f->name);
    return HD_OK;
}
/* The sort's output buffer, reused group after group (grown if a group
 * holds more).  First sized for the store (hint) rather than for the first
 * group: a later group a little larger than the first no longer makes a
 * fresh buffer (10 MB of page faults and zeroing at 10 M photons). */
typedef struct sortbuf { pm_rec *p; size_t cap, hint; } sortbuf;
static hd_status sortbuf_fit(sortbuf *b, size_t n)
{
    if (n <= b->cap) return HD_OK;
    size_t want = n > b->hint ? n : b->hint;
    free(b->p);
    b->p = hd_big_alloc(want, sizeof(pm_rec), 0);
    b->cap = b->p ? want : 0;
    return b->p ? HD_OK : HD_ERR_NOMEM;
}

static hd_status spill(runset *rs, pm_rec *a, size_t n, uint32_t s0, uint32_t s1, sortbuf *tmp, int nthreads,
                       const char *base)
{
    hd_status st;
    if ((st = HD_GROW(rs->names, (size_t)rs->n + 1, rs->cap, 8))) return st;
    if ((st = sortbuf_fit(tmp, n)) || (st = sort_group(a, tmp->p, n, s0, s1, nthreads))) return st;
    /* ".MAP.hdtmp.PID.runN" beside the map: removed by the exit and signal
     * handlers, and by the next run if this one is killed (io.h) */
    char name[4200];
    const char *slash = strrchr(base, '/');
    int dl = slash ? (int)(slash - base + 1) : 0;
    if (snprintf(name, sizeof name, "%.*s.%s.hdtmp.%ld.run%03d", dl, base, base + dl, (long)getpid(), rs->n) >=
        (int)sizeof name)
        return hd_fail(HD_ERR_RANGE, "run file name too long");
    if ((st = hd_temp_track(name))) return st;
    FILE *fp = fopen(name, "wb");
    if (!fp) return hd_fail(HD_ERR_IO, "%s: cannot create run file: %s", name, strerror(errno));
    rs->names[rs->n] = hd_strdup(name);
    if (!rs->names[rs->n]) { fclose(fp); remove(name); return HD_ERR_NOMEM; }
    rs->n++;
    fwctx f = {fp, rs->names[rs->n - 1]};
    if ((st = emit_file(&f, tmp->p, n))) { fclose(fp); return st; }
    if (fclose(fp) != 0) return hd_fail(HD_ERR_IO, "%s: write failed", name);
    return HD_OK;
}

static void runs_free(runset *rs)
{
    for (int i = 0; i < rs->n; i++) { remove(rs->names[i]); hd_temp_forget(rs->names[i]); free(rs->names[i]); }
    free(rs->names);
    memset(rs, 0, sizeof *rs);
}

#define RUNBUF 65536
static hd_status merge_runs(runset *rs, pm_writer *w)
{
    int n = rs->n;
    FILE **fp = hd_calloc((size_t)n, sizeof *fp);
    pm_rec **buf = hd_calloc((size_t)n, sizeof *buf);
    size_t *len = hd_calloc((size_t)n, sizeof *len), *pos = hd_calloc((size_t)n, sizeof *pos);
    pm_rec *out = hd_malloc_array(RUNBUF, sizeof *out);
    hd_status st = HD_OK;
    if (!fp || !buf || !len || !pos || !out) { st = HD_ERR_NOMEM; goto done; }
    for (int i = 0; i < n; i++) {
        fp[i] = fopen(rs->names[i], "rb");
        buf[i] = hd_malloc_array(RUNBUF, sizeof(pm_rec));
        if (!fp[i] || !buf[i]) { st = hd_fail(HD_ERR_IO, "%s: cannot reopen run file", rs->names[i]); goto done; }
        len[i] = fread(buf[i], sizeof(pm_rec), RUNBUF, fp[i]);
    }
    size_t no = 0;
    for (;;) {
        int best = -1;
        for (int i = 0; i < n; i++) {
            if (pos[i] == len[i]) continue;
            if (best < 0) { best = i; continue; }
            const pm_rec *a = &buf[i][pos[i]], *b = &buf[best][pos[best]];
            unsigned fa = a->flags & PM_F_DIRECT, fb = b->flags & PM_F_DIRECT;
            if (a->src < b->src || (a->src == b->src && (fa < fb || (fa == fb && pm_rec_key(a) < pm_rec_key(b))))) best = i;
        }
        if (best < 0) break;
        out[no++] = buf[best][pos[best]++];
        if (pos[best] == len[best]) {
            len[best] = fread(buf[best], sizeof(pm_rec), RUNBUF, fp[best]);
            pos[best] = 0;
        }
        if (no == RUNBUF) {
            if ((st = pm_writer_add(w, out, no))) goto done;
            no = 0;
        }
    }
    st = pm_writer_add(w, out, no);
done:
    for (int i = 0; fp && i < n; i++) if (fp[i]) fclose(fp[i]);
    for (int i = 0; buf && i < n; i++) free(buf[i]);
    free(fp); free(buf); free(len); free(pos); free(out);
    return st;
}

/* A group's sort and write on a thread of its own, overlapping the tracing
 * of the next group (the writer's serial parts — page filling, CRCs, the
 * file writes — no longer stall both cores).  Jobs run one at a time in
 * group order, so the file is the same. */
typedef struct wjob {
    pthread_t tid;
    int live;
    pm_writer *w;
    pm_rec *in;
    size_t n;
    uint32_t s0, s1;
    sortbuf *sb;
    int nth;
    hd_status st;
    char err[1024];
} wjob;
static void *wjob_main(void *arg)
{
    wjob *j = arg;
    j->st = sortbuf_fit(j->sb, j->n);
    if (!j->st) j->st = sort_group(j->in, j->sb->p, j->n, j->s0, j->s1, j->nth);
    if (!j->st) j->st = pm_writer_add(j->w, j->sb->p, j->n);
    if (j->st) hd_strlcpy(j->err, hd_errmsg(), sizeof j->err);
    return NULL;
}
static hd_status wjob_start(wjob *j)
{
    j->st = HD_OK;
    j->err[0] = 0;
    if (pthread_create(&j->tid, NULL, wjob_main, j) != 0) {   /* no thread: run it here */
        wjob_main(j);
        return j->st ? hd_fail(j->st, "%s", j->err) : HD_OK;
    }
    j->live = 1;
    return HD_OK;
}
static hd_status wjob_wait(wjob *j)
{
    if (!j->live) return HD_OK;
    pthread_join(j->tid, NULL);
    j->live = 0;
    return j->st ? hd_fail(j->st, "%s", j->err) : HD_OK;
}

/* Which sources can emit.  The tracing loop gives a source up when its
 * first 16 batches (rounds of 1, 1, 2, 4 and 8 batches) store nothing; the
 * same batches are traced here first (their records dropped), for every
 * source that faces a port (other shards' too: every shard must find the
 * same count), so that the asked photon count can be shared among the
 * sources that store photons.  A batch's photons depend only on (seed,
 * source, batch): the result does not depend on the thread count.  Sets
 * dead[s] = 1 for the sources that cannot emit (their emission and energy
 * counts are those of these batches, as the tracing loop would have
 * counted them); returns the others' count in *nlive. */
#define PM_EMPTY_ROUNDS 5
static hd_status find_emitters(bctx *c, hd_pool *pool, src_state *S, uint32_t ns, size_t W, uint8_t *dead,
                               uint32_t *nlive)
{
    hd_status st = HD_OK;
    uint8_t *alive = hd_calloc(ns ? ns : 1, 1), *done0 = hd_calloc(ns ? ns : 1, 1);
    src_state *acc = hd_calloc(ns ? ns : 1, sizeof *acc);   /* the pilot's counts */
    if (!alive || !done0 || !acc) { free(alive); free(done0); free(acc); return HD_ERR_NOMEM; }
    for (uint32_t s = 0; s < ns; s++) {
        done0[s] = (uint8_t)S[s].done;
        S[s].done = S[s].npu == 0;   /* run_batch skips done sources: open the other shards' */
    }
    uint64_t lo = 0, hi = 1;
    for (int round = 0; round < PM_EMPTY_ROUNDS && !st; round++) {
        size_t nit = 0;
        for (uint32_t s = 0; s < ns; s++)
            if (S[s].npu && !alive[s]) nit += (size_t)(hi - lo);
        if (!nit) break;
        item *items = hd_calloc(nit, sizeof *items);
        if (!items) { st = HD_ERR_NOMEM; break; }
        nit = 0;
        for (uint32_t s = 0; s < ns; s++)
            if (S[s].npu && !alive[s])
                for (uint64_t b = lo; b < hi; b++) { items[nit].s = (int)s; items[nit].batch = b; nit++; }
        for (size_t c0 = 0; c0 < nit && !st; c0 += W) {
            size_t cn = nit - c0 < W ? nit - c0 : W;
            c->items = items + c0;
            st = hd_pool_for(pool, cn, 1, run_batch, c);
            for (size_t i = c0; i < c0 + cn; i++) {
                src_state *a = &acc[items[i].s];
                if (items[i].n) alive[items[i].s] = 1;
                a->batches++;
                a->emitted += items[i].emitted;
                a->en.emitted += items[i].en.emitted;
                a->en.absorbed += items[i].en.absorbed;
                a->en.escaped += items[i].en.escaped;
                a->en.stored += items[i].en.stored;
                a->en.lost += items[i].en.lost;
                if (items[i].own) free(items[i].recs);
                items[i].recs = NULL;
                items[i].own = 0;
            }
        }
        free(items);
        lo = hi;
        hi = round == 0 ? 2 : hi * 2;
    }
    uint32_t n = 0;
    for (uint32_t s = 0; s < ns; s++) {
        S[s].done = done0[s];
        dead[s] = S[s].npu && !alive[s];
        if (dead[s]) {
            S[s].batches = acc[s].batches;
            S[s].emitted = acc[s].emitted;
            S[s].en = acc[s].en;
        }
        n += alive[s];
    }
    *nlive = n;
    free(acc);
    free(alive);
    free(done0);
    return st;
}

/* ---- emission set-up: the port polygons and every source's state ---- */

/* The polygons of the port modifiers, once per orientation asked for. */
static hd_status find_ports(const hd_tscene *ts, const hd_pmap_build_opts *o, port_use **out, int *npo)
{
    int nsurf = hd_tscene_nsurfaces(ts);
    port_use *ports = hd_calloc((size_t)nsurf * 2 + 1, sizeof *ports);
    if (!ports) return HD_ERR_NOMEM;
    int np = 0;
    for (int p = 0; p < o->nports; p++) {
        int found = 0;
        for (int i = 0; i < nsurf; i++) {
            const hd_surface *f = hd_tscene_surface(ts, i);
            const hd_tmat *m = hd_tscene_material(ts, f->mat);
            if (!m || strcmp(m->name, o->ports[p].modifier) != 0) continue;
            if (f->kind != HD_SURF_POLYGON) {
                free(ports);
                return hd_fail(HD_ERR_UNSUPPORTED, "%s: photon ports must be polygons", f->where);
            }
            found = 1;
            char c = o->ports[p].orient;
            if (c == '+' || c == '0') ports[np++] = (port_use){i, 1.0, 0, 0};
            if (c == '-' || c == '0') ports[np++] = (port_use){i, -1.0, 0, 0};
        }
        if (!found) {
            free(ports);
            return hd_fail(HD_ERR_USAGE, "no polygon with photon port modifier '%s'", o->ports[p].modifier);
        }
    }
    *out = ports;
    *npo = np;
    return HD_OK;
}

/* Per source (S[ns], tab[ns], zeroed): the ports it faces with their
 * sampling weights, its flux and its table entry; *nactive: the sources
 * that face a port (this shard's or not). */
static hd_status source_states(const hd_tscene *ts, const hd_pmap_build_opts *o, const port_use *ports, int np,
                               src_state *S, hd_pmap_source *tab, uint32_t *nactive)
{
    uint32_t k = 0;
    *nactive = 0;
    for (int i = 0; i < hd_tscene_nsurfaces(ts); i++) {
        const hd_surface *f = hd_tscene_surface(ts, i);
        if (!is_emitter(ts, f)) continue;
        src_state *s = &S[k];
        const hd_tmat *m = hd_tscene_material(ts, f->mat);
        s->surf = i;
        s->dir = hd_vnorm(f->b);
        s->d0 = hd_vneg(s->dir);
        s->half = f->r0;
        s->omega = f->area;
        s->pu = hd_calloc((size_t)np + 1, sizeof *s->pu);
        s->cdf = hd_calloc((size_t)np + 1, sizeof *s->cdf);
        if (!s->pu || !s->cdf) return HD_ERR_NOMEM;
        double tot = 0;
        for (int p = 0; p < np; p++) {
            const hd_surface *pf = hd_tscene_surface(ts, ports[p].surf);
            double c = hd_vdot(s->d0, hd_vscale(pf->n, ports[p].sign));
            if (c <= 0) continue;
            s->pu[s->npu] = ports[p];
            s->pu[s->npu].w = pf->area * c;
            s->pu[s->npu].tlo = port_tlo(ts, o, &ports[p], s->d0, s->half);
            tot += pf->area * c;
            s->npu++;
        }
        double acc = 0;
        for (int p = 0; p < s->npu; p++) { acc += s->pu[p].w; s->cdf[p] = acc / tot; }
        s->flux = s->omega * tot;
        hd_strlcpy(tab[k].modifier, m->name, sizeof tab[k].modifier);
        tab[k].dir = s->dir;
        tab[k].half_angle = s->half;
        for (int c = 0; c < 3; c++) tab[k].radiance[c] = m->color[c];
        if (s->npu == 0) {
            s->done = 1;
            hd_warn("%s: no emission through the photon ports (source behind them)", f->where);
        } else {
            (*nactive)++;
            if (o->nshards > 1 && (int)(k % (uint32_t)o->nshards) != o->shard) s->done = 1;   /* another shard's */
        }
        k++;
    }
    return HD_OK;
}

/* Batch size: from the share of every source that faces a port (known
 * before tracing, so that the batches do not depend on which sources turn
 * out to emit nothing), small against it (the last accepted batch
 * overshoots the target by at most ~1/64), and a perfect square: every
 * stratum of the g x g port grid gets one photon per batch (otherwise the
 * emission would not be uniform). */
static uint32_t batch_size(const hd_pmap_build_opts *o, uint32_t nactive)
{
    uint64_t target = (o->nphotons + nactive - 1) / nactive;
    uint32_t B = o->batch;
    if (!B) {
        uint64_t b2 = target / 64;
        B = b2 < 64 ? 64 : b2 > 4096 ? 4096 : (uint32_t)b2;
    }
    uint32_t g = (uint32_t)sqrt((double)B);
    while ((g + 1) * (g + 1) <= B) g++;
    if (g < 1) g = 1;
    return g * g;
}

/* ---- scheduler: the batches of a round ---- */

/* The items (one batch each) of the next round of sources [g0, g1): a
 * source's first round is one batch; then as many as its stored count so
 * far says it needs to reach target (+2 %, at most 4096); a source that
 * stores nothing in 5 rounds is given up.  *nit = 0: the group is done. */
static hd_status round_items(const hd_tscene *ts, src_state *S, uint32_t g0, uint32_t g1, uint64_t target,
                             item **out, size_t *nitp)
{
    size_t nit = 0, capit = 0;
    item *items = NULL;
    for (uint32_t s = g0; s < g1; s++) {
        src_state *q = &S[s];
        if (q->done) continue;
        uint64_t nb;
        if (q->batches == 0) nb = 1;
        else if (q->stored == 0) {
            if (++q->empty_rounds > 4) {
                q->done = 1;
                hd_warn("%s: no photons stored after %llu emitted; source skipped",
                        hd_tscene_surface(ts, q->surf)->where, (unsigned long long)q->emitted);
                continue;
            }
            nb = q->batches;
        } else {
            double per = (double)q->stored / (double)q->batches;
            double need = (double)(target - q->stored) / per;
            nb = (uint64_t)ceil(need * 1.02);
            if (nb < 1) nb = 1;
            if (nb > 4096) nb = 4096;
        }
        if (nit + nb > capit) {
            size_t nc = (nit + nb) * 2;
            item *p = hd_realloc_array(items, nc, sizeof *p);
            if (!p) { free(items); return HD_ERR_NOMEM; }
            items = p;
            capit = nc;
        }
        for (uint64_t j = 0; j < nb; j++) {
            memset(&items[nit], 0, sizeof items[nit]);
            items[nit].s = (int)s;
            items[nit].batch = q->batches + j;
            nit++;
        }
    }
    *out = items;
    *nitp = nit;
    return HD_OK;
}

/* ---- store, sort and write pipeline ---- */

/* Sources are traced in groups of consecutive sources whose records fit
 * one store (about PM_GROUP_RECS, at least one source, at most the memory
 * budget); a group's records are sorted and written before the next group
 * starts, so the store and the sort's output buffer are allocated once and
 * reused (first touches of fresh memory cost ~15 % of the build's CPU time
 * on a VM), instead of holding every photon of the map.  A source's
 * photons depend only on (seed, source, batch) and its own counts, and the
 * file holds the sources in order: the map is the same for any grouping.
 * The store being filled, the previous group's store (being written by the
 * writer thread) and the sort's output take a third of the budget each. */
typedef struct pipeline {
    pm_rec *store, *store2;   /* filled by the tracing / being written */
    size_t cap, cap2, n;
    uint64_t maxrec;          /* records in memory before a spill to disk */
    sortbuf sb;
    wjob wj;
    runset rs;                /* spilled sorted runs of the current group */
    pm_writer *w;
    int nth;
    const char *path;
    hd_pool *pool;
    hd_progress *pr;
} pipeline;

/* Take the traced items [0, cn) of a chunk into the store: sources' counts
 * updated in item order (a source done by an earlier item ignores the
 * rest), records copied in parallel, the store grown, or spilled as a
 * sorted run when it holds maxrec records. */
static hd_status pipe_accept(pipeline *pp, item *items, size_t cn, src_state *S, uint64_t target, uint32_t g0,
                             uint32_t g1, size_t *pend)
{
    hd_status st = HD_OK;
    size_t npend = 0;
    for (size_t i = 0; i < cn && !st; i++) {
        item *it = &items[i];
        src_state *q = &S[it->s];
        if (q->done) {
            if (it->own) free(it->recs);
            it->recs = NULL;
            it->own = 0;
            continue;
        }
        q->batches = it->batch + 1;
        q->emitted += it->emitted;
        q->stored += it->n;
        q->en.emitted += it->en.emitted;
        q->en.absorbed += it->en.absorbed;
        q->en.escaped += it->en.escaped;
        q->en.stored += it->en.stored;
        q->en.lost += it->en.lost;
        if (pp->n + it->n > pp->cap) {
            size_t nc = pp->cap * 2;
            if (nc > pp->maxrec + it->n) nc = pp->maxrec + it->n;
            if (nc < pp->n + it->n) nc = pp->n + it->n;
            if ((st = flush_copies(items, pend, &npend, pp->store, pp->pool))) break;
            pm_rec *p = hd_realloc_array(pp->store, nc, sizeof *p);
            if (!p) { st = HD_ERR_NOMEM; break; }
            pp->store = p;
            pp->cap = nc;
        }
        it->dst = pp->n;
        pend[npend++] = i;
        pp->n += it->n;
        if (pp->pr) hd_progress_add(pp->pr, it->n);
        if (q->stored >= target) q->done = 1;
        if (pp->n >= pp->maxrec) {
            if ((st = flush_copies(items, pend, &npend, pp->store, pp->pool))) break;
            /* the sort buffer may still be the writer thread's */
            if ((st = wjob_wait(&pp->wj))) break;
            if ((st = spill(&pp->rs, pp->store, pp->n, g0, g1, &pp->sb, pp->nth, pp->path))) break;
            pp->n = 0;
        }
    }
    if (!st) st = flush_copies(items, pend, &npend, pp->store, pp->pool);
    return st;
}

/* The group's records, sorted, to the writer: spilled groups merged here,
 * the others by the writer thread while the next group is traced (the
 * previous group's job is waited for first: groups reach the file in
 * order). */
static hd_status pipe_group_done(pipeline *pp, uint32_t g0, uint32_t g1, int *nruns)
{
    hd_status st = wjob_wait(&pp->wj);
    if (st) return st;
    if (pp->rs.n) {
        if (pp->n && (st = spill(&pp->rs, pp->store, pp->n, g0, g1, &pp->sb, pp->nth, pp->path))) return st;
        pp->n = 0;
        *nruns += pp->rs.n;
        if ((st = merge_runs(&pp->rs, pp->w))) return st;
        runs_free(&pp->rs);
    } else if (pp->n) {
        wjob *wj = &pp->wj;
        wj->w = pp->w;
        wj->in = pp->store;
        wj->n = pp->n;
        wj->s0 = g0;
        wj->s1 = g1;
        wj->sb = &pp->sb;
        wj->nth = pp->nth;
        /* swap the stores (the second one allocated on first use) */
        if (!pp->store2) {
            pp->store2 = hd_big_alloc(pp->cap, sizeof *pp->store2, 0);
            pp->cap2 = pp->cap;
            if (!pp->store2) return HD_ERR_NOMEM;
        }
        pm_rec *t = pp->store; pp->store = pp->store2; pp->store2 = t;
        size_t tc = pp->cap; pp->cap = pp->cap2; pp->cap2 = tc;
        if ((st = wjob_start(wj))) return st;
        pp->n = 0;
    }
    return HD_OK;
}

static void pipe_free(pipeline *pp)
{
    if (pp->wj.live) { hd_status st2 = wjob_wait(&pp->wj); (void)st2; }
    free(pp->store2);
    if (pp->w) pm_writer_abort(pp->w);
    if (pp->pr) hd_progress_finish(pp->pr);
    free(pp->store);
    free(pp->sb.p);
    runs_free(&pp->rs);
    hd_pool_free(pp->pool);
}

/* Disk, before the tracing: the map (about 8 bytes a photon, with the last
 * batches' overshoot) and, when one source's photons (run_recs: its
 * expected records) exceed the memory budget, that source's sorted runs
 * beside it.  Groups of sources that fit the budget are sorted in memory,
 * and a spilled source's runs are merged and removed before the next
 * group, so the runs on disk never hold more than one source. */
static hd_status check_disk_space(const hd_pmap_build_opts *o, const char *path, uint64_t run_recs)
{
    uint64_t total = o->nphotons + o->nphotons / 32;
    uint64_t need = total * 8 + 65536 + run_recs * (uint64_t)sizeof(pm_rec);
    char what[4200];
    snprintf(what, sizeof what, "mkpmap -apC %s (%llu photons%s)", path, (unsigned long long)total,
             run_recs ? "; one source's photons are sorted in runs on disk: raise -apB to keep them in memory" : "");
    return hd_check_disk(path, need, what);
}

/* The traced sources' totals into the table (which the writer stores) and
 * the stats. */
static void build_totals(const src_state *S, hd_pmap_source *tab, uint32_t ns, hd_pmap_build_stats *stats)
{
    for (uint32_t s = 0; s < ns; s++) {
        tab[s].emitted = S[s].emitted;
        tab[s].flux = S[s].emitted ? S[s].flux / (double)S[s].emitted : 0;
        stats->emitted += S[s].emitted;
        stats->stored += S[s].stored;
        if (S[s].stored) stats->nactive++;
    }
}

/* The energy balance per source (flux units). */
static hd_status build_energy(const src_state *S, const hd_pmap_source *tab, uint32_t ns, hd_pmap_energy **energy)
{
    hd_pmap_energy *E = hd_calloc(ns, sizeof *E);
    if (!E) return HD_ERR_NOMEM;
    for (uint32_t s = 0; s < ns; s++) {
        double f = tab[s].flux;
        E[s].emitted = S[s].en.emitted * f;
        E[s].absorbed = S[s].en.absorbed * f;
        E[s].escaped = S[s].en.escaped * f;
        E[s].stored = S[s].en.stored * f;
        E[s].lost = S[s].en.lost * f;
    }
    *energy = E;
    return HD_OK;
}

/* Emission set-up, then per group of sources: rounds of batches traced on
 * the pool (the scheduler), their records through the pipeline. */
hd_status hd_pmap_build(const hd_tscene *ts, const hd_pmap_build_opts *o, const char *path,
                        const char *header_lines, hd_pmap_build_stats *stats, hd_pmap_energy **energy)
{
    hd_pmap_build_stats sdummy;
    if (!stats) stats = &sdummy;
    pthread_once(&mort_once, mort_init);
    memset(stats, 0, sizeof *stats);
    if (energy) *energy = NULL;
    double t0 = hd_seconds();
    uint32_t ns = (uint32_t)hd_pmap_count_sources(ts);
    if (ns == 0) return hd_fail(HD_ERR_USAGE, "no distant light sources (light + source) in the scene");
    if (ns > 65535) return hd_fail(HD_ERR_RANGE, "%u light sources: at most 65535", ns);
    if (o->nports <= 0) return hd_fail(HD_ERR_USAGE, "contribution photon maps need photon ports (-apo modifier)");
    port_use *ports = NULL;
    int np = 0;
    hd_status st = find_ports(ts, o, &ports, &np);
    if (st) return st;
    src_state *S = hd_calloc(ns, sizeof *S);
    hd_pmap_source *tab = hd_calloc(ns, sizeof *tab);
    uint32_t nactive = 0;
    if (!S || !tab) st = HD_ERR_NOMEM;
    if (!st) st = source_states(ts, o, ports, np, S, tab, &nactive);
    stats->nsources = (int)ns;
    if (!st && nactive == 0) st = hd_fail(HD_ERR_USAGE, "no light source shines through the photon ports");
    if (st) goto out;
    {
        uint32_t B = batch_size(o, nactive);
        hd_vec3 lo, hi;
        hd_tscene_bounds(ts, &lo, &hi);
        double size = hi.x - lo.x;
        if (hi.y - lo.y > size) size = hi.y - lo.y;
        if (hi.z - lo.z > size) size = hi.z - lo.z;
        size = size * 1.001 + 1e-6;
        hd_vec3 org = hd_vsub(lo, hd_v3(size * 0.0004, size * 0.0004, size * 0.0004));
        bctx c = {ts, o, S, NULL, B, org, size, hd_tscene_eps(ts), NULL, 0,
                  pm_quant_scale() / size, pm_quant_scale() - 1, NULL, 0, NULL, 0, NULL};
        int nth = hd_resolve_threads(o->nthreads);
        mat_fast *mf = mat_fast_build(ts);
        int *ncode = normal_codes(ts);
        c.mf = mf;
        c.nmf = hd_tscene_nmaterials(ts);
        c.ncode = ncode;
        c.wc = hd_calloc((size_t)nth, sizeof *c.wc);
        c.nwc = c.wc ? nth : 0;
        pipeline pp;
        memset(&pp, 0, sizeof pp);
        pp.maxrec = o->mem_budget / 3 / sizeof(pm_rec);
        if (pp.maxrec < 4096) pp.maxrec = 4096;
        pp.nth = nth;
        pp.path = path;
        pp.pool = hd_pool_new(nth);   /* persistent: ~280 loops for 10 M photons */
        /* batches of a chunk write their records into slices of one slab of
         * 2 B records each (a batch storing more moves to its own buffer) */
        size_t W = (size_t)(o->mem_budget / 4 / ((uint64_t)B * 2 * sizeof(pm_rec)));
        if (W > PM_CHUNK) W = PM_CHUNK;
        if (W < (size_t)nth * 2) W = (size_t)nth * 2;
        c.slab_per_item = (size_t)B * 2;
        c.slab = hd_big_alloc(W * c.slab_per_item, sizeof(pm_rec), 0);
        uint8_t *dead = hd_calloc(ns, 1);
        size_t *pend = hd_malloc_array(W, sizeof *pend);
        if (!c.slab || !dead || !pend || !c.wc || !mf || !ncode) { st = HD_ERR_NOMEM; goto fail; }
        /* the asked count is shared among the sources that can emit */
        uint32_t nlive = 0;
        if ((st = find_emitters(&c, pp.pool, S, ns, W, dead, &nlive))) goto fail;
        for (uint32_t s = 0; s < ns; s++)
            if (dead[s]) {
                S[s].done = 1;
                hd_warn("%s: no photons stored in the first %d batches; source skipped, its share goes to "
                        "the others", hd_tscene_surface(ts, S[s].surf)->where, 16);
            }
        uint64_t target = (o->nphotons + (nlive ? nlive : 1) - 1) / (nlive ? nlive : 1);
        stats->nlive = (int)nlive;
        uint64_t expect1 = target + target / 16 + 2 * (uint64_t)B;   /* one source's records, with margin */
        if ((st = check_disk_space(o, path, expect1 > pp.maxrec ? expect1 : 0))) goto fail;
        uint64_t grec = PM_GROUP_RECS > expect1 ? PM_GROUP_RECS : expect1;
        if (grec > pp.maxrec) grec = pp.maxrec;
        pp.cap = (size_t)grec;
        pp.sb.hint = pp.cap;
        pp.store = hd_big_alloc(pp.cap, sizeof *pp.store, 0);
        if (!pp.store) { st = HD_ERR_NOMEM; goto fail; }
        if ((st = pm_writer_open(&pp.w, path, header_lines, ns, o->page_photons ? o->page_photons : 2048, org, size,
                                 nth)))
            goto fail;
        pp.pr = o->report_interval > 0 ?
            hd_progress_start("mkpmap: stored photons", target * (uint64_t)stats->nlive, o->report_interval, 0) : NULL;
        double t_write = 0;
        for (uint32_t g0 = 0, g1; g0 < ns && !st; g0 = g1) {
            uint64_t gexp = 0;
            for (g1 = g0; g1 < ns; g1++) {
                uint64_t e1 = S[g1].done ? 0 : expect1;
                if (g1 > g0 && gexp + e1 > grec) break;
                gexp += e1;
            }
            for (;;) {   /* rounds until every source of the group is done */
                item *items;
                size_t nit;
                if ((st = round_items(ts, S, g0, g1, target, &items, &nit))) goto fail;
                if (!nit) { free(items); break; }
                /* in chunks of W items (their records within a quarter of
                 * the memory budget, and at most 256 batches: the slab is
                 * reused); items of sources finished by an earlier chunk
                 * are not traced */
                for (size_t c0 = 0; c0 < nit && !st; c0 += W) {
                    size_t cn = nit - c0 < W ? nit - c0 : W;
                    c.items = items + c0;
                    st = hd_pool_for(pp.pool, cn, 1, run_batch, &c);
                    if (!st) st = pipe_accept(&pp, items + c0, cn, S, target, g0, g1, pend);
                }
                for (size_t i = 0; i < nit; i++) if (items[i].own) free(items[i].recs);
                free(items);
                if (st) goto fail;
            }
            double t1 = hd_seconds();
            if ((st = pipe_group_done(&pp, g0, g1, &stats->nruns))) goto fail;
            t_write += hd_seconds() - t1;
        }
        if ((st = wjob_wait(&pp.wj))) goto fail;
        if (pp.pr) { hd_progress_finish(pp.pr); pp.pr = NULL; }
        build_totals(S, tab, ns, stats);
        double t1 = hd_seconds();
        st = pm_writer_close(pp.w, tab, &stats->file_bytes);
        pp.w = NULL;
        t_write += hd_seconds() - t1;
        stats->seconds_write = t_write;
        stats->seconds_trace = hd_seconds() - t0 - t_write;
        if (!st && energy) st = build_energy(S, tab, ns, energy);
    fail:
        free(dead);
        free(pend);
        pipe_free(&pp);
        for (int i = 0; i < c.nwc; i++) hd_scatter_cache_free(c.wc[i]);
        free(c.wc);
        free(c.slab);
        mat_fast_free(mf, hd_tscene_nmaterials(ts));
        free(ncode);
    }
out:
    for (uint32_t s = 0; S && s < ns; s++) { free(S[s].pu); free(S[s].cdf); }
    free(S);
    free(tab);
    free(ports);
    return st;
}

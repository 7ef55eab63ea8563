/* heliodon — rcontrib contribution tracer (see contrib.h).
 *
 * The path is followed forwards from the receiver of the record (sensor,
 * pixel, sender sample) carrying the product of the scattering
 * coefficients ("coef", RGB); whenever it reaches a tracked emitter the
 * coefficient (times the emitted radiance with -V+) is added to that
 * modifier's bin.  The sampling mirrors Radiance's -aa 0 ambient
 * calculation and ray-weight admission, so the expectation equals
 * rcontrib's result with the same -ab/-lw/-lr. */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/bsdf.h"
#include "shade_bsdf.h"
#include "heliodon/contrib.h"
#include "scatter.h"

#define FTINY 1e-7
#define GOLDEN 0.61803398874989484820

typedef struct cst {
    int level;       /* diffuse bounces taken */
    int depth;       /* ray depth */
    int skipsrc;     /* direct sources were counted by shadow rays */
    int firstamb;    /* no diffuse vertex yet: use all -ad divisions */
    double w;        /* Radiance ray weight */
    int scattered;   /* went through a sampled scattering (see render.c pstate) */
    int mixforce;    /* 1 / 2: the fore / back side of a mixture of different materials (render.c) */
} cst;

static double c_max(const double c[3]) { return fmax(c[0], fmax(c[1], c[2])); }
static double c_avg(const double c[3]) { return (c[0] + c[1] + c[2]) / 3; }

static int maxdepth(const hd_contrib *c)
{
    int d = c->o.lr < 0 ? -c->o.lr : c->o.lr;
    return d == 0 ? 1000 : d;
}

/* Radiance's rayorigin admission (scatter.c): factor for the child's
 * contribution, 0 = not traced. */
static double admit(const hd_contrib *c, double *w, hd_rng *rng)
{
    return hd_scatter_admit(c->o.lw, c->o.lr, w, rng);
}

static void tally(const hd_contrib *c, int mod, const hd_tmat *m, hd_vec3 D, const double coef[3],
                  hd_rng *rng, double *acc)
{
    const hd_cmod *cm = &c->mods[mod];
    double j1 = 0.5, j2 = 0.5;
    if (cm->bin.jtr > 0) { j1 = hd_rng_uniform(rng); j2 = hd_rng_uniform(rng); }
    int bin = hd_binfn_eval(&cm->bin, D, j1, j2);
    if (bin < 0) return;
    double *a = acc + 3 * (size_t)(cm->first + bin);
    if (c->vflag) {
        double L[3];
        hd_emit_color(m, D, NULL, L);
        for (int i = 0; i < 3; i++) a[i] += coef[i] * L[i];
    } else {
        for (int i = 0; i < 3; i++) a[i] += coef[i];
    }
}

/* -stats: the direct-source work, counted by every thread */
struct hd_contrib_counts {
    atomic_ullong vert0, vert1;   /* vertices considering sources: before / after a diffuse bounce */
    atomic_ullong sampled0, sampled1;   /* sources sampled (sample_light calls), before / after */
    atomic_ullong shadows;        /* shadow rays cast to tracked sources */
};

static void count(atomic_ullong *field)
{
    atomic_fetch_add_explicit(field, 1, memory_order_relaxed);
}

/* ---- which tracked sources a vertex samples (-dn) ---- */
typedef struct srcsel {
    int n;           /* sources visited at this vertex */
    double r0;       /* systematic offset (n < nlights) */
    double w;        /* weight of each visited source's term */
} srcsel;

static srcsel select_sources(const hd_contrib *c, int level, hd_rng *rng)
{
    srcsel s = {c->nlights, 0, 1};
    if (c->counts) count(level > 0 ? &c->counts->vert1 : &c->counts->vert0);
    if (level < 1 || c->dn <= 0 || c->dn >= c->nlights) return s;
    /* source i is visited when one of k + r0 (k = 0..n-1) falls in
     * [i n / N, (i + 1) n / N): probability n / N, never twice */
    s.n = c->dn;
    s.r0 = hd_rng_uniform(rng);
    s.w = (double)c->nlights / c->dn;
    return s;
}

static int selected_light(const hd_contrib *c, const srcsel *s, int k)
{
    if (s->n == c->nlights) return c->lights[k];
    int i = (int)((k + s->r0) * c->nlights / s->n);
    return c->lights[i < c->nlights ? i : c->nlights - 1];
}

/* ---- shadow rays to tracked direct sources (scatter.c) ---- */
static int shadow(const hd_contrib *c, hd_vec3 p, hd_vec3 l, double maxd, int target, double tr[3])
{
    if (c->counts) count(&c->counts->shadows);
    return hd_scatter_shadow(c->ts, p, l, maxd, target, 1, tr);
}

/* Sample tracked light surface si from p: direction, solid angle, distance
 * (0 = distant).  (-dj: fraction of a distant source's radius.) */
static int sample_light(const hd_contrib *c, int level, int si, hd_vec3 p, hd_rng *rng, hd_vec3 *l,
                        double *omega, double *dist)
{
    double L[3];
    if (c->counts) count(level > 0 ? &c->counts->sampled1 : &c->counts->sampled0);
    return hd_scatter_sample_source(c->ts, si, p, c->o.dj, rng, l, omega, dist, L);
}

/* sc: a plastic / metal / trans hit (hd_scatter_normal_direct); NULL: a
 * Lambertian surface of diffuse reflection rd, transmission td (render.c);
 * level: the vertex's diffuse depth (-dn samples sources after a bounce) */
static void direct(const hd_contrib *c, int level, hd_vec3 p, hd_vec3 nf, const hd_scatter *sc, const double rd[3],
                   const double td[3], const double coef[3], hd_rng *rng, double *acc)
{
    srcsel sel = select_sources(c, level, rng);
    for (int k = 0; k < sel.n; k++) {
        int si = selected_light(c, &sel, k);
        hd_vec3 l;
        double om, dist, tr[3], f[3];
        if (!sample_light(c, level, si, p, rng, &l, &om, &dist)) continue;
        if (sc ? !hd_scatter_normal_direct(sc, 1, c->o.dj, l, om, f) : !hd_scatter_direct_coef(nf, rd, td, 1, l, om, f))
            continue;
        if (!shadow(c, p, l, dist, si, tr)) continue;
        const hd_surface *sf = hd_tscene_surface(c->ts, si);
        double k3[3];
        for (int i = 0; i < 3; i++) k3[i] = sel.w * coef[i] * f[i] * tr[i];
        tally(c, c->matmod[sf->mat], hd_tscene_material(c->ts, sf->mat), l, k3, rng, acc);
    }
}

static void trace(const hd_contrib *c, hd_vec3 org, hd_vec3 dir, double tmax, cst st,
                  const double coef[3], hd_rng *rng, double *acc);

static void ambient(const hd_contrib *c, hd_vec3 p, hd_vec3 nd, const double col[3], cst st,
                    const double coef[3], hd_rng *rng, double *acc)
{
    double ac = c_avg(col), wt = st.w;
    if (ac <= 0 || c->o.ad <= 0) return;
    double d = c->o.lw > 0 ? 0.8 * ac * st.w / (c->o.ad * c->o.lw) : wt;
    /* first diffuse vertex: Radiance's n = sqrt(ad·w), w capped so that the
     * sample rays keep a weight of about -lw.  Deeper vertices: up to 2×2
     * divisions while that cap allows them (sample weights stay above
     * about -lw).  With one sample there, heliodon's indirect-only view-
     * matrix elements had twice the standard deviation of Radiance's at
     * the same -ad (docs/benchmarks/3pm.md); with this rule they match it
     * at less than half Radiance's CPU time.  The expectation is the same. */
    if (wt > d) wt = d;
    if (!st.firstamb) wt = d;
    int m = (int)(sqrt(c->o.ad * wt) + 0.5);
    if (!st.firstamb && m > 2) m = 2;
    if (m < 1) m = 1;
    int ndiv = m * m;
    cst cs = st;
    cs.level = st.level + 1;
    cs.depth = st.depth + 1;
    cs.skipsrc = 1;
    cs.scattered = 1;
    cs.firstamb = 0;
    cs.w = st.w * ac / ndiv;
    double fa = admit(c, &cs.w, rng);
    if (fa <= 0) return;
    int n = ndiv;
    double k3[3];
    for (int i = 0; i < 3; i++) k3[i] = fa * coef[i] * col[i] / n;
    double r1 = hd_rng_uniform(rng), r2 = hd_rng_uniform(rng);
    for (int j = 0; j < n; j++) {
        double u1, u2;
        if (n > 1) {   /* Fibonacci lattice, randomly shifted */
            u1 = (j + 0.5) / n + r1;
            u2 = j * GOLDEN + r2;
            u1 -= floor(u1);
            u2 -= floor(u2);
        } else {
            u1 = hd_rng_uniform(rng);
            u2 = hd_rng_uniform(rng);
        }
        trace(c, p, hd_scatter_cosdir(nd, u1, u2), 0, cs, k3, rng, acc);
    }
}

static void shade_normal(const hd_contrib *c, const hd_scatter *sc, cst st, const double coef[3], hd_rng *rng,
                         double *acc)
{
    const hd_nshade *ns = &sc->ns;
    hd_vec3 nf = sc->nf, dir = sc->dir, p = sc->p;
    double ramb[3], tamb[3];   /* rough lobes at most -st join the diffuse parts (render.c) */
    int smp = hd_scatter_normal_split(sc, c->o.st, ramb, tamb);
    if (c->nlights) direct(c, st.level, p, nf, sc, NULL, NULL, coef, rng, acc);
    if (st.level < c->o.ab) {
        if (c_max(ramb) > 0) ambient(c, p, nf, ramb, st, coef, rng, acc);
        if (c_max(tamb) > 0) ambient(c, p, hd_vneg(nf), tamb, st, coef, rng, acc);
    }
    /* specular reflection, then transmission: the pure ray, or samples of
     * the rough lobe that do not count direct sources (render.c) */
    for (int side = 0; side < 2; side++) {
        const double *col = side ? ns->tscol : ns->scol;
        if (!(smp & (side ? 2 : 1))) continue;
        cst cs = st;
        cs.depth++;
        cs.w = st.w * c_avg(col);
        double fa = admit(c, &cs.w, rng);
        if (fa <= 0) continue;
        double k3[3];
        if (ns->pure) {
            for (int i = 0; i < 3; i++) k3[i] = fa * coef[i] * col[i];
            trace(c, p, side ? dir : hd_scatter_mirror(sc), 0, cs, k3, rng, acc);
        } else if (c->o.ss > 0) {
            int n = c->o.ss >= 1 ? (int)(c->o.ss + 0.5) : (hd_rng_uniform(rng) < c->o.ss ? 1 : 0);
            double scale = c->o.ss >= 1 ? 1.0 / n : 1.0 / c->o.ss;
            cs.skipsrc = 1;
            cs.scattered = 1;
            for (int i = 0; i < 3; i++) k3[i] = fa * coef[i] * col[i] * scale;
            for (int j = 0; j < n; j++) {
                hd_vec3 sd;
                if (!hd_scatter_spec_draw(sc, side, rng, &sd)) continue;
                trace(c, p, sd, 0, cs, k3, rng, acc);
            }
        }
    }
}

/* BSDF / aBSDF (the rules of render.c's shade_bsdf, as coefficients):
 * extra Lambertian parts as a diffuse surface; tracked direct sources
 * evaluated through the data, f(l, v)·|cos l|·omega (shadow rays as for
 * other materials); one backward importance-sampled continuation per hit,
 * weighted by f·|cos|/pdf, that does not count direct sources (the shadow
 * rays did) and does not use a -ab bounce. */
typedef struct bsdf_ctx {
    const hd_contrib *c;
    cst st;
    const double *coef;
    double *acc;
    srcsel sel;          /* the sources the data's loop visits (-dn) */
} bsdf_ctx;

static void bsdf_lambert(void *ctx, const hd_scatter *sc, const double ramb[3], const double tamb[3], hd_rng *rng)
{
    bsdf_ctx *x = ctx;
    const hd_contrib *c = x->c;
    const double *rdx = sc->rdx, *tdx = sc->tdx;
    if (c->nlights && (c_max(rdx) > 0 || c_max(tdx) > 0))
        direct(c, x->st.level, sc->p, sc->nf, NULL, rdx, tdx, x->coef, rng, x->acc);
    if (x->st.level < c->o.ab) {
        if (c_max(ramb) > 0) ambient(c, sc->p, sc->nf, ramb, x->st, x->coef, rng, x->acc);
        if (c_max(tamb) > 0) ambient(c, sc->p, hd_vneg(sc->nf), tamb, x->st, x->coef, rng, x->acc);
    }
}

/* the tracked direct sources */
static int bsdf_sample(void *ctx, int k, hd_vec3 p, hd_rng *rng, hd_vec3 *l, double *om, double *dist, int *target)
{
    bsdf_ctx *x = ctx;
    int si = selected_light(x->c, &x->sel, k);
    if (!sample_light(x->c, x->st.level, si, p, rng, l, om, dist)) return 0;
    *target = si;
    return 1;
}

static double bsdf_eval(void *ctx, const hd_scatter *sc, int k, int target, hd_vec3 l, double om, hd_rng *rng,
                        double *wl)
{
    (void)k; (void)wl;
    const bsdf_ctx *x = ctx;   /* l: the shadow ray's direction (jittered over the source by -dj) */
    const hd_surface *f = hd_tscene_surface(x->c->ts, target);
    double half = f->kind == HD_SURF_SOURCE && x->c->o.dj > 0 ? f->r0 * fmin(1, x->c->o.dj) : 0;
    double fc = hd_scatter_bsdf_direct(sc, l, om, x->c->o.ss, x->st.w, f->b, half, rng, NULL);
    if (fc > 0 && x->c->counts) count(&x->c->counts->shadows);   /* hd_shade_bsdf casts its shadow ray */
    return fc;
}

static void bsdf_add(void *ctx, int k, int target, hd_vec3 l, double fc, double om, double wl, const double tr[3],
                     hd_rng *rng)
{
    (void)k; (void)wl;
    bsdf_ctx *x = ctx;
    const hd_contrib *c = x->c;
    const hd_surface *sf = hd_tscene_surface(c->ts, target);
    double k3[3];
    for (int i = 0; i < 3; i++) k3[i] = x->sel.w * x->coef[i] * fc * om * tr[i];
    tally(c, c->matmod[sf->mat], hd_tscene_material(c->ts, sf->mat), l, k3, rng, x->acc);
}

static void bsdf_cont(void *ctx, hd_vec3 o, hd_vec3 d, double wt, double pdf, hd_rng *rng)
{
    (void)pdf;
    bsdf_ctx *x = ctx;
    cst cs = x->st;
    cs.depth++;
    cs.skipsrc = 1;
    cs.scattered = 1;
    cs.w = x->st.w * wt;
    double fa = admit(x->c, &cs.w, rng);
    if (fa <= 0) return;
    double k3[3];
    for (int i = 0; i < 3; i++) k3[i] = fa * x->coef[i] * wt;
    trace(x->c, o, d, 0, cs, k3, rng, x->acc);
}

/* BSDF / aBSDF (the loop of shade_bsdf.c, shared with render.c, as
 * coefficients): extra Lambertian parts as a diffuse surface; tracked
 * direct sources evaluated through the data, f(l, v)·|cos l|·omega (shadow
 * rays as for other materials); one backward importance-sampled
 * continuation per hit, weighted by f·|cos|/pdf, that does not count direct
 * sources (the shadow rays did) and does not use a -ab bounce. */
static void shade_bsdf(const hd_contrib *c, const hd_scatter *sc, cst st, const double coef[3], hd_rng *rng,
                       double *acc)
{
    bsdf_ctx x = {c, st, coef, acc, {c->nlights, 0, 1}};
    if (c->nlights && hd_scatter_bsdf_has_data(sc)) x.sel = select_sources(c, st.level, rng);
    const hd_shade_bsdf_ops ops = {bsdf_lambert, x.sel.n, bsdf_sample, bsdf_eval, 1, bsdf_add, bsdf_cont, c->o.st};
    hd_shade_bsdf(c->ts, sc, rng, &ops, &x);
}

static void trace(const hd_contrib *c, hd_vec3 org, hd_vec3 dir, double tmax, cst st,
                  const double coef[3], hd_rng *rng, double *acc)
{
    const hd_tscene *s = c->ts;
    if (st.depth > maxdepth(c)) return;
    hd_hit h;
    double eps = hd_tscene_eps(s);
    if (!hd_tscene_intersect(s, org, dir, st.depth == 0 ? 0 : eps, tmax, &h)) {
        if (tmax > 0) return;
        int si = hd_tscene_source_hit(s, dir);
        if (si < 0) return;
        const hd_surface *f = hd_tscene_surface(s, si);
        int mod = c->matmod[f->mat];
        if (mod < 0) return;
        const hd_tmat *m = hd_tscene_material(s, f->mat);
        if (!hd_tmat_emits(m) || m->type == HD_MAT_ILLUM) return;
        if (st.skipsrc && f->nee) return;
        tally(c, mod, m, dir, coef, rng, acc);
        return;
    }
    const hd_surface *f = hd_tscene_surface(s, h.surf);
    hd_scatter sc;
    hd_scatter_at_sel(s, &h, dir, 0, rng, st.mixforce, &sc);
    if (sc.mixc > 0 && st.level <= 1 && !st.mixforce) {
        /* a hit before the second diffuse bounce on a mixture of two
         * different materials: both sides, their coefficients weighted by
         * the mixture's (render.c) */
        cst sa = st, sb = st;
        sa.mixforce = 1;
        sb.mixforce = 2;
        double ca[3], cb[3];
        for (int i = 0; i < 3; i++) { ca[i] = coef[i] * sc.mixc; cb[i] = coef[i] * (1 - sc.mixc); }
        trace(c, org, dir, tmax, sa, ca, rng, acc);
        trace(c, org, dir, tmax, sb, cb, rng, acc);
        return;
    }
    st.mixforce = 0;
    const hd_tmat *m = sc.m;
    switch (sc.kind) {
    case HD_SC_EMIT: {
        int mod = c->matmod[f->mat];
        if (mod < 0 || !h.front) return;
        if (st.skipsrc && f->nee && !(m->type == HD_MAT_GLOW && h.t > m->maxrad)) return;
        tally(c, mod, m, dir, coef, rng, acc);
        return;
    }
    case HD_SC_PASS: {
        cst cs = st;
        cs.depth++;
        trace(c, h.p, dir, tmax > 0 ? tmax - h.t : 0, cs, coef, rng, acc);
        return;
    }
    case HD_SC_GLASS: {
        double k3[3];
        cst cs = st;
        cs.depth++;
        cs.w = st.w * c_avg(sc.T);
        double fa = admit(c, &cs.w, rng);
        if (fa > 0) {
            for (int i = 0; i < 3; i++) k3[i] = fa * coef[i] * sc.T[i];
            trace(c, h.p, dir, 0, cs, k3, rng, acc);
        }
        cs.w = st.w * c_avg(sc.R);
        fa = admit(c, &cs.w, rng);
        if (fa > 0) {
            for (int i = 0; i < 3; i++) k3[i] = fa * coef[i] * sc.R[i];
            trace(c, h.p, hd_scatter_mirror(&sc), 0, cs, k3, rng, acc);
        }
        return;
    }
    case HD_SC_MIRROR: {
        double k3[3];
        cst cs = st;
        cs.depth++;
        cs.w = st.w * c_avg(m->color);
        double fa = admit(c, &cs.w, rng);
        if (fa > 0) {
            for (int i = 0; i < 3; i++) k3[i] = fa * coef[i] * m->color[i];
            trace(c, h.p, hd_scatter_mirror(&sc), 0, cs, k3, rng, acc);
        }
        return;
    }
    case HD_SC_BSDF:
        if (hd_tmat_bsdf_passes(sc.m, st.scattered ? HD_BSDF_RAY_SCATTERED : HD_BSDF_RAY_VIEW, hd_vdot(dir, h.n) < 0)) {
            cst cs = st;   /* a thickness proxy: the detailed geometry decides */
            cs.depth++;
            trace(c, h.p, dir, tmax > 0 ? tmax - h.t : 0, cs, coef, rng, acc);
            return;
        }
        shade_bsdf(c, &sc, st, coef, rng, acc);
        return;
    case HD_SC_NORMAL:
        shade_normal(c, &sc, st, coef, rng, acc);
        return;
    case HD_SC_ABSORB:
        return;
    }
}

static void irradiance_at(const hd_contrib *c, hd_vec3 p, hd_vec3 n, hd_rng *rng, double scale, double *acc)
{
    static const double white[3] = {1, 1, 1};
    cst st = {0, 0, 0, 1, 1.0, 0, 0};
    /* a white Lambertian receiver: E = π × its radiance */
    double k3[3] = {HD_PI * scale, HD_PI * scale, HD_PI * scale};
    if (c->nlights) direct(c, 0, p, n, NULL, white, NULL, k3, rng, acc);
    if (c->o.ab > 0) ambient(c, p, n, white, st, k3, rng, acc);
}

void hd_contrib_ray(const hd_contrib *c, hd_vec3 org, hd_vec3 dir, double tmax, int irrad,
                    hd_rng *rng, double scale, double *acc)
{
    double len = hd_vlen(dir);
    if (!(len > 0)) return;
    dir = hd_vscale(dir, 1 / len);
    if (irrad == 1) {
        irradiance_at(c, org, dir, rng, scale, acc);
        return;
    }
    cst st = {0, 0, 0, 1, 1.0, 0, 0};
    double k3[3] = {scale, scale, scale};
    if (irrad == 2) {
        /* Radiance's -i: nominally transparent surfaces (glass, trans, BSDF
         * proxies, invisible) pass the ray on as it is, light sources and
         * glows keep their own value (a view matrix's receivers); the first
         * other surface gives its irradiance */
        const hd_tscene *s = c->ts;
        for (; st.depth <= maxdepth(c); st.depth++) {
            hd_hit h;
            if (!hd_tscene_intersect(s, org, dir, st.depth == 0 ? 0 : hd_tscene_eps(s), tmax, &h)) break;
            hd_scatter sc;
            hd_scatter_at(s, &h, dir, 0, &sc);
            int pass = sc.kind == HD_SC_PASS || sc.kind == HD_SC_GLASS ||
                       (sc.kind == HD_SC_NORMAL && sc.m->type == HD_MAT_TRANS) ||
                       (sc.kind == HD_SC_BSDF && hd_tmat_bsdf_passes(sc.m, HD_BSDF_RAY_VIEW, hd_vdot(dir, h.n) < 0));
            if (sc.kind == HD_SC_EMIT) break;
            if (!pass) {
                irradiance_at(c, h.p, h.front ? h.n : hd_vneg(h.n), rng, scale, acc);
                return;
            }
            org = h.p;
            if (tmax > 0) tmax -= h.t;
        }
        if (st.depth > maxdepth(c)) return;
    }
    trace(c, org, dir, tmax, st, k3, rng, acc);
}

hd_status hd_contrib_prepare(hd_contrib *c)
{
    const hd_tscene *s = c->ts;
    c->ncols = 0;
    for (int i = 0; i < c->nmods; i++) {
        for (int j = 0; j < i; j++)
            if (!strcmp(c->mods[i].name, c->mods[j].name))
                return hd_fail(HD_ERR_USAGE, "modifier '%s' is given more than once", c->mods[i].name);
        if (!strcmp(c->mods[i].name, "void"))
            return hd_fail(HD_ERR_USAGE, "modifier 'void' cannot be tracked");
        c->mods[i].first = c->ncols;
        c->ncols += c->mods[i].bin.nbins;
    }
    if (c->nmods == 0) return hd_fail(HD_ERR_USAGE, "no modifiers given (-m or -M)");
    c->nmat = hd_tscene_nmaterials(s);
    free(c->matmod);
    c->matmod = hd_malloc_array((size_t)(c->nmat > 0 ? c->nmat : 1), sizeof *c->matmod);
    if (!c->matmod) return HD_ERR_NOMEM;
    int *used = hd_calloc((size_t)c->nmods, sizeof *used);
    if (!used) return HD_ERR_NOMEM;
    for (int k = 0; k < c->nmat; k++) {
        const hd_tmat *m = hd_tscene_material(s, k);
        c->matmod[k] = -1;
        for (int i = 0; i < c->nmods; i++)
            if (!strcmp(m->name, c->mods[i].name)) { c->matmod[k] = i; break; }
    }
    int ns = hd_tscene_nsurfaces(s);
    for (int k = 0; k < ns; k++) {
        int mod = c->matmod[hd_tscene_surface(s, k)->mat];
        if (mod >= 0) used[mod] = 1;
    }
    for (int i = 0; i < c->nmods; i++)
        if (!used[i]) {
            free(used);
            return hd_fail(HD_ERR_USAGE, "unknown modifier '%s': no surface of the scene uses it", c->mods[i].name);
        }
    free(used);
    free(c->lights);
    c->lights = NULL;
    c->nlights = 0;
    free(c->counts);
    c->counts = NULL;
    if (c->dn < 0) return hd_fail(HD_ERR_USAGE, "-dn %d: must not be negative", c->dn);
    if (c->stats) {
        c->counts = hd_calloc(1, sizeof *c->counts);
        if (!c->counts) return HD_ERR_NOMEM;
    }
    int nl = hd_tscene_nlights(s);
    if (nl > 0) {
        c->lights = hd_malloc_array((size_t)nl, sizeof *c->lights);
        if (!c->lights) return HD_ERR_NOMEM;
        for (int k = 0; k < nl; k++) {
            int si = hd_tscene_light(s, k);
            const hd_surface *f = hd_tscene_surface(s, si);
            if (c->matmod[f->mat] < 0) continue;
            if (f->kind != HD_SURF_SOURCE && f->kind != HD_SURF_POLYGON && f->kind != HD_SURF_RING) {
                hd_warn("%s: tracked light source of this shape is reached by sampled rays only", f->where);
                continue;
            }
            c->lights[c->nlights++] = si;
        }
    }
    return HD_OK;
}

void hd_contrib_free(hd_contrib *c)
{
    for (int i = 0; i < c->nmods; i++) {
        hd_binfn_free(&c->mods[i].bin);
        free(c->mods[i].outspec);
    }
    free(c->mods);
    free(c->matmod);
    free(c->lights);
    free(c->counts);
    memset(c, 0, sizeof *c);
}

void hd_contrib_print_stats(const hd_contrib *c, FILE *f)
{
    if (!c->counts) return;
    const struct hd_contrib_counts *k = c->counts;
    fprintf(f, "%s: stats: %d tracked direct sources (-dn %d); vertices sampling them: %llu before, %llu after a "
            "diffuse bounce; sources sampled there: %llu before, %llu after; shadow rays %llu\n", hd_progname(),
            c->nlights, c->dn, (unsigned long long)atomic_load(&k->vert0), (unsigned long long)atomic_load(&k->vert1),
            (unsigned long long)atomic_load(&k->sampled0), (unsigned long long)atomic_load(&k->sampled1),
            (unsigned long long)atomic_load(&k->shadows));
}

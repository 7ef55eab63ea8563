/* heliodon — backward Monte Carlo renderer (see render.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/bsdf.h"
#include "heliodon/klems.h"
#include "heliodon/render.h"
#include "heliodon/options.h"

#define FTINY 1e-7

/* Targets of options accepted for compatibility without effect. */
static double ignored_d;
static int ignored_i, ignored_t;

void hd_render_option_table(hd_opt *tab, hd_render_opts *o)
{
    const hd_opt t[HD_RENDER_NOPTS] = {
        {"ab", HD_OPT_INT, &o->ab, 0, 0, "N", "maximum number of diffuse bounces"},
        {"ad", HD_OPT_INT, &o->ad, 0, 0, "N", "samples at the first diffuse vertex"},
        {"lw", HD_OPT_REAL, &o->lw, 0, 0, "w", "minimum path weight"},
        {"lr", HD_OPT_INT, &o->lr, 0, 0, "N", "maximum ray depth"},
        {"ss", HD_OPT_REAL, &o->ss, 0, 0, "f", "specular sampling"},
        {"st", HD_OPT_REAL, &o->st, 0, 0, "f", "specular sampling threshold"},
        {"dj", HD_OPT_REAL, &o->dj, 0, 0, "f", "source jitter (0 = source centres)"},
        {"av", HD_OPT_REAL3, o->av, 0, 0, "r g b", "ambient value where -ab is exhausted"},
        {"seed", HD_OPT_COUNT, &o->seed, 0, 0, "N", "random seed, >= 0 (heliodon extension)"},
        /* accepted for compatibility, no effect (no ambient cache, no source subdivision) */
        {"aa", HD_OPT_REAL, &ignored_d, 0, 0, "f", "ignored (no ambient cache: always like -aa 0)"},
        {"ar", HD_OPT_INT, &ignored_i, 0, 0, "N", "ignored"},
        {"as", HD_OPT_INT, &ignored_i, 0, 0, "N", "ignored (no super-sampling, see the manual)"},
        {"dt", HD_OPT_REAL, &ignored_d, 0, 0, "f", "ignored (every source is tested)"},
        {"dc", HD_OPT_REAL, &ignored_d, 0, 0, "f", "ignored"},
        {"ds", HD_OPT_REAL, &ignored_d, 0, 0, "f", "ignored (area sources are sampled stochastically)"},
        {"dr", HD_OPT_INT, &ignored_i, 0, 0, "N", "ignored (no virtual sources)"},
        {"dp", HD_OPT_INT, &ignored_i, 0, 0, "N", "ignored"},
        {"dv", HD_OPT_TOGGLE, &ignored_t, 0, 0, 0, "ignored"},
        {"u", HD_OPT_TOGGLE, &ignored_t, 0, 0, 0, "ignored (streams are always uncorrelated)"},
        {"bv", HD_OPT_TOGGLE, &ignored_t, 0, 0, 0, "ignored"},
        HD_OPT_END};
    memcpy(tab, t, sizeof t);
}

void hd_render_defaults(hd_render_opts *o)
{
    memset(o, 0, sizeof *o);
    o->ab = 0;
    o->ad = 1024;
    o->lw = 2e-3;
    o->lr = -10;
    o->ss = 1;
    o->st = 0.15;
    o->dj = 0;
    o->seed = 1;
}

typedef struct pstate {
    int level;       /* diffuse bounces taken */
    int depth;       /* ray depth */
    int skipsrc;     /* the path went through a sampled (diffuse / rough) scattering:
                        direct sources are not seen (counted by shadow rays) */
    int firstamb;    /* no diffuse vertex yet on this path: use -ad samples */
    double w;        /* path weight */
    double mis_n;    /* > 0: the ray is one of mis_n cosine-weighted diffuse samples whose
                        vertex also sampled the light sources (multiple importance sampling,
                        power heuristic on the per-sample densities: weights that sum to
                        one keep the estimate unbiased, and a single shadow ray to a small
                        source keeps its weight against hundreds of hemisphere samples) */
    double mis_cos;  /* cosine between the ray and that vertex's normal */
    int pm;          /* the ray was sampled at a diffuse vertex that also sampled the sky
                        through the window portals (portal_direct), and has only passed
                        straight through glass / invisible surfaces since */
    double pm_b;     /* that sample's density (cos/π) */
    double pm_d;     /* distance travelled from the vertex */
    double pm_s;     /* density with which the portal strategy picks this direction:
                        Σ t_j²/(A |cos θ_j|) over the portals crossed */
    double pm_k;     /* portal samples per portal at that vertex */
} pstate;

static void c_zero(double c[3]) { c[0] = c[1] = c[2] = 0; }
static double c_max(const double c[3]) { return fmax(c[0], fmax(c[1], c[2])); }
static double c_avg(const double c[3]) { return (c[0] + c[1] + c[2]) / 3; }

static void radiance(const hd_renderer *r, hd_vec3 org, hd_vec3 dir, double tmax, pstate st,
                     hd_rng *rng, double out[3], hd_rayinfo *info);

static int maxdepth(const hd_renderer *r)
{
    int d = r->o.lr < 0 ? -r->o.lr : r->o.lr;
    return d == 0 ? 1000 : d;
}

/* cosine-weighted direction about n from (u1, u2) */
static hd_vec3 cosdir(hd_vec3 n, double u1, double u2)
{
    hd_vec3 a, b;
    hd_vbasis(n, &a, &b);
    double rr = sqrt(u1), ph = 2 * HD_PI * u2;
    double z = sqrt(fmax(0, 1 - u1));
    return hd_vnorm(hd_vadd(hd_vscale(n, z), hd_vadd(hd_vscale(a, rr * cos(ph)), hd_vscale(b, rr * sin(ph)))));
}

/* ---- shadow rays ---- */
/* Transmission from p along l to the surface `target` (distance maxd, or
 * infinite for distant sources).  Returns 0 if blocked. */
static int shadow(const hd_renderer *r, hd_vec3 p, hd_vec3 l, double maxd, int target, double tr[3])
{
    const hd_tscene *s = r->scene;
    double eps = hd_tscene_eps(s);
    hd_vec3 o = p;
    double gone = 0;
    tr[0] = tr[1] = tr[2] = 1;
    for (int iter = 0; iter < 64; iter++) {
        hd_hit h;
        double lim = maxd > 0 ? maxd - gone + eps : 0;
        if (!hd_tscene_intersect(s, o, l, eps, lim, &h)) return 1;
        if (h.surf == target) return 1;
        if (maxd > 0 && gone + h.t >= maxd - eps) return 1;
        const hd_surface *f = hd_tscene_surface(s, h.surf);
        const hd_tmat *m = hd_tscene_material(s, f->mat);
        switch (m->type) {
        case HD_MAT_GLASS: {
            double rf[3], t[3];
            hd_glass_coeffs(m->color, m->rindex, fabs(hd_vdot(l, h.n)), rf, t);
            for (int i = 0; i < 3; i++) tr[i] *= t[i];
            break;
        }
        case HD_MAT_TRANS: {
            hd_nshade ns;
            hd_normal_coeffs(m, fabs(hd_vdot(l, h.n)), &ns);
            if (!ns.pure || ns.tspec <= FTINY) return 0;
            for (int i = 0; i < 3; i++) tr[i] *= ns.tscol[i];
            break;
        }
        case HD_MAT_ILLUM:
        case HD_MAT_INVISIBLE:
            break;
        default:
            return 0;
        }
        if (c_max(tr) <= 1e-12) return 0;
        gone += h.t;
        o = h.p;
    }
    return 0;
}

/* Sample direct source k as seen from p.  Fills the unit direction *l, the
 * solid-angle weight *omega (contribution = L · omega · cos), the distance
 * (0 = infinite) and the radiance L.  Returns 0 if the source gives nothing. */
static int sample_source(const hd_renderer *r, int k, hd_vec3 p, hd_rng *rng,
                         hd_vec3 *l, double *omega, double *dist, double L[3])
{
    const hd_tscene *s = r->scene;
    int si = hd_tscene_light(s, k);
    const hd_surface *f = hd_tscene_surface(s, si);
    const hd_tmat *m = hd_tscene_material(s, f->mat);
    hd_vec3 q, nq;
    switch (f->kind) {
    case HD_SURF_SOURCE:
        if (r->o.dj <= 0) {
            *l = f->b;
        } else {
            double cmax = cos(f->r0);
            double u1 = hd_rng_uniform(rng), u2 = hd_rng_uniform(rng);
            double ct = 1 - u1 * (1 - cmax), stt = sqrt(fmax(0, 1 - ct * ct)), ph = 2 * HD_PI * u2;
            hd_vec3 a, b;
            hd_vbasis(f->b, &a, &b);
            *l = hd_vnorm(hd_vadd(hd_vscale(f->b, ct), hd_vadd(hd_vscale(a, stt * cos(ph)), hd_vscale(b, stt * sin(ph)))));
        }
        *omega = f->area;
        *dist = 0;
        goto emit;
    case HD_SURF_POLYGON:
        q = hd_tscene_sample_polygon(s, si, hd_rng_uniform(rng), hd_rng_uniform(rng), hd_rng_uniform(rng));
        nq = f->n;
        break;
    case HD_SURF_SPHERE: {
        hd_vec3 dc = hd_vsub(f->a, p);
        double d2 = hd_vdot(dc, dc), r2 = f->r0 * f->r0;
        if (!f->inward && d2 > r2 * (1 + 1e-9)) {
            /* uniform in the cone subtended by the sphere */
            double dcl = sqrt(d2), cmax = sqrt(fmax(0, 1 - r2 / d2));
            hd_vec3 ax = hd_vscale(dc, 1 / dcl), a, b;
            hd_vbasis(ax, &a, &b);
            double u1 = hd_rng_uniform(rng), u2 = hd_rng_uniform(rng);
            double ct = 1 - u1 * (1 - cmax), stt = sqrt(fmax(0, 1 - ct * ct)), ph = 2 * HD_PI * u2;
            *l = hd_vnorm(hd_vadd(hd_vscale(ax, ct), hd_vadd(hd_vscale(a, stt * cos(ph)), hd_vscale(b, stt * sin(ph)))));
            double bq = hd_vdot(*l, dc), disc = bq * bq - (d2 - r2);
            *dist = bq - sqrt(fmax(0, disc));
            *omega = 2 * HD_PI * (1 - cmax);
            goto emit;
        }
        double z = 1 - 2 * hd_rng_uniform(rng), ph = 2 * HD_PI * hd_rng_uniform(rng), sr = sqrt(fmax(0, 1 - z * z));
        nq = hd_v3(sr * cos(ph), sr * sin(ph), z);
        q = hd_vmadd(f->a, nq, f->r0);
        if (f->inward) nq = hd_vneg(nq);
        break;
    }
    case HD_SURF_RING: {
        double u = hd_rng_uniform(rng), ph = 2 * HD_PI * hd_rng_uniform(rng);
        double rr = sqrt(f->r0 * f->r0 + u * (f->r1 * f->r1 - f->r0 * f->r0));
        hd_vec3 a, b;
        hd_vbasis(f->b, &a, &b);
        q = hd_vadd(f->a, hd_vadd(hd_vscale(a, rr * cos(ph)), hd_vscale(b, rr * sin(ph))));
        nq = f->b;
        break;
    }
    case HD_SURF_CONE: {   /* cylinders only (cones are not direct sources) */
        hd_vec3 ax = hd_vsub(f->b, f->a), a, b;
        double len = hd_vlen(ax);
        ax = hd_vscale(ax, 1 / len);
        hd_vbasis(ax, &a, &b);
        double h = hd_rng_uniform(rng) * len, ph = 2 * HD_PI * hd_rng_uniform(rng);
        nq = hd_vadd(hd_vscale(a, cos(ph)), hd_vscale(b, sin(ph)));
        q = hd_vadd(hd_vmadd(f->a, ax, h), hd_vscale(nq, f->r0));
        if (f->inward) nq = hd_vneg(nq);
        break;
    }
    default:
        return 0;
    }
    {
        hd_vec3 v = hd_vsub(q, p);
        double d2 = hd_vdot(v, v);
        if (d2 <= 1e-300) return 0;
        double d = sqrt(d2);
        *l = hd_vscale(v, 1 / d);
        double cl = -hd_vdot(*l, nq);
        if (cl <= 0) return 0;          /* back of the emitter */
        *omega = f->area * cl / d2;
        *dist = d;
        if (m->type == HD_MAT_GLOW && m->maxrad > 0 && d > m->maxrad) return 0;
    }
emit:
    {
        double pat = hd_pattern_eval(m, *l);
        for (int i = 0; i < 3; i++) L[i] = m->color[i] * pat;
    }
    return 1;
}

/* Sources that both strategies reach: local `light` surfaces (illum is
 * invisible to non-shadow rays; distant sources and glow keep Radiance's
 * rules). */
static int mis_source(const hd_surface *f, const hd_tmat *m)
{
    return f->nee && m->type == HD_MAT_LIGHT && f->kind != HD_SURF_SOURCE;
}

/* Solid-angle density with which sample_source() picks direction dir from
 * org towards the point at distance t on surface f (cos_l: cosine at the
 * emitter). */
static double source_pdf(const hd_surface *f, hd_vec3 org, double t, double cos_l)
{
    if (f->kind == HD_SURF_SPHERE && !f->inward) {
        hd_vec3 dc = hd_vsub(f->a, org);
        double d2 = hd_vdot(dc, dc), r2 = f->r0 * f->r0;
        if (d2 > r2 * (1 + 1e-9)) return 1 / (2 * HD_PI * (1 - sqrt(fmax(0, 1 - r2 / d2))));
    }
    if (cos_l <= 0 || f->area <= 0) return 0;
    return t * t / (f->area * cos_l);
}

static double power_weight(double a, double b) { return a * a / (a * a + b * b); }

/* Direct light at p (normal nf facing the viewer, view direction v) onto a
 * diffuse / specular surface: adds to out. refl/trans diffuse colours,
 * specular colour scol with roughness alpha2 (rough lobe only). */
static void direct(const hd_renderer *r, hd_vec3 p, hd_vec3 nf, hd_vec3 v,
                   const double rd[3], const double td[3], const double scol[3], double alpha2,
                   int dospec, double mis_n, hd_rng *rng, double out[3])
{
    const hd_tscene *s = r->scene;
    int nl = hd_tscene_nlights(s);
    int dotr = td && c_max(td) > 0;
    for (int k = 0; k < nl; k++) {
        hd_vec3 l;
        double om, dist, L[3], tr[3];
        if (!sample_source(r, k, p, rng, &l, &om, &dist, L)) continue;
        double c = hd_vdot(nf, l);
        double f[3] = {0, 0, 0};
        if (c > 0) {
            double wl = 1;
            if (mis_n > 0) {
                const hd_surface *sf = hd_tscene_surface(s, hd_tscene_light(s, k));
                if (mis_source(sf, hd_tscene_material(s, sf->mat)))
                    wl = power_weight(1 / om, c / HD_PI);
            }
            for (int i = 0; i < 3; i++) f[i] = wl * rd[i] * c * om / HD_PI;
            if (dospec) {
                double sp = hd_specular_lobe(nf, v, l, alpha2, om);
                for (int i = 0; i < 3; i++) f[i] += scol[i] * sp;
            }
        } else if (dotr && c < 0) {
            for (int i = 0; i < 3; i++) f[i] = td[i] * (-c) * om / HD_PI;
        } else {
            continue;
        }
        if (c_max(f) <= 0 || c_max(L) <= 0) continue;
        int tgt = hd_tscene_light(s, k);
        if (!shadow(r, p, l, dist, tgt, tr)) continue;
        for (int i = 0; i < 3; i++) out[i] += f[i] * L[i] * tr[i];
    }
}

/* Shirley–Chiu concentric map of (u,v) in [0,1)² to the unit disk, lifted
 * to a cosine-weighted direction about n (tangent axes a, b). */
static hd_vec3 diskdir(hd_vec3 n, hd_vec3 a, hd_vec3 b, double u, double v)
{
    double x = 2 * u - 1, y = 2 * v - 1, rr, ph;
    if (x == 0 && y == 0) { rr = 0; ph = 0; }
    else if (fabs(x) > fabs(y)) { rr = x; ph = (HD_PI / 4) * (y / x); }
    else { rr = y; ph = HD_PI / 2 - (HD_PI / 4) * (x / y); }
    double dx = rr * cos(ph), dy = rr * sin(ph), z = sqrt(fmax(0, 1 - dx * dx - dy * dy));
    return hd_vnorm(hd_vadd(hd_vscale(n, z), hd_vadd(hd_vscale(a, dx), hd_vscale(b, dy))));
}

/* Radiance's ray admission (rayorigin): a child ray of weight w is traced
 * if w >= lw; below, with -lr > 0 it is dropped, with -lr <= 0 it survives
 * Russian roulette with probability w/lw and is promoted to weight lw.
 * Returns the factor for the child's contribution (0 = not traced) and
 * updates *w. */
static double admit(const hd_renderer *r, double *w, hd_rng *rng)
{
    if (!(*w > 0)) return 0;
    if (r->o.lw <= 0 || *w >= r->o.lw) return 1;
    if (r->o.lr > 0) return 0;
    if (hd_rng_uniform(rng) > *w / r->o.lw) return 0;
    double f = r->o.lw / *w;
    *w = r->o.lw;
    return f;
}

/* ---- window portals ----
 * In Russian-roulette mode (-lr <= 0, no -lw truncation to reproduce), a
 * diffuse vertex that traces one hemisphere ray also samples the sky
 * through every glass polygon ("portal"): one point per portal, the line
 * followed through glass (transmittance at each crossing) and invisible
 * surfaces to the sky.  Both strategies are combined with the power
 * heuristic; for a direction crossing the portals C, the hemisphere ray's
 * weight is p_b²/(p_b² + Σ_C p_j²) and portal k's p_k²/(p_b² + Σ_C p_j²)
 * (p_b = cos/π, p_j = t_j²/(A_j |cos_j|)): the weights sum to one, so the
 * expectation is unchanged.  Directions that meet anything else (ground,
 * frames, reflection off the pane) are left to the hemisphere ray with
 * weight one.  With -lr > 0 (Radiance's hard cut-off, reproduced for
 * conformance) portals are not used: they would add light that the cut-off
 * removes. */
static int portal_mode(const hd_renderer *r)
{
    return r->o.lr <= 0 && !r->o.nomis && !r->o.noportal && hd_tscene_nportals(r->scene) > 0;
}

/* Radiance of the distant source (sky) an indirect ray meets when it
 * leaves the scene in direction dir (radiance()'s rules for such rays). */
static int sky_value(const hd_tscene *s, hd_vec3 dir, double L[3])
{
    int si = hd_tscene_source_hit(s, dir);
    if (si < 0) return 0;
    const hd_surface *f = hd_tscene_surface(s, si);
    const hd_tmat *m = hd_tscene_material(s, f->mat);
    if (!hd_tmat_emits(m) || m->type == HD_MAT_ILLUM) return 0;
    if (f->nee || (m->type == HD_MAT_GLOW && m->maxrad < 0)) return 0;
    double pat = hd_pattern_eval(m, dir);
    for (int i = 0; i < 3; i++) L[i] = m->color[i] * pat;
    return 1;
}

/* kn samples of the portals as one strategy: a portal chosen with
 * probability proportional to its area, a uniform point on it; the solid
 * angle density of a direction is Σ t_j²/(A |cos θ_j|) over the portals j
 * it crosses (A: total portal area).  nb: the hemisphere rays' count at
 * this vertex (power heuristic with counts). */
static void portal_direct(const hd_renderer *r, hd_vec3 p, hd_vec3 nd, const double col[3],
                          double nb, int kn, hd_rng *rng, double out[3])
{
    const hd_tscene *s = r->scene;
    double eps = hd_tscene_eps(s);
    int np = hd_tscene_nportals(s);
    double atot = hd_tscene_portal_area(s);
    for (int j = 0; j < kn; j++) {
        double uk = hd_rng_uniform(rng) * atot;
        int k = 0;
        while (k < np - 1 && uk >= hd_tscene_surface(s, hd_tscene_portal(s, k))->area) {
            uk -= hd_tscene_surface(s, hd_tscene_portal(s, k))->area;
            k++;
        }
        int pk = hd_tscene_portal(s, k);
        double u0 = hd_rng_uniform(rng), u1 = hd_rng_uniform(rng), u2 = hd_rng_uniform(rng);
        hd_vec3 v = hd_vsub(hd_tscene_sample_polygon(s, pk, u0, u1, u2), p);
        double d2 = hd_vdot(v, v);
        if (d2 <= 1e-300) continue;
        hd_vec3 l = hd_vscale(v, 1 / sqrt(d2));
        double c = hd_vdot(nd, l);
        if (c <= 0) continue;
        double tr[3] = {1, 1, 1}, psum = 0, gone = 0;
        int crossed = 0, open = 0;
        hd_vec3 o = p;
        for (int it = 0; it < 64; it++) {
            hd_hit h;
            if (!hd_tscene_intersect(s, o, l, eps, 0, &h)) { open = 1; break; }
            const hd_surface *f = hd_tscene_surface(s, h.surf);
            const hd_tmat *m = hd_tscene_material(s, f->mat);
            gone += h.t;
            if (m->type == HD_MAT_GLASS) {
                double rf[3], t[3], cg = fabs(hd_vdot(l, h.n));
                hd_glass_coeffs(m->color, m->rindex, cg, rf, t);
                for (int i = 0; i < 3; i++) tr[i] *= t[i];
                if (f->portal && cg > 1e-9) {
                    psum += gone * gone / (atot * cg);
                    if (h.surf == pk) crossed = 1;
                }
            } else if (m->type != HD_MAT_ILLUM && m->type != HD_MAT_INVISIBLE) {
                break;
            }
            o = h.p;
        }
        double L[3];
        if (!open || !crossed || !(psum > 0) || !sky_value(s, l, L)) continue;
        double pb = nb * c / HD_PI, pp = kn * psum;
        double f = pp * pp / (pb * pb + pp * pp) * c / (HD_PI * pp);
        for (int i = 0; i < 3; i++) out[i] += col[i] * f * L[i] * tr[i];
    }
}

/* Indirect diffuse ("ambient") light over the hemisphere of nd with
 * coefficient col, as Radiance's -aa 0 sampling: the number of samples
 * follows the ray weight (ad for a ray of weight 1; deeper vertices get
 * fewer, at least one), each sample ray carries weight w·avg(col)/n. */
/* Radiance's hemisphere for a vertex reached with weight w: m × m
 * divisions, m = sqrt(ad·w′) rounded (w′ = w clamped to avoid ray
 * termination); returns the number of rays this renderer traces there
 * (all divisions at the first diffuse vertex, else one), 0 if none would
 * be traced (no -ab left, no reflectance, below -lw with -lr > 0). */
static int amb_plan(const hd_renderer *r, pstate st, double ac, double wref, int *m_out, double *wchild)
{
    if (st.level >= r->o.ab || ac <= 0 || r->o.ad <= 0) return 0;
    double wt = st.w;
    if (r->o.lw > 0) {
        double d = 0.8 * ac * st.w / (r->o.ad * r->o.lw);
        if (wt > d) wt = d;    /* avoid ray termination (as Radiance) */
    }
    int m = (int)(sqrt(r->o.ad * wt) + 0.5);
    if (m < 1) m = 1;
    *m_out = m;
    /* weight of each of Radiance's sample rays (wref: see hd_render_irradiance) */
    double rw = (wref > 0 ? wref : ac) / (m * m);
    if (rw > 1) rw = 1;    /* as Radiance's rayorigin: a coefficient above 1 does not raise the weight */
    *wchild = st.w * rw;
    if (r->o.lr > 0 && *wchild < r->o.lw) return 0;
    return st.firstamb ? m * m : 1;
}

static void ambient(const hd_renderer *r, hd_vec3 p, hd_vec3 nd, const double col[3], double wref,
                    int mis, int portal, pstate st, hd_rng *rng, double out[3])
{
    double ac = c_avg(col);
    int m;
    double wchild;
    if (amb_plan(r, st, ac, wref, &m, &wchild) <= 0) return;
    int ndiv = m * m;
    pstate cs = st;
    cs.level = st.level + 1;
    cs.depth = st.depth + 1;
    cs.skipsrc = 1;
    cs.firstamb = 0;
    cs.w = wchild;
    int deeper = !st.firstamb || ndiv == 1;
    /* portals at the first two vertices below the first diffuse one: deeper
     * vertices carry little weight, and their extra shadow rays cost more
     * than they save (measured on the box and office fisheyes) */
    int pm = portal && deeper && portal_mode(r) && st.level <= 2;
    if (pm) portal_direct(r, p, nd, col, 1, 1, rng, out);
    double f = admit(r, &cs.w, rng);
    if (f <= 0) return;
    if (deeper) {
        /* deeper vertices: one sample, an unbiased estimate of the mean of
         * Radiance's divisions */
        double c[3];
        hd_vec3 d = cosdir(nd, hd_rng_uniform(rng), hd_rng_uniform(rng));
        cs.mis_n = mis ? 1 : 0;
        cs.mis_cos = hd_vdot(d, nd);
        cs.pm = pm;
        cs.pm_b = cs.mis_cos / HD_PI;
        cs.pm_k = 1;
        cs.pm_d = cs.pm_s = 0;
        radiance(r, p, d, 0, cs, rng, c, NULL);
        for (int i = 0; i < 3; i++) out[i] += f * col[i] * c[i];
        return;
    }
    /* first diffuse vertex: every division of the m × m grid (jittered,
     * mapped to the disk and lifted to a cosine-weighted direction) */
    double sum[3] = {0, 0, 0};
    hd_vec3 ua, ub;
    hd_vbasis(nd, &ua, &ub);
    int kn = portal && portal_mode(r) ? ndiv / 8 : 0;
    if (kn > 0) {
        /* first vertex: ndiv/8 portal samples against the ndiv hemisphere
         * rays (power heuristic with the sample counts) */
        double po[3] = {0, 0, 0};
        portal_direct(r, p, nd, col, ndiv, kn, rng, po);
        for (int i = 0; i < 3; i++) out[i] += f * po[i];
    }
    for (int k = 0; k < ndiv; k++) {
        int i = k / m, j = k % m;
        hd_vec3 d = diskdir(nd, ua, ub, (i + hd_rng_uniform(rng)) / m, (j + hd_rng_uniform(rng)) / m);
        double c[3];
        cs.mis_n = mis ? ndiv : 0;
        cs.mis_cos = hd_vdot(d, nd);
        cs.pm = kn > 0;
        cs.pm_b = ndiv * cs.mis_cos / HD_PI;
        cs.pm_k = kn;
        cs.pm_d = cs.pm_s = 0;
        radiance(r, p, d, 0, cs, rng, c, NULL);
        for (int q = 0; q < 3; q++) sum[q] += c[q];
    }
    for (int i = 0; i < 3; i++) out[i] += f * col[i] * sum[i] / ndiv;
}

static void shade_normal(const hd_renderer *r, const hd_tmat *m, const hd_hit *h, hd_vec3 dir,
                         pstate st, hd_rng *rng, double out[3])
{
    hd_vec3 nf = h->front ? h->n : hd_vneg(h->n);
    double cosi = -hd_vdot(dir, nf);
    if (cosi < 0) cosi = 0;
    hd_nshade ns;
    hd_normal_coeffs(m, cosi, &ns);
    int rough = !ns.pure && ns.rspec > FTINY;
    /* direct (weighted against the diffuse samples that will follow) */
    int am;
    double aw;
    int nb = r->o.nomis ? 0 : amb_plan(r, st, c_avg(ns.rdiff), 0, &am, &aw);
    direct(r, h->p, nf, dir, ns.rdiff, m->type == HD_MAT_TRANS ? ns.tdiff : NULL, ns.scol, ns.alpha2,
           rough, nb, rng, out);
    /* indirect diffuse reflection and transmission */
    if (st.level < r->o.ab) {
        if (c_max(ns.rdiff) > 0) ambient(r, h->p, nf, ns.rdiff, 0, nb > 0, 1, st, rng, out);
        if (c_max(ns.tdiff) > 0) ambient(r, h->p, hd_vneg(nf), ns.tdiff, 0, 0, 0, st, rng, out);
    } else {
        for (int i = 0; i < 3; i++) out[i] += (ns.rdiff[i] + ns.tdiff[i]) * r->o.av[i];
    }
    /* specular reflection */
    if (ns.rspec > FTINY) {
        pstate cs = st;
        cs.depth++;
        cs.mis_n = 0;
        cs.w = st.w * c_avg(ns.scol);
        double fa = admit(r, &cs.w, rng);
        if (fa > 0) {
            if (ns.pure) {
                hd_vec3 rd = hd_vmadd(dir, nf, 2 * cosi);
                double c[3];
                radiance(r, h->p, hd_vnorm(rd), 0, cs, rng, c, NULL);
                for (int i = 0; i < 3; i++) out[i] += fa * ns.scol[i] * c[i];
            } else if (ns.rspec > r->o.st && r->o.ss > 0) {
                int n = r->o.ss >= 1 ? (int)(r->o.ss + 0.5) : (hd_rng_uniform(rng) < r->o.ss ? 1 : 0);
                double scale = r->o.ss >= 1 ? 1.0 / n : 1.0 / r->o.ss;
                cs.skipsrc = 1;
                for (int j = 0; j < n; j++) {
                    hd_vec3 sd;
                    if (!hd_specular_sample(nf, dir, ns.alpha2, hd_rng_uniform(rng), hd_rng_uniform(rng), &sd)) continue;
                    double c[3];
                    radiance(r, h->p, sd, 0, cs, rng, c, NULL);
                    for (int i = 0; i < 3; i++) out[i] += fa * ns.scol[i] * c[i] * scale;
                }
            }
        }
    }
    /* specular transmission (trans) */
    if (ns.tspec > FTINY) {
        pstate cs = st;
        cs.depth++;
        cs.mis_n = 0;
        cs.w = st.w * c_avg(ns.tscol);
        double fa = admit(r, &cs.w, rng);
        if (fa > 0) {
            hd_vec3 td = dir;
            if (!ns.pure) {
                hd_vec3 sd;
                /* Gaussian spread about the straight-through direction */
                if (!hd_specular_sample(hd_vneg(nf), hd_vneg(hd_vmadd(dir, nf, 2 * cosi)), ns.alpha2,
                                        hd_rng_uniform(rng), hd_rng_uniform(rng), &sd))
                    sd = dir;
                td = sd;
            }
            double c[3];
            radiance(r, h->p, td, 0, cs, rng, c, NULL);
            for (int i = 0; i < 3; i++) out[i] += fa * ns.tscol[i] * c[i];
        }
    }
}

/* ---- BSDF / aBSDF materials (LBNL XML data) ----
 * Local frame: z = the surface's geometric front normal (never flipped
 * towards the ray), x = up × z, y = z × x (Radiance's m_bsdf convention);
 * the bsdf module's +z "front" is that side.  Direct light: every source is
 * evaluated with f(l, v)·|l.z| (shadow rays as for other materials);
 * indirect: one direction per hit drawn by the module's backward
 * importance sampling (transmission and reflection, both sides), weighted
 * by f·|cos|/pdf.  Sampled rays do not count light from direct sources
 * (shadow rays did) except local `light` surfaces, which are combined with
 * the shadow rays by multiple importance sampling (power heuristic on the
 * BSDF pdf and the source pdf).  Extra Lambertian reals are shaded as a
 * diffuse surface (direct + -ab sampling).  BSDF sampling does not use a
 * -ab bounce (like Radiance's non-diffuse BSDF component): ray depth and
 * -lw limit the paths. */
static hd_vec3 to_local(hd_vec3 v, hd_vec3 x, hd_vec3 y, hd_vec3 z)
{
    return hd_v3(hd_vdot(v, x), hd_vdot(v, y), hd_vdot(v, z));
}

static void shade_bsdf(const hd_renderer *r, const hd_tmat *m, const hd_hit *h, hd_vec3 dir,
                       pstate st, hd_rng *rng, double out[3])
{
    static const double black[3] = {0, 0, 0};
    const hd_tscene *s = r->scene;
    const hd_bsdf *b = m->bsdf;
    hd_vec3 x, y, z;
    if (hd_klems_frame(h->n, m->up, &x, &y, &z)) {
        /* up parallel to the normal: any perpendicular frame */
        z = hd_vnorm(h->n);
        hd_vbasis(z, &x, &y);
    }
    hd_vec3 vo = to_local(hd_vneg(dir), x, y, z);
    int front = vo.z > 0;
    hd_vec3 nf = front ? z : hd_vneg(z);
    /* extra Lambertian parts */
    const double *rdx = front ? m->bsdf_rfront : m->bsdf_rback;
    if (c_max(rdx) > 0 || c_max(m->bsdf_tdiff) > 0) {
        direct(r, h->p, nf, dir, rdx, m->bsdf_tdiff, black, 0, 0, 0, rng, out);
        if (st.level < r->o.ab) {
            if (c_max(rdx) > 0) ambient(r, h->p, nf, rdx, 0, 0, 1, st, rng, out);
            if (c_max(m->bsdf_tdiff) > 0) ambient(r, h->p, hd_vneg(nf), m->bsdf_tdiff, 0, 0, 0, st, rng, out);
        } else {
            for (int i = 0; i < 3; i++) out[i] += (rdx[i] + m->bsdf_tdiff[i]) * r->o.av[i];
        }
    }
    if (!b) return;
    int usemis = !r->o.nomis;
    /* direct light through / off the BSDF */
    int nl = hd_tscene_nlights(s);
    for (int k = 0; k < nl; k++) {
        hd_vec3 l;
        double om, dist, L[3], tr[3];
        if (!sample_source(r, k, h->p, rng, &l, &om, &dist, L)) continue;
        if (c_max(L) <= 0) continue;
        hd_vec3 li = to_local(l, x, y, z);
        double fv = hd_bsdf_eval(b, li, vo);
        if (!(fv > 0)) continue;
        double wl = 1;
        int tgt = hd_tscene_light(s, k);
        const hd_surface *sf = hd_tscene_surface(s, tgt);
        if (usemis && mis_source(sf, hd_tscene_material(s, sf->mat)))
            wl = power_weight(1 / om, hd_bsdf_pdf(b, NULL, vo, li, HD_BSDF_BACKWARD, HD_BSDF_ALL));
        if (!shadow(r, h->p, l, dist, tgt, tr)) continue;
        double c = wl * fv * fabs(li.z) * om;
        for (int i = 0; i < 3; i++) out[i] += c * L[i] * tr[i];
    }
    /* indirect: one importance-sampled direction */
    hd_bsdf_sample smp;
    double u1 = hd_rng_uniform(rng), u2 = hd_rng_uniform(rng), u3 = hd_rng_uniform(rng);
    if (!hd_bsdf_sample_dir(b, NULL, vo, HD_BSDF_BACKWARD, HD_BSDF_ALL, u1, u2, u3, &smp)) return;
    if (!(smp.weight > 0) || !(smp.pdf > 0)) return;
    pstate cs = st;
    cs.depth++;
    cs.skipsrc = 1;
    cs.mis_n = usemis ? 1 : 0;
    cs.mis_cos = smp.pdf * HD_PI;    /* the LIGHT case weighs with mis_cos/π = this pdf */
    cs.w = st.w * smp.weight;
    double fa = admit(r, &cs.w, rng);
    if (fa <= 0) return;
    hd_vec3 d = hd_vnorm(hd_vadd(hd_vscale(x, smp.dir.x), hd_vadd(hd_vscale(y, smp.dir.y), hd_vscale(z, smp.dir.z))));
    double c[3];
    radiance(r, h->p, d, 0, cs, rng, c, NULL);
    for (int i = 0; i < 3; i++) out[i] += fa * smp.weight * c[i];
}

static void radiance(const hd_renderer *r, hd_vec3 org, hd_vec3 dir, double tmax, pstate st,
                     hd_rng *rng, double out[3], hd_rayinfo *info)
{
    const hd_tscene *s = r->scene;
    c_zero(out);
    if (info) { info->hit = 0; info->t = INFINITY; info->surf = -1; }
    if (st.depth > maxdepth(r)) return;
    hd_hit h;
    double eps = hd_tscene_eps(s);
    if (!hd_tscene_intersect(s, org, dir, st.depth == 0 ? 0 : eps, tmax, &h)) {
        if (tmax > 0) return;
        int si = hd_tscene_source_hit(s, dir);
        if (si < 0) return;
        const hd_surface *f = hd_tscene_surface(s, si);
        const hd_tmat *m = hd_tscene_material(s, f->mat);
        if (!hd_tmat_emits(m)) return;
        if (m->type == HD_MAT_ILLUM) return;
        if (st.skipsrc && (f->nee || (m->type == HD_MAT_GLOW && m->maxrad < 0))) return;
        double pat = hd_pattern_eval(m, dir);
        if (st.pm)    /* combined with portal_direct (power heuristic) */
            pat *= st.pm_b * st.pm_b / (st.pm_b * st.pm_b + st.pm_k * st.pm_k * st.pm_s * st.pm_s);
        for (int i = 0; i < 3; i++) out[i] = m->color[i] * pat;
        return;
    }
    if (info) { info->hit = 1; info->t = h.t; info->p = h.p; info->n = h.front ? h.n : hd_vneg(h.n); info->surf = h.surf; }
    const hd_surface *f = hd_tscene_surface(s, h.surf);
    const hd_tmat *m = hd_tscene_material(s, f->mat);
    /* the portal state only survives straight passages (glass
     * transmission, invisible surfaces): cleared for everything else */
    pstate in = st;
    st.pm = 0;
    st.pm_d = st.pm_s = 0;
    switch (m->type) {
    case HD_MAT_LIGHT:
    case HD_MAT_GLOW: {
        if (!h.front) return;
        double wb = 1;
        if (st.skipsrc) {
            if (m->type == HD_MAT_GLOW && m->maxrad < 0) return;
            if (f->nee && st.mis_n > 0 && mis_source(f, m)) {
                /* multiple importance sampling with the shadow rays */
                double pl = source_pdf(f, org, h.t, -hd_vdot(dir, h.n));
                wb = power_weight(st.mis_cos / HD_PI, pl);
            } else if (f->nee && !(m->type == HD_MAT_GLOW && h.t > m->maxrad)) {
                return;
            }
        }
        double pat = hd_pattern_eval(m, dir);
        for (int i = 0; i < 3; i++) out[i] = wb * m->color[i] * pat;
        return;
    }
    case HD_MAT_ILLUM:
    case HD_MAT_INVISIBLE:
        if (m->type == HD_MAT_ILLUM && m->alt >= 0) {
            const hd_tmat *a = hd_tscene_material(s, m->alt);
            if (a->type == HD_MAT_PLASTIC || a->type == HD_MAT_METAL || a->type == HD_MAT_TRANS) {
                shade_normal(r, a, &h, dir, st, rng, out);
                return;
            }
        }
        {   /* pass through */
            pstate cs = in;
            cs.depth++;
            cs.pm_d += h.t;
            radiance(r, h.p, dir, tmax > 0 ? tmax - h.t : 0, cs, rng, out, NULL);
        }
        return;
    case HD_MAT_GLASS: {
        hd_vec3 nf = h.front ? h.n : hd_vneg(h.n);
        double cosi = -hd_vdot(dir, nf), rf[3], tr[3], c[3];
        hd_glass_coeffs(m->color, m->rindex, cosi, rf, tr);
        pstate cs = st;
        cs.depth++;
        cs.w = st.w * c_avg(tr);
        if (in.pm) {    /* straight through: keep the portal state */
            cs.pm = 1;
            cs.pm_b = in.pm_b;
            cs.pm_d = in.pm_d + h.t;
            cs.pm_s = in.pm_s;
            cs.pm_k = in.pm_k;
            if (f->portal && cosi > 1e-9)
                cs.pm_s += cs.pm_d * cs.pm_d / (hd_tscene_portal_area(s) * cosi);
        }
        double fa = admit(r, &cs.w, rng);
        if (fa > 0) {
            radiance(r, h.p, dir, 0, cs, rng, c, NULL);
            for (int i = 0; i < 3; i++) out[i] += fa * tr[i] * c[i];
        }
        cs.pm = 0;
        cs.pm_d = cs.pm_s = 0;
        cs.w = st.w * c_avg(rf);
        cs.mis_n = 0;      /* a mirrored path is not one the shadow rays sample */
        fa = admit(r, &cs.w, rng);
        if (fa > 0) {
            radiance(r, h.p, hd_vnorm(hd_vmadd(dir, nf, 2 * cosi)), 0, cs, rng, c, NULL);
            for (int i = 0; i < 3; i++) out[i] += fa * rf[i] * c[i];
        }
        return;
    }
    case HD_MAT_BSDF:
        shade_bsdf(r, m, &h, dir, st, rng, out);
        return;
    case HD_MAT_MIRROR: {
        hd_vec3 nf = h.front ? h.n : hd_vneg(h.n);
        double cosi = -hd_vdot(dir, nf), c[3];
        pstate cs = st;
        cs.depth++;
        cs.w = st.w * c_avg(m->color);
        cs.mis_n = 0;
        double fa = admit(r, &cs.w, rng);
        if (fa > 0) {
            radiance(r, h.p, hd_vnorm(hd_vmadd(dir, nf, 2 * cosi)), 0, cs, rng, c, NULL);
            for (int i = 0; i < 3; i++) out[i] = fa * m->color[i] * c[i];
        }
        return;
    }
    default:
        shade_normal(r, m, &h, dir, st, rng, out);
        return;
    }
}

static pstate start_state(void)
{
    pstate st;
    memset(&st, 0, sizeof st);
    st.firstamb = 1;
    st.w = 1.0;
    return st;
}

void hd_render_radiance(const hd_renderer *r, hd_vec3 org, hd_vec3 dir, double tmax,
                        hd_rng *rng, double rgb[3], hd_rayinfo *info)
{
    radiance(r, org, dir, tmax, start_state(), rng, rgb, info);
}

void hd_render_irradiance(const hd_renderer *r, hd_vec3 p, hd_vec3 n, hd_rng *rng, double rgb[3])
{
    /* As Radiance's rtrace -I: the point is shaded as a Lambertian surface
     * of "reflectance" π (radiance = E).  The π matters beyond the scale:
     * Radiance sizes the hemisphere and weighs its sample rays (π/n², for
     * the -lw cut-off of the deeper paths) with that coefficient. */
    static const double white[3] = {1, 1, 1}, black[3] = {0, 0, 0};
    static const double pi3[3] = {HD_PI, HD_PI, HD_PI};
    double v[3] = {0, 0, 0};
    int am;
    double aw;
    int nb = r->o.nomis ? 0 : amb_plan(r, start_state(), HD_PI, 0, &am, &aw);
    direct(r, p, n, hd_vneg(n), white, NULL, black, 0, 0, nb, rng, v);
    for (int i = 0; i < 3; i++) v[i] *= HD_PI;
    if (r->o.ab > 0) ambient(r, p, n, pi3, 0, nb > 0, 1, start_state(), rng, v);
    else for (int i = 0; i < 3; i++) v[i] += HD_PI * r->o.av[i];
    for (int i = 0; i < 3; i++) rgb[i] = v[i];
}

void hd_render_irradiance_at_hit(const hd_renderer *r, hd_vec3 org, hd_vec3 dir, hd_rng *rng,
                                 double rgb[3], hd_rayinfo *info)
{
    hd_hit h;
    c_zero(rgb);
    if (info) { info->hit = 0; info->t = INFINITY; info->surf = -1; }
    if (!hd_tscene_intersect(r->scene, org, dir, 0, 0, &h)) return;
    hd_vec3 nf = h.front ? h.n : hd_vneg(h.n);
    if (info) { info->hit = 1; info->t = h.t; info->p = h.p; info->n = nf; info->surf = h.surf; }
    hd_render_irradiance(r, h.p, nf, rng, rgb);
}

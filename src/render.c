/* heliodon — backward Monte Carlo renderer (see render.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/bsdf.h"
#include "heliodon/render.h"
#include "heliodon/options.h"
#include "scatter.h"
#include "shade_bsdf.h"

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
    int scattered;   /* the path went through a sampled scattering (not a view ray
                        or its unscattered continuation: BSDF proxies and aBSDF
                        through peaks treat the two kinds differently) */
    int pm;          /* the ray was sampled at a diffuse vertex that also sampled the sky
                        through the window portals (portal_direct), and has only passed
                        straight through glass / invisible surfaces since */
    double pm_b;     /* that sample's density (cos/π) */
    double pm_d;     /* distance travelled from the vertex */
    double pm_s;     /* density with which the portal strategy picks this direction:
                        Σ t_j²/(A |cos θ_j|) over the portals crossed */
    double pm_k;     /* portal samples per portal at that vertex */
    int mixforce;    /* 1 / 2: this view ray shades the fore / back side of the mixture of two
                        different materials it hits (the split in radiance()) */
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

/* light sources, shadow rays: scatter.c */
static int sample_source(const hd_renderer *r, int k, hd_vec3 p, hd_rng *rng,
                         hd_vec3 *l, double *omega, double *dist, double L[3])
{
    return hd_scatter_sample_source(r->scene, hd_tscene_light(r->scene, k), p, r->o.dj > 0 ? 1 : 0, rng, l, omega,
                                    dist, L);
}

static int shadow(const hd_renderer *r, hd_vec3 p, hd_vec3 l, double maxd, int target, double tr[3])
{
    return hd_scatter_shadow(r->scene, p, l, maxd, target, 0, tr);
}

/* Direct light at p (normal nf facing the viewer): adds to out.  sc: a
 * plastic / metal / trans hit, shaded by its own rule
 * (hd_scatter_normal_direct); NULL: a Lambertian surface of diffuse
 * reflection rd and transmission td (NULL: none). */
static void direct(const hd_renderer *r, hd_vec3 p, hd_vec3 nf, const hd_scatter *sc, const double rd[3],
                   const double td[3], double mis_n, hd_rng *rng, double out[3])
{
    const hd_tscene *s = r->scene;
    int nl = hd_tscene_nlights(s);
    for (int k = 0; k < nl; k++) {
        hd_vec3 l;
        double om, dist, L[3], tr[3], f[3];
        if (!sample_source(r, k, p, rng, &l, &om, &dist, L)) continue;
        double c = hd_vdot(nf, l), wl = 1;
        if (c > 0 && mis_n > 0) {
            const hd_surface *sf = hd_tscene_surface(s, hd_tscene_light(s, k));
            if (hd_scatter_mis_source(sf, hd_tscene_material(s, sf->mat)))
                wl = hd_scatter_power(1 / om, c / HD_PI);
        }
        if (sc ? !hd_scatter_normal_direct(sc, wl, r->o.dj, l, om, f) : !hd_scatter_direct_coef(nf, rd, td, wl, l, om, f))
            continue;
        if (c_max(L) <= 0) continue;
        int tgt = hd_tscene_light(s, k);
        if (!shadow(r, p, l, dist, tgt, tr)) continue;
        for (int i = 0; i < 3; i++) out[i] += f[i] * L[i] * tr[i];
    }
}

/* Radiance's ray admission (scatter.c) */
static double admit(const hd_renderer *r, double *w, hd_rng *rng)
{
    return hd_scatter_admit(r->o.lw, r->o.lr, w, rng);
}

/* ---- window portals ----
 * In Russian-roulette mode (-lr <= 0, no -lw truncation to reproduce), a
 * diffuse vertex also samples the sky through the glass polygons
 * ("portals"): as many portal points as hemisphere rays (stratified at the
 * first vertex, one random point at the next two), each line followed
 * through glass (transmittance at each crossing) and invisible surfaces to
 * the sky.  Both strategies are combined with the power
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
    hd_emit_color(m, dir, NULL, L);
    return 1;
}

/* kn samples of the portals as one strategy: a portal chosen with
 * probability proportional to its area, a uniform point on it; the solid
 * angle density of a direction is Σ t_j²/(A |cos θ_j|) over the portals j
 * it crosses (A: total portal area).  nb: the hemisphere rays' count at
 * this vertex (power heuristic with counts). */
static void portal_direct(const hd_renderer *r, hd_vec3 p, hd_vec3 nd, const double col[3],
                          double nb, int kn, int strat, hd_rng *rng, double out[3])
{
    const hd_tscene *s = r->scene;
    double eps = hd_tscene_eps(s);
    int np = hd_tscene_nportals(s);
    double atot = hd_tscene_portal_area(s);
    /* strat: the kn points form a randomly shifted rank-1 lattice over
     * (cumulative portal area, radial triangle coordinate): each point is
     * still uniform over the portals' area (same density), the set covers
     * them evenly */
    double s0 = 0, s1 = 0, s2 = 0;
    if (strat) {
        s0 = hd_rng_uniform(rng);
        s1 = hd_rng_uniform(rng);
        s2 = hd_rng_uniform(rng);
    }
    for (int j = 0; j < kn; j++) {
        double ua, u1, u2;
        if (strat) {
            ua = (j + s0) / kn;
            u1 = s1 + 0.7548776662466927 * j;
            u1 -= floor(u1);
            u2 = s2 + 0.5698402909980532 * j;
            u2 -= floor(u2);
        } else {
            ua = hd_rng_uniform(rng);
            u1 = hd_rng_uniform(rng);
            u2 = hd_rng_uniform(rng);
        }
        double uk = ua * atot;
        int k = 0;
        while (k < np - 1 && uk >= hd_tscene_surface(s, hd_tscene_portal(s, k))->area) {
            uk -= hd_tscene_surface(s, hd_tscene_portal(s, k))->area;
            k++;
        }
        int pk = hd_tscene_portal(s, k);
        double ak = hd_tscene_surface(s, pk)->area;
        double u0 = ak > 0 ? uk / ak : 0;
        if (u0 >= 1) u0 = 0.9999999999;
        if (u0 < 0) u0 = 0;
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
            hd_tmat mt;
            const hd_tmat *m = hd_scatter_hitmat(hd_tscene_material(s, f->mat), &h, l, &mt);
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
    cs.scattered = 1;
    cs.firstamb = 0;
    cs.w = wchild;
    int deeper = !st.firstamb || ndiv == 1;
    /* portals at the first two vertices below the first diffuse one: deeper
     * vertices carry little weight, and their extra shadow rays cost more
     * than they save (measured on the box and office fisheyes) */
    int pm = portal && deeper && portal_mode(r) && st.level <= 2;
    if (pm) portal_direct(r, p, nd, col, 1, 1, 0, rng, out);
    double f = admit(r, &cs.w, rng);
    if (f <= 0) return;
    if (deeper) {
        /* deeper vertices: one sample, an unbiased estimate of the mean of
         * Radiance's divisions */
        double c[3];
        hd_vec3 d = hd_scatter_cosdir(nd, hd_rng_uniform(rng), hd_rng_uniform(rng));
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
    int kn = portal && portal_mode(r) ? ndiv : 0;
    if (kn > 0) {
        /* first vertex: ndiv portal samples, spread evenly over the
         * portals (stratified), against the ndiv hemisphere rays (power
         * heuristic with the sample counts; measured on the office
         * fisheye: ndiv/8 random samples -> ndiv stratified ones halves
         * error² × time, the box gains 1.9×) */
        double po[3] = {0, 0, 0};
        portal_direct(r, p, nd, col, ndiv, kn, 1, rng, po);
        for (int i = 0; i < 3; i++) out[i] += f * po[i];
    }
    for (int k = 0; k < ndiv; k++) {
        int i = k / m, j = k % m;
        hd_vec3 d = hd_scatter_diskdir(nd, ua, ub, (i + hd_rng_uniform(rng)) / m, (j + hd_rng_uniform(rng)) / m);
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

static void shade_normal(const hd_renderer *r, const hd_scatter *sc, pstate st, hd_rng *rng, double out[3])
{
    const hd_nshade *ns = &sc->ns;
    hd_vec3 nf = sc->nf, dir = sc->dir, p = sc->p;
    /* rough lobes at most -st are lit as diffuse (Radiance's *BLT rule) */
    double ramb[3], tamb[3];
    int smp = hd_scatter_normal_split(sc, r->o.st, ramb, tamb);
    /* direct (weighted against the diffuse samples that will follow) */
    int am;
    double aw;
    int nb = r->o.nomis ? 0 : amb_plan(r, st, c_avg(ramb), 0, &am, &aw);
    direct(r, p, nf, sc, NULL, NULL, nb, rng, out);
    /* indirect diffuse reflection and transmission */
    if (st.level < r->o.ab) {
        if (c_max(ramb) > 0) ambient(r, p, nf, ramb, 0, nb > 0, 1, st, rng, out);
        if (c_max(tamb) > 0) ambient(r, p, hd_vneg(nf), tamb, 0, 0, 0, st, rng, out);
    } else {
        for (int i = 0; i < 3; i++) out[i] += (ramb[i] + tamb[i]) * r->o.av[i];
    }
    /* specular reflection, then transmission (trans): the pure ray, or
     * samples of the rough lobe that do not see direct sources (the
     * Gaussian of the direct term counted them) */
    for (int side = 0; side < 2; side++) {
        const double *col = side ? ns->tscol : ns->scol;
        if (!(smp & (side ? 2 : 1))) continue;
        pstate cs = st;
        cs.depth++;
        cs.mis_n = 0;
        cs.w = st.w * c_avg(col);
        double fa = admit(r, &cs.w, rng);
        if (fa <= 0) continue;
        if (ns->pure) {
            double c[3];
            radiance(r, p, side ? dir : hd_scatter_mirror(sc), 0, cs, rng, c, NULL);
            for (int i = 0; i < 3; i++) out[i] += fa * col[i] * c[i];
        } else if (r->o.ss > 0) {
            int n = r->o.ss >= 1 ? (int)(r->o.ss + 0.5) : (hd_rng_uniform(rng) < r->o.ss ? 1 : 0);
            double scale = r->o.ss >= 1 ? 1.0 / n : 1.0 / r->o.ss;
            cs.skipsrc = 1;
            cs.scattered = 1;
            for (int j = 0; j < n; j++) {
                hd_vec3 sd;
                if (!hd_scatter_spec_draw(sc, side, rng, &sd)) continue;
                double c[3];
                radiance(r, p, sd, 0, cs, rng, c, NULL);
                for (int i = 0; i < 3; i++) out[i] += fa * col[i] * c[i] * scale;
            }
        }
    }
}

/* ---- BSDF / aBSDF materials (LBNL XML data) ----
 * Frame and evaluation: scatter.c (z = the surface's geometric front
 * normal, never flipped towards the ray; x = up × z, y = z × x as
 * Radiance's m_bsdf).  Direct light: every source is evaluated with
 * f(l, v)·|l.z| (shadow rays as for other materials); indirect: one
 * direction per hit drawn by the module's backward importance sampling
 * (transmission and reflection, both sides), weighted by f·|cos|/pdf.
 * Sampled rays do not count light from direct sources (shadow rays did)
 * except local `light` surfaces, which are combined with the shadow rays by
 * multiple importance sampling (power heuristic on the BSDF pdf and the
 * source pdf).  Extra Lambertian reals are shaded as a diffuse surface
 * (direct + -ab sampling).  BSDF sampling does not use a -ab bounce (like
 * Radiance's non-diffuse BSDF component): ray depth and -lw limit the
 * paths.  A side of the data below -st (hd_scatter_bsdf_split) is not
 * sampled but lit with the diffuse rules (an -ab bounce), as Radiance. */
/* The loop itself is shade_bsdf.c's (shared with contrib.c); these
 * callbacks add radiance. */
typedef struct bsdf_ctx {
    const hd_renderer *r;
    pstate st;
    double *out;
    int usemis;
    double L[3];     /* radiance of the source just sampled */
} bsdf_ctx;

static void bsdf_lambert(void *ctx, const hd_scatter *sc, const double ramb[3], const double tamb[3], hd_rng *rng)
{
    bsdf_ctx *x = ctx;
    const hd_renderer *r = x->r;
    const double *rdx = sc->rdx, *tdx = sc->tdx;
    if (c_max(rdx) > 0 || c_max(tdx) > 0) direct(r, sc->p, sc->nf, NULL, rdx, tdx, 0, rng, x->out);
    if (x->st.level < r->o.ab) {
        if (c_max(ramb) > 0) ambient(r, sc->p, sc->nf, ramb, 0, 0, 1, x->st, rng, x->out);
        if (c_max(tamb) > 0) ambient(r, sc->p, hd_vneg(sc->nf), tamb, 0, 0, 0, x->st, rng, x->out);
    } else {
        for (int i = 0; i < 3; i++) x->out[i] += (ramb[i] + tamb[i]) * r->o.av[i];
    }
}

static int bsdf_sample(void *ctx, int k, hd_vec3 p, hd_rng *rng, hd_vec3 *l, double *om, double *dist, int *target)
{
    bsdf_ctx *x = ctx;
    if (!sample_source(x->r, k, p, rng, l, om, dist, x->L)) return 0;
    if (c_max(x->L) <= 0) return 0;
    *target = hd_tscene_light(x->r->scene, k);
    return 1;
}

/* every light source, combined with the sampled continuation by multiple
 * importance sampling where the source is one the continuation can hit */
static double bsdf_eval(void *ctx, const hd_scatter *sc, int k, int target, hd_vec3 l, double om, hd_rng *rng,
                        double *wl)
{
    (void)k;
    bsdf_ctx *x = ctx;
    const hd_tscene *s = x->r->scene;
    const hd_surface *sf = hd_tscene_surface(s, target);
    int want = x->usemis && hd_scatter_mis_source(sf, hd_tscene_material(s, sf->mat));
    int disk = x->r->o.dj > 0 && sf->kind == HD_SURF_SOURCE;   /* sample_source jitters over the whole disk */
    double pb = 0, fc = hd_scatter_bsdf_direct(sc, l, om, x->r->o.ss, x->st.w, sf->b, disk ? sf->r0 : 0, rng,
                                               want ? &pb : NULL);
    if (fc > 0) *wl = want ? hd_scatter_power(1 / om, pb) : 1;
    return fc;
}

static void bsdf_add(void *ctx, int k, int target, hd_vec3 l, double fc, double om, double wl, const double tr[3],
                     hd_rng *rng)
{
    (void)k; (void)target; (void)l; (void)rng;
    bsdf_ctx *x = ctx;
    double c = wl * fc * om;
    for (int i = 0; i < 3; i++) x->out[i] += c * x->L[i] * tr[i];
}

static void bsdf_cont(void *ctx, hd_vec3 o, hd_vec3 d, double wt, double pdf, hd_rng *rng)
{
    bsdf_ctx *x = ctx;
    pstate cs = x->st;
    cs.depth++;
    cs.skipsrc = 1;
    cs.scattered = 1;
    cs.mis_n = x->usemis ? 1 : 0;
    cs.mis_cos = pdf * HD_PI;    /* the LIGHT case weighs with mis_cos/π = this pdf */
    cs.w = x->st.w * wt;
    double fa = admit(x->r, &cs.w, rng);
    if (fa <= 0) return;
    double c[3];
    radiance(x->r, o, d, 0, cs, rng, c, NULL);
    for (int i = 0; i < 3; i++) x->out[i] += fa * wt * c[i];
}

static void shade_bsdf(const hd_renderer *r, const hd_scatter *sc, pstate st, hd_rng *rng, double out[3])
{
    bsdf_ctx x = {r, st, out, !r->o.nomis, {0, 0, 0}};
    const hd_shade_bsdf_ops ops = {bsdf_lambert, hd_tscene_nlights(r->scene), bsdf_sample, bsdf_eval, 0, bsdf_add,
                                   bsdf_cont, r->o.st};
    hd_shade_bsdf(r->scene, sc, rng, &ops, &x);
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
        double pat = 1;
        if (st.pm)    /* combined with portal_direct (power heuristic) */
            pat = st.pm_b * st.pm_b / (st.pm_b * st.pm_b + st.pm_k * st.pm_k * st.pm_s * st.pm_s);
        hd_emit_color(m, dir, NULL, out);
        for (int i = 0; i < 3; i++) out[i] *= pat;
        return;
    }
    if (info) { info->hit = 1; info->t = h.t; info->p = h.p; info->n = h.front ? h.n : hd_vneg(h.n); info->ng = h.n; info->surf = h.surf; }
    const hd_surface *f = hd_tscene_surface(s, h.surf);
    hd_scatter sc;
    hd_scatter_at_sel(s, &h, dir, 0, rng, st.mixforce, &sc);
    if (sc.mixc > 0 && st.level <= 1 && !st.mixforce) {
        /* a view ray, or a ray of the first diffuse bounce, on a mixture of
         * two different materials: both sides shaded and blended with the
         * coefficient, as Radiance does (deeper rays, of small weight,
         * select one side at random with its probability: the same
         * expectation; selecting at the first hits too would be unbiased
         * but noisy where a side has a sharp highlight) */
        double a[3], b[3];
        pstate sa = st, sb = st;
        sa.mixforce = 1;
        sb.mixforce = 2;
        radiance(r, org, dir, tmax, sa, rng, a, NULL);
        radiance(r, org, dir, tmax, sb, rng, b, NULL);
        for (int i = 0; i < 3; i++) out[i] = sc.mixc * a[i] + (1 - sc.mixc) * b[i];
        return;
    }
    st.mixforce = 0;
    const hd_tmat *m = sc.m;
    /* the portal state only survives straight passages (glass
     * transmission, invisible surfaces): cleared for everything else */
    pstate in = st;
    st.pm = 0;
    st.pm_d = st.pm_s = 0;
    switch (sc.kind) {
    case HD_SC_EMIT: {
        if (!h.front) return;
        double wb = 1;
        if (st.skipsrc) {
            if (m->type == HD_MAT_GLOW && m->maxrad < 0) return;
            if (f->nee && st.mis_n > 0 && hd_scatter_mis_source(f, m)) {
                /* multiple importance sampling with the shadow rays */
                double pl = hd_scatter_source_pdf(f, org, h.t, -hd_vdot(dir, h.n));
                wb = hd_scatter_power(st.mis_cos / HD_PI, pl);
            } else if (f->nee && !(m->type == HD_MAT_GLOW && h.t > m->maxrad)) {
                return;
            }
        }
        hd_emit_color(m, dir, &h, out);
        for (int i = 0; i < 3; i++) out[i] *= wb;
        return;
    }
    case HD_SC_PASS: {
        pstate cs = in;
        cs.depth++;
        cs.pm_d += h.t;
        radiance(r, h.p, dir, tmax > 0 ? tmax - h.t : 0, cs, rng, out, NULL);
        return;
    }
    case HD_SC_GLASS: {
        double c[3];
        pstate cs = st;
        cs.depth++;
        cs.w = st.w * c_avg(sc.T);
        if (in.pm) {    /* straight through: keep the portal state */
            double cosi = fabs(hd_vdot(dir, h.n));
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
            for (int i = 0; i < 3; i++) out[i] += fa * sc.T[i] * c[i];
        }
        cs.pm = 0;
        cs.pm_d = cs.pm_s = 0;
        cs.w = st.w * c_avg(sc.R);
        cs.mis_n = 0;      /* a mirrored path is not one the shadow rays sample */
        fa = admit(r, &cs.w, rng);
        if (fa > 0) {
            radiance(r, h.p, hd_scatter_mirror(&sc), 0, cs, rng, c, NULL);
            for (int i = 0; i < 3; i++) out[i] += fa * sc.R[i] * c[i];
        }
        return;
    }
    case HD_SC_BSDF:
        if (hd_tmat_bsdf_passes(m, st.scattered ? HD_BSDF_RAY_SCATTERED : HD_BSDF_RAY_VIEW, hd_vdot(dir, h.n) < 0)) {
            pstate cs = in;   /* a thickness proxy: the detailed geometry decides (as PASS) */
            cs.depth++;
            cs.pm_d += h.t;
            radiance(r, h.p, dir, tmax > 0 ? tmax - h.t : 0, cs, rng, out, NULL);
            return;
        }
        shade_bsdf(r, &sc, st, rng, out);
        return;
    case HD_SC_MIRROR: {
        double c[3];
        pstate cs = st;
        cs.depth++;
        cs.w = st.w * c_avg(m->color);
        cs.mis_n = 0;
        double fa = admit(r, &cs.w, rng);
        if (fa > 0) {
            radiance(r, h.p, hd_scatter_mirror(&sc), 0, cs, rng, c, NULL);
            for (int i = 0; i < 3; i++) out[i] = fa * m->color[i] * c[i];
        }
        return;
    }
    case HD_SC_NORMAL:
        shade_normal(r, &sc, st, rng, out);
        return;
    case HD_SC_ABSORB:
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
    static const double white[3] = {1, 1, 1};
    static const double pi3[3] = {HD_PI, HD_PI, HD_PI};
    double v[3] = {0, 0, 0};
    int am;
    double aw;
    int nb = r->o.nomis ? 0 : amb_plan(r, start_state(), HD_PI, 0, &am, &aw);
    direct(r, p, n, NULL, white, NULL, nb, rng, v);
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
    if (info) { info->hit = 1; info->t = h.t; info->p = h.p; info->n = nf; info->ng = h.n; info->surf = h.surf; }
    hd_render_irradiance(r, h.p, nf, rng, rgb);
}

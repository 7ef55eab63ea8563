/* heliodon — scattering rules of the scene materials shared by the radiance
 * renderer, the contribution tracer and the photon tracer (see scatter.h). */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/bsdf.h"
#include "heliodon/klems.h"
#include "scatter.h"

#define FTINY 1e-7
#define RFTINY 1e-6   /* Radiance's FTINY (double build): the thresholds of normal.c */

/* mean of a colour; exact for grey (c, c, c), so that a photon's factor c[k] / c_avg(c) is
 * exactly 1 there (with (c + c + c) / 3 it could be 1 - 2^-53, and the weight's RGBE code
 * (255, 255, 255, 128) = 0.996 instead of (128, 128, 128, 129) = 1: 20 % of the A4 map) */
static double c_avg(const double c[3]) { return c[0] == c[1] && c[1] == c[2] ? c[0] : (c[0] + c[1] + c[2]) / 3; }

static hd_vec3 to_local(hd_vec3 v, hd_vec3 x, hd_vec3 y, hd_vec3 z)
{
    return hd_v3(hd_vdot(v, x), hd_vdot(v, y), hd_vdot(v, z));
}

static hd_vec3 to_world(const hd_scatter *sc, hd_vec3 v)
{
    return hd_vnorm(hd_vadd(hd_vscale(sc->bx, v.x), hd_vadd(hd_vscale(sc->by, v.y), hd_vscale(sc->bz, v.z))));
}

/* ---- resolving a hit ---- */
void hd_scatter_material(const hd_tmat *m, const hd_hit *h, hd_vec3 dir, hd_scatter *sc)
{
    sc->m = m;
    sc->p = h->p;
    sc->n = h->n;
    sc->dir = dir;
    sc->flat = 1;
    sc->nf = h->front ? h->n : hd_vneg(h->n);
    sc->cosi = -hd_vdot(dir, sc->nf);
    if (sc->cosi < 0) sc->cosi = 0;
    if (!m) { sc->kind = HD_SC_ABSORB; return; }
    switch (m->type) {
    case HD_MAT_LIGHT:
    case HD_MAT_GLOW:
        sc->kind = HD_SC_EMIT;
        return;
    case HD_MAT_ILLUM:
    case HD_MAT_INVISIBLE:
        sc->kind = HD_SC_PASS;
        return;
    case HD_MAT_GLASS:
        sc->kind = HD_SC_GLASS;
        hd_glass_coeffs(m->color, m->rindex, sc->cosi, sc->R, sc->T);
        return;
    case HD_MAT_MIRROR:
        sc->kind = HD_SC_MIRROR;
        return;
    case HD_MAT_BSDF: {
        sc->kind = HD_SC_BSDF;
        hd_tmat_bsdf_frame(m, h->n, &sc->bx, &sc->by, &sc->bz);   /* up parallel to the normal: any frame */
        sc->vo = to_local(hd_vneg(dir), sc->bx, sc->by, sc->bz);
        sc->bfront = sc->vo.z > 0;
        sc->nf = sc->bfront ? sc->bz : hd_vneg(sc->bz);
        sc->cosi = fabs(sc->vo.z);
        sc->rdx = sc->bfront ? m->bsdf_rfront : m->bsdf_rback;
        sc->tdx = m->bsdf_tdiff;
        /* aBSDF's through peak (hd_tmat_bsdf_through) is not used: with Klems
         * data the peak's energy stays in the smeared diagonal patch, and
         * passing shadow rays by the peak counted the sun twice (rcontrib,
         * cfs1_klems.xml: +20 %).  aBSDF is rendered as BSDF. */
        sc->has_thru = 0;
        sc->unsampled = 0;
        return;
    }
    case HD_MAT_PLASTIC:
    case HD_MAT_METAL:
    case HD_MAT_TRANS:
        sc->kind = HD_SC_NORMAL;
        hd_normal_coeffs(m, sc->cosi, &sc->ns);
        return;
    }
    sc->kind = HD_SC_ABSORB;
}

const hd_tmat *hd_scatter_hitmat(const hd_tmat *m, const hd_hit *h, hd_vec3 dir, hd_tmat *tmp)
{
    return hd_scatter_hitmat_side(m, h, dir, 0, tmp);
}

const hd_tmat *hd_scatter_hitmat_side(const hd_tmat *m, const hd_hit *h, hd_vec3 dir, int side, hd_tmat *tmp)
{
    if (!m || !m->chain) return m;
    hd_modray ray = {dir, h->p, h->n, h->t, NULL, side};
    return hd_tmat_modify(m, &ray, tmp, NULL);
}

void hd_scatter_at(const hd_tscene *ts, const hd_hit *h, hd_vec3 dir, int flags, hd_scatter *sc)
{
    hd_scatter_at_sel(ts, h, dir, flags, NULL, 0, sc);
}

void hd_scatter_at_sel(const hd_tscene *ts, const hd_hit *h, hd_vec3 dir, int flags, hd_rng *rng, int force,
                       hd_scatter *sc)
{
    sc->mixc = 0;
    const hd_surface *f = hd_tscene_surface(ts, h->surf);
    const hd_tmat *m = hd_tscene_material(ts, f->mat);
    if (m->type == HD_MAT_ILLUM) {
        if (flags & HD_SC_ILLUM_ANYALT) {
            while (m && m->type == HD_MAT_ILLUM) m = m->alt >= 0 ? hd_tscene_material(ts, m->alt) : NULL;
            if (!m) {   /* void alternate: invisible */
                hd_scatter_material(NULL, h, dir, sc);
                sc->kind = HD_SC_PASS;
                return;
            }
        } else if (m->alt >= 0) {
            const hd_tmat *a = hd_tscene_material(ts, m->alt);
            if (a->type == HD_MAT_PLASTIC || a->type == HD_MAT_METAL || a->type == HD_MAT_TRANS) m = a;
        }
    }
    if (m && m->chain) {   /* patterns, textures, mixtures: this hit's material and normal */
        hd_modray ray = {dir, h->p, h->n, h->t, rng, force};
        hd_vec3 pert;
        m = hd_tmat_modify(m, &ray, &sc->mloc, &pert);
        double mixc = m->mixsel;
        if (pert.x != 0 || pert.y != 0 || pert.z != 0) {
            hd_hit hp = *h;
            hp.n = hd_perturb_normal(h->n, pert, dir);
            hd_scatter_material(m, &hp, dir, sc);
            sc->flat = 0;
        } else {
            hd_scatter_material(m, h, dir, sc);
            sc->flat = f->kind == HD_SURF_POLYGON || f->kind == HD_SURF_RING;
        }
        sc->mixc = mixc;
        return;
    }
    hd_scatter_material(m, h, dir, sc);
    sc->flat = f->kind == HD_SURF_POLYGON || f->kind == HD_SURF_RING;
}

/* ---- directions ---- */
hd_vec3 hd_scatter_cosdir(hd_vec3 n, double u1, double u2)
{
    hd_vec3 a, b;
    hd_vbasis(n, &a, &b);
    double rr = sqrt(u1), ph = 2 * HD_PI * u2;
    double z = sqrt(fmax(0, 1 - u1));
    return hd_vnorm(hd_vadd(hd_vscale(n, z), hd_vadd(hd_vscale(a, rr * cos(ph)), hd_vscale(b, rr * sin(ph)))));
}

void hd_scatter_sincos2pi(double u, double *s, double *c)
{
    double t = 4 * u;                       /* quarter turns in [0, 4) */
    if (!(t >= 0 && t < 4)) t = 4 * (u - floor(u));
    int q = (int)t;
    if (q > 3) q = 3;
    double x = (t - q - 0.5) * (HD_PI / 2);  /* [-pi/4, pi/4] around the quadrant's middle */
    /* Taylor polynomials in x^2, evaluated by Estrin's scheme (short
     * dependency chains; Horner's 9 dependent steps were the cost) */
    const double s1 = -1.0 / 6, s2 = 1.0 / 120, s3 = -1.0 / 5040, s4 = 1.0 / 362880, s5 = -1.0 / 39916800,
                 s6 = 1.0 / 6227020800, s7 = -1.0 / 1307674368000;
    const double c1 = -0.5, c2 = 1.0 / 24, c3 = -1.0 / 720, c4 = 1.0 / 40320, c5 = -1.0 / 3628800,
                 c6 = 1.0 / 479001600, c7 = -1.0 / 87178291200, c8 = 1.0 / 20922789888000;
    double y = x * x, y2 = y * y, y4 = y2 * y2;
    double sx = x * (((1 + s1 * y) + y2 * (s2 + s3 * y)) + y4 * ((s4 + s5 * y) + y2 * (s6 + s7 * y)));
    double cx = ((1 + c1 * y) + y2 * (c2 + c3 * y)) + y4 * (((c4 + c5 * y) + y2 * (c6 + c7 * y)) + y4 * c8);
    /* angle = q pi/2 + pi/4 + x: quadrant q swaps (q odd) and negates (sin
     * for q = 2, 3; cos for q = 1, 2) — done on the bits, without the
     * unpredictable branch of a switch */
    const double h = 0.70710678118654752440;
    double sa = h * (sx + cx), ca = h * (cx - sx);
    uint64_t bs, bc, m = -(uint64_t)(q & 1), sw;
    memcpy(&bs, &sa, 8);
    memcpy(&bc, &ca, 8);
    sw = (bs ^ bc) & m;   /* swap when q is odd */
    bs ^= sw;
    bc ^= sw;
    bs ^= (uint64_t)(q >> 1) << 63;
    bc ^= (uint64_t)((q ^ (q >> 1)) & 1) << 63;
    memcpy(s, &bs, 8);
    memcpy(c, &bc, 8);
}

/* hd_scatter_cosdir with hd_scatter_sincos2pi (photon tracing) */
static hd_vec3 photon_cosdir(hd_vec3 n, double u1, double u2)
{
    hd_vec3 a, b;
    hd_vbasis(n, &a, &b);
    double rr = sqrt(u1), sp, cp;
    hd_scatter_sincos2pi(u2, &sp, &cp);
    double z = sqrt(fmax(0, 1 - u1));
    /* unit up to rounding (n, a, b orthonormal, z^2 + rr^2 = 1): no normalisation */
    return hd_vadd(hd_vscale(n, z), hd_vadd(hd_vscale(a, rr * cp), hd_vscale(b, rr * sp)));
}

hd_vec3 hd_scatter_photon_cosdir(hd_vec3 n, double u1, double u2) { return photon_cosdir(n, u1, u2); }

hd_vec3 hd_scatter_diskdir(hd_vec3 n, hd_vec3 a, hd_vec3 b, double u, double v)
{
    double x = 2 * u - 1, y = 2 * v - 1, rr, ph;
    if (x == 0 && y == 0) { rr = 0; ph = 0; }
    else if (fabs(x) > fabs(y)) { rr = x; ph = (HD_PI / 4) * (y / x); }
    else { rr = y; ph = HD_PI / 2 - (HD_PI / 4) * (x / y); }
    double dx = rr * cos(ph), dy = rr * sin(ph), z = sqrt(fmax(0, 1 - dx * dx - dy * dy));
    return hd_vnorm(hd_vadd(hd_vscale(n, z), hd_vadd(hd_vscale(a, dx), hd_vscale(b, dy))));
}

hd_vec3 hd_scatter_mirror(const hd_scatter *sc)
{
    return hd_vnorm(hd_vmadd(sc->dir, sc->nf, 2 * sc->cosi));
}

int hd_scatter_spec_refl(const hd_scatter *sc, double u1, double u2, hd_vec3 *out)
{
    if (sc->ns.pure) {
        *out = hd_scatter_mirror(sc);
        return 1;
    }
    return hd_specular_sample(sc->nf, sc->dir, sc->ns.alpha2, u1, u2, out);
}

int hd_scatter_spec_trans(const hd_scatter *sc, double u1, double u2, hd_vec3 *out)
{
    if (sc->ns.pure) {
        *out = sc->dir;
        return 1;
    }
    hd_vec3 a, b;
    hd_vbasis(sc->nf, &a, &b);
    double t = sqrt(-sc->ns.alpha2 * log(1 - u1 < 1e-300 ? 1e-300 : 1 - u1)), sp, cp;
    hd_scatter_sincos2pi(u2, &sp, &cp);
    hd_vec3 d = hd_vadd(sc->dir, hd_vadd(hd_vscale(a, t * cp), hd_vscale(b, t * sp)));
    if (hd_vdot(d, sc->nf) >= -RFTINY) return 0;
    *out = hd_vnorm(d);
    return 1;
}

int hd_scatter_spec_try(const hd_scatter *sc, int trans, double jit, hd_rng *rng, hd_vec3 *out)
{
    double u1 = jit * hd_rng_uniform(rng), u2 = hd_rng_uniform(rng);
    return trans ? hd_scatter_spec_trans(sc, u1, u2, out) : hd_scatter_spec_refl(sc, u1, u2, out);
}

int hd_scatter_spec_draw(const hd_scatter *sc, int trans, hd_rng *rng, hd_vec3 *out)
{
    for (int k = 0; k < 10; k++)   /* Radiance's MAXITER */
        if (hd_scatter_spec_try(sc, trans, 1, rng, out)) return 1;
    return 0;
}

int hd_scatter_normal_split(const hd_scatter *sc, double st, double ramb[3], double tamb[3])
{
    const hd_nshade *ns = &sc->ns;
    int rblt = 0, tblt = 0, smp = 0;
    if (ns->rspec > RFTINY) {
        if (!ns->pure && st >= ns->rspec - RFTINY) rblt = 1;
        else smp |= 1;
    }
    if (ns->tspec > RFTINY) {
        if (!ns->pure && st >= ns->tspec - RFTINY) tblt = 1;
        else smp |= 2;
    }
    for (int i = 0; i < 3; i++) {
        ramb[i] = ns->rds > RFTINY ? ns->rdiff[i] + (rblt ? ns->scol[i] : 0) : 0;
        tamb[i] = ns->tds > RFTINY ? ns->tdiff[i] + (tblt ? ns->tscol[i] : 0) : 0;
    }
    return smp;
}

double hd_scatter_admit(double lw, int lr, double *w, hd_rng *rng)
{
    if (!(*w > 0)) return 0;
    if (lw <= 0 || *w >= lw) return 1;
    if (lr > 0) return 0;
    if (hd_rng_uniform(rng) > *w / lw) return 0;
    double f = lw / *w;
    *w = lw;
    return f;
}

/* ---- light sources ---- */
static hd_vec3 cone_dir(hd_vec3 ax, double cmax, double u1, double u2)
{
    double ct = 1 - u1 * (1 - cmax), stt = sqrt(fmax(0, 1 - ct * ct)), ph = 2 * HD_PI * u2;
    hd_vec3 a, b;
    hd_vbasis(ax, &a, &b);
    return hd_vnorm(hd_vadd(hd_vscale(ax, ct), hd_vadd(hd_vscale(a, stt * cos(ph)), hd_vscale(b, stt * sin(ph)))));
}

int hd_scatter_sample_source(const hd_tscene *s, int si, hd_vec3 p, double jitter, hd_rng *rng,
                             hd_vec3 *l, double *omega, double *dist, double L[3])
{
    const hd_surface *f = hd_tscene_surface(s, si);
    const hd_tmat *m = hd_tscene_material(s, f->mat);
    hd_vec3 q, nq;
    hd_hit eh, *ehp = NULL;   /* the emitter's point, for patterns */
    switch (f->kind) {
    case HD_SURF_SOURCE:
        if (jitter <= 0) {
            *l = f->b;
        } else {
            double cmax = cos(f->r0 * fmin(1, jitter));
            double u1 = hd_rng_uniform(rng), u2 = hd_rng_uniform(rng);
            *l = cone_dir(f->b, cmax, u1, u2);
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
            hd_vec3 ax = hd_vscale(dc, 1 / dcl);
            double u1 = hd_rng_uniform(rng), u2 = hd_rng_uniform(rng);
            *l = cone_dir(ax, cmax, u1, u2);
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
        eh.t = d;
        eh.p = q;
        eh.n = nq;
        eh.surf = si;
        eh.front = 1;
        ehp = &eh;
    }
emit:
    hd_emit_color(m, *l, ehp, L);
    return 1;
}

int hd_scatter_mis_source(const hd_surface *f, const hd_tmat *m)
{
    return f->nee && m->type == HD_MAT_LIGHT && f->kind != HD_SURF_SOURCE;
}

double hd_scatter_source_pdf(const hd_surface *f, hd_vec3 org, double t, double cos_l)
{
    if (f->kind == HD_SURF_SPHERE && !f->inward) {
        hd_vec3 dc = hd_vsub(f->a, org);
        double d2 = hd_vdot(dc, dc), r2 = f->r0 * f->r0;
        if (d2 > r2 * (1 + 1e-9)) return 1 / (2 * HD_PI * (1 - sqrt(fmax(0, 1 - r2 / d2))));
    }
    if (cos_l <= 0 || f->area <= 0) return 0;
    return t * t / (f->area * cos_l);
}

double hd_scatter_power(double a, double b) { return a * a / (a * a + b * b); }

/* What a shadow ray along l keeps crossing material m at h: 0 if it stops
 * there, else 1 with the transmission in t. */
static int shadow_trans(const hd_tmat *m, const hd_hit *h, hd_vec3 l, double t[3])
{
    t[0] = t[1] = t[2] = 1;
    switch (m->type) {
    case HD_MAT_GLASS: {
        double rf[3];
        hd_glass_coeffs(m->color, m->rindex, fabs(hd_vdot(l, h->n)), rf, t);
        return 1;
    }
    case HD_MAT_TRANS: {
        hd_nshade ns;
        hd_normal_coeffs(m, fabs(hd_vdot(l, h->n)), &ns);
        if (!ns.pure || ns.tspec <= FTINY) return 0;
        for (int i = 0; i < 3; i++) t[i] = ns.tscol[i];
        return 1;
    }
    case HD_MAT_BSDF:   /* a thickness proxy passes; aBSDF as BSDF (see hd_scatter_material) */
        return !m->absdf && hd_tmat_bsdf_shadow(m, h->n, l, t);
    case HD_MAT_ILLUM:
    case HD_MAT_INVISIBLE:
        return 1;
    default:
        return 0;
    }
}

int hd_scatter_shadow(const hd_tscene *s, hd_vec3 p, hd_vec3 l, double maxd, int target,
                      int strict_distant, double tr[3])
{
    double eps = hd_tscene_eps(s);
    hd_vec3 o = p;
    double gone = 0;
    tr[0] = tr[1] = tr[2] = 1;
    for (int iter = 0; iter < 64; iter++) {
        hd_hit h;
        double lim = maxd > 0 ? maxd - gone + eps : 0;
        if (!hd_tscene_intersect(s, o, l, eps, lim, &h))
            return maxd > 0 || !strict_distant ? 1 : hd_tscene_source_hit_is(s, l, target);
        if (h.surf == target) return 1;
        if (maxd > 0 && gone + h.t >= maxd - eps) return 1;
        const hd_surface *f = hd_tscene_surface(s, h.surf);
        const hd_tmat *m0 = hd_tscene_material(s, f->mat);
        hd_tmat mt;
        double t[3];
        const hd_tmat *m = hd_scatter_hitmat_side(m0, &h, l, 1, &mt);
        int pass = shadow_trans(m, &h, l, t);
        if (m->mixsel > 0) {
            /* a mixture of two different materials: the two sides'
             * transmissions blended with its coefficient (Radiance's
             * raymixture of the shadow ray) */
            double c = m->mixsel, tb[3];
            const hd_tmat *mb = hd_scatter_hitmat_side(m0, &h, l, 2, &mt);
            int passb = shadow_trans(mb, &h, l, tb);
            for (int i = 0; i < 3; i++) t[i] = c * (pass ? t[i] : 0) + (1 - c) * (passb ? tb[i] : 0);
            pass = pass || passb;
        }
        if (!pass) return 0;
        for (int i = 0; i < 3; i++) tr[i] *= t[i];
        if (hd_scatter_cmax(tr) <= 1e-12) return 0;
        gone += h.t;
        o = h.p;
    }
    return 0;
}

int hd_scatter_direct_coef(hd_vec3 nf, const double rd[3], const double td[3], double wl, hd_vec3 l, double om,
                           double f[3])
{
    double c = hd_vdot(nf, l);
    f[0] = f[1] = f[2] = 0;
    if (c > 0) {
        for (int i = 0; i < 3; i++) f[i] = wl * rd[i] * c * om / HD_PI;
    } else if (td && hd_scatter_cmax(td) > 0 && c < 0) {
        for (int i = 0; i < 3; i++) f[i] = td[i] * (-c) * om / HD_PI;
    } else {
        return 0;
    }
    return hd_scatter_cmax(f) > 0;
}

int hd_scatter_normal_lit(const hd_scatter *sc)
{
    const hd_nshade *ns = &sc->ns;
    return (ns->rds > RFTINY && hd_scatter_cmax(ns->rdiff) > 0) || (ns->tds > RFTINY && hd_scatter_cmax(ns->tdiff) > 0) ||
           (!ns->pure && ns->rspec > RFTINY && hd_scatter_cmax(ns->scol) > 0) ||
           (!ns->pure && ns->tspec > RFTINY && hd_scatter_cmax(ns->tscol) > 0);
}

int hd_scatter_normal_direct(const hd_scatter *sc, double wl, double dj, hd_vec3 l, double om, double f[3])
{
    const hd_nshade *ns = &sc->ns;
    double c = hd_vdot(sc->nf, l), trans = ns->tds + ns->tspec;
    f[0] = f[1] = f[2] = 0;
    if (c < 0 ? trans <= RFTINY : trans >= 1 - RFTINY) return 0;   /* wrong side */
    double lrd = ns->rds, ltd = ns->tds, fr = 1;
    if (ns->pure && ns->rspec >= 0.017999 && (lrd > RFTINY || ltd > RFTINY))   /* Fresnel estimate */
        fr = 1 - (exp(-5.85 * fabs(c)) - 0.00287989916);
    if (c > RFTINY && lrd > RFTINY)
        for (int i = 0; i < 3; i++) f[i] += wl * ns->rdiff[i] * fr * c * om / HD_PI;
    if (c < -RFTINY && ltd > RFTINY)
        for (int i = 0; i < 3; i++) f[i] += ns->tdiff[i] * fr * (-c) * om / HD_PI;
    if (c > RFTINY && !ns->pure && ns->rspec > RFTINY) {   /* Gaussian reflected lobe */
        double a2 = ns->alpha2;
        if (sc->flat) a2 += (1 - fmin(fmax(dj, 0), 1)) * om / (4 * HD_PI);
        double g = hd_specular_gauss(sc->nf, sc->dir, l, a2);
        if (g > RFTINY)
            for (int i = 0; i < 3; i++) f[i] += ns->scol[i] * g * c * om;
    }
    if (c < -RFTINY && !ns->pure && ns->tspec > RFTINY) {   /* Gaussian transmitted lobe */
        double a2 = ns->alpha2 + om / HD_PI;
        double g = exp((2 * hd_vdot(sc->dir, l) - 2) / a2) / (HD_PI * a2);
        if (g > RFTINY) {
            double k = g * om * sqrt(-c / fmax(sc->cosi, 0.001));
            for (int i = 0; i < 3; i++) f[i] += ns->tscol[i] * k;
        }
    }
    return hd_scatter_cmax(f) > 0;
}

/* ---- BSDF ---- */
int hd_scatter_bsdf_has_data(const hd_scatter *sc)
{
    return sc->kind == HD_SC_BSDF && sc->m->bsdf != NULL;
}

/* The data component a query (in, out) reads, as hd_bsdf_eval picks it. */
static int bsdf_comp(hd_vec3 in, hd_vec3 out)
{
    if (in.z > 0) return out.z > 0 ? HD_BSDF_RF : out.z < 0 ? HD_BSDF_TF : -1;
    if (in.z < 0) return out.z < 0 ? HD_BSDF_RB : out.z > 0 ? HD_BSDF_TB : -1;
    return -1;
}

/* The Lambertian value (1/sr) split off component c at load. */
static double bsdf_lamb(const hd_bsdf *b, int c)
{
    const hd_bsdf_info *inf = hd_bsdf_get_info(b);
    if (inf->avail[c] == HD_BSDF_RECIPROCAL) c = c == HD_BSDF_TF ? HD_BSDF_TB : HD_BSDF_TF;
    return inf->avail[c] ? inf->lambertian[c] / HD_PI : 0;
}

hd_vec3 hd_scatter_bsdf_jitter(hd_vec3 vo, double r, double u1, double u2)
{
    vo.x += r * (0.5 - u1);
    vo.y += r * (0.5 - u2);
    return hd_vnorm(vo);
}

double hd_scatter_bsdf_view_width(const hd_scatter *sc, double ss, double *st_width)
{
    const hd_bsdf *b = sc->m->bsdf;
    *st_width = 0;
    if (!b || ss <= 0) return 0;
    hd_vec3 vo = sc->vo;
    double pmax, psa = hd_bsdf_view_psa(b, hd_scatter_cache_for(hd_scatter_thread_cache(), sc), vo, &pmax);
    if (psa < 0) {
        double pr = hd_bsdf_cell_psa(b, vo, vo), pt = hd_bsdf_cell_psa(b, vo, hd_vneg(vo));
        pmax = psa = pr > 0 && (pt <= 0 || pr < pt) ? pr : pt;
    }
    *st_width = pmax > 0 ? sqrt(pmax) * (ss < 1 ? ss : 1) : 0;
    return psa > 0 ? sqrt(psa) * (ss < 1 ? ss : 1) : 0;
}

double hd_scatter_bsdf_pdf_back(const hd_scatter *sc, struct hd_bsdf_cache *cache, hd_vec3 l)
{
    const hd_bsdf *b = sc->m->bsdf;
    if (!b) return 0;
    hd_vec3 li = to_local(l, sc->bx, sc->by, sc->bz), vo = sc->vo;
    int side = li.z * vo.z > 0 ? HD_BSDF_REFL : HD_BSDF_TRANS;
    return sc->unsampled & side ? 0 : hd_bsdf_pdf(b, cache, vo, li, HD_BSDF_BACKWARD, HD_BSDF_ALL);
}

int hd_scatter_bsdf_nsamp(double ss, double w)
{
    double n = 4 * ss * w + 0.5;
    return n >= 1 ? (n < 1e6 ? (int)n : 1000000) : 1;
}

/* The rule (docs/design/bsdf.md, "Sources of finite size"): the
 * Lambertian part of the component the view side and the source side
 * select, plus the mean of the non-Lambertian data over view directions
 * jittered in a square of side √psa·min(ss, 1) around vo in the local
 * (x, y) plane, psa the projected solid angle of the data cell that holds
 * (vo, l); jittered queries that land in a cell finer than 0.12 psa are
 * left out of the mean, queries where the data is zero count as zero.
 * The data is queried with the view vector as the first vector (the
 * component of the view side: a window seen from the room reads the
 * room-to-exterior transmission, equal to the other by reciprocity). */
double hd_scatter_bsdf_value(const hd_scatter *sc, hd_vec3 l)
{
    const hd_bsdf *b = sc->m->bsdf;
    if (!b) return 0;
    if (sc->has_thru) return 1;
    hd_vec3 li = to_local(l, sc->bx, sc->by, sc->bz);
    int c = bsdf_comp(sc->vo, li);
    return c < 0 ? 0 : hd_bsdf_eval_comp(b, (hd_bsdf_comp)c, sc->vo, li, 1) * fabs(li.z);
}

double hd_scatter_bsdf_direct(const hd_scatter *sc, hd_vec3 l, double om, double ss, double w, hd_vec3 axis,
                              double half, hd_rng *rng, double *pdf_back)
{
    const hd_bsdf *b = sc->m->bsdf;
    if (!b) return 0;
    hd_vec3 li = to_local(l, sc->bx, sc->by, sc->bz), vo = sc->vo;
    double fv;
    if (sc->has_thru) {
        fv = hd_bsdf_through_direct(b, &sc->thru, vo, li, om);
    } else {
        int c = bsdf_comp(vo, li);
        if (c < 0) return 0;
        fv = bsdf_lamb(b, c);
        double psa = hd_bsdf_cell_psa(b, vo, li), spec = 0;
        if (psa > 0) {
            double r = sqrt(psa) * (ss < 1 ? fmax(ss, 0) : 1);
            /* Radiance's count n, at least 16 stratified samples of the
             * same mean; where Radiance takes one (light rays) left-out
             * queries count as zero, as its single sample then gives 0.
             * With the source's disk (half > 0) every sample also takes its
             * own direction of the disk: the mean over the source jitter. */
            int n = hd_scatter_bsdf_nsamp(ss, w), one = n == 1, cnt = 0;
            if (n < 16) n = 16;
            int jit = r > FTINY, disk = half > 0 && rng, k = jit || disk ? (int)(sqrt((double)n) + 0.5) : 1;
            hd_vec3 ax = {0, 0, 0}, ea = {0, 0, 0}, eb = {0, 0, 0};
            double cmax = cos(half);
            if (disk) {   /* the source's disk (local frame) */
                ax = to_local(axis, sc->bx, sc->by, sc->bz);
                hd_vbasis(ax, &ea, &eb);
            }
            for (int i = 0; i < k * k; i++) {
                hd_vec3 vj = vo, lj = li;
                if (disk) {   /* a direction of the source's disk */
                    double ct = 1 - hd_rng_uniform(rng) * (1 - cmax), st = sqrt(fmax(0, 1 - ct * ct));
                    double sp, cp;
                    hd_scatter_sincos2pi(hd_rng_uniform(rng), &sp, &cp);
                    lj = hd_vnorm(hd_vadd(hd_vscale(ax, ct), hd_vadd(hd_vscale(ea, st * cp), hd_vscale(eb, st * sp))));
                    if (bsdf_comp(vo, lj) != c) { cnt++; continue; }   /* below the horizon: nothing */
                }
                if (jit) {   /* stratified over the square (strata centres without rng) */
                    double u1 = ((i % k) + (rng ? hd_rng_uniform(rng) : 0.5)) / k;
                    double u2 = ((i / k) + (rng ? hd_rng_uniform(rng) : 0.5)) / k;
                    vj = hd_scatter_bsdf_jitter(vj, r, u1, u2);
                }
                double pj, f = hd_bsdf_eval_comp_psa(b, (hd_bsdf_comp)c, vj, lj, 0, &pj);
                if (!(f > 1e-6)) { cnt++; continue; }
                if (pj < 0.12 * psa) {   /* finer data here: left out */
                    cnt += one;
                    continue;
                }
                spec += f;
                cnt++;
            }
            if (cnt) fv += spec / cnt;
        }
    }
    if (!(fv > 0)) return 0;
    if (pdf_back) *pdf_back = hd_scatter_bsdf_pdf_back(sc, NULL, l);
    return fv * fabs(li.z);
}

int hd_scatter_bsdf_split(const hd_scatter *sc, struct hd_bsdf_cache *cache, double st, double *ra, double *ta)
{
    *ra = *ta = 0;
    const hd_bsdf *b = sc->m->bsdf;
    if (!b || sc->has_thru) return 0;
    double w[4];
    hd_bsdf_hemi_parts(b, cache, sc->vo, w);
    int un = 0;
    /* Radiance: b <= specthresh + FTINY; a side without data has nothing to sample */
    if (w[1] <= st + FTINY) { un |= HD_BSDF_REFL; *ra = w[0] + w[1]; }
    if (w[3] <= st + FTINY) { un |= HD_BSDF_TRANS; *ta = w[2] + w[3]; }
    return un;
}

int hd_scatter_bsdf_sample(const hd_scatter *sc, struct hd_bsdf_cache *cache, int mode, int mask, double narrow,
                           double u1, double u2, double u3, hd_vec3 *out, double *weight, double *pdf)
{
    const hd_bsdf *b = sc->m->bsdf;
    if (!b) return 0;
    hd_bsdf_sample smp;
    /* backward: given = towards the eye (vo); forward: given = towards the
     * light, i.e. where the photon came from (also vo) */
    /* a side lit as diffuse instead (hd_scatter_bsdf_split): drawn with the
     * density of both sides, so dropping it leaves the others unbiased */
    if (!hd_bsdf_sample_drop(b, cache, sc->vo, mode, mask, sc->unsampled & mask, narrow, u1, u2, u3, &smp)) return 0;
    if (!(smp.weight > 0) || !(smp.pdf > 0)) return 0;
    if (sc->unsampled & (smp.dir.z * sc->vo.z > 0 ? HD_BSDF_REFL : HD_BSDF_TRANS)) return 0;
    *out = to_world(sc, smp.dir);
    *weight = smp.weight;
    *pdf = smp.pdf;
    return 1;
}

/* ---- photons ---- */
int hd_scatter_photon_stores(const hd_scatter *sc)
{
    switch (sc->kind) {
    case HD_SC_NORMAL:
        return c_avg(sc->ns.rdiff) + c_avg(sc->ns.tdiff) > 0;
    case HD_SC_BSDF:
        return c_avg(sc->rdx) + c_avg(sc->tdx) > 0;
    default:
        return 0;
    }
}

#define SC_NCACHE 8
/* a vertex's values in hd_scatter_source_values' table */
typedef struct srcval_slot {
    const hd_bsdf *b;        /* NULL: empty */
    hd_vec3 bx, by, bz;      /* the data frame */
    int64_t cell;            /* hd_bsdf_vector_cell of vo */
    double sum;
} srcval_slot;
#define SV_BYTES ((size_t)16 << 20)     /* a thread's table, at most */
struct hd_scatter_cache {
    const hd_bsdf *key[SC_NCACHE];
    hd_bsdf_cache *c[SC_NCACHE];
    int n;
    unsigned long epoch;     /* thread caches: sc_epoch when filled */
    /* hd_scatter_source_values: the set (ts, lights, n) the table holds */
    const hd_tscene *sv_ts;
    const int *sv_lights;
    int sv_n, sv_nslot;
    int sv_far;              /* 1 all sources distant, 0 not (no values) */
    srcval_slot *sv_slot;
    double *sv_val;          /* sv_nslot × sv_n */
    double *sv_tmp;          /* sv_n: a vertex left out of the table */
};

static void sv_free(hd_scatter_cache *c)
{
    free(c->sv_slot);
    free(c->sv_val);
    free(c->sv_tmp);
    c->sv_slot = NULL;
    c->sv_val = c->sv_tmp = NULL;
    c->sv_ts = NULL;
    c->sv_lights = NULL;
    c->sv_n = c->sv_nslot = 0;
}

/* the table for the set (ts, lights, n): emptied when the set changes */
static int sv_set(hd_scatter_cache *c, const hd_tscene *ts, const int *lights, int n)
{
    if (c->sv_n == n && c->sv_ts == ts && c->sv_lights == lights) return 1;
    sv_free(c);
    int far = 1;
    for (int i = 0; i < n && far; i++)
        far = hd_tscene_surface(ts, lights ? lights[i] : hd_tscene_light(ts, i))->kind == HD_SURF_SOURCE;
    size_t per = (size_t)n * sizeof(double) + sizeof(srcval_slot), ns = SV_BYTES / per;
    if (ns > 8192) ns = 8192;
    if (ns < 1) ns = 1;
    if (far) {
        c->sv_tmp = hd_malloc_array((size_t)n, sizeof(double));
        c->sv_slot = hd_calloc(ns, sizeof(srcval_slot));
        c->sv_val = hd_malloc_array(ns * (size_t)n, sizeof(double));
        if (!c->sv_tmp || !c->sv_slot || !c->sv_val) { sv_free(c); return 0; }
    }
    c->sv_ts = ts;
    c->sv_lights = lights;
    c->sv_n = n;
    c->sv_nslot = far ? (int)ns : 0;
    c->sv_far = far;
    return 1;
}

static int same_frame(const srcval_slot *s, const hd_scatter *sc)
{
    return !memcmp(&s->bx, &sc->bx, sizeof s->bx) && !memcmp(&s->by, &sc->by, sizeof s->by) &&
           !memcmp(&s->bz, &sc->bz, sizeof s->bz);
}

static uint64_t frame_hash(const hd_scatter *sc, const hd_bsdf *b, int64_t cell)
{
    const hd_vec3 *f[3] = {&sc->bx, &sc->by, &sc->bz};
    uint64_t h = hd_hash64((uint64_t)cell, (uint64_t)(uintptr_t)b);
    for (int k = 0; k < 3; k++) {
        double v[3] = {f[k]->x, f[k]->y, f[k]->z};
        for (int i = 0; i < 3; i++) {
            uint64_t u;
            memcpy(&u, &v[i], sizeof u);
            h = hd_hash64(h, u);
        }
    }
    return h;
}

const double *hd_scatter_source_values(hd_scatter_cache *c, const hd_scatter *sc, const hd_tscene *ts,
                                       const int *lights, int n, double *sum)
{
    *sum = 0;
    if (!c || n <= 0 || sc->kind != HD_SC_BSDF || !sc->m->bsdf) return NULL;
    if (!sv_set(c, ts, lights, n) || !c->sv_far) return NULL;
    const hd_bsdf *b = sc->m->bsdf;
    int64_t cell = sc->has_thru ? -1 : hd_bsdf_vector_cell(b, sc->vo);
    srcval_slot *s = NULL;
    double *v = c->sv_tmp;
    if (cell >= 0) {
        size_t k = (size_t)(frame_hash(sc, b, cell) % (uint64_t)c->sv_nslot);
        s = &c->sv_slot[k];
        v = c->sv_val + k * (size_t)n;
        if (s->b == b && s->cell == cell && same_frame(s, sc)) {
            *sum = s->sum;
            return v;
        }
    }
    double q = 0;
    for (int i = 0; i < n; i++) {
        const hd_surface *f = hd_tscene_surface(ts, lights ? lights[i] : hd_tscene_light(ts, i));
        q += v[i] = hd_scatter_bsdf_value(sc, f->b);
    }
    if (s) *s = (srcval_slot){b, sc->bx, sc->by, sc->bz, cell, q};
    *sum = q;
    return v;
}

/* Bumped whenever a material's BSDF is released: the pool's threads live
 * on between loops (and scenes), and a BSDF allocated later at the same
 * address must not find the old one's cache. */
static atomic_ulong sc_epoch;
void hd_scatter_forget_bsdfs(void) { atomic_fetch_add(&sc_epoch, 1); }

hd_scatter_cache *hd_scatter_cache_new(void) { return hd_calloc(1, sizeof(hd_scatter_cache)); }

void hd_scatter_cache_free(hd_scatter_cache *c)
{
    if (!c) return;
    for (int i = 0; i < c->n; i++) hd_bsdf_cache_free(c->c[i]);
    sv_free(c);
    free(c);
}

static pthread_key_t tc_key;
static pthread_once_t tc_once = PTHREAD_ONCE_INIT;
static int tc_ok;
static void tc_free(void *p) { hd_scatter_cache_free(p); }
static void tc_init(void) { tc_ok = pthread_key_create(&tc_key, tc_free) == 0; }

hd_scatter_cache *hd_scatter_thread_cache(void)
{
    pthread_once(&tc_once, tc_init);
    if (!tc_ok) return NULL;
    hd_scatter_cache *c = pthread_getspecific(tc_key);
    unsigned long ep = atomic_load(&sc_epoch);
    if (c && c->epoch != ep) {
        for (int i = 0; i < c->n; i++) hd_bsdf_cache_free(c->c[i]);
        c->n = 0;
        sv_free(c);
        c->epoch = ep;
    }
    if (!c) {
        c = hd_scatter_cache_new();
        if (c) c->epoch = ep;
        if (c && pthread_setspecific(tc_key, c) != 0) {
            hd_scatter_cache_free(c);
            c = NULL;
        }
    }
    return c;
}

struct hd_bsdf_cache *hd_scatter_cache_for(hd_scatter_cache *c, const hd_scatter *sc)
{
    if (!c || sc->kind != HD_SC_BSDF || !sc->m->bsdf) return NULL;
    const hd_bsdf *b = sc->m->bsdf;
    for (int i = 0; i < c->n; i++)
        if (c->key[i] == b) return c->c[i];
    if (c->n == SC_NCACHE) return NULL;
    hd_bsdf_cache *bc = hd_bsdf_cache_new(b, 0);
    if (!bc) return NULL;
    c->key[c->n] = b;
    c->c[c->n++] = bc;
    return bc;
}

/* photon_cosdir with two fresh random numbers, the second argument drawn
 * first (the order the calls with both draws as arguments had, as gcc
 * compiled them; now fixed, and the photon tracer's tables repeat it) */
static hd_vec3 cosdir_draw(hd_vec3 n, hd_rng *rng)
{
    double u2 = hd_rng_uniform(rng), u1 = hd_rng_uniform(rng);
    return photon_cosdir(n, u1, u2);
}

hd_scevent hd_scatter_photon(const hd_scatter *sc, hd_scatter_cache *cache, double u, hd_rng *rng,
                             hd_vec3 *nd, double fac[3])
{
    switch (sc->kind) {
    case HD_SC_GLASS: {
        double pt = c_avg(sc->T), pr = c_avg(sc->R);
        if (u < pt) {
            *nd = sc->dir;
            for (int k = 0; k < 3; k++) fac[k] = sc->T[k] / pt;
            return HD_SCE_GLASS_T;
        }
        if (u < pt + pr) {
            *nd = hd_scatter_mirror(sc);
            for (int k = 0; k < 3; k++) fac[k] = sc->R[k] / pr;
            return HD_SCE_SPECULAR;
        }
        return HD_SCE_ABSORB;
    }
    case HD_SC_MIRROR: {
        double pr = c_avg(sc->m->color);
        if (u >= pr) return HD_SCE_ABSORB;
        *nd = hd_scatter_mirror(sc);
        for (int k = 0; k < 3; k++) fac[k] = sc->m->color[k] / pr;
        return HD_SCE_SPECULAR;
    }
    case HD_SC_NORMAL: {
        const hd_nshade *ns = &sc->ns;
        double pd = c_avg(ns->rdiff), ps = c_avg(ns->scol), ptd = c_avg(ns->tdiff), pts = c_avg(ns->tscol);
        if (u < pd) {
            *nd = cosdir_draw(sc->nf, rng);
            for (int k = 0; k < 3; k++) fac[k] = ns->rdiff[k] / pd;
            return HD_SCE_DIFFUSE;
        }
        if (u < pd + ps) {
            double u1 = hd_rng_uniform(rng), u2 = hd_rng_uniform(rng);
            if (!hd_scatter_spec_refl(sc, u1, u2, nd)) return HD_SCE_ABSORB;
            for (int k = 0; k < 3; k++) fac[k] = ns->scol[k] / ps;
            return HD_SCE_SPECULAR;
        }
        if (u < pd + ps + ptd) {
            *nd = cosdir_draw(hd_vneg(sc->nf), rng);
            for (int k = 0; k < 3; k++) fac[k] = ns->tdiff[k] / ptd;
            return HD_SCE_DIFFUSE;
        }
        if (u < pd + ps + ptd + pts) {
            if (ns->pure) *nd = sc->dir;
            else {
                double u1 = hd_rng_uniform(rng), u2 = hd_rng_uniform(rng);
                if (!hd_scatter_spec_trans(sc, u1, u2, nd)) return HD_SCE_ABSORB;
            }
            for (int k = 0; k < 3; k++) fac[k] = ns->tscol[k] / pts;
            return HD_SCE_SPECULAR;
        }
        return HD_SCE_ABSORB;
    }
    case HD_SC_BSDF: {
        /* lobes: extra Lambertian reflection, extra Lambertian transmission,
         * the data (forward-sampled; its albedo for this incidence is the
         * sample's weight).  Russian roulette with the lobe albedos; if they
         * sum to more than one, the choice is normalised and fac carries
         * the excess. */
        double prd = c_avg(sc->rdx), ptd = c_avg(sc->tdx);
        double u1 = hd_rng_uniform(rng), u2 = hd_rng_uniform(rng), u3 = hd_rng_uniform(rng);
        hd_vec3 bd;
        double wb = 0, pdf;
        struct hd_bsdf_cache *bc = hd_scatter_cache_for(cache, sc);
        if (!hd_scatter_bsdf_sample(sc, bc, HD_BSDF_FORWARD, HD_BSDF_ALL, 1, u1, u2, u3, &bd, &wb, &pdf))
            wb = 0;
        double tot = prd + ptd + wb, sc1 = tot > 1 ? tot : 1;
        double x = u * sc1;
        if (x < prd) {
            *nd = cosdir_draw(sc->nf, rng);
            for (int k = 0; k < 3; k++) fac[k] = sc->rdx[k] / prd * sc1;
            return HD_SCE_DIFFUSE;
        }
        if (x < prd + ptd) {
            *nd = cosdir_draw(hd_vneg(sc->nf), rng);
            for (int k = 0; k < 3; k++) fac[k] = sc->tdx[k] / ptd * sc1;
            return HD_SCE_DIFFUSE;
        }
        if (x < tot) {
            *nd = bd;
            /* chosen with probability wb/sc1: the factor restores wb */
            for (int k = 0; k < 3; k++) fac[k] = sc1;
            return HD_SCE_BSDF;
        }
        return HD_SCE_ABSORB;
    }
    default:
        return HD_SCE_ABSORB;
    }
}

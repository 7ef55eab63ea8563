/* Primary hits of view/sensor rays in photon-map gathers: density-estimate
 * lookups where the ray meets a diffuse surface, analytic per-source terms
 * where it meets what a density estimate cannot answer (see pmprimary.h). */
#include "pmprimary.h"
#include "heliodon/material.h"
#include "scatter.h"

#include <math.h>
#include <string.h>


static void add_point(hd_pmprim *pp, hd_vec3 p, hd_vec3 n, const double f[3], const double k[3], double kscale)
{
    if (pp->npt >= HD_PMPRIM_PTS) return;
    hd_pmprim_point *q = &pp->pt[pp->npt];
    for (int i = 0; i < 3; i++) q->f[i] = f[i] * (k ? k[i] : 1) * kscale;
    if (hd_scatter_cmax(q->f) <= 0) return;
    q->p = p;
    q->n = n;
    pp->npt++;
}

static void add_ana(hd_pmprim *pp, int kind, const hd_hit *h, hd_vec3 d, const double f[3])
{
    if (pp->nana >= HD_PMPRIM_ANA) return;
    hd_pmprim_ana *a = &pp->ana[pp->nana++];
    memset(a, 0, sizeof *a);
    a->kind = kind;
    if (h) a->h = *h;
    a->d = d;
    for (int i = 0; i < 3; i++) a->f[i] = f[i];
}

static void walk(const hd_tscene *ts, hd_vec3 org, hd_vec3 d, const double f0[3], int irrad, int depth,
                 double lw, double tmin, hd_pmprim *pp)
{
    double f[3] = {f0[0], f0[1], f0[2]};
    double eps = hd_tscene_eps(ts);
    for (int guard = 0; guard < 100; guard++) {
        if (hd_scatter_cmax(f) < lw) return;
        hd_hit h;
        if (!hd_tscene_intersect(ts, org, d, tmin, 0, &h)) {
            if (irrad == 0) add_ana(pp, HD_PMPRIM_ESCAPE, NULL, d, f);
            return;
        }
        hd_scatter sc;
        hd_scatter_at(ts, &h, d, 0, &sc);
        switch (sc.kind) {
        case HD_SC_PASS:
            org = h.p;
            tmin = eps;
            continue;
        case HD_SC_GLASS: {
            if (depth > 0) {
                double fr[3];
                for (int i = 0; i < 3; i++) fr[i] = f[i] * sc.R[i];
                walk(ts, h.p, hd_scatter_mirror(&sc), fr, irrad, depth - 1, lw, eps, pp);
            }
            for (int i = 0; i < 3; i++) f[i] *= sc.T[i];
            org = h.p;
            tmin = eps;
            continue;
        }
        case HD_SC_MIRROR:
            if (depth <= 0) return;
            for (int i = 0; i < 3; i++) f[i] *= sc.m->color[i];
            d = hd_scatter_mirror(&sc);
            org = h.p;
            tmin = eps;
            depth--;
            continue;
        case HD_SC_NORMAL: {
            const hd_nshade *ns = &sc.ns;
            if (irrad == 2) { add_point(pp, h.p, sc.nf, f, NULL, 1); return; }
            add_point(pp, h.p, sc.nf, f, ns->rdiff, 1 / HD_PI);
            if (hd_scatter_cmax(ns->tdiff) > 0) add_point(pp, h.p, hd_vneg(sc.nf), f, ns->tdiff, 1 / HD_PI);
            if (ns->rspec > 0) {
                if (ns->pure) {
                    if (depth > 0) {
                        double fs[3];
                        for (int i = 0; i < 3; i++) fs[i] = f[i] * ns->scol[i];
                        walk(ts, h.p, hd_scatter_mirror(&sc), fs, irrad, depth - 1, lw, eps, pp);
                    }
                } else {
                    add_ana(pp, HD_PMPRIM_SURF, &h, d, f);
                }
            }
            if (ns->tspec > 0 && ns->pure) {   /* straight through a pure trans */
                for (int i = 0; i < 3; i++) f[i] *= ns->tscol[i];
                org = h.p;
                tmin = eps;
                continue;
            }
            return;
        }
        case HD_SC_BSDF:
            if (irrad == 2) { add_point(pp, h.p, sc.nf, f, NULL, 1); return; }
            if (sc.rdx && hd_scatter_cmax(sc.rdx) > 0) add_point(pp, h.p, sc.nf, f, sc.rdx, 1 / HD_PI);
            if (hd_scatter_bsdf_has_data(&sc)) add_ana(pp, HD_PMPRIM_SURF, &h, d, f);
            return;
        default:   /* absorbing, emitting: nothing a distant-source DC sees */
            return;
        }
    }
}

int hd_pmap_primary(const hd_tscene *ts, hd_vec3 org, hd_vec3 dir, int irrad, double scale, int depth,
                    double lw, hd_pmprim *out)
{
    out->npt = out->nana = 0;
    double f[3] = {scale, scale, scale};
    hd_vec3 d = hd_vnorm(dir);
    if (irrad == 1) {
        out->pt[0].p = org;
        out->pt[0].n = d;
        for (int i = 0; i < 3; i++) out->pt[0].f[i] = scale;
        out->npt = 1;
        return 1;
    }
    walk(ts, org, d, f, irrad, depth, lw * fabs(scale), 0, out);
    return out->npt + out->nana;
}

int hd_pmprim_direct(const hd_tscene *ts, const hd_pmprim *pp, hd_vec3 l, double half, double ss, double out[3])
{
    int any = 0;
    double om = 2 * HD_PI * (1 - cos(half)), cosh = cos(half);
    for (int a = 0; a < pp->nana; a++) {
        const hd_pmprim_ana *r = &pp->ana[a];
        if (r->kind == HD_PMPRIM_ESCAPE) {
            if (hd_vdot(r->d, l) >= cosh) {
                for (int i = 0; i < 3; i++) out[i] += r->f[i];
                any = 1;
            }
            continue;
        }
        hd_scatter sc;
        hd_scatter_at(ts, &r->h, r->d, 0, &sc);
        double coef[3] = {0, 0, 0};
        if (sc.kind == HD_SC_NORMAL) {
            if (hd_vdot(sc.nf, l) <= 0) continue;
            double sp = hd_specular_lobe(sc.nf, r->d, l, sc.ns.alpha2, om);
            if (!(sp > 0)) continue;
            for (int i = 0; i < 3; i++) coef[i] = sc.ns.scol[i] * sp;
        } else if (sc.kind == HD_SC_BSDF) {
            double fc = hd_scatter_bsdf_direct(&sc, l, om, ss, 1, l, 0, NULL, NULL);
            if (!(fc > 0)) continue;
            for (int i = 0; i < 3; i++) coef[i] = fc * om;
        } else {
            continue;
        }
        double tr[3];
        if (!hd_scatter_shadow(ts, r->h.p, l, 0, -1, 0, tr)) continue;
        for (int i = 0; i < 3; i++) out[i] += r->f[i] * coef[i] * tr[i];
        any = 1;
    }
    return any;
}

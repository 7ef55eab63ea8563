/* heliodon — the BSDF shading loop of the backward walk, walk.c (see
 * shade_bsdf.h). */
#include <math.h>

#include "heliodon/bsdf.h"
#include "shade_bsdf.h"

static double c_max(const double c[3]) { return fmax(c[0], fmax(c[1], c[2])); }

void hd_shade_bsdf(const hd_tscene *ts, const hd_scatter *sc, hd_rng *rng, const hd_shade_bsdf_ops *ops, void *ctx)
{
    hd_vec3 nf = sc->nf, p = sc->p;
    if (!hd_scatter_bsdf_has_data(sc)) {
        if (c_max(sc->rdx) > 0 || c_max(sc->tdx) > 0) ops->lambert(ctx, sc, sc->rdx, sc->tdx, rng);
        return;
    }
    /* sides below the specular threshold: lit as diffuse (with the extra
     * Lambertian reals), not sampled */
    hd_scatter s1 = *sc;
    double ra, ta, ramb[3], tamb[3];
    struct hd_bsdf_cache *cache = hd_scatter_cache_for(hd_scatter_thread_cache(), sc);
    s1.unsampled = hd_scatter_bsdf_split(sc, cache, ops->st, &ra, &ta);
    sc = &s1;
    for (int i = 0; i < 3; i++) {
        ramb[i] = sc->rdx[i] + ra;
        tamb[i] = sc->tdx[i] + ta;
    }
    if (c_max(ramb) > 0 || c_max(tamb) > 0) ops->lambert(ctx, sc, ramb, tamb, rng);
    /* direct sources through / off the data */
    for (int k = 0; k < ops->nsources; k++) {
        hd_vec3 l;
        double om, dist, tr[3], wl = 1;
        int tgt;
        if (!ops->sample(ctx, k, p, rng, &l, &om, &dist, &tgt)) continue;
        double fc = ops->eval(ctx, sc, k, tgt, l, om, rng, &wl);
        if (!(fc > 0)) continue;
        hd_vec3 so = hd_vdot(l, nf) < 0 ? hd_tmat_bsdf_through_origin(sc->m, p, sc->n) : p;
        if (!hd_scatter_shadow(ts, so, l, dist, tgt, ops->strict_distant, tr)) continue;
        ops->add(ctx, k, tgt, l, fc, om, wl, tr, rng);
    }
    /* one importance-sampled continuation */
    if (sc->unsampled == HD_BSDF_ALL) return;
    double u1 = hd_rng_uniform(rng), u2 = hd_rng_uniform(rng), u3 = hd_rng_uniform(rng);
    hd_vec3 d;
    double wt, pdf;
    if (!hd_scatter_bsdf_sample(sc, cache, HD_BSDF_BACKWARD, u1, u2, u3, &d, &wt, &pdf))
        return;
    hd_vec3 o = hd_vdot(d, nf) < 0 ? hd_tmat_bsdf_through_origin(sc->m, p, sc->n) : p;
    ops->cont(ctx, o, d, wt, pdf, rng);
}

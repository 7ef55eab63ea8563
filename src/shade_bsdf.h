/* heliodon — the shading loop of the BSDF / aBSDF materials, shared by the
 * backward walk (walk.c: radiance for rtrace / rpict, coefficients for
 * rcontrib / rfluxmtx).
 *
 * At a BSDF hit (resolved by hd_scatter_at into sc) the shape is always:
 *   1. extra Lambertian reals (rdx / tdx of the side hit) shaded as a
 *      diffuse surface — the integrator's own diffuse rules (callback);
 *      a side of the data below the specular threshold st (Radiance's
 *      -st, hd_scatter_bsdf_split) adds its hemispherical value to the
 *      indirect part of that callback and is not sampled in 3.;
 *   2. if the material has data: every direct source the integrator
 *      considers is sampled (callback), its f(l, v)·|cos l| evaluated
 *      (callback: the integrator picks MIS weights or a disk average), the
 *      shadow ray leaves from the transmitted side's origin when l goes
 *      through (thickness proxy, hd_tmat_bsdf_through_origin) and the
 *      unblocked term is handed back (callback: add radiance, or tally a
 *      coefficient);
 *   3. one backward importance-sampled continuation through the data
 *      (three uniforms drawn from rng after the sources), leaving from the
 *      same side-dependent origin, handed back with its throughput
 *      f·|cos|/pdf and pdf (callback: trace it with the integrator's path
 *      state).
 * The random numbers are drawn in that order (the callbacks draw their
 * own), so results are those of the two copies this replaces, bit for bit. */
#ifndef HELIODON_SHADE_BSDF_H
#define HELIODON_SHADE_BSDF_H

#include "heliodon/common.h"
#include "heliodon/rng.h"
#include "scatter.h"
#include "heliodon/trace.h"
#include "heliodon/vec.h"

typedef struct hd_shade_bsdf_ops {
    /* 1. diffuse parts, called only when one is non-zero: direct light with
     * the extra Lambertian reals sc->rdx / sc->tdx, indirect light with
     * ramb / tamb (those reals plus the unsampled sides of the data) */
    void (*lambert)(void *ctx, const hd_scatter *sc, const double ramb[3], const double tamb[3], hd_rng *rng);
    /* 2. sources k = 0 .. nsources-1: sample source k from point p; 0 to
     * skip it, else l (unit, towards the source), solid angle om, distance
     * dist (0 = distant) and the source's surface index *target */
    int nsources;
    int (*sample)(void *ctx, int k, hd_vec3 p, hd_rng *rng, hd_vec3 *l, double *om, double *dist, int *target);
    /* f(l, v)·|cos l| of the data for the sampled direction (<= 0: skip);
     * *wl = the weight of the term (1 without multiple importance sampling) */
    double (*eval)(void *ctx, const hd_scatter *sc, int k, int target, hd_vec3 l, double om, hd_rng *rng,
                   double *wl);
    int strict_distant;   /* hd_scatter_shadow's strict_distant for the shadow rays */
    /* the unblocked term: fc (from eval), om, wl, shadow transmission tr */
    void (*add)(void *ctx, int k, int target, hd_vec3 l, double fc, double om, double wl, const double tr[3],
                hd_rng *rng);
    /* 3. the sampled continuation from org along d, throughput wt, pdf per sr */
    void (*cont)(void *ctx, hd_vec3 org, hd_vec3 d, double wt, double pdf, hd_rng *rng);
    double st;            /* specular threshold (-st) */
} hd_shade_bsdf_ops;

/* Shade the BSDF / aBSDF hit sc of scene ts (see above). */
void hd_shade_bsdf(const hd_tscene *ts, const hd_scatter *sc, hd_rng *rng, const hd_shade_bsdf_ops *ops, void *ctx);

#endif

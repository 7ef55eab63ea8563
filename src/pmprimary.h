/* heliodon — the primary hit of a view or sensor ray in a photon-map gather
 * (rcontrib -ap).
 *
 * A density estimate only answers for diffuse surfaces.  What a view ray
 * sees directly of a distant source (the sun) through specular or
 * data-driven surfaces is added analytically, per source:
 *   * glass: the ray continues through (transmission) and, up to a depth,
 *     also along the reflected branch — both branches carry their weights;
 *   * mirror and pure specular plastic/metal: the mirror branch;
 *   * plastic/metal/trans: a density-estimate lookup with rho_d/pi (radiance)
 *     plus, for a rough specular lobe, the sun's highlight
 *     scol × lobe(l) (shadow ray to the source);
 *   * BSDF/aBSDF: f(l, view)·cos·Omega of the data for the source direction l
 *     (shadow ray from the far side), plus a lookup for its extra Lambertian
 *     reflection;
 *   * a ray leaving the scene inside a source's disk sees that source
 *     (radiance 1 per unit source radiance times the path weight).
 * Only the analytic records depend on the source; they are resolved once
 * per ray (hd_pmap_primary) and evaluated per source (hd_pmprim_direct). */
#ifndef HELIODON_PMPRIMARY_H
#define HELIODON_PMPRIMARY_H
#include "heliodon/trace.h"
#include "heliodon/vec.h"

#define HD_PMPRIM_PTS 4   /* density-estimate lookups per ray */
#define HD_PMPRIM_ANA 4   /* analytic records per ray */

typedef struct hd_pmprim_point {
    hd_vec3 p, n;     /* lookup point and the normal facing the ray */
    double f[3];      /* weight of the irradiance found there */
} hd_pmprim_point;

typedef enum { HD_PMPRIM_SURF = 1, HD_PMPRIM_ESCAPE = 2 } hd_pmprim_kind;

typedef struct hd_pmprim_ana {
    int kind;
    hd_hit h;         /* SURF: the hit */
    hd_vec3 d;        /* travel direction of the ray (SURF: arriving; ESCAPE: leaving) */
    double f[3];      /* path weight */
} hd_pmprim_ana;

typedef struct hd_pmprim {
    int npt, nana;
    hd_pmprim_point pt[HD_PMPRIM_PTS];
    hd_pmprim_ana ana[HD_PMPRIM_ANA];
} hd_pmprim;

/* Resolve a ray.  irrad: 0 radiance (view rays), 1 irradiance at org with
 * normal dir (rcontrib -I: one lookup, no analytic records), 2 irradiance at
 * the first diffuse hit (-i).  scale multiplies every weight; branches whose
 * weight falls below lw (grey) are dropped; depth = specular branchings
 * followed (glass reflections, mirrors).  Returns the number of records. */
int hd_pmap_primary(const hd_tscene *ts, hd_vec3 org, hd_vec3 dir, int irrad, double scale, int depth,
                    double lw, hd_pmprim *out);

/* Analytic contribution (per unit source radiance) of a distant source in
 * unit direction l with angular radius half (radians) to the ray resolved
 * in pp: added to out[3] (not cleared).  BSDF data is evaluated by the
 * one rule of hd_scatter_bsdf_direct (ss: -ss; deterministic jitter).
 * Returns 1 if anything was added. */
int hd_pmprim_direct(const hd_tscene *ts, const hd_pmprim *pp, hd_vec3 l, double half, double ss, double out[3]);

#endif

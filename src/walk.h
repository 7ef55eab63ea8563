/* heliodon — the backward path walk, the one implementation of Radiance's
 * rendering rules shared by every backward program (private seam).
 *
 * A ray is followed from the eye / receiver carrying the product of the
 * scattering coefficients met so far (`coef`, RGB); at every hit the
 * material is resolved by scatter.c (hd_scatter_at: patterns, mixtures,
 * illum alternates) and its kind shaded:
 *   - direct light: shadow rays to the walk's sources (-dj: the fraction of
 *     a distant source's radius sampled; -dn: how many after a diffuse
 *     bounce), the material's coefficient towards each (scatter.c);
 *   - indirect diffuse light: Radiance's -aa 0 hemisphere (-ab, -ad) at
 *     every diffuse vertex, its divisions set by the ray weight capped
 *     against -lw (amb_plan; in practice all -ad at the first vertex of
 *     a view ray, about one at deeper ones);
 *   - specular rays (pure mirror / glass / roughness-0 lobes, -ss samples
 *     of rough lobes above -st, the BSDF data's continuation: one ray, or
 *     Radiance's -ss count per side above 1.5);
 *   - every child ray admitted by Radiance's rayorigin rule (-lw, and -lr
 *     on the reflection level: reflected rays count, transmitted ones not).
 * What reaches an emitter, by a shadow ray or by a traced ray, is reported
 * to the sink with its coefficient: the radiance sink (render.c) adds
 * coefficient × emitted radiance, the coefficient sink (contrib.c) tallies
 * into the emitter's modifier bin.  The walk itself does not know which.
 *
 * With `radiance` set the walk also uses two variance-reduction strategies
 * whose extra terms carry radiance that has no modifier bin: multiple
 * importance sampling of local light surfaces between the shadow rays and
 * the hemisphere rays (unless o.nomis), and window portals (unless
 * o.noportal); and -av where -ab is exhausted.  Each changes the noise,
 * not the expectation.  And Radiance's ambient super-sampling (-as, o.as
 * > 0), which changes the expectation as Radiance's does (walk.c). */
#ifndef HELIODON_WALK_H
#define HELIODON_WALK_H

#include <stdatomic.h>

#include "heliodon/render.h"
#include "heliodon/trace.h"

/* -stats counters (rcontrib): the direct-source work, counted by every thread */
struct hd_contrib_counts {
    atomic_ullong vert0, vert1;         /* vertices considering sources: before / after a diffuse bounce */
    atomic_ullong sampled0, sampled1;   /* sources sampled, before / after */
    atomic_ullong shadows;              /* shadow rays cast to the sources */
};

/* Light reaching the walk: from emitter surface `surf` (material m, its
 * radiance in direction dir, from the hit h or NULL for a distant source or
 * a shadow ray), with coefficient k.  L: the radiance when the walk knows
 * it (shadow rays, portal samples, -av with surf < 0), else NULL (the
 * sink evaluates m towards dir at h if it needs it). */
typedef void (*hd_walk_emit_fn)(void *ctx, int surf, const hd_tmat *m, hd_vec3 dir, const hd_hit *h,
                                const double L[3], const double k[3], hd_rng *rng);

/* The radiance sink (rtrace, rpict): ctx is a double[3] to which
 * k × radiance is added (the emitter's value towards dir at h when L is
 * NULL).  A walk with `radiance` set reports to this sink. */
void hd_walk_add_radiance(void *ctx, int surf, const hd_tmat *m, hd_vec3 dir, const hd_hit *h, const double L[3],
                          const double k[3], hd_rng *rng);

typedef struct hd_walk {
    const hd_tscene *ts;
    hd_render_opts o;           /* -ab -ad -lw -lr -ss -st -dj -av, nomis, noportal */
    const int *lights;          /* surfaces the shadow rays aim at; NULL: every light of the scene */
    int nlights;
    int dn;                     /* -dn (rcontrib): sources sampled per vertex after a diffuse bounce, 0 = all */
    struct hd_contrib_counts *counts;   /* -stats, NULL: not counted */
    int strict_distant;         /* a shadow ray to a distant source must end in it (hd_scatter_shadow) */
    int radiance;               /* the sink is hd_walk_add_radiance: MIS, portals, -av, -as (see above) */
    hd_walk_emit_fn emit;
    void *ctx;
    hd_status *status;          /* set by hd_walk_ray: its first error (the walk then stops) */
} hd_walk;

/* Follow the ray org + t dir (dir unit; tmax > 0 limits the first ray) with
 * coefficient coef.  irrad: 0 radiance along the ray, 1 irradiance at org
 * with normal dir (-I), 2 irradiance at the first surface that is not
 * nominally transparent (-i; light sources and glows met first are
 * reported as seen).  info (may be NULL): the first hit (-i: the point
 * whose irradiance is taken).  HD_OK, or the first error met (HD_ERR_NOMEM
 * with the message set: a buffer the walk needs is refused by the
 * allocation limit); the sink then has part of the walk only. */
hd_status hd_walk_ray(const hd_walk *w, hd_vec3 org, hd_vec3 dir, double tmax, int irrad, const double coef[3],
                 hd_rng *rng, hd_rayinfo *info);

#endif

/* heliodon — rtrace / rpict: the rendering options and the radiance sink of
 * the backward path walk (walk.c; see render.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/render.h"
#include "heliodon/options.h"
#include "walk.h"

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
        {"as", HD_OPT_INT, &o->as, 0, 0, "N", "ambient super-samples (rtrace, rpict; rcontrib: none, as Radiance)"},
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

/* ---- the radiance sink of the walk (walk.c) ---- */
static hd_status radiance_walk(const hd_renderer *r, hd_vec3 org, hd_vec3 dir, double tmax, int irrad, hd_rng *rng,
                          double rgb[3], hd_rayinfo *info)
{
    static const double one[3] = {1, 1, 1};
    rgb[0] = rgb[1] = rgb[2] = 0;
    hd_walk w = {r->scene, r->o, NULL, 0, 0, NULL, 0, 1, hd_walk_add_radiance, rgb, NULL};
    return hd_walk_ray(&w, org, dir, tmax, irrad, one, rng, info);
}

hd_status hd_render_radiance(const hd_renderer *r, hd_vec3 org, hd_vec3 dir, double tmax,
                        hd_rng *rng, double rgb[3], hd_rayinfo *info)
{
    return radiance_walk(r, org, dir, tmax, 0, rng, rgb, info);
}

hd_status hd_render_irradiance(const hd_renderer *r, hd_vec3 p, hd_vec3 n, hd_rng *rng, double rgb[3])
{
    return radiance_walk(r, p, n, 0, 1, rng, rgb, NULL);
}

hd_status hd_render_irradiance_at_hit(const hd_renderer *r, hd_vec3 org, hd_vec3 dir, hd_rng *rng,
                                 double rgb[3], hd_rayinfo *info)
{
    return radiance_walk(r, org, dir, 0, 2, rng, rgb, info);
}

/* heliodon — backward Monte Carlo renderer (rtrace / rpict core): the
 * radiance sink of the one backward path walk (src/walk.c, shared with
 * rcontrib).
 *
 * Radiance semantics, path-traced without an ambient cache:
 * - direct light: next-event estimation (shadow rays) to every direct
 *   source (light/illum surfaces and distant sources with non-zero
 *   radiance, glow with maxrad > 0); -dj 0 aims at the centre of distant
 *   sources (as Radiance); area sources are sampled uniformly by area or
 *   solid angle.  Shadow rays pass through glass (with its transmittance at
 *   that angle), through the specular transmission of trans, and through
 *   illum surfaces that are not their target.
 * - indirect diffuse ("ambient") light: -ab = maximum number of diffuse
 *   bounces; at every diffuse vertex m × m cosine-weighted, stratified
 *   samples, m² = -ad × the ray weight capped against -lw (Radiance's -aa 0
 *   rule: all -ad at the first vertex of a primary ray or -I/-i point,
 *   about one deeper); -as super-samples as Radiance does;
 *   an indirect ray that hits a direct source contributes nothing (that
 *   light was counted by the shadow rays); glow with maxrad 0 (skies) is
 *   reached by indirect rays only.
 * - specular: pure mirror-like reflection/transmission rays (mirror, glass,
 *   roughness-0 plastic/metal/trans) see sources; rough specular lobes are
 *   evaluated for sources (Radiance's Gaussian lobe) and sampled (-ss, -st)
 *   for the rest of the scene.
 * - -lw: rays whose path weight falls below it are not traced; -lr: maximum
 *   ray depth (|lr| when negative).
 * Random streams: one per work unit (pixel or input ray), so results do not
 * depend on the thread count. */
#ifndef HELIODON_RENDER_H
#define HELIODON_RENDER_H

#include <stdint.h>
#include "common.h"
#include "rng.h"
#include <stdio.h>
#include "header.h"
#include "io.h"
#include "trace.h"
#include "vec.h"
#include "view.h"

typedef struct hd_render_opts {
    int ab;            /* -ab: maximum diffuse bounces */
    int ad;            /* -ad: samples at the first diffuse vertex */
    double lw;         /* -lw: minimum path weight */
    int lr;            /* -lr: maximum ray depth (<= 0: |lr|, 0 = unlimited) */
    double ss;         /* -ss: specular sampling multiplier */
    double st;         /* -st: specular sampling threshold */
    double dj;         /* -dj: source jitter (0 = centres of distant sources) */
    double av[3];      /* -av: ambient value added where -ab is exhausted */
    int as;            /* -as: Radiance's ambient super-samples (radiance walks; 0 here,
                          rtrace 512, rpict 128 as Radiance; rcontrib never, as Radiance) */
    uint64_t seed;     /* random seed */
    int nomis;         /* disable multiple importance sampling (tests) */
    int noportal;      /* disable window-portal sampling of the sky (tests, benchmarks) */
} hd_render_opts;

/* rtrace defaults (-ab 0 -ad 1024 -lw 2e-3 -lr -10 -ss 1 -st .15 -dj 0). */
void hd_render_defaults(hd_render_opts *o);

/* The rendering option group shared by the renderers (-ab -ad -lw -lr -ss
 * -st -dj -av -seed, and Radiance's ambient-cache / source-subdivision
 * options, accepted without effect).  Fills tab (HD_RENDER_NOPTS entries,
 * the last one HD_OPT_END) bound to *o; a program puts
 * {"", HD_OPT_TABLE, tab} in its own option table. */
#define HD_RENDER_NOPTS 21
struct hd_opt;
void hd_render_option_table(struct hd_opt *tab, hd_render_opts *o);

typedef struct hd_renderer {
    const hd_tscene *scene;
    hd_render_opts o;
} hd_renderer;

/* What the first ray hit (for rtrace -o specs). */
typedef struct hd_rayinfo {
    int hit;           /* 0 = escaped */
    double t;          /* distance to the first hit (inf if escaped) */
    hd_vec3 p, n;      /* point and front-facing normal at the first hit */
    hd_vec3 ng;        /* the surface's own normal there (its orientation, not turned
                          towards the ray: Radiance's -oN; a cup's and a tube's point inwards) */
    int surf;          /* surface index or -1 */
} hd_rayinfo;

/* Radiance seen along a ray (dir unit; tmax <= 0: unlimited).  info may be
 * NULL.  These three return HD_OK, or HD_ERR_NOMEM (message set) when a
 * buffer the walk needs (-ss samples, -as divisions) is refused by the
 * allocation limit; rgb then holds part of the walk only. */
hd_status hd_render_radiance(const hd_renderer *r, hd_vec3 org, hd_vec3 dir, double tmax,
                             hd_rng *rng, double rgb[3], hd_rayinfo *info);

/* Irradiance (W/m², RGB) at point p on a virtual surface with unit normal n
 * (rtrace -I). */
hd_status hd_render_irradiance(const hd_renderer *r, hd_vec3 p, hd_vec3 n, hd_rng *rng, double rgb[3]);

/* rtrace -i: irradiance at the first hit of the ray (normal facing the ray
 * origin); zero if the ray escapes.  info may be NULL. */
hd_status hd_render_irradiance_at_hit(const hd_renderer *r, hd_vec3 org, hd_vec3 dir, hd_rng *rng,
                                      double rgb[3], hd_rayinfo *info);

/* Luminance-weighted brightness of RGB (Radiance's bright()):
 * 0.265 R + 0.670 G + 0.065 B. */
static inline double hd_color_bright(const double c[3])
{
    return 0.2651 * c[0] + 0.6701 * c[1] + 0.0648 * c[2];
}

/* ---- program drivers (render_run.c) ---- */
struct hd_scene;

typedef struct hd_rtrace_opts {
    hd_render_opts r;
    int irrad;            /* 0: radiance (-ov...), 1: -I (at points), 2: -i (at hits) */
    char outspec[32];     /* -o spec: o d v p n N l L w m M s */
    char fin, fout;       /* 'a' ascii, 'f' float, 'd' double (-f[afd][afd]) */
    int header;           /* -h: write an information header */
    int xres, yres;       /* -x -y (recorded as NCOLS/NROWS) */
    int nthreads;         /* -n */
} hd_rtrace_opts;

void hd_rtrace_defaults(hd_rtrace_opts *o);
/* Check an -o spec; *ncomp = numbers per ray (names excluded). */
hd_status hd_rtrace_check_spec(const char *spec, int binary, int *ncomp);
/* Read rays (x y z dx dy dz) from in until the end, write the results in
 * input order.  hdr: lines to put before NCOMP/FORMAT (inherited lines,
 * command line, SOFTWARE, dates). A zero direction gives zero values. */
hd_status hd_rtrace_run(const hd_renderer *r, const hd_rtrace_opts *o, const struct hd_scene *sc,
                        hd_istream *in, FILE *out, const hd_header *hdr);

typedef struct hd_rpict_opts {
    hd_view view;
    int xres, yres;       /* requested; adjusted for -pa by hd_rpict_render */
    double pa;            /* pixel aspect (default 1; 0 = keep resolution) */
    double pj;            /* pixel jitter (0 = pixel centres) */
    int spp;              /* independent passes per pixel, averaged (heliodon -spp; default 1) */
    int nthreads;
    double report;        /* -t seconds (0 = none) */
} hd_rpict_opts;

/* Render the picture: *pix (3 floats per pixel, row 0 = top) of
 * o->xres × o->yres (after the -pa adjustment).  Seeds per pixel. */
hd_status hd_rpict_render(const hd_renderer *r, hd_rpict_opts *o, float **pix);

/* Load scene files (.rad text or heliodon scene caches, in order) into sc
 * and build the trace scene; hdr (may be NULL) receives the cache's
 * command line, the program's command line and SOFTWARE=. */
hd_status hd_render_load_scene(int nfiles, char **files, struct hd_scene *sc, hd_tscene **ts,
                               hd_header *hdr, int argc, char **argv);

/* vwrays: the rays of every pixel (top row first, left to right) as
 * "ox oy oz dx dy dz" (ascii, float or double), each written `repeat`
 * times (independently jittered with pj > 0: rcontrib -c repeat averages
 * them into one record per pixel); zero direction outside the view
 * (fisheye corners). */
hd_status hd_vwrays_run(hd_view *v, int xres, int yres, double pa, double pj, int repeat, char fmt,
                        uint64_t seed, FILE *out);

#endif

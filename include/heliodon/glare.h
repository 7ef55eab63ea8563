/* heliodon — discomfort-glare evaluation of 180-degree fisheye luminance
 * images, compatible with Radiance's evalglare (v3.06) for -vta and -vth
 * views: per-pixel solid angles, vertical eye illuminance E_v, glare-source
 * detection (threshold, merging within a search angle, peak extraction),
 * Guth/Iwata position index, DGP, DGI, UGR, CGI, DGR/VCP, veiling luminance.
 *
 * Typical use on an in-memory image (float RGB, row 0 = top):
 *
 *   hd_glare_view v;  hd_view_default(&v);
 *   hd_view_parse_line(&v, "-vta -vp 1 2.2 1.2 -vd 1 0 0 -vh 180 -vv 180");
 *   hd_glare_opts o;  hd_glare_opts_default(&o);
 *   hd_glare_result r;
 *   if (hd_glare_eval(rgb, xres, yres, &v, &o, &r)) ... hd_errmsg() ...
 *   printf("%f\n", r.dgp);  hd_glare_result_free(&r);
 *
 * For many images of the same view and size (annual runs), build the pixel
 * geometry once with hd_glare_geom_new() and call hd_glare_eval_geom() per
 * image: the geometry (directions, solid angles) is then not recomputed.
 * A geometry is read-only after creation and may be shared by threads that
 * evaluate different images concurrently (no global state). 
 *
 * Pixel convention: pixel (x, row) with row 0 the top scanline has image
 * location ((x+0.5)/xres, (yres-1-row+0.5)/yres) as Radiance's pix2loc.
 * Source positions are reported as evalglare prints them: x-pos = mean x,
 * y-pos = mean (row+1). */
#ifndef HELIODON_GLARE_H
#define HELIODON_GLARE_H

#include "common.h"
#include "vec.h"
#include "view.h"

/* ---- views --------------------------------------------------------------
 * The views of view.h (hd_view: parsed, defaulted, read from VIEW= lines
 * and view files there).  Only the fisheye types 'a' (-vta,
 * angular/equidistant) and 'h' (-vth, hemispherical) are accepted by the
 * evaluation; others parse but are refused with a clear error by
 * hd_glare_view_check(). */
typedef hd_view hd_glare_view;

/* The view options of the glare programs' command lines: "-vf file" and the
 * -v? options of hd_view_parse_arg, applied to *view.  Counts them and
 * records whether -vt, -vh and -vv were given (a view given on the command
 * line must be complete).  argv[i] is the option word; returns the number of
 * following words consumed, or -1 with an error set. */
typedef struct hd_glare_viewargs {
    hd_glare_view *view;
    int nview, has_t, has_h, has_v;
} hd_glare_viewargs;
int hd_glare_view_option(hd_glare_viewargs *va, int argc, char **argv, int i);
/* Verify that v is a fisheye view glare evaluation can use ("-vta"/"-vth",
 * non-zero orthogonal-enough direction and up); errors say what is wrong. */
hd_status hd_glare_view_check(const hd_glare_view *v);
/* Format as Radiance writes a view ("-vta -vp ... -vl 0"). */
int hd_glare_view_format(char *buf, size_t cap, const hd_glare_view *v);

/* Luminance image (cd/m2, row 0 = top) of a picture as evalglare sees it:
 * L = 179*(0.265074126 R + 0.670114631 G + 0.064811243 B) divided by the
 * cumulative EXPOSURE of the header.  XYZE pictures use L = 179*Y/EXPOSURE.
 * *lum is allocated (free()). */
struct hd_picture;
hd_status hd_glare_picture_lum(const struct hd_picture *p, float **lum);

/* ---- options ------------------------------------------------------------ */
typedef struct hd_glare_opts {
    double threshold;     /* -b: > 100 absolute cd/m2, else factor x mean (2000) */
    double search_radius; /* -r: radians (0.2) */
    int peak_extract;     /* -y (1) / -x (0) */
    double peak_value;    /* -Y: cd/m2 (50000) */
    int task;             /* -t given */
    double task_x, task_y, task_angle; /* pixel x, pixel y (row from top as
                                          evalglare's y), full angle in rad */
    int bg_mode;          /* -q: 0 (E_v-E_dir)/pi, 1 mean non-source, 2 E_v/pi */
    int lowlight;         /* -C l+: low-light DGP correction */
    double ev_external;   /* -i Ev: use this E_v (if > 0) for the metrics */
    int want_map;         /* fill hd_glare_result.source_map */
    /* DGP constants */
    double c1, c2, c3, a1, a2, a3, a4;
} hd_glare_opts;

void hd_glare_opts_default(hd_glare_opts *o);

/* ---- results ------------------------------------------------------------ */
typedef struct hd_glare_source {
    double npix;          /* number of pixels */
    double x, y;          /* mean pixel position (evalglare convention) */
    double lum;           /* omega-weighted mean luminance L_s, cd/m2 */
    double omega;         /* solid angle, sr */
    double posidx;        /* position index P (capped at 16) */
    double dir[3];        /* mean direction in the view frame: right, forward, up */
    double sigma;         /* angle from the view direction, degrees */
    double tau;           /* angle from the view-up direction in the image plane, degrees */
    double e_glare;       /* sum of cos*omega*L of its pixels, lux */
    double lveil_cie;     /* 10 * e_glare / sigma^2 */
    double lmax;          /* largest pixel luminance */
    double r_contrast;    /* log10(1+t_i)/log10(1+sum t), t_i = L^2 w/(P^2 E_v^1.87) */
    double r_dgp;         /* c2*log10(1+t_i)/DGP: share of DGP due to this source */
} hd_glare_source;

typedef struct hd_glare_result {
    double dgp, av_lum, ev, lum_backg, ev_dir, dgi, ugr, vcp, cgi;
    double lum_sources, omega_sources, lveil, lveil_cie, dgr, ugp;
    double max_lum;       /* largest pixel luminance in the field */
    double med_lum;       /* median pixel luminance in the field */
    double av_lum_pos;    /* sum(L w / P) / sum(w), P of each pixel direction */
    double av_lum_pos2;   /* sum(L w / P^2) / sum(w)^2 (as evalglare prints it) */
    double med_lum_pos;   /* median of L / P */
    double med_lum_pos2;  /* median of L / P^2 */
    double threshold;     /* threshold luminance actually used, cd/m2 */
    double task_lum;      /* task-area (or whole-field) mean luminance */
    long nvalid;          /* pixels inside the 180-degree field */
    int nsources;
    hd_glare_source *sources;   /* nsources entries (owned) */
    int *source_map;      /* optional per-pixel source index (-1 none),
                             filled only if opts->want_map */
} hd_glare_result;

void hd_glare_result_free(hd_glare_result *r);

/* ---- evaluation ---------------------------------------------------------- */
typedef struct hd_glare_geom hd_glare_geom;

/* Precompute pixel directions and solid angles for a view and size.  Fails
 * (HD_ERR_UNSUPPORTED) for non-fisheye views, (HD_ERR_RANGE) for absurd
 * sizes. */
hd_status hd_glare_geom_new(hd_glare_geom **g, const hd_glare_view *v, int xres, int yres);
void hd_glare_geom_free(hd_glare_geom *g);
/* Solid angle (sr) and cosine to the view direction of a pixel (row 0 =
 * top); 0 for pixels outside the 180-degree field. */
double hd_glare_geom_omega(const hd_glare_geom *g, int x, int row);
double hd_glare_geom_cos(const hd_glare_geom *g, int x, int row);

/* Vertical illuminance only (evalglare -V): lux.  lum is luminance per pixel. */
double hd_glare_ev_lum(const hd_glare_geom *g, const float *lum);

/* Full evaluation from luminance (cd/m2 per pixel, xres*yres, row 0 = top). */
hd_status hd_glare_eval_lum(const hd_glare_geom *g, const float *lum,
                            const hd_glare_opts *o, hd_glare_result *r);
/* Same from float RGB radiance (3 per pixel): L = 179*(0.265074126 R +
 * 0.670114631 G + 0.064811243 B). */
hd_status hd_glare_eval_geom(const hd_glare_geom *g, const float *rgb,
                             const hd_glare_opts *o, hd_glare_result *r);
/* One-shot convenience (builds and frees the geometry). */
hd_status hd_glare_eval(const float *rgb, int xres, int yres, const hd_glare_view *v,
                        const hd_glare_opts *o, hd_glare_result *r);

/* Compute every metric (dgp, dgi, ugr, ugp, cgi, dgr, vcp, lveil, lveil_cie,
 * per-source r_contrast/r_dgp) from r->ev, r->ev_dir, r->lum_backg,
 * r->av_lum and r->sources[0..nsources-1] (each with lum, omega, posidx,
 * sigma, dir, lveil_cie).  Used by the evaluation; exposed so that metrics
 * can be checked or recomputed from a source list alone. */
void hd_glare_metrics(hd_glare_result *r, const hd_glare_opts *o);

/* Luminance of an RGB radiance triple as evalglare computes it. */
double hd_glare_luminance(const float rgb[3]);

/* Position index for a direction in the view frame (right, forward, up). */
double hd_glare_posidx(const double dir[3]);

/* DGP from E_v and the sources (used by hd_glare_eval; exposed for tests). */
double hd_glare_dgp(double ev, const hd_glare_source *s, int n, const hd_glare_opts *o);

/* ---- output in evalglare's formats ---------------------------------------
 * Default line: "dgp,dgi,ugr,vcp,cgi,Lveil: %f %f %f %f %f %f  \n".
 * Detail (-d): the glare-source table (count line, one line per source) and
 * the 23-value line.  Three of evalglare's 23 values (ugr_exp, dgi_mod,
 * ugp2) are not computed by heliodon and are printed as "nan" (see
 * docs/man/evalglare.1). */
#include <stdio.h>
void hd_glare_write_line(FILE *fp, const hd_glare_result *r);
void hd_glare_write_detail(FILE *fp, const hd_glare_result *r);

/* ---- annual statistics ----------------------------------------------------
 * Ratings per the comfort classes used by the paper (Table 3):
 *   DGP: imperceptible < 0.35 <= perceptible < 0.40 <= disturbing < 0.45 <= intolerable
 *   DGI: imperceptible < 18 <= perceptible < 24 <= disturbing < 31 <= intolerable */
typedef enum hd_glare_class {
    HD_GLARE_IMPERCEPTIBLE = 0,
    HD_GLARE_PERCEPTIBLE,
    HD_GLARE_DISTURBING,
    HD_GLARE_INTOLERABLE
} hd_glare_class;

hd_glare_class hd_glare_class_dgp(double dgp);
hd_glare_class hd_glare_class_dgi(double dgi);
const char *hd_glare_class_name(hd_glare_class c);

/* Operated shade: closed when DGP >= the limit (0.40 in the paper). */
#define HD_GLARE_SHADE_LIMIT 0.40
int hd_glare_shade_closed(double dgp, double limit);

/* Percentile p (0..100) of n values (linear interpolation between order
 * statistics, as numpy's default); values are not modified. NAN if n == 0. */
double hd_glare_percentile(const double *v, size_t n, double p);

/* Running annual statistics: add one hour at a time. */
typedef struct hd_glare_annual {
    size_t n, cap;
    double *hour, *ev, *dgp, *dgi;
    size_t count_dgp[4], count_dgi[4];
    size_t shade_closed;
    double shade_limit;
} hd_glare_annual;

void hd_glare_annual_init(hd_glare_annual *a, double shade_limit);
void hd_glare_annual_free(hd_glare_annual *a);
/* Record one hour; returns 1 if the operated shade is closed for it. */
hd_status hd_glare_annual_add(hd_glare_annual *a, double hour, double ev, double dgp, double dgi,
                              int *shade_closed);

/* CSV output of an annual run: header
 * "hour,Ev,DGP,DGI,UGR,nsources,DGP_class,DGI_class,shade" and one row per
 * hour (shade = 1 when the operated shade is closed). */
void hd_glare_csv_header(FILE *fp);
void hd_glare_csv_row(FILE *fp, double hour, const hd_glare_result *r, int shade_closed);
/* Summary of an annual run: hours, 95th percentiles of DGP and DGI, hours
 * per comfort class (DGP and DGI), hours with the shade closed. */
void hd_glare_annual_write_summary(FILE *fp, const hd_glare_annual *a);

#endif

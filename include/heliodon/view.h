/* heliodon — Radiance views (-vt? -vp -vd -vu -vh -vv -vo -va -vs -vl -vf).
 *
 * Types: 'v' perspective, 'l' parallel, 'a' angular (equidistant) fisheye,
 * 'h' hemispherical (orthographic fisheye), 's' stereographic (planisphere),
 * 'c' cylindrical panorama.  -vh/-vv are full angles in degrees (parallel:
 * widths in world units).  Image locations (x, y) are in [0,1]², origin at
 * the lower left, x to the right, y up; pixel (i, j) of an xres × yres
 * image counted from the lower left has location ((i+.5)/xres, (j+.5)/yres).
 *
 * Edges: for every type the image edge x = 0 / x = 1 lies at an angle of
 * vh/2 from the view direction (perspective: tan, hemispherical: sin,
 * angular: linear, stereographic: tan of half angle, cylindrical: linear
 * horizontally and perspective vertically). */
#ifndef HELIODON_VIEW_H
#define HELIODON_VIEW_H

#include "common.h"
#include "header.h"
#include "vec.h"

typedef struct hd_view {
    char type;            /* 'v','l','a','h','s','c' */
    hd_vec3 vp;           /* view point */
    hd_vec3 vd;           /* view direction as given (its length is kept) */
    hd_vec3 vu;           /* view up */
    double vh, vv;        /* horizontal / vertical size */
    double vo, va;        /* fore / aft clipping distances (0 = none) */
    double vs, vl;        /* view shift / lift (image fractions) */
    /* computed by hd_view_setup(): */
    hd_vec3 dir;          /* unit view direction */
    hd_vec3 hvec, vvec;   /* scaled image vectors (see view.c) */
    hd_vec3 hunit, vunit; /* unit right / up vectors */
    int ready;
} hd_view;

/* Radiance's default view: -vtv -vp 0 0 0 -vd 0 1 0 -vu 0 0 1 -vh 45 -vv 45
 * -vo 0 -va 0 -vs 0 -vl 0. */
void hd_view_default(hd_view *v);

/* Parse one view option at argv[i] ("-vta", "-vp", "-vf", ...).  Returns
 * the number of argv words used (>= 1), 0 if argv[i] is not a view option,
 * or -1 after hd_fail() for a malformed option (missing or non-numeric
 * value, unknown type, unreadable -vf file). */
int hd_view_parse_arg(hd_view *v, int argc, char **argv, int i);

/* Parse every view option in a line of words, e.g. the value of a VIEW=
 * header line or a line of a view file ("rview -vta ..."): words that are
 * not view options are ignored.  Returns the number of view options found
 * or -1 on a malformed option. */
int hd_view_parse_line(hd_view *v, const char *line);

/* Read a view file (-vf): every line's view options are applied in order
 * (lines starting with a program name such as "rview" or "rpict", or
 * "VIEW=" lines of a picture header). */
hd_status hd_view_read_file(hd_view *v, const char *path);

/* Apply all VIEW= lines of a header in order; *found = count. */
hd_status hd_view_from_header(hd_view *v, const hd_header *h, int *found);

/* Check the view and compute the image vectors; errors name the problem
 * (zero direction, up parallel to direction, angle out of range). */
hd_status hd_view_setup(hd_view *v);

/* Ray for image location (x, y): origin and unit direction.  Returns the
 * maximum ray length (aft clipping, 0 = unlimited), or -1 if the location
 * lies outside the view (fisheye circle): then *dir is zero. */
double hd_view_ray(const hd_view *v, double x, double y, hd_vec3 *org, hd_vec3 *dir);

/* Image location of a world direction seen from the view point (inverse
 * of hd_view_ray for the direction); returns 0 if not visible. */
int hd_view_loc(const hd_view *v, hd_vec3 dir, double *x, double *y);

/* Ratio of the vertical to the horizontal image size (Radiance viewaspect). */
double hd_view_aspect(const hd_view *v);

/* Radiance's normaspect: with pixel aspect *pa (height/width) > 0, reduce
 * *xres or *yres so that the pixels have that aspect; with *pa <= 0, set
 * *pa to the aspect that the given resolution implies. */
void hd_view_normaspect(double view_aspect, double *pa, int *xres, int *yres);

/* Format as Radiance does in VIEW= lines (no leading/trailing blank):
 * "-vta -vp 1.5 3.5 1.2 -vd 0 -1 0 -vu 0 0 1 -vh 180 -vv 180 -vo 0 -va 0 -vs 0 -vl 0". */
int hd_view_format(const hd_view *v, char *buf, size_t cap);

#endif

/* heliodon — imageless annual glare (dcglare, Radiance-compatible).
 *
 * The simplified enhanced daylight glare probability of every view and time
 * step from two daylight-coefficient matrices and a sky matrix, without
 * images (Radiance's dcglare, N. Jones):
 *   E_v(p,t)  = 179 * lum(DCtotal(p,.) . S(.,t))     (or V T D S)
 *   for every sky bin c with DCdirect(p,c) > 0 whose direction d_c (patch
 *   centre; ground: the mean of straight down and the view direction)
 *   makes cos_c = v.d_c > 0 with the view direction v:
 *     L_c = 179 * lum(DCdirect(p,c)) * lum(S(c,t)) / (omega_c cos_c)
 *     (omega_c: patch solid angle; ground: 2 (pi - 2 acos cos_c))
 *   glare sources: L_c >= threshold (a luminance when the threshold is
 *   > 100 cd/m2, else that factor times E_v / pi);
 *   DGPs = 5.87e-5 E_v + 0.0918 log10(1 + sum L_c^2 omega_c / P_c^2 / E_v^1.87) + 0.16,
 *   times the low-light factor e^(0.024 E - 4) / (1 + e^(0.024 E - 4)) when
 *   E_v < 1000 lx, at most 1; 0 when E_v is 0.
 * The position index P_c is Radiance dcglare's (hd_dcglare_posidx).  lum()
 * is 0.265074126 R + 0.670114631 G + 0.064811243 B.
 * With a glare limit (>= 0) the result per view is the glare autonomy: the
 * fraction of occupied steps with DGPs below the limit. */
#ifndef HELIODON_DCGLARE_H
#define HELIODON_DCGLARE_H

#include "common.h"
#include "matrix.h"
#include "vec.h"

typedef struct hd_dcglare_opts {
    double limit;                 /* -l: < 0 hourly DGP, else glare autonomy */
    double threshold;             /* -b: > 100 luminance (cd/m2), else factor x E_v/pi (2000) */
    hd_vec3 vdir;                 /* -vd: view direction of every view (normalised) */
    hd_vec3 vup;                  /* -vu (0 0 1) */
    const hd_vec3 *views;         /* per view (row) directions, or NULL: vdir */
    const unsigned char *occupied;/* [nsteps] 1 = occupied, or NULL: all */
} hd_dcglare_opts;

void hd_dcglare_opts_default(hd_dcglare_opts *o);

/* The position index of direction dir for a view looking along fwd with up
 * vector up, as Radiance's dcglare computes it: above the line of sight
 * Guth's formula with sigma = angle(dir, fwd) and tau = the angle between
 * up and fwd + dir / (dir . fwd) (Radiance's construction); below it
 * 1 + f r with r = sqrt(1 + s^2) |tan phi| (s = tan theta / tan phi, phi
 * the angle below the line of sight, theta the angle towards the side,
 * r at most 3, f = 0.8, or 1.2 when r > 0.6); at most 16. */
double hd_dcglare_posidx(hd_vec3 dir, hd_vec3 fwd, hd_vec3 up);

/* The DGPs of one view for one time step: ev = E_v (lux), dcdir = the view's
 * direct coefficients (nbins RGB triplets), sky = the step's sky vector
 * (nbins RGB triplets), b = the sky basis of nbins. */
struct hd_skybasis;
double hd_dcglare_step(double ev, const double *dcdir, const double *sky, const struct hd_skybasis *b, hd_vec3 vdir,
                       hd_vec3 vup, double threshold);

/* The whole evaluation: dcdirect (views x bins), ev (views x steps: RGB
 * irradiance coefficients already multiplied by the sky, i.e. DCtotal . S),
 * sky (bins x steps).  out: views x steps (hourly) or views x 1 (autonomy),
 * allocated by the call (free()). */
hd_status hd_dcglare_eval(const hd_matrix *dcdirect, const hd_matrix *ev, const hd_matrix *sky,
                          const hd_dcglare_opts *o, float **out);

/* Occupancy schedule: one value per line, the last comma-separated field of
 * each line (# comments), > 0 = occupied; exactly nsteps lines. */
hd_status hd_dcglare_read_schedule(const char *path, int nsteps, unsigned char *occ);

/* View directions: "x y z dx dy dz" per view (the rcontrib input), format
 * hd_mtxfmt ascii/float/double; exactly nviews, directions normalised. */
hd_status hd_dcglare_read_views(const char *path, int fmt, int nviews, hd_vec3 *dirs);

#endif

/* heliodon — error measures between two results of the same scene:
 * pictures (per-pixel relative RMS of luminance over lit pixels, vertical
 * illuminance E_v and DGP of fisheye views) and matrices (mean, RMS,
 * largest and per-row relative differences).  Used by tools/hdcompare.c,
 * the benchmark sweeps and the stability tests.
 *
 * Conventions: "a" is the result under test, "b" the reference.  Relative
 * differences are (a-b)/b.  Luminance uses Radiance's RGB weights
 * 179*(0.265 R + 0.670 G + 0.065 B) (evalglare's); matrix elements with 3
 * components are reduced to the same weighted sum (without the 179).
 * Non-finite values (NaN, Inf) are counted, never folded into the
 * measures. */
#ifndef HELIODON_COMPARE_H
#define HELIODON_COMPARE_H

#include <stddef.h>
#include "common.h"

struct hd_picture;
struct hd_matrix;
struct hd_view;

typedef struct hd_cmp_stats {
    long n;            /* values compared */
    long nused;        /* of which "lit" (reference above the floor) */
    long nonfinite_a;  /* NaN/Inf values in a */
    long nonfinite_b;  /* NaN/Inf values in b */
    double floor;      /* reference value below which a value is not "lit" */
    double rms_rel;    /* sqrt(mean ((a-b)/b)^2) over lit values */
    double mean_rel;   /* mean (a-b)/b over lit values (bias) */
    double mean_abs_rel; /* mean |a-b|/b over lit values */
    double max_rel;    /* largest |a-b|/b over lit values */
    long imax;         /* index of that value (-1 if none) */
    double sum_a, sum_b; /* sums over all finite values */
    double total_rel;  /* sum_a/sum_b - 1 (0 if sum_b == 0) */
} hd_cmp_stats;

/* Compare two arrays of n values.  Values with b <= floor are "unlit": they
 * count in n and the sums only.  floor < 0 means: floor = -floor times the
 * mean of the finite reference values (e.g. -0.01 = 1 % of the mean).
 * Never fails: NaN/Inf are counted in nonfinite_a/b. */
void hd_compare_values(const double *a, const double *b, size_t n, double floor, hd_cmp_stats *st);

/* Picture comparison: luminance statistics plus, if view is given (a fisheye
 * -vta/-vth view; NULL = take it from the reference header, or skip the
 * glare part if neither has a usable view), E_v and DGP of both pictures. */
typedef struct hd_piccmp {
    hd_cmp_stats lum;     /* luminance in cd/m2 */
    int have_glare;       /* E_v / DGP computed */
    double ev_a, ev_b, dgp_a, dgp_b;
} hd_piccmp;

/* Sizes must match (HD_ERR_RANGE otherwise, message names both sizes).
 * floor as for hd_compare_values (in cd/m2 when >= 0). */
hd_status hd_compare_pictures(const struct hd_picture *a, const struct hd_picture *b,
                              const struct hd_view *view, double floor, hd_piccmp *r);

/* Box-filter a picture by an integer factor k (k x k pixels become one,
 * their mean), as pfilt -x /k -y /k -1 -b: emulates k*k samples per pixel
 * from a picture rendered k times larger.  Sizes must be multiples of k.
 * out is allocated; the header lines of in are copied. */
hd_status hd_compare_reduce(const struct hd_picture *in, int k, struct hd_picture *out);

/* Matrix comparison (same nrows, ncols, ncomp required).  Elements are
 * reduced to one value each (grey value for ncomp 3).  per_row (may be
 * NULL) receives nrows relative row-sum differences sum_a/sum_b - 1 of each
 * row (0 for rows whose reference sum is 0). */
hd_status hd_compare_matrices(const struct hd_matrix *a, const struct hd_matrix *b, double floor,
                              hd_cmp_stats *st, double *per_row);

/* Grey value of an element (ncomp 1: itself; 3: 0.265 R + 0.670 G + 0.065 B;
 * other: mean). */
double hd_compare_grey(const double *v, int ncomp);

/* The 1/sqrt(N) law used to choose sample or photon counts: an error err0
 * measured with n0 samples predicts err0*sqrt(n0/n) with n; the count for a
 * target error is n0*(err0/target)^2 (rounded up, at least 1). */
double hd_compare_predict_error(double err0, double n0, double n);
double hd_compare_predict_count(double err0, double n0, double target);

/* Photon-map error model for choosing the photon count N AND the bandwidth k
 * (photons per lookup and source) from a pilot run, without a reference:
 *   e^2(N, k) = C / k + (B k / N)^2
 * (relative noise variance of a k-nearest-neighbour density estimate ~ 1/k
 * whatever N; kernel bias ~ the area the k photons cover ~ k / N).
 * hd_compare_pm_fit: from a pilot with n0 photons gathered at bandwidths
 * k[0] < k[1] < ... (n values): var[i] = relative noise variance at k[i]
 * (from two pilots with different seeds: mean of ((a-b)/mean)^2 / 2) and
 * dbias2[i] = mean squared relative difference of the seed-averaged estimates
 * at k[i] and k[0] with the noise removed (dbias2[0] unused).  Least squares:
 *   C = sum(var/k) / sum(1/k^2),  (B/n0)^2 = sum(dbias2 d^2) / sum(d^4), d = k - k[0].
 * hd_compare_pm_choose: the smallest N reaching the target error with its
 * optimal k:  k = 1.5 C / target^2,  N = B k sqrt(2 k / C)  (when B = 0 the
 * error does not depend on N: N = 0 and k = C / target^2 are returned).
 * Returns -1 when the model cannot be fitted or the target is not positive. */
typedef struct hd_pm_model { double C, B; } hd_pm_model;
int hd_compare_pm_fit(const double *k, const double *var, const double *dbias2, int n, double n0, hd_pm_model *m);
double hd_compare_pm_error(const hd_pm_model *m, double N, double k);
int hd_compare_pm_choose(const hd_pm_model *m, double target, double *N, double *k);

#endif

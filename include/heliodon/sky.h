/* heliodon — sky models: Perez all-weather luminance and luminous efficacy
 * as gendaymtx implements them, sky-matrix columns (gendaymtx), CIE skies
 * (gensky), Perez sky descriptions (gendaylit) and their evaluation over a
 * sky basis (genskyvec).
 *
 * Units: the "illuminances" below follow Radiance: lux for visible output,
 * or W/m2 * 179 for solar output (-O1), so that dividing by 179 always
 * gives the patch radiance in W/sr/m2. */
#ifndef HELIODON_SKY_H
#define HELIODON_SKY_H

#include <stdio.h>
#include "basis.h"
#include "common.h"
#include "solar.h"
#include "vec.h"

#define HD_WHTEFFICACY 179.0        /* lm/W of Radiance's white */
#define HD_SOLAR_CONSTANT 1367.0    /* W/m2 */
#define HD_SUN_DIAMETER 0.533       /* degrees */
#define HD_SUN_HALFANGLE_RAD (0.2665 * HD_PI / 180)

/* ---- Perez all-weather model (gendaymtx form) ---- */
typedef struct hd_perez {
    double sun_zenith;     /* rad, as used (90 deg below horizon, 3 deg above 87) */
    double epsilon, delta; /* clearness, brightness (after clamping) */
    int category;          /* 0..7 */
    double precip_water;   /* cm */
    double dni, dhi;       /* W/m2 */
    double dir_illum, diff_illum;   /* lux (or 179*W/m2 with solar output) */
    double coef[5];        /* a b c d e */
} hd_perez;

/* Compute the Perez parameters for one time step.  v1, v2 in the WEA units
 * (1: DNI DHI W/m2; 2: direct horizontal, DHI W/m2; 3: DNI DHI lux);
 * sun_alt in radians; jd day of year; dewpoint in deg C (NAN -> 11 C);
 * solar_output: 1 for -O1 (illuminances = 179 * irradiances). */
void hd_perez_compute(hd_perez *p, double sun_alt, int jd, double v1, double v2, int units,
                      double dewpoint, int solar_output);
/* Same with the iteration limits of the photometric (units 3) conversion:
 * at most maxiter steps, stopping when both irradiances change by less
 * than tol W/m2 (gendaymtx: 5, 10; gendaylit: 15, 0.01). */
void hd_perez_compute_iter(hd_perez *p, double sun_alt, int jd, double v1, double v2, int units,
                           double dewpoint, int solar_output, int maxiter, double tol);
/* Relative luminance for a sky point at zenith angle zeta and angle gamma
 * from the sun (radians); negative values are returned as 0. */
double hd_perez_rel_lum(const hd_perez *p, double zeta, double gamma);
/* The five coefficients for given zenith, clearness and brightness (with
 * the 1.065<eps<2.8 brightness floor of Radiance). */
void hd_perez_params(double sun_zenith, double epsilon, double delta, double coef[5]);
/* Clearness category for epsilon (0..7). */
int hd_perez_category(double epsilon);
/* Luminous efficacies (lm/W) of diffuse and direct light (Perez 1990). */
double hd_perez_diffuse_efficacy(int cat, double precip_water, double sun_zenith, double delta);
double hd_perez_direct_efficacy(int cat, double precip_water, double sun_zenith, double delta);
/* Air mass (Kasten) and eccentricity correction. */
double hd_air_mass(double sun_zenith);
double hd_eccentricity(int jd);

/* ---- sky-matrix columns (gendaymtx) ---- */
typedef struct hd_daymtx_opts {
    double skycolor[3];    /* default 0.960 1.004 1.118 */
    double suncolor[3];    /* default 1 1 1 */
    double grefl[3];       /* default 0.2 0.2 0.2 */
    int sun_only;          /* -d: sky and ground zero */
    int sky_only;          /* -s: no direct sun */
    int solar_output;      /* -O1 */
    double disk_deg;       /* -5: > 0 puts the sun in one patch with the
                              radiance of a disk of this full angle */
    int nsuns;             /* patches sharing the sun (4; 1 with -5) */
    double rotation_deg;   /* -r: counter-clockwise sky rotation */
    double interval_min;   /* -i: time-step length (minutes) for the
                              sunrise/sunset correction, 0 = off */
} hd_daymtx_opts;

void hd_daymtx_opts_default(hd_daymtx_opts *o);

typedef struct hd_daymtx_step {
    int jd;                /* day of year (leap shift applied) */
    double hour;           /* standard time */
    double v1, v2;         /* weather values in the file units */
    int units;
    double dewpoint;       /* NAN -> default */
} hd_daymtx_step;

typedef struct hd_daymtx_info {
    double alt, azi;       /* sun altitude, azimuth east of north (rotated), rad */
    double dir_illum, diff_illum;
    int night;             /* DNI+DHI <= 1e-4: column all zero */
    int bright_below;      /* DNI > 20 with the sun below -0.2665 deg */
} hd_daymtx_info;

/* Solar time (hours) of a step: standard time + equation of time +
 * longitude correction; with o->interval_min > 0, a step whose interval
 * (+-interval/2) contains sunrise or sunset is moved to the middle of the
 * part of the interval during which the sun is up. */
double hd_daymtx_solar_time(const hd_site *site, const hd_daymtx_opts *o, int jd, double hour);

/* Compute one column (3*b->nbins values, patch-major) for a time step. */
void hd_daymtx_column(const hd_skybasis *b, const hd_daymtx_opts *o, const hd_site *site,
                      const hd_daymtx_step *t, double *out, hd_daymtx_info *info);

/* ---- whole sky matrices (gendaymtx) ---- */
struct hd_weather;
typedef struct hd_daymtx_job {
    hd_daymtx_opts o;
    int mf;                /* sky subdivision */
    int skip_night;        /* -u: omit steps with the sun below -0.2665 deg */
    int average;           /* -A: one column, the mean of all steps */
    int nthreads;          /* <= 0: all processors */
    int warnings;          /* print "unusually bright" warnings */
} hd_daymtx_job;

typedef struct hd_daymtx_result {
    int nbins, ncols;      /* rows (patches incl. ground) and columns */
    long naveraged;        /* steps averaged with -A (0 otherwise) */
    float *data;           /* nbins*ncols*3, patch-major like the file */
    size_t *steps;         /* [ncols] weather record of each column */
} hd_daymtx_result;

/* Day of year of every record as gendaymtx counts it (a Feb 29 record maps
 * to 60 and shifts later dates of that year by one).  jd: w->n ints. */
void hd_daymtx_julian_days(const struct hd_weather *w, int *jd);
/* The step of weather record i (jd from hd_daymtx_julian_days). */
hd_daymtx_step hd_daymtx_step_of(const struct hd_weather *w, const int *jd, size_t i);
hd_status hd_daymtx_generate(const struct hd_weather *w, const hd_daymtx_job *job, hd_daymtx_result *r);
void hd_daymtx_result_free(hd_daymtx_result *r);
/* gendaymtx ascii data ("%.3g %.3g %.3g" per element, blank line after
 * each row when ncols > 1). */
hd_status hd_daymtx_write_ascii(FILE *fp, const hd_daymtx_result *r);

/* The same matrix kept compactly for writing (gendaymtx): only the columns
 * with light are stored (night columns, DNI+DHI <= 1e-4, are zero), as
 * float triplets in blocks of HD_DAYMTX_BLOCK columns, patch-major inside a
 * block, so rows are gathered without transposing the whole matrix.  The
 * values are those of hd_daymtx_column rounded to float, exactly as in
 * hd_daymtx_result.  Not for -A (use hd_daymtx_generate). */
#define HD_DAYMTX_BLOCK 64
typedef struct hd_daymtx_store {
    int nbins, ncols;
    size_t nday;           /* stored columns */
    long *colmap;          /* [ncols] stored column index, or -1: zero column */
    size_t *steps;         /* [ncols] weather record of each column */
    float *blk;            /* [nday/BLOCK rounded up][nbins][BLOCK][3] */
    int nthreads;
} hd_daymtx_store;
hd_status hd_daymtx_compute(const struct hd_weather *w, const hd_daymtx_job *job, hd_daymtx_store *s);
/* Row (patch) p of the matrix: 3*ncols floats. */
void hd_daymtx_store_row(const hd_daymtx_store *s, int p, float *row);
typedef enum hd_daymtx_format { HD_DAYMTX_ASCII, HD_DAYMTX_FLOAT, HD_DAYMTX_DOUBLE } hd_daymtx_format;
/* The data part of the file, rows formatted in parallel, written in order:
 * byte-identical to hd_daymtx_write_ascii / fwrite of hd_daymtx_result. */
hd_status hd_daymtx_store_write(FILE *fp, const hd_daymtx_store *s, hd_daymtx_format fmt);
void hd_daymtx_store_free(hd_daymtx_store *s);
/* x formatted exactly as printf("%.3g") does (glibc, round-to-nearest);
 * writes at most 16 bytes plus a NUL into buf, returns the length. */
size_t hd_format_g3(char *buf, double x);
/* Sun descriptions (-D) and modifier list (-M) for the steps whose sun is
 * above -0.2665 deg; cmdline goes into the comment header. */
hd_status hd_daymtx_write_suns(FILE *rad, FILE *mods, const struct hd_weather *w, const hd_daymtx_job *job,
                               const char *cmdline);

/* ---- gendaylit / gensky ---- */
typedef enum hd_skytype {
    HD_SKY_PEREZ = 0,      /* gendaylit: perezlum.cal */
    HD_SKY_CIE_CLEAR,      /* gensky +s / -s */
    HD_SKY_CIE_INTERMEDIATE,
    HD_SKY_CIE_OVERCAST,
    HD_SKY_UNIFORM
} hd_skytype;

typedef struct hd_daylit_opts {
    hd_site site;
    int month, day, jd;    /* jd = day of year used for the sun */
    double hour;           /* standard time, or solar time if solar_time */
    int solar_time;
    int use_angles;        /* -ang: alt_deg, azi_deg (from south, west +) */
    double alt_deg, azi_deg;
    int mode;              /* 'W', 'G', 'L', 'P' or 'E' */
    double v1, v2;         /* the two values of the mode (E: v1 only) */
    int output;            /* -O: 0 visible, 1 solar, 2 luminance */
    int with_sun;          /* 0 with -s */
    double ground_refl;    /* -g (0.2) */
    double dewpoint;       /* -d (default: 2 cm of precipitable water) */
} hd_daylit_opts;
void hd_daylit_opts_default(hd_daylit_opts *o);
/* Write the sky description; warn receives the warning text (no newline)
 * when an "error sky" is written. */
hd_status hd_gendaylit(FILE *fp, const hd_daylit_opts *o, const char *cmdline, char *warn, size_t warncap);

typedef struct hd_gensky_opts {
    hd_site site;
    int jd;
    double hour;
    int solar_time, use_angles;
    double alt_deg, azi_deg;
    hd_skytype type;       /* CIE clear, intermediate, overcast, uniform */
    int with_sun;          /* +s / -s, +i / -i */
    double turbidity;      /* -t (2.45) */
    double ground_refl;    /* -g (0.2) */
    double zenith_br;      /* -b (W/sr/m2), < 0 unset */
    double horiz_irr;      /* -B (W/m2 diffuse horizontal), < 0 unset */
    double solar_rad;      /* -r (W/sr/m2), < 0 unset */
    double solar_irr;      /* -R (W/m2 normal), < 0 unset */
} hd_gensky_opts;
void hd_gensky_opts_default(hd_gensky_opts *o);
hd_status hd_gensky(FILE *fp, const hd_gensky_opts *o, const char *cmdline);
/* The same factor as Radiance's gensky/gendaylit evaluate it (their
 * polynomial fit over the sun altitude alt, radians): what the ground
 * brightness of both programs uses.  Overcast 7/9, other types 1. */
double hd_cie_norm_fitted(hd_skytype type, double alt);

/* ---- sky descriptions (gensky / gendaylit output) ---- */


/* A parsed sky (what genskyvec reads): the skyfunc and an optional sun. */
typedef struct hd_skydesc {
    hd_skytype type;
    double args[16];       /* real arguments of the skyfunc primitive */
    int nargs;
    hd_vec3 sundir;        /* from the skyfunc arguments or the source */
    int has_sun;           /* a light + source pair was found */
    double sun_rgb[3];     /* radiance of the light primitive */
    double sun_diam_deg;   /* source full angle */
    hd_vec3 sun_source_dir;
} hd_skydesc;

/* Parse the text of a gensky/gendaylit description (brightfunc skyfunc
 * with skybright/perezlum.cal, or skybr/skybright.cal; light/source). */
hd_status hd_skydesc_parse(const char *text, const char *name, hd_skydesc *d);
/* Sky radiance (visible W/sr/m2 before colour) towards unit direction dir
 * (Dz < 0 returns the ground value as the .cal files blend it). */
double hd_skydesc_eval(const hd_skydesc *d, hd_vec3 dir);

/* genskyvec: patch radiances (3*nbins) of a sky description.  nsamp per
 * patch side (nsamp^2 stratified samples); sun handling as genskyvec
 * (spread over 3 patches, or -5: replace the nearest patch). */
typedef struct hd_skyvec_opts {
    double skycolor[3];
    int sun_only;          /* -d */
    int five_phase;        /* -5 */
    int nsamp;             /* <= 0: Radiance genskyvec's own 16 fixed
                              pseudo-random rays per patch (reproduces its
                              output); > 0: nsamp x nsamp stratified samples */
    double *stddev;        /* optional [nbins]: standard deviation of the
                              sky function over each patch (the spread a
                              few-sample estimate such as Radiance's 16
                              rays is subject to); sky part only */
} hd_skyvec_opts;
hd_status hd_skyvec_compute(const hd_skybasis *b, const hd_skydesc *d, const hd_skyvec_opts *o, double *out);

#endif

/* heliodon — annual composition of PM-CBDM luminance images and streaming
 * glare evaluation (the last step of the two-step PM-CBDM pipeline).
 *
 * For every record of a weather file with daylight (suns.h), the hourly
 * image is composed from coefficient pictures:
 *
 *   I_sun(h)  = DC_sun[p(h)] * s_sun(h)       p(h): the single non-zero
 *               patch of the sun-only sky vector (gendaymtx -5 0.533 -d,
 *               Reinhart MF:sun_mf), DC_sun[p] = picture file sun_pattern
 *               with %d = p (rcontrib -V- of the unit-radiance source
 *               solar<p>, e.g. with -ap photon map or -ab);
 *   I_sky(h)  = sum_b C_sky[b] * s_sky[b](h)  s_sky: diffuse-only sky
 *               vector (gendaymtx -s, MF:sky_mf, ground bin 0 included);
 *               C_sky = sum over window groups of V_wg * (T_wg D_wg) —
 *               V_wg: one picture per Klems patch k (pattern %d = k),
 *               TD_wg: a matrix (rows = Klems patches, columns = sky bins,
 *               e.g. rmtxop T.xml D.mtx) — and/or direct sky coefficient
 *               pictures (pattern %d = sky bin);
 *   I_fen(h)  = sum_b DC_fen[b] * s_sky[b](h) refined backward DC for the
 *               pixels inside the fenestration mask;
 *   I(h)      = I_sun + I_sky outside the mask, I_sun + I_fen inside;
 *               with direct-sun terms (ndterms, the five-phase method) the
 *               sky vectors keep the sun and I_sky - I_sun,3PM replaces I_sky;
 *               optionally DC_sun is replaced inside the mask by a refined
 *               backward sun DC (the sun seen through a BSDF window: its
 *               direct transmission towards the eye, which a photon lookup
 *               on the window surface cannot give).
 *
 * The sky vectors are computed from the weather record with the sky
 * library (the same columns gendaymtx writes), so no 8760-column matrix is
 * held in memory.  Each image goes straight into the glare evaluation
 * (glare.h); hourly images are written only on request.
 *
 * Everything that can be checked before the long loop is checked first:
 * the view (must be a 180-degree fisheye: -vta/-vth), the presence and size
 * of every coefficient picture the weather file needs, matrix dimensions,
 * the weather file having daylight records. */
#ifndef HELIODON_ANNUAL_H
#define HELIODON_ANNUAL_H

#include <stdio.h>
#include "common.h"
#include "glare.h"

#define HD_ANNUAL_MAXTERMS 8

typedef struct hd_annual_opts {
    const char *weather;          /* WEA or EPW (required) */
    int sun_mf;                   /* MF of the sun patches (1) */
    int sky_mf;                   /* MF of the sky coefficients (1) */
    const char *sun_pattern;      /* DC_sun pictures, %d = patch (NULL: no sun) */
    const char *sky_pattern;      /* direct sky DC pictures, %d = sky bin */
    int nterms;                   /* 3PM window-group terms */
    const char *v_pattern[HD_ANNUAL_MAXTERMS];
    const char *td_matrix[HD_ANNUAL_MAXTERMS];
    const char *fen_pattern;      /* refined DC for the masked pixels, %d = sky bin */
    const char *mask;             /* picture: pixel in the mask when its value > 0.5 */
    const char *fensun_pattern;   /* refined sun DC for the masked pixels, %d = sun
                                     patch (backward rcontrib, no photon map): replaces
                                     DC_sun inside the mask (needs sun_pattern, mask) */
    int sky_sun;                  /* 1: the sky vectors keep the direct sun, shared
                                     among the nearest sky bins as gendaymtx does
                                     without -s / -d (the plain three-phase method
                                     with sun: V T D s); excludes sun_pattern */
    int ndterms;                  /* five-phase method: three-phase terms of the
                                     direct sun (black-interior V times the reflectance
                                     map, T, the -ab 0 daylight matrix) folded with the
                                     hour's sun-only sky vector (gendaymtx -d: the sun
                                     shared among its nearest bins) and subtracted;
                                     needs sky_sun; allows sun_pattern with sky_sun
                                     (I = I_3PM - I_sun,3PM + I_sun); the composed
                                     pixels are clamped at 0 as an RGBE picture is */
    const char *vd_pattern[HD_ANNUAL_MAXTERMS];
    const char *tdd_matrix[HD_ANNUAL_MAXTERMS];
    const char *ground_sun;       /* per sun patch, the sunlit fraction of the exterior
                                     ground the windows see: lines "patch fraction"
                                     (# comments); the sun term of the sky vectors'
                                     ground bin is scaled by it (NULL: 1; needs
                                     sun_pattern).  Patches not listed: 1 */
    hd_glare_view view;           /* fisheye view (required for glare) */
    int have_view;                /* 0: take the VIEW= line of the first picture */
    hd_glare_opts glare;
    double shade_limit;           /* DGP at which the operated shade closes */
    const char *csv;              /* glare CSV (glarestats format); NULL = stdout */
    const char *summary;          /* summary file; NULL = none */
    const char *hourlog;          /* per-hour log: record month day hour sunbin
                                     sun direction (patch centre) sun radiance
                                     R G B and the image's mean luminance */
    const char *image_pattern;    /* hourly images, %d = record index (NULL: none) */
    int image_exr;                /* write OpenEXR instead of RGBE */
    const long *records;          /* only these record indices (NULL: all) */
    int nrecords;
    int nthreads;                 /* <= 0: all processors */
    int verbose;
    int preflight;                /* only check the view, patterns and the
                                     weather file (daylight hours), then stop */
    int no_glare;                 /* compose only (images, hour log): no glare
                                     evaluation, any view (or none) */
    const char *illum_csv;        /* sensor mode: the pictures hold irradiance
                                     coefficients of sensor points (rcontrib -I,
                                     one pixel per point in scanline order);
                                     writes "record,month,day,hour,E1..En"
                                     (lux = 179 x luminance weights) for every
                                     daylight hour; implies no_glare */
    int piece_k, piece_n;         /* -H k n: piece k of n contiguous slices of the
                                     daylight hours (piece_n 0: every hour); every
                                     output starts with "# PIECE=" / "# COMMAND="
                                     lines and the summary is the piece's record
                                     for hd_annual_join (src/annual_pieces.c) */
    int argc;                     /* command line for the headers */
    char **argv;
} hd_annual_opts;

void hd_annual_opts_default(hd_annual_opts *o);

typedef struct hd_annual_stats {
    long nrecords;                /* records in the weather file */
    long ndaylight;               /* hours composed and evaluated */
    int nsun;                     /* distinct sun patches used */
    double t_load, t_loop;        /* seconds */
    double dgp_p95, dgi_p95;
    long shade_closed;
    double mean_lum_max;          /* largest hourly mean luminance */
} hd_annual_stats;

/* Run the composition and glare evaluation; returns HD_OK or an error
 * naming the file/setting at fault. */
hd_status hd_annual_run(const hd_annual_opts *o, hd_annual_stats *st);

/* The sky part of every hour is folded by dctimestep's kernels
 * (hd_dcts_fold, dctimestep.h), several hours at a time. */

/* Ray filter for the refined fenestration DC: copy a vwrays -ff stream
 * (6 floats per ray, pixels in scanline order from the top) from in to
 * out, zeroing the direction of every ray whose pixel is outside the mask
 * (mask value <= 0.5), so that rcontrib traces only the masked pixels.
 * The stream must hold exactly per_pixel rays for each of the mask's
 * xres*yres pixels, the rays of a pixel consecutive (vwrays -c per_pixel,
 * jittered within the pixel with -pj); they are kept or zeroed together.
 * *nmasked receives the number of rays kept.  Every ray is written
 * `repeat` times (1..1024), so that rcontrib -c per_pixel*repeat makes each
 * pixel's coefficient the mean of that many independent estimates (spiky
 * estimates such as a BSDF peak lit by the sun average out). */
struct hd_istream;
hd_status hd_annual_mask_rays(const char *mask, struct hd_istream *in, const char *inname, FILE *out, int per_pixel,
                              int repeat, long *nmasked);

/* ---- two-pass operated shade (e.g. FS2: shade open / closed) ----
 * Pass 1 is an annual run with the shade open, pass 2 the same hours with
 * the shade closed (same weather, view and records; typically the same sun
 * sources).  The shade is closed for an hour when the open run's DGP >=
 * shade_limit; the composite takes the closed run's result for those hours
 * and the open run's otherwise.  Inputs are pmcompose's glare CSVs and hour
 * logs (-o, -L) of both runs; they must list the same hours in the same
 * order (checked line by line).  Outputs:
 *   csv       composite glare CSV (glarestats format; shade column = the
 *             schedule: 1 closed, 0 open)
 *   schedule  "hour,record,month,day,time,DGP_open,DGP_closed,DGP,shade"
 *   hourlog   composite hour log (pmcompose -L format)
 *   summary   composite statistics, hours with the shade closed and the
 *             open-run percentiles for comparison */
typedef struct hd_annual_sched_opts {
    const char *open_csv, *open_log;
    const char *closed_csv, *closed_log;
    double shade_limit;           /* HD_GLARE_SHADE_LIMIT */
    const char *csv, *schedule, *hourlog, *summary;   /* csv required */
} hd_annual_sched_opts;

typedef struct hd_annual_sched_stats {
    long nhours, nclosed;
    double dgp_p95_open, dgi_p95_open;   /* shade always open */
    double dgp_p95, dgi_p95;             /* with the schedule */
} hd_annual_sched_stats;

void hd_annual_sched_opts_default(hd_annual_sched_opts *o);

/* ---- hour pieces joined (pmcompose -J) ----
 * dirs: the folders of pieces 0 ... n-1 of one pmcompose -H run (any order);
 * each holds the files named like the outputs (their base names).  Writes
 * the glare CSV, hour log, illuminance CSV and summary of one run over
 * every hour; refuses a missing or repeated piece, pieces of another run,
 * overlapping or missing hours and truncated files. */
typedef struct hd_annual_join_opts {
    const char *const *dirs;
    int ndirs;
    const char *csv, *hourlog, *illum_csv, *summary;
    double shade_limit;
} hd_annual_join_opts;
hd_status hd_annual_join(const hd_annual_join_opts *o);
hd_status hd_annual_schedule(const hd_annual_sched_opts *o, hd_annual_sched_stats *st);

#endif

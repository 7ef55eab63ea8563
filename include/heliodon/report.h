/* heliodon — static HTML report of an annual glare run (PM-CBDM pipeline).
 *
 * The page (index.html) and its figures are written into one directory:
 *   dgp_heat.svg, dgi_heat.svg   day of year x hour heat maps
 *   dgp_hist.svg, dgi_hist.svg   histograms with cumulative curve, 95th
 *                                percentile and comfort-class limits
 *   shade.svg                    operated-shade schedule (closed when
 *                                DGP >= limit)
 *   fc_<n>.png                   false-colour luminance images (log scale)
 *                                of selected hours, legend fc_legend.svg
 * plus tables of run parameters, stage timings, 95th percentiles and hours
 * per comfort class.  Every referenced file is written by the report
 * itself; nothing is loaded from the network. */
#ifndef HELIODON_REPORT_H
#define HELIODON_REPORT_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include "common.h"

/* ---- PNG (8-bit RGB, zlib) ---- */
hd_status hd_png_write(const char *path, const uint8_t *rgb, int w, int h);
/* Decode a PNG written by hd_png_write (8-bit RGB or RGBA, non-interlaced,
 * any filter): checks the signature, every chunk CRC and the image size.
 * rgb may be NULL (verification only); otherwise *rgb is allocated. */
hd_status hd_png_read(const char *path, uint8_t **rgb, int *w, int *h);

/* ---- colour scales ---- */
/* t in [0,1] -> colour of the report's ramp (dark blue .. red). */
void hd_report_ramp(double t, uint8_t rgb[3]);
/* Luminance (cd/m2) to false colour on a log scale from lmin to lmax. */
void hd_report_falsecolor(double lum, double lmin, double lmax, uint8_t rgb[3]);

/* ---- annual data (glarestats / pmcompose CSV) ---- */
typedef struct hd_report_data {
    size_t n;
    double *hoy;    /* hour of year (decimal, 0 = Jan 1 00:00) */
    double *ev, *dgp, *dgi;
    int *shade;
} hd_report_data;

hd_status hd_report_read_csv(const char *path, hd_report_data *d);
void hd_report_data_free(hd_report_data *d);

/* ---- figures ---- */
/* which: 0 DGP, 1 DGI, 2 operated shade (closed when DGP >= shade_limit),
 * 3 two-pass schedule (closed where the CSV's shade column is 1) */
hd_status hd_report_heatmap_svg(const char *path, const hd_report_data *d, int which, double shade_limit);
/* which: 0 DGP, 1 DGI */
hd_status hd_report_histogram_svg(const char *path, const hd_report_data *d, int which);
hd_status hd_report_falsecolor_png(const char *hdr_path, const char *png_path, double lmin, double lmax,
                                   char *caption, size_t capcap);
hd_status hd_report_legend_svg(const char *path, double lmin, double lmax);
/* A display picture (falsecolor's output: RGB in 0..1) as an 8-bit PNG, each
 * channel clipped to 0..1 and gamma-encoded with 2.2, as Radiance's picture
 * converters do by default; the picture's EXPOSURE is not undone. */
hd_status hd_report_display_png(const char *hdr_path, const char *png_path);

/* ---- the page ---- */
typedef struct hd_report_opts {
    const char *csv;          /* annual CSV (required) */
    const char *outdir;       /* output directory (created if missing) */
    const char *title;
    const char *params;       /* "key = value" or "key value" lines (optional) */
    const char *timings;      /* "stage seconds" lines (optional) */
    const char *summary;      /* extra text file shown verbatim (optional) */
    const char **images;      /* hourly pictures to show in false colour */
    int nimages;
    double shade_limit;       /* 0.40 */
    const char *open_csv;     /* two-pass shade (pmcompose -schedule): the open
                                 run's CSV; csv is then the composite and its
                                 shade column the schedule (optional) */
    double lmin, lmax;        /* false-colour range, cd/m2 (10, 10000) */
} hd_report_opts;

void hd_report_opts_default(hd_report_opts *o);
hd_status hd_report_write(const hd_report_opts *o);

/* Records to show: reads a pmcompose hour log (-L) and writes to fp the
 * record indices (comma-separated) of the hours with the largest DGP, the
 * DGP nearest the 95th percentile, the median DGP and the smallest DGP,
 * without repeats, at most n (<= 4). */
hd_status hd_report_select(const char *hourlog, int n, FILE *fp);

#endif

/* heliodon — picture utilities with Radiance's behaviour: pfilt (filtering
 * and resampling with exposure), pextrem, and the geometric ones (pflip,
 * protate, pcompos) live in src/pfilt.c and src/pictools.c. */
#ifndef HELIODON_PICTOOLS_H
#define HELIODON_PICTOOLS_H

#include "cal.h"
#include "common.h"
#include "header.h"
#include "io.h"
#include "picture.h"

typedef struct hd_pfilt_opts {
    int ncols, nrows;        /* output size (0: from xratio/yratio) */
    double xratio, yratio;   /* output/input size ratios (-x /N gives 1/N) */
    int singlepass;          /* -1: no exposure pass */
    double exposure[3];      /* -e, -er, -eg, -eb (multiplied) */
    double rad;              /* -r: Gaussian radius in output pixels (0: box) */
    double thresh;           /* -m: threshold for the limited Gaussian */
    double hotlvl;           /* -h: level of "hot" pixels (100) */
    int npts;                /* -n: star points (half stored, as Radiance) */
    double spread;           /* -s (1e-4) */
    int avghot;              /* -a */
    int correctaspect;       /* -c */
    double outaspect;        /* -p */
} hd_pfilt_opts;

void hd_pfilt_opts_default(hd_pfilt_opts *o);
/* Filter the picture in (header lines in in->hdr are copied to the output
 * header, followed by the command line cmd_argc/cmd_argv and the new
 * PIXASPECT/EXPOSURE/COLORCORR lines) and write it to fp. */
hd_status hd_pfilt(const hd_picture *in, const hd_pfilt_opts *o, int cmd_argc, char **cmd_argv, FILE *fp);
/* RGB colour (brightness = lumen depreciation) of lamp type LAMP in the
 * lamp table TABLE (Radiance's lamp.tab format, found through RAYPATH and
 * heliodon's library): pfilt -t/-f divide the exposure by it. */
hd_status hd_lamp_color(const char *table, const char *lamp, double rgb[3]);

/* A picture as its stored RGBE bytes in file order (scanlines as in the
 * file, orientation in r), with its header lines (FORMAT removed). */
typedef struct hd_rawpic {
    hd_header hdr;
    hd_picfmt fmt;
    hd_resolu r;
    int len, nscans;       /* scanline length, number of scanlines */
    uint8_t *rgbe;         /* nscans * len * 4 bytes */
} hd_rawpic;

hd_status hd_rawpic_read(const char *path, hd_rawpic *p);
hd_status hd_rawpic_read_stream(hd_istream *s, hd_rawpic *p);
/* Write with header hdr (NULL: p->hdr), orientation and size from p->r. */
hd_status hd_rawpic_write(FILE *fp, const hd_rawpic *p, const hd_header *hdr);
/* The same through hd_ofile to path (NULL or "-": standard output). */
hd_status hd_rawpic_save(const char *path, const hd_rawpic *p);
/* A black picture w x h of format fmt (standard orientation, empty header). */
hd_status hd_rawpic_blank(hd_rawpic *p, hd_picfmt fmt, int w, int h);
void hd_rawpic_free(hd_rawpic *p);
/* pflip: flip left-right (h) and/or top-bottom (v) as Radiance's pflip:
 * the scanlines are reordered and, unless keep_order (-c), the orientation
 * flags change as Radiance's do. */
hd_status hd_rawpic_flip(hd_rawpic *p, int h, int v, int keep_order);
/* protate: 90 degrees clockwise (ccw = 0) or counter-clockwise. */
hd_status hd_rawpic_rotate(hd_rawpic *p, int ccw, int keep_order);

/* ---- pextrem: the darkest and brightest pixel, as Radiance's pextrem:
 * pixels compared on their stored RGBE bytes (exponent first, then an
 * integer brightness), ties keep the first pixel met scanning each
 * scanline from its end; x along the scanline, y counting scanlines from
 * the last one (from the bottom of a standard picture).  orig 1 (-o)
 * undoes EXPOSURE= and COLORCORR=, -1 (-O) also 179 for XYZE pictures. */
typedef struct hd_extrema {
    int xmin, ymin, xmax, ymax;
    float min[3], max[3];   /* decoded colours (original values with orig) */
} hd_extrema;
hd_status hd_pextrem(hd_istream *s, int orig, hd_extrema *e);

/* ---- pcomb: combine pictures with .cal expressions ---- */
typedef struct hd_pcomb_input {
    const char *name;       /* path, "-" or "!command" */
    int original;           /* -o: undo EXPOSURE/COLORCORR */
    double coef[3];         /* -s, -c */
} hd_pcomb_input;

typedef struct hd_pcomb_opts {
    int echo_header;        /* -h toggles */
    int nowarn;             /* -w */
    int outfloat;           /* -ff: float matrix output */
    /* definitions in command-line order: kind 'e' (expression), 'f'
     * (file), 'x' / 'y' (output size expression) */
    int ndefs;
    char *defkind;
    const char **deftext;
    int ninputs;
    hd_pcomb_input *inputs;
    /* optional: called once after pcomb's own functions are defined and
     * before the definitions above (falsecolor's palettes) */
    hd_status (*define)(hd_cal *c, void *user);
    void *define_user;
} hd_pcomb_opts;

hd_status hd_pcomb(const hd_pcomb_opts *o, int cmd_argc, char **cmd_argv, FILE *fp);

/* ---- falsecolor: false-colour pictures (Radiance's falsecolor options) ---- */
hd_status hd_falsecolor(int argc, char **argv, FILE *fp);

#endif

/* pvalue — conversion between Radiance pictures and pixel values (ascii,
 * integer, byte, 16-bit, float, double), the work behind tools/pvalue.c.
 *
 * The program parses Radiance's sign-letter options into hd_pvalue_opts
 * (hd_pvalue_opts_init, then the fields and hd_pvalue_set_format, then
 * hd_pvalue_opts_finish) and calls hd_pvalue_to_values (picture -> values)
 * or hd_pvalue_from_values (values -> picture, -r).  See docs/man/pvalue.1. */
#ifndef HELIODON_PVALUE_H
#define HELIODON_PVALUE_H

#include "heliodon/common.h"
#include "heliodon/picture.h"

#include <stdio.h>

/* which primaries are written / read (putprim) */
enum { HD_PV_RED = 0, HD_PV_GRN = 1, HD_PV_BLU = 2, HD_PV_ALL = 3, HD_PV_BRIGHT = 4 };
/* output primaries of a reversed conversion (prims_mode) */
enum { HD_PV_PRIM_STD = 0, HD_PV_PRIM_CUSTOM = 1, HD_PV_PRIM_XYZ = 2 };

typedef struct hd_pvalue_opts {
    int uniq;          /* -u: only values that differ from the previous pixel (forward); flat scanlines (reverse) */
    int dataonly;      /* -d...: no pixel positions */
    int putprim;       /* HD_PV_* */
    int format;        /* 'a' 'i' 'b' 'w' 'f' 'd' */
    int header;        /* +h */
    int swapbytes;     /* -dW -dF -dD (or BigEndian= of the input) */
    int interleave;    /* +n; -1 when three separate inputs are given */
    int resolution;    /* +H */
    int original;      /* -o: 1 undo EXPOSURE/COLORCORR; -O: -1 also the 179 lm/W of XYZE */
    int doexposure;    /* exposure[] differs from 1 */
    int prims_mode;    /* HD_PV_PRIM_* */
    long skipbytes;    /* -s N */
    double gamcor;     /* gamma correction exponent (1/g for +g) */
    double expval;     /* total exposure written as EXPOSURE= */
    double prims[8];   /* -p xr yr xg yg xb yb xw yw */
    float exposure[3]; /* per-channel factor applied to values */
    const char *fmtid; /* FORMAT= of the value stream */
    int ord[3];        /* channel order of the values (-R) */
    int rord[3];       /* inverse of ord */
    hd_resolu picres;  /* -x/-y given resolution (reverse without +H) */
} hd_pvalue_opts;

void hd_pvalue_opts_init(hd_pvalue_opts *o);
/* -d<c> / +d<c> (and heliodon's -f<c>): c = a i b w W f F d D (or '\0' = a). */
hd_status hd_pvalue_set_format(hd_pvalue_opts *o, char c, int minus);
/* Derive fmtid and rord once all options are set. */
void hd_pvalue_opts_finish(hd_pvalue_opts *o);

/* Picture (path, or "-" for stdin) -> values on out.  argc/argv are recorded
 * in the output header.  The options may be updated (exposure from -o). */
hd_status hd_pvalue_to_values(hd_pvalue_opts *o, const char *path, FILE *out, int argc, char **argv);
/* Values -> picture on out.  npaths = 0 (stdin), 1, or 3 (one channel each). */
hd_status hd_pvalue_from_values(hd_pvalue_opts *o, const char *const *paths, int npaths, FILE *out,
                                int argc, char **argv);

#endif

/* heliodon — rcomb: combine matrices and pictures element by element with
 * component transforms (-c), scale factors (-s), .cal expressions (-e/-f:
 * co, co(p), ro/go/bo with ci(i,p), ri/gi/bi) and a final concatenation
 * matrix (-m/-mt), as Radiance's rcomb (docs/man/rcomb.1).
 *
 * Values are held in single precision between the steps, as Radiance's
 * rcomb does (its matrices are float), so that ascii output agrees with it
 * digit for digit. */
#ifndef HELIODON_RCOMB_H
#define HELIODON_RCOMB_H

#include <stdio.h>
#include "common.h"

#define HD_RCOMB_MAXCOEF 1024

/* -c / -s given before one input (or after the last: the result) */
typedef struct hd_rcomb_op {
    const char *csym;               /* letters (RGBXYZA) or a reference file (name with '.') */
    int clen;                       /* number of -c coefficients */
    double cmat[HD_RCOMB_MAXCOEF];
    int nsf;                        /* number of -s factors */
    double sf[HD_RCOMB_MAXCOEF];
} hd_rcomb_op;

typedef struct hd_rcomb_input {
    const char *spec;               /* file, "-" (standard input) or "!command" */
    hd_rcomb_op op;
} hd_rcomb_input;

typedef struct hd_rcomb_opts {
    hd_rcomb_input *in;
    int nin;
    hd_rcomb_op trail;              /* operations after the last input */
    const char *const *deftext;     /* -e expressions / -f files, in order */
    const char *defkind;            /* 'e' or 'f' per definition */
    int ndefs;
    const char *mcat;               /* -m matrix (or NULL) */
    int mcat_transpose;             /* -mt */
    int mcat_last;                  /* -m after the trailing -c/-s */
    int outfmt;                     /* hd_mtxfmt, or -1: from the inputs */
    int echo_header;                /* copy the inputs' headers (-h toggles) */
    int nowarn;                     /* -w */
    int nthreads;                   /* -n */
} hd_rcomb_opts;

/* Run rcomb and write the result (header included) to out.  argv is the
 * command line for the header. */
hd_status hd_rcomb(const hd_rcomb_opts *o, int argc, char **argv, FILE *out);

#endif

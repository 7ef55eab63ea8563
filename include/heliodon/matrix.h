/* heliodon — Radiance matrix files (rcontrib, rfluxmtx, dctimestep,
 * rmtxop, gendaymtx): header with NROWS/NCOLS/NCOMP/FORMAT/BigEndian,
 * data as ascii, float, double (either byte order), or RGBE/XYZE pictures
 * (one scanline per row).  In memory: double, row-major, NCOMP values per
 * element; EXPOSURE / COLORCORR of the input are undone on read. */
#ifndef HELIODON_MATRIX_H
#define HELIODON_MATRIX_H

#include <stdio.h>
#include "common.h"
#include "header.h"
#include "io.h"

typedef enum hd_mtxfmt {
    HD_MTX_ASCII = 0,
    HD_MTX_FLOAT,
    HD_MTX_DOUBLE,
    HD_MTX_RGBE,
    HD_MTX_XYZE
} hd_mtxfmt;

/* Refuse matrices with more elements than this (absurd headers). */
#define HD_MTX_MAXELEMENTS ((int64_t)1 << 34)

typedef struct hd_matrix {
    int nrows, ncols, ncomp;
    double *data;           /* nrows*ncols*ncomp */
    hd_header hdr;          /* input header lines (FORMAT, NROWS, NCOLS,
                               NCOMP, BigEndian removed) */
    hd_mtxfmt infmt;        /* format read */
} hd_matrix;

typedef struct hd_matrix_readopts {
    /* For headerless input (-h): dimensions and format; 0/-1 = unknown. */
    int nrows, ncols, ncomp;
    int fmt;                /* hd_mtxfmt, or -1 to require a header */
} hd_matrix_readopts;

void hd_matrix_init(hd_matrix *m);
hd_status hd_matrix_alloc(hd_matrix *m, int nrows, int ncols, int ncomp);
void hd_matrix_free(hd_matrix *m);
static inline double *hd_matrix_at(const hd_matrix *m, int r, int c)
{
    return m->data + ((size_t)r * (size_t)m->ncols + (size_t)c) * (size_t)m->ncomp;
}

const char *hd_mtxfmt_name(hd_mtxfmt f);        /* "ascii", "float", ... */
int hd_mtxfmt_parse(const char *name);          /* -1 if unknown */

/* Read a matrix file or picture ("-" = stdin, "!cmd", gzip transparently).
 * opts may be NULL.  Errors name the file, the byte offset or line, and
 * the dimension or value that was expected. */
hd_status hd_matrix_read(const char *path, hd_matrix *m, const hd_matrix_readopts *opts);
hd_status hd_matrix_read_stream(hd_istream *s, hd_matrix *m, const hd_matrix_readopts *opts);

/* Streaming writer: header (hdr lines as given — the caller adds its
 * command line etc. — then NROWS, NCOLS, NCOMP, BigEndian, padded FORMAT,
 * empty line; for RGBE/XYZE a resolution string instead of NROWS/NCOLS)
 * followed by rows. */
typedef struct hd_mtxwriter {
    FILE *fp;
    hd_mtxfmt fmt;
    int nrows, ncols, ncomp;
    int rows_written;
    unsigned char *scratch;
} hd_mtxwriter;
hd_status hd_mtxwriter_begin(hd_mtxwriter *w, FILE *fp, const hd_header *hdr,
                             int write_header, hd_mtxfmt fmt,
                             int nrows, int ncols, int ncomp);
/* One row: ncols*ncomp values. */
hd_status hd_mtxwriter_row(hd_mtxwriter *w, const double *vals);
hd_status hd_mtxwriter_end(hd_mtxwriter *w);
/* Whole matrix. */
hd_status hd_matrix_write(FILE *fp, const hd_matrix *m, const hd_header *hdr,
                          int write_header, hd_mtxfmt fmt);

/* Algebra (per component; ncomp must match, or one side has 1 component). */
hd_status hd_matrix_multiply(hd_matrix *out, const hd_matrix *a, const hd_matrix *b);
hd_status hd_matrix_transpose(hd_matrix *out, const hd_matrix *a);

#endif

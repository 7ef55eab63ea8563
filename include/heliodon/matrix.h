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
    /* For headerless input (-h): dimensions and format; 0/-1 = unknown.
     * fmt >= 0: the input has NO header; it is read as fmt with these
     *   dimensions (ncols required; nrows <= 0 = as many rows as the data
     *   holds; ncomp <= 0 = 3).  Note: a zeroed struct means headerless
     *   ascii — set fmt = -1 for files with headers.
     * fmt == -1: a header is required; nrows/ncols/ncomp > 0 are used
     *   only when the header lacks NROWS/NCOLS/NCOMP. */
    int nrows, ncols, ncomp;
    int fmt;                /* hd_mtxfmt, or -1 to require a header */
} hd_matrix_readopts;

/* An empty matrix (no data, empty header). */
void hd_matrix_init(hd_matrix *m);
/* Initialise m (it need not have been initialised: any previous content is
 * NOT freed — call hd_matrix_free first) and allocate zeroed data of
 * nrows x ncols x ncomp, checked against HD_MTX_MAXELEMENTS. */
hd_status hd_matrix_alloc(hd_matrix *m, int nrows, int ncols, int ncomp);
/* Free data and header; m is left initialised (empty). */
void hd_matrix_free(hd_matrix *m);
static inline double *hd_matrix_at(const hd_matrix *m, int r, int c)
{
    return m->data + ((size_t)r * (size_t)m->ncols + (size_t)c) * (size_t)m->ncomp;
}

const char *hd_mtxfmt_name(hd_mtxfmt f);        /* "ascii", "float", ... */
int hd_mtxfmt_parse(const char *name);          /* -1 if unknown */

/* Read a matrix file or picture ("-" = stdin, "!cmd", gzip transparently).
 * opts may be NULL.  Errors name the file, the byte offset or line, and
 * the dimension or value that was expected.  m is an output: it need not
 * be initialised and previous content is not freed; on error m is left
 * initialised (empty). */
hd_status hd_matrix_read(const char *path, hd_matrix *m, const hd_matrix_readopts *opts);
hd_status hd_matrix_read_stream(hd_istream *s, hd_matrix *m, const hd_matrix_readopts *opts);

/* Streaming writer: header (hdr lines as given — the caller adds its
 * command line etc. — then NROWS, NCOLS, NCOMP, BigEndian, padded FORMAT,
 * empty line; for RGBE/XYZE a resolution string instead of NROWS/NCOLS)
 * followed by rows.
 * - nrows <= 0: number of rows unknown (streaming): NROWS is not written
 *   and hd_mtxwriter_end does not check the count (not for RGBE/XYZE).
 * - If hdr already holds an NCOMP= (or NROWS=/NCOLS=) line, e.g. because
 *   the caller wants rcontrib's order NCOMP, NROWS, NCOLS, that variable is
 *   not repeated; its value must agree with the arguments.
 * - RGBE/XYZE: ncomp must be 1 (written grey) or 3; values are written
 *   as they are (no EXPOSURE).
 * - float/double are written in the host byte order (BigEndian= says which). */
/* ASCII layouts written by the Radiance programs (none is significant on
 * read): rmtxop " %.7e" per component and a TAB after each element;
 * dctimestep "%.6e" components separated by blanks, a TAB between
 * elements; rcontrib "%.6e\t" per component.  One line per row in every
 * case. */
typedef enum hd_mtxascii {
    HD_MTXASCII_RMTXOP = 0,
    HD_MTXASCII_DCTIMESTEP,
    HD_MTXASCII_RCONTRIB
} hd_mtxascii;

typedef struct hd_mtxwriter {
    FILE *fp;
    hd_mtxfmt fmt;
    int nrows, ncols, ncomp;
    int rows_written;
    unsigned char *scratch;
    hd_mtxascii ascii_style;   /* set after begin, before the first row */
} hd_mtxwriter;
/* write_header: 0 no header, else HD_MTXW_HEADER, optionally with
 * HD_MTXW_NO_NCOLS (no NCOLS line: rcontrib's -x -y streams of one column). */
#define HD_MTXW_HEADER 1
#define HD_MTXW_NO_NCOLS 2
hd_status hd_mtxwriter_begin(hd_mtxwriter *w, FILE *fp, const hd_header *hdr,
                             int write_header, hd_mtxfmt fmt,
                             int nrows, int ncols, int ncomp);
/* One row: ncols*ncomp values. */
hd_status hd_mtxwriter_row(hd_mtxwriter *w, const double *vals);
/* One row gathered from a longer record: element c is the ncomp values at
 * vals + ncomp*cols[c] (cols NULL: contiguous, as hd_mtxwriter_row). */
hd_status hd_mtxwriter_row_cols(hd_mtxwriter *w, const double *vals, const int *cols);
hd_status hd_mtxwriter_end(hd_mtxwriter *w);
/* Whole matrix. */
hd_status hd_matrix_write(FILE *fp, const hd_matrix *m, const hd_header *hdr,
                          int write_header, hd_mtxfmt fmt);

/* Algebra (per component; ncomp must match, or one side has 1 component).
 * out may be a or b (the result replaces it); otherwise it must have been
 * initialised (hd_matrix_init) or hold a previous result, which is freed.
 * The result's header is empty. */
hd_status hd_matrix_multiply(hd_matrix *out, const hd_matrix *a, const hd_matrix *b);
/* The same on nthreads threads (rows split in chunks; the result does not
 * depend on the thread count). */
hd_status hd_matrix_multiply_mt(hd_matrix *out, const hd_matrix *a, const hd_matrix *b, int nthreads);
hd_status hd_matrix_transpose(hd_matrix *out, const hd_matrix *a);
/* Product of a chain mats[0] . mats[1] . ... . mats[n-1], evaluated in the
 * order with the fewest multiply-adds (dynamic programming over the
 * parenthesisations; ties keep left to right), e.g. V.T.D.s with a sky
 * vector s is computed from the right.  Dimension and component checks and
 * messages are those of left-to-right evaluation; the values agree with it
 * up to rounding.  Products of more than 2e7 multiply-adds use nthreads.
 * cost_ltr / cost_best (may be NULL) receive the multiply-add counts of
 * left-to-right and of the chosen order.  out must not be one of mats. */
hd_status hd_matrix_chain(hd_matrix *out, const hd_matrix *const *mats, int n, int nthreads,
                          double *cost_ltr, double *cost_best);

/* ---- further operations (rmtxop) ---- */

/* Deep copy (data and header); dst initialised or a previous result. */
hd_status hd_matrix_copy(hd_matrix *dst, const hd_matrix *src);
/* Move src into dst (dst freed first); src is left empty/initialised. */
void hd_matrix_move(hd_matrix *dst, hd_matrix *src);

typedef enum hd_mtxop {
    HD_MTXOP_MUL = '.',    /* matrix product */
    HD_MTXOP_ADD = '+',    /* element sum */
    HD_MTXOP_EMUL = '*',   /* element product */
    HD_MTXOP_EDIV = '/'    /* element quotient */
} hd_mtxop;
/* Element-wise a := a op b: same rows and columns; b has a's ncomp or 1
 * component (applied to every component of a).  For '/' a zero divisor
 * gives 0 and one warning (hd_warn) per call; *nzero (may be NULL)
 * receives the number of zero divisors. */
hd_status hd_matrix_elementwise(hd_matrix *a, const hd_matrix *b, hd_mtxop op,
                                unsigned long *nzero);
/* Component transform: out component i = sum_j coefs[i*a->ncomp + j] *
 * a component j, for i < nout (nout*a->ncomp coefficients). */
hd_status hd_matrix_transform(hd_matrix *out, const hd_matrix *a,
                              const double *coefs, int nout);
/* Scale every value by sf[0] (nsf == 1) or component c by sf[c]
 * (nsf == m->ncomp). */
hd_status hd_matrix_scale(hd_matrix *m, const double *sf, int nsf);

/* Coefficients of symbolic colour components (-c letters R G B X Y Z A of
 * rmtxop and rcomb) for a 3-component input in RGB (xyz_in 0) or CIE XYZ
 * (xyz_in 1): 3 coefficients per letter into coef (room for 3 per letter).
 * *xyz_out (may be NULL): 1 when the letters are "XYZ", 0 when "RGB" (any
 * case), -1 otherwise.  Upper-case letters apply 179 lm/W between RGB and
 * XYZ.  Unknown letters and S/M (spectral) are HD_ERR_USAGE. */
hd_status hd_color_symbols(const char *letters, int xyz_in, double *coef, int *xyz_out);

/* Output type rmtxop picks for two inputs: the lower precision
 * (ascii < float < double), a picture type only when both are the same
 * picture type, float when a picture type meets anything else. */
hd_mtxfmt hd_mtxfmt_combine(hd_mtxfmt a, hd_mtxfmt b);

/* Whether a name looks like an XML BSDF (".xml" suffix, any case). */
int hd_matrix_is_xml(const char *path);
/* Klems matrix of an XML BSDF (rows = outgoing, columns = incident bins,
 * 3 equal components, infmt float): which = 'T' transmission as the
 * 3-phase method uses it (dctimestep, rmtxop default), 'f' front and 'b'
 * back reflection (rmtxop -rf / -rb).  hd_matrix_read does this ('T') for
 * names ending in .xml (through the BSDF module, bsdf.h). */
hd_status hd_matrix_read_bsdf(const char *path, hd_matrix *m, int which);

#endif

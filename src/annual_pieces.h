/* heliodon — hour pieces of the annual composition (private to annual.c
 * and annual_pieces.c; pmcompose -H / -J, see annual_pieces.c). */
#ifndef HELIODON_ANNUAL_PIECES_H
#define HELIODON_ANNUAL_PIECES_H

#include <stdio.h>

#include "heliodon/annual.h"
#include "heliodon/header.h"

/* the hour log's first line */
#define HD_ANNUAL_LOG_HEADER "# record month day hour sun_patch sun_dx sun_dy sun_dz sun_R sun_G sun_B mean_lum_cd/m2 DGP"

/* Keep piece o->piece_k of o->piece_n of the nrec daylight records in recs
 * (nothing without -H); first: its first hour among total. */
hd_status hd_annual_piece_slice(const hd_annual_opts *o, long *recs, long *nrec, long *first, long *total);

/* The "# PIECE=" and "# COMMAND=" lines every output of a piece starts with. */
void hd_annual_piece_lines(FILE *fp, const hd_annual_opts *o, long first, long count, long total);

/* A text file's lines, without their line ends ('\n', '\r'): the one line
 * reader of the composition's CSVs and logs (the join, the two-pass schedule);
 * a line of cap bytes or more is an error naming the file and line. */
typedef struct hd_annual_text {
    char **line;
    size_t n, cap;
} hd_annual_text;
hd_status hd_annual_text_read(const char *path, size_t cap, hd_annual_text *t);
void hd_annual_text_free(hd_annual_text *t);

/* The command line for the hourly images' headers, without -H k n. */
hd_status hd_annual_header_command(hd_header *h, const hd_annual_opts *o);

#endif

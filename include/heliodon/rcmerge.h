/* heliodon — joining the pieces of an rcontrib output (rcontrib -R) into
 * the full output, byte for byte what one run over all records writes.
 * See src/rcmerge.c for the piece format and docs/man/rcmerge.1. */
#ifndef HELIODON_RCMERGE_H
#define HELIODON_RCMERGE_H

#include "heliodon/common.h"
#include "heliodon/contrib.h"
#include "heliodon/header.h"

/* The RECORDS= line of a piece (nothing without -R). */
hd_status hd_rcontrib_piece_line(const hd_rcontrib_opts *o, hd_header *h);

/* Join the n pieces into out (any order; they must be pieces of one run that
 * cover every record once). */
hd_status hd_rcmerge(const char *out, const char *const *pieces, int n);

/* Join every file of the n piece folders (the same names in each) into
 * outdir/name. */
hd_status hd_rcmerge_dirs(const char *outdir, const char *const *dirs, int n);

/* The records of the full output: -y times -x (1 without -x); 0 unknown. */
uint64_t hd_rcontrib_nrecords(const hd_rcontrib_opts *o);

/* -R in rcontrib's options: checked against -x -y -c -r. */
hd_status hd_rcontrib_check_range(const hd_rcontrib_opts *o);

#endif

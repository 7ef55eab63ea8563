/* heliodon — Radiance information headers (pictures, matrices, octrees).
 *
 * On disk: "#?RADIANCE\n", then text lines (command lines, NAME=value
 * variables), then an empty line.  An hd_header holds the lines between the
 * "#?" line and the empty line, each ending with '\n'. */
#ifndef HELIODON_HEADER_H
#define HELIODON_HEADER_H

#include <stdio.h>
#include "common.h"
#include "io.h"

#define HD_HEADER_MAXLINE 2047   /* Radiance splits longer lines */

typedef struct hd_header {
    char *text;      /* NUL-terminated lines, each ending in '\n' */
    size_t len, cap;
    char ident[64];  /* identifier after "#?" ("RADIANCE"); "" if none */
} hd_header;

void hd_header_init(hd_header *h);
void hd_header_free(hd_header *h);
hd_status hd_header_copy(hd_header *dst, const hd_header *src);

/* Read a header up to and including the empty line.  Requires a "#?" first
 * line unless allow_no_ident is set; limits the header to 16 MiB; errors
 * name the stream and byte offset. */
hd_status hd_header_read(hd_istream *s, hd_header *h, int allow_no_ident);

/* Value of the last "NAME=" line, with leading blanks skipped and trailing
 * white space removed, copied into buf; returns 1 if found, 0 if absent. */
int hd_header_get(const hd_header *h, const char *name, char *buf, size_t cap);
/* Integer variable: HD_OK with *found 0/1, or HD_ERR_FORMAT if malformed. */
hd_status hd_header_get_long(const hd_header *h, const char *name, long *out, int *found);
/* Cumulative EXPOSURE (product of all EXPOSURE= lines; 1 if none). */
double hd_header_exposure(const hd_header *h);

hd_status hd_header_append(hd_header *h, const char *line);  /* adds '\n' */
/* Lines as they are (each ending in '\n'; one is added after the last if
 * it has none); NULL or "" adds nothing. */
hd_status hd_header_append_lines(hd_header *h, const char *lines);
hd_status hd_header_appendf(hd_header *h, const char *fmt, ...) HD_PRINTF(2, 3);
/* Append a command line as Radiance's printargs does (words with blanks quoted). */
hd_status hd_header_add_command(hd_header *h, int argc, char **argv);
/* Append the standard "SOFTWARE= heliodon x.y.z" line. */
hd_status hd_header_add_software(hd_header *h);
/* Append "CAPDATE= YYYY:MM:DD HH:MM:SS" and "GMT= ..." lines (now). */
hd_status hd_header_add_date(hd_header *h);
/* Remove every "NAME=" line (e.g. FORMAT, NROWS when passing a header on). */
void hd_header_remove(hd_header *h, const char *name);

/* Variables a matrix header adds after the caller's lines (hd_header_put). */
typedef struct hd_header_dims {
    int nrows, ncols, ncomp; /* NROWS=, NCOLS=, NCOMP= when > 0 and the header has
                                no such line already (if it has, the values must agree) */
    int endian;              /* BigEndian= line: HD_ENDIAN_NONE, _HOST or _SWAPPED */
} hd_header_dims;
enum { HD_ENDIAN_NONE = 0, HD_ENDIAN_HOST, HD_ENDIAN_SWAPPED };

/* The writer of every header (matrices, pictures, octrees, caches, photon
 * maps, interpolants): "#?RADIANCE" (or h's identifier), h's lines, the
 * variables of dims (may be NULL), "FORMAT=fmt" padded as
 * hd_header_write_format, and the empty line.  h may be NULL (no lines).
 * *nwritten (may be NULL): all bytes written, padding included. */
hd_status hd_header_put(FILE *fp, const hd_header *h, const hd_header_dims *dims, const char *fmt,
                        size_t *nwritten);

/* The two halves of hd_header_put, for callers that copy a header through:
 * Write "#?RADIANCE\n" and the lines (no FORMAT, no empty line). Returns the
 * bytes written so far in *nwritten (may be NULL). */
hd_status hd_header_write(FILE *fp, const hd_header *h, size_t *nwritten);
/* Write "FORMAT=fmt" and the empty line.  For binary matrix formats
 * (float, double, 16/32/64-bit...) that are not pictures, pad the line with
 * spaces as Radiance does so that the data starts at a multiple of
 * 4 (float) / 8 (double) bytes; header_bytes = bytes written before. */
hd_status hd_header_write_format(FILE *fp, const char *fmt, size_t header_bytes);

#endif

/* heliodon — Radiance HDR pictures (RGBE / XYZE), byte-compatible with
 * Radiance: information header, resolution string in all 8 orientations,
 * flat, old run-length and new run-length scanlines.
 *
 * In memory a picture is float RGB (or XYZ) in standard orientation: row 0
 * is the top scanline, pixels left to right — whatever the file's
 * orientation.  Values are as stored in the file (EXPOSURE not undone; use
 * hd_header_exposure()). */
#ifndef HELIODON_PICTURE_H
#define HELIODON_PICTURE_H

#include <stdint.h>
#include <stdio.h>
#include "common.h"
#include "header.h"
#include "io.h"

/* Orientation flags as Radiance's resolu.h */
#define HD_RES_XDECR 1
#define HD_RES_YDECR 2
#define HD_RES_YMAJOR 4
#define HD_RES_STANDARD (HD_RES_YMAJOR | HD_RES_YDECR)   /* "-Y n +X m" */

/* Largest accepted picture side and pixel count (refuses absurd sizes). */
#define HD_PIC_MAXSIDE 1000000
#define HD_PIC_MAXPIXELS ((int64_t)1 << 31)

typedef struct hd_resolu {
    int orient;      /* HD_RES_* flags */
    int xres, yres;  /* image width and height */
} hd_resolu;

typedef enum hd_picfmt { HD_PIC_RGBE = 0, HD_PIC_XYZE = 1 } hd_picfmt;

typedef struct hd_picture {
    int xres, yres;
    float *pix;        /* 3*xres*yres, row-major, row 0 = top */
    hd_picfmt fmt;
    hd_header hdr;     /* header lines as read (FORMAT removed) */
    int orient;        /* orientation found in the file */
} hd_picture;

/* Resolution string: read (any orientation; errors name stream and offset),
 * format as Radiance writes it ("-Y %8d +X %8d\n" etc.). */
hd_status hd_resolu_read(hd_istream *s, hd_resolu *r);
int hd_resolu_format(char *buf, size_t cap, const hd_resolu *r);
/* Parse one resolution line held in memory ("-Y 512 +X 768", trailing
 * newline optional).  what names the source in the error message. */
hd_status hd_resolu_parse(const char *line, hd_resolu *r, const char *what);
/* Check a resolution against HD_PIC_MAXSIDE / HD_PIC_MAXPIXELS (what names
 * the source in the message). */
hd_status hd_resolu_check(const hd_resolu *r, const char *what);
/* Scanline length and count for a resolution. */
int hd_resolu_scanlen(const hd_resolu *r);
int hd_resolu_nscans(const hd_resolu *r);
/* Image position of pixel pos of scanline scan in file order, as
 * Radiance's pix2loc: x from the left, y from the BOTTOM (0..yres-1). */
void hd_resolu_pixel(const hd_resolu *r, int scan, int pos, int *x, int *y);

/* RGBE pixel conversion exactly as Radiance's setcolr/colr_color. */
void hd_rgbe_encode(uint8_t out[4], float r, float g, float b);
void hd_rgbe_decode(const uint8_t in[4], float rgb[3]);
/* Whole runs of n pixels (rgb: 3 floats a pixel, rgbe: 4 bytes a pixel). */
void hd_rgbe_encode_n(uint8_t *rgbe, const float *rgb, size_t n);
void hd_rgbe_decode_n(float *rgb, const uint8_t *rgbe, size_t n);
/* n pixels from separate red, green and blue arrays (planar), the same
 * bytes as hd_rgbe_encode on each pixel: interleaved (rgbe[4*i+c]), or as
 * four planes of n bytes (planes[c*n+i], what hd_scanline_encode_planar
 * takes). */
void hd_rgbe_encode_planar(uint8_t *rgbe, const float *r, const float *g, const float *b, size_t n);
void hd_rgbe_encode_planar_bytes(uint8_t *planes, const float *r, const float *g, const float *b, size_t n);

/* One scanline of len pixels (4 bytes each): reads flat, old-RLE and
 * new-RLE records; writes new RLE for 17 <= len <= 32767 byte-for-byte as
 * Radiance's fwritecolrs, flat otherwise. */
hd_status hd_scanline_read(hd_istream *s, uint8_t *rgbe, int len);
hd_status hd_scanline_write(FILE *fp, const uint8_t *rgbe, int len);
/* Encode one scanline into memory (what hd_scanline_write writes); out
 * must hold hd_scanline_maxbytes(len) bytes.  Returns the byte count. */
size_t hd_scanline_encode(uint8_t *out, const uint8_t *rgbe, int len);
size_t hd_scanline_maxbytes(int len);
/* The same bytes from the scanline's four component planes (planes[c*len + i]
 * is component c of pixel i: R, G, B, E), as hd_rgbe_encode_planar_bytes
 * writes them; the fast path of dctimestep. */
size_t hd_scanline_encode_planar(uint8_t *out, const uint8_t *planes, int len);

/* Streaming access: read the header (FORMAT checked: 32-bit_rle_rgbe,
 * 32-bit_rle_xyze or absent = RGBE; FORMAT removed from hdr) and the
 * resolution string (checked against the size limits).  Then read
 * hd_resolu_nscans() scanlines of hd_resolu_scanlen() pixels with
 * hd_scanline_read().  hdr is initialised here. */
hd_status hd_picture_read_header(hd_istream *s, hd_header *hdr, hd_picfmt *fmt, hd_resolu *r);
/* Header, FORMAT line, empty line and resolution string of a picture. */
hd_status hd_picture_write_header(FILE *fp, const hd_header *hdr, hd_picfmt fmt, const hd_resolu *r);

/* hd_picture_alloc initialises *p completely (as hd_picture_init; it does
 * not free previous contents), then allocates zeroed pixels; fmt RGBE,
 * orient standard.  Refuses sizes over the limits above. */
hd_status hd_picture_alloc(hd_picture *p, int xres, int yres);
void hd_picture_init(hd_picture *p);
void hd_picture_free(hd_picture *p);

/* Read a whole picture ("-" = stdin; gzip transparently).  *p is
 * initialised here (left initialised, with nothing allocated, on failure).
 * The stream variant may read ahead past the end of the picture data. */
hd_status hd_picture_read(const char *path, hd_picture *p);
hd_status hd_picture_read_stream(hd_istream *s, hd_picture *p);

/* Write header (hdr lines, then FORMAT and the empty line), resolution
 * string (orient, normally HD_RES_STANDARD) and RLE scanlines.  The caller
 * composes hdr (inherited lines, command line, SOFTWARE=, VIEW=, ...);
 * hdr NULL means p->hdr. */
hd_status hd_picture_write(FILE *fp, const hd_picture *p, const hd_header *hdr, int orient);
/* Convenience: atomic write to path ("-" = stdout). */
hd_status hd_picture_save(const char *path, const hd_picture *p, const hd_header *hdr);

/* Luminance-weighted brightness of an RGB value as Radiance's bright()
 * (0.265074126 R + 0.670114631 G + 0.064811243 B); for XYZE data the
 * brightness is Y. */
double hd_rgb_bright(const float rgb[3]);
/* Radiance 6.1's bright() with the factors of its standard primaries as its
 * compiler evaluates them (y_r C_rD / D ...: 0.26510582 R + 0.67010582 G +
 * 0.06478836 B), which differ from the rounded ones above in the 5th digit:
 * what pfilt's exposure and -m decisions, pcomb's brightness and
 * falsecolor's scale are computed with. */
double hd_rgb_bright_rad(const float rgb[3]);

/* ---- getinfo support ----
 * Read an information header exactly as Radiance's getheader does: the
 * first byte must be printable, lines are read up to the first empty line
 * ("\n" or "\r\n"), which is consumed but not returned.  *text receives the
 * raw header bytes (NUL-terminated, free() it), *len their count. */
hd_status hd_info_read_raw(hd_istream *s, char **text, size_t *len);
/* The dimension line printed by getinfo -d for the data that follows a
 * header (stream positioned just after the empty line): a picture's
 * resolution string as found in the file, an octree's bounding cube
 * "xmin ymin zmin size", for a matrix (header with NROWS= and NCOLS=) the
 * line "NROWS=r NCOLS=c NCOMP=n", else "unknown file type".  buf receives
 * the line with its newline; returns HD_OK (also for unknown types). */
hd_status hd_info_dimensions(hd_istream *s, const char *rawhdr, char *buf, size_t cap);
/* getinfo -r: whether header line matches one of the patterns (NULL-
 * terminated) and must be dropped (Radiance's rules: a single word removes
 * "WORD=" lines, "WORD=value" removes "WORD=" lines, "word more" removes
 * lines whose first word is "word"; a pattern starting with white space
 * matches only indented lines).  hd_info_pattern_line_len: whether a
 * pattern is itself a line to add (contains '=' or a blank strictly inside
 * its trimmed text): the number of bytes to print (trailing white space
 * removed), or 0. */
int hd_info_line_removed(const char *line, char *const *patterns);
size_t hd_info_pattern_line_len(const char *pattern);
/* FORMAT= value of a raw header line ("FORMAT=x\n" -> "x"), or 0. */
int hd_info_format_value(const char *line, char *buf, size_t cap);

#endif

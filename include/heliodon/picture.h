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
/* Scanline length and count for a resolution. */
int hd_resolu_scanlen(const hd_resolu *r);
int hd_resolu_nscans(const hd_resolu *r);

/* RGBE pixel conversion exactly as Radiance's setcolr/colr_color. */
void hd_rgbe_encode(uint8_t out[4], float r, float g, float b);
void hd_rgbe_decode(const uint8_t in[4], float rgb[3]);

/* One scanline of len pixels (4 bytes each): reads flat, old-RLE and
 * new-RLE records; writes new RLE for 17 <= len <= 32767 byte-for-byte as
 * Radiance's fwritecolrs, flat otherwise. */
hd_status hd_scanline_read(hd_istream *s, uint8_t *rgbe, int len);
hd_status hd_scanline_write(FILE *fp, const uint8_t *rgbe, int len);

hd_status hd_picture_alloc(hd_picture *p, int xres, int yres);
void hd_picture_init(hd_picture *p);
void hd_picture_free(hd_picture *p);

/* Read a whole picture ("-" = stdin; gzip transparently). */
hd_status hd_picture_read(const char *path, hd_picture *p);
hd_status hd_picture_read_stream(hd_istream *s, hd_picture *p);

/* Write header (hdr lines, then FORMAT and the empty line), resolution
 * string (orient, normally HD_RES_STANDARD) and RLE scanlines.  The caller
 * composes hdr (inherited lines, command line, SOFTWARE=, VIEW=, ...). */
hd_status hd_picture_write(FILE *fp, const hd_picture *p, const hd_header *hdr, int orient);
/* Convenience: atomic write to path ("-" = stdout). */
hd_status hd_picture_save(const char *path, const hd_picture *p, const hd_header *hdr);

#endif

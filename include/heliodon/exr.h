/* heliodon — OpenEXR images through the OpenEXRCore C API.
 *
 * An hd_exr_image holds named float channels of xres*yres values each
 * (row-major, row 0 = the top scanline, like hd_picture), the pixel type
 * each channel has (or will have) in the file, string attributes, and
 * optionally chromaticities.
 *
 * Writing: scanline images, one part, HALF / FLOAT / UINT channels,
 * compression NONE, RLE, ZIPS, ZIP or PIZ; data and display windows are
 * (0,0)-(xres-1,yres-1), line order increasing Y.  The file is assembled in
 * memory and written through hd_ofile (temporary name + rename; "-" =
 * standard output).  The same image gives byte-identical files.
 *
 * Reading: one part (the first by default) of a scanline or tiled file
 * (tiled: level 0 only), every channel converted to float whatever its type
 * (HALF, FLOAT, UINT; UINT values above 2^24 lose precision);
 * the data window becomes the image (its origin is kept in x0, y0).  Input
 * may be a file, "-" or "!command" (read whole into memory, gzip
 * transparently).  Corrupt or truncated files give HD_ERR_FORMAT with a
 * message naming the file and OpenEXRCore's description; sizes beyond
 * HD_EXR_MAXSIDE or the allocation limit are refused before allocating.
 *
 * Deep images and subsampled channels (x/y sampling > 1) are not read
 * (HD_ERR_UNSUPPORTED); multi-part files are not written. */
#ifndef HELIODON_EXR_H
#define HELIODON_EXR_H

#include <stdint.h>
#include "common.h"
#include "picture.h"

/* Largest accepted image side (read and write). */
#define HD_EXR_MAXSIDE 1000000
/* Largest finite half-float value. */
#define HD_EXR_HALF_MAX 65504.0
/* Name of the string attribute carrying the Radiance-style header lines
 * (inherited lines, command lines, variables) for provenance. */
#define HD_EXR_HEADER_ATTR "heliodonHeader"
/* hdr2exr -L stores each layer's input header in "heliodonHeader.LAYER"
 * and its own command line in HD_EXR_HEADER_ATTR. */

/* Values as in the OpenEXR file format. */
typedef enum hd_exr_compression {
    HD_EXR_NONE = 0,
    HD_EXR_RLE = 1,
    HD_EXR_ZIPS = 2,
    HD_EXR_ZIP = 3,
    HD_EXR_PIZ = 4,
    HD_EXR_PXR24 = 5,   /* read only */
    HD_EXR_B44 = 6,     /* read only */
    HD_EXR_B44A = 7,    /* read only */
    HD_EXR_DWAA = 8,    /* read only if OpenEXRCore implements it (3.1 does */
    HD_EXR_DWAB = 9     /* not: HD_ERR_UNSUPPORTED naming the compression) */
} hd_exr_compression;

typedef enum hd_exr_pixtype {
    HD_EXR_UINT = 0,
    HD_EXR_HALF = 1,
    HD_EXR_FLOAT = 2
} hd_exr_pixtype;

typedef struct hd_exr_channel {
    char *name;              /* full name, e.g. "R" or "wg1.R" */
    hd_exr_pixtype type;     /* type in the file */
    float *data;             /* xres*yres values, row 0 = top */
} hd_exr_channel;

typedef struct hd_exr_attr {
    char *name;
    char *value;             /* NUL-terminated */
} hd_exr_attr;

typedef struct hd_exr_image {
    int xres, yres;
    int x0, y0;              /* data window origin (read); 0 when writing */
    int nchan;
    hd_exr_channel *chan;    /* in the order added (write) / file order (read:
                                alphabetical, as OpenEXR sorts channels) */
    int nattr;
    hd_exr_attr *attr;       /* string attributes */
    int has_chroma;          /* chromaticities attribute present / to write */
    float chroma[8];         /* red x y, green x y, blue x y, white x y */
    hd_exr_compression compression;   /* as read; hd_exr_save takes its own */
    int tiled;               /* read: file was tiled */
    int part;                /* read: index of the part read */
} hd_exr_image;

/* Radiance's default primaries (CIE xy of R, G, B, equal-energy white) and
 * the XYZ convention of OpenEXR (X, Y, Z stored in R, G, B). */
extern const float hd_exr_chroma_radiance[8];
extern const float hd_exr_chroma_xyz[8];

void hd_exr_init(hd_exr_image *img);
void hd_exr_free(hd_exr_image *img);
/* Set the size (no channels yet): refuses sizes < 1 or > HD_EXR_MAXSIDE. */
hd_status hd_exr_set_size(hd_exr_image *img, int xres, int yres);
/* Add a zero-filled channel; *index (may be NULL) receives its index.
 * Names must be 1..255 bytes and unique. */
hd_status hd_exr_add_channel(hd_exr_image *img, const char *name,
                             hd_exr_pixtype type, int *index);
/* Index of a channel by full name, or -1. */
int hd_exr_find_channel(const hd_exr_image *img, const char *name);
/* Set (replace) a string attribute.  Names 1..255 bytes; names of the
 * attributes OpenEXR reserves (channels, compression, dataWindow, ...) are
 * refused. */
hd_status hd_exr_set_attr(hd_exr_image *img, const char *name, const char *value);
/* Value of a string attribute, or NULL. */
const char *hd_exr_get_attr(const hd_exr_image *img, const char *name);

/* Parse "none", "rle", "zips", "zip", "piz" (case-insensitive). Returns 0
 * on success. */
int hd_exr_parse_compression(const char *word, hd_exr_compression *out);
const char *hd_exr_compression_name(hd_exr_compression c);
const char *hd_exr_pixtype_name(hd_exr_pixtype t);

/* Encode to an in-memory file (malloc'ed, free with free()). */
hd_status hd_exr_encode(const hd_exr_image *img, hd_exr_compression comp,
                        const char *name, uint8_t **data, size_t *len);
/* Write to fp (name for messages), or to path ("-" = standard output)
 * through hd_ofile. */
hd_status hd_exr_write(FILE *fp, const char *name, const hd_exr_image *img, hd_exr_compression comp);
hd_status hd_exr_save(const char *path, const hd_exr_image *img, hd_exr_compression comp);

/* Decode an in-memory file; name is used in messages.  img must have been
 * initialised (hd_exr_init); its previous contents are freed.  Reads the
 * first part (with a warning if there are more). */
hd_status hd_exr_decode(const void *data, size_t len, const char *name, hd_exr_image *img);
/* Same for the part named part (its "name" attribute) or numbered part
 * (0 = first); NULL or "" = first. An unknown part gives HD_ERR_FORMAT
 * listing the parts. */
hd_status hd_exr_decode_part(const void *data, size_t len, const char *name, const char *part,
                             hd_exr_image *img);
/* Read a whole file ("-" = standard input, "!cmd", gzip transparently). */
hd_status hd_exr_load(const char *path, hd_exr_image *img);
hd_status hd_exr_load_part(const char *path, const char *part, hd_exr_image *img);
/* Whether the 4 bytes are the OpenEXR magic number. */
int hd_exr_is_magic(const uint8_t b[4]);

/* ---- conversions with Radiance pictures ----
 * hd_exr_from_picture adds channels LAYER.R, LAYER.G, LAYER.B (R, G, B
 * when layer is NULL or "") of the given type holding the picture's values
 * times scale.  The first picture fixes the size; later ones must match.
 * Chromaticities are set (if not yet) from the picture: XYZE pictures get
 * hd_exr_chroma_xyz, RGBE pictures their PRIMARIES= line or Radiance's
 * default primaries.  For HALF channels, values beyond +-HD_EXR_HALF_MAX are
 * clamped to it (with a warning giving the count). */
hd_status hd_exr_from_picture(hd_exr_image *img, const hd_picture *p,
                              const char *layer, hd_exr_pixtype type, double scale);
/* The one picture-as-OpenEXR writer (dctimestep, rcontrib): p as float R,
 * G, B channels, ZIP, on fp; h's lines (when h has any) in the
 * HD_EXR_HEADER_ATTR attribute. */
hd_status hd_exr_write_picture(FILE *fp, const char *name, const hd_picture *p, const hd_header *h);
/* hd_exr_to_picture fills p (allocated here; p must be initialised) from
 * LAYER.R/G/B, or — when those are absent — from a single LAYER.Y
 * (luminance, copied to all three).  Chromaticities equal to
 * hd_exr_chroma_xyz make an XYZE picture.  Missing channels give
 * HD_ERR_FORMAT listing the layers the file has.  NaN becomes 0 and values
 * above 1e38 (beyond RGBE) become 1e38, with a warning giving the count;
 * negative values are kept (RGBE encoding writes them as 0). */
hd_status hd_exr_to_picture(const hd_exr_image *img, const char *layer, hd_picture *p);
/* Append "PRIMARIES= ..." (Radiance's %.4f layout) to h when the image has
 * chromaticities (other than the XYZ convention) that differ from the last
 * PRIMARIES line already in h, or from Radiance's default primaries if h has
 * none.  Radiance takes the last PRIMARIES line. */
hd_status hd_exr_header_add_primaries(const hd_exr_image *img, hd_header *h);
/* Comma-separated list of the layers (channel name up to the last '.',
 * "" for the unnamed layer, shown as "(default)") in buf. */
void hd_exr_list_layers(const hd_exr_image *img, char *buf, size_t cap);

#endif

/* heliodon — rcontrib picture streams (kept apart from render.h, whose
 * colour helper name clashes with picture.h on some branches). */
#include <stdio.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/picture.h"

hd_status hd_contrib_write_scanlines(FILE *fp, const float *pix, int xres, int yres);
hd_status hd_contrib_write_flat(FILE *fp, const float *pix, uint64_t n);

hd_status hd_contrib_write_scanlines(FILE *fp, const float *pix, int xres, int yres)
{
    uint8_t *line = hd_malloc_array((size_t)xres, 4);
    if (!line) return HD_ERR_NOMEM;
    for (int y = 0; y < yres; y++) {
        hd_rgbe_encode_n(line, pix + 3 * (size_t)y * xres, (size_t)xres);
        hd_status st = hd_scanline_write(fp, line, xres);
        if (st != HD_OK) { free(line); return st; }
    }
    free(line);
    return HD_OK;
}

/* The pixels of an rcontrib -R piece: flat 4-byte RGBE records (rcmerge
 * encodes the scanlines of the joined picture). */
hd_status hd_contrib_write_flat(FILE *fp, const float *pix, uint64_t n)
{
    uint8_t buf[4 * 1024];
    for (uint64_t i = 0; i < n; i += 1024) {
        size_t k = n - i < 1024 ? (size_t)(n - i) : 1024;
        hd_rgbe_encode_n(buf, pix + 3 * i, k);
        if (fwrite(buf, 4, k, fp) != k) return hd_fail(HD_ERR_IO, "error writing a picture piece: %s", strerror(errno));
    }
    return HD_OK;
}

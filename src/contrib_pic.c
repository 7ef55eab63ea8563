/* heliodon — rcontrib picture streams (kept apart from render.h, whose
 * colour helper name clashes with picture.h on some branches). */
#include <stdio.h>
#include <stdlib.h>

#include "heliodon/picture.h"

hd_status hd_contrib_write_scanlines(FILE *fp, const float *pix, int xres, int yres);

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

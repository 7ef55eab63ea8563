/* pextrem — the darkest and brightest pixel of a Radiance picture, as
 * Radiance's pextrem (docs/man/pextrem.1): pixels are compared on their
 * stored RGBE bytes (exponent first, then an integer brightness), ties keep
 * the first pixel met scanning each scanline from its end. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/picture.h"

/* integer brightness of RGBE bytes (Radiance's weights x 256, rounded) */
static long normbright(const uint8_t *c) { return (68L * c[0] + 172L * c[1] + 16L * c[2]) >> 8; }

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int orig = 0, i;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "-o")) orig = 1;
        else if (!strcmp(argv[i], "-O")) orig = -1;
        else break;
    }
    if (i < argc - 1) hd_die_msg("usage: pextrem [-o|-O] [picture]");
    hd_istream *s;
    if (hd_istream_open(&s, i < argc ? argv[i] : "-")) hd_die();
    hd_header h;
    hd_picfmt fmt;
    hd_resolu r;
    if (hd_picture_read_header(s, &h, &fmt, &r)) hd_die();
    float expos[3] = {1, 1, 1};
    if (orig) {                  /* undo EXPOSURE= and COLORCORR= */
        for (const char *l = h.text; l && *l;) {
            if (!strncmp(l, "EXPOSURE=", 9)) {
                double d = atof(l + 9);
                for (int k = 0; k < 3; k++) expos[k] = (float)(expos[k] * d);
            } else if (!strncmp(l, "COLORCORR=", 10)) {
                double c[3] = {1, 1, 1};
                if (sscanf(l + 10, "%lf %lf %lf", &c[0], &c[1], &c[2]) == 3)
                    for (int k = 0; k < 3; k++) expos[k] = (float)(expos[k] * c[k]);
            }
            const char *nl = strchr(l, '\n');
            l = nl ? nl + 1 : l + strlen(l);
        }
        if (orig < 0 && fmt == HD_PIC_XYZE)
            for (int k = 0; k < 3; k++) expos[k] = (float)(expos[k] * (1. / 179.));
    }
    int len = hd_resolu_scanlen(&r), n = hd_resolu_nscans(&r);
    uint8_t *scan = hd_malloc_array((size_t)len, 4);
    if (!scan) hd_die();
    uint8_t cmin[4], cmax[4] = {0, 0, 0, 0};
    hd_rgbe_encode(cmin, 1e30f, 1e30f, 1e30f);
    int xmin = 0, ymin = 0, xmax = 0, ymax = 0;
    for (int y = n - 1; y >= 0; y--) {
        if (hd_scanline_read(s, scan, len)) hd_die();
        for (int x = len; x-- > 0;) {
            const uint8_t *c = scan + 4 * x;
            if (c[3] > cmax[3] || (c[3] == cmax[3] && normbright(c) > normbright(cmax))) {
                memcpy(cmax, c, 4); xmax = x; ymax = y;
            }
            if (c[3] < cmin[3] || (c[3] == cmin[3] && normbright(c) < normbright(cmin))) {
                memcpy(cmin, c, 4); xmin = x; ymin = y;
            }
        }
    }
    float t[3];
    hd_rgbe_decode(cmin, t);
    printf("%d %d\t%.2e %.2e %.2e\n", xmin, ymin, t[0] / expos[0], t[1] / expos[1], t[2] / expos[2]);
    hd_rgbe_decode(cmax, t);
    printf("%d %d\t%.2e %.2e %.2e\n", xmax, ymax, t[0] / expos[0], t[1] / expos[1], t[2] / expos[2]);
    if (fflush(stdout)) hd_die_msg("write error on standard output");
    free(scan);
    hd_header_free(&h);
    hd_istream_close(s);
    return 0;
}

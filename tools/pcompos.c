/* pcompos — compose Radiance pictures side by side or on top of each
 * other, as Radiance's pcompos (docs/man/pcompos.1).  Pixels are copied as
 * stored RGBE bytes.  Labels (-l, -la, -lh) need Radiance's psign and are
 * refused. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/io.h"
#include "heliodon/pictools.h"

typedef struct input {
    hd_rawpic pic;
    int xloc, yloc, flags;
    double thmin, thmax;
} input;

static long normbright(const uint8_t *c) { return (68L * c[0] + 172L * c[1] + 16L * c[2]) >> 8; }

/* compare stored bytes to a luminance (as Radiance's pcompos thresholds) */
static int cmp_lum(const uint8_t *c, double lv)
{
    double l = c[3] ? ldexp((double)normbright(c), (int)c[3] - (128 + 8)) : 0.;
    return l < lv ? -1 : l > lv;
}

static int iarg(int argc, char **argv, int i)
{
    long v;
    if (i >= argc || hd_parse_long(argv[i], &v)) hd_die_msg("%s: expected an integer", argv[i - 1]);
    return (int)v;
}

static void usage(void)
{
    hd_die_msg("usage: pcompos [-h][-x xr][-y yr][-b r g b][-a n][-s p][-o x0 y0] "
               "[-t min1][+t max1][=SS] pic1 x1 y1 ..");
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int echo = 1, xsiz = 0, ysiz = 0, ncol = 0, spacing = 0, x0 = 0, curx = 0, cury = 0, curcol = 0, an;
    uint8_t bg[4] = {0, 0, 0, 0};
    for (an = 1; an < argc && argv[an][0] == '-'; an++) {
        char c = argv[an][1];
        if (c == 0 || c == 't') break;
        switch (c) {
        case 'h': echo = !echo; break;
        case 'x': xsiz = iarg(argc, argv, ++an); break;
        case 'y': ysiz = iarg(argc, argv, ++an); break;
        case 'b': {
            double v[3];
            for (int k = 0; k < 3; k++)
                if (an + 1 + k >= argc || hd_parse_double(argv[an + 1 + k], &v[k])) hd_die_msg("-b: expected r g b");
            hd_rgbe_encode(bg, (float)v[0], (float)v[1], (float)v[2]);
            an += 3;
            break;
        }
        case 'a': ncol = iarg(argc, argv, ++an); break;
        case 's': spacing = iarg(argc, argv, ++an); break;
        case 'o': curx = x0 = iarg(argc, argv, ++an); cury = iarg(argc, argv, ++an); break;
        case 'l': hd_die_msg("%s: labels need Radiance's psign, which heliodon does not have", argv[an]);
        default: usage();
        }
    }
    hd_header h;
    hd_header_init(&h);
    if (hd_header_add_date(&h)) hd_die();
    input *in = NULL;
    int n = 0, xmin = 0, ymin = 0, xmax = 0, ymax = 0, check = 0;
    double common = 1.;
    hd_picfmt fmt = HD_PIC_RGBE;
    while (an < argc) {
        input *x = hd_realloc_array(in, (size_t)n + 1, sizeof *in);
        if (!x) hd_die();
        in = x;
        input *p = &in[n];
        memset(p, 0, sizeof *p);
        char xs = '-', ys = '-';
        while (an < argc && (argv[an][0] == '-' || argv[an][0] == '+' || argv[an][0] == '=')) {
            const char *a = argv[an];
            if (a[1] == 't' && a[0] != '=') {
                double v;
                if (an + 1 >= argc || hd_parse_double(argv[an + 1], &v)) usage();
                check = 1;
                if (a[0] == '-') { p->flags |= 1; p->thmin = v; } else { p->flags |= 2; p->thmax = v; }
                an++;
            } else if (!strcmp(a, "-l")) {
                hd_die_msg("-l: labels need Radiance's psign, which heliodon does not have");
            } else if (a[0] == '=' && (a[1] == '+' || a[1] == '-' || a[1] == '0') &&
                       (a[2] == '+' || a[2] == '-' || a[2] == '0')) {
                xs = a[1]; ys = a[2];
            } else if (!strcmp(a, "-")) {
                break;
            } else usage();
            an++;
        }
        if (argc - an < (ncol ? 1 : 3)) usage();
        const char *name = argv[an];
        if (hd_rawpic_read(name, &p->pic)) hd_die();
        an++;
        const char *shown = !strcmp(name, "-") ? "<stdin>" : name[0] == '!' ? "<Command>" : name;
        double ex = 1;
        if (echo && hd_header_appendf(&h, "%s:", shown)) hd_die();
        for (const char *l = p->pic.hdr.text; l && *l;) {
            const char *nl = strchr(l, '\n');
            size_t len = nl ? (size_t)(nl - l) : strlen(l);
            if (!strncmp(l, "EXPOSURE=", 9)) ex *= atof(l + 9);
            if (echo && hd_header_appendf(&h, "\t%.*s", (int)len, l)) hd_die();
            l = nl ? nl + 1 : l + len;
        }
        if (!n) common = ex;
        else if (common > 0 && fabs(ex / common - 1.) > 0.02) common = 0;
        if (n && p->pic.fmt != fmt) hd_die_msg("%s: incompatible input format", shown);
        fmt = p->pic.fmt;
        int xr = p->pic.len, yr = p->pic.nscans;
        if (ncol) {
            if (curcol >= abs(ncol)) { cury = ymax + spacing; curx = x0; curcol = 0; }
            p->xloc = curx; p->yloc = cury;
            curx += xr + spacing;
            curcol++;
        } else {
            p->xloc = iarg(argc, argv, an++);
            if (xs == '+') p->xloc -= xr; else if (xs == '0') p->xloc -= xr / 2;
            p->yloc = iarg(argc, argv, an++);
            if (ys == '+') p->yloc -= yr; else if (ys == '0') p->yloc -= yr / 2;
        }
        if (p->xloc < xmin) xmin = p->xloc;
        if (p->yloc < ymin) ymin = p->yloc;
        if (p->xloc + xr > xmax) xmax = p->xloc + xr;
        if (p->yloc + yr > ymax) ymax = p->yloc + yr;
        n++;
    }
    if (xsiz <= 0) xsiz = xmax; else if (xsiz > xmax) xmax = xsiz;
    if (ysiz <= 0) ysiz = ymax; else if (ysiz > ymax) ymax = ysiz;
    if (ncol < 0)
        for (int i = 0; i < n; i++) in[i].yloc = ymax - in[i].pic.nscans - in[i].yloc;
    if (xsiz <= 0 || ysiz <= 0) hd_die_msg("nothing to compose (no input, or an empty output size)");
    if (hd_header_add_command(&h, argc, argv)) hd_die();
    if (common > 0 && hd_header_appendf(&h, "EXPOSURE=%.4e", common)) hd_die();
    hd_rawpic out;
    if (hd_rawpic_blank(&out, fmt, xsiz, ysiz)) hd_die();
    /* one shared scanline buffer spanning xmin..xmax, as later inputs
     * overwrite earlier ones */
    uint8_t *buf = hd_malloc_array((size_t)(xmax - xmin), 4), *row = buf - 4 * (ptrdiff_t)xmin;
    uint8_t *sout = check ? hd_malloc_array((size_t)xsiz, 4) : row;
    if (!buf || !sout) hd_die();
    for (int y = ymax - 1; y >= 0; y--) {
        for (int x = 0; x < xsiz; x++) memcpy(sout + 4 * x, bg, 4);
        for (int i = 0; i < n; i++) {
            input *p = &in[i];
            if (p->yloc > y || p->yloc + p->pic.nscans <= y) continue;
            int scan = p->yloc + p->pic.nscans - 1 - y;      /* top scanline first */
            memcpy(row + 4 * (ptrdiff_t)p->xloc, p->pic.rgbe + (size_t)scan * p->pic.len * 4, (size_t)p->pic.len * 4);
            if (y >= ysiz || !check) continue;
            int x = p->xloc + p->pic.len;
            if (x > xsiz) x = xsiz;
            for (x--; x >= 0 && x >= p->xloc; x--) {
                const uint8_t *c = row + 4 * x;
                if ((p->flags & 1) && cmp_lum(c, p->thmin) <= 0) continue;
                if ((p->flags & 2) && cmp_lum(c, p->thmax) >= 0) continue;
                memcpy(sout + 4 * x, c, 4);
            }
        }
        if (y < ysiz) memcpy(out.rgbe + (size_t)(ysiz - 1 - y) * xsiz * 4, sout, (size_t)xsiz * 4);
    }
    if (hd_rawpic_write(stdout, &out, &h) || fflush(stdout)) hd_die();
    for (int i = 0; i < n; i++) hd_rawpic_free(&in[i].pic);
    free(in);
    free(buf);
    if (check) free(sout);
    hd_rawpic_free(&out);
    hd_header_free(&h);
    return 0;
}

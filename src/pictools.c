/* heliodon — pictures as stored RGBE bytes: reading and writing them in
 * file order, the lossless transforms of pflip and protate (pixels are
 * moved, never decoded, so the output bytes are those of the input), and
 * pextrem's search for the extreme pixels. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/io.h"
#include "heliodon/pictools.h"

hd_status hd_rawpic_read(const char *path, hd_rawpic *p)
{
    hd_istream *s;
    memset(p, 0, sizeof *p);
    hd_status st = hd_istream_open(&s, path);
    if (st) return st;
    st = hd_rawpic_read_stream(s, p);
    hd_istream_close(s);
    return st;
}

hd_status hd_rawpic_read_stream(hd_istream *s, hd_rawpic *p)
{
    memset(p, 0, sizeof *p);
    hd_status st = hd_picture_read_header(s, &p->hdr, &p->fmt, &p->r);
    if (!st) {
        p->len = hd_resolu_scanlen(&p->r);
        p->nscans = hd_resolu_nscans(&p->r);
        p->rgbe = hd_malloc_array((size_t)p->len * p->nscans, 4);
        if (!p->rgbe) st = HD_ERR_NOMEM;
    }
    for (int y = 0; y < p->nscans && !st; y++) st = hd_scanline_read(s, p->rgbe + (size_t)y * p->len * 4, p->len);
    if (st) hd_rawpic_free(p);
    return st;
}

hd_status hd_rawpic_blank(hd_rawpic *p, hd_picfmt fmt, int w, int h)
{
    memset(p, 0, sizeof *p);
    hd_header_init(&p->hdr);
    p->fmt = fmt;
    p->len = w;
    p->nscans = h;
    p->r.orient = HD_RES_STANDARD;
    p->r.xres = w;
    p->r.yres = h;
    hd_status st = hd_resolu_check(&p->r, "picture");
    if (st) return st;
    p->rgbe = hd_calloc((size_t)w * (size_t)h, 4);
    return p->rgbe ? HD_OK : HD_ERR_NOMEM;
}

void hd_rawpic_free(hd_rawpic *p)
{
    hd_header_free(&p->hdr);
    free(p->rgbe);
    p->rgbe = NULL;
}

hd_status hd_rawpic_write(FILE *fp, const hd_rawpic *p, const hd_header *hdr)
{
    hd_status st = hd_picture_write_header(fp, hdr ? hdr : &p->hdr, p->fmt, &p->r);
    for (int y = 0; y < p->nscans && !st; y++) st = hd_scanline_write(fp, p->rgbe + (size_t)y * p->len * 4, p->len);
    return st;
}

hd_status hd_rawpic_save(const char *path, const hd_rawpic *p)
{
    hd_ofile *of;
    hd_status st = hd_ofile_open(&of, path);
    if (st) return st;
    if ((st = hd_rawpic_write(hd_ofile_fp(of), p, NULL))) { hd_ofile_abort(of); return st; }
    return hd_ofile_commit(of);
}

/* new resolution from orientation and (scanline length, count) */
static void set_res(hd_resolu *r, int orient, int len, int nscans)
{
    r->orient = orient;
    if (orient & HD_RES_YMAJOR) { r->xres = len; r->yres = nscans; }
    else { r->xres = nscans; r->yres = len; }
}

hd_status hd_rawpic_flip(hd_rawpic *p, int h, int v, int keep_order)
{
    size_t row = (size_t)p->len * 4;
    uint8_t *out = hd_malloc_array((size_t)p->nscans, row);
    if (!out) return HD_ERR_NOMEM;
    for (int y = 0; y < p->nscans; y++) {
        const uint8_t *src = p->rgbe + (size_t)(v ? p->nscans - 1 - y : y) * row;
        uint8_t *dst = out + (size_t)y * row;
        if (h) for (int x = 0; x < p->len; x++) memcpy(dst + 4 * x, src + 4 * (p->len - 1 - x), 4);
        else memcpy(dst, src, row);
    }
    free(p->rgbe);
    p->rgbe = out;
    int o = p->r.orient;
    if (!keep_order) {
        if (o & HD_RES_YMAJOR) { if (h) o ^= HD_RES_XDECR; if (v) o ^= HD_RES_YDECR; }
        else { if (h) o ^= HD_RES_YDECR; if (v) o ^= HD_RES_XDECR; }
    }
    set_res(&p->r, o, p->len, p->nscans);
    return HD_OK;
}

hd_status hd_rawpic_rotate(hd_rawpic *p, int ccw, int keep_order)
{
    /* orientation after a clockwise turn, indexed by the old one */
    static const int cw[8] = {
        [HD_RES_YMAJOR | HD_RES_YDECR] = 0,
        [0] = HD_RES_YMAJOR | HD_RES_XDECR,
        [HD_RES_YMAJOR | HD_RES_XDECR] = HD_RES_XDECR | HD_RES_YDECR,
        [HD_RES_XDECR | HD_RES_YDECR] = HD_RES_YMAJOR | HD_RES_YDECR,
        [HD_RES_YMAJOR | HD_RES_XDECR | HD_RES_YDECR] = HD_RES_XDECR,
        [HD_RES_XDECR] = HD_RES_YMAJOR,
        [HD_RES_YMAJOR] = HD_RES_YDECR,
        [HD_RES_YDECR] = HD_RES_YMAJOR | HD_RES_XDECR | HD_RES_YDECR,
    };
    int len = p->len, ns = p->nscans;
    uint8_t *out = hd_malloc_array((size_t)len * ns, 4);
    if (!out) return HD_ERR_NOMEM;
    /* new scanline j (of ns pixels) is old column j (clockwise: bottom
     * scanline first) or old column len-1-j (counter-clockwise) */
    for (int j = 0; j < len; j++)
        for (int k = 0; k < ns; k++) {
            const uint8_t *src = ccw ? p->rgbe + ((size_t)k * len + (size_t)(len - 1 - j)) * 4
                                     : p->rgbe + ((size_t)(ns - 1 - k) * len + (size_t)j) * 4;
            memcpy(out + ((size_t)j * ns + k) * 4, src, 4);
        }
    free(p->rgbe);
    p->rgbe = out;
    int o = p->r.orient & 7;
    if (!keep_order) {
        if (!ccw) o = cw[o];
        else for (int i = 0; i < 8; i++) if (cw[i] == o) { o = i; break; }
    }
    p->len = ns;
    p->nscans = len;
    set_res(&p->r, o, p->len, p->nscans);
    return HD_OK;
}

/* integer brightness of RGBE bytes (Radiance's weights x 256, rounded) */
static long normbright(const uint8_t *c) { return (68L * c[0] + 172L * c[1] + 16L * c[2]) >> 8; }

hd_status hd_pextrem(hd_istream *s, int orig, hd_extrema *e)
{
    hd_header h;
    hd_picfmt fmt;
    hd_resolu r;
    memset(e, 0, sizeof *e);
    hd_status st = hd_picture_read_header(s, &h, &fmt, &r);
    if (st) return st;
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
    hd_header_free(&h);
    int len = hd_resolu_scanlen(&r), n = hd_resolu_nscans(&r);
    uint8_t *scan = hd_malloc_array((size_t)len, 4);
    if (!scan) return HD_ERR_NOMEM;
    uint8_t cmin[4], cmax[4] = {0, 0, 0, 0};
    hd_rgbe_encode(cmin, 1e30f, 1e30f, 1e30f);
    for (int y = n - 1; y >= 0 && !st; y--) {
        if ((st = hd_scanline_read(s, scan, len))) break;
        for (int x = len; x-- > 0;) {
            const uint8_t *c = scan + 4 * x;
            if (c[3] > cmax[3] || (c[3] == cmax[3] && normbright(c) > normbright(cmax))) {
                memcpy(cmax, c, 4); e->xmax = x; e->ymax = y;
            }
            if (c[3] < cmin[3] || (c[3] == cmin[3] && normbright(c) < normbright(cmin))) {
                memcpy(cmin, c, 4); e->xmin = x; e->ymin = y;
            }
        }
    }
    free(scan);
    hd_rgbe_decode(cmin, e->min);
    hd_rgbe_decode(cmax, e->max);
    for (int k = 0; k < 3; k++) { e->min[k] /= expos[k]; e->max[k] /= expos[k]; }
    return st;
}

/* heliodon — pfilt: picture filtering and resampling as Radiance's pfilt
 * (box filter, Gaussian filter -r, Gaussian with limited influence -m,
 * automatic exposure in a first pass, star patterns on hot pixels).
 *
 * The arithmetic follows Radiance's pfilt step by step so that the output
 * pixels are the same: colours are single-precision floats as in a
 * Radiance scanline, sums are accumulated in float, weights in double, and
 * the Gaussian is read from a table sampled every 0.05 of the squared
 * distance.  The picture is held whole in memory (in file order), so the
 * scanline bars of the original become plain row indexing. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/pictools.h"
#include "heliodon/view.h"

#define PF_FTINY 1e-6
#define PF_CHECKRAD 2.0       /* filter radius checked, in output pixels */
#define PF_THRESHRAD 5.0      /* largest spread of a sample (-m) */
#define PF_AVGLVL 0.5         /* mean brightness the exposure aims at */
#define PF_RSCA 1.13          /* square-radius multiplier, sqrt(4/pi) */
#define PF_TEPS 0.2
#define PF_REPS 0.1
#define PF_GTAB 1776            /* 444 * CHECKRAD^2 entries */

void hd_pfilt_opts_default(hd_pfilt_opts *o)
{
    memset(o, 0, sizeof *o);
    o->xratio = o->yratio = 1.0;
    o->exposure[0] = o->exposure[1] = o->exposure[2] = 1.0;
    o->hotlvl = 100.0;
    o->spread = 1e-4;
}

typedef struct pf {
    int xres, yres, ncols, nrows;
    double x_c, y_r, rad, thresh;
    int xbrad, ybrad, xrad, yrad, orad;
    int wrap, xyz;
    float *in;                /* yres rows of xres RGB floats */
    float gauss[PF_GTAB];
    short *ringndx;
    float *ringsum;
    short *ringwt;
    float *warr;
    float *grey;              /* nrows x ncols box-filtered brightness (-m) */
    float *out;               /* nrows x ncols RGB */
} pf;

/* Radiance 6.1's bright() (hd_rgb_bright_rad): pfilt's exposure and its
 * -m filter decisions depend on its factors */
static double brt(const pf *p, const float *c)
{
    return p->xyz ? c[1] : hd_rgb_bright_rad(c);
}

static float lookgauss(const pf *p, double x)
{
    int i = (int)(20. * x + .5);
    return p->gauss[i < PF_GTAB ? i : PF_GTAB - 1];
}

/* cosine from a table of 1024 entries per quadrant (nearest entry), the
 * approximation Radiance's star slopes are computed with */
static double tab_cos(double x)
{
    static double tab[1025];
    if (tab[0] < .5)
        for (int i = 0; i <= 1024; i++) tab[i] = cos((M_PI / 2. / 1024) * i);
    if (x < 0) x = -x;
    int i = (int)((1024 * 2. / M_PI) * x + .5);
    while (i >= 4 * 1024) i -= 4 * 1024;
    switch (i / 1024) {
    case 0: return tab[i];
    case 1: return -tab[2048 - i];
    case 2: return -tab[i - 2048];
    default: return tab[4096 - i];
    }
}

static void box(const pf *p, float sum[3], int xcent, int ycent, int c, int r)
{
    int n = 0;
    sum[0] = sum[1] = sum[2] = 0;
    for (int y = ycent + 1 - p->ybrad; y <= ycent + p->ybrad; y++) {
        if (y < 0) continue;
        if (y >= p->yres) break;
        /* fused multiply-subtract, as Radiance's build computes it (the
         * rounding decides the pixels on a box's edge, e.g. -x /12) */
        double d = p->y_r < 1.0 ? fma(p->y_r, y, -(r + .5)) : (double)(y - ycent);
        if (d < -0.5) continue;
        if (d >= 0.5) break;
        const float *row = p->in + (size_t)y * p->xres * 3;
        for (int x = xcent + 1 - p->xbrad; x <= xcent + p->xbrad; x++) {
            int off = x < 0 ? p->xres : x >= p->xres ? -p->xres : 0;
            if (off && !p->wrap) continue;
            d = p->x_c < 1.0 ? fma(p->x_c, x, -(c + .5)) : (double)(x - xcent);
            if (d < -0.5) continue;
            if (d >= 0.5) break;
            n++;
            const float *px = row + (size_t)(x + off) * 3;
            sum[0] += px[0]; sum[1] += px[1]; sum[2] += px[2];
        }
    }
    if (n > 1) {
        double w = 1.0 / n;
        sum[0] = (float)(sum[0] * w); sum[1] = (float)(sum[1] * w); sum[2] = (float)(sum[2] * w);
    }
}

static void gaussf(const pf *p, float sum[3], int xcent, int ycent, int c, int r)
{
    double wsum = PF_FTINY;
    sum[0] = sum[1] = sum[2] = 0;
    for (int y = ycent - p->yrad; y <= ycent + p->yrad; y++) {
        if (y < 0) continue;
        if (y >= p->yres) break;
        double dy = (p->y_r * (y + .5) - (r + .5)) / p->rad;
        const float *row = p->in + (size_t)y * p->xres * 3;
        for (int x = xcent - p->xrad; x <= xcent + p->xrad; x++) {
            int off = x < 0 ? p->xres : x >= p->xres ? -p->xres : 0;
            if (off && !p->wrap) continue;
            double dx = (p->x_c * (x + .5) - (c + .5)) / p->rad;
            double w = lookgauss(p, dx * dx + dy * dy);
            wsum += w;
            const float *px = row + (size_t)(x + off) * 3;
            for (int k = 0; k < 3; k++) sum[k] += (float)(px[k] * w);
        }
    }
    double w = 1.0 / wsum;
    for (int k = 0; k < 3; k++) sum[k] = (float)(sum[k] * w);
}

/* the spread factor m for an input pixel of brightness p0 (-m) */
static double pick_m(const pf *p, double p0)
{
    double m = 1.0, lim[2] = {1.0, p->orad / p->rad / PF_CHECKRAD};
    int iter = (int)(4.0 / PF_TEPS);
    do {
        int i = (int)(PF_RSCA * PF_CHECKRAD * p->rad * m + .5);
        if (i > p->orad) i = p->orad;
        double avg = 0, wsum = 0;
        while (i--) {
            double t = (i + .5) / (m * p->rad);
            t = lookgauss(p, t * t);
            avg += t * p->ringsum[i];
            wsum += t * p->ringwt[i];
        }
        if (avg < 1e-20) return 1.0;
        avg /= wsum;
        double denom = m * m / p->gauss[0] - p0 / avg;
        if (denom <= PF_FTINY) {
            if (m >= lim[1] - PF_REPS) break;
            m = lim[1];
            continue;
        }
        double num = fabs(p0 / avg - 1.0);
        double t = num / denom;
        if (t <= p->thresh) {
            if (m <= lim[0] + PF_REPS || (p->thresh - t) / p->thresh <= PF_TEPS) break;
        } else {
            if (m >= lim[1] - PF_REPS || (t - p->thresh) / p->thresh <= PF_TEPS) break;
        }
        double prev = m;
        m = sqrt(p->gauss[0] * (num / p->thresh + p0 / avg));
        if (m < prev) {
            if (m <= lim[0] + PF_FTINY) m = 0.5 * (lim[0] + prev);
            lim[1] = prev;
        } else {
            if (m >= lim[1] - PF_FTINY) m = 0.5 * (lim[1] + prev);
            lim[0] = prev;
        }
    } while (--iter > 0);
    return m;
}

/* spread input pixel (px, py) over the output around (rc, cc) with factor m */
static void spread_px(pf *p, int px, int py, int rc, int cc, double m)
{
    int off = px < 0 ? p->xres : px >= p->xres ? -p->xres : 0;
    const float *v = p->in + ((size_t)py * p->xres + (size_t)(px + off)) * 3;
    float val[3] = {v[0], v[1], v[2]};
    double pc = p->x_c * (px + .5), pr = p->y_r * (py + .5);
    int ks = (int)(PF_CHECKRAD * m * p->rad + 1);
    if (ks > p->orad) ks = p->orad;
    double norm = 0;
    int i = 0;
    for (int r = rc - ks; r <= rc + ks; r++) {
        if (r < 0) continue;
        if (r >= p->nrows) break;
        double dy2 = (pr - (r + .5)) / (m * p->rad);
        dy2 *= dy2;
        for (int c = cc - ks; c <= cc + ks; c++) {
            if (!p->wrap) {
                if (c < 0) continue;
                if (c >= p->ncols) break;
            }
            double dx = (pc - (c + .5)) / (m * p->rad);
            norm += p->warr[i++] = lookgauss(p, dx * dx + dy2);
        }
    }
    norm = 1.0 / norm;
    if (p->x_c < 1.0) norm *= p->x_c;
    if (p->y_r < 1.0) norm *= p->y_r;
    i = 0;
    for (int r = rc - ks; r <= rc + ks; r++) {
        if (r < 0) continue;
        if (r >= p->nrows) break;
        float *row = p->out + (size_t)r * p->ncols * 3;
        for (int c = cc - ks; c <= cc + ks; c++) {
            int o = c < 0 ? p->ncols : c >= p->ncols ? -p->ncols : 0;
            if (o && !p->wrap) continue;
            /* the weight is rounded to float and the product taken in
             * float, as Radiance's scalescolor() does: pf07_m's sun pixel
             * lands one float ulp from an RGBE mantissa step otherwise */
            float w = (float)(norm * p->warr[i++]);
            float *d = row + (size_t)(c + o) * 3;
            for (int k = 0; k < 3; k++) d[k] += val[k] * w;
        }
    }
}

static void thresh_px(pf *p, int xcent, int ycent, int cc, int rc)
{
    memset(p->ringsum, 0, (size_t)(p->orad + 1) * sizeof *p->ringsum);
    memset(p->ringwt, 0, (size_t)(p->orad + 1) * sizeof *p->ringwt);
    for (int r = -p->orad; r <= p->orad; r++) {
        if (rc + r < 0) continue;
        if (rc + r >= p->nrows) break;
        const float *g = p->grey + (size_t)(rc + r) * p->ncols;
        for (int c = -p->orad; c <= p->orad; c++) {
            int o = cc + c < 0 ? p->ncols : cc + c >= p->ncols ? -p->ncols : 0;
            if (o && !p->wrap) continue;
            int x = p->ringndx[c * c + r * r];
            if (x < 0) continue;
            p->ringsum[x] += g[cc + c + o];
            p->ringwt[x]++;
        }
    }
    for (int y = ycent + 1 - p->ybrad; y <= ycent + p->ybrad; y++) {
        if (y < 0) continue;
        if (y >= p->yres) break;
        double d = p->y_r < 1.0 ? p->y_r * y - (rc + .5) : (double)(y - ycent);
        if (d < -0.5) continue;
        if (d >= 0.5) break;
        for (int x = xcent + 1 - p->xbrad; x <= xcent + p->xbrad; x++) {
            int o = x < 0 ? p->xres : x >= p->xres ? -p->xres : 0;
            if (o && !p->wrap) continue;
            d = p->x_c < 1.0 ? p->x_c * x - (cc + .5) : (double)(x - xcent);
            if (d < -0.5) continue;
            if (d >= 0.5) break;
            const float *v = p->in + ((size_t)y * p->xres + (size_t)(x + o)) * 3;
            spread_px(p, x, y, rc, cc, pick_m(p, brt(p, v)));
        }
    }
}

static hd_status init_mask(pf *p)
{
    double d = p->x_c * p->y_r * 0.25 / (p->rad * p->rad);
    p->gauss[0] = (float)exp(-d);
    for (int x = 1; x < PF_GTAB; x++) p->gauss[x] = x * 0.05 <= d ? p->gauss[0] : (float)exp(-x * 0.05);
    if (p->thresh <= PF_FTINY) return HD_OK;
    double n = M_PI * d * exp(-d);                   /* the plateau */
    for (d = sqrt(d) + 0.05; d <= PF_RSCA * PF_CHECKRAD; d += 0.1) n += 0.1 * 2.0 * M_PI * d * exp(-d * d);
    n = p->x_c * p->y_r / (p->rad * p->rad * n);
    for (int x = 0; x < PF_GTAB; x++) p->gauss[x] = (float)(p->gauss[x] * n);
    int o2 = p->orad * p->orad;
    p->ringndx = hd_malloc_array((size_t)(2 * o2 + 1), sizeof *p->ringndx);
    p->ringsum = hd_malloc_array((size_t)p->orad + 1, sizeof *p->ringsum);
    p->ringwt = hd_malloc_array((size_t)p->orad + 1, sizeof *p->ringwt);
    int ob = 2 * p->orad + 1;
    p->warr = hd_malloc_array((size_t)ob * ob, sizeof *p->warr);
    if (!p->ringndx || !p->ringsum || !p->ringwt || !p->warr) return HD_ERR_NOMEM;
    for (int x = 0; x <= 2 * o2; x++) p->ringndx[x] = x > o2 ? -1 : (short)sqrt((double)x);
    return HD_OK;
}

typedef struct hot { float val[3]; short x, y; float slope; } hot;

hd_status hd_pfilt(const hd_picture *in, const hd_pfilt_opts *o, int cmd_argc, char **cmd_argv, FILE *fp)
{
    pf p;
    memset(&p, 0, sizeof p);
    p.xres = in->xres;
    p.yres = in->yres;
    p.xyz = in->fmt == HD_PIC_XYZE;
    double inpaspect = 1.0, hotlvl = o->hotlvl;
    for (const char *l = in->hdr.text; l && *l;) {
        if (!strncmp(l, "PIXASPECT=", 10)) inpaspect *= atof(l + 10);
        else if (!strncmp(l, "EXPOSURE=", 9)) hotlvl *= atof(l + 9);
        const char *nl = strchr(l, '\n');
        l = nl ? nl + 1 : l + strlen(l);
    }
    hd_view v;
    int gotview = 0;
    if (hd_view_from_header(&v, &in->hdr, &gotview) == HD_OK && gotview)
        p.wrap = v.type == 'c' && v.vh >= 360. - PF_FTINY;
    int ncols = o->ncols > 0 ? o->ncols : (int)(o->xratio * p.xres + .5);
    int nrows = o->nrows > 0 ? o->nrows : (int)(o->yratio * p.yres + .5);
    if (o->outaspect > .01) {
        double d = inpaspect * p.yres / p.xres / o->outaspect;
        if (d * ncols > nrows) ncols = (int)(nrows / d);
        else nrows = (int)(ncols * d);
    }
    if (ncols <= 0 || nrows <= 0 || ncols > HD_PIC_MAXSIDE || nrows > HD_PIC_MAXSIDE ||
        (int64_t)ncols * nrows > HD_PIC_MAXPIXELS)
        return hd_fail(HD_ERR_RANGE, "pfilt: bad output size %d x %d", ncols, nrows);
    p.ncols = ncols;
    p.nrows = nrows;
    p.x_c = (double)ncols / p.xres;
    p.y_r = (double)nrows / p.yres;
    size_t npx = (size_t)p.xres * p.yres;
    p.in = hd_malloc_array(npx * 3, sizeof *p.in);
    if (!p.in) return HD_ERR_NOMEM;
    memcpy(p.in, in->pix, npx * 3 * sizeof *p.in);

    /* pass 1: mean brightness below the hot level, hot pixels for stars */
    float expo[3] = {(float)o->exposure[0], (float)o->exposure[1], (float)o->exposure[2]};
    double avgbrt = 0;
    long npix = 0;
    hot *hots = NULL;
    size_t nhot = 0, caphot = 0;
    hd_status st = HD_OK;
    if (o->singlepass) {
        avgbrt = PF_AVGLVL;
        npix = 1;
    } else {
        for (int y = 0; y < p.yres && !st; y++)
            for (int x = 0; x < p.xres; x++) {
                const float *c = p.in + ((size_t)y * p.xres + x) * 3;
                double b = brt(&p, c);
                if (b <= 0) continue;
                if (o->avghot || b < hotlvl) { avgbrt += b; npix++; }
                if (o->npts && b >= hotlvl) {
                    if (nhot == caphot) {
                        size_t nc = caphot ? 2 * caphot : 64;
                        hot *h = hd_realloc_array(hots, nc, sizeof *h);
                        if (!h) { st = HD_ERR_NOMEM; break; }
                        hots = h;
                        caphot = nc;
                    }
                    hot *h = &hots[nhot++];
                    memcpy(h->val, c, sizeof h->val);
                    h->x = (short)x;
                    h->y = (short)y;
                    long k = (long)((lrand48() * (long long)o->npts) >> 31);
                    double a = M_PI * (0.5 - (k + 0.5) / o->npts);
                    h->slope = (float)(tab_cos(a - M_PI / 2.) / tab_cos(a));
                }
            }
        if (!st && !npix) st = hd_fail(HD_ERR_RANGE, "pfilt: picture too dark or too bright");
    }
    if (st) { free(hots); free(p.in); return st; }
    avgbrt /= (double)npix;
    for (int k = 0; k < 3; k++) expo[k] = (float)(expo[k] * (PF_AVGLVL / avgbrt));
    double expbrt = hd_rgb_bright_rad(expo);
    double sprd = o->spread / (hotlvl * expbrt) * ((double)p.xres * p.xres + (double)p.yres * p.yres) / 4.0;
    /* stars (the last hot pixel found is applied first) and exposure */
    for (int y = 0; y < p.yres; y++) {
        float *row = p.in + (size_t)y * p.xres * 3;
        for (size_t h = nhot; h-- > 0;) {
            const hot *hp = &hots[h];
            int xmin, xmax;
            if (hp->slope > PF_FTINY) {
                xmin = (int)((y - hp->y - 0.5) / hp->slope + hp->x);
                xmax = (int)((y - hp->y + 0.5) / hp->slope + hp->x);
            } else if (hp->slope < -PF_FTINY) {
                xmin = (int)((y - hp->y + 0.5) / hp->slope + hp->x);
                xmax = (int)((y - hp->y - 0.5) / hp->slope + hp->x);
            } else if (y == hp->y) {
                xmin = 0; xmax = p.xres - 1;
            } else {
                xmin = 1; xmax = 0;
            }
            if (xmin < 0) xmin = 0;
            if (xmax >= p.xres) xmax = p.xres - 1;
            for (int x = xmin; x <= xmax; x++) {
                double d2 = (double)(x - hp->x) * (x - hp->x) + (double)(y - hp->y) * (y - hp->y);
                float *c = row + (size_t)x * 3;
                if (d2 > sprd) {
                    d2 = sprd / d2;
                    if (d2 < PF_FTINY) continue;
                    for (int k = 0; k < 3; k++) c[k] += (float)(hp->val[k] * d2);
                } else if (d2 > PF_FTINY) {
                    for (int k = 0; k < 3; k++) c[k] += hp->val[k];
                }
            }
        }
        for (int x = 0; x < p.xres; x++)
            for (int k = 0; k < 3; k++) row[x * 3 + k] *= expo[k];
    }
    free(hots);

    /* filter set-up */
    p.xbrad = p.xres / p.ncols / 2 + 1;
    p.ybrad = p.yres / p.nrows / 2 + 1;
    p.rad = o->rad;
    p.thresh = o->thresh;
    if (p.thresh > PF_FTINY && p.rad <= PF_FTINY) p.rad = 0.6;
    if (p.rad > PF_FTINY) {
        if (p.nrows >= p.yres && p.ncols >= p.xres) p.rad *= (p.y_r + p.x_c) / 2.0;
        if (p.thresh > PF_FTINY) {
            p.orad = (int)(PF_CHECKRAD * PF_THRESHRAD * p.rad + 1);
            p.xrad = (int)(p.orad / p.x_c + p.xbrad);
            p.yrad = (int)(p.orad / p.y_r + p.ybrad);
        } else {
            p.xrad = (int)(PF_CHECKRAD * p.rad / p.x_c + 1);
            p.yrad = (int)(PF_CHECKRAD * p.rad / p.y_r + 1);
        }
        st = init_mask(&p);
    } else {
        p.xrad = p.xbrad;
        p.yrad = p.ybrad;
    }
    size_t nout = (size_t)p.ncols * p.nrows;
    if (!st && !(p.out = calloc(nout * 3, sizeof *p.out))) st = HD_ERR_NOMEM;
    if (!st && p.thresh > PF_FTINY) {
        if (!(p.grey = hd_malloc_array(nout, sizeof *p.grey))) st = HD_ERR_NOMEM;
        for (int r = 0; r < p.nrows && !st; r++) {
            int yb = (int)((r + .5) * p.yres / p.nrows);
            for (int c = 0; c < p.ncols; c++) {
                float t[3];
                box(&p, t, (int)((c + .5) * p.xres / p.ncols), yb, c, r);
                p.grey[(size_t)r * p.ncols + c] = (float)brt(&p, t);
            }
        }
    }
    /* pass 2 */
    for (int r = 0; r < p.nrows && !st; r++) {
        int ycent = (int)((r + .5) * p.yres / p.nrows);
        for (int c = 0; c < p.ncols; c++) {
            int xcent = (int)((c + .5) * p.xres / p.ncols);
            float *d = p.out + ((size_t)r * p.ncols + c) * 3;
            if (p.thresh > PF_FTINY) thresh_px(&p, xcent, ycent, c, r);
            else if (p.rad > PF_FTINY) gaussf(&p, d, xcent, ycent, c, r);
            else box(&p, d, xcent, ycent, c, r);
        }
    }
    /* header: input lines, command, aspect, exposure, colour correction */
    hd_header h;
    hd_header_init(&h);
    if (!st) st = hd_header_copy(&h, &in->hdr);
    if (!st && cmd_argc > 0) st = hd_header_add_command(&h, cmd_argc, cmd_argv);
    if (!st && !o->correctaspect) {
        double a = p.x_c / p.y_r;
        if (a < 0.995 || a > 1.005) st = hd_header_appendf(&h, "PIXASPECT=%f", a);
    }
    double eb = hd_rgb_bright_rad(expo);
    if (!st && !(eb >= .98 && eb <= 1.02)) st = hd_header_appendf(&h, "EXPOSURE=%.4e", eb);
    if (!st) {
        float cc[3];
        for (int k = 0; k < 3; k++) cc[k] = (float)(expo[k] * (1.0 / eb));
#define PF_FEQ(a, b) ((a) >= .98 * (b) && (a) <= 1.02 * (b))
        if (!PF_FEQ(cc[0], cc[1]) || !PF_FEQ(cc[1], cc[2]))
            st = hd_header_appendf(&h, "COLORCORR= %f %f %f", cc[0], cc[1], cc[2]);
#undef PF_FEQ
    }
    if (!st) {
        hd_picture op;
        hd_picture_init(&op);
        op.xres = p.ncols;
        op.yres = p.nrows;
        op.pix = p.out;
        op.fmt = in->fmt;
        st = hd_picture_write(fp, &op, &h, HD_RES_STANDARD);
    }
    hd_header_free(&h);
    free(p.in); free(p.out); free(p.grey);
    free(p.ringndx); free(p.ringsum); free(p.ringwt); free(p.warr);
    return st;
}

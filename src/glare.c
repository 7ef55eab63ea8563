/* heliodon — glare evaluation of 180-degree fisheye images (evalglare
 * compatible).  See include/heliodon/glare.h and docs/design/glare.md. */
#include "heliodon/glare.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/picture.h"
#include "heliodon/view.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEG (180.0 / HD_PI)

/* ------------------------------------------------------------------ views */

hd_status hd_glare_view_check(const hd_glare_view *v)
{
    if (v->type != 'a' && v->type != 'h') {
        static const char *names[] = {"v", "perspective", "l", "parallel", "s", "planisphere (stereographic)",
                                      "c", "cylindrical"};
        const char *nm = "unknown";
        for (int k = 0; k < 8; k += 2)
            if (v->type == names[k][0]) nm = names[k + 1];
        return hd_fail(HD_ERR_UNSUPPORTED,
                       "view type -vt%c (%s) is not a fisheye view: glare evaluation needs a 180-degree "
                       "angular (-vta) or hemispherical (-vth) fisheye image",
                       v->type, nm);
    }
    hd_view w = *v;   /* direction, up vector and angles as hd_view_setup checks them */
    hd_status st = hd_view_setup(&w);
    if (st) return st;
    if (fabs(v->vh - 180) > 1e-6 || fabs(v->vv - 180) > 1e-6)
        hd_warn("view angles -vh %g -vv %g: glare evaluation expects a 180-degree fisheye", v->vh, v->vv);
    return HD_OK;
}

int hd_glare_view_format(char *buf, size_t cap, const hd_glare_view *v)
{
    return snprintf(buf, cap,
                    "-vt%c -vp %.7g %.7g %.7g -vd %.7g %.7g %.7g -vu %.7g %.7g %.7g -vh %.7g -vv %.7g "
                    "-vo %.7g -va %.7g -vs %.7g -vl %.7g",
                    v->type, v->vp.x, v->vp.y, v->vp.z, v->vd.x, v->vd.y, v->vd.z, v->vu.x, v->vu.y, v->vu.z,
                    v->vh, v->vv, v->vo, v->va, v->vs, v->vl);
}

/* v in its own frame (right, forward, up = x, y, z), set up for
 * hd_view_ray: the geometry's rays are those of the view in that frame. */
static hd_status frame_view(const hd_glare_view *v, hd_view *f)
{
    *f = *v;
    f->vp = hd_v3(0, 0, 0);
    f->vd = hd_v3(0, 1, 0);
    f->vu = hd_v3(0, 0, 1);
    return hd_view_setup(f);
}

/* Ray of frame view f (frame_view) for location (lx, ly).  Returns 1 if
 * valid; invalid locations are projected onto the rim (clamp != 0), the
 * direction there is that of the fisheye's edge (perpendicular to the view
 * direction for -vth, straight back for -vta), so that corner rays always
 * exist. */
static int frame_ray(const hd_view *f, double lx, double ly, double out[3], int clamp)
{
    hd_vec3 o, d;
    if (hd_view_ray(f, lx, ly, &o, &d) < 0) {
        if (!clamp) return 0;
        double u = (lx + f->vs - 0.5) * hd_vlen(f->hvec), w = (ly + f->vl - 0.5) * hd_vlen(f->vvec);
        double l = sqrt(u * u + w * w), s = f->type == 'h' ? 1 : sin(HD_PI);
        out[0] = s * (u / l);
        out[1] = f->type == 'h' ? 0 : -1;
        out[2] = s * (w / l);
        return 0;
    }
    out[0] = d.x;
    out[1] = d.y;
    out[2] = d.z;
    return 1;
}

hd_status hd_glare_picture_lum(const hd_picture *p, float **out)
{
    *out = NULL;
    double ex = hd_header_exposure(&p->hdr);
    if (!(ex > 0) || !isfinite(ex)) return hd_fail(HD_ERR_FORMAT, "invalid EXPOSURE %g in the picture header", ex);
    size_t np = (size_t)p->xres * p->yres;
    float *lum = hd_malloc_array(np ? np : 1, sizeof(float));
    if (!lum) return HD_ERR_NOMEM;
    for (size_t k = 0; k < np; k++) {
        const float *c = p->pix + 3 * k;
        double L = p->fmt == HD_PIC_XYZE ? 179.0 * c[1] : hd_glare_luminance(c);
        lum[k] = (float)(L / ex);
    }
    *out = lum;
    return HD_OK;
}

/* --------------------------------------------------------------- geometry */

struct hd_glare_geom {
    int xres, yres;
    hd_view view;     /* in its own frame (frame_view) */
    float *dir;       /* 3 per pixel, view frame */
    double *omega;    /* 0 outside the field */
    double *cosv;     /* forward component, 0 outside */
    double *posidx;   /* position index of the pixel direction, 0 outside */
    unsigned char *valid;
    double minstep;   /* smallest angle between 4-neighbour pixel centres */
    long nvalid;
};

static double tri_solid_angle(const double *a, const double *b, const double *c)
{
    double bc[3] = {b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2], b[0] * c[1] - b[1] * c[0]};
    double num = a[0] * bc[0] + a[1] * bc[1] + a[2] * bc[2];
    double den = 1.0 + (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) + (b[0] * c[0] + b[1] * c[1] + b[2] * c[2]) +
                 (c[0] * a[0] + c[1] * a[1] + c[2] * a[2]);
    return fabs(2.0 * atan2(num, den));
}

hd_status hd_glare_geom_new(hd_glare_geom **out, const hd_glare_view *v, int xres, int yres)
{
    *out = NULL;
    hd_status st = hd_glare_view_check(v);
    if (st) return st;
    if (xres < 2 || yres < 2 || xres > 65536 || yres > 65536 || (int64_t)xres * yres > ((int64_t)1 << 28))
        return hd_fail(HD_ERR_RANGE, "image size %d x %d out of range for glare evaluation (2..65536 per side, "
                                     "at most 2^28 pixels)", xres, yres);
    hd_glare_geom *g = hd_calloc(1, sizeof *g);
    if (!g) return HD_ERR_NOMEM;
    if ((st = frame_view(v, &g->view))) {
        free(g);
        return st;
    }
    size_t np = (size_t)xres * yres, nc = (size_t)(xres + 1) * (yres + 1);
    g->xres = xres;
    g->yres = yres;
    g->dir = hd_malloc_array(np * 3, sizeof(float));
    g->omega = hd_calloc(np, sizeof(double));
    g->cosv = hd_calloc(np, sizeof(double));
    g->valid = hd_calloc(np, 1);
    g->posidx = hd_calloc(np, sizeof(double));
    double *corner = hd_malloc_array(nc * 3, sizeof(double));
    if (!g->dir || !g->omega || !g->cosv || !g->valid || !g->posidx || !corner) {
        free(corner);
        hd_glare_geom_free(g);
        return HD_ERR_NOMEM;
    }
    /* corner j (from the bottom), i (from the left) */
    for (int j = 0; j <= yres; j++)
        for (int i = 0; i <= xres; i++)
            frame_ray(&g->view, (double)i / xres, (double)j / yres, corner + 3 * ((size_t)j * (xres + 1) + i), 1);
    for (int row = 0; row < yres; row++) {
        int yb = yres - 1 - row;
        for (int x = 0; x < xres; x++) {
            size_t k = (size_t)row * xres + x;
            double d[3];
            int ok = frame_ray(&g->view, (x + 0.5) / xres, (yb + 0.5) / yres, d, 0);
            g->dir[3 * k] = (float)d[0];
            g->dir[3 * k + 1] = (float)d[1];
            g->dir[3 * k + 2] = (float)d[2];
            if (!ok || d[1] <= 0) {
                if (!ok) g->dir[3 * k] = g->dir[3 * k + 1] = g->dir[3 * k + 2] = 0;
                continue;
            }
            const double *c00 = corner + 3 * ((size_t)yb * (xres + 1) + x);
            const double *c10 = c00 + 3;
            const double *c01 = corner + 3 * ((size_t)(yb + 1) * (xres + 1) + x);
            const double *c11 = c01 + 3;
            g->omega[k] = tri_solid_angle(c00, c10, c11) + tri_solid_angle(c00, c11, c01);
            g->cosv[k] = d[1];
            g->posidx[k] = hd_glare_posidx(d);
            g->valid[k] = 1;
            g->nvalid++;
        }
    }
    free(corner);
    /* smallest neighbour step (for the search window of source merging) */
    double mins = HD_PI;
    for (int row = 0; row < yres; row++)
        for (int x = 0; x < xres; x++) {
            size_t k = (size_t)row * xres + x;
            if (!g->valid[k]) continue;
            const float *a = g->dir + 3 * k;
            for (int nb = 0; nb < 2; nb++) {   /* the right and the lower neighbour */
                size_t k2 = nb ? k + (size_t)xres : k + 1;
                if ((nb ? row + 1 >= yres : x + 1 >= xres) || !g->valid[k2]) continue;
                const float *b = g->dir + 3 * k2;
                double c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
                double s = acos(c > 1 ? 1 : c);
                if (s > 0 && s < mins) mins = s;
            }
        }
    g->minstep = mins;
    *out = g;
    return HD_OK;
}

void hd_glare_geom_free(hd_glare_geom *g)
{
    if (!g) return;
    free(g->dir);
    free(g->omega);
    free(g->cosv);
    free(g->posidx);
    free(g->valid);
    free(g);
}

double hd_glare_geom_omega(const hd_glare_geom *g, int x, int row)
{
    if (x < 0 || row < 0 || x >= g->xres || row >= g->yres) return 0;
    return g->omega[(size_t)row * g->xres + x];
}

double hd_glare_geom_cos(const hd_glare_geom *g, int x, int row)
{
    if (x < 0 || row < 0 || x >= g->xres || row >= g->yres) return 0;
    return g->cosv[(size_t)row * g->xres + x];
}

double hd_glare_luminance(const float rgb[3])
{
    return 179.0 * (0.265074126 * rgb[0] + 0.670114631 * rgb[1] + 0.064811243 * rgb[2]);
}

double hd_glare_ev_lum(const hd_glare_geom *g, const float *lum)
{
    double e = 0;
    size_t np = (size_t)g->xres * g->yres;
    for (size_t k = 0; k < np; k++)
        if (g->valid[k]) e += lum[k] * g->omega[k] * g->cosv[k];
    return e;
}

/* ------------------------------------------------------------ options */

void hd_glare_opts_default(hd_glare_opts *o)
{
    memset(o, 0, sizeof *o);
    o->threshold = 2000;
    o->search_radius = 0.2;
    o->peak_extract = 1;
    o->peak_value = 50000;
    o->bg_mode = 0;
    o->c1 = 5.87e-5;
    o->c2 = 0.092;
    o->c3 = 0.159;
    o->a1 = 2;
    o->a2 = 1;
    o->a3 = 1.87;
    o->a4 = 2;
}

void hd_glare_result_free(hd_glare_result *r)
{
    if (!r) return;
    free(r->sources);
    free(r->source_map);
    r->sources = NULL;
    r->source_map = NULL;
    r->nsources = 0;
}

/* --------------------------------------------------------- position index */

double hd_glare_posidx(const double dir[3])
{
    double r = dir[0], f = dir[1], u = dir[2];
    double n = sqrt(r * r + f * f + u * u);
    if (n <= 0) return 16;
    r /= n; f /= n; u /= n;
    double sigma = acos(f > 1 ? 1 : f < -1 ? -1 : f) * DEG;
    double ru = sqrt(r * r + u * u);
    double tau = ru > 0 ? acos(u / ru > 1 ? 1 : u / ru < -1 ? -1 : u / ru) * DEG : 0;
    double p;
    if (u >= 0) {
        /* Guth, above (or on) the line of sight */
        p = exp((35.2 - 0.31889 * tau - 1.22 * exp(-2.0 * tau / 9.0)) * 1e-3 * sigma +
                (21.0 + 0.26667 * tau - 0.002963 * tau * tau) * 1e-5 * sigma * sigma);
    } else {
        /* Iwata (CIE 2010, Kikuchi's conversion), below the line of sight */
        double ct = cos(tau / DEG);
        double beta = atan(tan(sigma / DEG) * sqrt(1.0 + 0.3225 * ct * ct)) * DEG;
        if (sigma >= 90) beta = 90;
        p = exp(6.49e-3 * beta + 21e-5 * beta * beta);
    }
    if (!(p <= 16)) p = 16;
    if (p < 1) p = 1;
    return p;
}

/* ------------------------------------------------------ source clustering */

static void uf_union(int *par, int a, int b)
{
    a = hd_uf_find(par, a);
    b = hd_uf_find(par, b);
    if (a == b) return;
    if (a < b) par[b] = a;
    else par[a] = b;
}

/* A masked pixel at the picture's edge or beside an unmasked 4-neighbour. */
static int on_boundary(const unsigned char *mask, int x, int row, int xr, int yr)
{
    int k = row * xr + x;
    return x == 0 || row == 0 || x == xr - 1 || row == yr - 1 || !mask[k - 1] || !mask[k + 1] || !mask[k - xr] ||
           !mask[k + xr];
}

typedef struct { int cell, root, k; } bkey_t;

static int bkey_cmp(const void *pa, const void *pb)
{
    const bkey_t *a = pa, *b = pb;
    if (a->cell != b->cell) return a->cell < b->cell ? -1 : 1;
    if (a->root != b->root) return a->root < b->root ? -1 : 1;
    return (a->k > b->k) - (a->k < b->k);
}

/* Single-linkage clustering of the pixels with mask[k] set: two pixels are
 * linked when the angle between their directions is below radius.  par[k]
 * is set for masked pixels (the root is the smallest linked index). */
static hd_status cluster(const hd_glare_geom *g, const unsigned char *mask, double radius, int *par)
{
    int xr = g->xres, yr = g->yres;
    size_t np = (size_t)xr * yr;
    double cr = cos(radius);
    const float *D = g->dir;
#define DOTK(a, b) ((double)D[3 * (a)] * D[3 * (b)] + (double)D[3 * (a) + 1] * D[3 * (b) + 1] + \
                    (double)D[3 * (a) + 2] * D[3 * (b) + 2])
    for (size_t k = 0; k < np; k++) par[k] = mask[k] ? (int)k : -1;
    /* immediate neighbours */
    for (int row = 0; row < yr; row++)
        for (int x = 0; x < xr; x++) {
            int k = row * xr + x;
            if (!mask[k]) continue;
            static const int nb[4][2] = {{1, 0}, {-1, 1}, {0, 1}, {1, 1}};
            for (int t = 0; t < 4; t++) {
                int xx = x + nb[t][0], yy = row + nb[t][1];
                if (xx < 0 || xx >= xr || yy >= yr) continue;
                int q = yy * xr + xx;
                if (mask[q] && DOTK(k, q) >= cr) uf_union(par, k, q);
            }
        }
    /* boundary pixels, bucketed on a grid of cells at least radius wide */
    int K = (int)ceil(radius / (g->minstep > 0 ? g->minstep : 1e-3)) + 1;
    if (K < 1) K = 1;
    if (K > xr) K = xr;
    int gx = (xr + K - 1) / K, gy = (yr + K - 1) / K;
    size_t nb = 0;
    for (int row = 0; row < yr; row++)
        for (int x = 0; x < xr; x++) {
            int k = row * xr + x;
            if (!mask[k]) continue;
            if (on_boundary(mask, x, row, xr, yr))
                nb++;
        }
    if (nb == 0) return HD_OK;
    /* each boundary pixel keyed by (cell, root after the neighbour unions, index): within a cell the
     * pixels of one component form a run, and a run whose component is already the pixel's is skipped
     * whole (its root refreshed lazily: unions only merge, so an equal root, stale or not, means linked) */
    bkey_t *key = hd_malloc_array(nb, sizeof(bkey_t));
    int *cellrun = hd_calloc((size_t)gx * gy + 1, sizeof(int));
    int *runbeg = hd_malloc_array(nb + 1, sizeof(int));
    int *runroot = hd_malloc_array(nb, sizeof(int));
    if (!key || !cellrun || !runbeg || !runroot) {
        free(key); free(cellrun); free(runbeg); free(runroot);
        return HD_ERR_NOMEM;
    }
    nb = 0;
    for (int row = 0; row < yr; row++)
        for (int x = 0; x < xr; x++) {
            int k = row * xr + x;
            if (!mask[k]) continue;
            if (on_boundary(mask, x, row, xr, yr))
                key[nb++] = (bkey_t){(row / K) * gx + x / K, hd_uf_find(par, k), k};
        }
    qsort(key, nb, sizeof(bkey_t), bkey_cmp);
    int nrun = 0;
    for (size_t t = 0; t < nb; t++)
        if (t == 0 || key[t].cell != key[t - 1].cell || key[t].root != key[t - 1].root) {
            runbeg[nrun] = (int)t;
            runroot[nrun] = key[t].root;
            cellrun[key[t].cell + 1] = ++nrun;
        }
    runbeg[nrun] = (int)nb;
    for (int c = 0; c < gx * gy; c++)   /* cells without runs end where the previous one did */
        if (cellrun[c + 1] < cellrun[c]) cellrun[c + 1] = cellrun[c];
    /* every unordered pair of boundary pixels in neighbouring cells is either tested or known linked */
    for (size_t t = 0; t < nb; t++) {
        int k = key[t].k, cx = (k % xr) / K, cy = (k / xr) / K;
        int rk = hd_uf_find(par, k);
        for (int ey = cy - 1; ey <= cy + 1; ey++) {
            if (ey < 0 || ey >= gy) continue;
            for (int ex = cx - 1; ex <= cx + 1; ex++) {
                if (ex < 0 || ex >= gx) continue;
                int c = ey * gx + ex;
                for (int run = cellrun[c]; run < cellrun[c + 1]; run++) {
                    int rr = runroot[run];
                    if (rr != rk) runroot[run] = rr = hd_uf_find(par, rr);
                    if (rr == rk) continue;
                    for (int s = runbeg[run]; s < runbeg[run + 1]; s++) {
                        int q = key[s].k;
                        if (q <= k) continue;
                        if (DOTK(k, q) >= cr) {
                            uf_union(par, k, q);
                            runroot[run] = rk = hd_uf_find(par, k);
                            break;
                        }
                    }
                }
            }
        }
    }
#undef DOTK
    free(key);
    free(cellrun);
    free(runbeg);
    free(runroot);
    return HD_OK;
}

/* ------------------------------------------------------------ evaluation */

typedef struct acc_t {
    double npix, om, lom, x, y, w, eg, lmax;
    int first;   /* scan position of the first pixel (for numbering) */
} acc_t;

/* k-th smallest (0-based) of v[0..n-1], partially reordering v. */
static double select_kth(double *v, size_t n, size_t k)
{
    size_t lo = 0, hi = n - 1;
    while (lo < hi) {
        double pv = v[lo + (hi - lo) / 2];
        size_t i = lo, j = hi;
        while (i <= j) {
            while (v[i] < pv) i++;
            while (v[j] > pv) j--;
            if (i <= j) {
                double t = v[i]; v[i] = v[j]; v[j] = t;
                i++;
                if (j == 0) break;
                j--;
            }
        }
        if (k <= j) hi = j;
        else if (k >= i) lo = i;
        else return v[k];
    }
    return v[k];
}

/* Median as hd_glare_percentile(v, n, 50), in O(n). */
static double median_inplace(double *v, size_t n)
{
    double a = select_kth(v, n, (n - 1) / 2);
    if (n % 2) return a;
    /* the next order statistic is the smallest of the upper part */
    double b = v[n / 2];
    for (size_t i = n / 2; i < n; i++)
        if (v[i] < b) b = v[i];
    return 0.5 * (a + b);
}

double hd_glare_percentile(const double *v, size_t n, double p)
{
    if (n == 0) return NAN;
    double *t = hd_malloc_array(n, sizeof(double));
    if (!t) return NAN;
    memcpy(t, v, n * sizeof(double));
    qsort(t, n, sizeof(double), hd_cmp_double);
    if (p <= 0) { double r = t[0]; free(t); return r; }
    if (p >= 100) { double r = t[n - 1]; free(t); return r; }
    double pos = p / 100.0 * (double)(n - 1);
    size_t i = (size_t)floor(pos);
    double f = pos - (double)i;
    double r = i + 1 < n ? t[i] + f * (t[i + 1] - t[i]) : t[i];
    free(t);
    return r;
}

double hd_glare_dgp(double ev, const hd_glare_source *s, int n, const hd_glare_opts *o)
{
    if (ev <= 0) return 0;
    double sum = 0;
    for (int i = 0; i < n; i++)
        sum += pow(s[i].lum, o->a1) * pow(s[i].omega, o->a2) / (pow(ev, o->a3) * pow(s[i].posidx, o->a4));
    double dgp = o->c1 * ev + o->c3 + (n > 0 ? o->c2 * log10(1.0 + sum) : 0);
    if (o->lowlight && ev < 1000) {
        double e = exp(0.024 * ev - 4.0);
        dgp *= e / (1.0 + e);
    }
    if (dgp > 1) dgp = 1;
    return dgp;
}

void hd_glare_metrics(hd_glare_result *r, const hd_glare_opts *o)
{
    double E = r->ev, lb = r->lum_backg, edir = r->ev_dir;
    int ns = r->nsources;
    r->dgp = hd_glare_dgp(E, r->sources, ns, o);
    if (E > 0 && ns > 0) {
        double tsum = 0;
        for (int i = 0; i < ns; i++) {
            hd_glare_source *q = &r->sources[i];
            tsum += pow(q->lum, o->a1) * pow(q->omega, o->a2) / (pow(E, o->a3) * pow(q->posidx, o->a4));
        }
        for (int i = 0; i < ns; i++) {
            hd_glare_source *q = &r->sources[i];
            double t = pow(q->lum, o->a1) * pow(q->omega, o->a2) / (pow(E, o->a3) * pow(q->posidx, o->a4));
            q->r_contrast = tsum > 0 ? log10(1 + t) / log10(1 + tsum) : 0;
            q->r_dgp = r->dgp > 0 ? o->c2 * log10(1 + t) / r->dgp : 0;
        }
    }
    double sdgi = 0, sugr = 0, sveil = 0, sdgr = 0, sveilcie = 0;
    for (int i = 0; i < ns; i++) {
        const hd_glare_source *q = &r->sources[i];
        double L = q->lum, w = q->omega, P = q->posidx;
        sugr += L * L * w / (P * P);
        double den = lb + 0.07 * sqrt(w) * L;
        if (den > 0) sdgi += 0.478 * pow(L, 1.6) * pow(w / (P * P), 0.8) / den;
        if (q->sigma > 0) sveil += L * q->dir[1] * w / q->sigma;
        sveilcie += q->lveil_cie;
        if (r->av_lum > 0) /* adaptation luminance = mean field luminance */
            sdgr += 0.5 * L * (20.4 * w + 1.52 * pow(w, 0.2) - 0.075) / (P * pow(r->av_lum, 0.44));
    }
    if (ns > 0) {
        r->dgi = sdgi > 0 ? 10.0 * log10(sdgi) : 0;
        r->ugr = lb > 0 ? 8.0 * log10(0.25 / lb * sugr) : -99;
        r->ugp = lb > 0 ? 0.26 * log10(0.25 / lb * sugr) : 0;
        r->cgi = E > 0 ? 8.0 * log10(2.0 * (1.0 + edir / 500.0) / E * sugr) : 0;
        r->dgr = sdgr > 0 ? pow(sdgr, pow((double)ns, -0.0914)) : 0;
    }
    r->lveil = 5.0 * sveil;
    r->lveil_cie = sveilcie;
    if (r->dgr > 0) {
        double vcp = 50.0 * erf((6.374 - 1.3227 * log(r->dgr)) / sqrt(2.0)) + 50.0;
        if (r->dgr > 750) vcp = 0;
        r->vcp = vcp < 0 ? 0 : vcp > 100 ? 100 : vcp;
    } else r->vcp = 100;
}

hd_status hd_glare_eval_lum(const hd_glare_geom *g, const float *lum, const hd_glare_opts *o,
                            hd_glare_result *r)
{
    memset(r, 0, sizeof *r);
    int xr = g->xres, yr = g->yres;
    size_t np = (size_t)xr * yr;
    hd_status st = HD_OK;
    if (!(o->search_radius > 0) || o->search_radius > HD_PI)
        return hd_fail(HD_ERR_RANGE, "search radius -r %g out of range (0, pi]", o->search_radius);
    if (!(o->threshold > 0)) return hd_fail(HD_ERR_RANGE, "threshold -b %g must be positive", o->threshold);

    /* field statistics */
    double ev = 0, sl = 0, so = 0, lmax = 0;
    for (size_t k = 0; k < np; k++) {
        if (!g->valid[k]) continue;
        double L = lum[k];
        if (!(L >= 0) || !isfinite(L)) L = 0;
        ev += L * g->omega[k] * g->cosv[k];
        sl += L * g->omega[k];
        so += g->omega[k];
        if (L > lmax) lmax = L;
    }
    r->nvalid = g->nvalid;
    r->av_lum = so > 0 ? sl / so : 0;
    r->max_lum = lmax;
    r->ev = ev;
    {
        double *v = hd_malloc_array(g->nvalid > 0 ? (size_t)g->nvalid : 1, sizeof(double));
        if (!v) return HD_ERR_NOMEM;
        size_t n = 0;
        for (size_t k = 0; k < np; k++)
            if (g->valid[k]) v[n++] = lum[k] >= 0 ? lum[k] : 0;
        r->med_lum = n ? median_inplace(v, n) : 0;
        /* position-weighted luminances (evalglare's av_lum_pos, av_lum_pos2,
         * med_lum_pos, med_lum_pos2; definitions found to match the
         * references to 7 digits) */
        double sp = 0, sp2 = 0;
        n = 0;
        for (size_t k = 0; k < np; k++)
            if (g->valid[k]) {
                double L = lum[k] >= 0 ? lum[k] : 0, P = g->posidx[k];
                sp += L * g->omega[k] / P;
                sp2 += L * g->omega[k] / (P * P);
                v[n++] = L / P;
            }
        r->av_lum_pos = so > 0 ? sp / so : 0;
        r->av_lum_pos2 = so > 0 ? sp2 / (so * so) : 0;
        r->med_lum_pos = n ? median_inplace(v, n) : 0;
        n = 0;
        for (size_t k = 0; k < np; k++)
            if (g->valid[k]) v[n++] = (lum[k] >= 0 ? lum[k] : 0) / (g->posidx[k] * g->posidx[k]);
        r->med_lum_pos2 = n ? median_inplace(v, n) : 0;
        free(v);
    }

    /* threshold */
    double task = r->av_lum;
    if (o->task) {
        int tx = (int)floor(o->task_x + 0.5), ty = (int)floor(o->task_y + 0.5) - 1;
        if (tx < 0 || tx >= xr || ty < 0 || ty >= yr || !g->valid[(size_t)ty * xr + tx])
            return hd_fail(HD_ERR_RANGE, "task area centre (%g, %g) is outside the fisheye field", o->task_x,
                           o->task_y);
        const float *c = g->dir + 3 * ((size_t)ty * xr + tx);
        double ca = cos(o->task_angle / 2), tl = 0, to = 0;
        for (size_t k = 0; k < np; k++) {
            if (!g->valid[k]) continue;
            const float *d = g->dir + 3 * k;
            if ((double)c[0] * d[0] + (double)c[1] * d[1] + (double)c[2] * d[2] >= ca) {
                tl += lum[k] * g->omega[k];
                to += g->omega[k];
            }
        }
        if (to > 0) task = tl / to;
    }
    r->task_lum = task;
    double thr = o->threshold > 100 ? o->threshold : o->threshold * task;
    r->threshold = thr;

    /* detection */
    unsigned char *mask = hd_calloc(np, 1);
    int *par = hd_malloc_array(np, sizeof(int));
    int *ppar = NULL;
    int *label = hd_malloc_array(np, sizeof(int));
    acc_t *acc = NULL;
    if (!mask || !par || !label) { st = HD_ERR_NOMEM; goto done; }
    size_t nglare = 0;
    for (size_t k = 0; k < np; k++)
        if (g->valid[k] && lum[k] > thr) { mask[k] = 1; nglare++; }
    /* -r is the opening angle of the search cone: two glare pixels belong to
     * the same source when they are linked by a chain of pixels less than
     * r/2 apart (this reproduces evalglare's source lists exactly on the
     * reference images; see docs/design/glare.md) */
    if ((st = cluster(g, mask, o->search_radius / 2, par))) goto done;
    int use_peaks = o->peak_extract && o->peak_value > 0;
    if (use_peaks) {
        size_t npk = 0;
        for (size_t k = 0; k < np; k++)
            if (mask[k] && lum[k] >= o->peak_value) { mask[k] = 2; npk++; }
        if (npk) {
            unsigned char *pm = hd_calloc(np, 1);
            ppar = hd_malloc_array(np, sizeof(int));
            if (!pm || !ppar) { free(pm); st = HD_ERR_NOMEM; goto done; }
            for (size_t k = 0; k < np; k++) pm[k] = mask[k] == 2;
            st = cluster(g, pm, o->search_radius / 4, ppar);   /* peaks: cone r/2 */
            free(pm);
            if (st) goto done;
        } else use_peaks = 0;
    }
    /* number sources in scan order (columns left to right, each top to
     * bottom); peak sources after the others */
    /* numbering: main sources first, then peak sources; a peak root may
     * coincide with a main root, so peaks get a label table of their own */
    int nsrc = 0;
    {
        int *plabel = hd_malloc_array(np, sizeof(int));
        if (!plabel) { st = HD_ERR_NOMEM; goto done; }
        for (size_t k = 0; k < np; k++) { label[k] = -1; plabel[k] = -1; }
        nsrc = 0;
        for (int m = 1; m <= (use_peaks ? 2 : 1); m++) {   /* mask value 1: main sources, 2: peaks */
            int *lab = m == 1 ? label : plabel, *pr = m == 1 ? par : ppar;
            for (int x = 0; x < xr; x++)
                for (int row = 0; row < yr; row++) {
                    int k = row * xr + x;
                    if (mask[k] != m) continue;
                    int root = hd_uf_find(pr, k);
                    if (lab[root] < 0) lab[root] = nsrc++;
                }
        }
        /* per-pixel source index, written into par once all roots are known */
        int *map = hd_malloc_array(np, sizeof(int));
        if (!map) { free(plabel); st = HD_ERR_NOMEM; goto done; }
        for (size_t k = 0; k < np; k++)
            map[k] = mask[k] == 1 ? label[hd_uf_find(par, (int)k)]
                   : mask[k] == 2 ? plabel[hd_uf_find(ppar, (int)k)] : -1;
        memcpy(par, map, np * sizeof(int));
        free(map);
        free(plabel);
    }
    acc = hd_calloc(nsrc > 0 ? (size_t)nsrc : 1, sizeof(acc_t));
    if (!acc) { st = HD_ERR_NOMEM; goto done; }
    double edir = 0;
    for (int row = 0; row < yr; row++)
        for (int x = 0; x < xr; x++) {
            size_t k = (size_t)row * xr + x;
            int s = par[k];
            if (s < 0) continue;
            acc_t *a = &acc[s];
            double L = lum[k], om = g->omega[k], w = L * om;
            a->npix += 1;
            a->om += om;
            a->lom += w;
            a->x += w * x;
            a->y += w * (yr - 1 - row);   /* from the bottom */
            a->w += w;

            a->eg += L * om * g->cosv[k];
            if (L > a->lmax) a->lmax = L;
            edir += L * om * g->cosv[k];
        }
    r->sources = hd_calloc(nsrc > 0 ? (size_t)nsrc : 1, sizeof(hd_glare_source));
    if (!r->sources) { st = HD_ERR_NOMEM; goto done; }
    int ns = 0;
    double lsum = 0, osum = 0;
    for (int s = 0; s < nsrc; s++) {
        acc_t *a = &acc[s];
        if (a->npix <= 0 || a->om <= 0) continue;
        hd_glare_source *q = &r->sources[ns++];
        q->npix = a->npix;
        q->omega = a->om;
        q->lum = a->lom / a->om;
        /* evalglare's convention: the position is the L*omega-weighted mean
         * pixel (x from the left, y from the bottom; printed as yres - y),
         * and the direction is the view ray through the centre of the pixel
         * at the truncated mean position */
        double mx = a->w > 0 ? a->x / a->w : 0, myb = a->w > 0 ? a->y / a->w : 0;
        q->x = mx;
        q->y = yr - myb;
        /* (a tiny bias keeps exact integers, e.g. single pixels, from
         * truncating to the pixel below through rounding of the mean) */
        frame_ray(&g->view, ((int)(mx + 1e-7) + 0.5) / xr, ((int)(myb + 1e-7) + 0.5) / yr, q->dir, 1);
        double f = q->dir[1] > 1 ? 1 : q->dir[1] < -1 ? -1 : q->dir[1];
        q->sigma = acos(f) * DEG;
        double ru = sqrt(q->dir[0] * q->dir[0] + q->dir[2] * q->dir[2]);
        q->tau = ru > 0 ? acos(q->dir[2] / ru > 1 ? 1 : q->dir[2] / ru < -1 ? -1 : q->dir[2] / ru) * DEG : 0;
        q->posidx = hd_glare_posidx(q->dir);
        q->e_glare = a->eg;
        q->lveil_cie = q->sigma > 0 ? 10.0 * a->eg / (q->sigma * q->sigma) : 0;
        q->lmax = a->lmax;
        lsum += a->lom;
        osum += a->om;
    }
    r->nsources = ns;
    r->ev_dir = edir;
    r->lum_sources = osum > 0 ? lsum / osum : 0;
    r->omega_sources = osum;
    if (o->want_map) {
        r->source_map = par;   /* indices before compaction: remap */
        int *remap = hd_malloc_array(nsrc > 0 ? (size_t)nsrc : 1, sizeof(int));
        if (!remap) { r->source_map = NULL; st = HD_ERR_NOMEM; goto done; }
        for (int s = 0, t = 0; s < nsrc; s++) remap[s] = (acc[s].npix > 0 && acc[s].om > 0) ? t++ : -1;
        for (size_t k = 0; k < np; k++)
            if (par[k] >= 0) par[k] = remap[par[k]];
        free(remap);
        par = NULL;
    }

    /* metrics */
    double E = o->ev_external > 0 ? o->ev_external : ev;
    if (o->ev_external > 0) r->ev = E;
    double lb;
    if (o->bg_mode == 1) {
        double bl = 0, bo = 0;
        for (size_t k = 0; k < np; k++)
            if (g->valid[k] && !mask[k]) { bl += lum[k] * g->omega[k]; bo += g->omega[k]; }
        lb = bo > 0 ? bl / bo : 0;
    } else if (o->bg_mode == 2) {
        lb = E / HD_PI;
    } else {
        lb = (E - edir) / HD_PI;
    }
    r->lum_backg = lb;
    hd_glare_metrics(r, o);
    (void)nglare;
done:
    free(mask);
    free(par);
    free(ppar);
    free(label);
    free(acc);
    if (st) hd_glare_result_free(r);
    return st;
}

hd_status hd_glare_eval_geom(const hd_glare_geom *g, const float *rgb, const hd_glare_opts *o,
                             hd_glare_result *r)
{
    size_t np = (size_t)g->xres * g->yres;
    float *lum = hd_malloc_array(np, sizeof(float));
    if (!lum) return HD_ERR_NOMEM;
    for (size_t k = 0; k < np; k++) lum[k] = (float)hd_glare_luminance(rgb + 3 * k);
    hd_status st = hd_glare_eval_lum(g, lum, o, r);
    free(lum);
    return st;
}

hd_status hd_glare_eval(const float *rgb, int xres, int yres, const hd_glare_view *v, const hd_glare_opts *o,
                        hd_glare_result *r)
{
    hd_glare_geom *g;
    hd_status st = hd_glare_geom_new(&g, v, xres, yres);
    if (st) return st;
    st = hd_glare_eval_geom(g, rgb, o, r);
    hd_glare_geom_free(g);
    return st;
}

/* ------------------------------------------------------------ output */

void hd_glare_write_line(FILE *fp, const hd_glare_result *r)
{
    fprintf(fp, "dgp,dgi,ugr,vcp,cgi,Lveil: %f %f %f %f %f %f  \n", r->dgp, r->dgi, r->ugr, r->vcp, r->cgi,
            r->lveil);
}

void hd_glare_write_detail(FILE *fp, const hd_glare_result *r)
{
    fprintf(fp, "%d No pixels x-pos y-pos L_s Omega_s Posindx L_b L_t E_v Edir Max_Lum Sigma xdir ydir zdir "
                "Eglare Lveil_cie teta glare_zone r_contrast r_dgp\n", r->nsources);
    for (int i = 0; i < r->nsources; i++) {
        const hd_glare_source *q = &r->sources[i];
        fprintf(fp, "%d %f %f %f %f %.10f %f %f %f %f %f %f %f %f %f %f %f %f %f %d %f %f \n", i + 1, q->npix,
                q->x, q->y, q->lum, q->omega, q->posidx, r->lum_backg, (double)(float)r->task_lum, r->ev,
                r->ev_dir, r->max_lum, q->sigma, q->dir[0], q->dir[1], q->dir[2], q->e_glare, q->lveil_cie,
                q->sigma, 0, q->r_contrast, q->r_dgp);
    }
    fprintf(fp, "dgp,av_lum,E_v,lum_backg,E_v_dir,dgi,ugr,vcp,cgi,lum_sources,omega_sources,Lveil,Lveil_cie,"
                "dgr,ugp,ugr_exp,dgi_mod,av_lum_pos,av_lum_pos2,med_lum,med_lum_pos,med_lum_pos2,ugp2: "
                "%f %f %f %f %f %f %f %f %f %f %f %f %f %f %f nan nan %f %f %f %f %f nan\n",
            r->dgp, r->av_lum, r->ev, r->lum_backg, r->ev_dir, r->dgi, r->ugr, r->vcp, r->cgi, r->lum_sources,
            r->omega_sources, r->lveil, r->lveil_cie, r->dgr, r->ugp, r->av_lum_pos, r->av_lum_pos2, r->med_lum,
            r->med_lum_pos, r->med_lum_pos2);
}

/* ------------------------------------------------------------ annual */

hd_glare_class hd_glare_class_dgp(double dgp)
{
    return dgp < 0.35 ? HD_GLARE_IMPERCEPTIBLE : dgp < 0.40 ? HD_GLARE_PERCEPTIBLE
                                               : dgp < 0.45 ? HD_GLARE_DISTURBING : HD_GLARE_INTOLERABLE;
}

hd_glare_class hd_glare_class_dgi(double dgi)
{
    return dgi < 18 ? HD_GLARE_IMPERCEPTIBLE : dgi < 24 ? HD_GLARE_PERCEPTIBLE
                                             : dgi < 31 ? HD_GLARE_DISTURBING : HD_GLARE_INTOLERABLE;
}

const char *hd_glare_class_name(hd_glare_class c)
{
    static const char *n[] = {"imperceptible", "perceptible", "disturbing", "intolerable"};
    return (unsigned)c < 4 ? n[c] : "?";
}

int hd_glare_shade_closed(double dgp, double limit) { return dgp >= limit; }

void hd_glare_annual_init(hd_glare_annual *a, double shade_limit)
{
    memset(a, 0, sizeof *a);
    a->shade_limit = shade_limit > 0 ? shade_limit : HD_GLARE_SHADE_LIMIT;
}

void hd_glare_annual_free(hd_glare_annual *a)
{
    free(a->hour);
    free(a->ev);
    free(a->dgp);
    free(a->dgi);
    memset(a, 0, sizeof *a);
}

hd_status hd_glare_annual_add(hd_glare_annual *a, double hour, double ev, double dgp, double dgi,
                              int *shade_closed)
{
    if (a->n == a->cap) {
        size_t nc = a->cap ? a->cap * 2 : 1024;
        double **arr[4] = {&a->hour, &a->ev, &a->dgp, &a->dgi};
        for (int k = 0; k < 4; k++) {
            double *p = hd_realloc_array(*arr[k], nc, sizeof(double));
            if (!p) return HD_ERR_NOMEM;
            *arr[k] = p;
        }
        a->cap = nc;
    }
    a->hour[a->n] = hour;
    a->ev[a->n] = ev;
    a->dgp[a->n] = dgp;
    a->dgi[a->n] = dgi;
    a->n++;
    a->count_dgp[hd_glare_class_dgp(dgp)]++;
    a->count_dgi[hd_glare_class_dgi(dgi)]++;
    int c = hd_glare_shade_closed(dgp, a->shade_limit);
    a->shade_closed += c;
    if (shade_closed) *shade_closed = c;
    return HD_OK;
}

void hd_glare_csv_header(FILE *fp)
{
    fprintf(fp, "hour,Ev,DGP,DGI,UGR,nsources,DGP_class,DGI_class,shade\n");
}

void hd_glare_csv_row(FILE *fp, double hour, const hd_glare_result *r, int shade_closed)
{
    fprintf(fp, "%.10g,%.2f,%.6f,%.4f,%.4f,%d,%s,%s,%d\n", hour, r->ev, r->dgp, r->dgi, r->ugr, r->nsources,
            hd_glare_class_name(hd_glare_class_dgp(r->dgp)), hd_glare_class_name(hd_glare_class_dgi(r->dgi)),
            shade_closed);
}

void hd_glare_annual_write_summary(FILE *fp, const hd_glare_annual *a)
{
    size_t n = a->n;
    fprintf(fp, "hours: %zu\n", n);
    fprintf(fp, "Ev_p95: %.2f\n", hd_glare_percentile(a->ev, n, 95));
    fprintf(fp, "DGP_p95: %.6f\n", hd_glare_percentile(a->dgp, n, 95));
    fprintf(fp, "DGI_p95: %.4f\n", hd_glare_percentile(a->dgi, n, 95));
    static const char *lim_dgp[] = {"< 0.35", "0.35-0.40", "0.40-0.45", ">= 0.45"};
    static const char *lim_dgi[] = {"< 18", "18-24", "24-31", ">= 31"};
    for (int c = 0; c < 4; c++)
        fprintf(fp, "DGP_%s: %zu hours (%.1f%%, DGP %s)\n", hd_glare_class_name((hd_glare_class)c), a->count_dgp[c],
                n ? 100.0 * (double)a->count_dgp[c] / (double)n : 0.0, lim_dgp[c]);
    for (int c = 0; c < 4; c++)
        fprintf(fp, "DGI_%s: %zu hours (%.1f%%, DGI %s)\n", hd_glare_class_name((hd_glare_class)c), a->count_dgi[c],
                n ? 100.0 * (double)a->count_dgi[c] / (double)n : 0.0, lim_dgi[c]);
    fprintf(fp, "shade_closed: %zu hours (%.1f%%, DGP >= %.2f)\n", a->shade_closed,
            n ? 100.0 * (double)a->shade_closed / (double)n : 0.0, a->shade_limit);
}

int hd_glare_view_option(hd_glare_viewargs *va, int argc, char **argv, int i)
{
    const char *w = argv[i];
    if (!strcmp(w, "-vf")) {
        if (i + 1 >= argc) { hd_fail(HD_ERR_USAGE, "option -vf expects a view file"); return -1; }
        hd_istream *s;
        if (hd_istream_open(&s, argv[i + 1])) return -1;
        char buf[4096];
        size_t n = hd_istream_read(s, buf, sizeof buf - 1);
        buf[n] = 0;
        hd_istream_close(s);
        int k = hd_view_parse_line(va->view, buf);
        if (k < 0) return -1;
        if (!k) { hd_fail(HD_ERR_USAGE, "view file %s: no view options found", argv[i + 1]); return -1; }
        va->has_t |= strstr(buf, "-vt") != NULL;
        va->has_h |= strstr(buf, "-vh") != NULL;
        va->has_v |= strstr(buf, "-vv") != NULL;
        va->nview++;
        return 1;
    }
    int k = hd_view_parse_arg(va->view, argc, argv, i);
    if (k <= 0) {
        if (!k) hd_fail(HD_ERR_USAGE, "unknown view option %s", w);
        return -1;
    }
    if (w[2] == 't') va->has_t = 1;
    if (!strcmp(w, "-vh")) va->has_h = 1;
    if (!strcmp(w, "-vv")) va->has_v = 1;
    va->nview++;
    return k - 1;
}

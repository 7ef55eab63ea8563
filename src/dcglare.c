/* heliodon — imageless annual glare (see dcglare.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/basis.h"
#include "heliodon/dcglare.h"
#include "heliodon/io.h"

#define DCG_EFFICACY 179.0
/* thresholds up to this value are factors of the mean luminance E_v / pi */
#define DCG_FACTOR_MAX 100.0
#define DCG_TINY 1e-6

void hd_dcglare_opts_default(hd_dcglare_opts *o)
{
    memset(o, 0, sizeof *o);
    o->limit = -1;
    o->threshold = 2000;
    o->vup = hd_v3(0, 0, 1);
}

static double lum3(const double *c) { return 0.265074126 * c[0] + 0.670114631 * c[1] + 0.064811243 * c[2]; }

static double angle_between(hd_vec3 a, hd_vec3 b)
{
    double c = hd_vdot(a, b);
    return acos(c > 1 ? 1 : c < -1 ? -1 : c);
}

double hd_dcglare_posidx(hd_vec3 dir, hd_vec3 fwd, hd_vec3 up)
{
    const double deg = 180.0 / HD_PI;
    hd_vec3 side = hd_vnorm(hd_vcross(fwd, up));       /* horizontal, to the right */
    hd_vec3 down = hd_vcross(fwd, side);               /* in the view plane, pointing down */
    double phi = angle_between(dir, down) - HD_PI / 2; /* > 0: above the line of sight */
    double p;
    if (phi >= 0) {
        double sigma = fabs(angle_between(dir, fwd) * deg);
        /* Radiance's dcglare measures tau from fwd + dir / (dir . fwd) */
        hd_vec3 t = hd_vnorm(hd_vmadd(fwd, dir, 1 / hd_vdot(dir, fwd)));
        double tau = angle_between(t, up) * deg;
        p = exp((35.2 - 0.31889 * tau - 1.22 * exp(-2.0 * tau / 9.0)) / 1000.0 * sigma +
                (21.0 + 0.26667 * tau - 0.002963 * tau * tau) / 100000.0 * sigma * sigma);
    } else {
        double theta = HD_PI / 2 - angle_between(dir, side);
        if (theta == 0) theta = DCG_TINY;
        double tp = tan(phi);
        double s = tan(theta) / tp;
        double r = sqrt(1 + s * s) * fabs(tp);
        double f = r > 0.6 ? 1.2 : 0.8;
        if (r > 3) r = 3;
        p = 1 + f * r;
    }
    return p > 16 ? 16 : p;
}

double hd_dcglare_step(double ev, const double *dcdir, const double *sky, const hd_skybasis *b, hd_vec3 vdir,
                       hd_vec3 vup, double threshold)
{
    if (ev <= DCG_TINY) return 0;
    double lmin = threshold < DCG_FACTOR_MAX ? threshold * ev / HD_PI : threshold;
    double sum = 0;
    for (int c = 0; c < b->nbins; c++) {
        double dc = lum3(dcdir + 3 * c);
        if (!(dc > 0)) continue;
        hd_vec3 d = b->dir[c];
        if (c == 0) { /* the ground seen: halfway between straight down and the view direction */
            d = hd_vadd(d, vdir);
            if (hd_vlen2(d) == 0) continue;
            d = hd_vnorm(d);
        }
        double cth = hd_vdot(vdir, d);
        if (cth <= DCG_TINY) continue;
        double omega = c == 0 ? 2 * (HD_PI - 2 * acos(cth > 1 ? 1 : cth)) : b->omega[c];
        double L = dc * DCG_EFFICACY * lum3(sky + 3 * c) / (omega * cth);
        if (L < lmin) continue;
        double p = hd_dcglare_posidx(d, vdir, vup);
        sum += L * L * omega / (p * p);
    }
    double dgp = 5.87e-5 * ev + 0.0918 * log10(1 + sum / pow(ev, 1.87)) + 0.16;
    if (ev < 1000) {
        double e = exp(0.024 * ev - 4);
        dgp *= e / (1 + e);
    }
    return dgp > 1 ? 1 : dgp;
}

static int mf_of_bins(int nbins)
{
    for (int mf = 1; mf <= HD_SKY_MAXMF; mf++)
        if (hd_skybasis_count(mf) == nbins) return mf;
    return 0;
}

hd_status hd_dcglare_eval(const hd_matrix *dcdirect, const hd_matrix *ev, const hd_matrix *sky,
                          const hd_dcglare_opts *o, float **out)
{
    *out = NULL;
    if (dcdirect->nrows != ev->nrows || dcdirect->ncols != sky->nrows || ev->ncols != sky->ncols)
        return hd_fail(HD_ERR_FORMAT, "inconsistent matrix sizes: direct DC %d x %d, E_v %d x %d, sky %d x %d "
                       "(expected views x bins, views x steps, bins x steps)", dcdirect->nrows, dcdirect->ncols,
                       ev->nrows, ev->ncols, sky->nrows, sky->ncols);
    if (dcdirect->ncomp != 3 || ev->ncomp != 3 || sky->ncomp != 3)
        return hd_fail(HD_ERR_FORMAT, "expected RGB matrices (NCOMP=3): direct DC %d, E_v %d, sky %d",
                       dcdirect->ncomp, ev->ncomp, sky->ncomp);
    int mf = mf_of_bins(sky->nrows);
    if (mf == 0)
        return hd_fail(HD_ERR_FORMAT, "the sky matrix has %d rows: not a Reinhart sky with its ground bin "
                       "(146 for MF:1, 578 for MF:2, ...)", sky->nrows);
    if (!o->views && hd_vlen2(o->vdir) == 0)
        return hd_fail(HD_ERR_USAGE, "no view direction: give -vd dx dy dz or a view file -vf");
    hd_skybasis b;
    hd_status st = hd_skybasis_init(&b, mf);
    if (st) return st;
    int hourly = o->limit < 0;
    int nv = ev->nrows, nt = ev->ncols, nb = sky->nrows;
    float *res = hd_malloc_array((size_t)nv * (size_t)(hourly ? nt : 1), sizeof(float));
    double *dcrow = hd_malloc_array((size_t)nb * 3, sizeof(double));
    double *col = hd_malloc_array((size_t)nb * 3, sizeof(double));
    if (!res || !dcrow || !col) {
        free(res);
        free(dcrow);
        free(col);
        hd_skybasis_free(&b);
        return HD_ERR_NOMEM;
    }
    /* E_v at or above this gives DGPs >= limit whatever the sources */
    double ev_glare = hourly ? HUGE_VAL : fmax(0, (o->limit - 0.16) / 5.87e-5);
    hd_vec3 up = hd_vnorm(o->vup);
    for (int p = 0; p < nv; p++) {
        hd_vec3 vd = hd_vnorm(o->views ? o->views[p] : o->vdir);
        memcpy(dcrow, hd_matrix_at(dcdirect, p, 0), sizeof(double) * 3 * (size_t)nb);
        long nocc = 0, nglare = 0;
        for (int t = 0; t < nt; t++) {
            float *dst = hourly ? &res[(size_t)p * (size_t)nt + (size_t)t] : NULL;
            if (o->occupied && !o->occupied[t]) {
                if (dst) *dst = 0;
                continue;
            }
            nocc++;
            double e = DCG_EFFICACY * lum3(hd_matrix_at(ev, p, t));
            if (e <= DCG_TINY) {
                if (dst) *dst = 0;
                continue;
            }
            if (!hourly && e >= ev_glare) {
                nglare++;
                continue;
            }
            for (int c = 0; c < nb; c++) memcpy(col + 3 * c, hd_matrix_at(sky, c, t), sizeof(double) * 3);
            double dgp = hd_dcglare_step(e, dcrow, col, &b, vd, up, o->threshold);
            if (dst) *dst = (float)dgp;
            else if (dgp >= o->limit) nglare++;
        }
        if (!hourly) res[p] = nocc > 0 ? (float)(nocc - nglare) / (float)nocc : 0.0f;
    }
    free(dcrow);
    free(col);
    hd_skybasis_free(&b);
    *out = res;
    return HD_OK;
}

hd_status hd_dcglare_read_schedule(const char *path, int nsteps, unsigned char *occ)
{
    hd_istream *s;
    hd_status st = hd_istream_open(&s, path);
    if (st) return st;
    char line[4096];
    int n = 0;
    long len;
    while (!st && (len = hd_istream_getline(s, line, sizeof line)) >= 0) {
        if (line[0] == '#') continue;
        const char *v = strrchr(line, ',');
        v = v ? v + 1 : line;
        char *end;
        double x = strtod(v, &end);
        if (end == v) {
            if (line[strspn(line, " \t\r\n")] == '\0') continue; /* blank line */
            st = hd_fail(HD_ERR_FORMAT, "%s: line %lu: expected a number after the last comma", path,
                         hd_istream_lineno(s));
        } else if (n >= nsteps) {
            st = hd_fail(HD_ERR_FORMAT, "%s: line %lu: more schedule entries than the %d time steps of the sky",
                         path, hd_istream_lineno(s), nsteps);
        } else {
            occ[n++] = x > 0;
        }
    }
    hd_status cst = hd_istream_close(s);
    if (!st && cst) st = cst;
    if (!st && n < nsteps)
        st = hd_fail(HD_ERR_FORMAT, "%s: %d schedule entries, the sky has %d time steps", path, n, nsteps);
    return st;
}

hd_status hd_dcglare_read_views(const char *path, int fmt, int nviews, hd_vec3 *dirs)
{
    hd_matrix m;
    hd_matrix_init(&m);
    hd_matrix_readopts ro = {0, 1, 6, fmt};
    hd_status st = hd_matrix_read(path, &m, &ro);
    if (st) return st;
    if (m.nrows < nviews) {
        int n = m.nrows;
        hd_matrix_free(&m);
        return hd_fail(HD_ERR_FORMAT, "%s: %d views (x y z dx dy dz each), the matrices have %d rows", path, n,
                       nviews);
    }
    for (int i = 0; i < nviews && !st; i++) {
        const double *v = hd_matrix_at(&m, i, 0);
        hd_vec3 d = hd_v3(v[3], v[4], v[5]);
        if (hd_vlen2(d) == 0) st = hd_fail(HD_ERR_FORMAT, "%s: view %d: zero-length direction", path, i + 1);
        else dirs[i] = hd_vnorm(d);
    }
    hd_matrix_free(&m);
    return st;
}

/* heliodon — error measures between two results (see compare.h). */
#include "heliodon/compare.h"

#include <math.h>
#include <stdlib.h>

#include "heliodon/glare.h"
#include "heliodon/matrix.h"
#include "heliodon/picture.h"

void hd_compare_values(const double *a, const double *b, size_t n, double floor, hd_cmp_stats *st)
{
    hd_cmp_stats s = {0};
    s.imax = -1;
    s.n = (long)n;
    if (floor < 0) {
        double sum = 0;
        long cnt = 0;
        for (size_t i = 0; i < n; i++)
            if (isfinite(b[i])) { sum += b[i]; cnt++; }
        floor = cnt > 0 ? -floor * sum / (double)cnt : 0;
        if (floor < 0) floor = 0;
    }
    s.floor = floor;
    double s2 = 0, s1 = 0, sa = 0;
    for (size_t i = 0; i < n; i++) {
        int fa = isfinite(a[i]), fb = isfinite(b[i]);
        if (!fa) s.nonfinite_a++;
        if (!fb) s.nonfinite_b++;
        if (!fa || !fb) continue;
        s.sum_a += a[i];
        s.sum_b += b[i];
        if (!(b[i] > floor) || b[i] <= 0) continue;
        double d = (a[i] - b[i]) / b[i];
        s.nused++;
        s1 += d;
        s2 += d * d;
        sa += fabs(d);
        if (fabs(d) > s.max_rel || s.imax < 0) { s.max_rel = fabs(d); s.imax = (long)i; }
    }
    if (s.nused > 0) {
        s.rms_rel = sqrt(s2 / (double)s.nused);
        s.mean_rel = s1 / (double)s.nused;
        s.mean_abs_rel = sa / (double)s.nused;
    }
    s.total_rel = s.sum_b != 0 ? s.sum_a / s.sum_b - 1 : 0;
    *st = s;
}

double hd_compare_grey(const double *v, int ncomp)
{
    if (ncomp == 1) return v[0];
    if (ncomp == 3) return 0.265074126 * v[0] + 0.670114631 * v[1] + 0.064811243 * v[2];
    double s = 0;
    for (int k = 0; k < ncomp; k++) s += v[k];
    return ncomp > 0 ? s / ncomp : 0;
}

static hd_status glare_part(const float *la, const float *lb, int xres, int yres,
                            const hd_glare_view *v, hd_piccmp *r)
{
    hd_glare_geom *g = NULL;
    hd_status st = hd_glare_geom_new(&g, v, xres, yres);
    if (st != HD_OK) return st;
    hd_glare_opts o;
    hd_glare_opts_default(&o);
    hd_glare_result ra = {0}, rb = {0};
    st = hd_glare_eval_lum(g, la, &o, &ra);
    if (st == HD_OK) st = hd_glare_eval_lum(g, lb, &o, &rb);
    if (st == HD_OK) {
        r->have_glare = 1;
        r->ev_a = ra.ev;
        r->ev_b = rb.ev;
        r->dgp_a = ra.dgp;
        r->dgp_b = rb.dgp;
    }
    hd_glare_result_free(&ra);
    hd_glare_result_free(&rb);
    hd_glare_geom_free(g);
    return st;
}

hd_status hd_compare_pictures(const hd_picture *a, const hd_picture *b, const hd_glare_view *view,
                              double floor, hd_piccmp *r)
{
    hd_piccmp out = {0};
    if (a->xres != b->xres || a->yres != b->yres)
        return hd_fail(HD_ERR_RANGE, "picture sizes differ: %d x %d vs reference %d x %d", a->xres, a->yres,
                       b->xres, b->yres);
    float *la = NULL, *lb = NULL;
    double *da = NULL, *db = NULL;
    hd_status st = hd_glare_picture_lum(a, &la);
    if (st == HD_OK) st = hd_glare_picture_lum(b, &lb);
    size_t n = (size_t)a->xres * (size_t)a->yres;
    if (st == HD_OK) {
        da = hd_malloc_array(n, sizeof *da);
        db = hd_malloc_array(n, sizeof *db);
        if (!da || !db) st = hd_fail(HD_ERR_NOMEM, "out of memory comparing %zu pixels", n);
    }
    if (st == HD_OK) {
        for (size_t i = 0; i < n; i++) { da[i] = la[i]; db[i] = lb[i]; }
        hd_compare_values(da, db, n, floor, &out.lum);
        hd_glare_view v;
        int ok = 0;
        if (view) { v = *view; ok = 1; }
        else {
            int found = 0;
            hd_view_default(&v);
            if (hd_view_from_header(&v, &b->hdr, &found) == HD_OK && found > 0) ok = 1;
            else {
                hd_view_default(&v);
                if (hd_view_from_header(&v, &a->hdr, &found) == HD_OK && found > 0) ok = 1;
            }
            hd_clear_error();
        }
        if (ok) {
            hd_status cs = hd_glare_view_check(&v);
            if (cs != HD_OK) {
                if (view) st = cs;
                else hd_clear_error();
                ok = 0;
            }
        }
        if (ok && st == HD_OK) st = glare_part(la, lb, a->xres, a->yres, &v, &out);
    }
    free(la);
    free(lb);
    free(da);
    free(db);
    if (st == HD_OK) *r = out;
    return st;
}

hd_status hd_compare_matrices(const hd_matrix *a, const hd_matrix *b, double floor, hd_cmp_stats *st,
                              double *per_row)
{
    if (a->nrows != b->nrows || a->ncols != b->ncols || a->ncomp != b->ncomp)
        return hd_fail(HD_ERR_RANGE, "matrix sizes differ: %d x %d x %d vs reference %d x %d x %d", a->nrows,
                       a->ncols, a->ncomp, b->nrows, b->ncols, b->ncomp);
    size_t n = (size_t)a->nrows * (size_t)a->ncols;
    double *ga = hd_malloc_array(n ? n : 1, sizeof *ga), *gb = hd_malloc_array(n ? n : 1, sizeof *gb);
    if (!ga || !gb) {
        free(ga);
        free(gb);
        return hd_fail(HD_ERR_NOMEM, "out of memory comparing %zu matrix elements", n);
    }
    for (size_t i = 0; i < n; i++) {
        ga[i] = hd_compare_grey(a->data + i * (size_t)a->ncomp, a->ncomp);
        gb[i] = hd_compare_grey(b->data + i * (size_t)b->ncomp, b->ncomp);
    }
    hd_compare_values(ga, gb, n, floor, st);
    if (per_row)
        for (int r = 0; r < a->nrows; r++) {
            double sa = 0, sb = 0;
            for (int c = 0; c < a->ncols; c++) {
                size_t i = (size_t)r * (size_t)a->ncols + (size_t)c;
                if (isfinite(ga[i]) && isfinite(gb[i])) { sa += ga[i]; sb += gb[i]; }
            }
            per_row[r] = sb != 0 ? sa / sb - 1 : 0;
        }
    free(ga);
    free(gb);
    return HD_OK;
}

double hd_compare_predict_error(double err0, double n0, double n)
{
    if (!(n > 0) || !(n0 > 0)) return err0;
    return err0 * sqrt(n0 / n);
}

double hd_compare_predict_count(double err0, double n0, double target)
{
    if (!(target > 0) || !(err0 >= 0)) return n0;
    double n = ceil(n0 * (err0 / target) * (err0 / target));
    return n < 1 ? 1 : n;
}

int hd_compare_pm_fit(const double *k, const double *var, const double *dbias2, int n, double n0, hd_pm_model *m)
{
    if (n < 2 || !(n0 > 0)) return -1;
    double sv = 0, sk = 0, sb = 0, sd = 0;
    for (int i = 0; i < n; i++) {
        if (!(k[i] > 0) || !(var[i] >= 0) || !isfinite(var[i])) return -1;
        sv += var[i] / k[i];
        sk += 1.0 / (k[i] * k[i]);
        if (i > 0) {
            double d = k[i] - k[0];
            if (!(d > 0)) return -1;
            double b2 = dbias2[i] > 0 && isfinite(dbias2[i]) ? dbias2[i] : 0;
            sb += b2 * d * d;
            sd += d * d * d * d;
        }
    }
    m->C = sv / sk;
    m->B = n0 * sqrt(sb / sd);
    return m->C > 0 ? 0 : -1;
}

double hd_compare_pm_error(const hd_pm_model *m, double N, double k)
{
    if (!(k > 0)) return INFINITY;
    double bias = N > 0 ? m->B * k / N : (m->B > 0 ? INFINITY : 0);
    return sqrt(m->C / k + bias * bias);
}

int hd_compare_pm_choose(const hd_pm_model *m, double target, double *N, double *k)
{
    if (!(target > 0) || !(m->C > 0) || !(m->B >= 0)) return -1;
    if (m->B == 0) {   /* no measurable bias: the error depends on k only */
        *k = m->C / (target * target);
        *N = 0;
        return 0;
    }
    *k = 1.5 * m->C / (target * target);
    *N = m->B * *k * sqrt(2 * *k / m->C);
    return 0;
}

hd_status hd_compare_reduce(const hd_picture *in, int k, hd_picture *out)
{
    if (k < 1 || in->xres % k || in->yres % k)
        return hd_fail(HD_ERR_RANGE, "cannot reduce a %d x %d picture by %d (sizes must be multiples)", in->xres,
                       in->yres, k);
    hd_status st = hd_picture_alloc(out, in->xres / k, in->yres / k);
    if (st) return st;
    out->fmt = in->fmt;
    hd_header_free(&out->hdr);
    if ((st = hd_header_copy(&out->hdr, &in->hdr))) { hd_picture_free(out); return st; }
    double w = 1.0 / ((double)k * k);
    for (int y = 0; y < out->yres; y++)
        for (int x = 0; x < out->xres; x++) {
            double s[3] = {0, 0, 0};
            for (int j = 0; j < k; j++)
                for (int i = 0; i < k; i++) {
                    const float *c = in->pix + 3 * ((size_t)(y * k + j) * (size_t)in->xres + (size_t)(x * k + i));
                    s[0] += c[0]; s[1] += c[1]; s[2] += c[2];
                }
            float *o = out->pix + 3 * ((size_t)y * (size_t)out->xres + (size_t)x);
            for (int c = 0; c < 3; c++) o[c] = (float)(s[c] * w);
        }
    return HD_OK;
}

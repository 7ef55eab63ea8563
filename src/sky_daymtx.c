/* heliodon — whole sky matrices over a weather file (gendaymtx). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/parallel.h"
#include "heliodon/sky.h"
#include "heliodon/weather.h"

void hd_daymtx_julian_days(const hd_weather *w, int *jd)
{
    int leap = 0, prev_month = 0, prev_year = 0;
    for (size_t i = 0; i < w->n; i++) {
        const hd_weather_rec *r = &w->rec[i];
        if (r->month < prev_month || (w->is_epw && r->year != prev_year && i > 0 && r->month == 1 && prev_month == 12))
            leap = 0;   /* a new year starts */
        if (r->month == 2 && r->day == 29) leap = 1;
        jd[i] = hd_julian_day(r->month, r->day) + ((leap && r->month > 2) ? 1 : 0);
        if (r->month == 2 && r->day == 29) jd[i] = 60;
        prev_month = r->month;
        prev_year = r->year;
    }
}

void hd_daymtx_result_free(hd_daymtx_result *r)
{
    free(r->data);
    free(r->steps);
    memset(r, 0, sizeof *r);
}

hd_daymtx_step hd_daymtx_step_of(const hd_weather *w, const int *jd, size_t i)
{
    const hd_weather_rec *rec = &w->rec[i];
    hd_daymtx_step t = {jd[i], rec->hour, rec->v1, rec->v2, w->units, hd_weather_dewpoint(w, i)};
    return t;
}

typedef struct gen_ctx {
    const hd_weather *w;
    const hd_daymtx_job *job;
    const hd_skybasis *b;
    const int *jd;
    hd_daymtx_result *r;
    double *sum;          /* -A: per chunk partial sums [nchunks][3*nbins] */
    size_t chunk;
    double **scratch;     /* per worker: chunk columns */
} gen_ctx;

static hd_status gen_chunk(void *vctx, size_t begin, size_t end, size_t chunk_index, int worker)
{
    gen_ctx *g = vctx;
    int nb = g->b->nbins;
    size_t ncol = end - begin;
    /* the columns of this chunk, then copied patch by patch so that each
     * patch row of the matrix receives a contiguous run of columns */
    double *cols = g->scratch[worker];
    for (size_t k = begin; k < end; k++) {
        hd_daymtx_step t = hd_daymtx_step_of(g->w, g->jd, g->r->steps[k]);
        double *col = cols + (k - begin) * (size_t)nb * 3;
        hd_daymtx_column(g->b, &g->job->o, &g->w->site, &t, col, NULL);
        if (g->sum) {
            double *s = g->sum + chunk_index * (size_t)nb * 3;
            for (int j = 0; j < 3 * nb; j++) s[j] += col[j];
        }
    }
    if (!g->sum) {
        size_t nc = (size_t)g->r->ncols;
        for (int p = 0; p < nb; p++) {
            float *d = g->r->data + ((size_t)p * nc + begin) * 3;
            for (size_t k = 0; k < ncol; k++, d += 3) {
                const double *v = cols + (k * (size_t)nb + (size_t)p) * 3;
                d[0] = (float)v[0];
                d[1] = (float)v[1];
                d[2] = (float)v[2];
            }
        }
    }
    return HD_OK;
}

static void free_scratch(gen_ctx *g, int n)
{
    if (!g->scratch) return;
    for (int t = 0; t < n; t++) free(g->scratch[t]);
    free(g->scratch);
    g->scratch = NULL;
}

/* The weather records that become columns (-u drops those with the sun
 * below -0.2665 deg), with Radiance's "unusually bright" warnings. */
static size_t select_steps(const hd_weather *w, const hd_daymtx_job *job, const int *jd, size_t *steps)
{
    size_t nsteps = 0;
    for (size_t i = 0; i < w->n; i++) {
        const hd_weather_rec *rec = &w->rec[i];
        double decl = hd_sun_declination(jd[i]);
        double alt = hd_sun_altitude(&w->site, decl, hd_daymtx_solar_time(&w->site, &job->o, jd[i], rec->hour));
        if (job->skip_night && alt < -HD_SUN_HALFANGLE_RAD) continue;
        if (job->warnings && rec->v1 + rec->v2 > 1e-4 && rec->v1 > 20 && alt < -HD_SUN_HALFANGLE_RAD &&
            hd_warnings_enabled()) {
            /* same wording as Radiance's gendaymtx */
            fprintf(stderr, "%s: warning - unusually bright at %.1f on %d-%d\n", hd_progname(), rec->hour,
                    rec->month, rec->day);
        }
        steps[nsteps++] = i;
    }
    return nsteps;
}

hd_status hd_daymtx_generate(const hd_weather *w, const hd_daymtx_job *job, hd_daymtx_result *r)
{
    hd_status st;
    if (!job->average) {   /* the compact store, expanded row by row */
        hd_daymtx_store s;
        memset(r, 0, sizeof *r);
        if ((st = hd_daymtx_compute(w, job, &s))) return st;
        size_t tot;
        if (hd_mul_overflow((size_t)s.nbins * 3, s.ncols ? (size_t)s.ncols : 1, &tot) ||
            !(r->data = hd_malloc_array(tot, sizeof(float)))) {
            hd_daymtx_store_free(&s);
            return HD_ERR_NOMEM;
        }
        r->nbins = s.nbins;
        r->ncols = s.ncols;
        for (int p = 0; p < s.nbins; p++) hd_daymtx_store_row(&s, p, r->data + (size_t)p * (size_t)s.ncols * 3);
        r->steps = s.steps;
        s.steps = NULL;
        hd_daymtx_store_free(&s);
        return HD_OK;
    }
    hd_skybasis b;
    gen_ctx g;
    memset(&g, 0, sizeof g);
    int nthreads = hd_resolve_threads(job->nthreads);
    memset(r, 0, sizeof *r);
    if ((st = hd_skybasis_init(&b, job->mf))) return st;
    int *jd = hd_malloc_array(w->n ? w->n : 1, sizeof(int));
    r->steps = hd_malloc_array(w->n ? w->n : 1, sizeof(size_t));
    if (!jd || !r->steps) { st = HD_ERR_NOMEM; goto fail; }
    hd_daymtx_julian_days(w, jd);
    size_t nsteps = select_steps(w, job, jd, r->steps);
    r->nbins = b.nbins;
    size_t chunk = 64;
    g.w = w; g.job = job; g.b = &b; g.jd = jd; g.r = r; g.chunk = chunk;
    g.scratch = hd_calloc((size_t)nthreads, sizeof(double *));
    if (!g.scratch) { st = HD_ERR_NOMEM; goto fail; }
    for (int t = 0; t < nthreads; t++)
        if (!(g.scratch[t] = hd_malloc_array((size_t)b.nbins * 3 * chunk, sizeof(double)))) {
            st = HD_ERR_NOMEM;
            goto fail;
        }
    if (job->average) {
        size_t nchunks = (nsteps + chunk - 1) / chunk;
        r->ncols = 1;
        r->naveraged = (long)nsteps;
        g.sum = hd_calloc(nchunks ? nchunks : 1, (size_t)b.nbins * 3 * sizeof(double));
        r->data = hd_calloc((size_t)b.nbins * 3, sizeof(float));
        if (!g.sum || !r->data) { free(g.sum); st = HD_ERR_NOMEM; goto fail; }
        st = hd_parallel_for(nsteps, chunk, nthreads, gen_chunk, &g);
        if (!st) {
            /* sum the chunk partial sums in chunk order: deterministic */
            for (int j = 0; j < 3 * b.nbins; j++) {
                double s = 0;
                for (size_t c = 0; c < nchunks; c++) s += g.sum[c * (size_t)b.nbins * 3 + j];
                r->data[j] = (float)(nsteps ? s / (double)nsteps : 0);
            }
        }
        free(g.sum);
        if (st) goto fail;
    } else {
        if (nsteps > (size_t)1 << 30) { st = hd_fail(HD_ERR_RANGE, "%s: too many time steps", w->name); goto fail; }
        r->ncols = (int)nsteps;
        size_t tot;
        if (hd_mul_overflow((size_t)b.nbins * 3, nsteps ? nsteps : 1, &tot)) {
            st = hd_fail(HD_ERR_NOMEM, "sky matrix too large");
            goto fail;
        }
        r->data = hd_malloc_array(tot, sizeof(float));
        if (!r->data) { st = HD_ERR_NOMEM; goto fail; }
        st = hd_parallel_for(nsteps, chunk, nthreads, gen_chunk, &g);
        if (st) goto fail;
    }
    free_scratch(&g, nthreads);
    free(jd);
    hd_skybasis_free(&b);
    return HD_OK;
fail:
    free_scratch(&g, nthreads);
    free(jd);
    hd_skybasis_free(&b);
    hd_daymtx_result_free(r);
    return st;
}

hd_status hd_daymtx_write_ascii(FILE *fp, const hd_daymtx_result *r)
{
    size_t nc = (size_t)r->ncols;
    for (int p = 0; p < r->nbins; p++) {
        const float *d = r->data + (size_t)p * nc * 3;
        for (size_t c = 0; c < nc; c++, d += 3) fprintf(fp, "%.3g %.3g %.3g\n", d[0], d[1], d[2]);
        if (nc > 1) fputc('\n', fp);
    }
    return ferror(fp) ? hd_fail(HD_ERR_IO, "write error on the sky matrix") : HD_OK;
}

hd_status hd_daymtx_write_suns(FILE *rad, FILE *mods, const hd_weather *w, const hd_daymtx_job *job,
                               const char *cmdline)
{
    int *jd = hd_malloc_array(w->n ? w->n : 1, sizeof(int));
    if (!jd) return HD_ERR_NOMEM;
    hd_daymtx_julian_days(w, jd);
    if (rad) fprintf(rad, "#\n# Sun positions generated by:\n#\t%s\n#\n\n", cmdline ? cmdline : "");
    long nsun = 0;
    double sunsa = HD_PI * HD_SUN_HALFANGLE_RAD * HD_SUN_HALFANGLE_RAD;
    for (size_t i = 0; i < w->n; i++) {
        hd_daymtx_step t = hd_daymtx_step_of(w, jd, i);
        double decl = hd_sun_declination(t.jd);
        double stime = hd_daymtx_solar_time(&w->site, &job->o, t.jd, t.hour);
        double alt = hd_sun_altitude(&w->site, decl, stime);
        double azi = hd_sun_azimuth(&w->site, decl, stime) + HD_PI - job->o.rotation_deg * HD_PI / 180;
        if (alt <= -HD_SUN_HALFANGLE_RAD) continue;
        double rad_v = 0;
        if (t.v1 + t.v2 > 1e-4 && !job->o.sky_only) {
            hd_perez p;
            hd_perez_compute(&p, alt, t.jd, t.v1, t.v2, t.units, t.dewpoint, job->o.solar_output);
            rad_v = p.dir_illum / (HD_WHTEFFICACY * sunsa);
        }
        long minute = 1440L * (t.jd - 1) + lround(60 * t.hour);
        if (rad) {
            if (nsun++) fputc('\n', rad);
            fprintf(rad, "void light solar%ld\n0\n0\n3 %.3e %.3e %.3e\n\n", minute, rad_v * job->o.suncolor[0],
                    rad_v * job->o.suncolor[1], rad_v * job->o.suncolor[2]);
            fprintf(rad, "solar%ld source sun%ld\n0\n0\n4 %f %f %f 0.5330\n", minute, minute,
                    cos(alt) * sin(azi), cos(alt) * cos(azi), sin(alt));
        }
        if (mods) fprintf(mods, "solar%ld\n", minute);
    }
    free(jd);
    if ((rad && ferror(rad)) || (mods && ferror(mods))) return hd_fail(HD_ERR_IO, "write error on the sun list");
    return HD_OK;
}

/* ---- the compact store (gendaymtx without -A) ---- */

typedef struct store_ctx {
    const hd_weather *w;
    const hd_daymtx_job *job;
    const hd_skybasis *b;
    const int *jd;
    hd_daymtx_store *s;
    const size_t *dayrec;    /* [nday] weather record of each stored column */
    double **scratch;        /* per worker: one column */
} store_ctx;

/* One block of HD_DAYMTX_BLOCK stored columns: each column is computed in
 * double (hd_daymtx_column) and rounded to float into the block, whose
 * layout is [patch][column in block][3]. */
static hd_status store_chunk(void *vctx, size_t begin, size_t end, size_t chunk_index, int worker)
{
    store_ctx *g = vctx;
    int nb = g->b->nbins;
    double *col = g->scratch[worker];
    float *blk = g->s->blk + chunk_index * (size_t)nb * HD_DAYMTX_BLOCK * 3;
    for (size_t k = begin; k < end; k++) {
        hd_daymtx_step t = hd_daymtx_step_of(g->w, g->jd, g->dayrec[k]);
        hd_daymtx_column(g->b, &g->job->o, &g->w->site, &t, col, NULL);
        float *d = blk + (k - begin) * 3;
        for (int p = 0; p < nb; p++, d += HD_DAYMTX_BLOCK * 3) {
            d[0] = (float)col[3 * p];
            d[1] = (float)col[3 * p + 1];
            d[2] = (float)col[3 * p + 2];
        }
    }
    return HD_OK;
}

void hd_daymtx_store_free(hd_daymtx_store *s)
{
    free(s->colmap);
    free(s->steps);
    free(s->blk);
    memset(s, 0, sizeof *s);
}

/* a large zero-filled float array (hd_big_alloc: transparent huge pages,
 * far fewer page faults for the ~100 MB - 1 GB of an annual MF:6 matrix) */
static float *big_floats(size_t n) { return hd_big_alloc(n ? n : 1, sizeof(float), 1); }

hd_status hd_daymtx_compute(const hd_weather *w, const hd_daymtx_job *job, hd_daymtx_store *s)
{
    hd_status st;
    hd_skybasis b;
    memset(s, 0, sizeof *s);
    int nthreads = hd_resolve_threads(job->nthreads);
    if ((st = hd_skybasis_init(&b, job->mf))) return st;
    store_ctx g;
    memset(&g, 0, sizeof g);
    size_t *dayrec = NULL;
    int *jd = hd_malloc_array(w->n ? w->n : 1, sizeof(int));
    s->steps = hd_malloc_array(w->n ? w->n : 1, sizeof(size_t));
    s->colmap = hd_malloc_array(w->n ? w->n : 1, sizeof(long));
    dayrec = hd_malloc_array(w->n ? w->n : 1, sizeof(size_t));
    if (!jd || !s->steps || !s->colmap || !dayrec) { st = HD_ERR_NOMEM; goto done; }
    hd_daymtx_julian_days(w, jd);
    size_t nsteps = select_steps(w, job, jd, s->steps);
    if (nsteps > (size_t)1 << 30) { st = hd_fail(HD_ERR_RANGE, "%s: too many time steps", w->name); goto done; }
    s->nbins = b.nbins;
    s->ncols = (int)nsteps;
    s->nthreads = nthreads;
    for (size_t k = 0; k < nsteps; k++) {
        const hd_weather_rec *rec = &w->rec[s->steps[k]];
        if (rec->v1 + rec->v2 <= 1e-4) {   /* the test of hd_daymtx_column: an all-zero column */
            s->colmap[k] = -1;
        } else {
            s->colmap[k] = (long)s->nday;
            dayrec[s->nday++] = s->steps[k];
        }
    }
    size_t nblk = (s->nday + HD_DAYMTX_BLOCK - 1) / HD_DAYMTX_BLOCK, tot;
    if (hd_mul_overflow(nblk ? nblk : 1, (size_t)b.nbins * HD_DAYMTX_BLOCK * 3, &tot)) {
        st = hd_fail(HD_ERR_NOMEM, "sky matrix too large");
        goto done;
    }
    s->blk = big_floats(tot);
    g.scratch = hd_calloc((size_t)nthreads, sizeof(double *));
    if (!s->blk || !g.scratch) { st = HD_ERR_NOMEM; goto done; }
    for (int t = 0; t < nthreads; t++)
        if (!(g.scratch[t] = hd_malloc_array((size_t)b.nbins * 3, sizeof(double)))) { st = HD_ERR_NOMEM; goto done; }
    g.w = w; g.job = job; g.b = &b; g.jd = jd; g.s = s; g.dayrec = dayrec;
    st = hd_parallel_for(s->nday, HD_DAYMTX_BLOCK, nthreads, store_chunk, &g);
done:
    if (g.scratch)
        for (int t = 0; t < nthreads; t++) free(g.scratch[t]);
    free(g.scratch);
    free(dayrec);
    free(jd);
    hd_skybasis_free(&b);
    if (st) hd_daymtx_store_free(s);
    return st;
}

void hd_daymtx_store_row(const hd_daymtx_store *s, int p, float *row)
{
    const size_t bs = (size_t)s->nbins * HD_DAYMTX_BLOCK * 3;
    const float *base = s->blk + (size_t)p * HD_DAYMTX_BLOCK * 3;
    for (int j = 0; j < s->ncols; j++, row += 3) {
        long d = s->colmap[j];
        if (d < 0) {
            row[0] = row[1] = row[2] = 0;
        } else {
            size_t u = (size_t)d;   /* unsigned: the block arithmetic becomes shifts */
            const float *v = base + u / HD_DAYMTX_BLOCK * bs + u % HD_DAYMTX_BLOCK * 3;
            row[0] = v[0];
            row[1] = v[1];
            row[2] = v[2];
        }
    }
}

/* %.3g, exactly as glibc prints it: the three significant digits are found
 * with one correctly rounded scaling by an exact power of ten; values whose
 * scaled form lies within 1e-6 of a rounding tie (where that single rounding
 * could matter), or outside 1e-22..1e22, go to snprintf. */
size_t hd_format_g3(char *buf, double x)
{
    static const double p10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
    char *q = buf;
    if (x == 0) {
        if (signbit(x)) *q++ = '-';
        *q++ = '0';
        *q = 0;
        return (size_t)(q - buf);
    }
    double ax = fabs(x);
    if (!(ax >= 1e-20 && ax <= 1e20)) goto slow;
    /* decimal exponent from the binary one (x = f 2^be, f in [0.5,1)):
     * floor((be-1) log10 2) is floor(log10 x) or one less */
    uint64_t bits;
    memcpy(&bits, &ax, sizeof bits);
    int be = (int)((bits >> 52) & 0x7ff) - 1022;
    int e = (be - 1) >= 0 ? (be - 1) * 78913 / 262144 : -((-(be - 1) * 78913 + 262143) / 262144);
    double m = 0;
    for (int tries = 0; tries < 3; tries++) {
        int k = 2 - e;
        if (k > 22 || k < -22) goto slow;   /* beyond the table (|x| near 1e-20) */
        m = k >= 0 ? ax * p10[k] : ax / p10[-k];
        if (m >= 1000) e++;
        else if (m < 100) e--;
        else break;
    }
    if (!(m >= 100 && m < 1000)) goto slow;
    int ni = (int)m;   /* m >= 100: truncation is floor */
    double frac = m - ni;
    if (fabs(frac - 0.5) < 1e-6) goto slow;
    ni += frac > 0.5;
    if (ni == 1000) { ni = 100; e++; }
    int d0 = ni / 100, d1 = ni / 10 % 10, d2 = ni % 10;
    if (x < 0) *q++ = '-';
    if (e < -4 || e >= 3) {
        *q++ = (char)('0' + d0);
        if (d1 || d2) {
            *q++ = '.';
            *q++ = (char)('0' + d1);
            if (d2) *q++ = (char)('0' + d2);
        }
        *q++ = 'e';
        *q++ = e < 0 ? '-' : '+';
        int ae = e < 0 ? -e : e;
        if (ae >= 100) *q++ = (char)('0' + ae / 100);
        *q++ = (char)('0' + ae / 10 % 10);
        *q++ = (char)('0' + ae % 10);
    } else {
        char dg[3] = {(char)('0' + d0), (char)('0' + d1), (char)('0' + d2)};
        int nd = d2 ? 3 : d1 ? 2 : 1;   /* significant digits without trailing zeros */
        if (e >= 0) {
            int ip = e + 1;   /* digits before the point */
            for (int i = 0; i < ip; i++) *q++ = dg[i];
            if (nd > ip) {
                *q++ = '.';
                for (int i = ip; i < nd; i++) *q++ = dg[i];
            }
        } else {
            *q++ = '0';
            *q++ = '.';
            for (int i = 0; i < -e - 1; i++) *q++ = '0';
            for (int i = 0; i < nd; i++) *q++ = dg[i];
        }
    }
    *q = 0;
    return (size_t)(q - buf);
slow:;
    int len = snprintf(buf, 24, "%.3g", x);
    return len > 0 ? (size_t)len : 0;
}

typedef struct write_ctx {
    const hd_daymtx_store *s;
    hd_daymtx_format fmt;
    int p0;
    char **buf;              /* per row of the batch */
    size_t *len;
    float **row;             /* per worker */
} write_ctx;

static hd_status write_rows(void *vctx, size_t begin, size_t end, size_t chunk_index, int worker)
{
    (void)chunk_index;
    write_ctx *c = vctx;
    const hd_daymtx_store *s = c->s;
    float *row = c->row[worker];
    size_t nc = (size_t)s->ncols;
    for (size_t r = begin; r < end; r++) {
        char *out = c->buf[r];
        hd_daymtx_store_row(s, c->p0 + (int)r, row);
        if (c->fmt == HD_DAYMTX_FLOAT) {
            memcpy(out, row, nc * 3 * sizeof(float));
            c->len[r] = nc * 3 * sizeof(float);
        } else if (c->fmt == HD_DAYMTX_DOUBLE) {
            double *dv = (double *)(void *)out;
            for (size_t i = 0; i < 3 * nc; i++) dv[i] = row[i];
            c->len[r] = nc * 3 * sizeof(double);
        } else {
            char *q = out;
            for (size_t j = 0; j < nc; j++) {
                if (row[3 * j] == 0 && row[3 * j + 1] == 0 && row[3 * j + 2] == 0 && !signbit(row[3 * j]) &&
                    !signbit(row[3 * j + 1]) && !signbit(row[3 * j + 2])) {
                    memcpy(q, "0 0 0\n", 6);   /* night columns */
                    q += 6;
                    continue;
                }
                q += hd_format_g3(q, row[3 * j]);
                *q++ = ' ';
                q += hd_format_g3(q, row[3 * j + 1]);
                *q++ = ' ';
                q += hd_format_g3(q, row[3 * j + 2]);
                *q++ = '\n';
            }
            if (nc > 1) *q++ = '\n';
            c->len[r] = (size_t)(q - out);
        }
    }
    return HD_OK;
}

hd_status hd_daymtx_store_write(FILE *fp, const hd_daymtx_store *s, hd_daymtx_format fmt)
{
    enum { BATCH = 32 };
    size_t nc = (size_t)s->ncols, rowbytes;
    int nthreads = s->nthreads > 0 ? s->nthreads : 1;
    /* ascii: at most 24 bytes per number (snprintf fallback) + separators */
    size_t per = fmt == HD_DAYMTX_FLOAT ? 3 * sizeof(float) : fmt == HD_DAYMTX_DOUBLE ? 3 * sizeof(double) : 3 * 25;
    if (hd_mul_overflow(nc ? nc : 1, per, &rowbytes)) return hd_fail(HD_ERR_NOMEM, "sky matrix row too large");
    rowbytes = (rowbytes + 2 + 15) / 16 * 16;   /* keeps every row buffer aligned for doubles */
    write_ctx c;
    memset(&c, 0, sizeof c);
    c.s = s;
    c.fmt = fmt;
    hd_status st = HD_OK;
    char *mem = hd_malloc_array(BATCH, rowbytes);
    c.buf = hd_calloc(BATCH, sizeof(char *));
    c.len = hd_calloc(BATCH, sizeof(size_t));
    c.row = hd_calloc((size_t)nthreads, sizeof(float *));
    if (!mem || !c.buf || !c.len || !c.row) { st = HD_ERR_NOMEM; goto done; }
    for (int t = 0; t < nthreads; t++)
        if (!(c.row[t] = hd_malloc_array((nc ? nc : 1) * 3, sizeof(float)))) { st = HD_ERR_NOMEM; goto done; }
    for (int i = 0; i < BATCH; i++) c.buf[i] = mem + (size_t)i * rowbytes;
    for (int p0 = 0; p0 < s->nbins && !st; p0 += BATCH) {
        int n = s->nbins - p0 < BATCH ? s->nbins - p0 : BATCH;
        c.p0 = p0;
        /* rows are independent: any thread count gives the same bytes */
        st = hd_parallel_for((size_t)n, 4, nthreads, write_rows, &c);
        for (int r = 0; r < n && !st; r++)
            if (c.len[r] && fwrite(c.buf[r], 1, c.len[r], fp) != c.len[r])
                st = hd_fail(HD_ERR_IO, "write error on the sky matrix");
    }
done:
    if (c.row)
        for (int t = 0; t < nthreads; t++) free(c.row[t]);
    free(c.row);
    free(c.buf);
    free(c.len);
    free(mem);
    return st;
}

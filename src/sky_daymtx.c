/* heliodon — whole sky matrices over a weather file (gendaymtx). */
#include <math.h>
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
        size_t i = g->r->steps[k];
        const hd_weather_rec *rec = &g->w->rec[i];
        hd_daymtx_step t;
        t.jd = g->jd[i];
        t.hour = rec->hour;
        t.v1 = rec->v1;
        t.v2 = rec->v2;
        t.units = g->w->units;
        t.dewpoint = hd_weather_dewpoint(g->w, i);
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

hd_status hd_daymtx_generate(const hd_weather *w, const hd_daymtx_job *job, hd_daymtx_result *r)
{
    hd_status st;
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
        r->steps[nsteps++] = i;
    }
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
        const hd_weather_rec *rec = &w->rec[i];
        hd_daymtx_step t = {jd[i], rec->hour, rec->v1, rec->v2, w->units, hd_weather_dewpoint(w, i)};
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

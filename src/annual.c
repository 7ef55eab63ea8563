/* heliodon — annual PM-CBDM composition with streaming glare evaluation
 * (see annual.h). */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "annual_pieces.h"
#include "heliodon/annual.h"
#include "heliodon/basis.h"
#include "heliodon/dctimestep.h"
#include "heliodon/exr.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/matrix.h"
#include "heliodon/parallel.h"
#include "heliodon/picture.h"
#include "heliodon/sky.h"
#include "heliodon/suns.h"
#include "heliodon/weather.h"

void hd_annual_opts_default(hd_annual_opts *o)
{
    memset(o, 0, sizeof *o);
    o->sun_mf = 1;
    o->sky_mf = 1;
    hd_view_default(&o->view);
    hd_glare_opts_default(&o->glare);
    o->shade_limit = HD_GLARE_SHADE_LIMIT;
}

static double now_sec(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

typedef struct actx {
    const hd_annual_opts *o;
    int xres, yres;
    size_t npix;
    int nsky;
    int ncomp;             /* coefficient images folded: nsky, or 2 nsky with the
                              direct-sun terms (csky[nsky + b], sun-only vector, minus) */
    float **csky;          /* [ncomp] composite sky coefficients, planar
                              (3 planes of npad floats, dctimestep's layout) */
    int nsunbins;
    /* DC_sun pictures are read when the first hour of their patch is composed
     * and freed after its last: the hours are composed in sun-patch order
     * (order[]), so only the patches of the hours in flight are held */
    float **sun;           /* [nsunbins] DC_sun of the patches in memory (NULL: not held) */
    unsigned char *sunneed;/* [nsunbins] 1: some hour has its sun in this patch */
    long *sunleft;         /* [nsunbins] hours of the patch not yet composed */
    unsigned char *sunstate; /* [nsunbins] SUN_IDLE / SUN_LOADING / SUN_HELD / SUN_FAILED */
    unsigned char *fmask;  /* -Fs: the fenestration mask (NULL: none) */
    int sunheld, sunheld_max;  /* patches in memory now, at most */
    pthread_mutex_t sunmu;
    pthread_cond_t suncv;
    int sunsync;           /* sunmu / suncv initialised */
    long *order;           /* [nrec] composition order: hours sorted by sun patch */
    hd_glare_geom *geom;
    hd_weather w;
    int *jd;
    long *recs;            /* evaluated record indices */
    long nrec;
    int *sunbin;           /* [nrec] sun patch (0 = no sun) */
    double *gsun;          /* [nsunbins] sunlit ground fraction (NULL: 1) */
    double *sunrgb;        /* [nrec*3] */
    hd_skybasis skyb;
    hd_daymtx_opts skyopt;
    hd_daymtx_opts skyopt_d;   /* the sun-only vector of the direct-sun terms (gendaymtx -d) */
    hd_glare_result *res;  /* [nrec] */
    double *meanlum;       /* [nrec] */
    float *illum;          /* [nrec*npix] sensor mode: lux per point */
    int noglare;
    long piece_first, piece_total;   /* -H: the piece's first hour, all daylight hours */
    int nthreads;
    float **wbuf;          /* per worker: rgb */
    float **wlum;
    double **wcol;
    double **wcoef;        /* per worker: nsky x FOLD_HOURS x 3 coefficients */
    float **wfold;         /* per worker: FOLD_HOURS x 3 planes of npad */
} actx;

/* Hours folded together by dctimestep's kernels (one register tile of
 * time steps); the sum over sky bins is the same float sum in the same
 * order as one hour at a time. */
enum { FOLD_HOURS = 6 };

static size_t npad(const actx *a) { return (a->npix + 15) & ~(size_t)15; }

/* An interleaved RGB picture's pixels as a planar component (zero padded). */
static float *planar_of(const actx *a, const float *pix)
{
    size_t np = npad(a);
    float *f = hd_calloc(3 * np, sizeof(float));
    if (!f) return NULL;
    for (size_t i = 0; i < a->npix; i++)
        for (int c = 0; c < 3; c++) f[(size_t)c * np + i] = pix[3 * i + c];
    return f;
}

/* A coefficient picture's size and format: the first one read sets the
 * size, every other must have it; RGB only. */
static hd_status check_size_fmt(actx *a, const char *path, int xres, int yres, hd_picfmt fmt)
{
    if (a->xres == 0) {
        a->xres = xres;
        a->yres = yres;
        a->npix = (size_t)xres * (size_t)yres;
    } else if (xres != a->xres || yres != a->yres) {
        return hd_fail(HD_ERR_FORMAT, "%s: picture is %d x %d, expected %d x %d like the other coefficient pictures",
                       path, xres, yres, a->xres, a->yres);
    }
    if (fmt != HD_PIC_RGBE) return hd_fail(HD_ERR_FORMAT, "%s: expected an RGB picture (32-bit_rle_rgbe)", path);
    return HD_OK;
}

static hd_status load_pic(actx *a, const char *path, hd_picture *p)
{
    if (access(path, R_OK) != 0) return hd_fail(HD_ERR_IO, "%s: cannot read this coefficient picture", path);
    hd_status st = hd_picture_read(path, p);
    if (st) return st;
    if ((st = check_size_fmt(a, path, p->xres, p->yres, p->fmt))) hd_picture_free(p);
    return st;
}

static hd_status pat_path(char *buf, size_t cap, const char *pat, long idx, const char *what)
{
    int k = hd_pattern_kind(pat);
    if (k < 0) return HD_ERR_USAGE;
    if (!(k & 1) || (k & 2))
        return hd_fail(HD_ERR_USAGE, "%s pattern '%s': expected exactly one integer conversion (%%d) and no %%s",
                       what, pat);
    return hd_pattern_format(buf, cap, pat, NULL, idx);
}

/* Take ownership of a picture's pixels as a coefficient array. */
static float *take_pixels(hd_picture *p)
{
    float *f = p->pix;
    p->pix = NULL;
    hd_picture_free(p);
    return f;
}

/* mask picture -> 0/1 per pixel (size checked against the other pictures) */
static hd_status load_mask(actx *a, unsigned char **out, size_t *nm)
{
    hd_picture p;
    hd_status st = load_pic(a, a->o->mask, &p);
    if (st) return st;
    unsigned char *mask = hd_malloc(a->npix);
    if (!mask) {
        hd_picture_free(&p);
        return HD_ERR_NOMEM;
    }
    size_t n = 0;
    for (size_t i = 0; i < a->npix; i++) n += mask[i] = p.pix[3 * i] > 0.5f;
    hd_picture_free(&p);
    *out = mask;
    if (nm) *nm = n;
    return HD_OK;
}

/* Three-phase terms (V pictures per Klems patch times a T*D matrix) added
 * into the nsky planar coefficient images dst. */
static hd_status add_terms(actx *a, float **dst, int nterms, const char *const *pats, const char *const *mats)
{
    const hd_annual_opts *o = a->o;
    char path[4096];
    hd_status st;
    hd_picture p;
    for (int t = 0; t < nterms; t++) {
        hd_matrix td;
        hd_matrix_init(&td);
        if ((st = hd_matrix_read(mats[t], &td, NULL))) return st;
        if (td.ncols != a->nsky || (td.ncomp != 3 && td.ncomp != 1)) {
            hd_matrix_free(&td);
            return hd_fail(HD_ERR_FORMAT, "%s: T*D matrix has %d columns x %d components, expected %d sky bins "
                           "(MF:%d) with 1 or 3 components", mats[t], td.ncols, td.ncomp, a->nsky, o->sky_mf);
        }
        for (int k = 0; k < td.nrows; k++) {
            if ((st = pat_path(path, sizeof path, pats[t], k, "view matrix")) ||
                (st = load_pic(a, path, &p))) {
                hd_matrix_free(&td);
                return st;
            }
            for (int b = 0; b < a->nsky; b++) {
                if (!dst[b] && !(dst[b] = hd_calloc(3 * npad(a), sizeof(float)))) {
                    hd_picture_free(&p);
                    hd_matrix_free(&td);
                    return HD_ERR_NOMEM;
                }
                const double *m = hd_matrix_at(&td, k, b);
                float f[3];
                for (int c = 0; c < 3; c++) f[c] = (float)m[td.ncomp == 3 ? c : 0];
                if (f[0] == 0 && f[1] == 0 && f[2] == 0) continue;
                float *d = dst[b];
                size_t np = npad(a);
                for (size_t i = 0; i < a->npix; i++)
                    for (int c = 0; c < 3; c++) d[(size_t)c * np + i] += p.pix[3 * i + c] * f[c];
            }
            hd_picture_free(&p);
        }
        hd_matrix_free(&td);
    }
    return HD_OK;
}

/* ---- DC_sun pictures held only while their hours are composed ---- */
enum { SUN_IDLE = 0, SUN_LOADING, SUN_HELD, SUN_FAILED };

/* DC_sun of patch b, with the refined fenestration sun DC inside the mask (-Fs). */
static hd_status read_sun(actx *a, int b, float **out)
{
    const hd_annual_opts *o = a->o;
    char path[4096];
    hd_picture p;
    hd_status st;
    if ((st = pat_path(path, sizeof path, o->sun_pattern, b, "sun DC")) || (st = load_pic(a, path, &p))) return st;
    float *sun = take_pixels(&p);
    if (o->fensun_pattern) {
        if ((st = pat_path(path, sizeof path, o->fensun_pattern, b, "fenestration sun DC")) ||
            (st = load_pic(a, path, &p))) {
            free(sun);
            return st;
        }
        for (size_t i = 0; i < a->npix; i++)
            if (a->fmask[i])
                for (int c = 0; c < 3; c++) sun[3 * i + c] = p.pix[3 * i + c];
        hd_picture_free(&p);
    }
    *out = sun;
    return HD_OK;
}

/* The DC_sun of patch b for one hour (read by the first worker that needs it;
 * the others wait); every sun_get is followed by one sun_put. */
static hd_status sun_get(actx *a, int b, const float **out)
{
    pthread_mutex_lock(&a->sunmu);
    while (a->sunstate[b] == SUN_LOADING) pthread_cond_wait(&a->suncv, &a->sunmu);
    if (a->sunstate[b] == SUN_HELD) {
        *out = a->sun[b];
        pthread_mutex_unlock(&a->sunmu);
        return HD_OK;
    }
    if (a->sunstate[b] == SUN_FAILED) {
        pthread_mutex_unlock(&a->sunmu);
        return hd_fail(HD_ERR_IO, "sun patch %d: its coefficient picture could not be read (see the first error)", b);
    }
    a->sunstate[b] = SUN_LOADING;
    pthread_mutex_unlock(&a->sunmu);
    float *pic = NULL;
    hd_status st = read_sun(a, b, &pic);
    pthread_mutex_lock(&a->sunmu);
    a->sun[b] = pic;
    a->sunstate[b] = st ? SUN_FAILED : SUN_HELD;
    if (!st && ++a->sunheld > a->sunheld_max) a->sunheld_max = a->sunheld;
    pthread_cond_broadcast(&a->suncv);
    pthread_mutex_unlock(&a->sunmu);
    *out = pic;
    return st;
}

/* One hour of patch b is composed: the picture is freed after the patch's last hour. */
static void sun_put(actx *a, int b)
{
    pthread_mutex_lock(&a->sunmu);
    if (--a->sunleft[b] == 0 && a->sunstate[b] == SUN_HELD) {
        free(a->sun[b]);
        a->sun[b] = NULL;
        a->sunstate[b] = SUN_IDLE;
        a->sunheld--;
    }
    pthread_mutex_unlock(&a->sunmu);
}

/* A needed picture's header: readable, RGB, the size of the others (checked
 * before the long loop; the pixels are read when the patch's hours come). */
static hd_status check_pic(actx *a, const char *path)
{
    hd_istream *s;
    if (access(path, R_OK) != 0 || hd_istream_open(&s, path))
        return hd_fail(HD_ERR_IO, "%s: cannot read this coefficient picture", path);
    hd_header h;
    hd_picfmt fmt;
    hd_resolu r;
    hd_status st = hd_picture_read_header(s, &h, &fmt, &r);
    hd_istream_close(s);
    if (st) return st;
    hd_header_free(&h);
    return check_size_fmt(a, path, r.xres, r.yres, fmt);
}

/* Composition order: the hours grouped by sun patch, record order within a
 * patch (a counting sort on the patch). */
static hd_status make_order(actx *a)
{
    int nb = a->nsunbins > 0 ? a->nsunbins : 1;   /* no sun: every hour in "patch" 0 */
    long *start = hd_calloc((size_t)nb + 1, sizeof(long));
    a->order = hd_malloc_array((size_t)a->nrec, sizeof(long));
    if (!start || !a->order) {
        free(start);
        return HD_ERR_NOMEM;
    }
    for (long r = 0; r < a->nrec; r++) start[a->sunbin[r] + 1]++;
    for (int b = 0; b < nb; b++) start[b + 1] += start[b];
    for (long r = 0; r < a->nrec; r++) a->order[start[a->sunbin[r]]++] = r;
    free(start);
    return HD_OK;
}

static hd_status load_sky(actx *a)
{
    const hd_annual_opts *o = a->o;
    char path[4096];
    hd_status st;
    hd_picture p;
    int any = o->sky_pattern || o->nterms > 0;
    if (!any && !o->fen_pattern) return HD_OK;
    if (!any) return hd_fail(HD_ERR_USAGE, "a fenestration DC (-F) needs the sky coefficients outside the mask (-k or -V)");
    if ((o->fen_pattern != NULL) != (o->mask != NULL))
        return hd_fail(HD_ERR_USAGE, "the refined fenestration DC and its mask go together (-F with -K)");
    a->ncomp = a->nsky * (o->ndterms ? 2 : 1);
    a->csky = hd_calloc((size_t)a->ncomp, sizeof(float *));
    if (!a->csky) return HD_ERR_NOMEM;
    if (o->sky_pattern) {
        for (int b = 0; b < a->nsky; b++) {
            if ((st = pat_path(path, sizeof path, o->sky_pattern, b, "sky DC"))) return st;
            if ((st = load_pic(a, path, &p))) return st;
            a->csky[b] = planar_of(a, p.pix);
            hd_picture_free(&p);
            if (!a->csky[b]) return HD_ERR_NOMEM;
        }
    }
    if ((st = add_terms(a, a->csky, o->nterms, o->v_pattern, o->td_matrix)) ||
        (st = add_terms(a, a->csky + a->nsky, o->ndterms, o->vd_pattern, o->tdd_matrix)))
        return st;
    if (o->fen_pattern) {
        unsigned char *mask;
        size_t nm;
        if ((st = load_mask(a, &mask, &nm))) return st;
        if (o->verbose) fprintf(stderr, "%s: mask %s: %zu of %zu pixels see the fenestration\n", hd_progname(), o->mask, nm, a->npix);
        for (int b = 0; b < a->nsky; b++) {
            if ((st = pat_path(path, sizeof path, o->fen_pattern, b, "fenestration DC")) ||
                (st = load_pic(a, path, &p))) {
                free(mask);
                return st;
            }
            if (!a->csky[b] && !(a->csky[b] = hd_calloc(3 * npad(a), sizeof(float)))) {
                free(mask);
                hd_picture_free(&p);
                return HD_ERR_NOMEM;
            }
            for (size_t i = 0; i < a->npix; i++)
                if (mask[i])
                    for (int c = 0; c < 3; c++) a->csky[b][(size_t)c * npad(a) + i] = p.pix[3 * i + c];
            hd_picture_free(&p);
        }
        free(mask);
    }
    return HD_OK;
}

/* Sky coefficients of record r (3 x nsky) into col. */
static void sky_column(actx *a, size_t r, double *col)
{
    long i = a->recs[r];
    hd_daymtx_step t = hd_daymtx_step_of(&a->w, a->jd, (size_t)i);
    hd_daymtx_info inf;
    hd_daymtx_column(&a->skyb, &a->skyopt, &a->w.site, &t, col, &inf);
    if (a->gsun && a->sunbin[r] > 0 && inf.alt > 0) {
        /* the ground bin holds rho (E_diff + E_dir sin alt) / pi: keep the sunlit
         * fraction of its sun term */
        double e = inf.dir_illum * sin(inf.alt) / HD_PI / HD_WHTEFFICACY * (1 - a->gsun[a->sunbin[r]]);
        for (int c = 0; c < 3; c++) col[c] = fmax(0, col[c] - e * a->skyopt.grefl[c]);
    }
}

static hd_status hour_chunk(void *vctx, size_t begin, size_t end, size_t chunk, int worker)
{
    (void)chunk;
    actx *a = vctx;
    const hd_annual_opts *o = a->o;
    float *rgb = a->wbuf[worker], *lum = a->wlum[worker], *fold = a->wfold[worker];
    double *col = a->wcol[worker], *coef = a->wcoef[worker];
    size_t np = npad(a);
    int sky = a->nsky > 0 && a->csky;
    for (size_t r0 = begin; r0 < end; r0 += FOLD_HOURS) {
      int nh = end - r0 < FOLD_HOURS ? (int)(end - r0) : FOLD_HOURS;
      if (sky) {   /* the sky part of nh hours: dctimestep's fold */
        for (int h = 0; h < nh; h++) {
            sky_column(a, (size_t)a->order[r0 + (size_t)h], col);
            for (int b = 0; b < a->nsky; b++)
                for (int c = 0; c < 3; c++) coef[((size_t)b * (size_t)nh + (size_t)h) * 3 + (size_t)c] = col[3 * b + c];
            if (a->ncomp > a->nsky) {   /* direct-sun terms: minus the sun-only vector */
                hd_daymtx_step t = hd_daymtx_step_of(&a->w, a->jd, (size_t)a->recs[a->order[r0 + (size_t)h]]);
                hd_daymtx_column(&a->skyb, &a->skyopt_d, &a->w.site, &t, col, NULL);
                for (int b = 0; b < a->nsky; b++)
                    for (int c = 0; c < 3; c++)
                        coef[((size_t)(a->nsky + b) * (size_t)nh + (size_t)h) * 3 + (size_t)c] = -col[3 * b + c];
            }
        }
        hd_status st = hd_dcts_fold(a->csky, a->ncomp, coef, nh, np, fold, 1);
        if (st) return st;
      }
      for (size_t j = r0; j < r0 + (size_t)nh; j++) {
        size_t r = (size_t)a->order[j];
        long i = a->recs[r];
        const hd_weather_rec *rec = &a->w.rec[i];
        if (sky) {
            const float *f = fold + (j - r0) * 3 * np;
            for (size_t k = 0; k < a->npix; k++)
                for (int c = 0; c < 3; c++) rgb[3 * k + c] = f[(size_t)c * np + k];
        } else {
            memset(rgb, 0, sizeof(float) * 3 * a->npix);
        }
        int sb = a->sunbin[r];
        if (sb > 0 && a->sunneed) {
            const float *s = NULL;
            hd_status st = sun_get(a, sb, &s);
            if (st) return st;
            float f[3] = {(float)a->sunrgb[3 * r], (float)a->sunrgb[3 * r + 1], (float)a->sunrgb[3 * r + 2]};
            for (size_t k = 0; k < a->npix; k++)
                for (int c = 0; c < 3; c++) rgb[3 * k + c] += s[3 * k + c] * f[c];
            sun_put(a, sb);
        }
        if (a->ncomp > a->nsky)   /* I_3PM - I_sun,3PM + I_sun: no negative pixel, as in an RGBE picture */
            for (size_t k = 0; k < 3 * a->npix; k++)
                if (!(rgb[k] > 0)) rgb[k] = 0;
        double sum = 0;
        for (size_t k = 0; k < a->npix; k++) {
            lum[k] = (float)hd_glare_luminance(rgb + 3 * k);
            sum += lum[k];
        }
        a->meanlum[r] = sum / (double)a->npix;
        if (a->illum)
            for (size_t k = 0; k < a->npix; k++) a->illum[(size_t)r * a->npix + k] = lum[k];
        hd_status st = a->noglare ? HD_OK : hd_glare_eval_lum(a->geom, lum, &o->glare, &a->res[r]);
        if (st) return st;
        free(a->res[r].sources);
        a->res[r].sources = NULL;
        free(a->res[r].source_map);
        a->res[r].source_map = NULL;
        if (o->image_pattern) {
            char path[4096];
            if ((st = pat_path(path, sizeof path, o->image_pattern, i, "hourly image"))) return st;
            hd_picture p;
            hd_picture_init(&p);
            p.xres = a->xres;
            p.yres = a->yres;
            p.pix = rgb;
            p.fmt = HD_PIC_RGBE;
            hd_header h;
            hd_header_init(&h);
            char vbuf[512];
            hd_glare_view_format(vbuf, sizeof vbuf, &o->view);
            if (o->argc) hd_annual_header_command(&h, o);   /* without -H: a piece's images are the whole run's */
            hd_header_add_software(&h);
            if (o->have_view) hd_header_appendf(&h, "VIEW= %s", vbuf);
            hd_header_appendf(&h, "HOUR= %ld %d %d %.3f", i, rec->month, rec->day, rec->hour);
            if (o->image_exr) {
                hd_exr_image img;
                hd_exr_init(&img);
                p.hdr = h;
                st = hd_exr_from_picture(&img, &p, NULL, HD_EXR_HALF, 1.0);
                if (!st) st = hd_exr_save(path, &img, HD_EXR_ZIP);
                hd_exr_free(&img);
            } else {
                st = hd_picture_save(path, &p, &h);
            }
            hd_header_free(&h);
            if (st) return st;
        }
      }
    }
    return HD_OK;
}

/* "patch fraction" lines (# comments, blank lines): the sunlit fraction of the
 * exterior ground per sun patch; patches not listed keep 1. */
static hd_status load_ground_sun(actx *a, const char *path)
{
    FILE *fp = fopen(path, "r");
    if (!fp) return hd_fail(HD_ERR_IO, "%s: cannot read the sunlit ground fractions", path);
    a->gsun = hd_malloc_array((size_t)a->nsunbins, sizeof(double));
    if (!a->gsun) {
        fclose(fp);
        return HD_ERR_NOMEM;
    }
    for (int b = 0; b < a->nsunbins; b++) a->gsun[b] = 1;
    char line[512];
    unsigned long ln = 0;
    hd_status st = HD_OK;
    while (!st && fgets(line, sizeof line, fp)) {
        ln++;
        char *p = line + strspn(line, " \t\r\n");
        if (!*p || *p == '#') continue;
        long patch;
        double f;
        char extra;
        if (sscanf(p, "%ld %lf %c", &patch, &f, &extra) != 2)
            st = hd_fail(HD_ERR_FORMAT, "%s: line %lu: expected 'patch fraction'", path, ln);
        else if (patch < 1 || patch >= a->nsunbins)
            st = hd_fail(HD_ERR_RANGE, "%s: line %lu: sun patch %ld outside 1..%d (Reinhart MF of -m)", path, ln, patch,
                         a->nsunbins - 1);
        else if (!(f >= 0 && f <= 1 + 1e-6))
            st = hd_fail(HD_ERR_RANGE, "%s: line %lu: fraction %g outside 0..1", path, ln, f);
        else
            a->gsun[patch] = fmin(1, f);
    }
    fclose(fp);
    return st;
}

static void actx_free(actx *a)
{
    if (a->csky)
        for (int b = 0; b < a->ncomp; b++) free(a->csky[b]);
    free(a->csky);
    if (a->sun)
        for (int b = 0; b < a->nsunbins; b++) free(a->sun[b]);
    free(a->sun);
    free(a->sunneed);
    free(a->sunleft);
    free(a->sunstate);
    free(a->fmask);
    free(a->order);
    if (a->sunsync) {
        pthread_mutex_destroy(&a->sunmu);
        pthread_cond_destroy(&a->suncv);
    }
    if (a->geom) hd_glare_geom_free(a->geom);
    free(a->jd);
    free(a->recs);
    free(a->sunbin);
    free(a->gsun);
    free(a->sunrgb);
    free(a->res);
    free(a->meanlum);
    free(a->illum);
    if (a->wbuf)
        for (int k = 0; k < a->nthreads; k++) {
            free(a->wbuf[k]);
            free(a->wlum[k]);
            free(a->wcol[k]);
            free(a->wcoef[k]);
            free(a->wfold[k]);
        }
    free(a->wbuf);
    free(a->wlum);
    free(a->wcol);
    free(a->wcoef);
    free(a->wfold);
    if (a->skyb.nbins) hd_skybasis_free(&a->skyb);
    hd_weather_free(&a->w);
}

static hd_status write_log(actx *a)
{
    const hd_annual_opts *o = a->o;
    hd_skybasis sb;
    hd_status st = hd_skybasis_init(&sb, o->sun_mf);
    if (st) return st;
    hd_ofile *of;
    if ((st = hd_ofile_open(&of, o->hourlog))) {
        hd_skybasis_free(&sb);
        return st;
    }
    FILE *fp = hd_ofile_fp(of);
    hd_annual_piece_lines(fp, o, a->piece_first, a->nrec, a->piece_total);
    fprintf(fp, "%s\n", HD_ANNUAL_LOG_HEADER);
    for (long r = 0; r < a->nrec; r++) {
        long i = a->recs[r];
        const hd_weather_rec *rec = &a->w.rec[i];
        int b = o->sun_pattern ? a->sunbin[r] : 0;
        hd_vec3 d = b > 0 ? sb.dir[b] : hd_v3(0, 0, 0);
        fprintf(fp, "%ld %d %d %.3f %d %.6f %.6f %.6f %.6g %.6g %.6g %.6g %.6f\n", i, rec->month, rec->day, rec->hour, b,
                d.x, d.y, d.z, a->sunrgb[3 * r], a->sunrgb[3 * r + 1], a->sunrgb[3 * r + 2], a->meanlum[r], a->res[r].dgp);
    }
    hd_skybasis_free(&sb);
    return hd_ofile_commit(of);
}

static hd_status run(actx *a, hd_annual_stats *stats)
{
    const hd_annual_opts *o = a->o;
    hd_status st;
    double t0 = now_sec();
    if (!o->weather) return hd_fail(HD_ERR_USAGE, "no weather file given");
    if (!o->preflight && !o->sun_pattern && !o->sky_pattern && o->nterms == 0)
        return hd_fail(HD_ERR_USAGE, "nothing to compose: give sun coefficients (-s) and/or sky coefficients (-k, -V)");
    a->noglare = o->no_glare || o->illum_csv;
    if (!a->noglare && o->have_view && (st = hd_glare_view_check(&o->view))) return st;
    if (!a->noglare && !o->have_view) return hd_fail(HD_ERR_USAGE, "no view given (-vf file or -vta ... options): the glare "
                                      "evaluation needs the 180-degree fisheye view of the coefficient pictures");
    /* patterns checked before anything is read */
    if (o->fensun_pattern && (!o->sun_pattern || !o->mask))
        return hd_fail(HD_ERR_USAGE, "the refined fenestration sun DC (-Fs) needs the sun DC (-s) and the mask (-K)");
    if (o->sky_sun && o->sun_pattern && o->ndterms == 0)
        return hd_fail(HD_ERR_USAGE, "the sky vectors with the sun in their patches (-sunsky) and the sun DC (-s) "
                       "would count the direct sun twice: give one of them (or subtract the three-phase direct sun, -Vd)");
    if (o->ndterms > 0 && !o->sky_sun)
        return hd_fail(HD_ERR_USAGE, "the direct-sun terms (-Vd) subtract the sun of the three-phase sky vectors: "
                       "they need -sunsky");
    if (o->ndterms > 0 && o->nterms == 0 && !o->sky_pattern)
        return hd_fail(HD_ERR_USAGE, "the direct-sun terms (-Vd) are subtracted from the three-phase image: give -V (or -k)");
    if (o->ground_sun && !o->sun_pattern)
        return hd_fail(HD_ERR_USAGE, "the sunlit ground fractions (-G) are per sun patch: they need the sun DC (-s)");
    const char *pats[5] = {o->sun_pattern, o->sky_pattern, o->fen_pattern, o->image_pattern, o->fensun_pattern};
    for (int k = 0; k < 5; k++)
        if (pats[k]) {
            int kind = hd_pattern_kind(pats[k]);
            if (kind < 0) return HD_ERR_USAGE;
            if (kind != 1) return hd_fail(HD_ERR_USAGE, "pattern '%s': expected exactly one %%d", pats[k]);
        }
    hd_weather_init(&a->w);
    if ((st = hd_weather_read(o->weather, &a->w))) return st;
    size_t nw = a->w.n;
    a->jd = hd_malloc_array(nw ? nw : 1, sizeof(int));
    a->recs = hd_malloc_array(nw ? nw : 1, sizeof(long));
    if (!a->jd || !a->recs) return HD_ERR_NOMEM;
    hd_daymtx_julian_days(&a->w, a->jd);
    unsigned char *want = NULL;
    if (o->records) {
        want = hd_calloc(nw ? nw : 1, 1);
        if (!want) return HD_ERR_NOMEM;
        for (int k = 0; k < o->nrecords; k++) {
            if (o->records[k] < 0 || (size_t)o->records[k] >= nw) {
                free(want);
                return hd_fail(HD_ERR_RANGE, "record %ld out of range: %s has %zu records (0..%zu)", o->records[k],
                               o->weather, nw, nw ? nw - 1 : 0);
            }
            want[o->records[k]] = 1;
        }
    }
    a->nrec = 0;
    for (size_t i = 0; i < nw; i++)
        if ((!want || want[i]) && hd_suns_daylight(&a->w, i, a->jd, NULL)) a->recs[a->nrec++] = (long)i;
    free(want);
    if (a->nrec == 0)
        return hd_fail(HD_ERR_FORMAT, "%s: no daylight hours%s (sun above the horizon with non-zero radiation): "
                       "nothing to evaluate", o->weather, o->records ? " among the selected records" : "");
    if ((st = hd_annual_piece_slice(o, a->recs, &a->nrec, &a->piece_first, &a->piece_total))) return st;
    if (o->piece_n > 0 && !a->noglare && !o->summary)
        return hd_fail(HD_ERR_USAGE, "-H: a glare piece needs its summary (-S), the record the join reads");
    if (o->preflight) {
        stats->nrecords = (long)nw;
        stats->ndaylight = a->nrec;
        return HD_OK;
    }
    /* sun patch of every hour, and the files it needs */
    a->sunbin = hd_calloc((size_t)a->nrec, sizeof(int));
    a->sunrgb = hd_calloc((size_t)a->nrec * 3, sizeof(double));
    a->res = hd_calloc((size_t)a->nrec, sizeof(hd_glare_result));
    a->meanlum = hd_calloc((size_t)a->nrec, sizeof(double));
    if (!a->sunbin || !a->sunrgb || !a->res || !a->meanlum) return HD_ERR_NOMEM;
    if ((st = hd_skybasis_init(&a->skyb, o->sky_mf))) return st;
    a->nsky = a->skyb.nbins;
    hd_daymtx_opts_default(&a->skyopt);
    a->skyopt.sky_only = !o->sky_sun;
    hd_daymtx_opts_default(&a->skyopt_d);
    a->skyopt_d.sun_only = 1;
    char path[4096];
    if (o->sun_pattern) {
        hd_skybasis sb;
        if ((st = hd_skybasis_init(&sb, o->sun_mf))) return st;
        hd_daymtx_opts so;
        hd_daymtx_opts_default(&so);
        so.sun_only = 1;
        so.disk_deg = HD_SUN_DIAMETER;
        so.nsuns = 1;
        a->nsunbins = sb.nbins;
        if (o->ground_sun && (st = load_ground_sun(a, o->ground_sun))) {
            hd_skybasis_free(&sb);
            return st;
        }
        double *col = hd_malloc_array((size_t)sb.nbins * 3, sizeof(double));
        a->sun = hd_calloc((size_t)sb.nbins, sizeof(float *));
        unsigned char *need = hd_calloc((size_t)sb.nbins, 1);
        if (!col || !a->sun || !need) {
            free(col);
            free(need);
            hd_skybasis_free(&sb);
            return HD_ERR_NOMEM;
        }
        for (long r = 0; r < a->nrec; r++) {
            long i = a->recs[r];
            hd_daymtx_step t = hd_daymtx_step_of(&a->w, a->jd, (size_t)i);
            hd_daymtx_column(&sb, &so, &a->w.site, &t, col, NULL);
            for (int b = 1; b < sb.nbins; b++)
                if (col[3 * b] > 0 || col[3 * b + 1] > 0 || col[3 * b + 2] > 0) {
                    a->sunbin[r] = b;
                    for (int c = 0; c < 3; c++) a->sunrgb[3 * r + c] = col[3 * b + c];
                    need[b] = 1;
                    break;
                }
        }
        free(col);
        hd_skybasis_free(&sb);
        /* every needed file must exist before the long part starts */
        for (int b = 1; b < a->nsunbins && !st; b++) {
            if (!need[b]) continue;
            stats->nsun++;
            if ((st = pat_path(path, sizeof path, o->sun_pattern, b, "sun DC"))) break;
            if (access(path, R_OK) != 0) {
                long r = 0;
                while (r < a->nrec && a->sunbin[r] != b) r++;
                const hd_weather_rec *rec = &a->w.rec[a->recs[r]];
                st = hd_fail(HD_ERR_IO, "%s: missing sun coefficient picture for sun patch %d (MF:%d), needed for "
                             "%s line %lu (%d/%d %.2f h); make the suns with gensuns -m %d from the same weather file",
                             path, b, o->sun_mf, o->weather, rec->line, rec->month, rec->day, rec->hour, o->sun_mf);
            }
        }
        if (st) {
            free(need);
            return st;
        }
        /* every needed picture's header now; the pixels when the patch's hours come */
        for (int b = 1; b < a->nsunbins && !st; b++) {
            if (!need[b]) continue;
            if (!(st = pat_path(path, sizeof path, o->sun_pattern, b, "sun DC")) && !(st = check_pic(a, path)) &&
                o->fensun_pattern && !(st = pat_path(path, sizeof path, o->fensun_pattern, b, "fenestration sun DC")))
                st = check_pic(a, path);
        }
        if (!st && o->fensun_pattern) st = load_mask(a, &a->fmask, NULL);
        a->sunneed = need;
        a->sunleft = hd_calloc((size_t)a->nsunbins, sizeof(long));
        a->sunstate = hd_calloc((size_t)a->nsunbins, 1);
        if (!st && (!a->sunleft || !a->sunstate)) st = HD_ERR_NOMEM;
        if (st) return st;
        for (long r = 0; r < a->nrec; r++) a->sunleft[a->sunbin[r]]++;
        pthread_mutex_init(&a->sunmu, NULL);
        pthread_cond_init(&a->suncv, NULL);
        a->sunsync = 1;
    }
    if ((st = load_sky(a))) return st;
    if (a->npix == 0) return hd_fail(HD_ERR_USAGE, "no coefficient picture was loaded");
    if (!a->noglare && (st = hd_glare_geom_new(&a->geom, &o->view, a->xres, a->yres))) return st;
    if (o->illum_csv && !(a->illum = hd_malloc_array((size_t)a->nrec * a->npix, sizeof(float)))) return HD_ERR_NOMEM;
    a->nthreads = hd_resolve_threads(o->nthreads);
    a->wbuf = hd_calloc((size_t)a->nthreads, sizeof(float *));
    a->wlum = hd_calloc((size_t)a->nthreads, sizeof(float *));
    a->wcol = hd_calloc((size_t)a->nthreads, sizeof(double *));
    a->wcoef = hd_calloc((size_t)a->nthreads, sizeof(double *));
    a->wfold = hd_calloc((size_t)a->nthreads, sizeof(float *));
    if (!a->wbuf || !a->wlum || !a->wcol || !a->wcoef || !a->wfold) return HD_ERR_NOMEM;
    for (int k = 0; k < a->nthreads; k++) {
        a->wbuf[k] = hd_malloc_array(a->npix * 3, sizeof(float));
        a->wlum[k] = hd_malloc_array(a->npix, sizeof(float));
        a->wcol[k] = hd_malloc_array((size_t)a->nsky + 1, 3 * sizeof(double));
        a->wcoef[k] = hd_malloc_array((size_t)a->ncomp + 1, 3 * FOLD_HOURS * sizeof(double));
        a->wfold[k] = hd_malloc_array(npad(a), 3 * FOLD_HOURS * sizeof(float));
        if (!a->wbuf[k] || !a->wlum[k] || !a->wcol[k] || !a->wcoef[k] || !a->wfold[k]) return HD_ERR_NOMEM;
    }
    if ((st = make_order(a))) return st;
    double t1 = now_sec();
    stats->t_load = t1 - t0;
    if (o->verbose)
        fprintf(stderr, "%s: %ld daylight hours of %zu records, %d sun patches, %d sky bins, %dx%d pixels, "
                "loaded in %.2f s\n", hd_progname(), a->nrec, nw, stats->nsun, a->nsky, a->xres, a->yres, stats->t_load);
    if ((st = hd_parallel_for((size_t)a->nrec, FOLD_HOURS, a->nthreads, hour_chunk, a))) return st;
    stats->t_loop = now_sec() - t1;
    if (o->verbose && a->sunneed)
        fprintf(stderr, "%s: hours composed in sun-patch order: at most %d of the %d DC_sun pictures held at once\n",
                hd_progname(), a->sunheld_max, stats->nsun);
    hd_ofile *of;
    if (a->noglare) {
        stats->nrecords = (long)nw;
        stats->ndaylight = a->nrec;
        for (long r = 0; r < a->nrec; r++)
            if (a->meanlum[r] > stats->mean_lum_max) stats->mean_lum_max = a->meanlum[r];
        if (o->illum_csv) {
            if ((st = hd_ofile_open(&of, o->illum_csv))) return st;
            FILE *fp = hd_ofile_fp(of);
            hd_annual_piece_lines(fp, o, a->piece_first, a->nrec, a->piece_total);
            fprintf(fp, "record,month,day,hour");
            for (size_t k = 0; k < a->npix; k++) fprintf(fp, ",E%zu", k + 1);
            fputc('\n', fp);
            for (long r = 0; r < a->nrec; r++) {
                const hd_weather_rec *rec = &a->w.rec[a->recs[r]];
                fprintf(fp, "%ld,%d,%d,%.3f", a->recs[r], rec->month, rec->day, rec->hour);
                for (size_t k = 0; k < a->npix; k++) fprintf(fp, ",%.6g", a->illum[(size_t)r * a->npix + k]);
                fputc('\n', fp);
            }
            if ((st = hd_ofile_commit(of))) return st;
        }
        return o->hourlog ? write_log(a) : HD_OK;
    }
    /* results in record order */
    if ((st = hd_ofile_open(&of, o->csv))) return st;
    FILE *fp = hd_ofile_fp(of);
    hd_glare_annual an;
    hd_glare_annual_init(&an, o->shade_limit);
    hd_annual_piece_lines(fp, o, a->piece_first, a->nrec, a->piece_total);
    hd_glare_csv_header(fp);
    for (long r = 0; r < a->nrec; r++) {
        long i = a->recs[r];
        double hoy = 24.0 * (a->jd[i] - 1) + a->w.rec[i].hour;
        int closed = 0;
        if ((st = hd_glare_annual_add(&an, hoy, a->res[r].ev, a->res[r].dgp, a->res[r].dgi, &closed))) break;
        hd_glare_csv_row(fp, hoy, &a->res[r], closed);
        if (a->meanlum[r] > stats->mean_lum_max) stats->mean_lum_max = a->meanlum[r];
    }
    if (st) {
        hd_ofile_abort(of);
        hd_glare_annual_free(&an);
        return st;
    }
    if ((st = hd_ofile_commit(of))) {
        hd_glare_annual_free(&an);
        return st;
    }
    stats->nrecords = (long)nw;
    stats->ndaylight = a->nrec;
    stats->dgp_p95 = hd_glare_percentile(an.dgp, an.n, 95);
    stats->dgi_p95 = hd_glare_percentile(an.dgi, an.n, 95);
    stats->shade_closed = (long)an.shade_closed;
    if (o->summary) {
        if ((st = hd_ofile_open(&of, o->summary))) {
            hd_glare_annual_free(&an);
            return st;
        }
        fp = hd_ofile_fp(of);
        if (o->piece_n > 0) {   /* the piece's record for the join: exact values */
            hd_annual_piece_lines(fp, o, a->piece_first, a->nrec, a->piece_total);
            fprintf(fp, "image: %d x %d\nshade_limit: %a\nload_seconds: %.3f\ncompose_glare_seconds: %.3f\n"
                    "sun_patches_used:", a->xres, a->yres, o->shade_limit, stats->t_load, stats->t_loop);
            for (int b = 1; b < a->nsunbins; b++)
                if (a->sunneed && a->sunneed[b]) fprintf(fp, " %d", b);
            fputc('\n', fp);
            for (long r = 0; r < a->nrec; r++) {
                long i = a->recs[r];
                fprintf(fp, "hour: %a %a %a %a\n", 24.0 * (a->jd[i] - 1) + a->w.rec[i].hour, a->res[r].ev,
                        a->res[r].dgp, a->res[r].dgi);
            }
        } else {
            hd_glare_annual_write_summary(fp, &an);
            fprintf(fp, "sun_patches: %d\nload_seconds: %.3f\ncompose_glare_seconds: %.3f\nimage: %d x %d\n",
                    stats->nsun, stats->t_load, stats->t_loop, a->xres, a->yres);
        }
        st = hd_ofile_commit(of);
    }
    hd_glare_annual_free(&an);
    if (!st && o->hourlog) st = write_log(a);
    return st;
}

hd_status hd_annual_run(const hd_annual_opts *o, hd_annual_stats *stats)
{
    actx a;
    memset(&a, 0, sizeof a);
    a.o = o;
    hd_annual_stats dummy;
    if (!stats) stats = &dummy;
    memset(stats, 0, sizeof *stats);
    hd_status st = run(&a, stats);
    actx_free(&a);
    return st;
}

hd_status hd_annual_mask_rays(const char *mask, hd_istream *in, const char *inname, FILE *out, int per_pixel,
                              int repeat, long *nmasked)
{
    if (repeat < 1 || repeat > 1024) return hd_fail(HD_ERR_RANGE, "ray repeat count %d out of range 1..1024", repeat);
    if (per_pixel < 1 || per_pixel > 1024)
        return hd_fail(HD_ERR_RANGE, "rays per pixel %d out of range 1..1024", per_pixel);
    hd_picture p;
    hd_status st = hd_picture_read(mask, &p);
    if (st) return st;
    size_t npix = (size_t)p.xres * (size_t)p.yres, nray = npix * (size_t)per_pixel;
    long kept = 0;
    float ray[6];
    for (size_t i = 0; i < nray; i++) {
        if ((st = hd_istream_read_exact(in, ray, sizeof ray, "ray (6 floats)"))) {
            hd_picture_free(&p);
            return hd_fail(HD_ERR_FORMAT, "%s: ray %zu: the stream ended before the %zu rays of the %d x %d mask %s (%d per pixel)",
                           inname, i, nray, p.xres, p.yres, mask, per_pixel);
        }
        if (p.pix[3 * (i / (size_t)per_pixel)] > 0.5f) kept++;
        else ray[3] = ray[4] = ray[5] = 0;
        int wr = 0;
        for (int k = 0; k < repeat; k++) wr += (int)fwrite(ray, sizeof ray, 1, out);
        if (wr != repeat) {
            hd_picture_free(&p);
            return hd_fail(HD_ERR_IO, "write error on the masked ray stream");
        }
    }
    hd_picture_free(&p);
    if (hd_istream_getc(in) != EOF)
        return hd_fail(HD_ERR_FORMAT, "%s: more rays than the %zu of the %zu pixels of the mask %s (%d per pixel)", inname,
                       nray, npix, mask, per_pixel);
    if (nmasked) *nmasked = kept;
    return HD_OK;
}

/* ---- two-pass operated shade ---- */

void hd_annual_sched_opts_default(hd_annual_sched_opts *o)
{
    memset(o, 0, sizeof *o);
    o->shade_limit = HD_GLARE_SHADE_LIMIT;
}

typedef struct lines_t {
    char **s;
    unsigned long *ln;   /* line number in the file */
    size_t n, cap;
} lines_t;

static void lines_free(lines_t *l)
{
    for (size_t i = 0; i < l->n; i++) free(l->s[i]);
    free(l->s);
    free(l->ln);
    memset(l, 0, sizeof *l);
}

/* Data lines of a CSV (header checked, then skipped) or an hour log ('#' lines skipped). */
static hd_status read_lines(const char *path, int csv, lines_t *l)
{
    memset(l, 0, sizeof *l);
    hd_annual_text t;
    hd_status st = hd_annual_text_read(path, 4096, &t);
    if (st) return st;
    l->s = hd_malloc_array(t.n ? t.n : 1, sizeof *l->s);
    l->ln = hd_malloc_array(t.n ? t.n : 1, sizeof *l->ln);
    if (!l->s || !l->ln) st = HD_ERR_NOMEM;
    for (size_t i = 0; i < t.n && !st; i++) {
        char *buf = t.line[i];
        if (!buf[0] || buf[0] == '#') continue;
        if (csv && i == 0) {
            if (strncmp(buf, "hour,Ev,DGP,DGI,", 16) != 0)
                st = hd_fail(HD_ERR_FORMAT, "%s: line 1: expected the glare CSV header hour,Ev,DGP,DGI,...", path);
            continue;
        }
        l->s[l->n] = buf;   /* taken over from t */
        t.line[i] = NULL;
        l->ln[l->n++] = (unsigned long)i + 1;
    }
    l->cap = l->n;
    hd_annual_text_free(&t);
    if (st) lines_free(l);
    return st;
}

/* CSV row: hour, Ev, DGP, DGI (the first four fields). */
static hd_status csv_fields(const char *path, const lines_t *l, size_t i, double v[4])
{
    const char *p = l->s[i];
    for (int k = 0; k < 4; k++) {
        char *end;
        v[k] = strtod(p, &end);
        if (end == p || (*end != ',' && k < 3) || !isfinite(v[k]))
            return hd_fail(HD_ERR_FORMAT, "%s: line %lu: expected hour,Ev,DGP,DGI,... numbers", path, l->ln[i]);
        p = end + 1;
    }
    return HD_OK;
}

/* Hour-log line: record month day hour ... DGP (last field). */
static hd_status log_fields(const char *path, const lines_t *l, size_t i, long *rec, int *mo, int *da, double *hr,
                            double *dgp)
{
    const char *last = strrchr(l->s[i], ' ');
    if (sscanf(l->s[i], "%ld %d %d %lf", rec, mo, da, hr) != 4 || !last || sscanf(last, "%lf", dgp) != 1)
        return hd_fail(HD_ERR_FORMAT, "%s: line %lu: expected 'record month day hour ... DGP' (pmcompose -L)", path,
                       l->ln[i]);
    return HD_OK;
}

hd_status hd_annual_schedule(const hd_annual_sched_opts *o, hd_annual_sched_stats *stats)
{
    hd_annual_sched_stats dummy;
    if (!stats) stats = &dummy;
    memset(stats, 0, sizeof *stats);
    if (!o->open_csv || !o->closed_csv || !o->open_log || !o->closed_log || !o->csv)
        return hd_fail(HD_ERR_USAGE, "the two-pass schedule needs the glare CSV and hour log of the open and the "
                       "closed run and an output CSV");
    if (!(o->shade_limit > 0 && o->shade_limit < 1))
        return hd_fail(HD_ERR_RANGE, "shade limit %g: expected a DGP between 0 and 1", o->shade_limit);
    lines_t oc, cc, ol, cl;
    memset(&cc, 0, sizeof cc);
    memset(&ol, 0, sizeof ol);
    memset(&cl, 0, sizeof cl);
    hd_status st = read_lines(o->open_csv, 1, &oc);
    if (!st) st = read_lines(o->closed_csv, 1, &cc);
    if (!st) st = read_lines(o->open_log, 0, &ol);
    if (!st) st = read_lines(o->closed_log, 0, &cl);
    size_t n = oc.n;
    if (!st && n == 0) st = hd_fail(HD_ERR_FORMAT, "%s: no hours", o->open_csv);
    if (!st && cc.n != n)
        st = hd_fail(HD_ERR_FORMAT, "%s has %zu hours, %s %zu: the open and closed runs must cover the same hours "
                     "(same weather file and records)", o->open_csv, n, o->closed_csv, cc.n);
    if (!st && (ol.n != n || cl.n != n))
        st = hd_fail(HD_ERR_FORMAT, "hour logs %s (%zu lines) and %s (%zu lines) must have one line per CSV hour (%zu)",
                     o->open_log, ol.n, o->closed_log, cl.n, n);
    double *dgp = NULL, *dgi = NULL, *dgpo = NULL, *dgio = NULL;
    unsigned char *closed = NULL;
    hd_ofile *of = NULL;
    if (!st) {
        dgp = hd_malloc_array(n, sizeof(double));
        dgi = hd_malloc_array(n, sizeof(double));
        dgpo = hd_malloc_array(n, sizeof(double));
        dgio = hd_malloc_array(n, sizeof(double));
        closed = hd_calloc(n, 1);
        if (!dgp || !dgi || !dgpo || !dgio || !closed) st = HD_ERR_NOMEM;
    }
    /* check the two runs line by line and decide the schedule */
    hd_glare_annual an;
    hd_glare_annual_init(&an, o->shade_limit);
    for (size_t i = 0; i < n && !st; i++) {
        double vo[4], vc[4], ho, hc, gpo, gpc;
        long ro, rc;
        int mo, da, mc, dc;
        if ((st = csv_fields(o->open_csv, &oc, i, vo)) || (st = csv_fields(o->closed_csv, &cc, i, vc)) ||
            (st = log_fields(o->open_log, &ol, i, &ro, &mo, &da, &ho, &gpo)) ||
            (st = log_fields(o->closed_log, &cl, i, &rc, &mc, &dc, &hc, &gpc)))
            break;
        if (fabs(vo[0] - vc[0]) > 1e-6) {
            st = hd_fail(HD_ERR_FORMAT, "%s: line %lu: hour %g, but %s line %lu has hour %g: the runs must cover the "
                         "same hours", o->closed_csv, cc.ln[i], vc[0], o->open_csv, oc.ln[i], vo[0]);
            break;
        }
        if (ro != rc || fabs(gpo - vo[2]) > 1e-5 || fabs(gpc - vc[2]) > 1e-5) {
            st = hd_fail(HD_ERR_FORMAT, "%s line %lu / %s line %lu: hour log does not match the CSV row (record %ld vs "
                         "%ld, DGP %g vs %g)", o->open_log, ol.ln[i], o->closed_log, cl.ln[i], ro, rc, gpo, vo[2]);
            break;
        }
        closed[i] = (unsigned char)hd_glare_shade_closed(vo[2], o->shade_limit);
        stats->nclosed += closed[i];
        dgpo[i] = vo[2];
        dgio[i] = vo[3];
        const double *v = closed[i] ? vc : vo;
        dgp[i] = v[2];
        dgi[i] = v[3];
        if ((st = hd_glare_annual_add(&an, v[0], v[1], v[2], v[3], NULL))) break;
    }
    /* composite CSV: the chosen run's row, shade column = schedule */
    if (!st && !(st = hd_ofile_open(&of, o->csv))) {
        FILE *fp = hd_ofile_fp(of);
        hd_glare_csv_header(fp);
        for (size_t i = 0; i < n; i++) {
            const char *row = closed[i] ? cc.s[i] : oc.s[i];
            const char *comma = strrchr(row, ',');
            fprintf(fp, "%.*s,%d\n", (int)(comma - row), row, closed[i]);
        }
        st = hd_ofile_commit(of);
    }
    if (!st && o->schedule && !(st = hd_ofile_open(&of, o->schedule))) {
        FILE *fp = hd_ofile_fp(of);
        fprintf(fp, "hour,record,month,day,time,DGP_open,DGP_closed,DGP,shade\n");
        for (size_t i = 0; i < n; i++) {
            double vo[4], vc[4], hr, g;
            long rec;
            int mo, da;
            csv_fields(o->open_csv, &oc, i, vo);
            csv_fields(o->closed_csv, &cc, i, vc);
            log_fields(o->open_log, &ol, i, &rec, &mo, &da, &hr, &g);
            fprintf(fp, "%.10g,%ld,%d,%d,%.3f,%.6f,%.6f,%.6f,%d\n", vo[0], rec, mo, da, hr, vo[2], vc[2], dgp[i], closed[i]);
        }
        st = hd_ofile_commit(of);
    }
    if (!st && o->hourlog && !(st = hd_ofile_open(&of, o->hourlog))) {
        FILE *fp = hd_ofile_fp(of);
        fprintf(fp, "# record month day hour sun_patch sun_dx sun_dy sun_dz sun_R sun_G sun_B mean_lum_cd/m2 DGP\n"
                "# two-pass composite: %s (shade open) / %s (closed when the open DGP >= %.2f)\n",
                o->open_log, o->closed_log, o->shade_limit);
        for (size_t i = 0; i < n; i++) fprintf(fp, "%s\n", closed[i] ? cl.s[i] : ol.s[i]);
        st = hd_ofile_commit(of);
    }
    if (!st) {
        stats->nhours = (long)n;
        stats->dgp_p95 = hd_glare_percentile(dgp, n, 95);
        stats->dgi_p95 = hd_glare_percentile(dgi, n, 95);
        stats->dgp_p95_open = hd_glare_percentile(dgpo, n, 95);
        stats->dgi_p95_open = hd_glare_percentile(dgio, n, 95);
        an.shade_closed = (size_t)stats->nclosed;
    }
    if (!st && o->summary && !(st = hd_ofile_open(&of, o->summary))) {
        FILE *fp = hd_ofile_fp(of);
        fprintf(fp, "two_pass: shade closed for the hours whose open-shade DGP >= %.2f (%s), open otherwise (%s)\n",
                o->shade_limit, o->closed_csv, o->open_csv);
        hd_glare_annual_write_summary(fp, &an);
        fprintf(fp, "open_only_DGP_p95: %.6f\nopen_only_DGI_p95: %.4f\n", stats->dgp_p95_open, stats->dgi_p95_open);
        st = hd_ofile_commit(of);
    }
    hd_glare_annual_free(&an);
    free(dgp);
    free(dgi);
    free(dgpo);
    free(dgio);
    free(closed);
    lines_free(&oc);
    lines_free(&cc);
    lines_free(&ol);
    lines_free(&cl);
    return st;
}

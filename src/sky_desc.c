/* heliodon — sky descriptions as gensky/gendaylit write them: parsing,
 * evaluation (the perezlum.cal and skybright.cal functions written out in
 * C) and integration over a sky basis (genskyvec). */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/io.h"
#include "heliodon/sky.h"

#define MAXTOK 4096

typedef struct toks {
    char **w;
    unsigned long *line;
    int n;
} toks;

static void toks_free(toks *t)
{
    for (int i = 0; i < t->n; i++) free(t->w[i]);
    free(t->w);
    free(t->line);
}

static hd_status tokenize(const char *text, const char *name, toks *t)
{
    memset(t, 0, sizeof *t);
    int cap = 0;
    unsigned long line = 1;
    const char *p = text;
    while (*p) {
        if (*p == '\n') { line++; p++; continue; }
        if (isspace((unsigned char)*p)) { p++; continue; }
        if (*p == '#') { while (*p && *p != '\n') p++; continue; }
        if (*p == '!')
            return hd_fail(HD_ERR_UNSUPPORTED, "%s: line %lu: commands ('!') in sky descriptions are not supported",
                           name, line);
        const char *s = p;
        while (*p && !isspace((unsigned char)*p)) p++;
        if (t->n >= MAXTOK) return hd_fail(HD_ERR_RANGE, "%s: line %lu: sky description too long", name, line);
        if (t->n == cap) {
            cap = cap ? 2 * cap : 64;
            char **nw = hd_realloc_array(t->w, (size_t)cap, sizeof *nw);
            if (!nw) return HD_ERR_NOMEM;
            t->w = nw;
            unsigned long *nl = hd_realloc_array(t->line, (size_t)cap, sizeof *nl);
            if (!nl) return HD_ERR_NOMEM;
            t->line = nl;
        }
        size_t len = (size_t)(p - s);
        char *w = hd_malloc(len + 1);
        if (!w) return HD_ERR_NOMEM;
        memcpy(w, s, len);
        w[len] = 0;
        t->w[t->n] = w;
        t->line[t->n++] = line;
    }
    return HD_OK;
}

typedef struct prim {
    const char *mod, *type, *id;
    int nstr;
    const char **str;
    int nreal;
    double real[16];
    unsigned long line;
} prim;

/* read one primitive at token *i */
static hd_status read_prim(const toks *t, int *i, const char *name, prim *pr)
{
    int k = *i;
    memset(pr, 0, sizeof *pr);
    if (k + 3 > t->n) return hd_fail(HD_ERR_FORMAT, "%s: line %lu: incomplete primitive", name, t->line[k]);
    pr->line = t->line[k];
    pr->mod = t->w[k];
    pr->type = t->w[k + 1];
    pr->id = t->w[k + 2];
    k += 3;
    long n;
    for (int part = 0; part < 3; part++) {
        if (k >= t->n || hd_parse_long(t->w[k], &n) || n < 0 || n > 1000)
            return hd_fail(HD_ERR_FORMAT, "%s: line %lu: primitive %s %s: expected an argument count, found '%s'",
                           name, k < t->n ? t->line[k] : t->line[t->n - 1], pr->type, pr->id,
                           k < t->n ? t->w[k] : "end of input");
        k++;
        if (k + n > t->n)
            return hd_fail(HD_ERR_FORMAT, "%s: line %lu: primitive %s %s: %ld arguments announced, input ends",
                           name, pr->line, pr->type, pr->id, n);
        if (part == 0) {
            pr->nstr = (int)n;
            pr->str = (const char **)(t->w + k);
        } else if (part == 2) {
            if (n > 16)
                return hd_fail(HD_ERR_FORMAT, "%s: line %lu: %s %s: too many real arguments (%ld)", name, pr->line,
                               pr->type, pr->id, n);
            pr->nreal = (int)n;
            for (int j = 0; j < n; j++)
                if (hd_parse_double(t->w[k + j], &pr->real[j]))
                    return hd_fail(HD_ERR_FORMAT, "%s: line %lu: %s %s: real argument %d: expected a number, found '%s'",
                                   name, t->line[k + j], pr->type, pr->id, j + 1, t->w[k + j]);
        }
        k += (int)n;
    }
    *i = k;
    return HD_OK;
}

hd_status hd_skydesc_parse(const char *text, const char *name, hd_skydesc *d)
{
    memset(d, 0, sizeof *d);
    toks t;
    hd_status st = tokenize(text, name, &t);
    if (st) { toks_free(&t); return st; }
    int found_sky = 0, have_light = 0;
    char lightname[256] = "";
    int i = 0;
    while (i < t.n) {
        prim pr;
        if ((st = read_prim(&t, &i, name, &pr))) break;
        if (!strcmp(pr.type, "brightfunc") && !found_sky) {
            if (pr.nstr >= 2 && !strcmp(pr.str[1], "perezlum.cal")) {
                if (pr.nreal < 10) {
                    st = hd_fail(HD_ERR_FORMAT, "%s: line %lu: perezlum.cal sky needs 10 real arguments, found %d",
                                 name, pr.line, pr.nreal);
                    break;
                }
                d->type = HD_SKY_PEREZ;
                d->sundir = hd_v3(pr.real[7], pr.real[8], pr.real[9]);
            } else if (pr.nstr >= 2 && !strcmp(pr.str[1], "skybright.cal")) {
                if (pr.nreal < 3) {
                    st = hd_fail(HD_ERR_FORMAT, "%s: line %lu: skybright.cal sky needs at least 3 real arguments",
                                 name, pr.line);
                    break;
                }
                int type = (int)pr.real[0];
                if (type < 1 || type > 4 || (type != 2 && type != 3 && pr.nreal < 7)) {
                    st = hd_fail(HD_ERR_FORMAT, "%s: line %lu: skybright.cal: bad sky type %g or argument count %d",
                                 name, pr.line, pr.real[0], pr.nreal);
                    break;
                }
                d->type = type == 1 ? HD_SKY_CIE_CLEAR : type == 2 ? HD_SKY_CIE_OVERCAST
                        : type == 3 ? HD_SKY_UNIFORM : HD_SKY_CIE_INTERMEDIATE;
                if (pr.nreal >= 7) d->sundir = hd_v3(pr.real[4], pr.real[5], pr.real[6]);
                else d->sundir = hd_v3(0, 0, 1);
            } else {
                continue;   /* some other brightfunc */
            }
            found_sky = 1;
            d->nargs = pr.nreal;
            memcpy(d->args, pr.real, sizeof(double) * (size_t)pr.nreal);
        } else if (!strcmp(pr.type, "light") && !have_light) {
            if (pr.nreal < 3) {
                st = hd_fail(HD_ERR_FORMAT, "%s: line %lu: light %s needs 3 real arguments", name, pr.line, pr.id);
                break;
            }
            have_light = 1;
            snprintf(lightname, sizeof lightname, "%s", pr.id);
            for (int c = 0; c < 3; c++) d->sun_rgb[c] = pr.real[c];
        } else if (!strcmp(pr.type, "source") && have_light && !d->has_sun && !strcmp(pr.mod, lightname)) {
            if (pr.nreal < 4) {
                st = hd_fail(HD_ERR_FORMAT, "%s: line %lu: source %s needs 4 real arguments", name, pr.line, pr.id);
                break;
            }
            d->has_sun = 1;
            d->sun_source_dir = hd_vnorm(hd_v3(pr.real[0], pr.real[1], pr.real[2]));
            d->sun_diam_deg = pr.real[3];
        }
    }
    toks_free(&t);
    if (st) return st;
    if (!found_sky)
        return hd_fail(HD_ERR_FORMAT, "%s: no 'brightfunc skyfunc' with perezlum.cal or skybright.cal found", name);
    return HD_OK;
}

/* relative sky functions (before the ground blend) */
static double sky_value(const hd_skydesc *d, hd_vec3 D)
{
    const double *A = d->args;
    double cg = hd_clamp(D.x * d->sundir.x + D.y * d->sundir.y + D.z * d->sundir.z, -1, 1);
    double gamma = acos(cg);
    switch (d->type) {
    case HD_SKY_PEREZ: {
        double dz = D.z > 0.01 ? D.z : 0.01;
        return A[0] * (1 + A[2] * exp(A[3] / dz)) * (1 + A[4] * exp(A[5] * gamma) + A[6] * cg * cg);
    }
    case HD_SKY_CIE_CLEAR:
        return A[1] * (0.91 + 10 * exp(-3 * gamma) + 0.45 * cg * cg) * (D.z > 0.01 ? 1 - exp(-0.32 / D.z) : 1) / A[3];
    case HD_SKY_CIE_OVERCAST:
        return A[1] * (1 + 2 * D.z) / 3;
    case HD_SKY_UNIFORM:
        return A[1];
    case HD_SKY_CIE_INTERMEDIATE: {
        double eta = acos(hd_clamp(D.z, -1, 1)), zt = acos(hd_clamp(d->sundir.z, -1, 1));
        return A[1] * ((1.35 * sin(5.631 - 3.59 * eta) + 3.12) * sin(4.396 - 2.6 * zt) + 6.37 - eta) / 2.326 *
               exp(gamma * -0.563 * ((2.629 - eta) * (1.562 - zt) + 0.812)) / A[3];
    }
    }
    return 0;
}

double hd_skydesc_eval(const hd_skydesc *d, hd_vec3 D)
{
    double ground = d->type == HD_SKY_PEREZ ? d->args[1] : d->args[2];
    double a = pow(D.z + 1.01, 10), b = pow(D.z + 1.01, -10);
    return (a * sky_value(d, D) + b * ground) / (a + b);
}

static hd_vec3 altazi(double alt, double azi)
{
    return hd_v3(sin(azi) * cos(alt), cos(azi) * cos(alt), sin(alt));
}

/* The pseudo-random function of Radiance's calculator language (rand(x)):
 * a fixed hash of its argument to [0,1). */
static double cal_rand(double x)
{
    double y = x * (1.0 / (1.0 + x * x) + 2.71828182845904);
    y += 0.785398163397447 - floor(y);
    y = 1e5 / y;
    return y - floor(y);
}

/* Radiance's genskyvec sample directions: record r = 1, 2, ... of its
 * sample stream (16 per patch, patch by patch) jitters the patch with
 * x1 = rand(0.37 r - 5.3) in altitude and x2 = rand(0.86 - 1.47 r) in
 * azimuth, uniformly in angle; the ground bin takes altitude asin(-x1) and
 * azimuth 2 pi x2.  The direction goes to rtrace as float32. */
static hd_vec3 radiance_ray(const hd_skybasis *b, int p, long rec)
{
    const double pi = 3.14159265358979323846;
    double x1 = cal_rand((double)rec * .37 - 5.3), x2 = cal_rand((double)rec * -1.47 + .86);
    double alt, azi;
    if (p == 0) {
        azi = 2 * pi * x2;
        alt = asin(-x1);
    } else {
        int row, col, naz;
        if (p >= b->nbins - 1) {
            row = b->nbands;
            col = 0;
            naz = 1;
        } else {
            int lo = 0, hi = b->nbands - 1;
            while (lo < hi) {
                int mid = (lo + hi + 1) / 2;
                if (b->band_first[mid] <= p) lo = mid;
                else hi = mid - 1;
            }
            row = lo;
            col = p - b->band_first[lo];
            naz = b->band_count[lo];
        }
        double rah = 90 / (b->mf * 7 + .5) * (pi / 180);
        alt = (row + x1) * rah;
        azi = (col + x2 - .5) * (2 * pi / naz);
    }
    double ca = cos(alt);
    float f[3] = {(float)(sin(azi) * ca), (float)(cos(azi) * ca), (float)sin(alt)};
    hd_vec3 v = hd_v3(f[0], f[1], f[2]);
    double len = sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    return hd_v3(v.x / len, v.y / len, v.z / len);
}

hd_status hd_skyvec_compute(const hd_skybasis *b, const hd_skydesc *d, const hd_skyvec_opts *o, double *out)
{
    int n = b->nbins;
    int ns = o->nsamp;
    memset(out, 0, sizeof(double) * 3 * (size_t)n);
    if (o->stddev) memset(o->stddev, 0, sizeof(double) * (size_t)n);
    if (!o->sun_only && ns <= 0) {   /* Radiance's 16 fixed rays per patch */
        for (int p = 0; p < n; p++) {
            double sum = 0, sum2 = 0;
            for (int k = 0; k < 16; k++) {
                double f = hd_skydesc_eval(d, radiance_ray(b, p, 16L * p + k + 1));
                sum += f;
                sum2 += f * f;
            }
            double v = sum / 16;
            if (o->stddev) o->stddev[p] = sqrt(fmax(0, sum2 / 16 - v * v));
            for (int c = 0; c < 3; c++) out[3 * p + c] = v * o->skycolor[c];
        }
    } else if (!o->sun_only) {
        for (int p = 0; p < n; p++) {
            double sum = 0, sum2 = 0;
            for (int i = 0; i < ns; i++)
                for (int j = 0; j < ns; j++) {
                    double u1 = (i + 0.5) / ns, u2 = (j + 0.5) / ns;
                    hd_vec3 D;
                    if (p == 0) D = altazi(-asin(sqrt(u1)), u2 * 2 * HD_PI);          /* ground, cosine-weighted */
                    else if (p == n - 1)                                               /* zenith cap */
                        D = altazi(b->nbands * b->alpha + u1 * (HD_PI / 2 - b->nbands * b->alpha), u2 * 2 * HD_PI);
                    else D = hd_skybasis_sample(b, p, u1, u2);
                    double f = hd_skydesc_eval(d, D);
                    sum += f;
                    sum2 += f * f;
                }
            double v = sum / (ns * ns);
            if (o->stddev) o->stddev[p] = sqrt(fmax(0, sum2 / (ns * ns) - v * v));
            for (int c = 0; c < 3; c++) out[3 * p + c] = v * o->skycolor[c];
        }
    }
    if (d->has_sun && d->sun_source_dir.z > 0) {
        hd_vec3 s = d->sun_source_dir;
        if (o->five_phase) {
            int best = 1;
            double bd = -2;
            for (int p = 1; p < n; p++) {
                double dp = hd_vdot(b->dir[p], s);
                if (dp > bd) { bd = dp; best = p; }
            }
            for (int c = 0; c < 3; c++) out[3 * best + c] = d->sun_rgb[c];
        } else {
            /* three nearest patch centres, weights 1/(angle + 0.02) */
            int idx[3] = {-1, -1, -1};
            double cosv[3] = {-2, -2, -2};
            for (int p = 1; p < n; p++) {
                double dp = hd_vdot(b->dir[p], s);
                if (dp <= cosv[2]) continue;
                int k = 2;
                while (k > 0 && cosv[k - 1] < dp) { cosv[k] = cosv[k - 1]; idx[k] = idx[k - 1]; k--; }
                cosv[k] = dp;
                idx[k] = p;
            }
            double w[3], wt = 0;
            for (int k = 0; k < 3; k++) wt += w[k] = idx[k] < 0 ? 0 : 1 / (acos(hd_clamp(cosv[k], -1, 1)) + 0.02);
            double dd = d->sun_diam_deg / 360;
            double sun_sa = dd * dd * HD_PI * HD_PI * HD_PI;
            for (int k = 0; k < 3; k++) {
                if (idx[k] < 0) continue;
                double f = w[k] / wt * sun_sa / b->omega[idx[k]];
                for (int c = 0; c < 3; c++) out[3 * idx[k] + c] += d->sun_rgb[c] * f;
            }
        }
    }
    return HD_OK;
}

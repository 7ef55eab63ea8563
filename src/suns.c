/* heliodon — sun sources at Reinhart patch centres (see suns.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/basis.h"
#include "heliodon/sky.h"
#include "heliodon/solar.h"
#include "heliodon/suns.h"
#include "heliodon/weather.h"

void hd_sunlist_init(hd_sunlist *s) { memset(s, 0, sizeof *s); }

void hd_sunlist_free(hd_sunlist *s)
{
    free(s->bin);
    free(s->dir);
    free(s->hours);
    memset(s, 0, sizeof *s);
}

int hd_suns_daylight(const hd_weather *w, size_t i, const int *jd, hd_vec3 *sundir)
{
    const hd_weather_rec *r = &w->rec[i];
    double decl = hd_sun_declination(jd[i]);
    double stime = r->hour + hd_sun_time_adjust(&w->site, jd[i]);
    double alt = hd_sun_altitude(&w->site, decl, stime);
    /* same direction convention as gendaymtx: azimuth from south (west +)
     * turned to "east of north" */
    double azi = hd_sun_azimuth(&w->site, decl, stime) + HD_PI;
    if (sundir) *sundir = hd_v3(cos(alt) * sin(azi), cos(alt) * cos(azi), sin(alt));
    return alt > -HD_SUN_HALFANGLE_RAD && r->v1 + r->v2 > 1e-4;
}

int hd_suns_nearest(const hd_skybasis *b, hd_vec3 d)
{
    int best = 1;
    double bd = -2;
    for (int i = 1; i < b->nbins; i++) {
        double x = hd_vdot(b->dir[i], d);
        if (x > bd) {
            bd = x;
            best = i;
        }
    }
    return best;
}

hd_status hd_suns_select(const hd_weather *w, int mf, int keep_all, hd_sunlist *out)
{
    hd_sunlist_init(out);
    if (mf < 1 || mf > HD_SKY_MAXMF)
        return hd_fail(HD_ERR_USAGE, "Reinhart subdivision MF:%d out of range 1..%d", mf, HD_SKY_MAXMF);
    hd_skybasis b;
    hd_status st = hd_skybasis_init(&b, mf);
    if (st) return st;
    long *count = hd_calloc((size_t)b.nbins, sizeof(long));
    int *jd = hd_malloc_array(w->n ? w->n : 1, sizeof(int));
    if (!count || !jd) {
        free(count);
        free(jd);
        hd_skybasis_free(&b);
        return HD_ERR_NOMEM;
    }
    hd_daymtx_julian_days(w, jd);
    long nday = 0;
    for (size_t i = 0; i < w->n; i++) {
        hd_vec3 d;
        if (!hd_suns_daylight(w, i, jd, &d)) continue;
        int bin = hd_suns_nearest(&b, d);
        count[bin]++;
        nday++;
    }
    free(jd);
    if (nday == 0 && !keep_all) {
        free(count);
        hd_skybasis_free(&b);
        return hd_fail(HD_ERR_FORMAT, "%s: no daylight hours (no record with the sun above the horizon and "
                       "non-zero radiation): nothing to compute", w->name);
    }
    int n = 0;
    for (int k = 1; k < b.nbins; k++)
        if (keep_all || count[k]) n++;
    out->bin = hd_malloc_array((size_t)n, sizeof(int));
    out->dir = hd_malloc_array((size_t)n, sizeof(hd_vec3));
    out->hours = hd_malloc_array((size_t)n, sizeof(long));
    if (!out->bin || !out->dir || !out->hours) {
        free(count);
        hd_skybasis_free(&b);
        hd_sunlist_free(out);
        return HD_ERR_NOMEM;
    }
    int j = 0;
    for (int k = 1; k < b.nbins; k++) {
        if (!(keep_all || count[k])) continue;
        out->bin[j] = k;
        out->dir[j] = hd_skybasis_dir(&b, k);
        out->hours[j] = count[k];
        j++;
    }
    out->n = n;
    out->mf = mf;
    out->nbins = b.nbins;
    out->ndaylight = nday;
    free(count);
    hd_skybasis_free(&b);
    return HD_OK;
}

hd_status hd_suns_write(const hd_sunlist *s, FILE *rad, FILE *mods, const char *cmdline)
{
    if (rad) {
        fprintf(rad, "# Sun sources at the centres of Reinhart MF:%d patches (%d of %d sky patches)\n",
                s->mf, s->n, s->nbins - 1);
        if (cmdline) fprintf(rad, "# %s\n", cmdline);
        for (int i = 0; i < s->n; i++) {
            fprintf(rad, "\nvoid light solar%d\n0\n0\n3 1 1 1\n", s->bin[i]);
            fprintf(rad, "\nsolar%d source sun%d\n0\n0\n4 %.8f %.8f %.8f %.3f\n", s->bin[i], s->bin[i],
                    s->dir[i].x, s->dir[i].y, s->dir[i].z, HD_SUN_DIAMETER);
        }
    }
    if (mods)
        for (int i = 0; i < s->n; i++) fprintf(mods, "solar%d\n", s->bin[i]);
    if ((rad && ferror(rad)) || (mods && ferror(mods))) return hd_fail(HD_ERR_IO, "write error on the sun list");
    return HD_OK;
}

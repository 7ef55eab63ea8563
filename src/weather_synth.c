/* heliodon — deterministic synthetic weather year (see weather.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/rng.h"
#include "heliodon/sky.h"
#include "heliodon/weather.h"

void hd_synth_opts_default(hd_synth_opts *o)
{
    memset(o, 0, sizeof *o);
    o->seed = 1;
    o->tl_mean = 3.5;
    o->tl_amp = 0.5;
    o->cloud_mean = 0.4;
    o->cloud_amp = 0.3;
    o->cloud_persist = 0.6;
}

void hd_clear_sky(double alt, int jd, double elev, double tl, double *ghi, double *dni, double *dhi)
{
    *ghi = *dni = *dhi = 0;
    if (alt <= 0) return;
    double cz = sin(alt);
    double zdeg = 90 - alt * 180 / HD_PI;
    double am = 1 / (cz + 0.50572 * pow(96.07995 - zdeg, -1.6364));   /* Kasten & Young 1989 */
    double i0 = HD_SOLAR_CONSTANT * hd_eccentricity(jd);
    double fh1 = exp(-elev / 8000), fh2 = exp(-elev / 1250);
    double cg1 = 5.09e-5 * elev + 0.868, cg2 = 3.92e-5 * elev + 0.0387;
    double g = cg1 * i0 * cz * exp(-cg2 * am * (fh1 + fh2 * (tl - 1))) * exp(0.01 * pow(am, 1.8));
    double b = 0.664 + 0.163 / fh1;
    double n = b * i0 * exp(-0.09 * am * (tl - 1));
    if (n * cz > g) n = g / cz;
    if (g < 0) g = 0;
    *ghi = g;
    *dni = n;
    *dhi = g - n * cz;
}

static double erbs(double kt)
{
    if (kt <= 0.22) return 1 - 0.09 * kt;
    if (kt <= 0.80) return 0.9511 - 0.1604 * kt + 4.388 * kt * kt - 16.638 * kt * kt * kt + 12.336 * pow(kt, 4);
    return 0.165;
}

static double clamp01(double x) { return x < 0 ? 0 : x > 1 ? 1 : x; }

hd_status hd_weather_synth(hd_weather *w, const hd_synth_opts *o)
{
    static const int mdays[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    hd_weather_init(w);
    if (!(fabs(o->site.lat) <= 90) || !(fabs(o->site.lon) <= 360) || !(fabs(o->site.meridian) <= 360))
        return hd_fail(HD_ERR_RANGE, "genwea: site out of range (lat %g, lon %g, meridian %g)", o->site.lat,
                       o->site.lon, o->site.meridian);
    if (!(o->tl_mean - fabs(o->tl_amp) >= 1) || !(o->tl_mean + fabs(o->tl_amp) <= 10))
        return hd_fail(HD_ERR_RANGE, "genwea: Linke turbidity %g +- %g outside 1..10", o->tl_mean, o->tl_amp);
    snprintf(w->name, sizeof w->name, "genwea");
    snprintf(w->place, sizeof w->place, "SYNTHETIC_genwea_seed%llu%s%s", (unsigned long long)o->seed,
             o->name && *o->name ? "_" : "", o->name ? o->name : "");
    for (char *c = w->place; *c; c++)
        if (*c == ' ' || *c == '\t') *c = '_';
    snprintf(w->lat_text, sizeof w->lat_text, "%.4f", o->site.lat);
    snprintf(w->elev_text, sizeof w->elev_text, "%.1f", o->site.elev);
    w->site = o->site;
    w->tz_hours = -o->site.meridian / 15;
    w->units = 1;
    w->cap = 8760;
    w->rec = hd_calloc(w->cap, sizeof *w->rec);
    if (!w->rec) return HD_ERR_NOMEM;
    hd_rng dayrng;
    hd_rng_init(&dayrng, o->seed, 0);
    double cday = 0, chour = 0;
    int cloudy = 0;
    int jd = 0;
    for (int m = 1; m <= 12; m++)
        for (int d = 1; d <= mdays[m - 1]; d++) {
            jd++;
            /* day type: cloudy with the seasonal probability, kept from
             * the previous day with probability cloud_persist */
            double pc = clamp01(o->cloud_mean + o->cloud_amp * cos(2 * HD_PI * (jd - 15) / 365.0));
            double u1 = hd_rng_uniform(&dayrng), u2 = hd_rng_uniform(&dayrng), u3 = hd_rng_uniform(&dayrng);
            if (jd == 1 || u1 >= o->cloud_persist) cloudy = u2 < pc;
            cday = cloudy ? 0.7 + 0.3 * u3 : 0.3 * u3;
            double tl = o->tl_mean + o->tl_amp * cos(2 * HD_PI * (jd - 196) / 365.0);
            hd_rng hr;
            hd_rng_init(&hr, o->seed, 1000 + (uint64_t)jd);
            for (int h = 0; h < 24; h++) {
                hd_weather_rec *r = &w->rec[w->n++];
                r->month = m;
                r->day = d;
                r->hour = h + 0.5;
                r->dewpoint = r->ghi = r->dni_lux = r->dhi_lux = NAN;
                r->line = 6 + w->n;
                chour = 0.7 * chour + 0.3 * (2 * hd_rng_uniform(&hr) - 1);
                hd_sunpos sp;
                hd_sun_position(&o->site, jd, r->hour, 0, &sp);
                if (sp.alt <= 0) continue;
                double g0, n0, d0;
                hd_clear_sky(sp.alt, jd, o->site.elev, tl, &g0, &n0, &d0);
                double c = clamp01(cday + 0.2 * chour);
                double ghi = g0 * (1 - 0.75 * pow(c, 3.4));
                double ext = HD_SOLAR_CONSTANT * hd_eccentricity(jd) * sin(sp.alt);
                double kt = ext > 0 ? ghi / ext : 0;
                double dhi = c < 0.05 ? d0 : fmax(d0, ghi * erbs(kt));
                if (dhi > ghi) dhi = ghi;
                double dni = (ghi - dhi) / sin(sp.alt);
                if (dni > n0) dni = n0;
                dhi = ghi - dni * sin(sp.alt);
                r->v1 = floor(dni + 0.5);
                r->v2 = floor(dhi + 0.5);
            }
        }
    return HD_OK;
}

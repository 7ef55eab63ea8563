/* heliodon — Perez all-weather sky and luminous efficacy, and sky-matrix
 * columns as gendaymtx computes them (see sky.h and
 * docs/design/sky.md).  Model: Perez et al. 1990 (efficacy, Table 4) and
 * 1993 (all-weather luminance, Table 1). */
#include <math.h>
#include <string.h>

#include "heliodon/render.h"
#include "heliodon/sky.h"

static const double eps_bounds[9] = {1.000, 1.065, 1.230, 1.500, 1.950, 2.800, 4.500, 6.200, 12.01};

/* diffuse a b c d, direct a b c d per clearness category */
static const double efficacy_tab[8][8] = {
    {97.24, -0.46, 12.00, -8.91, 57.20, -4.55, -2.98, 117.12},
    {107.22, 1.15, 0.59, -3.95, 98.99, -3.46, -1.21, 12.38},
    {104.97, 2.96, -5.53, -8.77, 109.83, -4.90, -1.71, -8.81},
    {102.39, 5.59, -13.95, -13.90, 110.34, -5.84, -1.99, -4.56},
    {100.71, 5.94, -22.75, -23.74, 106.36, -3.97, -1.75, -6.16},
    {106.42, 3.83, -36.15, -28.83, 107.19, -1.25, -1.51, -26.73},
    {141.88, 1.90, -53.24, -14.03, 105.75, 0.77, -1.26, -34.44},
    {152.23, 0.35, -45.27, -7.98, 101.18, 1.58, -1.10, -8.29},
};

/* Perez 1993 coefficients: per category, a1..a4 b1..b4 c1..c4 d1..d4 e1..e4 */
static const double perez_tab[8][20] = {
    {1.3525, -0.2576, -0.2690, -1.4366, -0.7670, 0.0007, 1.2734, -0.1233, 2.8000, 0.6004, 1.2375, 1.0000,
     1.8734, 0.6297, 0.9738, 0.2809, 0.0356, -0.1246, -0.5718, 0.9938},
    {-1.2219, -0.7730, 1.4148, 1.1016, -0.2054, 0.0367, -3.9128, 0.9156, 6.9750, 0.1774, 6.4477, -0.1239,
     -1.5798, -0.5081, -1.7812, 0.1080, 0.2624, 0.0672, -0.2190, -0.4285},
    {-1.1000, -0.2515, 0.8952, 0.0156, 0.2782, -0.1812, -4.5000, 1.1766, 24.7219, -13.0812, -37.7000, 34.8438,
     -5.0000, 1.5218, 3.9229, -2.6204, -0.0156, 0.1597, 0.4199, -0.5562},
    {-0.5484, -0.6654, -0.2672, 0.7117, 0.7234, -0.6219, -5.6812, 2.6297, 33.3389, -18.3000, -62.2500, 52.0781,
     -3.5000, 0.0016, 1.1477, 0.1062, 0.4659, -0.3296, -0.0876, -0.0329},
    {-0.6000, -0.3566, -2.5000, 2.3250, 0.2937, 0.0496, -5.6812, 1.8415, 21.0000, -4.7656, -21.5906, 7.2492,
     -3.5000, -0.1554, 1.4062, 0.3988, 0.0032, 0.0766, -0.0656, -0.1294},
    {-1.0156, -0.3670, 1.0078, 1.4051, 0.2875, -0.5328, -3.8500, 3.3750, 14.0000, -0.9999, -7.1406, 7.5469,
     -3.4000, -0.1078, -1.0750, 1.5702, -0.0672, 0.4016, 0.3017, -0.4844},
    {-1.0000, 0.0211, 0.5025, -0.5119, -0.3000, 0.1922, 0.7023, -1.6317, 19.0000, -5.0000, 1.2438, -1.9094,
     -4.0000, 0.0250, 0.3844, 0.2656, 1.0468, -0.3788, -2.4517, 1.4656},
    {-1.0500, 0.0289, 0.4260, 0.3590, -0.3250, 0.1156, 0.7781, 0.0025, 31.0625, -14.5000, -46.1148, 55.3750,
     -7.2312, 0.4050, 13.3500, 0.6234, 1.5000, -0.6426, 1.8564, 0.5636},
};

int hd_perez_category(double eps)
{
    for (int i = 0; i < 8; i++)
        if (eps >= eps_bounds[i] && eps < eps_bounds[i + 1]) return i;
    return eps < 1 ? 0 : 7;
}

double hd_air_mass(double z)
{
    return 1.0 / (cos(z) + 0.15 * pow(93.885 - z * 180 / HD_PI, -1.253));
}

double hd_eccentricity(int jd)
{
    double g = 2 * HD_PI * (jd - 1) / 365.0;
    return 1.00011 + 0.034221 * cos(g) + 0.00128 * sin(g) + 0.000719 * cos(2 * g) + 0.000077 * sin(2 * g);
}

double hd_perez_diffuse_efficacy(int k, double w, double z, double delta)
{
    const double *t = efficacy_tab[k];
    return t[0] + t[1] * w + t[2] * cos(z) + t[3] * log(delta);
}

double hd_perez_direct_efficacy(int k, double w, double z, double delta)
{
    const double *t = efficacy_tab[k] + 4;
    double v = t[0] + t[1] * w + t[2] * exp(5.73 * z - 5) + t[3] * delta;
    return v > 0 ? v : 0;
}

void hd_perez_params(double z, double eps, double delta, double coef[5])
{
    int k = hd_perez_category(eps);
    if (eps > 1.065 && eps < 2.8 && delta < 0.2) delta = 0.2;
    const double *x = perez_tab[k];
    for (int i = 0; i < 5; i++) {
        const double *c = x + 4 * i;
        coef[i] = c[0] + c[1] * z + delta * (c[2] + c[3] * z);
    }
    if (k == 0) {
        coef[2] = exp(pow(delta * (x[8] + x[9] * z), x[10])) - x[11];
        coef[3] = -exp(delta * (x[12] + x[13] * z)) + x[14] + delta * x[15];
    }
}

double hd_perez_rel_lum(const hd_perez *p, double zeta, double gamma)
{
    const double *c = p->coef;
    double cg = cos(gamma);
    double v = (1 + c[0] * exp(c[1] / cos(zeta))) * (1 + c[2] * exp(c[3] * gamma) + c[4] * cg * cg);
    return v > 0 ? v : 0;
}

static void clearness_brightness(double z, int jd, double dni, double dhi, double *eps, double *delta)
{
    double z3 = 1.041 * z * z * z;
    *delta = dhi * hd_air_mass(z) / (HD_SOLAR_CONSTANT * hd_eccentricity(jd));
    *eps = ((dhi + dni) / dhi + z3) / (1 + z3);   /* dhi = 0 gives +inf, clamped below */
    if (!(*eps <= 11.9)) *eps = 11.9;
    if (*eps < 1) *eps = 1;
    if (!(*delta >= 0.01)) *delta = 0.01;
    if (*delta > 0.6) *delta = 0.6;
}

void hd_perez_compute(hd_perez *p, double alt, int jd, double v1, double v2, int units, double dew,
                      int solar_output)
{
    /* gendaymtx: at most 5 iterations, until changes are below 10 W/m2 */
    hd_perez_compute_iter(p, alt, jd, v1, v2, units, dew, solar_output, 5, 10);
}

void hd_perez_compute_iter(hd_perez *p, double alt, int jd, double v1, double v2, int units, double dew,
                           int solar_output, int maxiter, double tol)
{
    memset(p, 0, sizeof *p);
    if (alt > 87 * HD_PI / 180) p->sun_zenith = 3 * HD_PI / 180;
    else if (alt <= 0) p->sun_zenith = HD_PI / 2;
    else p->sun_zenith = HD_PI / 2 - alt;
    double z = p->sun_zenith;
    if (isnan(dew)) dew = 11.0;
    p->precip_water = exp(0.07 * dew - 0.075);
    double w = p->precip_water;
    double dni = v1, dhi = v2;
    if (units == 2) dni = alt > 0 ? v1 / sin(alt) : 0;
    if (dni < 0) dni = 0;
    if (dhi < 0) dhi = 0;
    if (units == 3) {
        /* photometric input: find the irradiances whose efficacies give
         * these illuminances */
        double lux_b = dni, lux_d = dhi;
        double ib = lux_b * HD_SOLAR_CONSTANT / 127500, id = lux_d * HD_SOLAR_CONSTANT / 127500;
        for (int it = 0; it < maxiter; it++) {
            double eps, delta;
            clearness_brightness(z, jd, ib, id, &eps, &delta);
            int k = hd_perez_category(eps);
            double kd = hd_perez_diffuse_efficacy(k, w, z, delta);
            double kb = hd_perez_direct_efficacy(k, w, z, delta);
            double nd = kd > 0 ? lux_d / kd : 0, nb = kb > 0 ? lux_b / kb : 0;
            int done = fabs(nd - id) < tol && fabs(nb - ib) < tol;
            id = nd;
            ib = nb;
            if (done) break;
        }
        p->dni = ib;
        p->dhi = id;
        clearness_brightness(z, jd, ib, id, &p->epsilon, &p->delta);
        p->category = hd_perez_category(p->epsilon);
        p->diff_illum = lux_d;
        p->dir_illum = ib > 0 ? lux_b : 0;   /* no direct irradiance found: no sun */
    } else {
        p->dni = dni;
        p->dhi = dhi;
        clearness_brightness(z, jd, dni, dhi, &p->epsilon, &p->delta);
        p->category = hd_perez_category(p->epsilon);
        p->diff_illum = dhi * hd_perez_diffuse_efficacy(p->category, w, z, p->delta);
        p->dir_illum = dni * hd_perez_direct_efficacy(p->category, w, z, p->delta);
    }
    if (solar_output) {
        p->diff_illum = p->dhi * HD_WHTEFFICACY;
        p->dir_illum = p->dni * HD_WHTEFFICACY;
    }
    hd_perez_params(z, p->epsilon, p->delta, p->coef);
}

void hd_daymtx_opts_default(hd_daymtx_opts *o)
{
    memset(o, 0, sizeof *o);
    o->skycolor[0] = 0.960; o->skycolor[1] = 1.004; o->skycolor[2] = 1.118;
    o->suncolor[0] = o->suncolor[1] = o->suncolor[2] = 1;
    o->grefl[0] = o->grefl[1] = o->grefl[2] = 0.2;
    o->nsuns = 4;
}

#define MAXSUNS 16

double hd_daymtx_solar_time(const hd_site *site, const hd_daymtx_opts *o, int jd, double hour)
{
    double st = hour + hd_sun_time_adjust(site, jd);
    if (o && o->interval_min > 0) {
        double half = o->interval_min / 120.0, rise, set;
        hd_sun_rise_set(site, jd, &rise, &set);
        if (rise > 0 && rise < set) {
            if (fabs(st - rise) <= half) st = (st + half + rise) / 2;
            else if (fabs(st - set) <= half) st = (st - half + set) / 2;
        }
    }
    return st;
}

void hd_daymtx_column(const hd_skybasis *b, const hd_daymtx_opts *o, const hd_site *site,
                      const hd_daymtx_step *t, double *out, hd_daymtx_info *info)
{
    int n = b->nbins;
    double decl = hd_sun_declination(t->jd);
    double st = hd_daymtx_solar_time(site, o, t->jd, t->hour);
    double alt = hd_sun_altitude(site, decl, st);
    double azi = hd_sun_azimuth(site, decl, st) + HD_PI - o->rotation_deg * HD_PI / 180;
    hd_daymtx_info inf;
    memset(&inf, 0, sizeof inf);
    inf.alt = alt;
    inf.azi = azi;
    if (t->v1 + t->v2 <= 1e-4) {
        memset(out, 0, sizeof(double) * 3 * (size_t)n);
        inf.night = 1;
        if (info) *info = inf;
        return;
    }
    if (t->v1 > 20 && alt < -HD_SUN_HALFANGLE_RAD) inf.bright_below = 1;
    hd_perez p;
    hd_perez_compute(&p, alt, t->jd, t->v1, t->v2, t->units, t->dewpoint, o->solar_output);
    inf.dir_illum = p.dir_illum;
    inf.diff_illum = p.diff_illum;
    double skybright = hd_color_bright(o->skycolor);
    /* the sky branch writes every element; otherwise start from zeros */
    if (!(skybright > 1e-4 && !o->sun_only)) memset(out, 0, sizeof(double) * 3 * (size_t)n);
    if (skybright > 1e-4 && !o->sun_only) {
        double g = p.diff_illum;
        if (alt > 0) g += p.dir_illum * sin(alt);
        g *= 1.0 / HD_PI / HD_WHTEFFICACY;
        for (int c = 0; c < 3; c++) out[c] = g * o->grefl[c];
        double z = p.sun_zenith, cz = cos(z), sz = sin(z);
        /* sun direction with the clamped zenith angle: cos(gamma) is a dot
         * product with the patch centre; the zenith-angle factor
         * (1 + a exp(b / cos zeta)) is the same for a whole band */
        hd_vec3 s = hd_v3(sz * sin(azi), sz * cos(azi), cz);
        const double *c = p.coef;
        double norm = 0;
        for (int r = 0; r <= b->nbands; r++) {
            int i0 = b->band_first[r], i1 = r < b->nbands ? i0 + b->band_count[r] : i0 + 1;
            double czeta = sin(b->alt[i0]);
            double fz = 1 + c[0] * exp(c[1] / czeta);
            double bandsum = 0;
            for (int i = i0; i < i1; i++) {
                double cg = hd_vdot(b->dir[i], s);
                if (cg > 1) cg = 1;
                if (cg < -1) cg = -1;
                double lv = fz * (1 + c[2] * exp(c[3] * acos(cg)) + c[4] * cg * cg);
                if (lv < 0) lv = 0;
                out[3 * i] = lv;
                bandsum += lv;
            }
            norm += bandsum * czeta * b->omega[i0];
        }
        if (norm < 1e-4) {
            norm = 0;
            for (int i = 1; i < n; i++) {
                out[3 * i] = 1;
                norm += sin(b->alt[i]) * b->omega[i];
            }
        }
        double scale = p.diff_illum / norm / HD_WHTEFFICACY;
        for (int i = 1; i < n; i++) {
            double v = out[3 * i] * scale;
            for (int c = 0; c < 3; c++) out[3 * i + c] = v * o->skycolor[c];
        }
    }
    if (!o->sky_only && p.dir_illum > 1e-4) {
        double sunbright = hd_color_bright(o->suncolor);
        if (sunbright > 1e-4) {
            int ns = o->disk_deg > 0 ? 1 : o->nsuns;
            if (ns < 1) ns = 1;
            if (ns > MAXSUNS) ns = MAXSUNS;
            hd_vec3 sv = hd_v3(cos(alt) * sin(azi), cos(alt) * cos(azi), sin(alt));
            int idx[MAXSUNS];
            double dp[MAXSUNS];
            for (int k = 0; k < ns; k++) { idx[k] = -1; dp[k] = -2; }
            for (int i = 1; i < n; i++) {
                double d = hd_vdot(b->dir[i], sv);
                if (d <= dp[ns - 1]) continue;
                int k = ns - 1;
                while (k > 0 && dp[k - 1] < d) {
                    dp[k] = dp[k - 1];
                    idx[k] = idx[k - 1];
                    k--;
                }
                dp[k] = d;
                idx[k] = i;
            }
            double wt[MAXSUNS], wtot = 0;
            for (int k = 0; k < ns; k++) wtot += wt[k] = 1.0 / (1.002 - dp[k]);
            double disk = 0;
            if (o->disk_deg > 0) {
                double r = o->disk_deg * HD_PI / 360;
                disk = HD_PI * r * r;
            }
            for (int k = 0; k < ns; k++) {
                int i = idx[k];
                if (i < 0) continue;
                double v = wt[k] / wtot * p.dir_illum / HD_WHTEFFICACY / (disk > 0 ? disk : b->omega[i]);
                for (int c = 0; c < 3; c++) out[3 * i + c] += v * o->suncolor[c];
            }
        }
    }
    if (info) *info = inf;
}

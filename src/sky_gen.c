/* heliodon — sky descriptions: Perez skies as gendaylit writes them and CIE
 * skies as gensky writes them (see sky.h, docs/design/sky.md). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "heliodon/sky.h"

#define SUN_SA_DAYLIT (2 * HD_PI * (1 - cos(HD_SUN_HALFANGLE_RAD)))   /* 0.533 deg disk */
#define SUNEFFICACY 208.0      /* lm/W used by gensky for the sun */
#define SKYEFFICACY 203.0      /* lm/W used by gensky for the sky (D65) */

/* The same normalisation as Radiance's gensky and gendaylit compute it: a
 * fourth-degree polynomial in x = (alt - 45 deg) / 45 deg fitted to
 * E_horizontal * F2 / L_zenith, divided by pi and by the sky type's own
 * zenith indicatrix F2 (the constants are the published fit; the exact
 * integral of the distribution differs by up to ~1 % at intermediate
 * altitudes). */
/* gensky's F2: the (unnormalised) CIE clear / intermediate distribution at
 * the zenith for a sun at altitude alt, as gensky writes it for skybright.cal */
static double cie_f2(hd_skytype type, double alt)
{
    double zt = HD_PI / 2 - alt, sa = sin(alt);
    if (type == HD_SKY_CIE_CLEAR) return 0.274 * (0.91 + 10 * exp(-3 * zt) + 0.45 * sa * sa);
    return (2.739 + 0.9891 * sin(0.3119 + 2.6 * alt)) * exp(-zt * (0.4441 + 1.48 * alt));
}

double hd_cie_norm_fitted(hd_skytype type, double alt)
{
    static const double clear_fit[5] = {2.766521, 0.547665, -0.369832, 0.009237, 0.059229};
    static const double inter_fit[5] = {3.5556, -2.7152, -1.3081, 1.0660, 0.60227};
    const double *c;
    if (type == HD_SKY_CIE_CLEAR) {
        c = clear_fit;
    } else if (type == HD_SKY_CIE_INTERMEDIATE) {
        c = inter_fit;
    } else if (type == HD_SKY_CIE_OVERCAST) {
        return 7.0 / 9.0;
    } else {
        return 1;
    }
    double x = (alt - HD_PI / 4) / (HD_PI / 4), poly = 0;
    for (int k = 4; k >= 0; k--) poly = poly * x + c[k];
    return poly / cie_f2(type, alt) / HD_PI;
}

/* ---- gendaylit ---- */

void hd_daylit_opts_default(hd_daylit_opts *o)
{
    memset(o, 0, sizeof *o);
    o->ground_refl = 0.2;
    o->dewpoint = (log(2.0) + 0.075) / 0.07;   /* precipitable water 2 cm */
    o->with_sun = 1;
}

/* Perez relative luminance integrated over 145 fixed directions (the
 * Tregenza patch centres: zenith angles 84, 72, ... 12 deg with 30, 30, 24,
 * 24, 18, 12, 6 azimuths, and the zenith) with equal weights 2 pi / 145,
 * the discrete normalisation gendaylit uses.  The azimuths are counted from
 * the sun's azimuth (as gendaylit does), so the result depends only on the
 * sun's zenith angle. */
static double daylit_integral(const hd_perez *p, double sun_zenith)
{
    static const int tn[7] = {30, 30, 24, 24, 18, 12, 6};
    double cz = cos(sun_zenith), sz = sin(sun_zenith), sum = 0;
    for (int r = 0; r <= 7; r++) {
        int n = r < 7 ? tn[r] : 1;
        double th = r < 7 ? (84 - 12 * r) * HD_PI / 180 : 0;
        double ct = cos(th), st = sin(th);
        for (int c = 0; c < n; c++) {
            double cg = cz * ct + sz * st * cos(2 * HD_PI * c / n);
            if (cg > 1) cg = 1;
            if (cg < -1) cg = -1;
            double lv = (1 + p->coef[0] * exp(p->coef[1] / ct)) * (1 + p->coef[2] * exp(p->coef[3] * acos(cg)) +
                                                                  p->coef[4] * cg * cg);
            sum += lv * ct;
        }
    }
    return sum * 2 * HD_PI / 145;
}

/* The sun of a gendaylit / gensky command: from -ang altitude and azimuth
 * (day of year jd_angles, solar hour 0), or from the site, day and time. */
static hd_sunpos sky_sun(const hd_site *site, int use_angles, double alt_deg, double azi_deg, int jd_angles, int jd,
                         double hour, int solar_time)
{
    hd_sunpos sp;
    if (use_angles) {
        sp.jd = jd_angles;
        sp.solar_hour = 0;
        sp.alt = alt_deg * HD_PI / 180;
        sp.azi = azi_deg * HD_PI / 180;
        sp.dir = hd_sun_vector(sp.alt, sp.azi);
    } else {
        hd_sun_position(site, jd, hour, solar_time, &sp);
    }
    return sp;
}

static double erbs_fraction(double kt)
{
    if (kt <= 0.22) return 1 - 0.09 * kt;
    if (kt <= 0.80) return 0.9511 - 0.1604 * kt + 4.388 * kt * kt - 16.638 * kt * kt * kt + 12.336 * kt * kt * kt * kt;
    return 0.165;
}

hd_status hd_gendaylit(FILE *fp, const hd_daylit_opts *o, const char *cmdline, char *warn, size_t warncap)
{
    if (warn && warncap) warn[0] = 0;
    hd_sunpos sp = sky_sun(&o->site, o->use_angles, o->alt_deg, o->azi_deg, o->jd > 0 ? o->jd : 1, o->jd, o->hour,
                           o->solar_time);
    double alt = sp.alt;
    fprintf(fp, "# %s\n", cmdline ? cmdline : "gendaylit");
    double v1 = o->v1, v2 = o->v2;
    int units = 1;
    if (o->mode == 'E') {
        double s0 = HD_SOLAR_CONSTANT * hd_eccentricity(sp.jd) * sin(alt);
        double kt = s0 > 0 ? o->v1 / s0 : 0;
        if (kt > 1) kt = 1;
        double diff = o->v1 * erbs_fraction(kt);
        double dirh = o->v1 - diff;
        fprintf(fp, "# erbs_s0, erbs_kt, irr_dir_h, irr_diff: %.3f %.3f %.3f %.3f\n", s0, kt, dirh, diff);
        fprintf(fp, "# WARNING: the -E option is only recommended for a rough estimation!\n");
        v1 = dirh;
        v2 = diff;
        units = 2;
    } else if (o->mode == 'G') {
        units = 2;
    } else if (o->mode == 'L') {
        units = 3;
    }
    if (!o->use_angles) {
        fprintf(fp, "# Local solar time: %.2f\n", sp.solar_hour);
    } else {
        fprintf(fp, "# Local solar time: %.2f\n", 0.0);
    }
    fprintf(fp, "# Solar altitude and azimuth: %.1f %.1f\n", alt * 180 / HD_PI, sp.azi * 180 / HD_PI);
    hd_vec3 s = sp.dir;
    int error_sky = 0;
    hd_perez p;
    if (alt <= 0) {
        error_sky = 1;
        if (warn)
            snprintf(warn, warncap, "Warning: sun altitude below zero at time step %d %d %.2f, printing error sky",
                     o->month, o->day, o->hour);
    } else if (o->mode == 'P') {
        /* clearness and brightness given: irradiances that produce them */
        double z = HD_PI / 2 - alt;
        double kz = 1.041 * z * z * z;
        double dhi = o->v2 * HD_SOLAR_CONSTANT * hd_eccentricity(sp.jd) / hd_air_mass(z);
        double dni = dhi * (o->v1 * (1 + kz) - kz - 1);
        hd_perez_compute(&p, alt, sp.jd, dni, dhi, 1, o->dewpoint, o->output == 1);
        p.epsilon = o->v1;
        p.delta = o->v2;
        p.category = hd_perez_category(p.epsilon);
        hd_perez_params(p.sun_zenith, p.epsilon, p.delta, p.coef);
    } else {
        hd_perez_compute_iter(&p, alt, sp.jd, v1, v2, units, o->dewpoint, o->output == 1, 15, 0.01);
    }
    if (!error_sky && p.coef[1] > 0) {
        error_sky = 1;
        if (warn)
            snprintf(warn, warncap, "Warning: positive Perez parameter B (= %f), printing error sky", p.coef[1]);
    }
    if (error_sky) {
        fprintf(fp, "\nvoid brightfunc skyfunc\n2 skybright perezlum.cal\n0\n");
        fprintf(fp, "10 0.00 0.00  0.000 0.000 0.000 0.000 0.000  %f %f %f \n", s.x, s.y, s.z);
        return ferror(fp) ? hd_fail(HD_ERR_IO, "write error") : HD_OK;
    }
    fprintf(fp, "# epsilon, delta, atmospheric precipitable water content : %.4f %.4f %.4f \n", p.epsilon, p.delta,
            p.precip_water);
    /* output quantity: 0 visible radiance, 1 solar radiance, 2 luminance */
    double unit = o->output == 2 ? HD_WHTEFFICACY : 1;
    double dir_illum = p.dir_illum, diff_illum = p.diff_illum;
    double sunrad = dir_illum / SUN_SA_DAYLIT / HD_WHTEFFICACY * unit;
    double integ = daylit_integral(&p, HD_PI / 2 - alt);
    double diffnorm = diff_illum / HD_WHTEFFICACY / integ * unit;
    /* ground: the zenith radiance times the horizontal-illuminance factor of
     * the CIE sky type closest to these conditions, plus the sun */
    double zt = HD_PI / 2 - alt;
    double lvz = (1 + p.coef[0] * exp(p.coef[1])) * (1 + p.coef[2] * exp(p.coef[3] * zt) +
                                                     p.coef[4] * cos(zt) * cos(zt));
    /* Radiance's rule: overcast for epsilon == 1 (no direct light), CIE clear
     * from epsilon 6 up, intermediate in between; its fitted normalisation */
    double nf;
    if (p.epsilon <= 1) nf = hd_cie_norm_fitted(HD_SKY_CIE_OVERCAST, alt);
    else if (p.epsilon >= 6) nf = hd_cie_norm_fitted(HD_SKY_CIE_CLEAR, alt);
    else nf = hd_cie_norm_fitted(HD_SKY_CIE_INTERMEDIATE, alt);
    double ground = o->ground_refl * (nf * diffnorm * lvz);
    /* the sun's horizontal contribution, with Radiance's rounded solid angle
     * of the disk (6.8e-5 sr; exact 6.796e-5), only when there is direct light */
    if (o->with_sun && p.epsilon > 1) ground += o->ground_refl * 6.8e-5 / HD_PI * sunrad * sin(alt);
    if (o->with_sun) {
        if (sunrad > 0) fprintf(fp, "\nvoid light solar\n0\n0\n3 %.3e %.3e %.3e\n", sunrad, sunrad, sunrad);
        else fprintf(fp, "\nvoid light solar\n0\n0\n3 0.0 0.0 0.0\n");
        fprintf(fp, "\nsolar source sun\n0\n0\n4 %f %f %f %f\n", s.x, s.y, s.z, HD_SUN_DIAMETER);
    }
    fprintf(fp, "\nvoid brightfunc skyfunc\n2 skybright perezlum.cal\n0\n");
    fprintf(fp, "10 %.3e %.3e %f %f %f %f %f %f %f %f \n", diffnorm, ground, p.coef[0], p.coef[1], p.coef[2],
            p.coef[3], p.coef[4], s.x, s.y, s.z);
    return ferror(fp) ? hd_fail(HD_ERR_IO, "write error") : HD_OK;
}

/* ---- gensky ---- */

void hd_gensky_opts_default(hd_gensky_opts *o)
{
    memset(o, 0, sizeof *o);
    o->type = HD_SKY_CIE_CLEAR;
    o->with_sun = 1;
    o->turbidity = 2.45;
    o->ground_refl = 0.2;
    o->zenith_br = -1;
    o->horiz_irr = -1;
    o->solar_rad = -1;
    o->solar_irr = -1;
}

hd_status hd_gensky(FILE *fp, const hd_gensky_opts *o, const char *cmdline)
{
    hd_sunpos sp = sky_sun(&o->site, o->use_angles, o->alt_deg, o->azi_deg, 1, o->jd, o->hour, o->solar_time);
    double alt = sp.alt;
    fprintf(fp, "# %s\n", cmdline ? cmdline : "gensky");
    if (!o->use_angles) {
        fprintf(fp, "# Local solar time: %.2f\n", sp.solar_hour);
        fprintf(fp, "# Solar altitude and azimuth: %.1f %.1f\n", alt * 180 / HD_PI, sp.azi * 180 / HD_PI);
    }
    int type = o->type;
    int sunny = (type == HD_SKY_CIE_CLEAR || type == HD_SKY_CIE_INTERMEDIATE);
    if (sunny && alt > 87 * HD_PI / 180) {   /* as Radiance: the CIE formulas need a sun off the zenith */
        hd_warn("sun too close to zenith, reducing altitude to 87 degrees");
        fprintf(fp, "# warning - sun too close to zenith, reducing altitude to 87 degrees\n");
        alt = 87 * HD_PI / 180;
        sp.dir = hd_sun_vector(alt, sp.azi);
    }
    /* sky normalisation (horizontal illuminance / (pi * zenith luminance)) */
    double nf = 1, a4 = 1;
    switch (type) {
    case HD_SKY_CIE_OVERCAST: nf = 7.0 / 9.0; break;
    case HD_SKY_UNIFORM: nf = 1; break;
    case HD_SKY_CIE_CLEAR:
        nf = hd_cie_norm_fitted(type, alt);
        a4 = cie_f2(type, alt);
        break;
    case HD_SKY_CIE_INTERMEDIATE:
        nf = hd_cie_norm_fitted(type, alt);
        a4 = cie_f2(type, alt);
        break;
    default: break;
    }
    /* zenith brightness (W/sr/m2) */
    double zen;
    if (o->zenith_br >= 0) zen = o->zenith_br;
    else if (o->horiz_irr >= 0) zen = o->horiz_irr / (HD_PI * nf);
    else {
        double kcd;
        double sa = alt;
        switch (type) {
        case HD_SKY_CIE_CLEAR: kcd = (1.376 * o->turbidity - 1.81) * tan(sa) + 0.38; break;
        case HD_SKY_CIE_INTERMEDIATE:   /* mean of the clear and overcast zenith luminances */
            kcd = ((1.376 * o->turbidity - 1.81) * tan(sa) + 0.38 + 8.6 * sin(sa) + 0.123) / 2;
            break;
        default: kcd = 8.6 * sin(sa) + 0.123; break;
        }
        zen = kcd * 1000 / SKYEFFICACY;
    }
    if (zen < 0) zen = 0;
    /* sun */
    double solarbr = 0;
    int sunup = sunny && alt > 0;
    int dosun = o->with_sun && sunup;
    if (sunup) {   /* the ground sees the sun even with -s / -i */
        if (o->solar_rad >= 0) solarbr = o->solar_rad;
        else if (o->solar_irr >= 0)   /* -R: direct HORIZONTAL irradiance (Radiance's man page) */
            solarbr = o->solar_irr / (5.98e-5 * sin(alt));   /* Radiance's disk solid angle */
        else {
            solarbr = 1.5e9 / SUNEFFICACY * (1.147 - 0.147 / fmax(sin(alt), 0.16));
            if (type == HD_SKY_CIE_INTERMEDIATE) solarbr *= 0.15;
        }
    }
    double ambient = zen * nf;
    double ground = ambient;
    /* the sun on the ground, with Radiance's rounded disk solid angle 6e-5 sr */
    if (sunup) ground += solarbr * 6e-5 * sin(alt) / HD_PI;
    ground *= o->ground_refl;
    fprintf(fp, "# Ground ambient level: %.1f\n", ambient);
    if (dosun) {
        fprintf(fp, "\nvoid light solar\n0\n0\n3 %.3e %.3e %.3e\n", solarbr, solarbr, solarbr);
        fprintf(fp, "\nsolar source sun\n0\n0\n4 %f %f %f 0.5\n", sp.dir.x, sp.dir.y, sp.dir.z);
    }
    fprintf(fp, "\nvoid brightfunc skyfunc\n2 skybr skybright.cal\n0\n");
    int code = type == HD_SKY_CIE_CLEAR ? 1 : type == HD_SKY_CIE_OVERCAST ? 2 : type == HD_SKY_UNIFORM ? 3 : 4;
    if (sunny)
        fprintf(fp, "7 %d %.3e %.3e %.3e %f %f %f\n", code, zen, ground, a4, sp.dir.x, sp.dir.y, sp.dir.z);
    else
        fprintf(fp, "3 %d %.3e %.3e\n", code, zen, ground);
    return ferror(fp) ? hd_fail(HD_ERR_IO, "write error") : HD_OK;
}

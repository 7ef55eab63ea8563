/* heliodon — solar position (formulas of Radiance's sun.c, see solar.h). */
#include <math.h>

#include "heliodon/solar.h"

static const int cumdays[12] = {0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334};

int hd_julian_day(int month, int day)
{
    if (month < 1) month = 1;
    if (month > 12) month = 12;
    return cumdays[month - 1] + day;
}

double hd_sun_declination(int jd)
{
    return 0.4093 * sin(2 * HD_PI * (jd - 81) / 365.0);
}

double hd_sun_time_adjust(const hd_site *s, int jd)
{
    double lon = s->lon * HD_PI / 180, mer = s->meridian * HD_PI / 180;
    return 0.170 * sin(4 * HD_PI * (jd - 80) / 373.0) - 0.129 * sin(2 * HD_PI * (jd - 8) / 355.0) +
           12 * (mer - lon) / HD_PI;
}

double hd_sun_altitude(const hd_site *s, double decl, double st)
{
    double lat = s->lat * HD_PI / 180;
    return asin(sin(lat) * sin(decl) - cos(lat) * cos(decl) * cos(st * (HD_PI / 12)));
}

double hd_sun_azimuth(const hd_site *s, double decl, double st)
{
    double lat = s->lat * HD_PI / 180;
    return -atan2(cos(decl) * sin(st * (HD_PI / 12)),
                  -cos(lat) * sin(decl) - sin(lat) * cos(decl) * cos(st * (HD_PI / 12)));
}

void hd_sun_rise_set(const hd_site *s, int jd, double *rise, double *set)
{
    double lat = s->lat * HD_PI / 180;
    double w = -tan(lat) * tan(hd_sun_declination(jd));
    if (w >= 1) { *rise = *set = 12; return; }     /* polar night */
    if (w <= -1) { *rise = 0; *set = 24; return; } /* midnight sun */
    double h = (HD_PI / 2 - atan2(w, sqrt(1 - w * w))) * 180 / (15 * HD_PI);
    *rise = 12 - h;
    *set = 12 + h;
}

hd_vec3 hd_sun_vector(double alt, double azi)
{
    return hd_v3(-sin(azi) * cos(alt), -cos(azi) * cos(alt), sin(alt));
}

void hd_sun_position(const hd_site *s, int jd, double hour, int is_solar, hd_sunpos *out)
{
    double decl = hd_sun_declination(jd);
    out->jd = jd;
    out->solar_hour = is_solar ? hour : hour + hd_sun_time_adjust(s, jd);
    out->alt = hd_sun_altitude(s, decl, out->solar_hour);
    out->azi = hd_sun_azimuth(s, decl, out->solar_hour);
    out->dir = hd_sun_vector(out->alt, out->azi);
}

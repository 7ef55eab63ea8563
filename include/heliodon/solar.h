/* heliodon — Radiance's simple solar-position algorithm (sun.c), as used by
 * gendaymtx, gendaylit and gensky.
 *
 * Conventions follow Radiance: latitude north-positive; longitude and
 * standard meridian WEST-positive (degrees; meridian = 15 * hours west of
 * Greenwich, so UTC+2 is -30); day of year without leap day; hours in local
 * standard time unless a solar time is given.  Azimuth as returned here is
 * measured from SOUTH, positive towards WEST (gensky/gendaylit comments). */
#ifndef HELIODON_SOLAR_H
#define HELIODON_SOLAR_H

#include "vec.h"

typedef struct hd_site {
    double lat;       /* degrees north */
    double lon;       /* degrees WEST */
    double meridian;  /* standard meridian, degrees WEST */
    double elev;      /* metres (informative) */
} hd_site;

/* Day of year 1..365 (Feb 29 -> 60, like Mar 1). month 1..12. */
int hd_julian_day(int month, int day);
/* Solar declination (radians) for day of year jd. */
double hd_sun_declination(int jd);
/* Solar time minus standard time (hours) at the site for day jd. */
double hd_sun_time_adjust(const hd_site *s, int jd);
/* Altitude (rad) for declination and solar time (hours). */
double hd_sun_altitude(const hd_site *s, double decl, double solar_hour);
/* Azimuth (rad) from south, positive towards west. */
double hd_sun_azimuth(const hd_site *s, double decl, double solar_hour);
/* Sunrise / sunset in solar time (hours) for day jd (NaN-free: polar day
 * gives 0/24, polar night 12/12). */
void hd_sun_rise_set(const hd_site *s, int jd, double *rise, double *set);

typedef struct hd_sunpos {
    int jd;              /* day of year used */
    double solar_hour;   /* local solar time (hours) */
    double alt;          /* altitude (rad) */
    double azi;          /* azimuth from south towards west (rad) */
    hd_vec3 dir;         /* unit vector towards the sun: x east, y north, z up */
} hd_sunpos;

/* Position for month, day, hour (standard time; solar time if is_solar). */
void hd_sun_position(const hd_site *s, int jd, double hour, int is_solar, hd_sunpos *out);
/* Sun direction (x east, y north, z up) from altitude and azimuth
 * (from south towards west), as gensky/gendaylit write it. */
hd_vec3 hd_sun_vector(double alt, double azi_south_west);

#endif

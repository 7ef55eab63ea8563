/* heliodon — date/time arguments of gensky and gendaylit:
 * "month day hour" where hour is decimal ("14.5"), "HH:MM", solar time with
 * a leading '+' ("+12"), or carries a time-zone suffix ("14:30CDT": the
 * zone sets the standard meridian, daylight zones subtract one hour). */
#ifndef HELIODON_SKYTIME_H
#define HELIODON_SKYTIME_H

#include "common.h"

typedef struct hd_skytime {
    int month, day;
    double hour;          /* standard (or solar) time, hours */
    int solar;            /* given as solar time */
    int has_zone;         /* a zone suffix gave the meridian */
    double meridian;      /* degrees west, when has_zone */
} hd_skytime;

/* Parse the three words; errors name the offending word. */
hd_status hd_skytime_parse(const char *month, const char *day, const char *hour, hd_skytime *t);

/* The three leading words of gensky and gendaylit, argv[1..3]: either
 * "-ang altitude azimuth" (degrees) or "month day hour[zone]".
 * HD_ERR_FORMAT for bad -ang numbers, HD_ERR_USAGE for bad date words
 * (the programs then also print their usage). */
typedef struct hd_skywhen {
    int use_angles;          /* -ang given */
    double alt_deg, azi_deg; /* with -ang */
    hd_skytime t;            /* otherwise */
} hd_skywhen;
hd_status hd_skywhen_parse(char **argv, hd_skywhen *w);

#endif

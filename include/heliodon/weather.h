/* heliodon — weather files: Radiance WEA and EnergyPlus EPW.
 *
 * WEA (epw2wea / gendaymtx input):
 *   place <name>
 *   latitude <deg north>
 *   longitude <deg WEST>
 *   time_zone <standard meridian, deg WEST>
 *   site_elevation <m>
 *   weather_data_file_units <1|2|3>
 *   <month> <day> <hour, decimal standard time> <v1> <v2> [more columns ignored]
 * units 1: direct normal + diffuse horizontal irradiance (W/m2); 2: direct
 * horizontal + diffuse horizontal (W/m2); 3: direct normal + diffuse
 * horizontal illuminance (lux).
 *
 * EPW: 8 header lines (LOCATION ... DATA PERIODS) then comma-separated hourly
 * records; the hour is "hour ending" and becomes hour - 0.5 (1 record per
 * hour) as in Radiance.  Longitude (east-positive in the EPW) and time zone
 * (hours) are converted to Radiance's west-positive convention.
 *
 * Errors name the file and line, and what was expected. */
#ifndef HELIODON_WEATHER_H
#define HELIODON_WEATHER_H

#include <stdio.h>
#include "common.h"
#include "solar.h"

typedef struct hd_weather_rec {
    int year;              /* EPW year, 0 for WEA */
    int month, day;
    double hour;           /* decimal standard time (0..24) */
    double v1, v2;         /* WEA values in the file's units (EPW: DNI, DHI W/m2) */
    double dewpoint;       /* deg C (EPW column 8); NAN if not given */
    double ghi;            /* EPW global horizontal W/m2, NAN otherwise */
    double dni_lux, dhi_lux; /* EPW illuminances, NAN if missing/absent */
    unsigned long line;    /* line number in the file */
} hd_weather_rec;

typedef struct hd_weather {
    char name[512];        /* file name for messages */
    char place[256];       /* WEA place / EPW "city_country" */
    char lat_text[64];     /* latitude and elevation as written in the file */
    char elev_text[64];
    hd_site site;          /* west-positive longitude and meridian */
    double tz_hours;       /* EPW time zone (hours east of UTC) */
    int units;             /* 1, 2 or 3 */
    int is_epw;
    int records_per_hour;  /* EPW DATA PERIODS (1 for WEA) */
    size_t n, cap;
    hd_weather_rec *rec;
} hd_weather;

void hd_weather_init(hd_weather *w);
void hd_weather_free(hd_weather *w);

/* Read a WEA or EPW file ("-" = stdin, gzip transparently); the kind is
 * detected from the first line ("place " -> WEA, "LOCATION," -> EPW). */
hd_status hd_weather_read(const char *path, hd_weather *w);
/* Parse from memory (used by tests). */
hd_status hd_weather_read_memory(const char *text, size_t len, const char *name, hd_weather *w);

/* Dew point for record i as gendaymtx uses it: mean of this and up to two
 * previous records' dew points, or NAN if the file has none. */
double hd_weather_dewpoint(const hd_weather *w, size_t i);

/* Write a WEA file as epw2wea does (header, "%d %d %.3f %.0f %.0f"). */
hd_status hd_weather_write_wea(FILE *fp, const hd_weather *w);
/* Only the 6 header lines. */
hd_status hd_weather_write_wea_header(FILE *fp, const char *place, const char *lat_text,
                                      double lon_west, double meridian_west,
                                      const char *elev_text, int units);

/* ---- synthetic weather (genwea) ----
 * A deterministic synthetic year (8760 hourly records, hour-ending
 * convention as epw2wea: hh.5 standard time, units 1), documented in
 * docs/design/sky.md:
 *   clear sky   Ineichen & Perez (2002) with a seasonal Linke turbidity
 *               TL = tl_mean + tl_amp * cos(2 pi (J - 196) / 365);
 *   clouds      each day is "cloudy" (cover 0.7..1) or "fair" (0..0.3); the
 *               type is kept from the previous day with probability
 *               cloud_persist, else drawn anew: cloudy with probability
 *               cloud_mean + cloud_amp * cos(2 pi (J - 15) / 365) (most
 *               in January); an hourly AR(1) perturbation (+-0.2) is
 *               added; random numbers come from hd_rng streams keyed by
 *               (seed, 0) for days and (seed, 1000 + day) for hours, so
 *               the output depends only on the options;
 *   irradiance  GHI = GHI_clear * (1 - 0.75 c^3.4) (Kasten & Czeplak),
 *               split with the Erbs diffuse fraction, DNI capped at the
 *               clear-sky DNI.
 * The place name starts with "SYNTHETIC_" so the file is never mistaken
 * for measured data. */
typedef struct hd_synth_opts {
    hd_site site;          /* lat, lon (WEST+), meridian (WEST+), elevation */
    uint64_t seed;
    double tl_mean, tl_amp;         /* Linke turbidity (3.5, 0.5) */
    double cloud_mean, cloud_amp;   /* seasonal probability of a cloudy day (0.4, 0.3) */
    double cloud_persist;           /* probability to keep the day type (0.6) */
    const char *name;               /* appended to the place name */
} hd_synth_opts;
void hd_synth_opts_default(hd_synth_opts *o);
hd_status hd_weather_synth(hd_weather *w, const hd_synth_opts *o);
/* Ineichen-Perez clear-sky irradiances (W/m2) for a sun at altitude alt
 * (rad), day jd, elevation (m) and Linke turbidity; 0 below the horizon. */
void hd_clear_sky(double alt, int jd, double elev, double linke, double *ghi, double *dni, double *dhi);

#endif

/* heliodon — gensky/gendaylit date and time words (see skytime.h). */
#include <ctype.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "heliodon/io.h"
#include "heliodon/skytime.h"

static const struct { const char *name; double meridian; int dst; } zones[] = {
    {"GMT", 0, 0}, {"UTC", 0, 0}, {"WET", 0, 0}, {"BST", 0, 1}, {"WEST", 0, 1},
    {"CET", -15, 0}, {"CEST", -15, 1}, {"MET", -15, 0}, {"MEST", -15, 1},
    {"EET", -30, 0}, {"EEST", -30, 1}, {"TRT", -45, 0}, {"MSK", -45, 0},
    {"IST", -82.5, 0}, {"JST", -135, 0}, {"AEST", -150, 0}, {"AEDT", -150, 1}, {"NZST", -180, 0}, {"NZDT", -180, 1},
    {"AST", 60, 0}, {"ADT", 60, 1}, {"EST", 75, 0}, {"EDT", 75, 1}, {"CST", 90, 0}, {"CDT", 90, 1},
    {"MST", 105, 0}, {"MDT", 105, 1}, {"PST", 120, 0}, {"PDT", 120, 1}, {"YST", 135, 0}, {"YDT", 135, 1},
    {"HST", 150, 0},
};

hd_status hd_skytime_parse(const char *ms, const char *ds, const char *hs, hd_skytime *t)
{
    static const int mdays[12] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    memset(t, 0, sizeof *t);
    long m, d;
    if (hd_parse_long(ms, &m) || m < 1 || m > 12)
        return hd_fail(HD_ERR_USAGE, "bad month '%s' (expected 1..12)", ms);
    if (hd_parse_long(ds, &d) || d < 1 || d > mdays[m - 1])
        return hd_fail(HD_ERR_USAGE, "bad day '%s' for month %ld", ds, m);
    t->month = (int)m;
    t->day = (int)d;
    const char *p = hs;
    if (*p == '+') { t->solar = 1; p++; }
    char num[64];
    size_t n = 0;
    while (p[n] && (isdigit((unsigned char)p[n]) || p[n] == '.' || p[n] == ':') && n < sizeof num - 1) n++;
    memcpy(num, p, n);
    num[n] = 0;
    const char *zone = p + n;
    char *colon = strchr(num, ':');
    double h;
    if (colon) {
        *colon = 0;
        long hh, mm;
        if (hd_parse_long(num, &hh) || hd_parse_long(colon + 1, &mm) || mm < 0 || mm > 59)
            return hd_fail(HD_ERR_USAGE, "bad time '%s' (expected H.H, HH:MM, +H for solar time, or with a zone like 14:30CDT)", hs);
        h = hh + mm / 60.0;
    } else if (hd_parse_double(num, &h)) {
        return hd_fail(HD_ERR_USAGE, "bad time '%s' (expected H.H, HH:MM, +H for solar time, or with a zone like 14:30CDT)", hs);
    }
    if (*zone) {
        if (t->solar) return hd_fail(HD_ERR_USAGE, "bad time '%s': solar time cannot have a time zone", hs);
        size_t k;
        for (k = 0; k < sizeof zones / sizeof zones[0]; k++)
            if (!strcasecmp(zone, zones[k].name)) break;
        if (k == sizeof zones / sizeof zones[0]) return hd_fail(HD_ERR_USAGE, "unknown time zone '%s' in '%s'", zone, hs);
        t->has_zone = 1;
        t->meridian = zones[k].meridian;
        if (zones[k].dst) h -= 1;
    }
    if (h < 0 || h > 24) return hd_fail(HD_ERR_USAGE, "time '%s' out of range 0..24", hs);
    t->hour = h;
    return HD_OK;
}

hd_status hd_skywhen_parse(char **argv, hd_skywhen *w)
{
    memset(w, 0, sizeof *w);
    if (!strcmp(argv[1], "-ang")) {
        if (hd_parse_double(argv[2], &w->alt_deg) || hd_parse_double(argv[3], &w->azi_deg))
            return hd_fail(HD_ERR_FORMAT, "-ang: expected altitude and azimuth in degrees, found '%s' '%s'", argv[2],
                           argv[3]);
        w->use_angles = 1;
        return HD_OK;
    }
    return hd_skytime_parse(argv[1], argv[2], argv[3], &w->t) ? HD_ERR_USAGE : HD_OK;
}

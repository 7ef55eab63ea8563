/* heliodon — WEA and EPW weather readers (see weather.h). */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/io.h"
#include "heliodon/weather.h"

#define LINECAP 16384
#define MAXRECORDS 10000000   /* a year of 1-minute data is 525600 */

static const int mdays[12] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};

void hd_weather_init(hd_weather *w)
{
    memset(w, 0, sizeof *w);
    w->units = 1;
    w->records_per_hour = 1;
}

void hd_weather_free(hd_weather *w)
{
    if (!w) return;
    free(w->rec);
    hd_weather_init(w);
}

static hd_status add_record(hd_weather *w, const hd_weather_rec *r)
{
    if (w->n == w->cap) {
        size_t nc = w->cap ? 2 * w->cap : 1024;
        if (nc > MAXRECORDS) {
            if (w->n >= MAXRECORDS)
                return hd_fail(HD_ERR_RANGE, "%s: line %lu: more than %d records", w->name, r->line,
                               MAXRECORDS);
            nc = MAXRECORDS;
        }
        hd_weather_rec *p = hd_realloc_array(w->rec, nc, sizeof *p);
        if (!p) return HD_ERR_NOMEM;
        w->rec = p;
        w->cap = nc;
    }
    w->rec[w->n++] = *r;
    return HD_OK;
}

static void chomp(char *s)
{
    size_t n = strlen(s);
    while (n && (s[n - 1] == '\r' || s[n - 1] == '\n' || s[n - 1] == ' ' || s[n - 1] == '\t')) s[--n] = 0;
}

/* The next line of s into line (LINECAP bytes, trailing blanks removed),
 * counted in *lineno: 1, 0 at the end of the file, -1 (failed: the
 * status is HD_ERR_FORMAT) for a line too long. */
static int next_line(const hd_weather *w, hd_istream *s, char *line, unsigned long *lineno)
{
    long len = hd_istream_getline(s, line, LINECAP);
    ++*lineno;
    if (len == -1) return 0;
    if (len == -2) { hd_fail(HD_ERR_FORMAT, "%s: line %lu: line too long", w->name, *lineno); return -1; }
    chomp(line);
    return 1;
}

/* strict real number of a whole (trimmed) field */
static int parse_real(const char *s, double *v)
{
    while (isspace((unsigned char)*s)) s++;
    char buf[128];
    size_t n = strlen(s);
    if (n == 0 || n >= sizeof buf) return -1;
    memcpy(buf, s, n + 1);
    while (n && isspace((unsigned char)buf[n - 1])) buf[--n] = 0;
    char *end;
    double x = strtod(buf, &end);
    if (end == buf || *end || !isfinite(x)) return -1;
    *v = x;
    return 0;
}

static hd_status check_date(const hd_weather *w, unsigned long line, int month, int day, double hour)
{
    if (month < 1 || month > 12)
        return hd_fail(HD_ERR_FORMAT, "%s: line %lu: month %d out of range 1..12", w->name, line, month);
    if (day < 1 || day > mdays[month - 1])
        return hd_fail(HD_ERR_FORMAT, "%s: line %lu: day %d out of range 1..%d for month %d", w->name,
                       line, day, mdays[month - 1], month);
    if (!(hour >= 0 && hour <= 24))
        return hd_fail(HD_ERR_FORMAT, "%s: line %lu: hour %g out of range 0..24", w->name, line, hour);
    return HD_OK;
}

/* ---------------- WEA ---------------- */

static hd_status wea_keyword(hd_weather *w, hd_istream *s, unsigned long *lineno, const char *key,
                             char *val, size_t cap)
{
    char line[LINECAP];
    int k = next_line(w, s, line, lineno);
    if (k < 0) return HD_ERR_FORMAT;
    if (k == 0)
        return hd_fail(HD_ERR_FORMAT, "%s: line %lu: unexpected end of file, expected '%s' header line",
                       w->name, *lineno, key);
    size_t kl = strlen(key);
    if (strncmp(line, key, kl) || (line[kl] != ' ' && line[kl] != '\t' && line[kl] != 0))
        return hd_fail(HD_ERR_FORMAT, "%s: line %lu: wrong WEA header: expected '%s ...', found '%.40s'",
                       w->name, *lineno, key, line);
    const char *v = line + kl;
    while (*v == ' ' || *v == '\t') v++;
    snprintf(val, cap, "%s", v);
    return HD_OK;
}

static hd_status wea_number(hd_weather *w, unsigned long line, const char *key, const char *val, double *out)
{
    if (parse_real(val, out))
        return hd_fail(HD_ERR_FORMAT, "%s: line %lu: %s: expected a number, found '%.40s'", w->name, line,
                       key, val);
    return HD_OK;
}

static hd_status read_wea(hd_istream *s, hd_weather *w, const char *firstline)
{
    unsigned long lineno = 1;
    hd_status st;
    char val[256];
    double lon, tz, units;
    const char *p = firstline + 5;
    while (*p == ' ' || *p == '\t') p++;
    snprintf(w->place, sizeof w->place, "%s", p);
    if ((st = wea_keyword(w, s, &lineno, "latitude", val, sizeof val))) return st;
    if ((st = wea_number(w, lineno, "latitude", val, &w->site.lat))) return st;
    snprintf(w->lat_text, sizeof w->lat_text, "%.63s", val);
    if ((st = wea_keyword(w, s, &lineno, "longitude", val, sizeof val))) return st;
    if ((st = wea_number(w, lineno, "longitude", val, &lon))) return st;
    if ((st = wea_keyword(w, s, &lineno, "time_zone", val, sizeof val))) return st;
    if ((st = wea_number(w, lineno, "time_zone", val, &tz))) return st;
    if ((st = wea_keyword(w, s, &lineno, "site_elevation", val, sizeof val))) return st;
    if ((st = wea_number(w, lineno, "site_elevation", val, &w->site.elev))) return st;
    snprintf(w->elev_text, sizeof w->elev_text, "%.63s", val);
    if ((st = wea_keyword(w, s, &lineno, "weather_data_file_units", val, sizeof val))) return st;
    if ((st = wea_number(w, lineno, "weather_data_file_units", val, &units))) return st;
    if (units != 1 && units != 2 && units != 3)
        return hd_fail(HD_ERR_FORMAT, "%s: line %lu: weather_data_file_units %s not 1, 2 or 3", w->name,
                       lineno, val);
    if (fabs(w->site.lat) > 90)
        return hd_fail(HD_ERR_FORMAT, "%s: line 2: latitude %g out of range -90..90", w->name, w->site.lat);
    if (fabs(lon) > 360)
        return hd_fail(HD_ERR_FORMAT, "%s: line 3: longitude %g out of range", w->name, lon);
    if (fabs(tz) > 360)
        return hd_fail(HD_ERR_FORMAT, "%s: line 4: time_zone %g out of range", w->name, tz);
    w->site.lon = lon;
    w->site.meridian = tz;
    w->tz_hours = -tz / 15;
    w->units = (int)units;
    w->is_epw = 0;

    char line[LINECAP];
    for (int k; (k = next_line(w, s, line, &lineno));) {
        if (k < 0) return HD_ERR_FORMAT;
        char *q = line;
        while (isspace((unsigned char)*q)) q++;
        if (!*q) continue;   /* blank lines are tolerated */
        char *tok[5];
        int nt = 0;
        char *save = NULL;
        for (char *t = strtok_r(q, " \t,", &save); t && nt < 5; t = strtok_r(NULL, " \t,", &save))
            tok[nt++] = t;
        static const char *what[5] = {"month", "day", "hour", "first value", "second value"};
        if (nt < 5)
            return hd_fail(HD_ERR_FORMAT, "%s: line %lu: missing column %d (%s): expected 'month day hour v1 v2'",
                           w->name, lineno, nt + 1, what[nt]);
        double v[5];
        for (int i = 0; i < 5; i++)
            if (parse_real(tok[i], &v[i]))
                return hd_fail(HD_ERR_FORMAT, "%s: line %lu: column %d (%s): expected a number, found '%.40s'",
                               w->name, lineno, i + 1, what[i], tok[i]);
        if (v[0] != floor(v[0]) || v[1] != floor(v[1]))
            return hd_fail(HD_ERR_FORMAT, "%s: line %lu: month and day must be integers", w->name, lineno);
        hd_weather_rec r;
        memset(&r, 0, sizeof r);
        r.month = (int)fmax(-1, fmin(v[0], 99));
        r.day = (int)fmax(-1, fmin(v[1], 99));
        r.hour = v[2];
        r.v1 = v[3];
        r.v2 = v[4];
        r.dewpoint = r.ghi = r.dni_lux = r.dhi_lux = NAN;
        r.line = lineno;
        if ((st = check_date(w, lineno, r.month, r.day, r.hour))) return st;
        if ((st = add_record(w, &r))) return st;
    }
    if (w->n == 0) return hd_fail(HD_ERR_FORMAT, "%s: no weather records after the WEA header", w->name);
    return HD_OK;
}

/* ---------------- EPW ---------------- */

/* split a CSV line in place (quotes group commas); returns the field count */
static int split_csv(char *line, char **f, int maxf)
{
    int n = 0;
    char *p = line;
    while (n < maxf) {
        f[n++] = p;
        int inq = 0;
        while (*p && (inq || *p != ',')) {
            if (*p == '"') inq = !inq;
            p++;
        }
        if (!*p) break;
        *p++ = 0;
    }
    return n;
}

static void trim(char *s)
{
    size_t n = strlen(s);
    while (n && isspace((unsigned char)s[n - 1])) s[--n] = 0;
    size_t i = 0;
    while (isspace((unsigned char)s[i])) i++;
    if (i) memmove(s, s + i, n - i + 1);
}

/* "M/D" or "YYYY/M/D" (spaces allowed); returns 0 on success */
static int parse_epw_date(const char *s, int *month, int *day)
{
    int a, b, c;
    char extra;
    if (sscanf(s, " %d / %d / %d %c", &a, &b, &c, &extra) == 3) { *month = b; *day = c; }
    else if (sscanf(s, " %d / %d %c", &a, &b, &extra) == 2) { *month = a; *day = b; }
    else return -1;
    if (*month < 1 || *month > 12 || *day < 1 || *day > mdays[*month - 1]) return -1;
    return 0;
}

static const char *epw_heads[8] = {"LOCATION", "DESIGN CONDITIONS", "TYPICAL/EXTREME PERIODS",
                                   "GROUND TEMPERATURES", "HOLIDAYS/DAYLIGHT SAVINGS", "COMMENTS 1",
                                   "COMMENTS 2", "DATA PERIODS"};

static hd_status read_epw(hd_istream *s, hd_weather *w, char *firstline)
{
    hd_status st;
    char *f[64];
    char line[LINECAP];
    unsigned long lineno = 1;
    int nf = split_csv(firstline, f, 64);
    if (nf < 10)
        return hd_fail(HD_ERR_FORMAT, "%s: line 1: LOCATION line has %d fields, expected 10 "
                       "(LOCATION,city,state,country,source,WMO,lat,lon,tz,elev)", w->name, nf);
    for (int i = 0; i < nf; i++) trim(f[i]);
    snprintf(w->place, sizeof w->place, "%s_%s", f[1], f[3]);
    for (char *c = w->place; *c; c++)
        if (*c == '"') *c = '\'';
    double lat, lon, tz, elev;
    static const char *lname[4] = {"latitude", "longitude", "time zone", "elevation"};
    double *lv[4] = {&lat, &lon, &tz, &elev};
    for (int i = 0; i < 4; i++)
        if (parse_real(f[6 + i], lv[i]))
            return hd_fail(HD_ERR_FORMAT, "%s: line 1: LOCATION field %d (%s): expected a number, found '%.40s'",
                           w->name, 7 + i, lname[i], f[6 + i]);
    if (fabs(lat) > 90 || fabs(lon) > 180 || fabs(tz) > 24)
        return hd_fail(HD_ERR_FORMAT, "%s: line 1: LOCATION latitude/longitude/time zone out of range", w->name);
    snprintf(w->lat_text, sizeof w->lat_text, "%s", f[6]);
    snprintf(w->elev_text, sizeof w->elev_text, "%s", f[9]);
    w->site.lat = lat;
    w->site.lon = -lon;
    w->site.meridian = -15 * tz;
    w->site.elev = elev;
    w->tz_hours = tz;
    w->units = 1;
    w->is_epw = 1;
    w->records_per_hour = 1;

    for (int h = 1; h < 8; h++) {
        long len = hd_istream_getline(s, line, sizeof line);
        lineno++;
        if (len == -1)
            return hd_fail(HD_ERR_FORMAT, "%s: line %lu: unexpected end of file in the EPW header, expected '%s'",
                           w->name, lineno, epw_heads[h]);
        /* over-long comment lines are accepted (the rest was skipped) */
        chomp(line);
        size_t kl = strlen(epw_heads[h]);
        if (strncmp(line, epw_heads[h], kl) || line[kl] != ',')
            return hd_fail(HD_ERR_FORMAT, "%s: line %lu: wrong EPW header: expected '%s,...', found '%.40s'",
                           w->name, lineno, epw_heads[h], line);
        if (h == 7) {
            nf = split_csv(line, f, 64);
            for (int i = 0; i < nf; i++) trim(f[i]);
            long nper, rph;
            if (nf < 7 || hd_parse_long(f[1], &nper) || hd_parse_long(f[2], &rph) || nper < 1 || rph < 1 ||
                rph > 60)
                return hd_fail(HD_ERR_FORMAT, "%s: line %lu: DATA PERIODS: expected 'DATA PERIODS,n,"
                               "records_per_hour,name,start_day,first_date,last_date'", w->name, lineno);
            int m, d;
            if (parse_epw_date(f[5], &m, &d) || parse_epw_date(f[6], &m, &d))
                return hd_fail(HD_ERR_FORMAT, "%s: line %lu: DATA PERIODS: bad date '%s' or '%s' "
                               "(expected M/D or YYYY/M/D)", w->name, lineno, f[5], f[6]);
            w->records_per_hour = (int)rph;
        }
    }
    for (int k; (k = next_line(w, s, line, &lineno));) {
        if (k < 0) return HD_ERR_FORMAT;
        if (!line[0]) continue;
        nf = split_csv(line, f, 64);
        if (nf < 16)
            return hd_fail(HD_ERR_FORMAT, "%s: line %lu: EPW record has %d fields, need at least 16 "
                           "(up to direct normal and diffuse horizontal radiation)", w->name, lineno, nf);
        static const int need[8] = {1, 2, 3, 4, 5, 8, 15, 16};
        static const char *nname[8] = {"year", "month", "day", "hour", "minute", "dew point",
                                       "direct normal radiation", "diffuse horizontal radiation"};
        double v[8];
        for (int i = 0; i < 8; i++)
            if (parse_real(f[need[i] - 1], &v[i]))
                return hd_fail(HD_ERR_FORMAT, "%s: line %lu: field %d (%s): expected a number, found '%.40s'",
                               w->name, lineno, need[i], nname[i], f[need[i] - 1]);
        if (v[3] < 1 || v[3] > 24 || v[3] != floor(v[3]))
            return hd_fail(HD_ERR_FORMAT, "%s: line %lu: hour %g out of range 1..24", w->name, lineno, v[3]);
        if (v[4] < 0 || v[4] > 60)
            return hd_fail(HD_ERR_FORMAT, "%s: line %lu: minute %g out of range 0..60", w->name, lineno, v[4]);
        hd_weather_rec r;
        memset(&r, 0, sizeof r);
        r.year = (int)fmax(-1e6, fmin(v[0], 1e6));
        r.month = (int)fmax(-1, fmin(v[1], 99));
        r.day = (int)fmax(-1, fmin(v[2], 99));
        if (w->records_per_hour == 1) r.hour = v[3] - 0.5;     /* hour ending: mid-hour */
        else r.hour = v[3] - 1 + v[4] / 60;                   /* sub-hourly: minute given */
        r.dewpoint = (v[5] >= 99.9) ? NAN : v[5];       /* 99.9 = missing */
        r.v1 = v[6];
        r.v2 = v[7];
        if (r.v1 >= 9999 || r.v1 < 0 || r.v2 >= 9999 || r.v2 < 0)
            return hd_fail(HD_ERR_FORMAT, "%s: line %lu: radiation value %g/%g missing or out of range",
                           w->name, lineno, r.v1, r.v2);
        double x;
        r.ghi = (nf >= 14 && !parse_real(f[13], &x) && x < 9999) ? x : NAN;
        r.dni_lux = (nf >= 18 && !parse_real(f[17], &x) && x < 999900) ? x : NAN;
        r.dhi_lux = (nf >= 19 && !parse_real(f[18], &x) && x < 999900) ? x : NAN;
        r.line = lineno;
        if ((st = check_date(w, lineno, r.month, r.day, r.hour))) return st;
        if ((st = add_record(w, &r))) return st;
    }
    if (w->n == 0) return hd_fail(HD_ERR_FORMAT, "%s: no weather records after the EPW header", w->name);
    return HD_OK;
}

static hd_status read_stream(hd_istream *s, hd_weather *w)
{
    char line[LINECAP];
    unsigned long lineno = 0;
    int k = next_line(w, s, line, &lineno);
    if (k < 0) return HD_ERR_FORMAT;
    if (k == 0) return hd_fail(HD_ERR_FORMAT, "%s: line 1: empty file, expected a WEA or EPW header", w->name);
    const char *l = line;
    if (!strncmp(l, "\xEF\xBB\xBF", 3)) l += 3;   /* UTF-8 byte-order mark */
    if (!strncmp(l, "place", 5) && (l[5] == ' ' || l[5] == '\t' || l[5] == 0))
        return read_wea(s, w, l);
    if (!strncmp(l, "LOCATION,", 9)) {
        char copy[LINECAP];
        snprintf(copy, sizeof copy, "%s", l);
        return read_epw(s, w, copy);
    }
    return hd_fail(HD_ERR_FORMAT, "%s: line 1: wrong header: expected 'place ...' (WEA) or 'LOCATION,...' (EPW), "
                   "found '%.40s'", w->name, l);
}

hd_status hd_weather_read(const char *path, hd_weather *w)
{
    hd_istream *s;
    hd_weather_init(w);
    snprintf(w->name, sizeof w->name, "%s", strcmp(path, "-") ? path : "<stdin>");
    hd_status st = hd_istream_open(&s, path);
    if (st) return st;
    st = read_stream(s, w);
    hd_status st2 = hd_istream_close(s);
    if (!st) st = st2;
    if (st) {
        free(w->rec);
        w->rec = NULL;
        w->n = w->cap = 0;
    }
    return st;
}

hd_status hd_weather_read_memory(const char *text, size_t len, const char *name, hd_weather *w)
{
    hd_istream *s;
    hd_weather_init(w);
    snprintf(w->name, sizeof w->name, "%s", name);
    hd_status st = hd_istream_memory(&s, text, len, name);
    if (st) return st;
    st = read_stream(s, w);
    hd_istream_close(s);
    if (st) {
        free(w->rec);
        w->rec = NULL;
        w->n = w->cap = 0;
    }
    return st;
}

double hd_weather_dewpoint(const hd_weather *w, size_t i)
{
    double sum = 0;
    int n = 0;
    for (size_t k = 0; k < 3 && k <= i; k++) {
        double d = w->rec[i - k].dewpoint;
        if (isnan(d)) continue;
        sum += d;
        n++;
    }
    return n ? sum / n : NAN;
}

hd_status hd_weather_write_wea_header(FILE *fp, const char *place, const char *lat_text, double lon_west,
                                      double meridian_west, const char *elev_text, int units)
{
    fprintf(fp, "place %s\n", place);
    fprintf(fp, "latitude %s\n", lat_text);
    fprintf(fp, "longitude %f\n", lon_west);
    if (meridian_west == floor(meridian_west)) fprintf(fp, "time_zone %.0f\n", meridian_west);
    else fprintf(fp, "time_zone %g\n", meridian_west);
    fprintf(fp, "site_elevation %s\n", elev_text);
    fprintf(fp, "weather_data_file_units %d\n", units);
    return ferror(fp) ? hd_fail(HD_ERR_IO, "write error") : HD_OK;
}

hd_status hd_weather_write_wea(FILE *fp, const hd_weather *w)
{
    char lat[64], elev[64];
    snprintf(lat, sizeof lat, "%s", w->lat_text[0] ? w->lat_text : "0");
    snprintf(elev, sizeof elev, "%s", w->elev_text[0] ? w->elev_text : "0");
    hd_status st = hd_weather_write_wea_header(fp, w->place, lat, w->site.lon, w->site.meridian, elev, w->units);
    if (st) return st;
    for (size_t i = 0; i < w->n; i++) {
        const hd_weather_rec *r = &w->rec[i];
        fprintf(fp, "%d %d %.3f %.0f %.0f\n", r->month, r->day, r->hour, r->v1, r->v2);
    }
    return ferror(fp) ? hd_fail(HD_ERR_IO, "write error") : HD_OK;
}

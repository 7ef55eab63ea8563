/* heliodon — lamp colour tables (pfilt -t/-f; the format of Radiance's
 * lamp.tab): each line is a pattern between any delimiter character (a
 * case-insensitive regular expression, GNU basic syntax with \< \>), then
 * either "x y m" (CIE chromaticity and lumen depreciation) or "(name)", an
 * alias resolved against the entries above it.  '#' starts a comment line.
 * The first entry whose pattern matches the lamp name wins. */
#include <ctype.h>
#include <regex.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/cal.h"
#include "heliodon/matrix.h"
#include "heliodon/pictools.h"

typedef struct lampent { regex_t re; double rgb[3]; } lampent;

static int find(const lampent *e, int n, const char *name)
{
    for (int i = 0; i < n; i++)
        if (!regexec(&e[i].re, name, 0, NULL, 0)) return i;
    return -1;
}

/* xyY (Y = m) to RGB with Radiance's primaries (single precision, as
 * Radiance's tables); a colour outside the RGB gamut is desaturated towards
 * the grey of the same Y until its negative components reach 0. */
static void xym_rgb(double x, double y, double m, double rgb[3])
{
    float fx = (float)x, fy = (float)y, fm = (float)m;
    float xyz[3];
    xyz[1] = fm;
    xyz[0] = fx / fy * xyz[1];
    xyz[2] = (float)(xyz[1] * (1. / fy - 1.) - xyz[0]);
    double c[9], t = 1;
    hd_color_symbols("rgb", 1, c, NULL);
    for (int i = 0; i < 3; i++) {      /* in single precision throughout */
        float v = (float)c[3 * i] * xyz[0] + (float)c[3 * i + 1] * xyz[1] + (float)c[3 * i + 2] * xyz[2];
        rgb[i] = v;
    }
    double grey = xyz[1] < 0 ? 0 : xyz[1] > 1 ? 1 : xyz[1];
    for (int i = 0; i < 3; i++)
        if (rgb[i] < 0 && (0 - grey) / (rgb[i] - grey) < t) t = (0 - grey) / (rgb[i] - grey);
    if (t < 1)
        for (int i = 0; i < 3; i++) rgb[i] = (float)(t * rgb[i] + (1 - t) * grey);
}

hd_status hd_lamp_color(const char *table, const char *lamp, double rgb[3])
{
    char path[4096];
    if (!hd_cal_findfile(table, path, sizeof path))
        return hd_fail(HD_ERR_IO, "cannot find lamp table '%s'", table);
    FILE *fp = fopen(path, "r");
    if (!fp) return hd_fail(HD_ERR_IO, "%s: cannot open", path);
    lampent *e = NULL;
    int n = 0, line = 0;
    hd_status st = HD_OK;
    char buf[1024];
    while (!st && fgets(buf, sizeof buf, fp)) {
        line++;
        char *p = buf;
        while (isspace((unsigned char)*p)) p++;
        if (!*p || *p == '#') continue;
        char delim = *p++, *q = p;
        while (*q && !(*q == delim && q[-1] != '\\')) q++;
        if (!*q) { st = hd_fail(HD_ERR_FORMAT, "%s, line %d: unclosed pattern", path, line); break; }
        *q++ = 0;
        lampent *ne = realloc(e, (size_t)(n + 1) * sizeof *e);
        if (!ne) { st = HD_ERR_NOMEM; break; }
        e = ne;
        if (regcomp(&e[n].re, p, REG_ICASE | REG_NOSUB)) {
            st = hd_fail(HD_ERR_FORMAT, "%s, line %d: bad regular expression '%s'", path, line, p);
            break;
        }
        while (isspace((unsigned char)*q)) q++;
        if (*q == '(') {
            char *a = ++q;
            while (*q && !(*q == ')' && q[-1] != '\\')) q++;
            *q = 0;
            int k = find(e, n, a);
            if (k < 0) st = hd_fail(HD_ERR_FORMAT, "%s, line %d: unmatched alias '%s'", path, line, a);
            else memcpy(e[n].rgb, e[k].rgb, sizeof e[n].rgb);
        } else {
            double x, y, m;
            if (sscanf(q, "%lf %lf %lf", &x, &y, &m) != 3 || !(y > 0))
                st = hd_fail(HD_ERR_FORMAT, "%s, line %d: expected \"x y m\" or \"(alias)\" after the pattern", path, line);
            else xym_rgb(x, y, m, e[n].rgb);
        }
        if (st) regfree(&e[n].re);
        else n++;
    }
    fclose(fp);
    int k = st ? -1 : find(e, n, lamp);
    if (!st && k < 0) st = hd_fail(HD_ERR_USAGE, "%s: unknown lamp type (table %s)", lamp, path);
    if (!st) memcpy(rgb, e[k].rgb, 3 * sizeof *rgb);
    for (int i = 0; i < n; i++) regfree(&e[i].re);
    free(e);
    return st;
}

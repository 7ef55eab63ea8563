/* heliodon — Radiance views: parsing, formatting, view rays. */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/io.h"
#include "heliodon/view.h"

#define DEG (HD_PI / 180.0)

void hd_view_default(hd_view *v)
{
    memset(v, 0, sizeof *v);
    v->type = 'v';
    v->vp = hd_v3(0, 0, 0);
    v->vd = hd_v3(0, 1, 0);
    v->vu = hd_v3(0, 0, 1);
    v->vh = v->vv = 45.0;
}

static int num_arg(const char *opt, int argc, char **argv, int i, int n, double *out)
{
    for (int k = 0; k < n; k++) {
        if (i + 1 + k >= argc) {
            hd_fail(HD_ERR_USAGE, "option %s: expected %d number%s", opt, n, n > 1 ? "s" : "");
            return -1;
        }
        if (hd_parse_double(argv[i + 1 + k], &out[k])) {
            hd_fail(HD_ERR_USAGE, "option %s: expected a number, got '%s'", opt, argv[i + 1 + k]);
            return -1;
        }
    }
    return 0;
}

int hd_view_parse_arg(hd_view *v, int argc, char **argv, int i)
{
    const char *a = argv[i];
    double x[3];
    if (a[0] != '-' || a[1] != 'v' || !a[2]) return 0;
    v->ready = 0;
    if (a[2] == 't') {
        if (!a[3] || a[4] || !strchr("vlahsc", a[3])) {
            hd_fail(HD_ERR_USAGE, "option %s: unknown view type (expected -vtv, -vtl, -vta, -vth, -vts or -vtc)", a);
            return -1;
        }
        v->type = a[3];
        return 1;
    }
    if (a[3]) return 0;
    switch (a[2]) {
    case 'p': case 'd': case 'u':
        if (num_arg(a, argc, argv, i, 3, x)) return -1;
        if (a[2] == 'p') v->vp = hd_v3(x[0], x[1], x[2]);
        else if (a[2] == 'd') v->vd = hd_v3(x[0], x[1], x[2]);
        else v->vu = hd_v3(x[0], x[1], x[2]);
        return 4;
    case 'h': case 'v': case 'o': case 'a': case 's': case 'l':
        if (num_arg(a, argc, argv, i, 1, x)) return -1;
        switch (a[2]) {
        case 'h': v->vh = x[0]; break;
        case 'v': v->vv = x[0]; break;
        case 'o': v->vo = x[0]; break;
        case 'a': v->va = x[0]; break;
        case 's': v->vs = x[0]; break;
        default: v->vl = x[0]; break;
        }
        return 2;
    case 'f':
        if (i + 1 >= argc) {
            hd_fail(HD_ERR_USAGE, "option -vf: expected a view file name");
            return -1;
        }
        if (hd_view_read_file(v, argv[i + 1]) != HD_OK) return -1;
        return 2;
    default:
        return 0;
    }
}

int hd_view_parse_line(hd_view *v, const char *line)
{
    char buf[4096];
    char *w[256];
    int n = 0, found = 0;
    snprintf(buf, sizeof buf, "%s", line);
    for (char *p = strtok(buf, " \t\r\n"); p && n < 256; p = strtok(NULL, " \t\r\n"))
        w[n++] = p;
    for (int i = 0; i < n;) {
        int k = hd_view_parse_arg(v, n, w, i);
        if (k < 0) return -1;
        if (k == 0) { i++; continue; }
        found++;
        i += k;
    }
    return found;
}

/* view files read through -vf inside view files: a file that names itself would recurse forever */
#define HD_VIEW_MAXNEST 16
static _Thread_local int view_nest;

static hd_status view_read_file(hd_view *v, const char *path);

hd_status hd_view_read_file(hd_view *v, const char *path)
{
    if (view_nest >= HD_VIEW_MAXNEST)
        return hd_fail(HD_ERR_FORMAT, "%s: view files nested deeper than %d through -vf (does it name itself?)", path,
                       HD_VIEW_MAXNEST);
    view_nest++;
    hd_status st = view_read_file(v, path);
    view_nest--;
    return st;
}

static hd_status view_read_file(hd_view *v, const char *path)
{
    FILE *fp = fopen(path, "rb");
    char line[4096];
    unsigned long lineno = 0;
    int header = 0, any = 0;
    if (!fp) return hd_fail(HD_ERR_IO, "%s: cannot open view file", path);
    while (fgets(line, sizeof line, fp)) {
        lineno++;
        if (lineno == 1 && line[0] == '#' && line[1] == '?') { header = 1; continue; }
        if (header && (line[0] == '\n' || (line[0] == '\r' && line[1] == '\n'))) break;
        const char *s = line;
        while (isspace((unsigned char)*s)) s++;
        if (header) {
            if (strncmp(s, "VIEW=", 5) != 0) continue;
            s += 5;
        }
        int k = hd_view_parse_line(v, s);
        if (k < 0) {
            fclose(fp);
            return hd_fail_context(HD_ERR_FORMAT, "%s: line %lu", path, lineno);
        }
        any += k;
    }
    fclose(fp);
    if (!any) return hd_fail(HD_ERR_FORMAT, "%s: no view options found in view file", path);
    return HD_OK;
}

hd_status hd_view_from_header(hd_view *v, const hd_header *h, int *found)
{
    int n = 0;
    const char *p = h && h->text ? h->text : "";
    while (*p) {
        const char *e = strchr(p, '\n');
        size_t len = e ? (size_t)(e - p) : strlen(p);
        if (len > 5 && strncmp(p, "VIEW=", 5) == 0) {
            char line[4096];
            size_t l = len - 5 < sizeof line - 1 ? len - 5 : sizeof line - 1;
            memcpy(line, p + 5, l);
            line[l] = 0;
            if (hd_view_parse_line(v, line) < 0)
                return hd_fail_context(HD_ERR_FORMAT, "VIEW= line in header");
            n++;
        }
        p += len + (e ? 1 : 0);
    }
    if (found) *found = n;
    return HD_OK;
}

hd_status hd_view_setup(hd_view *v)
{
    double dl = hd_vlen(v->vd);
    v->ready = 0;
    /* lengths that overflow (components near DBL_MAX) are refused too:
     * every later division and product assumes finite unit vectors */
    if (!(dl > 1e-12) || !isfinite(dl)) return hd_fail(HD_ERR_RANGE, "view: zero or overflowing view direction (-vd)");
    v->dir = hd_vscale(v->vd, 1.0 / dl);
    double ul = hd_vlen(v->vu);
    if (!isfinite(ul)) return hd_fail(HD_ERR_RANGE, "view: overflowing up vector (-vu)");
    hd_vec3 h = hd_vcross(v->dir, v->vu);
    if (!(hd_vlen(h) > 1e-9 * (ul + 1e-300)))
        return hd_fail(HD_ERR_RANGE, "view: up vector (-vu) is zero or parallel to the view direction (-vd)");
    v->hunit = hd_vnorm(h);
    v->vunit = hd_vnorm(hd_vcross(v->hunit, v->dir));
    if (v->vh < 0 || v->vv < 0) return hd_fail(HD_ERR_RANGE, "view: negative view size (-vh/-vv)");
    /* a zero-sized view has no image plane: its aspect (vv/vh) and every
     * image location would divide by zero (Radiance refuses it too) */
    if (v->vh <= 1e-6 || v->vv <= 1e-6)
        return hd_fail(HD_ERR_RANGE, "view: zero view size (-vh %g -vv %g): both must be positive", v->vh, v->vv);
    double sh = 1, sv = 1;
    switch (v->type) {
    case 'l':
        sh = v->vh; sv = v->vv;
        break;
    case 'v':
        if (v->vh >= 180 || v->vv >= 180)
            return hd_fail(HD_ERR_RANGE, "view: perspective view angles must be below 180 degrees");
        sh = 2 * tan(v->vh / 2 * DEG); sv = 2 * tan(v->vv / 2 * DEG);
        break;
    case 'h':
        if (v->vh > 180 || v->vv > 180)
            return hd_fail(HD_ERR_RANGE, "view: hemispherical view angles must be at most 180 degrees");
        sh = 2 * sin(v->vh / 2 * DEG); sv = 2 * sin(v->vv / 2 * DEG);
        break;
    case 'a':
        if (v->vh > 360 || v->vv > 360)
            return hd_fail(HD_ERR_RANGE, "view: angular fisheye view angles must be at most 360 degrees");
        sh = v->vh / 180; sv = v->vv / 180;
        break;
    case 's':
        if (v->vh >= 360 || v->vv >= 360)
            return hd_fail(HD_ERR_RANGE, "view: stereographic view angles must be below 360 degrees");
        sh = 2 * tan(v->vh / 4 * DEG); sv = 2 * tan(v->vv / 4 * DEG);
        break;
    case 'c':
        if (v->vh > 360 || v->vv >= 180)
            return hd_fail(HD_ERR_RANGE, "view: cylindrical view: -vh at most 360, -vv below 180 degrees");
        sh = v->vh * DEG; sv = 2 * tan(v->vv / 2 * DEG);
        break;
    default:
        return hd_fail(HD_ERR_RANGE, "view: unknown view type '%c'", v->type);
    }
    v->hvec = hd_vscale(v->hunit, sh);
    v->vvec = hd_vscale(v->vunit, sv);
    v->ready = 1;
    return HD_OK;
}

double hd_view_ray(const hd_view *v, double x, double y, hd_vec3 *org, hd_vec3 *dir)
{
    double xs = x + v->vs - 0.5, ys = y + v->vl - 0.5;
    double hl = hd_vlen(v->hvec), vl = hd_vlen(v->vvec);
    hd_vec3 d;
    int planar = 0;
    *org = v->vp;
    switch (v->type) {
    case 'l':
        *org = hd_vadd(hd_vadd(v->vp, hd_vscale(v->hvec, xs)), hd_vscale(v->vvec, ys));
        d = v->dir;
        planar = 1;
        break;
    case 'v':
        d = hd_vadd(hd_vadd(v->dir, hd_vscale(v->hvec, xs)), hd_vscale(v->vvec, ys));
        planar = 1;
        break;
    case 'h': {
        double u = xs * hl, w = ys * vl, z = 1 - u * u - w * w;
        if (z < 0) goto outside;
        d = hd_vadd(hd_vscale(v->dir, sqrt(z)), hd_vadd(hd_vscale(v->hunit, u), hd_vscale(v->vunit, w)));
        break;
    }
    case 'a': {
        double u = xs * hl, w = ys * vl, r = sqrt(u * u + w * w);
        if (r > 1) goto outside;
        double th = HD_PI * r, s = r > 1e-12 ? sin(th) / r : HD_PI;
        d = hd_vadd(hd_vscale(v->dir, cos(th)), hd_vadd(hd_vscale(v->hunit, u * s), hd_vscale(v->vunit, w * s)));
        break;
    }
    case 's': {
        double u = xs * hl, w = ys * vl, r2 = u * u + w * w;
        double z = (1 - r2) / (1 + r2), s = 2 / (1 + r2);
        d = hd_vadd(hd_vscale(v->dir, z), hd_vadd(hd_vscale(v->hunit, u * s), hd_vscale(v->vunit, w * s)));
        break;
    }
    case 'c': {
        double a = xs * hl;
        d = hd_vadd(hd_vadd(hd_vscale(v->dir, cos(a)), hd_vscale(v->hunit, sin(a))), hd_vscale(v->vvec, ys));
        break;
    }
    default:
        goto outside;
    }
    double dl = hd_vlen(d);
    if (v->vo > 0) *org = hd_vadd(*org, hd_vscale(d, planar ? v->vo : v->vo / dl));
    *dir = hd_vscale(d, 1.0 / dl);
    if (v->va > 0) {
        double m = (planar ? dl : 1.0) * (v->va - v->vo);
        return m > 0 ? m : 1e-30;
    }
    return 0;
outside:
    *dir = hd_v3(0, 0, 0);
    return -1;
}

int hd_view_loc(const hd_view *v, hd_vec3 dir, double *x, double *y)
{
    hd_vec3 d = hd_vnorm(dir);
    double z = hd_vdot(d, v->dir), u = hd_vdot(d, v->hunit), w = hd_vdot(d, v->vunit);
    double hl = hd_vlen(v->hvec), vl = hd_vlen(v->vvec), xs, ys;
    switch (v->type) {
    case 'v':
        if (z <= 0) return 0;
        xs = u / z / hl; ys = w / z / vl;
        break;
    case 'h':
        if (z < 0) return 0;
        xs = u / hl; ys = w / vl;
        break;
    case 'a': {
        double th = acos(z < -1 ? -1 : z > 1 ? 1 : z), s = sqrt(u * u + w * w);
        double r = th / HD_PI;
        if (s > 1e-12) { u *= r / s; w *= r / s; } else { u = w = 0; }
        xs = u / hl; ys = w / vl;
        break;
    }
    case 's': {
        double k = 1 / (1 + z);
        xs = u * k / hl; ys = w * k / vl;
        break;
    }
    case 'c': {
        double a = atan2(u, z), c = sqrt(z * z + u * u);
        if (c <= 1e-12) return 0;
        xs = a / hl; ys = w / c / vl;
        break;
    }
    default:
        return 0;
    }
    *x = xs + 0.5 - v->vs;
    *y = ys + 0.5 - v->vl;
    return *x >= 0 && *x <= 1 && *y >= 0 && *y <= 1;
}

double hd_view_aspect(const hd_view *v)
{
    return hd_vlen(v->vvec) / hd_vlen(v->hvec);
}

void hd_view_normaspect(double va, double *pa, int *xres, int *yres)
{
    if (*pa <= 1e-7)
        *pa = va * *xres / *yres;
    else if (va * *xres > *pa * *yres)
        *xres = (int)(*yres / va * *pa + 0.5);
    else
        *yres = (int)(*xres * va / *pa + 0.5);
}

int hd_view_format(const hd_view *v, char *buf, size_t cap)
{
    return snprintf(buf, cap,
                    "-vt%c -vp %.6g %.6g %.6g -vd %.6g %.6g %.6g -vu %.6g %.6g %.6g "
                    "-vh %.6g -vv %.6g -vo %.6g -va %.6g -vs %.6g -vl %.6g",
                    v->type, v->vp.x, v->vp.y, v->vp.z, v->vd.x, v->vd.y, v->vd.z,
                    v->vu.x, v->vu.y, v->vu.z, v->vh, v->vv, v->vo, v->va, v->vs, v->vl);
}

/* heliodon — static HTML report of an annual glare run (see report.h). */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "heliodon/glare.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/picture.h"
#include "heliodon/report.h"

void hd_report_ramp(double t, uint8_t rgb[3])
{
    /* piecewise-linear ramp: dark blue, blue, cyan, green, yellow, orange, red */
    static const double stops[7][3] = {{20, 20, 90},  {30, 80, 200},  {40, 180, 210}, {60, 190, 90},
                                       {230, 220, 50}, {240, 140, 30}, {200, 30, 30}};
    if (!(t >= 0)) t = 0;
    if (t > 1) t = 1;
    double x = t * 6;
    int i = (int)x;
    if (i >= 6) i = 5;
    double f = x - i;
    for (int c = 0; c < 3; c++) rgb[c] = (uint8_t)lround(stops[i][c] + f * (stops[i + 1][c] - stops[i][c]));
}

void hd_report_falsecolor(double lum, double lmin, double lmax, uint8_t rgb[3])
{
    if (!(lum > 0)) {
        rgb[0] = rgb[1] = rgb[2] = 0;
        return;
    }
    hd_report_ramp(log10(lum / lmin) / log10(lmax / lmin), rgb);
}

void hd_report_data_free(hd_report_data *d)
{
    free(d->hoy);
    free(d->ev);
    free(d->dgp);
    free(d->dgi);
    free(d->shade);
    memset(d, 0, sizeof *d);
}

hd_status hd_report_read_csv(const char *path, hd_report_data *d)
{
    memset(d, 0, sizeof *d);
    hd_istream *s;
    hd_status st = hd_istream_open(&s, path);
    if (st) return st;
    char line[1024];
    long len = hd_istream_getline(s, line, sizeof line);
    if (len <= 0 || strncmp(line, "hour,Ev,DGP,DGI", 15)) {
        hd_istream_close(s);
        return hd_fail(HD_ERR_FORMAT, "%s: line 1: expected the CSV header \"hour,Ev,DGP,DGI,...\"", path);
    }
    size_t cap = 0;
    unsigned long lineno = 1;
    while ((len = hd_istream_getline(s, line, sizeof line)) > 0) {
        lineno++;
        if (line[0] == '\n' || line[0] == '#') continue;
        if (d->n == cap) {
            cap = cap ? 2 * cap : 1024;
            double *a = hd_realloc_array(d->hoy, cap, sizeof(double)), *b = NULL, *c = NULL, *e = NULL;
            int *f = NULL;
            if (a) d->hoy = a;
            if (a && (b = hd_realloc_array(d->ev, cap, sizeof(double)))) d->ev = b;
            if (b && (c = hd_realloc_array(d->dgp, cap, sizeof(double)))) d->dgp = c;
            if (c && (e = hd_realloc_array(d->dgi, cap, sizeof(double)))) d->dgi = e;
            if (e && (f = hd_realloc_array(d->shade, cap, sizeof(int)))) d->shade = f;
            if (!f) {
                hd_istream_close(s);
                hd_report_data_free(d);
                return HD_ERR_NOMEM;
            }
        }
        double h, ev, dgp, dgi, ugr;
        int nsrc, shade;
        char c1[32], c2[32];
        if (sscanf(line, "%lf,%lf,%lf,%lf,%lf,%d,%31[^,],%31[^,],%d", &h, &ev, &dgp, &dgi, &ugr, &nsrc, c1, c2, &shade) != 9) {
            unsigned long ln = lineno;
            hd_istream_close(s);
            hd_report_data_free(d);
            return hd_fail(HD_ERR_FORMAT, "%s: line %lu: expected hour,Ev,DGP,DGI,UGR,nsources,class,class,shade", path, ln);
        }
        d->hoy[d->n] = h;
        d->ev[d->n] = ev;
        d->dgp[d->n] = dgp;
        d->dgi[d->n] = dgi;
        d->shade[d->n] = shade;
        d->n++;
    }
    hd_istream_close(s);
    if (d->n == 0) return hd_fail(HD_ERR_FORMAT, "%s: no hourly rows", path);
    return HD_OK;
}

static hd_status open_out(hd_ofile **of, const char *path, FILE **fp)
{
    hd_status st = hd_ofile_open(of, path);
    if (!st) *fp = hd_ofile_fp(*of);
    return st;
}

static const char *month_name[12] = {"Jan", "Feb", "Mar", "Apr", "May", "Jun",
                                     "Jul", "Aug", "Sep", "Oct", "Nov", "Dec"};
static const int month_start[12] = {0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334};

#define HM_L 50
#define HM_T 34
#define HM_CW 2
#define HM_CH 8

hd_status hd_report_heatmap_svg(const char *path, const hd_report_data *d, int which, double shade_limit)
{
    hd_ofile *of;
    FILE *fp;
    hd_status st = open_out(&of, path, &fp);
    if (st) return st;
    int W = HM_L + 366 * HM_CW + 20, H = HM_T + 24 * HM_CH + 80;
    static const char *title[4] = {"Daylight glare probability (DGP)", "Daylight glare index (DGI)",
                                   "Operated shade (closed when DGP", "Shade schedule (closed when the open-shade DGP"};
    fprintf(fp, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" font-family=\"sans-serif\" "
            "font-size=\"11\">\n", W, H);
    if (which >= 2)
        fprintf(fp, "<text x=\"%d\" y=\"16\" font-size=\"13\">%s &#8805; %.2f)</text>\n", HM_L, title[which],
                shade_limit);
    else
        fprintf(fp, "<text x=\"%d\" y=\"16\" font-size=\"13\">%s, day of year &#215; hour</text>\n", HM_L, title[which]);
    fprintf(fp, "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"#e4e4e4\"/>\n<g shape-rendering=\"crispEdges\">\n",
            HM_L, HM_T, 366 * HM_CW, 24 * HM_CH);
    long nclosed = 0;
    for (size_t i = 0; i < d->n; i++) {
        int day = (int)floor(d->hoy[i] / 24);
        int hr = (int)floor(fmod(d->hoy[i], 24));
        if (day < 0 || day > 365 || hr < 0 || hr > 23) continue;
        uint8_t c[3];
        if (which == 0) hd_report_ramp((d->dgp[i] - 0.15) / 0.40, c);
        else if (which == 1) hd_report_ramp((d->dgi[i] - 5) / 30, c);
        else {
            int closed = which == 3 ? d->shade[i] != 0 : d->dgp[i] >= shade_limit;
            nclosed += closed;
            c[0] = closed ? 40 : 246;
            c[1] = closed ? 40 : 214;
            c[2] = closed ? 60 : 110;
        }
        fprintf(fp, "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"#%02x%02x%02x\"/>\n", HM_L + day * HM_CW,
                HM_T + hr * HM_CH, HM_CW, HM_CH, c[0], c[1], c[2]);
    }
    fputs("</g>\n", fp);
    for (int m = 0; m < 12; m++)
        fprintf(fp, "<text x=\"%d\" y=\"%d\">%s</text><line x1=\"%d\" y1=\"%d\" x2=\"%d\" y2=\"%d\" stroke=\"#888\"/>\n",
                HM_L + month_start[m] * HM_CW + 2, HM_T + 24 * HM_CH + 14, month_name[m], HM_L + month_start[m] * HM_CW,
                HM_T + 24 * HM_CH, HM_L + month_start[m] * HM_CW, HM_T + 24 * HM_CH + 5);
    for (int h = 0; h <= 24; h += 6)
        fprintf(fp, "<text x=\"%d\" y=\"%d\" text-anchor=\"end\">%02d:00</text>\n", HM_L - 4, HM_T + h * HM_CH + 4, h);
    int ly = HM_T + 24 * HM_CH + 30;
    if (which < 2) {
        /* colour bar with the comfort-class limits */
        double lo = which ? 5 : 0.15, span = which ? 30 : 0.40;
        for (int k = 0; k < 200; k++) {
            uint8_t c[3];
            hd_report_ramp(k / 199.0, c);
            fprintf(fp, "<rect x=\"%d\" y=\"%d\" width=\"2\" height=\"12\" fill=\"#%02x%02x%02x\"/>", HM_L + 2 * k, ly,
                    c[0], c[1], c[2]);
        }
        fputc('\n', fp);
        const double lim_dgp[] = {0.15, 0.35, 0.40, 0.45, 0.55}, lim_dgi[] = {5, 18, 24, 31, 35};
        for (int k = 0; k < 5; k++) {
            double v = which ? lim_dgi[k] : lim_dgp[k];
            int x = HM_L + (int)lround(400 * (v - lo) / span);
            fprintf(fp, "<line x1=\"%d\" y1=\"%d\" x2=\"%d\" y2=\"%d\" stroke=\"#000\"/><text x=\"%d\" y=\"%d\" "
                    "text-anchor=\"middle\">%g</text>\n", x, ly - 2, x, ly + 14, x, ly + 27, v);
        }
        fprintf(fp, "<text x=\"%d\" y=\"%d\">grey: night / no daylight</text>\n", HM_L + 420, ly + 10);
    } else {
        fprintf(fp, "<rect x=\"%d\" y=\"%d\" width=\"12\" height=\"12\" fill=\"#28283c\"/><text x=\"%d\" y=\"%d\">closed "
                "(%ld h)</text><rect x=\"%d\" y=\"%d\" width=\"12\" height=\"12\" fill=\"#f6d66e\"/><text x=\"%d\" y=\"%d\">"
                "open (%ld h)</text>\n", HM_L, ly, HM_L + 16, ly + 10, nclosed, HM_L + 120, ly, HM_L + 136, ly + 10,
                (long)d->n - nclosed);
    }
    fputs("</svg>\n", fp);
    return hd_ofile_commit(of);
}

hd_status hd_report_histogram_svg(const char *path, const hd_report_data *d, int which)
{
    const double *v = which ? d->dgi : d->dgp;
    double lo = which ? 0 : 0.1, hi = which ? 40 : 0.8, step = which ? 1 : 0.02;
    int nb = (int)lround((hi - lo) / step);
    size_t cnt[64] = {0};
    for (size_t i = 0; i < d->n; i++) {
        int b = (int)floor((v[i] - lo) / step);
        if (b < 0) b = 0;
        if (b >= nb) b = nb - 1;
        cnt[b]++;
    }
    size_t cmax = 1;
    for (int b = 0; b < nb; b++)
        if (cnt[b] > cmax) cmax = cnt[b];
    double p95 = hd_glare_percentile(v, d->n, 95);
    hd_ofile *of;
    FILE *fp;
    hd_status st = open_out(&of, path, &fp);
    if (st) return st;
    const int L = 60, T = 30, PW = 560, PH = 260;
    fprintf(fp, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" font-family=\"sans-serif\" "
            "font-size=\"11\">\n", L + PW + 60, T + PH + 50);
    fprintf(fp, "<text x=\"%d\" y=\"16\" font-size=\"13\">%s: hours per bin (bars), cumulative share (line), "
            "95th percentile %.3g</text>\n", L, which ? "DGI" : "DGP", p95);
    fprintf(fp, "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"none\" stroke=\"#444\"/>\n", L, T, PW, PH);
    double bw = (double)PW / nb;
    for (int b = 0; b < nb; b++) {
        double hgt = (double)PH * cnt[b] / cmax;
        fprintf(fp, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"#5b8fd0\" stroke=\"#fff\" "
                "stroke-width=\"0.5\"/>\n", L + b * bw, T + PH - hgt, bw, hgt);
    }
    fprintf(fp, "<polyline fill=\"none\" stroke=\"#d04020\" stroke-width=\"2\" points=\"%d,%d", L, T + PH);
    size_t cum = 0;
    for (int b = 0; b < nb; b++) {
        cum += cnt[b];
        fprintf(fp, " %.1f,%.1f", L + (b + 1) * bw, T + PH - (double)PH * cum / d->n);
    }
    fputs("\"/>\n", fp);
    const double lim_dgp[] = {0.35, 0.40, 0.45}, lim_dgi[] = {18, 24, 31};
    for (int k = 0; k < 3; k++) {
        double x = L + PW * ((which ? lim_dgi[k] : lim_dgp[k]) - lo) / (hi - lo);
        fprintf(fp, "<line x1=\"%.1f\" y1=\"%d\" x2=\"%.1f\" y2=\"%d\" stroke=\"#777\" stroke-dasharray=\"4 3\"/>\n", x,
                T, x, T + PH);
    }
    double xp = L + PW * (p95 - lo) / (hi - lo);
    if (xp < L) xp = L;
    if (xp > L + PW) xp = L + PW;
    fprintf(fp, "<line x1=\"%.1f\" y1=\"%d\" x2=\"%.1f\" y2=\"%d\" stroke=\"#c00\" stroke-width=\"2\"/>"
            "<text x=\"%.1f\" y=\"%d\" fill=\"#c00\">p95 = %.3g</text>\n", xp, T, xp, T + PH, xp + 3, T + 12, p95);
    int nt = which ? 8 : 7;
    for (int k = 0; k <= nt; k++) {
        double val = lo + k * (hi - lo) / nt;
        fprintf(fp, "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%g</text>\n", L + PW * k / (double)nt,
                T + PH + 14, round(val * 100) / 100);
    }
    for (int k = 0; k <= 4; k++) {
        fprintf(fp, "<text x=\"%d\" y=\"%d\" text-anchor=\"end\">%.3g</text>", L - 4, T + PH - PH * k / 4 + 4,
                cmax * k / 4.0);
        fprintf(fp, "<text x=\"%d\" y=\"%d\" fill=\"#d04020\">%d%%</text>\n", L + PW + 4, T + PH - PH * k / 4 + 4, 25 * k);
    }
    fprintf(fp, "<text x=\"%d\" y=\"%d\" text-anchor=\"middle\">%s</text>\n", L + PW / 2, T + PH + 32,
            which ? "DGI (dashed: 18 / 24 / 31)" : "DGP (dashed: 0.35 / 0.40 / 0.45)");
    fputs("</svg>\n", fp);
    return hd_ofile_commit(of);
}

hd_status hd_report_legend_svg(const char *path, double lmin, double lmax)
{
    hd_ofile *of;
    FILE *fp;
    hd_status st = open_out(&of, path, &fp);
    if (st) return st;
    fprintf(fp, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"460\" height=\"48\" font-family=\"sans-serif\" "
            "font-size=\"11\">\n");
    for (int k = 0; k < 200; k++) {
        uint8_t c[3];
        hd_report_ramp(k / 199.0, c);
        fprintf(fp, "<rect x=\"%d\" y=\"4\" width=\"2\" height=\"14\" fill=\"#%02x%02x%02x\"/>", 10 + 2 * k, c[0], c[1], c[2]);
    }
    double dec = log10(lmax / lmin);
    for (double l = lmin; l <= lmax * 1.0001; l *= 10) {
        double x = 10 + 400 * log10(l / lmin) / dec;
        fprintf(fp, "\n<line x1=\"%.1f\" y1=\"2\" x2=\"%.1f\" y2=\"20\" stroke=\"#000\"/><text x=\"%.1f\" y=\"32\" "
                "text-anchor=\"middle\">%g</text>", x, x, x, l);
    }
    fprintf(fp, "\n<text x=\"10\" y=\"45\">luminance, cd/m&#178; (log scale)</text>\n</svg>\n");
    return hd_ofile_commit(of);
}

hd_status hd_report_falsecolor_png(const char *hdr_path, const char *png_path, double lmin, double lmax,
                                   char *caption, size_t capcap)
{
    hd_picture p;
    hd_status st = hd_picture_read(hdr_path, &p);
    if (st) return st;
    double expo = hd_header_exposure(&p.hdr);
    if (!(expo > 0)) expo = 1;
    size_t npix = (size_t)p.xres * p.yres;
    uint8_t *rgb = hd_malloc_array(npix, 3);
    if (!rgb) {
        hd_picture_free(&p);
        return HD_ERR_NOMEM;
    }
    for (size_t i = 0; i < npix; i++)
        hd_report_falsecolor(hd_glare_luminance(p.pix + 3 * i) / expo, lmin, lmax, rgb + 3 * i);
    st = hd_png_write(png_path, rgb, p.xres, p.yres);
    free(rgb);
    if (!st && caption) {
        char hour[128] = "";
        hd_header_get(&p.hdr, "HOUR", hour, sizeof hour);
        hd_glare_view v;
        hd_view_default(&v);
        int found = 0;
        hd_glare_result r;
        memset(&r, 0, sizeof r);
        int have = 0;
        if (!hd_view_from_header(&v, &p.hdr, &found) && found && !hd_glare_view_check(&v)) {
            hd_glare_opts o;
            hd_glare_opts_default(&o);
            if (!hd_glare_eval(p.pix, p.xres, p.yres, &v, &o, &r)) have = 1;
        }
        hd_clear_error();
        long rec = -1;
        int mo = 0, da = 0;
        double hr = 0;
        if (sscanf(hour, "%ld %d %d %lf", &rec, &mo, &da, &hr) == 4) {
            int hh = (int)floor(hr), mm = (int)lround((hr - hh) * 60);
            if (have)
                snprintf(caption, capcap, "%02d/%02d %02d:%02d (record %ld): DGP %.3f, DGI %.1f, Ev %.0f lx", da, mo,
                         hh, mm, rec, r.dgp, r.dgi, r.ev);
            else
                snprintf(caption, capcap, "%02d/%02d %02d:%02d (record %ld)", da, mo, hh, mm, rec);
        } else if (have) {
            snprintf(caption, capcap, "DGP %.3f, DGI %.1f, Ev %.0f lx", r.dgp, r.dgi, r.ev);
        } else {
            hd_strlcpy(caption, hdr_path, capcap);
        }
        hd_glare_result_free(&r);
    }
    hd_picture_free(&p);
    return st;
}

hd_status hd_report_display_png(const char *hdr_path, const char *png_path)
{
    hd_picture p;
    hd_status st = hd_picture_read(hdr_path, &p);
    if (st) return st;
    size_t n = (size_t)p.xres * p.yres * 3;
    uint8_t *rgb = hd_malloc_array(n, 1);
    if (!rgb) {
        hd_picture_free(&p);
        return HD_ERR_NOMEM;
    }
    for (size_t i = 0; i < n; i++) {
        double v = p.pix[i];
        v = v > 0 ? (v < 1 ? pow(v, 1 / 2.2) : 1) : 0;
        rgb[i] = (uint8_t)lround(255 * v);
    }
    st = hd_png_write(png_path, rgb, p.xres, p.yres);
    free(rgb);
    hd_picture_free(&p);
    return st;
}

void hd_report_opts_default(hd_report_opts *o)
{
    memset(o, 0, sizeof *o);
    o->title = "Annual glare assessment (PM-CBDM)";
    o->shade_limit = HD_GLARE_SHADE_LIMIT;
    o->lmin = 10;
    o->lmax = 10000;
}

static void html_escape(FILE *fp, const char *s)
{
    for (; *s; s++) {
        if (*s == '<') fputs("&lt;", fp);
        else if (*s == '>') fputs("&gt;", fp);
        else if (*s == '&') fputs("&amp;", fp);
        else if (*s == '"') fputs("&quot;", fp);
        else if (*s != '\n' && *s != '\r') fputc(*s, fp);
    }
}

/* "key = value" / "key value" lines as table rows */
static hd_status kv_table(FILE *fp, const char *path, const char *h1, const char *h2)
{
    hd_istream *s;
    hd_status st = hd_istream_open(&s, path);
    if (st) return st;
    fprintf(fp, "<table><tr><th>%s</th><th>%s</th></tr>\n", h1, h2);
    char line[2048];
    while (hd_istream_getline(s, line, sizeof line) > 0) {
        char *k = line;
        while (*k == ' ' || *k == '\t') k++;
        if (!*k || *k == '#' || *k == '\n') continue;
        char *eq = strchr(k, '='), *e, *v;
        if (eq) {   /* "key words = value" */
            e = eq;
            while (e > k && (e[-1] == ' ' || e[-1] == '\t')) e--;
            v = eq + 1;
        } else {    /* "key value" */
            e = k;
            while (*e && *e != ' ' && *e != '\t' && *e != '\n') e++;
            v = e;
        }
        while (*v == ' ' || *v == '\t') v++;
        *e = 0;
        fputs("<tr><td>", fp);
        html_escape(fp, k);
        fputs("</td><td>", fp);
        html_escape(fp, v);
        fputs("</td></tr>\n", fp);
    }
    hd_istream_close(s);
    fputs("</table>\n", fp);
    return HD_OK;
}

/* the stage timings of pipeline/stage.sh, "NAME WALL [cpu CPU rss_mb RSS disk_mb DISK peak_mb PEAK]"
 * (older files: "NAME WALL" only), as a table with a total row: wall and CPU summed, the largest
 * resident set and run-folder size, the disk added summed */
static hd_status timings_table(FILE *fp, const char *path)
{
    static const char *const key[] = {"cpu", "rss_mb", "disk_mb", "peak_mb"};
    hd_istream *s;
    hd_status st = hd_istream_open(&s, path);
    if (st) return st;
    fputs("<table><tr><th>stage</th><th>wall s</th><th>CPU s</th><th>peak RSS MB</th><th>disk added MB</th>"
          "<th>run folder peak MB</th></tr>\n", fp);
    double tot[5] = {0};
    int have[5] = {0};
    char line[2048];
    while (hd_istream_getline(s, line, sizeof line) > 0) {
        char *save = NULL, *name = strtok_r(line, " \t\n", &save);
        if (!name || *name == '#') continue;
        char *val[5] = {strtok_r(NULL, " \t\n", &save), NULL, NULL, NULL, NULL}, *k;
        while ((k = strtok_r(NULL, " \t\n", &save))) {
            char *v = strtok_r(NULL, " \t\n", &save);
            for (int i = 0; i < 4 && v; i++)
                if (!strcmp(k, key[i])) val[i + 1] = v;
        }
        fputs("<tr><td>", fp);
        html_escape(fp, name);
        fputs("</td>", fp);
        for (int i = 0; i < 5; i++) {
            char *e;
            double x = val[i] ? strtod(val[i], &e) : 0;
            int ok = val[i] && e != val[i] && !*e;
            if (ok) {
                have[i] = 1;
                if (i == 2 || i == 4) tot[i] = x > tot[i] ? x : tot[i];
                else tot[i] += x;
            }
            fputs("<td>", fp);
            if (val[i]) html_escape(fp, val[i]);
            fputs("</td>", fp);
        }
        fputs("</tr>\n", fp);
    }
    hd_istream_close(s);
    fputs("<tr><th>total (RSS, folder: largest)</th>", fp);
    for (int i = 0; i < 5; i++)
        if (have[i]) fprintf(fp, "<th>%.*f</th>", i < 2 ? 2 : 1, tot[i]);
        else fputs("<th></th>", fp);
    fputs("</tr>\n</table>\n", fp);
    return HD_OK;
}

hd_status hd_report_write(const hd_report_opts *o)
{
    if (!o->csv || !o->outdir) return hd_fail(HD_ERR_USAGE, "the report needs the annual CSV and an output directory");
    if (mkdir(o->outdir, 0777) != 0 && errno != EEXIST)
        return hd_fail(HD_ERR_IO, "%s: cannot create the report directory: %s", o->outdir, strerror(errno));
    hd_report_data d;
    hd_status st = hd_report_read_csv(o->csv, &d);
    if (st) return st;
    char path[4096];
#define OUT(name) (snprintf(path, sizeof path, "%s/%s", o->outdir, name) < (int)sizeof path ? path : "")
    static const char *figs[5] = {"dgp_heat.svg", "dgi_heat.svg", "shade.svg", "dgp_hist.svg", "dgi_hist.svg"};
    hd_report_data od;
    memset(&od, 0, sizeof od);
    if (o->open_csv) {
        if ((st = hd_report_read_csv(o->open_csv, &od))) {
            hd_report_data_free(&d);
            return st;
        }
        for (size_t i = 0; i < d.n && !st; i++)
            if (od.n != d.n || fabs(od.hoy[i] - d.hoy[i]) > 1e-6)
                st = hd_fail(HD_ERR_FORMAT, "%s: the open run's hours differ from the composite %s (%zu vs %zu hours)",
                             o->open_csv, o->csv, od.n, d.n);
    }
    for (int k = 0; k < 3 && !st; k++)
        st = hd_report_heatmap_svg(OUT(figs[k]), &d, k == 2 && o->open_csv ? 3 : k, o->shade_limit);
    for (int k = 0; k < 2 && !st; k++) st = hd_report_histogram_svg(OUT(figs[3 + k]), &d, k);
    if (!st && o->nimages) st = hd_report_legend_svg(OUT("fc_legend.svg"), o->lmin, o->lmax);
    char (*caps)[256] = o->nimages ? hd_calloc((size_t)o->nimages, sizeof *caps) : NULL;
    if (o->nimages && !caps) st = HD_ERR_NOMEM;
    for (int i = 0; i < o->nimages && !st; i++) {
        char name[64];
        snprintf(name, sizeof name, "fc_%d.png", i);
        st = hd_report_falsecolor_png(o->images[i], OUT(name), o->lmin, o->lmax, caps[i], sizeof caps[i]);
    }
    hd_ofile *of = NULL;
    FILE *fp = NULL;
    if (!st) st = open_out(&of, OUT("index.html"), &fp);
    if (st) {
        free(caps);
        hd_report_data_free(&d);
        hd_report_data_free(&od);
        return st;
    }
    fputs("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>", fp);
    html_escape(fp, o->title);
    fputs("</title>\n<style>body{font-family:sans-serif;margin:2em;max-width:1100px}table{border-collapse:collapse;"
          "margin:0.5em 0}td,th{border:1px solid #bbb;padding:2px 8px;text-align:left}figure{display:inline-block;"
          "margin:0.5em}img.fc{width:256px;height:256px;image-rendering:pixelated}</style></head><body>\n<h1>", fp);
    html_escape(fp, o->title);
    fputs("</h1>\n", fp);
    size_t nclosed = 0, cdgp[4] = {0}, cdgi[4] = {0};
    for (size_t i = 0; i < d.n; i++) {
        nclosed += o->open_csv ? d.shade[i] != 0 : d.dgp[i] >= o->shade_limit;
        cdgp[hd_glare_class_dgp(d.dgp[i])]++;
        cdgi[hd_glare_class_dgi(d.dgi[i])]++;
    }
    fprintf(fp, "<h2>Summary</h2>\n<table><tr><th>daylight hours evaluated</th><td>%zu</td></tr>\n"
            "<tr><th>DGP, 95th percentile</th><td>%.3f</td></tr><tr><th>DGI, 95th percentile</th><td>%.2f</td></tr>\n"
            "<tr><th>E<sub>v</sub>, 95th percentile</th><td>%.0f lx</td></tr>\n"
            "<tr><th>%s shade closed (%sDGP &#8805; %.2f)</th><td>%zu h (%.1f %%)</td></tr></table>\n",
            d.n, hd_glare_percentile(d.dgp, d.n, 95), hd_glare_percentile(d.dgi, d.n, 95),
            hd_glare_percentile(d.ev, d.n, 95), o->open_csv ? "scheduled" : "operated",
            o->open_csv ? "open-shade " : "", o->shade_limit, nclosed, 100.0 * nclosed / d.n);
    fputs("<table><tr><th>class</th><th>DGP hours</th><th>DGI hours</th></tr>\n", fp);
    static const char *cls[4] = {"imperceptible (DGP &lt; 0.35, DGI &lt; 18)", "perceptible (0.35&#8211;0.40, 18&#8211;24)",
                                 "disturbing (0.40&#8211;0.45, 24&#8211;31)", "intolerable (&#8805; 0.45, &#8805; 31)"};
    for (int k = 0; k < 4; k++)
        fprintf(fp, "<tr><td>%s</td><td>%zu (%.1f %%)</td><td>%zu (%.1f %%)</td></tr>\n", cls[k], cdgp[k],
                100.0 * cdgp[k] / d.n, cdgi[k], 100.0 * cdgi[k] / d.n);
    fputs("</table>\n<h2>Heat maps</h2>\n<p><img src=\"dgp_heat.svg\" alt=\"DGP heat map\"></p>\n"
          "<p><img src=\"dgi_heat.svg\" alt=\"DGI heat map\"></p>\n<h2>Distributions</h2>\n"
          "<p><img src=\"dgp_hist.svg\" alt=\"DGP histogram\"> <img src=\"dgi_hist.svg\" alt=\"DGI histogram\"></p>\n"
          "<h2>Shade schedule</h2>\n<p><img src=\"shade.svg\" alt=\"shade schedule\"></p>\n", fp);
    if (o->open_csv) {
        size_t co[4] = {0};
        for (size_t i = 0; i < od.n; i++) co[hd_glare_class_dgp(od.dgp[i])]++;
        fprintf(fp, "<p>Two-pass shade operation: pass 1 with the shade open for every hour; the shade is closed for "
                "the hours whose open-shade DGP &#8805; %.2f, whose results come from pass 2 (shade closed).</p>\n"
                "<table><tr><th></th><th>shade always open</th><th>with the schedule</th></tr>\n"
                "<tr><td>DGP, 95th percentile</td><td>%.3f</td><td>%.3f</td></tr>\n"
                "<tr><td>DGI, 95th percentile</td><td>%.2f</td><td>%.2f</td></tr>\n", o->shade_limit,
                hd_glare_percentile(od.dgp, od.n, 95), hd_glare_percentile(d.dgp, d.n, 95),
                hd_glare_percentile(od.dgi, od.n, 95), hd_glare_percentile(d.dgi, d.n, 95));
        for (int k = 0; k < 4; k++)
            fprintf(fp, "<tr><td>DGP %s</td><td>%zu h</td><td>%zu h</td></tr>\n",
                    hd_glare_class_name((hd_glare_class)k), co[k], cdgp[k]);
        fputs("</table>\n", fp);
    }
    if (o->nimages) {
        fputs("<h2>Selected hours (false colour)</h2>\n<p><img src=\"fc_legend.svg\" alt=\"luminance legend\"></p>\n", fp);
        for (int i = 0; i < o->nimages; i++) {
            fprintf(fp, "<figure><img class=\"fc\" src=\"fc_%d.png\" alt=\"hour %d\"><figcaption>", i, i);
            html_escape(fp, caps[i]);
            fputs("</figcaption></figure>\n", fp);
        }
    }
    if (o->params) {
        fputs("<h2>Run parameters</h2>\n", fp);
        if ((st = kv_table(fp, o->params, "parameter", "value"))) goto fail;
    }
    if (o->timings) {
        fputs("<h2>Timings</h2>\n", fp);
        if ((st = timings_table(fp, o->timings))) goto fail;
    }
    if (o->summary) {
        hd_istream *s;
        if ((st = hd_istream_open(&s, o->summary))) goto fail;
        fputs("<h2>Notes</h2>\n<pre>", fp);
        char line[2048];
        while (hd_istream_getline(s, line, sizeof line) > 0) {
            html_escape(fp, line);
            fputc('\n', fp);
        }
        hd_istream_close(s);
        fputs("</pre>\n", fp);
    }
    fputs("<p><small>Written by heliodon cbdmreport from ", fp);
    html_escape(fp, o->csv);
    fputs(".</small></p>\n</body></html>\n", fp);
    free(caps);
    hd_report_data_free(&d);
    hd_report_data_free(&od);
    return hd_ofile_commit(of);
fail:
    free(caps);
    hd_report_data_free(&d);
    hd_report_data_free(&od);
    hd_ofile_abort(of);
    return st;
#undef OUT
}

static int cmp_dgp(const void *a, const void *b)
{
    const double *x = a, *y = b;
    return (x[1] > y[1]) - (x[1] < y[1]);
}

hd_status hd_report_select(const char *hourlog, int n, FILE *fp)
{
    hd_istream *s;
    hd_status st = hd_istream_open(&s, hourlog);
    if (st) return st;
    size_t cnt = 0, cap = 0;
    double *v = NULL;   /* pairs: record, dgp */
    char line[1024];
    unsigned long lineno = 0;
    while (hd_istream_getline(s, line, sizeof line) > 0) {
        lineno++;
        if (line[0] == '#' || line[0] == '\n') continue;
        double f[13];
        if (sscanf(line, "%lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf", &f[0], &f[1], &f[2], &f[3], &f[4], &f[5],
                   &f[6], &f[7], &f[8], &f[9], &f[10], &f[11], &f[12]) != 13) {
            unsigned long ln = lineno;
            hd_istream_close(s);
            free(v);
            return hd_fail(HD_ERR_FORMAT, "%s: line %lu: expected the 13 columns of a pmcompose -L log", hourlog, ln);
        }
        if (cnt == cap) {
            cap = cap ? 2 * cap : 256;
            double *nv = hd_realloc_array(v, cap, 2 * sizeof(double));
            if (!nv) {
                free(v);
                hd_istream_close(s);
                return HD_ERR_NOMEM;
            }
            v = nv;
        }
        v[2 * cnt] = f[0];
        v[2 * cnt + 1] = f[12];
        cnt++;
    }
    hd_istream_close(s);
    if (!cnt) {
        free(v);
        return hd_fail(HD_ERR_FORMAT, "%s: no hours in the log", hourlog);
    }
    qsort(v, cnt, 2 * sizeof(double), cmp_dgp);
    size_t pick[4] = {cnt - 1, (size_t)floor(0.95 * (cnt - 1) + 0.5), (cnt - 1) / 2, 0};
    long out[4];
    int no = 0;
    if (n > 4) n = 4;
    for (int k = 0; k < 4 && no < n; k++) {
        long r = (long)v[2 * pick[k]];
        int dup = 0;
        for (int j = 0; j < no; j++) dup |= out[j] == r;
        if (!dup) out[no++] = r;
    }
    for (int j = 0; j < no; j++) fprintf(fp, "%s%ld", j ? "," : "", out[j]);
    fputc('\n', fp);
    free(v);
    return HD_OK;
}

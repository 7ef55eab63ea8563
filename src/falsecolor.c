/* heliodon — falsecolor: false-colour pictures with Radiance's falsecolor
 * options (scale, -log decades, contour lines -cl, bands -cb, posterize
 * -cp, palettes, -r/-g/-b mapping functions, -ip/-p background), written
 * as one program on pcomb (src/pcomb.c): the value v = map(L / scale) of
 * each pixel goes through the palette's .cal functions, exactly as
 * Radiance's falsecolor script drives pcomb, so the pixels are the same.
 *
 * The tabulated palettes "def" (the default: falsecolor2's colours) and
 * "tbo" (Google's Turbo) are C functions over the published tables
 * (falsecolor_pal.h) with the interpolation Radiance's falsecolor uses
 * (fc_def, fc_tbo below), so their pixels are Radiance's to the bit.
 *
 * The legend's labels (positions, values, digits, shadow), the labels of
 * -e (extrema) and the names of the -palettes chart are drawn as Radiance's
 * psign draws them with Radiance's font helvet.fnt found through RAYPATH
 * (font.c), so they are Radiance's pixels; heliodon ships no font, and
 * without one they are drawn with heliodon's own bitmap glyphs (glyphs.c)
 * in the same places; so are the values of the -odim/-orct overlay. */
#include <ctype.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "heliodon/cal.h"
#include "heliodon/font.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/pictools.h"
#include "heliodon/picture.h"
#include "heliodon/pvalue.h"
#include "falsecolor_pal.h"
#include "glyphs.h"

/* The .cal definitions common to the picture and the legend (after the
 * scale, mult and ndivs constants).  Palettes map v in 0..1 to a colour. */
static const char *fc_defs =
    "gamma : 2.2;\n"
    "or(a,b) : if(a,a,b);\n"
    "EPS : 1e-7;\n"
    "neq(a,b) : if(a-b-EPS,1,b-a-EPS);\n"
    "btwn(a,x,b) : if(a-x,-1,b-x);\n"
    "clip(x) : min(1,max(x,0));\n"
    "frac(x) : x - floor(x);\n"
    "boundary(a,b) : neq(floor(ndivs*a),floor(ndivs*b));\n"
    "round(x) : floor(x+.5);\n"
    /* spectrum: blue - green - red */
    "spec_red(x) = 1.6*x - .6;\n"
    "spec_grn(x) = if(x-.375, 1.6-1.6*x, 8/3*x);\n"
    "spec_blu(x) = 1 - 8/3*x;\n"
    /* gnuplot's pm3d default (sqrt, cube, sine), gamma-expanded */
    "pm3d_red(x) = sqrt(clip(x)) ^ gamma;\n"
    "pm3d_grn(x) = clip(x*x*x) ^ gamma;\n"
    "pm3d_blu(x) = clip(sin(2*PI*clip(x))) ^ gamma;\n"
    /* black body ("hot"): red, then green, then blue ramps */
    "hot_red(x) = clip(3*x) ^ gamma;\n"
    "hot_grn(x) = clip(3*x - 1) ^ gamma;\n"
    "hot_blu(x) = clip(3*x - 2) ^ gamma;\n"
    /* eco: blue to green to red in two halves */
    "eco_red(x) = clip(2*x) ^ gamma;\n"
    "eco_grn(x) = clip(2*(x-0.5)) ^ gamma;\n"
    "eco_blu(x) = clip(2*(0.5-x)) ^ gamma;\n"
    "isconta = if(btwn(1/ndivs/2,v,1+1/ndivs/2),or(boundary(vleft,vright),boundary(vabove,vbelow)),-1);\n"
    "iscontb = if(btwn(1/ndivs/2,v,1+1/ndivs/2),-btwn(.1,frac(ndivs*v),.9),-1);\n"
    "iscont0 = -1;\n"
    "seg(x) = (floor(v*ndivs)+.5)/ndivs;\n"
    "seg2(x) = (seg(x)-1/ndivs)*ndivs/(ndivs-1);\n"
    "ra = 0;\nga = 0;\nba = 0;\n"
    "in = 1;\n";

/* the picture's value v and the background (after fc_defs) */
static const char *fc_pic =
    "norm : mult/scale/le(1);\n"
    "v = map(li(1)*norm);\n"
    "vleft = map(li(1,-1,0)*norm);\n"
    "vright = map(li(1,1,0)*norm);\n"
    "vabove = map(li(1,0,1)*norm);\n"
    "vbelow = map(li(1,0,-1)*norm);\n"
    "map(x) = x;\n"
    "ra = ri(nfiles);\nga = gi(nfiles);\nba = bi(nfiles);\n";

/* Replace every "v" in s by rep, splitting like Perl's split (trailing
 * empty fields dropped) and joining with rep, as Radiance's script does to
 * the mapping functions. */
static char *subst_v(const char *s, const char *rep)
{
    size_t n = strlen(s), end = n;
    while (end > 0 && s[end - 1] == 'v') end--;      /* trailing empty fields */
    size_t cap = n * (strlen(rep) + 1) + 1, k = 0;
    char *out = malloc(cap);
    if (!out) return NULL;
    for (size_t i = 0; i < end; i++) {
        if (s[i] == 'v') { strcpy(out + k, rep); k += strlen(rep); }
        else out[k++] = s[i];
    }
    out[k] = 0;
    return out;
}

typedef struct fcopt {
    const char *mult, *label, *scale, *digits, *decades, *ndivs;
    char *redv, *grnv, *bluv;
    const char *picture, *cpict;
    long legw, legh;
    int haszero, poster, needfile, extrem, showpal;
    char cont;              /* 0, 'a', 'b', '0' */
    hd_font *font;          /* helvet.fnt through RAYPATH; NULL: heliodon's glyphs */
    const char *odim[2];    /* -odim: overlay matrix columns, rows */
    const char *orct[4];    /* -orct: overlay rectangle left, bottom, right, top */
    int has_orct;
} fcopt;

static hd_status take(int argc, char **argv, int *i, const char **v)
{
    if (*i + 1 >= argc) return hd_fail(HD_ERR_USAGE, "option %s needs a value", argv[*i]);
    *v = argv[++*i];
    return HD_OK;
}

static hd_status set_pal(fcopt *o, const char *pal)
{
    static const char *pals[] = {"def", "spec", "pm3d", "hot", "eco", "tbo"};
    int ok = 0;
    for (int k = 0; k < 6; k++) ok |= !strcmp(pal, pals[k]);
    if (!ok) return hd_fail(HD_ERR_USAGE, "invalid palette '%s'", pal);
    char b[64];
    free(o->redv); free(o->grnv); free(o->bluv);
    snprintf(b, sizeof b, "%s_red(v)", pal); o->redv = hd_strdup(b);
    snprintf(b, sizeof b, "%s_grn(v)", pal); o->grnv = hd_strdup(b);
    snprintf(b, sizeof b, "%s_blu(v)", pal); o->bluv = hd_strdup(b);
    return o->redv && o->grnv && o->bluv ? HD_OK : HD_ERR_NOMEM;
}

/* Options as Radiance's falsecolor matches them (substrings, in this order). */
static hd_status parse(fcopt *o, int argc, char **argv)
{
    hd_status st = set_pal(o, "def");
    for (int i = 1; i < argc && !st; i++) {
        const char *a = argv[i], *v = NULL;
        size_t n = strlen(a);
#define HAS(s) (strstr(a, s) != NULL)
#define ENDS(s) (n >= strlen(s) && !strcmp(a + n - strlen(s), s) && HAS(s))
        if (HAS("-lw")) { if (!(st = take(argc, argv, &i, &v))) o->legw = atol(v); }
        else if (HAS("-lh")) { if (!(st = take(argc, argv, &i, &v))) o->legh = atol(v); }
        else if (HAS("-m")) st = take(argc, argv, &i, &o->mult);
        else if (HAS("-spec")) st = hd_fail(HD_ERR_USAGE, "depricated option '-spec'. Please use '-pal spec' instead.");
        else if (HAS("-s")) { if (!(st = take(argc, argv, &i, &o->scale)) && (o->scale[0] == 'a' || o->scale[0] == 'A')) o->needfile = 1; }
        else if (HAS("-d")) st = take(argc, argv, &i, &o->digits);
        else if (ENDS("-l")) st = take(argc, argv, &i, &o->label);
        else if (HAS("-log")) st = take(argc, argv, &i, &o->decades);
        else if (HAS("-r")) { if (!(st = take(argc, argv, &i, &v))) { free(o->redv); o->redv = hd_strdup(v); } }
        else if (HAS("-g")) { if (!(st = take(argc, argv, &i, &v))) { free(o->grnv); o->grnv = hd_strdup(v); } }
        else if (HAS("-b")) { if (!(st = take(argc, argv, &i, &v))) { free(o->bluv); o->bluv = hd_strdup(v); } }
        else if (ENDS("-pal")) { if (!(st = take(argc, argv, &i, &v))) st = set_pal(o, v); }
        else if (ENDS("-i")) st = take(argc, argv, &i, &o->picture);
        else if (ENDS("-p")) st = take(argc, argv, &i, &o->cpict);
        else if (HAS("-ip") || HAS("-pi")) { if (!(st = take(argc, argv, &i, &o->picture))) o->cpict = o->picture; }
        else if (HAS("-n")) st = take(argc, argv, &i, &o->ndivs);
        else if (ENDS("-odim")) {
            for (int k = 0; k < 2 && !st; k++) st = take(argc, argv, &i, &o->odim[k]);
            if (!st && atof(o->odim[0]) != 0 && atof(o->odim[1]) != 0) o->needfile = 1;
        } else if (HAS("-orct")) {
            for (int k = 0; k < 4 && !st; k++) st = take(argc, argv, &i, &o->orct[k]);
            o->has_orct = 1;
        }
        else if (HAS("-cl")) { o->cont = 'a'; o->haszero = 0; }
        else if (HAS("-cb")) { o->cont = 'b'; o->haszero = 0; }
        else if (HAS("-cp")) { o->poster = 1; o->haszero = 0; }
        else if (HAS("-c0")) { o->cont = '0'; o->legw = o->legh = 0; }
        else if (HAS("-palettes")) { o->scale = "45824"; o->showpal = 1; }
        else if (HAS("-e"))
            o->extrem = o->needfile = 1;
        else st = hd_fail(HD_ERR_USAGE, "bad option \"%s\"", a);
#undef HAS
#undef ENDS
    }
    if (!st && (!o->redv || !o->grnv || !o->bluv)) st = HD_ERR_NOMEM;
    return st;
}

/* -s auto: the top of the luminance histogram as Radiance's phisto
 * computes it (128x128 box-filtered picture, original values, 777 bins of
 * log10 luminance; the centre of the next-to-last bin), printed and read
 * back with the precision the script's tools use. */
static hd_status auto_scale(const char *picture, const char *mult, char *out, size_t cap)
{
    hd_picture in;
    hd_status st = hd_picture_read(picture, &in);
    if (st) return st;
    hd_pfilt_opts po;
    hd_pfilt_opts_default(&po);
    po.singlepass = 1;
    po.ncols = po.nrows = 128;
    po.outaspect = 1;
    char *buf = NULL;
    size_t len = 0;
    FILE *ms = open_memstream(&buf, &len);
    if (!ms) { hd_picture_free(&in); return HD_ERR_NOMEM; }
    st = hd_pfilt(&in, &po, 0, NULL, ms);
    fclose(ms);
    hd_picture_free(&in);
    hd_picture f;
    hd_istream *s = NULL;
    if (!st) st = hd_istream_memory(&s, buf, len, picture);
    if (!st) st = hd_picture_read_stream(s, &f);
    if (s) hd_istream_close(s);
    free(buf);
    if (st) return st;
    double ex = hd_header_exposure(&f.hdr);
    size_t n = (size_t)f.xres * f.yres;
    double lo = HUGE_VAL, hi = -HUGE_VAL;
    float *L = hd_malloc_array(n ? n : 1, sizeof *L);
    if (!L) { hd_picture_free(&f); return HD_ERR_NOMEM; }
    for (size_t i = 0; i < n; i++) {
        const float *c = f.pix + 3 * i;
        double b = hd_rgb_bright_rad(c);
        L[i] = (float)(b / ex);
        if (L[i] < lo) lo = L[i];
        if (L[i] > hi) hi = L[i];
    }
    hd_picture_free(&f);
    char t[64];
    double Ll = lo * 179;
    snprintf(t, sizeof t, "%.9g", Ll - 1e-7 > 0 ? log10(Ll) - .01 : -7.);
    double lmin = atof(t);
    snprintf(t, sizeof t, "%.9g", log10(hi * 179) + .01);
    double lmax = atof(t);
    free(L);
    snprintf(t, sizeof t, "%g", lmin + (lmax - lmin) * (775 + .5) / 777);
    snprintf(out, cap, "%.15g", atof(mult) / 179 * pow(10., atof(t)));
    return HD_OK;
}

/* The tabulated palettes, as C functions of one argument x (v), with the
 * arithmetic of Radiance's falsecolor so that the doubles are the same:
 *
 * def: the 23 colours of falsecolor2 (falsecolor_pal.h) sit at the
 * positions t = x / 0.0454545 + 1 = 1 .. 23 (the step written as that
 * decimal, not 1/22, as in Radiance); colours are interpolated linearly in
 * t between the two neighbours, (k + 1 - t) c[k] + (t - k) c[k+1] with k =
 * floor(t), and held at the end colours for t <= 1 and t >= 23.
 *
 * tbo: Google's Turbo table, entry n at x = n / 255.  Radiance takes the
 * nearest entry n = floor(255 x + .5) and adds (255 x - n) times the
 * difference to the following entry (the following entry of the last one
 * is itself), so below an entry the line of the segment above it is
 * extended; x <= 0 gives entry 0 and x > 1 the last entry.  The result is
 * raised to the power 2.2 (the table is sRGB-like, the picture linear).
 *
 * Both are registered in pcomb's .cal context as def_red, def_grn,
 * def_blu, tbo_red, tbo_grn, tbo_blu (pure functions of x). */
#define FC_DEF_STEP 0.0454545
#define FC_GAMMA 2.2

static double fc_def(double x, int c)
{
    double t = x / FC_DEF_STEP + 1;
    if (!(t - 1 > 0)) return fc_falsecolor2[0][c];
    if (!(23 - t > 0)) return fc_falsecolor2[22][c];
    double k = floor(t);
    int i = (int)k - 1;                         /* table row of position k */
    return (k + 1 - t) * fc_falsecolor2[i][c] + (t - k) * fc_falsecolor2[i + 1][c];
}

static double fc_tbo(double x, int c)
{
    double y;
    if (x - 1 > 0) y = fc_turbo[255][c];
    else if (!(x > 0)) y = fc_turbo[0][c];
    else {
        double n = floor(x * 255 + .5);
        int i = (int)n, j = i < 255 ? i + 1 : 255;
        y = fc_turbo[i][c] + (fc_turbo[j][c] - fc_turbo[i][c]) * (x * 255 - n);
    }
    return pow(y, FC_GAMMA);
}

static double fc_palfn(hd_calrun *run, void *user, int nargs, const double *args)
{
    (void)run; (void)nargs;
    int k = (int)(intptr_t)user;                /* 0..2 def, 3..5 tbo */
    return k < 3 ? fc_def(args[0], k) : fc_tbo(args[0], k - 3);
}

static hd_status fc_define(hd_cal *c, void *user)
{
    (void)user;
    static const char *names[6] = {"def_red", "def_grn", "def_blu", "tbo_red", "tbo_grn", "tbo_blu"};
    hd_status st = HD_OK;
    for (int k = 0; k < 6 && !st; k++) st = hd_cal_define_fn(c, names[k], 1, 1, fc_palfn, (void *)(intptr_t)k, 1);
    return st;
}

/* A legend value as Radiance's script prints it: the number with 15
 * significant digits, its decimals cut to `digits` (none for digits <= 0). */
static void label_value(char *buf, size_t cap, double v, int digits)
{
    char t[64];
    snprintf(t, sizeof t, "%.15g", v);
    char *dot = strchr(t, '.');
    if (dot) {
        char *e = dot + 1;
        while (*e >= '0' && *e <= '9') e++;
        char *keep = digits <= 0 ? dot : dot + 1 + digits < e ? dot + 1 + digits : e;
        memmove(keep, e, strlen(e) + 1);
    }
    hd_strlcpy(buf, t, cap);
}

/* Coverage (0..1, row 0 at the top) of TEXT HEIGHT pixels high as Radiance's
 * psign draws it (-a aspect, 0 = psign's 1.67; -s spacing) with font F, or
 * with heliodon's own glyphs when there is no font file (F NULL). */
static hd_status text_cover(const hd_font *f, const char *text, int height, double aspect, double spacing,
                            float **m, int *w)
{
    if (!f) return hd_text_mask(text, height, aspect, m, w);
    hd_textopts to;
    hd_textopts_default(&to);
    to.height = height;
    if (aspect > 0) to.aspect = aspect;
    to.spacing = spacing;
    unsigned char *c;
    int h;
    hd_status st = hd_font_text(f, &text, 1, &to, &c, w, &h);
    if (st) return st;
    size_t n = (size_t)*w * (size_t)h;
    *m = hd_malloc_array(n ? n : 1, sizeof **m);
    if (!*m) { free(c); return HD_ERR_NOMEM; }
    for (size_t i = 0; i < n; i++) (*m)[i] = (float)(c[i] / (double)(HD_FONT_SSS * HD_FONT_SSS));
    free(c);
    return HD_OK;
}

/* The legend's labels, laid out as Radiance's falsecolor does (the unit
 * above ndivs+haszero values, text lines th high centred at (k + .5) *
 * sheight, left-aligned), drawn with o->font or heliodon's glyphs: a
 * shadow 2 pixels right and 1 down of grey 1 - coverage where the glyph
 * covers > 90 % of a pixel, then grey = coverage where it covers > 50 % (as
 * Radiance composes its white-on-black label pictures with thresholds .1
 * and .5).  The picture (x >= legw, below pich) stays on top. */
/* Coverage mask m (w x h, row 0 at the top) onto out with its lower left
 * corner at (x0, y0): its grey (or, invert, its inverse) where the coverage
 * is above thr; the pixels at x >= clipx, y < clipy are left alone.  The
 * labels are drawn in two passes: the inverse above .9 shifted (the
 * shadow), then the grey above .5. */
static void put_cover(hd_rawpic *out, const float *m, int w, long h, long x0, long y0, float thr, int invert,
                      long clipx, long clipy)
{
    for (long r = 0; r < h; r++)
        for (int c = 0; c < w; c++) {
            float cov = m[(size_t)r * (size_t)w + (size_t)c];
            long px = x0 + c, py = y0 + h - 1 - r;
            if (cov <= thr) continue;
            if (px < 0 || py < 0 || px >= out->len || py >= out->nscans) continue;
            if (px >= clipx && py < clipy) continue;
            float g = invert ? 1 - cov : cov;
            hd_rgbe_encode(out->rgbe + ((size_t)(out->nscans - 1 - py) * (size_t)out->len + (size_t)px) * 4, g, g, g);
        }
}

static hd_status draw_labels(const fcopt *o, hd_rawpic *out, long sheight, long th, long top, int pich)
{
    int nd = (int)atof(o->ndivs), loop = nd + o->haszero;
    double scale = atof(o->scale), dec = atof(o->decades);
    int digits = atoi(o->digits);
    for (int pass = 0; pass < 2; pass++)
        for (int i = -1; i < loop; i++) {
            char text[128];
            long centre;
            if (i < 0) {
                hd_strlcpy(text, o->label, sizeof text);
                centre = top;
            } else {
                double imap = (double)(nd - i) / nd;
                label_value(text, sizeof text, dec > 0 ? scale * pow(10., (imap - 1) * dec) : scale * imap, digits);
                centre = (long)(sheight * (loop - i - 1) + sheight * .5);
            }
            float *m;
            int w;
            hd_status st = text_cover(o->font, text, (int)th, 0, -.15, &m, &w);
            if (st) return st;
            long y0 = centre - th / 2;                  /* bottom row of the text */
            put_cover(out, m, w, th, pass ? 0 : 2, y0 - (pass ? 0 : 1), pass ? .5f : .9f, !pass, o->legw, pich);
            free(m);
        }
    return HD_OK;
}

/* run pcomb with definitions and inputs, return the picture's bytes */
static hd_status run_pcomb(int ndef, char *kinds, const char **texts, int nin, hd_pcomb_input *ins, hd_rawpic *out)
{
    hd_pcomb_opts po;
    memset(&po, 0, sizeof po);
    po.echo_header = 0;
    po.ndefs = ndef;
    po.defkind = kinds;
    po.deftext = texts;
    po.ninputs = nin;
    po.inputs = ins;
    po.define = fc_define;
    char *buf = NULL;
    size_t len = 0;
    FILE *ms = open_memstream(&buf, &len);
    if (!ms) return HD_ERR_NOMEM;
    hd_status st = hd_pcomb(&po, 0, NULL, ms);
    fclose(ms);
    hd_istream *s = NULL;
    if (!st) st = hd_istream_memory(&s, buf, len, "pcomb output");
    if (!st) st = hd_rawpic_read_stream(s, out);
    if (s) hd_istream_close(s);
    free(buf);
    return st;
}

/* Radiance's falsecolor writes the extrema (and value overlays) with
 * characters 32 pixels high */
#define FC_CHEIGHT 32

/* A text box to paste: coverage mask m (w x h, row 0 at the top), lower
 * left corner at (x, y) counted from the picture's bottom left; text white
 * on black (invert 0, Radiance's psign -cb 0 0 0 -cf 1 1 1) or black on
 * white (invert 1, psign's default colours). */
typedef struct fctext {
    float *m;
    int w, h, invert;
    long x, y;
} fctext;

static hd_status make_text(const hd_font *f, fctext *t, const char *text, int height, double aspect, double spacing,
                           long x, long y, int invert)
{
    hd_status st = text_cover(f, text, height, aspect, spacing, &t->m, &t->w);
    t->h = height;
    t->x = x;
    t->y = y;
    t->invert = invert;
    return st;
}

/* the whole box, background included, over what is there (clipped) */
static void paste_text(hd_rawpic *out, const fctext *t)
{
    put_cover(out, t->m, t->w, t->h, t->x, t->y, -HUGE_VALF, t->invert, out->len, 0);
}

/* the output with a header of the date and the falsecolor command line */
static hd_status write_picture(FILE *fp, const hd_rawpic *out, int argc, char **argv)
{
    hd_header hh;
    hd_header_init(&hh);
    hd_status st = hd_header_add_date(&hh);
    if (!st) {
        size_t L = 16;
        for (int i = 1; i < argc; i++) L += strlen(argv[i]) + 1;
        char *line = malloc(L);
        if (!line) st = HD_ERR_NOMEM;
        else {
            strcpy(line, "falsecolor");
            for (int i = 1; i < argc; i++) { strcat(line, " "); strcat(line, argv[i]); }
            st = hd_header_append(&hh, line);
            free(line);
        }
    }
    if (!st) st = hd_rawpic_write(fp, out, &hh);
    hd_header_free(&hh);
    return st;
}

/* Copy standard input to a new temporary file (its name in path). */
static hd_status stdin_to_file(char *path, size_t cap)
{
    const char *dir = getenv("TMPDIR");
    snprintf(path, cap, "%s/falsecolorXXXXXX", dir && *dir && strlen(dir) < cap - 24 ? dir : "/tmp");
    int fd = mkstemp(path);
    if (fd < 0) { path[0] = 0; return hd_fail(HD_ERR_IO, "cannot make a temporary file for the standard input"); }
    FILE *f = fdopen(fd, "wb");
    hd_status st = f ? HD_OK : hd_fail(HD_ERR_IO, "cannot make a temporary file for the standard input");
    char buf[65536];
    size_t n;
    while (!st && (n = fread(buf, 1, sizeof buf, stdin)) > 0)
        if (fwrite(buf, 1, n, f) != n) st = hd_fail(HD_ERR_IO, "%s: write error", path);
    if (!st && ferror(stdin)) st = hd_fail(HD_ERR_IO, "read error on standard input");
    if (f ? fclose(f) : close(fd)) if (!st) st = hd_fail(HD_ERR_IO, "%s: write error", path);
    if (st) { remove(path); path[0] = 0; }
    return st;
}

/* A value of the overlay as Radiance's script rewrites pvalue's "%.3e"
 * output: exponent form below 1e-3 or from 1e7 on, else positional digits
 * (all four significant digits below 1, %g from 1 to 999.9, the mantissa's
 * digits padded with zeros from 1000 on). */
static void overlay_text(const char *s, char *out, size_t cap)
{
    while (*s == ' ' || *s == '\t') s++;
    hd_strlcpy(out, s, cap);
    size_t n = strlen(out);
    while (n && (out[n - 1] == '\n' || out[n - 1] == ' ')) out[--n] = 0;
    const char *p = out;
    if (!isdigit((unsigned char)p[0]) || p[1] != '.') return;
    char manti = p[0], mantf[32];
    size_t nf = 0;
    for (p += 2; isdigit((unsigned char)*p) && nf < sizeof mantf - 1; p++) mantf[nf++] = *p;
    mantf[nf] = 0;
    if (!nf || (*p != 'e' && *p != 'E')) return;
    char *end;
    long ex = strtol(p + 1, &end, 10);
    if (end == p + 1 || *end) return;
    char t[96];
    if (ex < -3 || ex > 6) return;                 /* exponent form */
    if (ex < 0) {
        int k = snprintf(t, sizeof t, "0.");
        for (long i = ex; ++i < 0;) t[k++] = '0';
        snprintf(t + k, sizeof t - (size_t)k, "%c%s", manti, mantf);
    } else if (ex < (long)nf)
        snprintf(t, sizeof t, "%g", atof(out));
    else {
        int k = snprintf(t, sizeof t, "%c%s", manti, mantf);
        for (long i = ex - (long)nf; i-- > 0;) t[k++] = '0';
        t[k] = 0;
    }
    hd_strlcpy(out, t, cap);
}

/* -odim NX NY [-orct L B R T]: an NX x NY matrix of the picture's values
 * (mult times the brightness) over the rectangle (default the whole
 * picture), as Radiance's script makes it: the rectangle box-filtered down
 * by the character height and Gaussian-filtered (radius .5) back up,
 * values taken at the centres of the matrix cells, each written white on
 * black (squeezed, *cheight high) centred on its cell, the labels of a row
 * side by side in a strip cropped to the rectangle's width, the strips
 * centred on their rows.  *over gets the rectangle's picture of labels
 * (grey levels, row 0 at the top; *ow x *oh). */
static hd_status overlay_labels(const fcopt *o, int *cheight, float **over, int *ow, int *oh)
{
    *over = NULL;
    hd_picture in;
    hd_status st = hd_picture_read(o->picture, &in);
    if (st) return st;
    double rect[4] = {0, 0, in.xres, in.yres};
    if (o->has_orct) {
        for (int k = 0; k < 4; k++) rect[k] = atof(o->orct[k]);
        if (rect[2] <= rect[0] || rect[3] <= rect[1]) st = hd_fail(HD_ERR_USAGE, "Illegal overlay rectangle");
    }
    long left = (long)rect[0], bottom = (long)rect[1];
    long cw = (long)(rect[2] - rect[0]), chh = (long)(rect[3] - rect[1]);
    double nx = atof(o->odim[0]), ny = atof(o->odim[1]);
    double hsp = cw / nx, vsp = chh / ny;
    int ch = (int)(vsp * 0.67 + 0.5);
    if (ch >= 1.67 / 10 * hsp) ch = (int)(1.67 / 10 * hsp);
    if (!st && ch < 10) st = hd_fail(HD_ERR_USAGE, "Overlay matrix spacing too tight");
    if (!st && (cw < 1 || chh < 1 || cw > HD_PIC_MAXSIDE || chh > HD_PIC_MAXSIDE))
        st = hd_fail(HD_ERR_RANGE, "overlay rectangle of %ld x %ld pixels", cw, chh);
    /* the rectangle (black outside the picture), as pcompos crops it */
    hd_picture crop;
    hd_picture_init(&crop);
    if (!st) st = hd_picture_alloc(&crop, (int)cw, (int)chh);
    if (!st) {
        memset(crop.pix, 0, (size_t)cw * (size_t)chh * 3 * sizeof *crop.pix);
        for (long y = 0; y < chh; y++) {            /* y from the rectangle's top */
            long sy = in.yres - 1 - (bottom + chh - 1 - y);
            if (sy < 0 || sy >= in.yres) continue;
            for (long x = 0; x < cw; x++) {
                long sx = left + x;
                if (sx < 0 || sx >= in.xres) continue;
                memcpy(crop.pix + 3 * ((size_t)y * (size_t)cw + (size_t)x), in.pix + 3 * ((size_t)sy * (size_t)in.xres + (size_t)sx),
                       3 * sizeof *crop.pix);
            }
        }
        char e[64];
        snprintf(e, sizeof e, "EXPOSURE=%e", hd_header_exposure(&in.hdr));
        if (hd_header_exposure(&in.hdr) != 1) st = hd_header_append(&crop.hdr, e);
    }
    hd_picture_free(&in);
    /* pfilt -1 -b -x /ch -y /ch, then pfilt -1 -r .5 back to the rectangle's size */
    hd_picture f2;
    hd_picture_init(&f2);
    char tmp[64] = "";
    for (int pass = 0; pass < 2 && !st; pass++) {
        hd_pfilt_opts po;
        hd_pfilt_opts_default(&po);
        po.singlepass = 1;
        if (pass == 0) { po.xratio = po.yratio = 1.0 / ch; po.ncols = po.nrows = 0; }
        else { po.rad = .5; po.ncols = (int)cw; po.nrows = (int)chh; }
        char *buf = NULL;
        size_t len = 0;
        FILE *ms = open_memstream(&buf, &len);
        if (!ms) { st = HD_ERR_NOMEM; break; }
        st = hd_pfilt(pass ? &f2 : &crop, &po, 0, NULL, ms);
        fclose(ms);
        if (!st && pass == 1) {                     /* pvalue reads it from a file */
            const char *dir = getenv("TMPDIR");
            snprintf(tmp, sizeof tmp, "%s/falsecolorXXXXXX", dir && *dir && strlen(dir) < 32 ? dir : "/tmp");
            int fd = mkstemp(tmp);
            FILE *tf = fd >= 0 ? fdopen(fd, "wb") : NULL;
            if (!tf || fwrite(buf, 1, len, tf) != len) st = hd_fail(HD_ERR_IO, "cannot write a temporary file");
            if (tf) fclose(tf);
            else if (fd >= 0) close(fd);
            if (fd < 0) tmp[0] = 0;
        } else if (!st) {
            hd_istream *is = NULL;
            hd_picture_free(&f2);
            st = hd_istream_memory(&is, buf, len, "pfilt output");
            if (!st) st = hd_picture_read_stream(is, &f2);
            if (is) hd_istream_close(is);
        }
        free(buf);
    }
    hd_picture_free(&crop);
    hd_picture_free(&f2);
    /* pvalue -o -h -H -b -d -e mult */
    char *vals = NULL;
    size_t vlen = 0;
    if (!st) {
        hd_pvalue_opts pv;
        hd_pvalue_opts_init(&pv);
        pv.header = 0;
        pv.resolution = 0;
        pv.original = 1;
        pv.putprim = HD_PV_BRIGHT;
        st = hd_pvalue_set_format(&pv, 0, 1);
        double d = atof(o->mult);
        if (o->mult[0] == '-' || o->mult[0] == '+') d = pow(2.0, d);
        pv.expval *= d;
        for (int c = 0; c < 3; c++) pv.exposure[c] *= (float)d;
        pv.doexposure++;
        hd_pvalue_opts_finish(&pv);
        FILE *ms = open_memstream(&vals, &vlen);
        if (!ms) st = HD_ERR_NOMEM;
        if (!st) st = hd_pvalue_to_values(&pv, tmp, ms, 0, NULL);
        if (ms) fclose(ms);
    }
    if (tmp[0]) remove(tmp);
    /* the labels */
    float *ov = NULL;
    if (!st && !(ov = hd_malloc_array((size_t)cw * (size_t)chh, sizeof *ov))) st = HD_ERR_NOMEM;
    if (!st) memset(ov, 0, (size_t)cw * (size_t)chh * sizeof *ov);
    int mx = (int)floor(nx - 1) + 1, my = (int)floor(ny - 1) + 1;
    float *strip = NULL;
    if (!st && !(strip = hd_malloc_array((size_t)cw * (size_t)ch, sizeof *strip))) st = HD_ERR_NOMEM;
    const char *vp = vals;
    for (long y = 0; y < chh && !st; y++) {
        int ymatch = 0;
        for (int j = 0; j < my; j++) ymatch |= (long)(vsp * (j + .5)) == y;
        memset(strip, 0, (size_t)cw * (size_t)ch * sizeof *strip);
        int stripw = 0;
        for (long x = 0; x < cw && !st; x++) {
            const char *nl = vp ? strchr(vp, '\n') : NULL;
            if (!nl) { st = hd_fail(HD_ERR_INTERNAL, "overlay: too few values"); break; }
            char line[64];
            size_t L = (size_t)(nl - vp) < sizeof line - 1 ? (size_t)(nl - vp) : sizeof line - 1;
            memcpy(line, vp, L);
            line[L] = 0;
            vp = nl + 1;
            int xmatch = 0;
            for (int i = 0; i < mx && ymatch; i++) xmatch |= (long)(hsp * (i + .5)) == x;
            if (!xmatch) continue;
            char text[96];
            overlay_text(line, text, sizeof text);
            float *m;
            int w;
            st = text_cover(o->font, text, ch, 0, -.15, &m, &w);
            if (st) break;
            long x0 = x - w / 2;                    /* pcompos =0- */
            for (int r = 0; r < ch; r++)
                for (int c = 0; c < w; c++)
                    if (x0 + c >= 0 && x0 + c < cw) strip[(size_t)r * (size_t)cw + (size_t)(x0 + c)] = m[(size_t)r * (size_t)w + (size_t)c];
            free(m);
            stripw = 1;
        }
        if (st || !ymatch || !stripw) continue;
        long top = chh - 1 - y - ch / 2 + ch - 1;   /* =-0 at (0, chh-1-y): its top row, from the bottom */
        for (int r = 0; r < ch; r++) {
            long py = top - r;                      /* from the bottom */
            if (py < 0 || py >= chh) continue;
            memcpy(ov + (size_t)(chh - 1 - py) * (size_t)cw, strip + (size_t)r * (size_t)cw, (size_t)cw * sizeof *ov);
        }
    }
    free(strip);
    free(vals);
    if (st) { free(ov); return st; }
    *over = ov;
    *ow = (int)cw;
    *oh = (int)chh;
    *cheight = ch;
    return HD_OK;
}

/* -e: the darkest and brightest pixels of the picture as pextrem -o finds
 * them, their values as Radiance's script computes them from pextrem's
 * printed colours ((.27 r + .67 g + .06 b) * mult, decimals cut to -d),
 * each written black on white, cheight high, centred on its pixel (x
 * shifted by the legend's width). */
static hd_status extrema_labels(const fcopt *o, int cheight, fctext lab[2])
{
    hd_istream *s;
    hd_status st = hd_istream_open(&s, o->picture);
    if (st) return st;
    hd_extrema e;
    st = hd_pextrem(s, 1, &e);
    hd_istream_close(s);
    double mult = atof(o->mult);
    int digits = atoi(o->digits);
    for (int k = 0; k < 2 && !st; k++) {
        const float *c = k ? e.max : e.min;
        char t[96], text[96];
        snprintf(t, sizeof t, "%.2e %.2e %.2e", c[0], c[1], c[2]);   /* as pextrem prints them */
        double rgb[3];
        if (sscanf(t, "%lf %lf %lf", &rgb[0], &rgb[1], &rgb[2]) != 3) return hd_fail(HD_ERR_FORMAT, "extrema: %s", t);
        label_value(text, sizeof text, (rgb[0] * .27 + rgb[1] * .67 + rgb[2] * .06) * mult, digits);
        long x = (k ? e.xmax : e.xmin) + o->legw, y = k ? e.ymax : e.ymin;
        st = make_text(o->font, &lab[k], text, cheight, 2, -.15, 0, 0, 1);  /* psign -s -.15 -a 2 */
        lab[k].x = x - lab[k].w / 2;               /* pcompos's anchor =00 */
        lab[k].y = y - cheight / 2;
    }
    return st;
}

/* -palettes: a chart of every palette as Radiance's falsecolor makes it:
 * for each palette a 256 x 30 bar of v = x/256 with its name (white on
 * black, 20 high) above it, stacked from the bottom in the order def,
 * spec, pm3d, hot, eco, tbo. */
static hd_status palette_chart(const hd_font *font, int argc, char **argv, FILE *fp)
{
    static const char *pals[6] = {"def", "spec", "pm3d", "hot", "eco", "tbo"};
    enum { BW = 256, BH = 30, LH = 20 };
    hd_rawpic out;
    hd_status st = hd_rawpic_blank(&out, HD_PIC_RGBE, BW, 6 * (BH + LH));
    char *head = malloc(strlen(fc_defs) + 128);
    if (!st && !head) st = HD_ERR_NOMEM;
    if (!st) sprintf(head, "scale : 45824 ;\nmult : 179 ;\nndivs : 8 ;\n%s", fc_defs);
    for (int k = 0; k < 6 && !st; k++) {
        char e[256];
        snprintf(e, sizeof e, "ro=clip(%s_red(v));go=clip(%s_grn(v));bo=clip(%s_blu(v))", pals[k], pals[k], pals[k]);
        char kinds[5] = {'e', 'e', 'e', 'x', 'y'};
        const char *texts[5] = {head, "v=x/256", e, "256", "30"};
        hd_rawpic bar;
        st = run_pcomb(5, kinds, texts, 0, NULL, &bar);
        if (st) break;
        int y0 = k * (BH + LH);                   /* bottom row of the bar */
        for (int y = 0; y < BH; y++)
            memcpy(out.rgbe + (size_t)(out.nscans - 1 - (y0 + y)) * BW * 4,
                   bar.rgbe + (size_t)(bar.nscans - 1 - y) * bar.len * 4, (size_t)BW * 4);
        hd_rawpic_free(&bar);
        fctext t;
        st = make_text(font, &t, pals[k], LH, 0, 0, 0, y0 + BH, 0);
        if (!st) paste_text(&out, &t);
        free(t.m);
    }
    if (!st) st = write_picture(fp, &out, argc, argv);
    free(out.rgbe);
    free(head);
    return st;
}

hd_status hd_falsecolor(int argc, char **argv, FILE *fp)
{
    fcopt o;
    memset(&o, 0, sizeof o);
    o.mult = "179"; o.label = "cd/m2"; o.scale = "1000"; o.digits = "3"; o.decades = "0"; o.ndivs = "8";
    o.picture = "-"; o.cpict = "";
    o.legw = 100; o.legh = 200;
    o.haszero = 1;
    hd_status st = parse(&o, argc, argv);
    char scalebuf[64];
    if (!st && (o.legw <= 20 || o.legh <= 40)) o.legw = o.legh = 0;
    char tmppic[64] = "";
    if (!st && !strcmp(o.picture, "-") && o.needfile) {    /* -s auto, -e: the picture is read twice */
        st = stdin_to_file(tmppic, sizeof tmppic);
        if (!st) {
            o.picture = tmppic;
            if (!strcmp(o.cpict, "-")) o.cpict = tmppic;
        }
    }
    /* the labels' font, as Radiance's psign finds it; without one,
     * heliodon's own glyphs */
    if (!st && (o.legw > 0 || o.extrem || o.showpal || o.odim[0])) {
        st = hd_font_load("helvet.fnt", &o.font);
        if (st == HD_ERR_IO && !strncmp(hd_errmsg(), "cannot find", 11)) { hd_clear_error(); st = HD_OK; }
    }
    if (!st && o.showpal) {
        st = palette_chart(o.font, argc, argv, fp);
        hd_font_free(o.font);
        if (tmppic[0]) remove(tmppic);
        free(o.redv); free(o.grnv); free(o.bluv);
        return st;
    }
    if (!st && (o.scale[0] == 'a' || o.scale[0] == 'A')) {
        st = auto_scale(o.picture, o.mult, scalebuf, sizeof scalebuf);
        o.scale = scalebuf;
    }
    char *r = NULL, *g = NULL, *b = NULL;
    if (!st) {
        const char *rep = o.poster ? "seg2(v)" : o.cont ? "(v-1/ndivs)*ndivs/(ndivs-1)" : NULL;
        r = rep ? subst_v(o.redv, rep) : hd_strdup(o.redv);
        g = rep ? subst_v(o.grnv, rep) : hd_strdup(o.grnv);
        b = rep ? subst_v(o.bluv, rep) : hd_strdup(o.bluv);
        if (!r || !g || !b) st = HD_ERR_NOMEM;
    }
    /* definitions: constants, common part, outputs, mode */
    char *head = NULL, *outs = NULL, *inmode = NULL, *mapdef = NULL;
    if (!st) {
        size_t n1 = strlen(o.scale) + strlen(o.mult) + strlen(o.ndivs) + 64;
        size_t n2 = strlen(r) + strlen(g) + strlen(b) + 96;
        head = malloc(n1 + strlen(fc_defs));
        outs = malloc(n2);
        inmode = malloc(32);
        mapdef = malloc(2 * strlen(o.decades) + 64);
        if (!head || !outs || !inmode || !mapdef) st = HD_ERR_NOMEM;
    }
    if (!st) {
        sprintf(head, "scale : %s ;\nmult : %s ;\nndivs : %s ;\n%s", o.scale, o.mult, o.ndivs, fc_defs);
        sprintf(outs, "ro = if(in,clip(%s),ra);\ngo = if(in,clip(%s),ga);\nbo = if(in,clip(%s),ba);\n", r, g, b);
        sprintf(inmode, "in=iscont%c", o.cont);
        sprintf(mapdef, "map(x)=if(x-10^-%s,log10(x)/%s+1,0)", o.decades, o.decades);
    }
    /* the picture */
    hd_rawpic pic, bar;
    memset(&pic, 0, sizeof pic);
    memset(&bar, 0, sizeof bar);
    if (!st) {
        char kinds[8];
        const char *texts[8];
        int nd = 0;
        kinds[nd] = 'e'; texts[nd++] = head;
        kinds[nd] = 'e'; texts[nd++] = outs;
        if (o.cont) { kinds[nd] = 'e'; texts[nd++] = inmode; }
        kinds[nd] = 'e'; texts[nd++] = fc_pic;
        int bg = o.cpict[0] != 0 && strcmp(o.cpict, o.picture);
        if (!o.cpict[0] && o.cont != '0') { kinds[nd] = 'e'; texts[nd++] = "ra=0;ga=0;ba=0"; }
        if (atof(o.decades) > 0) { kinds[nd] = 'e'; texts[nd++] = mapdef; }
        hd_pcomb_input ins[2] = {{o.picture, 0, {1, 1, 1}}, {o.cpict, 0, {1, 1, 1}}};
        st = run_pcomb(nd, kinds, texts, bg ? 2 : 1, ins, &pic);
    }
    /* the legend's colour bar */
    long sheight = 0, vleg = 0, sh0 = 0, slabh = 0, th = 0, top = 0;
    double nd = atof(o.ndivs);
    if (!st && o.legw > 0) {
        sheight = (long)(o.legh / nd);
        vleg = (long)(sheight * nd * (1 + 1.5 / nd));
        char e1[256], e2[256], xs[32], ys[32];
        snprintf(e1, sizeof e1, "v=(y+.5-%ld)/(yres/(1+1.5/%s));vleft=v;vright=v", sheight, o.ndivs);
        snprintf(e2, sizeof e2, "vbelow=(y-.5-%ld)/(yres/(1+1.5/%s));vabove=(y+1.5-%ld)/(yres/(1+1.5/%s))",
                 sheight, o.ndivs, sheight, o.ndivs);
        snprintf(xs, sizeof xs, "%ld", o.legw);
        snprintf(ys, sizeof ys, "%ld", vleg);
        char kinds[8];
        const char *texts[8];
        int n = 0;
        kinds[n] = 'e'; texts[n++] = head;
        kinds[n] = 'e'; texts[n++] = outs;
        if (o.cont) { kinds[n] = 'e'; texts[n++] = inmode; }
        kinds[n] = 'x'; texts[n++] = xs;
        kinds[n] = 'y'; texts[n++] = ys;
        kinds[n] = 'e'; texts[n++] = e1;
        kinds[n] = 'e'; texts[n++] = e2;
        kinds[n] = 'e'; texts[n++] = "ra=0;ga=0;ba=0;";
        st = run_pcomb(n, kinds, texts, 0, NULL, &bar);
        sh0 = o.haszero < 1 ? -(long)(o.legh / nd * 1.5) : -(long)(o.legh / nd / 2);
        /* the labels' column as Radiance lays it out: text lines of height
         * th centred at (k + .5) * sheight for k = 0 .. ndivs+haszero-1 and
         * the unit label above them; its top sets the picture's height */
        th = (long)(o.legw / (8 / 1.67));
        if (sheight < th) th = sheight;
        top = (long)(sheight * (nd + o.haszero) + sheight * .5);
        slabh = top - th / 2 + th;
    }
    /* -e: the extrema's labels, centred on the darkest and brightest pixels */
    /* -odim: the value overlay (its character height is then also the
     * extrema labels', as in Radiance's script) */
    int cheight = FC_CHEIGHT, ow = 0, oh = 0;
    float *over = NULL;
    long oxl = o.legw, oyb = 0;
    if (!st && o.odim[0] && atof(o.odim[0]) != 0 && atof(o.odim[1]) != 0) {
        st = overlay_labels(&o, &cheight, &over, &ow, &oh);
        if (o.has_orct) { oxl += (long)atof(o.orct[0]); oyb = (long)atof(o.orct[1]); }
    }
    fctext ext[2];
    memset(ext, 0, sizeof ext);
    if (!st && o.extrem) st = extrema_labels(&o, cheight, ext);
    /* compose: the bar at (0, sh0), the picture at (legw, 0), black
     * elsewhere, the labels, then the extrema's labels on top; the picture
     * grows to hold everything placed (as pcompos does) */
    if (!st) {
        int w = (int)(o.legw + pic.len), h = pic.nscans;
        if (o.legw > 0 && sh0 + bar.nscans > h) h = (int)(sh0 + bar.nscans);
        if (o.legw > 0 && slabh > h) h = (int)slabh;
        if (over) {     /* the shadow at (oxl, oyb), the text 2 left and 1 up */
            if (oxl + ow > w) w = (int)(oxl + ow);
            if (oyb + oh > h) h = (int)(oyb + oh);
            if (oyb + 1 + oh > h) h = (int)(oyb + 1 + oh);
        }
        for (int k = 0; k < 2; k++)
            if (ext[k].m) {
                if (ext[k].x + ext[k].w > w) w = (int)(ext[k].x + ext[k].w);
                if (ext[k].y + ext[k].h > h) h = (int)(ext[k].y + ext[k].h);
            }
        if (w < 3) w = 3;
        hd_rawpic out;
        st = hd_rawpic_blank(&out, HD_PIC_RGBE, w, h);
        for (int y = 0; y < h && !st; y++) {          /* y from the bottom */
            uint8_t *row = out.rgbe + (size_t)(h - 1 - y) * w * 4;
            if (o.legw > 0 && y >= sh0 && y < sh0 + bar.nscans)
                memcpy(row, bar.rgbe + (size_t)(sh0 + bar.nscans - 1 - y) * bar.len * 4, (size_t)bar.len * 4);
            if (y < pic.nscans)
                memcpy(row + 4 * o.legw, pic.rgbe + (size_t)(pic.nscans - 1 - y) * pic.len * 4, (size_t)pic.len * 4);
        }
        if (!st && o.legw > 0 && th > 0)
            st = draw_labels(&o, &out, sheight, th, top, pic.nscans);
        if (!st && over)
            for (int pass = 0; pass < 2; pass++)
                put_cover(&out, over, ow, oh, oxl - (pass ? 2 : 0), oyb + (pass ? 1 : 0), pass ? .5f : .9f, !pass, out.len, 0);
        for (int k = 0; k < 2 && !st; k++)
            if (ext[k].m) paste_text(&out, &ext[k]);
        if (!st) st = write_picture(fp, &out, argc, argv);
        free(out.rgbe);
    }
    for (int k = 0; k < 2; k++) free(ext[k].m);
    free(over);
    if (tmppic[0]) remove(tmppic);
    hd_rawpic_free(&pic);
    hd_rawpic_free(&bar);
    free(r); free(g); free(b);
    free(head); free(outs); free(inmode); free(mapdef);
    free(o.redv); free(o.grnv); free(o.bluv);
    hd_font_free(o.font);
    return st;
}

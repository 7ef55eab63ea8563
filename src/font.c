/* heliodon — Radiance polygon font files and text drawn with them
 * (heliodon/font.h).  The layout (uniform, squeezed and proportional
 * spacing) and the drawing follow Radiance's psign so that the pixels are
 * the same: glyph vertices are scaled to the subsampled bitmap with integer
 * arithmetic (v * size >> 8), every outline edge toggles one bit per
 * subsample row it crosses (walked from its lower end), and each subsample
 * row is then filled by parity from the left. */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/cal.h"
#include "heliodon/font.h"

void hd_font_free(hd_font *f)
{
    if (!f) return;
    for (int i = 0; i < 256; i++)
        if (f->g[i]) { free(f->g[i]->v); free(f->g[i]); }
    free(f->path);
    free(f);
}

/* the next integer word of the file (# comments skipped); 1 read, 0 end,
 * -1 a word that is not an integer */
static int next_int(FILE *fp, int *line, long *v)
{
    int c;
    for (;;) {
        c = getc(fp);
        if (c == '\n') (*line)++;
        else if (c == '#') {
            while ((c = getc(fp)) != EOF && c != '\n') {}
            if (c == '\n') (*line)++;
        } else if (c == EOF) return 0;
        else if (!isspace(c)) break;
    }
    char w[64];
    size_t n = 0;
    int ok = 1;
    do {
        if (n < sizeof w - 1) w[n++] = (char)c;
        else ok = 0;
    } while ((c = getc(fp)) != EOF && !isspace(c) && c != '#');
    if (c != EOF) ungetc(c, fp);
    w[n] = 0;
    char *end;
    long x = strtol(w, &end, 10);
    if (!ok || end == w || *end || !(isdigit((unsigned char)w[0]) || ((w[0] == '-' || w[0] == '+') && w[1]))) return -1;
    *v = x;
    return 1;
}

hd_status hd_font_load(const char *name, hd_font **out)
{
    *out = NULL;
    char path[4096];
    if (!hd_cal_findfile(name, path, sizeof path)) return hd_fail(HD_ERR_IO, "cannot find font file \"%s\"", name);
    FILE *fp = fopen(path, "r");
    if (!fp) return hd_fail(HD_ERR_IO, "%s: cannot open font file", path);
    hd_font *f = calloc(1, sizeof *f);
    hd_status st = f && (f->path = hd_strdup(path)) ? HD_OK : HD_ERR_NOMEM;
    int line = 1, r;
    long code, nv, x;
    unsigned wsum = 0, hsum = 0, ndrawn = 0;
    while (!st && (r = next_int(fp, &line, &code)) != 0) {
        if (r < 0) { st = hd_fail(HD_ERR_FORMAT, "%s: line %d: expected a character code (an integer)", path, line); break; }
        if (code < 1 || code > 255) { st = hd_fail(HD_ERR_FORMAT, "%s: line %d: character code %ld outside 1..255", path, line, code); break; }
        if (f->g[code]) { st = hd_fail(HD_ERR_FORMAT, "%s: line %d: character %ld defined twice", path, line, code); break; }
        if (next_int(fp, &line, &nv) != 1 || nv < 0 || nv > 32000) {
            st = hd_fail(HD_ERR_FORMAT, "%s: line %d: character %ld: expected a vertex count 0..32000", path, line, code);
            break;
        }
        hd_glyph *g = calloc(1, sizeof *g);
        if (!g || !(g->v = malloc(nv ? (size_t)nv * 2 : 1))) { free(g); st = HD_ERR_NOMEM; break; }
        f->g[code] = g;
        g->nverts = (int)nv;
        g->left = g->right = g->top = g->bottom = 128;
        for (long k = 0; k < 2 * nv; k++) {
            if (next_int(fp, &line, &x) != 1 || x < 0 || x > 255) {
                st = hd_fail(HD_ERR_FORMAT, "%s: line %d: character %ld: expected a coordinate 0..255", path, line, code);
                break;
            }
            g->v[k] = (unsigned char)x;
            if (k % 2 == 0) { if (x < g->left) g->left = (int)x; if (x > g->right) g->right = (int)x; }
            else { if (x < g->bottom) g->bottom = (int)x; if (x > g->top) g->top = (int)x; }
        }
        if (g->right > g->left && g->top > g->bottom) {
            ndrawn++;
            wsum += (unsigned)(g->right - g->left);
            hsum += (unsigned)(g->top - g->bottom);
        }
    }
    fclose(fp);
    if (!st && ndrawn) { f->mwidth = (int)(wsum / ndrawn); f->mheight = (int)(hsum / ndrawn); }
    if (st) { hd_font_free(f); return st; }
    *out = f;
    return HD_OK;
}

static const hd_glyph *glyph_of(const hd_font *f, char c) { return f->g[(unsigned char)c]; }

/* every glyph a full cell, characters without one take no room */
static int layout_uniform(const hd_font *f, const char *t, short *sp)
{
    int width = 0;
    sp[0] = 0;
    for (size_t i = 0; t[i]; i++) {
        short d = glyph_of(f, t[i]) ? 255 : 0;
        sp[i + 1] = d;
        width += d;
    }
    return width;
}

/* glyphs packed by their extents, gap cells apart (units of 1/256); blanks
 * take the font's mean width.  sp[i] collects the room before character i:
 * the previous glyph's right part and half the gap, then half the gap and
 * the part left of this glyph's extent. */
static int layout_squeeze(const hd_font *f, const char *t, int gap, short *sp)
{
    size_t n = strlen(t), i = 0;
    int width = 0, half = gap / 2;
    while (i < n && !glyph_of(f, t[i])) sp[i++] = 0;    /* leading characters without glyphs */
    sp[i] = (short)half;
    while (i < n) {
        const hd_glyph *g = glyph_of(f, t[i]);
        if (g->nverts) {
            sp[i] = (short)(sp[i] + half - g->left);
            sp[i + 1] = (short)(g->right + half);
        } else
            sp[i + 1] = (short)f->mwidth;
        width += sp[i++];
        while (i < n && !glyph_of(f, t[i])) {           /* no glyph: drawn nowhere, no room */
            width += sp[i];
            sp[++i] = 0;
        }
    }
    sp[n] = (short)(sp[n] + half);
    return width + sp[n];
}

/* squeezed, then each run of characters (a word and the blanks after it,
 * or the text up to a run of more than 3 blanks) stretched evenly to the
 * font's mean width plus the gap per character */
static int layout_prop(const hd_font *f, const char *t, int gap, short *sp)
{
    layout_squeeze(f, t, gap, sp);
    int width = sp[0];
    short *s = sp + 1;
    const char *p = t;
    while (*p) {
        int len = 0, alen = 0;
        short *ns = s;
        const char *e = p, *next = p;
        for (; *e; e = next) {
            next = e + 1;
            alen += *ns++;
            if (glyph_of(f, *e)) {
                const hd_glyph *g;
                while ((g = glyph_of(f, *next)) != NULL && g->nverts == 0) {   /* the blanks after it */
                    alen += *ns++;
                    next++;
                }
                len += (int)(next - e);
            }
            if (next - e > 3) break;
        }
        len *= f->mwidth + gap;
        width += len;
        len -= alen;
        while (s < ns) {
            int share = len / (int)(ns - s);
            *s = (short)(*s + share);
            s++;
            len -= share;
        }
        p = next;
    }
    return width;
}

int hd_font_layout(const hd_font *f, const char *text, double spacing, short *sp)
{
    if (spacing < -1. / 256.) return layout_squeeze(f, text, (int)(spacing * -256.), sp);
    if (spacing > 1. / 256.) return layout_prop(f, text, (int)(spacing * 256.), sp);
    return layout_uniform(f, text, sp);
}

int hd_font_layout_units(const hd_font *f, const char *text, int gap, short *sp)
{
    if (gap < 0) return layout_squeeze(f, text, -gap, sp);
    if (gap > 0) return layout_prop(f, text, gap, sp);
    return layout_uniform(f, text, sp);
}

int hd_glyph_inside(const hd_glyph *g, double x, double y)
{
    if (!g) return 0;
    int xi = (int)x, yi = (int)y;
    if (g->left > xi || g->right <= xi || g->bottom > yi || g->top <= yi) return 0;
    int xt = xi << 1 | 1, yt = yi << 1 | 1;     /* doubled, plus a half */
    int n = g->nverts, cross = 0;
    const unsigned char *a = g->v + 2 * (n - 1), *b = g->v;
    for (int k = 0; k < n; k++, a = b, b += 2) {
        if (((a[1] << 1) > yt) == ((b[1] << 1) > yt)) continue;    /* not across the test row */
        int right = ((a[0] << 1) > xt) | ((b[0] << 1) > xt) << 1;
        if (right == 3) cross++;
        else if (right)     /* one end on each side: which side of the edge */
            cross += (b[1] > a[1]) ^ ((a[1] - y) * (b[0] - x) > (a[0] - x) * (b[1] - y));
    }
    return cross & 1;
}

void hd_textopts_default(hd_textopts *o)
{
    memset(o, 0, sizeof *o);
    o->height = 32;
    o->aspect = 1.67;
    o->direct = 'r';
}

/* the subsampled bitmap, one byte a bit, rows of `stride` (bottom row 0) */
typedef struct bitmap {
    unsigned char *b;
    long xsiz, ysiz, stride;
    int cheight, cwidth;
    char direct;
} bitmap;

static void toggle(bitmap *m, long x, long y)
{
    if (x >= 0 && x < m->stride && y >= 0 && y < m->ysiz) m->b[y * m->stride + x] ^= 1;
}

/* font units (tx, ty) of the text to bitmap coordinates */
static void to_bitmap(const bitmap *m, long tx, long ty, long p[2])
{
    tx = tx * m->cwidth >> 8;
    ty = ty * m->cheight >> 8;
    switch (m->direct) {
    case 'u': p[0] = m->xsiz - 1 - ty; p[1] = tx; break;
    case 'l': p[0] = m->xsiz - 1 - tx; p[1] = m->ysiz - 1 - ty; break;
    case 'd': p[0] = ty; p[1] = m->ysiz - 1 - tx; break;
    default: p[0] = tx; p[1] = ty; break;
    }
}

/* one edge: one toggled bit on each row from its lower end up to (not
 * including) its upper end, x stepped towards the upper end whenever the
 * rows climbed so far (times the run) outrun the columns (times the rise) */
static void edge(bitmap *m, long x, long y, long run, long rise)
{
    if (rise == 0) return;
    if (rise < 0) { x += run; y += rise; rise = -rise; run = -run; }
    long step = run < 0 ? -1 : 1;
    if (run < 0) run = -run;
    long acc_run = 0, acc_rise = 0;
    for (long left = rise; left > 0;) {
        if (acc_rise >= acc_run) {
            toggle(m, x, y);
            y++;
            left--;
            acc_run += run;
        } else {
            x += step;
            acc_rise += rise;
        }
    }
}

static void outline(bitmap *m, const hd_glyph *g, long tx, long ty)
{
    int n = g->nverts;
    if (n == 0) return;
    long a[2], b[2];
    to_bitmap(m, g->v[2 * n - 2] + tx, g->v[2 * n - 1] + ty, a);
    for (int k = 0; k < n; k++) {
        to_bitmap(m, g->v[2 * k] + tx, g->v[2 * k + 1] + ty, b);
        edge(m, a[0], a[1], b[0] - a[0], b[1] - a[1]);
        a[0] = b[0];
        a[1] = b[1];
    }
}

hd_status hd_font_text(const hd_font *f, const char *const *lines, int nlines, const hd_textopts *o,
                       unsigned char **cover, int *w, int *h)
{
    *cover = NULL;
    *w = *h = 0;
    if (nlines < 1) return hd_fail(HD_ERR_USAGE, "no text to draw");
    if (o->height < 1 || o->height > 100000) return hd_fail(HD_ERR_RANGE, "character height %d outside 1..100000", o->height);
    short **sp = calloc((size_t)nlines, sizeof *sp);
    if (!sp) return HD_ERR_NOMEM;
    hd_status st = HD_OK;
    long maxwidth = 0;
    for (int l = 0; l < nlines && !st; l++) {
        if (!(sp[l] = hd_malloc_array(strlen(lines[l]) + 1, sizeof **sp))) { st = HD_ERR_NOMEM; break; }
        long lw = hd_font_layout(f, lines[l], o->spacing, sp[l]);
        if (lw > maxwidth) maxwidth = lw;
    }
    const int S = HD_FONT_SSS;
    bitmap m = {0};
    m.direct = o->direct;
    double aspect = o->aspect;
    long xsiz = (long)o->xres * S, ysiz = (long)o->yres * S;
    long cheight = (long)o->height * S;
    double cwidth = 0;
    int across = o->direct == 'r' || o->direct == 'l';
    if (!st && maxwidth <= 0) st = hd_fail(HD_ERR_USAGE, "the text has no characters of font %s", f->path);
    if (!st) {
        /* the picture's size and the characters' size, as psign fits them */
        long *along = across ? &xsiz : &ysiz, *side = across ? &ysiz : &xsiz;
        if (*along <= 0) {
            cwidth = (double)(long)(cheight / aspect + .5);
            *along = maxwidth * (long)cwidth >> 8;
            *side = nlines * cheight;
        } else {
            if (*side <= 0) *side = cheight * nlines;
            double pa;      /* the picture's side / along */
            if (aspect > 1e-6) {
                pa = across ? 256. * nlines * aspect / maxwidth : maxwidth / (256. * nlines * aspect);
                if (pa * xsiz < ysiz) ysiz = (long)(pa * xsiz + .5);
                else xsiz = (long)(ysiz / pa + .5);
            } else {
                pa = (double)ysiz / xsiz;
                aspect = across ? pa * maxwidth / (256. * nlines) : maxwidth / (256. * nlines * pa);
            }
            cheight = *side / nlines;
            cwidth = (double)(long)(cheight / aspect);
        }
        if (xsiz % S) xsiz += S - xsiz % S;
        if (ysiz % S) ysiz += S - ysiz % S;
        if (xsiz <= 0 || ysiz <= 0 || xsiz > 200000L * S || ysiz > 200000L * S)
            st = hd_fail(HD_ERR_RANGE, "text picture of %ld x %ld pixels", xsiz / S, ysiz / S);
    }
    if (!st) {
        m.xsiz = xsiz;
        m.ysiz = ysiz;
        m.stride = (xsiz + 7) / 8 * 8;
        m.cheight = (int)cheight;
        m.cwidth = (int)cwidth;
        if (!(m.b = hd_malloc_array((size_t)m.stride, (size_t)ysiz))) st = HD_ERR_NOMEM;
        else memset(m.b, 0, (size_t)m.stride * (size_t)ysiz);
    }
    /* the last line at the bottom, lines 256 units apart */
    for (int l = nlines - 1; l >= 0 && !st; l--) {
        long ty = 256L * (nlines - 1 - l), tx = 0;
        for (size_t i = 0; lines[l][i]; i++) {
            tx += sp[l][i];
            const hd_glyph *g = glyph_of(f, lines[l][i]);
            if (g) outline(&m, g, tx, ty);
        }
    }
    if (!st) {
        int W = (int)(xsiz / S), H = (int)(ysiz / S);
        unsigned char *c = hd_malloc_array((size_t)W, (size_t)H);
        if (!c) st = HD_ERR_NOMEM;
        for (int y = 0; y < H && !st; y++) {
            unsigned inside = 0;    /* parity of each subsample row */
            unsigned char *row = c + (size_t)(H - 1 - y) * (size_t)W;
            for (int x = 0; x < W; x++) {
                int n = 0;
                for (int j = 0; j < S; j++)
                    for (int i = 0; i < S; i++) {
                        if (m.b[(long)(y * S + j) * m.stride + x * S + i]) inside ^= 1u << j;
                        if (inside & 1u << j) n++;
                    }
                row[x] = (unsigned char)n;
            }
        }
        if (!st) { *cover = c; *w = W; *h = H; }
    }
    free(m.b);
    for (int l = 0; l < nlines; l++) free(sp[l]);
    free(sp);
    return st;
}

/* heliodon — Radiance's polygon font files (.fnt, e.g. helvet.fnt) and text
 * drawn with them as Radiance's psign draws it.
 *
 * A font file is a list of integers (# starts a comment to the end of the
 * line): for each glyph its character code (1..255), its vertex count n
 * (0 for a blank such as the space) and n vertices x y, each coordinate in
 * 0..255 (a cell 256 units wide and high, y up).  A glyph is one closed
 * outline; its holes and pieces are joined into it by zero-width cuts, so
 * that even-odd filling of the outline gives the character.  The fonts are
 * found through RAYPATH, as Radiance finds them; heliodon ships none. */
#ifndef HD_FONT_H
#define HD_FONT_H
#include "heliodon/common.h"

typedef struct hd_glyph {
    int nverts;
    int left, right, top, bottom;   /* extent, each bound widened to include 128 */
    unsigned char *v;               /* x0 y0 x1 y1 ... */
} hd_glyph;

typedef struct hd_font {
    char *path;
    int mwidth, mheight;            /* mean width and height of the drawn glyphs */
    hd_glyph *g[256];               /* NULL: no glyph for that code */
} hd_font;

/* Load font file NAME (a path with '/', or found through RAYPATH like a
 * .cal file).  Not found: HD_ERR_IO "cannot find font file"; errors in the
 * file name it, the line and what was expected. */
hd_status hd_font_load(const char *name, hd_font **out);
void hd_font_free(hd_font *f);

/* Character offsets of a line of text in font units (256 a cell), as
 * Radiance lays text out: sp[i] is added before character i is drawn
 * (sp has strlen(text) + 1 entries; the last is the trailing space).
 * spacing < 0: squeezed to the glyphs' extents plus -spacing cells between
 * them; > 0: proportional with about `spacing` cells between glyphs; 0:
 * every glyph one full cell.  Returns the line's width. */
int hd_font_layout(const hd_font *f, const char *text, double spacing, short *sp);
/* The same with the gap in font units (Radiance's text patterns give it
 * as spacing * 255): < 0 squeezed by -gap, > 0 proportional, 0 uniform. */
int hd_font_layout_units(const hd_font *f, const char *text, int gap, short *sp);

/* Whether (x, y), in a glyph's cell units (0..255, y up), is inside glyph
 * g (NULL: no), by Radiance's crossing test on the outline (test points
 * at half units, so that no vertex is met exactly). */
int hd_glyph_inside(const hd_glyph *g, double x, double y);

/* Subsamples per pixel side in hd_font_text's coverage */
#define HD_FONT_SSS 3

typedef struct hd_textopts {
    int height;         /* character height in pixels (psign -h; default 32) */
    double aspect;      /* character height / width (psign -a; default 1.67) */
    double spacing;     /* psign -s (default 0) */
    char direct;        /* 'r' (default), 'u', 'l', 'd': reading direction */
    int xres, yres;     /* psign -x, -y: picture size, 0 = from the text */
} hd_textopts;
void hd_textopts_default(hd_textopts *o);

/* TEXT's lines (nlines, first at the top) drawn as psign draws them: each
 * pixel is HD_FONT_SSS x HD_FONT_SSS subsamples, glyph outlines are filled
 * even-odd along each subsample row.  *cover gets w x h counts of covered
 * subsamples (0 .. HD_FONT_SSS^2), row 0 at the top (free() it). */
hd_status hd_font_text(const hd_font *f, const char *const *lines, int nlines, const hd_textopts *o,
                       unsigned char **cover, int *w, int *h);
#endif

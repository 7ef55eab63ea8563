/* psign — a picture of text drawn with a Radiance font file, as Radiance's
 * psign (docs/man/psign.1); the font and the drawing are in src/font.c. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/font.h"
#include "heliodon/header.h"
#include "heliodon/pictools.h"
#include "heliodon/picture.h"

#define USAGE "usage: psign [-cf r g b][-cb r g b][-f font][-dr|-du|-dl|-dd][-x xres][-y yres][-h height][-a aspect][-s spacing] [text ...]"

static double num(int argc, char **argv, int i)
{
    if (i >= argc) hd_die_msg("option %s needs a value\n%s", argv[i - 1], USAGE);
    char *end;
    double v = strtod(argv[i], &end);
    if (end == argv[i] || *end) hd_die_msg("%s: expected a number after %s", argv[i], argv[i - 1]);
    return v;
}

/* the lines of standard input (without their newlines) */
static char **read_lines(int *n)
{
    char **l = NULL, *buf = NULL;
    size_t cap = 0;
    ssize_t len;
    *n = 0;
    while ((len = getline(&buf, &cap, stdin)) >= 0) {
        if (len > 0 && buf[len - 1] == '\n') buf[--len] = 0;
        char **nl = realloc(l, (size_t)(*n + 1) * sizeof *l);
        if (!nl || !(nl[*n] = hd_strdup(buf))) hd_die_msg("out of memory reading the text");
        l = nl;
        (*n)++;
    }
    free(buf);
    return l;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    float fg[3] = {0, 0, 0}, bg[3] = {1, 1, 1};
    const char *fontname = "helvet.fnt";
    hd_textopts to;
    hd_textopts_default(&to);
    int i;
    for (i = 1; i < argc && argv[i][0] == '-'; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "-cf") || !strcmp(a, "-cb")) {
            float *c = a[2] == 'f' ? fg : bg;
            for (int k = 0; k < 3; k++) c[k] = (float)num(argc, argv, ++i);
        } else if (!strcmp(a, "-f")) {
            if (++i >= argc) hd_die_msg("option -f needs a font file\n%s", USAGE);
            fontname = argv[i];
        } else if (a[1] == 'd' && a[2] && strchr("rlud", a[2]) && !a[3]) to.direct = a[2];
        else if (!strcmp(a, "-x")) to.xres = (int)num(argc, argv, ++i);
        else if (!strcmp(a, "-y")) to.yres = (int)num(argc, argv, ++i);
        else if (!strcmp(a, "-h")) to.height = (int)num(argc, argv, ++i);
        else if (!strcmp(a, "-a")) to.aspect = num(argc, argv, ++i);
        else if (!strcmp(a, "-s")) to.spacing = num(argc, argv, ++i);
        else hd_die_msg("unknown option: %s\n%s", a, USAGE);
    }
    hd_font *font;
    if (hd_font_load(fontname, &font)) hd_die();
    /* the text: the remaining words joined by blanks, or standard input */
    char **lines, *joined = NULL;
    int nlines;
    if (i < argc) {
        size_t L = 1;
        for (int k = i; k < argc; k++) L += strlen(argv[k]) + 1;
        if (!(joined = malloc(L))) hd_die_msg("out of memory");
        joined[0] = 0;
        for (int k = i; k < argc; k++) {
            if (k > i) strcat(joined, " ");
            strcat(joined, argv[k]);
        }
        lines = &joined;
        nlines = 1;
    } else
        lines = read_lines(&nlines);
    unsigned char *cover;
    int w, h;
    if (hd_font_text(font, (const char *const *)lines, nlines, &to, &cover, &w, &h)) hd_die();
    /* the colour of each coverage count: fg * d + bg * (1 - d) */
    enum { NS = HD_FONT_SSS * HD_FONT_SSS };
    uint8_t val[NS + 1][4];
    for (int k = 0; k <= NS; k++) {
        double d = (double)k / NS;
        float c[3];
        for (int j = 0; j < 3; j++) c[j] = (float)(fg[j] * d) + (float)(bg[j] * (1 - d));
        hd_rgbe_encode(val[k], c[0], c[1], c[2]);
    }
    hd_rawpic p;
    if (hd_rawpic_blank(&p, HD_PIC_RGBE, w, h)) hd_die();
    for (size_t k = 0; k < (size_t)w * (size_t)h; k++) memcpy(p.rgbe + 4 * k, val[cover[k]], 4);
    if (hd_header_add_command(&p.hdr, argc, argv) || hd_rawpic_save(NULL, &p)) hd_die();
    hd_rawpic_free(&p);
    free(cover);
    hd_font_free(font);
    if (joined) free(joined);
    else {
        for (int k = 0; k < nlines; k++) free(lines[k]);
        free(lines);
    }
    return 0;
}

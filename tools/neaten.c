/* neaten — align white-space separated columns (Radiance's neaten).
 * The format "L.R" (default 8.8): each field takes L characters left of
 * the alignment character ('.' here, any non-digit in general), the
 * character itself and R characters right of it; a field without the
 * alignment character ends where the character would be; a field too wide
 * is printed whole (that row is then out of line). */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    const char *fmt = argc > 1 ? argv[1] : "8.8";
    if (argc > 2 || !isdigit((unsigned char)fmt[0])) {
        fprintf(stderr, "Usage: %s [format]\n", argv[0]);
        return 1;
    }
    char *e;
    long left = strtol(fmt, &e, 10);
    char align = *e ? *e : '.';
    long right = *e ? atol(e + 1) : 0;
    if (left < 0 || right < 0 || left > 1000 || right > 1000) {
        fprintf(stderr, "%s: bad format '%s'\n", argv[0], fmt);
        return 1;
    }
    char *line = NULL;
    size_t cap = 0;
    while (getline(&line, &cap, stdin) >= 0) {
        char *p = line;
        for (;;) {
            while (isspace((unsigned char)*p)) p++;
            if (!*p) break;
            char *w = p;
            while (*p && !isspace((unsigned char)*p)) p++;
            int len = (int)(p - w);
            char *dot = memchr(w, align, (size_t)len);
            int lpart = dot ? (int)(dot - w) : len;
            int rpart = len - lpart;                /* the character and what follows */
            for (long k = lpart; k < left; k++) putchar(' ');
            fwrite(w, 1, (size_t)len, stdout);
            for (long k = rpart; k < right + 1; k++) putchar(' ');
        }
        putchar('\n');
    }
    free(line);
    return fflush(stdout) ? 1 : 0;
}

/* histo — histogram of each input column (Radiance's histo).
 *   histo [-c][-p] min max n     n equal bins on [min,max)
 *   histo [-c][-p] imin imax     one bin per integer imin..imax
 * Output: bin centre (or, -c, the lower bound of the cumulative count)
 * then a count per column; -p gives percentages of all values of the
 * column (those outside the range included). */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "heliodon/common.h"

#define MAXCOL 2048
#define MAXDIV 1024

static long (*hist)[MAXDIV];
static long below[MAXCOL], above[MAXCOL], ctotal[MAXCOL];
static int ncols, ndiv;
static double minv, maxv;

static int isint(double x) { return floor(x + 1e-6) != floor(x - 1e-6); }

static _Noreturn void usage(const char *prog)
{
    fprintf(stderr, "Usage: %s [-c][-p] min max n\n", prog);
    fprintf(stderr, "   Or: %s [-c][-p] imin imax\n", prog);
    exit(1);
}

int main(int argc, char **argv)
{
    const char *prog = argv[0];
    hd_set_progname(prog);
    int cumulative = 0, percent = 0, a = 1;
    for (; a < argc && argv[a][0] == '-'; a++) {
        if (argv[a][1] == 'c') cumulative = 1;
        else if (argv[a][1] == 'p') percent = 1;
        else break;
    }
    int nargs = argc - a;
    if (nargs < 2 || nargs > 3) usage(prog);
    minv = atof(argv[a]);
    maxv = atof(argv[a + 1]);
    if (nargs == 3) {
        ndiv = atoi(argv[a + 2]);
    } else {
        if (!isint(minv) || !isint(maxv)) usage(prog);
        minv -= 0.5;
        maxv += 0.5;
        ndiv = (int)(maxv - minv + 0.5);
    }
    if (!(minv < maxv) || ndiv <= 0) usage(prog);
    if (ndiv > MAXDIV) {
        fprintf(stderr, "%s: maximum number of divisions: %d\n", prog, MAXDIV);
        usage(prog);
    }
    hist = hd_calloc(MAXCOL, sizeof *hist);
    if (!hist) hd_die();
    char *line = NULL;
    size_t cap = 0;
    while (getline(&line, &cap, stdin) >= 0) {
        const char *cp = line;
        int c;
        for (c = 0; c < MAXCOL; c++) {
            while (isspace((unsigned char)*cp)) cp++;
            if (!*cp) break;
            double d = atof(cp);
            while (*cp && !isspace((unsigned char)*cp)) cp++;
            if (d < minv) below[c]++;
            else if (d >= maxv) above[c]++;
            else {
                int i = (int)(ndiv * (d - minv) / (maxv - minv));
                hist[c][i < ndiv ? i : ndiv - 1]++;
            }
        }
        if (c > ncols) ncols = c;
    }
    free(line);
    for (int c = 0; c < ncols; c++) {
        ctotal[c] = below[c] + above[c];
        for (int i = 0; i < ndiv; i++) ctotal[c] += hist[c][i];
    }
    if (cumulative) {
        long *sum = hd_calloc((size_t)ncols + 1, sizeof *sum);
        if (!sum) hd_die();
        for (int c = 0; c < ncols; c++) sum[c] = below[c];
        for (int i = 0; i <= ndiv; i++) {
            printf("%g", minv + (maxv - minv) * i / ndiv);
            for (int c = 0; c < ncols; c++) {
                if (percent) printf("\t%f", 100. * sum[c] / ctotal[c]);
                else printf("\t%ld", sum[c]);
                if (i < ndiv) sum[c] += hist[c][i];
            }
            putchar('\n');
        }
        free(sum);
    } else {
        for (int i = 0; i < ndiv; i++) {
            printf("%g", minv + (maxv - minv) * (i + .5) / ndiv);
            for (int c = 0; c < ncols; c++) {
                if (percent) printf("\t%f", 100. * hist[c][i] / ctotal[c]);
                else printf("\t%ld", hist[c][i]);
            }
            putchar('\n');
        }
    }
    free(hist);
    return fflush(stdout) ? 1 : 0;
}

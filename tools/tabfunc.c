/* tabfunc — turn a table (first column x, then one column per function)
 * into .cal functions of x (Radiance's tabfunc; docs/man/tabfunc.1).
 *
 * Without -i a function returns the tabulated value at the nearest table
 * index (select() rounds); with -i it interpolates linearly between rows
 * and holds the end values outside.  Evenly spaced x becomes an index
 * expression ("x", "x-a", "(x-a)/s+1"); otherwise helper functions named
 * with the suffix `p<process id> find the fractional index. */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "heliodon/common.h"

#define MAXROWS 8192
#define MAXLINE 16384

static const char *prog;
static int nfunc, nrows;
static double *xs, *ys;         /* ys[f * MAXROWS + row] */

static _Noreturn void fatal(int line, const char *what)
{
    fprintf(stderr, "%s: input line %d: %s\n", prog, line, what);
    exit(1);
}

static int isdelim(int c) { return isspace(c) || c == ','; }

/* parse a number at p: its end, or NULL when there is none */
static const char *number(const char *p, double *v)
{
    while (isspace((unsigned char)*p)) p++;
    char *e;
    *v = strtod(p, &e);
    if (e == p || (!isdigit((unsigned char)e[-1]) && e[-1] != '.')) return NULL;
    return e;
}

static void load(FILE *fp)
{
    char *buf = hd_malloc(MAXLINE);
    if (!buf) hd_die();
    int line = 0;
    while (fgets(buf, MAXLINE, fp)) {
        line++;
        size_t len = strlen(buf);
        if (len == MAXLINE - 1 && buf[len - 1] != '\n') fatal(line, "line too long");
        if (nrows >= MAXROWS - 1) fatal(line, "too many rows");
        double v;
        const char *p = number(buf, &v);
        if (!p) continue;                       /* not a data line */
        xs[nrows] = v;
        for (int f = 0; f < nfunc; f++) {
            while (isdelim((unsigned char)*p)) p++;
            if (!*p) fatal(line, "too few columns");
            p = number(p, &ys[(size_t)f * MAXROWS + (size_t)nrows]);
            if (!p || !(isdelim((unsigned char)*p) || !*p)) fatal(line, "bad floating-point format");
        }
        nrows++;
    }
    free(buf);
}

/* comma-separated values, a new line before the text would pass column 64 */
static void values(const double *v, int n, int col)
{
    for (int i = 0; i < n; i++) {
        char b[40];
        int len = snprintf(b, sizeof b, "%.7g", v[i]);
        col += len + 1;
        if (col >= 64) {
            putchar('\n');
            col = len + 1;
        }
        fputs(b, stdout);
        if (i + 1 < n) putchar(',');
    }
}

/* the expression giving the table index (1 .. nrows) of x */
static void index_expr(char *out, size_t cap, const char *id)
{
    if (nrows < 2) {
        snprintf(out, cap, "1");
        return;
    }
    double step = xs[1] - xs[0];
    int up = step > 0;
    double eps = (up ? 1e-3 : -1e-3) * step;
    int even = 1;
    for (int i = 2; i < nrows; i++) {
        if (even && fabs(xs[i] - xs[i - 1] - step) > eps) even = 0;
        if (!even && (xs[i - 1] < xs[i]) != up) {
            fprintf(stderr, "%s: input not a function\n", prog);
            exit(1);
        }
    }
    if (even) {
        if (up && fabs(step - 1) < eps) {
            if (fabs(xs[0] - 1) < eps) snprintf(out, cap, "x");
            else snprintf(out, cap, "x-%g", xs[0] - 1);
        } else if (fabs(xs[0]) < eps) {
            snprintf(out, cap, "x/%g+1", step);
        } else {
            snprintf(out, cap, "(x-%g)/%g+1", xs[0], step);
        }
        return;
    }
    /* uneven: X(i) holds the abscissae; fx2 walks down from the last row
     * to the interval holding x and returns the fractional index */
    printf("X`%s(i):select(i,", id);
    values(xs, nrows, 20);
    puts(");");
    printf(up ? "fx2`%s(x,i):if(x-X`%s(i),\n" : "fx2`%s(x,i):if(X`%s(i)-x,\n", id, id);
    printf("\ti+(x-X`%s(i))/(X`%s(i+1)-X`%s(i)),\n", id, id, id);
    printf("\tfx2`%s(x,i-1));\n", id);
    printf(up ? "fx`%s(x):if(x-%g,if(%g-x,fx2`%s(x,%d),%d),1);\n"
              : "fx`%s(x):if(%g-x,if(x-%g,fx2`%s(x,%d),%d),1);\n",
           id, xs[0], xs[nrows - 1], id, nrows, nrows);
    snprintf(out, cap, "fx`%s(x)", id);
}

int main(int argc, char **argv)
{
    prog = argv[0];
    hd_set_progname(argv[0]);
    int interp = 0, a = 1;
    if (a < argc && !strcmp(argv[a], "-i")) {
        interp = 1;
        a++;
    }
    if (a >= argc || argv[a][0] == '-') {
        fprintf(stderr, "Usage: %s [-i] func1 [func2 ..]\n", prog);
        return 1;
    }
    nfunc = argc - a;
    xs = hd_malloc_array(MAXROWS, sizeof *xs);
    ys = hd_malloc_array((size_t)nfunc * MAXROWS, sizeof *ys);
    if (!xs || !ys) hd_die();
    char id[32];
    snprintf(id, sizeof id, "p%ld", (long)getpid());
    if (interp) {
        /* tf_at`(x,f): linear interpolation of the list f (f(0) = its
         * length) at the fractional index x, already within 1 .. f(0) */
        puts("tf_seg`(i,x,f):f(i)+(x-i)*(f(i+1)-f(i));");
        puts("tf_at`(x,f):tf_seg`(max(1,min(floor(x),f(0)-1)),x,f);");
    }
    load(stdin);
    char xe[128];
    index_expr(xe, sizeof xe, id);
    for (int f = 0; f < nfunc; f++) {
        const char *name = argv[a + f];
        if (!name[0] || name[0] == '0') continue;       /* a skipped column */
        const double *v = ys + (size_t)f * MAXROWS;
        if (interp) {
            printf("%s`%s(i):select(i,", name, id);
            values(v, nrows, 27 + (int)strlen(name));
            puts(");");
            printf("%s(x):tf_at`(max(1,min(%s,%s`%s(0))),%s`%s);\n", name, xe, name, id, name, id);
        } else {
            printf("%s(x):select(%s,", name, xe);
            values(v, nrows, (int)(strlen(name) + strlen(xe) + 12));
            puts(");");
        }
    }
    free(xs);
    free(ys);
    return fflush(stdout) ? 1 : 0;
}

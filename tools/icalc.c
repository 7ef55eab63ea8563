/* icalc — calculator reading definitions and expressions from standard
 * input (Radiance's icalc; docs/man/icalc.1).  Each expression line prints
 * "$N=value"; $N in later lines is that result ('$' alone: the previous
 * one).  A line with '=' or ':' is a definition ("name=" / "name:" alone
 * remove definitions, "*=" / "*:" all of them); "? [name]" prints
 * definitions, "> file" writes them, "< file" loads a file, "[ ctx" and "]"
 * push and pop a context.  Errors are reported and the next line is read. */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/cal.h"
#include "cal_internal.h"

#define MAXRES 100

static double result[MAXRES];
static int nres;

static double chan(hd_calrun *r, void *u, int n)
{
    (void)r; (void)u;
    if (n == 0) n = nres;
    if (n < 1 || n > nres || nres - n >= MAXRES) {
        fprintf(stderr, "$%d: illegal result\n", n);
        return 0.0;
    }
    return result[(n - 1) % MAXRES];
}

static const char *arg(const char *p)
{
    while (isspace((unsigned char)*p)) p++;
    return p;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    hd_cal *c = hd_cal_new();
    if (!c) hd_die();
    hd_cal_rconst(c, 0);            /* definitions are kept as written */
    hd_cal_nooutchan(c, 1);
    if (hd_cal_set(c, "PI", 3.14159265358979323846, 1)) hd_die();
    for (int i = 1; i < argc; i++)
        if (hd_cal_load(c, argv[i])) {
            fprintf(stderr, "%s\n", hd_errmsg());
            return 1;
        }
    hd_calrun *run = hd_calrun_new(c, NULL);
    if (!run) hd_die();
    hd_calrun_set_chan(run, chan, NULL);
    char ctx[256] = "";             /* context path, innermost first */

    char *line = NULL, *expr = NULL;
    size_t cap = 0, elen = 0;
    ssize_t n;
    while ((n = getline(&line, &cap, stdin)) >= 0) {
        if (n > 0 && line[n - 1] == '\n') line[--n] = 0;
        char *ne = realloc(expr, elen + (size_t)n + 2);
        if (!ne) hd_die_msg("out of memory");
        expr = ne;
        memcpy(expr + elen, line, (size_t)n + 1);
        elen += (size_t)n;
        if (elen && expr[elen - 1] == '\\') {   /* continued on the next line */
            expr[elen - 1] = ' ';
            continue;
        }
        while (elen && isspace((unsigned char)expr[elen - 1])) expr[--elen] = 0;
        elen = 0;
        const char *p;
        switch (expr[0]) {
        case 0:
            continue;
        case '?':
            p = arg(expr + 1);
            if (ctx[0]) printf("context is: `%s\n", ctx);
            if (hd_cal_print(c, *p ? p : NULL, stdout)) fprintf(stderr, "%s: undefined\n", p);
            fflush(stdout);
            continue;
        case '>': {
            p = arg(expr + 1);
            if (!*p) { fputs("file name required\n", stderr); continue; }
            FILE *fp = fopen(p, "w");
            if (!fp) { fprintf(stderr, "%s: cannot open\n", p); continue; }
            hd_cal_print(c, NULL, fp);
            if (fclose(fp)) fprintf(stderr, "%s: write error\n", p);
            continue;
        }
        case '<':
            p = arg(expr + 1);
            if (!*p) { fputs("file name required\n", stderr); continue; }
            if (hd_cal_load(c, p)) fprintf(stderr, "%s\n", hd_errmsg());
            hd_calrun_next(run);
            continue;
        case '[': {
            p = arg(expr + 1);
            if (!isalpha((unsigned char)*p)) { fputs("context name required\n", stderr); continue; }
            char nc[256];
            size_t k = 0;
            for (; *p && k + 1 < sizeof nc; p++)        /* non-name characters become '_' */
                nc[k++] = isalnum((unsigned char)*p) || *p == '_' || *p == '.' ? *p : '_';
            nc[k] = 0;
            char path[256];
            snprintf(path, sizeof path, ctx[0] ? "%s`%s" : "%s", nc, ctx);
            if (hd_cal_set_context(c, path)) { fprintf(stderr, "%s\n", hd_errmsg()); continue; }
            hd_strlcpy(ctx, path, sizeof ctx);
            printf("context now: `%s\n", ctx);
            fflush(stdout);
            continue;
        }
        case ']': {
            char *b = strchr(ctx, '`');
            if (b) memmove(ctx, b + 1, strlen(b + 1) + 1);
            else ctx[0] = 0;
            hd_cal_set_context(c, ctx);
            if (ctx[0]) printf("context now: `%s\n", ctx);
            else printf("at global context\n");
            fflush(stdout);
            continue;
        }
        }
        char *eq = strchr(expr, '=');
        if (!eq) eq = strchr(expr, ':');
        if (eq) {
            if (eq[1]) {
                if (hd_cal_parse(c, expr, NULL)) fprintf(stderr, "%s\n", hd_errmsg());
            } else {
                int all = *eq == ':';
                *eq = 0;
                const char *nm = arg(expr);
                char *e = expr + strlen(expr);
                while (e > nm && isspace((unsigned char)e[-1])) *--e = 0;
                hd_cal_undefine(c, strcmp(nm, "*") ? nm : NULL, all);
            }
            hd_calrun_next(run);
            continue;
        }
        int id;
        if (hd_cal_expr(c, expr, NULL, &id)) {
            fprintf(stderr, "%s\n", hd_errmsg());
            continue;
        }
        double v = hd_calrun_expr(run, id);
        if (hd_calrun_status(run)) {
            fflush(stdout);
            fprintf(stderr, "%s\n", hd_errmsg());
            hd_calrun_clear(run);
            continue;
        }
        result[nres % MAXRES] = v;
        nres++;
        printf("$%d=%.9g\n", nres, v);
        fflush(stdout);
    }
    free(line);
    free(expr);
    hd_calrun_free(run);
    hd_cal_free(c);
    return fflush(stdout) ? 1 : 0;
}

/* heliodon — Radiance-style option parsing with @file expansion. */
#include "heliodon/options.h"
#include "heliodon/io.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct argstore {
    char **owned;
    size_t nowned, cap;
    char **vec;
} argstore;

static int own(argstore *st, char *s)
{
    if (HD_GROW(st->owned, st->nowned + 1, st->cap, 16)) return -1;
    st->owned[st->nowned++] = s;
    return 0;
}

typedef struct wordvec { char **w; size_t n, cap; } wordvec;

static int push(wordvec *v, char *s)
{
    if (HD_GROW(v->w, v->n + 1, v->cap, 32)) return -1;
    v->w[v->n++] = s;
    return 0;
}

static hd_status expand_file(const char *path, wordvec *out, argstore *st, int depth)
{
    if (depth > 8) return hd_fail(HD_ERR_USAGE, "%s: @file options nested too deeply", path);
    hd_istream *s;
    hd_status rc = hd_istream_open(&s, path);
    if (rc) return rc;
    char word[8192];
    int c = hd_istream_getc(s);
    for (;;) {
        while (c != EOF && isspace(c)) c = hd_istream_getc(s);
        if (c == EOF) break;
        if (c == '#') { /* comment to end of line */
            while (c != EOF && c != '\n') c = hd_istream_getc(s);
            continue;
        }
        size_t n = 0;
        unsigned long line = hd_istream_lineno(s);
        while (c != EOF && !isspace(c)) {
            if (c == '"' || c == '\'') {
                int q = c;
                c = hd_istream_getc(s);
                while (c != EOF && c != q) {
                    if (n + 1 < sizeof word) word[n++] = (char)c;
                    c = hd_istream_getc(s);
                }
                if (c == EOF) {
                    hd_istream_close(s);
                    return hd_fail(HD_ERR_USAGE, "%s: line %lu: unterminated quote in option file", path, line);
                }
                c = hd_istream_getc(s);
                continue;
            }
            if (n + 1 < sizeof word) word[n++] = (char)c;
            c = hd_istream_getc(s);
        }
        word[n] = 0;
        if (word[0] == '@' && word[1]) {
            rc = expand_file(word + 1, out, st, depth + 1);
            if (rc) { hd_istream_close(s); return rc; }
            continue;
        }
        char *w = hd_strdup(word);
        if (!w || own(st, w) || push(out, w)) { hd_istream_close(s); return HD_ERR_NOMEM; }
    }
    return hd_istream_close(s);
}

void hd_expand_args_free(void *storage)
{
    argstore *st = storage;
    if (!st) return;
    for (size_t k = 0; k < st->nowned; k++) free(st->owned[k]);
    free(st->owned);
    free(st->vec);
    free(st);
}

hd_status hd_expand_args(int argc, char **argv, int *nargc, char ***nargv, void **storage)
{
    argstore *st = hd_calloc(1, sizeof *st);
    if (!st) return HD_ERR_NOMEM;
    wordvec v = {0};
    hd_status rc = HD_OK;
    for (int i = 0; i < argc && !rc; i++) {
        if (i > 0 && argv[i][0] == '@' && argv[i][1]) rc = expand_file(argv[i] + 1, &v, st, 0);
        else if (push(&v, argv[i])) rc = HD_ERR_NOMEM;
    }
    if (!rc && push(&v, NULL)) rc = HD_ERR_NOMEM;
    if (rc) {
        st->vec = v.w;
        hd_expand_args_free(st);
        return rc;
    }
    st->vec = v.w;
    *nargc = (int)v.n - 1;
    *nargv = v.w;
    *storage = st;
    return HD_OK;
}

int hd_opt_toggle_value(const char *word, int current)
{
    size_t n = strlen(word);
    if (word[0] == '+') return 1;
    if (n > 2 && word[n - 1] == '+') return 1;
    if (n > 2 && word[n - 1] == '-') return 0;
    return !current;
}

static const hd_opt *lookup(const hd_opt *table, const char *body);

/* Search the nested tables of table (HD_OPT_TABLE entries). */
static const hd_opt *lookup_nested(const hd_opt *table, const char *body)
{
    for (const hd_opt *o = table; o->name; o++)
        if (o->kind == HD_OPT_TABLE) {
            const hd_opt *f = lookup((const hd_opt *)o->dest, body);
            if (f) return f;
        }
    return NULL;
}

static const hd_opt *lookup(const hd_opt *table, const char *body)
{
    for (const hd_opt *o = table; o->name; o++)
        if (o->kind != HD_OPT_TABLE && !strcmp(o->name, body)) return o;
    size_t bl = strlen(body);
    if (bl > 1 && (body[bl - 1] == '+' || body[bl - 1] == '-'))
        for (const hd_opt *o = table; o->name; o++)
            if ((o->kind == HD_OPT_TOGGLE) && strlen(o->name) == bl - 1 && !strncmp(o->name, body, bl - 1))
                return o;
    const hd_opt *best = NULL;
    for (const hd_opt *o = table; o->name; o++)
        if (o->kind != HD_OPT_TABLE && o->prefix && !strncmp(o->name, body, strlen(o->name)) &&
            (!best || strlen(o->name) > strlen(best->name)))
            best = o;
    return best ? best : lookup_nested(table, body);
}

static hd_status need(int argc, char **argv, int i, int k, const hd_opt *o)
{
    if (i + k >= argc)
        return hd_fail(HD_ERR_USAGE, "option %s expects %s", argv[i], o->args ? o->args : "a value");
    return HD_OK;
}

int hd_opt_parse_one(const hd_opt *table, int argc, char **argv, int i)
{
    hd_status rc;
    const char *a = argv[i];
    const hd_opt *o = lookup(table, a + 1);
    if (!o) return 0;
    if (a[0] == '+' && o->kind != HD_OPT_TOGGLE && o->kind != HD_OPT_FUNC) {
        hd_fail(HD_ERR_USAGE, "option %s cannot be given with '+'", a);
        return -1;
    }
    int used = 0;
    switch (o->kind) {
    case HD_OPT_TOGGLE:
        *(int *)o->dest = hd_opt_toggle_value(a, *(int *)o->dest);
        break;
    case HD_OPT_INT:
    case HD_OPT_LONG: {
        if ((rc = need(argc, argv, i, 1, o))) return -1;
        long v;
        if (hd_parse_long(argv[i + 1], &v)) {
            hd_fail(HD_ERR_USAGE, "option %s: expected an integer, found \"%s\"", a, argv[i + 1]);
            return -1;
        }
        if (o->kind == HD_OPT_INT) {
            if (v < -2147483647L || v > 2147483647L) {
                hd_fail(HD_ERR_USAGE, "option %s: value %s out of range", a, argv[i + 1]);
                return -1;
            }
            *(int *)o->dest = (int)v;
        } else {
            *(long *)o->dest = v;
        }
        used = 1;
        break;
    }
    case HD_OPT_COUNT:
        if ((rc = need(argc, argv, i, 1, o))) return -1;
        if (hd_parse_count(argv[i + 1], (uint64_t *)o->dest)) {
            hd_fail(HD_ERR_USAGE, "option %s: expected a count (e.g. 500, 20k, 10m, 1g), found \"%s\"", a,
                    argv[i + 1]);
            return -1;
        }
        used = 1;
        break;
    case HD_OPT_REAL:
        if ((rc = need(argc, argv, i, 1, o))) return -1;
        if (hd_parse_double(argv[i + 1], (double *)o->dest)) {
            hd_fail(HD_ERR_USAGE, "option %s: expected a number, found \"%s\"", a, argv[i + 1]);
            return -1;
        }
        used = 1;
        break;
    case HD_OPT_REAL3:
        if ((rc = need(argc, argv, i, 3, o))) return -1;
        for (int k = 0; k < 3; k++)
            if (hd_parse_double(argv[i + 1 + k], (double *)o->dest + k)) {
                hd_fail(HD_ERR_USAGE, "option %s: expected 3 numbers, found \"%s\"", a, argv[i + 1 + k]);
                return -1;
            }
        used = 3;
        break;
    case HD_OPT_STRING:
        if (o->prefix && strcmp(a + 1, o->name)) { /* value inside the word: "-faf" */
            *(const char **)o->dest = argv[i];
            break;
        }
        if ((rc = need(argc, argv, i, 1, o))) return -1;
        *(const char **)o->dest = argv[i + 1];
        used = 1;
        break;
    case HD_OPT_TABLE: /* never returned by lookup */
        hd_fail(HD_ERR_INTERNAL, "option table entry matched as an option");
        return -1;
    case HD_OPT_FUNC:
        used = o->func(o, argc, argv, i, o->dest);
        if (used < 0) return -1;
        if (i + used >= argc + 1) {
            hd_fail(HD_ERR_USAGE, "option %s: missing arguments", a);
            return -1;
        }
        break;
    }
    return 1 + used;
}

hd_status hd_opt_parse_args(int argc, char **argv, const hd_opt *table, int *first)
{
    int i = 1;
    while (i < argc) {
        const char *a = argv[i];
        if (!strcmp(a, "--")) { i++; break; }
        if ((a[0] != '-' && a[0] != '+') || a[1] == 0) break;
        int n = hd_opt_parse_one(table, argc, argv, i);
        if (n == 0) return hd_fail(HD_ERR_USAGE, "unknown option %s", a);
        if (n < 0) return HD_ERR_USAGE;
        i += n;
    }
    *first = i;
    return HD_OK;
}

hd_status hd_opt_parse(hd_optparse *p, int argc, char **argv, const hd_opt *table)
{
    memset(p, 0, sizeof *p);
    hd_status rc = hd_expand_args(argc, argv, &p->argc, &p->argv, &p->storage);
    if (rc) return rc == HD_ERR_NOMEM ? rc : HD_ERR_USAGE;
    return hd_opt_parse_args(p->argc, p->argv, table, &p->first);
}

void hd_optparse_free(hd_optparse *p)
{
    hd_expand_args_free(p->storage);
    memset(p, 0, sizeof *p);
}

static void usage_rows(const hd_opt *table)
{
    for (const hd_opt *o = table; o->name; o++) {
        if (o->kind == HD_OPT_TABLE) {
            usage_rows((const hd_opt *)o->dest);
            continue;
        }
        char left[64];
        const char *pre = o->kind == HD_OPT_TOGGLE ? "[+-]" : "-";
        snprintf(left, sizeof left, "%s%s%s%s%s", pre, o->name, o->prefix ? "*" : "", o->args ? " " : "",
                 o->args ? o->args : "");
        fprintf(stderr, "  %-22s %s\n", left, o->help ? o->help : "");
    }
}

void hd_opt_usage(const hd_opt *table, const char *synopsis)
{
    fprintf(stderr, "usage: %s %s\n", hd_progname(), synopsis ? synopsis : "[options]");
    if (!table || !table->name) return;
    fprintf(stderr, "options:\n");
    usage_rows(table);
}

void hd_opt_parse_or_exit(hd_optparse *p, int argc, char **argv, const hd_opt *table, const char *synopsis)
{
    hd_set_progname(argv[0]);
    if (argc > 1 && (!strcmp(argv[1], "-version") || !strcmp(argv[1], "--version"))) {
        printf("%s (%s)\n", hd_progname(), HD_SOFTWARE);
        exit(0);
    }
    if (argc > 1 && (!strcmp(argv[1], "-help") || !strcmp(argv[1], "--help"))) {
        hd_opt_usage(table, synopsis);
        exit(0);
    }
    hd_status rc = hd_opt_parse(p, argc, argv, table);
    if (rc) {
        fprintf(stderr, "%s: %s\n", hd_progname(), hd_errmsg());
        if (rc == HD_ERR_USAGE) hd_opt_usage(table, synopsis);
        exit(1);
    }
}

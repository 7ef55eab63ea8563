/* heliodon — Radiance scene text parser.
 *
 * Statements: '#' comments (to end of line), '!' in-line commands (run
 * through "sh -c" with popen, their output parsed in place; a trailing
 * backslash continues the command on the next line), and primitives:
 *   modifier type identifier  nS s1..  nI i1..  nR r1..
 * or aliases "modifier alias identifier oldidentifier".  Words are
 * white-space delimited; ' and " quote groups (quotes removed). */
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include "heliodon/scene.h"
#include "heliodon/io.h"
#include "scene_priv.h"

#define MAXWORD 4096          /* Radiance allows 512; we are more generous */
#define MAXCOUNT 100000000u   /* argument count sanity limit */
#define MAXDEPTH 32           /* nested in-line commands */
#define DEPTH_ENV "HELIODON_SCENE_DEPTH"

typedef struct reader {
    FILE *fp;
    const char *mem;
    size_t memlen, mempos;
    uint32_t file;
    unsigned long line;
    int depth;
} reader;

typedef struct parser {
    hd_scene *s;
    hd_scene_opts o;
    /* scratch argument storage */
    char **sv; size_t nsv, capsv;
    double *rv; size_t caprv;
} parser;

static int rgetc(reader *r)
{
    int c;
    if (r->fp) c = getc_unlocked(r->fp);
    else c = r->mempos < r->memlen ? (unsigned char)r->mem[r->mempos++] : EOF;
    if (c == '\n') r->line++;
    return c;
}

static void rungetc(reader *r, int c)
{
    if (c == EOF) return;
    if (c == '\n') r->line--;
    if (r->fp) ungetc(c, r->fp);
    else r->mempos--;
}

static void where(parser *p, reader *r, unsigned long line, char *buf, size_t cap)
{
    hd_scene_where_file(p->s, r->file, (uint32_t)line, buf, cap);
}

/* Skip white space; return the next character (not consumed) or EOF. */
static int skip_space(reader *r)
{
    int c;
    do c = rgetc(r); while (c != EOF && isspace(c));
    rungetc(r, c);
    return c;
}

/* Read one word; returns its length, 0 at end of data, -1 if too long. */
static long get_word(reader *r, char *buf, size_t cap)
{
    size_t n = 0;
    int c, quote = 0, got = 0;
    if (skip_space(r) == EOF) return 0;
    for (;;) {
        c = rgetc(r);
        if (c == EOF) break;
        got = 1;
        if (quote) {
            if (c == quote) { quote = 0; continue; }
        } else if (c == '"' || c == '\'') {
            quote = c; continue;
        } else if (isspace(c)) {
            rungetc(r, c);
            break;
        }
        if (n + 1 >= cap) return -1;
        buf[n++] = (char)c;
    }
    buf[n] = 0;
    /* an empty quoted word ("") is a word: report length 1 with buf = "" */
    return n ? (long)n : got ? 1 : 0;
}

static int is_real_word(const char *w, double *v)
{
    for (const char *q = w; *q; q++)
        if (!(isdigit((unsigned char)*q) || *q == '.' || *q == '-' || *q == '+' || *q == 'e' || *q == 'E'))
            return 0;
    char *end;
    errno = 0;
    *v = strtod(w, &end);
    return end != w && *end == 0 && errno != ERANGE;
}

static int is_count_word(const char *w, unsigned long *v)
{
    if (!*w) return 0;
    for (const char *q = w; *q; q++)
        if (!isdigit((unsigned char)*q)) return 0;
    errno = 0;
    *v = strtoul(w, NULL, 10);
    return errno == 0;
}

static hd_status parse_stream(parser *p, reader *r);

/* Is the program named by the first word of cmd available? */
static int program_available(const char *cmd)
{
    char word[1024];
    size_t n = 0;
    while (*cmd == ' ' || *cmd == '\t') cmd++;
    while (*cmd && !strchr(" \t\n;|&<>()", *cmd) && n + 1 < sizeof word) word[n++] = *cmd++;
    word[n] = 0;
    if (!n || strchr(word, '=') || strchr(word, '$') || strchr(word, '`')) return 1;
    static const char *builtins[] = {"cd", "echo", "printf", "test", "[", "exec", "eval", "set",
                                     "export", "true", "false", ":", ".", "if", "for", "while", "{", 0};
    for (int i = 0; builtins[i]; i++)
        if (!strcmp(word, builtins[i])) return 1;
    if (strchr(word, '/')) return access(word, X_OK) == 0;
    const char *path = getenv("PATH");
    if (!path) path = "/usr/bin:/bin";
    char full[4096];
    while (*path) {
        const char *e = strchr(path, ':');
        size_t len = e ? (size_t)(e - path) : strlen(path);
        snprintf(full, sizeof full, "%.*s/%s", (int)len, len ? path : ".", word);
        struct stat st;
        if (stat(full, &st) == 0 && S_ISREG(st.st_mode) && access(full, X_OK) == 0) return 1;
        if (!e) break;
        path = e + 1;
    }
    return 0;
}

static int current_depth(void)
{
    const char *d = getenv(DEPTH_ENV);
    return d ? atoi(d) : 0;
}

static hd_status run_command(parser *p, reader *r, const char *cmd, unsigned long line)
{
    char w[1200];
    where(p, r, line, w, sizeof w);
    if (p->o.no_commands || (p->o.skip_missing && !program_available(cmd)))
        return hd_scene_add_skipped(p->s, cmd, r->file, (uint32_t)line);
    int depth = current_depth() + r->depth;
    if (depth >= MAXDEPTH)
        return hd_fail(HD_ERR_RANGE, "%s: in-line commands nested more than %d deep: '!%s'",
                       w, MAXDEPTH, cmd);
    size_t len = strlen(cmd);
    char *name = hd_malloc(len + 2);
    if (!name) return HD_ERR_NOMEM;
    name[0] = '!';
    memcpy(name + 1, cmd, len + 1);
    uint32_t fidx;
    hd_status st = hd_scene_add_file(p->s, name, (int32_t)r->file, (uint32_t)line, &fidx);
    free(name);
    if (st) return st;
    char dbuf[32], *old = getenv(DEPTH_ENV) ? hd_strdup(getenv(DEPTH_ENV)) : NULL;
    snprintf(dbuf, sizeof dbuf, "%d", current_depth() + 1);
    setenv(DEPTH_ENV, dbuf, 1);
    int had_skip = getenv(HD_SKIP_ENV) != NULL;
    if (p->o.skip_missing && !had_skip) setenv(HD_SKIP_ENV, "1", 1);
    fflush(NULL);
    char *full = NULL;
    if (p->o.command_dir && *p->o.command_dir) {
        size_t n = strlen(p->o.command_dir) * 4 + strlen(cmd) + 32;
        full = hd_malloc(n);
        if (!full) { free(old); return HD_ERR_NOMEM; }
        char *q = full;
        q += sprintf(q, "cd '");
        for (const char *d = p->o.command_dir; *d; d++) {
            if (*d == '\'') { memcpy(q, "'\\''", 4); q += 4; }
            else *q++ = *d;
        }
        sprintf(q, "' && %s", cmd);
    }
    FILE *fp = popen(full ? full : cmd, "r");
    free(full);
    if (!fp) {
        if (old) { setenv(DEPTH_ENV, old, 1); free(old); } else unsetenv(DEPTH_ENV);
        if (p->o.skip_missing && !had_skip) unsetenv(HD_SKIP_ENV);
        return hd_fail(HD_ERR_IO, "%s: cannot run command '!%s': %s", w, cmd, strerror(errno));
    }
    reader sub = {fp, NULL, 0, 0, fidx, 1, r->depth + 1};
    st = parse_stream(p, &sub);
    int status = pclose(fp);
    if (old) { setenv(DEPTH_ENV, old, 1); free(old); } else unsetenv(DEPTH_ENV);
    if (p->o.skip_missing && !had_skip) unsetenv(HD_SKIP_ENV);
    if (st) return st;
    if (status == -1)
        return hd_fail(HD_ERR_IO, "%s: command '!%s': cannot get its exit status", w, cmd);
    if (WIFSIGNALED(status))
        return hd_fail(HD_ERR_IO, "%s: command '!%s' killed by signal %d", w, cmd, WTERMSIG(status));
    if (WIFEXITED(status) && WEXITSTATUS(status) != 0)
        return hd_fail(HD_ERR_IO, "%s: command '!%s' failed with exit status %d%s", w, cmd,
                       WEXITSTATUS(status), WEXITSTATUS(status) == 127 ? " (command not found)" : "");
    return HD_OK;
}

/* Read an in-line command after '!' (continuations joined). */
static hd_status read_command(parser *p, reader *r, unsigned long line, char **out)
{
    size_t n = 0, cap = 256;
    char *buf = hd_malloc(cap);
    if (!buf) return HD_ERR_NOMEM;
    for (;;) {
        int c = rgetc(r);
        if (c == EOF || c == '\n') break;
        if (c == '\\') {
            int d = rgetc(r);
            if (d == '\n') { c = ' '; }
            else if (d == EOF) {
                char w[1200];
                where(p, r, line, w, sizeof w);
                free(buf);
                return hd_fail(HD_ERR_FORMAT, "%s: unterminated in-line command (end of data after '\\')", w);
            } else { rungetc(r, d); }
        }
        if (n + 2 >= cap) {
            if (cap > (1u << 24)) {
                char w[1200];
                where(p, r, line, w, sizeof w);
                free(buf);
                return hd_fail(HD_ERR_RANGE, "%s: in-line command longer than 16 MiB", w);
            }
            char *nb = hd_realloc_array(buf, cap * 2, 1);
            if (!nb) { free(buf); return HD_ERR_NOMEM; }
            buf = nb; cap *= 2;
        }
        buf[n++] = (char)c;
    }
    while (n && isspace((unsigned char)buf[n - 1])) n--;
    buf[n] = 0;
    *out = buf;
    return HD_OK;
}

static void free_strings(parser *p)
{
    for (size_t k = 0; k < p->nsv; k++) free(p->sv[k]);
    p->nsv = 0;
}

/* Radiance warns about polygons with zero area or vertices off their plane */
static void polygon_warnings(const hd_prim *pr, const char *w)
{
    uint32_t n = pr->nrargs / 3;
    hd_vec3 s = {0, 0, 0}, lo = {INFINITY, INFINITY, INFINITY}, hi = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = 0; i < n; i++) {
        hd_vec3 a = hd_polygon_vertex(pr, i), b = hd_polygon_vertex(pr, (i + 1) % n);
        s.x += (a.y - b.y) * (a.z + b.z);
        s.y += (a.z - b.z) * (a.x + b.x);
        s.z += (a.x - b.x) * (a.y + b.y);
        lo = hd_v3(fmin(lo.x, a.x), fmin(lo.y, a.y), fmin(lo.z, a.z));
        hi = hd_v3(fmax(hi.x, a.x), fmax(hi.y, a.y), fmax(hi.z, a.z));
    }
    double size = hd_vlen(hd_vsub(hi, lo)), len = hd_vlen(s);
    if (!(len > 1e-12 * size * size)) {
        hd_warn("%s: polygon %s has zero area", w, pr->id);
        return;
    }
    hd_vec3 nrm = hd_vscale(s, 1.0 / len), v0 = hd_polygon_vertex(pr, 0);
    double dmax = 0;
    for (uint32_t i = 1; i < n; i++)
        dmax = fmax(dmax, fabs(hd_vdot(nrm, hd_vsub(hd_polygon_vertex(pr, i), v0))));
    if (dmax > 1e-5 * size)
        hd_warn("%s: polygon %s is not planar (a vertex is %g off its plane)", w, pr->id, dmax);
}

/* As Radiance does: negative radii turn a cone into a cup (cylinder into a
 * tube) and back, with a warning; cones with equal radii stay cones. */
static hd_status normalise_radii(hd_prim *pr, const char *w)
{
    double *r = pr->rargs;
    if (pr->type == HD_T_CYLINDER || pr->type == HD_T_TUBE) {
        if (r[6] < 0) {
            hd_prim_type nt = pr->type == HD_T_CYLINDER ? HD_T_TUBE : HD_T_CYLINDER;
            hd_warn("%s: %s %s: negative radius, made a %s", w, hd_type_name(pr->type), pr->id, hd_type_name(nt));
            r[6] = -r[6];
            pr->type = nt;
        }
    } else if (pr->type == HD_T_CONE || pr->type == HD_T_CUP) {
        if ((r[6] < 0 && r[7] > 0) || (r[6] > 0 && r[7] < 0))
            return hd_fail(HD_ERR_FORMAT, "%s: %s %s: radii of opposite signs", w, hd_type_name(pr->type), pr->id);
        if (r[6] < 0 || r[7] < 0) {
            hd_prim_type nt = pr->type == HD_T_CONE ? HD_T_CUP : HD_T_CONE;
            hd_warn("%s: %s %s: negative radii, made a %s", w, hd_type_name(pr->type), pr->id, hd_type_name(nt));
            r[6] = -r[6];
            r[7] = -r[7];
            pr->type = nt;
        }
    }
    return HD_OK;
}

static hd_status parse_primitive(parser *p, reader *r)
{
    char w[1200], word[MAXWORD], modname[MAXWORD], type[MAXWORD], id[MAXWORD];
    unsigned long line;
    long n;
    skip_space(r);
    line = r->line;
#define EXPECT(buf, what) do { \
        n = get_word(r, buf, sizeof buf); \
        if (n < 0) { where(p, r, r->line, w, sizeof w); \
            return hd_fail(HD_ERR_FORMAT, "%s: word longer than %d characters reading %s", w, MAXWORD - 1, what); } \
        if (n == 0) { where(p, r, line, w, sizeof w); \
            return hd_fail(HD_ERR_FORMAT, "%s: unexpected end of data: expected %s", w, what); } \
    } while (0)
    /* the count of KIND arguments into cnt */
#define EXPECT_COUNT(kind) do { \
        EXPECT(word, "the number of " kind " arguments"); \
        if (!is_count_word(word, &cnt) || cnt > MAXCOUNT) { \
            where(p, r, r->line, w, sizeof w); \
            return hd_fail(HD_ERR_FORMAT, "%s: %s %s: expected the number of " kind " arguments, got '%s'", \
                           w, type, id, word); } \
    } while (0)
    EXPECT(modname, "a modifier name");
    EXPECT(type, "a primitive type");
    int t = hd_type_from_name(type);
    if (t < 0) {
        where(p, r, line, w, sizeof w);
        return hd_fail(HD_ERR_FORMAT, "%s: unknown primitive type '%s' (modifier '%s')", w, type, modname);
    }
    EXPECT(id, "an identifier");
    hd_prim pr;
    memset(&pr, 0, sizeof pr);
    pr.type = (hd_prim_type)t;
    pr.modifier = -1;
    pr.alias_of = -1;
    pr.file = r->file;
    pr.line = (uint32_t)line;
    pr.modname = modname;
    pr.id = id;
    hd_status st = HD_OK;
    free_strings(p);
    if (t == HD_T_ALIAS) {
        EXPECT(word, "the aliased identifier");
        if ((st = HD_GROW(p->sv, 1, p->capsv, 16))) return st;
        if (!(p->sv[0] = hd_strdup(word))) return HD_ERR_NOMEM;
        p->nsv = 1;
        pr.nsargs = 1;
        pr.sargs = p->sv;
    } else {
        unsigned long cnt;
        EXPECT_COUNT("string");
        for (unsigned long k = 0; k < cnt; k++) {
            n = get_word(r, word, sizeof word);
            if (n <= 0) {
                where(p, r, n == 0 ? line : r->line, w, sizeof w);
                return hd_fail(HD_ERR_FORMAT, "%s: %s %s: %s reading string argument %lu of %lu",
                               w, type, id, n < 0 ? "word too long" : "unexpected end of data", k + 1, cnt);
            }
            if ((st = HD_GROW(p->sv, p->nsv + 1, p->capsv, 16))) return st;
            if (!(p->sv[p->nsv] = hd_strdup(word))) return HD_ERR_NOMEM;
            p->nsv++;
        }
        pr.nsargs = (uint32_t)cnt;
        pr.sargs = p->sv;
        EXPECT_COUNT("integer");
        if (cnt != 0) {
            where(p, r, r->line, w, sizeof w);
            return hd_fail(HD_ERR_FORMAT, "%s: %s %s: integer argument count must be 0, got %lu",
                           w, type, id, cnt);
        }
        pr.niargs = 0;   /* no primitive type takes integer arguments */
        pr.iargs = NULL;
        EXPECT_COUNT("real");
        for (unsigned long k = 0; k < cnt; k++) {
            double v;
            n = get_word(r, word, sizeof word);
            if (n <= 0 || !is_real_word(word, &v)) {
                where(p, r, n == 0 ? line : r->line, w, sizeof w);
                return hd_fail(HD_ERR_FORMAT, "%s: %s %s: expected real argument %lu of %lu, got %s%s%s",
                               w, type, id, k + 1, cnt, n > 0 ? "'" : "", n > 0 ? word : "end of data",
                               n > 0 ? "'" : "");
            }
            if ((st = HD_GROW(p->rv, k + 1, p->caprv, 16))) return st;
            p->rv[k] = v;
        }
        pr.nrargs = (uint32_t)cnt;
        pr.rargs = p->rv;
    }
#undef EXPECT_COUNT
#undef EXPECT
    if (!p->o.raw) {
        where(p, r, line, w, sizeof w);
        if (strcmp(modname, "void")) {
            if (t == HD_T_ALIAS && !strcmp(modname, "inherit")) {
                /* resolved below */
            } else {
                pr.modifier = hd_scene_find_modifier(p->s, modname);
                if (pr.modifier < 0)
                    return hd_fail(HD_ERR_FORMAT, "%s: %s %s: undefined modifier '%s'", w, type, id, modname);
            }
        }
        if (hd_type_is_modifier(pr.type) && (!strcmp(id, "void") || !strcmp(id, "inherit")))
            return hd_fail(HD_ERR_FORMAT, "%s: %s: a modifier may not be named '%s'", w, type, id);
        if (t == HD_T_ALIAS) {
            pr.alias_of = hd_scene_find_modifier(p->s, pr.sargs[0]);
            if (pr.alias_of < 0)
                return hd_fail(HD_ERR_FORMAT, "%s: alias %s: undefined modifier '%s' to alias", w, id,
                               pr.sargs[0]);
            if (!strcmp(modname, "inherit")) pr.modifier = p->s->prims[pr.alias_of].modifier;
        }
        if ((st = hd_prim_check(p->s, &pr, w))) return st;
        if (t == HD_T_POLYGON) polygon_warnings(&pr, w);
        if ((st = normalise_radii(&pr, w))) return st;
    }
    st = hd_scene_add(p->s, &pr);
    free_strings(p);
    return st;
}

static hd_status parse_stream(parser *p, reader *r)
{
    for (;;) {
        int c = skip_space(r);
        if (c == EOF) break;
        if (c == '#') {
            /* "#@heliodon-skipped CMD": a nested program (our xform) skipped
             * an in-line command whose program is missing: record it here */
            static const char mark[] = "#@heliodon-skipped ";
            char buf[8192];
            size_t n = 0;
            unsigned long line = r->line;
            while ((c = rgetc(r)) != EOF && c != '\n')
                if (n + 1 < sizeof buf) buf[n++] = (char)c;
            buf[n] = 0;
            if (!strncmp(buf, mark, sizeof mark - 1)) {
                hd_status st = hd_scene_add_skipped(p->s, buf + sizeof mark - 1, r->file, (uint32_t)line);
                if (st) return st;
            }
            continue;
        }
        if (c == '!') {
            unsigned long line = r->line;
            rgetc(r);
            char *cmd = NULL;
            hd_status st = read_command(p, r, line, &cmd);
            if (st) return st;
            if (cmd[0]) st = run_command(p, r, cmd, line);
            free(cmd);
            if (st) return st;
            continue;
        }
        hd_status st = parse_primitive(p, r);
        if (st) return st;
    }
    if (r->fp && ferror(r->fp)) {
        char w[1200];
        where(p, r, r->line, w, sizeof w);
        return hd_fail(HD_ERR_IO, "%s: read error", w);
    }
    return HD_OK;
}

static void parser_init(parser *p, hd_scene *s, const hd_scene_opts *o)
{
    memset(p, 0, sizeof *p);
    p->s = s;
    if (o) p->o = *o;
}

static void parser_free(parser *p)
{
    free_strings(p);
    free(p->sv); free(p->rv);
}

hd_status hd_scene_load_rad(hd_scene *s, const char *path, const hd_scene_opts *opts)
{
    if (path[0] == '!') {
        parser p;
        parser_init(&p, s, opts);
        /* a command given as input: record a pseudo-file so messages make sense */
        uint32_t fidx;
        hd_status st = hd_scene_add_file(s, "(command line)", -1, 0, &fidx);
        if (!st) {
            reader r = {NULL, "", 0, 0, fidx, 1, 0};
            st = run_command(&p, &r, path + 1, 1);
        }
        parser_free(&p);
        return st;
    }
    FILE *fp = strcmp(path, "-") ? fopen(path, "r") : stdin;
    if (!fp)
        return hd_fail(HD_ERR_IO, "cannot open scene file '%s': %s", path, strerror(errno));
    uint32_t fidx;
    hd_status st = hd_scene_add_file(s, path, -1, 0, &fidx);
    if (!st) {
        parser p;
        parser_init(&p, s, opts);
        reader r = {fp, NULL, 0, 0, fidx, 1, 0};
        st = parse_stream(&p, &r);
        parser_free(&p);
    }
    if (fp != stdin) fclose(fp);
    return st;
}

hd_status hd_scene_load_string(hd_scene *s, const char *text, const char *name,
                               const hd_scene_opts *opts)
{
    uint32_t fidx;
    hd_status st = hd_scene_add_file(s, name ? name : "(string)", -1, 0, &fidx);
    if (st) return st;
    parser p;
    parser_init(&p, s, opts);
    reader r = {NULL, text, strlen(text), 0, fidx, 1, 0};
    st = parse_stream(&p, &r);
    parser_free(&p);
    return st;
}

hd_status hd_scene_load_files(hd_scene *s, int n, char *const *paths, const hd_scene_opts *opts)
{
    for (int i = 0; i < n; i++) {
        hd_status st;
        int is = paths[i][0] != '!' && strcmp(paths[i], "-") ? hd_scene_is_cache(paths[i]) : 0;
        if (is < 0) return HD_ERR_IO;
        int oct = 0;
        if (is) st = hd_scene_read_cache(s, paths[i]);
        else if (paths[i][0] != '!' && strcmp(paths[i], "-") &&
                 ((st = hd_scene_load_radiance_octree(s, paths[i], opts, &oct)) || oct)) {
            /* a Radiance octree: its scene files were loaded */
        } else st = hd_scene_load_rad(s, paths[i], opts);
        if (st) return st;
    }
    return HD_OK;
}

/* heliodon — the .cal function language: definitions, parser, evaluator.
 * See include/heliodon/cal.h for the contract and docs/design/cal.md.
 *
 * Representation.  Every name is a symbol (sym) in a hash table; a symbol
 * carries a stack of definitions (a `=` definition replaces the `=`
 * definitions on top of the stack, a `:` definition replaces them all, as
 * Radiance does) and possibly a built-in.  Expressions are trees of nodes
 * whose names were resolved to symbols at parse time, so evaluation never
 * looks anything up by name and several threads can evaluate one context.
 * Constant sub-expressions are folded while parsing (numbers, references
 * to constants, calls of constant functions with constant arguments).
 *
 * Evaluation state (hd_calrun): one cached value per symbol stamped with
 * the record clock (constants: stamped for ever), the $N callback and the
 * first fatal error. */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include "heliodon/cal.h"
#include "heliodon/io.h"
#include "cal_internal.h"

/* ---------------------------------------------------------------- nodes */
enum {
    N_NUM, N_VAR, N_ARG, N_CALL, N_ACALL, N_CHAN, N_NEG,
    N_ADD, N_SUB, N_MUL, N_DIV, N_POW
};

typedef struct sym sym;
typedef struct node node;
struct node {
    int op;
    int n;          /* kids (N_CALL/N_ACALL: arguments), N_ARG/N_ACALL: index, N_CHAN: channel */
    double num;
    sym *s, *fb;    /* N_VAR/N_CALL: symbol, fallback (global) symbol */
    node *k[];
};

/* built-in kinds */
enum { L_NONE, L_IF, L_SELECT, L_MIN, L_MAX, L_RAND, L_M1, L_ATAN2, L_JN, L_YN, L_C };

typedef struct def {
    int type;           /* '=' or ':' */
    int nparams;        /* -1: variable */
    node *expr;
    struct def *below;
    char **pnames;              /* parameter names (for printing) */
    int purity;                 /* fold check: 0 unknown, 1 in progress, 2 pure, 3 not */
    unsigned long puregen;      /* context generation of that answer */
} def;

struct sym {
    char *name;
    int id;
    def *top;
    int lib;            /* L_* */
    int minargs, maxargs;
    double (*m1)(double);
    hd_cal_fn cfn;
    void *cuser;
    int pure;
    sym *hnext;
};

#define MAXPARAMS 64

struct hd_cal {
    sym **hash;
    size_t nhash;
    sym **syms;
    int nsyms, capsyms;
    node **outchan;
    int noutchan;
    node **exprs;
    int nexprs;
    char ctx[64];
    unsigned long gen;          /* bumped by every definition change */
    hd_cal_warnfn warn;
    void *warnuser;
    int warn_on;
    int novars;                 /* ev: names must be function calls */
    int norconst;               /* no constant folding, no redefinition warnings (rcalc -n) */
    int redefw;                 /* warn on every redefinition (rcontrib) */
    int nooutchan;              /* icalc: "$N = ..." is not a definition */
    hd_calrun *prun;            /* run used for folding at parse time */
    /* every allocated node and string, freed with the context */
    void **blocks;
    size_t nblocks, capblocks;
};

typedef struct cache { uint64_t clock; double v; } cache;

typedef struct frame {
    const node *call;           /* call node (args in call->k), or NULL */
    struct frame *caller;
    const sym *fn;
    int nargs;
    uint64_t done;
    double *vals;
} frame;

struct hd_calrun {
    const hd_cal *c;
    void *user;
    hd_cal_chanfn chan;
    void *chanuser;
    cache *cache;
    int ncache;
    uint64_t clock;
    unsigned long gen;
    hd_status st;
    int depth;
    uintptr_t stack_base;       /* address near the top of the evaluation stack */
};

#define CONSTCLOCK UINT64_MAX
#define MAXDEPTH 1000000          /* calls; the real bound is the stack budget */
#define MAXNEST 2000              /* parser: nested parentheses and calls */

/* Bytes of stack an evaluation may use: half the stack limit, within
 * 512 KiB .. 16 MiB (1 MiB when unlimited: threads then get glibc's
 * default).  Deeper recursion is a fatal "recursion too deep", not a crash. */
static size_t stack_budget(void)
{
    static size_t budget;
    if (!budget) {
        struct rlimit rl;
        size_t b = (size_t)1 << 20;
        if (!getrlimit(RLIMIT_STACK, &rl) && rl.rlim_cur != RLIM_INFINITY) {
            b = (size_t)rl.rlim_cur / 2;
            if (b < ((size_t)512 << 10)) b = (size_t)512 << 10;
            if (b > ((size_t)16 << 20)) b = (size_t)16 << 20;
        }
        budget = b;
    }
    return budget;
}

static uintptr_t stack_here(void)
{
    return (uintptr_t)__builtin_frame_address(0);
}

static int stack_exceeded(const hd_calrun *r)
{
    uintptr_t h = stack_here();
    size_t used = r->stack_base > h ? (size_t)(r->stack_base - h) : (size_t)(h - r->stack_base);
    return used > stack_budget();
}

/* ------------------------------------------------------------ allocation */
static void *keep(hd_cal *c, void *p)
{
    if (!p) return NULL;
    if (HD_GROW(c->blocks, c->nblocks + 1, c->capblocks, 256)) { free(p); return NULL; }
    c->blocks[c->nblocks++] = p;
    return p;
}

static node *newnode(hd_cal *c, int op, int nk)
{
    node *e = keep(c, hd_calloc(1, sizeof(node) + (size_t)nk * sizeof(node *)));
    if (e) { e->op = op; e->n = nk; }
    return e;
}

static unsigned long hashstr(const char *s)
{
    unsigned long h = 5381;
    while (*s) h = h * 33 + (unsigned char)*s++;
    return h;
}

static sym *symfind(const hd_cal *c, const char *name)
{
    for (sym *s = c->hash[hashstr(name) & (c->nhash - 1)]; s; s = s->hnext)
        if (!strcmp(s->name, name)) return s;
    return NULL;
}

static sym *symget(hd_cal *c, const char *name)
{
    sym *s = symfind(c, name);
    if (s) return s;
    if ((size_t)c->nsyms * 2 >= c->nhash) {
        size_t nh = c->nhash * 2;
        sym **h = hd_calloc(nh, sizeof *h);
        if (!h) return NULL;
        for (int i = 0; i < c->nsyms; i++) {
            sym *t = c->syms[i];
            size_t b = hashstr(t->name) & (nh - 1);
            t->hnext = h[b];
            h[b] = t;
        }
        free(c->hash);
        c->hash = h;
        c->nhash = nh;
    }
    if (c->nsyms == c->capsyms) {
        int nc = c->capsyms ? 2 * c->capsyms : 128;
        sym **ns = hd_realloc_array(c->syms, (size_t)nc, sizeof *ns);
        if (!ns) return NULL;
        c->syms = ns;
        c->capsyms = nc;
    }
    s = keep(c, hd_calloc(1, sizeof *s));
    if (!s) return NULL;
    s->name = keep(c, hd_strdup(name));
    if (!s->name) return NULL;
    s->id = c->nsyms;
    c->syms[c->nsyms++] = s;
    size_t b = hashstr(name) & (c->nhash - 1);
    s->hnext = c->hash[b];
    c->hash[b] = s;
    return s;
}

/* ------------------------------------------------------------- warnings */
static void default_warn(void *user, const char *msg)
{
    (void)user;
    fprintf(stderr, "%s\n", msg);
}

static void calwarn(const hd_cal *c, const char *fmt, ...) HD_PRINTF(2, 3);
static void calwarn(const hd_cal *c, const char *fmt, ...)
{
    if (!c->warn_on || !hd_warnings_enabled()) return;
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    c->warn(c->warnuser, msg);
}

static double fatal(hd_calrun *r, hd_status st, const char *fmt, ...) HD_PRINTF(3, 4);
static double fatal(hd_calrun *r, hd_status st, const char *fmt, ...)
{
    if (r->st == HD_OK) {
        char msg[512];
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, sizeof msg, fmt, ap);
        va_end(ap);
        r->st = hd_fail(st, "%s", msg);
    }
    return 0.0;
}

/* ------------------------------------------------------------ evaluator */
static double eval(hd_calrun *r, const node *e, frame *f);

/* operand value: numbers and already evaluated arguments without a call */
#define LEAF(r, x, f) ((x)->op == N_NUM ? (x)->num \
    : ((x)->op == N_ARG && (f) && (x)->n < (f)->nargs && ((f)->done >> (x)->n & 1)) ? (f)->vals[(x)->n] \
    : eval((r), (x), (f)))


static inline const def *symdef(const node *e, const sym **sp)
{
    const sym *s = e->s;
    /* a context name without definition falls back to the global one
     * (also for messages about undefined names) */
    if (!s->top && e->fb && (e->fb->top || e->fb->lib || !s->lib)) s = e->fb;
    *sp = s;
    return s->top;
}

/* Value of argument i of frame f (evaluated at first use). */
static double argval(hd_calrun *r, frame *f, int i)
{
    if (!f) return fatal(r, HD_ERR_FORMAT, "argument outside a function");
    if (i >= f->nargs)
        return fatal(r, HD_ERR_FORMAT, "%s(): too few arguments", f->fn ? f->fn->name : "?");
    if (!(f->done & ((uint64_t)1 << i))) {
        f->vals[i] = eval(r, f->call->k[i], f->caller);
        f->done |= (uint64_t)1 << i;
    }
    return f->vals[i];
}

static double callsym(hd_calrun *r, const sym *s, const node *call, frame *caller);

static double varvalue(hd_calrun *r, const sym *s, const def *d)
{
    if (!d || d->nparams >= 0) {
        if (!d && s->lib == L_C && s->minargs == 0)
            return s->cfn(r, s->cuser, 0, NULL);
        return fatal(r, HD_ERR_FORMAT, "%s: undefined variable", s->name);
    }
    const node *x = d->expr;
    if (x->op == N_NUM) return x->num;
    cache *ch = &r->cache[s->id];
    uint64_t want = d->type == ':' ? CONSTCLOCK : r->clock;
    if (ch->clock == want || ch->clock == CONSTCLOCK) return ch->v;
    if (++r->depth > MAXDEPTH || stack_exceeded(r)) {
        r->depth--;
        return fatal(r, HD_ERR_RANGE, "%s: recursion too deep", s->name);
    }
    double v = eval(r, x, NULL);
    r->depth--;
    ch->v = v;
    ch->clock = want;
    return v;
}

static double chkmath(hd_calrun *r, const char *name, double v)
{
    if (isnan(v)) {
        calwarn(r->c, "%s(): domain error", name);
        return 0.0;
    }
    if (isinf(v)) {
        calwarn(r->c, "%s(): range error", name);
        return 0.0;
    }
    return v;
}

static double hashrand(double x)
{
    /* deterministic pseudo-random value in [0,1) from x: mix the bits of
     * the double with a 64-bit finaliser */
    uint64_t u;
    if (x == 0) x = 0;          /* -0 == 0 */
    memcpy(&u, &x, sizeof u);
    u ^= u >> 33;
    u *= 0xff51afd7ed558ccdULL;
    u ^= u >> 33;
    u *= 0xc4ceb9fe1a85ec53ULL;
    u ^= u >> 33;
    return (double)(u >> 11) * (1.0 / 9007199254740992.0);
}

/* Built-in call: arguments in call->k evaluated in frame fr. */
static double libcall(hd_calrun *r, const sym *s, const node *call, frame *fr)
{
    int n = call ? call->n : 0;
    const node *const *k = call ? (const node *const *)call->k : NULL;
    if (n < s->minargs)
        return fatal(r, HD_ERR_FORMAT, "%s(): too few arguments", s->name);
    switch (s->lib) {
    case L_IF:
        return LEAF(r, k[0], fr) > 0.0 ? LEAF(r, k[1], fr) : LEAF(r, k[2], fr);
    case L_SELECT: {
        double a = eval(r, k[0], fr);
        int i = (int)(a + .5);
        if (a < -.5 || i >= n) {
            calwarn(r->c, "select(): domain error");
            return 0.0;
        }
        if (i == 0) return n - 1;
        return eval(r, k[i], fr);
    }
    case L_MIN: case L_MAX: {
        double v = eval(r, k[0], fr);
        for (int i = n - 1; i >= 1; i--) {
            double w = eval(r, k[i], fr);
            if (s->lib == L_MIN ? w < v : w > v) v = w;
        }
        return v;
    }
    case L_RAND:
        return hashrand(eval(r, k[0], fr));
    case L_M1:
        return chkmath(r, s->name, s->m1(LEAF(r, k[0], fr)));
    case L_ATAN2: {
        double y = eval(r, k[0], fr);
        return chkmath(r, s->name, atan2(y, eval(r, k[1], fr)));
    }
    case L_JN: case L_YN: {
        double a = eval(r, k[0], fr), x = eval(r, k[1], fr);
        if (!(fabs(a) < 2147483647.0)) {   /* an order that is no int (inf, NaN, 1e10): no cast */
            calwarn(r->c, "%s(): order %g out of range", s->name, a);
            return 0.0;
        }
        return chkmath(r, s->name, s->lib == L_JN ? jn((int)a, x) : yn((int)a, x));
    }
    case L_C: {
        double buf[16], *v = buf;
        buf[0] = 0.0;
        int m = n;
        if (s->maxargs >= 0 && m > s->maxargs) m = s->maxargs;
        if (m > 16) {
            v = hd_malloc_array((size_t)m, sizeof *v);
            if (!v) return fatal(r, HD_ERR_NOMEM, "%s(): out of memory", s->name);
        }
        for (int i = 0; i < m; i++) v[i] = eval(r, k[i], fr);
        double res = s->cfn(r, s->cuser, m, v);
        if (v != buf) free(v);
        return chkmath(r, s->name, res);    /* NaN: the callback's domain error */
    }
    }
    return fatal(r, HD_ERR_FORMAT, "%s(): undefined function", s->name);
}

static double callsym(hd_calrun *r, const sym *s, const node *call, frame *caller)
{
    const def *d = s->top;
    if (!d || d->nparams < 0) {
        if (s->lib != L_NONE) return libcall(r, s, call, caller);
        return fatal(r, HD_ERR_FORMAT, "%s(): undefined function", s->name);
    }
    int n = call ? call->n : 0;
    int nv = n > d->nparams ? n : d->nparams;
    if (nv > MAXPARAMS) nv = MAXPARAMS;
    double vals[nv > 0 ? nv : 1];
    frame f = { call, caller, s, n > MAXPARAMS ? MAXPARAMS : n, 0, vals };
    if (++r->depth > MAXDEPTH || stack_exceeded(r)) {
        r->depth--;
        return fatal(r, HD_ERR_RANGE, "%s(): recursion too deep", s->name);
    }
    double v = eval(r, d->expr, &f);
    r->depth--;
    return v;
}

static double powchk(hd_calrun *r, double a, double b)
{
    double v = pow(a, b);
    if (isnan(v) || (isinf(v) && !isinf(a) && !isinf(b) && a == 0.0)) {
        calwarn(r->c, "Illegal power");
        return 0.0;
    }
    return v;
}

static double eval(hd_calrun *r, const node *e, frame *f)
{
    switch (e->op) {
    case N_NUM: return e->num;
    case N_ADD: { double a = LEAF(r, e->k[0], f); return a + LEAF(r, e->k[1], f); }
    case N_SUB: { double a = LEAF(r, e->k[0], f); return a - LEAF(r, e->k[1], f); }
    case N_MUL: { double a = LEAF(r, e->k[0], f); return a * LEAF(r, e->k[1], f); }
    case N_DIV: {
        double a = LEAF(r, e->k[0], f), b = LEAF(r, e->k[1], f);
        if (b == 0.0) {
            calwarn(r->c, "Division by zero");
            return 0.0;
        }
        return a / b;
    }
    case N_POW: {
        double a = LEAF(r, e->k[0], f);
        return powchk(r, a, LEAF(r, e->k[1], f));
    }
    case N_NEG: return -LEAF(r, e->k[0], f);
    case N_ARG: return argval(r, f, e->n);
    case N_CHAN:
        if (!r->chan) return fatal(r, HD_ERR_FORMAT, "$%d: no input channels", e->n);
        return r->chan(r, r->chanuser, e->n);
    case N_VAR: {
        const sym *s;
        const def *d = symdef(e, &s);
        return varvalue(r, s, d);
    }
    case N_CALL: {
        const sym *s;
        symdef(e, &s);
        return callsym(r, s, e, f);
    }
    case N_ACALL: {
        /* a parameter used as a function: follow the argument back to the
         * name the caller passed */
        const node *a = NULL;
        frame *cf = f;
        int i = (int)e->num;
        for (;;) {
            if (!cf || i >= cf->nargs)
                return fatal(r, HD_ERR_FORMAT, "%s(): too few arguments",
                             cf && cf->fn ? cf->fn->name : "?");
            a = cf->call->k[i];
            frame *up = cf->caller;
            if (a->op != N_ARG) { cf = up; break; }
            i = a->n;
            cf = up;
        }
        (void)cf;
        if (a->op != N_VAR)
            return fatal(r, HD_ERR_FORMAT, "%s(): argument not a function",
                         f && f->fn ? f->fn->name : "?");
        const sym *s;
        symdef(a, &s);
        return callsym(r, s, e, f);
    }
    }
    return 0.0;
}

/* --------------------------------------------------------------- runs */
static int run_sync(hd_calrun *r)
{
    const hd_cal *c = r->c;
    if (r->gen == c->gen && r->ncache >= c->nsyms) return 0;
    if (r->ncache < c->nsyms) {
        int n = c->capsyms > c->nsyms ? c->capsyms : c->nsyms;
        cache *nc = hd_realloc_array(r->cache, (size_t)n, sizeof *nc);
        if (!nc) { r->st = HD_ERR_NOMEM; return -1; }
        r->cache = nc;
        r->ncache = n;
    }
    memset(r->cache, 0, (size_t)r->ncache * sizeof *r->cache);
    r->gen = c->gen;
    return 0;
}

hd_calrun *hd_calrun_new(const hd_cal *c, void *user)
{
    hd_calrun *r = hd_calloc(1, sizeof *r);
    if (!r) return NULL;
    r->c = c;
    r->user = user;
    r->clock = 1;
    r->gen = c->gen - 1;
    if (run_sync(r)) { free(r); return NULL; }
    return r;
}

void hd_calrun_free(hd_calrun *r)
{
    if (!r) return;
    free(r->cache);
    free(r);
}

void *hd_calrun_user(const hd_calrun *r) { return r->user; }

void hd_calrun_set_chan(hd_calrun *r, hd_cal_chanfn fn, void *user)
{
    r->chan = fn;
    r->chanuser = user;
}

void hd_calrun_next(hd_calrun *r)
{
    r->clock++;
    run_sync(r);
}

hd_status hd_calrun_status(const hd_calrun *r) { return r->st; }
void hd_calrun_clear(hd_calrun *r) { r->st = HD_OK; r->depth = 0; }

static double run_checked(hd_calrun *r)
{
    if (r->gen != r->c->gen || r->ncache < r->c->nsyms) run_sync(r);
    if (r->depth == 0) r->stack_base = stack_here();
    return 0;
}

int hd_cal_lookup(const hd_cal *c, const char *name)
{
    char q[256];
    if (c->ctx[0] && !strchr(name, '`')) {
        snprintf(q, sizeof q, "%s`%s", name, c->ctx);
        sym *s = symfind(c, q);
        if (s && s->top) return s->id;
    }
    sym *s = symfind(c, name);
    return s && (s->top || s->lib) ? s->id : -1;
}

double hd_calrun_var_id(hd_calrun *r, int h)
{
    run_checked(r);
    if (h < 0 || h >= r->c->nsyms) return fatal(r, HD_ERR_USAGE, "bad variable handle %d", h);
    const sym *s = r->c->syms[h];
    return varvalue(r, s, s->top);
}

double hd_calrun_call_id(hd_calrun *r, int h, int nargs, const double *args)
{
    run_checked(r);
    if (h < 0 || h >= r->c->nsyms) return fatal(r, HD_ERR_USAGE, "bad function handle %d", h);
    const sym *s = r->c->syms[h];
    if (nargs == 0 && (!s->top || s->top->nparams < 0) && !(s->lib == L_C && s->minargs == 0))
        return varvalue(r, s, s->top);
    /* build a call node of numbers on the stack */
    int n = nargs > MAXPARAMS ? MAXPARAMS : nargs;
    node nums[n > 0 ? n : 1];
    /* a union, not a struct: C11 allows no member after a flexible array */
    union { node call; unsigned char room[sizeof(node) + MAXPARAMS * sizeof(node *)]; } cn;
    memset(&cn, 0, sizeof cn);
    cn.call.op = N_CALL;
    cn.call.n = n;
    for (int i = 0; i < n; i++) {
        memset(&nums[i], 0, sizeof nums[i]);
        nums[i].op = N_NUM;
        nums[i].num = args[i];
        cn.call.k[i] = &nums[i];
    }
    return callsym(r, s, &cn.call, NULL);
}

double hd_calrun_var(hd_calrun *r, const char *name)
{
    int h = hd_cal_lookup(r->c, name);
    if (h < 0) return fatal(r, HD_ERR_FORMAT, "%s: undefined variable", name);
    return hd_calrun_var_id(r, h);
}

double hd_calrun_call(hd_calrun *r, const char *name, int nargs, const double *args)
{
    int h = hd_cal_lookup(r->c, name);
    if (h < 0) {
        if (nargs == 0) return fatal(r, HD_ERR_FORMAT, "%s: undefined variable", name);
        return fatal(r, HD_ERR_FORMAT, "%s(): undefined function", name);
    }
    return hd_calrun_call_id(r, h, nargs, args);
}

double hd_calrun_outchan(hd_calrun *r, int n)
{
    run_checked(r);
    if (n < 1 || n > r->c->noutchan || !r->c->outchan[n - 1])
        return fatal(r, HD_ERR_FORMAT, "$%d: undefined output channel", n);
    return eval(r, r->c->outchan[n - 1], NULL);
}

double hd_calrun_expr(hd_calrun *r, int id)
{
    run_checked(r);
    if (id < 0 || id >= r->c->nexprs) return fatal(r, HD_ERR_USAGE, "bad expression id %d", id);
    return eval(r, r->c->exprs[id], NULL);
}

/* --------------------------------------------------------------- parser */
typedef struct parser {
    hd_cal *c;
    const char *text, *p;
    const char *origin;         /* NULL: command-line text */
    int isfile;
    const char *fparams[MAXPARAMS];
    int nfparams;               /* >= 0 inside a function definition */
    int infunc;
    hd_status st;
    int nest;                   /* nesting depth (parentheses, calls, ^) */
} parser;

static void skipws(parser *ps)
{
    for (;;) {
        while (*ps->p && isspace((unsigned char)*ps->p)) ps->p++;
        if (*ps->p == '{') {
            int depth = 0;
            do {
                if (*ps->p == '{') depth++;
                else if (*ps->p == '}') depth--;
                ps->p++;
            } while (*ps->p && depth > 0);
            continue;
        }
        break;
    }
}

/* Syntax error at the current position: Radiance's echo of the line with a
 * caret under the last character read, preceded for files by
 * "FILE, line L (column C):". */
static node *syntax(parser *ps, const char *msg)
{
    if (ps->st != HD_OK) return NULL;
    const char *pos = ps->p;
    const char *ls = pos;
    while (ls > ps->text && ls[-1] != '\n') ls--;
    const char *le = pos;
    while (*le && *le != '\n') le++;
    int line = 1;
    for (const char *q = ps->text; q < ls; q++) line += *q == '\n';
    int col = (int)(pos - ls);          /* caret under the last char read */
    if (col < 1 && pos > ls) col = 1;
    /* long lines: show at most 100 characters around the position */
    const char *ws = ls, *we = le;
    if (col > 80) ws = ls + col - 80;
    if (we - ws > 100) we = ws + 100;
    char caret[128];
    int m = 0;
    for (const char *q = ws; q < ls + (col > 0 ? col - 1 : 0) && m < 120; q++)
        caret[m++] = *q == '\t' ? '\t' : ' ';
    caret[m] = 0;
    int w = (int)(we - ws);
    const char *pre = ws > ls ? "..." : "", *post = we < le ? "..." : "";
    if (*pre) {
        /* the "..." shifts the line by three columns */
        memmove(caret + 3, caret, (size_t)m + 1);
        memset(caret, ' ', 3);
    }
    if (ps->isfile)
        ps->st = hd_fail(HD_ERR_FORMAT, "%s, line %d, column %d:\n%s%.*s%s\n%s^ %s",
                         ps->origin, line, col > 0 ? col : 1, pre, w, ws, post, caret, msg);
    else if (line > 1)
        ps->st = hd_fail(HD_ERR_FORMAT, "line %d:\n%s%.*s%s\n%s^ %s", line, pre, w, ws, post, caret, msg);
    else
        ps->st = hd_fail(HD_ERR_FORMAT, "%s%.*s%s\n%s^ %s", pre, w, ws, post, caret, msg);
    return NULL;
}

static int isidc(int ch) { return isalnum(ch) || ch == '_' || ch == '.' || ch == '`'; }

static int getname(parser *ps, char *buf, size_t cap)
{
    size_t n = 0;
    while (isidc((unsigned char)*ps->p)) {
        if (n + 1 < cap) buf[n++] = *ps->p;
        ps->p++;
    }
    buf[n] = 0;
    return (int)n;
}

/* qualified symbols for a reference (sym, fallback) or a definition */
static void qualify(hd_cal *c, const char *name, int forref, sym **s, sym **fb)
{
    char q[320];
    *fb = NULL;
    size_t len = strlen(name);
    if (len && name[len - 1] == '`') {         /* explicit global */
        snprintf(q, sizeof q, "%.*s", (int)(len - 1), name);
        *s = symget(c, q);
        return;
    }
    if (name[0] == '`') name++;
    if (!c->ctx[0] || strchr(name, '`')) {
        *s = symget(c, name);
        return;
    }
    snprintf(q, sizeof q, "%s`%s", name, c->ctx);
    *s = symget(c, q);
    if (forref) *fb = symget(c, name);
}

static node *getE1(parser *ps);

static int isconstsym(const sym *s)
{
    return s && s->top && s->top->type == ':' && s->top->nparams < 0 && s->top->expr->op == N_NUM;
}

/* Whether an expression depends only on numbers, arguments, constants and
 * pure functions (so that a constant function of it may be folded while
 * parsing).  A body that reads $N, a variable or an impure callback is not
 * evaluated before its time even when its function is declared with ':'. */
static int pure_expr(const hd_cal *c, const node *e, int depth);

static int pure_def(const hd_cal *c, def *d, int depth)
{
    if (d->type != ':' || d->nparams < 0) return 0;
    if (d->puregen == c->gen && d->purity) return d->purity != 3;   /* in progress counts as pure */
    d->puregen = c->gen;
    d->purity = 1;
    int p = pure_expr(c, d->expr, depth + 1);
    d->purity = p ? 2 : 3;
    return p;
}

static int pure_expr(const hd_cal *c, const node *e, int depth)
{
    if (depth > 200) return 0;
    switch (e->op) {
    case N_NUM: case N_ARG: return 1;
    case N_CHAN: case N_ACALL: return 0;
    case N_VAR: {
        const sym *s;
        symdef(e, &s);
        return isconstsym(s);
    }
    case N_CALL: {
        const sym *s;
        def *d = (def *)symdef(e, &s);
        for (int i = 0; i < e->n; i++)
            if (!pure_expr(c, e->k[i], depth + 1)) return 0;
        if (d) return pure_def(c, d, depth);
        return s->lib != L_NONE && (s->lib != L_C || s->pure);
    }
    case N_NEG: return pure_expr(c, e->k[0], depth + 1);
    default: return pure_expr(c, e->k[0], depth + 1) && pure_expr(c, e->k[1], depth + 1);
    }
}

static node *fold(parser *ps, node *e)
{
    hd_cal *c = ps->c;
    if (!e || ps->st != HD_OK || c->norconst) return e;
    double v;
    switch (e->op) {
    case N_ADD: case N_SUB: case N_MUL: case N_DIV: case N_POW:
        if (e->k[0]->op != N_NUM || e->k[1]->op != N_NUM) return e;
        break;
    case N_NEG:
        if (e->k[0]->op != N_NUM) return e;
        break;
    case N_VAR: {
        const sym *s;
        symdef(e, &s);
        if (!isconstsym(s)) return e;
        break;
    }
    case N_CALL: {
        const sym *s;
        const def *d = symdef(e, &s);
        for (int i = 0; i < e->n; i++)
            if (e->k[i]->op != N_NUM) return e;
        if (d) {
            if (!pure_def(c, (def *)d, 0)) return e;
        } else if (s->lib == L_NONE || (s->lib == L_C && !s->pure)) {
            return e;
        }
        break;
    }
    default:
        return e;
    }
    hd_calrun *r = c->prun;
    run_sync(r);
    r->clock++;
    r->depth = 0;
    r->stack_base = stack_here();
    v = eval(r, e, NULL);
    if (r->st != HD_OK) {
        ps->st = r->st;
        r->st = HD_OK;
        return NULL;
    }
    node *n = newnode(c, N_NUM, 0);
    if (n) n->num = v;
    return n;
}

static node *getE5(parser *ps)
{
    hd_cal *c = ps->c;
    skipws(ps);
    char ch = *ps->p;
    if (ch == '(') {
        ps->p++;
        if (++ps->nest > MAXNEST) return syntax(ps, "expression too deeply nested");
        node *e = getE1(ps);
        ps->nest--;
        if (!e) return NULL;
        skipws(ps);
        if (*ps->p != ')') { if (*ps->p) ps->p++; return syntax(ps, "')' expected"); }
        ps->p++;
        return e;
    }
    if (ch == '$') {
        ps->p++;
        if (!isdigit((unsigned char)*ps->p) && !c->nooutchan) {
            if (*ps->p) ps->p++;
            return syntax(ps, "integer expected");
        }
        long n = 0;     /* icalc: a bare '$' is $0, the previous result */
        while (isdigit((unsigned char)*ps->p)) { n = n * 10 + (*ps->p - '0'); if (n > 1000000) n = 1000000; ps->p++; }
        node *e = newnode(c, N_CHAN, 0);
        if (e) e->n = (int)n;
        return e;
    }
    if (isalpha((unsigned char)ch) || ch == '`' || ch == '_') {
        char name[256];
        getname(ps, name, sizeof name);
        int argi = -1;
        for (int i = 0; ps->infunc && i < ps->nfparams; i++)
            if (!strcmp(ps->fparams[i], name)) { argi = i; break; }
        skipws(ps);
        if (*ps->p == '(') {
            /* any number of arguments (select() of a long table) */
            node *stack[MAXPARAMS * 4], **args = stack, **grown;
            int n = 0, cap = (int)(sizeof stack / sizeof *stack);
            do {
                ps->p++;
                if (++ps->nest > MAXNEST) { if (args != stack) free(args); return syntax(ps, "expression too deeply nested"); }
                node *a = getE1(ps);
                ps->nest--;
                if (a && n == cap) {
                    grown = cap <= 1 << 20 ? hd_malloc_array((size_t)cap * 2, sizeof *args) : NULL;
                    if (!grown) { if (args != stack) free(args); return syntax(ps, "too many arguments"); }
                    memcpy(grown, args, (size_t)n * sizeof *args);
                    if (args != stack) free(args);
                    args = grown;
                    cap *= 2;
                }
                if (!a) { if (args != stack) free(args); return NULL; }
                args[n++] = a;
                skipws(ps);
            } while (*ps->p == ',');
            if (*ps->p != ')') { if (args != stack) free(args); if (*ps->p) ps->p++; return syntax(ps, "')' expected"); }
            ps->p++;
            node *e = newnode(c, argi >= 0 ? N_ACALL : N_CALL, n);
            if (e) memcpy(e->k, args, (size_t)n * sizeof *args);
            if (args != stack) free(args);
            if (!e) return NULL;
            if (argi >= 0) e->num = argi;
            else qualify(c, name, 1, &e->s, &e->fb);
            return fold(ps, e);
        }
        if (c->novars) return syntax(ps, "'(' expected");
        if (argi >= 0) {
            node *e = newnode(c, N_ARG, 0);
            if (e) e->n = argi;
            return e;
        }
        node *e = newnode(c, N_VAR, 0);
        if (!e) return NULL;
        qualify(c, name, 1, &e->s, &e->fb);
        return fold(ps, e);
    }
    if (isdigit((unsigned char)ch) || ch == '.') {
        const char *q = ps->p;
        char buf[128];
        size_t n = 0;
        while (isdigit((unsigned char)*q) || *q == '.') q++;
        if ((*q == 'e' || *q == 'E')) {
            const char *t = q + 1;
            if (*t == '+' || *t == '-') t++;
            if (isdigit((unsigned char)*t)) {
                q = t;
                while (isdigit((unsigned char)*q)) q++;
            }
        }
        n = (size_t)(q - ps->p);
        if (n >= sizeof buf) n = sizeof buf - 1;
        memcpy(buf, ps->p, n);
        buf[n] = 0;
        char *end;
        double v = strtod(buf, &end);
        if (end == buf) { ps->p++; return syntax(ps, "bad number"); }
        ps->p = q;
        node *e = newnode(c, N_NUM, 0);
        if (e) e->num = v;
        return e;
    }
    if (*ps->p) ps->p++;
    return syntax(ps, "unexpected character");
}

static node *getE4(parser *ps)
{
    skipws(ps);
    if (*ps->p == '-') {
        ps->p++;
        node *k = getE5(ps);
        if (!k) return NULL;
        if (k->op == N_NUM) { k->num = -k->num; return k; }
        if (k->op == N_NEG) return k->k[0];
        node *e = newnode(ps->c, N_NEG, 1);
        if (e) e->k[0] = k;
        return e;
    }
    if (*ps->p == '+') ps->p++;
    return getE5(ps);
}

static node *binop(parser *ps, int op, node *a, node *b)
{
    if (!a || !b) return NULL;
    node *e = newnode(ps->c, op, 2);
    if (!e) return NULL;
    e->k[0] = a;
    e->k[1] = b;
    return fold(ps, e);
}

static node *getE3(parser *ps)
{
    node *a = getE4(ps);
    if (!a) return NULL;
    skipws(ps);
    if (*ps->p == '^') {
        ps->p++;
        if (++ps->nest > MAXNEST) return syntax(ps, "expression too deeply nested");
        node *b = getE3(ps);
        ps->nest--;
        return binop(ps, N_POW, a, b);
    }
    return a;
}

/* left-associative levels: E2 = E3 {(*|/) E3}, E1 = E2 {(+|-) E2} */
static node *getlevel(parser *ps, int lvl)
{
    node *a = lvl == 2 ? getE3(ps) : getlevel(ps, 2);
    const char op1 = lvl == 2 ? '*' : '+', op2 = lvl == 2 ? '/' : '-';
    for (;;) {
        if (!a) return NULL;
        skipws(ps);
        char ch = *ps->p;
        if (ch != op1 && ch != op2) return a;
        ps->p++;
        node *b = lvl == 2 ? getE3(ps) : getlevel(ps, 2);
        a = binop(ps, ch == '*' ? N_MUL : ch == '/' ? N_DIV : ch == '+' ? N_ADD : N_SUB, a, b);
    }
}

static node *getE1(parser *ps) { return getlevel(ps, 1); }

/* structural equality of two expressions (for "redefined" warnings) */
static int samenode(const node *a, const node *b)
{
    if (a->op != b->op || a->n != b->n) return 0;
    switch (a->op) {
    case N_NUM: return a->num == b->num || (a->num != a->num && b->num != b->num);
    case N_VAR: return a->s == b->s;
    case N_CALL: if (a->s != b->s) return 0; break;
    case N_ACALL: if (a->num != b->num) return 0; break;
    case N_ARG: case N_CHAN: return 1;
    default: break;
    }
    int nk = a->op == N_NUM || a->op == N_VAR || a->op == N_ARG || a->op == N_CHAN ? 0 : a->n;
    if (a->op == N_NEG) nk = 1;
    else if (a->op >= N_ADD) nk = 2;
    for (int i = 0; i < nk; i++)
        if (!samenode(a->k[i], b->k[i])) return 0;
    return 1;
}

static void pushdef(hd_cal *c, sym *s, def *d)
{
    if (d->type == ':') {
        s->top = NULL;                       /* remove every definition */
    } else {
        while (s->top && s->top->type == '=') s->top = s->top->below;
    }
    d->below = s->top;
    s->top = d;
    c->gen++;
}

static void warn_redef(hd_cal *c, const sym *s, const def *d)
{
    const def *o = s->top;
    if (!o || (c->norconst && !c->redefw)) return;
    if (o->nparams != d->nparams || !samenode(o->expr, d->expr)) {
        if (o->type == ':') calwarn(c, "%s: constant redefined", s->name);
        else if (c->redefw) calwarn(c, "%s: redefined", s->name);
    }
}

static int getstatement(parser *ps)
{
    hd_cal *c = ps->c;
    skipws(ps);
    if (*ps->p == ';') { ps->p++; return 0; }
    if (!*ps->p) return 0;
    if (*ps->p == '$' && c->nooutchan) {
        ps->p++;
        syntax(ps, "illegal variable name");
        return -1;
    }
    if (*ps->p == '$') {
        ps->p++;
        if (!isdigit((unsigned char)*ps->p)) { if (*ps->p) ps->p++; syntax(ps, "integer expected"); return -1; }
        long n = 0;
        while (isdigit((unsigned char)*ps->p)) { n = n * 10 + (*ps->p - '0'); if (n > 100000) n = 100000; ps->p++; }
        skipws(ps);
        if (*ps->p != '=' && *ps->p != ':') { if (*ps->p) ps->p++; syntax(ps, "'=' expected"); return -1; }
        ps->p++;
        ps->infunc = 0;
        node *e = getE1(ps);
        if (!e) return -1;
        if (n < 1) { syntax(ps, "bad channel number"); return -1; }
        if (n > c->noutchan) {
            node **no = hd_realloc_array(c->outchan, (size_t)n, sizeof *no);
            if (!no) { ps->st = HD_ERR_NOMEM; return -1; }
            for (long i = c->noutchan; i < n; i++) no[i] = NULL;
            c->outchan = no;
            c->noutchan = (int)n;
        }
        c->outchan[n - 1] = e;
        c->gen++;
    } else {
        if (!(isalpha((unsigned char)*ps->p) || *ps->p == '`' || *ps->p == '_')) {
            if (*ps->p) ps->p++;
            syntax(ps, "illegal variable name");
            return -1;
        }
        char name[256];
        getname(ps, name, sizeof name);
        skipws(ps);
        char pnames[MAXPARAMS][64];
        int np = -1;
        if (*ps->p == '(') {
            np = 0;
            do {
                ps->p++;
                skipws(ps);
                if (!isalpha((unsigned char)*ps->p)) { if (*ps->p) ps->p++; syntax(ps, "illegal parameter name"); return -1; }
                if (np >= MAXPARAMS) { syntax(ps, "too many parameters"); return -1; }
                getname(ps, pnames[np], sizeof pnames[np]);
                ps->fparams[np] = pnames[np];
                np++;
                skipws(ps);
            } while (*ps->p == ',');
            if (*ps->p != ')') { if (*ps->p) ps->p++; syntax(ps, "')' expected"); return -1; }
            ps->p++;
            skipws(ps);
        }
        if (*ps->p != '=' && *ps->p != ':') {
            if (*ps->p) ps->p++;
            syntax(ps, np >= 0 ? "'=' or ':' expected" : "'=' or ':' expected");
            return -1;
        }
        int type = *ps->p++;
        ps->nfparams = np > 0 ? np : 0;
        ps->infunc = np >= 0;
        node *e = getE1(ps);
        ps->infunc = 0;
        if (!e) return -1;
        sym *s, *fb;
        qualify(c, name, 0, &s, &fb);
        if (!s) { ps->st = HD_ERR_NOMEM; return -1; }
        def *d = keep(c, hd_calloc(1, sizeof *d));
        if (!d) { ps->st = HD_ERR_NOMEM; return -1; }
        d->type = type;
        d->nparams = np;
        if (np > 0) {
            d->pnames = keep(c, hd_calloc((size_t)np, sizeof *d->pnames));
            if (!d->pnames) { ps->st = HD_ERR_NOMEM; return -1; }
            for (int i = 0; i < np; i++)
                if (!(d->pnames[i] = keep(c, hd_strdup(pnames[i])))) { ps->st = HD_ERR_NOMEM; return -1; }
        }
        d->expr = e;
        warn_redef(c, s, d);
        pushdef(c, s, d);
    }
    skipws(ps);
    if (*ps->p && *ps->p != ';') {
        ps->p++;
        syntax(ps, "';' expected");
        return -1;
    }
    if (*ps->p == ';') ps->p++;
    return 0;
}

static hd_status parse_text(hd_cal *c, const char *text, const char *origin, int isfile)
{
    parser ps = { c, text, text, origin, isfile, { 0 }, 0, 0, HD_OK, 0 };
    hd_calrun_clear(c->prun);
    for (;;) {
        skipws(&ps);
        if (!*ps.p) break;
        if (getstatement(&ps) || ps.st != HD_OK) {
            if (ps.st == HD_OK) ps.st = HD_ERR_FORMAT;
            return ps.st;
        }
    }
    return HD_OK;
}

hd_status hd_cal_parse(hd_cal *c, const char *text, const char *origin)
{
    return parse_text(c, text, origin, 0);
}

hd_status hd_cal_expr(hd_cal *c, const char *text, const char *origin, int *id)
{
    parser ps = { c, text, text, origin, 0, { 0 }, 0, 0, HD_OK, 0 };
    *id = -1;
    hd_calrun_clear(c->prun);
    node *e = getE1(&ps);
    if (e) {
        skipws(&ps);
        if (*ps.p) { ps.p++; syntax(&ps, "unexpected character"); e = NULL; }
    }
    if (!e) return ps.st != HD_OK ? ps.st : HD_ERR_FORMAT;
    node **ne = hd_realloc_array(c->exprs, (size_t)c->nexprs + 1, sizeof *ne);
    if (!ne) return HD_ERR_NOMEM;
    c->exprs = ne;
    c->exprs[c->nexprs] = e;
    *id = c->nexprs++;
    return HD_OK;
}

hd_status hd_cal_eval(hd_cal *c, const char *text, double *out)
{
    int id;
    *out = 0;
    hd_status st = hd_cal_expr(c, text, NULL, &id);
    if (st != HD_OK) return st;
    hd_calrun *r = hd_calrun_new(c, NULL);
    if (!r) return HD_ERR_NOMEM;
    *out = hd_calrun_expr(r, id);
    st = r->st;
    hd_calrun_free(r);
    return st;
}

/* -------------------------------------------------------------- context */
static double m_sqrt(double x) { return sqrt(x); }
static double m_sin(double x) { return sin(x); }
static double m_cos(double x) { return cos(x); }
static double m_tan(double x) { return tan(x); }
static double m_asin(double x) { return asin(x); }
static double m_acos(double x) { return acos(x); }
static double m_atan(double x) { return atan(x); }
static double m_exp(double x) { return exp(x); }
static double m_log(double x) { return log(x); }
static double m_log10(double x) { return log10(x); }
static double m_floor(double x) { return floor(x); }
static double m_ceil(double x) { return ceil(x); }
static double m_j0(double x) { return j0(x); }
static double m_j1(double x) { return j1(x); }
static double m_y0(double x) { return y0(x); }
static double m_y1(double x) { return y1(x); }
static double m_erf(double x) { return erf(x); }
static double m_erfc(double x) { return erfc(x); }

static int deflib(hd_cal *c, const char *name, int kind, int minargs, int maxargs, double (*m1)(double))
{
    sym *s = symget(c, name);
    if (!s) return -1;
    s->lib = kind;
    s->minargs = minargs;
    s->maxargs = maxargs;
    s->m1 = m1;
    s->pure = 1;
    return 0;
}

hd_cal *hd_cal_new(void)
{
    hd_cal *c = hd_calloc(1, sizeof *c);
    if (!c) return NULL;
    c->nhash = 256;
    c->hash = hd_calloc(c->nhash, sizeof *c->hash);
    c->warn = default_warn;
    c->warn_on = 1;
    c->gen = 1;
    if (!c->hash) { free(c); return NULL; }
    static const struct { const char *n; double (*f)(double); } m1[] = {
        { "sqrt", m_sqrt }, { "sin", m_sin }, { "cos", m_cos }, { "tan", m_tan },
        { "asin", m_asin }, { "acos", m_acos }, { "atan", m_atan }, { "exp", m_exp },
        { "log", m_log }, { "log10", m_log10 }, { "floor", m_floor }, { "ceil", m_ceil },
        { "j0", m_j0 }, { "j1", m_j1 }, { "y0", m_y0 }, { "y1", m_y1 },
        { "erf", m_erf }, { "erfc", m_erfc },
    };
    int bad = 0;
    for (size_t i = 0; i < sizeof m1 / sizeof *m1; i++)
        bad |= deflib(c, m1[i].n, L_M1, 1, 1, m1[i].f);
    bad |= deflib(c, "if", L_IF, 3, 3, NULL);
    bad |= deflib(c, "select", L_SELECT, 1, HD_CAL_ANYARGS, NULL);
    bad |= deflib(c, "min", L_MIN, 1, HD_CAL_ANYARGS, NULL);
    bad |= deflib(c, "max", L_MAX, 1, HD_CAL_ANYARGS, NULL);
    bad |= deflib(c, "rand", L_RAND, 1, 1, NULL);
    bad |= deflib(c, "atan2", L_ATAN2, 2, 2, NULL);
    bad |= deflib(c, "jn", L_JN, 2, 2, NULL);
    bad |= deflib(c, "yn", L_YN, 2, 2, NULL);
    c->prun = bad ? NULL : hd_calrun_new(c, NULL);
    if (!c->prun) { hd_cal_free(c); return NULL; }
    return c;
}

void hd_cal_free(hd_cal *c)
{
    if (!c) return;
    hd_calrun_free(c->prun);
    for (size_t i = 0; i < c->nblocks; i++) free(c->blocks[i]);
    free(c->blocks);
    free(c->hash);
    free(c->syms);
    free(c->outchan);
    free(c->exprs);
    free(c);
}

hd_status hd_cal_set(hd_cal *c, const char *name, double v, int constant)
{
    sym *s, *fb;
    qualify(c, name, 0, &s, &fb);
    if (!s) return HD_ERR_NOMEM;
    /* quick set: replace the number of a `=` definition on top */
    if (s->top && s->top->type == '=' && s->top->nparams < 0 && s->top->expr->op == N_NUM) {
        /* a new value for a `=` number: nothing caches it (variables that
         * use it are recomputed at the next record), so no generation
         * change is needed unless it becomes a constant */
        s->top->expr->num = v;
        if (constant) {
            s->top->type = ':';
            c->gen++;
        }
        return HD_OK;
    }
    node *e = newnode(c, N_NUM, 0);
    def *d = keep(c, hd_calloc(1, sizeof *d));
    if (!e || !d) return HD_ERR_NOMEM;
    e->num = v;
    d->type = constant ? ':' : '=';
    d->nparams = -1;
    d->expr = e;
    pushdef(c, s, d);
    return HD_OK;
}

hd_status hd_cal_define_fn(hd_cal *c, const char *name, int minargs, int maxargs,
                           hd_cal_fn fn, void *user, int pure)
{
    if (!fn || minargs < 0 || (maxargs >= 0 && maxargs < minargs))
        return hd_fail(HD_ERR_USAGE, "%s: bad callback definition", name);
    sym *s = symget(c, name);
    if (!s) return HD_ERR_NOMEM;
    s->lib = L_C;
    s->minargs = minargs;
    s->maxargs = maxargs;
    s->cfn = fn;
    s->cuser = user;
    s->pure = pure;
    c->gen++;
    return HD_OK;
}

hd_status hd_cal_set_context(hd_cal *c, const char *ctx)
{
    if (ctx && strlen(ctx) >= sizeof c->ctx)
        return hd_fail(HD_ERR_RANGE, "context name too long: %s", ctx);
    hd_strlcpy(c->ctx, ctx ? ctx : "", sizeof c->ctx);
    return HD_OK;
}

int hd_cal_defined(const hd_cal *c, const char *name) { return hd_cal_lookup(c, name) >= 0; }

int hd_cal_nparams(const hd_cal *c, const char *name)
{
    const sym *s = symfind(c, name);
    if (!s) return -2;
    if (s->top) return s->top->nparams;
    if (s->lib == L_NONE) return -2;
    return s->lib == L_C && s->maxargs == 0 ? -1 : s->minargs;
}

int hd_cal_is_const(const hd_cal *c, const char *name)
{
    int h = hd_cal_lookup(c, name);
    if (h < 0) return 0;
    const sym *s = c->syms[h];
    return s->top ? s->top->type == ':' : s->lib != L_C || s->pure;
}

int hd_cal_max_outchan(const hd_cal *c) { return c->noutchan; }
int hd_cal_has_outchan(const hd_cal *c, int n) { return n >= 1 && n <= c->noutchan && c->outchan[n - 1]; }

void hd_cal_set_warn(hd_cal *c, hd_cal_warnfn fn, void *user)
{
    c->warn = fn ? fn : default_warn;
    c->warnuser = user;
}

void hd_cal_warnings(hd_cal *c, int on) { c->warn_on = on; }
void hd_cal_novars(hd_cal *c, int on) { c->novars = on; }
void hd_cal_nooutchan(hd_cal *c, int on) { c->nooutchan = on; }
void hd_cal_rconst(hd_cal *c, int on) { c->norconst = !on; }
void hd_cal_redefw(hd_cal *c, int on) { c->redefw = on; }

int hd_cal_named(const hd_cal *c, const char *name) { return symfind(c, name) != NULL; }

/* ------------------------------------------------------------ files */
#ifndef HD_CAL_LIBDIR
#define HD_CAL_LIBDIR "/usr/local/lib/ray"
#endif

#ifdef HD_CAL_SRCLIB
#define HD_CAL_LIBDIRS HD_CAL_LIBDIR ":" HD_CAL_SRCLIB
#else
#define HD_CAL_LIBDIRS HD_CAL_LIBDIR
#endif

const char *hd_cal_findfile(const char *name, char *buf, size_t cap)
{
    if (!name || !*name) return NULL;
    if (strchr(name, '/')) return hd_find_in_path("", name, buf, cap);
    /* RAYPATH (or "." when unset), then always heliodon's own library
     * folders: scripts that set RAYPATH for their BSDF or scene files
     * still find the standard .cal files */
    const char *env = getenv("RAYPATH");
    char defpath[8192];
    snprintf(defpath, sizeof defpath, "%s:%s", env && *env ? env : ".", HD_CAL_LIBDIRS);
    return hd_find_in_path(defpath, name, buf, cap);
}

const char *hd_cal_libfile(const char *name, char *buf, size_t cap)
{
    if (!name || !*name || strchr(name, '/')) return NULL;
    return hd_find_in_path(HD_CAL_LIBDIRS, name, buf, cap);
}

hd_status hd_cal_load(hd_cal *c, const char *name)
{
    char path[4096];
    if (!hd_cal_findfile(name, path, sizeof path))
        return hd_fail(HD_ERR_IO, "cannot find file '%s'", name);
    FILE *f = fopen(path, "rb");
    if (!f) return hd_fail(HD_ERR_IO, "cannot open file '%s'", path);
    size_t cap = 65536, n = 0;
    char *text = hd_malloc(cap);
    while (text) {
        size_t got = fread(text + n, 1, cap - n - 1, f);
        n += got;
        if (n < cap - 1) break;
        char *t = hd_malloc_array(cap, 2);
        if (t) memcpy(t, text, n);
        free(text);
        text = t;
        cap *= 2;
    }
    int rerr = ferror(f);
    fclose(f);
    if (!text) return HD_ERR_NOMEM;
    if (rerr) { free(text); return hd_fail(HD_ERR_IO, "%s: read error", path); }
    text[n] = 0;
    if (memchr(text, 0, n)) { free(text); return hd_fail(HD_ERR_FORMAT, "%s: not a text file (NUL byte)", path); }
    hd_status st = parse_text(c, text, path, 1);
    free(text);
    return st;
}

/* ------------------------------------------------- printing (icalc '?') */
/* binding strength of an operator node (higher binds tighter) */
static int prec(const node *e)
{
    switch (e->op) {
    case N_ADD: case N_SUB: return 1;
    case N_MUL: case N_DIV: return 2;
    case N_NEG: return 3;
    case N_POW: return 4;
    default: return 5;
    }
}

static void print_expr(FILE *fp, const node *e, const def *d);

static void print_operand(FILE *fp, const node *k, const def *d, int paren)
{
    if (paren) fputc('(', fp);
    print_expr(fp, k, d);
    if (paren) fputc(')', fp);
}

static void print_expr(FILE *fp, const node *e, const def *d)
{
    switch (e->op) {
    case N_NUM: fprintf(fp, "%.9g", e->num); return;
    case N_VAR: fputs(e->s->name, fp); return;
    case N_CHAN: fprintf(fp, "$%d", e->n); return;
    case N_ARG: case N_ACALL: {
        int i = e->op == N_ARG ? e->n : (int)e->num;
        if (d && d->pnames && i < d->nparams) fputs(d->pnames[i], fp);
        else fprintf(fp, "arg%d", i + 1);
        if (e->op == N_ARG) return;
        break;
    }
    case N_CALL: fputs(e->s->name, fp); break;
    case N_NEG:
        fputc('-', fp);
        print_operand(fp, e->k[0], d, prec(e->k[0]) < 5);
        return;
    default: {
        static const char *ops[] = { " + ", " - ", " * ", " / ", "^" };
        int p = prec(e);
        /* left operand: parenthesised when it binds less (for ^, which
         * groups to the right, also when equal); right operand: when it
         * binds less, or equally for - and / (which group to the left) */
        int lp = prec(e->k[0]) < p || (e->op == N_POW && prec(e->k[0]) <= p);
        int rp = prec(e->k[1]) < p || (prec(e->k[1]) == p && (e->op == N_SUB || e->op == N_DIV));
        print_operand(fp, e->k[0], d, lp);
        fputs(ops[e->op - N_ADD], fp);
        print_operand(fp, e->k[1], d, rp);
        return;
    }
    }
    fputc('(', fp);
    for (int i = 0; i < e->n; i++) {
        if (i) fputs(", ", fp);
        print_expr(fp, e->k[i], d);
    }
    fputc(')', fp);
}

static void print_def(FILE *fp, const sym *s)
{
    const def *d = s->top;
    fputs(s->name, fp);
    if (d->nparams >= 0) {
        fputc('(', fp);
        for (int i = 0; i < d->nparams; i++) fprintf(fp, i ? ", %s" : "%s", d->pnames ? d->pnames[i] : "?");
        fputc(')', fp);
    }
    fprintf(fp, " %c ", d->type);
    print_expr(fp, d->expr, d);
    fputs(";\n", fp);
}

/* the symbol NAME refers to from the current context */
static sym *symref(const hd_cal *c, const char *name)
{
    if (c->ctx[0] && !strchr(name, '`')) {
        char q[320];
        snprintf(q, sizeof q, "%s`%s", name, c->ctx);
        sym *s = symfind(c, q);
        if (s && s->top) return s;
    }
    return symfind(c, name);
}

int hd_cal_print(const hd_cal *c, const char *name, FILE *fp)
{
    if (name) {
        const sym *s = symref(c, name);
        if (!s || !s->top) return -1;
        print_def(fp, s);
        return 0;
    }
    for (int i = 0; i < c->nsyms; i++)
        if (c->syms[i]->top) print_def(fp, c->syms[i]);
    return 0;
}

void hd_cal_undefine(hd_cal *c, const char *name, int all)
{
    for (int i = 0; i < c->nsyms; i++) {
        sym *s = c->syms[i];
        if (name && s != symref(c, name)) continue;
        if (!name && c->ctx[0]) {       /* "*": only the current context's names */
            const char *b = strchr(s->name, '`');
            if (!b || strcmp(b + 1, c->ctx)) continue;
        }
        if (all) s->top = NULL;
        else while (s->top && s->top->type == '=') s->top = s->top->below;
    }
    c->gen++;
}

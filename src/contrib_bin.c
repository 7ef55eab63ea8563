/* heliodon — rcontrib bin functions: the standard .cal forms (see contrib.h). */
#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <pthread.h>
#include <stdio.h>

#include "heliodon/cal.h"
#include "heliodon/contrib.h"
#include "cal_internal.h"

/* ---- the shared .cal context of an rcontrib command line ---- */
typedef struct hd_calshare {
    hd_cal *cal;
    int refs;
    unsigned long serial;          /* identifies the context in thread caches */
    pthread_mutex_t lock;
    hd_calrun **runs;              /* one per evaluating thread */
    int nruns;
} hd_calshare;

typedef struct dstate { hd_vec3 D; } dstate;

static double v_dx(hd_calrun *r, void *u, int n, const double *a) { (void)u; (void)n; (void)a; const dstate *d = hd_calrun_user(r); return d ? d->D.x : 0.0; }
static double v_dy(hd_calrun *r, void *u, int n, const double *a) { (void)u; (void)n; (void)a; const dstate *d = hd_calrun_user(r); return d ? d->D.y : 0.0; }
static double v_dz(hd_calrun *r, void *u, int n, const double *a) { (void)u; (void)n; (void)a; const dstate *d = hd_calrun_user(r); return d ? d->D.z : 0.0; }

static void rc_warn(void *user, const char *msg)
{
    (void)user;
    fprintf(stderr, "%s: %s\n", hd_progname(), msg);
}

static pthread_mutex_t serial_lock = PTHREAD_MUTEX_INITIALIZER;
static unsigned long next_serial = 1;

static hd_calshare *share_new(int quiet)
{
    hd_calshare *s = hd_calloc(1, sizeof *s);
    if (!s) return NULL;
    s->cal = hd_cal_new();
    if (!s->cal) { free(s); return NULL; }
    s->refs = 1;
    pthread_mutex_lock(&serial_lock);
    s->serial = next_serial++;
    pthread_mutex_unlock(&serial_lock);
    pthread_mutex_init(&s->lock, NULL);
    hd_cal_set_context(s->cal, "RC.");
    hd_cal_redefw(s->cal, 1);
    hd_cal_set_warn(s->cal, rc_warn, NULL);
    if (quiet) hd_cal_warnings(s->cal, 0);
    hd_cal_set_context(s->cal, NULL);
    hd_cal_set(s->cal, "PI", 3.14159265358979323846, 1);
    hd_cal_define_fn(s->cal, "Dx", 0, 0, v_dx, NULL, 0);
    hd_cal_define_fn(s->cal, "Dy", 0, 0, v_dy, NULL, 0);
    hd_cal_define_fn(s->cal, "Dz", 0, 0, v_dz, NULL, 0);
    hd_cal_set_context(s->cal, "RC.");
    return s;
}

static void share_unref(hd_calshare *s)
{
    if (!s || --s->refs > 0) return;
    for (int i = 0; i < s->nruns; i++) {
        free(hd_calrun_user(s->runs[i]));
        hd_calrun_free(s->runs[i]);
    }
    free(s->runs);
    pthread_mutex_destroy(&s->lock);
    hd_cal_free(s->cal);
    free(s);
}

/* this thread's run of context s */
static hd_calrun *share_run(hd_calshare *s)
{
    enum { NTL = 8 };
    static _Thread_local struct { unsigned long serial; hd_calrun *run; } tl[NTL];
    static _Thread_local int tl_next;
    for (int i = 0; i < NTL; i++)
        if (tl[i].serial == s->serial) return tl[i].run;
    dstate *d = hd_calloc(1, sizeof *d);
    hd_calrun *r = d ? hd_calrun_new(s->cal, d) : NULL;
    if (!r) { free(d); return NULL; }
    pthread_mutex_lock(&s->lock);
    hd_calrun **nr = hd_realloc_array(s->runs, (size_t)s->nruns + 1, sizeof *nr);
    if (nr) { s->runs = nr; s->runs[s->nruns++] = r; }
    pthread_mutex_unlock(&s->lock);
    if (!nr) { hd_calrun_free(r); free(d); return NULL; }
    tl[tl_next].serial = s->serial;
    tl[tl_next].run = r;
    tl_next = (tl_next + 1) % NTL;
    return r;
}

void hd_calctx_init(hd_calctx *c)
{
    memset(c, 0, sizeof *c);
}

void hd_calctx_free(hd_calctx *c)
{
    share_unref(c->share);
    for (int i = 0; i < c->nlog; i++) free(c->log[i].text);
    free(c->log);
    memset(c, 0, sizeof *c);
}

static hd_status apply(hd_calshare *s, char kind, const char *text)
{
    hd_status st = kind == 'f' ? hd_cal_load(s->cal, text) : hd_cal_parse(s->cal, text, NULL);
    if (st != HD_OK && kind == 'f' && st != HD_ERR_IO) return hd_fail_context(st, "-f %s", text);
    if (st != HD_OK && kind == 'e') return hd_fail_context(st, "-e");
    return st;
}

static hd_status logged(hd_calctx *c, char kind, const char *text)
{
    if (!c->share && !(c->share = share_new(0))) return HD_ERR_NOMEM;
    hd_status st = apply(c->share, kind, text);
    if (st != HD_OK) return st;
    void *nl = hd_realloc_array(c->log, (size_t)c->nlog + 1, sizeof *c->log);
    if (!nl) return HD_ERR_NOMEM;
    c->log = nl;
    c->log[c->nlog].kind = kind;
    c->log[c->nlog].text = hd_strdup(text);
    if (!c->log[c->nlog].text) return HD_ERR_NOMEM;
    c->nlog++;
    return HD_OK;
}

hd_status hd_calctx_file(hd_calctx *c, const char *path) { return logged(c, 'f', path); }

hd_status hd_calctx_assign(hd_calctx *c, const char *text, int params)
{
    (void)params;
    return logged(c, 'e', text);
}

void hd_binfn_free(hd_binfn *b)
{
    share_unref(b->cal);
    b->cal = NULL;
    free(b->rcargs);
    b->rcargs = NULL;
    free(b->kb);
    if (b->sky) {
        hd_skybasis_free(b->sky);
        free(b->sky);
    }
    b->kb = NULL;
    b->sky = NULL;
}

static hd_status make_frame(hd_binfn *b, const char *what)
{
    double nl = hd_vlen(b->n);
    if (!(nl > 0)) return hd_fail(HD_ERR_RANGE, "%s: zero normal vector", what);
    b->az = hd_vscale(b->n, 1 / nl);
    hd_vec3 u = hd_vsub(b->u, hd_vscale(b->az, hd_vdot(b->u, b->az)));
    double ul = hd_vlen(u);
    if (!(ul > 1e-9 * (hd_vlen(b->u) + 1e-300)))
        return hd_fail(HD_ERR_RANGE, "%s: up vector parallel to the normal", what);
    b->ay = hd_vscale(u, 1 / ul);
    b->ax = hd_vscale(hd_vcross(b->ay, b->az), b->rhs);
    return HD_OK;
}

hd_status hd_binfn_klems(hd_binfn *b, hd_klems_kind kk, hd_vec3 n, hd_vec3 u, double rhs)
{
    memset(b, 0, sizeof *b);
    b->kind = HD_BIN_KLEMS;
    b->n = n;
    b->u = u;
    b->rhs = rhs < 0 ? -1 : 1;
    b->kb = hd_malloc(sizeof *b->kb);
    if (!b->kb) return HD_ERR_NOMEM;
    hd_klems_standard(b->kb, kk);
    b->nbins = b->kb->nbins;
    hd_status st = make_frame(b, "kbin");
    if (st != HD_OK) hd_binfn_free(b);
    return st;
}

static hd_status init_sky(hd_binfn *b, int mf)
{
    if (mf < 1 || mf > HD_SKY_MAXMF) return hd_fail(HD_ERR_RANGE, "MF=%d out of range 1..%d", mf, HD_SKY_MAXMF);
    b->mf = mf;
    b->sky = hd_calloc(1, sizeof *b->sky);
    if (!b->sky) return HD_ERR_NOMEM;
    hd_status st = hd_skybasis_init(b->sky, mf);
    if (st != HD_OK) { free(b->sky); b->sky = NULL; }
    return st;
}

hd_status hd_binfn_reinhartb(hd_binfn *b, int mf, hd_vec3 rn, hd_vec3 u, double rhs, double jtr)
{
    memset(b, 0, sizeof *b);
    b->kind = HD_BIN_REINHARTB;
    b->n = rn;
    b->u = u;
    b->rhs = rhs < 0 ? -1 : 1;
    b->jtr = jtr;
    hd_status st = init_sky(b, mf);
    if (st != HD_OK) return st;
    b->nbins = b->sky->nbins - 1;
    return HD_OK;
}

/* -p "a=1,b=2" as .cal text (commas separate assignments) */
static hd_status params_text(const char *p, char *buf, size_t cap)
{
    if (strlen(p) + 1 > cap) return hd_fail(HD_ERR_RANGE, "-p %s: too long", p);
    size_t n = 0;
    for (; *p; p++) buf[n++] = *p == ',' ? ';' : *p;
    buf[n] = 0;
    return HD_OK;
}

hd_status hd_binfn_parse(hd_binfn *b, const hd_calctx *c, const char *params,
                         const char *expr, const char *count)
{
    memset(b, 0, sizeof *b);
    const char *e = expr ? expr : "0";
    while (isspace((unsigned char)*e)) e++;
    char *end;
    double cv = strtod(e, &end);
    while (end != e && isspace((unsigned char)*end)) end++;
    int literal = end != e && !*end;
    if (literal && cv != 0)
        return hd_fail(HD_ERR_USAGE, "illegal non-zero constant for bin (%s)", e);
    if (literal && cv == 0) {
        /* the default "-b 0": no expression to evaluate per ray */
        long n = 1;
        if (count) {
            char *ce;
            n = strtol(count, &ce, 10);
            while (isspace((unsigned char)*ce)) ce++;
            if (*ce || ce == count) n = -1;
        }
        if (n >= 1 && n < 100000000) {
            b->kind = HD_BIN_CONST;
            b->nbins = (int)n;
            return HD_OK;
        }
    }
    /* the shared context, or (with -p) a context of this modifier's own:
     * the definitions so far, then the parameters */
    hd_calshare *s;
    hd_status st = HD_OK;
    if (params && *params) {
        if (!(s = share_new(1))) return HD_ERR_NOMEM;
        for (int i = 0; i < c->nlog && st == HD_OK; i++) st = apply(s, c->log[i].kind, c->log[i].text);
        char pt[1024];
        if (st == HD_OK) st = params_text(params, pt, sizeof pt);
        if (st == HD_OK && (st = hd_cal_parse(s->cal, pt, NULL)) != HD_OK) st = hd_fail_context(st, "-p %s", params);
    } else {
        s = c->share;
        if (s) s->refs++;
        else if (!(s = share_new(0))) return HD_ERR_NOMEM;
    }
    b->kind = HD_BIN_CAL;
    b->cal = s;
    if (st == HD_OK && (st = hd_cal_expr(s->cal, e, NULL, &b->expr)) != HD_OK)
        st = hd_fail_context(st, "-b %s", e);
    double nb = 1;
    if (st == HD_OK && count) {
        int id;
        if ((st = hd_cal_expr(s->cal, count, NULL, &id)) != HD_OK) {
            st = hd_fail_context(st, "-bn %s", count);
        } else {
            hd_calrun *r = share_run(s);
            if (!r) st = HD_ERR_NOMEM;
            else {
                hd_calrun_next(r);
                nb = hd_calrun_expr(r, id);
                if ((st = hd_calrun_status(r)) != HD_OK) {
                    hd_calrun_clear(r);
                    st = hd_fail_context(st, "-bn %s", count);
                }
            }
        }
    }
    if (st == HD_OK && !(nb >= 0.5 && nb < 1e8))
        st = hd_fail(HD_ERR_USAGE, "-bn %s: bin count %g out of range", count, nb);
    if (st != HD_OK) {
        hd_binfn_free(b);
        return st;
    }
    b->nbins = (int)(nb + .5);
    return HD_OK;
}

int hd_binfn_eval(const hd_binfn *b, hd_vec3 D, double jr1, double jr2)
{
    int bin = -1;
    switch (b->kind) {
    case HD_BIN_CONST:
        bin = 0;
        break;
    case HD_BIN_HEMI:
        bin = hd_vdot(D, b->n) < 0 ? 0 : -1;
        break;
    case HD_BIN_KLEMS: {
        hd_vec3 v = hd_v3(-hd_vdot(D, b->ax), -hd_vdot(D, b->ay), -hd_vdot(D, b->az));
        if (!(v.z > 0)) return -1;
        bin = hd_klems_bin(b->kb, v);
        break;
    }
    case HD_BIN_REINHARTB: {
        hd_vec3 rn = b->n, u = b->u;
        double dz = -hd_vdot(D, rn);
        if (!(dz > 0)) return -1;
        double rx = -b->rhs * hd_vdot(D, hd_vcross(u, rn));
        double ry = hd_vdot(D, u) + dz * hd_vdot(rn, u);
        hd_vec3 d = hd_v3(rx, ry, dz);
        if (b->jtr > 0) {
            /* jitter the bin boundaries: perturb altitude and azimuth by up to
             * ±JTR/2 of a band height */
            double alt = asin(fmin(1, dz / hd_vlen(d))), azi = atan2(rx, ry);
            alt += b->jtr * (jr1 - 0.5) * b->sky->alpha;
            azi += b->jtr * (jr2 - 0.5) * b->sky->alpha / fmax(cos(alt), 0.05);
            if (alt <= 0) return -1;
            if (alt > HD_PI / 2) alt = HD_PI / 2;
            d = hd_v3(sin(azi) * cos(alt), cos(azi) * cos(alt), sin(alt));
        }
        bin = hd_skybasis_bin(b->sky, d) - 1;
        break;
    }
    case HD_BIN_REINHART:
        bin = hd_skybasis_bin(b->sky, D);
        break;
    case HD_BIN_CAL: {
        hd_calrun *r = share_run(b->cal);
        if (!r) return -1;
        ((dstate *)hd_calrun_user(r))->D = D;
        hd_calrun_next(r);
        double v = hd_calrun_expr(r, b->expr);
        if (hd_calrun_status(r) != HD_OK) {
            /* a fatal .cal error (undefined name ...) stops the run as
             * Radiance does */
            char msg[512];
            hd_strlcpy(msg, hd_errmsg(), sizeof msg);
            hd_die_msg("%s", msg);
        }
        if (!(v > -0.5)) return -1;           /* negatives: silently ignored */
        bin = (int)fmin(v + .5, 2e9);
        if (bin >= b->nbins) {
            static _Atomic int warned;
            if (!warned++) hd_warn("bad bin number (%d ignored)", bin);
            return -1;
        }
        break;
    }
    }
    if (bin >= b->nbins) return -1;
    return bin;
}

/* heliodon — brightfunc patterns of emitting materials (light, glow,
 * illum: skies and luminaires) evaluated with the .cal module: any
 * function file, the variable named by the primitive's first string, the
 * ray direction as Dx Dy Dz (in the pattern's own frame when the primitive
 * carries a transform), the real arguments as arg(n), A1..A10 and AC.
 * Every context loads rayinit.cal first, as Radiance does.
 *
 * Evaluation is thread-safe: each pattern keeps a few evaluation runs that
 * threads take with an atomic flag (a new one when all are busy). */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/cal.h"
#include "heliodon/material.h"
#include "heliodon/xform.h"

#define CP_SLOTS 64

typedef struct cp_slot {
    atomic_int busy;
    hd_calrun *run;           /* its user pointer is this slot */
    hd_vec3 dir;              /* the direction being evaluated by this run */
    const struct hd_calpat *owner;
} cp_slot;

struct hd_calpat {
    hd_cal *cal;
    int var;                  /* handle of the pattern variable */
    int nargs;
    double args[HD_MAT_MAXPARG];
    int has_xf;
    double rinv[3][3];        /* world -> pattern frame for directions */
    cp_slot slot[CP_SLOTS];
};

static double f_arg(hd_calrun *r, void *u, int na, const double *a)
{
    (void)r; (void)na;
    const struct hd_calpat *p = u;
    int n = (int)(a[0] + .5);
    if (n == 0) return p->nargs;
    return n >= 1 && n <= p->nargs ? p->args[n - 1] : 0.;
}

static double f_an(hd_calrun *r, void *u, int na, const double *a)
{
    (void)a; (void)na;
    const struct hd_calpat *p = ((const cp_slot *)hd_calrun_user(r))->owner;
    int n = (int)(intptr_t)u;
    if (n == 0) return p->nargs;
    return n <= p->nargs ? p->args[n - 1] : 0.;
}

static double f_dir(hd_calrun *r, void *u, int na, const double *a)
{
    (void)a; (void)na;
    const cp_slot *s = hd_calrun_user(r);
    int c = (int)(intptr_t)u;
    return c == 0 ? s->dir.x : c == 1 ? s->dir.y : s->dir.z;
}

static double f_zero(hd_calrun *r, void *u, int na, const double *a)
{
    (void)r; (void)u; (void)na; (void)a;
    return 0.;
}

void hd_calpat_free(struct hd_calpat *p)
{
    if (!p) return;
    for (int k = 0; k < CP_SLOTS; k++)
        if (p->slot[k].run) hd_calrun_free(p->slot[k].run);
    hd_cal_free(p->cal);
    free(p);
}

double hd_calpat_eval(struct hd_calpat *p, hd_vec3 dir)
{
    if (p->has_xf)
        dir = hd_v3(p->rinv[0][0] * dir.x + p->rinv[0][1] * dir.y + p->rinv[0][2] * dir.z,
                    p->rinv[1][0] * dir.x + p->rinv[1][1] * dir.y + p->rinv[1][2] * dir.z,
                    p->rinv[2][0] * dir.x + p->rinv[2][1] * dir.y + p->rinv[2][2] * dir.z);
    for (int k = 0; k < CP_SLOTS; k++) {
        cp_slot *s = &p->slot[k];
        if (atomic_exchange_explicit(&s->busy, 1, memory_order_acquire)) continue;
        if (!s->run && !(s->run = hd_calrun_new(p->cal, s))) {
            atomic_store_explicit(&s->busy, 0, memory_order_release);
            return 0.;
        }
        s->dir = dir;
        hd_calrun_next(s->run);
        double v = hd_calrun_var_id(s->run, p->var);
        if (hd_calrun_status(s->run)) { v = 0.; hd_calrun_clear(s->run); }
        atomic_store_explicit(&s->busy, 0, memory_order_release);
        return v;
    }
    return 0.;     /* more than CP_SLOTS threads at once: not reached with the pools */
}

hd_status hd_calpat_new(struct hd_calpat **out, char *const *sargs, int ns, const double *r, int nr,
                        const char *where)
{
    *out = NULL;
    if (ns < 2) return hd_fail(HD_ERR_FORMAT, "%s: brightfunc: expected a variable and a function file", where);
    if (nr > HD_MAT_MAXPARG)
        return hd_fail(HD_ERR_UNSUPPORTED, "%s: brightfunc %s: at most %d real arguments", where, sargs[0],
                       HD_MAT_MAXPARG);
    struct hd_calpat *p = calloc(1, sizeof *p);
    if (!p) return HD_ERR_NOMEM;
    for (int k = 0; k < CP_SLOTS; k++) p->slot[k].owner = p;
    p->nargs = nr;
    for (int i = 0; i < nr; i++) p->args[i] = r[i];
    hd_status st = HD_OK;
    if (ns > 2) {
        hd_xf xf;
        if ((st = hd_xf_from_words(&xf, ns - 2, sargs + 2))) {
            free(p);
            return hd_fail_context(st, "%s: brightfunc %s transform", where, sargs[0]);
        }
        p->has_xf = 1;
        for (int i = 0; i < 3; i++)          /* inverse rotation = transpose */
            for (int j = 0; j < 3; j++) p->rinv[i][j] = xf.m[j][i] / xf.sca;
    }
    if (!(p->cal = hd_cal_new())) { free(p); return HD_ERR_NOMEM; }
    static const char *dirs[3] = {"Dx", "Dy", "Dz"};
    static const char *zero[] = {"Px", "Py", "Pz", "Nx", "Ny", "Nz", "Rdot", "T", "Ts", "S"};
    static const char *an[11] = {"AC", "A1", "A2", "A3", "A4", "A5", "A6", "A7", "A8", "A9", "A10"};
    for (int k = 0; k < 3 && !st; k++) st = hd_cal_define_fn(p->cal, dirs[k], 0, 0, f_dir, (void *)(intptr_t)k, 0);
    for (size_t k = 0; k < sizeof zero / sizeof *zero && !st; k++)
        st = hd_cal_define_fn(p->cal, zero[k], 0, 0, f_zero, NULL, 0);
    if (!st) st = hd_cal_define_fn(p->cal, "arg", 1, 1, f_arg, p, 0);
    for (int k = 0; k < 11 && !st; k++) st = hd_cal_define_fn(p->cal, an[k], 0, 0, f_an, (void *)(intptr_t)k, 0);
    if (!st) st = hd_cal_load(p->cal, "rayinit.cal");
    if (!st && strcmp(sargs[1], ".")) st = hd_cal_load(p->cal, sargs[1]);
    if (!st && (p->var = hd_cal_lookup(p->cal, sargs[0])) < 0)
        st = hd_fail(HD_ERR_FORMAT, "%s: brightfunc: '%s' is not defined in %s", where, sargs[0], sargs[1]);
    if (!st) {                           /* one evaluation now: errors here, not per ray */
        hd_calrun *run = hd_calrun_new(p->cal, &p->slot[0]);
        if (!run) st = HD_ERR_NOMEM;
        else {
            p->slot[0].run = run;
            p->slot[0].dir = hd_v3(0, 0, 1);
            hd_calrun_next(run);
            (void)hd_calrun_var_id(run, p->var);
            if ((st = hd_calrun_status(run))) hd_calrun_clear(run);
        }
    }
    if (st) {
        hd_calpat_free(p);
        return hd_fail_context(st, "%s: brightfunc %s %s", where, sargs[0], sargs[1]);
    }
    *out = p;
    return HD_OK;
}

/* heliodon — the .cal function language (Radiance's calcomp syntax and
 * semantics) as one module.
 *
 * A context (hd_cal) holds definitions: variables `name = expr`, constants
 * `name : expr`, functions `f(a,b) = expr`, output/input channels `$N`,
 * C callbacks (li(n), x, y ...).  Definitions come from strings (-e) or
 * files (-f, looked up through RAYPATH) and are compiled on entry to a
 * compact form (constant folding, names resolved at first use).
 *
 * Evaluation happens in an hd_calrun: per-thread state (cached variable
 * values for the current record, the $N channel callback, error flag).  Any
 * number of runs may evaluate one context in parallel as long as nobody
 * adds definitions at the same time.  Definitions added after a run was made
 * are seen by it from its next hd_calrun_next().
 *
 * Semantics follow Radiance: a variable's value is computed once per record
 * (hd_calrun_next starts a new record) unless it is a constant; function
 * arguments are evaluated when used; `if(c,a,b)` takes a when c > 0;
 * `select(n,a1,a2,..)` returns argument n (rounded; n = 0 gives the count).
 *
 * Errors.  Syntax errors (HD_ERR_FORMAT) name the source, line and column
 * and quote the line with a caret.  Run-time problems Radiance treats as
 * warnings ("Division by zero", "sqrt(): domain error" ...) give 0 and are
 * reported through the warning sink (stderr, no program prefix, unless
 * disabled).  Fatal run-time errors ("foo: undefined variable",
 * "bar(): undefined function", "f(): too few arguments") make the evaluation
 * return 0, set the run's status and leave the message in hd_errmsg(). */
#ifndef HELIODON_CAL_H
#define HELIODON_CAL_H

#include <stddef.h>
#include "common.h"

typedef struct hd_cal hd_cal;
typedef struct hd_calrun hd_calrun;

/* Callback for a C function (nargs evaluated arguments).  `user` is the
 * pointer given at definition, `run` the evaluating run (for
 * hd_calrun_user()).  A callback defined with 0 arguments is used by the
 * expressions as a variable (`x`), not cached: it is called at each use. */
typedef double (*hd_cal_fn)(hd_calrun *run, void *user, int nargs, const double *args);
/* Callback for input channels $N (n >= 1). */
typedef double (*hd_cal_chanfn)(hd_calrun *run, void *user, int n);
/* Warning sink: message without newline.  Default prints "msg\n" to stderr. */
typedef void (*hd_cal_warnfn)(void *user, const char *msg);

#define HD_CAL_ANYARGS (-1)  /* maxargs of a variadic callback */

/* ---- contexts ---- */
hd_cal *hd_cal_new(void);            /* with the built-in functions defined */
void hd_cal_free(hd_cal *c);

/* Parse definitions "a=1; f(x)=x*x; $1=f($2)" (like -e).  `origin` names
 * the text in messages (e.g. "-e" or a file path); line numbers start at 1.
 * Redefining a constant gives the warning "NAME: constant redefined" and
 * the new definition (Radiance's rcalc behaviour). */
hd_status hd_cal_parse(hd_cal *c, const char *text, const char *origin);
/* Load a file of definitions (like -f).  A name without '/' is searched in
 * RAYPATH (hd_cal_findfile).  Missing file: HD_ERR_IO
 * "cannot find file 'NAME'". */
hd_status hd_cal_load(hd_cal *c, const char *name);
/* RAYPATH search: each RAYPATH entry (colon-separated; "." when RAYPATH is
 * unset), then the installed library directory and the source tree's lib/
 * (so that the standard .cal files are found whatever RAYPATH holds).
 * Returns buf or NULL. */
const char *hd_cal_findfile(const char *name, char *buf, size_t cap);

/* The file NAME of heliodon's own library (installed, then the source
 * tree's lib/), whatever RAYPATH holds; NULL if it has none. */
const char *hd_cal_libfile(const char *name, char *buf, size_t cap);

/* name = v (constant != 0: name : v).  Overrides a previous definition. */
hd_status hd_cal_set(hd_cal *c, const char *name, double v, int constant);
/* Define a C function or (nargs 0) C variable.  minargs..maxargs
 * (HD_CAL_ANYARGS = no limit).  pure != 0: result depends only on the
 * arguments (allows constant folding); otherwise never folded. */
hd_status hd_cal_define_fn(hd_cal *c, const char *name, int minargs, int maxargs,
                           hd_cal_fn fn, void *user, int pure);
/* Context suffix used for names defined afterwards (rcontrib "RC."):
 * NAME becomes NAME`CTX in messages; lookups try NAME`CTX then NAME.
 * NULL or "" = none. */
hd_status hd_cal_set_context(hd_cal *c, const char *ctx);

/* Compile an anonymous expression ("rbin", "$1*2+x") and return its id
 * (>= 0) in *id, to evaluate with hd_calrun_expr. */
hd_status hd_cal_expr(hd_cal *c, const char *text, const char *origin, int *id);

/* Whether NAME is defined (as variable, constant or function; 1/0), and
 * whether it is a constant. */
int hd_cal_defined(const hd_cal *c, const char *name);
int hd_cal_is_const(const hd_cal *c, const char *name);
/* Number of parameters of NAME's definition in force: -1 for a variable,
 * -2 if undefined (built-ins: their least number of arguments). */
int hd_cal_nparams(const hd_cal *c, const char *name);
/* Highest output channel $N defined (0 if none). */
int hd_cal_max_outchan(const hd_cal *c);
/* Warnings: sink and on/off (-w).  Off by hd_set_warnings(0) as well. */
void hd_cal_set_warn(hd_cal *c, hd_cal_warnfn fn, void *user);
void hd_cal_warnings(hd_cal *c, int on);

/* ---- evaluation (one hd_calrun per thread) ---- */
hd_calrun *hd_calrun_new(const hd_cal *c, void *user);
void hd_calrun_free(hd_calrun *r);
void *hd_calrun_user(const hd_calrun *r);
void hd_calrun_set_chan(hd_calrun *r, hd_cal_chanfn fn, void *user);
/* New record: forget cached variable values (constants stay). */
void hd_calrun_next(hd_calrun *r);
/* Status of the run: HD_OK, or the first fatal error since the last
 * hd_calrun_clear (message in hd_errmsg() of the evaluating thread). */
hd_status hd_calrun_status(const hd_calrun *r);
void hd_calrun_clear(hd_calrun *r);

/* Value of variable NAME (fatal "NAME: undefined variable" if none). */
double hd_calrun_var(hd_calrun *r, const char *name);
/* Call function NAME with nargs values (a variable when nargs == 0). */
double hd_calrun_call(hd_calrun *r, const char *name, int nargs, const double *args);
/* Output channel $n (fatal if undefined). */
double hd_calrun_outchan(hd_calrun *r, int n);
/* Expression compiled by hd_cal_expr. */
double hd_calrun_expr(hd_calrun *r, int id);

/* Resolve NAME once to a handle, for loops (-1 if undefined now). */
int hd_cal_lookup(const hd_cal *c, const char *name);
double hd_calrun_var_id(hd_calrun *r, int handle);
double hd_calrun_call_id(hd_calrun *r, int handle, int nargs, const double *args);

/* One-shot convenience: evaluate an expression text in a fresh run of c. */
hd_status hd_cal_eval(hd_cal *c, const char *text, double *out);

#endif

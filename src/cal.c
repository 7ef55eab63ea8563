/* heliodon — .cal language module (see include/heliodon/cal.h).
 * First commit: the public API with a placeholder implementation that
 * refuses everything (HD_ERR_UNSUPPORTED); the evaluator follows. */
#include <stdlib.h>
#include "heliodon/cal.h"

struct hd_cal { int dummy; };
struct hd_calrun { const hd_cal *c; void *user; hd_status st; };

#define NOTYET hd_fail(HD_ERR_UNSUPPORTED, ".cal language: not implemented yet")

hd_cal *hd_cal_new(void) { return hd_calloc(1, sizeof(hd_cal)); }
void hd_cal_free(hd_cal *c) { free(c); }
hd_status hd_cal_parse(hd_cal *c, const char *t, const char *o) { (void)c; (void)t; (void)o; return NOTYET; }
hd_status hd_cal_load(hd_cal *c, const char *n) { (void)c; (void)n; return NOTYET; }
const char *hd_cal_findfile(const char *n, char *b, size_t cap) { (void)n; (void)b; (void)cap; return NULL; }
hd_status hd_cal_set(hd_cal *c, const char *n, double v, int k) { (void)c; (void)n; (void)v; (void)k; return NOTYET; }
hd_status hd_cal_define_fn(hd_cal *c, const char *n, int a, int b, hd_cal_fn f, void *u, int p)
{ (void)c; (void)n; (void)a; (void)b; (void)f; (void)u; (void)p; return NOTYET; }
hd_status hd_cal_set_context(hd_cal *c, const char *x) { (void)c; (void)x; return NOTYET; }
hd_status hd_cal_expr(hd_cal *c, const char *t, const char *o, int *id) { (void)c; (void)t; (void)o; *id = -1; return NOTYET; }
int hd_cal_defined(const hd_cal *c, const char *n) { (void)c; (void)n; return 0; }
int hd_cal_is_const(const hd_cal *c, const char *n) { (void)c; (void)n; return 0; }
int hd_cal_max_outchan(const hd_cal *c) { (void)c; return 0; }
void hd_cal_set_warn(hd_cal *c, hd_cal_warnfn f, void *u) { (void)c; (void)f; (void)u; }
void hd_cal_warnings(hd_cal *c, int on) { (void)c; (void)on; }
hd_calrun *hd_calrun_new(const hd_cal *c, void *u)
{ hd_calrun *r = hd_calloc(1, sizeof *r); if (r) { r->c = c; r->user = u; } return r; }
void hd_calrun_free(hd_calrun *r) { free(r); }
void *hd_calrun_user(const hd_calrun *r) { return r->user; }
void hd_calrun_set_chan(hd_calrun *r, hd_cal_chanfn f, void *u) { (void)r; (void)f; (void)u; }
void hd_calrun_next(hd_calrun *r) { (void)r; }
hd_status hd_calrun_status(const hd_calrun *r) { return r->st; }
void hd_calrun_clear(hd_calrun *r) { r->st = HD_OK; }
double hd_calrun_var(hd_calrun *r, const char *n) { (void)n; r->st = NOTYET; return 0; }
double hd_calrun_call(hd_calrun *r, const char *n, int k, const double *a) { (void)n; (void)k; (void)a; r->st = NOTYET; return 0; }
double hd_calrun_outchan(hd_calrun *r, int n) { (void)n; r->st = NOTYET; return 0; }
double hd_calrun_expr(hd_calrun *r, int id) { (void)id; r->st = NOTYET; return 0; }
int hd_cal_lookup(const hd_cal *c, const char *n) { (void)c; (void)n; return -1; }
double hd_calrun_var_id(hd_calrun *r, int h) { (void)h; r->st = NOTYET; return 0; }
double hd_calrun_call_id(hd_calrun *r, int h, int k, const double *a) { (void)h; (void)k; (void)a; r->st = NOTYET; return 0; }
hd_status hd_cal_eval(hd_cal *c, const char *t, double *o) { (void)c; (void)t; *o = 0; return NOTYET; }

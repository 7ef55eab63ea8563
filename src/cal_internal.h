/* heliodon — .cal module: internal entry points for the record programs
 * (rcalc, ev) beyond the public include/heliodon/cal.h. */
#ifndef HD_CAL_INTERNAL_H
#define HD_CAL_INTERNAL_H
#include <stdio.h>
#include "heliodon/cal.h"

/* whether output channel $n is defined */
int hd_cal_has_outchan(const hd_cal *c, int n);
/* ev: names must be calls "f(...)"; a bare name is a syntax error */
void hd_cal_novars(hd_cal *c, int on);
/* constant folding and "constant redefined" warnings (on by default;
 * rcalc -n turns them off as Radiance's does) */
void hd_cal_rconst(hd_cal *c, int on);
/* warn "NAME: redefined" for every changed definition (rcontrib) */
void hd_cal_redefw(hd_cal *c, int on);
/* whether NAME was ever mentioned (defined or referenced) */
int hd_cal_named(const hd_cal *c, const char *name);
/* NAME's definition: -1 a variable, n >= 0 a function of n parameters
 * (built-ins: their minimum), -2 undefined */
int hd_cal_nparams(const hd_cal *c, const char *name);
/* icalc: "$N = ..." is a syntax error ("illegal variable name"); a bare
 * '$' in an expression is $0 */
void hd_cal_nooutchan(hd_cal *c, int on);
/* Print NAME's definition ("f(a, b) = expr;"), or every definition when
 * NAME is NULL, in the order the names appeared.  -1 if NAME is undefined. */
int hd_cal_print(const hd_cal *c, const char *name, FILE *fp);
/* Remove NAME's '=' definitions (all != 0: every definition); NAME NULL:
 * every name of the current context (all names when there is none). */
void hd_cal_undefine(hd_cal *c, const char *name, int all);
#endif

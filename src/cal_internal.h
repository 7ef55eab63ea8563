/* heliodon — .cal module: internal entry points for the record programs
 * (rcalc, ev) beyond the public include/heliodon/cal.h. */
#ifndef HD_CAL_INTERNAL_H
#define HD_CAL_INTERNAL_H
#include "heliodon/cal.h"

/* whether output channel $n is defined */
int hd_cal_has_outchan(const hd_cal *c, int n);
/* ev: names must be calls "f(...)"; a bare name is a syntax error */
void hd_cal_novars(hd_cal *c, int on);
/* whether any parsed expression reads an input channel $N */
int hd_cal_uses_inchan(const hd_cal *c);
/* constant folding and "constant redefined" warnings (on by default;
 * rcalc -n turns them off as Radiance's does) */
void hd_cal_rconst(hd_cal *c, int on);
/* warn "NAME: redefined" for every changed definition (rcontrib) */
void hd_cal_redefw(hd_cal *c, int on);
/* whether NAME was ever mentioned (defined or referenced) */
int hd_cal_named(const hd_cal *c, const char *name);
#endif

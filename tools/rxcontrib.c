/* rxcontrib — Radiance 6's newer name for rcontrib (same options and
 * outputs, -r recovers as in rcontrib): the same program as rcontrib. */
#include "rcontrib.c"

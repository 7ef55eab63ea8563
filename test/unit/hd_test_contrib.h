/* heliodon — unit-test helper for rcontrib's / rfluxmtx's option parser.
 * Include after hd_test.h. */
#ifndef HD_TEST_CONTRIB_H
#define HD_TEST_CONTRIB_H

#include <string.h>

#include "heliodon/contrib.h"

/* Parse rcontrib's command line "rcontrib args..." (NULL-terminated, at
 * most 62 words) into c and o from the defaults; rflux: as rfluxmtx does. */
static inline hd_status hd_test_rc_parse(hd_contrib *c, hd_rcontrib_opts *o, int rflux, const char *const *args)
{
    char *argv[64];
    int argc = 0;
    argv[argc++] = "rcontrib";
    for (int i = 0; args[i]; i++) {
        if (argc >= 63) return hd_fail(HD_ERR_USAGE, "test: too many words");
        argv[argc++] = (char *)args[i];
    }
    argv[argc] = NULL;
    memset(c, 0, sizeof *c);
    hd_rcontrib_defaults(o, &c->o);
    o->rflux = rflux;
    int first;
    return hd_rcontrib_parse_args(argc, argv, c, o, &first);
}

#endif

/* ev — evaluate expressions given as arguments (Radiance's ev): one value
 * per line.  Functions only (built-ins); a bare name is a syntax error. */
#include <stdio.h>
#include <stdlib.h>
#include "heliodon/cal.h"
#include "cal_internal.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    hd_cal *c = hd_cal_new();
    if (!c) hd_die();
    hd_cal_novars(c, 1);
    for (int i = 1; i < argc; i++) {
        double v;
        if (hd_cal_eval(c, argv[i], &v) != HD_OK) {
            fflush(stdout);
            fprintf(stderr, "%s\n", hd_errmsg());
            return 1;
        }
        printf("%.9g\n", v);
    }
    hd_cal_free(c);
    return fflush(stdout) ? 1 : 0;
}

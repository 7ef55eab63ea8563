/* falsecolor — false-colour pictures with Radiance's falsecolor options
 * (docs/man/falsecolor.1); the work is in src/falsecolor.c. */
#include <stdio.h>
#include "heliodon/common.h"
#include "heliodon/pictools.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    /* errors exit with 255, as Radiance's falsecolor script (Perl's die) */
    if (hd_falsecolor(argc, argv, stdout) || fflush(stdout)) {
        hd_report_error();
        return 255;
    }
    return 0;
}

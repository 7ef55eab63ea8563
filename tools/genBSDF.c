/* genBSDF — generate a BSDF (Klems or tensor tree XML) from fenestration
 * geometry by ray tracing (see docs/man/genBSDF.1). */
#include "heliodon/common.h"
#include "heliodon/genbsdf.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    return hd_genbsdf_main(argc, argv, NULL);
}

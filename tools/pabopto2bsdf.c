/* pabopto2bsdf — see docs/man/pabopto2bsdf.1 (Radiance-compatible). */
#include "heliodon/rbf.h"

int main(int argc, char **argv) { return hd_pabopto2bsdf_main(argc, argv); }

/* bsdf2ttree — see docs/man/bsdf2ttree.1 (Radiance-compatible). */
#include "heliodon/rbf.h"

int main(int argc, char **argv) { return hd_bsdf2ttree_main(argc, argv); }

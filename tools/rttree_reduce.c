/* rttree_reduce — see docs/man/rttree_reduce.1 (Radiance-compatible). */
#include "heliodon/rbf.h"

int main(int argc, char **argv) { return hd_rttree_reduce_main(argc, argv); }

/* rfluxmtx — flux-transfer matrices between #@rfluxmtx senders and receivers (heliodon). */
#include "heliodon/rfluxmtx.h"

int main(int argc, char **argv)
{
    return hd_rfluxmtx_main(argc, argv);
}

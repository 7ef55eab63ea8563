/* rxfluxmtx — Radiance 6's newer name for rfluxmtx (same senders,
 * receivers, options; -r and -fo pass to the contribution engine as in
 * rfluxmtx): the same program as rfluxmtx. */
#include "heliodon/rfluxmtx.h"

int main(int argc, char **argv)
{
    return hd_rfluxmtx_main(argc, argv);
}

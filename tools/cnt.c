/* cnt — count through the index combinations of N0 x N1 x ... (Radiance's
 * cnt): one line per combination, each index preceded by a TAB, the last
 * dimension varying fastest.  -s prints the combinations in a random
 * order (a shuffled sequence of record numbers). */
#include <stdio.h>
#include <stdlib.h>
#include <stdint.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include "heliodon/common.h"

#define MAXDIM 50

static void usage(const char *prog)
{
    fprintf(stderr, "Usage: %s [-s] N0 [N1 ..]\n", prog);
    exit(1);
}

static void put_index(const long *n, int nd, uint64_t rec)
{
    long idx[MAXDIM];
    for (int d = nd - 1; d >= 0; d--) {
        idx[d] = (long)(rec % (uint64_t)n[d]);
        rec /= (uint64_t)n[d];
    }
    for (int d = 0; d < nd; d++) printf("\t%ld", idx[d]);
    putchar('\n');
}

int main(int argc, char **argv)
{
    const char *prog = argv[0];
    hd_set_progname(argv[0]);
    int shuffle = 0, a = 1;
    if (a < argc && argv[a][0] == '-' && argv[a][1] == 's') { shuffle = 1; a++; }
    long n[MAXDIM];
    int nd = 0;
    uint64_t total = 1;
    for (; a < argc; a++) {
        char *end;
        long v = strtol(argv[a], &end, 10);
        if (*end || v <= 1 || nd >= MAXDIM) usage(prog);
        n[nd++] = v;
        if (total > UINT64_MAX / (uint64_t)v) {
            fprintf(stderr, "%s: too many combinations\n", prog);
            return 1;
        }
        total *= (uint64_t)v;
    }
    if (!nd) usage(prog);
    if (!shuffle) {
        /* odometer: last index fastest */
        long idx[MAXDIM] = { 0 };
        for (uint64_t r = 0; r < total; r++) {
            for (int d = 0; d < nd; d++) printf("\t%ld", idx[d]);
            putchar('\n');
            for (int d = nd - 1; d >= 0; d--) {
                if (++idx[d] < n[d]) break;
                idx[d] = 0;
            }
        }
    } else {
        uint64_t *perm = hd_malloc_array((size_t)total, sizeof *perm);
        if (!perm) hd_die();
        for (uint64_t i = 0; i < total; i++) perm[i] = i;
        uint64_t s = (uint64_t)time(NULL) * 0x9e3779b97f4a7c15ULL ^ (uint64_t)getpid();
        for (uint64_t i = total; i > 1; i--) {
            s ^= s << 13; s ^= s >> 7; s ^= s << 17;
            uint64_t j = s % i, t = perm[i - 1];
            perm[i - 1] = perm[j];
            perm[j] = t;
        }
        for (uint64_t i = 0; i < total; i++) put_index(n, nd, perm[i]);
        free(perm);
    }
    if (fflush(stdout) || ferror(stdout)) return 1;
    return 0;
}

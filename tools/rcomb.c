/* rcomb — combine and convert matrices and pictures element by element
 * (Radiance's rcomb; docs/man/rcomb.1).  Options are read in order as
 * Radiance reads them: -c/-s apply to the next input, or to the result when
 * they follow the last input; -C sets a default -c for the inputs after it. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/io.h"
#include "heliodon/matrix.h"
#include "heliodon/rcomb.h"

static const char synopsis[] =
    "rcomb [-h][-w][-f{a|f|d|c}][-n nproc][-e expr][-f file][-C symbols|file] "
    "[-c ce ..|-c symbols|file][-s sf ..] m1 .. [-c ..][-s ..][-m[t] mcat]";

static _Noreturn void usage(const char *msg)
{
    if (msg) fprintf(stderr, "%s: %s\n", hd_progname(), msg);
    fprintf(stderr, "usage: %s\n", synopsis);
    exit(1);
}

/* numbers following argv[i] (at most max): how many */
static int factors(int argc, char **argv, int i, double *dst, int max)
{
    int k = 0;
    double v;
    while (i + 1 + k < argc && k < max && !hd_parse_double(argv[i + 1 + k], &v)) dst[k++] = v;
    return k;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    hd_rcomb_opts o;
    memset(&o, 0, sizeof o);
    o.outfmt = -1;
    o.echo_header = 1;
    o.nthreads = 1;
    o.in = hd_calloc((size_t)argc + 1, sizeof *o.in);
    const char **deftext = hd_calloc((size_t)argc + 1, sizeof *deftext);
    char *defkind = hd_calloc((size_t)argc + 1, 1);
    if (!o.in || !deftext || !defkind) hd_die();
    o.deftext = deftext;
    o.defkind = defkind;
    const char *defcsym = NULL;
    int stdin_used = 0;
    hd_rcomb_op *cur = &o.in[0].op;

    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (a[0] != '-' || !a[1]) {             /* an input */
            if (!strcmp(a, "-") && stdin_used++) usage("standard input used for more than one input");
            o.in[o.nin].spec = a;
            if (!cur->csym && !cur->clen && defcsym) cur->csym = defcsym;
            cur = &o.in[++o.nin].op;
            continue;
        }
        int rest = argc - 1 - i;
        switch (a[1]) {
        case 'w': o.nowarn = !o.nowarn; break;
        case 'h': o.echo_header = !o.echo_header; break;
        case 'n':
            if (!rest || (o.nthreads = atoi(argv[++i])) <= 0) usage("-n needs a positive count");
            break;
        case 'e':
            if (!rest) usage("-e needs an expression");
            defkind[o.ndefs] = 'e';
            deftext[o.ndefs++] = argv[++i];
            break;
        case 'f':
            switch (a[2]) {
            case 0:
                if (!rest) usage("-f needs a file");
                defkind[o.ndefs] = 'f';
                deftext[o.ndefs++] = argv[++i];
                break;
            case 'a': o.outfmt = HD_MTX_ASCII; break;
            case 'f': o.outfmt = HD_MTX_FLOAT; break;
            case 'd': o.outfmt = HD_MTX_DOUBLE; break;
            case 'c': o.outfmt = HD_MTX_RGBE; break;
            default: usage("-f needs a, f, d or c (or a file name after -f)");
            }
            break;
        case 's': {
            int n = factors(argc, argv, i, cur->sf, HD_RCOMB_MAXCOEF);
            if (!n) usage("-s missing arguments");
            cur->nsf = n;
            i += n;
            break;
        }
        case 'C': {
            double v;
            o.mcat_last = 0;
            if (!rest || !hd_parse_double(argv[i + 1], &v)) usage("-C needs component symbols or a file");
            defcsym = cur->csym = argv[++i];
            cur->clen = 0;
            break;
        }
        case 'c': {
            double v;
            o.mcat_last = 0;
            if (rest && hd_parse_double(argv[i + 1], &v)) {
                cur->csym = argv[++i];
                cur->clen = 0;
                break;
            }
            int n = factors(argc, argv, i, cur->cmat, HD_RCOMB_MAXCOEF);
            if (!n) usage("-c missing arguments");
            cur->clen = n;
            cur->csym = NULL;
            i += n;
            break;
        }
        case 'm':
            if (!rest || (a[2] && strcmp(a + 2, "t"))) usage("-m needs a matrix (-mt: transposed)");
            o.mcat_last = 1;
            o.mcat_transpose = a[2] == 't';
            o.mcat = argv[++i];
            if (!strcmp(o.mcat, "-") && stdin_used++) usage("standard input used for more than one input");
            break;
        default: {
            char msg[160];
            snprintf(msg, sizeof msg, "unknown option '%s'", a);
            usage(msg);
        }
        }
    }
    if (!o.nin) usage("need at least one input matrix");
    o.trail = *cur;                     /* -c/-s after the last input */
    hd_ofile *of;
    if (hd_ofile_open(&of, NULL)) hd_die();
    if (hd_rcomb(&o, argc, argv, hd_ofile_fp(of))) {
        fflush(stdout);
        hd_die();
    }
    if (hd_ofile_commit(of)) hd_die();
    free(o.in);
    free(deftext);
    free(defkind);
    return 0;
}

/* rlam — laminate records from several inputs side by side (Radiance's
 * rlam).  An input is a file, '-' (standard input, may repeat) or a
 * command '!cmd'.  -tS sets the separator written before the records of the
 * inputs named after it (-t alone: a newline); -ia[N] reads N lines per
 * record (default 1), -if/-id/-ii/-iw/-ib[N] N binary floats, doubles,
 * 4-byte integers, 2-byte words or bytes per record (and make the default
 * separator empty); -in M stops after M records; -u flushes every record.
 * The output ends when one of the inputs runs out (as Radiance 6.1's rlam
 * does).  A newline ends each output record when some input is ASCII. */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"

typedef struct input {
    const char *name;
    FILE *fp;
    int ispipe;
    int type;           /* 'a' or binary 'f' 'd' 'i' 'w' 'b' */
    int n;              /* values or lines per record */
    char *sep;
} input;

static size_t valsize(int type)
{
    switch (type) {
    case 'f': case 'i': return 4;
    case 'd': return 8;
    case 'w': return 2;
    default: return 1;
    }
}

static _Noreturn void usage(const char *prog)
{
    fprintf(stderr, "Usage: %s [-tS][-u][-ia[N]|-if[N]|-id[N]|-ii[N]|-iw[N]|-ib[N]][-in M] input1 [options] input2 ..\n", prog);
    exit(1);
}

int main(int argc, char **argv)
{
    const char *prog = argv[0];
    hd_set_progname(prog);
    input *in = hd_calloc((size_t)argc + 1, sizeof *in);
    if (!in) hd_die();
    int nin = 0, type = 'a', n = 1, unbuf = 0, sepset = 0;
    long maxrec = 0;
    char *sep = "\t";
    for (int a = 1; a < argc; a++) {
        const char *w = argv[a];
        if (w[0] == '-' && w[1]) {
            switch (w[1]) {
            case 't':
                sep = w[2] ? (char *)w + 2 : "\n";
                sepset = 1;
                continue;
            case 'u':
                unbuf = 1;
                continue;
            case 'i':
                if (w[2] == 'n') {
                    if (a + 1 >= argc) usage(prog);
                    maxrec = atol(argv[++a]);
                    continue;
                }
                if (!strchr("afdiwb", w[2]) || !w[2]) usage(prog);
                type = w[2];
                n = isdigit((unsigned char)w[3]) ? atoi(w + 3) : 1;
                if (n < 1) n = 1;
                if (type != 'a' && !sepset) sep = "";
                continue;
            default:
                usage(prog);
            }
        }
        input *p = &in[nin++];
        p->name = w;
        p->type = type;
        p->n = n;
        p->sep = sep;
        if (!strcmp(w, "-")) {
            p->fp = stdin;
        } else if (w[0] == '!') {
            fflush(stdout);
            p->fp = popen(w + 1, "r");
            p->ispipe = 1;
        } else {
            p->fp = fopen(w, type == 'a' ? "r" : "rb");
        }
        if (!p->fp) {
            fprintf(stderr, "%s: cannot open input '%s'\n", prog, w);
            return 1;
        }
    }
    if (!nin) usage(prog);
    int ascii = 0;
    for (int i = 0; i < nin; i++) ascii |= in[i].type == 'a';
    char *line = NULL;
    size_t cap = 0;
    unsigned char *bin = NULL;
    size_t bincap = 0;
    for (long rec = 0; !maxrec || rec < maxrec; rec++) {
        int any = 0, ended = 0;
        for (int i = 0; i < nin && !ended; i++) {
            input *p = &in[i];
            if (p->type == 'a') {
                for (int k = 0; k < p->n; k++) {
                    ssize_t len = getline(&line, &cap, p->fp);
                    if (len < 0) { ended = 1; break; }
                    if (len && line[len - 1] == '\n') line[--len] = 0;
                    if (i > 0 || k > 0) fputs(p->sep, stdout);
                    fwrite(line, 1, (size_t)len, stdout);
                    any = 1;
                }
            } else {
                size_t sz = valsize(p->type) * (size_t)p->n;
                if (sz > bincap) {
                    unsigned char *nb = hd_realloc_array(bin, sz, 1);
                    if (!nb) hd_die();
                    bin = nb;
                    bincap = sz;
                }
                if (fread(bin, 1, sz, p->fp) != sz) { ended = 1; break; }
                if (i > 0) fputs(p->sep, stdout);
                fwrite(bin, 1, sz, stdout);
                any = 1;
            }
        }
        if (any && ascii) putchar('\n');
        if (ended) break;
        if (unbuf) fflush(stdout);
    }
    int st = 0;
    for (int i = 0; i < nin; i++) {
        if (in[i].ispipe) pclose(in[i].fp);
        else if (in[i].fp != stdin) fclose(in[i].fp);
    }
    free(line);
    free(bin);
    free(in);
    if (fflush(stdout) || ferror(stdout)) {
        fprintf(stderr, "%s: write error\n", prog);
        return 1;
    }
    return st;
}

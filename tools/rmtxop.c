/* rmtxop — concatenate, add, multiply, divide, transpose, scale and convert
 * Radiance matrices (heliodon).  Operands are read with hd_matrix_read and
 * combined left to right; see docs/man/rmtxop.1. */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/common.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/matrix.h"
#include "heliodon/options.h"
#include "heliodon/parallel.h"

#define MAXCOEF 1024

static const char synopsis[] =
    "rmtxop [-v][-f{a|f|d|c}][-c coef ..|-c RGBXYZA][-s sf ..][-t][-rf|-rb] m1 "
    "[.|+|*|/] [-c ..][-s ..][-t] m2 .. [-c ..][-s ..][-t]";

typedef struct unary {
    int transpose;
    int ncoef;              /* numeric coefficients, or symbolic rows x 3 */
    int symbolic;           /* non-zero: coef holds nsym rows of 3 */
    double coef[MAXCOEF];
    int nsf;
    double sf[MAXCOEF];
    const char *cword;      /* for messages */
    char refl;              /* XML BSDF: 0/'T' transmission, 'f' / 'b' reflection */
} unary;

typedef struct operand {
    const char *path;
    char op;                /* operator joining it to the result so far */
    unary u;
} operand;

static int verbose;

static _Noreturn void usage(const char *msg)
{
    fprintf(stderr, "%s: %s\nusage: %s\n", hd_progname(), msg, synopsis);
    exit(1);
}

/* Symbolic -c: check the letters (one output component each). */
static void parse_symbolic(unary *u, const char *w)
{
    u->symbolic = 1;
    u->ncoef = 3 * (int)strlen(w);
    if (u->ncoef + 3 > MAXCOEF) usage("-c: too many symbols");
    double tmp[MAXCOEF];
    if (hd_color_symbols(w, 0, tmp, NULL)) usage(hd_errmsg());
}

/* Parse the numbers following argv[i]; returns how many were consumed. */
static int parse_numbers(int argc, char **argv, int i, double *dst, int *n, const char *opt)
{
    int k = 0;
    double v;
    while (i + 1 + k < argc && !hd_parse_double(argv[i + 1 + k], &v)) {
        if (k >= MAXCOEF) usage("too many numbers after an option");
        dst[k++] = v;
    }
    if (!k) {
        char msg[96];
        snprintf(msg, sizeof msg, "%s needs at least one number", opt);
        usage(msg);
    }
    *n = k;
    return k;
}

/* Apply per-operand / final unary operations: -c, then -s, then -t.
 * *xyz tracks whether the matrix holds CIE XYZ (1) rather than RGB. */
static void apply_unary(hd_matrix *m, const unary *u, const char *what, int *xyz)
{
    if (u->ncoef) {
        const double *coef = u->coef;
        double sym[MAXCOEF];
        int ni = u->symbolic ? 3 : m->ncomp;
        if (u->symbolic && m->ncomp != 3)
            hd_die_msg("%s: -c %s needs 3 (RGB or XYZ) components, the matrix has %d", what, u->cword, m->ncomp);
        if (u->ncoef % ni)
            hd_die_msg("%s: -c: %d coefficients is not a multiple of the %d components", what, u->ncoef, ni);
        int nout = u->ncoef / ni, xyz_out = 0;
        if (u->symbolic) {
            if (hd_color_symbols(u->cword, *xyz, sym, &xyz_out)) hd_die();
            xyz_out = xyz_out == 1;
            coef = sym;
        }
        if (verbose) fprintf(stderr, "%s: %s: component transform %d -> %d\n", hd_progname(), what, ni, nout);
        int pic = m->infmt == HD_MTX_RGBE || m->infmt == HD_MTX_XYZE;
        if (hd_matrix_transform(m, m, coef, nout)) hd_die();
        *xyz = xyz_out;
        if (pic && nout == 3) m->infmt = xyz_out ? HD_MTX_XYZE : HD_MTX_RGBE;
    }
    if (u->nsf) {
        if (verbose) fprintf(stderr, "%s: %s: scaling by %d factor(s)\n", hd_progname(), what, u->nsf);
        if (hd_matrix_scale(m, u->sf, u->nsf)) {
            hd_fail_context(HD_ERR_USAGE, "%s", what);
            hd_die();
        }
    }
    if (u->transpose) {
        if (verbose) fprintf(stderr, "%s: %s: transposing\n", hd_progname(), what);
        hd_header keep;
        hd_header_init(&keep);
        if (hd_header_copy(&keep, &m->hdr) || hd_matrix_transpose(m, m)) hd_die();
        hd_header_free(&m->hdr);
        m->hdr = keep;
    }
}

static void load(hd_matrix *m, const operand *o, int *xyz)
{
    hd_matrix_readopts ro = {0, 0, 0, -1};
    if (hd_matrix_is_xml(o->path)) {
        if (hd_matrix_read_bsdf(o->path, m, o->u.refl ? o->u.refl : 'T')) hd_die();
    } else {
        if (o->u.refl)
            hd_warn("%s: -r%c applies only to XML BSDF inputs: ignored", o->path, o->u.refl);
        if (hd_matrix_read(o->path, m, &ro)) hd_die();
    }
    if (verbose)
        fprintf(stderr, "%s: read %s: %d x %d x %d (%s)\n", hd_progname(), o->path,
                m->nrows, m->ncols, m->ncomp, hd_mtxfmt_name(m->infmt));
    *xyz = m->infmt == HD_MTX_XYZE;
    apply_unary(m, &o->u, o->path, xyz);
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    void *argstore = NULL;     /* "@file" words expanded, as the other tools */
    if (hd_expand_args(argc, argv, &argc, &argv, &argstore)) hd_die();
    int outfmt = -1;
    operand *ops = hd_calloc((size_t)argc + 1, sizeof *ops);
    unary *pend = hd_calloc(1, sizeof *pend);
    if (!ops || !pend) hd_die();
    int nops = 0;
    char pendop = 0;

    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (a[0] == '-' && a[1]) {
            if (!strcmp(a, "-v")) verbose = 1;
            else if (!strcmp(a, "-t")) pend->transpose = !pend->transpose;
            else if (!strncmp(a, "-f", 2) && a[2] && !a[3]) {
                switch (a[2]) {
                case 'a': outfmt = HD_MTX_ASCII; break;
                case 'f': outfmt = HD_MTX_FLOAT; break;
                case 'd': outfmt = HD_MTX_DOUBLE; break;
                case 'c': outfmt = HD_MTX_RGBE; break;
                default: usage("-f needs a, f, d or c");
                }
            } else if (!strcmp(a, "-s")) {
                i += parse_numbers(argc, argv, i, pend->sf, &pend->nsf, "-s");
            } else if (!strcmp(a, "-c")) {
                if (i + 1 >= argc) usage("-c needs coefficients or component symbols");
                pend->cword = argv[i + 1];
                if (isalpha((unsigned char)argv[i + 1][0])) {
                    parse_symbolic(pend, argv[i + 1]);
                    i++;
                } else {
                    pend->symbolic = 0;
                    i += parse_numbers(argc, argv, i, pend->coef, &pend->ncoef, "-c");
                }
            } else if (!strcmp(a, "-rf") || !strcmp(a, "-rb")) {
                pend->refl = a[2];
            } else if (!strcmp(a, "-C")) {
                usage("-C (spectral colour space) is not supported");
            } else if (!strcmp(a, "-help") || !strcmp(a, "-version")) {
                printf("%s (%s)\nusage: %s\n", hd_progname(), HD_SOFTWARE, synopsis);
                return 0;
            } else {
                char msg[128];
                snprintf(msg, sizeof msg, "unknown option %s", a);
                usage(msg);
            }
            continue;
        }
        if ((a[0] == '.' || a[0] == '+' || a[0] == '*' || a[0] == '/') && !a[1]) {
            if (!nops) usage("an operator must follow a matrix");
            if (pendop) usage("two operators in a row");
            pendop = a[0];
            continue;
        }
        operand *o = &ops[nops];
        o->path = a;
        o->op = nops ? (pendop ? pendop : '.') : 0;
        o->u = *pend;
        memset(pend, 0, sizeof *pend);
        pendop = 0;
        nops++;
    }
    if (!nops) usage("no input matrix");
    if (pendop) usage("an operator must be followed by a matrix");

    hd_matrix res, m;
    hd_matrix_init(&res);
    hd_matrix_init(&m);
    int xyz = 0, mxyz = 0;
    load(&res, &ops[0], &xyz);
    int inherit = 1;
    for (int i = 1; i < nops;) {
        if (ops[i].op == '.') {
            /* a run of products: load it whole and multiply in the
             * cheapest order (as Radiance re-associates concatenations) */
            int j = i;
            while (j < nops && ops[j].op == '.') j++;
            int n = j - i + 1;
            hd_matrix *run = hd_calloc((size_t)n, sizeof *run);
            const hd_matrix **mp = hd_calloc((size_t)n, sizeof *mp);
            if (!run || !mp) hd_die();
            hd_matrix_init(&run[0]);
            hd_matrix_move(&run[0], &res);
            for (int k = 1; k < n; k++) {
                hd_matrix_init(&run[k]);
                load(&run[k], &ops[i + k - 1], &mxyz);
                xyz |= mxyz;
            }
            for (int k = 0; k < n; k++) mp[k] = &run[k];
            /* name the operand in errors (the dims of the left side are
             * those of the left-to-right partial product) */
            for (int k = 1, nc = run[0].ncomp; k < n; k++) {
                const char *what = ops[i + k - 1].path;
                if (run[k - 1].ncols != run[k].nrows)
                    hd_die_msg("%s: matrix product: %d x %d times %d x %d: the columns of the first (%d) must "
                               "equal the rows of the second (%d)", what, run[0].nrows, run[k - 1].ncols,
                               run[k].nrows, run[k].ncols, run[k - 1].ncols, run[k].nrows);
                if (nc != run[k].ncomp && nc != 1 && run[k].ncomp != 1)
                    hd_die_msg("%s: matrix product: component counts differ (%d and %d; one side may have 1)",
                               what, nc, run[k].ncomp);
                if (run[k].ncomp > nc) nc = run[k].ncomp;
            }
            double ltr = 0, best = 0;
            if (hd_matrix_chain(&res, mp, n, hd_ncpus(), &ltr, &best)) hd_die();
            if (verbose)
                fprintf(stderr, "%s: product of %d matrices: %.4g multiply-adds (left to right %.4g)\n",
                        hd_progname(), n, best, ltr);
            for (int k = 0; k < n; k++) hd_matrix_free(&run[k]);
            free(run);
            free(mp);
            inherit = 0;
            i = j;
            continue;
        }
        load(&m, &ops[i], &mxyz);
        if (verbose) fprintf(stderr, "%s: applying '%c' with %s\n", hd_progname(), ops[i].op, ops[i].path);
        if (hd_matrix_elementwise(&res, &m, (hd_mtxop)ops[i].op, NULL)) {
            hd_fail_context(HD_ERR_FORMAT, "%s", ops[i].path);
            hd_die();
        }
        hd_matrix_free(&m);
        i++;
    }
    apply_unary(&res, pend, "result", &xyz);

    hd_mtxfmt fmt = outfmt >= 0 ? (hd_mtxfmt)outfmt : res.infmt;
    if ((fmt == HD_MTX_RGBE || fmt == HD_MTX_XYZE) && res.ncomp == 3)
        fmt = xyz ? HD_MTX_XYZE : HD_MTX_RGBE;
    hd_header h;
    hd_header_init(&h);
    if (inherit && hd_header_copy(&h, &res.hdr)) hd_die();
    if (hd_header_add_command(&h, argc, argv)) hd_die();
    hd_ofile *of;
    if (hd_ofile_open(&of, NULL)) hd_die();
    if (hd_matrix_write(hd_ofile_fp(of), &res, &h, 1, fmt)) {
        hd_fail_context(HD_ERR_IO, "standard output");
        hd_die();
    }
    if (hd_ofile_commit(of)) hd_die();
    hd_header_free(&h);
    hd_matrix_free(&res);
    free(ops);
    free(pend);
    hd_expand_args_free(argstore);
    return 0;
}

/* heliodon — rcomb (include/heliodon/rcomb.h, docs/man/rcomb.1).
 *
 * Steps, as Radiance's rcomb orders them:
 *   1. each input is read (hd_matrix_read: exposure undone) and its own
 *      -c/-s applied (a -s after a -c scales the coefficients);
 *   2. every element and component of the output is either the sum of the
 *      inputs or the .cal value co / co(p) (ro, go, bo: co(p) =
 *      select(p,ro,go,bo)), with ci(i,p), r, c, nrows, ncols, ncomp ...;
 *   3. the trailing -c/-s and the -m matrix, in command-line order.
 * Rows are independent: -n threads split them (one .cal run each); the
 * result does not depend on the thread count.  Values are rounded to single
 * precision after each step, as in Radiance's float matrices. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include "heliodon/cal.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/matrix.h"
#include "heliodon/parallel.h"
#include "heliodon/rcomb.h"
#include "cal_internal.h"

/* Radiance's order of data types, lowest precision first */
enum { DT_RGBE = 1, DT_XYZE, DT_ASCII = 4, DT_FLOAT, DT_DOUBLE };

static int dt_of(hd_mtxfmt f)
{
    switch (f) {
    case HD_MTX_RGBE: return DT_RGBE;
    case HD_MTX_XYZE: return DT_XYZE;
    case HD_MTX_ASCII: return DT_ASCII;
    case HD_MTX_FLOAT: return DT_FLOAT;
    default: return DT_DOUBLE;
    }
}

static hd_mtxfmt fmt_of(int dt)
{
    switch (dt) {
    case DT_RGBE: return HD_MTX_RGBE;
    case DT_XYZE: return HD_MTX_XYZE;
    case DT_ASCII: return HD_MTX_ASCII;
    case DT_FLOAT: return HD_MTX_FLOAT;
    default: return HD_MTX_DOUBLE;
    }
}

/* a resolved -c/-s: out = M . in (nout x nin), or in scaled by sf */
typedef struct xfm {
    int nin, nout;
    double *m;          /* NULL: no transform */
    int nsf;            /* 0, or nout factors */
    double *sf;
} xfm;

static void xfm_free(xfm *x)
{
    free(x->m);
    free(x->sf);
    memset(x, 0, sizeof *x);
}

/* Component count of a reference file given to -c (header only). */
static hd_status ref_components(const char *path, int *nc, int *xyz)
{
    hd_istream *s;
    hd_status st = hd_istream_open(&s, path);
    if (st) return st;
    hd_header h;
    hd_header_init(&h);
    st = hd_header_read(s, &h, 1);
    hd_istream_close(s);
    if (st) {
        hd_header_free(&h);
        return hd_fail_context(st, "%s: cannot read info header", path);
    }
    char fmt[64] = "";
    long n = 3;
    int found = 0;
    hd_header_get(&h, "FORMAT", fmt, sizeof fmt);
    st = hd_header_get_long(&h, "NCOMP", &n, &found);
    hd_header_free(&h);
    if (st) return st;
    *nc = found ? (int)n : 3;
    *xyz = !strcmp(fmt, "32-bit_rle_xyze");
    return HD_OK;
}

/* Resolve op for an input of nc components in format *fmt (updated when the
 * transform makes an RGBE/XYZE picture or leaves picture space); the number
 * of output components goes to *ncout. */
static hd_status resolve(const hd_rcomb_op *op, const char *what, int nc, hd_mtxfmt *fmt,
                         xfm *x, int *ncout)
{
    memset(x, 0, sizeof *x);
    x->nin = nc;
    int clen = op->clen;
    const double *cm = op->cmat;
    double *sym = NULL;
    hd_status st = HD_OK;
    if (op->csym) {
        const char *letters = op->csym;
        if (strchr(letters, '.')) {         /* colour space of a reference file */
            int rnc = 0, rxyz = 0;
            if ((st = ref_components(letters, &rnc, &rxyz))) return st;
            if (rnc == 3) letters = rxyz ? "XYZ" : "RGB";
            else if (rnc == 1) letters = "Y";
            else if (rnc == nc) letters = NULL;
            else if (rnc == 2) return hd_fail(HD_ERR_USAGE, "%s: cannot convert to 2 components", op->csym);
            else return hd_fail(HD_ERR_USAGE, "%s: cannot resample from %d to %d components "
                                "(spectral data are not supported)", op->csym, nc, rnc);
        }
        if (letters) {
            if (nc < 3)
                return hd_fail(HD_ERR_USAGE, "%s: -c '%s' requires at least 3 components", what, letters);
            if (nc > 3)
                return hd_fail(HD_ERR_USAGE, "%s: -c '%s' on %d components: spectral conversion is not supported",
                               what, letters, nc);
            size_t nl = strlen(letters);
            if (3 * nl > HD_RCOMB_MAXCOEF)
                return hd_fail(HD_ERR_USAGE, "%s: -c '%s' results in too many components", what, letters);
            sym = hd_malloc(3 * nl * sizeof *sym + 1);
            if (!sym) return HD_ERR_NOMEM;
            int space;
            if ((st = hd_color_symbols(letters, *fmt == HD_MTX_XYZE, sym, &space))) {
                free(sym);
                return hd_fail_context(st, "%s", what);
            }
            int pic = *fmt == HD_MTX_RGBE || *fmt == HD_MTX_XYZE;
            if (space == 1 && pic) *fmt = HD_MTX_XYZE;
            else if (space == 0 && pic) *fmt = HD_MTX_RGBE;
            clen = 3 * (int)nl;
            cm = sym;
        } else {
            clen = 0;
        }
    }
    int nsf = op->nsf;
    if (clen > 0) {
        if (clen % nc) {
            free(sym);
            return hd_fail(HD_ERR_USAGE, "%s: -c must have N x %d coefficients", what, nc);
        }
        int nout = clen / nc;
        if (nsf > 1 && nsf != nout) {
            free(sym);
            return hd_fail(HD_ERR_USAGE, "%s: -s must have one or %d factors", what, nout);
        }
        x->m = hd_malloc_array((size_t)clen, sizeof *x->m);
        if (!x->m) { free(sym); return HD_ERR_NOMEM; }
        for (int i = 0; i < nout; i++)          /* -s folded into the rows */
            for (int j = 0; j < nc; j++)
                x->m[i * nc + j] = cm[i * nc + j] * (nsf ? op->sf[nsf == 1 ? 0 : i] : 1.0);
        x->nout = nout;
        if (nout > 3 && (*fmt == HD_MTX_RGBE || *fmt == HD_MTX_XYZE)) *fmt = HD_MTX_FLOAT;
    } else {
        x->nout = nc;
        if (nsf > 0) {
            if (nsf != 1 && nsf != nc) {
                free(sym);
                return hd_fail(HD_ERR_USAGE, "%s: -s must have one or %d factors", what, nc);
            }
            x->sf = hd_malloc_array((size_t)nc, sizeof *x->sf);
            if (!x->sf) { free(sym); return HD_ERR_NOMEM; }
            for (int k = 0; k < nc; k++) x->sf[k] = op->sf[nsf == 1 ? 0 : k];
            x->nsf = nc;
        }
    }
    free(sym);
    *ncout = x->nout;
    return HD_OK;
}

/* Apply x to n elements of in (x->nin values each) into out (x->nout each),
 * with float rounding; in and out may be the same only without a transform. */
static void apply(const xfm *x, const double *in, double *out, int n)
{
    if (x->m) {
        for (int e = 0; e < n; e++) {
            const double *a = in + (size_t)e * (size_t)x->nin;
            double *b = out + (size_t)e * (size_t)x->nout;
            for (int i = 0; i < x->nout; i++) {
                double s = 0;
                for (int j = 0; j < x->nin; j++) s += x->m[i * x->nin + j] * a[j];
                b[i] = (float)s;
            }
        }
        return;
    }
    size_t nv = (size_t)n * (size_t)x->nin;
    for (size_t i = 0; i < nv; i++)
        out[i] = x->nsf ? (float)((float)in[i] * x->sf[i % (size_t)x->nin]) : (float)in[i];
}

/* ------------------------------------------------------------------ run */
typedef struct rc {
    const hd_rcomb_opts *o;
    int nin;
    hd_matrix *mats;            /* inputs as read */
    xfm *ixf;                   /* per input */
    int nrows, ncols, ncomp;    /* of the combined elements */
    xfm trail;
    int outcomp, outcols;
    hd_matrix mcat;
    int have_mcat;
    hd_cal *cal;
    int co_h, co_fn;            /* handle of co, whether a function; -1 none */
    double *result;             /* nrows x outcols x outcomp */
    struct worker *w;
    int nw;
} rc;

typedef struct worker {
    const rc *p;
    hd_calrun *run;
    double **rows;              /* per input: current row after its -c/-s */
    double *comb, *tmp, *tmp2;
    int row, col, chan;
} worker;

static double f_ci(hd_calrun *r, void *u, int na, const double *a)
{
    (void)u;
    const worker *w = hd_calrun_user(r);
    double inp = a[0];
    int mi = (int)(inp - .5);
    if (mi < 0 || mi >= w->p->nin) return NAN;
    if (inp < .5) return w->p->nin;
    int ch = w->chan;
    if (na >= 2) {
        if (a[1] < .5 || (ch = (int)(a[1] - .5)) >= w->p->ncomp) return NAN;
    }
    return w->rows[mi][(size_t)w->col * (size_t)w->p->ncomp + (size_t)ch];
}

/* Central wavelength of channel p (nm) for the default band limits 780 ..
 * 380 nm (Radiance's RGB split at 588 and 480 nm); wl(0) = ncomp. */
static double f_wl(hd_calrun *r, void *u, int na, const double *a)
{
    (void)u; (void)na;
    const worker *w = hd_calrun_user(r);
    int nc = w->p->ncomp;
    double p = a[0];
    if (p < -.5 || p >= nc + .5) return NAN;
    if (p < .5) return nc;
    if (nc == 3) {
        static const double lim[4] = {780, 588, 480, 380};
        int k = (int)(p - .5);
        return .5 * (lim[k] + lim[k + 1]);
    }
    return 780 + (p - .5) / nc * (380 - 780);
}

static double f_r(hd_calrun *r, void *u, int na, const double *a)
{
    (void)u; (void)na; (void)a;
    return ((const worker *)hd_calrun_user(r))->row;
}

static double f_c(hd_calrun *r, void *u, int na, const double *a)
{
    (void)u; (void)na; (void)a;
    return ((const worker *)hd_calrun_user(r))->col;
}

/* one output row */
static hd_status do_row(rc *p, worker *w, int row)
{
    const int nc = p->ncomp, ncols = p->ncols;
    w->row = row;
    for (int i = 0; i < p->nin; i++)
        apply(&p->ixf[i], hd_matrix_at(&p->mats[i], row, 0), w->rows[i], ncols);
    for (int c = 0; c < ncols; c++) {
        w->col = c;
        for (int k = 0; k < nc; k++) {
            size_t ndx = (size_t)c * (size_t)nc + (size_t)k;
            w->chan = k;
            if (p->co_h < 0) {
                float s = 0;
                for (int i = p->nin; i--;) s += (float)w->rows[i][ndx];
                w->comb[ndx] = s;
            } else {
                hd_calrun_next(w->run);
                double v;
                if (p->co_fn) {
                    double dch = k + 1;
                    v = hd_calrun_call_id(w->run, p->co_h, 1, &dch);
                } else {
                    v = hd_calrun_var_id(w->run, p->co_h);
                }
                w->comb[ndx] = (float)v;
            }
        }
        if (p->co_h >= 0 && hd_calrun_status(w->run) != HD_OK) return hd_calrun_status(w->run);
    }
    double *out = p->result + (size_t)row * (size_t)p->outcols * (size_t)p->outcomp;
    if (!p->have_mcat) {
        apply(&p->trail, w->comb, out, ncols);
        return HD_OK;
    }
    const double *lhs = w->comb;
    int lnc = nc;
    if (p->o->mcat_last) {
        apply(&p->trail, w->comb, w->tmp, ncols);
        lhs = w->tmp;
        lnc = p->trail.nout;
    }
    /* row (1 x ncols x lnc) times mcat (ncols x mcols x lnc), per component */
    const hd_matrix *m = &p->mcat;
    double *prod = p->o->mcat_last ? out : w->tmp2;
    for (int j = 0; j < m->ncols; j++)
        for (int k = 0; k < lnc; k++) {
            double s = 0;
            for (int i = 0; i < ncols; i++) s += lhs[(size_t)i * lnc + k] * hd_matrix_at(m, i, j)[k];
            prod[(size_t)j * lnc + k] = (float)s;
        }
    if (!p->o->mcat_last) apply(&p->trail, w->tmp2, out, m->ncols);
    return HD_OK;
}

static hd_status rows_chunk(void *ctx, size_t begin, size_t end, size_t chunk, int worker_ix)
{
    (void)chunk;
    rc *p = ctx;
    worker *w = &p->w[worker_ix];
    for (size_t r = begin; r < end; r++) {
        hd_status st = do_row(p, w, (int)r);
        if (st) {
            if (w->run) hd_calrun_clear(w->run);
            return st;
        }
    }
    return HD_OK;
}

static hd_status setup_cal(rc *p)
{
    const hd_rcomb_opts *o = p->o;
    hd_cal *c = p->cal = hd_cal_new();
    if (!c) return HD_ERR_NOMEM;
    if (o->nowarn) hd_cal_warnings(c, 0);
    hd_status st = HD_OK;
    if (!st) st = hd_cal_set(c, "PI", M_PI, 1);
    if (!st) st = hd_cal_set(c, "nfiles", p->nin, 1);
    if (!st) st = hd_cal_set(c, "nrows", p->nrows, 1);
    if (!st) st = hd_cal_set(c, "ncols", p->ncols, 1);
    if (!st) st = hd_cal_set(c, "ncomp", p->ncomp, 1);
    if (!st) st = hd_cal_set(c, "R", 1, 1);
    if (!st) st = hd_cal_set(c, "G", 2, 1);
    if (!st) st = hd_cal_set(c, "B", 3, 1);
    if (!st) st = hd_cal_define_fn(c, "ci", 1, 2, f_ci, NULL, 0);
    if (!st) st = hd_cal_define_fn(c, "wl", 1, 1, f_wl, NULL, 0);
    if (!st) st = hd_cal_parse(c, "ri(i)=ci(i,R);gi(i)=ci(i,G);bi(i)=ci(i,B)", "rcomb");
    for (int i = 0; i < o->ndefs && !st; i++) {
        if (o->defkind[i] == 'f') st = hd_cal_load(c, o->deftext[i]);
        else st = hd_cal_parse(c, o->deftext[i], NULL);
    }
    if (st) return st;
    int np = hd_cal_nparams(c, "co");
    if (np == -2 && p->ncomp == 3 && hd_cal_nparams(c, "ro") == -1 && hd_cal_nparams(c, "go") == -1 &&
        hd_cal_nparams(c, "bo") == -1) {
        if ((st = hd_cal_parse(c, "co(p)=select(p,ro,go,bo)", "rcomb"))) return st;
        np = 1;
    }
    p->co_h = -1;
    if (np == -2) return HD_OK;             /* no expression: sums */
    p->co_fn = np >= 0;
    p->co_h = hd_cal_lookup(c, "co");
    if (!hd_cal_defined(c, "r") && (st = hd_cal_define_fn(c, "r", 0, 0, f_r, NULL, 0))) return st;
    if (!hd_cal_defined(c, "c") && (st = hd_cal_define_fn(c, "c", 0, 0, f_c, NULL, 0))) return st;
    return HD_OK;
}

hd_status hd_rcomb(const hd_rcomb_opts *o, int argc, char **argv, FILE *out)
{
    rc P, *p = &P;
    memset(p, 0, sizeof *p);
    p->o = o;
    p->nin = o->nin;
    hd_matrix_init(&p->mcat);
    hd_header h;
    hd_header_init(&h);
    hd_status st = HD_OK;
    if (o->nin < 1) return hd_fail(HD_ERR_USAGE, "need at least one input matrix");
    p->mats = hd_calloc((size_t)o->nin, sizeof *p->mats);
    p->ixf = hd_calloc((size_t)o->nin, sizeof *p->ixf);
    if (!p->mats || !p->ixf) { st = HD_ERR_NOMEM; goto done; }
    for (int i = 0; i < o->nin; i++) hd_matrix_init(&p->mats[i]);

    /* inputs and their own -c/-s; the output type is the lowest precision */
    int dtype = 0;
    for (int i = 0; i < o->nin && !st; i++) {
        const char *spec = o->in[i].spec;
        const char *name = strcmp(spec, "-") ? spec : "<stdin>";
        hd_matrix *m = &p->mats[i];
        hd_matrix_readopts ro = {0, 0, 0, -1};
        if ((st = hd_matrix_read(spec, m, &ro))) break;
        size_t nv = (size_t)m->nrows * (size_t)m->ncols * (size_t)m->ncomp;
        for (size_t k = 0; k < nv; k++) m->data[k] = (float)m->data[k];
        hd_mtxfmt f = m->infmt;
        int ncout;
        if ((st = resolve(&o->in[i].op, name, m->ncomp, &f, &p->ixf[i], &ncout))) break;
        int t = dt_of(f);
        int pic = t <= DT_XYZE || dtype <= DT_XYZE;
        if (!dtype) dtype = t;
        else if (pic && t != dtype) {
            if (!o->nowarn) hd_warn("%s: warning - data type mismatch", name);
        } else if (t < dtype) dtype = t;
        if (!i) {
            p->nrows = m->nrows;
            p->ncols = m->ncols;
            p->ncomp = ncout;
        } else if (m->ncols != p->ncols || ncout != p->ncomp || m->nrows != p->nrows) {
            st = hd_fail(HD_ERR_FORMAT, "%s: mismatch in size or #components (%d x %d x %d, the first input "
                         "gives %d x %d x %d)", name, m->nrows, m->ncols, ncout, p->nrows, p->ncols, p->ncomp);
        }
    }
    if (st) goto done;
    if ((st = setup_cal(p))) goto done;

    /* trailing operations and the concatenation matrix */
    hd_mtxfmt f = fmt_of(dtype);
    if ((st = resolve(&o->trail, "trailing_ops", p->ncomp, &f, &p->trail, &p->outcomp))) goto done;
    dtype = dt_of(f);
    p->outcols = p->ncols;
    if (o->mcat) {
        hd_matrix_readopts ro = {0, 0, 0, -1};
        if ((st = hd_matrix_read(o->mcat, &p->mcat, &ro))) {
            hd_fail_context(st, "error loading concatenation matrix: %s", o->mcat);
            goto done;
        }
        p->have_mcat = 1;
        size_t nv = (size_t)p->mcat.nrows * (size_t)p->mcat.ncols * (size_t)p->mcat.ncomp;
        for (size_t k = 0; k < nv; k++) p->mcat.data[k] = (float)p->mcat.data[k];
        if (o->mcat_transpose && (st = hd_matrix_transpose(&p->mcat, &p->mcat))) goto done;
        if (p->ncols != p->mcat.nrows) {
            st = hd_fail(HD_ERR_FORMAT, "number of input columns (%d) does not match number of rows in '%s' (%d)",
                         p->ncols, o->mcat, p->mcat.nrows);
            goto done;
        }
        int need = o->mcat_last ? p->outcomp : p->ncomp;
        if (p->mcat.ncomp != need) {
            st = hd_fail(HD_ERR_FORMAT, "number of components does not match those in '%s' (%d, expected %d)",
                         o->mcat, p->mcat.ncomp, need);
            goto done;
        }
        p->outcols = p->mcat.ncols;
    }

    /* output format: -f, or the inputs' (double is stored as float) */
    hd_mtxfmt ofmt;
    if (o->outfmt < 0) {
        ofmt = fmt_of(dtype);
        if (ofmt == HD_MTX_DOUBLE) ofmt = HD_MTX_FLOAT;
    } else {
        ofmt = (hd_mtxfmt)o->outfmt;
        if (ofmt == HD_MTX_RGBE && dtype == DT_XYZE) ofmt = HD_MTX_XYZE;
        else if (ofmt == HD_MTX_XYZE && dtype == DT_RGBE) ofmt = HD_MTX_RGBE;
    }
    if ((ofmt == HD_MTX_RGBE || ofmt == HD_MTX_XYZE) && p->outcomp != 1 && p->outcomp != 3) {
        st = hd_fail(HD_ERR_USAGE, "unsupported output format: a picture of %d components%s", p->outcomp,
                     p->outcomp > 3 ? " (spectral pictures are not supported)" : "");
        goto done;
    }

    /* compute */
    size_t nres = (size_t)p->nrows * (size_t)p->outcols * (size_t)p->outcomp;
    p->result = hd_malloc_array(nres ? nres : 1, sizeof *p->result);
    int nth = hd_resolve_threads(o->nthreads > 0 ? o->nthreads : 1);
    if (p->nrows > 0 && nth > p->nrows) nth = p->nrows;
    if (nth < 1) nth = 1;
    p->w = hd_calloc((size_t)nth, sizeof *p->w);
    if (!p->result || !p->w) { st = HD_ERR_NOMEM; goto done; }
    p->nw = nth;
    size_t rowlen = (size_t)p->ncols * (size_t)(p->ncomp > p->outcomp ? p->ncomp : p->outcomp);
    size_t wide = rowlen > (size_t)p->outcols * (size_t)p->ncomp ? rowlen : (size_t)p->outcols * (size_t)p->ncomp;
    for (int t = 0; t < nth && !st; t++) {
        worker *w = &p->w[t];
        w->p = p;
        w->rows = hd_calloc((size_t)p->nin, sizeof *w->rows);
        w->comb = hd_malloc_array(wide + 1, sizeof *w->comb);
        w->tmp = hd_malloc_array(wide + 1, sizeof *w->tmp);
        w->tmp2 = hd_malloc_array(wide + 1, sizeof *w->tmp2);
        if (!w->rows || !w->comb || !w->tmp || !w->tmp2) { st = HD_ERR_NOMEM; break; }
        for (int i = 0; i < p->nin && !st; i++) {
            size_t n = (size_t)p->ncols * (size_t)(p->ixf[i].nout > p->ixf[i].nin ? p->ixf[i].nout : p->ixf[i].nin);
            if (!(w->rows[i] = hd_malloc_array(n + 1, sizeof **w->rows))) st = HD_ERR_NOMEM;
        }
        if (!st && p->co_h >= 0 && !(w->run = hd_calrun_new(p->cal, w))) st = HD_ERR_NOMEM;
    }
    if (st) goto done;
    if ((st = hd_parallel_for((size_t)p->nrows, 16, nth, rows_chunk, p))) goto done;

    /* header and data */
    for (int i = 0; i < o->nin && o->echo_header; i++) {
        const char *spec = strcmp(o->in[i].spec, "-") ? o->in[i].spec : "<stdin>";
        if ((st = hd_header_appendf(&h, "%s:", spec))) goto done;
        const char *t = p->mats[i].hdr.text;
        while (t && *t) {
            const char *e = strchr(t, '\n');
            size_t len = e ? (size_t)(e - t) : strlen(t);
            if (len && (st = hd_header_appendf(&h, "\t%.*s", (int)len, t))) goto done;
            t += len + (e != NULL);
        }
    }
    if (!st) st = hd_header_add_command(&h, argc, argv);
    if (!st) st = hd_header_add_date(&h);
    if (st) goto done;
    hd_mtxwriter wr;
    if ((st = hd_mtxwriter_begin(&wr, out, &h, 1, ofmt, p->nrows, p->outcols, p->outcomp))) goto done;
    size_t rl = (size_t)p->outcols * (size_t)p->outcomp;
    for (int r = 0; r < p->nrows && !st; r++) st = hd_mtxwriter_row(&wr, p->result + (size_t)r * rl);
    hd_status st2 = hd_mtxwriter_end(&wr);
    if (!st) st = st2;

done:
    hd_header_free(&h);
    if (p->w) {
        for (int t = 0; t < p->nw; t++) {
            worker *w = &p->w[t];
            if (w->rows) for (int i = 0; i < p->nin; i++) free(w->rows[i]);
            free(w->rows);
            free(w->comb);
            free(w->tmp);
            free(w->tmp2);
            if (w->run) hd_calrun_free(w->run);
        }
        free(p->w);
    }
    if (p->mats) for (int i = 0; i < o->nin; i++) hd_matrix_free(&p->mats[i]);
    if (p->ixf) for (int i = 0; i < o->nin; i++) xfm_free(&p->ixf[i]);
    free(p->mats);
    free(p->ixf);
    xfm_free(&p->trail);
    hd_matrix_free(&p->mcat);
    free(p->result);
    if (p->cal) hd_cal_free(p->cal);
    return st;
}

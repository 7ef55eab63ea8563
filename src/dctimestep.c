/* heliodon — dctimestep: daylight coefficients × sky, 3-phase V·T·D·S,
 * component-picture folding. */
#include "heliodon/dctimestep.h"
#include "heliodon/exr.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/parallel.h"
#include "heliodon/picture.h"

#include <stdlib.h>
#include <string.h>

#define FOLD_PIXCHUNK 512    /* pixels per work unit (multiple of 16) */
#define FOLD_TSUB 32         /* time steps folded together: 32x3x512 floats = 192 KiB of output stay in L2 */

void hd_dcts_opts_init(hd_dcts_opts *o)
{
    memset(o, 0, sizeof *o);
    o->sky_fmt = -1;
    o->out_fmt = HD_MTX_ASCII;
    o->header = 1;
}

static int ends_with(const char *s, const char *suffix)
{
    size_t a = strlen(s), b = strlen(suffix);
    return a >= b && !strcasecmp(s + a - b, suffix);
}

/* ---------------------------------------------------------------- loading */

/* T: a matrix file, or a BSDF XML file read as its Klems transmission
 * matrix (hd_matrix_read does that for names ending in .xml). */
static hd_status load_transfer(const char *path, hd_matrix *T) { return hd_matrix_read(path, T, NULL); }

static hd_status load_sky(const char *path, const hd_dcts_opts *o, int npatches, hd_matrix *S)
{
    hd_matrix_readopts ro;
    ro.nrows = npatches;
    ro.ncols = o->nsteps > 0 ? o->nsteps : 0;
    ro.ncomp = 3;
    ro.fmt = o->sky_fmt;
    hd_status st = hd_matrix_read(path ? path : "-", S, o->sky_fmt >= 0 ? &ro : NULL);
    if (st) return st;
    if (S->ncomp != 3)
        return hd_fail(HD_ERR_FORMAT, "%s: sky has %d components per element, expected 3 (RGB)",
                       path ? path : "<stdin>", S->ncomp);
    if (npatches > 0 && S->nrows != npatches)
        return hd_fail(HD_ERR_FORMAT, "%s: sky has %d rows (patches) but the coefficient matrix has %d columns",
                       path ? path : "<stdin>", S->nrows, npatches);
    return HD_OK;
}

static hd_status product(hd_matrix *out, const hd_matrix *a, const char *aname, const hd_matrix *b,
                         const char *bname)
{
    if (a->ncols != b->nrows)
        return hd_fail(HD_ERR_FORMAT, "%s has %d columns but %s has %d rows: cannot multiply", aname, a->ncols,
                       bname, b->nrows);
    if (a->ncomp != b->ncomp)
        return hd_fail(HD_ERR_FORMAT, "%s has %d components but %s has %d", aname, a->ncomp, bname, b->ncomp);
    return hd_matrix_multiply(out, a, b);
}

hd_status hd_dcts_coefficients(const char *t_path, const char *d_path, const char *sky_path,
                               const hd_dcts_opts *o, int npatches_hint, hd_matrix *out)
{
    hd_status st;
    hd_matrix_init(out);
    if (!t_path) return load_sky(sky_path, o, npatches_hint, out);
    hd_matrix T, D, S, DS;
    hd_matrix_init(&T);
    hd_matrix_init(&D);
    hd_matrix_init(&S);
    hd_matrix_init(&DS);
    if ((st = load_transfer(t_path, &T))) goto done;
    if ((st = hd_matrix_read(d_path, &D, NULL))) goto done;
    if ((st = load_sky(sky_path, o, D.ncols, &S))) goto done;
    if (T.ncomp == 1 && D.ncomp == 3) { /* grey BSDF: spread to RGB */
        hd_matrix T3;
        if ((st = hd_matrix_alloc(&T3, T.nrows, T.ncols, 3))) goto done;
        for (size_t i = 0; i < (size_t)T.nrows * (size_t)T.ncols; i++)
            T3.data[3 * i] = T3.data[3 * i + 1] = T3.data[3 * i + 2] = T.data[i];
        hd_matrix_free(&T);
        T = T3;
    }
    if ((st = product(&DS, &D, d_path, &S, sky_path ? sky_path : "the sky"))) goto done;
    st = product(out, &T, t_path, &DS, "D·S");
done:
    hd_matrix_free(&T);
    hd_matrix_free(&D);
    hd_matrix_free(&S);
    hd_matrix_free(&DS);
    return st;
}

/* ---------------------------------------------------------------- folding */

typedef struct fold_ctx {
    float *const *comp;
    int K;
    const double *coef;
    int nsteps;
    size_t npix; /* padded: multiple of 16 */
    float *out;
} fold_ctx;

/* The hot loop.  On x86-64 with GCC or Clang an AVX2 clone is selected at
 * run time where the CPU has it (same operations, 8 lanes instead of 4, so
 * results are bit-identical to the baseline clone: ISO C mode does not
 * contract a*s+o into FMAs). */
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(__SANITIZE_ADDRESS__)
__attribute__((target_clones("avx2", "default")))
#endif
static void saxpy8(float *restrict o, float a, const float *restrict s, size_t n)
{
    for (size_t i = 0; i < n; i += 8)
        for (int j = 0; j < 8; j++) o[i + j] += a * s[i + j];
}

static hd_status fold_chunk(void *vctx, size_t b, size_t e, size_t chunk, int worker)
{
    fold_ctx *c = vctx;
    (void)chunk;
    (void)worker;
    size_t n = e - b; /* multiple of 16: npix padded and chunk size a multiple of 16 */
    for (int t0 = 0; t0 < c->nsteps; t0 += FOLD_TSUB) {
        int t1 = t0 + FOLD_TSUB < c->nsteps ? t0 + FOLD_TSUB : c->nsteps;
        for (int t = t0; t < t1; t++)
            for (int ch = 0; ch < 3; ch++) memset(c->out + ((size_t)t * 3 + (size_t)ch) * c->npix + b, 0, n * sizeof(float));
        for (int k = 0; k < c->K; k++) {
            if (!c->comp[k]) continue;
            for (int ch = 0; ch < 3; ch++) {
                const float *s = c->comp[k] + (size_t)ch * c->npix + b;
                for (int t = t0; t < t1; t++) {
                    double a = c->coef[((size_t)k * (size_t)c->nsteps + (size_t)t) * 3 + (size_t)ch];
                    if (a != 0) saxpy8(c->out + ((size_t)t * 3 + (size_t)ch) * c->npix + b, (float)a, s, n);
                }
            }
        }
    }
    return HD_OK;
}

hd_status hd_dcts_fold(float *const *comp, int K, const double *coef, int nsteps, size_t npix, float *out,
                       int nthreads)
{
    if (npix % 16) return hd_fail(HD_ERR_INTERNAL, "hd_dcts_fold: pixel count %zu not padded to 16", npix);
    fold_ctx c = {comp, K, coef, nsteps, npix, out};
    return hd_parallel_for(npix, FOLD_PIXCHUNK, nthreads, fold_chunk, &c);
}

/* ---------------------------------------------------------------- output */

static hd_status base_header(const hd_dcts_opts *o, long frame, hd_header *h)
{
    hd_header_init(h);
    hd_status st = HD_OK;
    if (frame >= 0) st = hd_header_appendf(h, "FRAME=%ld", frame);
    if (!st && o->cmd_argc > 0) st = hd_header_add_command(h, o->cmd_argc, o->cmd_argv);
    if (!st) st = hd_header_add_software(h);
    if (!st) st = hd_header_add_date(h);
    return st;
}

/* Matrix output: values nrows × ncols × 3 (double), as Radiance's
 * dctimestep writes it. */
static hd_status write_matrix(FILE *fp, const hd_dcts_opts *o, long frame, const double *v, int nrows, int ncols,
                              size_t col_stride, size_t col0)
{
    hd_status st = HD_OK;
    const char *fmtname = o->out_fmt == HD_MTX_FLOAT ? "float" : o->out_fmt == HD_MTX_DOUBLE ? "double" : "ascii";
    if (o->header) {
        hd_header h;
        if ((st = base_header(o, frame, &h))) return st;
        st = hd_header_appendf(&h, "NROWS=%d", nrows);
        if (!st) st = hd_header_appendf(&h, "NCOLS=%d", ncols);
        if (!st) st = hd_header_append(&h, "NCOMP=3");
        if (!st && o->out_fmt != HD_MTX_ASCII) {
            const union { uint16_t u; uint8_t b[2]; } probe = {1};
            st = hd_header_appendf(&h, "BigEndian=%d", probe.b[0] ? 0 : 1);
        }
        size_t nb = 0;
        if (!st) st = hd_header_write(fp, &h, &nb);
        if (!st) st = hd_header_write_format(fp, fmtname, nb);
        hd_header_free(&h);
        if (st) return st;
    }
    for (int r = 0; r < nrows; r++) {
        for (int c = 0; c < ncols; c++) {
            const double *e = v + ((size_t)r * col_stride + col0 + (size_t)c) * 3;
            if (o->out_fmt == HD_MTX_FLOAT) {
                float f[3] = {(float)e[0], (float)e[1], (float)e[2]};
                fwrite(f, sizeof f, 1, fp);
            } else if (o->out_fmt == HD_MTX_DOUBLE) {
                fwrite(e, sizeof(double), 3, fp);
            } else {
                fprintf(fp, "%e %e %e%c", e[0], e[1], e[2], c == ncols - 1 ? '\n' : '\t');
            }
        }
    }
    if (ferror(fp)) return hd_fail(HD_ERR_IO, "error writing output");
    return HD_OK;
}

/* EXR output of a picture: float RGB, ZIP, the header text carried in the
 * "heliodonHeader" attribute (as hdr2exr does). */
static hd_status write_exr(FILE *fp, const hd_picture *pic, const hd_header *h, const char *name)
{
    hd_exr_image img;
    hd_exr_init(&img);
    uint8_t *data = NULL;
    size_t len = 0;
    hd_status st = hd_exr_from_picture(&img, pic, NULL, HD_EXR_FLOAT, 1.0);
    if (!st && h->len) st = hd_exr_set_attr(&img, "heliodonHeader", h->text);
    if (!st) st = hd_exr_encode(&img, HD_EXR_ZIP, name, &data, &len);
    if (!st && fwrite(data, 1, len, fp) != len) st = hd_fail(HD_ERR_IO, "%s: error writing EXR data", name);
    free(data);
    hd_exr_free(&img);
    return st;
}

/* Picture output of one step from planar float data (EXR when the output
 * name ends in .exr, else a Radiance picture).  pic is the caller's scratch
 * picture, allocated on first use and reused for every step (allocating a
 * fresh picture per step cost a third of the run in page faults). */
static hd_status write_picture_planar(FILE *fp, const hd_dcts_opts *o, long frame, const float *planar,
                                      size_t npix_pad, int xres, int yres, hd_picture *scratch)
{
    hd_status st = HD_OK;
    if (!scratch->pix && (st = hd_picture_alloc(scratch, xres, yres))) return st;
    hd_picture pic = *scratch;
    size_t n = (size_t)xres * (size_t)yres;
    for (size_t p = 0; p < n; p++)
        for (int c = 0; c < 3; c++) pic.pix[3 * p + (size_t)c] = planar[(size_t)c * npix_pad + p];
    hd_header h;
    hd_header_init(&h);
    if (o->header) st = base_header(o, frame, &h);
    if (!st) st = o->outspec && ends_with(o->outspec, ".exr") ? write_exr(fp, &pic, &h, o->outspec)
                                                             : hd_picture_write(fp, &pic, &h, HD_RES_STANDARD);
    hd_header_free(&h);
    return st;
}

/* Open the output for step t (pattern) or return stdout. */
static hd_status open_step_output(const hd_dcts_opts *o, long t, hd_ofile **f)
{
    char name[4096];
    if (!o->outspec) return hd_ofile_open(f, NULL);
    hd_status st = hd_pattern_format(name, sizeof name, o->outspec, NULL, t);
    if (st) return st;
    return hd_ofile_open(f, name);
}

/* ---------------------------------------------------------------- picture mode */

typedef struct load_ctx {
    const char *spec;
    const unsigned char *need;
    float **comp;
    int *xres, *yres; /* per component */
} load_ctx;

static hd_status load_component(void *vctx, size_t b, size_t e, size_t chunk, int worker)
{
    load_ctx *c = vctx;
    (void)chunk;
    (void)worker;
    for (size_t k = b; k < e; k++) {
        if (!c->need[k]) continue;
        char path[4096];
        hd_status st = hd_pattern_format(path, sizeof path, c->spec, NULL, (long)k);
        if (st) return st;
        hd_picture pic;
        hd_picture_init(&pic);
        if ((st = hd_picture_read(path, &pic))) return st;
        size_t n = (size_t)pic.xres * (size_t)pic.yres, np = (n + 15) & ~(size_t)15;
        float *pl = hd_calloc(3 * np, sizeof(float));
        if (!pl) { hd_picture_free(&pic); return HD_ERR_NOMEM; }
        double ex = hd_header_exposure(&pic.hdr);
        float inv = (float)(1.0 / ex);
        for (size_t p = 0; p < n; p++)
            for (int ch = 0; ch < 3; ch++) pl[(size_t)ch * np + p] = pic.pix[3 * p + (size_t)ch] * inv;
        c->comp[k] = pl;
        c->xres[k] = pic.xres;
        c->yres[k] = pic.yres;
        hd_picture_free(&pic);
    }
    return HD_OK;
}

typedef struct write_ctx {
    const hd_dcts_opts *o;
    const float *out;
    size_t npix_pad;
    int xres, yres, t0;
    hd_picture *scratch; /* one per worker */
} write_ctx;

static hd_status write_step_file(void *vctx, size_t b, size_t e, size_t chunk, int worker)
{
    write_ctx *c = vctx;
    (void)chunk;
    for (size_t t = b; t < e; t++) {
        hd_ofile *f;
        long frame = c->t0 + (long)t;
        hd_status st = open_step_output(c->o, frame, &f);
        if (st) return st;
        st = write_picture_planar(hd_ofile_fp(f), c->o, frame, c->out + t * 3 * c->npix_pad, c->npix_pad, c->xres,
                                  c->yres, &c->scratch[worker]);
        if (st) { hd_ofile_abort(f); return st; }
        if ((st = hd_ofile_commit(f))) return st;
    }
    return HD_OK;
}

/* Fold planar components with coefficient matrix C (K × nsteps × 3) and
 * write one picture per step. */
static hd_status fold_and_write(float **comp, int K, const hd_matrix *C, size_t npix_pad, int xres, int yres,
                                const hd_dcts_opts *o)
{
    int T = C->ncols;
    size_t per_step = 3 * npix_pad * sizeof(float);
    /* Blocks of at most 64 steps (and HD_DCTS_BLOCK_BYTES): enough for every
     * thread to encode its own pictures, small enough that the buffer is
     * faulted in once and stays warm. */
    int batch = (int)(HD_DCTS_BLOCK_BYTES / per_step);
    if (batch > 64) batch = 64;
    if (batch < 1) batch = 1;
    if (batch > T) batch = T;
    float *out = hd_malloc_array((size_t)batch, per_step);
    double *coef = hd_malloc_array((size_t)K * (size_t)batch * 3, sizeof(double));
    int nworkers = hd_resolve_threads(o->nthreads);
    hd_picture *scratch = hd_calloc((size_t)nworkers, sizeof *scratch);
    hd_status st = (!out || !coef || !scratch) ? HD_ERR_NOMEM : HD_OK;
    hd_ofile *single = NULL;
    if (!st && !o->outspec) st = hd_ofile_open(&single, NULL);
    for (int t0 = 0; !st && t0 < T; t0 += batch) {
        int nb = T - t0 < batch ? T - t0 : batch;
        for (int k = 0; k < K; k++)
            for (int t = 0; t < nb; t++)
                memcpy(coef + ((size_t)k * (size_t)nb + (size_t)t) * 3, hd_matrix_at(C, k, t0 + t), 3 * sizeof(double));
        if ((st = hd_dcts_fold(comp, K, coef, nb, npix_pad, out, o->nthreads))) break;
        if (o->outspec) {
            write_ctx wc = {o, out, npix_pad, xres, yres, t0, scratch};
            st = hd_parallel_for((size_t)nb, 1, nworkers, write_step_file, &wc);
        } else {
            for (int t = 0; t < nb && !st; t++)
                st = write_picture_planar(hd_ofile_fp(single), o, T > 1 ? t0 + t : -1, out + (size_t)t * 3 * npix_pad,
                                          npix_pad, xres, yres, &scratch[0]);
        }
    }
    if (single) {
        if (st) hd_ofile_abort(single);
        else st = hd_ofile_commit(single);
    }
    for (int w = 0; scratch && w < nworkers; w++) hd_picture_free(&scratch[w]);
    free(scratch);
    free(out);
    free(coef);
    return st;
}

static hd_status picture_mode(const char *spec, const hd_matrix *C, const hd_dcts_opts *o)
{
    int K = C->nrows, T = C->ncols;
    unsigned char *need = hd_calloc((size_t)K, 1);
    float **comp = hd_calloc((size_t)K, sizeof *comp);
    int *xr = hd_calloc((size_t)K, sizeof(int)), *yr = hd_calloc((size_t)K, sizeof(int));
    hd_status st = (!need || !comp || !xr || !yr) ? HD_ERR_NOMEM : HD_OK;
    int nneed = 0;
    for (int k = 0; !st && k < K; k++) {
        for (int t = 0; t < T && !need[k]; t++) {
            const double *c = hd_matrix_at(C, k, t);
            need[k] = c[0] != 0 || c[1] != 0 || c[2] != 0;
        }
        nneed += need[k];
    }
    if (!st && o->verbose)
        fprintf(stderr, "%s: %d of %d component pictures have non-zero coefficients\n", hd_progname(), nneed, K);
    if (!st) {
        load_ctx lc = {spec, need, comp, xr, yr};
        st = hd_parallel_for((size_t)K, 1, o->nthreads, load_component, &lc);
    }
    int xres = 0, yres = 0, first = -1;
    for (int k = 0; !st && k < K; k++) {
        if (!comp[k]) continue;
        if (first < 0) { first = k; xres = xr[k]; yres = yr[k]; continue; }
        if (xr[k] != xres || yr[k] != yres) {
            char a[4096], b[4096];
            hd_pattern_format(a, sizeof a, spec, NULL, first);
            hd_pattern_format(b, sizeof b, spec, NULL, k);
            st = hd_fail(HD_ERR_FORMAT, "%s is %dx%d but %s is %dx%d: component pictures must have the same size", b,
                         xr[k], yr[k], a, xres, yres);
        }
    }
    if (!st && first < 0) {
        /* every coefficient is zero: size from the first picture that exists */
        char path[4096];
        for (int k = 0; k < K && first < 0; k++) {
            hd_pattern_format(path, sizeof path, spec, NULL, k);
            hd_picture pic;
            hd_picture_init(&pic);
            if (hd_picture_read(path, &pic) == HD_OK) { first = k; xres = pic.xres; yres = pic.yres; }
            hd_picture_free(&pic);
        }
        if (first < 0) st = hd_fail(HD_ERR_IO, "no component picture matching \"%s\" could be read", spec);
    }
    if (!st) {
        size_t npix_pad = ((size_t)xres * (size_t)yres + 15) & ~(size_t)15;
        st = fold_and_write(comp, K, C, npix_pad, xres, yres, o);
    }
    for (int k = 0; comp && k < K; k++) free(comp[k]);
    free(comp);
    free(need);
    free(xr);
    free(yr);
    return st;
}

/* ---------------------------------------------------------------- matrix mode */

typedef struct mm_ctx {
    const hd_matrix *A, *C;
    double *R;
    const int *steps; /* non-zero steps */
    int nsteps_nz;
} mm_ctx;

static hd_status mm_rows(void *vctx, size_t b, size_t e, size_t chunk, int worker)
{
    mm_ctx *c = vctx;
    (void)chunk;
    (void)worker;
    int K = c->A->ncols, T = c->C->ncols;
    for (size_t r = b; r < e; r++) {
        const double *a = c->A->data + r * (size_t)K * 3;
        for (int i = 0; i < c->nsteps_nz; i++) {
            int t = c->steps[i];
            double s0 = 0, s1 = 0, s2 = 0;
            for (int k = 0; k < K; k++) {
                const double *x = c->C->data + ((size_t)k * (size_t)T + (size_t)t) * 3;
                s0 += a[3 * k] * x[0];
                s1 += a[3 * k + 1] * x[1];
                s2 += a[3 * k + 2] * x[2];
            }
            double *o = c->R + (r * (size_t)T + (size_t)t) * 3;
            o[0] = s0;
            o[1] = s1;
            o[2] = s2;
        }
    }
    return HD_OK;
}

static hd_status matrix_mode(const char *dc_path, const hd_matrix *A, const hd_matrix *C, const hd_dcts_opts *o)
{
    if (A->ncols != C->nrows)
        return hd_fail(HD_ERR_FORMAT, "%s has %d columns but the coefficient vector has %d rows", dc_path, A->ncols,
                       C->nrows);
    if (A->ncomp != 3)
        return hd_fail(HD_ERR_FORMAT, "%s has %d components per element, expected 3", dc_path, A->ncomp);
    int T = C->ncols;
    double *R = hd_calloc((size_t)A->nrows * (size_t)T, 3 * sizeof(double));
    int *steps = hd_malloc_array((size_t)T, sizeof(int));
    if (!R || !steps) { free(R); free(steps); return HD_ERR_NOMEM; }
    int nz = 0;
    for (int t = 0; t < T; t++) {
        int any = 0;
        for (int k = 0; k < C->nrows && !any; k++) {
            const double *x = hd_matrix_at(C, k, t);
            any = x[0] != 0 || x[1] != 0 || x[2] != 0;
        }
        if (any) steps[nz++] = t;
    }
    mm_ctx mc = {A, C, R, steps, nz};
    hd_status st = hd_parallel_for((size_t)A->nrows, 16, o->nthreads, mm_rows, &mc);
    if (!st) {
        if (o->xres > 0 && o->yres > 0) { /* result vectors as pictures */
            if ((long)o->xres * o->yres != A->nrows)
                st = hd_fail(HD_ERR_USAGE, "-x %d -y %d makes %ld pixels but the result has %d rows", o->xres, o->yres,
                             (long)o->xres * o->yres, A->nrows);
            size_t np = ((size_t)A->nrows + 15) & ~(size_t)15;
            float *pl = st ? NULL : hd_calloc(3 * np, sizeof(float));
            if (!st && !pl) st = HD_ERR_NOMEM;
            hd_ofile *single = NULL;
            hd_picture scratch;
            hd_picture_init(&scratch);
            if (!st && !o->outspec) st = hd_ofile_open(&single, NULL);
            for (int t = 0; !st && t < T; t++) {
                for (int r = 0; r < A->nrows; r++)
                    for (int ch = 0; ch < 3; ch++)
                        pl[(size_t)ch * np + (size_t)r] = (float)R[((size_t)r * (size_t)T + (size_t)t) * 3 + (size_t)ch];
                if (single) {
                    st = write_picture_planar(hd_ofile_fp(single), o, T > 1 ? t : -1, pl, np, o->xres, o->yres, &scratch);
                } else {
                    hd_ofile *f;
                    if ((st = open_step_output(o, t, &f))) break;
                    st = write_picture_planar(hd_ofile_fp(f), o, t, pl, np, o->xres, o->yres, &scratch);
                    if (st) hd_ofile_abort(f);
                    else st = hd_ofile_commit(f);
                }
            }
            if (single) {
                if (st) hd_ofile_abort(single);
                else st = hd_ofile_commit(single);
            }
            hd_picture_free(&scratch);
            free(pl);
        } else if (o->outspec) {
            for (int t = 0; !st && t < T; t++) {
                hd_ofile *f;
                if ((st = open_step_output(o, t, &f))) break;
                st = write_matrix(hd_ofile_fp(f), o, t, R, A->nrows, 1, (size_t)T, (size_t)t);
                if (st) hd_ofile_abort(f);
                else st = hd_ofile_commit(f);
            }
        } else {
            hd_ofile *f;
            if (!(st = hd_ofile_open(&f, NULL))) {
                st = write_matrix(hd_ofile_fp(f), o, -1, R, A->nrows, T, (size_t)T, 0);
                if (st) hd_ofile_abort(f);
                else st = hd_ofile_commit(f);
            }
        }
    }
    free(R);
    free(steps);
    return st;
}

/* ---------------------------------------------------------------- driver */

hd_status hd_dctimestep(int n, char **in, const hd_dcts_opts *o)
{
    if (n < 1 || n > 4) return hd_fail(HD_ERR_USAGE, "expected DC [sky] or V T D [sky], got %d file names", n);
    if (o->outspec) {
        int k = hd_pattern_kind(o->outspec);
        if (k < 0) return HD_ERR_USAGE;
        if (!(k & 1)) return hd_fail(HD_ERR_USAGE, "-o %s: the output pattern needs a %%d for the time step", o->outspec);
    }
    int three = n >= 3;
    const char *first = in[0];
    const char *sky = (three ? n == 4 : n == 2) ? in[n - 1] : NULL;
    int kind = hd_pattern_kind(first);
    if (kind < 0) return HD_ERR_USAGE;
    int picmode = kind & 1;
    hd_matrix A, C;
    hd_matrix_init(&A);
    hd_matrix_init(&C);
    hd_status st = HD_OK;
    if (!picmode) st = hd_matrix_read(first, &A, NULL);
    if (!st) st = hd_dcts_coefficients(three ? in[1] : NULL, three ? in[2] : NULL, sky, o, picmode ? 0 : A.ncols, &C);
    if (!st && o->verbose)
        fprintf(stderr, "%s: %d coefficients x %d time steps\n", hd_progname(), C.nrows, C.ncols);
    if (!st) st = picmode ? picture_mode(first, &C, o) : matrix_mode(first, &A, &C, o);
    hd_matrix_free(&A);
    hd_matrix_free(&C);
    return st;
}

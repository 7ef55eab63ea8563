/* heliodon — dctimestep: daylight coefficients × sky, 3-phase V·T·D·S,
 * component-picture folding. */
#include "heliodon/dctimestep.h"
#include "heliodon/exr.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/parallel.h"
#include "heliodon/picture.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

void hd_dcts_opts_init(hd_dcts_opts *o)
{
    memset(o, 0, sizeof *o);
    o->sky_fmt = -1;
    o->out_fmt = HD_MTX_ASCII;
    o->header = 1;
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

/* The fold is a matrix product per colour channel: out[t][p] =
 * Σ_k c[k][t]·comp[k][p] with K ≈ 150 components, thousands of steps and
 * 10^4..10^6 pixels.  It runs as register tiles: TS time steps × W pixels
 * of accumulators stay in vector registers while k runs over the
 * components (each component's W pixels are loaded once per tile and used
 * TS times), so the inner loop does no memory writes.  The sum is the
 * float sum over k in ascending order, each term a separate multiply and
 * add (no fused multiply-add), so every kernel — portable C, AVX2, AVX-512
 * — gives bit-identical results, whatever the thread count or CPU. */

#define TS 6 /* time steps per register tile */

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define HD_DCTS_X86 1
#include <immintrin.h>
#else
#define HD_DCTS_X86 0
#endif

/* A tile: for t < nt (<= TS) and x < W: out[t*ostride + x] =
 * Σ_{k<K} cf[k*TS + t] · src[k][off + x]  (cf rows beyond nt are zero). */
typedef void (*tile_fn)(const float *const *src, size_t off, const float *cf, int K, float *out, size_t ostride,
                        int nt);

#define REP6(M) M(0) M(1) M(2) M(3) M(4) M(5)

static void tile16_c(const float *const *src, size_t off, const float *cf, int K, float *out, size_t ostride, int nt)
{
    float acc[TS][16];
    memset(acc, 0, sizeof acc);
    for (int k = 0; k < K; k++) {
        const float *s = src[k] + off, *c = cf + (size_t)k * TS;
        for (int t = 0; t < TS; t++) {
            float a = c[t];
            for (int j = 0; j < 16; j++) acc[t][j] += a * s[j];
        }
    }
    for (int t = 0; t < nt; t++) memcpy(out + (size_t)t * ostride, acc[t], sizeof acc[t]);
}

#if HD_DCTS_X86
/* AVX2, 16 pixels (2 registers) × 6 steps: 12 accumulators. */
__attribute__((target("avx2"))) static void tile16_avx2(const float *const *src, size_t off, const float *cf, int K,
                                                         float *out, size_t ostride, int nt)
{
#define DECL(t) __m256 a##t##0 = _mm256_setzero_ps(), a##t##1 = _mm256_setzero_ps();
    REP6(DECL)
#undef DECL
    for (int k = 0; k < K; k++) {
        const float *s = src[k] + off, *c = cf + (size_t)k * TS;
        __m256 s0 = _mm256_loadu_ps(s), s1 = _mm256_loadu_ps(s + 8);
#define STEP(t)                                                                                                  \
    {                                                                                                            \
        __m256 w = _mm256_broadcast_ss(c + t);                                                                   \
        a##t##0 = _mm256_add_ps(a##t##0, _mm256_mul_ps(w, s0));                                                  \
        a##t##1 = _mm256_add_ps(a##t##1, _mm256_mul_ps(w, s1));                                                  \
    }
        REP6(STEP)
#undef STEP
    }
#define STORE(t)                                                                                                 \
    if (t < nt) {                                                                                                \
        _mm256_storeu_ps(out + (size_t)t * ostride, a##t##0);                                                   \
        _mm256_storeu_ps(out + (size_t)t * ostride + 8, a##t##1);                                               \
    }
    REP6(STORE)
#undef STORE
}

/* AVX-512, 64 pixels (4 registers) × 6 steps: 24 of the 32 registers. */
__attribute__((target("avx512f"))) static void tile64_avx512(const float *const *src, size_t off, const float *cf,
                                                              int K, float *out, size_t ostride, int nt)
{
#define DECL(t)                                                                                                  \
    __m512 a##t##0 = _mm512_setzero_ps(), a##t##1 = _mm512_setzero_ps(), a##t##2 = _mm512_setzero_ps(),        \
           a##t##3 = _mm512_setzero_ps();
    REP6(DECL)
#undef DECL
    for (int k = 0; k < K; k++) {
        const float *s = src[k] + off, *c = cf + (size_t)k * TS;
        __m512 s0 = _mm512_loadu_ps(s), s1 = _mm512_loadu_ps(s + 16), s2 = _mm512_loadu_ps(s + 32),
               s3 = _mm512_loadu_ps(s + 48);
#define STEP(t)                                                                                                  \
    {                                                                                                            \
        __m512 w = _mm512_set1_ps(c[t]);                                                                         \
        a##t##0 = _mm512_add_ps(a##t##0, _mm512_mul_ps(w, s0));                                                  \
        a##t##1 = _mm512_add_ps(a##t##1, _mm512_mul_ps(w, s1));                                                  \
        a##t##2 = _mm512_add_ps(a##t##2, _mm512_mul_ps(w, s2));                                                  \
        a##t##3 = _mm512_add_ps(a##t##3, _mm512_mul_ps(w, s3));                                                  \
    }
        REP6(STEP)
#undef STEP
    }
#define STORE(t)                                                                                                 \
    if (t < nt) {                                                                                                \
        float *o = out + (size_t)t * ostride;                                                                    \
        _mm512_storeu_ps(o, a##t##0);                                                                            \
        _mm512_storeu_ps(o + 16, a##t##1);                                                                       \
        _mm512_storeu_ps(o + 32, a##t##2);                                                                       \
        _mm512_storeu_ps(o + 48, a##t##3);                                                                       \
    }
    REP6(STORE)
#undef STORE
}
#endif

/* Kernel level: 0 portable C, 1 AVX2, 2 AVX-512 (the best the CPU has,
 * hd_cpu_level, unless lowered with hd_dcts_set_kernel). */
static int kernel_use = -1;

int hd_dcts_set_kernel(int level)
{
    int mx = HD_DCTS_X86 ? hd_cpu_level() : 0;
    int u = level < 0 || level > mx ? mx : level;
    __atomic_store_n(&kernel_use, u, __ATOMIC_RELAXED);
    return u;
}

static int kernel_level(void)
{
    int u = __atomic_load_n(&kernel_use, __ATOMIC_RELAXED);
    return u < 0 ? hd_dcts_set_kernel(-1) : u;
}

/* One channel of a span of width pixels (a multiple of 16) for every step:
 * out[t*ostride + x] for t < nsteps, x < width; cf is the packed
 * coefficient block of this channel: [tile][k][TS], tile = t / TS. */
static void fold_span(int level, const float *const *src, size_t off, int K, const float *cf, int nsteps, float *out,
                      size_t ostride, size_t width)
{
    tile_fn k16 = tile16_c;
#if HD_DCTS_X86
    if (level >= 1) k16 = tile16_avx2;
#endif
    size_t x = 0;
#if HD_DCTS_X86
    if (level >= 2)
        for (; x + 64 <= width; x += 64)
            for (int t0 = 0; t0 < nsteps; t0 += TS)
                tile64_avx512(src, off + x, cf + (size_t)(t0 / TS) * (size_t)K * TS, K, out + (size_t)t0 * ostride + x,
                              ostride, nsteps - t0 < TS ? nsteps - t0 : TS);
#else
    (void)level;
#endif
    for (; x < width; x += 16)
        for (int t0 = 0; t0 < nsteps; t0 += TS)
            k16(src, off + x, cf + (size_t)(t0 / TS) * (size_t)K * TS, K, out + (size_t)t0 * ostride + x, ostride,
                nsteps - t0 < TS ? nsteps - t0 : TS);
}

/* Pack coefficients of the steps steps[0..nb) (NULL: 0..nb) of the
 * components kidx[0..Kn) into cf[ch][tile][k][TS] (zero padded). */
static void pack_coef(const double *coef, size_t coef_stride_k, const int *kidx, int Kn, const int *steps, int nb,
                      float *cf)
{
    int ntile = (nb + TS - 1) / TS;
    size_t chsz = (size_t)ntile * (size_t)Kn * TS;
    memset(cf, 0, 3 * chsz * sizeof(float));
    for (int ch = 0; ch < 3; ch++)
        for (int i = 0; i < nb; i++) {
            int t = steps ? steps[i] : i;
            float *dst = cf + (size_t)ch * chsz + (size_t)(i / TS) * (size_t)Kn * TS + (size_t)(i % TS);
            for (int k = 0; k < Kn; k++)
                dst[(size_t)k * TS] = (float)coef[(size_t)kidx[k] * coef_stride_k + (size_t)t * 3 + (size_t)ch];
        }
}

typedef struct fold_ctx {
    const float *const *src; /* the Kn non-NULL components */
    int Kn, nsteps, level;
    const float *cf;
    size_t npix;
    float *out;
} fold_ctx;

static hd_status fold_chunk(void *vctx, size_t b, size_t e, size_t chunk, int worker)
{
    fold_ctx *c = vctx;
    (void)chunk;
    (void)worker;
    size_t chsz = (size_t)((c->nsteps + TS - 1) / TS) * (size_t)c->Kn * TS;
    for (int ch = 0; ch < 3; ch++)
        fold_span(c->level, c->src, (size_t)ch * c->npix + b, c->Kn, c->cf + (size_t)ch * chsz, c->nsteps,
                  c->out + (size_t)ch * c->npix + b, 3 * c->npix, e - b);
    return HD_OK;
}

hd_status hd_dcts_fold(float *const *comp, int K, const double *coef, int nsteps, size_t npix, float *out,
                       int nthreads)
{
    if (npix % 16) return hd_fail(HD_ERR_INTERNAL, "hd_dcts_fold: pixel count %zu not padded to 16", npix);
    if (nsteps <= 0) return HD_OK;
    int *kidx = hd_malloc_array((size_t)K + 1, sizeof(int));
    const float **src = hd_malloc_array((size_t)K + 1, sizeof *src);
    int ntile = (nsteps + TS - 1) / TS;
    float *cf = hd_malloc_array(3 * (size_t)ntile * ((size_t)K + 1), TS * sizeof(float));
    hd_status st = (!kidx || !src || !cf) ? HD_ERR_NOMEM : HD_OK;
    int Kn = 0;
    for (int k = 0; !st && k < K; k++)
        if (comp[k]) { kidx[Kn] = k; src[Kn++] = comp[k]; }
    if (!st) {
        pack_coef(coef, (size_t)nsteps * 3, kidx, Kn, NULL, nsteps, cf);
        fold_ctx c = {src, Kn, nsteps, kernel_level(), cf, npix, out};
        st = hd_parallel_for(npix, 512, nthreads, fold_chunk, &c);
    }
    free(kidx);
    free(src);
    free(cf);
    return st;
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

/* Matrix output in Radiance dctimestep's layout, through the matrix
 * writer: the header (unless -h) with nrows x ncols x 3 ... */
static hd_status matrix_begin(hd_mtxwriter *w, FILE *fp, const hd_dcts_opts *o, long frame, int nrows, int ncols)
{
    hd_header h;
    memset(w, 0, sizeof *w);
    hd_status st = base_header(o, frame, &h);
    hd_mtxfmt f = o->out_fmt == HD_MTX_FLOAT || o->out_fmt == HD_MTX_DOUBLE ? o->out_fmt : HD_MTX_ASCII;
    if (!st) st = hd_mtxwriter_begin(w, fp, &h, o->header ? HD_MTXW_HEADER : 0, f, nrows, ncols, 3);
    hd_header_free(&h);
    w->ascii_style = HD_MTXASCII_DCTIMESTEP;
    return st;
}

/* ... then rows: element c of row r of v at (r*col_stride + col0 + c)*3 */
static hd_status matrix_rows(hd_mtxwriter *w, const double *v, int nrows, size_t col_stride, size_t col0)
{
    hd_status st = HD_OK;
    for (int r = 0; r < nrows && !st; r++) st = hd_mtxwriter_row(w, v + ((size_t)r * col_stride + col0) * 3);
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
    if (!st) st = o->outspec && hd_has_suffix(o->outspec, ".exr") ? hd_exr_write_picture(fp, o->outspec, &pic, &h)
                                                             : hd_picture_write(fp, &pic, &h, HD_RES_STANDARD);
    hd_header_free(&h);
    return st;
}

/* A failed write of step file f: its name and the system's reason (a full
 * disk, a file-size limit) put before the message. */
static hd_status step_failed(hd_status st, hd_ofile *f)
{
    int e = errno;
    if (e) st = hd_fail_context(st, "%s (%s)", hd_ofile_name(f), strerror(e));
    else st = hd_fail_context(st, "%s", hd_ofile_name(f));
    hd_ofile_abort(f);
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

/* -r: the steps whose file an earlier run wrote (every -o file is committed
 * by rename, so one that exists is complete; with a header, it must name its
 * step in FRAME=).  *done is NULL when nothing is to be kept. */
static hd_status done_steps(const hd_dcts_opts *o, int T, unsigned char **done, int *ndone)
{
    *done = NULL;
    *ndone = 0;
    if (!o->resume || !o->outspec) return HD_OK;
    unsigned char *d = hd_calloc((size_t)T + 1, 1);
    if (!d) return HD_ERR_NOMEM;
    for (int t = 0; t < T; t++) {
        char name[4096];
        hd_status st = hd_pattern_format(name, sizeof name, o->outspec, NULL, t);
        if (st) { free(d); return st; }
        if (access(name, F_OK) != 0) continue;
        if (o->header) {
            hd_istream *in;
            hd_header h;
            long frame = -1;
            int found = 0;
            if (hd_istream_open(&in, name) == HD_OK) {
                if (hd_header_read(in, &h, 0) == HD_OK) {
                    if (hd_header_get_long(&h, "FRAME", &frame, &found) != HD_OK) found = 0;
                    hd_header_free(&h);
                }
                hd_istream_close(in);
            }
            hd_clear_error();
            if (!found || frame != t) {
                hd_warn("-r: %s does not hold step %d (FRAME=); it is computed again", name, t);
                continue;
            }
        }
        d[t] = 1;
        (*ndone)++;
    }
    if (o->verbose || *ndone)
        fprintf(stderr, "%s: -r: %d of %d step files already written, computing %d\n", hd_progname(), *ndone, T,
                T - *ndone);
    *done = d;
    return HD_OK;
}

/* Refuse a series that will not fit on the disk (before any work). */
static hd_status series_disk(const hd_dcts_opts *o, uint64_t bytes, int nfiles)
{
    char what[4200];
    snprintf(what, sizeof what, "-o %s (%d files)", o->outspec, nfiles);
    return hd_check_disk(o->outspec, bytes, what);
}

/* ---------------------------------------------------------------- picture mode */

/* Large zeroed buffers (components, encoded output) */
/* Component pictures are held as planar float, rows padded to a multiple
 * of 16 pixels: comp[k][(ch*yres + y)*xpad + x].  A run is cut into blocks
 * of consecutive time steps whose non-black steps fit in
 * HD_DCTS_BLOCK_BYTES of encoded output.  For a block, every scanline is a
 * work unit: its 3 × xpad × K component floats (450 KB for 256 pixels and
 * 146 components) stay in the L2 cache while all the block's steps are
 * folded in sub-blocks of PM_TSUB steps and each result scanline is at once
 * RGBE- and run-length encoded into that step's slot; so the float results
 * never go to memory and the components are read from memory once per
 * block.  Steps whose coefficients are all zero (night) are not computed:
 * their picture body is encoded once.  Then the block's files are written
 * (in parallel with -o: the header, then the scanlines). */

#define PM_TSUB 48 /* steps folded per scanline sub-block (a multiple of TS) */

typedef struct load_ctx {
    const char *spec;
    const unsigned char *need;
    float **comp;     /* comp[k]: its place in the region (needed ones) */
    int xres, yres;   /* the size every component must have */
    size_t xpad, plane;
    const char *first; /* name of the picture the size came from */
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
        if (pic.xres != c->xres || pic.yres != c->yres) {
            st = hd_fail(HD_ERR_FORMAT, "%s is %dx%d but %s is %dx%d: component pictures must have the same size", path,
                         pic.xres, pic.yres, c->first, c->xres, c->yres);
            hd_picture_free(&pic);
            return st;
        }
        float *pl = c->comp[k];
        double ex = hd_header_exposure(&pic.hdr);
        float inv = (float)(1.0 / ex);
        for (size_t y = 0; y < (size_t)pic.yres; y++)
            for (size_t x = 0; x < (size_t)pic.xres; x++)
                for (int ch = 0; ch < 3; ch++)
                    pl[(size_t)ch * c->plane + y * c->xpad + x] = pic.pix[3 * (y * (size_t)pic.xres + x) + (size_t)ch] * inv;
        hd_picture_free(&pic);
    }
    return HD_OK;
}

/* Size of the picture named by pattern spec for index k (header only). */
static hd_status picture_size(const char *spec, long k, int *xres, int *yres, char *name, size_t cap)
{
    hd_status st = hd_pattern_format(name, cap, spec, NULL, k);
    if (st) return st;
    hd_istream *s;
    if ((st = hd_istream_open(&s, name))) return st;
    hd_header h;
    hd_picfmt fmt;
    hd_resolu r;
    st = hd_picture_read_header(s, &h, &fmt, &r);
    if (!st) {
        hd_header_free(&h);
        *xres = r.xres;
        *yres = r.yres;
    }
    hd_istream_close(s);
    return st;
}

typedef struct pm_ctx {
    const hd_dcts_opts *o;
    int exr;                 /* EXR outputs: slots hold interleaved float pictures */
    const float *const *src; /* Kn needed components */
    int Kn, level, xres, yres;
    size_t xpad, plane;
    /* current block */
    const float *cf;          /* [ch][tile][k][TS] for the block's nb computed steps */
    int nb;
    uint8_t *slots;           /* per computed step: step_bytes */
    size_t slot_bytes;        /* RGBE: one encoded scanline's room */
    size_t step_bytes;
    uint32_t *lens;           /* [nb][yres] encoded scanline lengths (RGBE) */
    float **tbuf;             /* per worker: [PM_TSUB][3][xpad] */
    uint8_t **ebuf;           /* per worker: 4*xres RGBE bytes */
    /* writing */
    int T0, T1;               /* steps of the block */
    const int *slot_of;       /* step - T0 -> computed index, or -1 (black) */
    const uint8_t *black;     /* encoded black body (RGBE) */
    size_t black_len;
    const float *black_f;     /* zero picture (EXR) */
    FILE *single;             /* stdout output, or NULL for -o files */
    const unsigned char *done; /* -r: steps whose file exists (not computed, not written) */
} pm_ctx;

static hd_status pm_scanline(void *vctx, size_t b, size_t e, size_t chunk, int worker)
{
    pm_ctx *c = vctx;
    (void)chunk;
    float *tb = c->tbuf[worker];
    uint8_t *eb = c->ebuf[worker];
    int ntile = (c->nb + TS - 1) / TS;
    size_t chsz = (size_t)ntile * (size_t)c->Kn * TS;
    for (size_t y = b; y < e; y++) {
        for (int s0 = 0; s0 < c->nb; s0 += PM_TSUB) {
            int ns = c->nb - s0 < PM_TSUB ? c->nb - s0 : PM_TSUB;
            for (int ch = 0; ch < 3; ch++)
                fold_span(c->level, c->src, (size_t)ch * c->plane + y * c->xpad, c->Kn,
                          c->cf + (size_t)ch * chsz + (size_t)(s0 / TS) * (size_t)c->Kn * TS, ns,
                          tb + (size_t)ch * c->xpad, 3 * c->xpad, c->xpad);
            for (int i = 0; i < ns; i++) {
                const float *r = tb + (size_t)i * 3 * c->xpad;
                uint8_t *slot = c->slots + (size_t)(s0 + i) * c->step_bytes;
                if (c->exr) {
                    float *row = (float *)(void *)slot + y * (size_t)c->xres * 3;
                    for (int x = 0; x < c->xres; x++) {
                        row[3 * x] = r[x];
                        row[3 * x + 1] = r[c->xpad + (size_t)x];
                        row[3 * x + 2] = r[2 * c->xpad + (size_t)x];
                    }
                } else {
                    hd_rgbe_encode_planar_bytes(eb, r, r + c->xpad, r + 2 * c->xpad, (size_t)c->xres);
                    c->lens[(size_t)(s0 + i) * (size_t)c->yres + y] =
                        (uint32_t)hd_scanline_encode_planar(slot + y * c->slot_bytes, eb, c->xres);
                }
            }
        }
    }
    return HD_OK;
}

/* Write step t of the block to fp (header, resolution, pixels). */
static hd_status pm_write_step(pm_ctx *c, FILE *fp, int t, long frame)
{
    hd_header h;
    hd_header_init(&h);
    hd_status st = c->o->header ? base_header(c->o, frame, &h) : HD_OK;
    int si = c->slot_of[t - c->T0];
    if (c->exr) {
        if (!st) {
            hd_picture pic;
            hd_picture_init(&pic);
            pic.xres = c->xres;
            pic.yres = c->yres;
            pic.pix = (float *)(si < 0 ? c->black_f : (const float *)(const void *)(c->slots + (size_t)si * c->step_bytes));
            st = hd_exr_write_picture(fp, c->o->outspec, &pic, &h);
        }
        hd_header_free(&h);
        return st;
    }
    hd_resolu r = {HD_RES_STANDARD, c->xres, c->yres};
    if (!st) st = hd_picture_write_header(fp, &h, HD_PIC_RGBE, &r);
    hd_header_free(&h);
    if (st) return st;
    if (si < 0) {
        if (fwrite(c->black, 1, c->black_len, fp) != c->black_len) return hd_fail(HD_ERR_IO, "write error");
        return HD_OK;
    }
    /* compact the scanlines of the slot and write them at once */
    uint8_t *slot = c->slots + (size_t)si * c->step_bytes;
    const uint32_t *len = c->lens + (size_t)si * (size_t)c->yres;
    size_t n = 0;
    for (int y = 0; y < c->yres; y++) {
        if (n != (size_t)y * c->slot_bytes) memmove(slot + n, slot + (size_t)y * c->slot_bytes, len[y]);
        n += len[y];
    }
    if (fwrite(slot, 1, n, fp) != n) return hd_fail(HD_ERR_IO, "write error");
    return HD_OK;
}

static hd_status pm_write_files(void *vctx, size_t b, size_t e, size_t chunk, int worker)
{
    pm_ctx *c = vctx;
    (void)chunk;
    (void)worker;
    for (size_t i = b; i < e; i++) {
        int t = c->T0 + (int)i;
        if (c->done && c->done[t]) continue;
        hd_ofile *f;
        hd_status st = open_step_output(c->o, t, &f);
        if (st) return st;
        errno = 0;
        st = pm_write_step(c, hd_ofile_fp(f), t, t);
        if (st) return step_failed(st, f);
        if ((st = hd_ofile_commit(f))) return st;
    }
    return HD_OK;
}

/* Fold the components with coefficient matrix C (K × T × 3) and write
 * one picture per step. */
static hd_status fold_and_write(float **comp, int K, const hd_matrix *C, int xres, int yres, const hd_dcts_opts *o)
{
    int T = C->ncols;
    size_t xpad = ((size_t)xres + 15) & ~(size_t)15;
    int exr = o->outspec && hd_has_suffix(o->outspec, ".exr");
    int nworkers = hd_resolve_threads(o->nthreads);
    pm_ctx c;
    memset(&c, 0, sizeof c);
    c.o = o;
    c.exr = exr;
    c.level = kernel_level();
    c.xres = xres;
    c.yres = yres;
    c.xpad = xpad;
    c.plane = xpad * (size_t)yres;
    c.slot_bytes = hd_scanline_maxbytes(xres);
    c.step_bytes = exr ? (size_t)xres * (size_t)yres * 3 * sizeof(float) : c.slot_bytes * (size_t)yres;
    int *kidx = hd_malloc_array((size_t)K + 1, sizeof(int));
    const float **src = hd_malloc_array((size_t)K + 1, sizeof *src);
    int *nz = hd_malloc_array((size_t)T + 1, sizeof(int));     /* non-black steps */
    int *slot_of = hd_malloc_array((size_t)T + 1, sizeof(int));
    c.tbuf = hd_calloc((size_t)nworkers, sizeof *c.tbuf);
    c.ebuf = hd_calloc((size_t)nworkers, sizeof *c.ebuf);
    hd_status st = (!kidx || !src || !nz || !slot_of || !c.tbuf || !c.ebuf) ? HD_ERR_NOMEM : HD_OK;
    for (int w = 0; !st && w < nworkers; w++) {
        c.tbuf[w] = hd_malloc_array((size_t)PM_TSUB * 3, xpad * sizeof(float));
        c.ebuf[w] = hd_malloc_array((size_t)xres, 4);
        if (!c.tbuf[w] || !c.ebuf[w]) st = HD_ERR_NOMEM;
    }
    int Kn = 0, nnz = 0;
    for (int k = 0; !st && k < K; k++)
        if (comp[k]) { kidx[Kn] = k; src[Kn++] = comp[k]; }
    for (int t = 0; !st && t < T; t++) {
        int any = 0;
        for (int k = 0; k < Kn && !any; k++) {
            const double *v = hd_matrix_at(C, kidx[k], t);
            any = v[0] != 0 || v[1] != 0 || v[2] != 0;
        }
        if (any) nz[nnz++] = t;
    }
    unsigned char *done = NULL;
    int ndone = 0;
    if (!st) st = done_steps(o, T, &done, &ndone);
    if (done) {   /* -r: the steps already written are not computed */
        int k = 0;
        for (int i = 0; i < nnz; i++)
            if (!done[nz[i]]) nz[k++] = nz[i];
        nnz = k;
    }
    c.done = done;
    if (!st && o->outspec) {
        /* about the uncompressed size of each picture still to write (black
         * ones are a few bytes a scanline) */
        uint64_t pic = exr ? (uint64_t)xres * (uint64_t)yres * 12 : (uint64_t)xres * (uint64_t)yres * 4;
        uint64_t need = (uint64_t)nnz * pic + (uint64_t)(T - ndone - nnz) * ((uint64_t)yres * 8 + 4096) +
                        (uint64_t)(T - ndone) * 1024;
        st = series_disk(o, need, T - ndone);
    }
    c.src = src;
    c.Kn = Kn;
    /* block size: computed steps whose encoded output fits the budget */
    int batch = (int)(HD_DCTS_BLOCK_BYTES / c.step_bytes);
    if (batch < 1) batch = 1;
    if (batch > nnz) batch = nnz > 0 ? nnz : 1;
    size_t slots_bytes = (size_t)batch * c.step_bytes;
    uint8_t *slots = st ? NULL : hd_big_alloc(slots_bytes, 1, 1);
    uint32_t *lens = st ? NULL : hd_malloc_array((size_t)batch * (size_t)yres, sizeof(uint32_t));
    int ntile_max = (batch + TS - 1) / TS;
    float *cf = st ? NULL : hd_malloc_array(3 * (size_t)ntile_max * ((size_t)Kn + 1), TS * sizeof(float));
    /* the black picture: body encoded once (RGBE), or zero floats (EXR) */
    uint8_t *black = NULL;
    float *black_f = NULL;
    size_t black_len = 0;
    if (!st && nnz < T) {
        if (exr) {
            black_f = hd_calloc((size_t)xres * (size_t)yres, 3 * sizeof(float));
            if (!black_f) st = HD_ERR_NOMEM;
        } else {
            uint8_t *zero = hd_calloc((size_t)xres, 4);
            black = hd_malloc_array((size_t)yres, c.slot_bytes);
            if (!zero || !black) st = HD_ERR_NOMEM;
            for (int y = 0; !st && y < yres; y++) black_len += hd_scanline_encode(black + black_len, zero, xres);
            free(zero);
        }
    }
    if (!st && (!slots || !lens || !cf)) st = HD_ERR_NOMEM;
    c.slots = slots;
    c.lens = lens;
    c.cf = cf;
    c.slot_of = slot_of;
    c.black = black;
    c.black_len = black_len;
    c.black_f = black_f;
    hd_ofile *single = NULL;
    if (!st && !o->outspec) {
        st = hd_ofile_open(&single, NULL);
        if (!st) c.single = hd_ofile_fp(single);
    }
    if (!st && o->verbose)
        fprintf(stderr, "%s: %d of %d steps non-black, blocks of up to %d steps (%d blocks), kernel level %d\n",
                hd_progname(), nnz, T, batch, nnz > 0 ? (nnz + batch - 1) / batch : 0, c.level);
    int inz = 0; /* next non-black step */
    for (int T0 = 0; !st && T0 < T;) {
        /* the block: up to batch non-black steps and the black ones before the next */
        int nb = nnz - inz < batch ? nnz - inz : batch;
        int T1 = inz + nb < nnz ? nz[inz + nb] : T;
        for (int t = T0; t < T1; t++) slot_of[t - T0] = -1;
        for (int i = 0; i < nb; i++) slot_of[nz[inz + i] - T0] = i;
        c.T0 = T0;
        c.T1 = T1;
        c.nb = nb;
        if (nb > 0) {
            pack_coef(C->data, (size_t)T * 3, kidx, Kn, nz + inz, nb, cf);
            st = hd_parallel_for((size_t)yres, 1, nworkers, pm_scanline, &c);
        }
        if (!st) {
            if (o->outspec)
                st = hd_parallel_for((size_t)(T1 - T0), 1, nworkers, pm_write_files, &c);
            else
                for (int t = T0; t < T1 && !st; t++) st = pm_write_step(&c, c.single, t, T > 1 ? t : -1);
        }
        inz += nb;
        T0 = T1;
    }
    if (single) {
        if (st) hd_ofile_abort(single);
        else st = hd_ofile_commit(single);
    }
    for (int w = 0; w < nworkers; w++) {
        if (c.tbuf) free(c.tbuf[w]);
        if (c.ebuf) free(c.ebuf[w]);
    }
    free(c.tbuf);
    free(c.ebuf);
    free(kidx);
    free(src);
    free(nz);
    free(done);
    free(slot_of);
    free(slots);
    free(lens);
    free(cf);
    free(black);
    free(black_f);
    return st;
}

static hd_status picture_mode(const char *spec, const hd_matrix *C, const hd_dcts_opts *o)
{
    int K = C->nrows, T = C->ncols;
    unsigned char *need = hd_calloc((size_t)K, 1);
    float **comp = hd_calloc((size_t)K, sizeof *comp);
    hd_status st = (!need || !comp) ? HD_ERR_NOMEM : HD_OK;
    int nneed = 0, first = -1;
    for (int k = 0; !st && k < K; k++) {
        for (int t = 0; t < T && !need[k]; t++) {
            const double *c = hd_matrix_at(C, k, t);
            need[k] = c[0] != 0 || c[1] != 0 || c[2] != 0;
        }
        nneed += need[k];
        if (need[k] && first < 0) first = k;
    }
    if (!st && o->verbose)
        fprintf(stderr, "%s: %d of %d component pictures have non-zero coefficients\n", hd_progname(), nneed, K);
    int xres = 0, yres = 0;
    char firstname[4096];
    if (!st && first >= 0) st = picture_size(spec, first, &xres, &yres, firstname, sizeof firstname);
    if (!st && first < 0) {
        /* every coefficient is zero: size from the first picture that exists */
        for (int k = 0; k < K && first < 0; k++)
            if (picture_size(spec, k, &xres, &yres, firstname, sizeof firstname) == HD_OK) first = k;
        hd_clear_error();
        if (first < 0) st = hd_fail(HD_ERR_IO, "no component picture matching \"%s\" could be read", spec);
    }
    size_t xpad = ((size_t)xres + 15) & ~(size_t)15, plane = xpad * (size_t)yres;
    size_t region_bytes = 0;
    float *region = NULL;
    if (!st && nneed > 0) {
        if (plane > (SIZE_MAX / sizeof(float)) / 3 / (size_t)nneed) st = HD_ERR_NOMEM;
        else {
            region_bytes = (size_t)nneed * 3 * plane * sizeof(float);
            region = hd_big_alloc(region_bytes, 1, 1);
            if (!region)
                st = hd_fail_context(HD_ERR_NOMEM, "%d component pictures of %d x %d (%s)", nneed, xres, yres, spec);
        }
        for (int k = 0, i = 0; !st && k < K; k++)
            if (need[k]) comp[k] = region + (size_t)(i++) * 3 * plane;
    }
    if (!st && nneed > 0) {
        load_ctx lc = {spec, need, comp, xres, yres, xpad, plane, firstname};
        st = hd_parallel_for((size_t)K, 1, o->nthreads, load_component, &lc);
    }
    if (!st) st = fold_and_write(comp, K, C, xres, yres, o);
    free(region);
    free(comp);
    free(need);
    return st;
}

/* ---------------------------------------------------------------- matrix mode */

typedef struct mm_ctx {
    const hd_matrix *A;
    const double *Cp; /* non-zero steps in groups of MM_TS: [group][k][3][MM_TS] (zero padded) */
    double *R;
    const int *steps; /* non-zero steps */
    int nsteps_nz, T;
    size_t row0; /* R holds rows row0.. */
} mm_ctx;

#define MM_TS 8 /* steps per tile */
#define MM_RB 2 /* rows per tile */

/* Rows a0, a1 (K × 3 each) against one group of MM_TS steps: s[r][ch][j]
 * = Σ_k a_r[3k+ch] · x[k][ch][j], double, k ascending (separate multiply
 * and add: the same bits in every clone). */
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(__SANITIZE_ADDRESS__)
__attribute__((target_clones("avx512f", "avx2", "default")))
#endif
static void mm_tile(const double *a0, const double *a1, const double *x, int K, double s[MM_RB][3][MM_TS])
{
    double acc[MM_RB][3][MM_TS];
    memset(acc, 0, sizeof acc);
    for (int k = 0; k < K; k++)
        for (int ch = 0; ch < 3; ch++) {
            const double *xv = x + ((size_t)k * 3 + (size_t)ch) * MM_TS;
            double v0 = a0[3 * k + ch], v1 = a1[3 * k + ch];
            for (int j = 0; j < MM_TS; j++) {
                acc[0][ch][j] += v0 * xv[j];
                acc[1][ch][j] += v1 * xv[j];
            }
        }
    memcpy(s, acc, sizeof acc);
}

/* Rows [b,e) (a block of 16 rows, in L1/L2) against every group of
 * non-zero steps (each group's coefficients, K × 3 × 8 doubles, read once
 * per block from a contiguous copy: the sky matrix itself is K × T, so a
 * step's column is strided by T). */
static hd_status mm_rows(void *vctx, size_t b, size_t e, size_t chunk, int worker)
{
    mm_ctx *c = vctx;
    (void)chunk;
    (void)worker;
    int K = c->A->ncols, T = c->T;
    double s[MM_RB][3][MM_TS];
    for (int g = 0; g * MM_TS < c->nsteps_nz; g++) {
        const double *x = c->Cp + (size_t)g * (size_t)K * 3 * MM_TS;
        int nt = c->nsteps_nz - g * MM_TS < MM_TS ? c->nsteps_nz - g * MM_TS : MM_TS;
        for (size_t r = b; r < e; r += MM_RB) {
            const double *a0 = c->A->data + (c->row0 + r) * (size_t)K * 3;
            const double *a1 = r + 1 < e ? a0 + (size_t)K * 3 : a0;
            mm_tile(a0, a1, x, K, s);
            for (int q = 0; q < MM_RB && r + (size_t)q < e; q++)
                for (int j = 0; j < nt; j++) {
                    double *o = c->R + ((r + (size_t)q) * (size_t)T + (size_t)c->steps[g * MM_TS + j]) * 3;
                    o[0] = s[q][0][j];
                    o[1] = s[q][1][j];
                    o[2] = s[q][2][j];
                }
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
    /* One matrix on the output: rows are computed and written in blocks
     * (at most 64 MiB of results); per-step outputs need every row first. */
    int stream = !o->outspec && !(o->xres > 0 && o->yres > 0);
    size_t rows = (size_t)A->nrows;
    if (stream) {
        size_t per_row = (size_t)T * 3 * sizeof(double);
        rows = ((size_t)64 << 20) / (per_row ? per_row : 1);
        rows = rows < 16 ? 16 : rows & ~(size_t)15;
        if (rows > (size_t)A->nrows) rows = (size_t)A->nrows;
    }
    if (rows > 0 && (size_t)T > SIZE_MAX / (3 * sizeof(double)) / rows)
        return hd_fail(HD_ERR_NOMEM, "%s: %d rows x %d steps: result too large", dc_path, A->nrows, T);
    size_t rbytes = rows * (size_t)T * 3 * sizeof(double);
    double *R = hd_big_alloc(rbytes, 1, 1); /* zeroed: black steps stay 0 */
    if (!R) return hd_fail_context(HD_ERR_NOMEM, "%s: results of %zu rows x %d steps", dc_path, rows, T);
    int *steps = hd_malloc_array((size_t)T + 1, sizeof(int));
    if (!steps) { free(R); return HD_ERR_NOMEM; }
    int nz = 0;
    for (int t = 0; t < T; t++) {
        int any = 0;
        for (int k = 0; k < C->nrows && !any; k++) {
            const double *x = hd_matrix_at(C, k, t);
            any = x[0] != 0 || x[1] != 0 || x[2] != 0;
        }
        if (any) steps[nz++] = t;
    }
    size_t ngroups = ((size_t)nz + MM_TS - 1) / MM_TS;
    double *Cp = hd_calloc(ngroups + 1, (size_t)C->nrows * 3 * MM_TS * sizeof(double));
    if (!Cp) { free(R); free(steps); return HD_ERR_NOMEM; }
    for (int i = 0; i < nz; i++)
        for (int k = 0; k < C->nrows; k++)
            for (int ch = 0; ch < 3; ch++)
                Cp[(((size_t)(i / MM_TS) * (size_t)C->nrows + (size_t)k) * 3 + (size_t)ch) * MM_TS + (size_t)(i % MM_TS)] =
                    hd_matrix_at(C, k, steps[i])[ch];
    mm_ctx mc = {A, Cp, R, steps, nz, T, 0};
    hd_status st = HD_OK;
    if (stream) {
        hd_ofile *f;
        if (!(st = hd_ofile_open(&f, NULL))) {
            hd_mtxwriter w;
            st = matrix_begin(&w, hd_ofile_fp(f), o, -1, A->nrows, T);
            for (size_t r0 = 0; !st && r0 < (size_t)A->nrows; r0 += rows) {
                size_t n = (size_t)A->nrows - r0 < rows ? (size_t)A->nrows - r0 : rows;
                mc.row0 = r0;
                st = hd_parallel_for(n, 16, o->nthreads, mm_rows, &mc);
                if (!st) st = matrix_rows(&w, R, (int)n, (size_t)T, 0);
            }
            hd_status st2 = hd_mtxwriter_end(&w);
            if (!st) st = st2;
            if (st) hd_ofile_abort(f);
            else st = hd_ofile_commit(f);
        }
        free(Cp);
        free(R);
        free(steps);
        return st;
    }
    st = hd_parallel_for((size_t)A->nrows, 16, o->nthreads, mm_rows, &mc);
    free(Cp);
    unsigned char *done = NULL;
    int ndone = 0;
    if (!st) st = done_steps(o, T, &done, &ndone);
    if (!st && o->outspec) {
        int pic = o->xres > 0 && o->yres > 0;
        uint64_t per = (uint64_t)A->nrows * (pic ? 4 : o->out_fmt == HD_MTX_FLOAT ? 12 : o->out_fmt == HD_MTX_DOUBLE ? 24 : 42);
        st = series_disk(o, (uint64_t)(T - ndone) * (per + 1024), T - ndone);
    }
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
                } else if (done && done[t]) {
                    continue;
                } else {
                    hd_ofile *f;
                    if ((st = open_step_output(o, t, &f))) break;
                    errno = 0;
                    st = write_picture_planar(hd_ofile_fp(f), o, t, pl, np, o->xres, o->yres, &scratch);
                    if (st) st = step_failed(st, f);
                    else st = hd_ofile_commit(f);
                }
            }
            if (single) {
                if (st) hd_ofile_abort(single);
                else st = hd_ofile_commit(single);
            }
            hd_picture_free(&scratch);
            free(pl);
        } else {
            for (int t = 0; !st && t < T; t++) {
                if (done && done[t]) continue;
                hd_ofile *f;
                if ((st = open_step_output(o, t, &f))) break;
                errno = 0;
                hd_mtxwriter w;
                st = matrix_begin(&w, hd_ofile_fp(f), o, t, A->nrows, 1);
                if (!st) st = matrix_rows(&w, R, A->nrows, (size_t)T, (size_t)t);
                hd_status st2 = hd_mtxwriter_end(&w);
                if (!st) st = st2;
                if (st) st = step_failed(st, f);
                else st = hd_ofile_commit(f);
            }
        }
    }
    free(R);
    free(steps);
    free(done);
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

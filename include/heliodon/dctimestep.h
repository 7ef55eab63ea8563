/* heliodon — daylight-coefficient time stepping (dctimestep).
 *
 * Two forms, as Radiance's dctimestep:
 *   DC [sky]        result = DC · S
 *   V T D [sky]     result = V · T · D · S   (3-phase; computed D·S first,
 *                   then T·(D·S), then V·(...); T may be a BSDF XML file)
 * DC or V may be a printf pattern of component pictures ("v%03d.hdr"):
 * then each result column is a picture Σ_k c_k · picture_k.  Pictures
 * whose coefficients are zero at every time step are not read.
 *
 * Speed: the fold runs as register tiles (6 steps x 16-64 pixels, AVX-512 /
 * AVX2 / portable C, bit-identical); in picture mode every scanline's
 * components stay in cache while all steps of a block are folded and at
 * once RGBE- and run-length encoded; all-zero sky columns (night) are not
 * computed (their picture is encoded once).  Memory: component pictures are
 * held once as planar float; the encoded output of a block is bounded
 * (HD_DCTS_BLOCK_BYTES). */
#ifndef HELIODON_DCTIMESTEP_H
#define HELIODON_DCTIMESTEP_H

#include "common.h"
#include "matrix.h"

#define HD_DCTS_BLOCK_BYTES ((size_t)256 << 20)

typedef struct hd_dcts_opts {
    int nsteps;          /* -n: time steps of a headerless sky (0 = 1 or header) */
    int sky_fmt;         /* -if/-id/-ia: headerless sky data format (hd_mtxfmt), -1 = expect header */
    int out_fmt;         /* hd_mtxfmt of matrix output (-oa -of -od), or HD_MTX_RGBE (-oc) */
    int header;          /* write information headers */
    const char *outspec; /* -o: per-time-step output pattern ("%d"), or NULL = stdout */
    int xres, yres;      /* -x -y: shape result vectors as pictures */
    int nthreads;        /* -N / -n threads (0 = all processors) */
    int verbose;         /* -v: report what is computed */
    int resume;          /* -r: with -o, keep the step files an earlier run wrote, compute the others */
    int cmd_argc;        /* command line for headers */
    char **cmd_argv;
} hd_dcts_opts;

void hd_dcts_opts_init(hd_dcts_opts *o);

/* inputs: 1 or 2 names (DC [sky]) or 3 or 4 (V T D [sky]); no sky = stdin. */
hd_status hd_dctimestep(int ninputs, char **inputs, const hd_dcts_opts *o);

/* The coefficient matrix of a run: S, or T·(D·S) (exposed for tests and
 * for the annual pipeline). t_path may name a BSDF XML file. */
hd_status hd_dcts_coefficients(const char *t_path, const char *d_path, const char *sky_path,
                               const hd_dcts_opts *o, int npatches_hint, hd_matrix *out);

/* Fold planar component images: out[t][c][p] = Σ_k coef[k][t][c] · comp[k][c][p]
 * for p in [0,npix), t in [0,nsteps).  comp[k] may be NULL where every
 * coefficient of component k is zero.  coef is K × nsteps × 3 (double,
 * row-major as an hd_matrix).  Deterministic for any thread count. */
hd_status hd_dcts_fold(float *const *comp, int ncomp_images, const double *coef, int nsteps,
                       size_t npix, float *out, int nthreads);

/* The fold kernel in use: 0 portable C, 1 AVX2, 2 AVX-512.  All give
 * bit-identical results (separate multiply and add, fixed order).  level < 0
 * or above what the CPU supports selects the best supported; returns the
 * level now in use (for tests and benchmarks; not thread-safe). */
int hd_dcts_set_kernel(int level);

#endif

/* heliodon — the one rcontrib driver (contrib_run.c) and the estimators
 * plugged into it (private).
 *
 * The driver reads the rays (hd_istream_ray, or a generator), cuts them
 * into batches of records (-c rays each, -c 0: chunks summed into one
 * record), skips what -r recovered or what lies before a -R piece, and
 * routes every record column to its -o stream: matrices (-fa/-ff/-fd with
 * the header of rcontrib, BigEndian=), pictures (-fc, RGBE or OpenEXR for
 * names ending in .exr, spooled to TMPDIR and written at the end), files,
 * the standard output or "!command" pipes.  An estimator fills the
 * records of a batch: the backward path walk (contrib.c) or the photon
 * gather (pmap_rcontrib.c, rcontrib -ap). */
#ifndef HELIODON_RCDRIVER_H
#define HELIODON_RCDRIVER_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "heliodon/contrib.h"
#include "heliodon/rng.h"

typedef struct hd_rc_out hd_rc_out;   /* the -o streams of a run */

/* One batch of records.  Ray k of record u is org/dir[u * per + k], its
 * global index (the random stream's) (rec0 + u) * per + k, its weight
 * scale.  Records are rlen doubles (3 per column) at out + u * rlen; out is
 * NULL when the estimator writes picture columns itself (colmajor):
 * then stream colstream[col] (-1: none) receives column col through
 * hd_rc_out_encode.  recs (NULL: rec0 + u) is the place of each record
 * among the run's output records when the driver orders them by keys. */
typedef struct hd_rc_batch {
    const hd_vec3 *org, *dir;
    size_t nrec;
    int per;
    uint64_t rec0;
    double scale;
    size_t rlen;
    double *out;
    hd_rc_out *os;
    const int *colstream;
    const uint64_t *recs;
} hd_rc_batch;

typedef struct hd_rc_estimator {
    void *ctx;
    int c0_per;         /* rays per summed chunk with -c 0 */
    size_t batch;       /* records per batch */
    size_t batch_big;   /* records per batch once evicted() says so (0: never) */
    int colmajor;       /* -fc: fills the pictures column by column (hd_rc_out_encode) */
    hd_status (*run)(void *ctx, const hd_rc_batch *b);
    /* optional: a locality key per record (records with near keys share
     * the estimator's work); with pictures of known size (-fc -x -y) the
     * driver reads the whole input and runs the records in key order,
     * when each record's result does not depend on its batch */
    hd_status (*keys)(void *ctx, const hd_vec3 *org, const hd_vec3 *dir, size_t nrec, int per, uint64_t *key);
    /* optional, asked after the first batch: whether its work did not stay
     * in the estimator's cache (later batches would redo it); then grow()
     * makes room for batch_big records, and pictures of known size go on in
     * key order */
    int (*evicted)(void *ctx);
    hd_status (*grow)(void *ctx);
    void (*stats)(void *ctx, FILE *f);   /* -stats: the estimator's counts, after the run */
    void (*free)(void *ctx);
} hd_rc_estimator;

/* Estimators that trace one ray at a time: fn adds ray (org, dir) of
 * weight scale into its record rec (zeroed before the record's first ray),
 * with the ray's own random stream (seed, global ray index); records are
 * handed out in chunks of chunk records to nthreads workers. */
typedef hd_status (*hd_rc_ray_fn)(void *ctx, int worker, hd_vec3 org, hd_vec3 dir, hd_rng *rng, double scale,
                                  double *rec);
hd_status hd_rc_per_ray(const hd_rc_batch *b, uint64_t seed, int nthreads, size_t chunk, hd_rc_ray_fn fn, void *ctx);

/* Picture stream q's pixels of the batch's nrec records: the value of
 * record r at vals + r * us (3 doubles).  Thread-safe for distinct q. */
void hd_rc_out_encode(hd_rc_out *os, int q, const double *vals, size_t nrec, size_t us);

/* The photon gather (pmap_rcontrib.c): opens o->pm.file, maps modifiers to
 * the map's light sources. */
#define HD_PMAP_RC_BATCH_BYTES ((size_t)512 << 20)   /* the photon gather's batch memory */
size_t hd_pmap_rc_batch(const hd_contrib *c, const hd_rcontrib_opts *o, int nth, int maxbins, uint64_t nout);
hd_status hd_pmap_rc_estimator(const hd_contrib *c, const hd_rcontrib_opts *o, hd_rc_estimator *e);

#endif

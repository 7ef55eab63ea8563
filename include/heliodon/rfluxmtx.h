/* heliodon — rfluxmtx: flux-transfer matrices between a sender and
 * receivers described by "#@rfluxmtx h= u= o=" control comments.
 *
 * Sender: surfaces (polygons, rings) of one hemisphere basis; rays leave
 * its BACK side: for sender bin b, -c samples with origins uniform over the
 * sender area and directions = minus the basis vector of b expressed in
 * the sender frame (u = normalize(up × n), v = n × u, n).  Pass-through
 * mode ("-" as sender) reads rays from standard input instead.
 * Receivers: polygons, rings and sources; every receiver modifier is one
 * rcontrib modifier whose bins follow its h= basis (u, kf/kh/kq, rN) in
 * the receiver's frame.  Output: rows = sender bins (or input records),
 * columns = receiver bins (modifiers in file order). */
#ifndef HELIODON_RFLUXMTX_H
#define HELIODON_RFLUXMTX_H

#include "common.h"
#include "contrib.h"
#include "vec.h"

typedef enum hd_hbasis {
    HD_HB_NONE = 0,
    HD_HB_UNIFORM,        /* h=u */
    HD_HB_KLEMS,          /* h=kf/kh/kq (k, k1, k2, k4) */
    HD_HB_REINHART        /* h=rN (r, t) */
} hd_hbasis;

typedef struct hd_rfparams {
    hd_hbasis basis;
    hd_klems_kind klems;
    int mf;
    double rhs;           /* -1 for h=-... (left-handed) */
    int has_up;
    hd_vec3 up;
    char out[1024];       /* o= ("" = none) */
} hd_rfparams;

/* Parse the words after "#@rfluxmtx" into p (updating only the keys
 * given).  Errors name `where`. */
hd_status hd_rfparams_parse(hd_rfparams *p, const char *text, const char *where);

typedef struct hd_rfsurf {
    char mod[128];
    int type;             /* HD_T_POLYGON, HD_T_RING, HD_T_SOURCE */
    double *r;            /* real arguments */
    int nr;
    hd_rfparams params;
    char where[256];
} hd_rfsurf;

typedef struct hd_rffile {
    hd_rfsurf *s;
    int n;
    int ncomments;        /* #@rfluxmtx lines seen */
} hd_rffile;

/* Read the surfaces of a sender/receiver file with the control
 * parameters in force for each (materials and other modifiers are
 * skipped; surfaces other than polygon/ring/source are an error). */
hd_status hd_rffile_read(hd_rffile *f, const char *path);
void hd_rffile_free(hd_rffile *f);

/* A receiver group: contiguous surfaces with one modifier. Fills the bin
 * function of modifier m (name, bin, outspec). jtr: -bj. */
hd_status hd_rf_receivers(const hd_rffile *f, double jtr, hd_contrib *c);

/* Sender sampler. */
typedef struct hd_rfsender hd_rfsender;
hd_status hd_rf_sender_create(hd_rfsender **out, const hd_rffile *f, int nsamp, uint64_t seed);
void hd_rf_sender_free(hd_rfsender *s);
int hd_rf_sender_nbins(const hd_rfsender *s);
/* Ray k (= bin k / nsamp, sample k % nsamp); returns 1. */
int hd_rf_sender_ray(void *s, uint64_t k, hd_vec3 *org, hd_vec3 *dir);
/* Frame used (for -v / tests). */
void hd_rf_sender_frame(const hd_rfsender *s, hd_vec3 *u, hd_vec3 *v, hd_vec3 *n);

/* The whole program (tools/rfluxmtx.c calls this). */
int hd_rfluxmtx_main(int argc, char **argv);

#endif

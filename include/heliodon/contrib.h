/* heliodon — rcontrib (backward): per-modifier, per-bin contributions.
 *
 * For every input ray, the paths traced (primary rays, -ad/-ab diffuse
 * "ambient" sampling without cache, specular rays, and shadow rays to
 * tracked direct sources) that end on a surface whose modifier is tracked
 * add their path coefficient (-V-) or coefficient × emitted radiance (-V+)
 * to that modifier's bin.  The bin is computed from the direction D of the
 * ray that reached the surface by the -b expression, evaluated by the .cal
 * module (cal.h) with the -f files and -e definitions (rfluxmtx builds its
 * Klems and Reinhart bins directly, without expressions).
 *
 * Records: one per input ray, or per -c N rays (averaged), or a single
 * record summing every ray (-c 0).  Streams: -o patterns as Radiance
 * (%s = modifier, %d = bin), headers as rcontrib writes them. */
#ifndef HELIODON_CONTRIB_H
#define HELIODON_CONTRIB_H

#include <stdint.h>
#include <stdio.h>
#include "common.h"
#include "header.h"
#include "io.h"
#include "basis.h"
#include "klems.h"
#include "render.h"
#include "trace.h"
#include "vec.h"

/* ---- bin functions ---- */
typedef enum hd_binkind {
    HD_BIN_CONST = 0,     /* always bin 0 ("-b 0", the default) */
    HD_BIN_HEMI,          /* uniform receiver: 0 if D·n < 0, else none (rfluxmtx h=u on surfaces) */
    HD_BIN_KLEMS,         /* klems_full/half/quarter.cal kbin(N,U) */
    HD_BIN_REINHARTB,     /* reinhartb.cal rbin (no ground bin, arbitrary frame) */
    HD_BIN_REINHART,      /* reinhart.cal rbin / tregenza.cal tbin (bin 0 = ground) */
    HD_BIN_CAL            /* a .cal expression (rcontrib -b) */
} hd_binkind;

typedef struct hd_binfn {
    hd_binkind kind;
    int nbins;            /* the -bn value */
    int mf;               /* Reinhart subdivision */
    double rhs;           /* handedness (+1 / -1) */
    double jtr;           /* reinhartb JTR (bin jitter, fraction of a patch) */
    hd_vec3 n;            /* HD_BIN_HEMI: normal; KLEMS: N; REINHARTB: rN */
    hd_vec3 u;            /* up vector */
    hd_klems_basis *kb;   /* HD_BIN_KLEMS (owned) */
    hd_skybasis *sky;     /* HD_BIN_REINHART[B] (owned) */
    /* derived frame for REINHARTB / KLEMS: local = (x, y, z) axes */
    hd_vec3 ax, ay, az;
    struct hd_calshare *cal;   /* HD_BIN_CAL: context (refcounted) */
    int expr;                  /* HD_BIN_CAL: compiled -b expression */
    char *rcargs;              /* rfluxmtx: the equivalent rcontrib options (owned) */
} hd_binfn;

/* Definitions in force when a modifier is given: -f files and -e texts in
 * command-line order, compiled by the .cal module (cal.h) into one shared
 * context (Radiance's rcontrib context "RC.": names print as NAME`RC.). */
typedef struct hd_calctx {
    struct hd_calshare *share;     /* shared context (refcounted) */
    struct { char kind; char *text; } *log;   /* 'f' path / 'e' text, in order */
    int nlog;
} hd_calctx;

void hd_calctx_init(hd_calctx *c);
void hd_calctx_free(hd_calctx *c);
/* -f file.cal (found through RAYPATH) */
hd_status hd_calctx_file(hd_calctx *c, const char *path);
/* -e "definitions" (params = 0).  params != 0 is not used any more (-p is
 * given to hd_binfn_parse). */
hd_status hd_calctx_assign(hd_calctx *c, const char *text, int params);

/* Build the bin function for "-b expr -bn count" in context c (params:
 * the -p text in force, "name=value,name2=value2", may be NULL): any .cal
 * expression of Dx, Dy, Dz and the definitions; -bn is an expression too
 * (e.g. Nrbins), evaluated now.  A literal 0 is the constant bin. */
hd_status hd_binfn_parse(hd_binfn *b, const hd_calctx *c, const char *params,
                         const char *expr, const char *count);
/* Direct construction (rfluxmtx). kind KLEMS: kk = basis kind. */
hd_status hd_binfn_klems(hd_binfn *b, hd_klems_kind kk, hd_vec3 n, hd_vec3 u, double rhs);
hd_status hd_binfn_reinhartb(hd_binfn *b, int mf, hd_vec3 rn, hd_vec3 u, double rhs, double jtr);
void hd_binfn_free(hd_binfn *b);
/* Bin of ray direction D (unit), -1 = none.  rng used for JTR only. */
int hd_binfn_eval(const hd_binfn *b, hd_vec3 D, double jr1, double jr2);

/* ---- contribution tracer ---- */
typedef struct hd_cmod {
    char name[128];
    hd_binfn bin;
    char *outspec;        /* -o in force (NULL = standard output) */
    int first;            /* first column of this modifier in a record */
} hd_cmod;

typedef struct hd_contrib {
    const hd_tscene *ts;
    hd_render_opts o;
    int vflag;            /* -V+: contributions (× emitted radiance) */
    int nmods;
    hd_cmod *mods;
    int ncols;            /* total bins over all modifiers */
    int *matmod;          /* per material index: tracked modifier or -1 */
    int nmat;
    int *lights;          /* tracked direct sources (surface indices) */
    int nlights;
    /* -dn N (heliodon extension): at a vertex reached after a diffuse
     * bounce, N of the tracked direct sources are sampled (systematically,
     * from one random offset: each source with probability N/nlights) and
     * their terms weighted by nlights/N, an unbiased estimate whose cost
     * does not grow with the number of sources; the vertices before the
     * first diffuse bounce (the primary hit and its specular or BSDF
     * continuations) test every source.  0 (default): every source at every
     * vertex (Radiance's rule). */
    int dn;
    int stats;            /* -stats: count the direct-source work (with -ap the photon gather's), printed
                           * on stderr by hd_rcontrib_run after the run */
    struct hd_contrib_counts *counts;   /* owned; set by hd_contrib_prepare when stats */
} hd_contrib;

/* After mods are set: map materials to modifiers; error for a modifier
 * that no surface of the scene uses ("unknown modifier"). */
hd_status hd_contrib_prepare(hd_contrib *c);
void hd_contrib_free(hd_contrib *c);
/* -stats: "rcontrib: stats: ..." (vertices where direct sources were
 * considered, before / after a diffuse bounce; sources sampled; shadow
 * rays) on f; nothing without stats. */
void hd_contrib_print_stats(const hd_contrib *c, FILE *f);

/* Trace one ray and add its contributions (ncols × 3 doubles) to acc,
 * scaled by `scale`.  irrad: 0 = radiance along the ray, 1 = irradiance at
 * org with normal dir (-I), 2 = irradiance at the first hit (-i).  tmax > 0
 * limits the first ray (-ld). */
hd_status hd_contrib_ray(const hd_contrib *c, hd_vec3 org, hd_vec3 dir, double tmax, int irrad,
                         hd_rng *rng, double scale, double *acc);

/* ---- rcontrib driver ---- */
/* -ap photon-map mode: the photon gather replaces the path walk */
typedef struct hd_rc_pmap_opts {
    const char *file;         /* -ap file (NULL: backward mode) */
    double bw, bw2;           /* -ap bandwidth [bandwidth2] */
    uint64_t cache;           /* -aC cached photons (default 4M) */
    double ac;                /* -ac (accepted; pages are fixed at build time) */
    double am;                /* -am max radius (0 = none) */
    int exact_direct;         /* -apd+ (default): direct through glass by shadow rays */
} hd_rc_pmap_opts;

typedef struct hd_rcontrib_opts {
    int irrad;            /* 0, 1 (-I), 2 (-i) */
    char fin, fout;       /* a f d / a f d c */
    int accum;            /* -c (0 = sum everything into one record) */
    int xres, yres;
    int ld;               /* -ld: limit ray length to |dir| */
    int header;           /* -h */
    int force;            /* -fo */
    int nthreads;
    double report;        /* -t */
    /* rfluxmtx mode (set before parsing): -v and -bj accepted, the
     * options rfluxmtx controls refused */
    int rflux;
    int verbose;          /* -v */
    double bj;            /* -bj */
    int cgiven, xygiven;  /* -c / -x -y seen */
    int recover;          /* -r: take up the outputs of an interrupted run */
    /* -R first count: compute records first..first+count-1 only and write
     * them as a piece (the full output's header plus a RECORDS= line, the
     * records flat); rcmerge(1) joins the pieces into the full output */
    int ranged;
    uint64_t rec_first, rec_count;
    hd_rc_pmap_opts pm;   /* -ap -aC -ac -am -apd (rcontrib; -ab < 0 allowed) */
} hd_rcontrib_opts;

void hd_rcontrib_defaults(hd_rcontrib_opts *o, hd_render_opts *r);

/* A source of rays: either a stream of "ox oy oz dx dy dz" records in
 * format fin, or a generator (rfluxmtx senders) that fills ray k. */
typedef int (*hd_raygen_fn)(void *ctx, uint64_t k, hd_vec3 *org, hd_vec3 *dir);

typedef struct hd_raysrc {
    hd_istream *in;       /* or NULL with gen */
    hd_raygen_fn gen;
    void *genctx;
    uint64_t ngen;        /* rays the generator provides */
} hd_raysrc;

/* Run: trace all rays (the backward path walk, or the photon gather with
 * -ap), write every stream.  hdr: lines before NCOMP (inherited lines,
 * command line, SOFTWARE, dates). */
hd_status hd_rcontrib_run(const hd_contrib *c, const hd_rcontrib_opts *o, hd_raysrc *src,
                          const hd_header *hdr);

/* -r (contrib_resume.c): each of the n named output streams is opened from
 * what an earlier run left (hd_ofile_open_resume), its complete records are
 * counted and every stream is cut to the smallest count *done; has_header
 * tells whether the stream's header is kept (else the caller writes it).
 * With -fc, of stays NULL and *done = expect when every picture exists.
 * Refused for the standard output and commands.  With -c 0 (as Radiance)
 * nothing is taken up: the one record each file holds is added into sum
 * (3 doubles per column of the run, the stream's columns in cols) and the
 * files are written again at the end; a missing file adds nothing. */
typedef struct hd_rc_resume {
    const char *name;
    int ncols;
    const int *cols;          /* -c 0: the run's column of each of the ncols */
    hd_ofile *of;
    int has_header;
} hd_rc_resume;
hd_status hd_rcontrib_resume(const hd_rcontrib_opts *o, hd_rc_resume *s, int n, uint64_t expect, uint64_t *done,
                             double *sum);
/* Before the work: refuse outputs of expect records (done of them already
 * written) that will not fit the disk holding them, naming the options and
 * the numbers (the -fc picture spool is checked by the driver). */
hd_status hd_rcontrib_check_size(const hd_rcontrib_opts *o, const hd_rc_resume *s, int n, uint64_t expect,
                                 uint64_t done);

/* Parse the rcontrib command line (after @file expansion) into c and o;
 * *first = index of the first scene file.  Loading the scene is the
 * caller's job (c->ts set later). */
hd_status hd_rcontrib_parse_args(int argc, char **argv, hd_contrib *c, hd_rcontrib_opts *o, int *first);

#endif

/* heliodon — measured BSDFs as radial-basis interpolants (the "SIR" files
 * of Radiance's pabopto2bsdf / bsdf2ttree / bsdf2klems).
 *
 * One interpolant holds one component (light arriving on one side,
 * scattered to one side).  For each measured incident direction it keeps
 * a set of Gaussian lobes over the outgoing hemisphere (a DSF, the BSDF
 * times a moderated cosine), placed on a GRIDRES x GRIDRES Shirley-Chiu
 * grid; between incident directions it keeps "migration" matrices (mass
 * transport plans between the lobes of two neighbouring directions) along
 * the edges of a mesh over the incident directions (a chain for isotropic
 * data, a spherical triangulation otherwise).  A BSDF for an unmeasured
 * incident direction is made by advecting the lobes along the edge or
 * across the triangle that holds it.
 *
 * File format (binary, Radiance's portable integers: big-endian, floats as
 * a 4-byte mantissa and a 1-byte exponent): a Radiance header with NAME=,
 * MANUFACT=, SYMMETRY= (0 = isotropic, else the quadrant coverage bits),
 * IO_SIDES= in out, COLORIMETRY=, GRIDRES=, BSDFMIN=, BSDFSPEC= and
 * FORMAT=BSDF_RBFmesh; the magic number 0x5a3c (2 bytes); per DSF: ord (4),
 * incident vector (3 floats), volume (float), lobe count (4), lobes (peak
 * float, chroma 2, radius 2, gx 2, gy 2); -1 (4); per migration: from and
 * to ord (4 + 4), matrix in a zero-run-length code; -1 -1.  docs/design/
 * measured.md describes the method. */
#ifndef HELIODON_RBF_H
#define HELIODON_RBF_H

#include <stdint.h>
#include <stdio.h>
#include "common.h"
#include "vec.h"

#define HD_RBF_GRIDRES 256

typedef struct hd_rbflobe {
    float peak;              /* lobe value at its centre (DSF) */
    uint16_t chroma;         /* encoded chromaticity (kept as read) */
    uint16_t crad;           /* radius, coded angle: radians * 65536 / pi */
    uint16_t gx, gy;         /* grid position of the centre */
} hd_rbflobe;

typedef struct hd_rbfdsf {
    int ord;
    hd_vec3 invec;           /* incident direction (towards the light) */
    double vtotal;           /* integral of the DSF */
    int nrbf;
    hd_rbflobe *rbfa;
} hd_rbfdsf;

typedef struct hd_rbfmig {
    int from, to;            /* DSF ords */
    float *mtx;              /* nrbf(from) x nrbf(to), rows sum to 1 (NULL after hd_rbf_read_rows) */
    int *rs, *ci;            /* derived (hd_rbf_link): non-zero columns of each row */
    float *cv;               /* derived: the values of those entries (what the advection reads) */
} hd_rbfmig;

/* quadrant coverage bits (SYMMETRY=) */
#define HD_RBF_Q1 1
#define HD_RBF_Q2 2
#define HD_RBF_Q3 4
#define HD_RBF_Q4 8

typedef struct hd_rbfrep {
    char name[256], manuf[256];
    int grid_res;
    int inp_coverage;        /* quadrant bits */
    int single_plane;        /* 1 = isotropic (all incident phi equal) */
    int input_orient, output_orient;   /* +1 = +Z side, -1 = -Z side */
    int colorimetry;         /* 0 CIE-Y, 1 CIE-XYZ, 2 Spectral, 3 Unknown */
    double bsdf_min, spec_val, spec_rad;
    int ndsf;
    hd_rbfdsf *dsf;          /* indexed by ord */
    int nmig;
    hd_rbfmig *mig;
    char *header;            /* header lines of the file read (for comments) */
    /* derived: per-DSF edge lists (indices into mig) */
    int *edge_start, *edge_list;
    float (*q_uv)[2];        /* outgoing-direction table of the grid */
} hd_rbfrep;

hd_status hd_rbf_init(hd_rbfrep *r, int grid_res);
void hd_rbf_free(hd_rbfrep *r);

/* Read / write the binary interpolant.  Reading checks every count and
 * reference and names the file and byte offset of what is wrong. */
/* On failure r holds nothing (what was read is freed). */
hd_status hd_rbf_read(hd_rbfrep *r, const char *path);
/* The same for evaluation only (bsdf2ttree): each plan is kept as its row
 * lists (non-zero entries), not as a dense matrix, so r cannot be written or
 * replanned (film tb, 113 plans: bsdf2ttree -g 2 peaks at 13 MB instead of
 * 186 MB). */
hd_status hd_rbf_read_rows(hd_rbfrep *r, const char *path);
/* header_lines: command line etc. written after "#?RADIANCE" (may be NULL) */
hd_status hd_rbf_write(const hd_rbfrep *r, FILE *fp, const char *header_lines);
/* (Re)build the per-DSF edge lists after DSFs or migrations change. */
hd_status hd_rbf_link(hd_rbfrep *r);

/* Grid <-> direction (outgoing side = r->output_orient). */
hd_vec3 hd_rbf_ovec(const hd_rbfrep *r, int gx, int gy);
void hd_rbf_pos(const hd_rbfrep *r, hd_vec3 v, int pos[2]);
/* coded angle <-> radians */
static inline double hd_rbf_r2ang(unsigned c) { return (c + 0.5) * (HD_PI / 65536.0); }
static inline unsigned hd_rbf_ang2r(double a) { return (unsigned)(a * (65536.0 / HD_PI)); }
/* moderated cosine of the DSF */
static inline double hd_rbf_cosf(double z) { return fabs(z) * 0.98 + 0.02; }

/* Volume of one lobe (with the horizon cut-off correction). */
double hd_rbf_lobe_volume(const hd_rbfrep *r, const hd_rbflobe *l);

/* A DSF prepared for fast evaluation (lobe directions and a coarse bin
 * index of the lobes that reach each region of the grid). */
typedef struct hd_rbfeval hd_rbfeval;
hd_status hd_rbfeval_make(hd_rbfeval **out, const hd_rbfrep *r, const hd_rbfdsf *d);
void hd_rbfeval_free(hd_rbfeval *e);
/* BSDF value (1/sr) towards unit outgoing vector o (never below bsdf_min;
 * bsdf_min when e == NULL or o is on the wrong side). */
double hd_rbfeval_bsdf(const hd_rbfeval *e, hd_vec3 o);
/* The same in double precision and Radiance's order of summation (the
 * value hd_rbf_eval gives, found through the index): for the transport
 * costs, which must equal Radiance's to the last bit. */
double hd_rbfeval_bsdf_exact(const hd_rbfeval *e, hd_vec3 o);
/* Plain evaluation without the index. */
double hd_rbf_eval(const hd_rbfrep *r, const hd_rbfdsf *d, hd_vec3 o);

/* Interpolated DSF for incident vector in (unit, on the input side), with
 * at most lobe_lim lobes (0 = no limit).  *out->rbfa is allocated; the
 * result has nrbf = 0 when the direction cannot be interpolated and no
 * default specular lobe is set. */
hd_status hd_rbf_advect(const hd_rbfrep *r, hd_vec3 in, int lobe_lim, hd_rbfdsf *out);
/* Interpolate between two DSFs along migration m at incident vector in. */
hd_status hd_rbf_edge_advect(const hd_rbfrep *r, const hd_rbfmig *m, hd_vec3 in, int lobe_lim,
                             hd_rbfdsf *out);

/* Symmetry from the quadrant coverage: mirror v into the covered
 * quadrants; returns the mirror bits applied (1 = x, 2 = y). */
int hd_rbf_use_symmetry(const hd_rbfrep *r, hd_vec3 *v);
void hd_rbf_mirror_dsf(const hd_rbfrep *r, hd_rbfdsf *d, int sym);

/* ---- building an interpolant from measurements (pabopto2bsdf) ---- */
typedef struct hd_pabopto_opts {
    int flip;                /* -t: reverse the surface normal */
    double lim_graze;        /* -g: drop data within this many degrees of grazing */
    int auto_graze;          /* -g A */
    char symmetry;           /* -s: '0' (infer), 'I', 'Q', 'B', 'A', 'U' */
    int nthreads;
    int report;              /* progress on stderr */
    int exact;               /* -x: least-cost transport plans instead of Radiance's */
} hd_pabopto_opts;

/* Read the PAB-Opto files paths[0..n-1], fit lobes per incident
 * direction, build the mesh and transport plans into r (initialised by
 * this call).  Errors name the file and line. */
hd_status hd_pabopto_build(hd_rbfrep *r, const char *const *paths, int n, const hd_pabopto_opts *o);
/* Recompute the transport plan of migration m of r from its two DSFs
 * (Radiance's plan, or the least-cost one with exact), replacing m's
 * matrix; hd_rbf_link(r) must follow before r is evaluated. */
hd_status hd_rbf_replan(hd_rbfrep *r, int m, int exact);

/* ---- tensor trees from interpolants (bsdf2ttree) ---- */
typedef struct hd_ttmake_opts {
    int log2res;             /* -g (2..9) */
    double pctcull;          /* -t (< 0: no reduction, full tree) */
    int nssamp;              /* -n super-samples per cell (64) */
    double ssamp_thresh;     /* -s relative difference that triggers super-sampling (0.35) */
    int lobe_lim;            /* -l (15000) */
    int recip;               /* +a: reciprocity averaging of reflection */
    int nthreads;
    int report;
} hd_ttmake_opts;

/* Fill grid (R^3 for an isotropic interpolant, R^4 otherwise, R =
 * 2^log2res; layout of genbsdf.h's tensor-tree grids) with BSDF values
 * resampled from r. */
hd_status hd_ttmake_grid(const hd_rbfrep *r, const hd_ttmake_opts *o, float *grid);

/* The program mains (tools/ call these). */
int hd_pabopto2bsdf_main(int argc, char **argv);
int hd_bsdf2ttree_main(int argc, char **argv);
int hd_rttree_reduce_main(int argc, char **argv);

#endif

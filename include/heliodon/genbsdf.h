/* heliodon — BSDF generation from fenestration geometry (genBSDF).
 *
 * A "system" is a Radiance scene in genBSDF's frame: +z points into the
 * room, +y is up, the device lies in the -dim box (z <= 0 normally), the
 * exterior is on the -z side.  Rays are sent from the sender planes
 * z = zmin (light from the exterior, WINDOW "front") or z = zmax (light from
 * the room, WINDOW "back"), from points stratified over the -dim
 * rectangle, in directions stratified over the incident patch or cell,
 * and followed through the geometry with heliodon's tracer (trace.h): a
 * hit on glass, mirror or a dielectric interface splits the ray into a
 * reflected and a transmitted branch with their Fresnel weights (as
 * Radiance's materials do); plastic, metal and trans follow Radiance's
 * normal.c (specular rays with their coefficients; a diffuse hit splits
 * into Radiance's -ad ambient rays, 700 by default as Radiance's genBSDF,
 * or with -ad 0 continues one path chosen with its probability; CIE Y
 * values of the material).  Branches end as
 * Radiance's rayorigin() ends them (-lr reflection limit, -lw weight with
 * Russian roulette).  A branch that leaves the geometry towards +z or -z
 * is scored with its flux in the outgoing bin of its direction; BSDF value
 * = flux in the bin per incident ray / projected solid angle of the bin.
 *
 * Materials: plastic, metal, trans (Radiance normal.c model via
 * material.h), glass (thin pane), mirror, dielectric (refracting closed
 * volumes with unpolarised Fresnel reflection, total internal reflection
 * and absorption per unit length; implemented here), light/glow/illum
 * (absorbing).  Anything else is an error naming the primitive.
 *
 * Data layouts (values in 1/sr):
 *   Klems: vals[o * n + i], o = outgoing bin, i = incident bin, in the
 *     bsdf_m.c conventions (incident bin of the propagation direction's
 *     (x, y, |z|), outgoing bin of the outgoing direction's (x, y, |z|)).
 *   Tensor trees: a full grid of R = 2^N cells per dimension, dimension 0
 *     slowest: 4D index ((i0*R + i1)*R + i2)*R + i3 with (c0,c1) =
 *     disk2square of the incident propagation's (x, y), (c2,c3) of the
 *     outgoing (x, y); 3D (i0*R + i1)*R + i2 with c0 = 0.5 - 0.5 sin(theta_in)
 *     (cells c0 >= 0.5 mirror those below) and (c1,c2) of the outgoing
 *     direction rotated so that the incident plane is the x axis.
 *
 * Random streams: one per (side, incident direction), so results do not
 * depend on the thread count. */
#ifndef HELIODON_GENBSDF_H
#define HELIODON_GENBSDF_H

#include <stdint.h>
#include <stdio.h>
#include "common.h"
#include "klems.h"

struct hd_scene;

/* Sides: light arriving from the exterior (WINDOW "front": Transmission
 * Front / Reflection Front) or from the room (WINDOW "back"). */
#define HD_GB_FROM_EXTERIOR 0
#define HD_GB_FROM_ROOM 1

typedef struct hd_genbsdf_opts {
    int have_dim;
    double dim[6];          /* xmin xmax ymin ymax zmin zmax (geometry units) */
    char unit[32];          /* geometry unit name ("millimeter"); "" = meter */
    int embed_geom;         /* +geom: embed the polygons as MGF in <Geometry> */
    uint64_t nsamp;         /* -c: rays per incident direction (default 2000) */
    int tree_dims;          /* 0 = Klems full basis, 3 or 4 = tensor tree */
    int tree_log2;          /* -t3/-t4 N */
    double cull_pct;        /* -t: tree reduction strength (90), see hd_gbtree_build */
    int forward, backward;  /* +f / +b (default: backward only) */
    int nthreads;           /* -n */
    int ab;                 /* diffuse bounces (-r '-ab N', default 5) */
    int lr;                 /* -r '-lr N': reflection limit as Radiance's (default -10, rcontrib's) */
    double lw;              /* -r '-lw w': minimum ray weight (default 3e-6, Radiance's genBSDF) */
    int ad;                 /* -r '-ad N': a diffuse event of plastic/metal/trans splits as Radiance's
                               (round(sqrt(N w))^2 rays); default 700, Radiance's genBSDF's;
                               0 (a heliodon extension): one diffuse event chosen with its
                               probability (one path: much cheaper per sample, noisier) */
    double st;              /* -r '-st t': specular threshold of plastic/metal/trans (default .02, rcontrib's) */
    int maxdepth;           /* safety cap on the events of one ray branch (default 1000) */
    uint64_t seed;          /* random seed (-r '-rs N' is not Radiance; see man page) */
    char manufacturer[128]; /* -s m=... */
    char name[128];         /* -s n=... */
    int report;             /* print progress on stderr */
} hd_genbsdf_opts;

void hd_genbsdf_defaults(hd_genbsdf_opts *o);

/* Metres per unit for a unit name (meter, millimeter, centimeter, foot,
 * inch; case-insensitive; plural "s" accepted): 0 if unknown. */
double hd_genbsdf_unit_scale(const char *unit);

/* Parse genBSDF's command line into o and the list of input files
 * (*first = index of the first file in argv; no files = standard input).
 * HD_ERR_USAGE with a message on bad usage. */
hd_status hd_genbsdf_parse_args(int argc, char **argv, hd_genbsdf_opts *o, int *first);

typedef struct hd_gbsystem hd_gbsystem;

/* Build a system from a parsed scene: resolves materials, checks that
 * there are surfaces, that the geometry lies inside the -dim z range (and
 * sets dim from the bounding box if !o->have_dim), that the -dim
 * rectangle is covered by the geometry's x/y extent, and that dielectric
 * volumes are closed (every edge shared by two of their polygons). */
hd_status hd_gbsystem_create(hd_gbsystem **out, const struct hd_scene *sc, hd_genbsdf_opts *o);
void hd_gbsystem_free(hd_gbsystem *g);

/* Trace one side into the Klems basis kb: trans and refl receive n*n
 * values [o*n+i] (either may be NULL). */
hd_status hd_genbsdf_klems(const hd_gbsystem *g, const hd_genbsdf_opts *o, int side,
                           const hd_klems_basis *kb, double *trans, double *refl);

/* The same for incident bins first .. first+count-1 only (other columns
 * are left as they are); results equal those of the full run. */
hd_status hd_genbsdf_klems_range(const hd_gbsystem *g, const hd_genbsdf_opts *o, int side,
                                 const hd_klems_basis *kb, int first, int count, double *trans, double *refl);

/* Trace one side into tensor-tree grids (o->tree_dims, o->tree_log2):
 * arrays of R^D floats each (either may be NULL). */
hd_status hd_genbsdf_tree(const hd_gbsystem *g, const hd_genbsdf_opts *o, int side,
                          float *trans, float *refl);

/* Directional-hemispherical total of a Klems matrix for incident bin i:
 * sum over o of vals[o*n+i] * lambda(o). */
double hd_genbsdf_klems_hemi(const hd_klems_basis *kb, const double *vals, int i);

/* ---- tensor trees ---- */
typedef struct hd_gbtree hd_gbtree;
/* Build a tree from a full grid (R = 2^log2 per dimension, D = 3 or 4)
 * and merge sibling leaves bottom-up; a group of 2^D leaves becomes one
 * (their mean) when
 *  - nrays > 0 (Monte Carlo data, nrays rays per incident cell): the
 *    chi-square statistic of the children's ray counts about their mean is
 *    at most (n-1) + z sqrt(2(n-1)), n = 2^D, z = 3 cull_pct/100, i.e. the
 *    differences are consistent with sampling noise;
 *  - nrays <= 0: its relative spread (max-min)/mean is among the cull_pct %
 *    smallest of the candidate groups of that level.
 * Groups of equal values always merge; cull_pct 0 merges nothing else. */
hd_status hd_gbtree_build(hd_gbtree **out, const float *grid, int dims, int log2res, double cull_pct,
                          double nrays);
/* The data reduction of Radiance's rttree_reduce (used by bsdf2ttree and
 * rttree_reduce): takes ownership of grid (freed on error too); cull_pct
 * is the percentile of the variation measure below which groups of 2^D
 * finest cells are merged, larger cells merge when their measure over all
 * their finest cells is not above that threshold. */
hd_status hd_gbtree_build_rtr(hd_gbtree **out, float *grid, int dims, int log2res, double cull_pct);
void hd_gbtree_free(hd_gbtree *t);
size_t hd_gbtree_nleaves(const hd_gbtree *t);
/* Value at cell coordinates in [0,1)^D. */
double hd_gbtree_lookup(const hd_gbtree *t, const double *c);
/* Average a 4D reflection grid with itself under reciprocity
 * f(in, out) = f(out, in): cell (i0,i1,i2,i3) pairs with
 * (R-1-i2, R-1-i3, R-1-i0, R-1-i1) (the Shirley-Chiu map is symmetric
 * under (x,y) -> (-x,-y)).  genBSDF applies it to reflection trees, as
 * Radiance's genBSDF does. */
void hd_gbtree_reciprocal_avg(float *grid, int log2res);
/* Write the <ScatteringData> body (curly-brace encoding of spec §8.3). */
hd_status hd_gbtree_write(FILE *fp, const hd_gbtree *t);

/* ---- XML output ----
 * Blocks: NULL to omit; Klems blocks are written in the order
 * Transmission Back, Reflection Back, Transmission Front, Reflection Front
 * (WINDOW names: front = exterior).  comment: the command line. */
typedef struct hd_gbxml {
    const char *comment;
    const char *manufacturer, *name, *unit;   /* unit name for Thickness/Width/Height */
    double thickness, width, height;          /* in that unit */
    const double *klems[4];                   /* [0] T back, [1] R back, [2] T front, [3] R front */
    const hd_gbtree *tree[4];                  /* same order */
    int tree_dims;
    const char *mgf;                          /* MGF text for <Geometry> or NULL */
} hd_gbxml;

hd_status hd_genbsdf_write_xml(FILE *fp, const hd_gbxml *x, const hd_klems_basis *kb);

/* The whole program: parse, load, trace, write to out. */
int hd_genbsdf_main(int argc, char **argv, FILE *out);

#endif

/* heliodon — data-driven BSDFs from LBNL/WINDOW XML files (Klems matrices
 * in any angle basis, isotropic and anisotropic tensor trees): load,
 * evaluate, integrate, importance-sample, convert to Klems matrices.
 *
 * COORDINATE FRAME (Radiance's BSDF library conventions)
 *   +z is the BSDF "front" normal, which for WINDOW/genBSDF files points
 *   INTO THE ROOM; the exterior is on the -z side.  +y is "up" (the up
 *   vector of the BSDF material), x = y × z.  Both vectors of a query point
 *   AWAY from the surface: `in` towards the light source, `out` towards the
 *   viewer (or the next surface the scattered light goes to).  Reflection:
 *   in.z and out.z have the same sign; transmission: opposite signs.
 *
 * FRONT/BACK NAMING SWAP (WINDOW "front" = exterior = Radiance back):
 *   HD_BSDF_RF  Radiance rf, front (room-side) reflection  = WINDOW "Reflection Back"
 *   HD_BSDF_RB  Radiance rb, back (exterior) reflection     = WINDOW "Reflection Front"
 *   HD_BSDF_TF  Radiance tf, light from the room (+z) to the exterior
 *                                                         = WINDOW "Transmission Back"
 *   HD_BSDF_TB  Radiance tb, light from the exterior (-z) into the room
 *                                                         = WINDOW "Transmission Front"
 *   A missing transmission block is derived from the other by reciprocity
 *   f_tb(in, out) = f_tf(out, in).  A missing reflection block is zero.
 *
 * VALUES are BSDF values in 1/sr (Visible = CIE Y data only).  As Radiance
 * does, the minimum of a component is split off as a Lambertian part when
 * large enough (see docs/design/bsdf.md); evaluation returns the sum.
 *
 * A loaded hd_bsdf may be shared between threads.  Its exact sampling
 * distributions (one per fixed cell of the data) are built once by the first thread that
 * needs them and shared by all (lock-free; at most 256 MiB per data block,
 * then the per-thread caches hd_bsdf_cache take over).  Results do not
 * depend on which thread built what. */
#ifndef HELIODON_BSDF_H
#define HELIODON_BSDF_H

#include <stdio.h>
#include "common.h"
#include "vec.h"
#include "klems.h"
#include "matrix.h"

typedef enum hd_bsdf_comp {
    HD_BSDF_RF = 0, HD_BSDF_RB = 1, HD_BSDF_TF = 2, HD_BSDF_TB = 3
} hd_bsdf_comp;

/* Selection masks for hemispherical integrals and sampling. */
#define HD_BSDF_REFL  1
#define HD_BSDF_TRANS 2
#define HD_BSDF_ALL   3

/* How a component is available. */
#define HD_BSDF_ABSENT     0
#define HD_BSDF_IN_FILE    1
#define HD_BSDF_RECIPROCAL 2   /* derived from the other transmission */

typedef enum hd_bsdf_type {
    HD_BSDF_KLEMS_FULL = 0, HD_BSDF_KLEMS_HALF, HD_BSDF_KLEMS_QUARTER,
    HD_BSDF_KLEMS_OTHER,        /* matrix in another basis */
    HD_BSDF_TREE3,              /* isotropic tensor tree */
    HD_BSDF_TREE4,              /* anisotropic tensor tree */
    HD_BSDF_LAMBERTIAN          /* only Lambertian parts survived */
} hd_bsdf_type;

typedef struct hd_bsdf_info {
    char name[256];             /* <Material><Name> */
    char manufacturer[256];
    double width, height, thickness;  /* metres (0 if absent) */
    int has_geometry;           /* a non-empty <MGFblock> */
    hd_bsdf_type type;
    int avail[4];               /* HD_BSDF_ABSENT / IN_FILE / RECIPROCAL */
    double lambertian[4];       /* split-off Lambertian hemispherical part (a
                                   RECIPROCAL component: its source's) */
    double max_hemi[4];         /* max over incident directions of the non-
                                   Lambertian directional-hemispherical value
                                   of the data block (IN_FILE only) */
    double min_proj_sa[4];      /* finest projected solid angle (sr) */
    int tree_res;               /* trees: finest cells per square side */
} hd_bsdf_info;

typedef struct hd_bsdf hd_bsdf;

/* Load an XML file ("-", "!cmd" and gzip accepted).  Errors name the file,
 * the line and the element. */
hd_status hd_bsdf_load(const char *path, hd_bsdf **out);
hd_status hd_bsdf_load_memory(const char *data, size_t len, const char *name, hd_bsdf **out);
void hd_bsdf_free(hd_bsdf *b);
const hd_bsdf_info *hd_bsdf_get_info(const hd_bsdf *b);
/* Bytes of memory held by the loaded data. */
size_t hd_bsdf_memory(const hd_bsdf *b);

/* BSDF value (1/sr), all components; 0 for zero vectors or absent data. */
double hd_bsdf_eval(const hd_bsdf *b, hd_vec3 in, hd_vec3 out);
/* One component (the side tests are not repeated: the caller picks the
 * component that matches the signs of in.z and out.z). */
double hd_bsdf_eval_comp(const hd_bsdf *b, hd_bsdf_comp c, hd_vec3 in, hd_vec3 out,
                         int with_lambertian);
/* The finest data cell holding v in either role (and v's side), for data that are 4D tensor
 * trees only: hd_bsdf_eval_comp(b, c, v, x, .) and (b, c, x, v, .) are the same for every v
 * of one key, any x and c (a tree's leaves are dyadic cells no finer than its finest
 * level).  -1 for other data (3D trees, Klems, none) and for v in the data's plane. */
int64_t hd_bsdf_vector_cell(const hd_bsdf *b, hd_vec3 v);
/* The same and (psa, may be NULL) hd_bsdf_cell_psa of the pair in component c, from one
 * lookup of the data (a source through BSDF data asks both at every sample). */
double hd_bsdf_eval_comp_psa(const hd_bsdf *b, hd_bsdf_comp c, hd_vec3 in, hd_vec3 out,
                             int with_lambertian, double *psa);

/* ---- sampling ----
 * FORWARD: `given` is the incident vector (towards the light; e.g. the sun
 *   for photon emission); a scattered `out` is drawn with density
 *   proportional to f(given, out)·|out.z|.
 * BACKWARD: `given` is the outgoing vector (towards the eye); an incident
 *   `in` is drawn with density proportional to f(in, given)·|in.z|.
 * The density is exact for every data type and role: pdf (per steradian)
 * = f·|cos| / albedo, where albedo = ∫ f |cos| dω over the selected
 * hemispheres (the value that hd_bsdf_albedo returns; isotropic trees
 * sampled on their data-incident side included, by rings of the fixed
 * vector).  hd_bsdf_pdf returns the same density. */
#define HD_BSDF_FORWARD  0
#define HD_BSDF_BACKWARD 1

typedef struct hd_bsdf_sample {
    hd_vec3 dir;        /* sampled unit vector (pointing away) */
    double value;       /* f(in, out) at the sample, 1/sr */
    double pdf;         /* per steradian */
    double weight;      /* value·|dir.z| / pdf (= albedo when exact) */
    int comp;           /* hd_bsdf_comp that produced it */
    int lambertian;     /* drawn from the Lambertian part */
} hd_bsdf_sample;

typedef struct hd_bsdf_cache hd_bsdf_cache;
/* A cache of per-direction sampling distributions (max_bytes 0: 64 MiB)
 * used when the shared ones exceed their bound.  One per thread; results
 * do not depend on the cache state.  NULL: distributions that are not
 * shared are built for the query and freed. */
hd_bsdf_cache *hd_bsdf_cache_new(const hd_bsdf *b, size_t max_bytes);
void hd_bsdf_cache_free(hd_bsdf_cache *c);

/* Draw a sample using three uniform numbers in [0,1).  mask selects
 * HD_BSDF_REFL/TRANS.  Returns 1, or 0 if nothing scatters (albedo 0). */
int hd_bsdf_sample_dir(const hd_bsdf *b, hd_bsdf_cache *c, hd_vec3 given, int mode,
                       int mask, double u1, double u2, double u3, hd_bsdf_sample *s);
/* The same draw, but a draw that falls on a side in `drop` (HD_BSDF_REFL/
 * TRANS) returns 0 without building anything for it: the kept draws have
 * the density of the full sampler (the -st rule's unsampled sides).
 * narrow in [0, 1) (Radiance's -ss below 1 at BSDF data, m_bsdf.c): a draw
 * on a part of the data's directional values picks its cell with the
 * part's uniform narrowed to 0.5 + narrow·(u - 0.5) (0: the cell at the
 * middle of the part's distribution) and, as Radiance's bsdf_m.c /
 * bsdf_t.c, the point inside the cell from the same number (its place in
 * the cell's share, along a Hilbert curve over a Klems patch or, with the
 * tree's cells taken in that curve's order, over the sampled square; u2, u3
 * only below 2^-31 of it; isotropic trees sampled on their incident role
 * keep a uniform point); the weight is the part's total, so the estimate
 * leans to the middle of the distribution, as Radiance's.  1: the plain
 * draw. */
int hd_bsdf_sample_drop(const hd_bsdf *b, hd_bsdf_cache *c, hd_vec3 given, int mode,
                        int mask, int drop, double narrow, double u1, double u2, double u3, hd_bsdf_sample *s);
double hd_bsdf_pdf(const hd_bsdf *b, hd_bsdf_cache *c, hd_vec3 given, hd_vec3 dir,
                   int mode, int mask);
/* ∫ f |cos| dω of the sampled side (FORWARD: directional-hemispherical
 * value for incident `given`). */
double hd_bsdf_albedo(const hd_bsdf *b, hd_bsdf_cache *c, hd_vec3 given, int mode, int mask);
/* Tensor trees: π w² for w the side of the finest cell of the
 * distributions sampled from v as the data's incident vector (both sides;
 * Radiance's SDsizeBSDF minimum for v alone, the width of its view
 * jitter), *pmax the same of the coarsest (its maximum, the -st test's
 * jitter); -1 when a side holds Klems data or no tree cell is found. */
double hd_bsdf_view_psa(const hd_bsdf *b, hd_bsdf_cache *c, hd_vec3 v, double *pmax);
/* Forward directional-hemispherical values for light incident from `in`
 * (as Radiance's SDdirectHemi, per part): w[0] reflection, Lambertian part;
 * w[1] reflection, the data's non-Lambertian part; w[2], w[3] the same for
 * transmission.  Returns the total.  Data in the file are read from a table
 * made at load (no sampling structure is built); reciprocal data from the
 * total of the slice the backward sampler uses at the same vector (for
 * isotropic trees the ring totals, one traversal per block: no slice). */
double hd_bsdf_hemi_parts(const hd_bsdf *b, hd_bsdf_cache *c, hd_vec3 in, double w[4]);
/* Directional-hemispherical transmittance or reflectance for light
 * incident from `in` (forward), as Radiance's SDdirectHemi. */
double hd_bsdf_hemi(const hd_bsdf *b, hd_vec3 in, int mask);

/* ---- Klems matrices ----
 * Matrix of component c in basis kb (NULL: the file's basis for Klems
 * data, else LBNL/Klems Full): rows = outgoing bins, columns = incident
 * bins, element = mean of (f + Lambertian/π) over the bin pair ×
 * projected solid angle of the incident bin; ncomp copies (1 or 3).
 * Klems data in the same basis is copied exactly, in another ring basis
 * rebinned exactly (bin overlaps); anisotropic trees up to 128² cells per
 * hemisphere are integrated exactly over each bin pair; other data
 * (isotropic trees) is averaged over nsamp stratified direction pairs per
 * bin pair (0: 1024; a negative value forces that Monte Carlo path with
 * |nsamp| pairs, for testing).
 * For the 3-phase T matrix (dctimestep, rmtxop) use HD_BSDF_TB; rmtxop -rf
 * is HD_BSDF_RF, -rb HD_BSDF_RB.  Fails if the component is absent.
 * With kb NULL and Klems data whose row and column bases differ, the
 * matrix is the file's own nout × ninc one. */
hd_status hd_bsdf_klems_matrix(const hd_bsdf *b, hd_bsdf_comp c, const hd_klems_basis *kb,
                               int nsamp, int ncomp, hd_matrix *m);
/* The BSDF values (1/sr, no projected-solid-angle factor, Lambertian
 * included) of component c in basis kb, row-major [out][in]; as above. */
hd_status hd_bsdf_klems_values(const hd_bsdf *b, hd_bsdf_comp c, const hd_klems_basis *kb,
                               int nsamp, double *vals);

/* The incident / outgoing vector of Klems bin k for component c (the
 * directions the matrix rows and columns mean), at (r0, r1) in the bin. */
hd_vec3 hd_bsdf_klems_in_dir(const hd_klems_basis *kb, hd_bsdf_comp c, int k, double r0, double r1);
hd_vec3 hd_bsdf_klems_out_dir(const hd_klems_basis *kb, hd_bsdf_comp c, int k, double r0, double r1);

/* ---- data resolution and the "through" (view) component ----
 * Projected solid angle (sr) of the data cell that holds f(in, out): for
 * trees π·w² of the leaf cell (w its side in the unit square), for Klems
 * data the smaller of the two bins' λ (Radiance's SDsizeBSDF with both
 * vectors); 0 without data for that pair. */
double hd_bsdf_cell_psa(const hd_bsdf *b, hd_vec3 in, hd_vec3 out);

/* The straight-through part of the transmission seen along -vo (vo: local
 * unit vector towards the viewer), as Radiance's aBSDF finds it: the
 * finest-resolution cells around -vo that stand out from their
 * surroundings form a peak of transmittance `peak` (Lambertian part
 * removed); `surround` is the mean non-Lambertian BTDF of the probed cells
 * around it.  Returns 1 and fills t if there is such a peak (peak ≥ 0.0005),
 * else 0 (t->peak = 0). */
typedef struct hd_bsdf_through {
    double peak;        /* transmittance of the through (view) component */
    double surround;    /* BTDF (1/sr, non-Lambertian) around the peak */
    double psa_min;     /* finest projected solid angle of the data (sr) */
    double psa_peak;    /* smallest projected solid angle of the peak cells */
    int comp;           /* the transmission component probed */
} hd_bsdf_through;
int hd_bsdf_find_through(const hd_bsdf *b, hd_vec3 vo, hd_bsdf_through *t);
/* BSDF value (Lambertian included) for a direct source in local unit
 * direction li of solid angle omega, seen by vo: f(li, vo), except that
 * with a through component, a source behind the surface within the peak
 * (|li.xy + vo.xy|² ≤ 2.5·4/π·(ω|li.z| + psa_min + 2√(ω|li.z|·psa_min)))
 * gets the surround BTDF (its light arrives by the straight-through ray).
 * t may be NULL (plain f). */
double hd_bsdf_through_direct(const hd_bsdf *b, const hd_bsdf_through *t, hd_vec3 vo, hd_vec3 li,
                              double omega);
/* Whether a sampled transmitted direction dir (local, pointing away) falls
 * in the through peak of t and must be dropped because the through ray
 * carries that light (|dir.xy + vo.xy|² ≤ psa_peak). */
int hd_bsdf_through_excludes(const hd_bsdf_through *t, hd_vec3 vo, hd_vec3 dir);

/* ---- the BSDF / aBSDF scene materials (src/material_bsdf.c) ----
 * Radiance semantics (m_bsdf.c).  Ray kinds as m_bsdf distinguishes them: */
#define HD_BSDF_RAY_SHADOW    0   /* shadow (source) ray */
#define HD_BSDF_RAY_VIEW      1   /* primary ray or its unscattered continuation */
#define HD_BSDF_RAY_SCATTERED 2   /* a specular or diffuse (ambient) sample */
struct hd_tmat;
/* The local BSDF frame at a hit with geometric normal n (never flipped
 * towards the ray): z = n, x = up × z, y = z × x.  Returns 0, or -1 when
 * the up vector is parallel to n (Radiance: "illegal orientation"; any
 * perpendicular frame is returned then). */
int hd_tmat_bsdf_frame(const struct hd_tmat *m, hd_vec3 n, hd_vec3 *x, hd_vec3 *y, hd_vec3 *z);
/* Whether a ray passes the surface unchanged (the proxy case): only a BSDF
 * of non-zero thickness, for shadow and view rays, and for scattered rays
 * that hit the side the thickness does not hide (thick > 0 hides the back:
 * only front hits interact; thick < 0 the reverse).  hit_front: the ray
 * arrives on the +z side (dir·n < 0). */
int hd_tmat_bsdf_passes(const struct hd_tmat *m, int ray_kind, int hit_front);
/* Origin of rays and source tests on the transmitted side: p − thick·n
 * (n the unit geometric normal); p for zero thickness and aBSDF. */
hd_vec3 hd_tmat_bsdf_through_origin(const struct hd_tmat *m, hd_vec3 p, hd_vec3 n);
/* A shadow ray in world direction dir hits the surface (normal n): returns
 * 1 and the factor tr[3] it passes with (non-zero thickness: 1; aBSDF: its
 * through component for that direction, if any), or 0 if it is blocked
 * (BSDF of zero thickness, aBSDF without a through part or transmission). */
int hd_tmat_bsdf_shadow(const struct hd_tmat *m, hd_vec3 n, hd_vec3 dir, double tr[3]);
/* The through component of an aBSDF hit by a ray in world direction dir
 * (normal n): 1 and *t filled if the material is an aBSDF with a peak along
 * dir, else 0 (t->peak = 0).  As Radiance: for every ray kind the sources
 * are evaluated with hd_bsdf_through_direct(t); for VIEW rays only, the
 * integrator also sends one unscattered ray along dir with weight t->peak
 * and drops the BSDF samples for which hd_bsdf_through_excludes is true. */
int hd_tmat_bsdf_through(const struct hd_tmat *m, hd_vec3 n, hd_vec3 dir, hd_bsdf_through *t);

/* ---- tools ----
 * checkBSDF report of a loaded file (same layout as Radiance's checkBSDF;
 * path is printed as given). */
hd_status hd_bsdf_check_report(FILE *fp, const char *path, const hd_bsdf *b);
/* Reciprocity error statistics (percent) of a component pair: reflection
 * HD_BSDF_RF / HD_BSDF_RB compares f(v1,v2) with f(v2,v1); HD_BSDF_TF
 * compares tf(v1,v2) with tb(v2,v1).  Returns 0 if not computable (absent
 * blocks), else 1 with min, avg, max of 100·|f1-f2|/max(f1,f2) over all
 * Klems-full bin pairs with max > 0 (Klems data at bin centres, trees at
 * one random point per bin, fixed seed). */
int hd_bsdf_reciprocity(const hd_bsdf *b, hd_bsdf_comp c, double *mn, double *avg, double *mx);
/* Energy conservation: at the centre of every Klems-full bin on both sides,
 * the directional-hemispherical T + R must not exceed 1 + tol.  The first
 * max_report violations are reported with hd_warn naming the file, the
 * side, the incident direction (theta, phi in the BSDF frame; phi of the
 * direction towards the source) and the values, then a count; returns the
 * number of violating directions, and the largest T + R in *worst. */
int hd_bsdf_check_energy(const hd_bsdf *b, const char *path, double tol, int max_report, double *worst);
/* Write a Klems XML (as Radiance's bsdf2klems) in basis kb (NULL = full)
 * with nsamp samples per bin pair; comment names the producing command.
 * Writes every component that can be evaluated, in the order Reflection
 * Back, Reflection Front, Transmission Back, Transmission Front. */
hd_status hd_bsdf_write_klems_xml(FILE *fp, const hd_bsdf *b, const hd_klems_basis *kb,
                                  int nsamp, const char *comment);

/* Shirley–Chiu maps (spec §4.3): unit square <-> unit disk. */
void hd_square2disk(double sx, double sy, double *x, double *y);
void hd_disk2square(double x, double y, double *sx, double *sy);

/* WINDOW block name ("Transmission Front", ...) of a component, and
 * checkBSDF's label ("Interior Refl", ...). */
const char *hd_bsdf_window_name(hd_bsdf_comp c);
const char *hd_bsdf_label(hd_bsdf_comp c);

#endif

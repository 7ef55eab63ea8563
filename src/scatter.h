/* heliodon — the scattering rules of the scene materials, shared by the
 * path samplers:
 *   walk.c        the backward walk: radiance (rtrace / rpict) or
 *                 coefficients tallied at tracked emitters (rcontrib /
 *                 rfluxmtx / genBSDF), one implementation;
 *   pmap_build.c  mkpmap: photons, forward from the light.
 * The samplers keep their own strategies (how many diffuse samples,
 * what is tallied where); what a material does to light — which lobes it
 * has, their colours, the directions they scatter into and with which
 * density, how shadow rays pass it, how light sources are sampled — is
 * defined here once.
 *
 * A hit is first resolved (hd_scatter_at) into an hd_scatter: the
 * effective material (illum alternates resolved; patterns, textures and
 * mixtures evaluated at the hit: the one place every integrator gets them), the normal facing the
 * incoming ray, the derived coefficients of that material for the
 * incidence angle, and for BSDF / aBSDF materials the local frame of the
 * data (z = geometric front normal, y = up, as Radiance's m_bsdf).
 *
 * Direction conventions: `dir` / `d` is a travel direction (unit, from
 * the previous vertex towards the hit); sampled directions returned are
 * travel directions of the next ray (pointing away from the surface);
 * `l` is the unit direction from the hit towards a light source. */
#ifndef HELIODON_SCATTER_H
#define HELIODON_SCATTER_H

#include <math.h>

#include "heliodon/common.h"
#include "heliodon/bsdf.h"
#include "heliodon/vec.h"
#include "heliodon/material.h"
#include "heliodon/rng.h"
#include "heliodon/trace.h"

/* the largest channel of an RGB colour */
static inline double hd_scatter_cmax(const double c[3]) { return fmax(c[0], fmax(c[1], c[2])); }

struct hd_bsdf_cache;

typedef enum hd_sckind {
    HD_SC_ABSORB = 0,  /* black: nothing leaves (unknown material, illum without alternate in photon mode) */
    HD_SC_EMIT,        /* light / glow */
    HD_SC_PASS,        /* invisible for this ray (illum, void alternate) */
    HD_SC_NORMAL,      /* plastic / metal / trans (Radiance normal.c model) */
    HD_SC_GLASS,       /* thin glass */
    HD_SC_MIRROR,      /* mirror */
    HD_SC_BSDF         /* BSDF / aBSDF with LBNL XML data (and extra Lambertian parts) */
} hd_sckind;

/* hd_scatter_at flags */
#define HD_SC_ILLUM_ANYALT 1   /* illum shows any alternate material (photons);
                                  default: only plastic/metal/trans alternates,
                                  others pass (rtrace/rcontrib) */

typedef struct hd_scatter {
    hd_sckind kind;
    const hd_tmat *m;       /* effective material */
    hd_vec3 p;              /* hit point */
    hd_vec3 n;              /* geometric front normal */
    hd_vec3 nf;             /* normal on the side of the incoming ray */
    hd_vec3 dir;            /* incoming travel direction */
    double cosi;            /* -dir·nf, >= 0 */
    hd_nshade ns;           /* HD_SC_NORMAL: coefficients at cosi */
    int flat;               /* a polygon or ring without normal perturbation (Radiance's
                               SP_FLAT: a source's size widens the reflected lobe); 1 when
                               resolved without the surface (hd_scatter_material) */
    double R[3], T[3];      /* HD_SC_GLASS: reflectance, transmittance at cosi */
    /* HD_SC_BSDF */
    hd_vec3 bx, by, bz;     /* data frame (world) */
    hd_vec3 vo;             /* -dir in the data frame */
    int bfront;             /* the ray arrived on the data's +z side */
    const double *rdx;      /* extra Lambertian reflection of the side hit */
    const double *tdx;      /* extra Lambertian transmission */
    int has_thru;           /* aBSDF with a straight-through (view) peak along dir */
    int unsampled;          /* HD_BSDF_REFL/TRANS sides lit as diffuse, not
                               sampled (hd_scatter_bsdf_split; 0 = none) */
    hd_bsdf_through thru;   /* that peak (hd_tmat_bsdf_through) */
    hd_tmat mloc;           /* the material at this hit when patterns modify it (m points here) */
    double mixc;            /* > 0: m is one side of a mixture of two different materials, selected at
                               random (hd_scatter_at_sel); the outermost mixture's fore coefficient */
} hd_scatter;

/* Resolve the hit h of a ray travelling along unit dir. */
void hd_scatter_at(const hd_tscene *ts, const hd_hit *h, hd_vec3 dir, int flags, hd_scatter *sc);
/* The same, selecting one side of each mixture of two different materials
 * at random with rng (force 1 / 2: the fore / back side of the outermost
 * one; material.h hd_modray).  Weighted by nothing: the selection's
 * probability is the mixture's coefficient, so the expectation is
 * Radiance's coef x fore + (1 - coef) x back.  rng NULL: hd_scatter_at. */
void hd_scatter_at_sel(const hd_tscene *ts, const hd_hit *h, hd_vec3 dir, int flags, hd_rng *rng, int force,
                       hd_scatter *sc);
/* The material m shows at hit h of a ray along dir: m itself, or with its
 * patterns (and mixtures) evaluated there, in *tmp (no normal
 * perturbation: for shadow and gather rays). */
const hd_tmat *hd_scatter_hitmat(const hd_tmat *m, const hd_hit *h, hd_vec3 dir, hd_tmat *tmp);
/* The same with side 1 / 2: the fore / back side of the outermost mixture
 * of two different materials (tmp->mixsel its coefficient, 0 if none). */
const hd_tmat *hd_scatter_hitmat_side(const hd_tmat *m, const hd_hit *h, hd_vec3 dir, int side, hd_tmat *tmp);
/* Resolve material m at h (no illum rule, no patterns). */
void hd_scatter_material(const hd_tmat *m, const hd_hit *h, hd_vec3 dir, hd_scatter *sc);

/* ---- direction helpers ---- */
/* cosine-weighted direction about unit n from (u1, u2) in [0,1) */
hd_vec3 hd_scatter_cosdir(hd_vec3 n, double u1, double u2);
/* sin and cos of 2 pi u for u in [0, 1) without libm (quadrant + Taylor
 * polynomials on [-pi/4, pi/4]: within ~2e-16 of the exact values; the
 * photon tracer's direction sampling; same results on every platform). */
void hd_scatter_sincos2pi(double u, double *s, double *c);
/* cosine-weighted direction about n through the Shirley–Chiu map of (u, v)
 * (a, b: tangent axes of n) — stratifies well */
hd_vec3 hd_scatter_diskdir(hd_vec3 n, hd_vec3 a, hd_vec3 b, double u, double v);
/* mirror direction of the incoming ray */
hd_vec3 hd_scatter_mirror(const hd_scatter *sc);
/* Specular reflection of a plastic/metal/trans: the mirror direction when
 * pure, else a sample of the Gaussian lobe; 0 if it goes below the surface. */
int hd_scatter_spec_refl(const hd_scatter *sc, double u1, double u2, hd_vec3 *out);
/* Specular transmission (trans): straight through when pure, else
 * Radiance's Gaussian spread (normal.c): the straight direction moved by
 * t (cos φ a + sin φ b), a, b tangent to the surface, t = sqrt(-α² ln u1),
 * φ = 2π u2; 0 if that leaves on the incoming side. */
int hd_scatter_spec_trans(const hd_scatter *sc, double u1, double u2, hd_vec3 *out);
/* One trial of the rough reflected (trans = 0) or transmitted lobe: the
 * lobe's radial variate u1 drawn from [0, jit) (Radiance's -ss below 1
 * narrows the lobe towards the mirror / straight direction; jit 1: the
 * whole lobe, 0: that direction); 0 if it left its side. */
int hd_scatter_spec_try(const hd_scatter *sc, int trans, double jit, hd_rng *rng, hd_vec3 *out);
/* One sample of the rough reflected (trans = 0) or transmitted lobe as
 * Radiance draws it: up to 10 trials, each with fresh numbers from rng,
 * until one stays on its side.  0 if none did. */
int hd_scatter_spec_draw(const hd_scatter *sc, int trans, hd_rng *rng, hd_vec3 *out);

/* Radiance's specular threshold for a plastic/metal/trans (normal.c): a
 * rough lobe whose specularity is at most st (-st) is not sampled; its
 * colour joins the diffuse part of its side instead (reflection: added to
 * the diffuse reflection; transmission: the diffuse transmission becomes
 * the whole transmission), and that side is lit by the -ab rules — only if
 * it has a diffuse part (Radiance's rdiff / tdiff > FTINY).  Returns the
 * bits 1 (a specular reflected ray is traced: the mirror ray of a pure
 * surface, or samples of the rough lobe) and 2 (a transmitted one);
 * ramb / tamb: the colours of the diffuse reflection and transmission. */
int hd_scatter_normal_split(const hd_scatter *sc, double st, double ramb[3], double tamb[3]);

/* ---- Radiance's ray admission (rayorigin) ----
 * A child ray of weight *w is traced if *w >= lw; below, with lr > 0 it is
 * dropped, with lr <= 0 it survives Russian roulette with probability
 * *w/lw and is promoted to weight lw.  Returns the factor for the child's
 * contribution (0 = not traced) and updates *w. */
double hd_scatter_admit(double lw, int lr, double *w, hd_rng *rng);

/* ---- light sources ---- */
/* Sample light source surface si as seen from p: unit direction *l,
 * solid-angle weight *omega (contribution = L·omega·cos), distance *dist
 * (0 = distant source) and emitted radiance L (pattern applied).  jitter:
 * fraction of a distant source's radius sampled (0 = its centre).
 * Distant sources, polygons, spheres, rings and cylinders.  Returns 0 if
 * the source gives nothing (back side, beyond a glow's radius). */
int hd_scatter_sample_source(const hd_tscene *ts, int si, hd_vec3 p, double jitter, hd_rng *rng,
                             hd_vec3 *l, double *omega, double *dist, double L[3]);
/* Local `light` surfaces, reached both by shadow rays and by sampled rays
 * (candidates for multiple importance sampling). */
int hd_scatter_mis_source(const hd_surface *f, const hd_tmat *m);
/* Solid-angle density with which hd_scatter_sample_source picks the
 * direction from org to the point at distance t on f (cos_l at the emitter). */
double hd_scatter_source_pdf(const hd_surface *f, hd_vec3 org, double t, double cos_l);
/* power heuristic a²/(a²+b²) */
double hd_scatter_power(double a, double b);

/* Transmission of a shadow ray from p along l to surface `target` at
 * distance maxd (0: distant source): glass transmits, pure trans its
 * specular part, illum and invisible surfaces pass, anything else blocks.
 * strict_distant: for a distant target, the ray must also end in that
 * source (hd_tscene_source_hit_is), not another one.  Returns 0 if blocked. */
int hd_scatter_shadow(const hd_tscene *ts, hd_vec3 p, hd_vec3 l, double maxd, int target,
                      int strict_distant, double tr[3]);

/* Direct-light coefficient of a Lambertian surface (normal nf facing the
 * viewer) for a source in direction l of solid angle om: f such that the
 * contribution is f × L × transmission.  rd: diffuse reflection, td:
 * diffuse transmission (NULL: none), wl a weight on the diffuse reflection
 * (multiple importance sampling).  Returns 0 if nothing. */
int hd_scatter_direct_coef(hd_vec3 nf, const double rd[3], const double td[3], double wl, hd_vec3 l, double om,
                           double f[3]);
/* The same for a plastic / metal / trans at sc (HD_SC_NORMAL), Radiance's
 * dirnorm (normal.c): the diffuse parts (reduced by the Fresnel estimate
 * 1 - F(|n·l|) on a pure surface of specularity >= 0.018), the Gaussian
 * reflected lobe of a rough surface (variance α², plus (1 - dj) om / 4π
 * on a flat one), and the rough transmitted lobe about the straight
 * direction d: tspec × colour × exp((2 d·l - 2) / s) / (π s) × om ×
 * sqrt(|n·l| / max(cos_i, .001)), s = α² + om / π.  dj: -dj (0..1). */
int hd_scatter_normal_direct(const hd_scatter *sc, double wl, double dj, hd_vec3 l, double om, double f[3]);
/* Whether any part of hd_scatter_normal_direct can be non-zero at sc (a
 * diffuse part, or a rough lobe): 0 on a black or purely specular surface,
 * where the walk samples no source. */
int hd_scatter_normal_lit(const hd_scatter *sc);

/* ---- BSDF / aBSDF ----
 * f(l, view)·|cos l| for a light in world direction l of solid angle om,
 * seen along the incoming ray (1/sr; multiply by L·omega): the one rule
 * every integrator uses for direct sources through BSDF data (walk.c,
 * pmap_primary.c), Radiance's m_bsdf rule for a source of
 * finite size (docs/design/bsdf.md): the Lambertian part plus the mean of
 * the data over hd_scatter_bsdf_nsamp(ss, w) view directions jittered
 * across the data cell that holds the pair (stratified; rng NULL: the
 * strata centres, deterministic).  ss: -ss (jitter width × min(ss, 1));
 * w: the ray's weight (1 for view rays).  half > 0 (with rng): the
 * integrator jitters the source over the cone of half-angle half about
 * axis (-dj); every sample then takes its own direction of that disk (the
 * mean over the jitter, without the spikes of one direction per ray where
 * the disk straddles a data cell).  om matters to an aBSDF with a
 * through peak (sources inside it get the surround BTDF: their light
 * comes by the through ray).  pdf_back (may be NULL): the backward
 * sampling density of l at the unjittered view vector. */
double hd_scatter_bsdf_direct(const hd_scatter *sc, hd_vec3 l, double om, double ss, double w, hd_vec3 axis,
                              double half, hd_rng *rng, double *pdf_back);
/* Radiance's bsdf_jitter (m_bsdf.c): the local view vector vo moved by
 * r·(0.5 - u1), r·(0.5 - u2) in x and y, renormalised. */
hd_vec3 hd_scatter_bsdf_jitter(hd_vec3 vo, double r, double u1, double u2);
/* The width of that jitter for the data's sampling: √ of Radiance's
 * SDsizeBSDF minimum for the view vector alone, × min(ss, 1); *st_width
 * the same of its maximum, the jitter of the -st test (m_bsdf.c sr_vpsa);
 * 0 without data or with ss <= 0.  Trees: the finest and coarsest cells
 * of the distributions Radiance samples from vo (hd_bsdf_view_psa); Klems
 * data: the finer of the cells holding (vo, vo) and (vo, -vo), for both
 * (the patches of one direction). */
double hd_scatter_bsdf_view_width(const hd_scatter *sc, double ss, double *st_width);
/* The data's value towards world direction l times |cos l| (one lookup,
 * no jitter, Lambertian parts included): a cheap measure of how much a
 * source in direction l matters at sc (the -dn draw at data); through an
 * aBSDF's geometry (has_thru) 1. */
double hd_scatter_bsdf_value(const hd_scatter *sc, hd_vec3 l);
/* The continuation's backward density of world direction l at the
 * (unjittered) view vector, 0 on a side left unsampled (the MIS weight of
 * both the shadow rays and the continuation). */
double hd_scatter_bsdf_pdf_back(const hd_scatter *sc, struct hd_bsdf_cache *cache, hd_vec3 l);
/* Radiance's number of jittered view directions: round(4·ss·w), at least
 * 1.  hd_scatter_bsdf_direct takes at least 16 stratified samples with the
 * same mean (where Radiance takes 1, a query left out counts as zero, as
 * its single sample then gives no specular part): one random cell of the
 * neighbourhood per ray made rtrace -ab 1 irradiance through a Klems
 * window scatter by ±10 % between seeds, 4 samples ±3 %, and a window
 * pixel's rcontrib sun coefficient through a tree had a CV of 0.67 per
 * ray with 4. */
int hd_scatter_bsdf_nsamp(double ss, double w);

/* Draw the next travel direction through the data, on the sides of mask
 * (HD_BSDF_REFL / TRANS / ALL; the pdf is that of the sides drawn from).
 *   mode HD_BSDF_BACKWARD (eye paths): density ∝ f(in=out_dir, vo)·|cos|;
 *   mode HD_BSDF_FORWARD (photons): density ∝ f(-dir, out)·|cos|.
 * *weight = f·|cos|/pdf (the path throughput factor), *pdf per sr.
 * cache: per-thread sampling cache (may be NULL).  narrow: 1, or -ss
 * below 1 (hd_bsdf_sample_drop).  Returns 0 if nothing scatters. */
int hd_scatter_bsdf_sample(const hd_scatter *sc, struct hd_bsdf_cache *cache, int mode, int mask, double narrow,
                           double u1, double u2, double u3, hd_vec3 *out, double *weight, double *pdf);
/* Radiance's specular threshold (m_bsdf.c): a side of the data
 * (reflection or transmission) whose non-Lambertian directional-
 * hemispherical value towards the viewer is at most st is not sampled;
 * that value and the side's Lambertian part are lit from the side's
 * hemisphere as a diffuse surface instead (the integrator's -ab rules),
 * while direct sources still see the data (hd_scatter_bsdf_direct).
 * Returns the HD_BSDF_REFL/TRANS bits of the sides not sampled and their
 * hemispherical values in *ra, *ta (0 for sampled sides).  The value is
 * Radiance's SDdirectHemi: the data's directional-hemispherical value
 * with the view vector vo as the incident one (forward; data that are
 * not reciprocal, e.g. room-side reflection of a generated fabric tree,
 * give another value backward). */
int hd_scatter_bsdf_split(const hd_scatter *sc, struct hd_bsdf_cache *cache, double st, double *ra, double *ta);
/* whether the material has data (not only extra Lambertian parts) */
int hd_scatter_bsdf_has_data(const hd_scatter *sc);

/* ---- photons (forward) ----
 * One scattering event of a photon arriving at sc: a lobe is chosen by
 * Russian roulette with its albedo (u: uniform number; more are drawn from
 * rng as the lobe needs), the new travel direction goes to *nd and the
 * per-channel factor that keeps the estimate unbiased to fac (mean 1 when
 * the lobe is grey).  Returns the event. */
typedef enum hd_scevent {
    HD_SCE_ABSORB = 0,
    HD_SCE_DIFFUSE,       /* Lambertian reflection or transmission */
    HD_SCE_SPECULAR,      /* mirror / glossy reflection, glossy transmission */
    HD_SCE_GLASS_T,       /* straight through glass or pure trans: the photon stays "direct" */
    HD_SCE_BSDF           /* through / off data-driven BSDF */
} hd_scevent;

/* Per-thread BSDF sampling caches, one per BSDF data set met (created on
 * first use; results never depend on them). */
typedef struct hd_scatter_cache hd_scatter_cache;
hd_scatter_cache *hd_scatter_cache_new(void);
void hd_scatter_cache_free(hd_scatter_cache *c);
/* The calling thread's own caches (created on first use, freed when the
 * thread ends; NULL if out of memory). */
hd_scatter_cache *hd_scatter_thread_cache(void);
/* Called when a BSDF is released: every thread's caches are dropped on
 * their next use (threads outlive scenes in the shared pool). */
void hd_scatter_forget_bsdfs(void);
/* The cache for the BSDF of sc's material (NULL: none / out of memory). */
struct hd_bsdf_cache *hd_scatter_cache_for(hd_scatter_cache *c, const hd_scatter *sc);
/* The values hd_scatter_bsdf_value gives towards each of n distant sources
 * (surfaces lights[0..n), or the scene's lights when lights is NULL) at sc,
 * and (*sum) their sum, summed in that order: from the calling thread's
 * table c when a vertex on the same data, in the same frame and with its
 * view vector in the same finest data cell (hd_bsdf_vector_cell) asked for
 * them before, the same numbers bit for bit.  The array lives until the
 * next call on c.  NULL (and *sum 0) when a source is not distant, sc has
 * no data, or memory runs out. */
const double *hd_scatter_source_values(hd_scatter_cache *c, const hd_scatter *sc, const hd_tscene *ts,
                                       const int *lights, int n, double *sum);

hd_scevent hd_scatter_photon(const hd_scatter *sc, hd_scatter_cache *cache, double u, hd_rng *rng,
                             hd_vec3 *nd, double fac[3]);
/* The cosine-weighted direction about unit n that hd_scatter_photon's
 * diffuse lobes draw from (u1, u2) (hd_scatter_sincos2pi, not libm). */
hd_vec3 hd_scatter_photon_cosdir(hd_vec3 n, double u1, double u2);
/* Whether a photon arriving at sc is stored there (the surface has a
 * diffuse part that a density estimate would gather). */
int hd_scatter_photon_stores(const hd_scatter *sc);

#endif

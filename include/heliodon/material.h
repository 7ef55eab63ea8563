/* heliodon — Radiance materials for the ray tracer: the parameters of
 * plastic, metal, trans, glass, mirror, light, glow, illum (resolved from the
 * scene's primitives by the tracer), their reflection and transmission
 * formulas (as Radiance's normal.c and glass semantics define them) and the
 * sky brightness functions that gensky/gendaylit emit (skybright.cal,
 * perezlum.cal), evaluated natively.
 *
 * Colours are RGB triples of doubles (Radiance's visible-unit channels). */
#ifndef HELIODON_MATERIAL_H
#define HELIODON_MATERIAL_H

#include "common.h"
#include "vec.h"

typedef enum hd_mtype {
    HD_MAT_PLASTIC = 0,
    HD_MAT_METAL,
    HD_MAT_TRANS,
    HD_MAT_GLASS,
    HD_MAT_MIRROR,
    HD_MAT_LIGHT,
    HD_MAT_GLOW,
    HD_MAT_ILLUM,
    HD_MAT_INVISIBLE,     /* "void" alternate of illum/mirror: rays pass */
    HD_MAT_BSDF           /* BSDF / aBSDF with LBNL XML data (material_bsdf.c) */
} hd_mtype;

/* Brightness patterns (brightfunc skyfunc) evaluated natively. */
typedef enum hd_pattern {
    HD_PAT_NONE = 0,
    HD_PAT_PEREZ,         /* perezlum.cal skybright: 10 reals */
    HD_PAT_SKYBRIGHT,     /* skybright.cal skybr (gensky): 7 reals */
    HD_PAT_CAL            /* any brightfunc: evaluated with the .cal module */
} hd_pattern;

/* ---- patterns, textures and mixtures with function files (material_cal.c) ----
 * Radiance's brightfunc, colorfunc, texfunc, mixfunc, brightdata,
 * colordata, colorpict, texdata, mixdata and mixpict evaluated with the .cal module (rayinit.cal
 * loaded first, then the primitive's function file; one context per file,
 * shared by the modifiers that name it), with the ray state at the hit bound
 * to rayinit.cal's variables (Dx Dy Dz, Nx Ny Nz, Px Py Pz, Rdot, T, Ts, S,
 * Tx.., Ix.., Jx.., Kx.., Lu Lv; arg(n), A1.. for the real arguments) in
 * the modifier's own frame when its strings end with a transform.
 *
 * A modifier chain is the list of modifiers a material's shading applies
 * (Radiance's raytexture): patterns multiply a colour, textures add to a
 * normal perturbation, a mixture blends two sub-chains by a coefficient
 * (and, when they end in materials, the two materials: see
 * hd_tmat_modify).  A hd_modset owns every node, context and data file of
 * a scene.  Evaluation is thread-safe (per-thread evaluation runs). */
struct hd_modset;
struct hd_modnode;
struct hd_modchain;
struct hd_tmat;

struct hd_rng;

typedef struct hd_modray {
    hd_vec3 dir;          /* travel direction (unit) */
    hd_vec3 p;            /* hit point */
    hd_vec3 n;            /* front normal of the surface (unperturbed) */
    double t;             /* distance travelled to the hit (T, Ts) */
    /* A mixture of two different materials (or of a material and void)
     * shades as coef x fore + (1 - coef) x back (Radiance's raymixture).
     * With rng, one side is selected at random with probability coef /
     * 1 - coef (the same expectation; force 1 / 2 selects the fore / back
     * side of the outermost such mixture, the integrators' deterministic
     * split of view rays; without rng the middle of the side's range, for
     * shadow rays).  Without rng and force: the side with the larger
     * coefficient (emitters, the photon map's gathers). */
    struct hd_rng *rng;
    int force;
} hd_modray;

struct hd_modset *hd_modset_new(void);
void hd_modset_free(struct hd_modset *ms);
/* A node for pattern/texture/mixture primitive `type` (Radiance name) with
 * its strings and reals; function files, data files and pictures are
 * loaded (once per set).  `dir` is the scene file's directory (data files
 * are also looked for there), may be NULL.  Errors name `where`. */
hd_status hd_modset_node(struct hd_modset *ms, const char *type, char *const *sargs, int ns, const double *r,
                         int nr, const char *where, struct hd_modnode **out);
/* Names of a mixfunc's two modifiers (sargs[0..1]) */
const char *hd_modnode_mixname(const struct hd_modnode *nd, int side);
int hd_modnode_is_mix(const struct hd_modnode *nd);
/* A mixture of materials: its fore (else back) material; else NULL. */
const struct hd_tmat *hd_modnode_material(const struct hd_modnode *nd);
/* A mixture's side (0 fore, 1 back): the chain of modifiers of that side
 * (may be NULL) and the material it ends in (copied; NULL: none). */
hd_status hd_modnode_set_side(struct hd_modnode *nd, int side, const struct hd_modchain *chain,
                              const struct hd_tmat *mat);
/* A chain of n nodes, applied in order (n may be 0: returns NULL). */
hd_status hd_modset_chain(struct hd_modset *ms, struct hd_modnode *const *nodes, int n,
                          const struct hd_modchain **out);

/* Evaluate a chain at a hit: pcol[3] multiplied by the patterns, *pert
 * incremented by the textures; *mat (may be NULL) receives the material
 * a mixture of materials resolves to (into *tmp), else is left alone. */
void hd_modchain_eval(const struct hd_modchain *c, const hd_modray *ray, double pcol[3], hd_vec3 *pert,
                      const struct hd_tmat **mat, struct hd_tmat *tmp);

/* The material to shade a hit with: m itself when it has no modifiers,
 * else a copy in *tmp with the colour multiplied by the patterns (the
 * material a mixture selects).  *pert (may be NULL) receives the normal
 * perturbation of the textures (world frame; 0 if none). */
const struct hd_tmat *hd_tmat_modify(const struct hd_tmat *m, const hd_modray *ray, struct hd_tmat *tmp,
                                     hd_vec3 *pert);
/* Radiance's raynormal: the unit normal n + pert, turned back to the side
 * of n the ray sees when the perturbation would flip it. */
hd_vec3 hd_perturb_normal(hd_vec3 n, hd_vec3 pert, hd_vec3 dir);

#define HD_MAT_MAXPARG 12

typedef struct hd_tmat {
    hd_mtype type;
    double color[3];      /* plastic/metal/trans/mirror colour; light/glow/illum radiance; glass transmissivity */
    double spec, rough;   /* plastic/metal/trans */
    double trans, tspec;  /* trans */
    double rindex;        /* glass (default 1.52) */
    double maxrad;        /* glow */
    int alt;              /* illum/mirror: index of the alternate material, -1 = none (invisible) */
    hd_pattern pattern;
    int npattern;
    double parg[HD_MAT_MAXPARG];
    const struct hd_modchain *chain; /* patterns/textures/mixtures applied at each hit (or NULL) */
    struct hd_modset *ownmods;        /* set owned by this material (hd_tmat_set_brightfunc), or NULL */
    int mixed;            /* chain ends in a mixture of materials (the type above is the fore one's) */
    double mixsel;        /* hd_tmat_modify's result selected by a random choice between two different
                             materials: the outermost mixture's fore coefficient (0 < mixsel < 1), else 0 */
    char name[128];       /* modifier name */
    char where[256];      /* "file:line" of the definition, for messages */
    /* ---- BSDF / aBSDF (HD_MAT_BSDF) ---- */
    struct hd_bsdf *bsdf; /* loaded data, shared by the materials naming the same file */
    int bsdf_owner;       /* this material frees bsdf (hd_tmat_release) */
    int absdf;            /* aBSDF */
    double thick;         /* thickness (non-zero is approximated as 0) */
    hd_vec3 up;           /* up vector (world, after the material's transform) */
    double bsdf_rfront[3], bsdf_rback[3], bsdf_tdiff[3];  /* extra Lambertian parts */
} hd_tmat;

void hd_tmat_init(hd_tmat *m, hd_mtype type, const char *name);

/* Set the material from a Radiance type name and real arguments; errors
 * (wrong argument count, negative values) name `where`.  Unsupported
 * types give HD_ERR_UNSUPPORTED. */
hd_status hd_tmat_from_args(hd_tmat *m, const char *type, const char *name,
                                const double *r, int nr, int nstrings, const char *where);
/* Attach a brightfunc pattern: funcname and calfile as in the primitive's
 * strings ("skybright perezlum.cal", "skybr skybright.cal"). */
hd_status hd_tmat_set_pattern(hd_tmat *m, const char *funcname, const char *calfile,
                                  const double *r, int nr, const char *where);
/* Attach any brightfunc (its strings: variable, file, transform words):
 * perezlum.cal skybright and skybright.cal skybr without a transform are
 * computed natively (the same values as lib/perezlum.cal and
 * lib/skybright.cal, docs/design/funcfile.md), everything else with the .cal
 * module; HELIODON_SKY_CAL=1 sends those two through the .cal module too. */
hd_status hd_tmat_set_brightfunc(hd_tmat *m, char *const *sargs, int ns, const double *r, int nr,
                                 const char *where);

/* BSDF / aBSDF from a primitive's strings and reals (Radiance's
 * arguments: [thick] file ux uy uz funcfile [transform...], reals 0, 3, 6
 * or 9: extra front reflection, back reflection, diffuse transmission).
 * Only numeric thickness and up components are supported (funcfile must be
 * "." or a file whose variables are not used).  The data file is resolved
 * (current directory, then the directory of scenefile, then RAYPATH) into
 * path (cap bytes); the caller loads it (hd_bsdf_load) and sets m->bsdf.
 * Errors name `where`. */
hd_status hd_tmat_bsdf_args(hd_tmat *m, int absdf, const char *name, char *const *sargs, int ns,
                            const double *r, int nr, const char *scenefile, const char *where,
                            char *path, size_t cap);
/* Free what a material owns (the BSDF data of its owner). */
void hd_tmat_release(hd_tmat *m);

/* Pattern multiplier for a ray direction (unit). 1 for HD_PAT_NONE; the
 * first channel of a colour pattern. */
double hd_pattern_eval(const hd_tmat *m, hd_vec3 dir);
/* Radiance an emitter sends along travel direction dir: its colour times
 * its pattern(s).  h: the point seen (NULL for a distant source). */
struct hd_hit;
void hd_emit_color(const hd_tmat *m, hd_vec3 dir, const struct hd_hit *h, double L[3]);

/* Whether the material emits (light, glow, illum). */
static inline int hd_tmat_emits(const hd_tmat *m)
{
    return m->type == HD_MAT_LIGHT || m->type == HD_MAT_GLOW || m->type == HD_MAT_ILLUM;
}

/* ---- plastic / metal / trans (Radiance normal.c model) ----
 * Derived coefficients for an incidence cosine cosi = |n·v| (> 0): */
typedef struct hd_nshade {
    double rdiff[3];      /* diffuse reflectance (colour × (1 − trans − rspec)) */
    double tdiff[3];      /* diffuse transmittance (trans only) */
    double scol[3];       /* specular reflection colour (incl. Fresnel for pure specular) */
    double tscol[3];      /* specular transmission colour (trans only) */
    double rspec;         /* specular reflectance (scalar) */
    double tspec;         /* specular transmittance (scalar) */
    double rds, tds;      /* diffuse reflectance, transmittance (scalars, before the colour) */
    double alpha2;        /* roughness² */
    int pure;             /* roughness² <= tiny: mirror-like specular */
} hd_nshade;

void hd_normal_coeffs(const hd_tmat *m, double cosi, hd_nshade *ns);

/* Reflected specular lobe for a source seen in unit direction l from a
 * surface with unit normal n (facing the viewer), view ray direction v
 * (unit, pointing at the surface), source solid angle omega: the factor
 * that multiplies scol × source radiance (Radiance's Gaussian lobe with the
 * roughness widened by the source size). 0 if l is below the surface. */
double hd_specular_lobe(hd_vec3 n, hd_vec3 v, hd_vec3 l, double alpha2, double omega);
/* The Gaussian itself for a total variance a2 (roughness² plus the
 * source's share, which Radiance adds on flat surfaces only): the factor
 * that, times n·l × omega, is hd_specular_lobe.  0 if degenerate. */
double hd_specular_gauss(hd_vec3 n, hd_vec3 v, hd_vec3 l, double a2);

/* Sample a direction from the Gaussian (Ward) lobe around the mirror
 * direction of v about n, with random numbers u1, u2 in [0,1); returns 0
 * if the sampled direction goes below the surface. */
int hd_specular_sample(hd_vec3 n, hd_vec3 v, double alpha2, double u1, double u2, hd_vec3 *out);

/* ---- glass (thin, Radiance convention) ----
 * For incidence cosine cosi (> 0), per channel transmissivity tn and index
 * n: reflectance and transmittance of the pane including the internal
 * reflections, averaged over the two polarisations. */
void hd_glass_coeffs(const double tn[3], double rindex, double cosi, double refl[3], double trans[3]);
/* Transmissivity tn for a measured normal transmittance Tn (n = 1.52). */
double hd_glass_transmissivity(double Tn);

/* Perez all-weather sky (perezlum.cal "skybright"): args A1..A10 =
 * diffnorm, groundbr, a, b, c, d, e, sun x y z. */
double hd_perezlum(const double *a, hd_vec3 dir);
/* gensky skybright.cal "skybr": A1 = type (1 clear, 2 overcast,
 * 3 uniform; 4 intermediate is unsupported), A2 zenith brightness,
 * A3 ground brightness, A4 normalisation, A5..A7 sun direction. */
double hd_skybright(const double *a, hd_vec3 dir);

#endif

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
    HD_MAT_INVISIBLE      /* "void" alternate of illum/mirror: rays pass */
} hd_mtype;

/* Brightness patterns (brightfunc skyfunc) evaluated natively. */
typedef enum hd_pattern {
    HD_PAT_NONE = 0,
    HD_PAT_PEREZ,         /* perezlum.cal skybright: 10 reals */
    HD_PAT_SKYBRIGHT      /* skybright.cal skybr (gensky): 7 reals */
} hd_pattern;

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
    char name[128];       /* modifier name */
    char where[256];      /* "file:line" of the definition, for messages */
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

/* Pattern multiplier for a ray direction (unit). 1 for HD_PAT_NONE. */
double hd_pattern_eval(const hd_tmat *m, hd_vec3 dir);

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

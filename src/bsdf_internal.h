/* heliodon — private BSDF structures shared by bsdf_load.c and bsdf.c. */
#ifndef HELIODON_BSDF_INTERNAL_H
#define HELIODON_BSDF_INTERNAL_H

#include <stdint.h>
#include "heliodon/bsdf.h"

/* Tensor-tree node: k < 0 internal node whose 2^D children are the nodes
 * off .. off+2^D-1 (child index bit i = upper half of dimension i);
 * k >= 0 a leaf grid of 2^k cells per dimension, values val[off ...],
 * last dimension varying fastest. */
typedef struct hd_tnode { int32_t k; uint32_t off; } hd_tnode;

typedef struct hd_ttree {
    int dim;                /* 3 or 4 */
    hd_tnode root;
    hd_tnode *node;
    size_t nnode, capnode;
    float *val;
    size_t nval, capval;
    int maxlev;             /* finest level: cells of side 2^-maxlev */
} hd_ttree;

/* One data block of the file (one WINDOW direction, visible data). */
typedef struct hd_bsdf_block {
    int kind;               /* 1 = Klems matrix, 3/4 = tensor tree */
    hd_klems_basis inb;     /* Klems: incident (column) basis */
    hd_klems_basis outb;    /* Klems: outgoing (row) basis */
    float *mtx;             /* Klems: [out * ninc + in], 1/sr */
    hd_ttree tree;
    double lamb;            /* split-off Lambertian hemispherical value */
    double max_hemi;        /* max directional-hemispherical (non-Lambertian) */
    double min_proj_sa;
    double *hemi;           /* forward non-Lambertian directional-hemispherical
                               value per incident cell (load-time marginal):
                               Klems per incident bin; trees on a grid of
                               hemi_res cells per fixed dimension */
    int hemi_res;
    int id;                 /* 0..3: the component it serves directly */
    struct hd_slice_store *store;   /* sampling distributions shared by all
                                       threads (bsdf.c), NULL if none */
} hd_bsdf_block;

struct hd_bsdf {
    hd_bsdf_info info;
    hd_bsdf_block *blk[4];          /* indexed by the component served directly */
    const hd_bsdf_block *src[4];    /* data for component c */
    int recip[4];                   /* 1: component c = src data with in/out swapped */
    double lamb[4];                 /* Lambertian hemispherical part of component c */
    size_t bytes;
};

/* Evaluation of the raw data: a = data-incident vector, b = data-outgoing
 * vector (both pointing away; only their x, y enter), and from the same
 * lookup (psa, key: may be NULL) the cell of hd_block_cell. */
double hd_block_eval_cell(const hd_bsdf_block *d, hd_vec3 a, hd_vec3 b, double *psa, uint64_t *key);
/* Projected solid angle (sr) of the data cell holding (a, b) and an
 * identifier of that cell; 0 outside the data. */
double hd_block_cell(const hd_bsdf_block *d, hd_vec3 a, hd_vec3 b, uint64_t *key);
/* Finish a loaded bsdf: diffuse extraction, extrema, component table. */
hd_status hd_bsdf_finish(hd_bsdf *b, const char *fname);
void hd_ttree_free(hd_ttree *t);
/* Free the shared sampling distributions of a block. */
void hd_block_store_free(hd_bsdf_block *d);
/* Tests: largest relative difference between a 3D block's ring totals
 * (one traversal, used for albedos and the -st value) and the sums of its
 * ring slices built one by one; -1 if not a 3D tree or out of memory. */
double hd_block_ring_sums_check(const hd_bsdf_block *d);
/* The component (hd_bsdf_comp) of the pair (in, out) by the sides of the
 * surface (z) they lie on; -1 when either lies in its plane. */
static inline int hd_bsdf_comp_of(hd_vec3 in, hd_vec3 out)
{
    if (in.z > 0) return out.z > 0 ? HD_BSDF_RF : out.z < 0 ? HD_BSDF_TF : -1;
    if (in.z < 0) return out.z < 0 ? HD_BSDF_RB : out.z > 0 ? HD_BSDF_TB : -1;
    return -1;
}
/* Text in WINDOW XML (bsdf2klems, genBSDF): <, > and & escaped; NULL writes nothing. */
void hd_xml_text(FILE *fp, const char *s);
/* The LBNL BSDF XML writers' (bsdf2klems, genBSDF) common parts: the
 * prologue up to </Manufacturer> (the comment, when given, between
 * "<!-- LEAD" and TAIL, "--" made "__"), and a WavelengthData block's
 * head up to <ScatteringData> (the angle basis: Klems basis kbasis for
 * rows and columns, NULL: a tensor tree's; type "BRDF" or "BTDF") and its
 * tail from </ScatteringData>. */
void hd_xml_bsdf_head(FILE *fp, const char *lead, const char *comment, const char *tail, const char *name,
                      const char *manufacturer);
void hd_xml_wavelength_head(FILE *fp, const char *direction, const char *kbasis, const char *type);
void hd_xml_wavelength_tail(FILE *fp);

#endif

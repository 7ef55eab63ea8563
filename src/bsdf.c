/* heliodon — BSDF evaluation, integration, sampling and Klems matrices
 * (see bsdf.h for the conventions and docs/design/bsdf.md for the design). */
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bsdf_internal.h"
#include "heliodon/rng.h"

/* ---- Shirley–Chiu ---- */
#define SC_SHRINK 0.9999999999999

void hd_square2disk(double sx, double sy, double *x, double *y)
{
    double a = 2 * sx - 1, b = 2 * sy - 1, r, phi;
    if (a > -b) {
        if (a > b) { r = a; phi = (HD_PI / 4) * (b / a); }
        else { r = b; phi = (HD_PI / 4) * (2 - a / b); }
    } else {
        if (a < b) { r = -a; phi = (HD_PI / 4) * (4 + b / a); }
        else { r = -b; phi = b != 0 ? (HD_PI / 4) * (6 - a / b) : 0; }
    }
    r *= SC_SHRINK;
    *x = r * cos(phi);
    *y = r * sin(phi);
}

void hd_disk2square(double x, double y, double *sx, double *sy)
{
    double r = sqrt(x * x + y * y), phi = atan2(y, x), a, b;
    if (phi < -HD_PI / 4) phi += 2 * HD_PI;
    if (phi < HD_PI / 4) { a = r; b = phi * a / (HD_PI / 4); }
    else if (phi < 3 * HD_PI / 4) { b = r; a = -(phi - HD_PI / 2) * b / (HD_PI / 4); }
    else if (phi < 5 * HD_PI / 4) { a = -r; b = (phi - HD_PI) * a / (HD_PI / 4); }
    else { b = -r; a = -(phi - 3 * HD_PI / 2) * b / (HD_PI / 4); }
    *sx = a * (0.5 / SC_SHRINK) + 0.5;
    *sy = b * (0.5 / SC_SHRINK) + 0.5;
    if (*sx < 0) *sx = 0;
    if (*sy < 0) *sy = 0;
    if (*sx >= 1) *sx = 1 - 1e-15;
    if (*sy >= 1) *sy = 1 - 1e-15;
}

/* ---- component geometry ---- */
static const int in_side[4] = {1, -1, 1, -1};   /* rf rb tf tb */
static const int out_side[4] = {1, -1, -1, 1};

const char *hd_bsdf_window_name(hd_bsdf_comp c)
{
    static const char *const n[4] = {"Reflection Back", "Reflection Front",
                                      "Transmission Back", "Transmission Front"};
    return (unsigned)c < 4 ? n[c] : "?";
}

const char *hd_bsdf_label(hd_bsdf_comp c)
{
    static const char *const n[4] = {"Interior Refl", "Exterior Refl",
                                     "Int->Ext Trans", "Ext->Int Trans"};
    return (unsigned)c < 4 ? n[c] : "?";
}

/* ---- tensor trees ---- */
/* The leaf of the tree at coordinates c (each in [0,1), changed): its index
 * into t->val; *side (if not NULL) receives the leaf cell's side length. */
static inline size_t tree_leaf(const hd_ttree *t, double c[4], double *side)
{
    int D = t->dim;
    double w = 1;
    hd_tnode nd = t->root;
    while (nd.k < 0) {
        int n = 0;
        for (int i = 0; i < D; i++) {
            if (c[i] >= 0.5) { n |= 1 << i; c[i] = 2 * c[i] - 1; }
            else c[i] *= 2;
        }
        w *= 0.5;
        nd = t->node[nd.off + (uint32_t)n];
    }
    int r = 1 << nd.k;
    size_t idx = 0;
    for (int i = 0; i < D; i++) {
        int ii = (int)(c[i] * r);
        if (ii >= r) ii = r - 1;
        if (ii < 0) ii = 0;
        idx = idx * (size_t)r + (size_t)ii;
    }
    if (side) *side = w / r;
    return nd.off + idx;
}

/* The square coordinates of the last vector of each role, per thread: evaluations repeat one
 * of the two (a window pixel's view direction against every sun; a sun against every photon
 * bounce).  Inputs compared bit for bit (atan2 tells -0 from +0), so results are unchanged. */
typedef struct tc_memo { double in[2], out[2]; int ok; } tc_memo;
static _Thread_local tc_memo tc_last[2];

static void disk2square_memo(int role, double x, double y, double *sx, double *sy)
{
    tc_memo *m = &tc_last[role];
    double in[2] = {x, y};
    if (m->ok && !memcmp(m->in, in, sizeof in)) { *sx = m->out[0]; *sy = m->out[1]; return; }
    hd_disk2square(x, y, sx, sy);
    memcpy(m->in, in, sizeof in);
    m->out[0] = *sx;
    m->out[1] = *sy;
    m->ok = 1;
}

/* tree coordinates of (a, b) */
static void tree_coords(int D, hd_vec3 a, hd_vec3 b, double c[4])
{
    if (D == 4) {
        disk2square_memo(0, -a.x, -a.y, &c[0], &c[1]);
        disk2square_memo(1, b.x, b.y, &c[2], &c[3]);
        return;
    }
    double ra = sqrt(a.x * a.x + a.y * a.y);
    c[0] = 0.5 - 0.5 * ra;
    if (c[0] >= 0.5) c[0] = 0.5 - 1e-12;
    if (c[0] < 0) c[0] = 0;
    double rx = b.x, ry = b.y;
    if (ra > 1e-12) {
        double cp = -a.x / ra, sp = -a.y / ra;
        rx = b.x * cp + b.y * sp;
        ry = -b.x * sp + b.y * cp;
    }
    hd_disk2square(rx, ry, &c[1], &c[2]);
}

static inline float tree_lookup(const hd_ttree *t, double c[4])
{
    return t->val[tree_leaf(t, c, NULL)];
}

/* The value at (a, b) and (psa, key: may be NULL) the leaf cell holding the pair: its
 * projected solid angle in the outgoing square (π·w², w = cell side; Klems: the smaller bin
 * λ) and an identifier (leaf value index; Klems: matrix index), from one lookup.  0 and
 * psa 0 outside the data. */
double hd_block_eval_cell(const hd_bsdf_block *d, hd_vec3 a, hd_vec3 b, double *psa, uint64_t *key)
{
    if (psa) *psa = 0;
    if (d->kind == 1) {
        int i = hd_klems_bin(&d->inb, hd_v3(-a.x, -a.y, fabs(a.z)));
        int o = hd_klems_bin(&d->outb, hd_v3(b.x, b.y, fabs(b.z)));
        if (i < 0 || o < 0) return 0;
        size_t k = (size_t)o * (size_t)d->inb.nbins + (size_t)i;
        if (key) *key = k;
        if (psa) {
            double li = hd_klems_lambda(&d->inb, i), lo = hd_klems_lambda(&d->outb, o);
            *psa = li < lo ? li : lo;
        }
        return d->mtx[k];
    }
    if (d->kind < 3) return 0;
    double c[4], w;
    tree_coords(d->kind, a, b, c);
    size_t leaf = tree_leaf(&d->tree, c, &w);
    if (key) *key = leaf;
    if (psa) *psa = HD_PI * w * w;
    return d->tree.val[leaf];
}

double hd_block_cell(const hd_bsdf_block *d, hd_vec3 a, hd_vec3 b, uint64_t *key)
{
    double psa;
    hd_block_eval_cell(d, a, b, &psa, key);
    return psa;
}

/* ---- loading: finish ---- */
static struct hd_slice_store *store_new(const hd_bsdf_block *d);

static void tree_min(const hd_ttree *t, hd_tnode nd, double lo0, double s0, double *mn)
{
    int D = t->dim;
    if (nd.k < 0) {
        for (int n = 0; n < (1 << D); n++)
            tree_min(t, t->node[nd.off + (uint32_t)n], lo0 + ((n & 1) ? s0 / 2 : 0), s0 / 2, mn);
        return;
    }
    size_t r = (size_t)1 << nd.k, nv = (size_t)1 << (nd.k * D), per0 = nv / r;
    for (size_t i0 = 0; i0 < r; i0++) {
        if (D == 3 && lo0 + (double)i0 * s0 / (double)r >= 0.5) break;
        const float *v = t->val + nd.off + i0 * per0;
        for (size_t j = 0; j < per0; j++) if (v[j] < *mn) *mn = v[j];
    }
}

static void tree_sub(hd_ttree *t, hd_tnode nd, float m)
{
    (void)nd;
    for (size_t i = 0; i < t->nval; i++) {
        t->val[i] -= m;
        if (t->val[i] < 0) t->val[i] = 0;
    }
}

/* Marginal over the two outgoing dimensions, for every incident cell of a
 * grid G (gres per fixed dimension; fixed dims = the first D-2). */
static void tree_marg(const hd_ttree *t, hd_tnode nd, const double lo[2], double s,
                      double *G, int gres)
{
    int D = t->dim, nf = D - 2;
    if (nd.k < 0) {
        for (int n = 0; n < (1 << D); n++) {
            double l2[2] = {lo[0], nf > 1 ? lo[1] : 0};
            for (int d = 0; d < nf; d++) if (n & (1 << d)) l2[d] += s / 2;
            tree_marg(t, t->node[nd.off + (uint32_t)n], l2, s / 2, G, gres);
        }
        return;
    }
    size_t r = (size_t)1 << nd.k, r2 = r * r, nfix = nf == 2 ? r2 : r;
    double cs = s / (double)r, area = HD_PI * cs * cs;
    double cover = cs * gres;                 /* grid cells per fixed side */
    double wfrac = cover < 1 ? cover : 1;
    for (size_t f = 0; f < nfix; f++) {
        const float *v = t->val + nd.off + f * r2;
        double sum = 0;
        for (size_t j = 0; j < r2; j++) sum += v[j];
        if (sum <= 0) continue;
        size_t i0 = nf == 2 ? f / r : f, i1 = nf == 2 ? f % r : 0;
        double x0 = lo[0] + (double)i0 * cs, y0 = nf == 2 ? lo[1] + (double)i1 * cs : 0;
        int gx0 = (int)(x0 * gres + 1e-9), gx1 = (int)ceil((x0 + cs) * gres - 1e-9);
        int gy0 = 0, gy1 = 1;
        if (nf == 2) { gy0 = (int)(y0 * gres + 1e-9); gy1 = (int)ceil((y0 + cs) * gres - 1e-9); }
        if (gx1 <= gx0) gx1 = gx0 + 1;
        if (gy1 <= gy0) gy1 = gy0 + 1;
        double add = sum * area * wfrac * (nf == 2 ? wfrac : 1);
        for (int gx = gx0; gx < gx1 && gx < gres; gx++)
            for (int gy = gy0; gy < gy1 && gy < (nf == 2 ? gres : 1); gy++)
                G[(size_t)gx * (nf == 2 ? (size_t)gres : 1) + (size_t)gy] += add;
    }
}

/* The forward hemispherical value per incident grid cell (kept in d->hemi
 * for hd_bsdf_hemi_parts) and its maximum. */
static double tree_max_hemi(hd_bsdf_block *d)
{
    const hd_ttree *t = &d->tree;
    int nf = t->dim - 2;
    int gres = 1 << (t->maxlev < 9 ? t->maxlev : 9);
    size_t n = nf == 2 ? (size_t)gres * (size_t)gres : (size_t)gres;
    double *G = hd_calloc(n, sizeof *G);
    if (!G) return 0;
    double lo[2] = {0, 0};
    tree_marg(t, t->root, lo, 1.0, G, gres);
    double mx = 0;
    for (size_t i = 0; i < n; i++) {
        if (nf == 1 && i >= (size_t)gres / 2 && gres > 1) break;   /* 3D: used half */
        if (G[i] > mx) mx = G[i];
    }
    d->hemi = G;
    d->hemi_res = gres;
    return mx;
}

/* forward hemispherical value of block d (as stored, not reciprocal) for
 * the data-incident vector a; -1 without a table */
static double block_hemi(const hd_bsdf_block *d, hd_vec3 a)
{
    if (!d->hemi) return -1;
    if (d->kind == 1) {
        int i = hd_klems_bin(&d->inb, hd_v3(-a.x, -a.y, fabs(a.z)));
        return i < 0 ? 0 : d->hemi[i];
    }
    double c[4];
    tree_coords(d->kind, a, hd_v3(0, 0, 1), c);
    int n = d->hemi_res, gx = (int)(c[0] * n), gy = (int)(c[1] * n);
    if (gx >= n) gx = n - 1;
    if (gy >= n) gy = n - 1;
    if (gx < 0) gx = 0;
    if (gy < 0) gy = 0;
    return d->kind == 3 ? d->hemi[gx] : d->hemi[(size_t)gx * (size_t)n + (size_t)gy];
}

static void finish_block(hd_bsdf_block *d)
{
    if (d->kind == 1) {
        size_t ninc = (size_t)d->inb.nbins, nout = (size_t)d->outb.nbins, n = ninc * nout;
        float mn = HUGE_VALF;
        for (size_t i = 0; i < n; i++) if (d->mtx[i] < mn) mn = d->mtx[i];
        if (HD_PI * mn > 0.01) {
            for (size_t i = 0; i < n; i++) d->mtx[i] -= mn;
            d->lamb = HD_PI * mn;
        }
        d->max_hemi = 0;
        d->hemi = hd_malloc_array(ninc, sizeof *d->hemi);
        for (size_t i = 0; i < ninc; i++) {
            double s = 0;
            for (size_t o = 0; o < nout; o++) s += d->mtx[o * ninc + i] * hd_klems_lambda(&d->outb, (int)o);
            if (s > d->max_hemi) d->max_hemi = s;
            if (d->hemi) d->hemi[i] = s;
        }
        d->min_proj_sa = hd_klems_min_lambda(&d->outb);
        return;
    }
    hd_ttree *t = &d->tree;
    double mn = HUGE_VAL;
    tree_min(t, t->root, 0, 1, &mn);
    if (mn > 0.01 / HD_PI && mn < 1.5 / HD_PI) {
        tree_sub(t, t->root, (float)mn);
        d->lamb = HD_PI * mn;
    }
    d->max_hemi = tree_max_hemi(d);
    double w = ldexp(1.0, -t->maxlev);
    d->min_proj_sa = HD_PI * w * w;
}

hd_status hd_bsdf_finish(hd_bsdf *b, const char *fname)
{
    (void)fname;
    hd_bsdf_info *inf = &b->info;
    b->bytes = sizeof *b;
    for (int c = 0; c < 4; c++) {
        hd_bsdf_block *d = b->blk[c];
        if (!d) continue;
        finish_block(d);
        b->bytes += sizeof *d;
        if (d->kind == 1) b->bytes += (size_t)d->inb.nbins * (size_t)d->outb.nbins * sizeof(float);
        else b->bytes += d->tree.nnode * sizeof(hd_tnode) + d->tree.nval * sizeof(float);
        inf->avail[c] = HD_BSDF_IN_FILE;
        inf->lambertian[c] = d->lamb;
        inf->max_hemi[c] = d->max_hemi;
        inf->min_proj_sa[c] = d->min_proj_sa;
        if (d->kind >= 3 && d->tree.maxlev >= 0) inf->tree_res = 1 << d->tree.maxlev;
        if (d->max_hemi <= 0.001) {      /* negligible directional part */
            free(d->mtx);
            d->mtx = NULL;
            hd_ttree_free(&d->tree);
            free(d->hemi);
            d->hemi = NULL;
            d->kind = 0;
            d->max_hemi = 0;
        }
        if (d->kind) d->store = store_new(d);
    }
    /* component table */
    for (int c = 0; c < 4; c++) { b->src[c] = b->blk[c]; b->recip[c] = 0; }
    if (!b->blk[HD_BSDF_TF] && b->blk[HD_BSDF_TB]) {
        b->src[HD_BSDF_TF] = b->blk[HD_BSDF_TB]; b->recip[HD_BSDF_TF] = 1;
        inf->avail[HD_BSDF_TF] = HD_BSDF_RECIPROCAL;
    }
    if (!b->blk[HD_BSDF_TB] && b->blk[HD_BSDF_TF]) {
        b->src[HD_BSDF_TB] = b->blk[HD_BSDF_TF]; b->recip[HD_BSDF_TB] = 1;
        inf->avail[HD_BSDF_TB] = HD_BSDF_RECIPROCAL;
    }
    /* a reciprocal transmission component has its source's Lambertian part
     * (Radiance copies it between the two sides too: checkBSDF prints it) */
    for (int c = 0; c < 4; c++) inf->lambertian[c] = b->lamb[c] = b->src[c] ? b->src[c]->lamb : 0;
    /* type */
    inf->type = HD_BSDF_LAMBERTIAN;
    for (int c = 0; c < 4; c++) {
        const hd_bsdf_block *d = b->blk[c];
        if (!d || !d->kind) continue;
        if (d->kind == 3) inf->type = HD_BSDF_TREE3;
        else if (d->kind == 4) inf->type = HD_BSDF_TREE4;
        else {
            const hd_klems_basis *kb = &d->inb;
            hd_klems_basis std;
            inf->type = HD_BSDF_KLEMS_OTHER;
            for (int k = 0; k < 3; k++) {
                hd_klems_standard(&std, (hd_klems_kind)k);
                if (kb->nbins != std.nbins || kb->nrings != std.nrings) continue;
                int same = 1;
                for (int r = 0; r < kb->nrings; r++)
                    if (kb->ring[r].nphi != std.ring[r].nphi ||
                        fabs(kb->ring[r].theta_hi - std.ring[r].theta_hi) > 1e-6) same = 0;
                if (same && !memcmp(&d->inb.ring, &d->outb.ring, sizeof d->inb.ring))
                    inf->type = (hd_bsdf_type)(HD_BSDF_KLEMS_FULL + k);
            }
        }
        break;
    }
    return HD_OK;
}

const hd_bsdf_info *hd_bsdf_get_info(const hd_bsdf *b) { return &b->info; }
size_t hd_bsdf_memory(const hd_bsdf *b) { return b->bytes; }

/* ---- evaluation ---- */
static inline hd_vec3 unitv(hd_vec3 v)
{
    double l2 = v.x * v.x + v.y * v.y + v.z * v.z;
    if (l2 > 0 && fabs(l2 - 1) > 1e-12) return hd_vscale(v, 1 / sqrt(l2));
    return v;
}

static double comp_nd_psa(const hd_bsdf *b, int c, hd_vec3 in, hd_vec3 out, double *psa)
{
    const hd_bsdf_block *d = b->src[c];
    if (psa) *psa = 0;
    if (!d || !d->kind) return 0;
    return b->recip[c] ? hd_block_eval_cell(d, out, in, psa, NULL) : hd_block_eval_cell(d, in, out, psa, NULL);
}

static double comp_nd(const hd_bsdf *b, int c, hd_vec3 in, hd_vec3 out)
{
    return comp_nd_psa(b, c, in, out, NULL);
}

double hd_bsdf_eval_comp_psa(const hd_bsdf *b, hd_bsdf_comp c, hd_vec3 in, hd_vec3 out, int with_lamb, double *psa)
{
    if (psa) *psa = 0;
    if ((unsigned)c > 3) return 0;
    in = unitv(in);
    out = unitv(out);
    double v = comp_nd_psa(b, c, in, out, psa);
    if (with_lamb) v += b->lamb[c] / HD_PI;
    return v;
}

/* tree_coords of v in both roles (0: -x, -y; 1: x, y), cut at the finest level of all
 * blocks: a leaf at depth + k <= that level is a function of them. */
int64_t hd_bsdf_vector_cell(const hd_bsdf *b, hd_vec3 v)
{
    int lev = -1;
    for (int c = 0; c < 4; c++) {
        const hd_bsdf_block *d = b->src[c];
        if (!d || !d->kind) continue;
        if (d->kind != 4 || d->tree.maxlev < 0 || d->tree.maxlev > 12) return -1;
        if (d->tree.maxlev > lev) lev = d->tree.maxlev;
    }
    v = unitv(v);
    if (lev < 0 || !(v.z != 0)) return -1;
    double s[4];
    tree_coords(4, v, v, s);
    int64_t key = v.z > 0, r = (int64_t)1 << lev;
    for (int i = 0; i < 4; i++) {
        int64_t k = (int64_t)(s[i] * (double)r);
        key = key << 13 | (k < r ? k : r - 1);
    }
    return key;
}

double hd_bsdf_eval_comp(const hd_bsdf *b, hd_bsdf_comp c, hd_vec3 in, hd_vec3 out, int with_lamb)
{
    return hd_bsdf_eval_comp_psa(b, c, in, out, with_lamb, NULL);
}

double hd_bsdf_eval(const hd_bsdf *b, hd_vec3 in, hd_vec3 out)
{
    int c = hd_bsdf_comp_of(in, out);
    if (c < 0) return 0;
    return hd_bsdf_eval_comp(b, (hd_bsdf_comp)c, in, out, 1);
}

/* ---- sampling distributions ("slices") ----
 * For component data d and a fixed vector on one of its roles (a = data
 * incident, b = data outgoing), the slice is the list of cells of the other
 * role with their values; each cell has a projected solid angle
 * (Klems: lambda; square cells: π w²).  An isotropic tree sampled on its
 * data-incident role (SL_RING) uses its symmetry: with b fixed, f(a, b)
 * depends on a's radius (tree dim 0) and on the angle ψ between b and -a
 * (b turned into the tree's frame lies on the circle of radius |b|, which
 * Shirley–Chiu maps onto the boundary of a square, ψ linear along each of
 * its four sides).  The cells crossed by those four axis-aligned planes of
 * the tree are the same for every |b| in one ring of finest cells, so the
 * distribution is exact with one slice per ring: the sides' interior parts
 * (fixed) plus the two end pieces of each side, whose length grows with
 * |b| across the ring's corner cells (a second cumulative sum, scaled per
 * query). */
enum { SL_KLEMS = 1, SL_CELLS, SL_RING };

typedef struct scell {
    union {
        double cdf;         /* cumulative within the group (SL_RING: while
                               building only) */
        struct {            /* SL_RING: Walker's alias table of the group: draw
                               k uniformly, keep it with probability
                               prob/2^32, else take alias (relative to the
                               group's first entry) */
            uint32_t prob;
            int32_t alias;
        };
    };
    float val, aval;        /* the value in the cell; the alias's */
    uint64_t geo, ageo;     /* the cell (cell_geo); the alias's: a sample
                               reads one 32-byte entry */
} scell;

/* Guide entry k of a group with total T and ng = n entries: the first
 * cell whose cdf exceeds T·k/ng (with its end, value and cell inline, so
 * that a draw landing in it reads one cache line) and the cell holding
 * T·(k+1)/ng.  The draw is the inverse of the cumulative sum (monotone in
 * the random number: stratified numbers stay stratified over the cells). */
typedef struct gentry {
    double cend;
    int32_t first, last;
    float val;
    uint32_t pad_;
    uint64_t geo;
} gentry;
_Static_assert(sizeof(scell) == 32 && sizeof(gentry) == 32, "32-byte entries: one cache line never splits one");

/* geometry of a square cell in units of the finest cells (res = 2^maxlev):
 * lower corner (ix, iy) and side 2^lw; SL_RING: ix along c0, iy along the
 * side's free coordinate u */
static inline uint64_t geo_make(double x0, double y0, double w, int res)
{
    uint64_t ix = (uint64_t)(x0 * res + 0.5), iy = (uint64_t)(y0 * res + 0.5);
    int lw = 0;
    while ((double)(1 << lw) < w * res - 0.5 && lw < 30) lw++;
    return ix | iy << 24 | (uint64_t)lw << 48;
}

static inline void geo_get(uint64_t g, double scale, double *x0, double *y0, double *w)
{
    *x0 = (double)(g & 0xffffff) * scale;
    *y0 = (double)(g >> 24 & 0xffffff) * scale;
    *w = (double)(1u << (g >> 48 & 31)) * scale;
}

typedef struct slice {
    uint64_t key;
    int kind, n;
    double total;           /* Σ value × projected solid angle */
    struct scell *c;        /* the cells: cumulative sums and the guide g,
                               or (SL_RING) alias entries */
    gentry *g;
    float *lut;             /* SL_CELLS: value per finest cell (lres²), or NULL */
    int lres;
    int nquery;             /* point queries so far (the table comes after 32) */
    int shared;             /* in the block's shared store: never changed */
    /* SL_RING: c[0, nm) the sides' interior pieces (cdf Σ val·A·Δd, with
     * A = Δ(r²)/2 of the leaf's radius range), c[nm, n) the end pieces
     * (cdf Σ val·A, restarting at 0), one alias table each; gb[k] the
     * first entry of group k: sides 0-3, then ends 4 + 2·side + (0 upper,
     * 1 lower); cent: an alias table of group 4 alone (ring 0: b = 0) */
    int nm, gb[13];
    scell *cent;
    double cmain, ccorn, ccent;     /* Σ of the interior, of the ends, of
                                       the centre column (group 4, ring 0) */
    double rb;              /* 2·ring/res: the interior's half length in d */
    double scale;           /* 1/res of the tree: cell_geo units */
    double wmin, wmax;      /* SL_CELLS: the sides of the finest and coarsest cells */
    size_t bytes;
} slice;

/* The distributions of a block shared by all threads: one table per role of
 * the fixed vector (fixa 0/1), indexed by the fixed cell (Klems bin, tree
 * cell, incident theta cell or ring of the outgoing vector).  A slice
 * is built once by whichever thread needs it first and published with a
 * compare-and-swap; it is never changed or freed before the BSDF.  Slices
 * are deterministic functions of their cell, so results do not depend on
 * which thread built them.  Memory is bounded by HD_BSDF_SHARED_MAX; beyond
 * it the per-thread caches take over (as before). */
#define HD_BSDF_SHARED_MAX ((size_t)256 << 20)
typedef struct hd_slice_store {
    _Atomic(slice *) *tab[2];
    size_t n[2];
    atomic_size_t used;
    /* 3D trees: the sums of every ring slice (ring_sums), made in one
     * traversal on first use, so that totals need no slice */
    _Atomic(double *) ring;
} hd_slice_store;

struct hd_bsdf_cache {
    const hd_bsdf *b;
    size_t max, used;
    int nslot;
    uint64_t *keys;
    slice **sl;
    int flush;              /* over budget: empty at the next query */
    /* the last two queries, most recent first (photon emission repeats the
     * same sun direction, between the queries of the photons' later hits) */
    int memo_ok, memo_mode[2], memo_mask[2], memo_n;
    hd_vec3 memo_g[2];
    struct qset *memo;
};

static void slice_free(slice *s);

static hd_slice_store *store_new(const hd_bsdf_block *d)
{
    size_t n[2];
    if (d->kind == 1) { n[0] = (size_t)d->outb.nbins; n[1] = (size_t)d->inb.nbins; }
    else if (d->kind == 4) n[0] = n[1] = (size_t)1 << (2 * d->tree.maxlev);
    else if (d->kind == 3) {
        n[0] = d->tree.maxlev > 0 ? (size_t)1 << (d->tree.maxlev - 1) : 1;   /* rings */
        n[1] = (size_t)1 << d->tree.maxlev;
    }
    else return NULL;
    hd_slice_store *st = hd_calloc(1, sizeof *st);
    if (!st) return NULL;
    atomic_init(&st->used, 0);
    atomic_init(&st->ring, NULL);
    for (int r = 0; r < 2; r++) {
        st->n[r] = n[r];
        st->tab[r] = hd_malloc_array(n[r] ? n[r] : 1, sizeof *st->tab[r]);
        if (!st->tab[r]) { free(st->tab[0]); free(st); return NULL; }
        for (size_t i = 0; i < n[r]; i++) atomic_init(&st->tab[r][i], NULL);
    }
    return st;
}

void hd_block_store_free(hd_bsdf_block *d)
{
    hd_slice_store *st = d->store;
    if (!st) return;
    for (int r = 0; r < 2; r++) {
        for (size_t i = 0; i < st->n[r]; i++) slice_free(atomic_load(&st->tab[r][i]));
        free(st->tab[r]);
    }
    free(atomic_load(&st->ring));
    free(st);
    d->store = NULL;
}

hd_bsdf_cache *hd_bsdf_cache_new(const hd_bsdf *b, size_t max_bytes)
{
    hd_bsdf_cache *c = hd_calloc(1, sizeof *c);
    if (!c) return NULL;
    c->b = b;
    c->max = max_bytes ? max_bytes : (size_t)64 << 20;
    c->nslot = 16384;
    c->keys = hd_calloc((size_t)c->nslot, sizeof *c->keys);
    c->sl = hd_calloc((size_t)c->nslot, sizeof *c->sl);
    if (!c->keys || !c->sl) { hd_bsdf_cache_free(c); return NULL; }
    return c;
}

static void slice_free(slice *s)
{
    if (!s) return;
    free(s->c);
    free(s->cent);
    free(s->g);
    free(s->lut);
    free(s);
}

void hd_bsdf_cache_free(hd_bsdf_cache *c)
{
    if (!c) return;
    if (c->sl) for (int i = 0; i < c->nslot; i++) slice_free(c->sl[i]);
    free(c->sl);
    free(c->keys);
    free(c->memo);
    free(c);
}

/* slice builder */
typedef struct sbuf { float *val, *cell; size_t n, cap; int fail; } sbuf;

static void sb_push(sbuf *sb, float x0, float y0, float w, float v)
{
    if (sb->n == sb->cap) {
        size_t nc = sb->cap ? 2 * sb->cap : 256;
        float *a = hd_realloc_array(sb->val, nc, sizeof *a), *c;
        if (!a) { sb->fail = 1; return; }
        sb->val = a;
        c = hd_realloc_array(sb->cell, nc * 3, sizeof *c);
        if (!c) { sb->fail = 1; return; }
        sb->cell = c;
        sb->cap = nc;
    }
    sb->val[sb->n] = v;
    sb->cell[3 * sb->n] = x0;
    sb->cell[3 * sb->n + 1] = y0;
    sb->cell[3 * sb->n + 2] = w;
    sb->n++;
}

/* Collect the cells of the free dims (fx, fy) of tree t at fixed coords cf
 * (used only at the fixed dims); box (or NULL: all) = {xlo, xhi, ylo, yhi}
 * leaves out the cells outside that rectangle of the free dims. */
static void collect_box(const hd_ttree *t, hd_tnode nd, const double *cf, int fixmask,
                        int fx, int fy, double x0, double y0, double w, const double *box, sbuf *sb)
{
    int D = t->dim;
    if (box && (x0 >= box[1] || x0 + w <= box[0] || y0 >= box[3] || y0 + w <= box[2])) return;
    if (nd.k < 0) {
        double c2[4];
        int base = 0;
        for (int d = 0; d < D; d++) {
            if (!(fixmask & (1 << d))) { c2[d] = 0; continue; }
            if (cf[d] >= 0.5) { base |= 1 << d; c2[d] = 2 * cf[d] - 1; }
            else c2[d] = 2 * cf[d];
        }
        for (int bx = 0; bx < 2; bx++)
            for (int by = 0; by < 2; by++)
                collect_box(t, t->node[nd.off + (uint32_t)(base | bx << fx | by << fy)], c2, fixmask,
                            fx, fy, x0 + bx * w / 2, y0 + by * w / 2, w / 2, box, sb);
        return;
    }
    int r = 1 << nd.k;
    size_t stride[4], s = 1, fixidx = 0;
    for (int d = D - 1; d >= 0; d--) { stride[d] = s; s *= (size_t)r; }
    for (int d = 0; d < D; d++) {
        if (!(fixmask & (1 << d))) continue;
        int i = (int)(cf[d] * r);
        if (i >= r) i = r - 1;
        fixidx += (size_t)i * stride[d];
    }
    const float *v = t->val + nd.off + fixidx;
    double cw = w / r;
    for (int ix = 0; ix < r; ix++)
        for (int iy = 0; iy < r; iy++) {
            float x = v[(size_t)ix * stride[fx] + (size_t)iy * stride[fy]];
            double cx = x0 + ix * cw, cy = y0 + iy * cw;
            if (box && (cx >= box[1] || cx + cw <= box[0] || cy >= box[3] || cy + cw <= box[2])) continue;
            if (x > 0) sb_push(sb, (float)cx, (float)cy, (float)cw, x);
        }
}

static void collect(const hd_ttree *t, hd_tnode nd, const double *cf, int fixmask, int fx, int fy,
                    double x0, double y0, double w, sbuf *sb)
{
    collect_box(t, nd, cf, fixmask, fx, fy, x0, y0, w, NULL, sb);
}

/* Mapping context of a component query. */
typedef struct qctx {
    const hd_bsdf_block *d;
    int c;                  /* component */
    int fixa;               /* the given vector plays the data-incident role */
    int side;               /* z sign of the sampled vector */
    double cp, sp;          /* 3D trees, fix a: rotation of the outgoing frame */
    uint64_t key;
    double fc[4];           /* representative fixed coordinates */
    int fbin;               /* Klems: fixed bin */
    /* 3D fix b (SL_RING): the ring, |b| in square units (d = 2s - 1), the
     * length of the sides' end pieces, b = 0, the unit vector of b.xy */
    int ring, centre;
    double rr, ell, bx, by;
    size_t sidx;            /* index into the block's shared store */
} qctx;

static int setup_q(const hd_bsdf *b, int c, hd_vec3 g, int mode, qctx *q)
{
    const hd_bsdf_block *d = b->src[c];
    memset(q, 0, sizeof *q);
    if (!d || !d->kind) return 0;
    q->d = d;
    q->c = c;
    q->fixa = (mode == HD_BSDF_FORWARD) ^ b->recip[c];
    q->side = mode == HD_BSDF_FORWARD ? out_side[c] : in_side[c];
    uint64_t id = (uint64_t)d->id << 62 | (uint64_t)q->fixa << 61;
    if (d->kind == 1) {
        q->fbin = q->fixa ? hd_klems_bin(&d->inb, hd_v3(-g.x, -g.y, fabs(g.z)))
                          : hd_klems_bin(&d->outb, hd_v3(g.x, g.y, fabs(g.z)));
        if (q->fbin < 0) return 0;
        q->key = id | (uint64_t)q->fbin;
        q->sidx = (size_t)q->fbin;
        return 1;
    }
    int res = 1 << d->tree.maxlev;
    double c4[4];
    if (d->kind == 4) {
        if (q->fixa) hd_disk2square(-g.x, -g.y, &c4[0], &c4[1]);
        else hd_disk2square(g.x, g.y, &c4[2], &c4[3]);
        int o = q->fixa ? 0 : 2;
        uint64_t ix = (uint64_t)(c4[o] * res), iy = (uint64_t)(c4[o + 1] * res);
        q->fc[o] = (ix + 0.5) / res;
        q->fc[o + 1] = (iy + 0.5) / res;
        q->key = id | ix << 28 | iy;
        q->sidx = (size_t)(ix * (uint64_t)res + iy);
        return 1;
    }
    if (q->fixa) {
        tree_coords(3, g, hd_v3(0, 0, 1), c4);
        uint64_t ix = (uint64_t)(c4[0] * res);
        q->fc[0] = (ix + 0.5) / res;
        double ra = sqrt(g.x * g.x + g.y * g.y);
        q->cp = 1; q->sp = 0;
        if (ra > 1e-12) { q->cp = -g.x / ra; q->sp = -g.y / ra; }
        q->key = id | ix;
        q->sidx = (size_t)ix;
        return 1;
    }
    /* 3D, given vector on the outgoing role: the ring of finest cells its
     * Shirley–Chiu square holds (r in d = 2s - 1 units) */
    double sx, sy;
    hd_disk2square(g.x, g.y, &sx, &sy);
    double rr = fmax(fabs(2 * sx - 1), fabs(2 * sy - 1)), gr = sqrt(g.x * g.x + g.y * g.y);
    int nring = res >= 2 ? res / 2 : 1;
    int m = (int)(rr * 0.5 * res);
    if (m >= nring) m = nring - 1;
    if (m < 0) m = 0;
    q->ring = m;
    q->rr = rr;
    q->ell = fmin(fmax(rr - 2.0 * m / res, 0), 2.0 / res);
    q->centre = !(rr > 0);
    q->bx = 1; q->by = 0;
    if (gr > 0) { q->bx = g.x / gr; q->by = g.y / gr; }
    q->key = id | (uint64_t)m;
    q->sidx = (size_t)m;
    return 1;
}

/* The guide of cells c[0, n) (cdf cumulative from 0): max(n, 1) entries */
static gentry *guide_build(const scell *c, int n)
{
    int ng = n > 0 ? n : 1;
    gentry *g = hd_big_alloc((size_t)ng, sizeof *g, 0);   /* aligned: entries never split */
    if (!g) return NULL;
    memset(g, 0, (size_t)ng * sizeof *g);
    if (n <= 0) return g;
    double T = c[n - 1].cdf;
    for (int k = 0, i = 0; k < ng; k++) {
        double x = T * k / ng, x1 = T * (k + 1) / ng;
        while (i < n - 1 && c[i].cdf <= x) i++;
        int j = i;
        while (j < n - 1 && c[j].cdf <= x1) j++;
        g[k] = (gentry){c[i].cdf, i, j, c[i].val, 0, c[i].geo};
    }
    return g;
}

/* The cell of c[0, n) (guide g, total T) holding x in [0, T): the first
 * with cdf > x, its value and cell */
static inline int guide_pick(const scell *c, const gentry *g, int n, double T, double x, float *val,
                             uint64_t *geo)
{
    int ng = n > 0 ? n : 1;
    if (!(x < T)) x = T * (1 - 1e-12);
    if (x < 0) x = 0;
    int k = (int)(x / T * ng);
    if (k >= ng) k = ng - 1;
    if (k < 0) k = 0;
    /* the bucket exactly as guide_build computed its bounds */
    while (k > 0 && T * k / ng > x) k--;
    while (k < ng - 1 && T * (k + 1) / ng <= x) k++;
    const gentry *e = g + k;
    if (x < e->cend) { *val = e->val; *geo = e->geo; return e->first; }
    int lo = e->first + 1, hi = e->last;
    if (hi > n - 1) hi = n - 1;
    if (lo > hi) lo = hi;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (c[mid].cdf > x) hi = mid; else lo = mid + 1;
    }
    *val = c[lo].val;
    *geo = c[lo].geo;
    return lo;
}

/* Turn the cumulative sums c[0, n).cdf of one group into Walker's alias
 * table (Vose's construction): O(1) sampling that touches one or two
 * cells, whatever the slice's size.  0 when out of memory. */
static int alias_build(scell *c, int n)
{
    if (n <= 0) return 1;
    double *p = hd_malloc_array((size_t)n, sizeof *p);
    int *sm = hd_malloc_array((size_t)n, sizeof *sm), *lg = hd_malloc_array((size_t)n, sizeof *lg);
    if (!p || !sm || !lg) { free(p); free(sm); free(lg); return 0; }
    double W = c[n - 1].cdf, prev = 0;
    for (int i = 0; i < n; i++) {
        double w = c[i].cdf - prev;
        prev = c[i].cdf;
        p[i] = W > 0 ? w * n / W : 1;
    }
    int ns = 0, nl = 0;
    for (int i = 0; i < n; i++) {
        if (p[i] < 1) sm[ns++] = i; else lg[nl++] = i;
    }
    while (ns && nl) {
        int a = sm[--ns], l = lg[nl - 1];
        c[a].prob = (uint32_t)(p[a] * 4294967296.0);
        c[a].alias = l;
        p[l] -= 1 - p[a];
        if (p[l] < 1) { nl--; sm[ns++] = l; }
    }
    /* the rest (and rounding leftovers) keep themselves */
    while (nl) { int l = lg[--nl]; c[l].prob = UINT32_MAX; c[l].alias = l; }
    while (ns) { int a = sm[--ns]; c[a].prob = UINT32_MAX; c[a].alias = a; }
    for (int i = 0; i < n; i++) {
        c[i].aval = c[c[i].alias].val;
        c[i].ageo = c[c[i].alias].geo;
    }
    free(p); free(sm); free(lg);
    return 1;
}

/* the entry of an alias table c[0, n) for y uniform in [0, 1), with its
 * value and geometry (read from the one entry drawn) */
static inline int alias_pick(const scell *c, int n, double y, float *val, uint64_t *geo)
{
    double z = y * n;
    int k = (int)z;
    if (k >= n) k = n - 1;
    if (k < 0) k = 0;
    const scell *e = c + k;
    if ((z - k) * 4294967296.0 < e->prob) { *val = e->val; *geo = e->geo; return k; }
    *val = e->aval;
    *geo = e->ageo;
    return e->alias;
}

/* n entries (uninitialised), each within one cache line (hd_big_alloc
 * aligns to 64 bytes), refused above the allocation limit */
static scell *scell_alloc(size_t n)
{
    return hd_big_alloc(n ? n : 1, sizeof(scell), 0);
}

/* SL_RING: the leaves of an isotropic tree crossed by the four sides of
 * ring q->ring (planes c1 = 0.5 ± (m+½)/res and c2 = the same; u the other
 * of c1, c2, d = 2u - 1), with c0 < 0.5 (|a| = 1 - 2·c0), split into the
 * interior |d| ≤ 2m/res and the end pieces in the corner cells. */
static int build_ring(const qctx *q, slice *s)
{
    const hd_ttree *t = &q->d->tree;
    int res = 1 << t->maxlev, m = q->ring;
    double B = 2.0 * m / res, B1 = 2.0 * (m + 1) / res;
    sbuf grp[12];
    memset(grp, 0, sizeof grp);
    int fail = 0;
    for (int e = 0; e < 4 && !fail; e++) {
        int fd = e % 2 ? 2 : 1, ud = 3 - fd;            /* sides: c1 hi, c2 hi, c1 lo, c2 lo */
        double fc[4] = {0, 0, 0, 0};
        fc[fd] = e < 2 ? 0.5 + (m + 0.5) / res : 0.5 - (m + 0.5) / res;
        if (fc[fd] >= 1) fc[fd] = 1 - 1e-12;
        if (fc[fd] < 0) fc[fd] = 0;
        sbuf sb = {0};
        /* c0 < 0.5, u within the ring's corner cells */
        double box[4] = {0, 0.5, 0.5 - (m + 1.0) / res, 0.5 + (m + 1.0) / res};
        collect_box(t, t->root, fc, 1 << fd, 0, ud, 0, 0, 1, box, &sb);
        fail |= sb.fail;
        for (size_t k = 0; k < sb.n && !fail; k++) {
            float c0 = sb.cell[3 * k], w = sb.cell[3 * k + 2];
            if (c0 >= 0.5f) continue;
            float d0 = 2 * sb.cell[3 * k + 1] - 1;     /* exact: dyadic */
            double d1 = d0 + 2.0 * w;
            if (fmin(d1, B) > fmax(d0, -B)) sb_push(&grp[e], c0, d0, w, sb.val[k]);
            if (d1 > B && d0 < B1) sb_push(&grp[4 + 2 * e], c0, d0, w, sb.val[k]);
            if (d0 < -B && d1 > -B1) sb_push(&grp[5 + 2 * e], c0, d0, w, sb.val[k]);
        }
        free(sb.val);
        free(sb.cell);
    }
    size_t n = 0;
    for (int g = 0; g < 12; g++) { fail |= grp[g].fail; n += grp[g].n; }
    if (!fail && n > (size_t)INT32_MAX) fail = 1;
    if (!fail) s->c = scell_alloc(n);
    if (fail || !s->c) {
        for (int g = 0; g < 12; g++) { free(grp[g].val); free(grp[g].cell); }
        return 0;
    }
    s->kind = SL_RING;
    s->n = (int)n;
    s->rb = B;
    double acc = 0;
    int k = 0;
    for (int g = 0; g < 12; g++) {
        if (g == 4) { s->nm = k; s->cmain = acc; acc = 0; }
        s->gb[g] = k;
        for (size_t i = 0; i < grp[g].n; i++, k++) {
            const float *cl = grp[g].cell + 3 * i;
            double c0 = cl[0], w = cl[2], d0 = cl[1], v = grp[g].val[i];
            double rlo = 1 - 2 * fmin(c0 + w, 0.5), rhi = 1 - 2 * c0;
            double a = v * 0.5 * (rhi * rhi - rlo * rlo);
            if (g < 4) a *= fmin(d0 + 2 * w, B) - fmax(d0, -B);
            acc += a;
            s->c[k] = (scell){{acc}, (float)v, 0, geo_make(c0, 0.5 * (d0 + 1), w, res), 0};
        }
        if (g == 4) s->ccent = acc;
        free(grp[g].val);
        free(grp[g].cell);
    }
    s->gb[12] = k;
    s->ccorn = acc;
    s->total = s->cmain + s->ccorn;
    return 1;
}

/* The sums build_ring gives each ring m of block d's tree, without
 * building the rings: R[3m] the interior (cmain), R[3m + 1] the ends
 * (ccorn), R[3m + 2] group 4 (ccent).  One traversal of the used half
 * c0 < 0.5: a leaf cell is crossed by the side planes of the rings whose
 * finest plane cell lies within its c1 or c2 range (the side c1 or c2 =
 * 0.5 ± (m + ½)/res) and counts where its other coordinate u lies within
 * the ring's corner cells, as collect_box's box in build_ring. */
static void ring_walk(const hd_ttree *t, hd_tnode nd, const double lo[3], double s, int res, double *R)
{
    if (nd.k < 0) {
        for (int n = 0; n < 8; n++) {
            double l2[3];
            for (int d = 0; d < 3; d++) l2[d] = lo[d] + ((n >> d & 1) ? s / 2 : 0);
            if (l2[0] < 0.5) ring_walk(t, t->node[nd.off + (uint32_t)n], l2, s / 2, res, R);
        }
        return;
    }
    int r = 1 << nd.k, h = res / 2;
    double cs = s / r;
    long nf = (long)(cs * res + 0.5);
    if (nf < 1) nf = 1;
    for (int i0 = 0; i0 < r; i0++) {
        double x0 = lo[0] + i0 * cs;
        if (x0 >= 0.5) break;
        double rhi = 1 - 2 * x0, rlo = 1 - 2 * fmin(x0 + cs, 0.5), ar = 0.5 * (rhi * rhi - rlo * rlo);
        for (int i1 = 0; i1 < r; i1++)
            for (int i2 = 0; i2 < r; i2++) {
                float v = t->val[nd.off + ((size_t)i0 * (size_t)r + (size_t)i1) * (size_t)r + (size_t)i2];
                if (!(v > 0)) continue;
                double A = v * ar, p[3] = {x0, lo[1] + i1 * cs, lo[2] + i2 * cs};
                for (int fd = 1; fd <= 2; fd++) {
                    double u0 = p[3 - fd], d0 = 2 * u0 - 1, d1 = d0 + 2 * cs;
                    long P0 = (long)(p[fd] * res + 0.5);
                    for (long I = P0; I < P0 + nf; I++)
                        for (int hi = 1; hi >= 0; hi--) {
                            /* res 1: both planes lie in the one cell */
                            if (hi ? I < h : (I >= h && res > 1)) continue;
                            int m = hi ? (int)(I - h) : res > 1 ? (int)(h - 1 - I) : 0;
                            if (u0 >= 0.5 + (m + 1.0) / res || u0 + cs <= 0.5 - (m + 1.0) / res) continue;
                            double B = 2.0 * m / res, B1 = 2.0 * (m + 1) / res;
                            double a = fmax(d0, -B), b = fmin(d1, B);
                            if (b > a) R[3 * m] += A * (b - a);
                            if (d1 > B && d0 < B1) {
                                R[3 * m + 1] += A;
                                if (fd == 1 && hi) R[3 * m + 2] += A;
                            }
                            if (d0 < -B && d1 > -B1) R[3 * m + 1] += A;
                        }
                }
            }
    }
}

/* block d's ring sums (ring_walk), made by the first thread that needs
 * them and shared; NULL without a store or memory */
static const double *ring_sums(const hd_bsdf_block *d)
{
    hd_slice_store *st = d->store;
    if (!st || d->kind != 3) return NULL;
    double *R = atomic_load_explicit(&st->ring, memory_order_acquire);
    if (R) return R;
    int res = 1 << d->tree.maxlev, nring = res >= 2 ? res / 2 : 1;
    R = hd_calloc((size_t)nring * 3, sizeof *R);
    if (!R) return NULL;
    double lo[3] = {0, 0, 0};
    ring_walk(&d->tree, d->tree.root, lo, 1.0, res, R);
    double *expect = NULL;
    if (atomic_compare_exchange_strong_explicit(&st->ring, &expect, R, memory_order_acq_rel,
                                                memory_order_acquire))
        return R;
    free(R);
    return expect;
}

/* the ring query q's total from the sums (as ring_total of its slice) */
static double ring_total_sums(const qctx *q, const double *R)
{
    const double *e = R + 3 * (size_t)q->ring;
    if (q->centre) return 2 * HD_PI * e[2];
    return HD_PI / 4 / q->rr * (e[0] + q->ell * e[1]);
}

/* Largest relative difference between ring_sums and the sums of the ring
 * slices built one by one (all rings of a 3D block; tests) */
double hd_block_ring_sums_check(const hd_bsdf_block *d)
{
    const double *R = d->kind == 3 ? ring_sums(d) : NULL;
    if (!R) return -1;
    int res = 1 << d->tree.maxlev, nring = res >= 2 ? res / 2 : 1;
    double worst = 0;
    for (int m = 0; m < nring; m++) {
        qctx q;
        memset(&q, 0, sizeof q);
        q.d = d;
        q.ring = m;
        slice s;
        memset(&s, 0, sizeof s);
        if (!build_ring(&q, &s)) return -1;
        double got[3] = {s.cmain, s.ccorn, s.ccent}, sc = fabs(s.cmain) + fabs(s.ccorn) + 1e-300;
        for (int k = 0; k < 3; k++) {
            if (k == 2 && m) break;
            double e = fabs(got[k] - R[3 * m + k]) / sc;
            if (e > worst) worst = e;
        }
        free(s.c);
    }
    return worst;
}

/* ∫ f |cos| over the sampled role of the ring slice s for query q */
static double ring_total(const qctx *q, const slice *s)
{
    if (q->centre) return 2 * HD_PI * s->ccent;
    return HD_PI / 4 / q->rr * (s->cmain + q->ell * s->ccorn);
}

/* the vector a of SL_RING entry k at (u2, u3), kept off the cell's edges */
static hd_vec3 ring_dir(const qctx *q, const slice *s, int k, uint64_t geo, double u2, double u3)
{
    double c0, u0, w;
    geo_get(geo, s->scale, &c0, &u0, &w);
    u2 = 1e-9 + u2 * (1 - 2e-9);
    u3 = 1e-9 + u3 * (1 - 2e-9);
    double rlo = 1 - 2 * fmin(c0 + w, 0.5), rhi = 1 - 2 * c0;
    double r2 = rlo * rlo + u2 * (rhi * rhi - rlo * rlo), ra = sqrt(r2);
    double psi;
    if (q->centre) psi = 2 * HD_PI * u3;
    else {
        int g = 0;
        while (g < 11 && k >= s->gb[g + 1]) g++;
        int e = g < 4 ? g : (g - 4) / 2;
        double dd;
        if (g < 4) {
            double d0 = 2 * u0 - 1, lo = fmax(d0, -s->rb), hi = fmin(d0 + 2 * w, s->rb);
            dd = lo + u3 * (hi - lo);
        } else {
            dd = s->rb + u3 * q->ell;
            if ((g - 4) % 2) dd = -dd;
        }
        double tt = dd / q->rr;
        if (tt > 1) tt = 1;
        if (tt < -1) tt = -1;
        psi = e == 0 ? HD_PI / 4 * tt : e == 1 ? HD_PI / 2 - HD_PI / 4 * tt
            : e == 2 ? HD_PI - HD_PI / 4 * tt : 1.5 * HD_PI + HD_PI / 4 * tt;
    }
    /* -a's azimuth = b's azimuth - psi */
    double cs = cos(psi), sn = sin(psi);
    double ux = q->bx * cs + q->by * sn, uy = q->by * cs - q->bx * sn;
    double z2 = 1 - r2;
    return hd_v3(-ra * ux, -ra * uy, q->side * sqrt(z2 > 0 ? z2 : 0));
}

static slice *build_slice(const qctx *q)
{
    const hd_bsdf_block *d = q->d;
    slice *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    s->key = q->key;
    if (d->kind >= 3) s->scale = 1.0 / (1 << d->tree.maxlev);
    if (d->kind == 1) {
        const hd_klems_basis *fb = q->fixa ? &d->outb : &d->inb;
        size_t ninc = (size_t)d->inb.nbins;
        s->kind = SL_KLEMS;
        s->n = fb->nbins;
        s->c = scell_alloc((size_t)s->n);
        if (!s->c) { slice_free(s); return NULL; }
        double acc = 0;
        for (int k = 0; k < s->n; k++) {
            float v = q->fixa ? d->mtx[(size_t)k * ninc + (size_t)q->fbin]
                              : d->mtx[(size_t)q->fbin * ninc + (size_t)k];
            acc += v * hd_klems_lambda(fb, k);
            s->c[k] = (scell){{acc}, v, 0, 0, 0};
        }
        s->total = acc;
    } else if (d->kind == 4 || q->fixa) {
        sbuf sb = {0};
        int fixmask = d->kind == 4 ? (q->fixa ? 3 : 12) : 1;
        int fx = d->kind == 4 ? (q->fixa ? 2 : 0) : 1, fy = fx + 1;
        collect(&d->tree, d->tree.root, q->fc, fixmask, fx, fy, 0, 0, 1, &sb);
        if (sb.fail) { free(sb.val); free(sb.cell); slice_free(s); return NULL; }
        s->kind = SL_CELLS;
        s->n = (int)sb.n;
        s->c = scell_alloc(sb.n);
        if (!s->c) { free(sb.val); free(sb.cell); slice_free(s); return NULL; }
        double acc = 0;
        int res = 1 << d->tree.maxlev;
        s->wmin = 2;
        for (size_t k = 0; k < sb.n; k++) {
            double w = sb.cell[3 * k + 2];
            if (w < s->wmin) s->wmin = w;
            if (w > s->wmax) s->wmax = w;
            acc += sb.val[k] * HD_PI * w * w;
            s->c[k] = (scell){{acc}, sb.val[k], 0, geo_make(sb.cell[3 * k], sb.cell[3 * k + 1], w, res), 0};
        }
        free(sb.val);
        free(sb.cell);
        s->total = acc;
    } else if (!build_ring(q, s)) {
        slice_free(s);
        return NULL;
    } else {
        /* the totals every query uses before the slice exists (qset_init) */
        const double *R = ring_sums(d);
        if (R) {
            const double *e = R + 3 * (size_t)q->ring;
            s->cmain = e[0];
            s->ccorn = e[1];
            s->ccent = e[2];
            s->total = e[0] + e[1];
        }
    }
    /* alias tables: O(1) sampling */
    int nm = s->kind == SL_RING ? s->nm : s->n;
    if (s->kind == SL_RING && q->ring == 0 && s->gb[5] > s->gb[4]) {
        int n4 = s->gb[5] - s->gb[4];
        if (!(s->cent = scell_alloc((size_t)n4))) { slice_free(s); return NULL; }
        memcpy(s->cent, s->c + s->gb[4], (size_t)n4 * sizeof *s->cent);
        if (!alias_build(s->cent, n4)) { slice_free(s); return NULL; }
    }
    if (s->kind != SL_RING) {
        if (!(s->g = guide_build(s->c, s->n))) { slice_free(s); return NULL; }
    } else if (!alias_build(s->c, nm) || !alias_build(s->c + nm, s->n - nm)) { slice_free(s); return NULL; }
    s->bytes = sizeof *s + (size_t)s->n * sizeof(scell) + (s->cent ? (size_t)(s->gb[5] - s->gb[4]) * sizeof(scell) : 0) +
               (s->g ? (size_t)s->n * sizeof(gentry) : 0);
    if (s->kind == SL_CELLS && d->tree.maxlev <= 8)     /* room for a lookup table */
        s->bytes += ((size_t)1 << (2 * d->tree.maxlev)) * sizeof(float);
    return s;
}

/* The shared slice of q: found, or built and published (NULL with *built
 * set to a fresh slice when the store is full or absent, so that the
 * caller keeps it elsewhere). */
static const slice *shared_slice(const qctx *q, slice **built)
{
    *built = NULL;
    hd_slice_store *st = q->d->store;
    if (!st || q->sidx >= st->n[q->fixa]) return NULL;
    _Atomic(slice *) *cell = &st->tab[q->fixa][q->sidx];
    slice *s = atomic_load_explicit(cell, memory_order_acquire);
    if (s) return s;
    /* full (slices are never removed): no slice is built here only to be
     * dropped when the caller's cache already holds it */
    if (atomic_load_explicit(&st->used, memory_order_relaxed) >= HD_BSDF_SHARED_MAX) return NULL;
    s = build_slice(q);
    if (!s) return NULL;
    size_t prev = atomic_fetch_add(&st->used, s->bytes);
    if (prev + s->bytes > HD_BSDF_SHARED_MAX) {
        atomic_fetch_sub(&st->used, s->bytes);
        *built = s;
        return NULL;
    }
    s->shared = 1;
    slice *expect = NULL;
    if (atomic_compare_exchange_strong_explicit(cell, &expect, s, memory_order_acq_rel, memory_order_acquire))
        return s;
    atomic_fetch_sub(&st->used, s->bytes);      /* another thread won */
    slice_free(s);
    return expect;
}

static void cache_flush(hd_bsdf_cache *cache)
{
    for (int k = 0; k < cache->nslot; k++) { slice_free(cache->sl[k]); cache->sl[k] = NULL; }
    cache->used = 0;
    cache->flush = 0;
    cache->memo_ok = 0;
}

/* A slice from the cache, or a temporary one (*tmp, freed by the caller)
 * when its slot holds `pinned` (a slice in use by the same query).  Over
 * the memory budget the cache is emptied at the start of the next query,
 * never while a query holds pointers into it. */
static const slice *get_slice(hd_bsdf_cache *cache, const qctx *q, slice **tmp, const slice *pinned)
{
    *tmp = NULL;
    slice *s;
    const slice *sh = shared_slice(q, &s);
    if (sh) return sh;
    if (!cache) return *tmp = s ? s : build_slice(q);
    uint64_t h = hd_hash64(q->key, 0x5bd1e995u);
    int i = (int)(h % (uint64_t)cache->nslot);
    if (cache->sl[i] && cache->keys[i] == q->key) { slice_free(s); return cache->sl[i]; }
    if (!s) s = build_slice(q);
    if (!s) return NULL;
    if (cache->sl[i] && cache->sl[i] == pinned) return *tmp = s;
    if (cache->sl[i]) {
        cache->used -= cache->sl[i]->bytes;
        slice_free(cache->sl[i]);
        cache->memo_ok = 0;
    }
    cache->sl[i] = s;
    cache->keys[i] = q->key;
    cache->used += s->bytes;
    if (cache->used > cache->max) cache->flush = 1;
    return s;
}

/* the sampled vector for slice cell k at (u2, u3) */
static hd_vec3 cell_dir(const qctx *q, const slice *s, int k, uint64_t geo, double u2, double u3)
{
    const hd_bsdf_block *d = q->d;
    double x, y;
    if (s->kind == SL_KLEMS) {
        const hd_klems_basis *fb = q->fixa ? &d->outb : &d->inb;
        hd_vec3 v = hd_klems_dir(fb, k, u2, u3);
        return q->fixa ? hd_v3(v.x, v.y, q->side * v.z) : hd_v3(-v.x, -v.y, q->side * v.z);
    }
    if (s->kind == SL_RING) return ring_dir(q, s, k, geo, u2, u3);
    double x0, y0, w;
    geo_get(geo, s->scale, &x0, &y0, &w);
    hd_square2disk(x0 + u2 * w, y0 + u3 * w, &x, &y);
    double z2 = 1 - x * x - y * y, z = q->side * sqrt(z2 > 0 ? z2 : 0);
    if (d->kind == 3 && q->fixa)
        return hd_v3(x * q->cp - y * q->sp, x * q->sp + y * q->cp, z);
    if (q->fixa && d->kind == 4) return hd_v3(x, y, z);
    return hd_v3(-x, -y, z);
}

/* Finest-cell lookup table for point queries (Lambertian samples, pdf
 * queries), built once a slice has served enough of them: the slice
 * belongs to one thread's cache (or is temporary), so this is safe. */
static void slice_build_lut(slice *s, const hd_bsdf_block *d)
{
    if (s->kind != SL_CELLS || d->tree.maxlev > 8 || s->lut) return;
    int lr = 1 << d->tree.maxlev;
    s->lut = calloc((size_t)lr * (size_t)lr, sizeof *s->lut);
    if (!s->lut) return;
    s->lres = lr;
    for (int k = 0; k < s->n; k++) {
        uint64_t g = s->c[k].geo;
        int x0 = (int)(g & 0xffffff), y0 = (int)(g >> 24 & 0xffffff), w = 1 << (g >> 48 & 31);
        for (int x = x0; x < x0 + w && x < lr; x++)
            for (int y = y0; y < y0 + w && y < lr; y++) s->lut[(size_t)x * lr + y] = s->c[k].val;
    }
}

/* value of the slice's distribution at a vector `v` of the free role */
static double slice_value(const hd_bsdf *b, const qctx *q, const slice *s, hd_vec3 g, hd_vec3 v,
                          int mode)
{
    if (!s->lut && !s->shared && ++((slice *)s)->nquery > 32) slice_build_lut((slice *)s, q->d);
    if (s->lut) {
        double x = v.x, y = v.y, sx, sy;
        if (q->d->kind == 3) { x = v.x * q->cp + v.y * q->sp; y = -v.x * q->sp + v.y * q->cp; }
        else if (!q->fixa) { x = -x; y = -y; }
        hd_disk2square(x, y, &sx, &sy);
        int ix = (int)(sx * s->lres), iy = (int)(sy * s->lres);
        if (ix >= s->lres) ix = s->lres - 1;
        if (iy >= s->lres) iy = s->lres - 1;
        return s->lut[(size_t)ix * s->lres + iy];
    }
    return mode == HD_BSDF_FORWARD ? comp_nd(b, q->c, g, v) : comp_nd(b, q->c, v, g);
}

/* components for (given, mode): [0] reflection, [1] transmission */
static void comps_for(hd_vec3 g, int mode, int c[2])
{
    if (mode == HD_BSDF_FORWARD) {
        c[0] = g.z > 0 ? HD_BSDF_RF : HD_BSDF_RB;
        c[1] = g.z > 0 ? HD_BSDF_TF : HD_BSDF_TB;
    } else {
        c[0] = g.z > 0 ? HD_BSDF_RF : HD_BSDF_RB;
        c[1] = g.z > 0 ? HD_BSDF_TB : HD_BSDF_TF;
    }
}

typedef struct qset {
    int c[2];
    qctx q[2];
    const slice *s[2];
    slice *tmp[2];
    int lazy[2];            /* ring query: total from ring_sums, the slice
                               fetched only when a draw needs it (qset_slice) */
    double w[4];            /* R diffuse, R directional, T diffuse, T directional */
    double total;
} qset;

static int qset_init(const hd_bsdf *b, hd_bsdf_cache *cache, hd_vec3 g, int mode, int mask, qset *Q)
{
    int nm = cache && cache->memo_ok && !cache->flush ? cache->memo_n : 0;
    for (int i = 0; i < nm; i++)
        if (cache->memo_mode[i] == mode && cache->memo_mask[i] == mask && cache->memo_g[i].x == g.x &&
            cache->memo_g[i].y == g.y && cache->memo_g[i].z == g.z) {
            *Q = cache->memo[i];
            return 1;
        }
    memset(Q, 0, sizeof *Q);
    if (!(g.z != 0) || !isfinite(g.z)) return 0;
    comps_for(g, mode, Q->c);
    if (cache && cache->flush) cache_flush(cache);
    /* the last query's slices serve again when the given vector falls in the
     * same fixed cells (photons of one sun: nearly one direction): a cell slice
     * (SL_CELLS, Klems) is a function of its key alone and its total is the
     * slice's, so only the mapping (qctx) is new; ring slices, whose totals
     * depend on the vector, and lazy queries take the full path */
    for (int j = 0; j < 2; j++) {
        if (!(mask & (j ? HD_BSDF_TRANS : HD_BSDF_REFL))) continue;
        int c = Q->c[j];
        Q->w[2 * j] = b->lamb[c];
        if (setup_q(b, c, g, mode, &Q->q[j])) {
            const qset *M = NULL;
            for (int i = 0; i < nm && !M; i++) {
                const qset *m = &cache->memo[i];
                if (cache->memo_mode[i] == mode && cache->memo_mask[i] == mask && m->c[j] == c && m->s[j] &&
                    !m->lazy[j] && m->s[j]->kind != SL_RING && m->q[j].d == Q->q[j].d && m->q[j].key == Q->q[j].key)
                    M = m;
            }
            if (M) {
                Q->s[j] = M->s[j];
                Q->w[2 * j + 1] = M->w[2 * j + 1];
                continue;
            }
            const double *R = Q->q[j].d->kind == 3 && !Q->q[j].fixa ? ring_sums(Q->q[j].d) : NULL;
            if (R) {
                Q->lazy[j] = 1;
                Q->w[2 * j + 1] = ring_total_sums(&Q->q[j], R);
                continue;
            }
            Q->s[j] = get_slice(cache, &Q->q[j], &Q->tmp[j], j ? Q->s[0] : NULL);
            if (Q->s[j])
                Q->w[2 * j + 1] = Q->s[j]->kind == SL_RING ? ring_total(&Q->q[j], Q->s[j]) : Q->s[j]->total;
        }
    }
    Q->total = Q->w[0] + Q->w[1] + Q->w[2] + Q->w[3];
    if (cache && !Q->tmp[0] && !Q->tmp[1]) {
        if (!cache->memo) cache->memo = malloc(2 * sizeof *cache->memo);
        if (cache->memo) {
            if (!cache->memo_ok) cache->memo_n = 0;
            if (cache->memo_n) {   /* the previous one moves to the second place */
                cache->memo[1] = cache->memo[0];
                cache->memo_g[1] = cache->memo_g[0];
                cache->memo_mode[1] = cache->memo_mode[0];
                cache->memo_mask[1] = cache->memo_mask[0];
            }
            cache->memo[0] = *Q;
            cache->memo_g[0] = g;
            cache->memo_mode[0] = mode;
            cache->memo_mask[0] = mask;
            cache->memo_n = cache->memo_n ? 2 : 1;
            cache->memo_ok = 1;
        }
    }
    return 1;
}

/* the slice of component j of Q (fetched now if lazy), NULL without memory */
static const slice *qset_slice(hd_bsdf_cache *cache, qset *Q, int j)
{
    if (!Q->s[j] && Q->lazy[j]) Q->s[j] = get_slice(cache, &Q->q[j], &Q->tmp[j], Q->s[1 - j]);
    return Q->s[j];
}

static void qset_done(qset *Q)
{
    slice_free(Q->tmp[0]);
    slice_free(Q->tmp[1]);
}

/* density (per sr) of the sampler at v, with f(v) returned in *fval */
static double qset_pdf(const hd_bsdf *b, const qset *Q, hd_vec3 g, hd_vec3 v, int mode, double *fval)
{
    if (fval) *fval = 0;
    if (!(Q->total > 0)) return 0;
    int j = (v.z > 0) == (g.z > 0) ? 0 : 1;
    int c = Q->c[j];
    if (!Q->w[2 * j] && !Q->s[j] && !Q->lazy[j]) return 0;
    double lam = b->lamb[c] / HD_PI, dv = 0, fv = 0;
    if (Q->s[j]) dv = slice_value(b, &Q->q[j], Q->s[j], g, v, mode);
    else if (Q->lazy[j]) dv = mode == HD_BSDF_FORWARD ? comp_nd(b, c, g, v) : comp_nd(b, c, v, g);
    fv = dv;
    if (fval) *fval = fv + (Q->w[2 * j] > 0 ? lam : 0);
    return ((Q->w[2 * j] > 0 ? lam : 0) + dv) * fabs(v.z) / Q->total;
}

/* ---- -ss below 1: the point inside the cell as Radiance places it ----
 * Radiance's BSDF library turns the one random number of a draw into the
 * point inside the chosen cell along a 2D Hilbert curve (the Klems patch:
 * the number's place inside the patch's share of the cumulative sum, as a
 * point of the unit square, radial in cos² and azimuthal; the tree: its
 * cells ordered along the curve over the sampled square, the number's
 * place inside the cell's share giving the point of the curve's stretch
 * through that cell).  A narrowed number (-ss below 1) then keeps its point
 * near the middle of the curve, not only its cell.  The curve's orientation
 * is Radiance's (the first step along the first coordinate at every order). */

/* the point (x, y) of index d on the Hilbert curve over a 2^bits square */
static void hilbert_point(int bits, uint64_t d, uint64_t *x, uint64_t *y)
{
    uint64_t a = 0, c = 0, n = (uint64_t)1 << bits;
    for (uint64_t s = 1; s < n; s <<= 1) {
        uint64_t rx = 1 & (d >> 1), ry = 1 & (d ^ rx);
        if (!ry) {
            if (rx) { a = s - 1 - a; c = s - 1 - c; }
            uint64_t t = a; a = c; c = t;
        }
        a += s * rx;
        c += s * ry;
        d >>= 2;
    }
    *x = c;     /* the first coordinate moves first */
    *y = a;
}

/* the index on that curve of the point (x, y) */
static uint64_t hilbert_index(int bits, uint64_t x, uint64_t y)
{
    uint64_t n = (uint64_t)1 << bits, d = 0, a = y, c = x;
    for (uint64_t s = n >> 1; s > 0; s >>= 1) {
        uint64_t rx = (a & s) ? 1 : 0, ry = (c & s) ? 1 : 0;
        d += s * s * ((3 * rx) ^ ry);
        if (!ry) {
            if (rx) { a = n - 1 - a; c = n - 1 - c; }
            uint64_t t = a; a = c; c = t;
        }
    }
    return d;
}

/* r in [0, 1) as a point of the unit square along the curve (31 bits a
 * side), u2, u3 placing it inside its finest step */
static void hilbert_square(double r, double u2, double u3, double *x, double *y)
{
    if (!(r >= 0)) r = 0;
    if (r >= 1) r = 1 - 1e-15;
    uint64_t ix, iy;
    hilbert_point(31, (uint64_t)(r * 4611686018427387904.0), &ix, &iy);
    *x = ((double)ix + u2) / 2147483648.0;
    *y = ((double)iy + u3) / 2147483648.0;
}

typedef struct hcell {
    uint64_t h;         /* the cell's first index on the curve (16 bits a side) */
    double w;           /* its share of the sum */
    int k;
} hcell;

static int hcell_cmp(const void *a, const void *b)
{
    uint64_t x = ((const hcell *)a)->h, y = ((const hcell *)b)->h;
    return x < y ? -1 : x > y;
}

/* SL_CELLS, draw t in [0, total): the cell holding t with the cells in
 * curve order over the sampled square (flipped: the square of the returned
 * vector is 1 - the cells'), and (u2, u3) placing the vector at the
 * curve's point for t.  -1 without memory. */
static int cells_hilbert_pick(const slice *s, int flip, double t, double *u2, double *u3)
{
    if (s->n <= 0) return -1;
    hcell *hc = hd_malloc_array((size_t)s->n, sizeof *hc);
    if (!hc) return -1;
    const double R = 65536.0;
    for (int k = 0; k < s->n; k++) {
        double x0, y0, w;
        geo_get(s->c[k].geo, s->scale, &x0, &y0, &w);
        if (flip) { x0 = 1 - x0 - w; y0 = 1 - y0 - w; }
        uint64_t side = (uint64_t)(w * R + 0.5), area = side * side;
        uint64_t h = hilbert_index(16, (uint64_t)(x0 * R + 0.5), (uint64_t)(y0 * R + 0.5));
        hc[k] = (hcell){area ? h / area * area : h, s->c[k].cdf - (k ? s->c[k - 1].cdf : 0), k};
    }
    qsort(hc, (size_t)s->n, sizeof *hc, hcell_cmp);
    int i = 0;
    while (i < s->n - 1 && !(t < hc[i].w)) { t -= hc[i].w; i++; }
    double r = hc[i].w > 0 ? t / hc[i].w : 0.5;
    if (r < 0) r = 0;
    if (r >= 1) r = 1 - 1e-12;
    uint64_t end = i + 1 < s->n ? hc[i + 1].h : (uint64_t)1 << 32;
    double hd = (double)hc[i].h + r * (double)(end - hc[i].h);
    uint64_t px, py;
    hilbert_point(32, (uint64_t)(hd * 4294967296.0), &px, &py);
    double X = ((double)px + *u2) / 4294967296.0, Y = ((double)py + *u3) / 4294967296.0;
    int k = hc[i].k;
    free(hc);
    double x0, y0, w;
    geo_get(s->c[k].geo, s->scale, &x0, &y0, &w);
    if (flip) { X = 1 - X; Y = 1 - Y; }
    *u2 = fmin(fmax((X - x0) / w, 0), 1 - 1e-12);
    *u3 = fmin(fmax((Y - y0) / w, 0), 1 - 1e-12);
    return k;
}

int hd_bsdf_sample_dir(const hd_bsdf *b, hd_bsdf_cache *cache, hd_vec3 given, int mode,
                       int mask, double u1, double u2, double u3, hd_bsdf_sample *out)
{
    return hd_bsdf_sample_drop(b, cache, given, mode, mask, 0, 1, u1, u2, u3, out);
}

int hd_bsdf_sample_drop(const hd_bsdf *b, hd_bsdf_cache *cache, hd_vec3 given, int mode,
                        int mask, int drop, double narrow, double u1, double u2, double u3, hd_bsdf_sample *out)
{
    qset Q;
    memset(out, 0, sizeof *out);
    given = unitv(given);
    if (!qset_init(b, cache, given, mode, mask, &Q) || !(Q.total > 0)) {
        qset_done(&Q);
        return 0;
    }
    double t = u1 * Q.total;
    int pick = -1;
    for (int k = 0; k < 4; k++) {
        if (!(Q.w[k] > 0)) continue;
        pick = k;
        if (t < Q.w[k]) break;
        t -= Q.w[k];
    }
    if (t >= Q.w[pick]) t = Q.w[pick] * (1 - 1e-12);
    int j = pick / 2;
    if (drop & (j ? HD_BSDF_TRANS : HD_BSDF_REFL)) {   /* dropped: nothing built for it */
        qset_done(&Q);
        return 0;
    }
    hd_vec3 v;
    if (pick % 2 == 0) {               /* Lambertian: cosine-weighted */
        double r = sqrt(u2), phi = 2 * HD_PI * u3;
        int side = mode == HD_BSDF_FORWARD ? out_side[Q.c[j]] : in_side[Q.c[j]];
        double z2 = 1 - u2;
        v = hd_v3(r * cos(phi), r * sin(phi), side * sqrt(z2 > 0 ? z2 : 0));
        out->lambertian = 1;
    } else {                           /* directional: cell by the CDF */
        int narrowed = narrow >= 0 && narrow < 1, c2[2];
        if (narrowed) t = Q.w[pick] * (0.5 + narrow * (t / Q.w[pick] - 0.5));
        qctx q2;
        comps_for(given, HD_BSDF_FORWARD, c2);
        /* narrowed at a 3D tree (SL_RING): Radiance's distribution, the given
         * vector as the data's incident one (SDgetTreCDist), its total the weight */
        if (narrowed && Q.q[j].d->kind == 3 && !Q.q[j].fixa && setup_q(b, c2[j], given, HD_BSDF_FORWARD, &q2) &&
            q2.fixa) {
            slice_free(Q.tmp[j]);
            Q.q[j] = q2;
            Q.lazy[j] = 0;
            if ((Q.s[j] = get_slice(cache, &q2, &Q.tmp[j], Q.s[1 - j]))) {
                t *= Q.s[j]->total / Q.w[pick];
                Q.total += Q.s[j]->total - Q.w[pick];
            }
        }
        const slice *s = qset_slice(cache, &Q, j);
        if (!s) { qset_done(&Q); return 0; }
        const qctx *q = &Q.q[j];
        int k;
        float val;
        uint64_t geo;
        if (narrowed && s->kind == SL_CELLS) {
            /* Radiance's order of the cells and point in the cell */
            int flip = !q->fixa;    /* as cell_dir */
            k = cells_hilbert_pick(s, flip, t, &u2, &u3);
            if (k < 0) { qset_done(&Q); return 0; }
            val = s->c[k].val;
            geo = s->c[k].geo;
        } else if (s->kind != SL_RING) {
            k = guide_pick(s->c, s->g, s->n, s->total, t, &val, &geo);
            if (narrowed && s->kind == SL_KLEMS) {
                double lo = k ? s->c[k - 1].cdf : 0, r = s->c[k].cdf > lo ? (t - lo) / (s->c[k].cdf - lo) : 0.5;
                hilbert_square(r, u2, u3, &u2, &u3);
            }
        }
        else if (q->centre) k = s->gb[4] + alias_pick(s->cent, s->gb[5] - s->gb[4], t / Q.w[pick], &val, &geo);
        else {
            /* t in [0, ring_total): the interior, or the ends scaled by ell */
            double x = t * q->rr / (HD_PI / 4);
            if (x < s->cmain) k = alias_pick(s->c, s->nm, x / s->cmain, &val, &geo);
            else k = s->nm + alias_pick(s->c + s->nm, s->n - s->nm, (x - s->cmain) / (q->ell * s->ccorn), &val, &geo);
        }
        v = cell_dir(q, s, k, geo, u2, u3);
        double fv = val + (Q.w[2 * j] > 0 ? b->lamb[Q.c[j]] / HD_PI : 0);
        out->dir = v;
        out->comp = Q.c[j];
        out->value = fv;
        out->pdf = fv * fabs(v.z) / Q.total;
        out->weight = Q.total;
        qset_done(&Q);
        return out->pdf > 0;
    }
    double fv;
    out->dir = v;
    out->comp = Q.c[j];
    out->pdf = qset_pdf(b, &Q, given, v, mode, &fv);
    out->value = fv;
    out->weight = out->pdf > 0 ? fv * fabs(v.z) / out->pdf : 0;
    qset_done(&Q);
    return out->pdf > 0;
}

double hd_bsdf_pdf(const hd_bsdf *b, hd_bsdf_cache *cache, hd_vec3 given, hd_vec3 dir,
                   int mode, int mask)
{
    qset Q;
    given = unitv(given);
    dir = unitv(dir);
    if (!qset_init(b, cache, given, mode, mask, &Q)) return 0;
    int j = (dir.z > 0) == (given.z > 0) ? 0 : 1;
    double p = 0;
    if (dir.z != 0 && (mask & (j ? HD_BSDF_TRANS : HD_BSDF_REFL)))
        p = qset_pdf(b, &Q, given, dir, mode, NULL);
    qset_done(&Q);
    return p;
}

double hd_bsdf_albedo(const hd_bsdf *b, hd_bsdf_cache *cache, hd_vec3 given, int mode, int mask)
{
    qset Q;
    given = unitv(given);
    if (!qset_init(b, cache, given, mode, mask, &Q)) return 0;
    double t = Q.total;
    qset_done(&Q);
    return t;
}

double hd_bsdf_view_psa(const hd_bsdf *b, hd_bsdf_cache *cache, hd_vec3 v, double *pmax)
{
    qset Q;
    int c[2];
    v = unitv(v);
    comps_for(v, HD_BSDF_FORWARD, c);
    for (int j = 0; j < 2; j++)
        if (b->src[c[j]] && b->src[c[j]]->kind == 1) return -1;
    /* Radiance's role: v the data's incident vector (a 3D tree only
     * reversed, SL_RING, is Radiance's empty distribution) */
    if (!qset_init(b, cache, v, HD_BSDF_FORWARD, HD_BSDF_ALL, &Q)) return -1;
    double wmin = 2, wmax = 0;
    for (int j = 0; j < 2; j++) {
        const slice *s = Q.q[j].d && (Q.q[j].d->kind == 4 || Q.q[j].fixa) ? qset_slice(cache, &Q, j) : NULL;
        if (s && s->kind == SL_CELLS) { wmin = fmin(wmin, s->wmin); wmax = fmax(wmax, s->wmax); }
    }
    qset_done(&Q);
    *pmax = HD_PI * wmax * wmax;
    return wmin <= 1 ? HD_PI * wmin * wmin : -1;
}

double hd_bsdf_hemi_parts(const hd_bsdf *b, hd_bsdf_cache *cache, hd_vec3 in, double w[4])
{
    w[0] = w[1] = w[2] = w[3] = 0;
    in = unitv(in);
    if (!(in.z != 0) || !isfinite(in.z)) return 0;
    int c[2], need = 0;
    comps_for(in, HD_BSDF_FORWARD, c);
    for (int j = 0; j < 2; j++) {
        w[2 * j] = b->lamb[c[j]];
        const hd_bsdf_block *d = b->src[c[j]];
        if (!d || !d->kind) continue;
        double h = b->recip[c[j]] ? -1 : block_hemi(d, in);
        if (h >= 0) w[2 * j + 1] = h;
        else need |= j ? HD_BSDF_TRANS : HD_BSDF_REFL;
    }
    if (need) {   /* reciprocal data: the sampler's own total (3D: ring_sums, no slice) */
        qset Q;
        if (qset_init(b, cache, in, HD_BSDF_FORWARD, need, &Q)) {
            for (int j = 0; j < 2; j++)
                if (need & (j ? HD_BSDF_TRANS : HD_BSDF_REFL)) w[2 * j + 1] = Q.w[2 * j + 1];
            qset_done(&Q);
        }
    }
    return w[0] + w[1] + w[2] + w[3];
}

double hd_bsdf_hemi(const hd_bsdf *b, hd_vec3 in, int mask)
{
    return hd_bsdf_albedo(b, NULL, in, HD_BSDF_FORWARD, mask);
}

/* ---- Klems matrices ---- */
hd_vec3 hd_bsdf_klems_in_dir(const hd_klems_basis *kb, hd_bsdf_comp c, int k, double r0, double r1)
{
    hd_vec3 v = hd_klems_dir(kb, k, r0, r1);
    return hd_v3(-v.x, -v.y, in_side[c] * v.z);
}

hd_vec3 hd_bsdf_klems_out_dir(const hd_klems_basis *kb, hd_bsdf_comp c, int k, double r0, double r1)
{
    hd_vec3 v = hd_klems_dir(kb, k, r0, r1);
    return hd_v3(v.x, v.y, out_side[c] * v.z);
}

static int same_basis(const hd_klems_basis *a, const hd_klems_basis *b)
{
    if (a->nrings != b->nrings || a->nbins != b->nbins) return 0;
    for (int r = 0; r < a->nrings; r++)
        if (a->ring[r].nphi != b->ring[r].nphi || fabs(a->ring[r].theta_hi - b->ring[r].theta_hi) > 1e-6)
            return 0;
    return 1;
}

/* Exact patch-pair averages of a 4D tree: the tree is constant on cells of
 * the finest grid (res per square side) in each of its two squares, so
 * mean_{Pi x Po} f = Σ_ca Σ_cb μ(Pi∩ca) μ(Po∩cb) f(ca,cb) / (λi λo), with
 * the overlaps μ(P∩c) measured once by K×K points per finest cell (the
 * square maps uniformly to projected solid angle). */
typedef struct ovl { int *start; int *bin; float *frac; } ovl;

static hd_status overlap_table(const hd_klems_basis *kb, int res, int sign, ovl *t)
{
    int K = 2048 / res < 4 ? 4 : 2048 / res;    /* about 2048 points per square side */
    size_t ncell = (size_t)res * (size_t)res;
    t->start = hd_malloc_array(ncell + 1, sizeof *t->start);
    t->bin = hd_malloc_array(ncell * 16, sizeof *t->bin);
    t->frac = hd_malloc_array(ncell * 16, sizeof *t->frac);
    if (!t->start || !t->bin || !t->frac) return HD_ERR_NOMEM;
    int ne = 0, cnt[16], bins[16];
    for (size_t cidx = 0; cidx < ncell; cidx++) {
        int ix = (int)(cidx / (size_t)res), iy = (int)(cidx % (size_t)res), nb = 0, other = 0;
        for (int p = 0; p < K; p++)
            for (int q = 0; q < K; q++) {
                double x, y;
                hd_square2disk((ix + (p + 0.5) / K) / res, (iy + (q + 0.5) / K) / res, &x, &y);
                double z2 = 1 - x * x - y * y;
                int bn = hd_klems_bin(kb, hd_v3(sign * x, sign * y, sqrt(z2 > 0 ? z2 : 0)));
                if (bn < 0) continue;
                int k = 0;
                while (k < nb && bins[k] != bn) k++;
                if (k == nb) {
                    if (nb == 16) { other++; continue; }
                    bins[nb] = bn; cnt[nb++] = 0;
                }
                cnt[k]++;
            }
        t->start[cidx] = ne;
        for (int k = 0; k < nb; k++) {
            t->bin[ne] = bins[k];
            t->frac[ne] = (float)cnt[k] / (float)(K * K - other);
            ne++;
        }
    }
    t->start[ncell] = ne;
    return HD_OK;
}

static void ovl_free(ovl *t) { free(t->start); free(t->bin); free(t->frac); }

static hd_status tree4_klems(const hd_bsdf *b, int c, const hd_klems_basis *kb, double *vals)
{
    const hd_bsdf_block *d = b->src[c];
    const hd_ttree *t = &d->tree;
    int res = 1 << t->maxlev, n = kb->nbins, rc = b->recip[c];
    ovl T = {0};
    hd_status st = overlap_table(kb, res, rc ? -1 : 1, &T);
    double *G = hd_calloc((size_t)n * (size_t)n, sizeof *G), *tmp = hd_malloc_array((size_t)n, sizeof *tmp);
    if (st || !G || !tmp) { ovl_free(&T); free(G); free(tmp); return HD_ERR_NOMEM; }
    sbuf sb = {0};
    for (int ix = 0; ix < res; ix++)
        for (int iy = 0; iy < res; iy++) {
            int ca = ix * res + iy;
            if (T.start[ca] == T.start[ca + 1]) continue;
            double fc[4] = {(ix + 0.5) / res, (iy + 0.5) / res, 0, 0};
            sb.n = 0;
            collect(t, t->root, fc, 3, 2, 3, 0, 0, 1, &sb);
            if (sb.fail) { free(sb.val); free(sb.cell); ovl_free(&T); free(G); free(tmp); return HD_ERR_NOMEM; }
            memset(tmp, 0, (size_t)n * sizeof *tmp);
            for (size_t k = 0; k < sb.n; k++) {
                int x0 = (int)(sb.cell[3 * k] * res + 0.5), y0 = (int)(sb.cell[3 * k + 1] * res + 0.5);
                int w = (int)(sb.cell[3 * k + 2] * res + 0.5);
                double v = sb.val[k];
                for (int u = x0; u < x0 + w; u++)
                    for (int vv = y0; vv < y0 + w; vv++) {
                        int cb = u * res + vv;
                        for (int e = T.start[cb]; e < T.start[cb + 1]; e++) tmp[T.bin[e]] += v * T.frac[e];
                    }
            }
            for (int e = T.start[ca]; e < T.start[ca + 1]; e++) {
                double *row = G + (size_t)T.bin[e] * (size_t)n;
                double fr = T.frac[e];
                for (int p = 0; p < n; p++) row[p] += fr * tmp[p];
            }
        }
    free(sb.val);
    free(sb.cell);
    /* the patches' projected solid angles as the overlap table measures
     * them (normalising by these keeps each average a proper mean) */
    double cellsa = HD_PI / ((double)res * res), lam = b->lamb[c] / HD_PI;
    memset(tmp, 0, (size_t)n * sizeof *tmp);
    for (int e = 0; e < T.start[res * res]; e++) tmp[T.bin[e]] += T.frac[e] * cellsa;
    ovl_free(&T);
    /* G[a-patch][b-patch]; non-reciprocal: a = incident, b = outgoing */
    for (int o = 0; o < n; o++)
        for (int i = 0; i < n; i++) {
            double g = rc ? G[(size_t)o * n + i] : G[(size_t)i * n + o];
            double li = tmp[i] > 0 ? tmp[i] : hd_klems_lambda(kb, i), lo = tmp[o] > 0 ? tmp[o] : hd_klems_lambda(kb, o);
            vals[(size_t)o * n + i] = g * cellsa * cellsa / (li * lo) + lam;
        }
    free(G);
    free(tmp);
    return HD_OK;
}

/* Klems bins are rectangles in (u = sin²θ, φ), where the projected solid
 * angle is du·dφ/2: the exact overlap (sr) of bin a of basis A and bin b of
 * basis B (azimuth ranges centred on col·2π/nphi, compared modulo 2π). */
static double bin_overlap(const hd_klems_basis *A, int a, const hd_klems_basis *B, int b)
{
    int ca = 0, cb = 0, ra = hd_klems_ring_of(A, a, &ca), rb = hd_klems_ring_of(B, b, &cb);
    if (ra < 0 || rb < 0) return 0;
    const hd_klems_ring *x = &A->ring[ra], *y = &B->ring[rb];
    double s;
    s = sin(x->theta_lo * HD_PI / 180); double xu0 = s * s;
    s = sin(x->theta_hi * HD_PI / 180); double xu1 = s * s;
    s = sin(y->theta_lo * HD_PI / 180); double yu0 = s * s;
    s = sin(y->theta_hi * HD_PI / 180); double yu1 = s * s;
    double du = fmin(xu1, yu1) - fmax(xu0, yu0);
    if (!(du > 0)) return 0;
    double xw = 2 * HD_PI / x->nphi, yw = 2 * HD_PI / y->nphi;
    double x0 = (ca - 0.5) * xw, x1 = x0 + xw, y0 = (cb - 0.5) * yw, y1 = y0 + yw;
    double dphi = 0;
    for (int k = -2; k <= 2; k++) {
        double lo = fmax(x0, y0 + 2 * HD_PI * k), hi = fmin(x1, y1 + 2 * HD_PI * k);
        if (hi > lo) dphi += hi - lo;
    }
    return du * dphi / 2;
}

/* Exact conversion of Klems data to another ring basis: the data is
 * constant on the pairs of its own bins, so each target pair mean is the
 * overlap-weighted sum of the data. */
static hd_status klems_rebin(const hd_bsdf *b, int c, const hd_klems_basis *kb, double *vals)
{
    const hd_bsdf_block *d = b->src[c];
    int rc = b->recip[c];
    const hd_klems_basis *ib = rc ? &d->outb : &d->inb, *ob = rc ? &d->inb : &d->outb;
    int n = kb->nbins, ni = ib->nbins, no = ob->nbins;
    double *F = hd_malloc_array((size_t)no * (size_t)ni, sizeof *F);
    double *OI = hd_calloc((size_t)n * (size_t)ni, sizeof *OI);
    double *OO = hd_calloc((size_t)n * (size_t)no, sizeof *OO);
    double *G = hd_calloc((size_t)no * (size_t)n, sizeof *G);
    if (!F || !OI || !OO || !G) { free(F); free(OI); free(OO); free(G); return HD_ERR_NOMEM; }
    for (int o = 0; o < no; o++) {
        hd_vec3 vo = hd_bsdf_klems_out_dir(ob, (hd_bsdf_comp)c, o, 0.5, 0.5);
        for (int i = 0; i < ni; i++)
            F[(size_t)o * ni + i] = comp_nd(b, c, hd_bsdf_klems_in_dir(ib, (hd_bsdf_comp)c, i, 0.5, 0.5), vo);
    }
    for (int t = 0; t < n; t++) {
        for (int i = 0; i < ni; i++) OI[(size_t)t * ni + i] = bin_overlap(kb, t, ib, i);
        for (int o = 0; o < no; o++) OO[(size_t)t * no + o] = bin_overlap(kb, t, ob, o);
    }
    /* G[o][I] = Σ_i F[o][i]·OI[I][i] */
    for (int o = 0; o < no; o++)
        for (int I = 0; I < n; I++) {
            double acc = 0;
            const double *fr = F + (size_t)o * ni, *ov = OI + (size_t)I * ni;
            for (int i = 0; i < ni; i++) acc += fr[i] * ov[i];
            G[(size_t)o * n + I] = acc;
        }
    double lam = b->lamb[c] / HD_PI;
    for (int O = 0; O < n; O++)
        for (int I = 0; I < n; I++) {
            double acc = 0;
            for (int o = 0; o < no; o++) acc += OO[(size_t)O * no + o] * G[(size_t)o * n + I];
            double lo = hd_klems_lambda(kb, O), li = hd_klems_lambda(kb, I);
            vals[(size_t)O * n + I] = (lo > 0 && li > 0 ? acc / (lo * li) : 0) + lam;
        }
    free(F); free(OI); free(OO); free(G);
    return HD_OK;
}

/* Fisher-Yates shuffle of p[0..n-1] (any prior order) driven by xorshift */
static void shuffle(int *p, int n, uint64_t x)
{
    for (int k = n - 1; k > 0; k--) {
        x ^= x << 13; x ^= x >> 7; x ^= x << 17;
        int j = (int)((x >> 11) % (uint64_t)(k + 1));
        int t = p[k]; p[k] = p[j]; p[j] = t;
    }
}

hd_status hd_bsdf_klems_values(const hd_bsdf *b, hd_bsdf_comp c, const hd_klems_basis *kb,
                               int nsamp, double *vals)
{
    if ((unsigned)c > 3) return hd_fail(HD_ERR_USAGE, "bad BSDF component %d", (int)c);
    const hd_bsdf_block *d = b->src[c];
    if (!d && b->lamb[c] <= 0)
        return hd_fail(HD_ERR_FORMAT, "BSDF has no %s component (WINDOW '%s' block)",
                       hd_bsdf_label(c), hd_bsdf_window_name(c));
    hd_klems_basis full;
    if (!kb) {
        if (d && d->kind == 1) kb = b->recip[c] ? &d->outb : &d->inb;
        else { hd_klems_standard(&full, HD_KLEMS_FULL); kb = &full; }
    }
    int n = kb->nbins;
    double lam = b->lamb[c] / HD_PI;
    if (d && d->kind == 1 && same_basis(kb, &d->inb) && same_basis(kb, &d->outb)) {
        /* exact: evaluate at bin centres */
        for (int o = 0; o < n; o++) {
            hd_vec3 vo = hd_bsdf_klems_out_dir(kb, c, o, 0.5, 0.5);
            for (int i = 0; i < n; i++) {
                hd_vec3 vi = hd_bsdf_klems_in_dir(kb, c, i, 0.5, 0.5);
                vals[(size_t)o * (size_t)n + (size_t)i] = comp_nd(b, c, vi, vo) + lam;
            }
        }
        return HD_OK;
    }
    if (d && d->kind == 4 && d->tree.maxlev <= 7 && nsamp >= 0) return tree4_klems(b, c, kb, vals);
    if (d && d->kind == 1 && nsamp >= 0) return klems_rebin(b, c, kb, vals);
    if (nsamp < 0) nsamp = -nsamp;   /* (testing: force Monte Carlo) */
    if (nsamp == 0) nsamp = 1024;
    int m = (int)floor(sqrt((double)nsamp));
    while ((m + 1) * (m + 1) <= nsamp) m++;
    while (m * m > nsamp) m--;
    /* stratified m×m points per bin (the nsamp - m² others uniform over
     * the bin, so that every point has the same density); incident and
     * outgoing points paired by a random permutation per bin pair below */
    hd_rng r;
    hd_rng_init(&r, 0x6b6c656d73ULL, (uint64_t)c);
    hd_vec3 *vin = hd_malloc_array((size_t)n * (size_t)nsamp, sizeof *vin);
    hd_vec3 *vout = hd_malloc_array((size_t)n * (size_t)nsamp, sizeof *vout);
    int *perm = hd_malloc_array((size_t)nsamp, sizeof *perm);
    if (!vin || !vout || !perm) { free(vin); free(vout); free(perm); return HD_ERR_NOMEM; }
    for (int k = 0; k < nsamp; k++) perm[k] = k;
    for (int k = 0; k < n; k++)
        for (int s = 0; s < nsamp; s++) {
            double w = 1.0 / m, r0, r1;
            int sx = s % m, sy = s / m;
            if (s >= m * m) { sx = sy = 0; w = 1; }
            r0 = (sx + hd_rng_uniform(&r)) * w;
            r1 = (sy + hd_rng_uniform(&r)) * w;
            vin[(size_t)k * nsamp + s] = hd_bsdf_klems_in_dir(kb, c, k, r0, r1);
            r0 = (sy + hd_rng_uniform(&r)) * w;
            r1 = (sx + hd_rng_uniform(&r)) * w;
            vout[(size_t)k * nsamp + s] = hd_bsdf_klems_out_dir(kb, c, k, r0, r1);
        }
    if (d && d->kind == 4) {
        /* fast path: tree coordinates of every sample computed once */
        size_t ns = (size_t)n * (size_t)nsamp;
        float *ci = hd_malloc_array(ns, 2 * sizeof(float)), *co = hd_malloc_array(ns, 2 * sizeof(float));
        if (!ci || !co) { free(ci); free(co); free(vin); free(vout); free(perm); return HD_ERR_NOMEM; }
        int rc = b->recip[c];
        for (size_t k = 0; k < ns; k++) {
            double x, y;
            hd_vec3 a = rc ? vout[k] : vin[k];   /* data-incident role */
            hd_vec3 bb = rc ? vin[k] : vout[k];
            /* ci: coordinates of the incident-bin sample in its role */
            if (rc) hd_disk2square(bb.x, bb.y, &x, &y); else hd_disk2square(-a.x, -a.y, &x, &y);
            ci[2 * k] = (float)x; ci[2 * k + 1] = (float)y;
            if (rc) hd_disk2square(-a.x, -a.y, &x, &y); else hd_disk2square(bb.x, bb.y, &x, &y);
            co[2 * k] = (float)x; co[2 * k + 1] = (float)y;
        }
        for (int o = 0; o < n; o++)
            for (int i = 0; i < n; i++) {
                double acc = 0;
                const float *pi = ci + 2 * (size_t)i * nsamp, *po = co + 2 * (size_t)o * nsamp;
                /* each incident stratum pairs with a different outgoing
                 * stratum through a fresh random permutation per patch
                 * pair (a fixed, structured pairing would be biased for
                 * peaks; pairing with replacement is noisier) */
                shuffle(perm, nsamp, hd_hash64((uint64_t)o, (uint64_t)i) | 1);
                for (int s = 0; s < nsamp; s++) {
                    int t = perm[s];
                    double c4[4];
                    if (rc) { c4[0] = po[2 * t]; c4[1] = po[2 * t + 1]; c4[2] = pi[2 * s]; c4[3] = pi[2 * s + 1]; }
                    else { c4[0] = pi[2 * s]; c4[1] = pi[2 * s + 1]; c4[2] = po[2 * t]; c4[3] = po[2 * t + 1]; }
                    acc += tree_lookup(&d->tree, c4);
                }
                vals[(size_t)o * (size_t)n + (size_t)i] = acc / nsamp + lam;
            }
        free(ci);
        free(co);
    } else {
        for (int o = 0; o < n; o++)
            for (int i = 0; i < n; i++) {
                double acc = 0;
                const hd_vec3 *pi = vin + (size_t)i * nsamp, *po = vout + (size_t)o * nsamp;
                shuffle(perm, nsamp, hd_hash64((uint64_t)o, (uint64_t)i) | 1);
                for (int s = 0; s < nsamp; s++) {
                    int t = perm[s];
                    acc += comp_nd(b, c, pi[s], po[t]);
                }
                vals[(size_t)o * (size_t)n + (size_t)i] = acc / nsamp + lam;
            }
    }
    free(vin);
    free(vout);
    free(perm);
    return HD_OK;
}

hd_status hd_bsdf_klems_matrix(const hd_bsdf *b, hd_bsdf_comp c, const hd_klems_basis *kb,
                               int nsamp, int ncomp, hd_matrix *m)
{
    hd_klems_basis use;
    if (!kb) {
        const hd_bsdf_block *d = (unsigned)c < 4 ? b->src[c] : NULL;
        if (d && d->kind == 1) use = b->recip[c] ? d->outb : d->inb;
        else hd_klems_standard(&use, HD_KLEMS_FULL);
        kb = &use;
    }
    if (ncomp != 1 && ncomp != 3) return hd_fail(HD_ERR_USAGE, "matrix components must be 1 or 3");
    const hd_bsdf_block *dd = (unsigned)c < 4 ? b->src[c] : NULL;
    if (kb == &use && dd && dd->kind == 1 && !same_basis(&dd->inb, &dd->outb)) {
        /* Klems data with different row and column bases: the file's own
         * nout × ninc matrix */
        const hd_klems_basis *ib = b->recip[c] ? &dd->outb : &dd->inb, *ob = b->recip[c] ? &dd->inb : &dd->outb;
        int ni = ib->nbins, no = ob->nbins;
        memset(m, 0, sizeof *m);
        m->nrows = no;
        m->ncols = ni;
        m->ncomp = ncomp;
        m->infmt = HD_MTX_ASCII;
        m->data = hd_calloc((size_t)no * (size_t)ni * (size_t)ncomp, sizeof *m->data);
        if (!m->data) return HD_ERR_NOMEM;
        double lam = b->lamb[c] / HD_PI;
        for (int o = 0; o < no; o++) {
            hd_vec3 vo = hd_bsdf_klems_out_dir(ob, c, o, 0.5, 0.5);
            for (int i = 0; i < ni; i++) {
                double v = (comp_nd(b, c, hd_bsdf_klems_in_dir(ib, c, i, 0.5, 0.5), vo) + lam) *
                           hd_klems_lambda(ib, i);
                for (int k = 0; k < ncomp; k++) m->data[((size_t)o * ni + i) * ncomp + k] = v;
            }
        }
        return HD_OK;
    }
    int n = kb->nbins;
    double *vals = hd_malloc_array((size_t)n * (size_t)n, sizeof *vals);
    if (!vals) return HD_ERR_NOMEM;
    hd_status st = hd_bsdf_klems_values(b, c, kb, nsamp, vals);
    if (st) { free(vals); return st; }
    memset(m, 0, sizeof *m);
    m->nrows = m->ncols = n;
    m->ncomp = ncomp;
    m->infmt = HD_MTX_ASCII;
    m->data = hd_calloc((size_t)n * (size_t)n * (size_t)ncomp, sizeof *m->data);
    if (!m->data) { free(vals); return HD_ERR_NOMEM; }
    for (int o = 0; o < n; o++)
        for (int i = 0; i < n; i++) {
            double v = vals[(size_t)o * n + i] * hd_klems_lambda(kb, i);
            for (int k = 0; k < ncomp; k++) m->data[((size_t)o * n + i) * ncomp + k] = v;
        }
    free(vals);
    return HD_OK;
}

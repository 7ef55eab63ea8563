/* heliodon — tensor trees for genBSDF: bottom-up data reduction of a full
 * grid (like rttree_reduce) and the curly-brace XML encoding (spec §8.3). */
#include "heliodon/genbsdf.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct hd_gbtree {
    int dims, log2res;
    const float *grid;       /* level 0: borrowed copy owned below */
    float *own;              /* copy of the grid */
    float *val[16];          /* levels 1..log2res: cell values */
    unsigned char *leaf[16]; /* levels 1..log2res: 1 = uniform cell */
    size_t nleaves;
};

static size_t ncells(int dims, int side)
{
    size_t n = 1;
    for (int i = 0; i < dims; i++) n *= (size_t)side;
    return n;
}

/* index of the cell with per-dimension coordinates c[] on a side^D grid */
static size_t cell_index(int dims, int side, const int *c)
{
    size_t k = 0;
    for (int i = 0; i < dims; i++) k = k * (size_t)side + (size_t)c[i];
    return k;
}

/* children of cell c at level L (side s) on level L-1 (side 2s): child n
 * has bit i = offset in dimension i */
static void child_coords(int dims, const int *c, int n, int *cc)
{
    for (int i = 0; i < dims; i++) cc[i] = 2 * c[i] + ((n >> i) & 1);
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

static float spread(const float *v, int n, float *mean)
{
    double s = 0;
    float mn = v[0], mx = v[0];
    for (int k = 0; k < n; k++) {
        s += v[k];
        if (v[k] < mn) mn = v[k];
        if (v[k] > mx) mx = v[k];
    }
    *mean = (float)(s / n);
    if (mx == mn) return 0;
    double m = fabs(s / n);
    return (float)((mx - mn) / (m > 1e-9 ? m : 1e-9));
}

/* values of the 2^D children of cell c at level L (1-based) */
static int gather(const hd_gbtree *t, int L, const int *c, float *v, int *allleaf)
{
    int nch = 1 << t->dims;
    int cside = 1 << (t->log2res - L + 1);
    int cc[4];
    *allleaf = 1;
    for (int n = 0; n < nch; n++) {
        child_coords(t->dims, c, n, cc);
        size_t k = cell_index(t->dims, cside, cc);
        if (L == 1) v[n] = t->grid[k];
        else {
            v[n] = t->val[L - 1][k];
            if (!t->leaf[L - 1][k]) *allleaf = 0;
        }
    }
    return nch;
}

static void coords_of(int dims, int side, size_t k, int *c)
{
    for (int i = dims - 1; i >= 0; i--) { c[i] = (int)(k % (size_t)side); k /= (size_t)side; }
}

/* leaves written top-down: a cell counts when no ancestor is a leaf; a
 * non-leaf cell of level 1 writes its 2^D finest values */
static size_t count_leaves(const hd_gbtree *t)
{
    int dims = t->dims, log2res = t->log2res, R = 1 << log2res, c[4], pc[4];
    size_t nl = 0;
    for (int L = log2res; L >= 1; L--) {
        int side = R >> L;
        size_t n = ncells(dims, side);
        for (size_t k = 0; k < n; k++) {
            coords_of(dims, side, k, c);
            int reach = 1;
            for (int i = 0; i < dims; i++) pc[i] = c[i] / 2;
            for (int LL = L + 1, ps = side / 2; LL <= log2res && reach; LL++, ps /= 2) {
                if (t->leaf[LL][cell_index(dims, ps, pc)]) reach = 0;
                for (int i = 0; i < dims; i++) pc[i] /= 2;
            }
            if (!reach) continue;
            if (t->leaf[L][k]) nl++;
            else if (L == 1) nl += (size_t)1 << dims;
        }
    }
    return nl;
}

hd_status hd_gbtree_build(hd_gbtree **out, const float *grid, int dims, int log2res, double cull_pct,
                          double nrays)
{
    *out = NULL;
    if ((dims != 3 && dims != 4) || log2res < 1 || log2res > 9)
        return hd_fail(HD_ERR_RANGE, "tensor tree: dimensions %d / resolution 2^%d out of range", dims, log2res);
    hd_gbtree *t = hd_calloc(1, sizeof *t);
    if (!t) return HD_ERR_NOMEM;
    t->dims = dims;
    t->log2res = log2res;
    int R = 1 << log2res;
    size_t n0 = ncells(dims, R);
    t->own = hd_malloc_array(n0, sizeof *t->own);
    if (!t->own) { hd_gbtree_free(t); return HD_ERR_NOMEM; }
    memcpy(t->own, grid, n0 * sizeof *grid);
    for (size_t k = 0; k < n0; k++) if (!(t->own[k] >= 0)) t->own[k] = 0;   /* NaN, negative */
    t->grid = t->own;
    /* level by level: among the groups whose children are all leaves, the
     * cull_pct % with the smallest relative spread are merged (and groups
     * of equal values always) */
    double q = cull_pct / 100.0;
    int c[4], all;
    float v[16], mean;
    for (int L = 1; L <= log2res; L++) {
        int side = R >> L;
        size_t n = ncells(dims, side);
        t->val[L] = hd_malloc_array(n, sizeof(float));
        t->leaf[L] = hd_malloc_array(n, 1);
        float *sp = hd_malloc_array(n, sizeof(float));
        float *cand = hd_malloc_array(n, sizeof(float));
        if (!t->val[L] || !t->leaf[L] || !sp || !cand) { free(sp); free(cand); hd_gbtree_free(t); return HD_ERR_NOMEM; }
        size_t ncand = 0;
        for (size_t k = 0; k < n; k++) {
            coords_of(dims, side, k, c);
            int nch = gather(t, L, c, v, &all);
            sp[k] = spread(v, nch, &mean);
            t->val[L][k] = mean;
            t->leaf[L][k] = (unsigned char)all;
            if (all) cand[ncand++] = sp[k];
        }
        if (nrays > 0) {
            /* ray counts of the children: value x rays x projected solid
             * angle of a finest output cell x finest cells per child */
            double scale = nrays * HD_PI / ((double)R * R) * (double)((size_t)1 << (dims * (L - 1)));
            int nch = 1 << dims;
            double z = 3.0 * q;
            double lim = (nch - 1) + z * sqrt(2.0 * (nch - 1));
            for (size_t k = 0; k < n; k++) {
                if (!t->leaf[L][k]) continue;
                if (sp[k] == 0) continue;
                if (q <= 0) { t->leaf[L][k] = 0; continue; }
                coords_of(dims, side, k, c);
                gather(t, L, c, v, &all);
                double m = t->val[L][k] * scale, chi2 = 0;
                for (int j = 0; j < nch; j++) {
                    double d = v[j] * scale - m;
                    chi2 += d * d;
                }
                chi2 = m > 0 ? chi2 / m : 0;
                t->leaf[L][k] = (unsigned char)(chi2 <= lim);
            }
            free(sp);
            free(cand);
            continue;
        }
        float thr = -1;
        if (ncand && q > 0) {
            qsort(cand, ncand, sizeof *cand, cmp_float);
            size_t at = (size_t)floor(q * (double)ncand);
            thr = at >= ncand ? INFINITY : at > 0 ? cand[at - 1] : -1;
        }
        for (size_t k = 0; k < n; k++)
            if (t->leaf[L][k]) t->leaf[L][k] = (unsigned char)(sp[k] == 0 || sp[k] <= thr);
        free(sp);
        free(cand);
    }
    t->nleaves = count_leaves(t);
    *out = t;
    return HD_OK;
}

void hd_gbtree_free(hd_gbtree *t)
{
    if (!t) return;
    free(t->own);
    for (int L = 0; L < 16; L++) { free(t->val[L]); free(t->leaf[L]); }
    free(t);
}

size_t hd_gbtree_nleaves(const hd_gbtree *t) { return t->nleaves; }

double hd_gbtree_lookup(const hd_gbtree *t, const double *cf)
{
    int R = 1 << t->log2res;
    int c0[4];
    for (int i = 0; i < t->dims; i++) {
        int k = (int)(cf[i] * R);
        c0[i] = k < 0 ? 0 : k >= R ? R - 1 : k;
    }
    for (int L = t->log2res; L >= 1; L--) {
        int c[4];
        for (int i = 0; i < t->dims; i++) c[i] = c0[i] >> L;
        size_t k = cell_index(t->dims, R >> L, c);
        if (t->leaf[L][k]) return t->val[L][k];
    }
    return t->grid[cell_index(t->dims, R, c0)];
}

static void put(FILE *fp, float v)
{
    fprintf(fp, " %.5g", (double)v);
}

/* write cell c of level L (0 = finest) */
static void write_node(FILE *fp, const hd_gbtree *t, int L, const int *c, int indent)
{
    int R = 1 << t->log2res;
    if (L == 0) { fputc('{', fp); (void)indent; put(fp, t->grid[cell_index(t->dims, R, c)]); fputs(" }\n", fp); return; }
    size_t k = cell_index(t->dims, R >> L, c);
    if (t->leaf[L][k]) { fputc('{', fp); (void)indent; put(fp, t->val[L][k]); fputs(" }\n", fp); return; }
    int nch = 1 << t->dims;
    int cside = R >> (L - 1);
    int cc[4];
    /* all children leaves: one grid, last dimension fastest */
    int all = 1;
    for (int n = 0; n < nch && all; n++) {
        child_coords(t->dims, c, n, cc);
        if (L - 1 > 0 && !t->leaf[L - 1][cell_index(t->dims, cside, cc)]) all = 0;
    }
    if (all) {
        fputc('{', fp); (void)indent;
        for (int g = 0; g < nch; g++) {
            /* grid position g: dimension 0 is the most significant bit */
            for (int i = 0; i < t->dims; i++) cc[i] = 2 * c[i] + ((g >> (t->dims - 1 - i)) & 1);
            size_t kk = cell_index(t->dims, cside, cc);
            put(fp, L - 1 == 0 ? t->grid[kk] : t->val[L - 1][kk]);
        }
        fputs(" }\n", fp);
        return;
    }
    fputs("{\n", fp);
    for (int n = 0; n < nch; n++) {
        child_coords(t->dims, c, n, cc);
        write_node(fp, t, L - 1, cc, indent + 1);
    }
    fputs("}\n", fp);
}

hd_status hd_gbtree_write(FILE *fp, const hd_gbtree *t)
{
    int c[4] = {0, 0, 0, 0};
    write_node(fp, t, t->log2res, c, 0);
    if (ferror(fp)) return hd_fail(HD_ERR_IO, "write error on the tensor tree data");
    return HD_OK;
}

void hd_gbtree_reciprocal_avg(float *grid, int log2res)
{
    size_t R = (size_t)1 << log2res;
    for (size_t i0 = 0; i0 < R; i0++)
        for (size_t i1 = 0; i1 < R; i1++)
            for (size_t i2 = 0; i2 < R; i2++)
                for (size_t i3 = 0; i3 < R; i3++) {
                    size_t k = ((i0 * R + i1) * R + i2) * R + i3;
                    size_t m = (((R - 1 - i2) * R + (R - 1 - i3)) * R + (R - 1 - i0)) * R + (R - 1 - i1);
                    if (m <= k) continue;
                    float a = 0.5f * (grid[k] + grid[m]);
                    grid[k] = grid[m] = a;
                }
}

/* Data reduction of rttree_reduce: every group of 2^D finest cells gets a
 * variation measure sqrt((max-min)/(sqrt(mean)+0.03)); the threshold is
 * the cull_pct percentile of the measures of those groups (histogram of
 * 300 bins up to 4); then from the root down, a cell whose measure (over
 * all its finest cells) is not above the threshold becomes one leaf. */
#define RTR_HISTLEN 300
#define RTR_HISTMAX 4.0

static float rtr_measure(float vmin, float vmax, float vavg)
{
    return sqrtf((vmax - vmin) / (sqrtf(vavg > 0 ? vavg : 0) + .03f));
}

/* smallest and largest finest value under cell c of level L */
static void grid_range(const hd_gbtree *t, int L, const int *c, float *mn, float *mx)
{
    int dims = t->dims, R = 1 << t->log2res, b = 1 << L, o[4], g[4];
    float lo = 1e20f, hi = 0;
    size_t nb = ncells(dims, b);
    for (size_t q = 0; q < nb; q++) {
        coords_of(dims, b, q, o);
        for (int i = 0; i < dims; i++) g[i] = c[i] * b + o[i];
        float v = t->grid[cell_index(dims, R, g)];
        if (v < lo) lo = v;
        if (v > hi) hi = v;
    }
    *mn = lo;
    *mx = hi;
}

/* Memory: besides the grid and the levels' values and leaf flags, only the
 * ranges of levels 2 and up are stored (a 16th of level 1's); those of
 * levels 1 and 2 are read from the grid (at -g 7 anisotropic this keeps
 * 128 MB of level-1 ranges out of the peak). */
hd_status hd_gbtree_build_rtr(hd_gbtree **out, float *grid, int dims, int log2res, double cull_pct)
{
    *out = NULL;
    if ((dims != 3 && dims != 4) || log2res < 1 || log2res > 9) {
        free(grid);
        return hd_fail(HD_ERR_RANGE, "tensor tree: dimensions %d / resolution 2^%d out of range", dims, log2res);
    }
    hd_gbtree *t = hd_calloc(1, sizeof *t);
    if (!t) { free(grid); return HD_ERR_NOMEM; }
    t->dims = dims;
    t->log2res = log2res;
    t->own = grid;
    t->grid = grid;
    int R = 1 << log2res, nch = 1 << dims;
    size_t n0 = ncells(dims, R);
    for (size_t k = 0; k < n0; k++) if (!(grid[k] >= 0)) grid[k] = 0;
    float *pmin = NULL, *pmax = NULL;
    float thr = 0;
    int c[4], cc[4];
    for (int L = 1; L <= log2res; L++) {
        int side = R >> L, cside = side * 2;
        size_t n = ncells(dims, side);
        t->val[L] = hd_malloc_array(n, sizeof(float));
        t->leaf[L] = hd_malloc_array(n, 1);
        float *vmin = NULL, *vmax = NULL;
        if (L >= 2) {
            vmin = hd_malloc_array(n, sizeof(float));
            vmax = hd_malloc_array(n, sizeof(float));
        }
        size_t *histo = L == 1 && cull_pct >= 0 ? hd_calloc(RTR_HISTLEN, sizeof(size_t)) : NULL;
        if (!t->val[L] || !t->leaf[L] || (L >= 2 && (!vmin || !vmax)) || (L == 1 && cull_pct >= 0 && !histo)) {
            free(vmin); free(vmax); free(pmin); free(pmax); free(histo);
            hd_gbtree_free(t);
            return HD_ERR_NOMEM;
        }
        for (size_t k = 0; k < n; k++) {
            coords_of(dims, side, k, c);
            float mn = 1e20f, mx = 0, sum = 0;
            for (int q = 0; q < nch; q++) {
                child_coords(dims, c, q, cc);
                size_t kk = cell_index(dims, cside, cc);
                float a, lo, hi;
                if (L == 1) a = lo = hi = grid[kk];
                else if (L == 2) a = lo = hi = t->val[1][kk];   /* range: below */
                else { a = t->val[L - 1][kk]; lo = pmin[kk]; hi = pmax[kk]; }
                if (lo < mn) mn = lo;
                if (hi > mx) mx = hi;
                sum += a;
            }
            if (L == 2) grid_range(t, 2, c, &mn, &mx);
            t->val[L][k] = sum / (float)nch;
            if (L >= 2) {
                vmin[k] = mn;
                vmax[k] = mx;
                t->leaf[L][k] = (unsigned char)!(rtr_measure(mn, mx, t->val[L][k]) > thr);
            } else if (histo) {
                /* threshold from the histogram of the finest groups */
                int i = (int)((RTR_HISTLEN / RTR_HISTMAX) * rtr_measure(mn, mx, t->val[1][k]));
                histo[i >= RTR_HISTLEN ? RTR_HISTLEN - 1 : i < 0 ? 0 : i]++;
            }
        }
        if (L == 1) {
            if (cull_pct < 0) thr = -1;   /* no reduction */
            else {
                double hsum = floor(cull_pct * .01 * (double)n);
                int i = 0;
                for (; hsum > 0 && i < RTR_HISTLEN; i++) hsum -= (double)histo[i];
                thr = (float)((RTR_HISTMAX / RTR_HISTLEN) * i);
                free(histo);
            }
            for (size_t k = 0; k < n; k++) {
                float mn, mx;
                coords_of(dims, side, k, c);
                grid_range(t, 1, c, &mn, &mx);
                t->leaf[1][k] = (unsigned char)!(rtr_measure(mn, mx, t->val[1][k]) > thr);
            }
        }
        free(pmin);
        free(pmax);
        pmin = vmin;
        pmax = vmax;
    }
    free(pmin);
    free(pmax);
    t->nleaves = count_leaves(t);
    *out = t;
    return HD_OK;
}

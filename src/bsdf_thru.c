/* heliodon — data-cell sizes and the "through" (view / peak) component of a
 * transmitting BSDF, as the aBSDF material uses it (Radiance m_bsdf.c
 * semantics, our own implementation; see docs/design/bsdf.md). */
#include <math.h>
#include <stdlib.h>

#include "bsdf_internal.h"

static hd_vec3 unit(hd_vec3 v)
{
    double l = sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    return l > 0 ? hd_vscale(v, 1 / l) : v;
}

double hd_bsdf_cell_psa(const hd_bsdf *b, hd_vec3 in, hd_vec3 out)
{
    int c = hd_bsdf_comp_of(in, out);
    if (c < 0) return 0;
    const hd_bsdf_block *d = b->src[c];
    if (!d || !d->kind) return 0;
    in = unit(in);
    out = unit(out);
    return b->recip[c] ? hd_block_cell(d, out, in, NULL) : hd_block_cell(d, in, out, NULL);
}

typedef struct probe { double v, psa; uint64_t key; } probe;

static int by_value_desc(const void *p, const void *q)
{
    double a = ((const probe *)p)->v, b = ((const probe *)q)->v;
    return a > b ? -1 : a < b ? 1 : 0;
}

/* Probe the transmission around the straight-through direction -vo on a
 * square grid of spacing 0.6·r (r = √ of the finest projected solid angle
 * of the data) out to 2.4·r, one value per distinct data cell; the
 * brightest cells that are of the finest size and not 8 times darker than
 * the running mean of the peak form the peak, the others the surround. */
int hd_bsdf_find_through(const hd_bsdf *b, hd_vec3 vo, hd_bsdf_through *t)
{
    t->peak = t->surround = t->psa_min = t->psa_peak = 0;
    t->comp = -1;
    vo = unit(vo);
    if (!(fabs(vo.z) > 1e-9)) return 0;
    hd_vec3 td0 = hd_vneg(vo);
    int c = hd_bsdf_comp_of(vo, td0);
    if (c != HD_BSDF_TF && c != HD_BSDF_TB) return 0;
    const hd_bsdf_block *d = b->src[c];
    if (!d || !d->kind || !(d->min_proj_sa > 0)) return 0;
    double r = sqrt(d->min_proj_sa);
    probe pr[64];
    int np = 0;
    for (int i = -4; i <= 4; i++)
        for (int j = -4; j <= 4; j++) {
            if (i * i + j * j > 16) continue;
            hd_vec3 td = hd_v3(td0.x + 0.6 * r * i, td0.y + 0.6 * r * j, td0.z);
            double l2 = td.x * td.x + td.y * td.y;
            if (l2 >= 1) continue;                /* beyond the horizon */
            td = unit(hd_v3(td.x, td.y, td.z));
            uint64_t key = 0;
            double psa = b->recip[c] ? hd_block_cell(d, td, vo, &key) : hd_block_cell(d, vo, td, &key);
            if (!(psa > 0)) continue;
            int dup = 0;
            for (int k = 0; k < np && !dup; k++) dup = pr[k].key == key;
            if (dup) continue;
            pr[np].v = hd_bsdf_eval_comp(b, (hd_bsdf_comp)c, vo, td, 1);
            pr[np].psa = psa;
            pr[np].key = key;
            np++;
        }
    if (!np) return 0;
    qsort(pr, (size_t)np, sizeof *pr, by_value_desc);
    if (!(pr[0].v > 1e-9)) return 0;
    double vsum = 0, peak = 0, psa_p = 0, surr = 0, psa_s = 0, psa_min = HUGE_VAL;
    int ns = 0;
    for (int k = 0; k < np; k++) {
        if (pr[k].psa > 1.5 * d->min_proj_sa || vsum > 8 * pr[k].v * ns) {
            if (k == 0) return 0;                 /* the brightest cell is not fine: no peak */
            surr += pr[k].v * pr[k].psa;
            psa_s += pr[k].psa;
            continue;
        }
        peak += pr[k].v * pr[k].psa;
        psa_p += pr[k].psa;
        if (pr[k].psa < psa_min) psa_min = pr[k].psa;
        vsum += pr[k].v;
        ns++;
    }
    if (psa_s < 0.2 * psa_p) return 0;            /* not enough surround to tell a peak */
    double lam = b->lamb[c] / HD_PI;
    surr = surr / psa_s - lam;
    peak -= psa_p * lam;
    if (surr < 0) surr = 0;
    if (peak < 0.0005) return 0;                  /* under 0.05 %: no view component */
    t->peak = peak;
    t->surround = surr;
    t->psa_min = d->min_proj_sa;
    t->psa_peak = psa_min;
    t->comp = c;
    return 1;
}

double hd_bsdf_through_direct(const hd_bsdf *b, const hd_bsdf_through *t, hd_vec3 vo, hd_vec3 li,
                              double omega)
{
    vo = unit(vo);
    li = unit(li);
    if (t && t->peak > 0 && (li.z > 0) != (vo.z > 0)) {
        double dx = li.x + vo.x, dy = li.y + vo.y;
        double tom = omega * fabs(li.z);
        if (dx * dx + dy * dy <= 2.5 * 4 / HD_PI * (tom + t->psa_min + 2 * sqrt(tom * t->psa_min)))
            return t->surround + b->lamb[t->comp] / HD_PI;
    }
    return hd_bsdf_eval(b, li, vo);
}

int hd_bsdf_through_excludes(const hd_bsdf_through *t, hd_vec3 vo, hd_vec3 dir)
{
    if (!t || !(t->peak > 0)) return 0;
    vo = unit(vo);
    dir = unit(dir);
    if ((dir.z > 0) == (vo.z > 0)) return 0;      /* reflection: never */
    double dx = dir.x + vo.x, dy = dir.y + vo.y;
    return dx * dx + dy * dy <= t->psa_peak;
}

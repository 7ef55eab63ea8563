/* heliodon — rcontrib contribution tracer (see contrib.h).
 *
 * The path is followed forwards from the receiver of the record (sensor,
 * pixel, sender sample) carrying the product of the scattering
 * coefficients ("coef", RGB); whenever it reaches a tracked emitter the
 * coefficient (times the emitted radiance with -V+) is added to that
 * modifier's bin.  The sampling mirrors Radiance's -aa 0 ambient
 * calculation and ray-weight admission, so the expectation equals
 * rcontrib's result with the same -ab/-lw/-lr. */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/contrib.h"
#include "walk.h"

static void tally(const hd_contrib *c, int mod, const hd_tmat *m, hd_vec3 D, const double coef[3],
                  hd_rng *rng, double *acc)
{
    const hd_cmod *cm = &c->mods[mod];
    double j1 = 0.5, j2 = 0.5;
    if (cm->bin.jtr > 0) { j1 = hd_rng_uniform(rng); j2 = hd_rng_uniform(rng); }
    int bin = hd_binfn_eval(&cm->bin, D, j1, j2);
    if (bin < 0) return;
    double *a = acc + 3 * (size_t)(cm->first + bin);
    if (c->vflag) {
        double L[3];
        hd_emit_color(m, D, NULL, L);
        for (int i = 0; i < 3; i++) a[i] += coef[i] * L[i];
    } else {
        for (int i = 0; i < 3; i++) a[i] += coef[i];
    }
}

/* ---- the coefficient sink of the walk (walk.c) ---- */
typedef struct csink {
    const hd_contrib *c;
    double *acc;
} csink;

/* light reaching the walk from emitter surf: its coefficient (× the
 * emitted radiance with -V+) into the bin of its modifier, if tracked */
static void add_coef(void *ctx, int surf, const hd_tmat *m, hd_vec3 dir, const hd_hit *h, const double L[3],
                     const double k[3], hd_rng *rng)
{
    (void)h; (void)L;
    const csink *x = ctx;
    if (surf < 0) return;
    int mod = x->c->matmod[hd_tscene_surface(x->c->ts, surf)->mat];
    if (mod >= 0) tally(x->c, mod, m, dir, k, rng, x->acc);
}

hd_status hd_contrib_ray(const hd_contrib *c, hd_vec3 org, hd_vec3 dir, double tmax, int irrad,
                         hd_rng *rng, double scale, double *acc)
{
    double len = hd_vlen(dir);
    if (!(len > 0)) return HD_OK;
    dir = hd_vscale(dir, 1 / len);
    csink x = {c, acc};
    hd_walk w = {c->ts, c->o, c->lights, c->nlights, c->dn, c->counts, 1, 0, add_coef, &x, NULL};
    double k3[3] = {scale, scale, scale};
    return hd_walk_ray(&w, org, dir, tmax, irrad, k3, rng, NULL);
}

hd_status hd_contrib_prepare(hd_contrib *c)
{
    const hd_tscene *s = c->ts;
    c->ncols = 0;
    for (int i = 0; i < c->nmods; i++) {
        for (int j = 0; j < i; j++)
            if (!strcmp(c->mods[i].name, c->mods[j].name))
                return hd_fail(HD_ERR_USAGE, "modifier '%s' is given more than once", c->mods[i].name);
        if (!strcmp(c->mods[i].name, "void"))
            return hd_fail(HD_ERR_USAGE, "modifier 'void' cannot be tracked");
        c->mods[i].first = c->ncols;
        c->ncols += c->mods[i].bin.nbins;
    }
    if (c->nmods == 0) return hd_fail(HD_ERR_USAGE, "no modifiers given (-m or -M)");
    c->nmat = hd_tscene_nmaterials(s);
    free(c->matmod);
    c->matmod = hd_malloc_array((size_t)(c->nmat > 0 ? c->nmat : 1), sizeof *c->matmod);
    if (!c->matmod) return HD_ERR_NOMEM;
    int *used = hd_calloc((size_t)c->nmods, sizeof *used);
    if (!used) return HD_ERR_NOMEM;
    for (int k = 0; k < c->nmat; k++) {
        const hd_tmat *m = hd_tscene_material(s, k);
        c->matmod[k] = -1;
        for (int i = 0; i < c->nmods; i++)
            if (!strcmp(m->name, c->mods[i].name)) { c->matmod[k] = i; break; }
    }
    int ns = hd_tscene_nsurfaces(s);
    for (int k = 0; k < ns; k++) {
        int mod = c->matmod[hd_tscene_surface(s, k)->mat];
        if (mod >= 0) used[mod] = 1;
    }
    for (int i = 0; i < c->nmods; i++)
        if (!used[i]) {
            free(used);
            return hd_fail(HD_ERR_USAGE, "unknown modifier '%s': no surface of the scene uses it", c->mods[i].name);
        }
    free(used);
    free(c->lights);
    c->lights = NULL;
    c->nlights = 0;
    free(c->counts);
    c->counts = NULL;
    if (c->dn < 0) return hd_fail(HD_ERR_USAGE, "-dn %d: must not be negative", c->dn);
    if (c->stats) {
        c->counts = hd_calloc(1, sizeof *c->counts);
        if (!c->counts) return HD_ERR_NOMEM;
    }
    int nl = hd_tscene_nlights(s);
    if (nl > 0) {
        c->lights = hd_malloc_array((size_t)nl, sizeof *c->lights);
        if (!c->lights) return HD_ERR_NOMEM;
        for (int k = 0; k < nl; k++) {
            int si = hd_tscene_light(s, k);
            const hd_surface *f = hd_tscene_surface(s, si);
            if (c->matmod[f->mat] < 0) continue;
            if (f->kind != HD_SURF_SOURCE && f->kind != HD_SURF_POLYGON && f->kind != HD_SURF_RING) {
                hd_warn("%s: tracked light source of this shape is reached by sampled rays only", f->where);
                continue;
            }
            c->lights[c->nlights++] = si;
        }
    }
    return HD_OK;
}

void hd_contrib_free(hd_contrib *c)
{
    for (int i = 0; i < c->nmods; i++) {
        hd_binfn_free(&c->mods[i].bin);
        free(c->mods[i].outspec);
    }
    free(c->mods);
    free(c->matmod);
    free(c->lights);
    free(c->counts);
    memset(c, 0, sizeof *c);
}

void hd_contrib_print_stats(const hd_contrib *c, FILE *f)
{
    if (!c->counts) return;
    const struct hd_contrib_counts *k = c->counts;
    fprintf(f, "%s: stats: %d tracked direct sources (-dn %d); vertices sampling them: %llu before, %llu after a "
            "diffuse bounce; sources sampled there: %llu before, %llu after; shadow rays %llu\n", hd_progname(),
            c->nlights, c->dn, (unsigned long long)atomic_load(&k->vert0), (unsigned long long)atomic_load(&k->vert1),
            (unsigned long long)atomic_load(&k->sampled0), (unsigned long long)atomic_load(&k->sampled1),
            (unsigned long long)atomic_load(&k->shadows));
}

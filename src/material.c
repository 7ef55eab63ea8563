/* heliodon — material parameters and reflection formulas (Radiance
 * semantics, our own implementation). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/cal.h"
#include "heliodon/material.h"

#define FTINY 1e-6   /* Radiance's FTINY (double build): the thresholds of normal.c */
#define FRESTHRESH 0.017999    /* minimum specularity for the Fresnel approximation */

void hd_tmat_init(hd_tmat *m, hd_mtype type, const char *name)
{
    memset(m, 0, sizeof *m);
    m->type = type;
    m->alt = -1;
    m->rindex = 1.52;
    snprintf(m->name, sizeof m->name, "%s", name ? name : "");
}

static hd_status badargs(const char *where, const char *type, const char *name, const char *expect, int got)
{
    return hd_fail(HD_ERR_FORMAT, "%s: %s %s: expected %s real arguments, got %d",
                   where, type, name, expect, got);
}

hd_status hd_tmat_from_args(hd_tmat *m, const char *type, const char *name,
                                const double *r, int nr, int nstrings, const char *where)
{
    hd_tmat_init(m, HD_MAT_PLASTIC, name);
    snprintf(m->where, sizeof m->where, "%s", where ? where : "?");
    if (!strcmp(type, "plastic") || !strcmp(type, "metal")) {
        m->type = type[0] == 'p' ? HD_MAT_PLASTIC : HD_MAT_METAL;
        if (nr != 5) return badargs(where, type, name, "5", nr);
        for (int i = 0; i < 3; i++) m->color[i] = r[i];
        m->spec = r[3];
        m->rough = r[4];
    } else if (!strcmp(type, "trans")) {
        m->type = HD_MAT_TRANS;
        if (nr != 7) return badargs(where, type, name, "7", nr);
        for (int i = 0; i < 3; i++) m->color[i] = r[i];
        m->spec = r[3];
        m->rough = r[4];
        m->trans = r[5];
        m->tspec = r[6];
    } else if (!strcmp(type, "glass")) {
        m->type = HD_MAT_GLASS;
        if (nr != 3 && nr != 4) return badargs(where, type, name, "3 or 4", nr);
        for (int i = 0; i < 3; i++) m->color[i] = r[i];
        if (nr == 4) m->rindex = r[3];
        if (m->rindex <= 0) return hd_fail(HD_ERR_FORMAT, "%s: glass %s: refractive index must be positive", where, name);
    } else if (!strcmp(type, "mirror")) {
        m->type = HD_MAT_MIRROR;
        if (nr != 3) return badargs(where, type, name, "3", nr);
        for (int i = 0; i < 3; i++) m->color[i] = r[i];
    } else if (!strcmp(type, "light") || !strcmp(type, "illum")) {
        m->type = type[0] == 'l' ? HD_MAT_LIGHT : HD_MAT_ILLUM;
        if (nr != 3) return badargs(where, type, name, "3", nr);
        for (int i = 0; i < 3; i++) m->color[i] = r[i];
    } else if (!strcmp(type, "glow")) {
        m->type = HD_MAT_GLOW;
        if (nr != 4) return badargs(where, type, name, "4", nr);
        for (int i = 0; i < 3; i++) m->color[i] = r[i];
        m->maxrad = r[3];
    } else {
        return hd_fail(HD_ERR_UNSUPPORTED, "%s: material type '%s' (%s) is not supported by the ray tracer",
                       where, type, name);
    }
    (void)nstrings;
    if (m->type == HD_MAT_PLASTIC || m->type == HD_MAT_METAL || m->type == HD_MAT_TRANS) {
        if (m->spec < 0 || m->spec > 1 || m->rough < 0)
            return hd_fail(HD_ERR_FORMAT, "%s: %s %s: specularity must be in [0,1] and roughness >= 0",
                           where, type, name);
        if (m->type == HD_MAT_TRANS && (m->trans < 0 || m->trans > 1 || m->tspec < 0 || m->tspec > 1))
            return hd_fail(HD_ERR_FORMAT, "%s: trans %s: transmission values must be in [0,1]", where, name);
    }
    return HD_OK;
}

hd_status hd_tmat_set_pattern(hd_tmat *m, const char *funcname, const char *calfile,
                                  const double *r, int nr, const char *where)
{
    const char *base = strrchr(calfile, '/');
    base = base ? base + 1 : calfile;
    if (!strcmp(base, "perezlum.cal") && !strcmp(funcname, "skybright")) {
        if (nr != 10)
            return hd_fail(HD_ERR_FORMAT, "%s: brightfunc %s perezlum.cal: expected 10 real arguments, got %d",
                           where, funcname, nr);
        m->pattern = HD_PAT_PEREZ;
    } else if (!strcmp(base, "skybright.cal") && !strcmp(funcname, "skybr")) {
        /* gensky writes 7 reals for skies with a sun direction, 3 for the
         * overcast and uniform skies (type, zenith, ground) */
        if (nr != 7 && !(nr == 3 && (r[0] == 2 || r[0] == 3)))
            return hd_fail(HD_ERR_FORMAT, "%s: brightfunc %s skybright.cal: expected 7 real arguments "
                           "(3 for the overcast and uniform skies), got %d", where, funcname, nr);
        if (r[0] != 1 && r[0] != 2 && r[0] != 3)
            return hd_fail(HD_ERR_UNSUPPORTED,
                           "%s: skybright.cal sky type %g is not supported (only 1 clear, 2 overcast, 3 uniform)",
                           where, r[0]);
        m->pattern = HD_PAT_SKYBRIGHT;
    } else {
        return hd_fail(HD_ERR_UNSUPPORTED,
                       "%s: brightfunc '%s' from '%s' is not supported (only perezlum.cal skybright and "
                       "skybright.cal skybr are evaluated)", where, funcname, calfile);
    }
    m->npattern = nr;
    for (int i = 0; i < nr; i++) m->parg[i] = r[i];
    return HD_OK;
}

double hd_perezlum(const double *a, hd_vec3 d)
{
    double cg = hd_clamp(d.x * a[7] + d.y * a[8] + d.z * a[9], -1, 1);
    double g = acos(cg);
    double dz = d.z < 0.01 ? 0.01 : d.z;
    double sky = a[0] * (1 + a[2] * exp(a[3] / dz)) * (1 + a[4] * exp(a[5] * g) + a[6] * cg * cg);
    double w1 = pow(d.z + 1.01, 10), w2 = pow(d.z + 1.01, -10);
    return (w1 * sky + w2 * a[1]) / (w1 + w2);
}

double hd_skybright(const double *a, hd_vec3 d)
{
    double dz = d.z < 0.01 ? 0.01 : d.z, sky;
    switch ((int)a[0]) {
    case 1: {
        double cg = hd_clamp(d.x * a[4] + d.y * a[5] + d.z * a[6], -1, 1), g = acos(cg);
        sky = a[1] / a[3] * (0.91 + 10 * exp(-3 * g) + 0.45 * cg * cg) * (1 - exp(-0.32 / dz));
        break;
    }
    case 2: sky = a[1] * (1 + 2 * dz) / 3; break;
    default: sky = a[1]; break;
    }
    double w1 = pow(d.z + 1.01, 10), w2 = pow(d.z + 1.01, -10);
    return (w1 * sky + w2 * a[2]) / (w1 + w2);
}

/* Whether the function file `name` found through RAYPATH (as the .cal
 * module would load it) is byte for byte heliodon's own library copy. */
static int same_as_library(const char *name)
{
    char a[4096], b[4096];
    if (!hd_cal_findfile(name, a, sizeof a) || !hd_cal_libfile(name, b, sizeof b)) return 0;
    if (!strcmp(a, b)) return 1;
    FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
    int same = fa && fb;
    while (same) {
        int ca = getc(fa), cb = getc(fb);
        if (ca != cb) same = 0;
        if (ca == EOF || cb == EOF) break;
    }
    if (fa) fclose(fa);
    if (fb) fclose(fb);
    return same;
}

hd_status hd_tmat_set_brightfunc(hd_tmat *m, char *const *sargs, int ns, const double *r, int nr,
                                 const char *where)
{
    if (ns < 2) return hd_fail(HD_ERR_FORMAT, "%s: brightfunc: expected a variable and a function file", where);
    const char *force = getenv("HELIODON_SKY_CAL");
    /* the sky functions are ordinary .cal evaluations of the file found
     * through RAYPATH; when that file is heliodon's own (lib/perezlum.cal,
     * lib/skybright.cal), the same function is computed by the equivalent
     * C (identical values, 1.16x - 2.5x faster rtrace: docs/benchmarks.md) */
    int native = ns == 2 && !(force && force[0] == '1') &&
                 ((!strcmp(sargs[1], "perezlum.cal") && !strcmp(sargs[0], "skybright")) ||
                  (!strcmp(sargs[1], "skybright.cal") && !strcmp(sargs[0], "skybr"))) &&
                 same_as_library(sargs[1]);
    if (native) return hd_tmat_set_pattern(m, sargs[0], sargs[1], r, nr, where);
    struct hd_modset *ms = hd_modset_new();
    if (!ms) return HD_ERR_NOMEM;
    struct hd_modnode *nd;
    const struct hd_modchain *ch;
    hd_status st = hd_modset_node(ms, "brightfunc", sargs, ns, r, nr, where, &nd);
    if (!st) st = hd_modset_chain(ms, &nd, 1, &ch);
    if (st) { hd_modset_free(ms); return st; }
    m->ownmods = ms;
    m->chain = ch;
    m->pattern = HD_PAT_CAL;
    m->npattern = nr;
    return HD_OK;
}

double hd_pattern_eval(const hd_tmat *m, hd_vec3 dir)
{
    switch (m->pattern) {
    case HD_PAT_PEREZ: return hd_perezlum(m->parg, dir);
    case HD_PAT_SKYBRIGHT: return hd_skybright(m->parg, dir);
    case HD_PAT_CAL: {
        hd_modray ray = {dir, {0, 0, 0}, {0, 0, 0}, 0, NULL, 0};
        double pc[3] = {1, 1, 1};
        hd_vec3 pert = {0, 0, 0};
        hd_modchain_eval(m->chain, &ray, pc, &pert, NULL, NULL);
        return pc[0];
    }
    default: return 1.0;
    }
}

void hd_normal_coeffs(const hd_tmat *m, double cosi, hd_nshade *ns)
{
    memset(ns, 0, sizeof *ns);
    ns->rspec = m->spec;
    ns->alpha2 = m->rough * m->rough;
    ns->pure = ns->alpha2 <= FTINY;
    for (int i = 0; i < 3; i++)
        ns->scol[i] = (m->type == HD_MAT_METAL ? m->color[i] : 1.0) * m->spec;
    if (ns->pure && ns->rspec >= FRESTHRESH) {
        double f = exp(-5.85 * cosi) - 0.00287989916;
        for (int i = 0; i < 3; i++) ns->scol[i] += (1 - ns->scol[i]) * f;
        ns->rspec += (1 - ns->rspec) * f;
    }
    double trans = 0, tspec = 0, tdiff = 0;
    if (m->type == HD_MAT_TRANS) {
        trans = m->trans * (1 - ns->rspec);
        tspec = trans * m->tspec;
        tdiff = trans - tspec;
    }
    ns->tspec = tspec;
    ns->tds = tdiff;
    double rd = 1 - trans - ns->rspec;
    if (rd < 0) rd = 0;
    ns->rds = rd;
    for (int i = 0; i < 3; i++) {
        ns->rdiff[i] = m->color[i] * rd;
        ns->tdiff[i] = m->color[i] * tdiff;
        ns->tscol[i] = m->color[i] * tspec;
    }
}

double hd_specular_gauss(hd_vec3 n, hd_vec3 v, hd_vec3 l, double a2)
{
    hd_vec3 h = hd_vsub(l, v);
    double hn = hd_vdot(h, n), hn2 = hn * hn, h2 = hd_vdot(h, h);
    if (hn2 <= 1e-30 || a2 <= 1e-30) return 0;
    double tan2 = (h2 - hn2) / hn2;
    return exp(-tan2 / a2) * h2 / (HD_PI * hn2 * hn2 * a2);
}

double hd_specular_lobe(hd_vec3 n, hd_vec3 v, hd_vec3 l, double alpha2, double omega)
{
    double ldot = hd_vdot(n, l);
    if (ldot <= FTINY) return 0;
    return hd_specular_gauss(n, v, l, alpha2 + omega / (4 * HD_PI)) * ldot * omega;
}

int hd_specular_sample(hd_vec3 n, hd_vec3 v, double alpha2, double u1, double u2, hd_vec3 *out)
{
    hd_vec3 bu, bv;
    hd_vbasis(n, &bu, &bv);
    double t = sqrt(-alpha2 * log(1 - u1 < 1e-300 ? 1e-300 : 1 - u1));
    double ph = 2 * HD_PI * u2;
    hd_vec3 h = hd_vnorm(hd_vadd(n, hd_vadd(hd_vscale(bu, t * cos(ph)), hd_vscale(bv, t * sin(ph)))));
    double d = hd_vdot(v, h);
    hd_vec3 r = hd_vsub(v, hd_vscale(h, 2 * d));
    if (hd_vdot(r, n) <= FTINY) return 0;
    *out = hd_vnorm(r);
    return 1;
}

void hd_glass_coeffs(const double tn[3], double rindex, double cosi, double refl[3], double trans[3])
{
    double n = rindex, c1 = cosi;
    if (c1 < 1e-9) c1 = 1e-9;
    double c2 = sqrt(1 - (1 - c1 * c1) / (n * n));
    double re = (c1 - n * c2) / (c1 + n * c2);
    re *= re;
    double rm = (1 / c1 - n / c2) / (1 / c1 + n / c2);
    rm *= rm;
    for (int i = 0; i < 3; i++) {
        /* grey glass: a channel equal to the previous one copies its results
         * (the same expressions of the same values) */
        if (i > 0 && tn[i] == tn[i - 1]) {
            trans[i] = trans[i - 1];
            refl[i] = refl[i - 1];
            continue;
        }
        double d = tn[i] > 0 ? pow(tn[i], 1 / c2) : 0;
        double d2 = d * d;
        trans[i] = 0.5 * (1 - re) * (1 - re) * d / (1 - re * re * d2)
                 + 0.5 * (1 - rm) * (1 - rm) * d / (1 - rm * rm * d2);
        refl[i] = 0.5 * re * (1 + (1 - 2 * re) * d2) / (1 - re * re * d2)
                + 0.5 * rm * (1 + (1 - 2 * rm) * d2) / (1 - rm * rm * d2);
    }
}

double hd_glass_transmissivity(double Tn)
{
    if (Tn <= 0) return 0;
    return (sqrt(0.8402528435 + 0.0072522239 * Tn * Tn) - 0.9166530661) / 0.0036261119 / Tn;
}

/* heliodon — the BSDF and aBSDF scene materials: argument parsing and data
 * file resolution (the shading is in walk.c and scatter.c, the XML module in bsdf*.c).
 * Radiance semantics; our own implementation. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "heliodon/bsdf.h"
#include "heliodon/io.h"
#include "heliodon/material.h"
#include "scatter.h"
#include "heliodon/xform.h"

/* Resolve a data file as Radiance's getpath does with its library path:
 * absolute paths as they are; else the current directory, the directory
 * of the scene file that names it, then each RAYPATH entry. */
static int resolve(const char *file, const char *scenefile, char *out, size_t cap)
{
    if (hd_find_in_path("", file, out, cap)) return 1;
    if (file[0] == '/') return 0;
    if (scenefile && scenefile[0] != '!' && strcmp(scenefile, "-")) {
        const char *sl = strrchr(scenefile, '/');
        if (sl) {
            int n = snprintf(out, cap, "%.*s/%s", (int)(sl - scenefile), scenefile, file);
            if (n > 0 && (size_t)n < cap && access(out, R_OK) == 0) return 1;
        }
    }
    const char *rp = getenv("RAYPATH");
    return rp && hd_find_in_path(rp, file, out, cap);
}

hd_status hd_tmat_bsdf_args(hd_tmat *m, int absdf, const char *name, char *const *sargs, int ns,
                            const double *r, int nr, const char *scenefile, const char *where,
                            char *path, size_t cap)
{
    hd_tmat_init(m, HD_MAT_BSDF, name);
    snprintf(m->where, sizeof m->where, "%s", where ? where : "?");
    m->absdf = absdf;
    int need = absdf ? 5 : 6;
    if (ns < need)
        return hd_fail(HD_ERR_FORMAT, "%s: expected at least %d string arguments (%sfile ux uy uz funcfile), got %d",
                       where, need, absdf ? "" : "thickness ", ns);
    if (nr != 0 && nr != 3 && nr != 6 && nr != 9)
        return hd_fail(HD_ERR_FORMAT, "%s: expected 0, 3, 6 or 9 real arguments, got %d", where, nr);
    int k = 0;
    if (!absdf) {
        if (hd_parse_double(sargs[k], &m->thick))
            return hd_fail(HD_ERR_UNSUPPORTED, "%s: thickness '%s' is not a number (expressions from a "
                           "function file are not supported)", where, sargs[k]);
        k++;
    }
    const char *file = sargs[k++];
    double u[3];
    for (int i = 0; i < 3; i++)
        if (hd_parse_double(sargs[k + i], &u[i]))
            return hd_fail(HD_ERR_UNSUPPORTED, "%s: up vector component '%s' is not a number (variables "
                           "from a function file are not supported)", where, sargs[k + i]);
    k += 3;
    m->up = hd_v3(u[0], u[1], u[2]);
    if (hd_vlen(m->up) <= 0)
        return hd_fail(HD_ERR_FORMAT, "%s: zero up vector", where);
    k++;   /* funcfile: only numeric arguments are used, so its variables are not needed */
    if (k < ns) {   /* transform (as xform appends): applies to the up vector */
        hd_xf xf;
        hd_status st = hd_xf_from_words(&xf, ns - k, sargs + k);
        if (st != HD_OK)
            return hd_fail(HD_ERR_FORMAT, "%s: bad transform after the function file", where);
        m->up = hd_xf_direction(&xf, m->up);
        m->thick *= xf.sca;   /* as Radiance: the thickness scales with the object */
    }
    for (int i = 0; i < 3; i++) {
        m->bsdf_rfront[i] = nr >= 3 ? r[i] : 0;
        m->bsdf_rback[i] = nr >= 6 ? r[3 + i] : 0;
        m->bsdf_tdiff[i] = nr >= 9 ? r[6 + i] : 0;
    }
    for (int i = 0; i < nr; i++)
        if (r[i] < 0 || r[i] > 1)
            return hd_fail(HD_ERR_FORMAT, "%s: extra diffuse coefficients must be in [0,1]", where);
    if (!resolve(file, scenefile, path, cap))
        return hd_fail(HD_ERR_IO, "%s: cannot find BSDF file '%s' (searched the current directory, the "
                       "scene file's directory and RAYPATH)", where, file);
    return HD_OK;
}

void hd_tmat_release(hd_tmat *m)
{
    if (m->type == HD_MAT_BSDF && m->bsdf_owner && m->bsdf) { hd_bsdf_free(m->bsdf); hd_scatter_forget_bsdfs(); }
    m->bsdf = NULL;
    m->bsdf_owner = 0;
    hd_modset_free(m->ownmods);          /* a brightfunc's own .cal evaluation */
    m->ownmods = NULL;
    m->chain = NULL;
}

/* ---- BSDF / aBSDF shading helpers for the integrators (Radiance m_bsdf.c
 * semantics: thickness makes a proxy, aBSDF separates a through part) ---- */

int hd_tmat_bsdf_frame(const hd_tmat *m, hd_vec3 n, hd_vec3 *x, hd_vec3 *y, hd_vec3 *z)
{
    if (hd_klems_frame(n, m->up, x, y, z) == 0) return 0;
    *z = hd_vnorm(n);
    hd_vbasis(*z, x, y);
    return -1;
}

int hd_tmat_bsdf_passes(const hd_tmat *m, int ray_kind, int hit_front)
{
    if (m->type != HD_MAT_BSDF || m->absdf || m->thick == 0) return 0;
    if (ray_kind != HD_BSDF_RAY_SCATTERED) return 1;
    return (m->thick > 0) != (hit_front != 0);
}

hd_vec3 hd_tmat_bsdf_through_origin(const hd_tmat *m, hd_vec3 p, hd_vec3 n)
{
    if (m->type != HD_MAT_BSDF || m->absdf || m->thick == 0) return p;
    return hd_vmadd(p, hd_vnorm(n), -m->thick);
}

static hd_vec3 bsdf_local(hd_vec3 v, hd_vec3 x, hd_vec3 y, hd_vec3 z)
{
    return hd_v3(hd_vdot(v, x), hd_vdot(v, y), hd_vdot(v, z));
}

int hd_tmat_bsdf_through(const hd_tmat *m, hd_vec3 n, hd_vec3 dir, hd_bsdf_through *t)
{
    t->peak = t->surround = t->psa_min = t->psa_peak = 0;
    t->comp = -1;
    if (m->type != HD_MAT_BSDF || !m->absdf || !m->bsdf) return 0;
    hd_vec3 x, y, z;
    if (hd_tmat_bsdf_frame(m, n, &x, &y, &z)) return 0;
    return hd_bsdf_find_through(m->bsdf, bsdf_local(hd_vneg(dir), x, y, z), t);
}

int hd_tmat_bsdf_shadow(const hd_tmat *m, hd_vec3 n, hd_vec3 dir, double tr[3])
{
    tr[0] = tr[1] = tr[2] = 0;
    if (m->type != HD_MAT_BSDF) return 0;
    if (!m->absdf) {
        if (m->thick == 0) return 0;      /* the surface itself scatters the source */
        tr[0] = tr[1] = tr[2] = 1;        /* proxy: the detailed geometry decides */
        return 1;
    }
    hd_bsdf_through t;
    if (!hd_tmat_bsdf_through(m, n, dir, &t)) return 0;
    tr[0] = tr[1] = tr[2] = t.peak;
    return 1;
}

/* heliodon — build a trace scene from a parsed Radiance scene. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/bsdf.h"
#include "heliodon/scene.h"
#include "heliodon/trace.h"

typedef struct matkey { int32_t mat, pat; int idx; } matkey;

typedef struct loadedbsdf { char *path; hd_bsdf *b; } loadedbsdf;

typedef struct builder {
    const hd_scene *sc;
    hd_tscene *ts;
    matkey *keys;
    int nkeys, capkeys;
    loadedbsdf *bsdfs;    /* XML files loaded so far (each once per scene) */
    int nbsdfs, capbsdfs;
} builder;

static const char *where_of(const builder *b, int32_t i, char *buf, size_t cap)
{
    char w[200];
    const hd_prim *p = &b->sc->prims[i];
    hd_prim_where(b->sc, i, w, sizeof w);
    snprintf(buf, cap, "%s: %s %s", w, hd_type_name(p->type), p->id ? p->id : "?");
    return buf;
}

static hd_status convert_material(builder *b, int32_t mi, int32_t pi, int *out);

/* Resolve the alternate material of illum/mirror (string argument 1). */
static hd_status resolve_alt(builder *b, int32_t mi, hd_tmat *m)
{
    const hd_prim *p = &b->sc->prims[mi];
    m->alt = -1;
    if (p->nsargs < 1 || !strcmp(p->sargs[0], "void")) {
        if (m->type == HD_MAT_ILLUM) return HD_OK;
        return HD_OK;
    }
    int32_t a = -1;
    for (int32_t k = mi - 1; k >= 0; k--) {
        const hd_prim *q = &b->sc->prims[k];
        if (q->id && !strcmp(q->id, p->sargs[0]) && hd_type_is_modifier(q->type)) { a = k; break; }
    }
    char w[300];
    where_of(b, mi, w, sizeof w);
    if (a < 0) return hd_fail(HD_ERR_FORMAT, "%s: alternate material '%s' is not defined", w, p->sargs[0]);
    a = hd_scene_unalias(b->sc, a);
    int idx;
    hd_status st = convert_material(b, a, -1, &idx);
    if (st != HD_OK) return st;
    hd_mtype at = hd_tscene_material(b->ts, idx)->type;
    if (at != HD_MAT_PLASTIC && at != HD_MAT_METAL && at != HD_MAT_TRANS) {
        hd_warn("%s: alternate material '%s' is not plastic, metal or trans: the illum is rendered invisible",
                w, p->sargs[0]);
        idx = -1;
    }
    m->alt = idx;
    return HD_OK;
}

/* BSDF / aBSDF: arguments, then the XML data, loaded once per resolved
 * path and shared (the first material using it owns it). */
static hd_status bsdf_material(builder *b, const hd_prim *p, const char *w, hd_tmat *m)
{
    char path[4096];
    const char *scenefile = p->file < b->sc->nfiles ? b->sc->files[p->file].name : NULL;
    hd_status st = hd_tmat_bsdf_args(m, p->type == HD_T_ABSDF, p->id ? p->id : "?", p->sargs, (int)p->nsargs,
                                     p->rargs, (int)p->nrargs, scenefile, w, path, sizeof path);
    if (st != HD_OK) return st;
    for (int k = 0; k < b->nbsdfs; k++)
        if (!strcmp(b->bsdfs[k].path, path)) { m->bsdf = b->bsdfs[k].b; return HD_OK; }
    hd_bsdf *bd;
    st = hd_bsdf_load(path, &bd);
    if (st != HD_OK) return hd_fail_context(st, "%s", w);
    if (b->nbsdfs == b->capbsdfs) {
        int nc = b->capbsdfs ? 2 * b->capbsdfs : 8;
        loadedbsdf *nl = hd_realloc_array(b->bsdfs, (size_t)nc, sizeof *nl);
        if (!nl) { hd_bsdf_free(bd); return HD_ERR_NOMEM; }
        b->bsdfs = nl;
        b->capbsdfs = nc;
    }
    size_t len = strlen(path) + 1;
    char *cp = hd_malloc(len);
    if (!cp) { hd_bsdf_free(bd); return HD_ERR_NOMEM; }
    memcpy(cp, path, len);
    b->bsdfs[b->nbsdfs].path = cp;
    b->bsdfs[b->nbsdfs].b = bd;
    b->nbsdfs++;
    m->bsdf = bd;
    m->bsdf_owner = 1;
    return HD_OK;
}

static hd_status convert_material(builder *b, int32_t mi, int32_t pi, int *out)
{
    for (int k = 0; k < b->nkeys; k++)
        if (b->keys[k].mat == mi && b->keys[k].pat == pi) { *out = b->keys[k].idx; return HD_OK; }
    const hd_prim *p = &b->sc->prims[mi];
    char w[300];
    where_of(b, mi, w, sizeof w);
    hd_tmat m;
    hd_status st;
    if (p->type == HD_T_BSDF || p->type == HD_T_ABSDF) {
        st = bsdf_material(b, p, w, &m);
        if (st != HD_OK) return st;
        goto add;
    }
    st = hd_tmat_from_args(&m, hd_type_name(p->type), p->id ? p->id : "?", p->rargs,
                                     (int)p->nrargs, (int)p->nsargs, w);
    if (st != HD_OK) return st;
    if (m.type == HD_MAT_ILLUM || m.type == HD_MAT_MIRROR) {
        if (m.type == HD_MAT_MIRROR && p->nsargs >= 1)
            hd_warn("%s: the alternate material of mirror is ignored (mirror reflection is used for every ray)", w);
        if (m.type == HD_MAT_ILLUM) {
            st = resolve_alt(b, mi, &m);
            if (st != HD_OK) return st;
        }
    }
    if (pi >= 0) {
        const hd_prim *q = &b->sc->prims[pi];
        char wq[300];
        where_of(b, pi, wq, sizeof wq);
        if (!hd_tmat_emits(&m)) {
            hd_warn("%s: pattern on a non-emitting material %s is not supported and is ignored", wq, p->id);
        } else {
            st = hd_tmat_set_brightfunc(&m, q->sargs, (int)q->nsargs, q->rargs, (int)q->nrargs, wq);
            if (st != HD_OK) return st;
        }
    }
add:;
    int idx = hd_tscene_add_material(b->ts, &m);
    if (idx < 0) return HD_ERR_NOMEM;   /* BSDF data freed with the builder */
    if (b->nkeys == b->capkeys) {
        int nc = b->capkeys ? 2 * b->capkeys : 32;
        matkey *nk = hd_realloc_array(b->keys, (size_t)nc, sizeof *nk);
        if (!nk) return HD_ERR_NOMEM;
        b->keys = nk;
        b->capkeys = nc;
    }
    b->keys[b->nkeys].mat = mi;
    b->keys[b->nkeys].pat = pi;
    b->keys[b->nkeys].idx = idx;
    b->nkeys++;
    *out = idx;
    return HD_OK;
}

/* Walk the modifier chain of surface si: the first material, at most one
 * brightfunc pattern.  *mat = -1 for void. */
static hd_status resolve_chain(builder *b, int32_t si, int32_t *mat, int32_t *pat)
{
    const hd_scene *sc = b->sc;
    int32_t m = sc->prims[si].modifier;
    *mat = -1;
    *pat = -1;
    char w[300];
    for (int guard = 0; m >= 0 && guard < 10000; guard++) {
        int32_t u = hd_scene_unalias(sc, m);
        const hd_prim *p = &sc->prims[u];
        switch (hd_type_class_of(p->type)) {
        case HD_CLASS_MATERIAL:
            if (*mat < 0) *mat = u;
            else if (p->type != HD_T_ANTIMATTER)
                hd_warn("%s: material modifying a material is ignored", where_of(b, u, w, sizeof w));
            break;
        case HD_CLASS_PATTERN:
            if (p->type != HD_T_BRIGHTFUNC)
                return hd_fail(HD_ERR_UNSUPPORTED, "%s: pattern type not supported by the ray tracer", where_of(b, u, w, sizeof w));
            if (*pat >= 0)
                return hd_fail(HD_ERR_UNSUPPORTED, "%s: more than one pattern on a surface is not supported", where_of(b, u, w, sizeof w));
            *pat = u;
            break;
        case HD_CLASS_TEXTURE:
            hd_warn("%s: textures are not supported by the ray tracer; ignored", where_of(b, u, w, sizeof w));
            break;
        case HD_CLASS_MIXTURE:
            return hd_fail(HD_ERR_UNSUPPORTED, "%s: mixtures are not supported by the ray tracer", where_of(b, u, w, sizeof w));
        default:
            return hd_fail(HD_ERR_FORMAT, "%s: not a modifier", where_of(b, u, w, sizeof w));
        }
        m = p->modifier;
    }
    return HD_OK;
}

static int supported_material(hd_prim_type t)
{
    return t == HD_T_PLASTIC || t == HD_T_METAL || t == HD_T_TRANS || t == HD_T_GLASS || t == HD_T_MIRROR ||
           t == HD_T_LIGHT || t == HD_T_GLOW || t == HD_T_ILLUM || t == HD_T_BSDF || t == HD_T_ABSDF;
}

hd_status hd_tscene_from_scene(hd_tscene **out, const hd_scene *sc)
{
    builder b;
    memset(&b, 0, sizeof b);
    b.sc = sc;
    hd_status st = hd_tscene_create(&b.ts);
    if (st != HD_OK) return st;
    char w[300];
    for (size_t i = 0; i < sc->nprims && st == HD_OK; i++) {
        const hd_prim *p = &sc->prims[i];
        hd_type_class cl = hd_type_class_of(p->type);
        if (cl == HD_CLASS_MATERIAL && !supported_material(p->type)) {
            /* unused definitions do not matter; used ones are reported below */
            continue;
        }
        if (cl != HD_CLASS_SURFACE) continue;
        where_of(&b, (int32_t)i, w, sizeof w);
        if (p->type == HD_T_INSTANCE || p->type == HD_T_MESH) {
            st = hd_fail(HD_ERR_UNSUPPORTED, "%s: instances and meshes are not supported by the ray tracer", w);
            break;
        }
        int32_t mi, pi;
        st = resolve_chain(&b, (int32_t)i, &mi, &pi);
        if (st != HD_OK) break;
        if (mi < 0) {
            hd_warn("%s: surface has no material (void modifier); it is not rendered", w);
            continue;
        }
        if (!supported_material(sc->prims[mi].type)) {
            char wm[300];
            st = hd_fail(HD_ERR_UNSUPPORTED, "%s: material type not supported by the ray tracer (used by %s)",
                         where_of(&b, mi, wm, sizeof wm), w);
            break;
        }
        int mat;
        st = convert_material(&b, mi, pi, &mat);
        if (st != HD_OK) break;
        const double *r = p->rargs;
        switch (p->type) {
        case HD_T_POLYGON: {
            int n = (int)(p->nrargs / 3);
            if (p->nrargs % 3 || n < 3) { st = hd_fail(HD_ERR_FORMAT, "%s: expected 3n (n >= 3) real arguments", w); break; }
            hd_vec3 *v = hd_malloc_array((size_t)n, sizeof *v);
            if (!v) { st = HD_ERR_NOMEM; break; }
            for (int k = 0; k < n; k++) v[k] = hd_v3(r[3 * k], r[3 * k + 1], r[3 * k + 2]);
            st = hd_tscene_add_polygon(b.ts, mat, v, n, w);
            free(v);
            if (st == HD_OK) {   /* BSDF frame: the up vector must not be along the normal */
                const hd_tmat *tm = hd_tscene_material(b.ts, mat);
                const hd_surface *sf = hd_tscene_surface(b.ts, hd_tscene_nsurfaces(b.ts) - 1);
                if (tm->type == HD_MAT_BSDF &&
                    hd_vlen(hd_vcross(tm->up, sf->n)) <= 1e-6 * hd_vlen(tm->up))
                    hd_warn("%s: the up vector of %s %s is parallel to the surface normal: an arbitrary "
                            "orientation is used", w, tm->absdf ? "aBSDF" : "BSDF", tm->name);
            }
            break;
        }
        case HD_T_SPHERE:
        case HD_T_BUBBLE:
            if (p->nrargs != 4) { st = hd_fail(HD_ERR_FORMAT, "%s: expected 4 real arguments", w); break; }
            st = hd_tscene_add_sphere(b.ts, mat, hd_v3(r[0], r[1], r[2]), r[3], p->type == HD_T_BUBBLE, w);
            break;
        case HD_T_CONE:
        case HD_T_CUP:
        case HD_T_CYLINDER:
        case HD_T_TUBE: {
            int cyl = p->type == HD_T_CYLINDER || p->type == HD_T_TUBE;
            if (p->nrargs != (cyl ? 7u : 8u)) { st = hd_fail(HD_ERR_FORMAT, "%s: expected %d real arguments", w, cyl ? 7 : 8); break; }
            double r0 = r[6], r1 = cyl ? r[6] : r[7];
            int inward = p->type == HD_T_CUP || p->type == HD_T_TUBE;
            if (r0 < 0 || r1 < 0) {   /* Radiance: negative radii flip the orientation */
                hd_warn("%s: negative radius: orientation reversed", w);
                r0 = -r0; r1 = -r1;
                inward = !inward;
            }
            st = hd_tscene_add_cone(b.ts, mat, hd_v3(r[0], r[1], r[2]), hd_v3(r[3], r[4], r[5]), r0, r1, inward, w);
            break;
        }
        case HD_T_RING:
            if (p->nrargs != 8) { st = hd_fail(HD_ERR_FORMAT, "%s: expected 8 real arguments", w); break; }
            st = hd_tscene_add_ring(b.ts, mat, hd_v3(r[0], r[1], r[2]), hd_v3(r[3], r[4], r[5]), r[6], r[7], w);
            break;
        case HD_T_SOURCE:
            if (p->nrargs != 4) { st = hd_fail(HD_ERR_FORMAT, "%s: expected 4 real arguments", w); break; }
            st = hd_tscene_add_source(b.ts, mat, hd_v3(r[0], r[1], r[2]), r[3], w);
            break;
        default:
            st = hd_fail(HD_ERR_UNSUPPORTED, "%s: surface type not supported by the ray tracer", w);
            break;
        }
    }
    free(b.keys);
    for (int k = 0; k < b.nbsdfs; k++) {
        free(b.bsdfs[k].path);
        /* not yet owned by a material of the trace scene (it failed to be added) */
        int owned = 0;
        for (int j = 0; j < hd_tscene_nmaterials(b.ts); j++)
            if (hd_tscene_material(b.ts, j)->bsdf == b.bsdfs[k].b) owned = 1;
        if (!owned) hd_bsdf_free(b.bsdfs[k].b);
    }
    free(b.bsdfs);
    if (st == HD_OK) st = hd_tscene_commit(b.ts);
    if (st != HD_OK) {
        hd_tscene_free(b.ts);
        return st;
    }
    *out = b.ts;
    return HD_OK;
}

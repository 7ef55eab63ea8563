/* heliodon — build a trace scene from a parsed Radiance scene. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/bsdf.h"
#include "heliodon/scene.h"
#include "heliodon/trace.h"

typedef struct loadedbsdf { char *path; hd_bsdf *b; } loadedbsdf;

typedef struct builder {
    const hd_scene *sc;
    hd_tscene *ts;
    int *mat_of;          /* trace-scene material of each modifier primitive: -1 none, -2 not yet made */
    loadedbsdf *bsdfs;    /* XML files loaded so far (each once per scene) */
    int nbsdfs;
    size_t capbsdfs;
    struct hd_modset *ms; /* patterns, textures, mixtures (given to the trace scene) */
    struct hd_modnode **node_of;   /* node of each modifier primitive (made on first use) */
} builder;

static const char *where_of(const builder *b, int32_t i, char *buf, size_t cap)
{
    char w[200];
    const hd_prim *p = &b->sc->prims[i];
    hd_prim_where(b->sc, i, w, sizeof w);
    snprintf(buf, cap, "%s: %s %s", w, hd_type_name(p->type), p->id ? p->id : "?");
    return buf;
}

static hd_status material_for(builder *b, int32_t start, int *out);

/* The definition in force at primitive `at` of modifier `name` (unaliased), or -1 */
static int32_t modifier_before(const builder *b, int32_t at, const char *name)
{
    for (int32_t k = at - 1; k >= 0; k--) {
        const hd_prim *q = &b->sc->prims[k];
        if (q->id && !strcmp(q->id, name) && hd_type_is_modifier(q->type)) return hd_scene_unalias(b->sc, k);
    }
    return -1;
}

/* Resolve the alternate material of illum/mirror (string argument 1). */
static hd_status resolve_alt(builder *b, int32_t mi, hd_tmat *m)
{
    const hd_prim *p = &b->sc->prims[mi];
    m->alt = -1;
    if (p->nsargs < 1 || !strcmp(p->sargs[0], "void")) return HD_OK;
    int32_t a = modifier_before(b, mi, p->sargs[0]);
    char w[300];
    where_of(b, mi, w, sizeof w);
    if (a < 0) return hd_fail(HD_ERR_FORMAT, "%s: alternate material '%s' is not defined", w, p->sargs[0]);
    int idx;
    hd_status st = material_for(b, a, &idx);
    if (st != HD_OK) return st;
    if (idx < 0) {
        hd_warn("%s: alternate '%s' has no material: the illum is rendered invisible", w, p->sargs[0]);
        m->alt = -1;
        return HD_OK;
    }
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
    if (HD_GROW(b->bsdfs, (size_t)b->nbsdfs + 1, b->capbsdfs, 8)) { hd_bsdf_free(bd); return HD_ERR_NOMEM; }
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

static int supported_material(hd_prim_type t);

/* The parameters of material primitive mi (no modifiers). */
static hd_status plain_material(builder *b, int32_t mi, hd_tmat *m)
{
    const hd_prim *p = &b->sc->prims[mi];
    char w[300];
    where_of(b, mi, w, sizeof w);
    if (!supported_material(p->type))
        return hd_fail(HD_ERR_UNSUPPORTED, "%s: material type not supported by the ray tracer", w);
    if (p->type == HD_T_BSDF || p->type == HD_T_ABSDF) return bsdf_material(b, p, w, m);
    hd_status st = hd_tmat_from_args(m, hd_type_name(p->type), p->id ? p->id : "?", p->rargs,
                                     (int)p->nrargs, (int)p->nsargs, w);
    if (st != HD_OK) return st;
    if (m->type == HD_MAT_MIRROR && p->nsargs >= 1)
        hd_warn("%s: the alternate material of mirror is ignored (mirror reflection is used for every ray)", w);
    if (m->type == HD_MAT_ILLUM) return resolve_alt(b, mi, m);
    return HD_OK;
}

/* A modifier chain: the modifiers met walking from primitive `start`
 * (included) along the modifier links, as Radiance's shading applies them
 * (those before the material and the material's own); the first material
 * goes to *mat (-1: none).  A mixfunc of materials ends the search for a
 * material: *mixbase then points to its fore (else back) material. */
typedef struct walkres {
    struct hd_modnode *nodes[64];
    int32_t prims[64];
    int n;
    int32_t mat;
    const hd_tmat *mixbase;
} walkres;

static hd_status make_node(builder *b, int32_t u, struct hd_modnode **out, const hd_tmat **mixbase);
static hd_status make_nodes(builder *b, walkres *wr);

static hd_status walk(builder *b, int32_t start, walkres *wr)
{
    const hd_scene *sc = b->sc;
    wr->n = 0;
    wr->mat = -1;
    wr->mixbase = NULL;
    char w[300];
    int32_t m = start;
    for (int guard = 0; m >= 0 && guard < 10000; guard++) {
        int32_t u = hd_scene_unalias(sc, m);
        const hd_prim *p = &sc->prims[u];
        switch (hd_type_class_of(p->type)) {
        case HD_CLASS_MATERIAL:
            if (wr->mat < 0 && !wr->mixbase) wr->mat = u;
            else if (p->type != HD_T_ANTIMATTER)
                hd_warn("%s: material modifying a material is ignored", where_of(b, u, w, sizeof w));
            break;
        case HD_CLASS_PATTERN:
        case HD_CLASS_TEXTURE:
        case HD_CLASS_MIXTURE: {
            if (wr->n == (int)(sizeof wr->nodes / sizeof *wr->nodes))
                return hd_fail(HD_ERR_UNSUPPORTED, "%s: more than 64 modifiers in a chain",
                               where_of(b, u, w, sizeof w));
            /* nodes are made when needed (make_nodes): a sky's brightfunc
             * may be computed natively, without loading its file; a
             * mixture is made now (its sides tell whether it is a material) */
            const hd_tmat *mb = NULL;
            wr->nodes[wr->n] = NULL;
            if (p->type == HD_T_MIXFUNC || p->type == HD_T_MIXDATA || p->type == HD_T_MIXPICT || p->type == HD_T_MIXTEXT) {
                hd_status st = make_node(b, u, &wr->nodes[wr->n], &mb);
                if (st) return st;
            }
            wr->prims[wr->n++] = u;
            if (mb && wr->mat < 0 && !wr->mixbase) wr->mixbase = mb;
            break;
        }
        default:
            return hd_fail(HD_ERR_FORMAT, "%s: not a modifier", where_of(b, u, w, sizeof w));
        }
        m = p->modifier;
    }
    return HD_OK;
}

static hd_status make_nodes(builder *b, walkres *wr)
{
    for (int i = 0; i < wr->n; i++)
        if (!wr->nodes[i]) {
            hd_status st = make_node(b, wr->prims[i], &wr->nodes[i], NULL);
            if (st) return st;
        }
    return HD_OK;
}

static hd_status make_node(builder *b, int32_t u, struct hd_modnode **out, const hd_tmat **mixbase)
{
    const hd_prim *p = &b->sc->prims[u];
    char w[300];
    where_of(b, u, w, sizeof w);
    if (!b->node_of && !(b->node_of = hd_calloc(b->sc->nprims + 1, sizeof *b->node_of))) return HD_ERR_NOMEM;
    if (!b->ms && !(b->ms = hd_modset_new())) return HD_ERR_NOMEM;
    struct hd_modnode *nd = b->node_of[u];
    if (!nd) {
        hd_status st = hd_modset_node(b->ms, hd_type_name(p->type), p->sargs, (int)p->nsargs, p->rargs,
                                      (int)p->nrargs, w, &nd);
        if (st) return st;
        b->node_of[u] = nd;
        if (hd_modnode_is_mix(nd)) {
            for (int s = 0; s < 2; s++) {
                const char *name = hd_modnode_mixname(nd, s);
                if (!strcmp(name, "void")) continue;
                int32_t a = modifier_before(b, u, name);
                if (a < 0) return hd_fail(HD_ERR_FORMAT, "%s: undefined modifier '%s'", w, name);
                walkres sub;
                if ((st = walk(b, a, &sub)) || (st = make_nodes(b, &sub))) return st;
                const struct hd_modchain *ch;
                if ((st = hd_modset_chain(b->ms, sub.nodes, sub.n, &ch))) return st;
                hd_tmat sm, *smp = NULL;
                if (sub.mat >= 0) {
                    if ((st = plain_material(b, sub.mat, &sm))) return st;
                    smp = &sm;
                } else if (sub.mixbase) {
                    smp = (hd_tmat *)sub.mixbase;
                }
                if ((st = hd_modnode_set_side(nd, s, ch, smp))) return st;
            }
        }
    }
    *out = nd;
    if (mixbase) *mixbase = hd_modnode_material(nd);
    return HD_OK;
}

/* The trace-scene material of everything modified by primitive `start`
 * (a surface's modifier, an illum's alternate): -1 in *out for none. */
static hd_status material_for(builder *b, int32_t start, int *out)
{
    *out = -1;
    if (!b->mat_of) {
        if (!(b->mat_of = hd_malloc_array(b->sc->nprims + 1, sizeof *b->mat_of))) return HD_ERR_NOMEM;
        for (size_t k = 0; k <= b->sc->nprims; k++) b->mat_of[k] = -2;
    }
    if (start < 0) return HD_OK;
    if (b->mat_of[start] != -2) { *out = b->mat_of[start]; return HD_OK; }
    walkres wr;
    hd_status st = walk(b, start, &wr);
    if (st) return st;
    hd_tmat m;
    if (wr.mat >= 0) {
        if ((st = plain_material(b, wr.mat, &m))) return st;
    } else if (wr.mixbase) {
        m = *wr.mixbase;
        m.mixed = 1;
    } else {
        return HD_OK;   /* void */
    }
    if (wr.n > 0) {
        char w[300];
        const hd_prim *q = &b->sc->prims[wr.prims[0]];
        if (hd_tmat_emits(&m) && wr.n == 1 && q->type == HD_T_BRIGHTFUNC) {
            /* an emitter's brightfunc: the sky functions natively */
            st = hd_tmat_set_brightfunc(&m, q->sargs, (int)q->nsargs, q->rargs, (int)q->nrargs,
                                        where_of(b, wr.prims[0], w, sizeof w));
            if (st) return st;
        } else {
            const struct hd_modchain *ch;
            if ((st = make_nodes(b, &wr)) || (st = hd_modset_chain(b->ms, wr.nodes, wr.n, &ch))) return st;
            m.chain = ch;
            if (hd_tmat_emits(&m)) m.pattern = HD_PAT_CAL;
        }
    }
    int idx = hd_tscene_add_material(b->ts, &m);
    if (idx < 0) { hd_tmat_release(&m); return HD_ERR_NOMEM; }
    b->mat_of[start] = idx;
    *out = idx;
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
        int mat;
        st = material_for(&b, p->modifier, &mat);
        if (st != HD_OK) break;
        if (mat < 0) {
            hd_warn("%s: surface has no material (void modifier); it is not rendered", w);
            continue;
        }
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
    free(b.mat_of);
    free(b.node_of);
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
        hd_modset_free(b.ms);
        return st;
    }
    hd_tscene_own_mods(b.ts, b.ms);
    *out = b.ts;
    return HD_OK;
}

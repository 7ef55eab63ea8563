/* heliodon — genBSDF: system set-up and Monte Carlo ray tracing of
 * fenestration geometry (see genbsdf.h). */
#include "heliodon/genbsdf.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "heliodon/bsdf.h"
#include "heliodon/material.h"
#include "heliodon/parallel.h"
#include "heliodon/render.h"
#include "progress.h"
#include "heliodon/rng.h"
#include "scatter.h"
#include "heliodon/scene.h"
#include "heliodon/trace.h"

/* material kinds handled by the generator */
enum { GM_NORMAL = 0, GM_GLASS, GM_MIRROR, GM_DIELECTRIC, GM_BLACK };

typedef struct gmat {
    int kind;
    hd_tmat tm;
    double ior;        /* dielectric */
    double absorb;     /* dielectric: -ln(Y transmission per unit length) */
} gmat;

struct hd_gbsystem {
    hd_tscene *ts;
    gmat *mats;
    int nmats;
    double dim[6];
    double eps;
};

void hd_genbsdf_defaults(hd_genbsdf_opts *o)
{
    memset(o, 0, sizeof *o);
    o->nsamp = 2000;
    o->cull_pct = 90;
    o->backward = 1;
    o->nthreads = 1;
    o->ab = 5;
    o->lr = -10;
    o->lw = 3e-6;
    o->ad = 700;
    o->st = 0.02;
    o->maxdepth = 1000;
    o->seed = 1;
    hd_strlcpy(o->unit, "meter", sizeof o->unit);
    hd_strlcpy(o->manufacturer, "Unknown", sizeof o->manufacturer);
    hd_strlcpy(o->name, "Unnamed", sizeof o->name);
}

double hd_genbsdf_unit_scale(const char *u)
{
    static const struct { const char *n; double s; } t[] = {
        {"meter", 1}, {"millimeter", 1e-3}, {"centimeter", 1e-2}, {"foot", 0.3048},
        {"inch", 0.0254}, {"meters", 1}, {"millimeters", 1e-3}, {"centimeters", 1e-2},
        {"feet", 0.3048}, {"inches", 0.0254}, {"metre", 1}, {"millimetre", 1e-3},
        {"centimetre", 1e-2}, {"metres", 1}, {"millimetres", 1e-3}, {"centimetres", 1e-2},
    };
    if (!u) return 0;
    for (size_t i = 0; i < sizeof t / sizeof t[0]; i++)
        if (!strcasecmp(u, t[i].n)) return t[i].s;
    return 0;
}

/* ---- system set-up ---- */

typedef struct edgekey { int64_t a[3], b[3]; } edgekey;

static int cmp_edge(const void *x, const void *y)
{
    return memcmp(x, y, sizeof(edgekey));
}

static void quant(hd_vec3 v, double q, int64_t k[3])
{
    k[0] = (int64_t)llround(v.x / q);
    k[1] = (int64_t)llround(v.y / q);
    k[2] = (int64_t)llround(v.z / q);
}

/* Every edge of the dielectric polygons must appear exactly twice. */
static hd_status check_closed(const hd_scene *sc, const int32_t *polys, size_t npolys, double q)
{
    size_t ne = 0;
    for (size_t k = 0; k < npolys; k++) ne += sc->prims[polys[k]].nrargs / 3;
    if (!ne) return HD_OK;
    edgekey *e = hd_malloc_array(ne, sizeof *e);
    int32_t *owner = hd_malloc_array(ne, sizeof *owner);
    if (!e || !owner) { free(e); free(owner); return HD_ERR_NOMEM; }
    size_t m = 0;
    for (size_t k = 0; k < npolys; k++) {
        const hd_prim *p = &sc->prims[polys[k]];
        uint32_t n = p->nrargs / 3;
        for (uint32_t j = 0; j < n; j++) {
            int64_t a[3], b[3];
            quant(hd_polygon_vertex(p, j), q, a);
            quant(hd_polygon_vertex(p, (j + 1) % n), q, b);
            if (!memcmp(a, b, sizeof a)) continue;       /* zero-length edge */
            edgekey key;
            memset(&key, 0, sizeof key);
            if (memcmp(a, b, sizeof a) < 0) { memcpy(key.a, a, sizeof a); memcpy(key.b, b, sizeof b); }
            else { memcpy(key.a, b, sizeof b); memcpy(key.b, a, sizeof a); }
            owner[m] = polys[k];
            e[m++] = key;
        }
    }
    /* sort indices by key to find the owner of an unmatched edge */
    size_t *idx = hd_malloc_array(m ? m : 1, sizeof *idx);
    if (!idx) { free(e); free(owner); return HD_ERR_NOMEM; }
    edgekey *sorted = hd_malloc_array(m ? m : 1, sizeof *sorted);
    if (!sorted) { free(e); free(owner); free(idx); return HD_ERR_NOMEM; }
    memcpy(sorted, e, m * sizeof *e);
    qsort(sorted, m, sizeof *sorted, cmp_edge);
    hd_status st = HD_OK;
    for (size_t i = 0; i < m && st == HD_OK;) {
        size_t j = i + 1;
        while (j < m && !cmp_edge(&sorted[i], &sorted[j])) j++;
        if (j - i != 2) {
            /* find a polygon with that edge for the message */
            int32_t who = -1;
            for (size_t k = 0; k < m; k++)
                if (!cmp_edge(&e[k], &sorted[i])) { who = owner[k]; break; }
            char w[300];
            hd_prim_where(sc, who, w, sizeof w);
            st = hd_fail(HD_ERR_FORMAT,
                         "%s: polygon %s: dielectric volume is not closed: edge (%g %g %g)-(%g %g %g) "
                         "is shared by %zu polygon(s) of the volume, expected 2",
                         w, sc->prims[who].id ? sc->prims[who].id : "?",
                         sorted[i].a[0] * q, sorted[i].a[1] * q, sorted[i].a[2] * q,
                         sorted[i].b[0] * q, sorted[i].b[1] * q, sorted[i].b[2] * q, j - i);
        }
        i = j;
    }
    free(e); free(owner); free(idx); free(sorted);
    return st;
}

static hd_status add_material(hd_gbsystem *g, const hd_scene *sc, int32_t mi, int *out, int32_t *matidx, int *nmatidx)
{
    for (int k = 0; k < *nmatidx; k++)
        if (matidx[k] == mi) { *out = k; return HD_OK; }
    const hd_prim *p = &sc->prims[mi];
    char w[300];
    hd_prim_where(sc, mi, w, sizeof w);
    gmat gm;
    memset(&gm, 0, sizeof gm);
    hd_status st;
    if (p->type == HD_T_DIELECTRIC) {
        if (p->nrargs != 5)
            return hd_fail(HD_ERR_FORMAT, "%s: dielectric %s: expected 5 real arguments, got %u", w,
                           p->id ? p->id : "?", p->nrargs);
        double c[3] = {p->rargs[0], p->rargs[1], p->rargs[2]};
        double ty = hd_color_bright(c);
        if (ty <= 0 || ty > 1 || p->rargs[3] <= 0)
            return hd_fail(HD_ERR_FORMAT, "%s: dielectric %s: transmission per unit length must be in (0,1] "
                           "and the index positive", w, p->id ? p->id : "?");
        if (p->rargs[4] != 0)
            hd_warn("%s: dielectric %s: Hartmann dispersion constant ignored", w, p->id ? p->id : "?");
        gm.kind = GM_DIELECTRIC;
        gm.ior = p->rargs[3];
        gm.absorb = -log(ty);
        hd_tmat_init(&gm.tm, HD_MAT_GLASS, p->id ? p->id : "?");
    } else {
        st = hd_tmat_from_args(&gm.tm, hd_type_name(p->type), p->id ? p->id : "?", p->rargs,
                               (int)p->nrargs, (int)p->nsargs, w);
        if (st != HD_OK) return st;
        switch (gm.tm.type) {
        case HD_MAT_PLASTIC: case HD_MAT_METAL: case HD_MAT_TRANS: gm.kind = GM_NORMAL; break;
        case HD_MAT_GLASS: gm.kind = GM_GLASS; break;
        case HD_MAT_MIRROR: gm.kind = GM_MIRROR; break;
        default: gm.kind = GM_BLACK; break;
        }
    }
    int idx = hd_tscene_add_material(g->ts, &gm.tm);
    if (idx < 0) return HD_ERR_NOMEM;
    if (idx != *nmatidx) return hd_fail(HD_ERR_INTERNAL, "material index mismatch");
    gmat *nm = hd_realloc_array(g->mats, (size_t)idx + 1, sizeof *nm);
    if (!nm) return HD_ERR_NOMEM;
    g->mats = nm;
    g->mats[idx] = gm;
    g->nmats = idx + 1;
    matidx[idx] = mi;
    (*nmatidx)++;
    *out = idx;
    return HD_OK;
}

hd_status hd_gbsystem_create(hd_gbsystem **out, const hd_scene *sc, hd_genbsdf_opts *o)
{
    *out = NULL;
    hd_gbsystem *g = hd_calloc(1, sizeof *g);
    if (!g) return HD_ERR_NOMEM;
    hd_status st = hd_tscene_create(&g->ts);
    if (st != HD_OK) { free(g); return st; }
    int32_t *matidx = hd_malloc_array(sc->nprims + 1, sizeof *matidx);
    int32_t *dpolys = hd_malloc_array(sc->nprims + 1, sizeof *dpolys);
    size_t ndpolys = 0;
    int nmatidx = 0, nsurf = 0;
    if (!matidx || !dpolys) st = HD_ERR_NOMEM;
    char w[300];
    for (size_t i = 0; i < sc->nprims && st == HD_OK; i++) {
        const hd_prim *p = &sc->prims[i];
        if (hd_type_class_of(p->type) != HD_CLASS_SURFACE) continue;
        hd_prim_where(sc, (int32_t)i, w, sizeof w);
        /* the modifier chain must not contain mixtures or textures */
        for (int32_t m = p->modifier; m >= 0 && st == HD_OK;) {
            int32_t u = hd_scene_unalias(sc, m);
            hd_type_class cl = hd_type_class_of(sc->prims[u].type);
            if (cl == HD_CLASS_MIXTURE || cl == HD_CLASS_TEXTURE) {
                char wm[300];
                st = hd_fail(HD_ERR_UNSUPPORTED, "%s: %s %s (used by %s) is not supported by genBSDF; "
                             "model holes as polygons with seam-edge holes",
                             hd_prim_where(sc, u, wm, sizeof wm), hd_type_name(sc->prims[u].type),
                             sc->prims[u].id ? sc->prims[u].id : "?", w);
                break;
            }
            if (cl == HD_CLASS_MATERIAL) break;
            m = sc->prims[u].modifier;
        }
        if (st != HD_OK) break;
        int32_t mi = hd_scene_material_of(sc, (int32_t)i);
        if (mi < 0) {
            hd_warn("%s: surface has no material (void modifier); ignored", w);
            continue;
        }
        hd_prim_type mt = sc->prims[mi].type;
        if (mt != HD_T_PLASTIC && mt != HD_T_METAL && mt != HD_T_TRANS && mt != HD_T_GLASS &&
            mt != HD_T_MIRROR && mt != HD_T_DIELECTRIC && mt != HD_T_LIGHT && mt != HD_T_GLOW &&
            mt != HD_T_ILLUM) {
            char wm[300];
            st = hd_fail(HD_ERR_UNSUPPORTED, "%s: material type %s (used by %s) is not supported by genBSDF",
                         hd_prim_where(sc, mi, wm, sizeof wm), hd_type_name(mt), w);
            break;
        }
        int mat = -1;
        st = add_material(g, sc, mi, &mat, matidx, &nmatidx);
        if (st != HD_OK) break;
        const double *r = p->rargs;
        switch (p->type) {
        case HD_T_POLYGON: {
            int n = (int)(p->nrargs / 3);
            hd_vec3 *v = hd_malloc_array((size_t)n + 1, sizeof *v);
            if (!v) { st = HD_ERR_NOMEM; break; }
            for (int k = 0; k < n; k++) v[k] = hd_v3(r[3 * k], r[3 * k + 1], r[3 * k + 2]);
            st = hd_tscene_add_polygon(g->ts, mat, v, n, w);
            free(v);
            if (mt == HD_T_DIELECTRIC) dpolys[ndpolys++] = (int32_t)i;
            break;
        }
        case HD_T_SPHERE: case HD_T_BUBBLE:
            st = hd_tscene_add_sphere(g->ts, mat, hd_v3(r[0], r[1], r[2]), fabs(r[3]),
                                      (p->type == HD_T_BUBBLE) ^ (r[3] < 0), w);
            break;
        case HD_T_CONE: case HD_T_CUP: case HD_T_CYLINDER: case HD_T_TUBE: {
            int cyl = p->type == HD_T_CYLINDER || p->type == HD_T_TUBE;
            double r0 = r[6], r1 = cyl ? r[6] : r[7];
            int inward = p->type == HD_T_CUP || p->type == HD_T_TUBE;
            if (r0 < 0 || r1 < 0) { r0 = -r0; r1 = -r1; inward = !inward; }
            st = hd_tscene_add_cone(g->ts, mat, hd_v3(r[0], r[1], r[2]), hd_v3(r[3], r[4], r[5]), r0, r1, inward, w);
            break;
        }
        case HD_T_RING:
            st = hd_tscene_add_ring(g->ts, mat, hd_v3(r[0], r[1], r[2]), hd_v3(r[3], r[4], r[5]), r[6], r[7], w);
            break;
        case HD_T_SOURCE:
            hd_warn("%s: distant source ignored by genBSDF", w);
            continue;
        default:
            st = hd_fail(HD_ERR_UNSUPPORTED, "%s: surface type %s is not supported by genBSDF", w,
                         hd_type_name(p->type));
            break;
        }
        if (st == HD_OK) nsurf++;
    }
    if (st == HD_OK && nsurf == 0)
        st = hd_fail(HD_ERR_FORMAT, "no surfaces with a material in the input: nothing to sample");
    if (st == HD_OK) st = hd_tscene_commit(g->ts);
    hd_vec3 lo = {0, 0, 0}, hi = {0, 0, 0};
    if (st == HD_OK) {
        hd_tscene_bounds(g->ts, &lo, &hi);
        double size = fmax(fmax(hi.x - lo.x, hi.y - lo.y), hi.z - lo.z);
        double tol = 1e-6 * (size > 0 ? size : 1);
        int auto_dim = !o->have_dim;
        if (auto_dim) {
            o->dim[0] = lo.x; o->dim[1] = hi.x; o->dim[2] = lo.y; o->dim[3] = hi.y;
            o->dim[4] = lo.z; o->dim[5] = hi.z;
            o->have_dim = 1;
        }
        const double *d = o->dim;
        /* a flat device (zmin = zmax) is accepted, as by Radiance's genBSDF */
        if (!(d[0] < d[1] && d[2] < d[3] && d[4] <= d[5]))
            st = hd_fail(HD_ERR_RANGE, "%s %g %g %g %g %g %g: each minimum must be below its maximum",
                         auto_dim ? "the geometry's bounding box (no -dim given)" : "-dim",
                         d[0], d[1], d[2], d[3], d[4], d[5]);
        else if (d[4] >= 0)     /* Radiance's genBSDF: "Device entirely inside room!" */
            st = hd_fail(HD_ERR_RANGE, "%s z range [%g, %g]: the device lies entirely inside the room "
                         "(genBSDF's frame: the exterior is at z < 0, the room at z > 0)",
                         auto_dim ? "the geometry's" : "-dim", d[4], d[5]);
        else if (lo.z < d[4] - tol || hi.z > d[5] + tol)
            st = hd_fail(HD_ERR_RANGE, "geometry extends outside the -dim z range [%g, %g]: "
                         "z from %g to %g (the device must lie between the sender planes)",
                         d[4], d[5], lo.z, hi.z);
        else if (d[0] < lo.x - tol || d[1] > hi.x + tol || d[2] < lo.y - tol || d[3] > hi.y + tol)
            st = hd_fail(HD_ERR_RANGE, "the -dim rectangle x [%g, %g] y [%g, %g] is not covered by the "
                         "geometry (x from %g to %g, y from %g to %g)",
                         d[0], d[1], d[2], d[3], lo.x, hi.x, lo.y, hi.y);
        if (st == HD_OK && d[5] > 1e-5)     /* Radiance's genBSDF warns likewise */
            hd_warn("the device extends into the room (zmax %g > 0)", d[5]);
        if (st == HD_OK && ndpolys) st = check_closed(sc, dpolys, ndpolys, 1e-7 * (size > 0 ? size : 1));
        memcpy(g->dim, o->dim, sizeof g->dim);
        g->eps = hd_tscene_eps(g->ts);
    }
    free(matidx);
    free(dpolys);
    if (st != HD_OK) { hd_gbsystem_free(g); return st; }
    *out = g;
    return HD_OK;
}

void hd_gbsystem_free(hd_gbsystem *g)
{
    if (!g) return;
    hd_tscene_free(g->ts);
    free(g->mats);
    free(g);
}

/* ---- ray tracing ---- */

static hd_vec3 mirror_dir(hd_vec3 d, hd_vec3 n)
{
    return hd_vnorm(hd_vmadd(d, n, -2 * hd_vdot(d, n)));
}

/* Fresnel reflectance of an interface from index n1 into n2 for
 * unpolarised light (the average of the s and p reflectances, as
 * Radiance's dielectric material computes it at every interface); 1 on
 * total internal reflection; *cost = cosine of the refracted ray. */
static double fresnel(double cosi, double n1, double n2, double *cost)
{
    double eta = n1 / n2;
    double s2 = eta * eta * (1 - cosi * cosi);
    if (s2 >= 1) { *cost = 0; return 1; }
    double ct = sqrt(1 - s2);
    *cost = ct;
    double rs = (n1 * cosi - n2 * ct) / (n1 * cosi + n2 * ct);
    double rp = (n1 * ct - n2 * cosi) / (n1 * ct + n2 * cosi);
    return 0.5 * (rs * rs + rp * rp);
}

/* One branch of a sample's ray tree.  w is the flux the branch carries
 * (1 at the sender); rw is the ray weight Radiance's ray tracer would give
 * it (the product of the coefficients of its events, each capped at 1, the
 * transmitted coefficient of a dielectric including the solid-angle ratio
 * (n1/n2)^2), against which -lw is applied; nrefl counts reflections (the
 * ray level that -lr limits), ndiff diffuse events (-ab). */
typedef struct gbray {
    hd_vec3 org, d;
    double w, rw;
    int inside;     /* dielectric material the ray travels in, -1 = air */
    int nrefl, ndiff, nev;
} gbray;

/* Where a branch that leaves the system is scored. */
typedef struct gbsink {
    void (*deposit)(void *ctx, hd_vec3 dout, double w);
    void *ctx;
} gbsink;

/* Start a child branch of weight coefficient coef (flux factor wf) from
 * parent p; applies Radiance's rayorigin() limits: the reflection limit
 * |lr| (lr != 0), then for lr <= 0 Russian roulette below -lw (the
 * survivor's flux is promoted by lw/rw), for lr > 0 a cut below -lw.
 * Returns 0 if the branch is not traced. */
static int spawn(const hd_genbsdf_opts *o, const gbray *p, int reflected, double coef, double wf,
                 double ext, hd_rng *rng, gbray *c)
{
    *c = *p;
    c->w = p->w * wf;
    if (c->w <= 0) return 0;
    c->nrefl = p->nrefl + (reflected != 0);
    if (o->lr != 0 && c->nrefl > abs(o->lr)) return 0;
    c->rw = p->rw * (coef < 1 ? coef : 1);
    if (ext > 0.1) c->rw *= ext > 92 ? 0 : exp(-ext);
    double f = hd_scatter_admit(o->lw, o->lr, &c->rw, rng);
    c->w *= f;
    return f > 0;
}

#define GB_STACK 64

static void trace_branch(const hd_gbsystem *g, const hd_genbsdf_opts *o, gbray r, double tmin, hd_rng *rng,
                         const gbsink *sink);

/* Radiance's diffuse event (ambcomp.c, -aa 0): n × n stratified
 * cosine-weighted rays about nd, n = round(sqrt(ad × w)), w the ray weight
 * capped at 0.8 a w / (ad lw) so that no child falls below -lw, each with
 * the coefficient a / n² (ai: its mean, ay: its luminance, the flux).
 * A single ray is appended to kids (the caller follows it); more are
 * traced here, each as its own tree. */
static void diffuse_split(const hd_gbsystem *g, const hd_genbsdf_opts *o, const gbray *p, hd_vec3 org,
                          hd_vec3 nd, const double col[3], int reflected, double ext, hd_rng *rng,
                          const gbsink *sink, gbray *kids, int *nk)
{
    double ai = (col[0] + col[1] + col[2]) / 3, ay = hd_color_bright(col);
    if (ai <= 1e-6 || p->ndiff >= o->ab || o->ad <= 0) return;
    double wt = p->rw;
    if (o->lw > 0 && wt > 0.8 * ai * p->rw / (o->ad * o->lw)) wt = 0.8 * ai * p->rw / (o->ad * o->lw);
    int n = (int)(sqrt(o->ad * wt) + 0.5);
    if (n < 1) n = 1;
    double inv = 1.0 / ((double)n * n);
    hd_vec3 a, b;
    hd_vbasis(nd, &a, &b);
    for (int i = 0; i < n; i++)
        for (int k = 0; k < n; k++) {
            gbray c;
            if (!spawn(o, p, reflected, ai * inv, ay * inv, ext, rng, &c)) continue;
            c.ndiff++;
            c.org = org;
            c.d = hd_scatter_diskdir(nd, a, b, (i + hd_rng_uniform(rng)) / n, (k + hd_rng_uniform(rng)) / n);
            if (n == 1) kids[(*nk)++] = c;
            else trace_branch(g, o, c, g->eps, rng, sink);
        }
}

/* Follow the ray tree of one sample from org in direction d: specular
 * events of glass, mirror and dielectric split the ray into a reflected
 * and a transmitted branch with their Fresnel weights (as Radiance's
 * materials do); plastic, metal and trans follow Radiance's normal.c
 * (scatter.c: specular rays with their coefficients, rough lobes below
 * -st lit as diffuse) and, with -ad, its diffuse sampling
 * (diffuse_split); without, one diffuse event is chosen with its
 * probability (analog, one path: fast, and noisier per sample).  Branches
 * that leave the geometry are scored with their flux in sink. */
static void trace_sample(const hd_gbsystem *g, const hd_genbsdf_opts *o, hd_vec3 org, hd_vec3 d,
                         hd_rng *rng, const gbsink *sink)
{
    gbray r = {org, d, 1.0, 1.0, -1, 0, 0, 0};
    trace_branch(g, o, r, 0, rng, sink);
}

static void trace_branch(const hd_gbsystem *g, const hd_genbsdf_opts *o, gbray r, double tmin, hd_rng *rng,
                         const gbsink *sink)
{
    gbray stack[GB_STACK];
    int top = 0;
    for (;;) {
        int alive = 1;
        while (alive) {
            if (++r.nev > o->maxdepth) { alive = 0; break; }
            hd_hit h;
            if (!hd_tscene_intersect(g->ts, r.org, r.d, tmin, 0, &h)) {
                /* escaped from inside a volume (not closed): lost */
                if (r.inside < 0 && r.d.z != 0) sink->deposit(sink->ctx, r.d, r.w);
                alive = 0;
                break;
            }
            const hd_surface *s = hd_tscene_surface(g->ts, h.surf);
            const gmat *m = &g->mats[s->mat];
            hd_vec3 nf = h.front ? h.n : hd_vneg(h.n);      /* facing the incoming ray */
            double cosi = -hd_vdot(r.d, nf);
            if (cosi < 1e-12) cosi = 1e-12;
            double ext = 0;     /* optical depth of the segment just travelled */
            if (r.inside >= 0) {
                ext = g->mats[r.inside].absorb * h.t;
                r.w *= exp(-ext);
            }
            gbray kids[6];
            int nk = 0;
            switch (m->kind) {
            case GM_BLACK:
                break;
            case GM_MIRROR: {
                double c = hd_color_bright(m->tm.color);
                if (spawn(o, &r, 1, c, c, ext, rng, &kids[nk])) kids[nk++].d = mirror_dir(r.d, nf);
                break;
            }
            case GM_GLASS: {
                double rc[3], tc[3];
                hd_glass_coeffs(m->tm.color, m->tm.rindex, cosi, rc, tc);
                double pr = hd_color_bright(rc), pt = hd_color_bright(tc);
                if (spawn(o, &r, 1, pr, pr, ext, rng, &kids[nk])) kids[nk++].d = mirror_dir(r.d, nf);
                if (spawn(o, &r, 0, pt, pt, ext, rng, &kids[nk])) nk++;
                break;
            }
            case GM_DIELECTRIC: {
                int entering = h.front;
                double n1 = entering ? 1.0 : m->ior, n2 = entering ? m->ior : 1.0;
                double cost;
                double R = fresnel(cosi, n1, n2, &cost);
                if (R < 1) {
                    double eta = n1 / n2;
                    if (spawn(o, &r, 0, (1 - R) * eta * eta, 1 - R, ext, rng, &kids[nk])) {
                        kids[nk].d = hd_vnorm(hd_vsub(hd_vscale(hd_vadd(r.d, hd_vscale(nf, cosi)), eta),
                                                      hd_vscale(nf, cost)));
                        kids[nk++].inside = entering ? s->mat : -1;
                    }
                }
                if (spawn(o, &r, 1, R, R, ext, rng, &kids[nk])) kids[nk++].d = mirror_dir(r.d, nf);
                break;
            }
            default: {      /* plastic, metal, trans: Radiance's rules */
                hd_scatter sc;
                hd_scatter_material(&m->tm, &h, r.d, &sc);
                double ramb[3], tamb[3];
                int smp = hd_scatter_normal_split(&sc, o->st, ramb, tamb);
                double ps = hd_color_bright(sc.ns.scol), pts = hd_color_bright(sc.ns.tscol);
                hd_vec3 nd;
                if ((smp & 1) && hd_scatter_spec_draw(&sc, 0, rng, &nd) && spawn(o, &r, 1, ps, ps, ext, rng, &kids[nk]))
                    kids[nk++].d = nd;
                if ((smp & 2) && hd_scatter_spec_draw(&sc, 1, rng, &nd) && spawn(o, &r, 0, pts, pts, ext, rng, &kids[nk]))
                    kids[nk++].d = nd;
                if (o->ad > 0) {   /* Radiance's diffuse sampling */
                    diffuse_split(g, o, &r, h.p, nf, ramb, 1, ext, rng, sink, kids, &nk);
                    diffuse_split(g, o, &r, h.p, hd_vneg(nf), tamb, 0, ext, rng, sink, kids, &nk);
                } else if (r.ndiff < o->ab) {   /* one diffuse event, chosen with its probability */
                    double pd = hd_color_bright(ramb), ptd = hd_color_bright(tamb), u = hd_rng_uniform(rng);
                    int side = u < pd ? 1 : u < pd + ptd ? 2 : 0;
                    if (side && spawn(o, &r, side == 1, 1, 1, ext, rng, &kids[nk])) {
                        kids[nk].ndiff++;
                        kids[nk++].d = hd_scatter_cosdir(side == 1 ? nf : hd_vneg(nf), hd_rng_uniform(rng),
                                                         hd_rng_uniform(rng));
                    }
                }
                break;
            }
            }
            for (int k = 0; k < nk; k++) kids[k].org = h.p;
            tmin = g->eps;
            if (!nk) { alive = 0; break; }
            for (int k = 1; k < nk; k++) {
                if (top < GB_STACK) stack[top++] = kids[k];
                else {  /* stack full: keep one branch, chosen in proportion to the flux */
                    double sum = kids[0].w + kids[k].w;
                    if (hd_rng_uniform(rng) * sum < kids[k].w) kids[0] = kids[k];
                    kids[0].w = sum;
                }
            }
            r = kids[0];
        }
        if (!top) break;
        r = stack[--top];
        tmin = g->eps;
    }
}

/* ---- sampling drivers ---- */

typedef struct job {
    const hd_gbsystem *g;
    const hd_genbsdf_opts *o;
    int side;
    int nin;                    /* incident directions */
    int first;                  /* index of the first one */
    const hd_klems_basis *kb;   /* Klems, or NULL for trees */
    double *kt, *kr;            /* Klems outputs */
    float *tt, *tr;             /* tree outputs */
    uint32_t sobol[4][32];      /* generator matrices of the sample points */
    hd_progress *prog;
} job;

/* Sample points: a 4D Sobol' sequence (direction numbers of the first four
 * dimensions: polynomials 1, x+1, x^2+x+1, x^3+x+1) with nested uniform
 * (Owen) scrambling by hashing (Burley, "Practical hash-based Owen
 * scrambling", JCGT 2020), a fresh scramble per incident direction and
 * dimension, and the point index scrambled the same way (indices 0..2^m-1
 * map onto a random aligned block of 2^m points of the sequence, so a
 * power-of-two count is a complete net).  Coordinates 0-1 place the
 * direction in the incident patch, 2-3 the origin on the -dim rectangle:
 * the samples are stratified in 4D (every elementary interval of the
 * pattern holds its share), not only in each pair, which matters where the
 * outcome depends on direction and position together (which prism face a
 * ray meets). */
static void sobol_init(uint32_t sobol_mat[4][32])
{
    static const struct { int s, a; uint32_t m[3]; } p[3] = {{1, 0, {1}}, {2, 1, {1, 3}}, {3, 1, {1, 3, 1}}};
    for (int k = 0; k < 32; k++) sobol_mat[0][k] = 1u << (31 - k);
    for (int d = 1; d < 4; d++) {
        int sd = p[d - 1].s, ad = p[d - 1].a;
        uint32_t m[32];
        for (int k = 0; k < 32; k++) {
            if (k < sd) m[k] = p[d - 1].m[k];
            else {
                uint32_t v = m[k - sd] ^ (m[k - sd] << sd);
                for (int q = 1; q < sd; q++)
                    if ((ad >> (sd - 1 - q)) & 1) v ^= m[k - q] << q;
                m[k] = v;
            }
            sobol_mat[d][k] = m[k] << (31 - k);
        }
    }
}

static uint32_t rev32(uint32_t x)
{
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
    x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
    return (x >> 16) | (x << 16);
}

/* nested uniform scramble of the bits of x (most significant first) */
static uint32_t owen(uint32_t x, uint32_t seed)
{
    x = rev32(x);
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return rev32(x);
}

typedef struct qmc { const uint32_t (*mat)[32]; uint32_t seed[5]; } qmc;

static void qmc_point(const qmc *q, uint64_t k, hd_rng *rng, double u[4])
{
    uint32_t i = owen((uint32_t)k, q->seed[4]);
    uint32_t x[4] = {0, 0, 0, 0};
    for (; i; i &= i - 1) {
        int b = __builtin_ctz(i);
        for (int d = 0; d < 4; d++) x[d] ^= q->mat[d][b];
    }
    for (int d = 0; d < 4; d++)   /* 32 bits, then uniform jitter below the last one */
        u[d] = ((double)owen(x[d], q->seed[d]) + hd_rng_uniform(rng)) * 0x1.0p-32;
}

/* propagation direction and origin of sample k of incident direction i */
static void incident(const job *j, size_t i, uint64_t k, const qmc *q, hd_rng *rng, hd_vec3 *org, hd_vec3 *dir,
                     double *azrot)
{
    const double *dim = j->g->dim;
    double u[4];
    qmc_point(q, k, rng, u);
    double sx = u[0], sy = u[1];
    double sgn = j->side == HD_GB_FROM_EXTERIOR ? 1.0 : -1.0;
    hd_vec3 d;
    *azrot = 0;
    if (j->kb) {
        hd_vec3 fo = hd_klems_dir(j->kb, (int)i, sx, sy);
        d = hd_v3(fo.x, fo.y, sgn * fo.z);
    } else {
        int R = 1 << j->o->tree_log2;
        double px, py;
        if (j->o->tree_dims == 4) {
            int i0 = (int)(i / (size_t)R), i1 = (int)(i % (size_t)R);
            hd_square2disk((i0 + sx) / R, (i1 + sy) / R, &px, &py);
        } else {
            double c0 = (i + sx) / R;                 /* in [0, 0.5) */
            double st = 1 - 2 * c0;
            double ph = 2 * HD_PI * sy;
            px = st * cos(ph);
            py = st * sin(ph);
            *azrot = ph;
        }
        double r2 = px * px + py * py;
        d = hd_v3(px, py, sgn * sqrt(fmax(0.0, 1 - r2)));
    }
    *dir = hd_vnorm(d);
    double x = dim[0] + (dim[1] - dim[0]) * u[2];
    double y = dim[2] + (dim[3] - dim[2]) * u[3];
    double span = dim[5] - dim[4];
    double back = 1e-3 * (span > 0 ? span : 1);
    double z0 = j->side == HD_GB_FROM_EXTERIOR ? dim[4] - back : dim[5] + back;
    *org = hd_v3(x, y, z0);
}

/* accumulation of one incident direction's exiting flux */
typedef struct accum {
    const job *j;
    double *acc_t, *acc_r;
    double az;      /* 3D trees: azimuth of the incident plane */
    int R;
} accum;

static void deposit(void *ctx, hd_vec3 out, double w)
{
    const accum *a = ctx;
    const job *j = a->j;
    int transmitted = (j->side == HD_GB_FROM_EXTERIOR) ? out.z > 0 : out.z < 0;
    double *acc = transmitted ? a->acc_t : a->acc_r;
    if (j->kb) {
        int b = hd_klems_bin(j->kb, hd_v3(out.x, out.y, fabs(out.z)));
        if (b >= 0) acc[b] += w;
    } else {
        int R = a->R;
        double ox = out.x, oy = out.y;
        if (j->o->tree_dims == 3) {   /* incident plane -> x axis */
            double c = cos(-a->az), s = sin(-a->az);
            double rx = c * ox - s * oy, ry = s * ox + c * oy;
            ox = rx; oy = ry;
        }
        double sx, sy;
        hd_disk2square(ox, oy, &sx, &sy);
        int ix = (int)(sx * R), iy = (int)(sy * R);
        ix = ix < 0 ? 0 : ix >= R ? R - 1 : ix;
        iy = iy < 0 ? 0 : iy >= R ? R - 1 : iy;
        acc[(size_t)ix * R + iy] += w;
    }
}

static hd_status run_chunk(void *ctx, size_t begin, size_t end, size_t chunk, int worker)
{
    (void)chunk; (void)worker;
    const job *j = ctx;
    uint64_t ns = (uint64_t)ceil(sqrt((double)j->o->nsamp));
    if (ns < 1) ns = 1;
    uint64_t total = ns * ns;
    for (size_t i = begin + (size_t)j->first; i < end + (size_t)j->first; i++) {
        hd_rng rng;
        hd_rng_init(&rng, j->o->seed, hd_hash64((uint64_t)j->side + 1, i));
        int nout = j->kb ? j->kb->nbins : 0;
        int R = j->kb ? 0 : 1 << j->o->tree_log2;
        size_t R2 = (size_t)R * (size_t)R;
        size_t nacc = j->kb ? (size_t)nout : R2;
        accum a = {j, hd_calloc(nacc, sizeof(double)), hd_calloc(nacc, sizeof(double)), 0, R};
        if (!a.acc_t || !a.acc_r) { free(a.acc_t); free(a.acc_r); return HD_ERR_NOMEM; }
        gbsink sink = {deposit, &a};
        qmc q;
        q.mat = (const uint32_t (*)[32])j->sobol;
        for (int d = 0; d < 5; d++) q.seed[d] = (uint32_t)hd_rng_u64(&rng);
        for (uint64_t k = 0; k < total; k++) {
            hd_vec3 org, d;
            incident(j, i, k, &q, &rng, &org, &d, &a.az);
            trace_sample(j->g, j->o, org, d, &rng, &sink);
        }
        double *acc_t = a.acc_t, *acc_r = a.acc_r;
        if (j->kb) {
            for (int o = 0; o < nout; o++) {
                double lam = hd_klems_lambda(j->kb, o);
                if (j->kt) j->kt[(size_t)o * nout + i] = acc_t[o] / (double)total / lam;
                if (j->kr) j->kr[(size_t)o * nout + i] = acc_r[o] / (double)total / lam;
            }
        } else {
            double lam = HD_PI / (double)R2;
            /* 4D: row i = (i0, i1); 3D: row i0 (and its mirror) */
            size_t rows[2] = {i, i};
            int nrows = 1;
            if (j->o->tree_dims == 3) { rows[1] = (size_t)R - 1 - i; nrows = 2; }
            for (int q = 0; q < nrows; q++)
                for (size_t c = 0; c < R2; c++) {
                    if (j->tt) j->tt[rows[q] * R2 + c] = (float)(acc_t[c] / (double)total / lam);
                    if (j->tr) j->tr[rows[q] * R2 + c] = (float)(acc_r[c] / (double)total / lam);
                }
        }
        free(acc_t);
        free(acc_r);
        if (j->prog) hd_progress_add(j->prog, 1);
    }
    return HD_OK;
}

static hd_status run_side(job *j)
{
    sobol_init(j->sobol);
    j->prog = j->o->report ? hd_progress_start(j->side == HD_GB_FROM_EXTERIOR ? "front" : "back",
                                               (uint64_t)j->nin, 10, 1) : NULL;
    hd_status st = hd_parallel_for((size_t)j->nin, 1, j->o->nthreads, run_chunk, j);
    if (j->prog) hd_progress_finish(j->prog);
    return st;
}

hd_status hd_genbsdf_klems_range(const hd_gbsystem *g, const hd_genbsdf_opts *o, int side,
                                 const hd_klems_basis *kb, int first, int count, double *trans, double *refl)
{
    if (first < 0 || count < 0 || first + count > kb->nbins)
        return hd_fail(HD_ERR_RANGE, "incident bins %d..%d outside the basis (%d bins)", first,
                       first + count - 1, kb->nbins);
    job j;
    memset(&j, 0, sizeof j);
    j.g = g; j.o = o; j.side = side; j.kb = kb; j.nin = count; j.first = first;
    j.kt = trans; j.kr = refl;
    return run_side(&j);
}

hd_status hd_genbsdf_klems(const hd_gbsystem *g, const hd_genbsdf_opts *o, int side,
                           const hd_klems_basis *kb, double *trans, double *refl)
{
    return hd_genbsdf_klems_range(g, o, side, kb, 0, kb->nbins, trans, refl);
}

hd_status hd_genbsdf_tree(const hd_gbsystem *g, const hd_genbsdf_opts *o, int side,
                          float *trans, float *refl)
{
    if ((o->tree_dims != 3 && o->tree_dims != 4) || o->tree_log2 < 1 || o->tree_log2 > 9)
        return hd_fail(HD_ERR_RANGE, "tensor tree: expected -t3 or -t4 with a resolution 1..9, got -t%d %d",
                       o->tree_dims, o->tree_log2);
    job j;
    memset(&j, 0, sizeof j);
    j.g = g; j.o = o; j.side = side;
    int R = 1 << o->tree_log2;
    j.nin = o->tree_dims == 4 ? R * R : R / 2;
    j.tt = trans; j.tr = refl;
    return run_side(&j);
}

double hd_genbsdf_klems_hemi(const hd_klems_basis *kb, const double *vals, int i)
{
    double s = 0;
    for (int o = 0; o < kb->nbins; o++) s += vals[(size_t)o * kb->nbins + i] * hd_klems_lambda(kb, o);
    return s;
}

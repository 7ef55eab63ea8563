/* heliodon — ray-tracing scene on Embree 3 (see trace.h). */
#include <embree3/rtcore.h>
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/trace.h"
#include "heliodon/scene.h"

struct hd_tscene {
    hd_tmat *mats;
    int nmats;
    size_t capmats;
    struct hd_modset *mods;   /* patterns, textures, mixtures of the materials (owned) */
    hd_surface *surfs;
    int nsurfs;
    size_t capsurfs;
    hd_vec3 *tv;             /* triangle vertices, 3 per triangle (double) */
    int *tsurf;              /* triangle -> surface */
    int ntri;
    size_t captv, capts, captc;
    double *tcum;            /* per polygon: cumulative triangle areas (indexed by triangle) */
    int *user;               /* user-geometry primitive -> surface */
    int nuser;
    int *sources;            /* distant sources (surface indices) */
    int nsources;
    int *srcpos;             /* surface -> its index in sources, -1 if not a source */
    int *srcov, *srcov_off;  /* per source: the other sources whose cones overlap its cone */
    atomic_int srcov_state;  /* srcpos, srcov: 0 not built yet, 1 built, 2 refused (see source_overlaps) */
    int *lights;
    int nlights;
    int *portals;
    int nportals;
    double portal_area;
    RTCDevice dev;
    RTCScene scene;
    unsigned tri_geom, user_geom;
    int has_tri, has_user;
    hd_vec3 lo, hi;
    double eps;
    int committed;
};

hd_status hd_tscene_create(hd_tscene **out)
{
    hd_tscene *s = hd_calloc(1, sizeof *s);
    if (!s) return HD_ERR_NOMEM;
    *out = s;
    return HD_OK;
}

void hd_tscene_free(hd_tscene *s)
{
    if (!s) return;
    if (s->scene) rtcReleaseScene(s->scene);
    if (s->dev) rtcReleaseDevice(s->dev);
    for (int i = 0; i < s->nmats; i++) hd_tmat_release(&s->mats[i]);   /* BSDF data */
    hd_modset_free(s->mods);
    free(s->mats);
    free(s->surfs);
    free(s->tv);
    free(s->tsurf);
    free(s->tcum);
    free(s->user);
    free(s->sources);
    free(s->srcpos);
    free(s->srcov);
    free(s->srcov_off);
    free(s->lights);
    free(s->portals);
    free(s);
}

void hd_tscene_own_mods(hd_tscene *s, struct hd_modset *ms) { s->mods = ms; }

int hd_tscene_add_material(hd_tscene *s, const hd_tmat *m)
{
    if (HD_GROW(s->mats, (size_t)s->nmats + 1, s->capmats, 64)) return -1;
    s->mats[s->nmats] = *m;
    return s->nmats++;
}

const hd_tmat *hd_tscene_material(const hd_tscene *s, int i) { return &s->mats[i]; }
int hd_tscene_nmaterials(const hd_tscene *s) { return s->nmats; }
int hd_tscene_nsurfaces(const hd_tscene *s) { return s->nsurfs; }
const hd_surface *hd_tscene_surface(const hd_tscene *s, int i) { return &s->surfs[i]; }
double hd_tscene_eps(const hd_tscene *s) { return s->eps; }
int hd_tscene_nlights(const hd_tscene *s) { return s->nlights; }
int hd_tscene_light(const hd_tscene *s, int k) { return s->lights[k]; }
int hd_tscene_nportals(const hd_tscene *s) { return s->nportals; }
int hd_tscene_portal(const hd_tscene *s, int k) { return s->portals[k]; }
double hd_tscene_portal_area(const hd_tscene *s) { return s->portal_area; }
void hd_tscene_bounds(const hd_tscene *s, hd_vec3 *lo, hd_vec3 *hi) { *lo = s->lo; *hi = s->hi; }

static hd_surface *new_surface(hd_tscene *s, hd_skind kind, int mat, const char *where)
{
    if (s->committed) {
        hd_fail(HD_ERR_INTERNAL, "trace scene: surface added after commit");
        return NULL;
    }
    if (mat < 0 || mat >= s->nmats) {
        hd_fail(HD_ERR_INTERNAL, "%s: bad material index %d", where ? where : "?", mat);
        return NULL;
    }
    if (HD_GROW(s->surfs, (size_t)s->nsurfs + 1, s->capsurfs, 64)) return NULL;
    hd_surface *f = &s->surfs[s->nsurfs];
    memset(f, 0, sizeof *f);
    f->kind = kind;
    f->mat = mat;
    snprintf(f->where, sizeof f->where, "%s", where ? where : "?");
    return f;
}

static double tri_area(hd_vec3 a, hd_vec3 b, hd_vec3 c)
{
    return 0.5 * hd_vlen(hd_vcross(hd_vsub(b, a), hd_vsub(c, a)));
}

hd_status hd_tscene_add_polygon(hd_tscene *s, int mat, const hd_vec3 *vin, int n, const char *where)
{
    if (n >= 4 && vin[0].x == vin[n - 1].x && vin[0].y == vin[n - 1].y && vin[0].z == vin[n - 1].z) n--;
    if (n < 3) return hd_fail(HD_ERR_FORMAT, "%s: polygon needs at least 3 vertices", where);
    double parea = 0;
    hd_vec3 nr = hd_polygon_normal(vin, (uint32_t)n, &parea);
    if (!(parea > 0) || !isfinite(parea)) return hd_fail(HD_ERR_FORMAT, "%s: polygon has zero area", where);
    uint32_t *tri = hd_malloc_array((size_t)(n > 3 ? n - 2 : 1), 3 * sizeof(uint32_t));
    if (!tri) return HD_ERR_NOMEM;
    uint32_t ntri = 0;
    if (hd_polygon_triangulate(vin, (uint32_t)n, tri, &ntri) != HD_OK || ntri == 0) {
        hd_warn("%s: polygon could not be triangulated by ear clipping (self-intersecting?); using a fan", where);
        ntri = 0;
        for (int i = 1; i + 1 < n; i++) {
            tri[3 * ntri] = 0; tri[3 * ntri + 1] = (uint32_t)i; tri[3 * ntri + 2] = (uint32_t)i + 1; ntri++;
        }
    }
    int nt = (int)ntri;
    hd_surface *f = new_surface(s, HD_SURF_POLYGON, mat, where);
    if (!f) { free(tri); return HD_ERR_NOMEM; }
    f->n = nr;
    double dsum = 0;
    for (int i = 0; i < n; i++) dsum += hd_vdot(nr, vin[i]);
    f->d = dsum / n;
    f->tri0 = s->ntri;
    size_t need = (size_t)s->ntri + (size_t)nt;
    if (HD_GROW(s->tv, 3 * need, s->captv, 64) || HD_GROW(s->tsurf, need, s->capts, 64) ||
        HD_GROW(s->tcum, need, s->captc, 64)) {
        free(tri);
        return HD_ERR_NOMEM;
    }
    double area = 0;
    int k = 0;
    for (int i = 0; i < nt; i++) {
        hd_vec3 a = vin[tri[3 * i]], b = vin[tri[3 * i + 1]], c = vin[tri[3 * i + 2]];
        double ar = tri_area(a, b, c);
        if (ar <= 0) continue;
        int t = s->ntri + k;
        s->tv[3 * t] = a; s->tv[3 * t + 1] = b; s->tv[3 * t + 2] = c;
        s->tsurf[t] = s->nsurfs;
        area += ar;
        s->tcum[t] = area;
        k++;
    }
    free(tri);
    f->ntri = k;
    f->area = area;
    s->ntri += k;
    s->nsurfs++;
    if (k == 0) return hd_fail(HD_ERR_FORMAT, "%s: polygon has zero area", where);
    return HD_OK;
}

hd_status hd_tscene_add_sphere(hd_tscene *s, int mat, hd_vec3 c, double r, int inward, const char *where)
{
    if (!(r > 0)) return hd_fail(HD_ERR_FORMAT, "%s: sphere radius must be positive", where);
    hd_surface *f = new_surface(s, HD_SURF_SPHERE, mat, where);
    if (!f) return HD_ERR_NOMEM;
    f->a = c; f->r0 = r; f->inward = inward;
    f->area = 4 * HD_PI * r * r;
    s->nsurfs++;
    return HD_OK;
}

hd_status hd_tscene_add_cone(hd_tscene *s, int mat, hd_vec3 p0, hd_vec3 p1, double r0, double r1,
                             int inward, const char *where)
{
    double L = hd_vlen(hd_vsub(p1, p0));
    if (!(L > 0)) return hd_fail(HD_ERR_FORMAT, "%s: cone/cylinder has zero length", where);
    if (r0 < 0 || r1 < 0 || (r0 == 0 && r1 == 0))
        return hd_fail(HD_ERR_FORMAT, "%s: cone/cylinder radii must be >= 0 and not both zero", where);
    hd_surface *f = new_surface(s, HD_SURF_CONE, mat, where);
    if (!f) return HD_ERR_NOMEM;
    f->a = p0; f->b = p1; f->r0 = r0; f->r1 = r1; f->inward = inward;
    f->area = HD_PI * (r0 + r1) * sqrt((r1 - r0) * (r1 - r0) + L * L);
    s->nsurfs++;
    return HD_OK;
}

hd_status hd_tscene_add_ring(hd_tscene *s, int mat, hd_vec3 c, hd_vec3 n, double r0, double r1,
                             const char *where)
{
    if (r0 < 0 || r1 < 0) return hd_fail(HD_ERR_FORMAT, "%s: ring radius must not be negative", where);
    if (r0 > r1) { double t = r0; r0 = r1; r1 = t; }
    if (r0 == r1) return hd_fail(HD_ERR_FORMAT, "%s: ring radii must differ", where);
    if (!(hd_vlen(n) > 0)) return hd_fail(HD_ERR_FORMAT, "%s: ring normal is zero", where);
    hd_surface *f = new_surface(s, HD_SURF_RING, mat, where);
    if (!f) return HD_ERR_NOMEM;
    f->a = c; f->b = hd_vnorm(n); f->r0 = r0; f->r1 = r1;
    f->area = HD_PI * (r1 * r1 - r0 * r0);
    s->nsurfs++;
    return HD_OK;
}

hd_status hd_tscene_add_source(hd_tscene *s, int mat, hd_vec3 dir, double angle, const char *where)
{
    if (!(hd_vlen(dir) > 0)) return hd_fail(HD_ERR_FORMAT, "%s: source direction is zero", where);
    if (!(angle > 0) || angle > 360) return hd_fail(HD_ERR_FORMAT, "%s: source angle must be in (0,360]", where);
    hd_surface *f = new_surface(s, HD_SURF_SOURCE, mat, where);
    if (!f) return HD_ERR_NOMEM;
    f->b = hd_vnorm(dir);
    f->r0 = angle / 2 * HD_PI / 180;
    f->area = 2 * HD_PI * (1 - cos(f->r0));
    s->nsurfs++;
    return HD_OK;
}

/* ---- exact intersections (double) ---- */
static int isect_sphere(const hd_surface *f, hd_vec3 o, hd_vec3 d, double tmin, double tmax, double *t)
{
    hd_vec3 oc = hd_vsub(o, f->a);
    double a = hd_vdot(d, d), b = hd_vdot(oc, d), c = hd_vdot(oc, oc) - f->r0 * f->r0;
    double disc = b * b - a * c;
    if (disc < 0) return 0;
    double sq = sqrt(disc), t1 = (-b - sq) / a, t2 = (-b + sq) / a;
    if (t1 > tmin && t1 < tmax) { *t = t1; return 1; }
    if (t2 > tmin && t2 < tmax) { *t = t2; return 1; }
    return 0;
}

static int isect_cone(const hd_surface *f, hd_vec3 o, hd_vec3 d, double tmin, double tmax, double *t)
{
    hd_vec3 ax = hd_vsub(f->b, f->a);
    double L = hd_vlen(ax);
    ax = hd_vscale(ax, 1 / L);
    double k = (f->r1 - f->r0) / L;
    hd_vec3 op = hd_vsub(o, f->a);
    double h0 = hd_vdot(op, ax), hd = hd_vdot(d, ax);
    double rr = f->r0 + k * h0;
    double A = hd_vdot(d, d) - hd * hd - k * k * hd * hd;
    double B = 2 * (hd_vdot(op, d) - h0 * hd - k * hd * rr);
    double C = hd_vdot(op, op) - h0 * h0 - rr * rr;
    double ts[2];
    int nt = 0;
    if (fabs(A) < 1e-14 * hd_vdot(d, d)) {
        if (fabs(B) > 0) ts[nt++] = -C / B;
    } else {
        double disc = B * B - 4 * A * C;
        if (disc < 0) return 0;
        double sq = sqrt(disc);
        double q = B < 0 ? -0.5 * (B - sq) : -0.5 * (B + sq);
        double x1 = q / A, x2 = q != 0 ? C / q : x1;
        if (x1 > x2) { double tt = x1; x1 = x2; x2 = tt; }
        ts[nt++] = x1;
        ts[nt++] = x2;
    }
    for (int i = 0; i < nt; i++) {
        if (!(ts[i] > tmin && ts[i] < tmax)) continue;
        double h = h0 + ts[i] * hd;
        if (h < 0 || h > L) continue;
        if (f->r0 + k * h < 0) continue;
        *t = ts[i];
        return 1;
    }
    return 0;
}

static int isect_ring(const hd_surface *f, hd_vec3 o, hd_vec3 d, double tmin, double tmax, double *t)
{
    double dn = hd_vdot(d, f->b);
    if (fabs(dn) < 1e-300) return 0;
    double tt = hd_vdot(hd_vsub(f->a, o), f->b) / dn;
    if (!(tt > tmin && tt < tmax)) return 0;
    hd_vec3 p = hd_vsub(hd_vmadd(o, d, tt), f->a);
    double r2 = hd_vdot(p, p);
    if (r2 < f->r0 * f->r0 || r2 > f->r1 * f->r1) return 0;
    *t = tt;
    return 1;
}

static int isect_user(const hd_surface *f, hd_vec3 o, hd_vec3 d, double tmin, double tmax, double *t)
{
    switch (f->kind) {
    case HD_SURF_SPHERE: return isect_sphere(f, o, d, tmin, tmax, t);
    case HD_SURF_CONE: return isect_cone(f, o, d, tmin, tmax, t);
    case HD_SURF_RING: return isect_ring(f, o, d, tmin, tmax, t);
    default: return 0;
    }
}

static hd_vec3 user_normal(const hd_surface *f, hd_vec3 p)
{
    hd_vec3 n;
    switch (f->kind) {
    case HD_SURF_SPHERE:
        n = hd_vnorm(hd_vsub(p, f->a));
        break;
    case HD_SURF_CONE: {
        hd_vec3 ax = hd_vsub(f->b, f->a);
        double L = hd_vlen(ax);
        ax = hd_vscale(ax, 1 / L);
        hd_vec3 w = hd_vsub(p, f->a);
        w = hd_vsub(w, hd_vscale(ax, hd_vdot(w, ax)));
        double k = (f->r1 - f->r0) / L;
        n = hd_vnorm(hd_vsub(hd_vnorm(w), hd_vscale(ax, k)));
        break;
    }
    default:
        return f->b;
    }
    return f->inward ? hd_vneg(n) : n;
}

/* SoA accessors for Embree's RTCRayN / RTCHitN (the C++ inline helpers of
 * rtcore_ray.h are not available in C). */
#define RAYF(r, N, k, i) (((float *)(r))[(k) * (N) + (i)])
#define HITF(h, N, k, i) (((float *)(h))[(k) * (N) + (i)])
#define HITU(h, N, k, i) (((unsigned *)(h))[(k) * (N) + (i)])

/* ---- Embree callbacks ---- */
static void user_bounds(const struct RTCBoundsFunctionArguments *args)
{
    const hd_tscene *s = args->geometryUserPtr;
    const hd_surface *f = &s->surfs[s->user[args->primID]];
    hd_vec3 lo, hi;
    if (f->kind == HD_SURF_SPHERE) {
        lo = hd_vsub(f->a, hd_v3(f->r0, f->r0, f->r0));
        hi = hd_vadd(f->a, hd_v3(f->r0, f->r0, f->r0));
    } else {
        hd_vec3 c0 = f->a, c1 = f->kind == HD_SURF_CONE ? f->b : f->a;
        hd_vec3 ax = f->kind == HD_SURF_CONE ? hd_vnorm(hd_vsub(f->b, f->a)) : f->b;
        double r0 = f->kind == HD_SURF_CONE ? f->r0 : f->r1, r1 = f->r1;
        double e[3];
        for (int i = 0; i < 3; i++) {
            double ai = hd_vget(ax, i);
            e[i] = sqrt(fmax(0, 1 - ai * ai));
        }
        lo = hd_v3(fmin(c0.x - r0 * e[0], c1.x - r1 * e[0]), fmin(c0.y - r0 * e[1], c1.y - r1 * e[1]),
                   fmin(c0.z - r0 * e[2], c1.z - r1 * e[2]));
        hi = hd_v3(fmax(c0.x + r0 * e[0], c1.x + r1 * e[0]), fmax(c0.y + r0 * e[1], c1.y + r1 * e[1]),
                   fmax(c0.z + r0 * e[2], c1.z + r1 * e[2]));
    }
    double pad = 1e-6 * (1 + fmax(fmax(fabs(lo.x), fabs(hi.x)), fmax(fmax(fabs(lo.y), fabs(hi.y)),
                                                                    fmax(fabs(lo.z), fabs(hi.z)))));
    args->bounds_o->lower_x = (float)(lo.x - pad);
    args->bounds_o->lower_y = (float)(lo.y - pad);
    args->bounds_o->lower_z = (float)(lo.z - pad);
    args->bounds_o->upper_x = (float)(hi.x + pad);
    args->bounds_o->upper_y = (float)(hi.y + pad);
    args->bounds_o->upper_z = (float)(hi.z + pad);
}

static void user_intersect(const struct RTCIntersectFunctionNArguments *args)
{
    const hd_tscene *s = args->geometryUserPtr;
    const hd_surface *f = &s->surfs[s->user[args->primID]];
    unsigned N = args->N;
    struct RTCRayN *ray = (struct RTCRayN *)args->rayhit;
    struct RTCHitN *hit = (struct RTCHitN *)&((float *)args->rayhit)[12 * N];
    for (unsigned i = 0; i < N; i++) {
        if (args->valid[i] != -1) continue;
        hd_vec3 o = hd_v3(RAYF(ray, N, 0, i), RAYF(ray, N, 1, i), RAYF(ray, N, 2, i));
        hd_vec3 d = hd_v3(RAYF(ray, N, 4, i), RAYF(ray, N, 5, i), RAYF(ray, N, 6, i));
        double t;
        if (!isect_user(f, o, d, RAYF(ray, N, 3, i), RAYF(ray, N, 8, i), &t)) continue;
        RAYF(ray, N, 8, i) = (float)t;
        HITU(hit, N, 6, i) = args->geomID;
        HITU(hit, N, 5, i) = args->primID;
        HITU(hit, N, 7, i) = RTC_INVALID_GEOMETRY_ID;
        HITF(hit, N, 0, i) = 0;
        HITF(hit, N, 1, i) = 0;
        HITF(hit, N, 2, i) = 1;
        HITF(hit, N, 3, i) = 0;
        HITF(hit, N, 4, i) = 0;
    }
}

static void user_occluded(const struct RTCOccludedFunctionNArguments *args)
{
    const hd_tscene *s = args->geometryUserPtr;
    const hd_surface *f = &s->surfs[s->user[args->primID]];
    unsigned N = args->N;
    for (unsigned i = 0; i < N; i++) {
        if (args->valid[i] != -1) continue;
        hd_vec3 o = hd_v3(RAYF(args->ray, N, 0, i), RAYF(args->ray, N, 1, i), RAYF(args->ray, N, 2, i));
        hd_vec3 d = hd_v3(RAYF(args->ray, N, 4, i), RAYF(args->ray, N, 5, i), RAYF(args->ray, N, 6, i));
        double t;
        if (isect_user(f, o, d, RAYF(args->ray, N, 3, i), RAYF(args->ray, N, 8, i), &t))
            RAYF(args->ray, N, 8, i) = -INFINITY;
    }
}

static void embree_error(void *ptr, enum RTCError code, const char *str)
{
    (void)ptr;
    hd_warn("embree error %d: %s", (int)code, str ? str : "");
}

hd_status hd_tscene_commit(hd_tscene *s)
{
    if (s->committed) return HD_OK;
    s->dev = rtcNewDevice("threads=1");
    if (!s->dev) return hd_fail(HD_ERR_INTERNAL, "cannot create the Embree device (error %d)", (int)rtcGetDeviceError(NULL));
    rtcSetDeviceErrorFunction(s->dev, embree_error, NULL);
    s->scene = rtcNewScene(s->dev);
    rtcSetSceneFlags(s->scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(s->scene, RTC_BUILD_QUALITY_HIGH);
    /* bounds of finite geometry */
    hd_vec3 lo = hd_v3(DBL_MAX, DBL_MAX, DBL_MAX), hi = hd_v3(-DBL_MAX, -DBL_MAX, -DBL_MAX);
#define EXT(p) do { hd_vec3 q_ = (p); lo = hd_v3(fmin(lo.x, q_.x), fmin(lo.y, q_.y), fmin(lo.z, q_.z)); \
                    hi = hd_v3(fmax(hi.x, q_.x), fmax(hi.y, q_.y), fmax(hi.z, q_.z)); } while (0)
    for (int t = 0; t < 3 * s->ntri; t++) EXT(s->tv[t]);
    int nuser = 0;
    for (int i = 0; i < s->nsurfs; i++) {
        hd_surface *f = &s->surfs[i];
        if (f->kind == HD_SURF_SPHERE || f->kind == HD_SURF_CONE || f->kind == HD_SURF_RING) {
            nuser++;
            double r = fmax(f->r0, f->r1);
            EXT(hd_vsub(f->a, hd_v3(r, r, r)));
            EXT(hd_vadd(f->a, hd_v3(r, r, r)));
            if (f->kind == HD_SURF_CONE) { EXT(hd_vsub(f->b, hd_v3(r, r, r))); EXT(hd_vadd(f->b, hd_v3(r, r, r))); }
        }
    }
#undef EXT
    if (lo.x > hi.x) lo = hi = hd_v3(0, 0, 0);
    s->lo = lo;
    s->hi = hi;
    double ext = fmax(fmax(fmax(fabs(lo.x), fabs(hi.x)), fmax(fabs(lo.y), fabs(hi.y))), fmax(fabs(lo.z), fabs(hi.z)));
    s->eps = 2e-6 * (1 + ext);
    if (s->ntri) {
        RTCGeometry g = rtcNewGeometry(s->dev, RTC_GEOMETRY_TYPE_TRIANGLE);
        float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                            (size_t)3 * s->ntri);
        unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                               (size_t)s->ntri);
        if (!vb || !ib) { rtcReleaseGeometry(g); return hd_fail(HD_ERR_NOMEM, "embree: cannot allocate triangle buffers"); }
        for (int t = 0; t < 3 * s->ntri; t++) {
            vb[3 * t] = (float)s->tv[t].x;
            vb[3 * t + 1] = (float)s->tv[t].y;
            vb[3 * t + 2] = (float)s->tv[t].z;
            ib[t] = (unsigned)t;
        }
        rtcCommitGeometry(g);
        s->tri_geom = rtcAttachGeometry(s->scene, g);
        rtcReleaseGeometry(g);
        s->has_tri = 1;
    }
    if (nuser) {
        s->user = hd_malloc_array((size_t)nuser, sizeof(int));
        if (!s->user) return HD_ERR_NOMEM;
        for (int i = 0; i < s->nsurfs; i++) {
            hd_skind k = s->surfs[i].kind;
            if (k == HD_SURF_SPHERE || k == HD_SURF_CONE || k == HD_SURF_RING) s->user[s->nuser++] = i;
        }
        RTCGeometry g = rtcNewGeometry(s->dev, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(g, (unsigned)nuser);
        rtcSetGeometryUserData(g, s);
        rtcSetGeometryBoundsFunction(g, user_bounds, s);
        rtcSetGeometryIntersectFunction(g, user_intersect);
        rtcSetGeometryOccludedFunction(g, user_occluded);
        rtcCommitGeometry(g);
        s->user_geom = rtcAttachGeometry(s->scene, g);
        rtcReleaseGeometry(g);
        s->has_user = 1;
    }
    rtcCommitScene(s->scene);
    /* distant sources and direct lights */
    s->sources = hd_malloc_array((size_t)s->nsurfs + 1, sizeof(int));
    s->lights = hd_malloc_array((size_t)s->nsurfs + 1, sizeof(int));
    s->portals = hd_malloc_array((size_t)s->nsurfs + 1, sizeof(int));
    if (!s->sources || !s->lights || !s->portals) return HD_ERR_NOMEM;
    for (int i = 0; i < s->nsurfs; i++) {
        hd_surface *f = &s->surfs[i];
        const hd_tmat *m = &s->mats[f->mat];
        if (f->kind == HD_SURF_SOURCE) s->sources[s->nsources++] = i;
        int bright = m->color[0] > 1e-7 || m->color[1] > 1e-7 || m->color[2] > 1e-7;
        int nee = 0;
        if (m->type == HD_MAT_LIGHT || m->type == HD_MAT_ILLUM) nee = bright;
        else if (m->type == HD_MAT_GLOW) nee = bright && m->maxrad > 0;
        if (nee && f->kind == HD_SURF_CONE && f->r0 != f->r1) {
            hd_warn("%s: light on a cone is not a direct source (as in Radiance); it is only seen by rays", f->where);
            nee = 0;
        }
        f->nee = nee;
        if (nee) s->lights[s->nlights++] = i;
        f->portal = f->kind == HD_SURF_POLYGON && m->type == HD_MAT_GLASS && f->area > 0;
        if (f->portal) {
            s->portals[s->nportals++] = i;
            s->portal_area += f->area;
        }
    }
    s->committed = 1;
    return HD_OK;
}

/* hd_hit from Embree's answer for the ray (org, dir), for single rays and
 * packets: polygon hits moved onto the plane in double precision, curved
 * surfaces refined near Embree's t. */
static void embree_hit(const hd_tscene *s, hd_vec3 org, hd_vec3 dir, double tmin, unsigned geom, unsigned prim,
                       double t, hd_hit *h)
{
    const hd_surface *f;
    if (s->has_tri && geom == s->tri_geom) {
        h->surf = s->tsurf[prim];
        f = &s->surfs[h->surf];
        double dn = hd_vdot(dir, f->n);
        if (fabs(dn) > 1e-12) {
            double tt = (f->d - hd_vdot(org, f->n)) / dn;
            if (tt > 0) t = tt;
        }
        h->n = f->n;
    } else {
        h->surf = s->user[prim];
        f = &s->surfs[h->surf];
        double tt;
        double lo = t - 1e-4 * (1 + t), hi = t + 1e-4 * (1 + t);
        if (lo < tmin) lo = tmin;
        if (isect_user(f, org, dir, lo, hi, &tt)) t = tt;
    }
    h->t = t;
    h->p = hd_vmadd(org, dir, t);
    if (f->kind != HD_SURF_POLYGON) h->n = user_normal(f, h->p);
    h->front = hd_vdot(dir, h->n) < 0;
}

int hd_tscene_intersect(const hd_tscene *s, hd_vec3 org, hd_vec3 dir, double tmin, double tmax, hd_hit *h)
{
    if (!s->has_tri && !s->has_user) return 0;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    rh.ray.org_x = (float)org.x;
    rh.ray.org_y = (float)org.y;
    rh.ray.org_z = (float)org.z;
    rh.ray.dir_x = (float)dir.x;
    rh.ray.dir_y = (float)dir.y;
    rh.ray.dir_z = (float)dir.z;
    rh.ray.tnear = (float)tmin;
    rh.ray.tfar = tmax > 0 ? (float)tmax : INFINITY;
    rh.ray.time = 0;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(s->scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return 0;
    embree_hit(s, org, dir, tmin, rh.hit.geomID, rh.hit.primID, rh.ray.tfar, h);
    return 1;
}

/* cos r0 of a distant source's cone (less a margin) from its solid angle 2π(1 - cos r0): no cos
 * per source and ray (with the 670 suns of a year at MF:6 the cos calls were 41 % of a
 * window-pixel sun DC) */
static double cone_cos(const hd_surface *f) { return 1 - f->area / (2 * HD_PI) - 1e-12; }

/* A distant source's cone holds dir: the test of hd_tscene_source_hit. */
static int source_holds(const hd_surface *f, hd_vec3 dir) { return !(hd_vdot(dir, f->b) < cone_cos(f)); }

/* Per distant source, the other sources whose cones overlap its cone (centres at most r0 + r0'
 * apart, with a margin): the only ones that can hold a direction it holds.  Suns of a year do not
 * overlap, so hd_tscene_source_hit_is is one test per shadow ray instead of one per source.
 * O(sources²) (27 M pairs for 5 185 suns): built on the first hd_tscene_source_hit_is, not by
 * the commit, so that programs that never test a shadow ray against its sun do not pay it. */
static hd_status build_overlaps(hd_tscene *s)
{
    int n = s->nsources;
    s->srcpos = hd_malloc_array((size_t)s->nsurfs + 1, sizeof(int));
    s->srcov_off = hd_malloc_array((size_t)n + 1, sizeof(int));
    double *cr = hd_malloc_array((size_t)n + 1, sizeof(double)), *sr = hd_malloc_array((size_t)n + 1, sizeof(double));
    double *ra = hd_malloc_array((size_t)n + 1, sizeof(double));
    hd_status st = HD_ERR_NOMEM;
    if (!s->srcpos || !s->srcov_off || !cr || !sr || !ra) goto out;
    for (int i = 0; i < s->nsurfs; i++) s->srcpos[i] = -1;
    for (int k = 0; k < n; k++) {
        const hd_surface *f = &s->surfs[s->sources[k]];
        s->srcpos[s->sources[k]] = k;
        double c = cone_cos(f);
        c = c < -1 ? -1 : c > 1 ? 1 : c;
        cr[k] = c;
        sr[k] = sqrt(1 - c * c);
        ra[k] = acos(c);
    }
    /* two passes: count, then fill (pairs (k, j) with cos(angle) >= cos(r_k + r_j) - margin) */
    int cap = 0, m = 0;
    for (int pass = 0; pass < 2; pass++) {
        m = 0;
        for (int k = 0; k < n; k++) {
            s->srcov_off[k] = m;
            hd_vec3 bk = s->surfs[s->sources[k]].b;
            for (int j = 0; j < n; j++) {
                if (j == k) continue;
                /* r_k + r_j >= π: every direction of one may lie in the other */
                int wide = ra[k] + ra[j] >= HD_PI - 1e-9;
                double cmin = cr[k] * cr[j] - sr[k] * sr[j] - 1e-9;
                if (!wide && hd_vdot(bk, s->surfs[s->sources[j]].b) < cmin) continue;
                if (pass == 1) s->srcov[m] = j;
                m++;
            }
        }
        s->srcov_off[n] = m;
        if (pass == 0) {
            cap = m;
            s->srcov = hd_malloc_array((size_t)cap + 1, sizeof(int));
            if (!s->srcov) goto out;
        }
    }
    st = HD_OK;
out:
    free(cr);
    free(sr);
    free(ra);
    return st;
}

/* The lists of build_overlaps, once per scene whichever thread asks first (the others wait):
 * 1, or 2 if they were refused (the allocation limit; a warning), and hd_tscene_source_hit_is
 * then tests every source: the same answers, slower. */
static int source_overlaps(const hd_tscene *cs)
{
    static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
    int state = atomic_load_explicit(&cs->srcov_state, memory_order_acquire);
    if (state) return state;
    hd_tscene *s = (hd_tscene *)cs;   /* a cache of the committed scene, filled once */
    pthread_mutex_lock(&lock);
    state = atomic_load_explicit(&s->srcov_state, memory_order_relaxed);
    if (!state) {
        state = 1;
        if (build_overlaps(s) != HD_OK) {
            hd_warn("the sources' overlap lists: %s; every source is tested instead", hd_errmsg());
            state = 2;
        }
        atomic_store_explicit(&s->srcov_state, state, memory_order_release);
    }
    pthread_mutex_unlock(&lock);
    return state;
}

int hd_tscene_source_hit_is(const hd_tscene *s, hd_vec3 dir, int target)
{
    if (!s->committed) return 0;
    if (source_overlaps(s) == 2) return target >= 0 && hd_tscene_source_hit(s, dir) == target;
    int k = target >= 0 && target < s->nsurfs && s->srcpos ? s->srcpos[target] : -1;
    if (k < 0) return 0;
    const hd_surface *f = &s->surfs[target];
    if (!source_holds(f, dir)) return 0;
    /* hd_tscene_source_hit's choice: the smallest cone holding dir, the first of equal ones */
    for (int i = s->srcov_off[k]; i < s->srcov_off[k + 1]; i++) {
        int j = s->srcov[i];
        const hd_surface *g = &s->surfs[s->sources[j]];
        if (source_holds(g, dir) && (g->area < f->area || (g->area == f->area && j < k))) return 0;
    }
    return 1;
}

int hd_tscene_source_hit(const hd_tscene *s, hd_vec3 dir)
{
    int best = -1;
    double bo = 1e300;
    for (int k = 0; k < s->nsources; k++) {
        const hd_surface *f = &s->surfs[s->sources[k]];
        if (!source_holds(f, dir)) continue;
        if (f->area < bo) { bo = f->area; best = s->sources[k]; }
    }
    return best;
}

hd_vec3 hd_tscene_sample_polygon(const hd_tscene *s, int surf, double u0, double u1, double u2)
{
    const hd_surface *f = &s->surfs[surf];
    double target = u0 * f->area;
    int lo = f->tri0, hi = f->tri0 + f->ntri - 1;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (s->tcum[mid] < target) lo = mid + 1; else hi = mid;
    }
    hd_vec3 a = s->tv[3 * lo], b = s->tv[3 * lo + 1], c = s->tv[3 * lo + 2];
    double su = sqrt(u1);
    double wa = 1 - su, wb = u2 * su;
    return hd_vadd(hd_vadd(hd_vscale(a, wa), hd_vscale(b, wb)), hd_vscale(c, 1 - wa - wb));
}

/* ---- packets (hd_tscene_intersect_packet) ---- */


uint32_t hd_tscene_intersect_packet(const hd_tscene *s, int n, const hd_vec3 *org, const hd_vec3 *dir,
                                    double tmin, double tmax, hd_hit *h)
{
    if (n <= 0 || (!s->has_tri && !s->has_user)) return 0;
    if (n > HD_TPACKET) n = HD_TPACKET;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    _Alignas(64) int valid[16];
    _Alignas(64) struct RTCRayHit16 rh;
    float tn = (float)tmin, tf = tmax > 0 ? (float)tmax : INFINITY;
    for (int i = 0; i < 16; i++) {
        int k = i < n ? i : 0;
        valid[i] = i < n ? -1 : 0;
        rh.ray.org_x[i] = (float)org[k].x;
        rh.ray.org_y[i] = (float)org[k].y;
        rh.ray.org_z[i] = (float)org[k].z;
        rh.ray.dir_x[i] = (float)dir[k].x;
        rh.ray.dir_y[i] = (float)dir[k].y;
        rh.ray.dir_z[i] = (float)dir[k].z;
        rh.ray.tnear[i] = tn;
        rh.ray.tfar[i] = tf;
        rh.ray.time[i] = 0;
        rh.ray.mask[i] = 0xFFFFFFFFu;
        rh.ray.id[i] = (unsigned)i;
        rh.ray.flags[i] = 0;
        rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect16(valid, s->scene, &ctx, &rh);
    uint32_t mask = 0;
    for (int i = 0; i < n; i++) {
        if (rh.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) continue;
        embree_hit(s, org[i], dir[i], tmin, rh.hit.geomID[i], rh.hit.primID[i], rh.ray.tfar[i], &h[i]);
        mask |= 1u << i;
    }
    return mask;
}

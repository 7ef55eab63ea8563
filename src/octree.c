/* heliodon — writing Radiance's octree format (see include/heliodon/octree.h
 * and docs/design/octree.md).  Written from the format as Radiance reads it:
 * big-endian integers, NUL-terminated strings, pre-order tree with one byte
 * per node (0 empty, 1 full, 2 tree), full nodes as a counted, sorted
 * object set; frozen scene data as a type-name list and one record per
 * object (type, modifier, name, strings, reals: Radiance is built without
 * integer arguments), -1 ending it. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/octree.h"
#include "heliodon/xform.h"
#include "scene_priv.h"

#define OCT_FTINY 1e-6
#define OCT_MARGIN (10 * OCT_FTINY)   /* margin around the scene cube, as oconv */
#define OCT_OBJSIZE 4                 /* bytes per object number */
#define OCT_MAGIC (4 * 8 + 251)       /* Radiance's base; + object size */
#define OCT_MAXSET 511                /* largest set Radiance reads */

void hd_octree_opts_default(hd_octree_opts *o)
{
    memset(o, 0, sizeof *o);
    o->resolu = 16384;
    o->objlim = 6;
}

/* ---- bounding boxes ---- */
static void bb_point(double bmin[3], double bmax[3], const double p[3])
{
    for (int i = 0; i < 3; i++) {
        if (p[i] < bmin[i]) bmin[i] = p[i];
        if (p[i] > bmax[i]) bmax[i] = p[i];
    }
}

static void bb_circle(double bmin[3], double bmax[3], const double c[3], const double n[3], double r)
{
    for (int i = 0; i < 3; i++) {
        double e = 1. - n[i] * n[i];
        e = e > 0 ? sqrt(e) * r : 0;
        if (c[i] + e > bmax[i]) bmax[i] = c[i] + e;
        if (c[i] - e < bmin[i]) bmin[i] = c[i] - e;
    }
}

static hd_status read_head(const char *path, int mesh, double org[3], double *size, char ***names, int *nnames)
{
    const char *format = mesh ? "Radiance_tmesh" : "Radiance_octree";
    int magic0 = mesh ? 8 + 311 : OCT_MAGIC;
    FILE *fp = fopen(path, "rb");
    if (!fp) return hd_fail(HD_ERR_IO, "cannot open octree '%s': %s", path, strerror(errno));
    char line[4096];
    hd_status st = HD_OK;
    int fmt = 0;
    if (names) { *names = NULL; *nnames = 0; }
    if (!fgets(line, sizeof line, fp) || strncmp(line, "#?", 2))
        st = hd_fail(HD_ERR_FORMAT, "%s: not an octree (no Radiance header)", path);
    while (!st && fgets(line, sizeof line, fp) && line[0] != '\n')
        if (!strncmp(line, "FORMAT=", 7) && !strncmp(line + 7, format, strlen(format))) fmt = 1;
    if (!st && !fmt) st = hd_fail(HD_ERR_FORMAT, "%s: not an %s (no FORMAT=%s)", path, mesh ? "mesh" : "octree", format);
    int c0 = st ? EOF : getc(fp), c1 = st ? EOF : getc(fp);
    if (!st && (c1 == EOF || ((c0 << 8 | c1) - magic0) <= 0 || ((c0 << 8 | c1) - magic0) > 8))
        st = hd_fail(HD_ERR_FORMAT, "%s: incompatible %s format (byte offset %ld)", path, format, ftell(fp));
    for (int k = 0; !st; k++) {
        char buf[4096];
        size_t n = 0;
        int c;
        while ((c = getc(fp)) != EOF && c && n + 1 < sizeof buf) buf[n++] = (char)c;
        buf[n] = 0;
        if (c != 0) {
            st = hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: truncated octree", path, ftell(fp));
        } else if (k < 4) {
            double v;
            if (hd_parse_double(buf, &v))
                st = hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: bad bounding cube value '%s'", path, ftell(fp), buf);
            else if (k < 3) org[k] = v;
            else *size = v;
            if (!names && k == 3) break;
        } else if (!buf[0]) {
            break;
        } else {
            char **x = hd_realloc_array(*names, (size_t)*nnames + 1, sizeof *x);
            if (!x) { st = HD_ERR_NOMEM; break; }
            *names = x;
            if (!(x[*nnames] = hd_strdup(buf))) { st = HD_ERR_NOMEM; break; }
            ++*nnames;
        }
    }
    fclose(fp);
    if (st && names) {
        for (int k = 0; k < *nnames; k++) free((*names)[k]);
        free(*names);
        *names = NULL;
        *nnames = 0;
    }
    return st;
}

hd_status hd_octree_read_head(const char *path, double org[3], double *size, char ***names, int *nnames)
{
    return read_head(path, 0, org, size, names, nnames);
}

/* Bounding box of one surface primitive (Radiance's rules). */
static hd_status prim_bbox(const hd_scene *s, size_t i, double bmin[3], double bmax[3], int *surface)
{
    const hd_prim *p = &s->prims[i];
    char where[1200];
    *surface = 1;
    switch (p->type) {
    case HD_T_SPHERE: case HD_T_BUBBLE: {
        hd_vec3 c;
        double r;
        hd_sphere_get(p, &c, &r);
        for (int k = 0; k < 3; k++) {
            double v[3] = {c.x, c.y, c.z};
            v[k] -= r;
            bb_point(bmin, bmax, v);
            v[k] += 2 * r;
            bb_point(bmin, bmax, v);
        }
        return HD_OK;
    }
    case HD_T_POLYGON:
        for (uint32_t k = 0; k < hd_polygon_nverts(p); k++) bb_point(bmin, bmax, p->rargs + 3 * k);
        return HD_OK;
    case HD_T_CONE: case HD_T_CUP: case HD_T_CYLINDER: case HD_T_TUBE: {
        hd_vec3 p0, p1;
        double r0, r1;
        hd_cone_get(p, &p0, &p1, &r0, &r1);
        hd_vec3 d = hd_v3(p1.x - p0.x, p1.y - p0.y, p1.z - p0.z);
        double len = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
        if (len <= 0) return HD_OK;
        double n[3] = {d.x / len, d.y / len, d.z / len};
        double a[3] = {p0.x, p0.y, p0.z}, b[3] = {p1.x, p1.y, p1.z};
        bb_circle(bmin, bmax, a, n, fabs(r0));
        bb_circle(bmin, bmax, b, n, fabs(r1));
        return HD_OK;
    }
    case HD_T_RING: {
        hd_vec3 c, nn;
        double rin, rout;
        hd_ring_get(p, &c, &nn, &rin, &rout);
        double len = sqrt(nn.x * nn.x + nn.y * nn.y + nn.z * nn.z);
        if (len <= 0) return HD_OK;
        double n[3] = {nn.x / len, nn.y / len, nn.z / len}, cc[3] = {c.x, c.y, c.z};
        bb_circle(bmin, bmax, cc, n, rout);
        return HD_OK;
    }
    case HD_T_INSTANCE: case HD_T_MESH: {
        const char *what = p->type == HD_T_MESH ? "mesh" : "instance";
        if (p->nsargs < 1)
            return hd_fail(HD_ERR_FORMAT, "%s: %s %s: expected a file name",
                           hd_prim_where(s, (int32_t)i, where, sizeof where), what, p->id);
        double org[3], size;
        hd_xf xf;
        hd_status st = read_head(p->sargs[0], p->type == HD_T_MESH, org, &size, NULL, NULL);
        if (!st) st = hd_xf_from_words(&xf, (int)p->nsargs - 1, p->sargs + 1);
        if (st) return hd_fail_context(st, "%s: %s %s", hd_prim_where(s, (int32_t)i, where, sizeof where), what, p->id);
        for (int j = 0; j < 8; j++) {
            hd_vec3 v = hd_v3(org[0] + (j & 1 ? size : 0), org[1] + (j & 2 ? size : 0), org[2] + (j & 4 ? size : 0));
            v = hd_xf_point(&xf, v);
            double q[3] = {v.x, v.y, v.z};
            bb_point(bmin, bmax, q);
        }
        return HD_OK;
    }
    default:
        *surface = 0;        /* modifiers and sources are not in the octree */
        return HD_OK;
    }
}

hd_status hd_scene_bbox(const hd_scene *s, size_t from, double bbmin[3], double bbmax[3])
{
    for (int k = 0; k < 3; k++) { bbmin[k] = HUGE_VAL; bbmax[k] = -HUGE_VAL; }
    for (size_t i = from; i < s->nprims; i++) {
        int surf;
        hd_status st = prim_bbox(s, i, bbmin, bbmax, &surf);
        if (st) return st;
    }
    return HD_OK;
}

/* ---- octree construction ---- */
typedef struct obj {          /* a surface to place */
    int32_t id;
    double bmin[3], bmax[3];
    int kind;                 /* 0 box only, 1 plane + box, 2 sphere, 3 cone */
    double n[3], d;           /* plane n.x = d, or sphere centre n, radius d */
    double c0[3], len, r0, r1;   /* cone: base centre c0, unit axis n, length, end radii */
} obj;

typedef struct node {
    int kind;                 /* 0 empty, 1 full, 2 tree */
    int32_t kid;              /* tree: index of the first of 8 nodes */
    int32_t *set;             /* full: object numbers (indices into objs) */
    int n, cap;
} node;

typedef struct builder {
    node *nodes;
    size_t nnodes, cap;
    const obj *objs;
    long objlim;
    double mincusize;
    const hd_scene *s;
    int overflow_warned;
} builder;

/* May the surface touch the cube [org, org+size]^3?  Conservative. */
static int touches(const obj *o, const double org[3], double size)
{
    double eps = OCT_FTINY + size * 1e-9;
    for (int k = 0; k < 3; k++)
        if (o->bmax[k] < org[k] - eps || o->bmin[k] > org[k] + size + eps) return 0;
    if (o->kind == 1) {
        double lo = HUGE_VAL, hi = -HUGE_VAL;
        for (int j = 0; j < 8; j++) {
            double v = 0;
            for (int k = 0; k < 3; k++) v += o->n[k] * (org[k] + ((j >> k) & 1 ? size : 0));
            if (v < lo) lo = v;
            if (v > hi) hi = v;
        }
        return o->d >= lo - eps && o->d <= hi + eps;
    }
    if (o->kind == 2) {
        double dmin = 0, dmax = 0;
        for (int k = 0; k < 3; k++) {
            double c = o->n[k], a = org[k], b = org[k] + size;
            double e = c < a ? a - c : c > b ? c - b : 0;
            double f = fabs(c - a) > fabs(c - b) ? fabs(c - a) : fabs(c - b);
            dmin += e * e;
            dmax += f * f;
        }
        return sqrt(dmin) <= o->d + eps && sqrt(dmax) >= o->d - eps;
    }
    if (o->kind == 3) {
        /* the cube's bounding sphere against the cone's surface: in the
         * (axial, radial) half-plane of the cube's centre, the distance to
         * the side's segment from (0, r0) to (len, r1) */
        double h = size * .5, q[3], t = 0, rr = 0;
        for (int k = 0; k < 3; k++) { q[k] = org[k] + h - o->c0[k]; t += q[k] * o->n[k]; }
        for (int k = 0; k < 3; k++) { double e = q[k] - t * o->n[k]; rr += e * e; }
        double rho = sqrt(rr), ex = o->len, ey = o->r1 - o->r0, l2 = ex * ex + ey * ey;
        double u = l2 > 0 ? (t * ex + (rho - o->r0) * ey) / l2 : 0;
        if (u < 0) u = 0;
        if (u > 1) u = 1;
        double dx = t - u * ex, dy = rho - (o->r0 + u * ey);
        return sqrt(dx * dx + dy * dy) <= h * 1.7320508075688772 * 1.01 + 10 * eps;
    }
    return 1;
}

static hd_status new_kids(builder *b, int32_t *first)
{
    if (HD_GROW(b->nodes, b->nnodes + 8, b->cap, 1024)) return HD_ERR_NOMEM;
    *first = (int32_t)b->nnodes;
    memset(b->nodes + b->nnodes, 0, 8 * sizeof *b->nodes);
    b->nnodes += 8;
    return HD_OK;
}

static hd_status set_add(node *nd, int32_t o)
{
    if (nd->n == nd->cap) {
        int nc = nd->cap ? nd->cap * 2 : 8;
        int32_t *x = hd_realloc_array(nd->set, (size_t)nc, sizeof *x);
        if (!x) return HD_ERR_NOMEM;
        nd->set = x;
        nd->cap = nc;
    }
    nd->set[nd->n++] = o;
    return HD_OK;
}

static hd_status add(builder *b, int32_t ni, const double org[3], double size, int32_t o)
{
    if (!touches(&b->objs[o], org, size)) return HD_OK;
    hd_status st;
    if (b->nodes[ni].kind == 2) {
        double h = size * .5;
        for (int i = 0; i < 8; i++) {
            double ko[3];
            for (int k = 0; k < 3; k++) ko[k] = org[k] + ((i >> k) & 1 ? h : 0);
            if ((st = add(b, b->nodes[ni].kid + i, ko, h, o))) return st;
        }
        return HD_OK;
    }
    if (b->nodes[ni].kind == 0) {
        b->nodes[ni].kind = 1;
        return set_add(&b->nodes[ni], o);
    }
    double h = size * .5;
    if (b->nodes[ni].n < b->objlim || h < b->mincusize) {
        if (b->nodes[ni].n >= OCT_MAXSET) {
            if (!b->overflow_warned++)
                hd_warn("set overflow at the octree's resolution limit (%s): object left out of a "
                        "cube, as Radiance's oconv does; raise -r or -n", b->s->prims[b->objs[o].id].id);
            return HD_OK;
        }
        return set_add(&b->nodes[ni], o);
    }
    /* split: re-add the set's objects, then this one, to 8 children */
    int32_t *set = b->nodes[ni].set;
    int n = b->nodes[ni].n;
    int32_t kid;
    if ((st = new_kids(b, &kid))) return st;
    b->nodes[ni].kind = 2;
    b->nodes[ni].kid = kid;
    b->nodes[ni].set = NULL;
    b->nodes[ni].n = b->nodes[ni].cap = 0;
    for (int i = 0; i < 8 && !st; i++) {
        double ko[3];
        for (int k = 0; k < 3; k++) ko[k] = org[k] + ((i >> k) & 1 ? h : 0);
        for (int j = 0; j < n && !st; j++) st = add(b, kid + i, ko, h, set[j]);
        if (!st) st = add(b, kid + i, ko, h, o);
    }
    free(set);
    return st;
}

/* ---- output ---- */
static void put_nstr(FILE *fp, const char *s) { fputs(s, fp); putc(0, fp); }

static void put_tree(FILE *fp, const builder *b, int32_t ni)
{
    const node *nd = &b->nodes[ni];
    if (nd->kind == 2) {
        putc(2, fp);
        for (int i = 0; i < 8; i++) put_tree(fp, b, nd->kid + i);
    } else if (nd->kind == 1) {
        putc(1, fp);
        hd_put_int(fp, nd->n, OCT_OBJSIZE);
        for (int i = 0; i < nd->n; i++) hd_put_int(fp, b->objs[nd->set[i]].id, OCT_OBJSIZE);
    } else {
        putc(0, fp);
    }
}

/* Frozen scene data: heliodon's type names as the type map, then each
 * primitive as Radiance holds it (aliases keep type "alias": the aliased
 * object as modifier when the modifier is inherited, else the new modifier
 * and the aliased name as one string). */
static void put_scene(FILE *fp, const hd_scene *s)
{
    for (int t = 0; t < HD_T_COUNT; t++) put_nstr(fp, hd_type_name((hd_prim_type)t));
    put_nstr(fp, "");
    for (size_t i = 0; i < s->nprims; i++) {
        const hd_prim *p = &s->prims[i];
        hd_put_int(fp, (long)p->type, 1);
        if (p->type == HD_T_ALIAS) {
            int32_t ref = p->alias_of;
            int inherit = ref >= 0 && (!strcmp(p->modname, "inherit") || p->modifier == s->prims[ref].modifier);
            hd_put_int(fp, inherit ? ref : p->modifier, OCT_OBJSIZE);
            put_nstr(fp, p->id);
            if (inherit) {
                hd_put_int(fp, 0, 2);
            } else {
                hd_put_int(fp, 1, 2);
                put_nstr(fp, p->nsargs ? p->sargs[0] : "");
            }
            hd_put_int(fp, 0, 2);
            continue;
        }
        hd_put_int(fp, p->modifier, OCT_OBJSIZE);
        put_nstr(fp, p->id);
        hd_put_int(fp, p->nsargs, 2);
        for (uint32_t k = 0; k < p->nsargs; k++) put_nstr(fp, p->sargs[k]);
        hd_put_int(fp, p->nrargs, 2);
        for (uint32_t k = 0; k < p->nrargs; k++) hd_put_flt(fp, p->rargs[k]);
    }
    hd_put_int(fp, -1, 1);
}

static hd_status make_obj(const hd_scene *s, size_t i, obj *o, int *surface)
{
    o->id = (int32_t)i;
    for (int k = 0; k < 3; k++) { o->bmin[k] = HUGE_VAL; o->bmax[k] = -HUGE_VAL; }
    hd_status st = prim_bbox(s, i, o->bmin, o->bmax, surface);
    if (st || !*surface) return st;
    const hd_prim *p = &s->prims[i];
    o->kind = 0;
    if (p->type == HD_T_POLYGON && hd_polygon_nverts(p) >= 3) {
        uint32_t nv = hd_polygon_nverts(p);
        hd_vec3 *v = hd_malloc_array(nv, sizeof *v);
        if (!v) return HD_ERR_NOMEM;
        for (uint32_t k = 0; k < nv; k++) v[k] = hd_polygon_vertex(p, k);
        double area;
        hd_vec3 n = hd_polygon_normal(v, nv, &area);
        if (area > 0 && isfinite(n.x)) {
            o->kind = 1;
            o->n[0] = n.x; o->n[1] = n.y; o->n[2] = n.z;
            /* the plane through the vertices' mean (planar within tolerance) */
            double d = 0;
            for (uint32_t k = 0; k < nv; k++) d += n.x * v[k].x + n.y * v[k].y + n.z * v[k].z;
            o->d = d / nv;
            /* non-planar polygons: fall back to the box */
            for (uint32_t k = 0; k < nv; k++)
                if (fabs(n.x * v[k].x + n.y * v[k].y + n.z * v[k].z - o->d) > 1e-6) { o->kind = 0; break; }
        }
        free(v);
    } else if (p->type == HD_T_CONE || p->type == HD_T_CUP || p->type == HD_T_CYLINDER || p->type == HD_T_TUBE) {
        hd_vec3 p0, p1;
        double r0, r1;
        hd_cone_get(p, &p0, &p1, &r0, &r1);
        double d[3] = {p1.x - p0.x, p1.y - p0.y, p1.z - p0.z}, len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (len > 0 && isfinite(len)) {
            o->kind = 3;
            for (int k = 0; k < 3; k++) o->n[k] = d[k] / len;
            o->c0[0] = p0.x; o->c0[1] = p0.y; o->c0[2] = p0.z;
            o->len = len;
            o->r0 = fabs(r0);
            o->r1 = fabs(r1);
        }
    } else if (p->type == HD_T_RING) {
        hd_vec3 c, nn;
        double rin, rout;
        hd_ring_get(p, &c, &nn, &rin, &rout);
        double len = sqrt(nn.x * nn.x + nn.y * nn.y + nn.z * nn.z);
        if (len > 0) {
            o->kind = 1;
            o->n[0] = nn.x / len; o->n[1] = nn.y / len; o->n[2] = nn.z / len;
            o->d = o->n[0] * c.x + o->n[1] * c.y + o->n[2] * c.z;
        }
    } else if (p->type == HD_T_SPHERE || p->type == HD_T_BUBBLE) {
        hd_vec3 c;
        double r;
        hd_sphere_get(p, &c, &r);
        o->kind = 2;
        o->n[0] = c.x; o->n[1] = c.y; o->n[2] = c.z;
        o->d = fabs(r);
    }
    return HD_OK;
}

hd_status hd_octree_write(const hd_scene *s, const char *path, int argc, char **argv,
                          char *const *files, int nfiles, const hd_octree_opts *o)
{
    if (s->nprims > (size_t)INT32_MAX / 2)
        return hd_fail(HD_ERR_RANGE, "too many primitives for an octree (%zu)", s->nprims);
    if (o->resolu < 1 || o->objlim < 1)
        return hd_fail(HD_ERR_USAGE, "octree resolution (-r) and leaf size (-n) must be positive");
    obj *objs = hd_malloc_array(s->nprims ? s->nprims : 1, sizeof *objs);
    if (!objs) return HD_ERR_NOMEM;
    size_t nobj = 0;
    double bmin[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, bmax[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    hd_status st = HD_OK;
    for (size_t i = 0; i < s->nprims && !st; i++) {
        int surf;
        if ((st = make_obj(s, i, &objs[nobj], &surf))) {
            const hd_prim *p = &s->prims[i];
            if ((p->type == HD_T_INSTANCE || p->type == HD_T_MESH) && st != HD_ERR_NOMEM) {
                /* heliodon's own cache still holds it; Radiance cannot use it */
                hd_warn("%s (left out of the octree: Radiance's programs will not see it)", hd_errmsg());
                st = HD_OK;
            }
            continue;
        }
        if (!surf) continue;
        bb_point(bmin, bmax, objs[nobj].bmin);
        bb_point(bmin, bmax, objs[nobj].bmax);
        nobj++;
    }
    if (st) { free(objs); return st; }
    double org[3] = {0, 0, 0}, size = 0;
    if (o->have_bound) {
        for (int k = 0; k < 3; k++) org[k] = o->bound[k] - OCT_MARGIN;
        size = o->bound[3] + 2 * OCT_MARGIN;
        for (int k = 0; k < 3 && nobj; k++)
            if (bmin[k] < org[k] || bmax[k] > org[k] + size) {
                free(objs);
                return hd_fail(HD_ERR_USAGE, "-b: boundary does not encompass scene");
            }
    } else if (nobj) {
        for (int k = 0; k < 3; k++) {
            bmin[k] -= OCT_MARGIN;
            bmax[k] += OCT_MARGIN;
            if (bmax[k] - bmin[k] > size) size = bmax[k] - bmin[k];
        }
        for (int k = 0; k < 3; k++) org[k] = (bmax[k] + bmin[k] - size) * .5;
    }
    builder b = {0};
    b.objs = objs;
    b.objlim = o->objlim;
    b.mincusize = size / (double)o->resolu - OCT_FTINY;
    b.s = s;
    b.cap = 1024;
    b.nodes = hd_malloc_array(b.cap, sizeof *b.nodes);
    if (!b.nodes) { free(objs); return HD_ERR_NOMEM; }
    memset(b.nodes, 0, sizeof *b.nodes);
    b.nnodes = 1;
    for (size_t j = 0; j < nobj && !st; j++) st = add(&b, 0, org, size, (int32_t)j);

    /* assembled in memory: the trailer needs the cache body's offset */
    char *mem = NULL;
    size_t memlen = 0;
    FILE *fp = NULL;
    if (!st && !(fp = open_memstream(&mem, &memlen))) st = hd_fail(HD_ERR_NOMEM, "cannot buffer the octree");
    if (!st) {
        hd_header h;
        hd_header_init(&h);
        if (argc > 0) st = hd_header_add_command(&h, argc, argv);
        if (!st) st = hd_header_put(fp, &h, NULL, "Radiance_octree", NULL);
        hd_header_free(&h);
    }
    if (!st) {
        hd_put_int(fp, OCT_MAGIC + OCT_OBJSIZE, 2);
        char buf[64];
        for (int k = 0; k < 3; k++) { snprintf(buf, sizeof buf, "%.12g", org[k]); put_nstr(fp, buf); }
        snprintf(buf, sizeof buf, "%.12g", size);
        put_nstr(fp, buf);
        if (!o->frozen)
            for (int k = 0; k < nfiles; k++) put_nstr(fp, files[k]);
        put_nstr(fp, "");
        hd_put_int(fp, (long)s->nprims, OCT_OBJSIZE);
        put_tree(fp, &b, 0);
        if (o->frozen) put_scene(fp, s);
        /* heliodon's parsed scene after Radiance's data, then the trailer */
        fflush(fp);
        unsigned long long off = memlen;
        st = hd_scene_cache_write_body(s, fp);
        fwrite("HDSCACHE", 1, 8, fp);
        for (int k = 0; k < 8; k++) putc((int)((off >> (8 * k)) & 255), fp);
    }
    if (fp && fclose(fp) && !st) st = hd_fail(HD_ERR_NOMEM, "cannot buffer the octree");
    hd_ofile *of = NULL;
    if (!st) st = hd_ofile_open(&of, path);
    if (!st) {
        if (fwrite(mem, 1, memlen, hd_ofile_fp(of)) != memlen) {
            hd_ofile_abort(of);
            st = hd_fail(HD_ERR_IO, "%s: write error", path ? path : "standard output");
        } else {
            st = hd_ofile_commit(of);
        }
    }
    free(mem);
    for (size_t i = 0; i < b.nnodes; i++) free(b.nodes[i].set);
    free(b.nodes);
    free(objs);
    return st;
}

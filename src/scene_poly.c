/* heliodon — polygon normals (Newell) and triangulation by ear clipping,
 * robust to Radiance's seam-edge holes (coincident edges joining an inner
 * loop to the outer one), collinear vertices and duplicate vertices. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/scene.h"

hd_vec3 hd_polygon_normal(const hd_vec3 *v, uint32_t n, double *area)
{
    hd_vec3 s = {0, 0, 0};
    for (uint32_t i = 0; i < n; i++) {
        hd_vec3 a = v[i], b = v[(i + 1) % n];
        s.x += (a.y - b.y) * (a.z + b.z);
        s.y += (a.z - b.z) * (a.x + b.x);
        s.z += (a.x - b.x) * (a.y + b.y);
    }
    double len = hd_vlen(s);
    if (area) *area = 0.5 * len;
    return len > 0 ? hd_vscale(s, 1.0 / len) : s;
}

typedef struct { double x, y; } p2;

static double cross3(p2 a, p2 b, p2 c)   /* (b-a) x (c-a) */
{
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

static int same(p2 a, p2 b, double eps) { return fabs(a.x - b.x) <= eps && fabs(a.y - b.y) <= eps; }

/* strictly inside triangle abc (counter-clockwise), with tolerance */
static int inside_tri(p2 a, p2 b, p2 c, p2 q, double eps2)
{
    return cross3(a, b, q) > eps2 && cross3(b, c, q) > eps2 && cross3(c, a, q) > eps2;
}

/* do open segments ab and cd properly cross? */
static int seg_cross(p2 a, p2 b, p2 c, p2 d, double eps2)
{
    double d1 = cross3(a, b, c), d2 = cross3(a, b, d), d3 = cross3(c, d, a), d4 = cross3(c, d, b);
    return ((d1 > eps2 && d2 < -eps2) || (d1 < -eps2 && d2 > eps2)) &&
           ((d3 > eps2 && d4 < -eps2) || (d3 < -eps2 && d4 > eps2));
}

hd_status hd_polygon_triangulate(const hd_vec3 *v, uint32_t n, uint32_t *tri, uint32_t *ntri)
{
    *ntri = 0;
    if (n < 3) return hd_fail(HD_ERR_FORMAT, "polygon: fewer than 3 vertices");
    double area;
    hd_vec3 nrm = hd_polygon_normal(v, n, &area);
    if (!(area > 0)) return hd_fail(HD_ERR_FORMAT, "polygon: zero area");
    /* project: drop the dominant axis, keep counter-clockwise orientation */
    int ax = fabs(nrm.x) > fabs(nrm.y) ? (fabs(nrm.x) > fabs(nrm.z) ? 0 : 2) : (fabs(nrm.y) > fabs(nrm.z) ? 1 : 2);
    double sgn = hd_vget(nrm, ax) >= 0 ? 1.0 : -1.0;
    p2 *q = hd_malloc_array(n, sizeof *q);
    uint32_t *idx = hd_malloc_array(n, sizeof *idx);
    if (!q || !idx) { free(q); free(idx); return HD_ERR_NOMEM; }
    double minx = INFINITY, maxx = -INFINITY, miny = INFINITY, maxy = -INFINITY;
    for (uint32_t i = 0; i < n; i++) {
        double x, y;
        if (ax == 0) { x = v[i].y; y = v[i].z; }
        else if (ax == 1) { x = v[i].z; y = v[i].x; }
        else { x = v[i].x; y = v[i].y; }
        if (sgn < 0) { double t = x; x = y; y = t; }
        q[i].x = x; q[i].y = y;
        if (x < minx) minx = x;
        if (x > maxx) maxx = x;
        if (y < miny) miny = y;
        if (y > maxy) maxy = y;
    }
    double size = fmax(maxx - minx, maxy - miny);
    double eps = 1e-12 * size, eps2 = 1e-14 * size * size;
    /* active vertex list without consecutive duplicates */
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; i++)
        if (!m || !same(q[idx[m - 1]], q[i], eps)) idx[m++] = i;
    while (m > 1 && same(q[idx[m - 1]], q[idx[0]], eps)) m--;
    uint32_t k = 0, fails = 0;
    int relaxed = 0;
    while (m > 3) {
        if (k >= m) k = 0;
        uint32_t ip = idx[(k + m - 1) % m], ii = idx[k], in = idx[(k + 1) % m];
        p2 a = q[ip], b = q[ii], c = q[in];
        double cr = cross3(a, b, c);
        double la = hypot(b.x - a.x, b.y - a.y), lc = hypot(c.x - b.x, c.y - b.y);
        int degenerate = fabs(cr) <= 1e-10 * la * lc || same(a, c, eps);
        int ear = 0;
        if (degenerate) {
            ear = 1;   /* collinear or spike: remove without a triangle */
        } else if (cr > 0) {
            ear = 1;
            for (uint32_t j = 0; j < m && ear; j++) {
                uint32_t vj = idx[j];
                if (vj == ip || vj == ii || vj == in) continue;
                p2 t = q[vj];
                if (same(t, a, eps) || same(t, b, eps) || same(t, c, eps)) {
                    /* a seam twin of the ear tip: its edges must not enter the ear */
                    if (same(t, b, eps)) {
                        p2 tp = q[idx[(j + m - 1) % m]], tn = q[idx[(j + 1) % m]];
                        p2 mid1 = {0.5 * (t.x + tp.x), 0.5 * (t.y + tp.y)};
                        p2 mid2 = {0.5 * (t.x + tn.x), 0.5 * (t.y + tn.y)};
                        if ((!same(tp, a, eps) && !same(tp, c, eps) && inside_tri(a, b, c, mid1, eps2)) ||
                            (!same(tn, a, eps) && !same(tn, c, eps) && inside_tri(a, b, c, mid2, eps2)))
                            ear = 0;
                    }
                    continue;
                }
                if (inside_tri(a, b, c, t, eps2)) ear = 0;
            }
            /* the new diagonal a-c must not cross any other edge */
            for (uint32_t j = 0; j < m && ear && !relaxed; j++) {
                uint32_t e0 = idx[j], e1 = idx[(j + 1) % m];
                if (e0 == ip || e0 == ii || e1 == ii || e1 == in) continue;
                if (seg_cross(a, c, q[e0], q[e1], eps2)) ear = 0;
            }
        } else if (relaxed > 1) {
            ear = 0;
        }
        if (relaxed > 1 && !ear && cr > 0) ear = 1;   /* last resort: force progress */
        if (ear) {
            if (!degenerate) {
                tri[3 * *ntri] = ip; tri[3 * *ntri + 1] = ii; tri[3 * *ntri + 2] = in;
                (*ntri)++;
            }
            memmove(idx + k, idx + k + 1, (m - k - 1) * sizeof *idx);
            m--;
            if (k > 0) k--;
            fails = 0;
            relaxed = 0;
            /* drop a duplicate created by the removal */
            if (m > 1) {
                uint32_t kp = (k + m - 1) % m;
                if (same(q[idx[kp]], q[idx[k % m]], eps)) {
                    memmove(idx + k % m, idx + k % m + 1, (m - k % m - 1) * sizeof *idx);
                    m--;
                }
            }
            continue;
        }
        k++;
        if (++fails > m) {
            fails = 0;
            if (++relaxed > 2) break;   /* give up: no ear even when forced */
        }
    }
    if (m == 3) {
        p2 a = q[idx[0]], b = q[idx[1]], c = q[idx[2]];
        if (cross3(a, b, c) > eps2) {
            tri[3 * *ntri] = idx[0]; tri[3 * *ntri + 1] = idx[1]; tri[3 * *ntri + 2] = idx[2];
            (*ntri)++;
        }
    }
    free(q);
    free(idx);
    if (!*ntri) return hd_fail(HD_ERR_FORMAT, "polygon: could not triangulate (degenerate)");
    return HD_OK;
}

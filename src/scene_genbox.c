/* heliodon — genbox: boxes as Radiance polygons (optionally rounded or
 * bevelled edges). */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "heliodon/xform.h"

typedef struct box { double size[3], d; int invert; const char *mat, *name; FILE *out; } box;

static void put_prim(box *b, hd_prim_type t, const char *id, const double *r, uint32_t n)
{
    hd_prim pr;
    memset(&pr, 0, sizeof pr);
    pr.type = t;
    pr.modname = b->mat;
    pr.id = id;
    pr.nrargs = n;
    pr.rargs = (double *)r;
    hd_prim_write(b->out, &pr);
}

static void put_poly(box *b, const char *id, hd_vec3 *v, int n, hd_vec3 outward)
{
    double area;
    hd_vec3 nrm = hd_polygon_normal(v, (uint32_t)n, &area);
    int rev = (hd_vdot(nrm, outward) < 0) ^ (b->invert != 0);
    double r[12];
    for (int k = 0; k < n; k++) {
        hd_vec3 p = v[rev ? n - 1 - k : k];
        r[3 * k] = p.x; r[3 * k + 1] = p.y; r[3 * k + 2] = p.z;
    }
    put_prim(b, HD_T_POLYGON, id, r, (uint32_t)(3 * n));
}

/* coordinate along axis a for a corner bit: face value or inset value */
static double at(const box *b, int a, int bit, int inset)
{
    double d = inset ? b->d : 0;
    return bit ? b->size[a] - d : d;
}

static hd_vec3 vec_axes(double c[3]) { return hd_v3(c[0], c[1], c[2]); }

hd_status hd_genbox_write(FILE *out, const char *mat, const char *name, double x, double y, double z,
                          int invert, double round, double bevel, int argc, char *const *argv)
{
    if (!(x > 0 && y > 0 && z > 0) || !isfinite(x) || !isfinite(y) || !isfinite(z))
        return hd_fail(HD_ERR_USAGE, "box sizes must be positive numbers");
    if (round > 0 && bevel > 0) return hd_fail(HD_ERR_USAGE, "-r and -b are exclusive");
    double d = round > 0 ? round : bevel > 0 ? bevel : 0;
    if (d < 0 || 2 * d >= fmin(x, fmin(y, z)))
        return hd_fail(HD_ERR_USAGE, "rounding/bevel radius %g must be less than half the smallest size", d);
    box b = {{x, y, z}, d, invert, mat, name, out};
    fprintf(out, "# %s", hd_progname());
    for (int i = 1; i < argc; i++) fprintf(out, " %s", argv[i]);
    fputc('\n', out);
    static const char *faces[6] = {"1540", "4620", "2310", "3267", "5137", "6457"};
    char id[1024];
    for (int f = 0; f < 6; f++) {
        hd_vec3 v[4];
        int c0 = faces[f][0] - '0';
        /* the face's fixed axis: the bit shared by all four corners */
        int and = 7, or = 0;
        for (int k = 0; k < 4; k++) { and &= faces[f][k] - '0'; or |= faces[f][k] - '0'; }
        int axis = 0, side = 0;
        for (int a = 0; a < 3; a++) {
            if (and & (1 << a)) { axis = a; side = 1; }
            else if (!(or & (1 << a))) { axis = a; side = 0; }
        }
        (void)c0;
        for (int k = 0; k < 4; k++) {
            int c = faces[f][k] - '0';
            double p[3];
            for (int a = 0; a < 3; a++) p[a] = at(&b, a, (c >> a) & 1, a != axis);
            v[k] = vec_axes(p);
        }
        double o[3] = {0, 0, 0};
        o[axis] = side ? 1 : -1;
        snprintf(id, sizeof id, "%s.%s", name, faces[f]);
        put_poly(&b, id, v, 4, vec_axes(o));
    }
    if (d <= 0) return ferror(out) ? hd_fail(HD_ERR_IO, "write error") : HD_OK;
    /* edges: along axis c, at corner bits (sa on axis a, sb on axis b) */
    for (int c = 0; c < 3; c++) {
        int a = (c + 1) % 3, bb = (c + 2) % 3;
        for (int s = 0; s < 4; s++) {
            int sa = s & 1, sb = s >> 1;
            int c0 = (sa << a) | (sb << bb), c1 = c0 | (1 << c);
            snprintf(id, sizeof id, "%s.e%d%d", name, c0, c1);
            if (round > 0) {
                double p0[3], p1[3], r[7];
                p0[a] = p1[a] = at(&b, a, sa, 1);
                p0[bb] = p1[bb] = at(&b, bb, sb, 1);
                p0[c] = d; p1[c] = b.size[c] - d;
                memcpy(r, p0, sizeof p0); memcpy(r + 3, p1, sizeof p1); r[6] = d;
                put_prim(&b, invert ? HD_T_TUBE : HD_T_CYLINDER, id, r, 7);
            } else {
                hd_vec3 v[4];
                double p[3];
                double cs[2] = {d, b.size[c] - d};
                /* on the face normal to a: a at face, bb inset; then the face normal to bb */
                for (int k = 0; k < 2; k++) {
                    p[c] = cs[k]; p[a] = at(&b, a, sa, 0); p[bb] = at(&b, bb, sb, 1);
                    v[k] = vec_axes(p);
                    p[c] = cs[1 - k]; p[a] = at(&b, a, sa, 1); p[bb] = at(&b, bb, sb, 0);
                    v[2 + k] = vec_axes(p);
                }
                double o[3];
                o[c] = 0; o[a] = sa ? 1 : -1; o[bb] = sb ? 1 : -1;
                put_poly(&b, id, v, 4, vec_axes(o));
            }
        }
    }
    for (int c = 0; c < 8; c++) {
        snprintf(id, sizeof id, "%s.c%d", name, c);
        double o[3], p[3];
        for (int a = 0; a < 3; a++) o[a] = (c >> a) & 1 ? 1 : -1;
        if (round > 0) {
            double r[4];
            for (int a = 0; a < 3; a++) r[a] = at(&b, a, (c >> a) & 1, 1);
            r[3] = d;
            put_prim(&b, invert ? HD_T_BUBBLE : HD_T_SPHERE, id, r, 4);
        } else {
            hd_vec3 v[3];
            for (int k = 0; k < 3; k++) {
                for (int a = 0; a < 3; a++) p[a] = at(&b, a, (c >> a) & 1, a != k);
                v[k] = vec_axes(p);
            }
            put_poly(&b, id, v, 3, vec_axes(o));
        }
    }
    return ferror(out) ? hd_fail(HD_ERR_IO, "write error") : HD_OK;
}

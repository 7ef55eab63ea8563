/* heliodon — gensurf: a parametric surface x(s,t), y(s,t), z(s,t) on
 * [0,1]² tessellated into m × n cells, each written as one quadrilateral
 * when its two triangles are coplanar, else as two triangles, in Radiance's
 * text layout.  With smoothing, each cell carries a "Phong" texfunc
 * (lib/surf.cal) whose perturbation interpolates the vertex normals
 * (averaged from the neighbouring grid points) bilinearly in the two
 * coordinates across the cell's dominant axis.  Points where a function
 * valid(s,t) is not positive are left out (cells with fewer than three
 * valid corners too). */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/cal.h"
#include "heliodon/xform.h"

#define GS_TINY 1e-7

typedef struct gpoint {
    int valid;
    hd_vec3 p, n;
} gpoint;

typedef struct gsurf {
    FILE *out;
    const hd_gensurf_opts *o;
    hd_calrun *run;
    int fx, fy, fz, fvalid;
    int nout;
} gsurf;

static void put3(FILE *f, hd_vec3 v) { fprintf(f, "%18.12g %18.12g %18.12g\n", v.x, v.y, v.z); }

static void row_values(gsurf *g, double s, gpoint *row)
{
    int n = g->o->n, lo = 0, hi = n;
    if (g->o->smooth) { lo = -1; hi = n + 1; }
    else if (s < -GS_TINY || s > 1 + GS_TINY) return;
    for (int i = lo; i <= hi; i++) {
        double st[2] = {s, (double)i / n};
        gpoint *q = &row[i];
        if (g->fvalid >= 0 && hd_calrun_call_id(g->run, g->fvalid, 2, st) <= 0) {
            q->valid = 0;
            q->p = hd_v3(0, 0, 0);
            continue;
        }
        q->valid = 1;
        q->p = hd_v3(hd_calrun_call_id(g->run, g->fx, 2, st), hd_calrun_call_id(g->run, g->fy, 2, st),
                     hd_calrun_call_id(g->run, g->fz, 2, st));
    }
}

/* vertex normals of row r1 from the differences to its neighbours */
static void row_normals(gsurf *g, const gpoint *r0, gpoint *r1, const gpoint *r2)
{
    if (!g->o->smooth) return;
    for (int i = 0; i <= g->o->n; i++) {
        gpoint *q = &r1[i];
        if (!q->valid) continue;
        hd_vec3 ds, dt;
        if (r0[i].valid && r2[i].valid) ds = hd_vsub(r2[i].p, r0[i].p);
        else if (r2[i].valid) ds = hd_vsub(r2[i].p, q->p);
        else if (r0[i].valid) ds = hd_vsub(q->p, r0[i].p);
        else { q->n = hd_v3(0, 0, 0); continue; }
        if (r1[i - 1].valid && r1[i + 1].valid) dt = hd_vsub(r1[i + 1].p, r1[i - 1].p);
        else if (r1[i + 1].valid) dt = hd_vsub(r1[i + 1].p, q->p);
        else if (r1[i - 1].valid) dt = hd_vsub(q->p, r1[i - 1].p);
        else { q->n = hd_v3(0, 0, 0); continue; }
        hd_vec3 c = g->o->rev ? hd_vcross(dt, ds) : hd_vcross(ds, dt);
        double len = hd_vlen(c);
        q->n = len > 0 ? hd_vscale(c, 1 / len) : c;
    }
}

static double comp(hd_vec3 v, int k) { return k == 0 ? v.x : k == 1 ? v.y : v.z; }

/* Gauss-Jordan inversion with partial pivoting; 0 if a pivot is tiny */
static int inverse4(double a[4][4], double inv[4][4])
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) inv[i][j] = i == j;
    for (int c = 0; c < 4; c++) {
        int piv = -1;
        double best = GS_TINY;
        for (int r = c; r < 4; r++)
            if (fabs(a[r][c]) > best) { best = fabs(a[r][c]); piv = r; }
        if (piv < 0) return 0;
        if (piv != c)
            for (int k = 0; k < 4; k++) {
                double t = a[c][k]; a[c][k] = a[piv][k]; a[piv][k] = t;
                t = inv[c][k]; inv[c][k] = inv[piv][k]; inv[piv][k] = t;
            }
        double d = a[c][c];
        for (int k = 0; k < 4; k++) { a[c][k] /= d; inv[c][k] /= d; }
        for (int r = 0; r < 4; r++) {
            if (r == c) continue;
            double f = a[r][c];
            for (int k = 0; k < 4; k++) { a[r][k] -= a[c][k] * f; inv[r][k] -= inv[c][k] * f; }
        }
    }
    return 1;
}

/* The bilinear normal interpolation of a cell: the dominant axis (or -1)
 * and the 4 x 3 matrix M with n(u, v) = [u*v u v 1] M at the corners. */
static int normal_fit(const gsurf *g, const gpoint *q[4], hd_vec3 M[4])
{
    if (!g->o->smooth) return -1;
    hd_vec3 s = hd_vadd(hd_vadd(q[0]->n, q[1]->n), hd_vadd(q[2]->n, q[3]->n));
    int ax = fabs(s.x) > fabs(s.y) ? 0 : 1;
    ax = fabs(comp(s, ax)) > fabs(s.z) ? ax : 2;
    int u = (ax + 1) % 3, v = (ax + 2) % 3;
    double a[4][4], inv[4][4];
    for (int k = 0; k < 4; k++) {
        double pu = comp(q[k]->p, u), pv = comp(q[k]->p, v);
        a[k][0] = pu * pv;
        a[k][1] = pu;
        a[k][2] = pv;
        a[k][3] = 1;
    }
    if (!inverse4(a, inv)) return -1;
    for (int j = 0; j < 4; j++) {
        hd_vec3 r = {0, 0, 0};
        for (int k = 0; k < 4; k++) r = hd_vadd(r, hd_vscale(q[k]->n, inv[j][k]));
        M[j] = r;
    }
    return ax;
}

static void put_poly(gsurf *g, int ax, const hd_vec3 M[4], hd_vec3 last, const hd_vec3 *v, int nv)
{
    FILE *f = g->out;
    fprintf(f, "\n%s ", g->o->mat);
    if (ax >= 0) {
        fprintf(f, "texfunc Phong\n4 surf_dx surf_dy surf_dz surf.cal\n0\n13\t%d\n", ax);
        put3(f, M[0]);
        put3(f, M[1]);
        put3(f, M[2]);
        put3(f, last);
        fprintf(f, "\nPhong ");
    }
    fprintf(f, "polygon %s.%d\n0\n0\n%d\n", g->o->name, ++g->nout, 3 * nv);
    for (int k = 0; k < nv; k++) put3(f, v[k]);
}

/* corners p0 p1 p2 p3: triangles (p0, p1, p2) and (p2, p1, p3) */
static void put_cell(gsurf *g, const gpoint *p0, const gpoint *p1, const gpoint *p2, const gpoint *p3)
{
    if (g->o->rev) { const gpoint *t = p1; p1 = p2; p2 = t; }
    hd_vec3 c1 = {0, 0, 0}, c2 = {0, 0, 0};
    int ok1 = p0->valid && p1->valid && p2->valid, ok2 = p1->valid && p2->valid && p3->valid;
    if (ok1) {
        c1 = hd_vcross(hd_vsub(p1->p, p0->p), hd_vsub(p2->p, p0->p));
        double l = hd_vlen(c1);
        if ((ok1 = l > 0)) c1 = hd_vscale(c1, 1 / l);
    }
    if (ok2) {
        c2 = hd_vcross(hd_vsub(p2->p, p3->p), hd_vsub(p1->p, p3->p));
        double l = hd_vlen(c2);
        if ((ok2 = l > 0)) c2 = hd_vscale(c2, 1 / l);
    }
    if (!ok1 && !ok2) return;
    const gpoint *q[4] = {p0, p1, p2, p3};
    hd_vec3 M[4];
    int ax = normal_fit(g, q, M);
    if (ok1 && ok2 && hd_vdot(c1, c2) >= 1 - GS_TINY * GS_TINY) {
        /* one quadrilateral: the constant row lowered by the mean facet normal */
        hd_vec3 last = ax >= 0 ? hd_vadd(hd_vadd(M[3], hd_vscale(c1, -.5)), hd_vscale(c2, -.5)) : M[0];
        hd_vec3 v[4] = {p0->p, p1->p, p3->p, p2->p};
        put_poly(g, ax, M, last, v, 4);
        return;
    }
    if (ok1) {
        hd_vec3 v[3] = {p0->p, p1->p, p2->p};
        put_poly(g, ax, M, ax >= 0 ? hd_vsub(M[3], c1) : M[0], v, 3);
    }
    if (ok2) {
        hd_vec3 v[3] = {p2->p, p1->p, p3->p};
        put_poly(g, ax, M, ax >= 0 ? hd_vsub(M[3], c2) : M[0], v, 3);
    }
}

hd_status hd_gensurf_write(FILE *out, hd_cal *cal, const hd_gensurf_opts *o)
{
    if (o->m <= 0 || o->n <= 0 || o->m > 100000000 / (o->n + 3))
        return hd_fail(HD_ERR_RANGE, "gensurf: bad grid size %d x %d", o->m, o->n);
    hd_status st = HD_OK;
    static const char *names[3] = {"X`SYS", "Y`SYS", "Z`SYS"};
    const char *ex[3] = {o->xe, o->ye, o->ze};
    for (int k = 0; k < 3 && !st; k++) {
        size_t len = strlen(ex[k]) + 32;
        char *def = hd_malloc(len);
        if (!def) return HD_ERR_NOMEM;
        snprintf(def, len, "%s(s,t)=%s;", names[k], ex[k]);
        st = hd_cal_parse(cal, def, "gensurf");
        free(def);
    }
    if (st) return st;
    gsurf g = {out, o, NULL, hd_cal_lookup(cal, names[0]), hd_cal_lookup(cal, names[1]), hd_cal_lookup(cal, names[2]),
               hd_cal_nparams(cal, "valid") == 2 ? hd_cal_lookup(cal, "valid") : -1, 0};
    int n = o->n;
    gpoint *buf = hd_calloc(3 * ((size_t)n + 3), sizeof *buf);
    if (!buf || !(g.run = hd_calrun_new(cal, NULL))) { free(buf); return HD_ERR_NOMEM; }
    gpoint *r0 = buf + 1, *r1 = buf + n + 4, *r2 = buf + 2 * (n + 3) + 1;
    row_values(&g, -1.0 / o->m, r0);
    row_values(&g, 0.0, r1);
    row_values(&g, 1.0 / o->m, r2);
    row_normals(&g, r0, r1, r2);
    for (int i = 0; i < o->m && !st; i++) {
        gpoint *t = r0;
        r0 = r1;
        r1 = r2;
        r2 = t;
        hd_calrun_next(g.run);
        row_values(&g, (double)(i + 2) / o->m, r2);
        row_normals(&g, r0, r1, r2);
        for (int j = 0; j < n; j++) {
            int orient = j & 1;
            if (!(r0[j].valid && r1[j + 1].valid)) orient = 1;
            else if (!(r1[j].valid && r0[j + 1].valid)) orient = 0;
            if (orient) put_cell(&g, &r0[j], &r1[j], &r0[j + 1], &r1[j + 1]);
            else put_cell(&g, &r1[j], &r1[j + 1], &r0[j], &r0[j + 1]);
        }
        st = hd_calrun_status(g.run);
    }
    hd_calrun_free(g.run);
    free(buf);
    return st;
}

/* ---- shared by the generators ---- */
static const char curves[] =
    "hermite(p0,p1,r0,r1,t) : p0*((2*t-3)*t*t+1) + p1*(3-2*t)*t*t + r0*((t-2)*t+1)*t + r1*(t-1)*t*t;\n"
    "bezier(p1,p2,p3,p4,t) : p1*(1+t*(-3+t*(3-t))) + p2*3*t*(1+t*(t-2)) + p3*3*t*t*(1-t) + p4*t*t*t;\n"
    "bspline(pp,p0,p1,pn,t) : pp*(1/6+t*(-1/2+t*(1/2-t/6))) + p0*(2/3+t*t*(t/2-1))"
    " + p1*(1/6+t*(1/2+t*(1/2-t/2))) + pn*t*t*t/6;\n";

hd_status hd_gen_define_curves(hd_cal *cal)
{
    hd_status st = hd_cal_set(cal, "PI", 3.14159265358979323846, 1);
    return st ? st : hd_cal_parse(cal, curves, "curves");
}

/* a word of the command line as Radiance's headers write it */
static void put_word(FILE *out, const char *w)
{
    int quote = 0, space = !*w;
    for (const char *c = w; *c; c++) {
        if (isspace((unsigned char)*c)) space = 1;
        else if (c > w && c[1] && *c == '"') quote = '\'';
        else if (c > w && c[1] && *c == '\'') quote = '"';
    }
    if (space || quote) fprintf(out, "%c%s%c", quote ? quote : '"', w, quote ? quote : '"');
    else fputs(w, out);
}

void hd_gen_print_command(FILE *out, const char *prog, int argc, char **argv)
{
    fputs("# ", out);
    for (int i = 0; i < argc; i++) {
        if (i) putc(' ', out);
        put_word(out, i ? argv[i] : prog);
    }
    putc('\n', out);
}

/* ---- genrev ---- */
/* unit normal (in the z-r plane) of the step from (z0, r0) to (z1, r1),
 * pointing to the right of the direction of travel: out for rising z */
static void step_normal(double z0, double r0, double z1, double r1, double *nz, double *nr)
{
    double a = r0 - r1, b = z1 - z0, len = sqrt(a * a + b * b);
    *nz = a / len;
    *nr = b / len;
}

hd_status hd_genrev_write(FILE *out, hd_cal *cal, const char *mat, const char *name, const char *ze,
                          const char *re, int nseg, int smooth)
{
    const double tiny = 1e-9;
    char *def = malloc(strlen(ze) + strlen(re) + 64);
    if (!def) return HD_ERR_NOMEM;
    sprintf(def, "Z`genrev(t) = %s;\nR`genrev(t) = %s;\n", ze, re);
    hd_status st = hd_cal_parse(cal, def, "genrev");
    free(def);
    if (st) return st;
    hd_calrun *run = hd_calrun_new(cal, NULL);
    if (!run) return HD_ERR_NOMEM;
    /* the curve at t = k / nseg */
    double *z = malloc(sizeof *z * (size_t)(nseg + 1)), *r = malloc(sizeof *r * (size_t)(nseg + 1));
    if (!z || !r) { free(z); free(r); hd_calrun_free(run); return HD_ERR_NOMEM; }
    for (int k = 0; k <= nseg && !st; k++) {
        double t = (double)k / nseg;
        hd_calrun_next(run);
        z[k] = hd_calrun_call(run, "Z`genrev", 1, &t);
        r[k] = hd_calrun_call(run, "R`genrev", 1, &t);
        st = hd_calrun_status(run);
    }
    hd_calrun_free(run);
    const char *m = smooth ? "Phong" : mat;
    /* normals of the step before (0 before the first), this and the next (0 after the last) */
    double pnz = 0, pnr = 0, nz, nr;
    if (!st) step_normal(z[0], r[0], z[1], r[1], &nz, &nr);
    for (int i = 1; i <= nseg && !st; i++) {
        double qnz = 0, qnr = 0;
        if (i < nseg) step_normal(z[i], r[i], z[i + 1], r[i + 1], &qnz, &qnr);
        double z0 = z[i - 1], r0 = r[i - 1], z1 = z[i], r1 = r[i];
        int down = z1 < z0 - tiny, up = z1 > z0 + tiny, in = r1 < r0 - tiny, outw = r1 > r0 + tiny;
        if (down || up || in || outw) {
            if (smooth) {
                /* rev.cal's A1..A4: the normal's z and r components as
                 * linear functions of z and r across the step, from the
                 * neighbouring steps' normals */
                fprintf(out, "\n%s texfunc Phong\n4 rev_dx rev_dy rev_dz rev.cal\n0\n4\n", mat);
                if (up || down) {
                    double k = (qnz - pnz) / (z1 - z0);
                    fprintf(out, "\t%18.12g\t%18.12g\n", k, pnz - k * z0);
                } else {
                    fprintf(out, "\t0\t%d\n", in ? 1 : -1);
                }
                if (in || outw) {
                    double k = (qnr - pnr) / (r1 - r0);
                    fprintf(out, "\t%18.12g\t%18.12g\n", k, pnr - k * r0);
                } else {
                    fprintf(out, "\t0\t%d\n", up ? 1 : -1);
                }
            }
            if (!in && !outw) {
                fprintf(out, "\n%s %s %s.%d\n0\n0\n7\n", m, down ? "tube" : "cylinder", name, i);
                fprintf(out, "\t0\t0\t%18.12g\n\t0\t0\t%18.12g\n\t%18.12g\n", z0, z1, r1);
            } else if (!up && !down) {
                fprintf(out, "\n%s ring %s.%d\n0\n0\n8\n", m, name, i);
                fprintf(out, "\t0\t0\t%18.12g\n\t0\t0\t%18.12g\n\t%18.12g\t%18.12g\n", z1, in ? 1.0 : -1.0, r0, r1);
            } else {
                fprintf(out, "\n%s %s %s.%d\n0\n0\n8\n", m, down ? "cup" : "cone", name, i);
                fprintf(out, "\t0\t0\t%18.12g\n\t0\t0\t%18.12g\n\t%18.12g\t%18.12g\n", z0, z1, r0, r1);
            }
        }
        pnz = nz; pnr = nr;
        nz = qnz; nr = qnr;
    }
    free(z);
    free(r);
    return st;
}

/* ---- genprism ---- */
#define PRISM_TINY 1e-6

static void prism_pt(FILE *out, double x, double y, double z) { fprintf(out, "\t%18.12g\t%18.12g\t%18.12g\n", x, y, z); }

hd_status hd_genprism_write(FILE *out, const hd_genprism_opts *o, const char *header)
{
    int n = o->n;
    const double (*v)[2] = o->v, *l = o->l;
    int dir = l[2] < 0 ? -1 : 1;                 /* the extrusion's side of the plane */
    double len = sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
    double rad = o->round > PRISM_TINY ? o->round : 0;
    if (rad > 0 && rad > dir * l[2]) return hd_fail(HD_ERR_RANGE, "rounding greater than height");
    double (*u)[2] = NULL, *a = NULL;            /* unit vectors of the sides into each vertex, corner trims */
    if (rad > 0) {
        rad *= dir;
        u = malloc(sizeof *u * (size_t)n);
        a = malloc(sizeof *a * (size_t)n);
        if (!u || !a) { free(u); free(a); return HD_ERR_NOMEM; }
        for (int i = 0; i < n; i++) {            /* side from vertex i-1 to i, pointing back */
            const double *p0 = v[(i + n - 1) % n], *p1 = v[i];
            double dx = p0[0] - p1[0], dy = p0[1] - p1[1], d = sqrt(dx * dx + dy * dy);
            if (d <= PRISM_TINY) { free(u); free(a); return hd_fail(HD_ERR_FORMAT, "Degenerate side in prism"); }
            u[i][0] = dx / d;
            u[i][1] = dy / d;
        }
        for (int i = n - 1; i >= 0; i--) {       /* half-angle tangent of the corner at vertex i */
            const double *ui = u[i], *un = u[(i + 1) % n];
            double c = ui[0] * un[0] + ui[1] * un[1];
            if (1 + c <= PRISM_TINY) { free(u); free(a); return hd_fail(HD_ERR_FORMAT, "Overlapping sides in prism"); }
            if (1 - c <= 0) { a[i] = 0; continue; }
            a[i] = sqrt((1 - c) / (1 + c));
            if (un[0] * ui[1] - un[1] * ui[0] < 0) a[i] = -a[i];
        }
    }
    fprintf(out, "%s", header);
    /* the inset corner points of the rounded faces */
#define CX(i) (v[i][0] + rad * (a[i] * u[i][0] - u[i][1]))
#define CY(i) (v[i][1] + rad * (a[i] * u[i][1] + u[i][0]))
    if (o->ends) {
        fprintf(out, "\n%s polygon %s.b\n0\n0\n%d\n", o->mat, o->name, 3 * n);
        for (int i = 0; i < n; i++)
            if (rad != 0) prism_pt(out, CX(i), CY(i), 0);
            else prism_pt(out, v[i][0], v[i][1], 0);
        fprintf(out, "\n%s polygon %s.t\n0\n0\n%d\n", o->mat, o->name, 3 * n);
        for (int i = n - 1; i >= 0; i--)
            if (rad != 0) prism_pt(out, CX(i) + l[0], CY(i) + l[1], l[2]);
            else prism_pt(out, v[i][0] + l[0], v[i][1] + l[1], l[2]);
        if (rad != 0) {
            /* the edges round the two ends: cylinders between the corner
             * points, spheres on the convex corners */
            for (int e = 0; e < 2; e++) {
                double ox = e ? l[0] : 0, oy = e ? l[1] : 0, z = e ? l[2] - rad : rad;
                double x0 = CX(n - 1) + ox, y0 = CY(n - 1) + oy;
                for (int i = 0; i < n; i++) {
                    double x1 = CX(i) + ox, y1 = CY(i) + oy;
                    if (dir * a[i] > 0)
                        fprintf(out, "\n%s sphere %s.%cc%d\n0\n0\n4 %18.12g %18.12g %18.12g %18.12g\n", o->mat,
                                o->name, e ? 't' : 'b', i + 1, x1, y1, z, dir * rad);
                    fprintf(out, "\n%s cylinder %s.%ce%d\n0\n0\n7\n", o->mat, o->name, e ? 't' : 'b', i + 1);
                    prism_pt(out, x0, y0, z);
                    prism_pt(out, x1, y1, z);
                    fprintf(out, "\t%18.12g\n", dir * rad);
                    x0 = x1;
                    y0 = y1;
                }
            }
        }
    }
    int nsides = o->complete ? n - 1 : n;
    for (int k = 0; k < nsides; k++) {
        int i = k, j = (k + 1) % n;
        fprintf(out, "\n%s polygon %s.%d\n0\n0\n12\n", o->mat, o->name, i + 1);
        if (rad == 0) {
            prism_pt(out, v[i][0], v[i][1], 0);
            prism_pt(out, v[i][0] + l[0], v[i][1] + l[1], l[2]);
            prism_pt(out, v[j][0] + l[0], v[j][1] + l[1], l[2]);
            prism_pt(out, v[j][0], v[j][1], 0);
            continue;
        }
        /* the side moved in to meet the rounding: along its normal
         * tilted by the extrusion, trimmed at both corners */
        double s = dir * (l[1] * u[j][0] - l[0] * u[j][1]) / len, t[3] = {0, 0, 0};
        if (s < -PRISM_TINY || s > PRISM_TINY) {
            double c = sqrt(1 - s * s);
            t[0] = (c - 1) * u[j][1];
            t[1] = (1 - c) * u[j][0];
            t[2] = s;
        }
        prism_pt(out, v[i][0] + rad * (t[0] - a[i] * u[j][0]), v[i][1] + rad * (t[1] - a[i] * u[j][1]), rad * (t[2] + 1));
        prism_pt(out, v[i][0] + l[0] + rad * (t[0] - a[i] * u[j][0]), v[i][1] + l[1] + rad * (t[1] - a[i] * u[j][1]),
             l[2] + rad * (t[2] - 1));
        prism_pt(out, v[j][0] + l[0] + rad * (t[0] + a[j] * u[j][0]), v[j][1] + l[1] + rad * (t[1] + a[j] * u[j][1]),
             l[2] + rad * (t[2] - 1));
        prism_pt(out, v[j][0] + rad * (t[0] + a[j] * u[j][0]), v[j][1] + rad * (t[1] + a[j] * u[j][1]), rad * (t[2] + 1));
        if (dir * a[j] < 0) continue;
        fprintf(out, "\n%s cylinder %s.e%d\n0\n0\n7\n", o->mat, o->name, i + 1);   /* the side's edge along l */
        prism_pt(out, v[j][0] + rad * (a[j] * u[j][0] - u[j][1]), v[j][1] + rad * (a[j] * u[j][1] + u[j][0]), rad);
        prism_pt(out, v[j][0] + l[0] + rad * (a[j] * u[j][0] - u[j][1]), v[j][1] + l[1] + rad * (a[j] * u[j][1] + u[j][0]),
             l[2] - rad);
        fprintf(out, "\t%18.12g\n", dir * rad);
    }
#undef CX
#undef CY
    free(u);
    free(a);
    return HD_OK;
}

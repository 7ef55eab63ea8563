/* Unit tests: polygon normals (Newell) and triangulation, including
 * Radiance's seam-edge holes.  Coverage is checked against an independent
 * crossing-number point-in-polygon test (even-odd rule: seam edges are
 * traversed twice and cancel). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "hd_test.h"
#include "heliodon/scene.h"
#include "heliodon/rng.h"

/* 2D helpers in a plane given by basis (u, v) */
static int pip(const double *x, const double *y, int n, double px, double py)
{
    int in = 0;
    for (int i = 0, j = n - 1; i < n; j = i++)
        if ((y[i] > py) != (y[j] > py) && px < (x[j] - x[i]) * (py - y[i]) / (y[j] - y[i]) + x[i]) in = !in;
    return in;
}

static int in_tri(double ax, double ay, double bx, double by, double cx, double cy, double px, double py)
{
    double d1 = (bx - ax) * (py - ay) - (by - ay) * (px - ax);
    double d2 = (cx - bx) * (py - by) - (cy - by) * (px - bx);
    double d3 = (ax - cx) * (py - cy) - (ay - cy) * (px - cx);
    return (d1 > 0 && d2 > 0 && d3 > 0) || (d1 < 0 && d2 < 0 && d3 < 0);
}

/* Check a triangulation of v[0..n) lying in the plane spanned by u, w. */
static void check_poly(const char *name, const hd_vec3 *v, int n, hd_vec3 u, hd_vec3 w, int grid)
{
    uint32_t *tri = malloc(sizeof(uint32_t) * 3 * (size_t)(n > 3 ? n - 2 : 1));
    uint32_t ntri = 0;
    hd_status st = hd_polygon_triangulate(v, (uint32_t)n, tri, &ntri);
    CHECK_MSG(st == HD_OK, "%s: %s", name, hd_errmsg());
    if (st) { free(tri); return; }
    CHECK_MSG(ntri <= (uint32_t)n - 2, "%s: %u triangles for %d vertices", name, ntri, n);
    double area;
    hd_vec3 nrm = hd_polygon_normal(v, (uint32_t)n, &area);
    double sum = 0;
    int badorient = 0;
    for (uint32_t t = 0; t < ntri; t++) {
        hd_vec3 a = v[tri[3 * t]], b = v[tri[3 * t + 1]], c = v[tri[3 * t + 2]];
        hd_vec3 cr = hd_vcross(hd_vsub(b, a), hd_vsub(c, a));
        double d = hd_vdot(cr, nrm);
        if (d < -1e-12 * area) badorient++;
        sum += 0.5 * d;
    }
    CHECK_MSG(badorient == 0, "%s: %d triangles with reversed orientation", name, badorient);
    CHECK_MSG(fabs(sum - area) <= 1e-9 * area, "%s: triangle area %.12g != polygon area %.12g", name, sum, area);
    /* coverage on a grid */
    double *x = malloc(sizeof(double) * (size_t)n), *y = malloc(sizeof(double) * (size_t)n);
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (int i = 0; i < n; i++) {
        x[i] = hd_vdot(v[i], u); y[i] = hd_vdot(v[i], w);
        x0 = fmin(x0, x[i]); x1 = fmax(x1, x[i]); y0 = fmin(y0, y[i]); y1 = fmax(y1, y[i]);
    }
    int wrong = 0;
    for (int i = 0; i < grid; i++)
        for (int j = 0; j < grid; j++) {
            double px = x0 + (x1 - x0) * (i + 0.5 + 0.1234567) / (grid + 0.5);
            double py = y0 + (y1 - y0) * (j + 0.5 + 0.0765432) / (grid + 0.5);
            int want = pip(x, y, n, px, py), got = 0;
            for (uint32_t t = 0; t < ntri; t++) {
                uint32_t a = tri[3 * t], b = tri[3 * t + 1], c = tri[3 * t + 2];
                got += in_tri(x[a], y[a], x[b], y[b], x[c], y[c], px, py);
            }
            if (got != want) wrong++;
        }
    CHECK_MSG(wrong == 0, "%s: %d of %d grid points covered wrongly", name, wrong, grid * grid);
    free(x); free(y); free(tri);
}

static hd_vec3 ex = {1, 0, 0}, ey = {0, 1, 0}, ez = {0, 0, 1};

static void test_newell(void)
{
    hd_vec3 sq[4] = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0, 1, 0}};
    double a;
    hd_vec3 n = hd_polygon_normal(sq, 4, &a);
    CHECK_NEAR(n.z, 1, 1e-15); CHECK_NEAR(a, 2, 1e-15);
    hd_vec3 rv[4] = {sq[3], sq[2], sq[1], sq[0]};
    n = hd_polygon_normal(rv, 4, &a);
    CHECK_NEAR(n.z, -1, 1e-15);
    /* box_room.rad floor: normal into the room (+z), north wall -y */
    hd_vec3 wall[4] = {{0, 4, 0}, {3, 4, 0}, {3, 4, 3}, {0, 4, 3}};
    n = hd_polygon_normal(wall, 4, &a);
    CHECK_NEAR(n.y, -1, 1e-15); CHECK_NEAR(a, 9, 1e-12);
}

static void test_convex_concave(void)
{
    hd_vec3 hex[6];
    for (int i = 0; i < 6; i++) hex[i] = hd_v3(cos(i * HD_PI / 3), sin(i * HD_PI / 3), 0);
    check_poly("hexagon", hex, 6, ex, ey, 60);
    hd_vec3 L[6] = {{0, 0, 0}, {3, 0, 0}, {3, 1, 0}, {1, 1, 0}, {1, 3, 0}, {0, 3, 0}};
    check_poly("L", L, 6, ex, ey, 60);
    /* comb with collinear vertices along the base */
    hd_vec3 comb[4 * 5 + 2];
    int n = 0;
    for (int t = 0; t < 5; t++) {
        comb[n++] = hd_v3(2 * t, 0, 0);
        comb[n++] = hd_v3(2 * t + 1, 0, 0);
    }
    comb[n++] = hd_v3(10, 0, 0);
    for (int t = 4; t >= 0; t--) {
        comb[n++] = hd_v3(2 * t + 1, 3, 0);
        comb[n++] = hd_v3(2 * t + 0.5, 1, 0);
    }
    comb[n++] = hd_v3(0, 3, 0);
    check_poly("comb", comb, n, ex, ey, 80);
    /* square with edge midpoints (collinear) and a duplicate closing vertex */
    hd_vec3 sqm[9] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {2, 1, 0}, {2, 2, 0}, {1, 2, 0}, {0, 2, 0}, {0, 1, 0}, {0, 0, 0}};
    check_poly("square+midpoints", sqm, 9, ex, ey, 40);
    /* clockwise seen from +z (front = -z) */
    hd_vec3 Lr[6];
    for (int i = 0; i < 6; i++) Lr[i] = L[5 - i];
    check_poly("L reversed", Lr, 6, ex, ey, 60);
}

static void test_seam_holes(void)
{
    /* 4x4 square with a 2x2 hole joined by a seam from (0,0) to (1,1) */
    hd_vec3 h[10] = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}, {0, 0, 0},
                     {1, 1, 0}, {1, 3, 0}, {3, 3, 0}, {3, 1, 0}, {1, 1, 0}};
    check_poly("square hole", h, 10, ex, ey, 80);
    double a;
    hd_polygon_normal(h, 10, &a);
    CHECK_NEAR(a, 12, 1e-12);
    /* diorama_walls.rad "wall.b" (corpus data: x-plane wall with a window
     * hole, noisy 1e-16 coordinates from a rotation) */
    hd_vec3 wb[10] = {{-6.12323399574e-18, -0.1, -0.1}, {-6.12323399574e-18, 5.1, -0.1},
                      {1.89820253868e-16, 5.1, 3.1}, {1.89820253868e-16, -0.1, 3.1},
                      {-6.12323399574e-18, -0.1, -0.1}, {0, 0, 0}, {1.83697019872e-16, 0, 3},
                      {1.83697019872e-16, 5, 3}, {0, 5, 0}, {0, 0, 0}};
    check_poly("wall.b", wb, 10, ey, ez, 100);
    hd_polygon_normal(wb, 10, &a);
    CHECK_NEAR(a, 5.2 * 3.2 - 5 * 3, 1e-9);
    /* two holes, each with its own seam from the same outer corner */
    hd_vec3 h2[16] = {{0, 0, 0}, {10, 0, 0}, {10, 4, 0}, {0, 4, 0}, {0, 0, 0},
                      {1, 1, 0}, {1, 3, 0}, {3, 3, 0}, {3, 1, 0}, {1, 1, 0}, {0, 0, 0},
                      {6, 1, 0}, {6, 3, 0}, {8, 3, 0}, {8, 1, 0}, {6, 1, 0}};
    check_poly("two holes", h2, 16, ex, ey, 100);
    /* hole whose seam runs collinear with an outer edge (seam along y = 0 to a hole on the base) */
    hd_vec3 h3[10] = {{0, 0, 0}, {6, 0, 0}, {6, 4, 0}, {0, 4, 0}, {0, 0, 0},
                      {2, 0, 0}, {2, 2, 0}, {4, 2, 0}, {4, 0.5, 0}, {2, 0, 0}};
    check_poly("collinear seam", h3, 10, ex, ey, 100);
}

static void test_random_star(void)
{
    hd_rng r;
    hd_rng_init(&r, 42, 7);
    for (int trial = 0; trial < 40; trial++) {
        int n = 5 + (int)(hd_rng_uniform(&r) * 60);
        hd_vec3 nrm = hd_vnorm(hd_v3(hd_rng_uniform(&r) - .5, hd_rng_uniform(&r) - .5, hd_rng_uniform(&r) - .5));
        hd_vec3 u, w;
        hd_vbasis(nrm, &u, &w);
        hd_vec3 *v = malloc(sizeof(hd_vec3) * (size_t)n);
        for (int i = 0; i < n; i++) {
            double ang = 2 * HD_PI * i / n, rad = 0.2 + hd_rng_uniform(&r);
            v[i] = hd_vadd(hd_v3(1, 2, 3), hd_vadd(hd_vscale(u, rad * cos(ang)), hd_vscale(w, rad * sin(ang))));
        }
        char name[64];
        snprintf(name, sizeof name, "star %d (n=%d)", trial, n);
        check_poly(name, v, n, u, w, 50);
        free(v);
    }
}

/* proper crossing of segments ab, cd (touching at end points is not) */
static int seg_cross2(hd_vec3 a, hd_vec3 b, hd_vec3 c, hd_vec3 d)
{
    double d1 = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    double d2 = (b.x - a.x) * (d.y - a.y) - (b.y - a.y) * (d.x - a.x);
    double d3 = (d.x - c.x) * (a.y - c.y) - (d.y - c.y) * (a.x - c.x);
    double d4 = (d.x - c.x) * (b.y - c.y) - (d.y - c.y) * (b.x - c.x);
    return ((d1 > 1e-12 && d2 < -1e-12) || (d1 < -1e-12 && d2 > 1e-12)) &&
           ((d3 > 1e-12 && d4 < -1e-12) || (d3 < -1e-12 && d4 > 1e-12));
}

/* random star outer loop with a random star hole joined by a seam, in the
 * layout Radiance files use: outer loop closed, hole loop closed, then
 * the implicit closing edge back to the first vertex */
static void test_random_holes(void)
{
    hd_rng r;
    hd_rng_init(&r, 4242, 3);
    for (int trial = 0; trial < 60; trial++) {
        int no = 4 + (int)(hd_rng_uniform(&r) * 30), nh = 3 + (int)(hd_rng_uniform(&r) * 20);
        int n = no + 1 + nh + 1;
        hd_vec3 *v = malloc(sizeof(hd_vec3) * (size_t)n);
        int k = 0;
        double phase = hd_rng_uniform(&r) * 2 * HD_PI;
        int seam_o = (int)(hd_rng_uniform(&r) * no);
        hd_vec3 outer[40], hole[30];
        for (int i = 0; i < no; i++) {
            double ang = 2 * HD_PI * i / no, rad = 2.0 + hd_rng_uniform(&r);
            outer[i] = hd_v3(rad * cos(ang), rad * sin(ang), 0);
        }
        for (int i = 0; i < nh; i++) {
            double ang = phase - 2 * HD_PI * i / nh, rad = 0.3 + 1.2 * hd_rng_uniform(&r);
            hole[i] = hd_v3(rad * cos(ang), rad * sin(ang), 0);
        }
        /* a seam that crosses no edge (else the polygon is not simple) */
        int seam_h = -1;
        for (int tries = 0; tries < no * nh && seam_h < 0; tries++) {
            int io = (seam_o + tries / nh) % no, ih = tries % nh, ok = 1;
            for (int e = 0; e < no && ok; e++)
                ok = !seg_cross2(outer[io], hole[ih], outer[e], outer[(e + 1) % no]);
            for (int e = 0; e < nh && ok; e++)
                ok = !seg_cross2(outer[io], hole[ih], hole[e], hole[(e + 1) % nh]);
            if (ok) { seam_o = io; seam_h = ih; }
        }
        if (seam_h < 0) { free(v); continue; }
        for (int i = 0; i <= no; i++) v[k++] = outer[(seam_o + i) % no];
        for (int i = 0; i <= nh; i++) v[k++] = hole[(seam_h + i) % nh];
        char name[64];
        snprintf(name, sizeof name, "holed star %d (%d+%d)", trial, no, nh);
        check_poly(name, v, n, ex, ey, 60);
        free(v);
    }
}

static void test_degenerate(void)
{
    uint32_t tri[12], nt;
    hd_vec3 line[3] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    CHECK(hd_polygon_triangulate(line, 3, tri, &nt) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "zero area");
    CHECK(hd_polygon_triangulate(line, 2, tri, &nt) == HD_ERR_FORMAT);
    hd_vec3 tri1[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    REQUIRE(hd_polygon_triangulate(tri1, 3, tri, &nt) == HD_OK);
    CHECK(nt == 1 && tri[0] == 0 && tri[1] == 1 && tri[2] == 2);
}

int main(void)
{
    (void)hd_test_ref;
    (void)hd_test_tmpdir;
    RUN(test_newell);
    RUN(test_convex_concave);
    RUN(test_seam_holes);
    RUN(test_random_star);
    RUN(test_random_holes);
    RUN(test_degenerate);
    return hd_test_done();
}

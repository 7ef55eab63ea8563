/* Unit tests: Embree scene, exact intersections, polygons with holes. */
#include <stdatomic.h>

#include "hd_test.h"
#include "heliodon/scene.h"
#include "heliodon/parallel.h"
#include "heliodon/trace.h"

static int add_plastic(hd_tscene *s)
{
    hd_tmat m;
    double a[5] = {0.5, 0.5, 0.5, 0, 0};
    hd_tmat_from_args(&m, "plastic", "grey", a, 5, 0, "test");
    return hd_tscene_add_material(s, &m);
}

/* Square 0..4 with a square hole 1..2 (joined by a seam edge), plus an
 * L-shaped concave polygon at z = 1. */
static int in_region(double x, double y, int which)
{
    if (which == 0) return x > 0 && x < 4 && y > 0 && y < 4 && !(x > 1 && x < 2 && y > 1 && y < 2);
    return x > 0 && x < 3 && y > 0 && y < 3 && !(x > 1 && y > 1);   /* L shape */
}

static void test_polygon_hole_and_concave(void)
{
    hd_tscene *s;
    REQUIRE(hd_tscene_create(&s) == HD_OK);
    int m = add_plastic(s);
    /* outer loop counter-clockwise, then the seam to the hole, the hole
     * clockwise, back along the seam */
    hd_vec3 holed[] = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}, {0, 0, 0},
                       {1, 1, 0}, {1, 2, 0}, {2, 2, 0}, {2, 1, 0}, {1, 1, 0}};
    REQUIRE(hd_tscene_add_polygon(s, m, holed, 10, "holed") == HD_OK);
    hd_vec3 ell[] = {{0, 0, 1}, {3, 0, 1}, {3, 1, 1}, {1, 1, 1}, {1, 3, 1}, {0, 3, 1}};
    REQUIRE(hd_tscene_add_polygon(s, m, ell, 6, "ell") == HD_OK);
    REQUIRE(hd_tscene_commit(s) == HD_OK);
    CHECK_NEAR(hd_tscene_surface(s, 0)->area, 15, 1e-9);
    CHECK_NEAR(hd_tscene_surface(s, 1)->area, 5, 1e-9);
    CHECK_NEAR(hd_tscene_surface(s, 0)->n.z, 1, 1e-12);
    int bad = 0;
    for (int i = 0; i < 97; i++)
        for (int j = 0; j < 97; j++) {
            double x = -0.5 + 5.0 * (i + 0.37) / 97, y = -0.5 + 5.0 * (j + 0.61) / 97;
            hd_hit h;
            /* ray downwards from above both polygons */
            int hit = hd_tscene_intersect(s, hd_v3(x, y, 5), hd_v3(0, 0, -1), 0, 0, &h);
            int want_ell = in_region(x, y, 1), want_holed = in_region(x, y, 0);
            if (want_ell) {
                if (!hit || h.surf != 1 || fabs(h.t - 4) > 1e-9 || !h.front) bad++;
            } else if (want_holed) {
                if (!hit || h.surf != 0 || fabs(h.p.z) > 1e-12 || !h.front) bad++;
            } else if (hit) {
                bad++;
            }
        }
    CHECK_MSG(bad == 0, "%d of 9409 rays hit the wrong polygon or missed", bad);
    /* from below: back side */
    hd_hit h;
    REQUIRE(hd_tscene_intersect(s, hd_v3(3.5, 3.5, -1), hd_v3(0, 0, 1), 0, 0, &h));
    CHECK(!h.front && h.surf == 0);
    hd_tscene_free(s);
}

static void test_triangulate_function(void)
{
    /* a comb: concave with many reflex vertices */
    hd_vec3 v[] = {{0, 0, 0}, {5, 0, 0}, {5, 3, 0}, {4, 3, 0}, {4, 1, 0}, {3, 1, 0}, {3, 3, 0},
                   {2, 3, 0}, {2, 1, 0}, {1, 1, 0}, {1, 3, 0}, {0, 3, 0}};
    uint32_t tri[3 * 10], nt = 0;
    REQUIRE(hd_polygon_triangulate(v, 12, tri, &nt) == HD_OK);
    int n = (int)nt;
    REQUIRE(n > 0);
    double area = 0;
    for (int k = 0; k < n; k++) {
        hd_vec3 a = v[tri[3 * k]], b = v[tri[3 * k + 1]], c = v[tri[3 * k + 2]];
        area += 0.5 * hd_vcross(hd_vsub(b, a), hd_vsub(c, a)).z;   /* signed */
    }
    CHECK_NEAR(area, 5 + 3 * 2, 1e-12);
}

static void test_analytic_surfaces(void)
{
    hd_tscene *s;
    REQUIRE(hd_tscene_create(&s) == HD_OK);
    int m = add_plastic(s);
    REQUIRE(hd_tscene_add_sphere(s, m, hd_v3(0, 0, 0), 1, 0, "sphere") == HD_OK);
    REQUIRE(hd_tscene_add_sphere(s, m, hd_v3(10, 0, 0), 2, 1, "bubble") == HD_OK);
    REQUIRE(hd_tscene_add_cone(s, m, hd_v3(0, 10, -1), hd_v3(0, 10, 1), 1, 1, 0, "cylinder") == HD_OK);
    REQUIRE(hd_tscene_add_cone(s, m, hd_v3(0, 20, 0), hd_v3(0, 20, 2), 2, 0, 0, "cone") == HD_OK);
    REQUIRE(hd_tscene_add_ring(s, m, hd_v3(0, 30, 0), hd_v3(0, 0, 2), 0.5, 1.5, "ring") == HD_OK);
    REQUIRE(hd_tscene_add_cone(s, m, hd_v3(0, 40, -1), hd_v3(0, 40, 1), 1, 1, 1, "tube") == HD_OK);
    REQUIRE(hd_tscene_commit(s) == HD_OK);
    hd_hit h;
    /* sphere from outside */
    REQUIRE(hd_tscene_intersect(s, hd_v3(-5, 0.6, 0), hd_v3(1, 0, 0), 0, 0, &h));
    CHECK(h.surf == 0);
    CHECK_NEAR(h.t, 5 - sqrt(1 - 0.36), 1e-9);
    CHECK_NEAR(h.n.x, -0.8, 1e-9);
    CHECK(h.front);
    /* bubble from inside: inward normal faces the ray origin */
    REQUIRE(hd_tscene_intersect(s, hd_v3(10, 0, 0), hd_v3(0, 0, 1), 0, 0, &h));
    CHECK(h.surf == 1);
    CHECK_NEAR(h.t, 2, 1e-9);
    CHECK_NEAR(h.n.z, -1, 1e-9);
    CHECK(h.front);
    /* cylinder side */
    REQUIRE(hd_tscene_intersect(s, hd_v3(-3, 10, 0.5), hd_v3(1, 0, 0), 0, 0, &h));
    CHECK(h.surf == 2);
    CHECK_NEAR(h.t, 2, 1e-9);
    CHECK_NEAR(h.n.x, -1, 1e-9);
    /* open cylinder: straight down its axis misses */
    CHECK(!hd_tscene_intersect(s, hd_v3(0, 10, 5), hd_v3(0, 0, -1), 0, 20, &h) || h.surf != 2);
    /* cone: radius at height z is 2 - z */
    REQUIRE(hd_tscene_intersect(s, hd_v3(-5, 20, 0.5), hd_v3(1, 0, 0), 0, 0, &h));
    CHECK(h.surf == 3);
    CHECK_NEAR(h.p.x, -1.5, 1e-9);
    CHECK_NEAR(h.n.x, -1 / sqrt(2), 1e-9);
    CHECK_NEAR(h.n.z, 1 / sqrt(2), 1e-9);
    /* ring: inside the inner radius misses, in the annulus hits */
    CHECK(!hd_tscene_intersect(s, hd_v3(0.2, 30, 3), hd_v3(0, 0, -1), 0, 5, &h));
    REQUIRE(hd_tscene_intersect(s, hd_v3(1.0, 30, 3), hd_v3(0, 0, -1), 0, 5, &h));
    CHECK(h.surf == 4 && h.front);
    CHECK_NEAR(h.t, 3, 1e-9);
    /* tube: inward normal */
    REQUIRE(hd_tscene_intersect(s, hd_v3(0, 40, 0), hd_v3(1, 0, 0), 0, 0, &h));
    CHECK(h.surf == 5 && h.front);
    CHECK_NEAR(h.n.x, -1, 1e-9);
    hd_tscene_free(s);
}

static void test_sources(void)
{
    hd_tscene *s;
    REQUIRE(hd_tscene_create(&s) == HD_OK);
    hd_tmat l, g;
    double a[4] = {100, 100, 100, 0};
    hd_tmat_from_args(&l, "light", "sun", a, 3, 0, "t");
    hd_tmat_from_args(&g, "glow", "sky", a, 4, 0, "t");
    int ml = hd_tscene_add_material(s, &l), mg = hd_tscene_add_material(s, &g);
    REQUIRE(hd_tscene_add_source(s, ml, hd_v3(0, 1, 1), 2.0, "sun") == HD_OK);
    REQUIRE(hd_tscene_add_source(s, mg, hd_v3(0, 0, 1), 180, "sky") == HD_OK);
    REQUIRE(hd_tscene_commit(s) == HD_OK);
    CHECK(hd_tscene_nlights(s) == 1);
    CHECK(hd_tscene_light(s, 0) == 0);
    CHECK_NEAR(hd_tscene_surface(s, 0)->area, 2 * HD_PI * (1 - cos(HD_PI / 180)), 1e-15);
    CHECK(hd_tscene_source_hit(s, hd_vnorm(hd_v3(0, 1, 1))) == 0);      /* smallest wins */
    CHECK(hd_tscene_source_hit(s, hd_vnorm(hd_v3(0, 1, 0.5))) == 1);
    CHECK(hd_tscene_source_hit(s, hd_v3(0, 0, -1)) == -1);
    CHECK(hd_tscene_source_hit_is(s, hd_vnorm(hd_v3(0, 1, 1)), 0));
    CHECK(!hd_tscene_source_hit_is(s, hd_vnorm(hd_v3(0, 1, 1)), 1));   /* the sun is smaller */
    CHECK(hd_tscene_source_hit_is(s, hd_vnorm(hd_v3(0, 1, 0.5)), 1));
    CHECK(!hd_tscene_source_hit_is(s, hd_v3(0, 0, -1), 1));
    hd_tscene_free(s);
}

/* a new scene *s with one light material (its index; -1 on failure) for distant sources */
static int light_scene(hd_tscene **s)
{
    if (hd_tscene_create(s) != HD_OK) return -1;
    hd_tmat l;
    double a[3] = {1, 1, 1};
    hd_tmat_from_args(&l, "light", "src", a, 3, 0, "t");
    return hd_tscene_add_material(*s, &l);
}

/* hd_tscene_source_hit_is(dir, t) == (hd_tscene_source_hit(dir) == t) for every source t: suns on a
 * grid (apart), overlapping discs of equal and unequal size, a hemisphere and a whole-sphere
 * source; random directions and directions near the sources' rims */
static void test_source_hit_is(void)
{
    hd_tscene *s;
    int ml = light_scene(&s), n = 0;
    REQUIRE(ml >= 0);
    for (int i = 0; i < 12; i++)
        for (int j = 0; j < 4; j++) {
            double az = 2 * HD_PI * i / 12, alt = 0.15 + 0.3 * j;
            REQUIRE(hd_tscene_add_source(s, ml, hd_v3(cos(alt) * cos(az), cos(alt) * sin(az), sin(alt)), 0.533, "sun") == HD_OK);
            n++;
        }
    double d[][4] = {{1, 0, 0.2, 10}, {1, 0.05, 0.2, 10}, {1, -0.05, 0.2, 6}, {1, 0.02, 0.2, 10},
                     {0, 0, 1, 180}, {0, 0, -1, 360}, {0.3, 0.3, 1, 20}};
    for (size_t k = 0; k < sizeof d / sizeof d[0]; k++) {
        REQUIRE(hd_tscene_add_source(s, ml, hd_vnorm(hd_v3(d[k][0], d[k][1], d[k][2])), d[k][3], "disc") == HD_OK);
        n++;
    }
    REQUIRE(hd_tscene_commit(s) == HD_OK);
    unsigned x = 12345;
    int bad = 0, hits = 0;
    for (int r = 0; r < 100000; r++) {
        hd_vec3 v;
        if (r % 2) {   /* near a source's rim: 0.98 to 1.02 of its half-angle from its centre */
            x = x * 1103515245u + 12345u;
            const hd_surface *f = hd_tscene_surface(s, (int)((x >> 8) % (unsigned)n));
            double c = 1 - f->area / (2 * HD_PI), rr = acos(c < -1 ? -1 : c);
            x = x * 1103515245u + 12345u;
            double u = ((x >> 8) & 0xffff) / 65536.0 * 2 * HD_PI;
            x = x * 1103515245u + 12345u;
            double t = rr * (0.98 + 0.04 * ((x >> 8) & 0xffff) / 65536.0);
            hd_vec3 e1 = hd_vnorm(fabs(f->b.x) < 0.9 ? hd_vcross(f->b, hd_v3(1, 0, 0)) : hd_vcross(f->b, hd_v3(0, 1, 0)));
            hd_vec3 e2 = hd_vcross(f->b, e1);
            v = hd_vnorm(hd_vadd(hd_vscale(f->b, cos(t)), hd_vadd(hd_vscale(e1, sin(t) * cos(u)), hd_vscale(e2, sin(t) * sin(u)))));
        } else {
            double q[3];
            for (int c = 0; c < 3; c++) {
                x = x * 1103515245u + 12345u;
                q[c] = ((x >> 8) & 0xffff) / 32768.0 - 1;
            }
            v = hd_vnorm(hd_v3(q[0], q[1], q[2] + 1e-9));
        }
        int best = hd_tscene_source_hit(s, v);
        for (int t = 0; t < n; t++) {
            int is = hd_tscene_source_hit_is(s, v, t);
            if (is != (best == t)) bad++;
            hits += is;
        }
    }
    CHECK(bad == 0);
    CHECK(hits > 1000);
    hd_tscene_free(s);
}

/* The overlap lists are made on the first hd_tscene_source_hit_is, not by the commit: 3 000
 * sources on one direction (9 M pairs, 36 MB of lists) commit under a 4 MB allocation limit (the
 * commit made them and failed before); the refused lists then give a warning and the answers of
 * hd_tscene_source_hit. */
static void test_source_overlaps_lazy(void)
{
    hd_tscene *s;
    int ml = light_scene(&s);
    REQUIRE(ml >= 0);
    for (int i = 0; i < 3000; i++) REQUIRE(hd_tscene_add_source(s, ml, hd_v3(0, 0, 1), 0.533, "sun") == HD_OK);
    size_t lim = hd_alloc_limit();
    hd_set_alloc_limit((size_t)4 << 20);
    CHECK(hd_tscene_commit(s) == HD_OK);
    hd_set_warnings(0);
    unsigned long w0 = hd_warning_count();
    CHECK(hd_tscene_source_hit_is(s, hd_v3(0, 0, 1), 0));    /* equal cones: the first */
    CHECK(!hd_tscene_source_hit_is(s, hd_v3(0, 0, 1), 1));
    CHECK(!hd_tscene_source_hit_is(s, hd_v3(0, 1, 0), 0));
    CHECK(hd_warning_count() == w0 + 1);                      /* one warning, at the first call */
    hd_set_warnings(1);
    hd_set_alloc_limit(lim);
    hd_tscene_free(s);
}

/* The lists made by whichever of several threads asks first: every thread's answers are
 * hd_tscene_source_hit's */
typedef struct { const hd_tscene *s; int n; atomic_int bad; } lazy_job;

static hd_status lazy_chunk(void *ctx, size_t b, size_t e, size_t ci, int worker)
{
    lazy_job *j = ctx;
    (void)ci; (void)worker;
    for (size_t r = b; r < e; r++) {
        double az = 0.001 * (double)r, alt = 0.0007 * (double)(r % 2000);
        hd_vec3 v = hd_v3(cos(alt) * cos(az), cos(alt) * sin(az), sin(alt));
        int best = hd_tscene_source_hit(j->s, v);
        for (int t = 0; t < j->n; t++)
            if (hd_tscene_source_hit_is(j->s, v, t) != (best == t)) atomic_fetch_add(&j->bad, 1);
    }
    return HD_OK;
}

static void test_source_overlaps_threads(void)
{
    hd_tscene *s;
    int ml = light_scene(&s), n = 0;
    REQUIRE(ml >= 0);
    for (int i = 0; i < 40; i++)
        for (int j = 0; j < 5; j++, n++) {
            double az = 2 * HD_PI * i / 40, alt = 0.1 + 0.25 * j;
            REQUIRE(hd_tscene_add_source(s, ml, hd_v3(cos(alt) * cos(az), cos(alt) * sin(az), sin(alt)),
                                         j == 4 ? 12 : 0.533, "sun") == HD_OK);
        }
    REQUIRE(hd_tscene_commit(s) == HD_OK);
    lazy_job j = {s, n, 0};
    CHECK(hd_parallel_for(20000, 50, 4, lazy_chunk, &j) == HD_OK);
    CHECK(atomic_load(&j.bad) == 0);
    hd_tscene_free(s);
}

static void test_bad_geometry(void)
{
    hd_tscene *s;
    REQUIRE(hd_tscene_create(&s) == HD_OK);
    int m = add_plastic(s);
    hd_vec3 line[] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    CHECK(hd_tscene_add_polygon(s, m, line, 3, "f.rad:3: polygon flat") == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "f.rad:3");
    CHECK(hd_tscene_add_polygon(s, m, line, 2, "f.rad:4: polygon two") == HD_ERR_FORMAT);
    CHECK(hd_tscene_add_sphere(s, m, hd_v3(0, 0, 0), 0, 0, "f.rad:5: sphere s") == HD_ERR_FORMAT);
    CHECK(hd_tscene_add_ring(s, m, hd_v3(0, 0, 0), hd_v3(0, 0, 1), 1, 1, "f.rad:6: ring r") == HD_ERR_FORMAT);
    CHECK(hd_tscene_add_cone(s, m, hd_v3(0, 0, 0), hd_v3(0, 0, 0), 1, 1, 0, "f.rad:7: cone c") == HD_ERR_FORMAT);
    CHECK(hd_tscene_add_source(s, m, hd_v3(0, 0, 0), 1, "f.rad:8: source s") == HD_ERR_FORMAT);
    hd_tscene_free(s);
}

static void test_from_scene_unsupported(void)
{
    hd_scene sc;
    hd_scene_init(&sc);
    const char *txt = "void plastic p 0 0 5 .5 .5 .5 0 0\n"
                      "void antimatter anti 1 p 0 0\n"
                      "anti sphere hole 0 0 4 0 0 0 1\n";
    REQUIRE(hd_scene_load_string(&sc, txt, "anti.rad", NULL) == HD_OK);
    hd_tscene *ts = NULL;
    CHECK(hd_tscene_from_scene(&ts, &sc) == HD_ERR_UNSUPPORTED);
    CHECK_CONTAINS(hd_errmsg(), "anti.rad:2");
    CHECK_CONTAINS(hd_errmsg(), "antimatter");
    hd_scene_free(&sc);
    hd_scene_init(&sc);
    const char *txt2 = "void brightfunc skyfunc 2 skybright perezlum.cal 0 10 1 2 0 -1 0 -1 0 0 0 1\n"
                       "skyfunc glow sg 0 0 4 1 1 1 0\n"
                       "sg source sky 0 0 4 0 0 1 180\n"
                       "void plastic p 0 0 5 .5 .5 .5 0 0\n"
                       "p polygon floor 0 0 12 0 0 0 1 0 0 1 1 0 0 1 0\n";
    REQUIRE(hd_scene_load_string(&sc, txt2, "sky.rad", NULL) == HD_OK);
    REQUIRE(hd_tscene_from_scene(&ts, &sc) == HD_OK);
    CHECK(hd_tscene_nsurfaces(ts) == 2);
    const hd_tmat *m = hd_tscene_material(ts, hd_tscene_surface(ts, 0)->mat);
    CHECK(m->type == HD_MAT_GLOW && m->pattern == HD_PAT_PEREZ);
    CHECK_CONTAINS(hd_tscene_surface(ts, 1)->where, "sky.rad:5");
    hd_tscene_free(ts);
    hd_scene_free(&sc);
}

int main(void)
{
    RUN(test_polygon_hole_and_concave);
    RUN(test_triangulate_function);
    RUN(test_analytic_surfaces);
    RUN(test_sources);
    RUN(test_source_hit_is);
    RUN(test_source_overlaps_lazy);
    RUN(test_source_overlaps_threads);
    RUN(test_bad_geometry);
    RUN(test_from_scene_unsupported);
    return hd_test_done();
}

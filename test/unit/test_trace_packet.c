/* Unit tests: hd_tscene_intersect_packet (16-ray Embree packets) against
 * single rays (hd_tscene_intersect) and against analytic hits. */
#include <math.h>

#include "hd_test.h"
#include "heliodon/rng.h"
#include "heliodon/trace.h"

static int add_plastic(hd_tscene *s)
{
    hd_tmat m;
    double a[5] = {0.5, 0.5, 0.5, 0, 0};
    hd_tmat_from_args(&m, "plastic", "grey", a, 5, 0, "test");
    return hd_tscene_add_material(s, &m);
}

/* A closed box 0..4 (six polygons, one with a square hole) holding a
 * sphere, a cylinder, a cone, a ring and a tube: every kind of surface. */
static hd_tscene *make_scene(void)
{
    hd_tscene *s;
    if (hd_tscene_create(&s) != HD_OK) return NULL;
    int m = add_plastic(s);
    hd_vec3 floor_[] = {{0, 0, 0}, {0, 4, 0}, {4, 4, 0}, {4, 0, 0}};
    hd_vec3 ceil_[] = {{0, 0, 4}, {4, 0, 4}, {4, 4, 4}, {0, 4, 4}, {0, 0, 4},
                       {1, 1, 4}, {1, 2, 4}, {2, 2, 4}, {2, 1, 4}, {1, 1, 4}};   /* hole 1..2 */
    hd_vec3 w0[] = {{0, 0, 0}, {4, 0, 0}, {4, 0, 4}, {0, 0, 4}};
    hd_vec3 w1[] = {{0, 4, 0}, {0, 4, 4}, {4, 4, 4}, {4, 4, 0}};
    hd_vec3 w2[] = {{0, 0, 0}, {0, 0, 4}, {0, 4, 4}, {0, 4, 0}};
    hd_vec3 w3[] = {{4, 0, 0}, {4, 4, 0}, {4, 4, 4}, {4, 0, 4}};
    int ok = hd_tscene_add_polygon(s, m, floor_, 4, "floor") == HD_OK &&
             hd_tscene_add_polygon(s, m, ceil_, 10, "ceiling") == HD_OK &&
             hd_tscene_add_polygon(s, m, w0, 4, "w0") == HD_OK && hd_tscene_add_polygon(s, m, w1, 4, "w1") == HD_OK &&
             hd_tscene_add_polygon(s, m, w2, 4, "w2") == HD_OK && hd_tscene_add_polygon(s, m, w3, 4, "w3") == HD_OK &&
             hd_tscene_add_sphere(s, m, hd_v3(1, 1, 1), 0.5, 0, "sphere") == HD_OK &&
             hd_tscene_add_cone(s, m, hd_v3(3, 1, 0.5), hd_v3(3, 1, 2), 0.4, 0.4, 0, "cylinder") == HD_OK &&
             hd_tscene_add_cone(s, m, hd_v3(1, 3, 0.2), hd_v3(1, 3, 1.5), 0.6, 0.1, 0, "cone") == HD_OK &&
             hd_tscene_add_ring(s, m, hd_v3(3, 3, 2), hd_v3(0, 0, 1), 0.2, 0.7, "ring") == HD_OK &&
             hd_tscene_add_cone(s, m, hd_v3(2, 2, 2.5), hd_v3(2, 2, 3.5), 0.3, 0.3, 1, "tube") == HD_OK &&
             hd_tscene_commit(s) == HD_OK;
    if (!ok) { hd_tscene_free(s); return NULL; }
    return s;
}

static hd_vec3 rand_dir(hd_rng *r)
{
    double z = 2 * hd_rng_uniform(r) - 1, p = 2 * HD_PI * hd_rng_uniform(r), q = sqrt(1 - z * z);
    return hd_v3(q * cos(p), q * sin(p), z);
}

/* Random rays, incoherent (inside the box, any direction, some starting
 * outside) and coherent (a parallel beam through the ceiling's hole), in
 * packets of every size 1..16, with and without tmax: the packet's answer
 * equals the single-ray answer ray by ray. */
static void test_packet_equals_single(void)
{
    hd_tscene *s = make_scene();
    REQUIRE(s != NULL);
    hd_rng r;
    hd_rng_init(&r, 7, 1);
    int nrays = 0, nhit = 0, surf_bad = 0, mask_bad = 0, kinds[16] = {0};
    double tmax_err = 0;
    for (int round = 0; round < 300; round++) {
        int n = 1 + round % HD_TPACKET;
        int coherent = round % 3 == 2;
        double tmax = round % 5 == 4 ? 1.5 : 0;
        hd_vec3 o[HD_TPACKET], d[HD_TPACKET];
        hd_vec3 beam = hd_vnorm(hd_v3(0.2, -0.1, -1));
        for (int i = 0; i < n; i++) {
            if (coherent) {
                o[i] = hd_v3(0.5 + 2 * hd_rng_uniform(&r), 0.5 + 2 * hd_rng_uniform(&r), 6);
                d[i] = beam;
            } else {
                double out = hd_rng_uniform(&r) < 0.1 ? 3 : 0;
                o[i] = hd_v3(0.05 + 3.9 * hd_rng_uniform(&r) + out, 0.05 + 3.9 * hd_rng_uniform(&r),
                             0.05 + 3.9 * hd_rng_uniform(&r));
                d[i] = rand_dir(&r);
            }
        }
        hd_hit ph[HD_TPACKET];
        uint32_t mask = hd_tscene_intersect_packet(s, n, o, d, 1e-6, tmax, ph);
        CHECK((mask >> n) == 0);
        for (int i = 0; i < n; i++) {
            hd_hit h;
            int hit = hd_tscene_intersect(s, o[i], d[i], 1e-6, tmax, &h);
            nrays++;
            if (hit != (int)(mask >> i & 1)) { mask_bad++; continue; }
            if (!hit) continue;
            nhit++;
            if (h.surf != ph[i].surf || h.front != ph[i].front) { surf_bad++; continue; }
            kinds[h.surf]++;
            double e = fabs(h.t - ph[i].t) / (1 + h.t);
            if (e > tmax_err) tmax_err = e;
            CHECK_NEAR(hd_vdot(h.n, ph[i].n), 1, 1e-12);
            CHECK_NEAR(hd_vlen(hd_vsub(h.p, ph[i].p)), 0, 1e-9);
            if (tmax > 0) CHECK(ph[i].t < tmax);
        }
    }
    CHECK(nrays > 2000);
    CHECK(nhit > nrays / 2);
    CHECK(mask_bad == 0);
    CHECK(surf_bad == 0);
    CHECK(tmax_err < 1e-9);
    /* every surface was hit by some ray (the test covers all kinds) */
    for (int k = 0; k < 11; k++) CHECK(kinds[k] > 0);
    hd_tscene_free(s);
}

/* Analytic: a vertical beam of 16 rays onto the floor through the hole
 * hits the floor at t = 6 exactly; rays outside the hole's shadow hit the
 * ceiling's back side at t = 2; empty packets answer 0. */
static void test_packet_analytic(void)
{
    hd_tscene *s = make_scene();
    REQUIRE(s != NULL);
    hd_vec3 o[HD_TPACKET], d[HD_TPACKET];
    for (int i = 0; i < HD_TPACKET; i++) {
        o[i] = hd_v3(1.1 + 0.05 * (i % 4), 1.6 + 0.05 * (i / 4), 6);   /* over the hole, away from the tube */
        d[i] = hd_v3(0, 0, -1);
    }
    o[15] = hd_v3(3.5, 3.5, 6);   /* not over the hole: ceiling at z = 4 */
    hd_hit h[HD_TPACKET];
    uint32_t mask = hd_tscene_intersect_packet(s, HD_TPACKET, o, d, 0, 0, h);
    CHECK(mask == 0xFFFFu);
    for (int i = 0; i < 15; i++) {
        CHECK(h[i].surf == 0);
        CHECK_NEAR(h[i].t, 6, 1e-12);
        CHECK(!h[i].front);   /* the floor faces down (clockwise seen from above) */
    }
    CHECK(h[15].surf == 1);
    CHECK_NEAR(h[15].t, 2, 1e-12);
    /* the same beam limited to t < 5 stops at nothing but the ceiling ray */
    mask = hd_tscene_intersect_packet(s, HD_TPACKET, o, d, 0, 5, h);
    CHECK(mask == 0x8000u);
    /* pointing away: no hits; n = 0: nothing */
    for (int i = 0; i < HD_TPACKET; i++) d[i] = hd_v3(0, 0, 1);
    CHECK(hd_tscene_intersect_packet(s, HD_TPACKET, o, d, 0, 0, h) == 0);
    CHECK(hd_tscene_intersect_packet(s, 0, o, d, 0, 0, h) == 0);
    hd_tscene_free(s);
}

int main(void)
{
    RUN(test_packet_equals_single);
    RUN(test_packet_analytic);
    return hd_test_done();
}

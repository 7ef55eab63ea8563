/* Unit tests: the Monte Carlo renderer against analytic results. */
#include "hd_test.h"
#include "hd_test_scene.h"
#include "heliodon/render.h"
#include "heliodon/scene.h"

#include <string.h>

#define load(text) hd_test_tscene((text), "test.rad")

static hd_renderer make(const hd_tscene *ts, int ab, int ad)
{
    hd_renderer r;
    r.scene = ts;
    hd_render_defaults(&r.o);
    r.o.ab = ab;
    r.o.ad = ad;
    r.o.lw = 1e-9;
    r.o.lr = 100;
    return r;
}

static const double SUNOMEGA_HALF = 0.2665 * HD_PI / 180;

static void test_uniform_sky_pi_L(void)
{
    hd_tscene *ts = load("void glow skyg 0 0 4 2.5 2.5 2.5 0\n"
                         "skyg source sky 0 0 4 0 0 1 180\n"
                         "void plastic ground 0 0 5 .3 .3 .3 0 0\n"
                         "ground polygon plane 0 0 12 -50 -50 0 50 -50 0 50 50 0 -50 50 0\n");
    REQUIRE(ts);
    hd_renderer r = make(ts, 1, 512);
    hd_rng rng;
    hd_rng_init(&rng, 1, 0);
    double e[3];
    hd_render_irradiance(&r, hd_v3(0, 0, 0.001), hd_v3(0, 0, 1), &rng, e);
    CHECK_REL(e[0], HD_PI * 2.5, 1e-9);
    /* -i: irradiance where a ray meets the plane */
    hd_render_irradiance_at_hit(&r, hd_v3(3, 4, 10), hd_vnorm(hd_v3(0.1, 0, -1)), &rng, e, NULL);
    CHECK_REL(e[1], HD_PI * 2.5, 1e-9);
    /* radiance of the plane seen from above: rho * E / pi */
    double c[3];
    r.o.ab = 2;
    hd_render_radiance(&r, hd_v3(0, 0, 10), hd_v3(0, 0, -1), 0, &rng, c, NULL);
    CHECK_REL(c[2], 0.3 * 2.5, 1e-9);
    /* -ab 0: the glow sky is not a direct source */
    r.o.ab = 0;
    hd_render_irradiance(&r, hd_v3(0, 0, 0.001), hd_v3(0, 0, 1), &rng, e);
    CHECK(e[0] == 0);
    hd_tscene_free(ts);
}

static void test_furnace_sphere(void)
{
    /* closed sphere (albedo rho) lit by a small light sphere at its centre:
     * every wall point receives E_d directly, and each bounce multiplies by
     * rho, so E(ab) = E_d (1 - rho^(ab+1)) / (1 - rho) */
    hd_tscene *ts = load("void light lit 0 0 3 100 100 100\n"
                         "lit sphere bulb 0 0 4 0 0 0 0.05\n"
                         "void plastic w 0 0 5 .6 .6 .6 0 0\n"
                         "w bubble enclosure 0 0 4 0 0 0 1\n");
    REQUIRE(ts);
    double rho = 0.6, d = 0.999;
    double Ed = 100 * 2 * HD_PI * (1 - sqrt(1 - 0.05 * 0.05 / (d * d))) * 1.0; /* exact cone, facing */
    /* for a sphere facing the point, E = L pi sin^2(a) */
    Ed = 100 * HD_PI * 0.05 * 0.05 / (d * d);
    int abs_[3] = {0, 2, 12};
    for (int k = 0; k < 3; k++) {
        hd_renderer r = make(ts, abs_[k], 4096);
        double sum = 0;
        int npts = 4;
        for (int p = 0; p < npts; p++) {
            hd_rng rng;
            hd_rng_init(&rng, 7, (uint64_t)p);
            double e[3];
            hd_vec3 n = hd_vnorm(hd_v3(p - 1.5, 0.3 * p, -1));
            hd_render_irradiance(&r, hd_vscale(n, -d), n, &rng, e);
            sum += e[0];
        }
        double want = Ed * (1 - pow(rho, abs_[k] + 1)) / (1 - rho);
        CHECK_REL(sum / npts, want, 0.01);
    }
    hd_tscene_free(ts);
}

static void test_sun_on_tilted_plane(void)
{
    hd_tscene *ts = load("void light solar 0 0 3 1e6 1e6 1e6\n"
                         "solar source sun 0 0 4 0 0 1 0.533\n");
    REQUIRE(ts);
    hd_renderer r = make(ts, 0, 1);
    hd_rng rng;
    hd_rng_init(&rng, 1, 0);
    double omega = 2 * HD_PI * (1 - cos(SUNOMEGA_HALF));
    for (int deg = 0; deg <= 80; deg += 20) {
        double th = deg * HD_PI / 180, e[3];
        hd_render_irradiance(&r, hd_v3(0, 0, 0), hd_v3(sin(th), 0, cos(th)), &rng, e);
        CHECK_REL(e[0], 1e6 * omega * cos(th), 1e-9);
    }
    double e[3];
    hd_render_irradiance(&r, hd_v3(0, 0, 0), hd_v3(0, 0, -1), &rng, e);
    CHECK(e[0] == 0);
    /* with jitter the sun is sampled over its disk: same mean */
    r.o.dj = 1;
    double s = 0;
    for (int k = 0; k < 200; k++) {
        hd_render_irradiance(&r, hd_v3(0, 0, 0), hd_v3(0.5, 0, sqrt(0.75)), &rng, e);
        s += e[0];
    }
    CHECK_REL(s / 200, 1e6 * omega * sqrt(0.75), 1e-3);
    hd_tscene_free(ts);
}

/* -ss samples of a rough lobe beyond the walk's stack buffer come from the
 * bounded allocator: a refusal is the ray's error (HD_ERR_NOMEM with the
 * size named), not a silent cut to fewer samples */
static void test_spec_samples_alloc_limit(void)
{
    hd_tscene *ts = load("void glow skyg 0 0 4 1 1 1 0\n"
                         "skyg source sky 0 0 4 0 0 1 180\n"
                         "void metal rough 0 0 5 .8 .8 .8 1 .05\n"
                         "rough polygon floor 0 0 12 -50 -50 0 50 -50 0 50 50 0 -50 50 0\n");
    REQUIRE(ts);
    hd_renderer r = make(ts, 0, 1);
    r.o.ss = 1000;   /* 1000 samples of 24 bytes */
    hd_rng rng;
    hd_rng_init(&rng, 1, 0);
    double c[3];
    hd_vec3 dir = hd_vnorm(hd_v3(1, 0, -1));
    CHECK(hd_render_radiance(&r, hd_v3(0, 0, 1), dir, 0, &rng, c, NULL) == HD_OK);
    CHECK_REL(c[1], 0.8, 0.02);   /* white sky of radiance 1 on a metal of 0.8 (a narrow lobe: few samples lost below) */
    size_t lim = hd_alloc_limit();
    hd_set_alloc_limit(16000);
    hd_status st = hd_render_radiance(&r, hd_v3(0, 0, 1), dir, 0, &rng, c, NULL);
    hd_set_alloc_limit(lim);
    CHECK(st == HD_ERR_NOMEM);
    CHECK(strstr(hd_errmsg(), "refusing to allocate") != NULL);
    hd_tscene_free(ts);
}

static void test_glass_normal_transmission(void)
{
    hd_tscene *ts = load("void light solar 0 0 3 1e6 1e6 1e6\n"
                         "solar source sun 0 0 4 0 0 1 0.533\n"
                         "void glass pane 0 0 3 .96 .8 .5\n"
                         "pane polygon window 0 0 12 -1 -1 1 1 -1 1 1 1 1 -1 1 1\n");
    REQUIRE(ts);
    hd_renderer r = make(ts, 0, 1);
    hd_rng rng;
    hd_rng_init(&rng, 1, 0);
    double e[3], omega = 2 * HD_PI * (1 - cos(SUNOMEGA_HALF));
    hd_render_irradiance(&r, hd_v3(0.2, 0.3, 0), hd_v3(0, 0, 1), &rng, e);
    double tn[3] = {0.96, 0.8, 0.5}, n = 1.52, rr = (n - 1) / (n + 1);
    rr *= rr;
    for (int i = 0; i < 3; i++) {
        double T = (1 - rr) * (1 - rr) * tn[i] / (1 - rr * rr * tn[i] * tn[i]);
        CHECK_REL(e[i], 1e6 * omega * T, 1e-9);
    }
    /* beside the pane: the full sun */
    hd_render_irradiance(&r, hd_v3(2, 0, 0), hd_v3(0, 0, 1), &rng, e);
    CHECK_REL(e[0], 1e6 * omega, 1e-9);
    /* seen through the pane, the sun's radiance is transmitted */
    double c[3];
    hd_render_radiance(&r, hd_v3(0, 0, 0), hd_v3(0, 0, 1), 0, &rng, c, NULL);
    CHECK_REL(c[0], 1e6 * (1 - rr) * (1 - rr) * 0.96 / (1 - rr * rr * 0.96 * 0.96), 1e-9);
    hd_tscene_free(ts);
}

static void test_shadow_of_polygon_with_hole(void)
{
    /* opaque plate with a square hole (seam edges) over sensors */
    hd_tscene *ts = load("void light solar 0 0 3 1e6 1e6 1e6\n"
                         "solar source sun 0 0 4 0 0 1 0.533\n"
                         "void plastic black 0 0 5 0 0 0 0 0\n"
                         "black polygon plate 0 0 30 0 0 1 4 0 1 4 4 1 0 4 1 0 0 1"
                         " 1 1 1 1 2 1 2 2 1 2 1 1 1 1 1\n");
    REQUIRE(ts);
    hd_renderer r = make(ts, 0, 1);
    hd_rng rng;
    hd_rng_init(&rng, 1, 0);
    int bad = 0;
    for (int i = 0; i < 40; i++)
        for (int j = 0; j < 40; j++) {
            double x = -0.5 + 5 * (i + 0.5) / 40, y = -0.5 + 5 * (j + 0.5) / 40, e[3];
            if (fabs(x - 1) < 0.02 || fabs(x - 2) < 0.02 || fabs(y - 1) < 0.02 || fabs(y - 2) < 0.02) continue;
            hd_render_irradiance(&r, hd_v3(x, y, 0), hd_v3(0, 0, 1), &rng, e);
            int covered = x > 0 && x < 4 && y > 0 && y < 4 && !(x > 1 && x < 2 && y > 1 && y < 2);
            if ((e[0] > 0) == covered) bad++;
        }
    CHECK_MSG(bad == 0, "%d sensors lit/shaded wrongly", bad);
    hd_tscene_free(ts);
}

static void test_rtrace_threads_deterministic(void)
{
    hd_tscene *ts = load("void glow skyg 0 0 4 1 1 1 0\n"
                         "skyg source sky 0 0 4 0 0 1 180\n"
                         "void plastic w 0 0 5 .5 .5 .5 0 0\n"
                         "w polygon floor 0 0 12 0 0 0 3 0 0 3 3 0 0 3 0\n"
                         "w polygon wall 0 0 12 0 2 0 3 2 0 3 2 2 0 2 2\n");
    REQUIRE(ts);
    char in[4096] = "";
    for (int k = 0; k < 40; k++) {
        char line[100];
        snprintf(line, sizeof line, "%g %g 0.01 0 0 1\n", 0.1 + 0.07 * k, 0.5 + 0.03 * k);
        strcat(in, line);
    }
    char out[2][8192];
    for (int t = 0; t < 2; t++) {
        hd_rtrace_opts o;
        hd_rtrace_defaults(&o);
        o.irrad = 1;
        o.header = 0;
        o.nthreads = t + 1;
        o.r.ab = 2;
        o.r.ad = 64;
        hd_renderer r = {ts, o.r};
        hd_istream *s;
        REQUIRE(hd_istream_memory(&s, in, strlen(in), "rays") == HD_OK);
        FILE *fp = fmemopen(out[t], sizeof out[t], "w");
        REQUIRE(fp);
        CHECK(hd_rtrace_run(&r, &o, NULL, s, fp, NULL) == HD_OK);
        fclose(fp);
        hd_istream_close(s);
    }
    CHECK(strlen(out[0]) > 200);
    CHECK_STR(out[0], out[1]);
    /* bad input: incomplete ray */
    hd_rtrace_opts o;
    hd_rtrace_defaults(&o);
    hd_renderer r = {ts, o.r};
    hd_istream *s;
    REQUIRE(hd_istream_memory(&s, "1 2 3 0 0 1\n4 5 x", 17, "bad") == HD_OK);
    char buf[512];
    FILE *fp = fmemopen(buf, sizeof buf, "w");
    CHECK(hd_rtrace_run(&r, &o, NULL, s, fp, NULL) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "bad");
    fclose(fp);
    hd_istream_close(s);
    hd_tscene_free(ts);
}

/* Irradiance below the corner of a parallel emitting rectangle a x b at
 * height h: E = L pi F with the classic view factor. */
static double corner_E(double L, double a, double b, double h)
{
    double A = a / h, B = b / h;
    double F = (A / sqrt(1 + A * A) * atan(B / sqrt(1 + A * A)) + B / sqrt(1 + B * B) * atan(A / sqrt(1 + B * B))) /
               (2 * HD_PI);
    return L * HD_PI * F;
}

static void test_area_light_mis(void)
{
    /* a 2 x 1 light panel 0.5 above the floor, facing down */
    hd_tscene *ts = load("void light panel 0 0 3 10 10 10\n"
                         "panel polygon lamp 0 0 12 0 0 .5 0 1 .5 2 1 .5 2 0 .5\n"
                         "void plastic floor 0 0 5 .3 .3 .3 0 0\n"
                         "floor polygon ground 0 0 12 -9 -9 0 9 -9 0 9 9 0 -9 9 0\n");
    REQUIRE(ts);
    REQUIRE(hd_tscene_nlights(ts) == 1);
    double want = corner_E(10, 2, 1, 0.5);
    double mean[2], var[2];
    for (int mis = 0; mis < 2; mis++) {
        hd_renderer r = make(ts, 1, 16);
        r.o.nomis = !mis;
        double s = 0, s2 = 0;
        int n = 4000;
        for (int k = 0; k < n; k++) {
            hd_rng rng;
            hd_rng_init(&rng, 3, (uint64_t)k);
            double e[3];
            hd_render_irradiance(&r, hd_v3(0, 0, 0.0), hd_v3(0, 0, 1), &rng, e);
            s += e[0];
            s2 += e[0] * e[0];
        }
        mean[mis] = s / n;
        var[mis] = s2 / n - mean[mis] * mean[mis];
        /* within 4 standard errors (shadow rays alone are noisy here) */
        CHECK_NEAR(mean[mis], want, 4 * sqrt(var[mis] / n) + 1e-3 * want);
    }
    /* the combination is less noisy than shadow rays alone for a big, near source */
    CHECK_MSG(var[1] < 0.25 * var[0], "variance with MIS %g, without %g", var[1], var[0]);
    CHECK_REL(mean[1], want, 0.01);
    /* a point under the middle: 4 corner rectangles of 1 x 0.5 */
    hd_renderer r = make(ts, 2, 64);
    double s = 0;
    for (int k = 0; k < 400; k++) {
        hd_rng rng;
        hd_rng_init(&rng, 4, (uint64_t)k);
        double e[3];
        hd_render_irradiance(&r, hd_v3(1, 0.5, 0.0), hd_v3(0, 0, 1), &rng, e);
        s += e[0];
    }
    /* -ab 2: the floor around the point reflects light back up to the lamp's
     * back (not emitting) and nowhere else, so E is the direct value */
    CHECK_REL(s / 400, 4 * corner_E(10, 1, 0.5, 0.5), 0.01);
    hd_tscene_free(ts);
}

/* Window portals (render.c, Russian-roulette mode): a closed grey room lit
 * by a uniform sky through a glass pane in the ceiling.  Sampling the sky
 * through the pane at the deeper vertices must not change the expectation
 * (power-heuristic weights sum to one) and must lower the noise.  The -I
 * point faces down: all its light comes after at least one bounce. */
static void test_window_portal(void)
{
    hd_tscene *ts = load("void glow skyg 0 0 4 1 1 1 0\n"
                         "skyg source sky 0 0 4 0 0 1 180\n"
                         "void plastic w 0 0 5 .6 .6 .6 0 0\n"
                         "void glass pane 0 0 3 .96 .96 .96\n"
                         "w polygon floor 0 0 12 0 0 0 1 0 0 1 1 0 0 1 0\n"
                         "w polygon north 0 0 12 0 1 0 1 1 0 1 1 1 0 1 1\n"
                         "w polygon west 0 0 12 0 0 0 0 1 0 0 1 1 0 0 1\n"
                         "w polygon east 0 0 12 1 0 0 1 0 1 1 1 1 1 1 0\n"
                         "w polygon south 0 0 12 0 0 0 0 0 1 1 0 1 1 0 0\n"
                         "w polygon ca 0 0 12 0 0 1 0 .3 1 1 .3 1 1 0 1\n"
                         "w polygon cb 0 0 12 0 .7 1 0 1 1 1 1 1 1 .7 1\n"
                         "w polygon cc 0 0 12 0 .3 1 0 .7 1 .3 .7 1 .3 .3 1\n"
                         "w polygon cd 0 0 12 .7 .3 1 .7 .7 1 1 .7 1 1 .3 1\n"
                         "pane polygon window1 0 0 12 .3 .3 1 .3 .7 1 .5 .7 1 .5 .3 1\n"
                         "pane polygon window2 0 0 12 .5 .3 1 .5 .45 1 .7 .45 1 .7 .3 1\n"
                         "pane polygon window3 0 0 12 .5 .45 1 .5 .7 1 .7 .7 1 .7 .45 1\n");
    REQUIRE(ts);
    CHECK(hd_tscene_nportals(ts) == 3);    /* three panes of different sizes: one strategy */
    double mean[2], var[2];
    int n = 10000;
    for (int pm = 0; pm < 2; pm++) {
        hd_renderer r = make(ts, 3, 4);    /* portals at both deeper vertices */
        r.o.lr = -30;
        r.o.lw = 1e-3;
        r.o.noportal = !pm;
        double s = 0, s2 = 0;
        for (int k = 0; k < n; k++) {
            hd_rng rng;
            hd_rng_init(&rng, 11, (uint64_t)k);
            double e[3];
            hd_render_irradiance(&r, hd_v3(0.5, 0.5, 0.5), hd_v3(0, 0, -1), &rng, e);
            s += e[0];
            s2 += e[0] * e[0];
        }
        mean[pm] = s / n;
        var[pm] = s2 / n - mean[pm] * mean[pm];
    }
    double se = sqrt((var[0] + var[1]) / n);
    CHECK_MSG(fabs(mean[1] - mean[0]) < 4 * se, "mean with portals %g, without %g (standard error %g)",
              mean[1], mean[0], se);
    CHECK_MSG(var[1] < 0.1 * var[0], "variance with portals %g, without %g", var[1], var[0]);
    printf("  portal: mean %g vs %g (se %g), variance %g vs %g\n", mean[1], mean[0], se, var[1], var[0]);
    /* a floor point that sees the pane: with -ad 64 the first vertex also
     * samples the portals (64 stratified points against 64 hemisphere
     * rays) */
    for (int pm = 0; pm < 2; pm++) {
        hd_renderer r = make(ts, 3, 64);
        r.o.lr = -30;
        r.o.lw = 1e-3;
        r.o.noportal = !pm;
        double s = 0, s2 = 0;
        for (int k = 0; k < 2000; k++) {
            hd_rng rng;
            hd_rng_init(&rng, 12, (uint64_t)k);
            double e[3];
            hd_render_irradiance(&r, hd_v3(0.2, 0.15, 0.0), hd_v3(0, 0, 1), &rng, e);
            s += e[0];
            s2 += e[0] * e[0];
        }
        mean[pm] = s / 2000;
        var[pm] = s2 / 2000 - mean[pm] * mean[pm];
    }
    se = sqrt((var[0] + var[1]) / 2000);
    CHECK_MSG(fabs(mean[1] - mean[0]) < 4 * se, "first vertex: mean with portals %g, without %g (standard error %g)",
              mean[1], mean[0], se);
    /* measured: 229x lower; 67x with the former 8 random portal points,
     * which this bound rejects (the stratification must work) */
    CHECK_MSG(var[1] < var[0] / 120, "first vertex: variance with portals %g, without %g", var[1], var[0]);
    printf("  portal, first vertex: mean %g vs %g (se %g), variance %g vs %g\n", mean[1], mean[0], se, var[1], var[0]);
    hd_tscene_free(ts);
}

int main(void)
{
    RUN(test_uniform_sky_pi_L);
    RUN(test_furnace_sphere);
    RUN(test_sun_on_tilted_plane);
    RUN(test_spec_samples_alloc_limit);
    RUN(test_glass_normal_transmission);
    RUN(test_shadow_of_polygon_with_hole);
    RUN(test_rtrace_threads_deterministic);
    RUN(test_area_light_mis);
    RUN(test_window_portal);
    return hd_test_done();
}

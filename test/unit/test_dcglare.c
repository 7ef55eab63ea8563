/* Unit tests for the imageless glare formula (dcglare.h): position index, one step against the
 * formula written out by hand, thresholds, low-light factor, autonomy. */
#include "hd_test.h"
#include "heliodon/basis.h"
#include "heliodon/dcglare.h"

static void test_posidx(void)
{
    hd_vec3 f = hd_v3(0, -1, 0), up = hd_v3(0, 0, 1);
    /* on the line of sight: Guth with sigma 0 gives 1 */
    CHECK_NEAR(hd_dcglare_posidx(f, f, up), 1.0, 1e-12);
    /* 30 degrees straight up: tau from fwd + dir/(dir.fwd) = angle acos(tan s / sqrt(4 + tan^2 s)) */
    double s = 30 * HD_PI / 180;
    hd_vec3 d = hd_v3(0, -cos(s), sin(s));
    double tau = acos(tan(s) / sqrt(4 + tan(s) * tan(s))) * 180 / HD_PI, sg = 30;
    double want = exp((35.2 - 0.31889 * tau - 1.22 * exp(-2.0 * tau / 9.0)) / 1000.0 * sg +
                      (21.0 + 0.26667 * tau - 0.002963 * tau * tau) / 100000.0 * sg * sg);
    CHECK_NEAR(hd_dcglare_posidx(d, f, up), want, 1e-9);
    /* 30 degrees straight down: r = tan 30 (< 0.6, factor 0.8) */
    d = hd_v3(0, -cos(s), -sin(s));
    CHECK_NEAR(hd_dcglare_posidx(d, f, up), 1 + 0.8 * tan(s), 1e-6);
    /* 60 degrees down: r = tan 60 > 0.6 (factor 1.2); 89 degrees: r capped at 3 */
    s = 60 * HD_PI / 180;
    d = hd_v3(0, -cos(s), -sin(s));
    CHECK_NEAR(hd_dcglare_posidx(d, f, up), 1 + 1.2 * tan(s), 1e-6);
    s = 89 * HD_PI / 180;
    d = hd_v3(0, -cos(s), -sin(s));
    CHECK_NEAR(hd_dcglare_posidx(d, f, up), 1 + 1.2 * 3, 1e-6);
    /* far to the side above: capped at 16 */
    CHECK(hd_dcglare_posidx(hd_vnorm(hd_v3(1, -0.01, 0.3)), f, up) <= 16);
}

static void test_step(void)
{
    hd_skybasis b;
    REQUIRE(hd_skybasis_init(&b, 1) == HD_OK);
    double *dc = calloc((size_t)b.nbins * 3, sizeof(double)), *sky = calloc((size_t)b.nbins * 3, sizeof(double));
    REQUIRE(dc && sky);
    int c = 10; /* a horizon-row patch; the view looks at its centre */
    hd_vec3 v = b.dir[c];
    for (int k = 0; k < 3; k++) {
        dc[3 * c + k] = 1e-3;
        sky[3 * c + k] = 1000;
    }
    double ev = 2000;
    double L = 1e-3 * 179 * 1000 / b.omega[c];
    double sum = L * L * b.omega[c];
    double want = 5.87e-5 * ev + 0.0918 * log10(1 + sum / pow(ev, 1.87)) + 0.16;
    CHECK_NEAR(hd_dcglare_step(ev, dc, sky, &b, v, hd_v3(0, 0, 1), 2000), want, 1e-12);
    /* the patch below the threshold: no source */
    double nosrc = 5.87e-5 * ev + 0.16;
    CHECK_NEAR(hd_dcglare_step(ev, dc, sky, &b, v, hd_v3(0, 0, 1), L * 1.01), nosrc, 1e-12);
    /* a factor threshold (<= 100) is a multiple of E_v / pi */
    CHECK_NEAR(hd_dcglare_step(ev, dc, sky, &b, v, hd_v3(0, 0, 1), L * HD_PI / ev * 0.99), want, 1e-12);
    CHECK_NEAR(hd_dcglare_step(ev, dc, sky, &b, v, hd_v3(0, 0, 1), L * HD_PI / ev * 1.01), nosrc, 1e-12);
    /* behind the view: no source */
    CHECK_NEAR(hd_dcglare_step(ev, dc, sky, &b, hd_vneg(v), hd_v3(0, 0, 1), 2000), nosrc, 1e-12);
    /* low light: the factor e / (1 + e), e = exp(0.024 E - 4); no light: 0 */
    double e = exp(0.024 * 300 - 4);
    CHECK_NEAR(hd_dcglare_step(300, dc, sky, &b, hd_vneg(v), hd_v3(0, 0, 1), 2000), (5.87e-5 * 300 + 0.16) * e / (1 + e),
               1e-12);
    CHECK(hd_dcglare_step(0, dc, sky, &b, v, hd_v3(0, 0, 1), 2000) == 0);
    /* the ground seen by a level view: direction halfway down, solid angle 2 (pi - 2 acos cos) = pi */
    memset(dc, 0, sizeof(double) * 3 * (size_t)b.nbins);
    for (int k = 0; k < 3; k++) {
        dc[k] = 1e-1;
        sky[k] = 100;
    }
    hd_vec3 lv = hd_v3(0, -1, 0);
    double Lg = 1e-1 * 179 * 100 / (HD_PI * sqrt(0.5));
    double P = hd_dcglare_posidx(hd_vnorm(hd_v3(0, -1, -1)), lv, hd_v3(0, 0, 1));
    want = 5.87e-5 * ev + 0.0918 * log10(1 + Lg * Lg * HD_PI / (P * P) / pow(ev, 1.87)) + 0.16;
    CHECK(Lg > 100.5);
    CHECK_NEAR(hd_dcglare_step(ev, dc, sky, &b, lv, hd_v3(0, 0, 1), 100.5), want, 1e-9);
    free(dc);
    free(sky);
    hd_skybasis_free(&b);
}

static void test_eval(void)
{
    /* one view, three steps (night, dim, bright), sky of MF:1 with light in one patch */
    hd_matrix dcd, ev, sky;
    REQUIRE(hd_matrix_alloc(&dcd, 1, 146, 3) == HD_OK);
    REQUIRE(hd_matrix_alloc(&ev, 1, 3, 3) == HD_OK);
    REQUIRE(hd_matrix_alloc(&sky, 146, 3, 3) == HD_OK);
    double evl[3] = {0, 500, 10000};
    for (int t = 0; t < 3; t++)
        for (int k = 0; k < 3; k++) hd_matrix_at(&ev, 0, t)[k] = evl[t] / 179;
    hd_dcglare_opts o;
    hd_dcglare_opts_default(&o);
    o.vdir = hd_v3(0, -1, 0);
    float *res;
    REQUIRE(hd_dcglare_eval(&dcd, &ev, &sky, &o, &res) == HD_OK);
    CHECK(res[0] == 0);
    CHECK_NEAR(res[2], 5.87e-5 * 10000 + 0.16, 1e-6);
    free(res);
    /* autonomy: 10000 lx is glare at 0.4, 500 lx not; the night step counts as occupied, no glare */
    o.limit = 0.4;
    REQUIRE(hd_dcglare_eval(&dcd, &ev, &sky, &o, &res) == HD_OK);
    CHECK_NEAR(res[0], 2.0 / 3.0, 1e-6);
    free(res);
    unsigned char occ[3] = {0, 1, 1};
    o.occupied = occ;
    REQUIRE(hd_dcglare_eval(&dcd, &ev, &sky, &o, &res) == HD_OK);
    CHECK_NEAR(res[0], 0.5, 1e-6);
    free(res);
    /* sizes checked */
    hd_matrix bad;
    REQUIRE(hd_matrix_alloc(&bad, 145, 3, 3) == HD_OK);
    CHECK(hd_dcglare_eval(&dcd, &ev, &bad, &o, &res) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "inconsistent matrix sizes");
    hd_matrix_free(&bad);
    REQUIRE(hd_matrix_alloc(&bad, 1, 145, 3) == HD_OK);
    hd_matrix sky145;
    REQUIRE(hd_matrix_alloc(&sky145, 145, 3, 3) == HD_OK);
    CHECK(hd_dcglare_eval(&bad, &ev, &sky145, &o, &res) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "not a Reinhart sky");
    hd_matrix_free(&bad);
    hd_matrix_free(&sky145);
    hd_matrix_free(&dcd);
    hd_matrix_free(&ev);
    hd_matrix_free(&sky);
}

int main(void)
{
    (void)hd_test_tmpdir;
    RUN(test_posidx);
    RUN(test_step);
    RUN(test_eval);
    return hd_test_done();
}

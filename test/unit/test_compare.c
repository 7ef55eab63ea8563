/* Unit tests: error measures (compare.h) against analytic cases. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hd_test.h"
#include "heliodon/compare.h"
#include "heliodon/glare.h"
#include "heliodon/matrix.h"
#include "heliodon/picture.h"

/* identical inputs -> every measure 0 */
static void test_identical(void)
{
    double a[5] = {1, 2, 3, 0, 5};
    hd_cmp_stats s;
    hd_compare_values(a, a, 5, 0, &s);
    CHECK(s.n == 5);
    CHECK(s.nused == 4);   /* the 0 is not lit */
    CHECK_NEAR(s.rms_rel, 0, 0);
    CHECK_NEAR(s.max_rel, 0, 0);
    CHECK_NEAR(s.total_rel, 0, 0);
}

/* a = k*b everywhere -> rms = mean = max = k-1 */
static void test_scaled(void)
{
    double b[100], a[100];
    for (int i = 0; i < 100; i++) { b[i] = 1 + i; a[i] = 1.1 * b[i]; }
    hd_cmp_stats s;
    hd_compare_values(a, b, 100, 0, &s);
    CHECK_REL(s.rms_rel, 0.1, 1e-12);
    CHECK_REL(s.mean_rel, 0.1, 1e-12);
    CHECK_REL(s.max_rel, 0.1, 1e-12);
    CHECK_REL(s.total_rel, 0.1, 1e-12);
}

/* alternating +e/-e: rms e, bias 0; floor as a fraction of the mean */
static void test_alternating_floor(void)
{
    double b[10], a[10];
    for (int i = 0; i < 10; i++) { b[i] = i < 8 ? 10 : 0.01; a[i] = b[i] * (i % 2 ? 1.2 : 0.8); }
    hd_cmp_stats s;
    hd_compare_values(a, b, 10, -0.01, &s);   /* floor = 1 % of mean 8.002 */
    CHECK(s.nused == 8);
    CHECK_NEAR(s.floor, 0.08002, 1e-9);
    CHECK_REL(s.rms_rel, 0.2, 1e-12);
    CHECK_NEAR(s.mean_rel, 0, 1e-12);
    CHECK_REL(s.mean_abs_rel, 0.2, 1e-12);
}

static void test_nonfinite(void)
{
    double b[4] = {1, 1, 1, 1}, a[4] = {1, NAN, INFINITY, 2};
    hd_cmp_stats s;
    hd_compare_values(a, b, 4, 0, &s);
    CHECK(s.nonfinite_a == 2);
    CHECK(s.nonfinite_b == 0);
    CHECK(s.nused == 2);
    CHECK(isfinite(s.rms_rel));
    CHECK_REL(s.rms_rel, sqrt(0.5), 1e-12);
    CHECK(s.imax == 3);
}

static void fill(hd_picture *p, double scale)
{
    for (int y = 0; y < p->yres; y++)
        for (int x = 0; x < p->xres; x++) {
            float *c = p->pix + 3 * ((size_t)y * p->xres + x);
            double v = (x < p->xres / 2) ? 0 : scale * (1 + 0.01 * x + 0.02 * y);
            c[0] = c[1] = c[2] = (float)v;
        }
}

/* a picture scaled by 1.25: luminance RMS 0.25 over lit pixels (the dark
 * half excluded), E_v ratio 1.25; identical pictures give 0 and equal DGP */
static void test_pictures(void)
{
    hd_picture a, b;
    REQUIRE(hd_picture_alloc(&a, 64, 64) == HD_OK);
    REQUIRE(hd_picture_alloc(&b, 64, 64) == HD_OK);
    fill(&a, 1.25);
    fill(&b, 1.0);
    hd_glare_view v;
    hd_view_default(&v);
    REQUIRE(hd_view_parse_line(&v, "-vta -vp 0 0 0 -vd 0 1 0 -vu 0 0 1 -vh 180 -vv 180") >= 0);
    hd_piccmp r;
    REQUIRE(hd_compare_pictures(&a, &b, &v, -0.01, &r) == HD_OK);
    CHECK(r.lum.nused == 64 * 32);
    CHECK_REL(r.lum.rms_rel, 0.25, 1e-6);
    CHECK(r.have_glare);
    CHECK_REL(r.ev_a / r.ev_b, 1.25, 1e-6);
    CHECK(r.dgp_a >= r.dgp_b);
    REQUIRE(hd_compare_pictures(&b, &b, &v, -0.01, &r) == HD_OK);
    CHECK_NEAR(r.lum.rms_rel, 0, 0);
    CHECK_NEAR(r.dgp_a - r.dgp_b, 0, 0);
    /* no view anywhere: glare part skipped, no error */
    REQUIRE(hd_compare_pictures(&a, &b, NULL, -0.01, &r) == HD_OK);
    CHECK(!r.have_glare);
    /* a perspective view given explicitly is refused */
    hd_glare_view pv;
    hd_view_default(&pv);
    CHECK(hd_compare_pictures(&a, &b, &pv, -0.01, &r) != HD_OK);
    hd_picture c;
    REQUIRE(hd_picture_alloc(&c, 32, 64) == HD_OK);
    CHECK(hd_compare_pictures(&a, &c, NULL, 0, &r) == HD_ERR_RANGE);
    CHECK_CONTAINS(hd_errmsg(), "32 x 64");
    hd_picture_free(&a);
    hd_picture_free(&b);
    hd_picture_free(&c);
}

/* reduce: 2x2 blocks averaged; constant picture unchanged; bad factor refused */
static void test_reduce(void)
{
    hd_picture a, r;
    REQUIRE(hd_picture_alloc(&a, 4, 2) == HD_OK);
    for (int i = 0; i < 8; i++) a.pix[3 * i] = a.pix[3 * i + 1] = a.pix[3 * i + 2] = (float)i;
    REQUIRE(hd_compare_reduce(&a, 2, &r) == HD_OK);
    CHECK(r.xres == 2 && r.yres == 1);
    CHECK_NEAR(r.pix[0], (0 + 1 + 4 + 5) / 4.0, 1e-6);
    CHECK_NEAR(r.pix[3], (2 + 3 + 6 + 7) / 4.0, 1e-6);
    hd_picture_free(&r);
    CHECK(hd_compare_reduce(&a, 3, &r) == HD_ERR_RANGE);
    hd_picture_free(&a);
}

static void test_matrices(void)
{
    hd_matrix a, b;
    REQUIRE(hd_matrix_alloc(&a, 2, 3, 3) == HD_OK);
    REQUIRE(hd_matrix_alloc(&b, 2, 3, 3) == HD_OK);
    for (int r = 0; r < 2; r++)
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 3; k++) {
                hd_matrix_at(&b, r, c)[k] = 1 + r + c;
                hd_matrix_at(&a, r, c)[k] = (1 + r + c) * (r ? 0.5 : 1.0);
            }
    hd_cmp_stats s;
    double pr[2];
    REQUIRE(hd_compare_matrices(&a, &b, 0, &s, pr) == HD_OK);
    CHECK_NEAR(pr[0], 0, 1e-12);
    CHECK_NEAR(pr[1], -0.5, 1e-12);
    CHECK_REL(s.rms_rel, sqrt(0.125), 1e-12);   /* half the elements at -0.5 */
    CHECK_NEAR(s.mean_rel, -0.25, 1e-12);
    hd_matrix c;
    REQUIRE(hd_matrix_alloc(&c, 3, 2, 3) == HD_OK);
    CHECK(hd_compare_matrices(&a, &c, 0, &s, NULL) == HD_ERR_RANGE);
    hd_matrix_free(&a);
    hd_matrix_free(&b);
    hd_matrix_free(&c);
}

/* the 1/sqrt(N) law: 4x samples halve the error; count for a target */
static void test_predict(void)
{
    CHECK_REL(hd_compare_predict_error(0.2, 100, 400), 0.1, 1e-12);
    CHECK_REL(hd_compare_predict_count(0.2, 100, 0.05), 1600, 1e-12);
    CHECK(hd_compare_predict_count(0.01, 100, 0.5) == 1);
    CHECK(hd_compare_predict_count(0.2, 100, 0) == 100);
}

/* the photon-map bias-variance model: fitted from values the model itself
 * generates, it returns its parameters; the chosen (N, k) reaches the target
 * and is optimal (other k at that N do worse, smaller N cannot reach it) */
static void test_pm_model(void)
{
    const double C = 0.8, B = 3e4, n0 = 3e5, k[4] = {5, 10, 20, 40};
    double var[4], db[4];
    for (int i = 0; i < 4; i++) {
        var[i] = C / k[i];
        double d = B * (k[i] - k[0]) / n0;
        db[i] = d * d;
    }
    hd_pm_model m;
    REQUIRE(hd_compare_pm_fit(k, var, db, 4, n0, &m) == 0);
    CHECK_REL(m.C, C, 1e-12);
    CHECK_REL(m.B, B, 1e-12);
    double N, kk;
    REQUIRE(hd_compare_pm_choose(&m, 0.1, &N, &kk) == 0);
    CHECK_REL(hd_compare_pm_error(&m, N, kk), 0.1, 1e-9);
    CHECK(hd_compare_pm_error(&m, N, kk * 1.2) > 0.1);
    CHECK(hd_compare_pm_error(&m, N, kk / 1.2) > 0.1);
    double best = 1e9;   /* with 2 % fewer photons no k reaches the target */
    for (double t = kk / 4; t < kk * 4; t *= 1.01) best = fmin(best, hd_compare_pm_error(&m, 0.98 * N, t));
    CHECK(best > 0.1);
    /* noise alone (no bias): any N, error from k only */
    double z[4] = {0, 0, 0, 0};
    REQUIRE(hd_compare_pm_fit(k, var, z, 4, n0, &m) == 0);
    CHECK(m.B == 0);
    REQUIRE(hd_compare_pm_choose(&m, 0.2, &N, &kk) == 0);
    CHECK(N == 0);
    CHECK_REL(hd_compare_pm_error(&m, 1e6, kk), 0.2, 1e-9);
    /* refusals */
    CHECK(hd_compare_pm_fit(k, var, db, 1, n0, &m) == -1);
    double kbad[2] = {10, 10};
    CHECK(hd_compare_pm_fit(kbad, var, db, 2, n0, &m) == -1);
    CHECK(hd_compare_pm_choose(&m, 0, &N, &kk) == -1);
}

int main(void)
{
    RUN(test_identical);
    RUN(test_scaled);
    RUN(test_alternating_floor);
    RUN(test_nonfinite);
    RUN(test_pictures);
    RUN(test_matrices);
    RUN(test_reduce);
    RUN(test_predict);
    RUN(test_pm_model);
    return hd_test_done();
}

/* Unit tests for the Klems angle bases (klems.h). */
#include "hd_test.h"
#include "heliodon/klems.h"
#include "heliodon/rng.h"

static void test_standard_counts(void)
{
    hd_klems_basis b;
    hd_klems_standard(&b, HD_KLEMS_FULL);
    CHECK(b.nbins == 145);
    CHECK(b.nrings == 9);
    hd_klems_standard(&b, HD_KLEMS_HALF);
    CHECK(b.nbins == 77);
    hd_klems_standard(&b, HD_KLEMS_QUARTER);
    CHECK(b.nbins == 41);
    CHECK(hd_klems_by_name(&b, "LBNL/Klems Full") == HD_OK && b.nbins == 145);
    CHECK(hd_klems_by_name(&b, "LBNL/Klems Whatever") == HD_ERR_FORMAT);
}

/* Projected solid angles sum to pi; solid angles to 2 pi; the values of
 * the spec (full-basis bin 0 = pi sin^2 5deg). */
static void test_lambda(void)
{
    for (int k = 0; k < 3; k++) {
        hd_klems_basis b;
        hd_klems_standard(&b, (hd_klems_kind)k);
        double s = 0, so = 0;
        for (int i = 0; i < b.nbins; i++) {
            s += hd_klems_lambda(&b, i);
            so += hd_klems_solid_angle(&b, i);
        }
        CHECK_NEAR(s, HD_PI, 1e-12);
        CHECK_NEAR(so, 2 * HD_PI, 1e-12);
    }
    hd_klems_basis b;
    hd_klems_standard(&b, HD_KLEMS_FULL);
    double s5 = sin(5 * HD_PI / 180);
    CHECK_NEAR(hd_klems_lambda(&b, 0), HD_PI * s5 * s5, 1e-12);
    /* smallest bin: outer ring, pi cos^2(75)/12 -> checkBSDF's 8.56 deg */
    double ml = hd_klems_min_lambda(&b);
    CHECK_NEAR(sqrt(ml / HD_PI) * 360 / HD_PI, 8.56, 0.005);
}

/* Spec values: bin of (0.196,0,0.98) is 1, (0,0.196,0.98) is 3. */
static void test_bins_spec(void)
{
    hd_klems_basis b;
    hd_klems_standard(&b, HD_KLEMS_FULL);
    CHECK(hd_klems_bin(&b, hd_v3(0, 0, 1)) == 0);
    CHECK(hd_klems_bin(&b, hd_v3(0.196, 0, 0.98)) == 1);
    CHECK(hd_klems_bin(&b, hd_v3(0, 0.196, 0.98)) == 3);
    CHECK(hd_klems_bin(&b, hd_v3(0, 0.196, -0.98)) == -1);
    /* grazing: last ring, azimuth 180 deg = column 6 of 12 */
    CHECK(hd_klems_bin(&b, hd_v3(-1, 0, 0)) == 133 + 6);
    /* world frame: ray travelling along -v in frame N=+Z, U=+Y */
    CHECK(hd_klems_bin_world(&b, hd_v3(-0.196, 0, -0.98), hd_v3(0, 0, 1), hd_v3(0, 1, 0)) == 1);
    CHECK(hd_klems_bin_world(&b, hd_v3(0, -0.196, -0.98), hd_v3(0, 0, 1), hd_v3(0, 1, 0)) == 3);
    CHECK(hd_klems_bin_world(&b, hd_v3(0, 0, 1), hd_v3(0, 0, 1), hd_v3(0, 1, 0)) == -1);
    CHECK(hd_klems_bin_world(&b, hd_v3(0, 0, -1), hd_v3(0, 0, 1), hd_v3(0, 0, 1)) == -1);
}

/* Direction <-> bin round trips, centres and random points. */
static void test_roundtrip(void)
{
    hd_rng r;
    hd_klems_basis b;
    hd_rng_init(&r, 1, 0);
    for (int k = 0; k < 3; k++) {
        hd_klems_standard(&b, (hd_klems_kind)k);
        int bad = 0, badw = 0;
        for (int i = 0; i < b.nbins; i++) {
            for (int j = 0; j < 20; j++) {
                double r0 = j ? hd_rng_uniform(&r) : 0.5, r1 = j ? hd_rng_uniform(&r) : 0.5;
                hd_vec3 v = hd_klems_dir(&b, i, r0, r1);
                if (fabs(hd_vlen(v) - 1) > 1e-12 || hd_klems_bin(&b, v) != i) bad++;
                hd_vec3 N = hd_vnorm(hd_v3(1, 2, 0.5)), U = hd_v3(0, 0, 1);
                hd_vec3 D = hd_klems_dir_world(&b, i, r0, r1, N, U);
                if (hd_klems_bin_world(&b, D, N, U) != i) badw++;
            }
        }
        CHECK_MSG(bad == 0, "basis %d: %d local round trips failed", k, bad);
        CHECK_MSG(badw == 0, "basis %d: %d world round trips failed", k, badw);
    }
}

/* Uniform (r0,r1) must be uniform in projected solid angle: a Monte Carlo
 * estimate of the projected solid angle of each bin (hits of cosine-
 * distributed directions) matches lambda. */
static void test_projected_uniform(void)
{
    hd_klems_basis b;
    hd_klems_standard(&b, HD_KLEMS_QUARTER);
    static int count[64];
    hd_rng r;
    hd_rng_init(&r, 7, 0);
    const int n = 400000;
    for (int i = 0; i < n; i++) {
        /* cosine-weighted hemisphere sample */
        double u = hd_rng_uniform(&r), phi = 2 * HD_PI * hd_rng_uniform(&r);
        double s = sqrt(u);
        hd_vec3 v = hd_v3(s * cos(phi), s * sin(phi), sqrt(1 - u));
        int k = hd_klems_bin(&b, v);
        if (k >= 0) count[k]++;
    }
    int worst = 0;
    for (int i = 0; i < b.nbins; i++) {
        double expect = n * hd_klems_lambda(&b, i) / HD_PI;
        if (fabs(count[i] - expect) > 5 * sqrt(expect)) worst++;
    }
    CHECK_MSG(worst == 0, "%d bins off by more than 5 sigma", worst);
    /* and the within-bin mapping: cos^2 uniform means the fraction of
     * directions of a bin above its mid-cos^2 is one half */
    int above = 0, tot = 0;
    double clo = cos(27 * HD_PI / 180), chi = cos(45 * HD_PI / 180);
    double mid = 0.5 * (clo * clo + chi * chi);
    for (int i = 0; i < 20000; i++) {
        hd_vec3 v = hd_klems_dir(&b, 9 + 3, hd_rng_uniform(&r), hd_rng_uniform(&r));
        tot++;
        if (v.z * v.z > mid) above++;
    }
    CHECK_NEAR((double)above / tot, 0.5, 0.015);
}

static void test_custom(void)
{
    hd_klems_basis b;
    double bnd[] = {0, 30, 60, 90};
    int nphi[] = {1, 4, 6};
    CHECK(hd_klems_init(&b, "custom", 3, bnd, nphi, NULL) == HD_OK);
    CHECK(b.nbins == 11);
    CHECK(hd_klems_ring_of(&b, 5, NULL) == 2);
    double bad[] = {0, 30, 20, 90};
    CHECK(hd_klems_init(&b, "bad", 3, bad, nphi, NULL) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "ring 1");
    double bad2[] = {0, 30, 60, 80};
    CHECK(hd_klems_init(&b, "bad2", 3, bad2, nphi, NULL) == HD_ERR_FORMAT);
    int nphi0[] = {1, 0, 6};
    CHECK(hd_klems_init(&b, "bad3", 3, bnd, nphi0, NULL) == HD_ERR_FORMAT);
}

int main(void)
{
    (void)hd_test_ref;     /* harness helpers unused here */
    (void)hd_test_tmpdir;
    RUN(test_standard_counts);
    RUN(test_lambda);
    RUN(test_bins_spec);
    RUN(test_roundtrip);
    RUN(test_projected_uniform);
    RUN(test_custom);
    return hd_test_done();
}

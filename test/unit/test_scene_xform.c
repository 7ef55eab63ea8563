/* Unit tests: xform transforms (rotation senses, composition order,
 * scale/mirror bookkeeping, arrays and their per-copy word lists). */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "hd_test.h"
#include "heliodon/xform.h"

static hd_vec3 apply(const char *words, hd_vec3 p, hd_xf *xo)
{
    char buf[512], *argv[64];
    int argc = 0;
    snprintf(buf, sizeof buf, "%s", words);
    for (char *t = strtok(buf, " "); t && argc < 64; t = strtok(NULL, " ")) argv[argc++] = t;
    hd_xf x;
    if (hd_xf_from_words(&x, argc, argv) != HD_OK) { printf("  %s\n", hd_errmsg()); return hd_v3(NAN, NAN, NAN); }
    if (xo) *xo = x;
    return hd_xf_point(&x, p);
}

#define CHECK_V(v, X, Y, Z) do { hd_vec3 v_ = (v); CHECK_NEAR(v_.x, X, 1e-12); CHECK_NEAR(v_.y, Y, 1e-12); CHECK_NEAR(v_.z, Z, 1e-12); } while (0)

static void test_rotations(void)
{
    CHECK_V(apply("-rz 90", hd_v3(1, 0, 0), NULL), 0, 1, 0);
    CHECK_V(apply("-rx 90", hd_v3(0, 1, 0), NULL), 0, 0, 1);
    CHECK_V(apply("-ry 90", hd_v3(0, 0, 1), NULL), 1, 0, 0);
    CHECK_V(apply("-rz 30", hd_v3(1, 0, 0), NULL), cos(HD_PI / 6), sin(HD_PI / 6), 0);
    CHECK_V(apply("-rz -450", hd_v3(1, 0, 0), NULL), 0, -1, 0);
    /* order: left to right */
    CHECK_V(apply("-rz 90 -t 1 2 3", hd_v3(1, 0, 0), NULL), 1, 3, 3);
    CHECK_V(apply("-t 1 2 3 -rz 90", hd_v3(1, 0, 0), NULL), -2, 2, 3);
}

static void test_scale_mirror(void)
{
    hd_xf x;
    CHECK_V(apply("-s 2 -t 1 0 0", hd_v3(1, 1, 1), &x), 3, 2, 2);
    CHECK_NEAR(x.sca, 2, 0); CHECK(!x.mirror);
    CHECK_V(apply("-mx", hd_v3(1, 2, 3), &x), -1, 2, 3);
    CHECK(x.mirror);
    CHECK_V(apply("-mx -my", hd_v3(1, 2, 3), &x), -1, -2, 3);
    CHECK(!x.mirror);
    CHECK_V(apply("-s -2", hd_v3(1, 2, 3), &x), -2, -4, -6);
    CHECK(x.mirror); CHECK_NEAR(x.sca, 2, 0);
    /* directions: rotation only */
    apply("-s 3 -rz 90 -t 5 5 5", hd_v3(0, 0, 0), &x);
    CHECK_V(hd_xf_direction(&x, hd_v3(1, 0, 0)), 0, 1, 0);
    CHECK_V(hd_xf_vector(&x, hd_v3(1, 0, 0)), 0, 3, 0);
    /* -i repeats */
    CHECK_V(apply("-i 3 -t 1 0 0 -rz 90", hd_v3(0, 0, 0), NULL), -1, 0, 0);
}

static void test_arrays(void)
{
    char *argv[] = {"-rz", "10", "-a", "3", "-t", "1", "0", "0", "-rz", "5", "-a", "2", "-t", "0", "1", "0",
                    "-i", "1", "-s", "2", "file.rad"};
    int argc = (int)(sizeof argv / sizeof argv[0]);
    hd_xf_spec sp;
    REQUIRE(hd_xf_parse(&sp, argc, argv) == HD_OK);
    CHECK(sp.nwords == argc - 1);
    CHECK(sp.ncopies == 6);
    for (long c = 0; c < sp.ncopies; c++) {
        hd_xf a, b;
        hd_xf_spec_copy(&sp, c, &a);
        const char *w[64];
        char buf[256];
        int nw = hd_xf_spec_copy_words(&sp, argv, c, w, 64, buf, sizeof buf);
        REQUIRE(hd_xf_from_words(&b, nw, (char *const *)w) == HD_OK);
        hd_vec3 p = hd_v3(0.3, -0.7, 1.1);
        hd_vec3 pa = hd_xf_point(&a, p), pb = hd_xf_point(&b, p);
        CHECK_NEAR(pa.x, pb.x, 1e-12); CHECK_NEAR(pa.y, pb.y, 1e-12); CHECK_NEAR(pa.z, pb.z, 1e-12);
        /* copy (i, j): rz10, (t1 rz5)^i, (ty)^j, s2 */
        long i = c / 2, j = c % 2;
        hd_xf e;
        hd_xf_identity(&e);
        char words[256];
        int n = snprintf(words, sizeof words, "-rz 10");
        for (long k = 0; k < i; k++) n += snprintf(words + n, sizeof words - (size_t)n, " -t 1 0 0 -rz 5");
        for (long k = 0; k < j; k++) n += snprintf(words + n, sizeof words - (size_t)n, " -t 0 1 0");
        snprintf(words + n, sizeof words - (size_t)n, " -s 2");
        hd_vec3 pe = apply(words, p, NULL);
        CHECK_NEAR(pa.x, pe.x, 1e-12); CHECK_NEAR(pa.y, pe.y, 1e-12); CHECK_NEAR(pa.z, pe.z, 1e-12);
    }
    hd_xf_spec_free(&sp);
}

static void test_errors(void)
{
    hd_xf x;
    char *a1[] = {"-t", "1", "2"};
    CHECK(hd_xf_from_words(&x, 3, a1) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "-t: expected 3 numbers");
    char *a2[] = {"-rz", "abc"};
    CHECK(hd_xf_from_words(&x, 2, a2) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "got abc");
    char *a3[] = {"-a", "0", "-t", "1", "0", "0"};
    hd_xf_spec sp;
    CHECK(hd_xf_parse(&sp, 6, a3) == HD_ERR_USAGE);
    char *a4[] = {"-s", "0"};
    CHECK(hd_xf_from_words(&x, 2, a4) == HD_ERR_USAGE);
    char *a5[] = {"-t", "1", "0", "0", "extra"};
    CHECK(hd_xf_from_words(&x, 5, a5) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "extra");
}

int main(void)
{
    (void)hd_test_ref;
    (void)hd_test_tmpdir;
    RUN(test_rotations);
    RUN(test_scale_mirror);
    RUN(test_arrays);
    RUN(test_errors);
    return hd_test_done();
}

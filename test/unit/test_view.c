/* Unit tests: views (parsing, formatting, view rays, aspect). */
#include "hd_test.h"
#include "heliodon/view.h"

#define DEG (HD_PI / 180)

static double angle_between(hd_vec3 a, hd_vec3 b)
{
    double c = hd_vdot(hd_vnorm(a), hd_vnorm(b));
    return acos(c > 1 ? 1 : c < -1 ? -1 : c);
}

static void test_format_radiance_view_line(void)
{
    hd_view v;
    hd_view_default(&v);
    char buf[512];
    hd_view_format(&v, buf, sizeof buf);
    CHECK_STR(buf, "-vtv -vp 0 0 0 -vd 0 1 0 -vu 0 0 1 -vh 45 -vv 45 -vo 0 -va 0 -vs 0 -vl 0");
    /* the VIEW= line Radiance's rpict wrote for fish.vf (shared reference) */
    REQUIRE(hd_view_parse_line(&v, "rview -vta -vp 1.5 3.5 1.2 -vd 0 -1 0 -vu 0 0 1 -vh 180 -vv 180") == 6);
    hd_view_format(&v, buf, sizeof buf);
    CHECK_STR(buf, "-vta -vp 1.5 3.5 1.2 -vd 0 -1 0 -vu 0 0 1 -vh 180 -vv 180 -vo 0 -va 0 -vs 0 -vl 0");
}

static void test_view_file_and_reference_header(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder");
    char path[512];
    hd_view v;
    hd_view_default(&v);
    snprintf(path, sizeof path, "%s/scenes/box/persp.vf", ref);
    REQUIRE(hd_view_read_file(&v, path) == HD_OK);
    char buf[512];
    hd_view_format(&v, buf, sizeof buf);
    /* compare with the VIEW= line in Radiance's getinfo output */
    snprintf(path, sizeof path, "%s/scenes/box/a2_clear_persp.getinfo.txt", ref);
    FILE *fp = fopen(path, "r");
    REQUIRE(fp != NULL);
    char line[1024], *want = NULL;
    while (fgets(line, sizeof line, fp))
        if ((want = strstr(line, "VIEW= "))) break;
    fclose(fp);
    REQUIRE(want != NULL);
    want += 6;
    want[strcspn(want, "\r\n")] = 0;
    CHECK_STR(buf, want);
}

static void test_edges_at_half_angle(void)
{
    const char types[] = "vahsc";
    for (int k = 0; types[k]; k++) {
        hd_view v;
        hd_view_default(&v);
        v.type = types[k];
        v.vd = hd_v3(1, 2, 0.5);
        v.vu = hd_v3(0, 0, 1);
        v.vh = types[k] == 'v' ? 70 : types[k] == 'c' ? 240 : 150;
        v.vv = types[k] == 'v' || types[k] == 'c' ? 50 : 150;
        REQUIRE(hd_view_setup(&v) == HD_OK);
        hd_vec3 o, d;
        CHECK(hd_view_ray(&v, 0.5, 0.5, &o, &d) >= 0);
        CHECK_NEAR(angle_between(d, v.vd), 0, 1e-9);
        CHECK(hd_view_ray(&v, 1.0, 0.5, &o, &d) >= 0);
        CHECK_NEAR(angle_between(d, v.vd), v.vh / 2 * DEG, 1e-9);
        CHECK(hd_view_ray(&v, 0.5, 0.0, &o, &d) >= 0);
        CHECK_NEAR(angle_between(d, v.vd), v.vv / 2 * DEG, 1e-9);
        /* right edge is to the right: (vd x vu) */
        hd_view_ray(&v, 0.9, 0.5, &o, &d);
        CHECK(hd_vdot(d, hd_vcross(v.vd, v.vu)) > 0);
        hd_view_ray(&v, 0.5, 0.9, &o, &d);
        CHECK(hd_vdot(d, v.vu) > 0);
        /* inverse mapping */
        double x, y;
        hd_view_ray(&v, 0.3, 0.7, &o, &d);
        CHECK(hd_view_loc(&v, d, &x, &y));
        CHECK_NEAR(x, 0.3, 1e-9);
        CHECK_NEAR(y, 0.7, 1e-9);
    }
}

static void test_angular_fisheye_circle(void)
{
    hd_view v;
    hd_view_default(&v);
    REQUIRE(hd_view_parse_line(&v, "-vta -vp 1 2 3 -vd 0 -1 0 -vu 0 0 1 -vh 180 -vv 180") == 6);
    REQUIRE(hd_view_setup(&v) == HD_OK);
    hd_vec3 o, d;
    /* as in Radiance, a 180-degree angular fisheye still maps its corners
     * (to directions behind the view plane, 125 degrees here); only
     * locations beyond 360 degrees are outside */
    CHECK(hd_view_ray(&v, 0.01, 0.01, &o, &d) >= 0);
    CHECK_NEAR(angle_between(d, v.vd), HD_PI * sqrt(2 * 0.49 * 0.49), 1e-9);
    v.vh = v.vv = 360;
    REQUIRE(hd_view_setup(&v) == HD_OK);
    CHECK(hd_view_ray(&v, 0.01, 0.01, &o, &d) < 0);
    CHECK(d.x == 0 && d.y == 0 && d.z == 0);
    v.vh = v.vv = 180;
    REQUIRE(hd_view_setup(&v) == HD_OK);
    /* equidistant: radius 0.25 -> 45 degrees */
    CHECK(hd_view_ray(&v, 0.75, 0.5, &o, &d) >= 0);
    CHECK_NEAR(angle_between(d, v.vd), 45 * DEG, 1e-9);
    CHECK_NEAR(o.x, 1, 0); CHECK_NEAR(o.y, 2, 0); CHECK_NEAR(o.z, 3, 0);
    /* hemispherical: radius 0.25 -> asin(0.5) = 30 degrees */
    v.type = 'h';
    REQUIRE(hd_view_setup(&v) == HD_OK);
    hd_view_ray(&v, 0.75, 0.5, &o, &d);
    CHECK_NEAR(angle_between(d, v.vd), 30 * DEG, 1e-9);
    CHECK(hd_view_ray(&v, 0.0, 0.0, &o, &d) < 0);
}

static void test_parallel_and_shift(void)
{
    hd_view v;
    hd_view_default(&v);
    REQUIRE(hd_view_parse_line(&v, "-vtl -vp 0 0 0 -vd 0 0 -1 -vu 0 1 0 -vh 10 -vv 4 -vs 0.5 -vl 0") == 8);
    REQUIRE(hd_view_setup(&v) == HD_OK);
    hd_vec3 o, d;
    hd_view_ray(&v, 0.5, 1.0, &o, &d);
    CHECK_NEAR(d.z, -1, 1e-12);
    /* shifted by half the width: x' = 0.5 + 0.5 - 0.5 = 0.5 of 10 units along vd x vu = (1,0,0) */
    CHECK_NEAR(o.x, 5, 1e-12);
    CHECK_NEAR(o.y, 2, 1e-12);
}

static void test_normaspect(void)
{
    hd_view v;
    hd_view_default(&v);
    v.vh = 60; v.vv = 40;
    REQUIRE(hd_view_setup(&v) == HD_OK);
    int x = 512, y = 512;
    double pa = 1;
    hd_view_normaspect(hd_view_aspect(&v), &pa, &x, &y);
    CHECK(x == 512);
    CHECK(y == (int)(512 * tan(20 * DEG) / tan(30 * DEG) + 0.5));
    x = 512; y = 100; pa = 1;
    hd_view_normaspect(hd_view_aspect(&v), &pa, &x, &y);
    CHECK(y == 100);
    CHECK(x == (int)(100 / (tan(20 * DEG) / tan(30 * DEG)) + 0.5));
    x = 300; y = 200; pa = 0;
    hd_view_normaspect(hd_view_aspect(&v), &pa, &x, &y);
    CHECK(x == 300 && y == 200);
    CHECK_NEAR(pa, hd_view_aspect(&v) * 300 / 200, 1e-12);
}

static void test_bad_views(void)
{
    hd_view v;
    hd_view_default(&v);
    char *a1[] = {"-vtx"};
    CHECK(hd_view_parse_arg(&v, 1, a1, 0) < 0);
    CHECK_CONTAINS(hd_errmsg(), "view type");
    char *a2[] = {"-vp", "1", "2"};
    CHECK(hd_view_parse_arg(&v, 3, a2, 0) < 0);
    CHECK_CONTAINS(hd_errmsg(), "-vp");
    char *a3[] = {"-vh", "wide"};
    CHECK(hd_view_parse_arg(&v, 2, a3, 0) < 0);
    CHECK_CONTAINS(hd_errmsg(), "wide");
    char *a4[] = {"-vf", "/nonexistent/view.vf"};
    CHECK(hd_view_parse_arg(&v, 2, a4, 0) < 0);
    CHECK_CONTAINS(hd_errmsg(), "/nonexistent/view.vf");
    char *a5[] = {"-x"};
    CHECK(hd_view_parse_arg(&v, 1, a5, 0) == 0);
    hd_view_default(&v);
    v.vu = hd_v3(0, 2, 0);
    CHECK(hd_view_setup(&v) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "parallel");
    hd_view_default(&v);
    v.vh = 180;
    CHECK(hd_view_setup(&v) != HD_OK);
    hd_view_default(&v);
    v.vd = hd_v3(0, 0, 0);
    CHECK(hd_view_setup(&v) != HD_OK);
}

int main(void)
{
    RUN(test_format_radiance_view_line);
    RUN(test_view_file_and_reference_header);
    RUN(test_edges_at_half_angle);
    RUN(test_angular_fisheye_circle);
    RUN(test_parallel_and_shift);
    RUN(test_normaspect);
    RUN(test_bad_views);
    return hd_test_done();
}

/* Unit tests: the BSDF / aBSDF scene materials (material_bsdf.c) and their
 * shading in the renderer (render.c). */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "hd_test.h"
#include "heliodon/bsdf.h"
#include "heliodon/material.h"
#include "heliodon/render.h"
#include "heliodon/scene.h"
#include "heliodon/trace.h"

static void test_args(void)
{
    char dir[512], xml[600], scene[600], path[1024];
    snprintf(dir, sizeof dir, "%s/test_material_bsdf", hd_test_tmpdir());
    char cmd[600];
    snprintf(cmd, sizeof cmd, "mkdir -p '%s'", dir);
    REQUIRE(system(cmd) == 0);
    snprintf(xml, sizeof xml, "%s/lam.xml", dir);
    snprintf(scene, sizeof scene, "%s/scene.rad", dir);
    REQUIRE(hd_test_write_lambert_klems(xml, 0.5));
    hd_tmat m;
    /* found relative to the scene file; transform rotates the up vector */
    char *s1[] = {"0", "lam.xml", "0", "1", "0", ".", "-rz", "90"};
    double r9[9] = {.1, .2, .3, .4, .5, .6, .7, .8, .9};
    CHECK(hd_tmat_bsdf_args(&m, 0, "w", s1, 8, r9, 9, scene, "f.rad:3: BSDF w", path, sizeof path) == HD_OK);
    CHECK_STR(path, xml);
    CHECK_NEAR(m.up.x, -1, 1e-12);
    CHECK_NEAR(m.up.y, 0, 1e-12);
    CHECK_NEAR(m.bsdf_rfront[2], .3, 0);
    CHECK_NEAR(m.bsdf_rback[0], .4, 0);
    CHECK_NEAR(m.bsdf_tdiff[1], .8, 0);
    CHECK(m.type == HD_MAT_BSDF && !m.absdf && m.thick == 0);
    /* aBSDF: no thickness */
    char *s2[] = {"lam.xml", "0", "0", "1", "."};
    CHECK(hd_tmat_bsdf_args(&m, 1, "a", s2, 5, NULL, 0, scene, "f.rad:4: aBSDF a", path, sizeof path) == HD_OK);
    CHECK(m.absdf && m.up.z == 1);
    /* errors name the place */
    CHECK(hd_tmat_bsdf_args(&m, 0, "w", s2, 5, NULL, 0, scene, "f.rad:5", path, sizeof path) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "f.rad:5");
    char *s3[] = {"0", "nosuch.xml", "0", "0", "1", "."};
    CHECK(hd_tmat_bsdf_args(&m, 0, "w", s3, 6, NULL, 0, scene, "f.rad:6", path, sizeof path) == HD_ERR_IO);
    CHECK_CONTAINS(hd_errmsg(), "f.rad:6");
    CHECK_CONTAINS(hd_errmsg(), "nosuch.xml");
    char *s4[] = {"thick", "lam.xml", "0", "0", "1", "."};
    CHECK(hd_tmat_bsdf_args(&m, 0, "w", s4, 6, NULL, 0, scene, "f.rad:7", path, sizeof path) == HD_ERR_UNSUPPORTED);
    CHECK(hd_tmat_bsdf_args(&m, 0, "w", s1, 6, r9, 4, scene, "f.rad:8", path, sizeof path) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "f.rad:8");
}

/* A local light above a Lambertian-transmitting pane: the irradiance below
 * with multiple importance sampling (NEE at the pane + BSDF sampling)
 * equals the estimate without it (NEE only counts the light), and both are
 * close to the analytic value for a small source. */
static void test_mis_local_light(void)
{
    char dir[512], xml[600], scene[600];
    snprintf(dir, sizeof dir, "%s/test_material_bsdf", hd_test_tmpdir());
    snprintf(xml, sizeof xml, "%s/lam2.xml", dir);
    snprintf(scene, sizeof scene, "%s/mis.rad", dir);
    REQUIRE(hd_test_write_lambert_klems(xml, 0.6));
    FILE *fp = fopen(scene, "w");
    REQUIRE(fp);
    /* 0.2 x 0.2 light at z = 2 facing down (radiance 1000); pane at z = 1 facing down */
    fprintf(fp, "void light lamp 0 0 3 1000 1000 1000\n"
                "lamp polygon l 0 0 12  -.1 -.1 2  -.1 .1 2  .1 .1 2  .1 -.1 2\n"
                "void BSDF pane 6 0 lam2.xml 0 1 0 . 0 0\n"
                "pane polygon p 0 0 12  -50 -50 1  -50 50 1  50 50 1  50 -50 1\n");
    fclose(fp);
    hd_scene sc;
    hd_scene_init(&sc);
    char *files[] = {scene};
    REQUIRE(hd_scene_load_files(&sc, 1, files, NULL) == HD_OK);
    hd_tscene *ts;
    REQUIRE(hd_tscene_from_scene(&ts, &sc) == HD_OK);
    double e[2];
    for (int k = 0; k < 2; k++) {
        hd_renderer r;
        r.scene = ts;
        hd_render_defaults(&r.o);
        r.o.ab = 1;
        r.o.ad = 4096;
        r.o.lw = 1e-7;
        r.o.nomis = k;
        double sum = 0;
        int n = 40;
        for (int i = 0; i < n; i++) {
            hd_rng rng;
            hd_rng_init(&rng, 7, (uint64_t)i + 100 * (uint64_t)k);
            double rgb[3];
            hd_render_irradiance(&r, hd_v3(0, 0, 0), hd_v3(0, 0, 1), &rng, rgb);
            sum += rgb[1];
        }
        e[k] = sum / n;
    }
    /* analytic: the pane irradiance below the light is I/d² with
     * I = L·A (d = 1), the pane's transmitted radiance tau/pi·E_pane(x),
     * integrated over the pane as seen from the sensor 1 m below: for a
     * small source this is tau·L·A·∫ cos^4 cos^4 / (pi r^2 ...) — computed
     * here numerically over the pane */
    double L = 1000, A = 0.04, tau = 0.6, want = 0;
    int g = 400;
    double h = 20.0 / g;
    for (int i = 0; i < g; i++)
        for (int j = 0; j < g; j++) {
            double x = -10 + (i + 0.5) * h, y = -10 + (j + 0.5) * h, r2 = x * x + y * y + 1;
            double epane = L * A / (r2 * r2);              /* cos·cos/r² with cos = 1/r */
            double lpane = tau / HD_PI * epane;
            want += lpane / (r2 * r2) * h * h;            /* sensor 1 m below: cos·cos/r² */
        }
    printf("  MIS %.5g, NEE only %.5g, analytic %.5g\n", e[0], e[1], want);
    CHECK_REL(e[0], e[1], 0.03);
    CHECK_REL(e[0], want, 0.03);
    hd_tscene_free(ts);
    hd_scene_free(&sc);
}

int main(void)
{
    RUN(test_args);
    RUN(test_mis_local_light);
    return hd_test_done();
}

/* Unit tests: primary hits of photon-map gathers (pmap_primary.c) — the
 * per-source analytic terms against closed forms and against the backward
 * renderer's direct light. */
#include <stdlib.h>
#include <string.h>

#include "hd_test.h"
#include "heliodon/material.h"
#include "pmprimary.h"
#include "heliodon/render.h"
#include "heliodon/scene.h"
#include "heliodon/trace.h"

static hd_tscene *load_file(const char *path, const char *text)
{
    FILE *fp = fopen(path, "w");
    if (!fp) return NULL;
    fputs(text, fp);
    fclose(fp);
    hd_scene sc;
    hd_scene_init(&sc);
    char *files[] = {(char *)path};
    hd_tscene *ts = NULL;
    if (hd_scene_load_files(&sc, 1, files, NULL) != HD_OK || hd_tscene_from_scene(&ts, &sc) != HD_OK) {
        hd_report_error();
        ts = NULL;
    }
    hd_scene_free(&sc);
    return ts;
}

static const double HALF = 0.2665 * HD_PI / 180;

/* The sun through a Lambertian Klems pane (tau/pi) seen from below:
 * radiance per unit sun radiance = tau/pi cos(theta) Omega. */
static void test_bsdf_window(void)
{
    char xml[600], scene[600];
    snprintf(xml, sizeof xml, "%s/pmprim_lam.xml", hd_test_tmpdir());
    snprintf(scene, sizeof scene, "%s/pmprim_lam.rad", hd_test_tmpdir());
    REQUIRE(hd_test_write_lambert_klems(xml, 0.4));
    hd_tscene *ts = load_file(scene, "void BSDF pane 6 0 pmprim_lam.xml 0 1 0 . 0 0\n"
                                     "pane polygon p 0 0 12  -50 -50 1  -50 50 1  50 50 1  50 -50 1\n");
    REQUIRE(ts);
    hd_pmprim pp;
    REQUIRE(hd_pmap_primary(ts, hd_v3(0, 0, 0), hd_v3(0, 0, 1), 0, 1, 2, 1e-6, &pp) > 0);
    CHECK(pp.npt == 0);
    REQUIRE(pp.nana == 1);
    double th = 30 * HD_PI / 180;
    hd_vec3 l = hd_v3(sin(th), 0, cos(th));
    double out[3] = {0, 0, 0};
    CHECK(hd_pmprim_direct(ts, &pp, l, HALF, 1, out) == 1);
    double om = 2 * HD_PI * (1 - cos(HALF));
    CHECK_REL(out[1], 0.4 / HD_PI * cos(th) * om, 1e-3);
    /* a source below the pane (same side as the viewer) gives nothing */
    double none[3] = {0, 0, 0};
    CHECK(hd_pmprim_direct(ts, &pp, hd_v3(0, sin(th), -cos(th)), HALF, 1, none) == 0 && none[1] == 0);
    /* a blocker between the pane and the sun casts its shadow */
    hd_tscene_free(ts);
    ts = load_file(scene, "void BSDF pane 6 0 pmprim_lam.xml 0 1 0 . 0 0\n"
                          "pane polygon p 0 0 12  -50 -50 1  -50 50 1  50 50 1  50 -50 1\n"
                          "void plastic black 0 0 5 0 0 0 0 0\n"
                          "black polygon roof 0 0 12  -50 -50 5  50 -50 5  50 50 5  -50 50 5\n");
    REQUIRE(ts);
    REQUIRE(hd_pmap_primary(ts, hd_v3(0, 0, 0), hd_v3(0, 0, 1), 0, 1, 2, 1e-6, &pp) > 0);
    double sh[3] = {0, 0, 0};
    CHECK(hd_pmprim_direct(ts, &pp, l, HALF, 1, sh) == 0 && sh[1] == 0);
    hd_tscene_free(ts);
}

/* The sun seen straight through a glass pane: the escaping ray inside the
 * disk counts T (per unit radiance); outside the disk nothing; the reflected
 * branch of the glass sees a sun mirrored in the pane. */
static void test_glass_escape(void)
{
    char scene[600];
    snprintf(scene, sizeof scene, "%s/pmprim_glass.rad", hd_test_tmpdir());
    hd_tscene *ts = load_file(scene, "void glass g 0 0 3 .9 .9 .9\n"
                                     "g polygon p 0 0 12  -50 -50 1  -50 50 1  50 50 1  50 -50 1\n");
    REQUIRE(ts);
    hd_pmprim pp;
    REQUIRE(hd_pmap_primary(ts, hd_v3(0, 0, 0), hd_v3(0, 0, 1), 0, 1, 2, 1e-6, &pp) > 0);
    REQUIRE(pp.nana == 2);   /* through, and the reflected branch leaving downwards */
    double R[3], T[3];
    const double tn[3] = {.9, .9, .9};
    hd_glass_coeffs(tn, 1.52, 1, R, T);
    double out[3] = {0, 0, 0};
    CHECK(hd_pmprim_direct(ts, &pp, hd_v3(0, 0, 1), HALF, 1, out) == 1);
    CHECK_REL(out[1], T[1], 1e-9);
    double off[3] = {0, 0, 0};
    CHECK(hd_pmprim_direct(ts, &pp, hd_vnorm(hd_v3(0.01, 0, 1)), HALF, 1, off) == 0);
    double refl[3] = {0, 0, 0};
    CHECK(hd_pmprim_direct(ts, &pp, hd_v3(0, 0, -1), HALF, 1, refl) == 1);
    CHECK_REL(refl[1], R[1], 1e-9);
    /* depth 0: no reflected branch */
    REQUIRE(hd_pmap_primary(ts, hd_v3(0, 0, 0), hd_v3(0, 0, 1), 0, 1, 0, 1e-6, &pp) > 0);
    CHECK(pp.nana == 1);
    /* -I: one lookup at the origin, nothing analytic */
    REQUIRE(hd_pmap_primary(ts, hd_v3(1, 2, 3), hd_v3(0, 0, 2), 1, 0.5, 2, 1e-6, &pp) == 1);
    CHECK(pp.npt == 1 && pp.nana == 0 && pp.pt[0].n.z == 1 && pp.pt[0].f[0] == 0.5);
    hd_tscene_free(ts);
}

/* A rough plastic floor lit by a sun, seen near the mirror direction: the
 * analytic highlight plus the diffuse direct rho/pi cos Omega L equals the
 * backward renderer's direct light (-ab 0, sun centre). */
static void test_specular_highlight(void)
{
    char scene[600];
    snprintf(scene, sizeof scene, "%s/pmprim_spec.rad", hd_test_tmpdir());
    double th = 40 * HD_PI / 180;
    char text[1024];
    snprintf(text, sizeof text,
             "void light solar 0 0 3 1000 1000 1000\n"
             "solar source sun 0 0 4 %.9f 0 %.9f 0.533\n"
             "void plastic desk 0 0 5 .35 .35 .35 .05 .08\n"
             "desk polygon f 0 0 12  -50 -50 0  50 -50 0  50 50 0  -50 50 0\n",
             sin(th), cos(th));
    hd_tscene *ts = load_file(scene, text);
    REQUIRE(ts);
    hd_vec3 l = hd_v3(sin(th), 0, cos(th));
    /* eye above, looking at the origin from 3 degrees off the mirror direction */
    double te = (40 + 3) * HD_PI / 180;
    hd_vec3 eye = hd_vscale(hd_v3(-sin(te), 0.02, cos(te)), 2);
    hd_vec3 d = hd_vnorm(hd_vneg(eye));
    hd_pmprim pp;
    REQUIRE(hd_pmap_primary(ts, eye, d, 0, 1, 2, 1e-6, &pp) > 0);
    REQUIRE(pp.npt == 1 && pp.nana == 1);
    double spec[3] = {0, 0, 0};
    CHECK(hd_pmprim_direct(ts, &pp, l, HALF, 1, spec) == 1);
    double om = 2 * HD_PI * (1 - cos(HALF));
    hd_renderer r;
    r.scene = ts;
    hd_render_defaults(&r.o);
    r.o.ab = 0;
    double rgb[3];
    hd_rng rng;
    hd_rng_init(&rng, 1, 0);
    hd_render_radiance(&r, eye, d, 0, &rng, rgb, NULL);
    /* diffuse coefficient of the lookup point (rho_d/pi) times the direct irradiance */
    double diff = pp.pt[0].f[1] * cos(th) * om * 1000;
    fprintf(stderr, "  highlight %.4g + diffuse %.4g vs rtrace -ab 0 %.4g\n", spec[1] * 1000, diff, rgb[1]);
    CHECK(spec[1] * 1000 > 0.2 * rgb[1]);   /* near the mirror direction the highlight matters */
    CHECK_REL(diff + spec[1] * 1000, rgb[1], 0.02);
    hd_tscene_free(ts);
}

int main(void)
{
    RUN(test_bsdf_window);
    RUN(test_glass_escape);
    RUN(test_specular_highlight);
    return hd_test_done();
}

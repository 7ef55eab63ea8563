/* Unit tests: the BSDF rules the backward walk (walk.c) applies at a hit
 * of Klems data: the source term f(l, v)·|cos l| (hd_scatter_bsdf_direct),
 * Radiance's specular threshold (hd_scatter_bsdf_split) and the sampled
 * continuation's throughput (hd_scatter_bsdf_sample).  The walk's numbers
 * are checked by test_render, test_contrib, test_material_bsdf and the
 * bsdf_* e2e scripts. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "hd_test.h"
#include "scatter.h"
#include "heliodon/scene.h"
#include "heliodon/trace.h"

static hd_tscene *load(hd_scene *sc, const char *name, const char *reals)
{
    char dir[512], xml[600], path[600];
    snprintf(dir, sizeof dir, "%s/test_bsdf_split", hd_test_tmpdir());
    snprintf(xml, sizeof xml, "%s/lam.xml", dir);
    snprintf(path, sizeof path, "%s/%s", dir, name);
    char cmd[700];
    snprintf(cmd, sizeof cmd, "mkdir -p '%s'", dir);
    if (system(cmd) != 0) return NULL;
    if (!hd_test_write_lambert_klems(xml, 0.6)) return NULL;
    FILE *fp = fopen(path, "w");
    if (!fp) return NULL;
    /* lamp 0.2 x 0.2 at z = 2 facing down; pane at z = 1 facing down
     * (thickness 0.1: the transmitted side's origin is 0.1 above it) */
    fprintf(fp, "void light lamp 0 0 3 1000 1000 1000\n"
                "lamp polygon l 0 0 12  -.1 -.1 2  -.1 .1 2  .1 .1 2  .1 -.1 2\n"
                "void BSDF pane 6 0.1 lam.xml 0 1 0 . 0 %s\n"
                "pane polygon p 0 0 12  -50 -50 1  -50 50 1  50 50 1  50 -50 1\n", reals);
    fclose(fp);
    hd_scene_init(sc);
    char *files[] = {path};
    hd_tscene *ts = NULL;
    if (hd_scene_load_files(sc, 1, files, NULL) != HD_OK || hd_tscene_from_scene(&ts, sc) != HD_OK) return NULL;
    return ts;
}

/* the scene (load) and the pane's hit s by a ray from below; NULL on failure */
static hd_tscene *hit_pane(hd_scene *sc, const char *name, const char *reals, hd_scatter *s)
{
    hd_tscene *ts = load(sc, name, reals);
    hd_hit h;
    hd_vec3 dir = hd_v3(0, 0, 1);
    if (!ts || !hd_tscene_intersect(ts, hd_v3(0.3, 0.2, 0), dir, 0, 0, &h)) return NULL;
    hd_scatter_at(ts, &h, dir, 0, s);
    return s->kind == HD_SC_BSDF ? ts : NULL;
}

/* the source term and the continuation of Lambertian transmission 0.6 */
static void test_lambert_data(void)
{
    hd_scene sc;
    hd_scatter s;
    hd_tscene *ts = hit_pane(&sc, "plain.rad", "0", &s);
    REQUIRE(ts);
    hd_vec3 v = hd_vsub(hd_v3(0, 0, 2), s.p);
    hd_vec3 l = hd_vscale(v, 1 / hd_vlen(v));
    /* tau/pi times the cosine towards the lamp centre */
    CHECK_REL(hd_scatter_bsdf_direct(&s, l, 0.04 / hd_vdot(v, v), 1, 1, l, 0, NULL, NULL),
              0.6 / HD_PI / sqrt(1 + 0.3 * 0.3 + 0.2 * 0.2), 0.02);
    /* the data only transmit: the continuation goes up, f·|cos|/pdf = tau */
    hd_vec3 d;
    double wt, pdf;
    REQUIRE(hd_scatter_bsdf_sample(&s, NULL, HD_BSDF_BACKWARD, HD_BSDF_ALL, 1, 0.3, 0.6, 0.2, &d, &wt, &pdf));
    CHECK(d.z > 0 && pdf > 0);
    CHECK_NEAR(wt, 0.6, 0.02);
    /* thickness 0.1: the transmitted side's rays leave from 0.1 above */
    CHECK_NEAR(hd_tmat_bsdf_through_origin(s.m, s.p, s.n).z, 1.1, 1e-9);
    hd_tscene_free(ts);
    hd_scene_free(&sc);
}

/* Radiance's specular threshold (m_bsdf.c): the Klems data here are all
 * Lambertian (the split leaves no directional part, b = 0 <= st), so the
 * transmission (0.6) is lit as a diffuse surface and not sampled; the
 * reflection side has no data. */
static void test_threshold(void)
{
    hd_scene sc;
    hd_scatter s;
    hd_tscene *ts = hit_pane(&sc, "thr.rad", "9 .1 .1 .1 .1 .1 .1 .1 .1 .1", &s);
    REQUIRE(ts);
    double ra, ta;
    CHECK(hd_scatter_bsdf_split(&s, NULL, 0.15, &ra, &ta) == HD_BSDF_ALL);
    CHECK_NEAR(ta, 0.6, 0.01);
    CHECK_NEAR(ra, 0, 1e-12);
    /* without the threshold the same hit is sampled */
    CHECK(hd_scatter_bsdf_split(&s, NULL, -1, &ra, &ta) == 0 && ra == 0 && ta == 0);
    hd_tscene_free(ts);
    hd_scene_free(&sc);
}

int main(void)
{
    RUN(test_lambert_data);
    RUN(test_threshold);
    return hd_test_done();
}

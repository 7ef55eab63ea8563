/* Unit tests: the BSDF shading loop shared by render.c and contrib.c
 * (shade_bsdf.c): which callbacks run, in which order, with which origins
 * (thickness proxy), and how many random numbers the loop itself draws.
 * The numbers of the two integrators are checked by test_render,
 * test_contrib, test_material_bsdf and the bsdf_* e2e scripts. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "hd_test.h"
#include "scatter.h"
#include "heliodon/scene.h"
#include "shade_bsdf.h"
#include "heliodon/trace.h"

typedef struct log {
    const hd_tscene *ts;
    char seq[64];          /* L = lambert, S = sample, E = eval, A = add, C = cont */
    int n;
    int skip_k;            /* sample() refuses this source */
    int zero_eval;         /* eval() returns 0 */
    double tr[3];
    hd_vec3 corg, cdir;
    double cwt, cpdf, fc, wl_seen;
    double ramb[3], tamb[3];   /* the diffuse parts lambert() was given */
} log_t;

static void mark(log_t *g, char c) { if (g->n < 63) g->seq[g->n++] = c; }

static void cb_lambert(void *ctx, const hd_scatter *sc, const double ramb[3], const double tamb[3], hd_rng *rng)
{
    (void)sc; (void)rng;
    log_t *g = ctx;
    mark(g, 'L');
    memcpy(g->ramb, ramb, sizeof g->ramb);
    memcpy(g->tamb, tamb, sizeof g->tamb);
}

static int cb_sample(void *ctx, int k, hd_vec3 p, hd_rng *rng, hd_vec3 *l, double *om, double *dist, int *target)
{
    (void)rng;
    log_t *g = ctx;
    mark(g, 'S');
    if (k == g->skip_k) return 0;
    hd_vec3 c = hd_v3(0, 0, 2);    /* centre of the lamp */
    hd_vec3 v = hd_vsub(c, p);
    *dist = hd_vlen(v);
    *l = hd_vscale(v, 1 / *dist);
    *om = 0.04 / (*dist * *dist);
    *target = hd_tscene_light(g->ts, 0);
    return 1;
}

static double cb_eval(void *ctx, const hd_scatter *sc, int k, int target, hd_vec3 l, double om, hd_rng *rng, double *wl)
{
    (void)k; (void)target; (void)rng;
    log_t *g = ctx;
    mark(g, 'E');
    g->wl_seen = *wl;              /* the loop passes 1 unless eval changes it */
    if (g->zero_eval) return 0;
    return hd_scatter_bsdf_direct(sc, l, om, 1, 1, l, 0, NULL, NULL);
}

static void cb_add(void *ctx, int k, int target, hd_vec3 l, double fc, double om, double wl, const double tr[3],
                   hd_rng *rng)
{
    (void)k; (void)target; (void)l; (void)om; (void)wl; (void)rng;
    log_t *g = ctx;
    mark(g, 'A');
    g->fc = fc;
    memcpy(g->tr, tr, sizeof g->tr);
}

static void cb_cont(void *ctx, hd_vec3 org, hd_vec3 d, double wt, double pdf, hd_rng *rng)
{
    (void)rng;
    log_t *g = ctx;
    mark(g, 'C');
    g->corg = org;
    g->cdir = d;
    g->cwt = wt;
    g->cpdf = pdf;
}

static hd_tscene *load(hd_scene *sc, const char *name, const char *reals)
{
    char dir[512], xml[600], path[600];
    snprintf(dir, sizeof dir, "%s/test_shade_bsdf", hd_test_tmpdir());
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

static int hit_pane(const hd_tscene *ts, hd_scatter *s)
{
    hd_hit h;
    hd_vec3 dir = hd_v3(0, 0, 1);
    if (!hd_tscene_intersect(ts, hd_v3(0.3, 0.2, 0), dir, 0, 0, &h)) return 0;
    hd_scatter_at(ts, &h, dir, 0, s);
    return s->kind == HD_SC_BSDF;
}

static void test_loop(void)
{
    hd_scene sc;
    hd_tscene *ts = load(&sc, "plain.rad", "0");
    REQUIRE(ts);
    hd_scatter s;
    REQUIRE(hit_pane(ts, &s));
    /* st < 0: every side of the data is sampled (no specular threshold) */
    hd_shade_bsdf_ops ops = {cb_lambert, 1, cb_sample, cb_eval, 0, cb_add, cb_cont, -1};
    log_t g;
    memset(&g, 0, sizeof g);
    g.ts = ts;
    g.skip_k = -1;
    hd_rng rng;
    hd_rng_init(&rng, 3, 0);
    hd_shade_bsdf(ts, &s, &rng, &ops, &g);
    /* no extra Lambertian reals: source (sample, eval, add), then the continuation */
    CHECK_STR(g.seq, "SEAC");
    CHECK(g.wl_seen == 1);
    /* Lambertian transmission tau/pi times the cosine towards the lamp centre */
    CHECK_REL(g.fc, 0.6 / HD_PI / sqrt(1 + 0.3 * 0.3 + 0.2 * 0.2), 0.02);
    CHECK(g.tr[0] == 1 && g.tr[1] == 1 && g.tr[2] == 1);   /* unblocked: the shadow ray left from above the pane */
    /* the data only transmit: the continuation goes up, from the transmitted
     * side's origin p + 0.1 (thickness proxy) */
    CHECK(g.cdir.z > 0);
    CHECK_NEAR(g.corg.z, 1.1, 1e-9);
    CHECK_NEAR(g.corg.x, 0.3, 1e-9);
    CHECK(g.cwt > 0 && g.cpdf > 0);
    CHECK_NEAR(g.cwt, 0.6, 0.02);       /* Lambertian: f·|cos|/pdf = tau */

    /* a refused source is neither evaluated nor added; a zero f is not added */
    memset(&g, 0, sizeof g);
    g.ts = ts;
    g.skip_k = 0;
    hd_shade_bsdf(ts, &s, &rng, &ops, &g);
    CHECK_STR(g.seq, "SC");
    memset(&g, 0, sizeof g);
    g.ts = ts;
    g.skip_k = -1;
    g.zero_eval = 1;
    hd_shade_bsdf(ts, &s, &rng, &ops, &g);
    CHECK_STR(g.seq, "SEC");

    /* the loop itself draws exactly three uniforms (the continuation) when
     * the callbacks draw none */
    ops.nsources = 0;
    hd_rng a, b;
    hd_rng_init(&a, 11, 5);
    b = a;
    memset(&g, 0, sizeof g);
    g.ts = ts;
    hd_shade_bsdf(ts, &s, &a, &ops, &g);
    CHECK_STR(g.seq, "C");
    for (int i = 0; i < 3; i++) hd_rng_uniform(&b);
    CHECK(hd_rng_uniform(&a) == hd_rng_uniform(&b));
    hd_tscene_free(ts);
    hd_scene_free(&sc);
}

static void test_lambert_first(void)
{
    hd_scene sc;
    hd_tscene *ts = load(&sc, "extra.rad", "9 .1 .1 .1 .1 .1 .1 .1 .1 .1");
    REQUIRE(ts);
    hd_scatter s;
    REQUIRE(hit_pane(ts, &s));
    hd_shade_bsdf_ops ops = {cb_lambert, 2, cb_sample, cb_eval, 0, cb_add, cb_cont, -1};
    log_t g;
    memset(&g, 0, sizeof g);
    g.ts = ts;
    g.skip_k = 1;
    hd_rng rng;
    hd_rng_init(&rng, 3, 1);
    hd_shade_bsdf(ts, &s, &rng, &ops, &g);
    CHECK_STR(g.seq, "LSEASC");      /* Lambertian parts, the two sources in order, the continuation */
    CHECK_NEAR(g.ramb[0], 0.1, 1e-12);   /* st < 0: the data is sampled, only the reals are diffuse */
    CHECK_NEAR(g.tamb[0], 0.1, 1e-12);
    hd_tscene_free(ts);
    hd_scene_free(&sc);
}

/* Radiance's specular threshold (m_bsdf.c): the Klems data here are all
 * Lambertian (the split leaves no directional part, b = 0 <= st), so the
 * transmission is lit as a diffuse surface through lambert() (0.6 plus the
 * extra real 0.1) and not sampled; the reflection side has no data (its
 * extra real only).  Direct sources still see the data. */
static void test_threshold(void)
{
    hd_scene sc;
    hd_tscene *ts = load(&sc, "thr.rad", "9 .1 .1 .1 .1 .1 .1 .1 .1 .1");
    REQUIRE(ts);
    hd_scatter s;
    REQUIRE(hit_pane(ts, &s));
    double ra, ta;
    CHECK(hd_scatter_bsdf_split(&s, NULL, 0.15, &ra, &ta) == HD_BSDF_ALL);
    CHECK_NEAR(ta, 0.6, 0.01);
    CHECK_NEAR(ra, 0, 1e-12);
    hd_shade_bsdf_ops ops = {cb_lambert, 1, cb_sample, cb_eval, 0, cb_add, cb_cont, 0.15};
    log_t g;
    memset(&g, 0, sizeof g);
    g.ts = ts;
    g.skip_k = -1;
    hd_rng rng;
    hd_rng_init(&rng, 3, 2);
    hd_shade_bsdf(ts, &s, &rng, &ops, &g);
    CHECK_STR(g.seq, "LSEA");        /* no continuation */
    CHECK_NEAR(g.tamb[0], 0.7, 0.01);
    CHECK_NEAR(g.ramb[0], 0.1, 1e-12);
    CHECK_REL(g.fc, 0.6 / HD_PI / sqrt(1 + 0.3 * 0.3 + 0.2 * 0.2), 0.02);   /* the source sees the data */
    /* without the threshold the same hit is sampled */
    CHECK(hd_scatter_bsdf_split(&s, NULL, -1, &ra, &ta) == 0 && ra == 0 && ta == 0);
    hd_tscene_free(ts);
    hd_scene_free(&sc);
}

int main(void)
{
    RUN(test_loop);
    RUN(test_lambert_first);
    RUN(test_threshold);
    return hd_test_done();
}

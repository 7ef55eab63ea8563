/* Unit tests: patterns, textures and mixtures with function files
 * (material_cal.c): data interpolation and extrapolation, the noise
 * functions, the ray variables in a transformed frame, normal perturbation,
 * mixtures, evaluation from several threads. */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "hd_test.h"
#include "heliodon/material.h"

static char dir[4096];

static const char *put(const char *name, const char *text)
{
    static char path[8][4200];
    static int k;
    char *p = path[k++ & 7];
    snprintf(p, 4200, "%s/%s", dir, name);
    FILE *f = fopen(p, "w");
    if (f) { fputs(text, f); fclose(f); }
    return p;
}

/* one node of `type` with strings s (count ns) and reals r, evaluated at (p, dir, n) */
static int eval1(struct hd_modset *ms, const char *type, char **s, int ns, const double *r, int nr,
                 hd_modray ray, double pcol[3], hd_vec3 *pert)
{
    struct hd_modnode *nd;
    const struct hd_modchain *ch;
    if (hd_modset_node(ms, type, s, ns, r, nr, "test", &nd) || hd_modset_chain(ms, &nd, 1, &ch)) return 0;
    pcol[0] = pcol[1] = pcol[2] = 1;
    *pert = hd_v3(0, 0, 0);
    hd_modchain_eval(ch, &ray, pcol, pert, NULL, NULL);
    return 1;
}

static hd_modray at(double x, double y, double z)
{
    hd_modray r = {hd_v3(0, 0, -1), hd_v3(x, y, z), hd_v3(0, 0, 1), 1, NULL, 0};
    return r;
}

static void test_data_interpolation(void)
{
    /* values 0 and 1 at x = 0 and 1: linear inside, linear up to one
     * division outside, then 1/(distance) tapering (Radiance's rule):
     * at x = 3.5 (2.5 divisions beyond the first point): c0 = 1/(-1 - 3.5),
     * c1 = -2 c0, value c1 = 0.4444 */
    const char *dat = put("ramp.dat", "1\n0 1 2\n0 1\n");
    const char *cal = put("d.cal", "{ nothing }\nid(v) = v;\n");
    struct hd_modset *ms = hd_modset_new();
    REQUIRE(ms);
    char *s[4] = {"id", (char *)dat, (char *)cal, "Px"};
    /* x = -2.5: x < i - 1: c1 = 1/(x - i) = -0.4, c0 = -2 c1: value c1 * 1 = -0.4 */
    double xs[4] = {.25, 1.5, 3.5, -2.5}, want[4] = {.25, 1.5, 2.0 / 4.5, -0.4};
    for (int k = 0; k < 4; k++) {
        double pc[3];
        hd_vec3 pt;
        REQUIRE(eval1(ms, "brightdata", s, 4, NULL, 0, at(xs[k], 0, 0), pc, &pt));
        CHECK_NEAR(pc[0], want[k], 1e-12);
        CHECK(pc[0] == pc[1] && pc[1] == pc[2]);
    }
    /* 2-D data, irregular points along y: bilinear */
    const char *d2 = put("grid.dat", "2\n0 1 2\n0 0 3 0 .2 1\n0 1 2\n10 11 12\n");
    char *s2[5] = {"id", (char *)d2, (char *)cal, "Px", "Py"};
    double pc[3];
    hd_vec3 pt;
    REQUIRE(eval1(ms, "brightdata", s2, 5, NULL, 0, at(.5, .6, 0), pc, &pt));
    /* x = .5: halfway between rows (0 1 2) and (10 11 12); y = .6 halfway between .2 and 1 */
    CHECK_NEAR(pc[0], .5 * (1.5 + 11.5), 1e-12);
    /* a missing data file is refused, naming it */
    char *s3[4] = {"id", "no_such.dat", (char *)cal, "Px"};
    struct hd_modnode *nd;
    CHECK(hd_modset_node(ms, "brightdata", s3, 4, NULL, 0, "test", &nd) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "no_such.dat");
    hd_modset_free(ms);
}

static void test_noise(void)
{
    struct hd_modset *ms = hd_modset_new();
    REQUIRE(ms);
    double pc[3];
    hd_vec3 pt;
    /* Perlin noise is 0 at the lattice points; its x derivative matches a difference */
    char *s[2] = {"noise3(Px, Py, Pz)", "."};
    REQUIRE(eval1(ms, "brightfunc", s, 2, NULL, 0, at(3, -2, 7), pc, &pt));
    CHECK_NEAR(pc[0], 0, 1e-15);
    char *sa[2] = {"noise3(Px, Py, Pz)", "."}, *sd[2] = {"noise3x(Px, Py, Pz)", "."};
    double a, b, d;
    REQUIRE(eval1(ms, "brightfunc", sa, 2, NULL, 0, at(.3, .4, .55), pc, &pt));
    a = pc[0];
    REQUIRE(eval1(ms, "brightfunc", sa, 2, NULL, 0, at(.3 - 5e-4, .4, .55), pc, &pt));
    b = pc[0];
    REQUIRE(eval1(ms, "brightfunc", sd, 2, NULL, 0, at(.3, .4, .55), pc, &pt));
    d = pc[0];
    CHECK_NEAR(d, (a - b) / 5e-4, 1e-9);
    CHECK(a != 0);
    /* fractal noise: bounded, varies, and the same at the same point */
    char *sf[2] = {"fnoise3(Px, Py, Pz)", "."};
    double lo = 1e9, hi = -1e9, first = 0;
    for (int k = 0; k < 200; k++) {
        REQUIRE(eval1(ms, "brightfunc", sf, 2, NULL, 0, at(k * .137, k * .071, .5), pc, &pt));
        if (!k) first = pc[0];
        lo = pc[0] < lo ? pc[0] : lo;
        hi = pc[0] > hi ? pc[0] : hi;
    }
    CHECK(lo >= -2 && hi <= 2 && hi - lo > .3);
    REQUIRE(eval1(ms, "brightfunc", sf, 2, NULL, 0, at(0, 0, .5), pc, &pt));
    CHECK(pc[0] == first);
    hd_modset_free(ms);
}

static void test_frame_and_texture(void)
{
    /* -t 1 0 0 -rz 90 -s 2: the pattern frame's point is the inverse
     * transform of the world point; S = 1/2; a texture's perturbation
     * comes back rotated (not scaled) */
    struct hd_modset *ms = hd_modset_new();
    REQUIRE(ms);
    char *s[10] = {"Px", "Py", "S", ".", "-t", "1", "0", "0", "-rz", "90"};
    double pc[3];
    hd_vec3 pt;
    /* colorfunc (Px, Py, S) after -t 1 0 0 -rz 90 (world = Rz(q + t)): world
     * (1, 2, 0) is q = Rz^-1 (1, 2, 0) - t = (2, -1, 0) - (1, 0, 0) */
    REQUIRE(eval1(ms, "colorfunc", s, 10, NULL, 0, at(1, 2, 0), pc, &pt));
    CHECK_NEAR(pc[0], 1, 1e-12);
    CHECK_NEAR(pc[1], -1, 1e-12);
    CHECK_NEAR(pc[2], 1, 1e-12);
    char *s2[8] = {"Px", "Dx", "S", ".", "-s", "2", "-rz", "90"};
    REQUIRE(eval1(ms, "colorfunc", s2, 8, NULL, 0, at(0, 4, 0), pc, &pt));
    CHECK_NEAR(pc[0], 2, 1e-12);     /* (0, 4) rotated by -90, halved: (2, 0) */
    CHECK_NEAR(pc[1], 0, 1e-12);     /* the direction (0, 0, -1) keeps Dx = 0 */
    CHECK_NEAR(pc[2], .5, 1e-12);
    char *t[6] = {"1", "0", "0", ".", "-rz", "90"};
    REQUIRE(eval1(ms, "texfunc", t, 6, NULL, 0, at(0, 0, 0), pc, &pt));
    CHECK_NEAR(pt.x, 0, 1e-12);
    CHECK_NEAR(pt.y, 1, 1e-12);
    CHECK(pc[0] == 1 && pc[1] == 1 && pc[2] == 1);
    /* A1.. and arg(n) are the modifier's own reals */
    double r[3] = {5, 6, 7};
    char *sa[4] = {"A1", "arg(3)", "arg(0)", "."};
    REQUIRE(eval1(ms, "colorfunc", sa, 4, r, 3, at(0, 0, 0), pc, &pt));
    CHECK(pc[0] == 5 && pc[1] == 7 && pc[2] == 3);
    hd_modset_free(ms);
}

static void test_perturb_normal(void)
{
    hd_vec3 n = hd_v3(0, 0, 1), d = hd_v3(0, 0, -1);
    hd_vec3 m = hd_perturb_normal(n, hd_v3(1, 0, 0), d);
    CHECK_NEAR(m.x, sqrt(.5), 1e-15);
    CHECK_NEAR(m.z, sqrt(.5), 1e-15);
    /* a perturbation that would turn the normal away from the viewer is mirrored back */
    hd_vec3 dd = hd_vnorm(hd_v3(1, 0, -1));
    m = hd_perturb_normal(n, hd_v3(3, 0, 0), dd);
    CHECK(-hd_vdot(m, dd) > 0);
    CHECK_NEAR(hd_vlen(m), 1, 1e-12);
    /* no change without perturbation */
    m = hd_perturb_normal(n, hd_v3(0, 0, 0), d);
    CHECK(m.x == 0 && m.y == 0 && m.z == 1);
}

static void test_mixture(void)
{
    /* a mixfunc of two brightfuncs: coef clipped to [0, 1]; a mixfunc of two
     * plastics: the colours blended (materials through hd_modchain_eval) */
    struct hd_modset *ms = hd_modset_new();
    REQUIRE(ms);
    struct hd_modnode *a, *b, *mx;
    const struct hd_modchain *ca, *cb, *cm;
    char *sa[2] = {".8", "."}, *sb[2] = {".2", "."}, *sm[4] = {"fa", "fb", "Px", "."};
    REQUIRE(!hd_modset_node(ms, "brightfunc", sa, 2, NULL, 0, "a", &a));
    REQUIRE(!hd_modset_node(ms, "brightfunc", sb, 2, NULL, 0, "b", &b));
    REQUIRE(!hd_modset_node(ms, "mixfunc", sm, 4, NULL, 0, "m", &mx));
    REQUIRE(!hd_modset_chain(ms, &a, 1, &ca) && !hd_modset_chain(ms, &b, 1, &cb));
    REQUIRE(!hd_modnode_set_side(mx, 0, ca, NULL) && !hd_modnode_set_side(mx, 1, cb, NULL));
    REQUIRE(!hd_modset_chain(ms, &mx, 1, &cm));
    double xs[3] = {-1, .25, 2}, want[3] = {.2, .25 * .8 + .75 * .2, .8};
    for (int k = 0; k < 3; k++) {
        double pc[3] = {1, 1, 1};
        hd_vec3 pt = {0, 0, 0};
        hd_modray ray = at(xs[k], 0, 0);
        hd_modchain_eval(cm, &ray, pc, &pt, NULL, NULL);
        CHECK_NEAR(pc[0], want[k], 1e-15);
    }
    hd_tmat red, blue, base, tmp;
    hd_tmat_init(&red, HD_MAT_PLASTIC, "red");
    hd_tmat_init(&blue, HD_MAT_PLASTIC, "blue");
    red.color[0] = .7; red.color[1] = .1; red.color[2] = .1;
    blue.color[0] = .1; blue.color[1] = .1; blue.color[2] = .7;
    struct hd_modnode *mm;
    const struct hd_modchain *cmm;
    REQUIRE(!hd_modset_node(ms, "mixfunc", sm, 4, NULL, 0, "mm", &mm));
    REQUIRE(!hd_modnode_set_side(mm, 0, NULL, &red) && !hd_modnode_set_side(mm, 1, NULL, &blue));
    REQUIRE(!hd_modset_chain(ms, &mm, 1, &cmm));
    base = red;
    base.chain = cmm;
    hd_modray ray = at(.25, 0, 0);
    const hd_tmat *got = hd_tmat_modify(&base, &ray, &tmp, NULL);
    CHECK(got == &tmp && got->type == HD_MAT_PLASTIC && !got->chain);
    CHECK_NEAR(got->color[0], .25 * .7 + .75 * .1, 1e-15);
    CHECK_NEAR(got->color[2], .25 * .1 + .75 * .7, 1e-15);
    hd_modset_free(ms);
}

/* the same values from several threads at once */
typedef struct job { const struct hd_modchain *c; double sum; } job;
static void *worker(void *arg)
{
    job *j = arg;
    for (int k = 0; k < 20000; k++) {
        double pc[3] = {1, 1, 1};
        hd_vec3 pt = {0, 0, 0};
        hd_modray ray = at(k * 1e-3, k * 7e-4, .5);
        hd_modchain_eval(j->c, &ray, pc, &pt, NULL, NULL);
        j->sum += pc[0] * (k + 1);
    }
    return NULL;
}

static void test_threads(void)
{
    struct hd_modset *ms = hd_modset_new();
    REQUIRE(ms);
    const char *cal = put("t.cal", "v = sin(Px*3) + q;\nq = Py*Py + A1;\n");
    struct hd_modnode *nd;
    const struct hd_modchain *c;
    char *s[2] = {"v", (char *)cal};
    double r[1] = {.5};
    REQUIRE(!hd_modset_node(ms, "brightfunc", s, 2, r, 1, "t", &nd) && !hd_modset_chain(ms, &nd, 1, &c));
    job j0 = {c, 0};
    worker(&j0);
    job jobs[4];
    pthread_t th[4];
    for (int i = 0; i < 4; i++) { jobs[i].c = c; jobs[i].sum = 0; pthread_create(&th[i], NULL, worker, &jobs[i]); }
    for (int i = 0; i < 4; i++) pthread_join(th[i], NULL);
    for (int i = 0; i < 4; i++) CHECK(jobs[i].sum == j0.sum);
    hd_modset_free(ms);
}

int main(void)
{
    snprintf(dir, sizeof dir, "%s", hd_test_tmpdir());
    RUN(test_data_interpolation);
    RUN(test_noise);
    RUN(test_frame_and_texture);
    RUN(test_perturb_normal);
    RUN(test_mixture);
    RUN(test_threads);
    return hd_test_done();
}

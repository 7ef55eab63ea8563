/* Unit tests: glare evaluation (analytic cases, the spec's worked example,
 * Radiance evalglare reference outputs, bad inputs, annual statistics). */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hd_test.h"
#include "heliodon/glare.h"
#include "heliodon/header.h"
#include "heliodon/picture.h"
#include "heliodon/view.h"

static hd_glare_view fisheye(char type)
{
    hd_glare_view v;
    hd_view_default(&v);
    char buf[64];
    snprintf(buf, sizeof buf, "-vt%c -vh 180 -vv 180", type);
    hd_view_parse_line(&v, buf);
    hd_view_setup(&v);
    return v;
}

/* the view ray through image location (x, y) and whether it exists */
static int view_dir(const hd_view *v, double x, double y, hd_vec3 *d)
{
    hd_vec3 o;
    return hd_view_ray(v, x, y, &o, d) >= 0;
}

/* Uniform field: E_v = pi * L.  The pixels straddling the 90-degree rim are
 * counted whole (as evalglare does) or not at all, so the error is of the
 * order of half a rim ring: ~ 1/xres relative at most; measured below. */
static void test_uniform_ev(void)
{
    for (int t = 0; t < 2; t++) {
        char type = t ? 'h' : 'a';
        int res[] = {128, 256, 512};
        for (int k = 0; k < 3; k++) {
            int n = res[k];
            hd_glare_view v = fisheye(type);
            hd_glare_geom *g;
            REQUIRE(hd_glare_geom_new(&g, &v, n, n) == HD_OK);
            float *lum = malloc(sizeof(float) * n * n);
            for (int i = 0; i < n * n; i++) lum[i] = 1000;
            double ev = hd_glare_ev_lum(g, lum);
            double om = 0;
            for (int r = 0; r < n; r++)
                for (int x = 0; x < n; x++) om += hd_glare_geom_omega(g, x, r);
            /* tolerance: 2/n relative for E_v (rim discretisation), 4/n for
             * the total solid angle (rim pixels carry up to a full pixel) */
            CHECK_REL(ev, HD_PI * 1000, 2.0 / n);
            printf("  -vt%c %dx%d: E_v/(1000 pi) - 1 = %+.2e, sum omega/(2 pi) - 1 = %+.2e\n", type, n, n,
                   ev / (HD_PI * 1000) - 1, om / (2 * HD_PI) - 1);
            if (type == 'a') CHECK_REL(om, 2 * HD_PI, 4.0 / n);
            /* -vth compresses the rim: the half-pixel ring left out there
             * holds ~2 pi sqrt(2/n) sr (little illuminance: cos ~ 0) */
            else CHECK_REL(om, 2 * HD_PI, sqrt(2.0 / n));
            if (n == 256 && type == 'a') CHECK_REL(ev, HD_PI * 1000, 1e-3);
            hd_glare_opts o;
            hd_glare_opts_default(&o);
            hd_glare_result res2;
            REQUIRE(hd_glare_eval_lum(g, lum, &o, &res2) == HD_OK);
            CHECK(res2.nsources == 0);
            CHECK_NEAR(res2.dgp, o.c1 * ev + o.c3, 1e-12);
            CHECK_NEAR(res2.av_lum, 1000, 1e-3);
            CHECK_NEAR(res2.lum_backg, ev / HD_PI, 1e-9);
            hd_glare_result_free(&res2);
            free(lum);
            hd_glare_geom_free(g);
        }
    }
}

/* Centre pixel solid angle of an angular fisheye: (pi/n)^2 sr. */
static void test_pixel_solid_angle(void)
{
    int n = 256;
    hd_glare_view v = fisheye('a');
    hd_glare_geom *g;
    REQUIRE(hd_glare_geom_new(&g, &v, n, n) == HD_OK);
    double w = HD_PI / n;
    CHECK_REL(hd_glare_geom_omega(g, n / 2, n / 2), w * w, 1e-4);
    CHECK(hd_glare_geom_omega(g, 0, 0) == 0);   /* corner: outside 180 degrees */
    CHECK(hd_glare_geom_cos(g, 2, 2) == 0);
    hd_glare_geom_free(g);
}

/* The spec's verified example, at the formula level: one source of
 * 5000 cd/m2, 0.4765 sr, P = 1.0023; E_v = 4971.7, L_b = 852.8. */
static void test_spec_example_formulas(void)
{
    hd_glare_opts o;
    hd_glare_opts_default(&o);
    hd_glare_source s;
    memset(&s, 0, sizeof s);
    s.lum = 5000;
    s.omega = 0.4765;
    s.posidx = 1.0023;
    s.sigma = 1;
    s.dir[1] = 1;
    hd_glare_result r;
    memset(&r, 0, sizeof r);
    r.ev = 4971.7;
    r.lum_backg = 852.8;
    r.av_lum = 1000;
    r.ev_dir = 4971.7 - HD_PI * 852.8;
    r.nsources = 1;
    r.sources = &s;
    hd_glare_metrics(&r, &o);
    /* the spec gives 5-6 digits, computed from rounded inputs */
    CHECK_NEAR(r.dgp, 0.48667, 5e-5);
    CHECK_NEAR(r.dgi, 22.996, 5e-3);
    CHECK_NEAR(r.ugr, 28.331, 5e-3);
    CHECK_NEAR(hd_glare_dgp(4971.7, &s, 1, &o), 0.48667, 5e-5);
    /* no source: c1 E_v + c3 */
    CHECK_NEAR(hd_glare_dgp(2000, &s, 0, &o), 5.87e-5 * 2000 + 0.159, 1e-12);
    /* low-light correction only when asked */
    o.lowlight = 1;
    double e = exp(0.024 * 300 - 4);
    CHECK_NEAR(hd_glare_dgp(300, &s, 0, &o), (5.87e-5 * 300 + 0.159) * e / (1 + e), 1e-12);
}

/* The same example as a picture: a 5000 cd/m2 disk of 0.4765 sr centred
 * on the view direction in a 1000 cd/m2 field, 512 x 512 -vta.  Analytic
 * (continuous) values: E_v = 1000 pi + 4000 pi sin^2(a) = 4975.3,
 * L_b = 1000 sin... = 854.1; the spec's numbers (4971.7, 852.8) come from a
 * discretised image; tolerances cover the disk-edge discretisation. */
static void test_spec_example_image(void)
{
    int n = 512;
    double cosa = 1 - 0.4765 / (2 * HD_PI);
    hd_glare_view v = fisheye('a');
    hd_glare_geom *g;
    REQUIRE(hd_glare_geom_new(&g, &v, n, n) == HD_OK);
    float *rgb = malloc(sizeof(float) * 3 * n * n);
    for (int row = 0; row < n; row++)
        for (int x = 0; x < n; x++) {
            hd_vec3 d;
            float L = 1000;
            if (view_dir(&v, (x + 0.5) / n, (n - 1 - row + 0.5) / n, &d) && d.y >= cosa) L = 5000;
            for (int c = 0; c < 3; c++) rgb[3 * (row * n + x) + c] = L / 179.0f;
        }
    hd_glare_opts o;
    hd_glare_opts_default(&o);
    hd_glare_result r;
    REQUIRE(hd_glare_eval_geom(g, rgb, &o, &r) == HD_OK);
    double sa2 = 1 - cosa * cosa;
    CHECK_REL(r.ev, 1000 * HD_PI + 4000 * HD_PI * sa2, 2e-3);
    CHECK_NEAR(r.ev, 4971.7, 10);
    REQUIRE(r.nsources == 1);
    CHECK_REL(r.sources[0].omega, 0.4765, 5e-3);
    CHECK_NEAR(r.sources[0].lum, 5000, 0.5);
    CHECK_NEAR(r.sources[0].posidx, 1.0023, 5e-3);
    CHECK_NEAR(r.lum_backg, 852.8, 3);
    CHECK_NEAR(r.dgp, 0.48667, 2e-3);
    CHECK_NEAR(r.dgi, 22.996, 0.1);
    CHECK_NEAR(r.ugr, 28.331, 0.1);
    hd_glare_result_free(&r);
    free(rgb);
    hd_glare_geom_free(g);
}

/* The same scene seen through -vta and -vth gives the same glare within
 * discretisation: a 3000 cd/m2 patch (window-like, off-axis) in 400 cd/m2. */
static void test_angular_vs_hemispherical(void)
{
    int n = 512;
    double res[2][4];
    for (int t = 0; t < 2; t++) {
        hd_glare_view v = fisheye(t ? 'h' : 'a');
        hd_glare_geom *g;
        REQUIRE(hd_glare_geom_new(&g, &v, n, n) == HD_OK);
        float *lum = malloc(sizeof(float) * n * n);
        for (int row = 0; row < n; row++)
            for (int x = 0; x < n; x++) {
                hd_vec3 d;
                float L = 400;
                if (view_dir(&v, (x + 0.5) / n, (n - 1 - row + 0.5) / n, &d)) {
                    double az = atan2(d.x, d.y), el = asin(d.z);
                    if (az > 0.3 && az < 0.9 && el > -0.2 && el < 0.5) L = 3000;
                }
                lum[row * n + x] = L;
            }
        hd_glare_opts o;
        hd_glare_opts_default(&o);
        hd_glare_result r;
        REQUIRE(hd_glare_eval_lum(g, lum, &o, &r) == HD_OK);
        REQUIRE(r.nsources == 1);
        res[t][0] = r.ev;
        res[t][1] = r.dgp;
        res[t][2] = r.dgi;
        res[t][3] = r.sources[0].omega;
        hd_glare_result_free(&r);
        free(lum);
        hd_glare_geom_free(g);
    }
    CHECK_REL(res[1][0], res[0][0], 2e-3);
    CHECK_NEAR(res[1][1], res[0][1], 2e-3);
    /* the source direction is that of the mean *image* position (as
     * evalglare), which depends on the projection: P and DGI differ a
     * little (measured 0.19) */
    CHECK_NEAR(res[1][2], res[0][2], 0.3);
    CHECK_REL(res[1][3], res[0][3], 5e-3);
}

/* Position index against values printed by Radiance's evalglare (office
 * reference, source table: dir -> Posindx). */
static void test_posidx(void)
{
    double d0[3] = {0, 1, 0};
    CHECK_NEAR(hd_glare_posidx(d0), 1.0, 1e-12);
    double guth[3] = {0.658586, 0.588544, 0.468913};   /* above: Guth */
    CHECK_NEAR(hd_glare_posidx(guth), 5.688207, 2e-5);
    double iwata[3] = {0.977293, 0.132945, -0.164998}; /* below: Iwata */
    CHECK_NEAR(hd_glare_posidx(iwata), 7.101942, 2e-5);
    double cap[3] = {0.852374, 0.137103, 0.504639};    /* capped */
    CHECK_NEAR(hd_glare_posidx(cap), 16.0, 1e-12);
    double box[3] = {-0.042820, 0.990790, 0.128459};
    CHECK_NEAR(hd_glare_posidx(box), 1.275210, 2e-5);
}

/* Two sources 0.15 rad apart merge with -r 0.4 (cone half-angle 0.2) but
 * stay apart with the default -r 0.2; a peak inside a source is split off. */
static void test_detection(void)
{
    int n = 256;
    hd_glare_view v = fisheye('a');
    hd_glare_geom *g;
    REQUIRE(hd_glare_geom_new(&g, &v, n, n) == HD_OK);
    float *lum = malloc(sizeof(float) * n * n);
    for (int row = 0; row < n; row++)
        for (int x = 0; x < n; x++) {
            hd_vec3 d;
            lum[row * n + x] = 500;
            if (!view_dir(&v, (x + 0.5) / n, (n - 1 - row + 0.5) / n, &d)) continue;
            double az = atan2(d.x, d.y), el = asin(d.z);
            if (fabs(el) < 0.05 && fabs(az - 0.3) < 0.05) lum[row * n + x] = 4000;
            if (fabs(el) < 0.05 && fabs(az - 0.55) < 0.05) lum[row * n + x] = 4000;
            if (fabs(el) < 0.01 && fabs(az - 0.3) < 0.01) lum[row * n + x] = 80000;
        }
    hd_glare_opts o;
    hd_glare_opts_default(&o);
    o.peak_extract = 0;
    hd_glare_result r;
    REQUIRE(hd_glare_eval_lum(g, lum, &o, &r) == HD_OK);
    CHECK(r.nsources == 2);
    hd_glare_result_free(&r);
    o.search_radius = 0.4;
    REQUIRE(hd_glare_eval_lum(g, lum, &o, &r) == HD_OK);
    CHECK(r.nsources == 1);
    hd_glare_result_free(&r);
    o.search_radius = 0.2;
    o.peak_extract = 1;
    REQUIRE(hd_glare_eval_lum(g, lum, &o, &r) == HD_OK);
    CHECK(r.nsources == 3);
    int peaks = 0;
    for (int i = 0; i < r.nsources; i++)
        if (r.sources[i].lum >= 50000) peaks++;
    CHECK(peaks == 1);
    /* threshold as a factor of the mean luminance */
    hd_glare_result_free(&r);
    o.threshold = 5;
    REQUIRE(hd_glare_eval_lum(g, lum, &o, &r) == HD_OK);
    CHECK_NEAR(r.threshold, 5 * r.av_lum, 1e-9);
    hd_glare_result_free(&r);
    /* task area at the image centre (background only): threshold 5 x 500 */
    o.task = 1;
    o.task_x = n / 2;
    o.task_y = n / 2;
    o.task_angle = 0.2;
    REQUIRE(hd_glare_eval_lum(g, lum, &o, &r) == HD_OK);
    CHECK_NEAR(r.task_lum, 500, 1e-3);
    CHECK_NEAR(r.threshold, 2500, 1e-2);
    CHECK(r.nsources == 3);
    hd_glare_result_free(&r);
    o.task_x = 0;
    o.task_y = 1;   /* corner: outside the field */
    CHECK(hd_glare_eval_lum(g, lum, &o, &r) == HD_ERR_RANGE);
    CHECK_CONTAINS(hd_errmsg(), "outside the fisheye");
    free(lum);
    hd_glare_geom_free(g);
}

static void test_bad_views(void)
{
    hd_glare_view v;
    hd_view_default(&v);   /* -vtv */
    hd_glare_geom *g = NULL;
    CHECK(hd_glare_geom_new(&g, &v, 64, 64) == HD_ERR_UNSUPPORTED);
    CHECK_CONTAINS(hd_errmsg(), "not a fisheye");
    CHECK(g == NULL);
    v = fisheye('a');
    v.vd = hd_v3(0, 0, 1);       /* parallel to up */
    CHECK(hd_glare_geom_new(&g, &v, 64, 64) == HD_ERR_RANGE);
    CHECK_CONTAINS(hd_errmsg(), "-vu");
    v = fisheye('a');
    CHECK(hd_glare_geom_new(&g, &v, 1000000, 1000000) == HD_ERR_RANGE);
    CHECK_CONTAINS(hd_errmsg(), "out of range");
    CHECK(hd_view_parse_line(&v, "-vta -vh") < 0);
    CHECK_CONTAINS(hd_errmsg(), "-vh");
    CHECK(hd_view_parse_line(&v, "-vtq") < 0);
    CHECK(hd_view_parse_line(&v, "-vp 1 2 x") < 0);
    CHECK_CONTAINS(hd_errmsg(), "'x'");
}

static void test_view_header(void)
{
    hd_header h;
    hd_header_init(&h);
    hd_header_append(&h, "VIEW= -vtv -vp 1 2 3 -vd 0 -1 0 -vh 60");
    hd_header_append(&h, "VIEW= -vta -vh 180 -vv 180");
    hd_glare_view v;
    hd_view_default(&v);
    int found = 0;
    CHECK(hd_view_from_header(&v, &h, &found) == HD_OK);
    CHECK(found == 2);
    CHECK(v.type == 'a');
    CHECK_NEAR(v.vp.z, 3, 0);
    CHECK_NEAR(v.vd.y, -1, 0);
    CHECK_NEAR(v.vh, 180, 0);
    hd_header_free(&h);
}

/* The glare geometry's pixel directions are the view's rays (view.h) for
 * both fisheye types, shifted and turned views included: the forward
 * component of each valid pixel's direction is the cosine of the ray of
 * its centre to the view direction. */
static void test_view_module_agrees(void)
{
    const char *views[] = {"-vta -vp 1 2 3 -vd 1 0.2 0 -vu 0 0 1 -vh 180 -vv 180",
                           "-vth -vd 0 -1 0.1 -vh 180 -vv 180 -vs 0.05 -vl -0.1"};
    int n = 21;
    for (int k = 0; k < 2; k++) {
        hd_view v;
        hd_view_default(&v);
        REQUIRE(hd_view_parse_line(&v, views[k]) > 0);
        REQUIRE(hd_view_setup(&v) == HD_OK);
        hd_glare_geom *g;
        REQUIRE(hd_glare_geom_new(&g, &v, n, n) == HD_OK);
        double maxerr = 0;
        int nvalid = 0;
        for (int row = 0; row < n; row++)
            for (int x = 0; x < n; x++) {
                hd_vec3 d;
                if (!view_dir(&v, (x + 0.5) / n, (n - 1 - row + 0.5) / n, &d) || hd_vdot(d, v.dir) <= 0) {
                    CHECK_NEAR(hd_glare_geom_omega(g, x, row), 0, 0);
                    continue;
                }
                nvalid++;
                double e = fabs(hd_glare_geom_cos(g, x, row) - hd_vdot(d, v.dir));
                if (e > maxerr) maxerr = e;
            }
        CHECK(nvalid > n * n / 2);
        CHECK_NEAR(maxerr, 0, 1e-9);
        hd_glare_geom_free(g);
    }
}

/* ---- Radiance references ---- */

typedef struct refsrc { double npix, x, y, L, om, P; } refsrc;

static int read_ref(const char *path, double vals[23], refsrc *src, int maxsrc, int *nsrc)
{
    FILE *f = fopen(path, "r");
    if (!f) return -1;
    char line[8192];
    int ns = 0, got = 0;
    while (fgets(line, sizeof line, f)) {
        if (!strncmp(line, "dgp,av_lum", 10)) {
            char *p = strchr(line, ':');
            for (int k = 0; k < 23 && p; k++) vals[k] = strtod(p + 1, &p);
            got = 1;
        } else if (strstr(line, "No pixels")) {
            continue;
        } else if (ns < maxsrc) {
            double i;
            if (sscanf(line, "%lf %lf %lf %lf %lf %lf %lf", &i, &src[ns].npix, &src[ns].x, &src[ns].y,
                       &src[ns].L, &src[ns].om, &src[ns].P) == 7)
                ns++;
        }
    }
    fclose(f);
    *nsrc = ns;
    return got ? 0 : -1;
}

static int compare_image(const char *hdr, const char *txt, double *ddgp, double *ddgi)
{
    double ref[23];
    refsrc rs[64];
    int nrs = 0;
    if (read_ref(txt, ref, rs, 64, &nrs)) { CHECK_MSG(0, "cannot read %s", txt); return -1; }
    hd_picture p;
    hd_picture_init(&p);
    if (hd_picture_read(hdr, &p) != HD_OK) { CHECK_MSG(0, "%s: %s", hdr, hd_errmsg()); return -1; }
    /* the references were made with -vta -vv 180 -vh 180 on the command line */
    hd_glare_view v = fisheye('a');
    float *lum;
    hd_glare_geom *g;
    hd_glare_opts o;
    hd_glare_opts_default(&o);
    o.threshold = 2000;
    hd_glare_result r;
    int ok = hd_glare_picture_lum(&p, &lum) == HD_OK && hd_glare_geom_new(&g, &v, p.xres, p.yres) == HD_OK;
    if (!ok) { CHECK_MSG(0, "%s: %s", hdr, hd_errmsg()); hd_picture_free(&p); return -1; }
    if (hd_glare_eval_lum(g, lum, &o, &r) != HD_OK) { CHECK_MSG(0, "%s", hd_errmsg()); return -1; }
    /* required by the issue: DGP within 0.005, DGI within 0.5 */
    CHECK_NEAR(r.dgp, ref[0], 0.005);
    CHECK_NEAR(r.dgi, ref[5], 0.5);
    /* tighter: what the implementation achieves (regression guard) */
    CHECK_NEAR(r.dgp, ref[0], 1e-4);
    CHECK_NEAR(r.dgi, ref[5], 0.01);
    CHECK_NEAR(r.ugr, ref[6], 0.01);
    CHECK_REL(r.av_lum, ref[1], 1e-6);
    CHECK_REL(r.ev, ref[2], 1e-6);
    CHECK_REL(r.lum_backg, ref[3], 1e-5);
    CHECK_REL(r.ev_dir, ref[4], 1e-5);
    CHECK_NEAR(r.vcp, ref[7], 0.01);
    CHECK_NEAR(r.cgi, ref[8], 0.01);
    CHECK_REL(r.lum_sources, ref[9], 1e-5);
    CHECK_REL(r.omega_sources, ref[10], 1e-5);
    CHECK_REL(r.lveil, ref[11], 1e-4);
    CHECK_REL(r.lveil_cie, ref[12], 1e-4);
    CHECK_REL(r.dgr, ref[13], 1e-4);
    CHECK_NEAR(r.ugp, ref[14], 1e-4);
    CHECK_REL(r.med_lum, ref[19], 1e-6);
    CHECK_REL(r.av_lum_pos, ref[17], 1e-6);
    CHECK_REL(r.av_lum_pos2, ref[18], 1e-6);
    CHECK_REL(r.med_lum_pos, ref[20], 1e-6);
    CHECK_REL(r.med_lum_pos2, ref[21], 1e-6);
    CHECK_MSG(r.nsources == nrs, "%s: %d sources, Radiance %d", hdr, r.nsources, nrs);
    for (int i = 0; i < nrs && i < r.nsources; i++) {
        CHECK_NEAR(r.sources[i].npix, rs[i].npix, 0);
        CHECK_REL(r.sources[i].omega, rs[i].om, 1e-6);
        CHECK_REL(r.sources[i].lum, rs[i].L, 1e-6);
        CHECK_NEAR(r.sources[i].x, rs[i].x, 1e-4);
        CHECK_NEAR(r.sources[i].y, rs[i].y, 1e-4);
        CHECK_NEAR(r.sources[i].posidx, rs[i].P, 1e-4);
    }
    *ddgp = r.dgp - ref[0];
    *ddgi = r.dgi - ref[5];
    hd_glare_result_free(&r);
    hd_glare_geom_free(g);
    free(lum);
    hd_picture_free(&p);
    return 0;
}

static int run_dir(const char *dir, const char *must_contain)
{
    DIR *d = opendir(dir);
    if (!d) return 0;
    struct dirent *e;
    int n = 0;
    while ((e = readdir(d))) {
        size_t l = strlen(e->d_name);
        if (l < 5 || strcmp(e->d_name + l - 4, ".hdr") || (must_contain && !strstr(e->d_name, must_contain)))
            continue;
        char hdr[1024], txt[1024];
        snprintf(hdr, sizeof hdr, "%s/%s", dir, e->d_name);
        snprintf(txt, sizeof txt, "%s/%.*s.evalglare.txt", dir, (int)(l - 4), e->d_name);
        FILE *f = fopen(txt, "r");
        if (!f) { CHECK_MSG(0, "%s has no evalglare reference", hdr); continue; }
        fclose(f);
        double a = 0, b = 0;
        if (compare_image(hdr, txt, &a, &b) == 0) {
            printf("  %s: dDGP %+.2e dDGI %+.2e\n", e->d_name, a, b);
            n++;
        }
    }
    closedir(d);
    return n;
}

static void test_reference_office(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no ../shared/ref (set HELIODON_REF)");
    char dir[1024];
    snprintf(dir, sizeof dir, "%s/scenes/office", ref);
    int n = run_dir(dir, NULL);
    if (n == 0) SKIP("no office images in the reference folder");
}

static void test_reference_box(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no ../shared/ref (set HELIODON_REF)");
    char dir[1024];
    snprintf(dir, sizeof dir, "%s/scenes/box", ref);
    int n = run_dir(dir, "_fish");
    if (n == 0) SKIP("no box fisheye images in the reference folder");
    CHECK(n >= 2);
}

/* evalglare -V -vf fish.vf on the A4 128x128 images (values to 0.1 lux). */
static void test_reference_ev(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no ../shared/ref");
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/box/a4_res/a4_image_ev.txt", ref);
    FILE *f = fopen(path, "r");
    if (!f) SKIP("no scenes/box/a4_res/a4_image_ev.txt");
    char vf[1024];
    snprintf(vf, sizeof vf, "%s/scenes/box/fish.vf", ref);
    FILE *fv = fopen(vf, "r");
    if (!fv) { fclose(f); SKIP("no scenes/box/fish.vf"); }
    char vtext[512] = "";
    if (!fgets(vtext, sizeof vtext, fv)) vtext[0] = 0;
    fclose(fv);
    hd_glare_view v;
    hd_view_default(&v);
    REQUIRE(hd_view_parse_line(&v, vtext) >= 0);
    char line[1024];
    int n = 0;
    while (fgets(line, sizeof line, f)) {
        char name[512];
        double ev, ml;
        if (line[0] == '#' || sscanf(line, "%511s %lf %lf", name, &ev, &ml) != 3) continue;
        char img[1024];
        snprintf(img, sizeof img, "%s/scenes/box/%s", ref, name);
        hd_picture p;
        hd_picture_init(&p);
        if (hd_picture_read(img, &p) != HD_OK) continue;
        float *lum;
        hd_glare_geom *g;
        REQUIRE(hd_glare_picture_lum(&p, &lum) == HD_OK);
        REQUIRE(hd_glare_geom_new(&g, &v, p.xres, p.yres) == HD_OK);
        CHECK_NEAR(hd_glare_ev_lum(g, lum), ev, 0.051);
        n++;
        hd_glare_geom_free(g);
        free(lum);
        hd_picture_free(&p);
    }
    fclose(f);
    if (!n) SKIP("no A4 images found");
}

/* A picture written with a VIEW= line and read back: the view comes from
 * the header and the result equals the in-memory evaluation. */
static void test_picture_roundtrip(void)
{
    int n = 64;
    hd_picture p;
    hd_picture_init(&p);
    REQUIRE(hd_picture_alloc(&p, n, n) == HD_OK);
    for (int k = 0; k < n * n; k++)
        for (int c = 0; c < 3; c++) p.pix[3 * k + c] = (k % 7 == 0 ? 30.0f : 2.0f);
    hd_header h;
    hd_header_init(&h);
    hd_header_append(&h, "VIEW= -vth -vp 0 0 0 -vd 1 0 0 -vu 0 0 1 -vh 180 -vv 180");
    char path[300];
    snprintf(path, sizeof path, "%s/glare_rt.hdr", hd_test_tmpdir());
    REQUIRE(hd_picture_save(path, &p, &h) == HD_OK);
    hd_picture q;
    hd_picture_init(&q);
    REQUIRE(hd_picture_read(path, &q) == HD_OK);
    hd_glare_view v;
    hd_view_default(&v);
    int found = 0;
    REQUIRE(hd_view_from_header(&v, &q.hdr, &found) == HD_OK);
    CHECK(found == 1 && v.type == 'h');
    float *lum;
    REQUIRE(hd_glare_picture_lum(&q, &lum) == HD_OK);
    hd_glare_geom *g;
    REQUIRE(hd_glare_geom_new(&g, &v, n, n) == HD_OK);
    hd_glare_opts o;
    hd_glare_opts_default(&o);
    hd_glare_result a, b;
    REQUIRE(hd_glare_eval_lum(g, lum, &o, &a) == HD_OK);
    REQUIRE(hd_glare_eval_geom(g, p.pix, &o, &b) == HD_OK);
    /* RGBE quantisation: 1 part in 256 at most */
    CHECK_REL(a.ev, b.ev, 1.0 / 128);
    CHECK_NEAR(a.dgp, b.dgp, 2e-3);
    CHECK(a.nsources == b.nsources);
    hd_glare_result_free(&a);
    hd_glare_result_free(&b);
    hd_glare_geom_free(g);
    free(lum);
    hd_picture_free(&p);
    hd_picture_free(&q);
    hd_header_free(&h);
}

/* ---- annual statistics ---- */
static void test_annual(void)
{
    CHECK(hd_glare_class_dgp(0.3499) == HD_GLARE_IMPERCEPTIBLE);
    CHECK(hd_glare_class_dgp(0.35) == HD_GLARE_PERCEPTIBLE);
    CHECK(hd_glare_class_dgp(0.40) == HD_GLARE_DISTURBING);
    CHECK(hd_glare_class_dgp(0.45) == HD_GLARE_INTOLERABLE);
    CHECK(hd_glare_class_dgi(17.9) == HD_GLARE_IMPERCEPTIBLE);
    CHECK(hd_glare_class_dgi(18) == HD_GLARE_PERCEPTIBLE);
    CHECK(hd_glare_class_dgi(24) == HD_GLARE_DISTURBING);
    CHECK(hd_glare_class_dgi(31) == HD_GLARE_INTOLERABLE);
    CHECK_STR(hd_glare_class_name(HD_GLARE_DISTURBING), "disturbing");
    CHECK(hd_glare_shade_closed(0.40, HD_GLARE_SHADE_LIMIT) == 1);
    CHECK(hd_glare_shade_closed(0.3999, HD_GLARE_SHADE_LIMIT) == 0);
    double v[] = {5, 1, 4, 2, 3};
    CHECK_NEAR(hd_glare_percentile(v, 5, 50), 3, 1e-12);
    CHECK_NEAR(hd_glare_percentile(v, 5, 95), 4.8, 1e-12);   /* 1 + 0.95*4 -> 4.8 */
    CHECK_NEAR(hd_glare_percentile(v, 5, 0), 1, 0);
    CHECK(isnan(hd_glare_percentile(v, 0, 50)));
    hd_glare_annual a;
    hd_glare_annual_init(&a, 0);
    int closed = -1;
    for (int h = 0; h < 3000; h++) {
        double dgp = 0.2 + 0.3 * (h % 100) / 99.0;   /* 0.2 .. 0.5 */
        REQUIRE(hd_glare_annual_add(&a, h, 1000, dgp, 10 + h % 30, &closed) == HD_OK);
        CHECK(closed == (dgp >= 0.40));
    }
    CHECK(a.n == 3000);
    size_t tot = 0;
    for (int c = 0; c < 4; c++) tot += a.count_dgp[c];
    CHECK(tot == 3000);
    /* dgp >= 0.40 <=> h%100 >= 66 : 34 per 100 */
    CHECK(a.shade_closed == 34 * 30);
    hd_glare_annual_free(&a);
}

int main(void)
{
    hd_set_warnings(0);
    RUN(test_uniform_ev);
    RUN(test_pixel_solid_angle);
    RUN(test_spec_example_formulas);
    RUN(test_spec_example_image);
    RUN(test_posidx);
    RUN(test_angular_vs_hemispherical);
    RUN(test_detection);
    RUN(test_bad_views);
    RUN(test_view_header);
    RUN(test_view_module_agrees);
    RUN(test_reference_office);
    RUN(test_reference_box);
    RUN(test_reference_ev);
    RUN(test_picture_roundtrip);
    RUN(test_annual);
    return hd_test_done();
}

/* Unit tests: annual composition (annual.h) on synthetic coefficient
 * pictures whose composite is known in closed form. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hd_test.h"
#include "heliodon/annual.h"
#include "heliodon/rng.h"
#include "heliodon/dctimestep.h"
#include "heliodon/basis.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/picture.h"
#include "heliodon/sky.h"
#include "heliodon/weather.h"

#define RES 16
static char dir[256];
static const double K = 1.0 / 1024;        /* exactly representable in RGBE */
static const double KSUN = 1.0 / 1048576;
/* RGBE decoding puts a power of two m = 128 at the centre of its mantissa
 * step: (128 + 0.5) / 128 */
static const double DEC = 128.5 / 128;

static int write_const(const char *path, double v, int left_half_only)
{
    hd_picture p;
    if (hd_picture_alloc(&p, RES, RES)) return 0;
    for (int y = 0; y < RES; y++)
        for (int x = 0; x < RES; x++)
            for (int c = 0; c < 3; c++) p.pix[3 * (y * RES + x) + c] = (!left_half_only || x < RES / 2) ? (float)v : 0;
    hd_header h;
    hd_header_init(&h);
    int ok = hd_picture_save(path, &p, &h) == HD_OK;
    hd_header_free(&h);
    hd_picture_free(&p);
    return ok;
}

static const char *WEA = "place t\nlatitude 38.4\nlongitude -27.1\ntime_zone -30\nsite_elevation 0\n"
                         "weather_data_file_units 1\n3 21 2.5 0 0\n3 21 10.5 820 110\n6 21 15.5 600 150\n";

static int setup(void)
{
    if (snprintf(dir, sizeof dir, "%s/annual_unit", hd_test_tmpdir()) >= (int)sizeof dir) return 0;
    char cmd[1200], path[1200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s' && mkdir -p '%s'", dir, dir);
    if (system(cmd) != 0) return 0;
    snprintf(path, sizeof path, "%s/w.wea", dir);
    FILE *f = fopen(path, "w");
    if (!f) return 0;
    fputs(WEA, f);
    fclose(f);
    for (int b = 0; b < 146; b++) {
        snprintf(path, sizeof path, "%s/sky%03d.hdr", dir, b);
        if (!write_const(path, K, 0)) return 0;
        snprintf(path, sizeof path, "%s/fen%03d.hdr", dir, b);
        if (!write_const(path, 4 * K, 0)) return 0;
        if (b > 0) {
            snprintf(path, sizeof path, "%s/solar%d.hdr", dir, b);
            if (!write_const(path, KSUN, 0)) return 0;
        }
    }
    snprintf(path, sizeof path, "%s/mask.hdr", dir);
    if (!write_const(path, 1, 1)) return 0;
    snprintf(path, sizeof path, "%s/v0.hdr", dir);
    if (!write_const(path, K, 0)) return 0;
    snprintf(path, sizeof path, "%s/v1.hdr", dir);
    if (!write_const(path, 2 * K, 0)) return 0;
    snprintf(path, sizeof path, "%s/td.mtx", dir);
    f = fopen(path, "w");
    if (!f) return 0;
    fprintf(f, "#?RADIANCE\nNROWS=2\nNCOLS=146\nNCOMP=3\nFORMAT=ascii\n\n");
    for (int k = 0; k < 2; k++) {
        for (int b = 0; b < 146; b++) fprintf(f, "%g %g %g\t", k ? 0.5 : 1.0, k ? 0.5 : 1.0, k ? 0.5 : 1.0);
        fputc('\n', f);
    }
    fclose(f);
    return 1;
}

/* expected sums over the sky vector and the sun radiance of weather record i */
static void expected(int i, double sky[3], double sun[3])
{
    hd_weather w;
    hd_weather_init(&w);
    hd_weather_read_memory(WEA, strlen(WEA), "w", &w);
    int jd[8];
    hd_daymtx_julian_days(&w, jd);
    hd_daymtx_step st = {jd[i], w.rec[i].hour, w.rec[i].v1, w.rec[i].v2, 1, NAN};
    hd_skybasis b;
    hd_skybasis_init(&b, 1);
    double col[146 * 3];
    hd_daymtx_opts o;
    hd_daymtx_opts_default(&o);
    o.sky_only = 1;
    hd_daymtx_column(&b, &o, &w.site, &st, col, NULL);
    for (int c = 0; c < 3; c++) {
        sky[c] = 0;
        for (int p = 0; p < 146; p++) sky[c] += col[3 * p + c];
    }
    hd_daymtx_opts_default(&o);
    o.sun_only = 1;
    o.disk_deg = 0.533;
    o.nsuns = 1;
    hd_daymtx_column(&b, &o, &w.site, &st, col, NULL);
    for (int c = 0; c < 3; c++) {
        sun[c] = 0;
        for (int p = 0; p < 146; p++) sun[c] += col[3 * p + c];
    }
    hd_skybasis_free(&b);
    hd_weather_free(&w);
}

static double lum(const double v[3]) { return DEC * 179 * (0.265074126 * v[0] + 0.670114631 * v[1] + 0.064811243 * v[2]); }

/* run with the given inputs; returns the mean luminance of the two hours
 * from the hour log and the E_v of the first one */
static int run(const char *sky, int terms, int fen, int sun, double ml[2], double ev[2])
{
    char w[1200], s1[1200], k1[1200], f1[1200], m1[1200], v1[1200], t1[1200], log[1200], csv[1200];
    snprintf(w, sizeof w, "%s/w.wea", dir);
    snprintf(s1, sizeof s1, "%s/solar%%d.hdr", dir);
    snprintf(k1, sizeof k1, "%s/%s%%03d.hdr", dir, sky ? sky : "sky");
    snprintf(f1, sizeof f1, "%s/fen%%03d.hdr", dir);
    snprintf(m1, sizeof m1, "%s/mask.hdr", dir);
    snprintf(v1, sizeof v1, "%s/v%%d.hdr", dir);
    snprintf(t1, sizeof t1, "%s/td.mtx", dir);
    snprintf(log, sizeof log, "%s/hours.log", dir);
    snprintf(csv, sizeof csv, "%s/a.csv", dir);
    hd_annual_opts o;
    hd_annual_opts_default(&o);
    o.weather = w;
    o.sun_pattern = sun ? s1 : NULL;
    o.sky_pattern = sky ? k1 : NULL;
    if (terms) {
        o.nterms = 1;
        o.v_pattern[0] = v1;
        o.td_matrix[0] = t1;
    }
    if (fen) {
        o.fen_pattern = f1;
        o.mask = m1;
    }
    hd_view_parse_line(&o.view, "-vta -vp 0 0 0 -vd 1 0 0 -vu 0 0 1 -vh 180 -vv 180");
    o.have_view = 1;
    o.csv = csv;
    o.hourlog = log;
    o.nthreads = 2;
    hd_annual_stats st;
    if (hd_annual_run(&o, &st) != HD_OK) return 0;
    if (st.ndaylight != 2) return 0;
    FILE *f = fopen(log, "r");
    if (!f) return 0;
    char line[512];
    int n = 0;
    while (fgets(line, sizeof line, f) && n < 2) {
        if (line[0] == '#') continue;
        double v[13];
        if (sscanf(line, "%lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5],
                   &v[6], &v[7], &v[8], &v[9], &v[10], &v[11], &v[12]) == 13)
            ml[n++] = v[11];
    }
    fclose(f);
    f = fopen(csv, "r");
    if (!f) return 0;
    int r = 0;
    while (fgets(line, sizeof line, f))
        if (r < 3) {
            double h, e;
            if (sscanf(line, "%lf,%lf", &h, &e) == 2) ev[r - 1 < 0 ? 0 : r - 1] = e;
            r++;
        }
    fclose(f);
    return n == 2;
}

/* The annual sky fold runs on dctimestep's kernels, several hours at a
 * time: every kernel level gives, bit for bit, the one-hour scalar fold
 * annual.c had (rgb += coef_b * (float)s_b over b ascending, separate
 * multiply and add), zero bins and absent components included. */
static void test_fold(void)
{
    enum { NB = 7, NP = 37, NPAD = 48, NH = 5 };
    float *planar[NB];
    float inter[NB][3 * NP];
    double s[NH][3 * NB];
    hd_rng rng;
    hd_rng_init(&rng, 5, 0);
    for (int b = 0; b < NB; b++) {
        planar[b] = b == 3 ? NULL : calloc(3 * NPAD, sizeof(float));
        for (int i = 0; i < NP; i++)
            for (int c = 0; c < 3; c++) {
                inter[b][3 * i + c] = b == 3 ? 0.0f : (float)(hd_rng_uniform(&rng) * 1e3);
                if (planar[b]) planar[b][c * NPAD + i] = inter[b][3 * i + c];
            }
    }
    for (int h = 0; h < NH; h++)
        for (int k = 0; k < 3 * NB; k++) s[h][k] = (h + k) % 4 == 0 ? 0 : hd_rng_uniform(&rng) * 0.37;
    double coef[NB * NH * 3];
    for (int b = 0; b < NB; b++)
        for (int h = 0; h < NH; h++)
            for (int c = 0; c < 3; c++) coef[(b * NH + h) * 3 + c] = s[h][3 * b + c];
    for (int lv = 0; lv <= 2; lv++) {
        if (hd_dcts_set_kernel(lv) != lv) continue;
        float out[NH * 3 * NPAD];
        REQUIRE(hd_dcts_fold(planar, NB, coef, NH, NPAD, out, 1) == HD_OK);
        int same = 1;
        for (int h = 0; h < NH; h++) {
            float ref[3 * NP];
            memset(ref, 0, sizeof ref);
            for (int b = 0; b < NB; b++) {
                float f[3] = {(float)s[h][3 * b], (float)s[h][3 * b + 1], (float)s[h][3 * b + 2]};
                if (f[0] == 0 && f[1] == 0 && f[2] == 0) continue;
                for (int i = 0; i < NP; i++)
                    for (int c = 0; c < 3; c++) ref[3 * i + c] += inter[b][3 * i + c] * f[c];
            }
            for (int i = 0; i < NP; i++)
                for (int c = 0; c < 3; c++)
                    if (memcmp(&ref[3 * i + c], &out[(h * 3 + c) * NPAD + i], sizeof(float))) same = 0;
        }
        CHECK_MSG(same, "kernel level %d differs from the scalar one-hour fold", lv);
    }
    hd_dcts_set_kernel(-1);
    for (int b = 0; b < NB; b++) free(planar[b]);
}

static void test_compose(void)
{
    REQUIRE(setup());
    double sky1[3], sun1[3], sky2[3], sun2[3];
    expected(1, sky1, sun1);
    expected(2, sky2, sun2);
    CHECK(lum(sun1) > 0);
    double ml[2], ev[2];
    /* sky only */
    REQUIRE(run("sky", 0, 0, 0, ml, ev));
    double e1[3] = {K * sky1[0], K * sky1[1], K * sky1[2]}, e2[3] = {K * sky2[0], K * sky2[1], K * sky2[2]};
    CHECK_REL(ml[0], lum(e1), 1e-4);
    CHECK_REL(ml[1], lum(e2), 1e-4);
    CHECK_REL(ev[0], HD_PI * lum(e1), 0.02);   /* uniform field: E_v = pi L */
    /* sky + sun */
    REQUIRE(run("sky", 0, 0, 1, ml, ev));
    double f1[3], f2[3];
    for (int c = 0; c < 3; c++) {
        f1[c] = K * sky1[c] + KSUN * sun1[c];
        f2[c] = K * sky2[c] + KSUN * sun2[c];
    }
    CHECK_REL(ml[0], lum(f1), 1e-4);
    CHECK_REL(ml[1], lum(f2), 1e-4);
    /* 3PM term V*TD: coefficients K*1 + 2K*0.5 = 2K */
    REQUIRE(run(NULL, 1, 0, 0, ml, ev));
    CHECK_REL(ml[0], 2 * lum(e1), 1e-4);
    /* 3PM term plus direct sky DC: 3K */
    REQUIRE(run("sky", 1, 0, 0, ml, ev));
    CHECK_REL(ml[0], 3 * lum(e1), 1e-4);
    /* fenestration DC inside the left-half mask: (4K + K)/2 */
    REQUIRE(run("sky", 0, 1, 0, ml, ev));
    CHECK_REL(ml[0], 2.5 * lum(e1), 1e-4);
    CHECK_REL(ml[1], 2.5 * lum(e2), 1e-4);
}

static void test_errors(void)
{
    REQUIRE(setup());
    char w[1200], s1[1200], k1[1200];
    snprintf(w, sizeof w, "%s/w.wea", dir);
    snprintf(s1, sizeof s1, "%s/nosun%%d.hdr", dir);
    snprintf(k1, sizeof k1, "%s/sky%%03d.hdr", dir);
    hd_annual_opts o;
    hd_annual_opts_default(&o);
    o.weather = w;
    o.sun_pattern = s1;
    o.sky_pattern = k1;
    o.csv = "/dev/null";
    /* no view */
    CHECK(hd_annual_run(&o, NULL) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "no view");
    /* perspective view */
    hd_view_parse_line(&o.view, "-vtv -vh 60 -vv 60");
    o.have_view = 1;
    CHECK(hd_annual_run(&o, NULL) != HD_OK);
    /* fisheye, but the sun pictures are missing */
    hd_view_default(&o.view);
    hd_view_parse_line(&o.view, "-vta -vd 1 0 0 -vh 180 -vv 180");
    CHECK(hd_annual_run(&o, NULL) == HD_ERR_IO);
    CHECK_CONTAINS(hd_errmsg(), "missing sun coefficient picture");
    /* a fenestration DC without its mask */
    o.sun_pattern = NULL;
    o.fen_pattern = k1;
    CHECK(hd_annual_run(&o, NULL) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "mask");
    o.fen_pattern = NULL;
    /* wrong TD matrix width */
    char t[1200], v[1200];
    snprintf(t, sizeof t, "%s/td_bad.mtx", dir);
    snprintf(v, sizeof v, "%s/v%%d.hdr", dir);
    FILE *f = fopen(t, "w");
    REQUIRE(f);
    fprintf(f, "#?RADIANCE\nNROWS=1\nNCOLS=2\nNCOMP=3\nFORMAT=ascii\n\n1 1 1 1 1 1\n");
    fclose(f);
    o.nterms = 1;
    o.v_pattern[0] = v;
    o.td_matrix[0] = t;
    CHECK(hd_annual_run(&o, NULL) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "expected 146 sky bins");
    o.nterms = 0;
    /* records out of range */
    long recs[1] = {99};
    o.records = recs;
    o.nrecords = 1;
    CHECK(hd_annual_run(&o, NULL) == HD_ERR_RANGE);
}

/* two-pass schedule: hand-made CSVs and logs of an open and a closed run */
static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (f) {
        fputs(text, f);
        fclose(f);
    }
}

static void test_schedule(void)
{
    const char *tmp = hd_test_tmpdir();
    REQUIRE(tmp);
    char oc[1200], ol[1200], cc[1200], cl[1200], out[1200], sch[1200], log[1200], sum[1200];
    snprintf(oc, sizeof oc, "%s/sched_open.csv", tmp);
    snprintf(ol, sizeof ol, "%s/sched_open.log", tmp);
    snprintf(cc, sizeof cc, "%s/sched_closed.csv", tmp);
    snprintf(cl, sizeof cl, "%s/sched_closed.log", tmp);
    snprintf(out, sizeof out, "%s/sched_out.csv", tmp);
    snprintf(sch, sizeof sch, "%s/sched.csv", tmp);
    snprintf(log, sizeof log, "%s/sched_out.log", tmp);
    snprintf(sum, sizeof sum, "%s/sched_sum.txt", tmp);
    const char *H = "hour,Ev,DGP,DGI,UGR,nsources,DGP_class,DGI_class,shade\n";
    char buf[2048];
    /* open DGPs 0.30, 0.40 (= limit: closed), 0.55 (closed) */
    snprintf(buf, sizeof buf, "%s10.5,1000,0.300000,15,10,1,imperceptible,imperceptible,0\n"
             "11.5,2000,0.400000,20,12,2,disturbing,perceptible,1\n12.5,3000,0.550000,30,14,3,intolerable,disturbing,1\n", H);
    write_text(oc, buf);
    snprintf(buf, sizeof buf, "%s10.5,500,0.200000,10,5,1,imperceptible,imperceptible,0\n"
             "11.5,600,0.210000,11,6,1,imperceptible,imperceptible,0\n12.5,700,0.220000,12,7,1,imperceptible,imperceptible,0\n", H);
    write_text(cc, buf);
    write_text(ol, "# log\n10 1 1 10.5 1 0 0 1 1 1 1 100 0.300000\n11 1 1 11.5 1 0 0 1 1 1 1 200 0.400000\n"
                   "12 1 1 12.5 1 0 0 1 1 1 1 300 0.550000\n");
    write_text(cl, "# log\n10 1 1 10.5 1 0 0 1 1 1 1 50 0.200000\n11 1 1 11.5 1 0 0 1 1 1 1 60 0.210000\n"
                   "12 1 1 12.5 1 0 0 1 1 1 1 70 0.220000\n");
    hd_annual_sched_opts so;
    hd_annual_sched_opts_default(&so);
    so.open_csv = oc;
    so.open_log = ol;
    so.closed_csv = cc;
    so.closed_log = cl;
    so.csv = out;
    so.schedule = sch;
    so.hourlog = log;
    so.summary = sum;
    hd_annual_sched_stats st;
    REQUIRE(hd_annual_schedule(&so, &st) == HD_OK);
    CHECK(st.nhours == 3);
    CHECK(st.nclosed == 2);
    /* composite DGP 0.30, 0.21, 0.22 -> p95 = 0.30 - 0.1*(0.30-0.22)... linear: sorted .21 .22 .30, pos 1.9 */
    CHECK_NEAR(st.dgp_p95, 0.22 + 0.9 * 0.08, 1e-9);
    CHECK_NEAR(st.dgp_p95_open, 0.40 + 0.9 * 0.15, 1e-9);
    FILE *f = fopen(out, "r");
    REQUIRE(f);
    char l[4][256];
    int n = 0;
    while (n < 4 && fgets(l[n], sizeof l[n], f)) n++;
    fclose(f);
    REQUIRE(n == 4);
    CHECK(!strcmp(l[1], "10.5,1000,0.300000,15,10,1,imperceptible,imperceptible,0\n"));
    CHECK(!strcmp(l[2], "11.5,600,0.210000,11,6,1,imperceptible,imperceptible,1\n"));
    CHECK(!strcmp(l[3], "12.5,700,0.220000,12,7,1,imperceptible,imperceptible,1\n"));
    f = fopen(log, "r");
    REQUIRE(f);
    int nl = 0, has70 = 0;
    while (fgets(buf, sizeof buf, f))
        if (buf[0] != '#') {
            nl++;
            has70 += strstr(buf, " 70 0.220000") != NULL;
        }
    fclose(f);
    CHECK(nl == 3 && has70 == 1);
    /* mismatched hours are refused and nothing is written */
    write_text(cc, "hour,Ev,DGP,DGI,UGR,nsources,DGP_class,DGI_class,shade\n10.5,1,0.2,1,1,1,a,b,0\n"
                   "13.5,1,0.2,1,1,1,a,b,0\n12.5,1,0.2,1,1,1,a,b,0\n");
    remove(out);
    CHECK(hd_annual_schedule(&so, NULL) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "same hours");
    f = fopen(out, "r");
    CHECK(f == NULL);
    if (f) fclose(f);
    so.shade_limit = 1.5;
    CHECK(hd_annual_schedule(&so, NULL) == HD_ERR_RANGE);
}

/* Hours are composed grouped by sun patch and each DC_sun picture is read
 * for its patch's hours only (annual.c): every hour must still get its own
 * patch's picture, whatever the thread count.  Ten hours on four days, sun
 * only, DC_sun of patch b = KSUN 2^(b mod 5) (exact in RGBE; neighbouring
 * patches differ by a factor 2), mean luminance from the hour log. */
static const char *WEA10 = "place t\nlatitude 38.4\nlongitude -27.1\ntime_zone -30\nsite_elevation 0\n"
                           "weather_data_file_units 1\n3 21 8.5 700 100\n3 21 10.5 820 110\n3 21 12.5 850 100\n"
                           "3 21 14.5 800 120\n6 21 9.5 700 150\n6 21 12.5 900 120\n6 21 15.5 600 150\n"
                           "9 21 10.5 800 110\n12 21 11.5 700 90\n12 21 13.5 650 95\n";

static int sunorder_run(int nthreads, const char *log, double ml[10], int patch[10], double rgb[10][3])
{
    char w[1200], s1[1200];
    snprintf(w, sizeof w, "%s/w10.wea", dir);
    snprintf(s1, sizeof s1, "%s/sun2k%%d.hdr", dir);
    hd_annual_opts o;
    hd_annual_opts_default(&o);
    o.weather = w;
    o.sun_pattern = s1;
    hd_view_parse_line(&o.view, "-vta -vp 0 0 0 -vd 1 0 0 -vu 0 0 1 -vh 180 -vv 180");
    o.have_view = 1;
    o.csv = "/dev/null";
    o.hourlog = log;
    o.nthreads = nthreads;
    hd_annual_stats st;
    if (hd_annual_run(&o, &st) != HD_OK || st.ndaylight != 10) return 0;
    FILE *f = fopen(log, "r");
    if (!f) return 0;
    char line[512];
    int n = 0;
    while (fgets(line, sizeof line, f) && n < 10) {
        if (line[0] == '#') continue;
        double v[13];
        if (sscanf(line, "%lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5],
                   &v[6], &v[7], &v[8], &v[9], &v[10], &v[11], &v[12]) != 13)
            break;
        patch[n] = (int)v[4];
        for (int c = 0; c < 3; c++) rgb[n][c] = v[8 + c];
        ml[n++] = v[11];
    }
    fclose(f);
    return n == 10;
}

static void test_sunorder(void)
{
    REQUIRE(setup());
    char path[1200], log1[1200], log4[1200];
    snprintf(path, sizeof path, "%s/w10.wea", dir);
    FILE *f = fopen(path, "w");
    REQUIRE(f);
    fputs(WEA10, f);
    fclose(f);
    for (int b = 1; b < 146; b++) {
        snprintf(path, sizeof path, "%s/sun2k%d.hdr", dir, b);
        REQUIRE(write_const(path, KSUN * (1 << (b % 5)), 0));
    }
    snprintf(log1, sizeof log1, "%s/h1.log", dir);
    snprintf(log4, sizeof log4, "%s/h4.log", dir);
    double ml1[10], ml4[10], rgb[10][3];
    int p1[10], p4[10];
    REQUIRE(sunorder_run(1, log1, ml1, p1, rgb));
    REQUIRE(sunorder_run(4, log4, ml4, p4, rgb));
    int distinct = 0, same = 1;
    for (int i = 0; i < 10; i++) {
        int seen = 0;
        for (int j = 0; j < i; j++) seen |= p1[j] == p1[i];
        distinct += !seen && p1[i] > 0;
        double e[3];
        for (int c = 0; c < 3; c++) e[c] = rgb[i][c] * KSUN * (1 << (p1[i] % 5));
        CHECK_REL(ml1[i], lum(e), 1e-4);
        same &= p1[i] == p4[i] && ml1[i] == ml4[i];
    }
    CHECK_MSG(distinct >= 8, "only %d distinct sun patches among the 10 hours", distinct);
    CHECK_MSG(same, "1 and 4 threads give different hour logs");
}

/* pmmask's ray masking: N rays per pixel (vwrays -c N) kept or zeroed
 * together, each written `repeat` times; wrong stream lengths fail */
static void test_mask_rays(void)
{
    const char *tmp = hd_test_tmpdir();
    REQUIRE(tmp);
    char mask[1200];
    snprintf(mask, sizeof mask, "%s/annual_mask_rays.hdr", tmp);
    hd_picture m;
    REQUIRE(hd_picture_alloc(&m, 2, 2) == HD_OK);
    for (int i = 0; i < 4; i++)   /* pixels 0 and 2 (the left column) see the window */
        for (int c = 0; c < 3; c++) m.pix[3 * i + c] = (i % 2 == 0) ? 1.0f : 0.0f;
    hd_header h;
    hd_header_init(&h);
    REQUIRE(hd_picture_save(mask, &m, &h) == HD_OK);
    hd_header_free(&h);
    hd_picture_free(&m);
    enum { PER = 3, REP = 2, NIN = 4 * PER };
    float in[NIN][6];
    for (int r = 0; r < NIN; r++)
        for (int k = 0; k < 6; k++) in[r][k] = (float)(10 * r + k + 1);
    hd_istream *is;
    REQUIRE(hd_istream_memory(&is, in, sizeof in, "rays") == HD_OK);
    FILE *out = tmpfile();
    REQUIRE(out);
    long kept = -1;
    CHECK(hd_annual_mask_rays(mask, is, "rays", out, PER, REP, &kept) == HD_OK);
    hd_istream_close(is);
    CHECK(kept == 2 * PER);
    rewind(out);
    float got[NIN * REP][6];
    CHECK(fread(got, sizeof got[0], NIN * REP, out) == NIN * REP);
    CHECK(fgetc(out) == EOF);
    fclose(out);
    for (int r = 0; r < NIN * REP; r++) {
        int src = r / REP, pix = src / PER, inside = pix % 2 == 0;
        for (int k = 0; k < 6; k++) CHECK(got[r][k] == (k < 3 || inside ? in[src][k] : 0.0f));
    }
    /* one ray short, one ray too many */
    REQUIRE(hd_istream_memory(&is, in, sizeof in - sizeof in[0], "short") == HD_OK);
    out = tmpfile();
    REQUIRE(out);
    CHECK(hd_annual_mask_rays(mask, is, "short", out, PER, 1, NULL) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "before the 12 rays");
    hd_istream_close(is);
    REQUIRE(hd_istream_memory(&is, in, sizeof in, "long") == HD_OK);
    CHECK(hd_annual_mask_rays(mask, is, "long", out, PER - 1, 1, NULL) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "more rays than the 8");
    hd_istream_close(is);
    REQUIRE(hd_istream_memory(&is, in, sizeof in, "range") == HD_OK);
    CHECK(hd_annual_mask_rays(mask, is, "range", out, 0, 1, NULL) == HD_ERR_RANGE);
    hd_istream_close(is);
    fclose(out);
}

int main(void)
{
    hd_set_warnings(0);
    RUN(test_fold);
    RUN(test_compose);
    RUN(test_errors);
    RUN(test_schedule);
    RUN(test_sunorder);
    RUN(test_mask_rays);
    return hd_test_done();
}

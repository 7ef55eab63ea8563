/* Unit tests: sun sources at Reinhart patch centres (suns.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hd_test.h"
#include "heliodon/basis.h"
#include "heliodon/sky.h"
#include "heliodon/suns.h"
#include "heliodon/weather.h"

static const char *WEA_HDR = "place t\nlatitude %g\nlongitude %g\ntime_zone %g\nsite_elevation 0\n"
                             "weather_data_file_units 1\n";

static int load(hd_weather *w, double lat, double lon, double mer, const char *recs)
{
    char text[8192];
    int n = snprintf(text, sizeof text, WEA_HDR, lat, lon, mer);
    snprintf(text + n, sizeof text - (size_t)n, "%s", recs);
    hd_weather_init(w);
    return hd_weather_read_memory(text, strlen(text), "mem.wea", w) == HD_OK;
}

/* At the equator at an equinox, solar noon puts the sun (nearly) at the
 * zenith: the kept patch must be the zenith cap. */
static void test_zenith(void)
{
    hd_weather w;
    REQUIRE(load(&w, 0, 0, 0, "3 20 12.1 900 100\n"));
    hd_sunlist s;
    REQUIRE(hd_suns_select(&w, 1, 0, &s) == HD_OK);
    CHECK(s.n == 1);
    CHECK(s.nbins == 146);
    CHECK(s.bin[0] == 145);
    CHECK_NEAR(s.dir[0].z, 1.0, 1e-9);
    CHECK(s.ndaylight == 1);
    hd_sunlist_free(&s);
    hd_weather_free(&w);
}

/* Every sun-only sky vector of gendaymtx -5 0.533 -d has its non-zero
 * patch among the kept ones, for MF 1, 2 and 6, over a day every month. */
static void test_matches_daymtx(void)
{
    char recs[65536];
    size_t k = 0;
    for (int m = 1; m <= 12; m++)
        for (int h = 0; h < 24; h++)
            k += (size_t)snprintf(recs + k, sizeof recs - k, "%d 15 %d.5 %d %d\n", m, h, (h > 5 && h < 19) ? 700 : 0,
                                  (h > 5 && h < 19) ? 90 : 0);
    hd_weather w;
    REQUIRE(load(&w, 38.4, -27.1, -30, recs));
    int mfs[3] = {1, 2, 6};
    for (int t = 0; t < 3; t++) {
        hd_sunlist s;
        REQUIRE(hd_suns_select(&w, mfs[t], 0, &s) == HD_OK);
        hd_skybasis b;
        REQUIRE(hd_skybasis_init(&b, mfs[t]) == HD_OK);
        hd_daymtx_opts o;
        hd_daymtx_opts_default(&o);
        o.sun_only = 1;
        o.disk_deg = 0.533;
        o.nsuns = 1;
        int *jd = malloc(w.n * sizeof(int));
        double *col = malloc((size_t)b.nbins * 3 * sizeof(double));
        REQUIRE(jd && col);
        hd_daymtx_julian_days(&w, jd);
        int nsun = 0, missing = 0;
        for (size_t i = 0; i < w.n; i++) {
            hd_daymtx_step st = {jd[i], w.rec[i].hour, w.rec[i].v1, w.rec[i].v2, 1, NAN};
            hd_daymtx_column(&b, &o, &w.site, &st, col, NULL);
            for (int p = 1; p < b.nbins; p++)
                if (col[3 * p] > 0) {
                    nsun++;
                    int found = 0;
                    for (int q = 0; q < s.n; q++) found |= s.bin[q] == p;
                    missing += !found;
                }
        }
        CHECK(nsun > 100);
        CHECK_MSG(missing == 0, "MF:%d: %d sun vectors in patches that gensuns did not keep", mfs[t], missing);
        /* each kept patch is used by at least one record */
        long tot = 0;
        for (int q = 0; q < s.n; q++) {
            CHECK(s.hours[q] > 0);
            tot += s.hours[q];
            CHECK_NEAR(hd_vdot(s.dir[q], b.dir[s.bin[q]]), 1.0, 1e-12);
        }
        CHECK(tot == s.ndaylight);
        free(jd);
        free(col);
        hd_skybasis_free(&b);
        hd_sunlist_free(&s);
    }
    hd_weather_free(&w);
}

static void test_keep_all_and_write(void)
{
    hd_weather w;
    REQUIRE(load(&w, 50, 0, 0, "6 21 12 800 100\n6 21 13 800 100\n"));
    hd_sunlist s;
    REQUIRE(hd_suns_select(&w, 2, 1, &s) == HD_OK);
    CHECK(s.n == 144 * 4 + 1);   /* all sky patches incl. the zenith cap */
    char path[512], mpath[512];
    snprintf(path, sizeof path, "%s/suns_test.rad", hd_test_tmpdir());
    snprintf(mpath, sizeof mpath, "%s/suns_test.txt", hd_test_tmpdir());
    FILE *f = fopen(path, "w"), *m = fopen(mpath, "w");
    REQUIRE(f && m);
    REQUIRE(hd_suns_write(&s, f, m, "test") == HD_OK);
    fclose(f);
    fclose(m);
    f = fopen(path, "r");
    REQUIRE(f);
    char line[256];
    int nsrc = 0, nlight = 0, bad = 0;
    while (fgets(line, sizeof line, f)) {
        int b1, b2;
        if (sscanf(line, "solar%d source sun%d", &b1, &b2) == 2) {
            nsrc++;
            double d[4];
            char l2[256];
            if (!fgets(l2, sizeof l2, f) || !fgets(l2, sizeof l2, f) || !fgets(l2, sizeof l2, f) ||
                sscanf(l2, "4 %lf %lf %lf %lf", &d[0], &d[1], &d[2], &d[3]) != 4)
                bad++;
            else if (fabs(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - 1) > 1e-6 || fabs(d[3] - 0.533) > 1e-9 || b1 != b2)
                bad++;
        }
        if (!strncmp(line, "void light solar", 16)) nlight++;
    }
    fclose(f);
    CHECK(nsrc == s.n);
    CHECK(nlight == s.n);
    CHECK(bad == 0);
    f = fopen(mpath, "r");
    REQUIRE(f);
    int nm = 0, prev = 0, order = 1;
    while (fgets(line, sizeof line, f)) {
        int b;
        if (sscanf(line, "solar%d", &b) == 1) {
            order &= b > prev;
            prev = b;
            nm++;
        }
    }
    fclose(f);
    CHECK(nm == s.n);
    CHECK(order);
    hd_sunlist_free(&s);
    hd_weather_free(&w);
}

static void test_errors(void)
{
    hd_weather w;
    REQUIRE(load(&w, 38.4, -27.1, -30, "1 1 0.5 0 0\n1 1 12.5 0 0\n1 1 23.5 500 50\n"));
    hd_sunlist s;
    CHECK(hd_suns_select(&w, 1, 0, &s) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "no daylight hours");
    CHECK(hd_suns_select(&w, 1, 1, &s) == HD_OK);   /* keep_all still works */
    CHECK(s.n == 145);
    hd_sunlist_free(&s);
    CHECK(hd_suns_select(&w, 0, 0, &s) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "MF:0");
    CHECK(hd_suns_select(&w, 65, 0, &s) == HD_ERR_USAGE);
    hd_weather_free(&w);
}

int main(void)
{
    hd_set_warnings(0);
    RUN(test_zenith);
    RUN(test_matches_daymtx);
    RUN(test_keep_all_and_write);
    RUN(test_errors);
    return hd_test_done();
}

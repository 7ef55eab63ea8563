/* Unit tests for the Tregenza / Reinhart sky bases (basis.h). */
#include "hd_test.h"
#include "heliodon/basis.h"
#include "heliodon/rng.h"
#include "heliodon/solar.h"

static void test_counts(void)
{
    /* Radiance's Nrbins with the ground (spec 4.1) */
    static const int expect[7] = {0, 146, 578, 1298, 2306, 3602, 5186};
    for (int mf = 1; mf <= 6; mf++) {
        hd_skybasis b;
        REQUIRE(hd_skybasis_init(&b, mf) == HD_OK);
        CHECK(b.nbins == expect[mf]);
        CHECK(hd_skybasis_count(mf) == expect[mf]);
        CHECK(b.band_count[0] == 30 * mf && b.band_count[b.nbands - 1] == 6 * mf);
        hd_skybasis_free(&b);
    }
    hd_skybasis b;
    CHECK(hd_skybasis_init(&b, 0) == HD_ERR_RANGE);
    CHECK_CONTAINS(hd_errmsg(), "MF:0");
    CHECK(hd_skybasis_count(HD_SKY_MAXMF + 1) == 0);
}

static void test_solid_angles(void)
{
    for (int mf = 1; mf <= 12; mf++) {
        hd_skybasis b;
        REQUIRE(hd_skybasis_init(&b, mf) == HD_OK);
        double sum = 0, proj = 0;
        for (int i = 1; i < b.nbins; i++) {
            sum += b.omega[i];
            proj += b.omega[i] * sin(b.alt[i]);
        }
        CHECK_NEAR(sum, 2 * HD_PI, 1e-9);
        CHECK_NEAR(b.omega[0], 2 * HD_PI, 1e-12);
        /* projected solid angle with centre sines approaches pi */
        CHECK_REL(proj, HD_PI, 0.01 / mf);
        hd_skybasis_free(&b);
    }
}

static void test_roundtrip(void)
{
    for (int mf = 1; mf <= 8; mf++) {
        hd_skybasis b;
        REQUIRE(hd_skybasis_init(&b, mf) == HD_OK);
        int bad = 0;
        for (int i = 0; i < b.nbins; i++)
            if (hd_skybasis_bin(&b, hd_skybasis_dir(&b, i)) != i) bad++;
        CHECK_MSG(bad == 0, "MF:%d: %d bins do not round-trip", mf, bad);
        /* samples inside a bin map back to it */
        hd_rng r;
        hd_rng_init(&r, 7, (uint64_t)mf);
        bad = 0;
        for (int i = 1; i < b.nbins; i++)
            for (int k = 0; k < 4; k++) {
                double u1 = 0.01 + 0.98 * hd_rng_uniform(&r), u2 = 0.01 + 0.98 * hd_rng_uniform(&r);
                if (hd_skybasis_bin(&b, hd_skybasis_sample(&b, i, u1, u2)) != i) bad++;
            }
        CHECK_MSG(bad == 0, "MF:%d: %d samples fall outside their bin", mf, bad);
        hd_skybasis_free(&b);
    }
}

static void test_numbering(void)
{
    hd_skybasis b;
    REQUIRE(hd_skybasis_init(&b, 1) == HD_OK);
    CHECK(hd_skybasis_bin(&b, hd_v3(0, 0, -1)) == 0);
    CHECK(hd_skybasis_bin(&b, hd_v3(0.3, 0.2, -0.01)) == 0);
    CHECK(hd_skybasis_bin(&b, hd_v3(0, 1, 0.01)) == 1);            /* north, horizon */
    CHECK(hd_skybasis_bin(&b, hd_v3(sin(0.21), cos(0.21), 0.01)) == 2); /* 12 deg east of north */
    CHECK(hd_skybasis_bin(&b, hd_v3(sin(1.48), cos(1.48), 0.01)) == 1 + 7); /* 84.8 deg east: centre 84 */
    CHECK(hd_skybasis_bin(&b, hd_v3(-sin(0.05), cos(0.05), 0.01)) == 1); /* just west of north wraps */
    CHECK(hd_skybasis_bin(&b, hd_v3(0, 0, 1)) == 145);
    /* row starts as in tregenza.cal: 1, 31, 61, 85, 109, 127, 139, zenith 145 */
    static const int base[8] = {1, 31, 61, 85, 109, 127, 139, 145};
    for (int r = 0; r <= 7; r++) CHECK(b.band_first[r] == base[r]);
    /* MANIFEST item 6: a sun 62 deg east of south at alt ~25 deg lands in
     * MF:1 patch 69 (azimuth 118 deg east of north, band 2) */
    double az = (180 - 62) * HD_PI / 180, alt = 25 * HD_PI / 180;
    CHECK(hd_skybasis_bin(&b, hd_v3(sin(az) * cos(alt), cos(az) * cos(alt), sin(alt))) == 69);
    hd_skybasis_free(&b);
    int mf;
    CHECK(hd_skybasis_parse("r4", &mf) == HD_OK && mf == 4);
    CHECK(hd_skybasis_parse("MF:6", &mf) == HD_OK && mf == 6);
    CHECK(hd_skybasis_parse("tregenza", &mf) == HD_OK && mf == 1);
    CHECK(hd_skybasis_parse("u", &mf) == HD_OK && mf == 0);
    CHECK(hd_skybasis_parse("r0", &mf) == HD_ERR_USAGE);
    CHECK(hd_skybasis_parse("kf", &mf) == HD_ERR_USAGE);
}

/* The patch that gendaymtx -5 puts each sun in (reference matrix) is the
 * basis bin nearest to the sun direction we compute. */
static void test_numbering_vs_reference(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder");
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "gzip -dc %s/sky/daymtx/chicago_0621-0623_mf6_5.mtx.gz", ref);
    FILE *f = popen(cmd, "r");
    if (!f) SKIP("cannot run gzip");
    char line[512];
    int nr = 0, nc = 0;
    while (fgets(line, sizeof line, f) && line[0] != '\n') {
        sscanf(line, "NROWS=%d", &nr);
        sscanf(line, "NCOLS=%d", &nc);
    }
    REQUIRE(nr == 5186 && nc == 72);
    float *d = malloc((size_t)nr * nc * 3 * sizeof(float));
    REQUIRE(d);
    size_t got = fread(d, sizeof(float), (size_t)nr * nc * 3, f);
    pclose(f);
    REQUIRE(got == (size_t)nr * nc * 3);
    hd_skybasis b;
    REQUIRE(hd_skybasis_init(&b, 6) == HD_OK);
    hd_site site = {41.98, 87.92, 90, 201};
    int checked = 0, agree = 0, agree_bin = 0;
    for (int c = 0; c < nc; c++) {
        int day = 21 + c / 24;
        double hour = c % 24 + 0.5;
        hd_sunpos sp;
        hd_sun_position(&site, hd_julian_day(6, day), hour, 0, &sp);
        if (sp.alt < 5 * HD_PI / 180) continue;
        int best = 1, argmax = 1;
        double bd = -2;
        for (int i = 1; i < nr; i++) {
            double dp = hd_vdot(b.dir[i], sp.dir);
            if (dp > bd) { bd = dp; best = i; }
            if (d[((size_t)i * nc + c) * 3] > d[((size_t)argmax * nc + c) * 3]) argmax = i;
        }
        checked++;
        if (argmax == best) agree++;
        if (hd_skybasis_bin(&b, sp.dir) == argmax) agree_bin++;
    }
    CHECK(checked > 30);
    CHECK_MSG(agree == checked, "nearest patch = reference sun patch for %d of %d hours", agree, checked);
    CHECK_MSG(agree_bin >= checked * 9 / 10, "containing bin = reference sun patch for %d of %d hours", agree_bin, checked);
    hd_skybasis_free(&b);
    free(d);
}

int main(void)
{
    (void)hd_test_tmpdir;
    RUN(test_counts);
    RUN(test_solid_angles);
    RUN(test_roundtrip);
    RUN(test_numbering);
    RUN(test_numbering_vs_reference);
    return hd_test_done();
}

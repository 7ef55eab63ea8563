/* Unit tests for the WEA / EPW readers and the epw2wea writer. */
#include "hd_test.h"
#include "heliodon/weather.h"

#define WEAHDR "place Test_X\nlatitude 40.5\nlongitude -27.1\ntime_zone -30\nsite_elevation 12\nweather_data_file_units 1\n"

static hd_status parse(const char *text, hd_weather *w)
{
    return hd_weather_read_memory(text, strlen(text), "t.wea", w);
}

static void test_wea_ok(void)
{
    hd_weather w;
    REQUIRE(parse(WEAHDR "1 1 0.5 0 0\n1 1 12.5 800 100 0.1 3\n\n2 29 13.000 5.5 6.25\n", &w) == HD_OK);
    CHECK(w.n == 3);
    CHECK_STR(w.place, "Test_X");
    CHECK_NEAR(w.site.lat, 40.5, 0);
    CHECK_NEAR(w.site.lon, -27.1, 0);
    CHECK_NEAR(w.site.meridian, -30, 0);
    CHECK_NEAR(w.tz_hours, 2, 1e-12);
    CHECK(w.units == 1 && !w.is_epw);
    CHECK(w.rec[1].month == 1 && w.rec[1].day == 1 && w.rec[1].hour == 12.5 && w.rec[1].v1 == 800 && w.rec[1].v2 == 100);
    CHECK(w.rec[2].line == 10 && w.rec[2].month == 2 && w.rec[2].day == 29);
    CHECK(isnan(hd_weather_dewpoint(&w, 0)));
    hd_weather_free(&w);
}

static void expect_error(const char *text, const char *what)
{
    hd_weather w;
    hd_status st = parse(text, &w);
    CHECK(st == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), what);
    CHECK(w.n == 0 && w.rec == NULL);
}

static void test_wea_bad(void)
{
    expect_error(WEAHDR "1 1 0.5 0\n", "t.wea: line 7: missing column 5");
    expect_error(WEAHDR "1 1 0.5 0 0\n1 1\n", "t.wea: line 8: missing column 3 (hour)");
    expect_error(WEAHDR "1 1 0.5 x 0\n", "t.wea: line 7: column 4 (first value): expected a number, found 'x'");
    expect_error(WEAHDR "1 1 0.5 0 1e999\n", "line 7: column 5");
    expect_error(WEAHDR "1 1 24.5 0 0\n", "t.wea: line 7: hour 24.5 out of range");
    expect_error(WEAHDR "1 1 -1 0 0\n", "line 7: hour -1 out of range");
    expect_error(WEAHDR "13 1 1 0 0\n", "line 7: month 13 out of range");
    expect_error(WEAHDR "2 30 1 0 0\n", "line 7: day 30 out of range 1..29");
    expect_error(WEAHDR "1.5 1 1 0 0\n", "line 7: month and day must be integers");
    expect_error("LOCATIONS x\n", "t.wea: line 1: wrong header");
    expect_error("", "t.wea: line 1: empty file");
    expect_error("place X\nlatitude 40\nlongitude 0\ntimezone 0\n", "t.wea: line 4: wrong WEA header: expected 'time_zone");
    expect_error("place X\nlatitude north\n", "line 2: latitude: expected a number");
    expect_error("place X\nlatitude 40\nlongitude 0\n", "line 4: unexpected end of file, expected 'time_zone'");
    expect_error("place X\nlatitude 40\nlongitude 0\ntime_zone 0\nsite_elevation 0\nweather_data_file_units 4\n",
                 "line 6: weather_data_file_units 4 not 1, 2 or 3");
    expect_error("place X\nlatitude 100\nlongitude 0\ntime_zone 0\nsite_elevation 0\nweather_data_file_units 1\n1 1 1 0 0\n",
                 "latitude 100 out of range");
    expect_error(WEAHDR, "no weather records");
}

#define EPWHDR(dp) "LOCATION,Izmir,,TUR,test,0,38.40,27.10,2.0,25.0\nDESIGN CONDITIONS,0\nTYPICAL/EXTREME PERIODS,0\n" \
    "GROUND TEMPERATURES,0\nHOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0\nCOMMENTS 1,\"a, b\"\nCOMMENTS 2,\nDATA PERIODS,1,1,Data,Sunday," dp "\n"
#define EPWREC(h, dew, dni, dhi) "2015,1,1," h ",0,?9,5," dew ",80,100000,0,0,300,150," dni "," dhi ",999999,999999,999999\n"

static hd_status parse_epw(const char *text, hd_weather *w)
{
    return hd_weather_read_memory(text, strlen(text), "t.epw", w);
}

static void test_epw(void)
{
    hd_weather w;
    /* header dates with a year (2015/12/31) are accepted (MANIFEST quirk) */
    REQUIRE(parse_epw(EPWHDR("2015/ 1/ 1,2015/12/31") EPWREC("1", "2", "0", "0") EPWREC("2", "4", "10", "20")
                      EPWREC("3", "9", "30", "40") EPWREC("4", "3", "50", "60"), &w) == HD_OK);
    CHECK(w.n == 4 && w.is_epw);
    CHECK_STR(w.place, "Izmir_TUR");
    CHECK_NEAR(w.site.lon, -27.1, 1e-12);
    CHECK_NEAR(w.site.meridian, -30, 1e-12);
    CHECK_NEAR(w.rec[0].hour, 0.5, 0);
    CHECK_NEAR(w.rec[3].hour, 3.5, 0);
    CHECK(w.rec[2].v1 == 30 && w.rec[2].v2 == 40 && w.rec[2].year == 2015 && w.rec[2].line == 11);
    CHECK(isnan(w.rec[0].dni_lux));
    /* dew point: mean of this and up to two previous records */
    CHECK_NEAR(hd_weather_dewpoint(&w, 0), 2, 1e-12);
    CHECK_NEAR(hd_weather_dewpoint(&w, 1), 3, 1e-12);
    CHECK_NEAR(hd_weather_dewpoint(&w, 3), (4 + 9 + 3) / 3.0, 1e-12);
    hd_weather_free(&w);
    REQUIRE(parse_epw(EPWHDR(" 1/ 1,12/31") EPWREC("24", "2", "0", "0"), &w) == HD_OK);
    CHECK_NEAR(w.rec[0].hour, 23.5, 0);
    hd_weather_free(&w);
    /* sub-hourly data: hour - 1 + minute/60 */
    const char *sub = "LOCATION,Izmir,,TUR,test,0,38.40,27.10,2.0,25.0\nDESIGN CONDITIONS,0\nTYPICAL/EXTREME PERIODS,0\n"
        "GROUND TEMPERATURES,0\nHOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0\nCOMMENTS 1,\nCOMMENTS 2,\nDATA PERIODS,1,4,Data,Sunday,1/1,12/31\n"
        "2015,1,1,13,15,?9,5,2,80,100000,0,0,300,150,10,20\n2015,1,1,13,60,?9,5,2,80,100000,0,0,300,150,10,20\n";
    REQUIRE(parse_epw(sub, &w) == HD_OK);
    CHECK(w.records_per_hour == 4);
    CHECK_NEAR(w.rec[0].hour, 12.25, 1e-12);
    CHECK_NEAR(w.rec[1].hour, 13.0, 1e-12);
    hd_weather_free(&w);

    CHECK(parse_epw(EPWHDR("1/1,13/40") EPWREC("1", "2", "0", "0"), &w) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "t.epw: line 8: DATA PERIODS: bad date");
    CHECK(parse_epw(EPWHDR("1/1,12/31") EPWREC("25", "2", "0", "0"), &w) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "t.epw: line 9: hour 25 out of range 1..24");
    CHECK(parse_epw(EPWHDR("1/1,12/31") EPWREC("0", "2", "0", "0"), &w) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "line 9: hour 0 out of range");
    CHECK(parse_epw(EPWHDR("1/1,12/31") EPWREC("1", "2", "abc", "0"), &w) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "t.epw: line 9: field 15 (direct normal radiation): expected a number, found 'abc'");
    CHECK(parse_epw(EPWHDR("1/1,12/31") "2015,1,1,1,0,?9,5,3,80\n", &w) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "t.epw: line 9: EPW record has 9 fields, need at least 16");
    CHECK(parse_epw(EPWHDR("1/1,12/31") EPWREC("1", "2", "9999", "0"), &w) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "missing or out of range");
    CHECK(parse_epw("LOCATION,Izmir,,TUR,test,0,38.40,27.10,2.0,25.0\nDESIGN CONDITIONS,0\nCOMMENTS 1,\n", &w) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "t.epw: line 3: wrong EPW header: expected 'TYPICAL/EXTREME PERIODS");
    CHECK(parse_epw("LOCATION,Izmir,,TUR,test,0,north,27.10,2.0,25.0\n", &w) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "t.epw: line 1: LOCATION field 7 (latitude)");
    CHECK(parse_epw("LOCATION,Izmir,TUR\n", &w) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "line 1: LOCATION line has 3 fields");
    CHECK(parse_epw(EPWHDR("1/1,12/31"), &w) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "no weather records");
}

/* epw2wea output equals Radiance's for both reference EPW files */
static void test_epw2wea_reference(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder");
    static const char *sites[2] = {"chicago", "mannheim"};
    for (int s = 0; s < 2; s++) {
        char epw[512], wea[512], out[512];
        snprintf(epw, sizeof epw, "%.200s/weather/%s.epw", ref, sites[s]);
        snprintf(wea, sizeof wea, "%.200s/sky/wea/%s.wea", ref, sites[s]);
        snprintf(out, sizeof out, "%.200s/weather_%s.wea", hd_test_tmpdir(), sites[s]);
        hd_weather w, r;
        REQUIRE(hd_weather_read(epw, &w) == HD_OK);
        CHECK(w.n == 8760);
        FILE *fp = fopen(out, "w");
        REQUIRE(fp);
        CHECK(hd_weather_write_wea(fp, &w) == HD_OK);
        fclose(fp);
        FILE *a = fopen(out, "rb"), *b = fopen(wea, "rb");
        REQUIRE(a && b);
        int same = 1, ca, cb;
        long off = 0;
        do { ca = getc(a); cb = getc(b); if (ca != cb) same = 0; off++; } while (same && ca != EOF);
        fclose(a);
        fclose(b);
        CHECK_MSG(same, "%s: epw2wea output differs from %s at byte %ld", out, wea, off);
        /* and the WEA reader gives back the same records */
        REQUIRE(hd_weather_read(wea, &r) == HD_OK);
        CHECK(r.n == w.n);
        int bad = 0;
        for (size_t i = 0; i < r.n && i < w.n; i++)
            if (r.rec[i].month != w.rec[i].month || r.rec[i].day != w.rec[i].day ||
                fabs(r.rec[i].hour - w.rec[i].hour) > 1e-9 || fabs(r.rec[i].v1 - w.rec[i].v1) > 0.5 ||
                fabs(r.rec[i].v2 - w.rec[i].v2) > 0.5) bad++;
        CHECK(bad == 0);
        CHECK_NEAR(r.site.lon, w.site.lon, 1e-9);
        CHECK_NEAR(r.site.meridian, w.site.meridian, 1e-9);
        hd_weather_free(&w);
        hd_weather_free(&r);
    }
}


/* genwea: deterministic synthetic year */
static void test_synth(void)
{
    hd_synth_opts o;
    hd_synth_opts_default(&o);
    o.site = (hd_site){38.4, -27.1, -30, 25};   /* Izmir, UTC+2 standard meridian */
    o.name = "Izmir";
    hd_weather a, b, c;
    REQUIRE(hd_weather_synth(&a, &o) == HD_OK);
    REQUIRE(hd_weather_synth(&b, &o) == HD_OK);
    o.seed = 2;
    REQUIRE(hd_weather_synth(&c, &o) == HD_OK);
    REQUIRE(a.n == 8760 && b.n == 8760 && c.n == 8760);
    CHECK(!strncmp(a.place, "SYNTHETIC_", 10));
    int same = 1, differ = 0;
    for (size_t i = 0; i < a.n; i++) {
        if (a.rec[i].v1 != b.rec[i].v1 || a.rec[i].v2 != b.rec[i].v2 || a.rec[i].hour != b.rec[i].hour) same = 0;
        if (a.rec[i].v1 != c.rec[i].v1) differ++;
    }
    CHECK(same);
    CHECK(differ > 1000);
    /* annual sums (kWh/m2) in the range of Izmir's measured climate
     * (GHI ~1700-1800, DNI ~1800-2100 kWh/m2/yr) */
    double ghi = 0, dni = 0, dhi = 0, jan = 0, jul = 0;
    int day_bad = 0, night_bad = 0, over = 0, daylight = 0;
    for (size_t i = 0; i < a.n; i++) {
        const hd_weather_rec *r = &a.rec[i];
        hd_sunpos sp;
        hd_sun_position(&a.site, hd_julian_day(r->month, r->day), r->hour, 0, &sp);
        double g = r->v1 * fmax(0, sin(sp.alt)) + r->v2;
        if (sp.alt <= 0 && (r->v1 > 0 || r->v2 > 0)) night_bad++;
        if (sp.alt > 2 * HD_PI / 180 && g <= 0) day_bad++;
        if (sp.alt > 0) {
            daylight++;
            double cg, cn, cd;
            hd_clear_sky(sp.alt, hd_julian_day(r->month, r->day), 25, 2.5, &cg, &cn, &cd);
            if (g > 1.02 * cg + 1 || r->v1 > cn + 1) over++;
        }
        ghi += g; dni += r->v1; dhi += r->v2;
        if (r->month == 1) jan += g;
        if (r->month == 7) jul += g;
    }
    printf("  synthetic Izmir: GHI %.0f, DNI %.0f, DHI %.0f kWh/m2; %d daylight hours; July/January GHI %.2f\n",
           ghi / 1000, dni / 1000, dhi / 1000, daylight, jul / jan);
    CHECK(ghi / 1000 > 1500 && ghi / 1000 < 2000);
    CHECK(dni / 1000 > 1500 && dni / 1000 < 2400);
    CHECK(dhi / 1000 > 400 && dhi / 1000 < 900);
    CHECK(jul > 2.5 * jan);
    CHECK(night_bad == 0);      /* daylight hours follow the solar position */
    CHECK(day_bad == 0);
    CHECK(over == 0);           /* never above a very clear sky (TL 2.5) */
    CHECK(daylight > 4300 && daylight < 4500);   /* ~12 h a day on average */
    /* WEA round trip */
    char path[512];
    snprintf(path, sizeof path, "%.400s/synth.wea", hd_test_tmpdir());
    FILE *fp = fopen(path, "w");
    REQUIRE(fp);
    CHECK(hd_weather_write_wea(fp, &a) == HD_OK);
    fclose(fp);
    hd_weather r;
    REQUIRE(hd_weather_read(path, &r) == HD_OK);
    CHECK(r.n == 8760 && !strcmp(r.place, a.place));
    CHECK_NEAR(r.site.lon, -27.1, 1e-9);
    CHECK_NEAR(r.site.meridian, -30, 1e-9);
    hd_weather_free(&r);
    hd_weather_free(&a); hd_weather_free(&b); hd_weather_free(&c);
    /* bad options */
    o.site.lat = 95;
    CHECK(hd_weather_synth(&a, &o) == HD_ERR_RANGE);
    CHECK_CONTAINS(hd_errmsg(), "site out of range");
    o.site.lat = 38.4;
    o.tl_mean = 0.5;
    CHECK(hd_weather_synth(&a, &o) == HD_ERR_RANGE);
    CHECK_CONTAINS(hd_errmsg(), "Linke turbidity");
}

static void test_clear_sky(void)
{
    double g, n, d;
    hd_clear_sky(-0.1, 100, 0, 3, &g, &n, &d);
    CHECK(g == 0 && n == 0 && d == 0);
    hd_clear_sky(HD_PI / 2, 172, 0, 3, &g, &n, &d);
    /* high sun, moderate turbidity: ~1000 W/m2 global, ~850-950 direct */
    CHECK(g > 950 && g < 1100);
    CHECK(n > 800 && n < 1000);
    CHECK_NEAR(g, n + d, 1e-9);
    double g2, n2, d2;
    hd_clear_sky(HD_PI / 2, 172, 0, 6, &g2, &n2, &d2);
    CHECK(n2 < n && d2 > d);   /* more turbid: less direct, more diffuse */
}

int main(void)
{
    RUN(test_wea_ok);
    RUN(test_wea_bad);
    RUN(test_epw);
    RUN(test_epw2wea_reference);
    RUN(test_synth);
    RUN(test_clear_sky);
    return hd_test_done();
}

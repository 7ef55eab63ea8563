/* Unit tests for the Perez model and sky-matrix columns (sky.h), with
 * value-by-value comparisons against Radiance's gendaymtx references. */
#include <math.h>
#include <stdint.h>

#include "hd_test.h"
#include "heliodon/sky.h"
#include "heliodon/weather.h"

static void test_perez_basics(void)
{
    CHECK(hd_perez_category(1.0) == 0);
    CHECK(hd_perez_category(1.064) == 0);
    CHECK(hd_perez_category(1.065) == 1);
    CHECK(hd_perez_category(6.2) == 7);
    CHECK(hd_perez_category(11.9) == 7);
    /* Kasten air mass: 1 at the zenith, ~2 at 60 deg */
    CHECK_NEAR(hd_air_mass(0), 1.0 / (1 + 0.15 * pow(93.885, -1.253)), 1e-12);
    CHECK_REL(hd_air_mass(HD_PI / 3), 1.995, 0.005);
    CHECK_REL(hd_eccentricity(1), 1.0350, 0.001);   /* perihelion in January */
    CHECK_REL(hd_eccentricity(182), 0.9666, 0.002);
    /* a clear sky is brighter near the sun than opposite to it, and an
     * overcast sky (eps = 1) brighter at the zenith than at the horizon */
    hd_perez p;
    hd_perez_compute(&p, 40 * HD_PI / 180, 172, 800, 100, 1, NAN, 0);
    CHECK(p.category >= 6);
    CHECK(hd_perez_rel_lum(&p, HD_PI / 4, 0.1) > 5 * hd_perez_rel_lum(&p, HD_PI / 4, 2.5));
    CHECK(p.dir_illum > 800 * 80 && p.dir_illum < 800 * 110);     /* efficacy 80..110 lm/W */
    CHECK(p.diff_illum > 100 * 100 && p.diff_illum < 100 * 150);
    hd_perez_compute(&p, 40 * HD_PI / 180, 172, 0, 200, 1, NAN, 0);
    CHECK(p.category == 0 && p.epsilon == 1);
    CHECK(hd_perez_rel_lum(&p, 0, 1) > 1.2 * hd_perez_rel_lum(&p, 1.5, 1));
    /* -O1: 179 lm/W for both */
    hd_perez_compute(&p, 40 * HD_PI / 180, 172, 500, 200, 1, NAN, 1);
    CHECK_NEAR(p.dir_illum, 500 * 179, 1e-9);
    CHECK_NEAR(p.diff_illum, 200 * 179, 1e-9);
    /* precipitable water from the dew point; default 11 C */
    CHECK_NEAR(p.precip_water, exp(0.07 * 11 - 0.075), 1e-12);
    /* units 2 (direct horizontal) = units 1 with DNI * sin(alt) */
    hd_perez q;
    hd_perez_compute(&p, 30 * HD_PI / 180, 100, 600, 150, 1, 5, 0);
    hd_perez_compute(&q, 30 * HD_PI / 180, 100, 300, 150, 2, 5, 0);
    CHECK_REL(q.dir_illum, p.dir_illum, 1e-9);
    /* units 3 (illuminances) inverts the efficacies */
    hd_perez_compute(&q, 30 * HD_PI / 180, 100, p.dir_illum, p.diff_illum, 3, 5, 0);
    CHECK_NEAR(q.dni, 600, 10);
    CHECK_NEAR(q.dhi, 150, 10);   /* Radiance stops iterating below 10 W/m2 changes */
}

static void test_column_analytic(void)
{
    hd_skybasis b;
    REQUIRE(hd_skybasis_init(&b, 2) == HD_OK);
    hd_daymtx_opts o;
    hd_daymtx_opts_default(&o);
    hd_site site = {38.4, -27.1, -30, 0};
    double *col = malloc(sizeof(double) * 3 * b.nbins);
    REQUIRE(col);
    hd_daymtx_step t = {172, 11.5, 700, 150, 1, NAN};
    hd_daymtx_info inf;
    o.sky_only = 1;
    hd_daymtx_column(&b, &o, &site, &t, col, &inf);
    /* the sky patches integrate to the diffuse horizontal illuminance */
    double e = 0;
    for (int i = 1; i < b.nbins; i++) e += col[3 * i + 1] * sin(b.alt[i]) * b.omega[i];
    CHECK_REL(e * 179 / o.skycolor[1], inf.diff_illum, 1e-9);
    /* the ground: (diffuse + direct horizontal)/pi/179 * reflectance */
    CHECK_REL(col[0], (inf.diff_illum + inf.dir_illum * sin(inf.alt)) / HD_PI / 179 * 0.2, 1e-12);
    /* sun only: the 4 patches nearest the sun carry DNI-illuminance */
    o.sky_only = 0;
    o.sun_only = 1;
    hd_daymtx_column(&b, &o, &site, &t, col, &inf);
    int nz = 0;
    double en = 0;
    for (int i = 0; i < b.nbins; i++)
        if (col[3 * i] > 0) { nz++; en += col[3 * i] * b.omega[i]; }
    CHECK(nz == 4);
    CHECK_REL(en * 179, inf.dir_illum, 1e-9);
    /* -5: one patch, radiance of the 0.533 deg disk */
    o.disk_deg = 0.533;
    hd_daymtx_column(&b, &o, &site, &t, col, &inf);
    nz = 0;
    for (int i = 0; i < b.nbins; i++)
        if (col[3 * i] > 0) {
            nz++;
            CHECK_REL(col[3 * i] * 179 * HD_PI * pow(0.2665 * HD_PI / 180, 2), inf.dir_illum, 1e-9);
        }
    CHECK(nz == 1);
    /* night: all zero */
    hd_daymtx_step night = {172, 0.5, 0, 0, 1, NAN};
    o.disk_deg = 0;
    o.sun_only = 0;
    hd_daymtx_column(&b, &o, &site, &night, col, &inf);
    int allzero = 1;
    for (int i = 0; i < 3 * b.nbins; i++) if (col[i] != 0) allzero = 0;
    CHECK(allzero && inf.night);
    free(col);
    hd_skybasis_free(&b);
}

/* MANIFEST quirks 5 and 13: direct sun with the sun below the horizon
 * lands in the lowest patch row and raises a warning flag; Feb 29. */
static void test_quirks(void)
{
    hd_skybasis b;
    REQUIRE(hd_skybasis_init(&b, 1) == HD_OK);
    hd_daymtx_opts o;
    hd_daymtx_opts_default(&o);
    o.sun_only = 1;
    hd_site mannheim = {49.52, -8.55, -15, 96};
    double col[3 * 146];
    hd_daymtx_info inf;
    hd_daymtx_step t = {22, 17.5, 22, 0, 1, NAN};     /* Jan 22 17:30: sun below the horizon */
    hd_daymtx_column(&b, &o, &mannheim, &t, col, &inf);
    CHECK(inf.alt < -2 * HD_PI / 180);
    CHECK(inf.bright_below);
    int nz = 0, low = 1;
    for (int i = 1; i < 146; i++)
        if (col[3 * i] > 0) { nz++; if (i > 30) low = 0; }
    CHECK(nz == 4 && low);
    CHECK(col[0] == 0);
    /* DNI <= 20: no warning */
    t.v1 = 15;
    hd_daymtx_column(&b, &o, &mannheim, &t, col, &inf);
    CHECK(!inf.bright_below);
    hd_skybasis_free(&b);
    /* Feb 29 maps to day 60 and shifts the rest of that year */
    hd_weather w;
    const char *txt = "place X\nlatitude 40\nlongitude 0\ntime_zone 0\nsite_elevation 0\nweather_data_file_units 1\n"
                      "2 28 12 0 0\n2 29 12 0 0\n3 1 12 0 0\n12 31 12 0 0\n1 1 12 0 0\n3 1 12 0 0\n";
    REQUIRE(hd_weather_read_memory(txt, strlen(txt), "leap.wea", &w) == HD_OK);
    int jd[6];
    hd_daymtx_julian_days(&w, jd);
    CHECK(jd[0] == 59 && jd[1] == 60 && jd[2] == 61 && jd[3] == 366 && jd[4] == 1 && jd[5] == 60);
    hd_weather_free(&w);
}

/* read a reference matrix (float or ascii, gzip allowed) */
static float *read_ref(const char *path, int *nr, int *nc)
{
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "gzip -dcf '%s'", path);
    FILE *f = popen(cmd, "r");
    if (!f) return NULL;
    char line[4096];
    int ascii = 0;
    *nr = *nc = 0;
    while (fgets(line, sizeof line, f) && line[0] != '\n') {
        sscanf(line, "NROWS=%d", nr);
        sscanf(line, "NCOLS=%d", nc);
        if (strstr(line, "FORMAT=ascii")) ascii = 1;
    }
    size_t n = (size_t)*nr * (size_t)*nc * 3;
    float *d = n ? malloc(n * sizeof(float)) : NULL;
    size_t got = 0;
    if (d) {
        if (ascii) { while (got < n && fscanf(f, "%f", &d[got]) == 1) got++; }
        else got = fread(d, sizeof(float), n, f);
    }
    pclose(f);
    if (got != n) { free(d); return NULL; }
    return d;
}

static void compare(const char *refdir, const char *weather, const char *mtx, int mf, const char *flags)
{
    char wpath[600], mpath[600];
    snprintf(wpath, sizeof wpath, "%.300s/%s", refdir, weather);
    snprintf(mpath, sizeof mpath, "%.300s/sky/daymtx/%s", refdir, mtx);
    hd_weather w;
    REQUIRE(hd_weather_read(wpath, &w) == HD_OK);
    hd_daymtx_job job;
    memset(&job, 0, sizeof job);
    hd_daymtx_opts_default(&job.o);
    job.mf = mf;
    job.nthreads = 2;
    if (strchr(flags, 'd')) job.o.sun_only = 1;
    if (strchr(flags, '5')) job.o.disk_deg = 0.533;
    hd_daymtx_result r;
    REQUIRE(hd_daymtx_generate(&w, &job, &r) == HD_OK);
    int nr, nc;
    float *ref = read_ref(mpath, &nr, &nc);
    REQUIRE(ref);
    REQUIRE(nr == r.nbins && nc == r.ncols);
    long outside = 0;
    double worst = 0, worst_sum = 0;
    for (int c = 0; c < nc; c++)
        for (int k = 0; k < 3; k++) {
            double mx = 0, sa = 0, sb = 0;
            for (int p = 0; p < nr; p++) {
                double v = ref[((size_t)p * nc + c) * 3 + k];
                if (v > mx) mx = v;
            }
            for (int p = 0; p < nr; p++) {
                size_t at = ((size_t)p * nc + c) * 3 + k;
                double a = r.data[at], bv = ref[at];
                sa += a;
                sb += bv;
                if (bv > 1e-3 * mx) {
                    double e = fabs(a - bv) / bv;
                    if (e > worst) worst = e;
                    if (e > 0.005) outside++;
                } else if (fabs(a - bv) > 1e-3 * mx + 1e-6) outside++;
            }
            if (sb > 0 && fabs(sa - sb) / sb > worst_sum) worst_sum = fabs(sa - sb) / sb;
        }
    printf("  %s: %dx%d, worst element %.4f%%, worst column sum %.4f%%, %ld outside 0.5%%\n", mtx, nr, nc,
           100 * worst, 100 * worst_sum, outside);
    CHECK(outside == 0);
    CHECK(worst_sum <= 0.001);
    free(ref);
    hd_daymtx_result_free(&r);
    hd_weather_free(&w);
}

static void test_reference_year(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder");
    compare(ref, "weather/chicago.epw", "chicago_year_mf1.mtx.gz", 1, "");
    compare(ref, "weather/mannheim.epw", "mannheim_year_mf1.mtx.gz", 1, "");
}

static void test_reference_mf4_mf6(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder");
    compare(ref, "sky/wea/chicago_0101-0107.wea", "chicago_0101-0107_mf4.mtx.gz", 4, "");
    compare(ref, "sky/wea/mannheim_0101-0107.wea", "mannheim_0101-0107_mf4.mtx.gz", 4, "");
    compare(ref, "sky/wea/chicago_0621-0623.wea", "chicago_0621-0623_mf6_5.mtx.gz", 6, "5");
    compare(ref, "sky/wea/mannheim_0614-0616.wea", "mannheim_0614-0616_mf6_5.mtx.gz", 6, "5");
    compare(ref, "sky/wea/mannheim_sel.wea", "mannheim_sel_mf6.mtx", 6, "");
    compare(ref, "sky/wea/chicago_sel.wea", "chicago_sel_mf6.mtx", 6, "");
}


/* genskyvec: all reference commands of the manifest.  Radiance averages 16
 * pseudo-random rays per patch, so a patch value carries a sampling error
 * of about sigma/4 (sigma = spread of the sky function over the patch);
 * each patch must lie within 3 % or within 4.5 of those standard errors,
 * the total within 0.5 % or 6 standard errors of the sum (a sum of a few
 * heavy-tailed circumsolar terms); the sun part of a patch (computed
 * exactly by Radiance) within 0.2 % plus the sky's sampling error. */
static char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *b = malloc((size_t)n + 1);
    if (b && fread(b, 1, (size_t)n, f) != (size_t)n) { free(b); b = NULL; }
    if (b) b[n] = 0;
    fclose(f);
    if (len) *len = (size_t)n;
    return b;
}

/* genskyvec against Radiance's genskyvec.pl outputs.  nsamp 0 (the
 * default): Radiance's own 16 fixed rays per patch, checked with the
 * issue's criteria exactly: every patch above 1e-3 of the maximum within
 * 3 %, the others within 1e-3 of the maximum, totals within 0.5 %.
 * nsamp 8: our stratified 8x8 integral, which can only agree within
 * Radiance's sampling error (3 % or 4.5 standard errors of a 16-ray mean). */
static void skyvec_reference(int nsamp)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder");
    char path[1024];
    snprintf(path, sizeof path, "%.900s/sky/manifest.json", ref);
    char *man = slurp(path, NULL);
    if (!man) SKIP("no %s", "sky/manifest.json");
    int ncases = 0, nfail = 0;
    long npatch = 0, nplain = 0;
    double worst_sig = 0, worst_tot = 0, worst_rel = 0;
    for (char *c = strstr(man, "\"command\": \"genskyvec "); c; c = strstr(c + 1, "\"command\": \"genskyvec ")) {
        char cmd[512];
        char *q = c + 12, *e = strchr(q, '"');
        if (!e || e - q >= (long)sizeof cmd) continue;
        memcpy(cmd, q, (size_t)(e - q));
        cmd[e - q] = 0;
        int mf = 4, sun_only = strstr(cmd, " -d ") != NULL, five = strstr(cmd, " -5") != NULL;
        char *m = strstr(cmd, "-m ");
        if (m) mf = atoi(m + 3);
        char in[256], out[256];
        char *lt = strchr(cmd, '<'), *gt = strchr(cmd, '>');
        if (!lt || !gt || sscanf(lt + 1, "%255s", in) != 1 || sscanf(gt + 1, "%255s", out) != 1) continue;
        char ip[1024], op[1024];
        snprintf(ip, sizeof ip, "%.700s/sky/%s", ref, in);
        snprintf(op, sizeof op, "%.700s/sky/%s", ref, out);
        char *desc = slurp(ip, NULL), *vec = slurp(op, NULL);
        REQUIRE(desc && vec);
        hd_skydesc d;
        REQUIRE(hd_skydesc_parse(desc, in, &d) == HD_OK);
        hd_skybasis b;
        REQUIRE(hd_skybasis_init(&b, mf) == HD_OK);
        double *v = malloc(sizeof(double) * 3 * b.nbins), *sd = malloc(sizeof(double) * b.nbins);
        REQUIRE(v && sd);
        hd_skyvec_opts o = {{0.960, 1.004, 1.118}, sun_only, five, nsamp, sd};
        REQUIRE(hd_skyvec_compute(&b, &d, &o, v) == HD_OK);
        /* the same without the sun, to know which patches received it */
        double *vs = malloc(sizeof(double) * 3 * b.nbins);
        REQUIRE(vs);
        hd_skydesc dn = d;
        dn.has_sun = 0;
        REQUIRE(hd_skyvec_compute(&b, &dn, &o, vs) == HD_OK);
        char *p = strstr(vec, "\n\n");
        REQUIRE(p);
        p += 2;
        int bad = 0;
        double mx = 0, sa = 0, sb = 0, var = 0;
        double *r = malloc(sizeof(double) * 3 * b.nbins);
        REQUIRE(r);
        for (int i = 0; i < 3 * b.nbins; i++) {
            char *end;
            r[i] = strtod(p, &end);
            if (end == p) { bad = 1; break; }
            p = end;
            if (r[i] > mx) mx = r[i];
        }
        CHECK_MSG(!bad, "%s: short reference", out);
        for (int i = 0; i < b.nbins && !bad; i++)
            for (int k = 0; k < 3; k++) {
                double a = v[3 * i + k], y = r[3 * i + k];
                double se = sd[i] * o.skycolor[k] / 4;
                int sunpatch = a != vs[3 * i + k];
                sa += a;
                sb += y;
                var += se * se;
                double tol = nsamp <= 0 ? 0.03 * y : sunpatch ? 0.002 * y + 4.5 * se : fmax(0.03 * y, 4.5 * se);
                if (y > 1e-3 * mx) {
                    npatch++;
                    if (fabs(a - y) <= 0.03 * y) nplain++;
                    if (fabs(a - y) / y > worst_rel) worst_rel = fabs(a - y) / y;
                    if (se > 0 && fabs(a - y) / se > worst_sig && fabs(a - y) > 0.03 * y) worst_sig = fabs(a - y) / se;
                } else tol = 1e-3 * mx + (nsamp <= 0 ? 0 : 4.5 * se);
                if (fabs(a - y) > tol + 1e-9) {
                    if (!bad) printf("  %s: patch %d comp %d: %g vs %g (se %g)\n", out, i, k, a, y, se);
                    bad = 1;
                }
            }
        double tot = sb > 0 ? fabs(sa - sb) / sb : fabs(sa);
        if (tot > worst_tot) worst_tot = tot;
        if (tot > 0.005 && (nsamp <= 0 || fabs(sa - sb) > 6 * sqrt(var))) {
            printf("  %s: total %g vs %g\n", out, sa, sb);
            bad = 1;
        }
        ncases++;
        nfail += bad;
        free(r); free(v); free(vs); free(sd); free(desc); free(vec);
        hd_skybasis_free(&b);
    }
    free(man);
    if (nsamp <= 0)
        printf("  genskyvec (Radiance's 16 rays): %d reference vectors, %d failed; worst patch above 1e-3 of the "
               "maximum %.4f%% (%ld patches), worst total %.5f%%\n",
               ncases, nfail, 100 * worst_rel, npatch, 100 * worst_tot);
    else
        printf("  genskyvec (%dx%d stratified): %d reference vectors, %d failed; %.1f%% of %ld patches within 3%% "
               "plainly, the rest within %.2f standard errors of Radiance's 16-ray estimate; worst total %.3f%%\n",
               nsamp, nsamp, ncases, nfail, 100.0 * nplain / (npatch ? npatch : 1), npatch, worst_sig, 100 * worst_tot);
    CHECK(ncases >= 90);
    CHECK(nfail == 0);
}


static void test_skyvec_reference(void) { skyvec_reference(0); }
static void test_skyvec_stratified(void) { skyvec_reference(8); }

/* -i: a step whose interval contains sunrise/sunset moves to the middle of
 * its sunlit part; other steps keep their time */
static void test_interval(void)
{
    hd_site site = {41.98, 87.92, 90, 0};
    hd_daymtx_opts o;
    hd_daymtx_opts_default(&o);
    int jd = 172;
    double rise, set;
    hd_sun_rise_set(&site, jd, &rise, &set);
    double adj = hd_sun_time_adjust(&site, jd);
    double h = rise - 0.3 - adj;   /* standard time whose solar time is 18 min before sunrise */
    CHECK_NEAR(hd_daymtx_solar_time(&site, &o, jd, h), rise - 0.3, 1e-12);
    o.interval_min = 60;
    double st = hd_daymtx_solar_time(&site, &o, jd, h);
    CHECK_NEAR(st, (rise - 0.3 + 0.5 + rise) / 2, 1e-12);
    CHECK(hd_sun_altitude(&site, hd_sun_declination(jd), st) > 0);
    double h2 = set + 0.2 - adj;
    st = hd_daymtx_solar_time(&site, &o, jd, h2);
    CHECK_NEAR(st, (set + 0.2 - 0.5 + set) / 2, 1e-12);
    CHECK(hd_sun_altitude(&site, hd_sun_declination(jd), st) > 0);
    CHECK_NEAR(hd_daymtx_solar_time(&site, &o, jd, 12.0), 12.0 + adj, 1e-12);
}

/* the fast %.3g formatter of gendaymtx's ascii output against the C
 * library's printf: every float tried must give the same characters */
static void test_format_g3(void)
{
    char a[64], b[64];
    long bad = 0, n = 0;
    static const double fixed[] = {0.0, -0.0, 1, 9.995, 9.9949999, 999.5, 999.4999, 1000, 99.95, 0.0001, 0.00009995,
                                   1.125, 1.135, 0.125, 2.5e-5, 1e-5, 123456, 1e20, 3e-21, -4.56e-3, 0.5, 100, 0.1};
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++) {
        size_t l = hd_format_g3(a, fixed[i]);
        snprintf(b, sizeof b, "%.3g", fixed[i]);
        if (strcmp(a, b) || l != strlen(b)) {
            if (bad++ < 5) printf("  %.17g: '%s' vs printf '%s'\n", fixed[i], a, b);
        }
        n++;
    }
    /* random float bit patterns over the whole positive range, and floats
     * just around every 3-digit rounding tie of a few decades */
    uint32_t x = 12345;
    for (int i = 0; i < 2000000; i++) {
        x = x * 1664525u + 1013904223u;
        uint32_t bits = x & 0x7fffffffu;
        float f;
        memcpy(&f, &bits, sizeof f);
        if (!isfinite(f)) continue;
        hd_format_g3(a, f);
        snprintf(b, sizeof b, "%.3g", (double)f);
        if (strcmp(a, b) && bad++ < 5) printf("  %.9g: '%s' vs printf '%s'\n", (double)f, a, b);
        n++;
    }
    for (int e = -6; e <= 6; e++)
        for (int d = 1000; d < 10000; d += 10) {
            float f = (float)((d + 5) * pow(10, e - 3));
            for (int k = -3; k <= 3; k++) {
                float g = nextafterf(f, k < 0 ? 0 : INFINITY);
                if (k == 0) g = f;
                for (int j = 1; j < abs(k); j++) g = nextafterf(g, k < 0 ? 0 : INFINITY);
                hd_format_g3(a, g);
                snprintf(b, sizeof b, "%.3g", (double)g);
                if (strcmp(a, b) && bad++ < 5) printf("  %.9g: '%s' vs printf '%s'\n", (double)g, a, b);
                n++;
            }
        }
    printf("  %%.3g formatter: %ld values, %ld differ from printf\n", n, bad);
    CHECK(bad == 0);
}

/* the compact store (gendaymtx's path) holds exactly the floats of
 * hd_daymtx_column, for every column, patch and component, whatever the
 * thread count; its -of / -od / -oa output is the same bytes as writing those
 * floats directly (fwrite / printf "%.3g") */
static void store_case(const hd_weather *w, int mf, int nthreads, const char *what, void (*set)(hd_daymtx_job *))
{
    hd_daymtx_job job;
    memset(&job, 0, sizeof job);
    hd_daymtx_opts_default(&job.o);
    job.mf = mf;
    job.nthreads = nthreads;
    if (set) set(&job);
    hd_daymtx_store s;
    REQUIRE(hd_daymtx_compute(w, &job, &s) == HD_OK);
    hd_skybasis b;
    REQUIRE(hd_skybasis_init(&b, mf) == HD_OK);
    int *jd = malloc(sizeof(int) * w->n);
    double *col = malloc(sizeof(double) * 3 * (size_t)b.nbins);
    float *ref = malloc(sizeof(float) * 3 * (size_t)b.nbins * (size_t)s.ncols);
    float *row = malloc(sizeof(float) * 3 * (size_t)s.ncols);
    REQUIRE(jd && col && ref && row);
    hd_daymtx_julian_days(w, jd);
    for (int c = 0; c < s.ncols; c++) {
        size_t i = s.steps[c];
        hd_daymtx_step t = {jd[i], w->rec[i].hour, w->rec[i].v1, w->rec[i].v2, w->units, hd_weather_dewpoint(w, i)};
        hd_daymtx_column(&b, &job.o, &w->site, &t, col, NULL);
        for (int p = 0; p < b.nbins; p++)
            for (int k = 0; k < 3; k++) ref[((size_t)p * s.ncols + c) * 3 + k] = (float)col[3 * p + k];
    }
    long bad = 0;
    for (int p = 0; p < s.nbins; p++) {
        hd_daymtx_store_row(&s, p, row);
        if (memcmp(row, ref + (size_t)p * s.ncols * 3, sizeof(float) * 3 * (size_t)s.ncols)) bad++;
    }
    CHECK_MSG(bad == 0, "%s: %ld rows differ from hd_daymtx_column", what, bad);
    /* the three output formats */
    const char *tmp = hd_test_tmpdir();
    char pa[1024], pb[1024];
    snprintf(pa, sizeof pa, "%.900s/store_a.out", tmp);
    snprintf(pb, sizeof pb, "%.900s/store_b.out", tmp);
    for (int f = 0; f < 3; f++) {
        FILE *fa = fopen(pa, "wb"), *fb = fopen(pb, "wb");
        REQUIRE(fa && fb);
        CHECK(hd_daymtx_store_write(fa, &s, f == 0 ? HD_DAYMTX_ASCII : f == 1 ? HD_DAYMTX_FLOAT : HD_DAYMTX_DOUBLE) ==
              HD_OK);
        size_t nc = (size_t)s.ncols;
        for (int p = 0; p < s.nbins; p++) {
            const float *d = ref + (size_t)p * nc * 3;
            if (f == 0) {
                for (size_t c = 0; c < nc; c++) fprintf(fb, "%.3g %.3g %.3g\n", d[3 * c], d[3 * c + 1], d[3 * c + 2]);
                if (nc > 1) fputc('\n', fb);
            } else if (f == 1) {
                fwrite(d, sizeof(float), 3 * nc, fb);
            } else {
                for (size_t c = 0; c < 3 * nc; c++) {
                    double v = d[c];
                    fwrite(&v, sizeof v, 1, fb);
                }
            }
        }
        fclose(fa);
        fclose(fb);
        size_t la, lb;
        char *ta = slurp(pa, &la), *tb = slurp(pb, &lb);
        REQUIRE(ta && tb);
        CHECK_MSG(la == lb && !memcmp(ta, tb, la), "%s: format %d output differs (%zu vs %zu bytes)", what, f, la, lb);
        free(ta);
        free(tb);
    }
    printf("  store %s: %dx%d (%zu stored columns), %d threads: identical\n", what, s.nbins, s.ncols, s.nday, nthreads);
    free(jd); free(col); free(ref); free(row);
    hd_skybasis_free(&b);
    hd_daymtx_store_free(&s);
}

static void set_colours(hd_daymtx_job *j)
{
    j->o.skycolor[0] = 1; j->o.skycolor[1] = 0.5; j->o.skycolor[2] = 0.2;
    j->o.grefl[0] = 0.1; j->o.grefl[2] = 0.3;
    j->o.disk_deg = 0.533;
}
static void set_skip_night(hd_daymtx_job *j) { j->skip_night = 1; j->o.rotation_deg = 30; }
static void set_sun_only(hd_daymtx_job *j) { j->o.sun_only = 1; j->o.solar_output = 1; }

static void test_store_exact(void)
{
    hd_synth_opts so;
    hd_synth_opts_default(&so);
    hd_weather w;
    REQUIRE(hd_weather_synth(&w, &so) == HD_OK);
    /* a fortnight in June and one in December (130 columns with a few
     * blocks of 64), then the rest dropped to keep the test short */
    hd_weather sub = w;
    hd_weather_rec *recs = malloc(sizeof *recs * 24 * 28);
    REQUIRE(recs);
    size_t n = 0;
    for (size_t i = 0; i < w.n; i++)
        if ((w.rec[i].month == 6 && w.rec[i].day <= 14) || (w.rec[i].month == 12 && w.rec[i].day >= 18)) recs[n++] = w.rec[i];
    sub.rec = recs;
    sub.n = n;
    store_case(&sub, 1, 1, "MF:1 defaults", NULL);
    store_case(&sub, 2, 2, "MF:2 colours/-5", set_colours);
    store_case(&sub, 1, 2, "MF:1 -u -r 30", set_skip_night);
    store_case(&sub, 1, 3, "MF:1 -d -O1", set_sun_only);
    free(recs);
    hd_weather_free(&w);
}

int main(void)
{
    (void)hd_test_tmpdir;
    RUN(test_perez_basics);
    RUN(test_format_g3);
    RUN(test_column_analytic);
    RUN(test_quirks);
    RUN(test_interval);
    RUN(test_store_exact);
    RUN(test_reference_year);
    RUN(test_reference_mf4_mf6);
    RUN(test_skyvec_reference);
    RUN(test_skyvec_stratified);
    return hd_test_done();
}

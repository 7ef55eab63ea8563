/* heliodon — minimal unit-test harness (header-only).
 *
 *   static void test_foo(void) { CHECK(x == 1); CHECK_NEAR(y, 2.0, 1e-9); }
 *   int main(void) { RUN(test_foo); return hd_test_done(); }
 *
 * Each test prints "PASS: file:name", "FAIL: file:name ..." or
 * "SKIP: file:name: reason"; test/run-tests.sh counts these lines.
 * CHECK* record a failure and continue; REQUIRE* return from the test. */
#ifndef HD_TEST_H
#define HD_TEST_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static int hd_t_failed, hd_t_skipped, hd_t_npass, hd_t_nfail, hd_t_nskip;
static char hd_t_skipmsg[512];

#define HD_T_FAILMSG(...) do { \
    fprintf(stdout, "  %s:%d: ", __FILE__, __LINE__); fprintf(stdout, __VA_ARGS__); \
    fputc('\n', stdout); hd_t_failed = 1; } while (0)

#define CHECK(c) do { if (!(c)) HD_T_FAILMSG("CHECK(%s) failed", #c); } while (0)
#define REQUIRE(c) do { if (!(c)) { HD_T_FAILMSG("REQUIRE(%s) failed", #c); return; } } while (0)
#define CHECK_MSG(c, ...) do { if (!(c)) HD_T_FAILMSG(__VA_ARGS__); } while (0)
#define CHECK_NEAR(a, b, tol) do { double hd_a_ = (a), hd_b_ = (b); \
    if (!(fabs(hd_a_ - hd_b_) <= (tol))) \
        HD_T_FAILMSG("%s = %.9g, expected %s = %.9g within %g", #a, hd_a_, #b, hd_b_, (double)(tol)); \
    } while (0)
/* relative tolerance */
#define CHECK_REL(a, b, rtol) do { double hd_a_ = (a), hd_b_ = (b); \
    if (!(fabs(hd_a_ - hd_b_) <= (rtol) * fabs(hd_b_))) \
        HD_T_FAILMSG("%s = %.9g, expected %s = %.9g within %g relative", #a, hd_a_, #b, hd_b_, (double)(rtol)); \
    } while (0)
#define CHECK_STR(a, b) do { const char *hd_a_ = (a), *hd_b_ = (b); \
    if (!hd_a_ || !hd_b_ || strcmp(hd_a_, hd_b_)) \
        HD_T_FAILMSG("%s = \"%s\", expected \"%s\"", #a, hd_a_ ? hd_a_ : "(null)", hd_b_ ? hd_b_ : "(null)"); \
    } while (0)
/* a substring of the error message */
#define CHECK_CONTAINS(hay, needle) do { const char *hd_h_ = (hay), *hd_n_ = (needle); \
    if (!hd_h_ || !strstr(hd_h_, hd_n_)) \
        HD_T_FAILMSG("\"%s\" does not contain \"%s\"", hd_h_ ? hd_h_ : "(null)", hd_n_); \
    } while (0)
#define SKIP(...) do { snprintf(hd_t_skipmsg, sizeof hd_t_skipmsg, __VA_ARGS__); \
    hd_t_skipped = 1; return; } while (0)

static inline const char *hd_t_basename(const char *p)
{
    const char *s = strrchr(p, '/');
    return s ? s + 1 : p;
}

#define RUN(fn) hd_test_run(#fn, fn, __FILE__)
static inline void hd_test_run(const char *name, void (*fn)(void), const char *file)
{
    hd_t_failed = hd_t_skipped = 0;
    hd_t_skipmsg[0] = 0;
    fflush(stdout);
    fn();
    if (hd_t_failed) { printf("FAIL: %s:%s\n", hd_t_basename(file), name); hd_t_nfail++; }
    else if (hd_t_skipped) { printf("SKIP: %s:%s: %s\n", hd_t_basename(file), name, hd_t_skipmsg); hd_t_nskip++; }
    else { printf("PASS: %s:%s\n", hd_t_basename(file), name); hd_t_npass++; }
    fflush(stdout);
}

static inline int hd_test_done(void)
{
    return hd_t_nfail ? 1 : 0;
}

/* The reference folder (HELIODON_REF, default ../shared/ref), or NULL if
 * it does not exist. */
static inline const char *hd_test_ref(void)
{
    const char *r = getenv("HELIODON_REF");
    struct stat st;
    if (!r || !*r) r = "../shared/ref";
    return (stat(r, &st) == 0 && S_ISDIR(st.st_mode)) ? r : NULL;
}

/* A scratch directory for the test's files (created). */
static inline const char *hd_test_tmpdir(void)
{
    static char dir[256];
    if (!dir[0]) {
        const char *b = getenv("HD_TEST_TMP");
        snprintf(dir, sizeof dir, "%s", b && *b ? b : "build/tmp");
        char cmd[300];
        snprintf(cmd, sizeof cmd, "mkdir -p '%s'", dir);
        if (system(cmd) != 0) { /* tests will fail on open */ }
    }
    return dir;
}

/* A Klems-full XML whose Transmission Front is Lambertian (tau/pi). */
static inline int hd_test_write_lambert_klems(const char *path, double tau)
{
    static const double th[] = {0, 10, 20, 30, 40, 50, 60, 70, 82.5};
    static const int np[] = {1, 8, 16, 20, 24, 24, 24, 16, 12};
    static const double tb[] = {0, 5, 15, 25, 35, 45, 55, 65, 75, 90};
    FILE *fp = fopen(path, "w");
    if (!fp) return 0;
    fprintf(fp, "<?xml version=\"1.0\"?>\n<WindowElement xmlns=\"http://windows.lbl.gov\">\n"
                "<WindowElementType>System</WindowElementType><FileType>BSDF</FileType>\n"
                "<Optical><Layer><Material><Name>l</Name></Material><DataDefinition>\n"
                "<IncidentDataStructure>Columns</IncidentDataStructure>\n"
                "<AngleBasis><AngleBasisName>LBNL/Klems Full</AngleBasisName>\n");
    int n = 0;
    for (int i = 0; i < 9; i++) {
        fprintf(fp, "<AngleBasisBlock><Theta>%g</Theta><nPhis>%d</nPhis><ThetaBounds><LowerTheta>%g</LowerTheta>"
                    "<UpperTheta>%g</UpperTheta></ThetaBounds></AngleBasisBlock>\n", th[i], np[i], tb[i], tb[i + 1]);
        n += np[i];
    }
    fprintf(fp, "</AngleBasis></DataDefinition>\n<WavelengthData><LayerNumber>System</LayerNumber>"
                "<Wavelength unit=\"Integral\">Visible</Wavelength><WavelengthDataBlock>"
                "<WavelengthDataDirection>Transmission Front</WavelengthDataDirection>"
                "<ColumnAngleBasis>LBNL/Klems Full</ColumnAngleBasis><RowAngleBasis>LBNL/Klems Full</RowAngleBasis>"
                "<ScatteringData>\n");
    for (int r = 0; r < n; r++) {
        for (int c = 0; c < n; c++) fprintf(fp, "%.6f ", tau / 3.14159265358979323846);
        fputc('\n', fp);
    }
    fprintf(fp, "</ScatteringData></WavelengthDataBlock></WavelengthData></Layer></Optical></WindowElement>\n");
    return fclose(fp) == 0;
}

#endif

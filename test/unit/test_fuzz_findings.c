/* Inputs found by the fuzz harnesses (make fuzz, docs/fuzz.md) that once
 * crashed or hit undefined behaviour: each is now refused with a message
 * naming the file (or option) and the position.  The crash inputs
 * themselves run in make check through the harness driver
 * (test/fuzz/regress/NAME/); these tests assert the messages. */
#include "hd_test.h"
#include "../fuzz/pmap_fix.h"
#include "heliodon/bsdf.h"
#include "heliodon/cal.h"
#include "heliodon/exr.h"
#include "heliodon/io.h"
#include "heliodon/matrix.h"
#include "heliodon/picture.h"
#include "heliodon/pmap.h"
#include "heliodon/view.h"

/* view: a zero -vv (or -vh) made the aspect 0/0 and the image size NaN
 * (cast to int in hd_view_normaspect). */
static void test_view_zero_size(void)
{
    hd_view v;
    hd_view_default(&v);
    CHECK(hd_view_parse_line(&v, "-vd 0 0 -1 -vu 5 1 0 -vh 10 -vv 0") == 4);
    CHECK(hd_view_setup(&v) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "zero view size (-vh 10 -vv 0)");
    hd_view_default(&v);
    CHECK(hd_view_parse_line(&v, "-vtl -vh 0 -vv 3") == 3);
    CHECK(hd_view_setup(&v) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "zero view size");
    hd_view_default(&v);
    CHECK(hd_view_parse_line(&v, "-vd 1e308 1e308 1e308") == 1);
    CHECK(hd_view_setup(&v) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "-vd");
    hd_view_default(&v);
    CHECK(hd_view_parse_line(&v, "-vu 1e308 -1e308 1e308") == 1);
    CHECK(hd_view_setup(&v) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "-vu");
}

/* matrix: headerless binary input shorter than one value (or empty)
 * stored zero values through a NULL data pointer before the error. */
static void test_matrix_empty_binary(void)
{
    static const unsigned char six[6] = {0, 0, 0, 0, 4, 0x40};
    for (int len = 0; len <= 6; len += 6)
        for (int fmt = HD_MTX_FLOAT; fmt <= HD_MTX_DOUBLE; fmt++) {
            hd_istream *s;
            REQUIRE(hd_istream_memory(&s, six, (size_t)len, "short.mtx") == HD_OK);
            hd_matrix_readopts o = {0, 1, 1, fmt};
            hd_matrix m;
            CHECK(hd_matrix_read_stream(s, &m, &o) == HD_ERR_FORMAT);
            CHECK_CONTAINS(hd_errmsg(), "short.mtx: byte offset");
            CHECK_CONTAINS(hd_errmsg(), "unexpected end of data");
            CHECK(m.data == NULL && m.nrows == 0);
            hd_istream_close(s);
        }
}

/* BSDF: a value beyond FLT_MAX (or near it) became inf in the float data
 * and NaN in the sampling tables (NaN cast to int in bsdf.c). */
static void test_bsdf_huge_value(void)
{
    static const char *const vals[] = {"1e39", "3.3e38", "2e9"};
    for (int k = 0; k < 3; k++) {
        char doc[2048];
        snprintf(doc, sizeof doc,
                 "<WindowElement><Optical><Layer><DataDefinition><IncidentDataStructure>TensorTree3"
                 "</IncidentDataStructure></DataDefinition>\n<WavelengthData><Wavelength>Visible</Wavelength>"
                 "<WavelengthDataBlock><WavelengthDataDirection>Transmission Front</WavelengthDataDirection>\n"
                 "<AngleBasis>LBNL/Shirley-Chiu</AngleBasis>\n<ScatteringData>{ 1 2 3 %s }</ScatteringData>"
                 "</WavelengthDataBlock></WavelengthData></Layer></Optical></WindowElement>\n", vals[k]);
        hd_bsdf *b = NULL;
        CHECK(hd_bsdf_load_memory(doc, strlen(doc), "big.xml", &b) == HD_ERR_RANGE);
        CHECK(b == NULL);
        CHECK_CONTAINS(hd_errmsg(), "big.xml: line 4: <ScatteringData>: value");
        CHECK_CONTAINS(hd_errmsg(), "out of range");
        hd_bsdf_free(b);
    }
}

/* Read a regression input of test/fuzz/regress/ (tests run from the
 * project's top directory); NULL if absent. */
static unsigned char *read_input(const char *path, size_t *len)
{
    FILE *fp = fopen(path, "rb");
    if (!fp) return NULL;
    static unsigned char buf[1 << 16];
    *len = fread(buf, 1, sizeof buf, fp);
    fclose(fp);
    return buf;
}

/* photon map: a source-table entry whose modifier name length byte
 * (up to 255) exceeded the 128-byte name field: heap overflow when the
 * map was opened (every program that reads maps). */
static void test_pmap_long_modifier_name(void)
{
    size_t len;
    unsigned char *b = read_input("test/fuzz/regress/pmap/long-modifier-name", &len);
    REQUIRE(b);
    hd_fuzz_pmap_fix(b, len);   /* as the harness does: valid checksums */
    char path[512];
    snprintf(path, sizeof path, "%s/long-name.pm", hd_test_tmpdir());
    FILE *fp = fopen(path, "wb");
    REQUIRE(fp);
    CHECK(fwrite(b, 1, len, fp) == len);
    fclose(fp);
    hd_pmap *m = NULL;
    CHECK(hd_pmap_open(&m, path, 0) == HD_ERR_FORMAT);
    CHECK(m == NULL);
    CHECK_CONTAINS(hd_errmsg(), "long-name.pm: byte ");
    CHECK_CONTAINS(hd_errmsg(), "modifier name of 182 bytes (at most 127)");
    hd_pmap_close(m);
    remove(path);
}

/* The committed seeds are valid inputs (so the harnesses' runs over them
 * in make check reach past the parsers): they load without error. */
static void test_seeds_valid(void)
{
    static const char *const maps[] = {"small", "tiny", "long"};
    for (int i = 0; i < 3; i++) {
        char path[256];
        snprintf(path, sizeof path, "test/fuzz/seeds/pmap/%s.pm", maps[i]);
        hd_pmap *m = NULL;
        CHECK_MSG(hd_pmap_open(&m, path, 0) == HD_OK, "%s", hd_errmsg());
        if (!m) continue;
        uint64_t bad = 1;
        CHECK(hd_pmap_verify(m, &bad) == HD_OK && bad == 0);
        CHECK(hd_pmap_get_info(m)->nphotons > 0);
        hd_pmap_close(m);
    }
    static const char *const xml[] = {"klems9", "klems9_rows", "tree3", "tree4"};
    for (int i = 0; i < 4; i++) {
        char path[256];
        snprintf(path, sizeof path, "test/fuzz/seeds/bsdf/%s.xml", xml[i]);
        hd_bsdf *b = NULL;
        CHECK_MSG(hd_bsdf_load(path, &b) == HD_OK, "%s", hd_errmsg());
        hd_bsdf_free(b);
    }
    hd_picture p;
    CHECK_MSG(hd_picture_read("test/fuzz/seeds/hdr/rle.hdr", &p) == HD_OK, "%s", hd_errmsg());
    CHECK(p.xres == 12 && p.yres == 12);   /* rpict -x 16 -y 12 of a square view */
    hd_picture_free(&p);
    hd_matrix_readopts o = {0, 0, 0, -1};
    hd_matrix mx;
    CHECK_MSG(hd_matrix_read("test/fuzz/seeds/matrix/double_be.mtx", &mx, &o) == HD_OK, "%s", hd_errmsg());
    CHECK(mx.nrows == 1 && mx.ncols == 2 && mx.ncomp == 3 && mx.data && mx.data[5] == 2.5);
    hd_matrix_free(&mx);
}

/* OpenEXR: a 2.4 kB file whose data window claims 786188 scanlines had
 * its pixels allocated (up to the allocation limit) before the decoder
 * found the chunk table missing: slow, and memory a file cannot fill. */
static void test_exr_huge_window_small_file(void)
{
    size_t len;
    unsigned char *b = read_input("test/fuzz/regress/exr/huge-window-small-file", &len);
    REQUIRE(b);
    hd_exr_image img;
    hd_exr_init(&img);
    CHECK(hd_exr_decode(b, len, "small.exr", &img) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "small.exr: 12x786188 pixels in 786188 chunks need a chunk table of 6289504 bytes");
    CHECK(img.nchan == 0);
    hd_exr_free(&img);
}

/* cal: jn()/yn() cast their order to int, and an order of 1e400 (inf) in
 * an rcontrib -b expression was undefined behaviour (fuzz_options). */
static char cal_warning[512];
static void keep_warning(void *user, const char *msg)
{
    (void)user;
    snprintf(cal_warning, sizeof cal_warning, "%s", msg);
}

static void test_cal_bessel_order(void)
{
    const char *exprs[] = {"x = yn(51e400, 1);", "x = jn(-1e10, 2);"};
    const char *want[] = {"yn(): order inf out of range", "jn(): order -1e+10 out of range"};
    for (int i = 0; i < 2; i++) {
        hd_cal *c = hd_cal_new();
        REQUIRE(c);
        hd_cal_set_warn(c, keep_warning, NULL);
        cal_warning[0] = 0;
        CHECK(hd_cal_parse(c, exprs[i], "fuzz") == HD_OK);
        hd_calrun *r = hd_calrun_new(c, NULL);
        REQUIRE(r);
        CHECK(hd_calrun_var(r, "x") == 0.0);
        CHECK_CONTAINS(cal_warning, want[i]);
        hd_calrun_free(r);
        hd_cal_free(c);
    }
    /* an order within range still gives the Bessel function */
    hd_cal *c = hd_cal_new();
    REQUIRE(c);
    CHECK(hd_cal_parse(c, "x = jn(1, 2.5);", "fuzz") == HD_OK);
    hd_calrun *r = hd_calrun_new(c, NULL);
    REQUIRE(r);
    CHECK(fabs(hd_calrun_var(r, "x") - 0.4970941024642741) < 1e-12);
    hd_calrun_free(r);
    hd_cal_free(c);
}

int main(void)
{
    RUN(test_cal_bessel_order);
    RUN(test_exr_huge_window_small_file);
    RUN(test_seeds_valid);
    RUN(test_pmap_long_modifier_name);
    RUN(test_matrix_empty_binary);
    RUN(test_bsdf_huge_value);
    RUN(test_view_zero_size);
    return hd_test_done();
}

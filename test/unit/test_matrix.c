/* Unit tests for src/matrix.c: formats, byte orders, Radiance header
 * layout, reference files, algebra and bad input. */
#include "hd_test.h"

#include <stdint.h>

#include "heliodon/common.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/matrix.h"
#include "heliodon/picture.h"

static const hd_matrix_readopts HDR = {0, 0, 0, -1};   /* header required */

static char *tmpname(const char *base)
{
    static char buf[8][512];
    static int k;
    char *p = buf[k++ & 7];
    snprintf(p, 512, "%s/test_matrix_%s", hd_test_tmpdir(), base);
    return p;
}

static int write_bytes(const char *path, const void *data, size_t n)
{
    FILE *fp = fopen(path, "wb");
    if (!fp) return -1;
    size_t k = fwrite(data, 1, n, fp);
    fclose(fp);
    return k == n ? 0 : -1;
}

/* Whole file into memory (NUL-terminated); *len = size. */
static char *slurp(const char *path, size_t *len)
{
    FILE *fp = fopen(path, "rb");
    if (!fp) return NULL;
    fseek(fp, 0, SEEK_END);
    long n = ftell(fp);
    fseek(fp, 0, SEEK_SET);
    char *b = malloc((size_t)n + 1);
    if (b && fread(b, 1, (size_t)n, fp) != (size_t)n) { free(b); b = NULL; }
    if (b) b[n] = 0;
    fclose(fp);
    if (len) *len = (size_t)n;
    return b;
}

/* Length of the header including the blank line. */
static size_t header_len(const char *b, size_t n)
{
    for (size_t i = 0; i + 1 < n; i++)
        if (b[i] == '\n' && b[i + 1] == '\n') return i + 2;
    return 0;
}

static void fill(hd_matrix *m, int positive)
{
    for (int r = 0; r < m->nrows; r++)
        for (int c = 0; c < m->ncols; c++)
            for (int k = 0; k < m->ncomp; k++) {
                double v = (r + 1) * 1.25 + c * 0.37 + k * 3.1e-3 + 1e-4 * (r * 7 + c * 3 + k);
                if (!positive && (r + c + k) % 3 == 0) v = -v * 1e5;
                hd_matrix_at(m, r, c)[k] = v;
            }
}

static void round_trip(hd_mtxfmt fmt, double rtol, int positive)
{
    hd_matrix m, r;
    hd_matrix_init(&m);
    hd_matrix_init(&r);
    REQUIRE(hd_matrix_alloc(&m, 5, 7, 3) == HD_OK);
    fill(&m, positive);
    hd_header h;
    hd_header_init(&h);
    REQUIRE(hd_header_append(&h, "test_matrix round trip") == HD_OK);
    char name[64];
    snprintf(name, sizeof name, "rt.%s", hd_mtxfmt_name(fmt));
    const char *path = tmpname(name);
    FILE *fp = fopen(path, "wb");
    REQUIRE(fp);
    CHECK(hd_matrix_write(fp, &m, &h, 1, fmt) == HD_OK);
    fclose(fp);
    hd_status st = hd_matrix_read(path, &r, &HDR);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    REQUIRE(st == HD_OK);
    CHECK(r.nrows == 5 && r.ncols == 7 && r.ncomp == 3);
    CHECK(r.infmt == fmt);
    REQUIRE(r.nrows == 5 && r.ncols == 7 && r.ncomp == 3);
    double worst = 0;
    for (size_t i = 0; i < 5 * 7 * 3; i++) {
        double a = m.data[i], b = r.data[i];
        double rel = fabs(a - b) / fabs(a);
        if (rel > worst) worst = rel;
    }
    CHECK_MSG(worst <= rtol, "%s: worst relative error %g > %g", hd_mtxfmt_name(fmt), worst, rtol);
    /* header lines are kept, dims/format removed */
    CHECK(strstr(r.hdr.text, "test_matrix round trip\n") != NULL);
    CHECK(strstr(r.hdr.text, "NROWS=") == NULL && strstr(r.hdr.text, "FORMAT=") == NULL);
    hd_header_free(&h);
    hd_matrix_free(&m);
    hd_matrix_free(&r);
}

static void test_roundtrip_ascii(void) { round_trip(HD_MTX_ASCII, 6e-8, 0); }
static void test_roundtrip_float(void) { round_trip(HD_MTX_FLOAT, 6e-8, 0); }
static void test_roundtrip_double(void) { round_trip(HD_MTX_DOUBLE, 0, 0); }
/* RGBE: 8-bit mantissas relative to the largest component (>= 1/256 of
 * it); our values have components within a factor ~1.01, so 1 % */
static void test_roundtrip_rgbe(void) { round_trip(HD_MTX_RGBE, 0.01, 1); }
static void test_roundtrip_xyze(void) { round_trip(HD_MTX_XYZE, 0.01, 1); }

/* Hand-made files in both byte orders, float and double. */
static void test_byte_orders(void)
{
    /* 1.5f = 0x3FC00000, -2.25f = 0xC0100000; 1.5 = 0x3FF8000000000000,
     * -2.25 = 0xC002000000000000 */
    const unsigned char fbe[] = {0x3F, 0xC0, 0, 0, 0xC0, 0x10, 0, 0};
    const unsigned char fle[] = {0, 0, 0xC0, 0x3F, 0, 0, 0x10, 0xC0};
    const unsigned char dbe[] = {0x3F, 0xF8, 0, 0, 0, 0, 0, 0, 0xC0, 0x02, 0, 0, 0, 0, 0, 0};
    const unsigned char dle[] = {0, 0, 0, 0, 0, 0, 0xF8, 0x3F, 0, 0, 0, 0, 0, 0, 0x02, 0xC0};
    struct { const char *fmt; int be; const unsigned char *d; size_t n; } cases[] = {
        {"float", 1, fbe, 8}, {"float", 0, fle, 8}, {"double", 1, dbe, 16}, {"double", 0, dle, 16},
    };
    for (int i = 0; i < 4; i++) {
        char buf[256];
        int n = snprintf(buf, sizeof buf, "#?RADIANCE\nNROWS=1\nNCOLS=2\nNCOMP=1\nBigEndian=%d\nFORMAT=%s\n\n",
                         cases[i].be, cases[i].fmt);
        memcpy(buf + n, cases[i].d, cases[i].n);
        const char *p = tmpname("order.mtx");
        REQUIRE(write_bytes(p, buf, (size_t)n + cases[i].n) == 0);
        hd_matrix m;
        hd_matrix_init(&m);
        hd_status st = hd_matrix_read(p, &m, &HDR);
        CHECK_MSG(st == HD_OK, "%s BigEndian=%d: %s", cases[i].fmt, cases[i].be, hd_errmsg());
        if (st == HD_OK) {
            CHECK(m.nrows == 1 && m.ncols == 2 && m.ncomp == 1);
            CHECK_MSG(m.data[0] == 1.5 && m.data[1] == -2.25, "%s BigEndian=%d: read %g %g",
                      cases[i].fmt, cases[i].be, m.data[0], m.data[1]);
        }
        hd_matrix_free(&m);
    }
}

/* No BigEndian line: native order assumed. */
static void test_native_order(void)
{
    char buf[256];
    int n = snprintf(buf, sizeof buf, "#?RADIANCE\nNROWS=2\nNCOLS=1\nNCOMP=1\nFORMAT=float\n\n");
    float v[2] = {3.5f, 1e-3f};
    memcpy(buf + n, v, sizeof v);
    const char *p = tmpname("native.mtx");
    REQUIRE(write_bytes(p, buf, (size_t)n + sizeof v) == 0);
    hd_matrix m;
    hd_matrix_init(&m);
    REQUIRE(hd_matrix_read(p, &m, &HDR) == HD_OK);
    CHECK(m.data[0] == 3.5 && m.data[1] == (double)1e-3f);
    hd_matrix_free(&m);
}

/* Headerless input with dimensions given, ascii and float, and the row
 * count taken from the data. */
static void test_headerless(void)
{
    const char *p = tmpname("nohdr.txt");
    const char *txt = "1 2 3\t4 5 6\n7 8 9 10 11 12\n";
    REQUIRE(write_bytes(p, txt, strlen(txt)) == 0);
    hd_matrix m;
    hd_matrix_init(&m);
    hd_matrix_readopts o = {2, 2, 3, HD_MTX_ASCII};
    REQUIRE(hd_matrix_read(p, &m, &o) == HD_OK);
    CHECK(m.nrows == 2 && m.ncols == 2 && m.ncomp == 3);
    CHECK(hd_matrix_at(&m, 1, 1)[2] == 12);
    hd_matrix_free(&m);
    hd_matrix_readopts o2 = {0, 1, 3, HD_MTX_ASCII};   /* rows from data */
    REQUIRE(hd_matrix_read(p, &m, &o2) == HD_OK);
    CHECK(m.nrows == 4 && m.ncols == 1);
    CHECK(hd_matrix_at(&m, 3, 0)[0] == 10);
    hd_matrix_free(&m);
    hd_matrix_readopts o3 = {0, 5, 1, HD_MTX_ASCII};   /* 12 values, rows of 5 */
    CHECK(hd_matrix_read(p, &m, &o3) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "whole number of rows");
    float f[6] = {1, 2, 3, 4, 5, 6};
    const char *pf = tmpname("nohdr.f");
    REQUIRE(write_bytes(pf, f, sizeof f) == 0);
    hd_matrix_readopts o4 = {0, 2, 1, HD_MTX_FLOAT};
    REQUIRE(hd_matrix_read(pf, &m, &o4) == HD_OK);
    CHECK(m.nrows == 3 && hd_matrix_at(&m, 2, 1)[0] == 6);
    hd_matrix_free(&m);
}

/* EXPOSURE and COLORCORR are undone on read, and dropped from the header. */
static void test_exposure(void)
{
    const char *p = tmpname("expo.mtx");
    const char *txt = "#?RADIANCE\nEXPOSURE=2\nEXPOSURE=0.5e1\nCOLORCORR= 1 2 4\nNROWS=1\nNCOLS=1\nNCOMP=3\n"
                      "FORMAT=ascii\n\n10 20 40\n";
    REQUIRE(write_bytes(p, txt, strlen(txt)) == 0);
    hd_matrix m;
    hd_matrix_init(&m);
    REQUIRE(hd_matrix_read(p, &m, &HDR) == HD_OK);
    CHECK_NEAR(m.data[0], 1.0, 1e-12);
    CHECK_NEAR(m.data[1], 1.0, 1e-12);
    CHECK_NEAR(m.data[2], 1.0, 1e-12);
    CHECK(strstr(m.hdr.text, "EXPOSURE") == NULL && strstr(m.hdr.text, "COLORCORR") == NULL);
    hd_matrix_free(&m);
}

/* A picture with EXPOSURE read as a matrix: values divided back. */
static void test_picture_exposure(void)
{
    hd_matrix m, r;
    hd_matrix_init(&m);
    hd_matrix_init(&r);
    REQUIRE(hd_matrix_alloc(&m, 2, 20, 3) == HD_OK);   /* 20 pixels: RLE scanlines */
    for (int i = 0; i < 2 * 20 * 3; i++) m.data[i] = 4.0 * (1 + (i / 3) % 7);   /* grey pixels */
    hd_header h;
    hd_header_init(&h);
    hd_header_append(&h, "EXPOSURE=4");
    const char *p = tmpname("expo.hdr");
    FILE *fp = fopen(p, "wb");
    REQUIRE(fp);
    CHECK(hd_matrix_write(fp, &m, &h, 1, HD_MTX_RGBE) == HD_OK);
    fclose(fp);
    hd_status st = hd_matrix_read(p, &r, &HDR);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    if (!st) {
        CHECK(r.nrows == 2 && r.ncols == 20 && r.ncomp == 3 && r.infmt == HD_MTX_RGBE);
        double worst = 0;
        for (int i = 0; i < 2 * 20 * 3; i++) {
            double d = fabs(r.data[i] - m.data[i] / 4) / (m.data[i] / 4);
            if (d > worst) worst = d;
        }
        CHECK_MSG(worst < 0.01, "worst relative error %g", worst);
    }
    hd_header_free(&h);
    hd_matrix_free(&m);
    hd_matrix_free(&r);
}

/* Pictures in all 8 orientations read as matrices in standard order. */
static void test_picture_orientations(void)
{
    hd_picture pic;
    hd_picture_init(&pic);
    REQUIRE(hd_picture_alloc(&pic, 19, 7) == HD_OK);
    for (int i = 0; i < 19 * 7; i++) {    /* grey, all pixels of a row differ */
        float v = (float)(1 + i % 97);
        pic.pix[3 * i] = pic.pix[3 * i + 1] = pic.pix[3 * i + 2] = v;
    }
    for (int o = 0; o < 8; o++) {
        const char *p = tmpname("orient.hdr");
        FILE *fp = fopen(p, "wb");
        REQUIRE(fp);
        hd_status st = hd_picture_write(fp, &pic, NULL, o);
        fclose(fp);
        CHECK_MSG(st == HD_OK, "orientation %d: %s", o, hd_errmsg());
        if (st) continue;
        hd_matrix m;
        hd_matrix_init(&m);
        st = hd_matrix_read(p, &m, &HDR);
        CHECK_MSG(st == HD_OK, "orientation %d: %s", o, hd_errmsg());
        if (!st) {
            CHECK_MSG(m.nrows == 7 && m.ncols == 19, "orientation %d: %d x %d", o, m.nrows, m.ncols);
            int bad = 0;
            for (int i = 0; i < 19 * 7 && m.nrows == 7 && m.ncols == 19; i++)
                /* RGBE centring error <= 0.4 %; neighbouring values differ by >= 1 % */
                if (fabs(m.data[3 * i + 1] - pic.pix[3 * i + 1]) > 0.005 * pic.pix[3 * i + 1]) bad++;
            CHECK_MSG(bad == 0, "orientation %d: %d pixels differ", o, bad);
        }
        hd_matrix_free(&m);
    }
    hd_picture_free(&pic);
}

/* A reference rcontrib picture (NROWS=16384 in its header, resolution
 * string 128 x 128) read as a matrix equals the picture module's pixels. */
static void test_ref_picture(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("reference folder not found");
    char p[1024];
    snprintf(p, sizeof p, "%s/scenes/box/a3_vimg/v044.hdr.gz", ref);
    hd_matrix m;
    hd_matrix_init(&m);
    hd_status st = hd_matrix_read(p, &m, &HDR);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    if (st) return;
    CHECK(m.nrows == 128 && m.ncols == 128 && m.ncomp == 3 && m.infmt == HD_MTX_RGBE);
    hd_picture pic;
    hd_picture_init(&pic);
    st = hd_picture_read(p, &pic);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    if (!st && pic.xres == 128 && pic.yres == 128) {
        int bad = 0, nonzero = 0;
        for (int i = 0; i < 128 * 128 * 3; i++) {
            if ((float)m.data[i] != pic.pix[i]) bad++;
            nonzero += pic.pix[i] != 0;
        }
        CHECK_MSG(bad == 0, "%d values differ from hd_picture_read", bad);
        CHECK(nonzero > 1000);
    }
    hd_picture_free(&pic);
    hd_matrix_free(&m);
}

/* A header without the "#?RADIANCE" line is accepted (as Radiance does);
 * data without any header is not. */
static void test_no_ident(void)
{
    const char *p = tmpname("noident.mtx");
    const char *t = "NROWS=1\nNCOLS=2\nNCOMP=1\nFORMAT=ascii\n\n5 6\n";
    REQUIRE(write_bytes(p, t, strlen(t)) == 0);
    hd_matrix m;
    hd_matrix_init(&m);
    hd_status st = hd_matrix_read(p, &m, &HDR);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    if (!st) CHECK(m.ncols == 2 && m.data[1] == 6);
    hd_matrix_free(&m);
    t = "1 2 3\n4 5 6\n";
    REQUIRE(write_bytes(p, t, strlen(t)) == 0);
    CHECK(hd_matrix_read(p, &m, &HDR) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "noident.mtx");
    CHECK(m.data == NULL);
}

/* gzip and "!command" inputs. */
static void test_gzip_and_command(void)
{
    const char *p = tmpname("gz.mtx");
    const char *txt = "#?RADIANCE\nNROWS=1\nNCOLS=2\nNCOMP=1\nFORMAT=ascii\n\n0.5 -7\n";
    REQUIRE(write_bytes(p, txt, strlen(txt)) == 0);
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "gzip -c '%s' > '%s.gz'", p, p);
    REQUIRE(system(cmd) == 0);
    snprintf(cmd, sizeof cmd, "%s.gz", p);
    hd_matrix m;
    hd_matrix_init(&m);
    hd_status st = hd_matrix_read(cmd, &m, &HDR);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    if (!st) CHECK(m.ncols == 2 && m.data[1] == -7);
    hd_matrix_free(&m);
    snprintf(cmd, sizeof cmd, "!cat '%s'", p);
    st = hd_matrix_read(cmd, &m, &HDR);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    if (!st) CHECK(m.ncols == 2 && m.data[0] == 0.5);
    hd_matrix_free(&m);
}

/* ------------------------------------------------------ reference files */

/* Header dims of a file (found flags), -1 if absent. */
static int ref_header_dims(const char *path, long *nr, long *nc, long *nk)
{
    hd_istream *s;
    if (hd_istream_open(&s, path)) return -1;
    hd_header h;
    hd_header_init(&h);
    int ok = hd_header_read(s, &h, 0) == HD_OK;
    hd_istream_close(s);
    int f;
    *nr = *nc = *nk = -1;
    if (ok) {
        if (hd_header_get_long(&h, "NROWS", nr, &f) || !f) *nr = -1;
        if (hd_header_get_long(&h, "NCOLS", nc, &f) || !f) *nc = -1;
        if (hd_header_get_long(&h, "NCOMP", nk, &f) || !f) *nk = 3;
    }
    hd_header_free(&h);
    return ok ? 0 : -1;
}

static void test_ref_all_matrices(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("reference folder not found (HELIODON_REF)");
    char cmd[1024];
    snprintf(cmd, sizeof cmd,
             "find '%s' -type f \\( -name '*.mtx' -o -name '*.smx' -o -name '*.dmx' -o -name '*.vmx' "
             "-o -name '*.dc' -o -name '*.vec' -o -name '*.dat' -o -name '*.mtx.gz' -o -name '*.smx.gz' "
             "-o -name '*.dmx.gz' -o -name '*.vmx.gz' -o -name '*.dc.gz' -o -name '*.vec.gz' \\) | sort", ref);
    FILE *lp = popen(cmd, "r");
    REQUIRE(lp);
    char path[1024];
    int nread = 0, nskipped = 0;
    while (fgets(path, sizeof path, lp)) {
        path[strcspn(path, "\n")] = 0;
        long nr, nc, nk;
        if (ref_header_dims(path, &nr, &nc, &nk) || nr < 0 || nc < 0) {
            nskipped++;          /* e.g. rtrace output without NROWS */
            continue;
        }
        hd_matrix m;
        hd_matrix_init(&m);
        hd_status st = hd_matrix_read(path, &m, &HDR);
        CHECK_MSG(st == HD_OK, "%s: %s", path, hd_errmsg());
        if (!st)
            CHECK_MSG(m.nrows == nr && m.ncols == nc && m.ncomp == nk,
                      "%s: read %d x %d x %d, header says %ld x %ld x %ld",
                      path, m.nrows, m.ncols, m.ncomp, nr, nc, nk);
        hd_matrix_free(&m);
        nread++;
    }
    pclose(lp);
    printf("  reference matrices read: %d (skipped %d without NROWS/NCOLS)\n", nread, nskipped);
    CHECK(nread >= 60);
}

/* XML BSDF as a Klems matrix (when the BSDF module is in the library):
 * equals Radiance's rmtxop -fa output of the same file. */
static void test_ref_xml(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("reference folder not found");
    char px[1024], pm[1024];
    snprintf(px, sizeof px, "%s/bsdf/cfs1/cfs1_klems.xml", ref);
    snprintf(pm, sizeof pm, "%s/bsdf/cfs1/cfs1_klems_T.mtx", ref);
    hd_matrix x, r;
    hd_matrix_init(&x);
    hd_matrix_init(&r);
    hd_status st = hd_matrix_read(px, &x, &HDR);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    REQUIRE(hd_matrix_read(pm, &r, &HDR) == HD_OK);
    if (!st) {
        CHECK(x.nrows == 145 && x.ncols == 145 && x.ncomp == 3);
        double worst = 0;
        for (size_t i = 0; i < 145 * 145 * 3 && x.nrows == 145; i++) {
            double d = fabs(x.data[i] - r.data[i]) / (fabs(r.data[i]) + 1e-30);
            if (d > worst) worst = d;
        }
        CHECK_MSG(worst <= 6e-8, "worst relative difference %g", worst);   /* %.7e rounding */
    }
    hd_matrix_free(&x);
    hd_matrix_free(&r);
}

/* Float values equal the raw bytes of the file. */
static void test_ref_float_raw(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("reference folder not found");
    char p[1024];
    snprintf(p, sizeof p, "%s/scenes/box/a3_D.dmx", ref);
    size_t n;
    char *b = slurp(p, &n);
    if (!b) SKIP("a3_D.dmx missing");
    hd_matrix m;
    hd_matrix_init(&m);
    hd_status st = hd_matrix_read(p, &m, &HDR);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    if (!st) {
        CHECK(m.nrows == 145 && m.ncols == 146 && m.ncomp == 3 && m.infmt == HD_MTX_FLOAT);
        size_t nv = 145 * 146 * 3, off = n - nv * 4;
        CHECK(off == header_len(b, n));
        int bad = 0;
        for (size_t i = 0; i < nv; i++) {
            float f;
            memcpy(&f, b + off + 4 * i, 4);       /* file is BigEndian=0, host is LE */
            if ((double)f != m.data[i]) bad++;
        }
        CHECK_MSG(bad == 0, "%d values differ from the raw floats", bad);
    }
    free(b);
    hd_matrix_free(&m);
}

/* Radiance's rmtxop result (a3_sky_mf1_3h.smx = a3_sky_mf1.smx . a3_select3.mtx)
 * reproduced exactly (float output of a double product). */
static void test_ref_product(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("reference folder not found");
    char p1[1024], p2[1024], p3[1024];
    snprintf(p1, sizeof p1, "%s/scenes/box/a3_sky_mf1.smx", ref);
    snprintf(p2, sizeof p2, "%s/scenes/box/a3_select3.mtx", ref);
    snprintf(p3, sizeof p3, "%s/scenes/box/a3_sky_mf1_3h.smx", ref);
    hd_matrix a, s, r, out;
    hd_matrix_init(&a); hd_matrix_init(&s); hd_matrix_init(&r); hd_matrix_init(&out);
    REQUIRE(hd_matrix_read(p1, &a, &HDR) == HD_OK);
    REQUIRE(hd_matrix_read(p2, &s, &HDR) == HD_OK);
    REQUIRE(hd_matrix_read(p3, &r, &HDR) == HD_OK);
    REQUIRE(hd_matrix_multiply(&out, &a, &s) == HD_OK);
    CHECK(out.nrows == 146 && out.ncols == 3 && out.ncomp == 3);
    CHECK(out.infmt == HD_MTX_ASCII);     /* float . ascii -> lower precision */
    int bad = 0;
    for (size_t i = 0; i < 146 * 3 * 3; i++)
        if ((float)out.data[i] != (float)r.data[i]) bad++;
    CHECK_MSG(bad == 0, "%d values differ from Radiance's rmtxop", bad);
    /* column 0 of the result = time step 10 of the sky */
    CHECK(out.data[3 * 3 * 50] == hd_matrix_at(&a, 50, 10)[0]);
    hd_matrix_free(&a); hd_matrix_free(&s); hd_matrix_free(&r); hd_matrix_free(&out);
}

/* ascii %.3g (gendaymtx -A) vs the float year matrix averaged over its columns. */
static void test_ref_ascii_vs_float(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("reference folder not found");
    char p1[1024], p2[1024];
    snprintf(p1, sizeof p1, "%s/sky/daymtx/chicago_year_mf1.mtx.gz", ref);
    snprintf(p2, sizeof p2, "%s/sky/daymtx/chicago_year_mf1_avg_epw.mtx", ref);
    hd_matrix y, avg;
    hd_matrix_init(&y); hd_matrix_init(&avg);
    hd_status st = hd_matrix_read(p1, &y, &HDR);
    if (st == HD_ERR_IO) SKIP("%s", hd_errmsg());
    REQUIRE(st == HD_OK);
    REQUIRE(hd_matrix_read(p2, &avg, &HDR) == HD_OK);
    REQUIRE(y.nrows == 146 && y.ncols == 8760 && avg.nrows == 146 && avg.ncols == 1);
    double worst = 0;
    for (int r = 0; r < 146; r++)
        for (int k = 0; k < 3; k++) {
            double s = 0;
            for (int c = 0; c < 8760; c++) s += hd_matrix_at(&y, r, c)[k];
            s /= 8760;
            double a = hd_matrix_at(&avg, r, 0)[k];
            double d = fabs(s - a) / (fabs(a) > 1e-3 ? fabs(a) : 1e-3);
            if (d > worst) worst = d;
        }
    CHECK_MSG(worst < 0.006, "ascii %%.3g average differs by %g relative", worst);   /* 3 digits */
    hd_matrix_free(&y); hd_matrix_free(&avg);
}

/* Headers we write are laid out byte for byte like Radiance's. */
static void test_header_layout(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("reference folder not found");
    struct { const char *file; int fmt; int nkeep; } cases[] = {
        {"scenes/box/a3_sky_mf1.smx", HD_MTX_FLOAT, 2},      /* gendaymtx: FORMAT=float + 1 blank */
        {"scenes/box/a3_D.dmx", HD_MTX_FLOAT, 7},            /* rcontrib order: NCOMP first, 3 blanks */
        {"scenes/box/a3_V_sensors.vmx", HD_MTX_FLOAT, 7},
        {"sky/daymtx/chicago_0101-0107_mf1_d.mtx", HD_MTX_FLOAT, 2},   /* 2 blanks */
        {"scenes/box/a3_sky_mf1_3h.smx", HD_MTX_FLOAT, 1},   /* rmtxop: no padding needed */
        {"bsdf/cfs1/cfs1_klems_T.mtx", HD_MTX_ASCII, 1},     /* rmtxop -fa: data too */
        {"scenes/box/a4_sunvec_mf1_0101_1030.vec", HD_MTX_ASCII, 1},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        char p[1024];
        snprintf(p, sizeof p, "%s/%s", ref, cases[i].file);
        size_t n;
        char *b = slurp(p, &n);
        if (!b) { CHECK_MSG(0, "cannot read %s", p); continue; }
        size_t hl = header_len(b, n);
        hd_matrix m;
        hd_matrix_init(&m);
        hd_status st = hd_matrix_read(p, &m, &HDR);
        CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
        if (st) { free(b); continue; }
        /* header to pass: the first nkeep text lines after "#?RADIANCE" */
        hd_header h;
        hd_header_init(&h);
        const char *q = strchr(b, '\n') + 1;
        for (int k = 0; k < cases[i].nkeep; k++) {
            const char *e = strchr(q, '\n');
            char line[4096];
            snprintf(line, sizeof line, "%.*s", (int)(e - q), q);
            hd_header_append(&h, line);
            q = e + 1;
        }
        const char *op = tmpname("layout.out");
        FILE *fp = fopen(op, "wb");
        REQUIRE(fp);
        CHECK(hd_matrix_write(fp, &m, &h, 1, (hd_mtxfmt)cases[i].fmt) == HD_OK);
        fclose(fp);
        size_t on;
        char *o = slurp(op, &on);
        size_t ohl = o ? header_len(o, on) : 0;
        int hsame = o && ohl == hl && !memcmp(o, b, hl);
        CHECK_MSG(hsame, "%s: header differs:\n--- ours ---\n%.*s--- Radiance ---\n%.*s", cases[i].file,
                  (int)ohl, o ? o : "", (int)hl, b);
        if (cases[i].fmt == HD_MTX_FLOAT || !strstr(cases[i].file, "vec"))
            CHECK_MSG(on == n && !memcmp(o, b, n), "%s: data differ (%zu vs %zu bytes)", cases[i].file, on, n);
        free(o);
        free(b);
        hd_header_free(&h);
        hd_matrix_free(&m);
    }
}

/* rcontrib-style streaming: NCOMP in the caller's header, rows unknown. */
static void test_writer_streaming(void)
{
    hd_header h;
    hd_header_init(&h);
    hd_header_append(&h, "NCOMP=3");
    const char *p = tmpname("stream.mtx");
    FILE *fp = fopen(p, "wb");
    REQUIRE(fp);
    hd_mtxwriter w;
    REQUIRE(hd_mtxwriter_begin(&w, fp, &h, 1, HD_MTX_ASCII, 0, 2, 3) == HD_OK);
    w.ascii_style = HD_MTXASCII_RCONTRIB;
    double row[6] = {1, 2, 3, 4, 5, 6};
    for (int i = 0; i < 3; i++) CHECK(hd_mtxwriter_row(&w, row) == HD_OK);
    CHECK(hd_mtxwriter_end(&w) == HD_OK);
    fclose(fp);
    char *b = slurp(p, NULL);
    REQUIRE(b);
    CHECK_STR(b, "#?RADIANCE\nNCOMP=3\nNCOLS=2\nFORMAT=ascii\n\n"
                 "1.000000e+00\t2.000000e+00\t3.000000e+00\t4.000000e+00\t5.000000e+00\t6.000000e+00\t\n"
                 "1.000000e+00\t2.000000e+00\t3.000000e+00\t4.000000e+00\t5.000000e+00\t6.000000e+00\t\n"
                 "1.000000e+00\t2.000000e+00\t3.000000e+00\t4.000000e+00\t5.000000e+00\t6.000000e+00\t\n");
    free(b);
    hd_matrix m;
    hd_matrix_init(&m);
    REQUIRE(hd_matrix_read(p, &m, &HDR) == HD_OK);     /* rows counted from the data */
    CHECK(m.nrows == 3 && m.ncols == 2 && m.ncomp == 3);
    hd_matrix_free(&m);
    /* too many rows announced */
    fp = fopen(p, "wb");
    REQUIRE(hd_mtxwriter_begin(&w, fp, NULL, 1, HD_MTX_FLOAT, 1, 2, 3) == HD_OK);
    CHECK(hd_mtxwriter_row(&w, row) == HD_OK);
    CHECK(hd_mtxwriter_row(&w, row) != HD_OK);
    hd_mtxwriter_end(&w);
    fclose(fp);
    hd_header_free(&h);
}

/* ascii layout of dctimestep */
static void test_writer_dctimestep_style(void)
{
    const char *p = tmpname("dct.mtx");
    FILE *fp = fopen(p, "wb");
    REQUIRE(fp);
    hd_mtxwriter w;
    REQUIRE(hd_mtxwriter_begin(&w, fp, NULL, 0, HD_MTX_ASCII, 1, 2, 3) == HD_OK);
    w.ascii_style = HD_MTXASCII_DCTIMESTEP;
    double row[6] = {0, 0.5107021, 7.387875, 1, 2, 3};
    CHECK(hd_mtxwriter_row(&w, row) == HD_OK);
    CHECK(hd_mtxwriter_end(&w) == HD_OK);
    fclose(fp);
    char *b = slurp(p, NULL);
    REQUIRE(b);
    /* a TAB between elements, none before the newline (as Radiance's
     * dctimestep: see the a3_res_*.mtx references) */
    CHECK_STR(b, "0.000000e+00 5.107021e-01 7.387875e+00\t1.000000e+00 2.000000e+00 3.000000e+00\n");
    free(b);
}

/* ------------------------------------------------------------- algebra */

static void set_vals(hd_matrix *m, int nr, int nc, int nk, const double *v)
{
    hd_matrix_free(m);
    hd_matrix_alloc(m, nr, nc, nk);
    memcpy(m->data, v, sizeof(double) * (size_t)(nr * nc * nk));
}

static void test_multiply(void)
{
    hd_matrix a, b, c;
    hd_matrix_init(&a); hd_matrix_init(&b); hd_matrix_init(&c);
    /* [1 2 3; 4 5 6] . [7 8; 9 10; 11 12] = [58 64; 139 154] */
    const double av[] = {1, 2, 3, 4, 5, 6}, bv[] = {7, 8, 9, 10, 11, 12};
    set_vals(&a, 2, 3, 1, av);
    set_vals(&b, 3, 2, 1, bv);
    REQUIRE(hd_matrix_multiply(&c, &a, &b) == HD_OK);
    CHECK(c.nrows == 2 && c.ncols == 2 && c.ncomp == 1);
    CHECK(c.data[0] == 58 && c.data[1] == 64 && c.data[2] == 139 && c.data[3] == 154);
    /* 3 components times 1 component: per component */
    const double a3[] = {1, 10, 100, 2, 20, 200};   /* 1 x 2 x 3 */
    const double b1[] = {3, 4};                     /* 2 x 1 x 1 */
    set_vals(&a, 1, 2, 3, a3);
    set_vals(&b, 2, 1, 1, b1);
    REQUIRE(hd_matrix_multiply(&c, &a, &b) == HD_OK);
    CHECK(c.nrows == 1 && c.ncols == 1 && c.ncomp == 3);
    CHECK(c.data[0] == 11 && c.data[1] == 110 && c.data[2] == 1100);
    /* 3 x 3 components, in place (out aliases a) */
    const double b3[] = {1, 2, 3, 4, 5, 6};         /* 2 x 1 x 3 */
    set_vals(&b, 2, 1, 3, b3);
    REQUIRE(hd_matrix_multiply(&a, &a, &b) == HD_OK);
    CHECK(a.nrows == 1 && a.ncols == 1 && a.ncomp == 3);
    CHECK(a.data[0] == 1 * 1 + 2 * 4 && a.data[1] == 10 * 2 + 20 * 5 && a.data[2] == 100 * 3 + 200 * 6);
    /* mismatched NCOMP */
    hd_matrix d;
    hd_matrix_init(&d);
    const double d2[] = {1, 2, 3, 4};
    set_vals(&d, 1, 2, 2, d2);
    set_vals(&b, 2, 1, 3, b3);
    CHECK(hd_matrix_multiply(&c, &d, &b) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "component counts differ (2 and 3");
    /* inner dimension mismatch */
    set_vals(&a, 2, 3, 1, av);
    CHECK(hd_matrix_multiply(&c, &a, &a) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "2 x 3 times 2 x 3");
    hd_matrix_free(&a); hd_matrix_free(&b); hd_matrix_free(&c); hd_matrix_free(&d);
}

/* Threaded product equals the single-thread one bit for bit; general
 * component count (4) path checked against a naive triple loop. */
static void test_multiply_mt(void)
{
    hd_matrix a, b, c1, c3;
    hd_matrix_init(&a); hd_matrix_init(&b); hd_matrix_init(&c1); hd_matrix_init(&c3);
    REQUIRE(hd_matrix_alloc(&a, 37, 23, 4) == HD_OK);
    REQUIRE(hd_matrix_alloc(&b, 23, 11, 4) == HD_OK);
    fill(&a, 0);
    fill(&b, 1);
    hd_matrix_at(&a, 3, 5)[0] = hd_matrix_at(&a, 3, 5)[1] = 0;   /* partly zero element */
    REQUIRE(hd_matrix_multiply(&c1, &a, &b) == HD_OK);
    REQUIRE(hd_matrix_multiply_mt(&c3, &a, &b, 3) == HD_OK);
    CHECK(!memcmp(c1.data, c3.data, sizeof(double) * 37 * 11 * 4));
    double worst = 0;
    for (int i = 0; i < 37; i++)
        for (int j = 0; j < 11; j++)
            for (int k = 0; k < 4; k++) {
                double s = 0;
                for (int x = 0; x < 23; x++) s += hd_matrix_at(&a, i, x)[k] * hd_matrix_at(&b, x, j)[k];
                double d = fabs(s - hd_matrix_at(&c1, i, j)[k]) / (fabs(s) + 1e-300);
                if (d > worst) worst = d;
            }
    CHECK_MSG(worst < 1e-12, "worst relative difference %g", worst);
    hd_matrix_free(&a); hd_matrix_free(&b); hd_matrix_free(&c1); hd_matrix_free(&c3);
}

/* Chains: cheapest order chosen, values equal to left to right. */
static void test_chain(void)
{
    hd_matrix a, b, c, d, ab, abc, out;
    hd_matrix_init(&a); hd_matrix_init(&b); hd_matrix_init(&c); hd_matrix_init(&d);
    hd_matrix_init(&ab); hd_matrix_init(&abc); hd_matrix_init(&out);
    REQUIRE(hd_matrix_alloc(&a, 50, 40, 3) == HD_OK);
    REQUIRE(hd_matrix_alloc(&b, 40, 30, 3) == HD_OK);
    REQUIRE(hd_matrix_alloc(&c, 30, 20, 1) == HD_OK);
    REQUIRE(hd_matrix_alloc(&d, 20, 1, 3) == HD_OK);
    fill(&a, 0); fill(&b, 1); fill(&c, 0); fill(&d, 1);
    REQUIRE(hd_matrix_multiply(&ab, &a, &b) == HD_OK);
    REQUIRE(hd_matrix_multiply(&abc, &ab, &c) == HD_OK);
    REQUIRE(hd_matrix_multiply(&ab, &abc, &d) == HD_OK);          /* left to right */
    const hd_matrix *ms[4] = {&a, &b, &c, &d};
    double ltr = 0, best = 0;
    REQUIRE(hd_matrix_chain(&out, ms, 4, 2, &ltr, &best) == HD_OK);
    CHECK(out.nrows == 50 && out.ncols == 1 && out.ncomp == 3);
    CHECK_NEAR(ltr, 3.0 * (50 * 40 * 30 + 50 * 30 * 20 + 50 * 20 * 1), 0);
    /* best: a.(b.(c.d)) = 30*20*1 + 40*30*1 + 50*40*1, times 3 components */
    CHECK_NEAR(best, 3.0 * (30 * 20 + 40 * 30 + 50 * 40), 0);
    double worst = 0;
    for (int i = 0; i < 50 * 3; i++) {
        double dd = fabs(out.data[i] - ab.data[i]) / fabs(ab.data[i]);
        if (dd > worst) worst = dd;
    }
    CHECK_MSG(worst < 1e-12, "chain differs from left to right by %g", worst);
    /* a single matrix: a copy without header */
    REQUIRE(hd_matrix_chain(&out, ms, 1, 1, NULL, NULL) == HD_OK);
    CHECK(out.nrows == 50 && out.ncols == 40 && out.data[7] == a.data[7]);
    /* errors as left to right */
    const hd_matrix *bad[3] = {&a, &c, &d};
    CHECK(hd_matrix_chain(&out, bad, 3, 1, NULL, NULL) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "50 x 40 times 30 x 20");
    hd_matrix e;
    hd_matrix_init(&e);
    REQUIRE(hd_matrix_alloc(&e, 30, 2, 2) == HD_OK);
    const hd_matrix *bad2[3] = {&a, &b, &e};
    CHECK(hd_matrix_chain(&out, bad2, 3, 1, NULL, NULL) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "component counts differ (3 and 2");
    hd_matrix_free(&a); hd_matrix_free(&b); hd_matrix_free(&c); hd_matrix_free(&d); hd_matrix_free(&e);
    hd_matrix_free(&ab); hd_matrix_free(&abc); hd_matrix_free(&out);
}

static void test_transpose_elementwise(void)
{
    hd_matrix a, b, t;
    hd_matrix_init(&a); hd_matrix_init(&b); hd_matrix_init(&t);
    const double av[] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};   /* 2 x 3 x 2 */
    set_vals(&a, 2, 3, 2, av);
    REQUIRE(hd_matrix_transpose(&t, &a) == HD_OK);
    CHECK(t.nrows == 3 && t.ncols == 2 && t.ncomp == 2);
    CHECK(hd_matrix_at(&t, 2, 1)[0] == 11 && hd_matrix_at(&t, 2, 1)[1] == 12);
    CHECK(hd_matrix_at(&t, 0, 1)[0] == 7);
    const double bv[] = {2, 0, 4, 1, 0.5, 8};                       /* 2 x 3 x 1 */
    set_vals(&b, 2, 3, 1, bv);
    REQUIRE(hd_matrix_copy(&t, &a) == HD_OK);
    CHECK(hd_matrix_elementwise(&t, &b, HD_MTXOP_ADD, NULL) == HD_OK);
    CHECK(t.data[0] == 3 && t.data[1] == 4 && t.data[2] == 3 && t.data[11] == 20);
    REQUIRE(hd_matrix_copy(&t, &a) == HD_OK);
    CHECK(hd_matrix_elementwise(&t, &b, HD_MTXOP_EMUL, NULL) == HD_OK);
    CHECK(t.data[0] == 2 && t.data[3] == 0 && t.data[9] == 5);
    REQUIRE(hd_matrix_copy(&t, &a) == HD_OK);
    unsigned long nz = 0;
    int w0 = hd_warnings_enabled();
    hd_set_warnings(0);
    CHECK(hd_matrix_elementwise(&t, &b, HD_MTXOP_EDIV, &nz) == HD_OK);
    hd_set_warnings(w0);
    CHECK(nz == 2);                              /* element 1 (two components) */
    CHECK(t.data[0] == 0.5 && t.data[2] == 0 && t.data[3] == 0 && t.data[8] == 18);
    /* size mismatch */
    CHECK(hd_matrix_elementwise(&t, &a, HD_MTXOP_ADD, NULL) == HD_OK);
    hd_matrix_transpose(&b, &a);
    CHECK(hd_matrix_elementwise(&t, &b, HD_MTXOP_ADD, NULL) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "sizes differ");
    hd_matrix_free(&a); hd_matrix_free(&b); hd_matrix_free(&t);
}

static void test_transform_scale(void)
{
    hd_matrix a, t;
    hd_matrix_init(&a); hd_matrix_init(&t);
    const double av[] = {1, 2, 3, 10, 20, 30};   /* 1 x 2 x 3 */
    set_vals(&a, 1, 2, 3, av);
    const double lum[] = {47.4, 119.9, 11.6};
    REQUIRE(hd_matrix_transform(&t, &a, lum, 1) == HD_OK);
    CHECK(t.ncomp == 1 && t.ncols == 2);
    CHECK_NEAR(t.data[0], 47.4 + 2 * 119.9 + 3 * 11.6, 1e-12);
    CHECK_NEAR(t.data[1], 474 + 2398 + 348, 1e-9);
    const double swap[] = {0, 0, 1, 0, 1, 0};    /* 2 outputs: B, G */
    REQUIRE(hd_matrix_transform(&t, &a, swap, 2) == HD_OK);
    CHECK(t.ncomp == 2 && t.data[0] == 3 && t.data[1] == 2 && t.data[2] == 30);
    const double sf[] = {2, 3, 4};
    CHECK(hd_matrix_scale(&a, sf, 3) == HD_OK);
    CHECK(a.data[0] == 2 && a.data[1] == 6 && a.data[5] == 120);
    CHECK(hd_matrix_scale(&a, sf, 1) == HD_OK);
    CHECK(a.data[5] == 240);
    CHECK(hd_matrix_scale(&a, sf, 2) == HD_ERR_USAGE);
    hd_matrix_free(&a); hd_matrix_free(&t);
}

static void test_combine(void)
{
    CHECK(hd_mtxfmt_combine(HD_MTX_FLOAT, HD_MTX_ASCII) == HD_MTX_ASCII);
    CHECK(hd_mtxfmt_combine(HD_MTX_DOUBLE, HD_MTX_FLOAT) == HD_MTX_FLOAT);
    CHECK(hd_mtxfmt_combine(HD_MTX_DOUBLE, HD_MTX_DOUBLE) == HD_MTX_DOUBLE);
    CHECK(hd_mtxfmt_combine(HD_MTX_RGBE, HD_MTX_RGBE) == HD_MTX_RGBE);
    CHECK(hd_mtxfmt_combine(HD_MTX_RGBE, HD_MTX_DOUBLE) == HD_MTX_FLOAT);
    CHECK(hd_mtxfmt_combine(HD_MTX_RGBE, HD_MTX_XYZE) == HD_MTX_FLOAT);
    CHECK(hd_mtxfmt_parse("32-bit_rle_xyze") == HD_MTX_XYZE && hd_mtxfmt_parse("floats") == -1);
}

/* hd_matrix_alloc and hd_matrix_read take uninitialised structs (outputs). */
static void test_uninitialised_outputs(void)
{
    hd_matrix m;
    memset(&m, 0xAB, sizeof m);
    REQUIRE(hd_matrix_alloc(&m, 2, 3, 1) == HD_OK);
    CHECK(m.data[5] == 0 && m.hdr.len == 0);
    hd_matrix_free(&m);
    const char *p = tmpname("uninit.mtx");
    const char *t = "#?RADIANCE\nNROWS=1\nNCOLS=1\nNCOMP=1\nFORMAT=ascii\n\n4\n";
    REQUIRE(write_bytes(p, t, strlen(t)) == 0);
    memset(&m, 0xCD, sizeof m);
    REQUIRE(hd_matrix_read(p, &m, NULL) == HD_OK);
    CHECK(m.data[0] == 4);
    hd_matrix_free(&m);
    memset(&m, 0xCD, sizeof m);
    CHECK(hd_matrix_read("/nonexistent/u.mtx", &m, NULL) == HD_ERR_IO);
    CHECK(m.data == NULL);
    hd_matrix_free(&m);       /* safe after an error */
}

/* ----------------------------------------------------------- bad input */

static void expect_fail(const char *what, const void *data, size_t n, hd_status want, const char *msg1,
                        const char *msg2)
{
    const char *p = tmpname("bad.mtx");
    if (write_bytes(p, data, n)) { CHECK_MSG(0, "cannot write %s", p); return; }
    hd_matrix m;
    hd_matrix_init(&m);
    hd_status st = hd_matrix_read(p, &m, &HDR);
    CHECK_MSG(st == want, "%s: status %s, expected %s (%s)", what, hd_status_name(st), hd_status_name(want),
              hd_errmsg());
    CHECK_CONTAINS(hd_errmsg(), "bad.mtx");
    if (msg1) CHECK_CONTAINS(hd_errmsg(), msg1);
    if (msg2) CHECK_CONTAINS(hd_errmsg(), msg2);
    CHECK(m.data == NULL);
    hd_matrix_free(&m);
}

static void test_bad_input(void)
{
    char buf[512];
    int n = snprintf(buf, sizeof buf, "#?RADIANCE\nNROWS=3\nNCOLS=4\nNCOMP=3\nBigEndian=0\nFORMAT=float\n\n");
    memset(buf + n, 0, 100);     /* 100 of the 144 bytes */
    expect_fail("truncated float", buf, (size_t)n + 100, HD_ERR_FORMAT, "byte offset", "needs 144 bytes");
    n = snprintf(buf, sizeof buf, "#?RADIANCE\nNROWS=2\nNCOLS=2\nNCOMP=1\nFORMAT=double\n\n");
    memset(buf + n, 0, 31);
    expect_fail("truncated double", buf, (size_t)n + 31, HD_ERR_FORMAT, "byte offset", "needs 32 bytes");
    const char *t;
    t = "#?RADIANCE\nNROWS=-1\nNCOLS=3\nNCOMP=3\nFORMAT=ascii\n\n1 2 3\n";
    expect_fail("NROWS=-1", t, strlen(t), HD_ERR_RANGE, "NROWS=-1", NULL);
    t = "#?RADIANCE\nNROWS=3\nNCOLS=0\nFORMAT=ascii\n\n1 2 3\n";
    expect_fail("NCOLS=0", t, strlen(t), HD_ERR_RANGE, "NCOLS=0", NULL);
    t = "#?RADIANCE\nNROWS=3\nNCOLS=3\nNCOMP=0\nFORMAT=ascii\n\n1 2 3\n";
    expect_fail("NCOMP=0", t, strlen(t), HD_ERR_RANGE, "NCOMP=0", NULL);
    t = "#?RADIANCE\nNROWS=2000000000\nNCOLS=2000000000\nNCOMP=3\nFORMAT=float\n\n";
    expect_fail("huge", t, strlen(t), HD_ERR_RANGE, "exceeds the limit", "NROWS=2000000000");
    t = "#?RADIANCE\nNROWS=99999999999\nNCOLS=2\nFORMAT=float\n\n";
    expect_fail("NROWS over int", t, strlen(t), HD_ERR_RANGE, "NROWS=99999999999", NULL);
    t = "#?RADIANCE\nNROWS=abc\nNCOLS=2\nFORMAT=float\n\n";
    expect_fail("NROWS=abc", t, strlen(t), HD_ERR_FORMAT, "NROWS", NULL);
    t = "#?RADIANCE\nNROWS=2\nNCOLS=2\nNCOMP=1\nFORMAT=ascii\n\n1 2\n3 x4\n";
    expect_fail("non-numeric", t, strlen(t), HD_ERR_FORMAT, "line 8", "x4");
    t = "#?RADIANCE\nNROWS=2\nNCOLS=2\nNCOMP=1\nFORMAT=ascii\n\n1 2\n3\n";
    expect_fail("short ascii", t, strlen(t), HD_ERR_FORMAT, "expected 4 values", NULL);
    t = "#?RADIANCE\nNROWS=2\nNCOLS=2\nNCOMP=1\nFORMAT=flaot\n\n1 2 3 4\n";
    expect_fail("wrong FORMAT", t, strlen(t), HD_ERR_FORMAT, "FORMAT=flaot", NULL);
    t = "#?RADIANCE\nNROWS=2\nNCOLS=2\nNCOMP=1\nFORMAT=Radiance_spectra\n\n";
    expect_fail("spectral", t, strlen(t), HD_ERR_UNSUPPORTED, "Radiance_spectra", NULL);
    t = "#?RADIANCE\nNROWS=1\nNCOLS=1\nBigEndian=7\nFORMAT=float\n\n1234";
    expect_fail("BigEndian=7", t, strlen(t), HD_ERR_FORMAT, "BigEndian=7", NULL);
    t = "#?RADIANCE\nNROWS=2\nNCOMP=1\nFORMAT=ascii\n\n1 2 3 4\n";
    expect_fail("no NCOLS, no resolution", t, strlen(t), HD_ERR_FORMAT, "NCOLS", NULL);
    t = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 2\n\x80\x80\x80\x81";
    expect_fail("truncated picture", t, strlen(t), HD_ERR_FORMAT, NULL, NULL);
    t = "";
    expect_fail("empty file", t, 0, HD_ERR_FORMAT, NULL, NULL);
    /* missing file, XML */
    hd_matrix m;
    hd_matrix_init(&m);
    CHECK(hd_matrix_read("/nonexistent/x.mtx", &m, &HDR) == HD_ERR_IO);
    CHECK_CONTAINS(hd_errmsg(), "/nonexistent/x.mtx");
    CHECK(hd_matrix_read("/nonexistent/window.XML", &m, &HDR) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "window.XML");
    /* allocation of absurd sizes refused */
    CHECK(hd_matrix_alloc(&m, 2000000000, 2000000000, 3) == HD_ERR_RANGE);
    CHECK(hd_matrix_alloc(&m, -1, 2, 3) == HD_ERR_RANGE);
    CHECK(m.data == NULL);
    /* picture output of 2 components refused */
    REQUIRE(hd_matrix_alloc(&m, 1, 1, 2) == HD_OK);
    FILE *fp = fopen(tmpname("x.hdr"), "wb");
    REQUIRE(fp);
    CHECK(hd_matrix_write(fp, &m, NULL, 1, HD_MTX_RGBE) == HD_ERR_USAGE);
    fclose(fp);
    hd_matrix_free(&m);
}

/* Truncations and byte flips of valid files in every format: any status
 * is fine, but no crash (run under check-asan), and on error no data. */
static void test_corrupt_no_crash(void)
{
    hd_matrix m;
    hd_matrix_init(&m);
    REQUIRE(hd_matrix_alloc(&m, 4, 20, 3) == HD_OK);
    fill(&m, 1);
    unsigned seed = 12345;
    int nok = 0, nfail = 0;
    const hd_mtxfmt fmts[] = {HD_MTX_ASCII, HD_MTX_FLOAT, HD_MTX_DOUBLE, HD_MTX_RGBE};
    for (int f = 0; f < 4; f++) {
        const char *p = tmpname("fuzz.src");
        FILE *fp = fopen(p, "wb");
        REQUIRE(fp);
        REQUIRE(hd_matrix_write(fp, &m, NULL, 1, fmts[f]) == HD_OK);
        fclose(fp);
        size_t n;
        char *b = slurp(p, &n);
        REQUIRE(b);
        char *c = malloc(n);
        REQUIRE(c);
        const char *q = tmpname("fuzz.mtx");
        for (int trial = 0; trial < 300; trial++) {
            size_t len = n;
            memcpy(c, b, n);
            seed = seed * 1103515245u + 12345u;
            if (trial < 100) {
                len = (size_t)(seed >> 8) % n;          /* truncation */
            } else {
                for (int k = 0; k < 1 + trial % 4; k++) { /* byte flips */
                    seed = seed * 1103515245u + 12345u;
                    size_t at = (size_t)(seed >> 8) % n;
                    seed = seed * 1103515245u + 12345u;
                    c[at] = (char)(seed >> 16);
                }
            }
            if (write_bytes(q, c, len)) continue;
            hd_matrix r;
            hd_matrix_init(&r);
            hd_status st = hd_matrix_read(q, &r, &HDR);
            if (st == HD_OK) {
                nok++;
                CHECK(r.data != NULL && r.nrows > 0 && r.ncols > 0 && r.ncomp > 0);
            } else {
                nfail++;
                CHECK(r.data == NULL);
                CHECK(hd_errmsg()[0] != 0);
            }
            hd_matrix_free(&r);
        }
        free(b);
        free(c);
    }
    CHECK(nfail > 100);          /* truncations at least */
    printf("  corrupted inputs: %d read, %d refused\n", nok, nfail);
    hd_matrix_free(&m);
}

int main(void)
{
    hd_set_progname("test_matrix");
    RUN(test_roundtrip_ascii);
    RUN(test_roundtrip_float);
    RUN(test_roundtrip_double);
    RUN(test_roundtrip_rgbe);
    RUN(test_roundtrip_xyze);
    RUN(test_byte_orders);
    RUN(test_native_order);
    RUN(test_headerless);
    RUN(test_exposure);
    RUN(test_picture_exposure);
    RUN(test_ref_picture);
    RUN(test_picture_orientations);
    RUN(test_no_ident);
    RUN(test_gzip_and_command);
    RUN(test_ref_all_matrices);
    RUN(test_ref_float_raw);
    RUN(test_ref_xml);
    RUN(test_ref_product);
    RUN(test_ref_ascii_vs_float);
    RUN(test_header_layout);
    RUN(test_writer_streaming);
    RUN(test_writer_dctimestep_style);
    RUN(test_multiply);
    RUN(test_multiply_mt);
    RUN(test_chain);
    RUN(test_transpose_elementwise);
    RUN(test_transform_scale);
    RUN(test_combine);
    RUN(test_uninitialised_outputs);
    RUN(test_bad_input);
    RUN(test_corrupt_no_crash);
    return hd_test_done();
}

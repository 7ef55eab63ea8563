/* Unit tests for the Radiance picture module (src/picture.c). */
#include "hd_test.h"
#include "heliodon/picture.h"

#include <dirent.h>
#include <stdint.h>
#include <time.h>

/* ---- helpers ---- */

/* Radiance's setcolr as the spec (§2.3) describes it, in double with frexp:
 * an independent reference for hd_rgbe_encode. */
static void ref_encode(uint8_t out[4], double r, double g, double b)
{
    double d = r > g ? r : g;
    if (b > d) d = b;
    if (d <= 1e-32) { out[0] = out[1] = out[2] = out[3] = 0; return; }
    int e;
    d = frexp(d, &e) * 256.0 / d;
    out[0] = r > 0 ? (uint8_t)(r * d) : 0;
    out[1] = g > 0 ? (uint8_t)(g * d) : 0;
    out[2] = b > 0 ? (uint8_t)(b * d) : 0;
    out[3] = (uint8_t)(e + 128);
}

static uint64_t rng_state = 88172645463325252ull;
static uint32_t rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (uint32_t)(rng_state >> 11);
}
static double rndu(void) { return rnd() / 4294967296.0; }

static hd_istream *mem_stream(const void *data, size_t n, const char *name)
{
    hd_istream *s = NULL;
    if (hd_istream_memory(&s, data, n, name)) return NULL;
    return s;
}

/* write a picture into memory */
static unsigned char *write_mem(const hd_picture *p, int orient, size_t *n)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *fp = open_memstream(&buf, &len);
    if (!fp) return NULL;
    hd_header h;
    hd_header_init(&h);
    hd_header_append(&h, "test_picture");
    hd_status st = hd_picture_write(fp, p, &h, orient);
    hd_header_free(&h);
    fclose(fp);
    if (st) { free(buf); return NULL; }
    *n = len;
    return (unsigned char *)buf;
}

static hd_status read_mem(const void *data, size_t n, hd_picture *p)
{
    hd_istream *s = mem_stream(data, n, "mem.hdr");
    if (!s) return HD_ERR_IO;
    hd_status st = hd_picture_read_stream(s, p);
    hd_istream_close(s);
    return st;
}

/* ---- RGBE pixels ---- */

static void test_rgbe_exact(void)
{
    uint8_t c[4];
    float v[3];
    hd_rgbe_encode(c, 0, 0, 0);
    CHECK(c[0] == 0 && c[1] == 0 && c[2] == 0 && c[3] == 0);
    hd_rgbe_encode(c, 1e-33f, 1e-33f, 0);          /* below 1e-32: black */
    CHECK(c[0] == 0 && c[3] == 0);
    hd_rgbe_encode(c, 1, 1, 1);                    /* 1 = 0.5*2^1 -> 128, e 129 */
    CHECK(c[0] == 128 && c[1] == 128 && c[2] == 128 && c[3] == 129);
    hd_rgbe_encode(c, 0.5f, 0.25f, -3.0f);         /* negative clamps to 0 */
    CHECK(c[0] == 128 && c[1] == 64 && c[2] == 0 && c[3] == 128);
    hd_rgbe_encode(c, 1000.0f, 1.0f, 0.0f);        /* 1000 = 0.9765625*2^10 */
    CHECK(c[0] == 250 && c[1] == 0 && c[2] == 0 && c[3] == 138);
    hd_rgbe_encode(c, 0.999f, 0.0f, 0.0f);          /* 0.999*256 = 255.74 -> 255 */
    CHECK(c[0] == 255 && c[3] == 128);
    /* decode adds 0.5 to the mantissa: (m+0.5)*2^(e-136) */
    uint8_t d1[4] = {128, 128, 128, 129};
    hd_rgbe_decode(d1, v);
    CHECK(v[0] == 1.00390625f && v[1] == v[0] && v[2] == v[0]);
    uint8_t d2[4] = {0, 64, 255, 128};
    hd_rgbe_decode(d2, v);
    CHECK(v[0] == 0.5f / 256 && v[1] == 64.5f / 256 && v[2] == 255.5f / 256);
    uint8_t d3[4] = {200, 10, 0, 0};               /* e == 0: black whatever the mantissas */
    hd_rgbe_decode(d3, v);
    CHECK(v[0] == 0 && v[1] == 0 && v[2] == 0);
    uint8_t d4[4] = {255, 1, 0, 255};
    hd_rgbe_decode(d4, v);
    CHECK(v[0] == (float)ldexp(255.5, 255 - 136) && v[1] == (float)ldexp(1.5, 119));
    /* every exponent and mantissa against Radiance's double formula */
    int nbad = 0;
    for (int e = 1; e < 256; e++)
        for (int m = 0; m < 256; m++) {
            uint8_t q[4] = {(uint8_t)m, (uint8_t)(255 - m), 0, (uint8_t)e};
            hd_rgbe_decode(q, v);
            if (v[0] != (float)((m + 0.5) * ldexp(1.0, e - 136)) ||
                v[1] != (float)((255 - m + 0.5) * ldexp(1.0, e - 136)) ||
                v[2] != (float)(0.5 * ldexp(1.0, e - 136)))
                nbad++;
        }
    CHECK(nbad == 0);
    /* huge and non-finite inputs do not wrap the exponent */
    hd_rgbe_encode(c, INFINITY, 1.0f, 0.0f);
    CHECK(c[3] == 255 && c[0] == 255);
    hd_rgbe_encode(c, NAN, NAN, NAN);
    CHECK(c[3] == 0);
}

static void test_rgbe_vs_reference(void)
{
    int bad = 0;
    for (int i = 0; i < 2000000; i++) {
        float r, g, b;
        int mode = i % 4;
        double scale = ldexp(1.0, (int)(rnd() % 200) - 100);
        r = (float)(rndu() * scale);
        g = (float)(rndu() * scale);
        b = (float)(rndu() * scale);
        if (mode == 1) { g = r; b = (float)ldexp(1.0, (int)(rnd() % 120) - 60); }   /* powers of two */
        if (mode == 2) { r = nextafterf((float)ldexp(1.0, (int)(rnd() % 120) - 60), 0); }
        if (mode == 3 && (rnd() & 1)) g = -g;
        uint8_t a[4], e[4];
        hd_rgbe_encode(a, r, g, b);
        ref_encode(e, r, g, b);
        if (memcmp(a, e, 4)) {
            if (bad < 5)
                printf("  rgbe(%.9g %.9g %.9g) = %d %d %d %d, reference %d %d %d %d\n", r, g, b,
                       a[0], a[1], a[2], a[3], e[0], e[1], e[2], e[3]);
            bad++;
        }
    }
    CHECK(bad == 0);
    /* every normalised pixel (max mantissa >= 128) decodes and re-encodes to itself */
    bad = 0;
    for (int e = 1; e < 256; e++)
        for (int m = 128; m < 256; m++) {
            uint8_t c[4] = {(uint8_t)m, (uint8_t)(rnd() % (m + 1)), (uint8_t)(rnd() % (m + 1)), (uint8_t)e};
            float v[3];
            uint8_t c2[4];
            hd_rgbe_decode(c, v);
            hd_rgbe_encode(c2, v[0], v[1], v[2]);
            if (memcmp(c, c2, 4) && e > 22) bad++;   /* e <= 22 is below the 1e-32 cut-off */
        }
    CHECK(bad == 0);
    /* the _n variants agree with the single-pixel ones */
    float rgb[30];
    uint8_t q[40], q1[4];
    for (int i = 0; i < 30; i++) rgb[i] = (float)(rndu() * 10);
    hd_rgbe_encode_n(q, rgb, 10);
    for (int i = 0; i < 10; i++) {
        hd_rgbe_encode(q1, rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]);
        CHECK(!memcmp(q1, q + 4 * i, 4));
    }
    float back[30], b1[3];
    hd_rgbe_decode_n(back, q, 10);
    for (int i = 0; i < 10; i++) {
        hd_rgbe_decode(q + 4 * i, b1);
        CHECK(b1[0] == back[3 * i] && b1[1] == back[3 * i + 1] && b1[2] == back[3 * i + 2]);
    }
    float one[3] = {1, 1, 1}, grn[3] = {0, 1, 0};
    CHECK_NEAR(hd_rgb_bright(one), 1.0, 1e-8);
    CHECK_NEAR(hd_rgb_bright(grn), 0.670114631, 1e-12);
}

/* ---- resolution strings ---- */

static void test_resolu_strings(void)
{
    static const struct { const char *s; int orient; int xres, yres; } cases[] = {
        {"-Y 512 +X 768", HD_RES_YMAJOR | HD_RES_YDECR, 768, 512},
        {"+Y 512 +X 768", HD_RES_YMAJOR, 768, 512},
        {"-Y 512 -X 768", HD_RES_YMAJOR | HD_RES_YDECR | HD_RES_XDECR, 768, 512},
        {"+Y 512 -X 768", HD_RES_YMAJOR | HD_RES_XDECR, 768, 512},
        {"+X 768 +Y 512", 0, 768, 512},
        {"-X 768 +Y 512", HD_RES_XDECR, 768, 512},
        {"+X 768 -Y 512", HD_RES_YDECR, 768, 512},
        {"-X 768 -Y 512", HD_RES_XDECR | HD_RES_YDECR, 768, 512},
        {"-Y      256 +X      256\n", HD_RES_STANDARD, 256, 256},
        {"-Y256 +X5", HD_RES_STANDARD, 5, 256},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        hd_resolu r;
        CHECK_MSG(hd_resolu_parse(cases[i].s, &r, "t") == HD_OK, "parse %s: %s", cases[i].s, hd_errmsg());
        CHECK(r.orient == cases[i].orient && r.xres == cases[i].xres && r.yres == cases[i].yres);
        /* format and parse back */
        char buf[64];
        hd_resolu r2;
        hd_resolu_format(buf, sizeof buf, &r);
        CHECK(hd_resolu_parse(buf, &r2, "t") == HD_OK);
        CHECK(r2.orient == r.orient && r2.xres == r.xres && r2.yres == r.yres);
        CHECK(hd_resolu_scanlen(&r) == ((r.orient & HD_RES_YMAJOR) ? r.xres : r.yres));
    }
    hd_resolu r = {HD_RES_STANDARD, 768, 512};
    char buf[64];
    hd_resolu_format(buf, sizeof buf, &r);
    CHECK_STR(buf, "-Y      512 +X      768\n");
    r.orient = HD_RES_XDECR;
    hd_resolu_format(buf, sizeof buf, &r);
    CHECK_STR(buf, "-X      768 +Y      512\n");
    /* bad strings */
    const char *bad[] = {"", "Y 512 X 768", "-Y 512", "-Y 512 +Y 768", "-Y abc +X 5", "-Y 5 +X 5 junk",
                         "-Y 0 +X 5", "-Y -5 +X 5", "-Y 5 *X 5"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        hd_status st = hd_resolu_parse(bad[i], &r, "file.hdr: byte offset 9");
        CHECK_MSG(st != HD_OK, "accepted bad resolution \"%s\"", bad[i]);
        CHECK_CONTAINS(hd_errmsg(), "file.hdr: byte offset 9");
    }
    CHECK(hd_resolu_parse("-Y 2000000000 +X 2000000000", &r, "t") == HD_ERR_RANGE);
    CHECK(hd_resolu_parse("-Y 1000000 +X 1000000", &r, "t") == HD_ERR_RANGE);  /* > 2^31 pixels */
    CHECK(hd_resolu_parse("-Y 99999999999999999999 +X 3", &r, "t") == HD_ERR_RANGE);
}

/* Pixel placement by hand: a 2x3 picture stored in every orientation. */
static void test_orientation_by_hand(void)
{
    /* image (row 0 = top):   A B
     *                        C D
     *                        E F      xres 2, yres 3 */
    const uint8_t px[6][4] = {{130, 0, 0, 129}, {0, 130, 0, 129}, {0, 0, 130, 129},
                              {140, 0, 0, 129}, {0, 140, 0, 129}, {0, 0, 140, 129}};
    enum { A, B, C, D, E, F };
    struct { const char *res; int order[6]; } cases[] = {
        {"-Y 3 +X 2", {A, B, C, D, E, F}},     /* standard: top row first, left to right */
        {"+Y 3 +X 2", {E, F, C, D, A, B}},     /* bottom row first */
        {"-Y 3 -X 2", {B, A, D, C, F, E}},     /* right to left */
        {"+Y 3 -X 2", {F, E, D, C, B, A}},
        {"+X 2 +Y 3", {E, C, A, F, D, B}},     /* columns, left first, bottom to top */
        {"+X 2 -Y 3", {A, C, E, B, D, F}},     /* columns, left first, top to bottom */
        {"-X 2 +Y 3", {F, D, B, E, C, A}},     /* right column first, bottom to top */
        {"-X 2 -Y 3", {B, D, F, A, C, E}},
    };
    for (size_t k = 0; k < 8; k++) {
        unsigned char file[256];
        int n = snprintf((char *)file, sizeof file, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n%s\n", cases[k].res);
        for (int i = 0; i < 6; i++) { memcpy(file + n, px[cases[k].order[i]], 4); n += 4; }
        hd_picture p;
        hd_status st = read_mem(file, (size_t)n, &p);
        REQUIRE(st == HD_OK);
        CHECK(p.xres == 2 && p.yres == 3);
        for (int i = 0; i < 6; i++) {
            float v[3];
            hd_rgbe_decode(px[i], v);
            CHECK_MSG(p.pix[3 * i] == v[0] && p.pix[3 * i + 1] == v[1] && p.pix[3 * i + 2] == v[2],
                      "orientation %s: pixel %c misplaced", cases[k].res, 'A' + i);
        }
        /* writing in that orientation reproduces the same data bytes */
        size_t wn;
        unsigned char *w = write_mem(&p, p.orient, &wn);
        REQUIRE(w);
        CHECK(wn >= 24 && !memcmp(w + wn - 24, file + n - 24, 24));
        free(w);
        hd_picture_free(&p);
    }
}

static void fill_test_picture(hd_picture *p, int xres, int yres)
{
    hd_picture_alloc(p, xres, yres);
    for (int y = 0; y < yres; y++)
        for (int x = 0; x < xres; x++) {
            float *d = p->pix + 3 * ((size_t)y * xres + x);
            /* smooth areas (runs), noise (literals) and black */
            if (x < xres / 3) { d[0] = 0.5f; d[1] = 0.25f; d[2] = (float)y; }
            else if (x < 2 * xres / 3) { d[0] = (float)rndu(); d[1] = (float)(rndu() * 100); d[2] = (float)(rndu() * 1e-3); }
            else { d[0] = d[1] = d[2] = (x & 4) ? 0.0f : 3.0f; }
        }
    /* quantise to RGBE so that round trips are exact */
    for (size_t i = 0; i < (size_t)xres * yres; i++) {
        uint8_t c[4];
        hd_rgbe_encode(c, p->pix[3 * i], p->pix[3 * i + 1], p->pix[3 * i + 2]);
        hd_rgbe_decode(c, p->pix + 3 * i);
    }
}

static void test_orientation_roundtrip(void)
{
    hd_picture p, q;
    fill_test_picture(&p, 37, 29);
    for (int o = 0; o < 8; o++) {
        size_t n;
        unsigned char *buf = write_mem(&p, o, &n);
        REQUIRE(buf);
        REQUIRE(read_mem(buf, n, &q) == HD_OK);
        CHECK(q.orient == o && q.xres == 37 && q.yres == 29);
        CHECK_MSG(!memcmp(q.pix, p.pix, sizeof(float) * 3 * 37 * 29), "orientation %d differs", o);
        char line[64];
        CHECK(hd_header_get(&q.hdr, "FORMAT", line, sizeof line) == 0);   /* removed */
        CHECK(strstr(q.hdr.text, "test_picture\n") != NULL);
        hd_picture_free(&q);
        free(buf);
    }
    /* XYZE is kept */
    p.fmt = HD_PIC_XYZE;
    size_t n;
    unsigned char *buf = write_mem(&p, HD_RES_STANDARD, &n);
    REQUIRE(buf);
    CHECK(strstr((char *)buf, "FORMAT=32-bit_rle_xyze\n\n-Y       29 +X       37\n") != NULL);
    CHECK(read_mem(buf, n, &q) == HD_OK && q.fmt == HD_PIC_XYZE);
    hd_picture_free(&q);
    free(buf);
    hd_picture_free(&p);
}

/* scanlines: flat (short and long), RLE, old RLE */
static void scan_roundtrip(int len, int expect_rle)
{
    uint8_t *sl = malloc((size_t)len * 4), *back = malloc((size_t)len * 4);
    for (int i = 0; i < len; i++) {
        float r = (i % 50 < 20) ? 1.0f : (float)rndu(), g = (i % 7) ? 0.3f : 2.0f, b = (float)(i / 100);
        hd_rgbe_encode(sl + 4 * i, r, g, b);
    }
    char *buf = NULL;
    size_t n = 0;
    FILE *fp = open_memstream(&buf, &n);
    CHECK(hd_scanline_write(fp, sl, len) == HD_OK);
    CHECK(hd_scanline_write(fp, sl, len) == HD_OK);   /* two in a row */
    fclose(fp);
    if (expect_rle) CHECK(n >= 4 && buf[0] == 2 && buf[1] == 2 && (buf[2] & 0xff) == (len >> 8) && (buf[3] & 0xff) == (len & 0xff));
    else CHECK(n == (size_t)len * 8);
    CHECK(n / 2 <= hd_scanline_maxbytes(len));
    hd_istream *s = mem_stream(buf, n, "scan");
    CHECK(hd_scanline_read(s, back, len) == HD_OK && !memcmp(back, sl, (size_t)len * 4));
    memset(back, 0, (size_t)len * 4);
    CHECK(hd_scanline_read(s, back, len) == HD_OK && !memcmp(back, sl, (size_t)len * 4));
    CHECK(hd_istream_getc(s) == EOF);
    hd_istream_close(s);
    free(buf);
    free(sl);
    free(back);
}

static void test_scanline_roundtrip(void)
{
    scan_roundtrip(1, 0);
    scan_roundtrip(16, 0);       /* < 17: flat */
    scan_roundtrip(17, 1);
    scan_roundtrip(500, 1);
    scan_roundtrip(32767, 1);
    scan_roundtrip(32768, 0);    /* > 32767: flat */
    scan_roundtrip(40000, 0);
}

static void test_old_rle(void)
{
    /* P0 P1 [1,1,1,3] P2 [1,1,1,2] [1,1,1,1] P3 -> P0 P1 P1 P1 P1 P2 + (2 + 256) x P2 + P3 */
    const uint8_t P0[4] = {10, 20, 30, 130}, P1[4] = {40, 50, 60, 131}, P2[4] = {70, 80, 90, 132},
                  P3[4] = {100, 110, 120, 133};
    const uint8_t M3[4] = {1, 1, 1, 3}, M2[4] = {1, 1, 1, 2}, M1[4] = {1, 1, 1, 1};
    uint8_t data[64];
    size_t n = 0;
    const uint8_t *seq[] = {P0, P1, M3, P2, M2, M1, P3};
    for (int i = 0; i < 7; i++) { memcpy(data + n, seq[i], 4); n += 4; }
    int len = 1 + 1 + 3 + 1 + 258 + 1;   /* 265: read as old format since byte 0 != 2 */
    uint8_t *sl = calloc((size_t)len, 4);
    hd_istream *s = mem_stream(data, n, "old");
    CHECK(hd_scanline_read(s, sl, len) == HD_OK);
    hd_istream_close(s);
    CHECK(!memcmp(sl, P0, 4));
    for (int i = 1; i <= 4; i++) CHECK(!memcmp(sl + 4 * i, P1, 4));
    for (int i = 5; i < 5 + 259; i++) CHECK(!memcmp(sl + 4 * i, P2, 4));
    CHECK(!memcmp(sl + 4 * (len - 1), P3, 4));
    free(sl);
    /* short scanline (< 17 pixels) with a marker: P0 [1,1,1,4] = 5 pixels */
    uint8_t d2[8];
    memcpy(d2, P0, 4);
    memcpy(d2 + 4, (uint8_t[4]){1, 1, 1, 4}, 4);
    uint8_t sl5[20];
    s = mem_stream(d2, 8, "old5");
    CHECK(hd_scanline_read(s, sl5, 5) == HD_OK);
    hd_istream_close(s);
    for (int i = 0; i < 5; i++) CHECK(!memcmp(sl5 + 4 * i, P0, 4));
    /* a flat scanline starting with byte 2 but not an RLE marker */
    uint8_t d3[17 * 4];
    for (int i = 0; i < 17; i++) { d3[4 * i] = 2; d3[4 * i + 1] = (uint8_t)(3 + i); d3[4 * i + 2] = 0; d3[4 * i + 3] = 130; }
    uint8_t sl17[17 * 4];
    s = mem_stream(d3, sizeof d3, "flat2");
    CHECK(hd_scanline_read(s, sl17, 17) == HD_OK && !memcmp(sl17, d3, sizeof d3));
    hd_istream_close(s);
}

/* Radiance's run-length writer, checked against hand-computed packets. */
static void check_component(const uint8_t *vals, int len, const uint8_t *expect, size_t elen, const char *what)
{
    /* put vals in component 1 (green); other components constant 0x80 (one run each when len<=127) */
    uint8_t *sl = malloc((size_t)len * 4), *out = malloc(hd_scanline_maxbytes(len));
    for (int i = 0; i < len; i++) { sl[4 * i] = 0x80; sl[4 * i + 1] = vals[i]; sl[4 * i + 2] = 0x80; sl[4 * i + 3] = 0x80; }
    size_t n = hd_scanline_encode(out, sl, len);
    /* header 4 + red packets + green + blue + exp; red: runs of <=127 */
    size_t runbytes = 2 * (size_t)((len + 126) / 127);
    CHECK_MSG(n == 4 + 3 * runbytes + elen, "%s: %zu bytes, expected %zu", what, n, 4 + 3 * runbytes + elen);
    CHECK_MSG(n >= 4 + runbytes + elen && !memcmp(out + 4 + runbytes, expect, elen), "%s: packets differ", what);
    free(sl);
    free(out);
}

static void test_rle_writer_bytes(void)
{
    /* the spec's example: 20-pixel gradient in red -> literal 0x14 + 20 bytes;
     * constant 0.5 green -> run 0x94 0x80 */
    uint8_t sl[80], out[256];
    for (int k = 0; k < 20; k++) hd_rgbe_encode(sl + 4 * k, (float)((k + 0.5) / 20), 0.5f, 0.25f);
    size_t n = hd_scanline_encode(out, sl, 20);
    uint8_t expect[4 + 21 + 2 + 2 + 2];
    size_t e = 0;
    expect[e++] = 2; expect[e++] = 2; expect[e++] = 0; expect[e++] = 20;
    expect[e++] = 0x14;
    for (int k = 0; k < 20; k++) expect[e++] = (uint8_t)floor((k + 0.5) / 20 * 256);  /* max channel in [.5,1): e = 128 */
    expect[e++] = 0x94; expect[e++] = 0x80;    /* green 0.5 -> 128 */
    expect[e++] = 0x94; expect[e++] = 0x40;    /* blue 0.25 -> 64 */
    expect[e++] = 0x94; expect[e++] = 0x80;    /* exponent 128 */
    CHECK(n == e && !memcmp(out, expect, e));

    /* short run of 2 right before a run, then a literal tail */
    const uint8_t a[17] = {7, 7, 9, 9, 9, 9, 1, 2, 3, 4, 5, 6, 7, 8, 10, 11, 12};
    const uint8_t ea[] = {0x82, 7, 0x84, 9, 11, 1, 2, 3, 4, 5, 6, 7, 8, 10, 11, 12};
    check_component(a, 17, ea, sizeof ea, "short run");
    /* 3 equal bytes NOT followed by a run stay in the literal */
    const uint8_t b[17] = {3, 3, 3, 1, 2, 1, 2, 1, 2, 1, 2, 1, 2, 1, 2, 1, 2};
    uint8_t eb[18];
    eb[0] = 17;
    memcpy(eb + 1, b, 17);
    check_component(b, 17, eb, sizeof eb, "no short run at the end");
    /* 3 equal bytes before a run -> short run of 3; unequal pair before a run -> literal */
    const uint8_t c[20] = {1, 1, 1, 2, 2, 2, 2, 5, 6, 8, 8, 8, 8, 8, 9, 9, 9, 9, 9, 4};
    const uint8_t ec[] = {0x83, 1, 0x84, 2, 2, 5, 6, 0x85, 8, 0x85, 9, 1, 4};
    check_component(c, 20, ec, sizeof ec, "short run of 3");
    /* a 2-byte run that is not equal before a run: literal of 1, run of 4 */
    const uint8_t d[17] = {1, 2, 2, 2, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14};
    const uint8_t ed[] = {1, 1, 0x84, 2, 12, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14};
    check_component(d, 17, ed, sizeof ed, "literal of 1 before a run");
    /* 300 equal bytes: runs of 127, 127, 46 */
    uint8_t f[300];
    memset(f, 42, sizeof f);
    const uint8_t ef[] = {0xFF, 42, 0xFF, 42, 0x80 + 46, 42};
    check_component(f, 300, ef, sizeof ef, "long run");
    /* 200 bytes with no repeats: literals of 128 and 72 */
    uint8_t g[200], eg[202];
    for (int i = 0; i < 200; i++) g[i] = (uint8_t)(i * 37);
    eg[0] = 128;
    memcpy(eg + 1, g, 128);
    eg[129] = 72;
    memcpy(eg + 130, g + 128, 72);
    check_component(g, 200, eg, sizeof eg, "long literal");
    /* a run of exactly 3 at the very end stays literal */
    const uint8_t h[17] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 6, 6, 6};
    uint8_t eh[18];
    eh[0] = 17;
    memcpy(eh + 1, h, 17);
    check_component(h, 17, eh, sizeof eh, "3 at the end");
}

/* ---- every reference picture ---- */

static int nref, nref_rle_exact, nref_rgbe_exact, nref_flat, nref_rle, nref_bytes_exact;
static long ref_mismatch_files;

static void check_ref_file(const char *path)
{
    hd_istream *s;
    if (hd_istream_open(&s, path)) { CHECK_MSG(0, "%s", hd_errmsg()); return; }
    hd_header h;
    hd_picfmt fmt;
    hd_resolu r;
    if (hd_picture_read_header(s, &h, &fmt, &r)) {
        CHECK_MSG(0, "%s", hd_errmsg());
        hd_istream_close(s);
        return;
    }
    hd_header_free(&h);
    /* the data section as stored */
    size_t cap = 1 << 16, n = 0, k;
    unsigned char *data = malloc(cap);
    while ((k = hd_istream_read(s, data + n, cap - n)) > 0) {
        n += k;
        if (n == cap) data = realloc(data, cap *= 2);
    }
    hd_istream_close(s);
    int len = hd_resolu_scanlen(&r), ns = hd_resolu_nscans(&r);
    uint8_t *sl = malloc((size_t)len * 4), *sl2 = malloc((size_t)len * 4);
    uint8_t *enc = malloc(hd_scanline_maxbytes(len));
    float *rgb = malloc((size_t)len * 12);
    hd_istream *m = mem_stream(data, n, path);
    size_t pos = 0;
    int rgbe_same = 1, bytes_same = 1, ok = 1, file_flat = 0, file_rle = 0;
    for (int y = 0; y < ns; y++) {
        if (hd_scanline_read(m, sl, len)) { CHECK_MSG(0, "%s", hd_errmsg()); ok = 0; break; }
        hd_rgbe_decode_n(rgb, sl, (size_t)len);
        hd_rgbe_encode_n(sl2, rgb, (size_t)len);
        if (memcmp(sl, sl2, (size_t)len * 4)) rgbe_same = 0;
        /* Radiance writes run-length scanlines with fwritecolrs (our writer
         * must match byte for byte); rcontrib / rfluxmtx write flat pixels */
        int was_rle = len >= 17 && len <= 32767 && pos + 4 <= n && data[pos] == 2 &&
                      data[pos + 1] == 2 && !(data[pos + 2] & 0x80);
        size_t en;
        if (was_rle) en = hd_scanline_encode(enc, sl, len);
        else { memcpy(enc, sl, (size_t)len * 4); en = (size_t)len * 4; }
        if (!was_rle) file_flat = 1; else file_rle = 1;
        if (pos + en > n || memcmp(data + pos, enc, en)) bytes_same = 0;
        pos += en;
    }
    if (ok && pos != n) bytes_same = 0;
    hd_istream_close(m);
    if (ok) {
        nref++;
        nref_rgbe_exact += rgbe_same;
        nref_bytes_exact += bytes_same;
        nref_flat += file_flat && !file_rle;
        nref_rle += file_rle;
        nref_rle_exact += bytes_same && file_rle;
        if (!rgbe_same || !bytes_same) {
            if (ref_mismatch_files++ < 5)
                printf("  %s: rgbe %s, data bytes %s\n", path, rgbe_same ? "same" : "DIFFER",
                       bytes_same ? "same" : "DIFFER");
        }
    }
    free(sl); free(sl2); free(enc); free(rgb); free(data);
}

static void walk(const char *dir, int depth)
{
    if (depth > 8) return;
    DIR *d = opendir(dir);
    if (!d) return;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        struct stat st;
        if (stat(path, &st)) continue;
        if (S_ISDIR(st.st_mode)) walk(path, depth + 1);
        else {
            size_t l = strlen(e->d_name);
            if ((l > 4 && !strcmp(e->d_name + l - 4, ".hdr")) || (l > 7 && !strcmp(e->d_name + l - 7, ".hdr.gz")))
                check_ref_file(path);
        }
    }
    closedir(d);
}

static void test_reference_pictures(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder (set HELIODON_REF)");
    clock_t t0 = clock();
    walk(ref, 0);
    double secs = (double)(clock() - t0) / CLOCKS_PER_SEC;
    printf("  %d reference pictures read (%.1f s cpu): float->RGBE re-encoding identical in %d; "
           "%d written run-length by Radiance, data section reproduced byte for byte in %d; "
           "%d written flat (rcontrib/rfluxmtx), reproduced in %d\n",
           nref, secs, nref_rgbe_exact, nref_rle, nref_rle_exact, nref_flat,
           nref_bytes_exact - nref_rle_exact);
    if (nref == 0) SKIP("no .hdr files under %s", ref);
    CHECK(nref_rgbe_exact == nref);
    CHECK(nref_bytes_exact == nref);
    CHECK(nref_rle_exact == nref_rle);
    CHECK(nref_rle > 0);
    /* a full read of one picture agrees with the scanline path */
    char path[4096];
    snprintf(path, sizeof path, "%s/scenes/box/a2_clear_fish.hdr", ref);
    hd_picture p;
    struct stat st;
    if (stat(path, &st) == 0) {
        REQUIRE(hd_picture_read(path, &p) == HD_OK);
        CHECK(p.xres == 256 && p.yres == 256 && p.fmt == HD_PIC_RGBE && p.orient == HD_RES_STANDARD);
        char v[256];
        CHECK(hd_header_get(&p.hdr, "VIEW", v, sizeof v) && !strncmp(v, "-vta", 4));
        /* re-writing it reproduces the original file's data section */
        size_t n;
        unsigned char *w = write_mem(&p, HD_RES_STANDARD, &n);
        FILE *fp = fopen(path, "rb");
        unsigned char *orig = malloc((size_t)st.st_size);
        CHECK(fp && fread(orig, 1, (size_t)st.st_size, fp) == (size_t)st.st_size);
        if (fp) fclose(fp);
        const char *res = "-Y      256 +X      256\n";
        unsigned char *a = (unsigned char *)strstr((char *)w, res), *b = NULL;
        for (size_t i = 0; i + 24 < (size_t)st.st_size; i++)
            if (!memcmp(orig + i, res, 24)) { b = orig + i; break; }
        REQUIRE(a && b);
        size_t da = n - (size_t)(a - w), db = (size_t)st.st_size - (size_t)(b - orig);
        CHECK(da == db && !memcmp(a, b, da));
        free(w);
        free(orig);
        hd_picture_free(&p);
    }
}

/* ---- bad input ---- */

static hd_status read_bytes(const void *d, size_t n)
{
    hd_picture p;
    hd_status st = read_mem(d, n, &p);
    if (!st) hd_picture_free(&p);
    return st;
}

static void test_bad_input(void)
{
    hd_picture p;
    fill_test_picture(&p, 40, 30);
    size_t n;
    unsigned char *good = write_mem(&p, HD_RES_STANDARD, &n);
    hd_picture_free(&p);
    REQUIRE(good);
    CHECK(read_bytes(good, n) == HD_OK);
    /* truncated everywhere: every prefix fails cleanly */
    int bad = 0;
    for (size_t cut = 0; cut < n; cut += (cut < 200 ? 1 : 37)) {
        hd_status st = read_bytes(good, cut);
        if (st == HD_OK) bad++;
    }
    CHECK(bad == 0);
    const char *datastart = strstr((char *)good, "+X       40\n") + 12;
    size_t dataoff = (size_t)(datastart - (char *)good);
    CHECK(read_bytes(good, dataoff + 100) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "mem.hdr: byte offset");
    CHECK_CONTAINS(hd_errmsg(), "unexpected end of data");

    /* garbage header */
    unsigned char junk[300];
    for (int i = 0; i < 300; i++) junk[i] = (unsigned char)(rnd() & 0xff);
    junk[0] = 0x89;
    CHECK(read_bytes(junk, sizeof junk) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "mem.hdr");
    const char *txt = "this is just some text\nwithout an empty line\n";
    CHECK(read_bytes(txt, strlen(txt)) != HD_OK);

    /* wrong FORMAT */
    const char *wf = "#?RADIANCE\nFORMAT=ascii\n\n-Y 2 +X 2\n";
    CHECK(read_bytes(wf, strlen(wf)) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "FORMAT=ascii");

    /* absurd dimensions: refused before allocating */
    const char *ab = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2000000000 +X 2000000000\n";
    CHECK(read_bytes(ab, strlen(ab)) == HD_ERR_RANGE);
    CHECK_CONTAINS(hd_errmsg(), "byte offset 35");
    CHECK_CONTAINS(hd_errmsg(), "2000000000");

    /* bad resolution strings */
    const char *br[] = {"#?RADIANCE\n\n-Y 2 +Z 2\n", "#?RADIANCE\n\nY 2 X 2\n", "#?RADIANCE\n\n-Y 2\n",
                        "#?RADIANCE\n\n", "#?RADIANCE\n\n-Y 0 +X 3\n"};
    for (int i = 0; i < 5; i++) {
        CHECK(read_bytes(br[i], strlen(br[i])) != HD_OK);
        CHECK_CONTAINS(hd_errmsg(), "byte offset 12");
    }

    /* RLE run overrunning the scanline */
    unsigned char rle[128];
    memset(rle, 0, sizeof rle);
    int k = sprintf((char *)rle, "#?RADIANCE\n\n-Y 1 +X 20\n");
    size_t hdrlen = (size_t)k;
    rle[k++] = 2; rle[k++] = 2; rle[k++] = 0; rle[k++] = 20;
    rle[k++] = 0x80 + 15; rle[k++] = 5;
    rle[k++] = 0x80 + 10; rle[k++] = 6;              /* 15 + 10 > 20 */
    CHECK(read_bytes(rle, (size_t)k) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "overruns");
    char want[64];
    snprintf(want, sizeof want, "byte offset %zu", hdrlen + 6);
    CHECK_CONTAINS(hd_errmsg(), want);
    /* literal overrunning */
    k = (int)hdrlen + 4;
    rle[k++] = 19; memset(rle + k, 1, 19); k += 19;
    rle[k++] = 2; rle[k++] = 1; rle[k++] = 1;
    CHECK(read_bytes(rle, (size_t)k) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "literal of 2 bytes overruns");
    /* RLE length that does not match the picture */
    k = (int)hdrlen;
    rle[k++] = 2; rle[k++] = 2; rle[k++] = 0; rle[k++] = 21;
    CHECK(read_bytes(rle, (size_t)k + 40) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "21 pixels");
    /* old-style marker with nothing to repeat, and one that overruns */
    const char *om = "#?RADIANCE\n\n-Y 1 +X 3\n\x01\x01\x01\x02\x05\x05\x05\x80\x05\x05\x05\x80";
    CHECK(read_bytes(om, strlen(om) + 1) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "no pixel to repeat");
    const unsigned char om2[] = "#?RADIANCE\n\n-Y 1 +X 3\n\x05\x05\x05\x80\x01\x01\x01\x09";
    CHECK(read_bytes(om2, sizeof om2 - 1) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "overruns");
    /* huge old-style count from consecutive markers */
    const unsigned char om3[] = "#?RADIANCE\n\n-Y 1 +X 3\n\x05\x05\x05\x80\x01\x01\x01\x01\x01\x01\x01\x01"
                                "\x01\x01\x01\x01\x01\x01\x01\x01\x01\x01\x01\x01\x01\x01\x01\xff";
    CHECK(read_bytes(om3, sizeof om3 - 1) == HD_ERR_FORMAT);

    /* random corruption of the data never crashes */
    unsigned char *cp = malloc(n);
    for (int t = 0; t < 300; t++) {
        memcpy(cp, good, n);
        for (int j = 0; j < 5; j++) cp[dataoff + rnd() % (n - dataoff)] = (unsigned char)rnd();
        read_bytes(cp, n);
    }
    free(cp);
    free(good);

    /* picture allocation limits */
    CHECK(hd_picture_alloc(&p, 0, 5) == HD_ERR_RANGE);
    CHECK(hd_picture_alloc(&p, 2000000, 1) == HD_ERR_RANGE);
    hd_picture_free(&p);
}

static void test_save_file(void)
{
    hd_picture p, q;
    fill_test_picture(&p, 20, 18);
    char path[512];
    snprintf(path, sizeof path, "%s/test_picture_save.hdr", hd_test_tmpdir());
    hd_header h;
    hd_header_init(&h);
    hd_header_append(&h, "VIEW= -vtv -vh 60");
    CHECK(hd_picture_save(path, &p, &h) == HD_OK);
    REQUIRE(hd_picture_read(path, &q) == HD_OK);
    CHECK(!memcmp(p.pix, q.pix, sizeof(float) * 3 * 20 * 18));
    char v[64];
    CHECK(hd_header_get(&q.hdr, "VIEW", v, sizeof v) && !strcmp(v, "-vtv -vh 60"));
    hd_picture_free(&q);
    CHECK(hd_picture_read("/nonexistent/x.hdr", &q) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "/nonexistent/x.hdr");
    hd_header_free(&h);
    hd_picture_free(&p);
}

static void test_info_helpers(void)
{
    char *patterns[] = {"EXPOSURE", NULL};
    CHECK(hd_info_line_removed("EXPOSURE=2\n", patterns));
    CHECK(!hd_info_line_removed("EXPOSURES=2\n", patterns));
    CHECK(!hd_info_line_removed("  EXPOSURE=2\n", patterns));
    char *p2[] = {" EXPOSURE=", NULL};
    CHECK(hd_info_line_removed("\tEXPOSURE=2\n", p2));
    CHECK(!hd_info_line_removed("EXPOSURE=2\n", p2));
    char *p3[] = {"VIEW= -vta", "rpict -x 5", NULL};
    CHECK(hd_info_line_removed("VIEW= -vtv -vp 0 0 0\n", p3));
    CHECK(hd_info_line_removed("rpict -vf v.vf x.oct\n", p3));
    CHECK(!hd_info_line_removed("rpictx -vf\n", p3));
    CHECK(!hd_info_line_removed("rtrace -h\n", p3));
    CHECK(hd_info_pattern_line_len("EXPOSURE") == 0);
    CHECK(hd_info_pattern_line_len("EXPOSURE=") == 0);
    CHECK(hd_info_pattern_line_len(" EXPOSURE=") == 0);
    CHECK(hd_info_pattern_line_len("EXPOSURE=16  ") == 11);
    CHECK(hd_info_pattern_line_len("a b") == 3);
    char f[64];
    CHECK(hd_info_format_value("FORMAT=float   \n", f, sizeof f) && !strcmp(f, "float"));
    CHECK(!hd_info_format_value("FORMAT=\n", f, sizeof f));
    CHECK(!hd_info_format_value(" FORMAT=x\n", f, sizeof f));
    /* raw header and dimensions */
    const char *pic = "#?RADIANCE\nx y\r\nFORMAT=32-bit_rle_rgbe\n\r\n-Y 3 +X 4\n....";
    hd_istream *s = mem_stream(pic, strlen(pic), "pic");
    char *text;
    size_t len;
    char dims[128];
    REQUIRE(hd_info_read_raw(s, &text, &len) == HD_OK);
    CHECK_STR(text, "#?RADIANCE\nx y\r\nFORMAT=32-bit_rle_rgbe\n");
    CHECK(hd_info_dimensions(s, text, dims, sizeof dims) == HD_OK);
    CHECK_STR(dims, "-Y 3 +X 4\n");
    free(text);
    hd_istream_close(s);
    const char *mtx = "#?RADIANCE\nNROWS=5\nNCOLS=7\nNCOMP=3\nFORMAT=float\n\n\x01\x02";
    s = mem_stream(mtx, strlen(mtx), "mtx");
    REQUIRE(hd_info_read_raw(s, &text, &len) == HD_OK);
    hd_info_dimensions(s, text, dims, sizeof dims);
    CHECK_STR(dims, "NROWS=5 NCOLS=7 NCOMP=3\n");
    free(text);
    hd_istream_close(s);
    const char *oct = "#?RADIANCE\nFORMAT=Radiance_octree\n\n\x01\x1f-1\0-2\0-3\0" "10\0junk";
    s = mem_stream(oct, 53, "oct");
    REQUIRE(hd_info_read_raw(s, &text, &len) == HD_OK);
    hd_info_dimensions(s, text, dims, sizeof dims);
    CHECK_STR(dims, "-1 -2 -3 10\n");
    free(text);
    hd_istream_close(s);
    const char *nohdr = "#?RADIANCE\nno end\n";
    s = mem_stream(nohdr, strlen(nohdr), "noend");
    CHECK(hd_info_read_raw(s, &text, &len) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "noend: byte offset 18");
    hd_istream_close(s);
    s = mem_stream("\x02\x02", 2, "bin");
    CHECK(hd_info_read_raw(s, &text, &len) == HD_ERR_FORMAT);
    hd_istream_close(s);
}

int main(void)
{
    RUN(test_rgbe_exact);
    RUN(test_rgbe_vs_reference);
    RUN(test_resolu_strings);
    RUN(test_orientation_by_hand);
    RUN(test_orientation_roundtrip);
    RUN(test_scanline_roundtrip);
    RUN(test_old_rle);
    RUN(test_rle_writer_bytes);
    RUN(test_reference_pictures);
    RUN(test_bad_input);
    RUN(test_save_file);
    RUN(test_info_helpers);
    return hd_test_done();
}

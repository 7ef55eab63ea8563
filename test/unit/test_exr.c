/* Unit tests for the OpenEXR module (src/exr.c). */
#include "hd_test.h"

#include <stdint.h>
#include <string.h>

#include <openexr.h>

#include "heliodon/exr.h"
#include "heliodon/header.h"
#include "heliodon/picture.h"

/* Deterministic pseudo-random values (xorshift). */
static uint32_t rs = 12345u;
static uint32_t rnd(void)
{
    rs ^= rs << 13;
    rs ^= rs >> 17;
    rs ^= rs << 5;
    return rs;
}
static double urand(void) { return (rnd() >> 8) / 16777216.0; }

/* Fill a channel with values spanning many magnitudes, signs and zeros. */
static void fill_wide(float *d, size_t n, int allow_negative)
{
    for (size_t i = 0; i < n; i++) {
        double e = -6.0 + 12.0 * urand();          /* 1e-6 .. 1e6 */
        double v = pow(10.0, e);
        if (i % 17 == 0)
            v = 0.0;
        if (allow_negative && i % 5 == 1)
            v = -v;
        d[i] = (float)v;
    }
}

/* Fill with values that half can hold (6e-5 .. 6e4, normal range). */
static void fill_half_range(float *d, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        double e = -4.0 + 8.5 * urand();           /* 1e-4 .. 3e4 */
        d[i] = (float)pow(10.0, e);
        if (i % 23 == 0)
            d[i] = 0.0f;
    }
}

/* memmem without _GNU_SOURCE */
static uint8_t *find_bytes(uint8_t *hay, size_t len, const void *needle, size_t n)
{
    for (size_t i = 0; i + n <= len; i++)
        if (!memcmp(hay + i, needle, n))
            return hay + i;
    return NULL;
}

static const hd_exr_compression comps[] = {HD_EXR_NONE, HD_EXR_ZIP, HD_EXR_PIZ, HD_EXR_ZIPS, HD_EXR_RLE};
#define NCOMPS ((int)(sizeof comps / sizeof comps[0]))

/* Build an image of the given size with channels named in names[]. */
static int make_image(hd_exr_image *img, int w, int h, const char *const *names, int n,
                      hd_exr_pixtype t)
{
    hd_exr_init(img);
    if (hd_exr_set_size(img, w, h) != HD_OK)
        return 0;
    for (int i = 0; i < n; i++) {
        int idx;
        if (hd_exr_add_channel(img, names[i], t, &idx) != HD_OK)
            return 0;
        if (t == HD_EXR_HALF)
            fill_half_range(img->chan[idx].data, (size_t)w * h);
        else
            fill_wide(img->chan[idx].data, (size_t)w * h, 1);
    }
    return 1;
}

static void test_roundtrip_float_rgb(void)
{
    static const char *const rgb[] = {"R", "G", "B"};
    for (int k = 0; k < NCOMPS; k++) {
        hd_exr_image img, back;
        REQUIRE(make_image(&img, 37, 45, rgb, 3, HD_EXR_FLOAT));
        uint8_t *data;
        size_t len;
        hd_status st = hd_exr_encode(&img, comps[k], "mem.exr", &data, &len);
        CHECK_MSG(st == HD_OK, "encode %s: %s", hd_exr_compression_name(comps[k]), hd_errmsg());
        if (st != HD_OK) {
            hd_exr_free(&img);
            continue;
        }
        hd_exr_init(&back);
        st = hd_exr_decode(data, len, "mem.exr", &back);
        CHECK_MSG(st == HD_OK, "decode %s: %s", hd_exr_compression_name(comps[k]), hd_errmsg());
        if (st == HD_OK) {
            CHECK(back.xres == 37 && back.yres == 45 && back.x0 == 0 && back.y0 == 0);
            CHECK(back.nchan == 3);
            CHECK(back.compression == comps[k]);
            CHECK(!back.tiled);
            for (int c = 0; c < 3; c++) {
                int i = hd_exr_find_channel(&back, rgb[c]);
                REQUIRE(i >= 0);
                CHECK(back.chan[i].type == HD_EXR_FLOAT);
                CHECK_MSG(!memcmp(back.chan[i].data, img.chan[c].data, sizeof(float) * 37 * 45),
                          "%s channel %s not bit-exact", hd_exr_compression_name(comps[k]), rgb[c]);
            }
        }
        free(data);
        hd_exr_free(&img);
        hd_exr_free(&back);
    }
}

static void test_roundtrip_half_layers(void)
{
    static const char *const names[] = {"wg1.R", "wg1.G", "wg1.B", "wg2.R", "wg2.G", "wg2.B", "Y"};
    for (int k = 0; k < NCOMPS; k++) {
        hd_exr_image img, back;
        REQUIRE(make_image(&img, 70, 33, names, 7, HD_EXR_HALF));
        uint8_t *data;
        size_t len;
        REQUIRE(hd_exr_encode(&img, comps[k], "half.exr", &data, &len) == HD_OK);
        hd_exr_init(&back);
        hd_status st = hd_exr_decode(data, len, "half.exr", &back);
        CHECK_MSG(st == HD_OK, "decode %s: %s", hd_exr_compression_name(comps[k]), hd_errmsg());
        if (st == HD_OK) {
            CHECK(back.nchan == 7);
            for (int c = 0; c < 7; c++) {
                int i = hd_exr_find_channel(&back, names[c]);
                REQUIRE(i >= 0);
                CHECK(back.chan[i].type == HD_EXR_HALF);
                double worst = 0;
                int zeros_ok = 1;
                for (size_t p = 0; p < 70 * 33; p++) {
                    double a = back.chan[i].data[p], b = img.chan[c].data[p];
                    if (b == 0) {
                        zeros_ok &= a == 0;
                        continue;
                    }
                    double r = fabs(a - b) / b;
                    if (r > worst)
                        worst = r;
                }
                CHECK(zeros_ok);
                /* half keeps 11 significant bits: rounding error <= 2^-11 */
                CHECK_MSG(worst <= 1e-3, "%s %s: worst relative error %g",
                          hd_exr_compression_name(comps[k]), names[c], worst);
                CHECK_MSG(worst > 0, "%s %s: half values identical to floats: not converted?",
                          hd_exr_compression_name(comps[k]), names[c]);
            }
        }
        free(data);
        hd_exr_free(&img);
        hd_exr_free(&back);
    }
}

static void test_uint_and_mixed(void)
{
    hd_exr_image img, back;
    hd_exr_init(&img);
    REQUIRE(hd_exr_set_size(&img, 19, 40) == HD_OK);
    int iu, ih, ifl;
    REQUIRE(hd_exr_add_channel(&img, "id", HD_EXR_UINT, &iu) == HD_OK);
    REQUIRE(hd_exr_add_channel(&img, "a.h", HD_EXR_HALF, &ih) == HD_OK);
    REQUIRE(hd_exr_add_channel(&img, "a.f", HD_EXR_FLOAT, &ifl) == HD_OK);
    for (int p = 0; p < 19 * 40; p++) {
        img.chan[iu].data[p] = (float)(p * 1013 % 65536);
        img.chan[ih].data[p] = 0.5f + p;           /* exact in half up to 1024 */
        img.chan[ifl].data[p] = 1.0f / (p + 1);
    }
    uint8_t *data;
    size_t len;
    REQUIRE(hd_exr_encode(&img, HD_EXR_PIZ, "mixed.exr", &data, &len) == HD_OK);
    hd_exr_init(&back);
    hd_status st = hd_exr_decode(data, len, "mixed.exr", &back);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    if (st == HD_OK) {
        int bu = hd_exr_find_channel(&back, "id"), bh = hd_exr_find_channel(&back, "a.h"),
            bf = hd_exr_find_channel(&back, "a.f");
        REQUIRE(bu >= 0 && bh >= 0 && bf >= 0);
        CHECK(back.chan[bu].type == HD_EXR_UINT);
        CHECK(back.chan[bh].type == HD_EXR_HALF);
        CHECK(back.chan[bf].type == HD_EXR_FLOAT);
        int ok = 1;
        for (int p = 0; p < 19 * 40; p++) {
            ok &= back.chan[bu].data[p] == (float)(p * 1013 % 65536);
            if (p < 1000)
                ok &= back.chan[bh].data[p] == 0.5f + p;
            ok &= back.chan[bf].data[p] == 1.0f / (p + 1);
        }
        CHECK(ok);
        /* OpenEXR sorts channels by name */
        CHECK_STR(back.chan[0].name, "a.f");
        CHECK_STR(back.chan[2].name, "id");
    }
    free(data);
    hd_exr_free(&img);
    hd_exr_free(&back);
}

static void test_attributes(void)
{
    static const char *const rgb[] = {"R", "G", "B"};
    hd_exr_image img, back;
    REQUIRE(make_image(&img, 8, 8, rgb, 3, HD_EXR_HALF));
    const char *hdr = "rpict -vf fish.vf -ab 2 box.oct\nSOFTWARE= heliodon 0.1.0\nEXPOSURE=2.5e-01\n"
                      "VIEW= -vta -vp 1.5 3.5 1.2 -vd 0 -1 0 -vu 0 0 1 -vh 180 -vv 180\n";
    CHECK(hd_exr_set_attr(&img, HD_EXR_HEADER_ATTR, "first value") == HD_OK);
    CHECK(hd_exr_set_attr(&img, HD_EXR_HEADER_ATTR, hdr) == HD_OK);   /* replaces */
    CHECK(hd_exr_set_attr(&img, "owner", "heliodon tests") == HD_OK);
    CHECK(hd_exr_set_attr(&img, "comments", "") == HD_OK);
    CHECK(img.nattr == 3);
    CHECK(hd_exr_set_attr(&img, "channels", "x") == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "reserved");
    img.has_chroma = 1;
    memcpy(img.chroma, hd_exr_chroma_radiance, sizeof img.chroma);
    uint8_t *data;
    size_t len;
    REQUIRE(hd_exr_encode(&img, HD_EXR_ZIP, "attr.exr", &data, &len) == HD_OK);
    hd_exr_init(&back);
    hd_status st = hd_exr_decode(data, len, "attr.exr", &back);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    CHECK_STR(hd_exr_get_attr(&back, HD_EXR_HEADER_ATTR), hdr);
    CHECK_STR(hd_exr_get_attr(&back, "owner"), "heliodon tests");
    CHECK_STR(hd_exr_get_attr(&back, "comments"), "");
    CHECK(hd_exr_get_attr(&back, "nothere") == NULL);
    CHECK(back.has_chroma);
    for (int i = 0; i < 8; i++)
        CHECK(back.chroma[i] == hd_exr_chroma_radiance[i]);
    free(data);
    hd_exr_free(&img);
    hd_exr_free(&back);
}

/* Same image -> byte-identical files; row 0 is the first scanline stored
 * (EXR y = 0 is the top of the image, like hd_picture). */
static void test_determinism_and_row_order(void)
{
    static const char *const ch[] = {"Y"};
    hd_exr_image img;
    REQUIRE(make_image(&img, 16, 4, ch, 1, HD_EXR_FLOAT));
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 16; x++)
            img.chan[0].data[y * 16 + x] = 1000.0f * (y + 1) + x;
    uint8_t *a, *b;
    size_t la, lb;
    REQUIRE(hd_exr_encode(&img, HD_EXR_NONE, "det.exr", &a, &la) == HD_OK);
    REQUIRE(hd_exr_encode(&img, HD_EXR_NONE, "det.exr", &b, &lb) == HD_OK);
    CHECK(la == lb && !memcmp(a, b, la));
    /* find rows 0 and 3 (little-endian floats, as EXR stores them) */
    long pos0 = -1, pos3 = -1;
    for (size_t i = 0; i + 4 <= la; i++) {
        float f;
        memcpy(&f, a + i, 4);
        if (f == 1000.0f && pos0 < 0)
            pos0 = (long)i;
        if (f == 4000.0f && pos3 < 0)
            pos3 = (long)i;
    }
    CHECK(pos0 > 0 && pos3 > pos0);
    free(a);
    free(b);
    /* compressed files are deterministic too */
    REQUIRE(hd_exr_encode(&img, HD_EXR_PIZ, "det.exr", &a, &la) == HD_OK);
    REQUIRE(hd_exr_encode(&img, HD_EXR_PIZ, "det.exr", &b, &lb) == HD_OK);
    CHECK(la == lb && !memcmp(a, b, la));
    free(a);
    free(b);
    hd_exr_free(&img);
}

static void test_save_load_file(void)
{
    static const char *const rgb[] = {"R", "G", "B"};
    hd_exr_image img, back;
    REQUIRE(make_image(&img, 21, 13, rgb, 3, HD_EXR_FLOAT));
    char path[512];
    snprintf(path, sizeof path, "%s/test_exr_save.exr", hd_test_tmpdir());
    remove(path);
    hd_status st = hd_exr_save(path, &img, HD_EXR_ZIP);
    REQUIRE(st == HD_OK);
    hd_exr_init(&back);
    st = hd_exr_load(path, &back);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    if (st == HD_OK)
        for (int c = 0; c < 3; c++)
            CHECK(!memcmp(back.chan[hd_exr_find_channel(&back, rgb[c])].data, img.chan[c].data,
                          sizeof(float) * 21 * 13));
    /* a missing file is an I/O error naming it */
    st = hd_exr_load("/nonexistent/dir/x.exr", &back);
    CHECK(st != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "/nonexistent/dir/x.exr");
    hd_exr_free(&img);
    hd_exr_free(&back);
}

static void test_truncated(void)
{
    static const char *const rgb[] = {"R", "G", "B"};
    for (int k = 0; k < 3; k++) {
        hd_exr_image img, back;
        REQUIRE(make_image(&img, 40, 64, rgb, 3, k == 0 ? HD_EXR_FLOAT : HD_EXR_HALF));
        uint8_t *data;
        size_t len;
        REQUIRE(hd_exr_encode(&img, comps[k], "cut.exr", &data, &len) == HD_OK);
        hd_exr_init(&back);
        /* half the file */
        hd_status st = hd_exr_decode(data, len / 2, "cut.exr", &back);
        CHECK(st == HD_ERR_FORMAT);
        CHECK_CONTAINS(hd_errmsg(), "cut.exr");
        /* every cut length must fail cleanly */
        int nfail = 0, ncut = 0;
        for (size_t cut = 0; cut < len; cut += 1 + len / 97) {
            ncut++;
            st = hd_exr_decode(data, cut, "cut.exr", &back);
            nfail += st != HD_OK;
            if (st != HD_OK && !strstr(hd_errmsg(), "cut.exr"))
                CHECK_MSG(0, "cut at %zu: message without the file name: %s", cut, hd_errmsg());
        }
        CHECK_MSG(nfail == ncut, "%s: %d of %d truncated files accepted",
                  hd_exr_compression_name(comps[k]), ncut - nfail, ncut);
        st = hd_exr_decode(data, len - 1, "cut.exr", &back);
        CHECK_MSG(st == HD_ERR_FORMAT, "missing last byte accepted");
        free(data);
        hd_exr_free(&img);
        hd_exr_free(&back);
    }
}

/* Flip bytes: must never crash; the magic number and structural header
 * fields must give a clear error. */
static void test_corrupt(void)
{
    static const char *const rgb[] = {"R", "G", "B"};
    hd_exr_image img, back;
    REQUIRE(make_image(&img, 32, 32, rgb, 3, HD_EXR_HALF));
    uint8_t *data;
    size_t len;
    REQUIRE(hd_exr_encode(&img, HD_EXR_PIZ, "bad.exr", &data, &len) == HD_OK);
    uint8_t *copy = malloc(len);
    REQUIRE(copy);
    hd_exr_init(&back);

    memcpy(copy, data, len);
    copy[0] ^= 0xff;
    CHECK(hd_exr_decode(copy, len, "bad.exr", &back) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "bad.exr: not an OpenEXR file");

    /* version field: unknown version number */
    memcpy(copy, data, len);
    copy[4] = 0x7f;
    CHECK(hd_exr_decode(copy, len, "bad.exr", &back) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "bad.exr");

    /* the attribute type name of "channels" */
    uint8_t *p = find_bytes(data, len, "chlist", 6);
    REQUIRE(p);
    memcpy(copy, data, len);
    copy[p - data] = 'X';
    CHECK(hd_exr_decode(copy, len, "bad.exr", &back) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "bad.exr");

    /* the chunk offset table: the first entry holds the offset just past
     * the (one-entry) table; every flipped byte must be detected */
    long tab = -1;
    for (size_t i = 8; i + 8 <= len && tab < 0; i++) {
        uint64_t v = 0;
        for (int j = 7; j >= 0; j--)
            v = (v << 8) | data[i + j];
        if (v == i + 8)
            tab = (long)i;
    }
    REQUIRE(tab > 0);
    for (int j = 0; j < 8; j++) {
        memcpy(copy, data, len);
        copy[tab + j] ^= 0x5a;
        CHECK_MSG(hd_exr_decode(copy, len, "bad.exr", &back) == HD_ERR_FORMAT, "offset byte %d", j);
        CHECK_CONTAINS(hd_errmsg(), "bad.exr: corrupt or truncated file");
    }

    /* every byte flipped in turn (header and offsets byte by byte, pixel data
     * sparsely): no crash (run under ASan/UBSan), and every error names the
     * file.  OpenEXR has no checksums: flipped pixel data or attribute
     * values may go unnoticed, so no detection rate is required here. */
    int nbad = 0, ntry = 0;
    for (size_t i = 0; i < len; i += (i < (size_t)tab + 16 ? 1 : 5)) {
        memcpy(copy, data, len);
        copy[i] ^= 0xa5;
        ntry++;
        hd_status st = hd_exr_decode(copy, len, "bad.exr", &back);
        if (st != HD_OK) {
            nbad++;
            if (!strstr(hd_errmsg(), "bad.exr"))
                CHECK_MSG(0, "flip at %zu: message without the file name: %s", i, hd_errmsg());
        } else {
            CHECK(back.xres == 32 && back.yres == 32);
        }
    }
    printf("note: %d of %d single-byte corruptions detected\n", nbad, ntry);
    free(copy);
    free(data);
    hd_exr_free(&img);
    hd_exr_free(&back);
}

/* Write a little-endian int32 into a buffer. */
static void put_i32(uint8_t *p, int32_t v)
{
    uint32_t u = (uint32_t)v;
    p[0] = u & 0xff;
    p[1] = (u >> 8) & 0xff;
    p[2] = (u >> 16) & 0xff;
    p[3] = (u >> 24) & 0xff;
}

static void test_absurd_sizes(void)
{
    hd_exr_image img, back;
    hd_exr_init(&img);
    CHECK(hd_exr_set_size(&img, 0, 10) == HD_ERR_RANGE);
    CHECK(hd_exr_set_size(&img, 10, HD_EXR_MAXSIDE + 1) == HD_ERR_RANGE);
    CHECK(hd_exr_set_size(&img, -5, -5) == HD_ERR_RANGE);
    img.xres = 2000000000;   /* bypassing set_size: encode refuses too */
    img.yres = 1;
    uint8_t *data;
    size_t len;
    CHECK(hd_exr_encode(&img, HD_EXR_ZIP, "huge.exr", &data, &len) == HD_ERR_RANGE);
    hd_exr_init(&img);
    CHECK(hd_exr_set_size(&img, 4, 4) == HD_OK);
    CHECK(hd_exr_encode(&img, HD_EXR_ZIP, "nochan.exr", &data, &len) == HD_ERR_USAGE);
    CHECK(hd_exr_add_channel(&img, "", HD_EXR_FLOAT, NULL) == HD_ERR_RANGE);
    CHECK(hd_exr_add_channel(&img, "R", HD_EXR_FLOAT, NULL) == HD_OK);
    CHECK(hd_exr_add_channel(&img, "R", HD_EXR_HALF, NULL) != HD_OK);
    CHECK(hd_exr_set_size(&img, 5, 4) != HD_OK);    /* size fixed once channels exist */

    /* patch the data window of a valid file to absurd sizes */
    REQUIRE(hd_exr_encode(&img, HD_EXR_NONE, "win.exr", &data, &len) == HD_OK);
    uint8_t *dw = find_bytes(data, len, "dataWindow\0box2i\0", 17);
    REQUIRE(dw);
    uint8_t *box = dw + 17 + 4;     /* after the size field: xmin ymin xmax ymax */
    uint8_t *copy = malloc(len);
    REQUIRE(copy);
    static const int32_t wins[][4] = {
        {0, 0, 2000000000, 3},            /* 2e9 wide */
        {0, 0, 3, 1999999999},            /* 2e9 high */
        {-2000000000, 0, 2000000000, 3},  /* width overflows int32 */
        {0, 0, -5, 3},                    /* negative size */
        {0, 0, 99999, 99999},             /* plausible header, data missing */
    };
    hd_exr_init(&back);
    for (size_t w = 0; w < sizeof wins / sizeof wins[0]; w++) {
        memcpy(copy, data, len);
        for (int j = 0; j < 4; j++)
            put_i32(copy + (box - data) + 4 * j, wins[w][j]);
        hd_status st = hd_exr_decode(copy, len, "win.exr", &back);
        CHECK_MSG(st != HD_OK, "window %zu accepted", w);
        CHECK_CONTAINS(hd_errmsg(), "win.exr");
    }
    /* the allocation limit is honoured before decoding */
    size_t old = hd_alloc_limit();
    hd_set_alloc_limit(16);
    CHECK(hd_exr_decode(data, len, "win.exr", &back) == HD_ERR_NOMEM);
    CHECK_CONTAINS(hd_errmsg(), "win.exr");
    hd_set_alloc_limit(old);
    CHECK(hd_exr_decode(data, len, "win.exr", &back) == HD_OK);
    free(copy);
    free(data);
    hd_exr_free(&img);
    hd_exr_free(&back);
}

/* A tiled file made directly with OpenEXRCore is read (level 0). */
static void test_read_tiled(void)
{
    const int W = 45, H = 30, TW = 16, TH = 8;
    char path[512];
    snprintf(path, sizeof path, "%s/test_exr_tiled.exr", hd_test_tmpdir());
    exr_context_t ctx;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    REQUIRE(exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init) == EXR_ERR_SUCCESS);
    int part;
    REQUIRE(exr_add_part(ctx, NULL, EXR_STORAGE_TILED, &part) == EXR_ERR_SUCCESS);
    REQUIRE(exr_initialize_required_attr_simple(ctx, part, W, H, EXR_COMPRESSION_ZIP) == EXR_ERR_SUCCESS);
    REQUIRE(exr_set_tile_descriptor(ctx, part, TW, TH, EXR_TILE_ONE_LEVEL, EXR_TILE_ROUND_DOWN) == EXR_ERR_SUCCESS);
    REQUIRE(exr_add_channel(ctx, part, "G", EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1) == EXR_ERR_SUCCESS);
    REQUIRE(exr_write_header(ctx) == EXR_ERR_SUCCESS);
    float *full = malloc(sizeof(float) * W * H);
    REQUIRE(full);
    for (int i = 0; i < W * H; i++)
        full[i] = (float)(i % W) + 0.001f * (i / W);
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int first = 1, ok = 1;
    for (int ty = 0; ty * TH < H && ok; ty++)
        for (int tx = 0; tx * TW < W && ok; tx++) {
            exr_chunk_info_t ci;
            ok &= exr_write_tile_chunk_info(ctx, part, tx, ty, 0, 0, &ci) == EXR_ERR_SUCCESS;
            ok &= (first ? exr_encoding_initialize(ctx, part, &ci, &enc)
                         : exr_encoding_update(ctx, part, &ci, &enc)) == EXR_ERR_SUCCESS;
            enc.channels[0].encode_from_ptr = (const uint8_t *)(full + ty * TH * W + tx * TW);
            enc.channels[0].user_pixel_stride = 4;
            enc.channels[0].user_line_stride = 4 * W;
            enc.channels[0].user_bytes_per_element = 4;
            enc.channels[0].user_data_type = EXR_PIXEL_FLOAT;
            if (first)
                ok &= exr_encoding_choose_default_routines(ctx, part, &enc) == EXR_ERR_SUCCESS;
            first = 0;
            ok &= exr_encoding_run(ctx, part, &enc) == EXR_ERR_SUCCESS;
        }
    exr_encoding_destroy(ctx, &enc);
    CHECK(exr_finish(&ctx) == EXR_ERR_SUCCESS);
    REQUIRE(ok);
    hd_exr_image back;
    hd_exr_init(&back);
    hd_status st = hd_exr_load(path, &back);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    if (st == HD_OK) {
        CHECK(back.tiled);
        CHECK(back.xres == W && back.yres == H && back.nchan == 1);
        CHECK(!memcmp(back.chan[0].data, full, sizeof(float) * W * H));
    }
    free(full);
    hd_exr_free(&back);
}

/* A two-part file made with OpenEXRCore directly: parts chosen by name or
 * number; unknown parts are listed. */
static void test_parts(void)
{
    const int W = 7, H = 5;
    char path[512];
    snprintf(path, sizeof path, "%s/test_exr_parts.exr", hd_test_tmpdir());
    exr_context_t ctx;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    REQUIRE(exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init) == EXR_ERR_SUCCESS);
    static const char *const names[2] = {"left", "right"};
    float vals[2][7 * 5];
    int ok = 1;
    for (int k = 0; k < 2; k++) {
        int part;
        ok &= exr_add_part(ctx, names[k], EXR_STORAGE_SCANLINE, &part) == EXR_ERR_SUCCESS;
        ok &= exr_initialize_required_attr_simple(ctx, part, W, H, EXR_COMPRESSION_ZIPS) == EXR_ERR_SUCCESS;
        ok &= exr_add_channel(ctx, part, "Y", EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1) == EXR_ERR_SUCCESS;
        for (int i = 0; i < W * H; i++)
            vals[k][i] = (float)(100 * (k + 1) + i);
    }
    REQUIRE(ok);
    REQUIRE(exr_write_header(ctx) == EXR_ERR_SUCCESS);
    for (int k = 0; k < 2 && ok; k++) {
        exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
        for (int y = 0; y < H && ok; y++) {
            exr_chunk_info_t ci;
            ok &= exr_write_scanline_chunk_info(ctx, k, y, &ci) == EXR_ERR_SUCCESS;
            ok &= (y == 0 ? exr_encoding_initialize(ctx, k, &ci, &enc)
                          : exr_encoding_update(ctx, k, &ci, &enc)) == EXR_ERR_SUCCESS;
            enc.channels[0].encode_from_ptr = (const uint8_t *)(vals[k] + y * W);
            enc.channels[0].user_pixel_stride = 4;
            enc.channels[0].user_line_stride = 4 * W;
            enc.channels[0].user_bytes_per_element = 4;
            enc.channels[0].user_data_type = EXR_PIXEL_FLOAT;
            if (y == 0)
                ok &= exr_encoding_choose_default_routines(ctx, k, &enc) == EXR_ERR_SUCCESS;
            ok &= exr_encoding_run(ctx, k, &enc) == EXR_ERR_SUCCESS;
        }
        exr_encoding_destroy(ctx, &enc);
    }
    CHECK(exr_finish(&ctx) == EXR_ERR_SUCCESS);
    REQUIRE(ok);
    hd_exr_image img;
    hd_exr_init(&img);
    static const char *const sel[4] = {"right", "1", "left", "0"};
    for (int t = 0; t < 4; t++) {
        hd_status st = hd_exr_load_part(path, sel[t], &img);
        CHECK_MSG(st == HD_OK, "part %s: %s", sel[t], hd_errmsg());
        if (st == HD_OK) {
            int k = t < 2 ? 1 : 0;
            CHECK(img.part == k);
            CHECK(img.nchan == 1 && !memcmp(img.chan[0].data, vals[k], sizeof vals[k]));
        }
    }
    hd_set_warnings(0);
    CHECK(hd_exr_load(path, &img) == HD_OK && img.part == 0 && img.chan[0].data[0] == 100.0f);
    hd_set_warnings(1);
    CHECK(hd_exr_load_part(path, "middle", &img) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "no part 'middle'; its parts: 0 (left), 1 (right)");
    CHECK(hd_exr_load_part(path, "2", &img) == HD_ERR_FORMAT);
    hd_exr_free(&img);
}

/* Names over 31 bytes need OpenEXR's long-name flag. */
static void test_long_names(void)
{
    const char *ch = "window_group_with_a_rather_long_name_north_facade.R";
    const char *at = "heliodonHeader.window_group_with_a_rather_long_name";
    hd_exr_image img, back;
    hd_exr_init(&img);
    REQUIRE(hd_exr_set_size(&img, 3, 2) == HD_OK);
    int i;
    REQUIRE(hd_exr_add_channel(&img, ch, HD_EXR_FLOAT, &i) == HD_OK);
    img.chan[i].data[5] = 42.0f;
    REQUIRE(hd_exr_set_attr(&img, at, "line one\n") == HD_OK);
    uint8_t *data;
    size_t len;
    hd_status st = hd_exr_encode(&img, HD_EXR_ZIP, "long.exr", &data, &len);
    REQUIRE(st == HD_OK);
    CHECK(data[5] & 0x04);   /* version flags: long names */
    hd_exr_init(&back);
    st = hd_exr_decode(data, len, "long.exr", &back);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    if (st == HD_OK) {
        i = hd_exr_find_channel(&back, ch);
        CHECK(i >= 0 && back.chan[i].data[5] == 42.0f);
        CHECK_STR(hd_exr_get_attr(&back, at), "line one\n");
    }
    free(data);
    /* short names: flag not set */
    hd_exr_free(&img);
    REQUIRE(hd_exr_set_size(&img, 3, 2) == HD_OK);
    REQUIRE(hd_exr_add_channel(&img, "R", HD_EXR_FLOAT, NULL) == HD_OK);
    REQUIRE(hd_exr_encode(&img, HD_EXR_ZIP, "short.exr", &data, &len) == HD_OK);
    CHECK(!(data[5] & 0x04));
    free(data);
    hd_exr_free(&img);
    hd_exr_free(&back);
}

static void test_names(void)
{
    hd_exr_compression c;
    CHECK(hd_exr_parse_compression("ZIP", &c) == 0 && c == HD_EXR_ZIP);
    CHECK(hd_exr_parse_compression("piz", &c) == 0 && c == HD_EXR_PIZ);
    CHECK(hd_exr_parse_compression("none", &c) == 0 && c == HD_EXR_NONE);
    CHECK(hd_exr_parse_compression("zips", &c) == 0 && c == HD_EXR_ZIPS);
    CHECK(hd_exr_parse_compression("dwaa", &c) != 0);   /* cannot write it */
    CHECK(hd_exr_parse_compression("", &c) != 0);
    CHECK_STR(hd_exr_compression_name(HD_EXR_PIZ), "piz");
    CHECK_STR(hd_exr_pixtype_name(HD_EXR_HALF), "half");
    static const char *const ch[] = {"Y", "wg1.R", "wg1.G", "a.b.c"};
    hd_exr_image img;
    REQUIRE(make_image(&img, 2, 2, ch, 4, HD_EXR_HALF));
    char buf[256];
    hd_exr_list_layers(&img, buf, sizeof buf);
    CHECK_STR(buf, "(default), wg1, a.b");
    hd_exr_free(&img);
}

#ifndef HD_TEST_NO_PICTURE
/* picture -> EXR -> picture equals the RGBE-decoded values of the picture. */
static void test_picture_roundtrip(void)
{
    const int W = 29, H = 17;
    hd_picture pic, rd, out;
    hd_picture_init(&pic);
    hd_picture_init(&rd);
    hd_picture_init(&out);
    REQUIRE(hd_picture_alloc(&pic, W, H) == HD_OK);
    for (int i = 0; i < 3 * W * H; i++)
        pic.pix[i] = (float)pow(10.0, -3.0 + 6.0 * urand());
    char hpath[512];
    snprintf(hpath, sizeof hpath, "%s/test_exr_pic.hdr", hd_test_tmpdir());
    hd_header h;
    hd_header_init(&h);
    REQUIRE(hd_picture_save(hpath, &pic, &h) == HD_OK);
    hd_status st = hd_picture_read(hpath, &rd);
    REQUIRE(st == HD_OK);
    /* expected values: RGBE-decoded */
    for (int i = 0; i < W * H; i++) {
        uint8_t e[4];
        float v[3];
        hd_rgbe_encode(e, pic.pix[3 * i], pic.pix[3 * i + 1], pic.pix[3 * i + 2]);
        hd_rgbe_decode(e, v);
        for (int k = 0; k < 3; k++)
            if (rd.pix[3 * i + k] != v[k]) {
                CHECK_MSG(0, "picture read back differs from RGBE decoding at %d", i);
                i = W * H;
                break;
            }
    }
    for (int t = 0; t < 2; t++) {
        hd_exr_image img, back;
        hd_exr_init(&img);
        REQUIRE(hd_exr_from_picture(&img, &rd, t ? "wg1" : NULL, t ? HD_EXR_HALF : HD_EXR_FLOAT, 1.0) == HD_OK);
        CHECK(img.has_chroma && img.chroma[0] == 0.640f);
        uint8_t *data;
        size_t len;
        REQUIRE(hd_exr_encode(&img, t ? HD_EXR_PIZ : HD_EXR_ZIP, "pic.exr", &data, &len) == HD_OK);
        hd_exr_init(&back);
        REQUIRE(hd_exr_decode(data, len, "pic.exr", &back) == HD_OK);
        /* the default layer is absent in the layered file: clear error */
        if (t) {
            CHECK(hd_exr_to_picture(&back, NULL, &out) == HD_ERR_FORMAT);
            CHECK_CONTAINS(hd_errmsg(), "wg1");
        }
        st = hd_exr_to_picture(&back, t ? "wg1" : NULL, &out);
        CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
        if (st == HD_OK) {
            CHECK(out.xres == W && out.yres == H && out.fmt == HD_PIC_RGBE);
            double worst = 0;
            for (int i = 0; i < 3 * W * H; i++) {
                double r = fabs(out.pix[i] - rd.pix[i]) / rd.pix[i];
                if (r > worst)
                    worst = r;
            }
            if (t == 0)
                CHECK_MSG(worst == 0, "float round trip not exact: %g", worst);
            else
                CHECK_MSG(worst <= 1e-3, "half round trip: worst relative error %g", worst);
        }
        hd_picture_free(&out);
        hd_picture_init(&out);
        free(data);
        hd_exr_free(&img);
        hd_exr_free(&back);
    }
    /* XYZE pictures are marked with the XYZ chromaticities and come back as XYZE */
    rd.fmt = HD_PIC_XYZE;
    hd_exr_image img;
    hd_exr_init(&img);
    REQUIRE(hd_exr_from_picture(&img, &rd, NULL, HD_EXR_FLOAT, 0.5) == HD_OK);
    CHECK(img.chroma[0] == 1.0f && img.chroma[3] == 1.0f);
    CHECK(img.chan[0].data[0] == (float)(rd.pix[0] * 0.5));
    REQUIRE(hd_exr_to_picture(&img, NULL, &out) == HD_OK);
    CHECK(out.fmt == HD_PIC_XYZE);
    /* PRIMARIES lines: only when the chromaticities differ from what the
     * header already says (or from Radiance's default) */
    hd_header ph;
    hd_header_init(&ph);
    CHECK(hd_exr_header_add_primaries(&img, &ph) == HD_OK && ph.len == 0);   /* XYZ */
    memcpy(img.chroma, hd_exr_chroma_radiance, sizeof img.chroma);
    CHECK(hd_exr_header_add_primaries(&img, &ph) == HD_OK && ph.len == 0);   /* default */
    static const float rec709[8] = {0.64f, 0.33f, 0.30f, 0.60f, 0.15f, 0.06f, 0.3127f, 0.3290f};
    memcpy(img.chroma, rec709, sizeof img.chroma);
    CHECK(hd_exr_header_add_primaries(&img, &ph) == HD_OK);
    CHECK_STR(ph.text, "PRIMARIES= 0.6400 0.3300 0.3000 0.6000 0.1500 0.0600 0.3127 0.3290\n");
    size_t l1 = ph.len;
    CHECK(hd_exr_header_add_primaries(&img, &ph) == HD_OK && ph.len == l1);  /* already said */
    memcpy(img.chroma, hd_exr_chroma_radiance, sizeof img.chroma);
    CHECK(hd_exr_header_add_primaries(&img, &ph) == HD_OK && ph.len > l1);   /* back to default */
    CHECK_CONTAINS(ph.text, "PRIMARIES= 0.6400 0.3300 0.2900 0.6000 0.1500 0.0600 0.3333 0.3333\n");
    hd_header_free(&ph);
    hd_exr_free(&img);
    hd_header_free(&h);
    hd_picture_free(&pic);
    hd_picture_free(&rd);
    hd_picture_free(&out);
}
#endif

int main(void)
{
    (void)hd_test_ref;   /* reference data is used by the e2e test */
    RUN(test_roundtrip_float_rgb);
    RUN(test_roundtrip_half_layers);
    RUN(test_uint_and_mixed);
    RUN(test_attributes);
    RUN(test_determinism_and_row_order);
    RUN(test_save_load_file);
    RUN(test_truncated);
    RUN(test_corrupt);
    RUN(test_absurd_sizes);
    RUN(test_read_tiled);
    RUN(test_parts);
    RUN(test_long_names);
    RUN(test_names);
#ifndef HD_TEST_NO_PICTURE
    RUN(test_picture_roundtrip);
#endif
    return hd_test_done();
}

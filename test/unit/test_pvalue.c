/* pvalue library: picture -> values -> picture round trips (float, byte,
 * ascii), the byte order flag, and errors on truncated value streams. */
#include "hd_test.h"

#include "heliodon/header.h"
#include "heliodon/pvalue.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static char *argv0[] = {"pvalue", NULL};

/* a 7 x 5 picture of distinct values spanning several exponents */
static void make_picture(const char *path, hd_picture *p)
{
    REQUIRE(hd_picture_alloc(p, 7, 5) == HD_OK);
    for (int i = 0; i < 7 * 5; i++)
        for (int c = 0; c < 3; c++) p->pix[3 * i + c] = (float)((i + 1) * (c + 1) * pow(10.0, (i % 5) - 2));
    hd_header h;
    hd_header_init(&h);
    REQUIRE(hd_picture_save(path, p, &h) == HD_OK);
    hd_header_free(&h);
}

/* forward with format c, then reverse; the result equals the RGBE-decoded
 * input exactly for float (values are RGBE-representable) */
static void roundtrip(char fmt, double rtol)
{
    char pic[512], val[512], back[512];
    const char *tmp = hd_test_tmpdir();
    snprintf(pic, sizeof pic, "%s/pv_in.hdr", tmp);
    snprintf(val, sizeof val, "%s/pv_%c.dat", tmp, fmt);
    snprintf(back, sizeof back, "%s/pv_back_%c.hdr", tmp, fmt);
    hd_picture p, in, q;
    make_picture(pic, &p);
    REQUIRE(hd_picture_read(pic, &in) == HD_OK);

    hd_pvalue_opts o;
    hd_pvalue_opts_init(&o);
    REQUIRE(hd_pvalue_set_format(&o, fmt, 1) == HD_OK);
    hd_pvalue_opts_finish(&o);
    FILE *f = fopen(val, "wb");
    REQUIRE(f);
    CHECK(hd_pvalue_to_values(&o, pic, f, 1, argv0) == HD_OK);
    fclose(f);

    hd_pvalue_opts_init(&o);
    REQUIRE(hd_pvalue_set_format(&o, fmt, 1) == HD_OK);
    hd_pvalue_opts_finish(&o);
    f = fopen(back, "wb");
    REQUIRE(f);
    const char *paths[1] = {val};
    CHECK(hd_pvalue_from_values(&o, paths, 1, f, 1, argv0) == HD_OK);
    fclose(f);
    REQUIRE(hd_picture_read(back, &q) == HD_OK);
    CHECK(q.xres == 7 && q.yres == 5);
    double worst = 0;
    for (int i = 0; i < 3 * 7 * 5; i++) {
        double a = in.pix[i], b = q.pix[i];
        double r = fabs(b - a) / (a > 1e-30 ? a : 1e-30);
        if (r > worst) worst = r;
    }
    CHECK_MSG(worst <= rtol, "format %c: worst relative difference %g > %g", fmt, worst, rtol);
    hd_picture_free(&p);
    hd_picture_free(&in);
    hd_picture_free(&q);
}

static void test_roundtrip_float(void) { roundtrip('f', 0); }
static void test_roundtrip_double(void) { roundtrip('d', 0); }
/* ascii keeps 4 significant digits (%15.3e): 5e-4 relative, plus RGBE's
 * 1/256 mantissa step on re-encoding */
static void test_roundtrip_ascii(void) { roundtrip('a', 5e-4 + 1.0 / 128); }

static void test_truncated_values(void)
{
    char val[512], out[512];
    snprintf(val, sizeof val, "%s/pv_trunc.dat", hd_test_tmpdir());
    snprintf(out, sizeof out, "%s/pv_trunc.hdr", hd_test_tmpdir());
    FILE *f = fopen(val, "wb");
    REQUIRE(f);
    float v[3 * 5] = {0};
    fwrite(v, sizeof v, 1, f);      /* 5 pixels of a 4 x 4 picture */
    fclose(f);
    hd_pvalue_opts o;
    hd_pvalue_opts_init(&o);
    REQUIRE(hd_pvalue_set_format(&o, 'f', 1) == HD_OK);
    o.header = 0;
    o.resolution = 0;
    o.picres.xres = o.picres.yres = 4;
    o.picres.orient = HD_RES_YMAJOR | HD_RES_YDECR;
    hd_pvalue_opts_finish(&o);
    f = fopen(out, "wb");
    REQUIRE(f);
    const char *paths[1] = {val};
    CHECK(hd_pvalue_from_values(&o, paths, 1, f, 1, argv0) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "pixel 1 of scanline 1");
    fclose(f);
}

static void test_bad_format_letter(void)
{
    hd_pvalue_opts o;
    hd_pvalue_opts_init(&o);
    CHECK(hd_pvalue_set_format(&o, 'q', 1) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "-dq");
}

int main(void)
{
    RUN(test_roundtrip_float);
    RUN(test_roundtrip_double);
    RUN(test_roundtrip_ascii);
    RUN(test_truncated_values);
    RUN(test_bad_format_letter);
    return hd_test_done();
}

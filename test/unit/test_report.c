/* Unit tests: report figures and the PNG writer/reader (report.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "hd_test.h"
#include "heliodon/picture.h"
#include "heliodon/report.h"

static void tmp(char *buf, size_t cap, const char *name)
{
    if (snprintf(buf, cap, "%s/%s", hd_test_tmpdir(), name) >= (int)cap) buf[0] = 0;
}

static void test_png_roundtrip(void)
{
    int w = 37, h = 23;
    uint8_t *rgb = malloc((size_t)w * h * 3);
    REQUIRE(rgb);
    unsigned s = 12345;
    for (int i = 0; i < w * h * 3; i++) {
        s = s * 1103515245u + 12345u;
        rgb[i] = (uint8_t)(s >> 16);
    }
    char p[1024];
    tmp(p, sizeof p, "report_rt.png");
    REQUIRE(hd_png_write(p, rgb, w, h) == HD_OK);
    uint8_t *back = NULL;
    int bw = 0, bh = 0;
    REQUIRE(hd_png_read(p, &back, &bw, &bh) == HD_OK);
    CHECK(bw == w && bh == h);
    CHECK(memcmp(back, rgb, (size_t)w * h * 3) == 0);
    free(back);
    /* corrupt one byte inside the IDAT chunk: the CRC check must catch it */
    FILE *f = fopen(p, "r+b");
    REQUIRE(f);
    fseek(f, 8 + 25 + 12, SEEK_SET);
    int c = fgetc(f);
    fseek(f, 8 + 25 + 12, SEEK_SET);
    fputc(c ^ 0x5a, f);
    fclose(f);
    CHECK(hd_png_read(p, NULL, &bw, &bh) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "CRC mismatch in IDAT");
    /* truncated */
    REQUIRE(hd_png_write(p, rgb, w, h) == HD_OK);
    f = fopen(p, "r+b");
    REQUIRE(f);
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fclose(f);
    CHECK(truncate(p, len - 6) == 0);
    CHECK(hd_png_read(p, NULL, &bw, &bh) == HD_ERR_FORMAT);
    CHECK(hd_png_write(p, rgb, 0, 5) == HD_ERR_RANGE);
    free(rgb);
}

static void test_colours(void)
{
    uint8_t a[3], b[3], z[3];
    hd_report_falsecolor(10, 10, 10000, a);
    hd_report_ramp(0, b);
    CHECK(memcmp(a, b, 3) == 0);
    hd_report_falsecolor(1e6, 10, 10000, a);   /* clamped to the top */
    hd_report_ramp(1, b);
    CHECK(memcmp(a, b, 3) == 0);
    hd_report_falsecolor(0, 10, 10000, z);
    CHECK(z[0] == 0 && z[1] == 0 && z[2] == 0);
    /* a decade in the middle is the ramp at t = 1/3 */
    hd_report_falsecolor(100, 10, 10000, a);
    hd_report_ramp(1.0 / 3, b);
    CHECK(abs(a[0] - b[0]) <= 1 && abs(a[1] - b[1]) <= 1 && abs(a[2] - b[2]) <= 1);
}

static void test_report_and_select(void)
{
    char csv[1024], log[1024], out[1024];
    tmp(csv, sizeof csv, "report_t.csv");
    tmp(log, sizeof log, "report_t.log");
    tmp(out, sizeof out, "report_t");
    FILE *f = fopen(csv, "w");
    REQUIRE(f);
    fprintf(f, "hour,Ev,DGP,DGI,UGR,nsources,DGP_class,DGI_class,shade\n");
    double dgps[5] = {0.2, 0.5, 0.3, 0.41, 0.25};
    for (int i = 0; i < 5; i++) fprintf(f, "%d.5,1000,%.3f,15,20,1,a,b,%d\n", 1900 + i, dgps[i], dgps[i] >= 0.4);
    fclose(f);
    hd_report_data d;
    REQUIRE(hd_report_read_csv(csv, &d) == HD_OK);
    CHECK(d.n == 5);
    CHECK_NEAR(d.hoy[2], 1902.5, 1e-12);
    CHECK_NEAR(d.dgp[1], 0.5, 1e-12);
    CHECK(d.shade[3] == 1);
    hd_report_data_free(&d);
    f = fopen(log, "w");
    REQUIRE(f);
    fprintf(f, "# header\n");
    for (int i = 0; i < 5; i++) fprintf(f, "%d 3 21 10.5 94 0 0 1 1 1 1 100 %.3f\n", 10 + i, dgps[i]);
    fclose(f);
    char sel[1024];
    tmp(sel, sizeof sel, "report_t.sel");
    f = fopen(sel, "w");
    REQUIRE(f);
    REQUIRE(hd_report_select(log, 4, f) == HD_OK);
    fclose(f);
    f = fopen(sel, "r");
    REQUIRE(f);
    char line[256] = "";
    CHECK(fgets(line, sizeof line, f) != NULL);
    fclose(f);
    /* max (record 11, DGP .5); p95 of 5 -> index 4 = max again (skipped);
     * median (record 12, .3); min (record 10, .2) */
    CHECK_STR(line, "11,12,10\n");
    char par[1024], tim[1024];
    tmp(par, sizeof par, "report_t.par");
    tmp(tim, sizeof tim, "report_t.tim");
    f = fopen(par, "w");
    REQUIRE(f);
    fprintf(f, "# comment\nsun patches = Reinhart MF:6\nview = v1 (-vta -vh 180)\n");
    fclose(f);
    f = fopen(tim, "w");
    REQUIRE(f);
    fprintf(f, "mkpmap 12.5\nrcontrib_sun 100 cpu 150.25 rss_mb 812.5 disk_mb 40.0 peak_mb 1040.5\n"
               "pmcompose 2.5 cpu 4.75 rss_mb 1200.0 disk_mb -1.5 peak_mb 1000.0\n");
    fclose(f);
    hd_report_opts o;
    hd_report_opts_default(&o);
    o.csv = csv;
    o.outdir = out;
    o.params = par;
    o.timings = tim;
    REQUIRE(hd_report_write(&o) == HD_OK);
    {
        char ip[1200], html[65536];
        snprintf(ip, sizeof ip, "%s/index.html", out);
        FILE *h = fopen(ip, "r");
        REQUIRE(h);
        size_t hn = fread(html, 1, sizeof html - 1, h);
        html[hn] = 0;
        fclose(h);
        CHECK_CONTAINS(html, "<td>sun patches</td><td>Reinhart MF:6</td>");
        CHECK_CONTAINS(html, "<td>view</td><td>v1 (-vta -vh 180)</td>");
        CHECK_CONTAINS(html, "<td>mkpmap</td><td>12.5</td><td></td>");
        CHECK_CONTAINS(html, "<td>rcontrib_sun</td><td>100</td><td>150.25</td><td>812.5</td><td>40.0</td><td>1040.5</td>");
        /* totals: wall and CPU summed, RSS and folder peak the largest, disk summed */
        CHECK_CONTAINS(html, "<th>115.00</th><th>155.00</th><th>1200.0</th><th>38.5</th><th>1040.5</th>");
        CHECK_CONTAINS(html, "<td>5</td>");   /* daylight hours */
    }
    const char *files[] = {"index.html", "dgp_heat.svg", "dgi_heat.svg", "shade.svg", "dgp_hist.svg", "dgi_hist.svg"};
    for (int i = 0; i < 6; i++) {
        char p[1200];
        snprintf(p, sizeof p, "%s/%s", out, files[i]);
        f = fopen(p, "r");
        CHECK_MSG(f != NULL, "%s not written", p);
        if (f) fclose(f);
    }
    /* the shade schedule counts the closed hours */
    char p[1200];
    snprintf(p, sizeof p, "%s/shade.svg", out);
    f = fopen(p, "r");
    REQUIRE(f);
    char buf[65536];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    buf[n] = 0;
    fclose(f);
    CHECK_CONTAINS(buf, "closed (2 h)");
    CHECK_CONTAINS(buf, "open (3 h)");
    /* bad CSV */
    f = fopen(csv, "w");
    REQUIRE(f);
    fprintf(f, "hour,Ev,DGP,DGI,UGR,nsources,DGP_class,DGI_class,shade\n1,2,3\n");
    fclose(f);
    CHECK(hd_report_read_csv(csv, &d) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "line 2");
}

/* cbdmreport -png: display values clipped to 0..1, gamma 2.2 (0.5 -> 186, 0.25 -> 136), rows top first */
static void test_display_png(void)
{
    hd_picture pic;
    hd_picture_init(&pic);
    REQUIRE(hd_picture_alloc(&pic, 3, 2) == HD_OK);
    const float v[6] = {0, 0.5f, 2, 0.25f, 1, -1};
    for (int i = 0; i < 6; i++) pic.pix[3 * i] = pic.pix[3 * i + 1] = pic.pix[3 * i + 2] = v[i];
    pic.pix[3 * 1 + 2] = 0; /* pixel 1: blue 0 */
    char h[1024], p[1024];
    tmp(h, sizeof h, "display.hdr");
    tmp(p, sizeof p, "display.png");
    FILE *fp = fopen(h, "wb");
    REQUIRE(fp);
    REQUIRE(hd_picture_write(fp, &pic, NULL, 0) == HD_OK);
    fclose(fp);
    hd_picture_free(&pic);
    REQUIRE(hd_report_display_png(h, p) == HD_OK);
    uint8_t *rgb = NULL;
    int w = 0, ht = 0;
    REQUIRE(hd_png_read(p, &rgb, &w, &ht) == HD_OK);
    CHECK(w == 3 && ht == 2);
    const int want[6] = {0, 186, 255, 136, 255, 0};
    for (int i = 0; i < 6; i++) CHECK_MSG(rgb[3 * i] == want[i], "pixel %d: %d, expected %d", i, rgb[3 * i], want[i]);
    CHECK(rgb[3 * 1 + 2] <= 16); /* RGBE: a 0 beside 0.5 decodes as half a step of the shared exponent */
    free(rgb);
    CHECK(hd_report_display_png("/nonexistent/x.hdr", p) != HD_OK);
}

int main(void)
{
    hd_set_warnings(0);
    RUN(test_png_roundtrip);
    RUN(test_colours);
    RUN(test_display_png);
    RUN(test_report_and_select);
    return hd_test_done();
}

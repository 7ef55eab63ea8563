/* BSDF XML loader: malformed and incomplete inputs give clear errors that
 * name the element and the line; small valid synthetic files load with
 * the right values (custom angle basis, Rows layout, TensorTree3/4). */
#include "hd_test.h"
#include "heliodon/bsdf.h"

static const char *HEAD =
    "<?xml version=\"1.0\"?>\n"
    "<WindowElement xmlns=\"http://windows.lbl.gov\">\n"
    "<FileType>BSDF</FileType>\n"
    "<Optical><Layer>\n"
    "<Material><Name>test</Name><Manufacturer>me</Manufacturer>\n"
    "<Thickness unit=\"Millimeter\">4</Thickness><Width unit=\"Centimeter\">50</Width>\n"
    "<Height>2</Height></Material>\n";

/* A 3-ring custom basis: 1 + 4 + 4 = 9 bins */
static const char *BASIS =
    "<AngleBasis><AngleBasisName>Custom9</AngleBasisName>\n"
    "<AngleBasisBlock><Theta>0</Theta><nPhis>1</nPhis><ThetaBounds><LowerTheta>0</LowerTheta><UpperTheta>30</UpperTheta></ThetaBounds></AngleBasisBlock>\n"
    "<AngleBasisBlock><Theta>45</Theta><nPhis>4</nPhis><ThetaBounds><LowerTheta>30</LowerTheta><UpperTheta>60</UpperTheta></ThetaBounds></AngleBasisBlock>\n"
    "<AngleBasisBlock><Theta>75</Theta><nPhis>4</nPhis><ThetaBounds><LowerTheta>60</LowerTheta><UpperTheta>90</UpperTheta></ThetaBounds></AngleBasisBlock>\n"
    "</AngleBasis>\n";

static char doc[1 << 17];

static void make(const char *ids, const char *basis, const char *dir, const char *extra_block,
                 const char *data)
{
    snprintf(doc, sizeof doc,
             "%s<DataDefinition><IncidentDataStructure>%s</IncidentDataStructure>\n%s</DataDefinition>\n"
             "<WavelengthData><Wavelength unit=\"Integral\">Visible</Wavelength>\n"
             "<WavelengthDataBlock>\n%s%s"
             "<ScatteringData>%s</ScatteringData>\n"
             "</WavelengthDataBlock></WavelengthData>\n</Layer></Optical></WindowElement>\n",
             HEAD, ids, basis, dir, extra_block, data);
}

static const char *DIR_TF = "<WavelengthDataDirection>Transmission Front</WavelengthDataDirection>\n";
static const char *KB = "<ColumnAngleBasis>Custom9</ColumnAngleBasis><RowAngleBasis>Custom9</RowAngleBasis>\n";

/* 81 values: value = out*10 + in (plus 1000 so none is 0) */
static void klems_values(char *buf, size_t cap, int rows_layout)
{
    size_t n = 0;
    for (int r = 0; r < 9; r++) {
        for (int k = 0; k < 9; k++) {
            int out = rows_layout ? k : r, in = rows_layout ? r : k;
            n += (size_t)snprintf(buf + n, cap - n, "%d%s", 1000 + out * 10 + in, k < 8 ? ", " : "\n");
        }
    }
}

static hd_bsdf *load_doc(hd_status *st)
{
    hd_bsdf *b = NULL;
    *st = hd_bsdf_load_memory(doc, strlen(doc), "t.xml", &b);
    return b;
}

static void expect_error(const char *what, const char *needle1, const char *needle2)
{
    hd_status st;
    hd_bsdf *b = load_doc(&st);
    CHECK_MSG(st != HD_OK && !b, "%s: loaded although malformed", what);
    if (st != HD_OK) {
        CHECK_CONTAINS(hd_errmsg(), "t.xml");
        CHECK_CONTAINS(hd_errmsg(), needle1);
        if (needle2) CHECK_CONTAINS(hd_errmsg(), needle2);
    }
    hd_bsdf_free(b);
}

static void test_custom_basis_columns(void)
{
    char vals[4096];
    klems_values(vals, sizeof vals, 0);
    make("Columns", BASIS, DIR_TF, KB, vals);
    hd_status st;
    hd_bsdf *b = load_doc(&st);
    REQUIRE(st == HD_OK && b);
    const hd_bsdf_info *in = hd_bsdf_get_info(b);
    CHECK(in->type == HD_BSDF_KLEMS_OTHER);
    CHECK_NEAR(in->thickness, 0.004, 1e-12);
    CHECK_NEAR(in->width, 0.5, 1e-12);
    CHECK_NEAR(in->height, 2, 1e-12);
    CHECK_STR(in->name, "test");
    CHECK(in->avail[HD_BSDF_TB] == HD_BSDF_IN_FILE);
    CHECK(in->avail[HD_BSDF_TF] == HD_BSDF_RECIPROCAL);
    CHECK(in->avail[HD_BSDF_RF] == HD_BSDF_ABSENT);
    /* Lambertian split: min 1000 → π·1000 */
    CHECK_NEAR(in->lambertian[HD_BSDF_TB], HD_PI * 1000, 1e-3);
    /* the reciprocal side reports its source's Lambertian part (Radiance's checkBSDF prints it) */
    CHECK_NEAR(in->lambertian[HD_BSDF_TF], HD_PI * 1000, 1e-3);
    CHECK(in->lambertian[HD_BSDF_RF] == 0);
    /* incident from the exterior (-z) in bin 5 (ring 1, column 0 → the
     * incident vector's in-plane part points to azimuth 180), outgoing in
     * room-side bin 7 (ring 1 col 2 → azimuth 180) */
    hd_klems_basis kb;
    double bnd[] = {0, 30, 60, 90};
    int nphi[] = {1, 4, 4};
    hd_klems_init(&kb, "Custom9", 3, bnd, nphi, NULL);
    for (int i = 0; i < 9; i++)
        for (int o = 0; o < 9; o++) {
            hd_vec3 vi = hd_bsdf_klems_in_dir(&kb, HD_BSDF_TB, i, 0.5, 0.5);
            hd_vec3 vo = hd_bsdf_klems_out_dir(&kb, HD_BSDF_TB, o, 0.5, 0.5);
            double f = hd_bsdf_eval(b, vi, vo);
            if (fabs(f - (1000 + o * 10 + i)) > 1e-3) {
                CHECK_MSG(0, "f(in bin %d, out bin %d) = %g, expected %d", i, o, f, 1000 + o * 10 + i);
                i = o = 99;
            }
        }
    /* explicit direction: incident from below the window travelling
     * straight in at normal incidence → bin 0 both */
    CHECK_NEAR(hd_bsdf_eval(b, hd_v3(0, 0, -1), hd_v3(0, 0, 1)), 1000, 1e-3);
    /* reciprocity: tf(v2, v1) = tb(v1, v2) */
    hd_vec3 v1 = hd_bsdf_klems_in_dir(&kb, HD_BSDF_TB, 3, 0.5, 0.5);
    hd_vec3 v2 = hd_bsdf_klems_out_dir(&kb, HD_BSDF_TB, 6, 0.5, 0.5);
    CHECK_NEAR(hd_bsdf_eval(b, v2, v1), hd_bsdf_eval(b, v1, v2), 1e-9);
    hd_bsdf_free(b);
}

static void test_rows_layout(void)
{
    char vals[4096];
    klems_values(vals, sizeof vals, 1);
    make("Rows", BASIS, DIR_TF, KB, vals);
    hd_status st;
    hd_bsdf *b = load_doc(&st);
    REQUIRE(st == HD_OK && b);
    hd_klems_basis kb;
    double bnd[] = {0, 30, 60, 90};
    int nphi[] = {1, 4, 4};
    hd_klems_init(&kb, "Custom9", 3, bnd, nphi, NULL);
    hd_vec3 vi = hd_bsdf_klems_in_dir(&kb, HD_BSDF_TB, 2, 0.5, 0.5);
    hd_vec3 vo = hd_bsdf_klems_out_dir(&kb, HD_BSDF_TB, 7, 0.5, 0.5);
    CHECK_NEAR(hd_bsdf_eval(b, vi, vo), 1072, 1e-3);
    hd_bsdf_free(b);
}

/* TensorTree4 with one subdivision: child n (bit i = upper half of dim i)
 * holds a single value n+1, except child 0 which is a 16-value grid. */
static void test_tree4_order(void)
{
    char data[4096];
    size_t n = (size_t)snprintf(data, sizeof data, "{\n { ");
    for (int k = 0; k < 16; k++) n += (size_t)snprintf(data + n, sizeof data - n, "%d ", 100 + k);
    n += (size_t)snprintf(data + n, sizeof data - n, "}\n");
    for (int c = 1; c < 16; c++) n += (size_t)snprintf(data + n, sizeof data - n, " { %d }\n", c + 1);
    snprintf(data + n, sizeof data - n, "}\n");
    make("TensorTree4", "",
         "<WavelengthDataDirection>Transmission Back</WavelengthDataDirection>\n",
         "<AngleBasis>LBNL/Shirley-Chiu</AngleBasis>\n", data);
    hd_status st;
    hd_bsdf *b = load_doc(&st);
    REQUIRE(st == HD_OK && b);
    const hd_bsdf_info *in = hd_bsdf_get_info(b);
    CHECK(in->type == HD_BSDF_TREE4);
    CHECK(in->tree_res == 4);
    /* tf: in on +z.  Choose square coords: c0,c1 from (-in.x,-in.y),
     * c2,c3 from (out.x,out.y). */
    for (int child = 0; child < 16; child++) {
        double c[4], dx, dy;
        for (int d = 0; d < 4; d++) c[d] = (child >> d & 1) ? 0.8 : 0.2;
        hd_square2disk(c[0], c[1], &dx, &dy);
        hd_vec3 vin = hd_v3(-dx, -dy, sqrt(1 - dx * dx - dy * dy));
        hd_square2disk(c[2], c[3], &dx, &dy);
        hd_vec3 vout = hd_v3(dx, dy, -sqrt(1 - dx * dx - dy * dy));
        double f = hd_bsdf_eval(b, vin, vout);
        double expect = child + 1;
        if (child == 0) {
            /* grid of child 0: each coord 0.2 → 0.4 → index 0 in a 2-grid
             * (0.4 < 0.5): value index 0 */
            expect = 100;
        }
        CHECK_MSG(fabs(f - expect) < 1e-4, "child %d: f = %g, expected %g", child, f, expect);
    }
    /* value-grid order: last dimension fastest.  Inside child 0 move only
     * dim 3 to its upper half (coord 0.4 → local 0.8... use 0.3 → 0.6) */
    {
        double c[4] = {0.1, 0.1, 0.1, 0.3}, dx, dy;
        hd_square2disk(c[0], c[1], &dx, &dy);
        hd_vec3 vin = hd_v3(-dx, -dy, sqrt(1 - dx * dx - dy * dy));
        hd_square2disk(c[2], c[3], &dx, &dy);
        hd_vec3 vout = hd_v3(dx, dy, -sqrt(1 - dx * dx - dy * dy));
        CHECK_NEAR(hd_bsdf_eval(b, vin, vout), 101, 1e-4);
        c[3] = 0.1;
        c[0] = 0.3;      /* dim 0 slowest: index 8 */
        hd_square2disk(c[0], c[1], &dx, &dy);
        vin = hd_v3(-dx, -dy, sqrt(1 - dx * dx - dy * dy));
        hd_square2disk(c[2], c[3], &dx, &dy);
        vout = hd_v3(dx, dy, -sqrt(1 - dx * dx - dy * dy));
        CHECK_NEAR(hd_bsdf_eval(b, vin, vout), 108, 1e-4);
    }
    hd_bsdf_free(b);
}

static void test_shirley_chiu(void)
{
    int bad = 0;
    for (int i = 0; i < 50; i++)
        for (int j = 0; j < 50; j++) {
            double sx = (i + 0.37) / 50, sy = (j + 0.61) / 50, x, y, tx, ty;
            hd_square2disk(sx, sy, &x, &y);
            hd_disk2square(x, y, &tx, &ty);
            if (fabs(tx - sx) > 1e-9 || fabs(ty - sy) > 1e-9 || x * x + y * y > 1) bad++;
        }
    CHECK(bad == 0);
    double x, y;
    hd_square2disk(0.5, 0.5, &x, &y);
    CHECK_NEAR(x, 0, 1e-12);
    CHECK_NEAR(y, 0, 1e-12);
    hd_square2disk(1, 0.5, &x, &y);     /* a = 1, b = 0: phi = 0 */
    CHECK_NEAR(x, 1, 1e-9);
}

static void test_malformed(void)
{
    char vals[4096];
    klems_values(vals, sizeof vals, 0);

    snprintf(doc, sizeof doc, "this is not XML");
    expect_error("not xml", "malformed XML", "line 1");

    snprintf(doc, sizeof doc, "<?xml version=\"1.0\"?>\n<Foo><Bar/></Foo>\n");
    expect_error("root", "<Foo>", "WindowElement");

    make("Columns", BASIS, DIR_TF, KB, vals);
    doc[strlen(doc) / 2] = 0;            /* truncated file */
    expect_error("truncated", "malformed XML", "line");

    char *p;
    snprintf(doc, sizeof doc, "%s</Layer></Optical></WindowElement>", HEAD);
    expect_error("no data", "IncidentDataStructure", NULL);

    make("Colums", BASIS, DIR_TF, KB, vals);
    expect_error("bad ids", "<IncidentDataStructure>", "Colums");

    make("Columns", BASIS, DIR_TF, KB, "1 2 3 4 5");
    expect_error("count", "<ScatteringData>", "5 values, expected 81");

    make("Columns", BASIS, DIR_TF, KB, "1 2 3.4.5");
    expect_error("bad number", "bad number '3.4.5'", "line");

    make("Columns", BASIS, DIR_TF, "<ColumnAngleBasis>Nope</ColumnAngleBasis><RowAngleBasis>Custom9</RowAngleBasis>\n", vals);
    expect_error("basis name", "'Nope'", "ColumnAngleBasis");

    make("Columns", BASIS, "", KB, vals);
    expect_error("no direction", "missing <WavelengthDataDirection>", NULL);

    make("Columns", BASIS, "<WavelengthDataDirection>Sideways</WavelengthDataDirection>", KB, vals);
    expect_error("bad direction", "Sideways", NULL);

    make("Columns",
         "<AngleBasis><AngleBasisName>B</AngleBasisName><AngleBasisBlock><Theta>0</Theta>"
         "<ThetaBounds><LowerTheta>0</LowerTheta><UpperTheta>90</UpperTheta></ThetaBounds>"
         "</AngleBasisBlock></AngleBasis>", DIR_TF, KB, vals);
    expect_error("no nPhis", "<AngleBasisBlock>", "nPhis");

    make("Columns",
         "<AngleBasis><AngleBasisName>B</AngleBasisName><AngleBasisBlock><nPhis>1</nPhis>"
         "<ThetaBounds><LowerTheta>0</LowerTheta><UpperTheta>80</UpperTheta></ThetaBounds>"
         "</AngleBasisBlock></AngleBasis>", DIR_TF, KB, vals);
    expect_error("bounds", "ends at 80", NULL);

    /* trees */
    const char *SC = "<AngleBasis>LBNL/Shirley-Chiu</AngleBasis>\n";
    make("TensorTree3", "", DIR_TF, SC, "{ { 1 2 3 4 5 6 7 8 } { 1 } { 1 } { 1 } { 1 } { 1 } { 1 } ");
    expect_error("truncated tree", "truncated", "<ScatteringData>");

    make("TensorTree3", "", DIR_TF, SC, "{ 1 2 3 }");
    expect_error("tree count", "has 3 values", "line");

    make("TensorTree3", "", DIR_TF, SC, "{ {1} {2} {3} }");
    expect_error("tree children", "3 child nodes", "expected 8");

    make("TensorTree4", "", DIR_TF, SC, "{ 1 } { 2 }");
    expect_error("after root", "after the end of the tree", NULL);

    make("TensorTree4", "", DIR_TF, SC, "{ 1 { 2 } }");
    expect_error("mixed", "mixes", NULL);

    make("TensorTree4", "", DIR_TF, SC, "{ 1 2 ) }");
    expect_error("bad char", "unexpected character ')'", NULL);

    make("Columns", BASIS, DIR_TF, KB, "{ 1 }");
    expect_error("brace in klems", "unexpected '{'", NULL);

    /* ScatteringData before the data structure is known */
    snprintf(doc, sizeof doc, "%s<WavelengthData><Wavelength>Visible</Wavelength><WavelengthDataBlock>"
             "<ScatteringData>1</ScatteringData></WavelengthDataBlock></WavelengthData>"
             "</Layer></Optical></WindowElement>", HEAD);
    expect_error("order", "before <IncidentDataStructure>", NULL);

    /* only non-visible data */
    make("Columns", BASIS, DIR_TF, KB, vals);
    p = strstr(doc, ">Visible<");
    REQUIRE(p);
    memcpy(p, ">Solar  <", 9);
    expect_error("no visible", "no visible-spectrum", NULL);

    /* nonexistent file */
    hd_bsdf *b = NULL;
    CHECK(hd_bsdf_load("/nonexistent/dir/x.xml", &b) != HD_OK && !b);
    CHECK_CONTAINS(hd_errmsg(), "x.xml");
}

/* Non-visible blocks are ignored, a second layer is ignored. */
static void test_ignored(void)
{
    char vals[4096];
    klems_values(vals, sizeof vals, 0);
    make("Columns", BASIS, DIR_TF, KB, vals);
    /* prepend a Solar block with garbage-free but wrong-size data */
    char *p = strstr(doc, "<WavelengthData>");
    REQUIRE(p);
    char rest[1 << 16];
    snprintf(rest, sizeof rest, "%s", p);
    snprintf(p, sizeof doc - (size_t)(p - doc),
             "<WavelengthData><Wavelength>Solar</Wavelength><WavelengthDataBlock>%s%s"
             "<ScatteringData>1 2 3</ScatteringData></WavelengthDataBlock></WavelengthData>\n%s",
             DIR_TF, KB, rest);
    hd_status st;
    hd_bsdf *b = load_doc(&st);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    hd_bsdf_free(b);
}

/* Klems data with a quarter-basis incident side and the 9-bin custom
 * outgoing side: the matrix is 9 × 41 with the file's values. */
static void test_mixed_bases(void)
{
    static char vals[8 * 1024];
    size_t n = 0;
    for (int o = 0; o < 9; o++) {
        for (int i = 0; i < 41; i++) n += (size_t)snprintf(vals + n, sizeof vals - n, "%d ", o * 100 + i);
        vals[n++] = '\n';
    }
    vals[n] = 0;
    make("Columns", BASIS, DIR_TF,
         "<ColumnAngleBasis>LBNL/Klems Quarter</ColumnAngleBasis><RowAngleBasis>Custom9</RowAngleBasis>\n", vals);
    hd_status st;
    hd_bsdf *b = load_doc(&st);
    REQUIRE(st == HD_OK && b);
    hd_matrix m;
    REQUIRE(hd_bsdf_klems_matrix(b, HD_BSDF_TB, NULL, 0, 1, &m) == HD_OK);
    CHECK(m.nrows == 9 && m.ncols == 41);
    hd_klems_basis q;
    hd_klems_standard(&q, HD_KLEMS_QUARTER);
    if (m.nrows == 9 && m.ncols == 41) {
        CHECK_NEAR(m.data[3 * 41 + 17], (300 + 17) * hd_klems_lambda(&q, 17), 1e-3);
        CHECK_NEAR(m.data[8 * 41 + 40], (800 + 40) * hd_klems_lambda(&q, 40), 1e-3);
    }
    free(m.data);
    hd_bsdf_free(b);
}

/* Random corruption of small valid files never crashes the loader (run
 * under AddressSanitizer by make check-asan): every load either succeeds
 * or fails with a message naming the file. */
static void test_corruption(void)
{
    static char base[1 << 17];
    char vals[4096];
    klems_values(vals, sizeof vals, 0);
    make("Columns", BASIS, DIR_TF, KB, vals);
    const char *tree = "{ { 1 2 3 4 5 6 7 8 } {2} {3} {4} {5} {6} {7} { {1}{2}{3}{4}{5}{6}{7}{8} } }";
    unsigned long x = 12345;
    int ok = 0, failed = 0, nomsg = 0;
    for (int pass = 0; pass < 2; pass++) {
        if (pass == 0) make("Columns", BASIS, DIR_TF, KB, vals);
        else make("TensorTree3", "", DIR_TF, "<AngleBasis>LBNL/Shirley-Chiu</AngleBasis>\n", tree);
        size_t len = strlen(doc);
        memcpy(base, doc, len + 1);
        static const char junk[] = "{}<>/ ,.-e9x\"&";
        for (int k = 0; k < 300; k++) {
            memcpy(doc, base, len + 1);
            int nflip = 1 + k % 4;
            for (int j = 0; j < nflip; j++) {
                x = x * 6364136223846793005UL + 1442695040888963407UL;
                size_t pos = (size_t)(x >> 33) % len;
                doc[pos] = junk[(x >> 20) % (sizeof junk - 1)];
            }
            if (k % 7 == 0) doc[(x >> 40) % len] = 0;    /* truncation */
            hd_bsdf *b = NULL;
            hd_status st = hd_bsdf_load_memory(doc, strlen(doc), "t.xml", &b);
            if (st == HD_OK) {
                ok++;
                /* usable: evaluate and sample a little */
                hd_bsdf_sample s;
                hd_bsdf_eval(b, hd_v3(0.1, 0.2, -0.97), hd_v3(-0.3, 0.1, 0.95));
                hd_bsdf_sample_dir(b, NULL, hd_v3(0.1, 0.2, -0.97), HD_BSDF_FORWARD, HD_BSDF_ALL, 0.3, 0.6, 0.2, &s);
                hd_bsdf_free(b);
            } else {
                failed++;
                if (!strstr(hd_errmsg(), "t.xml")) nomsg++;
            }
        }
    }
    printf("  corrupted files: %d loaded, %d refused\n", ok, failed);
    CHECK(nomsg == 0);
    CHECK(failed > 0);
}

/* Material numbers: an empty <Thickness> (wrapBSDF without t=) is absent,
 * a non-number is an error naming the element. */
static void test_material_numbers(void)
{
    char vals[4096];
    klems_values(vals, sizeof vals, 0);
    make("Columns", BASIS, DIR_TF, KB, vals);
    char *p = strstr(doc, ">4</Thickness>");
    REQUIRE(p);
    memmove(p + 1, p + 2, strlen(p + 2) + 1);      /* <Thickness ...></Thickness> */
    hd_status st;
    hd_bsdf *b = load_doc(&st);
    CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
    if (b) CHECK(hd_bsdf_get_info(b)->thickness == 0);
    hd_bsdf_free(b);
    make("Columns", BASIS, DIR_TF, KB, vals);
    p = strstr(doc, ">4</Thickness>");
    REQUIRE(p);
    p[1] = 'x';
    expect_error("thickness", "<Thickness>: expected a number", "'x'");
}

/* Energy conservation check: values of ~1000/sr violate T + R <= 1 on both
 * sides (the exterior block and its reciprocal); a dim file passes. */
static void test_energy_check(void)
{
    char vals[4096];
    klems_values(vals, sizeof vals, 0);
    make("Columns", BASIS, DIR_TF, KB, vals);
    hd_status st;
    hd_bsdf *b = load_doc(&st);
    REQUIRE(b);
    unsigned long w0 = hd_warning_count();
    double worst = 0;
    int n = hd_bsdf_check_energy(b, "t.xml", 0.05, 3, &worst);
    CHECK_MSG(n == 290, "%d violating directions, expected all 2 x 145", n);
    CHECK(worst > 100);
    CHECK(hd_warning_count() - w0 == 4);            /* 3 listed + the count */
    hd_bsdf_free(b);
    /* 0.05 /sr everywhere: T = 0.05 pi < 1 */
    size_t k = 0;
    for (int i = 0; i < 81; i++) k += (size_t)snprintf(vals + k, sizeof vals - k, "0.05 ");
    make("Columns", BASIS, DIR_TF, KB, vals);
    b = load_doc(&st);
    REQUIRE(b);
    w0 = hd_warning_count();
    CHECK(hd_bsdf_check_energy(b, "t.xml", 0.0, 3, &worst) == 0);
    CHECK_NEAR(worst, 0.05 * HD_PI, 1e-6);
    CHECK(hd_warning_count() == w0);
    hd_bsdf_free(b);
}

int main(void)
{
    (void)hd_test_ref;
    (void)hd_test_tmpdir;
    RUN(test_shirley_chiu);
    RUN(test_custom_basis_columns);
    RUN(test_rows_layout);
    RUN(test_tree4_order);
    RUN(test_malformed);
    RUN(test_ignored);
    RUN(test_mixed_bases);
    RUN(test_corruption);
    RUN(test_material_numbers);
    RUN(test_energy_check);
    return hd_test_done();
}

/* BSDF / aBSDF material helpers (Radiance m_bsdf semantics): thickness
 * proxy rules, transmitted-side origin, shadow rays, the aBSDF "through"
 * component of a synthetic peaked tree (exact expected values), data cell
 * sizes. */
#include <math.h>

#include "hd_test.h"
#include "heliodon/bsdf.h"
#include "heliodon/material.h"

/* Anisotropic tree, 8 cells per square side, Transmission Back (Radiance
 * tf: light from +z to -z): floor value everywhere, plus `peak` on the
 * straight-through diagonal (outgoing cell = incident cell). */
static hd_bsdf *make_tree(double floor_v, double peak)
{
    static char doc[1 << 17];
    size_t n = (size_t)snprintf(doc, sizeof doc,
        "<?xml version=\"1.0\"?>\n<WindowElement><Optical><Layer><Material><Name>diag</Name></Material>"
        "<DataDefinition><IncidentDataStructure>TensorTree4</IncidentDataStructure></DataDefinition>\n"
        "<WavelengthData><Wavelength>Visible</Wavelength><WavelengthDataBlock>"
        "<WavelengthDataDirection>Transmission Back</WavelengthDataDirection>"
        "<ScatteringData>{\n");
    for (int i0 = 0; i0 < 8; i0++)
        for (int i1 = 0; i1 < 8; i1++) {
            for (int i2 = 0; i2 < 8; i2++)
                for (int i3 = 0; i3 < 8; i3++) {
                    double v = floor_v + ((i0 == i2 && i1 == i3) ? peak : 0);
                    n += (size_t)snprintf(doc + n, sizeof doc - n, "%g ", v);
                }
            doc[n++] = '\n';
        }
    snprintf(doc + n, sizeof doc - n, "}</ScatteringData></WavelengthDataBlock></WavelengthData>"
             "</Layer></Optical></WindowElement>\n");
    hd_bsdf *b = NULL;
    if (hd_bsdf_load_memory(doc, strlen(doc), "diag.xml", &b) != HD_OK) {
        printf("  %s\n", hd_errmsg());
        return NULL;
    }
    return b;
}

static hd_vec3 dir_deg(double theta, double phi, double zsign)
{
    double t = theta * HD_PI / 180, p = phi * HD_PI / 180;
    return hd_v3(sin(t) * cos(p), sin(t) * sin(p), zsign * cos(t));
}

static void test_passes(void)
{
    hd_tmat m;
    hd_tmat_init(&m, HD_MAT_BSDF, "b");
    m.up = hd_v3(0, 1, 0);
    /* zero thickness: nothing passes */
    for (int k = 0; k < 3; k++)
        for (int f = 0; f < 2; f++) CHECK(!hd_tmat_bsdf_passes(&m, k, f));
    /* positive thickness hides the back: shadow and view rays always pass,
     * scattered rays interact only on the front */
    m.thick = 0.01;
    CHECK(hd_tmat_bsdf_passes(&m, HD_BSDF_RAY_SHADOW, 1) && hd_tmat_bsdf_passes(&m, HD_BSDF_RAY_SHADOW, 0));
    CHECK(hd_tmat_bsdf_passes(&m, HD_BSDF_RAY_VIEW, 1) && hd_tmat_bsdf_passes(&m, HD_BSDF_RAY_VIEW, 0));
    CHECK(!hd_tmat_bsdf_passes(&m, HD_BSDF_RAY_SCATTERED, 1));
    CHECK(hd_tmat_bsdf_passes(&m, HD_BSDF_RAY_SCATTERED, 0));
    m.thick = -0.01;
    CHECK(hd_tmat_bsdf_passes(&m, HD_BSDF_RAY_SCATTERED, 1));
    CHECK(!hd_tmat_bsdf_passes(&m, HD_BSDF_RAY_SCATTERED, 0));
    /* aBSDF has no thickness: never a proxy */
    m.absdf = 1;
    m.thick = 0.01;
    for (int k = 0; k < 3; k++)
        for (int f = 0; f < 2; f++) CHECK(!hd_tmat_bsdf_passes(&m, k, f));
    /* transmitted-side origin: p - thick * unit normal */
    m.absdf = 0;
    m.thick = 0.5;
    hd_vec3 o = hd_tmat_bsdf_through_origin(&m, hd_v3(1, 2, 3), hd_v3(0, 0, 2));
    CHECK_NEAR(o.x, 1, 1e-12);
    CHECK_NEAR(o.y, 2, 1e-12);
    CHECK_NEAR(o.z, 2.5, 1e-12);
    m.thick = -0.25;
    o = hd_tmat_bsdf_through_origin(&m, hd_v3(1, 2, 3), hd_v3(0, 0, 2));
    CHECK_NEAR(o.z, 3.25, 1e-12);
    m.thick = 0;
    o = hd_tmat_bsdf_through_origin(&m, hd_v3(1, 2, 3), hd_v3(0, 0, 2));
    CHECK_NEAR(o.z, 3, 1e-12);
    /* frame: z = n, x = up x z, y = z x x; up parallel to n is reported */
    hd_vec3 x, y, z;
    CHECK(hd_tmat_bsdf_frame(&m, hd_v3(0, 0, 3), &x, &y, &z) == 0);
    CHECK_NEAR(x.x, 1, 1e-12);
    CHECK_NEAR(y.y, 1, 1e-12);
    CHECK_NEAR(z.z, 1, 1e-12);
    CHECK(hd_tmat_bsdf_frame(&m, hd_v3(0, 2, 0), &x, &y, &z) == -1);
    CHECK_NEAR(hd_vdot(x, z), 0, 1e-12);
    CHECK_NEAR(hd_vdot(y, z), 0, 1e-12);
}

static void test_through(void)
{
    const double fl = 0.1, pk = 10;
    hd_bsdf *b = make_tree(fl, pk);
    REQUIRE(b);
    const double cell = HD_PI / 64;           /* projected solid angle of one cell */
    CHECK_NEAR(hd_bsdf_get_info(b)->min_proj_sa[HD_BSDF_TF], cell, 1e-9);
    /* the floor is split off as the Lambertian part (pi * 0.1) */
    CHECK_NEAR(hd_bsdf_get_info(b)->lambertian[HD_BSDF_TF], HD_PI * fl, 1e-6);
    hd_bsdf_through t;
    /* viewer on the +z side, 20 deg off the normal: the through cell is the
     * diagonal one; peak = (value - Lambertian/pi) * cell */
    hd_vec3 vo = dir_deg(20, 30, 1);
    CHECK(hd_bsdf_cell_psa(b, vo, hd_vneg(vo)) > 0);
    CHECK_NEAR(hd_bsdf_cell_psa(b, vo, hd_vneg(vo)), cell, 1e-9);
    REQUIRE(hd_bsdf_find_through(b, vo, &t) == 1);
    CHECK_NEAR(t.peak, pk * cell, 1e-5);
    CHECK_NEAR(t.surround, 0, 1e-6);
    CHECK(t.comp == HD_BSDF_TF);
    /* from the other side (reciprocal component tb): the same peak */
    hd_vec3 vb = dir_deg(35, 250, -1);
    REQUIRE(hd_bsdf_find_through(b, vb, &t) == 1);
    CHECK_NEAR(t.peak, pk * cell, 1e-5);
    CHECK(t.comp == HD_BSDF_TB);
    /* sources: straight behind -> surround + Lambertian/pi (the peak comes
     * through the unscattered ray); elsewhere f itself */
    REQUIRE(hd_bsdf_find_through(b, vo, &t) == 1);
    CHECK_NEAR(hd_bsdf_through_direct(b, &t, vo, hd_vneg(vo), 6.8e-5), fl, 1e-6);
    CHECK_NEAR(hd_bsdf_through_direct(b, NULL, vo, hd_vneg(vo), 6.8e-5), fl + pk, 1e-4);
    hd_vec3 far = dir_deg(70, 200, -1);
    CHECK_NEAR(hd_bsdf_through_direct(b, &t, vo, far, 6.8e-5), hd_bsdf_eval(b, far, vo), 1e-12);
    /* sample exclusion: only transmitted directions inside the peak */
    CHECK(hd_bsdf_through_excludes(&t, vo, hd_vneg(vo)));
    CHECK(!hd_bsdf_through_excludes(&t, vo, far));
    CHECK(!hd_bsdf_through_excludes(&t, vo, dir_deg(20, 210, 1)));
    CHECK(!hd_bsdf_through_excludes(NULL, vo, hd_vneg(vo)));

    /* as an aBSDF material (normal +z, up +y: local = world) */
    hd_tmat m;
    hd_tmat_init(&m, HD_MAT_BSDF, "a");
    m.absdf = 1;
    m.up = hd_v3(0, 1, 0);
    m.bsdf = b;
    double tr[3];
    /* a shadow ray travelling along -vo crosses with the peak */
    CHECK(hd_tmat_bsdf_shadow(&m, hd_v3(0, 0, 1), hd_vneg(vo), tr) == 1);
    CHECK_NEAR(tr[0], pk * cell, 1e-5);
    CHECK(tr[1] == tr[0] && tr[2] == tr[0]);
    CHECK(hd_tmat_bsdf_through(&m, hd_v3(0, 0, 1), hd_vneg(vo), &t) == 1);
    CHECK_NEAR(t.peak, pk * cell, 1e-5);
    /* a BSDF of zero thickness blocks shadow rays; with thickness they pass */
    m.absdf = 0;
    CHECK(hd_tmat_bsdf_shadow(&m, hd_v3(0, 0, 1), hd_vneg(vo), tr) == 0);
    CHECK(tr[0] == 0);
    CHECK(hd_tmat_bsdf_through(&m, hd_v3(0, 0, 1), hd_vneg(vo), &t) == 0);
    m.thick = 0.02;
    CHECK(hd_tmat_bsdf_shadow(&m, hd_v3(0, 0, 1), hd_vneg(vo), tr) == 1);
    CHECK(tr[0] == 1 && tr[1] == 1 && tr[2] == 1);
    hd_bsdf_free(b);

    /* no peak: a uniform transmission has no through component */
    b = make_tree(0.2, 0);
    REQUIRE(b);
    CHECK(hd_bsdf_find_through(b, vo, &t) == 0);
    CHECK(t.peak == 0);
    m.absdf = 1;
    m.thick = 0;
    m.bsdf = b;
    CHECK(hd_tmat_bsdf_shadow(&m, hd_v3(0, 0, 1), hd_vneg(vo), tr) == 0);
    hd_bsdf_free(b);
    /* Radiance's rule: the surround must be 8 times darker than the mean of
     * the peak cells: a diagonal 4x the floor is no peak, 11x is */
    b = make_tree(0.1, 0.3);
    REQUIRE(b);
    CHECK(hd_bsdf_find_through(b, vo, &t) == 0);
    hd_bsdf_free(b);
    b = make_tree(0.1, 1.0);
    REQUIRE(b);
    CHECK(hd_bsdf_find_through(b, vo, &t) == 1);
    CHECK_NEAR(t.peak, 1.0 * cell, 1e-5);
    CHECK_NEAR(t.surround, 0, 1e-6);
    hd_bsdf_free(b);
}

/* clear glazing (Klems): the straight-through bin carries the whole
 * transmission; cell sizes are Klems bin projected solid angles */
static void test_through_ref(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder");
    char path[1024];
    snprintf(path, sizeof path, "%s/bsdf/glazing/glazing_klems.xml", ref);
    hd_bsdf *b = NULL;
    REQUIRE(hd_bsdf_load(path, &b) == HD_OK);
    hd_bsdf_through t;
    for (int side = 0; side < 2; side++) {
        hd_vec3 vo = dir_deg(0.5, 0, side ? -1 : 1);
        REQUIRE(hd_bsdf_find_through(b, vo, &t) == 1);
        double T = hd_bsdf_hemi(b, hd_vneg(vo), HD_BSDF_TRANS);
        printf("  glazing through peak %.4f, hemispherical T %.4f (side %d)\n", t.peak, T, side);
        CHECK_REL(t.peak, T, 0.01);
    }
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    hd_vec3 vi = hd_bsdf_klems_in_dir(&kb, HD_BSDF_TB, 20, 0.5, 0.5);
    hd_vec3 vo = hd_bsdf_klems_out_dir(&kb, HD_BSDF_TB, 140, 0.5, 0.5);
    double l1 = hd_klems_lambda(&kb, 20), l2 = hd_klems_lambda(&kb, 140);
    CHECK_NEAR(hd_bsdf_cell_psa(b, vi, vo), l1 < l2 ? l1 : l2, 1e-9);
    hd_bsdf_free(b);

    /* tensor tree: every cell is pi/4^k, the smallest is the file's finest */
    snprintf(path, sizeof path, "%s/bsdf/cfs3/cfs3_ttree.xml", ref);
    REQUIRE(hd_bsdf_load(path, &b) == HD_OK);
    double mn = HUGE_VAL;
    int bad = 0;
    for (int i = 0; i < 400; i++) {
        hd_vec3 a = dir_deg(1 + (i % 20) * 4.4, (i / 20) * 18.0, 1);
        hd_vec3 o = dir_deg(3 + (i % 17) * 5, (i % 23) * 15.0, -1);
        double p = hd_bsdf_cell_psa(b, a, o);
        double k = log(HD_PI / p) / log(4);
        if (fabs(k - floor(k + 0.5)) > 1e-9) bad++;
        if (p < mn) mn = p;
    }
    CHECK(bad == 0);
    CHECK(mn >= hd_bsdf_get_info(b)->min_proj_sa[HD_BSDF_TF] - 1e-12);
    hd_bsdf_free(b);
}

/* The width of the view jitter at a tree (hd_bsdf_view_psa): π w² of the
 * finest cell of the distribution sampled from the view vector, as
 * Radiance's SDsizeBSDF minimum, not the cell holding (vo, -vo).  A
 * TensorTree4 of 2⁴ cells whose one child with dims 0, 1 in the lower and
 * dims 2, 3 in the upper half is split once more: Radiance 6.1's
 * SDsizeBSDF (its library called on the same XML) gives π/16 at azimuth
 * 45° (θ 40°, either side) and π/4 at 135°, 225°, 315°; the cell at the
 * straight-through pair is π/4 at all four. */
static void test_view_psa(void)
{
    static char doc[8192];
    size_t n = (size_t)snprintf(doc, sizeof doc,
        "<?xml version=\"1.0\"?>\n<WindowElement><Optical><Layer><Material><Name>q</Name></Material>"
        "<DataDefinition><IncidentDataStructure>TensorTree4</IncidentDataStructure></DataDefinition>\n"
        "<WavelengthData><Wavelength>Visible</Wavelength><WavelengthDataBlock>"
        "<WavelengthDataDirection>Transmission Back</WavelengthDataDirection>"
        "<AngleBasis>LBNL/Shirley-Chiu</AngleBasis><ScatteringDataType>BTDF</ScatteringDataType>"
        "<ScatteringData>{ ");
    for (int c = 0; c < 16; c++)
        n += (size_t)snprintf(doc + n, sizeof doc - n, "%s", c == 12 ? "{ 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 } " : "{ 1 } ");
    snprintf(doc + n, sizeof doc - n, "}</ScatteringData></WavelengthDataBlock></WavelengthData>"
             "</Layer></Optical></WindowElement>\n");
    hd_bsdf *b = NULL;
    CHECK(hd_bsdf_load_memory(doc, strlen(doc), "q.xml", &b) == HD_OK);
    if (!b) return;
    for (int side = -1; side <= 1; side += 2)
        for (int az = 45; az < 360; az += 90) {
            hd_vec3 v = dir_deg(40, az, side);
            double want = az == 45 ? HD_PI / 16 : HD_PI / 4;
            double pmax = 0;
            CHECK_NEAR(hd_bsdf_view_psa(b, NULL, v, &pmax), want, 1e-12);
            CHECK_NEAR(pmax, HD_PI / 4, 1e-12);
            CHECK_NEAR(hd_bsdf_cell_psa(b, v, hd_vneg(v)), HD_PI / 4, 1e-12);
        }
    hd_bsdf_free(b);
}

/* hd_bsdf_eval_comp_psa: the value of hd_bsdf_eval_comp and the cell of hd_bsdf_cell_psa from
 * one lookup, the same figures for Klems data and two 4-D tensor trees, in every component */
static void test_eval_psa(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder");
    static const char *const f[] = {"glazing/glazing_klems", "cfs3/cfs3_ttree", "cfs1/cfs1_ttree"};
    for (int k = 0; k < 3; k++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/bsdf/%s.xml", ref, f[k]);
        hd_bsdf *b = NULL;
        REQUIRE(hd_bsdf_load(path, &b) == HD_OK);
        int bad_v = 0, bad_p = 0, cells = 0;
        for (int i = 0; i < 4000; i++) {
            int c = i % 4;   /* rf rb tf tb: the sides of in and out */
            double si = c == HD_BSDF_RF || c == HD_BSDF_TF ? 1 : -1;
            double so = c == HD_BSDF_RF || c == HD_BSDF_TB ? 1 : -1;
            hd_vec3 a = dir_deg(0.3 + (i * 7 % 89), (i * 37 % 360) + 0.25, si);
            hd_vec3 o = dir_deg(0.7 + (i * 13 % 89), (i * 101 % 360) + 0.5, so);
            double psa = -1, v = hd_bsdf_eval_comp_psa(b, (hd_bsdf_comp)c, a, o, i & 1, &psa);
            if (v != hd_bsdf_eval_comp(b, (hd_bsdf_comp)c, a, o, i & 1)) bad_v++;
            double p = hd_bsdf_cell_psa(b, a, o);
            if (fabs(psa - p) > 1e-12 * p) bad_p++;
            cells += p > 0;
        }
        printf("  %s: 4000 pairs, %d in data cells; values differ %d, cells differ %d\n", f[k], cells, bad_v, bad_p);
        CHECK(cells > 1000);
        CHECK(bad_v == 0);
        CHECK(bad_p == 0);
        hd_bsdf_free(b);
    }
}

int main(void)
{
    (void)hd_test_tmpdir;
    RUN(test_passes);
    RUN(test_through);
    RUN(test_through_ref);
    RUN(test_view_psa);
    RUN(test_eval_psa);
    return hd_test_done();
}

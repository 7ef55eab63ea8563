/* Unit tests: the shared scattering rules (scatter.c) — photon lobe choice
 * is unbiased for every material, BSDF forward sampling through a port,
 * energy bookkeeping of photon maps through BSDF data, shadow
 * transmission, ray admission. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hd_test.h"
#include "hd_test_scene.h"
#include "heliodon/bsdf.h"
#include "heliodon/pmap.h"
#include "heliodon/rng.h"
#include "scatter.h"
#include "heliodon/scene.h"
#include "heliodon/trace.h"

/* A Klems-full XML: Transmission Front (exterior -> interior) Lambertian
 * tau, and Reflection Front (exterior side) Lambertian rho (if > 0). */
static const char *klems_xml(const char *name, double tau, double rho)
{
    static char path[512];
    snprintf(path, sizeof path, "%s/%s", hd_test_tmpdir(), name);
    FILE *fp = fopen(path, "w");
    if (!fp) return NULL;
    static const double th[] = {0, 10, 20, 30, 40, 50, 60, 70, 82.5}, tb[] = {0, 5, 15, 25, 35, 45, 55, 65, 75, 90};
    static const int np[] = {1, 8, 16, 20, 24, 24, 24, 16, 12};
    int n = 0;
    fprintf(fp, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<WindowElement xmlns=\"http://windows.lbl.gov\">\n"
                "<WindowElementType>System</WindowElementType><FileType>BSDF</FileType>\n"
                "<Optical><Layer><Material><Name>t</Name><Manufacturer>t</Manufacturer>"
                "<Thickness unit=\"Millimeter\">1</Thickness></Material>\n"
                "<DataDefinition><IncidentDataStructure>Columns</IncidentDataStructure>\n"
                "<AngleBasis><AngleBasisName>LBNL/Klems Full</AngleBasisName>\n");
    for (int i = 0; i < 9; i++) {
        fprintf(fp, "<AngleBasisBlock><Theta>%g</Theta><nPhis>%d</nPhis><ThetaBounds><LowerTheta>%g</LowerTheta>"
                    "<UpperTheta>%g</UpperTheta></ThetaBounds></AngleBasisBlock>\n", th[i], np[i], tb[i], tb[i + 1]);
        n += np[i];
    }
    fprintf(fp, "</AngleBasis></DataDefinition>\n");
    for (int blk = 0; blk < 2; blk++) {
        double v = (blk ? rho : tau) / HD_PI;
        if (blk && rho <= 0) break;
        fprintf(fp, "<WavelengthData><LayerNumber>System</LayerNumber><Wavelength unit=\"Integral\">Visible</Wavelength>\n"
                    "<WavelengthDataBlock><WavelengthDataDirection>%s</WavelengthDataDirection>\n"
                    "<ColumnAngleBasis>LBNL/Klems Full</ColumnAngleBasis><RowAngleBasis>LBNL/Klems Full</RowAngleBasis>\n"
                    "<ScatteringDataType>%s</ScatteringDataType><ScatteringData>\n",
                blk ? "Reflection Front" : "Transmission Front", blk ? "BRDF" : "BTDF");
        for (int r = 0; r < n; r++) {
            for (int c = 0; c < n; c++) fprintf(fp, "%.6f ", v);
            fputc('\n', fp);
        }
        fprintf(fp, "</ScatteringData></WavelengthDataBlock></WavelengthData>\n");
    }
    fprintf(fp, "</Layer></Optical></WindowElement>\n");
    fclose(fp);
    return path;
}

#define load_ts(text) hd_test_tscene((text), "scatter")

static double avg3(const double *v) { return (v[0] + v[1] + v[2]) / 3; }

/* E[survival × mean(fac)] over many photon events = the total albedo of the
 * lobes for that incidence (the photon lobe choice is unbiased). */
static double photon_albedo(const hd_scatter *sc, hd_scatter_cache *cache, int n, double *sd)
{
    hd_rng r;
    hd_rng_init(&r, 3, 0);
    double s = 0, s2 = 0;
    for (int i = 0; i < n; i++) {
        hd_vec3 nd;
        double fac[3];
        double u = hd_rng_uniform(&r);
        hd_scevent ev = hd_scatter_photon(sc, cache, u, &r, &nd, fac);
        double x = ev == HD_SCE_ABSORB ? 0 : avg3(fac);
        s += x;
        s2 += x * x;
    }
    s /= n;
    *sd = sqrt(fmax(0, s2 / n - s * s) / n);
    return s;
}

static void test_photon_lobes_unbiased(void)
{
    const char *xml = klems_xml("sc_lam.xml", 0.4, 0.1);
    REQUIRE(xml);
    char text[2048];
    snprintf(text, sizeof text,
             "void plastic pl 0 0 5 .6 .4 .2 .05 .1\n"
             "void trans tr 0 0 7 .7 .7 .7 .03 0 .5 .3\n"
             "void metal mt 0 0 5 .8 .6 .5 .9 .05\n"
             "void glass gl 0 0 3 .9 .85 .8\n"
             "void mirror mi 0 0 3 .9 .8 .7\n"
             "void BSDF bs 6 0 %s 0 1 0 . 0 9 .1 .1 .1 .2 .2 .2 .15 .15 .15\n"
             "pl polygon p0 0 0 12 0 0 0 1 0 0 1 1 0 0 1 0\n"
             "tr polygon p1 0 0 12 0 0 0 1 0 0 1 1 0 0 1 0\n"
             "mt polygon p2 0 0 12 0 0 0 1 0 0 1 1 0 0 1 0\n"
             "gl polygon p3 0 0 12 0 0 0 1 0 0 1 1 0 0 1 0\n"
             "mi polygon p4 0 0 12 0 0 0 1 0 0 1 1 0 0 1 0\n"
             "bs polygon p5 0 0 12 0 0 0 0 1 0 1 1 0 1 0 0\n", xml);
    hd_tscene *ts = load_ts(text);
    REQUIRE(ts);
    hd_scatter_cache *cache = hd_scatter_cache_new();
    hd_vec3 d = hd_vnorm(hd_v3(0.3, 0.2, -1));   /* travelling down onto the +z faces */
    for (int k = 0; k < 6; k++) {
        hd_hit h;
        memset(&h, 0, sizeof h);
        h.surf = k;
        h.p = hd_v3(0.5, 0.5, 0);
        h.n = hd_tscene_surface(ts, k)->n;
        h.front = hd_vdot(d, h.n) < 0;
        hd_scatter sc;
        hd_scatter_at(ts, &h, d, 0, &sc);
        double expect = 0;
        switch (sc.kind) {
        case HD_SC_NORMAL:
            expect = avg3(sc.ns.rdiff) + avg3(sc.ns.scol) + avg3(sc.ns.tdiff) + avg3(sc.ns.tscol);
            break;
        case HD_SC_GLASS: expect = avg3(sc.R) + avg3(sc.T); break;
        case HD_SC_MIRROR: expect = avg3(sc.m->color); break;
        case HD_SC_BSDF: {
            /* the polygon's normal points down: the photon arrives on the
             * data's back (exterior) side: extra back reflection .2 + extra
             * diffuse transmission .15 + the data (T .4 + the file's
             * "Reflection Front" .1, which is Radiance's back reflection) */
            CHECK(!sc.bfront);
            expect = avg3(sc.rdx) + avg3(sc.tdx) + hd_bsdf_hemi(sc.m->bsdf, sc.vo, HD_BSDF_ALL);
            CHECK_NEAR(expect, 0.85, 0.01);
            break;
        }
        default:
            CHECK_MSG(0, "surface %d: unexpected kind %d", k, (int)sc.kind);
            continue;
        }
        double sd, got = photon_albedo(&sc, cache, 200000, &sd);
        CHECK_MSG(fabs(got - expect) < 4 * sd + 1e-9, "surface %d (%s): photon albedo %g vs lobes %g (sd %g)", k,
                  sc.m->name, got, expect, sd);
    }
    /* from the front (interior) side: no front reflection data, the
     * transmission .4 by reciprocity, extra front reflection .1, extra
     * diffuse transmission .15 */
    {
        hd_hit h;
        memset(&h, 0, sizeof h);
        h.surf = 5;
        h.p = hd_v3(0.5, 0.5, 0);
        h.n = hd_tscene_surface(ts, 5)->n;
        hd_vec3 du = hd_vneg(d);   /* travelling up: arrives on the front (+z of the data = down) */
        h.front = hd_vdot(du, h.n) < 0;
        hd_scatter sc;
        hd_scatter_at(ts, &h, du, 0, &sc);
        CHECK(sc.kind == HD_SC_BSDF && sc.bfront);
        double expect = avg3(sc.rdx) + avg3(sc.tdx) + hd_bsdf_hemi(sc.m->bsdf, sc.vo, HD_BSDF_ALL);
        CHECK_NEAR(expect, 0.65, 0.01);
        double sd, got = photon_albedo(&sc, cache, 200000, &sd);
        CHECK_MSG(fabs(got - expect) < 4 * sd + 1e-9, "BSDF front: photon albedo %g vs lobes %g (sd %g)", got, expect, sd);
    }
    hd_scatter_cache_free(cache);
    hd_tscene_free(ts);
}

/* BSDF forward sampling of a photon: directions into the other side,
 * cosine distributed for the Lambertian data (mean cos 2/3). */
static void test_bsdf_forward_directions(void)
{
    const char *xml = klems_xml("sc_lam2.xml", 0.5, 0);
    REQUIRE(xml);
    char text[1024];
    snprintf(text, sizeof text, "void BSDF bs 6 0 %s 0 1 0 . 0 0\n"
                                "bs polygon p 0 0 12 0 0 0 0 1 0 1 1 0 1 0 0\n", xml);
    hd_tscene *ts = load_ts(text);
    REQUIRE(ts);
    hd_hit h;
    memset(&h, 0, sizeof h);
    h.surf = 0;
    h.n = hd_tscene_surface(ts, 0)->n;
    CHECK_NEAR(h.n.z, -1, 1e-12);
    hd_vec3 d = hd_vnorm(hd_v3(0.5, 0, -1));
    h.front = hd_vdot(d, h.n) < 0;
    hd_scatter sc;
    hd_scatter_at(ts, &h, d, HD_SC_ILLUM_ANYALT, &sc);
    hd_rng r;
    hd_rng_init(&r, 5, 0);
    int n = 100000, down = 0, bsdf = 0;
    double sumc = 0;
    for (int i = 0; i < n; i++) {
        hd_vec3 nd;
        double fac[3];
        hd_scevent ev = hd_scatter_photon(&sc, NULL, hd_rng_uniform(&r), &r, &nd, fac);
        if (ev != HD_SCE_BSDF) continue;
        bsdf++;
        CHECK_NEAR(fac[0], 1, 1e-12);
        if (nd.z < 0) down++;
        sumc += fabs(nd.z);
    }
    CHECK_NEAR((double)bsdf / n, 0.5, 0.01);
    CHECK(down == bsdf);
    CHECK_NEAR(sumc / bsdf, 2.0 / 3.0, 0.01);
    hd_tscene_free(ts);
}

/* Photon maps through a BSDF port: per source, absorbed + escaped + lost =
 * emitted, and the stored flux on the floor of the analytic box equals
 * tau × the flux through the port × the port-to-floor view factor share
 * (checked against the photon count instead: stored > 0). */
static void test_pmap_energy_bsdf(void)
{
    const char *xml = klems_xml("sc_lam3.xml", 0.5, 0.2);
    REQUIRE(xml);
    char text[4096];
    snprintf(text, sizeof text,
             "void plastic black 0 0 5 0 0 0 0 0\n"
             "void plastic floormat 0 0 5 .6 .6 .6 0 0\n"
             "void BSDF diff 6 0 %s 0 1 0 . 0 0\n"
             "void light solar1 0 0 3 1 1 1\n"
             "solar1 source sun1 0 0 4 0.2 0 1 0.533\n"
             "void light solar2 0 0 3 1 1 1\n"
             "solar2 source sun2 0 0 4 0 0.4 1 0.533\n"
             "floormat polygon floor 0 0 12 0 0 0 1 0 0 1 1 0 0 1 0\n"
             "black polygon w1 0 0 12 0 0 0 0 0 1 1 0 1 1 0 0\n"
             "black polygon w2 0 0 12 1 0 0 1 0 1 1 1 1 1 1 0\n"
             "floormat polygon w3 0 0 12 1 1 0 1 1 1 0 1 1 0 1 0\n"
             "black polygon w4 0 0 12 0 1 0 0 1 1 0 0 1 0 0 0\n"
             "black polygon r1 0 0 12 0 0 1 1 0 1 1 .25 1 0 .25 1\n"
             "black polygon r2 0 0 12 0 .75 1 1 .75 1 1 1 1 0 1 1\n"
             "black polygon r3 0 0 12 0 .25 1 .25 .25 1 .25 .75 1 0 .75 1\n"
             "black polygon r4 0 0 12 .75 .25 1 1 .25 1 1 .75 1 .75 .75 1\n"
             "diff polygon port 0 0 12 .25 .25 1 .25 .75 1 .75 .75 1 .75 .25 1\n", xml);
    hd_tscene *ts = load_ts(text);
    REQUIRE(ts);
    hd_pmap_build_opts o;
    hd_test_port_opts(&o, "diff");
    o.nphotons = 40000;
    o.nthreads = 2;
    hd_pmap_energy *E = NULL;
    hd_pmap_build_stats st;
    char path[512];
    snprintf(path, sizeof path, "%s/sc_energy.pm", hd_test_tmpdir());
    REQUIRE(hd_pmap_build(ts, &o, path, NULL, &st, &E) == HD_OK);
    REQUIRE(E);
    for (int s = 0; s < 2; s++) {
        double sum = E[s].absorbed + E[s].escaped + E[s].lost;
        printf("  source %d: emitted %.6g absorbed %.6g escaped %.6g lost %.6g stored %.6g\n", s, E[s].emitted,
               E[s].absorbed, E[s].escaped, E[s].lost, E[s].stored);
        CHECK_REL(sum, E[s].emitted, 1e-9);
        CHECK(E[s].stored > 0 && E[s].absorbed > 0 && E[s].escaped > 0);
        /* the port absorbs 1 - 0.5 - 0.2 of what crosses it from outside
         * (Lambertian data: the same for every incidence), the rest goes
         * in (0.5) or back out (0.2, escapes): escaped >= 0.2 emitted */
        CHECK(E[s].escaped >= 0.19 * E[s].emitted);
        CHECK(E[s].absorbed >= 0.29 * E[s].emitted);
    }
    CHECK_MSG(fabs((double)st.stored / 40000.0 - 1) < 0.05, "stored %llu for 40000 asked",
              (unsigned long long)st.stored);
    free(E);
    hd_tscene_free(ts);
}

/* Shadow rays: glass transmits its transmittance, opaque blocks, BSDF blocks
 * (its light is evaluated at the BSDF surface), strict distant targets. */
static void test_shadow(void)
{
    hd_tscene *ts = load_ts("void glass gl 0 0 3 .9 .9 .9\n"
                            "void plastic op 0 0 5 .5 .5 .5 0 0\n"
                            "void light sl 0 0 3 1 1 1\n"
                            "sl source sun 0 0 4 0 0 1 0.5\n"
                            "sl source sun2 0 0 4 0 0 1 20\n"
                            "gl polygon g 0 0 12 -1 -1 1 1 -1 1 1 1 1 -1 1 1\n"
                            "op polygon o 0 0 12 2 -1 1 4 -1 1 4 1 1 2 1 1\n");
    REQUIRE(ts);
    double tr[3], R[3], T[3];
    hd_glass_coeffs((double[3]){.9, .9, .9}, 1.52, 1, R, T);
    int sun = -1;
    for (int i = 0; i < hd_tscene_nsurfaces(ts); i++)
        if (hd_tscene_surface(ts, i)->kind == HD_SURF_SOURCE && sun < 0) sun = i;
    REQUIRE(sun >= 0);
    CHECK(hd_scatter_shadow(ts, hd_v3(0, 0, 0), hd_v3(0, 0, 1), 0, sun, 0, tr) == 1);
    CHECK_REL(tr[0], T[0], 1e-9);
    CHECK(hd_scatter_shadow(ts, hd_v3(3, 0, 0), hd_v3(0, 0, 1), 0, sun, 0, tr) == 0);
    CHECK(hd_scatter_shadow(ts, hd_v3(10, 0, 0), hd_v3(0, 0, 1), 0, sun, 0, tr) == 1);
    hd_tscene_free(ts);
}

/* sin/cos of 2 pi u without libm: within 2e-15 of libm's sin(2 pi u) on a fine grid
 * (the rounding of 2 pi u itself is up to ~9e-16 near u = 1),
 * at the quadrant boundaries and the ends of [0, 1); outside [0, 1) the
 * fractional part is used */
static void test_sincos2pi(void)
{
    double worst = 0;
    for (int i = 0; i <= 400000; i++) {
        double u = i < 400000 ? i / 400000.0 : 1 - 0x1p-53, s, c;
        hd_scatter_sincos2pi(u, &s, &c);
        double es = fabs(s - sin(2 * HD_PI * u)), ec = fabs(c - cos(2 * HD_PI * u));
        if (es > worst) worst = es;
        if (ec > worst) worst = ec;
    }
    printf("  sincos2pi: max abs error %.2e\n", worst);
    CHECK(worst < 2e-15);
    double s, c;
    hd_scatter_sincos2pi(0.25, &s, &c);
    CHECK_NEAR(s, 1, 1e-16);
    CHECK_NEAR(c, 0, 1e-16);
    hd_scatter_sincos2pi(1.375, &s, &c);   /* = 0.375 */
    CHECK_NEAR(s, sin(0.75 * HD_PI), 4e-16);
    CHECK_NEAR(c, cos(0.75 * HD_PI), 4e-16);
    hd_scatter_sincos2pi(-0.125, &s, &c);  /* = 0.875 */
    CHECK_NEAR(s, -sqrt(0.5), 4e-16);
    CHECK_NEAR(c, sqrt(0.5), 4e-16);
}

/* Radiance's admission: above -lw the factor is 1; below with -lr <= 0
 * the expected factor is 1 (Russian roulette); with -lr > 0 it is 0. */
static void test_admit(void)
{
    hd_rng r;
    hd_rng_init(&r, 1, 0);
    double w = 0.5;
    CHECK(hd_scatter_admit(0.01, -10, &w, &r) == 1 && w == 0.5);
    double s = 0;
    int n = 200000;
    for (int i = 0; i < n; i++) {
        w = 0.002;
        s += hd_scatter_admit(0.01, -10, &w, &r);
    }
    CHECK_NEAR(s / n, 1, 0.03);
    w = 0.002;
    CHECK(hd_scatter_admit(0.01, 10, &w, &r) == 0);
}

int main(void)
{
    RUN(test_photon_lobes_unbiased);
    RUN(test_bsdf_forward_directions);
    RUN(test_pmap_energy_bsdf);
    RUN(test_shadow);
    RUN(test_admit);
    RUN(test_sincos2pi);
    return hd_test_done();
}

/* Unit tests of genBSDF (BSDF generation from geometry). */
#include "hd_test.h"

#include "heliodon/bsdf.h"
#include "heliodon/genbsdf.h"
#include "heliodon/material.h"
#include "heliodon/scene.h"

/* A closed lossless dielectric slab, 4 mm thick (z = -4 .. 0 - gap),
 * 2 m wide, outward normals. */
static const char *SLAB =
    "void dielectric clear 0 0 5 1 1 1 1.52 0\n"
    "clear polygon bottom 0 0 12  -1000 -1000 -4.5  -1000 1000 -4.5  1000 1000 -4.5  1000 -1000 -4.5\n"
    "clear polygon top 0 0 12  -1000 -1000 -0.5  1000 -1000 -0.5  1000 1000 -0.5  -1000 1000 -0.5\n"
    "clear polygon s1 0 0 12  -1000 -1000 -4.5  1000 -1000 -4.5  1000 -1000 -0.5  -1000 -1000 -0.5\n"
    "clear polygon s2 0 0 12  -1000 1000 -4.5  -1000 1000 -0.5  1000 1000 -0.5  1000 1000 -4.5\n"
    "clear polygon s3 0 0 12  -1000 -1000 -4.5  -1000 -1000 -0.5  -1000 1000 -0.5  -1000 1000 -4.5\n"
    "clear polygon s4 0 0 12  1000 -1000 -4.5  1000 1000 -4.5  1000 1000 -0.5  1000 -1000 -0.5\n";

static hd_status make_system(const char *text, hd_genbsdf_opts *o, hd_gbsystem **g)
{
    hd_scene sc;
    hd_scene_init(&sc);
    hd_status st = hd_scene_load_string(&sc, text, "test.rad", NULL);
    if (st == HD_OK) st = hd_gbsystem_create(g, &sc, o);
    hd_scene_free(&sc);
    return st;
}

static void set_dim(hd_genbsdf_opts *o, double z0, double z1)
{
    double d[6] = {-50, 50, -50, 50, z0, z1};
    memcpy(o->dim, d, sizeof d);
    o->have_dim = 1;
}

/* unpolarised Fresnel reflectance of an air-glass interface at incidence th */
static double fresnel_R(double th, double n)
{
    double ci = cos(th), si = sin(th), st = si / n, ct = sqrt(1 - st * st);
    double rs = (ci - n * ct) / (ci + n * ct), rp = (ct - n * ci) / (ct + n * ci);
    return 0.5 * (rs * rs + rp * rp);
}

/* transmittance of a lossless slab (incoherent multiple reflections) with
 * the unpolarised reflectance R at each interface, as Radiance's
 * dielectric computes it: (1-R)^2 sum_k R^2k over the paths with at most
 * maxrefl reflections (maxrefl < 0: all, (1-R)/(1+R)) */
static double slab_T(double th, double n, int maxrefl)
{
    double R = fresnel_R(th, n);
    if (maxrefl < 0) return (1 - R) / (1 + R);
    double s = 0, p = 1;
    for (int k = 0; 2 * k <= maxrefl; k++, p *= R * R) s += p;
    return (1 - R) * (1 - R) * s;
}

/* projected-solid-angle average of f over the ring [t0, t1] (degrees) */
static double ring_avg(double (*f)(double th, const void *arg), const void *arg, double t0, double t1)
{
    double s = 0, w = 0;
    for (int k = 0; k < 4000; k++) {
        double th = (t0 + (t1 - t0) * (k + 0.5) / 4000) * M_PI / 180;
        double q = cos(th) * sin(th);
        s += f(th, arg) * q;
        w += q;
    }
    return s / w;
}

static double slab_f(double th, const void *arg) { return slab_T(th, 1.52, *(const int *)arg); }

static double slab_T_ring(double t0, double t1, double n)
{
    (void)n;
    int all = -1;
    return ring_avg(slab_f, &all, t0, t1);
}

static void test_fresnel_slab(void)
{
    hd_genbsdf_opts o;
    hd_genbsdf_defaults(&o);
    set_dim(&o, -5, 0);
    o.nsamp = 20000;
    o.nthreads = 2;
    hd_gbsystem *g = NULL;
    REQUIRE(make_system(SLAB, &o, &g) == HD_OK);
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    size_t n = (size_t)kb.nbins * kb.nbins;
    double *T = calloc(n, sizeof *T), *R = calloc(n, sizeof *R);
    REQUIRE(T && R);
    CHECK(hd_genbsdf_klems(g, &o, HD_GB_FROM_EXTERIOR, &kb, T, R) == HD_OK);
    /* normal incidence: bin 0 (0..5 deg); 60 deg: first bin of ring 6 (55..65 deg) */
    double t0 = hd_genbsdf_klems_hemi(&kb, T, 0);
    int b60 = kb.ring[6].first;
    double t60 = hd_genbsdf_klems_hemi(&kb, T, b60);
    printf("  slab T: normal %.4f (Fresnel %.4f), 60 deg %.4f (Fresnel %.4f)\n", t0, slab_T_ring(0, 5, 1.52),
           t60, slab_T_ring(55, 65, 1.52));
    /* both Fresnel branches are followed: only the directions within the
     * patch are sampled */
    CHECK_REL(t0, slab_T_ring(0, 5, 1.52), 2e-4);
    CHECK_REL(t60, slab_T_ring(55, 65, 1.52), 2e-4);
    /* reflection + transmission = 1 (no absorption) */
    CHECK_NEAR(t60 + hd_genbsdf_klems_hemi(&kb, R, b60), 1.0, 1e-4);
    /* specular: the normal-incidence light leaves in the normal bin */
    CHECK_REL(T[0] * hd_klems_lambda(&kb, 0), t0, 1e-6);
    /* the room side gives the same by symmetry */
    double *T2 = calloc(n, sizeof *T2);
    REQUIRE(T2);
    CHECK(hd_genbsdf_klems(g, &o, HD_GB_FROM_ROOM, &kb, T2, NULL) == HD_OK);
    CHECK_REL(hd_genbsdf_klems_hemi(&kb, T2, b60), slab_T_ring(55, 65, 1.52), 2e-4);
    free(T); free(R); free(T2);
    hd_gbsystem_free(g);
}

/* -lr as Radiance's rayorigin(): a slab with -lr 1 transmits only the
 * paths with at most 1 reflection, (1-R)^2; -lr 0 (roulette only) all of
 * them, -lr -10 those with at most 10 */
static void test_reflection_limit(void)
{
    hd_genbsdf_opts o;
    hd_genbsdf_defaults(&o);
    set_dim(&o, -5, 0);
    o.nsamp = 400;
    hd_gbsystem *g = NULL;
    REQUIRE(make_system(SLAB, &o, &g) == HD_OK);
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    size_t n = (size_t)kb.nbins * kb.nbins;
    double *T = calloc(n, sizeof *T);
    REQUIRE(T);
    int b = kb.ring[7].first;   /* 65..75 deg */
    int lim[3] = {1, 0, -10};
    for (int k = 0; k < 3; k++) {
        o.lr = lim[k];
        CHECK(hd_genbsdf_klems(g, &o, HD_GB_FROM_EXTERIOR, &kb, T, NULL) == HD_OK);
        int mr = lim[k] == 1 ? 1 : lim[k] == -10 ? 10 : -1;
        double want = ring_avg(slab_f, &mr, 65, 75);
        printf("  slab T 65-75 deg, -lr %d: %.5f (expected %.5f)\n", lim[k], hd_genbsdf_klems_hemi(&kb, T, b), want);
        /* the tolerance is the sampling of directions within the patch */
        CHECK_REL(hd_genbsdf_klems_hemi(&kb, T, b), want, 3e-4);
    }
    /* the limit matters here: at most 1 reflection is visibly less */
    int one = 1, all = -1;
    CHECK(ring_avg(slab_f, &all, 65, 75) - ring_avg(slab_f, &one, 65, 75) > 0.02);
    free(T);
    hd_gbsystem_free(g);
}

/* glass: both branches are followed with their weights (as Radiance's
 * glass material does), so a pane's transmittance per patch has no
 * sampling noise from choosing between them; at 400 samples a random
 * choice would be off by about 2.5 % (binomial) */
static double glass_f(double th, const void *arg)
{
    (void)arg;
    double tn[3] = {0.96, 0.96, 0.96}, r[3], t[3];
    hd_glass_coeffs(tn, 1.52, cos(th), r, t);
    return t[1];
}

static void test_glass_split(void)
{
    hd_genbsdf_opts o;
    hd_genbsdf_defaults(&o);
    set_dim(&o, -5, 0);
    o.nsamp = 400;
    const char *pane =
        "void glass clear 0 0 3 0.96 0.96 0.96\n"
        "clear polygon p 0 0 12  -1000 -1000 -2  1000 -1000 -2  1000 1000 -2  -1000 1000 -2\n";
    hd_gbsystem *g = NULL;
    REQUIRE(make_system(pane, &o, &g) == HD_OK);
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    size_t n = (size_t)kb.nbins * kb.nbins;
    double *T = calloc(n, sizeof *T);
    REQUIRE(T);
    CHECK(hd_genbsdf_klems(g, &o, HD_GB_FROM_EXTERIOR, &kb, T, NULL) == HD_OK);
    double mx = 0, mx8 = 0;
    for (int r = 0; r < kb.nrings; r++) {
        double want = ring_avg(glass_f, NULL, kb.ring[r].theta_lo, kb.ring[r].theta_hi);
        for (int c = 0; c < kb.ring[r].nphi; c++) {
            double e = fabs(hd_genbsdf_klems_hemi(&kb, T, kb.ring[r].first + c) / want - 1);
            if (r < kb.nrings - 1 && e > mx) mx = e;
            if (r == kb.nrings - 1 && e > mx8) mx8 = e;
        }
    }
    printf("  glass pane, 400 samples: largest relative error per patch %.2e (grazing ring %.2e)\n", mx, mx8);
    /* the remaining error is the sampling of directions within a patch,
     * largest in the grazing ring where T falls from 0.6 to 0 */
    CHECK_MSG(mx < 3e-4, "largest relative error %g", mx);
    CHECK_MSG(mx8 < 3e-3, "largest relative error in the grazing ring %g", mx8);
    free(T);
    hd_gbsystem_free(g);
}

/* the sample origins are stratified over the -dim rectangle: an opaque
 * half-plane x < 0 just behind the sender plane passes exactly half of the
 * near-normal light when the count is a power of two (4096 = 64^2: every
 * dyadic interval of the scrambled Sobol' points holds its share; uniform
 * random origins: binomial noise of 0.5/sqrt(c), 0.8 % at c = 4096) */
static void test_origin_strata(void)
{
    hd_genbsdf_opts o;
    hd_genbsdf_defaults(&o);
    set_dim(&o, -5, 0);
    o.nsamp = 4096;
    const char *half =
        "void plastic black 0 0 5 0 0 0 0 0\n"
        "black polygon h 0 0 12  -1000 -1000 -5  0 -1000 -5  0 1000 -5  -1000 1000 -5\n"
        "black polygon c 0 0 12  999 999 -5  1000 999 -5  1000 1000 -5  999 1000 -5\n";
    hd_gbsystem *g = NULL;
    REQUIRE(make_system(half, &o, &g) == HD_OK);
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    size_t n = (size_t)kb.nbins * kb.nbins;
    double *T = calloc(n, sizeof *T);
    REQUIRE(T);
    CHECK(hd_genbsdf_klems(g, &o, HD_GB_FROM_EXTERIOR, &kb, T, NULL) == HD_OK);
    double dev = 0;
    for (int i = 0; i < 9; i++) dev += fabs(hd_genbsdf_klems_hemi(&kb, T, i) - 0.5) / 9;
    printf("  half-plane: mean |T - 0.5| over patches 0-8: %.2e\n", dev);
    CHECK_MSG(dev < 1e-3, "mean deviation %g", dev);
    free(T);
    hd_gbsystem_free(g);
}

static void test_thread_independent(void)
{
    hd_genbsdf_opts o;
    hd_genbsdf_defaults(&o);
    set_dim(&o, -5, 0);
    o.nsamp = 16;   /* the default -ad 700: every diffuse hit splits (branches traced recursively) */
    const char *diffuse =
        "void trans sheet 0 0 7 0.6 0.6 0.6 0.05 0.1 0.5 0.2\n"
        "sheet polygon p 0 0 12  -1000 -1000 -2  1000 -1000 -2  1000 1000 -2  -1000 1000 -2\n";
    hd_gbsystem *g = NULL;
    REQUIRE(make_system(diffuse, &o, &g) == HD_OK);
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    size_t n = (size_t)kb.nbins * kb.nbins;
    double *a = calloc(n, sizeof *a), *b = calloc(n, sizeof *b);
    REQUIRE(a && b);
    o.nthreads = 1;
    CHECK(hd_genbsdf_klems(g, &o, HD_GB_FROM_ROOM, &kb, a, NULL) == HD_OK);
    o.nthreads = 2;
    CHECK(hd_genbsdf_klems(g, &o, HD_GB_FROM_ROOM, &kb, b, NULL) == HD_OK);
    CHECK(memcmp(a, b, n * sizeof *a) == 0);
    free(a); free(b);
    hd_gbsystem_free(g);
}

/* trees written, loaded by the BSDF loader, reproduce the sampled totals */
static void test_tree_roundtrip(void)
{
    hd_genbsdf_opts o;
    hd_genbsdf_defaults(&o);
    set_dim(&o, -5, 0);
    o.nsamp = 400;
    o.ad = 0;       /* one path per diffuse hit: the encoding is under test, not the default */
    o.nthreads = 2;
    o.tree_dims = 4;
    o.tree_log2 = 3;
    const char *sheet =
        "void trans sheet 0 0 7 0.6 0.6 0.6 0.05 0.05 0.5 0.3\n"
        "sheet polygon p 0 0 12  -1000 -1000 -2  1000 -1000 -2  1000 1000 -2  -1000 1000 -2\n";
    hd_gbsystem *g = NULL;
    REQUIRE(make_system(sheet, &o, &g) == HD_OK);
    int R = 8;
    size_t n = (size_t)R * R * R * R;
    float *T = calloc(n, sizeof *T), *Rf = calloc(n, sizeof *Rf);
    REQUIRE(T && Rf);
    REQUIRE(hd_genbsdf_tree(g, &o, HD_GB_FROM_ROOM, T, Rf) == HD_OK);
    hd_gbtree_reciprocal_avg(Rf, 3);
    for (int cull = 0; cull < 2; cull++) {
        hd_gbtree *tt = NULL, *tr = NULL;
        REQUIRE(hd_gbtree_build(&tt, T, 4, 3, cull ? 90 : 0, 400) == HD_OK);
        REQUIRE(hd_gbtree_build(&tr, Rf, 4, 3, cull ? 90 : 0, 400) == HD_OK);
        if (cull) CHECK(hd_gbtree_nleaves(tt) < n);
        else CHECK(hd_gbtree_nleaves(tt) == n);
        char path[512];
        if (snprintf(path, sizeof path, "%s/genbsdf_tree%d.xml", hd_test_tmpdir(), cull) >= (int)sizeof path) return;
        FILE *fp = fopen(path, "w");
        REQUIRE(fp);
        hd_gbxml x;
        memset(&x, 0, sizeof x);
        x.name = "sheet"; x.manufacturer = "test"; x.unit = "millimeter";
        x.thickness = 5; x.width = x.height = 100;
        x.tree_dims = 4;
        x.tree[0] = tt; x.tree[1] = tr;
        CHECK(hd_genbsdf_write_xml(fp, &x, NULL) == HD_OK);
        fclose(fp);
        hd_bsdf *b = NULL;
        hd_status st = hd_bsdf_load(path, &b);
        CHECK_MSG(st == HD_OK, "load %s: %s", path, hd_errmsg());
        if (st == HD_OK) {
            CHECK(hd_bsdf_get_info(b)->type == HD_BSDF_TREE4);
            /* reflection averaged over reciprocal pairs: the loader's
             * reciprocity check finds no error */
            double rmn, ravg, rmx;
            if (hd_bsdf_reciprocity(b, HD_BSDF_RF, &rmn, &ravg, &rmx))
                CHECK_MSG(ravg < 0.5, "reciprocity error avg %g %%", ravg);
            else
                CHECK_MSG(0, "reciprocity not computable");
            /* per incident cell: tree total vs the sampled grid total */
            double maxerr = 0, sumgot = 0, sumwant = 0;
            for (int i0 = 0; i0 < R; i0++)
                for (int i1 = 0; i1 < R; i1++) {
                    double px, py;
                    hd_square2disk((i0 + 0.5) / R, (i1 + 0.5) / R, &px, &py);
                    /* light from the room: in vector points to +z, propagation (px, py, -) */
                    hd_vec3 in = hd_v3(-px, -py, sqrt(fmax(0, 1 - px * px - py * py)));
                    double want = 0, wantr = 0;
                    for (size_t c = 0; c < (size_t)R * R; c++) {
                        want += T[((size_t)i0 * R + i1) * R * R + c] * M_PI / (R * R);
                        wantr += Rf[((size_t)i0 * R + i1) * R * R + c] * M_PI / (R * R);
                    }
                    double got = hd_bsdf_hemi(b, in, HD_BSDF_TRANS);
                    double gotr = hd_bsdf_hemi(b, in, HD_BSDF_REFL);
                    sumgot += got + gotr;
                    sumwant += want + wantr;
                    double e = fabs(got - want) / want, er = fabs(gotr - wantr) / wantr;
                    if (e > maxerr) maxerr = e;
                    if (er > maxerr) maxerr = er;
                }
            /* no culling: exact up to the 7-digit values; 90 % culling
             * averages neighbouring incident cells of a smooth BSDF */
            if (cull) CHECK_MSG(maxerr < 0.3, "culled tree: max relative error %g", maxerr);
            else CHECK_MSG(maxerr < 2e-3, "tree: max relative error %g", maxerr);
            CHECK_MSG(fabs(sumgot - sumwant) < 2e-3 * sumwant, "mean total %g, sampled %g", sumgot / (R * R),
                      sumwant / (R * R));
            /* point values agree with the tree */
            double cc[4] = {0.3, 0.6, 0.2, 0.7};
            double ix, iy, ox, oy;
            hd_square2disk(cc[0], cc[1], &ix, &iy);
            hd_square2disk(cc[2], cc[3], &ox, &oy);
            hd_vec3 in = hd_v3(-ix, -iy, sqrt(1 - ix * ix - iy * iy));
            hd_vec3 out = hd_v3(ox, oy, -sqrt(1 - ox * ox - oy * oy));
            CHECK_REL(hd_bsdf_eval(b, in, out), hd_gbtree_lookup(tt, cc), 2e-3);
            hd_bsdf_free(b);
        }
        hd_gbtree_free(tt);
        hd_gbtree_free(tr);
    }
    free(T); free(Rf);
    hd_gbsystem_free(g);
}

/* the tree encoding (child order, grid order) read back by the BSDF
 * loader: a synthetic grid with distinct values, one merged block */
static void test_tree_encoding(void)
{
    for (int dims = 3; dims <= 4; dims++) {
        int R = 4;
        size_t n = dims == 4 ? 256 : 64;
        float *grid = calloc(n, sizeof *grid);
        REQUIRE(grid);
        for (size_t k = 0; k < n; k++) {
            int c[4] = {0, 0, 0, 0};
            size_t q = k;
            for (int i = dims - 1; i >= 0; i--) { c[i] = (int)(q % R); q /= R; }
            int inblock = 1;
            for (int i = 0; i < dims; i++) if (c[i] >= 2) inblock = 0;
            grid[k] = inblock ? 5.0f : (float)(1 + c[0] + 4 * c[1] + 16 * c[2] + (dims == 4 ? 64 * c[3] : 0));
        }
        hd_gbtree *t = NULL;
        REQUIRE(hd_gbtree_build(&t, grid, dims, 2, 0, 0) == HD_OK);
        CHECK(hd_gbtree_nleaves(t) == n - ((size_t)1 << dims) + 1);
        char path[512];
        if (snprintf(path, sizeof path, "%s/genbsdf_enc%d.xml", hd_test_tmpdir(), dims) >= (int)sizeof path) return;
        FILE *fp = fopen(path, "w");
        REQUIRE(fp);
        hd_gbxml x;
        memset(&x, 0, sizeof x);
        x.name = "synthetic"; x.manufacturer = "test"; x.unit = "meter";
        x.thickness = 0.01; x.width = x.height = 1;
        x.tree_dims = dims;
        x.tree[0] = t;      /* Transmission Back = Radiance tf: incident z > 0 */
        CHECK(hd_genbsdf_write_xml(fp, &x, NULL) == HD_OK);
        fclose(fp);
        hd_bsdf *b = NULL;
        hd_status st = hd_bsdf_load(path, &b);
        CHECK_MSG(st == HD_OK, "%s", hd_errmsg());
        if (st != HD_OK) { hd_gbtree_free(t); free(grid); continue; }
        int bad = 0;
        for (size_t k = 0; k < n; k++) {
            int c[4] = {0, 0, 0, 0};
            size_t q = k;
            for (int i = dims - 1; i >= 0; i--) { c[i] = (int)(q % R); q /= R; }
            hd_vec3 in, out;
            double ox, oy;
            if (dims == 4) {
                double px, py;
                hd_square2disk((c[0] + 0.5) / R, (c[1] + 0.5) / R, &px, &py);
                in = hd_v3(-px, -py, sqrt(1 - px * px - py * py));
                hd_square2disk((c[2] + 0.5) / R, (c[3] + 0.5) / R, &ox, &oy);
            } else {
                if (c[0] >= 2) continue;              /* unused half */
                double st0 = 1 - 2 * (c[0] + 0.5) / R;
                in = hd_v3(-st0, 0, sqrt(1 - st0 * st0));   /* propagation along +x */
                hd_square2disk((c[1] + 0.5) / R, (c[2] + 0.5) / R, &ox, &oy);
            }
            out = hd_v3(ox, oy, -sqrt(fmax(0, 1 - ox * ox - oy * oy)));
            if (dims == 3 && (k & 1)) {   /* same data for light propagating along +y: rotate by 90 deg */
                in = hd_v3(-in.y, in.x, in.z);
                out = hd_v3(-out.y, out.x, out.z);
            }
            double f = hd_bsdf_eval(b, in, out);
            if (fabs(f - grid[k]) > 1e-3 * grid[k]) {
                if (bad++ < 3) printf("  %dD cell %zu: loaded %g, written %g\n", dims, k, f, grid[k]);
            }
        }
        CHECK_MSG(bad == 0, "%dD: %d cells differ", dims, bad);
        hd_bsdf_free(b);
        hd_gbtree_free(t);
        free(grid);
    }
}

/* Klems XML round trip through the loader */
static void test_klems_roundtrip(void)
{
    hd_genbsdf_opts o;
    hd_genbsdf_defaults(&o);
    set_dim(&o, -5, 0);
    o.nsamp = 100;
    o.ad = 0;       /* one path per diffuse hit: the XML round trip is under test */
    o.nthreads = 2;
    const char *sheet =
        "void trans sheet 0 0 7 0.6 0.6 0.6 0.05 0.05 0.5 0.3\n"
        "sheet polygon p 0 0 12  -1000 -1000 -2  1000 -1000 -2  1000 1000 -2  -1000 1000 -2\n";
    hd_gbsystem *g = NULL;
    REQUIRE(make_system(sheet, &o, &g) == HD_OK);
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    size_t n = (size_t)kb.nbins * kb.nbins;
    double *v[4];
    for (int k = 0; k < 4; k++) REQUIRE((v[k] = calloc(n, sizeof(double))));
    CHECK(hd_genbsdf_klems(g, &o, HD_GB_FROM_ROOM, &kb, v[0], v[1]) == HD_OK);
    CHECK(hd_genbsdf_klems(g, &o, HD_GB_FROM_EXTERIOR, &kb, v[2], v[3]) == HD_OK);
    char path[512];
    if (snprintf(path, sizeof path, "%s/genbsdf_klems.xml", hd_test_tmpdir()) >= (int)sizeof path) return;
    FILE *fp = fopen(path, "w");
    REQUIRE(fp);
    hd_gbxml x;
    memset(&x, 0, sizeof x);
    x.name = "sheet"; x.manufacturer = "test"; x.unit = "millimeter";
    x.thickness = 5; x.width = x.height = 100;
    for (int k = 0; k < 4; k++) x.klems[k] = v[k];
    CHECK(hd_genbsdf_write_xml(fp, &x, &kb) == HD_OK);
    fclose(fp);
    hd_bsdf *b = NULL;
    REQUIRE(hd_bsdf_load(path, &b) == HD_OK);
    CHECK(hd_bsdf_get_info(b)->type == HD_BSDF_KLEMS_FULL);
    /* WINDOW names: [2] Transmission Front = Radiance tb */
    double *w = calloc(n, sizeof *w);
    REQUIRE(w);
    hd_bsdf_comp comps[4] = {HD_BSDF_TF, HD_BSDF_RF, HD_BSDF_TB, HD_BSDF_RB};
    for (int k = 0; k < 4; k++) {
        CHECK(hd_bsdf_klems_values(b, comps[k], &kb, 0, w) == HD_OK);
        double maxerr = 0;
        for (int i = 0; i < kb.nbins; i++) {
            double a = hd_genbsdf_klems_hemi(&kb, v[k], i), c = hd_genbsdf_klems_hemi(&kb, w, i);
            if (fabs(a - c) / a > maxerr) maxerr = fabs(a - c) / a;
        }
        CHECK_MSG(maxerr < 1e-3, "component %d: max relative error %g", k, maxerr);
    }
    free(w);
    hd_bsdf_free(b);
    for (int k = 0; k < 4; k++) free(v[k]);
    hd_gbsystem_free(g);
}

/* heliodon vs Radiance genBSDF on comparable geometry (../shared/ref/bsdf):
 * exterior->room hemispherical transmittance per Klems incident patch */
static void compare_ref(const char *sys, int nfiles, char **files, double zmin, int nsamp, int ad, double tol)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no ../shared/ref");
    char path[512];
    if (snprintf(path, sizeof path, "%s/bsdf/%s/%s_klems.xml", ref, sys, sys) >= (int)sizeof path) SKIP("path too long");
    hd_bsdf *b = NULL;
    if (hd_bsdf_load(path, &b) != HD_OK) SKIP("cannot load the reference Klems XML");
    hd_scene sc;
    hd_scene_init(&sc);
    hd_status st = hd_scene_load_files(&sc, nfiles, files, NULL);
    REQUIRE(st == HD_OK);
    hd_genbsdf_opts o;
    hd_genbsdf_defaults(&o);
    set_dim(&o, zmin, 0);
    o.nsamp = (uint64_t)nsamp;
    o.ad = ad;
    o.nthreads = 2;
    hd_gbsystem *g = NULL;
    st = hd_gbsystem_create(&g, &sc, &o);
    hd_scene_free(&sc);
    REQUIRE(st == HD_OK);
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    size_t n = (size_t)kb.nbins * kb.nbins;
    double *T = calloc(n, sizeof *T), *W = calloc(n, sizeof *W);
    REQUIRE(T && W);
    CHECK(hd_genbsdf_klems(g, &o, HD_GB_FROM_EXTERIOR, &kb, T, NULL) == HD_OK);
    CHECK(hd_bsdf_klems_values(b, HD_BSDF_TB, &kb, 0, W) == HD_OK);
    double sum = 0, mx = 0;
    int imx = 0;
    for (int i = 0; i < kb.nbins; i++) {
        double a = hd_genbsdf_klems_hemi(&kb, T, i), r = hd_genbsdf_klems_hemi(&kb, W, i);
        double e = fabs(a - r) / r;
        sum += e;
        if (e > mx) { mx = e; imx = i; }
    }
    double avg = sum / kb.nbins;
    printf("  %s front transmittance per Klems patch: mean relative difference %.2f %%, max %.1f %% (patch %d)\n",
           sys, 100 * avg, 100 * mx, imx);
    CHECK_MSG(avg < tol, "mean relative difference %g", avg);
    free(T); free(W);
    hd_bsdf_free(b);
    hd_gbsystem_free(g);
}

static void test_cfs1_vs_radiance(void)
{
    char *files[2] = {"scenes/cfs/slat.mat", "scenes/cfs/cfs1.rad"};
    compare_ref("cfs1", 2, files, -12.01, 500, 16, 0.05);   /* -ad 16: the reference's -r '-ad 16' */
}

static void test_cfs3_vs_radiance(void)
{
    char *files[1] = {"scenes/cfs/cfs3.rad"};
    compare_ref("cfs3", 1, files, -4.62, 1000, 16, 0.05);   /* purely specular: -ad has no effect */
}

/* tree direction conventions on an asymmetric system (CFS1 slats, light
 * from the exterior): the loaded tree's hemispherical transmittance agrees
 * with the Klems run for sources above and below the horizontal plane */
static void test_tree_conventions(void)
{
    hd_scene sc;
    hd_scene_init(&sc);
    char *files[2] = {"scenes/cfs/slat.mat", "scenes/cfs/cfs1.rad"};
    REQUIRE(hd_scene_load_files(&sc, 2, files, NULL) == HD_OK);
    hd_genbsdf_opts o;
    hd_genbsdf_defaults(&o);
    set_dim(&o, -12.01, 0);
    o.nsamp = 400;
    o.ad = 0;       /* one path per diffuse hit: the tree's direction conventions are under test */
    o.nthreads = 2;
    o.forward = 1;
    o.backward = 0;
    hd_gbsystem *g = NULL;
    hd_status st = hd_gbsystem_create(&g, &sc, &o);
    hd_scene_free(&sc);
    REQUIRE(st == HD_OK);
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    size_t n = (size_t)kb.nbins * kb.nbins;
    double *K = calloc(n, sizeof *K);
    o.tree_dims = 4;
    o.tree_log2 = 4;
    size_t nt = (size_t)1 << 16;
    float *T = calloc(nt, sizeof *T);
    REQUIRE(K && T);
    CHECK(hd_genbsdf_klems(g, &o, HD_GB_FROM_EXTERIOR, &kb, K, NULL) == HD_OK);
    CHECK(hd_genbsdf_tree(g, &o, HD_GB_FROM_EXTERIOR, T, NULL) == HD_OK);
    hd_gbtree *tt = NULL;
    REQUIRE(hd_gbtree_build(&tt, T, 4, 4, 0, 400) == HD_OK);
    char path[512];
    if (snprintf(path, sizeof path, "%s/genbsdf_conv.xml", hd_test_tmpdir()) >= (int)sizeof path) return;
    FILE *fp = fopen(path, "w");
    REQUIRE(fp);
    hd_gbxml x;
    memset(&x, 0, sizeof x);
    x.name = "cfs1"; x.manufacturer = "test"; x.unit = "millimeter";
    x.thickness = 12.01; x.width = x.height = 100;
    x.tree_dims = 4;
    x.tree[2] = tt;
    CHECK(hd_genbsdf_write_xml(fp, &x, NULL) == HD_OK);
    fclose(fp);
    hd_bsdf *b = NULL;
    REQUIRE(hd_bsdf_load(path, &b) == HD_OK);
    /* sources at 50 deg above (phi 90) and below (phi 270) and to the side */
    double phis[3] = {90, 270, 0};
    double tv[3];
    for (int k = 0; k < 3; k++) {
        double th = 50 * M_PI / 180, ph = phis[k] * M_PI / 180;
        hd_vec3 in = hd_v3(sin(th) * cos(ph), sin(th) * sin(ph), -cos(th));   /* towards the source */
        /* Klems patch of the propagation direction -in, with |z| */
        int bin = hd_klems_bin(&kb, hd_v3(-in.x, -in.y, -in.z));
        double kt = hd_genbsdf_klems_hemi(&kb, K, bin);
        tv[k] = hd_bsdf_hemi(b, in, HD_BSDF_TRANS);
        printf("  CFS1 T(50, %3.0f): tree %.3f, Klems %.3f\n", phis[k], tv[k], kt);
        /* a 16 x 16 tree's value in one direction against the Klems patch's
         * mean: 0.475 / 0.542 at phi 90 when the slats' specular event was
         * chosen at random, 0.479 / 0.580 with it weighted (as Radiance; the
         * Klems matrix then moved closer to Radiance's, test_cfs1_vs_radiance
         * 2.03 -> 1.57 % mean): the orientation is what is tested here */
        CHECK_MSG(fabs(tv[k] - kt) < 0.11, "phi %g: tree %g vs Klems %g", phis[k], tv[k], kt);
    }
    /* asymmetric (Klems: 0.54 above, 0.39 below): a flipped axis would swap these */
    CHECK(tv[1] < tv[0] - 0.05);
    hd_bsdf_free(b);
    hd_gbtree_free(tt);
    free(K); free(T);
    hd_gbsystem_free(g);
}

/* CFS4 fabric: normal-hemispherical values vs the paper's targets
 * (tau 0.014, rho exterior 0.438, rho room side 0.241) */
static void test_cfs4_targets(void)
{
    hd_scene sc;
    hd_scene_init(&sc);
    hd_status st = hd_scene_load_rad(&sc, "!awk -f scenes/cfs/fabric.awk", NULL);
    REQUIRE(st == HD_OK);
    hd_genbsdf_opts o;
    hd_genbsdf_defaults(&o);
    set_dim(&o, -50, 50);
    o.dim[4] = -0.6; o.dim[5] = 0;
    o.nsamp = 40000;
    o.ad = 0;       /* one path per diffuse hit: 40000 paths reach the targets' accuracy cheaply */
    o.nthreads = 2;
    hd_gbsystem *g = NULL;
    st = hd_gbsystem_create(&g, &sc, &o);
    hd_scene_free(&sc);
    REQUIRE(st == HD_OK);
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    size_t n = (size_t)kb.nbins * kb.nbins;
    double *T = calloc(n, sizeof *T), *R = calloc(n, sizeof *R), *R2 = calloc(n, sizeof *R2);
    REQUIRE(T && R && R2);
    CHECK(hd_genbsdf_klems_range(g, &o, HD_GB_FROM_EXTERIOR, &kb, 0, 1, T, R) == HD_OK);
    CHECK(hd_genbsdf_klems_range(g, &o, HD_GB_FROM_ROOM, &kb, 0, 1, NULL, R2) == HD_OK);
    double t = hd_genbsdf_klems_hemi(&kb, T, 0), re = hd_genbsdf_klems_hemi(&kb, R, 0);
    double ri = hd_genbsdf_klems_hemi(&kb, R2, 0);
    printf("  CFS4 normal incidence: T %.4f (0.014), R ext %.4f (0.438), R room %.4f (0.241)\n", t, re, ri);
    CHECK_NEAR(t, 0.014, 0.002);
    CHECK_NEAR(re, 0.438, 0.01);
    CHECK_NEAR(ri, 0.241, 0.01);
    free(T); free(R); free(R2);
    hd_gbsystem_free(g);
}

static void test_errors(void)
{
    hd_genbsdf_opts o;
    hd_gbsystem *g = NULL;
    /* geometry outside -dim */
    hd_genbsdf_defaults(&o);
    set_dim(&o, -3, 0);
    CHECK(make_system(SLAB, &o, &g) == HD_ERR_RANGE);
    CHECK_CONTAINS(hd_errmsg(), "outside the -dim z range");
    /* -dim rectangle not covered */
    hd_genbsdf_defaults(&o);
    set_dim(&o, -5, 0);
    o.dim[1] = 5000;
    CHECK(make_system(SLAB, &o, &g) == HD_ERR_RANGE);
    CHECK_CONTAINS(hd_errmsg(), "not covered");
    /* no surfaces */
    hd_genbsdf_defaults(&o);
    CHECK(make_system("void plastic p 0 0 5 .5 .5 .5 0 0\n", &o, &g) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "no surfaces");
    /* a dielectric volume with a missing face */
    hd_genbsdf_defaults(&o);
    set_dim(&o, -5, 0);
    char open[2048];
    snprintf(open, sizeof open, "%s", SLAB);
    char *cut = strstr(open, "clear polygon s4");
    REQUIRE(cut);
    *cut = 0;
    CHECK(make_system(open, &o, &g) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "not closed");
    /* unsupported material */
    hd_genbsdf_defaults(&o);
    CHECK(make_system("void mist m 0 0 0\nm sphere s 0 0 4 0 0 0 1\n", &o, &g) == HD_ERR_UNSUPPORTED);
    /* command line */
    char *a1[] = {"genBSDF", "-geom", "furlong", "x.rad"};
    int first;
    hd_genbsdf_defaults(&o);
    CHECK(hd_genbsdf_parse_args(4, a1, &o, &first) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "unknown unit");
    char *a2[] = {"genBSDF", "-dim", "1", "2", "3"};
    hd_genbsdf_defaults(&o);
    CHECK(hd_genbsdf_parse_args(5, a2, &o, &first) == HD_ERR_USAGE);
    char *a3[] = {"genBSDF", "-b", "x.rad"};
    hd_genbsdf_defaults(&o);
    CHECK(hd_genbsdf_parse_args(3, a3, &o, &first) == HD_ERR_USAGE);
    char *a4[] = {"genBSDF", "+f", "-b", "-t4", "5", "-c", "10k", "-n", "2", "-geom", "mm", "x.rad"};
    hd_genbsdf_defaults(&o);
    CHECK(hd_genbsdf_parse_args(12, a4, &o, &first) == HD_ERR_USAGE);   /* "mm" is not a unit name */
    a4[10] = "millimeter";
    hd_genbsdf_defaults(&o);
    CHECK(hd_genbsdf_parse_args(12, a4, &o, &first) == HD_OK);
    CHECK(o.forward == 1 && o.backward == 0 && o.tree_dims == 4 && o.tree_log2 == 5 && o.nsamp == 10000);
    CHECK(first == 11);
}

int main(void)
{
    RUN(test_fresnel_slab);
    RUN(test_reflection_limit);
    RUN(test_glass_split);
    RUN(test_origin_strata);
    RUN(test_thread_independent);
    RUN(test_tree_roundtrip);
    RUN(test_tree_encoding);
    RUN(test_klems_roundtrip);
    RUN(test_cfs1_vs_radiance);
    RUN(test_cfs3_vs_radiance);
    RUN(test_tree_conventions);
    RUN(test_cfs4_targets);
    RUN(test_errors);
    return hd_test_done();
}

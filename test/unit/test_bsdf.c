/* BSDF library against Radiance 6.1 reference outputs (../shared/ref/bsdf):
 * checkBSDF reports, testBSDF hemispherical values, rmtxop Klems matrices,
 * bsdf2klems conversions; energy conservation of every file. */
#define _GNU_SOURCE
#include "hd_test.h"
#include "heliodon/bsdf.h"
#include "heliodon/rng.h"

static const char *const FILES[] = {
    "glazing/glazing_klems", "cfs1/cfs1_klems", "cfs1/cfs1_ttree", "cfs1/cfs1_ttree_klems",
    "cfs3/cfs3_klems", "cfs3/cfs3_ttree", "cfs3/cfs3_ttree_klems"};
#define NFILES (int)(sizeof FILES / sizeof FILES[0])

static hd_bsdf *load_ref(const char *stem)
{
    const char *ref = hd_test_ref();
    char path[1024];
    snprintf(path, sizeof path, "%s/bsdf/%s.xml", ref, stem);
    hd_bsdf *b = NULL;
    if (hd_bsdf_load(path, &b) != HD_OK) {
        printf("  load %s: %s\n", path, hd_errmsg());
        return NULL;
    }
    return b;
}

static char *slurp(const char *path)
{
    FILE *fp = fopen(path, "rb");
    if (!fp) return NULL;
    fseek(fp, 0, SEEK_END);
    long n = ftell(fp);
    fseek(fp, 0, SEEK_SET);
    char *s = malloc((size_t)n + 1);
    if (s && fread(s, 1, (size_t)n, fp) != (size_t)n) { free(s); s = NULL; }
    if (s) s[n] = 0;
    fclose(fp);
    return s;
}

/* one component line of a checkBSDF report */
typedef struct cline { double lamb, maxdir, minang; int ok; } cline;

static void parse_report(const char *txt, cline out[4], char *type, size_t tcap)
{
    static const char *const lab[4] = {"Interior Refl\t", "Exterior Refl\t", "Int->Ext Trans\t",
                                       "Ext->Int Trans\t"};
    const char *t = strstr(txt, "Type: ");
    if (t) sscanf(t + 6, "%63s", type);
    (void)tcap;
    for (int c = 0; c < 4; c++) {
        out[c].ok = 0;
        const char *p = strstr(txt, lab[c]);
        if (!p) continue;
        double x, y, z;
        if (sscanf(p + strlen(lab[c]), "%lf %lf %lf %lf%% %lf", &x, &y, &z, &out[c].maxdir,
                   &out[c].minang) == 5) {
            out[c].lamb = y;
            out[c].ok = 1;
        }
    }
}

/* hd_bsdf_vector_cell: view vectors of one key give the same value against any vector, in
 * either role and every component (the -dn draw's table relies on it, bit for bit); keys
 * differ between neighbours a cell apart; -1 for Klems data and for a vector in the plane. */
static void test_vector_cell(void)
{
    if (!hd_test_ref()) SKIP("no reference folder");
    hd_bsdf *b = load_ref("cfs1/cfs1_ttree"), *k = load_ref("cfs1/cfs1_klems");
    REQUIRE(b && k);
    CHECK(hd_bsdf_get_info(b)->type == HD_BSDF_TREE4);
    CHECK(hd_bsdf_vector_cell(k, hd_v3(0.1, 0.2, 0.97)) == -1);
    CHECK(hd_bsdf_vector_cell(b, hd_v3(1, 0, 0)) == -1);
    hd_rng rng;
    hd_rng_init(&rng, 12345, 0);
#define U01() hd_rng_uniform(&rng)
    int same = 0, differ = 0, bad = 0;
    for (int t = 0; t < 4000; t++) {
        double th = acos(U01()), ph = 2 * HD_PI * U01(), side = t % 2 ? -1 : 1;
        hd_vec3 v = hd_v3(sin(th) * cos(ph), sin(th) * sin(ph), side * cos(th));
        /* a neighbour: a step of up to about two finest cells of a level-6 tree (1.8 deg) */
        double d = 0.08 * U01();
        hd_vec3 w = hd_vnorm(hd_v3(v.x + d * (U01() - 0.5), v.y + d * (U01() - 0.5), v.z));
        int64_t kv = hd_bsdf_vector_cell(b, v), kw = hd_bsdf_vector_cell(b, w);
        CHECK(kv >= 0 && kw >= 0);
        if (kv != kw) { differ++; continue; }
        same++;
        for (int j = 0; j < 8; j++) {
            double t2 = acos(U01()), p2 = 2 * HD_PI * U01(), s2 = j % 2 ? -1 : 1;
            hd_vec3 x = hd_v3(sin(t2) * cos(p2), sin(t2) * sin(p2), s2 * cos(t2));
            for (int c = 0; c < 4; c++) {
                hd_bsdf_comp cc = (hd_bsdf_comp)c;
                bad += hd_bsdf_eval_comp(b, cc, v, x, 1) != hd_bsdf_eval_comp(b, cc, w, x, 1);
                bad += hd_bsdf_eval_comp(b, cc, x, v, 1) != hd_bsdf_eval_comp(b, cc, x, w, 1);
            }
        }
    }
#undef U01
    printf("  vector_cell: %d pairs in one cell, %d in two; %d values differ within a cell\n", same, differ, bad);
    CHECK(same > 500 && differ > 500);
    CHECK(bad == 0);
    hd_bsdf_free(b);
    hd_bsdf_free(k);
}

/* checkBSDF figures within 1 percentage point (and the angle within 0.01
 * deg); the report layout identical up to the reciprocity numbers. */
static void test_checkbsdf(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder");
    for (int f = 0; f < NFILES; f++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/bsdf/%s.checkBSDF.txt", ref, FILES[f]);
        char *want = slurp(path);
        hd_bsdf *b = load_ref(FILES[f]);
        REQUIRE(want && b);
        char *got = NULL;
        size_t glen = 0;
        FILE *mf = open_memstream(&got, &glen);
        char shown[256];
        snprintf(shown, sizeof shown, "%s.xml", FILES[f]);
        CHECK(hd_bsdf_check_report(mf, shown, b) == HD_OK);
        fclose(mf);
        cline a[4], w[4];
        char ta[64] = "", tw[64] = "";
        parse_report(got, a, ta, sizeof ta);
        parse_report(want, w, tw, sizeof tw);
        CHECK_MSG(!strcmp(ta, tw), "%s: type %s, expected %s", FILES[f], ta, tw);
        for (int c = 0; c < 4; c++) {
            CHECK_MSG(a[c].ok && w[c].ok, "%s: component line %d unparsable", FILES[f], c);
            CHECK_MSG(fabs(a[c].lamb - w[c].lamb) <= 1.0, "%s %s: Lambertian %.1f%%, ref %.1f%%",
                      FILES[f], hd_bsdf_label(c), a[c].lamb, w[c].lamb);
            CHECK_MSG(fabs(a[c].maxdir - w[c].maxdir) <= 1.0, "%s %s: Max. Tot. Dir %.1f%%, ref %.1f%%",
                      FILES[f], hd_bsdf_label(c), a[c].maxdir, w[c].maxdir);
            CHECK_MSG(fabs(a[c].minang - w[c].minang) <= 0.011, "%s %s: Min. Angle %.2f, ref %.2f",
                      FILES[f], hd_bsdf_label(c), a[c].minang, w[c].minang);
        }
        /* the first 13 lines are identical text */
        const char *pa = got, *pw = want;
        for (int line = 0; line < 13; line++) {
            const char *ea = strchr(pa, '\n'), *ew = strchr(pw, '\n');
            if (!ea || !ew) break;
            if (ea - pa != ew - pw || memcmp(pa, pw, (size_t)(ea - pa))) {
                CHECK_MSG(0, "%s: report line %d differs:\n    got  %.*s\n    want %.*s", FILES[f],
                          line + 1, (int)(ea - pa), pa, (int)(ew - pw), pw);
            }
            pa = ea + 1;
            pw = ew + 1;
        }
        free(got);
        free(want);
        hd_bsdf_free(b);
    }
}

/* Directional-hemispherical values against testBSDF (SDdirectHemi). */
static void test_hemi(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder");
    double worst = 0;
    for (int f = 0; f < NFILES; f++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/bsdf/%s.hemi.txt", ref, FILES[f]);
        FILE *fp = fopen(path, "r");
        hd_bsdf *b = load_ref(FILES[f]);
        REQUIRE(fp && b);
        char line[512];
        int n = 0;
        while (fgets(line, sizeof line, fp)) {
            char side[8];
            double th, ph, T, R;
            if (line[0] == '#' || sscanf(line, "%7s %lf %lf %lf %lf", side, &th, &ph, &T, &R) != 5) continue;
            double t = th * HD_PI / 180, p = ph * HD_PI / 180;
            hd_vec3 v = hd_v3(sin(t) * cos(p), sin(t) * sin(p), cos(t));
            if (!strcmp(side, "ext")) v.z = -v.z;
            double gT = hd_bsdf_hemi(b, v, HD_BSDF_TRANS), gR = hd_bsdf_hemi(b, v, HD_BSDF_REFL);
            double d = fmax(fabs(gT - T), fabs(gR - R));
            if (d > worst) worst = d;
            CHECK_MSG(fabs(gT - T) <= 0.002 && fabs(gR - R) <= 0.002,
                      "%s %s (%g,%g): T %.4f R %.4f, testBSDF T %.4f R %.4f", FILES[f], side, th, ph,
                      gT, gR, T, R);
            n++;
        }
        CHECK(n == 12);
        fclose(fp);
        hd_bsdf_free(b);
    }
    printf("  hemispherical values: largest difference from testBSDF %.5f\n", worst);
}

/* test-local reader for rmtxop's ascii output */
static double *read_mtx(const char *path, int *nr, int *nc)
{
    FILE *fp = fopen(path, "r");
    if (!fp) return NULL;
    char line[512];
    int nrows = 0, ncols = 0, ncomp = 0;
    while (fgets(line, sizeof line, fp)) {
        if (line[0] == '\n') break;
        sscanf(line, "NROWS=%d", &nrows);
        sscanf(line, "NCOLS=%d", &ncols);
        sscanf(line, "NCOMP=%d", &ncomp);
    }
    if (nrows <= 0 || ncols <= 0 || ncomp <= 0) { fclose(fp); return NULL; }
    double *m = malloc(sizeof *m * (size_t)nrows * (size_t)ncols);
    for (int i = 0; i < nrows * ncols; i++) {
        double v[3] = {0, 0, 0};
        for (int k = 0; k < ncomp; k++)
            if (fscanf(fp, "%lf", &v[k < 3 ? k : 2]) != 1) { free(m); fclose(fp); return NULL; }
        m[i] = v[1];
    }
    fclose(fp);
    *nr = nrows;
    *nc = ncols;
    return m;
}

/* Klems matrices (3-phase T, Rf, Rb) of the Klems files equal rmtxop's. */
static void test_klems_matrices(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder");
    static const char *const suf[3] = {"_T", "_Rf", "_Rb"};
    static const hd_bsdf_comp comp[3] = {HD_BSDF_TB, HD_BSDF_RF, HD_BSDF_RB};
    int compared = 0;
    for (int f = 0; f < NFILES; f++) {
        if (!strstr(FILES[f], "klems")) continue;
        hd_bsdf *b = load_ref(FILES[f]);
        REQUIRE(b);
        for (int k = 0; k < 3; k++) {
            char path[1024];
            snprintf(path, sizeof path, "%s/bsdf/%s%s.mtx", ref, FILES[f], suf[k]);
            int nr, nc;
            double *want = read_mtx(path, &nr, &nc);
            if (!want) continue;           /* omitted where the block is absent */
            hd_matrix m;
            hd_status st = hd_bsdf_klems_matrix(b, comp[k], NULL, 0, 3, &m);
            CHECK_MSG(st == HD_OK, "%s: %s", path, hd_errmsg());
            if (st == HD_OK) {
                CHECK(m.nrows == nr && m.ncols == nc && m.ncomp == 3);
                int bad = 0;
                for (int i = 0; i < nr * nc && m.nrows == nr && m.ncols == nc; i++) {
                    double g = m.data[3 * i + 1], w = want[i];
                    if (fabs(g - w) > 2e-4 * fabs(w) + 1e-9 || m.data[3 * i] != g) {
                        if (!bad) printf("  %s: element (%d,%d) = %.7g, rmtxop %.7g\n", path, i / nc,
                                         i % nc, g, w);
                        bad++;
                    }
                }
                CHECK_MSG(bad == 0, "%s: %d elements differ", path, bad);
                free(m.data);
                compared++;
            }
            free(want);
        }
        hd_bsdf_free(b);
    }
    CHECK(compared == 14);
}

/* Our Klems conversion of the tensor trees against Radiance's bsdf2klems. */
static void test_bsdf2klems(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder");
    static const char *const trees[2] = {"cfs1/cfs1_ttree", "cfs3/cfs3_ttree"};
    static const char *const suf[3] = {"_T", "_Rf", "_Rb"};
    static const hd_bsdf_comp comp[3] = {HD_BSDF_TB, HD_BSDF_RF, HD_BSDF_RB};
    for (int f = 0; f < 2; f++) {
        hd_bsdf *b = load_ref(trees[f]);
        REQUIRE(b);
        for (int k = 0; k < 3; k++) {
            char path[1024];
            snprintf(path, sizeof path, "%s/bsdf/%s_klems%s.mtx", ref, trees[f], suf[k]);
            int nr, nc;
            double *want = read_mtx(path, &nr, &nc);
            if (!want) continue;
            hd_matrix m;
            REQUIRE(hd_bsdf_klems_matrix(b, comp[k], NULL, 0, 1, &m) == HD_OK);
            REQUIRE(m.nrows == nr && m.ncols == nc);
            /* hemispherical sum per incident patch (column) */
            double sumdiff = 0, maxdiff = 0;
            int over1 = 0, ncol = 0;
            for (int i = 0; i < nc; i++) {
                double sg = 0, sw = 0;
                for (int o = 0; o < nr; o++) { sg += m.data[(size_t)o * nc + i]; sw += want[(size_t)o * nc + i]; }
                if (sw < 0.01) continue;
                double d = fabs(sg - sw) / sw;
                sumdiff += d;
                ncol++;
                if (d > maxdiff) maxdiff = d;
                if (d > 0.01) over1++;
            }
            /* element-wise, where the reference exceeds 1 % of its row max */
            double rel = 0;
            long nel = 0;
            for (int o = 0; o < nr; o++) {
                double rmax = 0;
                for (int i = 0; i < nc; i++) rmax = fmax(rmax, want[(size_t)o * nc + i]);
                for (int i = 0; i < nc; i++) {
                    double w = want[(size_t)o * nc + i];
                    if (w > 0.01 * rmax && w > 0) { rel += fabs(m.data[(size_t)o * nc + i] - w) / w; nel++; }
                }
            }
            rel /= nel ? nel : 1;
            printf("  %s%s: patch hemispherical sums: mean diff %.2f%%, max %.2f%%, %d of %d "
                   "patches over 1%%; element mean rel diff %.2f%% (%ld elements)\n", trees[f],
                   suf[k], 100 * sumdiff / ncol, 100 * maxdiff, over1, ncol, 100 * rel, nel);
            /* Radiance's conversion is a Monte Carlo average (1024 random
             * direction pairs per patch pair); ours integrates the tree
             * exactly.  On the smooth CFS1 data the two agree within the
             * issue's 5 %; on the very peaked CFS3 prisms Radiance's own
             * run-to-run noise (seeds changed) is 10-17 % element-wise, and
             * ours differs from one Radiance run by that noise / sqrt(2)
             * (8 / 7 / 12 %) and from the mean of 3 runs by / sqrt(3)
             * (docs/benchmarks/bsdf.md), so the bound there is 15 %. */
            double lim = f == 0 ? 0.05 : 0.15;
            CHECK_MSG(rel < lim, "%s%s: element-wise mean relative difference %.2f%% >= %.0f%%",
                      trees[f], suf[k], 100 * rel, 100 * lim);
            CHECK_MSG(sumdiff / ncol < 0.03, "%s%s: mean per-patch hemispherical difference %.2f%%",
                      trees[f], suf[k], 100 * sumdiff / ncol);
            free(m.data);
            free(want);
        }
        hd_bsdf_free(b);
    }
}

/* Our conversion against the exact per-direction hemispherical values:
 * Σ_o f[o][i]·λ_o must equal the mean over incident patch i of
 * hd_bsdf_hemi (16×16 stratified directions), within 1 %. */
static void test_bsdf2klems_exact(void)
{
    if (!hd_test_ref()) SKIP("no reference folder");
    static const char *const trees[2] = {"cfs1/cfs1_ttree", "cfs3/cfs3_ttree"};
    static const hd_bsdf_comp comps[4] = {HD_BSDF_RF, HD_BSDF_RB, HD_BSDF_TF, HD_BSDF_TB};
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    double *v = malloc(sizeof *v * 145 * 145);
    for (int f = 0; f < 2; f++) {
        hd_bsdf *b = load_ref(trees[f]);
        REQUIRE(b);
        hd_bsdf_cache *cache = hd_bsdf_cache_new(b, 0);
        for (int k = 0; k < 4; k++) {
            hd_bsdf_comp c = comps[k];
            if (hd_bsdf_get_info(b)->avail[c] == HD_BSDF_ABSENT) continue;
            REQUIRE(hd_bsdf_klems_values(b, c, &kb, 0, v) == HD_OK);
            double worst = 0, mean = 0;
            int n = 0;
            for (int i = 0; i < 145; i++) {
                double s = 0, h = 0;
                for (int o = 0; o < 145; o++) s += v[o * 145 + i] * hd_klems_lambda(&kb, o);
                for (int p = 0; p < 16; p++)
                    for (int q = 0; q < 16; q++)
                        h += hd_bsdf_albedo(b, cache, hd_bsdf_klems_in_dir(&kb, c, i, (p + 0.5) / 16, (q + 0.5) / 16),
                                            HD_BSDF_FORWARD, c < 2 ? HD_BSDF_REFL : HD_BSDF_TRANS);
                h /= 256;
                if (h < 0.02) continue;
                double d = fabs(s - h) / h;
                mean += d;
                n++;
                if (d > worst) worst = d;
            }
            mean /= n ? n : 1;
            printf("  %s %s: our Klems patch sums vs exact hemispherical means: mean %.2f%%, max %.2f%%\n",
                   trees[f], hd_bsdf_label(c), 100 * mean, 100 * worst);
            CHECK_MSG(mean < 0.01 && worst < 0.05, "%s %s: mean %.2f%% max %.2f%%", trees[f],
                      hd_bsdf_label(c), 100 * mean, 100 * worst);
        }
        hd_bsdf_cache_free(cache);
        hd_bsdf_free(b);
    }
    free(v);
}

/* The Monte Carlo path (used for isotropic trees and Klems data in another
 * basis), forced on the CFS3 tree with a non-square sample count, against
 * the exact patch means: unbiased (patch sums agree on average) and with
 * the noise of 2000 samples (measured 8-9 % element-wise). */
static void test_bsdf2klems_mc(void)
{
    if (!hd_test_ref()) SKIP("no reference folder");
    hd_bsdf *b = load_ref("cfs3/cfs3_ttree");
    REQUIRE(b);
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    int n = kb.nbins;
    double *ex = malloc(sizeof *ex * (size_t)(n * n)), *mc = malloc(sizeof *mc * (size_t)(n * n));
    REQUIRE(ex && mc);
    REQUIRE(hd_bsdf_klems_values(b, HD_BSDF_TB, &kb, 0, ex) == HD_OK);
    REQUIRE(hd_bsdf_klems_values(b, HD_BSDF_TB, &kb, -2000, mc) == HD_OK);
    double rel = 0, sabs = 0, ssig = 0;
    long ne = 0;
    int ns = 0;
    for (int o = 0; o < n; o++) {
        double rm = 0;
        for (int i = 0; i < n; i++) rm = fmax(rm, ex[o * n + i]);
        for (int i = 0; i < n; i++) {
            double w = ex[o * n + i];
            if (w > 0.01 * rm && w > 0) { rel += fabs(mc[o * n + i] - w) / w; ne++; }
        }
    }
    for (int i = 0; i < n; i++) {
        double a = 0, e = 0;
        for (int o = 0; o < n; o++) { a += mc[o * n + i] * hd_klems_lambda(&kb, o); e += ex[o * n + i] * hd_klems_lambda(&kb, o); }
        if (e < 0.01) continue;
        sabs += fabs(a - e) / e;
        ssig += (a - e) / e;
        ns++;
    }
    rel /= ne ? ne : 1;
    printf("  Monte Carlo (2000 samples) vs exact: elements %.2f %%, patch sums mean |d| %.2f %%, "
           "mean signed %.2f %%\n", 100 * rel, 100 * sabs / ns, 100 * ssig / ns);
    CHECK_MSG(rel < 0.12, "element-wise %.2f %%", 100 * rel);
    CHECK_MSG(sabs / ns < 0.04, "patch sums %.2f %%", 100 * sabs / ns);
    CHECK_MSG(fabs(ssig / ns) < 0.01, "patch sums biased by %.2f %%", 100 * ssig / ns);
    free(ex);
    free(mc);
    hd_bsdf_free(b);
}

/* Klems data converted to another basis (full -> quarter) is integrated
 * exactly (bin overlaps): per target incident patch the hemispherical sum
 * equals the mean of the source's directional-hemispherical values over
 * the patch (64x64 stratified directions, whose own error is ~0.1 %), and
 * the forced Monte Carlo path agrees within its noise, without bias. */
static void test_klems_rebin(void)
{
    if (!hd_test_ref()) SKIP("no reference folder");
    hd_bsdf *b = load_ref("cfs1/cfs1_klems");
    REQUIRE(b);
    hd_klems_basis kq;
    hd_klems_standard(&kq, HD_KLEMS_QUARTER);
    int n = kq.nbins;
    double *ex = malloc(sizeof *ex * (size_t)(n * n)), *mc = malloc(sizeof *mc * (size_t)(n * n));
    REQUIRE(ex && mc);
    static const hd_bsdf_comp comps[4] = {HD_BSDF_RF, HD_BSDF_RB, HD_BSDF_TF, HD_BSDF_TB};
    for (int k = 0; k < 4; k++) {
        hd_bsdf_comp c = comps[k];
        REQUIRE(hd_bsdf_klems_values(b, c, &kq, 0, ex) == HD_OK);
        double worst = 0, mean = 0;
        int cnt = 0;
        for (int i = 0; i < n; i++) {
            double sum = 0, h = 0;
            for (int o = 0; o < n; o++) sum += ex[o * n + i] * hd_klems_lambda(&kq, o);
            for (int p = 0; p < 64; p++)
                for (int q = 0; q < 64; q++)
                    h += hd_bsdf_hemi(b, hd_bsdf_klems_in_dir(&kq, c, i, (p + 0.5) / 64, (q + 0.5) / 64),
                                      c < 2 ? HD_BSDF_REFL : HD_BSDF_TRANS);
            h /= 64 * 64;
            if (h < 0.02) continue;
            double d = fabs(sum - h) / h;
            mean += d;
            cnt++;
            if (d > worst) worst = d;
        }
        mean /= cnt ? cnt : 1;
        printf("  quarter-basis %s: patch sums vs source hemispherical means: mean %.3f%%, max %.3f%%\n",
               hd_bsdf_label(c), 100 * mean, 100 * worst);
        CHECK_MSG(mean < 0.004 && worst < 0.01, "%s: mean %.3f%% max %.3f%%", hd_bsdf_label(c), 100 * mean,
                  100 * worst);
    }
    REQUIRE(hd_bsdf_klems_values(b, HD_BSDF_TB, &kq, 0, ex) == HD_OK);
    REQUIRE(hd_bsdf_klems_values(b, HD_BSDF_TB, &kq, -4096, mc) == HD_OK);
    double rel = 0, ssig = 0;
    long ne = 0;
    int ns = 0;
    for (int o = 0; o < n; o++) {
        double rm = 0;
        for (int i = 0; i < n; i++) rm = fmax(rm, ex[o * n + i]);
        for (int i = 0; i < n; i++)
            if (ex[o * n + i] > 0.01 * rm) { rel += fabs(mc[o * n + i] - ex[o * n + i]) / ex[o * n + i]; ne++; }
    }
    for (int i = 0; i < n; i++) {
        double a = 0, e = 0;
        for (int o = 0; o < n; o++) { a += mc[o * n + i] * hd_klems_lambda(&kq, o); e += ex[o * n + i] * hd_klems_lambda(&kq, o); }
        if (e < 0.02) continue;
        ssig += (a - e) / e;
        ns++;
    }
    rel /= ne ? ne : 1;
    printf("  quarter-basis T: Monte Carlo (4096) vs exact: elements %.2f%%, mean signed patch sum %.3f%%\n",
           100 * rel, 100 * ssig / ns);
    CHECK_MSG(rel < 0.04, "elements %.2f%%", 100 * rel);
    CHECK_MSG(fabs(ssig / ns) < 0.005, "bias %.3f%%", 100 * ssig / ns);
    free(ex);
    free(mc);
    hd_bsdf_free(b);
}

/* T + R <= 1 (within the data's tolerance) for every incident Klems
 * direction of every file, both sides; violations are listed. */
static void test_energy(void)
{
    if (!hd_test_ref()) SKIP("no reference folder");
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    const double tol = 0.06;   /* Monte Carlo noise of genBSDF / bsdf2klems data */
    int viol = 0;
    double worst = 0;
    for (int f = 0; f < NFILES; f++) {
        hd_bsdf *b = load_ref(FILES[f]);
        REQUIRE(b);
        int nover = 0;
        for (int side = 0; side < 2; side++)
            for (int i = 0; i < kb.nbins; i++) {
                hd_vec3 v = hd_klems_dir(&kb, i, 0.5, 0.5);
                if (side) v.z = -v.z;
                double T = hd_bsdf_hemi(b, v, HD_BSDF_TRANS), R = hd_bsdf_hemi(b, v, HD_BSDF_REFL);
                if (T + R > worst) worst = T + R;
                if (T + R > 1 && ++nover <= 2) {   /* reported; fails beyond the tolerance */
                    printf("  energy: %s.xml, light from the %s, direction (%.3f %.3f %.3f) "
                           "[Klems bin %d]: T %.4f + R %.4f = %.4f > 1\n", FILES[f],
                           side ? "exterior" : "room", v.x, v.y, v.z, i, T, R, T + R);
                }
                if (T + R > 1 + tol) viol++;
            }
        if (nover > 2) printf("  energy: %s.xml: %d directions in all with T+R > 1\n", FILES[f], nover);
        hd_bsdf_free(b);
    }
    printf("  energy: largest T+R over all files and Klems directions %.4f\n", worst);
    CHECK_MSG(viol == 0, "%d directions violate T+R <= 1 + %g", viol, tol);
}

int main(void)
{
    (void)hd_test_tmpdir;
    RUN(test_checkbsdf);
    RUN(test_hemi);
    RUN(test_klems_matrices);
    RUN(test_bsdf2klems);
    RUN(test_bsdf2klems_exact);
    RUN(test_bsdf2klems_mc);
    RUN(test_klems_rebin);
    RUN(test_energy);
    RUN(test_vector_cell);
    return hd_test_done();
}

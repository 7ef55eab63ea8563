/* BSDF importance sampling: chi-square goodness of fit of sampled
 * directions against the evaluated BSDF, forward (from the light) and
 * backward (from the eye), for every reference file and several incident
 * directions; the returned pdf equals the density hd_bsdf_pdf evaluates
 * and f·|cos|/albedo; a synthetic isotropic tree exercises TensorTree3. */
#include "hd_test.h"
#include "heliodon/bsdf.h"
#include "bsdf_internal.h"
#include "heliodon/rng.h"

static const char *const FILES[] = {
    "glazing/glazing_klems", "cfs1/cfs1_klems", "cfs1/cfs1_ttree", "cfs1/cfs1_ttree_klems",
    "cfs3/cfs3_klems", "cfs3/cfs3_ttree", "cfs3/cfs3_ttree_klems"};
#define NFILES (int)(sizeof FILES / sizeof FILES[0])

static hd_vec3 dir_deg(double th, double ph, int side)
{
    double t = th * HD_PI / 180, p = ph * HD_PI / 180;
    return hd_v3(sin(t) * cos(p), sin(t) * sin(p), side * cos(t));
}

/* Chi-square of nsamp samples over the 2×145 Klems bins of both
 * hemispheres, or (gres > 0) over a gres×gres Shirley–Chiu square grid per
 * hemisphere (for anisotropic trees at their resolution the density is
 * constant on each cell, so the expected count is exact).  use_pdf:
 * expected counts from hd_bsdf_pdf (the sampler's declared density)
 * instead of f·|cos|/albedo.  Returns 0 on pass. */
static int chi2_check(const hd_bsdf *b, hd_bsdf_cache *cache, hd_vec3 g, int mode, int nsamp,
                      int use_pdf, const char *what, double *chi_out, int *dof_out, int gres)
{
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    int nb = gres > 0 ? gres * gres : 145;
    double *obs = calloc(2 * (size_t)nb, sizeof *obs), *expct = calloc(2 * (size_t)nb, sizeof *expct);
    double alb = hd_bsdf_albedo(b, cache, g, mode, HD_BSDF_ALL);
    if (!(alb > 0)) { free(obs); free(expct); return 0; }
    hd_rng r;
    hd_rng_init(&r, 99, (uint64_t)(g.x * 1e6) ^ (uint64_t)mode);
    int badpdf = 0, nfail = 0;
    for (int k = 0; k < nsamp; k++) {
        hd_bsdf_sample s;
        double u1 = hd_rng_uniform(&r), u2 = hd_rng_uniform(&r), u3 = hd_rng_uniform(&r);
        if (!hd_bsdf_sample_dir(b, cache, g, mode, HD_BSDF_ALL, u1, u2, u3, &s)) { nfail++; continue; }
        hd_vec3 v = s.dir;
        int bin;
        if (gres > 0) {
            double sx, sy;
            hd_disk2square(v.x, v.y, &sx, &sy);
            bin = (int)(sx * gres) * gres + (int)(sy * gres);
        } else bin = hd_klems_bin(&kb, hd_v3(v.x, v.y, fabs(v.z)));
        if (bin < 0) { nfail++; continue; }
        obs[bin + (v.z < 0 ? nb : 0)] += 1;
        if (k < 2000) {
            double p = hd_bsdf_pdf(b, cache, g, v, mode, HD_BSDF_ALL);
            double f = mode == HD_BSDF_FORWARD ? hd_bsdf_eval(b, g, v) : hd_bsdf_eval(b, v, g);
            if (fabs(p - s.pdf) > 1e-9 * (p + 1e-12)) badpdf++;
            else if (!use_pdf && fabs(s.pdf - f * fabs(v.z) / alb) > 1e-4 * s.pdf + 1e-9) badpdf++;
            else if (fabs(s.value - f) > 1e-4 * f + 1e-9) badpdf++;
        }
    }
    CHECK_MSG(badpdf == 0, "%s: %d samples whose pdf/value disagree with hd_bsdf_pdf / f·cos/albedo",
              what, badpdf);
    CHECK_MSG(nfail == 0, "%s: %d failed samples", what, nfail);
    /* expected counts: ∫_bin pdf dω = λ_bin · mean over the bin of pdf/|cos| */
    const int m = 12;
    for (int side = 0; side < 2 && gres > 0; side++)
        for (int bin = 0; bin < nb; bin++) {
            double x, y;
            hd_square2disk((bin / gres + 0.5) / gres, (bin % gres + 0.5) / gres, &x, &y);
            hd_vec3 v = hd_v3(x, y, (side ? -1 : 1) * sqrt(fmax(0, 1 - x * x - y * y)));
            double d = use_pdf ? hd_bsdf_pdf(b, cache, g, v, mode, HD_BSDF_ALL) / fabs(v.z)
                               : (mode == HD_BSDF_FORWARD ? hd_bsdf_eval(b, g, v) : hd_bsdf_eval(b, v, g)) / alb;
            expct[bin + nb * side] = nsamp * d * HD_PI / ((double)gres * gres);
        }
    for (int side = 0; side < 2 && gres <= 0; side++)
        for (int bin = 0; bin < kb.nbins; bin++) {
            double acc = 0;
            for (int p = 0; p < m; p++)
                for (int q = 0; q < m; q++) {
                    hd_vec3 v = hd_klems_dir(&kb, bin, (p + 0.5) / m, (q + 0.5) / m);
                    if (side) v.z = -v.z;
                    if (use_pdf)
                        acc += hd_bsdf_pdf(b, cache, g, v, mode, HD_BSDF_ALL) / fabs(v.z);
                    else
                        acc += (mode == HD_BSDF_FORWARD ? hd_bsdf_eval(b, g, v) : hd_bsdf_eval(b, v, g)) / alb;
                }
            expct[bin + 145 * side] = nsamp * hd_klems_lambda(&kb, bin) * acc / (m * m);
        }
    double chi = 0, pool_o = 0, pool_e = 0;
    int dof = -1;
    for (int i = 0; i < 2 * nb; i++) {
        if (expct[i] >= 20) {
            chi += (obs[i] - expct[i]) * (obs[i] - expct[i]) / expct[i];
            dof++;
        } else { pool_o += obs[i]; pool_e += expct[i]; }
    }
    if (pool_e >= 20) { chi += (pool_o - pool_e) * (pool_o - pool_e) / pool_e; dof++; }
    else if (pool_o > 20 + 5 * sqrt(pool_e + 1)) chi += 1e9;     /* mass where none is expected */
    *chi_out = chi;
    *dof_out = dof;
    free(obs);
    free(expct);
    /* generous bound (about 6 sigma): the expected counts come from a
     * 12×12-point quadrature of each bin */
    double lim = dof + 6 * sqrt(2.0 * (dof > 1 ? dof : 1));
    return chi > lim;
}

static void test_chi2_refs(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder");
    static const double dirs[][2] = {{0, 0}, {30, 90}, {60, 45}, {75, 200}};
    int nbad = 0, ntests = 0;
    for (int f = 0; f < NFILES; f++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/bsdf/%s.xml", ref, FILES[f]);
        hd_bsdf *b;
        REQUIRE(hd_bsdf_load(path, &b) == HD_OK);
        hd_bsdf_cache *cache = hd_bsdf_cache_new(b, 0);
        for (int d = 0; d < 4; d++)
            for (int side = -1; side <= 1; side += 2)
                for (int mode = 0; mode < 2; mode++) {
                    hd_vec3 g = dir_deg(dirs[d][0] + 0.7, dirs[d][1] + 1.3, side);
                    char what[256];
                    snprintf(what, sizeof what, "%s (%g,%g) %s %s", FILES[f], dirs[d][0], dirs[d][1],
                             side < 0 ? "exterior" : "room", mode ? "backward" : "forward");
                    double chi;
                    int dof;
                    int tr = hd_bsdf_get_info(b)->type == HD_BSDF_TREE4 ? hd_bsdf_get_info(b)->tree_res : 0;
                    int bad = chi2_check(b, cache, g, mode, 20000, 0, what, &chi, &dof, tr);
                    ntests++;
                    if (bad) {
                        nbad++;
                        printf("  chi2 %s: %.1f for %d dof\n", what, chi, dof);
                    }
                }
        hd_bsdf_cache_free(cache);
        hd_bsdf_free(b);
    }
    printf("  chi-square: %d of %d (file, direction, side, mode) cases within bounds\n",
           ntests - nbad, ntests);
    CHECK(nbad == 0);
}

/* a TensorTree3 "Transmission Back" block around the tree's text */
static const char TREE3_HEAD[] =
    "<?xml version=\"1.0\"?>\n<WindowElement><Optical><Layer><Material><Name>iso</Name></Material>"
    "<DataDefinition><IncidentDataStructure>TensorTree3</IncidentDataStructure></DataDefinition>\n"
    "<WavelengthData><Wavelength>Visible</Wavelength><WavelengthDataBlock>"
    "<WavelengthDataDirection>Transmission Back</WavelengthDataDirection><ScatteringData>";
static const char TREE3_TAIL[] =
    "</ScatteringData></WavelengthDataBlock></WavelengthData></Layer></Optical></WindowElement>\n";

/* A synthetic isotropic tree: an 8×8×8 grid (TensorTree3) with a peak
 * and a floor; forward sampling is exact, backward sampling uses the
 * grid fit (checked against its declared pdf).  Hemispherical values are
 * compared with a brute-force integration of the evaluation. */
static void test_tree3(void)
{
    static char doc[1 << 16];
    size_t n = (size_t)snprintf(doc, sizeof doc, "%s{\n", TREE3_HEAD);
    for (int i0 = 0; i0 < 8; i0++)
        for (int i1 = 0; i1 < 8; i1++) {
            for (int i2 = 0; i2 < 8; i2++) {
                double v = 0.02 + 0.01 * i0;
                if (i1 >= 4 && i1 <= 5 && i2 >= 3 && i2 <= 4) v += 0.8 + 0.1 * i0;  /* forward peak */
                n += (size_t)snprintf(doc + n, sizeof doc - n, "%.4f ", v);
            }
            doc[n++] = '\n';
        }
    snprintf(doc + n, sizeof doc - n, "}%s", TREE3_TAIL);
    hd_bsdf *b;
    hd_status st = hd_bsdf_load_memory(doc, strlen(doc), "iso.xml", &b);
    REQUIRE(st == HD_OK);
    CHECK(hd_bsdf_get_info(b)->type == HD_BSDF_TREE3);
    hd_bsdf_cache *cache = hd_bsdf_cache_new(b, 0);
    /* isotropy: rotating both vectors about z leaves f unchanged */
    hd_vec3 vi = dir_deg(40, 10, 1), vo = dir_deg(20, 200, -1);
    double f0 = hd_bsdf_eval(b, vi, vo);
    hd_vec3 vi2 = dir_deg(40, 10 + 77, 1), vo2 = dir_deg(20, 200 + 77, -1);
    CHECK_NEAR(hd_bsdf_eval(b, vi2, vo2), f0, 1e-6);
    /* hemispherical transmittance against brute force on a fine grid */
    for (int k = 0; k < 3; k++) {
        hd_vec3 g = dir_deg(10 + 25 * k, 30 * k, 1);
        double h = hd_bsdf_hemi(b, g, HD_BSDF_TRANS), s = 0;
        const int N = 400;
        for (int p = 0; p < N; p++)
            for (int q = 0; q < N; q++) {
                double x, y;
                hd_square2disk((p + 0.5) / N, (q + 0.5) / N, &x, &y);
                s += hd_bsdf_eval(b, g, hd_v3(x, y, -sqrt(fmax(0, 1 - x * x - y * y))));
            }
        s *= HD_PI / ((double)N * N);
        CHECK_MSG(fabs(h - s) < 0.01 * s, "tree3 hemi %g vs brute force %g", h, s);
    }
    double chi;
    int dof;
    for (int k = 0; k < 3; k++) {
        /* exact cases: light from the room (forward) and eye in the room
         * (backward, transmission by reciprocity) */
        hd_vec3 g = dir_deg(15 + 25 * k, 20 + 50 * k, 1);
        CHECK_MSG(!chi2_check(b, cache, g, HD_BSDF_FORWARD, 20000, 0, "tree3 forward", &chi, &dof, 0),
                  "tree3 forward: chi2 %.1f dof %d", chi, dof);
        CHECK_MSG(!chi2_check(b, cache, g, HD_BSDF_BACKWARD, 20000, 0, "tree3 backward", &chi, &dof, 0),
                  "tree3 backward: chi2 %.1f dof %d", chi, dof);
        /* grid-fit cases (the data's outgoing role is fixed): checked
         * against the declared pdf */
        hd_vec3 ge = dir_deg(15 + 25 * k, 20 + 50 * k, -1);
        CHECK_MSG(!chi2_check(b, cache, ge, HD_BSDF_FORWARD, 20000, 1, "tree3 fit forward", &chi, &dof, 64),
                  "tree3 fit forward: chi2 %.1f dof %d", chi, dof);
        CHECK_MSG(!chi2_check(b, cache, ge, HD_BSDF_BACKWARD, 20000, 1, "tree3 fit backward", &chi, &dof, 64),
                  "tree3 fit backward: chi2 %.1f dof %d", chi, dof);
        /* the fit is close to the evaluated BSDF: albedo within 2 % of
         * the brute-force integral of f over the sampled side */
        double alb = hd_bsdf_albedo(b, cache, ge, HD_BSDF_FORWARD, HD_BSDF_TRANS), s = 0;
        const int N = 300;
        for (int p = 0; p < N; p++)
            for (int q = 0; q < N; q++) {
                double x, y;
                hd_square2disk((p + 0.5) / N, (q + 0.5) / N, &x, &y);
                s += hd_bsdf_eval(b, ge, hd_v3(x, y, sqrt(fmax(0, 1 - x * x - y * y))));
            }
        s *= HD_PI / ((double)N * N);
        CHECK_MSG(fabs(alb - s) < 0.02 * s, "tree3 fit albedo %g vs brute force %g", alb, s);
    }
    hd_bsdf_cache_free(cache);
    hd_bsdf_free(b);
}

/* ---- isotropic tree sampled on its data-incident role (rings) ----
 * A TensorTree3 of 32² cells per hemisphere with irregular refinement
 * (leaves of five sizes) and cell-to-cell noise: sampling on the incident
 * role (backward through the direct transmission, forward through the
 * reciprocal one) must follow the tree's own values exactly: chi-square of
 * the sampled directions against f·|cos|/albedo over the Klems bins, the
 * albedo against a brute-force integral (0.5 %), first moments of the
 * sampled directions against brute force, for vectors at the centre
 * (normal), 10⁻⁷ either side of a ring boundary (exactly on it the point
 * evaluation itself reads either ring, by rounding in its rotation),
 * grazing and elsewhere. */
static uint64_t hmix(uint64_t k)
{
    k ^= k >> 31; k *= 0x9e3779b97f4a7c15ULL; k ^= k >> 29; k *= 0xbf58476d1ce4e5b9ULL; k ^= k >> 32;
    return k;
}

static size_t ring_gen(char *doc, size_t n, size_t cap, int level, const double *lo, double s)
{
    uint64_t h = hmix((uint64_t)(lo[0] * 4096) * 1000003u + (uint64_t)(lo[1] * 4096) * 7919u +
                      (uint64_t)(lo[2] * 4096) + (uint64_t)level * 0x1234567u);
    int split = level < 2 || (level < 4 && h % 3 != 0);
    if (split && level < 4) {
        n += (size_t)snprintf(doc + n, cap - n, "{\n");
        for (int c = 0; c < 8; c++) {
            double l2[3];
            for (int d = 0; d < 3; d++) l2[d] = lo[d] + ((c >> d) & 1 ? s / 2 : 0);
            n = ring_gen(doc, n, cap, level + 1, l2, s / 2);
        }
        return n + (size_t)snprintf(doc + n, cap - n, "}\n");
    }
    n += (size_t)snprintf(doc + n, cap - n, "{");
    int grid = level == 4 && h % 2;         /* a 2³ grid of the finest cells */
    for (int k = 0; k < (grid ? 8 : 1); k++) {
        double c[3];
        for (int d = 0; d < 3; d++) c[d] = lo[d] + (grid ? (((k >> (2 - d)) & 1) + 0.5) * s / 2 : s / 2);
        double dx = c[1] - (1 - c[0]), dy = c[2] - 0.5;
        double v = 0.3 * (0.5 + (double)(hmix(h + (uint64_t)k) % 1000) / 1000.0) +
                   3 * exp(-(dx * dx + dy * dy) / (2 * 0.08 * 0.08));
        n += (size_t)snprintf(doc + n, cap - n, " %.5f", v);
    }
    return n + (size_t)snprintf(doc + n, cap - n, " }\n");
}

/* The ring tree's XML document (ring_gen over the whole tree), made once. */
static const char *ring_tree_doc(void)
{
    static char doc[1 << 20];
    if (doc[0]) return doc;
    size_t n = (size_t)snprintf(doc, sizeof doc, "%s\n", TREE3_HEAD);
    double lo[3] = {0, 0, 0};
    n = ring_gen(doc, n, sizeof doc, 0, lo, 1.0);
    snprintf(doc + n, sizeof doc - n, "%s", TREE3_TAIL);
    return doc;
}

static void test_tree3_rings(void)
{
    const char *doc = ring_tree_doc();
    hd_bsdf *b;
    REQUIRE(hd_bsdf_load_memory(doc, strlen(doc), "rings.xml", &b) == HD_OK);
    REQUIRE(hd_bsdf_get_info(b)->tree_res == 32);
    hd_bsdf_cache *cache = hd_bsdf_cache_new(b, 0);
    /* given vectors on the exterior side (z < 0): the normal, |b| just
     * inside ring 5 (square point 0.5 + 5/32) and just outside, grazing,
     * others */
    hd_vec3 gs[7];
    double x, y;
    gs[0] = hd_v3(0, 0, -1);
    hd_square2disk(0.5 + 5.0 / 32 + 1e-7, 0.5 + 0.37 / 32, &x, &y);
    gs[1] = hd_v3(x, y, -sqrt(1 - x * x - y * y));
    hd_square2disk(0.5 - 0.37 / 32, 0.5 - 5.0 / 32 + 1e-7, &x, &y);
    gs[6] = hd_v3(x, y, -sqrt(1 - x * x - y * y));
    gs[2] = dir_deg(85, 123, -1);
    gs[3] = dir_deg(20, 10, -1);
    gs[4] = dir_deg(47, 250, -1);
    gs[5] = dir_deg(0.3, 40, -1);
    for (int i = 0; i < 7; i++)
        for (int mode = 0; mode < 2; mode++) {
            hd_vec3 g = gs[i];
            char what[96];
            snprintf(what, sizeof what, "rings: given %d %s", i, mode ? "backward" : "forward");
            double chi;
            int dof;
            CHECK_MSG(!chi2_check(b, cache, g, mode, 20000, 0, what, &chi, &dof, 0), "%s: chi2 %.1f for %d dof",
                      what, chi, dof);
            /* brute force: albedo and first moments of the sampled role */
            const int N = 500;
            double s0 = 0, sx = 0, sy = 0, sz = 0;
            for (int p = 0; p < N; p++)
                for (int q = 0; q < N; q++) {
                    hd_square2disk((p + 0.5) / N, (q + 0.5) / N, &x, &y);
                    hd_vec3 v = hd_v3(x, y, sqrt(fmax(0, 1 - x * x - y * y)));
                    double f = mode == HD_BSDF_FORWARD ? hd_bsdf_eval(b, g, v) : hd_bsdf_eval(b, v, g);
                    s0 += f; sx += f * v.x; sy += f * v.y; sz += f * v.z;
                }
            double m = HD_PI / ((double)N * N);
            s0 *= m; sx *= m; sy *= m; sz *= m;
            double alb = hd_bsdf_albedo(b, cache, g, mode, HD_BSDF_ALL);
            CHECK_MSG(fabs(alb - s0) < 0.005 * s0, "%s: albedo %.5f vs brute force %.5f", what, alb, s0);
            hd_rng r;
            hd_rng_init(&r, 23, (uint64_t)(i * 2 + mode));
            const int M = 40000;
            double mx = 0, my = 0, mz = 0;
            for (int k = 0; k < M; k++) {
                hd_bsdf_sample smp;
                if (!hd_bsdf_sample_dir(b, cache, g, mode, HD_BSDF_ALL, hd_rng_uniform(&r), hd_rng_uniform(&r),
                                        hd_rng_uniform(&r), &smp))
                    continue;
                mx += smp.weight * smp.dir.x; my += smp.weight * smp.dir.y; mz += smp.weight * smp.dir.z;
            }
            mx /= M; my /= M; mz /= M;
            /* |dir| <= 1, weight = albedo: standard error <= albedo/sqrt(M) */
            double tol = 4 * alb / sqrt((double)M) + 0.005 * s0;
            CHECK_MSG(fabs(mx - sx) < tol && fabs(my - sy) < tol && fabs(mz - sz) < tol,
                      "%s: moments (%.4f %.4f %.4f) vs brute force (%.4f %.4f %.4f)", what, mx, my, mz, sx, sy,
                      sz);
        }
    /* the same samples with a private cache, a tiny one and none */
    hd_bsdf_cache *c2 = hd_bsdf_cache_new(b, 100000);
    int diff = 0;
    for (int k = 0; k < 2000; k++) {
        hd_vec3 g = dir_deg(89.0 * k / 2000, 7.3 * k, -1);
        double u1 = (k * 0.618034) - (int)(k * 0.618034), u2 = (k * 0.7548777) - (int)(k * 0.7548777);
        hd_bsdf_sample a, bb, cc;
        int ra = hd_bsdf_sample_dir(b, cache, g, k % 2, HD_BSDF_ALL, u1, u2, 0.37, &a);
        int rb = hd_bsdf_sample_dir(b, c2, g, k % 2, HD_BSDF_ALL, u1, u2, 0.37, &bb);
        int rc = hd_bsdf_sample_dir(b, NULL, g, k % 2, HD_BSDF_ALL, u1, u2, 0.37, &cc);
        if (ra != rb || ra != rc || a.dir.x != bb.dir.x || a.dir.x != cc.dir.x || a.pdf != bb.pdf || a.pdf != cc.pdf)
            diff++;
    }
    CHECK(diff == 0);
    /* the totals come from one traversal (no slice built for them): equal
     * to the sums of every ring slice of both blocks */
    int nchk = 0;
    for (int c = 0; c < 4; c++) {
        const hd_bsdf_block *d = b->blk[c];
        if (!d || d->kind != 3) continue;
        double e = hd_block_ring_sums_check(d);
        CHECK_MSG(e >= 0 && e < 1e-12, "ring sums of block %d: relative difference %g", c, e);
        nchk++;
    }
    CHECK(nchk >= 1);
    /* a draw on a dropped side returns 0, the others are the same draws */
    int ndrop = 0, nkept = 0;
    for (int k = 0; k < 4000; k++) {
        hd_vec3 g = dir_deg(89.0 * k / 4000, 13.1 * k, k % 3 ? -1 : 1);
        double u1 = (k * 0.618034) - (int)(k * 0.618034), u2 = (k * 0.7548777) - (int)(k * 0.7548777);
        int drop = k % 2 ? HD_BSDF_TRANS : HD_BSDF_REFL;
        hd_bsdf_sample a, d2;
        int ra = hd_bsdf_sample_dir(b, cache, g, k % 4 < 2, HD_BSDF_ALL, u1, u2, 0.61, &a);
        int rd = hd_bsdf_sample_drop(b, cache, g, k % 4 < 2, HD_BSDF_ALL, drop, 1, u1, u2, 0.61, &d2);
        int side = a.dir.z * g.z > 0 ? HD_BSDF_REFL : HD_BSDF_TRANS;
        if (ra && (side & drop)) { CHECK(rd == 0); ndrop++; }
        else if (ra) {
            CHECK(rd && a.dir.x == d2.dir.x && a.dir.z == d2.dir.z && a.pdf == d2.pdf && a.weight == d2.weight);
            nkept++;
        }
    }
    CHECK(ndrop > 100 && nkept > 100);
    hd_bsdf_cache_free(c2);
    hd_bsdf_cache_free(cache);
    hd_bsdf_free(b);
}

/* CFS1's tensor tree or Klems data (kind "ttree", "klems") from the reference folder (the caller
 * skips when there is none), NULL if it does not load */
static hd_bsdf *cfs1(const char *kind)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/bsdf/cfs1/cfs1_%s.xml", hd_test_ref(), kind);
    hd_bsdf *b = NULL;
    return hd_bsdf_load(path, &b) == HD_OK ? b : NULL;
}

/* Results do not depend on the cache state (determinism). */
static void test_cache_independent(void)
{
    if (!hd_test_ref()) SKIP("no reference folder");
    hd_bsdf *b = cfs1("ttree");
    REQUIRE(b);
    hd_bsdf_cache *c1 = hd_bsdf_cache_new(b, 0), *c2 = hd_bsdf_cache_new(b, 200000);
    hd_rng r;
    hd_rng_init(&r, 5, 0);
    int diff = 0;
    for (int k = 0; k < 3000; k++) {
        hd_vec3 g = dir_deg(80 * hd_rng_uniform(&r), 360 * hd_rng_uniform(&r), k % 2 ? 1 : -1);
        double u1 = hd_rng_uniform(&r), u2 = hd_rng_uniform(&r), u3 = hd_rng_uniform(&r);
        hd_bsdf_sample a, bb, cc;
        int ra = hd_bsdf_sample_dir(b, c1, g, k % 3 ? HD_BSDF_FORWARD : HD_BSDF_BACKWARD, HD_BSDF_ALL, u1, u2, u3, &a);
        int rb = hd_bsdf_sample_dir(b, c2, g, k % 3 ? HD_BSDF_FORWARD : HD_BSDF_BACKWARD, HD_BSDF_ALL, u1, u2, u3, &bb);
        int rc = hd_bsdf_sample_dir(b, NULL, g, k % 3 ? HD_BSDF_FORWARD : HD_BSDF_BACKWARD, HD_BSDF_ALL, u1, u2, u3, &cc);
        if (ra != rb || ra != rc || a.dir.x != bb.dir.x || a.dir.x != cc.dir.x || a.pdf != bb.pdf ||
            a.pdf != cc.pdf)
            diff++;
    }
    CHECK(diff == 0);
    /* photon emission: vectors jittered within a sun's disk (same fixed cells, the memo's
     * slices reused) between the queries of other hits, as mkpmap asks them */
    diff = 0;
    int same = 0;
    for (int k = 0; k < 3000; k++) {
        int sun = k % 3 == 0;
        hd_vec3 g = sun ? dir_deg(35 + 0.25 * hd_rng_uniform(&r), 200 + 0.25 * hd_rng_uniform(&r), -1)
                        : dir_deg(80 * hd_rng_uniform(&r), 360 * hd_rng_uniform(&r), k % 2 ? 1 : -1);
        int mode = sun || k % 5 ? HD_BSDF_FORWARD : HD_BSDF_BACKWARD;
        double u1 = hd_rng_uniform(&r), u2 = hd_rng_uniform(&r), u3 = hd_rng_uniform(&r);
        hd_bsdf_sample a, cc;
        int ra = hd_bsdf_sample_dir(b, c1, g, mode, HD_BSDF_ALL, u1, u2, u3, &a);
        int rc = hd_bsdf_sample_dir(b, NULL, g, mode, HD_BSDF_ALL, u1, u2, u3, &cc);
        if (ra != rc || a.dir.x != cc.dir.x || a.dir.y != cc.dir.y || a.dir.z != cc.dir.z || a.pdf != cc.pdf ||
            a.value != cc.value || a.weight != cc.weight)
            diff++;
        same += sun && ra;
    }
    CHECK_MSG(diff == 0, "%d of 3000 samples depend on the cache", diff);
    CHECK(same > 900);
    hd_bsdf_cache_free(c1);
    hd_bsdf_cache_free(c2);
    hd_bsdf_free(b);
}

/* The evaluation's memo of the last vector of each role (a window pixel's view against every sun):
 * a grid of (in, out) pairs evaluated row by row (the in vector repeated) and column by column (the
 * out vector repeated) gives the same values; vectors with -0 and +0 components are told apart. */
static void test_eval_order(void)
{
    if (!hd_test_ref()) SKIP("no reference folder");
    hd_bsdf *b = cfs1("ttree");
    REQUIRE(b);
    enum { N = 24 };
    hd_vec3 in[N], out[N];
    hd_rng r;
    hd_rng_init(&r, 11, 0);
    for (int i = 0; i < N; i++) {
        in[i] = dir_deg(85 * hd_rng_uniform(&r), 360 * hd_rng_uniform(&r), 1);
        out[i] = dir_deg(85 * hd_rng_uniform(&r), 360 * hd_rng_uniform(&r), i % 2 ? 1 : -1);
    }
    in[0] = hd_v3(0.0, 0.0, 1);             /* the normal, both signs of zero */
    in[1] = hd_v3(-0.0, -0.0, 1);
    out[0] = hd_v3(0.0, -0.0, -1);
    out[1] = hd_v3(-0.0, 0.0, -1);
    double rows[N][N], cols[N][N];
    for (int i = 0; i < N; i++)
        for (int j = 0; j < N; j++) rows[i][j] = hd_bsdf_eval(b, in[i], out[j]);
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++) cols[i][j] = hd_bsdf_eval(b, in[i], out[j]);
    int diff = 0, nz = 0;
    for (int i = 0; i < N; i++)
        for (int j = 0; j < N; j++) {
            diff += memcmp(&rows[i][j], &cols[i][j], sizeof(double)) != 0;
            nz += rows[i][j] > 0;
        }
    CHECK_MSG(diff == 0, "%d of %d values depend on the evaluation order", diff, N * N);
    CHECK(nz > N * N / 4);
    hd_bsdf_free(b);
}

/* hd_bsdf_hemi_parts (the -st threshold's value: load-time tables for data
 * in the file, the sampler's slice for reciprocal data) against the forward
 * albedo of the exact sampling structures, per side: the reference files
 * (Klems and trees) and the ring tree, both sides, several vectors. */
static void test_hemi_parts(void)
{
    const char *doc = ring_tree_doc();
    const char *ref = hd_test_ref();
    static const double dirs[][2] = {{0, 0}, {20, 10}, {47, 250}, {75, 200}, {85, 123}};
    int ncmp = 0;
    for (int f = -1; f < NFILES; f++) {
        hd_bsdf *b;
        if (f < 0) {
            REQUIRE(hd_bsdf_load_memory(doc, strlen(doc), "rings.xml", &b) == HD_OK);
        } else {
            if (!ref) break;
            char path[1024];
            snprintf(path, sizeof path, "%s/bsdf/%s.xml", ref, FILES[f]);
            REQUIRE(hd_bsdf_load(path, &b) == HD_OK);
        }
        hd_bsdf_cache *cache = hd_bsdf_cache_new(b, 0);
        for (int d = 0; d < 5; d++)
            for (int side = -1; side <= 1; side += 2) {
                hd_vec3 g = dir_deg(dirs[d][0] + 0.7, dirs[d][1] + 1.3, side);
                double w[4];
                double tot = hd_bsdf_hemi_parts(b, cache, g, w);
                double r = hd_bsdf_albedo(b, cache, g, HD_BSDF_FORWARD, HD_BSDF_REFL);
                double t = hd_bsdf_albedo(b, cache, g, HD_BSDF_FORWARD, HD_BSDF_TRANS);
                CHECK_NEAR(w[0] + w[1], r, 1e-6 + 1e-4 * r);
                CHECK_NEAR(w[2] + w[3], t, 1e-6 + 1e-4 * t);
                CHECK_NEAR(tot, r + t, 1e-6 + 1e-4 * (r + t));
                ncmp++;
            }
        hd_bsdf_cache_free(cache);
        hd_bsdf_free(b);
    }
    printf("  hemispherical parts: %d vectors compared\n", ncmp);
}

/* The sampling tables (cells, guides) come from hd_big_alloc: a Klems
 * slice (145 cells of 32 bytes) is refused under a 1 KiB allocation limit
 * and the draw fails with the limit's message (aligned_alloc bypassed the
 * limit); with the limit restored the same draw succeeds. */
static void test_alloc_limit(void)
{
    if (!hd_test_ref()) SKIP("no reference folder");
    hd_bsdf *b = cfs1("klems");
    REQUIRE(b);
    hd_vec3 g = dir_deg(30, 40, 1);
    hd_bsdf_sample s;
    size_t lim = hd_alloc_limit();
    hd_set_alloc_limit(1024);
    hd_clear_error();
    int ok = hd_bsdf_sample_dir(b, NULL, g, HD_BSDF_BACKWARD, HD_BSDF_ALL, 0.3, 0.5, 0.5, &s);
    hd_set_alloc_limit(lim);
    CHECK_MSG(!ok, "a draw succeeded although its table exceeds the allocation limit");
    CHECK_MSG(strstr(hd_errmsg(), "refusing to allocate") != NULL, "message '%s'", hd_errmsg());
    CHECK(hd_bsdf_sample_dir(b, NULL, g, HD_BSDF_BACKWARD, HD_BSDF_ALL, 0.3, 0.5, 0.5, &s) == 1);
    hd_bsdf_free(b);
}

/* -ss below 1 (hd_bsdf_sample_drop's narrow): a draw on the data's
 * directional part takes the cell at 0.5 + narrow·(u1 - 0.5) of the part's
 * distribution; narrow 0 is one cell for every u1 (with the point in the
 * cell fixed by u2, u3: one direction), narrow 1 the whole distribution;
 * the weight (the part's total) does not change */
static void test_narrow(void)
{
    if (!hd_test_ref()) SKIP("no reference folder");
    hd_bsdf *b = cfs1("klems");
    REQUIRE(b);
    hd_vec3 g = dir_deg(30, 40, 1);
    hd_vec3 first = {0, 0, 0};
    int nd = 0, distinct1 = 0, same0 = 1;
    double wt = -1;
    hd_vec3 prev1 = {0, 0, 0};
    for (int k = 0; k < 64; k++) {
        double u1 = (k + 0.5) / 64;
        hd_bsdf_sample s0, s1;
        REQUIRE(hd_bsdf_sample_drop(b, NULL, g, HD_BSDF_BACKWARD, HD_BSDF_TRANS, 0, 0, u1, 0.3, 0.7, &s0));
        REQUIRE(hd_bsdf_sample_drop(b, NULL, g, HD_BSDF_BACKWARD, HD_BSDF_TRANS, 0, 1, u1, 0.3, 0.7, &s1));
        if (!s1.lambertian && (s1.dir.x != prev1.x || s1.dir.y != prev1.y)) distinct1++;
        if (!s1.lambertian) prev1 = s1.dir;
        if (s0.lambertian) continue;
        if (!nd++) { first = s0.dir; wt = s0.weight; }
        else if (s0.dir.x != first.x || s0.dir.y != first.y || s0.dir.z != first.z || s0.weight != wt) same0 = 0;
        if (!s1.lambertian) CHECK(s1.weight == s0.weight);
    }
    CHECK(nd > 32);
    CHECK(same0);
    CHECK_MSG(distinct1 >= 8, "%d distinct cells without narrowing", distinct1);
    hd_bsdf_free(b);
}

int main(void)
{
    (void)hd_test_tmpdir;
    RUN(test_chi2_refs);
    RUN(test_tree3);
    RUN(test_tree3_rings);
    RUN(test_cache_independent);
    RUN(test_eval_order);
    RUN(test_hemi_parts);
    RUN(test_alloc_limit);
    RUN(test_narrow);
    return hd_test_done();
}

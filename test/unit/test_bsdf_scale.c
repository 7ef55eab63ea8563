/* Tensor-tree sampling cost per query does not grow with the tree: the
 * same synthetic isotropic tree (a broad lobe refined with cell-to-cell
 * noise around a transmission peak, a Lambertian floor, a room-side
 * reflection block) at 64², 256² and 512² cells per hemisphere; 10⁵
 * importance samples for random vectors on the room side (forward, and
 * backward: the reciprocal transmission and the room-side reflection on
 * its data-incident role, all sampled exactly from shared distributions)
 * once they exist take at most 2× the time at 512² they take at 64²
 * (issue 17; thread CPU time, the minimum of several repeats, so that a
 * loaded machine does not fail it).
 * Correctness at every size: the mean sample weight f·|cos|/pdf equals the
 * brute-force integral of the evaluated BSDF over the sampled hemispheres
 * (forward, and backward on both roles of the data), and the
 * returned pdf is the one hd_bsdf_pdf evaluates. */
#include <time.h>

#include "hd_test.h"
#include "heliodon/bsdf.h"
#include "heliodon/rng.h"

/* ---- the synthetic tree, written to memory ---- */
typedef struct { char *p; size_t n, cap; } sbuf;

static void put(sbuf *b, const char *s)
{
    size_t l = strlen(s);
    if (b->n + l + 1 > b->cap) {
        b->cap = (b->n + l + 1) * 2;
        b->p = realloc(b->p, b->cap);
        if (!b->p) abort();
    }
    memcpy(b->p + b->n, s, l + 1);
    b->n += l;
}

static int MAXLEV, REFL;

/* the lobe: transmission centred on c1 = 1 - c0 (the straight-through
 * direction in the tree's turned frame), c2 = 0.5 */
static double lobe(const double *c)
{
    double dx = c[1] - (1 - c[0]) + (REFL ? 0.2 : 0), dy = c[2] - 0.5;
    return 0.05 + 8 * exp(-(dx * dx + dy * dy) / (2 * 0.03 * 0.03));
}

static int near_lobe(const double *lo, double s)
{
    double e = 0.06;
    double a0 = lo[1] - (1 - lo[0]) + (REFL ? 0.2 : 0), a1 = a0 + 2 * s;
    return a0 - s < e && a1 > -e && lo[2] < 0.5 + e && lo[2] + s > 0.5 - e && lo[0] < 0.5;
}

/* deterministic noise in [0.8, 1.2) per finest cell (keeps the leaves
 * from merging, as in measured or Monte-Carlo data) */
static double noise(const double *c)
{
    uint64_t k = 0;
    for (int d = 0; d < 3; d++) k = k * 1315423911u + (uint64_t)(c[d] * (1 << MAXLEV));
    k ^= k >> 29; k *= 0xbf58476d1ce4e5b9ULL; k ^= k >> 32;
    return 0.8 + 0.4 * (double)(k & 0xffff) / 65536.0;
}

static void gen(sbuf *b, int level, const double *lo, double s)
{
    char tmp[64];
    if (level < MAXLEV - 1 && near_lobe(lo, s)) {
        put(b, "{\n");
        for (int n = 0; n < 8; n++) {
            double l2[3];
            for (int d = 0; d < 3; d++) l2[d] = lo[d] + ((n >> d) & 1 ? s / 2 : 0);
            gen(b, level + 1, l2, s / 2);
        }
        put(b, "}\n");
        return;
    }
    if (level == MAXLEV - 1 && near_lobe(lo, s)) {
        put(b, "{");
        for (int idx = 0; idx < 8; idx++) {
            double c[3];
            for (int d = 0; d < 3; d++) c[d] = lo[d] + (((idx >> (2 - d)) & 1) + 0.5) * s / 2;
            snprintf(tmp, sizeof tmp, " %.4g", lobe(c) * noise(c));
            put(b, tmp);
        }
        put(b, " }\n");
        return;
    }
    double c[3];
    for (int d = 0; d < 3; d++) c[d] = lo[d] + s / 2;
    snprintf(tmp, sizeof tmp, "{ %.4g }\n", lobe(c));
    put(b, tmp);
}

static hd_bsdf *make_tree(int maxlev, size_t *bytes)
{
    sbuf b = {0};
    double lo[3] = {0, 0, 0};
    put(&b, "<?xml version=\"1.0\"?>\n<WindowElement><Optical><Layer><Material><Name>scale</Name></Material>"
            "<DataDefinition><IncidentDataStructure>TensorTree3</IncidentDataStructure></DataDefinition>\n");
    MAXLEV = maxlev;
    for (REFL = 0; REFL < 2; REFL++) {
        put(&b, "<WavelengthData><Wavelength>Visible</Wavelength><WavelengthDataBlock><WavelengthDataDirection>");
        put(&b, REFL ? "Reflection Back" : "Transmission Back");
        put(&b, "</WavelengthDataDirection><ScatteringData>\n");
        gen(&b, 0, lo, 1.0);
        put(&b, "</ScatteringData></WavelengthDataBlock></WavelengthData>\n");
    }
    put(&b, "</Layer></Optical></WindowElement>\n");
    *bytes = b.n;
    hd_bsdf *bs = NULL;
    if (hd_bsdf_load_memory(b.p, b.n, "scale.xml", &bs) != HD_OK) bs = NULL;
    free(b.p);
    return bs;
}

static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

#define NQ 100000

/* NQ samples for random given vectors (the same sequence at every size) */
static double run_samples(const hd_bsdf *b, hd_bsdf_cache *c, uint64_t seed, double *wsum)
{
    hd_rng r;
    hd_rng_init(&r, seed, 3);
    double acc = 0, t0 = cpu_now();
    for (int k = 0; k < NQ; k++) {
        double u = hd_rng_uniform(&r), p = 2 * HD_PI * hd_rng_uniform(&r);
        hd_vec3 g = hd_v3(sqrt(u) * cos(p), sqrt(u) * sin(p), sqrt(1 - u));
        hd_bsdf_sample s;
        if (hd_bsdf_sample_dir(b, c, g, k & 1 ? HD_BSDF_BACKWARD : HD_BSDF_FORWARD, HD_BSDF_ALL,
                               hd_rng_uniform(&r), hd_rng_uniform(&r), hd_rng_uniform(&r), &s))
            acc += s.weight;
    }
    if (wsum) *wsum = acc;
    return cpu_now() - t0;
}

/* ∫ f(in, out)|cos| over both hemispheres of the sampled role, brute force */
static double brute(const hd_bsdf *b, hd_vec3 g, int mode)
{
    const int N = 400;
    double s = 0;
    for (int side = -1; side <= 1; side += 2)
        for (int p = 0; p < N; p++)
            for (int q = 0; q < N; q++) {
                double x, y;
                hd_square2disk((p + 0.5) / N, (q + 0.5) / N, &x, &y);
                hd_vec3 v = hd_v3(x, y, side * sqrt(fmax(0, 1 - x * x - y * y)));
                s += mode == HD_BSDF_FORWARD ? hd_bsdf_eval(b, g, v) : hd_bsdf_eval(b, v, g);
            }
    return s * HD_PI / ((double)N * N);
}

/* mean weight of n samples (mean and standard error) and pdf agreement */
static void mean_weight(const hd_bsdf *b, hd_bsdf_cache *c, hd_vec3 g, int mode, int n, double *m,
                        double *se, int *badpdf)
{
    hd_rng r;
    hd_rng_init(&r, 17, (uint64_t)mode);
    double s1 = 0, s2 = 0;
    for (int k = 0; k < n; k++) {
        hd_bsdf_sample s;
        double w = 0;
        if (hd_bsdf_sample_dir(b, c, g, mode, HD_BSDF_ALL, hd_rng_uniform(&r), hd_rng_uniform(&r),
                               hd_rng_uniform(&r), &s)) {
            w = s.weight;
            double f = mode == HD_BSDF_FORWARD ? hd_bsdf_eval(b, g, s.dir) : hd_bsdf_eval(b, s.dir, g);
            if (fabs(w - f * fabs(s.dir.z) / s.pdf) > 1e-6 * w) ++*badpdf;
            if (k < 500) {
                double p = hd_bsdf_pdf(b, c, g, s.dir, mode, HD_BSDF_ALL);
                if (fabs(p - s.pdf) > 1e-9 * s.pdf) ++*badpdf;
            }
        }
        s1 += w;
        s2 += w * w;
    }
    *m = s1 / n;
    *se = sqrt(fmax(0, s2 / n - *m * *m) / n);
}

static void test_flat_cost(void)
{
    static const int levs[3] = {6, 8, 9};
    hd_bsdf *b[3] = {NULL, NULL, NULL};
    hd_bsdf_cache *c[3] = {NULL, NULL, NULL};
    double tmin[3], tcold[3];
    size_t bytes[3];
    for (int i = 0; i < 3; i++) {
        b[i] = make_tree(levs[i], &bytes[i]);
        REQUIRE(b[i]);
        REQUIRE(hd_bsdf_get_info(b[i])->tree_res == 1 << levs[i]);
        c[i] = hd_bsdf_cache_new(b[i], 0);
        double wsum;
        tcold[i] = run_samples(b[i], c[i], 1, &wsum);     /* builds the distributions */
        tmin[i] = HUGE_VAL;
    }
    /* the sizes in turn (a drifting machine load hits all of them), the
     * fastest of several passes each; on a loaded machine the large trees'
     * memory latency suffers most from other processes' cache traffic, so a
     * failed ratio gets up to two more rounds of passes (the fastest pass
     * still has to meet it) */
    for (int round = 0; round < 3; round++) {
        for (int rep = 0; rep < 7; rep++)
            for (int i = 0; i < 3; i++) {
                double t = run_samples(b[i], c[i], 2 + (uint64_t)(7 * round + rep), NULL);
                if (t < tmin[i]) tmin[i] = t;
            }
        if (tmin[2] < 2 * tmin[0] && tmin[1] < 2 * tmin[0]) break;
    }
    for (int i = 0; i < 3; i++)
        printf("  %3d²: %.1f MB XML, %.1f MB loaded; 10^5 samples %.3f s CPU (first pass %.3f s)\n",
               1 << levs[i], bytes[i] / 1e6, hd_bsdf_memory(b[i]) / 1e6, tmin[i], tcold[i]);
    printf("  time per 10^5 samples, 512² / 64²: %.2f (256² / 64²: %.2f)\n", tmin[2] / tmin[0], tmin[1] / tmin[0]);
    /* issue 17: within 2× (measured 1.7–1.8× at load 17: what still grows
     * is memory latency, one guide or alias entry per sample, sometimes a
     * cell, and the tree descent of a Lambertian draw's point value) */
    CHECK_MSG(tmin[2] < 2 * tmin[0] && tmin[1] < 2 * tmin[0],
              "sampling cost grows with the tree: %.3f s at 64², %.3f s at 256², %.3f s at 512²", tmin[0],
              tmin[1], tmin[2]);
    /* correctness at every size: light from the room (forward), eye in
     * the room (backward: reciprocal transmission, and the reflection on
     * its data-incident role by rings) */
    for (int i = 0; i < 3; i++) {
        static const double th[3] = {10, 35, 60};
        int bad = 0;
        for (int k = 0; k < 3; k++)
            for (int mode = 0; mode < 2; mode++) {
                hd_vec3 g = hd_v3(sin(th[k] * HD_PI / 180) * cos(0.3 + k), sin(th[k] * HD_PI / 180) * sin(0.3 + k),
                                  cos(th[k] * HD_PI / 180));
                double m, se, ref = brute(b[i], g, mode);
                mean_weight(b[i], c[i], g, mode, 20000, &m, &se, &bad);
                CHECK_MSG(fabs(m - ref) < 4 * se + 0.003 * ref,
                          "%d², theta %g, %s: mean weight %.5f ± %.5f vs brute-force integral %.5f",
                          1 << levs[i], th[k], mode ? "backward" : "forward", m, se, ref);
                double alb = hd_bsdf_albedo(b[i], c[i], g, mode, HD_BSDF_ALL);
                CHECK_MSG(fabs(alb - ref) < 0.02 * ref, "%d², theta %g, %s: albedo %.5f vs %.5f",
                          1 << levs[i], th[k], mode ? "backward" : "forward", alb, ref);
            }
        CHECK_MSG(bad == 0, "%d²: %d samples whose weight or pdf disagree with f, hd_bsdf_pdf", 1 << levs[i], bad);
    }
    for (int i = 0; i < 3; i++) {
        hd_bsdf_cache_free(c[i]);
        hd_bsdf_free(b[i]);
    }
}

int main(void)
{
    (void)hd_test_tmpdir;
    (void)hd_test_ref;
    RUN(test_flat_cost);
    return hd_test_done();
}

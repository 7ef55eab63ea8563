/* Unit tests for the dctimestep fold kernel and coefficient handling. */
#include "hd_test.h"
#include "heliodon/dctimestep.h"
#include "heliodon/rng.h"

#include <stdlib.h>

/* The blocked, threaded float fold equals a naive double sum within float
 * rounding, skips NULL components, and is identical for 1 and 3 threads. */
static void test_fold_matches_naive(void)
{
    enum { K = 37, T = 21, NP = 5000 };
    size_t np = (NP + 15) & ~(size_t)15;
    float *comp[K];
    double *coef = calloc((size_t)K * T * 3, sizeof(double));
    hd_rng r;
    hd_rng_init(&r, 5, 0);
    for (int k = 0; k < K; k++) {
        if (k % 5 == 3) { comp[k] = NULL; continue; } /* never needed */
        comp[k] = calloc(3 * np, sizeof(float));
        for (size_t i = 0; i < 3 * np; i++) comp[k][i] = (float)hd_rng_uniform(&r);
    }
    for (int k = 0; k < K; k++)
        for (int t = 0; t < T; t++)
            for (int c = 0; c < 3; c++)
                coef[((size_t)k * T + t) * 3 + c] = (t % 4 == 0 || comp[k] == NULL) ? 0 : hd_rng_uniform(&r) * 10;
    float *o1 = calloc((size_t)T * 3 * np, sizeof(float)), *o3 = calloc((size_t)T * 3 * np, sizeof(float));
    REQUIRE(hd_dcts_fold(comp, K, coef, T, np, o1, 1) == HD_OK);
    REQUIRE(hd_dcts_fold(comp, K, coef, T, np, o3, 3) == HD_OK);
    CHECK(!memcmp(o1, o3, (size_t)T * 3 * np * sizeof(float)));
    double maxrel = 0;
    for (int t = 0; t < T; t++)
        for (int c = 0; c < 3; c++)
            for (size_t p = 0; p < NP; p += 7) {
                double s = 0;
                for (int k = 0; k < K; k++)
                    if (comp[k]) s += coef[((size_t)k * T + t) * 3 + c] * comp[k][(size_t)c * np + p];
                double o = o1[((size_t)t * 3 + c) * np + p];
                if (t % 4 == 0) CHECK(o == 0);
                else if (s > 0 && fabs(o - s) / s > maxrel) maxrel = fabs(o - s) / s;
            }
    CHECK_MSG(maxrel < 1e-5, "float fold differs from double sum by %g", maxrel);
    CHECK(hd_dcts_fold(comp, K, coef, T, NP, o1, 1) == HD_ERR_INTERNAL); /* unpadded */
    for (int k = 0; k < K; k++) free(comp[k]);
    free(coef);
    free(o1);
    free(o3);
}

/* Every kernel (portable C, AVX2, AVX-512 where the CPU has them) gives
 * the same bits: pixel counts with 64-pixel tiles and 16-pixel remainders,
 * step counts that are not multiples of the 6-step tile. */
static void test_kernels_bit_identical(void)
{
    enum { K = 29, T = 13, NP = 5008 }; /* 512-pixel chunks, the last 400 = 6 x 64 + 16 */
    float *comp[K];
    double *coef = calloc((size_t)K * T * 3, sizeof(double));
    hd_rng r;
    hd_rng_init(&r, 6, 0);
    for (int k = 0; k < K; k++) {
        comp[k] = calloc(3 * (size_t)NP, sizeof(float));
        for (size_t i = 0; i < 3 * (size_t)NP; i++) comp[k][i] = (float)(hd_rng_uniform(&r) * exp(10 * hd_rng_uniform(&r)));
    }
    for (size_t i = 0; i < (size_t)K * T * 3; i++) coef[i] = hd_rng_uniform(&r) < 0.1 ? 0 : hd_rng_uniform(&r) - 0.2;
    size_t bytes = (size_t)T * 3 * NP * sizeof(float);
    float *ref = malloc(bytes), *o = malloc(bytes);
    int maxlevel = hd_dcts_set_kernel(-1);
    REQUIRE(hd_dcts_set_kernel(0) == 0);
    REQUIRE(hd_dcts_fold(comp, K, coef, T, NP, ref, 2) == HD_OK);
    for (int l = 1; l <= maxlevel; l++) {
        REQUIRE(hd_dcts_set_kernel(l) == l);
        memset(o, 0xff, bytes);
        REQUIRE(hd_dcts_fold(comp, K, coef, T, NP, o, 2) == HD_OK);
        CHECK_MSG(!memcmp(o, ref, bytes), "kernel level %d differs from the portable kernel", l);
    }
    if (maxlevel < 2) printf("  (CPU kernels available up to level %d: AVX-512 path not exercised)\n", maxlevel);
    hd_dcts_set_kernel(-1);
    /* against a float sum written out plainly (same order: bit-identical) */
    int bad = 0;
    for (int t = 0; t < T; t++)
        for (int c = 0; c < 3; c++)
            for (size_t p = 0; p < NP; p += 37) {
                float s = 0;
                for (int k = 0; k < K; k++) {
                    float a = (float)coef[((size_t)k * T + (size_t)t) * 3 + (size_t)c];
                    float m = a * comp[k][(size_t)c * NP + p];
                    s = s + m;
                }
                if (s != ref[((size_t)t * 3 + (size_t)c) * NP + p]) bad++;
            }
    CHECK_MSG(bad == 0, "%d values differ from the plain float sum", bad);
    for (int k = 0; k < K; k++) free(comp[k]);
    free(coef);
    free(ref);
    free(o);
}

int main(void)
{
    RUN(test_fold_matches_naive);
    RUN(test_kernels_bit_identical);
    return hd_test_done();
}

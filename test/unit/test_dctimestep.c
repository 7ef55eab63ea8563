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

int main(void)
{
    RUN(test_fold_matches_naive);
    return hd_test_done();
}

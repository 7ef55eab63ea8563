/* Stability suite, library part (issue 10): a tensor tree at its
 * resolution limit (scenes/cfs/cfs4_ttree.xml: a near-opaque fabric,
 * tau ~ 0.014, whose tree holds single-leaf spikes next to zeros).
 * Importance sampling must stay consistent with evaluation: every sample's
 * value equals hd_bsdf_eval at the sampled direction, pdf and weight are
 * finite and positive, the mean weight equals the albedo, and the albedo
 * equals a brute-force integral of the evaluated BSDF — also at grazing
 * incidence (85 and 89.5 degrees) where the tree's patches are smallest
 * relative to the projected solid angle. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hd_test.h"
#include "heliodon/bsdf.h"
#include "heliodon/rng.h"

static hd_vec3 dir_deg(double theta, double phi, int side)
{
    double t = theta * HD_PI / 180, p = phi * HD_PI / 180;
    return hd_v3(sin(t) * cos(p), sin(t) * sin(p), side * cos(t));
}

/* integral of f(g, out)|cos| over the hemisphere of sign `side` (Shirley-Chiu grid) */
static double brute(const hd_bsdf *b, hd_vec3 g, int side, int N)
{
    double s = 0;
    for (int p = 0; p < N; p++)
        for (int q = 0; q < N; q++) {
            double x, y;
            hd_square2disk((p + 0.5) / N, (q + 0.5) / N, &x, &y);
            s += hd_bsdf_eval(b, g, hd_v3(x, y, side * sqrt(fmax(0, 1 - x * x - y * y))));
        }
    return s * HD_PI / ((double)N * N);
}

static void test_tree_resolution_limit(void)
{
    const char *path = "scenes/cfs/cfs4_ttree.xml";
    FILE *f = fopen(path, "r");
    if (!f) SKIP("%s not found (run from the project root)", path);
    fclose(f);
    hd_bsdf *b;
    REQUIRE(hd_bsdf_load(path, &b) == HD_OK);
    hd_bsdf_cache *c = hd_bsdf_cache_new(b, 0);
    REQUIRE(c != NULL);
    const double th[] = {0, 0.5, 5, 15, 30, 60, 85, 89.5};
    for (int k = 0; k < 8; k++)
        for (int side = -1; side <= 1; side += 2) {
            hd_vec3 g = dir_deg(th[k], 30 + 40 * k, side);
            double alb = hd_bsdf_albedo(b, c, g, HD_BSDF_FORWARD, HD_BSDF_TRANS);
            double s = brute(b, g, -side, 900);
            CHECK_MSG(isfinite(alb) && alb >= 0, "theta %g side %d: albedo %g", th[k], side, alb);
            hd_rng rng;
            hd_rng_init(&rng, 7, (uint64_t)(k * 2 + (side > 0)));
            const int NS = 20000;
            double sw = 0;
            int bad = 0, badval = 0, n = 0;
            for (int i = 0; i < NS; i++) {
                hd_bsdf_sample smp;
                double u1 = hd_rng_uniform(&rng), u2 = hd_rng_uniform(&rng), u3 = hd_rng_uniform(&rng);
                if (!hd_bsdf_sample_dir(b, c, g, HD_BSDF_FORWARD, HD_BSDF_TRANS, u1, u2, u3, &smp)) continue;
                n++;
                if (!isfinite(smp.value) || !isfinite(smp.pdf) || !isfinite(smp.weight) || smp.pdf <= 0 ||
                    smp.weight < 0 || smp.dir.z * side > 0)
                    bad++;
                double fe = hd_bsdf_eval(b, g, smp.dir);
                if (!smp.lambertian && fabs(fe - smp.value) > 1e-6 * fabs(fe) + 1e-9) badval++;
                sw += smp.weight;
            }
            double mw = sw / NS;
            printf("  theta %4.1f side %+d: albedo %.5f brute(900^2) %.5f mean weight %.5f (%d samples)\n", th[k],
                   side, alb, s, mw, n);
            CHECK_MSG(n == NS, "theta %g side %d: only %d of %d samples drawn", th[k], side, n, NS);
            CHECK_MSG(bad == 0, "theta %g side %d: %d of %d samples non-finite or on the wrong side", th[k], side,
                      bad, n);
            CHECK_MSG(badval == 0, "theta %g side %d: %d samples whose value differs from evaluation", th[k], side,
                      badval);
            if (side > 0) {
                /* exact sampler: weight == albedo, albedo == integral of f */
                CHECK_MSG(fabs(mw - alb) <= 0.01 * alb, "theta %g: mean weight %g vs albedo %g", th[k], mw, alb);
                if (th[k] > 0)
                    /* 5 %: the regular 900^2 grid itself aliases the spikes by ~4 % */
                    CHECK_MSG(fabs(alb - s) <= 0.05 * s, "theta %g: albedo %g vs brute force %g", th[k], alb, s);
            } else {
                /* grid-fit sampler (reciprocal side): the weights stay an
                 * unbiased estimate of the integral of f (within 6 % of the
                 * brute force, MC noise of a spiky f); the fitted albedo
                 * itself is off by up to 50 % within 1 degree of normal
                 * incidence (documented limitation), 8 % elsewhere */
                if (th[k] > 0)
                    CHECK_MSG(fabs(mw - s) <= 0.06 * s, "theta %g side -1: mean weight %g vs brute force %g", th[k],
                              mw, s);
                double lim = th[k] < 1 ? 0.5 : 0.08;
                CHECK_MSG(fabs(alb - mw) <= lim * mw, "theta %g side -1: fitted albedo %g vs mean weight %g (> %g)",
                          th[k], alb, mw, lim);
            }
        }
    hd_bsdf_cache_free(c);
    hd_bsdf_free(b);
}

int main(void)
{
    RUN(test_tree_resolution_limit);
    return hd_test_done();
}

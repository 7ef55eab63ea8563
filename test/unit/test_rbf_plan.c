/* Transport plans of measured-BSDF interpolants against Radiance 6.1's:
 * the interpolants of ref/bsdf/measured (pabopto2bsdf of Radiance) keep
 * Radiance's plan for every mesh edge; recomputed from the same lobes,
 * heliodon's Radiance-compatible plan (hd_transport_radiance through
 * hd_rbf_replan) must give the same matrices, and the exact plan must
 * cost no more than either. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hd_test.h"
#include "heliodon/rbf.h"

/* largest |ours - Radiance's| over the matrix entries of migration m,
 * relative to the row sum (1) */
static double mtx_diff(const hd_rbfrep *r, int m, const float *ref)
{
    int na = r->dsf[r->mig[m].from].nrbf, nb = r->dsf[r->mig[m].to].nrbf;
    double mx = 0;
    for (int q = 0; q < na * nb; q++) mx = fmax(mx, fabs((double)r->mig[m].mtx[q] - ref[q]));
    return mx;
}

static void check_file(const char *name)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder");
    char path[4096];
    if (snprintf(path, sizeof path, "%s/bsdf/measured/%s", ref, name) >= (int)sizeof path) SKIP("path too long");
    hd_rbfrep r;
    if (hd_rbf_read(&r, path) != HD_OK) { hd_rbf_free(&r); SKIP("%.300s not readable", path); }
    /* the plans were made with the volumes summed in double precision */
    for (int k = 0; k < r.ndsf; k++) {
        r.dsf[k].vtotal = 0;
        for (int i = 0; i < r.dsf[k].nrbf; i++) r.dsf[k].vtotal += hd_rbf_lobe_volume(&r, &r.dsf[k].rbfa[i]);
    }
    int same = 0;
    for (int m = 0; m < r.nmig; m++) {
        int na = r.dsf[r.mig[m].from].nrbf, nb = r.dsf[r.mig[m].to].nrbf;
        float *rad = malloc(sizeof(float) * (size_t)na * nb);
        REQUIRE(rad);
        memcpy(rad, r.mig[m].mtx, sizeof(float) * (size_t)na * nb);
        REQUIRE(hd_rbf_replan(&r, m, 0) == HD_OK);
        double d = mtx_diff(&r, m, rad);
        printf("  %s edge %d (%d x %d): largest difference %.3g\n", name, m, na, nb, d);
        CHECK_MSG(d <= 1e-5, "%s edge %d: plan differs from Radiance's by %g", name, m, d);
        if (d <= 1e-5) same++;
        /* control: the exact plan is a different matrix on at least one edge (checked below) */
        REQUIRE(hd_rbf_replan(&r, m, 1) == HD_OK);
        if (mtx_diff(&r, m, rad) > 1e-3) same += 1000;
        free(rad);
    }
    CHECK_MSG(same >= 1000, "%s: the exact plans equal Radiance's on every edge (the comparison cannot fail)", name);
    hd_rbf_free(&r);
}

static void test_fabric_tb(void) { check_file("fabric_tb.sir"); }
static void test_fabric_tf(void) { check_file("fabric_tf.sir"); }
static void test_fabric_rb(void) { check_file("fabric_rb.sir"); }
static void test_fabric_rf(void) { check_file("fabric_rf.sir"); }

int main(void)
{
    RUN(test_fabric_tb);
    RUN(test_fabric_tf);
    RUN(test_fabric_rb);
    RUN(test_fabric_rf);
    return hd_test_done();
}

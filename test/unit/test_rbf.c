/* Radial-basis BSDF interpolants (rbf.h) and the rttree_reduce tree
 * reduction (genbsdf.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hd_test.h"
#include "heliodon/bsdf.h"
#include "heliodon/genbsdf.h"
#include "heliodon/rbf.h"

/* an isotropic transmission interpolant: two incident directions (normal
 * and 40 degrees), each one narrow lobe on the through direction plus a
 * broad one at the normal, the narrow lobes linked to each other */
static void make_rep(hd_rbfrep *r)
{
    REQUIRE(hd_rbf_init(r, HD_RBF_GRIDRES) == HD_OK);
    r->single_plane = 1;
    r->input_orient = -1;
    r->output_orient = 1;
    r->colorimetry = 0;
    r->bsdf_min = 1e-3;
    snprintf(r->name, sizeof r->name, "unit test");
    r->ndsf = 2;
    r->dsf = calloc(2, sizeof *r->dsf);
    double th[2] = {0, 40 * HD_PI / 180};
    for (int k = 0; k < 2; k++) {
        hd_rbfdsf *d = &r->dsf[k];
        d->ord = k;
        d->invec = hd_v3(-sin(th[k]), 0, -cos(th[k]));
        d->nrbf = 2;
        d->rbfa = calloc(2, sizeof *d->rbfa);
        int pos[2];
        hd_rbf_pos(r, hd_v3(sin(th[k]), 0, cos(th[k])), pos);
        d->rbfa[0] = (hd_rbflobe){(float)(2.0 - k), 49750, (uint16_t)hd_rbf_ang2r(0.05), (uint16_t)pos[0], (uint16_t)pos[1]};
        d->rbfa[1] = (hd_rbflobe){0.03f, 49750, (uint16_t)hd_rbf_ang2r(0.6), HD_RBF_GRIDRES / 2, HD_RBF_GRIDRES / 2};
        for (int i = 0; i < 2; i++) d->vtotal += hd_rbf_lobe_volume(r, &d->rbfa[i]);
    }
    r->nmig = 1;
    r->mig = calloc(1, sizeof *r->mig);
    r->mig[0].from = 0;
    r->mig[0].to = 1;
    r->mig[0].mtx = calloc(4, sizeof(float));
    r->mig[0].mtx[0] = 1.0f;   /* narrow -> narrow */
    r->mig[0].mtx[3] = 1.0f;   /* broad -> broad */
    REQUIRE(hd_rbf_link(r) == HD_OK);
}

static void test_roundtrip(void)
{
    hd_rbfrep a, b;
    make_rep(&a);
    char path[512];
    snprintf(path, sizeof path, "%s/test_rbf.sir", hd_test_tmpdir());
    FILE *fp = fopen(path, "wb");
    REQUIRE(fp);
    CHECK(hd_rbf_write(&a, fp, "unit test\n") == HD_OK);
    fclose(fp);
    REQUIRE(hd_rbf_read(&b, path) == HD_OK);
    CHECK(b.single_plane == 1 && b.input_orient == -1 && b.output_orient == 1);
    CHECK_STR(b.name, "unit test");
    CHECK_NEAR(b.bsdf_min, 1e-3, 1e-9);
    REQUIRE(b.ndsf == 2 && b.nmig == 1);
    for (int k = 0; k < 2; k++) {
        CHECK_NEAR(b.dsf[k].invec.z, a.dsf[k].invec.z, 1e-8);
        CHECK_REL(b.dsf[k].vtotal, a.dsf[k].vtotal, 1e-8);
        REQUIRE(b.dsf[k].nrbf == 2);
        for (int i = 0; i < 2; i++) {
            CHECK_REL(b.dsf[k].rbfa[i].peak, a.dsf[k].rbfa[i].peak, 1e-7);
            CHECK(b.dsf[k].rbfa[i].gx == a.dsf[k].rbfa[i].gx && b.dsf[k].rbfa[i].gy == a.dsf[k].rbfa[i].gy);
            CHECK(b.dsf[k].rbfa[i].crad == a.dsf[k].rbfa[i].crad);
        }
    }
    CHECK(b.mig[0].mtx[0] == 1.0f && b.mig[0].mtx[1] == 0 && b.mig[0].mtx[3] == 1.0f);
    hd_rbf_free(&a);
    hd_rbf_free(&b);
    /* a truncated file is an error naming the byte offset */
    fp = fopen(path, "rb");
    REQUIRE(fp);
    char buf[4096];
    size_t n = fread(buf, 1, sizeof buf, fp);
    fclose(fp);
    fp = fopen(path, "wb");
    fwrite(buf, 1, n - 20, fp);
    fclose(fp);
    CHECK(hd_rbf_read(&b, path) == HD_ERR_FORMAT);
    hd_rbf_free(&b);
}

/* the DSF integrates to the lobe volumes; the indexed and plain evaluations agree */
static void test_eval_volume(void)
{
    hd_rbfrep r;
    make_rep(&r);
    hd_rbfeval *e;
    REQUIRE(hd_rbfeval_make(&e, &r, &r.dsf[0]) == HD_OK);
    int N = 512;
    double sum = 0, maxd = 0;
    int nexact = 0;
    for (int x = 0; x < N; x++)
        for (int y = 0; y < N; y++) {
            double u, v;
            hd_square2disk((x + .5) / N, (y + .5) / N, &u, &v);
            double s = sqrt(2. - u * u - v * v);
            hd_vec3 o = hd_v3(u * s, v * s, 0);
            o.z = sqrt(fmax(0, 1 - o.x * o.x - o.y * o.y));
            double f = hd_rbfeval_bsdf(e, o), g = hd_rbf_eval(&r, &r.dsf[0], o);
            if (fabs(f - g) > maxd * g) maxd = fabs(f - g) / g;   /* float lobe table: relative */
            nexact += hd_rbfeval_bsdf_exact(e, o) != g;           /* through the index, bit for bit */
            sum += (f - r.bsdf_min) * hd_rbf_cosf(o.z) * 2 * HD_PI / ((double)N * N);
        }
    CHECK(maxd < 1e-4);
    CHECK_MSG(nexact == 0, "%d exact evaluations differ from hd_rbf_eval", nexact);
    CHECK_REL(sum, r.dsf[0].vtotal, 0.03);
    /* the wrong side gives the minimum */
    CHECK_NEAR(hd_rbfeval_bsdf(e, hd_v3(0, 0, -1)), r.bsdf_min, 1e-12);
    hd_rbfeval_free(e);
    hd_rbf_free(&r);
}

/* advection: measured directions give their DSFs back, in between the
 * volume interpolates linearly and the narrow lobe moves along */
static void test_advect(void)
{
    hd_rbfrep r;
    make_rep(&r);
    hd_rbfdsf d;
    REQUIRE(hd_rbf_advect(&r, hd_v3(0, 0, -1), 0, &d) == HD_OK);
    CHECK(d.nrbf == 2);
    CHECK_REL(d.vtotal, r.dsf[0].vtotal, 1e-9);
    free(d.rbfa);
    double th = 20 * HD_PI / 180;   /* half-way, on the other azimuth (isotropic) */
    REQUIRE(hd_rbf_advect(&r, hd_v3(0, sin(th), -cos(th)), 0, &d) == HD_OK);
    REQUIRE(d.nrbf == 2);
    CHECK_REL(d.vtotal, .5 * (r.dsf[0].vtotal + r.dsf[1].vtotal), 1e-3);
    int pos[2];
    hd_rbf_pos(&r, hd_v3(0, -sin(th), cos(th)), pos);
    hd_vec3 c = hd_rbf_ovec(&r, d.rbfa[0].gx, d.rbfa[0].gy), w = hd_v3(0, -sin(th), cos(th));
    CHECK(hd_vdot(c, w) > cos(2 * HD_PI / 180));
    free(d.rbfa);
    /* beyond the last measured direction: no data, no default lobe */
    REQUIRE(hd_rbf_advect(&r, hd_v3(-sin(1.2), 0, -cos(1.2)), 0, &d) == HD_OK);
    CHECK(d.nrbf == 0);
    free(d.rbfa);
    hd_rbf_free(&r);
}

/* read as row lists only (bsdf2ttree): the advection is the same, lobe for
 * lobe, and the interpolant can no longer be written */
static void test_read_rows(void)
{
    hd_rbfrep a, b;
    make_rep(&a);
    a.mig[0].mtx[1] = 1e-9f;   /* a tiny entry below the advection's threshold: kept in the row lists */
    a.mig[0].mtx[0] = 1.0f - 1e-9f;
    REQUIRE(hd_rbf_link(&a) == HD_OK);
    CHECK(a.mig[0].rs[1] - a.mig[0].rs[0] == 2);
    char path[512];
    snprintf(path, sizeof path, "%s/test_rbf_rows.sir", hd_test_tmpdir());
    FILE *fp = fopen(path, "wb");
    REQUIRE(fp);
    REQUIRE(hd_rbf_write(&a, fp, NULL) == HD_OK);
    fclose(fp);
    hd_rbf_free(&a);
    REQUIRE(hd_rbf_read(&a, path) == HD_OK);
    REQUIRE(hd_rbf_read_rows(&b, path) == HD_OK);
    CHECK(a.mig[0].mtx != NULL && b.mig[0].mtx == NULL);
    CHECK(b.mig[0].rs[1] - b.mig[0].rs[0] == 2);
    double th = 25 * HD_PI / 180;
    hd_rbfdsf da, db;
    REQUIRE(hd_rbf_advect(&a, hd_v3(0, sin(th), -cos(th)), 0, &da) == HD_OK);
    REQUIRE(hd_rbf_advect(&b, hd_v3(0, sin(th), -cos(th)), 0, &db) == HD_OK);
    REQUIRE(da.nrbf == db.nrbf && da.nrbf > 0);
    CHECK(memcmp(da.rbfa, db.rbfa, (size_t)da.nrbf * sizeof *da.rbfa) == 0);
    CHECK(da.vtotal == db.vtotal);
    free(da.rbfa);
    free(db.rbfa);
    fp = tmpfile();
    REQUIRE(fp);
    CHECK(hd_rbf_write(&b, fp, NULL) == HD_ERR_RANGE);
    CHECK(ftell(fp) == 0);   /* nothing written */
    fclose(fp);
    CHECK(hd_rbf_link(&b) == HD_OK);   /* the edge lists are rebuilt, the rows kept */
    hd_rbf_free(&a);
    hd_rbf_free(&b);
}

/* rttree_reduce's reduction: a constant grid is one leaf; -t 0 keeps every
 * varying finest group; a single spike keeps its group and its ancestors */
static void test_reduce(void)
{
    int g = 3, R = 1 << g;
    size_t n = (size_t)R * R * R * R;
    float *a = malloc(n * sizeof *a);
    for (size_t k = 0; k < n; k++) a[k] = 0.25f;
    hd_gbtree *t;
    REQUIRE(hd_gbtree_build_rtr(&t, a, 4, g, 90) == HD_OK);
    CHECK(hd_gbtree_nleaves(t) == 1);
    hd_gbtree_free(t);
    a = malloc(n * sizeof *a);
    for (size_t k = 0; k < n; k++) a[k] = 0.25f;
    a[n / 3] = 5.0f;
    REQUIRE(hd_gbtree_build_rtr(&t, a, 4, g, 90) == HD_OK);
    /* root -> 16 -> 16 -> one group of 16 finest cells: 15 + 15 + 16 leaves */
    CHECK(hd_gbtree_nleaves(t) == 15 + 15 + 16);
    double c[4];
    size_t k = n / 3;
    for (int i = 3; i >= 0; i--) { c[i] = ((double)(k % R) + .5) / R; k /= R; }
    CHECK_NEAR(hd_gbtree_lookup(t, c), 5.0, 1e-6);
    c[3] = fmod(c[3] + 1.0 / R, 1.0);
    CHECK_NEAR(hd_gbtree_lookup(t, c), 0.25, 1e-6);
    hd_gbtree_free(t);
}

/* A crafted interpolant: two DSFs declaring 1000 lobes each (13 bytes a
 * lobe, all present), then a migration between them, whose 1000 x 1000
 * matrix (3.8 MiB) is over the 2 MiB allocation limit set here: refused up
 * front with the file, the byte offset and the size named.  The file itself
 * (26 kB) is read under the limit. */
static void test_absurd_sizes(void)
{
    char path[512];
    snprintf(path, sizeof path, "%s/test_rbf_huge.sir", hd_test_tmpdir());
    FILE *fp = fopen(path, "wb");
    REQUIRE(fp);
    fputs("#?RADIANCE\nSYMMETRY=1\nIO_SIDES= -1 1\nGRIDRES=128\nBSDFMIN=0.001\nFORMAT=BSDF_RBFmesh\n\n", fp);
    hd_put_int(fp, 0x5a3c, 2);   /* magic */
    long mig_at = 0;
    for (int k = 0; k < 2; k++) {
        hd_put_int(fp, k, 4);
        hd_put_flt(fp, 0);
        hd_put_flt(fp, 0);
        hd_put_flt(fp, -1);
        hd_put_flt(fp, 1);
        hd_put_int(fp, 1000, 4);
        for (int i = 0; i < 1000 * 13; i++) putc(0, fp);
    }
    hd_put_int(fp, -1, 4);
    mig_at = ftell(fp);
    hd_put_int(fp, 0, 4);
    hd_put_int(fp, 1, 4);
    for (int i = 0; i < 64; i++) putc(0, fp);
    fclose(fp);
    size_t old = hd_alloc_limit();
    hd_set_alloc_limit((size_t)2 << 20);
    hd_rbfrep r;
    hd_status st = hd_rbf_read(&r, path);
    hd_set_alloc_limit(old);
    CHECK(st == HD_ERR_NOMEM);
    char want[600];
    snprintf(want, sizeof want, "%s: byte %ld: migration 0 -> 1 (1000 x 1000 lobes): refusing to allocate 3.8 MiB",
             path, mig_at);
    CHECK_CONTAINS(hd_errmsg(), want);
    if (st == HD_OK) hd_rbf_free(&r);
}

int main(void)
{
    RUN(test_roundtrip);
    RUN(test_eval_volume);
    RUN(test_advect);
    RUN(test_read_rows);
    RUN(test_reduce);
    RUN(test_absurd_sizes);
    return hd_test_done();
}

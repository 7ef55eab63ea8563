/* Benchmark of src/matrix.c: product speed and read/write throughput.
 * Prints one line per figure.  Uses ../shared/ref (HELIODON_REF) when
 * present for a real-size sky matrix read. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "heliodon/common.h"
#include "heliodon/matrix.h"
#include "heliodon/parallel.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static double cpu(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static void fill(hd_matrix *m, unsigned seed)
{
    size_t n = (size_t)m->nrows * m->ncols * m->ncomp;
    for (size_t i = 0; i < n; i++) {
        seed = seed * 1103515245u + 12345u;
        m->data[i] = (seed >> 8) / 16777216.0;
    }
}

int main(void)
{
    hd_set_progname("bench_matrix");
    const char *tmp = getenv("HD_TEST_TMP");
    char dir[512];
    snprintf(dir, sizeof dir, "%s", tmp && *tmp ? tmp : "/tmp");
    mkdir(dir, 0777);

    /* product: a DC-like 1000 x 146 x 3 times a year sky 146 x 8760 x 3 */
    hd_matrix a, b, c;
    hd_matrix_init(&a); hd_matrix_init(&b); hd_matrix_init(&c);
    if (hd_matrix_alloc(&a, 1000, 146, 3) || hd_matrix_alloc(&b, 146, 8760, 3)) hd_die();
    fill(&a, 1);
    fill(&b, 2);
    double c0 = cpu(), t0 = now();
    if (hd_matrix_multiply(&c, &a, &b)) hd_die();
    double t1 = now(), c1 = cpu();
    double flops = 2.0 * 1000 * 146 * 8760 * 3;
    printf("multiply 1000x146x3 . 146x8760x3: %.3f s wall, %.3f s cpu (%.2f GFLOP/s per cpu-second, 1 thread)\n",
           t1 - t0, c1 - c0, flops / (c1 - c0) * 1e-9);
    hd_matrix c2;
    hd_matrix_init(&c2);
    int nthr = hd_ncpus();
    t0 = now();
    if (hd_matrix_multiply_mt(&c2, &a, &b, nthr)) hd_die();
    t1 = now();
    printf("multiply 1000x146x3 . 146x8760x3: %.3f s (%.2f GFLOP/s, %d threads)%s\n", t1 - t0,
           flops / (t1 - t0) * 1e-9, nthr,
           memcmp(c.data, c2.data, sizeof(double) * 1000 * 8760 * 3) ? " RESULTS DIFFER" : "");
    hd_matrix_free(&c2);

    /* write / read 1000 x 8760 x 3 in each format */
    const hd_mtxfmt fmts[] = {HD_MTX_ASCII, HD_MTX_FLOAT, HD_MTX_DOUBLE, HD_MTX_RGBE};
    for (int i = 0; i < 4; i++) {
        char path[700];
        snprintf(path, sizeof path, "%s/bench_matrix.%s", dir, hd_mtxfmt_name(fmts[i]));
        FILE *fp = fopen(path, "wb");
        if (!fp) { perror(path); return 1; }
        t0 = now();
        c0 = cpu();
        if (hd_matrix_write(fp, &c, NULL, 1, fmts[i])) hd_die();
        fclose(fp);
        t1 = now();
        c1 = cpu();
        struct stat st;
        stat(path, &st);
        hd_matrix r;
        hd_matrix_init(&r);
        hd_matrix_readopts ro = {0, 0, 0, -1};
        double t2 = now(), c2 = cpu();
        if (hd_matrix_read(path, &r, &ro)) hd_die();
        double t3 = now(), c3 = cpu();
        printf("%-16s 1000x8760x3 (%.1f MB): write %.3f s wall / %.3f s cpu, read %.3f s wall / %.3f s cpu "
               "(%.1f Mvalues per cpu-second)\n",
               hd_mtxfmt_name(fmts[i]), st.st_size / 1e6, t1 - t0, c1 - c0, t3 - t2, c3 - c2,
               1000 * 8760 * 3 / (c3 - c2) * 1e-6);
        hd_matrix_free(&r);
        remove(path);
    }

    const char *ref = getenv("HELIODON_REF");
    if (!ref) ref = "../shared/ref";
    char p[700];
    snprintf(p, sizeof p, "%s/sky/daymtx/chicago_year_mf1.mtx.gz", ref);
    hd_matrix y;
    hd_matrix_init(&y);
    hd_matrix_readopts ro = {0, 0, 0, -1};
    t0 = now();
    c0 = cpu();
    if (hd_matrix_read(p, &y, &ro) == HD_OK) {
        t1 = now();
        c1 = cpu();
        printf("read gzip float sky 146x8760x3 (%s): %.3f s wall, %.3f s cpu\n", p, t1 - t0, c1 - c0);
    } else {
        printf("reference sky matrix not available: %s\n", hd_errmsg());
    }
    hd_matrix_free(&y);
    hd_matrix_free(&a); hd_matrix_free(&b); hd_matrix_free(&c);
    return 0;
}

/* Benchmark of the BSDF library: load time and memory per file size
 * (reference files and synthetic large tensor trees), evaluation rate and
 * importance-sampling rate on one core.
 *
 *   build/bench/bench_bsdf [refdir] [tmpdir]
 *   build/bench/bench_bsdf -write 3|4 LEVELS FILE [R]   (one synthetic tree; R: with
 *                                              a Reflection Back block too)
 *
 * Synthetic trees (written to tmpdir, default build/tmp): an anisotropic
 * TensorTree4 refined to 128×128 cells per hemisphere around a
 * transmission peak, and an isotropic TensorTree3 refined to 512×512. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "heliodon/bsdf.h"
#include "progress.h"
#include "heliodon/rng.h"

#include <time.h>
/* CPU time of this thread: "per core" figures that do not depend on the
 * load of a shared machine */
static double cpu_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static long rss_kb(void)
{
    FILE *fp = fopen("/proc/self/statm", "r");
    long pages = 0, res = 0;
    if (fp) {
        if (fscanf(fp, "%ld %ld", &pages, &res) != 2) res = 0;
        fclose(fp);
    }
    return res * 4;
}

/* VmRSS / VmHWM (peak resident set) of this process, kB */
static long status_kb(const char *key)
{
    FILE *fp = fopen("/proc/self/status", "r");
    char line[256];
    long v = -1;
    size_t kl = strlen(key);
    while (fp && fgets(line, sizeof line, fp))
        if (!strncmp(line, key, kl)) { v = atol(line + kl); break; }
    if (fp) fclose(fp);
    return v;
}

/* Peak memory of loading a file: a fresh process (this program re-run as
 * "bench_bsdf -peak FILE", so no heap is inherited) loads it and reports
 * VmHWM (peak RSS) minus its VmRSS before the load. */
static double peak_load_mb(const char *path)
{
    int pfd[2];
    if (pipe(pfd)) return -1;
    pid_t pid = fork();
    if (pid < 0) { close(pfd[0]); close(pfd[1]); return -1; }
    if (pid == 0) {
        close(pfd[0]);
        if (dup2(pfd[1], 1) < 0) _exit(1);
        execl("/proc/self/exe", "bench_bsdf", "-peak", path, (char *)NULL);
        _exit(1);
    }
    close(pfd[1]);
    char buf[64] = {0};
    ssize_t n = read(pfd[0], buf, sizeof buf - 1);
    close(pfd[0]);
    waitpid(pid, NULL, 0);
    return n > 0 ? atol(buf) / 1e3 : -1;
}

static int peak_child(const char *path)
{
    long r0 = status_kb("VmRSS:");
    hd_bsdf *b = NULL;
    if (hd_bsdf_load(path, &b) != HD_OK) return 1;
    printf("%ld\n", status_kb("VmHWM:") - r0);
    hd_bsdf_free(b);
    return 0;
}

/* ---- synthetic trees ---- */
static int D, MAXLEV;

static double peakval(const double *c)
{
    double d2;
    if (D == 4) {
        double dx = c[2] - (1 - c[0]), dy = c[3] - (1 - c[1]);
        d2 = dx * dx + dy * dy;
    } else {
        double dx = c[1] - (1 - c[0]), dy = c[2] - 0.5;
        d2 = dx * dx + 0.1 * dy * dy;
    }
    return 0.05 + 40 * exp(-d2 / (2 * 0.006 * 0.006));
}

static int near_peak(const double *lo, double s)
{
    double eps = 0.02;
    if (D == 4) {
        /* box of (c2 - (1-c0)) and (c3 - (1-c1)) contains values near 0 */
        double a0 = lo[2] - (1 - lo[0]), a1 = a0 + 2 * s;
        double b0 = lo[3] - (1 - lo[1]), b1 = b0 + 2 * s;
        return a0 - s < eps && a1 > -eps && b0 - s < eps && b1 > -eps;
    }
    /* a sheet c1 ≈ 1 - c0 (all azimuths of the rotated frame) */
    double a0 = lo[1] - (1 - lo[0]), a1 = a0 + 2 * s;
    return a0 - s < eps && a1 > -eps;
}

static void gen(FILE *fp, int level, double *lo, double s)
{
    if (level < MAXLEV - 1 && near_peak(lo, s)) {
        fputs("{\n", fp);
        for (int n = 0; n < (1 << D); n++) {
            double l2[4];
            for (int d = 0; d < D; d++) l2[d] = lo[d] + ((n >> d) & 1 ? s / 2 : 0);
            gen(fp, level + 1, l2, s / 2);
        }
        fputs("}\n", fp);
        return;
    }
    if (level == MAXLEV - 1 && near_peak(lo, s)) {
        /* a 2^D grid, last dimension fastest */
        fputs("{", fp);
        for (int idx = 0; idx < (1 << D); idx++) {
            double c[4];
            for (int d = 0; d < D; d++) c[d] = lo[d] + (((idx >> (D - 1 - d)) & 1) + 0.5) * s / 2;
            fprintf(fp, " %.4g", peakval(c));
        }
        fputs(" }\n", fp);
        return;
    }
    double c[4];
    for (int d = 0; d < D; d++) c[d] = lo[d] + s / 2;
    fprintf(fp, "{ %.4g }\n", peakval(c));
}

static void write_tree2(const char *path, int dim, int maxlev, int refl);
static void write_tree(const char *path, int dim, int maxlev) { write_tree2(path, dim, maxlev, 0); }

/* refl: also a "Reflection Back" block (room-side reflection) of the same
 * structure, so that rays from the room sample a tree in both roles */
static void write_tree2(const char *path, int dim, int maxlev, int refl)
{
    FILE *fp = fopen(path, "w");
    if (!fp) { perror(path); exit(1); }
    D = dim;
    MAXLEV = maxlev;
    fprintf(fp, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<WindowElement xmlns=\"http://windows.lbl.gov\">\n"
            "<WindowElementType>System</WindowElementType><FileType>BSDF</FileType>\n<Optical><Layer>\n"
            "<Material><Name>synthetic</Name><Manufacturer>bench_bsdf</Manufacturer>"
            "<Thickness unit=\"millimeter\">5</Thickness></Material>\n"
            "<DataDefinition><IncidentDataStructure>TensorTree%d</IncidentDataStructure></DataDefinition>\n"
            "<WavelengthData><Wavelength unit=\"Integral\">Visible</Wavelength><WavelengthDataBlock>\n"
            "<WavelengthDataDirection>Transmission Back</WavelengthDataDirection>\n"
            "<AngleBasis>LBNL/Shirley-Chiu</AngleBasis><ScatteringData>\n", dim);
    double lo[4] = {0, 0, 0, 0};
    gen(fp, 0, lo, 1.0);
    fprintf(fp, "</ScatteringData></WavelengthDataBlock></WavelengthData>\n");
    if (refl) {
        fprintf(fp, "<WavelengthData><Wavelength unit=\"Integral\">Visible</Wavelength><WavelengthDataBlock>\n"
                "<WavelengthDataDirection>Reflection Back</WavelengthDataDirection>\n"
                "<AngleBasis>LBNL/Shirley-Chiu</AngleBasis><ScatteringData>\n");
        gen(fp, 0, lo, 1.0);
        fprintf(fp, "</ScatteringData></WavelengthDataBlock></WavelengthData>\n");
    }
    fprintf(fp, "</Layer></Optical></WindowElement>\n");
    fclose(fp);
}

static double file_mb(const char *path)
{
    struct stat st;
    return stat(path, &st) ? 0 : st.st_size / 1e6;
}

static hd_bsdf *bench_load(const char *path, const char *label)
{
    long r0 = rss_kb();
    double t0 = hd_seconds(), c0 = cpu_s();
    hd_bsdf *b;
    if (hd_bsdf_load(path, &b) != HD_OK) { fprintf(stderr, "%s\n", hd_errmsg()); exit(1); }
    double t1 = hd_seconds(), c1 = cpu_s();
    long r1 = rss_kb();
    double pk = peak_load_mb(path);
    printf("load  %-28s %8.2f MB  %6.3f s CPU (%6.3f s wall)  data %7.2f MB  RSS +%7.2f MB  (data %.2f x file)"
           "  peak RSS during load +%.2f MB (%.2f x file)  res %d\n",
           label, file_mb(path), c1 - c0, t1 - t0, hd_bsdf_memory(b) / 1e6, (r1 - r0) / 1e3,
           hd_bsdf_memory(b) / 1e6 / file_mb(path), pk, pk / file_mb(path), hd_bsdf_get_info(b)->tree_res);
    return b;
}

static void bench_sampling(hd_bsdf *b, const char *label, int side)
{
    hd_bsdf_cache *c = hd_bsdf_cache_new(b, 0);
    hd_rng r;
    hd_rng_init(&r, 1, 0);
    double t = 0.5, ph = 1.1;
    hd_vec3 sun = hd_v3(sin(t) * cos(ph), sin(t) * sin(ph), side * cos(t));
    hd_bsdf_sample s;
    double acc = 0;
    /* warm the cache for the fixed direction */
    hd_bsdf_sample_dir(b, c, sun, HD_BSDF_FORWARD, HD_BSDF_ALL, 0.5, 0.5, 0.5, &s);
    const int N = 2000000;
    double t0 = cpu_s();
    for (int i = 0; i < N; i++) {
        if (hd_bsdf_sample_dir(b, c, sun, HD_BSDF_FORWARD, HD_BSDF_ALL, hd_rng_uniform(&r),
                               hd_rng_uniform(&r), hd_rng_uniform(&r), &s))
            acc += s.weight;
    }
    double t1 = cpu_s();
    printf("sample %-27s fixed sun, forward:  %6.2f M samples/s per core (mean weight %.4f)\n", label,
           N / (t1 - t0) / 1e6, acc / N);
    /* random incident directions (each query may build a distribution) */
    const int M = 200000;
    t0 = cpu_s();
    for (int i = 0; i < M; i++) {
        double u = hd_rng_uniform(&r), p = 2 * HD_PI * hd_rng_uniform(&r);
        hd_vec3 g = hd_v3(sqrt(u) * cos(p), sqrt(u) * sin(p), side * sqrt(1 - u));
        hd_bsdf_sample_dir(b, c, g, i % 2 ? HD_BSDF_FORWARD : HD_BSDF_BACKWARD, HD_BSDF_ALL,
                           hd_rng_uniform(&r), hd_rng_uniform(&r), hd_rng_uniform(&r), &s);
    }
    t1 = cpu_s();
    printf("sample %-27s random directions:   %6.2f M samples/s\n", label, M / (t1 - t0) / 1e6);
    t0 = cpu_s();
    double sum = 0;
    for (int i = 0; i < N; i++) {
        double u = hd_rng_uniform(&r), p = 2 * HD_PI * hd_rng_uniform(&r);
        hd_vec3 o = hd_v3(sqrt(u) * cos(p), sqrt(u) * sin(p), -side * sqrt(1 - u));
        sum += hd_bsdf_eval(b, sun, o);
    }
    t1 = cpu_s();
    printf("eval   %-27s                      %6.2f M evaluations/s (%g)\n", label, N / (t1 - t0) / 1e6, sum > 0 ? 1.0 : 0.0);
    hd_bsdf_cache_free(c);
}

int main(int argc, char **argv)
{
    if (argc == 3 && !strcmp(argv[1], "-peak")) return peak_child(argv[2]);
    if ((argc == 5 || argc == 6) && !strcmp(argv[1], "-write")) {
        /* -write 3|4 LEVELS FILE [R]: a synthetic tree (R: with reflection) */
        write_tree2(argv[4], atoi(argv[2]), atoi(argv[3]), argc == 6 && !strcmp(argv[5], "R"));
        return 0;
    }
    const char *ref = argc > 1 ? argv[1] : "../shared/ref";
    const char *tmp = argc > 2 ? argv[2] : "build/tmp";
    char path[1024];
    static const char *const files[] = {"glazing/glazing_klems.xml", "cfs1/cfs1_klems.xml",
                                        "cfs1/cfs1_ttree.xml", "cfs3/cfs3_ttree.xml"};
    for (int i = 0; i < 4; i++) {
        snprintf(path, sizeof path, "%s/bsdf/%s", ref, files[i]);
        struct stat st;
        if (stat(path, &st)) { printf("skip %s (no reference folder)\n", path); continue; }
        hd_bsdf *b = bench_load(path, files[i]);
        bench_sampling(b, files[i], -1);
        hd_bsdf_free(b);
    }
    if (mkdir(tmp, 0777) && 0) perror(tmp);
    snprintf(path, sizeof path, "%s/bench_tree4_128.xml", tmp);
    double t0 = hd_seconds();
    write_tree(path, 4, 7);
    printf("(wrote synthetic TensorTree4 128x128 in %.1f s)\n", hd_seconds() - t0);
    hd_bsdf *b = bench_load(path, "synthetic aniso 128^2");
    bench_sampling(b, "synthetic aniso 128^2", 1);
    bench_sampling(b, "synthetic aniso 128^2 recip", -1);
    hd_bsdf_free(b);
    if (!getenv("BENCH_BSDF_KEEP")) remove(path);   /* keep for profiling */
    snprintf(path, sizeof path, "%s/bench_tree3_512.xml", tmp);
    t0 = hd_seconds();
    write_tree(path, 3, 9);
    printf("(wrote synthetic TensorTree3 512x512 in %.1f s)\n", hd_seconds() - t0);
    b = bench_load(path, "synthetic iso 512^2");
    bench_sampling(b, "synthetic iso 512^2", 1);
    hd_bsdf_free(b);
    if (!getenv("BENCH_BSDF_KEEP")) remove(path);   /* keep for profiling */
    return 0;
}

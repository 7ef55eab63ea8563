/* Unit tests for the core library: errors, bounded allocation, input
 * streams, crash-safe outputs, headers, options, random streams,
 * parallel-for. */
#include "hd_test.h"
#include "heliodon/common.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/options.h"
#include "heliodon/parallel.h"
#include "progress.h"
#include "heliodon/rng.h"
#include "heliodon/vec.h"

#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

static char *tmp_path(const char *name)
{
    static char buf[8][512];
    static int k;
    char *b = buf[k++ & 7];
    snprintf(b, 512, "%s/core_%s", hd_test_tmpdir(), name);
    return b;
}

static void write_file(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    fwrite(data, 1, n, f);
    fclose(f);
}

static int file_exists(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0;
}

static int count_tmp_leftovers(const char *dir)
{
    char cmd[600];
    snprintf(cmd, sizeof cmd, "ls -a '%s' | grep -c hdtmp", dir);
    FILE *p = popen(cmd, "r");
    int n = 0;
    if (fscanf(p, "%d", &n) != 1) n = -1;
    pclose(p);
    return n;
}

static void test_error_messages(void)
{
    hd_status st = hd_fail(HD_ERR_FORMAT, "%s: line %d: expected %s", "a.rad", 12, "a number");
    CHECK(st == HD_ERR_FORMAT);
    CHECK_STR(hd_errmsg(), "a.rad: line 12: expected a number");
    hd_fail_context(st, "reading %s", "scene");
    CHECK_STR(hd_errmsg(), "reading scene: a.rad: line 12: expected a number");
    CHECK_STR(hd_status_name(HD_ERR_NOMEM), "out of memory");
}

/* hd_istream_read_all: the whole stream NUL-terminated; a stream longer
 * than the allocation limit refused with its name and the limit. */
static void test_read_all_limit(void)
{
    char path[512];
    snprintf(path, sizeof path, "%s/read_all.bin", hd_test_tmpdir());
    FILE *f = fopen(path, "wb");
    REQUIRE(f);
    for (int i = 0; i < 300000; i++) putc('a' + i % 26, f);
    fclose(f);
    hd_istream *s;
    unsigned char *d = NULL;
    size_t n = 0;
    REQUIRE(hd_istream_open(&s, path) == HD_OK);
    CHECK(hd_istream_read_all(s, &d, &n) == HD_OK);
    CHECK(n == 300000 && d && d[n] == 0 && d[299999] == 'a' + 299999 % 26);
    free(d);
    hd_istream_close(s);
    size_t old = hd_alloc_limit();
    hd_set_alloc_limit(200000);
    REQUIRE(hd_istream_open(&s, path) == HD_OK);
    CHECK(hd_istream_read_all(s, &d, &n) == HD_ERR_NOMEM);
    CHECK(d == NULL && n == 0);
    char want[600];
    snprintf(want, sizeof want, "%s: longer than the allocation limit of 195.3 KiB, refused", path);
    CHECK_CONTAINS(hd_errmsg(), want);
    hd_istream_close(s);
    hd_set_alloc_limit(old);
}

static void test_bounded_alloc(void)
{
    size_t old = hd_alloc_limit();
    hd_set_alloc_limit((size_t)1 << 20);
    void *p = hd_malloc((size_t)2 << 20);
    CHECK(p == NULL);
    CHECK_CONTAINS(hd_errmsg(), "refusing to allocate 2.0 MiB");
    p = hd_malloc_array((size_t)2000000000, (size_t)2000000000 * 4);
    CHECK(p == NULL);
    p = hd_calloc(SIZE_MAX / 2, 4);
    CHECK(p == NULL);
    p = hd_malloc(1000);
    CHECK(p != NULL);
    free(p);
    size_t out;
    CHECK(hd_mul_overflow(SIZE_MAX, 2, &out) == 1);
    CHECK(hd_mul_overflow(3, 4, &out) == 0 && out == 12);
    /* the big-buffer allocator honours the same limit, at every size */
    hd_set_alloc_limit((size_t)8 << 20);
    CHECK(hd_big_alloc((size_t)3 << 20, 4, 0) == NULL);
    CHECK_CONTAINS(hd_errmsg(), "refusing to allocate 12.0 MiB");
    CHECK(hd_big_alloc((size_t)3 << 20, 4, 1) == NULL);
    CHECK(hd_big_alloc(SIZE_MAX / 2, 4, 0) == NULL);
    unsigned char *b = hd_big_alloc((size_t)6 << 20, 1, 1);   /* large, zeroed */
    CHECK(b != NULL);
    if (b) {
        size_t nz = 0;
        for (size_t i = 0; i < ((size_t)6 << 20); i += 4093) nz += b[i] != 0;
        CHECK(nz == 0);
        b[((size_t)6 << 20) - 1] = 1;
        free(b);
    }
    b = hd_big_alloc((size_t)5 << 20, 1, 0);                  /* large: 2 MiB aligned */
    CHECK(b != NULL && ((uintptr_t)b & (((uintptr_t)2 << 20) - 1)) == 0);
    free(b);
    hd_set_alloc_limit(old);
    /* host probes agree with the compiler's view */
#if defined(__BYTE_ORDER__) && defined(__ORDER_BIG_ENDIAN__)
    CHECK(hd_host_bigendian() == (__BYTE_ORDER__ == __ORDER_BIG_ENDIAN__));
#endif
    int lv = hd_cpu_level();
    CHECK(lv >= 0 && lv <= 2 && hd_cpu_level() == lv);
}

static void test_parse_numbers(void)
{
    uint64_t c;
    CHECK(hd_parse_count("10m", &c) == 0 && c == 10000000ULL);
    CHECK(hd_parse_count("4g", &c) == 0 && c == 4000000000ULL);
    CHECK(hd_parse_count("1.5k", &c) == 0 && c == 1500);
    CHECK(hd_parse_count("250", &c) == 0 && c == 250);
    CHECK(hd_parse_count("10x", &c) != 0);
    CHECK(hd_parse_count("-5", &c) != 0);
    CHECK(hd_parse_count("1.5", &c) != 0);
    CHECK(hd_parse_count("", &c) != 0);
    double d;
    CHECK(hd_parse_double("1e-3", &d) == 0 && d == 1e-3);
    CHECK(hd_parse_double("1e-3x", &d) != 0);
    CHECK(hd_parse_double("nan", &d) != 0);
    CHECK(hd_parse_double("inf", &d) != 0);
    long l;
    CHECK(hd_parse_long("-42", &l) == 0 && l == -42);
    CHECK(hd_parse_long("4.2", &l) != 0);
}

static void test_istream_plain_and_gzip(void)
{
    const char *text = "1 2.5\n  3e2\nfoo 7\n";
    const char *p1 = tmp_path("plain.txt"), *p2 = tmp_path("plain.txt.gz");
    write_file(p1, text, strlen(text));
    gzFile g = gzopen(p2, "wb");
    gzwrite(g, text, (unsigned)strlen(text));
    gzclose(g);
    for (int k = 0; k < 2; k++) {
        hd_istream *s;
        REQUIRE(hd_istream_open(&s, k ? p2 : p1) == HD_OK);
        double v;
        CHECK(hd_istream_real(s, &v, NULL) == HD_OK && v == 1);
        CHECK(hd_istream_real(s, &v, NULL) == HD_OK && v == 2.5);
        CHECK(hd_istream_real(s, &v, NULL) == HD_OK && v == 300);
        CHECK(hd_istream_real(s, &v, NULL) == HD_ERR_FORMAT);
        CHECK_CONTAINS(hd_errmsg(), "line 3: expected a number, found \"foo\"");
        CHECK(hd_istream_real(s, &v, NULL) == HD_OK && v == 7);
        int eof = 0;
        CHECK(hd_istream_real(s, &v, &eof) == HD_OK && eof == 1);
        CHECK(hd_istream_real(s, &v, NULL) == HD_ERR_FORMAT);
        CHECK_CONTAINS(hd_errmsg(), "unexpected end of data");
        CHECK(hd_istream_offset(s) == strlen(text));
        hd_istream_close(s);
    }
    hd_istream *s;
    CHECK(hd_istream_open(&s, tmp_path("does-not-exist")) == HD_ERR_IO);
    CHECK_CONTAINS(hd_errmsg(), "does-not-exist: cannot open");
}

static void test_istream_truncated_gzip(void)
{
    const char *p = tmp_path("trunc.gz");
    unsigned char big[100000];
    for (size_t i = 0; i < sizeof big; i++) big[i] = (unsigned char)(i * 7919 >> 3);
    gzFile g = gzopen(p, "wb");
    gzwrite(g, big, sizeof big);
    gzclose(g);
    FILE *f = fopen(p, "rb");
    unsigned char buf[200000];
    size_t n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    write_file(p, buf, n / 2);
    hd_istream *s;
    REQUIRE(hd_istream_open(&s, p) == HD_OK);
    hd_status st = hd_istream_read_exact(s, buf, sizeof big, "pixel data");
    CHECK(st != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "trunc.gz: byte offset");
    hd_istream_close(s);
}

static void test_istream_command_and_memory(void)
{
    hd_istream *s;
    REQUIRE(hd_istream_open(&s, "!printf 'a b\\nc\\n'") == HD_OK);
    char w[16];
    CHECK(hd_istream_word(s, w, sizeof w) == 1 && !strcmp(w, "a"));
    CHECK(hd_istream_word(s, w, sizeof w) == 1 && !strcmp(w, "b"));
    CHECK(hd_istream_word(s, w, sizeof w) == 1 && !strcmp(w, "c"));
    CHECK(hd_istream_lineno(s) == 2);
    CHECK(hd_istream_word(s, w, sizeof w) == 0);
    CHECK(hd_istream_close(s) == HD_OK);
    REQUIRE(hd_istream_open(&s, "!exit 3") == HD_OK);
    CHECK(hd_istream_getc(s) == EOF);
    CHECK(hd_istream_close(s) == HD_ERR_IO);
    CHECK_CONTAINS(hd_errmsg(), "exited with status 3");
    const char data[] = "line one\nline two";
    REQUIRE(hd_istream_memory(&s, data, sizeof data - 1, "mem") == HD_OK);
    char line[64];
    CHECK(hd_istream_getline(s, line, sizeof line) == 8 && !strcmp(line, "line one"));
    CHECK(hd_istream_getline(s, line, sizeof line) == 8 && !strcmp(line, "line two"));
    CHECK(hd_istream_getline(s, line, sizeof line) == -1);
    hd_istream_close(s);
}

static void test_ofile_commit_abort(void)
{
    const char *p = tmp_path("out.txt");
    unlink(p);
    hd_ofile *f;
    REQUIRE(hd_ofile_open(&f, p) == HD_OK);
    fputs("hello\n", hd_ofile_fp(f));
    CHECK(!file_exists(p)); /* not visible before commit */
    CHECK(hd_ofile_commit(f) == HD_OK);
    CHECK(file_exists(p));
    REQUIRE(hd_ofile_open(&f, p) == HD_OK);
    fputs("partial", hd_ofile_fp(f));
    hd_ofile_abort(f);
    FILE *r = fopen(p, "r");
    char buf[32] = {0};
    CHECK(r && fgets(buf, sizeof buf, r) && !strcmp(buf, "hello\n")); /* old content kept */
    if (r) fclose(r);
    CHECK(count_tmp_leftovers(hd_test_tmpdir()) == 0);
    CHECK(hd_ofile_open(&f, "/nonexistent-dir/x.hdr") == HD_ERR_IO);
    CHECK_CONTAINS(hd_errmsg(), "/nonexistent-dir/x.hdr: cannot create output");
}

static void test_ofile_killed_leaves_nothing(void)
{
    const char *p = tmp_path("killed.txt");
    unlink(p);
    pid_t pid = fork();
    if (pid == 0) {
        hd_ofile *f;
        if (hd_ofile_open(&f, p) != HD_OK) _exit(2);
        fputs("data", hd_ofile_fp(f));
        fflush(hd_ofile_fp(f));
        raise(SIGTERM);
        _exit(3);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    CHECK(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM);
    CHECK(!file_exists(p));
    CHECK(count_tmp_leftovers(hd_test_tmpdir()) == 0);
    /* exit(1) without commit: no output either */
    pid = fork();
    if (pid == 0) {
        hd_ofile *f;
        if (hd_ofile_open(&f, p) != HD_OK) _exit(2);
        fputs("data", hd_ofile_fp(f));
        exit(1);
    }
    waitpid(pid, &status, 0);
    CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 1);
    CHECK(!file_exists(p));
    CHECK(count_tmp_leftovers(hd_test_tmpdir()) == 0);
}

/* Temporaries of a killed run: removed by the next open of the same name,
 * taken over by hd_ofile_open_resume; those of live processes and of other
 * names are left alone; resumable temporaries survive SIGTERM only. */
static void test_ofile_stale_and_resume(void)
{
    char dir[600], a[700], b[700], c[700], d[700], e[700], out[700], other[700];
    snprintf(dir, sizeof dir, "%s/core_stale", hd_test_tmpdir());
    snprintf(a, sizeof a, "rm -rf '%s'", dir);
    CHECK(system(a) == 0);
    mkdir(dir, 0777);
    pid_t dead = fork();
    if (dead == 0) _exit(0);
    waitpid(dead, NULL, 0);
    snprintf(out, sizeof out, "%s/out.txt", dir);
    snprintf(other, sizeof other, "%s/other.txt", dir);
    unlink(out);
    snprintf(a, sizeof a, "%s/.out.txt.hdtmp.%ld.1", dir, (long)dead);
    snprintf(b, sizeof b, "%s/.out.txt.hdtmp.%ld.run002", dir, (long)dead);
    snprintf(c, sizeof c, "%s/.other.txt.hdtmp.%ld.1", dir, (long)dead);
    snprintf(d, sizeof d, "%s/.out.txt.hdtmp.%ld.7", dir, (long)getppid());
    write_file(a, "abc", 3);
    write_file(b, "run", 3);
    write_file(c, "xyz", 3);
    write_file(d, "live", 4);
    hd_ofile *f;
    int from = -1;
    uint64_t size = 0;
    REQUIRE(hd_ofile_open_resume(&f, out, &from, &size) == HD_OK);
    CHECK(from == 1 && size == 3);
    CHECK(!file_exists(a) && !file_exists(b));   /* taken over / removed */
    CHECK(file_exists(c) && file_exists(d));     /* another name; a live process */
    CHECK(hd_ofile_truncate(f, 2) == HD_OK);
    fputs("Z", hd_ofile_fp(f));
    REQUIRE(hd_ofile_commit(f) == HD_OK);
    FILE *fp = fopen(out, "rb");
    char buf[16] = "";
    REQUIRE(fp != NULL);
    CHECK(fread(buf, 1, sizeof buf, fp) == 3);
    fclose(fp);
    CHECK(!memcmp(buf, "abZ", 3));
    /* the final file itself is copied, and stays until the commit */
    REQUIRE(hd_ofile_open_resume(&f, out, &from, &size) == HD_OK);
    CHECK(from == 2 && size == 3);
    fputs("!", hd_ofile_fp(f));
    CHECK(file_exists(out));
    hd_ofile_abort(f);
    /* a plain open removes the dead run's temporaries of its name */
    REQUIRE(hd_ofile_open(&f, other) == HD_OK);
    CHECK(!file_exists(c));
    hd_ofile_abort(f);
    unlink(d);
    /* resumable: kept on SIGTERM, removed on exit without commit */
    for (int sig = 1; sig >= 0; sig--) {
        snprintf(e, sizeof e, "%s/res%d.txt", dir, sig);
        pid_t pid = fork();
        if (pid == 0) {
            if (hd_ofile_open(&f, e) != HD_OK) _exit(2);
            hd_ofile_keep_on_signal(f);
            fputs("data", hd_ofile_fp(f));
            fflush(hd_ofile_fp(f));
            if (sig) raise(SIGTERM);
            exit(1);
        }
        waitpid(pid, NULL, 0);
        CHECK(count_tmp_leftovers(dir) == 1);   /* the SIGTERM one */
    }
    snprintf(e, sizeof e, "%s/res1.txt", dir);
    CHECK(hd_ofile_clean_stale(e) == 0);   /* this process listed the directory before that run */
    /* free space */
    CHECK(hd_check_disk(out, 1, "test") == HD_OK);
    CHECK(hd_check_disk(out, UINT64_MAX / 2, "the test output") == HD_ERR_IO);
    CHECK_CONTAINS(hd_errmsg(), "the test output needs about");
}

static void test_header_roundtrip(void)
{
    const char *text = "#?RADIANCE\noconv a.rad\nrpict -x 5\nEXPOSURE=2\nNROWS=3\nEXPOSURE=0.5e1\n"
                       "FORMAT=32-bit_rle_rgbe\n\nDATA";
    hd_istream *s;
    REQUIRE(hd_istream_memory(&s, text, strlen(text), "mem.hdr") == HD_OK);
    hd_header h;
    REQUIRE(hd_header_read(s, &h, 0) == HD_OK);
    CHECK_STR(h.ident, "RADIANCE");
    char v[64];
    CHECK(hd_header_get(&h, "FORMAT", v, sizeof v) && !strcmp(v, "32-bit_rle_rgbe"));
    CHECK(!hd_header_get(&h, "NCOLS", v, sizeof v));
    long n;
    int found;
    CHECK(hd_header_get_long(&h, "NROWS", &n, &found) == HD_OK && found && n == 3);
    CHECK_NEAR(hd_header_exposure(&h), 10.0, 1e-12);
    char rest[8] = {0};
    CHECK(hd_istream_read(s, rest, 4) == 4 && !strcmp(rest, "DATA"));
    hd_istream_close(s);
    hd_header_remove(&h, "FORMAT");
    hd_header_remove(&h, "EXPOSURE");
    CHECK_STR(h.text, "oconv a.rad\nrpict -x 5\nNROWS=3\n");
    char *argv[] = {"/usr/bin/rtrace", "-I+", "-ab", "2", "my file.rad", "", NULL};
    hd_header_add_command(&h, 6, argv);
    CHECK_CONTAINS(h.text, "rtrace -I+ -ab 2 \"my file.rad\" \"\"\n");
    hd_header_free(&h);
}

static void test_header_bad(void)
{
    static const char c0[] = "", c1[] = "P6\n3 3\n255\n", c2[] = "#?RADIANCE\nFORMAT=float\n",
                      c3[] = "#?RADIANCE\nab\0cd\n\n";
    const char *cases[][2] = {
        {c0, "empty input"},
        {c1, "expected a Radiance header"},
        {c2, "end of data inside the information header"},
        {c3, "NUL byte"},
    };
    size_t lens[] = {sizeof c0 - 1, sizeof c1 - 1, sizeof c2 - 1, sizeof c3 - 1};
    for (int i = 0; i < 4; i++) {
        hd_istream *s;
        hd_istream_memory(&s, cases[i][0], lens[i], "bad.hdr");
        hd_header h;
        CHECK(hd_header_read(s, &h, 0) == HD_ERR_FORMAT);
        CHECK_CONTAINS(hd_errmsg(), cases[i][1]);
        CHECK_CONTAINS(hd_errmsg(), "bad.hdr");
        hd_istream_close(s);
    }
}

/* FORMAT padding as Radiance's writers: data starts 4/8-aligned. */
static void test_header_format_padding(void)
{
    struct { size_t before; const char *fmt; const char *line; } cases[] = {
        {375, "float", "FORMAT=float   \n\n"}, /* a3_D.dmx: data at 392 */
        {125, "float", "FORMAT=float \n\n"},   /* a3_sky_mf1.smx: data at 140 */
        {128, "float", "FORMAT=float  \n\n"},  /* a3_skyonly_mf1.smx: data at 144 */
        {100, "double", "FORMAT=double     \n\n"}, /* data at 120 */
        {100, "ascii", "FORMAT=ascii\n\n"},
        {101, "32-bit_rle_rgbe", "FORMAT=32-bit_rle_rgbe\n\n"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        char buf[64] = {0};
        FILE *f = fmemopen(buf, sizeof buf, "w");
        hd_header_write_format(f, cases[i].fmt, cases[i].before);
        fclose(f);
        CHECK_STR(buf, cases[i].line);
    }
    const char *ref = hd_test_ref();
    if (!ref) SKIP("reference folder not found (HELIODON_REF)");
    /* Compare with a Radiance file: rebuild its header and check the offset. */
    char path[512];
    snprintf(path, sizeof path, "%s/scenes/box/a3_D.dmx", ref);
    hd_istream *s;
    REQUIRE(hd_istream_open(&s, path) == HD_OK);
    hd_header h;
    REQUIRE(hd_header_read(s, &h, 0) == HD_OK);
    uint64_t data_at = hd_istream_offset(s);
    char fmt[32];
    REQUIRE(hd_header_get(&h, "FORMAT", fmt, sizeof fmt));
    hd_header_remove(&h, "FORMAT");
    char out[4096];
    FILE *f = fmemopen(out, sizeof out, "w");
    size_t nb = 0;
    CHECK(hd_header_put(f, &h, NULL, fmt, &nb) == HD_OK);
    long pos = ftell(f);
    fclose(f);
    CHECK((uint64_t)pos == data_at);
    CHECK(nb == data_at);
    hd_header_free(&h);
    hd_istream_close(s);
}

/* hd_header_put: the dimensions the header lacks, in NROWS, NCOLS, NCOMP
 * order, BigEndian of the host or the swapped order, padded FORMAT; a
 * dimension the header holds is not repeated and must agree. */
static void test_header_put(void)
{
    hd_header h;
    hd_header_init(&h);
    REQUIRE(hd_header_append_lines(&h, "prog -a\nNCOMP=3") == HD_OK);   /* '\n' added */
    char buf[256] = {0}, want[256];
    FILE *f = fmemopen(buf, sizeof buf, "w");
    hd_header_dims d = {7, 5, 3, HD_ENDIAN_SWAPPED};
    size_t nb = 0;
    CHECK(hd_header_put(f, &h, &d, "float", &nb) == HD_OK);
    long pos = ftell(f);
    fclose(f);
    /* 11 + 8 + 8 + 8 + 8 + 12 = 55 bytes, then "FORMAT=float", 3 blanks, "\n\n": data at 72 */
    snprintf(want, sizeof want, "#?RADIANCE\nprog -a\nNCOMP=3\nNROWS=7\nNCOLS=5\nBigEndian=%d\nFORMAT=float   \n\n",
             !hd_host_bigendian());
    CHECK_STR(buf, want);
    CHECK(nb == 72 && nb == strlen(want) && pos == (long)nb);
    /* NCOMP=3 in the header but 1 asked for: refused */
    f = fmemopen(buf, sizeof buf, "w");
    hd_header_dims bad = {0, 0, 1, HD_ENDIAN_NONE};
    CHECK(hd_header_put(f, &h, &bad, "ascii", NULL) == HD_ERR_INTERNAL);
    fclose(f);
    /* no header, no dimensions */
    memset(buf, 0, sizeof buf);
    f = fmemopen(buf, sizeof buf, "w");
    CHECK(hd_header_put(f, NULL, NULL, "ascii", &nb) == HD_OK);
    fclose(f);
    CHECK_STR(buf, "#?RADIANCE\nFORMAT=ascii\n\n");
    CHECK(nb == 25);
    hd_header_free(&h);
}

static int cb_calls;
static int cb_func(const hd_opt *o, int argc, char **argv, int i, void *ctx)
{
    (void)o;
    (void)ctx;
    if (i + 2 >= argc) { hd_fail(HD_ERR_USAGE, "option %s expects file N", argv[i]); return -1; }
    cb_calls++;
    return 2;
}

static void test_options(void)
{
    int ab = 0, I = 0, x = 0, h = 1;
    double lw = 0, vp[3] = {0};
    uint64_t n = 0;
    const char *fmt = NULL, *vf = NULL;
    hd_opt table[] = {
        {"ab", HD_OPT_INT, &ab, 0, 0, "N", "bounces"},
        {"lw", HD_OPT_REAL, &lw, 0, 0, "w", "weight"},
        {"I", HD_OPT_TOGGLE, &I, 0, 0, NULL, "irradiance"},
        {"h", HD_OPT_TOGGLE, &h, 0, 0, NULL, "header"},
        {"x", HD_OPT_INT, &x, 0, 0, "res", "x resolution"},
        {"vp", HD_OPT_REAL3, vp, 0, 0, "x y z", "view point"},
        {"vf", HD_OPT_STRING, &vf, 0, 0, "file", "view file"},
        {"apC", HD_OPT_FUNC, NULL, cb_func, 0, "file N", "contribution map"},
        {"apc", HD_OPT_COUNT, &n, 0, 0, "N", "count"},
        {"f", HD_OPT_STRING, &fmt, 0, 1, NULL, "formats -f[adf][adfc]"},
        HD_OPT_END};
    const char *optfile = tmp_path("opts.txt");
    const char *ot = "# rendering options\n-ab 3 -lw 1e-4\n-vf 'my view.vf'\n";
    write_file(optfile, ot, strlen(ot));
    char at[600];
    snprintf(at, sizeof at, "@%s", optfile);
    char *argv[] = {"rtrace", "-I+", "-h", "-x", "512", at, "-vp", "1", "2", "3", "-apC", "m.pm", "10m",
                    "-apc", "2k", "-faf", "scene.rad", "-", NULL};
    hd_optparse p;
    REQUIRE(hd_opt_parse(&p, 18, argv, table) == HD_OK);
    CHECK(ab == 3 && I == 1 && h == 0 && x == 512);
    CHECK(lw == 1e-4);
    CHECK(vp[0] == 1 && vp[1] == 2 && vp[2] == 3);
    CHECK_STR(vf, "my view.vf");
    CHECK(cb_calls == 1 && n == 2000);
    CHECK_STR(fmt, "-faf");
    CHECK(p.argc - p.first == 2);
    CHECK_STR(p.argv[p.first], "scene.rad");
    CHECK_STR(p.argv[p.first + 1], "-");
    hd_optparse_free(&p);
    /* toggles */
    CHECK(hd_opt_toggle_value("-I", 0) == 1 && hd_opt_toggle_value("-I", 1) == 0);
    CHECK(hd_opt_toggle_value("+I", 0) == 1 && hd_opt_toggle_value("-I-", 1) == 0);
    CHECK(hd_opt_toggle_value("-I+", 0) == 1);
    /* errors */
    char *bad1[] = {"rtrace", "-zz", NULL};
    CHECK(hd_opt_parse(&p, 2, bad1, table) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "unknown option -zz");
    hd_optparse_free(&p);
    char *bad2[] = {"rtrace", "-ab", "two", NULL};
    CHECK(hd_opt_parse(&p, 3, bad2, table) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "option -ab: expected an integer, found \"two\"");
    hd_optparse_free(&p);
    char *bad3[] = {"rtrace", "-vp", "1", "2", NULL};
    CHECK(hd_opt_parse(&p, 4, bad3, table) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "option -vp expects x y z");
    hd_optparse_free(&p);
    char *bad4[] = {"rtrace", "-apc", "12q", NULL};
    CHECK(hd_opt_parse(&p, 3, bad4, table) == HD_ERR_USAGE);
    hd_optparse_free(&p);
    char *bad5[] = {"rtrace", "+ab", "2", NULL};
    CHECK(hd_opt_parse(&p, 3, bad5, table) == HD_ERR_USAGE);
    hd_optparse_free(&p);
    /* nested option groups (HD_OPT_TABLE) are searched like the table itself */
    int ab2 = 0, flag2 = 0;
    double lw2 = 0;
    hd_opt group[] = {{"ab", HD_OPT_INT, &ab2, 0, 0, "N", "bounces"},
                      {"dv", HD_OPT_TOGGLE, &flag2, 0, 0, NULL, "toggle"},
                      HD_OPT_END};
    hd_opt outer[] = {{"lw", HD_OPT_REAL, &lw2, 0, 0, "w", "weight"},
                      {"", HD_OPT_TABLE, group, 0, 0, 0, "group"},
                      HD_OPT_END};
    char *nest[] = {"rpict", "-ab", "4", "-lw", "0.5", "-dv+", "scene.rad", NULL};
    REQUIRE(hd_opt_parse(&p, 7, nest, outer) == HD_OK);
    CHECK(ab2 == 4 && lw2 == 0.5 && flag2 == 1 && p.first == 6);
    hd_optparse_free(&p);
    char *nestbad[] = {"rpict", "-abc", "4", NULL};
    CHECK(hd_opt_parse(&p, 3, nestbad, outer) == HD_ERR_USAGE);
    hd_optparse_free(&p);
    char *bad6[] = {"rtrace", "@/nonexistent/opts", NULL};
    CHECK(hd_opt_parse(&p, 2, bad6, table) != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "/nonexistent/opts");
    hd_optparse_free(&p);
}

static void test_rng(void)
{
    hd_rng a, b, c;
    hd_rng_init(&a, 1, 7);
    hd_rng_init(&b, 1, 7);
    hd_rng_init(&c, 1, 8);
    int same = 1, diff = 0;
    for (int i = 0; i < 100; i++) {
        uint64_t x = hd_rng_u64(&a), y = hd_rng_u64(&b), z = hd_rng_u64(&c);
        same &= x == y;
        diff += x != z;
    }
    CHECK(same);
    CHECK(diff == 100);
    /* chi-square of 10 bins, 100000 draws: 99.9% quantile for 9 dof = 27.88 */
    int bins[10] = {0};
    hd_rng_init(&a, 12345, 0);
    for (int i = 0; i < 100000; i++) {
        double u = hd_rng_uniform(&a);
        REQUIRE(u >= 0 && u < 1);
        bins[(int)(u * 10)]++;
    }
    double chi = 0;
    for (int i = 0; i < 10; i++) chi += (bins[i] - 10000.0) * (bins[i] - 10000.0) / 10000.0;
    CHECK_MSG(chi < 27.88, "chi-square %g too large", chi);
    for (int i = 0; i < 1000; i++) CHECK(hd_rng_below(&a, 7) < 7);
}

typedef struct { double *out; int fail_at; } pf_ctx;
static hd_status pf_fn(void *vctx, size_t b, size_t e, size_t chunk, int worker)
{
    pf_ctx *c = vctx;
    (void)worker;
    hd_rng r;
    hd_rng_init(&r, 99, chunk);
    for (size_t i = b; i < e; i++) {
        if ((int)i == c->fail_at) return hd_fail(HD_ERR_RANGE, "item %zu failed", i);
        c->out[i] = hd_rng_uniform(&r);
    }
    return HD_OK;
}

static void test_parallel_determinism(void)
{
    enum { N = 10007 };
    static double o1[N], o2[N], o4[N];
    pf_ctx c1 = {o1, -1}, c2 = {o2, -1}, c4 = {o4, -1};
    CHECK(hd_parallel_for(N, 64, 1, pf_fn, &c1) == HD_OK);
    CHECK(hd_parallel_for(N, 64, 2, pf_fn, &c2) == HD_OK);
    CHECK(hd_parallel_for(N, 64, 4, pf_fn, &c4) == HD_OK);
    CHECK(!memcmp(o1, o2, sizeof o1));
    CHECK(!memcmp(o1, o4, sizeof o1));
    pf_ctx cf = {o2, 5000};
    CHECK(hd_parallel_for(N, 64, 3, pf_fn, &cf) == HD_ERR_RANGE);
    CHECK_STR(hd_errmsg(), "item 5000 failed");
}

static void test_progress_lines(void)
{
    /* -t reports go to stderr: capture by redirecting fd 2 */
    const char *p = tmp_path("progress.txt");
    fflush(stderr);
    int saved = dup(2);
    FILE *f = fopen(p, "w");
    dup2(fileno(f), 2);
    hd_progress *pr = hd_progress_start("unit", 100, 1e-9, 0);
    for (int i = 0; i < 4; i++) {
        hd_progress_add(pr, 25);
        usleep(2000);
    }
    hd_progress_finish(pr);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    fclose(f);
    FILE *r = fopen(p, "r");
    char line[256], last[256] = "";
    int n = 0;
    while (fgets(line, sizeof line, r)) { n++; strcpy(last, line); }
    fclose(r);
    CHECK(n >= 2);
    CHECK_CONTAINS(last, "unit: 100.0% done after");
}

static void test_patterns(void)
{
    char out[128];
    CHECK(hd_pattern_kind("view%03d.hdr") == 1);
    CHECK(hd_pattern_kind("c_%s.dat") == 2);
    CHECK(hd_pattern_kind("%s_%d.hdr") == 3);
    CHECK(hd_pattern_kind("plain.dat") == 0);
    CHECK(hd_pattern_kind("a%d%d") < 0);
    CHECK(hd_pattern_kind("a%f") < 0);
    CHECK(hd_pattern_format(out, sizeof out, "v%03d.hdr", NULL, 7) == HD_OK && !strcmp(out, "v007.hdr"));
    CHECK(hd_pattern_format(out, sizeof out, "%s_%x%%", "sun", 255) == HD_OK && !strcmp(out, "sun_ff%"));
    CHECK(hd_pattern_format(out, 6, "long%05d", NULL, 1) == HD_ERR_RANGE);
}

/* The shared pool: worker indices stay below the thread count asked for,
 * a loop nested in a chunk and loops from two threads at once complete
 * (the busy pool is not waited for), and a private pool gives the same
 * numbers as the shared one. */
typedef struct { int nthreads; atomic_int bad, sum; } pool_ctx;
static hd_status pool_inner(void *vctx, size_t b, size_t e, size_t ci, int worker)
{
    pool_ctx *c = vctx;
    (void)ci;
    if (worker < 0 || worker >= c->nthreads) atomic_fetch_add(&c->bad, 1);
    atomic_fetch_add(&c->sum, (int)(e - b));
    return HD_OK;
}
static hd_status pool_outer(void *vctx, size_t b, size_t e, size_t ci, int worker)
{
    pool_ctx *c = vctx;
    (void)b; (void)e; (void)ci;
    if (worker < 0 || worker >= c->nthreads) atomic_fetch_add(&c->bad, 1);
    pool_ctx in = {2, 0, 0};
    hd_status st = hd_parallel_for(100, 7, 2, pool_inner, &in);
    if (st || in.sum != 100 || in.bad) atomic_fetch_add(&c->bad, 1);
    return st;
}
static void *pool_thread(void *arg)
{
    pool_ctx *c = arg;
    for (int k = 0; k < 50; k++)
        if (hd_parallel_for(1000, 3, c->nthreads, pool_inner, c)) atomic_fetch_add(&c->bad, 1);
    return NULL;
}
static void test_pool(void)
{
    for (int nt = 1; nt <= 4; nt++) {
        pool_ctx c = {nt, 0, 0};
        CHECK(hd_parallel_for(1000, 3, nt, pool_inner, &c) == HD_OK);
        CHECK(c.bad == 0 && c.sum == 1000);
    }
    pool_ctx o = {3, 0, 0};
    CHECK(hd_parallel_for(12, 1, 3, pool_outer, &o) == HD_OK);
    CHECK(o.bad == 0);
    pool_ctx a = {3, 0, 0}, b = {2, 0, 0};
    pthread_t t;
    REQUIRE(pthread_create(&t, NULL, pool_thread, &a) == 0);
    pool_thread(&b);
    pthread_join(t, NULL);
    CHECK(a.bad == 0 && a.sum == 50000 && b.bad == 0 && b.sum == 50000);
    /* private pool: same values as the shared one, errors of the lowest chunk */
    double x[500], y[500];
    pf_ctx cx = {x, -1}, cy = {y, -1};
    hd_pool *p = hd_pool_new(3);
    REQUIRE(p != NULL);
    CHECK(hd_pool_threads(p) == 3);
    CHECK(hd_parallel_for(500, 16, 2, pf_fn, &cx) == HD_OK);
    for (int k = 0; k < 20; k++) CHECK(hd_pool_for(p, 500, 16, pf_fn, &cy) == HD_OK);
    CHECK(memcmp(x, y, sizeof x) == 0);
    cy.fail_at = 77;
    CHECK(hd_pool_for(p, 500, 1, pf_fn, &cy) == HD_ERR_RANGE);
    CHECK_CONTAINS(hd_errmsg(), "item 77 failed");
    hd_pool_free(p);
}

static void test_vec(void)
{
    hd_vec3 n = hd_vnorm(hd_v3(1, 2, 3)), u, v;
    hd_vbasis(n, &u, &v);
    CHECK_NEAR(hd_vdot(n, u), 0, 1e-12);
    CHECK_NEAR(hd_vdot(n, v), 0, 1e-12);
    CHECK_NEAR(hd_vdot(u, v), 0, 1e-12);
    CHECK_NEAR(hd_vlen(u), 1, 1e-12);
    hd_vec3 c = hd_vcross(u, v);
    CHECK_NEAR(hd_vdot(c, n), 1, 1e-12);
}

int main(void)
{
    RUN(test_error_messages);
    RUN(test_bounded_alloc);
    RUN(test_read_all_limit);
    RUN(test_parse_numbers);
    RUN(test_istream_plain_and_gzip);
    RUN(test_istream_truncated_gzip);
    RUN(test_istream_command_and_memory);
    RUN(test_ofile_commit_abort);
    RUN(test_ofile_killed_leaves_nothing);
    RUN(test_ofile_stale_and_resume);
    RUN(test_header_roundtrip);
    RUN(test_header_bad);
    RUN(test_header_format_padding);
    RUN(test_header_put);
    RUN(test_options);
    RUN(test_rng);
    RUN(test_parallel_determinism);
    RUN(test_pool);
    RUN(test_progress_lines);
    RUN(test_patterns);
    RUN(test_vec);
    return hd_test_done();
}

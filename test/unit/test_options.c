/* Unit tests: the option parser's in-order semantics (hd_opt_parse_args,
 * hd_opt_parse_one) and the programs that share rtrace's rendering option
 * group through it (rcontrib / rfluxmtx, genBSDF -r). */
#include <string.h>

#include "hd_test.h"
#include "hd_test_contrib.h"
#include "heliodon/contrib.h"
#include "heliodon/genbsdf.h"
#include "heliodon/options.h"
#include "heliodon/render.h"

/* ---- order semantics: a callback sees every option given before it ---- */
typedef struct rec {
    const char *b;            /* set by -b (HD_OPT_STRING) */
    int n;                    /* set by -n */
    const char *seen_b[8];    /* value of -b at each -m */
    int seen_n[8];
    int nm;
} rec;

static int opt_m(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)opt;
    rec *r = ctx;
    if (i + 1 >= argc) { hd_fail(HD_ERR_USAGE, "option %s expects a name", argv[i]); return -1; }
    if (r->nm >= 8) { hd_fail(HD_ERR_USAGE, "too many -m"); return -1; }
    r->seen_b[r->nm] = r->b;
    r->seen_n[r->nm] = r->n;
    r->nm++;
    return 1;
}

static void test_order(void)
{
    rec r;
    memset(&r, 0, sizeof r);
    const hd_opt t[] = {
        {"b", HD_OPT_STRING, &r.b, 0, 0, "expr", 0},
        {"n", HD_OPT_INT, &r.n, 0, 0, "N", 0},
        {"m", HD_OPT_FUNC, &r, opt_m, 0, "mod", 0},
        HD_OPT_END};
    char *argv[] = {"prog", "-m", "a", "-b", "X", "-n", "3", "-m", "c", "-b", "Y", "-m", "d", "-n", "5", "scene", NULL};
    int first = -1;
    REQUIRE(hd_opt_parse_args(16, argv, t, &first) == HD_OK);
    CHECK(first == 15);
    REQUIRE(r.nm == 3);
    CHECK(r.seen_b[0] == NULL && r.seen_n[0] == 0);
    CHECK_STR(r.seen_b[1], "X");
    CHECK(r.seen_n[1] == 3);
    CHECK_STR(r.seen_b[2], "Y");
    CHECK(r.seen_n[2] == 3);      /* -n 5 comes after the last -m */
    CHECK(r.n == 5);
    /* a failing callback stops the parse with its own message */
    char *bad[] = {"prog", "-b", "Z", "-m", NULL};
    memset(&r, 0, sizeof r);
    CHECK(hd_opt_parse_args(4, bad, t, &first) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "option -m expects a name");
    CHECK_STR(r.b, "Z");
    /* no @file expansion: "@x" is an operand here */
    char *at[] = {"prog", "-n", "1", "@nosuchfile", NULL};
    CHECK(hd_opt_parse_args(4, at, t, &first) == HD_OK);
    CHECK(first == 3);
    /* "--" ends the options */
    char *dd[] = {"prog", "--", "-n", NULL};
    CHECK(hd_opt_parse_args(3, dd, t, &first) == HD_OK);
    CHECK(first == 2);
}

/* ---- single options ---- */
static void test_parse_one(void)
{
    hd_render_opts R;
    hd_render_defaults(&R);
    hd_opt rt[HD_RENDER_NOPTS];
    hd_render_option_table(rt, &R);
    const hd_opt t[] = {{"", HD_OPT_TABLE, rt, 0, 0, 0, 0}, HD_OPT_END};
    char *v[] = {"-x", "-ab", "3", "-zz", "-dj", "abc", "-av", "1", "2", "3", "-u+", "-lr", NULL};
    CHECK(hd_opt_parse_one(t, 12, v, 1) == 2);
    CHECK(R.ab == 3);
    hd_fail(HD_OK, "sentinel");
    CHECK(hd_opt_parse_one(t, 12, v, 3) == 0);         /* unknown: no message, nothing set */
    CHECK_STR(hd_errmsg(), "sentinel");
    CHECK(hd_opt_parse_one(t, 12, v, 4) == -1);        /* bad value names the option */
    CHECK_CONTAINS(hd_errmsg(), "option -dj: expected a number, found \"abc\"");
    CHECK(R.dj == 0);
    CHECK(hd_opt_parse_one(t, 12, v, 6) == 4);
    CHECK(R.av[0] == 1 && R.av[1] == 2 && R.av[2] == 3);
    CHECK(hd_opt_parse_one(t, 12, v, 10) == 1);        /* ignored toggle */
    CHECK(hd_opt_parse_one(t, 12, v, 11) == -1);       /* missing value */
    CHECK_CONTAINS(hd_errmsg(), "-lr");
}

/* ---- rcontrib / rfluxmtx through the shared group ---- */
static void test_rcontrib_args(void)
{
    hd_contrib c;
    hd_rcontrib_opts o;
    /* rcontrib's defaults are unchanged (they are not rtrace's) */
    const char *none[] = {NULL};
    REQUIRE(hd_test_rc_parse(&c, &o, 0, none) == HD_OK);
    CHECK(c.o.ab == 1 && c.o.ad == 350 && c.o.lr == -10);
    CHECK_NEAR(c.o.lw, 2e-3, 0);
    CHECK_NEAR(c.o.dj, 0.9, 0);
    CHECK_NEAR(c.o.st, 0.02, 0);
    CHECK(o.accum == 1 && o.header == 1 && o.fin == 'a' && o.fout == 'a');
    hd_contrib_free(&c);
    /* render options as rtrace spells them; -seed takes rtrace's counts */
    const char *r1[] = {"-ab", "3", "-ad", "64", "-lr", "-4", "-lw", "1e-4", "-dj", "0", "-st", "0.5", "-ss", "2",
                        "-seed", "2k", "-aa", ".1", "-ar", "32", "-dv-", "-u+", "-bv", "-ps", "2", NULL};
    REQUIRE(hd_test_rc_parse(&c, &o, 0, r1) == HD_OK);
    CHECK(c.o.ab == 3 && c.o.ad == 64 && c.o.lr == -4 && c.o.seed == 2000);
    CHECK_NEAR(c.o.lw, 1e-4, 0);
    CHECK_NEAR(c.o.dj, 0, 0);
    CHECK_NEAR(c.o.st, 0.5, 0);
    CHECK_NEAR(c.o.ss, 2, 0);
    hd_contrib_free(&c);
    /* bad values: the message names the option, as rtrace's */
    const char *b1[] = {"-ab", "x", "-m", "m", NULL};
    CHECK(hd_test_rc_parse(&c, &o, 0, b1) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "option -ab: expected an integer, found \"x\"");
    hd_contrib_free(&c);
    const char *b2[] = {"-m", "m", "-dj", NULL};
    CHECK(hd_test_rc_parse(&c, &o, 0, b2) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "-dj");
    hd_contrib_free(&c);
    const char *b3[] = {"-seed", "-1", NULL};
    CHECK(hd_test_rc_parse(&c, &o, 0, b3) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "option -seed");
    hd_contrib_free(&c);
    const char *b4[] = {"-c", "many", NULL};
    CHECK(hd_test_rc_parse(&c, &o, 0, b4) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "option -c: expected an integer");
    hd_contrib_free(&c);
    /* order: -m takes the -b/-bn/-o in force at its position */
    const char *m1[] = {"-m", "a", "-o", "x_%s.dat", "-m", "b", "-bn", "4", "-b", "0", "-o", "y.dat", "-m", "c", "-I", "-i",
                        "-c", "0", "scene.rad", NULL};
    REQUIRE(hd_test_rc_parse(&c, &o, 0, m1) == HD_OK);
    REQUIRE(c.nmods == 3);
    CHECK_STR(c.mods[0].name, "a");
    CHECK(c.mods[0].outspec == NULL);
    CHECK_STR(c.mods[1].outspec, "x_%s.dat");
    CHECK(c.mods[1].bin.nbins == 1);
    CHECK_STR(c.mods[2].outspec, "y.dat");
    CHECK(c.mods[2].bin.kind == HD_BIN_CONST && c.mods[2].bin.nbins == 4);
    CHECK(o.irrad == 2);                 /* -I then -i: the last one wins */
    CHECK(o.accum == 0 && o.cgiven == 1);
    hd_contrib_free(&c);
    /* the rfluxmtx-only options are unknown to rcontrib ... */
    const char *v1[] = {"-v", NULL};
    CHECK(hd_test_rc_parse(&c, &o, 0, v1) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "unknown option -v");
    hd_contrib_free(&c);
    /* ... and rfluxmtx refuses what it controls, accepts the render group */
    const char *f1[] = {"-v", "-bj", "0.5", "-ab", "2", "-x", "4", "-fo+", NULL};
    CHECK(hd_test_rc_parse(&c, &o, 1, f1) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "option -fo+ is controlled by rfluxmtx");
    CHECK(o.verbose == 1 && o.xygiven == 1 && c.o.ab == 2);
    CHECK_NEAR(o.bj, 0.5, 0);
    hd_contrib_free(&c);
    const char *f2[] = {"-b", "0", NULL};
    CHECK(hd_test_rc_parse(&c, &o, 1, f2) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "-b is controlled by rfluxmtx");
    hd_contrib_free(&c);
    const char *f3[] = {"-faf", "-lr", "x", NULL};
    CHECK(hd_test_rc_parse(&c, &o, 1, f3) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "option -lr: expected an integer, found \"x\"");
    CHECK(o.fin == 'a' && o.fout == 'f');
    hd_contrib_free(&c);
}

/* ---- genBSDF -r: rtrace's words ---- */
static void test_genbsdf_r(void)
{
    hd_genbsdf_opts o;
    int first;
    char *a1[] = {"genBSDF", "-seed", "9", "-r", "-ab 3 -lr -300 -ad 700 -lw 3e-6 -u+ -I", "x.rad"};
    hd_genbsdf_defaults(&o);
    REQUIRE(hd_genbsdf_parse_args(6, a1, &o, &first) == HD_OK);
    CHECK(o.ab == 3 && o.lr == -300 && o.lw == 3e-6 && o.seed == 9 && first == 5);
    char *a2[] = {"genBSDF", "-r", "-lr 7 -seed 5", "x.rad"};
    hd_genbsdf_defaults(&o);
    REQUIRE(hd_genbsdf_parse_args(4, a2, &o, &first) == HD_OK);
    /* genBSDF's defaults stay: -ab 5, -lw 3e-6 (Radiance's genBSDF) */
    CHECK(o.ab == 5 && o.lr == 7 && o.lw == 3e-6 && o.seed == 5);
    char *a3[] = {"genBSDF", "-r", "-ab x", "x.rad"};
    hd_genbsdf_defaults(&o);
    CHECK(hd_genbsdf_parse_args(4, a3, &o, &first) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "-r: option -ab: expected an integer, found \"x\"");
    char *a4[] = {"genBSDF", "-r", "-ab 1001", "x.rad"};
    hd_genbsdf_defaults(&o);
    CHECK(hd_genbsdf_parse_args(4, a4, &o, &first) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "-ab 1001");
    char *a5[] = {"genBSDF", "-r", "-ab 2 -dj", "x.rad"};
    hd_genbsdf_defaults(&o);
    CHECK(hd_genbsdf_parse_args(4, a5, &o, &first) == HD_ERR_USAGE);
    CHECK_CONTAINS(hd_errmsg(), "-dj");
}

int main(void)
{
    RUN(test_order);
    RUN(test_parse_one);
    RUN(test_rcontrib_args);
    RUN(test_genbsdf_r);
    return hd_test_done();
}

/* Unit tests of the .cal module (cal.h): values against hand-computed
 * results, Radiance's definition-stack rules, messages with positions,
 * callbacks and per-thread evaluation. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "hd_test.h"
#include "heliodon/cal.h"
#include "cal_internal.h"

static char warned[4][128];
static int nwarned;
static void catch_warn(void *u, const char *msg)
{
    (void)u;
    if (nwarned < 4) snprintf(warned[nwarned], sizeof warned[0], "%s", msg);
    nwarned++;
}

static double ev1(hd_cal *c, const char *text)
{
    double v = -999;
    if (hd_cal_eval(c, text, &v) != HD_OK) return -12345;
    return v;
}

static void test_values(void)
{
    hd_cal *c = hd_cal_new();
    REQUIRE(c);
    CHECK_NEAR(ev1(c, "2^3^2"), 512, 0);            /* right associative */
    CHECK_NEAR(ev1(c, "-2^2"), 4, 0);               /* unary minus binds tighter */
    CHECK_NEAR(ev1(c, "10-2-3"), 5, 0);
    CHECK_NEAR(ev1(c, "8/2/2"), 2, 0);
    CHECK_NEAR(ev1(c, "select(2.5, 10, 20, 30)"), 30, 0);   /* index rounded */
    CHECK_NEAR(ev1(c, "select(0, 10, 20, 30)"), 3, 0);
    CHECK_NEAR(ev1(c, "if(0, 1, 2)"), 2, 0);
    {   /* a table of 1000 entries (Radiance's falsecolor has select()s of 257) */
        char *t = malloc(16 * 1000 + 64);
        REQUIRE(t);
        int n = sprintf(t, "select(777");
        for (int i = 1; i <= 1000; i++) n += sprintf(t + n, ",%d", 3 * i);
        strcpy(t + n, ")");
        CHECK_NEAR(ev1(c, t), 3 * 777, 0);
        strcpy(t, "select(0");
        n = 8;
        for (int i = 1; i <= 1000; i++) n += sprintf(t + n, ",%d", i);
        strcpy(t + n, ")");
        CHECK_NEAR(ev1(c, t), 1000, 0);
        free(t);
    }
    CHECK_NEAR(ev1(c, "if(1e-30, 1, 2)"), 1, 0);
    CHECK_NEAR(ev1(c, "max(3, -1, 7, 2) + min(3, -1, 2)"), 6, 0);
    CHECK_NEAR(ev1(c, "atan2(1, 0)"), M_PI / 2, 1e-15);
    CHECK_NEAR(ev1(c, "{ comment { nested } } 1 + .5e1"), 6, 0);
    REQUIRE(hd_cal_parse(c, "fact(n) : if(n - 1.5, n*fact(n-1), 1);\n"
                            "apply2(f, x) = f(f(x)); sq(x) = x*x;\n"
                            "k = 3; g(a, b) = a*10 + b", "defs") == HD_OK);
    CHECK_NEAR(ev1(c, "fact(10)"), 3628800, 0);
    CHECK_NEAR(ev1(c, "apply2(sq, 3)"), 81, 0);
    CHECK_NEAR(ev1(c, "g(k, 4)"), 34, 0);
    /* rand: deterministic, in [0,1) */
    double r1 = ev1(c, "rand(.3)"), r2 = ev1(c, "rand(.3)"), r3 = ev1(c, "rand(.31)");
    CHECK(r1 == r2 && r1 >= 0 && r1 < 1 && r1 != r3);
    hd_cal_free(c);
}

static void test_stacks_and_warnings(void)
{
    hd_cal *c = hd_cal_new();
    REQUIRE(c);
    nwarned = 0;
    hd_cal_set_warn(c, catch_warn, NULL);
    /* a constant, then a '=' definition on top of it: the latter wins */
    REQUIRE(hd_cal_parse(c, "MF : 2", NULL) == HD_OK);
    REQUIRE(hd_cal_parse(c, "MF = 1; N = MF*10", NULL) == HD_OK);
    CHECK(nwarned == 1);
    CHECK_STR(warned[0], "MF: constant redefined");
    CHECK_NEAR(ev1(c, "N"), 10, 0);
    /* a constant replaces everything */
    REQUIRE(hd_cal_parse(c, "MF : 3", NULL) == HD_OK);
    CHECK_NEAR(ev1(c, "N"), 30, 0);
    /* run-time warnings give 0 */
    nwarned = 0;
    CHECK_NEAR(ev1(c, "1/(MF-3) + 2"), 2, 0);
    CHECK(nwarned == 1);
    CHECK_STR(warned[0], "Division by zero");
    CHECK_NEAR(ev1(c, "sqrt(-1 + MF - MF) + 1"), 1, 0);
    CHECK_STR(warned[1], "sqrt(): domain error");
    hd_cal_warnings(c, 0);
    nwarned = 0;
    CHECK_NEAR(ev1(c, "log(MF-3)"), 0, 0);
    CHECK(nwarned == 0);
    hd_cal_free(c);
}

static void test_errors(void)
{
    hd_cal *c = hd_cal_new();
    REQUIRE(c);
    double v;
    CHECK(hd_cal_eval(c, "foo + 1", &v) == HD_ERR_FORMAT);
    CHECK_STR(hd_errmsg(), "foo: undefined variable");
    CHECK(hd_cal_eval(c, "bar(2)", &v) == HD_ERR_FORMAT);
    CHECK_STR(hd_errmsg(), "bar(): undefined function");
    REQUIRE(hd_cal_parse(c, "f(a, b) = a + b", NULL) == HD_OK);
    CHECK(hd_cal_eval(c, "f(1)", &v) == HD_ERR_FORMAT);
    CHECK_STR(hd_errmsg(), "f(): too few arguments");
    CHECK(hd_cal_eval(c, "f(1, 2, 3)", &v) == HD_OK && v == 3);   /* extra ignored */
    /* syntax errors: Radiance's caret under the last character read */
    CHECK(hd_cal_parse(c, "$1=(1+2", NULL) == HD_ERR_FORMAT);
    CHECK_STR(hd_errmsg(), "$1=(1+2\n      ^ ')' expected");
    /* in a file: file, line and column */
    char path[512];
    snprintf(path, sizeof path, "%s/cal_bad.cal", hd_test_tmpdir());
    FILE *fp = fopen(path, "w");
    REQUIRE(fp);
    fputs("a = 1;\n{ fine }\nb = a * (2 + ;\n", fp);
    fclose(fp);
    CHECK(hd_cal_load(c, path) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), ", line 3, column 14:");
    CHECK_CONTAINS(hd_errmsg(), "b = a * (2 + ;\n             ^ unexpected character");
    /* runaway recursion and nesting are errors, not crashes */
    REQUIRE(hd_cal_parse(c, "deep(n) = if(n, deep(n-1) + 1, 0); a1 = b1 + 1; b1 = a1 + 1", NULL) == HD_OK);
    CHECK(hd_cal_eval(c, "deep(100)", &v) == HD_OK && v == 100);
    CHECK(hd_cal_eval(c, "deep(1e9)", &v) == HD_ERR_RANGE);
    CHECK_STR(hd_errmsg(), "deep(): recursion too deep");
    CHECK(hd_cal_eval(c, "a1", &v) == HD_ERR_RANGE);
    char nest[6000];
    memset(nest, '(', 2500);
    strcpy(nest + 2500, "1");
    memset(nest + 2501, ')', 2500);
    nest[5001] = 0;
    CHECK(hd_cal_eval(c, nest, &v) == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "expression too deeply nested");
    CHECK(hd_cal_load(c, "no_such_file.cal") == HD_ERR_IO);
    CHECK_STR(hd_errmsg(), "cannot find file 'no_such_file.cal'");
    hd_cal_free(c);
}

/* callbacks: li(n) with arguments, x as a variable, $N channels */
static double cb_li(hd_calrun *r, void *u, int n, const double *a)
{
    (void)r; (void)n;
    return *(double *)u * a[0];
}
static double cb_x(hd_calrun *r, void *u, int n, const double *a)
{
    (void)u; (void)n; (void)a;
    return *(double *)hd_calrun_user(r);
}
static double cb_chan(hd_calrun *r, void *u, int n)
{
    (void)r; (void)u;
    return 100 + n;
}

static void test_callbacks(void)
{
    hd_cal *c = hd_cal_new();
    REQUIRE(c);
    double scale = 2, x = 5;
    REQUIRE(hd_cal_define_fn(c, "li", 1, 1, cb_li, &scale, 0) == HD_OK);
    REQUIRE(hd_cal_define_fn(c, "x", 0, 0, cb_x, NULL, 0) == HD_OK);
    REQUIRE(hd_cal_parse(c, "v = li(3) + x; $2 = v + $1; $4 = 7", NULL) == HD_OK);
    CHECK(hd_cal_max_outchan(c) == 4);
    CHECK(hd_cal_has_outchan(c, 2) && !hd_cal_has_outchan(c, 3));
    hd_calrun *r = hd_calrun_new(c, &x);
    REQUIRE(r);
    hd_calrun_set_chan(r, cb_chan, NULL);
    hd_calrun_next(r);
    CHECK_NEAR(hd_calrun_var(r, "v"), 11, 0);
    CHECK_NEAR(hd_calrun_outchan(r, 2), 112, 0);
    /* v is cached for the record; the next record sees the new x */
    x = 6;
    CHECK_NEAR(hd_calrun_var(r, "v"), 11, 0);
    hd_calrun_next(r);
    CHECK_NEAR(hd_calrun_var(r, "v"), 12, 0);
    /* handles and calls with arguments */
    REQUIRE(hd_cal_parse(c, "h(a, b) = a - b", NULL) == HD_OK);
    int hh = hd_cal_lookup(c, "h");
    REQUIRE(hh >= 0);
    double args[2] = {10, 4};
    CHECK_NEAR(hd_calrun_call_id(r, hh, 2, args), 6, 0);
    CHECK_NEAR(hd_calrun_call(r, "li", 1, args), 20, 0);
    CHECK(hd_calrun_status(r) == HD_OK);
    /* quick set of a number: no stale value */
    REQUIRE(hd_cal_set(c, "q", 1, 0) == HD_OK);
    REQUIRE(hd_cal_parse(c, "w = q * 10", NULL) == HD_OK);
    hd_calrun_next(r);
    CHECK_NEAR(hd_calrun_var(r, "w"), 10, 0);
    REQUIRE(hd_cal_set(c, "q", 2, 0) == HD_OK);
    hd_calrun_next(r);
    CHECK_NEAR(hd_calrun_var(r, "w"), 20, 0);
    hd_calrun_free(r);
    hd_cal_free(c);
}

static void test_context(void)
{
    hd_cal *c = hd_cal_new();
    REQUIRE(c);
    nwarned = 0;
    hd_cal_set_warn(c, catch_warn, NULL);
    REQUIRE(hd_cal_parse(c, "g = 5", NULL) == HD_OK);
    REQUIRE(hd_cal_set_context(c, "RC.") == HD_OK);
    REQUIRE(hd_cal_parse(c, "MF : 2; MF = 1; t = g + MF", NULL) == HD_OK);
    CHECK_STR(warned[0], "MF`RC.: constant redefined");
    CHECK(hd_cal_defined(c, "MF`RC."));
    CHECK(!hd_cal_defined(c, "MF`"));
    CHECK_NEAR(ev1(c, "t"), 6, 0);
    hd_cal_free(c);
}

/* several threads evaluate one context; same results as one thread */
typedef struct job { hd_cal *c; int id; double sum; } job;
static double cb_d(hd_calrun *r, void *u, int n, const double *a)
{
    (void)u; (void)n; (void)a;
    return *(double *)hd_calrun_user(r);
}
static void *worker(void *p)
{
    job *j = p;
    double d;
    hd_calrun *r = hd_calrun_new(j->c, &d);
    if (!r) return NULL;
    int h = hd_cal_lookup(j->c, "y");
    for (int i = 0; i < 20000; i++) {
        d = i * 1e-3;
        hd_calrun_next(r);
        j->sum += hd_calrun_var_id(r, h);
    }
    hd_calrun_free(r);
    return NULL;
}

static void test_threads(void)
{
    hd_cal *c = hd_cal_new();
    REQUIRE(c);
    REQUIRE(hd_cal_define_fn(c, "d", 0, 0, cb_d, NULL, 0) == HD_OK);
    REQUIRE(hd_cal_parse(c, "s = sin(d); y = s*s + fib(8); fib(n) : if(n - 1.5, fib(n-1) + fib(n-2), n)", NULL) == HD_OK);
    job j[3];
    pthread_t t[3];
    for (int i = 0; i < 3; i++) {
        j[i] = (job){c, i, 0};
        REQUIRE(pthread_create(&t[i], NULL, worker, &j[i]) == 0);
    }
    for (int i = 0; i < 3; i++) pthread_join(t[i], NULL);
    double ref = 0;
    for (int i = 0; i < 20000; i++) ref += sin(i * 1e-3) * sin(i * 1e-3) + 21;
    for (int i = 0; i < 3; i++) CHECK_NEAR(j[i].sum, ref, 1e-9 * ref);
    hd_cal_free(c);
}

int main(void)
{
    RUN(test_values);
    RUN(test_stacks_and_warnings);
    RUN(test_errors);
    RUN(test_callbacks);
    RUN(test_context);
    RUN(test_threads);
    return hd_test_done();
}

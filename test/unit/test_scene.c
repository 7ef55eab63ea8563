/* Unit tests: scene parser, modifier semantics, aliases, errors, cache. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "hd_test.h"
#include "heliodon/scene.h"
#include "heliodon/rng.h"

static hd_status load(hd_scene *s, const char *text)
{
    hd_scene_init(s);
    return hd_scene_load_string(s, text, "t.rad", NULL);
}

static void test_basic(void)
{
    hd_scene s;
    const char *text =
        "# comment line\n"
        "void plastic red\n0\n0\n5 .8 .1 .1 .02 .05\n"
        "red polygon floor 0 0 12  0 0 0  1 0 0  1 1 0  0 1 0\n"
        "  # indented comment\n"
        "red sphere ball 0 0 4 1 2 3 .5\n"
        "void glass 'my glass' 0 0 4 .9 .9 .9 1.5\n"
        "'my glass' ring disk 0 0 8 0 0 1 0 0 1 0 2\n"
        "void brightfunc skyfunc 2 skybright \"sky bright.cal\" 0 1 2.5e-1\n";
    REQUIRE(load(&s, text) == HD_OK);
    REQUIRE(s.nprims == 6);
    CHECK(s.prims[0].type == HD_T_PLASTIC);
    CHECK(s.prims[0].modifier == -1);
    CHECK_STR(s.prims[0].id, "red");
    CHECK(s.prims[0].line == 2);
    CHECK(s.prims[1].type == HD_T_POLYGON && s.prims[1].modifier == 0 && s.prims[1].line == 6);
    CHECK(hd_polygon_nverts(&s.prims[1]) == 4);
    CHECK_NEAR(hd_polygon_vertex(&s.prims[1], 2).y, 1, 0);
    hd_vec3 c; double r;
    hd_sphere_get(&s.prims[2], &c, &r);
    CHECK_NEAR(c.z, 3, 0); CHECK_NEAR(r, .5, 0);
    CHECK_STR(s.prims[3].id, "my glass");
    CHECK(s.prims[4].modifier == 3);
    hd_vec3 n; double rin, rout;
    hd_ring_get(&s.prims[4], &c, &n, &rin, &rout);
    CHECK_NEAR(rin, 0, 0); CHECK_NEAR(rout, 2, 0); CHECK_NEAR(n.z, 1, 0);
    CHECK(s.prims[5].nsargs == 2);
    CHECK_STR(s.prims[5].sargs[1], "sky bright.cal");
    CHECK_NEAR(s.prims[5].rargs[0], .25, 0);
    CHECK(hd_scene_material_of(&s, 1) == 0);
    REQUIRE(s.prims[0].nrargs == 5);
    CHECK_NEAR(s.prims[0].rargs[0], .8, 0); CHECK_NEAR(s.prims[0].rargs[3], .02, 0);
    CHECK_NEAR(s.prims[0].rargs[4], .05, 0);
    REQUIRE(s.prims[3].nrargs == 4);
    CHECK_NEAR(s.prims[3].rargs[3], 1.5, 0);
    char w[256];
    CHECK_STR(hd_prim_where(&s, 2, w, sizeof w), "t.rad:8");
    hd_scene_free(&s);
}

/* Radiance: a modifier must be defined before use; a redefinition shadows
 * the earlier one only for primitives read after it. */
static void test_shadowing_and_alias(void)
{
    hd_scene s;
    const char *text =
        "void plastic m 0 0 5 .1 .1 .1 0 0\n"          /* 0 */
        "m polygon a 0 0 9 0 0 0 1 0 0 0 1 0\n"         /* 1 */
        "void metal m 0 0 5 .9 .9 .9 0 0\n"             /* 2 */
        "m polygon b 0 0 9 0 0 0 1 0 0 0 1 0\n"         /* 3 */
        "void brightfunc pat 2 x x.cal 0 0\n"           /* 4 */
        "pat alias m2 m\n"                              /* 5 */
        "inherit alias m3 m2\n"                         /* 6 */
        "void alias m4 m\n"                             /* 7 */
        "m3 sphere c 0 0 4 0 0 0 1\n"                   /* 8 */
        "m4 sphere d 0 0 4 0 0 0 1\n";                  /* 9 */
    REQUIRE(load(&s, text) == HD_OK);
    REQUIRE(s.nprims == 10);
    CHECK(s.prims[1].modifier == 0);
    CHECK(s.prims[3].modifier == 2);
    CHECK(hd_scene_find_modifier(&s, "m") == 2);
    CHECK(hd_scene_find_modifier(&s, "a") == -1);     /* surfaces are not modifiers */
    CHECK(hd_scene_find_modifier(&s, "void") == -1);
    CHECK(s.prims[5].type == HD_T_ALIAS && s.prims[5].alias_of == 2 && s.prims[5].modifier == 4);
    CHECK(s.prims[6].alias_of == 5 && s.prims[6].modifier == 4);   /* inherit: modifier of m2 */
    CHECK(hd_scene_unalias(&s, 6) == 2);
    CHECK(s.prims[7].modifier == -1);
    CHECK(hd_scene_material_of(&s, 8) == 2);   /* through alias chain to the metal */
    CHECK(hd_scene_material_of(&s, 9) == 2);
    hd_scene_free(&s);
}

static void test_commands(void)
{
    hd_scene s;
    const char *text =
        "!echo void plastic m 0 0 5 .5 .5 .5 0 0\n"
        "m sphere s 0 0 4 0 0 0 1\n"
        "!printf 'm sphere t\\n0\\n0\\n4 1 1 1 2\\n' \\\n"
        "   ; true\n"
        "m sphere u 0 0 4 0 0 0 3\n";
    REQUIRE(load(&s, text) == HD_OK);
    REQUIRE(s.nprims == 4);
    CHECK(s.prims[0].type == HD_T_PLASTIC);
    CHECK(s.prims[1].modifier == 0);
    CHECK_STR(s.prims[2].id, "t");
    CHECK(s.prims[2].modifier == 0);
    CHECK(s.prims[3].line == 5);
    char w[512];
    hd_prim_where(&s, 2, w, sizeof w);
    CHECK_CONTAINS(w, "t.rad:3");
    CHECK_CONTAINS(w, "line 1");
    hd_scene_free(&s);
}

static void test_skip_missing(void)
{
    hd_scene s;
    hd_scene_init(&s);
    hd_scene_opts o = {0};
    o.skip_missing = 1;
    const char *text =
        "!no_such_program_hd42 a b | xform -t 1 0 0\n"
        "!echo void plastic m 0 0 5 .5 .5 .5 0 0\n"
        "m sphere s 0 0 4 0 0 0 1\n";
    REQUIRE(hd_scene_load_string(&s, text, "skip.rad", &o) == HD_OK);
    CHECK(s.nprims == 2);
    REQUIRE(s.nskipped == 1);
    CHECK_STR(s.skipped[0].command, "no_such_program_hd42 a b | xform -t 1 0 0");
    CHECK(s.skipped[0].line == 1);
    CHECK(s.skipped[0].before == 0);
    hd_scene_free(&s);
    /* without the option the same command is an error naming file:line and the status */
    hd_scene_init(&s);
    hd_status st = hd_scene_load_string(&s, "!no_such_program_hd42 x\n", "skip.rad", NULL);
    CHECK(st != HD_OK);
    CHECK_CONTAINS(hd_errmsg(), "skip.rad:1");
    CHECK_CONTAINS(hd_errmsg(), "exit status 127");
    hd_scene_free(&s);
}

typedef struct { const char *text, *expect1, *expect2; } bad_case;

static void test_errors(void)
{
    static const bad_case cases[] = {
        {"void plastic m 0 0 4 .5 .5 .5 0\n", "t.rad:1", "expected 0 strings and 5 reals"},
        {"\n\nvoid metal m 0 0 6 1 1 1 0 0 0\n", "t.rad:3", "metal m"},
        {"void trans m 0 0 5 1 1 1 0 0\n", "t.rad:1", "7 reals"},
        {"void glass m 0 0 2 1 1\n", "t.rad:1", "3 or 4 reals"},
        {"void mirror m 0 0 4 1 1 1 1\n", "t.rad:1", "3 reals"},
        {"void light m 0 0 4 1 1 1 1\n", "t.rad:1", "3 reals"},
        {"void glow m 0 0 3 1 1 1\n", "t.rad:1", "4 reals"},
        {"void illum m 0 0 4 1 1 1 0\n", "t.rad:1", "3 reals"},
        {"void antimatter m 1 x 0 1 1\n", "t.rad:1", "0 reals"},
        {"void BSDF m 5 0 f.xml 0 0 1 0 0\n", "t.rad:1", "at least 6 strings"},
        {"void aBSDF m 5 f.xml 0 0 1 . 0 2 1 1\n", "t.rad:1", "0, 3, 6 or 9 reals"},
        {"void polygon p 0 0 6 0 0 0 1 0 0\n", "t.rad:1", "n >= 3"},
        {"void polygon p 0 0 10 0 0 0 1 0 0 0 1 0 5\n", "t.rad:1", "3*n reals"},
        {"void sphere s 0 0 3 0 0 0\n", "t.rad:1", "4 reals"},
        {"void cone c 0 0 7 0 0 0 0 0 1 1\n", "t.rad:1", "8 reals"},
        {"void cylinder c 0 0 8 0 0 0 0 0 1 1 1\n", "t.rad:1", "7 reals"},
        {"void ring r 0 0 7 0 0 0 0 0 1 1\n", "t.rad:1", "8 reals"},
        {"void ring r 0 0 8 0 0 0 0 0 1 1 1\n", "t.rad:1", "radii are equal"},
        {"void source s 0 0 3 0 0 1\n", "t.rad:1", "4 reals"},
        {"void cone c 0 0 8 0 0 0 0 0 1 0 0\n", "t.rad:1", "both radii are zero"},
        {"\nnope polygon p 0 0 9 0 0 0 1 0 0 0 1 0\n", "t.rad:2", "undefined modifier 'nope'"},
        {"void plastic m 0 0 5 .5 .5 x5 0 0\n", "t.rad:1", "got 'x5'"},
        {"void plastic m 0 0 5 .5 .5 .5 0 nan\n", "t.rad:1", "got 'nan'"},
        {"void plastic m 0 0 five .5\n", "t.rad:1", "number of real arguments"},
        {"void plastic m 0 1 2 5 .5\n", "t.rad:1", "integer argument count must be 0"},
        {"void plastic m 0 0 5 .5 .5 .5\n", "t.rad:1", "end of data"},
        {"void plastique m 0 0 5 .5 .5 .5 0 0\n", "t.rad:1", "unknown primitive type 'plastique'"},
        {"void plastic void 0 0 5 .5 .5 .5 0 0\n", "t.rad:1", "may not be named 'void'"},
        {"void alias a nothere\n", "t.rad:1", "undefined modifier 'nothere'"},
        {"void sphere\n", "t.rad:1", "expected an identifier"},
        {"!printf 'void plastic m 0 0 5 1 1'\n", "t.rad:1", "end of data"},
        {"\n!exit 3\n", "t.rad:2", "exit status 3"},
        {"!echo void plastic m 0 0 5 1 1 1 0 0 \\", "t.rad:1", "unterminated"},
        {"!cat /nonexistent/hd_missing.rad\n", "t.rad:1", "exit status 1"},
        {"!printf 'void plastic m 0 0 5 1 1 1 0 0\\nm sphere s 0 0 4 0 0 0'\n", "line 2", "end of data"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        hd_scene s;
        hd_clear_error();
        hd_status st = load(&s, cases[i].text);
        CHECK_MSG(st != HD_OK, "case %zu (%s) was accepted", i, cases[i].text);
        CHECK_CONTAINS(hd_errmsg(), cases[i].expect1);
        CHECK_CONTAINS(hd_errmsg(), cases[i].expect2);
        hd_scene_free(&s);
    }
    hd_scene s;
    hd_scene_init(&s);
    CHECK(hd_scene_load_rad(&s, "/nonexistent/scene.rad", NULL) == HD_ERR_IO);
    CHECK_CONTAINS(hd_errmsg(), "/nonexistent/scene.rad");
    hd_scene_free(&s);
}

static void test_unsupported_kept(void)
{
    hd_scene s;
    const char *text =
        "void texfunc wavy 4 dx dy dz wavy.cal 0 0\n"
        "wavy plastic p 0 0 5 1 1 1 0 0\n"
        "void mesh m 1 woman.rtm 0 0\n"
        "p instance i 5 x.oct -t 1 0 0 0 0\n"
        "void dielectric d 0 0 5 1 1 1 1.33 0\n"
        "void mixfunc mx 4 p p a . 0 0\n";
    if (load(&s, text) != HD_OK) printf("  %s\n", hd_errmsg());
    REQUIRE(s.nprims == 6);
    CHECK(s.prims[0].type == HD_T_TEXFUNC && hd_type_class_of(HD_T_TEXFUNC) == HD_CLASS_TEXTURE);
    CHECK(s.prims[2].type == HD_T_MESH && !hd_type_is_modifier(HD_T_MESH));
    CHECK(s.prims[3].type == HD_T_INSTANCE && s.prims[3].nsargs == 5);
    CHECK(s.prims[5].type == HD_T_MIXFUNC && s.prims[5].line == 6);
    CHECK(hd_scene_material_of(&s, 3) == 1);   /* the instance's modifier, the plastic */
    hd_scene_free(&s);
}

static void test_negative_radii(void)
{
    hd_scene s;
    hd_set_warnings(0);
    REQUIRE(load(&s, "void cylinder c 0 0 7 0 0 0 0 0 1 -1\nvoid cone k 0 0 8 0 0 0 0 0 1 -1 -.5\n"
                     "void cup u 0 0 8 0 0 0 0 0 1 0 -2\n") == HD_OK);
    hd_set_warnings(1);
    REQUIRE(s.nprims == 3);
    CHECK(s.prims[0].type == HD_T_TUBE);
    CHECK_NEAR(s.prims[0].rargs[6], 1, 0);
    CHECK(s.prims[1].type == HD_T_CUP);
    CHECK_NEAR(s.prims[1].rargs[7], .5, 0);
    CHECK(s.prims[2].type == HD_T_CONE);
    hd_scene_free(&s);
    CHECK(load(&s, "void cone k 0 0 8 0 0 0 0 0 1 -1 .5\n") == HD_ERR_FORMAT);
    CHECK_CONTAINS(hd_errmsg(), "t.rad:1: cone k: radii of opposite signs");
    hd_scene_free(&s);
}

static void test_type_names(void)
{
    for (int t = 0; t < HD_T_COUNT; t++) {
        CHECK(hd_type_from_name(hd_type_name((hd_prim_type)t)) == t);
    }
    CHECK(hd_type_from_name("BRTDfunc") == HD_T_BRTDFUNC);
    CHECK(hd_type_from_name("brtdfunc") == -1);
    CHECK(hd_type_from_name("aBSDF") == HD_T_ABSDF);
}

static int prims_equal(const hd_prim *a, const hd_prim *b)
{
    if (a->type != b->type || a->modifier != b->modifier || a->alias_of != b->alias_of ||
        a->line != b->line || strcmp(a->modname, b->modname) || strcmp(a->id, b->id) ||
        a->nsargs != b->nsargs || a->niargs != b->niargs || a->nrargs != b->nrargs)
        return 0;
    for (uint32_t k = 0; k < a->nsargs; k++) if (strcmp(a->sargs[k], b->sargs[k])) return 0;
    for (uint32_t k = 0; k < a->nrargs; k++)
        if (memcmp(&a->rargs[k], &b->rargs[k], sizeof(double))) return 0;
    return 1;
}

static void test_cache_roundtrip(void)
{
    hd_scene s, t;
    const char *text =
        "void plastic m 0 0 5 .1 .2 .3 0.0123456789012345 1e-300\n"
        "m polygon a 0 0 9 0 0 0 1 0 0 0 1 0.1\n"
        "void brightfunc pat 4 'a b' x.cal -rz 30 0 2 1 2\n"
        "pat alias m2 m\n"
        "m2 sphere c 0 0 4 0 0 0 1\n"
        "!echo void light l 0 0 3 100 100 100\n";
    REQUIRE(load(&s, text) == HD_OK);
    char path[512];
    snprintf(path, sizeof path, "%s/test_scene_cache.oct", hd_test_tmpdir());
    char *argv[] = {"oconv", "t.rad"};
    REQUIRE(hd_scene_write_cache(&s, path, 2, argv) == HD_OK);
    CHECK(hd_scene_is_cache(path) == 1);
    hd_scene_init(&t);
    REQUIRE(hd_scene_read_cache(&t, path) == HD_OK);
    REQUIRE(t.nprims == s.nprims);
    for (size_t i = 0; i < s.nprims; i++)
        CHECK_MSG(prims_equal(&s.prims[i], &t.prims[i]), "primitive %zu differs after round trip", i);
    CHECK(t.nfiles == s.nfiles);
    CHECK(hd_scene_find_modifier(&t, "m2") == 3);
    CHECK(t.cmdline && strstr(t.cmdline, "oconv t.rad"));
    char w1[512], w2[512];
    CHECK_STR(hd_prim_where(&t, 5, w1, sizeof w1), hd_prim_where(&s, 5, w2, sizeof w2));
    /* skipped commands survive the round trip with their position */
    {
        hd_scene a, b;
        hd_scene_init(&a);
        hd_scene_opts o = {0};
        o.skip_missing = 1;
        REQUIRE(hd_scene_load_string(&a, "void light l 0 0 3 1 1 1\n!no_such_prog_hd7 x\nl sphere s 0 0 4 0 0 0 1\n",
                                     "sk.rad", &o) == HD_OK);
        REQUIRE(a.nskipped == 1);
        REQUIRE(hd_scene_write_cache(&a, path, 0, NULL) == HD_OK);
        hd_scene_init(&b);
        REQUIRE(hd_scene_read_cache(&b, path) == HD_OK);
        REQUIRE(b.nskipped == 1);
        CHECK_STR(b.skipped[0].command, "no_such_prog_hd7 x");
        CHECK(b.skipped[0].before == 1 && b.skipped[0].line == 2);
        CHECK_STR(hd_scene_where(&b, b.skipped[0].file, b.skipped[0].line, w1, sizeof w1), "sk.rad:2");
        hd_scene_free(&a);
        hd_scene_free(&b);
        REQUIRE(hd_scene_write_cache(&s, path, 2, argv) == HD_OK);
    }
    /* appending a second copy shifts modifier indices */
    REQUIRE(hd_scene_read_cache(&t, path) == HD_OK);
    CHECK(t.nprims == 2 * s.nprims);
    CHECK(t.prims[s.nprims + 1].modifier == (int32_t)s.nprims);
    hd_scene_free(&t);

    /* truncated and corrupted caches: clean errors */
    FILE *fp = fopen(path, "rb");
    REQUIRE(fp);
    char buf[8192];
    size_t n = fread(buf, 1, sizeof buf, fp);
    fclose(fp);
    char bad[512];
    snprintf(bad, sizeof bad, "%s/test_scene_bad.oct", hd_test_tmpdir());
    for (size_t cut = n - 1; cut > 60; cut -= 7) {
        fp = fopen(bad, "wb");
        fwrite(buf, 1, cut, fp);
        fclose(fp);
        hd_scene_init(&t);
        hd_status st = hd_scene_read_cache(&t, bad);
        CHECK_MSG(st != HD_OK, "truncated cache (%zu of %zu bytes) accepted", cut, n);
        hd_scene_free(&t);
    }
    char *magic = NULL;
    for (size_t k = 0; k + 8 <= n && !magic; k++)
        if (!memcmp(buf + k, "HDSCENE\n", 8)) magic = buf + k;
    REQUIRE(magic);
    magic[8] = 99;   /* version */
    fp = fopen(bad, "wb");
    fwrite(buf, 1, n, fp);
    fclose(fp);
    hd_scene_init(&t);
    CHECK(hd_scene_read_cache(&t, bad) == HD_ERR_UNSUPPORTED);
    CHECK_CONTAINS(hd_errmsg(), "version 99");
    hd_scene_free(&t);
    hd_scene_free(&s);
}

/* box_room.rad writes one primitive per line: count those lines independently */
static void test_ref_box_room(void)
{
    const char *ref = hd_test_ref();
    if (!ref) SKIP("no reference folder");
    char path[1024], line[4096];
    snprintf(path, sizeof path, "%s/scenes/box/box_room.rad", ref);
    FILE *fp = fopen(path, "r");
    if (!fp) SKIP("box_room.rad missing under the reference folder");
    size_t expect = 0, npoly = 0;
    while (fgets(line, sizeof line, fp)) {
        char a[256], b[256];
        if (sscanf(line, " %255s %255s", a, b) == 2 && a[0] != '#') {
            expect++;
            if (!strcmp(b, "polygon")) npoly++;
        }
    }
    fclose(fp);
    hd_scene s;
    hd_scene_init(&s);
    REQUIRE(hd_scene_load_rad(&s, path, NULL) == HD_OK);
    CHECK(s.nprims == expect);
    size_t n = 0;
    for (size_t i = 0; i < s.nprims; i++) n += s.prims[i].type == HD_T_POLYGON;
    CHECK(n == npoly);
    CHECK(npoly >= 10);
    hd_scene_free(&s);
}

/* Mutated inputs (bytes changed, inserted, cut) never crash the parser or
 * the cache reader; run under check-asan this also checks memory safety.
 * '!' is never produced, so no random shell command is run. */
static void test_fuzz(void)
{
    const char *base =
        "void plastic m 0 0 5 .1 .2 .3 0 0\n"
        "m polygon a 0 0 12 0 0 0 1 0 0 1 1 0 0 1 0\n"
        "void brightfunc pat 4 'a b' x.cal -rz 30 0 2 1 2\n"
        "pat alias m2 m\ninherit alias m3 m2\n"
        "m2 sphere c 0 0 4 0 0 0 1\nm ring r 0 0 8 0 0 0 0 0 1 0 1\n"
        "void BSDF b 6 0 f.xml 0 0 1 . 0 3 .1 .1 .1\n";
    static const char alphabet[] = " \n\t'\"#0123456789.-+eEabcmpolygnvid";
    hd_rng r;
    hd_rng_init(&r, 7, 0);
    char buf[1024];
    size_t blen = strlen(base);
    int accepted = 0, rejected = 0;
    hd_set_warnings(0);   /* mutated polygons warn about planarity */
    for (int it = 0; it < 3000; it++) {
        memcpy(buf, base, blen + 1);
        size_t len = blen;
        int nmut = 1 + (int)(hd_rng_uniform(&r) * 4);
        for (int k = 0; k < nmut && len > 0; k++) {
            size_t pos = (size_t)(hd_rng_uniform(&r) * (double)len);
            double u = hd_rng_uniform(&r);
            char c = alphabet[(int)(hd_rng_uniform(&r) * (sizeof alphabet - 1))];
            if (u < 0.4) buf[pos] = c;
            else if (u < 0.7 && len + 1 < sizeof buf) { memmove(buf + pos + 1, buf + pos, len - pos + 1); buf[pos] = c; len++; }
            else if (u < 0.9) { memmove(buf + pos, buf + pos + 1, len - pos); len--; }
            else { buf[pos] = 0; len = pos; }
        }
        hd_scene s;
        hd_scene_init(&s);
        if (hd_scene_load_string(&s, buf, "fuzz.rad", NULL) == HD_OK) accepted++;
        else { rejected++; CHECK(strstr(hd_errmsg(), "fuzz.rad") != NULL); }
        hd_scene_free(&s);
    }
    hd_set_warnings(1);
    CHECK(accepted > 0 && rejected > 0);
    /* cache: flip bytes of a valid file */
    hd_scene s;
    REQUIRE(load(&s, base) == HD_OK);
    char path[512], bad[512];
    snprintf(path, sizeof path, "%s/test_scene_fuzz.oct", hd_test_tmpdir());
    snprintf(bad, sizeof bad, "%s/test_scene_fuzz_bad.oct", hd_test_tmpdir());
    REQUIRE(hd_scene_write_cache(&s, path, 0, NULL) == HD_OK);
    hd_scene_free(&s);
    FILE *fp = fopen(path, "rb");
    REQUIRE(fp);
    unsigned char data[8192];
    size_t n = fread(data, 1, sizeof data, fp);
    fclose(fp);
    size_t body = 0;
    for (size_t k = 0; k + 8 <= n; k++) if (!memcmp(data + k, "HDSCENE\n", 8)) { body = k; break; }
    REQUIRE(body > 0);
    int crc_ok = 0, crc_bad = 0;
    for (int it = 0; it < 500; it++) {
        unsigned char m[8192];
        memcpy(m, data, n);
        int nflip = 1 + (int)(hd_rng_uniform(&r) * 3);
        for (int k = 0; k < nflip; k++) {
            size_t pos = body + (size_t)(hd_rng_uniform(&r) * (double)(n - body));
            m[pos] = (unsigned char)(hd_rng_uniform(&r) * 256);
        }
        fp = fopen(bad, "wb");
        fwrite(m, 1, n, fp);
        fclose(fp);
        hd_scene t;
        hd_scene_init(&t);
        if (hd_scene_read_cache(&t, bad) == HD_OK) crc_ok++; else crc_bad++;
        hd_scene_free(&t);
    }
    CHECK(crc_bad > 0);
    (void)crc_ok;
}

int main(void)
{
    RUN(test_ref_box_room);
    RUN(test_basic);
    RUN(test_shadowing_and_alias);
    RUN(test_commands);
    RUN(test_skip_missing);
    RUN(test_errors);
    RUN(test_unsupported_kept);
    RUN(test_negative_radii);
    RUN(test_type_names);
    RUN(test_cache_roundtrip);
    RUN(test_fuzz);
    return hd_test_done();
}

/* Fuzz harness: program options (options.h) — the input is a command line
 * (words separated by NUL or newline bytes) parsed against a table with
 * every option kind (toggles, int, long, counts with k/m/g, reals, real
 * triples, strings, prefixes, nested tables, callbacks), and against
 * rcontrib's table (render options, -m/-b/-bn/-o/-p/-e with bin
 * expressions, format letters, -x/-y/-c).  Words naming files to read
 * (-f file.cal, -M file) end the command line: reading files is not this
 * harness's job. */
#include <stdio.h>

#include "fuzz.h"
#include "heliodon/contrib.h"
#include "heliodon/options.h"
#include "heliodon/render.h"

#define MAXW 64

static int cb_two(const hd_opt *opt, int argc, char **argv, int i, void *ctx)
{
    (void)opt;
    int *n = ctx;
    if (i + 2 >= argc) { hd_fail(HD_ERR_USAGE, "option %s expects two words", argv[i]); return -1; }
    *n += (int)strlen(argv[i + 1]) + (int)strlen(argv[i + 2]);
    return 2;
}

static void generic(int argc, char **argv)
{
    int tog = 0, iv = 0, cbn = 0;
    long lv = 0;
    uint64_t cv = 0;
    double rv = 0, r3[3] = {0, 0, 0};
    const char *sv = NULL, *pv = NULL;
    hd_render_opts ro;
    hd_render_defaults(&ro);
    hd_opt render_tab[HD_RENDER_NOPTS];
    hd_render_option_table(render_tab, &ro);
    const hd_opt table[] = {
        {"T", HD_OPT_TOGGLE, &tog, 0, 0, 0, "toggle"},
        {"i", HD_OPT_INT, &iv, 0, 0, "N", "int"},
        {"l", HD_OPT_LONG, &lv, 0, 0, "N", "long"},
        {"c", HD_OPT_COUNT, &cv, 0, 0, "N", "count"},
        {"r", HD_OPT_REAL, &rv, 0, 0, "x", "real"},
        {"r3", HD_OPT_REAL3, r3, 0, 0, "x y z", "three reals"},
        {"s", HD_OPT_STRING, &sv, 0, 0, "word", "string"},
        {"f", HD_OPT_STRING, &pv, 0, 1, 0, "prefix string"},
        {"cb", HD_OPT_FUNC, &cbn, cb_two, 0, "a b", "callback"},
        {"", HD_OPT_TABLE, render_tab, 0, 0, 0, "render options"},
        HD_OPT_END};
    int first = 0;
    (void)hd_opt_parse_args(argc, argv, table, &first);
    for (int i = 1; i < argc; i++)
        if (argv[i][0] == '-' || argv[i][0] == '+') (void)hd_opt_parse_one(table, argc, argv, i);
    (void)hd_opt_toggle_value(argc > 1 ? argv[1] : "-T", tog);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    hd_fuzz_setup();
    hd_set_warnings(0);
    if (size > 4096) return 0;
    char *text = hd_fuzz_cstr(data, size);
    char *argv[MAXW + 2];
    int argc = 0;
    argv[argc++] = "prog";
    char *p = text, *end = text + size;
    while (p < end && argc < MAXW) {
        char *w = p;
        while (p < end && *p && *p != '\n') p++;
        *p++ = 0;
        /* '+M' is -M to the parser too, and its file "!cmd" would run a
         * command (a 10 s timeout found by the fuzzer in the harness) */
        if (((w[0] == '-' || w[0] == '+') && (!strcmp(w + 1, "f") || !strcmp(w + 1, "M") || !strcmp(w + 1, "vf"))) ||
            w[0] == '@')
            break;
        argv[argc++] = w;
    }
    argv[argc] = NULL;
    generic(argc, argv);
    hd_contrib c;
    hd_rcontrib_opts o;
    memset(&c, 0, sizeof c);
    hd_rcontrib_defaults(&o, &c.o);
    o.rflux = size > 0 && data[0] == 'R';
    argv[0] = "rcontrib";
    int first = 0;
    (void)hd_rcontrib_parse_args(argc, argv, &c, &o, &first);
    hd_contrib_free(&c);
    free(text);
    return 0;
}

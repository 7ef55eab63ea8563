/* pcomb — combine Radiance pictures with .cal expressions, as Radiance's
 * pcomb (docs/man/pcomb.1); options parsed as Radiance parses them. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/io.h"
#include "heliodon/pictools.h"

static void usage(const char *prog)
{
    hd_die_msg("usage: %s [-w][-h][-ff][-x xr][-y yr][-e expr][-f file] [ [-o][-s f][-c r g b] hdr ..]", prog);
}

static double num(int argc, char **argv, int i)
{
    double v;
    if (i >= argc || hd_parse_double(argv[i], &v)) hd_die_msg("%s: expected a number", argv[i - 1]);
    return v;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    hd_pcomb_opts o;
    memset(&o, 0, sizeof o);
    o.echo_header = 1;
    o.defkind = calloc((size_t)argc, 1);
    o.deftext = calloc((size_t)argc, sizeof *o.deftext);
    o.inputs = calloc((size_t)argc, sizeof *o.inputs);
    if (!o.defkind || !o.deftext || !o.inputs) hd_die();
    int a;
    for (a = 1; a < argc && argv[a][0] == '-'; a++) {
        char c = argv[a][1];
        if (c == 'x' || c == 'y' || c == 'e' || (c == 'f' && !argv[a][2])) {
            if (a + 1 >= argc) usage(argv[0]);
            o.defkind[o.ndefs] = c;
            o.deftext[o.ndefs++] = argv[++a];
        } else if (c == 'f') {
            o.outfloat = argv[a][2] == 'f';
            if (argv[a][2] != 'f' && argv[a][2] != 'c') hd_die_msg("unsupported output format %s", argv[a]);
            if (argv[a][2] == 'c') o.outfloat = 0;
        } else if (c == 'w') {
            o.nowarn = !o.nowarn;
        } else if (c == 'h') {
            o.echo_header = !o.echo_header;
        } else {
            break;
        }
    }
    hd_pcomb_input cur = {NULL, 0, {1, 1, 1}};
    for (; a < argc; a++) {
        if (argv[a][0] == '-' && argv[a][1]) {
            switch (argv[a][1]) {
            case 'o': cur.original = 1; continue;
            case 's': { double f = num(argc, argv, ++a); for (int k = 0; k < 3; k++) cur.coef[k] *= f; continue; }
            case 'c': for (int k = 0; k < 3; k++) cur.coef[k] *= num(argc, argv, ++a); continue;
            default: usage(argv[0]);
            }
        }
        cur.name = argv[a];
        o.inputs[o.ninputs++] = cur;
        cur = (hd_pcomb_input){NULL, 0, {1, 1, 1}};
    }
    if (hd_pcomb(&o, argc, argv, stdout) || fflush(stdout)) hd_die();
    free(o.defkind); free(o.deftext); free(o.inputs);
    return 0;
}

/* gensurf — generate a parametric surface as Radiance polygons (heliodon).
 *   gensurf mat name 'x(s,t)' 'y(s,t)' 'z(s,t)' m n [-e expr] [-f file] [-s] [-i] */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/cal.h"
#include "heliodon/common.h"
#include "heliodon/xform.h"

/* the curve helpers gensurf offers its expressions (t in [0,1]) */
static const char helpers[] =
    "hermite(p0,p1,r0,r1,t) : p0*((2*t-3)*t*t+1) + p1*(3-2*t)*t*t + r0*((t-2)*t+1)*t + r1*(t-1)*t*t;\n"
    "bezier(p1,p2,p3,p4,t) : p1*(1+t*(-3+t*(3-t))) + p2*3*t*(1+t*(t-2)) + p3*3*t*t*(1-t) + p4*t*t*t;\n"
    "bspline(pp,p0,p1,pn,t) : pp*(1/6+t*(-1/2+t*(1/2-t/6))) + p0*(2/3+t*t*(t/2-1))"
    " + p1*(1/6+t*(1/2+t*(1/2-t/2))) + pn*t*t*t/6;\n";

/* a word of the command line as Radiance's headers write it */
static void put_word(const char *w)
{
    int quote = 0, space = !*w;
    for (const char *c = w; *c; c++) {
        if (isspace((unsigned char)*c)) space = 1;
        else if (c > w && c[1] && *c == '"') quote = '\'';
        else if (c > w && c[1] && *c == '\'') quote = '"';
    }
    if (space || quote) printf("%c%s%c", quote ? quote : '"', w, quote ? quote : '"');
    else fputs(w, stdout);
}

static int grid(hd_cal *c, const char *text)
{
    double v;
    if (hd_cal_eval(c, text, &v)) hd_die();
    if (!(v + .5 >= 1) || v > 1e7) hd_die_msg("bad number of divisions '%s'", text);
    return (int)(v + .5);
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    if (argc < 8)
        hd_die_msg("usage: %s material name x(s,t) y(s,t) z(s,t) m n [-s][-i][-e expr][-f file]", hd_progname());
    hd_cal *c = hd_cal_new();
    if (!c || hd_cal_set(c, "PI", 3.14159265358979323846, 1) || hd_cal_parse(c, helpers, "gensurf")) hd_die();
    hd_gensurf_opts o = {argv[1], argv[2], argv[3], argv[4], argv[5], 0, 0, 0, 0};
    for (int i = 8; i < argc; i++) {
        if (!strcmp(argv[i], "-e") && i + 1 < argc) {
            if (hd_cal_parse(c, argv[++i], "-e")) hd_die();
        } else if (!strcmp(argv[i], "-f") && i + 1 < argc) {
            if (hd_cal_load(c, argv[++i])) hd_die();
        } else if (!strcmp(argv[i], "-s")) {
            o.smooth = 1;
        } else if (!strcmp(argv[i], "-i")) {
            o.rev = 1;
        } else if (!strcmp(argv[i], "-o")) {
            hd_die_msg("-o (Wavefront .OBJ output) is not supported");
        } else {
            hd_die_msg("unknown or incomplete option '%s'", argv[i]);
        }
    }
    if (!strcmp(argv[5], "-"))
        hd_die_msg("z values from a data file are not supported (give z(s,t) as an expression)");
    FILE *probe = fopen(argv[5], "r");
    if (probe) {
        fclose(probe);
        hd_die_msg("'%s' is a file: z values from a data file are not supported", argv[5]);
    }
    o.m = grid(c, argv[6]);
    o.n = grid(c, argv[7]);
    fputs("# ", stdout);
    for (int i = 0; i < argc; i++) {
        if (i) putchar(' ');
        put_word(i ? argv[i] : hd_progname());
    }
    putchar('\n');
    if (hd_gensurf_write(stdout, c, &o)) hd_die();
    hd_cal_free(c);
    if (fflush(stdout)) hd_die_msg("write error on standard output");
    return 0;
}

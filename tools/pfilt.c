/* pfilt — filter and resample a Radiance picture (docs/man/pfilt.1);
 * options parsed the way Radiance's pfilt parses them. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/io.h"
#include "heliodon/pictools.h"

static const char *arg(int argc, char **argv, int i)
{
    if (i >= argc) hd_die_msg("option %s needs a value", argv[i - 1]);
    return argv[i];
}

static double num(int argc, char **argv, int i)
{
    double v;
    if (hd_parse_double(arg(argc, argv, i), &v)) hd_die_msg("option %s: bad number \"%s\"", argv[i - 1], argv[i]);
    return v;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    hd_pfilt_opts o;
    hd_pfilt_opts_default(&o);
    const char *lampdat = "lamp.tab", *lamptype = NULL;
    int i;
    for (i = 1; i < argc && argv[i][0] == '-' && argv[i][1]; i++) {
        switch (argv[i][1]) {
        case 'x': case 'y': {
            const char *a = arg(argc, argv, ++i);
            double v;
            int isx = argv[i - 1][1] == 'x';
            if (a[0] == '/') {
                if (hd_parse_double(a + 1, &v) || v <= 0) hd_die_msg("option -%c: bad divisor \"%s\"", argv[i - 1][1], a);
                if (isx) { o.xratio = 1.0 / v; o.ncols = 0; } else { o.yratio = 1.0 / v; o.nrows = 0; }
            } else {
                long n;
                if (hd_parse_long(a, &n) || n <= 0 || n > 1000000) hd_die_msg("option -%c: bad size \"%s\"", argv[i - 1][1], a);
                if (isx) o.ncols = (int)n; else o.nrows = (int)n;
            }
            break;
        }
        case 'c': o.correctaspect = !o.correctaspect; break;
        case 'p': o.outaspect = num(argc, argv, ++i); break;
        case 'e': {
            const char *a = arg(argc, argv, i + 1);
            double d = num(argc, argv, i + 1);
            if (a[0] == '+' || a[0] == '-') d = pow(2.0, d);
            if (d < 1e-20 || d > 1e20) hd_die_msg("exposure out of range");
            switch (argv[i][2]) {
            case 0: for (int k = 0; k < 3; k++) o.exposure[k] *= d; break;
            case 'r': o.exposure[0] *= d; break;
            case 'g': o.exposure[1] *= d; break;
            case 'b': o.exposure[2] *= d; break;
            default: hd_die_msg("unknown option: %s", argv[i]);
            }
            i++;
            break;
        }
        case 'f': lampdat = arg(argc, argv, ++i); break;
        case 't': lamptype = arg(argc, argv, ++i); break;
        case '1': o.singlepass = 1; break;
        case '2': o.singlepass = 0; break;
        case 'n': o.npts = (int)num(argc, argv, ++i) / 2; break;
        case 's': o.spread = num(argc, argv, ++i); break;
        case 'a': o.avghot = !o.avghot; break;
        case 'h': o.hotlvl = num(argc, argv, ++i); break;
        case 'r': o.rad = num(argc, argv, ++i); break;
        case 'm':
            o.thresh = num(argc, argv, ++i);
            if (o.rad <= 1e-6) o.rad = 0.6;
            break;
        case 'b': o.rad = o.thresh = 0.0; break;
        default: hd_die_msg("unknown option: %s", argv[i]);
        }
    }
    if (i < argc - 1) hd_die_msg("bad # file arguments");
    if (lamptype) {             /* colour balance for the lamp: exposure / its colour */
        double rgb[3];
        if (hd_lamp_color(lampdat, lamptype, rgb)) hd_die();
        for (int k = 0; k < 3; k++)
            if (rgb[k] > 1e-4) o.exposure[k] = (float)((float)o.exposure[k] / (float)rgb[k]);
    }
    const char *path = i < argc ? argv[i] : "-";
    hd_picture in;
    if (hd_picture_read(path, &in)) hd_die();
    if (hd_pfilt(&in, &o, i, argv, stdout) || fflush(stdout)) hd_die();
    hd_picture_free(&in);
    return 0;
}

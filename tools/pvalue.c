/* pvalue — convert a Radiance picture to or from pixel values (ascii,
 * integer, byte, 16-bit, float, double), as Radiance's pvalue.  See
 * docs/man/pvalue.1 for the options and the differences from Radiance.
 *
 * Options are parsed the way Radiance's pvalue parses them (the letter after
 * the sign decides; "+" / "-" select the setting), so that command lines
 * written for Radiance work unchanged. */
#include "heliodon/common.h"
#include "heliodon/pvalue.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static double num_arg(int argc, char **argv, int i)
{
    double v;
    if (i >= argc) hd_die_msg("option %s needs a value", argv[i - 1]);
    if (hd_parse_double(argv[i], &v)) hd_die_msg("option %s: bad number \"%s\"", argv[i - 1], argv[i]);
    return v;
}

static long int_arg(int argc, char **argv, int i)
{
    long v;
    if (i >= argc) hd_die_msg("option %s needs a value", argv[i - 1]);
    if (hd_parse_long(argv[i], &v)) hd_die_msg("option %s: bad integer \"%s\"", argv[i - 1], argv[i]);
    return v;
}

static void set_format(hd_pvalue_opts *o, char c, int minus)
{
    if (hd_pvalue_set_format(o, c, minus)) hd_die();
}

/* Radiance-style options into *o; returns the index of the first file
 * argument and sets *reverse for -r. */
static int parse_options(int argc, char **argv, hd_pvalue_opts *o, int *reverse)
{
    int i;
    hd_pvalue_opts_init(o);
    *reverse = 0;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if ((a[0] != '-' && a[0] != '+') || !a[1]) break;   /* "-" = stdin */
        int minus = a[0] == '-';
        switch (a[1]) {
        case 'h': o->header = !minus; break;
        case 'H': o->resolution = !minus; break;
        case 's': o->skipbytes = int_arg(argc, argv, ++i); break;
        case 'u': o->uniq = minus; break;
        case 'o': o->original = minus; break;
        case 'O': o->original = minus ? -1 : 0; break;
        case 'g':
            o->gamcor = num_arg(argc, argv, ++i);
            if (o->gamcor <= 0) hd_die_msg("gamma must be positive");
            if (!minus) o->gamcor = 1.0 / o->gamcor;
            break;
        case 'e': {
            double d = num_arg(argc, argv, ++i);
            if (argv[i][0] == '-' || argv[i][0] == '+') d = pow(2.0, d);
            if (minus) o->expval *= d;
            for (int c = 0; c < 3; c++) o->exposure[c] *= (float)d;
            o->doexposure++;
            break;
        }
        case 'R':
            if (minus) { o->ord[0] = HD_PV_BLU; o->ord[1] = HD_PV_GRN; o->ord[2] = HD_PV_RED; }
            else { o->ord[0] = HD_PV_RED; o->ord[1] = HD_PV_GRN; o->ord[2] = HD_PV_BLU; }
            break;
        case 'r': *reverse = minus; break;
        case 'n': o->interleave = !minus; break;
        case 'b': o->putprim = minus ? HD_PV_BRIGHT : HD_PV_ALL; break;
        case 'p':
            switch (a[2]) {
            case '\0':
                for (int k = 0; k < 8; k++) o->prims[k] = num_arg(argc, argv, ++i);
                o->prims_mode = HD_PV_PRIM_CUSTOM;
                break;
            case 'x': case 'X': o->prims_mode = HD_PV_PRIM_XYZ; break;
            case 'r': case 'R': o->putprim = HD_PV_RED; break;
            case 'g': case 'G': o->putprim = HD_PV_GRN; break;
            case 'b': case 'B': o->putprim = HD_PV_BLU; break;
            default: hd_die_msg("unknown option: %s", a);
            }
            break;
        case 'd': set_format(o, a[2], minus); break;
        case 'f':   /* heliodon extension: -fa, -ff, -fd (and -fF, -fD) = -da, -df, -dd */
            if (a[2] && strchr("afdFD", a[2]) && !a[3]) set_format(o, a[2], minus);
            else hd_die_msg("unknown option: %s", a);
            break;
        case 'x': case 'X': {
            long v = int_arg(argc, argv, ++i);
            o->resolution = 0;
            if (minus) o->picres.orient |= HD_RES_XDECR;
            if (v <= 0 || v > HD_PIC_MAXSIDE)
                hd_die_msg("x resolution %ld out of range (1 to %d)", v, HD_PIC_MAXSIDE);
            o->picres.xres = (int)v;
            break;
        }
        case 'y': case 'Y': {
            long v = int_arg(argc, argv, ++i);
            o->resolution = 0;
            if (minus) o->picres.orient |= HD_RES_YDECR;
            if (o->picres.xres == 0) o->picres.orient |= HD_RES_YMAJOR;
            if (v <= 0 || v > HD_PIC_MAXSIDE)
                hd_die_msg("y resolution %ld out of range (1 to %d)", v, HD_PIC_MAXSIDE);
            o->picres.yres = (int)v;
            break;
        }
        default:
            hd_die_msg("unknown option: %s", a);
        }
    }
    hd_pvalue_opts_finish(o);
    return i;
}

int main(int argc, char **argv)
{
    hd_pvalue_opts o;
    int reverse;
    hd_set_progname(argv[0]);
    static char obuf[1 << 16];
    setvbuf(stdout, obuf, _IOFBF, sizeof obuf);
    int first = parse_options(argc, argv, &o, &reverse);
    int nfiles = argc - first;
    hd_status st;
    if (reverse)
        st = hd_pvalue_from_values(&o, (const char *const *)(argv + first), nfiles, stdout, first, argv);
    else if (nfiles > 1)
        st = hd_fail(HD_ERR_USAGE, "bad # file arguments (expected one picture or none)");
    else
        st = hd_pvalue_to_values(&o, nfiles ? argv[first] : "-", stdout, first, argv);
    if (st) hd_die();
    return 0;
}

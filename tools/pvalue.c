/* pvalue — convert a Radiance picture to or from pixel values (ascii,
 * integer, byte, 16-bit, float, double), as Radiance's pvalue.  See
 * docs/man/pvalue.1 for the options and the differences from Radiance.
 *
 * Options are parsed the way Radiance's pvalue parses them (the letter after
 * the sign decides; "+" / "-" select the setting), so that command lines
 * written for Radiance work unchanged. */
#include "heliodon/common.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/picture.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { P_RED = 0, P_GRN = 1, P_BLU = 2, P_ALL = 3, P_BRIGHT = 4 };
enum { PR_STD = 0, PR_CUSTOM = 1, PR_XYZ = 2 };

static struct {
    int uniq, dataonly, putprim, reverse, format, header, swapbytes, interleave;
    int resolution, original, doexposure, xyzin, prims_mode;
    long skipbytes;
    double gamcor, expval, prims[8];
    float exposure[3];
    const char *fmtid;
    int ord[3], rord[3];
    hd_resolu picres;
    int nfiles;
    char **files;
    int argc_opts;
    char **argv;
} O;

static int native_bigendian(void)
{
    const uint16_t one = 1;
    return *(const uint8_t *)&one == 0;
}

static void swap_bytes(void *p, size_t size, size_t n)
{
    uint8_t *b = p;
    for (size_t k = 0; k < n; k++, b += size)
        for (size_t i = 0; i < size / 2; i++) {
            uint8_t t = b[i];
            b[i] = b[size - 1 - i];
            b[size - 1 - i] = t;
        }
}

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

static void set_dformat(char c, int minus)
{
    O.dataonly = minus;
    switch (c) {
    case '\0': case 'a': O.format = 'a'; O.fmtid = "ascii"; break;
    case 'i': O.format = 'i'; O.fmtid = "ascii"; break;
    case 'b': O.dataonly = 1; O.format = 'b'; O.fmtid = "byte"; break;
    case 'W': O.swapbytes = 1; /* fall through */
    case 'w': O.dataonly = 1; O.format = 'w'; O.fmtid = "16-bit"; break;
    case 'F': O.swapbytes = 1; /* fall through */
    case 'f': O.dataonly = 1; O.format = 'f'; O.fmtid = "float"; break;
    case 'D': O.swapbytes = 1; /* fall through */
    case 'd': O.dataonly = 1; O.format = 'd'; O.fmtid = "double"; break;
    default: hd_die_msg("unknown data format option: -d%c (expected a, i, b, w, W, f, F, d or D)", c);
    }
}

static void parse_options(int argc, char **argv)
{
    int i;
    O.putprim = P_ALL;
    O.format = 'a';
    O.fmtid = "ascii";
    O.header = O.interleave = O.resolution = 1;
    O.gamcor = O.expval = 1.0;
    O.exposure[0] = O.exposure[1] = O.exposure[2] = 1.0f;
    O.ord[0] = P_RED; O.ord[1] = P_GRN; O.ord[2] = P_BLU;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if ((a[0] != '-' && a[0] != '+') || !a[1]) break;   /* "-" = stdin */
        int minus = a[0] == '-';
        switch (a[1]) {
        case 'h': O.header = !minus; break;
        case 'H': O.resolution = !minus; break;
        case 's': O.skipbytes = int_arg(argc, argv, ++i); break;
        case 'u': O.uniq = minus; break;
        case 'o': O.original = minus; break;
        case 'O': O.original = minus ? -1 : 0; break;
        case 'g':
            O.gamcor = num_arg(argc, argv, ++i);
            if (O.gamcor <= 0) hd_die_msg("gamma must be positive");
            if (!minus) O.gamcor = 1.0 / O.gamcor;
            break;
        case 'e': {
            double d = num_arg(argc, argv, ++i);
            if (argv[i][0] == '-' || argv[i][0] == '+') d = pow(2.0, d);
            if (minus) O.expval *= d;
            for (int c = 0; c < 3; c++) O.exposure[c] *= (float)d;
            O.doexposure++;
            break;
        }
        case 'R':
            if (minus) { O.ord[0] = P_BLU; O.ord[1] = P_GRN; O.ord[2] = P_RED; }
            else { O.ord[0] = P_RED; O.ord[1] = P_GRN; O.ord[2] = P_BLU; }
            break;
        case 'r': O.reverse = minus; break;
        case 'n': O.interleave = !minus; break;
        case 'b': O.putprim = minus ? P_BRIGHT : P_ALL; break;
        case 'p':
            switch (a[2]) {
            case '\0':
                for (int k = 0; k < 8; k++) O.prims[k] = num_arg(argc, argv, ++i);
                O.prims_mode = PR_CUSTOM;
                break;
            case 'x': case 'X': O.prims_mode = PR_XYZ; break;
            case 'r': case 'R': O.putprim = P_RED; break;
            case 'g': case 'G': O.putprim = P_GRN; break;
            case 'b': case 'B': O.putprim = P_BLU; break;
            default: hd_die_msg("unknown option: %s", a);
            }
            break;
        case 'd': set_dformat(a[2], minus); break;
        case 'f':   /* heliodon extension: -fa, -ff, -fd (and -fF, -fD) = -da, -df, -dd */
            if (a[2] && strchr("afdFD", a[2]) && !a[3]) set_dformat(a[2], minus);
            else hd_die_msg("unknown option: %s", a);
            break;
        case 'x': case 'X': {
            long v = int_arg(argc, argv, ++i);
            O.resolution = 0;
            if (minus) O.picres.orient |= HD_RES_XDECR;
            if (v <= 0 || v > HD_PIC_MAXSIDE)
                hd_die_msg("x resolution %ld out of range (1 to %d)", v, HD_PIC_MAXSIDE);
            O.picres.xres = (int)v;
            break;
        }
        case 'y': case 'Y': {
            long v = int_arg(argc, argv, ++i);
            O.resolution = 0;
            if (minus) O.picres.orient |= HD_RES_YDECR;
            if (O.picres.xres == 0) O.picres.orient |= HD_RES_YMAJOR;
            if (v <= 0 || v > HD_PIC_MAXSIDE)
                hd_die_msg("y resolution %ld out of range (1 to %d)", v, HD_PIC_MAXSIDE);
            O.picres.yres = (int)v;
            break;
        }
        default:
            hd_die_msg("unknown option: %s", a);
        }
    }
    if (O.dataonly && O.format == 'b') O.fmtid = O.putprim == P_ALL ? "24-bit_rgb" : "8-bit_grey";
    if (O.dataonly && O.format == 'w') O.fmtid = O.putprim == P_ALL ? "48-bit_rgb" : "16-bit_grey";
    O.rord[O.ord[0]] = 0;
    O.rord[O.ord[1]] = 1;
    O.rord[O.ord[2]] = 2;
    O.argc_opts = i;
    O.argv = argv;
    O.files = argv + i;
    O.nfiles = argc - i;
}

/* ---------------------------------------------------------------- */
/* output helpers                                                    */

static void put_header(hd_header *oh, const char *fmt)
{
    size_t n = 0;
    if (hd_header_write(stdout, oh, &n)) hd_die();
    if (hd_header_write_format(stdout, fmt, n)) hd_die();
}

/* Copy the lines of h into oh, dropping FORMAT, NROWS, NCOLS, NCOMP,
 * BigEndian (noting its value) and, with -o, EXPOSURE / COLORCORR (folded
 * into the exposure correction). */
static void filter_header(const hd_header *h, hd_header *oh, int *bigendian)
{
    const char *l = h->text ? h->text : "";
    char line[HD_HEADER_MAXLINE + 2];
    *bigendian = -1;
    while (*l) {
        const char *e = strchr(l, '\n');
        size_t n = e ? (size_t)(e - l) : strlen(l);
        size_t k = n < sizeof line - 1 ? n : sizeof line - 1;
        memcpy(line, l, k);
        line[k] = 0;
        l += e ? n + 1 : n;
        if (!strncmp(line, "FORMAT=", 7) || !strncmp(line, "NROWS=", 6) ||
            !strncmp(line, "NCOLS=", 6) || !strncmp(line, "NCOMP=", 6))
            continue;
        if (!strncmp(line, "BigEndian=", 10)) {
            *bigendian = atoi(line + 10) != 0;
            continue;
        }
        if (O.original && !strncmp(line, "EXPOSURE=", 9)) {
            double d = atof(line + 9);
            if (d > 0)
                for (int c = 0; c < 3; c++) O.exposure[c] *= (float)(1.0 / d);
            O.doexposure++;
            continue;
        }
        if (O.original && !strncmp(line, "COLORCORR=", 10)) {
            double cc[3] = {1, 1, 1};
            if (sscanf(line + 10, "%lf %lf %lf", &cc[0], &cc[1], &cc[2]) == 3)
                for (int c = 0; c < 3; c++)
                    if (cc[c] > 0) O.exposure[c] = (float)(O.exposure[c] / cc[c]);
            O.doexposure++;
            continue;
        }
        if (hd_header_append(oh, line)) hd_die();
    }
}

static void skip_bytes(hd_istream *s)
{
    char buf[4096];
    long n = O.skipbytes;
    while (n > 0) {
        size_t k = n > (long)sizeof buf ? sizeof buf : (size_t)n;
        if (hd_istream_read(s, buf, k) != k)
            hd_die_msg("%s: cannot skip %ld bytes on input", hd_istream_name(s), O.skipbytes);
        n -= (long)k;
    }
}

static void wbin(const void *p, size_t size, size_t n)
{
    if (fwrite(p, size, n, stdout) != n) hd_die_msg("write error on standard output");
}

/* one value (prim >= 0: that channel; P_BRIGHT; P_ALL) */
static void put_value(const float c[3], int prim, int xyz)
{
    double v[3];
    int nv = 3;
    if (prim == P_ALL) {
        v[0] = c[O.ord[0]];
        v[1] = c[O.ord[1]];
        v[2] = c[O.ord[2]];
    } else {
        v[0] = prim == P_BRIGHT ? (xyz ? c[1] : hd_rgb_bright(c)) : c[prim];
        nv = 1;
    }
    switch (O.format) {
    case 'a':
        if (nv == 3) printf("%15.3e %15.3e %15.3e\n", v[0], v[1], v[2]);
        else printf("%15.3e\n", v[0]);
        break;
    case 'i':
        if (nv == 3) printf("%d %d %d\n", (int)(v[0] * 256.), (int)(v[1] * 256.), (int)(v[2] * 256.));
        else printf("%d\n", (int)(v[0] * 256.));
        break;
    case 'b': {
        uint8_t b[3];
        for (int k = 0; k < nv; k++) {
            long i = (long)(v[k] * 256.);
            b[k] = (uint8_t)(i > 255 ? 255 : i);
        }
        wbin(b, 1, (size_t)nv);
        break;
    }
    case 'w': {
        uint16_t w[3];
        for (int k = 0; k < nv; k++) {
            long i = (long)(v[k] * 65536.);
            w[k] = (uint16_t)(i > 65535 ? 65535 : i);
        }
        if (O.swapbytes) swap_bytes(w, 2, (size_t)nv);
        wbin(w, 2, (size_t)nv);
        break;
    }
    case 'f': {
        float f[3];
        for (int k = 0; k < nv; k++) f[k] = (float)v[k];
        if (O.swapbytes) swap_bytes(f, 4, (size_t)nv);
        wbin(f, 4, (size_t)nv);
        break;
    }
    case 'd':
        if (O.swapbytes) swap_bytes(v, 8, (size_t)nv);
        wbin(v, 8, (size_t)nv);
        break;
    }
}

/* ---------------------------------------------------------------- */
/* picture -> values                                                 */

static int forward(void)
{
    hd_istream *s;
    if (O.nfiles > 1) hd_die_msg("bad # file arguments (expected one picture or none)");
    if (hd_istream_open(&s, O.nfiles ? O.files[0] : "-")) hd_die();
    if (O.skipbytes) skip_bytes(s);
    hd_header h;
    hd_picfmt fmt;
    hd_resolu r;
    if (hd_picture_read_header(s, &h, &fmt, &r)) hd_die();
    int xyz = fmt == HD_PIC_XYZE;
    hd_header oh;
    int be;
    hd_header_init(&oh);
    filter_header(&h, &oh, &be);
    if (O.original < 0 && xyz) {
        for (int c = 0; c < 3; c++) O.exposure[c] *= (float)(1.0 / 179.0);
        O.doexposure++;
    }
    int len = hd_resolu_scanlen(&r), nscan = hd_resolu_nscans(&r);
    if (O.header) {
        if (hd_header_add_command(&oh, O.argc_opts, O.argv)) hd_die();
        if (hd_header_appendf(&oh, "NCOMP=%d", O.putprim == P_ALL ? 3 : 1)) hd_die();
        if (!O.resolution && O.dataonly && !O.uniq)
            if (hd_header_appendf(&oh, "NCOLS=%d", len) || hd_header_appendf(&oh, "NROWS=%d", nscan))
                hd_die();
        if (O.expval < .99 || O.expval > 1.01)
            if (hd_header_appendf(&oh, "EXPOSURE=%e", O.expval)) hd_die();
        if (O.swapbytes) {
            if (hd_header_appendf(&oh, "BigEndian=%d", !native_bigendian())) hd_die();
        } else if (O.format != 'a' && O.format != 'i' && O.format != 'b') {
            if (hd_header_appendf(&oh, "BigEndian=%d", native_bigendian())) hd_die();
        }
        put_header(&oh, O.fmtid);
    }
    hd_header_free(&oh);
    hd_header_free(&h);
    if (O.resolution) {
        char res[64];
        hd_resolu_format(res, sizeof res, &r);
        fputs(res, stdout);
    }

    int dogamma = O.gamcor < .95 || O.gamcor > 1.05;
    int startprim = O.putprim, endprim = O.putprim;
    uint8_t *all = NULL;            /* whole picture for -n */
    uint8_t *sl = hd_malloc((size_t)len * 4);
    if (!sl) hd_die();
    if (O.putprim == P_ALL && !O.interleave) {
        startprim = P_RED;
        endprim = P_BLU;
        all = hd_malloc_array((size_t)len * (size_t)nscan, 4);
        if (!all) hd_die();
        for (int y = 0; y < nscan; y++)
            if (hd_scanline_read(s, all + (size_t)y * len * 4, len)) hd_die();
    }
    for (int prim = startprim; prim <= endprim; prim++) {
        float last[3] = {0, 0, 0};
        for (int y = 0; y < nscan; y++) {
            const uint8_t *row;
            if (all) row = all + (size_t)y * len * 4;
            else {
                if (hd_scanline_read(s, sl, len)) hd_die();
                row = sl;
            }
            for (int x = 0; x < len; x++) {
                float c[3];
                hd_rgbe_decode(row + 4 * x, c);
                if (O.uniq) {
                    if (c[0] == last[0] && c[1] == last[1] && c[2] == last[2]) continue;
                    memcpy(last, c, sizeof last);
                }
                if (O.doexposure)
                    for (int k = 0; k < 3; k++) c[k] *= O.exposure[k];
                if (dogamma)
                    for (int k = 0; k < 3; k++) c[k] = (float)pow(c[k], 1.0 / O.gamcor);
                if (!O.dataonly) {
                    int px, py;
                    hd_resolu_pixel(&r, y, x, &px, &py);
                    printf("%7d %7d ", px, py);
                }
                put_value(c, prim, xyz);
            }
        }
    }
    free(all);
    free(sl);
    hd_istream_close(s);
    if (fflush(stdout) || ferror(stdout)) hd_die_msg("write error on standard output");
    return 0;
}

/* ---------------------------------------------------------------- */
/* values -> picture                                                 */

typedef struct vsrc {
    hd_istream *s;
    const uint8_t *mem;     /* non-interleaved binary: a channel's block */
    size_t memlen, mempos;
} vsrc;

static void get_bin(vsrc *v, void *dst, size_t size, const char *what)
{
    if (v->mem) {
        if (v->mempos + size > v->memlen)
            hd_die_msg("%s: unexpected end of data reading %s", hd_istream_name(v->s), what);
        memcpy(dst, v->mem + v->mempos, size);
        v->mempos += size;
        return;
    }
    if (hd_istream_read_exact(v->s, dst, size, what)) hd_die();
}

static double get_real(vsrc *v, const char *what)
{
    double d;
    if (hd_istream_real(v->s, &d, NULL)) {
        hd_fail_context(HD_ERR_FORMAT, "reading %s", what);
        hd_die();
    }
    return d;
}

/* one value of one channel from source v, decoded per the format */
static double get_one(vsrc *v, const char *what)
{
    switch (O.format) {
    case 'a': return get_real(v, what);
    case 'i': return (get_real(v, what) + .5) / 256.;
    case 'b': { uint8_t b; get_bin(v, &b, 1, what); return (b + .5) / 256.; }
    case 'w': {
        uint16_t w;
        get_bin(v, &w, 2, what);
        if (O.swapbytes) swap_bytes(&w, 2, 1);
        return (w + .5) / 65536.;
    }
    case 'f': {
        float f;
        get_bin(v, &f, 4, what);
        if (O.swapbytes) swap_bytes(&f, 4, 1);
        return f;
    }
    default: {
        double d;
        get_bin(v, &d, 8, what);
        if (O.swapbytes) swap_bytes(&d, 8, 1);
        return d;
    }
    }
}

static void read_header_into(hd_istream *s, hd_header *oh, int keep)
{
    hd_header h;
    int be;
    hd_header_init(&h);
    if (hd_header_read(s, &h, 1)) hd_die();
    char fmt[256];
    if (hd_header_get(&h, "FORMAT", fmt, sizeof fmt) && strcmp(fmt, O.fmtid))
        hd_die_msg("%s: wrong input format FORMAT=%s (expected %s)", hd_istream_name(s), fmt, O.fmtid);
    if (keep) {
        filter_header(&h, oh, &be);
        if (be >= 0) O.swapbytes = native_bigendian() != be;
    }
    hd_header_free(&h);
}

static int reverse(void)
{
    vsrc src[3];
    int nsrc = 1;
    memset(src, 0, sizeof src);
    if (O.nfiles == 3 && O.putprim != P_BRIGHT) nsrc = 3;
    else if (O.nfiles > 1) hd_die_msg("bad # file arguments (expected one input, three inputs or none)");
    for (int k = 0; k < nsrc; k++) {
        if (hd_istream_open(&src[k].s, O.nfiles ? O.files[k] : "-")) hd_die();
        if (O.skipbytes) skip_bytes(src[k].s);
    }
    if (nsrc == 3) O.interleave = -1;
    if (!O.interleave && O.putprim == P_ALL && (O.format == 'a' || O.format == 'i'))
        hd_die_msg("%s input files must be interleaved", O.format == 'a' ? "ASCII" : "integer");

    hd_header oh;
    hd_header_init(&oh);
    if (O.header)
        for (int k = 0; k < nsrc; k++) read_header_into(src[k].s, &oh, k == 0);
    if (O.resolution) {
        for (int k = 0; k < nsrc; k++) {
            hd_resolu rr;
            if (hd_resolu_read(src[k].s, &rr)) {
                hd_fail_context(HD_ERR_FORMAT, "missing resolution");
                hd_die();
            }
            if (k == 0) O.picres = rr;
            else if (rr.orient != O.picres.orient || rr.xres != O.picres.xres ||
                     rr.yres != O.picres.yres)
                hd_die_msg("resolution mismatch between %s and %s", O.files[0], O.files[k]);
        }
    }
    if (O.picres.xres <= 0 || O.picres.yres <= 0)
        hd_die_msg("missing resolution (give -y N +x M, or a resolution string in the input)");
    if (hd_resolu_check(&O.picres, "pvalue -r")) hd_die();

    if (hd_header_add_command(&oh, O.argc_opts, O.argv)) hd_die();
    if (O.expval < .99 || O.expval > 1.01)
        if (hd_header_appendf(&oh, "EXPOSURE=%e", O.expval)) hd_die();
    const char *pfmt = "32-bit_rle_rgbe";
    if (O.prims_mode == PR_CUSTOM) {
        if (hd_header_appendf(&oh, "PRIMARIES= %.4f %.4f %.4f %.4f %.4f %.4f %.4f %.4f",
                              O.prims[0], O.prims[1], O.prims[2], O.prims[3], O.prims[4],
                              O.prims[5], O.prims[6], O.prims[7]))
            hd_die();
    } else if (O.prims_mode == PR_XYZ) {
        if (O.original < 0) {
            for (int c = 0; c < 3; c++) O.exposure[c] *= 179.0f;
            O.doexposure++;
        }
        pfmt = "32-bit_rle_xyze";
    }
    put_header(&oh, pfmt);
    hd_header_free(&oh);
    char res[64];
    hd_resolu_format(res, sizeof res, &O.picres);
    fputs(res, stdout);

    int len = hd_resolu_scanlen(&O.picres), nscan = hd_resolu_nscans(&O.picres);
    size_t npix = (size_t)len * (size_t)nscan;
    uint8_t *whole = NULL;
    if (!O.interleave && O.putprim == P_ALL) {
        /* one binary file holding the red, green and blue blocks in turn */
        size_t vs = O.format == 'b' ? 1 : O.format == 'w' ? 2 : O.format == 'f' ? 4 : 8;
        size_t need;
        if (hd_mul_overflow(npix * 3, vs, &need)) hd_die_msg("picture too large");
        whole = hd_malloc(need);
        if (!whole) hd_die();
        if (hd_istream_read_exact(src[0].s, whole, need, "non-interleaved channel data")) hd_die();
        for (int k = 0; k < 3; k++) {
            src[k].s = src[0].s;
            src[k].mem = whole + (size_t)k * npix * vs;
            src[k].memlen = npix * vs;
        }
        nsrc = 3;
    }
    int dogamma = O.gamcor < .95 || O.gamcor > 1.05;
    uint8_t *sl = hd_malloc((size_t)len * 4);
    uint8_t *enc = hd_malloc(hd_scanline_maxbytes(len));
    if (!sl || !enc) hd_die();
    char what[96];
    for (int y = 0; y < nscan; y++) {
        for (int x = 0; x < len; x++) {
            double vd[3];
            snprintf(what, sizeof what, "pixel %d of scanline %d", x, y);
            if (!O.dataonly) {
                /* pixel positions are read and ignored, as Radiance does */
                for (int k = 0; k < (nsrc == 3 && !whole ? 3 : 1); k++) {
                    get_real(&src[k], what);
                    get_real(&src[k], what);
                }
            }
            float c[3];
            if (O.putprim != P_ALL) {
                double d = get_one(&src[0], what);
                c[0] = c[1] = c[2] = (float)d;
            } else {
                if (nsrc == 1)
                    for (int k = 0; k < 3; k++) vd[k] = get_one(&src[0], what);
                else
                    for (int k = 0; k < 3; k++) vd[k] = get_one(&src[k], what);
                c[0] = (float)vd[O.rord[P_RED]];
                c[1] = (float)vd[O.rord[P_GRN]];
                c[2] = (float)vd[O.rord[P_BLU]];
            }
            if (dogamma)
                for (int k = 0; k < 3; k++) c[k] = (float)pow(c[k], O.gamcor);
            if (O.doexposure)
                for (int k = 0; k < 3; k++) c[k] *= O.exposure[k];
            hd_rgbe_encode(sl + 4 * x, c[0], c[1], c[2]);
        }
        if (O.uniq) wbin(sl, 4, (size_t)len);    /* -u: flat, uncompressed scanlines */
        else wbin(enc, 1, hd_scanline_encode(enc, sl, len));
    }
    free(sl);
    free(enc);
    free(whole);
    for (int k = 0; k < (O.nfiles == 3 ? 3 : 1); k++)
        if (hd_istream_close(src[k].s)) hd_die();
    if (fflush(stdout) || ferror(stdout)) hd_die_msg("write error on standard output");
    return 0;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    static char obuf[1 << 16];
    setvbuf(stdout, obuf, _IOFBF, sizeof obuf);
    parse_options(argc, argv);
    return O.reverse ? reverse() : forward();
}

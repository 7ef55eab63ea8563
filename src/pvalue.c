/* pvalue: Radiance picture <-> pixel values (see include/heliodon/pvalue.h). */
#include "heliodon/pvalue.h"

#include "heliodon/header.h"
#include "heliodon/io.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

void hd_pvalue_opts_init(hd_pvalue_opts *o)
{
    memset(o, 0, sizeof *o);
    o->putprim = HD_PV_ALL;
    o->format = 'a';
    o->fmtid = "ascii";
    o->header = o->interleave = o->resolution = 1;
    o->gamcor = o->expval = 1.0;
    o->exposure[0] = o->exposure[1] = o->exposure[2] = 1.0f;
    o->ord[0] = HD_PV_RED;
    o->ord[1] = HD_PV_GRN;
    o->ord[2] = HD_PV_BLU;
}

hd_status hd_pvalue_set_format(hd_pvalue_opts *o, char c, int minus)
{
    o->dataonly = minus;
    switch (c) {
    case '\0': case 'a': o->format = 'a'; o->fmtid = "ascii"; break;
    case 'i': o->format = 'i'; o->fmtid = "ascii"; break;
    case 'b': o->dataonly = 1; o->format = 'b'; o->fmtid = "byte"; break;
    case 'W': o->swapbytes = 1; /* fall through */
    case 'w': o->dataonly = 1; o->format = 'w'; o->fmtid = "16-bit"; break;
    case 'F': o->swapbytes = 1; /* fall through */
    case 'f': o->dataonly = 1; o->format = 'f'; o->fmtid = "float"; break;
    case 'D': o->swapbytes = 1; /* fall through */
    case 'd': o->dataonly = 1; o->format = 'd'; o->fmtid = "double"; break;
    default:
        return hd_fail(HD_ERR_USAGE, "unknown data format option: -d%c (expected a, i, b, w, W, f, F, d or D)", c);
    }
    return HD_OK;
}

void hd_pvalue_opts_finish(hd_pvalue_opts *o)
{
    if (o->dataonly && o->format == 'b') o->fmtid = o->putprim == HD_PV_ALL ? "24-bit_rgb" : "8-bit_grey";
    if (o->dataonly && o->format == 'w') o->fmtid = o->putprim == HD_PV_ALL ? "48-bit_rgb" : "16-bit_grey";
    o->rord[o->ord[0]] = 0;
    o->rord[o->ord[1]] = 1;
    o->rord[o->ord[2]] = 2;
}

/* Copy the lines of h into oh, dropping FORMAT, NROWS, NCOLS, NCOMP,
 * BigEndian (noting its value) and, with -o, EXPOSURE / COLORCORR (folded
 * into the exposure correction). */
static hd_status filter_header(hd_pvalue_opts *o, const hd_header *h, hd_header *oh, int *bigendian)
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
        if (o->original && !strncmp(line, "EXPOSURE=", 9)) {
            double d = atof(line + 9);
            if (d > 0)
                for (int c = 0; c < 3; c++) o->exposure[c] *= (float)(1.0 / d);
            o->doexposure++;
            continue;
        }
        if (o->original && !strncmp(line, "COLORCORR=", 10)) {
            double cc[3] = {1, 1, 1};
            if (sscanf(line + 10, "%lf %lf %lf", &cc[0], &cc[1], &cc[2]) == 3)
                for (int c = 0; c < 3; c++)
                    if (cc[c] > 0) o->exposure[c] = (float)(o->exposure[c] / cc[c]);
            o->doexposure++;
            continue;
        }
        hd_status st = hd_header_append(oh, line);
        if (st) return st;
    }
    return HD_OK;
}

static hd_status skip_bytes(const hd_pvalue_opts *o, hd_istream *s)
{
    char buf[4096];
    long n = o->skipbytes;
    while (n > 0) {
        size_t k = n > (long)sizeof buf ? sizeof buf : (size_t)n;
        if (hd_istream_read(s, buf, k) != k)
            return hd_fail(HD_ERR_FORMAT, "%s: cannot skip %ld bytes on input", hd_istream_name(s), o->skipbytes);
        n -= (long)k;
    }
    return HD_OK;
}

static hd_status wbin(FILE *out, const void *p, size_t size, size_t n)
{
    if (fwrite(p, size, n, out) != n) return hd_fail(HD_ERR_IO, "write error on standard output");
    return HD_OK;
}

/* one value (prim >= 0: that channel; HD_PV_BRIGHT; HD_PV_ALL) */
static hd_status put_value(const hd_pvalue_opts *o, FILE *out, const float c[3], int prim, int xyz)
{
    double v[3];
    int nv = 3;
    if (prim == HD_PV_ALL) {
        v[0] = c[o->ord[0]];
        v[1] = c[o->ord[1]];
        v[2] = c[o->ord[2]];
    } else {
        v[0] = prim == HD_PV_BRIGHT ? (xyz ? c[1] : hd_rgb_bright(c)) : c[prim];
        nv = 1;
    }
    switch (o->format) {
    case 'a':
        if (nv == 3) fprintf(out, "%15.3e %15.3e %15.3e\n", v[0], v[1], v[2]);
        else fprintf(out, "%15.3e\n", v[0]);
        return HD_OK;
    case 'i':
        if (nv == 3) fprintf(out, "%d %d %d\n", (int)(v[0] * 256.), (int)(v[1] * 256.), (int)(v[2] * 256.));
        else fprintf(out, "%d\n", (int)(v[0] * 256.));
        return HD_OK;
    case 'b': {
        uint8_t b[3];
        for (int k = 0; k < nv; k++) {
            long i = (long)(v[k] * 256.);
            b[k] = (uint8_t)(i > 255 ? 255 : i);
        }
        return wbin(out, b, 1, (size_t)nv);
    }
    case 'w': {
        uint16_t w[3];
        for (int k = 0; k < nv; k++) {
            long i = (long)(v[k] * 65536.);
            w[k] = (uint16_t)(i > 65535 ? 65535 : i);
        }
        if (o->swapbytes) hd_swap_bytes(w, 2, (size_t)nv);
        return wbin(out, w, 2, (size_t)nv);
    }
    case 'f': {
        float f[3];
        for (int k = 0; k < nv; k++) f[k] = (float)v[k];
        if (o->swapbytes) hd_swap_bytes(f, 4, (size_t)nv);
        return wbin(out, f, 4, (size_t)nv);
    }
    default:
        if (o->swapbytes) hd_swap_bytes(v, 8, (size_t)nv);
        return wbin(out, v, 8, (size_t)nv);
    }
}

/* ---------------------------------------------------------------- */
/* picture -> values                                                 */

static hd_status write_value_header(hd_pvalue_opts *o, FILE *out, hd_header *oh, int len, int nscan,
                                    int argc, char **argv)
{
    hd_status st;
    if ((st = hd_header_add_command(oh, argc, argv))) return st;
    if ((st = hd_header_appendf(oh, "NCOMP=%d", o->putprim == HD_PV_ALL ? 3 : 1))) return st;
    if (!o->resolution && o->dataonly && !o->uniq)
        if ((st = hd_header_appendf(oh, "NCOLS=%d", len)) || (st = hd_header_appendf(oh, "NROWS=%d", nscan)))
            return st;
    if (o->expval < .99 || o->expval > 1.01)
        if ((st = hd_header_appendf(oh, "EXPOSURE=%e", o->expval))) return st;
    hd_header_dims d = {0, 0, 0, HD_ENDIAN_NONE};
    if (o->swapbytes) d.endian = HD_ENDIAN_SWAPPED;
    else if (o->format != 'a' && o->format != 'i' && o->format != 'b') d.endian = HD_ENDIAN_HOST;
    return hd_header_put(out, oh, &d, o->fmtid, NULL);
}

hd_status hd_pvalue_to_values(hd_pvalue_opts *o, const char *path, FILE *out, int argc, char **argv)
{
    hd_istream *s = NULL;
    hd_header h, oh;
    hd_picfmt fmt;
    hd_resolu r;
    uint8_t *all = NULL, *sl = NULL;  /* all: whole picture for -n */
    int be;
    hd_status st;
    hd_header_init(&h);
    hd_header_init(&oh);
    if ((st = hd_istream_open(&s, path ? path : "-"))) return st;
    if (o->skipbytes && (st = skip_bytes(o, s))) goto done;
    if ((st = hd_picture_read_header(s, &h, &fmt, &r))) goto done;
    int xyz = fmt == HD_PIC_XYZE;
    if ((st = filter_header(o, &h, &oh, &be))) goto done;
    if (o->original < 0 && xyz) {
        for (int c = 0; c < 3; c++) o->exposure[c] *= (float)(1.0 / 179.0);
        o->doexposure++;
    }
    int len = hd_resolu_scanlen(&r), nscan = hd_resolu_nscans(&r);
    if (o->header && (st = write_value_header(o, out, &oh, len, nscan, argc, argv))) goto done;
    if (o->resolution) {
        char res[64];
        hd_resolu_format(res, sizeof res, &r);
        fputs(res, out);
    }

    int dogamma = o->gamcor < .95 || o->gamcor > 1.05;
    int startprim = o->putprim, endprim = o->putprim;
    if (!(sl = hd_malloc((size_t)len * 4))) { st = HD_ERR_NOMEM; goto done; }
    if (o->putprim == HD_PV_ALL && !o->interleave) {
        startprim = HD_PV_RED;
        endprim = HD_PV_BLU;
        if (!(all = hd_malloc_array((size_t)len * (size_t)nscan, 4))) { st = HD_ERR_NOMEM; goto done; }
        for (int y = 0; y < nscan; y++)
            if ((st = hd_scanline_read(s, all + (size_t)y * len * 4, len))) goto done;
    }
    for (int prim = startprim; prim <= endprim; prim++) {
        float last[3] = {0, 0, 0};
        for (int y = 0; y < nscan; y++) {
            const uint8_t *row;
            if (all) row = all + (size_t)y * len * 4;
            else {
                if ((st = hd_scanline_read(s, sl, len))) goto done;
                row = sl;
            }
            for (int x = 0; x < len; x++) {
                float c[3];
                hd_rgbe_decode(row + 4 * x, c);
                if (o->uniq) {
                    if (c[0] == last[0] && c[1] == last[1] && c[2] == last[2]) continue;
                    memcpy(last, c, sizeof last);
                }
                if (o->doexposure)
                    for (int k = 0; k < 3; k++) c[k] *= o->exposure[k];
                if (dogamma)
                    for (int k = 0; k < 3; k++) c[k] = (float)pow(c[k], 1.0 / o->gamcor);
                if (!o->dataonly) {
                    int px, py;
                    hd_resolu_pixel(&r, y, x, &px, &py);
                    fprintf(out, "%7d %7d ", px, py);
                }
                if ((st = put_value(o, out, c, prim, xyz))) goto done;
            }
        }
    }
    if (fflush(out) || ferror(out)) st = hd_fail(HD_ERR_IO, "write error on standard output");
done:
    free(all);
    free(sl);
    hd_header_free(&oh);
    hd_header_free(&h);
    hd_istream_close(s);
    return st;
}

/* ---------------------------------------------------------------- */
/* values -> picture                                                 */

typedef struct vsrc {
    hd_istream *s;
    const uint8_t *mem;     /* non-interleaved binary: a channel's block */
    size_t memlen, mempos;
} vsrc;

static hd_status get_bin(vsrc *v, void *dst, size_t size, const char *what)
{
    if (v->mem) {
        if (v->mempos + size > v->memlen)
            return hd_fail(HD_ERR_FORMAT, "%s: unexpected end of data reading %s", hd_istream_name(v->s), what);
        memcpy(dst, v->mem + v->mempos, size);
        v->mempos += size;
        return HD_OK;
    }
    return hd_istream_read_exact(v->s, dst, size, what);
}

static hd_status get_real(vsrc *v, const char *what, double *d)
{
    hd_status st = hd_istream_real(v->s, d, NULL);
    return st ? hd_fail_context(HD_ERR_FORMAT, "reading %s", what) : HD_OK;
}

/* one value of one channel from source v, decoded per the format */
static hd_status get_one(const hd_pvalue_opts *o, vsrc *v, const char *what, double *out)
{
    hd_status st;
    switch (o->format) {
    case 'a': return get_real(v, what, out);
    case 'i':
        if ((st = get_real(v, what, out))) return st;
        *out = (*out + .5) / 256.;
        return HD_OK;
    case 'b': {
        uint8_t b;
        if ((st = get_bin(v, &b, 1, what))) return st;
        *out = (b + .5) / 256.;
        return HD_OK;
    }
    case 'w': {
        uint16_t w;
        if ((st = get_bin(v, &w, 2, what))) return st;
        if (o->swapbytes) hd_swap_bytes(&w, 2, 1);
        *out = (w + .5) / 65536.;
        return HD_OK;
    }
    case 'f': {
        float f;
        if ((st = get_bin(v, &f, 4, what))) return st;
        if (o->swapbytes) hd_swap_bytes(&f, 4, 1);
        *out = f;
        return HD_OK;
    }
    default: {
        double d;
        if ((st = get_bin(v, &d, 8, what))) return st;
        if (o->swapbytes) hd_swap_bytes(&d, 8, 1);
        *out = d;
        return HD_OK;
    }
    }
}

static hd_status read_header_into(hd_pvalue_opts *o, hd_istream *s, hd_header *oh, int keep)
{
    hd_header h;
    int be;
    char fmt[256];
    hd_header_init(&h);
    hd_status st = hd_header_read(s, &h, 1);
    if (!st && hd_header_get(&h, "FORMAT", fmt, sizeof fmt) && strcmp(fmt, o->fmtid))
        st = hd_fail(HD_ERR_FORMAT, "%s: wrong input format FORMAT=%s (expected %s)", hd_istream_name(s), fmt,
                     o->fmtid);
    if (!st && keep) {
        st = filter_header(o, &h, oh, &be);
        if (be >= 0) o->swapbytes = hd_host_bigendian() != be;
    }
    hd_header_free(&h);
    return st;
}

/* header and resolution of the picture written by hd_pvalue_from_values */
static hd_status write_picture_header(hd_pvalue_opts *o, FILE *out, hd_header *oh, int argc, char **argv)
{
    hd_status st;
    if ((st = hd_header_add_command(oh, argc, argv))) return st;
    if (o->expval < .99 || o->expval > 1.01)
        if ((st = hd_header_appendf(oh, "EXPOSURE=%e", o->expval))) return st;
    hd_picfmt pfmt = HD_PIC_RGBE;
    if (o->prims_mode == HD_PV_PRIM_CUSTOM) {
        if ((st = hd_header_appendf(oh, "PRIMARIES= %.4f %.4f %.4f %.4f %.4f %.4f %.4f %.4f", o->prims[0],
                                    o->prims[1], o->prims[2], o->prims[3], o->prims[4], o->prims[5], o->prims[6],
                                    o->prims[7])))
            return st;
    } else if (o->prims_mode == HD_PV_PRIM_XYZ) {
        if (o->original < 0) {
            for (int c = 0; c < 3; c++) o->exposure[c] *= 179.0f;
            o->doexposure++;
        }
        pfmt = HD_PIC_XYZE;
    }
    return hd_picture_write_header(out, oh, pfmt, &o->picres);
}

hd_status hd_pvalue_from_values(hd_pvalue_opts *o, const char *const *paths, int npaths, FILE *out,
                                int argc, char **argv)
{
    vsrc src[3];
    int nsrc = 1, nopen = 0;
    uint8_t *whole = NULL, *sl = NULL, *enc = NULL;
    hd_header oh;
    hd_status st = HD_OK;
    memset(src, 0, sizeof src);
    hd_header_init(&oh);
    if (npaths == 3 && o->putprim != HD_PV_BRIGHT) nsrc = 3;
    else if (npaths > 1)
        return hd_fail(HD_ERR_USAGE, "bad # file arguments (expected one input, three inputs or none)");
    for (int k = 0; k < nsrc; k++) {
        if ((st = hd_istream_open(&src[k].s, npaths ? paths[k] : "-"))) goto done;
        nopen++;
        if (o->skipbytes && (st = skip_bytes(o, src[k].s))) goto done;
    }
    if (nsrc == 3) o->interleave = -1;
    if (!o->interleave && o->putprim == HD_PV_ALL && (o->format == 'a' || o->format == 'i')) {
        st = hd_fail(HD_ERR_USAGE, "%s input files must be interleaved", o->format == 'a' ? "ASCII" : "integer");
        goto done;
    }
    if (o->header)
        for (int k = 0; k < nsrc; k++)
            if ((st = read_header_into(o, src[k].s, &oh, k == 0))) goto done;
    if (o->resolution) {
        for (int k = 0; k < nsrc; k++) {
            hd_resolu rr;
            if (hd_resolu_read(src[k].s, &rr)) {
                st = hd_fail_context(HD_ERR_FORMAT, "missing resolution");
                goto done;
            }
            if (k == 0) o->picres = rr;
            else if (rr.orient != o->picres.orient || rr.xres != o->picres.xres || rr.yres != o->picres.yres) {
                st = hd_fail(HD_ERR_FORMAT, "resolution mismatch between %s and %s", paths[0], paths[k]);
                goto done;
            }
        }
    }
    if (o->picres.xres <= 0 || o->picres.yres <= 0) {
        st = hd_fail(HD_ERR_USAGE, "missing resolution (give -y N +x M, or a resolution string in the input)");
        goto done;
    }
    if ((st = hd_resolu_check(&o->picres, "pvalue -r"))) goto done;
    if ((st = write_picture_header(o, out, &oh, argc, argv))) goto done;

    int len = hd_resolu_scanlen(&o->picres), nscan = hd_resolu_nscans(&o->picres);
    size_t npix = (size_t)len * (size_t)nscan;
    if (!o->interleave && o->putprim == HD_PV_ALL) {
        /* one binary file holding the red, green and blue blocks in turn */
        size_t vs = o->format == 'b' ? 1 : o->format == 'w' ? 2 : o->format == 'f' ? 4 : 8;
        size_t need;
        if (hd_mul_overflow(npix * 3, vs, &need)) { st = hd_fail(HD_ERR_NOMEM, "picture too large"); goto done; }
        if (!(whole = hd_malloc(need))) { st = HD_ERR_NOMEM; goto done; }
        if ((st = hd_istream_read_exact(src[0].s, whole, need, "non-interleaved channel data"))) goto done;
        for (int k = 0; k < 3; k++) {
            src[k].s = src[0].s;
            src[k].mem = whole + (size_t)k * npix * vs;
            src[k].memlen = npix * vs;
        }
        nsrc = 3;
    }
    int dogamma = o->gamcor < .95 || o->gamcor > 1.05;
    sl = hd_malloc((size_t)len * 4);
    enc = hd_malloc(hd_scanline_maxbytes(len));
    if (!sl || !enc) { st = HD_ERR_NOMEM; goto done; }
    char what[96];
    for (int y = 0; y < nscan; y++) {
        for (int x = 0; x < len; x++) {
            double vd[3], skip;
            snprintf(what, sizeof what, "pixel %d of scanline %d", x, y);
            if (!o->dataonly) {
                /* pixel positions are read and ignored, as Radiance does */
                for (int k = 0; k < (nsrc == 3 && !whole ? 3 : 1); k++)
                    if ((st = get_real(&src[k], what, &skip)) || (st = get_real(&src[k], what, &skip))) goto done;
            }
            float c[3];
            if (o->putprim != HD_PV_ALL) {
                double d;
                if ((st = get_one(o, &src[0], what, &d))) goto done;
                c[0] = c[1] = c[2] = (float)d;
            } else {
                for (int k = 0; k < 3; k++)
                    if ((st = get_one(o, &src[nsrc == 1 ? 0 : k], what, &vd[k]))) goto done;
                c[0] = (float)vd[o->rord[HD_PV_RED]];
                c[1] = (float)vd[o->rord[HD_PV_GRN]];
                c[2] = (float)vd[o->rord[HD_PV_BLU]];
            }
            if (dogamma)
                for (int k = 0; k < 3; k++) c[k] = (float)pow(c[k], o->gamcor);
            if (o->doexposure)
                for (int k = 0; k < 3; k++) c[k] *= o->exposure[k];
            hd_rgbe_encode(sl + 4 * x, c[0], c[1], c[2]);
        }
        if (o->uniq) st = wbin(out, sl, 4, (size_t)len);    /* -u: flat, uncompressed scanlines */
        else st = wbin(out, enc, 1, hd_scanline_encode(enc, sl, len));
        if (st) goto done;
    }
    if (fflush(out) || ferror(out)) st = hd_fail(HD_ERR_IO, "write error on standard output");
done:
    free(sl);
    free(enc);
    free(whole);
    hd_header_free(&oh);
    for (int k = 0; k < nopen; k++) {
        hd_status cs = hd_istream_close(src[k].s);
        if (!st) st = cs;
    }
    return st;
}

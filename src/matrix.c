/* heliodon — Radiance matrix files: reading (ascii, float, double in either
 * byte order, RGBE/XYZE pictures), writing with Radiance's header layout,
 * and the algebra rmtxop needs.  See include/heliodon/matrix.h and
 * docs/design/matrix.md. */
#include "heliodon/matrix.h"
#include "heliodon/parallel.h"
#include "heliodon/picture.h"

/* XML BSDF input uses the BSDF module when it is part of the library
 * (include/heliodon/bsdf.h present); until then .xml inputs are refused. */
#include "heliodon/bsdf.h"

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* ---------------------------------------------------------------- basics */

void hd_matrix_init(hd_matrix *m)
{
    memset(m, 0, sizeof *m);
    hd_header_init(&m->hdr);
    m->infmt = HD_MTX_ASCII;
}

void hd_matrix_free(hd_matrix *m)
{
    if (!m) return;
    free(m->data);
    hd_header_free(&m->hdr);
    hd_matrix_init(m);
}

/* Check dimensions and compute the value count; name/what give context. */
static hd_status check_dims(const char *name, long nrows, long ncols, long ncomp, size_t *nvals)
{
    if (nrows <= 0 || nrows > INT_MAX)
        return hd_fail(HD_ERR_RANGE, "%s: NROWS=%ld: expected a positive number of rows (at most %d)",
                       name, nrows, INT_MAX);
    if (ncols <= 0 || ncols > INT_MAX)
        return hd_fail(HD_ERR_RANGE, "%s: NCOLS=%ld: expected a positive number of columns (at most %d)",
                       name, ncols, INT_MAX);
    if (ncomp <= 0 || ncomp > 1024)
        return hd_fail(HD_ERR_RANGE, "%s: NCOMP=%ld: expected a positive number of components (at most 1024)",
                       name, ncomp);
    /* each factor < 2^31 (ncomp < 2^11): compare in floating point first */
    double ne = (double)nrows * (double)ncols * (double)ncomp;
    if (ne > (double)HD_MTX_MAXELEMENTS)
        return hd_fail(HD_ERR_RANGE,
                       "%s: matrix of NROWS=%ld x NCOLS=%ld x NCOMP=%ld = %.4g values exceeds the limit of %lld values",
                       name, nrows, ncols, ncomp, ne, (long long)HD_MTX_MAXELEMENTS);
    if (nvals) *nvals = (size_t)nrows * (size_t)ncols * (size_t)ncomp;
    return HD_OK;
}

/* Replace m's data by a zeroed array of the given size (m initialised). */
static hd_status alloc_data(hd_matrix *m, int nrows, int ncols, int ncomp)
{
    size_t n;
    hd_status st = check_dims("matrix", nrows, ncols, ncomp, &n);
    if (st) return st;
    double *d = hd_calloc(n, sizeof(double));
    if (!d) return hd_fail_context(HD_ERR_NOMEM, "matrix of %d x %d x %d", nrows, ncols, ncomp);
    free(m->data);
    m->data = d;
    m->nrows = nrows;
    m->ncols = ncols;
    m->ncomp = ncomp;
    return HD_OK;
}

hd_status hd_matrix_alloc(hd_matrix *m, int nrows, int ncols, int ncomp)
{
    hd_matrix_init(m);
    return alloc_data(m, nrows, ncols, ncomp);
}

static size_t nvalues(const hd_matrix *m)
{
    return (size_t)m->nrows * (size_t)m->ncols * (size_t)m->ncomp;
}

hd_status hd_matrix_copy(hd_matrix *dst, const hd_matrix *src)
{
    hd_matrix t;
    hd_matrix_init(&t);
    hd_status st = hd_matrix_alloc(&t, src->nrows, src->ncols, src->ncomp);
    if (st) return st;
    memcpy(t.data, src->data, nvalues(src) * sizeof(double));
    st = hd_header_copy(&t.hdr, &src->hdr);
    if (st) { hd_matrix_free(&t); return st; }
    t.infmt = src->infmt;
    hd_matrix_move(dst, &t);
    return HD_OK;
}

void hd_matrix_move(hd_matrix *dst, hd_matrix *src)
{
    if (dst == src) return;
    hd_matrix_free(dst);
    *dst = *src;
    hd_matrix_init(src);
}

static const char *const fmt_names[] = {
    "ascii", "float", "double", "32-bit_rle_rgbe", "32-bit_rle_xyze"
};

const char *hd_mtxfmt_name(hd_mtxfmt f)
{
    if ((int)f < 0 || (int)f > HD_MTX_XYZE) return "unknown";
    return fmt_names[f];
}

int hd_mtxfmt_parse(const char *name)
{
    for (int i = 0; i <= HD_MTX_XYZE; i++)
        if (!strcmp(name, fmt_names[i])) return i;
    return -1;
}

static int is_picture_fmt(int f) { return f == HD_MTX_RGBE || f == HD_MTX_XYZE; }

hd_mtxfmt hd_mtxfmt_combine(hd_mtxfmt a, hd_mtxfmt b)
{
    if (is_picture_fmt(a) || is_picture_fmt(b))
        return a == b ? a : HD_MTX_FLOAT;
    return a < b ? a : b;
}

int hd_matrix_is_xml(const char *path)
{
    return path && strlen(path) > 4 && path[0] != '!' && hd_has_suffix(path, ".xml");
}

/* --------------------------------------------------------------- reading */

/* Product of every COLORCORR= line (3 components), 1 1 1 if none. */
static hd_status header_colorcorr(const hd_header *h, const char *name, double cc[3])
{
    cc[0] = cc[1] = cc[2] = 1.0;
    const char *p = h->text;
    while (p && *p) {
        const char *eol = strchr(p, '\n');
        size_t len = eol ? (size_t)(eol - p) : strlen(p);
        if (len > 10 && !strncmp(p, "COLORCORR=", 10)) {
            char buf[256];
            size_t n = len - 10 < sizeof buf - 1 ? len - 10 : sizeof buf - 1;
            memcpy(buf, p + 10, n);
            buf[n] = 0;
            double v[3];
            if (sscanf(buf, "%lf %lf %lf", &v[0], &v[1], &v[2]) != 3 ||
                !(v[0] > 0) || !(v[1] > 0) || !(v[2] > 0))
                return hd_fail(HD_ERR_FORMAT, "%s: header: malformed COLORCORR=%s (expected three positive numbers)",
                               name, buf);
            for (int i = 0; i < 3; i++) cc[i] *= v[i];
        }
        p = eol ? eol + 1 : p + len;
    }
    return HD_OK;
}

/* Grow a value array for matrices of unknown row count. */
static hd_status grow(double **data, size_t *cap, size_t need, const char *name)
{
    if (need > (size_t)HD_MTX_MAXELEMENTS)
        return hd_fail(HD_ERR_RANGE, "%s: more than %lld values", name, (long long)HD_MTX_MAXELEMENTS);
    if (hd_grow((void **)data, need, cap, sizeof **data, 4096)) return hd_fail_context(HD_ERR_NOMEM, "%s", name);
    return HD_OK;
}

/* data (nrows full rows, counted while reading) becomes m's, dimensions checked */
static hd_status adopt_rows(hd_matrix *m, double *data, size_t nrows, const char *name)
{
    hd_status st = check_dims(name, (long)nrows, m->ncols, m->ncomp, NULL);
    if (st) { free(data); return st; }
    free(m->data);
    m->data = data;
    m->nrows = (int)nrows;
    return HD_OK;
}

static hd_status read_ascii(hd_istream *s, hd_matrix *m, int nrows_known)
{
    const char *name = hd_istream_name(s);
    size_t rowvals = (size_t)m->ncols * (size_t)m->ncomp;
    if (nrows_known) {
        size_t n = nvalues(m);
        for (size_t i = 0; i < n; i++) {
            int eof = 0;
            hd_status st = hd_istream_real(s, &m->data[i], &eof);
            if (st) return st;
            if (eof)
                return hd_fail(HD_ERR_FORMAT,
                               "%s: line %lu: unexpected end of data: expected %zu values (%d rows x %d columns x %d components), got %zu",
                               name, hd_istream_lineno(s), n, m->nrows, m->ncols, m->ncomp, i);
        }
        return HD_OK;
    }
    double *data = NULL;
    size_t cap = 0, n = 0;
    for (;;) {
        double v;
        int eof = 0;
        hd_status st = hd_istream_real(s, &v, &eof);
        if (st) { free(data); return st; }
        if (eof) break;
        if ((st = grow(&data, &cap, n + 1, name))) { free(data); return st; }
        data[n++] = v;
    }
    if (n == 0 || n % rowvals) {
        free(data);
        return hd_fail(HD_ERR_FORMAT,
                       "%s: line %lu: %zu values is not a whole number of rows of %d columns x %d components",
                       name, hd_istream_lineno(s), n, m->ncols, m->ncomp);
    }
    return adopt_rows(m, data, n / rowvals, name);
}

static hd_status read_binary(hd_istream *s, hd_matrix *m, int nrows_known, int width, int swap)
{
    const char *name = hd_istream_name(s);
    size_t rowvals = (size_t)m->ncols * (size_t)m->ncomp;
    uint64_t start = hd_istream_offset(s);
    enum { CHUNK = 8192 };
    unsigned char buf[CHUNK * 8];
    double *data = nrows_known ? m->data : NULL;
    size_t cap = nrows_known ? nvalues(m) : 0;
    size_t want = nrows_known ? nvalues(m) : SIZE_MAX;
    size_t n = 0;
    while (n < want) {
        size_t k = want - n < CHUNK ? want - n : CHUNK;
        size_t got = hd_istream_read(s, buf, k * (size_t)width);
        if (hd_istream_failed(s)) {
            if (!nrows_known) free(data);
            return hd_fail(HD_ERR_IO, "%s: byte offset %llu: read error", name,
                           (unsigned long long)hd_istream_offset(s));
        }
        size_t nv = got / (size_t)width;
        if (!nrows_known && nv) {
            hd_status st = grow(&data, &cap, n + nv, name);
            if (st) { free(data); return st; }
        }
        /* nv == 0 (empty or partial last value): nothing to store, and data
         * may still be NULL when the row count is unknown */
        if (swap && nv) hd_swap_bytes(buf, (size_t)width, nv);
        if (width == 4) {
            for (size_t i = 0; i < nv; i++) {
                float f;
                memcpy(&f, buf + 4 * i, 4);
                data[n + i] = f;
            }
        } else if (nv) {
            memcpy(data + n, buf, nv * 8);
        }
        n += nv;
        if (got < k * (size_t)width) {
            if (nrows_known || got % (size_t)width) {
                uint64_t expect = (uint64_t)want * (uint64_t)width;
                if (!nrows_known) expect = ((uint64_t)n / rowvals + 1) * rowvals * (uint64_t)width;
                char rows[48];
                if (nrows_known) snprintf(rows, sizeof rows, "%d rows x ", m->nrows);
                else snprintf(rows, sizeof rows, "whole rows of ");
                hd_status st = hd_fail(HD_ERR_FORMAT,
                    "%s: byte offset %llu: unexpected end of data: %s data of %s%d columns x %d components "
                    "needs %llu bytes after the header (from byte %llu), got %llu",
                    name, (unsigned long long)hd_istream_offset(s), width == 4 ? "float" : "double",
                    rows, m->ncols, m->ncomp,
                    (unsigned long long)expect, (unsigned long long)start,
                    (unsigned long long)(hd_istream_offset(s) - start));
                if (!nrows_known) free(data);
                return st;
            }
            break;
        }
    }
    if (!nrows_known) {
        if (n == 0 || n % rowvals) {
            free(data);
            return hd_fail(HD_ERR_FORMAT,
                           "%s: byte offset %llu: unexpected end of data: %zu values is not a whole number of rows of %d columns x %d components",
                           name, (unsigned long long)hd_istream_offset(s), n, m->ncols, m->ncomp);
        }
        return adopt_rows(m, data, n / rowvals, name);
    }
    return HD_OK;
}

/* RGBE/XYZE scanlines.  r == NULL or standard orientation: scanline i is
 * row i.  Otherwise pixels are put in standard order (row 0 = top, pixels
 * left to right) whatever the file's orientation. */
static hd_status read_rgbe(hd_istream *s, hd_matrix *m, const hd_resolu *r)
{
    int std = !r || r->orient == HD_RES_STANDARD;
    int nscans = std ? m->nrows : hd_resolu_nscans(r), len = std ? m->ncols : hd_resolu_scanlen(r);
    uint8_t *scan = hd_malloc_array((size_t)len, 4);
    if (!scan) return hd_fail_context(HD_ERR_NOMEM, "%s", hd_istream_name(s));
    for (int sc = 0; sc < nscans; sc++) {
        hd_status st = hd_scanline_read(s, scan, len);
        if (st) {
            free(scan);
            return hd_fail_context(st, "%s: scanline %d of %d", hd_istream_name(s), sc, nscans);
        }
        for (int p = 0; p < len; p++) {
            float rgb[3];
            hd_rgbe_decode(scan + 4 * p, rgb);
            double *e;
            if (std) {
                e = hd_matrix_at(m, sc, p);
            } else {
                int x, y;
                hd_resolu_pixel(r, sc, p, &x, &y);
                e = hd_matrix_at(m, m->nrows - 1 - y, x);
            }
            if (m->ncomp == 3) {
                e[0] = rgb[0];
                e[1] = rgb[1];
                e[2] = rgb[2];
            } else {
                e[0] = rgb[1];
            }
        }
    }
    free(scan);
    return HD_OK;
}

static hd_status header_long(const hd_header *h, const char *var, const char *name, long *v, int *found)
{
    hd_status st = hd_header_get_long(h, var, v, found);
    if (st) {
        char buf[128] = "";
        hd_header_get(h, var, buf, sizeof buf);
        return hd_fail(HD_ERR_FORMAT, "%s: header: %s=%s: expected an integer", name, var, buf);
    }
    return HD_OK;
}

hd_status hd_matrix_read_stream(hd_istream *s, hd_matrix *m, const hd_matrix_readopts *opts)
{
    hd_matrix_init(m);   /* output only */
    const char *name = hd_istream_name(s);
    hd_matrix t;
    hd_matrix_init(&t);
    long nrows = opts && opts->nrows > 0 ? opts->nrows : 0;
    long ncols = opts && opts->ncols > 0 ? opts->ncols : 0;
    long ncomp = opts && opts->ncomp > 0 ? opts->ncomp : 0;
    int fmt = HD_MTX_ASCII, bigendian = hd_host_bigendian();
    double exposure = 1.0, cc[3] = {1, 1, 1};
    hd_status st = HD_OK;
    int headerless = opts && opts->fmt >= 0;
    hd_resolu res;
    int have_res = 0;

    if (headerless) {
        if (opts->fmt > HD_MTX_XYZE)
            return hd_fail(HD_ERR_USAGE, "%s: unknown matrix format code %d", name, opts->fmt);
        fmt = opts->fmt;
        if (ncols <= 0)
            return hd_fail(HD_ERR_USAGE, "%s: headerless input needs the number of columns", name);
        if (is_picture_fmt(fmt) && nrows <= 0)
            return hd_fail(HD_ERR_USAGE, "%s: headerless picture input needs the number of rows", name);
        if (!ncomp) ncomp = 3;
    } else {
        if ((st = hd_header_read(s, &t.hdr, 1))) goto fail;   /* "#?" optional, as Radiance */
        char fbuf[128];
        int havefmt = hd_header_get(&t.hdr, "FORMAT", fbuf, sizeof fbuf);
        if (havefmt) {
            fmt = hd_mtxfmt_parse(fbuf);
            if (fmt < 0) {
                if (!strcmp(fbuf, "Radiance_spectra") || !strncmp(fbuf, "16-bit", 6) ||
                    !strncmp(fbuf, "64-bit", 6) || !strncmp(fbuf, "32-bit", 6))
                    st = hd_fail(HD_ERR_UNSUPPORTED, "%s: header: FORMAT=%s is not supported "
                                 "(expected ascii, float, double, 32-bit_rle_rgbe or 32-bit_rle_xyze)",
                                 name, fbuf);
                else
                    st = hd_fail(HD_ERR_FORMAT, "%s: header: unknown FORMAT=%s "
                                 "(expected ascii, float, double, 32-bit_rle_rgbe or 32-bit_rle_xyze)",
                                 name, fbuf);
                goto fail;
            }
        }
        long v;
        int found;
        if ((st = header_long(&t.hdr, "NROWS", name, &v, &found))) goto fail;
        if (found) {
            if ((st = check_dims(name, v, 1, 1, NULL))) goto fail;
            nrows = v;
        }
        if ((st = header_long(&t.hdr, "NCOLS", name, &v, &found))) goto fail;
        if (found) {
            if ((st = check_dims(name, 1, v, 1, NULL))) goto fail;
            ncols = v;
        }
        int have_ncols = found;
        if ((st = header_long(&t.hdr, "NCOMP", name, &v, &found))) goto fail;
        if (found) {
            if ((st = check_dims(name, 1, 1, v, NULL))) goto fail;
            ncomp = v;
        }
        if ((st = header_long(&t.hdr, "BigEndian", name, &v, &found))) goto fail;
        if (found) {
            if (v != 0 && v != 1) {
                st = hd_fail(HD_ERR_FORMAT, "%s: header: BigEndian=%ld: expected 0 or 1", name, v);
                goto fail;
            }
            bigendian = (int)v;
        }
        exposure = hd_header_exposure(&t.hdr);
        if (!(exposure > 0) || !isfinite(exposure)) {
            st = hd_fail(HD_ERR_FORMAT, "%s: header: EXPOSURE must be positive", name);
            goto fail;
        }
        if ((st = header_colorcorr(&t.hdr, name, cc))) goto fail;
        if (is_picture_fmt(fmt) || (!have_ncols && !(opts && opts->ncols > 0))) {
            /* picture-style: resolution string gives the size */
            hd_resolu r;
            if ((st = hd_resolu_read(s, &r))) {
                if (!is_picture_fmt(fmt))
                    hd_fail_context(st, "%s: header has no NCOLS= and no resolution string follows", name);
                goto fail;
            }
            if (r.orient != HD_RES_STANDARD && !is_picture_fmt(fmt) && havefmt) {
                st = hd_fail(HD_ERR_UNSUPPORTED, "%s: FORMAT=%s with a resolution string in other than "
                             "the standard \"-Y N +X M\" order", name, hd_mtxfmt_name(fmt));
                goto fail;
            }
            res = r;
            have_res = 1;
            nrows = r.yres;      /* rows and columns in standard orientation */
            ncols = r.xres;
            if (!havefmt) fmt = HD_MTX_RGBE;    /* old pictures without FORMAT */
            if (is_picture_fmt(fmt)) ncomp = 3;
        }
        if (is_picture_fmt(fmt) && ncomp != 3 && ncomp != 1) {
            st = hd_fail(HD_ERR_FORMAT, "%s: header: NCOMP=%ld with FORMAT=%s: expected 3",
                         name, ncomp, hd_mtxfmt_name(fmt));
            goto fail;
        }
        if (!ncomp) ncomp = 3;
        static const char *const strip[] = {
            "FORMAT", "NROWS", "NCOLS", "NCOMP", "BigEndian", "EXPOSURE", "COLORCORR"
        };
        for (size_t i = 0; i < sizeof strip / sizeof *strip; i++)
            hd_header_remove(&t.hdr, strip[i]);
    }
    int nrows_known = nrows > 0;
    if ((st = check_dims(name, nrows_known ? nrows : 1, ncols, ncomp, NULL))) goto fail;
    t.ncols = (int)ncols;
    t.ncomp = (int)ncomp;
    t.infmt = (hd_mtxfmt)fmt;
    if (nrows_known) {
        if ((st = alloc_data(&t, (int)nrows, (int)ncols, (int)ncomp))) {
            hd_fail_context(st, "%s", name);
            goto fail;
        }
    }
    switch (fmt) {
    case HD_MTX_ASCII: st = read_ascii(s, &t, nrows_known); break;
    case HD_MTX_FLOAT: st = read_binary(s, &t, nrows_known, 4, bigendian != hd_host_bigendian()); break;
    case HD_MTX_DOUBLE: st = read_binary(s, &t, nrows_known, 8, bigendian != hd_host_bigendian()); break;
    default: st = read_rgbe(s, &t, have_res ? &res : NULL); break;
    }
    if (st) goto fail;
    if (exposure != 1.0 || cc[0] != 1.0 || cc[1] != 1.0 || cc[2] != 1.0) {
        size_t n = nvalues(&t);
        for (size_t i = 0; i < n; i++) {
            double f = exposure;
            if (t.ncomp == 3) f *= cc[i % 3];
            t.data[i] /= f;
        }
    }
    *m = t;          /* m is an output: previous content is not freed */
    return HD_OK;
fail:
    hd_matrix_free(&t);
    return st;
}

hd_status hd_matrix_read_bsdf(const char *path, hd_matrix *m, int which)
{
    hd_matrix_init(m);
    hd_bsdf_comp c;
    switch (which) {
    case 'T': c = HD_BSDF_TB; break;
    case 'f': c = HD_BSDF_RF; break;
    case 'b': c = HD_BSDF_RB; break;
    default: return hd_fail(HD_ERR_USAGE, "%s: unknown BSDF matrix '%c' (expected T, f or b)", path, which);
    }
    hd_bsdf *b = NULL;
    hd_status st = hd_bsdf_load(path, &b);
    if (st) return st;
    hd_matrix t;
    hd_matrix_init(&t);
    st = hd_bsdf_klems_matrix(b, c, NULL, 0, 3, &t);
    hd_bsdf_free(b);
    if (st) {
        free(t.data);
        return hd_fail_context(st, "%s: Klems %s matrix", path,
                               which == 'T' ? "transmission" : which == 'f' ? "front reflection" : "back reflection");
    }
    hd_header_init(&t.hdr);
    /* Radiance holds these matrices in single precision */
    for (size_t i = 0; i < nvalues(&t); i++) t.data[i] = (float)t.data[i];
    t.infmt = HD_MTX_FLOAT;
    *m = t;
    return HD_OK;
}

hd_status hd_matrix_read(const char *path, hd_matrix *m, const hd_matrix_readopts *opts)
{
    if (hd_matrix_is_xml(path)) return hd_matrix_read_bsdf(path, m, 'T');
    hd_matrix_init(m);
    hd_istream *s;
    hd_status st = hd_istream_open(&s, path);
    if (st) return st;
    st = hd_matrix_read_stream(s, m, opts);
    hd_status st2 = hd_istream_close(s);
    if (!st && st2) {
        hd_matrix_free(m);
        st = st2;
    }
    return st;
}

/* --------------------------------------------------------------- writing */

static hd_status werr(hd_mtxwriter *w)
{
    (void)w;
    return hd_fail(HD_ERR_IO, "error writing output: %s", strerror(errno));
}

hd_status hd_mtxwriter_begin(hd_mtxwriter *w, FILE *fp, const hd_header *hdr,
                             int write_header, hd_mtxfmt fmt,
                             int nrows, int ncols, int ncomp)
{
    memset(w, 0, sizeof *w);
    hd_status st = check_dims("output matrix", nrows > 0 ? nrows : 1, ncols, ncomp, NULL);
    if (st) return st;
    if ((int)fmt < 0 || fmt > HD_MTX_XYZE)
        return hd_fail(HD_ERR_USAGE, "unknown output matrix format %d", (int)fmt);
    if (is_picture_fmt(fmt)) {
        if (ncomp != 1 && ncomp != 3)
            return hd_fail(HD_ERR_USAGE, "cannot write a matrix of %d components as a picture "
                           "(needs 1 or 3 components)", ncomp);
        if (nrows <= 0)
            return hd_fail(HD_ERR_USAGE, "picture output needs the number of rows in advance");
    }
    w->fp = fp;
    w->fmt = fmt;
    w->nrows = nrows;
    w->ncols = ncols;
    w->ncomp = ncomp;
    size_t scr = 0;
    if (fmt == HD_MTX_FLOAT) scr = (size_t)ncols * (size_t)ncomp * 4;
    else if (fmt == HD_MTX_DOUBLE) scr = (size_t)ncols * (size_t)ncomp * 8;   /* gathered rows */
    else if (is_picture_fmt(fmt)) scr = (size_t)ncols * 4;
    if (scr) {
        w->scratch = hd_malloc(scr);
        if (!w->scratch) return hd_fail_context(HD_ERR_NOMEM, "output row");
    }
    if (!write_header) return HD_OK;
    if (is_picture_fmt(fmt)) {
        hd_resolu r = {HD_RES_STANDARD, ncols, nrows};
        st = hd_picture_write_header(fp, hdr, fmt == HD_MTX_XYZE ? HD_PIC_XYZE : HD_PIC_RGBE, &r);
    } else {
        hd_header_dims d = {nrows, write_header & HD_MTXW_NO_NCOLS ? 0 : ncols, ncomp,
                            fmt == HD_MTX_FLOAT || fmt == HD_MTX_DOUBLE ? HD_ENDIAN_HOST : HD_ENDIAN_NONE};
        st = hd_header_put(fp, hdr, &d, hd_mtxfmt_name(fmt), NULL);
    }
    if (st) goto fail;
    return HD_OK;
fail:
    free(w->scratch);
    w->scratch = NULL;
    return st;
}

/* element c of a row: contiguous, or gathered through cols */
#define ROW_ELEM(c) (vals + (cols ? (size_t)cols[c] : (size_t)(c)) * (size_t)nc)

hd_status hd_mtxwriter_row_cols(hd_mtxwriter *w, const double *vals, const int *cols)
{
    FILE *fp = w->fp;
    int nc = w->ncomp;
    size_t nv = (size_t)w->ncols * (size_t)nc;
    if (w->nrows > 0 && w->rows_written >= w->nrows)
        return hd_fail(HD_ERR_INTERNAL, "matrix writer: more than %d rows written", w->nrows);
    switch (w->fmt) {
    case HD_MTX_ASCII:
        for (int c = 0; c < w->ncols; c++) {
            const double *e = ROW_ELEM(c);
            switch (w->ascii_style) {
            case HD_MTXASCII_DCTIMESTEP:
                if (nc == 3) {
                    if (fprintf(fp, "%.6e %.6e %.6e", e[0], e[1], e[2]) < 0) return werr(w);
                } else {
                    for (int k = 0; k < nc; k++)
                        if (fprintf(fp, k ? " %.6e" : "%.6e", e[k]) < 0) return werr(w);
                }
                if (c + 1 < w->ncols && putc('\t', fp) == EOF) return werr(w);
                break;
            case HD_MTXASCII_RCONTRIB:
                if (nc == 3) {
                    if (fprintf(fp, "%.6e\t%.6e\t%.6e\t", e[0], e[1], e[2]) < 0) return werr(w);
                } else {
                    for (int k = 0; k < nc; k++)
                        if (fprintf(fp, "%.6e\t", e[k]) < 0) return werr(w);
                }
                break;
            default:
                for (int k = 0; k < nc; k++)
                    if (fprintf(fp, " %.7e", e[k]) < 0) return werr(w);
                if (putc('\t', fp) == EOF) return werr(w);
                break;
            }
        }
        if (putc('\n', fp) == EOF) return werr(w);
        break;
    case HD_MTX_FLOAT: {
        float *f = (float *)(void *)w->scratch;
        if (cols) {
            for (int c = 0; c < w->ncols; c++)
                for (int k = 0; k < nc; k++) f[(size_t)c * (size_t)nc + (size_t)k] = (float)ROW_ELEM(c)[k];
        } else {
            for (size_t i = 0; i < nv; i++) f[i] = (float)vals[i];
        }
        if (fwrite(f, 4, nv, fp) != nv) return werr(w);
        break;
    }
    case HD_MTX_DOUBLE:
        if (cols) {
            double *d = (double *)(void *)w->scratch;
            for (int c = 0; c < w->ncols; c++) memcpy(d + (size_t)c * (size_t)nc, ROW_ELEM(c), (size_t)nc * sizeof *d);
            vals = d;
        }
        if (fwrite(vals, 8, nv, fp) != nv) return werr(w);
        break;
    default: {
        uint8_t *p = w->scratch;
        for (int c = 0; c < w->ncols; c++) {
            const double *e = ROW_ELEM(c);
            if (nc == 3) hd_rgbe_encode(p + 4 * c, (float)e[0], (float)e[1], (float)e[2]);
            else hd_rgbe_encode(p + 4 * c, (float)e[0], (float)e[0], (float)e[0]);
        }
        hd_status st = hd_scanline_write(fp, p, w->ncols);
        if (st) return st;
        break;
    }
    }
    w->rows_written++;
    return HD_OK;
}
#undef ROW_ELEM

hd_status hd_mtxwriter_row(hd_mtxwriter *w, const double *vals) { return hd_mtxwriter_row_cols(w, vals, NULL); }

hd_status hd_mtxwriter_end(hd_mtxwriter *w)
{
    free(w->scratch);
    w->scratch = NULL;
    if (w->nrows > 0 && w->rows_written != w->nrows)
        return hd_fail(HD_ERR_INTERNAL, "matrix writer: %d rows written, %d announced",
                       w->rows_written, w->nrows);
    if (w->fp && fflush(w->fp) == EOF) return werr(w);
    return HD_OK;
}

hd_status hd_matrix_write(FILE *fp, const hd_matrix *m, const hd_header *hdr,
                          int write_header, hd_mtxfmt fmt)
{
    hd_mtxwriter w;
    hd_status st = hd_mtxwriter_begin(&w, fp, hdr, write_header, fmt, m->nrows, m->ncols, m->ncomp);
    if (st) return st;
    for (int r = 0; r < m->nrows; r++)
        if ((st = hd_mtxwriter_row(&w, hd_matrix_at(m, r, 0)))) {
            hd_mtxwriter_end(&w);
            return st;
        }
    return hd_mtxwriter_end(&w);
}

/* --------------------------------------------------------------- algebra */

static hd_status comp_match(const hd_matrix *a, const hd_matrix *b, const char *what, int *nc)
{
    if (a->ncomp == b->ncomp || b->ncomp == 1 || a->ncomp == 1) {
        *nc = a->ncomp > b->ncomp ? a->ncomp : b->ncomp;
        return HD_OK;
    }
    return hd_fail(HD_ERR_FORMAT, "%s: component counts differ (%d and %d; one side may have 1)",
                   what, a->ncomp, b->ncomp);
}

typedef struct mulctx {
    hd_matrix *t;
    const hd_matrix *a, *b;
} mulctx;

/* Rows [begin,end) of t = a . b.  Blocked over rows (IB) and output
 * columns (JB) so that a block of b's row is reused from cache by IB rows;
 * every output value still sums its terms in ascending k, so the result
 * is the same as the plain triple loop, bit for bit. */
enum { MUL_IB = 16, MUL_JB = 256 };
static hd_status mul_rows(void *vctx, size_t begin, size_t end, size_t chunk, int worker)
{
    (void)chunk;
    (void)worker;
    const mulctx *x = vctx;
    const hd_matrix *a = x->a, *b = x->b;
    const int nc = x->t->ncomp;
    const int sa = a->ncomp == 1 ? 0 : 1, sb = b->ncomp == 1 ? 0 : 1;
    const int ka = a->ncomp, kb = b->ncomp, n = b->ncols;
    for (size_t i0 = begin; i0 < end; i0 += MUL_IB) {
        size_t i1 = i0 + MUL_IB < end ? i0 + MUL_IB : end;
        for (int j0 = 0; j0 < n; j0 += MUL_JB) {
            int jn = n - j0 < MUL_JB ? n - j0 : MUL_JB;
            for (int k = 0; k < a->ncols; k++) {
                const double *bk = hd_matrix_at(b, k, j0);
                for (size_t i = i0; i < i1; i++) {
                    const double *av = hd_matrix_at(a, (int)i, k);
                    int nz = 0;
                    for (int c = 0; c < ka; c++) nz |= av[c] != 0.0;
                    if (!nz) continue;   /* sparse rows (e.g. night skies) */
                    double *o = hd_matrix_at(x->t, (int)i, j0);
                    const double *bv = bk;
                    if (nc == 3) {
                        const double a0 = av[0], a1 = av[sa], a2 = av[2 * sa];
                        for (int j = 0; j < jn; j++, o += 3, bv += kb) {
                            o[0] += a0 * bv[0];
                            o[1] += a1 * bv[sb];
                            o[2] += a2 * bv[2 * sb];
                        }
                    } else {
                        for (int j = 0; j < jn; j++, o += nc, bv += kb)
                            for (int c = 0; c < nc; c++) o[c] += av[c * sa] * bv[c * sb];
                    }
                }
            }
        }
    }
    return HD_OK;
}

hd_status hd_matrix_multiply_mt(hd_matrix *out, const hd_matrix *a, const hd_matrix *b, int nthreads)
{
    int nc = 0;
    if (a->ncols != b->nrows)
        return hd_fail(HD_ERR_FORMAT,
                       "matrix product: %d x %d times %d x %d: the columns of the first (%d) must equal the rows of the second (%d)",
                       a->nrows, a->ncols, b->nrows, b->ncols, a->ncols, b->nrows);
    hd_status st = comp_match(a, b, "matrix product", &nc);
    if (st) return st;
    hd_matrix t;
    hd_matrix_init(&t);
    if ((st = hd_matrix_alloc(&t, a->nrows, b->ncols, nc))) return st;
    mulctx x = {&t, a, b};
    if (nthreads <= 1 || a->nrows < 2) {
        st = mul_rows(&x, 0, (size_t)a->nrows, 0, 0);
    } else {
        /* about 64 chunks of rows; every row is computed the same way
         * whatever the thread count, so results do not depend on it */
        size_t chunk = ((size_t)a->nrows + 63) / 64;
        st = hd_parallel_for((size_t)a->nrows, chunk, nthreads, mul_rows, &x);
    }
    if (st) { hd_matrix_free(&t); return st; }
    t.infmt = hd_mtxfmt_combine(a->infmt, b->infmt);
    hd_matrix_move(out, &t);
    return HD_OK;
}

hd_status hd_matrix_multiply(hd_matrix *out, const hd_matrix *a, const hd_matrix *b)
{
    return hd_matrix_multiply_mt(out, a, b, 1);
}

/* ---- chains of products, evaluated in the cheapest order ---- */

typedef struct chain {
    const hd_matrix *const *m;
    int n;
    int *split;        /* n x n: best split k of [i..j] into [i..k][k+1..j] */
    int nthreads;
} chain;

static int chain_nc(const chain *c, int i, int j)
{
    int nc = 1;
    for (int k = i; k <= j; k++)
        if (c->m[k]->ncomp > nc) nc = c->m[k]->ncomp;
    return nc;
}

static hd_status chain_eval(const chain *c, int i, int j, hd_matrix *out, const hd_matrix **res)
{
    if (i == j) {
        *res = c->m[i];
        return HD_OK;
    }
    int k = c->split[i * c->n + j];
    hd_matrix l, r;
    hd_matrix_init(&l);
    hd_matrix_init(&r);
    const hd_matrix *lp, *rp;
    hd_status st = chain_eval(c, i, k, &l, &lp);
    if (!st) st = chain_eval(c, k + 1, j, &r, &rp);
    if (!st) {
        double work = (double)lp->nrows * lp->ncols * rp->ncols * (lp->ncomp > rp->ncomp ? lp->ncomp : rp->ncomp);
        st = hd_matrix_multiply_mt(out, lp, rp, work > 2e7 ? c->nthreads : 1);
    }
    hd_matrix_free(&l);
    hd_matrix_free(&r);
    *res = out;
    return st;
}

hd_status hd_matrix_chain(hd_matrix *out, const hd_matrix *const *mats, int n, int nthreads,
                          double *cost_ltr, double *cost_best)
{
    if (n < 1) return hd_fail(HD_ERR_USAGE, "matrix chain: no matrices");
    /* the same checks, in the same order, as multiplying left to right */
    int nc = mats[0]->ncomp;
    for (int i = 1; i < n; i++) {
        const hd_matrix *a = mats[i - 1], *b = mats[i];
        if (a->ncols != b->nrows)
            return hd_fail(HD_ERR_FORMAT,
                           "matrix product: %d x %d times %d x %d: the columns of the first (%d) must equal the rows of the second (%d)",
                           mats[0]->nrows, a->ncols, b->nrows, b->ncols, a->ncols, b->nrows);
        if (nc != b->ncomp && nc != 1 && b->ncomp != 1)
            return hd_fail(HD_ERR_FORMAT, "matrix product: component counts differ (%d and %d; one side may have 1)",
                           nc, b->ncomp);
        if (b->ncomp > nc) nc = b->ncomp;
    }
    double *cost = hd_calloc((size_t)n * (size_t)n, sizeof *cost);
    int *split = hd_calloc((size_t)n * (size_t)n, sizeof *split);
    if (!cost || !split) {
        free(cost);
        free(split);
        return hd_fail_context(HD_ERR_NOMEM, "matrix chain");
    }
    chain c = {mats, n, split, nthreads};
    for (int len = 2; len <= n; len++)
        for (int i = 0; i + len - 1 < n; i++) {
            int j = i + len - 1;
            double best = -1;
            for (int k = i; k < j; k++) {
                double q = cost[i * n + k] + cost[(k + 1) * n + j] +
                           (double)mats[i]->nrows * mats[k]->ncols * mats[j]->ncols *
                               (chain_nc(&c, i, k) > chain_nc(&c, k + 1, j) ? chain_nc(&c, i, k) : chain_nc(&c, k + 1, j));
                /* ties go to the left-to-right order (larger k) */
                if (best < 0 || q <= best) {
                    best = q;
                    split[i * n + j] = k;
                }
            }
            cost[i * n + j] = best;
        }
    if (cost_best) *cost_best = n > 1 ? cost[n - 1] : 0;
    if (cost_ltr) {
        double t = 0;
        for (int j = 1; j < n; j++)
            t += (double)mats[0]->nrows * mats[j - 1]->ncols * mats[j]->ncols * chain_nc(&c, 0, j);
        *cost_ltr = t;
    }
    hd_status st;
    if (n == 1) {
        st = hd_matrix_copy(out, mats[0]);
        if (!st) {
            hd_header_free(&out->hdr);
            hd_header_init(&out->hdr);
        }
    } else {
        hd_matrix t;
        hd_matrix_init(&t);
        const hd_matrix *r;
        st = chain_eval(&c, 0, n - 1, &t, &r);
        if (!st) {
            hd_mtxfmt f = mats[0]->infmt;
            for (int i = 1; i < n; i++) f = hd_mtxfmt_combine(f, mats[i]->infmt);
            t.infmt = f;
            hd_matrix_move(out, &t);
        } else {
            hd_matrix_free(&t);
        }
    }
    free(cost);
    free(split);
    return st;
}

hd_status hd_matrix_transpose(hd_matrix *out, const hd_matrix *a)
{
    hd_matrix t;
    hd_matrix_init(&t);
    hd_status st = hd_matrix_alloc(&t, a->ncols, a->nrows, a->ncomp);
    if (st) return st;
    const int nc = a->ncomp;
    for (int i = 0; i < a->nrows; i++)
        for (int j = 0; j < a->ncols; j++)
            memcpy(hd_matrix_at(&t, j, i), hd_matrix_at(a, i, j), (size_t)nc * sizeof(double));
    t.infmt = a->infmt;
    hd_matrix_move(out, &t);
    return HD_OK;
}

hd_status hd_matrix_elementwise(hd_matrix *a, const hd_matrix *b, hd_mtxop op, unsigned long *nzero)
{
    static const char *const opname[] = {"sum", "element product", "element quotient"};
    const char *what = op == HD_MTXOP_ADD ? opname[0] : op == HD_MTXOP_EMUL ? opname[1] : opname[2];
    if (nzero) *nzero = 0;
    if (op != HD_MTXOP_ADD && op != HD_MTXOP_EMUL && op != HD_MTXOP_EDIV)
        return hd_fail(HD_ERR_USAGE, "unknown element-wise operation '%c'", (char)op);
    if (a->nrows != b->nrows || a->ncols != b->ncols)
        return hd_fail(HD_ERR_FORMAT, "matrix %s: sizes differ (%d x %d and %d x %d)",
                       what, a->nrows, a->ncols, b->nrows, b->ncols);
    if (b->ncomp != a->ncomp && b->ncomp != 1)
        return hd_fail(HD_ERR_FORMAT, "matrix %s: component counts differ (%d and %d; the second may have 1)",
                       what, a->ncomp, b->ncomp);
    const int nc = a->ncomp, sb = b->ncomp == 1 ? 0 : 1;
    size_t ne = (size_t)a->nrows * (size_t)a->ncols;
    unsigned long zeros = 0;
    for (size_t e = 0; e < ne; e++) {
        double *x = a->data + e * (size_t)nc;
        const double *y = b->data + e * (size_t)b->ncomp;
        for (int c = 0; c < nc; c++) {
            double v = y[c * sb];
            switch (op) {
            case HD_MTXOP_ADD: x[c] += v; break;
            case HD_MTXOP_EMUL: x[c] *= v; break;
            default:
                if (v == 0.0) { zeros++; x[c] = 0.0; }
                else x[c] /= v;
                break;
            }
        }
    }
    if (zeros)
        hd_warn("matrix element quotient: %lu zero divisor%s (result set to 0)", zeros, zeros > 1 ? "s" : "");
    if (nzero) *nzero = zeros;
    a->infmt = hd_mtxfmt_combine(a->infmt, b->infmt);
    return HD_OK;
}

hd_status hd_matrix_transform(hd_matrix *out, const hd_matrix *a, const double *coefs, int nout)
{
    if (nout <= 0 || nout > 1024)
        return hd_fail(HD_ERR_USAGE, "component transform: %d output components", nout);
    hd_matrix t;
    hd_matrix_init(&t);
    hd_status st = hd_matrix_alloc(&t, a->nrows, a->ncols, nout);
    if (st) return st;
    const int ni = a->ncomp;
    size_t ne = (size_t)a->nrows * (size_t)a->ncols;
    for (size_t e = 0; e < ne; e++) {
        const double *x = a->data + e * (size_t)ni;
        double *y = t.data + e * (size_t)nout;
        for (int i = 0; i < nout; i++) {
            double s = 0;
            for (int j = 0; j < ni; j++) s += coefs[i * ni + j] * x[j];
            y[i] = s;
        }
    }
    if ((st = hd_header_copy(&t.hdr, &a->hdr))) { hd_matrix_free(&t); return st; }
    t.infmt = a->infmt;
    if (is_picture_fmt(t.infmt) && nout != 3 && nout != 1) t.infmt = HD_MTX_FLOAT;
    hd_matrix_move(out, &t);
    return HD_OK;
}

hd_status hd_matrix_scale(hd_matrix *m, const double *sf, int nsf)
{
    if (nsf != 1 && nsf != m->ncomp)
        return hd_fail(HD_ERR_USAGE, "scaling: %d factors for a matrix of %d components (expected 1 or %d)",
                       nsf, m->ncomp, m->ncomp);
    size_t n = nvalues(m);
    for (size_t i = 0; i < n; i++) m->data[i] *= sf[nsf == 1 ? 0 : i % (size_t)m->ncomp];
    return HD_OK;
}

/* heliodon — Radiance information headers. */
#include "heliodon/header.h"

#include <ctype.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define HEADER_MAX ((size_t)16 << 20)

void hd_header_init(hd_header *h) { memset(h, 0, sizeof *h); }

void hd_header_free(hd_header *h)
{
    free(h->text);
    hd_header_init(h);
}

static hd_status reserve(hd_header *h, size_t extra)
{
    if (h->len + extra + 1 <= h->cap) return HD_OK;
    size_t nc = h->cap ? h->cap : 256;
    while (nc < h->len + extra + 1) nc *= 2;
    if (nc > HEADER_MAX * 2) return hd_fail(HD_ERR_RANGE, "information header longer than %zu bytes", HEADER_MAX);
    char *t = realloc(h->text, nc);
    if (!t) return hd_fail(HD_ERR_NOMEM, "out of memory for header");
    h->text = t;
    h->cap = nc;
    return HD_OK;
}

static hd_status append_bytes(hd_header *h, const char *s, size_t n)
{
    hd_status st = reserve(h, n);
    if (st) return st;
    memcpy(h->text + h->len, s, n);
    h->len += n;
    h->text[h->len] = 0;
    return HD_OK;
}

hd_status hd_header_copy(hd_header *dst, const hd_header *src)
{
    hd_header_init(dst);
    memcpy(dst->ident, src->ident, sizeof dst->ident);
    return src->len ? append_bytes(dst, src->text, src->len) : HD_OK;
}

static hd_status read_header(hd_istream *s, hd_header *h, int allow_no_ident);

hd_status hd_header_read(hd_istream *s, hd_header *h, int allow_no_ident)
{
    hd_header_init(h);
    hd_status st = read_header(s, h, allow_no_ident);
    if (st) hd_header_free(h); /* nothing half-read is handed back */
    return st;
}

static hd_status read_header(hd_istream *s, hd_header *h, int allow_no_ident)
{
    int c = hd_istream_peek(s);
    if (c == EOF)
        return hd_fail(HD_ERR_FORMAT, "%s: empty input, expected a Radiance information header", hd_istream_name(s));
    if (!allow_no_ident && c != '#')
        return hd_fail(HD_ERR_FORMAT, "%s: byte offset 0: expected a Radiance header starting with \"#?\"",
                       hd_istream_name(s));
    if (!isprint(c) && c != '\n')
        return hd_fail(HD_ERR_FORMAT, "%s: byte offset 0: not a Radiance file (binary data where the header should be)",
                       hd_istream_name(s));
    int first = 1;
    char line[4096];
    for (;;) {
        uint64_t at = hd_istream_offset(s);
        size_t n = 0;
        int toolong = 0;
        for (;;) {
            c = hd_istream_getc(s);
            if (c == EOF || c == '\n') break;
            if (c == 0)
                return hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: NUL byte inside the information header",
                               hd_istream_name(s), (unsigned long long)hd_istream_offset(s) - 1);
            if (n + 1 < sizeof line) line[n++] = (char)c;
            else toolong = 1;
            if (hd_istream_offset(s) > HEADER_MAX)
                return hd_fail(HD_ERR_FORMAT, "%s: information header longer than %zu bytes (no empty line ending it)",
                               hd_istream_name(s), HEADER_MAX);
        }
        line[n] = 0;
        if (c == EOF) {
            if (hd_istream_failed(s))
                return hd_fail(HD_ERR_IO, "%s: read error in the information header", hd_istream_name(s));
            return hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: end of data inside the information header "
                           "(expected an empty line ending it)", hd_istream_name(s),
                           (unsigned long long)hd_istream_offset(s));
        }
        if (n > 0 && line[n - 1] == '\r') line[--n] = 0;
        if (n == 0 && !toolong) break;
        if (first && line[0] == '#' && line[1] == '?') {
            hd_strlcpy(h->ident, line + 2, sizeof h->ident);
        } else {
            if (first && !allow_no_ident)
                return hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: expected \"#?\" identification line",
                               hd_istream_name(s), (unsigned long long)at);
            hd_status st = append_bytes(h, line, n);
            if (!st) st = append_bytes(h, "\n", 1);
            if (st) return st;
        }
        first = 0;
    }
    if (!h->text) {
        hd_status st = append_bytes(h, "", 0);
        if (st) return st;
    }
    return HD_OK;
}

/* Find the value of the last "NAME=" line: returns a pointer to the value
 * start and its length (to end of line). */
static const char *find_var(const hd_header *h, const char *name, size_t *vlen, const char *from)
{
    size_t nl = strlen(name);
    const char *found = NULL;
    const char *p = from ? from : h->text;
    if (!p) return NULL;
    while (*p) {
        const char *e = strchr(p, '\n');
        if (!e) e = p + strlen(p);
        if ((size_t)(e - p) > nl && !strncmp(p, name, nl) && p[nl] == '=') {
            found = p + nl + 1;
            *vlen = (size_t)(e - found);
        }
        p = *e ? e + 1 : e;
    }
    return found;
}

int hd_header_get(const hd_header *h, const char *name, char *buf, size_t cap)
{
    size_t vl = 0;
    const char *v = find_var(h, name, &vl, NULL);
    if (!v) return 0;
    while (vl && (*v == ' ' || *v == '\t')) { v++; vl--; }
    while (vl && isspace((unsigned char)v[vl - 1])) vl--;
    if (cap) {
        size_t k = vl < cap - 1 ? vl : cap - 1;
        memcpy(buf, v, k);
        buf[k] = 0;
    }
    return 1;
}

hd_status hd_header_get_long(const hd_header *h, const char *name, long *out, int *found)
{
    char buf[64];
    *found = hd_header_get(h, name, buf, sizeof buf);
    if (!*found) return HD_OK;
    if (hd_parse_long(buf, out) != 0)
        return hd_fail(HD_ERR_FORMAT, "header variable %s=%s: expected an integer", name, buf);
    return HD_OK;
}

double hd_header_exposure(const hd_header *h)
{
    double e = 1;
    const char *p = h->text;
    if (!p) return 1;
    while (*p) {
        const char *nl = strchr(p, '\n');
        if (!strncmp(p, "EXPOSURE=", 9)) {
            double v = strtod(p + 9, NULL);
            if (v > 0) e *= v;
        }
        if (!nl) break;
        p = nl + 1;
    }
    return e;
}

hd_status hd_header_append(hd_header *h, const char *line)
{
    hd_status st = append_bytes(h, line, strlen(line));
    return st ? st : append_bytes(h, "\n", 1);
}

hd_status hd_header_append_lines(hd_header *h, const char *lines)
{
    size_t n = lines ? strlen(lines) : 0;
    if (!n) return HD_OK;
    hd_status st = append_bytes(h, lines, n);
    return st || lines[n - 1] == '\n' ? st : append_bytes(h, "\n", 1);
}

hd_status hd_header_appendf(hd_header *h, const char *fmt, ...)
{
    char buf[HD_HEADER_MAXLINE + 1];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    return hd_header_append(h, buf);
}

static int needs_quotes(const char *w)
{
    if (!*w) return 1;
    for (; *w; w++)
        if (isspace((unsigned char)*w)) return 1;
    return 0;
}

hd_status hd_header_add_command(hd_header *h, int argc, char **argv)
{
    hd_status st = HD_OK;
    for (int i = 0; i < argc && !st; i++) {
        const char *w = argv[i];
        if (i == 0) {
            const char *b = strrchr(w, '/');
            if (b) w = b + 1;
        } else {
            st = append_bytes(h, " ", 1);
        }
        if (!st && needs_quotes(w) && i > 0) {
            const char *q = strchr(w, '"') ? "'" : "\"";
            st = append_bytes(h, q, 1);
            if (!st) st = append_bytes(h, w, strlen(w));
            if (!st) st = append_bytes(h, q, 1);
        } else if (!st) {
            st = append_bytes(h, w, strlen(w));
        }
    }
    return st ? st : append_bytes(h, "\n", 1);
}

hd_status hd_header_add_software(hd_header *h)
{
    return hd_header_append(h, "SOFTWARE= " HD_SOFTWARE);
}

hd_status hd_header_add_date(hd_header *h)
{
    /* SOURCE_DATE_EPOCH (reproducible outputs) overrides the clock. */
    time_t t = time(NULL);
    const char *sde = getenv("SOURCE_DATE_EPOCH");
    long v;
    if (sde && hd_parse_long(sde, &v) == 0) t = (time_t)v;
    struct tm lt, gt;
    localtime_r(&t, &lt);
    gmtime_r(&t, &gt);
    char a[64], b[64];
    strftime(a, sizeof a, "CAPDATE= %Y:%m:%d %H:%M:%S", &lt);
    strftime(b, sizeof b, "GMT= %Y:%m:%d %H:%M:%S", &gt);
    hd_status st = hd_header_append(h, a);
    return st ? st : hd_header_append(h, b);
}

void hd_header_remove(hd_header *h, const char *name)
{
    if (!h->text) return;
    size_t nl = strlen(name);
    char *r = h->text, *w = h->text;
    while (*r) {
        char *e = strchr(r, '\n');
        size_t l = e ? (size_t)(e - r + 1) : strlen(r);
        int drop = l > nl && !strncmp(r, name, nl) && r[nl] == '=';
        if (!drop) {
            memmove(w, r, l);
            w += l;
        }
        r += l;
    }
    *w = 0;
    h->len = (size_t)(w - h->text);
}

hd_status hd_header_write(FILE *fp, const hd_header *h, size_t *nwritten)
{
    size_t n = 0;
    const char *id = h && h->ident[0] ? h->ident : "RADIANCE";
    int k = fprintf(fp, "#?%s\n", id);
    if (k < 0) return hd_fail(HD_ERR_IO, "error writing header");
    n += (size_t)k;
    if (h && h->len) {
        if (fwrite(h->text, 1, h->len, fp) != h->len) return hd_fail(HD_ERR_IO, "error writing header");
        n += h->len;
    }
    if (nwritten) *nwritten = n;
    return HD_OK;
}

static hd_status write_format(FILE *fp, const char *fmt, size_t header_bytes, size_t *nwritten);

hd_status hd_header_write_format(FILE *fp, const char *fmt, size_t header_bytes)
{
    return write_format(fp, fmt, header_bytes, NULL);
}

/* NAME=val unless h has NAME= already (then it must say val). */
static hd_status put_var(FILE *fp, const hd_header *h, const char *name, int val, size_t *n)
{
    char buf[64];
    if (h && hd_header_get(h, name, buf, sizeof buf)) {
        long v;
        if (hd_parse_long(buf, &v) || v != val)
            return hd_fail(HD_ERR_INTERNAL, "matrix header: %s=%s given, but the matrix has %d", name, buf, val);
        return HD_OK;
    }
    int k = fprintf(fp, "%s=%d\n", name, val);
    if (k < 0) return hd_fail(HD_ERR_IO, "error writing header");
    *n += (size_t)k;
    return HD_OK;
}

hd_status hd_header_put(FILE *fp, const hd_header *h, const hd_header_dims *dims, const char *fmt,
                        size_t *nwritten)
{
    size_t n = 0;
    hd_status st = hd_header_write(fp, h, &n);
    if (!st && dims) {
        if (dims->nrows > 0) st = put_var(fp, h, "NROWS", dims->nrows, &n);
        if (!st && dims->ncols > 0) st = put_var(fp, h, "NCOLS", dims->ncols, &n);
        if (!st && dims->ncomp > 0) st = put_var(fp, h, "NCOMP", dims->ncomp, &n);
        if (!st && dims->endian != HD_ENDIAN_NONE) {
            int k = fprintf(fp, "BigEndian=%d\n", hd_host_bigendian() ^ (dims->endian == HD_ENDIAN_SWAPPED));
            if (k < 0) st = hd_fail(HD_ERR_IO, "error writing header");
            else n += (size_t)k;
        }
    }
    if (!st) st = write_format(fp, fmt, n, &n);
    if (nwritten) *nwritten = n;
    return st;
}

static hd_status write_format(FILE *fp, const char *fmt, size_t header_bytes, size_t *nwritten)
{
    int align = 0;
    if (!strcmp(fmt, "float") || !strncmp(fmt, "32-bit", 6)) align = 4;
    else if (!strcmp(fmt, "double") || !strncmp(fmt, "64-bit", 6)) align = 8;
    else if (!strncmp(fmt, "16-bit", 6)) align = 2;
    /* pictures are never padded */
    if (!strcmp(fmt, "32-bit_rle_rgbe") || !strcmp(fmt, "32-bit_rle_xyze")) align = 0;
    size_t pos = header_bytes + 7 + strlen(fmt);
    int pad = 0;
    if (align) while ((pos + (size_t)pad + 2) % (size_t)align) pad++;
    int k = fprintf(fp, "FORMAT=%s%*s\n\n", fmt, pad, "");
    if (k < 0) return hd_fail(HD_ERR_IO, "error writing header");
    if (nwritten) *nwritten = header_bytes + (size_t)k;
    return HD_OK;
}

/* heliodon — pieces of an rcontrib output (rcontrib -R) and their join
 * (rcmerge).
 *
 * A piece is what the full run writes, cut to a record range: the same
 * header (the command line without -R, so every piece of one run carries the
 * same one) plus one line "RECORDS=first count total", the same resolution
 * line, then only the piece's records.  Matrix records are written as the
 * full run writes them; picture records are flat 4-byte RGBE pixels (a run
 * length encoded scanline does not split at arbitrary pixels).  The join
 * drops the RECORDS= line, concatenates the records in order and, for
 * pictures, encodes the scanlines with the encoder rcontrib uses, so the
 * joined file is byte for byte the output of the full run. */
#include <dirent.h>
#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "heliodon/common.h"
#include "heliodon/contrib.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/picture.h"
#include "heliodon/rcmerge.h"

#define PIECE_KEY "RECORDS="

hd_status hd_rcontrib_piece_line(const hd_rcontrib_opts *o, hd_header *h)
{
    if (!o->ranged) return HD_OK;
    return hd_header_appendf(h, PIECE_KEY "%" PRIu64 " %" PRIu64 " %" PRIu64, o->rec_first, o->rec_count,
                             hd_rcontrib_nrecords(o));
}

uint64_t hd_rcontrib_nrecords(const hd_rcontrib_opts *o)
{
    return o->yres > 0 ? (uint64_t)o->yres * (uint64_t)(o->xres > 0 ? o->xres : 1) : 0;
}

typedef struct piece {
    const char *path;
    FILE *fp;
    char *head;           /* header and resolution line without the RECORDS= line */
    size_t headlen;
    uint64_t first, count, total;
    uint64_t data0, ndata;   /* byte offset and size of the records */
} piece;

/* Read the header of p (lines up to the empty one, then the resolution line
 * of pictures and of rcontrib's -x/-y matrices). */
static hd_status read_piece_head(piece *p, char *format, size_t fcap)
{
    size_t cap = 4096, len = 0;
    p->head = hd_malloc(cap);
    if (!p->head) return HD_ERR_NOMEM;
    char line[8192];
    int found = 0, nl = 0, ended = 0;
    format[0] = 0;
    uint64_t off = 0;
    while (fgets(line, sizeof line, p->fp)) {
        size_t n = strlen(line);
        nl++;
        if (n == sizeof line - 1 && line[n - 1] != '\n')
            return hd_fail(HD_ERR_FORMAT, "%s: header line %d is longer than %zu bytes", p->path, nl, sizeof line - 2);
        off += n;
        if (!strncmp(line, PIECE_KEY, strlen(PIECE_KEY))) {
            char extra;
            if (found || sscanf(line + strlen(PIECE_KEY), "%" SCNu64 " %" SCNu64 " %" SCNu64 " %c", &p->first,
                                &p->count, &p->total, &extra) != 3 ||
                p->count == 0 || p->first >= p->total || p->count > p->total - p->first)
                return hd_fail(HD_ERR_FORMAT, "%s: header line %d: expected one " PIECE_KEY
                               "first count total with the range inside the total", p->path, nl);
            found = 1;
            continue;
        }
        if (!strncmp(line, "FORMAT=", 7)) {   /* kept without the padding, which depends on the header's length */
            while (n > 8 && line[n - 2] == ' ') line[--n - 1] = '\n', line[n] = 0;
            size_t k = strcspn(line + 7, "\r\n");
            if (k >= fcap) k = fcap - 1;
            memcpy(format, line + 7, k);
            format[k] = 0;
        }
        if (len + n + 1 > cap) {
            char *t = realloc(p->head, cap = 2 * (len + n + 1));
            if (!t) return HD_ERR_NOMEM;
            p->head = t;
        }
        memcpy(p->head + len, line, n);
        len += n;
        if (!strcmp(line, "\n")) { ended = 1; break; }
    }
    if (!ended) return hd_fail(HD_ERR_FORMAT, "%s: the header has no end (empty line)", p->path);
    if (!found)
        return hd_fail(HD_ERR_FORMAT, "%s: not a piece of an rcontrib -R run (no " PIECE_KEY " line in the header)",
                       p->path);
    /* a resolution line follows the header of pictures and of -x/-y matrices */
    long here = ftell(p->fp);
    if (fgets(line, sizeof line, p->fp)) {
        char a[3], b[3], t;
        int ny, nx;
        if (sscanf(line, "%2[-+XY] %d %2[-+XY] %d%c", a, &ny, b, &nx, &t) == 5 && t == '\n' && ny > 0 && nx > 0) {
            size_t n = strlen(line);
            if (len + n + 1 > cap) {
                char *q = realloc(p->head, cap = len + n + 1);
                if (!q) return HD_ERR_NOMEM;
                p->head = q;
            }
            memcpy(p->head + len, line, n);
            len += n;
            off += n;
        } else if (fseek(p->fp, here, SEEK_SET)) {
            return hd_fail(HD_ERR_IO, "%s: cannot seek: %s", p->path, strerror(errno));
        }
    }
    p->head[len] = 0;
    p->headlen = len;
    p->data0 = off;
    struct stat sb;
    if (fstat(fileno(p->fp), &sb)) return hd_fail(HD_ERR_IO, "%s: %s", p->path, strerror(errno));
    if ((uint64_t)sb.st_size < off) return hd_fail(HD_ERR_FORMAT, "%s: ends inside its header", p->path);
    p->ndata = (uint64_t)sb.st_size - off;
    return HD_OK;
}

/* The header without its date lines (CAPDATE=, GMT=: pieces run at
 * different times; the join keeps the first piece's). */
static char *without_dates(const char *h)
{
    char *o = hd_malloc(strlen(h) + 1), *w = o;
    if (!o) return NULL;
    while (*h) {
        size_t k = strcspn(h, "\n");
        if (h[k]) k++;
        if (strncmp(h, "CAPDATE=", 8) && strncmp(h, "GMT=", 4)) {
            memcpy(w, h, k);
            w += k;
        }
        h += k;
    }
    *w = 0;
    return o;
}

/* The first line where two headers differ (1-based), for the message. */
static int first_difference(const char *a, const char *b, char *la, char *lb, size_t cap)
{
    int n = 1;
    for (;;) {
        size_t ka = strcspn(a, "\n"), kb = strcspn(b, "\n");
        if (ka != kb || memcmp(a, b, ka) || a[ka] != b[kb]) {
            snprintf(la, cap, "%.*s", (int)(ka < cap - 1 ? ka : cap - 1), a);
            snprintf(lb, cap, "%.*s", (int)(kb < cap - 1 ? kb : cap - 1), b);
            return n;
        }
        if (!a[ka]) return 0;
        a += ka + 1;
        b += kb + 1;
        n++;
    }
}

static int cmp_first(const void *x, const void *y)
{
    const piece *a = x, *b = y;
    return a->first < b->first ? -1 : a->first > b->first;
}

static hd_status copy_bytes(piece *p, FILE *out, const char *oname)
{
    char buf[1 << 16];
    if (fseek(p->fp, (long)p->data0, SEEK_SET)) return hd_fail(HD_ERR_IO, "%s: cannot seek: %s", p->path, strerror(errno));
    uint64_t left = p->ndata;
    while (left) {
        size_t k = left < sizeof buf ? (size_t)left : sizeof buf;
        if (fread(buf, 1, k, p->fp) != k)
            return hd_fail(HD_ERR_IO, "%s: byte offset %" PRIu64 ": read failed", p->path, p->data0 + p->ndata - left);
        if (fwrite(buf, 1, k, out) != k) return hd_fail(HD_ERR_IO, "%s: write failed: %s", oname, strerror(errno));
        left -= k;
    }
    return HD_OK;
}

/* Check one piece's records against its format: rec is the record size in
 * bytes (0: ascii, one line per record). */
static hd_status check_records(piece *p, size_t rec)
{
    if (rec) {
        if (p->ndata != p->count * rec)
            return hd_fail(HD_ERR_FORMAT, "%s: %" PRIu64 " bytes of records, expected %" PRIu64 " (%" PRIu64
                           " records of %zu bytes): truncated or not this output's piece",
                           p->path, p->ndata, p->count * rec, p->count, rec);
        return HD_OK;
    }
    if (fseek(p->fp, (long)p->data0, SEEK_SET)) return hd_fail(HD_ERR_IO, "%s: cannot seek", p->path);
    uint64_t lines = 0;
    int c, last = '\n';
    while ((c = getc(p->fp)) != EOF) {
        if (c == '\n') lines++;
        last = c;
    }
    if (last != '\n' || lines != p->count)
        return hd_fail(HD_ERR_FORMAT, "%s: %" PRIu64 " complete records (lines), expected %" PRIu64
                       ": truncated or not this output's piece", p->path, lines, p->count);
    return HD_OK;
}

hd_status hd_rcmerge(const char *out, const char *const *paths, int n)
{
    if (n < 1) return hd_fail(HD_ERR_USAGE, "rcmerge: no pieces for %s", out);
    piece *p = hd_calloc((size_t)n, sizeof *p);
    if (!p) return HD_ERR_NOMEM;
    hd_status st = HD_OK;
    char fmt0[64] = "", fmt[64];
    size_t rec = 0;
    int xres = 0;
    for (int i = 0; i < n && !st; i++) {
        p[i].path = paths[i];
        p[i].fp = fopen(paths[i], "rb");
        if (!p[i].fp) { st = hd_fail(HD_ERR_IO, "%s: cannot open: %s", paths[i], strerror(errno)); break; }
        st = read_piece_head(&p[i], i ? fmt : fmt0, sizeof fmt);
        if (st) break;
        if (i == 0) continue;
        char la[160], lb[160];
        char *h0 = without_dates(p[0].head), *hi = without_dates(p[i].head);
        int d = h0 && hi ? first_difference(h0, hi, la, lb, sizeof la) : -1;
        free(h0);
        free(hi);
        if (d < 0) { st = HD_ERR_NOMEM; break; }
        if (d)
            st = hd_fail(HD_ERR_FORMAT, "%s: not a piece of the same run as %s: header line %d is '%s', there '%s'",
                         p[i].path, p[0].path, d, lb, la);
        else if (p[i].total != p[0].total)
            st = hd_fail(HD_ERR_FORMAT, "%s: a piece of %" PRIu64 " records, %s one of %" PRIu64, p[i].path,
                         p[i].total, p[0].path, p[0].total);
    }
    if (!st) {
        int pic = !strcmp(fmt0, "32-bit_rle_rgbe") || !strcmp(fmt0, "32-bit_rle_xyze");
        if (pic) {
            const char *r = strrchr(p[0].head, '\n');
            while (r > p[0].head && r[-1] != '\n') r--;   /* start of the last line: the resolution */
            char a[3], b[3];
            int ny = 0;
            if (sscanf(r, "%2[-+XY] %d %2[-+XY] %d", a, &ny, b, &xres) != 4 || xres <= 0 ||
                (uint64_t)xres * (uint64_t)ny != p[0].total)
                st = hd_fail(HD_ERR_FORMAT, "%s: a picture piece needs the full picture's resolution line "
                             "(%" PRIu64 " records)", p[0].path, p[0].total);
            rec = 4;
        } else if (!strcmp(fmt0, "float") || !strcmp(fmt0, "double")) {
            /* the record size from the first piece, checked against the others */
            if (p[0].ndata % p[0].count || (p[0].ndata / p[0].count) % (3 * (!strcmp(fmt0, "float") ? 4 : 8)))
                st = hd_fail(HD_ERR_FORMAT, "%s: %" PRIu64 " bytes is not %" PRIu64 " whole %s records", p[0].path,
                             p[0].ndata, p[0].count, fmt0);
            else rec = (size_t)(p[0].ndata / p[0].count);
        } else if (strcmp(fmt0, "ascii")) {
            st = hd_fail(HD_ERR_FORMAT, "%s: FORMAT=%s: expected ascii, float, double or a picture", p[0].path,
                         fmt0[0] ? fmt0 : "(none)");
        }
    }
    for (int i = 0; i < n && !st; i++) st = check_records(&p[i], rec);
    if (!st) {   /* the ranges must tile 0 ... total */
        qsort(p, (size_t)n, sizeof *p, cmp_first);
        uint64_t next = 0;
        for (int i = 0; i < n && !st; i++) {
            if (p[i].first > next)
                st = hd_fail(HD_ERR_FORMAT, "records %" PRIu64 " to %" PRIu64 " of %s are missing (no piece has them)",
                             next, p[i].first - 1, out);
            else if (p[i].first < next)
                st = hd_fail(HD_ERR_FORMAT, "%s and %s overlap (records %" PRIu64 " to %" PRIu64 ")", p[i - 1].path,
                             p[i].path, p[i].first, (next < p[i].first + p[i].count ? next : p[i].first + p[i].count) - 1);
            next = p[i].first + p[i].count;
        }
        if (!st && next != p[0].total)
            st = hd_fail(HD_ERR_FORMAT, "records %" PRIu64 " to %" PRIu64 " of %s are missing (no piece has them)", next,
                         p[0].total - 1, out);
    }
    hd_ofile *of = NULL;
    if (!st) st = hd_ofile_open(&of, out);
    FILE *fo = of ? hd_ofile_fp(of) : NULL;
    if (!st) {   /* the header up to FORMAT=, the format line padded as rcontrib pads it, the rest */
        const char *h = p[0].head, *f = strstr(h, "\nFORMAT=");
        size_t nw = f ? (size_t)(f - h) + 1 : 0;
        const char *rest = f ? strstr(f + 1, "\n\n") : NULL;
        if (!f || !rest) st = hd_fail(HD_ERR_FORMAT, "%s: expected a FORMAT= line ending the header", p[0].path);
        else if (fwrite(h, 1, nw, fo) != nw) st = hd_fail(HD_ERR_IO, "%s: write failed: %s", out, strerror(errno));
        else if (!(st = hd_header_write_format(fo, fmt0, nw))) {
            rest += 2;
            size_t k = p[0].headlen - (size_t)(rest - h);
            if (fwrite(rest, 1, k, fo) != k) st = hd_fail(HD_ERR_IO, "%s: write failed: %s", out, strerror(errno));
        }
    }
    if (!st && rec == 4) {   /* pictures: scanlines of xres pixels across the pieces */
        uint8_t *line = hd_malloc_array((size_t)xres, 4);
        if (!line) st = HD_ERR_NOMEM;
        int fill = 0;
        for (int i = 0; i < n && !st; i++) {
            if (fseek(p[i].fp, (long)p[i].data0, SEEK_SET)) { st = hd_fail(HD_ERR_IO, "%s: cannot seek", p[i].path); break; }
            for (uint64_t left = p[i].count; left && !st;) {
                size_t k = (size_t)(xres - fill) < left ? (size_t)(xres - fill) : (size_t)left;
                if (fread(line + 4 * fill, 4, k, p[i].fp) != k) {
                    st = hd_fail(HD_ERR_IO, "%s: read failed", p[i].path);
                    break;
                }
                fill += (int)k;
                left -= k;
                if (fill == xres) { st = hd_scanline_write(fo, line, xres); fill = 0; }
            }
        }
        free(line);
    } else {
        for (int i = 0; i < n && !st; i++) st = copy_bytes(&p[i], fo, out);
    }
    if (of) {
        if (st) hd_ofile_abort(of);
        else st = hd_ofile_commit(of);
    }
    for (int i = 0; i < n; i++) {
        if (p[i].fp) fclose(p[i].fp);
        free(p[i].head);
    }
    free(p);
    return st;
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The names of the plain files in dir, sorted. */
static hd_status list_dir(const char *dir, char ***names, int *n)
{
    DIR *d = opendir(dir);
    if (!d) return hd_fail(HD_ERR_IO, "%s: cannot open the folder: %s", dir, strerror(errno));
    int cap = 64;
    char **v = hd_malloc_array((size_t)cap, sizeof *v);
    *n = 0;
    struct dirent *e;
    hd_status st = v ? HD_OK : HD_ERR_NOMEM;
    while (!st && (e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        if (*n == cap) {
            char **t = realloc(v, (size_t)(cap *= 2) * sizeof *v);
            if (!t) { st = HD_ERR_NOMEM; break; }
            v = t;
        }
        if (!(v[*n] = strdup(e->d_name))) st = HD_ERR_NOMEM;
        else (*n)++;
    }
    closedir(d);
    if (st) {
        for (int i = 0; i < *n; i++) free(v[i]);
        free(v);
        return st;
    }
    qsort(v, (size_t)*n, sizeof *v, cmp_str);
    *names = v;
    return HD_OK;
}

hd_status hd_rcmerge_dirs(const char *outdir, const char *const *dirs, int n)
{
    if (n < 1) return hd_fail(HD_ERR_USAGE, "rcmerge: no piece folders for %s", outdir);
    char **names = NULL, **other = NULL;
    int nn = 0, no = 0;
    hd_status st = list_dir(dirs[0], &names, &nn);
    if (st) return st;
    if (nn == 0) st = hd_fail(HD_ERR_FORMAT, "%s: no pieces in the folder", dirs[0]);
    for (int i = 1; i < n && !st; i++) {   /* every folder holds the same names */
        if ((st = list_dir(dirs[i], &other, &no))) break;
        for (int a = 0, b = 0; !st && (a < nn || b < no);) {
            int c = a >= nn ? 1 : b >= no ? -1 : strcmp(names[a], other[b]);
            if (c < 0) st = hd_fail(HD_ERR_FORMAT, "%s/%s: no such piece (it is in %s)", dirs[i], names[a], dirs[0]);
            else if (c > 0) st = hd_fail(HD_ERR_FORMAT, "%s/%s: a piece that %s does not have", dirs[i], other[b], dirs[0]);
            a++, b++;
        }
        for (int k = 0; k < no; k++) free(other[k]);
        free(other);
    }
    if (!st && mkdir(outdir, 0777) && errno != EEXIST) st = hd_fail(HD_ERR_IO, "%s: cannot create: %s", outdir, strerror(errno));
    const char **paths = hd_calloc((size_t)n, sizeof *paths);
    char **bufs = hd_calloc((size_t)n, sizeof *bufs);
    if (!st && (!paths || !bufs)) st = HD_ERR_NOMEM;
    for (int k = 0; k < nn && !st; k++) {
        for (int i = 0; i < n && !st; i++) {
            free(bufs[i]);
            size_t len = strlen(dirs[i]) + strlen(names[k]) + 2;
            if (!(bufs[i] = hd_malloc(len))) { st = HD_ERR_NOMEM; break; }
            snprintf(bufs[i], len, "%s/%s", dirs[i], names[k]);
            paths[i] = bufs[i];
        }
        if (st) break;
        size_t len = strlen(outdir) + strlen(names[k]) + 2;
        char *o = hd_malloc(len);
        if (!o) { st = HD_ERR_NOMEM; break; }
        snprintf(o, len, "%s/%s", outdir, names[k]);
        st = hd_rcmerge(o, paths, n);
        free(o);
    }
    for (int i = 0; bufs && i < n; i++) free(bufs[i]);
    free(bufs);
    free(paths);
    for (int k = 0; k < nn; k++) free(names[k]);
    free(names);
    return st;
}

/* heliodon — the annual composition in hour pieces (pmcompose -H k n) and
 * their join (pmcompose -J).
 *
 * Piece k of n composes the k-th of n contiguous slices of the daylight
 * records.  Every file it writes starts with two lines
 *   # PIECE= k n first count total
 *   # COMMAND= the pmcompose command line without -H k n
 * (first, count: the slice among the total daylight records).  Its summary
 * (-S, required with glare) is the piece's record for the join: the image
 * size, the sun patches its hours used, its timings and every hour's Ev, DGP
 * and DGI as exact hexadecimal numbers.  The join checks that the pieces are
 * 0 ... n-1 of one run, once each, with contiguous slices, and writes the
 * glare CSV, hour log, illuminance CSV and summary that one run over every
 * hour writes (the summary's percentiles from the exact values; its timings
 * are the pieces' sums). */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "annual_pieces.h"
#include "heliodon/glare.h"
#include "heliodon/header.h"
#include "heliodon/io.h"

hd_status hd_annual_piece_slice(const hd_annual_opts *o, long *recs, long *nrec, long *first, long *total)
{
    *first = 0;
    *total = *nrec;
    if (o->piece_n <= 0) return HD_OK;
    long n = o->piece_n, k = o->piece_k, t = *nrec;
    if (k < 0 || k >= n) return hd_fail(HD_ERR_USAGE, "-H %ld %ld: expected piece 0 ... %ld", k, n, n - 1);
    if (n > t)
        return hd_fail(HD_ERR_USAGE, "-H %ld %ld: more pieces than the %ld daylight hours of %s", k, n, t, o->weather);
    long a = (long)((int64_t)k * t / n), b = (long)((int64_t)(k + 1) * t / n);
    memmove(recs, recs + a, (size_t)(b - a) * sizeof *recs);
    *nrec = b - a;
    *first = a;
    return HD_OK;
}

void hd_annual_piece_lines(FILE *fp, const hd_annual_opts *o, long first, long count, long total)
{
    if (o->piece_n <= 0) return;
    fprintf(fp, "# PIECE= %d %d %ld %ld %ld\n# COMMAND=", o->piece_k, o->piece_n, first, count, total);
    for (int i = 0; i < o->argc; i++) {
        if (!strcmp(o->argv[i], "-H") && i + 2 < o->argc) { i += 2; continue; }
        fprintf(fp, " %s", o->argv[i]);
    }
    fputc('\n', fp);
}

hd_status hd_annual_header_command(hd_header *h, const hd_annual_opts *o)
{
    char **v = hd_calloc((size_t)o->argc + 1, sizeof *v);
    if (!v) return HD_ERR_NOMEM;
    int n = 0;
    for (int i = 0; i < o->argc; i++) {
        if (o->piece_n > 0 && !strcmp(o->argv[i], "-H") && i + 2 < o->argc) { i += 2; continue; }
        v[n++] = o->argv[i];
    }
    hd_status st = hd_header_add_command(h, n, v);
    free(v);
    return st;
}

/* ---- the join ---- */
void hd_annual_text_free(hd_annual_text *t)
{
    for (size_t i = 0; i < t->n; i++) free(t->line[i]);
    free(t->line);
    memset(t, 0, sizeof *t);
}

hd_status hd_annual_text_read(const char *path, size_t cap, hd_annual_text *t)
{
    memset(t, 0, sizeof *t);
    hd_istream *s;
    hd_status st = hd_istream_open(&s, path);
    if (st) return st;
    char *buf = hd_malloc(cap);
    if (!buf) { hd_istream_close(s); return HD_ERR_NOMEM; }
    long len;
    while ((len = hd_istream_getline(s, buf, cap)) != -1) {
        if (len < 0) {
            st = hd_fail(HD_ERR_FORMAT, "%s: line %zu: longer than %zu characters", path, t->n + 1, cap - 1);
            break;
        }
        while (len > 0 && (buf[len - 1] == '\n' || buf[len - 1] == '\r')) buf[--len] = 0;
        if ((st = HD_GROW(t->line, t->n + 1, t->cap, 256))) break;
        if (!(t->line[t->n] = hd_strdup(buf))) { st = HD_ERR_NOMEM; break; }
        t->n++;
    }
    free(buf);
    hd_istream_close(s);
    if (st) hd_annual_text_free(t);
    return st;
}

typedef struct piece {
    const char *dir;
    int k, n;
    long first, count, total;
    const char *command;   /* points into the primary file's text */
    hd_annual_text csv, log, sum, ill;
} piece;

static const char *base_name(const char *p)
{
    const char *s = strrchr(p, '/');
    return s ? s + 1 : p;
}

static hd_status piece_path(char *buf, size_t cap, const char *dir, const char *out)
{
    if ((size_t)snprintf(buf, cap, "%s/%s", dir, base_name(out)) >= cap)
        return hd_fail(HD_ERR_USAGE, "%s/%s: path too long", dir, base_name(out));
    return HD_OK;
}

/* The two piece lines of a file; with p->n == 0 they define the piece,
 * otherwise they must repeat it. */
static hd_status piece_head(piece *p, const hd_annual_text *t, const char *path)
{
    int k, n;
    long a, c, tot;
    char extra;
    if (t->n < 2 || sscanf(t->line[0], "# PIECE= %d %d %ld %ld %ld %c", &k, &n, &a, &c, &tot, &extra) != 5 ||
        strncmp(t->line[1], "# COMMAND=", 10))
        return hd_fail(HD_ERR_FORMAT, "%s: line 1: expected '# PIECE= k n first count total' and a '# COMMAND=' line "
                       "(a file of pmcompose -H)", path);
    if (n < 1 || k < 0 || k >= n || a < 0 || c < 1 || tot < 1 || a + c > tot)
        return hd_fail(HD_ERR_FORMAT, "%s: line 1: piece %d of %d, hours %ld +%ld of %ld: inconsistent", path, k, n, a,
                       c, tot);
    if (!p->n) {
        p->k = k, p->n = n, p->first = a, p->count = c, p->total = tot;
        p->command = t->line[1];
        return HD_OK;
    }
    if (k != p->k || n != p->n || a != p->first || c != p->count || tot != p->total || strcmp(t->line[1], p->command))
        return hd_fail(HD_ERR_FORMAT, "%s: lines 1-2 differ from the other files of the piece in %s", path, p->dir);
    return HD_OK;
}

/* Data lines after the piece lines: '#' lines skipped in logs, the CSV
 * header (the first other line) skipped when header is set. */
static size_t data_lines(const hd_annual_text *t, int skip_header, size_t *from)
{
    size_t i = 2, n = 0;
    while (i < t->n && t->line[i][0] == '#') i++;
    if (skip_header && i < t->n) i++;
    *from = i;
    for (size_t j = i; j < t->n; j++)
        if (t->line[j][0] != '#') n++;
    return n;
}

static int cmp_piece(const void *x, const void *y)
{
    const piece *a = x, *b = y;
    return (a->k > b->k) - (a->k < b->k);
}

static hd_status write_rows(FILE *fp, piece *p, int np, size_t off, int skip_header, const char *what)
{
    for (int i = 0; i < np; i++) {
        const hd_annual_text *t = off == 0 ? &p[i].csv : off == 1 ? &p[i].log : &p[i].ill;
        size_t from, n = data_lines(t, skip_header, &from);
        if ((long)n != p[i].count)
            return hd_fail(HD_ERR_FORMAT, "%s/%s: %zu hours, its piece line says %ld (truncated?)", p[i].dir, what, n,
                           p[i].count);
        for (size_t j = from; j < t->n; j++)
            if (t->line[j][0] != '#') fprintf(fp, "%s\n", t->line[j]);
    }
    return HD_OK;
}

hd_status hd_annual_join(const hd_annual_join_opts *o)
{
    if (o->ndirs < 1) return hd_fail(HD_ERR_USAGE, "-J: no piece folders given");
    if (!o->csv && !o->illum_csv && !o->hourlog)
        return hd_fail(HD_ERR_USAGE, "-J: name the outputs to join (-o, -L, -E, -S)");
    if (o->csv && !o->summary)
        return hd_fail(HD_ERR_USAGE, "-J with a glare CSV needs -S (the pieces' summaries hold the exact values)");
    piece *p = hd_calloc((size_t)o->ndirs, sizeof *p);
    if (!p) return HD_ERR_NOMEM;
    hd_status st = HD_OK;
    char path[4200];
    const char *outs[4] = {o->csv, o->hourlog, o->illum_csv, o->summary};
    for (int i = 0; i < o->ndirs && !st; i++) {
        p[i].dir = o->dirs[i];
        hd_annual_text *ts[4] = {&p[i].csv, &p[i].log, &p[i].ill, &p[i].sum};
        for (int f = 0; f < 4 && !st; f++) {
            if (!outs[f]) continue;
            if (!(st = piece_path(path, sizeof path, o->dirs[i], outs[f])) && !(st = hd_annual_text_read(path, 1 << 16, ts[f])))
                st = piece_head(&p[i], ts[f], path);
        }
    }
    if (!st) {   /* one run's pieces 0 ... n-1, once each, contiguous */
        qsort(p, (size_t)o->ndirs, sizeof *p, cmp_piece);
        for (int i = 0; i < o->ndirs && !st; i++) {
            if (p[i].n != p[0].n || p[i].total != p[0].total || strcmp(p[i].command, p[0].command))
                st = hd_fail(HD_ERR_FORMAT, "%s: not a piece of the same run as %s (%s)", p[i].dir, p[0].dir,
                             p[i].n != p[0].n ? "another piece count" : p[i].total != p[0].total ?
                             "another number of daylight hours" : "another command line");
            else if (i > 0 && p[i].k == p[i - 1].k)
                st = hd_fail(HD_ERR_FORMAT, "%s and %s are both piece %d of %d", p[i - 1].dir, p[i].dir, p[i].k, p[i].n);
            else if (p[i].k != i)
                st = hd_fail(HD_ERR_FORMAT, "piece %d of %d is missing (folders: %d given)", i, p[0].n, o->ndirs);
            else if (p[i].first != (i ? p[i - 1].first + p[i - 1].count : 0))
                st = hd_fail(HD_ERR_FORMAT, "%s: hours %ld ... overlap or leave a gap after piece %d", p[i].dir,
                             p[i].first, i - 1);
        }
        if (!st && o->ndirs != p[0].n)
            st = hd_fail(HD_ERR_FORMAT, "piece %d of %d is missing (folders: %d given)", o->ndirs, p[0].n, o->ndirs);
        if (!st && p[o->ndirs - 1].first + p[o->ndirs - 1].count != p[0].total)
            st = hd_fail(HD_ERR_FORMAT, "the pieces cover %ld of %ld hours",
                         p[o->ndirs - 1].first + p[o->ndirs - 1].count, p[0].total);
    }
    int np = o->ndirs;
    /* every file complete before anything is written */
    for (int i = 0; i < np && !st; i++) {
        const hd_annual_text *ts[3] = {&p[i].csv, &p[i].log, &p[i].ill};
        for (int f = 0; f < 3 && !st; f++) {
            if (!outs[f]) continue;
            size_t from, n = data_lines(ts[f], f != 1, &from);
            if ((long)n != p[i].count)
                st = hd_fail(HD_ERR_FORMAT, "%s/%s: %zu hours, its piece line says %ld (truncated?)", p[i].dir,
                             base_name(outs[f]), n, p[i].count);
        }
        long nh = 0;
        for (size_t j = 2; j < p[i].sum.n; j++) nh += !strncmp(p[i].sum.line[j], "hour: ", 6);
        if (!st && o->csv && nh != p[i].count)
            st = hd_fail(HD_ERR_FORMAT, "%s/%s: %ld hour lines, its piece line says %ld (truncated?)", p[i].dir,
                         base_name(o->summary), nh, p[i].count);
    }
    hd_ofile *of = NULL;
    if (!st && o->csv && !(st = hd_ofile_open(&of, o->csv))) {
        hd_glare_csv_header(hd_ofile_fp(of));
        if ((st = write_rows(hd_ofile_fp(of), p, np, 0, 1, base_name(o->csv)))) hd_ofile_abort(of);
        else st = hd_ofile_commit(of);
    }
    if (!st && o->illum_csv && !(st = hd_ofile_open(&of, o->illum_csv))) {
        size_t from;
        data_lines(&p[0].ill, 0, &from);
        if (from >= p[0].ill.n) st = hd_fail(HD_ERR_FORMAT, "%s/%s: no header line", p[0].dir, base_name(o->illum_csv));
        else fprintf(hd_ofile_fp(of), "%s\n", p[0].ill.line[from]);
        if (st || (st = write_rows(hd_ofile_fp(of), p, np, 2, 1, base_name(o->illum_csv)))) hd_ofile_abort(of);
        else st = hd_ofile_commit(of);
    }
    if (!st && o->hourlog && !(st = hd_ofile_open(&of, o->hourlog))) {
        fprintf(hd_ofile_fp(of), "%s\n", HD_ANNUAL_LOG_HEADER);
        if ((st = write_rows(hd_ofile_fp(of), p, np, 1, 0, base_name(o->hourlog)))) hd_ofile_abort(of);
        else st = hd_ofile_commit(of);
    }
    if (!st && o->summary && o->csv) {   /* the statistics of every hour, from the exact values */
        double limit = o->shade_limit;   /* the pieces' own (-c of their command) */
        for (size_t j = 2; j < p[0].sum.n; j++)
            if (!strncmp(p[0].sum.line[j], "shade_limit: ", 13)) limit = strtod(p[0].sum.line[j] + 13, NULL);
        hd_glare_annual an;
        hd_glare_annual_init(&an, limit);
        double tload = 0, tloop = 0;
        const char *image = NULL;
        unsigned char *used = NULL;
        int nused = 0, maxb = 0;
        for (int i = 0; i < np && !st; i++) {
            long nh = 0;
            for (size_t j = 2; j < p[i].sum.n && !st; j++) {
                const char *l = p[i].sum.line[j];
                double v[4];
                if (!strncmp(l, "hour: ", 6)) {
                    char *e = (char *)l + 6;
                    for (int q = 0; q < 4; q++) v[q] = strtod(e, &e);
                    if ((st = hd_glare_annual_add(&an, v[0], v[1], v[2], v[3], NULL))) break;
                    nh++;
                } else if (!strncmp(l, "load_seconds: ", 14)) tload += atof(l + 14);
                else if (!strncmp(l, "compose_glare_seconds: ", 23)) tloop += atof(l + 23);
                else if (!strncmp(l, "image: ", 7)) image = l;
                else if (!strncmp(l, "sun_patches_used:", 17)) {
                    char *e = (char *)l + 17;
                    for (;;) {
                        char *q;
                        long b = strtol(e, &q, 10);
                        if (q == e) break;
                        e = q;
                        if (b < 1 || b > 1000000) { st = hd_fail(HD_ERR_FORMAT, "%s: bad sun patch %ld", p[i].dir, b); break; }
                        if (b >= maxb) {
                            unsigned char *u = realloc(used, (size_t)b + 1);
                            if (!u) { st = HD_ERR_NOMEM; break; }
                            memset(u + maxb, 0, (size_t)(b + 1 - maxb));
                            used = u;
                            maxb = (int)b + 1;
                        }
                        if (!used[b]) { used[b] = 1; nused++; }
                    }
                }
            }
            if (!st && nh != p[i].count)
                st = hd_fail(HD_ERR_FORMAT, "%s/%s: %ld hour lines, its piece line says %ld (truncated?)", p[i].dir,
                             base_name(o->summary), nh, p[i].count);
        }
        if (!st && !image) st = hd_fail(HD_ERR_FORMAT, "%s/%s: no 'image:' line", p[0].dir, base_name(o->summary));
        if (!st && !(st = hd_ofile_open(&of, o->summary))) {
            FILE *fp = hd_ofile_fp(of);
            hd_glare_annual_write_summary(fp, &an);
            fprintf(fp, "sun_patches: %d\nload_seconds: %.3f\ncompose_glare_seconds: %.3f\n%s\n", nused, tload, tloop,
                    image);
            st = hd_ofile_commit(of);
        }
        free(used);
        hd_glare_annual_free(&an);
    }
    for (int i = 0; i < o->ndirs; i++) {
        hd_annual_text_free(&p[i].csv);
        hd_annual_text_free(&p[i].log);
        hd_annual_text_free(&p[i].sum);
        hd_annual_text_free(&p[i].ill);
    }
    free(p);
    return st;
}

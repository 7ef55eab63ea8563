/* heliodon — rcontrib -r: take up the outputs of an interrupted run.
 *
 * Outputs are written to temporaries (hd_ofile) and renamed into place when
 * the run ends, so a killed run leaves its records in ".NAME.hdtmp.PID.N".
 * With -r each named stream takes over that temporary (or copies the final
 * file when there is one, e.g. a partial output of Radiance's rcontrib);
 * the complete records of every stream are counted, every stream is cut to
 * the smallest count, and the caller skips as many records of input.  The
 * kept header is the first run's, so the finished files are byte for byte
 * those of an uninterrupted run.  With -c 0 (as Radiance) the one record of
 * sums each file holds is read back and the new rays are added to it. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "heliodon/contrib.h"
#include "heliodon/header.h"

static const char *fmt_name(char f)
{
    return f == 'a' ? "ascii" : f == 'f' ? "float" : f == 'd' ? "double" : "32-bit_rle_rgbe";
}

/* Offset just after the k-th '\n' at or after off (or after the last one:
 * *count = newlines found, at most k). */
static hd_status ascii_records(const char *tmp, const char *name, uint64_t off, uint64_t k, uint64_t *count,
                               uint64_t *end)
{
    FILE *fp = fopen(tmp, "rb");
    if (!fp || fseeko(fp, (off_t)off, SEEK_SET) != 0) {
        if (fp) fclose(fp);
        return hd_fail(HD_ERR_IO, "%s: cannot read back the output to resume", name);
    }
    uint64_t n = 0, pos = off;
    *end = off;
    int c;
    while (n < k && (c = getc(fp)) != EOF) {
        pos++;
        if (c == '\n') { n++; *end = pos; }
    }
    fclose(fp);
    *count = n;
    return HD_OK;
}

/* The header h of the earlier output of s: its FORMAT and NCOLS must be
 * this run's (opt: the options that read it, for messages). */
static hd_status check_head(const hd_rcontrib_opts *o, const hd_rc_resume *s, const hd_header *h, const char *opt)
{
    char fmt[64] = "";
    long ncols = 0;
    int found = 0;
    hd_header_get(h, "FORMAT", fmt, sizeof fmt);
    hd_status st = hd_header_get_long(h, "NCOLS", &ncols, &found);
    if (!st && strcmp(fmt, fmt_name(o->fout)))
        st = hd_fail(HD_ERR_FORMAT, "%s: format mismatch: the file holds FORMAT=%s, this run writes %s (%s)", s->name,
                     fmt[0] ? fmt : "(none)", fmt_name(o->fout), opt);
    if (!st && found && ncols != s->ncols)
        st = hd_fail(HD_ERR_FORMAT, "%s: the file has NCOLS=%ld, this run writes %d columns (%s)", s->name, ncols,
                     s->ncols, opt);
    return st;
}

/* The header of stream s as the earlier run left it: *data = offset of the
 * first record, or 0 when the header (or resolution line) is incomplete. */
static hd_status read_head(const hd_rcontrib_opts *o, hd_rc_resume *s, uint64_t *data)
{
    *data = 0;
    hd_istream *in;
    hd_status st = hd_istream_open(&in, hd_ofile_tmpname(s->of));
    if (st) return st;
    hd_header h;
    if (hd_header_read(in, &h, 0) != HD_OK) {   /* cut inside the header: start again */
        hd_clear_error();
        hd_istream_close(in);
        return HD_OK;
    }
    st = check_head(o, s, &h, "-r");
    hd_header_free(&h);
    uint64_t at = hd_istream_offset(in);
    if (!st && s->ncols == 1 && o->xres > 0 && o->yres > 0) {
        char line[128], want[64];
        snprintf(want, sizeof want, "-Y %8d +X %8d", o->yres, o->xres);
        long n = hd_istream_getline(in, line, sizeof line);
        uint64_t end = hd_istream_offset(in);
        if (n < 0 || end == at + (uint64_t)n) at = 0;   /* absent or without its newline */
        else if (strcmp(line, want))
            st = hd_fail(HD_ERR_FORMAT, "%s: resolution mismatch: \"%s\", this run writes \"%s\" (-r)", s->name, line,
                         want);
        else at = end;
    }
    hd_istream_close(in);
    if (!st) *data = at;
    return st;
}

/* -c 0: the record of sums an earlier run wrote to s->name, added into sum
 * at the stream's columns.  A missing file, or one without data, adds
 * nothing; a header of another format or column count, or a record cut
 * short, is an error. */
static hd_status reload_sums(const hd_rcontrib_opts *o, const hd_rc_resume *s, double *sum)
{
    if (access(s->name, F_OK) != 0) {
        hd_warn("-r -c 0: %s: missing reload file, its sums start at zero", s->name);
        return HD_OK;
    }
    hd_istream *in;
    hd_status st = hd_istream_open(&in, s->name);
    if (st) return st;
    int swap = 0;
    if (o->header) {
        hd_header h;
        if ((st = hd_header_read(in, &h, 0))) { hd_istream_close(in); return st; }
        char be[16] = "";
        st = check_head(o, s, &h, "-r -c 0");
        if (!st && o->fout != 'a' && hd_header_get(&h, "BigEndian", be, sizeof be))
            swap = (be[0] == '1') != hd_host_bigendian();
        hd_header_free(&h);
        if (st) { hd_istream_close(in); return st; }
    }
    size_t nv = 3 * (size_t)s->ncols, esz = o->fout == 'f' ? 4 : 8;
    double *v = hd_malloc_array(nv, sizeof *v);
    if (!v) { hd_istream_close(in); return HD_ERR_NOMEM; }
    size_t got = 0;
    for (; got < nv && !st; got++) {
        int eof = 0;
        if (o->fout == 'a') {
            st = hd_istream_real(in, &v[got], &eof);
        } else {
            unsigned char b[8];
            size_t k = hd_istream_read(in, b, esz);
            if (k == 0) eof = 1;
            else if (k < esz) {
                st = hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: value %zu is cut short (-r -c 0)", s->name,
                             (unsigned long long)hd_istream_offset(in), got + 1);
                break;
            }
            if (!eof && swap) hd_swap_bytes(b, esz, 1);
            if (!eof && esz == 4) { float f; memcpy(&f, b, 4); v[got] = f; }
            else if (!eof) memcpy(&v[got], b, 8);
        }
        if (!st && eof) break;
        if (!st && !isfinite(v[got]))
            st = hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: value %zu is not finite (-r -c 0)", s->name,
                         (unsigned long long)hd_istream_offset(in), got + 1);
    }
    if (!st && got > 0 && got < nv)
        st = hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: the record of sums ends after %zu of %zu values (-r -c 0)",
                     s->name, (unsigned long long)hd_istream_offset(in), got, nv);
    if (!st && got == nv)
        for (size_t j = 0; j < nv; j++) sum[3 * (size_t)s->cols[j / 3] + j % 3] += v[j];
    free(v);
    hd_istream_close(in);
    return st;
}

hd_status hd_rcontrib_resume(const hd_rcontrib_opts *o, hd_rc_resume *s, int n, uint64_t expect, uint64_t *done,
                             double *sum)
{
    *done = 0;
    for (int i = 0; i < n; i++) {
        if (!s[i].name || !s[i].name[0])
            return hd_fail(HD_ERR_USAGE, "-r: cannot recover from the standard output (give -o files)");
        if (s[i].name[0] == '!') return hd_fail(HD_ERR_USAGE, "-r: cannot recover from a command (-o %s)", s[i].name);
    }
    if (o->accum == 0) {
        /* as Radiance: the sums already written are the start of the new
         * sums, and the files are written again when the run ends */
        if (!sum) return hd_fail(HD_ERR_INTERNAL, "-r -c 0: no sums to reload into");
        for (int i = 0; i < n; i++) {
            hd_status st = reload_sums(o, &s[i], sum);
            if (st) return st;
        }
        return HD_OK;
    }
    if (o->fout == 'c') {
        /* pictures are written whole at the end: either every one exists
         * (the run is complete) or the run starts again */
        int all = 1;
        for (int i = 0; i < n && all; i++) all = access(s[i].name, F_OK) == 0;
        if (all && n > 0) {
            hd_warn("-r: output appears to be complete");
            *done = expect;
        }
        return HD_OK;
    }
    size_t esz = o->fout == 'f' ? 4 : 8;
    uint64_t *data = hd_calloc((size_t)n + 1, sizeof *data);
    uint64_t *size = hd_calloc((size_t)n + 1, sizeof *size);
    if (!data || !size) { free(data); free(size); return HD_ERR_NOMEM; }
    uint64_t least = UINT64_MAX;
    hd_status st = HD_OK;
    for (int i = 0; i < n && !st; i++) {
        int from;
        if ((st = hd_ofile_open_resume(&s[i].of, s[i].name, &from, &size[i]))) break;
        hd_ofile_keep_on_signal(s[i].of);
        uint64_t recs = 0;
        data[i] = 0;
        s[i].has_header = 0;
        if (size[i] > 0) {
            if (o->header) {
                if ((st = read_head(o, &s[i], &data[i]))) break;
                s[i].has_header = data[i] > 0;
            } else {
                s[i].has_header = 1;   /* nothing to write before the records */
            }
        }
        if (s[i].has_header) {
            if (o->fout == 'a') {
                uint64_t end;
                st = ascii_records(hd_ofile_tmpname(s[i].of), s[i].name, data[i], UINT64_MAX, &recs, &end);
            } else {
                recs = (size[i] - data[i]) / ((uint64_t)s[i].ncols * 3 * esz);
            }
        }
        if (recs < least) least = recs;
    }
    if (!st && n == 0) least = 0;
    for (int i = 0; i < n && !st; i++) {
        uint64_t cut = 0;
        if (s[i].has_header) {
            if (o->fout == 'a') {
                uint64_t cnt;
                st = ascii_records(hd_ofile_tmpname(s[i].of), s[i].name, data[i], least, &cnt, &cut);
            } else {
                cut = data[i] + least * (uint64_t)s[i].ncols * 3 * esz;
            }
        }
        if (!st && cut != size[i]) st = hd_ofile_truncate(s[i].of, cut);
    }
    free(data);
    free(size);
    if (st) return st;
    *done = least;
    if (least == 0) hd_warn("-r: no earlier output to recover, starting from the first record");
    else if (expect && least >= expect) hd_warn("-r: output appears to be complete");
    else if (hd_warnings_enabled())
        fprintf(stderr, "%s: -r: %llu records recovered, skipping as many of the input\n", hd_progname(),
                (unsigned long long)least);
    return HD_OK;
}

/* Directory part of name ("." when none), into buf. */
static void dir_of(const char *name, char *buf, size_t cap)
{
    const char *slash = strrchr(name, '/');
    if (!slash) snprintf(buf, cap, ".");
    else snprintf(buf, cap, "%.*s", (int)(slash - name + 1), name);
}

hd_status hd_rcontrib_check_size(const hd_rcontrib_opts *o, const hd_rc_resume *s, int n, uint64_t expect,
                                 uint64_t done)
{
    if (!expect || done >= expect) return HD_OK;
    uint64_t left = expect - done;
    /* the files still to write, summed per directory */
    double vbytes = o->fout == 'c' ? 4.0 / 3 : o->fout == 'f' ? 4 : o->fout == 'd' ? 8 : 14;
    for (int i = 0; i < n; i++) {
        if (!s[i].name || !s[i].name[0] || s[i].name[0] == '!') continue;
        char d[4096], e[4096];
        dir_of(s[i].name, d, sizeof d);
        int seen = 0;
        for (int k = 0; k < i && !seen; k++) {
            if (!s[k].name || !s[k].name[0] || s[k].name[0] == '!') continue;
            dir_of(s[k].name, e, sizeof e);
            seen = !strcmp(d, e);
        }
        if (seen) continue;
        double need = 0;
        int nf = 0;
        for (int k = i; k < n; k++) {
            if (!s[k].name || !s[k].name[0] || s[k].name[0] == '!') continue;
            dir_of(s[k].name, e, sizeof e);
            if (strcmp(d, e)) continue;
            need += (double)left * (double)s[k].ncols * 3 * vbytes + 4096;
            nf++;
        }
        char what[4200];
        snprintf(what, sizeof what, "-o %s%s (%d file%s of %llu records)", s[i].name, nf > 1 ? " ..." : "", nf,
                 nf > 1 ? "s" : "", (unsigned long long)expect);
        hd_status st = hd_check_disk(s[i].name, need > 1.8e19 ? UINT64_MAX : (uint64_t)need, what);
        if (st) return st;
    }
    return HD_OK;
}

/* heliodon — the rcontrib driver (rcdriver.h): rays in, records out to the
 * -o streams, with the backward or the photon gather estimator. */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "heliodon/contrib.h"
#include "heliodon/exr.h"
#include "heliodon/matrix.h"
#include "heliodon/parallel.h"
#include "heliodon/picture.h"
#include "heliodon/rcmerge.h"
#include "progress.h"
#include "rcdriver.h"

/* ---- output streams ----
 * One stream per -o name (per modifier with %s, per bin with %d).
 * Matrices are written record by record; pictures (-fc) are not held in
 * memory: every batch appends each picture's pixels (RGBE, or floats for
 * .exr names) to an anonymous spool file, and the pictures are written at
 * the end, so memory does not grow with the number of pictures. */
typedef struct stream {
    char *name;           /* NULL = standard output, "!command" = a pipe */
    int *cols;            /* record columns routed here */
    int ncols, capcols;
    int mod;              /* modifier of the first column */
    int multimod;         /* columns from more than one modifier */
    int has_s, has_d;
    long bin;             /* BIN= value for %d streams */
    hd_ofile *of;
    FILE *fp;
    FILE *pipe;
    int exr;              /* picture written as OpenEXR (file name ends in .exr) */
    size_t esz, soff;     /* spool bytes per pixel, offset within a block's record */
    hd_mtxwriter w;       /* matrix output (-fa, -ff, -fd) */
} stream;

struct hd_rc_out {
    stream *s;
    int n;
    int spool_fd;
    size_t rec_bytes;     /* spool bytes per record (all picture streams) */
    struct { uint64_t off, n; } *sb;   /* spool blocks: file offset, records */
    size_t nblk, capblk;
    uint64_t *place;      /* records in coherent order: each spooled record's place in the pictures */
    uint64_t nplace;
    unsigned char *blk;   /* the block being filled */
};

static const char *stream_name(const stream *s) { return s->name ? s->name : "standard output"; }

static stream *find_stream(hd_rc_out *o, const char *name)
{
    for (int i = 0; i < o->n; i++) {
        if (!name && !o->s[i].name) return &o->s[i];
        if (name && o->s[i].name && !strcmp(name, o->s[i].name)) return &o->s[i];
    }
    stream *ns = hd_realloc_array(o->s, (size_t)o->n + 1, sizeof *ns);
    if (!ns) return NULL;
    o->s = ns;
    stream *s = &o->s[o->n++];
    memset(s, 0, sizeof *s);
    s->mod = -1;
    if (name) {
        s->name = hd_strdup(name);
        if (!s->name) { o->n--; return NULL; }
    }
    return s;
}

static hd_status add_col(stream *s, int mod, int col)
{
    if (s->ncols == s->capcols) {
        int nc = s->capcols ? 2 * s->capcols : 8;
        int *p = hd_realloc_array(s->cols, (size_t)nc, sizeof *p);
        if (!p) return HD_ERR_NOMEM;
        s->cols = p;
        s->capcols = nc;
    }
    s->cols[s->ncols++] = col;
    if (s->mod < 0) s->mod = mod;
    else if (s->mod != mod) s->multimod = 1;
    return HD_OK;
}

static void free_streams(hd_rc_out *o, int abort)
{
    for (int i = 0; i < o->n; i++) {
        stream *s = &o->s[i];
        if (s->of && abort) hd_ofile_abort(s->of);
        if (s->pipe) pclose(s->pipe);
        free(s->name);
        free(s->cols);
        free(s->w.scratch);
    }
    free(o->s);
    free(o->sb);
    free(o->place);
    free(o->blk);
    if (o->spool_fd >= 0) close(o->spool_fd);
    memset(o, 0, sizeof *o);
    o->spool_fd = -1;
}

static hd_status build_streams(const hd_contrib *c, hd_rc_out *o)
{
    char name[4096];
    for (int m = 0; m < c->nmods; m++) {
        const hd_cmod *cm = &c->mods[m];
        int kind = cm->outspec ? hd_pattern_kind(cm->outspec) : 0;
        if (kind < 0) return HD_ERR_USAGE;
        for (int b = 0; b < cm->bin.nbins; b++) {
            const char *nm = cm->outspec;
            if (kind) {
                hd_status st = hd_pattern_format(name, sizeof name, cm->outspec, kind & 2 ? cm->name : NULL,
                                                 kind & 1 ? b : 0);
                if (st != HD_OK) return st;
                nm = name;
            }
            stream *s = find_stream(o, nm);
            if (!s) return HD_ERR_NOMEM;
            s->has_s = (kind & 2) != 0;
            if (kind & 1) { s->has_d = 1; s->bin = b; }
            if (add_col(s, m, cm->first + b) != HD_OK) return HD_ERR_NOMEM;
        }
    }
    return HD_OK;
}

static hd_mtxfmt out_fmt(char f)
{
    return f == 'f' ? HD_MTX_FLOAT : f == 'd' ? HD_MTX_DOUBLE : HD_MTX_ASCII;
}

/* The header lines of stream s: the caller's, then NCOMP, MODIFIER, BIN,
 * NROWS, NCOLS in rcontrib's order (the writers add BigEndian and FORMAT). */
static hd_status stream_header(const hd_contrib *c, const hd_rcontrib_opts *o, const stream *s,
                               const hd_header *hdr, hd_header *h)
{
    hd_header_init(h);
    hd_status st = hd_header_copy(h, hdr);
    if (st == HD_OK) st = hd_header_append(h, "NCOMP=3");
    if (st == HD_OK && (s->has_s || s->ncols == 1) && !s->multimod)
        st = hd_header_appendf(h, "MODIFIER=%s", c->mods[s->mod].name);
    if (st == HD_OK && s->has_d) st = hd_header_appendf(h, "BIN=%ld", s->bin);
    if (st == HD_OK && o->yres > 0) st = hd_header_appendf(h, "NROWS=%llu", (unsigned long long)hd_rcontrib_nrecords(o));
    if (st == HD_OK && (o->xres <= 0 || s->ncols > 1)) st = hd_header_appendf(h, "NCOLS=%d", s->ncols);
    return st;
}

/* Sizes checked; with -r the streams' files from the earlier run (*done
 * records kept, keep_header: the stream's header is there) */
static hd_status resume_streams(const hd_rcontrib_opts *o, hd_rc_out *os, uint64_t expect, uint64_t *done,
                                unsigned char *keep_header, double *sum)
{
    hd_rc_resume *r = hd_calloc((size_t)os->n + 1, sizeof *r);
    if (!r) return HD_ERR_NOMEM;
    for (int i = 0; i < os->n; i++) {
        r[i].name = os->s[i].name;
        r[i].ncols = os->s[i].ncols;
        r[i].cols = os->s[i].cols;
    }
    hd_status st = o->recover ? hd_rcontrib_resume(o, r, os->n, expect, done, sum) : HD_OK;
    if (!st) st = hd_rcontrib_check_size(o, r, os->n, expect, *done);
    if (!st && o->fout == 'c' && expect > *done) {   /* the picture spool */
        const char *td = getenv("TMPDIR");
        char sp[4200];
        snprintf(sp, sizeof sp, "%s/spool", td && *td ? td : "/tmp");
        st = hd_check_disk(sp, (expect - *done) * (uint64_t)os->n * 12, "rcontrib -fc picture spool (TMPDIR)");
    }
    for (int i = 0; i < os->n; i++) {
        os->s[i].of = r[i].of;
        keep_header[i] = (unsigned char)r[i].has_header;
    }
    free(r);
    return st;
}

static hd_status open_pipe(stream *s)
{
    fflush(stdout);
    signal(SIGPIPE, SIG_IGN);   /* a command that exits early gives a write error */
    s->pipe = popen(s->name + 1, "w");
    if (!s->pipe) return hd_fail(HD_ERR_IO, "-o %s: cannot start the command", s->name);
    s->fp = s->pipe;
    return HD_OK;
}

static hd_status spool_open(hd_rc_out *os)
{
    const char *dir = getenv("TMPDIR");
    char path[4096];
    if (snprintf(path, sizeof path, "%s/hdrcXXXXXX", dir && *dir ? dir : "/tmp") >= (int)sizeof path)
        return hd_fail(HD_ERR_RANGE, "TMPDIR too long");
    int fd = mkstemp(path);
    if (fd < 0) return hd_fail(HD_ERR_IO, "%s: cannot create the picture spool file: %s", path, strerror(errno));
    unlink(path);   /* anonymous: goes away with the process */
    os->spool_fd = fd;
    return HD_OK;
}

/* Pictures: checked (one column, a path that can be written), given their
 * place in the spool; opened when written at the end. */
static hd_status open_picture(const hd_rcontrib_opts *o, hd_rc_out *os, stream *s)
{
    if (s->ncols != 1)
        return hd_fail(HD_ERR_USAGE, "%s: picture output (-f?c) needs one value per stream, this one has %d "
                       "(use an -o pattern with %%d per bin)", stream_name(s), s->ncols);
    s->exr = s->name && s->name[0] != '!' && hd_has_suffix(s->name, ".exr");
    if (s->exr && o->ranged)
        return hd_fail(HD_ERR_USAGE, "%s: -R pieces are Radiance pictures or matrices, not OpenEXR", s->name);
    s->esz = s->exr ? 12 : 4;
    s->soff = os->rec_bytes;
    os->rec_bytes += s->esz;
    if (s->name && s->name[0] != '!') {   /* check the path now (a bad one fails before the work) */
        hd_ofile *probe;
        hd_status st = hd_ofile_open(&probe, s->name);
        if (st != HD_OK) return st;
        hd_ofile_abort(probe);
    }
    return HD_OK;
}

static hd_status open_streams_k(const hd_contrib *c, const hd_rcontrib_opts *o, hd_rc_out *os,
                                const hd_header *hdr, const unsigned char *keep)
{
    for (int i = 0; i < os->n; i++) {
        stream *s = &os->s[i];
        int piped = s->name && s->name[0] == '!';
        if (s->of) {   /* resumed */
            s->fp = hd_ofile_fp(s->of);
        } else if (s->name && !piped && !o->force && !o->recover && access(s->name, F_OK) == 0)
            return hd_fail(HD_ERR_IO, "%s: output file exists (use -fo to overwrite)", s->name);
        if (o->fout == 'c') {
            hd_status st = open_picture(o, os, s);
            if (st != HD_OK) return st;
            continue;
        }
        hd_status st = HD_OK;
        if (s->of) {
        } else if (piped) {
            if ((st = open_pipe(s)) != HD_OK) return st;
        } else {
            st = hd_ofile_open(&s->of, s->name);
            if (st != HD_OK) return st;
            if (o->accum > 0) hd_ofile_keep_on_signal(s->of);   /* -r can continue it */
            s->fp = hd_ofile_fp(s->of);
        }
        int header = o->header && !keep[i];
        hd_header h;
        hd_header_init(&h);
        if (header) {
            st = stream_header(c, o, s, hdr, &h);
            if (st == HD_OK) st = hd_rcontrib_piece_line(o, &h);   /* -R: a piece */
        }
        int flags = header ? HD_MTXW_HEADER | (o->xres > 0 && s->ncols == 1 ? HD_MTXW_NO_NCOLS : 0) : 0;
        /* rows not counted by the writer: -r continues a partial file */
        if (st == HD_OK) st = hd_mtxwriter_begin(&s->w, s->fp, &h, flags, out_fmt(o->fout), 0, s->ncols, 3);
        hd_header_free(&h);
        if (st != HD_OK) return hd_fail_context(st, "%s", stream_name(s));
        s->w.ascii_style = HD_MTXASCII_RCONTRIB;
        if (header && s->ncols == 1 && o->xres > 0 && o->yres > 0) {   /* the resolution line of pictures */
            char res[64];
            hd_resolu_format(res, sizeof res, &(hd_resolu){HD_RES_STANDARD, o->xres, o->yres});
            fputs(res, s->fp);
        }
    }
    if (o->fout == 'c' && os->n) {
        hd_status st = spool_open(os);
        if (st != HD_OK) return st;
    }
    return HD_OK;
}

/* Open (or with -r take up) every stream and write the headers; *done:
 * records already there (-r); with -c 0 and -r, the sums already written
 * are added into sum. */
static hd_status open_streams(const hd_contrib *c, const hd_rcontrib_opts *o, hd_rc_out *os,
                              const hd_header *hdr, uint64_t nrec, uint64_t *done, double *sum)
{
    *done = 0;
    unsigned char *keep = hd_calloc((size_t)os->n + 1, 1);
    if (!keep) return HD_ERR_NOMEM;
    hd_status st = resume_streams(o, os, nrec, done, keep, sum);
    if (!st && !(o->recover && nrec && *done >= nrec)) st = open_streams_k(c, o, os, hdr, keep);
    free(keep);
    return st;
}

void hd_rc_out_encode(hd_rc_out *os, int q, const double *vals, size_t nrec, size_t us)
{
    stream *s = &os->s[q];
    unsigned char *d = os->blk + s->soff * nrec;
    for (size_t r = 0; r < nrec; r++) {
        const double *v = vals + r * us;
        float f[3] = {(float)v[0], (float)v[1], (float)v[2]};
        if (s->exr) memcpy(d + 12 * r, f, 12);
        else hd_rgbe_encode(d + 4 * r, f[0], f[1], f[2]);
    }
}

static hd_status spool_io(int fd, void *b, size_t n, uint64_t off, int wr)
{
    size_t done = 0;
    while (done < n) {
        ssize_t r = wr ? pwrite(fd, (const char *)b + done, n - done, (off_t)(off + done))
                       : pread(fd, (char *)b + done, n - done, (off_t)(off + done));
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0)
            return hd_fail(HD_ERR_IO, "picture spool file: %s failed at byte %llu%s", wr ? "write" : "read",
                           (unsigned long long)(off + done), wr ? " (disk full?)" : "");
        done += (size_t)r;
    }
    return HD_OK;
}

/* Append the picture pixels of the batch's nrec records (out: record-major
 * records of rlen doubles; NULL: the block is already encoded); recs: the
 * records' places in the pictures (NULL: they follow the previous block). */
static hd_status spool_batch(hd_rc_out *os, const double *out, size_t nrec, size_t rlen, const uint64_t *recs)
{
    if (recs) {
        if (!os->place)   /* the blocks before in input order */
            for (size_t b = 0; b < os->nblk; b++) os->nplace += os->sb[b].n;
        uint64_t *p = hd_realloc_array(os->place, (size_t)os->nplace + nrec, sizeof *p);
        if (!p) return HD_ERR_NOMEM;
        if (!os->place)
            for (uint64_t k = 0; k < os->nplace; k++) p[k] = k;
        os->place = p;
        memcpy(p + os->nplace, recs, nrec * sizeof *p);
        os->nplace += nrec;
    }
    if (HD_GROW(os->sb, os->nblk + 1, os->capblk, 64)) return HD_ERR_NOMEM;
    uint64_t off = os->nblk ? os->sb[os->nblk - 1].off + os->sb[os->nblk - 1].n * os->rec_bytes : 0;
    if (out)
        for (int q = 0; q < os->n; q++) hd_rc_out_encode(os, q, out + 3 * (size_t)os->s[q].cols[0], nrec, rlen);
    hd_status st = spool_io(os->spool_fd, os->blk, nrec * os->rec_bytes, off, 1);
    if (st) return st;
    os->sb[os->nblk].off = off;
    os->sb[os->nblk++].n = nrec;
    return HD_OK;
}

/* Records of the batch (record-major, or NULL: pictures already encoded)
 * to every stream. */
static hd_status write_batch(const hd_rcontrib_opts *o, hd_rc_out *os, const double *out, size_t nrec, size_t rlen,
                             const uint64_t *recs)
{
    if (o->fout == 'c') return spool_batch(os, out, nrec, rlen, recs);
    for (size_t r = 0; r < nrec; r++)
        for (int i = 0; i < os->n; i++) {
            stream *s = &os->s[i];
            hd_status st = hd_mtxwriter_row_cols(&s->w, out + r * rlen, s->cols);
            if (st) return hd_fail_context(st, "%s", stream_name(s));
        }
    return HD_OK;
}

/* Stream s's pixels of spool block b (esz bytes each) into *seg, grown as
 * needed. */
static hd_status spool_block(const hd_rc_out *os, const stream *s, size_t b, unsigned char **seg, size_t *segcap)
{
    size_t n = (size_t)os->sb[b].n;
    if (n * s->esz > *segcap) {
        free(*seg);
        *segcap = n * s->esz;
        *seg = hd_malloc(*segcap);
        if (!*seg) { *segcap = 0; return HD_ERR_NOMEM; }
    }
    return spool_io(os->spool_fd, *seg, n * s->esz, os->sb[b].off + s->soff * n, 0);
}

/* Stream s's pixels in picture order, segment by segment: spool block b
 * (*n pixels), or with placed records (coherent order) the whole picture
 * as segment 0 of the nseg = 1. */
static size_t spool_nseg(const hd_rc_out *os) { return os->place ? (os->nblk ? 1 : 0) : os->nblk; }

static hd_status spool_segment(const hd_rc_out *os, const stream *s, size_t b, unsigned char **seg, size_t *segcap,
                               size_t *n)
{
    if (!os->place) {
        *n = (size_t)os->sb[b].n;
        return spool_block(os, s, b, seg, segcap);
    }
    size_t tot = (size_t)os->nplace, es = s->esz;
    unsigned char *pic = hd_malloc_array(tot ? tot : 1, es), *blk = NULL;
    size_t blkcap = 0;
    hd_status st = pic ? HD_OK : HD_ERR_NOMEM;
    uint64_t k = 0;
    for (size_t q = 0; q < os->nblk && !st; q++) {
        if ((st = spool_block(os, s, q, &blk, &blkcap))) break;
        for (size_t r = 0; r < os->sb[q].n; r++, k++) {
            if (os->place[k] >= tot) { st = hd_fail(HD_ERR_INTERNAL, "picture spool: record place out of range"); break; }
            memcpy(pic + es * (size_t)os->place[k], blk + es * r, es);
        }
    }
    free(blk);
    if (st) { free(pic); return st; }
    free(*seg);
    *seg = pic;
    *segcap = tot * es;
    *n = tot;
    return HD_OK;
}

/* The pixels of picture s as OpenEXR on fp (exr.c's picture writer). */
static hd_status write_exr(const hd_rcontrib_opts *o, const hd_rc_out *os, const stream *s, const hd_header *h,
                           FILE *fp)
{
    uint64_t npix = (uint64_t)o->xres * (uint64_t)o->yres, px = 0;
    hd_picture p;
    unsigned char *seg = NULL;
    size_t segcap = 0;
    hd_status st = hd_picture_alloc(&p, o->xres, o->yres);
    for (size_t b = 0, n; b < spool_nseg(os) && !st && px < npix; b++) {
        if ((st = spool_segment(os, s, b, &seg, &segcap, &n))) break;
        if (n > npix - px) n = (size_t)(npix - px);
        memcpy(p.pix + 3 * px, seg, 12 * n);
        px += n;
    }
    if (!st) st = hd_exr_write_picture(fp, stream_name(s), &p, h);
    hd_picture_free(&p);
    free(seg);
    return st;
}

/* The pixels of picture s as RGBE on fp: scanlines, or flat for a -R piece
 * (rcmerge encodes the scanlines of the joined picture). */
static hd_status write_rgbe(const hd_rcontrib_opts *o, const hd_rc_out *os, const stream *s, FILE *fp)
{
    int xr = o->xres;
    uint64_t npix = o->ranged ? o->rec_count : (uint64_t)xr * (uint64_t)o->yres, px = 0;
    unsigned char *seg = NULL, *line = o->ranged ? NULL : hd_malloc_array((size_t)xr, 4);
    size_t segcap = 0;
    hd_status st = o->ranged || line ? HD_OK : HD_ERR_NOMEM;
    int fill = 0;
    for (size_t b = 0, n; b < spool_nseg(os) && !st && px < npix; b++) {
        if ((st = spool_segment(os, s, b, &seg, &segcap, &n))) break;
        if (n > npix - px) n = (size_t)(npix - px);
        if (o->ranged) {
            if (fwrite(seg, 4, n, fp) != n) st = hd_fail(HD_ERR_IO, "%s: write failed: %s", stream_name(s), strerror(errno));
            px += n;
            continue;
        }
        for (size_t r = 0; r < n && !st; r++, px++) {
            memcpy(line + 4 * fill, seg + 4 * r, 4);
            if (++fill == xr) { st = hd_scanline_write(fp, line, xr); fill = 0; }
        }
    }
    if (!st && px < npix) st = hd_fail(HD_ERR_INTERNAL, "%s: %llu of %llu pixels", stream_name(s),
                                        (unsigned long long)px, (unsigned long long)npix);
    free(line);
    free(seg);
    return st;
}

/* Write picture stream q from the spool: opened now (file, pipe or the
 * standard output), header, resolution, pixels, committed. */
typedef struct wpjob {
    const hd_contrib *c;
    const hd_rcontrib_opts *o;
    hd_rc_out *os;
    const hd_header *hdr;
} wpjob;

static hd_status write_picture(const wpjob *wj, stream *s)
{
    const hd_rcontrib_opts *o = wj->o;
    hd_status st = HD_OK;
    if (s->name && s->name[0] == '!') st = open_pipe(s);
    else if (!s->exr) {
        st = hd_ofile_open(&s->of, s->name);
        if (st == HD_OK) s->fp = hd_ofile_fp(s->of);
    }
    hd_header h;
    hd_header_init(&h);
    if (!st && o->header) {
        st = stream_header(wj->c, o, s, wj->hdr, &h);
        if (!st && !s->exr) st = hd_rcontrib_piece_line(o, &h);
    }
    if (!st && s->exr) {   /* through a temporary, renamed when complete */
        if (!(st = hd_ofile_open(&s->of, s->name))) st = write_exr(o, wj->os, s, &h, hd_ofile_fp(s->of));
    } else if (!st) {
        hd_resolu r = {HD_RES_STANDARD, o->xres, o->yres};
        if (o->header) st = hd_picture_write_header(s->fp, &h, HD_PIC_RGBE, &r);
        if (!st) st = write_rgbe(o, wj->os, s, s->fp);
    }
    hd_header_free(&h);
    return st;
}

static hd_status write_pictures(void *ctx, size_t b, size_t e, size_t ci, int w)
{
    (void)ci; (void)w;
    wpjob *wj = ctx;
    for (size_t q = b; q < e; q++) {
        hd_status st = write_picture(wj, &wj->os->s[q]);
        if (st) return st;
    }
    return HD_OK;
}

static hd_status finish_streams(const hd_contrib *c, const hd_rcontrib_opts *o, hd_rc_out *os,
                                const hd_header *hdr, int nthreads)
{
    if (o->fout == 'c') {   /* pictures from the spool, several at a time */
        wpjob wj = {c, o, os, hdr};
        hd_status st = hd_parallel_for((size_t)os->n, 1, nthreads, write_pictures, &wj);
        if (st != HD_OK) return st;
    }
    for (int i = 0; i < os->n; i++) {
        stream *s = &os->s[i];
        if (s->w.fp) {
            hd_status st = hd_mtxwriter_end(&s->w);
            if (st != HD_OK) return hd_fail_context(st, "%s", stream_name(s));
        }
        if (s->pipe) {
            int rc = pclose(s->pipe);
            s->pipe = NULL;
            if (rc != 0) return hd_fail(HD_ERR_IO, "-o %s: the command failed (status %d)", s->name, rc);
            continue;
        }
        hd_status st = s->of ? hd_ofile_commit(s->of) : HD_OK;
        s->of = NULL;
        if (st != HD_OK) return st;
    }
    fflush(stdout);
    return HD_OK;
}

/* ---- ray input ---- */
static hd_status read_ray(hd_raysrc *src, char fin, uint64_t k, hd_vec3 *org, hd_vec3 *dir, int *eof)
{
    *eof = 0;
    if (src->gen) {
        if (k >= src->ngen) { *eof = 1; return HD_OK; }
        if (!src->gen(src->genctx, k, org, dir)) return HD_ERR_INTERNAL;
        return HD_OK;
    }
    return hd_istream_ray(src->in, fin, k, org, dir, eof);
}

/* ---- estimators that trace one ray at a time ---- */
typedef struct rayjob {
    const hd_rc_batch *b;
    uint64_t seed;
    hd_rc_ray_fn fn;
    void *ctx;
} rayjob;

static hd_status ray_units(void *ctx, size_t b, size_t e, size_t ci, int w)
{
    (void)ci;
    const rayjob *j = ctx;
    const hd_rc_batch *bt = j->b;
    for (size_t u = b; u < e; u++) {
        double *rec = bt->out + u * bt->rlen;
        memset(rec, 0, bt->rlen * sizeof *rec);
        for (int k = 0; k < bt->per; k++) {
            size_t idx = u * (size_t)bt->per + (size_t)k;
            hd_rng rng;
            hd_rng_init(&rng, j->seed, (bt->rec0 + u) * (uint64_t)bt->per + (uint64_t)k);
            hd_status st = j->fn(j->ctx, w, bt->org[idx], bt->dir[idx], &rng, bt->scale, rec);
            if (st != HD_OK) return st;
        }
    }
    return HD_OK;
}

hd_status hd_rc_per_ray(const hd_rc_batch *b, uint64_t seed, int nthreads, size_t chunk, hd_rc_ray_fn fn, void *ctx)
{
    rayjob j = {b, seed, fn, ctx};
    return hd_parallel_for(b->nrec, chunk, nthreads, ray_units, &j);
}

/* ---- the backward estimator: contrib.c's path walk per ray ---- */
typedef struct backward {
    const hd_contrib *c;
    const hd_rcontrib_opts *o;
    int nthreads;
} backward;

static hd_status back_ray(void *ctx, int worker, hd_vec3 org, hd_vec3 dir, hd_rng *rng, double scale, double *rec)
{
    (void)worker;
    const backward *bw = ctx;
    return hd_contrib_ray(bw->c, org, dir, bw->o->ld ? hd_vlen(dir) : 0, bw->o->irrad, rng, scale, rec);
}

static hd_status back_run(void *ctx, const hd_rc_batch *b)
{
    backward *bw = ctx;
    return hd_rc_per_ray(b, bw->c->o.seed, bw->nthreads, 1, back_ray, bw);
}

static void back_stats(void *ctx, FILE *f)
{
    hd_contrib_print_stats(((const backward *)ctx)->c, f);
}

static hd_status backward_estimator(const hd_contrib *c, const hd_rcontrib_opts *o, hd_rc_estimator *e)
{
    backward *bw = hd_calloc(1, sizeof *bw);
    if (!bw) return HD_ERR_NOMEM;
    bw->c = c;
    bw->o = o;
    bw->nthreads = hd_resolve_threads(o->nthreads);
    e->ctx = bw;
    e->c0_per = 64;   /* -c 0: fixed chunks of 64 rays summed */
    int per = o->accum > 0 ? o->accum : e->c0_per;
    /* records per batch: bounded memory */
    size_t batch = (size_t)(48u << 20) / (3 * (size_t)c->ncols * sizeof(double) + (size_t)per * 2 * sizeof(hd_vec3));
    e->batch = batch < 1 ? 1 : batch > 8192 ? 8192 : batch;
    e->colmajor = 0;
    e->run = back_run;
    e->stats = back_stats;
    e->free = free;
    return HD_OK;
}

/* Up to bmax records of per rays into org/dir (*nu records; *eof at the
 * end of the input; with -c 0 the last chunk is padded with null rays). */
static hd_status read_records(hd_raysrc *src, const hd_rcontrib_opts *o, int per, size_t bmax, hd_vec3 *org,
                              hd_vec3 *dir, uint64_t *nray, size_t *nu, int *eof)
{
    int partial = 0;
    *nu = 0;
    for (; *nu < bmax && !*eof; (*nu)++) {
        size_t u = *nu;
        for (int k = 0; k < per; k++) {
            size_t idx = u * (size_t)per + (size_t)k;
            hd_status st = read_ray(src, o->fin, *nray, &org[idx], &dir[idx], eof);
            if (st != HD_OK) return st;
            if (*eof) {
                if (k == 0) break;
                if (o->accum > 0)
                    return hd_fail(HD_ERR_FORMAT, "input ended inside a record: %llu rays is not a multiple of -c %d",
                                   (unsigned long long)*nray, o->accum);
                for (int z = k; z < per; z++) { org[u * per + z] = hd_v3(0, 0, 0); dir[u * per + z] = hd_v3(0, 0, 0); }
                partial = 1;
                break;
            }
            (*nray)++;
        }
        if (*eof && !partial) break;
        if (partial) { (*nu)++; break; }
    }
    return HD_OK;
}

/* The n records read (org/dir) in the order of the estimator's keys, in
 * batches; each spooled with its place (rec0: the first record's index;
 * pbase: the records spooled before). */
typedef struct rckey { uint64_t key, rec; } rckey;

static int rckey_cmp(const void *a, const void *b)
{
    const rckey *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->rec < y->rec ? -1 : x->rec > y->rec;
}

static hd_status run_coherent(const hd_rc_estimator *est, const hd_rcontrib_opts *o, hd_rc_out *os,
                              const hd_vec3 *org, const hd_vec3 *dir, size_t n, int per, uint64_t rec0,
                              uint64_t pbase, size_t rlen, double *out, const int *colstream, size_t batch,
                              hd_progress *prog)
{
    uint64_t *key = hd_malloc_array(n ? n : 1, sizeof *key), *recs = hd_malloc_array(batch, sizeof *recs);
    rckey *ord = hd_malloc_array(n ? n : 1, sizeof *ord);
    hd_vec3 *bo = hd_malloc_array(batch * (size_t)per, sizeof *bo), *bd = hd_malloc_array(batch * (size_t)per, sizeof *bd);
    hd_status st = key && recs && ord && bo && bd ? HD_OK : HD_ERR_NOMEM;
    if (!st) st = est->keys(est->ctx, org, dir, n, per, key);
    if (!st) {
        for (size_t u = 0; u < n; u++) ord[u] = (rckey){key[u], u};
        qsort(ord, n, sizeof *ord, rckey_cmp);
    }
    for (size_t b0 = 0; !st && b0 < n; b0 += batch) {
        size_t nu = n - b0 < batch ? n - b0 : batch;
        for (size_t u = 0; u < nu; u++) {
            size_t r = (size_t)ord[b0 + u].rec;
            recs[u] = pbase + r;
            memcpy(bo + u * (size_t)per, org + r * (size_t)per, (size_t)per * sizeof *bo);
            memcpy(bd + u * (size_t)per, dir + r * (size_t)per, (size_t)per * sizeof *bd);
        }
        hd_rc_batch bt = {bo, bd, nu, per, rec0, 1.0 / per, rlen, out, os, colstream, recs};
        if (!(st = est->run(est->ctx, &bt)) && !(st = write_batch(o, os, out, nu, rlen, recs)) && prog)
            hd_progress_add(prog, nu);
    }
    free(key);
    free(recs);
    free(ord);
    free(bo);
    free(bd);
    return st;
}

/* The driver's buffers for batches of `batch` records (freed first; the
 * rays only with rays set: the key order reads the rest of the input whole). */
static hd_status batch_buffers(const hd_rcontrib_opts *o, hd_rc_out *os, size_t batch, int rays, int per, size_t rlen,
                               int colmajor, hd_vec3 **org, hd_vec3 **dir, double **out)
{
    free(*org);
    free(*dir);
    free(*out);
    free(os->blk);
    *org = rays ? hd_malloc_array(batch * (size_t)per, sizeof **org) : NULL;
    *dir = rays ? hd_malloc_array(batch * (size_t)per, sizeof **dir) : NULL;
    *out = colmajor ? NULL : hd_malloc_array(batch, rlen * sizeof(double));
    os->blk = o->fout == 'c' ? hd_malloc_array(batch, os->rec_bytes ? os->rec_bytes : 1) : NULL;
    if ((rays && (!*org || !*dir)) || (!*out && !colmajor) || (o->fout == 'c' && !os->blk)) return HD_ERR_NOMEM;
    return HD_OK;
}

/* ---- the driver ---- */
#define HD_RC_COHERENT_BYTES ((uint64_t)768 << 20)   /* the rays of a run read whole for key order */
hd_status hd_rcontrib_run(const hd_contrib *c, const hd_rcontrib_opts *o, hd_raysrc *src, const hd_header *hdr)
{
    hd_rc_estimator est = {0};
    hd_status st = o->pm.file ? hd_pmap_rc_estimator(c, o, &est) : backward_estimator(c, o, &est);
    if (st != HD_OK) return st;
    hd_rc_out os = {0};
    os.spool_fd = -1;
    uint64_t expect = hd_rcontrib_nrecords(o), nout = o->ranged ? o->rec_count : expect, done = 0;
    size_t rlen = 3 * (size_t)c->ncols;
    int nthreads = hd_resolve_threads(o->nthreads);
    hd_progress *prog = NULL;
    hd_vec3 *org = NULL, *dir = NULL;
    double *out = NULL, *sum = NULL;
    int *colstream = NULL;
    if ((st = build_streams(c, &os)) != HD_OK) goto done;
    sum = o->accum == 0 ? hd_calloc(rlen, sizeof *sum) : NULL;   /* -c 0 (-r: from the files) */
    if (o->accum == 0 && !sum) { st = HD_ERR_NOMEM; goto done; }
    if ((st = open_streams(c, o, &os, hdr, nout, &done, sum)) != HD_OK) goto done;
    if (o->recover && expect && done >= expect) {   /* nothing left to do */
        for (int i = 0; i < os.n && !st; i++) {
            st = os.s[i].of ? hd_ofile_commit(os.s[i].of) : HD_OK;
            os.s[i].of = NULL;
        }
        goto done;
    }
    int per = o->accum > 0 ? o->accum : est.c0_per;
    size_t batch = est.batch;
    int colmajor = est.colmajor && o->fout == 'c';
    /* after the first batch the estimator may ask for larger batches (its
     * cache did not hold one batch's work); pictures of known size from an
     * estimator with locality keys then go on in key order (the rest of
     * the input read whole, at most HD_RC_COHERENT_BYTES of rays) */
    int ask = est.evicted && est.grow && o->accum > 0, coherent = 0, grown = 0;
    int keyorder = est.keys && o->fout == 'c' && o->accum > 0 && nout > 0 &&
                   nout * (uint64_t)per * 2 * sizeof(hd_vec3) <= HD_RC_COHERENT_BYTES;
    if ((st = batch_buffers(o, &os, batch, 1, per, rlen, colmajor, &org, &dir, &out))) goto done;
    if (colmajor) {   /* -fc: one column per stream */
        colstream = hd_malloc_array(c->ncols ? (size_t)c->ncols : 1, sizeof *colstream);
        if (!colstream) { st = HD_ERR_NOMEM; goto done; }
        for (int q = 0; q < c->ncols; q++) colstream[q] = -1;
        for (int q = 0; q < os.n; q++) colstream[os.s[q].cols[0]] = q;
    }
    if (o->report > 0 || expect > 0)
        prog = hd_progress_start(hd_progname(), o->accum == 0 ? 0 : nout, o->report, o->report > 0);
    uint64_t nray = 0, nrec = 0;
    int eof = 0;
    /* -r: the input rays of the records already written are skipped; -R:
     * those before the piece */
    uint64_t skip = o->ranged ? o->rec_first : done;
    uint64_t rend = o->ranged ? o->rec_first + o->rec_count : 0;   /* -R: end of the piece */
    for (uint64_t k = 0; k < skip * (uint64_t)per; k++) {
        hd_vec3 a, b;
        if ((st = read_ray(src, o->fin, nray, &a, &b, &eof))) goto done;
        if (eof) {
            st = hd_fail(HD_ERR_FORMAT, "%s: the input ends after %llu rays, before the %llu records %s",
                         o->ranged ? "-R" : "-r", (unsigned long long)nray, (unsigned long long)skip,
                         o->ranged ? "before the piece" : "already written");
            goto done;
        }
        nray++;
    }
    nrec = skip;
    if (prog && done) hd_progress_add(prog, done);
    while (!eof && !(rend && nrec >= rend)) {
        size_t nu = 0;
        size_t bmax = rend && rend - nrec < batch ? (size_t)(rend - nrec) : batch;
        if ((st = read_records(src, o, per, bmax, org, dir, &nray, &nu, &eof))) goto done;
        if (nu == 0) break;
        if (expect && o->accum > 0 && nrec + nu > expect) {
            st = hd_fail(HD_ERR_FORMAT, "more input rays than -x %d -y %d × -c %d allow (%llu records expected)",
                         o->xres, o->yres, o->accum, (unsigned long long)expect);
            goto done;
        }
        hd_rc_batch bt = {org, dir, nu, per, nrec, o->accum > 0 ? 1.0 / o->accum : 1.0, rlen, out, &os, colstream, NULL};
        if ((st = est.run(est.ctx, &bt)) != HD_OK) goto done;
        if (o->accum == 0) {
            for (size_t u = 0; u < nu; u++)
                for (size_t q = 0; q < rlen; q++) sum[q] += out[u * rlen + q];
        } else {
            if ((st = write_batch(o, &os, out, nu, rlen, NULL)) != HD_OK) goto done;
            if (prog) hd_progress_add(prog, nu);
        }
        nrec += nu;
        if (ask && !eof && nrec < (rend ? rend : expect ? expect : UINT64_MAX)) {   /* after the first batch */
            ask = 0;
            if (est.batch_big && est.evicted(est.ctx)) {
                if ((st = est.grow(est.ctx))) goto done;
                batch = est.batch_big;
                grown = 1;
                if ((st = batch_buffers(o, &os, batch, !keyorder, per, rlen, colmajor, &org, &dir, &out))) goto done;
                if ((coherent = keyorder)) break;
            }
        }
    }
    if (coherent) {   /* the rest of the input, then its records in key order */
        uint64_t left = (rend ? rend : expect) - nrec;
        size_t nu = 0;
        free(org);
        free(dir);
        org = hd_malloc_array((left ? (size_t)left : 1) * (size_t)per, sizeof *org);
        dir = hd_malloc_array((left ? (size_t)left : 1) * (size_t)per, sizeof *dir);
        if (!org || !dir) { st = HD_ERR_NOMEM; goto done; }
        if ((st = read_records(src, o, per, (size_t)left, org, dir, &nray, &nu, &eof))) goto done;
        if (!eof && !rend && nu == left) {   /* input beyond the pictures */
            hd_vec3 a, b;
            if ((st = read_ray(src, o->fin, nray, &a, &b, &eof))) goto done;
            if (!eof) nu++;
        }
        if (nu > left) {
            st = hd_fail(HD_ERR_FORMAT, "more input rays than -x %d -y %d × -c %d allow (%llu records expected)",
                         o->xres, o->yres, o->accum, (unsigned long long)expect);
            goto done;
        }
        if ((st = run_coherent(&est, o, &os, org, dir, nu, per, nrec, nrec - skip, rlen, out, colstream, batch, prog)))
            goto done;
        nrec += nu;
    }
    if (o->accum == 0) {
        if ((st = write_batch(o, &os, sum, 1, rlen, NULL)) != HD_OK) goto done;
        nrec = 1;
    } else if (rend && nrec != rend) {
        st = hd_fail(HD_ERR_FORMAT, "-R %llu %llu: the input ends after %llu rays, inside the piece",
                     (unsigned long long)o->rec_first, (unsigned long long)o->rec_count, (unsigned long long)nray);
        goto done;
    } else if (!rend && expect && nrec != expect) {
        st = hd_fail(HD_ERR_FORMAT, "input has %llu rays but -x %d -y %d with -c %d needs %llu",
                     (unsigned long long)nray, o->xres, o->yres, o->accum,
                     (unsigned long long)(expect * (uint64_t)o->accum));
        goto done;
    } else if (nrec == 0) {
        hd_warn("no input rays");
    }
    if (prog) hd_progress_finish(prog);
    prog = NULL;
    st = finish_streams(c, o, &os, hdr, nthreads);
    if (!st && c->stats && est.stats) est.stats(est.ctx, stderr);
    if (!st && c->stats && grown)
        fprintf(stderr, "%s: stats: the first batch overflowed the cache: then batches of %zu records%s\n", hd_progname(),
                batch, coherent ? ", pictures in the order of their lookup points" : "");
done:
    if (prog) hd_progress_finish(prog);
    free(org);
    free(dir);
    free(out);
    free(sum);
    free(colstream);
    free_streams(&os, st != HD_OK);
    if (est.free) est.free(est.ctx);
    return st;
}

/* heliodon — rcontrib driver: rays in, records out to the -o streams. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <unistd.h>

#include "heliodon/contrib.h"
#include "heliodon/matrix.h"
#include "heliodon/parallel.h"
#include "progress.h"
#include "heliodon/rcmerge.h"

hd_status hd_contrib_write_scanlines(FILE *fp, const float *pix, int xres, int yres);
hd_status hd_contrib_write_flat(FILE *fp, const float *pix, uint64_t n);

typedef struct stream {
    char *name;           /* NULL = standard output */
    int *cols;            /* record columns routed here */
    int ncols, capcols;
    int mod;              /* modifier of the first column */
    int multimod;         /* columns from more than one modifier */
    int has_s, has_d;
    long bin;             /* BIN= value for %d streams */
    hd_ofile *of;
    FILE *fp;
    FILE *pipe;           /* "!command" output */
    float *pic;           /* picture output: all pixels */
    hd_mtxwriter w;       /* matrix output (-fa, -ff, -fd) */
} stream;

typedef struct outset {
    stream *s;
    int n;
} outset;

static stream *find_stream(outset *o, const char *name)
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

static void free_streams(outset *o, int abort)
{
    for (int i = 0; i < o->n; i++) {
        stream *s = &o->s[i];
        if (s->of && abort) hd_ofile_abort(s->of);
        if (s->pipe) pclose(s->pipe);
        free(s->name);
        free(s->cols);
        free(s->pic);
    }
    free(o->s);
    o->s = NULL;
    o->n = 0;
}

static hd_status build_streams(const hd_contrib *c, outset *o)
{
    char name[4096];
    for (int m = 0; m < c->nmods; m++) {
        const hd_cmod *cm = &c->mods[m];
        int kind = cm->outspec ? hd_pattern_kind(cm->outspec) : 0;
        if (kind < 0) return HD_ERR_USAGE;
        if (kind == 0 || kind == 2) {
            const char *nm = cm->outspec;
            if (kind == 2) {
                hd_status st = hd_pattern_format(name, sizeof name, cm->outspec, cm->name, 0);
                if (st != HD_OK) return st;
                nm = name;
            }
            stream *s = find_stream(o, nm);
            if (!s) return HD_ERR_NOMEM;
            s->has_s = kind == 2;
            for (int b = 0; b < cm->bin.nbins; b++)
                if (add_col(s, m, cm->first + b) != HD_OK) return HD_ERR_NOMEM;
        } else {
            for (int b = 0; b < cm->bin.nbins; b++) {
                hd_status st = hd_pattern_format(name, sizeof name, cm->outspec, kind & 2 ? cm->name : NULL, b);
                if (st != HD_OK) return st;
                stream *s = find_stream(o, name);
                if (!s) return HD_ERR_NOMEM;
                s->has_s = (kind & 2) != 0;
                s->has_d = 1;
                s->bin = b;
                if (add_col(s, m, cm->first + b) != HD_OK) return HD_ERR_NOMEM;
            }
        }
    }
    return HD_OK;
}

static hd_mtxfmt out_fmt(char f)
{
    return f == 'f' ? HD_MTX_FLOAT : f == 'd' ? HD_MTX_DOUBLE : f == 'a' ? HD_MTX_ASCII : HD_MTX_RGBE;
}

static const char *stream_name(const stream *s) { return s->name ? s->name : "standard output"; }

/* Sizes checked; with -r the streams' files from the earlier run (*done
 * records kept) */
static hd_status resume_streams(const hd_rcontrib_opts *o, outset *os, uint64_t expect, uint64_t *done,
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
    if (!st) st = hd_rcontrib_check_size(o, r, os->n, expect, *done, 1);
    for (int i = 0; i < os->n; i++) {
        os->s[i].of = r[i].of;
        keep_header[i] = (unsigned char)r[i].has_header;
    }
    free(r);
    return st;
}

static hd_status open_streams_k(const hd_contrib *c, const hd_rcontrib_opts *o, outset *os,
                                const hd_header *hdr, uint64_t nrec, const unsigned char *keep)
{
    for (int i = 0; i < os->n; i++) {
        stream *s = &os->s[i];
        int piped = s->name && s->name[0] == '!';
        if (s->of) {   /* resumed */
            s->fp = hd_ofile_fp(s->of);
            if (keep[i] && o->fout == 'c') continue;
        } else if (s->name && !piped && !o->force && !o->recover && access(s->name, F_OK) == 0)
            return hd_fail(HD_ERR_IO, "%s: output file exists (use -fo to overwrite)", s->name);
        if (o->fout == 'c' && s->ncols != 1)
            return hd_fail(HD_ERR_USAGE, "%s: picture output (-f?c) needs one value per stream, this one has %d "
                           "(use an -o pattern with %%d per bin)", s->name ? s->name : "standard output", s->ncols);
        hd_status st = HD_OK;
        if (s->of) {
        } else if (piped) {
            fflush(stdout);
            signal(SIGPIPE, SIG_IGN);   /* a command that exits early gives a write error */
            s->pipe = popen(s->name + 1, "w");
            if (!s->pipe) return hd_fail(HD_ERR_IO, "-o %s: cannot start the command", s->name);
            s->fp = s->pipe;
        } else {
            st = hd_ofile_open(&s->of, s->name);
            if (st != HD_OK) return st;
            if (o->fout != 'c' && o->accum > 0) hd_ofile_keep_on_signal(s->of);   /* -r can continue it */
            s->fp = hd_ofile_fp(s->of);
        }
        if (o->fout == 'c') {
            s->pic = hd_calloc((size_t)nrec * 3, sizeof *s->pic);
            if (!s->pic) return HD_ERR_NOMEM;
        }
        /* NCOMP, MODIFIER, BIN, NROWS, NCOLS in rcontrib's order; the
         * writer adds BigEndian and FORMAT */
        int header = o->header && !keep[i];
        hd_header h;
        hd_header_init(&h);
        if (header) {
            st = hd_header_copy(&h, hdr);
            if (st == HD_OK) st = hd_header_append(&h, "NCOMP=3");
            if (st == HD_OK && (s->has_s || s->ncols == 1) && !s->multimod)
                st = hd_header_appendf(&h, "MODIFIER=%s", c->mods[s->mod].name);
            if (st == HD_OK && s->has_d) st = hd_header_appendf(&h, "BIN=%ld", s->bin);
            if (st == HD_OK && o->yres > 0)
                st = hd_header_appendf(&h, "NROWS=%ld", (long)o->yres * (o->xres > 0 ? o->xres : 1));
            if (st == HD_OK && (o->xres <= 0 || s->ncols > 1)) st = hd_header_appendf(&h, "NCOLS=%d", s->ncols);
            if (st == HD_OK) st = hd_rcontrib_piece_line(o, &h);   /* -R: a piece */
        }
        if (o->fout == 'c') {   /* a picture: its header now, resolution and pixels at the end */
            size_t nw = 0;
            if (st == HD_OK && header) st = hd_header_write(s->fp, &h, &nw);
            if (st == HD_OK && header) st = hd_header_write_format(s->fp, "32-bit_rle_rgbe", nw);
            hd_header_free(&h);
            if (st != HD_OK) return st;
            continue;
        }
        int flags = header ? HD_MTXW_HEADER | (o->xres > 0 && s->ncols == 1 ? HD_MTXW_NO_NCOLS : 0) : 0;
        /* rows not counted by the writer: -r continues a partial file */
        if (st == HD_OK) st = hd_mtxwriter_begin(&s->w, s->fp, &h, flags, out_fmt(o->fout), 0, s->ncols, 3);
        hd_header_free(&h);
        if (st != HD_OK) return hd_fail_context(st, "%s", stream_name(s));
        s->w.ascii_style = HD_MTXASCII_RCONTRIB;
        if (header && s->ncols == 1 && o->xres > 0 && o->yres > 0)
            fprintf(s->fp, "-Y %8d +X %8d\n", o->yres, o->xres);
    }
    return HD_OK;
}

/* Open (or with -r take up) every stream and write the headers; *done:
 * records already there (-r); with -c 0 and -r, the sums already written
 * are added into sum. */
static hd_status open_streams(const hd_contrib *c, const hd_rcontrib_opts *o, outset *os,
                              const hd_header *hdr, uint64_t nrec, uint64_t *done, double *sum)
{
    *done = 0;
    unsigned char *keep = hd_calloc((size_t)os->n + 1, 1);
    if (!keep) return HD_ERR_NOMEM;
    hd_status st = resume_streams(o, os, nrec, done, keep, sum);
    if (!st && !(o->recover && nrec && *done >= nrec)) st = open_streams_k(c, o, os, hdr, nrec, keep);
    free(keep);
    return st;
}

static hd_status write_record(const hd_rcontrib_opts *o, outset *os, const double *rec, uint64_t r)
{
    for (int i = 0; i < os->n; i++) {
        stream *s = &os->s[i];
        if (o->fout == 'c') {
            const double *v = rec + 3 * (size_t)s->cols[0];
            uint64_t pr = o->ranged ? r - o->rec_first : r;   /* a piece holds its records only */
            for (int k = 0; k < 3; k++) s->pic[3 * pr + k] = (float)v[k];
            continue;
        }
        hd_status st = hd_mtxwriter_row_cols(&s->w, rec, s->cols);
        if (st) return hd_fail_context(st, "%s", stream_name(s));
    }
    return HD_OK;
}

static hd_status finish_streams(const hd_rcontrib_opts *o, outset *os)
{
    for (int i = 0; i < os->n; i++) {
        stream *s = &os->s[i];
        if (o->fout == 'c') {
            if (o->header) fprintf(s->fp, "-Y %8d +X %8d\n", o->yres, o->xres);   /* as Radiance pads it */
            hd_status st = o->ranged ? hd_contrib_write_flat(s->fp, s->pic, o->rec_count)
                                     : hd_contrib_write_scanlines(s->fp, s->pic, o->xres, o->yres);
            if (st != HD_OK) return st;
        } else if (s->w.fp) {
            hd_status st = hd_mtxwriter_end(&s->w);
            if (st != HD_OK) return hd_fail_context(st, "%s", stream_name(s));
        }
        if (s->pipe) {
            int rc = pclose(s->pipe);
            s->pipe = NULL;
            if (rc != 0) return hd_fail(HD_ERR_IO, "-o %s: the command failed (status %d)", s->name, rc);
            continue;
        }
        hd_status st = hd_ofile_commit(s->of);
        s->of = NULL;
        if (st != HD_OK) return st;
    }
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
    double v[6];
    if (fin == 'a') {
        for (int i = 0; i < 6; i++) {
            int e = 0;
            hd_status st = hd_istream_real(src->in, &v[i], &e);
            if (st != HD_OK) return st;
            if (e) {
                if (i == 0) { *eof = 1; return HD_OK; }
                return hd_fail(HD_ERR_FORMAT, "%s: line %lu: ray %llu is incomplete (expected 6 numbers)",
                               hd_istream_name(src->in), hd_istream_lineno(src->in), (unsigned long long)k + 1);
            }
        }
    } else {
        size_t sz = fin == 'f' ? 4 : 8;
        unsigned char buf[48];
        size_t got = hd_istream_read(src->in, buf, 6 * sz);
        if (got == 0) { *eof = 1; return HD_OK; }
        if (got < 6 * sz)
            return hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: ray %llu is truncated (%zu of %zu bytes)",
                           hd_istream_name(src->in), (unsigned long long)hd_istream_offset(src->in),
                           (unsigned long long)k + 1, got, 6 * sz);
        for (int i = 0; i < 6; i++) {
            if (sz == 4) { float f; memcpy(&f, buf + 4 * i, 4); v[i] = f; }
            else memcpy(&v[i], buf + 8 * i, 8);
        }
    }
    for (int i = 0; i < 6; i++)
        if (!isfinite(v[i]))
            return hd_fail(HD_ERR_FORMAT, "%s: ray %llu: value is not finite", hd_istream_name(src->in),
                           (unsigned long long)k + 1);
    *org = hd_v3(v[0], v[1], v[2]);
    *dir = hd_v3(v[3], v[4], v[5]);
    return HD_OK;
}

typedef struct job {
    const hd_contrib *c;
    const hd_rcontrib_opts *o;
    const hd_vec3 *org, *dir;
    uint64_t ray0;        /* global index of the first ray of the batch */
    int per;              /* rays per unit */
    double scale;
    size_t rlen;          /* doubles per record */
    double *out;          /* per unit records */
    hd_progress *prog;
} job;

static hd_status run_units(void *ctx, size_t b, size_t e, size_t ci, int worker)
{
    (void)ci; (void)worker;
    job *j = ctx;
    for (size_t u = b; u < e; u++) {
        double *rec = j->out + u * j->rlen;
        memset(rec, 0, j->rlen * sizeof *rec);
        for (int k = 0; k < j->per; k++) {
            size_t idx = u * (size_t)j->per + (size_t)k;
            hd_rng rng;
            hd_rng_init(&rng, j->c->o.seed, j->ray0 + idx);
            double tmax = j->o->ld ? hd_vlen(j->dir[idx]) : 0;
            hd_contrib_ray(j->c, j->org[idx], j->dir[idx], tmax, j->o->irrad, &rng, j->scale, rec);
        }
        if (j->prog) hd_progress_add(j->prog, 1);
    }
    return HD_OK;
}

hd_status hd_rcontrib_run(const hd_contrib *c, const hd_rcontrib_opts *o, hd_raysrc *src, const hd_header *hdr)
{
    outset os = {NULL, 0};
    hd_status st = build_streams(c, &os);
    if (st != HD_OK) { free_streams(&os, 1); return st; }
    uint64_t expect = hd_rcontrib_nrecords(o);
    uint64_t done = 0;
    size_t rlen = 3 * (size_t)c->ncols;
    double *sum = o->accum == 0 ? hd_calloc(rlen, sizeof *sum) : NULL;   /* -c 0 (-r: from the files) */
    if (o->accum == 0 && !sum) { free_streams(&os, 1); return HD_ERR_NOMEM; }
    st = open_streams(c, o, &os, hdr, o->ranged ? o->rec_count : expect, &done, sum);
    if (st != HD_OK) { free(sum); free_streams(&os, 1); return st; }
    if (o->recover && expect && done >= expect) {   /* nothing left to do */
        for (int i = 0; i < os.n && !st; i++) {
            st = os.s[i].of ? hd_ofile_commit(os.s[i].of) : HD_OK;
            os.s[i].of = NULL;
        }
        free(sum);
        free_streams(&os, st != HD_OK);
        return st;
    }
    int nthreads = hd_resolve_threads(o->nthreads);
    hd_progress *prog = NULL;
    int per = o->accum > 0 ? o->accum : 64;   /* -c 0: fixed chunks of 64 rays summed */
    /* records per batch: bounded memory */
    size_t batch = (size_t)(48u << 20) / (rlen * sizeof(double) + (size_t)per * 2 * sizeof(hd_vec3));
    if (batch < 1) batch = 1;
    if (batch > 8192) batch = 8192;
    hd_vec3 *org = hd_malloc_array(batch * (size_t)per, sizeof *org);
    hd_vec3 *dir = hd_malloc_array(batch * (size_t)per, sizeof *dir);
    double *out = hd_malloc_array(batch, rlen * sizeof(double));
    if (!org || !dir || !out) { st = HD_ERR_NOMEM; goto done; }
    if (o->report > 0 || expect > 0)
        prog = hd_progress_start(hd_progname(), o->accum == 0 ? 0 : o->ranged ? o->rec_count : expect, o->report,
                                 o->report > 0);
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
        int partial = 0;
        size_t bmax = rend && rend - nrec < batch ? (size_t)(rend - nrec) : batch;
        for (; nu < bmax && !eof; nu++) {
            for (int k = 0; k < per; k++) {
                size_t idx = nu * (size_t)per + (size_t)k;
                st = read_ray(src, o->fin, nray, &org[idx], &dir[idx], &eof);
                if (st != HD_OK) goto done;
                if (eof) {
                    if (k == 0) break;
                    if (o->accum > 0) {
                        st = hd_fail(HD_ERR_FORMAT, "input ended inside a record: %llu rays is not a multiple of -c %d",
                                     (unsigned long long)nray, o->accum);
                        goto done;
                    }
                    for (int z = k; z < per; z++) { org[nu * per + z] = hd_v3(0, 0, 0); dir[nu * per + z] = hd_v3(0, 0, 0); }
                    partial = 1;
                    break;
                }
                nray++;
            }
            if (eof && !partial) break;
            if (partial) { nu++; break; }
        }
        if (nu == 0) break;
        if (expect && o->accum > 0 && nrec + nu > expect) {
            st = hd_fail(HD_ERR_FORMAT, "more input rays than -x %d -y %d × -c %d allow (%llu records expected)",
                         o->xres, o->yres, o->accum, (unsigned long long)expect);
            goto done;
        }
        /* ray0: global index of the first ray in this batch */
        job j = {c, o, org, dir, nrec * (uint64_t)per, per,
                 o->accum > 0 ? 1.0 / o->accum : 1.0, rlen, out, o->accum > 0 ? prog : NULL};
        st = hd_parallel_for(nu, 1, nthreads, run_units, &j);
        if (st != HD_OK) goto done;
        for (size_t u = 0; u < nu; u++) {
            if (o->accum == 0) {
                for (size_t q = 0; q < rlen; q++) sum[q] += out[u * rlen + q];
            } else {
                st = write_record(o, &os, out + u * rlen, nrec + u);
                if (st != HD_OK) goto done;
            }
        }
        nrec += nu;
    }
    if (o->accum == 0) {
        st = write_record(o, &os, sum, 0);
        if (st != HD_OK) goto done;
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
    st = finish_streams(o, &os);
done:
    if (prog) hd_progress_finish(prog);
    free(org);
    free(dir);
    free(out);
    free(sum);
    free_streams(&os, st != HD_OK);
    return st;
}

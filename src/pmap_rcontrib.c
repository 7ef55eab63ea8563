/* heliodon — rcontrib -ap: photon-map contributions (see pmap_rcontrib.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/material.h"
#include "heliodon/parallel.h"
#include "heliodon/picture.h"
#include "heliodon/pmap.h"
#include "heliodon/pmap_rcontrib.h"
#include "heliodon/rng.h"
#include "heliodon/trace.h"

static void drop(int *argc, char **argv, int i, int n)
{
    for (int k = i; k + n <= *argc; k++) argv[k] = argv[k + n];
    *argc -= n;
}

static int is_number(const char *s)
{
    double v;
    return s && hd_parse_double(s, &v) == 0;
}

hd_status hd_pmap_rc_extract(int *argc, char **argv, hd_pmap_rc_opts *po)
{
    memset(po, 0, sizeof *po);
    po->cache = 4000000;
    po->exact_direct = 1;
    static char one[] = "1";
    for (int i = 1; i < *argc;) {
        const char *a = argv[i];
        if (!strcmp(a, "-ap")) {
            if (i + 1 >= *argc) return hd_fail(HD_ERR_USAGE, "-ap: expected a photon map file");
            po->file = argv[i + 1];
            int n = 2;
            po->bw = 0;
            if (i + 2 < *argc && is_number(argv[i + 2])) {
                hd_parse_double(argv[i + 2], &po->bw);
                n = 3;
                if (i + 3 < *argc && is_number(argv[i + 3]) && argv[i + 3][0] != '-') {
                    hd_parse_double(argv[i + 3], &po->bw2);
                    n = 4;
                }
            }
            drop(argc, argv, i, n);
        } else if (!strcmp(a, "-aC") || !strcmp(a, "-ac") || !strcmp(a, "-am")) {
            if (i + 1 >= *argc) return hd_fail(HD_ERR_USAGE, "%s: expected a value", a);
            if (!strcmp(a, "-aC")) {
                if (hd_parse_count(argv[i + 1], &po->cache))
                    return hd_fail(HD_ERR_USAGE, "-aC %s: expected a photon count (k/m/g suffixes)", argv[i + 1]);
            } else if (hd_parse_double(argv[i + 1], !strcmp(a, "-ac") ? &po->ac : &po->am)) {
                return hd_fail(HD_ERR_USAGE, "%s %s: expected a number", a, argv[i + 1]);
            }
            drop(argc, argv, i, 2);
        } else if (!strncmp(a, "-apd", 4) && (!a[4] || ((a[4] == '+' || a[4] == '-') && !a[5]))) {
            po->exact_direct = a[4] != '-';
            drop(argc, argv, i, 1);
        } else if (!strcmp(a, "-apR")) {
            long r0, nr;
            if (i + 2 >= *argc || hd_parse_long(argv[i + 1], &r0) || hd_parse_long(argv[i + 2], &nr) || r0 < 0 ||
                nr < 0)
                return hd_fail(HD_ERR_USAGE, "-apR: expected first record and record count (>= 0)");
            po->row0 = (uint64_t)r0;
            po->nrows = (uint64_t)nr;
            drop(argc, argv, i, 3);
        } else if (!strcmp(a, "-ab") && i + 1 < *argc) {
            long v;
            if (!hd_parse_long(argv[i + 1], &v)) {
                po->ab = (int)v;
                po->ab_given = 1;
                if (v < 0) argv[i + 1] = one;
            }
            i += 2;
        } else {
            i++;
        }
    }
    return HD_OK;
}

/* ---- per-modifier source lists and bins ---- */
typedef struct rcmod {
    uint32_t *src;
    int nsrc;
} rcmod;

typedef struct binctx { const hd_binfn *b; } binctx;
static int binfn_cb(void *ctx, uint32_t src, hd_vec3 from)
{
    (void)src;
    const binctx *bc = ctx;
    int b = hd_binfn_eval(bc->b, from, 0.5, 0.5);
    return b >= 0 && b < bc->b->nbins ? b : -1;
}

typedef struct rcjob {
    const hd_contrib *c;
    const hd_rcontrib_opts *o;
    const hd_pmap_rc_opts *po;
    hd_pmap *m;
    rcmod *mods;
    hd_pmap_lookup **lk;      /* per worker */
    double **tmp;             /* per worker, 3 * max bins */
    const hd_vec3 *org, *dir;
    uint64_t rec0;            /* global record index of the first record of the batch */
    int per;
    size_t rlen;
    double *out;
} rcjob;

/* Irradiance coefficients at p, n into rec (scaled by f[3] per channel). */
static hd_status gather_point(rcjob *j, int w, hd_vec3 p, hd_vec3 n, const double f[3], hd_rng *rng, double *rec)
{
    const hd_contrib *c = j->c;
    double *tmp = j->tmp[w];
    for (int mi = 0; mi < c->nmods; mi++) {
        const hd_cmod *cm = &c->mods[mi];
        int nb = cm->bin.nbins > 0 ? cm->bin.nbins : 1;
        binctx bc = {&cm->bin};
        for (int k = 0; k < j->mods[mi].nsrc; k++) {
            uint32_t s = j->mods[mi].src[k];
            const hd_pmap_source *S = hd_pmap_get_source(j->m, s);
            memset(tmp, 0, sizeof(double) * 3 * (size_t)nb);
            hd_status st;
            if (j->po->ab < 0) {
                st = hd_pmap_irradiance(j->lk[w], s, p, n, tmp, binfn_cb, &bc);
            } else {
                double e[3];
                st = hd_pmap_final_gather(j->lk[w], c->ts, s, p, n, c->o.ad, rng, e);
                int b = binfn_cb(&bc, s, S->dir);
                if (!st && b >= 0) for (int q = 0; q < 3; q++) tmp[3 * b + q] += e[q];
            }
            if (st) return st;
            for (int b = 0; b < nb; b++)
                for (int q = 0; q < 3; q++) {
                    double v = tmp[3 * b + q] * f[q];
                    if (c->vflag) v *= S->radiance[q];
                    rec[3 * ((size_t)cm->first + (size_t)b) + q] += v;
                }
        }
    }
    return HD_OK;
}

static hd_status trace_ray(rcjob *j, int w, hd_vec3 org, hd_vec3 dir, double scale, hd_rng *rng, double *rec)
{
    const hd_contrib *c = j->c;
    double f[3] = {scale, scale, scale};
    if (j->o->irrad == 1) return gather_point(j, w, org, hd_vnorm(dir), f, rng, rec);
    const hd_tscene *ts = c->ts;
    double eps = hd_tscene_eps(ts), tmin = 0;
    hd_vec3 d = hd_vnorm(dir);
    for (int guard = 0; guard < 100; guard++) {
        hd_hit h;
        if (!hd_tscene_intersect(ts, org, d, tmin, 0, &h)) return HD_OK;
        const hd_tmat *m = hd_tscene_material(ts, hd_tscene_surface(ts, h.surf)->mat);
        while (m && m->type == HD_MAT_ILLUM) m = m->alt >= 0 ? hd_tscene_material(ts, m->alt) : NULL;
        if (!m || m->type == HD_MAT_INVISIBLE) { org = h.p; tmin = eps; continue; }
        double cosi = fabs(hd_vdot(d, h.n));
        if (m->type == HD_MAT_GLASS) {
            double R[3], T[3];
            hd_glass_coeffs(m->color, m->rindex, cosi, R, T);
            for (int k = 0; k < 3; k++) f[k] *= T[k];
            org = h.p;
            tmin = eps;
            continue;
        }
        if (m->type != HD_MAT_PLASTIC && m->type != HD_MAT_METAL && m->type != HD_MAT_TRANS) return HD_OK;
        hd_vec3 nf = hd_vdot(d, h.n) < 0 ? h.n : hd_vneg(h.n);
        if (j->o->irrad == 0) {
            hd_nshade ns;
            hd_normal_coeffs(m, cosi, &ns);
            for (int k = 0; k < 3; k++) f[k] *= ns.rdiff[k] / HD_PI;
        }
        return gather_point(j, w, h.p, nf, f, rng, rec);
    }
    return HD_OK;
}

static hd_status rc_units(void *ctx, size_t b, size_t e, size_t ci, int w)
{
    (void)ci;
    rcjob *j = ctx;
    for (size_t u = b; u < e; u++) {
        double *rec = j->out + u * j->rlen;
        memset(rec, 0, j->rlen * sizeof *rec);
        for (int k = 0; k < j->per; k++) {
            size_t idx = u * (size_t)j->per + (size_t)k;
            hd_rng rng;
            hd_rng_init(&rng, j->c->o.seed, (j->rec0 + u) * (uint64_t)j->per + (uint64_t)k);
            hd_status st = trace_ray(j, w, j->org[idx], j->dir[idx], 1.0 / j->per, &rng, rec);
            if (st) return st;
        }
    }
    return HD_OK;
}

/* ---- output streams ---- */
typedef struct ostream {
    const char *spec;
    char name[1024];
    hd_ofile *of;
    FILE *fp;
    int *cols, ncols;
    hd_picture pic;
} ostream;

static hd_status read_ray(hd_raysrc *src, char fin, hd_vec3 *org, hd_vec3 *dir, int *eof)
{
    double v[6];
    *eof = 0;
    if (fin == 'a') {
        for (int k = 0; k < 6; k++) {
            int e = 0;
            hd_status st = hd_istream_real(src->in, &v[k], &e);
            if (st) return st;
            if (e) {
                if (k) return hd_fail(HD_ERR_FORMAT, "%s: incomplete ray at the end", hd_istream_name(src->in));
                *eof = 1;
                return HD_OK;
            }
        }
    } else if (fin == 'f') {
        float f[6];
        size_t n = hd_istream_read(src->in, f, sizeof f);
        if (n == 0) { *eof = 1; return HD_OK; }
        if (n != sizeof f) return hd_fail(HD_ERR_FORMAT, "%s: incomplete float ray", hd_istream_name(src->in));
        for (int k = 0; k < 6; k++) v[k] = f[k];
    } else {
        size_t n = hd_istream_read(src->in, v, sizeof v);
        if (n == 0) { *eof = 1; return HD_OK; }
        if (n != sizeof v) return hd_fail(HD_ERR_FORMAT, "%s: incomplete double ray", hd_istream_name(src->in));
    }
    *org = hd_v3(v[0], v[1], v[2]);
    *dir = hd_v3(v[3], v[4], v[5]);
    return HD_OK;
}

hd_status hd_pmap_rc_run(const hd_contrib *c, const hd_rcontrib_opts *o, hd_raysrc *src, const hd_header *hdr,
                         const hd_pmap_rc_opts *po)
{
    if (!src->in) return hd_fail(HD_ERR_UNSUPPORTED, "photon-map mode reads rays from a stream only");
    hd_pmap *m;
    hd_status st = hd_pmap_open(&m, po->file, po->cache);
    if (st) return st;
    const hd_pmap_info *I = hd_pmap_get_info(m);
    rcmod *mods = hd_calloc((size_t)c->nmods, sizeof *mods);
    ostream *os = NULL;
    int nos = 0;
    rcjob j;
    memset(&j, 0, sizeof j);
    int nth = hd_resolve_threads(o->nthreads);
    if (!mods) { hd_pmap_close(m); return HD_ERR_NOMEM; }
    uint32_t nactive = 0;
    int maxbins = 1;
    for (int mi = 0; mi < c->nmods; mi++) {
        mods[mi].src = hd_calloc(I->nsources ? I->nsources : 1, sizeof(uint32_t));
        if (!mods[mi].src) { st = HD_ERR_NOMEM; goto done; }
        for (uint32_t s = 0; s < I->nsources; s++)
            if (!strcmp(hd_pmap_get_source(m, s)->modifier, c->mods[mi].name)) {
                mods[mi].src[mods[mi].nsrc++] = s;
                if (hd_pmap_get_source(m, s)->stored) nactive++;
            }
        if (!mods[mi].nsrc) {
            st = hd_fail(HD_ERR_USAGE, "%s: modifier %s is not a light source of the photon map", po->file,
                         c->mods[mi].name);
            goto done;
        }
        if (c->mods[mi].bin.nbins > maxbins) maxbins = c->mods[mi].bin.nbins;
    }
    double bw = po->bw > 0 ? po->bw : 40;
    if (!(po->bw > 0)) hd_warn("-ap %s: no bandwidth given, using 40", po->file);
    if (po->bw2 > 0) hd_warn("-ap second bandwidth %g ignored: heliodon uses per-source neighbours", po->bw2);
    if (po->ac > 0) hd_warn("-ac %g ignored: the page size is fixed when the map is built (mkpmap -apZ)", po->ac);
    hd_pmap_lookup_opts lo;
    hd_pmap_lookup_opts_init(&lo);
    uint32_t k = (uint32_t)ceil(bw / (nactive ? nactive : 1));
    lo.k = k < 2 ? 2 : k;
    lo.max_radius = po->am;
    lo.direct_scene = po->exact_direct ? c->ts : NULL;
    j.lk = hd_calloc((size_t)nth, sizeof *j.lk);
    j.tmp = hd_calloc((size_t)nth, sizeof *j.tmp);
    if (!j.lk || !j.tmp) { st = HD_ERR_NOMEM; goto done; }
    for (int w = 0; w < nth; w++) {
        if ((st = hd_pmap_lookup_create(m, &lo, &j.lk[w]))) goto done;
        j.tmp[w] = hd_malloc_array((size_t)maxbins * 3, sizeof(double));
        if (!j.tmp[w]) { st = HD_ERR_NOMEM; goto done; }
    }
    /* streams */
    os = hd_calloc((size_t)c->ncols + 1, sizeof *os);
    if (!os) { st = HD_ERR_NOMEM; goto done; }
    for (int mi = 0; mi < c->nmods; mi++) {
        const hd_cmod *cm = &c->mods[mi];
        int nb = cm->bin.nbins > 0 ? cm->bin.nbins : 1;
        char name[1024] = "";
        if (cm->outspec) {
            int kind = hd_pattern_kind(cm->outspec);
            if (kind < 0) { st = HD_ERR_USAGE; goto done; }
            if (kind & 1) {
                st = hd_fail(HD_ERR_UNSUPPORTED, "-o %s: per-bin output files are not supported with -ap", cm->outspec);
                goto done;
            }
            if ((st = hd_pattern_format(name, sizeof name, cm->outspec, cm->name, 0))) goto done;
        }
        ostream *s = NULL;
        for (int q = 0; q < nos; q++) if (!strcmp(os[q].name, name)) s = &os[q];
        if (!s) {
            s = &os[nos++];
            hd_strlcpy(s->name, name, sizeof s->name);
            s->cols = hd_calloc((size_t)c->ncols, sizeof(int));
            if (!s->cols) { st = HD_ERR_NOMEM; goto done; }
        }
        for (int b = 0; b < nb; b++) s->cols[s->ncols++] = cm->first + b;
    }
    uint64_t expect = o->yres > 0 ? (uint64_t)o->yres * (uint64_t)(o->xres > 0 ? o->xres : 1) : 0;
    uint64_t nout = po->nrows ? po->nrows : (expect > po->row0 ? expect - po->row0 : 0);
    for (int q = 0; q < nos; q++) {
        ostream *s = &os[q];
        if (o->fout == 'c') {
            if (s->ncols != 1) {
                st = hd_fail(HD_ERR_UNSUPPORTED, "-fc: one picture per modifier needs one bin (got %d)", s->ncols);
                goto done;
            }
            if (o->xres <= 0 || o->yres <= 0) { st = hd_fail(HD_ERR_USAGE, "-fc needs -x and -y"); goto done; }
            if ((st = hd_picture_alloc(&s->pic, o->xres, o->yres))) goto done;
            continue;
        }
        if (!s->name[0]) s->fp = stdout;
        else {
            if (!o->force) {
                FILE *t = fopen(s->name, "r");
                if (t) { fclose(t); st = hd_fail(HD_ERR_USAGE, "%s: file exists (use -fo)", s->name); goto done; }
            }
            if ((st = hd_ofile_open(&s->of, s->name))) goto done;
            s->fp = hd_ofile_fp(s->of);
        }
        if (o->header) {
            size_t nw = 0;
            hd_header h;
            hd_header_init(&h);
            if ((st = hd_header_copy(&h, hdr))) goto done;
            hd_header_appendf(&h, "NCOMP=3");
            if (nout) hd_header_appendf(&h, "NROWS=%llu", (unsigned long long)nout);
            hd_header_appendf(&h, "NCOLS=%d", s->ncols);
            st = hd_header_write(s->fp, &h, &nw);
            hd_header_free(&h);
            if (st) goto done;
            if ((st = hd_header_write_format(s->fp, o->fout == 'a' ? "ascii" : o->fout == 'f' ? "float" : "double",
                                             nw)))
                goto done;
        }
    }
    /* rays in batches */
    int per = o->accum > 0 ? o->accum : 1;
    size_t rlen = 3 * (size_t)c->ncols, batch = 1024;
    hd_vec3 *org = hd_malloc_array(batch * (size_t)per, sizeof *org), *dir = hd_malloc_array(batch * (size_t)per, sizeof *dir);
    double *out = hd_malloc_array(batch, rlen * sizeof(double));
    double *sum = o->accum == 0 ? hd_calloc(rlen, sizeof(double)) : NULL;
    if (!org || !dir || !out || (o->accum == 0 && !sum)) { free(org); free(dir); free(out); free(sum); st = HD_ERR_NOMEM; goto done; }
    j.c = c; j.o = o; j.po = po; j.m = m; j.mods = mods; j.org = org; j.dir = dir; j.per = per; j.rlen = rlen; j.out = out;
    uint64_t rec = 0, written = 0;
    int eof = 0;
    while (!eof && !st) {
        size_t nrec = 0;
        while (nrec < batch) {
            size_t k;
            for (k = 0; k < (size_t)per; k++) {
                if ((st = read_ray(src, o->fin, &org[nrec * per + k], &dir[nrec * per + k], &eof))) break;
                if (eof) break;
            }
            if (st || eof) {
                if (!st && k && o->accum > 0)
                    st = hd_fail(HD_ERR_FORMAT, "input ends within a record of %d rays", per);
                break;
            }
            if (rec + nrec < po->row0) { rec++; continue; }   /* before the requested range */
            if (po->nrows && rec + nrec >= po->row0 + po->nrows) { eof = 1; break; }
            nrec++;
        }
        if (st || !nrec) break;
        j.rec0 = rec;
        if ((st = hd_parallel_for(nrec, 8, nth, rc_units, &j))) break;
        for (size_t r = 0; r < nrec; r++) {
            const double *rv = out + r * rlen;
            if (sum) { for (size_t q = 0; q < rlen; q++) sum[q] += rv[q]; continue; }
            for (int q = 0; q < nos; q++) {
                ostream *s = &os[q];
                if (o->fout == 'c') {
                    uint64_t px = written + r;
                    if (px < (uint64_t)o->xres * (uint64_t)o->yres)
                        for (int ch = 0; ch < 3; ch++) s->pic.pix[3 * px + ch] = (float)rv[3 * s->cols[0] + ch];
                    continue;
                }
                for (int cc = 0; cc < s->ncols; cc++) {
                    const double *v = rv + 3 * (size_t)s->cols[cc];
                    if (o->fout == 'a') fprintf(s->fp, "%.6e\t%.6e\t%.6e\t", v[0], v[1], v[2]);
                    else if (o->fout == 'f') { float f3[3] = {(float)v[0], (float)v[1], (float)v[2]}; fwrite(f3, 4, 3, s->fp); }
                    else fwrite(v, 8, 3, s->fp);
                }
                if (o->fout == 'a') fputc('\n', s->fp);
            }
        }
        written += nrec;
        rec += nrec;
    }
    if (!st && sum) {
        for (int q = 0; q < nos; q++)
            for (int cc = 0; cc < os[q].ncols && o->fout != 'c'; cc++) {
                const double *v = sum + 3 * (size_t)os[q].cols[cc];
                if (o->fout == 'a') fprintf(os[q].fp, "%.6e\t%.6e\t%.6e\t", v[0], v[1], v[2]);
                else if (o->fout == 'f') { float f3[3] = {(float)v[0], (float)v[1], (float)v[2]}; fwrite(f3, 4, 3, os[q].fp); }
                else fwrite(v, 8, 3, os[q].fp);
            }
        for (int q = 0; q < nos; q++) if (o->fout == 'a') fputc('\n', os[q].fp);
    }
    free(org); free(dir); free(out); free(sum);
    if (st) goto done;
    for (int q = 0; q < nos; q++) {
        ostream *s = &os[q];
        if (o->fout == 'c') {
            hd_header h;
            hd_header_init(&h);
            if ((st = hd_header_copy(&h, hdr))) goto done;
            st = hd_picture_save(s->name[0] ? s->name : "-", &s->pic, &h);
            hd_header_free(&h);
            if (st) goto done;
        } else if (s->of) {
            st = hd_ofile_commit(s->of);
            s->of = NULL;
            if (st) goto done;
        } else fflush(stdout);
    }
done:
    for (int q = 0; os && q < nos; q++) {
        if (os[q].of) hd_ofile_abort(os[q].of);
        free(os[q].cols);
        if (os[q].pic.pix) hd_picture_free(&os[q].pic);
    }
    free(os);
    for (int w = 0; j.lk && w < nth; w++) hd_pmap_lookup_free(j.lk[w]);
    for (int w = 0; j.tmp && w < nth; w++) free(j.tmp[w]);
    free(j.lk);
    free(j.tmp);
    for (int mi = 0; mi < c->nmods; mi++) free(mods[mi].src);
    free(mods);
    hd_pmap_close(m);
    return st;
}

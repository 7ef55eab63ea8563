/* heliodon — radial-basis BSDF interpolants: file format, evaluation and
 * advection between measured incident directions (see rbf.h and
 * docs/design/measured.md). */
#include "heliodon/rbf.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/bsdf.h"
#include "heliodon/io.h"

#define RBF_TINY 1e-6
#define RBF_MAGIC 0x5a3c
#define RBF_FORMAT "BSDF_RBFmesh"

static const char *const color_name[4] = {"CIE-Y", "CIE-XYZ", "Spectral", "Unknown"};

/* ---- set-up ---- */

static hd_status make_table(hd_rbfrep *r)
{
    int q = r->grid_res / 2;
    free(r->q_uv);
    r->q_uv = hd_malloc_array((size_t)q * q, sizeof *r->q_uv);
    if (!r->q_uv) return HD_ERR_NOMEM;
    for (int y = 0; y < q; y++)
        for (int x = 0; x < q; x++) {
            double u, v;
            hd_square2disk(0.5 + (x + .5) / r->grid_res, 0.5 + (y + .5) / r->grid_res, &u, &v);
            double s = sqrt(2. - u * u - v * v);   /* equal-area disk -> hemisphere */
            r->q_uv[q * y + x][0] = (float)(s * u);
            r->q_uv[q * y + x][1] = (float)(s * v);
        }
    return HD_OK;
}

hd_status hd_rbf_init(hd_rbfrep *r, int grid_res)
{
    memset(r, 0, sizeof *r);
    r->grid_res = grid_res;
    r->single_plane = -1;
    r->colorimetry = 3;
    return make_table(r);
}

void hd_rbf_free(hd_rbfrep *r)
{
    if (!r) return;
    for (int i = 0; i < r->ndsf; i++) free(r->dsf[i].rbfa);
    for (int i = 0; i < r->nmig; i++) {
        free(r->mig[i].mtx);
        free(r->mig[i].rs);
        free(r->mig[i].ci);
        free(r->mig[i].cv);
    }
    free(r->dsf);
    free(r->mig);
    free(r->header);
    free(r->edge_start);
    free(r->edge_list);
    free(r->q_uv);
    memset(r, 0, sizeof *r);
}

/* ---- grid geometry ---- */

hd_vec3 hd_rbf_ovec(const hd_rbfrep *r, int gx, int gy)
{
    int q = r->grid_res / 2;
    double sx = 1, sy = 1;
    if (gx >= q) gx -= q;
    else { gx = q - 1 - gx; sx = -1; }
    if (gy >= q) gy -= q;
    else { gy = q - 1 - gy; sy = -1; }
    if (gx < 0) gx = 0;
    if (gy < 0) gy = 0;
    if (gx >= q) gx = q - 1;
    if (gy >= q) gy = q - 1;
    hd_vec3 v;
    v.x = sx * (double)r->q_uv[q * gy + gx][0];
    v.y = sy * (double)r->q_uv[q * gy + gx][1];
    double z2 = 1. - v.x * v.x - v.y * v.y;
    v.z = r->output_orient * sqrt(z2 > 0 ? z2 : 0);
    return v;
}

void hd_rbf_pos(const hd_rbfrep *r, hd_vec3 v, int pos[2])
{
    double n = 1. / sqrt(1. + fabs(v.z)), sx, sy;
    hd_disk2square(v.x * n, v.y * n, &sx, &sy);
    pos[0] = (int)(sx * r->grid_res);
    pos[1] = (int)(sy * r->grid_res);
    if (pos[0] >= r->grid_res) pos[0] = r->grid_res - 1;
    if (pos[1] >= r->grid_res) pos[1] = r->grid_res - 1;
}

double hd_rbf_lobe_volume(const hd_rbfrep *r, const hd_rbflobe *l)
{
    double rad = hd_rbf_r2ang(l->crad);
    double integ = 2. * HD_PI * l->peak * rad * rad;
    hd_vec3 d = hd_rbf_ovec(r, l->gx, l->gy);
    double elev = r->output_orient * d.z;
    if (elev < 2.8 * rad) integ *= 1. - .5 * exp(-.5 * elev * elev / (rad * rad));
    return integ;
}

/* ---- evaluation ---- */

#define EB 16   /* evaluation bins per axis */

typedef struct ev_lobe { float dx, dy, dz, peak, irad2, cull2; int gx, gy; } ev_lobe;

struct hd_rbfeval {
    const hd_rbfrep *r;
    int n;
    ev_lobe *l;
    hd_vec3 *dv;             /* lobe directions and squared radii in double (hd_rbfeval_bsdf_exact) */
    double *rad2;
    int start[EB * EB + 1];
    int *idx;
};

static double cull_fact2(const hd_rbfrep *r)
{
    return (38. / HD_PI / HD_PI) * (double)(r->grid_res * r->grid_res);
}

hd_status hd_rbfeval_make(hd_rbfeval **out, const hd_rbfrep *r, const hd_rbfdsf *d)
{
    *out = NULL;
    hd_rbfeval *e = hd_calloc(1, sizeof *e);
    if (!e) return HD_ERR_NOMEM;
    e->r = r;
    e->n = d ? d->nrbf : 0;
    e->l = hd_malloc_array((size_t)(e->n ? e->n : 1), sizeof *e->l);
    e->dv = hd_malloc_array((size_t)(e->n ? e->n : 1), sizeof *e->dv);
    e->rad2 = hd_malloc_array((size_t)(e->n ? e->n : 1), sizeof *e->rad2);
    if (!e->l || !e->dv || !e->rad2) { hd_rbfeval_free(e); return HD_ERR_NOMEM; }
    double rf2 = cull_fact2(r);
    int bw = r->grid_res / EB;
    int *cnt = hd_calloc(EB * EB, sizeof(int));
    int (*box)[4] = hd_malloc_array((size_t)(e->n ? e->n : 1), sizeof *box);
    if (!cnt || !box) { free(cnt); free(box); hd_rbfeval_free(e); return HD_ERR_NOMEM; }
    for (int i = 0; i < e->n; i++) {
        const hd_rbflobe *lb = &d->rbfa[i];
        hd_vec3 v = hd_rbf_ovec(r, lb->gx, lb->gy);
        double rad2 = hd_rbf_r2ang(lb->crad);
        rad2 *= rad2;
        ev_lobe *el = &e->l[i];
        e->dv[i] = v;
        e->rad2[i] = rad2;
        el->dx = (float)v.x; el->dy = (float)v.y; el->dz = (float)v.z;
        el->peak = lb->peak;
        el->irad2 = (float)(1. / rad2);
        el->cull2 = (float)(rad2 * rf2);
        el->gx = lb->gx; el->gy = lb->gy;
        double cr = sqrt(rad2 * rf2) + 1;
        int x0 = (int)floor((lb->gx - cr) / bw), x1 = (int)floor((lb->gx + cr) / bw);
        int y0 = (int)floor((lb->gy - cr) / bw), y1 = (int)floor((lb->gy + cr) / bw);
        box[i][0] = x0 < 0 ? 0 : x0; box[i][1] = x1 >= EB ? EB - 1 : x1;
        box[i][2] = y0 < 0 ? 0 : y0; box[i][3] = y1 >= EB ? EB - 1 : y1;
        for (int bx = box[i][0]; bx <= box[i][1]; bx++)
            for (int by = box[i][2]; by <= box[i][3]; by++) cnt[bx * EB + by]++;
    }
    e->start[0] = 0;
    for (int b = 0; b < EB * EB; b++) e->start[b + 1] = e->start[b] + cnt[b];
    e->idx = hd_malloc_array((size_t)(e->start[EB * EB] ? e->start[EB * EB] : 1), sizeof(int));
    if (!e->idx) { free(cnt); free(box); hd_rbfeval_free(e); return HD_ERR_NOMEM; }
    memset(cnt, 0, EB * EB * sizeof(int));
    for (int i = 0; i < e->n; i++)
        for (int bx = box[i][0]; bx <= box[i][1]; bx++)
            for (int by = box[i][2]; by <= box[i][3]; by++) {
                int b = bx * EB + by;
                e->idx[e->start[b] + cnt[b]++] = i;
            }
    free(cnt);
    free(box);
    *out = e;
    return HD_OK;
}

void hd_rbfeval_free(hd_rbfeval *e)
{
    if (!e) return;
    free(e->l);
    free(e->dv);
    free(e->rad2);
    free(e->idx);
    free(e);
}

/* The grid position of o and its block of lobes in e; -1 when o is on the
 * other side than the data (the value is then bsdf_min). */
static int eval_block(const hd_rbfeval *e, hd_vec3 o, int pos[2])
{
    const hd_rbfrep *r = e->r;
    if ((o.z > 0) != (r->output_orient > 0)) return -1;
    hd_rbf_pos(r, o, pos);
    int bw = r->grid_res / EB;
    return (pos[0] / bw) * EB + pos[1] / bw;
}

double hd_rbfeval_bsdf(const hd_rbfeval *e, hd_vec3 o)
{
    if (!e) return 0;
    const hd_rbfrep *r = e->r;
    int pos[2], b = eval_block(e, o, pos);
    if (b < 0) return r->bsdf_min;
    double res = 0;
    for (int k = e->start[b]; k < e->start[b + 1]; k++) {
        const ev_lobe *l = &e->l[e->idx[k]];
        int dx = pos[0] - l->gx, dy = pos[1] - l->gy;
        if ((double)(dx * dx + dy * dy) > l->cull2) continue;
        double c = l->dx * o.x + l->dy * o.y + l->dz * o.z;
        res += l->peak * exp((c - 1.) * l->irad2);
    }
    res /= hd_rbf_cosf(o.z);
    return res < r->bsdf_min ? r->bsdf_min : res;
}

double hd_rbfeval_bsdf_exact(const hd_rbfeval *e, hd_vec3 o)
{
    if (!e) return 0;
    const hd_rbfrep *r = e->r;
    int pos[2], b = eval_block(e, o, pos);
    if (b < 0) return r->bsdf_min;
    double rf2 = cull_fact2(r), res = 0;
    for (int k = e->start[b]; k < e->start[b + 1]; k++) {     /* ascending lobe order */
        int n = e->idx[k];
        const ev_lobe *l = &e->l[n];
        int dx = pos[0] - l->gx, dy = pos[1] - l->gy;
        if (dx * dx + dy * dy > e->rad2[n] * rf2) continue;
        res += l->peak * exp((hd_vdot(e->dv[n], o) - 1.) / e->rad2[n]);
    }
    res /= hd_rbf_cosf(o.z);
    return res < r->bsdf_min ? r->bsdf_min : res;
}

double hd_rbf_eval(const hd_rbfrep *r, const hd_rbfdsf *d, hd_vec3 o)
{
    if ((o.z > 0) != (r->output_orient > 0)) return r->bsdf_min;
    if (!d) return r->bsdf_min;
    int pos[2];
    hd_rbf_pos(r, o, pos);
    double rf2 = cull_fact2(r), res = 0;
    for (int n = 0; n < d->nrbf; n++) {
        const hd_rbflobe *l = &d->rbfa[n];
        int dx = pos[0] - l->gx, dy = pos[1] - l->gy;
        double rad2 = hd_rbf_r2ang(l->crad);
        rad2 *= rad2;
        if (dx * dx + dy * dy > rad2 * rf2) continue;
        hd_vec3 v = hd_rbf_ovec(r, l->gx, l->gy);
        res += l->peak * exp((hd_vdot(v, o) - 1.) / rad2);
    }
    res /= hd_rbf_cosf(o.z);
    return res < r->bsdf_min ? r->bsdf_min : res;
}

/* ---- links ---- */

/* the row lists of a plan: columns and values of its non-zero entries */
static hd_status mig_rows(hd_rbfmig *g, int nr, int nc)
{
    free(g->rs);
    free(g->ci);
    free(g->cv);
    g->rs = hd_malloc_array((size_t)nr + 1, sizeof(int));
    size_t nz = 0;
    for (size_t k = 0; k < (size_t)nr * nc; k++) nz += g->mtx[k] != 0;
    g->ci = hd_malloc_array(nz ? nz : 1, sizeof(int));
    g->cv = hd_malloc_array(nz ? nz : 1, sizeof(float));
    if (!g->rs || !g->ci || !g->cv) return HD_ERR_NOMEM;
    nz = 0;
    for (int i = 0; i < nr; i++) {
        g->rs[i] = (int)nz;
        for (int j = 0; j < nc; j++) {
            float v = g->mtx[(size_t)i * nc + j];
            if (v != 0) { g->ci[nz] = j; g->cv[nz++] = v; }
        }
    }
    g->rs[nr] = (int)nz;
    return HD_OK;
}

hd_status hd_rbf_link(hd_rbfrep *r)
{
    free(r->edge_start);
    free(r->edge_list);
    r->edge_start = hd_calloc((size_t)r->ndsf + 1, sizeof(int));
    r->edge_list = hd_malloc_array((size_t)(2 * r->nmig + 1), sizeof(int));
    if (!r->edge_start || !r->edge_list) return HD_ERR_NOMEM;
    for (int m = 0; m < r->nmig; m++) {
        r->edge_start[r->mig[m].from + 1]++;
        r->edge_start[r->mig[m].to + 1]++;
    }
    for (int i = 0; i < r->ndsf; i++) r->edge_start[i + 1] += r->edge_start[i];
    int *fill = hd_calloc((size_t)r->ndsf + 1, sizeof(int));
    if (!fill) return HD_ERR_NOMEM;
    for (int m = 0; m < r->nmig; m++) {
        int a = r->mig[m].from, b = r->mig[m].to;
        r->edge_list[r->edge_start[a] + fill[a]++] = m;
        r->edge_list[r->edge_start[b] + fill[b]++] = m;
    }
    free(fill);
    for (int m = 0; m < r->nmig; m++) {
        hd_rbfmig *g = &r->mig[m];
        if (g->mtx) {
            hd_status st = mig_rows(g, r->dsf[g->from].nrbf, r->dsf[g->to].nrbf);
            if (st != HD_OK) return st;
        } else if (!g->rs)
            return hd_fail(HD_ERR_RANGE, "interpolant: plan %d has neither a matrix nor row lists", m);
    }
    return HD_OK;
}

/* ---- file format ---- */

typedef struct rd { const unsigned char *p; size_t n, at; const char *path; } rd;

static int rd_int(rd *b, int siz, long *v)
{
    if (b->at + (size_t)siz > b->n) return 0;
    long x = (b->p[b->at] & 0x80) ? -1 : 0;
    for (int i = 0; i < siz; i++) x = (long)((unsigned long)x << 8) | b->p[b->at + i];
    b->at += (size_t)siz;
    *v = x;
    return 1;
}

static int rd_flt(rd *b, double *v)
{
    long m, e;
    if (!rd_int(b, 4, &m) || !rd_int(b, 1, &e)) return 0;
    *v = hd_portable_flt(m, e);
    return 1;
}

static hd_status trunc_err(const rd *b, const char *what)
{
    return hd_fail(HD_ERR_FORMAT, "%s: byte %zu: file ends inside %s", b->path, b->at, what);
}

static hd_status parse_headline(hd_rbfrep *r, const char *s, const char *path, int line)
{
    if (!strncmp(s, "NAME=", 5)) { snprintf(r->name, sizeof r->name, "%.255s", s + 5); return HD_OK; }
    if (!strncmp(s, "MANUFACT=", 9)) { snprintf(r->manuf, sizeof r->manuf, "%.255s", s + 9); return HD_OK; }
    if (!strncmp(s, "SYMMETRY=", 9)) {
        r->inp_coverage = atoi(s + 9);
        if (r->inp_coverage < 0 || r->inp_coverage > 15)
            return hd_fail(HD_ERR_FORMAT, "%s: header line %d: SYMMETRY %d out of range 0..15", path, line,
                           r->inp_coverage);
        r->single_plane = !r->inp_coverage;
        return HD_OK;
    }
    if (!strncmp(s, "IO_SIDES=", 9)) {
        if (sscanf(s + 9, "%d %d", &r->input_orient, &r->output_orient) != 2 ||
            abs(r->input_orient) != 1 || abs(r->output_orient) != 1)
            return hd_fail(HD_ERR_FORMAT, "%s: header line %d: IO_SIDES needs two values of 1 or -1", path, line);
        return HD_OK;
    }
    if (!strncmp(s, "COLORIMETRY=", 12)) {
        char w[64] = "";
        sscanf(s + 12, "%63s", w);
        for (int i = 0; i < 4; i++)
            if (!strcmp(w, color_name[i])) { r->colorimetry = i; return HD_OK; }
        return hd_fail(HD_ERR_FORMAT, "%s: header line %d: unknown COLORIMETRY '%s'", path, line, w);
    }
    if (!strncmp(s, "GRIDRES=", 8)) { r->grid_res = atoi(s + 8); return HD_OK; }
    if (!strncmp(s, "BSDFMIN=", 8)) { r->bsdf_min = atof(s + 8); return HD_OK; }
    if (!strncmp(s, "BSDFSPEC=", 9)) {
        if (sscanf(s + 9, "%lf %lf", &r->spec_val, &r->spec_rad) != 2)
            return hd_fail(HD_ERR_FORMAT, "%s: header line %d: BSDFSPEC needs two numbers", path, line);
        return HD_OK;
    }
    return HD_OK;
}

static hd_status rbf_read(hd_rbfrep *r, const char *path, int rows_only)
{
    hd_status st = hd_rbf_init(r, HD_RBF_GRIDRES);
    if (st != HD_OK) return st;
    size_t n = 0;
    unsigned char *buf = NULL;
    if ((st = hd_file_read_all(path, &buf, &n)) != HD_OK) return st;
    /* header */
    size_t at = 0;
    int line = 0, have_format = 0;
    size_t hcap = 1024, hlen = 0;
    r->header = hd_malloc(hcap);
    if (!r->header) { free(buf); return HD_ERR_NOMEM; }
    r->header[0] = 0;
    for (;;) {
        size_t e = at;
        while (e < n && buf[e] != '\n') e++;
        if (e >= n) { free(buf); return hd_fail(HD_ERR_FORMAT, "%s: the header has no end (empty line)", path); }
        line++;
        size_t len = e - at;
        if (len == 0) { at = e + 1; break; }
        char ln[2048];
        size_t cl = len < sizeof ln - 1 ? len : sizeof ln - 1;
        memcpy(ln, buf + at, cl);
        ln[cl] = 0;
        at = e + 1;
        if (line == 1 && strncmp(ln, "#?", 2)) {
            free(buf);
            return hd_fail(HD_ERR_FORMAT, "%s: not a BSDF interpolant (no #?RADIANCE header)", path);
        }
        if (!strncmp(ln, "FORMAT=", 7)) {
            const char *f = ln + 7;
            while (*f == ' ' || *f == '\t') f++;
            if (strcmp(f, RBF_FORMAT)) {
                free(buf);
                return hd_fail(HD_ERR_FORMAT, "%s: header line %d: FORMAT is '%s', expected %s", path, line, f,
                               RBF_FORMAT);
            }
            have_format = 1;
            continue;
        }
        if (line == 1) continue;
        if ((st = parse_headline(r, ln, path, line)) != HD_OK) { free(buf); return st; }
        if (hlen + cl + 2 > hcap) {
            while (hlen + cl + 2 > hcap) hcap *= 2;
            char *nh = hd_realloc_array(r->header, hcap, 1);
            if (!nh) { free(buf); return HD_ERR_NOMEM; }
            r->header = nh;
        }
        memcpy(r->header + hlen, ln, cl);
        hlen += cl;
        r->header[hlen++] = '\n';
        r->header[hlen] = 0;
    }
    if (!have_format || r->single_plane < 0 || !r->input_orient || !r->output_orient || r->grid_res < 16 ||
        r->grid_res > 0xffff || (r->grid_res & 1)) {
        free(buf);
        return hd_fail(HD_ERR_FORMAT, "%s: header lacks FORMAT=%s, SYMMETRY, IO_SIDES or a valid GRIDRES", path,
                       RBF_FORMAT);
    }
    if ((st = make_table(r)) != HD_OK) { free(buf); return st; }
    rd b = {buf, n, at, path};
    long v;
    if (!rd_int(&b, 2, &v)) { st = trunc_err(&b, "the magic number"); goto fail; }
    if ((v & 0xffff) != RBF_MAGIC) {
        st = hd_fail(HD_ERR_FORMAT, "%s: byte %zu: bad magic number 0x%lx (expected 0x%x)", path, at, v & 0xffff,
                     RBF_MAGIC);
        goto fail;
    }
    size_t dcap = 0;
    for (;;) {
        size_t here = b.at;
        if (!rd_int(&b, 4, &v)) { st = trunc_err(&b, "the DSF list"); goto fail; }
        if (v < 0) break;
        if (v != r->ndsf) {
            st = hd_fail(HD_ERR_FORMAT, "%s: byte %zu: DSF number %ld out of order (expected %d)", path, here, v,
                         r->ndsf);
            goto fail;
        }
        if ((st = HD_GROW(r->dsf, (size_t)r->ndsf + 1, dcap, 16))) goto fail;
        hd_rbfdsf *d = &r->dsf[r->ndsf];
        memset(d, 0, sizeof *d);
        d->ord = (int)v;
        double x, y, z, vt;
        long nl;
        if (!rd_flt(&b, &x) || !rd_flt(&b, &y) || !rd_flt(&b, &z) || !rd_flt(&b, &vt) || !rd_int(&b, 4, &nl)) {
            st = trunc_err(&b, "a DSF record");
            goto fail;
        }
        d->invec = hd_vnorm(hd_v3(x, y, z));
        if (hd_vlen2(d->invec) == 0) {
            st = hd_fail(HD_ERR_FORMAT, "%s: byte %zu: zero incident vector", path, here);
            goto fail;
        }
        if (nl < 0 || (size_t)nl * 13 > b.n - b.at) {
            st = hd_fail(HD_ERR_FORMAT, "%s: byte %zu: lobe count %ld exceeds the file", path, here, nl);
            goto fail;
        }
        d->vtotal = vt;
        d->nrbf = (int)nl;
        d->rbfa = hd_malloc_array((size_t)(nl ? nl : 1), sizeof *d->rbfa);
        if (!d->rbfa) { st = HD_ERR_NOMEM; goto fail; }
        r->ndsf++;
        for (long i = 0; i < nl; i++) {
            double pk;
            long c = 0, cr = 0, gx = 0, gy = 0;
            rd_flt(&b, &pk);
            rd_int(&b, 2, &c); rd_int(&b, 2, &cr); rd_int(&b, 2, &gx); rd_int(&b, 2, &gy);
            hd_rbflobe *l = &d->rbfa[i];
            l->peak = (float)pk;
            l->chroma = (uint16_t)(c & 0xffff);
            l->crad = (uint16_t)(cr & 0xffff);
            l->gx = (uint16_t)(gx & 0xffff);
            l->gy = (uint16_t)(gy & 0xffff);
            if (l->gx >= r->grid_res || l->gy >= r->grid_res) {
                st = hd_fail(HD_ERR_FORMAT, "%s: DSF %d lobe %ld: grid position %d %d outside GRIDRES %d", path,
                             d->ord, i, l->gx, l->gy, r->grid_res);
                goto fail;
            }
        }
    }
    size_t mcap = 0;
    for (;;) {
        size_t here = b.at;
        long f, t;
        if (!rd_int(&b, 4, &f)) { st = trunc_err(&b, "the migration list"); goto fail; }
        if (f < 0) break;
        if (!rd_int(&b, 4, &t)) { st = trunc_err(&b, "the migration list"); goto fail; }
        if (t < 0) break;
        if (f >= r->ndsf || t >= r->ndsf || f == t) {
            st = hd_fail(HD_ERR_FORMAT, "%s: byte %zu: migration %ld -> %ld refers to a missing DSF", path, here, f,
                         t);
            goto fail;
        }
        if ((st = HD_GROW(r->mig, (size_t)r->nmig + 1, mcap, 16))) goto fail;
        hd_rbfmig *m = &r->mig[r->nmig];
        memset(m, 0, sizeof *m);
        m->from = (int)f;
        m->to = (int)t;
        size_t nn = (size_t)r->dsf[f].nrbf * r->dsf[t].nrbf;
        /* sized by the lobe counts the file declares: refused above the allocation limit */
        m->mtx = hd_big_alloc(nn ? nn : 1, sizeof(float), 1);
        if (!m->mtx) {
            st = hd_fail_context(HD_ERR_NOMEM, "%s: byte %zu: migration %ld -> %ld (%d x %d lobes)", path, here, f, t,
                                 r->dsf[f].nrbf, r->dsf[t].nrbf);
            goto fail;
        }
        r->nmig++;
        for (size_t i = 0;;) {
            long zc;
            if (!rd_int(&b, 1, &zc)) { st = trunc_err(&b, "a migration matrix"); goto fail; }
            zc &= 0xff;
            if ((i += (size_t)zc) >= nn) break;
            if (zc == 0xff) continue;
            double val;
            if (!rd_flt(&b, &val)) { st = trunc_err(&b, "a migration matrix"); goto fail; }
            m->mtx[i++] = (float)val;
        }
        if (rows_only) {   /* one dense matrix at a time */
            if ((st = mig_rows(m, r->dsf[f].nrbf, r->dsf[t].nrbf)) != HD_OK) goto fail;
            free(m->mtx);
            m->mtx = NULL;
        }
    }
    /* memory holds the edges oldest first; files (Radiance's and ours) newest first */
    for (int a = 0, z = r->nmig - 1; a < z; a++, z--) {
        hd_rbfmig t = r->mig[a];
        r->mig[a] = r->mig[z];
        r->mig[z] = t;
    }
    free(buf);
    return hd_rbf_link(r);
fail:
    free(buf);
    return st;
}

/* A failed read frees what it had built (r is left empty, and freeing it
 * again is harmless). */
static hd_status rbf_read_or_free(hd_rbfrep *r, const char *path, int rows_only)
{
    hd_status st = rbf_read(r, path, rows_only);
    if (st != HD_OK) hd_rbf_free(r);
    return st;
}

hd_status hd_rbf_read(hd_rbfrep *r, const char *path) { return rbf_read_or_free(r, path, 0); }

hd_status hd_rbf_read_rows(hd_rbfrep *r, const char *path) { return rbf_read_or_free(r, path, 1); }

hd_status hd_rbf_write(const hd_rbfrep *r, FILE *fp, const char *header_lines)
{
    for (int k = 0; k < r->nmig; k++)
        if (!r->mig[k].mtx) return hd_fail(HD_ERR_RANGE, "interpolant: plan %d was dropped (cannot write)", k);
    hd_header h;
    hd_header_init(&h);
    hd_status st = hd_header_append_lines(&h, header_lines);
    if (!st && r->name[0]) st = hd_header_appendf(&h, "NAME=%s", r->name);
    if (!st && r->manuf[0]) st = hd_header_appendf(&h, "MANUFACT=%s", r->manuf);
    if (!st) st = hd_header_appendf(&h, "SYMMETRY=%d", r->single_plane ? 0 : r->inp_coverage);
    if (!st) st = hd_header_appendf(&h, "IO_SIDES= %d %d", r->input_orient, r->output_orient);
    if (!st) st = hd_header_appendf(&h, "COLORIMETRY=%s", color_name[r->colorimetry & 3]);
    if (!st) st = hd_header_appendf(&h, "GRIDRES=%d", r->grid_res);
    if (!st) st = hd_header_appendf(&h, "BSDFMIN=%g", r->bsdf_min);
    if (!st && r->spec_val > r->bsdf_min && r->spec_rad > 0)
        st = hd_header_appendf(&h, "BSDFSPEC= %f %f", r->spec_val, r->spec_rad);
    if (!st) st = hd_header_put(fp, &h, NULL, RBF_FORMAT, NULL);
    hd_header_free(&h);
    if (st) return st;
    hd_put_int(fp, RBF_MAGIC, 2);
    for (int k = 0; k < r->ndsf; k++) {
        const hd_rbfdsf *d = &r->dsf[k];
        hd_put_int(fp, d->ord, 4);
        hd_put_flt(fp, d->invec.x);
        hd_put_flt(fp, d->invec.y);
        hd_put_flt(fp, d->invec.z);
        hd_put_flt(fp, d->vtotal);
        hd_put_int(fp, d->nrbf, 4);
        for (int i = 0; i < d->nrbf; i++) {
            hd_put_flt(fp, d->rbfa[i].peak);
            hd_put_int(fp, d->rbfa[i].chroma, 2);
            hd_put_int(fp, d->rbfa[i].crad, 2);
            hd_put_int(fp, d->rbfa[i].gx, 2);
            hd_put_int(fp, d->rbfa[i].gy, 2);
        }
    }
    hd_put_int(fp, -1, 4);
    for (int k = r->nmig - 1; k >= 0; k--) {   /* newest first, as Radiance writes them */
        const hd_rbfmig *m = &r->mig[k];
        hd_put_int(fp, m->from, 4);
        hd_put_int(fp, m->to, 4);
        size_t nn = (size_t)r->dsf[m->from].nrbf * r->dsf[m->to].nrbf;
        int zc = 0;
        for (size_t i = 0; i < nn; i++) {
            if (zc == 0xff) { hd_put_int(fp, 0xff, 1); zc = 0; }
            if (m->mtx[i] != 0) {
                hd_put_int(fp, zc, 1);
                zc = 0;
                hd_put_flt(fp, m->mtx[i]);
            } else
                zc++;
        }
        hd_put_int(fp, zc, 1);
    }
    hd_put_int(fp, -1, 4);
    hd_put_int(fp, -1, 4);
    if (ferror(fp)) return hd_fail(HD_ERR_IO, "write error on the interpolant");
    return HD_OK;
}

/* ---- symmetry ---- */

static hd_vec3 mirror(hd_vec3 v, int sym)
{
    if (sym & 1) v.x = -v.x;
    if (sym & 2) v.y = -v.y;
    return v;
}

int hd_rbf_use_symmetry(const hd_rbfrep *r, hd_vec3 *v)
{
    double phi = atan2(v->y, v->x) * (180. / HD_PI);
    while (phi >= 360.) phi -= 360.;
    while (phi < 0.) phi += 360.;
    const double T = RBF_TINY;
    int q = (int)(phi / 90.), sym = 0;
    if (q > 3) q = 3;
    switch (r->inp_coverage) {
    case 15: break;
    case HD_RBF_Q1 | HD_RBF_Q2: if (phi < -T || phi > 180. + T) sym = 2; break;
    case HD_RBF_Q2 | HD_RBF_Q3: if (phi < 90. - T || phi > 270. + T) sym = 1; break;
    case HD_RBF_Q3 | HD_RBF_Q4: if (phi < 180. - T || phi > 360. + T) sym = 2; break;
    case HD_RBF_Q4 | HD_RBF_Q1: if (phi < 270. - T && phi > 90. + T) sym = 1; break;
    case HD_RBF_Q1: if (phi > 90. + T) sym = (int[]){0, 1, 3, 2}[q]; break;
    case HD_RBF_Q2: if (phi < 90. - T || phi > 180. + T) sym = (int[]){1, 0, 2, 3}[q]; break;
    case HD_RBF_Q3: if (phi < 180. - T || phi > 270. + T) sym = (int[]){3, 2, 0, 1}[q]; break;
    case HD_RBF_Q4: if (phi < 270. - T) sym = (int[]){2, 3, 1, 0}[q]; break;
    default: break;
    }
    *v = mirror(*v, sym);
    return sym;
}

void hd_rbf_mirror_dsf(const hd_rbfrep *r, hd_rbfdsf *d, int sym)
{
    d->invec = mirror(d->invec, sym);
    for (int n = 0; n < d->nrbf; n++) {
        if (sym & 1) d->rbfa[n].gx = (uint16_t)(r->grid_res - 1 - d->rbfa[n].gx);
        if (sym & 2) d->rbfa[n].gy = (uint16_t)(r->grid_res - 1 - d->rbfa[n].gy);
    }
}

/* ---- advection ---- */

static hd_vec3 geodesic(hd_vec3 a, hd_vec3 b, double t)
{
    double d = hd_vdot(a, b);
    if (t == 0 || d >= 1. - 1e-12 || d <= -1. + 1e-12) return a;
    double ang = t * acos(d);
    double s = sin(ang) / sqrt(1. - d * d);
    return hd_vadd(hd_vscale(a, cos(ang)), hd_vscale(hd_vsub(b, hd_vscale(a, d)), s));
}

static double acos_c(double x) { return x >= 1 ? 0 : x <= -1 ? HD_PI : acos(x); }

static hd_status copy_dsf(const hd_rbfdsf *src, hd_rbfdsf *out)
{
    *out = *src;
    out->rbfa = hd_malloc_array((size_t)(src->nrbf ? src->nrbf : 1), sizeof *out->rbfa);
    if (!out->rbfa) return HD_ERR_NOMEM;
    memcpy(out->rbfa, src->rbfa, (size_t)src->nrbf * sizeof *out->rbfa);
    return HD_OK;
}

hd_status hd_rbf_edge_advect(const hd_rbfrep *r, const hd_rbfmig *m, hd_vec3 in, int lobe_lim, hd_rbfdsf *out)
{
    const hd_rbfdsf *d0 = &r->dsf[m->from], *d1 = &r->dsf[m->to];
    memset(out, 0, sizeof *out);
    double t = acos_c(hd_vdot(in, d0->invec));
    if (t <= .001) return copy_dsf(d0, out);
    double full = acos_c(hd_vdot(d0->invec, d1->invec));
    if (t >= full - .001) return copy_dsf(d1, out);
    t /= full;
    int nr = d0->nrbf;
    double cth = RBF_TINY;
    size_t n;
    for (;;) {
        n = 0;
        for (int i = 0; i < nr; i++)
            for (int k = m->rs[i]; k < m->rs[i + 1]; k++) n += m->cv[k] > cth;
        if (lobe_lim <= 0 || n <= (size_t)lobe_lim) break;
        cth = cth * 2. + 10. * RBF_TINY;
    }
    out->rbfa = hd_malloc_array(n ? n : 1, sizeof *out->rbfa);
    if (!out->rbfa) return HD_ERR_NOMEM;
    out->invec = in;
    out->vtotal = 1. - t + t * d1->vtotal / d0->vtotal;
    n = 0;
    for (int i = 0; i < nr; i++) {
        const hd_rbflobe *a = &d0->rbfa[i];
        double rad0 = hd_rbf_r2ang(a->crad);
        hd_vec3 v0 = hd_rbf_ovec(r, a->gx, a->gy);
        for (int k = m->rs[i]; k < m->rs[i + 1]; k++) {
            int j = m->ci[k];
            float mv = m->cv[k];
            if (!(mv > cth)) continue;
            const hd_rbflobe *bb = &d1->rbfa[j];
            double rad2 = hd_rbf_r2ang(bb->crad);
            rad2 = rad0 * rad0 * (1. - t) + rad2 * rad2 * t;
            hd_rbflobe *o = &out->rbfa[n++];
            o->peak = (float)(a->peak * mv * out->vtotal * rad0 * rad0 / rad2);
            o->chroma = a->chroma;
            o->crad = (uint16_t)hd_rbf_ang2r(sqrt(rad2));
            int pos[2];
            hd_rbf_pos(r, geodesic(v0, hd_rbf_ovec(r, bb->gx, bb->gy), t), pos);
            o->gx = (uint16_t)pos[0];
            o->gy = (uint16_t)pos[1];
        }
    }
    out->nrbf = (int)n;
    out->vtotal *= d0->vtotal;
    return HD_OK;
}

static const hd_rbfmig *find_edge(const hd_rbfrep *r, int a, int b)
{
    for (int k = r->edge_start[a]; k < r->edge_start[a + 1]; k++) {
        const hd_rbfmig *m = &r->mig[r->edge_list[k]];
        if ((m->from == a && m->to == b) || (m->from == b && m->to == a)) return m;
    }
    return NULL;
}

static int on_edge(const hd_rbfrep *r, const hd_rbfmig *m, hd_vec3 v)
{
    double ca = hd_vdot(r->dsf[m->from].invec, v);
    if (ca <= 0) return 0;
    if (ca >= 1.) return 1;
    double cb = hd_vdot(r->dsf[m->to].invec, v);
    if (cb <= 0) return 0;
    if (cb >= 1.) return 1;
    double cab = ca * cb - sqrt((1. - ca * ca) * (1. - cb * cb));
    if (cab <= 0) return 0;
    double cc = hd_vdot(r->dsf[m->from].invec, r->dsf[m->to].invec);
    return cc - cab < .0002;
}

static int in_tri(hd_vec3 a, hd_vec3 b, hd_vec3 c, hd_vec3 p)
{
    int s1 = hd_vdot(p, hd_vcross(a, b)) > 0;
    int s2 = hd_vdot(p, hd_vcross(b, c)) > 0;
    if (s1 != s2) return 0;
    return s2 == (hd_vdot(p, hd_vcross(c, a)) > 0);
}

/* the DSF at the other end of edge m from DSF a */
static int opp(const hd_rbfrep *r, int a, int m) { return r->mig[m].from == a ? r->mig[m].to : r->mig[m].from; }

/* 1 when the triangle a b c turns clockwise seen from outside the sphere */
static int rev_tri(hd_vec3 a, hd_vec3 b, hd_vec3 c)
{
    return hd_vdot(hd_vcross(hd_vsub(b, a), hd_vsub(c, b)), b) < 0;
}

/* The search for the edge or triangle holding a direction is a walk over
 * the mesh that gives the same answer as Radiance's where triangles
 * overlap (a mesh over measured directions need not be a proper
 * triangulation): it starts at the oldest edge (the file's last), takes at
 * most one triangle on either side of an edge (the last third vertex found
 * on that side), and goes through the edges of a vertex oldest first, as
 * Radiance's lists hold them after reading a file. */
typedef struct mesh_walk {
    const hd_rbfrep *r;
    hd_vec3 v;
    unsigned char *seen;     /* per edge */
    int m[3];                /* result: an edge, or a triangle's three edges */
} mesh_walk;

static int walk_edge(mesh_walk *w, int m)
{
    const hd_rbfrep *r = w->r;
    if (w->seen[m]) return 0;
    w->seen[m] = 1;
    if (on_edge(r, &r->mig[m], w->v)) {
        w->m[0] = m;
        return 1;
    }
    int a = r->mig[m].from, b = r->mig[m].to, tv[2] = {-1, -1};
    for (int k = r->edge_start[a]; k < r->edge_start[a + 1]; k++) {
        int e1 = r->edge_list[k];
        if (e1 == m) continue;
        int c = opp(r, a, e1);
        for (int q = r->edge_start[c]; q < r->edge_start[c + 1]; q++)
            if (opp(r, c, r->edge_list[q]) == b) {
                tv[rev_tri(r->dsf[a].invec, r->dsf[b].invec, r->dsf[c].invec)] = c;
                break;
            }
    }
    if (tv[0] < 0 && tv[1] < 0) return 0;
    int se[2], de[2];
    for (int i = 1; i >= 0; i--) {
        se[i] = de[i] = -1;
        if (tv[i] < 0) continue;
        for (int q = r->edge_start[tv[i]]; q < r->edge_start[tv[i] + 1]; q++) {
            int e = r->edge_list[q], o = opp(r, tv[i], e);
            if (o == a) { if (!w->seen[e]) se[i] = e; }
            else if (o == b && !w->seen[e]) de[i] = e;
        }
    }
    for (int i = 1; i >= 0; i--) {
        if (se[i] >= 0 && walk_edge(w, se[i])) return 1;
        if (de[i] >= 0 && walk_edge(w, de[i])) return 1;
        if (se[i] < 0 || de[i] < 0) continue;
        if (in_tri(r->dsf[a].invec, r->dsf[b].invec, r->dsf[tv[i]].invec, w->v)) {
            w->m[0] = m;
            w->m[1] = se[i];
            w->m[2] = de[i];
            return 1;
        }
    }
    return 0;
}

/* default specular lobe for directions outside the mesh */
static hd_status spec_dsf(const hd_rbfrep *r, hd_vec3 in, hd_rbfdsf *out)
{
    memset(out, 0, sizeof *out);
    out->invec = in;
    if ((r->input_orient > 0) != (in.z > 0)) return HD_OK;
    if (r->spec_val <= r->bsdf_min || r->spec_rad <= 0) return HD_OK;
    out->rbfa = hd_malloc(sizeof *out->rbfa);
    if (!out->rbfa) return HD_ERR_NOMEM;
    hd_vec3 o = hd_v3(-in.x, -in.y, in.z * (2 * (r->input_orient == r->output_orient) - 1));
    int pos[2];
    hd_rbf_pos(r, o, pos);
    out->nrbf = 1;
    out->rbfa[0].peak = (float)(r->spec_val * hd_rbf_cosf(o.z));
    out->rbfa[0].chroma = 49750;
    out->rbfa[0].crad = (uint16_t)hd_rbf_ang2r(r->spec_rad);
    out->rbfa[0].gx = (uint16_t)pos[0];
    out->rbfa[0].gy = (uint16_t)pos[1];
    out->vtotal = hd_rbf_lobe_volume(r, out->rbfa);
    return HD_OK;
}

static void rotate_dsf(const hd_rbfrep *r, hd_rbfdsf *d, hd_vec3 in)
{
    double phi = atan2(in.y, in.x) - atan2(d->invec.y, d->invec.x);
    if (cos(phi) < 1. - RBF_TINY) {
        double c = cos(phi), s = sin(phi);
        for (int n = 0; n < d->nrbf; n++) {
            hd_vec3 v = hd_rbf_ovec(r, d->rbfa[n].gx, d->rbfa[n].gy);
            hd_vec3 w = hd_v3(v.x * c - v.y * s, v.x * s + v.y * c, v.z);
            int pos[2];
            hd_rbf_pos(r, w, pos);
            d->rbfa[n].gx = (uint16_t)pos[0];
            d->rbfa[n].gy = (uint16_t)pos[1];
        }
    }
    d->invec = in;
}

static hd_status tri_advect(const hd_rbfrep *r, const hd_rbfmig *m0, const hd_rbfmig *m1, const hd_rbfmig *m2,
                            hd_vec3 sv, int lobe_lim, hd_rbfdsf *out)
{
    const hd_rbfdsf *A = &r->dsf[m0->from], *B = &r->dsf[m0->to], *C = &r->dsf[m1->to];
    hd_vec3 v0 = hd_vnorm(hd_vcross(A->invec, C->invec));
    hd_vec3 v2 = hd_vnorm(hd_vcross(B->invec, C->invec));
    hd_vec3 v1 = hd_vnorm(hd_vcross(sv, C->invec));
    double s = acos_c(hd_vdot(v0, v1)) / acos_c(hd_vdot(v0, v2));
    v1 = geodesic(A->invec, B->invec, s);
    double t = acos_c(hd_vdot(v1, sv)) / acos_c(hd_vdot(v1, C->invec));
    int na = A->nrbf, nc = C->nrbf;
    double cth = RBF_TINY;
    size_t n;
    unsigned char *mark = hd_calloc((size_t)(nc ? nc : 1), 1);
    if (!mark) return HD_ERR_NOMEM;
    for (;;) {
        n = 0;
        for (int i = 0; i < na; i++)
            for (int a = m0->rs[i]; a < m0->rs[i + 1]; a++) {
                int j = m0->ci[a];
                if (!(m0->cv[a] > cth)) continue;
                size_t cnt = 0;
                for (int b = m1->rs[j]; b < m1->rs[j + 1]; b++) {
                    int k = m1->ci[b];
                    if (m1->cv[b] > cth && !mark[k]) { mark[k] = 1; cnt++; }
                }
                for (int c = m2->rs[i]; c < m2->rs[i + 1]; c++) {
                    int k = m2->ci[c];
                    if (m2->cv[c] > cth && !mark[k]) { mark[k] = 1; cnt++; }
                }
                for (int b = m1->rs[j]; b < m1->rs[j + 1]; b++) mark[m1->ci[b]] = 0;
                for (int c = m2->rs[i]; c < m2->rs[i + 1]; c++) mark[m2->ci[c]] = 0;
                n += cnt;
            }
        if (lobe_lim <= 0 || n <= (size_t)lobe_lim) break;
        cth = cth * 2. + 10. * RBF_TINY;
    }
    memset(out, 0, sizeof *out);
    out->rbfa = hd_malloc_array(n ? n : 1, sizeof *out->rbfa);
    /* wk: the targets k of one (i, j); wb, wc: rows j of m1 and i of m2 spread out (0 elsewhere) */
    int *wk = hd_malloc_array((size_t)(nc ? nc : 1), sizeof(int));
    float *wb = hd_calloc((size_t)(nc ? nc : 1), sizeof(float)), *wc = hd_calloc((size_t)(nc ? nc : 1), sizeof(float));
    if (!out->rbfa || !wk || !wb || !wc) { free(mark); free(wk); free(wb); free(wc); return HD_ERR_NOMEM; }
    out->invec = sv;
    double mbf = s * B->vtotal / A->vtotal * (1. - t + t * C->vtotal / B->vtotal);
    double mcf = (1. - s) * (1. - t + t * C->vtotal / A->vtotal);
    n = 0;
    for (int i = 0; i < na; i++) {
        const hd_rbflobe *la = &A->rbfa[i];
        double r0 = hd_rbf_r2ang(la->crad);
        hd_vec3 d0 = hd_rbf_ovec(r, la->gx, la->gy);
        for (int a = m0->rs[i]; a < m0->rs[i + 1]; a++) {
            int j = m0->ci[a];
            float ma = m0->cv[a];
            if (!(ma > cth)) continue;
            const hd_rbflobe *lb = &B->rbfa[j];
            double sr2 = hd_rbf_r2ang(lb->crad);
            sr2 = (1. - s) * (1. - t) * r0 * r0 + s * (1. - t) * sr2 * sr2;
            hd_vec3 d1 = geodesic(d0, hd_rbf_ovec(r, lb->gx, lb->gy), s);
            /* targets k: union of row j of m1 and row i of m2 */
            int klist_n = 0;
            for (int b = m1->rs[j]; b < m1->rs[j + 1]; b++) {
                int k = m1->ci[b];
                wb[k] = m1->cv[b];
                if (m1->cv[b] > cth && !mark[k]) { mark[k] = 1; wk[klist_n++] = k; }
            }
            for (int c = m2->rs[i]; c < m2->rs[i + 1]; c++) {
                int k = m2->ci[c];
                wc[k] = m2->cv[c];
                if (m2->cv[c] > cth && !mark[k]) { mark[k] = 1; wk[klist_n++] = k; }
            }
            for (int q = 0; q < klist_n; q++) {
                int k = wk[q];
                mark[k] = 0;
                float mb = wb[k], mc = wc[k];
                const hd_rbflobe *lc = &C->rbfa[k];
                double rad2 = hd_rbf_r2ang(lc->crad);
                rad2 = sr2 + t * rad2 * rad2;
                hd_rbflobe *o = &out->rbfa[n++];
                o->peak = (float)(la->peak * ma * (mb * mbf + mc * mcf) * r0 * r0 / rad2);
                o->chroma = la->chroma;
                o->crad = (uint16_t)hd_rbf_ang2r(sqrt(rad2));
                int pos[2];
                hd_rbf_pos(r, geodesic(d1, hd_rbf_ovec(r, lc->gx, lc->gy), t), pos);
                o->gx = (uint16_t)pos[0];
                o->gy = (uint16_t)pos[1];
            }
            for (int b = m1->rs[j]; b < m1->rs[j + 1]; b++) wb[m1->ci[b]] = 0;
            for (int c = m2->rs[i]; c < m2->rs[i + 1]; c++) wc[m2->ci[c]] = 0;
        }
    }
    free(mark);
    free(wk);
    free(wb);
    free(wc);
    out->nrbf = (int)n;
    out->vtotal = A->vtotal * (mbf + mcf);
    return HD_OK;
}

hd_status hd_rbf_advect(const hd_rbfrep *r, hd_vec3 in, int lobe_lim, hd_rbfdsf *out)
{
    memset(out, 0, sizeof *out);
    if (r->single_plane) {
        for (int k = 0; k < r->ndsf; k++) {
            const hd_rbfdsf *d = &r->dsf[k];
            if (r->input_orient * d->invec.z < r->input_orient * in.z - RBF_TINY) break;
            if (k + 1 < r->ndsf && r->input_orient * r->dsf[k + 1].invec.z < r->input_orient * in.z + RBF_TINY) {
                const hd_rbfmig *m = find_edge(r, k, k + 1);
                if (!m) break;
                const hd_rbfdsf *nx = &r->dsf[k + 1];
                hd_vec3 sv = in;
                double nf = 1. - nx->invec.z * nx->invec.z;
                if (nf > RBF_TINY) {
                    nf = sqrt((1. - in.z * in.z) / nf);
                    sv.x = nf * nx->invec.x;
                    sv.y = nf * nx->invec.y;
                }
                hd_status st = hd_rbf_edge_advect(r, m, sv, lobe_lim, out);
                if (st != HD_OK) return st;
                rotate_dsf(r, out, in);
                return HD_OK;
            }
        }
        return spec_dsf(r, in, out);
    }
    hd_vec3 sv = in;
    int sym = hd_rbf_use_symmetry(r, &sv);
    /* the edge the direction lies on or the triangle that holds it, as
     * Radiance's walk finds them (a triangle whose edges do not run from
     * its lower to its higher vertices is not used: Radiance's neither) */
    mesh_walk w = {r, sv, hd_calloc((size_t)(r->nmig ? r->nmig : 1), 1), {-1, -1, -1}};
    if (!w.seen) return HD_ERR_NOMEM;
    int found = r->nmig > 0 && walk_edge(&w, 0);
    free(w.seen);
    if (!found) return spec_dsf(r, in, out);
    hd_status st;
    if (w.m[1] < 0)
        st = hd_rbf_edge_advect(r, &r->mig[w.m[0]], sv, lobe_lim, out);
    else {
        /* standard order: vertices a < b < c, edges a-b, b-c, a-c */
        const hd_rbfmig *e[3] = {&r->mig[w.m[0]], &r->mig[w.m[1]], &r->mig[w.m[2]]};
        int v[3] = {e[0]->from, e[0]->to, opp(r, e[0]->from, w.m[1])};   /* m[1] joins the third to from */
        int lo = v[0], hi = v[0];
        for (int i = 1; i < 3; i++) { if (v[i] < lo) lo = v[i]; if (v[i] > hi) hi = v[i]; }
        int mid = v[0] + v[1] + v[2] - lo - hi;
        const hd_rbfmig *ab = NULL, *bc = NULL, *ac = NULL;
        for (int i = 0; i < 3; i++) {
            if (e[i]->from == lo && e[i]->to == mid) ab = e[i];
            if (e[i]->from == mid && e[i]->to == hi) bc = e[i];
            if (e[i]->from == lo && e[i]->to == hi) ac = e[i];
        }
        if (!ab || !bc || !ac) return spec_dsf(r, in, out);
        st = tri_advect(r, ab, bc, ac, sv, lobe_lim, out);
    }
    if (st == HD_OK) hd_rbf_mirror_dsf(r, out, sym);
    return st;
}

/* heliodon — rfluxmtx sender/receiver files and sender sampling (see rfluxmtx.h). */
#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/rfluxmtx.h"
#include "heliodon/scene.h"

#define GOLDEN 0.61803398874989484820

static hd_status parse_up(const char *v, hd_vec3 *up, const char *where)
{
    double sign = 1;
    const char *s = v;
    if (*s == '+' || *s == '-') {
        if (*s == '-') sign = -1;
        if (s[1] && !s[2] && strchr("XYZxyz", s[1])) s++;
        else goto vec;
    }
    if (s[0] && !s[1] && strchr("XYZxyz", s[0])) {
        int k = tolower((unsigned char)s[0]) - 'x';
        *up = hd_v3(k == 0 ? sign : 0, k == 1 ? sign : 0, k == 2 ? sign : 0);
        return HD_OK;
    }
vec:
    {
        double x[3];
        char *end;
        const char *p = v;
        for (int i = 0; i < 3; i++) {
            x[i] = strtod(p, &end);
            if (end == p || (i < 2 && *end != ',') || (i == 2 && *end)) goto bad;
            p = end + 1;
        }
        *up = hd_v3(x[0], x[1], x[2]);
        if (!(hd_vlen(*up) > 0)) goto bad;
        return HD_OK;
    }
bad:
    return hd_fail(HD_ERR_FORMAT, "%s: u=%s: expected X, Y, Z, -X, ... or ux,uy,uz", where, v);
}

static hd_status parse_basis(hd_rfparams *p, const char *v, const char *where)
{
    const char *s = v;
    p->rhs = 1;
    if (*s == '-') { p->rhs = -1; s++; }
    else if (*s == '+') s++;
    if (!strcmp(s, "u")) { p->basis = HD_HB_UNIFORM; return HD_OK; }
    if (!strcmp(s, "kf") || !strcmp(s, "k") || !strcmp(s, "k1")) { p->basis = HD_HB_KLEMS; p->klems = HD_KLEMS_FULL; return HD_OK; }
    if (!strcmp(s, "kh") || !strcmp(s, "k2")) { p->basis = HD_HB_KLEMS; p->klems = HD_KLEMS_HALF; return HD_OK; }
    if (!strcmp(s, "kq") || !strcmp(s, "k4")) { p->basis = HD_HB_KLEMS; p->klems = HD_KLEMS_QUARTER; return HD_OK; }
    if (s[0] == 'r' || s[0] == 't') {
        long mf = 1;
        if (s[1]) {
            char *end;
            mf = strtol(s + 1, &end, 10);
            if (*end || mf < 1 || mf > HD_SKY_MAXMF) goto bad;
        }
        p->basis = HD_HB_REINHART;
        p->mf = (int)mf;
        return HD_OK;
    }
    if (!strncmp(s, "sc", 2) || !strcmp(s, "cie"))
        return hd_fail(HD_ERR_UNSUPPORTED, "%s: h=%s: Shirley-Chiu and CIE bases are not supported (use u, kf, kh, kq or rN)", where, v);
bad:
    return hd_fail(HD_ERR_FORMAT, "%s: h=%s: unknown basis (expected u, kf, kh, kq or rN)", where, v);
}

hd_status hd_rfparams_parse(hd_rfparams *p, const char *text, const char *where)
{
    const char *s = text;
    for (;;) {
        while (isspace((unsigned char)*s)) s++;
        if (!*s) return HD_OK;
        char key = *s;
        if (!s[0] || s[1] != '=')
            return hd_fail(HD_ERR_FORMAT, "%s: #@rfluxmtx: expected h=, u= or o= at '%s'", where, s);
        s += 2;
        char val[1024];
        size_t n = 0;
        char q = 0;
        if (*s == '"' || *s == '\'') q = *s++;
        while (*s && (q ? *s != q : !isspace((unsigned char)*s))) {
            if (n + 1 >= sizeof val) return hd_fail(HD_ERR_FORMAT, "%s: #@rfluxmtx: value too long", where);
            val[n++] = *s++;
        }
        if (q) {
            if (*s != q) return hd_fail(HD_ERR_FORMAT, "%s: #@rfluxmtx: unterminated quote", where);
            s++;
        }
        val[n] = 0;
        hd_status st = HD_OK;
        switch (key) {
        case 'h': st = parse_basis(p, val, where); break;
        case 'u': st = parse_up(val, &p->up, where); p->has_up = st == HD_OK; break;
        case 'o': hd_strlcpy(p->out, val, sizeof p->out); break;
        default:
            return hd_fail(HD_ERR_FORMAT, "%s: #@rfluxmtx: unknown parameter %c= (expected h=, u= or o=)", where, key);
        }
        if (st != HD_OK) return st;
    }
}

/* ---- reading sender / receiver files ---- */
typedef struct lexer {
    const char *t;
    size_t i, n;
    unsigned long line;
    const char *path;
} lexer;

/* next word; handles comment lines (#@rfluxmtx applied to params) */
static hd_status next_word(lexer *L, char *w, size_t cap, int *got, hd_rfparams *params, int *ncomm)
{
    *got = 0;
    for (;;) {
        while (L->i < L->n && isspace((unsigned char)L->t[L->i])) {
            if (L->t[L->i] == '\n') L->line++;
            L->i++;
        }
        if (L->i >= L->n) return HD_OK;
        if (L->t[L->i] == '#') {
            size_t e = L->i;
            while (e < L->n && L->t[e] != '\n') e++;
            size_t len = e - L->i;
            if (len >= 10 && !strncmp(L->t + L->i, "#@rfluxmtx", 10) && params) {
                char buf[2048], where[300];
                if (len >= sizeof buf) return hd_fail(HD_ERR_FORMAT, "%s:%lu: #@rfluxmtx line too long", L->path, L->line);
                memcpy(buf, L->t + L->i + 10, len - 10);
                buf[len - 10] = 0;
                snprintf(where, sizeof where, "%s:%lu", L->path, L->line);
                hd_status st = hd_rfparams_parse(params, buf, where);
                if (st != HD_OK) return st;
                (*ncomm)++;
            }
            L->i = e;
            continue;
        }
        if (L->t[L->i] == '!')
            return hd_fail(HD_ERR_UNSUPPORTED, "%s:%lu: in-line commands are not supported in rfluxmtx sender/receiver files",
                           L->path, L->line);
        size_t n = 0;
        while (L->i < L->n && !isspace((unsigned char)L->t[L->i])) {
            if (n + 1 >= cap) return hd_fail(HD_ERR_FORMAT, "%s:%lu: word too long", L->path, L->line);
            w[n++] = L->t[L->i++];
        }
        w[n] = 0;
        *got = 1;
        return HD_OK;
    }
}

void hd_rffile_free(hd_rffile *f)
{
    for (int i = 0; i < f->n; i++) free(f->s[i].r);
    free(f->s);
    memset(f, 0, sizeof *f);
}

hd_status hd_rffile_read(hd_rffile *f, const char *path)
{
    memset(f, 0, sizeof *f);
    char *text = NULL;
    size_t len = 0;
    hd_status st = hd_file_read_all(path, (unsigned char **)&text, &len);
    if (st != HD_OK) return st;
    lexer L = {text, 0, len, 1, path};
    hd_rfparams cur;
    memset(&cur, 0, sizeof cur);
    cur.rhs = 1;
    char w[4][256];
    for (;;) {
        int got;
        st = next_word(&L, w[0], sizeof w[0], &got, &cur, &f->ncomments);
        if (st != HD_OK) goto fail;
        if (!got) break;
        unsigned long line = L.line;
        for (int k = 1; k < 3; k++) {
            st = next_word(&L, w[k], sizeof w[k], &got, NULL, NULL);
            if (st != HD_OK) goto fail;
            if (!got) { st = hd_fail(HD_ERR_FORMAT, "%s:%lu: incomplete primitive", path, line); goto fail; }
        }
        int type = hd_type_from_name(w[1]);
        if (type < 0) { st = hd_fail(HD_ERR_FORMAT, "%s:%lu: unknown primitive type '%s'", path, line, w[1]); goto fail; }
        double *r = NULL;
        long cnt[3];
        for (int part = 0; part < 3; part++) {
            st = next_word(&L, w[3], sizeof w[3], &got, NULL, NULL);
            if (st != HD_OK) goto fail;
            if (!got || hd_parse_long(w[3], &cnt[part]) || cnt[part] < 0 || cnt[part] > 10000000) {
                free(r);
                st = hd_fail(HD_ERR_FORMAT, "%s:%lu: %s %s: expected an argument count", path, line, w[1], w[2]);
                goto fail;
            }
            if (part == 2) {
                r = hd_malloc_array((size_t)(cnt[2] ? cnt[2] : 1), sizeof *r);
                if (!r) { st = HD_ERR_NOMEM; goto fail; }
            }
            for (long k = 0; k < cnt[part]; k++) {
                st = next_word(&L, w[3], sizeof w[3], &got, NULL, NULL);
                if (st != HD_OK) { free(r); goto fail; }
                if (!got) { free(r); st = hd_fail(HD_ERR_FORMAT, "%s:%lu: %s %s: missing arguments", path, line, w[1], w[2]); goto fail; }
                if (part == 2 && hd_parse_double(w[3], &r[k])) {
                    free(r);
                    st = hd_fail(HD_ERR_FORMAT, "%s:%lu: %s %s: bad real argument '%s'", path, line, w[1], w[2], w[3]);
                    goto fail;
                }
            }
        }
        if (hd_type_class_of((hd_prim_type)type) != HD_CLASS_SURFACE) { free(r); continue; }
        if (type != HD_T_POLYGON && type != HD_T_RING && type != HD_T_SOURCE) {
            free(r);
            st = hd_fail(HD_ERR_UNSUPPORTED, "%s:%lu: %s %s: rfluxmtx senders/receivers must be polygons, rings or sources",
                         path, line, w[1], w[2]);
            goto fail;
        }
        int need = type == HD_T_RING ? 8 : type == HD_T_SOURCE ? 4 : -1;
        if ((need > 0 && cnt[2] != need) || (type == HD_T_POLYGON && (cnt[2] < 9 || cnt[2] % 3))) {
            free(r);
            st = hd_fail(HD_ERR_FORMAT, "%s:%lu: %s %s: wrong number of real arguments (%ld)", path, line, w[1], w[2], cnt[2]);
            goto fail;
        }
        hd_rfsurf *ns = hd_realloc_array(f->s, (size_t)f->n + 1, sizeof *ns);
        if (!ns) { free(r); st = HD_ERR_NOMEM; goto fail; }
        f->s = ns;
        hd_rfsurf *s = &f->s[f->n++];
        memset(s, 0, sizeof *s);
        hd_strlcpy(s->mod, w[0], sizeof s->mod);
        s->type = type;
        s->r = r;
        s->nr = (int)cnt[2];
        s->params = cur;
        if (snprintf(s->where, sizeof s->where, "%s:%lu: %s %s", path, line, w[1], w[2]) >= (int)sizeof s->where)
            s->where[sizeof s->where - 1] = 0;
    }
    free(text);
    if (f->ncomments == 0) {
        hd_rffile_free(f);
        return hd_fail(HD_ERR_FORMAT, "%s: no #@rfluxmtx control comment (expected e.g. '#@rfluxmtx h=kf u=Z' before the surfaces)", path);
    }
    if (f->n == 0) {
        hd_rffile_free(f);
        return hd_fail(HD_ERR_FORMAT, "%s: no surfaces", path);
    }
    return HD_OK;
fail:
    free(text);
    hd_rffile_free(f);
    return st;
}

/* area-weighted normal of surfaces [a,b) */
static hd_status group_normal(const hd_rffile *f, int a, int b, hd_vec3 *n, double *area)
{
    hd_vec3 sum = hd_v3(0, 0, 0);
    double at = 0;
    for (int i = a; i < b; i++) {
        const hd_rfsurf *s = &f->s[i];
        if (s->type == HD_T_POLYGON) {
            int nv = s->nr / 3;
            hd_vec3 *v = hd_malloc_array((size_t)nv, sizeof *v);
            if (!v) return HD_ERR_NOMEM;
            for (int k = 0; k < nv; k++) v[k] = hd_v3(s->r[3 * k], s->r[3 * k + 1], s->r[3 * k + 2]);
            double ar;
            hd_vec3 nn = hd_polygon_normal(v, (uint32_t)nv, &ar);
            free(v);
            sum = hd_vadd(sum, hd_vscale(nn, ar));
            at += ar;
        } else if (s->type == HD_T_RING) {
            hd_vec3 nn = hd_vnorm(hd_v3(s->r[3], s->r[4], s->r[5]));
            double ar = HD_PI * fabs(s->r[7] * s->r[7] - s->r[6] * s->r[6]);
            sum = hd_vadd(sum, hd_vscale(nn, ar));
            at += ar;
        } else {
            hd_vec3 d = hd_v3(s->r[0], s->r[1], s->r[2]);
            if (!(hd_vlen(d) > 0)) return hd_fail(HD_ERR_FORMAT, "%s: zero direction", s->where);
            sum = hd_vadd(sum, hd_vneg(hd_vnorm(d)));
            at += 1;
        }
    }
    double l = hd_vlen(sum);
    if (!(l > 1e-12 * (at > 0 ? at : 1)))
        return hd_fail(HD_ERR_FORMAT, "%s: the surfaces' normals cancel out (no average orientation)", f->s[a].where);
    *n = hd_vscale(sum, 1 / l);
    if (area) *area = at;
    return HD_OK;
}

static hd_vec3 default_up(const hd_rfparams *p, hd_vec3 n)
{
    if (p->has_up) return p->up;
    return fabs(n.z) >= 0.7 ? hd_v3(0, 1, 0) : hd_v3(0, 0, 1);
}

/* Klems and Reinhart receivers through the standard .cal files, as
 * Radiance's rfluxmtx hands them to rcontrib: -f klems_full.cal -p RHS=+1
 * -b "kbin(N,U)" -bn Nkbins (khbin/kqbin for half/quarter), or -f
 * reinhartb.cal -p MF=..,rNx=..,Ux=..,RHS=.. -b rbin -bn Nrbins (JTR with
 * -bj).  Vectors are written with all their digits (Radiance: %g). */
static hd_status std_bins(hd_binfn *b, const hd_rfparams *p, hd_vec3 n, hd_vec3 up, double jtr)
{
    const char *file, *count;
    char params[512], expr[512];
    char sign = p->rhs < 0 ? '-' : '+';
    int k = 0;
    if (p->basis == HD_HB_KLEMS) {
        static const char *files[] = {"klems_full.cal", "klems_half.cal", "klems_quarter.cal"};
        static const char *fns[] = {"kbin", "khbin", "kqbin"};
        static const char *counts[] = {"Nkbins", "Nkhbins", "Nkqbins"};
        int i = p->klems == HD_KLEMS_HALF ? 1 : p->klems == HD_KLEMS_QUARTER ? 2 : 0;
        file = files[i];
        count = counts[i];
        k = snprintf(params, sizeof params, "RHS=%c1", sign);
        snprintf(expr, sizeof expr, "%s(%.17g,%.17g,%.17g,%.17g,%.17g,%.17g)", fns[i], n.x, n.y, n.z, up.x, up.y, up.z);
    } else {
        file = "reinhartb.cal";
        count = "Nrbins";
        k = snprintf(params, sizeof params, "MF=%d,rNx=%.17g,rNy=%.17g,rNz=%.17g,Ux=%.17g,Uy=%.17g,Uz=%.17g,RHS=%c1",
                     p->mf, n.x, n.y, n.z, up.x, up.y, up.z, sign);
        snprintf(expr, sizeof expr, "rbin");
    }
    if (jtr > 0) snprintf(params + k, sizeof params - (size_t)k, ",JTR=%.17g", jtr);
    hd_calctx ctx;
    hd_calctx_init(&ctx);
    hd_status st = hd_calctx_file(&ctx, file);
    if (!st) st = hd_binfn_parse(b, &ctx, params, expr, count);
    hd_calctx_free(&ctx);
    if (!st) {
        size_t n = strlen(file) + strlen(params) + strlen(count) + strlen(expr) + 32;
        if (!(b->rcargs = hd_malloc(n))) { hd_binfn_free(b); return HD_ERR_NOMEM; }
        const char *q = strpbrk(expr, "()*; ") ? "'" : "";    /* quoted for a shell when needed */
        snprintf(b->rcargs, n, "-f %s -p %s -bn %s -b %s%s%s", file, params, count, q, expr, q);
    }
    return st;
}

hd_status hd_rf_receivers(const hd_rffile *f, double jtr, hd_contrib *c)
{
    int i = 0;
    while (i < f->n) {
        int j = i + 1;
        while (j < f->n && !strcmp(f->s[j].mod, f->s[i].mod)) j++;
        for (int k = j; k < f->n; k++)
            if (!strcmp(f->s[k].mod, f->s[i].mod))
                return hd_fail(HD_ERR_FORMAT, "%s: receiver modifier '%s' is used again after other receivers "
                               "(surfaces of one receiver must be contiguous)", f->s[k].where, f->s[i].mod);
        const hd_rfparams *p = &f->s[i].params;
        if (p->basis == HD_HB_NONE)
            return hd_fail(HD_ERR_FORMAT, "%s: no h= basis given for receiver '%s'", f->s[i].where, f->s[i].mod);
        int allsrc = 1;
        for (int k = i; k < j; k++) if (f->s[k].type != HD_T_SOURCE) allsrc = 0;
        hd_vec3 n;
        hd_status st = group_normal(f, i, j, &n, NULL);
        if (st != HD_OK) return st;
        if (p->basis != HD_HB_UNIFORM)
            for (int k = i; k < j; k++)
                if (f->s[k].type == HD_T_SOURCE && fabs(f->s[k].r[3] - 180) > 1e-6)
                    return hd_fail(HD_ERR_FORMAT, "%s: a source receiver must be 180 degrees unless h=u", f->s[k].where);
        hd_cmod *nm = hd_realloc_array(c->mods, (size_t)c->nmods + 1, sizeof *nm);
        if (!nm) return HD_ERR_NOMEM;
        c->mods = nm;
        hd_cmod *m = &c->mods[c->nmods];
        memset(m, 0, sizeof *m);
        hd_strlcpy(m->name, f->s[i].mod, sizeof m->name);
        hd_vec3 up = default_up(p, n);
        switch (p->basis) {
        case HD_HB_UNIFORM:
            memset(&m->bin, 0, sizeof m->bin);
            m->bin.kind = allsrc ? HD_BIN_CONST : HD_BIN_HEMI;
            m->bin.n = n;
            m->bin.nbins = 1;
            break;
        case HD_HB_KLEMS:
        case HD_HB_REINHART:
            st = std_bins(&m->bin, p, n, up, jtr);
            break;
        default:
            break;
        }
        if (st != HD_OK) return hd_fail_context(st, "%s", f->s[i].where);
        if (p->out[0]) {
            m->outspec = hd_strdup(p->out);
            if (!m->outspec) { hd_binfn_free(&m->bin); return HD_ERR_NOMEM; }
        }
        c->nmods++;
        i = j;
    }
    return HD_OK;
}

/* ---- sender sampling ---- */
typedef struct tri { hd_vec3 a, b, c; double cum; } tri;
typedef struct ringpart { hd_vec3 c, n; double r0, r1; double cum; } ringpart;

struct hd_rfsender {
    hd_rfparams p;
    hd_vec3 u, v, n;
    int nbins;
    int nsamp;
    uint64_t seed;
    hd_klems_basis kb;
    hd_skybasis sky;
    int has_sky;
    /* emitting area: triangles then ring pieces, cumulative areas */
    tri *t;
    int nt;
    ringpart *rp;
    int nrp;
    double total;
};

void hd_rf_sender_free(hd_rfsender *s)
{
    if (!s) return;
    if (s->has_sky) hd_skybasis_free(&s->sky);
    free(s->t);
    free(s->rp);
    free(s);
}

int hd_rf_sender_nbins(const hd_rfsender *s) { return s->nbins; }

void hd_rf_sender_frame(const hd_rfsender *s, hd_vec3 *u, hd_vec3 *v, hd_vec3 *n)
{
    *u = s->u;
    *v = s->v;
    *n = s->n;
}

hd_status hd_rf_sender_create(hd_rfsender **out, const hd_rffile *f, int nsamp, uint64_t seed)
{
    hd_rfsender *s = hd_calloc(1, sizeof *s);
    if (!s) return HD_ERR_NOMEM;
    hd_status st = HD_OK;
    s->p = f->s[0].params;
    s->nsamp = nsamp;
    s->seed = seed;
    for (int i = 0; i < f->n; i++) {
        if (f->s[i].type == HD_T_SOURCE) { st = hd_fail(HD_ERR_FORMAT, "%s: a source cannot be a sender", f->s[i].where); goto fail; }
        if (f->s[i].params.basis != s->p.basis || f->s[i].params.mf != s->p.mf || f->s[i].params.klems != s->p.klems) {
            st = hd_fail(HD_ERR_FORMAT, "%s: all sender surfaces must share one basis", f->s[i].where);
            goto fail;
        }
    }
    if (s->p.basis == HD_HB_NONE) { st = hd_fail(HD_ERR_FORMAT, "%s: no h= basis given for the sender", f->s[0].where); goto fail; }
    st = group_normal(f, 0, f->n, &s->n, NULL);
    if (st != HD_OK) goto fail;
    hd_vec3 up = default_up(&s->p, s->n);
    hd_vec3 u = hd_vcross(up, s->n);
    if (!(hd_vlen(u) > 1e-9)) { st = hd_fail(HD_ERR_FORMAT, "%s: sender up vector is parallel to its normal", f->s[0].where); goto fail; }
    s->u = hd_vnorm(u);
    s->v = hd_vcross(s->n, s->u);
    if (s->p.rhs < 0) s->u = hd_vneg(s->u);
    switch (s->p.basis) {
    case HD_HB_UNIFORM: s->nbins = 1; break;
    case HD_HB_KLEMS: hd_klems_standard(&s->kb, s->p.klems); s->nbins = s->kb.nbins; break;
    case HD_HB_REINHART:
        st = hd_skybasis_init(&s->sky, s->p.mf);
        if (st != HD_OK) goto fail;
        s->has_sky = 1;
        s->nbins = s->sky.nbins - 1;
        break;
    default: break;
    }
    /* area elements */
    for (int i = 0; i < f->n; i++) {
        const hd_rfsurf *fs = &f->s[i];
        if (fs->type == HD_T_POLYGON) {
            uint32_t nv = (uint32_t)fs->nr / 3, ntri = 0;
            hd_vec3 *v = hd_malloc_array(nv, sizeof *v);
            uint32_t *ix = hd_malloc_array(3 * (size_t)nv, sizeof *ix);
            if (!v || !ix) { free(v); free(ix); st = HD_ERR_NOMEM; goto fail; }
            for (uint32_t k = 0; k < nv; k++) v[k] = hd_v3(fs->r[3 * k], fs->r[3 * k + 1], fs->r[3 * k + 2]);
            st = hd_polygon_triangulate(v, nv, ix, &ntri);
            if (st != HD_OK) { free(v); free(ix); st = hd_fail_context(st, "%s", fs->where); goto fail; }
            tri *nt = hd_realloc_array(s->t, (size_t)s->nt + ntri, sizeof *nt);
            if (!nt) { free(v); free(ix); st = HD_ERR_NOMEM; goto fail; }
            s->t = nt;
            for (uint32_t k = 0; k < ntri; k++) {
                tri *t = &s->t[s->nt++];
                t->a = v[ix[3 * k]];
                t->b = v[ix[3 * k + 1]];
                t->c = v[ix[3 * k + 2]];
                s->total += 0.5 * hd_vlen(hd_vcross(hd_vsub(t->b, t->a), hd_vsub(t->c, t->a)));
                t->cum = s->total;
            }
            free(v);
            free(ix);
        }
    }
    for (int i = 0; i < f->n; i++) {
        const hd_rfsurf *fs = &f->s[i];
        if (fs->type != HD_T_RING) continue;
        ringpart *nr = hd_realloc_array(s->rp, (size_t)s->nrp + 1, sizeof *nr);
        if (!nr) { st = HD_ERR_NOMEM; goto fail; }
        s->rp = nr;
        ringpart *r = &s->rp[s->nrp++];
        r->c = hd_v3(fs->r[0], fs->r[1], fs->r[2]);
        r->n = hd_vnorm(hd_v3(fs->r[3], fs->r[4], fs->r[5]));
        r->r0 = fmin(fs->r[6], fs->r[7]);
        r->r1 = fmax(fs->r[6], fs->r[7]);
        s->total += HD_PI * (r->r1 * r->r1 - r->r0 * r->r0);
        r->cum = s->total;
    }
    if (!(s->total > 0)) { st = hd_fail(HD_ERR_FORMAT, "%s: sender has zero area", f->s[0].where); goto fail; }
    *out = s;
    return HD_OK;
fail:
    hd_rf_sender_free(s);
    return st;
}

static hd_vec3 sample_origin(const hd_rfsender *s, double u0, double u1, double u2)
{
    double a = u0 * s->total;
    for (int i = 0; i < s->nt; i++) {
        if (a <= s->t[i].cum || (i == s->nt - 1 && s->nrp == 0)) {
            double su = sqrt(u1);
            double b0 = 1 - su, b1 = u2 * su;
            const tri *t = &s->t[i];
            return hd_vadd(hd_vadd(hd_vscale(t->a, b0), hd_vscale(t->b, b1)), hd_vscale(t->c, 1 - b0 - b1));
        }
    }
    for (int i = 0; i < s->nrp; i++) {
        if (a <= s->rp[i].cum || i == s->nrp - 1) {
            const ringpart *r = &s->rp[i];
            hd_vec3 e1, e2;
            hd_vbasis(r->n, &e1, &e2);
            double rr = sqrt(r->r0 * r->r0 + u1 * (r->r1 * r->r1 - r->r0 * r->r0)), ph = 2 * HD_PI * u2;
            return hd_vadd(r->c, hd_vadd(hd_vscale(e1, rr * cos(ph)), hd_vscale(e2, rr * sin(ph))));
        }
    }
    return s->t ? s->t[0].a : s->rp[0].c;
}

int hd_rf_sender_ray(void *vs, uint64_t k, hd_vec3 *org, hd_vec3 *dir)
{
    const hd_rfsender *s = vs;
    uint64_t bin = k / (uint64_t)s->nsamp, j = k % (uint64_t)s->nsamp;
    hd_rng rng;
    /* per-bin random shift of the stratified pattern, per-ray origin */
    hd_rng_init(&rng, s->seed ^ 0x5fe1d0c3a7b2e911ULL, bin);
    double s1 = hd_rng_uniform(&rng), s2 = hd_rng_uniform(&rng);
    hd_rng_init(&rng, s->seed ^ 0x2c9b17e4f0a3d685ULL, k);
    double r0 = (j + 0.5) / s->nsamp + s1, r1 = j * GOLDEN + s2;
    r0 -= floor(r0);
    r1 -= floor(r1);
    hd_vec3 l;
    switch (s->p.basis) {
    case HD_HB_KLEMS:
        l = hd_klems_dir(&s->kb, (int)bin, r0, r1);
        break;
    case HD_HB_REINHART: {
        hd_vec3 d = hd_skybasis_sample(&s->sky, (int)bin + 1, r0, r1);
        l = hd_v3(d.x, -d.y, d.z);
        break;
    }
    default: {
        double rr = sqrt(r0), ph = 2 * HD_PI * r1;
        l = hd_v3(rr * cos(ph), rr * sin(ph), sqrt(fmax(0, 1 - r0)));
        break;
    }
    }
    hd_vec3 w = hd_vadd(hd_vadd(hd_vscale(s->u, l.x), hd_vscale(s->v, l.y)), hd_vscale(s->n, l.z));
    *dir = hd_vneg(hd_vnorm(w));
    *org = sample_origin(s, hd_rng_uniform(&rng), hd_rng_uniform(&rng), hd_rng_uniform(&rng));
    return 1;
}

/* heliodon — rcontrib bin functions: the standard .cal forms (see contrib.h). */
#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/contrib.h"

void hd_calctx_init(hd_calctx *c)
{
    memset(c, 0, sizeof *c);
}

static const char *base_name(const char *p)
{
    const char *s = strrchr(p, '/');
    return s ? s + 1 : p;
}

static const char *known_cal[] = {
    "reinhartb.cal", "reinhart.cal", "tregenza.cal", "klems_full.cal", "klems_half.cal",
    "klems_quarter.cal", "rayinit.cal", NULL
};

hd_status hd_calctx_file(hd_calctx *c, const char *path)
{
    const char *b = base_name(path);
    int ok = 0;
    for (int i = 0; known_cal[i]; i++)
        if (!strcmp(b, known_cal[i])) ok = 1;
    if (!ok)
        return hd_fail(HD_ERR_UNSUPPORTED,
                       "-f %s: unsupported function file (heliodon knows the bin files reinhartb.cal, "
                       "reinhart.cal, tregenza.cal, klems_full.cal, klems_half.cal, klems_quarter.cal; "
                       "there is no general .cal interpreter)", path);
    if (c->nfiles >= (int)(sizeof c->file / sizeof c->file[0]))
        return hd_fail(HD_ERR_RANGE, "-f %s: too many function files", path);
    hd_strlcpy(c->file[c->nfiles].name, b, sizeof c->file[0].name);
    c->file[c->nfiles].seq = ++c->seq;
    c->nfiles++;
    return HD_OK;
}

/* Parse "name=number" / "name:number" statements separated by ; or ,
 * (and, in -p, by :  when followed by a name: Radiance accepts , : ;). */
static hd_status parse_assign(const char *text, int params,
                              hd_status (*cb)(void *, const char *, double), void *ctx)
{
    const char *s = text;
    for (;;) {
        while (*s && (isspace((unsigned char)*s) || *s == ';' || *s == ',')) s++;
        if (!*s) return HD_OK;
        char name[32];
        size_t n = 0;
        if (!(isalpha((unsigned char)*s) || *s == '_' || *s == '`')) goto bad;
        while (*s && (isalnum((unsigned char)*s) || *s == '_' || *s == '.' || *s == '`')) {
            if (n + 1 >= sizeof name) goto bad;
            name[n++] = *s++;
        }
        name[n] = 0;
        while (n && name[n - 1] == '`') name[--n] = 0;
        while (isspace((unsigned char)*s)) s++;
        if (*s != '=' && *s != ':') goto bad;
        s++;
        char *end;
        double v = strtod(s, &end);
        if (end == s) goto bad;
        s = end;
        while (isspace((unsigned char)*s)) s++;
        if (*s && *s != ';' && *s != ',' && !(params && *s == ':')) goto bad;
        if (*s == ':') s++;
        hd_status st = cb(ctx, name, v);
        if (st != HD_OK) return st;
    }
bad:
    return hd_fail(HD_ERR_UNSUPPORTED,
                   "%s '%s': only numeric assignments (name=value) are supported (no general .cal interpreter)",
                   params ? "-p" : "-e", text);
}

static hd_status ctx_set(void *vc, const char *name, double v)
{
    hd_calctx *c = vc;
    if (c->nvar >= (int)(sizeof c->var / sizeof c->var[0]))
        return hd_fail(HD_ERR_RANGE, "too many -e/-p assignments");
    hd_strlcpy(c->var[c->nvar].name, name, sizeof c->var[0].name);
    c->var[c->nvar].val = v;
    c->var[c->nvar].seq = ++c->seq;
    c->nvar++;
    return HD_OK;
}

hd_status hd_calctx_assign(hd_calctx *c, const char *text, int params)
{
    return parse_assign(text, params, ctx_set, c);
}

/* -p parameters of one modifier */
typedef struct plist {
    struct { char name[32]; double val; } v[32];
    int n;
} plist;

static hd_status plist_set(void *vp, const char *name, double v)
{
    plist *p = vp;
    if (p->n >= 32) return hd_fail(HD_ERR_RANGE, "too many -p parameters");
    hd_strlcpy(p->v[p->n].name, name, sizeof p->v[0].name);
    p->v[p->n].val = v;
    p->n++;
    return HD_OK;
}

/* Value of a variable: -p parameters first (the last one wins), then the
 * latest -e assignment made after sequence number `after`. */
static int lookup(const hd_calctx *c, const plist *p, const char *name, int after, double *v)
{
    for (int i = p ? p->n - 1 : -1; i >= 0; i--)
        if (!strcmp(p->v[i].name, name)) { *v = p->v[i].val; return 1; }
    for (int i = c->nvar - 1; i >= 0; i--)
        if (c->var[i].seq > after && !strcmp(c->var[i].name, name)) { *v = c->var[i].val; return 1; }
    return 0;
}

/* sequence number of the latest loading of one of the named files, 0 if none */
static int file_seq(const hd_calctx *c, const char *name)
{
    int s = 0;
    for (int i = 0; i < c->nfiles; i++)
        if (!strcmp(c->file[i].name, name) && c->file[i].seq > s) s = c->file[i].seq;
    return s;
}

void hd_binfn_free(hd_binfn *b)
{
    free(b->kb);
    if (b->sky) {
        hd_skybasis_free(b->sky);
        free(b->sky);
    }
    b->kb = NULL;
    b->sky = NULL;
}

static hd_status make_frame(hd_binfn *b, const char *what)
{
    double nl = hd_vlen(b->n);
    if (!(nl > 0)) return hd_fail(HD_ERR_RANGE, "%s: zero normal vector", what);
    b->az = hd_vscale(b->n, 1 / nl);
    hd_vec3 u = hd_vsub(b->u, hd_vscale(b->az, hd_vdot(b->u, b->az)));
    double ul = hd_vlen(u);
    if (!(ul > 1e-9 * (hd_vlen(b->u) + 1e-300)))
        return hd_fail(HD_ERR_RANGE, "%s: up vector parallel to the normal", what);
    b->ay = hd_vscale(u, 1 / ul);
    b->ax = hd_vscale(hd_vcross(b->ay, b->az), b->rhs);
    return HD_OK;
}

hd_status hd_binfn_klems(hd_binfn *b, hd_klems_kind kk, hd_vec3 n, hd_vec3 u, double rhs)
{
    memset(b, 0, sizeof *b);
    b->kind = HD_BIN_KLEMS;
    b->n = n;
    b->u = u;
    b->rhs = rhs < 0 ? -1 : 1;
    b->kb = hd_malloc(sizeof *b->kb);
    if (!b->kb) return HD_ERR_NOMEM;
    hd_klems_standard(b->kb, kk);
    b->nbins = b->kb->nbins;
    hd_status st = make_frame(b, "kbin");
    if (st != HD_OK) hd_binfn_free(b);
    return st;
}

static hd_status init_sky(hd_binfn *b, int mf)
{
    if (mf < 1 || mf > HD_SKY_MAXMF) return hd_fail(HD_ERR_RANGE, "MF=%d out of range 1..%d", mf, HD_SKY_MAXMF);
    b->mf = mf;
    b->sky = hd_calloc(1, sizeof *b->sky);
    if (!b->sky) return HD_ERR_NOMEM;
    hd_status st = hd_skybasis_init(b->sky, mf);
    if (st != HD_OK) { free(b->sky); b->sky = NULL; }
    return st;
}

hd_status hd_binfn_reinhartb(hd_binfn *b, int mf, hd_vec3 rn, hd_vec3 u, double rhs, double jtr)
{
    memset(b, 0, sizeof *b);
    b->kind = HD_BIN_REINHARTB;
    b->n = rn;
    b->u = u;
    b->rhs = rhs < 0 ? -1 : 1;
    b->jtr = jtr;
    hd_status st = init_sky(b, mf);
    if (st != HD_OK) return st;
    b->nbins = b->sky->nbins - 1;
    return HD_OK;
}

/* strip blanks into buf */
static void squeeze(char *buf, size_t cap, const char *s)
{
    size_t n = 0;
    for (; *s && n + 1 < cap; s++)
        if (!isspace((unsigned char)*s)) buf[n++] = *s;
    buf[n] = 0;
}

/* Parse "if(<linear form in Dx Dy Dz>,0,-1)": the form is
 * sum of [+-]Dk*num or [+-]num*Dk terms; returns the normal n such that
 * the form = -D·n. */
static int parse_hemi(const char *e, hd_vec3 *n)
{
    if (strncmp(e, "if(", 3)) return 0;
    const char *s = e + 3;
    double c[3] = {0, 0, 0};
    int nterm = 0;
    while (*s && *s != ',') {
        double sign = 1;
        while (*s == '+' || *s == '-') { if (*s == '-') sign = -sign; s++; }
        int k = -1;
        double v = 1;
        char *end;
        if (s[0] == 'D' && (s[1] == 'x' || s[1] == 'y' || s[1] == 'z')) {
            k = s[1] - 'x';
            s += 2;
            if (*s == '*') {
                s++;
                v = strtod(s, &end);
                if (end == s) return 0;
                s = end;
            }
        } else {
            v = strtod(s, &end);
            if (end == s || *end != '*') return 0;
            s = end + 1;
            if (s[0] != 'D' || !(s[1] == 'x' || s[1] == 'y' || s[1] == 'z')) return 0;
            k = s[1] - 'x';
            s += 2;
        }
        c[k] += sign * v;
        nterm++;
    }
    if (nterm == 0 || strcmp(s, ",0,-1)")) return 0;
    *n = hd_v3(-c[0], -c[1], -c[2]);
    return 1;
}

static int parse_count(const char *s, const hd_binfn *b, int *out)
{
    char buf[128];
    squeeze(buf, sizeof buf, s);
    char *end;
    long v = strtol(buf, &end, 10);
    if (end != buf && !*end) { *out = (int)v; return v >= 1 && v <= 100000000; }
    if (!strcmp(buf, "Nrbins") || !strcmp(buf, "Ntbins") || !strcmp(buf, "Nkbins") ||
        !strcmp(buf, "Nkhbins") || !strcmp(buf, "Nkqbins")) {
        if (b->nbins <= 0) return 0;
        *out = b->nbins;
        return 1;
    }
    return 0;
}

hd_status hd_binfn_parse(hd_binfn *b, const hd_calctx *c, const char *params,
                         const char *expr, const char *count)
{
    memset(b, 0, sizeof *b);
    plist pl;
    pl.n = 0;
    if (params && *params) {
        hd_status st = parse_assign(params, 1, plist_set, &pl);
        if (st != HD_OK) return st;
    }
    char e[512];
    squeeze(e, sizeof e, expr ? expr : "0");
    hd_status st = HD_OK;
    char *end;
    double cv = strtod(e, &end);
    hd_vec3 hn;
    if (end != e && !*end) {
        if (cv != 0)
            return hd_fail(HD_ERR_USAGE, "-b %s: a constant bin expression must be 0", expr);
        b->kind = HD_BIN_CONST;
        b->nbins = 1;
    } else if (parse_hemi(e, &hn)) {
        b->kind = HD_BIN_HEMI;
        b->n = hn;
        b->nbins = 1;
    } else if (!strcmp(e, "rbin")) {
        int sb = file_seq(c, "reinhartb.cal"), sr = file_seq(c, "reinhart.cal");
        if (!sb && !sr)
            return hd_fail(HD_ERR_USAGE, "-b rbin: needs -f reinhartb.cal or -f reinhart.cal before it");
        double v;
        if (sb > sr) {
            /* reinhartb.cal sets its own defaults when loaded (MF=1, sky frame);
             * only later assignments and -p override them */
            double mf = 1, rx = 0, ry = 0, rz = -1, ux = 0, uy = 1, uz = 0, rhs = 1, jtr = 0;
            if (lookup(c, &pl, "MF", sb, &v)) mf = v;
            if (lookup(c, &pl, "rNx", sb, &v)) rx = v;
            if (lookup(c, &pl, "rNy", sb, &v)) ry = v;
            if (lookup(c, &pl, "rNz", sb, &v)) rz = v;
            if (lookup(c, &pl, "Ux", sb, &v)) ux = v;
            if (lookup(c, &pl, "Uy", sb, &v)) uy = v;
            if (lookup(c, &pl, "Uz", sb, &v)) uz = v;
            if (lookup(c, &pl, "RHS", sb, &v)) rhs = v;
            if (lookup(c, &pl, "JTR", sb, &v)) jtr = v;
            if (mf != floor(mf)) return hd_fail(HD_ERR_USAGE, "reinhartb.cal: MF=%g is not an integer", mf);
            st = hd_binfn_reinhartb(b, (int)mf, hd_v3(rx, ry, rz), hd_v3(ux, uy, uz), rhs, jtr);
        } else {
            if (!lookup(c, &pl, "MF", 0, &v))
                return hd_fail(HD_ERR_USAGE, "reinhart.cal: MF is not defined (use -e MF:n before -f reinhart.cal)");
            if (v != floor(v)) return hd_fail(HD_ERR_USAGE, "reinhart.cal: MF=%g is not an integer", v);
            b->kind = HD_BIN_REINHART;
            st = init_sky(b, (int)v);
            if (st == HD_OK) b->nbins = b->sky->nbins;
        }
    } else if (!strcmp(e, "tbin")) {
        if (!file_seq(c, "tregenza.cal"))
            return hd_fail(HD_ERR_USAGE, "-b tbin: needs -f tregenza.cal before it");
        b->kind = HD_BIN_REINHART;
        st = init_sky(b, 1);
        if (st == HD_OK) b->nbins = b->sky->nbins;
    } else if (!strncmp(e, "kbin", 4) || !strncmp(e, "khbin", 5) || !strncmp(e, "kqbin", 5)) {
        hd_klems_kind kk;
        const char *a;
        if (e[1] == 'h') { kk = HD_KLEMS_HALF; a = e + 5; }
        else if (e[1] == 'q') { kk = HD_KLEMS_QUARTER; a = e + 5; }
        else {
            a = e + 4;
            int sf = file_seq(c, "klems_full.cal"), sh = file_seq(c, "klems_half.cal"), sq = file_seq(c, "klems_quarter.cal");
            kk = sh > sf && sh > sq ? HD_KLEMS_HALF : sq > sf && sq > sh ? HD_KLEMS_QUARTER : HD_KLEMS_FULL;
        }
        const char *need = kk == HD_KLEMS_HALF ? "klems_half.cal" : kk == HD_KLEMS_QUARTER ? "klems_quarter.cal" : "klems_full.cal";
        if (!file_seq(c, need))
            return hd_fail(HD_ERR_USAGE, "-b %s: needs -f %s before it", expr, need);
        double x[6];
        if (*a == '(') {
            const char *s = a + 1;
            for (int i = 0; i < 6; i++) {
                x[i] = strtod(s, &end);
                if (end == s || *end != (i < 5 ? ',' : ')')) goto unsupported;
                s = end + 1;
            }
            if (*s) goto unsupported;
        } else if (a[0] && !a[1] && strchr("NESWD", a[0])) {
            /* kbinN/E/S/W: vertical windows facing that way, up +Z; kbinD: skylight facing down */
            static const double pre[5][6] = {
                {0, 1, 0, 0, 0, 1}, {1, 0, 0, 0, 0, 1}, {0, -1, 0, 0, 0, 1}, {-1, 0, 0, 0, 0, 1}, {0, 0, -1, 0, 1, 0}};
            int k = (int)(strchr("NESWD", a[0]) - "NESWD");
            memcpy(x, pre[k], sizeof x);
        } else {
            goto unsupported;
        }
        double rhs = 1, v;
        if (lookup(c, &pl, "RHS", 0, &v)) rhs = v;
        st = hd_binfn_klems(b, kk, hd_v3(x[0], x[1], x[2]), hd_v3(x[3], x[4], x[5]), rhs);
    } else {
        goto unsupported;
    }
    if (st != HD_OK) return st;
    int n;
    if (!parse_count(count ? count : "1", b, &n)) {
        hd_binfn_free(b);
        return hd_fail(HD_ERR_USAGE, "-bn %s: expected a positive bin count or the count variable of the bin file", count);
    }
    b->nbins = n;
    return HD_OK;
unsupported:
    hd_binfn_free(b);
    return hd_fail(HD_ERR_UNSUPPORTED,
                   "unsupported bin expression '%s' (heliodon recognises 0, if(-Dx*nx-Dy*ny-Dz*nz,0,-1), "
                   "rbin with reinhartb.cal/reinhart.cal, tbin with tregenza.cal, kbin(...)/kbinN/E/S/W/D with klems_*.cal)",
                   expr);
}

int hd_binfn_eval(const hd_binfn *b, hd_vec3 D, double jr1, double jr2)
{
    int bin = -1;
    switch (b->kind) {
    case HD_BIN_CONST:
        bin = 0;
        break;
    case HD_BIN_HEMI:
        bin = hd_vdot(D, b->n) < 0 ? 0 : -1;
        break;
    case HD_BIN_KLEMS: {
        hd_vec3 v = hd_v3(-hd_vdot(D, b->ax), -hd_vdot(D, b->ay), -hd_vdot(D, b->az));
        if (!(v.z > 0)) return -1;
        bin = hd_klems_bin(b->kb, v);
        break;
    }
    case HD_BIN_REINHARTB: {
        hd_vec3 rn = b->n, u = b->u;
        double dz = -hd_vdot(D, rn);
        if (!(dz > 0)) return -1;
        double rx = -b->rhs * hd_vdot(D, hd_vcross(u, rn));
        double ry = hd_vdot(D, u) + dz * hd_vdot(rn, u);
        hd_vec3 d = hd_v3(rx, ry, dz);
        if (b->jtr > 0) {
            /* jitter the bin boundaries: perturb altitude and azimuth by up to
             * ±JTR/2 of a band height */
            double alt = asin(fmin(1, dz / hd_vlen(d))), azi = atan2(rx, ry);
            alt += b->jtr * (jr1 - 0.5) * b->sky->alpha;
            azi += b->jtr * (jr2 - 0.5) * b->sky->alpha / fmax(cos(alt), 0.05);
            if (alt <= 0) return -1;
            if (alt > HD_PI / 2) alt = HD_PI / 2;
            d = hd_v3(sin(azi) * cos(alt), cos(azi) * cos(alt), sin(alt));
        }
        bin = hd_skybasis_bin(b->sky, d) - 1;
        break;
    }
    case HD_BIN_REINHART:
        bin = hd_skybasis_bin(b->sky, D);
        break;
    }
    if (bin >= b->nbins) return -1;
    return bin;
}

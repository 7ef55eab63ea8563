/* heliodon — patterns, textures and mixtures with function files
 * (brightfunc, colorfunc, texfunc, mixfunc, brightdata, colordata,
 * colorpict, texdata, mixdata, mixpict), evaluated with the .cal module at each hit.  See material.h
 * for the interface and docs/design/funcfile.md for the semantics.
 *
 * One .cal context per function file (rayinit.cal, then the file), shared
 * by every modifier naming it; each modifier compiles its expressions into
 * that context.  The ray state of the hit being evaluated lives in an
 * evaluation slot (a run of the context plus the state), taken with an
 * atomic flag, so any number of threads evaluate at once. */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "heliodon/cal.h"
#include "heliodon/font.h"
#include "heliodon/material.h"
#include "heliodon/picture.h"
#include "heliodon/rng.h"
#include "heliodon/trace.h"
#include "heliodon/xform.h"

#define NSLOTS 64
#define MAXDDIM 8          /* dimensions of a data file */
#define FTINY 1e-7

/* ------------------------------------------------------------ contexts */
struct fctx;

typedef struct evstate {
    const struct hd_modnode *nd;
    hd_vec3 D, N, P;
    double T, rdot;
} evstate;

typedef struct slot {
    atomic_int busy;
    hd_calrun *run;
    evstate st;
} slot;

typedef struct exprent { char *text; int id; } exprent;

typedef struct fctx {
    char *name;               /* function file as written ("." = none) */
    hd_cal *cal;
    slot slots[NSLOTS];
    exprent *ex;              /* compiled expressions by text (open addressing) */
    size_t nex, capex;
} fctx;

/* a data array (data file, or one channel of a picture) */
typedef struct darr {
    char *name;
    int nd;
    struct { double org, siz; int ne; double *p; } dim[MAXDDIM];
    double *v;
    int owns;                 /* frees dims' p and v */
} darr;

enum { MN_BRIGHT, MN_COLOR, MN_TEX, MN_MIX, MN_BDATA, MN_CDATA, MN_PICT, MN_TDATA, MN_MIXD, MN_MIXP,
       MN_BTEXT, MN_CTEXT, MN_MIXT };

/* text patterns and mixtures (brighttext, colortext, mixtext) */
#define IS_TEXT(k) ((k) == MN_BTEXT || (k) == MN_CTEXT || (k) == MN_MIXT)

/* mixtures: mixfunc (coefficient from an expression), mixdata (from a
 * data file through a function), mixpict (from a picture's colour through
 * a function of three arguments) */
#define IS_MIX(k) ((k) == MN_MIX || (k) == MN_MIXD || (k) == MN_MIXP || (k) == MN_MIXT)
/* nodes reading data: the number of data arrays and of functions of them */
#define HAS_DATA(k) ((k) == MN_BDATA || (k) == MN_CDATA || (k) == MN_PICT || (k) == MN_TDATA || (k) == MN_MIXD || (k) == MN_MIXP)
#define NDATA(k) ((k) == MN_BDATA || (k) == MN_MIXD ? 1 : 3)
#define NFUNC(k) ((k) == MN_BDATA || (k) == MN_MIXD || (k) == MN_MIXP ? 1 : 3)

struct hd_modnode {
    int kind;
    fctx *fc;
    int ex[MAXDDIM];          /* compiled expressions */
    int nex;
    double *args;
    int nargs;
    int has_xf;
    hd_xf fwd;                /* the transform as written */
    double im[3][3];          /* its inverse: world -> modifier frame */
    hd_vec3 it;
    double isca;
    const darr *d[3];         /* data: brightdata 1, colordata/colorpict 3 */
    int fn[3], fnargs[3];     /* data functions: handles and argument counts */
    const struct hd_modchain *side[2];
    struct hd_tmat *smat[2];
    char *mixname[2];
    struct textpat *tx;       /* text patterns */
    char where[256];
};

/* A text pattern's text: lines (first at the top) with their character
 * offsets, the font, the origin and the right and down vectors scaled so
 * that a dot product with them gives cells and lines. */
typedef struct textpat {
    hd_font *font;
    int nlines, width;        /* width: the longest line, font units */
    char **line;
    short **sp;
    int *lw;
    hd_vec3 org, right, down;
    double xscale;            /* font units per cell: 255, or mwidth + 255 |spacing| */
} textpat;

struct hd_modchain {
    int n;
    struct hd_modnode *nd[];
};

struct hd_modset {
    fctx **fc;
    size_t nfc, capfc;
    struct hd_modnode **nodes;
    size_t nnodes, capnodes;
    struct hd_modchain **chains;
    size_t nchains, capchains;
    darr **data;
    size_t ndata, capdata;
};

static int push(void **arr, size_t *n, size_t *cap, size_t elem, const void *item)
{
    if (hd_grow(arr, *n + 1, cap, elem, 16)) return -1;
    memcpy((char *)*arr + *n * elem, item, elem);
    (*n)++;
    return 0;
}

/* ---- rayinit.cal channels ---- */
enum { CH_DX, CH_DY, CH_DZ, CH_NX, CH_NY, CH_NZ, CH_PX, CH_PY, CH_PZ, CH_T, CH_TS, CH_RDOT, CH_S,
       CH_TX, CH_TY, CH_TZ, CH_IX, CH_IY, CH_IZ, CH_JX, CH_JY, CH_JZ, CH_KX, CH_KY, CH_KZ, CH_LU, CH_LV, CH_N };
static const char *chname[CH_N] = {"Dx", "Dy", "Dz", "Nx", "Ny", "Nz", "Px", "Py", "Pz", "T", "Ts", "Rdot", "S",
                                   "Tx", "Ty", "Tz", "Ix", "Iy", "Iz", "Jx", "Jy", "Jz", "Kx", "Ky", "Kz", "Lu",
                                   "Lv"};

static double f_chan(hd_calrun *r, void *u, int na, const double *a)
{
    (void)na; (void)a;
    const slot *s = hd_calrun_user(r);
    const evstate *e = &s->st;
    const struct hd_modnode *nd = e->nd;
    int c = (int)(intptr_t)u;
    switch (c) {
    case CH_DX: return e->D.x;
    case CH_DY: return e->D.y;
    case CH_DZ: return e->D.z;
    case CH_NX: return e->N.x;
    case CH_NY: return e->N.y;
    case CH_NZ: return e->N.z;
    case CH_PX: return e->P.x;
    case CH_PY: return e->P.y;
    case CH_PZ: return e->P.z;
    case CH_T: case CH_TS: return e->T;
    case CH_RDOT: return e->rdot;
    case CH_S: return nd && nd->has_xf ? nd->isca : 1;
    case CH_TX: return nd && nd->has_xf ? nd->it.x : 0;
    case CH_TY: return nd && nd->has_xf ? nd->it.y : 0;
    case CH_TZ: return nd && nd->has_xf ? nd->it.z : 0;
    case CH_LU: case CH_LV: return 0;
    default: {   /* unit vectors of the modifier frame: column k of the inverse */
        int k = (c - CH_IX) / 3, i = (c - CH_IX) % 3;
        if (!nd || !nd->has_xf) return i == k;
        return nd->im[i][k] / nd->isca;
    }
    }
}

static double f_arg(hd_calrun *r, void *u, int na, const double *a)
{
    (void)u; (void)na;
    const slot *s = hd_calrun_user(r);
    const struct hd_modnode *nd = s->st.nd;
    int n = (int)(a[0] + .5);
    if (!nd) return 0;
    if (n < 1) return nd->nargs;
    return n <= nd->nargs ? nd->args[n - 1] : 0.;
}

static double f_an(hd_calrun *r, void *u, int na, const double *a)
{
    (void)na; (void)a;
    const slot *s = hd_calrun_user(r);
    const struct hd_modnode *nd = s->st.nd;
    int n = (int)(intptr_t)u;
    if (!nd) return 0;
    if (n == 0) return nd->nargs;
    return n <= nd->nargs ? nd->args[n - 1] : 0.;
}

/* ---- noise functions of Radiance's renderers ----
 * noise3: Perlin's "improved noise" (2002) with his published permutation;
 * noise3x/y/z its partial derivatives by backward differences of 5e-4;
 * fnoise3: fractal noise by recursive midpoint subdivision of the unit
 * lattice cube holding the point (cells of 1/2000), each new point the
 * mean of its neighbours plus a hashed random offset scaled with the cell
 * size (the construction Radiance's renderers use, so that scenes keep
 * their look). */
static const unsigned char perm[256] = {
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69, 142, 8, 99, 37,
    240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219, 203, 117, 35, 11, 32, 57, 177,
    33, 88, 237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175, 74, 165, 71, 134, 139, 48, 27, 166, 77, 146,
    158, 231, 83, 111, 229, 122, 60, 211, 133, 230, 220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25,
    63, 161, 1, 216, 80, 73, 209, 76, 132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100,
    109, 198, 173, 186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206,
    59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163, 70, 221, 153,
    101, 155, 167, 43, 172, 9, 129, 22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232, 178, 185, 112, 104, 218, 246,
    97, 228, 251, 34, 242, 193, 238, 210, 144, 12, 191, 179, 162, 241, 81, 51, 145, 235, 249, 14, 239, 107, 49,
    192, 214, 31, 181, 199, 106, 157, 184, 84, 204, 176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93,
    222, 114, 67, 29, 24, 72, 243, 141, 128, 195, 78, 66, 215, 61, 156, 180};

static int P(int i) { return perm[i & 255]; }
static double smooth5(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }
static double mixl(double t, double a, double b) { return a + t * (b - a); }
static double gradc(int h, double x, double y, double z)
{
    h &= 15;
    double u = h < 8 ? x : y;
    double v = h < 4 ? y : (h == 12 || h == 14) ? x : z;
    return ((h & 1) ? -u : u) + ((h & 2) ? -v : v);
}

static double perlin(double x, double y, double z)
{
    int X = (int)x - (x < 0), Y = (int)y - (y < 0), Z = (int)z - (z < 0);
    x -= X; y -= Y; z -= Z;
    X &= 255; Y &= 255; Z &= 255;
    double u = smooth5(x), v = smooth5(y), w = smooth5(z);
    int a = P(X) + Y, aa = P(a) + Z, ab = P(a + 1) + Z;
    int b = P(X + 1) + Y, ba = P(b) + Z, bb = P(b + 1) + Z;
    double z0 = mixl(v, mixl(u, gradc(P(aa), x, y, z), gradc(P(ba), x - 1, y, z)),
                     mixl(u, gradc(P(ab), x, y - 1, z), gradc(P(bb), x - 1, y - 1, z)));
    double z1 = mixl(v, mixl(u, gradc(P(aa + 1), x, y, z - 1), gradc(P(ba + 1), x - 1, y, z - 1)),
                     mixl(u, gradc(P(ab + 1), x, y - 1, z - 1), gradc(P(bb + 1), x - 1, y - 1, z - 1)));
    return mixl(w, z0, z1);
}

#define NOISE_EPS .0005

static double f_noise3(hd_calrun *r, void *u, int na, const double *a)
{
    (void)r; (void)na;
    int c = (int)(intptr_t)u;   /* 3: value, 0..2: partial derivative */
    double f = perlin(a[0], a[1], a[2]);
    if (c == 3) return f;
    double b[3] = {a[0], a[1], a[2]};
    b[c] -= NOISE_EPS;
    return (f - perlin(b[0], b[1], b[2])) / NOISE_EPS;
}

/* hashed uniform number in (-1, 1] for an integer lattice point */
static double lattice_rand(long x, long y, long z)
{
    /* wrapping (unsigned) arithmetic on 64 bits */
    unsigned long s = 17 * (unsigned long)x + 23 * (unsigned long)y + 29 * (unsigned long)z;
    s = (s << 13) ^ s;
    return 1.0 - (double)((s * (s * s * 15731u + 789221u) + 1376312589u) & 0x7fffffffu) / 1073741824.0;
}

static double f_fnoise3(hd_calrun *r, void *u, int na, const double *a)
{
    (void)r; (void)u; (void)na;
    long cell = (long)(1.0 / NOISE_EPS), t[3], lo[3], q[3];
    double corner[8];
    for (int i = 0; i < 3; i++) {
        t[i] = (long)(cell * a[i]);
        lo[i] = (long)(cell * floor(a[i]));
    }
    for (int j = 0; j < 8; j++) {
        for (int i = 0; i < 3; i++) q[i] = lo[i] + ((j >> i & 1) ? cell : 0);
        corner[j] = lattice_rand(q[0], q[1], q[2]);
    }
    for (;;) {
        double mean = 0;
        for (int j = 0; j < 8; j++) mean += corner[j];
        mean *= 0.125;
        cell >>= 1;
        if (!cell) return mean;
        /* the centre of the current cube, and the octant holding the point */
        int oct = 0;
        for (int i = 0; i < 3; i++) {
            q[i] = lo[i] + cell;
            if (t[i] > q[i]) oct |= 1 << i;
        }
        double amp = cell * NOISE_EPS;
        corner[~oct & 7] = mean + amp * lattice_rand(q[0], q[1], q[2]);
        /* face centres of the octant's cube: mean of the face's 4 corners */
        for (int i = 0; i < 3; i++) {
            q[i] += (oct >> i & 1) ? cell : -cell;
            double sum = 0;
            for (int j = 0; j < 8; j++)
                if (!((j ^ oct) >> i & 1)) sum += corner[j];
            corner[~(oct ^ (1 << i)) & 7] = 0.25 * sum + amp * lattice_rand(q[0], q[1], q[2]);
            q[i] = lo[i] + cell;
        }
        /* edge midpoints: mean of the edge's 2 ends */
        for (int i = 0; i < 3; i++) {
            int j1 = (i + 1) % 3, j2 = (i + 2) % 3;
            q[j1] += (oct >> j1 & 1) ? cell : -cell;
            q[j2] += (oct >> j2 & 1) ? cell : -cell;
            double e = 0.5 * (corner[oct & ~(1 << i)] + corner[oct | (1 << i)]);
            corner[oct ^ (1 << i)] = e + amp * lattice_rand(q[0], q[1], q[2]);
            q[j1] = lo[j1] + cell;
            q[j2] = lo[j2] + cell;
        }
        for (int i = 0; i < 3; i++)
            if (oct >> i & 1) lo[i] += cell;
    }
}

static void fctx_free(fctx *f)
{
    if (!f) return;
    for (int k = 0; k < NSLOTS; k++)
        if (f->slots[k].run) hd_calrun_free(f->slots[k].run);
    for (size_t i = 0; i < f->capex; i++) free(f->ex[i].text);
    free(f->ex);
    hd_cal_free(f->cal);
    free(f->name);
    free(f);
}

static hd_status fctx_new(const char *file, fctx **out)
{
    *out = NULL;
    fctx *f = hd_calloc(1, sizeof *f);
    if (!f) return HD_ERR_NOMEM;
    f->name = hd_strdup(file);
    f->cal = hd_cal_new();
    if (!f->name || !f->cal) { fctx_free(f); return HD_ERR_NOMEM; }
    hd_status st = HD_OK;
    for (int k = 0; k < CH_N && !st; k++) st = hd_cal_define_fn(f->cal, chname[k], 0, 0, f_chan, (void *)(intptr_t)k, 0);
    if (!st) st = hd_cal_define_fn(f->cal, "arg", 1, 1, f_arg, NULL, 0);
    static const char *an[11] = {"AC", "A1", "A2", "A3", "A4", "A5", "A6", "A7", "A8", "A9", "A10"};
    for (int k = 0; k < 11 && !st; k++) st = hd_cal_define_fn(f->cal, an[k], 0, 0, f_an, (void *)(intptr_t)k, 0);
    static const char *nn[4] = {"noise3x", "noise3y", "noise3z", "noise3"};
    for (int k = 0; k < 4 && !st; k++) st = hd_cal_define_fn(f->cal, nn[k], 3, 3, f_noise3, (void *)(intptr_t)k, 1);
    if (!st) st = hd_cal_define_fn(f->cal, "fnoise3", 3, 3, f_fnoise3, NULL, 1);
    if (!st) st = hd_cal_load(f->cal, "rayinit.cal");
    if (!st && strcmp(file, ".")) st = hd_cal_load(f->cal, file);
    if (st) { fctx_free(f); return st; }
    *out = f;
    return HD_OK;
}

static uint64_t strhash(const char *s)
{
    uint64_t h = 1469598103934665603ull;
    while (*s) h = (h ^ (unsigned char)*s++) * 1099511628211ull;
    return h;
}

/* compile (or find) an expression in context f */
static hd_status fctx_expr(fctx *f, const char *text, const char *where, int *id)
{
    if (f->capex) {
        for (size_t i = strhash(text) & (f->capex - 1);; i = (i + 1) & (f->capex - 1)) {
            if (!f->ex[i].text) break;
            if (!strcmp(f->ex[i].text, text)) { *id = f->ex[i].id; return HD_OK; }
        }
    }
    hd_status st = hd_cal_expr(f->cal, text, where, id);
    if (st) return st;
    if (2 * (f->nex + 1) > f->capex) {
        size_t nc = f->capex ? 2 * f->capex : 64;
        exprent *ne = hd_calloc(nc, sizeof *ne);
        if (!ne) return HD_ERR_NOMEM;
        for (size_t i = 0; i < f->capex; i++) {
            if (!f->ex[i].text) continue;
            size_t j = strhash(f->ex[i].text) & (nc - 1);
            while (ne[j].text) j = (j + 1) & (nc - 1);
            ne[j] = f->ex[i];
        }
        free(f->ex);
        f->ex = ne;
        f->capex = nc;
    }
    char *cp = hd_strdup(text);
    if (!cp) return HD_ERR_NOMEM;
    size_t j = strhash(text) & (f->capex - 1);
    while (f->ex[j].text) j = (j + 1) & (f->capex - 1);
    f->ex[j].text = cp;
    f->ex[j].id = *id;
    f->nex++;
    return HD_OK;
}

static hd_status get_fctx(struct hd_modset *ms, const char *file, fctx **out)
{
    for (size_t i = 0; i < ms->nfc; i++)
        if (!strcmp(ms->fc[i]->name, file)) { *out = ms->fc[i]; return HD_OK; }
    hd_status st = fctx_new(file, out);
    if (st) return st;
    if (push((void **)&ms->fc, &ms->nfc, &ms->capfc, sizeof *ms->fc, out)) { fctx_free(*out); return HD_ERR_NOMEM; }
    return HD_OK;
}

/* take an evaluation slot of f (a temporary one when all are busy) */
static slot *take(fctx *f, slot *spare)
{
    for (int k = 0; k < NSLOTS; k++) {
        slot *s = &f->slots[k];
        if (atomic_exchange_explicit(&s->busy, 1, memory_order_acquire)) continue;
        if (!s->run && !(s->run = hd_calrun_new(f->cal, s))) {
            atomic_store_explicit(&s->busy, 0, memory_order_release);
            return NULL;
        }
        return s;
    }
    spare->run = hd_calrun_new(f->cal, spare);
    return spare->run ? spare : NULL;
}

static void give(fctx *f, slot *s)
{
    if (s < f->slots || s >= f->slots + NSLOTS) {
        hd_calrun_free(s->run);
        s->run = NULL;
        return;
    }
    atomic_store_explicit(&s->busy, 0, memory_order_release);
}

/* ------------------------------------------------------------ data files */
static void darr_free(darr *d)
{
    if (!d) return;
    if (d->owns) {
        for (int i = 0; i < d->nd; i++) free(d->dim[i].p);
        free(d->v);
    }
    free(d->name);
    free(d);
}

/* a file named in a primitive: as given (relative to the current
 * directory), else through RAYPATH */
static const char *find_file(const char *name, char *buf, size_t cap)
{
    if (strchr(name, '/') && access(name, R_OK) == 0) {
        hd_strlcpy(buf, name, cap);
        return buf;
    }
    return hd_cal_findfile(name, buf, cap);
}

static int next_number(FILE *fp, double *v)
{
    char w[128];
    for (;;) {
        int c;
        do c = getc(fp); while (c != EOF && isspace(c));
        if (c == EOF) return 0;
        if (c == '#') {
            while ((c = getc(fp)) != EOF && c != '\n') {}
            continue;
        }
        size_t n = 0;
        while (c != EOF && !isspace(c)) {
            if (n + 1 < sizeof w) w[n++] = (char)c;
            c = getc(fp);
        }
        w[n] = 0;
        char *end;
        *v = strtod(w, &end);
        return *end ? -1 : 1;
    }
}

static hd_status load_data(struct hd_modset *ms, const char *name, const char *where, const darr **out)
{
    for (size_t i = 0; i < ms->ndata; i++)
        if (!strcmp(ms->data[i]->name, name) && ms->data[i]->nd > 0 && ms->data[i]->owns != 2) {
            *out = ms->data[i];
            return HD_OK;
        }
    char path[4096];
    if (!find_file(name, path, sizeof path))
        return hd_fail(HD_ERR_IO, "%s: cannot find data file '%s'", where, name);
    FILE *fp = fopen(path, "r");
    if (!fp) return hd_fail(HD_ERR_IO, "%s: cannot open data file '%s': %s", where, path, strerror(errno));
    darr *d = hd_calloc(1, sizeof *d);
    if (!d || !(d->name = hd_strdup(name))) { free(d); fclose(fp); return HD_ERR_NOMEM; }
    d->owns = 1;
    double v;
    hd_status st = HD_OK;
    size_t total = 1;
    if (next_number(fp, &v) != 1 || v != floor(v) || v < 1 || v > MAXDDIM) {
        st = hd_fail(HD_ERR_FORMAT, "%s: data file '%s': expected the number of dimensions (1..%d)", where, path,
                     MAXDDIM);
        goto done;
    }
    d->nd = (int)v;
    for (int i = 0; i < d->nd && !st; i++) {
        double b, e, n;
        if (next_number(fp, &b) != 1 || next_number(fp, &e) != 1 || next_number(fp, &n) != 1 || n < 2 ||
            n != floor(n) || n > 1e8) {
            st = hd_fail(HD_ERR_FORMAT, "%s: data file '%s': dimension %d: expected 'begin end count' (count >= 2)",
                         where, path, i + 1);
            break;
        }
        d->dim[i].ne = (int)n;
        total *= (size_t)n;
        if (total > ((size_t)1 << 28)) {
            st = hd_fail(HD_ERR_RANGE, "%s: data file '%s': more than 2^28 values", where, path);
            break;
        }
        d->dim[i].org = b;
        d->dim[i].siz = e - b;
        if (e == b) {   /* irregular points follow */
            if (!(d->dim[i].p = hd_malloc_array((size_t)n, sizeof(double)))) { st = HD_ERR_NOMEM; break; }
            for (int j = 0; j < d->dim[i].ne; j++)
                if (next_number(fp, &d->dim[i].p[j]) != 1) {
                    st = hd_fail(HD_ERR_FORMAT, "%s: data file '%s': dimension %d: expected %d point positions",
                                 where, path, i + 1, d->dim[i].ne);
                    break;
                }
            if (st) break;
            for (int j = 1; j + 1 < d->dim[i].ne; j++)
                if ((d->dim[i].p[j - 1] < d->dim[i].p[j]) != (d->dim[i].p[j] < d->dim[i].p[j + 1])) {
                    st = hd_fail(HD_ERR_FORMAT, "%s: data file '%s': dimension %d: point positions not monotonic",
                                 where, path, i + 1);
                    break;
                }
            d->dim[i].org = d->dim[i].p[0];
            d->dim[i].siz = d->dim[i].p[d->dim[i].ne - 1] - d->dim[i].p[0];
        }
    }
    if (!st && !(d->v = hd_malloc_array(total, sizeof(double)))) st = HD_ERR_NOMEM;
    for (size_t k = 0; !st && k < total; k++) {
        int r = next_number(fp, &d->v[k]);
        if (r != 1)
            st = hd_fail(HD_ERR_FORMAT, "%s: data file '%s': %s at value %zu of %zu", where, path,
                         r == 0 ? "unexpected end of file" : "not a number", k + 1, total);
    }
done:
    fclose(fp);
    if (!st && push((void **)&ms->data, &ms->ndata, &ms->capdata, sizeof *ms->data, &d)) st = HD_ERR_NOMEM;
    if (st) { darr_free(d); return st; }
    *out = d;
    return HD_OK;
}

/* a picture as three 2-D arrays (y from the bottom, then x), over
 * [0, h] x [0, w] with the shorter side 1, as Radiance's pictures in
 * patterns; samples at the grid points */
static hd_status load_pict(struct hd_modset *ms, const char *name, const char *where, const darr *out[3])
{
    for (size_t i = 0; i + 2 < ms->ndata; i++)
        if (ms->data[i]->owns == 2 && !strcmp(ms->data[i]->name, name)) {
            for (int c = 0; c < 3; c++) out[c] = ms->data[i + c];
            return HD_OK;
        }
    char path[4096];
    if (!find_file(name, path, sizeof path))
        return hd_fail(HD_ERR_IO, "%s: cannot find picture file '%s'", where, name);
    hd_picture pic;
    hd_status st = hd_picture_read(path, &pic);
    if (st) return hd_fail_context(st, "%s: picture file '%s'", where, path);
    if (pic.xres < 2 || pic.yres < 2) {
        hd_picture_free(&pic);
        return hd_fail(HD_ERR_FORMAT, "%s: picture file '%s': at least 2 x 2 pixels needed", where, path);
    }
    darr *d[3] = {NULL, NULL, NULL};
    size_t n = (size_t)pic.xres * pic.yres;
    for (int c = 0; c < 3 && !st; c++) {
        if (!(d[c] = hd_calloc(1, sizeof **d)) || !(d[c]->name = hd_strdup(name)) ||
            !(d[c]->v = hd_malloc_array(n, sizeof(double)))) {
            st = HD_ERR_NOMEM;
            break;
        }
        d[c]->owns = 2;
        d[c]->nd = 2;
        d[c]->dim[0].ne = pic.yres;
        d[c]->dim[1].ne = pic.xres;
        if (pic.xres <= pic.yres) {
            d[c]->dim[0].siz = (double)pic.yres / pic.xres;
            d[c]->dim[1].siz = 1;
        } else {
            d[c]->dim[0].siz = 1;
            d[c]->dim[1].siz = (double)pic.xres / pic.yres;
        }
        for (int y = 0; y < pic.yres; y++)
            for (int x = 0; x < pic.xres; x++)
                d[c]->v[(size_t)y * pic.xres + x] = pic.pix[3 * ((size_t)(pic.yres - 1 - y) * pic.xres + x) + c];
    }
    hd_picture_free(&pic);
    for (int c = 0; c < 3 && !st; c++)
        if (push((void **)&ms->data, &ms->ndata, &ms->capdata, sizeof *ms->data, &d[c])) st = HD_ERR_NOMEM;
    if (st) {
        for (int c = 0; c < 3; c++) {
            int kept = 0;
            for (size_t i = 0; i < ms->ndata; i++) kept |= ms->data[i] == d[c];
            if (!kept && d[c]) { d[c]->owns = 1; darr_free(d[c]); }
        }
        return st;
    }
    for (int c = 0; c < 3; c++) out[c] = d[c];
    return HD_OK;
}

/* multilinear interpolation over dimensions k.. at pt, the block at off,
 * weighted by coef: linear between the two nearest points, extrapolated
 * up to one division beyond the ends and tapering off harmonically to 0
 * further out (Radiance's rule for data files) */
static double dinterp(const darr *d, int k, const double *pt, size_t off, double coef)
{
    if (coef >= -FTINY && coef <= FTINY) return 0;
    int ne = d->dim[k].ne, i;
    double x;
    if (!d->dim[k].p) {
        x = (pt[k] - d->dim[k].org) / d->dim[k].siz * (ne - 1);
        i = (int)x;
        if (i < 0) i = 0;
        else if (i > ne - 2) i = ne - 2;
    } else {
        const double *p = d->dim[k].p;
        int lo = 0, hi = ne - 1, up = p[ne - 1] >= p[0];
        while (hi - lo > 1) {   /* p[lo] .. p[hi] bracket pt where possible */
            int mid = (lo + hi) / 2;
            if ((pt[k] >= p[mid]) == up) lo = mid;
            else hi = mid;
        }
        i = lo > ne - 2 ? ne - 2 : lo;
        x = i + (pt[k] - p[i]) / (p[i + 1] - p[i]);
    }
    double c0, c1;
    if (x > i + 2) {
        c0 = 1. / (i - 1 - x);
        c1 = -2. * c0;
    } else if (x < i - 1) {
        c1 = 1. / (x - i);
        c0 = -2. * c1;
    } else {
        c0 = i + 1 - x;
        c1 = x - i;
    }
    c0 *= coef;
    c1 *= coef;
    if (k == d->nd - 1) return c0 * d->v[off + i] + c1 * d->v[off + i + 1];
    size_t stride = 1;
    for (int j = k + 1; j < d->nd; j++) stride *= (size_t)d->dim[j].ne;
    return dinterp(d, k + 1, pt, off + (size_t)i * stride, c0) + dinterp(d, k + 1, pt, off + (size_t)(i + 1) * stride, c1);
}

/* ------------------------------------------------------------ text */
static void textpat_free(textpat *t)
{
    if (!t) return;
    for (int i = 0; i < t->nlines; i++) { free(t->line[i]); free(t->sp[i]); }
    free(t->line);
    free(t->sp);
    free(t->lw);
    hd_font_free(t->font);
    free(t);
}

static hd_status textpat_addline(textpat *t, const char *s)
{
    char **l = hd_realloc_array(t->line, (size_t)t->nlines + 1, sizeof *l);
    if (!l) return HD_ERR_NOMEM;
    t->line = l;
    short **sp = hd_realloc_array(t->sp, (size_t)t->nlines + 1, sizeof *sp);
    if (!sp) return HD_ERR_NOMEM;
    t->sp = sp;
    t->line[t->nlines] = hd_strdup(s);
    t->sp[t->nlines] = NULL;
    t->nlines++;
    return t->line[t->nlines - 1] ? HD_OK : HD_ERR_NOMEM;
}

/* brighttext / colortext: font text... (11 / 15 reals); mixtext: fore
 * back font text... (9 reals).  The text is the words after the font
 * joined by blanks, or, one word alone, a file of lines found through
 * RAYPATH. */
static hd_status textpat_new(int kind, char *const *sargs, int ns, const double *r, int nr, const char *where,
                             textpat **out)
{
    *out = NULL;
    int f0 = kind == MN_MIXT ? 2 : 0, nreal = kind == MN_BTEXT ? 11 : kind == MN_CTEXT ? 15 : 9;
    if (ns - (f0 + 1) < 1 || nr < nreal)
        return hd_fail(HD_ERR_FORMAT, "%s: expected %d string arguments (font, text) and %d reals, got %d and %d",
                       where, f0 + 2, nreal, ns, nr);
    textpat *t = hd_calloc(1, sizeof *t);
    if (!t) return HD_ERR_NOMEM;
    hd_status st = HD_OK;
    hd_vec3 R = hd_v3(r[3], r[4], r[5]), D = hd_v3(r[6], r[7], r[8]);
    hd_vec3 DxR = hd_vcross(D, R);
    t->org = hd_v3(r[0], r[1], r[2]);
    t->right = hd_vcross(DxR, D);
    double d = hd_vdot(t->right, t->right);
    if (d <= 1e-24) st = hd_fail(HD_ERR_FORMAT, "%s: illegal motion vector", where);
    if (!st) {
        t->right = hd_vscale(t->right, hd_vdot(D, D) / d);
        t->down = hd_vcross(R, DxR);
        t->down = hd_vscale(t->down, hd_vdot(R, R) / hd_vdot(t->down, t->down));
    }
    if (!st && ns - (f0 + 1) > 1) {            /* the text in the arguments */
        size_t L = 1;
        for (int i = f0 + 2; i < ns; i++) L += strlen(sargs[i]) + 1;
        char *b = malloc(L);
        if (!b) st = HD_ERR_NOMEM;
        else {
            b[0] = 0;
            for (int i = f0 + 2; i < ns; i++) { if (i > f0 + 2) strcat(b, " "); strcat(b, sargs[i]); }
            st = textpat_addline(t, b);
            free(b);
        }
    } else if (!st) {                           /* a text file */
        char path[4096];
        FILE *fp = hd_cal_findfile(sargs[f0 + 1], path, sizeof path) ? fopen(path, "r") : NULL;
        if (!fp) st = hd_fail(HD_ERR_IO, "%s: cannot find text file \"%s\"", where, sargs[f0 + 1]);
        char *buf = NULL;
        size_t cap = 0;
        ssize_t n;
        while (fp && !st && (n = getline(&buf, &cap, fp)) >= 0) {
            if (n > 0 && buf[n - 1] == '\n') buf[n - 1] = 0;
            st = textpat_addline(t, buf);
        }
        free(buf);
        if (fp) fclose(fp);
    }
    if (!st) st = hd_font_load(sargs[f0], &t->font);
    if (st) { textpat_free(t); return hd_fail_context(st, "%s", where); }
    double spacing = nr > nreal ? r[nreal] : 0;
    int gap = (int)(spacing * 255.0);
    t->xscale = nr > nreal ? t->font->mwidth + 255. * fabs(spacing) : 255.;
    if (!(t->lw = hd_calloc((size_t)t->nlines, sizeof *t->lw))) st = HD_ERR_NOMEM;
    for (int i = 0; i < t->nlines && !st; i++) {
        if (!(t->sp[i] = hd_malloc_array(strlen(t->line[i]) + 1, sizeof **t->sp))) { st = HD_ERR_NOMEM; break; }
        t->lw[i] = hd_font_layout_units(t->font, t->line[i], gap, t->sp[i]);
        if (t->lw[i] > t->width) t->width = t->lw[i];
    }
    if (st) { textpat_free(t); return st; }
    *out = t;
    return HD_OK;
}

/* whether point p is inside a glyph of the text (as Radiance's intext) */
static int textpat_inside(const textpat *t, hd_vec3 p)
{
    hd_vec3 v = hd_vsub(p, t->org);
    double x = hd_vdot(v, t->right) * t->xscale, y = hd_vdot(v, t->down);
    if (x < 0 || y < 0 || x > 1e9 || y > 1e9) return 0;
    int h = (int)x, i = (int)y;
    x -= h;
    y = ((i + 1) - y) * 255.;
    if (i >= t->nlines || h >= t->lw[i]) return 0;
    const char *s = t->line[i];
    for (int k = 0; (h -= t->sp[i][k]) >= 0; k++)
        if (h < 255 && hd_glyph_inside(t->font->g[(unsigned char)s[k]], h + x, y)) return 1;
    return 0;
}

/* ------------------------------------------------------------ nodes */
struct hd_modset *hd_modset_new(void) { return hd_calloc(1, sizeof(struct hd_modset)); }

void hd_modset_free(struct hd_modset *ms)
{
    if (!ms) return;
    for (size_t i = 0; i < ms->nnodes; i++) {
        struct hd_modnode *nd = ms->nodes[i];
        free(nd->args);
        for (int s = 0; s < 2; s++) {
            free(nd->smat[s]);
            free(nd->mixname[s]);
        }
        textpat_free(nd->tx);
        free(nd);
    }
    for (size_t i = 0; i < ms->nchains; i++) free(ms->chains[i]);
    for (size_t i = 0; i < ms->nfc; i++) fctx_free(ms->fc[i]);
    for (size_t i = 0; i < ms->ndata; i++) darr_free(ms->data[i]);
    free(ms->nodes);
    free(ms->chains);
    free(ms->fc);
    free(ms->data);
    free(ms);
}

static void set_state(evstate *e, const struct hd_modnode *nd, const hd_modray *ray)
{
    e->nd = nd;
    double rdot = -hd_vdot(ray->dir, ray->n);
    e->rdot = rdot < -1 ? -1 : rdot > 1 ? 1 : rdot;
    if (!nd->has_xf) {
        e->D = ray->dir;
        e->N = ray->n;
        e->P = ray->p;
        e->T = ray->t;
        return;
    }
    const double (*m)[3] = nd->im;
    hd_vec3 v[3] = {ray->dir, ray->n, ray->p}, o[3];
    for (int k = 0; k < 3; k++)
        o[k] = hd_v3(m[0][0] * v[k].x + m[0][1] * v[k].y + m[0][2] * v[k].z,
                     m[1][0] * v[k].x + m[1][1] * v[k].y + m[1][2] * v[k].z,
                     m[2][0] * v[k].x + m[2][1] * v[k].y + m[2][2] * v[k].z);
    e->D = hd_vscale(o[0], 1 / nd->isca);
    e->N = hd_vscale(o[1], 1 / nd->isca);
    e->P = hd_vadd(o[2], nd->it);
    e->T = ray->t * nd->isca;
}

/* evaluate the node's expressions (vals[0..nex)) and, for data nodes, the
 * data functions (out[0..2]); returns 0 on a fatal error (reported once) */
static int node_values(const struct hd_modnode *nd, const hd_modray *ray, double *vals, double out[3])
{
    slot spare;
    memset(&spare, 0, sizeof spare);
    slot *s = take(nd->fc, &spare);
    if (!s) return 0;
    set_state(&s->st, nd, ray);
    hd_calrun_next(s->run);
    for (int i = 0; i < nd->nex; i++) vals[i] = hd_calrun_expr(s->run, nd->ex[i]);
    if (HAS_DATA(nd->kind)) {
        double pt[MAXDDIM], col[3];
        if (nd->kind == MN_PICT || nd->kind == MN_MIXP) {
            pt[0] = vals[1];   /* y, then x */
            pt[1] = vals[0];
        } else {
            for (int i = 0; i < nd->nex; i++) pt[i] = vals[i];
        }
        int nc = NDATA(nd->kind), nf = NFUNC(nd->kind);
        int pict = nd->kind == MN_PICT || nd->kind == MN_MIXP;
        for (int c = 0; c < nc; c++)
            col[c] = c && nd->d[c] == nd->d[c - 1] && !pict ? col[c - 1] : dinterp(nd->d[c], 0, pt, 0, 1);
        for (int c = 0; c < nf; c++)
            out[c] = hd_calrun_call_id(s->run, nd->fn[c], nd->fnargs[c], nd->fnargs[c] == 1 ? &col[c] : col);
    }
    int ok = hd_calrun_status(s->run) == HD_OK;
    if (!ok) {
        static atomic_int told;
        if (!atomic_exchange(&told, 1)) hd_warn("%s: %s", nd->where, hd_errmsg());
        hd_calrun_clear(s->run);
    }
    give(nd->fc, s);
    return ok;
}

/* two materials of the same kind, whose parameters a mixture blends */
static int same_kind(const struct hd_tmat *a, const struct hd_tmat *b)
{
    return a && b && a->type == b->type && a->type != HD_MAT_BSDF && a->type != HD_MAT_ILLUM &&
           (a->type != HD_MAT_GLASS || a->rindex == b->rindex);
}

/* One side sd of a mixture as the material: its material (void: invisible,
 * transparent) with its pattern colour pc, no chain of its own. */
static void mix_side(const struct hd_modnode *nd, int sd, const struct hd_tmat *m, const double pc[3],
                     struct hd_tmat *tmp)
{
    if (!m) {
        hd_tmat_init(tmp, HD_MAT_INVISIBLE, nd->mixname[sd]);
    } else {
        if (tmp != m) *tmp = *m;
        for (int i = 0; i < 3; i++) tmp->color[i] *= pc[i];
    }
    tmp->chain = NULL;
    tmp->ownmods = NULL;
    tmp->mixed = 0;
}

static void mix_materials(const struct hd_modnode *nd, double coef, const struct hd_tmat *a, const double pa[3],
                          const struct hd_tmat *b, const double pb[3], struct hd_tmat *tmp)
{
    if (same_kind(a, b)) {
        /* the same kind of material: the parameters mixed (exact for the
         * colours, which every result is linear in) */
        hd_tmat m = *a;
        for (int i = 0; i < 3; i++) m.color[i] = coef * a->color[i] * pa[i] + (1 - coef) * b->color[i] * pb[i];
        m.spec = coef * a->spec + (1 - coef) * b->spec;
        m.rough = coef * a->rough + (1 - coef) * b->rough;
        m.trans = coef * a->trans + (1 - coef) * b->trans;
        m.tspec = coef * a->tspec + (1 - coef) * b->tspec;
        m.maxrad = coef * a->maxrad + (1 - coef) * b->maxrad;
        *tmp = m;
    } else {
        /* different kinds: the dominant one */
        int sd = coef >= .5 ? 0 : 1;
        mix_side(nd, sd, sd ? b : a, sd ? pb : pa, tmp);
        return;
    }
    tmp->chain = NULL;
    tmp->ownmods = NULL;
    tmp->mixed = 0;
}

static void mix_eval(const struct hd_modnode *nd, double c0, const hd_modray *ray, double pcol[3], hd_vec3 *pert,
                     const struct hd_tmat **mat, struct hd_tmat *tmp);

static void node_eval(const struct hd_modnode *nd, const hd_modray *ray, double pcol[3], hd_vec3 *pert,
                      const struct hd_tmat **mat, struct hd_tmat *tmp)
{
    double v[MAXDDIM], out[3];
    if (IS_TEXT(nd->kind)) {    /* inside a glyph: the foreground */
        int fg = textpat_inside(nd->tx, ray->p);
        if (nd->kind == MN_MIXT) mix_eval(nd, fg, ray, pcol, pert, mat, tmp);
        else if (nd->kind == MN_BTEXT)
            for (int i = 0; i < 3; i++) pcol[i] *= nd->args[fg ? 9 : 10];
        else
            for (int i = 0; i < 3; i++) pcol[i] *= nd->args[(fg ? 9 : 12) + i];
        return;
    }
    if (!node_values(nd, ray, v, out)) return;
    switch (nd->kind) {
    case MN_BRIGHT:
        for (int i = 0; i < 3; i++) pcol[i] *= v[0];
        return;
    case MN_COLOR:
        for (int i = 0; i < 3; i++) pcol[i] *= v[i];
        return;
    case MN_BDATA:
        for (int i = 0; i < 3; i++) pcol[i] *= out[0];
        return;
    case MN_CDATA:
    case MN_PICT:
        for (int i = 0; i < 3; i++) pcol[i] *= out[i];
        return;
    case MN_TEX:
    case MN_TDATA: {
        hd_vec3 d = nd->kind == MN_TEX ? hd_v3(v[0], v[1], v[2]) : hd_v3(out[0], out[1], out[2]);
        if (nd->has_xf) d = hd_xf_direction(&nd->fwd, d);
        *pert = hd_vadd(*pert, d);
        return;
    }
    case MN_MIX:
    case MN_MIXD:
    case MN_MIXP:
        mix_eval(nd, nd->kind == MN_MIX ? v[0] : out[0], ray, pcol, pert, mat, tmp);
        return;
    }
}

/* a mixture with coefficient c0 (clipped to 0..1) of its two sides */
static void mix_eval(const struct hd_modnode *nd, double c0, const hd_modray *ray, double pcol[3], hd_vec3 *pert,
                     const struct hd_tmat **mat, struct hd_tmat *tmp)
{
    {
        double coef = c0 > 1 ? 1 : c0 < 0 ? 0 : c0;
        if (mat && (ray->rng || ray->force) && (nd->smat[0] || nd->smat[1]) &&
            !same_kind(nd->smat[0], nd->smat[1])) {
            /* different materials: one side at random with its probability
             * (its own patterns and perturbation, as Radiance shades each
             * side), the fore side below coef; without rng (forced side of
             * a shadow ray) the middle of the side's range */
            double u = ray->rng ? hd_rng_uniform(ray->rng) : .5;
            if (ray->force == 1) u *= coef;
            else if (ray->force == 2) u = coef + (1 - coef) * u;
            int sd = u < coef ? 0 : 1;
            hd_modray r2 = *ray;
            r2.force = 0;
            double pcs[3] = {1, 1, 1};
            hd_vec3 dps = {0, 0, 0};
            const struct hd_tmat *smat = nd->smat[sd];
            struct hd_tmat stmp;
            if (nd->side[sd]) hd_modchain_eval(nd->side[sd], &r2, pcs, &dps, &smat, &stmp);
            *pert = hd_vadd(*pert, dps);
            mix_side(nd, sd, smat, pcs, tmp);
            tmp->mixsel = coef > FTINY && coef < 1 - FTINY ? coef : 0;
            *mat = tmp;
            return;
        }
        double pc[2][3] = {{1, 1, 1}, {1, 1, 1}};
        hd_vec3 dp[2] = {{0, 0, 0}, {0, 0, 0}};
        const struct hd_tmat *sm[2] = {nd->smat[0], nd->smat[1]};
        struct hd_tmat st[2];
        for (int s = 0; s < 2; s++) {
            double w = s ? 1 - coef : coef;
            if (w <= FTINY) continue;
            if (nd->side[s]) hd_modchain_eval(nd->side[s], ray, pc[s], &dp[s], &sm[s], &st[s]);
        }
        *pert = hd_vadd(*pert, hd_vadd(hd_vscale(dp[0], coef), hd_vscale(dp[1], 1 - coef)));
        if (!nd->smat[0] && !nd->smat[1]) {
            for (int i = 0; i < 3; i++) pcol[i] *= coef * pc[0][i] + (1 - coef) * pc[1][i];
            return;
        }
        if (!mat) {   /* no material wanted (an emitter's pattern chain): the colours */
            for (int i = 0; i < 3; i++) pcol[i] *= coef * pc[0][i] + (1 - coef) * pc[1][i];
            return;
        }
        mix_materials(nd, coef, coef > FTINY ? sm[0] : NULL, pc[0], coef < 1 - FTINY ? sm[1] : NULL, pc[1], tmp);
        *mat = tmp;
        tmp->mixsel = 0;
        return;
    }
}

void hd_modchain_eval(const struct hd_modchain *c, const hd_modray *ray, double pcol[3], hd_vec3 *pert,
                      const struct hd_tmat **mat, struct hd_tmat *tmp)
{
    if (!c) return;
    for (int i = 0; i < c->n; i++) node_eval(c->nd[i], ray, pcol, pert, mat, tmp);
}

hd_vec3 hd_perturb_normal(hd_vec3 n, hd_vec3 pert, hd_vec3 dir)
{
    hd_vec3 m = hd_vadd(n, pert);
    double len = hd_vlen(m);
    if (!(len > 0)) return n;
    m = hd_vscale(m, 1 / len);
    double d0 = -hd_vdot(n, dir), d1 = -hd_vdot(m, dir);
    if ((d1 > 0) != (d0 > 0)) m = hd_vadd(m, hd_vscale(dir, 2 * d1));   /* back to the side the ray sees */
    return m;
}

const struct hd_tmat *hd_tmat_modify(const struct hd_tmat *m, const hd_modray *ray, struct hd_tmat *tmp,
                                     hd_vec3 *pert)
{
    hd_vec3 pp = {0, 0, 0};
    if (pert) *pert = pp;
    if (!m->chain) return m;
    double pcol[3] = {1, 1, 1};
    const struct hd_tmat *mm = m;
    hd_modchain_eval(m->chain, ray, pcol, &pp, &mm, tmp);
    if (mm != tmp) *tmp = *mm;
    for (int i = 0; i < 3; i++) tmp->color[i] *= pcol[i];
    tmp->chain = NULL;
    tmp->ownmods = NULL;
    tmp->mixed = 0;
    if (pert) *pert = pp;
    return tmp;
}

void hd_emit_color(const hd_tmat *m, hd_vec3 dir, const struct hd_hit *h, double L[3])
{
    if (!m->chain) {
        double pat = hd_pattern_eval(m, dir);
        for (int i = 0; i < 3; i++) L[i] = m->color[i] * pat;
        return;
    }
    hd_modray ray = {dir, h ? h->p : hd_v3(0, 0, 0), h ? h->n : hd_v3(0, 0, 0), h ? h->t : 0, NULL, 0};
    double pcol[3] = {1, 1, 1};
    hd_vec3 pert = {0, 0, 0};
    hd_modchain_eval(m->chain, &ray, pcol, &pert, NULL, NULL);
    for (int i = 0; i < 3; i++) L[i] = m->color[i] * pcol[i];
}

/* ---- construction ---- */
static int is_xf_word(const char *w)
{
    return w[0] == '-' && isalpha((unsigned char)w[1]);
}

hd_status hd_modset_node(struct hd_modset *ms, const char *type, char *const *sargs, int ns, const double *r,
                         int nr, const char *where, struct hd_modnode **out)
{
    *out = NULL;
    int kind, ff, e0, ne = 0, minns;
    if (!strcmp(type, "brightfunc")) { kind = MN_BRIGHT; ff = 1; e0 = 0; ne = 1; minns = 2; }
    else if (!strcmp(type, "colorfunc")) { kind = MN_COLOR; ff = 3; e0 = 0; ne = 3; minns = 4; }
    else if (!strcmp(type, "texfunc")) { kind = MN_TEX; ff = 3; e0 = 0; ne = 3; minns = 4; }
    else if (!strcmp(type, "mixfunc")) { kind = MN_MIX; ff = 3; e0 = 2; ne = 1; minns = 4; }
    else if (!strcmp(type, "brightdata")) { kind = MN_BDATA; ff = 2; e0 = 3; minns = 4; }
    else if (!strcmp(type, "colordata")) { kind = MN_CDATA; ff = 6; e0 = 7; minns = 8; }
    else if (!strcmp(type, "colorpict")) { kind = MN_PICT; ff = 4; e0 = 5; ne = 2; minns = 7; }
    else if (!strcmp(type, "texdata")) { kind = MN_TDATA; ff = 6; e0 = 7; minns = 8; }
    else if (!strcmp(type, "mixdata")) { kind = MN_MIXD; ff = 4; e0 = 5; minns = 6; }
    else if (!strcmp(type, "mixpict")) { kind = MN_MIXP; ff = 4; e0 = 5; ne = 2; minns = 7; }
    else if (!strcmp(type, "brighttext") || !strcmp(type, "colortext") || !strcmp(type, "mixtext")) {
        kind = type[0] == 'b' ? MN_BTEXT : type[0] == 'c' ? MN_CTEXT : MN_MIXT;
        textpat *t;
        hd_status st = textpat_new(kind, sargs, ns, r, nr, where, &t);
        if (st) return st;
        struct hd_modnode *nd = hd_calloc(1, sizeof *nd);
        if (!nd || push((void **)&ms->nodes, &ms->nnodes, &ms->capnodes, sizeof *ms->nodes, &nd)) {
            free(nd);
            textpat_free(t);
            return HD_ERR_NOMEM;
        }
        nd->kind = kind;
        nd->tx = t;
        hd_strlcpy(nd->where, where, sizeof nd->where);
        if (!(nd->args = hd_malloc_array((size_t)nr, sizeof(double)))) return HD_ERR_NOMEM;
        memcpy(nd->args, r, (size_t)nr * sizeof(double));
        nd->nargs = nr;
        if (kind == MN_MIXT)
            for (int k = 0; k < 2; k++)
                if (!(nd->mixname[k] = hd_strdup(sargs[k]))) return HD_ERR_NOMEM;
        *out = nd;
        return HD_OK;
    }
    else return hd_fail(HD_ERR_UNSUPPORTED, "%s: modifier type %s is not supported by the ray tracer", where, type);
    if (ns < minns)
        return hd_fail(HD_ERR_FORMAT, "%s: %s: expected at least %d string arguments, got %d", where, type, minns, ns);
    struct hd_modnode *nd = hd_calloc(1, sizeof *nd);
    if (!nd) return HD_ERR_NOMEM;
    if (push((void **)&ms->nodes, &ms->nnodes, &ms->capnodes, sizeof *ms->nodes, &nd)) { free(nd); return HD_ERR_NOMEM; }
    nd->kind = kind;
    hd_strlcpy(nd->where, where, sizeof nd->where);
    if (nr > 0) {
        if (!(nd->args = hd_malloc_array((size_t)nr, sizeof(double)))) return HD_ERR_NOMEM;
        memcpy(nd->args, r, (size_t)nr * sizeof(double));
    }
    nd->nargs = nr;
    hd_status st = HD_OK;
    if (kind == MN_BDATA || kind == MN_CDATA || kind == MN_TDATA || kind == MN_MIXD) {
        int nc = NDATA(kind);
        for (int c = 0; c < nc && !st; c++) {
            const char *dn = sargs[(kind == MN_BDATA ? 1 : 3) + c];
            if (c && !strcmp(dn, sargs[3 + c - 1])) nd->d[c] = nd->d[c - 1];
            else st = load_data(ms, dn, where, &nd->d[c]);
        }
        if (st) return st;
        ne = nd->d[0]->nd;
        for (int c = 1; c < nc; c++)
            if (nd->d[c]->nd != ne)
                return hd_fail(HD_ERR_FORMAT, "%s: %s: data files of different dimensions", where, type);
    } else if (kind == MN_PICT || kind == MN_MIXP) {
        if ((st = load_pict(ms, sargs[3], where, nd->d))) return st;
    }
    if (ns < e0 + ne)
        return hd_fail(HD_ERR_FORMAT, "%s: %s: expected %d string arguments before the transform, got %d", where,
                       type, e0 + ne, ns);
    /* the transform starts at the first transform option after the
     * expressions and the file (other words there are ignored, as Radiance) */
    int x0 = e0 + ne > ff + 1 ? e0 + ne : ff + 1;
    while (x0 < ns && !is_xf_word(sargs[x0])) x0++;
    if (x0 < ns) {
        st = hd_xf_from_words(&nd->fwd, ns - x0, sargs + x0);
        if (st) return hd_fail_context(st, "%s: %s transform", where, type);
        nd->has_xf = 1;
        double s2 = nd->fwd.sca * nd->fwd.sca;
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) nd->im[i][j] = nd->fwd.m[j][i] / s2;
        hd_vec3 t = nd->fwd.t;
        nd->it = hd_v3(-(nd->im[0][0] * t.x + nd->im[0][1] * t.y + nd->im[0][2] * t.z),
                       -(nd->im[1][0] * t.x + nd->im[1][1] * t.y + nd->im[1][2] * t.z),
                       -(nd->im[2][0] * t.x + nd->im[2][1] * t.y + nd->im[2][2] * t.z));
        nd->isca = 1 / nd->fwd.sca;
    }
    if ((st = get_fctx(ms, sargs[ff], &nd->fc))) return hd_fail_context(st, "%s: %s function file", where, type);
    nd->nex = ne;
    for (int i = 0; i < ne && !st; i++) st = fctx_expr(nd->fc, sargs[e0 + i], where, &nd->ex[i]);
    if (st) return st;
    if (HAS_DATA(kind)) {
        int nf = NFUNC(kind), f0 = IS_MIX(kind) ? 2 : 0;   /* mixtures: after the two modifiers */
        for (int c = 0; c < nf; c++) {
            const char *fname = sargs[f0 + c];
            int np = hd_cal_nparams(nd->fc->cal, fname);
            nd->fn[c] = hd_cal_lookup(nd->fc->cal, fname);
            if (nd->fn[c] < 0 || np < 0)
                return hd_fail(HD_ERR_FORMAT, "%s: %s: '%s' is not a function defined in %s", where, type, fname,
                               sargs[ff]);
            /* brightdata, mixdata: one argument; mixpict, texdata: the
             * three values; colour data: the first function gets the
             * three values, the others theirs alone unless they take three */
            nd->fnargs[c] = kind == MN_BDATA || kind == MN_MIXD ? 1
                            : kind == MN_TDATA || kind == MN_MIXP ? 3 : (c == 0 || np >= 3) ? 3 : 1;
        }
    }
    if (IS_MIX(kind)) {
        for (int s = 0; s < 2; s++)
            if (!(nd->mixname[s] = hd_strdup(sargs[s]))) return HD_ERR_NOMEM;
    }
    /* one evaluation now, so that undefined names fail here, not per ray */
    hd_modray ray = {hd_v3(0, 0, -1), hd_v3(0, 0, 0), hd_v3(0, 0, 1), 1, NULL, 0};
    slot spare;
    memset(&spare, 0, sizeof spare);
    slot *sl = take(nd->fc, &spare);
    if (!sl) return HD_ERR_NOMEM;
    set_state(&sl->st, nd, &ray);
    hd_calrun_next(sl->run);
    for (int i = 0; i < nd->nex; i++) (void)hd_calrun_expr(sl->run, nd->ex[i]);
    st = hd_calrun_status(sl->run);
    if (st) {
        hd_calrun_clear(sl->run);
        st = hd_fail_context(st, "%s: %s", where, type);
    }
    give(nd->fc, sl);
    if (st) return st;
    *out = nd;
    return HD_OK;
}

const char *hd_modnode_mixname(const struct hd_modnode *nd, int side) { return nd->mixname[side]; }
int hd_modnode_is_mix(const struct hd_modnode *nd) { return IS_MIX(nd->kind); }

const struct hd_tmat *hd_modnode_material(const struct hd_modnode *nd)
{
    if (!IS_MIX(nd->kind)) return NULL;
    return nd->smat[0] ? nd->smat[0] : nd->smat[1];
}

hd_status hd_modnode_set_side(struct hd_modnode *nd, int side, const struct hd_modchain *chain,
                              const struct hd_tmat *mat)
{
    nd->side[side] = chain;
    free(nd->smat[side]);
    nd->smat[side] = NULL;
    if (mat) {
        if (!(nd->smat[side] = hd_malloc(sizeof *nd->smat[side]))) return HD_ERR_NOMEM;
        *nd->smat[side] = *mat;
        nd->smat[side]->ownmods = NULL;
    }
    return HD_OK;
}

hd_status hd_modset_chain(struct hd_modset *ms, struct hd_modnode *const *nodes, int n,
                          const struct hd_modchain **out)
{
    *out = NULL;
    if (n <= 0) return HD_OK;
    struct hd_modchain *c = hd_malloc(sizeof *c + (size_t)n * sizeof c->nd[0]);
    if (!c) return HD_ERR_NOMEM;
    c->n = n;
    for (int i = 0; i < n; i++) c->nd[i] = nodes[i];
    if (push((void **)&ms->chains, &ms->nchains, &ms->capchains, sizeof *ms->chains, &c)) {
        free(c);
        return HD_ERR_NOMEM;
    }
    *out = c;
    return HD_OK;
}

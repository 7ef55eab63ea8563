/* heliodon — LBNL/WINDOW BSDF XML loader (expat, streaming).
 *
 * The XML is parsed in one pass.  Small elements are collected as text;
 * <ScatteringData> is tokenised as it streams: numbers go straight into the
 * Klems value array or the tensor-tree value array, braces drive a stack
 * that builds the tree (children stored contiguously), so memory stays a
 * small multiple of the data. */
#include <expat.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "bsdf_internal.h"
#include "heliodon/io.h"

enum {
    E_OTHER = 0, E_WindowElement, E_FileType, E_Optical, E_Layer, E_Material, E_Name,
    E_Manufacturer, E_Thickness, E_Width, E_Height, E_Geometry, E_MGFblock,
    E_DataDefinition, E_IncidentDataStructure, E_AngleBasis, E_AngleBasisName,
    E_AngleBasisBlock, E_Theta, E_nPhis, E_ThetaBounds, E_LowerTheta, E_UpperTheta,
    E_WavelengthData, E_Wavelength, E_WavelengthDataBlock, E_WavelengthDataDirection,
    E_ColumnAngleBasis, E_RowAngleBasis, E_ScatteringData, E_COUNT
};
static const char *const ename[E_COUNT] = {
    "", "WindowElement", "FileType", "Optical", "Layer", "Material", "Name",
    "Manufacturer", "Thickness", "Width", "Height", "Geometry", "MGFblock",
    "DataDefinition", "IncidentDataStructure", "AngleBasis", "AngleBasisName",
    "AngleBasisBlock", "Theta", "nPhis", "ThetaBounds", "LowerTheta", "UpperTheta",
    "WavelengthData", "Wavelength", "WavelengthDataBlock", "WavelengthDataDirection",
    "ColumnAngleBasis", "RowAngleBasis", "ScatteringData"
};

/* Largest BSDF value accepted (1/sr): far above any measured or simulated
 * peak (a specular cell of 10^-6 sr), far below FLT_MAX. */
#define HD_BSDF_MAXVALUE 1e9
#define MAXDEPTH 64
#define MAXTREEDEPTH 24
#define MAXBASES 8
#define TXTCAP 4096

typedef struct tframe {
    int nchild;             /* children collected so far */
    hd_tnode child[16];
    size_t val0;            /* first value of this node */
    int hasval;
} tframe;

typedef struct loader {
    XML_Parser xp;
    const char *fname;
    hd_status st;
    int depth;
    int stack[MAXDEPTH];
    int root_seen, root_ok;
    char txt[TXTCAP];
    size_t ntxt;
    int layers;             /* <Layer> elements started */
    int skip_layer;         /* inside a second or later layer */
    double unit;            /* of the current Thickness/Width/Height */
    int ids;                /* 0 unknown, 1 Columns, 2 Rows, 3/4 trees */
    /* angle bases */
    hd_klems_basis bases[MAXBASES];
    int nbases;
    char bname[64];
    double bnd_lo[HD_KLEMS_MAXRINGS], bnd_hi[HD_KLEMS_MAXRINGS], bctr[HD_KLEMS_MAXRINGS];
    int bnphi[HD_KLEMS_MAXRINGS], nrings;
    double blk_theta, blk_lo, blk_hi;
    int blk_nphi, blk_has;  /* bits: 1 theta, 2 nphi, 4 lo, 8 hi */
    /* wavelength data */
    int wl;                 /* -1 unknown, 0 other, 1 visible */
    char dir[64], colb[64], rowb[64];
    unsigned long block_line;
    int in_sdata, sdata_seen, data_wanted;
    /* Klems numbers */
    float *num;
    size_t nnum, capnum;
    /* tree */
    hd_ttree tree;
    tframe fr[MAXTREEDEPTH];
    int tdepth;             /* open braces */
    int troot_done;
    /* number token across chunk boundaries */
    char tok[80];
    int ntok;
    hd_bsdf *b;
} loader;

static unsigned long cur_line(loader *L)
{
    return (unsigned long)XML_GetCurrentLineNumber(L->xp);
}

static void lfail(loader *L, hd_status st, const char *fmt, ...) HD_PRINTF(3, 4);
static void lfail(loader *L, hd_status st, const char *fmt, ...)
{
    if (L->st != HD_OK) return;
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    L->st = hd_fail(st, "%s: line %lu: %s", L->fname, cur_line(L), msg);
    XML_StopParser(L->xp, XML_FALSE);
}

static int elem_id(const char *name)
{
    const char *c = strrchr(name, ':');
    if (c) name = c + 1;
    for (int i = 1; i < E_COUNT; i++)
        if (!strcmp(name, ename[i])) return i;
    return E_OTHER;
}

static int parent(loader *L, int up)
{
    int i = L->depth - 1 - up;
    return i >= 0 ? L->stack[i] : -1;
}

static int inside(loader *L, int id)
{
    for (int i = 0; i < L->depth; i++)
        if (L->stack[i] == id) return 1;
    return 0;
}

/* trimmed copy of the collected text */
static const char *text(loader *L)
{
    L->txt[L->ntxt] = 0;
    char *s = L->txt;
    while (*s == ' ' || *s == '\t' || *s == '\n' || *s == '\r') s++;
    size_t n = strlen(s);
    while (n && (s[n - 1] == ' ' || s[n - 1] == '\t' || s[n - 1] == '\n' || s[n - 1] == '\r'))
        s[--n] = 0;
    return s;
}

static int text_number(loader *L, int id, double *v)
{
    const char *t = text(L);
    if (hd_parse_double(t, v)) {
        lfail(L, HD_ERR_FORMAT, "<%s>: expected a number, found '%.40s'", ename[id], t);
        return -1;
    }
    return 0;
}

/* ---- numbers ---- */
static const double p10[] = {1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10,
    1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

/* Fast decimal conversion of a complete token; returns 0 on success. */
static int parse_num(const char *s, int n, double *out)
{
    int i = 0, neg = 0, nd = 0, ex = 0;
    uint64_t m = 0;
    if (i < n && (s[i] == '+' || s[i] == '-')) neg = s[i++] == '-';
    int digits = 0;
    while (i < n && s[i] >= '0' && s[i] <= '9') {
        if (nd < 19) { m = m * 10 + (uint64_t)(s[i] - '0'); if (m) nd++; }
        else ex++;
        i++; digits++;
    }
    if (i < n && s[i] == '.') {
        i++;
        while (i < n && s[i] >= '0' && s[i] <= '9') {
            if (nd < 19) { m = m * 10 + (uint64_t)(s[i] - '0'); ex--; if (m) nd++; }
            i++; digits++;
        }
    }
    if (!digits) return -1;
    if (i < n && (s[i] == 'e' || s[i] == 'E')) {
        i++;
        int eneg = 0, e = 0, ed = 0;
        if (i < n && (s[i] == '+' || s[i] == '-')) eneg = s[i++] == '-';
        while (i < n && s[i] >= '0' && s[i] <= '9') {
            if (e < 10000) e = e * 10 + (s[i] - '0');
            i++; ed++;
        }
        if (!ed) return -1;
        ex += eneg ? -e : e;
    }
    if (i != n) return -1;
    double v = (double)m;
    if (ex > 0) v = ex <= 22 ? v * p10[ex] : v * pow(10.0, ex);
    else if (ex < 0) v = -ex <= 22 ? v / p10[-ex] : v * pow(10.0, ex);
    if (!isfinite(v)) return -1;
    *out = neg ? -v : v;
    return 0;
}

static int push_klems_num(loader *L, double v)
{
    if (HD_GROW(L->num, L->nnum + 1, L->capnum, 4096)) {
        lfail(L, HD_ERR_NOMEM, "<ScatteringData>: %s", hd_errmsg());
        return -1;
    }
    L->num[L->nnum++] = v > 0 ? (float)v : 0.0f;
    return 0;
}

static int push_tree_val(loader *L, double v)
{
    hd_ttree *t = &L->tree;
    if (L->tdepth == 0) {
        lfail(L, HD_ERR_FORMAT, "<ScatteringData>: value outside the tree's braces");
        return -1;
    }
    tframe *f = &L->fr[L->tdepth - 1];
    if (f->nchild) {
        lfail(L, HD_ERR_FORMAT, "<ScatteringData>: tree node mixes child nodes and values");
        return -1;
    }
    if (HD_GROW(t->val, t->nval + 1, t->capval, 65536)) {
        lfail(L, HD_ERR_NOMEM, "<ScatteringData>: %s", hd_errmsg());
        return -1;
    }
    f->hasval = 1;
    t->val[t->nval++] = v > 0 ? (float)v : 0.0f;
    return 0;
}

static int flush_tok(loader *L)
{
    if (!L->ntok) return 0;
    double v;
    int n = L->ntok;
    L->ntok = 0;
    if (parse_num(L->tok, n, &v)) {
        L->tok[n < (int)sizeof L->tok ? n : (int)sizeof L->tok - 1] = 0;
        lfail(L, HD_ERR_FORMAT, "<ScatteringData>: bad number '%.40s'", L->tok);
        return -1;
    }
    if (!L->data_wanted) return 0;
    /* values are stored as floats and summed over cells: one near FLT_MAX
     * (or beyond it) would become inf and then NaN in every integral */
    if (v > HD_BSDF_MAXVALUE) {
        lfail(L, HD_ERR_RANGE, "<ScatteringData>: value %g out of range (at most %g per sr)", v,
              HD_BSDF_MAXVALUE);
        return -1;
    }
    return L->ids >= 3 ? push_tree_val(L, v) : push_klems_num(L, v);
}

static int tree_open(loader *L)
{
    if (L->troot_done) {
        lfail(L, HD_ERR_FORMAT, "<ScatteringData>: text after the end of the tree");
        return -1;
    }
    if (L->tdepth >= MAXTREEDEPTH) {
        lfail(L, HD_ERR_FORMAT, "<ScatteringData>: tree deeper than %d levels", MAXTREEDEPTH);
        return -1;
    }
    if (L->tdepth > 0 && L->fr[L->tdepth - 1].hasval) {
        lfail(L, HD_ERR_FORMAT, "<ScatteringData>: tree node mixes values and child nodes");
        return -1;
    }
    tframe *f = &L->fr[L->tdepth++];
    f->nchild = 0;
    f->hasval = 0;
    f->val0 = L->tree.nval;
    return 0;
}

static int append_nodes(loader *L, const hd_tnode *nodes, int n, uint32_t *first)
{
    hd_ttree *t = &L->tree;
    if (HD_GROW(t->node, t->nnode + (size_t)n, t->capnode, 4096)) {
        lfail(L, HD_ERR_NOMEM, "<ScatteringData>: %s", hd_errmsg());
        return -1;
    }
    if (t->nnode + (size_t)n > UINT32_MAX) {
        lfail(L, HD_ERR_RANGE, "<ScatteringData>: too many tree nodes");
        return -1;
    }
    *first = (uint32_t)t->nnode;
    memcpy(t->node + t->nnode, nodes, (size_t)n * sizeof *nodes);
    t->nnode += (size_t)n;
    return 0;
}

static int tree_close(loader *L)
{
    int D = L->ids;
    if (L->tdepth == 0) {
        lfail(L, HD_ERR_FORMAT, "<ScatteringData>: unbalanced '}'");
        return -1;
    }
    tframe *f = &L->fr[L->tdepth - 1];
    hd_tnode me;
    int level = L->tdepth - 1;
    if (f->nchild) {
        if (f->nchild != (1 << D)) {
            lfail(L, HD_ERR_FORMAT, "<ScatteringData>: tree node at depth %d has %d child nodes "
                  "(expected %d for TensorTree%d)", level, f->nchild, 1 << D, D);
            return -1;
        }
        uint32_t first;
        if (append_nodes(L, f->child, f->nchild, &first)) return -1;
        me.k = -1;
        me.off = first;
    } else {
        size_t n = L->tree.nval - f->val0;
        int k = 0;
        size_t c = 1;
        while (c < n) { c <<= D; k++; }
        if (n == 0 || c != n) {
            lfail(L, HD_ERR_FORMAT, "<ScatteringData>: tree node at depth %d has %zu values "
                  "(expected 2^(%d*k) = 1, %d, %d, ...)", level, n, D, 1 << D, 1 << (2 * D));
            return -1;
        }
        if (f->val0 > UINT32_MAX) {
            lfail(L, HD_ERR_RANGE, "<ScatteringData>: too many tree values");
            return -1;
        }
        me.k = k;
        me.off = (uint32_t)f->val0;
        if (level + k > L->tree.maxlev) L->tree.maxlev = level + k;
        if (level + k > 24) {
            lfail(L, HD_ERR_RANGE, "<ScatteringData>: tree resolution 2^%d too fine", level + k);
            return -1;
        }
    }
    L->tdepth--;
    if (L->tdepth == 0) {
        L->tree.root = me;
        L->troot_done = 1;
    } else {
        tframe *p = &L->fr[L->tdepth - 1];
        if (p->nchild >= 16 || p->nchild >= (1 << D)) {
            lfail(L, HD_ERR_FORMAT, "<ScatteringData>: tree node at depth %d has more than %d "
                  "child nodes", L->tdepth - 1, 1 << D);
            return -1;
        }
        p->child[p->nchild++] = me;
    }
    return 0;
}

static void sdata_chars(loader *L, const char *s, int len)
{
    for (int i = 0; i < len && L->st == HD_OK; i++) {
        char c = s[i];
        if ((c >= '0' && c <= '9') || c == '.' || c == '-' || c == '+' || c == 'e' || c == 'E') {
            if (L->ntok >= (int)sizeof L->tok - 1) {
                L->tok[sizeof L->tok - 1] = 0;
                lfail(L, HD_ERR_FORMAT, "<ScatteringData>: bad number '%.40s...'", L->tok);
                return;
            }
            L->tok[L->ntok++] = c;
            continue;
        }
        if (flush_tok(L)) return;
        if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == ',') continue;
        if ((c == '{' || c == '}') && L->ids >= 3) {
            if (!L->data_wanted) continue;
            if (c == '{') tree_open(L); else tree_close(L);
            continue;
        }
        if (c == '{' || c == '}')
            lfail(L, HD_ERR_FORMAT, "<ScatteringData>: unexpected '%c' in Klems matrix data", c);
        else
            lfail(L, HD_ERR_FORMAT, "<ScatteringData>: unexpected character '%c'", c);
    }
}

/* ---- element handlers ---- */
static double unit_scale(const char **atts)
{
    for (int i = 0; atts && atts[i]; i += 2) {
        if (strcasecmp(atts[i], "unit")) continue;
        const char *u = atts[i + 1];
        if (!strcasecmp(u, "meter")) return 1;
        if (!strcasecmp(u, "foot")) return 0.3048;
        if (!strcasecmp(u, "inch")) return 0.0254;
        if (!strcasecmp(u, "centimeter")) return 0.01;
        if (!strcasecmp(u, "millimeter")) return 0.001;
        return -1;
    }
    return 1;
}

static void reset_block(loader *L)
{
    L->dir[0] = L->colb[0] = L->rowb[0] = 0;
    L->nnum = 0;
    L->sdata_seen = 0;
    hd_ttree_free(&L->tree);
    memset(&L->tree, 0, sizeof L->tree);
    L->tdepth = 0;
    L->troot_done = 0;
    L->block_line = cur_line(L);
}

static void XMLCALL on_start(void *ud, const char *name, const char **atts)
{
    loader *L = ud;
    if (L->st != HD_OK) return;
    int id = elem_id(name);
    if (!L->root_seen) {
        L->root_seen = 1;
        if (id != E_WindowElement) {
            lfail(L, HD_ERR_FORMAT, "root element is <%s>, expected <WindowElement>", name);
            return;
        }
        L->root_ok = 1;
    }
    if (L->depth >= MAXDEPTH) {
        lfail(L, HD_ERR_FORMAT, "<%s>: elements nested more than %d deep", name, MAXDEPTH);
        return;
    }
    L->stack[L->depth++] = id;
    L->ntxt = 0;
    if (L->in_sdata) {
        lfail(L, HD_ERR_FORMAT, "<ScatteringData>: unexpected element <%s> inside the data", name);
        return;
    }
    if (id == E_Layer && parent(L, 1) == E_Optical) {
        if (L->layers++ > 0) L->skip_layer = 1;
        return;
    }
    if (L->skip_layer) return;
    switch (id) {
    case E_Thickness: case E_Width: case E_Height:
        L->unit = unit_scale(atts);
        if (L->unit < 0) lfail(L, HD_ERR_FORMAT, "<%s>: unknown unit", ename[id]);
        break;
    case E_MGFblock:
        break;
    case E_AngleBasis:
        if (parent(L, 1) == E_DataDefinition) {
            if (L->nbases >= MAXBASES) {
                lfail(L, HD_ERR_RANGE, "<AngleBasis>: more than %d angle bases", MAXBASES);
                return;
            }
            L->bname[0] = 0;
            L->nrings = 0;
        }
        break;
    case E_AngleBasisBlock:
        L->blk_has = 0;
        break;
    case E_WavelengthData:
        L->wl = -1;
        break;
    case E_WavelengthDataBlock:
        reset_block(L);
        break;
    case E_ScatteringData:
        if (parent(L, 1) != E_WavelengthDataBlock) break;
        if (L->sdata_seen) {
            lfail(L, HD_ERR_FORMAT, "<WavelengthDataBlock>: more than one <ScatteringData>");
            return;
        }
        if (!L->ids) {
            lfail(L, HD_ERR_FORMAT, "<ScatteringData> before <IncidentDataStructure>");
            return;
        }
        L->in_sdata = 1;
        L->sdata_seen = 1;
        L->data_wanted = L->wl != 0;
        L->ntok = 0;
        break;
    default:
        break;
    }
}

static void finish_basis_block(loader *L)
{
    if (!(L->blk_has & 2)) {
        lfail(L, HD_ERR_FORMAT, "<AngleBasisBlock>: missing <nPhis>");
        return;
    }
    if ((L->blk_has & 12) != 12) {
        /* no ThetaBounds: allowed only if it can be inferred (not here) */
        lfail(L, HD_ERR_FORMAT, "<AngleBasisBlock>: missing <ThetaBounds> with <LowerTheta> and <UpperTheta>");
        return;
    }
    if (L->nrings >= HD_KLEMS_MAXRINGS) {
        lfail(L, HD_ERR_RANGE, "<AngleBasis>: more than %d rings", HD_KLEMS_MAXRINGS);
        return;
    }
    int r = L->nrings++;
    L->bnd_lo[r] = L->blk_lo;
    L->bnd_hi[r] = L->blk_hi;
    L->bctr[r] = (L->blk_has & 1) ? L->blk_theta : 0.5 * (L->blk_lo + L->blk_hi);
    L->bnphi[r] = L->blk_nphi;
}

static void finish_basis(loader *L)
{
    if (!L->bname[0]) {
        lfail(L, HD_ERR_FORMAT, "<AngleBasis>: missing <AngleBasisName>");
        return;
    }
    if (!L->nrings) {
        lfail(L, HD_ERR_FORMAT, "<AngleBasis> '%s': no <AngleBasisBlock>", L->bname);
        return;
    }
    double bnd[HD_KLEMS_MAXRINGS + 1];
    for (int r = 0; r < L->nrings; r++) {
        bnd[r] = L->bnd_lo[r];
        if (r && fabs(L->bnd_lo[r] - L->bnd_hi[r - 1]) > 1e-6) {
            lfail(L, HD_ERR_FORMAT, "<AngleBasis> '%s': ring %d starts at %g deg but ring %d "
                  "ends at %g deg", L->bname, r, L->bnd_lo[r], r - 1, L->bnd_hi[r - 1]);
            return;
        }
    }
    bnd[L->nrings] = L->bnd_hi[L->nrings - 1];
    if (hd_klems_init(&L->bases[L->nbases], L->bname, L->nrings, bnd, L->bnphi, L->bctr)) {
        lfail(L, HD_ERR_FORMAT, "%s", hd_errmsg());
        return;
    }
    L->nbases++;
}

static int find_basis(loader *L, const char *name, hd_klems_basis *out, const char *what)
{
    if (!name[0]) {
        lfail(L, HD_ERR_FORMAT, "<WavelengthDataBlock> (line %lu): missing <%s>", L->block_line, what);
        return -1;
    }
    for (int i = 0; i < L->nbases; i++)
        if (!strcmp(L->bases[i].name, name)) { *out = L->bases[i]; return 0; }
    if (hd_klems_by_name(out, name) == HD_OK) return 0;
    lfail(L, HD_ERR_FORMAT, "<%s>: angle basis '%s' is not defined in <DataDefinition>", what, name);
    return -1;
}

static int dir_to_comp(const char *d)
{
    if (!strcasecmp(d, "Transmission Front")) return HD_BSDF_TB;
    if (!strcasecmp(d, "Transmission Back")) return HD_BSDF_TF;
    if (!strcasecmp(d, "Reflection Front")) return HD_BSDF_RB;
    if (!strcasecmp(d, "Reflection Back")) return HD_BSDF_RF;
    return -1;
}

static void finish_block(loader *L)
{
    if (L->wl == 0) return;             /* not the visible spectrum */
    if (L->wl < 0) {
        lfail(L, HD_ERR_FORMAT, "<WavelengthDataBlock> (line %lu): no <Wavelength> in its "
              "<WavelengthData>", L->block_line);
        return;
    }
    if (!L->dir[0]) {
        lfail(L, HD_ERR_FORMAT, "<WavelengthDataBlock> (line %lu): missing <WavelengthDataDirection>",
              L->block_line);
        return;
    }
    int c = dir_to_comp(L->dir);
    if (c < 0) {
        lfail(L, HD_ERR_FORMAT, "<WavelengthDataDirection>: unknown direction '%s' (expected "
              "Transmission Front/Back or Reflection Front/Back)", L->dir);
        return;
    }
    if (!L->sdata_seen) {
        lfail(L, HD_ERR_FORMAT, "<WavelengthDataBlock> '%s' (line %lu): missing <ScatteringData>",
              L->dir, L->block_line);
        return;
    }
    if (L->b->blk[c]) {
        lfail(L, HD_ERR_FORMAT, "<WavelengthDataBlock>: second visible '%s' block", L->dir);
        return;
    }
    hd_bsdf_block *d = hd_calloc(1, sizeof *d);
    if (!d) { lfail(L, HD_ERR_NOMEM, "%s", hd_errmsg()); return; }
    d->id = c;
    if (L->ids >= 3) {
        if (!L->troot_done || L->tree.nval == 0) {
            lfail(L, HD_ERR_FORMAT, "<ScatteringData> of '%s': truncated or empty tensor tree "
                  "(%d unclosed '{')", L->dir, L->tdepth);
            free(d);
            return;
        }
        d->kind = L->ids;
        d->tree = L->tree;
        d->tree.dim = L->ids;
        /* give back the growth slack of the arrays */
        float *v = realloc(d->tree.val, (d->tree.nval ? d->tree.nval : 1) * sizeof *v);
        if (v) { d->tree.val = v; d->tree.capval = d->tree.nval; }
        if (d->tree.nnode) {
            hd_tnode *nd = realloc(d->tree.node, d->tree.nnode * sizeof *nd);
            if (nd) { d->tree.node = nd; d->tree.capnode = d->tree.nnode; }
        }
        memset(&L->tree, 0, sizeof L->tree);
        L->troot_done = 0;
    } else {
        if (find_basis(L, L->colb, &d->inb, "ColumnAngleBasis") ||
            find_basis(L, L->rowb, &d->outb, "RowAngleBasis")) { free(d); return; }
        size_t ninc = (size_t)d->inb.nbins, nout = (size_t)d->outb.nbins;
        if (L->nnum != ninc * nout) {
            lfail(L, HD_ERR_FORMAT, "<ScatteringData> of '%s': %zu values, expected %zu "
                  "(%zu rows x %zu columns)", L->dir, L->nnum, ninc * nout, nout, ninc);
            free(d);
            return;
        }
        d->kind = 1;
        d->mtx = hd_malloc_array(ninc * nout, sizeof(float));
        if (!d->mtx) { lfail(L, HD_ERR_NOMEM, "%s", hd_errmsg()); free(d); return; }
        if (L->ids == 1) memcpy(d->mtx, L->num, ninc * nout * sizeof(float));
        else    /* Rows: each text row is one incident direction */
            for (size_t i = 0; i < ninc; i++)
                for (size_t o = 0; o < nout; o++) d->mtx[o * ninc + i] = L->num[i * nout + o];
    }
    L->b->blk[c] = d;
}

static void XMLCALL on_end(void *ud, const char *name)
{
    loader *L = ud;
    (void)name;
    if (L->st != HD_OK || L->depth == 0) return;
    int id = L->stack[L->depth - 1];
    hd_bsdf_info *inf = &L->b->info;
    if (id == E_Layer && parent(L, 1) == E_Optical) {
        L->skip_layer = 0;
        L->depth--;
        return;
    }
    if (L->skip_layer || (L->layers == 0 && id != E_WindowElement && id != E_FileType)) {
        L->depth--;
        L->ntxt = 0;
        return;
    }
    double v;
    switch (id) {
    case E_FileType:
        if (strcasecmp(text(L), "BSDF"))
            lfail(L, HD_ERR_FORMAT, "<FileType> is '%.40s', expected 'BSDF'", text(L));
        break;
    case E_Name:
        if (parent(L, 1) == E_Material) snprintf(inf->name, sizeof inf->name, "%s", text(L));
        break;
    case E_Manufacturer:
        if (parent(L, 1) == E_Material) snprintf(inf->manufacturer, sizeof inf->manufacturer, "%s", text(L));
        break;
    case E_Thickness: case E_Width: case E_Height:
        if (parent(L, 1) != E_Material) break;
        if (!text(L)[0]) break;   /* empty (wrapBSDF without t=, w=, h=): absent, as Radiance */
        if (text_number(L, id, &v)) break;
        if (v < 0) { lfail(L, HD_ERR_FORMAT, "<%s>: negative value %g", ename[id], v); break; }
        v *= L->unit;
        if (id == E_Thickness) inf->thickness = v;
        else if (id == E_Width) inf->width = v;
        else inf->height = v;
        break;
    case E_MGFblock:
        if (text(L)[0]) inf->has_geometry = 1;
        break;
    case E_IncidentDataStructure: {
        const char *t = text(L);
        if (!strcasecmp(t, "Columns")) L->ids = 1;
        else if (!strcasecmp(t, "Rows")) L->ids = 2;
        else if (!strcasecmp(t, "TensorTree3")) L->ids = 3;
        else if (!strcasecmp(t, "TensorTree4")) L->ids = 4;
        else lfail(L, HD_ERR_UNSUPPORTED, "<IncidentDataStructure>: unsupported '%.40s' (expected "
                   "Columns, Rows, TensorTree3 or TensorTree4)", t);
        break;
    }
    case E_AngleBasisName:
        snprintf(L->bname, sizeof L->bname, "%s", text(L));
        break;
    case E_Theta:
        if (!text_number(L, id, &L->blk_theta)) L->blk_has |= 1;
        break;
    case E_nPhis:
        if (text_number(L, id, &v)) break;
        if (v != floor(v) || v < 1 || v > HD_KLEMS_MAXBINS) {
            lfail(L, HD_ERR_FORMAT, "<nPhis>: %g is not a count from 1 to %d", v, HD_KLEMS_MAXBINS);
            break;
        }
        L->blk_nphi = (int)v;
        L->blk_has |= 2;
        break;
    case E_LowerTheta:
        if (!text_number(L, id, &L->blk_lo)) L->blk_has |= 4;
        break;
    case E_UpperTheta:
        if (!text_number(L, id, &L->blk_hi)) L->blk_has |= 8;
        break;
    case E_AngleBasisBlock:
        finish_basis_block(L);
        break;
    case E_AngleBasis:
        if (parent(L, 1) == E_DataDefinition) finish_basis(L);
        break;
    case E_Wavelength: {
        const char *t = text(L);
        L->wl = !strcasecmp(t, "Visible") ? 1 : 0;
        break;
    }
    case E_WavelengthDataDirection:
        snprintf(L->dir, sizeof L->dir, "%s", text(L));
        break;
    case E_ColumnAngleBasis:
        snprintf(L->colb, sizeof L->colb, "%s", text(L));
        break;
    case E_RowAngleBasis:
        snprintf(L->rowb, sizeof L->rowb, "%s", text(L));
        break;
    case E_ScatteringData:
        if (!L->in_sdata) break;
        flush_tok(L);
        L->in_sdata = 0;
        if (L->st == HD_OK && L->ids >= 3 && L->data_wanted && (L->tdepth || !L->troot_done))
            lfail(L, HD_ERR_FORMAT, "<ScatteringData> of '%s': truncated tensor tree "
                  "(%d unclosed '{')", L->dir[0] ? L->dir : "?", L->tdepth);
        break;
    case E_WavelengthDataBlock:
        if (inside(L, E_WavelengthData)) finish_block(L);
        break;
    default:
        break;
    }
    L->depth--;
    L->ntxt = 0;
}

static void XMLCALL on_chars(void *ud, const char *s, int len)
{
    loader *L = ud;
    if (L->st != HD_OK) return;
    if (L->in_sdata) { sdata_chars(L, s, len); return; }
    if (L->ntxt + (size_t)len >= TXTCAP) len = (int)(TXTCAP - 1 - L->ntxt);
    if (len > 0) { memcpy(L->txt + L->ntxt, s, (size_t)len); L->ntxt += (size_t)len; }
}

void hd_ttree_free(hd_ttree *t)
{
    free(t->node);
    free(t->val);
    t->node = NULL;
    t->val = NULL;
    t->nnode = t->nval = t->capnode = t->capval = 0;
}

typedef struct src { hd_istream *is; const char *mem; size_t len, pos; } src;

static hd_status load_any(src *in, const char *name, hd_bsdf **out)
{
    *out = NULL;
    loader *L = hd_calloc(1, sizeof *L);
    if (!L) return HD_ERR_NOMEM;
    hd_bsdf *b = hd_calloc(1, sizeof *b);
    if (!b) { free(L); return HD_ERR_NOMEM; }
    L->b = b;
    L->fname = name;
    L->wl = -1;
    L->xp = XML_ParserCreate(NULL);
    if (!L->xp) { free(L); free(b); return hd_fail(HD_ERR_NOMEM, "%s: cannot create XML parser", name); }
    XML_SetUserData(L->xp, L);
    XML_SetElementHandler(L->xp, on_start, on_end);
    XML_SetCharacterDataHandler(L->xp, on_chars);
    enum { CHUNK = 1 << 16 };
    char *buf = in->is ? hd_malloc(CHUNK) : NULL;
    if (in->is && !buf) L->st = HD_ERR_NOMEM;
    int done = 0;
    while (L->st == HD_OK && !done) {
        const char *p;
        size_t n;
        if (in->is) {
            n = hd_istream_read(in->is, buf, CHUNK);
            if (hd_istream_failed(in->is)) { L->st = hd_fail(HD_ERR_IO, "%s: read error", name); break; }
            p = buf;
        } else {
            n = in->len - in->pos;
            if (n > ((size_t)1 << 30)) n = (size_t)1 << 30;
            p = in->mem + in->pos;
            in->pos += n;
        }
        done = n == 0;
        if (XML_Parse(L->xp, p, (int)n, done) == XML_STATUS_ERROR && L->st == HD_OK)
            L->st = hd_fail(HD_ERR_FORMAT, "%s: line %lu: malformed XML: %s", name,
                            (unsigned long)XML_GetCurrentLineNumber(L->xp),
                            XML_ErrorString(XML_GetErrorCode(L->xp)));
    }
    free(buf);
    hd_status st = L->st;
    if (st == HD_OK && !L->root_ok)
        st = hd_fail(HD_ERR_FORMAT, "%s: no <WindowElement> root element", name);
    if (st == HD_OK && L->layers == 0)
        st = hd_fail(HD_ERR_FORMAT, "%s: no <Optical><Layer> element", name);
    if (st == HD_OK && !L->ids)
        st = hd_fail(HD_ERR_FORMAT, "%s: missing <IncidentDataStructure> in <DataDefinition>", name);
    if (st == HD_OK) {
        int any = 0;
        for (int c = 0; c < 4; c++) any |= b->blk[c] != NULL;
        if (!any) st = hd_fail(HD_ERR_FORMAT, "%s: no visible-spectrum <WavelengthDataBlock> "
                               "with <ScatteringData>", name);
    }
    if (st == HD_OK) st = hd_bsdf_finish(b, name);
    XML_ParserFree(L->xp);
    free(L->num);
    hd_ttree_free(&L->tree);
    free(L);
    if (st != HD_OK) { hd_bsdf_free(b); return st; }
    *out = b;
    return HD_OK;
}

hd_status hd_bsdf_load(const char *path, hd_bsdf **out)
{
    src in = {0};
    hd_status st = hd_istream_open(&in.is, path);
    if (st) return st;
    st = load_any(&in, path, out);
    hd_status st2 = hd_istream_close(in.is);
    if (st == HD_OK && st2 != HD_OK) {
        hd_bsdf_free(*out);
        *out = NULL;
        return st2;
    }
    return st;
}

hd_status hd_bsdf_load_memory(const char *data, size_t len, const char *name, hd_bsdf **out)
{
    src in = {0};
    in.mem = data;
    in.len = len;
    return load_any(&in, name ? name : "(memory)", out);
}

void hd_bsdf_free(hd_bsdf *b)
{
    if (!b) return;
    for (int c = 0; c < 4; c++) {
        if (!b->blk[c]) continue;
        free(b->blk[c]->mtx);
        free(b->blk[c]->hemi);
        hd_ttree_free(&b->blk[c]->tree);
        hd_block_store_free(b->blk[c]);
        free(b->blk[c]);
    }
    free(b);
}

/* heliodon — radial-basis interpolants from PAB-Opto goniophotometer files
 * (pabopto2bsdf): reading and checking the files, fitting Gaussian lobes
 * per incident direction over an adaptive quadtree of the Shirley-Chiu
 * grid, the mesh over the incident directions and the lobe transport
 * plans along its edges (docs/design/measured.md). */
#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "heliodon/bsdf.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/parallel.h"
#include "heliodon/rbf.h"
#include "transport.h"

#define GR HD_RBF_GRIDRES
#define TINY 1e-6
#define RSCA 2.0             /* lobe radius / leaf size (empirical) */
#define MAXSLOPE 200.0       /* steepest plane for a smooth region */
#define SMOOTH_MSE 5e-5      /* accepted mean squared error */
#define SMOOTH_MSER 0.0005   /* accepted relative mean squared error */
#define MAX_RAD (GR / 8)     /* largest merged region */
#define NEIGH_FACT2 0.1      /* weight of the neighbourhood difference in the transport cost */
#define HISTLEN 256
#define BSDF2BIG (1. / HD_PI)
#define BSDF2SML 1e-8
#define HISTLNR 17.2759509   /* log(BSDF2BIG/BSDF2SML) */
#define DFCHROMA 49750       /* encoded chromaticity of white (photopic data) */

/* ---- input files ---- */

typedef struct pab_in {
    const char *path;
    double theta, phi, up_phi;
    int igp[2];
    int isDSF, nspec;
    long dline;              /* first data line */
} pab_in;

typedef struct fitter {
    hd_rbfrep *r;
    const hd_pabopto_opts *o;
    double theta_in, phi_in;
    /* current grid */
    float *sum;              /* GR*GR */
    unsigned *cnt;
    unsigned long hist[HISTLEN];
    size_t dcap;
} fitter;

static void grid_pos(pab_in *p)
{
    if (p->theta <= TINY) { p->igp[0] = p->igp[1] = GR / 2 - 1; return; }
    double st = sin(HD_PI / 180. * p->theta);
    hd_vec3 v = hd_v3(cos(HD_PI / 180. * p->phi) * st, sin(HD_PI / 180. * p->phi) * st, sqrt(1. - st * st));
    double n = 1. / sqrt(1. + fabs(v.z)), sx, sy;
    hd_disk2square(v.x * n, v.y * n, &sx, &sy);
    p->igp[0] = (int)(sx * GR);
    p->igp[1] = (int)(sy * GR);
}

static int cmp_in(const void *a, const void *b)
{
    const pab_in *x = a, *y = b;
    if (x->igp[1] != y->igp[1]) return x->igp[1] - y->igp[1];
    return x->igp[0] - y->igp[0];
}

static const char *skipws(const char *s)
{
    while (*s == ' ' || *s == '\t') s++;
    return s;
}

/* header of one file: keys on lines starting with '#' */
static hd_status read_head(pab_in *p, const char *path, const hd_pabopto_opts *o, hd_rbfrep *r)
{
    hd_istream *in;
    hd_status st = hd_istream_open(&in, path);
    if (st != HD_OK) return st;
    p->path = path;
    p->isDSF = -1;
    p->nspec = 0;
    p->up_phi = 0;
    p->theta = p->phi = -10001.;
    long theta_line = 0;
    char ln[4096];
    long len, lineno = 0;
    p->dline = 0;
    while ((len = hd_istream_getline(in, ln, sizeof ln)) != -1) {
        lineno++;
        if (len == -2) {
            hd_istream_close(in);
            return hd_fail(HD_ERR_FORMAT, "%s: line %ld: longer than %zu characters", path, lineno, sizeof ln - 1);
        }
        const char *s = skipws(ln);
        if (*s == 0) continue;
        if (*s != '#') { p->dline = lineno; break; }
        s = skipws(s + 1);
        char typ[64];
        if (sscanf(s, "sample_name \"%255[^\"]\"", r->name) == 1) continue;
        if (sscanf(s, "colorimetry: %63s", typ) == 1) {
            if (!strcasecmp(typ, "CIE-XYZ")) p->nspec = 3;
            else if (!strcasecmp(typ, "CIE-Y")) p->nspec = 1;
            else {
                hd_istream_close(in);
                return hd_fail(HD_ERR_UNSUPPORTED, "%s: line %ld: colorimetry '%s' (CIE-Y or CIE-XYZ expected)", path,
                               lineno, typ);
            }
            continue;
        }
        if (sscanf(s, "format: theta phi %63s", typ) == 1) {
            if (!strcasecmp(typ, "DSF")) p->isDSF = 1;
            else if (!strcasecmp(typ, "BSDF") || !strcasecmp(typ, "BRDF") || !strcasecmp(typ, "BTDF")) p->isDSF = 0;
            else {
                hd_istream_close(in);
                return hd_fail(HD_ERR_FORMAT, "%s: line %ld: format '%s' (DSF, BSDF, BRDF or BTDF expected)", path,
                               lineno, typ);
            }
            continue;
        }
        if (sscanf(s, "upphi %lf", &p->up_phi) == 1) continue;
        if (sscanf(s, "intheta %lf", &p->theta) == 1) { theta_line = lineno; continue; }
        if (sscanf(s, "inphi %lf", &p->phi) == 1) continue;
        if (sscanf(s, "incident_angle %lf %lf", &p->theta, &p->phi) == 2) { theta_line = lineno; continue; }
    }
    int failed = hd_istream_failed(in);
    hd_istream_close(in);
    if (failed) return hd_fail(HD_ERR_IO, "%s: read error", path);
    long hl = p->dline ? p->dline - 1 : lineno;
    if (p->isDSF < 0)
        return hd_fail(HD_ERR_FORMAT, "%s: no '#format: theta phi DSF|BSDF' line in the header (lines 1-%ld)", path,
                       hl);
    if (p->theta < -10000. || p->phi < -10000.)
        return hd_fail(HD_ERR_FORMAT,
                       "%s: no incident angle in the header (lines 1-%ld): '#intheta' and '#inphi' or "
                       "'#incident_angle theta phi' expected", path, hl);
    if (!(p->theta >= 0 && p->theta <= 180.) || !(fabs(p->phi) <= 720.))
        return hd_fail(HD_ERR_RANGE, "%s: line %ld: incident angle theta %g phi %g out of range (0..180, -720..720)",
                       path, theta_line, p->theta, p->phi);
    if (!p->dline) return hd_fail(HD_ERR_FORMAT, "%s: no data rows after the header (%ld lines)", path, lineno);
    if (o->flip) {
        p->theta = 180. - p->theta;
        p->phi = 360. - p->phi;
    }
    p->phi += 90. - p->up_phi;
    grid_pos(p);
    return HD_OK;
}

/* register a new incident direction; 0 on error (message set) */
static hd_status new_direction(fitter *f, double th, double ph, const char *path)
{
    hd_rbfrep *r = f->r;
    while (th < -180.) th += 360.;
    while (th > 180.) th -= 360.;
    if (th < 0) { th = -th; ph += 180.; }
    while (ph < 0) ph += 360.;
    while (ph >= 360.) ph -= 360.;
    if (!r->input_orient) r->input_orient = 1 - 2 * (th > 90.);
    else if ((r->input_orient > 0) != (th < 90.))
        return hd_fail(HD_ERR_FORMAT, "%s: incident theta %g is on the other side of the surface from the files "
                       "before it (one component per run: all incident theta below 90 or all above)", path, th);
    memset(f->sum, 0, sizeof(float) * GR * GR);
    memset(f->cnt, 0, sizeof(unsigned) * GR * GR);
    if ((f->theta_in = th) < 1.0) return HD_OK;   /* phi is meaningless near the normal */
    if (r->single_plane > 0) r->single_plane = (int)floor(ph + .5) == (int)floor(f->phi_in + .5);
    else if (r->single_plane < 0) r->single_plane = 1;
    f->phi_in = ph;
    if (1. < ph && ph < 89.) r->inp_coverage |= HD_RBF_Q1;
    else if (91. < ph && ph < 179.) r->inp_coverage |= HD_RBF_Q2;
    else if (181. < ph && ph < 269.) r->inp_coverage |= HD_RBF_Q3;
    else if (271. < ph && ph < 359.) r->inp_coverage |= HD_RBF_Q4;
    return HD_OK;
}

/* data rows of one file into the current grid */
static hd_status read_data(fitter *f, const pab_in *p, double lim_graze)
{
    hd_rbfrep *r = f->r;
    hd_istream *in;
    hd_status st = hd_istream_open(&in, p->path);
    if (st != HD_OK) return st;
    char ln[4096];
    long lineno = 0, nrows = 0;
    int nval = 2 + (p->nspec > 1 ? p->nspec : 1);
    long len, ngraze = 0;
    while ((len = hd_istream_getline(in, ln, sizeof ln)) != -1) {
        if (++lineno < p->dline) continue;
        if (len == -2) {
            st = hd_fail(HD_ERR_FORMAT, "%s: line %ld: longer than %zu characters", p->path, lineno, sizeof ln - 1);
            break;
        }
        const char *s = skipws(ln);
        if (*s == 0 || *s == '\n' || *s == '\r') continue;
        double v[5];
        int k = 0;
        char *end;
        for (; k < nval; k++) {
            s = skipws(s);
            if (!*s || *s == '\n' || *s == '\r') break;
            v[k] = strtod(s, &end);
            if (end == s) break;
            s = end;
        }
        s = skipws(s);
        if (k < nval || (*s && *s != '\n' && *s != '\r')) {
            st = hd_fail(HD_ERR_FORMAT, "%s: line %ld: expected %d numbers (theta phi %s), %s", p->path, lineno,
                         nval, nval > 3 ? "X Y Z" : "value",
                         k < nval ? (*s && *s != '\n' && *s != '\r' ? "found text" : "the row is truncated")
                                  : "found more");
            break;
        }
        double tho = v[0], pho = v[1];
        if (!(tho >= 0 && tho <= 180.) || !(fabs(pho) <= 720.)) {
            st = hd_fail(HD_ERR_RANGE, "%s: line %ld: outgoing angle theta %g phi %g out of range (0..180, -720..720)",
                         p->path, lineno, tho, pho);
            break;
        }
        for (int i = 2; i < nval; i++)
            if (!(v[i] >= 0) || !isfinite(v[i])) {
                st = hd_fail(HD_ERR_RANGE, "%s: line %ld: negative or invalid BSDF value %g", p->path, lineno, v[i]);
                break;
            }
        if (st != HD_OK) break;
        nrows++;
        if (fabs(tho - 90.) < lim_graze - TINY) continue;
        if (fabs(tho - 90.) < TINY) { ngraze++; continue; }   /* on neither side */
        if (f->o->flip) { tho = 180. - tho; pho = 360. - pho; }
        pho += 90. - p->up_phi;
        if (!r->output_orient) r->output_orient = 1 - 2 * (tho > 90.);
        else if ((r->output_orient > 0) != (tho < 90.)) {
            st = hd_fail(HD_ERR_FORMAT, "%s: line %ld: outgoing theta %g is on the other side of the surface from "
                         "the data before it (one component per run)", p->path, lineno, v[0]);
            break;
        }
        double so = sin(HD_PI / 180. * tho);
        hd_vec3 ov = hd_v3(cos(HD_PI / 180. * pho) * so, sin(HD_PI / 180. * pho) * so, sqrt(1. - so * so));
        double cf = p->isDSF ? 1. : ov.z;
        double Y = cf * (p->nspec == 3 ? v[3] : v[2]);
        if (BSDF2SML * ov.z < Y && Y < BSDF2BIG * ov.z) {
            int h = (int)(log(Y / ov.z * (1. / BSDF2SML)) * (HISTLEN / HISTLNR));
            if (h >= 0 && h < HISTLEN) f->hist[h]++;
        }
        double n = 1. / sqrt(1. + fabs(ov.z)), sx, sy;
        hd_disk2square(ov.x * n, ov.y * n, &sx, &sy);
        int gx = (int)(sx * GR), gy = (int)(sy * GR);
        if (gx >= GR) gx = GR - 1;
        if (gy >= GR) gy = GR - 1;
        f->sum[gx * GR + gy] = (float)(f->sum[gx * GR + gy] + Y);   /* summed in double, kept in float */
        f->cnt[gx * GR + gy]++;
    }
    if (st == HD_OK && hd_istream_failed(in)) st = hd_fail(HD_ERR_IO, "%s: read error", p->path);
    hd_istream_close(in);
    if (st == HD_OK && !nrows) st = hd_fail(HD_ERR_FORMAT, "%s: no data rows", p->path);
    if (st == HD_OK && ngraze)
        fprintf(stderr, "%s: warning: %s: %ld rows at exactly 90 degrees (grazing) skipped\n", hd_progname(), p->path,
                ngraze);
    return st;
}

/* ---- lobes over an adaptive quadtree ---- */

static int empty_region(const fitter *f, int x0, int x1, int y0, int y1)
{
    for (int x = x0; x < x1; x++)
        for (int y = y0; y < y1; y++)
            if (f->cnt[x * GR + y]) return 0;
    return 1;
}

static int smooth_region(const fitter *f, int x0, int x1, int y0, int y1)
{
    double M[3][3] = {{0}}, xv[3] = {0};
    for (int x = x0; x < x1; x++)
        for (int y = y0; y < y1; y++) {
            unsigned n = f->cnt[x * GR + y];
            if (!n) continue;
            double z = f->sum[x * GR + y];
            M[0][0] += (double)x * x * n; M[0][1] += (double)x * y * n; M[0][2] += (double)x * n;
            M[1][1] += (double)y * y * n; M[1][2] += (double)y * n; M[2][2] += n;
            xv[0] += x * z; xv[1] += y * z; xv[2] += z;
        }
    M[1][0] = M[0][1]; M[2][0] = M[0][2]; M[2][1] = M[1][2];
    double nvs = M[2][2];
    double c00 = M[2][2] * M[1][1] - M[2][1] * M[1][2], c01 = M[2][1] * M[0][2] - M[2][2] * M[0][1];
    double c02 = M[1][2] * M[0][1] - M[1][1] * M[0][2];
    double det = M[0][0] * c00 + M[1][0] * c01 + M[2][0] * c02;
    if (det == 0) return 1;   /* colinear samples */
    double id = 1. / det;
    double I[3][3] = {
        {c00 * id, c01 * id, c02 * id},
        {id * (M[2][0] * M[1][2] - M[2][2] * M[1][0]), id * (M[2][2] * M[0][0] - M[2][0] * M[0][2]),
         id * (M[1][0] * M[0][2] - M[1][2] * M[0][0])},
        {id * (M[2][1] * M[1][0] - M[2][0] * M[1][1]), id * (M[2][0] * M[0][1] - M[2][1] * M[0][0]),
         id * (M[1][1] * M[0][0] - M[1][0] * M[0][1])}};
    double A = I[0][0] * xv[0] + I[0][1] * xv[1] + I[0][2] * xv[2];
    double B = I[1][0] * xv[0] + I[1][1] * xv[1] + I[1][2] * xv[2];
    if (A * A + B * B > MAXSLOPE * MAXSLOPE) return 0;
    double C = I[2][0] * xv[0] + I[2][1] * xv[1] + I[2][2] * xv[2];
    double e2 = 0;
    for (int x = x0; x < x1; x++)
        for (int y = y0; y < y1; y++) {
            unsigned n = f->cnt[x * GR + y];
            if (!n) continue;
            double d = A * x + B * y + C - f->sum[x * GR + y] / n;
            e2 += n * d * d;
        }
    if (e2 <= nvs * SMOOTH_MSE) return 1;
    return e2 * nvs <= xv[2] * xv[2] * SMOOTH_MSER;
}

static int create_lobe(const fitter *f, hd_rbflobe *l, int x0, int x1, int y0, int y1)
{
    double vtot = 0, wx = 0, wy = 0, wt = 0;
    unsigned long nv = 0;
    for (int x = x0; x < x1; x++)
        for (int y = y0; y < y1; y++) {
            unsigned n = f->cnt[x * GR + y];
            if (!n) continue;
            double v = f->sum[x * GR + y];
            if (v > 0) {
                double w = v / n;
                wx += w * x; wy += w * y; wt += w;
            }
            vtot += v;
            nv += n;
        }
    if (!nv || vtot <= 0) return 0;
    vtot *= (x1 - x0) * (y1 - y0) * (2. * HD_PI / GR / GR) / (double)nv;
    double rad = (RSCA / GR) * (x1 - x0);
    l->peak = (float)(vtot / (2. * HD_PI * rad * rad));
    l->chroma = DFCHROMA;
    l->crad = (uint16_t)hd_rbf_ang2r(rad);
    l->gx = (uint16_t)(int)(wx / wt + .5);
    l->gy = (uint16_t)(int)(wy / wt + .5);
    return 1;
}

typedef struct lobes { hd_rbflobe *a; int n; size_t cap; } lobes;

static int push_lobe(lobes *L, const fitter *f, int x0, int x1, int y0, int y1)
{
    if (HD_GROW(L->a, (size_t)L->n + 1, L->cap, 256)) return -1;
    return create_lobe(f, &L->a[L->n], x0, x1, y0, y1) ? (L->n++, 1) : 0;
}

/* returns lobes added below (>0), 0 for a leaf region, -1 out of memory */
static int build_quad(lobes *L, const fitter *f, int x0, int x1, int y0, int y1)
{
    int xm = (x0 + x1) >> 1, ym = (y0 + y1) >> 1;
    if (empty_region(f, x0, xm, y0, ym) || empty_region(f, xm, x1, y0, ym) || empty_region(f, x0, xm, ym, y1) ||
        empty_region(f, xm, x1, ym, y1))
        return 0;
    int br[4];
    if ((br[0] = build_quad(L, f, x0, xm, y0, ym)) < 0) return -1;
    if ((br[1] = build_quad(L, f, xm, x1, y0, ym)) < 0) return -1;
    if ((br[2] = build_quad(L, f, x0, xm, ym, y1)) < 0) return -1;
    if ((br[3] = build_quad(L, f, xm, x1, ym, y1)) < 0) return -1;
    int added = br[0] + br[1] + br[2] + br[3];
    int leaves = !br[0] + !br[1] + !br[2] + !br[3];
    if (!leaves) return added;
    if (leaves == 4 && x1 - x0 <= MAX_RAD && smooth_region(f, x0, x1, y0, y1)) return 0;
    const int q[4][4] = {{x0, xm, y0, ym}, {xm, x1, y0, ym}, {x0, xm, ym, y1}, {xm, x1, ym, y1}};
    for (int i = 0; i < 4; i++) {
        if (br[i]) continue;
        int a = push_lobe(L, f, q[i][0], q[i][1], q[i][2], q[i][3]);
        if (a < 0) return -1;
        added += a;
    }
    return added;
}

static void comp_bsdf_min(fitter *f)
{
    unsigned long cnt = 0, target;
    for (int i = 0; i < HISTLEN; i++) cnt += f->hist[i];
    if (!cnt) { f->r->bsdf_min = 0; return; }
    target = cnt / 100;
    cnt = 0;
    int i = 0;
    for (; cnt <= target && i < HISTLEN; i++) cnt += f->hist[i];
    f->r->bsdf_min = exp(((i - 1) + .5) * (HISTLNR / HISTLEN)) * BSDF2SML;
}

/* insert a DSF in the list (ascending incident angle while the data are in one plane) */
static hd_status insert_dsf(hd_rbfrep *r, hd_rbfdsf *nd, size_t *dcap)
{
    for (int k = 0; k < r->ndsf; k++)
        if (hd_vdot(r->dsf[k].invec, nd->invec) >= 1. - TINY) {
            hd_vec3 v = nd->invec;
            fprintf(stderr, "%s: warning: duplicate incident measurement ignored at theta %.1f phi %.1f\n",
                    hd_progname(), acos(v.z > 1 ? 1 : v.z < -1 ? -1 : v.z) * 180. / HD_PI,
                    fmod(atan2(v.y, v.x) * 180. / HD_PI + 360., 360.));
            free(nd->rbfa);
            return HD_OK;
        }
    int at = r->ndsf;
    if (r->single_plane)
        for (int k = 0; k < r->ndsf; k++)
            if (r->input_orient * r->dsf[k].invec.z < r->input_orient * nd->invec.z) { at = k; break; }
    if (HD_GROW(r->dsf, (size_t)r->ndsf + 1, *dcap, 16)) return HD_ERR_NOMEM;
    memmove(&r->dsf[at + 1], &r->dsf[at], (size_t)(r->ndsf - at) * sizeof *r->dsf);
    r->dsf[at] = *nd;
    r->ndsf++;
    for (int k = 0; k < r->ndsf; k++) r->dsf[k].ord = k;
    return HD_OK;
}

static hd_status make_rbfrep(fitter *f, const char *path)
{
    hd_rbfrep *r = f->r;
    comp_bsdf_min(f);
    lobes L = {0, 0, 0};
    int n = build_quad(&L, f, 0, GR, 0, GR);
    if (n < 0) { free(L.a); return HD_ERR_NOMEM; }
    if (n == 0) {
        free(L.a);
        fprintf(stderr, "%s: warning: %s: skipping incident direction theta %.1f phi %.1f: its data do not cover "
                "the hemisphere\n", hd_progname(), path, f->theta_in, f->phi_in);
        return HD_OK;
    }
    hd_rbfdsf d;
    memset(&d, 0, sizeof d);
    d.rbfa = L.a;
    d.nrbf = L.n;
    double s = sin(HD_PI / 180. * f->theta_in);
    d.invec = hd_v3(cos(HD_PI / 180. * f->phi_in) * s, sin(HD_PI / 180. * f->phi_in) * s,
                    r->input_orient * sqrt(fma(-s, s, 1.)));
    for (int i = 0; i < d.nrbf; i++) d.vtotal += hd_rbf_lobe_volume(r, &d.rbfa[i]);
    return insert_dsf(r, &d, &f->dcap);
}

/* ---- transport plans ---- */

typedef struct plan_ws { float *g0, *g1; } plan_ws;

static double nbr_dist2(const plan_ws *w, int x0, int y0, int x1, int y1)
{
    int rad = GR >> 5;
    const int p[4] = {x0, y0, x1, y1};
    for (int i = 0; i < 4; i++) {
        if (p[i] < rad) rad = p[i];
        if (GR - 1 - p[i] < rad) rad = GR - 1 - p[i];
    }
    double s2 = 0;
    for (int i = -rad; i <= rad; i++) {
        const float *a = w->g0 + (size_t)(x0 + i) * GR + y0, *b = w->g1 + (size_t)(x1 + i) * GR + y1;
        for (int j = -rad; j <= rad; j++) {
            double d = a[j] - b[j];
            s2 += d * d;
        }
    }
    return s2 / (4 * rad * (rad + 1) + 1);
}

/* The transport plan of the lobe volumes of DSF a onto those of DSF b
 * (cost: angular distance squared + radius difference squared +
 * neighbourhood difference of the normalised cube-root DSFs): Radiance's
 * plan (hd_transport_radiance) or, with exact, the least-cost one
 * (hd_transport_solve); transport.h.  Rows of the result sum to 1. */
static hd_status plan_migration(const hd_rbfrep *r, hd_rbfmig *m, plan_ws *w, int exact)
{
    const hd_rbfdsf *a = &r->dsf[m->from], *b = &r->dsf[m->to];
    int na = a->nrbf, nb = b->nrbf;
    double nf0 = (double)GR * GR / a->vtotal, nf1 = (double)GR * GR / b->vtotal;
    hd_rbfeval *e0, *e1;
    hd_status st;
    if ((st = hd_rbfeval_make(&e0, r, a)) != HD_OK) return st;
    if ((st = hd_rbfeval_make(&e1, r, b)) != HD_OK) { hd_rbfeval_free(e0); return st; }
    for (int x = 0; x < GR; x++)
        for (int y = 0; y < GR; y++) {
            hd_vec3 dv = hd_rbf_ovec(r, x, y);
            w->g0[x * GR + y] = (float)pow(nf0 * hd_rbfeval_bsdf_exact(e0, dv), .3333);
            w->g1[x * GR + y] = (float)pow(nf1 * hd_rbfeval_bsdf_exact(e1, dv), .3333);
        }
    hd_rbfeval_free(e0);
    hd_rbfeval_free(e1);
    size_t np = (size_t)na * nb;
    double *cost = hd_malloc_array(np ? np : 1, sizeof(double)), *flow = hd_malloc_array(np ? np : 1, sizeof(double));
    double *src = hd_malloc_array((size_t)na + 1, sizeof(double)), *dst = hd_malloc_array((size_t)nb + 1, sizeof(double));
    hd_vec3 *da = hd_malloc_array((size_t)na + 1, sizeof(hd_vec3)), *db = hd_malloc_array((size_t)nb + 1, sizeof(hd_vec3));
    m->mtx = hd_calloc(np ? np : 1, sizeof(float));
    if (!cost || !flow || !src || !dst || !da || !db || !m->mtx) {
        free(cost); free(flow); free(src); free(dst); free(da); free(db);
        return HD_ERR_NOMEM;
    }
    for (int i = 0; i < na; i++) {
        src[i] = hd_rbf_lobe_volume(r, &a->rbfa[i]) / a->vtotal;
        da[i] = hd_rbf_ovec(r, a->rbfa[i].gx, a->rbfa[i].gy);
    }
    for (int j = 0; j < nb; j++) {
        dst[j] = hd_rbf_lobe_volume(r, &b->rbfa[j]) / b->vtotal;
        db[j] = hd_rbf_ovec(r, b->rbfa[j].gx, b->rbfa[j].gy);
    }
    for (int i = 0; i < na; i++)
        for (int j = 0; j < nb; j++) {
            double c = hd_vdot(da[i], db[j]);
            double d = c >= 1 ? 0 : c <= -1 ? HD_PI : acos(c);
            double res = d * d;
            d = hd_rbf_r2ang(b->rbfa[j].crad) - hd_rbf_r2ang(a->rbfa[i].crad);
            res += d * d;
            res += NEIGH_FACT2 * nbr_dist2(w, a->rbfa[i].gx, a->rbfa[i].gy, b->rbfa[j].gx, b->rbfa[j].gy);
            cost[(size_t)i * nb + j] = res;
        }
    st = exact ? hd_transport_solve(na, nb, src, dst, cost, flow, NULL, NULL, NULL)
               : hd_transport_radiance(na, nb, src, dst, cost, flow, NULL);
    if (st == HD_ERR_RANGE) st = HD_OK;      /* pivot limit: the feasible plan reached is kept */
    for (size_t q = 0; q < np; q++) m->mtx[q] = (float)flow[q];
    for (int i = 0; i < na; i++) {
        double v = hd_rbf_lobe_volume(r, &a->rbfa[i]);
        if (v <= TINY) continue;
        double nf = a->vtotal / v;
        for (int j = 0; j < nb; j++) m->mtx[(size_t)i * nb + j] = (float)(m->mtx[(size_t)i * nb + j] * nf);
    }
    free(cost); free(flow); free(src); free(dst); free(da); free(db);
    return st;
}

typedef struct plan_job { hd_rbfrep *r; int first, exact; } plan_job;

static hd_status plan_chunk(void *ctx, size_t b, size_t e, size_t chunk, int worker)
{
    (void)chunk;
    (void)worker;
    plan_job *j = ctx;
    plan_ws w;
    w.g0 = hd_malloc_array((size_t)GR * GR, sizeof(float));
    w.g1 = hd_malloc_array((size_t)GR * GR, sizeof(float));
    hd_status st = (!w.g0 || !w.g1) ? HD_ERR_NOMEM : HD_OK;
    for (size_t k = b; k < e && st == HD_OK; k++) st = plan_migration(j->r, &j->r->mig[j->first + k], &w, j->exact);
    free(w.g0);
    free(w.g1);
    return st;
}

hd_status hd_rbf_replan(hd_rbfrep *r, int m, int exact)
{
    if (m < 0 || m >= r->nmig) return hd_fail(HD_ERR_RANGE, "no migration %d", m);
    plan_ws w;
    w.g0 = hd_malloc_array((size_t)GR * GR, sizeof(float));
    w.g1 = hd_malloc_array((size_t)GR * GR, sizeof(float));
    hd_status st = (!w.g0 || !w.g1) ? HD_ERR_NOMEM : HD_OK;
    if (st == HD_OK) {
        free(r->mig[m].mtx);
        r->mig[m].mtx = NULL;
        st = plan_migration(r, &r->mig[m], &w, exact);
    }
    free(w.g0);
    free(w.g1);
    return st;
}

/* ---- the mesh ---- */

typedef struct mesh { int cap; } mesh;

static int find_mig(const hd_rbfrep *r, int a, int b)
{
    for (int m = 0; m < r->nmig; m++)
        if ((r->mig[m].from == a && r->mig[m].to == b) || (r->mig[m].from == b && r->mig[m].to == a)) return m;
    return -1;
}

/* The mesh geometry in fused multiply-adds, as the Radiance build the
 * reference data come from computes it: on a grid symmetric in phi the two
 * diagonals of a quadrilateral tie exactly and the rounding picks one
 * (docs/design/measured.md, Mesh). fma() rounds the same on every machine. */
static double fdot(hd_vec3 a, hd_vec3 b)
{
    return fma(a.z, b.z, fma(a.x, b.x, a.y * b.y));
}

static hd_vec3 fcross(hd_vec3 a, hd_vec3 b)
{
    return hd_v3(fma(a.y, b.z, -(a.z * b.y)), fma(a.z, b.x, -(a.x * b.z)), fma(a.x, b.y, -(a.y * b.x)));
}

static hd_vec3 fnorm(hd_vec3 v)
{
    double d = fdot(v, v), len;
    if (d == 0) return v;
    if (d <= 1 + TINY && d >= 1 - TINY) {
        len = fma(.5, d, .5);
        d = 2 - len;
    } else {
        len = sqrt(d);
        d = 1 / len;
    }
    return hd_vscale(v, d);
}

static hd_vec3 tri_orient(hd_vec3 a, hd_vec3 b, hd_vec3 c)
{
    return fcross(hd_vsub(b, a), hd_vsub(c, b));
}

static int is_rev_tri(hd_vec3 a, hd_vec3 b, hd_vec3 c)
{
    return fdot(tri_orient(a, b, c), b) < 0.;
}

/* third vertices of the triangles on either side of edge m */
static int get_triangles(const hd_rbfrep *r, int m, int tv[2])
{
    tv[0] = tv[1] = -1;
    if (m < 0) return 0;
    int a = r->mig[m].from, b = r->mig[m].to;
    for (int e = 0; e < r->nmig; e++) {
        if (e == m) continue;
        int t;
        if (r->mig[e].from == a) t = r->mig[e].to;
        else if (r->mig[e].to == a) t = r->mig[e].from;
        else continue;
        if (find_mig(r, t, b) >= 0) tv[is_rev_tri(r->dsf[a].invec, r->dsf[b].invec, r->dsf[t].invec)] = t;
    }
    return (tv[0] >= 0) + (tv[1] >= 0);
}

static int overlaps_tri(const hd_rbfrep *r, int b0, int b1, int pv)
{
    int m = -1, rev = 0;
    for (int e = 0; e < r->nmig && m < 0; e++) {
        int f = r->mig[e].from, t = r->mig[e].to, o;
        if (f == pv) o = t;
        else if (t == pv) o = f;
        else continue;
        if (o == b0) { rev = is_rev_tri(r->dsf[f].invec, r->dsf[t].invec, r->dsf[b1].invec); m = e; }
        else if (o == b1) { rev = is_rev_tri(r->dsf[f].invec, r->dsf[t].invec, r->dsf[b0].invec); m = e; }
    }
    int tv[2];
    if (!get_triangles(r, m, tv)) return 0;
    return tv[rev] >= 0;
}

static int find_hull_vert(const hd_rbfrep *r, int v0, int v1)
{
    hd_vec3 ej = hd_vsub(r->dsf[v1].invec, r->dsf[v0].invec), mid = hd_vadd(r->dsf[v0].invec, r->dsf[v1].invec);
    if (fdot(ej, ej) == 0 || fdot(mid, mid) == 0) return -1;
    ej = fnorm(ej);
    mid = fnorm(mid);
    int best = -1;
    double bestd = -.5, besta2 = 1e300;
    for (int k = 0; k < r->ndsf; k++) {
        if (k == v0 || k == v1) continue;
        hd_vec3 vp = tri_orient(r->dsf[v0].invec, r->dsf[v1].invec, r->dsf[k].invec);
        if (fdot(vp, mid) <= TINY) continue;
        double a2 = .25 * fdot(vp, vp);
        vp = hd_vsub(r->dsf[k].invec, mid);
        double dp = -fdot(vp, ej);
        vp = hd_v3(fma(ej.x, dp, vp.x), fma(ej.y, dp, vp.y), fma(ej.z, dp, vp.z));
        dp = fdot(vp, mid) / sqrt(fdot(vp, vp));
        if (dp <= fma(TINY, (double)(1 - 2 * (a2 < besta2)), bestd)) continue;
        if (overlaps_tri(r, v0, v1, k)) continue;
        best = k;
        bestd = dp;
        besta2 = a2;
    }
    return best;
}

static int add_mig(hd_rbfrep *r, int a, int b, size_t *mcap)
{
    if (a > b) { int t = a; a = b; b = t; }
    int e = find_mig(r, a, b);
    if (e >= 0) return -2;   /* exists */
    if (HD_GROW(r->mig, (size_t)r->nmig + 1, *mcap, 32)) return -1;
    memset(&r->mig[r->nmig], 0, sizeof *r->mig);
    r->mig[r->nmig].from = a;
    r->mig[r->nmig].to = b;
    return r->nmig++;
}

static int mesh_from_edge(hd_rbfrep *r, int m, size_t *mcap, int depth)
{
    if (m < 0) return m == -1 ? -1 : 0;
    if (depth > 100000) return 0;
    int tv[2];
    get_triangles(r, m, tv);
    for (int side = 0; side < 2; side++) {
        if (tv[side] >= 0) continue;
        int a = r->mig[m].from, b = r->mig[m].to;
        int v = side == 0 ? find_hull_vert(r, a, b) : find_hull_vert(r, b, a);
        if (v < 0) continue;
        int e0 = add_mig(r, a, v, mcap);
        if (e0 == -1) return -1;
        int e1 = add_mig(r, b, v, mcap);
        if (e1 == -1) return -1;
        if (mesh_from_edge(r, e0, mcap, depth + 1) < 0) return -1;
        if (mesh_from_edge(r, e1, mcap, depth + 1) < 0) return -1;
        if (side == 0) return 0;
    }
    return 0;
}

/* ---- default specular lobe (for directions outside the mesh) ---- */

static hd_vec3 spin(hd_vec3 v, hd_vec3 axis, double th)
{
    double c = cos(th), s = sin(th), np = hd_vdot(v, axis) * (1. - c);
    hd_vec3 p = hd_vcross(axis, v);
    return hd_v3(v.x * c + axis.x * np + p.x * s, v.y * c + axis.y * np + p.y * s, v.z * c + axis.z * np + p.z * s);
}

static hd_vec3 rotate_towards(hd_vec3 a, hd_vec3 b, double ang)
{
    double d = hd_vdot(a, b);
    if (d >= 1. - 1e-12 || d <= -1. + 1e-12) return a;
    double s = sin(ang) / sqrt(1. - d * d);
    return hd_vadd(hd_vscale(a, cos(ang)), hd_vscale(hd_vsub(b, hd_vscale(a, d)), s));
}

static double dsf_surround(const hd_rbfrep *r, const hd_rbfdsf *d, hd_vec3 o, double rad)
{
    hd_vec3 t = r->output_orient * o.z >= 1. - TINY ? hd_v3(0, 1, 0) : hd_v3(0, 0, 1);
    t = rotate_towards(o, t, rad);
    double sum = 0;
    int n = 0;
    for (int i = 0; i < 12; i++) {
        if (i) t = spin(t, o, 2. * HD_PI / 12);
        if ((t.z > 0) != (r->output_orient > 0)) continue;
        sum += hd_rbf_eval(r, d, t) * hd_rbf_cosf(t.z);
        n++;
    }
    return n < 2 ? sum : sum / n;
}

static double est_radius(const hd_rbfrep *r, const hd_rbfdsf *d, hd_vec3 o)
{
    const double eps = .01;
    double target = .60653066 * hd_rbf_eval(r, d, o) * hd_rbf_cosf(o.z);
    double ir = eps, orad = .5, din = dsf_surround(r, d, o, ir), dout = dsf_surround(r, d, o, orad);
    int it = 0;
    do {
        double tr = dout != din ? ir + (orad - ir) * (target - din) / (dout - din) : .5 * (ir + orad);
        if (tr >= orad || tr <= ir || !isfinite(tr)) tr = .5 * (ir + orad);
        double dt = dsf_surround(r, d, o, tr);
        if (dt > target) { ir = tr; din = dt; }
        else { orad = tr; dout = dt; }
    } while (orad - ir > eps && ++it < 100);
    return .5 * (ir + orad);
}

static hd_status comp_bsdf_spec(hd_rbfrep *r)
{
    r->spec_val = r->spec_rad = 0;
    if (r->ndsf < 10) return HD_OK;
    double *cl = hd_malloc_array((size_t)r->ndsf, sizeof(double));
    if (!cl) return HD_ERR_NOMEM;
    for (int k = 0; k < r->ndsf; k++) cl[k] = r->dsf[k].invec.z * r->input_orient;
    qsort(cl, (size_t)r->ndsf, sizeof *cl, hd_cmp_double);
    double maxc = cl[(r->ndsf + 3) / 4];
    free(cl);
    double vsum = 0, rsum = 0;
    int n = 0;
    for (int k = 0; k < r->ndsf; k++) {
        const hd_rbfdsf *d = &r->dsf[k];
        if (d->invec.z * r->input_orient > maxc) continue;
        hd_vec3 sd = hd_v3(-d->invec.x, -d->invec.y, d->invec.z * (2 * (r->input_orient == r->output_orient) - 1));
        double cf = hd_rbf_cosf(sd.z), rad = est_radius(r, d, sd);
        double v = hd_rbf_eval(r, d, sd) * cf * 2. * HD_PI * rad * rad;
        if (v > d->vtotal) v = d->vtotal;
        vsum += v / cf;
        rsum += rad;
        n++;
    }
    if (!n) return HD_OK;
    r->spec_rad = rsum / n;
    r->spec_val = vsum / (2. * HD_PI * n * r->spec_rad * r->spec_rad);
    return HD_OK;
}

/* add the normal incidence by advecting half-way between the nearest
 * direction and its mirror image, when the data cannot reach it otherwise */
static hd_status check_normal(hd_rbfrep *r, size_t *dcap, int exact)
{
    if (!r->ndsf) return HD_OK;
    int near = 0;
    double best = r->input_orient * r->dsf[0].invec.z;
    if (r->single_plane) {
        if (best >= 1. - 2. * TINY) return HD_OK;
    } else {
        if (r->inp_coverage != HD_RBF_Q1 && r->inp_coverage != HD_RBF_Q2 && r->inp_coverage != HD_RBF_Q3 &&
            r->inp_coverage != HD_RBF_Q4)
            return HD_OK;
        for (int k = 0; k < r->ndsf; k++) {
            double d = r->input_orient * r->dsf[k].invec.z;
            if (d >= 1. - 2. * TINY) return HD_OK;
            if (d > best) { near = k; best = d; }
        }
    }
    /* temporary mirrored copy at index ndsf */
    if (HD_GROW(r->dsf, (size_t)r->ndsf + 1, *dcap, 1)) return HD_ERR_NOMEM;
    hd_rbfdsf *mir = &r->dsf[r->ndsf];
    *mir = r->dsf[near];
    mir->rbfa = hd_malloc_array((size_t)mir->nrbf, sizeof *mir->rbfa);
    if (!mir->rbfa) return HD_ERR_NOMEM;
    memcpy(mir->rbfa, r->dsf[near].rbfa, (size_t)mir->nrbf * sizeof *mir->rbfa);
    mir->ord = r->ndsf;
    hd_rbf_mirror_dsf(r, mir, 3);
    r->ndsf++;
    hd_rbfmig m;
    memset(&m, 0, sizeof m);
    m.from = r->ndsf - 1;
    m.to = near;
    plan_ws w = {hd_malloc_array((size_t)GR * GR, sizeof(float)), hd_malloc_array((size_t)GR * GR, sizeof(float))};
    hd_status st = (!w.g0 || !w.g1) ? HD_ERR_NOMEM : plan_migration(r, &m, &w, exact);
    free(w.g0);
    free(w.g1);
    hd_rbfdsf nd;
    memset(&nd, 0, sizeof nd);
    if (st == HD_OK) {
        /* row lists for the advection */
        hd_rbfmig *save = r->mig;
        int nsave = r->nmig;
        r->mig = &m;
        r->nmig = 1;
        st = hd_rbf_link(r);
        if (st == HD_OK) st = hd_rbf_edge_advect(r, &m, hd_v3(0, 0, r->input_orient), 0, &nd);
        r->mig = save;
        r->nmig = nsave;
    }
    free(m.mtx);
    free(m.rs);
    free(m.ci);
    free(m.cv);
    r->ndsf--;
    free(r->dsf[r->ndsf].rbfa);
    if (st != HD_OK) { free(nd.rbfa); return st; }
    nd.invec = hd_v3(0, 0, r->input_orient);
    return insert_dsf(r, &nd, dcap);
}

static hd_status build_mesh(hd_rbfrep *r, const hd_pabopto_opts *o, size_t *dcap)
{
    hd_status st = comp_bsdf_spec(r);
    if (st != HD_OK) return st;
    if ((st = check_normal(r, dcap, o->exact)) != HD_OK) return st;
    size_t mcap = 0;
    if (r->single_plane) {
        for (int k = 0; k + 1 < r->ndsf; k++)
            if (add_mig(r, k, k + 1, &mcap) == -1) return HD_ERR_NOMEM;
    } else if (r->ndsf > 1) {
        int s0 = -1, s1 = -1;
        double best = HD_PI * HD_PI;
        for (int a = 0; a < r->ndsf; a++)
            for (int b = a + 1; b < r->ndsf; b++) {
                double d2 = 2. - 2. * hd_vdot(r->dsf[a].invec, r->dsf[b].invec);
                if (d2 < best) { s0 = a; s1 = b; best = d2; }
            }
        if (s0 < 0) return hd_fail(HD_ERR_FORMAT, "cannot find the shortest edge between incident directions");
        int e = add_mig(r, s0, s1, &mcap);
        if (e == -1 || mesh_from_edge(r, e, &mcap, 0) < 0) return HD_ERR_NOMEM;
        if (r->nmig < r->ndsf - 1)
            fprintf(stderr, "%s: warning: %d incident directions but only %d interpolation edges\n", hd_progname(),
                    r->ndsf, r->nmig);
    }
    plan_job j = {r, 0, o->exact};
    st = hd_parallel_for((size_t)r->nmig, 1, hd_resolve_threads(o->nthreads), plan_chunk, &j);
    if (st != HD_OK) return st;
    return hd_rbf_link(r);
}

/* ---- driver ---- */

static const char quad_sym[16] = {'I', 'Q', 'Q', 'B', 'Q', '?', 'B', '?', 'Q', 'B', '?', '?', 'B', '?', '?', 'A'};

hd_status hd_pabopto_build(hd_rbfrep *r, const char *const *paths, int n, const hd_pabopto_opts *o)
{
    hd_status st = hd_rbf_init(r, GR);
    if (st != HD_OK) return st;
    int up = toupper((unsigned char)o->symmetry) == 'U';
    int tot = up ? 2 * n : n;
    pab_in *in = hd_calloc((size_t)tot + 1, sizeof *in);
    fitter f;
    memset(&f, 0, sizeof f);
    f.r = r;
    f.o = o;
    f.sum = hd_malloc_array((size_t)GR * GR, sizeof(float));
    f.cnt = hd_malloc_array((size_t)GR * GR, sizeof(unsigned));
    if (!in || !f.sum || !f.cnt) { st = HD_ERR_NOMEM; goto done; }
    double lim = o->auto_graze ? 90. : o->lim_graze;
    for (int i = 0; i < n; i++) {
        if ((st = read_head(&in[i], paths[i], o, r)) != HD_OK) goto done;
        if (o->auto_graze && fabs(in[i].theta - 90.) < lim) lim = fabs(in[i].theta - 90.);
    }
    for (int i = n; i < tot; i++) {
        in[i] = in[i - n];
        in[i].phi += 180.;
        in[i].up_phi -= 180.;
        grid_pos(&in[i]);
    }
    qsort(in, (size_t)tot, sizeof *in, cmp_in);
    for (int i = 0; i < tot; i++) {
        int nspec = in[i].nspec ? in[i].nspec : 1;
        if (i && (in[i - 1].nspec ? in[i - 1].nspec : 1) != nspec) {
            st = hd_fail(HD_ERR_FORMAT, "%s: colorimetry differs from %s", in[i].path, in[i - 1].path);
            goto done;
        }
        if (!i || cmp_in(&in[i - 1], &in[i])) {
            if (i && (st = make_rbfrep(&f, in[i - 1].path)) != HD_OK) goto done;
            if ((st = new_direction(&f, in[i].theta, in[i].phi, in[i].path)) != HD_OK) goto done;
        }
        if ((st = read_data(&f, &in[i], lim)) != HD_OK) goto done;
    }
    if ((st = make_rbfrep(&f, in[tot - 1].path)) != HD_OK) goto done;
    r->colorimetry = in[0].nspec ? 0 : 3;   /* photopic (Y of CIE-XYZ data) or unknown */
    if (r->ndsf < 2) {
        st = hd_fail(HD_ERR_FORMAT, "%d usable incident direction(s): at least 2 are needed", r->ndsf);
        goto done;
    }
    if (r->single_plane < 0) r->single_plane = 1;   /* only normal incidence */
    char sym = quad_sym[r->single_plane ? 0 : r->inp_coverage & 15];
    char want = (char)toupper((unsigned char)o->symmetry);
    if (want == '0' || !want) {
        if (sym == '?') {
            st = hd_fail(HD_ERR_UNSUPPORTED, "unsupported incident phi coverage (quadrant bits %d)", r->inp_coverage);
            goto done;
        }
    } else if (!(want == 'U' && sym == 'A') && want != sym) {
        st = hd_fail(HD_ERR_FORMAT, "incident phi coverage ('%c' symmetry) does not match the requested '%c'", sym,
                     want);
        goto done;
    }
    if (r->single_plane) r->inp_coverage = 0;
    st = build_mesh(r, o, &f.dcap);
done:
    free(in);
    free(f.sum);
    free(f.cnt);
    return st;
}

int hd_pabopto2bsdf_main(int argc, char **argv)
{
    hd_pabopto_opts o = {0, 0, 0, '0', 0, 0, 0};
    const char *usage = "usage: pabopto2bsdf [-t][-x][-n nproc][-s symmetry][-g angle|'A'] meas1.dat meas2.dat .. > bsdf.sir\n";
    hd_set_progname(argv[0]);
    int a = 1;
    for (; a < argc && argv[a][0] == '-' && argv[a][1]; a++) {
        switch (argv[a][1]) {
        case 't': o.flip = !o.flip; break;
        case 'x': o.exact = 1; break;
        case 'n':
            if (a + 1 >= argc) { fputs(usage, stderr); return 1; }
            o.nthreads = atoi(argv[++a]);
            break;
        case 's':
            if (a + 1 >= argc || !strchr("0IQBAUiqbau", argv[a + 1][0])) {
                fprintf(stderr, "%s: -s must be Isotropic, Quadrilateral, Bilateral, Up or Anisotropic\n",
                        hd_progname());
                return 1;
            }
            o.symmetry = argv[++a][0];
            break;
        case 'g':
            if (a + 1 >= argc) { fputs(usage, stderr); return 1; }
            if (toupper((unsigned char)argv[a + 1][0]) == 'A') o.auto_graze = 1;
            else {
                char *end;
                o.lim_graze = strtod(argv[a + 1], &end);
                if (*end || o.lim_graze < 0 || o.lim_graze >= 90) {
                    fprintf(stderr, "%s: -g %s: expected an angle 0..90 or A\n", hd_progname(), argv[a + 1]);
                    return 1;
                }
            }
            a++;
            break;
        default: fputs(usage, stderr); return 1;
        }
    }
    if (argc - a < 2) { fputs(usage, stderr); return 1; }
    hd_rbfrep r;
    if (hd_pabopto_build(&r, (const char *const *)argv + a, argc - a, &o) != HD_OK) {
        hd_report_error();
        hd_rbf_free(&r);
        return 1;
    }
    hd_header h;
    hd_header_init(&h);
    hd_header_add_command(&h, argc, argv);
    hd_header_add_date(&h);
    hd_header_add_software(&h);
    hd_status st = hd_rbf_write(&r, stdout, h.text);
    hd_header_free(&h);
    hd_rbf_free(&r);
    if (st != HD_OK || fflush(stdout)) {
        hd_fail(HD_ERR_IO, "write error on standard output");
        hd_report_error();
        return 1;
    }
    return 0;
}

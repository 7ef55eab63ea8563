/* heliodon — pcomb: combine pictures pixel by pixel with .cal expressions,
 * as Radiance's pcomb.  Variables and functions offered to the expressions:
 * ri(n) gi(n) bi(n) li(n) [with pixel offsets (n,dx,dy)], re/ge/be/le(n)
 * (recorded exposure), pa(n) (pixel aspect), Ox..Dz(n), T(n) (view rays),
 * S(n) (pixel solid angle), x y (output pixel, y up), xres yres (output
 * size), xmax ymax (input size), nfiles, WE (white efficacy); outputs ro go
 * bo or lo (when undefined: the sum of the inputs).  Colours are floats as
 * in Radiance's scanlines; negative outputs are clipped to 0 in pictures. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/cal.h"
#include "heliodon/matrix.h"
#include "heliodon/pictools.h"
#include "heliodon/view.h"

#define PC_WE 179.0

typedef struct pin {
    hd_picture pic;         /* coefficients applied */
    float expos[3];
    double pa;
    hd_view view;
    int hasview;
    const char *shown;
} pin;

typedef struct pc {
    pin *in;
    int n, xmax, ymax, xres, yres, xpos, ypos, xscan, yscan, xyz;
    /* per-pixel view ray cache */
    long tick, *rtick, *stick;
    hd_vec3 *org, *dir;
    double *dist, *psize;
} pc;

static double brt(const pc *p, const float *c)
{
    return p->xyz ? c[1] : hd_rgb_bright_rad(c);   /* Radiance 6.1's bright() */
}

/* file number from the first argument: -1 = out of range, n = nfiles
 * for 0 (as Radiance: the count) */
static int fileno_arg(const pc *p, double d, int *count)
{
    *count = 0;
    if (d <= -0.5 || d >= p->n + 0.5) return -1;
    if (d < 0.5) { *count = 1; return 0; }
    return (int)(d - 0.5);
}

static pc *g_pc;       /* the running combination (one per process) */

static double f_x(hd_calrun *r, void *u, int na, const double *a) { (void)r; (void)u; (void)na; (void)a; return g_pc->xpos; }
static double f_y(hd_calrun *r, void *u, int na, const double *a) { (void)r; (void)u; (void)na; (void)a; return g_pc->ypos; }

static double f_colin(hd_calrun *r, void *u, int na, const double *a)
{
    (void)r;
    pc *p = g_pc;
    int which = (int)(intptr_t)u, cnt, fn = fileno_arg(p, a[0], &cnt);
    if (fn < 0) return 0.;
    if (cnt) return p->n;
    int xo = 0, yo = 0;
    if (na >= 2) {
        double d = a[1];
        if (d < 0) { xo = (int)(d - .5); if (p->xscan + xo < 0) xo = -p->xscan; }
        else { xo = (int)(d + .5); if (p->xscan + xo >= p->xmax) xo = p->xmax - 1 - p->xscan; }
    }
    if (na >= 3) {
        double d = a[2];
        if (d < 0) { yo = (int)(d - .5); if (yo < -64) yo = -64; if (p->yscan + yo < 0) yo = -p->yscan; }
        else { yo = (int)(d + .5); if (yo > 62) yo = 62; if (p->yscan + yo >= p->ymax) yo = p->ymax - 1 - p->yscan; }
    }
    int row = p->ymax - 1 - (p->yscan + yo);
    const float *c = p->in[fn].pic.pix + ((size_t)row * p->xmax + (size_t)(p->xscan + xo)) * 3;
    return which == 3 ? brt(p, c) : c[which];
}

static double f_expos(hd_calrun *r, void *u, int na, const double *a)
{
    (void)r; (void)na;
    pc *p = g_pc;
    int which = (int)(intptr_t)u, cnt, fn = fileno_arg(p, a[0], &cnt);
    if (fn < 0) return 0.;
    if (cnt) return p->n;
    return which == 3 ? brt(p, p->in[fn].expos) : p->in[fn].expos[which];
}

static double f_pa(hd_calrun *r, void *u, int na, const double *a)
{
    (void)r; (void)na; (void)u;
    int cnt, fn = fileno_arg(g_pc, a[0], &cnt);
    if (fn < 0) return 0.;
    return cnt ? g_pc->n : g_pc->in[fn].pa;
}

static void ray_at(pc *p, int fn)
{
    if (p->rtick[fn] == p->tick) return;
    p->rtick[fn] = p->tick;
    p->org[fn] = p->dir[fn] = hd_v3(0, 0, 0);
    p->dist[fn] = -1;
    if (!p->in[fn].hasview) return;
    p->dist[fn] = hd_view_ray(&p->in[fn].view, (p->xscan + .5) / p->xmax, (p->yscan + .5) / p->ymax,
                              &p->org[fn], &p->dir[fn]);
}

static double f_ray(hd_calrun *r, void *u, int na, const double *a)
{
    (void)r; (void)na;
    pc *p = g_pc;
    int which = (int)(intptr_t)u, cnt, fn = fileno_arg(p, a[0], &cnt);
    if (fn < 0) return 0.;
    if (cnt) return p->n;
    ray_at(p, fn);
    switch (which) {
    case 0: return p->org[fn].x;
    case 1: return p->org[fn].y;
    case 2: return p->org[fn].z;
    case 3: return p->dir[fn].x;
    case 4: return p->dir[fn].y;
    case 5: return p->dir[fn].z;
    default: return p->dist[fn];
    }
}

/* solid angle of the pixel: |(d(x+1) - d) x (d(y-1) - d)| */
static double f_psize(hd_calrun *r, void *u, int na, const double *a)
{
    (void)r; (void)na; (void)u;
    pc *p = g_pc;
    int cnt, fn = fileno_arg(p, a[0], &cnt);
    if (fn < 0) return 0.;
    if (cnt) return p->n;
    if (p->stick[fn] == p->tick) return p->psize[fn];
    p->stick[fn] = p->tick;
    p->psize[fn] = 0;
    ray_at(p, fn);
    const hd_view *v = &p->in[fn].view;
    if (!p->in[fn].hasview || v->type == 'l' || p->dist[fn] < -1e-6) return 0;
    hd_vec3 o, dx, dy, d0 = p->dir[fn];
    if (hd_view_ray(v, (p->xscan + 1.5) / p->xmax, (p->yscan + .5) / p->ymax, &o, &dx) < -1e-6 ||
        hd_view_ray(v, (p->xscan + .5) / p->xmax, (p->yscan - .5) / p->ymax, &o, &dy) < -1e-6)
        return 0;
    dx = hd_v3(dx.x - d0.x, dx.y - d0.y, dx.z - d0.z);
    dy = hd_v3(dy.x - d0.x, dy.y - d0.y, dy.z - d0.z);
    hd_vec3 c = hd_v3(dx.y * dy.z - dx.z * dy.y, dx.z * dy.x - dx.x * dy.z, dx.x * dy.y - dx.y * dy.x);
    return p->psize[fn] = sqrt(c.x * c.x + c.y * c.y + c.z * c.z);
}

static hd_status read_input(pin *in, const hd_pcomb_input *spec, int echo, hd_header *out)
{
    hd_status st = hd_picture_read(spec->name, &in->pic);
    if (st) return st;
    in->shown = !strcmp(spec->name, "-") ? "<stdin>" : spec->name[0] == '!' ? "<Command>" : spec->name;
    float coef[3] = {(float)spec->coef[0], (float)spec->coef[1], (float)spec->coef[2]};
    in->expos[0] = in->expos[1] = in->expos[2] = 1;
    in->pa = 1;
    if (echo && (st = hd_header_appendf(out, "%s:", in->shown))) return st;
    for (const char *l = in->pic.hdr.text; l && *l;) {
        const char *nl = strchr(l, '\n');
        int len = (int)(nl ? nl - l : (long)strlen(l));
        int show = 1;
        if (!strncmp(l, "EXPOSURE=", 9) || !strncmp(l, "COLORCORR=", 10)) {
            double c[3];
            if (l[0] == 'E') c[0] = c[1] = c[2] = atof(l + 9);
            else if (sscanf(l + 10, "%lf %lf %lf", &c[0], &c[1], &c[2]) != 3) c[0] = c[1] = c[2] = 1;
            if (spec->original) {
                for (int k = 0; k < 3; k++) coef[k] = (float)(coef[k] * (1. / c[k]));
                show = 0;
            } else {
                for (int k = 0; k < 3; k++) in->expos[k] = (float)(in->expos[k] * c[k]);
            }
        } else if (!strncmp(l, "PIXASPECT=", 10)) {
            in->pa *= atof(l + 10);
        }
        if (show && echo && (st = hd_header_appendf(out, "\t%.*s", len, l))) return st;
        l = nl ? nl + 1 : l + len;
    }
    int found = 0;
    if (hd_view_from_header(&in->view, &in->pic.hdr, &found) == HD_OK && found &&
        hd_view_setup(&in->view) == HD_OK)
        in->hasview = 1;
    size_t n = (size_t)in->pic.xres * in->pic.yres * 3;
    for (size_t i = 0; i < n; i++) in->pic.pix[i] *= coef[i % 3];
    return HD_OK;
}

hd_status hd_pcomb(const hd_pcomb_opts *o, int cmd_argc, char **cmd_argv, FILE *fp)
{
    pc p;
    memset(&p, 0, sizeof p);
    hd_header h;
    hd_header_init(&h);
    hd_status st = hd_header_add_date(&h);
    p.in = calloc((size_t)o->ninputs + 1, sizeof *p.in);
    if (!p.in) return HD_ERR_NOMEM;
    int common = -1;
    for (int i = 0; i < o->ninputs && !st; i++) {
        st = read_input(&p.in[i], &o->inputs[i], o->echo_header, &h);
        if (st) break;
        p.n++;
        if (i == 0) {
            p.xmax = p.in[0].pic.xres;
            p.ymax = p.in[0].pic.yres;
            p.xyz = p.in[0].pic.fmt == HD_PIC_XYZE;
        } else if (p.in[i].pic.xres != p.xmax || p.in[i].pic.yres != p.ymax) {
            st = hd_fail(HD_ERR_FORMAT, "%s: resolution mismatch", p.in[i].shown);
        }
        if (common < 0 && p.in[i].hasview) common = i;
    }
    hd_cal *c = st ? NULL : hd_cal_new();
    if (!st && !c) st = HD_ERR_NOMEM;
    if (!st) {
        if (o->nowarn) hd_cal_warnings(c, 0);
        static const char *colin[4] = {"ri", "gi", "bi", "li"}, *colex[4] = {"re", "ge", "be", "le"};
        static const char *ray[7] = {"Ox", "Oy", "Oz", "Dx", "Dy", "Dz", "T"};
        for (int k = 0; k < 4 && !st; k++) {
            st = hd_cal_define_fn(c, colin[k], 1, 3, f_colin, (void *)(intptr_t)k, 0);
            if (!st) st = hd_cal_define_fn(c, colex[k], 1, 1, f_expos, (void *)(intptr_t)k, 0);
        }
        for (int k = 0; k < 7 && !st; k++) st = hd_cal_define_fn(c, ray[k], 1, 1, f_ray, (void *)(intptr_t)k, 0);
        if (!st) st = hd_cal_define_fn(c, "S", 1, 1, f_psize, NULL, 0);
        if (!st) st = hd_cal_define_fn(c, "pa", 1, 1, f_pa, NULL, 0);
        if (!st) st = hd_cal_set(c, "PI", M_PI, 1);
        if (!st) st = hd_cal_set(c, "nfiles", p.n, 1);
        if (!st) st = hd_cal_set(c, "xmax", p.xmax, 1);
        if (!st) st = hd_cal_set(c, "ymax", p.ymax, 1);
        if (!st) st = hd_cal_set(c, "WE", p.xyz ? 1.0 : PC_WE, 1);
        if (!st) st = hd_cal_set(c, "xres", p.xmax, 0);
        if (!st) st = hd_cal_set(c, "yres", p.ymax, 0);
        if (!st) st = hd_cal_define_fn(c, "x", 0, 0, f_x, NULL, 0);
        if (!st) st = hd_cal_define_fn(c, "y", 0, 0, f_y, NULL, 0);
        if (!st && o->define) st = o->define(c, o->define_user);
    }
    for (int k = 0; k < o->ndefs && !st; k++) {
        switch (o->defkind[k]) {
        case 'e': st = hd_cal_parse(c, o->deftext[k], "-e"); break;
        case 'f': st = hd_cal_load(c, o->deftext[k]); break;
        default: {
            double v;
            st = hd_cal_eval(c, o->deftext[k], &v);
            if (!st) st = hd_cal_set(c, o->defkind[k] == 'x' ? "xres" : "yres", v, 1);
        }
        }
    }
    double xr = 0, yr = 0;
    if (!st) st = hd_cal_eval(c, "xres", &xr);
    if (!st) st = hd_cal_eval(c, "yres", &yr);
    p.xres = (int)(xr + .5);
    p.yres = (int)(yr + .5);
    if (!st && (p.xres <= 0 || p.yres <= 0 || p.xres > HD_PIC_MAXSIDE || p.yres > HD_PIC_MAXSIDE ||
                (int64_t)p.xres * p.yres > HD_PIC_MAXPIXELS))
        st = hd_fail(HD_ERR_RANGE, "illegal output resolution");
    int haslo = !st && hd_cal_defined(c, "lo");
    int outfloat = o->outfloat ? (haslo ? 1 : 3) : 0;
    if (!st && cmd_argc > 0) st = hd_header_add_command(&h, cmd_argc, cmd_argv);
    if (!st && common >= 0) {
        char vb[1024];
        hd_view_format(&p.in[common].view, vb, sizeof vb);
        st = hd_header_appendf(&h, "VIEW= %s", vb);
    }
    size_t nout = (size_t)p.xres * p.yres;
    float *out = st ? NULL : hd_big_alloc(nout * 3, sizeof *out, 1);
    if (!st && !out) st = HD_ERR_NOMEM;
    p.rtick = calloc((size_t)p.n + 1, sizeof *p.rtick);
    p.stick = calloc((size_t)p.n + 1, sizeof *p.stick);
    p.org = calloc((size_t)p.n + 1, sizeof *p.org);
    p.dir = calloc((size_t)p.n + 1, sizeof *p.dir);
    p.dist = calloc((size_t)p.n + 1, sizeof *p.dist);
    p.psize = calloc((size_t)p.n + 1, sizeof *p.psize);
    if (!st && (!p.rtick || !p.stick || !p.org || !p.dir || !p.dist || !p.psize)) st = HD_ERR_NOMEM;
    hd_calrun *run = st ? NULL : hd_calrun_new(c, NULL);
    if (!st && !run) st = HD_ERR_NOMEM;
    if (!st) {
        g_pc = &p;
        static const char *colout[3] = {"ro", "go", "bo"};
        int hcol[3], hlo = haslo ? hd_cal_lookup(c, "lo") : -1;
        for (int k = 0; k < 3; k++) hcol[k] = hd_cal_defined(c, colout[k]) ? hd_cal_lookup(c, colout[k]) : -1;
        for (p.ypos = p.yres - 1; p.ypos >= 0 && !st; p.ypos--) {
            p.yscan = (int)((p.ypos + .5) * p.ymax / p.yres);   /* input row, from the bottom */
            float *orow = out + (size_t)(p.yres - 1 - p.ypos) * p.xres * 3;
            for (p.xpos = 0; p.xpos < p.xres; p.xpos++) {
                p.xscan = (int)((p.xpos + .5) * p.xmax / p.xres);
                p.tick++;
                hd_calrun_next(run);
                float *d = orow + (size_t)p.xpos * 3;
                if (hlo >= 0) {
                    double v = hd_calrun_var_id(run, hlo);
                    if (!outfloat && v < 0) v = 0;
                    d[0] = d[1] = d[2] = (float)v;
                } else {
                    for (int k = 0; k < 3; k++) {
                        double v = 0;
                        if (hcol[k] >= 0) {
                            v = hd_calrun_var_id(run, hcol[k]);
                        } else if (p.n) {
                            float s = 0;
                            for (int i = 0; i < p.n; i++)
                                s += p.in[i].pic.pix[((size_t)(p.ymax - 1 - p.yscan) * p.xmax + p.xscan) * 3 + k];
                            v = s;
                        }
                        if (!outfloat && v < 0) v = 0;
                        d[k] = (float)v;
                    }
                }
                if ((st = hd_calrun_status(run))) break;
            }
        }
        g_pc = NULL;
    }
    if (!st && outfloat) {   /* -ff: a float matrix, a row per scanline (lo: its one component) */
        hd_mtxwriter w;
        double *row = hd_malloc_array((size_t)p.xres * (size_t)outfloat, sizeof *row);
        st = row ? hd_mtxwriter_begin(&w, fp, &h, HD_MTXW_HEADER, HD_MTX_FLOAT, p.yres, p.xres, outfloat)
                 : HD_ERR_NOMEM;
        if (!st) {
            for (int y = 0; y < p.yres && !st; y++) {
                const float *o = out + (size_t)y * p.xres * 3;
                for (size_t i = 0; i < (size_t)p.xres * (size_t)outfloat; i++)
                    row[i] = outfloat == 1 ? o[3 * i + 1] : o[i];
                st = hd_mtxwriter_row(&w, row);
            }
            hd_status est = hd_mtxwriter_end(&w);
            if (!st) st = est;
        }
        free(row);
    } else if (!st) {
        hd_picture op;
        hd_picture_init(&op);
        op.xres = p.xres;
        op.yres = p.yres;
        op.pix = out;
        op.fmt = p.xyz ? HD_PIC_XYZE : HD_PIC_RGBE;
        st = hd_picture_write(fp, &op, &h, HD_RES_STANDARD);
    }
    if (run) hd_calrun_free(run);
    if (c) hd_cal_free(c);
    for (int i = 0; i < p.n; i++) hd_picture_free(&p.in[i].pic);
    free(p.in); free(out);
    free(p.rtick); free(p.stick); free(p.org); free(p.dir); free(p.dist); free(p.psize);
    hd_header_free(&h);
    return st;
}

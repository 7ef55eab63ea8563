/* heliodon — tensor trees from radial-basis interpolants (bsdf2ttree) and
 * the reduction of raw tree grids (rttree_reduce). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <stdint.h>

#include "heliodon/bsdf.h"
#include "heliodon/cal.h"
#include "heliodon/genbsdf.h"
#include "heliodon/io.h"
#include "heliodon/parallel.h"
#include "progress.h"
#include "heliodon/rbf.h"
#include "heliodon/rng.h"

/* what a grid is resampled from: an interpolant, or a .cal function
 * bsdf(ix,iy,iz,ox,oy,oz) (or bsdf(ix,iy,iz) with Dx,Dy,Dz the reversed
 * outgoing direction) */
typedef struct tt_src {
    const hd_rbfrep *r;      /* interpolant, or NULL */
    const hd_cal *cal;       /* function form */
    const char *fname;
    int fh, fnargs;
    int single_plane, in_orient, out_orient;
} tt_src;

typedef struct tt_fnstate { hd_calrun *run; double D[3]; } tt_fnstate;

typedef struct tt_job {
    const tt_src *src;
    const hd_ttmake_opts *o;
    float *grid;
    int R;
    hd_progress *prog;
    tt_fnstate *fs;          /* function form: one per worker */
} tt_job;

static double rel_diff(double a, double b)
{
    if (a < 0 || b < 0) return 0;
    double d = (a - b) * 2. / (a + b + .0001);
    return d < 0 ? -d : d;
}

static hd_vec3 out_dir(int orient, double sx, double sy)
{
    hd_vec3 v;
    hd_square2disk(sx, sy, &v.x, &v.y);
    double z2 = 1. - v.x * v.x - v.y * v.y;
    v.z = orient * sqrt(z2 > 0 ? z2 : 0);
    return v;
}

/* incident direction at (u, v) in [0,1)^2 of incident cell k (centre: .5,
 * .5): rank 3 cells lie along -x (the y offset alternates in sign), rank 4
 * cells on the reversed square */
static hd_vec3 cell_dir(const tt_job *j, size_t k, double u, double v)
{
    int R = j->R;
    hd_vec3 in;
    if (j->src->single_plane) {
        in.x = 2. * (k + u) / R - 1.;
        in.y = ((int)(k & 1) * 2 - 1) * v / R;
        if (1. - in.x * in.x - in.y * in.y < 0) in.y = 0;
    } else
        hd_square2disk(1. - ((double)(k / (size_t)R) + u) / R, 1. - ((double)(k % (size_t)R) + v) / R, &in.x, &in.y);
    double z2 = 1. - in.x * in.x - in.y * in.y;
    in.z = j->src->in_orient * sqrt(z2 > 0 ? z2 : 0);
    return in;
}

static double fn_D(hd_calrun *run, void *user, int nargs, const double *args)
{
    (void)nargs;
    (void)args;
    const tt_fnstate *f = hd_calrun_user(run);
    return f->D[(int)(intptr_t)user];
}

/* the function's value for incident in and outgoing o */
static double fn_value(const tt_job *j, tt_fnstate *f, hd_vec3 in, hd_vec3 o)
{
    double a[6] = {in.x, in.y, in.z, o.x, o.y, o.z};
    f->D[0] = -o.x;
    f->D[1] = -o.y;
    f->D[2] = -o.z;
    hd_calrun_next(f->run);
    return hd_calrun_call_id(f->run, j->src->fh, j->src->fnargs, a);
}

/* one incident cell: the R x R outgoing cells into dst */
static hd_status fill_slice(const tt_job *j, size_t cell, int worker, float *dst)
{
    const tt_src *src = j->src;
    const hd_ttmake_opts *o = j->o;
    int R = j->R, oo = src->out_orient;
    hd_vec3 in = cell_dir(j, cell, .5, .5);
    hd_rbfeval *e = NULL;
    tt_fnstate *fs = src->r ? NULL : &j->fs[worker];
    hd_status st = HD_OK;
    if (src->r) {
        hd_rbfdsf d;
        st = hd_rbf_advect(src->r, in, o->lobe_lim, &d);
        if (st != HD_OK) return st;
        st = hd_rbfeval_make(&e, src->r, d.nrbf ? &d : NULL);
        free(d.rbfa);
        if (st != HD_OK) return st;
    }
    float *c = hd_malloc_array((size_t)R * R, sizeof(float));
    if (!c) { hd_rbfeval_free(e); return HD_ERR_NOMEM; }
    double f = 1. / R;
    for (int ox = 0; ox < R; ox++)
        for (int oy = 0; oy < R; oy++) {
            hd_vec3 ov = out_dir(oo, (ox + .5) * f, (oy + .5) * f);
            c[ox * R + oy] = (float)(e ? hd_rbfeval_bsdf(e, ov) : fs ? fn_value(j, fs, in, ov) : src->r->bsdf_min);
        }
    int ns = o->nssamp > 0 ? o->nssamp : 1, k = (int)sqrt((double)ns);
    while (k * k > ns) k--;
    hd_rng rng;
    hd_rng_init(&rng, 0x6273646632747472ULL, cell);
    for (int ox = 0; ox < R; ox++)
        for (int oy = 0; oy < R; oy++) {
            double v = c[ox * R + oy], th = o->ssamp_thresh;
            int ss = (ox + 1 < R && rel_diff(v, c[(ox + 1) * R + oy]) > th) ||
                     (ox > 0 && rel_diff(v, c[(ox - 1) * R + oy]) > th) ||
                     (oy > 0 && rel_diff(v, c[ox * R + oy - 1]) > th) ||
                     (oy + 1 < R && rel_diff(v, c[ox * R + oy + 1]) > th);
            if (ss) {
                /* stratified: k x k strata, the rest jittered over the
                 * cell; a function is also sampled over the incident cell */
                double sum = 0;
                for (int s = 0; s < ns; s++) {
                    double a, b;
                    if (s < k * k) {
                        a = (s / k + hd_rng_uniform(&rng)) / k;
                        b = (s % k + hd_rng_uniform(&rng)) / k;
                    } else {
                        a = hd_rng_uniform(&rng);
                        b = hd_rng_uniform(&rng);
                    }
                    hd_vec3 ov = out_dir(oo, (ox + a) * f, (oy + b) * f);
                    if (e) sum += hd_rbfeval_bsdf(e, ov);
                    else if (fs) {
                        double iu = hd_rng_uniform(&rng), iv = hd_rng_uniform(&rng);
                        sum += fn_value(j, fs, cell_dir(j, cell, iu, iv), ov);
                    } else sum += src->r->bsdf_min;
                }
                v = sum / ns;
            }
            dst[(size_t)ox * R + oy] = (float)v;
        }
    free(c);
    hd_rbfeval_free(e);
    if (fs && hd_calrun_status(fs->run) != HD_OK)
        st = hd_fail(hd_calrun_status(fs->run), "%s: %s", src->fname, hd_errmsg());
    return st;
}

static hd_status cell_chunk(void *ctx, size_t b, size_t e, size_t chunk, int worker)
{
    (void)chunk;
    const tt_job *j = ctx;
    for (size_t k = b; k < e; k++) {
        hd_status st = fill_slice(j, k, worker, j->grid + k * (size_t)j->R * j->R);
        if (st != HD_OK) return st;
        if (j->prog) hd_progress_add(j->prog, 1);
    }
    return HD_OK;
}

static hd_status make_grid(const tt_src *src, const hd_ttmake_opts *o, float *grid)
{
    if (o->log2res < 2 || o->log2res > 9)
        return hd_fail(HD_ERR_RANGE, "-g %d: resolution must be 2..9", o->log2res);
    tt_job j = {src, o, grid, 1 << o->log2res, NULL, NULL};
    size_t R = (size_t)j.R;
    int dims = src->single_plane ? 3 : 4, nth = hd_resolve_threads(o->nthreads);
    size_t nin = dims == 3 ? R / 2 : R * R;
    if (dims == 3) memset(grid + nin * R * R, 0, (R * R * R - nin * R * R) * sizeof(float));
    if (!src->r) {
        j.fs = hd_calloc((size_t)nth, sizeof *j.fs);
        if (!j.fs) return HD_ERR_NOMEM;
        for (int w = 0; w < nth; w++) {
            j.fs[w].run = hd_calrun_new(src->cal, &j.fs[w]);
            if (!j.fs[w].run) {
                for (int q = 0; q < w; q++) hd_calrun_free(j.fs[q].run);
                free(j.fs);
                return HD_ERR_NOMEM;
            }
        }
    }
    if (o->report) j.prog = hd_progress_start("bsdf2ttree: interpolating", nin, 10, 1);
    hd_status st = hd_parallel_for(nin, 1, nth, cell_chunk, &j);
    if (j.prog) hd_progress_finish(j.prog);
    if (j.fs) {
        for (int w = 0; w < nth; w++) hd_calrun_free(j.fs[w].run);
        free(j.fs);
    }
    return st;
}

hd_status hd_ttmake_grid(const hd_rbfrep *r, const hd_ttmake_opts *o, float *grid)
{
    tt_src src = {.r = r, .single_plane = r->single_plane, .in_orient = r->input_orient, .out_orient = r->output_orient};
    return make_grid(&src, o, grid);
}

/* reciprocity averaging of a grid of rank 3 (isotropic: mirror averaging
 * about the incident plane) or 4 (hd_gbtree_reciprocal_avg) */
static void recip_avg(float *g, int rank, int log2res)
{
    if (rank == 4) {
        hd_gbtree_reciprocal_avg(g, log2res);
        return;
    }
    size_t R = (size_t)1 << log2res;
    for (size_t ix = 0; ix < R / 2; ix++)
        for (size_t ox = 0; ox < R; ox++)
            for (size_t oy = 0; oy < R / 2; oy++) {
                float *a = &g[(ix * R + ox) * R + oy], *b = &g[(ix * R + ox) * R + (R - 1 - oy)];
                *a = *b = .5f * (*a + *b);
            }
}

/* ---- bsdf2ttree ---- */

static int comp_index(int input_orient, int output_orient)
{
    /* genbsdf.h block order: T back, R back, T front, R front (front = -Z, exterior) */
    if (input_orient > 0) return output_orient > 0 ? 1 : 0;
    return output_orient > 0 ? 2 : 3;
}

static const char *b2t_usage =
    "usage: bsdf2ttree [{+|-}a][-g Nlog2][-t pctcull][-n nss][-s thresh][-l maxlobes][-p][-N nthreads] "
    "[bsdf.sir ..] > bsdf.xml\n"
    "   or: bsdf2ttree -t{3|4} [{+|-}a][-g Nlog2][-t pctcull][-n nss][-s thresh][-p][-N nthreads]"
    "[{+|-}for[ward]][{+|-}b[ackward]][-e expr][-f file] bsdf_func > bsdf.xml\n";

static int b2t_need(int argc, int i)
{
    if (i + 1 >= argc) {
        fprintf(stderr, "%s: option %s needs a value\n%s", hd_progname(), i < argc ? "" : "?", b2t_usage);
        return 0;
    }
    return 1;
}

/* The value of option argv[*i] (*i moved to it): a number (integral with
 * integer) in [lo, hi]; else 0 after "prog: -X value: expected EXPECT". */
static int opt_num(char **argv, int *i, int integer, double lo, double hi, const char *expect, double *v)
{
    char *end;
    *v = strtod(argv[++*i], &end);
    if (end != argv[*i] && !*end && *v >= lo && *v <= hi && (!integer || *v == floor(*v))) return 1;
    fprintf(stderr, "%s: %s %s: expected %s\n", hd_progname(), argv[*i - 1], argv[*i], expect);
    return 0;
}

int hd_bsdf2ttree_main(int argc, char **argv)
{
    hd_ttmake_opts o = {6, 90., 64, .35, 15000, 0, 0, 0};
    const char *sir[4];
    int nsir = 0;
    char *comment = NULL;
    size_t clen = 0;
    /* function form: -t3/-t4, -e, -f; components from each side */
    hd_cal *cal = NULL;
    int fn_plane = -1, dofwd = 0, dobwd = 1;
    const char *fname = NULL;
    hd_set_progname(argv[0]);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if ((a[0] == '-' || a[0] == '+') && a[1]) {
            double v;
            switch (a[1]) {
            case 'a': o.recip = a[0] == '+'; break;
            case 'g':
                if (!b2t_need(argc, i) || !opt_num(argv, &i, 1, 2, 9, "an integer 2..9", &v)) return 1;
                o.log2res = (int)v;
                break;
            case 't':
                if ((a[2] == '3' || a[2] == '4') && !a[3]) {
                    fn_plane = a[2] == '3';
                    break;
                }
                if (a[2] || !b2t_need(argc, i)) { fputs(b2t_usage, stderr); return 1; }
                if (!opt_num(argv, &i, 0, -HUGE_VAL, nextafter(100, 0),
                             "a percentage below 100 (negative: no reduction)", &o.pctcull))
                    return 1;
                break;
            case 'n':
                if (!b2t_need(argc, i) || !opt_num(argv, &i, 1, 1, 1 << 16, "a positive sample count", &v)) return 1;
                o.nssamp = (int)v;
                break;
            case 'N':
                if (!b2t_need(argc, i)) return 1;
                o.nthreads = atoi(argv[++i]);
                break;
            case 's':
                if (!b2t_need(argc, i) ||
                    !opt_num(argv, &i, 0, nextafter(1e-6, 1), HUGE_VAL, "a positive threshold", &o.ssamp_thresh))
                    return 1;
                break;
            case 'l':
                if (!b2t_need(argc, i)) return 1;
                o.lobe_lim = atoi(argv[++i]);
                break;
            case 'p': o.report = 1; break;
            case 'f':
            case 'e':
                if (a[1] == 'f' && (a[2] || a[0] == '+')) {   /* {+|-}for[ward] */
                    dofwd = a[0] == '+';
                    break;
                }
                if (a[2] || !b2t_need(argc, i)) { fputs(b2t_usage, stderr); return 1; }
                i++;
                if (a[1] == 'f' && strchr(argv[i], '=')) {
                    /* Radiance hands "-f name=value" to wrapBSDF (XML fields) */
                    fprintf(stderr, "%s: warning: -f %s: XML field assignments are not supported (ignored)\n",
                            hd_progname(), argv[i]);
                    break;
                }
                if (!cal) {
                    cal = hd_cal_new();
                    if (!cal || hd_cal_set(cal, "PI", 3.14159265358979323846, 1) != HD_OK) hd_die();
                }
                if ((a[1] == 'e' ? hd_cal_parse(cal, argv[i], "-e") : hd_cal_load(cal, argv[i])) != HD_OK) {
                    hd_report_error();
                    hd_cal_free(cal);
                    return 1;
                }
                if (fn_plane < 0) fn_plane = 0;
                break;
            case 'b': dobwd = a[0] == '+'; break;
            case 'W': break;
            case 'u':
            case 'C': if (!b2t_need(argc, i)) return 1; i++; break;
            default:
                fprintf(stderr, "%s: unknown option %s\n%s", hd_progname(), a, b2t_usage);
                return 1;
            }
            continue;
        }
        if (!nsir && fn_plane >= 0) {   /* the function name, last */
            if (i != argc - 1) {
                fprintf(stderr, "%s: %s: the BSDF function must be the last argument\n%s", hd_progname(), a, b2t_usage);
                hd_cal_free(cal);
                return 1;
            }
            fname = a;
            break;
        }
        if (nsir >= 4) { fprintf(stderr, "%s: at most 4 interpolants\n%s", hd_progname(), b2t_usage); return 1; }
        sir[nsir++] = a;
    }
    if (fn_plane >= 0 && !fname) {
        fprintf(stderr, "%s: -t3/-t4, -e or -f given but no BSDF function named\n%s", hd_progname(), b2t_usage);
        hd_cal_free(cal);
        return 1;
    }
    /* command line for the XML comment */
    hd_header cl;
    hd_header_init(&cl);
    if (hd_header_add_command(&cl, argc, argv) != HD_OK) hd_die();
    hd_gbxml x;
    memset(&x, 0, sizeof x);
    hd_gbtree *trees[4] = {0, 0, 0, 0};
    int dims = 0, rc = 1;
    char name[256] = "", manuf[256] = "";
    const char *stdin_name = "-";
    if (!nsir && !fname) sir[nsir++] = stdin_name;
    comment = hd_strdup(cl.text);
    if (!comment) hd_die();
    clen = strlen(comment);
    while (clen && comment[clen - 1] == '\n') comment[--clen] = 0;
    if (fname) {
        int np = cal ? hd_cal_nparams(cal, fname) : -2;
        if (np != 3 && np != 6) {
            fprintf(stderr, "%s: %s: %s; need a function of 6 arguments bsdf(ix,iy,iz,ox,oy,oz) "
                    "or of 3 using Dx,Dy,Dz bsdf(ix,iy,iz)\n", hd_progname(), fname,
                    np == -2 ? "not defined" : np == -1 ? "a variable, not a function" : "wrong number of arguments");
            goto done;
        }
        tt_src src = {.cal = cal, .fname = fname, .fh = hd_cal_lookup(cal, fname), .fnargs = np,
                      .single_plane = fn_plane};
        if (np == 3)
            for (int q = 0; q < 3; q++) {
                static const char *dn[3] = {"Dx", "Dy", "Dz"};
                if (hd_cal_define_fn(cal, dn[q], 0, 0, fn_D, (void *)(intptr_t)q, 0) != HD_OK) {
                    hd_report_error();
                    goto done;
                }
            }
        dims = fn_plane ? 3 : 4;
        size_t R = (size_t)1 << o.log2res, n = dims == 3 ? R * R * R : R * R * R * R;
        /* Radiance's order: front (exterior) side reflection, transmission;
         * then back side reflection, transmission */
        for (int side = 0; side < 2; side++) {
            if (!(side ? dobwd : dofwd)) continue;
            src.in_orient = side ? 1 : -1;
            for (int refl = 1; refl >= 0; refl--) {
                src.out_orient = refl ? src.in_orient : -src.in_orient;
                int k = comp_index(src.in_orient, src.out_orient);
                float *grid = hd_malloc_array(n, sizeof(float));
                if (!grid) { hd_report_error(); goto done; }
                hd_status st = make_grid(&src, &o, grid);
                if (st == HD_OK && o.recip && refl) recip_avg(grid, dims, o.log2res);
                if (st != HD_OK) { free(grid); hd_report_error(); goto done; }
                if (hd_gbtree_build_rtr(&trees[k], grid, dims, o.log2res, o.pctcull) != HD_OK) {   /* owns grid */
                    hd_report_error();
                    goto done;
                }
            }
        }
    }
    for (int s = 0; s < nsir; s++) {
        hd_rbfrep r;
        if (hd_rbf_read_rows(&r, sir[s]) != HD_OK) { hd_report_error(); hd_rbf_free(&r); goto done; }
        int d = r.single_plane ? 3 : 4;
        if (dims && d != dims) {
            fprintf(stderr, "%s: %s: %s interpolant mixed with %s ones\n", hd_progname(), sir[s],
                    d == 3 ? "isotropic" : "anisotropic", dims == 3 ? "isotropic" : "anisotropic");
            hd_rbf_free(&r);
            goto done;
        }
        dims = d;
        int k = comp_index(r.input_orient, r.output_orient);
        if (trees[k]) {
            fprintf(stderr, "%s: %s: a second interpolant for %s\n", hd_progname(), sir[s],
                    hd_bsdf_window_name((hd_bsdf_comp)(k == 0 ? 2 : k == 1 ? 0 : k == 2 ? 3 : 1)));
            hd_rbf_free(&r);
            goto done;
        }
        if (r.name[0]) snprintf(name, sizeof name, "%s", r.name);
        if (r.manuf[0]) snprintf(manuf, sizeof manuf, "%s", r.manuf);
        /* keep the interpolant's header in the comment */
        size_t add = strlen(sir[s]) + strlen(r.header ? r.header : "") + 8;
        char *nc = realloc(comment, clen + add);
        if (!nc) hd_die();
        comment = nc;
        clen += (size_t)snprintf(comment + clen, add, "\n%s:\n%s", sir[s], r.header ? r.header : "");
        while (clen && comment[clen - 1] == '\n') comment[--clen] = 0;
        size_t R = (size_t)1 << o.log2res, n = dims == 3 ? R * R * R : R * R * R * R;
        float *grid = hd_malloc_array(n, sizeof(float));
        if (!grid) { hd_report_error(); hd_rbf_free(&r); goto done; }
        if (hd_ttmake_grid(&r, &o, grid) != HD_OK) { hd_report_error(); free(grid); hd_rbf_free(&r); goto done; }
        if (o.recip && r.input_orient == r.output_orient) recip_avg(grid, dims, o.log2res);
        hd_rbf_free(&r);
        if (hd_gbtree_build_rtr(&trees[k], grid, dims, o.log2res, o.pctcull) != HD_OK) {
            hd_report_error();
            goto done;
        }
    }
    if (!dims) {
        fprintf(stderr, "%s: no component to write (-backward without +forward)\n", hd_progname());
        goto done;
    }
    x.comment = comment;
    x.name = name;
    x.manufacturer = manuf[0] ? manuf : "Manufacturer";
    x.tree_dims = dims;
    for (int k = 0; k < 4; k++) x.tree[k] = trees[k];
    if (hd_genbsdf_write_xml(stdout, &x, NULL) != HD_OK || fflush(stdout)) {
        hd_fail(HD_ERR_IO, "write error on standard output");
        hd_report_error();
        goto done;
    }
    rc = 0;
done:
    for (int k = 0; k < 4; k++) hd_gbtree_free(trees[k]);
    free(comment);
    hd_header_free(&cl);
    hd_cal_free(cal);
    return rc;
}

/* ---- rttree_reduce ---- */

int hd_rttree_reduce_main(int argc, char **argv)
{
    int header = 1, recip = 0, rank = 4, log2g = 4;
    char fmt = 'a';
    double pct = 95.;
    const char *usage = "usage: rttree_reduce [-h][-a][-f{a|f|d}][-r {3|4}][-g log2grid][-t trim%%] [input]\n";
    hd_set_progname(argv[0]);
    int i = 1;
    for (; i < argc && argv[i][0] == '-' && argv[i][1]; i++) {
        double v;
        switch (argv[i][1]) {
        case 'a': recip = !recip; break;
        case 'h': header = !header; break;
        case 'r':
            if (i + 1 >= argc || ((rank = atoi(argv[++i])) != 3 && rank != 4)) { fputs(usage, stderr); return 1; }
            break;
        case 'g':
            if (i + 1 >= argc) { fputs(usage, stderr); return 1; }
            if (!opt_num(argv, &i, 1, 2, 9, "2..9", &v)) return 1;
            log2g = (int)v;
            break;
        case 't':
            if (i + 1 >= argc) { fputs(usage, stderr); return 1; }
            if (!opt_num(argv, &i, 0, 0, nextafter(100, 0), "0 <= percentage < 100", &pct)) return 1;
            break;
        case 'f':
            fmt = argv[i][2];
            if (!fmt || !strchr("afd", fmt) || argv[i][3]) { fputs(usage, stderr); return 1; }
            break;
        default: fputs(usage, stderr); return 1;
        }
    }
    if (i < argc - 1) { fputs(usage, stderr); return 1; }
    const char *path = i < argc ? argv[i] : "-";
    size_t R = (size_t)1 << log2g, n = rank == 3 ? R * R * R : R * R * R * R;
    size_t nread = rank == 3 ? n / 2 : n;
    float *g = hd_calloc(n, sizeof(float));
    if (!g) { hd_report_error(); return 1; }
    hd_istream *in;
    if (hd_istream_open(&in, path) != HD_OK) { hd_report_error(); free(g); return 1; }
    hd_status st = HD_OK;
    for (size_t k = 0; k < nread && st == HD_OK; k++) {
        if (fmt == 'a') {
            double v;
            int eof;
            st = hd_istream_real(in, &v, &eof);
            if (st == HD_OK && eof)
                st = hd_fail(HD_ERR_FORMAT, "%s: line %lu: data end after %zu of %zu values", hd_istream_name(in),
                             hd_istream_lineno(in), k, nread);
            g[k] = (float)v;
        } else if (fmt == 'f') {
            st = hd_istream_read_exact(in, &g[k], sizeof(float), "float data");
        } else {
            double v;
            st = hd_istream_read_exact(in, &v, sizeof v, "double data");
            g[k] = (float)v;
        }
    }
    if (st == HD_OK) {
        int c;
        while ((c = hd_istream_getc(in)) != EOF)
            if (fmt != 'a' || !strchr(" \t\r\n", c)) {
                fprintf(stderr, "%s: warning: %s: data past the end of the expected input\n", hd_progname(), path);
                break;
            }
    }
    hd_istream_close(in);
    if (st != HD_OK) { hd_report_error(); free(g); return 1; }
    size_t nnan = 0;
    for (size_t k = 0; k < n; k++) nnan += isnan(g[k]) != 0;
    if (nnan) fprintf(stderr, "%s: warning: BSDF data contains %zu NaN values (taken as 0)\n", hd_progname(), nnan);
    if (recip) recip_avg(g, rank, log2g);
    if (header) {
        hd_header h;
        hd_header_init(&h);
        hd_status hs = hd_header_add_command(&h, argc, argv);
        if (!hs) hs = hd_header_put(stdout, &h, NULL, "ascii", NULL);
        hd_header_free(&h);
        if (hs) { hd_report_error(); free(g); return 1; }
    }
    hd_gbtree *t;
    if (hd_gbtree_build_rtr(&t, g, rank, log2g, pct) != HD_OK) { hd_report_error(); return 1; }
    hd_status ws = hd_gbtree_write(stdout, t);
    hd_gbtree_free(t);
    if (ws != HD_OK || fflush(stdout)) { hd_fail(HD_ERR_IO, "write error on standard output"); hd_report_error(); return 1; }
    return 0;
}

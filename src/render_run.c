/* heliodon — rtrace / rpict / vwrays drivers (the programs in tools/ only
 * parse options and call these). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/parallel.h"
#include "progress.h"
#include "heliodon/render.h"
#include "heliodon/scene.h"

/* ------------------------------------------------------------------ */
/* rtrace                                                              */

static int spec_width(char c)
{
    switch (c) {
    case 'o': case 'd': case 'v': case 'p': case 'n': case 'N': return 3;
    case 'l': case 'L': case 'w': return 1;
    case 'm': case 'M': case 's': return -1;   /* string */
    default: return 0;
    }
}

hd_status hd_rtrace_check_spec(const char *spec, int binary, int *ncomp)
{
    int n = 0;
    if (!*spec) return hd_fail(HD_ERR_USAGE, "empty output specification (-o)");
    for (const char *c = spec; *c; c++) {
        int w = spec_width(*c);
        if (w == 0)
            return hd_fail(HD_ERR_USAGE, "output specification -o%s: '%c' is not supported "
                           "(supported: o d v p n N l L w m M s)", spec, *c);
        if (w < 0 && binary)
            return hd_fail(HD_ERR_USAGE, "output specification -o%s: '%c' (a name) needs ASCII output (-fa)", spec, *c);
        if (w > 0) n += w;
    }
    if (ncomp) *ncomp = n;
    return HD_OK;
}

typedef struct rt_ray {
    hd_vec3 org, dir;
    double val[3];
    hd_rayinfo info;
} rt_ray;

typedef struct rt_job {
    const hd_renderer *r;
    const hd_rtrace_opts *o;
    rt_ray *rays;
    uint64_t base;
    hd_progress *prog;
} rt_job;

static hd_status rt_chunk(void *ctx, size_t b, size_t e, size_t ci, int worker)
{
    rt_job *j = ctx;
    (void)ci; (void)worker;
    for (size_t k = b; k < e; k++) {
        rt_ray *y = &j->rays[k];
        hd_rng rng;
        hd_rng_init(&rng, j->r->o.seed, j->base + k);
        memset(&y->info, 0, sizeof y->info);
        y->info.surf = -1;
        y->info.t = INFINITY;
        y->val[0] = y->val[1] = y->val[2] = 0;
        double dl = hd_vlen(y->dir);
        if (dl <= 0) continue;                 /* zero direction: zero output */
        hd_vec3 d = hd_vscale(y->dir, 1 / dl);
        hd_status st;
        if (j->o->irrad == 1) {
            st = hd_render_irradiance(j->r, y->org, d, &rng, y->val);
            y->info.p = y->org;
            y->info.n = y->info.ng = d;
        } else if (j->o->irrad == 2) {
            st = hd_render_irradiance_at_hit(j->r, y->org, d, &rng, y->val, &y->info);
        } else {
            st = hd_render_radiance(j->r, y->org, d, 0, &rng, y->val, &y->info);
        }
        if (st != HD_OK) return st;
    }
    if (j->prog) hd_progress_add(j->prog, e - b);
    return HD_OK;
}

static void put_vals(FILE *fp, char fmt, const double *v, int n)
{
    for (int i = 0; i < n; i++) {
        if (fmt == 'a') fprintf(fp, "%e\t", v[i]);
        else if (fmt == 'f') { float f = (float)v[i]; fwrite(&f, sizeof f, 1, fp); }
        else fwrite(&v[i], sizeof v[i], 1, fp);
    }
}

static void write_ray(FILE *fp, const hd_rtrace_opts *o, const hd_tscene *ts, const hd_scene *sc,
                      const rt_ray *y)
{
    for (const char *c = o->outspec; *c; c++) {
        double v[3];
        switch (*c) {
        case 'o': v[0] = y->org.x; v[1] = y->org.y; v[2] = y->org.z; put_vals(fp, o->fout, v, 3); break;
        case 'd': {
            hd_vec3 d = hd_vnorm(y->dir);
            v[0] = d.x; v[1] = d.y; v[2] = d.z; put_vals(fp, o->fout, v, 3);
            break;
        }
        case 'v': put_vals(fp, o->fout, y->val, 3); break;
        case 'p': v[0] = y->info.p.x; v[1] = y->info.p.y; v[2] = y->info.p.z; put_vals(fp, o->fout, v, 3); break;
        case 'n':
            v[0] = y->info.n.x; v[1] = y->info.n.y; v[2] = y->info.n.z; put_vals(fp, o->fout, v, 3); break;
        case 'N':   /* unperturbed and not turned towards the ray (Radiance's flips undone) */
            v[0] = y->info.ng.x; v[1] = y->info.ng.y; v[2] = y->info.ng.z; put_vals(fp, o->fout, v, 3); break;
        case 'l': case 'L':
            v[0] = y->info.surf >= 0 ? y->info.t : 1e10;   /* Radiance prints a huge length for misses */
            put_vals(fp, o->fout, v, 1);
            break;
        case 'w': v[0] = 1; put_vals(fp, o->fout, v, 1); break;
        case 'm': case 'M': case 's': {
            const char *name = "*";
            if (y->info.surf >= 0) {
                const hd_surface *f = hd_tscene_surface(ts, y->info.surf);
                const hd_tmat *m = hd_tscene_material(ts, f->mat);
                if (*c == 's') {
                    /* "file:line: type id": print the identifier */
                    const char *sp = strrchr(f->where, ' ');
                    name = sp ? sp + 1 : f->where;
                } else {
                    name = m->name;
                }
            }
            (void)sc;
            fprintf(fp, "%s\t", name);
            break;
        }
        default: break;
        }
    }
    if (o->fout == 'a') fputc('\n', fp);
}

void hd_rtrace_defaults(hd_rtrace_opts *o)
{
    memset(o, 0, sizeof *o);
    hd_render_defaults(&o->r);
    snprintf(o->outspec, sizeof o->outspec, "v");
    o->fin = o->fout = 'a';
    o->header = 1;
    o->nthreads = 1;
}

hd_status hd_rtrace_run(const hd_renderer *r, const hd_rtrace_opts *o, const hd_scene *sc,
                        hd_istream *in, FILE *out, const hd_header *hdr)
{
    int ncomp = 0;
    hd_status st = hd_rtrace_check_spec(o->outspec, o->fout != 'a', &ncomp);
    if (st != HD_OK) return st;
    if (o->header) {   /* NCOMP, then NCOLS and NROWS (-x -y), BigEndian= (-ff, -fd) */
        hd_header h;
        hd_header_init(&h);
        if (hdr) st = hd_header_copy(&h, hdr);
        if (st == HD_OK) st = hd_header_appendf(&h, "NCOMP=%d", ncomp);
        hd_header_dims d = {0, 0, 0, o->fout == 'a' ? HD_ENDIAN_NONE : HD_ENDIAN_HOST};
        if (st == HD_OK && o->xres > 0 && o->yres > 0) {
            st = hd_header_appendf(&h, "NCOLS=%d", o->xres);
            d.nrows = o->yres;
        }
        if (st == HD_OK)
            st = hd_header_put(out, &h, &d, o->fout == 'a' ? "ascii" : o->fout == 'f' ? "float" : "double", NULL);
        hd_header_free(&h);
        if (st != HD_OK) return st;
    }
    enum { BATCH = 4096 };
    rt_ray *rays = hd_malloc_array(BATCH, sizeof *rays);
    if (!rays) return HD_ERR_NOMEM;
    uint64_t base = 0;
    int nthreads = hd_resolve_threads(o->nthreads);
    for (;;) {
        size_t n = 0;
        int eof = 0;
        hd_status rs = HD_OK;
        while (n < BATCH && !(rs = hd_istream_ray(in, o->fin, base + n, &rays[n].org, &rays[n].dir, &eof)) && !eof) n++;
        if (rs != HD_OK) { free(rays); return rs; }
        if (n == 0) break;
        rt_job j = {r, o, rays, base, NULL};
        /* small chunks: -I with many samples per point is costly per ray */
        st = hd_parallel_for(n, o->irrad ? 1 : 16, nthreads, rt_chunk, &j);
        if (st != HD_OK) { free(rays); return st; }
        for (size_t k = 0; k < n; k++) write_ray(out, o, r->scene, sc, &rays[k]);
        if (fflush(out) != 0 || ferror(out)) { free(rays); return hd_fail(HD_ERR_IO, "write error on output"); }
        base += n;
        if (n < BATCH) break;
    }
    free(rays);
    return HD_OK;
}

/* ------------------------------------------------------------------ */
/* rpict                                                               */

/* The ray of pass `pass` through pixel (col, row) (row 0 at the top) of an
 * xres x yres picture of view v, jittered by pj within the pixel with the
 * random stream (seed, pass * xres * yres + row * xres + col), which *rng
 * continues (one stream per pixel and pass: independent of the thread
 * count); the value of hd_view_ray. */
static double pixel_ray(const hd_view *v, int xres, int yres, int col, int row, int pass, double pj, uint64_t seed,
                        hd_rng *rng, hd_vec3 *org, hd_vec3 *dir)
{
    hd_rng_init(rng, seed, (uint64_t)pass * (uint64_t)xres * (uint64_t)yres + (uint64_t)row * (uint64_t)xres +
                               (uint64_t)col);
    double jx = 0.5, jy = 0.5;
    if (pj > 0) {
        jx = 0.5 + pj * (hd_rng_uniform(rng) - 0.5);
        jy = 0.5 + pj * (hd_rng_uniform(rng) - 0.5);
    }
    return hd_view_ray(v, (col + jx) / xres, (yres - 1 - row + jy) / yres, org, dir);
}

typedef struct rp_job {
    const hd_renderer *r;
    const hd_rpict_opts *o;
    float *pix;
    int xres, yres;
    hd_progress *prog;
} rp_job;

static hd_status rp_chunk(void *ctx, size_t b, size_t e, size_t ci, int worker)
{
    rp_job *j = ctx;
    (void)ci; (void)worker;
    for (size_t k = b; k < e; k++) {
        int row = (int)(k / (size_t)j->xres), col = (int)(k % (size_t)j->xres);
        double c[3] = {0, 0, 0};
        int spp = j->o->spp > 0 ? j->o->spp : 1;
        for (int s = 0; s < spp; s++) {
            hd_rng rng;
            hd_vec3 org, dir;
            double v[3] = {0, 0, 0};
            double tmax = pixel_ray(&j->o->view, j->xres, j->yres, col, row, s, j->o->pj, j->r->o.seed, &rng, &org, &dir);
            hd_status st = tmax >= 0 ? hd_render_radiance(j->r, org, dir, tmax, &rng, v, NULL) : HD_OK;
            if (st != HD_OK) return st;
            for (int i = 0; i < 3; i++) c[i] += v[i] / spp;
        }
        float *p = j->pix + 3 * k;
        p[0] = (float)c[0]; p[1] = (float)c[1]; p[2] = (float)c[2];
    }
    if (j->prog) hd_progress_add(j->prog, e - b);
    return HD_OK;
}

hd_status hd_rpict_render(const hd_renderer *r, hd_rpict_opts *o, float **pix_out)
{
    hd_status st = hd_view_setup(&o->view);
    if (st != HD_OK) return st;
    if (o->xres <= 0 || o->yres <= 0 || o->xres > 100000 || o->yres > 100000)
        return hd_fail(HD_ERR_RANGE, "picture size %d x %d out of range", o->xres, o->yres);
    double pa = o->pa;
    hd_view_normaspect(hd_view_aspect(&o->view), &pa, &o->xres, &o->yres);
    if (o->xres <= 0 || o->yres <= 0) return hd_fail(HD_ERR_RANGE, "picture size reduced to nothing by -pa");
    size_t npix = (size_t)o->xres * (size_t)o->yres;
    float *pix = hd_malloc_array(npix, 3 * sizeof(float));
    if (!pix) return HD_ERR_NOMEM;
    rp_job j = {r, o, pix, o->xres, o->yres, NULL};
    j.prog = hd_progress_start("rpict", npix, o->report, 0);
    st = hd_parallel_for(npix, 64, hd_resolve_threads(o->nthreads), rp_chunk, &j);
    if (j.prog) hd_progress_finish(j.prog);
    if (st != HD_OK) { free(pix); return st; }
    *pix_out = pix;
    return HD_OK;
}

/* ------------------------------------------------------------------ */
/* vwrays                                                              */

hd_status hd_vwrays_run(hd_view *v, int xres, int yres, double pa, double pj, int repeat, char fmt,
                        uint64_t seed, FILE *out)
{
    hd_status st = hd_view_setup(v);
    if (st != HD_OK) return st;
    if (xres <= 0 || yres <= 0 || xres > 1000000 || yres > 1000000)
        return hd_fail(HD_ERR_RANGE, "resolution %d x %d out of range", xres, yres);
    if (repeat < 1 || repeat > 1000000) return hd_fail(HD_ERR_RANGE, "repeat count %d out of range 1..1000000", repeat);
    hd_view_normaspect(hd_view_aspect(v), &pa, &xres, &yres);
    for (int row = 0; row < yres; row++) {
        for (int col = 0; col < xres; col++)
          for (int k = 0; k < repeat; k++) {   /* rpict's rays of pass k */
            hd_rng rng;
            hd_vec3 o, d;
            if (pixel_ray(v, xres, yres, col, row, k, pj, seed, &rng, &o, &d) < 0) d = hd_v3(0, 0, 0);
            double w[6] = {o.x, o.y, o.z, d.x, d.y, d.z};
            if (fmt == 'a') {
                fprintf(out, "%.6e %.6e %.6e\t%.6e %.6e %.6e\n", w[0], w[1], w[2], w[3], w[4], w[5]);
            } else if (fmt == 'f') {
                float f[6];
                for (int i = 0; i < 6; i++) f[i] = (float)w[i];
                fwrite(f, sizeof f, 1, out);
            } else {
                fwrite(w, sizeof w, 1, out);
            }
        }
    }
    if (fflush(out) != 0 || ferror(out)) return hd_fail(HD_ERR_IO, "write error on output");
    return HD_OK;
}

/* ------------------------------------------------------------------ */
/* common program setup                                                */

hd_status hd_render_load_scene(int nfiles, char **files, hd_scene *sc, hd_tscene **ts, hd_header *hdr,
                               int argc, char **argv)
{
    if (nfiles <= 0) return hd_fail(HD_ERR_USAGE, "no scene file given");
    hd_status st = hd_scene_load_files(sc, nfiles, files, NULL);
    if (st != HD_OK) return st;
    st = hd_tscene_from_scene(ts, sc);
    if (st != HD_OK) return st;
    if (hdr) {
        if (sc->cmdline && *sc->cmdline) {
            /* command line of the scene cache (like Radiance's oconv line) */
            char *t = hd_strdup(sc->cmdline);
            if (!t) return HD_ERR_NOMEM;
            size_t l = strlen(t);
            while (l && (t[l - 1] == '\n' || t[l - 1] == '\r')) t[--l] = 0;
            for (char *line = strtok(t, "\n"); line; line = strtok(NULL, "\n"))
                if (strncmp(line, "SOFTWARE=", 9) != 0) hd_header_append(hdr, line);   /* ours follows */
            free(t);
        }
        hd_header_add_command(hdr, argc, argv);
        hd_header_add_software(hdr);
    }
    return HD_OK;
}

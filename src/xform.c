/* heliodon — similarity transforms (xform syntax) and primitive transformation. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/xform.h"
#include "heliodon/io.h"

void hd_xf_identity(hd_xf *x)
{
    memset(x, 0, sizeof *x);
    x->m[0][0] = x->m[1][1] = x->m[2][2] = 1;
    x->sca = 1;
}

void hd_xf_then(hd_xf *x, const hd_xf *n)
{
    hd_xf r;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            r.m[i][j] = n->m[i][0] * x->m[0][j] + n->m[i][1] * x->m[1][j] + n->m[i][2] * x->m[2][j];
    r.t = hd_xf_point(n, x->t);
    r.sca = x->sca * n->sca;
    r.mirror = x->mirror ^ n->mirror;
    *x = r;
}

hd_vec3 hd_xf_vector(const hd_xf *x, hd_vec3 v)
{
    return hd_v3(x->m[0][0] * v.x + x->m[0][1] * v.y + x->m[0][2] * v.z,
                 x->m[1][0] * v.x + x->m[1][1] * v.y + x->m[1][2] * v.z,
                 x->m[2][0] * v.x + x->m[2][1] * v.y + x->m[2][2] * v.z);
}

hd_vec3 hd_xf_point(const hd_xf *x, hd_vec3 p) { return hd_vadd(hd_xf_vector(x, p), x->t); }
hd_vec3 hd_xf_direction(const hd_xf *x, hd_vec3 v) { return hd_vscale(hd_xf_vector(x, v), 1.0 / x->sca); }

/* exact values for multiples of 90 degrees keep outputs clean */
static void sincos_deg(double deg, double *s, double *c)
{
    double r = fmod(deg, 360.0);
    if (r < 0) r += 360.0;
    if (r == 0) { *s = 0; *c = 1; }
    else if (r == 90) { *s = 1; *c = 0; }
    else if (r == 180) { *s = 0; *c = -1; }
    else if (r == 270) { *s = -1; *c = 0; }
    else { *s = sin(deg * HD_PI / 180); *c = cos(deg * HD_PI / 180); }
}

static int num(const char *w, double *v) { return hd_parse_double(w, v) == 0 && isfinite(*v); }

/* Apply one transform word (and its numbers) at argv[*i] to x.
 * Returns 1 if consumed, 0 if argv[*i] is not a transform word, -1 on error. */
static int one_word(hd_xf *x, int argc, char *const *argv, int *i)
{
    const char *w = argv[*i];
    hd_xf s;
    hd_xf_identity(&s);
    if (!strcmp(w, "-t")) {
        double v[3];
        for (int k = 0; k < 3; k++)
            if (*i + 1 + k >= argc || !num(argv[*i + 1 + k], &v[k])) {
                hd_fail(HD_ERR_USAGE, "-t: expected 3 numbers%s%s", *i + 1 + k < argc ? ", got " : "",
                        *i + 1 + k < argc ? argv[*i + 1 + k] : "");
                return -1;
            }
        s.t = hd_v3(v[0], v[1], v[2]);
        *i += 4;
    } else if (!strcmp(w, "-rx") || !strcmp(w, "-ry") || !strcmp(w, "-rz") || !strcmp(w, "-s")) {
        double d;
        if (*i + 1 >= argc || !num(argv[*i + 1], &d)) {
            hd_fail(HD_ERR_USAGE, "%s: expected a number%s%s", w, *i + 1 < argc ? ", got " : "",
                    *i + 1 < argc ? argv[*i + 1] : "");
            return -1;
        }
        if (w[1] == 's') {
            if (d == 0) { hd_fail(HD_ERR_USAGE, "-s: zero scale factor"); return -1; }
            double a = fabs(d);
            for (int k = 0; k < 3; k++) s.m[k][k] = d;
            s.sca = a;
            s.mirror = d < 0;   /* point inversion: det < 0 */
        } else {
            double sn, cs;
            sincos_deg(d, &sn, &cs);
            int a = w[2] - 'x', b = (a + 1) % 3, c = (a + 2) % 3;
            s.m[b][b] = cs; s.m[b][c] = -sn;
            s.m[c][b] = sn; s.m[c][c] = cs;
        }
        *i += 2;
    } else if (!strcmp(w, "-mx") || !strcmp(w, "-my") || !strcmp(w, "-mz")) {
        int a = w[2] - 'x';
        s.m[a][a] = -1;
        s.mirror = 1;
        *i += 1;
    } else {
        return 0;
    }
    hd_xf_then(x, &s);
    return 1;
}

hd_status hd_xf_parse(hd_xf_spec *spec, int argc, char *const *argv)
{
    memset(spec, 0, sizeof *spec);
    spec->ncopies = 1;
    int i = 0;
    size_t cap = 0;
    while (i < argc) {
        long count = 1;
        int array = 0, repeat = 0;
        const char *w = argv[i];
        if (!strcmp(w, "-a") || !strcmp(w, "-i")) {
            long n;
            if (i + 1 >= argc || hd_parse_long(argv[i + 1], &n) || n < 0 || n > 1000000) {
                hd_xf_spec_free(spec);
                return hd_fail(HD_ERR_USAGE, "%s: expected a count (0..1000000)%s%s", w,
                               i + 1 < argc ? ", got " : "", i + 1 < argc ? argv[i + 1] : "");
            }
            array = w[1] == 'a';
            repeat = !array;
            count = n;
            i += 2;
        }
        hd_xf x;
        hd_xf_identity(&x);
        int start = i, r;
        while (i < argc && (r = one_word(&x, argc, argv, &i)) != 0)
            if (r < 0) { hd_xf_spec_free(spec); return HD_ERR_USAGE; }
        if (!array && !repeat && i == start) break;   /* not a transform word */
        if (HD_GROW(spec->seg, (size_t)spec->nseg + 1, cap, 4)) { hd_xf_spec_free(spec); return HD_ERR_NOMEM; }
        hd_xf_seg *sg = &spec->seg[spec->nseg++];
        sg->array = array; sg->repeat = repeat; sg->count = count; sg->xf = x;
        sg->arg0 = start; sg->arg1 = i;
        if (array) {
            if (count == 0 || spec->ncopies > 100000000 / count) {
                hd_xf_spec_free(spec);
                return hd_fail(HD_ERR_USAGE, "-a: array of %ld copies refused (0, or more than 1e8 in all)", count);
            }
            spec->ncopies *= count;
        }
    }
    spec->nwords = i;
    return HD_OK;
}

void hd_xf_spec_free(hd_xf_spec *spec)
{
    free(spec->seg);
    memset(spec, 0, sizeof *spec);
}

/* per-array index of a copy: first array outermost */
static long array_index(const hd_xf_spec *spec, long copy, int segi)
{
    long inner = 1;
    for (int j = spec->nseg - 1; j > segi; j--)
        if (spec->seg[j].array) inner *= spec->seg[j].count;
    return (copy / inner) % spec->seg[segi].count;
}

void hd_xf_spec_copy(const hd_xf_spec *spec, long copy, hd_xf *out)
{
    hd_xf_identity(out);
    for (int j = 0; j < spec->nseg; j++) {
        const hd_xf_seg *sg = &spec->seg[j];
        long n = sg->array ? array_index(spec, copy, j) : sg->count;
        for (long k = 0; k < n; k++) hd_xf_then(out, &sg->xf);
    }
}

int hd_xf_spec_copy_words(const hd_xf_spec *spec, char *const *argv, long copy,
                          const char **words, int maxwords, char *buf, size_t bufcap)
{
    int nw = 0;
    size_t used = 0;
    for (int j = 0; j < spec->nseg; j++) {
        const hd_xf_seg *sg = &spec->seg[j];
        if (sg->array || sg->repeat) {
            long n = sg->array ? array_index(spec, copy, j) : sg->count;
            if (n == 0) continue;
            int len = snprintf(buf + used, bufcap > used ? bufcap - used : 0, "%ld", n);
            if (len < 0 || used + (size_t)len + 1 > bufcap || nw + 2 > maxwords) return nw;
            words[nw++] = "-i";
            words[nw++] = buf + used;
            used += (size_t)len + 1;
        }
        for (int a = sg->arg0; a < sg->arg1 && nw < maxwords; a++) words[nw++] = argv[a];
    }
    return nw;
}

hd_status hd_xf_from_words(hd_xf *out, int argc, char *const *argv)
{
    hd_xf_spec sp;
    hd_status st = hd_xf_parse(&sp, argc, argv);
    if (st) return st;
    if (sp.nwords != argc) {
        const char *w = argv[sp.nwords];
        hd_xf_spec_free(&sp);
        return hd_fail(HD_ERR_FORMAT, "transform: unexpected word '%s'", w);
    }
    hd_xf_spec_copy(&sp, 0, out);
    hd_xf_spec_free(&sp);
    return HD_OK;
}

/* ---- primitives ---- */
hd_status hd_xform_write_prim(FILE *out, const hd_prim *p, const hd_xf *xf, int nxfwords,
                              const char *const *xfwords, const hd_xform_opts *o, const char *where)
{
    hd_xform_opts dflt = {0, 0, 0};
    if (!o) o = &dflt;
    hd_prim q = *p;
    hd_status st = HD_OK;
    int surface = !hd_type_is_modifier(p->type);
    char *idbuf = NULL;
    double *r = NULL;
    char **sv = NULL;
    if (surface && p->type != HD_T_INSTANCE && p->type != HD_T_MESH) {
        hd_scene dummy;
        hd_scene_init(&dummy);
        st = hd_prim_check(&dummy, p, where);
        if (st) return st;
    }
    if (p->nrargs) {
        r = hd_malloc_array(p->nrargs, sizeof *r);
        if (!r) return HD_ERR_NOMEM;
        memcpy(r, p->rargs, p->nrargs * sizeof *r);
        q.rargs = r;
    }
    if (surface) {
        if (o->newmod) q.modname = o->newmod;
        if (o->prefix) {
            size_t n = strlen(o->prefix) + strlen(p->id) + 2;
            idbuf = hd_malloc(n);
            if (!idbuf) { st = HD_ERR_NOMEM; goto done; }
            snprintf(idbuf, n, "%s.%s", o->prefix, p->id);
            q.id = idbuf;
        }
    }
    switch (p->type) {
    case HD_T_POLYGON: {
        uint32_t nv = p->nrargs / 3;
        int rev = xf->mirror ^ (o->invert != 0);
        for (uint32_t k = 0; k < nv; k++) {
            uint32_t src = rev ? nv - 1 - k : k;
            hd_vec3 v = hd_xf_point(xf, hd_v3(p->rargs[3 * src], p->rargs[3 * src + 1], p->rargs[3 * src + 2]));
            r[3 * k] = v.x; r[3 * k + 1] = v.y; r[3 * k + 2] = v.z;
        }
        break;
    }
    case HD_T_SPHERE: case HD_T_BUBBLE: {
        hd_vec3 c = hd_xf_point(xf, hd_v3(r[0], r[1], r[2]));
        r[0] = c.x; r[1] = c.y; r[2] = c.z;
        r[3] *= xf->sca;
        if (o->invert) q.type = p->type == HD_T_SPHERE ? HD_T_BUBBLE : HD_T_SPHERE;
        break;
    }
    case HD_T_CONE: case HD_T_CUP: case HD_T_CYLINDER: case HD_T_TUBE: {
        hd_vec3 a = hd_xf_point(xf, hd_v3(r[0], r[1], r[2])), b = hd_xf_point(xf, hd_v3(r[3], r[4], r[5]));
        r[0] = a.x; r[1] = a.y; r[2] = a.z; r[3] = b.x; r[4] = b.y; r[5] = b.z;
        for (uint32_t k = 6; k < p->nrargs; k++) r[k] *= xf->sca;
        if (o->invert)
            q.type = p->type == HD_T_CONE ? HD_T_CUP : p->type == HD_T_CUP ? HD_T_CONE
                   : p->type == HD_T_CYLINDER ? HD_T_TUBE : HD_T_CYLINDER;
        break;
    }
    case HD_T_RING: {
        hd_vec3 c = hd_xf_point(xf, hd_v3(r[0], r[1], r[2])), n = hd_xf_direction(xf, hd_v3(r[3], r[4], r[5]));
        if (o->invert) n = hd_vneg(n);
        r[0] = c.x; r[1] = c.y; r[2] = c.z; r[3] = n.x; r[4] = n.y; r[5] = n.z;
        r[6] *= xf->sca; r[7] *= xf->sca;
        break;
    }
    case HD_T_SOURCE: {
        hd_vec3 d = hd_xf_direction(xf, hd_v3(r[0], r[1], r[2]));
        r[0] = d.x; r[1] = d.y; r[2] = d.z;
        break;
    }
    case HD_T_GLOW:
        if (p->nrargs >= 4 && r[3] > 0) r[3] *= xf->sca;
        break;
    case HD_T_SPOTLIGHT:
        if (p->nrargs >= 7) {
            hd_vec3 d = hd_xf_vector(xf, hd_v3(r[4], r[5], r[6]));
            r[4] = d.x; r[5] = d.y; r[6] = d.z;
        }
        break;
    default:
        break;
    }
    if (hd_type_has_transform(p->type) && nxfwords > 0) {
        sv = hd_malloc_array((size_t)p->nsargs + (size_t)nxfwords, sizeof *sv);
        if (!sv) { st = HD_ERR_NOMEM; goto done; }
        for (uint32_t k = 0; k < p->nsargs; k++) sv[k] = p->sargs[k];
        for (int k = 0; k < nxfwords; k++) sv[p->nsargs + k] = (char *)xfwords[k];
        q.sargs = sv;
        q.nsargs = p->nsargs + (uint32_t)nxfwords;
    }
    hd_prim_write(out, &q);
done:
    free(r);
    free(sv);
    free(idbuf);
    return st;
}

/* ---- the xform program ---- */
static void put_shell_word(FILE *out, const char *w)
{
    if (*w && !strpbrk(w, " \t\n'\"\\$`!&|;<>()*?[]#~")) { fputs(w, out); return; }
    fputc('\'', out);
    for (; *w; w++) {
        if (*w == '\'') fputs("'\\''", out);
        else fputc(*w, out);
    }
    fputc('\'', out);
}

hd_status hd_xform_files(FILE *out, int nfiles, char *const *files, const hd_xf_spec *spec,
                         char *const *xfargv, const hd_xform_opts *o, int expand,
                         int argc, char *const *argv)
{
    hd_scene s;
    hd_status st = HD_OK;
    char *const stdin_name[] = {"-"};
    if (nfiles == 0) { nfiles = 1; files = stdin_name; }
    hd_scene_init(&s);
    for (int f = 0; f < nfiles && !st; f++) {
        hd_scene_opts so = {1, expand && getenv(HD_SKIP_ENV) != NULL, !expand, NULL};
        char *dir = NULL;
        const char *slash = strrchr(files[f], '/');
        if (slash && expand) {
            dir = hd_strdup(files[f]);
            if (!dir) { st = HD_ERR_NOMEM; break; }
            dir[slash - files[f] + (slash == files[f])] = 0;
            so.command_dir = dir;
        }
        st = hd_scene_load_rad(&s, files[f], &so);
        free(dir);
    }
    if (st) { hd_scene_free(&s); return st; }
    fputs("# ", out);
    fputs(hd_progname(), out);
    for (int i = 1; i < argc; i++) { fputc(' ', out); put_shell_word(out, argv[i]); }
    fputs("\n", out);
    const char *words[512];
    char numbuf[2048];
    char where[1200];
    for (long c = 0; c < spec->ncopies && !st; c++) {
        hd_xf xf;
        hd_xf_spec_copy(spec, c, &xf);
        int nw = hd_xf_spec_copy_words(spec, xfargv, c, words, 512, numbuf, sizeof numbuf);
        size_t k = 0;
        for (size_t i = 0; i <= s.nprims && !st; i++) {
            while (k < s.nskipped && s.skipped[k].before == i) {
                if (expand) {   /* skipped because its program is missing */
                    fprintf(out, "#@heliodon-skipped %s\n", s.skipped[k].command);
                    k++;
                    continue;
                }
                fputc('!', out);
                fputs(s.skipped[k].command, out);
                fputs(" | xform", out);
                if (o && o->invert) fputs(" -I", out);
                if (o && o->prefix) { fputs(" -n ", out); put_shell_word(out, o->prefix); }
                if (o && o->newmod) { fputs(" -m ", out); put_shell_word(out, o->newmod); }
                for (int j = 0; j < nw; j++) { fputc(' ', out); put_shell_word(out, words[j]); }
                fputc('\n', out);
                k++;
            }
            if (i == s.nprims) break;
            hd_prim_where(&s, (int32_t)i, where, sizeof where);
            st = hd_xform_write_prim(out, &s.prims[i], &xf, nw, words, o, where);
        }
    }
    hd_scene_free(&s);
    if (!st && ferror(out)) st = hd_fail(HD_ERR_IO, "write error on output");
    return st;
}

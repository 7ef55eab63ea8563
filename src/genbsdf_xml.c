/* heliodon — genBSDF: command line, XML output and the program driver. */
#include "heliodon/genbsdf.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/io.h"
#include "heliodon/options.h"
#include "heliodon/parallel.h"
#include "heliodon/render.h"
#include "bsdf_internal.h"
#include "heliodon/scene.h"

static const char *block_name[4] = {"Transmission Back", "Reflection Back", "Transmission Front", "Reflection Front"};

hd_status hd_genbsdf_write_xml(FILE *fp, const hd_gbxml *x, const hd_klems_basis *kb)
{
    int tree = x->tree_dims == 3 || x->tree_dims == 4;
    hd_xml_bsdf_head(fp, "Created by: ", x->comment, " (" HD_SOFTWARE ") -->\n", x->name, x->manufacturer);
    fputs("\t\t<DeviceType>Other</DeviceType>\n", fp);
    const char *u = x->unit && *x->unit ? x->unit : "meter";
    if (x->thickness > 0 || x->width > 0 || x->height > 0) {   /* none for measured data */
        fprintf(fp, "\t\t<Thickness unit=\"%s\">%g</Thickness>\n", u, x->thickness);
        fprintf(fp, "\t\t<Width unit=\"%s\">%g</Width>\n", u, x->width);
        fprintf(fp, "\t\t<Height unit=\"%s\">%g</Height>\n", u, x->height);
    }
    fputs("\t</Material>\n", fp);
    if (x->mgf && *x->mgf) {
        fprintf(fp, "\t<Geometry format=\"MGF\">\n\t\t<MGFblock unit=\"%s\">", u);
        hd_xml_text(fp, x->mgf);
        fputs("</MGFblock>\n\t</Geometry>\n", fp);
    } else
        fputs("\t<Geometry></Geometry>\n", fp);
    fputs("\t<DataDefinition>\n", fp);
    if (tree) {
        fprintf(fp, "\t\t<IncidentDataStructure>TensorTree%d</IncidentDataStructure>\n\t</DataDefinition>\n",
                x->tree_dims);
        for (int k = 0; k < 4; k++) {
            if (!x->tree[k]) continue;
            hd_xml_wavelength_head(fp, block_name[k], NULL, k & 1 ? "BRDF" : "BTDF");
            hd_status st = hd_gbtree_write(fp, x->tree[k]);
            if (st != HD_OK) return st;
            hd_xml_wavelength_tail(fp);
        }
    } else {
        hd_klems_write_xml(fp, kb);
        int n = kb->nbins;
        for (int k = 0; k < 4; k++) {
            if (!x->klems[k]) continue;
            hd_xml_wavelength_head(fp, block_name[k], kb->name, k & 1 ? "BRDF" : "BTDF");
            for (int o = 0; o < n; o++) {
                for (int i = 0; i < n; i++) {
                    double v = x->klems[k][(size_t)o * n + i];
                    if (v == 0) fputs(i ? " 0" : "\t0", fp);
                    else fprintf(fp, i ? " %.5g" : "\t%.5g", v);
                }
                fputc('\n', fp);
            }
            hd_xml_wavelength_tail(fp);
        }
    }
    fputs("</Layer>\n</Optical>\n</WindowElement>\n", fp);
    if (ferror(fp)) return hd_fail(HD_ERR_IO, "write error on the BSDF XML output");
    return HD_OK;
}

/* ---- command line ---- */

static int need(int argc, int i, int n, const char *opt)
{
    if (i + n >= argc) {
        hd_fail(HD_ERR_USAGE, "option %s needs %d argument%s", opt, n, n > 1 ? "s" : "");
        return 0;
    }
    return 1;
}

/* -r 'rtrace options': the words are parsed with rtrace's rendering option
 * group (render.h), so they are spelt, checked and reported as rtrace does;
 * -ab (diffuse bounces), -ad (divisions of a diffuse event), -st (specular
 * threshold), -lr (reflection limit), -lw (minimum ray weight) and -seed apply to
 * genBSDF's tracer, the others are accepted without effect.  Options that
 * are not rendering options (and stray words) are warned about and skipped. */
static hd_status parse_render_opts(const char *s, hd_genbsdf_opts *o)
{
    char buf[1024];
    if (hd_strlcpy(buf, s, sizeof buf) >= sizeof buf)
        return hd_fail(HD_ERR_USAGE, "-r: option string too long");
    char *w[65];
    int n = 1;
    w[0] = "-r";
    for (char *t = strtok(buf, " \t\n'\""); t && n < 65; t = strtok(NULL, " \t\n'\"")) w[n++] = t;
    hd_render_opts R;
    hd_render_defaults(&R);
    R.ab = o->ab;      /* genBSDF's own defaults */
    R.seed = o->seed;
    R.lr = o->lr;
    R.lw = o->lw;
    R.ad = o->ad;
    R.st = o->st;
    hd_opt render_tab[HD_RENDER_NOPTS];
    hd_render_option_table(render_tab, &R);
    int ign_t = 0;
    double ign_d = 0;
    const hd_opt table[] = {
        /* rtrace's own options that make no sense here: accepted, no effect */
        {"I", HD_OPT_TOGGLE, &ign_t, 0, 0, 0, 0},
        {"w", HD_OPT_TOGGLE, &ign_t, 0, 0, 0, 0},
        {"h", HD_OPT_TOGGLE, &ign_t, 0, 0, 0, 0},
        {"ps", HD_OPT_REAL, &ign_d, 0, 0, "N", 0},
        {"pt", HD_OPT_REAL, &ign_d, 0, 0, "f", 0},
        {"", HD_OPT_TABLE, render_tab, 0, 0, 0, 0},
        HD_OPT_END};
    for (int i = 1; i < n;) {
        int used = (w[i][0] == '-' || w[i][0] == '+') && w[i][1] ? hd_opt_parse_one(table, n, w, i) : 0;
        if (used < 0) return hd_fail_context(HD_ERR_USAGE, "-r");
        if (used == 0) {
            hd_warn("-r: option '%s' ignored", w[i]);
            used = 1;
        }
        i += used;
    }
    if (R.ab < 0 || R.ab > 1000) return hd_fail(HD_ERR_USAGE, "-r: -ab %d: expected 0..1000 diffuse bounces", R.ab);
    o->ab = R.ab;
    o->seed = R.seed;
    if (!(R.lw >= 0 && R.lw < 1)) return hd_fail(HD_ERR_USAGE, "-r: -lw %g: expected a weight in [0, 1)", R.lw);
    if (R.lr <= 0 && R.lw <= 0)
        return hd_fail(HD_ERR_USAGE, "-r: -lr %d with -lw 0: Russian roulette needs a positive -lw", R.lr);
    o->lr = R.lr;
    o->lw = R.lw;
    if (R.ad < 0) return hd_fail(HD_ERR_USAGE, "-r: -ad %d: expected a count >= 0", R.ad);
    o->ad = R.ad;
    o->st = R.st;
    return HD_OK;
}

static hd_status parse_spec(const char *s, hd_genbsdf_opts *o)
{
    char buf[512];
    hd_strlcpy(buf, s, sizeof buf);
    for (char *t = strtok(buf, ";"); t; t = strtok(NULL, ";")) {
        if (t[0] && t[1] == '=') {
            if (t[0] == 'm') hd_strlcpy(o->manufacturer, t + 2, sizeof o->manufacturer);
            else if (t[0] == 'n') hd_strlcpy(o->name, t + 2, sizeof o->name);
            /* other fields (t=, h=, w=, d=, ...) accepted and ignored */
        } else
            return hd_fail(HD_ERR_USAGE, "-s: expected 'x=string;...', got '%s'", t);
    }
    return HD_OK;
}

hd_status hd_genbsdf_parse_args(int argc, char **argv, hd_genbsdf_opts *o, int *first)
{
    int i;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if ((a[0] != '-' && a[0] != '+') || !a[1]) break;
        int plus = a[0] == '+';
        const char *k = a + 1;
        long v;
        double d;
        if (!strcmp(k, "c") && !plus) {
            uint64_t c;
            if (!need(argc, i, 1, a)) return HD_ERR_USAGE;
            if (hd_parse_count(argv[++i], &c) || c < 1 || c > 100000000)
                return hd_fail(HD_ERR_USAGE, "-c expects a sample count 1..1e8, got '%s'", argv[i]);
            o->nsamp = c;
        } else if (!strcmp(k, "n") && !plus) {
            if (!need(argc, i, 1, a)) return HD_ERR_USAGE;
            if (hd_parse_long(argv[++i], &v) || v < 0 || v > 1024)
                return hd_fail(HD_ERR_USAGE, "-n expects a thread count, got '%s'", argv[i]);
            o->nthreads = hd_resolve_threads((int)v);
        } else if (!strcmp(k, "r") && !plus) {
            if (!need(argc, i, 1, a)) return HD_ERR_USAGE;
            hd_status st = parse_render_opts(argv[++i], o);
            if (st != HD_OK) return st;
        } else if (!strcmp(k, "t") && !plus) {
            if (!need(argc, i, 1, a)) return HD_ERR_USAGE;
            if (hd_parse_double(argv[++i], &d) || d < 0 || d > 100)
                return hd_fail(HD_ERR_USAGE, "-t expects a culling percentage 0..100, got '%s'", argv[i]);
            o->cull_pct = d;
        } else if ((!strcmp(k, "t3") || !strcmp(k, "t4")) && !plus) {
            if (!need(argc, i, 1, a)) return HD_ERR_USAGE;
            long vmax = k[1] == '4' ? 7 : 9;
            if (hd_parse_long(argv[++i], &v) || v < 1 || v > vmax)
                return hd_fail(HD_ERR_USAGE, "%s expects a resolution exponent 1..%ld, got '%s'", a, vmax, argv[i]);
            o->tree_dims = k[1] - '0';
            o->tree_log2 = (int)v;
        } else if (!strcmp(k, "s") && !plus) {
            if (!need(argc, i, 1, a)) return HD_ERR_USAGE;
            hd_status st = parse_spec(argv[++i], o);
            if (st != HD_OK) return st;
        } else if (!strcmp(k, "seed") && !plus) {
            uint64_t c;
            if (!need(argc, i, 1, a)) return HD_ERR_USAGE;
            if (hd_parse_count(argv[++i], &c))
                return hd_fail(HD_ERR_USAGE, "-seed expects a non-negative integer, got '%s'", argv[i]);
            o->seed = c;
        } else if (!strcmp(k, "dim") && !plus) {
            if (!need(argc, i, 6, a)) return HD_ERR_USAGE;
            for (int j = 0; j < 6; j++)
                if (hd_parse_double(argv[i + 1 + j], &o->dim[j]))
                    return hd_fail(HD_ERR_USAGE, "-dim expects 6 numbers (xmin xmax ymin ymax zmin zmax), got '%s'",
                                   argv[i + 1 + j]);
            i += 6;
            o->have_dim = 1;
        } else if (!strcmp(k, "geom")) {
            if (!need(argc, i, 1, a)) return HD_ERR_USAGE;
            if (hd_genbsdf_unit_scale(argv[i + 1]) <= 0)
                return hd_fail(HD_ERR_USAGE, "%s: unknown unit '%s' (expected meter, centimeter, millimeter, foot or inch)",
                               a, argv[i + 1]);
            hd_strlcpy(o->unit, argv[++i], sizeof o->unit);
            o->embed_geom = plus;
        } else if (k[0] == 'f' && !strncmp(k, "forward", strlen(k))) {
            o->forward = plus;
        } else if (k[0] == 'b' && !strncmp(k, "backward", strlen(k))) {
            o->backward = plus;
        } else if (!strcmp(k, "mgf") || !strcmp(k, "C") || !strcmp(k, "a")) {
            if (plus && k[0] == 'C') hd_warn("+C: colour BSDFs are not generated (Visible/CIE Y only)");
            else if (plus && k[0] == 'm') return hd_fail(HD_ERR_UNSUPPORTED, "+mgf: MGF input is not supported");
        } else if (!strcmp(k, "W") || !strcmp(k, "q")) {
            o->report = 0;
        } else if (!strcmp(k, "v") || !strcmp(k, "report")) {
            o->report = 1;
        } else
            return hd_fail(HD_ERR_USAGE, "unknown option '%s'", a);
    }
    if (!o->forward && !o->backward)
        return hd_fail(HD_ERR_USAGE, "-forward and -backward: nothing to compute");
    *first = i;
    return HD_OK;
}

/* The polygons of the scene as MGF text (faces only, no materials);
 * other surface types are left out with a warning.  Returns a malloc'd
 * string or NULL. */
static char *scene_mgf(const hd_scene *sc)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *m = open_memstream(&buf, &len);
    if (!m) { hd_fail(HD_ERR_NOMEM, "cannot buffer the MGF geometry"); return NULL; }
    unsigned long nv = 0;
    int skipped = 0;
    fputs("\n# geometry of the system (heliodon genBSDF +geom): polygons as MGF faces\n", m);
    for (size_t i = 0; i < sc->nprims; i++) {
        const hd_prim *p = &sc->prims[i];
        if (hd_type_class_of(p->type) != HD_CLASS_SURFACE) continue;
        if (hd_scene_material_of(sc, (int32_t)i) < 0) continue;
        if (p->type != HD_T_POLYGON) { skipped++; continue; }
        uint32_t n = p->nrargs / 3;
        unsigned long first = nv;
        for (uint32_t k = 0; k < n; k++, nv++)
            fprintf(m, "v v%lu =\n\tp %.9g %.9g %.9g\n", nv, p->rargs[3 * k], p->rargs[3 * k + 1], p->rargs[3 * k + 2]);
        fputs("f", m);
        for (uint32_t k = 0; k < n; k++) fprintf(m, " v%lu", first + k);
        fputc('\n', m);
    }
    if (fclose(m) != 0) { free(buf); hd_fail(HD_ERR_NOMEM, "cannot buffer the MGF geometry"); return NULL; }
    if (skipped) hd_warn("+geom: %d non-polygon surface(s) left out of the MGF geometry", skipped);
    return buf;
}

static char *join_args(int argc, char **argv)
{
    size_t n = 1;
    for (int i = 0; i < argc; i++) n += strlen(argv[i]) + 3;
    char *s = hd_malloc(n);
    if (!s) return NULL;
    s[0] = 0;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        if (i == 0 && strrchr(a, '/')) a = strrchr(a, '/') + 1;   /* program name without its directory */
        if (i) strcat(s, " ");
        int q = strchr(a, ' ') != NULL || strchr(a, ';') != NULL;
        if (q) strcat(s, "'");
        strcat(s, a);
        if (q) strcat(s, "'");
    }
    return s;
}

static hd_status generate(int argc, char **argv, FILE *out)
{
    hd_genbsdf_opts o;
    hd_genbsdf_defaults(&o);
    int first = argc;
    hd_status st = hd_genbsdf_parse_args(argc, argv, &o, &first);
    if (st != HD_OK) return st;
    hd_scene sc;
    hd_scene_init(&sc);
    char *stdin_arg[1] = {"-"};
    for (int i = first; i < argc; i++) {
        const char *e = strrchr(argv[i], '.');
        if (e && !strcmp(e, ".mgf")) { hd_scene_free(&sc); return hd_fail(HD_ERR_UNSUPPORTED, "%s: MGF input is not supported", argv[i]); }
    }
    st = first < argc ? hd_scene_load_files(&sc, argc - first, argv + first, NULL)
                      : hd_scene_load_files(&sc, 1, stdin_arg, NULL);
    if (st != HD_OK) { hd_scene_free(&sc); return st; }
    hd_gbsystem *g = NULL;
    st = hd_gbsystem_create(&g, &sc, &o);
    char *mgf = NULL;
    if (st == HD_OK && o.embed_geom && !(mgf = scene_mgf(&sc))) st = HD_ERR_NOMEM;
    hd_scene_free(&sc);
    if (st != HD_OK) { free(mgf); hd_gbsystem_free(g); return st; }
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    hd_gbxml x;
    memset(&x, 0, sizeof x);
    char *cmd = join_args(argc, argv);
    x.comment = cmd;
    x.manufacturer = o.manufacturer;
    x.name = o.name;
    x.unit = o.unit;
    x.thickness = -o.dim[4];     /* Radiance's genBSDF: t = -zmin (it assumes zmax = 0) */
    x.width = o.dim[1] - o.dim[0];
    x.height = o.dim[3] - o.dim[2];
    x.tree_dims = o.tree_dims;
    x.mgf = mgf;
    double *kv[4] = {0, 0, 0, 0};
    hd_gbtree *tv[4] = {0, 0, 0, 0};
    if (!o.tree_dims) {
        size_t n = (size_t)kb.nbins * (size_t)kb.nbins;
        for (int k = 0; k < 4 && st == HD_OK; k++) {
            int want = k < 2 ? o.backward : o.forward;
            if (!want) continue;
            if (!(kv[k] = hd_calloc(n, sizeof(double)))) st = HD_ERR_NOMEM;
        }
        if (st == HD_OK && o.backward) st = hd_genbsdf_klems(g, &o, HD_GB_FROM_ROOM, &kb, kv[0], kv[1]);
        if (st == HD_OK && o.forward) st = hd_genbsdf_klems(g, &o, HD_GB_FROM_EXTERIOR, &kb, kv[2], kv[3]);
        for (int k = 0; k < 4; k++) x.klems[k] = kv[k];
    } else {
        int R = 1 << o.tree_log2;
        size_t n = 1;
        for (int d = 0; d < o.tree_dims; d++) n *= (size_t)R;
        for (int side = 0; side < 2 && st == HD_OK; side++) {
            int from_room = side == 0;
            if (from_room ? !o.backward : !o.forward) continue;
            /* trees carry one transmission block (reciprocity gives the other) */
            int want_t = from_room || !o.backward;
            float *t = want_t ? hd_calloc(n, sizeof(float)) : NULL;
            float *r = hd_calloc(n, sizeof(float));
            if ((want_t && !t) || !r) st = HD_ERR_NOMEM;
            if (st == HD_OK)
                st = hd_genbsdf_tree(g, &o, from_room ? HD_GB_FROM_ROOM : HD_GB_FROM_EXTERIOR, t, r);
            if (st == HD_OK && o.tree_dims == 4) hd_gbtree_reciprocal_avg(r, o.tree_log2);
            int kt = from_room ? 0 : 2, kr = from_room ? 1 : 3;
            double ns = ceil(sqrt((double)o.nsamp));
            if (st == HD_OK && t) st = hd_gbtree_build(&tv[kt], t, o.tree_dims, o.tree_log2, o.cull_pct, ns * ns);
            if (st == HD_OK) st = hd_gbtree_build(&tv[kr], r, o.tree_dims, o.tree_log2, o.cull_pct, ns * ns);
            free(t);
            free(r);
        }
        for (int k = 0; k < 4; k++) x.tree[k] = tv[k];
    }
    if (st == HD_OK) st = hd_genbsdf_write_xml(out, &x, &kb);
    for (int k = 0; k < 4; k++) { free(kv[k]); hd_gbtree_free(tv[k]); }
    free(cmd);
    free(mgf);
    hd_gbsystem_free(g);
    return st;
}

int hd_genbsdf_main(int argc, char **argv, FILE *out)
{
    hd_ofile *of = NULL;
    hd_status st = HD_OK;
    if (!out) {
        st = hd_ofile_open(&of, NULL);
        if (st != HD_OK) { hd_report_error(); return 1; }
        out = hd_ofile_fp(of);
    }
    st = generate(argc, argv, out);
    if (st != HD_OK) {
        hd_report_error();
        if (of) hd_ofile_abort(of);
        return 1;
    }
    if (of && (st = hd_ofile_commit(of)) != HD_OK) { hd_report_error(); return 1; }
    return 0;
}

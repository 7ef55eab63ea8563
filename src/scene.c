/* heliodon — scene model: type table, primitive storage, name lookup,
 * aliases, argument checks, text output, material parameters. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/scene.h"
#include "scene_priv.h"

/* ---- type table ---- */
static const struct { const char *name; hd_type_class cls; int xf; } types[HD_T_COUNT] = {
    [HD_T_POLYGON] = {"polygon", HD_CLASS_SURFACE, 0},
    [HD_T_SPHERE] = {"sphere", HD_CLASS_SURFACE, 0},
    [HD_T_BUBBLE] = {"bubble", HD_CLASS_SURFACE, 0},
    [HD_T_CONE] = {"cone", HD_CLASS_SURFACE, 0},
    [HD_T_CUP] = {"cup", HD_CLASS_SURFACE, 0},
    [HD_T_CYLINDER] = {"cylinder", HD_CLASS_SURFACE, 0},
    [HD_T_TUBE] = {"tube", HD_CLASS_SURFACE, 0},
    [HD_T_RING] = {"ring", HD_CLASS_SURFACE, 0},
    [HD_T_SOURCE] = {"source", HD_CLASS_SURFACE, 0},
    [HD_T_INSTANCE] = {"instance", HD_CLASS_SURFACE, 1},
    [HD_T_MESH] = {"mesh", HD_CLASS_SURFACE, 1},
    [HD_T_LIGHT] = {"light", HD_CLASS_MATERIAL, 0},
    [HD_T_ILLUM] = {"illum", HD_CLASS_MATERIAL, 0},
    [HD_T_GLOW] = {"glow", HD_CLASS_MATERIAL, 0},
    [HD_T_SPOTLIGHT] = {"spotlight", HD_CLASS_MATERIAL, 0},
    [HD_T_PLASTIC] = {"plastic", HD_CLASS_MATERIAL, 0},
    [HD_T_METAL] = {"metal", HD_CLASS_MATERIAL, 0},
    [HD_T_TRANS] = {"trans", HD_CLASS_MATERIAL, 0},
    [HD_T_PLASTIC2] = {"plastic2", HD_CLASS_MATERIAL, 1},
    [HD_T_METAL2] = {"metal2", HD_CLASS_MATERIAL, 1},
    [HD_T_TRANS2] = {"trans2", HD_CLASS_MATERIAL, 1},
    [HD_T_MIRROR] = {"mirror", HD_CLASS_MATERIAL, 0},
    [HD_T_DIELECTRIC] = {"dielectric", HD_CLASS_MATERIAL, 0},
    [HD_T_INTERFACE] = {"interface", HD_CLASS_MATERIAL, 0},
    [HD_T_GLASS] = {"glass", HD_CLASS_MATERIAL, 0},
    [HD_T_PLASFUNC] = {"plasfunc", HD_CLASS_MATERIAL, 1},
    [HD_T_METFUNC] = {"metfunc", HD_CLASS_MATERIAL, 1},
    [HD_T_TRANSFUNC] = {"transfunc", HD_CLASS_MATERIAL, 1},
    [HD_T_BRTDFUNC] = {"BRTDfunc", HD_CLASS_MATERIAL, 1},
    [HD_T_PLASDATA] = {"plasdata", HD_CLASS_MATERIAL, 1},
    [HD_T_METDATA] = {"metdata", HD_CLASS_MATERIAL, 1},
    [HD_T_TRANSDATA] = {"transdata", HD_CLASS_MATERIAL, 1},
    [HD_T_BSDF] = {"BSDF", HD_CLASS_MATERIAL, 1},
    [HD_T_ABSDF] = {"aBSDF", HD_CLASS_MATERIAL, 1},
    [HD_T_ASHIK2] = {"ashik2", HD_CLASS_MATERIAL, 1},
    [HD_T_WGMDFUNC] = {"WGMDfunc", HD_CLASS_MATERIAL, 1},
    [HD_T_ANTIMATTER] = {"antimatter", HD_CLASS_MATERIAL, 0},
    [HD_T_MIST] = {"mist", HD_CLASS_MATERIAL, 0},
    [HD_T_PRISM1] = {"prism1", HD_CLASS_MATERIAL, 1},
    [HD_T_PRISM2] = {"prism2", HD_CLASS_MATERIAL, 1},
    [HD_T_TEXFUNC] = {"texfunc", HD_CLASS_TEXTURE, 1},
    [HD_T_TEXDATA] = {"texdata", HD_CLASS_TEXTURE, 1},
    [HD_T_COLORFUNC] = {"colorfunc", HD_CLASS_PATTERN, 1},
    [HD_T_BRIGHTFUNC] = {"brightfunc", HD_CLASS_PATTERN, 1},
    [HD_T_COLORDATA] = {"colordata", HD_CLASS_PATTERN, 1},
    [HD_T_BRIGHTDATA] = {"brightdata", HD_CLASS_PATTERN, 1},
    [HD_T_COLORPICT] = {"colorpict", HD_CLASS_PATTERN, 1},
    [HD_T_COLORTEXT] = {"colortext", HD_CLASS_PATTERN, 1},
    [HD_T_BRIGHTTEXT] = {"brighttext", HD_CLASS_PATTERN, 1},
    [HD_T_SPECTRUM] = {"spectrum", HD_CLASS_PATTERN, 0},
    [HD_T_SPECFILE] = {"specfile", HD_CLASS_PATTERN, 0},
    [HD_T_SPECFUNC] = {"specfunc", HD_CLASS_PATTERN, 1},
    [HD_T_SPECDATA] = {"specdata", HD_CLASS_PATTERN, 1},
    [HD_T_SPECPICT] = {"specpict", HD_CLASS_PATTERN, 1},
    [HD_T_MIXFUNC] = {"mixfunc", HD_CLASS_MIXTURE, 1},
    [HD_T_MIXDATA] = {"mixdata", HD_CLASS_MIXTURE, 1},
    [HD_T_MIXPICT] = {"mixpict", HD_CLASS_MIXTURE, 1},
    [HD_T_MIXTEXT] = {"mixtext", HD_CLASS_MIXTURE, 1},
    [HD_T_ALIAS] = {"alias", HD_CLASS_ALIAS, 0},
};

const char *hd_type_name(hd_prim_type t)
{
    return (unsigned)t < HD_T_COUNT ? types[t].name : "(bad type)";
}

int hd_type_from_name(const char *name)
{
    for (int t = 0; t < HD_T_COUNT; t++)
        if (!strcmp(types[t].name, name)) return t;
    return -1;
}

hd_type_class hd_type_class_of(hd_prim_type t)
{
    return (unsigned)t < HD_T_COUNT ? types[t].cls : HD_CLASS_SURFACE;
}

int hd_type_is_modifier(hd_prim_type t) { return hd_type_class_of(t) != HD_CLASS_SURFACE; }
int hd_type_has_transform(hd_prim_type t) { return (unsigned)t < HD_T_COUNT && types[t].xf; }

/* ---- arena: strings and argument arrays live in large chunks ---- */
typedef struct chunk { struct chunk *next; size_t used, cap; max_align_t data[]; } chunk;

static void *arena_alloc(hd_scene *s, size_t n)
{
    chunk *c = s->arena;
    n = (n + sizeof(max_align_t) - 1) / sizeof(max_align_t) * sizeof(max_align_t);
    if (!c || c->cap - c->used < n) {
        size_t cap = n > 65536 ? n : 65536;
        chunk *nc = hd_malloc(sizeof(chunk) + cap);
        if (!nc) return NULL;
        nc->next = c; nc->used = 0; nc->cap = cap;
        s->arena = c = nc;
    }
    void *p = (char *)c->data + c->used;
    c->used += n;
    return p;
}

static char *arena_str(hd_scene *s, const char *str)
{
    size_t n = strlen(str) + 1;
    char *p = arena_alloc(s, n);
    if (p) memcpy(p, str, n);
    return p;
}

/* ---- name table: open addressing, name -> latest modifier index ---- */
struct hd_scene_names { size_t cap, count; const char **key; int32_t *val; };

static uint64_t hash_str(const char *s)
{
    uint64_t h = 1469598103934665603ull;
    while (*s) { h ^= (unsigned char)*s++; h *= 1099511628211ull; }
    return h;
}

static hd_status names_put(hd_scene *s, const char *key, int32_t val)
{
    hd_scene_names *t = s->names;
    if (!t) {
        t = hd_calloc(1, sizeof *t);
        if (!t) return HD_ERR_NOMEM;
        s->names = t;
    }
    if ((t->count + 1) * 2 > t->cap) {
        size_t ncap = t->cap ? t->cap * 2 : 64;
        const char **nk = hd_calloc(ncap, sizeof *nk);
        int32_t *nv = hd_calloc(ncap, sizeof *nv);
        if (!nk || !nv) { free(nk); free(nv); return HD_ERR_NOMEM; }
        for (size_t i = 0; i < t->cap; i++) {
            if (!t->key[i]) continue;
            size_t j = hash_str(t->key[i]) & (ncap - 1);
            while (nk[j]) j = (j + 1) & (ncap - 1);
            nk[j] = t->key[i]; nv[j] = t->val[i];
        }
        free(t->key); free(t->val);
        t->key = nk; t->val = nv; t->cap = ncap;
    }
    size_t j = hash_str(key) & (t->cap - 1);
    while (t->key[j]) {
        if (!strcmp(t->key[j], key)) { t->val[j] = val; return HD_OK; }
        j = (j + 1) & (t->cap - 1);
    }
    t->key[j] = key; t->val[j] = val; t->count++;
    return HD_OK;
}

int32_t hd_scene_find_modifier(const hd_scene *s, const char *name)
{
    const hd_scene_names *t = s->names;
    if (!t || !t->cap || !strcmp(name, "void")) return -1;
    size_t j = hash_str(name) & (t->cap - 1);
    while (t->key[j]) {
        if (!strcmp(t->key[j], name)) return t->val[j];
        j = (j + 1) & (t->cap - 1);
    }
    return -1;
}

/* ---- scene ---- */
void hd_scene_init(hd_scene *s) { memset(s, 0, sizeof *s); }

void hd_scene_free(hd_scene *s)
{
    chunk *c = s->arena;
    while (c) { chunk *n = c->next; free(c); c = n; }
    for (size_t i = 0; i < s->nfiles; i++) free(s->files[i].name);
    for (size_t i = 0; i < s->nskipped; i++) free(s->skipped[i].command);
    free(s->files);
    free(s->skipped);
    free(s->prims);
    free(s->cmdline);
    if (s->names) { free(s->names->key); free(s->names->val); free(s->names); }
    memset(s, 0, sizeof *s);
}

hd_status hd_scene_add(hd_scene *s, const hd_prim *p)
{
    if (s->nprims >= INT32_MAX - 1)
        return hd_fail(HD_ERR_RANGE, "scene: more than %d primitives", INT32_MAX - 1);
    if (HD_GROW(s->prims, s->nprims + 1, s->capprims, 256)) return HD_ERR_NOMEM;
    hd_prim q = *p;
    q.modname = arena_str(s, p->modname ? p->modname : "void");
    q.id = arena_str(s, p->id ? p->id : "");
    if (!q.modname || !q.id) return HD_ERR_NOMEM;
    q.sargs = NULL; q.iargs = NULL; q.rargs = NULL;
    if (p->nsargs) {
        q.sargs = arena_alloc(s, (size_t)p->nsargs * sizeof(char *));
        if (!q.sargs) return HD_ERR_NOMEM;
        for (uint32_t k = 0; k < p->nsargs; k++)
            if (!(q.sargs[k] = arena_str(s, p->sargs[k]))) return HD_ERR_NOMEM;
    }
    if (p->niargs) {
        q.iargs = arena_alloc(s, (size_t)p->niargs * sizeof(long));
        if (!q.iargs) return HD_ERR_NOMEM;
        memcpy(q.iargs, p->iargs, (size_t)p->niargs * sizeof(long));
    }
    if (p->nrargs) {
        q.rargs = arena_alloc(s, (size_t)p->nrargs * sizeof(double));
        if (!q.rargs) return HD_ERR_NOMEM;
        memcpy(q.rargs, p->rargs, (size_t)p->nrargs * sizeof(double));
    }
    int32_t idx = (int32_t)s->nprims;
    s->prims[s->nprims++] = q;
    if (hd_type_is_modifier(q.type)) {
        hd_status st = names_put(s, q.id, idx);
        if (st) return st;
    }
    return HD_OK;
}

hd_status hd_scene_add_file(hd_scene *s, const char *name, int32_t parent,
                            uint32_t parent_line, uint32_t *idx)
{
    if (HD_GROW(s->files, s->nfiles + 1, s->capfiles, 16)) return HD_ERR_NOMEM;
    char *n = hd_strdup(name);
    if (!n) return HD_ERR_NOMEM;
    s->files[s->nfiles].name = n;
    s->files[s->nfiles].parent = parent;
    s->files[s->nfiles].parent_line = parent_line;
    *idx = (uint32_t)s->nfiles++;
    return HD_OK;
}

hd_status hd_scene_add_skipped(hd_scene *s, const char *cmd, uint32_t file, uint32_t line)
{
    if (HD_GROW(s->skipped, s->nskipped + 1, s->capskipped, 8)) return HD_ERR_NOMEM;
    char *c = hd_strdup(cmd);
    if (!c) return HD_ERR_NOMEM;
    s->skipped[s->nskipped].command = c;
    s->skipped[s->nskipped].file = file;
    s->skipped[s->nskipped].line = line;
    s->skipped[s->nskipped].before = s->nprims;
    s->nskipped++;
    return HD_OK;
}

int32_t hd_scene_unalias(const hd_scene *s, int32_t i)
{
    size_t guard = 0;
    while (i >= 0 && (size_t)i < s->nprims && s->prims[i].type == HD_T_ALIAS &&
           s->prims[i].alias_of >= 0 && guard++ < s->nprims)
        i = s->prims[i].alias_of;
    return i;
}

int32_t hd_scene_material_of(const hd_scene *s, int32_t surface)
{
    if (surface < 0 || (size_t)surface >= s->nprims) return -1;
    int32_t m = s->prims[surface].modifier;
    size_t guard = 0;
    while (m >= 0 && (size_t)m < s->nprims && guard++ < s->nprims) {
        int32_t u = hd_scene_unalias(s, m);
        if (u >= 0 && hd_type_class_of(s->prims[u].type) == HD_CLASS_MATERIAL) return u;
        m = s->prims[m].modifier;
    }
    return -1;
}

void hd_scene_where_file(const hd_scene *s, uint32_t f, uint32_t line, char *buf, size_t cap)
{
    if (f >= s->nfiles) { snprintf(buf, cap, "(unknown):%u", line); return; }
    const hd_scene_file *sf = &s->files[f];
    if (sf->name[0] == '!' && sf->parent >= 0 && (size_t)sf->parent < s->nfiles) {
        char outer[512];
        hd_scene_where_file(s, (uint32_t)sf->parent, sf->parent_line, outer, sizeof outer);
        snprintf(buf, cap, "%s: output of '%.200s' line %u", outer, sf->name, line);
    } else {
        snprintf(buf, cap, "%s:%u", sf->name, line);
    }
}

const char *hd_scene_where(const hd_scene *s, uint32_t file, uint32_t line, char *buf, size_t cap)
{
    if (cap) hd_scene_where_file(s, file, line, buf, cap);
    return buf;
}

const char *hd_prim_where(const hd_scene *s, int32_t i, char *buf, size_t cap)
{
    if (!cap) return buf;
    if (i < 0 || (size_t)i >= s->nprims) { snprintf(buf, cap, "(no primitive)"); return buf; }
    hd_scene_where_file(s, s->prims[i].file, s->prims[i].line, buf, cap);
    return buf;
}

/* ---- argument checks ---- */
#define BAD(...) hd_fail(HD_ERR_FORMAT, __VA_ARGS__)

hd_status hd_prim_check(const hd_scene *s, const hd_prim *p, const char *where)
{
    (void)s;
    const char *tn = hd_type_name(p->type), *id = p->id;
    uint32_t ns = p->nsargs, nr = p->nrargs;
    int nr_ok = 1, ns_ok = 1;
    const char *want = NULL;
    if (p->niargs != 0)
        return BAD("%s: %s %s: integer argument count must be 0, got %u", where, tn, id, p->niargs);
    switch (p->type) {
    case HD_T_POLYGON:
        ns_ok = ns == 0;
        nr_ok = nr >= 9 && nr % 3 == 0;
        want = "0 strings and 3*n reals with n >= 3 vertices";
        break;
    case HD_T_SPHERE: case HD_T_BUBBLE:
        ns_ok = ns == 0; nr_ok = nr == 4; want = "0 strings and 4 reals (centre, radius)"; break;
    case HD_T_CONE: case HD_T_CUP:
        ns_ok = ns == 0; nr_ok = nr == 8; want = "0 strings and 8 reals (x0 y0 z0 x1 y1 z1 r0 r1)"; break;
    case HD_T_CYLINDER: case HD_T_TUBE:
        ns_ok = ns == 0; nr_ok = nr == 7; want = "0 strings and 7 reals (x0 y0 z0 x1 y1 z1 r)"; break;
    case HD_T_RING:
        ns_ok = ns == 0; nr_ok = nr == 8; want = "0 strings and 8 reals (centre, normal, r0 r1)"; break;
    case HD_T_SOURCE:
        ns_ok = ns == 0; nr_ok = nr == 4; want = "0 strings and 4 reals (direction, angle)"; break;
    case HD_T_INSTANCE: case HD_T_MESH:
        ns_ok = ns >= 1; nr_ok = nr == 0; want = "at least 1 string (file [transform]) and 0 reals"; break;
    case HD_T_PLASTIC: case HD_T_METAL:
        ns_ok = ns == 0; nr_ok = nr == 5; want = "0 strings and 5 reals (R G B spec rough)"; break;
    case HD_T_TRANS:
        ns_ok = ns == 0; nr_ok = nr == 7; want = "0 strings and 7 reals (R G B spec rough trans tspec)"; break;
    case HD_T_GLASS:
        ns_ok = ns == 0; nr_ok = nr == 3 || nr == 4; want = "0 strings and 3 or 4 reals (tr tg tb [n])"; break;
    case HD_T_MIRROR:
        ns_ok = ns <= 1; nr_ok = nr == 3; want = "0 or 1 string and 3 reals (R G B)"; break;
    case HD_T_LIGHT:
        ns_ok = ns == 0; nr_ok = nr == 3; want = "0 strings and 3 reals (R G B)"; break;
    case HD_T_GLOW:
        ns_ok = ns == 0; nr_ok = nr == 4; want = "0 strings and 4 reals (R G B maxrad)"; break;
    case HD_T_ILLUM:
        ns_ok = ns <= 1; nr_ok = nr == 3; want = "0 or 1 string and 3 reals (R G B)"; break;
    case HD_T_SPOTLIGHT:
        ns_ok = ns == 0; nr_ok = nr == 7; want = "0 strings and 7 reals (R G B angle dx dy dz)"; break;
    case HD_T_ANTIMATTER:
        nr_ok = nr == 0; want = "modifier names as strings and 0 reals"; break;
    case HD_T_DIELECTRIC:
        ns_ok = ns == 0; nr_ok = nr == 5; want = "0 strings and 5 reals"; break;
    case HD_T_INTERFACE:
        ns_ok = ns == 0; nr_ok = nr == 8; want = "0 strings and 8 reals"; break;
    case HD_T_BSDF:
        ns_ok = ns >= 6; nr_ok = nr == 0 || nr == 3 || nr == 6 || nr == 9;
        want = "at least 6 strings (thick file ux uy uz funcfile [transform]) and 0, 3, 6 or 9 reals";
        break;
    case HD_T_ABSDF:
        ns_ok = ns >= 5; nr_ok = nr == 0 || nr == 3 || nr == 6 || nr == 9;
        want = "at least 5 strings (file ux uy uz funcfile [transform]) and 0, 3, 6 or 9 reals";
        break;
    case HD_T_ALIAS:
        ns_ok = ns == 1; nr_ok = nr == 0; want = "an aliased identifier"; break;
    default:
        break;
    }
    if (!ns_ok || !nr_ok)
        return BAD("%s: %s %s: expected %s, got %u string%s and %u real%s", where, tn, id, want,
                   ns, ns == 1 ? "" : "s", nr, nr == 1 ? "" : "s");
    for (uint32_t k = 0; k < nr; k++)
        if (!isfinite(p->rargs[k]))
            return BAD("%s: %s %s: real argument %u is not finite", where, tn, id, k + 1);
    /* geometric sanity that Radiance treats as errors */
    if (p->type == HD_T_RING) {
        double a = p->rargs[6], b = p->rargs[7];
        if (a < 0 || b < 0) return BAD("%s: ring %s: negative radius", where, id);
        if (a == b) return BAD("%s: ring %s: radii are equal (zero area)", where, id);
        if (p->rargs[3] == 0 && p->rargs[4] == 0 && p->rargs[5] == 0)
            return BAD("%s: ring %s: zero normal", where, id);
    } else if (p->type == HD_T_CONE || p->type == HD_T_CUP) {
        if (p->rargs[6] == 0 && p->rargs[7] == 0)
            return BAD("%s: %s %s: both radii are zero", where, tn, id);
    } else if (p->type == HD_T_CYLINDER || p->type == HD_T_TUBE) {
        if (p->rargs[6] == 0) return BAD("%s: %s %s: zero radius", where, tn, id);
    } else if (p->type == HD_T_SPHERE || p->type == HD_T_BUBBLE) {
        if (p->rargs[3] == 0) return BAD("%s: %s %s: zero radius", where, tn, id);
    }
    if (p->type == HD_T_CONE || p->type == HD_T_CUP || p->type == HD_T_CYLINDER || p->type == HD_T_TUBE) {
        if (p->rargs[0] == p->rargs[3] && p->rargs[1] == p->rargs[4] && p->rargs[2] == p->rargs[5])
            return BAD("%s: %s %s: axis end points coincide", where, tn, id);
    }
    return HD_OK;
}

/* ---- text output ---- */
static int needs_quotes(const char *w)
{
    if (!*w) return 1;
    for (; *w; w++)
        if (*w == ' ' || *w == '\t' || *w == '\n' || *w == '"' || *w == '\'') return 1;
    return 0;
}

static void put_word(FILE *fp, const char *w)
{
    if (!needs_quotes(w)) { fputs(w, fp); return; }
    char q = strchr(w, '"') ? '\'' : '"';
    fputc(q, fp); fputs(w, fp); fputc(q, fp);
}

void hd_prim_write(FILE *fp, const hd_prim *p)
{
    put_word(fp, p->modname ? p->modname : "void");
    fprintf(fp, " %s ", hd_type_name(p->type));
    put_word(fp, p->id);
    if (p->type == HD_T_ALIAS) {
        fputc(' ', fp);
        put_word(fp, p->nsargs ? p->sargs[0] : "void");
        fputs("\n\n", fp);
        return;
    }
    fprintf(fp, "\n%u", p->nsargs);
    for (uint32_t k = 0; k < p->nsargs; k++) { fputc(' ', fp); put_word(fp, p->sargs[k]); }
    fprintf(fp, "\n%u", p->niargs);
    for (uint32_t k = 0; k < p->niargs; k++) fprintf(fp, " %ld", p->iargs[k]);
    fprintf(fp, "\n%u", p->nrargs);
    for (uint32_t k = 0; k < p->nrargs; k++) {
        if (k % 3 == 0) fputc('\n', fp);
        fprintf(fp, " %18.12g", p->rargs[k]);
    }
    fputs("\n\n", fp);
}

/* ---- material parameters ---- */
hd_status hd_scene_write_rad(FILE *fp, const hd_scene *s)
{
    for (size_t i = 0; i < s->nprims; i++) hd_prim_write(fp, &s->prims[i]);
    return ferror(fp) ? hd_fail(HD_ERR_IO, "write error") : HD_OK;
}

/* heliodon — scene cache: binary serialisation of a parsed scene (written
 * by oconv, read by every program that takes a scene).  Layout (all
 * integers little-endian, reals IEEE-754 binary64 little-endian; "str" =
 * u32 byte length + bytes, no NUL) — see docs/design/scene.md:
 *
 *   Radiance header: "#?RADIANCE", command line(s), SOFTWARE=,
 *                    FORMAT=heliodon_scene, empty line
 *   "HDSCENE\n"  u32 version (1)
 *   u32 ntypes, ntypes x str      type names (index = stored type code)
 *   u32 nfiles,  nfiles x {str name, i32 parent, u32 parent_line}
 *   u32 nskip,   nskip x {str command, u32 file, u32 line, u64 before}
 *   u64 nprims,  nprims x {u16 type, i32 modifier, i32 alias_of, u32 file,
 *                u32 line, str modname, str id, u32 ns, ns x str,
 *                u32 ni, ni x i64, u32 nr, nr x f64}
 *   "HDSCEND\n"  u64 nprims (again, as a check)
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "heliodon/scene.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "scene_priv.h"

#define CACHE_FORMAT "heliodon_scene"
#define CACHE_MAGIC "HDSCENE\n"
#define CACHE_END "HDSCEND\n"
#define CACHE_VERSION 1u
#define MAXSTR (1u << 20)

/* ---- writing ---- */
static void put_u16(FILE *fp, uint16_t v) { fputc(v & 255, fp); fputc(v >> 8, fp); }
static void put_u32(FILE *fp, uint32_t v) { for (int i = 0; i < 4; i++) fputc((v >> (8 * i)) & 255, fp); }
static void put_u64(FILE *fp, uint64_t v) { for (int i = 0; i < 8; i++) fputc((int)((v >> (8 * i)) & 255), fp); }
static void put_f64(FILE *fp, double d) { uint64_t u; memcpy(&u, &d, 8); put_u64(fp, u); }
static void put_str(FILE *fp, const char *s)
{
    size_t n = strlen(s);
    put_u32(fp, (uint32_t)n);
    fwrite(s, 1, n, fp);
}

hd_status hd_scene_cache_write_body(const hd_scene *s, FILE *fp)
{
    fwrite(CACHE_MAGIC, 1, 8, fp);
    put_u32(fp, CACHE_VERSION);
    put_u32(fp, HD_T_COUNT);
    for (int t = 0; t < HD_T_COUNT; t++) put_str(fp, hd_type_name((hd_prim_type)t));
    put_u32(fp, (uint32_t)s->nfiles);
    for (size_t i = 0; i < s->nfiles; i++) {
        put_str(fp, s->files[i].name);
        put_u32(fp, (uint32_t)s->files[i].parent);
        put_u32(fp, s->files[i].parent_line);
    }
    put_u32(fp, (uint32_t)s->nskipped);
    for (size_t i = 0; i < s->nskipped; i++) {
        put_str(fp, s->skipped[i].command);
        put_u32(fp, s->skipped[i].file);
        put_u32(fp, s->skipped[i].line);
        put_u64(fp, s->skipped[i].before);
    }
    put_u64(fp, s->nprims);
    for (size_t i = 0; i < s->nprims; i++) {
        const hd_prim *p = &s->prims[i];
        put_u16(fp, (uint16_t)p->type);
        put_u32(fp, (uint32_t)p->modifier);
        put_u32(fp, (uint32_t)p->alias_of);
        put_u32(fp, p->file);
        put_u32(fp, p->line);
        put_str(fp, p->modname);
        put_str(fp, p->id);
        put_u32(fp, p->nsargs);
        for (uint32_t k = 0; k < p->nsargs; k++) put_str(fp, p->sargs[k]);
        put_u32(fp, p->niargs);
        for (uint32_t k = 0; k < p->niargs; k++) put_u64(fp, (uint64_t)(int64_t)p->iargs[k]);
        put_u32(fp, p->nrargs);
        for (uint32_t k = 0; k < p->nrargs; k++) put_f64(fp, p->rargs[k]);
    }
    fwrite(CACHE_END, 1, 8, fp);
    put_u64(fp, s->nprims);
    return ferror(fp) ? hd_fail(HD_ERR_IO, "error writing the scene cache") : HD_OK;
}

hd_status hd_scene_write_cache(const hd_scene *s, const char *path, int argc, char **argv)
{
    hd_ofile *of;
    hd_status st = hd_ofile_open(&of, path);
    if (st) return st;
    FILE *fp = hd_ofile_fp(of);
    hd_header h;
    hd_header_init(&h);
    if (argc > 0) st = hd_header_add_command(&h, argc, argv);
    if (!st) st = hd_header_add_software(&h);
    if (!st) st = hd_header_put(fp, &h, NULL, CACHE_FORMAT, NULL);
    hd_header_free(&h);
    if (st) { hd_ofile_abort(of); return st; }
    if ((st = hd_scene_cache_write_body(s, fp))) { hd_ofile_abort(of); return st; }
    return hd_ofile_commit(of);
}

/* ---- reading (from memory: the body is read whole) ---- */
typedef struct rd { const unsigned char *p, *end, *base; long base_off; const char *name; } rd;

static long rd_off(const rd *r) { return r->base_off + (long)(r->p - r->base); }

static hd_status trunc_err(rd *r, const char *what)
{
    return hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: unexpected end of data reading %s",
                   r->name, rd_off(r), what);
}

static hd_status get_bytes(rd *r, void *b, size_t n, const char *what)
{
    if ((size_t)(r->end - r->p) < n) return trunc_err(r, what);
    memcpy(b, r->p, n);
    r->p += n;
    return HD_OK;
}

static hd_status get_u16(rd *r, uint16_t *v, const char *what)
{
    unsigned char b[2] = {0, 0};
    hd_status st = get_bytes(r, b, 2, what);
    *v = (uint16_t)(b[0] | b[1] << 8);
    return st;
}

static hd_status get_u32(rd *r, uint32_t *v, const char *what)
{
    unsigned char b[4] = {0, 0, 0, 0};
    hd_status st = get_bytes(r, b, 4, what);
    *v = (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
    return st;
}

static hd_status get_u64(rd *r, uint64_t *v, const char *what)
{
    unsigned char b[8] = {0};
    hd_status st = get_bytes(r, b, 8, what);
    *v = 0;
    for (int i = 7; i >= 0; i--) *v = *v << 8 | b[i];
    return st;
}

/* Read a string into a malloc'd buffer. */
static hd_status get_str(rd *r, char **out, const char *what)
{
    uint32_t n;
    hd_status st = get_u32(r, &n, what);
    if (st) return st;
    if (n > MAXSTR)
        return hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: %s of %u bytes is too long (corrupt cache?)",
                       r->name, rd_off(r), what, n);
    char *s = hd_malloc((size_t)n + 1);
    if (!s) return HD_ERR_NOMEM;
    if ((st = get_bytes(r, s, n, what))) { free(s); return st; }
    s[n] = 0;
    if (strlen(s) != n) {
        free(s);
        return hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: NUL byte inside %s", r->name, rd_off(r), what);
    }
    *out = s;
    return HD_OK;
}

/* Read the Radiance header; returns 1 if it is a scene cache (and the
 * header text in *text if text != NULL), 2 if it is a Radiance octree,
 * 0 if neither. */
static int read_header(FILE *fp, char **text)
{
    char line[4096];
    size_t len = 0, cap = 0;
    char *buf = NULL;
    int is = 0;
    if (!fgets(line, sizeof line, fp) || strncmp(line, "#?RADIANCE", 10)) return 0;
    while (fgets(line, sizeof line, fp)) {
        if (line[0] == '\n') break;
        if (!strncmp(line, "FORMAT=", 7)) {
            char *v = line + 7;
            while (*v == ' ' || *v == '\t') v++;
            size_t n = strlen(CACHE_FORMAT);
            is = !strncmp(v, CACHE_FORMAT, n) && (v[n] == '\n' || v[n] == ' ' || v[n] == 0);
            if (!is && !strncmp(v, "Radiance_octree", 15)) is = 2;
            continue;
        }
        if (text) {
            size_t n = strlen(line);
            if (len + n + 1 > cap) {
                size_t nc = (len + n + 1) * 2;
                char *nb = realloc(buf, nc);
                if (!nb) break;
                buf = nb; cap = nc;
            }
            memcpy(buf + len, line, n + 1);
            len += n;
        }
    }
    if (text && is) *text = buf;
    else free(buf);
    return is;
}

/* Offset of the scene cache that heliodon's oconv appends to a Radiance
 * octree (16-byte trailer "HDSCACHE" + u64 offset), or -1. */
static long embedded_cache_offset(FILE *fp)
{
    unsigned char b[16];
    long here = ftell(fp);
    if (here < 0 || fseek(fp, -16, SEEK_END)) return -1;
    long end = ftell(fp);
    long off = -1;
    if (fread(b, 1, 16, fp) == 16 && !memcmp(b, "HDSCACHE", 8)) {
        unsigned long long v = 0;
        for (int i = 7; i >= 0; i--) v = v << 8 | b[8 + i];
        if (v >= (unsigned long long)here && v < (unsigned long long)end) off = (long)v;
    }
    fseek(fp, here, SEEK_SET);
    return off;
}

int hd_scene_is_cache(const char *path)
{
    FILE *fp = fopen(path, "rb");
    if (!fp) {
        hd_fail(HD_ERR_IO, "cannot open scene file '%s': %s", path, strerror(errno));
        return -1;
    }
    int is = read_header(fp, NULL);
    if (is == 2) is = embedded_cache_offset(fp) >= 0;
    fclose(fp);
    return is == 1;
}

/* Radiance octree (oconv output): read the scene file names it lists and
 * load them as Radiance text.  Frozen octrees (no names) are refused. */
static hd_status read_nul_string(FILE *fp, char *buf, size_t cap, const char *path, const char *what)
{
    size_t n = 0;
    int c;
    while ((c = getc(fp)) != EOF && c != 0) {
        if (n + 1 >= cap)
            return hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: %s too long", path, ftell(fp), what);
        buf[n++] = (char)c;
    }
    if (c == EOF)
        return hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: unexpected end of data reading %s", path, ftell(fp), what);
    buf[n] = 0;
    return HD_OK;
}

/* ---- frozen Radiance octrees: skip the tree, decode the scene data and
 * load it as Radiance text (so modifiers and aliases resolve as usual) ---- */
static hd_status oct_int(FILE *fp, int siz, long *v, const char *path, const char *what)
{
    long r = 0;
    *v = 0;
    for (int i = 0; i < siz; i++) {
        int c = getc(fp);
        if (c == EOF)
            return hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: unexpected end of data reading %s",
                           path, ftell(fp), what);
        if (i == 0 && (c & 0x80)) r = -1;
        r = (long)((unsigned long)r << 8) | c;
    }
    *v = r;
    return HD_OK;
}

static hd_status oct_skip_tree(FILE *fp, int objsize, const char *path, int depth)
{
    int c = getc(fp);
    long n;
    hd_status st;
    if (depth > 64) return hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: octree deeper than 64 levels", path, ftell(fp));
    switch (c) {
    case 0: return HD_OK;
    case 1:
        if ((st = oct_int(fp, objsize, &n, path, "object set size"))) return st;
        if (n < 0 || n > 511) return hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: bad object set size %ld", path, ftell(fp), n);
        if (fseek(fp, n * objsize, SEEK_CUR)) return hd_fail(HD_ERR_IO, "%s: seek error", path);
        return HD_OK;
    case 2:
        for (int i = 0; i < 8; i++)
            if ((st = oct_skip_tree(fp, objsize, path, depth + 1))) return st;
        return HD_OK;
    case EOF: return hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: truncated octree", path, ftell(fp));
    default: return hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: damaged octree (node byte %d)", path, ftell(fp) - 1, c);
    }
}

static hd_status load_frozen(hd_scene *s, FILE *fp, const char *path, int objsize, const hd_scene_opts *opts)
{
    long nobj = 0;
    char buf[4096];
    hd_status st = oct_int(fp, objsize, &nobj, path, "object count");
    if (!st && (nobj < 0 || nobj > INT32_MAX / 2)) st = hd_fail(HD_ERR_FORMAT, "%s: absurd object count %ld", path, nobj);
    if (!st) st = oct_skip_tree(fp, objsize, path, 0);
    int types[256];
    int ntypes = 0;
    for (;;) {
        if (st || (st = read_nul_string(fp, buf, sizeof buf, path, "type name")) || !buf[0]) break;
        if (ntypes == 256) { st = hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: too many type names", path, ftell(fp)); break; }
        types[ntypes++] = hd_type_from_name(buf);
    }
    if (st) return st;
    char **ids = hd_malloc_array((size_t)nobj + 1, sizeof *ids);
    if (!ids) return HD_ERR_NOMEM;
    char *text = NULL;
    size_t textlen = 0;
    FILE *ms = open_memstream(&text, &textlen);
    if (!ms) { free(ids); return hd_fail(HD_ERR_NOMEM, "%s: cannot buffer the frozen scene", path); }
    long n = 0;
    char **sv = NULL;
    double *rv = NULL;
    for (;;) {
        long t = 0, mod = 0, ns = 0, nr = 0;
        if ((st = oct_int(fp, 1, &t, path, "object type"))) break;
        if (t == -1) break;
        if (t < 0 || t >= ntypes || types[t] < 0) {
            st = hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: object %ld: unknown type code %ld", path, ftell(fp), n, t);
            break;
        }
        if (n >= nobj) { st = hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: more objects than the %ld announced", path, ftell(fp), nobj); break; }
        if ((st = oct_int(fp, objsize, &mod, path, "modifier"))) break;
        if (mod < -1 || mod >= n) { st = hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: object %ld: bad modifier %ld", path, ftell(fp), n, mod); break; }
        if ((st = read_nul_string(fp, buf, sizeof buf, path, "object name"))) break;
        ids[n] = hd_strdup(buf);
        if (!ids[n]) { st = HD_ERR_NOMEM; break; }
        n++;
        hd_prim p;
        memset(&p, 0, sizeof p);
        p.type = (hd_prim_type)types[t];
        p.id = ids[n - 1];
        p.modname = mod < 0 ? "void" : ids[mod];
        if ((st = oct_int(fp, 2, &ns, path, "string count"))) break;
        if (ns < 0 || ns > 10000) { st = hd_fail(HD_ERR_FORMAT, "%s: byte offset %ld: bad string count %ld", path, ftell(fp), ns); break; }
        char **x = hd_realloc_array(sv, (size_t)ns + 1, sizeof *sv);
        if (!x) { st = HD_ERR_NOMEM; break; }
        sv = x;
        long nalloc = 0;
        while (nalloc < ns) {
            if ((st = read_nul_string(fp, buf, sizeof buf, path, "string argument"))) break;
            if (!(sv[nalloc] = hd_strdup(buf))) { st = HD_ERR_NOMEM; break; }
            nalloc++;
        }
        if (!st && !(st = oct_int(fp, 2, &nr, path, "real count")) && nr < 0)
            nr += 65536;                      /* counts are unsigned 16-bit */
        if (!st) {
            double *y = hd_realloc_array(rv, (size_t)nr + 1, sizeof *rv);
            if (!y) st = HD_ERR_NOMEM; else rv = y;
        }
        for (long j = 0; !st && j < nr; j++) {
            long m = 0, e = 0;
            if (!(st = oct_int(fp, 4, &m, path, "real argument")) && !(st = oct_int(fp, 1, &e, path, "real exponent")))
                rv[j] = hd_portable_flt(m, e);
        }
        if (!st) {
            if (p.type == HD_T_ALIAS) {
                /* no string: the modifier is the aliased object (inherited) */
                if (ns == 0) {
                    p.modname = "inherit";
                    if ((sv[0] = hd_strdup(mod < 0 ? "void" : ids[mod]))) nalloc = 1;
                    else st = HD_ERR_NOMEM;
                }
                p.nsargs = 1;
            } else {
                p.nsargs = (uint32_t)ns;
            }
            p.sargs = sv;
            p.nrargs = (uint32_t)nr; p.rargs = rv;
            if (!st) hd_prim_write(ms, &p);
        }
        for (long j = 0; j < nalloc; j++) free(sv[j]);
        if (st) break;
    }
    free(sv); free(rv);
    if (fclose(ms) && !st) st = hd_fail(HD_ERR_NOMEM, "%s: cannot buffer the frozen scene", path);
    if (!st && n != nobj) st = hd_fail(HD_ERR_FORMAT, "%s: %ld objects in the scene data, %ld announced", path, n, nobj);
    if (!st) st = hd_scene_load_string(s, text, path, opts);
    for (long j = 0; j < n; j++) free(ids[j]);
    free(ids);
    free(text);
    return st;
}

hd_status hd_scene_load_radiance_octree(hd_scene *s, const char *path, const hd_scene_opts *opts, int *is_octree)
{
    *is_octree = 0;
    FILE *fp = fopen(path, "rb");
    if (!fp) return hd_fail(HD_ERR_IO, "cannot open scene file '%s': %s", path, strerror(errno));
    if (read_header(fp, NULL) != 2) { fclose(fp); return HD_OK; }
    *is_octree = 1;
    unsigned char m[2];
    char buf[4096];
    hd_status st = HD_OK;
    if (fread(m, 1, 2, fp) != 2) st = hd_fail(HD_ERR_FORMAT, "%s: truncated Radiance octree", path);
    int magic = m[0] << 8 | m[1];
    if (!st && magic != 285 && magic != 287 && magic != 291)
        st = hd_fail(HD_ERR_FORMAT, "%s: bad Radiance octree magic number %d", path, magic);
    for (int k = 0; k < 4 && !st; k++) st = read_nul_string(fp, buf, sizeof buf, path, "bounding cube");
    char **names = NULL;
    size_t nn = 0;
    while (!st) {
        st = read_nul_string(fp, buf, sizeof buf, path, "scene file name");
        if (st || !buf[0]) break;
        char **x = hd_realloc_array(names, nn + 1, sizeof *names);
        if (!x) { st = HD_ERR_NOMEM; break; }
        names = x;
        if (!(names[nn] = hd_strdup(buf))) { st = HD_ERR_NOMEM; break; }
        nn++;
    }
    if (!st && nn == 0) {
        /* frozen: the scene data follows the tree */
        st = load_frozen(s, fp, path, magic - 283, opts);
        fclose(fp);
        if (st) return hd_fail_context(st, "%s (frozen Radiance octree)", path);
        return HD_OK;
    }
    fclose(fp);
    /* names are relative to the directory oconv ran in: try the current
     * directory, then the octree's own directory */
    const char *slash = strrchr(path, '/');
    for (size_t k = 0; k < nn && !st; k++) {
        char full[8192];
        const char *use = names[k];
        if (names[k][0] != '/' && slash && access(names[k], R_OK) != 0) {
            snprintf(full, sizeof full, "%.*s/%s", (int)(slash - path), path, names[k]);
            use = full;
        }
        st = hd_scene_load_rad(s, use, opts);
    }
    for (size_t k = 0; k < nn; k++) free(names[k]);
    free(names);
    if (st) return hd_fail_context(st, "%s (Radiance octree)", path);
    return HD_OK;
}

static hd_status read_body(hd_scene *s, rd r, const char *name);

hd_status hd_scene_cache_read_body(hd_scene *s, FILE *fp, const char *name)
{
    long off = ftell(fp);
    size_t len = 0, cap = 1 << 16;
    unsigned char *buf = hd_malloc(cap);
    if (!buf) return HD_ERR_NOMEM;
    for (;;) {
        size_t got = fread(buf + len, 1, cap - len, fp);
        len += got;
        if (len < cap) break;
        unsigned char *nb = hd_realloc_array(buf, cap, 2);
        if (!nb) { free(buf); return HD_ERR_NOMEM; }
        buf = nb;
        cap *= 2;
    }
    if (ferror(fp)) { free(buf); return hd_fail(HD_ERR_IO, "%s: read error", name); }
    rd r = {buf, buf + len, buf, off, name};
    hd_status st = read_body(s, r, name);
    free(buf);
    return st;
}

static hd_status read_body(hd_scene *s, rd r, const char *name)
{
    char magic[8];
    uint32_t ver, ntypes, nfiles, nskip;
    uint64_t nprims;
    hd_status st;
    if ((st = get_bytes(&r, magic, 8, "magic"))) return st;
    if (memcmp(magic, CACHE_MAGIC, 8))
        return hd_fail(HD_ERR_FORMAT, "%s: not a heliodon scene cache (bad magic)", name);
    if ((st = get_u32(&r, &ver, "version"))) return st;
    if (ver != CACHE_VERSION)
        return hd_fail(HD_ERR_UNSUPPORTED, "%s: scene cache version %u, this program reads version %u "
                       "(re-run oconv)", name, ver, CACHE_VERSION);
    if ((st = get_u32(&r, &ntypes, "type count"))) return st;
    if (ntypes > 1000) return hd_fail(HD_ERR_FORMAT, "%s: absurd type count %u", name, ntypes);
    int map[1000];
    for (uint32_t t = 0; t < ntypes; t++) {
        char *tn;
        if ((st = get_str(&r, &tn, "type name"))) return st;
        map[t] = hd_type_from_name(tn);
        free(tn);
    }
    size_t file0 = s->nfiles, prim0 = s->nprims;
    if ((st = get_u32(&r, &nfiles, "file count"))) return st;
    for (uint32_t i = 0; i < nfiles; i++) {
        char *fname;
        uint32_t parent, pline, idx;
        if ((st = get_str(&r, &fname, "file name"))) return st;
        if ((st = get_u32(&r, &parent, "file parent")) || (st = get_u32(&r, &pline, "file parent line"))) {
            free(fname); return st;
        }
        int32_t par = (int32_t)parent;
        if (par >= (int32_t)i || par < -1) { free(fname); return hd_fail(HD_ERR_FORMAT, "%s: bad file parent", name); }
        st = hd_scene_add_file(s, fname, par < 0 ? -1 : par + (int32_t)file0, pline, &idx);
        free(fname);
        if (st) return st;
    }
    if ((st = get_u32(&r, &nskip, "skipped command count"))) return st;
    for (uint32_t i = 0; i < nskip; i++) {
        char *cmd;
        uint32_t f, l;
        uint64_t before;
        if ((st = get_str(&r, &cmd, "skipped command"))) return st;
        if ((st = get_u32(&r, &f, "skipped file")) || (st = get_u32(&r, &l, "skipped line")) ||
            (st = get_u64(&r, &before, "skipped position"))) { free(cmd); return st; }
        if (f >= nfiles || before > (uint64_t)INT32_MAX) {
            free(cmd);
            return hd_fail(HD_ERR_FORMAT, "%s: bad file index or position in skipped command", name);
        }
        st = hd_scene_add_skipped(s, cmd, f + (uint32_t)file0, l);
        free(cmd);
        if (st) return st;
        s->skipped[s->nskipped - 1].before = prim0 + (size_t)before;
    }
    if ((st = get_u64(&r, &nprims, "primitive count"))) return st;
    if (nprims > INT32_MAX / 2) return hd_fail(HD_ERR_FORMAT, "%s: absurd primitive count %llu", name,
                                               (unsigned long long)nprims);
    char **sv = NULL;
    long *iv = NULL;
    double *rv = NULL;
    size_t capsv = 0, capiv = 0, caprv = 0;
    char *modname = NULL, *id = NULL;
    uint32_t nsv = 0;
    for (uint64_t i = 0; i < nprims && !st; i++) {
        hd_prim p;
        uint16_t type;
        uint32_t mod, al, f, l, n;
        memset(&p, 0, sizeof p);
        if ((st = get_u16(&r, &type, "primitive type")) || (st = get_u32(&r, &mod, "modifier")) ||
            (st = get_u32(&r, &al, "alias")) || (st = get_u32(&r, &f, "file index")) ||
            (st = get_u32(&r, &l, "line")))
            break;
        if (type >= ntypes || map[type] < 0) { st = hd_fail(HD_ERR_FORMAT, "%s: primitive %llu: unknown type code %u", name, (unsigned long long)i, type); break; }
        int32_t m = (int32_t)mod, a = (int32_t)al;
        if (m < -1 || (int64_t)m >= (int64_t)i || a < -1 || (int64_t)a >= (int64_t)i || f >= nfiles) {
            st = hd_fail(HD_ERR_FORMAT, "%s: primitive %llu: bad modifier, alias or file index", name,
                         (unsigned long long)i);
            break;
        }
        p.type = (hd_prim_type)map[type];
        p.modifier = m < 0 ? -1 : m + (int32_t)prim0;
        p.alias_of = a < 0 ? -1 : a + (int32_t)prim0;
        p.file = f + (uint32_t)file0;
        p.line = l;
        if ((st = get_str(&r, &modname, "modifier name")) || (st = get_str(&r, &id, "identifier"))) break;
        p.modname = modname; p.id = id;
        if ((st = get_u32(&r, &n, "string count"))) break;
        if (n > MAXSTR) { st = hd_fail(HD_ERR_FORMAT, "%s: absurd string count %u", name, n); break; }
        if ((st = HD_GROW(sv, n, capsv, 16))) break;
        for (nsv = 0; nsv < n; nsv++)
            if ((st = get_str(&r, &sv[nsv], "string argument"))) break;
        if (st) break;
        p.nsargs = n; p.sargs = sv;
        if ((st = get_u32(&r, &n, "integer count"))) break;
        if (n > MAXSTR) { st = hd_fail(HD_ERR_FORMAT, "%s: absurd integer count %u", name, n); break; }
        if ((st = HD_GROW(iv, n, capiv, 16))) break;
        for (uint32_t k = 0; k < n && !st; k++) {
            uint64_t u;
            st = get_u64(&r, &u, "integer argument");
            iv[k] = (long)(int64_t)u;
        }
        if (st) break;
        p.niargs = n; p.iargs = iv;
        if ((st = get_u32(&r, &n, "real count"))) break;
        if (n > (1u << 28)) { st = hd_fail(HD_ERR_FORMAT, "%s: absurd real count %u", name, n); break; }
        if ((st = HD_GROW(rv, n, caprv, 16))) break;
        for (uint32_t k = 0; k < n && !st; k++) {
            uint64_t u;
            st = get_u64(&r, &u, "real argument");
            memcpy(&rv[k], &u, 8);
        }
        if (st) break;
        p.nrargs = n; p.rargs = rv;
        st = hd_scene_add(s, &p);
        for (uint32_t k = 0; k < nsv; k++) free(sv[k]);
        nsv = 0;
        free(modname); free(id);
        modname = id = NULL;
    }
    for (uint32_t k = 0; k < nsv; k++) free(sv[k]);
    free(modname); free(id);
    free(sv); free(iv); free(rv);
    if (st) return st;
    uint64_t check;
    if ((st = get_bytes(&r, magic, 8, "end marker"))) return st;
    if ((st = get_u64(&r, &check, "final count"))) return st;
    if (memcmp(magic, CACHE_END, 8) || check != nprims)
        return hd_fail(HD_ERR_FORMAT, "%s: bad end marker (corrupt or truncated cache)", name);
    return HD_OK;
}

hd_status hd_scene_read_cache(hd_scene *s, const char *path)
{
    FILE *fp = fopen(path, "rb");
    if (!fp) return hd_fail(HD_ERR_IO, "cannot open scene cache '%s': %s", path, strerror(errno));
    char *text = NULL;
    int is = read_header(fp, &text);
    long off = is == 2 ? embedded_cache_offset(fp) : 0;
    if (!is || off < 0 || (is == 2 && fseek(fp, off, SEEK_SET))) {
        fclose(fp);
        free(text);
        return hd_fail(HD_ERR_FORMAT, "%s: not a heliodon scene cache (no FORMAT=" CACHE_FORMAT
                       " header, and not an octree written by heliodon's oconv)", path);
    }
    if (text && !s->cmdline) s->cmdline = text;
    else free(text);
    hd_status st = hd_scene_cache_read_body(s, fp, path);
    fclose(fp);
    return st;
}

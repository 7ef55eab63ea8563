/* heliodon — in-memory scene model for Radiance scene descriptions (.rad).
 *
 * A scene is an ordered array of primitives, exactly as read: every
 * surface, material, pattern, texture, mixture and alias keeps its type,
 * identifier, modifier, arguments and the place (file:line) it came from.
 * Nothing is dropped: types heliodon cannot render are kept so that files
 * load, and the renderer reports them (hd_prim_where gives the location).
 *
 * Modifier semantics follow Radiance: a primitive's modifier must be
 * defined before it (or be "void"); a later definition with the same name
 * shadows the earlier one only for primitives read after it.  The parser
 * resolves every modifier to the index of the definition in force when the
 * primitive was read (hd_prim.modifier, -1 = void).
 *
 * Aliases ("newmod alias newid oldid") are kept as primitives of type
 * HD_T_ALIAS: .alias_of is the index of oldid's definition in force, and
 * .modifier is newmod (or, for "inherit", oldid's own modifier).  Their
 * type and arguments are those of hd_scene_unalias(s, i).
 *
 * This is a plain data model: no acceleration structure here. */
#ifndef HELIODON_SCENE_H
#define HELIODON_SCENE_H

#include <stdint.h>
#include <stdio.h>
#include "common.h"
#include "vec.h"

/* Every primitive type Radiance 6.1 knows (so that any scene loads). */
typedef enum hd_prim_type {
    /* surfaces */
    HD_T_POLYGON = 0, HD_T_SPHERE, HD_T_BUBBLE, HD_T_CONE, HD_T_CUP,
    HD_T_CYLINDER, HD_T_TUBE, HD_T_RING, HD_T_SOURCE,
    HD_T_INSTANCE, HD_T_MESH,
    /* materials */
    HD_T_LIGHT, HD_T_ILLUM, HD_T_GLOW, HD_T_SPOTLIGHT,
    HD_T_PLASTIC, HD_T_METAL, HD_T_TRANS, HD_T_PLASTIC2, HD_T_METAL2, HD_T_TRANS2,
    HD_T_MIRROR, HD_T_DIELECTRIC, HD_T_INTERFACE, HD_T_GLASS,
    HD_T_PLASFUNC, HD_T_METFUNC, HD_T_TRANSFUNC, HD_T_BRTDFUNC,
    HD_T_PLASDATA, HD_T_METDATA, HD_T_TRANSDATA,
    HD_T_BSDF, HD_T_ABSDF, HD_T_ASHIK2, HD_T_WGMDFUNC,
    HD_T_ANTIMATTER, HD_T_MIST, HD_T_PRISM1, HD_T_PRISM2,
    /* textures */
    HD_T_TEXFUNC, HD_T_TEXDATA,
    /* patterns */
    HD_T_COLORFUNC, HD_T_BRIGHTFUNC, HD_T_COLORDATA, HD_T_BRIGHTDATA,
    HD_T_COLORPICT, HD_T_COLORTEXT, HD_T_BRIGHTTEXT,
    HD_T_SPECTRUM, HD_T_SPECFILE, HD_T_SPECFUNC, HD_T_SPECDATA, HD_T_SPECPICT,
    /* mixtures */
    HD_T_MIXFUNC, HD_T_MIXDATA, HD_T_MIXPICT, HD_T_MIXTEXT,
    /* alias */
    HD_T_ALIAS,
    HD_T_COUNT
} hd_prim_type;

typedef enum hd_type_class {
    HD_CLASS_SURFACE, HD_CLASS_MATERIAL, HD_CLASS_TEXTURE, HD_CLASS_PATTERN,
    HD_CLASS_MIXTURE, HD_CLASS_ALIAS
} hd_type_class;

/* Radiance name of a type ("polygon", "BRTDfunc", ...). */
const char *hd_type_name(hd_prim_type t);
/* Type from its exact (case-sensitive) Radiance name; -1 if unknown. */
int hd_type_from_name(const char *name);
hd_type_class hd_type_class_of(hd_prim_type t);
/* Whether primitives of this type can be used as modifiers (all but surfaces). */
int hd_type_is_modifier(hd_prim_type t);
/* Surfaces and materials that take a function file / transform strings
 * (xform appends its transform to their string arguments). */
int hd_type_has_transform(hd_prim_type t);

typedef struct hd_prim {
    hd_prim_type type;
    int32_t modifier;      /* index of the modifier primitive, -1 = void */
    int32_t alias_of;      /* HD_T_ALIAS: index of the aliased primitive; else -1 */
    uint32_t file;         /* index into hd_scene.files */
    uint32_t line;         /* 1-based line in that file (or command output) */
    const char *modname;   /* modifier word as written ("void", "wall_mat") */
    const char *id;        /* identifier */
    uint32_t nsargs, niargs, nrargs;
    char **sargs;          /* nsargs strings (alias: sargs[0] = oldid) */
    long *iargs;           /* niargs integers (always 0 in Radiance files) */
    double *rargs;         /* nrargs reals */
} hd_prim;

/* A source of primitives: a file, standard input, or the output of an
 * in-line command.  parent/parent_line locate the command line that
 * produced it (-1 for top-level inputs). */
typedef struct hd_scene_file {
    char *name;            /* path, "-" for stdin, or "!command" */
    int32_t parent;
    uint32_t parent_line;
} hd_scene_file;

/* An in-line command that was not run (see hd_scene_opts.skip_missing). */
typedef struct hd_skipped_cmd {
    char *command;         /* command text without the '!' */
    uint32_t file, line;   /* where it appeared */
    size_t before;         /* number of primitives read before it */
} hd_skipped_cmd;

typedef struct hd_scene_names hd_scene_names;   /* private name table */

typedef struct hd_scene {
    hd_prim *prims;
    size_t nprims, capprims;
    hd_scene_file *files;
    size_t nfiles, capfiles;
    hd_skipped_cmd *skipped;
    size_t nskipped, capskipped;
    char *cmdline;         /* command line recorded in a scene cache (or NULL) */
    hd_scene_names *names; /* modifier name -> latest definition */
    void *arena;           /* private string/argument storage */
} hd_scene;

#define HD_SKIP_ENV "HELIODON_SKIP_MISSING"

typedef struct hd_scene_opts {
    /* Do not resolve modifiers or validate argument counts (xform reads
     * primitives whose modifiers are defined elsewhere): .modifier stays -1,
     * .modname keeps the word, aliases keep alias_of = -1. */
    int raw;
    /* In-line commands whose program cannot be found on PATH are replaced
     * by nothing and recorded in hd_scene.skipped instead of failing.  The
     * setting reaches nested heliodon xform runs through the environment
     * variable HELIODON_SKIP_MISSING; they report what they skipped as
     * "#@heliodon-skipped COMMAND" comment lines, which the parser records
     * in hd_scene.skipped too (at the comment's location). */
    int skip_missing;
    /* Do not run in-line commands at all: record every one in skipped. */
    int no_commands;
    /* Run in-line commands in this directory instead of the current one
     * (xform runs the commands of each file in that file's directory). */
    const char *command_dir;
} hd_scene_opts;

void hd_scene_init(hd_scene *s);
void hd_scene_free(hd_scene *s);

/* Read Radiance scene text from a file ("-" = stdin; "!cmd" = command
 * output) and append its primitives (opts may be NULL).  Errors name
 * file:line and what was expected; on error the scene keeps the
 * primitives read before the error. */
hd_status hd_scene_load_rad(hd_scene *s, const char *path, const hd_scene_opts *opts);
/* Same from a string in memory; name is used in messages. */
hd_status hd_scene_load_string(hd_scene *s, const char *text, const char *name,
                               const hd_scene_opts *opts);
/* Load several inputs in order: each is a heliodon scene cache (written
 * by oconv, recognised by its header), a Radiance octree that lists its
 * scene files (they are loaded instead; frozen octrees are refused), or
 * Radiance scene text. */
hd_status hd_scene_load_files(hd_scene *s, int n, char *const *paths, const hd_scene_opts *opts);

/* ---- scene cache (oconv output; format in docs/design/scene.md) ----
 * A versioned binary serialisation of a parsed scene behind a Radiance
 * header (FORMAT=heliodon_scene) that carries the producing command line.
 * Writing goes through hd_ofile (temporary name + rename). */
hd_status hd_scene_write_cache(const hd_scene *s, const char *path, int argc, char **argv);
/* Append the cached scene's primitives (indices shifted) to s. */
hd_status hd_scene_read_cache(hd_scene *s, const char *path);
/* 1 if path is a heliodon scene cache, 0 if not, -1 (error set) if unreadable. */
int hd_scene_is_cache(const char *path);

/* Latest definition of a modifier named name (searching all primitives
 * read so far), or -1.  "void" gives -1. */
int32_t hd_scene_find_modifier(const hd_scene *s, const char *name);
/* Follow alias links: the index whose type and arguments apply to prim i
 * (i itself when it is not an alias). */
int32_t hd_scene_unalias(const hd_scene *s, int32_t i);
/* The material of a surface: follows the modifier chain through aliases
 * and skips patterns/textures/mixtures, returning the first material
 * (unaliased index) or -1 (void).  Does not report unsupported types. */
int32_t hd_scene_material_of(const hd_scene *s, int32_t surface);

/* "file:line" of a primitive (with the command that produced it when it
 * came from an in-line command), into buf; returns buf. */
const char *hd_prim_where(const hd_scene *s, int32_t i, char *buf, size_t cap);

/* Same for a source index and line (e.g. of a skipped command). */
const char *hd_scene_where(const hd_scene *s, uint32_t file, uint32_t line, char *buf, size_t cap);

/* Append a primitive (copies every string and array).  Used by the parser,
 * the cache reader and tests.  modifier/alias_of are taken as given. */
hd_status hd_scene_add(hd_scene *s, const hd_prim *p);
/* Record an input source; returns its index in *idx. */
hd_status hd_scene_add_file(hd_scene *s, const char *name, int32_t parent,
                            uint32_t parent_line, uint32_t *idx);

/* Check the argument counts of a primitive for its type (surfaces, the
 * materials heliodon renders, alias, antimatter).  Types not checked are
 * accepted.  Message: "<where>: <type> <id>: expected ...". */
hd_status hd_prim_check(const hd_scene *s, const hd_prim *p, const char *where);

/* Write one primitive as Radiance text (modifier type id / strings / 0 /
 * reals), reals with 12 significant digits (as Radiance's xform), three to a
 * line; words with blanks or quotes are quoted.  Not bit-exact: the scene
 * cache is. */
void hd_prim_write(FILE *fp, const hd_prim *p);

/* Write every primitive of the scene as Radiance text (loadable again). */
hd_status hd_scene_write_rad(FILE *fp, const hd_scene *s);

/* ---- geometry accessors (arguments already validated) ---- */
static inline uint32_t hd_polygon_nverts(const hd_prim *p) { return p->nrargs / 3; }
static inline hd_vec3 hd_polygon_vertex(const hd_prim *p, uint32_t k)
{
    return hd_v3(p->rargs[3 * k], p->rargs[3 * k + 1], p->rargs[3 * k + 2]);
}
/* sphere, bubble: centre and radius */
static inline void hd_sphere_get(const hd_prim *p, hd_vec3 *c, double *r)
{
    *c = hd_v3(p->rargs[0], p->rargs[1], p->rargs[2]);
    *r = p->rargs[3];
}
/* cone, cup (8 reals) and cylinder, tube (7 reals, r0 = r1): axis end
 * points and radii as written. */
static inline void hd_cone_get(const hd_prim *p, hd_vec3 *p0, hd_vec3 *p1, double *r0, double *r1)
{
    *p0 = hd_v3(p->rargs[0], p->rargs[1], p->rargs[2]);
    *p1 = hd_v3(p->rargs[3], p->rargs[4], p->rargs[5]);
    *r0 = p->rargs[6];
    *r1 = p->nrargs >= 8 ? p->rargs[7] : p->rargs[6];
}
/* ring: centre, normal (as written, not unit) and radii sorted rin <= rout */
static inline void hd_ring_get(const hd_prim *p, hd_vec3 *c, hd_vec3 *n, double *rin, double *rout)
{
    *c = hd_v3(p->rargs[0], p->rargs[1], p->rargs[2]);
    *n = hd_v3(p->rargs[3], p->rargs[4], p->rargs[5]);
    double a = p->rargs[6], b = p->rargs[7];
    *rin = a < b ? a : b;
    *rout = a < b ? b : a;
}
/* source: direction towards the source (as written) and full angle (deg) */
static inline void hd_source_get(const hd_prim *p, hd_vec3 *dir, double *angle_deg)
{
    *dir = hd_v3(p->rargs[0], p->rargs[1], p->rargs[2]);
    *angle_deg = p->rargs[3];
}

/* ---- polygons ---- */
/* Newell normal of a closed loop (right-hand rule over the vertex order:
 * the side from which the vertices appear counter-clockwise is the front).
 * Returns the unit normal; *area (may be NULL) receives the area. */
hd_vec3 hd_polygon_normal(const hd_vec3 *v, uint32_t n, double *area);
/* Triangulate a planar simple polygon (convex or concave, possibly with
 * holes joined by coincident seam edges as Radiance allows) by ear
 * clipping in the plane of normal.  Writes up to 3*(n-2) vertex indices
 * to tri (capacity 3*(n-2)) and returns the number of triangles in *ntri;
 * all triangles have the polygon's orientation.  A duplicate closing
 * vertex and zero-length edges are ignored.  HD_ERR_FORMAT if fewer than
 * 3 distinct vertices or zero area. */
hd_status hd_polygon_triangulate(const hd_vec3 *v, uint32_t n, uint32_t *tri, uint32_t *ntri);

#endif

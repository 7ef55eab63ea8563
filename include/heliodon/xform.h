/* heliodon — similarity transforms in Radiance's xform syntax, and the
 * transformation of scene primitives (used by the xform program and by
 * anything that needs "-t x y z -rz 30 ..." style transforms).
 *
 * Transform words, applied left to right in the order written:
 *   -t x y z  translate      -rx/-ry/-rz deg  rotate (right-hand rule)
 *   -s f      scale          -mx/-my/-mz      mirror about the yz/xz/xy plane
 *   -i n      repeat the following words (up to the next -i or -a) n times
 *   -a n      array: n copies, copy k applies the following words k times
 * Only similarity transforms exist: p' = M p + t with M = sca * R,
 * R orthogonal (det -1 when mirrored). */
#ifndef HELIODON_XFORM_H
#define HELIODON_XFORM_H

#include <stdio.h>
#include "common.h"
#include "scene.h"
#include "vec.h"

typedef struct hd_xf {
    double m[3][3];   /* sca * R */
    hd_vec3 t;
    double sca;       /* > 0 */
    int mirror;       /* det(R) < 0 */
} hd_xf;

void hd_xf_identity(hd_xf *x);
/* x := next applied after x */
void hd_xf_then(hd_xf *x, const hd_xf *next);
hd_vec3 hd_xf_point(const hd_xf *x, hd_vec3 p);
/* M v (lengths scaled by sca) */
hd_vec3 hd_xf_vector(const hd_xf *x, hd_vec3 v);
/* M v / sca (rotation and mirroring only) */
hd_vec3 hd_xf_direction(const hd_xf *x, hd_vec3 v);

/* A parsed transform: segments applied in order; array segments vary
 * with the copy index, the others are fixed. */
typedef struct hd_xf_seg {
    int array;        /* 1 for -a */
    int repeat;       /* 1 for -i */
    long count;       /* -a n: n copies; -i n: n repetitions; plain: 1 */
    hd_xf xf;         /* one application of the segment's words */
    int arg0, arg1;   /* the segment's words argv[arg0..arg1) (without -a/-i n) */
} hd_xf_seg;

typedef struct hd_xf_spec {
    hd_xf_seg *seg;
    int nseg;
    int nwords;       /* words consumed */
    long ncopies;     /* product of array counts (1 without -a) */
} hd_xf_spec;

/* Parse transform words from argv[0..argc) until the first word that is
 * not a transform option (a file name, or another option).  Errors name
 * the offending word. */
hd_status hd_xf_parse(hd_xf_spec *spec, int argc, char *const *argv);
void hd_xf_spec_free(hd_xf_spec *spec);
/* Total transform of array copy number copy (0 <= copy < ncopies; the
 * first -a is the outermost loop). */
void hd_xf_spec_copy(const hd_xf_spec *spec, long copy, hd_xf *out);
/* The words of an equivalent transform for one copy (-a n replaced by
 * "-i k"), as used when the transform is appended to string arguments;
 * words point into argv or into buf (numbers).  Returns the word count. */
int hd_xf_spec_copy_words(const hd_xf_spec *spec, char *const *argv, long copy,
                          const char **words, int maxwords, char *buf, size_t bufcap);
/* Convenience: parse a complete transform word list (instance, mesh, and
 * the transform strings of patterns); words that are not transform
 * options are an error. */
hd_status hd_xf_from_words(hd_xf *out, int argc, char *const *argv);

typedef struct hd_xform_opts {
    const char *prefix;   /* -n: prefix surface identifiers with "prefix." */
    const char *newmod;   /* -m: modifier of every surface */
    int invert;           /* -I: reverse surface orientation */
} hd_xform_opts;

/* Write primitive p transformed by xf as Radiance text.  xfwords are the
 * transform words appended to the string arguments of types that take a
 * function file or an octree/mesh transform.  Errors (wrong argument
 * counts for the transformed types) name where. */
hd_status hd_xform_write_prim(FILE *out, const hd_prim *p, const hd_xf *xf, int nxfwords,
                              const char *const *xfwords, const hd_xform_opts *o, const char *where);

/* gensurf: the surface x(s,t), y(s,t), z(s,t) (expressions in s and t,
 * compiled into cal, which holds the -e/-f definitions and may define
 * valid(s,t)) over [0,1]² in m × n cells, written as Radiance polygons
 * (quadrilaterals where the two triangles of a cell are coplanar) named
 * name.1, name.2 ...; smooth: each cell gets a "Phong" texfunc with
 * surf.cal interpolating the vertex normals; rev: normals reversed. */
typedef struct hd_gensurf_opts {
    const char *mat, *name, *xe, *ye, *ze;
    int m, n, smooth, rev;
} hd_gensurf_opts;
struct hd_cal;
hd_status hd_gensurf_write(FILE *out, struct hd_cal *cal, const hd_gensurf_opts *o);

/* The curve functions gensurf and genrev offer their expressions:
 * hermite(p0,p1,r0,r1,t), bezier(p1,p2,p3,p4,t), bspline(pp,p0,p1,pn,t)
 * (.cal text, constant functions), and PI. */
hd_status hd_gen_define_curves(struct hd_cal *cal);
/* "# command args..." as Radiance's generators start their output (words
 * with blanks or quotes quoted as Radiance's printargs does). */
void hd_gen_print_command(FILE *out, const char *prog, int argc, char **argv);

/* genrev: the surface of revolution about z of r(t) at height z(t), t in
 * [0,1] in nseg steps (ze, re: expressions of t, compiled into cal), as
 * Radiance's genrev writes it: per step a cone / cup (z rising / falling),
 * cylinder / tube (r constant) or ring (z constant), named name.1 ...;
 * smooth: each gets a "Phong" texfunc with rev.cal interpolating the
 * normals between the steps.  Steps with neither z nor r changing are
 * left out. */
hd_status hd_genrev_write(FILE *out, struct hd_cal *cal, const char *mat, const char *name, const char *ze,
                          const char *re, int nseg, int smooth);

/* genprism: the polygon v[0..n-1] (x y pairs in the z = 0 plane) extruded
 * along l (l.z != 0), as Radiance's genprism writes it: ends name.b and
 * name.t (unless !ends), sides name.1 ... (the closing side unless
 * complete); round > 0 rounds the edges and corners with cylinders and
 * spheres of that radius (the faces trimmed to meet them).  Errors: a
 * degenerate or doubled-back side, round greater than the height. */
typedef struct hd_genprism_opts {
    const char *mat, *name;
    const double (*v)[2];
    int n;
    double l[3];
    double round;
    int ends, complete;
} hd_genprism_opts;
hd_status hd_genprism_write(FILE *out, const hd_genprism_opts *o, const char *header);

/* genbox: a box of size x*y*z with one corner at the origin, as six
 * polygons named name.1540 ... name.6457 (digits = corner numbers, bit 0 =
 * x, bit 1 = y, bit 2 = z), normals outward (inward with invert).  round
 * > 0 rounds the edges with cylinders and corner spheres of that radius;
 * bevel > 0 cuts them with bevel polygons (at most one of the two).  argc
 * and argv give the command line for the header comment. */
hd_status hd_genbox_write(FILE *out, const char *mat, const char *name, double x, double y, double z,
                          int invert, double round, double bevel, int argc, char *const *argv);

/* The xform program: read each file (or standard input for "-"; in-line
 * commands run in the file's directory unless expand is 0, in which case
 * they are written out as "!command | xform ..."), and write every array
 * copy of every primitive transformed.  argv/argc is the whole command
 * line (for the header comment); xfargv are the transform words. */
hd_status hd_xform_files(FILE *out, int nfiles, char *const *files, const hd_xf_spec *spec,
                         char *const *xfargv, const hd_xform_opts *o, int expand,
                         int argc, char *const *argv);

#endif

/* heliodon — Radiance's octree file format (oconv output).
 *
 * heliodon's oconv writes a file that Radiance's programs read as an
 * ordinary octree: header with FORMAT=Radiance_octree, the bounding cube,
 * the scene file names (unfrozen) or none (frozen, -f), the object count,
 * the octree in pre-order, and for frozen octrees the binary scene data.
 * Object numbers are the primitive indices of the parsed scene, which
 * follow Radiance's numbering (every primitive read, modifiers and aliases
 * included, in file order).  The octree's leaves hold every surface that
 * may touch the leaf's cube (conservative tests: Radiance only accepts hits
 * inside the cube being traversed, so a superset renders the same).
 *
 * heliodon's own scene cache (see scene.h) is appended after the Radiance
 * data, where Radiance's readers stop, and located by a 16-byte trailer
 * ("HDSCACHE" + u64 little-endian offset of the cache body), so heliodon
 * programs keep reading the parsed scene without re-running in-line
 * commands.  Format notes: docs/design/octree.md. */
#ifndef HELIODON_OCTREE_H
#define HELIODON_OCTREE_H

#include "common.h"
#include "scene.h"

typedef struct hd_octree_opts {
    int frozen;          /* -f: scene data inside, no file names */
    long resolu;         /* -r: resolution limit (default 16384) */
    long objlim;         /* -n: objects per leaf before a split (default 6) */
    int have_bound;      /* -b given */
    double bound[4];     /* -b xmin ymin zmin size */
} hd_octree_opts;

void hd_octree_opts_default(hd_octree_opts *o);

/* Bounding box of the surfaces prims[from..nprims) as Radiance computes it
 * (spheres +-r per axis, polygon vertices, cone/cylinder/ring end circles,
 * instances: the transformed cube of their octree).  Sources are ignored.
 * bbmin > bbmax when there is no surface.  Meshes are refused. */
hd_status hd_scene_bbox(const hd_scene *s, size_t from, double bbmin[3], double bbmax[3]);

/* Write scene s as a Radiance octree to path (NULL = stdout) with the
 * command line argc/argv in its header.  files/nfiles: the scene file
 * names to list for an unfrozen octree (ignored when frozen). */
hd_status hd_octree_write(const hd_scene *s, const char *path, int argc, char **argv,
                          char *const *files, int nfiles, const hd_octree_opts *o);

/* Read the bounding cube (origin, size) of a Radiance octree file and,
 * if names != NULL, the scene file names it lists (none: frozen; free
 * each and the array). */
hd_status hd_octree_read_head(const char *path, double org[3], double *size, char ***names, int *nnames);

#endif

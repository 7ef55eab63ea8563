/* heliodon — ray-tracing scene on Embree 3.
 *
 * A hd_tscene holds resolved materials and surfaces: polygons (convex or
 * concave, with Radiance's seam-edge holes; triangulated by ear clipping and
 * traced as Embree triangles, hit points recomputed in double precision on
 * the polygon's plane), spheres/bubbles, cones/cups, cylinders/tubes and
 * rings (Embree user geometry, intersected exactly in double precision) and
 * distant sources (kept outside Embree; rays that escape the scene look
 * them up).  Build once with hd_tscene_commit(); afterwards every query is
 * read-only and may run from many threads at once.
 *
 * Surface orientation follows Radiance: the geometric normal stored with a
 * hit is the surface's front normal (polygon: counter-clockwise vertices;
 * sphere/cone/cylinder outward, bubble/cup/tube inward; ring: the given
 * normal); hd_hit.front tells whether the ray arrived on the front side. */
#ifndef HELIODON_TRACE_H
#define HELIODON_TRACE_H

#include "common.h"
#include "material.h"
#include "vec.h"

typedef enum hd_skind {
    HD_SURF_POLYGON = 0,
    HD_SURF_SPHERE,       /* inward = bubble */
    HD_SURF_CONE,         /* cone/cup; cylinder/tube when r0 == r1 */
    HD_SURF_RING,
    HD_SURF_SOURCE        /* distant source */
} hd_skind;

typedef struct hd_surface {
    hd_skind kind;
    int mat;              /* material index */
    int inward;           /* bubble, cup, tube */
    hd_vec3 a, b;         /* sphere/ring centre; cone end points; ring/source: b = unit normal/direction */
    double r0, r1;        /* radii (sphere: r0); source: r0 = half angle (rad) */
    hd_vec3 n;            /* polygon plane normal (unit) */
    double d;             /* polygon plane offset n·p */
    double area;          /* surface area (source: solid angle) */
    int tri0, ntri;       /* polygon triangles */
    int nee;              /* sampled directly as a light source */
    int portal;           /* glass polygon: a window through which the renderer may
                             sample sky light directly (render.c, Russian-roulette mode) */
    char where[160];      /* "file:line type identifier" for messages */
} hd_surface;

typedef struct hd_hit {
    double t;
    hd_vec3 p;            /* hit point */
    hd_vec3 n;            /* front normal of the surface at p (unit) */
    int surf;             /* surface index */
    int front;            /* ray arrived on the front side */
} hd_hit;

typedef struct hd_tscene hd_tscene;

hd_status hd_tscene_create(hd_tscene **out);
void hd_tscene_free(hd_tscene *s);

/* Materials: returns the index (>= 0) or -1 on allocation failure. */
int hd_tscene_add_material(hd_tscene *s, const hd_tmat *m);
const hd_tmat *hd_tscene_material(const hd_tscene *s, int index);
/* The trace scene frees ms (the patterns its materials use) with itself. */
void hd_tscene_own_mods(hd_tscene *s, struct hd_modset *ms);
int hd_tscene_nmaterials(const hd_tscene *s);

/* Surfaces (before commit). `where` names the primitive for messages.
 * Degenerate input (fewer than 3 vertices, zero area, zero radius,...) is
 * an error naming `where`; a polygon that cannot be triangulated cleanly
 * is triangulated as a fan with a warning. */
hd_status hd_tscene_add_polygon(hd_tscene *s, int mat, const hd_vec3 *v, int n, const char *where);
hd_status hd_tscene_add_sphere(hd_tscene *s, int mat, hd_vec3 c, double r, int inward, const char *where);
hd_status hd_tscene_add_cone(hd_tscene *s, int mat, hd_vec3 p0, hd_vec3 p1, double r0, double r1,
                             int inward, const char *where);
hd_status hd_tscene_add_ring(hd_tscene *s, int mat, hd_vec3 c, hd_vec3 n, double r0, double r1,
                             const char *where);
/* Distant source: dir towards the source, full angle in degrees. */
hd_status hd_tscene_add_source(hd_tscene *s, int mat, hd_vec3 dir, double angle_deg, const char *where);

/* Build the acceleration structure and the light list. */
hd_status hd_tscene_commit(hd_tscene *s);

int hd_tscene_nsurfaces(const hd_tscene *s);
const hd_surface *hd_tscene_surface(const hd_tscene *s, int i);
/* Bounding box of the finite geometry (valid after commit). */
void hd_tscene_bounds(const hd_tscene *s, hd_vec3 *lo, hd_vec3 *hi);
/* Distance tolerance used to leave surfaces (depends on the scene size). */
double hd_tscene_eps(const hd_tscene *s);

/* Nearest hit with tmin < t < tmax (tmax <= 0: unlimited).  Returns 1 and
 * fills *h, or 0 if the ray escapes. */
int hd_tscene_intersect(const hd_tscene *s, hd_vec3 org, hd_vec3 dir, double tmin, double tmax, hd_hit *h);

/* Nearest hits of n <= HD_TPACKET rays at once, traced as one Embree
 * packet (meant for coherent rays, e.g. photons leaving a port in nearly
 * parallel directions): bit i of the result is set and h[i] filled when ray
 * i hits something with tmin < t < tmax (tmax <= 0: unlimited), with the
 * same conventions as hd_tscene_intersect. */
#define HD_TPACKET 16
uint32_t hd_tscene_intersect_packet(const hd_tscene *s, int n, const hd_vec3 *org, const hd_vec3 *dir,
                                    double tmin, double tmax, hd_hit *h);

/* Distant source hit by an escaping ray direction: the one with the
 * smallest solid angle containing dir, or -1. */
int hd_tscene_source_hit(const hd_tscene *s, hd_vec3 dir);
/* hd_tscene_source_hit(s, dir) == target, testing only target and the sources whose cones
 * overlap it (lists made on the first call, O(sources²), once per scene and thread-safe;
 * 0 before hd_tscene_commit). */
int hd_tscene_source_hit_is(const hd_tscene *s, hd_vec3 dir, int target);

/* Direct light sources (surfaces with nee set), in a fixed order. */
int hd_tscene_nlights(const hd_tscene *s);
int hd_tscene_light(const hd_tscene *s, int k);   /* surface index */

/* Window "portals": polygons of glass material, in a fixed order. */
int hd_tscene_nportals(const hd_tscene *s);
int hd_tscene_portal(const hd_tscene *s, int k);   /* surface index */
double hd_tscene_portal_area(const hd_tscene *s);  /* their total area */

/* Uniform point on a polygon surface (by area) for random numbers in
 * [0,1)^3; *n = front normal. */
hd_vec3 hd_tscene_sample_polygon(const hd_tscene *s, int surf, double u0, double u1, double u2);

/* Build a trace scene from a parsed Radiance scene (scene.h): surfaces
 * with their materials resolved through modifier chains and aliases;
 * brightfunc sky patterns (perezlum.cal, skybright.cal) attached to the
 * emitters they modify.  Types that affect rendering but are not supported
 * (antimatter, BSDF, dielectric, textures, mixtures, instances, ...) give
 * HD_ERR_UNSUPPORTED naming file:line, type and identifier; surfaces with a
 * void modifier are skipped with a warning.  The result is committed. */
struct hd_scene;
hd_status hd_tscene_from_scene(hd_tscene **out, const struct hd_scene *sc);

/* Polygons are triangulated with hd_polygon_triangulate (scene.h). */

#endif

/* heliodon — 3-vector math (double precision, header-only). */
#ifndef HELIODON_VEC_H
#define HELIODON_VEC_H

#include <math.h>

typedef struct hd_vec3 { double x, y, z; } hd_vec3;

#define HD_PI 3.14159265358979323846

static inline double hd_clamp(double x, double lo, double hi) { return x < lo ? lo : x > hi ? hi : x; }
static inline hd_vec3 hd_v3(double x, double y, double z) { hd_vec3 v = {x, y, z}; return v; }
static inline hd_vec3 hd_vadd(hd_vec3 a, hd_vec3 b) { return hd_v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline hd_vec3 hd_vsub(hd_vec3 a, hd_vec3 b) { return hd_v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline hd_vec3 hd_vscale(hd_vec3 a, double s) { return hd_v3(a.x * s, a.y * s, a.z * s); }
static inline hd_vec3 hd_vmadd(hd_vec3 a, hd_vec3 b, double s) { return hd_v3(a.x + b.x * s, a.y + b.y * s, a.z + b.z * s); }
static inline hd_vec3 hd_vneg(hd_vec3 a) { return hd_v3(-a.x, -a.y, -a.z); }
static inline double hd_vdot(hd_vec3 a, hd_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline hd_vec3 hd_vcross(hd_vec3 a, hd_vec3 b)
{
    return hd_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double hd_vlen2(hd_vec3 a) { return hd_vdot(a, a); }
static inline double hd_vlen(hd_vec3 a) { return sqrt(hd_vdot(a, a)); }
/* Unit vector; the zero vector stays zero. */
static inline hd_vec3 hd_vnorm(hd_vec3 a)
{
    double l = hd_vlen(a);
    return l > 0 ? hd_vscale(a, 1.0 / l) : a;
}
static inline double hd_vget(hd_vec3 a, int i) { return i == 0 ? a.x : i == 1 ? a.y : a.z; }
/* Orthonormal basis (u, v) perpendicular to unit n (Duff et al. 2017). */
static inline void hd_vbasis(hd_vec3 n, hd_vec3 *u, hd_vec3 *v)
{
    double s = n.z >= 0 ? 1.0 : -1.0;
    double a = -1.0 / (s + n.z), b = n.x * n.y * a;
    *u = hd_v3(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    *v = hd_v3(b, s + n.y * n.y * a, -n.y);
}

#endif

/* heliodon — angle bases for hemispheres: the LBNL/WINDOW "Klems" bases
 * and any ring basis read from a BSDF XML <AngleBasis>.
 *
 * A basis is a list of rings around the surface normal, from the normal
 * outwards.  Ring r covers polar angles [theta_lo, theta_hi) (degrees) and
 * is cut into nphi equal azimuth bins; bin 0 of each ring is centred on
 * azimuth 0 (the +x axis), bins go counter-clockwise (towards +y).  Bins are
 * numbered ring by ring from the normal (bin 0 = the normal cap).
 *
 * Local frame: +z = the surface normal of the hemisphere, vectors point
 * AWAY from the surface (as Radiance's fo_getvec / fo_getndx "front
 * outgoing" convention).  Within a bin, directions drawn by hd_klems_dir()
 * with uniform random numbers are uniform in projected solid angle.
 *
 * World helpers follow klems_full.cal (rfluxmtx h=kf): for a ray direction
 * D arriving at a surface of normal N (pointing away from the receiving
 * face) with up vector U, the local vector is v = -D in the frame z = N,
 * y = U made perpendicular to N, x = y × z = U × N (right-handed). */
#ifndef HELIODON_KLEMS_H
#define HELIODON_KLEMS_H

#include <stdio.h>

#include "common.h"
#include "vec.h"

#define HD_KLEMS_MAXRINGS 128
#define HD_KLEMS_MAXBINS 65536

typedef struct hd_klems_ring {
    double theta_lo, theta_hi;  /* degrees, 0 <= lo < hi <= 90 */
    double theta_c;             /* nominal centre written in XML (degrees) */
    int nphi;                   /* azimuth bins (>= 1) */
    int first;                  /* index of the ring's first bin */
} hd_klems_ring;

typedef struct hd_klems_basis {
    char name[64];              /* "LBNL/Klems Full", ... */
    int nrings;
    int nbins;
    hd_klems_ring ring[HD_KLEMS_MAXRINGS];
} hd_klems_basis;

typedef enum hd_klems_kind {
    HD_KLEMS_FULL = 0,          /* 145 bins */
    HD_KLEMS_HALF,              /* 77 bins */
    HD_KLEMS_QUARTER            /* 41 bins */
} hd_klems_kind;

/* The standard LBNL bases. */
void hd_klems_standard(hd_klems_basis *b, hd_klems_kind kind);
/* A standard basis by its XML name ("LBNL/Klems Full", "LBNL/Klems Half",
 * "LBNL/Klems Quarter", case-insensitive; also "kf", "kh", "kq" as in
 * rfluxmtx h=): HD_OK, or HD_ERR_FORMAT if unknown. */
hd_status hd_klems_by_name(hd_klems_basis *b, const char *name);
/* Write the basis as the body of an LBNL BSDF XML <DataDefinition>: the
 * IncidentDataStructure and AngleBasis elements (one AngleBasisBlock per
 * ring, tab-indented as WINDOW writes them), then </DataDefinition>. */
void hd_klems_write_xml(FILE *fp, const hd_klems_basis *b);
/* A custom basis: nrings rings with bounds[0..nrings] (degrees, strictly
 * increasing, bounds[0] = 0, bounds[nrings] = 90) and nphi[0..nrings-1].
 * Checks everything (message names the ring). centres may be NULL. */
hd_status hd_klems_init(hd_klems_basis *b, const char *name, int nrings,
                        const double *bounds, const int *nphi,
                        const double *centres);

/* Bin of a local unit vector v (z >= 0, pointing away from the surface);
 * -1 if v.z < 0 (or not finite).  v need not be normalised. */
int hd_klems_bin(const hd_klems_basis *b, hd_vec3 v);
/* Ring and azimuth column of a bin (returns ring, or -1 if out of range). */
int hd_klems_ring_of(const hd_klems_basis *b, int bin, int *col);
/* A local unit vector in bin: (r0, r1) in [0,1)^2, (0.5, 0.5) = centre.
 * Uniform (r0, r1) give directions uniform in projected solid angle. */
hd_vec3 hd_klems_dir(const hd_klems_basis *b, int bin, double r0, double r1);
/* Solid angle of a bin (sr) and its projected solid angle "lambda"
 * (∫cosθ dω, sr; the values of a basis sum to π). */
double hd_klems_solid_angle(const hd_klems_basis *b, int bin);
double hd_klems_lambda(const hd_klems_basis *b, int bin);
/* Smallest projected solid angle of any bin. */
double hd_klems_min_lambda(const hd_klems_basis *b);

/* ---- world frame (klems_full.cal / rfluxmtx conventions) ----
 * D: ray direction (travelling towards the surface), N: surface normal,
 * U: up vector (need not be perpendicular to N).  Returns the bin of
 * v = -D in the local frame, or -1 if -D·N <= 0 or U ∥ N. */
int hd_klems_bin_world(const hd_klems_basis *b, hd_vec3 D, hd_vec3 N, hd_vec3 U);
/* Inverse: the ray direction D (unit) for a point (r0, r1) of bin. */
hd_vec3 hd_klems_dir_world(const hd_klems_basis *b, int bin, double r0, double r1,
                           hd_vec3 N, hd_vec3 U);
/* The local frame used above: x = U×N normalised, y = z×x, z = N normalised.
 * Returns 0, or -1 if U ∥ N. */
int hd_klems_frame(hd_vec3 N, hd_vec3 U, hd_vec3 *x, hd_vec3 *y, hd_vec3 *z);

#endif

/* heliodon — sky and hemisphere bases.
 *
 * Tregenza / Reinhart (MF:n) sky subdivisions with Radiance's numbering, as
 * used by gendaymtx, genskyvec, reinhart.cal and tregenza.cal:
 *   bin 0       ground (every direction with Dz < 0)
 *   bins 1..    altitude bands from the horizon up; in each band the first
 *               patch is centred on north (+Y) and the following ones go
 *               EASTWARDS (azimuth = atan2(Dx, Dy), from +Y towards +X);
 *   last bin    the zenith cap.
 * Band height alpha = 90 deg / (7 MF + 0.5); band r holds MF*tnaz[r/MF]
 * patches with tnaz = 30 30 24 24 18 12 6; MF 1 is the Tregenza sky
 * (146 bins with the ground).  Directions are unit vectors pointing from
 * the scene towards the sky (x east, y north, z up).
 *
 * "reinhartb" numbering (rfluxmtx h=rN) is the same without the ground bin:
 * subtract 1 and treat 0 (ground) as "no bin". */
#ifndef HELIODON_BASIS_H
#define HELIODON_BASIS_H

#include "common.h"
#include "klems.h"
#include "vec.h"

#define HD_SKY_MAXMF 64

typedef struct hd_skybasis {
    int mf;             /* subdivision (1 = Tregenza) */
    int nbins;          /* with the ground bin: 144*mf*mf + 2 */
    int nbands;         /* 7*mf altitude bands (the zenith cap not counted) */
    double alpha;       /* band height (radians) */
    int *band_first;    /* [nbands+1]: bin number of the first patch of each
                           band; band_first[nbands] = zenith bin */
    int *band_count;    /* [nbands]: patches in the band */
    double *alt;        /* [nbins] centre altitude (rad); ground -pi/2 */
    double *azi;        /* [nbins] centre azimuth (rad, east of north) */
    double *omega;      /* [nbins] solid angle (sr); ground 2 pi */
    hd_vec3 *dir;       /* [nbins] centre direction; ground (0,0,-1) */
} hd_skybasis;

/* Build the MF:mf basis (1 <= mf <= HD_SKY_MAXMF). */
hd_status hd_skybasis_init(hd_skybasis *b, int mf);
void hd_skybasis_free(hd_skybasis *b);

/* Number of bins with the ground for a given MF (0 if mf is out of range). */
int hd_skybasis_count(int mf);

/* Bin of a direction (need not be normalised; the zero vector gives 0). */
int hd_skybasis_bin(const hd_skybasis *b, hd_vec3 d);

/* Centre direction / solid angle of a bin (bin in [0, nbins)). */
static inline hd_vec3 hd_skybasis_dir(const hd_skybasis *b, int bin) { return b->dir[bin]; }
static inline double hd_skybasis_omega(const hd_skybasis *b, int bin) { return b->omega[bin]; }

/* A direction inside a sky bin (bin >= 1) for (u1,u2) in [0,1)^2, uniform
 * in altitude and azimuth as genskyvec samples it (the zenith cap is
 * sampled uniformly in solid angle).  (0.5,0.5) is the centre except for
 * the cap. */
hd_vec3 hd_skybasis_sample(const hd_skybasis *b, int bin, double u1, double u2);

/* Parse a basis name: "u" (uniform, 1 bin), "tregenza", "r" (MF:1), "rN",
 * "MF:N", "reinhart:N".  Sets *mf (0 for "u").  Returns HD_OK or
 * HD_ERR_USAGE with a message. */
hd_status hd_skybasis_parse(const char *name, int *mf);

#endif

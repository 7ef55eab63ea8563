/* heliodon — sun sources for the solar daylight coefficients of PM-CBDM.
 *
 * The sun positions are discretised to the centres of the Reinhart MF:n
 * sky patches (basis.h numbering: bin 0 ground, 1.. from the horizon up,
 * last bin the zenith cap).  By default only the patches that the sun
 * visits during the daylight hours of a weather file are kept (a patch is
 * "visited" when, in some record with direct or diffuse radiation, the sun
 * is above the horizon and its direction falls in the patch); keep_all
 * keeps every sky patch (bins 1..nbins-1).  The patch of a sun position is
 * the one whose centre is nearest (largest dot product), as gendaymtx -5
 * assigns the sun, so that every sun-only sky vector of the weather file
 * has its single non-zero patch among the kept ones.
 *
 * Output for rcontrib / mkpmap: one light + source pair per kept patch,
 *     void light solar<bin>  0 0 3 1 1 1
 *     solar<bin> source sun<bin>  0 0 4 dx dy dz 0.533
 * (unit radiance: rcontrib -V- then gives coefficients; the sun-only sky
 * vector of the hour, as gendaymtx -5 0.533 -d computes it, supplies the
 * radiance) and the modifier list, one "solar<bin>" per line, in bin order,
 * so that rcontrib -M list -o dc_sun/%s.hdr writes dc_sun/solar<bin>.hdr. */
#ifndef HELIODON_SUNS_H
#define HELIODON_SUNS_H

#include <stdio.h>
#include "common.h"
#include "vec.h"

struct hd_weather;

typedef struct hd_sunlist {
    int mf;               /* Reinhart subdivision */
    int nbins;            /* bins of the basis including the ground bin */
    int n;                /* kept patches */
    int *bin;             /* [n] kept bins, ascending */
    hd_vec3 *dir;         /* [n] patch-centre directions (x east, y north, z up) */
    long *hours;          /* [n] daylight records whose sun falls in the patch */
    long ndaylight;       /* daylight records of the weather file */
} hd_sunlist;

void hd_sunlist_init(hd_sunlist *s);
void hd_sunlist_free(hd_sunlist *s);

/* Daylight test used by the pipeline for record i, as gendaymtx decides
 * whether a record has a sun: sun above -0.2665 deg (half the disk) and
 * v1 + v2 > 1e-4 in the file's units.  Writes the sun direction (may be
 * NULL). */
int hd_suns_daylight(const struct hd_weather *w, size_t i, const int *jd, hd_vec3 *sundir);

struct hd_skybasis;
/* Patch (bins 1..nbins-1) whose centre is nearest to direction d. */
int hd_suns_nearest(const struct hd_skybasis *b, hd_vec3 d);

/* Select the patches.  Errors: mf out of range; a weather file without a
 * single daylight record (unless keep_all). */
hd_status hd_suns_select(const struct hd_weather *w, int mf, int keep_all, hd_sunlist *out);

/* Write the light/source pairs (rad may be NULL) and the modifier list
 * (mods may be NULL).  cmdline goes into a comment at the top of rad. */
hd_status hd_suns_write(const hd_sunlist *s, FILE *rad, FILE *mods, const char *cmdline);

#endif

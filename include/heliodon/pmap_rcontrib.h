/* heliodon — rcontrib -ap: contribution photon-map mode of rcontrib.
 *
 * The photon-map options are taken out of the command line before the
 * backward-mode parser sees it (hd_pmap_rc_extract); the modifiers, bins,
 * -o/-f/-x/-y/-c/-V/-I/-i/-n settings are those the backward parser
 * filled into hd_contrib / hd_rcontrib_opts.  hd_pmap_rc_run then
 * replaces the path tracer: per ray, the photon lookups of every tracked
 * light-source modifier (-ab < 0: at the primary hit; -ab >= 1: one final
 * gather bounce with -ad rays) binned per modifier and, through the bin
 * function, by the photon's incident direction. */
#ifndef HELIODON_PMAP_RCONTRIB_H
#define HELIODON_PMAP_RCONTRIB_H

#include "common.h"
#include "contrib.h"
#include "header.h"

typedef struct hd_pmap_rc_opts {
    const char *file;         /* -ap file (NULL: not photon-map mode) */
    double bw, bw2;           /* -ap bandwidth [bandwidth2] */
    uint64_t cache;           /* -aC cached photons (default 4M) */
    double ac;                /* -ac (accepted; pages are fixed at build time) */
    double am;                /* -am max radius (0 = none) */
    int ab;                   /* the -ab value as given (negative kept) */
    int ab_given;
    int exact_direct;         /* -apd+ (default): direct through glass by shadow rays */
    uint64_t row0, nrows;     /* -apR first count: compute only these records (0 0 = all) */
} hd_pmap_rc_opts;

/* Remove -ap, -ac, -aC, -am, -apd[+-], -apR from argv (in place, *argc
 * updated) into po, and replace a negative -ab value by 1 for the
 * backward-mode parser (the value is kept in po->ab). */
hd_status hd_pmap_rc_extract(int *argc, char **argv, hd_pmap_rc_opts *po);

/* Run photon-map rcontrib on the rays of src. */
hd_status hd_pmap_rc_run(const hd_contrib *c, const hd_rcontrib_opts *o, hd_raysrc *src,
                         const hd_header *hdr, const hd_pmap_rc_opts *po);

#endif

/* heliodon — Tregenza / Reinhart sky bases (see basis.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/basis.h"

static const int tnaz[7] = {30, 30, 24, 24, 18, 12, 6};

int hd_skybasis_count(int mf)
{
    if (mf < 1 || mf > HD_SKY_MAXMF) return 0;
    return 144 * mf * mf + 2;
}

void hd_skybasis_free(hd_skybasis *b)
{
    if (!b) return;
    free(b->band_first);
    free(b->band_count);
    free(b->alt);
    free(b->azi);
    free(b->omega);
    free(b->dir);
    memset(b, 0, sizeof *b);
}

static hd_vec3 altazi_dir(double alt, double azi)
{
    return hd_v3(sin(azi) * cos(alt), cos(azi) * cos(alt), sin(alt));
}

hd_status hd_skybasis_init(hd_skybasis *b, int mf)
{
    memset(b, 0, sizeof *b);
    if (mf < 1 || mf > HD_SKY_MAXMF)
        return hd_fail(HD_ERR_RANGE, "sky subdivision MF:%d out of range [1,%d]", mf, HD_SKY_MAXMF);
    b->mf = mf;
    b->nbins = hd_skybasis_count(mf);
    b->nbands = 7 * mf;
    b->alpha = (HD_PI / 2) / (7 * mf + 0.5);
    b->band_first = hd_malloc_array((size_t)b->nbands + 1, sizeof(int));
    b->band_count = hd_malloc_array((size_t)b->nbands, sizeof(int));
    b->alt = hd_malloc_array((size_t)b->nbins, sizeof(double));
    b->azi = hd_malloc_array((size_t)b->nbins, sizeof(double));
    b->omega = hd_malloc_array((size_t)b->nbins, sizeof(double));
    b->dir = hd_malloc_array((size_t)b->nbins, sizeof(hd_vec3));
    if (!b->band_first || !b->band_count || !b->alt || !b->azi || !b->omega || !b->dir) {
        hd_skybasis_free(b);
        return HD_ERR_NOMEM;
    }
    b->alt[0] = -HD_PI / 2;
    b->azi[0] = 0;
    b->omega[0] = 2 * HD_PI;
    b->dir[0] = hd_v3(0, 0, -1);
    int p = 1;
    for (int r = 0; r < b->nbands; r++) {
        int n = mf * tnaz[r / mf];
        double alt = b->alpha * (r + 0.5);
        double dom = 2 * HD_PI * (sin(b->alpha * (r + 1)) - sin(b->alpha * r)) / n;
        b->band_first[r] = p;
        b->band_count[r] = n;
        for (int c = 0; c < n; c++, p++) {
            b->alt[p] = alt;
            b->azi[p] = 2 * HD_PI * c / n;
            b->omega[p] = dom;
            b->dir[p] = altazi_dir(alt, b->azi[p]);
        }
    }
    b->band_first[b->nbands] = p;
    b->alt[p] = HD_PI / 2;
    b->azi[p] = 0;
    b->omega[p] = 2 * HD_PI * (1 - cos(b->alpha * 0.5));
    b->dir[p] = hd_v3(0, 0, 1);
    if (p + 1 != b->nbins) {
        hd_skybasis_free(b);
        return hd_fail(HD_ERR_INTERNAL, "sky basis MF:%d: counted %d bins, expected %d", mf, p + 1,
                       hd_skybasis_count(mf));
    }
    return HD_OK;
}

int hd_skybasis_bin(const hd_skybasis *b, hd_vec3 d)
{
    double len = hd_vlen(d);
    if (!(len > 0)) return 0;
    double dz = d.z / len;
    if (dz < 0) return 0;
    if (dz > 1) dz = 1;
    double alt = asin(dz);
    int r = (int)floor(alt / b->alpha);
    if (r >= b->nbands) return b->band_first[b->nbands];
    double azi = atan2(d.x, d.y);
    if (azi < 0) azi += 2 * HD_PI;
    int n = b->band_count[r];
    double inc = 2 * HD_PI / n;
    int c = (int)floor((azi + 0.5 * inc) / inc);
    if (c >= n) c -= n;
    if (c < 0) c = 0;
    return b->band_first[r] + c;
}

hd_vec3 hd_skybasis_sample(const hd_skybasis *b, int bin, double u1, double u2)
{
    if (bin <= 0) return hd_v3(0, 0, -1);
    if (bin >= b->nbins - 1) {
        /* zenith cap: uniform in solid angle */
        double cmin = cos(0.5 * b->alpha);
        double cz = 1 - u1 * (1 - cmin);
        double sz = sqrt(fmax(0, 1 - cz * cz));
        double phi = 2 * HD_PI * u2;
        return hd_v3(sz * sin(phi), sz * cos(phi), cz);
    }
    /* find the band by bisection on band_first */
    int lo = 0, hi = b->nbands - 1;
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (b->band_first[mid] <= bin) lo = mid;
        else hi = mid - 1;
    }
    int c = bin - b->band_first[lo];
    double alt = (lo + u1) * b->alpha;
    double azi = (c + u2 - 0.5) * 2 * HD_PI / b->band_count[lo];
    return altazi_dir(alt, azi);
}

hd_status hd_skybasis_parse(const char *name, int *mf)
{
    long v = 1;
    const char *num = NULL;
    if (!strcmp(name, "u")) { *mf = 0; return HD_OK; }
    if (!strcmp(name, "tregenza") || !strcmp(name, "r") || !strcmp(name, "t")) { *mf = 1; return HD_OK; }
    if (name[0] == 'r' && name[1]) num = name + 1;
    else if (!strncmp(name, "MF:", 3)) num = name + 3;
    else if (!strncmp(name, "reinhart:", 9)) num = name + 9;
    if (!num)
        return hd_fail(HD_ERR_USAGE, "unknown sky basis '%s' (expected u, tregenza, rN, MF:N)", name);
    char *end;
    v = strtol(num, &end, 10);
    if (*end || end == num || v < 1 || v > HD_SKY_MAXMF)
        return hd_fail(HD_ERR_USAGE, "bad sky subdivision in '%s' (expected an integer 1..%d)", name,
                       HD_SKY_MAXMF);
    *mf = (int)v;
    return HD_OK;
}

/* heliodon — Klems and custom ring angle bases (see klems.h). */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "heliodon/klems.h"

#define DEG (HD_PI / 180.0)

static const double full_b[] = {0, 5, 15, 25, 35, 45, 55, 65, 75, 90};
static const int full_n[] = {1, 8, 16, 20, 24, 24, 24, 16, 12};
static const double full_c[] = {0, 10, 20, 30, 40, 50, 60, 70, 82.5};
static const double half_b[] = {0, 6.5, 19.5, 32.5, 45.5, 58.5, 71.5, 90};
static const int half_n[] = {1, 8, 12, 16, 20, 12, 8};
static const double half_c[] = {0, 13, 26, 39, 52, 65, 80.75};
static const double quarter_b[] = {0, 9, 27, 45, 63, 90};
static const int quarter_n[] = {1, 8, 12, 12, 8};
static const double quarter_c[] = {0, 18, 36, 54, 76.5};

void hd_klems_standard(hd_klems_basis *b, hd_klems_kind kind)
{
    switch (kind) {
    case HD_KLEMS_HALF:
        hd_klems_init(b, "LBNL/Klems Half", 7, half_b, half_n, half_c);
        break;
    case HD_KLEMS_QUARTER:
        hd_klems_init(b, "LBNL/Klems Quarter", 5, quarter_b, quarter_n, quarter_c);
        break;
    default:
        hd_klems_init(b, "LBNL/Klems Full", 9, full_b, full_n, full_c);
        break;
    }
}

hd_status hd_klems_by_name(hd_klems_basis *b, const char *name)
{
    if (!strcasecmp(name, "LBNL/Klems Full") || !strcmp(name, "kf") || !strcmp(name, "kbinF"))
        hd_klems_standard(b, HD_KLEMS_FULL);
    else if (!strcasecmp(name, "LBNL/Klems Half") || !strcmp(name, "kh"))
        hd_klems_standard(b, HD_KLEMS_HALF);
    else if (!strcasecmp(name, "LBNL/Klems Quarter") || !strcmp(name, "kq"))
        hd_klems_standard(b, HD_KLEMS_QUARTER);
    else
        return hd_fail(HD_ERR_FORMAT, "unknown angle basis '%s' (expected LBNL/Klems Full, "
                       "LBNL/Klems Half or LBNL/Klems Quarter)", name);
    return HD_OK;
}

hd_status hd_klems_init(hd_klems_basis *b, const char *name, int nrings,
                        const double *bounds, const int *nphi, const double *centres)
{
    memset(b, 0, sizeof *b);
    snprintf(b->name, sizeof b->name, "%s", name ? name : "");
    if (nrings < 1 || nrings > HD_KLEMS_MAXRINGS)
        return hd_fail(HD_ERR_RANGE, "angle basis '%s': %d rings (expected 1 to %d)",
                       b->name, nrings, HD_KLEMS_MAXRINGS);
    if (fabs(bounds[0]) > 1e-9)
        return hd_fail(HD_ERR_FORMAT, "angle basis '%s': first ring starts at %g deg (expected 0)",
                       b->name, bounds[0]);
    if (fabs(bounds[nrings] - 90.0) > 1e-6)
        return hd_fail(HD_ERR_FORMAT, "angle basis '%s': last ring ends at %g deg (expected 90)",
                       b->name, bounds[nrings]);
    int total = 0;
    for (int r = 0; r < nrings; r++) {
        if (!(bounds[r + 1] > bounds[r]))
            return hd_fail(HD_ERR_FORMAT, "angle basis '%s': ring %d: theta bounds %g..%g "
                           "are not increasing", b->name, r, bounds[r], bounds[r + 1]);
        if (nphi[r] < 1 || nphi[r] > HD_KLEMS_MAXBINS)
            return hd_fail(HD_ERR_FORMAT, "angle basis '%s': ring %d: nPhis %d (expected 1 to %d)",
                           b->name, r, nphi[r], HD_KLEMS_MAXBINS);
        if (total + nphi[r] > HD_KLEMS_MAXBINS)
            return hd_fail(HD_ERR_RANGE, "angle basis '%s': more than %d bins",
                           b->name, HD_KLEMS_MAXBINS);
        b->ring[r].theta_lo = r == 0 ? 0.0 : bounds[r];
        b->ring[r].theta_hi = bounds[r + 1];
        b->ring[r].theta_c = centres ? centres[r] : 0.5 * (bounds[r] + bounds[r + 1]);
        b->ring[r].nphi = nphi[r];
        b->ring[r].first = total;
        total += nphi[r];
    }
    b->ring[nrings - 1].theta_hi = 90.0;
    b->nrings = nrings;
    b->nbins = total;
    return HD_OK;
}

static int bin_local(const hd_klems_basis *b, double x, double y, double z)
{
    double len = sqrt(x * x + y * y + z * z);
    if (!(len > 0) || !(z >= 0) || !isfinite(len)) return -1;
    double c = z / len;
    if (c > 1) c = 1;
    double theta = acos(c) / DEG;
    int r = 0;
    while (r + 1 < b->nrings && theta >= b->ring[r + 1].theta_lo) r++;
    const hd_klems_ring *rg = &b->ring[r];
    if (rg->nphi == 1) return rg->first;
    double phi = atan2(y, x) / DEG;
    if (phi < 0) phi += 360.0;
    int k = (int)(phi * rg->nphi / 360.0 + 0.5);
    if (k >= rg->nphi) k -= rg->nphi;
    if (k < 0) k = 0;
    return rg->first + k;
}

int hd_klems_bin(const hd_klems_basis *b, hd_vec3 v)
{
    return bin_local(b, v.x, v.y, v.z);
}

int hd_klems_ring_of(const hd_klems_basis *b, int bin, int *col)
{
    if (bin < 0 || bin >= b->nbins) return -1;
    int lo = 0, hi = b->nrings - 1;
    while (lo < hi) {               /* last ring with first <= bin */
        int mid = (lo + hi + 1) / 2;
        if (b->ring[mid].first <= bin) lo = mid; else hi = mid - 1;
    }
    if (col) *col = bin - b->ring[lo].first;
    return lo;
}

hd_vec3 hd_klems_dir(const hd_klems_basis *b, int bin, double r0, double r1)
{
    int col = 0, r = hd_klems_ring_of(b, bin, &col);
    if (r < 0) return hd_v3(0, 0, 0);
    const hd_klems_ring *rg = &b->ring[r];
    double clo = cos(rg->theta_lo * DEG), chi = cos(rg->theta_hi * DEG);
    double c2 = (1.0 - r0) * clo * clo + r0 * chi * chi;
    if (c2 < 0) c2 = 0;
    double ct = sqrt(c2), st = sqrt(1.0 - c2 > 0 ? 1.0 - c2 : 0);
    double phi = 2.0 * HD_PI * (col + r1 - 0.5) / rg->nphi;
    return hd_v3(st * cos(phi), st * sin(phi), ct);
}

double hd_klems_solid_angle(const hd_klems_basis *b, int bin)
{
    int r = hd_klems_ring_of(b, bin, NULL);
    if (r < 0) return 0;
    const hd_klems_ring *rg = &b->ring[r];
    return 2.0 * HD_PI * (cos(rg->theta_lo * DEG) - cos(rg->theta_hi * DEG)) / rg->nphi;
}

double hd_klems_lambda(const hd_klems_basis *b, int bin)
{
    int r = hd_klems_ring_of(b, bin, NULL);
    if (r < 0) return 0;
    const hd_klems_ring *rg = &b->ring[r];
    double clo = cos(rg->theta_lo * DEG), chi = cos(rg->theta_hi * DEG);
    if (rg->theta_hi >= 90.0) chi = 0;
    return HD_PI * (clo * clo - chi * chi) / rg->nphi;
}

double hd_klems_min_lambda(const hd_klems_basis *b)
{
    double m = HUGE_VAL;
    for (int r = 0; r < b->nrings; r++) {
        double l = hd_klems_lambda(b, b->ring[r].first);
        if (l < m) m = l;
    }
    return m;
}

int hd_klems_frame(hd_vec3 N, hd_vec3 U, hd_vec3 *x, hd_vec3 *y, hd_vec3 *z)
{
    hd_vec3 n = hd_vnorm(N);
    hd_vec3 xx = hd_vcross(U, n);
    double l = hd_vlen(xx);
    if (!(l > 1e-9 * (hd_vlen(U) + 1e-300))) return -1;
    xx = hd_vscale(xx, 1.0 / l);
    *x = xx;
    *y = hd_vcross(n, xx);
    *z = n;
    return 0;
}

int hd_klems_bin_world(const hd_klems_basis *b, hd_vec3 D, hd_vec3 N, hd_vec3 U)
{
    hd_vec3 x, y, z;
    if (hd_klems_frame(N, U, &x, &y, &z)) return -1;
    hd_vec3 v = hd_vneg(D);
    double zv = hd_vdot(v, z);
    if (!(zv > 0)) return -1;
    return bin_local(b, hd_vdot(v, x), hd_vdot(v, y), zv);
}

hd_vec3 hd_klems_dir_world(const hd_klems_basis *b, int bin, double r0, double r1,
                           hd_vec3 N, hd_vec3 U)
{
    hd_vec3 x, y, z;
    if (hd_klems_frame(N, U, &x, &y, &z)) return hd_v3(0, 0, 0);
    hd_vec3 v = hd_klems_dir(b, bin, r0, r1);
    hd_vec3 w = hd_vadd(hd_vadd(hd_vscale(x, v.x), hd_vscale(y, v.y)), hd_vscale(z, v.z));
    return hd_vneg(w);
}

void hd_klems_write_xml(FILE *fp, const hd_klems_basis *b)
{
    fprintf(fp, "\t\t<IncidentDataStructure>Columns</IncidentDataStructure>\n\t\t<AngleBasis>\n"
            "\t\t\t<AngleBasisName>%s</AngleBasisName>\n", b->name);
    for (int r = 0; r < b->nrings; r++)
        fprintf(fp, "\t\t\t<AngleBasisBlock>\n\t\t\t\t<Theta>%g</Theta>\n\t\t\t\t<nPhis>%d</nPhis>\n"
                "\t\t\t\t<ThetaBounds>\n\t\t\t\t\t<LowerTheta>%g</LowerTheta>\n"
                "\t\t\t\t\t<UpperTheta>%g</UpperTheta>\n\t\t\t\t</ThetaBounds>\n"
                "\t\t\t</AngleBasisBlock>\n", b->ring[r].theta_c, b->ring[r].nphi,
                b->ring[r].theta_lo, b->ring[r].theta_hi);
    fputs("\t\t</AngleBasis>\n\t</DataDefinition>\n", fp);
}

/* heliodon — checkBSDF report and Klems XML writer (bsdf2klems). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bsdf_internal.h"
#include "heliodon/rng.h"

static const char *type_name(hd_bsdf_type t)
{
    switch (t) {
    case HD_BSDF_KLEMS_FULL: return "Klems_Full";
    case HD_BSDF_KLEMS_HALF: return "Klems_Half";
    case HD_BSDF_KLEMS_QUARTER: return "Klems_Quarter";
    case HD_BSDF_KLEMS_OTHER: return "Unknown_Matrix";
    case HD_BSDF_TREE3: return "Isotropic_Tensor_Tree";
    case HD_BSDF_TREE4: return "Anisotropic_Tensor_Tree";
    default: return "Pure_Lambertian";
    }
}

int hd_bsdf_reciprocity(const hd_bsdf *b, hd_bsdf_comp c, double *mn, double *avg, double *mx)
{
    hd_bsdf_comp c2;
    if (c == HD_BSDF_RF || c == HD_BSDF_RB) {
        if (b->info.avail[c] != HD_BSDF_IN_FILE) return 0;
        c2 = c;
    } else {
        if (b->info.avail[HD_BSDF_TF] != HD_BSDF_IN_FILE || b->info.avail[HD_BSDF_TB] != HD_BSDF_IN_FILE)
            return 0;
        c = HD_BSDF_TF;
        c2 = HD_BSDF_TB;
    }
    double smin = HUGE_VAL, smax = 0, sum = 0;
    long n = 0;
    /* Klems data: every pair of the block's own bins at their centres; as
     * checkBSDF, pairs where either value is <= 1e-4 (1/sr) are left out (a
     * zero against a non-zero would count 100 %).  Trees: one random point
     * per Klems-full bin pair (the bin centres at azimuths 0 and 90 deg sit
     * on tree cell boundaries), pairs of two zeros left out. */
    const hd_bsdf_block *d = b->src[c];
    int klems = d && d->kind == 1;
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    const hd_klems_basis *ib = !klems ? &kb : b->recip[c] ? &d->outb : &d->inb;
    const hd_klems_basis *ob = !klems ? &kb : b->recip[c] ? &d->inb : &d->outb;
    hd_rng r;
    hd_rng_init(&r, 12345, (uint64_t)c);
    for (int i = 0; i < ib->nbins; i++)
        for (int o = 0; o < ob->nbins; o++) {
            double u[4] = {0.5, 0.5, 0.5, 0.5};
            for (int k = 0; !klems && k < 4; k++) u[k] = hd_rng_uniform(&r);
            hd_vec3 v1 = hd_bsdf_klems_in_dir(ib, c, i, u[0], u[1]);
            hd_vec3 v2 = hd_bsdf_klems_out_dir(ob, c, o, u[2], u[3]);
            double f1 = hd_bsdf_eval_comp(b, c, v1, v2, 1);
            if (klems && !(f1 > 1e-4)) continue;
            double f2 = hd_bsdf_eval_comp(b, c2, v2, v1, 1);
            double m = f1 > f2 ? f1 : f2;
            if (klems ? !(f2 > 1e-4) : !(m > 0)) continue;
            double e = 100 * fabs(f1 - f2) / m;
            if (e < smin) smin = e;
            if (e > smax) smax = e;
            sum += e;
            n++;
        }
    if (!n) { *mn = *avg = *mx = 0; return 1; }
    *mn = smin;
    *avg = sum / n;
    *mx = smax;
    return 1;
}

hd_status hd_bsdf_check_report(FILE *fp, const char *path, const hd_bsdf *b)
{
    const hd_bsdf_info *in = &b->info;
    fprintf(fp, "=====================================================\n");
    fprintf(fp, "File: '%s'\n", path);
    fprintf(fp, "Manufacturer: '%s'\n", in->manufacturer);
    fprintf(fp, "BSDF Name: '%s'\n", in->name);
    fprintf(fp, "Dimensions (W x H x Thickness): %g x %g x %g cm\n",
            in->width * 100, in->height * 100, in->thickness * 100);
    fprintf(fp, "Type: %s\n", type_name(in->type));
    fprintf(fp, "Color: 0\n");
    fprintf(fp, "Has Geometry: %d\n", in->has_geometry);
    fprintf(fp, "Component\tLambertian XYZ (%%)\tMax. Tot. Dir\tMin. Angle\n");
    for (int c = 0; c < 4; c++) {
        double l = 100 * in->lambertian[c];
        fprintf(fp, "%s\t%4.1f %4.1f %4.1f\t\t", hd_bsdf_label((hd_bsdf_comp)c), l, l, l);
        const hd_bsdf_block *d = b->blk[c];
        if (in->avail[c] != HD_BSDF_IN_FILE || !d)
            fprintf(fp, "%5.1f%%\t\t180 deg\n", 0.0);
        else if (!d->kind)          /* Lambertian only: checkBSDF prints the fraction */
            fprintf(fp, "%5.1f%%\t\t180 deg\n", in->lambertian[c]);
        else
            fprintf(fp, "%5.1f%%\t\t%.2f deg\n", 100 * (in->lambertian[c] + in->max_hemi[c]),
                    sqrt(in->min_proj_sa[c] / HD_PI) * 360 / HD_PI);
    }
    fprintf(fp, "Component\tReciprocity Error (min avg max %%)\n");
    static const char *const lab[3] = {"Interior Refl", "Exterior Refl", "Transmission"};
    for (int k = 0; k < 3; k++) {
        double mn, avg, mx;
        if (hd_bsdf_reciprocity(b, (hd_bsdf_comp)k, &mn, &avg, &mx))
            fprintf(fp, "%s\t%5.1f\t%5.1f\t%5.1f\n", lab[k], mn, avg, mx);
        else
            fprintf(fp, "%s\t%3d\t%3d\t%3d\n", lab[k], 0, 0, 0);
    }
    if (ferror(fp)) return hd_fail(HD_ERR_IO, "write error on the report of %s", path);
    return HD_OK;
}

void hd_xml_text(FILE *fp, const char *s)
{
    for (; s && *s; s++) {
        if (*s == '<') fputs("&lt;", fp);
        else if (*s == '>') fputs("&gt;", fp);
        else if (*s == '&') fputs("&amp;", fp);
        else fputc(*s, fp);
    }
}

void hd_xml_bsdf_head(FILE *fp, const char *lead, const char *comment, const char *tail, const char *name,
                      const char *manufacturer)
{
    fprintf(fp, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    if (comment) {
        fprintf(fp, "<!-- %s", lead);
        for (const char *s = comment; *s; s++)      /* no "--" inside comments */
            fputc(*s == '-' && s[1] == '-' ? '_' : *s, fp);
        fputs(tail, fp);
    }
    fprintf(fp, "<WindowElement xmlns=\"http://windows.lbl.gov\" "
            "xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" "
            "xsi:schemaLocation=\"http://windows.lbl.gov/BSDF-v1.4.xsd\">\n"
            "<WindowElementType>System</WindowElementType>\n<FileType>BSDF</FileType>\n"
            "<Optical>\n<Layer>\n\t<Material>\n\t\t<Name>");
    hd_xml_text(fp, name);
    fputs("</Name>\n\t\t<Manufacturer>", fp);
    hd_xml_text(fp, manufacturer);
    fputs("</Manufacturer>\n", fp);
}

void hd_xml_wavelength_head(FILE *fp, const char *direction, const char *kbasis, const char *type)
{
    fprintf(fp, "\t<WavelengthData>\n\t\t<LayerNumber>System</LayerNumber>\n"
            "\t\t<Wavelength unit=\"Integral\">Visible</Wavelength>\n"
            "\t\t<SourceSpectrum>CIE Illuminant D65 1nm.ssp</SourceSpectrum>\n"
            "\t\t<DetectorSpectrum>ASTM E308 1931 Y.dsp</DetectorSpectrum>\n"
            "\t\t<WavelengthDataBlock>\n"
            "\t\t\t<WavelengthDataDirection>%s</WavelengthDataDirection>\n", direction);
    if (kbasis)
        fprintf(fp, "\t\t\t<ColumnAngleBasis>%s</ColumnAngleBasis>\n\t\t\t<RowAngleBasis>%s</RowAngleBasis>\n",
                kbasis, kbasis);
    else
        fputs("\t\t\t<AngleBasis>LBNL/Shirley-Chiu</AngleBasis>\n", fp);
    fprintf(fp, "\t\t\t<ScatteringDataType>%s</ScatteringDataType>\n\t\t\t<ScatteringData>\n", type);
}

void hd_xml_wavelength_tail(FILE *fp)
{
    fputs("\t\t\t</ScatteringData>\n\t\t</WavelengthDataBlock>\n\t</WavelengthData>\n", fp);
}

hd_status hd_bsdf_write_klems_xml(FILE *fp, const hd_bsdf *b, const hd_klems_basis *kb,
                                  int nsamp, const char *comment)
{
    hd_klems_basis full;
    if (!kb) { hd_klems_standard(&full, HD_KLEMS_FULL); kb = &full; }
    const hd_bsdf_info *in = &b->info;
    hd_xml_bsdf_head(fp, "File produced by: ", comment, " -->\n", in->name, in->manufacturer);
    if (in->thickness > 0) fprintf(fp, "\t\t<Thickness unit=\"meter\">%g</Thickness>\n", in->thickness);
    fprintf(fp, "\t\t<DeviceType>Other</DeviceType>\n");
    if (in->width > 0) fprintf(fp, "\t\t<Width unit=\"meter\">%g</Width>\n", in->width);
    if (in->height > 0) fprintf(fp, "\t\t<Height unit=\"meter\">%g</Height>\n", in->height);
    fprintf(fp, "\t</Material>\n\t<Geometry></Geometry>\n\t<DataDefinition>\n");
    hd_klems_write_xml(fp, kb);
    int n = kb->nbins;
    double *vals = hd_malloc_array((size_t)n * (size_t)n, sizeof *vals);
    if (!vals) return HD_ERR_NOMEM;
    for (int c = 0; c < 4; c++) {
        if (!b->src[c] && b->lamb[c] <= 0) continue;
        hd_status st = hd_bsdf_klems_values(b, (hd_bsdf_comp)c, kb, nsamp, vals);
        if (st) { free(vals); return st; }
        hd_xml_wavelength_head(fp, hd_bsdf_window_name((hd_bsdf_comp)c), kb->name, c < 2 ? "BRDF" : "BTDF");
        for (int o = 0; o < n; o++) {
            for (int i = 0; i < n; i++)
                fprintf(fp, i ? " %.3e" : "\t%.3e", vals[(size_t)o * n + i]);
            fputc('\n', fp);
        }
        hd_xml_wavelength_tail(fp);
    }
    free(vals);
    fprintf(fp, "</Layer>\n</Optical>\n</WindowElement>\n");
    if (ferror(fp)) return hd_fail(HD_ERR_IO, "write error");
    return HD_OK;
}

int hd_bsdf_check_energy(const hd_bsdf *b, const char *path, double tol, int max_report, double *worst)
{
    hd_klems_basis kb;
    hd_klems_standard(&kb, HD_KLEMS_FULL);
    int nviol = 0;
    double wmax = 0;
    for (int side = 0; side < 2; side++)
        for (int i = 0; i < kb.nbins; i++) {
            /* light arriving from the room (+z) or the exterior (-z) */
            hd_vec3 v = hd_klems_dir(&kb, i, 0.5, 0.5);
            if (side) v.z = -v.z;
            double T = hd_bsdf_hemi(b, v, HD_BSDF_TRANS), R = hd_bsdf_hemi(b, v, HD_BSDF_REFL);
            if (T + R > wmax) wmax = T + R;
            if (!(T + R <= 1 + tol)) {
                if (nviol < max_report) {
                    double th = acos(fabs(v.z)) * 180 / HD_PI, ph = atan2(v.y, v.x) * 180 / HD_PI;
                    hd_warn("%s: light from the %s at theta %.1f phi %.1f deg (Klems bin %d): "
                            "T %.4f + R %.4f = %.4f exceeds 1 + %g", path, side ? "exterior" : "room",
                            th, ph < 0 ? ph + 360 : ph, i, T, R, T + R, tol);
                }
                nviol++;
            }
        }
    if (nviol > max_report)
        hd_warn("%s: %d incident directions in all with T + R > 1 + %g (largest %.4f)", path, nviol, tol, wmax);
    if (worst) *worst = wmax;
    return nviol;
}

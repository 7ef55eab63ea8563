/* Fuzz harness: BSDF XML (Klems, custom bases, tensor trees): load from
 * memory, then evaluate, sample, take pdfs, albedos and hemispherical
 * values in a few fixed directions. */
#include <math.h>
#include <stdio.h>

#include "fuzz.h"
#include "heliodon/bsdf.h"

static hd_vec3 dir_of(double th, double ph)
{
    return hd_v3(sin(th) * cos(ph), sin(th) * sin(ph), cos(th));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    hd_fuzz_setup();
    if (size > 1024 * 1024) return 0;
    hd_bsdf *b = NULL;
    if (hd_bsdf_load_memory((const char *)data, size, "fuzz.xml", &b) != HD_OK) {
        hd_bsdf_free(b);
        return 0;
    }
    (void)hd_bsdf_get_info(b);
    (void)hd_bsdf_memory(b);
    hd_bsdf_cache *c = hd_bsdf_cache_new(b, (size_t)4 << 20);
    static const double th[4] = {0.0, 0.5, 1.2, 1.55};
    double acc = 0;
    for (int i = 0; i < 4; i++) {
        hd_vec3 in = dir_of(th[i], 0.3 + i), inb = hd_v3(in.x, in.y, -in.z);
        for (int j = 0; j < 4; j++) {
            hd_vec3 out = dir_of(th[j], 2.0 - j), outb = hd_v3(out.x, out.y, -out.z);
            acc += hd_bsdf_eval(b, in, out) + hd_bsdf_eval(b, in, outb) + hd_bsdf_eval(b, inb, out);
            acc += hd_bsdf_cell_psa(b, in, outb);
        }
        acc += hd_bsdf_hemi(b, in, HD_BSDF_REFL | HD_BSDF_TRANS) + hd_bsdf_hemi(b, inb, HD_BSDF_TRANS);
        if (!c) continue;
        for (int mode = 0; mode < 2; mode++) {
            hd_vec3 g = i & 1 ? inb : in;
            acc += hd_bsdf_albedo(b, c, g, mode, HD_BSDF_REFL | HD_BSDF_TRANS);
            for (int k = 0; k < 3; k++) {
                hd_bsdf_sample s;
                double u = (k + 0.5) / 3.0;
                if (hd_bsdf_sample_dir(b, c, g, mode, HD_BSDF_REFL | HD_BSDF_TRANS, u, 1 - u, 0.37 * (k + 1), &s))
                    acc += s.weight + hd_bsdf_pdf(b, c, g, s.dir, mode, HD_BSDF_REFL | HD_BSDF_TRANS);
            }
        }
    }
    hd_bsdf_through t;
    if (hd_bsdf_find_through(b, hd_v3(0, 0, 1), &t)) acc += t.peak + t.surround + hd_bsdf_through_direct(b, &t, hd_v3(0, 0, 1), hd_v3(0, 0.1, -0.99), 6.8e-5);
    hd_bsdf_cache_free(c);
    hd_bsdf_free(b);
    /* keep the computation (results are not checked: any value is fine) */
    volatile double sink = acc;
    (void)sink;
    return 0;
}

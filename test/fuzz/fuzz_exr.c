/* Fuzz harness: OpenEXR files (through the OpenEXRCore decoder: scanline
 * and tiled parts, every compression it reads, channel layouts), then the
 * conversion to a Radiance picture as exr2hdr does it. */
#include "fuzz.h"
#include "heliodon/exr.h"
#include "heliodon/picture.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    hd_fuzz_setup();
    hd_exr_image img;
    hd_exr_init(&img);
    if (hd_exr_decode(data, size, "fuzz.exr", &img) == HD_OK) {
        char layers[512];
        hd_exr_list_layers(&img, layers, sizeof layers);
        hd_picture p;
        hd_picture_init(&p);
        if (hd_exr_to_picture(&img, NULL, &p) == HD_OK) {
            hd_header h;
            hd_header_init(&h);
            (void)hd_exr_header_add_primaries(&img, &h);
            hd_header_free(&h);
        }
        hd_picture_free(&p);
    }
    hd_exr_free(&img);
    return 0;
}

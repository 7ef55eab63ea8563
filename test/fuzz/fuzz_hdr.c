/* Fuzz harness: Radiance HDR pictures (header, resolution string, flat
 * and run-length scanlines, VIEW= and EXPOSURE lines) read from memory,
 * plus getinfo's raw-header and dimension readers. */
#include "fuzz.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/picture.h"
#include "heliodon/view.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    hd_fuzz_setup();
    hd_istream *s = NULL;
    if (hd_istream_memory(&s, data, size, "fuzz.hdr") != HD_OK) return 0;
    hd_picture p;
    if (hd_picture_read_stream(s, &p) == HD_OK) {
        hd_view v;
        hd_view_default(&v);
        int found = 0;
        if (hd_view_from_header(&v, &p.hdr, &found) == HD_OK && found && hd_view_setup(&v) == HD_OK) {
            hd_vec3 o, d;
            (void)hd_view_ray(&v, 0.5, 0.5, &o, &d);
        }
        (void)hd_header_exposure(&p.hdr);
        hd_picture_free(&p);
    }
    hd_istream_close(s);
    /* getinfo -d path: header text, then the dimensions */
    if (hd_istream_memory(&s, data, size, "fuzz.hdr") != HD_OK) return 0;
    char *text = NULL;
    size_t len = 0;
    if (hd_info_read_raw(s, &text, &len) == HD_OK) {
        char buf[256];
        (void)hd_info_dimensions(s, text, buf, sizeof buf);
    }
    free(text);
    hd_istream_close(s);
    return 0;
}

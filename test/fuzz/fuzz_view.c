/* Fuzz harness: view specifications (-vt? -vp -vd -vu -vh -vv -vo -va -vs
 * -vl as a line of words, as in view files and VIEW= header lines), then
 * the view setup, rays through the image and their inverse, the
 * formatted view and the image size for the view's aspect. */
#include <stdio.h>

#include "fuzz.h"
#include "heliodon/view.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    hd_fuzz_setup();
    if (size > 64 * 1024) return 0;
    char *text = hd_fuzz_cstr(data, size);
    /* -vf names a file to read: not this harness's job (ignored word) */
    for (char *q = strstr(text, "-vf"); q; q = strstr(q + 3, "-vf")) q[2] = 'x';
    hd_view v;
    hd_view_default(&v);
    /* every line is applied in order, as hd_view_read_file does */
    char *line = text, *nl;
    int bad = 0;
    do {
        nl = strchr(line, '\n');
        if (nl) *nl = 0;
        if (hd_view_parse_line(&v, line) < 0) bad = 1;
        if (nl) line = nl + 1;
    } while (nl && !bad);
    if (!bad && hd_view_setup(&v) == HD_OK) {
        double acc = 0;
        for (int i = 0; i < 5; i++)
            for (int j = 0; j < 5; j++) {
                hd_vec3 o, d;
                double x = i / 4.0, y = j / 4.0, px, py;
                if (hd_view_ray(&v, x, y, &o, &d) >= 0 && hd_view_loc(&v, d, &px, &py)) acc += px + py;
            }
        char buf[512];
        (void)hd_view_format(&v, buf, sizeof buf);
        double pa = 1;
        int xr = 512, yr = 512;
        hd_view_normaspect(hd_view_aspect(&v), &pa, &xr, &yr);
        volatile double sink = acc + pa + xr + yr;
        (void)sink;
    }
    free(text);
    return 0;
}

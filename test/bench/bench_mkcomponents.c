/* Benchmark helper: write K smooth synthetic component pictures
 * DIR/c%03d.hdr of XRES x YRES (deterministic), and report the machine's
 * memory copy bandwidth (for the "fraction of bandwidth" figure).
 * usage: bench_mkcomponents DIR K XRES YRES */
#include "heliodon/io.h"
#include "heliodon/picture.h"
#include "progress.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    if (argc != 5) { fprintf(stderr, "usage: %s DIR K XRES YRES\n", argv[0]); return 1; }
    int K = atoi(argv[2]), xr = atoi(argv[3]), yr = atoi(argv[4]);
    hd_picture p;
    hd_picture_init(&p);
    if (hd_picture_alloc(&p, xr, yr)) hd_die();
    for (int k = 0; k < K; k++) {
        double cx = 0.5 + 0.4 * cos(k * 0.7), cy = 0.5 + 0.4 * sin(k * 1.3);
        for (int y = 0; y < yr; y++)
            for (int x = 0; x < xr; x++) {
                double dx = (x + 0.5) / xr - cx, dy = (y + 0.5) / yr - cy;
                float v = (float)(1e-3 * exp(-(dx * dx + dy * dy) * 20) + 1e-5);
                float *px = p.pix + 3 * ((size_t)y * xr + x);
                px[0] = v; px[1] = v * 0.9f; px[2] = v * 0.8f;
            }
        char name[4096];
        snprintf(name, sizeof name, "%s/c%03d.hdr", argv[1], k);
        hd_header h;
        hd_header_init(&h);
        hd_header_add_command(&h, argc, argv);
        if (hd_picture_save(name, &p, &h)) hd_die();
        hd_header_free(&h);
    }
    hd_picture_free(&p);
    /* memory bandwidth: copy 512 MiB 4 times */
    size_t n = (size_t)256 << 20;
    char *a = malloc(n), *b = malloc(n);
    memset(a, 1, n);
    memset(b, 2, n);
    double t0 = hd_seconds();
    for (int i = 0; i < 4; i++) { memcpy(b, a, n); a[i] = b[n - 1 - i]; }
    double dt = hd_seconds() - t0;
    printf("memcpy_bandwidth_GBps %.2f\n", 4.0 * 2 * n / dt / 1e9); /* read + write */
    free(a);
    free(b);
    return 0;
}

/* Benchmark: OpenEXR encode/decode speed and file size of a 1024x1024 RGB
 * image (smooth gradient + noise, like a rendering) for each compression and
 * pixel type.  Prints one line per case. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "heliodon/exr.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(void)
{
    const int W = 1024, H = 1024, REP = 3;
    static const char *const rgb[3] = {"R", "G", "B"};
    static const hd_exr_compression comps[] = {HD_EXR_NONE, HD_EXR_ZIPS, HD_EXR_ZIP, HD_EXR_PIZ};
    static const hd_exr_pixtype types[] = {HD_EXR_FLOAT, HD_EXR_HALF};
    unsigned s = 1;
    printf("image %dx%d RGB, best of %d runs\n", W, H, REP);
    printf("%-6s %-5s %10s %12s %12s\n", "type", "comp", "bytes", "encode MB/s", "decode MB/s");
    for (int t = 0; t < 2; t++)
        for (int c = 0; c < 4; c++) {
            hd_exr_image img, back;
            hd_exr_init(&img);
            if (hd_exr_set_size(&img, W, H) != HD_OK)
                return 1;
            for (int k = 0; k < 3; k++) {
                int idx;
                if (hd_exr_add_channel(&img, rgb[k], types[t], &idx) != HD_OK)
                    return 1;
                for (int i = 0; i < W * H; i++) {
                    s = s * 1103515245u + 12345u;
                    double noise = 1.0 + 0.05 * ((s >> 16) / 65536.0 - 0.5);
                    img.chan[idx].data[i] = (float)((1.0 + k) * (1 + (i % W)) * (1 + i / W) * 1e-3 * noise);
                }
            }
            double best_e = 1e30, best_d = 1e30;
            size_t len = 0;
            for (int r = 0; r < REP; r++) {
                uint8_t *data;
                double t0 = now();
                if (hd_exr_encode(&img, comps[c], "bench", &data, &len) != HD_OK) {
                    fprintf(stderr, "bench_exr: %s\n", hd_errmsg());
                    return 1;
                }
                double t1 = now();
                hd_exr_init(&back);
                if (hd_exr_decode(data, len, "bench", &back) != HD_OK) {
                    fprintf(stderr, "bench_exr: %s\n", hd_errmsg());
                    return 1;
                }
                double t2 = now();
                hd_exr_free(&back);
                free(data);
                if (t1 - t0 < best_e)
                    best_e = t1 - t0;
                if (t2 - t1 < best_d)
                    best_d = t2 - t1;
            }
            double mb = W * (double)H * 3 * 4 / 1e6;   /* float pixels in memory */
            printf("%-6s %-5s %10zu %12.1f %12.1f\n", hd_exr_pixtype_name(types[t]),
                   hd_exr_compression_name(comps[c]), len, mb / best_e, mb / best_d);
            hd_exr_free(&img);
        }
    return 0;
}

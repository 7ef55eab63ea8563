/* Unit tests for the fast picture-encoding paths dctimestep uses: planar
 * RGBE encoding (SIMD where the CPU has AVX2) and the planar run-length
 * writer with its vector run search.  Both must give exactly the bytes of
 * the per-pixel encoder and of Radiance's fwritecolrs packet rules. */
#include "hd_test.h"
#include "heliodon/picture.h"
#include "heliodon/rng.h"

#include <float.h>
#include <stdint.h>

/* Planar RGBE == hd_rgbe_encode pixel by pixel, including black (<= 1e-32),
 * negatives, NaN, infinities, values >= 2^127 (clamped) and values
 * straddling the 1e-32 threshold, for lengths that are not multiples of the
 * vector width. */
static void test_rgbe_planar_equals_scalar(void)
{
    enum { N = 4099 };
    float *r = malloc(N * sizeof(float)), *g = malloc(N * sizeof(float)), *b = malloc(N * sizeof(float));
    uint8_t *pl = malloc(4 * N), *il = malloc(4 * N);
    REQUIRE(r && g && b && pl && il);
    hd_rng rng;
    hd_rng_init(&rng, 11, 0);
    const float special[] = {0.0f, -0.0f, 1e-32f, nextafterf(1e-32f, 1.0f), nextafterf(1e-32f, 0.0f), 1e-33f, -1.0f,
                             NAN, INFINITY, -INFINITY, FLT_MAX, 1.7e38f, 1.0e38f, 0.999f, 1.0f, 255.9f, 1e-38f,
                             FLT_MIN, 3e-39f, 0.5f};
    int ns = (int)(sizeof special / sizeof special[0]);
    for (int i = 0; i < N; i++) {
        float *c[3] = {r, g, b};
        for (int k = 0; k < 3; k++) {
            double u = hd_rng_uniform(&rng);
            if (u < 0.15) c[k][i] = special[(int)(hd_rng_uniform(&rng) * ns) % ns];
            else c[k][i] = (float)(pow(10.0, -40 + 80 * hd_rng_uniform(&rng)) * (u < 0.2 ? -1 : 1));
        }
        if (i % 97 == 0) r[i] = g[i] = b[i] = 0;
    }
    for (int n = 0; n <= 40; n++) { /* short and odd lengths */
        hd_rgbe_encode_planar_bytes(pl, r + n, g + n, b + n, (size_t)n);
        for (int i = 0; i < n; i++) {
            uint8_t q[4];
            hd_rgbe_encode(q, r[n + i], g[n + i], b[n + i]);
            for (int c = 0; c < 4; c++) CHECK(pl[(size_t)c * (size_t)n + (size_t)i] == q[c]);
        }
    }
    hd_rgbe_encode_planar_bytes(pl, r, g, b, N);
    hd_rgbe_encode_planar(il, r, g, b, N);
    int bad = 0;
    for (int i = 0; i < N; i++) {
        uint8_t q[4];
        hd_rgbe_encode(q, r[i], g[i], b[i]);
        for (int c = 0; c < 4; c++) {
            if (pl[(size_t)c * N + (size_t)i] != q[c] || il[4 * i + c] != q[c]) {
                if (bad++ < 5)
                    HD_T_FAILMSG("pixel %d (%g %g %g) component %d: planar %u interleaved %u, expected %u", i, r[i],
                                 g[i], b[i], c, pl[(size_t)c * N + (size_t)i], il[4 * i + c], q[c]);
            }
        }
    }
    CHECK(bad == 0);
    free(r);
    free(g);
    free(b);
    free(pl);
    free(il);
}

/* Radiance's packet rules written out independently, hopping over maximal
 * groups of equal bytes from j as fwritecolrs does. */
static size_t ref_plane(uint8_t *o0, const uint8_t *b, int len)
{
    uint8_t *o = o0;
    int j = 0, cnt = 1;
    while (j < len) {
        int beg;
        for (beg = j; beg < len; beg += cnt) {
            for (cnt = 1; cnt < 127 && beg + cnt < len && b[beg + cnt] == b[beg]; cnt++)
                ;
            if (cnt >= 4) break;
        }
        if (beg - j > 1 && beg - j < 4) {
            int k = j + 1;
            while (k < beg && b[k] == b[j]) k++;
            if (k == beg) { *o++ = (uint8_t)(128 + beg - j); *o++ = b[j]; j = beg; }
        }
        while (j < beg) {
            int n = beg - j > 128 ? 128 : beg - j;
            *o++ = (uint8_t)n;
            for (int k = 0; k < n; k++) *o++ = b[j + k];
            j += n;
        }
        if (cnt >= 4) { *o++ = (uint8_t)(128 + cnt); *o++ = b[beg]; j = beg + cnt; }
        else { cnt = 0; j = beg; }
    }
    return (size_t)(o - o0);
}

/* Planar and interleaved writers == the reference, on data with runs of
 * every length (1..300), literals, short runs before runs and at the end,
 * for scan lengths around the RLE limits and the 1024-pixel planar buffer
 * of the interleaved writer. */
static void test_rle_planar_equals_reference(void)
{
    const int lens[] = {16, 17, 18, 31, 33, 127, 128, 129, 255, 256, 257, 1000, 1023, 1024, 1025, 2048, 4099};
    hd_rng rng;
    hd_rng_init(&rng, 12, 0);
    int bad = 0, ncase = 0;
    for (size_t li = 0; li < sizeof lens / sizeof lens[0]; li++)
        for (int rep = 0; rep < 12; rep++) {
            int len = lens[li];
            uint8_t *pl = malloc(4 * (size_t)len), *il = malloc(4 * (size_t)len);
            size_t cap = hd_scanline_maxbytes(len) + 64;
            uint8_t *a = malloc(cap), *c = malloc(cap), *ref = malloc(cap);
            REQUIRE(pl && il && a && c && ref);
            for (int ch = 0; ch < 4; ch++) {
                int i = 0;
                while (i < len) { /* runs with a length distribution biased to 1..5 */
                    double u = hd_rng_uniform(&rng);
                    int run = rep == 0 ? len : u < 0.5 ? 1 : u < 0.8 ? 2 + (int)(hd_rng_uniform(&rng) * 4)
                                                                   : 1 + (int)(hd_rng_uniform(&rng) * 300);
                    uint8_t v = (uint8_t)(hd_rng_uniform(&rng) * (rep % 3 == 1 ? 3 : 256));
                    for (int k = 0; k < run && i < len; k++, i++) pl[(size_t)ch * (size_t)len + (size_t)i] = v;
                }
            }
            for (int i = 0; i < len; i++)
                for (int ch = 0; ch < 4; ch++) il[4 * i + ch] = pl[(size_t)ch * (size_t)len + (size_t)i];
            size_t na = hd_scanline_encode_planar(a, pl, len);
            size_t nc = hd_scanline_encode(c, il, len);
            size_t nr;
            if (len < 17 || len > 32767) {
                memcpy(ref, il, 4 * (size_t)len);
                nr = 4 * (size_t)len;
            } else {
                ref[0] = 2; ref[1] = 2; ref[2] = (uint8_t)(len >> 8); ref[3] = (uint8_t)(len & 0xff);
                nr = 4;
                for (int ch = 0; ch < 4; ch++) nr += ref_plane(ref + nr, pl + (size_t)ch * (size_t)len, len);
            }
            ncase++;
            if (na != nr || nc != nr || memcmp(a, ref, nr) || memcmp(c, ref, nr)) {
                if (bad++ < 3) HD_T_FAILMSG("len %d case %d: planar %zu interleaved %zu reference %zu bytes", len, rep, na, nc, nr);
            }
            CHECK(nr <= hd_scanline_maxbytes(len));
            /* decoding gives the pixels back */
            hd_istream *s;
            uint8_t *back = malloc(4 * (size_t)len);
            REQUIRE(back);
            if (hd_istream_memory(&s, a, na, "rle") == HD_OK) {
                CHECK(hd_scanline_read(s, back, len) == HD_OK);
                CHECK(!memcmp(back, il, 4 * (size_t)len));
                hd_istream_close(s);
            }
            free(back);
            free(pl);
            free(il);
            free(a);
            free(c);
            free(ref);
        }
    CHECK(bad == 0);
    CHECK(ncase == 17 * 12);
}

int main(void)
{
    RUN(test_rgbe_planar_equals_scalar);
    RUN(test_rle_planar_equals_reference);
    return hd_test_done();
}

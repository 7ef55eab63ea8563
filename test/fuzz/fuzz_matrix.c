/* Fuzz harness: Radiance matrix files, with a header (ascii, float,
 * double in both byte orders, RGBE/XYZE pictures) and without one (-h
 * input as rmtxop/dctimestep read it: the first four bytes of the input
 * pick the format and dimensions, the rest is the data). */
#include "fuzz.h"
#include "heliodon/io.h"
#include "heliodon/matrix.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    hd_fuzz_setup();
    hd_matrix_readopts o = {0, 0, 0, -1};
    if (size >= 4 && data[0] == 'H') {   /* headerless */
        o.fmt = data[1] % 5;
        o.ncols = 1 + data[2] % 16;
        o.nrows = data[3] % 17;          /* 0: as many rows as the data hold */
        o.ncomp = data[3] >> 4 & 3;      /* 0: 3 */
        data += 4;
        size -= 4;
    }
    hd_istream *s = NULL;
    if (hd_istream_memory(&s, data, size, "fuzz.mtx") != HD_OK) return 0;
    hd_matrix m;
    if (hd_matrix_read_stream(s, &m, &o) == HD_OK) {
        hd_matrix t;
        hd_matrix_init(&t);
        /* The product is nrows x nrows: bound its work (rows^2 * cols) so
         * that a tall one-column input does not cost a 4096^2 product. */
        if ((size_t)m.nrows * (size_t)m.ncols <= 4096 &&
            (size_t)m.nrows * (size_t)m.nrows * (size_t)m.ncols <= 65536 &&
            hd_matrix_transpose(&t, &m) == HD_OK) {
            hd_matrix p;
            hd_matrix_init(&p);
            (void)hd_matrix_multiply(&p, &m, &t);
            hd_matrix_free(&p);
        }
        hd_matrix_free(&t);
    }
    hd_matrix_free(&m);
    hd_istream_close(s);
    return 0;
}

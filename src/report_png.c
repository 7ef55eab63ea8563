/* heliodon — minimal PNG writer/reader for the report (zlib). */
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "heliodon/io.h"
#include "heliodon/report.h"

static void put32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
}

static uint32_t get32(const uint8_t *p)
{
    return ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | p[3];
}

static int write_chunk(FILE *fp, const char *type, const uint8_t *data, size_t len)
{
    uint8_t b[8];
    put32(b, (uint32_t)len);
    memcpy(b + 4, type, 4);
    uLong crc = crc32(0L, (const Bytef *)type, 4);
    if (len) crc = crc32(crc, data, (uInt)len);
    uint8_t c[4];
    put32(c, (uint32_t)crc);
    return fwrite(b, 1, 8, fp) == 8 && (len == 0 || fwrite(data, 1, len, fp) == len) && fwrite(c, 1, 4, fp) == 4;
}

hd_status hd_png_write(const char *path, const uint8_t *rgb, int w, int h)
{
    if (w <= 0 || h <= 0 || w > 100000 || h > 100000)
        return hd_fail(HD_ERR_RANGE, "%s: PNG size %d x %d out of range", path, w, h);
    size_t stride = (size_t)w * 3 + 1, raw_len = stride * (size_t)h;
    uint8_t *raw = hd_malloc(raw_len);
    uLongf zlen = compressBound((uLong)raw_len);
    uint8_t *z = hd_malloc(zlen);
    if (!raw || !z) {
        free(raw);
        free(z);
        return HD_ERR_NOMEM;
    }
    for (int y = 0; y < h; y++) {
        raw[y * stride] = 0;
        memcpy(raw + y * stride + 1, rgb + (size_t)y * w * 3, (size_t)w * 3);
    }
    if (compress2(z, &zlen, raw, (uLong)raw_len, 6) != Z_OK) {
        free(raw);
        free(z);
        return hd_fail(HD_ERR_IO, "%s: zlib compression failed", path);
    }
    free(raw);
    hd_ofile *of;
    hd_status st = hd_ofile_open(&of, path);
    if (st) {
        free(z);
        return st;
    }
    FILE *fp = hd_ofile_fp(of);
    static const uint8_t sig[8] = {137, 80, 78, 71, 13, 10, 26, 10};
    uint8_t ihdr[13];
    put32(ihdr, (uint32_t)w);
    put32(ihdr + 4, (uint32_t)h);
    ihdr[8] = 8;   /* bit depth */
    ihdr[9] = 2;   /* truecolour */
    ihdr[10] = ihdr[11] = ihdr[12] = 0;
    int ok = fwrite(sig, 1, 8, fp) == 8 && write_chunk(fp, "IHDR", ihdr, 13) && write_chunk(fp, "IDAT", z, zlen) &&
             write_chunk(fp, "IEND", NULL, 0);
    free(z);
    if (!ok) {
        hd_ofile_abort(of);
        return hd_fail(HD_ERR_IO, "%s: write error", path);
    }
    return hd_ofile_commit(of);
}

static int paeth(int a, int b, int c)
{
    int p = a + b - c, pa = abs(p - a), pb = abs(p - b), pc = abs(p - c);
    return (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
}

hd_status hd_png_read(const char *path, uint8_t **rgb, int *w, int *h)
{
    hd_istream *s;
    hd_status st = hd_istream_open(&s, path);
    if (st) return st;
    uint8_t sig[8];
    static const uint8_t want[8] = {137, 80, 78, 71, 13, 10, 26, 10};
    if (hd_istream_read(s, sig, 8) != 8 || memcmp(sig, want, 8)) {
        hd_istream_close(s);
        return hd_fail(HD_ERR_FORMAT, "%s: not a PNG file (bad signature)", path);
    }
    uint8_t *idat = NULL;
    size_t nidat = 0;
    int W = 0, H = 0, ctype = -1, seen_end = 0;
    while (!seen_end) {
        uint8_t b[8];
        uint64_t off = hd_istream_offset(s);
        if (hd_istream_read(s, b, 8) != 8) {
            st = hd_fail(HD_ERR_FORMAT, "%s: byte %llu: truncated before IEND", path, (unsigned long long)off);
            break;
        }
        uint32_t len = get32(b);
        if (len > (1u << 30)) {
            st = hd_fail(HD_ERR_FORMAT, "%s: byte %llu: absurd chunk length %u", path, (unsigned long long)off, len);
            break;
        }
        uint8_t *data = hd_malloc(len + 4 ? len + 4 : 4);
        if (!data) {
            st = HD_ERR_NOMEM;
            break;
        }
        if (hd_istream_read(s, data, len + 4) != len + 4) {
            free(data);
            st = hd_fail(HD_ERR_FORMAT, "%s: byte %llu: truncated %.4s chunk", path, (unsigned long long)off, b + 4);
            break;
        }
        uLong crc = crc32(crc32(0L, b + 4, 4), data, len);
        if ((uint32_t)crc != get32(data + len)) {
            free(data);
            st = hd_fail(HD_ERR_FORMAT, "%s: byte %llu: CRC mismatch in %.4s chunk", path, (unsigned long long)off, b + 4);
            break;
        }
        if (!memcmp(b + 4, "IHDR", 4) && len == 13) {
            W = (int)get32(data);
            H = (int)get32(data + 4);
            ctype = data[9];
            if (data[8] != 8 || (ctype != 2 && ctype != 6) || data[12] != 0 || W <= 0 || H <= 0 || W > 100000 ||
                H > 100000) {
                free(data);
                st = hd_fail(HD_ERR_UNSUPPORTED, "%s: only 8-bit RGB/RGBA non-interlaced PNG is supported", path);
                break;
            }
        } else if (!memcmp(b + 4, "IDAT", 4)) {
            uint8_t *n2 = realloc(idat, nidat + len + 1);
            if (!n2) {
                free(data);
                st = HD_ERR_NOMEM;
                break;
            }
            idat = n2;
            memcpy(idat + nidat, data, len);
            nidat += len;
        } else if (!memcmp(b + 4, "IEND", 4)) {
            seen_end = 1;
        }
        free(data);
    }
    hd_istream_close(s);
    if (!st && (ctype < 0 || !nidat)) st = hd_fail(HD_ERR_FORMAT, "%s: missing IHDR or IDAT", path);
    if (st) {
        free(idat);
        return st;
    }
    int bpp = ctype == 6 ? 4 : 3;
    size_t stride = (size_t)W * bpp + 1;
    uLongf rlen = (uLongf)(stride * (size_t)H);
    uint8_t *raw = hd_malloc(rlen ? rlen : 1);
    if (!raw) {
        free(idat);
        return HD_ERR_NOMEM;
    }
    uLongf got = rlen;
    int zr = uncompress(raw, &got, idat, (uLong)nidat);
    free(idat);
    if (zr != Z_OK || got != rlen) {
        free(raw);
        return hd_fail(HD_ERR_FORMAT, "%s: image data does not inflate to %d x %d pixels", path, W, H);
    }
    /* unfilter in place */
    for (int y = 0; y < H; y++) {
        uint8_t *row = raw + (size_t)y * stride, *cur = row + 1;
        const uint8_t *prev = y ? raw + (size_t)(y - 1) * stride + 1 : NULL;
        int f = row[0];
        if (f > 4) {
            free(raw);
            return hd_fail(HD_ERR_FORMAT, "%s: row %d: bad filter type %d", path, y, f);
        }
        for (size_t x = 0; x < (size_t)W * bpp; x++) {
            int a = x >= (size_t)bpp ? cur[x - bpp] : 0, bb = prev ? prev[x] : 0,
                c = (prev && x >= (size_t)bpp) ? prev[x - bpp] : 0;
            int add = f == 0 ? 0 : f == 1 ? a : f == 2 ? bb : f == 3 ? (a + bb) / 2 : paeth(a, bb, c);
            cur[x] = (uint8_t)(cur[x] + add);
        }
    }
    if (rgb) {
        uint8_t *out = hd_malloc_array((size_t)W * H, 3);
        if (!out) {
            free(raw);
            return HD_ERR_NOMEM;
        }
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++)
                memcpy(out + ((size_t)y * W + x) * 3, raw + (size_t)y * stride + 1 + (size_t)x * bpp, 3);
        *rgb = out;
    }
    free(raw);
    *w = W;
    *h = H;
    return HD_OK;
}

/* heliodon — Radiance HDR pictures: resolution strings, RGBE/XYZE pixels,
 * flat / old run-length / new run-length scanlines, whole-picture read and
 * write in any of the 8 orientations, and the header helpers getinfo uses.
 *
 * Byte compatibility notes (see docs/design/picture.md):
 *  - pixel encoding follows Radiance's setcolr exactly (the scale factor
 *    frexp(d)*256/d is always the power of two 2^(8-E), so it is computed
 *    from the exponent bits without frexp; the result is identical);
 *  - decoding adds 0.5 to each mantissa as Radiance's colr_color;
 *  - the run-length writer reproduces Radiance's fwritecolrs packet choice
 *    byte for byte (runs of >= 4, short runs of 2-3 only right before a
 *    run, literals of at most 128), and only for 17..32767-pixel scanlines;
 *  - the reader accepts what Radiance's freadcolrs accepts, but refuses
 *    packets that overrun the scanline and old-style repeat markers with no
 *    pixel to repeat instead of corrupting memory. */
#include "heliodon/picture.h"

#include <ctype.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#define MINELEN 17      /* shortest scanline written run-length encoded */
#define MAXELEN 0x7fff  /* longest */
#define MINRUN 4        /* shortest run written as a run packet */

static const char FMT_RGBE[] = "32-bit_rle_rgbe";
static const char FMT_XYZE[] = "32-bit_rle_xyze";

/* ------------------------------------------------------------------ */
/* resolution strings                                                  */

int hd_resolu_scanlen(const hd_resolu *r)
{
    return (r->orient & HD_RES_YMAJOR) ? r->xres : r->yres;
}

int hd_resolu_nscans(const hd_resolu *r)
{
    return (r->orient & HD_RES_YMAJOR) ? r->yres : r->xres;
}

void hd_resolu_pixel(const hd_resolu *r, int scan, int pos, int *x, int *y)
{
    int px, py;
    if (r->orient & HD_RES_YMAJOR) { px = pos; py = scan; }
    else { px = scan; py = pos; }
    if (r->orient & HD_RES_XDECR) px = r->xres - 1 - px;
    if (r->orient & HD_RES_YDECR) py = r->yres - 1 - py;
    *x = px;
    *y = py;
}

int hd_resolu_format(char *buf, size_t cap, const hd_resolu *r)
{
    char xs = (r->orient & HD_RES_XDECR) ? '-' : '+';
    char ys = (r->orient & HD_RES_YDECR) ? '-' : '+';
    if (r->orient & HD_RES_YMAJOR)
        return snprintf(buf, cap, "%cY %8d %cX %8d\n", ys, r->yres, xs, r->xres);
    return snprintf(buf, cap, "%cX %8d %cY %8d\n", xs, r->xres, ys, r->yres);
}

hd_status hd_resolu_check(const hd_resolu *r, const char *what)
{
    if (r->orient < 0 || r->orient > 7)
        return hd_fail(HD_ERR_RANGE, "%s: invalid picture orientation %d", what, r->orient);
    if (r->xres <= 0 || r->yres <= 0)
        return hd_fail(HD_ERR_RANGE, "%s: picture size %d x %d must be positive",
                       what, r->xres, r->yres);
    if (r->xres > HD_PIC_MAXSIDE || r->yres > HD_PIC_MAXSIDE ||
        (int64_t)r->xres * r->yres > HD_PIC_MAXPIXELS)
        return hd_fail(HD_ERR_RANGE,
                       "%s: picture size %d x %d is too large (at most %d pixels a side "
                       "and %lld pixels)", what, r->xres, r->yres, HD_PIC_MAXSIDE,
                       (long long)HD_PIC_MAXPIXELS);
    return HD_OK;
}

/* one "[+-][XY] <int>" field; returns the position after it or NULL */
static const char *parse_axis(const char *p, char *axis, int *sign, long *val)
{
    while (*p == ' ' || *p == '\t') p++;
    if (*p != '+' && *p != '-') return NULL;
    *sign = *p++ == '-' ? -1 : 1;
    if (*p != 'X' && *p != 'Y') return NULL;
    *axis = *p++;
    while (*p == ' ' || *p == '\t') p++;
    if (!isdigit((unsigned char)*p)) return NULL;
    long v = 0;
    while (isdigit((unsigned char)*p)) {
        if (v < 100000000000L) v = v * 10 + (*p - '0');
        p++;
    }
    *val = v;
    return p;
}

hd_status hd_resolu_parse(const char *line, hd_resolu *r, const char *what)
{
    char a1 = 0, a2 = 0;
    int s1 = 0, s2 = 0;
    long v1 = 0, v2 = 0;
    const char *p = parse_axis(line, &a1, &s1, &v1);
    if (p) p = parse_axis(p, &a2, &s2, &v2);
    if (p) {
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n') p++;
        if (*p) p = NULL;
    }
    if (!p || a1 == a2) {
        char shown[80];
        size_t n = 0;
        for (const char *q = line; *q && *q != '\n' && n < sizeof shown - 4; q++)
            shown[n++] = isprint((unsigned char)*q) ? *q : '?';
        if (line[n] && line[n] != '\n') { shown[n++] = '.'; shown[n++] = '.'; shown[n++] = '.'; }
        shown[n] = 0;
        return hd_fail(HD_ERR_FORMAT,
                       "%s: bad resolution string \"%s\" (expected e.g. \"-Y 512 +X 768\")",
                       what, shown);
    }
    r->orient = 0;
    if (a1 == 'Y') r->orient |= HD_RES_YMAJOR;
    long xv = a1 == 'X' ? v1 : v2, yv = a1 == 'Y' ? v1 : v2;
    int xs = a1 == 'X' ? s1 : s2, ys = a1 == 'Y' ? s1 : s2;
    if (xs < 0) r->orient |= HD_RES_XDECR;
    if (ys < 0) r->orient |= HD_RES_YDECR;
    if (xv > HD_PIC_MAXSIDE || yv > HD_PIC_MAXSIDE || xv <= 0 || yv <= 0 ||
        xv * yv > HD_PIC_MAXPIXELS) {
        return hd_fail(HD_ERR_RANGE,
                       "%s: picture size %ld x %ld is out of range (1 to %d pixels a side, "
                       "at most %lld pixels)", what, xv, yv, HD_PIC_MAXSIDE,
                       (long long)HD_PIC_MAXPIXELS);
    }
    r->xres = (int)xv;
    r->yres = (int)yv;
    return HD_OK;
}

hd_status hd_resolu_read(hd_istream *s, hd_resolu *r)
{
    char line[128], what[600];
    uint64_t off = hd_istream_offset(s);
    long n = hd_istream_getline(s, line, sizeof line);
    snprintf(what, sizeof what, "%s: byte offset %llu", hd_istream_name(s),
             (unsigned long long)off);
    if (n == -1)
        return hd_fail(HD_ERR_FORMAT, "%s: unexpected end of data, expected the "
                       "resolution string (e.g. \"-Y 512 +X 768\")", what);
    if (n == -2)
        return hd_fail(HD_ERR_FORMAT, "%s: bad resolution string (line too long; expected "
                       "e.g. \"-Y 512 +X 768\")", what);
    if (hd_istream_failed(s))
        return hd_fail(HD_ERR_IO, "%s: read error", what);
    return hd_resolu_parse(line, r, what);
}

/* ------------------------------------------------------------------ */
/* pixels                                                              */

static inline float f_from_bits(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* 2^(e-136) as a float (0 for e == 0): normal for e >= 10, subnormal below */
static inline float exp_scale(unsigned e)
{
    uint32_t bits = e >= 10 ? (uint32_t)(e - 9) << 23 : e ? (uint32_t)1 << (e + 13) : 0;
    return f_from_bits(bits);
}

static inline void encode1(uint8_t *out, float r, float g, float b)
{
    float d = r > g ? r : g;
    if (b > d) d = b;
    if (!((double)d > 1e-32)) { /* also NaN */
        out[0] = out[1] = out[2] = out[3] = 0;
        return;
    }
    uint32_t bits;
    memcpy(&bits, &d, sizeof bits);
    int be = (int)((bits >> 23) & 0xff);   /* d > 1e-32: a normal number or inf */
    int E = be - 126;                      /* frexp exponent: d = f * 2^E, f in [.5,1) */
    if (E > 127) {                         /* >= 2^127 or inf: clamp (Radiance wraps) */
        float sc = f_from_bits((uint32_t)(8 - 127 + 127) << 23);
        float m;
        m = r > 0.0f ? r * sc : 0.0f; out[0] = m >= 255.0f ? 255 : (uint8_t)m;
        m = g > 0.0f ? g * sc : 0.0f; out[1] = m >= 255.0f ? 255 : (uint8_t)m;
        m = b > 0.0f ? b * sc : 0.0f; out[2] = m >= 255.0f ? 255 : (uint8_t)m;
        out[3] = 255;
        return;
    }
    float sc = f_from_bits((uint32_t)(8 - E + 127) << 23);   /* 2^(8-E), exact */
    /* c * 2^(8-E) < 256 for every channel c <= d; fmaxf maps negatives and
     * NaN to 0 (Radiance: "if (c > 0) ... else 0") */
    out[0] = (uint8_t)(fmaxf(r, 0.0f) * sc);
    out[1] = (uint8_t)(fmaxf(g, 0.0f) * sc);
    out[2] = (uint8_t)(fmaxf(b, 0.0f) * sc);
    out[3] = (uint8_t)(E + 128);
}

void hd_rgbe_encode(uint8_t out[4], float r, float g, float b)
{
    encode1(out, r, g, b);
}

void hd_rgbe_decode(const uint8_t in[4], float rgb[3])
{
    float f = exp_scale(in[3]);
    rgb[0] = ((float)in[0] + 0.5f) * f;
    rgb[1] = ((float)in[1] + 0.5f) * f;
    rgb[2] = ((float)in[2] + 0.5f) * f;
}

void hd_rgbe_encode_n(uint8_t *rgbe, const float *rgb, size_t n)
{
    for (size_t i = 0; i < n; i++) encode1(rgbe + 4 * i, rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]);
}

void hd_rgbe_encode_planar(uint8_t *rgbe, const float *r, const float *g, const float *b, size_t n)
{
    for (size_t i = 0; i < n; i++) encode1(rgbe + 4 * i, r[i], g[i], b[i]);
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define HD_PIC_X86 1
#include <immintrin.h>
/* 8 pixels at a time, the same bytes as encode1: d = max as encode1's
 * comparisons (maxps(a,b) is a > b ? a : b), "d > thr" is "(double)d >
 * 1e-32", the scale 2^(8-E) built from the exponent bits; groups holding a
 * value >= 2^127 (clamped) go through encode1.  Returns pixels done. */
__attribute__((target("avx2"))) static size_t planar_bytes_avx2(uint8_t *pl, const float *r, const float *g,
                                                                const float *b, size_t n, float thr)
{
    const __m256 zero = _mm256_setzero_ps(), vthr = _mm256_set1_ps(thr);
    const __m256i emask = _mm256_set1_epi32(0xff), c261 = _mm256_set1_epi32(261), two = _mm256_set1_epi32(2),
                  c253 = _mm256_set1_epi32(253), perm = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        __m256 vr = _mm256_loadu_ps(r + i), vg = _mm256_loadu_ps(g + i), vb = _mm256_loadu_ps(b + i);
        __m256 d = _mm256_max_ps(vb, _mm256_max_ps(vr, vg));
        __m256 valid = _mm256_cmp_ps(d, vthr, _CMP_GT_OQ);
        __m256i be = _mm256_and_si256(_mm256_srli_epi32(_mm256_castps_si256(d), 23), emask);
        if (_mm256_movemask_ps(_mm256_and_ps(valid, _mm256_castsi256_ps(_mm256_cmpgt_epi32(be, c253))))) {
            for (size_t k = i; k < i + 8; k++) {
                uint8_t q[4];
                encode1(q, r[k], g[k], b[k]);
                for (int c = 0; c < 4; c++) pl[(size_t)c * n + k] = q[c];
            }
            continue;
        }
        __m256 sc = _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_sub_epi32(c261, be), 23));
        __m256i vi = _mm256_castps_si256(valid);
        __m256i ri = _mm256_and_si256(vi, _mm256_cvttps_epi32(_mm256_mul_ps(_mm256_max_ps(vr, zero), sc)));
        __m256i gi = _mm256_and_si256(vi, _mm256_cvttps_epi32(_mm256_mul_ps(_mm256_max_ps(vg, zero), sc)));
        __m256i bi = _mm256_and_si256(vi, _mm256_cvttps_epi32(_mm256_mul_ps(_mm256_max_ps(vb, zero), sc)));
        __m256i ei = _mm256_and_si256(vi, _mm256_add_epi32(be, two));
        __m256i bytes = _mm256_packus_epi16(_mm256_packus_epi32(ri, gi), _mm256_packus_epi32(bi, ei));
        bytes = _mm256_permutevar8x32_epi32(bytes, perm);
        uint64_t q[4];
        _mm256_storeu_si256((__m256i *)(void *)q, bytes);
        for (int c = 0; c < 4; c++) memcpy(pl + (size_t)c * n + i, &q[c], 8);
    }
    return i;
}
#else
#define HD_PIC_X86 0
#endif

void hd_rgbe_encode_planar_bytes(uint8_t *pl, const float *r, const float *g, const float *b, size_t n)
{
    size_t i = 0;
#if HD_PIC_X86
    if (hd_cpu_level() >= 1) {
        float thr = (float)1e-32;
        if ((double)thr > 1e-32) thr = nextafterf(thr, 0.0f);
        i = planar_bytes_avx2(pl, r, g, b, n, thr);
    }
#endif
    for (; i < n; i++) {
        uint8_t q[4];
        encode1(q, r[i], g[i], b[i]);
        for (int c = 0; c < 4; c++) pl[(size_t)c * n + i] = q[c];
    }
}

void hd_rgbe_decode_n(float *rgb, const uint8_t *rgbe, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        const uint8_t *c = rgbe + 4 * i;
        float f = exp_scale(c[3]);
        rgb[3 * i] = ((float)c[0] + 0.5f) * f;
        rgb[3 * i + 1] = ((float)c[1] + 0.5f) * f;
        rgb[3 * i + 2] = ((float)c[2] + 0.5f) * f;
    }
}

double hd_rgb_bright(const float rgb[3])
{
    return 0.265074126 * rgb[0] + 0.670114631 * rgb[1] + 0.064811243 * rgb[2];
}

double hd_rgb_bright_rad(const float rgb[3])
{
    return 0.26510582010582007 * rgb[0] + 0.67010582010581987 * rgb[1] + 0.064788359788359784 * rgb[2];
}

/* ------------------------------------------------------------------ */
/* scanline decoding                                                   */

/* Byte source: a memory window (s == NULL or mem set) or a stream. */
typedef struct bsrc {
    const uint8_t *p, *end, *start;
    uint64_t base;          /* stream offset of start (memory mode) */
    hd_istream *s;
    int mem;
    const char *name;
} bsrc;

enum { DEC_OK = 0, DEC_SHORT = 1, DEC_BAD = 2 };

static inline int bs_getc(bsrc *b)
{
    if (b->mem) return b->p < b->end ? *b->p++ : EOF;
    return hd_istream_getc(b->s);
}

static inline int bs_read(bsrc *b, uint8_t *dst, size_t n)
{
    if (b->mem) {
        if ((size_t)(b->end - b->p) < n) return 0;
        memcpy(dst, b->p, n);
        b->p += n;
        return 1;
    }
    return hd_istream_read(b->s, dst, n) == n;
}

static uint64_t bs_offset(const bsrc *b)
{
    return b->mem ? b->base + (uint64_t)(b->p - b->start) : hd_istream_offset(b->s);
}

static _Thread_local char scan_where[64];
static const char *scanname(int scan)
{
    if (scan < 0) return "";
    snprintf(scan_where, sizeof scan_where, " in scanline %d", scan);
    return scan_where;
}

static int old_decode(bsrc *b, uint8_t *sl, int len, int j, int scan)
{
    int shift = 0;
    while (j < len) {
        uint8_t px[4];
        uint64_t off = bs_offset(b);
        if (!bs_read(b, px, 4)) return DEC_SHORT;
        if (px[0] == 1 && px[1] == 1 && px[2] == 1) {   /* repeat marker */
            uint64_t cnt;
            if (shift >= 32) cnt = px[3] ? UINT64_MAX : 0;
            else cnt = (uint64_t)px[3] << shift;
            if (cnt && j == 0) {
                hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: old-style run-length marker "
                        "at the start of a scanline (no pixel to repeat)%s", b->name,
                        (unsigned long long)off, scanname(scan));
                return DEC_BAD;
            }
            if (cnt > (uint64_t)(len - j)) {
                hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: old-style run of %llu pixels "
                        "overruns the scanline (%d of %d pixels filled)%s", b->name,
                        (unsigned long long)off, (unsigned long long)cnt, j, len,
                        scanname(scan));
                return DEC_BAD;
            }
            uint32_t prev;
            if (cnt) memcpy(&prev, sl + 4 * (j - 1), 4);
            for (uint64_t k = 0; k < cnt; k++, j++) memcpy(sl + 4 * j, &prev, 4);
            if (shift < 64) shift += 8;
        } else {
            memcpy(sl + 4 * j, px, 4);
            j++;
            shift = 0;
        }
    }
    return DEC_OK;
}

static int scan_decode(bsrc *b, uint8_t *sl, int len, int scan)
{
    if (len < MINELEN || len > MAXELEN) return old_decode(b, sl, len, 0, scan);
    uint8_t h[4];
    uint64_t off0 = bs_offset(b);
    if (!bs_read(b, h, 4)) return DEC_SHORT;
    if (h[0] != 2 || h[1] != 2 || (h[2] & 0x80)) {
        memcpy(sl, h, 4);
        return old_decode(b, sl, len, 1, scan);
    }
    int rl = h[2] << 8 | h[3];
    if (rl != len) {
        hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: run-length scanline of %d pixels in a "
                "picture whose scanlines have %d pixels%s", b->name,
                (unsigned long long)off0, rl, len, scanname(scan));
        return DEC_BAD;
    }
    for (int c = 0; c < 4; c++) {
        uint8_t *o = sl + c;
        int j = 0;
        while (j < len) {
            int code = bs_getc(b);
            if (code == EOF) return DEC_SHORT;
            if (code > 128) {
                int n = code & 127;
                int v = bs_getc(b);
                if (v == EOF) return DEC_SHORT;
                if (j + n > len) {
                    hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: run of %d bytes overruns "
                            "the scanline (component %d, %d of %d pixels filled)%s", b->name,
                            (unsigned long long)(bs_offset(b) - 2), n, c, j, len,
                            scanname(scan));
                    return DEC_BAD;
                }
                for (int k = 0; k < n; k++) o[4 * (j + k)] = (uint8_t)v;
                j += n;
            } else {
                if (j + code > len) {
                    hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: literal of %d bytes "
                            "overruns the scanline (component %d, %d of %d pixels filled)%s",
                            b->name, (unsigned long long)(bs_offset(b) - 1), code, c, j, len,
                            scanname(scan));
                    return DEC_BAD;
                }
                if (b->mem) {
                    if (b->end - b->p < code) return DEC_SHORT;
                    const uint8_t *q = b->p;
                    for (int k = 0; k < code; k++) o[4 * (j + k)] = q[k];
                    b->p += code;
                } else {
                    uint8_t tmp[128];
                    if (!bs_read(b, tmp, (size_t)code)) return DEC_SHORT;
                    for (int k = 0; k < code; k++) o[4 * (j + k)] = tmp[k];
                }
                j += code;
            }
        }
    }
    return DEC_OK;
}

hd_status hd_scanline_read(hd_istream *s, uint8_t *rgbe, int len)
{
    bsrc b = {0};
    b.s = s;
    b.name = hd_istream_name(s);
    if (len <= 0) return hd_fail(HD_ERR_RANGE, "%s: bad scanline length %d", b.name, len);
    int r = scan_decode(&b, rgbe, len, -1);
    if (r == DEC_OK) return HD_OK;
    if (r == DEC_BAD) return HD_ERR_FORMAT;
    if (hd_istream_failed(s))
        return hd_fail(HD_ERR_IO, "%s: byte offset %llu: read error in a scanline", b.name,
                       (unsigned long long)hd_istream_offset(s));
    return hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: unexpected end of data in a "
                   "scanline of %d pixels", b.name,
                   (unsigned long long)hd_istream_offset(s), len);
}

/* ------------------------------------------------------------------ */
/* scanline encoding                                                   */

size_t hd_scanline_maxbytes(int len)
{
    if (len <= 0) return 0;
    if (len < MINELEN || len > MAXELEN) return (size_t)len * 4;
    return 4 + 4 * ((size_t)len + (size_t)len / 128 + 4);
}

/* First p in [j, len-3) where plane bytes p..p+3 are equal, or len.  (The
 * first such window is also where Radiance's fwritecolrs, which hops over
 * maximal groups of equal bytes from j, finds its run.) */
static int find_run(const uint8_t *b, size_t stride, int j, int len)
{
    int p = j;
#if defined(__SSE2__)
    for (; stride == 1 && p + 19 <= len; p += 16) {
        __m128i v0 = _mm_loadu_si128((const __m128i *)(const void *)(b + p));
        __m128i v1 = _mm_loadu_si128((const __m128i *)(const void *)(b + p + 1));
        __m128i v2 = _mm_loadu_si128((const __m128i *)(const void *)(b + p + 2));
        __m128i v3 = _mm_loadu_si128((const __m128i *)(const void *)(b + p + 3));
        __m128i e = _mm_and_si128(_mm_and_si128(_mm_cmpeq_epi8(v0, v1), _mm_cmpeq_epi8(v1, v2)),
                                  _mm_cmpeq_epi8(v2, v3));
        unsigned m = (unsigned)_mm_movemask_epi8(e);
        if (m) return p + __builtin_ctz(m);
    }
#endif
    for (; p + 3 < len; p++) {
        const uint8_t *q = b + (size_t)p * stride;
        if (q[0] == q[stride] && q[0] == q[2 * stride] && q[0] == q[3 * stride]) return p;
    }
    return len;
}

/* Short copies without the start-up cost of the rep-movs the compiler
 * inlines for memcpy. */
static inline void copy_bytes(uint8_t *o, const uint8_t *s, int n)
{
    int k = 0;
#if defined(__SSE2__)
    for (; k + 16 <= n; k += 16)
        _mm_storeu_si128((__m128i *)(void *)(o + k), _mm_loadu_si128((const __m128i *)(const void *)(s + k)));
#endif
    for (; k + 8 <= n; k += 8) {
        uint64_t v;
        memcpy(&v, s + k, 8);
        memcpy(o + k, &v, 8);
    }
    for (; k < n; k++) o[k] = s[k];
}

/* One component plane of a new-RLE scanline, packet for packet as
 * Radiance's fwritecolrs: runs of >= MINRUN equal bytes (at most 127), a
 * short run of 2-3 equal bytes only right before a run (or the end),
 * literals of at most 128 bytes. */
static uint8_t *encode_plane(uint8_t *o, const uint8_t *b, size_t stride, int len)
{
#define B(i) b[(size_t)(i) * stride]
    int j = 0;
    while (j < len) {
        int beg = find_run(b, stride, j, len), cnt = 0;
        if (beg < len) {
            uint8_t v = B(beg);
            int lim = len - beg < 127 ? len - beg : 127;
            cnt = MINRUN; /* find_run checked the first MINRUN */
#if defined(__SSE2__)
            if (stride == 1) {
                __m128i vv = _mm_set1_epi8((char)v);
                for (; cnt + 16 <= lim; cnt += 16) {
                    unsigned m = (unsigned)_mm_movemask_epi8(
                        _mm_cmpeq_epi8(_mm_loadu_si128((const __m128i *)(const void *)(b + beg + cnt)), vv));
                    if (m != 0xffff) { cnt += __builtin_ctz(~m); goto counted; }
                }
            }
#endif
            while (cnt < lim && B(beg + cnt) == v) cnt++;
#if defined(__SSE2__)
        counted:;
#endif
        }
        if (beg - j > 1 && beg - j < MINRUN) {
            int k = j + 1;
            while (k < beg && B(k) == B(j)) k++;
            if (k == beg) {
                *o++ = (uint8_t)(128 + beg - j);
                *o++ = B(j);
                j = beg;
            }
        }
        while (j < beg) { /* literal packets */
            int n = beg - j;
            if (n > 128) n = 128;
            *o++ = (uint8_t)n;
            if (stride == 1) copy_bytes(o, b + j, n);
            else
                for (int k = 0; k < n; k++) o[k] = B(j + k);
            o += n;
            j += n;
        }
        if (cnt >= MINRUN) { /* the run */
            *o++ = (uint8_t)(128 + cnt);
            *o++ = B(beg);
            j = beg + cnt;
        }
    }
    return o;
#undef B
}

size_t hd_scanline_encode_planar(uint8_t *out, const uint8_t *planes, int len)
{
    if (len <= 0) return 0;
    if (len < MINELEN || len > MAXELEN) {
        for (int i = 0; i < len; i++)
            for (int c = 0; c < 4; c++) out[4 * i + c] = planes[(size_t)c * (size_t)len + (size_t)i];
        return (size_t)len * 4;
    }
    uint8_t *o = out;
    *o++ = 2;
    *o++ = 2;
    *o++ = (uint8_t)(len >> 8);
    *o++ = (uint8_t)(len & 0xff);
    for (int c = 0; c < 4; c++) o = encode_plane(o, planes + (size_t)c * (size_t)len, 1, len);
    return (size_t)(o - out);
}

size_t hd_scanline_encode(uint8_t *out, const uint8_t *sl, int len)
{
    if (len <= 0) return 0;
    if (len < MINELEN || len > MAXELEN) {
        memcpy(out, sl, (size_t)len * 4);
        return (size_t)len * 4;
    }
    uint8_t pl[4 * 1024]; /* planes of lines up to 1024 pixels (the SIMD run search) */
    if ((size_t)len * 4 <= sizeof pl) {
        for (int i = 0; i < len; i++)
            for (int c = 0; c < 4; c++) pl[(size_t)c * (size_t)len + (size_t)i] = sl[4 * i + c];
        return hd_scanline_encode_planar(out, pl, len);
    }
    uint8_t *o = out;
    *o++ = 2;
    *o++ = 2;
    *o++ = (uint8_t)(len >> 8);
    *o++ = (uint8_t)(len & 0xff);
    for (int c = 0; c < 4; c++) o = encode_plane(o, sl + c, 4, len);
    return (size_t)(o - out);
}

hd_status hd_scanline_write(FILE *fp, const uint8_t *rgbe, int len)
{
    if (len <= 0) return hd_fail(HD_ERR_RANGE, "bad scanline length %d", len);
    if (len < MINELEN || len > MAXELEN) {
        if (fwrite(rgbe, 4, (size_t)len, fp) != (size_t)len)
            return hd_fail(HD_ERR_IO, "write error (scanline)");
        return HD_OK;
    }
    uint8_t stackbuf[4096];
    size_t need = hd_scanline_maxbytes(len);
    uint8_t *buf = need <= sizeof stackbuf ? stackbuf : hd_malloc(need);
    if (!buf) return HD_ERR_NOMEM;
    size_t n = hd_scanline_encode(buf, rgbe, len);
    size_t w = fwrite(buf, 1, n, fp);
    if (buf != stackbuf) free(buf);
    if (w != n) return hd_fail(HD_ERR_IO, "write error (scanline)");
    return HD_OK;
}

/* ------------------------------------------------------------------ */
/* whole pictures                                                      */

void hd_picture_init(hd_picture *p)
{
    memset(p, 0, sizeof *p);
    hd_header_init(&p->hdr);
    p->fmt = HD_PIC_RGBE;
    p->orient = HD_RES_STANDARD;
}

void hd_picture_free(hd_picture *p)
{
    free(p->pix);
    hd_header_free(&p->hdr);
    hd_picture_init(p);
}

hd_status hd_picture_alloc(hd_picture *p, int xres, int yres)
{
    hd_picture_init(p);
    hd_resolu r = {HD_RES_STANDARD, xres, yres};
    hd_status st = hd_resolu_check(&r, "picture");
    if (st) return st;
    p->pix = hd_big_alloc((size_t)xres * (size_t)yres * 3, sizeof(float), 1);
    if (!p->pix) return HD_ERR_NOMEM;
    p->xres = xres;
    p->yres = yres;
    return HD_OK;
}

hd_status hd_picture_read_header(hd_istream *s, hd_header *hdr, hd_picfmt *fmt, hd_resolu *r)
{
    char val[256];
    hd_header_init(hdr);
    hd_status st = hd_header_read(s, hdr, 0);
    if (st) return st;
    *fmt = HD_PIC_RGBE;
    if (hd_header_get(hdr, "FORMAT", val, sizeof val)) {
        if (!strcmp(val, FMT_XYZE)) *fmt = HD_PIC_XYZE;
        else if (strcmp(val, FMT_RGBE))
            return hd_fail(HD_ERR_FORMAT, "%s: FORMAT=%s is not a Radiance picture format "
                           "(expected %s or %s)", hd_istream_name(s), val, FMT_RGBE, FMT_XYZE);
        hd_header_remove(hdr, "FORMAT");
    }
    return hd_resolu_read(s, r);
}

hd_status hd_picture_read_stream(hd_istream *s, hd_picture *p)
{
    hd_resolu r;
    hd_picfmt fmt;
    hd_picture_init(p);
    hd_status st = hd_picture_read_header(s, &p->hdr, &fmt, &r);
    if (st) { hd_picture_free(p); return st; }
    const char *name = hd_istream_name(s);
    hd_header keep = p->hdr;
    hd_header_init(&p->hdr);
    st = hd_picture_alloc(p, r.xres, r.yres);     /* re-initialises *p */
    if (st) {
        hd_header_free(&keep);
        hd_fail_context(st, "%s", name);
        return st;
    }
    p->hdr = keep;
    p->fmt = fmt;
    p->orient = r.orient;

    int len = hd_resolu_scanlen(&r), nscan = hd_resolu_nscans(&r);
    size_t cap = (size_t)1 << 16, have = 0, pos = 0;   /* grows below */
    uint64_t base = hd_istream_offset(s);
    int eof = 0;
    uint8_t *buf = hd_malloc(cap);
    uint8_t *sl = hd_malloc((size_t)len * 4);
    float *tmp = hd_malloc((size_t)len * 3 * sizeof(float));
    if (!buf || !sl || !tmp) { st = HD_ERR_NOMEM; goto done; }

    for (int scan = 0; scan < nscan; scan++) {
        for (;;) {
            bsrc b;
            b.start = buf;
            b.p = buf + pos;
            b.end = buf + have;
            b.base = base;
            b.s = s;
            b.mem = 1;
            b.name = name;
            int rc = scan_decode(&b, sl, len, scan);
            if (rc == DEC_OK) { pos = (size_t)(b.p - buf); break; }
            if (rc == DEC_BAD) { st = HD_ERR_FORMAT; goto done; }
            if (eof) {
                st = hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: unexpected end of data in "
                             "scanline %d of %d (picture %d x %d)", name,
                             (unsigned long long)(base + have), scan, nscan, r.xres, r.yres);
                goto done;
            }
            /* refill: keep the unread tail, grow if it fills half the buffer */
            if (pos) {
                memmove(buf, buf + pos, have - pos);
                base += pos;
                have -= pos;
                pos = 0;
            }
            if (have > cap / 2) {
                uint8_t *nb = hd_realloc_array(buf, cap, 2);
                if (!nb) { st = HD_ERR_NOMEM; goto done; }
                buf = nb;
                cap *= 2;
            }
            size_t n = hd_istream_read(s, buf + have, cap - have);
            if (n == 0) {
                if (hd_istream_failed(s)) {
                    st = hd_fail(HD_ERR_IO, "%s: byte offset %llu: read error", name,
                                 (unsigned long long)(base + have));
                    goto done;
                }
                eof = 1;
            }
            have += n;
        }
        /* place the scanline */
        if (r.orient == HD_RES_STANDARD) {
            hd_rgbe_decode_n(p->pix + (size_t)scan * len * 3, sl, (size_t)len);
        } else {
            hd_rgbe_decode_n(tmp, sl, (size_t)len);
            for (int j = 0; j < len; j++) {
                int x, y;
                hd_resolu_pixel(&r, scan, j, &x, &y);
                float *d = p->pix + ((size_t)(r.yres - 1 - y) * r.xres + x) * 3;
                d[0] = tmp[3 * j];
                d[1] = tmp[3 * j + 1];
                d[2] = tmp[3 * j + 2];
            }
        }
    }
done:
    free(buf);
    free(sl);
    free(tmp);
    if (st) hd_picture_free(p);
    return st;
}

hd_status hd_picture_read(const char *path, hd_picture *p)
{
    hd_istream *s;
    hd_picture_init(p);
    hd_status st = hd_istream_open(&s, path);
    if (st) return st;
    st = hd_picture_read_stream(s, p);
    hd_status cst = hd_istream_close(s);
    if (!st && cst) { hd_picture_free(p); st = cst; }
    return st;
}

hd_status hd_picture_write_header(FILE *fp, const hd_header *hdr, hd_picfmt fmt,
                                  const hd_resolu *r)
{
    char res[64];
    hd_status st = hd_resolu_check(r, "picture to write");
    if (st) return st;
    st = hd_header_put(fp, hdr, NULL, fmt == HD_PIC_XYZE ? FMT_XYZE : FMT_RGBE, NULL);
    if (st) return st;
    hd_resolu_format(res, sizeof res, r);
    if (fputs(res, fp) == EOF) return hd_fail(HD_ERR_IO, "write error (resolution string)");
    return HD_OK;
}

hd_status hd_picture_write(FILE *fp, const hd_picture *p, const hd_header *hdr, int orient)
{
    hd_resolu r = {orient, p->xres, p->yres};
    hd_status st = hd_picture_write_header(fp, hdr ? hdr : &p->hdr, p->fmt, &r);
    if (st) return st;
    int len = hd_resolu_scanlen(&r), nscan = hd_resolu_nscans(&r);
    uint8_t *sl = hd_malloc((size_t)len * 4);
    uint8_t *out = hd_malloc(hd_scanline_maxbytes(len));
    float *tmp = hd_malloc((size_t)len * 3 * sizeof(float));
    if (!sl || !out || !tmp) { st = HD_ERR_NOMEM; goto done; }
    for (int scan = 0; scan < nscan; scan++) {
        if (orient == HD_RES_STANDARD) {
            hd_rgbe_encode_n(sl, p->pix + (size_t)scan * len * 3, (size_t)len);
        } else {
            for (int j = 0; j < len; j++) {
                int x, y;
                hd_resolu_pixel(&r, scan, j, &x, &y);
                const float *d = p->pix + ((size_t)(r.yres - 1 - y) * r.xres + x) * 3;
                tmp[3 * j] = d[0];
                tmp[3 * j + 1] = d[1];
                tmp[3 * j + 2] = d[2];
            }
            hd_rgbe_encode_n(sl, tmp, (size_t)len);
        }
        size_t n = hd_scanline_encode(out, sl, len);
        if (fwrite(out, 1, n, fp) != n) {
            st = hd_fail(HD_ERR_IO, "write error (scanline %d of %d)", scan, nscan);
            goto done;
        }
    }
    if (ferror(fp)) st = hd_fail(HD_ERR_IO, "write error");
done:
    free(sl);
    free(out);
    free(tmp);
    return st;
}

hd_status hd_picture_save(const char *path, const hd_picture *p, const hd_header *hdr)
{
    hd_ofile *f;
    hd_status st = hd_ofile_open(&f, path);
    if (st) return st;
    st = hd_picture_write(hd_ofile_fp(f), p, hdr, HD_RES_STANDARD);
    if (st) {
        hd_fail_context(st, "%s", hd_ofile_name(f));
        hd_ofile_abort(f);
        return st;
    }
    return hd_ofile_commit(f);
}

/* ------------------------------------------------------------------ */
/* getinfo support                                                     */

#define INFO_MAXHEADER ((size_t)16 << 20)

hd_status hd_info_read_raw(hd_istream *s, char **text, size_t *len)
{
    const char *name = hd_istream_name(s);
    *text = NULL;
    *len = 0;
    int c = hd_istream_peek(s);
    if (c == EOF)
        return hd_fail(HD_ERR_FORMAT, "%s: empty input, expected a header", name);
    if (!isprint(c))
        return hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: not a Radiance file (a header "
                       "starts with a printable character, found byte 0x%02x)", name,
                       (unsigned long long)hd_istream_offset(s), c);
    size_t cap = 4096, n = 0;
    char *t = hd_malloc(cap);
    if (!t) return HD_ERR_NOMEM;
    for (;;) {
        size_t ls = n;   /* start of this line */
        for (;;) {
            c = hd_istream_getc(s);
            if (c == EOF) {
                free(t);
                if (hd_istream_failed(s))
                    return hd_fail(HD_ERR_IO, "%s: byte offset %llu: read error in the header",
                                   name, (unsigned long long)hd_istream_offset(s));
                return hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: unexpected end of data "
                               "in the header (expected an empty line ending it)", name,
                               (unsigned long long)hd_istream_offset(s));
            }
            if (n + 2 > cap) {
                if (cap >= INFO_MAXHEADER) {
                    free(t);
                    return hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: header longer than "
                                   "%zu bytes (no empty line ending it?)", name,
                                   (unsigned long long)hd_istream_offset(s), INFO_MAXHEADER);
                }
                char *nt = hd_realloc_array(t, cap, 2);
                if (!nt) { free(t); return HD_ERR_NOMEM; }
                t = nt;
                cap *= 2;
            }
            t[n++] = (char)c;
            if (c == '\n') break;
        }
        size_t ll = n - ls;
        if ((ll == 1) || (ll == 2 && t[ls] == '\r')) {   /* the empty line */
            n = ls;
            break;
        }
    }
    t[n] = 0;
    *text = t;
    *len = n;
    return HD_OK;
}

/* value of a "NAME=" line in a raw header, copied until white space */
static int raw_get(const char *raw, const char *name, char *buf, size_t cap)
{
    size_t nl = strlen(name);
    int found = 0;
    for (const char *l = raw; l && *l; l = strchr(l, '\n'), l = l ? l + 1 : NULL) {
        if (strncmp(l, name, nl) || l[nl] != '=') continue;
        const char *v = l + nl + 1;
        while (*v == ' ' || *v == '\t') v++;
        size_t k = 0;
        while (v[k] && !isspace((unsigned char)v[k]) && k + 1 < cap) { buf[k] = v[k]; k++; }
        buf[k] = 0;
        found = k > 0;
    }
    return found;
}

hd_status hd_info_dimensions(hd_istream *s, const char *rawhdr, char *buf, size_t cap)
{
    char nr[32], nc[32], ncomp[32];
    if (cap < 32) return hd_fail(HD_ERR_INTERNAL, "dimension buffer too small");
    size_t n = 0;
    if (rawhdr && raw_get(rawhdr, "NROWS", nr, sizeof nr) && raw_get(rawhdr, "NCOLS", nc, sizeof nc)) {
        if (raw_get(rawhdr, "NCOMP", ncomp, sizeof ncomp))
            snprintf(buf, cap, "NROWS=%s NCOLS=%s NCOMP=%s\n", nr, nc, ncomp);
        else
            snprintf(buf, cap, "NROWS=%s NCOLS=%s\n", nr, nc);
        return HD_OK;
    }
    int c = hd_istream_getc(s);
    if (c == '+' || c == '-') {             /* picture: the line as found */
        while (c != EOF && c != '\n' && n + 2 < cap) {
            buf[n++] = (char)c;
            c = hd_istream_getc(s);
        }
        buf[n++] = '\n';
        buf[n] = 0;
        return HD_OK;
    }
    if (c == 1) {                           /* octree: 4 NUL-ended strings */
        int j = 0;
        hd_istream_getc(s);
        while ((c = hd_istream_getc(s)) != EOF && n + 2 < cap) {
            if (c == 0) {
                if (++j >= 4) break;
                buf[n++] = ' ';
            } else {
                buf[n++] = (char)c;
            }
        }
        buf[n++] = '\n';
        buf[n] = 0;
        return HD_OK;
    }
    snprintf(buf, cap, "unknown file type\n");
    return HD_OK;
}

int hd_info_line_removed(const char *line, char *const *patterns)
{
    for (char *const *pp = patterns; *pp; pp++) {
        const char *l = line, *q = *pp;
        if (isspace((unsigned char)*q)) {
            if (!isspace((unsigned char)*l)) continue;
            while (isspace((unsigned char)*l)) l++;
            while (isspace((unsigned char)*q)) q++;
        }
        while (*q && *l == *q) {
            if (*l == '=' && l > line) return 1;
            if (isspace((unsigned char)*q)) break;
            l++;
            q++;
        }
        if (l == line) continue;
        if (*l == '=' && !*q) return 1;
        if (isspace((unsigned char)*l) && isspace((unsigned char)*q)) return 1;
    }
    return 0;
}

size_t hd_info_pattern_line_len(const char *pattern)
{
    size_t len = strlen(pattern), strt = 0;
    while (strt < len && isspace((unsigned char)pattern[strt])) strt++;
    if (strt == len) return 0;
    while (len > 0 && isspace((unsigned char)pattern[len - 1])) len--;
    for (size_t j = strt + 1; j + 1 < len; j++)
        if (pattern[j] == '=' || isspace((unsigned char)pattern[j])) return len;
    return 0;
}

int hd_info_format_value(const char *line, char *buf, size_t cap)
{
    if (strncmp(line, "FORMAT=", 7)) return 0;
    const char *v = line + 7;
    while (isspace((unsigned char)*v)) v++;
    if (!*v) return 0;
    size_t k = 0;
    while (v[k] && !isspace((unsigned char)v[k]) && k + 1 < cap) { buf[k] = v[k]; k++; }
    buf[k] = 0;
    return 1;
}

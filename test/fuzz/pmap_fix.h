/* heliodon — make a mutated photon-map file consistent where a corrupt
 * file would be refused at once (fuzz_pmap.c, test_fuzz_findings.c): the
 * file length in the binary header and the CRC-32s of the pages, the page
 * index, the source table and the binary header are recomputed in place
 * (layout in docs/design/pmap.md), so that mutations reach the decoders
 * behind the checksums. */
#ifndef HD_FUZZ_PMAP_FIX_H
#define HD_FUZZ_PMAP_FIX_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "heliodon/pmap.h"

static inline uint64_t pf_get64(const uint8_t *b)
{
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--) v = v << 8 | b[i];
    return v;
}
static inline uint32_t pf_get32(const uint8_t *b) { return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24; }
static inline void pf_put64(uint8_t *b, uint64_t v) { for (int i = 0; i < 8; i++) b[i] = (uint8_t)(v >> 8 * i); }
static inline void pf_put32(uint8_t *b, uint32_t v) { for (int i = 0; i < 4; i++) b[i] = (uint8_t)(v >> 8 * i); }

/* [off, off+len) lies within n bytes */
static inline int pf_within(uint64_t off, uint64_t len, uint64_t n) { return off <= n && len <= n - off; }

static inline void hd_fuzz_pmap_fix(uint8_t *b, size_t n)
{
    size_t lim = n < 65536 ? n : 65536, i = 0;
    while (i + 1 < lim && !(b[i] == '\n' && b[i + 1] == '\n')) i++;   /* end of the text header */
    if (i + 1 >= lim) return;
    uint64_t hoff = (uint64_t)i + 2;
    if (!pf_within(hoff, 128, n)) return;
    uint8_t *h = b + hoff;
    uint64_t flen = n - hoff;
    pf_put64(h + 112, flen);
    uint64_t npages = pf_get64(h + 24), tab_off = pf_get64(h + 72), tab_len = pf_get64(h + 80), idx_off = pf_get64(h + 88),
             idx_len = pf_get64(h + 96);
    if (pf_within(idx_off, idx_len, flen) && idx_len >= 4) {
        uint8_t *ib = h + idx_off;
        uint64_t nrec = (idx_len - 4) / 56;
        if (nrec > npages) nrec = npages;
        for (uint64_t i = 0; i < nrec; i++) {
            uint8_t *r = ib + i * 56;
            uint64_t off = pf_get64(r);
            uint32_t csize = pf_get32(r + 8);
            if (pf_within(off, csize, flen)) pf_put32(r + 48, hd_pmap_crc32(0, h + off, csize));
        }
        pf_put32(ib + idx_len - 4, hd_pmap_crc32(0, ib, idx_len - 4));
    }
    if (pf_within(tab_off, tab_len, flen) && tab_len >= 4)
        pf_put32(h + tab_off + tab_len - 4, hd_pmap_crc32(0, h + tab_off, tab_len - 4));
    pf_put32(h + 124, hd_pmap_crc32(0, h, 124));
}

#endif

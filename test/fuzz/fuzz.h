/* heliodon — fuzz harnesses (test/fuzz/fuzz_NAME.c, docs/fuzz.md).
 *
 * Each harness defines LLVMFuzzerTestOneInput in plain C: `make fuzz`
 * links it with clang's libFuzzer (+ ASan + UBSan); the normal build links
 * it with driver.c, which runs it over files, so the regression inputs in
 * test/fuzz/regress/NAME/ run in `make check` and `make check-asan`.
 * A harness returns 0 for every input: a bad input must give an error
 * status, never a crash, a sanitizer report or a hang. */
#ifndef HD_FUZZ_H
#define HD_FUZZ_H

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Per-process setup: single allocations above 256 MiB are refused by
 * hd_malloc (as a user's limit would), so an absurd size in an input is
 * an error, not an out-of-memory kill of the fuzzer; warnings are off
 * (they go to stderr and slow the runs down). */
static inline void hd_fuzz_setup(void)
{
    static int done;
    if (done) return;
    done = 1;
    hd_set_alloc_limit((size_t)256 << 20);
    hd_set_warnings(0);
}

/* NUL-terminated copy of the input (the caller frees it). */
static inline char *hd_fuzz_cstr(const uint8_t *data, size_t size)
{
    char *s = malloc(size + 1);
    if (!s) abort();
    if (size) memcpy(s, data, size);
    s[size] = 0;
    return s;
}

#endif

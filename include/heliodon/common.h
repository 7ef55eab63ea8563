/* heliodon — common definitions: status codes, error messages, warnings,
 * bounded allocation.  Every library function that can fail returns an
 * hd_status and leaves a readable message (file, line or byte offset, what
 * was expected) in a thread-local buffer read with hd_errmsg(). */
#ifndef HELIODON_COMMON_H
#define HELIODON_COMMON_H

#include <stddef.h>
#include <stdint.h>

#define HD_VERSION "0.1.0"
#define HD_SOFTWARE "heliodon " HD_VERSION

#if defined(__GNUC__) || defined(__clang__)
#define HD_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define HD_PRINTF(a, b)
#endif

typedef enum hd_status {
    HD_OK = 0,
    HD_ERR_IO,          /* cannot open/read/write a file or pipe */
    HD_ERR_FORMAT,      /* input does not follow its format */
    HD_ERR_RANGE,       /* value or size out of the accepted range */
    HD_ERR_NOMEM,       /* allocation refused (over the limit) or failed */
    HD_ERR_USAGE,       /* bad command-line usage */
    HD_ERR_UNSUPPORTED, /* valid input that heliodon does not handle */
    HD_ERR_INTERNAL
} hd_status;

/* Record an error message (printf-style) for the calling thread and return
 * st.  Typical use:  return hd_fail(HD_ERR_FORMAT, "%s: line %d: expected ...", ...); */
hd_status hd_fail(hd_status st, const char *fmt, ...) HD_PRINTF(2, 3);
/* Prefix the current message with "prefix: " (adds context on the way up). */
hd_status hd_fail_context(hd_status st, const char *fmt, ...) HD_PRINTF(2, 3);
const char *hd_errmsg(void);
void hd_clear_error(void);
const char *hd_status_name(hd_status st);

/* Program name used in messages ("rtrace: ..."). */
void hd_set_progname(const char *argv0);
const char *hd_progname(void);

/* Warnings go to stderr as "prog: warning: ...", unless disabled (-w). */
void hd_warn(const char *fmt, ...) HD_PRINTF(1, 2);
void hd_set_warnings(int on);
int hd_warnings_enabled(void);
/* Number of warnings issued so far (all threads). */
unsigned long hd_warning_count(void);

/* Print "prog: <message>" for the current error to stderr. */
void hd_report_error(void);
/* Report the current error, remove pending temporary outputs and exit(1). */
_Noreturn void hd_die(void);
/* Same with a message of its own. */
_Noreturn void hd_die_msg(const char *fmt, ...) HD_PRINTF(1, 2);

/* ---- bounded allocation ------------------------------------------------
 * Any single allocation above hd_alloc_limit() bytes (default 16 GiB, or the
 * environment variable HELIODON_MAX_ALLOC, which accepts k/m/g suffixes) is
 * refused with HD_ERR_NOMEM and a message naming the size: absurd sizes
 * read from files never reach malloc. All return NULL on failure with the
 * error recorded. */
size_t hd_alloc_limit(void);
void hd_set_alloc_limit(size_t bytes);
/* "1.5 GiB": a byte count for messages. */
void hd_format_bytes(char *buf, size_t cap, double n);
void *hd_malloc(size_t nbytes);
void *hd_calloc(size_t count, size_t size);            /* zeroed, overflow-checked */
void *hd_malloc_array(size_t count, size_t size);      /* overflow-checked */
void *hd_realloc_array(void *p, size_t count, size_t size);
/* Room for `need` elements of elem bytes in the array *arr of *cap: the
 * capacity doubles (from `first` when there is none) until they fit,
 * through hd_realloc_array.  HD_OK, or HD_ERR_NOMEM with the message set
 * and *arr, *cap unchanged.  HD_GROW(arr, need, cap, first) for an array
 * pointer and a size_t capacity. */
hd_status hd_grow(void **arr, size_t need, size_t *cap, size_t elem, size_t first);
#define HD_GROW(arr, need, cap, first) hd_grow((void **)&(arr), (need), &(cap), sizeof *(arr), (first))
/* Union-find: the root of element a in the parent array par (its path
 * halved on the way). */
static inline int hd_uf_find(int *par, int a)
{
    while (par[a] != a) a = par[a] = par[par[a]];
    return a;
}
char *hd_strdup(const char *s);
/* Copy src into dst[cap] (always NUL-terminated, truncating); returns strlen(src). */
size_t hd_strlcpy(char *dst, const char *src, size_t cap);
/* qsort comparison of doubles, ascending. */
int hd_cmp_double(const void *a, const void *b);
/* Whether s ends in suffix, ignoring case (".exr" names, ".xml" files). */
int hd_has_suffix(const char *s, const char *suffix);
/* a*b with overflow detection: returns 0 and sets *out, or 1 on overflow. */
int hd_mul_overflow(size_t a, size_t b, size_t *out);
/* Large buffers (pictures, photon stores, annual matrices): count*size
 * bytes, overflow-checked and refused above hd_alloc_limit() like
 * hd_malloc; 64-byte aligned (a cache line), from 4 MiB up 2 MiB aligned
 * with transparent huge pages asked for (first touches then fault once per
 * 2 MiB: page faults were 10-15 % of such runs with 4 KiB pages under
 * virtualisation).  zero: zero-filled (from 4 MiB up lazily, from the
 * system, and then only 16-byte aligned).  Released with free(). */
void *hd_big_alloc(size_t count, size_t size, int zero);

/* ---- host probes ------------------------------------------------------- */
/* 1 if the host stores numbers big-endian (BigEndian= of binary matrices). */
int hd_host_bigendian(void);
/* Reverse the byte order of count values of width bytes each, in place. */
void hd_swap_bytes(void *p, size_t width, size_t count);
/* SIMD level of the CPU, probed once (thread-safe): 0 portable C only,
 * 1 AVX2, 2 AVX-512F.  Kernels choose with it. */
int hd_cpu_level(void);

#endif

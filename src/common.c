/* heliodon — status messages, warnings, program name, bounded allocation. */
#include "heliodon/common.h"
#include "heliodon/io.h"

#include <errno.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/mman.h>

#define HD_ERRMSG_MAX 2048

static _Thread_local char errbuf[HD_ERRMSG_MAX];
static char progname[128] = "heliodon";
static atomic_int warnings_on = 1;
static atomic_ulong nwarnings;

hd_status hd_fail(hd_status st, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(errbuf, sizeof errbuf, fmt, ap);
    va_end(ap);
    return st;
}

hd_status hd_fail_context(hd_status st, const char *fmt, ...)
{
    char prefix[HD_ERRMSG_MAX], old[HD_ERRMSG_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(prefix, sizeof prefix, fmt, ap);
    va_end(ap);
    memcpy(old, errbuf, sizeof old);
    if (snprintf(errbuf, sizeof errbuf, "%s: %s", prefix, old) >= (int)sizeof errbuf)
        errbuf[sizeof errbuf - 2] = '~'; /* mark truncation */
    return st;
}

const char *hd_errmsg(void) { return errbuf[0] ? errbuf : "unknown error"; }
void hd_clear_error(void) { errbuf[0] = 0; }

const char *hd_status_name(hd_status st)
{
    switch (st) {
    case HD_OK: return "ok";
    case HD_ERR_IO: return "i/o error";
    case HD_ERR_FORMAT: return "format error";
    case HD_ERR_RANGE: return "value out of range";
    case HD_ERR_NOMEM: return "out of memory";
    case HD_ERR_USAGE: return "usage error";
    case HD_ERR_UNSUPPORTED: return "unsupported";
    case HD_ERR_INTERNAL: return "internal error";
    }
    return "unknown status";
}

void hd_set_progname(const char *argv0)
{
    const char *b = argv0 ? strrchr(argv0, '/') : NULL;
    b = b ? b + 1 : argv0;
    snprintf(progname, sizeof progname, "%s", b && *b ? b : "heliodon");
}

const char *hd_progname(void) { return progname; }
void hd_set_warnings(int on) { atomic_store(&warnings_on, on ? 1 : 0); }
int hd_warnings_enabled(void) { return atomic_load(&warnings_on); }
unsigned long hd_warning_count(void) { return atomic_load(&nwarnings); }

void hd_warn(const char *fmt, ...)
{
    atomic_fetch_add(&nwarnings, 1);
    if (!atomic_load(&warnings_on)) return;
    char msg[HD_ERRMSG_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    fprintf(stderr, "%s: warning: %s\n", progname, msg);
}

void hd_report_error(void) { fprintf(stderr, "%s: %s\n", progname, hd_errmsg()); }

void hd_die(void)
{
    hd_report_error();
    hd_ofile_abort_all();
    exit(1);
}

void hd_die_msg(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(errbuf, sizeof errbuf, fmt, ap);
    va_end(ap);
    hd_die();
}

/* ---- bounded allocation ---- */

static size_t alloc_limit; /* 0 = not yet initialised */

size_t hd_alloc_limit(void)
{
    if (!alloc_limit) {
        size_t lim = (size_t)16 << 30;
        const char *e = getenv("HELIODON_MAX_ALLOC");
        uint64_t v;
        if (e && *e && hd_parse_count(e, &v) == 0 && v > 0) lim = (size_t)v;
        alloc_limit = lim;
    }
    return alloc_limit;
}

void hd_set_alloc_limit(size_t bytes) { alloc_limit = bytes; }

int hd_mul_overflow(size_t a, size_t b, size_t *out)
{
    if (a && b > SIZE_MAX / a) return 1;
    *out = a * b;
    return 0;
}

void hd_format_bytes(char *buf, size_t cap, double n)
{
    const char *u[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
    int i = 0;
    while (n >= 1024 && i < 6) { n /= 1024; i++; }
    snprintf(buf, cap, i ? "%.1f %s" : "%.0f %s", n, u[i]);
}

static int refuse(double nbytes)
{
    char a[32], b[32];
    hd_format_bytes(a, sizeof a, nbytes);
    hd_format_bytes(b, sizeof b, (double)hd_alloc_limit());
    hd_fail(HD_ERR_NOMEM, "refusing to allocate %s (limit %s; set HELIODON_MAX_ALLOC to change)", a, b);
    return 0;
}

void *hd_malloc(size_t n)
{
    if (n > hd_alloc_limit()) { refuse((double)n); return NULL; }
    void *p = malloc(n ? n : 1);
    if (!p) {
        char a[32];
        hd_format_bytes(a, sizeof a, (double)n);
        hd_fail(HD_ERR_NOMEM, "out of memory allocating %s", a);
    }
    return p;
}

void *hd_malloc_array(size_t count, size_t size)
{
    size_t n;
    if (hd_mul_overflow(count, size, &n)) { refuse((double)count * (double)size); return NULL; }
    return hd_malloc(n);
}

void *hd_calloc(size_t count, size_t size)
{
    size_t n;
    if (hd_mul_overflow(count, size, &n)) { refuse((double)count * (double)size); return NULL; }
    if (n > hd_alloc_limit()) { refuse((double)n); return NULL; }
    void *p = calloc(count ? count : 1, size ? size : 1);
    if (!p) hd_fail(HD_ERR_NOMEM, "out of memory allocating %zu bytes", n);
    return p;
}

void *hd_realloc_array(void *p, size_t count, size_t size)
{
    size_t n;
    if (hd_mul_overflow(count, size, &n)) { refuse((double)count * (double)size); return NULL; }
    if (n > hd_alloc_limit()) { refuse((double)n); return NULL; }
    void *q = realloc(p, n ? n : 1);
    if (!q) hd_fail(HD_ERR_NOMEM, "out of memory allocating %zu bytes", n);
    return q;
}

hd_status hd_grow(void **arr, size_t need, size_t *cap, size_t elem, size_t first)
{
    if (need <= *cap) return HD_OK;
    size_t nc = *cap ? *cap : first ? first : 1;
    while (nc < need) nc = nc > SIZE_MAX / 2 ? need : 2 * nc;
    void *a = hd_realloc_array(*arr, nc, elem);
    if (!a) return HD_ERR_NOMEM;
    *arr = a;
    *cap = nc;
    return HD_OK;
}

void *hd_big_alloc(size_t count, size_t size, int zero)
{
    size_t n;
    if (hd_mul_overflow(count, size, &n)) { refuse((double)count * (double)size); return NULL; }
    int big = n >= ((size_t)4 << 20);
    if (n > hd_alloc_limit()) { refuse((double)n); return NULL; }
    void *p = NULL;
    if (big && zero) p = calloc(n, 1);   /* fresh zero pages from the system at this size */
    else if (posix_memalign(&p, big ? (size_t)2 << 20 : 64, n ? n : 1) != 0) p = NULL;
    if (!p) {
        char a[32];
        hd_format_bytes(a, sizeof a, (double)n);
        hd_fail(HD_ERR_NOMEM, "out of memory allocating %s", a);
        return NULL;
    }
    if (!big) return zero ? memset(p, 0, n) : p;
#ifdef MADV_HUGEPAGE
    uintptr_t a = ((uintptr_t)p + 4095) & ~(uintptr_t)4095, e = ((uintptr_t)p + n) & ~(uintptr_t)4095;
    if (e > a) (void)madvise((void *)a, e - a, MADV_HUGEPAGE);
#endif
    return p;
}

void hd_swap_bytes(void *p, size_t width, size_t count)
{
    unsigned char *v = p;
    for (size_t i = 0; i < count; i++, v += width)
        for (size_t a = 0, b = width - 1; a < b; a++, b--) {
            unsigned char t = v[a];
            v[a] = v[b];
            v[b] = t;
        }
}

int hd_host_bigendian(void)
{
    const uint16_t one = 1;
    unsigned char b[2];
    memcpy(b, &one, 2);
    return b[0] == 0;
}

#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__))
#define HD_CPU_X86 1
#else
#define HD_CPU_X86 0
#endif
static int cpu_level = -1;
static pthread_once_t cpu_once = PTHREAD_ONCE_INIT;
static void cpu_probe(void)
{
    int lv = 0;
#if HD_CPU_X86
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx2")) lv = 1;
    if (__builtin_cpu_supports("avx512f")) lv = 2;
#endif
    cpu_level = lv;
}

int hd_cpu_level(void)
{
    pthread_once(&cpu_once, cpu_probe);
    return cpu_level;
}

char *hd_strdup(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = hd_malloc(n);
    if (d) memcpy(d, s, n);
    return d;
}

int hd_has_suffix(const char *s, const char *suffix)
{
    size_t a = strlen(s), b = strlen(suffix);
    return a >= b && !strcasecmp(s + a - b, suffix);
}

int hd_cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

size_t hd_strlcpy(char *dst, const char *src, size_t cap)
{
    size_t n = strlen(src);
    if (cap) {
        size_t k = n < cap - 1 ? n : cap - 1;
        memcpy(dst, src, k);
        dst[k] = 0;
    }
    return n;
}

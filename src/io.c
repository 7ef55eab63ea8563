/* heliodon — input streams (files, stdin, "!command", gzip) and crash-safe
 * output files (temporary name + rename). */
#include "heliodon/io.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#define ISBUF 65536

struct hd_istream {
    char *name;
    gzFile gz;
    FILE *pipe;               /* "!command" */
    unsigned char *buf;       /* owned buffer (NULL in memory mode) */
    const unsigned char *p;   /* current data window */
    size_t pos, len;
    uint64_t offset;          /* bytes consumed before p[0] + pos */
    unsigned long line;
    int eof, err;
    char errtext[256];
};

static hd_status stream_new(hd_istream **out, const char *name)
{
    hd_istream *s = hd_calloc(1, sizeof *s);
    if (!s) return HD_ERR_NOMEM;
    s->name = hd_strdup(name);
    if (!s->name) { free(s); return HD_ERR_NOMEM; }
    s->line = 1;
    *out = s;
    return HD_OK;
}

static hd_status attach_gz(hd_istream *s, int fd)
{
    s->gz = gzdopen(fd, "rb");
    if (!s->gz) {
        close(fd);
        return hd_fail(HD_ERR_IO, "%s: cannot read: %s", s->name, strerror(errno ? errno : ENOMEM));
    }
    gzbuffer(s->gz, 1 << 17);
    s->buf = hd_malloc(ISBUF);
    if (!s->buf) return HD_ERR_NOMEM;
    s->p = s->buf;
    return HD_OK;
}

hd_status hd_istream_open(hd_istream **out, const char *path)
{
    hd_istream *s;
    hd_status st;
    *out = NULL;
    if (!path) path = "-";
    if ((st = stream_new(&s, path)) != HD_OK) return st;
    int fd;
    if (!strcmp(path, "-")) {
        free(s->name);
        s->name = hd_strdup("<stdin>");
        fd = dup(0);
        if (fd < 0) { st = hd_fail(HD_ERR_IO, "<stdin>: cannot read: %s", strerror(errno)); goto fail; }
    } else if (path[0] == '!') {
        fflush(NULL);
        s->pipe = popen(path + 1, "r");
        if (!s->pipe) { st = hd_fail(HD_ERR_IO, "cannot run command '%s': %s", path + 1, strerror(errno)); goto fail; }
        fd = dup(fileno(s->pipe));
        if (fd < 0) { st = hd_fail(HD_ERR_IO, "cannot read from command '%s': %s", path + 1, strerror(errno)); goto fail; }
    } else {
        fd = open(path, O_RDONLY);
        if (fd < 0) { st = hd_fail(HD_ERR_IO, "%s: cannot open: %s", path, strerror(errno)); goto fail; }
        struct stat sb;
        if (fstat(fd, &sb) == 0 && S_ISDIR(sb.st_mode)) {
            close(fd);
            st = hd_fail(HD_ERR_IO, "%s: is a directory", path);
            goto fail;
        }
    }
    if ((st = attach_gz(s, fd)) != HD_OK) goto fail;
    *out = s;
    return HD_OK;
fail:
    hd_istream_close(s);
    return st;
}

hd_status hd_istream_memory(hd_istream **out, const void *data, size_t len, const char *name)
{
    hd_istream *s;
    hd_status st;
    *out = NULL;
    if ((st = stream_new(&s, name)) != HD_OK) return st;
    s->p = data;
    s->len = len;
    s->eof = 1; /* no refill */
    *out = s;
    return HD_OK;
}

hd_status hd_istream_close(hd_istream *s)
{
    hd_status st = HD_OK;
    if (!s) return HD_OK;
    if (s->gz) gzclose(s->gz);
    if (s->pipe) {
        int rc = pclose(s->pipe);
        if (rc != 0) {
            if (rc > 0 && WIFEXITED(rc))
                st = hd_fail(HD_ERR_IO, "command '%s' exited with status %d", s->name + 1, WEXITSTATUS(rc));
            else
                st = hd_fail(HD_ERR_IO, "command '%s' failed", s->name + 1);
        }
    }
    free(s->buf);
    free(s->name);
    free(s);
    return st;
}

const char *hd_istream_name(const hd_istream *s) { return s->name; }
uint64_t hd_istream_offset(const hd_istream *s) { return s->offset + s->pos; }
unsigned long hd_istream_lineno(const hd_istream *s) { return s->line; }
int hd_istream_failed(const hd_istream *s) { return s->err; }

/* Refill the buffer; returns bytes available. */
static size_t refill(hd_istream *s)
{
    if (s->pos < s->len) return s->len - s->pos;
    if (s->eof || s->err || !s->gz) return 0;
    s->offset += s->len;
    s->pos = s->len = 0;
    int n = gzread(s->gz, s->buf, ISBUF);
    if (n < 0) {
        int zerr;
        const char *m = gzerror(s->gz, &zerr);
        snprintf(s->errtext, sizeof s->errtext, "%s", m ? m : "read error");
        s->err = 1;
        return 0;
    }
    if (n == 0) { s->eof = 1; return 0; }
    s->len = (size_t)n;
    return s->len;
}

int hd_istream_getc(hd_istream *s)
{
    if (s->pos >= s->len && !refill(s)) return EOF;
    int c = s->p[s->pos++];
    if (c == '\n') s->line++;
    return c;
}

int hd_istream_peek(hd_istream *s)
{
    if (s->pos >= s->len && !refill(s)) return EOF;
    return s->p[s->pos];
}

size_t hd_istream_read(hd_istream *s, void *buf, size_t n)
{
    unsigned char *d = buf;
    size_t got = 0;
    while (got < n) {
        size_t avail = s->len - s->pos;
        if (avail) {
            size_t k = n - got < avail ? n - got : avail;
            memcpy(d + got, s->p + s->pos, k);
            s->pos += k;
            got += k;
            continue;
        }
        /* large reads bypass the buffer */
        if (n - got >= ISBUF && s->gz && !s->eof && !s->err) {
            s->offset += s->len;
            s->pos = s->len = 0;
            size_t want = n - got > (size_t)INT_MAX / 2 ? (size_t)INT_MAX / 2 : n - got;
            int r = gzread(s->gz, d + got, (unsigned)want);
            if (r < 0) {
                int zerr;
                const char *m = gzerror(s->gz, &zerr);
                snprintf(s->errtext, sizeof s->errtext, "%s", m ? m : "read error");
                s->err = 1;
                break;
            }
            if (r == 0) { s->eof = 1; break; }
            got += (size_t)r;
            s->offset += (size_t)r;
            continue;
        }
        if (!refill(s)) break;
    }
    return got;
}

hd_status hd_istream_read_exact(hd_istream *s, void *buf, size_t n, const char *what)
{
    uint64_t at = hd_istream_offset(s);
    size_t got = hd_istream_read(s, buf, n);
    if (got == n) return HD_OK;
    if (s->err)
        return hd_fail(HD_ERR_IO, "%s: byte offset %llu: read error (%s) reading %s", s->name,
                       (unsigned long long)hd_istream_offset(s), s->errtext, what);
    return hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: unexpected end of data reading %s (%zu of %zu bytes present)",
                   s->name, (unsigned long long)at, what, got, n);
}

hd_status hd_istream_read_all(hd_istream *s, unsigned char **data, size_t *len)
{
    size_t n = 0, cap = 0, lim = hd_alloc_limit();
    unsigned char *b = NULL;
    *data = NULL;
    *len = 0;
    for (;;) {
        if (n + 1 >= cap) {   /* room for the data read next and the NUL */
            if (cap >= lim) {
                char a[32];
                hd_format_bytes(a, sizeof a, (double)lim);
                free(b);
                return hd_fail(HD_ERR_NOMEM, "%s: longer than the allocation limit of %s, refused "
                               "(set HELIODON_MAX_ALLOC to change)", s->name, a);
            }
            size_t nc = cap ? (cap > lim / 2 ? lim : 2 * cap) : (lim < 65536 ? lim : 65536);
            unsigned char *nb = hd_realloc_array(b, nc, 1);
            if (!nb) {
                free(b);
                return hd_fail_context(HD_ERR_NOMEM, "%s: reading %zu bytes and more", s->name, n);
            }
            b = nb;
            cap = nc;
        }
        size_t got = hd_istream_read(s, b + n, cap - 1 - n);
        n += got;
        if (got == 0) break;
    }
    if (s->err) {
        free(b);
        return hd_fail(HD_ERR_IO, "%s: byte offset %zu: read error (%s)", s->name, n, s->errtext);
    }
    b[n] = 0;
    *data = b;
    *len = n;
    return HD_OK;
}

hd_status hd_file_read_all(const char *path, unsigned char **data, size_t *len)
{
    hd_istream *in;
    *data = NULL;
    *len = 0;
    hd_status st = hd_istream_open(&in, path);
    if (st != HD_OK) return st;
    st = hd_istream_read_all(in, data, len);
    hd_status cst = hd_istream_close(in);
    if (st == HD_OK && cst != HD_OK) { free(*data); *data = NULL; *len = 0; st = cst; }
    return st;
}

long hd_istream_getline(hd_istream *s, char *buf, size_t cap)
{
    size_t n = 0;
    int c, toolong = 0;
    if (hd_istream_peek(s) == EOF) return -1;
    while ((c = hd_istream_getc(s)) != EOF && c != '\n') {
        if (n + 1 < cap) buf[n++] = (char)c;
        else toolong = 1;
    }
    if (cap) buf[n] = 0;
    return toolong ? -2 : (long)n;
}

long hd_istream_word(hd_istream *s, char *buf, size_t cap)
{
    int c;
    size_t n = 0;
    int toolong = 0;
    do c = hd_istream_getc(s);
    while (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v');
    while (c != EOF && !(c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v')) {
        if (n + 1 < cap) buf[n++] = (char)c;
        else toolong = 1;
        c = hd_istream_peek(s);
        if (c == EOF || c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v') break;
        c = hd_istream_getc(s);
    }
    if (cap) buf[n] = 0;
    return toolong ? -2 : (long)n;
}

hd_status hd_istream_real(hd_istream *s, double *v, int *eof)
{
    char w[128];
    long n = hd_istream_word(s, w, sizeof w);
    if (n == 0) {
        if (s->err)
            return hd_fail(HD_ERR_IO, "%s: read error (%s)", s->name, s->errtext);
        if (eof) { *eof = 1; return HD_OK; }
        return hd_fail(HD_ERR_FORMAT, "%s: line %lu: unexpected end of data, expected a number", s->name, s->line);
    }
    if (eof) *eof = 0;
    if (n < 0)
        return hd_fail(HD_ERR_FORMAT, "%s: line %lu: expected a number, found an overlong word", s->name, s->line);
    if (hd_parse_double(w, v) != 0)
        return hd_fail(HD_ERR_FORMAT, "%s: line %lu: expected a number, found \"%s\"", s->name, s->line, w);
    return HD_OK;
}

hd_status hd_istream_ray(hd_istream *s, char fmt, uint64_t k, hd_vec3 *org, hd_vec3 *dir, int *eof)
{
    double v[6];
    *eof = 0;
    if (fmt == 'a') {
        for (int i = 0; i < 6; i++) {
            int e = 0;
            hd_status st = hd_istream_real(s, &v[i], &e);
            if (st != HD_OK) return st;
            if (e) {
                if (i == 0) { *eof = 1; return HD_OK; }
                return hd_fail(HD_ERR_FORMAT, "%s: line %lu: incomplete ray %llu (expected 6 numbers, got %d)",
                               s->name, s->line, (unsigned long long)k + 1, i);
            }
        }
    } else {
        size_t sz = fmt == 'f' ? 4 : 8;
        unsigned char buf[48];
        size_t got = hd_istream_read(s, buf, 6 * sz);
        if (got == 0) { *eof = 1; return HD_OK; }
        if (got < 6 * sz)
            return hd_fail(HD_ERR_FORMAT, "%s: byte offset %llu: incomplete ray %llu, truncated (%zu of %zu bytes)",
                           s->name, (unsigned long long)hd_istream_offset(s), (unsigned long long)k + 1, got, 6 * sz);
        for (int i = 0; i < 6; i++) {
            if (sz == 4) { float f; memcpy(&f, buf + 4 * i, 4); v[i] = f; }
            else memcpy(&v[i], buf + 8 * i, 8);
        }
    }
    for (int i = 0; i < 6; i++)
        if (!isfinite(v[i]))
            return hd_fail(HD_ERR_FORMAT, "%s: ray %llu: value %d is not finite", s->name, (unsigned long long)k + 1,
                           i + 1);
    *org = hd_v3(v[0], v[1], v[2]);
    *dir = hd_v3(v[3], v[4], v[5]);
    return HD_OK;
}

const char *hd_find_in_path(const char *dirs, const char *name, char *buf, size_t cap)
{
    for (const char *p = dirs; p;) {
        const char *e = strchr(p, ':');
        int n = e ? (int)(e - p) : (int)strlen(p);
        int k = n ? snprintf(buf, cap, "%.*s/%s", n, p, name) : snprintf(buf, cap, "%s", name);
        if (k >= 0 && (size_t)k < cap && access(buf, R_OK) == 0) return buf;
        p = e ? e + 1 : NULL;
    }
    return NULL;
}

/* ---- numbers ---- */

int hd_parse_double(const char *s, double *out)
{
    char *end;
    if (!s || !*s) return -1;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end) return -1;
    if (!isfinite(v)) return -1;
    *out = v;
    return 0;
}

int hd_parse_long(const char *s, long *out)
{
    char *end;
    if (!s || !*s) return -1;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (end == s || *end || errno == ERANGE) return -1;
    *out = v;
    return 0;
}

int hd_parse_count(const char *s, uint64_t *out)
{
    char *end;
    if (!s || !*s) return -1;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || errno == ERANGE || !isfinite(v) || v < 0) return -1;
    double mult = 1;
    switch (*end) {
    case 0: break;
    case 'k': case 'K': mult = 1e3; end++; break;
    case 'm': case 'M': mult = 1e6; end++; break;
    case 'g': case 'G': mult = 1e9; end++; break;
    default: return -1;
    }
    if (*end) return -1;
    v *= mult;
    if (v != floor(v) || v >= 9.2e18) return -1;
    *out = (uint64_t)v;
    return 0;
}

/* ---- crash-safe outputs ---- */

struct hd_ofile {
    char *path;     /* final name */
    char *tmp;      /* temporary name (NULL for stdout) */
    FILE *fp;
    int keep;       /* kept on SIGINT/SIGTERM/SIGHUP (resumable) */
    int direct;     /* written in place (an existing device or pipe: /dev/null, a FIFO) */
    struct hd_ofile *next;
};

/* scratch files removed by the exit and signal handlers (hd_temp_track) */
#define MAXTRACK 1024
static char *tracked[MAXTRACK];

static pthread_mutex_t olock = PTHREAD_MUTEX_INITIALIZER;
static hd_ofile *pending;
static unsigned long ocounter;
static int handlers_installed;

/* interrupted: keep the temporaries marked resumable */
static void unlink_pending(int interrupted)
{
    for (hd_ofile *f = pending; f; f = f->next)
        if (f->tmp && !(interrupted && f->keep)) unlink(f->tmp);
    for (int i = 0; i < MAXTRACK; i++)
        if (tracked[i]) unlink(tracked[i]);
}

static void on_signal(int sig)
{
    unlink_pending(sig == SIGINT || sig == SIGTERM || sig == SIGHUP);
    signal(sig, SIG_DFL);
    raise(sig);
}

static void on_exit_cleanup(void) { unlink_pending(0); }

static void install_handlers(void)
{
    if (handlers_installed) return;
    handlers_installed = 1;
    /* a file-size limit (ulimit -f) makes writes fail with EFBIG and the
     * run end with a message naming the file, rather than die silently */
    struct sigaction xf;
    if (sigaction(SIGXFSZ, NULL, &xf) == 0 && xf.sa_handler == SIG_DFL) signal(SIGXFSZ, SIG_IGN);
    int sigs[] = {SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGQUIT, SIGXCPU};
    for (size_t i = 0; i < sizeof sigs / sizeof *sigs; i++) {
        struct sigaction sa, old;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_signal;
        sigemptyset(&sa.sa_mask);
        if (sigaction(sigs[i], NULL, &old) == 0 && old.sa_handler == SIG_IGN) continue;
        sigaction(sigs[i], &sa, NULL);
    }
    atexit(on_exit_cleanup);
}

static hd_status ofile_create(hd_ofile **out, const char *path, const char *adopt, uint64_t *size);

hd_status hd_ofile_open(hd_ofile **out, const char *path)
{
    if (path && strcmp(path, "-")) hd_ofile_clean_stale(path);
    return ofile_create(out, path, NULL, NULL);
}

/* New temporary for path; adopt: an existing file renamed to it (then
 * opened for update at its end, *size its length). */
static hd_status ofile_create(hd_ofile **out, const char *path, const char *adopt, uint64_t *size)
{
    *out = NULL;
    hd_ofile *f = hd_calloc(1, sizeof *f);
    if (!f) return HD_ERR_NOMEM;
    if (!path || !strcmp(path, "-")) {
        f->path = hd_strdup("<stdout>");
        f->fp = stdout;
        *out = f;
        return f->path ? HD_OK : HD_ERR_NOMEM;
    }
    struct stat sb;
    if (!adopt && stat(path, &sb) == 0 && !S_ISREG(sb.st_mode) && !S_ISDIR(sb.st_mode)) {
        /* a device or a FIFO (-o /dev/null): written in place; a temporary renamed onto it
         * would replace the device node by a regular file */
        f->path = hd_strdup(path);
        f->fp = f->path ? fopen(path, "wb") : NULL;
        if (!f->fp) {
            hd_status st = f->path ? hd_fail(HD_ERR_IO, "%s: cannot open output: %s", path, strerror(errno))
                                   : HD_ERR_NOMEM;
            free(f->path); free(f);
            return st;
        }
        f->direct = 1;
        *out = f;
        return HD_OK;
    }
    f->path = hd_strdup(path);
    size_t tl = strlen(path) + 64;
    f->tmp = hd_malloc(tl);
    if (!f->path || !f->tmp) { free(f->path); free(f->tmp); free(f); return HD_ERR_NOMEM; }
    const char *slash = strrchr(path, '/');
    int dirlen = slash ? (int)(slash - path + 1) : 0;
    pthread_mutex_lock(&olock);
    install_handlers();
    unsigned long k = ++ocounter;
    pthread_mutex_unlock(&olock);
    snprintf(f->tmp, tl, "%.*s.%s.hdtmp.%ld.%lu", dirlen, path, path + dirlen, (long)getpid(), k);
    int fd;
    if (adopt) {
        /* rename first: a second resuming run cannot take the same file */
        if (rename(adopt, f->tmp) != 0 || (fd = open(f->tmp, O_RDWR)) < 0) {
            hd_status st = hd_fail(HD_ERR_IO, "%s: cannot take over %s: %s", path, adopt, strerror(errno));
            free(f->path); free(f->tmp); free(f);
            return st;
        }
        off_t end = lseek(fd, 0, SEEK_END);
        *size = end > 0 ? (uint64_t)end : 0;
    } else {
        fd = open(f->tmp, O_WRONLY | O_CREAT | O_EXCL | O_TRUNC, 0666);
    }
    if (fd < 0) {
        hd_status st = hd_fail(HD_ERR_IO, "%s: cannot create output: %s", path, strerror(errno));
        free(f->path); free(f->tmp); free(f);
        return st;
    }
    f->fp = fdopen(fd, adopt ? "r+b" : "wb");
    if (f->fp && adopt) fseeko(f->fp, 0, SEEK_END);
    if (!f->fp) {
        close(fd);
        unlink(f->tmp);
        free(f->path); free(f->tmp); free(f);
        return hd_fail(HD_ERR_IO, "%s: cannot create output", path);
    }
    setvbuf(f->fp, NULL, _IOFBF, 1 << 16);
    pthread_mutex_lock(&olock);
    f->next = pending;
    pending = f;
    pthread_mutex_unlock(&olock);
    *out = f;
    return HD_OK;
}

FILE *hd_ofile_fp(hd_ofile *f) { return f->fp; }
const char *hd_ofile_tmpname(const hd_ofile *f) { return f->tmp; }
void hd_ofile_keep_on_signal(hd_ofile *f) { if (f) f->keep = 1; }

hd_status hd_ofile_truncate(hd_ofile *f, uint64_t len)
{
    if (!f->tmp) return hd_fail(HD_ERR_USAGE, "cannot truncate the standard output");
    if (fflush(f->fp) != 0 || ftruncate(fileno(f->fp), (off_t)len) != 0 || fseeko(f->fp, (off_t)len, SEEK_SET) != 0)
        return hd_fail(HD_ERR_IO, "%s: cannot cut the resumed output to %llu bytes: %s", f->path,
                       (unsigned long long)len, strerror(errno));
    return HD_OK;
}

/* ---- leftovers of killed runs ----
 * Each directory is listed once per process; the names of temporaries whose
 * process is gone are kept (a dead process stays dead) until removed or
 * taken over. */
typedef struct stale_dir {
    char *dir;          /* as given ("" = current directory) */
    char **names;       /* stale entries (NULL once removed / taken) */
    size_t n;
} stale_dir;
static pthread_mutex_t slock = PTHREAD_MUTEX_INITIALIZER;
static stale_dir *sdirs;
static size_t nsdirs;

/* PID of ".NAME.hdtmp.PID.SUFFIX" (the last ".hdtmp." in the name), or -1;
 * *suffix: what follows "PID.". */
static long tmp_pid(const char *ent, const char **suffix)
{
    const char *p = NULL, *q = ent;
    if (ent[0] != '.') return -1;
    while ((q = strstr(q + 1, ".hdtmp.")) != NULL) p = q;
    if (!p) return -1;
    p += 7;
    char *end;
    long pid = strtol(p, &end, 10);
    if (end == p || *end != '.' || !end[1] || pid <= 0) return -1;
    *suffix = end + 1;
    return pid;
}

static int pid_gone(long pid)
{
    if (pid == (long)getpid()) return 0;   /* ours (or reused: left alone) */
    return kill((pid_t)pid, 0) < 0 && errno == ESRCH;
}

static stale_dir *stale_list(const char *path)
{
    const char *slash = strrchr(path, '/');
    size_t dl = slash ? (size_t)(slash - path + 1) : 0;
    for (size_t i = 0; i < nsdirs; i++)
        if (strlen(sdirs[i].dir) == dl && !strncmp(sdirs[i].dir, path, dl)) return &sdirs[i];
    stale_dir *nd = realloc(sdirs, (nsdirs + 1) * sizeof *nd);
    if (!nd) return NULL;
    sdirs = nd;
    stale_dir *d = &sdirs[nsdirs];
    memset(d, 0, sizeof *d);
    d->dir = malloc(dl + 1);
    if (!d->dir) return NULL;
    memcpy(d->dir, path, dl);
    d->dir[dl] = 0;
    nsdirs++;
    DIR *D = opendir(dl ? d->dir : ".");
    if (!D) return d;
    struct dirent *e;
    size_t cap = 0;
    while ((e = readdir(D)) != NULL) {
        const char *suf;
        long pid = tmp_pid(e->d_name, &suf);
        if (pid < 0 || !pid_gone(pid)) continue;
        if (HD_GROW(d->names, d->n + 1, cap, 8)) break;
        size_t l = dl + strlen(e->d_name) + 1;
        if (!(d->names[d->n] = malloc(l))) break;
        snprintf(d->names[d->n++], l, "%s%s", d->dir, e->d_name);
    }
    closedir(D);
    return d;
}

/* Whether stale entry full (in d) belongs to path's base name. */
static int stale_of(const stale_dir *d, const char *full, const char *base)
{
    const char *ent = full + strlen(d->dir);
    size_t bl = strlen(base);
    return ent[0] == '.' && !strncmp(ent + 1, base, bl) && !strncmp(ent + 1 + bl, ".hdtmp.", 7);
}

/* Remove path's stale temporaries except *keep (the newest resumable one
 * when keep is non-NULL: its name is moved to *keep). */
static int clean_stale(const char *path, char **keep)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    int n = 0;
    pthread_mutex_lock(&slock);
    stale_dir *d = stale_list(path);
    size_t best = (size_t)-1;
    struct timespec bt = {0, 0};
    for (size_t i = 0; d && keep && i < d->n; i++) {
        const char *suf;
        struct stat sb;
        if (!d->names[i] || !stale_of(d, d->names[i], base)) continue;
        tmp_pid(d->names[i] + strlen(d->dir), &suf);
        if (strspn(suf, "0123456789") != strlen(suf) || stat(d->names[i], &sb) != 0) continue;
        if (best == (size_t)-1 || sb.st_mtim.tv_sec > bt.tv_sec ||
            (sb.st_mtim.tv_sec == bt.tv_sec && sb.st_mtim.tv_nsec > bt.tv_nsec)) {
            best = i;
            bt = sb.st_mtim;
        }
    }
    for (size_t i = 0; d && i < d->n; i++) {
        if (!d->names[i] || !stale_of(d, d->names[i], base)) continue;
        if (i == best) { *keep = d->names[i]; d->names[i] = NULL; continue; }
        if (unlink(d->names[i]) == 0) n++;
        free(d->names[i]);
        d->names[i] = NULL;
    }
    pthread_mutex_unlock(&slock);
    return n;
}

int hd_ofile_clean_stale(const char *path) { return clean_stale(path, NULL); }

static hd_status copy_file(const char *from, FILE *to, uint64_t *size)
{
    FILE *in = fopen(from, "rb");
    if (!in) return hd_fail(HD_ERR_IO, "%s: cannot open: %s", from, strerror(errno));
    char buf[65536];
    size_t n;
    *size = 0;
    while ((n = fread(buf, 1, sizeof buf, in)) > 0) {
        if (fwrite(buf, 1, n, to) != n) { fclose(in); return hd_fail(HD_ERR_IO, "error copying %s: %s", from, strerror(errno)); }
        *size += n;
    }
    int bad = ferror(in);
    fclose(in);
    if (bad) return hd_fail(HD_ERR_IO, "%s: read error", from);
    return HD_OK;
}

hd_status hd_ofile_open_resume(hd_ofile **out, const char *path, int *from, uint64_t *size)
{
    *out = NULL;
    *from = 0;
    *size = 0;
    if (!path || !strcmp(path, "-")) return hd_fail(HD_ERR_USAGE, "cannot resume the standard output");
    char *keep = NULL;
    clean_stale(path, &keep);
    if (keep) {
        hd_status st = ofile_create(out, path, keep, size);
        free(keep);
        if (st == HD_OK) *from = 1;
        return st;
    }
    hd_status st = ofile_create(out, path, NULL, NULL);
    if (st || access(path, F_OK) != 0) return st;
    if ((st = copy_file(path, (*out)->fp, size))) { hd_ofile_abort(*out); *out = NULL; return st; }
    *from = 2;
    return HD_OK;
}

hd_status hd_temp_track(const char *path)
{
    pthread_mutex_lock(&olock);
    install_handlers();
    int i = 0;
    while (i < MAXTRACK && tracked[i]) i++;
    if (i < MAXTRACK) tracked[i] = hd_strdup(path);   /* else left to the next run's clean-up */
    pthread_mutex_unlock(&olock);
    return HD_OK;
}

void hd_temp_forget(const char *path)
{
    pthread_mutex_lock(&olock);
    for (int i = 0; i < MAXTRACK; i++)
        if (tracked[i] && !strcmp(tracked[i], path)) {
            char *p = tracked[i];
            tracked[i] = NULL;
            free(p);
        }
    pthread_mutex_unlock(&olock);
}

hd_status hd_check_disk(const char *path, uint64_t need, const char *what)
{
    const char *slash = strrchr(path, '/');
    char dir[4096];
    if (!slash) hd_strlcpy(dir, ".", sizeof dir);
    else if (slash == path) hd_strlcpy(dir, "/", sizeof dir);
    else snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    struct statvfs v;
    if (statvfs(dir, &v) != 0) return HD_OK;
    uint64_t avail = (uint64_t)v.f_bavail * (uint64_t)(v.f_frsize ? v.f_frsize : v.f_bsize);
    if (need <= avail) return HD_OK;
    char a[32], b[32];
    hd_format_bytes(a, sizeof a, (double)need);
    hd_format_bytes(b, sizeof b, (double)avail);
    return hd_fail(HD_ERR_IO, "%s needs about %s (%llu bytes) but only %s are free in %s", what, a,
                   (unsigned long long)need, b, dir);
}
const char *hd_ofile_name(const hd_ofile *f) { return f->path; }

static void unlist(hd_ofile *f)
{
    pthread_mutex_lock(&olock);
    for (hd_ofile **pp = &pending; *pp; pp = &(*pp)->next)
        if (*pp == f) { *pp = f->next; break; }
    pthread_mutex_unlock(&olock);
}

hd_status hd_ofile_commit(hd_ofile *f)
{
    hd_status st = HD_OK;
    if (!f) return HD_OK;
    if (!f->tmp) {
        int bad = fflush(f->fp) != 0 || ferror(f->fp);
        if (f->direct && fclose(f->fp) != 0) bad = 1;
        if (bad)
            st = f->direct ? hd_fail(HD_ERR_IO, "%s: error writing output: %s", f->path, strerror(errno))
                           : hd_fail(HD_ERR_IO, "error writing standard output: %s", strerror(errno));
        free(f->path);
        free(f);
        return st;
    }
    int bad = fflush(f->fp) != 0 || ferror(f->fp);
    int e = errno;
    if (fclose(f->fp) != 0 && !bad) { bad = 1; e = errno; }
    if (bad) {
        st = hd_fail(HD_ERR_IO, "%s: error writing output: %s", f->path, strerror(e));
        unlink(f->tmp);
    } else if (rename(f->tmp, f->path) != 0) {
        st = hd_fail(HD_ERR_IO, "%s: cannot rename temporary output into place: %s", f->path, strerror(errno));
        unlink(f->tmp);
    }
    unlist(f);
    free(f->path);
    free(f->tmp);
    free(f);
    return st;
}

void hd_ofile_abort(hd_ofile *f)
{
    if (!f) return;
    if (f->tmp) {
        fclose(f->fp);
        unlink(f->tmp);
        unlist(f);
        free(f->tmp);
    } else if (f->direct) {
        fclose(f->fp);
    } else {
        fflush(f->fp);
    }
    free(f->path);
    free(f);
}

void hd_ofile_abort_all(void)
{
    pthread_mutex_lock(&olock);
    unlink_pending(0);
    pthread_mutex_unlock(&olock);
}

/* ---- output name patterns ---- */

/* Parse the conversion at spec[i] == '%'; returns its length and kind
 * ('d' class, 's', '%'), or 0 if malformed. */
static size_t conv_at(const char *spec, size_t i, char *kind)
{
    size_t j = i + 1;
    while (spec[j] && strchr("-+ #0", spec[j])) j++;
    while (spec[j] >= '0' && spec[j] <= '9') j++;
    char c = spec[j];
    if (c == '%' && j == i + 1) { *kind = '%'; return 2; }
    if (c == 's' && j == i + 1) { *kind = 's'; return 2; }
    if (c && strchr("dioxX", c)) { *kind = 'd'; return j - i + 1; }
    return 0;
}

int hd_pattern_kind(const char *spec)
{
    int mask = 0;
    for (size_t i = 0; spec[i]; i++) {
        if (spec[i] != '%') continue;
        char k;
        size_t n = conv_at(spec, i, &k);
        if (!n) { hd_fail(HD_ERR_USAGE, "bad conversion in pattern \"%s\" (allowed: %%s, %%d-style, %%%%)", spec); return -1; }
        if (k == 'd') {
            if (mask & 1) { hd_fail(HD_ERR_USAGE, "pattern \"%s\" has more than one integer conversion", spec); return -1; }
            mask |= 1;
        } else if (k == 's') {
            if (mask & 2) { hd_fail(HD_ERR_USAGE, "pattern \"%s\" has more than one %%s", spec); return -1; }
            mask |= 2;
        }
        i += n - 1;
    }
    return mask;
}

hd_status hd_pattern_format(char *out, size_t cap, const char *spec, const char *name, long index)
{
    if (hd_pattern_kind(spec) < 0) return HD_ERR_USAGE;
    size_t o = 0;
    for (size_t i = 0; spec[i];) {
        char piece[256];
        int n;
        if (spec[i] != '%') {
            piece[0] = spec[i++];
            piece[1] = 0;
            n = 1;
        } else {
            char k, fmt[32];
            size_t l = conv_at(spec, i, &k);
            if (k == '%') { piece[0] = '%'; piece[1] = 0; n = 1; }
            else if (k == 's') n = snprintf(piece, sizeof piece, "%s", name ? name : "");
            else {
                if (l + 2 > sizeof fmt) return hd_fail(HD_ERR_USAGE, "pattern \"%s\": conversion too long", spec);
                memcpy(fmt, spec + i, l - 1);
                fmt[l - 1] = 'l';
                fmt[l] = spec[i + l - 1];
                fmt[l + 1] = 0;
                /* fmt was validated by conv_at: flags, width and one of dioxX */
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wformat-nonliteral"
#endif
                n = snprintf(piece, sizeof piece, fmt, index);
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif
            }
            i += l;
        }
        if (n < 0 || (size_t)n >= sizeof piece || o + (size_t)n + 1 > cap)
            return hd_fail(HD_ERR_RANGE, "pattern \"%s\": resulting name too long", spec);
        memcpy(out + o, piece, (size_t)n);
        o += (size_t)n;
    }
    out[o] = 0;
    return HD_OK;
}

void hd_put_int(FILE *fp, long v, int siz)
{
    for (int sh = (siz - 1) * 8; sh >= 0; sh -= 8) putc((int)((unsigned long)v >> sh & 0xff), fp);
}

void hd_put_flt(FILE *fp, double f)
{
    int e;
    long m = (long)(frexp(f, &e) * 0x7fffffff);
    if (e > 127) { m = m > 0 ? 0x7fffffffL : -0x7fffffffL; e = 127; }
    else if (e < -128) { m = 0; e = 0; }
    hd_put_int(fp, m, 4);
    hd_put_int(fp, e, 1);
}

double hd_portable_flt(long m, long e)
{
    return m == 0 ? 0. : ldexp((m + .5 - (m < 0)) * (1. / 0x7fffffff), (int)e);
}

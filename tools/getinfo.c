/* getinfo — print the information header of Radiance files, or strip,
 * extend or edit it (see docs/man/getinfo.1).
 *
 *   getinfo [-d|+d] [file ..]        headers (or dimensions) of files / stdin
 *   getinfo [-d] -                   copy stdin without its header
 *   getinfo -a line ..               add header lines (stdin -> stdout)
 *   getinfo -r line ..               replace/remove header lines
 *   getinfo [-d|+d] -c command ..    run command on the data, header passed on
 */
#include "heliodon/common.h"
#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/picture.h"

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

static size_t nout;   /* bytes written to stdout (for FORMAT padding) */

static void out(const char *p, size_t n)
{
    if (fwrite(p, 1, n, stdout) != n) hd_die_msg("write error on standard output");
    nout += n;
}

static void outs(const char *s) { out(s, strlen(s)); }

/* header of file name, each line followed by a tab (as Radiance) */
static void put_tabbed(const char *text, size_t len)
{
    size_t a = 0;
    for (size_t i = 0; i < len; i++)
        if (text[i] == '\n') {
            out(text + a, i + 1 - a);
            out("\t", 1);
            a = i + 1;
        }
    if (a < len) out(text + a, len - a);
}

static void copy_rest(hd_istream *s)
{
    char buf[65536];
    size_t n;
    fflush(stdout);
    while ((n = hd_istream_read(s, buf, sizeof buf)) > 0) out(buf, n);
    if (hd_istream_failed(s))
        hd_die_msg("%s: byte offset %llu: read error", hd_istream_name(s),
                   (unsigned long long)hd_istream_offset(s));
}

/* Copy the header lines except FORMAT (and lines removed by -r patterns);
 * returns whether a FORMAT was found (value in fmt). */
static int copy_header(const char *text, char *const *remove, char *fmt, size_t cap)
{
    int havefmt = 0;
    const char *l = text;
    char line[HD_HEADER_MAXLINE + 2];
    while (*l) {
        const char *e = strchr(l, '\n');
        size_t n = e ? (size_t)(e - l) + 1 : strlen(l);
        size_t k = n < sizeof line - 1 ? n : sizeof line - 1;
        memcpy(line, l, k);
        line[k] = 0;
        if (hd_info_format_value(line, fmt, cap)) havefmt = 1;
        else if (!remove || !hd_info_line_removed(line, remove)) out(l, n);
        l += n;
    }
    return havefmt;
}

static void end_header(int havefmt, const char *fmt)
{
    if (havefmt) {
        fflush(stdout);
        if (hd_header_write_format(stdout, fmt, nout)) hd_die();
    } else {
        out("\n", 1);
    }
    fflush(stdout);
}

/* Die with "prefix: <current error>" (the message is copied first). */
static _Noreturn void die_ctx(const char *prefix)
{
    hd_fail_context(HD_ERR_FORMAT, "%s", prefix);
    hd_die();
}

static hd_istream *open_stdin(void)
{
    hd_istream *s;
    if (hd_istream_open(&s, "-")) hd_die();
    return s;
}

static char *read_header_or_die(hd_istream *s, size_t *len)
{
    char *text;
    if (hd_info_read_raw(s, &text, len)) die_ctx("bad header");
    return text;
}

static int run_command(int argc, char **argv, int dim)
{
    hd_istream *s = open_stdin();
    size_t len;
    char fmt[256];
    char *text = read_header_or_die(s, &len);
    int havefmt = copy_header(text, NULL, fmt, sizeof fmt);
    free(text);
    hd_header h;
    hd_header_init(&h);
    if (hd_header_add_command(&h, argc, argv)) hd_die();
    if (h.len) out(h.text, h.len);
    hd_header_free(&h);
    end_header(havefmt, fmt);
    if (dim) {
        hd_resolu r;
        char res[64];
        if (hd_resolu_read(s, &r)) die_ctx("no resolution string");
        if (dim > 0) {
            hd_resolu_format(res, sizeof res, &r);
            outs(res);
        }
    }
    fflush(stdout);
    int fd[2];
    if (pipe(fd)) hd_die_msg("cannot create a pipe for %s", argv[0]);
    pid_t pid = fork();
    if (pid < 0) hd_die_msg("cannot fork to run %s", argv[0]);
    if (pid == 0) {
        close(fd[1]);
        if (dup2(fd[0], 0) < 0) _exit(127);
        close(fd[0]);
        execvp(argv[0], argv);
        fprintf(stderr, "%s: cannot run %s\n", hd_progname(), argv[0]);
        _exit(127);
    }
    close(fd[0]);
    signal(SIGPIPE, SIG_IGN);
    char buf[65536];
    size_t n;
    while ((n = hd_istream_read(s, buf, sizeof buf)) > 0) {
        size_t w = 0;
        while (w < n) {
            ssize_t k = write(fd[1], buf + w, n - w);
            if (k <= 0) break;
            w += (size_t)k;
        }
        if (w < n) break;   /* the command stopped reading */
    }
    close(fd[1]);
    hd_istream_close(s);
    int status;
    while (waitpid(pid, &status, 0) < 0) {}
    if (WIFEXITED(status)) return WEXITSTATUS(status);
    return 1;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int dim = 0, failed = 0;
    if (argc > 1 && (!strcmp(argv[1], "-d") || !strcmp(argv[1], "+d"))) {
        dim = argv[1][0] == '-' ? -1 : 1;
        argc--;
        argv++;
    }
    if (argc > 2 && !strcmp(argv[1], "-c")) return run_command(argc - 2, argv + 2, dim);

    if (argc > 2 && (!strcmp(argv[1], "-a") || !strcmp(argv[1], "-r"))) {
        int replace = argv[1][1] == 'r';
        hd_istream *s = open_stdin();
        size_t len;
        char fmt[256];
        char *text = read_header_or_die(s, &len);
        int havefmt = copy_header(text, replace ? argv + 2 : NULL, fmt, sizeof fmt);
        free(text);
        for (int i = 2; i < argc; i++) {
            if (replace) {
                size_t n = hd_info_pattern_line_len(argv[i]);
                if (!n) continue;
                out(argv[i], n);
                out("\n", 1);
            } else {
                size_t n = strlen(argv[i]);
                if (!n) continue;
                out(argv[i], n);
                if (argv[i][n - 1] != '\n') out("\n", 1);
            }
        }
        end_header(havefmt, fmt);
        copy_rest(s);
        hd_istream_close(s);
        return fflush(stdout) ? 1 : 0;
    }

    if (argc == 2 && !strcmp(argv[1], "-")) {
        hd_istream *s = open_stdin();
        size_t len;
        free(read_header_or_die(s, &len));
        if (dim < 0) {
            hd_resolu r;
            if (hd_resolu_read(s, &r)) die_ctx("no resolution string");
        }
        copy_rest(s);
        hd_istream_close(s);
        return fflush(stdout) ? 1 : 0;
    }

    char dims[1024];
    for (int i = 1; i < argc; i++) {
        hd_istream *s;
        outs(argv[i]);
        if (hd_istream_open(&s, argv[i])) {
            outs(": cannot open\n");
            fflush(stdout);
            fprintf(stderr, "%s: %s\n", hd_progname(), hd_errmsg());
            failed = 1;
            continue;
        }
        char *text;
        size_t len;
        if (dim < 0) {
            if (hd_info_read_raw(s, &text, &len)) {
                outs(": bad header!\n");
                fflush(stdout);
                hd_report_error();
                failed = 1;
            } else {
                outs(": ");
                hd_info_dimensions(s, text, dims, sizeof dims);
                outs(dims);
                free(text);
            }
        } else {
            outs(":\n\t");
            if (hd_info_read_raw(s, &text, &len)) {
                fflush(stdout);
                hd_istream_close(s);
                die_ctx("bad header");
            }
            put_tabbed(text, len);
            out("\n", 1);
            if (dim > 0) {
                out("\t", 1);
                hd_info_dimensions(s, text, dims, sizeof dims);
                outs(dims);
            }
            free(text);
        }
        hd_istream_close(s);
    }
    if (argc == 1) {
        hd_istream *s = open_stdin();
        char *text;
        size_t len;
        text = read_header_or_die(s, &len);
        if (dim < 0) {
            hd_info_dimensions(s, text, dims, sizeof dims);
            outs(dims);
        } else {
            out(text, len);
            out("\n", 1);
            if (dim > 0) {
                hd_info_dimensions(s, text, dims, sizeof dims);
                outs(dims);
            }
        }
        free(text);
        hd_istream_close(s);
    }
    if (fflush(stdout)) {
        fprintf(stderr, "%s: write error on standard output\n", hd_progname());
        return 1;
    }
    return failed;
}

/* rcollate — reshape, transpose or re-block a matrix of records
 * (Radiance's rcollate).  A record is NCOMP words (ASCII) or NCOMP binary
 * values (-ff/-fd/-fb); the input header gives NROWS, NCOLS, NCOMP and
 * FORMAT unless -hi; -t transposes, -ic/-ir/-oc/-or give the shapes,
 * -o RxC[xR1xC1...] writes nested blocks, -c checks the data, -w turns
 * warnings off.  Shapes that need the whole matrix (transpose, blocks, an
 * output header without a row count) load the input in memory; a plain
 * reshape of ASCII records streams. */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/header.h"

#define MAXLEVELS 16

static int warnings = 1, check = 0, transpose = 0, i_header = 1, o_header = 1;
static char fmtbuf[64];
static const char *fmtid = NULL;
static int comp_size = 0, n_comp = 0;
static int ni_cols = 0, ni_rows = 0, no_cols = 0, no_rows = 0;
static int blk[MAXLEVELS][2], nlevels = 0;

static int bad(const char *msg)
{
    fputs(msg, stderr);
    return 0;
}

/* ---- input in memory ---- */
static unsigned char *buf;
static size_t blen, bpos;

static int readall(FILE *fp)
{
    size_t cap = 1 << 16;
    buf = hd_malloc(cap + 1);
    if (!buf) return -1;
    for (;;) {
        if (blen == cap) {
            unsigned char *nb = hd_realloc_array(buf, cap * 2 + 1, 1);
            if (!nb) return -1;
            buf = nb;
            cap *= 2;
        }
        size_t n = fread(buf + blen, 1, cap - blen, fp);
        if (!n) break;
        blen += n;
    }
    buf[blen] = 0;
    return ferror(fp) ? -1 : 0;
}

/* ---- header ---- */
static hd_header oh;   /* the output header's lines (hd_header_put writes it) */

static int header_line(const char *line)
{
    if (!strncmp(line, "FORMAT=", 7)) {
        char f[64];
        size_t n = 0;
        for (const char *p = line + 7; *p && !isspace((unsigned char)*p) && n + 1 < sizeof f; p++) f[n++] = *p;
        f[n] = 0;
        if (!fmtid) { hd_strlcpy(fmtbuf, f, sizeof fmtbuf); fmtid = fmtbuf; return 1; }
        if (!check && comp_size == 1 && n_comp > 1) return 1;
        if (!strcmp(f, fmtid)) return 1;
        fprintf(stderr, "Input format '%s' != '%s'\n", f, fmtid);
        return -1;
    }
    if (!strncmp(line, "NROWS=", 6)) {
        int n = atoi(line + 6);
        if (ni_rows > 0 && n != ni_rows) { bad("Incorrect input row count\n"); return -1; }
        ni_rows = n;
        return 1;
    }
    if (!strncmp(line, "NCOLS=", 6)) {
        int n = atoi(line + 6);
        if (ni_cols > 0 && n != ni_cols) { bad("Incorrect input column count\n"); return -1; }
        ni_cols = n;
        return 1;
    }
    if (!strncmp(line, "NCOMP=", 6)) {
        if (!check && comp_size == 1 && n_comp > 1) return 1;
        int n = atoi(line + 6);
        if (n_comp > 0 && n != n_comp) { bad("Incorrect number of components\n"); return -1; }
        n_comp = n;
        return 1;
    }
    return 0;
}

/* read the header at bpos (lines to an empty one); keep the other lines
 * (a leading "#?" line as the identifier) for the output header */
static int read_header(void)
{
    for (int first = 1; bpos < blen; first = 0) {
        const unsigned char *e = memchr(buf + bpos, '\n', blen - bpos);
        size_t len = e ? (size_t)(e - (buf + bpos)) : blen - bpos;
        char line[4096];
        hd_strlcpy(line, (const char *)buf + bpos, len < sizeof line ? len + 1 : sizeof line);
        bpos += len + (e != NULL);
        if (len == 0) return 0;
        int r = header_line(line);
        if (r < 0) return -1;
        if (r > 0 || !o_header) continue;
        if (first && !strncmp(line, "#?", 2)) hd_strlcpy(oh.ident, line + 2, sizeof oh.ident);
        else if (hd_header_append(&oh, line)) return -1;
    }
    return 0;
}

/* the output header: its lines, NROWS and NCOLS (when known), FORMAT */
static int put_header(void)
{
    hd_header_dims d = {no_rows > 0 ? no_rows : 0, no_cols > 0 ? no_cols : 0, 0, HD_ENDIAN_NONE};
    if (hd_header_put(stdout, &oh, &d, fmtid, NULL) != HD_OK) return bad("Error writing to stdout\n");
    return 1;
}

/* ---- ASCII records ---- */
static size_t *rec;         /* start offsets; rec[nrecs] = end */
static size_t nrecs;

static int isws(int c) { return c == 0 || isspace(c); }

static int index_records(void)
{
    size_t cap = 1024, p = bpos;
    rec = hd_malloc_array(cap + 1, sizeof *rec);
    if (!rec) return 0;
    for (;;) {
        while (p < blen && isws(buf[p])) p++;
        if (p >= blen) break;
        if (nrecs >= cap) {
            size_t *nr = hd_realloc_array(rec, cap * 2 + 1, sizeof *nr);
            if (!nr) return 0;
            rec = nr;
            cap *= 2;
        }
        rec[nrecs++] = p;
        int n = n_comp;
        while (++p < blen)
            if (isws(buf[p])) {
                if (--n <= 0) break;
                do {
                    if (buf[p] == '\n') return bad("Unexpected EOL in record!\n");
                    if (++p >= blen) break;
                } while (isws(buf[p]));
            }
    }
    rec[nrecs] = blen;
    return 1;
}

static int count_columns(void)
{
    if (!nrecs) return 0;
    size_t p = rec[0];
    while (p < blen && buf[p] != '\n') p++;
    if (p >= blen) return 0;
    size_t i;
    for (i = 0; i < nrecs; i++)
        if (rec[i] >= p) break;
    return (int)i;
}

static int isnumword(const unsigned char *s)
{
    char *end;
    strtod((const char *)s, &end);
    return end != (const char *)s && isws((unsigned char)*end);
}

static int print_record(size_t n)
{
    size_t p = rec[n], end = rec[n + 1];
    int words = n_comp;
    if (check && !isnumword(buf + p)) goto formerr;
    do {
        putchar(buf[p++]);
        if (p >= blen || isws(buf[p])) {
            if (--words <= 0) break;
            putchar(' ');
            do {
                if (++p >= end) break;
            } while (isws(buf[p]));
            if (check && p < end && !isnumword(buf + p)) goto formerr;
        }
    } while (p < end);
    return 1;
formerr:
    fputs("Badly formed number: ", stderr);
    while (p < blen && !isws(buf[p])) fputc(buf[p++], stderr);
    fputc('\n', stderr);
    return 0;
}

/* ---- shapes ---- */
static int parse_blocks(const char *spec, int lvl)
{
    if (lvl >= MAXLEVELS) { bad("Too many block levels!\n"); exit(1); }
    char *e;
    long r = strtol(spec, &e, 10);
    if (e == spec || *e != 'x') { bad("Bad block specification!\n"); exit(1); }
    const char *c0 = e + 1;
    long c = strtol(c0, &e, 10);
    if (e == c0) { bad("Bad block specification!\n"); exit(1); }
    blk[lvl][0] = (int)r;
    blk[lvl][1] = (int)c;
    if (*e != 'x' && *e != 'X') {
        if (*e) { bad("Blocks must be separated by 'x' or 'X'\n"); exit(1); }
        return 1;
    }
    int n = parse_blocks(e + 1, lvl + 1);
    blk[lvl][0] *= blk[lvl + 1][0];
    blk[lvl][1] *= blk[lvl + 1][1];
    return n + 1;
}

static size_t block_pos(int r, int c)
{
    size_t n = 0;
    int l = 0;
    while (nlevels - l > 1) {
        int sr = r / blk[l + 1][0], sc = c / blk[l + 1][1];
        r -= sr * blk[l + 1][0];
        c -= sc * blk[l + 1][1];
        n += (size_t)sr * blk[l + 1][0] * blk[l][1] + (size_t)sc * blk[l + 1][0] * blk[l + 1][1];
        l++;
    }
    return n + (size_t)r * blk[l][1] + c;
}

static size_t input_pos(int r, int c)
{
    if (nlevels > 1) {
        size_t n = block_pos(r, c);
        if (transpose) {
            size_t rr = n / (size_t)ni_rows, cc = n - rr * (size_t)ni_rows;
            n = cc * (size_t)ni_cols + rr;
        }
        return n;
    }
    if (transpose) return (size_t)c * ni_cols + r;
    return (size_t)r * no_cols + c;
}

static int reorder(void)
{
    if (ni_rows <= 0) ni_rows = transpose ? no_cols : no_rows;
    if (ni_cols <= 0) ni_cols = transpose ? no_rows : no_cols;
    size_t n_in;
    size_t recsize = (size_t)n_comp * comp_size;
    if (!comp_size) {
        if (!index_records()) return 0;
        if (ni_cols <= 0) ni_cols = count_columns();
        n_in = nrecs;
    } else if (ni_rows > 0 && ni_cols > 0) {
        n_in = (size_t)ni_rows * ni_cols;
        if (n_in > (blen - bpos) / recsize) return bad("Input too small for specified size and type\n");
    } else {
        n_in = (blen - bpos) / recsize;
    }
    if (ni_rows <= 0 && ni_cols > 0) ni_rows = (int)(n_in / ni_cols);
    else if (ni_cols <= 0 && ni_rows > 0) ni_cols = (int)(n_in / ni_rows);
    if (n_in != (size_t)ni_rows * ni_cols) return bad("Bad dimension(s)\n");
    if (transpose) {
        if (no_cols <= 0) no_cols = ni_rows;
        if (no_rows <= 0) no_rows = ni_cols;
        if (nlevels <= 1 && (no_rows != ni_cols || no_cols != ni_rows)) return bad("Bad dimension(s)\n");
    } else {
        if (no_cols <= 0) no_cols = ni_cols;
        if (no_rows <= 0) no_rows = ni_rows;
    }
    if ((size_t)ni_rows * ni_cols != (size_t)no_rows * no_cols)
        return bad("Number of input and output records do not match\n");
    if (o_header && !put_header()) return 0;
    for (int i = 0; i < no_rows; i++) {
        for (int j = 0; j < no_cols; j++) {
            size_t n = input_pos(i, j);
            if (n >= n_in) return bad("Index past end-of-file\n");
            if (!comp_size) {
                if (!print_record(n)) return 0;
                putchar(j >= no_cols - 1 ? '\n' : '\t');
            } else {
                fwrite(buf + bpos + recsize * n, recsize, 1, stdout);
            }
        }
        if (ferror(stdout)) return bad("Error writing to stdout\n");
    }
    return 1;
}

/* next word of the ASCII data at bpos; stops on the following EOL or word */
static int next_word(char *w, size_t cap)
{
    while (bpos < blen && isws(buf[bpos])) bpos++;
    if (bpos >= blen) return 0;
    size_t n = 0;
    while (bpos < blen && !isws(buf[bpos])) {
        if (n + 1 < cap) w[n++] = (char)buf[bpos];
        bpos++;
    }
    w[n] = 0;
    while (bpos < blen && isspace(buf[bpos]) && buf[bpos] != '\n') bpos++;
    return 1;
}

static int resize(void)
{
    size_t togo = (size_t)ni_rows * ni_cols;
    if (o_header && !put_header()) return 0;
    size_t rest = blen - bpos;
    if (comp_size) {
        fwrite(buf + bpos, 1, rest, stdout);
        if (no_rows > 0 && no_cols > 0 && rest != (size_t)no_rows * no_cols * n_comp * comp_size) {
            if (check) return bad("Incorrect binary file size\n");
            if (warnings) fputs("Warning -- unexpected binary file size\n", stderr);
        }
        return rest > 0;
    }
    if (!check && no_cols == ni_cols && no_rows == ni_rows) {
        fwrite(buf + bpos, 1, rest, stdout);
        return rest > 0;
    }
    if (no_cols <= 0) return bad("Missing -oc specification\n");
    int unlimited = 0;
    if (togo == 0 && no_rows > 0) togo = (size_t)no_rows * no_cols;
    else if ((size_t)no_rows * no_cols != togo) {
        fprintf(stderr, "Number of input and output records disagree (%dx%d != %dx%d)\n",
                ni_rows, ni_cols, no_rows, no_cols);
        return 0;
    }
    if (togo == 0) unlimited = 1;       /* until the data end (which is then an error) */
    int colsleft = no_cols;
    char w[256];
    for (;;) {
        int n = n_comp;
        while (n--) {
            if (!next_word(w, sizeof w)) {
                if (togo > 0 || unlimited || n < n_comp - 1) break;
                goto done;
            }
            if (check) {
                char *e;
                strtod(w, &e);
                if (e == w || *e) {
                    fprintf(stderr, "Badly formed number: %s\n", w);
                    return 0;
                }
            }
            fputs(w, stdout);
            if (n) {
                if (bpos >= blen || buf[bpos] == '\n') break;
                putchar(' ');
            }
        }
        if (n >= 0) return bad("Incomplete record / unexpected EOF\n");
        if (--colsleft <= 0) {
            putchar('\n');
            colsleft = no_cols;
        } else {
            putchar('\t');
        }
        if (!unlimited && --togo == 0) break;
    }
done:
    if (colsleft != no_cols) {
        if (check) return bad("Incomplete final row\n");
        if (warnings) fputs("Warning -- incomplete final row\n", stderr);
    }
    if (next_word(w, sizeof w)) {
        if (check) return bad("Characters beyond expected EOD\n");
        if (warnings) fputs("Warning -- characters beyond expected EOD\n", stderr);
    }
    return 1;
}

static _Noreturn void usage(const char *prog)
{
    fprintf(stderr, "Usage: %s [-h[io]][-w][-c][-f[afdb][N]][-t][-ic in_col][-ir in_row][-oc out_col]"
                    "[-or out_row][-o RxC[xR1xC1..]] [input.dat]\n", prog);
    exit(1);
}

int main(int argc, char **argv)
{
    const char *prog = argv[0];
    hd_set_progname(prog);
    hd_header_init(&oh);
    int a;
    for (a = 1; a < argc && argv[a][0] == '-'; a++) {
        const char *o = argv[a];
        switch (o[1]) {
        case 'i':
            if (a + 1 >= argc) usage(prog);
            if (o[2] == 'c') ni_cols = atoi(argv[++a]);
            else if (o[2] == 'r') ni_rows = atoi(argv[++a]);
            else usage(prog);
            break;
        case 'o':
            if (o[2] == 'c' && a + 1 < argc) no_cols = atoi(argv[++a]);
            else if (o[2] == 'r' && a + 1 < argc) no_rows = atoi(argv[++a]);
            else if (!o[2] && a + 1 < argc) nlevels = parse_blocks(argv[++a], 0);
            else usage(prog);
            break;
        case 'h':
            if (o[2] == 'i') i_header = 0;
            else if (o[2] == 'o') o_header = 0;
            else if (!o[2]) i_header = o_header = 0;
            else usage(prog);
            break;
        case 't': transpose = !transpose; break;
        case 'f':
            switch (o[2]) {
            case 'a': case 'A': fmtid = "ascii"; comp_size = 0; break;
            case 'f': case 'F': fmtid = "float"; comp_size = 4; break;
            case 'd': case 'D': fmtid = "double"; comp_size = 8; break;
            case 'b': case 'B': fmtid = "byte"; comp_size = 1; break;
            default: usage(prog);
            }
            if (o[3]) {
                if (!isdigit((unsigned char)o[3])) usage(prog);
                n_comp = atoi(o + 3);
            } else {
                n_comp = 1;
            }
            break;
        case 'w': warnings = !warnings; break;
        case 'c': check = 1; break;
        default: usage(prog);
        }
    }
    if (a < argc - 1) usage(prog);
    if (nlevels) {
        no_rows = blk[0][0];
        no_cols = blk[0][1];
    }
    FILE *in = stdin;
    if (a == argc - 1 && !(in = fopen(argv[a], "rb"))) {
        fprintf(stderr, "%s: cannot open for reading\n", argv[a]);
        return 1;
    }
    if (readall(in) < 0) {
        fprintf(stderr, "%s: error loading input into memory\n", a == argc - 1 ? argv[a] : prog);
        return 1;
    }
    if (!transpose && !check && nlevels <= 1 && i_header == o_header && no_cols == ni_cols && no_rows == ni_rows) {
        if (warnings) fprintf(stderr, "%s: no-op -- copying input verbatim\n", prog);
        fwrite(buf, 1, blen, stdout);
        return fflush(stdout) ? 1 : 0;
    }
    if (i_header && read_header() < 0) return 1;
    /* defaults */
    if (!fmtid) {
        fmtid = "ascii";
    } else if (!comp_size) {
        if (!strcmp(fmtid, "float")) comp_size = 4;
        else if (!strcmp(fmtid, "double")) comp_size = 8;
        else if (!strcmp(fmtid, "byte")) comp_size = 1;
        else if (strcmp(fmtid, "ascii")) { fprintf(stderr, "Unsupported format: %s\n", fmtid); return 1; }
    }
    if (transpose && no_rows <= 0 && no_cols <= 0) {
        if (ni_rows > 0) no_cols = ni_rows;
        if (ni_cols > 0) no_rows = ni_cols;
    } else {
        if (no_cols <= 0) no_cols = ni_cols;
        if (no_rows <= 0 && no_cols > 0 && !(((long long)ni_rows * ni_cols) % no_cols))
            no_rows = (int)((long long)ni_rows * ni_cols / no_cols);
    }
    if (n_comp <= 0) n_comp = 3;
    if (o_header && (hd_header_add_command(&oh, a, argv) || hd_header_appendf(&oh, "NCOMP=%d", n_comp))) hd_die();
    int ok = (transpose || nlevels > 1 || (o_header && no_rows <= 0)) ? reorder() : resize();
    if (fflush(stdout) || ferror(stdout)) return 1;
    return ok ? 0 : 1;
}

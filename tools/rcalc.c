/* rcalc — record calculator (Radiance's rcalc): evaluate .cal definitions
 * of output channels $1.. for every input record.
 *
 * Input: TAB (or -tS) separated columns read as $N, binary -id/-if[N]
 * (-iD/-iF swapped), or records matched by a format (-i fmt) whose ${name}
 * fields become variables and $(name) fields strings.  Output: columns
 * (%.9g), binary -od/-of, or a format (-o fmt) with ${expr} fields.
 * Options are parsed in order as Radiance does (-e/-f definitions stack). */
#include <ctype.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/cal.h"
#include "cal_internal.h"

enum { F_LIT, F_NUM, F_STR };

typedef struct field {
    int type;
    int width;          /* characters the field occupies in the format */
    char *text;         /* literal text, variable name, string name */
    int expr;           /* output numeric field: expression id */
    int svar;           /* string variable index */
} field;

typedef struct fmt { field *f; int n; } fmt;

typedef struct svar { char *name; char *val; char *preset; } svar;

static hd_cal *C;
static hd_calrun *R;
static int blnkeq = 1, igneol = 0, passive = 0, unbuff = 0, noinput = 0;
static char sepchar = '\t';
static int itype = 'a', otype = 'a', nbicols = 0;
static long incnt = 0, outcnt = 0;
static fmt inpfmt, outfmt;
static int have_inpfmt = 0, have_outfmt = 0;
static svar *svars;
static int nsvars;
static char *line;              /* current text record */
static size_t linecap;
static unsigned char binbuf[8 * 4096];
static double colval[64];
static uint64_t colflg;

static void die(const char *msg)
{
    fputs(msg, stderr);
    exit(1);
}

static void die_cal(void)
{
    fflush(stdout);
    fprintf(stderr, "%s\n", hd_errmsg());
    exit(1);
}

static void check_run(void)
{
    if (hd_calrun_status(R) != HD_OK) die_cal();
}

static int isblnk(int c) { return igneol ? c != EOF && isspace(c) : c == ' ' || c == '\t'; }
static int isnumc(int c) { return isdigit(c) || c == '-' || c == '.' || c == '+' || c == 'e' || c == 'E'; }

/* ---- channels ---- */
static double chanvalue(hd_calrun *r, void *u, int n)
{
    (void)r; (void)u;
    if (noinput || have_inpfmt) die("no column input\n");
    if (n < 1) die("illegal channel number\n");
    if (nbicols) {
        if (n > nbicols) return 0.0;
        if (itype == 'd' || itype == 'D') {
            double d;
            memcpy(&d, binbuf + (size_t)(n - 1) * 8, 8);
            return d;
        }
        float f;
        memcpy(&f, binbuf + (size_t)(n - 1) * 4, 4);
        return f;
    }
    if (n <= 64 && (colflg >> (n - 1) & 1)) return colval[n - 1];
    const char *cp = line ? line : "";
    for (int i = 1; i < n; i++) {
        if (blnkeq && isspace((unsigned char)sepchar)) {
            while (isspace((unsigned char)*cp)) cp++;
            while (*cp && !isspace((unsigned char)*cp)) cp++;
        } else {
            while (*cp && *cp++ != sepchar)
                ;
        }
    }
    while (isspace((unsigned char)*cp)) cp++;
    double v = atof(cp);
    if (n <= 64) { colflg |= (uint64_t)1 << (n - 1); colval[n - 1] = v; }
    return v;
}

static double l_in(hd_calrun *r, void *u, int nargs, const double *a)
{
    (void)u; (void)nargs;
    int n = (int)(a[0] + .5);
    if (n != 0) return chanvalue(r, NULL, n);
    if (noinput || have_inpfmt) return 0;
    if (nbicols) return nbicols;
    const char *cp = line ? line : "";
    n = 0;
    while (*cp) {
        if (blnkeq && isspace((unsigned char)sepchar)) {
            while (isspace((unsigned char)*cp)) cp++;
            n += *cp != '\0';
            while (*cp && !isspace((unsigned char)*cp)) cp++;
        } else {
            n += *cp != '\n';
            while (*cp && *cp++ != sepchar)
                ;
        }
    }
    return n;
}

/* ---- output ---- */
static int colpos;

static void putbin(double v, int n)
{
    static const unsigned char zero[8];
    int len = otype == 'd' || otype == 'D' ? 8 : 4;
    while (++colpos < n) fwrite(zero, (size_t)len, 1, stdout);
    unsigned char b[8];
    if (len == 8) memcpy(b, &v, 8);
    else { float f = (float)v; memcpy(b, &f, 4); }
    if (otype == 'D' || otype == 'F')
        for (int i = 0; i < len / 2; i++) { unsigned char t = b[i]; b[i] = b[len - 1 - i]; b[len - 1 - i] = t; }
    fwrite(b, (size_t)len, 1, stdout);
}

static void chanout(void)
{
    int max = hd_cal_max_outchan(C);
    for (int n = 1; n <= max; n++) {
        if (!hd_cal_has_outchan(C, n)) continue;
        double v = hd_calrun_outchan(R, n);
        check_run();
        if (otype == 'a') {
            if (colpos == 0) colpos = 1;
            while (colpos < n) { putchar(sepchar); colpos++; }
            printf("%.9g", v);
        } else {
            putbin(v, n);
        }
    }
}

static void putrec(void)
{
    int adlast = 0;
    for (int i = 0; i < outfmt.n; i++) {
        const field *f = &outfmt.f[i];
        int adnext = blnkeq && i + 1 < outfmt.n &&
                     !(outfmt.f[i + 1].type == F_LIT && outfmt.f[i + 1].text[0] == ' ');
        if (f->type == F_LIT) {
            fputs(f->text, stdout);
            size_t l = strlen(f->text);
            adlast = l && f->text[l - 1] != ' ';
        } else if (f->type == F_STR) {
            const svar *s = &svars[f->svar];
            if (!s->val) { fflush(stdout); fprintf(stderr, "%s: undefined string\n", s->name); exit(1); }
            int n = f->width - (int)strlen(s->val);
            if (adlast) fputs(s->val, stdout);
            if (!(adlast && adnext))
                while (n-- > 0) putchar(' ');
            if (!adlast) fputs(s->val, stdout);
            adlast = 1;
        } else {
            int n = f->width;
            double dv = hd_calrun_expr(R, f->expr);
            check_run();
            double av = fabs(dv);
            char typ[16], fm[40];
            if (n <= 9) strcpy(typ, "g");
            else snprintf(typ, sizeof typ, ".%de", n - 5);
            if (av < 2147483648.0) {
                long iv = (long)(av + .5);
                if (iv && fabs(av - (double)iv) <= av * 1e-14) strcpy(typ, ".0f");
            }
            if (adlast && adnext) snprintf(fm, sizeof fm, "%%%s", typ);
            else if (adlast) snprintf(fm, sizeof fm, "%%-%d%s", n, typ);
            else snprintf(fm, sizeof fm, "%%%d%s", n, typ);
            printf(fm, dv);
            adlast = 1;
        }
    }
}

static void putout(void)
{
    colpos = 0;
    if (have_outfmt) putrec();
    else chanout();
    if (colpos && otype == 'a') putchar('\n');
    if (unbuff) fflush(stdout);
}

/* ---- formats ---- */
static int getsvar(const char *name)
{
    for (int i = 0; i < nsvars; i++)
        if (!strcmp(svars[i].name, name)) return i;
    svar *ns = hd_realloc_array(svars, (size_t)nsvars + 1, sizeof *ns);
    if (!ns) hd_die();
    svars = ns;
    svars[nsvars].name = hd_strdup(name);
    svars[nsvars].val = svars[nsvars].preset = NULL;
    return nsvars++;
}

static void svpreset(const char *eqn)
{
    const char *eq = strchr(eqn, '=');
    if (!eq) return;
    char name[256];
    snprintf(name, sizeof name, "%.*s", (int)(eq - eqn), eqn);
    int i = getsvar(name);
    svars[i].preset = svars[i].val = hd_strdup(eq + 1);
}

static char *readwhole(FILE *fp, size_t *len)
{
    size_t cap = 65536, n = 0;
    char *b = hd_malloc(cap);
    if (!b) hd_die();
    for (;;) {
        if (n + 1 >= cap) {
            char *nb = hd_realloc_array(b, cap, 2);
            if (!nb) hd_die();
            b = nb;
            cap *= 2;
        }
        size_t got = fread(b + n, 1, cap - n - 1, fp);
        if (!got) break;
        n += got;
    }
    b[n] = 0;
    *len = n;
    return b;
}

static void readfmt(const char *spec, int output)
{
    char *text;
    if (strchr(spec, '$')) {
        text = hd_strdup(spec);
    } else {
        FILE *fp = fopen(spec, "r");
        if (!fp) { fprintf(stderr, "%s: cannot open\n", spec); exit(1); }
        size_t len;
        text = readwhole(fp, &len);
        fclose(fp);
        if (len == 0) { fprintf(stderr, "%s: empty file\n", spec); exit(1); }
    }
    fmt *fm = output ? &outfmt : &inpfmt;
    const char *p = text;
    size_t cap = strlen(text) + 8;
    char *buf = hd_malloc(cap);
    if (!buf) hd_die();
    while (*p) {
        int type = -1, width = 0;
        size_t b = 0;
        while (*p) {
            width++;
            if (type < 0) {
                if (*p == '$') {
                    p++;
                    width++;
                    if (*p == '{') { type = F_NUM; p++; continue; }
                    if (*p == '(') { type = F_STR; p++; continue; }
                    if (*p != '$') die("format error\n");
                    width--;
                }
                type = F_LIT;
                buf[b++] = *p++;
                continue;
            }
            if (type == F_LIT) {
                if (*p == '$') { width--; break; }
                buf[b++] = *p++;
                continue;
            }
            if (*p == (type == F_NUM ? '}' : ')')) { p++; break; }
            if (!isspace((unsigned char)*p)) buf[b++] = *p;
            p++;
        }
        buf[b] = 0;
        field *nf = hd_realloc_array(fm->f, (size_t)fm->n + 2, sizeof *nf);
        if (!nf) hd_die();
        fm->f = nf;
        field *f = &fm->f[fm->n++];
        memset(f, 0, sizeof *f);
        f->type = type;
        f->width = width;
        f->text = hd_strdup(buf);
        if (type == F_STR) f->svar = getsvar(buf);
        else if (type == F_NUM && output) {
            if (hd_cal_expr(C, buf, NULL, &f->expr) != HD_OK) die_cal();
        }
        if (!igneol && !*p && p > text && p[-1] != '\n') {
            /* a final newline ends every record */
            field *g = &fm->f[fm->n++];
            memset(g, 0, sizeof *g);
            g->type = F_LIT;
            g->width = 1;
            g->text = hd_strdup("\n");
            break;
        }
    }
    free(buf);
    free(text);
    if (output) have_outfmt = 1;
    else have_inpfmt = 1;
}

/* ---- formatted input: the whole input in memory, matched at pos ---- */
static char *ib;
static size_t ilen, ipos, ibeg;
static double *nvals;
static unsigned char *nset;

static int ichr(size_t pos) { return pos < ilen ? (unsigned char)ib[pos] : EOF; }

static void skipinp(void)          /* back to the record start and one on */
{
    if (passive && ibeg < ilen) putchar(ib[ibeg]);
    ibeg++;
    ipos = ibeg;
}

static int getfield(int i)
{
    field *f = &inpfmt.f[i];
    char buf[1024];
    if (f->type == F_LIT) {
        const char *cp = f->text;
        do {
            if (blnkeq && isblnk((unsigned char)*cp)) {
                if (!isblnk(ichr(ipos))) return 0;
                do cp++; while (isblnk((unsigned char)*cp));
                do ipos++; while (isblnk(ichr(ipos)));
            } else if ((unsigned char)*cp == ichr(ipos)) {
                cp++;
                ipos++;
            } else {
                return 0;
            }
        } while (*cp);
        return 1;
    }
    int delim = i + 1 < inpfmt.n && inpfmt.f[i + 1].type == F_LIT ? (unsigned char)inpfmt.f[i + 1].text[0] : EOF;
    size_t n = 0;
    if (f->type == F_STR) {
        for (;;) {
            int c = ichr(ipos), inword;
            if (c == EOF || c == '\n') inword = 0;
            else if (blnkeq && delim != EOF) inword = isblnk(delim) ? !isblnk(c) : c != delim;
            else inword = (int)n < f->width;
            if (!inword || n >= sizeof buf - 1) break;
            buf[n++] = (char)c;
            ipos++;
        }
        buf[n] = 0;
        svar *s = &svars[f->svar];
        if (!s->val) s->val = hd_strdup(buf);
        else if (strcmp(s->val, buf)) return 0;
        return 1;
    }
    long np = -1;
    for (;;) {
        int c = ichr(ipos), inword;
        if (!((np < 0 && isblnk(c)) || (c != EOF && isnumc(c)))) inword = 0;
        else if (blnkeq && delim != EOF) inword = isblnk(delim) ? !isblnk(c) : c != delim;
        else inword = (int)n < f->width;
        if (!inword || n >= sizeof buf - 1) break;
        if (np < 0 && !isblnk(c)) np = (long)n;
        buf[n++] = (char)c;
        ipos++;
    }
    buf[n] = 0;
    double d = np < 0 ? 0.0 : atof(buf + np);
    if (!nset[i]) {
        /* same variable earlier in this record? */
        for (int j = 0; j < i; j++)
            if (inpfmt.f[j].type == F_NUM && nset[j] && !strcmp(inpfmt.f[j].text, f->text)) {
                double rel = (nvals[j] - d) / (d == 0.0 ? 1.0 : d);
                if (rel > .001 || rel < -.001) return 0;
                return 1;
            }
        nset[i] = 1;
        nvals[i] = d;
        hd_cal_set(C, f->text, d, 0);
    }
    return 1;
}

static void clearrec(void)
{
    for (int i = 0; i < inpfmt.n; i++) {
        nset[i] = 0;
        if (inpfmt.f[i].type == F_STR) {
            svar *s = &svars[inpfmt.f[i].svar];
            if (s->val != s->preset) { free(s->val); s->val = s->preset; }
        }
    }
}

static int getrec(void)
{
    while (ipos < ilen) {
        if (blnkeq) {
            while (isblnk(ichr(ipos))) skipinp();
            if (ipos >= ilen) return 0;
        }
        int eatline = !igneol && ichr(ipos) != '\n';
        clearrec();
        int i;
        for (i = 0; i < inpfmt.n; i++)
            if (!getfield(i)) break;
        if (i == inpfmt.n) return 1;
        skipinp();
        if (eatline) {
            while (ichr(ipos) != '\n') {
                if (ipos >= ilen) return 0;
                skipinp();
            }
            skipinp();
        }
    }
    return 0;
}

static int getline_rec(FILE *fp)
{
    if (itype == 'a') {
        ssize_t n = getline(&line, &linecap, fp);
        return n >= 0;
    }
    size_t sz = itype == 'd' || itype == 'D' ? 8 : 4;
    if (fread(binbuf, sz, (size_t)nbicols, fp) != (size_t)nbicols) return 0;
    if (itype == 'D' || itype == 'F')
        for (int c = 0; c < nbicols; c++) {
            unsigned char *b = binbuf + (size_t)c * sz;
            for (size_t k = 0; k < sz / 2; k++) { unsigned char t = b[k]; b[k] = b[sz - 1 - k]; b[sz - 1 - k] = t; }
        }
    return 1;
}

static void execute(const char *file)
{
    FILE *fp = stdin;
    if (file && !(fp = fopen(file, "r"))) { fprintf(stderr, "%s: cannot open\n", file); exit(1); }
    int conditional = hd_cal_defined(C, "cond");
    if (conditional && hd_cal_is_const(C, "cond")) die("cond: defined as constant\n");
    long nrecs = 0, nout = 0;
    int set_recno = hd_cal_named(C, "recno"), set_outno = hd_cal_named(C, "outno");
    if (have_inpfmt) {
        free(ib);
        ib = readwhole(fp, &ilen);
        ipos = ibeg = 0;
    }
    while (have_inpfmt ? getrec() : getline_rec(fp)) {
        ++nrecs;
        if (set_recno) hd_cal_set(C, "recno", (double)nrecs, 0);
        if (set_outno) hd_cal_set(C, "outno", (double)(nout + 1), 0);
        colflg = 0;
        hd_calrun_next(R);
        int ok = 1;
        if (conditional) {
            ok = hd_calrun_var(R, "cond") > 0.0;
            check_run();
        }
        if (ok) {
            if (have_inpfmt) ibeg = ipos;
            putout();
            ++nout;
        } else if (have_inpfmt) {
            if (passive < 0) fwrite(ib + ibeg, 1, ipos - ibeg, stdout);
            ibeg = ipos;
        }
        if (incnt && nrecs >= incnt) break;
        if (outcnt && nout >= outcnt) break;
    }
    if (have_inpfmt && passive) {
        /* unmatched tail goes through in passive mode */
        if (ibeg < ilen && ipos >= ilen) fwrite(ib + ibeg, 1, ilen - ibeg, stdout);
    }
    if (fp != stdin) fclose(fp);
}

static void usage(const char *prog)
{
    fprintf(stderr, "Usage: %s [-b][-l][-n][-p|-P][-w][-u][-tS][-s svar=sval][-e expr][-f source]"
                    "[-i infmt][-o outfmt] [file]\n", prog);
    exit(1);
}

static const char *next_arg(int argc, char **argv, int *i)
{
    if (*i + 1 >= argc) usage(argv[0]);
    return argv[++*i];
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    C = hd_cal_new();
    if (!C) hd_die();
    hd_cal_set(C, "PI", 3.14159265358979323846, 1);
    hd_cal_define_fn(C, "in", 1, 1, l_in, NULL, 0);
    int i;
    for (i = 1; i < argc && argv[i][0] == '-' && argv[i][1]; i++) {
        const char *a = argv[i];
        switch (a[1]) {
        case 'b': blnkeq = !blnkeq; break;
        case 'l': igneol = !igneol; break;
        case 'p': passive = 1; break;
        case 'P': passive = -1; break;
        case 't': sepchar = a[2]; break;
        case 's': svpreset(next_arg(argc, argv, &i)); break;
        case 'f': {
            const char *f = next_arg(argc, argv, &i);
            hd_status st = hd_cal_load(C, f);
            if (st == HD_ERR_IO) { hd_report_error(); exit(1); }
            if (st != HD_OK) die_cal();
            break;
        }
        case 'e':
            if (hd_cal_parse(C, next_arg(argc, argv, &i), NULL) != HD_OK) die_cal();
            break;
        case 'n':
            noinput = 1;
            hd_cal_rconst(C, 0);
            break;
        case 'i':
            switch (a[2]) {
            case 0: itype = 'a'; nbicols = 0; readfmt(next_arg(argc, argv, &i), 0); break;
            case 'n': incnt = atol(next_arg(argc, argv, &i)); break;
            case 'a': itype = 'a'; nbicols = 0; break;
            case 'd': case 'D': case 'f': case 'F':
                itype = a[2];
                nbicols = isdigit((unsigned char)a[3]) ? atoi(a + 3) : 1;
                if (nbicols < 1 || (size_t)nbicols * (itype == 'd' || itype == 'D' ? 8 : 4) > sizeof binbuf) {
                    fprintf(stderr, "%s: too many input columns\n", argv[0]);
                    exit(1);
                }
                break;
            default: usage(argv[0]);
            }
            break;
        case 'o':
            switch (a[2]) {
            case 0: otype = 'a'; readfmt(next_arg(argc, argv, &i), 1); break;
            case 'n': outcnt = atol(next_arg(argc, argv, &i)); break;
            case 'a': otype = 'a'; break;
            case 'd': case 'D': case 'f': case 'F': otype = a[2]; break;
            default: usage(argv[0]);
            }
            break;
        case 'w': hd_cal_warnings(C, 0); break;
        case 'u': unbuff = !unbuff; break;
        default: usage(argv[0]);
        }
    }
    R = hd_calrun_new(C, NULL);
    if (!R) hd_die();
    hd_calrun_set_chan(R, chanvalue, NULL);
    if (have_inpfmt) {
        nvals = hd_calloc((size_t)inpfmt.n + 1, sizeof *nvals);
        nset = hd_calloc((size_t)inpfmt.n + 1, 1);
        if (!nvals || !nset) hd_die();
    }
    if (noinput) {
        if (i < argc) { fprintf(stderr, "%s: file argument(s) incompatible with -n\n", argv[0]); exit(1); }
        hd_calrun_next(R);
        putout();
        return 0;
    }
    if (passive && (!have_inpfmt || !have_outfmt)) {
        fprintf(stderr, "%s: options -p and -P require -i and -o formats\n", argv[0]);
        exit(1);
    }
    if (blnkeq && have_inpfmt && inpfmt.n && inpfmt.f[0].type == F_LIT) {
        /* a leading blank in the format synchronises on non-blank input */
        char *t = inpfmt.f[0].text;
        while (isblnk((unsigned char)*t)) t++;
        if (!*t) { memmove(inpfmt.f, inpfmt.f + 1, (size_t)(--inpfmt.n) * sizeof *inpfmt.f); memmove(nset, nset + 1, (size_t)inpfmt.n); }
        else memmove(inpfmt.f[0].text, t, strlen(t) + 1);
    }
    if (i == argc) execute(NULL);
    else for (; i < argc; i++) execute(argv[i]);
    if (fflush(stdout) || ferror(stdout)) { fprintf(stderr, "%s: write error\n", argv[0]); return 1; }
    return 0;
}

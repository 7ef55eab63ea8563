/* total — reduce columns of numbers (Radiance's total): sum (default),
 * -p product, -u maximum, -l minimum, -sE sum of |x|^E, -m mean (with -sE
 * the E-th root of the mean), -N totals every N records (-r running
 * totals), -i[df][N] binary input, -o[df] binary output, -tC separator,
 * -in / -on record limits.  A record with no fields (blank line) ends a
 * group; an empty group ends the input, as Radiance's does. */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"

#define MAXCOL 81920

enum { ADD, MULT, VMAX, VMIN };
static const double init_val[] = {0.0, 1.0, -1e12, 1e12};

static int func = ADD, mean = 0, subtotal = 0, bocols = 0, nbicols = 0;
static double power = 0.0;
static long count = 0, incnt = 0, outcnt = 0, nrecsout = 0;
static int tabc = '\t';
static double *inpval, *tally, *result;
static signed char *rsign;
static char *line;
static size_t linecap;

static int issep(int c) { return isspace(tabc) ? isspace(c) : c == tabc; }

/* next record into inpval: number of fields, 0 at the end */
static int getrecord(FILE *fp)
{
    if (nbicols > 0) {
        size_t n = fread(inpval, sizeof(double), (size_t)nbicols, fp);
        return (int)n;
    }
    if (nbicols < 0) {
        float f[256];
        int want = -nbicols, got = 0;
        while (got < want) {
            int chunk = want - got > 256 ? 256 : want - got;
            size_t n = fread(f, sizeof(float), (size_t)chunk, fp);
            for (size_t i = 0; i < n; i++) inpval[got + (int)i] = f[i];
            got += (int)n;
            if ((int)n < chunk) break;
        }
        return got;
    }
    if (getline(&line, &linecap, fp) < 0) return 0;
    char *cp = line;
    int nf;
    for (nf = 0; nf < MAXCOL; nf++) {
        while (isspace((unsigned char)*cp)) cp++;
        if (!*cp) break;
        char *num = cp;
        while (*cp && !issep((unsigned char)*cp)) cp++;
        if (*cp) *cp++ = '\0';
        inpval[nf] = !*num || isspace((unsigned char)*num) ? init_val[func] : atof(num);
    }
    return nf;
}

static void putrecord(int n)
{
    if (bocols > 0) {
        fwrite(result, sizeof(double), (size_t)n, stdout);
        return;
    }
    if (bocols < 0) {
        for (int i = 0; i < n; i++) {
            float f = (float)result[i];
            fwrite(&f, sizeof f, 1, stdout);
        }
        return;
    }
    for (int i = 0; i < n; i++) {
        printf("%.9g", result[i]);
        if (i + 1 < n) putchar(tabc);
    }
    putchar('\n');
    if (!subtotal) fflush(stdout);
}

static int execute(const char *fname)
{
    FILE *fp = stdin;
    if (fname && !(fp = fopen(fname, "r"))) {
        fprintf(stderr, "%s: cannot open\n", fname);
        return -1;
    }
    long ltotal = 0;
    while (!feof(fp)) {
        if (ltotal == 0)
            for (int n = 0; n < MAXCOL; n++) {
                tally[n] = func == MULT ? 0.0 : init_val[func];
                rsign[n] = 1;
            }
        int ncol = 0, nread;
        long nlin;
        for (nlin = 0; (count <= 0 || nlin < count) && (incnt <= 0 || nlin < incnt) &&
                       (nread = getrecord(fp)) > 0; nlin++) {
            for (int n = 0; n < nread; n++) {
                double v = inpval[n];
                switch (func) {
                case ADD:
                    if (v == 0.0) break;
                    if (power == 0.0) tally[n] += v;
                    else if (power == 1.0) tally[n] += fabs(v);
                    else if (power == -1.0) tally[n] += 1.0 / fabs(v);
                    else tally[n] += pow(fabs(v), power);
                    break;
                case MULT:          /* sum of logarithms, sign apart */
                    if (v == 0.0) rsign[n] = 0;
                    else if (v < 0.0) { rsign[n] = (signed char)-rsign[n]; v = -v; }
                    if (rsign[n]) tally[n] += log(v);
                    break;
                case VMAX: if (v > tally[n]) tally[n] = v; break;
                case VMIN: if (v < tally[n]) tally[n] = v; break;
                }
            }
            if (nread > ncol) ncol = nread;
        }
        if (nlin == 0) break;
        ltotal += nlin;
        for (int n = 0; n < ncol; n++) {
            result[n] = tally[n];
            if (mean) {
                result[n] /= (double)ltotal;
                if (func == ADD && power != 0.0 && result[n] != 0.0) result[n] = pow(result[n], 1.0 / power);
            }
            if (func == MULT) result[n] = rsign[n] * exp(result[n]);
        }
        putrecord(ncol);
        ++nrecsout;
        if (outcnt > 0 && nrecsout >= outcnt) break;
        if (!subtotal) ltotal = 0;
        if (incnt > 0 && nlin >= incnt) break;
    }
    return fclose(fp) == EOF ? 1 : 0;
}

static _Noreturn void usage(const char *prog)
{
    fprintf(stderr, "Usage: %s [-m][-sE|p|u|l][-tC][-i{f|d}[N]][-o{f|d}][-count [-r]] [file..]\n", prog);
    exit(1);
}

static int colarg(const char *prog, const char *s)
{
    int n = isdigit((unsigned char)*s) ? atoi(s) : 1;
    if (n < 1 || n > MAXCOL) {
        fprintf(stderr, "%s: too many input columns\n", prog);
        exit(1);
    }
    return n;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    const char *prog = argv[0];
    int a;
    for (a = 1; a < argc && argv[a][0] == '-' && argv[a][1]; a++) {
        const char *o = argv[a];
        if (isdigit((unsigned char)o[1])) { count = atol(o + 1); continue; }
        switch (o[1]) {
        case 'm': mean = !mean; break;
        case 'p': func = MULT; break;
        case 's': power = atof(o + 2); break;
        case 'u': func = VMAX; break;
        case 'l': func = VMIN; break;
        case 't': tabc = (unsigned char)o[2]; break;
        case 'r': subtotal = !subtotal; break;
        case 'i':
            switch (o[2]) {
            case 'n': if (a + 1 >= argc) usage(prog); incnt = atol(argv[++a]); break;
            case 'a': nbicols = 0; break;
            case 'd': nbicols = colarg(prog, o + 3); break;
            case 'f': nbicols = -colarg(prog, o + 3); break;
            default: usage(prog);
            }
            break;
        case 'o':
            switch (o[2]) {
            case 'n': if (a + 1 >= argc) usage(prog); outcnt = atol(argv[++a]); break;
            case 'a': bocols = 0; break;
            case 'd': bocols = 1; break;
            case 'f': bocols = -1; break;
            default: usage(prog);
            }
            break;
        default: usage(prog);
        }
    }
    if (power != 0.0 && func != ADD) {
        fprintf(stderr, "%s: -sE option requires summation\n", prog);
        return 1;
    }
    if (mean && (func == VMAX || func == VMIN)) {
        fprintf(stderr, "%s: average %s?!\n", prog, func == VMAX ? "maximum" : "minimum");
        return 1;
    }
    inpval = hd_malloc_array(MAXCOL, sizeof *inpval);
    tally = hd_malloc_array(MAXCOL, sizeof *tally);
    result = hd_malloc_array(MAXCOL, sizeof *result);
    rsign = hd_malloc(MAXCOL);
    if (!inpval || !tally || !result || !rsign) hd_die();
    int status = 0;
    if (a >= argc) status = execute(NULL) == -1 ? 1 : 0;
    else
        for (; a < argc && (outcnt <= 0 || nrecsout < outcnt); a++)
            if (execute(argv[a]) == -1) status = 2;
    if (fflush(stdout) || ferror(stdout)) {
        fprintf(stderr, "%s: write error\n", prog);
        return 1;
    }
    return status;
}

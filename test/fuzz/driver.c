/* heliodon — runs a fuzz harness over files without libFuzzer (make check,
 * make check-asan; docs/fuzz.md).
 *   fuzz_NAME [-q] PATH...   each PATH a file or a directory of files
 * Prints "PASS: NAME: N inputs from PATH" per PATH; an input that crashes
 * the harness ends the process (the sanitizer build reports it). */
#include <dirent.h>
#include <stdio.h>
#include <sys/stat.h>

#include "fuzz.h"

static int run_file(const char *path)
{
    FILE *fp = fopen(path, "rb");
    if (!fp) { fprintf(stderr, "fuzz driver: cannot open %s\n", path); return -1; }
    size_t cap = 1 << 16, n = 0;
    uint8_t *buf = malloc(cap);
    for (;;) {
        if (!buf) abort();
        n += fread(buf + n, 1, cap - n, fp);
        if (n < cap) break;
        cap *= 2;
        buf = realloc(buf, cap);
    }
    int bad = ferror(fp);
    fclose(fp);
    if (bad) { free(buf); fprintf(stderr, "fuzz driver: read error on %s\n", path); return -1; }
    /* an exact-size copy, so ASan sees reads past the input's end */
    uint8_t *in = malloc(n ? n : 1);
    if (!in) abort();
    memcpy(in, buf, n);
    free(buf);
    LLVMFuzzerTestOneInput(in, n);
    free(in);
    return 0;
}

static int cmp_names(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

int main(int argc, char **argv)
{
    const char *name = strrchr(argv[0], '/') ? strrchr(argv[0], '/') + 1 : argv[0];
    int quiet = 0, fails = 0;
    for (int a = 1; a < argc; a++) {
        if (!strcmp(argv[a], "-q")) { quiet = 1; continue; }
        struct stat st;
        if (stat(argv[a], &st) != 0) {
            printf("FAIL: %s: cannot read %s\n", name, argv[a]);
            fails++;
            continue;
        }
        long count = 0;
        if (S_ISDIR(st.st_mode)) {
            DIR *d = opendir(argv[a]);
            if (!d) { printf("FAIL: %s: cannot list %s\n", name, argv[a]); fails++; continue; }
            char **names = NULL;
            size_t nn = 0, cap = 0;
            struct dirent *e;
            while ((e = readdir(d))) {
                if (e->d_name[0] == '.') continue;
                if (nn == cap) {
                    cap = cap ? 2 * cap : 64;
                    names = realloc(names, cap * sizeof *names);
                    if (!names) abort();
                }
                size_t len = strlen(argv[a]) + strlen(e->d_name) + 2;
                names[nn] = malloc(len);
                if (!names[nn]) abort();
                snprintf(names[nn++], len, "%s/%s", argv[a], e->d_name);
            }
            closedir(d);
            if (nn) qsort(names, nn, sizeof *names, cmp_names);   /* same order every run */
            for (size_t i = 0; i < nn; i++) {
                struct stat fs;
                if (stat(names[i], &fs) == 0 && S_ISREG(fs.st_mode)) {
                    if (!quiet) fprintf(stderr, "%s: %s\n", name, names[i]);
                    if (run_file(names[i]) == 0) count++;
                    else fails++;
                }
                free(names[i]);
            }
            free(names);
        } else {
            if (run_file(argv[a]) == 0) count++;
            else fails++;
        }
        if (!fails) printf("PASS: %s: %ld inputs from %s\n", name, count, argv[a]);
    }
    return fails ? 1 : 0;
}

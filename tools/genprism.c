/* genprism — extrude a polygon into a prism of Radiance polygons (and, with
 * -r, cylinders and spheres rounding its edges), as Radiance's genprism
 * (docs/man/genprism.1):
 *   genprism mat name { N x1 y1 .. xN yN | - | file } [-l lx ly lz] [-r rad] [-c] [-e]
 * The work is hd_genprism_write (src/scene_gensurf.c). */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/xform.h"

#define MAXV 1024

static void usage(void)
{
    hd_die_msg("usage: %s material name { - | vfile | N v1 v2 .. vN } [-l lvect][-r radius][-c][-e]", hd_progname());
}

/* vertices as pairs of numbers from a file (NULL: standard input) */
static int read_vertices(const char *name, double (*v)[2])
{
    FILE *fp = name ? fopen(name, "r") : stdin;
    const char *shown = name ? name : "<stdin>";
    if (!fp) hd_die_msg("%s: cannot open", shown);
    int n = 0;
    while (n < MAXV && fscanf(fp, "%lf %lf", &v[n][0], &v[n][1]) == 2) n++;
    if (!feof(fp)) {
        if (n >= MAXV) hd_die_msg("%s: too many vertices", shown);
        fprintf(stderr, "%s: warning - non-numerical data\n", shown);
    }
    if (name) fclose(fp);
    return n;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    if (argc < 4) usage();
    static double v[MAXV][2];
    hd_genprism_opts o = {argv[1], argv[2], (const double (*)[2])v, 0, {0, 0, 1}, 0, 1, 0};
    int an;
    if (!strcmp(argv[3], "-")) {
        o.n = read_vertices(NULL, v);
        an = 4;
    } else if (isdigit((unsigned char)argv[3][0])) {
        o.n = atoi(argv[3]);
        if (argc - 3 < 2 * o.n) usage();
        if (o.n > MAXV) hd_die_msg("too many vertices");
        for (int i = 0; i < o.n; i++) {
            v[i][0] = atof(argv[2 * i + 4]);
            v[i][1] = atof(argv[2 * i + 5]);
        }
        an = 2 * o.n + 4;
    } else {
        o.n = read_vertices(argv[3], v);
        an = 4;
    }
    if (o.n < 3) hd_die_msg("not enough vertices");
    for (; an < argc; an++) {
        if (argv[an][0] != '-') usage();
        switch (argv[an][1]) {
        case 'l':
            if (an + 3 >= argc) usage();
            for (int k = 0; k < 3; k++) o.l[k] = atof(argv[++an]);
            if (fabs(o.l[2]) <= 1e-6) hd_die_msg("illegal extrusion vector");
            break;
        case 'r':
            if (an + 1 >= argc) usage();
            o.round = atof(argv[++an]);
            break;
        case 'e': o.ends = !o.ends; break;
        case 'c': o.complete = !o.complete; break;
        default: usage();
        }
    }
    char *header = NULL;
    size_t hlen = 0;
    FILE *hs = open_memstream(&header, &hlen);
    if (!hs) hd_die();
    hd_gen_print_command(hs, hd_progname(), argc, argv);
    fclose(hs);
    if (hd_genprism_write(stdout, &o, header)) hd_die();
    free(header);
    if (fflush(stdout)) hd_die_msg("write error on standard output");
    return 0;
}

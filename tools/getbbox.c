/* getbbox — bounding box of Radiance scene descriptions (docs/man/getbbox.1). */
#include <stdio.h>
#include <string.h>
#include "heliodon/common.h"
#include "heliodon/octree.h"
#include "heliodon/scene.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    int nohead = 0, i;
    for (i = 1; i < argc && argv[i][0] == '-' && argv[i][1]; i++) {
        if (!strcmp(argv[i], "-w")) hd_set_warnings(0);
        else if (!strcmp(argv[i], "-h")) nohead = 1;
        else break;
    }
    hd_scene s;
    hd_scene_init(&s);
    hd_scene_opts so = {1, 0, 0, NULL};     /* raw: modifiers may be defined elsewhere */
    char *in[1] = {"-"};
    if (i >= argc ? hd_scene_load_files(&s, 1, in, &so) : hd_scene_load_files(&s, argc - i, argv + i, &so))
        hd_die();
    double bmin[3], bmax[3];
    if (hd_scene_bbox(&s, 0, bmin, bmax)) hd_die();
    for (int k = 0; k < 3; k++)             /* no surface: Radiance prints its "huge" */
        if (bmin[k] > bmax[k]) { bmin[k] = 1e10; bmax[k] = -1e10; }
    if (!nohead) printf("     xmin      xmax      ymin      ymax      zmin      zmax\n");
    printf("%9g %9g %9g %9g %9g %9g\n", bmin[0], bmax[0], bmin[1], bmax[1], bmin[2], bmax[2]);
    if (fflush(stdout)) hd_die_msg("write error on standard output");
    hd_scene_free(&s);
    return 0;
}

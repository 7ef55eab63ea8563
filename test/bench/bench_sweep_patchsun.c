/* bench_sweep_patchsun MF dx dy dz — print the Reinhart MF sky patch that
 * holds direction (dx,dy,dz) and its centre direction (the sun position
 * that a patch-centre sun discretisation uses), for sweep_sun.sh:
 *   bin dx dy dz angle_deg */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "heliodon/basis.h"

int main(int argc, char **argv)
{
    if (argc != 5) {
        fprintf(stderr, "usage: %s MF dx dy dz\n", argv[0]);
        return 2;
    }
    int mf = atoi(argv[1]);
    hd_vec3 d = hd_v3(atof(argv[2]), atof(argv[3]), atof(argv[4]));
    hd_skybasis b;
    if (hd_skybasis_init(&b, mf) != HD_OK) {
        fprintf(stderr, "%s: bad MF %s\n", argv[0], argv[1]);
        return 1;
    }
    int bin = hd_skybasis_bin(&b, d);
    hd_vec3 c = hd_skybasis_dir(&b, bin);
    double n = sqrt(d.x * d.x + d.y * d.y + d.z * d.z), cn = sqrt(c.x * c.x + c.y * c.y + c.z * c.z);
    double cosa = (d.x * c.x + d.y * c.y + d.z * c.z) / (n * cn);
    printf("%d %.6f %.6f %.6f %.4f\n", bin, c.x / cn, c.y / cn, c.z / cn, acos(fmin(1, cosa)) * 180 / HD_PI);
    hd_skybasis_free(&b);
    return 0;
}

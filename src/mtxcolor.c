/* heliodon — symbolic colour components of matrices and pictures (the -c
 * letters of rmtxop and rcomb): R G B X Y Z A, upper or lower case.
 *
 * The RGB <-> CIE XYZ matrices are computed from Radiance's nominal
 * primaries (R .640 .330, G .290 .600, B .150 .060) and the equal-energy
 * white (1/3, 1/3), which is what Radiance 6.1's matrix tools use: its
 * Y row is 0.26506 0.67004 0.06490 (to 5 digits), slightly different from
 * the rounded luminance constants of pictures (0.265074126 ...).  The
 * coefficients are rounded to single precision, as Radiance stores them.
 * Upper-case letters apply the luminous efficacy 179 lm/W when converting
 * from RGB to XYZ and divide by it from XYZ to RGB; lower-case ones do not. */
#include <ctype.h>
#include <string.h>
#include <strings.h>
#include "heliodon/matrix.h"

#define EFFICACY 179.0

static double det3(double m[3][3])
{
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

/* rows X, Y, Z; columns R, G, B */
static void rgb_to_xyz(double m[3][3])
{
    const double xy[3][2] = {{.640, .330}, {.290, .600}, {.150, .060}};
    const double white[3] = {1.0, 1.0, 1.0};    /* (1/3,1/3): X = Y = Z */
    double p[3][3];  /* columns: each primary's XYZ for Y = 1 */
    for (int i = 0; i < 3; i++) {
        p[0][i] = xy[i][0] / xy[i][1];
        p[1][i] = 1.0;
        p[2][i] = (1.0 - xy[i][0] - xy[i][1]) / xy[i][1];
    }
    /* weights s with p . s = white (Cramer's rule) */
    double d = det3(p), s[3];
    for (int k = 0; k < 3; k++) {
        double t[3][3];
        memcpy(t, p, sizeof t);
        for (int r = 0; r < 3; r++) t[r][k] = white[r];
        s[k] = det3(t) / d;
    }
    for (int r = 0; r < 3; r++)
        for (int k = 0; k < 3; k++) m[r][k] = p[r][k] * s[k];
}

static void invert3(double m[3][3], double inv[3][3])
{
    double d = det3(m);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
            inv[r][c] = (m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1]) / d;
        }
}

hd_status hd_color_symbols(const char *letters, int xyz_in, double *coef, int *xyz_out)
{
    double x[3][3], r[3][3];
    rgb_to_xyz(x);
    invert3(x, r);
    for (int i = 0; i < 3; i++)         /* single precision, as Radiance keeps them */
        for (int j = 0; j < 3; j++) {
            x[i][j] = (float)x[i][j];
            r[i][j] = (float)r[i][j];
        }
    int n = 0;
    for (const char *p = letters; *p; p++, n++) {
        double *row = coef + 3 * n;
        int up = isupper((unsigned char)*p);
        int ch = toupper((unsigned char)*p);
        memset(row, 0, 3 * sizeof *row);
        switch (ch) {
        case 'A':
            row[0] = row[1] = row[2] = 1.0 / 3;
            break;
        case 'R': case 'G': case 'B': {
            int k = ch == 'R' ? 0 : ch == 'G' ? 1 : 2;
            if (!xyz_in) row[k] = 1;
            else for (int j = 0; j < 3; j++) row[j] = r[k][j] / (up ? EFFICACY : 1.0);
            break;
        }
        case 'X': case 'Y': case 'Z': {
            int k = ch - 'X';
            if (xyz_in) row[k] = 1;
            else for (int j = 0; j < 3; j++) row[j] = x[k][j] * (up ? EFFICACY : 1.0);
            break;
        }
        case 'S': case 'M':
            return hd_fail(HD_ERR_USAGE, "-c %s: '%c' (scotopic/melanopic) needs spectral data: not supported",
                           letters, *p);
        default:
            return hd_fail(HD_ERR_USAGE, "-c %s: unknown component symbol '%c' (expected R G B X Y Z A)",
                           letters, *p);
        }
    }
    if (!n) return hd_fail(HD_ERR_USAGE, "-c: empty component symbols");
    if (xyz_out) {
        if (!strcasecmp(letters, "XYZ")) *xyz_out = 1;
        else if (!strcasecmp(letters, "RGB")) *xyz_out = 0;
        else *xyz_out = -1;
    }
    return HD_OK;
}

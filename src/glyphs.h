/* heliodon — a small bitmap font of its own (5 x 8 cells: 7 rows above the
 * baseline, 1 below) for text in pictures (falsecolor's legend). */
#ifndef HD_GLYPHS_H
#define HD_GLYPHS_H
#include "heliodon/common.h"

/* Coverage (0..1) of TEXT drawn HEIGHT pixels high: *mask gets width x
 * height floats, row 0 at the top (free() it).  Characters without a glyph
 * are blank.  aspect: character height / width as Radiance's psign -a
 * (the glyphs are condensed in proportion; 0 = psign's default 1.67). */
hd_status hd_text_mask(const char *text, int height, double aspect, float **mask, int *width);
#endif

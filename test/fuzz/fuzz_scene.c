/* Fuzz harness: Radiance scene text (parser, modifier resolution,
 * material parameters, trace-scene build with polygon triangulation, one
 * ray).  In-line commands are never run (no_commands). */
#include <stdio.h>

#include "fuzz.h"
#include "heliodon/scene.h"
#include "heliodon/trace.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    hd_fuzz_setup();
    if (size > 256 * 1024) return 0;
    char *text = hd_fuzz_cstr(data, size);
    hd_scene_opts o;
    memset(&o, 0, sizeof o);
    o.no_commands = 1;
    o.raw = size > 0 && data[0] == '%';   /* xform's unresolved mode too */
    hd_scene s;
    hd_scene_init(&s);
    hd_status st = hd_scene_load_string(&s, text, "fuzz.rad", &o);
    if (st == HD_OK && !o.raw) {
        for (size_t i = 0; i < s.nprims; i++) {
            char where[256];
            (void)hd_prim_where(&s, (int32_t)i, where, sizeof where);
        }
        hd_tscene *ts = NULL;
        if (s.nprims <= 2000 && hd_tscene_from_scene(&ts, &s) == HD_OK) {
            hd_hit h;
            (void)hd_tscene_intersect(ts, hd_v3(0.5, 0.5, 0.5), hd_v3(0, 0, 1), 0, 0, &h);
            (void)hd_tscene_intersect(ts, hd_v3(0, 0, 0), hd_v3(0.6, 0.48, -0.64), 0, 0, &h);
            (void)hd_tscene_source_hit(ts, hd_v3(0, 0, 1));
            hd_tscene_free(ts);
        }
    }
    hd_scene_free(&s);
    free(text);
    return 0;
}

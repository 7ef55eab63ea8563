/* heliodon — unit-test helpers that need the library: scenes from text,
 * scratch file names, whole-file reads.  Include after hd_test.h. */
#ifndef HD_TEST_SCENE_H
#define HD_TEST_SCENE_H

#include "heliodon/pmap.h"
#include "heliodon/scene.h"
#include "heliodon/trace.h"

/* A traceable scene from Radiance scene text (name: the file name used in
 * messages); NULL (and the error printed) if it does not load. */
static inline hd_tscene *hd_test_tscene(const char *text, const char *name)
{
    hd_scene sc;
    hd_scene_init(&sc);
    hd_tscene *ts = NULL;
    if (hd_scene_load_string(&sc, text, name, NULL) || hd_tscene_from_scene(&ts, &sc)) {
        fprintf(stderr, "scene: %s\n", hd_errmsg());
        ts = NULL;
    }
    hd_scene_free(&sc);
    return ts;
}

/* The photon-map tests' roof box, as scene text into buf: a 1 m cube with
 * a floor of reflectance rho_floor ("floormat"), walls and roof of
 * rho_walls ("wallmat"), a glass pane ("pane", the photon port) in a
 * 0.5 x 0.5 m opening of the roof, the sun sun1 (modifier solar1, unit
 * radiance) overhead and, with two_suns, sun2 (solar2) tilted.  Also
 * defines "black" for extra objects. */
static inline const char *hd_test_roofbox(char *buf, size_t cap, double rho_floor, double rho_walls, int two_suns)
{
    snprintf(buf, cap,
             "void plastic black 0 0 5 0 0 0 0 0\n"
             "void plastic floormat 0 0 5 %g %g %g 0 0\n"
             "void plastic wallmat 0 0 5 %g %g %g 0 0\n"
             "void glass pane 0 0 3 .96 .96 .96\n"
             "void light solar1 0 0 3 1 1 1\n"
             "solar1 source sun1 0 0 4 0 0 1 0.533\n"
             "%s"
             "floormat polygon floor 0 0 12 0 0 0 1 0 0 1 1 0 0 1 0\n"
             "wallmat polygon w1 0 0 12 0 0 0 0 0 1 1 0 1 1 0 0\n"
             "wallmat polygon w2 0 0 12 1 0 0 1 0 1 1 1 1 1 1 0\n"
             "wallmat polygon w3 0 0 12 1 1 0 1 1 1 0 1 1 0 1 0\n"
             "wallmat polygon w4 0 0 12 0 1 0 0 1 1 0 0 1 0 0 0\n"
             /* roof with a hole: four strips around x,y in [.25,.75] */
             "wallmat polygon r1 0 0 12 0 0 1 1 0 1 1 .25 1 0 .25 1\n"
             "wallmat polygon r2 0 0 12 0 .75 1 1 .75 1 1 1 1 0 1 1\n"
             "wallmat polygon r3 0 0 12 0 .25 1 .25 .25 1 .25 .75 1 0 .75 1\n"
             "wallmat polygon r4 0 0 12 .75 .25 1 1 .25 1 1 .75 1 .75 .75 1\n"
             "pane polygon port 0 0 12 .25 .25 1 .25 .75 1 .75 .75 1 .75 .25 1\n",
             rho_floor, rho_floor, rho_floor, rho_walls, rho_walls, rho_walls,
             two_suns ? "void light solar2 0 0 3 1 1 1\nsolar2 source sun2 0 0 4 0.3 0.2 1 0.533\n" : "");
    return buf;
}

/* The reference box of ../shared/ref (ref: hd_test_ref()) with its 145 MF:1
 * suns (box_room.rad, box_window.rad, suns_mf1.rad), warnings off; NULL
 * (and the error printed) if it does not load. */
static inline hd_tscene *hd_test_refbox(const char *ref)
{
    static const char *const names[3] = {"box_room.rad", "box_window.rad", "suns_mf1.rad"};
    char files[3][512];
    char *fv[3];
    for (int i = 0; i < 3; i++) {
        snprintf(files[i], sizeof files[i], "%s/scenes/box/%s", ref, names[i]);
        fv[i] = files[i];
    }
    hd_scene sc;
    hd_scene_init(&sc);
    hd_set_warnings(0);
    hd_tscene *ts = NULL;
    if (hd_scene_load_files(&sc, 3, fv, NULL) || hd_tscene_from_scene(&ts, &sc)) {
        fprintf(stderr, "reference box: %s\n", hd_errmsg());
        ts = NULL;
    }
    hd_scene_free(&sc);
    return ts;
}

/* Photon-map build options with defaults and one photon port: the surfaces
 * of modifier mod, oriented as given ('+'). */
static inline void hd_test_port_opts(hd_pmap_build_opts *o, const char *mod)
{
    hd_pmap_build_opts_init(o);
    o->nports = 1;
    o->ports[0].modifier = mod;
    o->ports[0].orient = '+';
}

/* hd_test_tmpdir()/name, in one of 8 rotating buffers. */
static inline char *hd_test_path(const char *name)
{
    static char buf[8][512];
    static int k;
    char *b = buf[k++ & 7];
    snprintf(b, 512, "%s/%s", hd_test_tmpdir(), name);
    return b;
}

/* The whole file (malloc'd, NUL-terminated), its length in *n; NULL if it
 * cannot be read. */
static inline unsigned char *hd_test_slurp(const char *path, size_t *n)
{
    *n = 0;
    FILE *fp = fopen(path, "rb");
    if (!fp) return NULL;
    fseek(fp, 0, SEEK_END);
    long len = ftell(fp);
    fseek(fp, 0, SEEK_SET);
    unsigned char *b = len >= 0 ? malloc((size_t)len + 1) : NULL;
    if (b && fread(b, 1, (size_t)len, fp) != (size_t)len) { free(b); b = NULL; }
    if (b) b[len] = 0;
    fclose(fp);
    *n = len >= 0 ? (size_t)len : 0;
    return b;
}

#endif

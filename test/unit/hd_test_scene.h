/* heliodon — unit-test helpers that need the library: scenes from text,
 * scratch file names, whole-file reads.  Include after hd_test.h. */
#ifndef HD_TEST_SCENE_H
#define HD_TEST_SCENE_H

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

/* heliodon — private helpers shared by the scene sources (not installed). */
#ifndef HELIODON_SCENE_PRIV_H
#define HELIODON_SCENE_PRIV_H

#include "heliodon/scene.h"

/* "file:line" (or "outer:line: output of '!cmd' line N") for a source. */
void hd_scene_where_file(const hd_scene *s, uint32_t file, uint32_t line, char *buf, size_t cap);
/* Append a skipped in-line command record. */
hd_status hd_scene_add_skipped(hd_scene *s, const char *cmd, uint32_t file, uint32_t line);
/* Write the cache body (everything after the header). */
hd_status hd_scene_cache_write_body(const hd_scene *s, FILE *fp);
/* Read the cache body after its header (stream positioned after the blank line). */
hd_status hd_scene_cache_read_body(hd_scene *s, FILE *fp, const char *name);

/* If path is a Radiance octree that lists its scene files, load those
 * (*is_octree = 1); otherwise do nothing (*is_octree = 0). */
hd_status hd_scene_load_radiance_octree(hd_scene *s, const char *path, const hd_scene_opts *opts, int *is_octree);

#endif

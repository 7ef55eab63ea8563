/* heliodon — progress reports on stderr.
 *
 * -t N (as Radiance): a report line every N seconds ("prog: 42.0% done after
 * 0.013 hours, ETA 0.018 hours").  When stderr is a terminal and reports
 * are not disabled, a live bar with percent and ETA is redrawn instead.
 * Thread-safe: workers call hd_progress_add() with the units they finished. */
#ifndef HELIODON_PROGRESS_H
#define HELIODON_PROGRESS_H

#include <stdint.h>

typedef struct hd_progress hd_progress;

/* interval_s: the -t value (0 = no periodic lines); live_bar: allow the
 * terminal bar (it is shown only if stderr is a TTY). */
hd_progress *hd_progress_start(const char *label, uint64_t total,
                               double interval_s, int live_bar);
void hd_progress_add(hd_progress *p, uint64_t done_units);
/* Final line (if anything was shown) and free. */
void hd_progress_finish(hd_progress *p);
/* Monotonic wall-clock seconds. */
double hd_seconds(void);

#endif

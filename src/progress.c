/* heliodon — progress reports: periodic lines (-t) and a live terminal bar. */
#include "progress.h"
#include "heliodon/common.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

struct hd_progress {
    char label[64];
    uint64_t total;
    atomic_uint_least64_t done;
    double start, interval, last_report, last_bar;
    int bar, shown;
    pthread_mutex_t lock;
};

double hd_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

hd_progress *hd_progress_start(const char *label, uint64_t total, double interval_s, int live_bar)
{
    hd_progress *p = calloc(1, sizeof *p);
    if (!p) return NULL;
    snprintf(p->label, sizeof p->label, "%s", label ? label : hd_progname());
    p->total = total;
    atomic_init(&p->done, 0);
    p->start = p->last_report = p->last_bar = hd_seconds();
    p->interval = interval_s > 0 ? interval_s : 0;
    p->bar = live_bar && isatty(2) && getenv("HELIODON_NO_BAR") == NULL;
    pthread_mutex_init(&p->lock, NULL);
    return p;
}

static void fmt_time(char *buf, size_t cap, double s)
{
    if (s < 0 || s > 1e8) { snprintf(buf, cap, "--:--"); return; }
    long t = (long)(s + 0.5);
    if (t >= 3600) snprintf(buf, cap, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
    else snprintf(buf, cap, "%ld:%02ld", t / 60, t % 60);
}

static void draw(hd_progress *p, double now, uint64_t done, int final)
{
    double frac = p->total ? (double)done / (double)p->total : 0;
    if (frac > 1) frac = 1;
    double el = now - p->start;
    double eta = frac > 0 ? el * (1 - frac) / frac : -1;
    if (p->bar) {
        char e1[32], e2[32];
        fmt_time(e1, sizeof e1, el);
        fmt_time(e2, sizeof e2, final ? 0 : eta);
        int w = 30, k = (int)(frac * w + 0.5);
        char bar[64];
        for (int i = 0; i < w; i++) bar[i] = i < k ? '#' : '.';
        bar[w] = 0;
        fprintf(stderr, "\r%s [%s] %5.1f%% %s elapsed, ETA %s ", p->label, bar, 100 * frac, e1, e2);
        if (final) fputc('\n', stderr);
    } else {
        fprintf(stderr, "%s: %.1f%% done after %.3f hours", p->label, 100 * frac, el / 3600);
        if (!final && eta >= 0) fprintf(stderr, ", ETA %.3f hours", eta / 3600);
        fputc('\n', stderr);
    }
    fflush(stderr);
    p->shown = 1;
}

void hd_progress_add(hd_progress *p, uint64_t n)
{
    if (!p) return;
    uint64_t done = atomic_fetch_add(&p->done, n) + n;
    if (!p->bar && p->interval <= 0) return;
    double now = hd_seconds();
    if (p->bar ? now - p->last_bar < 0.2 : now - p->last_report < p->interval) return;
    if (pthread_mutex_trylock(&p->lock) != 0) return;
    if (p->bar && now - p->last_bar >= 0.2) { p->last_bar = now; draw(p, now, done, 0); }
    else if (!p->bar && now - p->last_report >= p->interval) { p->last_report = now; draw(p, now, done, 0); }
    pthread_mutex_unlock(&p->lock);
}

void hd_progress_finish(hd_progress *p)
{
    if (!p) return;
    if (p->shown || p->interval > 0) draw(p, hd_seconds(), atomic_load(&p->done), 1);
    pthread_mutex_destroy(&p->lock);
    free(p);
}

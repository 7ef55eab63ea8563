/* heliodon — parallel-for over fixed chunks with POSIX threads. */
#include "heliodon/parallel.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct pf_job {
    size_t n, chunk, nchunks;
    hd_chunk_fn fn;
    void *ctx;
    atomic_size_t next;
    atomic_int stop;
    pthread_mutex_t lock;
    hd_status err;
    size_t err_chunk;
    char errmsg[2048];
} pf_job;

typedef struct pf_worker { pf_job *job; int index; } pf_worker;

static void run_chunks(pf_job *j, int worker)
{
    for (;;) {
        if (atomic_load(&j->stop)) return;
        size_t c = atomic_fetch_add(&j->next, 1);
        if (c >= j->nchunks) return;
        size_t b = c * j->chunk, e = b + j->chunk < j->n ? b + j->chunk : j->n;
        hd_status st = j->fn(j->ctx, b, e, c, worker);
        if (st != HD_OK) {
            pthread_mutex_lock(&j->lock);
            /* keep the error of the lowest chunk for a deterministic message */
            if (j->err == HD_OK || c < j->err_chunk) {
                j->err = st;
                j->err_chunk = c;
                strncpy(j->errmsg, hd_errmsg(), sizeof j->errmsg - 1);
            }
            pthread_mutex_unlock(&j->lock);
            atomic_store(&j->stop, 1);
            return;
        }
    }
}

static void *thread_main(void *arg)
{
    pf_worker *w = arg;
    run_chunks(w->job, w->index);
    return NULL;
}

hd_status hd_parallel_for(size_t n, size_t chunk, int nthreads, hd_chunk_fn fn, void *ctx)
{
    if (n == 0) return HD_OK;
    if (chunk == 0) chunk = 1;
    pf_job j;
    memset(&j, 0, sizeof j);
    j.n = n;
    j.chunk = chunk;
    j.nchunks = (n + chunk - 1) / chunk;
    j.fn = fn;
    j.ctx = ctx;
    atomic_init(&j.next, 0);
    atomic_init(&j.stop, 0);
    pthread_mutex_init(&j.lock, NULL);
    nthreads = hd_resolve_threads(nthreads);
    if ((size_t)nthreads > j.nchunks) nthreads = (int)j.nchunks;
    pthread_t *tid = NULL;
    pf_worker *ws = NULL;
    int started = 0;
    if (nthreads > 1) {
        tid = calloc((size_t)nthreads, sizeof *tid);
        ws = calloc((size_t)nthreads, sizeof *ws);
        if (tid && ws)
            for (int t = 1; t < nthreads; t++) {
                ws[t].job = &j;
                ws[t].index = t;
                if (pthread_create(&tid[t], NULL, thread_main, &ws[t]) != 0) break;
                started = t;
            }
    }
    run_chunks(&j, 0);
    for (int t = 1; t <= started; t++) pthread_join(tid[t], NULL);
    free(tid);
    free(ws);
    pthread_mutex_destroy(&j.lock);
    if (j.err != HD_OK) return hd_fail(j.err, "%s", j.errmsg);
    return HD_OK;
}

int hd_ncpus(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)n : 1;
}

int hd_resolve_threads(int n) { return n > 0 ? n : hd_ncpus(); }

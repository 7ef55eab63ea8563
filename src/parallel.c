/* heliodon — one persistent thread pool, and the parallel-for over fixed
 * chunks that runs on it. */
#include "heliodon/parallel.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Workers 1..nstarted wait for a new generation of work; the caller of
 * hd_pool_for is worker 0.  Chunks are handed out in index order from an
 * atomic counter; a worker's index only decides which scratch it uses. */
struct hd_pool {
    int nstarted;             /* worker threads running (1..nstarted) */
    pthread_t *tid;
    pthread_mutex_t mu;
    pthread_cond_t go, done;
    uint64_t gen;             /* under mu */
    int quit, ndone;          /* under mu */
    /* the current loop */
    size_t n, chunk, nchunks;
    int active;               /* workers 0..active-1 take part */
    hd_chunk_fn fn;
    void *ctx;
    atomic_size_t next;
    atomic_int stop;
    hd_status err;            /* under mu */
    size_t err_chunk;
    char errmsg[2048];
};
typedef struct pool_arg { hd_pool *p; int index; } pool_arg;

static void run_chunks(hd_pool *p, int worker)
{
    for (;;) {
        if (atomic_load(&p->stop)) return;
        size_t c = atomic_fetch_add(&p->next, 1);
        if (c >= p->nchunks) return;
        size_t b = c * p->chunk, e = b + p->chunk < p->n ? b + p->chunk : p->n;
        hd_status st = p->fn(p->ctx, b, e, c, worker);
        if (st != HD_OK) {
            pthread_mutex_lock(&p->mu);
            /* keep the error of the lowest chunk for a deterministic message */
            if (p->err == HD_OK || c < p->err_chunk) {
                p->err = st;
                p->err_chunk = c;
                hd_strlcpy(p->errmsg, hd_errmsg(), sizeof p->errmsg);
            }
            pthread_mutex_unlock(&p->mu);
            atomic_store(&p->stop, 1);
            return;
        }
    }
}

static void *pool_main(void *arg)
{
    pool_arg *a = arg;
    hd_pool *p = a->p;
    int index = a->index;
    free(a);
    uint64_t seen = 0;
    for (;;) {
        pthread_mutex_lock(&p->mu);
        while (!p->quit && p->gen == seen) pthread_cond_wait(&p->go, &p->mu);
        if (p->quit) { pthread_mutex_unlock(&p->mu); return NULL; }
        seen = p->gen;
        int part = index < p->active;
        pthread_mutex_unlock(&p->mu);
        if (part) run_chunks(p, index);
        pthread_mutex_lock(&p->mu);
        p->ndone++;
        pthread_cond_signal(&p->done);
        pthread_mutex_unlock(&p->mu);
    }
}

hd_pool *hd_pool_new(int nthreads)
{
    hd_pool *p = hd_calloc(1, sizeof *p);
    if (!p) return NULL;
    pthread_mutex_init(&p->mu, NULL);
    pthread_cond_init(&p->go, NULL);
    pthread_cond_init(&p->done, NULL);
    nthreads = hd_resolve_threads(nthreads);
    p->tid = nthreads > 1 ? calloc((size_t)nthreads, sizeof *p->tid) : NULL;
    for (int t = 1; p->tid && t < nthreads; t++) {
        pool_arg *a = malloc(sizeof *a);
        if (!a) break;
        a->p = p;
        a->index = t;
        if (pthread_create(&p->tid[t], NULL, pool_main, a) != 0) { free(a); break; }
        p->nstarted = t;
    }
    return p;
}

int hd_pool_threads(const hd_pool *p) { return p ? p->nstarted + 1 : 1; }

void hd_pool_free(hd_pool *p)
{
    if (!p) return;
    pthread_mutex_lock(&p->mu);
    p->quit = 1;
    pthread_cond_broadcast(&p->go);
    pthread_mutex_unlock(&p->mu);
    for (int t = 1; t <= p->nstarted; t++) pthread_join(p->tid[t], NULL);
    free(p->tid);
    pthread_cond_destroy(&p->go);
    pthread_cond_destroy(&p->done);
    pthread_mutex_destroy(&p->mu);
    free(p);
}

/* The loop on workers 0..nthreads-1 of p (fewer if p has fewer). */
static hd_status pool_for(hd_pool *p, size_t n, size_t chunk, int nthreads, hd_chunk_fn fn, void *ctx)
{
    pthread_mutex_lock(&p->mu);
    p->n = n;
    p->chunk = chunk;
    p->nchunks = (n + chunk - 1) / chunk;
    p->fn = fn;
    p->ctx = ctx;
    atomic_store(&p->next, 0);
    atomic_store(&p->stop, 0);
    p->err = HD_OK;
    p->ndone = 0;
    if ((size_t)nthreads > p->nchunks) nthreads = (int)p->nchunks;
    p->active = nthreads;
    int wake = nthreads > 1 ? p->nstarted : 0;
    if (wake) { p->gen++; pthread_cond_broadcast(&p->go); }
    pthread_mutex_unlock(&p->mu);
    run_chunks(p, 0);
    pthread_mutex_lock(&p->mu);
    while (p->ndone < wake) pthread_cond_wait(&p->done, &p->mu);
    hd_status st = p->err;
    pthread_mutex_unlock(&p->mu);
    return st != HD_OK ? hd_fail(st, "%s", p->errmsg) : HD_OK;
}

hd_status hd_pool_for(hd_pool *p, size_t n, size_t chunk, hd_chunk_fn fn, void *ctx)
{
    return hd_parallel_for_on(p, n, chunk, hd_pool_threads(p), fn, ctx);
}

/* The process's pool, grown to the largest thread count asked for; a
 * caller that finds it busy (another thread's loop, or a loop nested in
 * one of its chunks) gets a pool of its own for the call. */
static pthread_mutex_t shared_mu = PTHREAD_MUTEX_INITIALIZER;
static hd_pool *shared;

hd_status hd_parallel_for_on(hd_pool *p, size_t n, size_t chunk, int nthreads, hd_chunk_fn fn, void *ctx)
{
    if (n == 0) return HD_OK;
    if (chunk == 0) chunk = 1;
    nthreads = hd_resolve_threads(nthreads);
    size_t nchunks = (n + chunk - 1) / chunk;
    if ((size_t)nthreads > nchunks) nthreads = (int)nchunks;
    if (p) return pool_for(p, n, chunk, nthreads, fn, ctx);
    if (nthreads <= 1) {   /* in the calling thread, no pool needed */
        hd_pool one;
        memset(&one, 0, sizeof one);
        pthread_mutex_init(&one.mu, NULL);
        hd_status st = pool_for(&one, n, chunk, 1, fn, ctx);
        pthread_mutex_destroy(&one.mu);
        return st;
    }
    if (pthread_mutex_trylock(&shared_mu) == 0) {
        if (hd_pool_threads(shared) < nthreads) {
            hd_pool_free(shared);
            shared = hd_pool_new(nthreads);
        }
        hd_status st = shared ? pool_for(shared, n, chunk, nthreads, fn, ctx) : HD_ERR_NOMEM;
        pthread_mutex_unlock(&shared_mu);
        return st;
    }
    hd_pool *own = hd_pool_new(nthreads);
    if (!own) return HD_ERR_NOMEM;
    hd_status st = pool_for(own, n, chunk, nthreads, fn, ctx);
    hd_pool_free(own);
    return st;
}

hd_status hd_parallel_for(size_t n, size_t chunk, int nthreads, hd_chunk_fn fn, void *ctx)
{
    return hd_parallel_for_on(NULL, n, chunk, nthreads, fn, ctx);
}

int hd_ncpus(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)n : 1;
}

int hd_resolve_threads(int n) { return n > 0 ? n : hd_ncpus(); }

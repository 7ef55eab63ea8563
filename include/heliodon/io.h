/* heliodon — input streams and crash-safe output files.
 *
 * hd_istream reads a named file, standard input ("-") or the output of a
 * shell command ("!command", as Radiance does), transparently decompressing
 * gzip data.  It tracks the byte offset (of the uncompressed data) and, for
 * text read through hd_istream_getc(), the line number, so that error
 * messages can name the position.
 *
 * hd_ofile writes to a temporary name beside the target and renames it on
 * hd_ofile_commit(); a failed, aborted or killed run (SIGINT, SIGTERM,
 * SIGHUP, exit without commit) leaves no truncated output behind. */
#ifndef HELIODON_IO_H
#define HELIODON_IO_H

#include <stdio.h>
#include "common.h"
#include "vec.h"

typedef struct hd_istream hd_istream;

hd_status hd_istream_open(hd_istream **out, const char *path);
/* Read from memory (not copied; must outlive the stream). */
hd_status hd_istream_memory(hd_istream **out, const void *data, size_t len, const char *name);
/* Close; for "!command" streams, a non-zero exit status of the command is
 * reported as HD_ERR_IO. */
hd_status hd_istream_close(hd_istream *s);

const char *hd_istream_name(const hd_istream *s);
uint64_t hd_istream_offset(const hd_istream *s);   /* bytes consumed */
/* 1-based line number of the next byte, counting '\n' consumed through
 * hd_istream_getc/getline/word functions (binary reads do not count). */
unsigned long hd_istream_lineno(const hd_istream *s);

int hd_istream_getc(hd_istream *s);                /* byte or EOF */
int hd_istream_peek(hd_istream *s);                /* byte or EOF, not consumed */
/* Read up to n bytes; returns the count (short only at end of data or error). */
size_t hd_istream_read(hd_istream *s, void *buf, size_t n);
/* Exactly n bytes, else HD_ERR_FORMAT "NAME: byte offset N: unexpected end of
 * data reading WHAT" (or HD_ERR_IO on a read error). */
hd_status hd_istream_read_exact(hd_istream *s, void *buf, size_t n, const char *what);
/* The rest of the stream in one buffer (*data, freed by the caller, with a
 * NUL after the *len bytes).  A stream longer than the allocation limit is
 * refused with HD_ERR_NOMEM naming the stream and the limit; read errors
 * name the byte offset. */
hd_status hd_istream_read_all(hd_istream *s, unsigned char **data, size_t *len);
/* The same for the file at path (opened and closed here; "-" is stdin). */
hd_status hd_file_read_all(const char *path, unsigned char **data, size_t *len);
/* Whether a read error (as opposed to end of data) occurred. */
int hd_istream_failed(const hd_istream *s);
/* Read one line without its '\n' into buf (NUL-terminated). Returns the
 * length, or -1 at end of data, or -2 if the line is longer than cap-1 (the
 * rest of the line is consumed). */
long hd_istream_getline(hd_istream *s, char *buf, size_t cap);
/* Skip white space and read one white-space delimited word into buf.
 * Returns its length, 0 at end of data, -2 if longer than cap-1. */
long hd_istream_word(hd_istream *s, char *buf, size_t cap);
/* Read one ASCII real number (skipping white space): HD_OK, or
 * HD_ERR_FORMAT naming the line and the offending word, or — at end of data —
 * HD_ERR_FORMAT "unexpected end of data" unless *eof is non-NULL, in which
 * case *eof is set to 1 and HD_OK returned. */
hd_status hd_istream_real(hd_istream *s, double *v, int *eof);
/* Read one ray "ox oy oz dx dy dz" in format fmt ('a' text, 'f' 4-byte
 * floats, 'd' 8-byte doubles) into org and dir: *eof = 1 at the end of data before
 * the ray; an incomplete (truncated) or non-finite ray is HD_ERR_FORMAT
 * naming the line or byte offset and the ray's number (k + 1).  The one
 * reader of rtrace's and rcontrib's ray input. */
hd_status hd_istream_ray(hd_istream *s, char fmt, uint64_t k, hd_vec3 *org, hd_vec3 *dir, int *eof);

/* The first readable file `name` in the directories of the ':' list dirs,
 * in order (an empty entry: name as it is), into buf; buf or NULL.  The one
 * search of RAYPATH and library folders (hd_cal_findfile, BSDF data
 * files). */
const char *hd_find_in_path(const char *dirs, const char *name, char *buf, size_t cap);

/* ---- crash-safe outputs ---- */
typedef struct hd_ofile hd_ofile;
/* path NULL or "-": standard output (commit just flushes). */
hd_status hd_ofile_open(hd_ofile **out, const char *path);
FILE *hd_ofile_fp(hd_ofile *f);
const char *hd_ofile_name(const hd_ofile *f);      /* the final name */
/* Flush, close and rename into place; reports write errors (disk full). */
hd_status hd_ofile_commit(hd_ofile *f);
/* Close and remove the temporary file. */
void hd_ofile_abort(hd_ofile *f);
/* Remove every temporary output not yet committed (called by hd_die, at
 * exit and from the signal handlers that hd_ofile_open installs). */
void hd_ofile_abort_all(void);

/* ---- leftovers of killed runs, resumable outputs, free space ----
 * A run killed by a signal that cannot be caught (SIGKILL, power loss)
 * leaves its temporaries ".NAME.hdtmp.PID.N" (and mkpmap's spill files
 * ".NAME.hdtmp.PID.runK") beside the final name.  hd_ofile_open removes
 * those of NAME whose process PID no longer exists before it creates its
 * own (each directory is listed once per process). */
/* Remove the stale temporaries of path now; returns how many. */
int hd_ofile_clean_stale(const char *path);
/* Open path for resuming (rcontrib -r): the newest stale temporary
 * ".NAME.hdtmp.PID.N" of a dead process is taken over (renamed to a new
 * temporary of this process, *from = 1); else, if path itself exists, it is
 * copied to a new temporary (*from = 2: the final file stays as it is until
 * the commit); else the temporary is new and empty (*from = 0).  The stream
 * is positioned at the end; *size is its length in bytes. */
hd_status hd_ofile_open_resume(hd_ofile **out, const char *path, int *from, uint64_t *size);
/* The temporary's name (to read back what it holds); NULL for stdout. */
const char *hd_ofile_tmpname(const hd_ofile *f);
/* Cut the temporary to len bytes and position the stream at its end. */
hd_status hd_ofile_truncate(hd_ofile *f, uint64_t len);
/* Keep the temporary when the run is interrupted by SIGINT, SIGTERM or
 * SIGHUP (a later run can resume from it); it is still removed on errors
 * and on exit without commit. */
void hd_ofile_keep_on_signal(hd_ofile *f);
/* Register a scratch file (e.g. a sort spill) to be removed by the exit and
 * signal handlers; hd_temp_forget after removing it yourself. */
hd_status hd_temp_track(const char *path);
void hd_temp_forget(const char *path);
/* Refuse up front when `need` bytes will not fit on the file system that
 * holds path (its directory): HD_ERR_IO naming what, the numbers and the
 * directory.  Unknown free space (statvfs fails) is not an error. */
hd_status hd_check_disk(const char *path, uint64_t need, const char *what);

/* Parse a count with an optional multiplier suffix as Radiance's mkpmap
 * does: k/K = 1e3, m/M = 1e6, g/G = 1e9 ("10m" = 10 000 000, "1.5k" =
 * 1500).  The result must be a non-negative integer. Returns 0 on success. */
int hd_parse_count(const char *s, uint64_t *out);
/* Strict numeric parsing of a whole word: returns 0 on success. */
int hd_parse_double(const char *s, double *out);
int hd_parse_long(const char *s, long *out);

/* ---- output name patterns (rcontrib -o, dctimestep -o, per-bin inputs) ----
 * A pattern holds at most one "%s" (replaced by name) and at most one
 * integer conversion %d %i %o %x %X with optional flags and width
 * ("%03d"), plus "%%" for a literal percent. */
/* Returns a bit mask: 1 if the pattern has an integer conversion, 2 if it
 * has %s; -1 (with an error set) if the pattern is malformed. */
int hd_pattern_kind(const char *spec);
hd_status hd_pattern_format(char *out, size_t cap, const char *spec, const char *name, long index);

/* Radiance's portable binary numbers (octrees, BSDF interpolants): an integer as siz big-endian
 * bytes; a real as a 4-byte mantissa m and a 1-byte exponent e, value (m + .5) / (2^31 - 1) * 2^e
 * (m - .5 for m < 0; 0 for m = 0). */
void hd_put_int(FILE *fp, long v, int siz);
void hd_put_flt(FILE *fp, double f);
double hd_portable_flt(long m, long e);

#endif

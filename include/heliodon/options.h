/* heliodon — Radiance-style command-line options.
 *
 * Options are single-dash words of one or more letters ("-ab 2", "-apC f 10m",
 * "-vta", "-I+").  A program describes its options in a table; the parser
 * matches each argument exactly against the names, then against entries
 * marked as prefixes (e.g. "f" for "-faf", "vt" for "-vta"), then fails
 * with a usage message.  "@file" arguments are replaced by the words of the
 * file (quotes '...' and "..." group words, '#' starts a comment line).
 * Parsing stops at the first argument that is not an option ("-" alone is
 * an operand meaning standard input) or after "--".
 *
 * Toggles follow Radiance: "-X" flips the value, "+X" and "-X+" set it,
 * "-X-" clears it. */
#ifndef HELIODON_OPTIONS_H
#define HELIODON_OPTIONS_H

#include <stdint.h>
#include "common.h"

typedef enum hd_opt_kind {
    HD_OPT_TOGGLE,   /* int*  : Radiance boolean */
    HD_OPT_INT,      /* int*  */
    HD_OPT_LONG,     /* long* */
    HD_OPT_COUNT,    /* uint64_t* : integer with k/m/g suffix */
    HD_OPT_REAL,     /* double* */
    HD_OPT_REAL3,    /* double[3] */
    HD_OPT_STRING,   /* const char** (points into argv); a prefix entry
                        matched by a longer word stores the word itself
                        ("-faf") and takes no argument */
    HD_OPT_FUNC,     /* callback, see below */
    HD_OPT_TABLE     /* dest: a nested table (const hd_opt *, ended by
                        HD_OPT_END) searched as if its entries were here —
                        option groups shared by several programs */
} hd_opt_kind;

struct hd_opt;
/* Callback: argv[i] is the option word itself ("-apC", "+I", "-faf").
 * Return the number of following words consumed (>= 0), or a negative
 * value after setting an error with hd_fail(). */
typedef int (*hd_opt_func)(const struct hd_opt *opt, int argc, char **argv, int i, void *ctx);

typedef struct hd_opt {
    const char *name;   /* without the dash: "ab", "vf", "I" */
    hd_opt_kind kind;
    void *dest;         /* variable to set, or ctx for HD_OPT_FUNC */
    hd_opt_func func;   /* HD_OPT_FUNC only */
    int prefix;         /* non-zero: also matches words that start with name */
    const char *args;   /* argument names for usage ("N", "file N") or NULL */
    const char *help;   /* one line for the usage message */
} hd_opt;

#define HD_OPT_END {0, 0, 0, 0, 0, 0, 0}

typedef struct hd_optparse {
    int argc;        /* expanded argument vector (after @file) */
    char **argv;
    int first;       /* index of the first operand */
    void *storage;   /* owned memory of the expanded vector */
} hd_optparse;

/* Parse argv against table.  On error sets a message and returns
 * HD_ERR_USAGE; the caller prints it with hd_opt_usage(). */
hd_status hd_opt_parse(hd_optparse *p, int argc, char **argv, const hd_opt *table);
void hd_optparse_free(hd_optparse *p);
/* Parse argv[1..] against table without @file expansion (the caller owns
 * the vector, already expanded): options are applied in the order given,
 * so an HD_OPT_FUNC callback sees the effect of every option before it
 * (rcontrib's -m takes the -b/-bn/-o/-p in force at its position).  On
 * success *first = index of the first operand.  Errors (unknown option,
 * bad value naming the option, callback failure): HD_ERR_USAGE with the
 * message set. */
hd_status hd_opt_parse_args(int argc, char **argv, const hd_opt *table, int *first);
/* Parse the single option at argv[i] (which starts with '-' or '+').
 * Returns the number of words used (>= 1), 0 if table has no such option
 * (no message set: the caller decides, e.g. warns and skips the word), or
 * -1 after setting a message (bad or missing value, callback failure). */
int hd_opt_parse_one(const hd_opt *table, int argc, char **argv, int i);
/* Print "prog: <error>\nusage: prog synopsis\n" and the option list. */
void hd_opt_usage(const hd_opt *table, const char *synopsis);
/* Convenience: parse or print usage and exit(1). Handles -version/-help. */
void hd_opt_parse_or_exit(hd_optparse *p, int argc, char **argv,
                          const hd_opt *table, const char *synopsis);
/* Expand "@file" words (used by hd_opt_parse; exposed for tests). */
hd_status hd_expand_args(int argc, char **argv, int *nargc, char ***nargv, void **storage);
/* Free the storage of an expanded vector (the vector and its words). */
void hd_expand_args_free(void *storage);
/* For HD_OPT_TOGGLE-like callbacks: new value of a toggle given the word. */
int hd_opt_toggle_value(const char *word, int current);

#endif

/* error.h: error values shared by every module.
 *
 * Fallible functions return int (0 = ok, non-zero = failure) and fill a
 * drape_error.  The first error wins: drape_error_set does nothing when the
 * error already holds one.  Only the command line prints or exits; it maps
 * a kind to an exit status with drape_error_exit_status.
 */
#ifndef DRAPE_ERROR_H
#define DRAPE_ERROR_H

#include <stddef.h>

typedef enum drape_error_kind {
    DRAPE_OK = 0,
    DRAPE_E_USAGE,   /* bad command line */
    DRAPE_E_IO,      /* file cannot be opened, read or written */
    DRAPE_E_SYNTAX,  /* not well-formed YAML, binary junk, empty file */
    DRAPE_E_INPUT,   /* well-formed but invalid input (key, type, unit, range) */
    DRAPE_E_NOMEM,   /* out of memory, or a lattice too large to allocate */
    DRAPE_E_NUMERIC, /* NaN/inf, folded hinge, solver failure */
    DRAPE_E_INTERNAL /* a bug: an invariant of drape itself was broken */
} drape_error_kind;

#define DRAPE_ERROR_FILE_MAX 512
#define DRAPE_ERROR_KEY_MAX 256
#define DRAPE_ERROR_MSG_MAX 512

typedef struct drape_error {
    drape_error_kind kind;
    char file[DRAPE_ERROR_FILE_MAX]; /* input file, "" if none */
    int line;                        /* 1-based, 0 if unknown */
    int column;                      /* 1-based, 0 if unknown */
    char key[DRAPE_ERROR_KEY_MAX];   /* key path, e.g. "bending.warp[1].poly" */
    char msg[DRAPE_ERROR_MSG_MAX];   /* what was expected, what was found */
} drape_error;

/* Reset to "no error". */
void drape_error_clear(drape_error *e);

/* Record an error unless one is already recorded (first error wins).
 * file and key may be NULL.  Returns -1 so callers can write
 * `return drape_error_set(...)`.  e may be NULL (then nothing is stored). */
int drape_error_set(drape_error *e, drape_error_kind kind, const char *file,
                    int line, int column, const char *key, const char *fmt,
                    ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 7, 8)))
#endif
    ;

/* GNU style message without the program name:
 * "FILE:LINE:COL: KEY: MSG" (parts that are unknown are left out).
 * Writes at most n bytes including the terminating NUL; returns buf. */
char *drape_error_format(const drape_error *e, char *buf, size_t n);

/* Exit status for a kind (documented in README and `drape --help`):
 * 0 ok, 1 invalid input (syntax or content), 2 usage, 3 I/O,
 * 4 numerical failure, 5 out of memory, 70 internal error. */
int drape_error_exit_status(drape_error_kind kind);

/* Warnings (e.g. a slope jump at a fit knot) go through a callback so only
 * the command line prints.  The drape_error carries location and text;
 * its kind is DRAPE_OK.  A NULL callback discards warnings. */
typedef void (*drape_warn_fn)(void *ctx, const drape_error *w);

#endif /* DRAPE_ERROR_H */

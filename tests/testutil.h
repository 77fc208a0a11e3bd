/* testutil.h: helpers shared by the Check suites. */
#ifndef DRAPE_TESTUTIL_H
#define DRAPE_TESTUTIL_H

#include <check.h>
#include <stddef.h>

/* Prototypes of every suite (the runner's list, generated from the file
 * names tests/check_NOUN.c -> NOUN_suite). */
#define SUITE(name) Suite *name##_suite(void);
#include "suites.gen.h"
#undef SUITE

/* Assert |obs - exp| <= tol * max(1, |exp|)-style checks print both values
 * with %.17g on failure. */
#define ck_assert_close_rel(obs, exp, rtol)                                   \
    do {                                                                      \
        double o_ = (obs), e_ = (exp), t_ = (rtol);                           \
        double d_ = o_ - e_; if (d_ < 0) d_ = -d_;                            \
        double s_ = e_ < 0 ? -e_ : e_;                                        \
        ck_assert_msg(d_ <= t_ * s_, "%s = %.17g, expected %.17g (rel tol %g)", \
                      #obs, o_, e_, t_);                                      \
    } while (0)
#define ck_assert_close_abs(obs, exp, atol)                                   \
    do {                                                                      \
        double o_ = (obs), e_ = (exp), t_ = (atol);                           \
        double d_ = o_ - e_; if (d_ < 0) d_ = -d_;                            \
        ck_assert_msg(d_ <= t_, "%s = %.17g, expected %.17g (abs tol %g)",     \
                      #obs, o_, e_, t_);                                      \
    } while (0)

/* Write `text` to a new file in a per-process scratch directory and return
 * its path (static buffer rotated over 8 slots).  `name` is the file's base
 * name, e.g. "bad.yaml". */
const char *tu_write_file(const char *name, const char *text);
/* Write raw bytes. */
const char *tu_write_bytes(const char *name, const void *data, size_t n);
/* The scratch directory (created on first use, removed at exit). */
const char *tu_scratch_dir(void);

/* Run the drape binary ($DRAPE_BIN, default ../drape) with the given
 * argument string through /bin/sh, capture stdout and stderr (each
 * truncated to cap-1 bytes, NUL-terminated), return the exit status (or -1
 * if it could not run / was killed by a signal). out/err may be NULL. */
int tu_run_drape(const char *args, char *out, size_t outcap, char *err,
                 size_t errcap);

/* Path of a file in the source tree relative to tests/ (e.g.
 * tu_src("scenes/cusick.yaml") -> "../scenes/cusick.yaml"). */
const char *tu_src(const char *rel);

/* The "# expect LINE KEY: why" first line of a tests/bad/ file: *line = 0
 * and key = "" when the file has none (or cannot be read). */
void tu_bad_header(const char *path, int *line, char *key, size_t nkey);

#endif

/* testutil.h: helpers shared by the Check suites. */
#ifndef DRAPE_TESTUTIL_H
#define DRAPE_TESTUTIL_H

#include <check.h>
#include <stddef.h>
#include <sys/types.h>

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

/* The drape binary the suites run: $DRAPE_BIN, or ../drape (relative to
 * tests/) when it is not set.  Read anew at each call (check_faults.c
 * changes DRAPE_BIN for a while); the string is getenv's or static. */
const char *tu_drape_bin(void);

/* Run the drape binary (tu_drape_bin()) with the given argument string
 * through /bin/sh, capture stdout and stderr (each truncated to cap-1
 * bytes, NUL-terminated), return the exit status (or -1 if it could not
 * run / was killed by a signal). out/err may be NULL. */
int tu_run_drape(const char *args, char *out, size_t outcap, char *err,
                 size_t errcap);

/* Run drape with the given argument string on a pseudo-terminal (stdout
 * and stderr a terminal, as a person's shell has them; made by script(1)),
 * capture what it prints (truncated to cap-1 bytes, NUL-terminated) and
 * return the exit status of script, which is drape's (-1 if it could not
 * run). */
int tu_run_drape_pty(const char *args, char *out, size_t outcap);

/* Processes of drape started without a shell, to signal them while they
 * run.  A test that spawns one ends it with tu_signal_and_reap. */

/* Start tu_drape_bin() with argv[0] "drape" and the NULL-terminated
 * arguments args (at most 62), SIGINT and SIGTERM at their default
 * actions, stdout and stderr written to the files out_path and err_path
 * (NULL: /dev/null); with new_group, in a process group of its own (id
 * the returned pid, set on both sides of the fork: either may run
 * first).  Returns the child's pid; fails the test if it cannot fork.  A
 * child that cannot redirect exits with 99, one that cannot exec with 98. */
pid_t tu_spawn_drape(const char *const args[], const char *out_path,
                     const char *err_path, int new_group);
/* tu_spawn_drape, and the child calls before_exec(arg) just before the
 * exec, after its redirections (its pid is drape's: drape re-execs
 * itself, keeping it); a non-zero return makes it exit with 97. */
pid_t tu_spawn_drape_hook(const char *const args[], const char *out_path,
                          const char *err_path, int new_group,
                          int (*before_exec)(void *), void *arg);

/* tu_wait_file's results other than 0. */
#define TU_WAIT_ENDED 1   /* the child ended first */
#define TU_WAIT_TIMEOUT 2 /* timeout_s passed */

/* Poll (every millisecond) until the file path exists (0), the child pid
 * ended (TU_WAIT_ENDED; it is not reaped: tu_signal_and_reap still gets
 * its status) or timeout_s seconds passed (TU_WAIT_TIMEOUT).  With path
 * NULL, wait the whole timeout_s: 0 if the child is still running then. */
int tu_wait_file(pid_t pid, const char *path, double timeout_s);
/* tu_wait_file that fails the test (at the caller's line) unless path
 * appeared: "drape ended before PATH" or "PATH never appeared". */
#define ck_assert_file_appears(pid, path, timeout_s)                          \
    do {                                                                      \
        const char *p_ = (path);                                              \
        int w_ = tu_wait_file((pid), p_, (timeout_s));                        \
        ck_assert_msg(w_ != TU_WAIT_ENDED, "drape ended before %s", p_);      \
        ck_assert_msg(w_ == 0, "%s never appeared", p_);                      \
    } while (0)

/* 1 if the child pid has ended (a zombie), without reaping it. */
int tu_child_ended(pid_t pid);

/* Send sig (0: none) to the child pid, or with group to its process
 * group, wait for it and return its wait status; fails the test if pid
 * is not a child that can be waited for. */
int tu_signal_and_reap(pid_t pid, int sig, int group);

/* Read the file path into buf (at most cap-1 bytes, NUL-terminated; ""
 * if it cannot be read).  buf NULL or cap 0: nothing. */
void tu_read_file(const char *path, char *buf, size_t cap);

/* Path of a file in the source tree relative to tests/ (e.g.
 * tu_src("scenes/cusick.yaml") -> "../scenes/cusick.yaml"). */
const char *tu_src(const char *rel);

/* The "# expect LINE KEY: why" first line of a tests/bad/ file: *line = 0
 * and key = "" when the file has none (or cannot be read). */
void tu_bad_header(const char *path, int *line, char *key, size_t nkey);

#endif

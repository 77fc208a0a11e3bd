/* cli_io.h: file helpers of the command-line files (cli_io.c): whole-file
 * reading, atomic file replacement, and a small RFC 4180 CSV reader and
 * writer.  Private to src/main.c and src/cli_*.c; only these print. */
#ifndef DRAPE_CLI_IO_H
#define DRAPE_CLI_IO_H

#include <stddef.h>
#include <stdio.h>
#include <sys/types.h>

#include "drape/error.h"

/* Fork a child that talks to the parent through a pipe (an ensemble's
 * specimen, a benchmark point).  stdout and stderr are flushed first.
 * Returns the child's pid in the parent, *fd the pipe's read end; 0 in
 * the child, *fd the write end; -1 if pipe or fork failed (errno set,
 * nothing left open). */
pid_t drape_cli_fork_pipe(int *fd);

/* Make directory DIR (one level) if it does not exist; an existing
 * non-directory is an E_IO error naming DIR and `--out`.  created may be
 * NULL; otherwise *created = 1 when this call made DIR. */
/* In a child just after fork: ask for SIGTERM when the parent (its pid
 * before the fork) dies, even of SIGKILL (Linux's PR_SET_PDEATHSIG; a
 * no-op elsewhere).  Async-signal-safe. */
void drape_cli_stop_with_parent(pid_t parent);

int drape_cli_ensure_dir(const char *dir, int *created, drape_error *err);
/* Hold DIR for this process until it exits (an exclusive flock on the
 * directory itself, shared with forked children; nothing is written): a
 * second drape run, ensemble or --resume with --out DIR while the first
 * still writes there is refused with an E_IO error naming DIR, instead
 * of both writing the same files.  Where the file system cannot lock a
 * directory (NFS) the run goes unguarded.  held may be NULL; otherwise
 * *held = 1 when this process now holds DIR, 0 when it goes unguarded.
 * 0, or -1 and err. */
int drape_cli_lock_dir(const char *dir, int *held, drape_error *err);
/* Where a temporary's name has its writer's PID: NAME.tmp.PID
 * (drape_cli_afile's: ensemble.json, shadow.svg, shadow.png, result.txt)
 * or NAME.PID.tmp (output.h's: frame_NNNNNN.obj, drape.h5, drape.xmf). */
typedef enum { DRAPE_CLI_TMP_PID_LAST, DRAPE_CLI_TMP_PID_FIRST } drape_cli_tmp_form;
/* Remove the temporaries of NAME in DIR, named as form says with digits
 * for the PID (left by a process killed outright while it wrote NAME),
 * and no other file.  NAME is an fnmatch(3) pattern (frame_[0-9]...
 * for every frame).  Only for a DIR this process holds
 * (drape_cli_lock_dir): no live writer's temporary is then there.
 * Returns how many were removed. */
int drape_cli_remove_stale_tmp(const char *dir, const char *name, drape_cli_tmp_form form);
/* DIR/NAME can be replaced by a file at the end of a run: it does not
 * exist or is not a directory.  0, or -1 with an E_IO error. */
int drape_cli_check_target(const char *dir, const char *name, drape_error *err);

/* Read a whole file of at most max bytes into a NUL-terminated buffer
 * (*len = its length, may be NULL).  Caller frees with drape_free.  NULL
 * and err on failure. */
char *drape_cli_read_file(const char *path, size_t max, size_t *len,
                          drape_error *err);

/* FNV-1a (64 bits) of a file's bytes (at most max): whether an input
 * changed since it was recorded (batch's inputs.sum, an ensemble's
 * manifest), not a digest against tampering.  Never 0 for a file read.
 * 0, or -1 and err (E_IO naming the file, E_NOMEM). */
int drape_cli_file_sum(const char *path, size_t max, unsigned long long *sum,
                       drape_error *err);

/* Read a file of at most max bytes that holds one JSON value (blanks and
 * // or / * * / comments around it, as ARCSim's files have): the value
 * (caller frees with json_object_put), or NULL and err: E_SYNTAX at
 * path:line:column for a NUL byte, malformed JSON or text after the value
 * (LF, CR LF and CR alone each end a line), E_IO or E_NOMEM. */
struct json_object *drape_cli_read_json(const char *path, size_t max, drape_error *err);

/* drape_cli_read_json, and every number in the file, checked on its own
 * text with drape_units_strtod (units.h), must be a normal double or 0:
 * one that overflows (1e400), underflows (1e-400) or is denormal (1e-310)
 * is an E_INPUT error at path:line:column naming its key path
 * ("bending[2][4]", "specimens[3].dc"), where json-c would give inf, 0
 * or the denormal.  For the files a person hands to drape (import's
 * ARCSim materials, compare's results); drape's own manifests are read
 * as they are. */
struct json_object *drape_cli_read_json_in_range(const char *path, size_t max, drape_error *err);

/* Replace a file atomically: open writes to PATH.tmp.PID next to it;
 * commit flushes, fsyncs and renames it over PATH; abort removes it.  A
 * reader sees either the old or the new file, never a partial one. */
typedef struct drape_cli_afile {
    FILE *f;         /* write the contents here */
    char path[4096]; /* target */
    char tmp[4160];  /* temporary, same directory */
} drape_cli_afile;
int drape_cli_afile_open(drape_cli_afile *a, const char *path, drape_error *err);
int drape_cli_afile_commit(drape_cli_afile *a, drape_error *err);
void drape_cli_afile_abort(drape_cli_afile *a);

/* CSV reader: position in a text (zero-initialise before the first call)
 * and one record (fields unquoted, NUL-terminated; col[i] is the 1-based
 * column where field i starts, line the line where the record starts). */
typedef struct drape_cli_csv_pos {
    size_t off;
    int line, col;
} drape_cli_csv_pos;
typedef struct drape_cli_csv_rec {
    int n;
    char **field;
    int *col;
    int line;
} drape_cli_csv_rec;
/* Read the next record of text[0..len).  Returns 1 and fills *r (caller
 * frees with drape_cli_csv_rec_free), 0 at the end of the text, or -1 and
 * fills err (file:line:column) for malformed CSV.  A record ends at LF,
 * CR LF or CR alone; a blank line is a record of one empty field. */
int drape_cli_csv_next(const char *text, size_t len, drape_cli_csv_pos *p,
                       drape_cli_csv_rec *r, const char *file, drape_error *err);
void drape_cli_csv_rec_free(drape_cli_csv_rec *r);
/* Write one field, quoted when it holds a comma, quote, line break or
 * leading/trailing space. */
void drape_cli_csv_put(FILE *out, const char *s);

#endif /* DRAPE_CLI_IO_H */

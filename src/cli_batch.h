/* cli_batch.h: `drape batch`'s state, shared by its two parts: the runner
 * (cli_batch.c: options, child processes, signals) and the record of the
 * batch directory (cli_batch_record.c: the rows of DIR/results.csv, the
 * fabric files' sums in DIR/inputs.sum, the DIR/batch.args stamp, and
 * what --resume reads back).  Private to src/cli_batch*.c. */
#ifndef DRAPE_CLI_BATCH_H
#define DRAPE_CLI_BATCH_H

#include <sys/types.h>

#include "drape/error.h"

#define BATCH_EXIT_SOME_FAILED 6
#define BATCH_EXIT_SIGINT 130  /* 128 + SIGINT, as shells report it */
#define BATCH_EXIT_SIGTERM 143 /* 128 + SIGTERM */
#define BATCH_MAX_JOBS 1024
#define BATCH_DEFAULT_DIR "batch-out"
#define BATCH_MAX_RESULTS (256L * 1024 * 1024) /* results.csv read on --resume */
#define BATCH_MAX_CHILD_OUT (1024L * 1024)    /* a run's stdout or stderr */
#define BATCH_PATH_MAX 4096
#define BATCH_NAME_MAX 100

/* The keys of `drape run --format csv`, in its order (cli_run.c; the
 * contract: added to, never renamed), are the columns between fabric_file and error.  A
 * child's row is mapped onto these by name; tests/check_batch.c checks
 * that the list matches the run's header. */
#define run_keys drape_cli_run_keys
#define N_RUN_KEYS drape_cli_run_nkeys()
/* results.csv columns: fabric_file, the run keys, error */
#define N_COLS (N_RUN_KEYS + 2)
#define COL_FILE 0
#define COL_ERROR (N_COLS - 1)

enum job_state { JOB_TODO, JOB_RUNNING, JOB_DONE, JOB_KILLED };

typedef struct job {
    const char *fabric;          /* as given on the command line */
    char name[BATCH_NAME_MAX + 16]; /* unique, file-name safe: logs/NAME.* (stem, -N) */
    pid_t pid;
    enum job_state state;
    int resumed;                 /* row taken from an earlier results.csv */
    int cont;                    /* continue its interrupted run (--resume --frames) */
    int rowless;                 /* cont without a row: its run's batch was killed */
    char **row;                  /* N_COLS fields, or NULL */
    unsigned long long sum;      /* of the fabric file's text (0: unreadable) */
} job;

typedef struct batch {
    const char *scene;
    const char *dir;
    const char *pass[48];        /* options passed on to `drape run` (name, value) */
    int npass;
    int frames, progress;
    job *jobs;
    int n;
    char ***extra;               /* earlier rows of fabrics not given now */
    int n_extra;
    /* DIR/inputs.sum as read by --resume: the fabric files' sums when
     * their rows were made (fabric_file as in results.csv) */
    char **old_file;
    unsigned long long *old_sum;
    char **old_name;             /* its NAME then (NULL: a file of before) */
    int n_old;
    int n_done, n_bad, n_running;
    char results[BATCH_PATH_MAX];
} batch;


/* ---- rows (N_COLS fields each) ---------------------------------------------- */

int drape_cli_batch_col(const char *key); /* column of a key, -1 if none */
char **drape_cli_batch_row_new(void);
void drape_cli_batch_row_free(char **row);
/* set a field (copied; line breaks become spaces) */
int drape_cli_batch_row_set(char **row, int col, const char *s);
const char *drape_cli_batch_row_status(char **row); /* "" if none */
int drape_cli_batch_status_ok(const char *s);       /* equilibrium or t_max */

/* ---- the batch directory ---------------------------------------------------- */

/* FNV-1a of a file's bytes (0: unreadable) */
unsigned long long drape_cli_batch_file_sum(const char *given);
/* write DIR/results.csv and DIR/inputs.sum (atomically) */
int drape_cli_batch_write_results(const batch *b, drape_error *err);
/* write DIR/batch.args, or with resume compare it with this batch's */
int drape_cli_batch_check_stamp(const batch *b, int resume, drape_error *err);
/* --resume: read DIR/inputs.sum, then DIR/results.csv */
int drape_cli_batch_read_sums(batch *b, drape_error *err);
/* the NAME recorded in inputs.sum for a row's fabric_file (NULL: none) */
const char *drape_cli_batch_old_name(const batch *b, const char *fabric_file);
int drape_cli_batch_load_previous(batch *b, drape_error *err);
/* free what the record functions allocated (b itself is the caller's) */
void drape_cli_batch_free_record(batch *b);

#endif

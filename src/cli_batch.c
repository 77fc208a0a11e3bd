/* cli_batch.c: `drape batch SCENE.yaml FABRIC.yaml... [options]`: run one
 * scene once per fabric, N at a time, each in a child process that
 * executes drape itself (`drape run --format csv --quiet --fabric F ...`),
 * and collect one row per fabric in DIR/results.csv: `fabric_file`, the
 * keys of `drape run` (its CSV header), and `error`.  The file is replaced
 * atomically after each finished fabric, so a batch that is killed keeps
 * every row it finished; --resume skips the fabrics whose row is done.
 * Contract, file layout and exit statuses: docs/batch.md. */
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cli.h"
#include "cli_data.h"
#include "cli_io.h"
#include "drape/alloc.h"
#include "drape/fabric.h"
#include "drape/integrator.h"
#include "drape/output.h"
#include "drape/scene.h"
#include "drape/units.h"
#include "drape/yamldoc.h"

static const char batch_usage[] =
    "Usage: drape batch SCENE.yaml FABRIC.yaml... [OPTIONS]\n"
    "\n"
    "Run SCENE once per fabric (`drape run SCENE --fabric FABRIC`) in parallel\n"
    "child processes and write one CSV row per fabric to DIR/results.csv:\n"
    "fabric_file, the keys of `drape run --format csv`, and error (the run's\n"
    "error message, empty on success).  status is equilibrium, t_max, failed\n"
    "or interrupted as reported by the run, or error when the run printed no\n"
    "result (invalid fabric, crash).  results.csv is replaced atomically after\n"
    "every finished fabric; each run's output and messages are kept in\n"
    "DIR/logs/.\n"
    "\n"
    "Options:\n"
    "  -j, --jobs N         run N fabrics at a time (default 1; 0 = one per CPU)\n"
    "  --out DIR            output directory (default batch-out; created)\n"
    "  --resume             keep the rows of DIR/results.csv whose status is\n"
    "                       equilibrium, t_max or failed and run only the other\n"
    "                       fabrics (rows with status error or interrupted are\n"
    "                       run again; with --frames an interrupted run continues\n"
    "                       from its checkpoint, `drape run --resume`); a fabric\n"
    "                       file changed since its row was made is run again, a\n"
    "                       changed scene file is refused (exit 2)\n"
    "  --frames             also write each run's frames to DIR/frames/NAME/\n"
    "  -q, --quiet          no progress line on stderr\n"
    "  -h, --help           show this help\n"
    "Passed on to every run (see `drape run --help`):\n"
    "  --integrator NAME, --rtol X, --atol X, --spacing LEN, --energy-form FORM,\n"
    "  --t-max T, --max-steps N, --strain-limit X, --method fall|dynamic|static,\n"
    "  --linear-solver NAME, --max-order N, --specimens N, --seed N,\n"
    "  --fall-time T, --fall-step T, --fall-swing X, --fall-tol L,\n"
    "  --fall-fold-time T, --fall-retry T, --terms LIST,\n"
    "  --damping-shear T (each fabric's specimens run one after another in its\n"
    "  process; the results carry the ensemble columns dc_sd,\n"
    "  dc_ci95, dc_mode, nodes_hist, specimens: docs/ensemble.md)\n"
    "\n"
    "Progress goes to stderr only when it is a terminal.  The first interrupt\n"
    "(Ctrl-C) stops launching runs and waits for the running ones; a second\n"
    "one, or SIGTERM, stops them at their next output point (their rows get\n"
    "status interrupted and are run again by --resume).  The scene is checked\n"
    "once, before any run (with the first fabric that loads).\n"
    "\n"
    "Exit status: 0 every fabric reached equilibrium or t_max; 6 at least one\n"
    "run failed or could not run (see its row); 1 invalid scene; 2 bad command\n"
    "line; 3 the scene file (or the fabric it names: it must exist, as for\n"
    "`drape check`) cannot be read, or DIR or results.csv cannot be written;\n"
    "5 out of memory; 130\n"
    "interrupted (SIGINT); 143 terminated (SIGTERM).\n";

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
 * contract of issue 3).  A child's row is mapped onto these by name;
 * tests/check_batch.c checks that the list matches the run's header. */
/* The run's result keys (cli_run.c), the columns between file and error. */
#define run_keys drape_cli_run_keys
#define N_RUN_KEYS drape_cli_run_nkeys()
/* results.csv columns: fabric_file, the run keys, error */
#define N_COLS (N_RUN_KEYS + 2)
#define COL_FILE 0
#define COL_ERROR (N_COLS - 1)

enum job_state { JOB_TODO, JOB_RUNNING, JOB_DONE, JOB_KILLED };

typedef struct job {
    const char *fabric;          /* as given on the command line */
    char name[BATCH_NAME_MAX + 8]; /* unique, file-name safe: logs/NAME.* */
    pid_t pid;
    enum job_state state;
    int resumed;                 /* row taken from an earlier results.csv */
    int cont;                    /* continue its interrupted run (--resume --frames) */
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
    int n_old;
    int n_done, n_bad, n_running;
    char results[BATCH_PATH_MAX];
} batch;

static volatile sig_atomic_t got_sigint, got_sigterm;

static void on_signal(int sig)
{
    if (sig == SIGINT) got_sigint++;
    else got_sigterm = 1;
}

/* ---- rows ------------------------------------------------------------------ */

static int col_of(const char *key)
{
    if (strcmp(key, "fabric_file") == 0) return COL_FILE;
    if (strcmp(key, "error") == 0) return COL_ERROR;
    for (int i = 0; i < N_RUN_KEYS; i++)
        if (strcmp(key, run_keys[i]) == 0) return i + 1;
    return -1;
}

static void row_free(char **row)
{
    if (!row) return;
    for (int i = 0; i < N_COLS; i++) drape_free(row[i]);
    drape_free(row);
}

static char **row_new(void)
{
    return drape_calloc(N_COLS, sizeof(char *));
}

/* Set a field (copy); line breaks become spaces so that every row is one
 * line (scripts/slurm/submit.sh merges row files line by line). */
static int row_set(char **row, int col, const char *s)
{
    char *t = drape_strdup(s ? s : "");
    if (!t) return -1;
    for (char *c = t; *c; c++)
        if (*c == '\n' || *c == '\r') *c = ' ';
    drape_free(row[col]);
    row[col] = t;
    return 0;
}

static const char *row_status(char **row)
{
    const char *s = row ? row[col_of("status")] : NULL;
    return s ? s : "";
}

/* A row is done (not run again by --resume) when the run produced a
 * result: equilibrium, t_max or failed (a numerical failure is
 * deterministic).  `error` rows (invalid input, I/O, crash) are run again. */
static int status_done(const char *s)
{
    return strcmp(s, "equilibrium") == 0 || strcmp(s, "t_max") == 0 ||
           strcmp(s, "failed") == 0;
}

static int status_ok(const char *s)
{
    return strcmp(s, "equilibrium") == 0 || strcmp(s, "t_max") == 0;
}

/* ---- files ----------------------------------------------------------------- */

static int mkdir_p(const char *dir, drape_error *err)
{
    char p[BATCH_PATH_MAX];
    if (snprintf(p, sizeof p, "%s", dir) >= (int)sizeof p)
        return drape_error_set(err, DRAPE_E_IO, dir, 0, 0, NULL, "path too long");
    for (char *c = p + 1;; c++) {
        if (*c != '/' && *c) continue;
        char keep = *c;
        *c = 0;
        struct stat st;
        if (stat(p, &st) != 0) {
            if (mkdir(p, 0777) != 0 && errno != EEXIST)
                return drape_error_set(err, DRAPE_E_IO, p, 0, 0, NULL,
                                       "cannot create directory: %s", strerror(errno));
        } else if (!S_ISDIR(st.st_mode)) {
            return drape_error_set(err, DRAPE_E_IO, p, 0, 0, NULL, "not a directory");
        }
        *c = keep;
        if (!keep) break;
    }
    return 0;
}

/* FNV-1a (64 bits) of a file's bytes: whether an input changed since a
 * row was made, not a digest against tampering.  0 if it cannot be read
 * (the run then reports the error itself). */
static unsigned long long file_sum(const char *given)
{
    char path[4096];
    drape_error e;
    drape_error_clear(&e);
    if (drape_cli_data_find(given, path, sizeof path, &e) != 0) return 0;
    size_t len = 0;
    char *text = drape_cli_read_file(path, DRAPE_YDOC_MAX_BYTES, &len, &e);
    if (!text) return 0;
    unsigned long long h = 14695981039346656037ULL;
    for (size_t i = 0; i < len; i++) {
        h ^= (unsigned char)text[i];
        h *= 1099511628211ULL;
    }
    drape_free(text);
    return h ? h : 1;
}

/* the sum recorded for a row's fabric_file (0: none recorded) */
static unsigned long long old_sum_of(const batch *b, const char *field)
{
    for (int i = 0; i < b->n_old; i++)
        if (strcmp(b->old_file[i], field) == 0) return b->old_sum[i];
    return 0;
}

/* DIR/inputs.sum: "SUM<TAB>fabric_file" for every row, so that --resume
 * can tell a fabric file edited since its row was made */
static int write_sums(const batch *b, drape_error *err)
{
    char path[BATCH_PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/inputs.sum", b->dir);
    drape_cli_afile a;
    if (drape_cli_afile_open(&a, path, err) != 0) return -1;
    for (int k = 0; k < b->n + b->n_extra; k++) {
        char **row = k < b->n ? b->jobs[k].row : b->extra[k - b->n];
        if (!row) continue;
        unsigned long long h = k < b->n ? b->jobs[k].sum : old_sum_of(b, row[COL_FILE]);
        if (h) fprintf(a.f, "%016llx\t%s\n", h, row[COL_FILE]);
    }
    return drape_cli_afile_commit(&a, err);
}

static int read_sums(batch *b, drape_error *err)
{
    char path[BATCH_PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/inputs.sum", b->dir);
    if (access(path, F_OK) != 0) return 0; /* a batch made before it */
    char *text = drape_cli_read_file(path, BATCH_MAX_RESULTS, NULL, err);
    if (!text) return -1;
    int rc = 0;
    for (char *line = text, *next; line && *line; line = next) {
        next = strchr(line, '\n');
        if (next) *next++ = 0;
        char *tab = strchr(line, '\t');
        if (!tab) continue;
        *tab = 0;
        char **nf = drape_realloc(b->old_file, (size_t)(b->n_old + 1) * sizeof *nf);
        unsigned long long *ns = nf ? drape_realloc(b->old_sum, (size_t)(b->n_old + 1) * sizeof *ns)
                                    : NULL;
        if (nf) b->old_file = nf;
        if (ns) b->old_sum = ns;
        if (!nf || !ns || !(b->old_file[b->n_old] = drape_strdup(tab + 1))) {
            rc = drape_error_set(err, DRAPE_E_NOMEM, path, 0, 0, NULL, "out of memory");
            break;
        }
        b->old_sum[b->n_old++] = strtoull(line, NULL, 16);
    }
    drape_free(text);
    return rc;
}

static int write_results(const batch *b, drape_error *err)
{
    drape_cli_afile a;
    if (drape_cli_afile_open(&a, b->results, err) != 0) return -1;
    fputs("fabric_file", a.f);
    for (int i = 0; i < N_RUN_KEYS; i++) fprintf(a.f, ",%s", run_keys[i]);
    fputs(",error\n", a.f);
    for (int k = 0; k < b->n + b->n_extra; k++) {
        char **row = k < b->n ? b->jobs[k].row : b->extra[k - b->n];
        if (!row) continue;
        for (int i = 0; i < N_COLS; i++) {
            if (i) fputc(',', a.f);
            drape_cli_csv_put(a.f, row[i]);
        }
        fputc('\n', a.f);
    }
    if (drape_cli_afile_commit(&a, err) != 0) return -1;
    return write_sums(b, err);
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

/* 1 if texts x and y hold the same lines in any order, leaving out those
 * that start with skip (NULL: none). */
static int same_lines(const char *x, const char *y, const char *skip)
{
    enum { MAXL = 128 };
    char *t[2] = {drape_strdup(x), drape_strdup(y)}, *l[2][MAXL];
    int n[2] = {0, 0}, same = t[0] && t[1];
    for (int s = 0; s < 2 && same; s++) {
        for (char *p = t[s], *q; p && *p; p = q) {
            q = strchr(p, '\n');
            if (q) *q++ = 0;
            if (skip && strncmp(p, skip, strlen(skip)) == 0) continue;
            if (n[s] == MAXL) { same = 0; break; }
            l[s][n[s]++] = p;
        }
        qsort(l[s], (size_t)n[s], sizeof l[s][0], cmp_str);
    }
    same = same && n[0] == n[1];
    for (int i = 0; same && i < n[0]; i++) same = strcmp(l[0][i], l[1][i]) == 0;
    drape_free(t[0]);
    drape_free(t[1]);
    return same;
}

/* DIR/batch.args records the scene and the options passed to the runs;
 * --resume refuses a directory made with other ones. */
static int check_args_stamp(const batch *b, int resume, drape_error *err)
{
    char path[BATCH_PATH_MAX], *want = NULL, *have = NULL;
    size_t wn = 0;
    int rc = -1;
    FILE *m = open_memstream(&want, &wn);
    if (!m) return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
    fprintf(m, "scene %s\n", b->scene);
    for (int i = 0; i + 1 < b->npass; i += 2) fprintf(m, "%s %s\n", b->pass[i], b->pass[i + 1]);
    if (b->frames) fputs("--frames\n", m);
    fprintf(m, "scene-sum %016llx\n", file_sum(b->scene));
    if (fclose(m) != 0) {
        free(want);
        return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
    }
    snprintf(path, sizeof path, "%s/batch.args", b->dir);
    if (resume && access(path, F_OK) == 0) {
        if (!(have = drape_cli_read_file(path, 1 << 20, NULL, err))) goto out;
        /* the same lines in any order: `--seed 3 --spacing 5mm` is the
         * batch of `--spacing 5mm --seed 3` (each option occurs once) */
        int same = same_lines(have, want, NULL);
        int same_but_sum = !same && same_lines(have, want, "scene-sum ");
        int have_sum = strncmp(have, "scene-sum ", 10) == 0 || strstr(have, "\nscene-sum ");
        if (same || (same_but_sum && !have_sum)) { /* (or made before scene-sum) */
            rc = 0;
            goto out;
        }
        if (same_but_sum) {
            drape_error_set(err, DRAPE_E_USAGE, path, 0, 0, NULL,
                            "--resume: the scene file %s changed since this batch "
                            "started (its scene-sum differs): rows made with the old "
                            "and the new scene would be mixed; use another --out",
                            b->scene);
            goto out;
        }
        {
            drape_error_set(err, DRAPE_E_USAGE, path, 0, 0, NULL,
                            "--resume: this batch was started with another scene "
                            "or other options; use the same ones (listed in this "
                            "file), or another --out");
            goto out;
        }
        rc = 0;
        goto out;
    }
    drape_cli_afile a;
    if (drape_cli_afile_open(&a, path, err) != 0) goto out;
    fputs(want, a.f);
    rc = drape_cli_afile_commit(&a, err);
out:
    free(want); /* from open_memstream */
    drape_free(have);
    return rc;
}

/* fabric_file as row_set stored it (line breaks as spaces) */
static int same_file_field(const char *fabric, const char *field)
{
    for (; *fabric && *field; fabric++, field++) {
        char c = *fabric == '\n' || *fabric == '\r' ? ' ' : *fabric;
        if (c != *field) return 0;
    }
    return *fabric == *field;
}

/* --resume: read DIR/results.csv; keep done rows of given fabrics and every
 * row of fabrics not given now. */
static int load_previous(batch *b, drape_error *err)
{
    struct stat st;
    if (stat(b->results, &st) != 0 && errno == ENOENT) return 0;
    size_t len;
    char *text = drape_cli_read_file(b->results, BATCH_MAX_RESULTS, &len, err);
    if (!text) return -1;
    drape_cli_csv_pos p = {0, 0, 0};
    drape_cli_csv_rec hdr = {0, NULL, NULL, 0}, r = {0, NULL, NULL, 0};
    int *map = NULL, rc = -1, got;
    char **row = NULL;
    if ((got = drape_cli_csv_next(text, len, &p, &hdr, b->results, err)) < 0) goto out;
    if (got == 0 || hdr.n < 1 || strcmp(hdr.field[0], "fabric_file") != 0) {
        drape_error_set(err, DRAPE_E_INPUT, b->results, 1, 1, NULL,
                        "--resume: not a results file of drape batch (the "
                        "first column must be fabric_file)");
        goto out;
    }
    if (!(map = drape_calloc((size_t)hdr.n, sizeof *map))) goto nomem;
    int have_status = 0;
    for (int i = 0; i < hdr.n; i++) {
        map[i] = col_of(hdr.field[i]);
        have_status |= map[i] == col_of("status");
    }
    if (!have_status) {
        drape_error_set(err, DRAPE_E_INPUT, b->results, 1, 1, NULL,
                        "--resume: no status column");
        goto out;
    }
    while ((got = drape_cli_csv_next(text, len, &p, &r, b->results, err)) == 1) {
        if (r.n == 1 && r.field[0][0] == 0) { /* blank line */
            drape_cli_csv_rec_free(&r);
            continue;
        }
        if (r.n != hdr.n) {
            drape_error_set(err, DRAPE_E_INPUT, b->results, r.line, 1, NULL,
                            "--resume: %d fields, the header has %d", r.n, hdr.n);
            goto out;
        }
        if (!(row = row_new())) goto nomem;
        for (int i = 0; i < r.n; i++)
            if (map[i] >= 0 && row_set(row, map[i], r.field[i]) != 0) goto nomem;
        for (int i = 0; i < N_COLS; i++)
            if (!row[i] && row_set(row, i, "") != 0) goto nomem;
        drape_cli_csv_rec_free(&r);
        job *jb = NULL;
        for (int k = 0; k < b->n && !jb; k++)
            if (same_file_field(b->jobs[k].fabric, row[COL_FILE])) jb = &b->jobs[k];
        /* the fabric file edited since this row was made (a sum is on
         * record and differs): its row is run again, afresh */
        unsigned long long was = jb ? old_sum_of(b, row[COL_FILE]) : 0;
        int changed = jb && was && jb->sum && was != jb->sum;
        if (changed)
            fprintf(stderr, "drape: batch: %s changed since its row was made: run again\n",
                    jb->fabric);
        if (jb) {
            if (b->frames && !changed && strcmp(row_status(row), "interrupted") == 0) jb->cont = 1;
            if (!jb->row || (jb->state != JOB_DONE && status_done(row_status(row)))) {
                /* a done row: kept; another (error, interrupted) or one of
                 * a changed file: kept in results.csv until the fabric's
                 * new run replaces it */
                row_free(jb->row);
                jb->row = row;
                if (status_done(row_status(row)) && !changed) {
                    jb->state = JOB_DONE;
                    jb->resumed = 1;
                }
                row = NULL;
            }
        } else {
            char ***ne = drape_realloc(b->extra, (size_t)(b->n_extra + 1) * sizeof *ne);
            if (!ne) goto nomem;
            b->extra = ne;
            b->extra[b->n_extra++] = row;
            row = NULL;
        }
        row_free(row);
        row = NULL;
    }
    if (got < 0) goto out;
    rc = 0;
    goto out;
nomem:
    drape_error_set(err, DRAPE_E_NOMEM, b->results, 0, 0, NULL, "out of memory");
out:
    row_free(row);
    drape_cli_csv_rec_free(&r);
    drape_cli_csv_rec_free(&hdr);
    drape_free(map);
    drape_free(text);
    return rc;
}

/* ---- children ---------------------------------------------------------------- */

static void log_path(const batch *b, const job *jb, const char *ext, char *out, size_t n)
{
    snprintf(out, n, "%s/logs/%s.%s", b->dir, jb->name, ext);
}

/* 1 if the checkpoint at path is a run of fabric (NAME depends on the
 * command line's order: another fabric may have had this NAME before). */
static int checkpoint_is_for(const char *path, const char *fabric)
{
    char buf[4096];
    struct stat want, have;
    drape_error e;
    drape_error_clear(&e);
    if (drape_cli_data_find(fabric, buf, sizeof buf, &e) != 0 || stat(buf, &want) != 0) return 0;
    drape_h5_checkpoint c;
    memset(&c, 0, sizeof c);
    if (drape_h5_checkpoint_read(path, &c, &e) != 0) return 0;
    const drape_kv *kv = drape_kv_find(c.run, c.n_run, "fabric_path");
    int same = kv && kv->text && stat(kv->text, &have) == 0 && have.st_dev == want.st_dev &&
               have.st_ino == want.st_ino;
    drape_h5_checkpoint_free(&c);
    return same;
}

static int launch(batch *b, job *jb, drape_error *err)
{
    char out_path[BATCH_PATH_MAX], err_path[BATCH_PATH_MAX], frames[BATCH_PATH_MAX];
    /* 7 fixed + --fabric F + every passed option + --out DIR + -- SCENE + NULL */
    const char *av[7 + 2 + sizeof b->pass / sizeof b->pass[0] + 2 + 2 + 1];
    int k = 0;
    log_path(b, jb, "csv", out_path, sizeof out_path);
    log_path(b, jb, "stderr", err_path, sizeof err_path);
    snprintf(frames, sizeof frames, "%s/frames/%s", b->dir, jb->name);
    av[k++] = "drape";
    av[k++] = "run";
    av[k++] = "--format";
    av[k++] = "csv";
    av[k++] = "--quiet";
    av[k++] = "-j"; /* the batch runs fabrics in parallel, each its specimens in turn */
    av[k++] = "1";
    char ck[BATCH_PATH_MAX + 16];
    snprintf(ck, sizeof ck, "%s/drape.h5", frames);
    if (jb->cont && access(ck, F_OK) == 0 && checkpoint_is_for(ck, jb->fabric)) {
        /* the options are stored in the checkpoint (batch.args made sure
         * they are this batch's) */
        av[k++] = "--resume";
        av[k++] = frames;
    } else {
        av[k++] = "--fabric";
        av[k++] = jb->fabric;
        for (int i = 0; i < b->npass; i++) av[k++] = b->pass[i];
        if (b->frames) {
            av[k++] = "--out";
            av[k++] = frames;
        }
        av[k++] = "--";
        av[k++] = b->scene;
    }
    av[k] = NULL;

    fflush(NULL);
    pid_t parent = getpid();
    pid_t pid = fork();
    if (pid < 0)
        return drape_error_set(err, DRAPE_E_IO, NULL, 0, 0, NULL,
                               "cannot start a process: %s", strerror(errno));
    if (pid == 0) {
        /* own process group: a Ctrl-C at the terminal reaches the batch
         * only, which lets the running fabrics finish; a batch killed
         * outright (SIGKILL, the OOM killer) stops them too */
        setpgid(0, 0);
        drape_cli_stop_with_parent(parent);
        int fi = open("/dev/null", O_RDONLY);
        int fo = open(out_path, O_WRONLY | O_CREAT | O_TRUNC, 0666);
        int fe = open(err_path, O_WRONLY | O_CREAT | O_TRUNC, 0666);
        if (fi < 0 || fo < 0 || fe < 0) _exit(127);
        if (dup2(fi, 0) < 0 || dup2(fo, 1) < 0 || dup2(fe, 2) < 0) _exit(127);
        close(fi), close(fo), close(fe);
        /* only async-signal-safe calls between fork and exec */
        signal(SIGINT, SIG_DFL);
        signal(SIGTERM, SIG_DFL);
        /* the same binary as the batch, even if the file was replaced */
        execv("/proc/self/exe", (char *const *)av);
        execvp("drape", (char *const *)av); /* no /proc */
        static const char m[] = "drape: batch: cannot execute drape\n";
        if (write(2, m, sizeof m - 1) < 0) _exit(127);
        _exit(127);
    }
    setpgid(pid, pid); /* also here: no race with a kill() below */
    jb->pid = pid;
    jb->state = JOB_RUNNING;
    b->n_running++;
    return 0;
}

/* Last "drape: ..." line of a run's stderr that is not a warning, without
 * the prefix. */
static void last_error_line(const char *text, char *out, size_t n)
{
    out[0] = 0;
    for (const char *l = text; l && *l;) {
        const char *e = strchr(l, '\n');
        size_t len = e ? (size_t)(e - l) : strlen(l);
        if (len > 7 && strncmp(l, "drape: ", 7) == 0) {
            const char *w = strstr(l, "warning: ");
            if (!w || w >= l + len) snprintf(out, n, "%.*s", (int)(len - 7), l + 7);
        }
        l = e ? e + 1 : NULL;
    }
}

/* Fill jb->row from the run's stdout, stderr and wait status. */
static int collect(batch *b, job *jb, int wstatus, drape_error *err)
{
    char out_path[BATCH_PATH_MAX], err_path[BATCH_PATH_MAX], msg[1024], full[1400];
    char *out = NULL, *etext = NULL;
    size_t olen = 0;
    drape_cli_csv_rec hdr = {0, NULL, NULL, 0}, r = {0, NULL, NULL, 0};
    drape_cli_csv_pos p = {0, 0, 0};
    drape_error ign;
    int rc = -1, have_row = 0, nf_hdr = -1, nf_row = -1;
    log_path(b, jb, "csv", out_path, sizeof out_path);
    log_path(b, jb, "stderr", err_path, sizeof err_path);
    drape_error_clear(&ign);
    out = drape_cli_read_file(out_path, BATCH_MAX_CHILD_OUT, &olen, &ign);
    drape_error_clear(&ign);
    etext = drape_cli_read_file(err_path, BATCH_MAX_CHILD_OUT, NULL, &ign);
    last_error_line(etext, msg, sizeof msg);

    row_free(jb->row);
    if (!(jb->row = row_new())) goto nomem;
    drape_error_clear(&ign);
    if (out && drape_cli_csv_next(out, olen, &p, &hdr, out_path, &ign) == 1 &&
        drape_cli_csv_next(out, olen, &p, &r, out_path, &ign) == 1) {
        nf_hdr = hdr.n, nf_row = r.n;
        have_row = r.n == hdr.n;
    }
    if (have_row) {
        for (int i = 0; i < hdr.n; i++) {
            int c = col_of(hdr.field[i]);
            if (c > COL_FILE && c < COL_ERROR && row_set(jb->row, c, r.field[i]) != 0)
                goto nomem;
        }
    }
    int code = WIFEXITED(wstatus) ? WEXITSTATUS(wstatus) : -1;
    if (WIFSIGNALED(wstatus))
        snprintf(full, sizeof full, "%s%sdrape run was killed by signal %d",
                 msg, msg[0] ? "; " : "", WTERMSIG(wstatus));
    else if (code == 127 && !msg[0])
        snprintf(full, sizeof full, "could not start drape run (exit status 127)");
    else if (code != 0)
        snprintf(full, sizeof full, "%s%s(exit status %d)", msg, msg[0] ? " " : "", code);
    else if (!have_row && nf_row >= 0)
        snprintf(full, sizeof full, "cannot read the result of drape run: %d fields, its "
                 "header has %d (a comma in the fabric name?)", nf_row, nf_hdr);
    else if (!have_row)
        snprintf(full, sizeof full, "drape run printed no result row");
    else
        full[0] = 0;
    if (row_set(jb->row, COL_FILE, jb->fabric) != 0) goto nomem;
    if (row_set(jb->row, COL_ERROR, full) != 0) goto nomem;
    if (!have_row && row_set(jb->row, col_of("status"), "error") != 0) goto nomem;
    for (int i = 0; i < N_COLS; i++)
        if (!jb->row[i] && row_set(jb->row, i, "") != 0) goto nomem;
    rc = 0;
    goto out;
nomem:
    drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
out:
    drape_cli_csv_rec_free(&hdr);
    drape_cli_csv_rec_free(&r);
    drape_free(out);
    drape_free(etext);
    return rc;
}

static void progress(const batch *b, int last)
{
    if (!b->progress) return;
    fprintf(stderr, "\rdrape batch: %d/%d done, %d failed, %d running ", b->n_done, b->n,
            b->n_bad, b->n_running);
    if (last) fputc('\n', stderr);
}

static void kill_running(batch *b)
{
    for (int k = 0; k < b->n; k++)
        if (b->jobs[k].state == JOB_RUNNING) kill(-b->jobs[k].pid, SIGTERM);
}

/* ---- options --------------------------------------------------------------- */

static int usage_error(const char *fmt, const char *a)
{
    fputs("drape: batch: ", stderr);
    fprintf(stderr, fmt, a);
    fputs("\nTry `drape batch --help'.\n", stderr);
    return drape_error_exit_status(DRAPE_E_USAGE);
}

/* A quantity of dimension dim given to option opt: > 0 with positive,
 * >= 0 without (usage error otherwise). */
static int check_quantity(const char *opt, const char *text, drape_dim dim, int positive,
                          double *out)
{
    char why[256];
    double v;
    if (drape_units_parse(text, dim, &v, why, sizeof why) != 0) {
        fprintf(stderr, "drape: batch: %s: %s\nTry `drape batch --help'.\n", opt, why);
        return -1;
    }
    if (positive && !(v > 0)) {
        fprintf(stderr, "drape: batch: %s: must be positive, got %s\n", opt, text);
        return -1;
    }
    if (!(v >= 0)) {
        fprintf(stderr, "drape: batch: %s: must not be negative, got %s\n", opt, text);
        return -1;
    }
    if (out) *out = v;
    return 0;
}

/* Unique, file-name-safe name from the fabric file name. */
static void make_name(batch *b, int k)
{
    job *jb = &b->jobs[k];
    const char *base = strrchr(jb->fabric, '/');
    base = base ? base + 1 : jb->fabric;
    size_t n = strlen(base);
    if (n > 5 && strcmp(base + n - 5, ".yaml") == 0) n -= 5;
    else if (n > 4 && strcmp(base + n - 4, ".yml") == 0) n -= 4;
    if (n > BATCH_NAME_MAX) n = BATCH_NAME_MAX;
    char nm[BATCH_NAME_MAX + 1];
    for (size_t i = 0; i < n; i++) {
        char c = base[i];
        int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                 (c >= '0' && c <= '9') || c == '-' || c == '_' || (c == '.' && i > 0);
        nm[i] = ok ? c : '_';
    }
    nm[n] = 0;
    if (!n) snprintf(nm, sizeof nm, "fabric");
    snprintf(jb->name, sizeof jb->name, "%s", nm);
    for (int dup = 2;; dup++) {
        int clash = 0;
        for (int i = 0; i < k && !clash; i++) clash = strcmp(b->jobs[i].name, jb->name) == 0;
        if (!clash) break;
        snprintf(jb->name, sizeof jb->name, "%s-%d", nm, dup);
    }
}

int drape_cli_batch(int argc, char **argv)
{
    enum { O_OUT = 1000, O_RESUME, O_FRAMES, O_INTEGRATOR, O_RTOL, O_ATOL,
           O_SPACING, O_FORM, O_TMAX, O_MAXSTEPS, O_STRAIN, O_METHOD, O_LINSOL,
           O_MAXORDER, O_SPECIMENS, O_SEED, O_FALLTIME, O_FALLSTEP, O_FALLSWING, O_TERMS,
           O_FALLTOL, O_DAMPSHEAR, O_FALLFOLD, O_FALLRETRY };
    static const struct option opts[] = {
        {"jobs", required_argument, NULL, 'j'},
        {"out", required_argument, NULL, O_OUT},
        {"resume", no_argument, NULL, O_RESUME},
        {"frames", no_argument, NULL, O_FRAMES},
        {"integrator", required_argument, NULL, O_INTEGRATOR},
        {"rtol", required_argument, NULL, O_RTOL},
        {"atol", required_argument, NULL, O_ATOL},
        {"spacing", required_argument, NULL, O_SPACING},
        {"energy-form", required_argument, NULL, O_FORM},
        {"t-max", required_argument, NULL, O_TMAX},
        {"max-steps", required_argument, NULL, O_MAXSTEPS},
        {"strain-limit", required_argument, NULL, O_STRAIN},
        {"method", required_argument, NULL, O_METHOD},
        {"linear-solver", required_argument, NULL, O_LINSOL},
        {"max-order", required_argument, NULL, O_MAXORDER},
        {"specimens", required_argument, NULL, O_SPECIMENS},
        {"seed", required_argument, NULL, O_SEED},
        {"fall-time", required_argument, NULL, O_FALLTIME},
        {"fall-step", required_argument, NULL, O_FALLSTEP},
        {"fall-swing", required_argument, NULL, O_FALLSWING},
        {"fall-tol", required_argument, NULL, O_FALLTOL},
        {"fall-fold-time", required_argument, NULL, O_FALLFOLD},
        {"fall-retry", required_argument, NULL, O_FALLRETRY},
        {"damping-shear", required_argument, NULL, O_DAMPSHEAR},
        {"terms", required_argument, NULL, O_TERMS},
        {"quiet", no_argument, NULL, 'q'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0}};
    batch b;
    memset(&b, 0, sizeof b);
    b.dir = BATCH_DEFAULT_DIR;
    long jobs = 1;
    int resume = 0, quiet = 0, c;
    double spacing = 0.0; /* --spacing, m: the scene is checked with it */
    while ((c = getopt_long(argc, argv, "j:qh", opts, NULL)) != -1) {
        const char *name = NULL;
        switch (c) {
        case 'j': {
            char *end;
            errno = 0;
            jobs = strtol(optarg, &end, 10);
            if (errno || *end || end == optarg || jobs < 0 || jobs > BATCH_MAX_JOBS)
                return usage_error("-j: expected 0..1024, got `%s'", optarg);
            break;
        }
        case O_OUT: b.dir = optarg; break;
        case O_RESUME: resume = 1; break;
        case O_FRAMES: b.frames = 1; break;
        case O_INTEGRATOR: {
            int ok = 0;
            for (int i = 0; drape_integrator_names[i]; i++)
                ok |= strcmp(drape_integrator_names[i], optarg) == 0;
            if (!ok) return usage_error("--integrator: unknown integrator `%s'; see `drape run --help'", optarg);
            name = "--integrator";
            break;
        }
        case O_RTOL: {
            double v;
            char why[256];
            if (check_quantity("--rtol", optarg, DRAPE_DIM_NONE, 1, NULL)) return 2;
            if (drape_units_parse(optarg, DRAPE_DIM_NONE, &v, why, sizeof why) == 0 && !(v < 1))
                return usage_error("--rtol: must be in (0, 1), got %s", optarg);
            name = "--rtol";
            break;
        }
        case O_ATOL:
            if (check_quantity("--atol", optarg, DRAPE_DIM_LENGTH, 1, NULL)) return 2;
            name = "--atol";
            break;
        case O_SPACING:
            if (check_quantity("--spacing", optarg, DRAPE_DIM_LENGTH, 1, &spacing)) return 2;
            name = "--spacing";
            break;
        case O_FORM:
            if (strcmp(optarg, "consistent") && strcmp(optarg, "seed"))
                return usage_error("--energy-form: expected consistent or seed, got `%s'", optarg);
            name = "--energy-form";
            break;
        case O_TMAX:
            if (check_quantity("--t-max", optarg, DRAPE_DIM_TIME, 1, NULL)) return 2;
            name = "--t-max";
            break;
        case O_STRAIN:
            if (check_quantity("--strain-limit", optarg, DRAPE_DIM_NONE, 1, NULL)) return 2;
            name = "--strain-limit";
            break;
        case O_METHOD:
            if (strcmp(optarg, "dynamic") && strcmp(optarg, "static") && strcmp(optarg, "fall"))
                return usage_error("--method: expected fall, dynamic or static, got `%s'", optarg);
            name = "--method";
            break;
        case O_FALLTIME:
        case O_FALLSTEP:
            name = c == O_FALLTIME ? "--fall-time" : "--fall-step";
            if (check_quantity(name, optarg, DRAPE_DIM_TIME, 1, NULL)) return 2;
            break;
        case O_FALLTOL:
            name = "--fall-tol";
            if (check_quantity(name, optarg, DRAPE_DIM_LENGTH, 0, NULL)) return 2;
            break;
        case O_FALLFOLD:
        case O_FALLRETRY:
            name = c == O_FALLFOLD ? "--fall-fold-time" : "--fall-retry";
            if (check_quantity(name, optarg, DRAPE_DIM_TIME, 0, NULL)) return 2;
            break;
        case O_DAMPSHEAR:
            name = "--damping-shear";
            if (check_quantity(name, optarg, DRAPE_DIM_TIME, 0, NULL)) return 2;
            break;
        case O_FALLSWING: {
            char *end;
            double v = strtod(optarg, &end);
            if (*end || end == optarg || !(v >= 0.0 && v < 1.0))
                return usage_error("--fall-swing: expected a fraction in [0, 1), got `%s'", optarg);
            name = "--fall-swing";
            break;
        }
        case O_TERMS: {
            unsigned t;
            if (drape_scene_terms_parse(optarg, &t) != 0)
                return usage_error("--terms: expected a comma-separated list of stretch, "
                                   "bend, shear, gravity, bias, got `%s'", optarg);
            name = "--terms";
            break;
        }
        case O_SPECIMENS:
        case O_SEED: {
            char *end;
            errno = 0;
            long long v = strtoll(optarg, &end, 10);
            name = c == O_SPECIMENS ? "--specimens" : "--seed";
            if (errno || *end || end == optarg || v < (c == O_SPECIMENS ? 1 : 0) ||
                (c == O_SPECIMENS && v > DRAPE_SCENE_SPECIMENS_MAX) ||
                (unsigned long long)v > DRAPE_SCENE_SEED_MAX)
                return usage_error(c == O_SPECIMENS
                                       ? "--specimens: expected an integer from 1 to 1000, got `%s'"
                                       : "--seed: expected a non-negative integer up to "
                                         DRAPE_SCENE_SEED_MAX_TEXT ", got `%s'",
                                   optarg);
            break;
        }
        case O_LINSOL: {
            int ls;
            if (drape_linsol_parse(optarg, &ls) != 0)
                return usage_error("--linear-solver: expected auto, klu, schur or schur-direct, got `%s'", optarg);
            name = "--linear-solver";
            break;
        }
        case O_MAXSTEPS: {
            char *end;
            errno = 0;
            long v = strtol(optarg, &end, 10);
            if (errno || *end || end == optarg || v <= 0)
                return usage_error("--max-steps: expected a positive integer, got `%s'", optarg);
            name = "--max-steps";
            break;
        }
        case O_MAXORDER: {
            int v;
            if (drape_max_order_parse(optarg, &v) != 0)
                return usage_error("--max-order: expected an integer from 1 to 5, got `%s'", optarg);
            name = "--max-order";
            break;
        }
        case 'q': quiet = 1; break;
        case 'h': fputs(batch_usage, stdout); return 0;
        default:
            fputs("Try `drape batch --help'.\n", stderr);
            return drape_error_exit_status(DRAPE_E_USAGE);
        }
        if (name) {
            int dup = -1;
            for (int i = 0; i < b.npass; i += 2)
                if (strcmp(b.pass[i], name) == 0) dup = i;
            if (dup >= 0) b.pass[dup + 1] = optarg; /* last one wins, as in run */
            else {
                b.pass[b.npass++] = name;
                b.pass[b.npass++] = optarg;
            }
        }
    }
    if (argc - optind < 2)
        return usage_error("%s", argc - optind < 1 ? "missing SCENE.yaml and FABRIC.yaml..."
                                                    : "missing FABRIC.yaml...");
    if (jobs == 0) {
        long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
        jobs = ncpu > 0 ? (ncpu < BATCH_MAX_JOBS ? ncpu : BATCH_MAX_JOBS) : 1;
    }
    b.progress = !quiet && isatty(STDERR_FILENO);

    drape_error err;
    drape_error_clear(&err);
    /* the scene, and below the fabrics, may come from the data directories
     * (cli_data.h); each run resolves its --fabric the same way */
    char scene_buf[4096];
    if (drape_cli_data_find(argv[optind], scene_buf, sizeof scene_buf, &err) != 0) {
        drape_cli_print_error(&err);
        return drape_error_exit_status(err.kind);
    }
    b.scene = scene_buf;
    int status = 0;
    struct sigaction sa_old_int, sa_old_term;
    int handlers = 0;
    char sub[BATCH_PATH_MAX];

    /* the scene is the same for every run: check it once, here, before
     * anything is written (its own checks, and those that need a fabric,
     * with the first one that loads; a fabric's own errors belong in its
     * row) */
    drape_scene s;
    /* strict: the scene's own fabric must exist too (a scene file with a
     * dangling fabric is bad input for check, run and batch alike, issue 7) */
    if (drape_scene_load(b.scene, &s, &err, NULL, NULL) != 0) goto fail;
    if (spacing > 0.0) { /* as each run applies it */
        s.spacing = spacing;
        s.at_spacing.line = DRAPE_SCENE_POS_COMMAND_LINE;
    }
    for (int i = optind + 1; i < argc; i++) {
        drape_fabric fab;
        drape_error fe;
        drape_error_clear(&fe);
        char fab_buf[4096];
        if (drape_cli_data_find(argv[i], fab_buf, sizeof fab_buf, &fe) != 0 ||
            drape_fabric_load(fab_buf, &fab, &fe, NULL, NULL) != 0) continue;
        if (drape_scene_check_with_fabric(&s, &fab, &err) != 0) goto fail;
        break;
    }

    /* fabrics, in command-line order, without repeats */
    int nf = argc - optind - 1;
    if (!(b.jobs = drape_calloc((size_t)nf, sizeof *b.jobs))) goto nomem;
    for (int i = 0; i < nf; i++) {
        const char *f = argv[optind + 1 + i];
        int seen = 0;
        for (int k = 0; k < b.n && !seen; k++) seen = strcmp(b.jobs[k].fabric, f) == 0;
        if (seen) continue;
        if (f[0] == 0) {
            drape_error_set(&err, DRAPE_E_USAGE, NULL, 0, 0, NULL, "batch: empty fabric file name");
            goto fail;
        }
        b.jobs[b.n].fabric = f;
        make_name(&b, b.n);
        b.n++;
    }

    if (mkdir_p(b.dir, &err) != 0) goto fail;
    snprintf(sub, sizeof sub, "%s/logs", b.dir);
    if (mkdir_p(sub, &err) != 0) goto fail;
    if (b.frames) {
        snprintf(sub, sizeof sub, "%s/frames", b.dir);
        if (mkdir_p(sub, &err) != 0) goto fail;
    }
    if (snprintf(b.results, sizeof b.results, "%s/results.csv", b.dir) >= (int)sizeof b.results) {
        drape_error_set(&err, DRAPE_E_IO, b.dir, 0, 0, NULL, "path too long");
        goto fail;
    }
    for (int k = 0; k < b.n; k++) b.jobs[k].sum = file_sum(b.jobs[k].fabric);
    if (check_args_stamp(&b, resume, &err) != 0) goto fail;
    if (resume && (read_sums(&b, &err) != 0 || load_previous(&b, &err) != 0)) goto fail;
    for (int k = 0; k < b.n; k++)
        if (b.jobs[k].state == JOB_DONE) {
            b.n_done++;
            b.n_bad += !status_ok(row_status(b.jobs[k].row));
        }
    if (write_results(&b, &err) != 0) goto fail; /* also: DIR is writable */

    /* SIGINT: stop launching, let the running fabrics finish; a second
     * SIGINT or a SIGTERM: stop them.  No SA_RESTART, so waitpid returns
     * EINTR.  A SIGINT ignored at start (background job) stays ignored. */
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    got_sigint = got_sigterm = 0;
    sigaction(SIGINT, NULL, &sa_old_int);
    sigaction(SIGTERM, NULL, &sa_old_term);
    if (sa_old_int.sa_handler != SIG_IGN) sigaction(SIGINT, &sa, NULL);
    if (sa_old_term.sa_handler != SIG_IGN) sigaction(SIGTERM, &sa, NULL);
    handlers = 1;
    /* one BLAS thread per run: the batch itself is the parallelism */
    setenv("OPENBLAS_NUM_THREADS", "1", 0);
    /* the runs may get a SIGTERM twice: from whoever signalled the whole
     * process tree (systemd, Slurm) and from kill_running; the second must
     * not kill them (cli_run.c, catch_signals) */
    setenv("DRAPE_SIGNAL_FORWARDED", "1", 1);

    int next = 0, warned = 0, killed = 0;
    for (;;) {
        while (!got_sigint && !got_sigterm && b.n_running < jobs && next < b.n) {
            job *jb = &b.jobs[next++];
            if (jb->state != JOB_TODO) continue;
            drape_error e2;
            drape_error_clear(&e2);
            if (launch(&b, jb, &e2) != 0) { /* fork failed: an error row */
                char m[1024];
                row_free(jb->row);
                if (!(jb->row = row_new())) goto nomem;
                if (row_set(jb->row, COL_FILE, jb->fabric) ||
                    row_set(jb->row, col_of("status"), "error") ||
                    row_set(jb->row, COL_ERROR, drape_error_format(&e2, m, sizeof m)))
                    goto nomem;
                for (int i = 0; i < N_COLS; i++)
                    if (!jb->row[i] && row_set(jb->row, i, "")) goto nomem;
                jb->state = JOB_DONE;
                b.n_done++, b.n_bad++;
                if (write_results(&b, &err) != 0) break;
            }
        }
        if (err.kind != DRAPE_OK) break;
        if (b.n_running == 0) break;
        if ((got_sigint > 1 || got_sigterm) && !killed) {
            kill_running(&b);
            killed = 1;
        } else if (got_sigint && !warned) {
            if (b.progress) fputc('\n', stderr);
            fprintf(stderr, "drape: batch: interrupted: waiting for %d running "
                    "fabric%s (interrupt again to stop %s)\n", b.n_running,
                    b.n_running == 1 ? "" : "s", b.n_running == 1 ? "it" : "them");
            warned = 1;
        }
        progress(&b, 0);
        int ws;
        pid_t pid = waitpid(-1, &ws, 0);
        if (pid < 0) {
            if (errno == EINTR) continue;
            drape_error_set(&err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                            "batch: waitpid: %s", strerror(errno));
            break;
        }
        job *jb = NULL;
        for (int k = 0; k < b.n && !jb; k++)
            if (b.jobs[k].state == JOB_RUNNING && b.jobs[k].pid == pid) jb = &b.jobs[k];
        if (!jb) continue; /* not ours */
        b.n_running--;
        if (killed && WIFSIGNALED(ws)) { /* stopped by us: no row */
            jb->state = JOB_KILLED;
            continue;
        }
        if (collect(&b, jb, ws, &err) != 0) break;
        jb->state = JOB_DONE;
        b.n_done++;
        b.n_bad += !status_ok(row_status(jb->row));
        if (write_results(&b, &err) != 0) break;
    }
    progress(&b, 1);
    if (err.kind != DRAPE_OK) {
        /* the batch itself failed: stop the runs, report */
        kill_running(&b);
        while (b.n_running > 0 && waitpid(-1, NULL, 0) > 0) b.n_running--;
        goto fail;
    }
    if (got_sigterm) status = BATCH_EXIT_SIGTERM;
    else if (got_sigint) status = BATCH_EXIT_SIGINT;
    else if (b.n_bad > 0) status = BATCH_EXIT_SOME_FAILED;
    goto out;
nomem:
    drape_error_set(&err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
    kill_running(&b);
    while (b.n_running > 0 && waitpid(-1, NULL, 0) > 0) b.n_running--;
fail:
    drape_cli_print_error(&err);
    status = drape_error_exit_status(err.kind);
out:
    if (handlers) {
        sigaction(SIGINT, &sa_old_int, NULL);
        sigaction(SIGTERM, &sa_old_term, NULL);
    }
    for (int k = 0; k < b.n; k++) row_free(b.jobs[k].row);
    for (int k = 0; k < b.n_extra; k++) row_free(b.extra[k]);
    drape_free(b.extra);
    for (int k = 0; k < b.n_old; k++) drape_free(b.old_file[k]);
    drape_free(b.old_file);
    drape_free(b.old_sum);
    drape_free(b.jobs);
    return status;
}

/* cli_batch.c: `drape batch SCENE.yaml FABRIC.yaml... [options]`: run one
 * scene once per fabric, N at a time, each in a child process that
 * executes drape itself (`drape run --format csv --quiet --fabric F ...`),
 * and collect one row per fabric in DIR/results.csv: `fabric_file`, the
 * keys of `drape run` (its CSV header), and `error`.  The file is replaced
 * atomically after each finished fabric, so a batch that is killed keeps
 * every row it finished; --resume skips the fabrics whose row is done.
 * The rows, sums and stamp in DIR, and their reading by --resume:
 * cli_batch_record.c.  Contract, file layout and exit statuses:
 * docs/batch.md. */
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
#include <time.h>
#include <unistd.h>

#include <json-c/json.h>

#include "cli.h"
#include "cli_batch.h"
#include "cli_data.h"
#include "cli_io.h"
#include "cli_run.h"
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
    "                       from its checkpoint, an interrupted ensemble from its\n"
    "                       manifest, `drape run --resume`); a fabric\n"
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

static volatile sig_atomic_t got_sigint, got_sigterm;

static void on_signal(int sig)
{
    if (sig == SIGINT) got_sigint++;
    else got_sigterm = 1;
}

static int mkdir_p(const char *dir, drape_error *err)
{
    char p[BATCH_PATH_MAX];
    if (!*dir) return drape_error_set(err, DRAPE_E_IO, dir, 0, 0, NULL, "empty directory name");
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

/* ---- children ---------------------------------------------------------------- */

static void log_path(const batch *b, const job *jb, const char *ext, char *out, size_t n)
{
    snprintf(out, n, "%s/logs/%s.%s", b->dir, jb->name, ext);
}

/* 1 if the checkpoint at path is an interrupted run of fabric (another
 * fabric may have had this NAME before: a directory made before NAMEs were
 * recorded, or a hand-edited inputs.sum) made from the file's present text (`drape run --resume`
 * refuses a finished run and a changed file: the fabric then runs
 * afresh). */
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
    const drape_kv *st = drape_kv_find(c.stats, c.n_stats, "status");
    int same = kv && kv->text && stat(kv->text, &have) == 0 && have.st_dev == want.st_dev &&
               have.st_ino == want.st_ino && st && st->text &&
               strcmp(st->text, "interrupted") == 0;
    if (same) {
        char *now = drape_cli_read_file(buf, DRAPE_YDOC_MAX_BYTES, NULL, &e);
        same = now && c.fabric_yaml && strcmp(now, c.fabric_yaml) == 0;
        drape_free(now);
    }
    drape_h5_checkpoint_free(&c);
    return same;
}

/* 1 if DIR/ensemble.json (path) is the manifest of an unfinished
 * ensemble (running or interrupted) of this fabric (the same file, its
 * text's sum `sum`): an ensemble row's run, continued by `drape run
 * --resume DIR` like a single run's checkpoint; 0 otherwise (none,
 * unreadable, finished, another fabric's, a changed file's: the row then
 * runs again from the start). */
static int ensemble_is_for(const char *path, const char *fabric, unsigned long long sum)
{
    char buf[4096];
    struct stat want, have;
    drape_error e;
    drape_error_clear(&e);
    if (drape_cli_data_find(fabric, buf, sizeof buf, &e) != 0 || stat(buf, &want) != 0) return 0;
    struct json_object *o = drape_cli_read_json(path, 1 << 20, &e), *v;
    if (!o) return 0;
    int same = json_object_object_get_ex(o, "fabric", &v) &&
               json_object_is_type(v, json_type_string) &&
               stat(json_object_get_string(v), &have) == 0 && have.st_dev == want.st_dev &&
               have.st_ino == want.st_ino;
    char hex[24];
    snprintf(hex, sizeof hex, "%016llx", sum);
    same = same && json_object_object_get_ex(o, "fabric_sum", &v) &&
           json_object_is_type(v, json_type_string) && strcmp(json_object_get_string(v), hex) == 0;
    same = same && json_object_object_get_ex(o, "status", &v) &&
           json_object_is_type(v, json_type_string) &&
           (strcmp(json_object_get_string(v), "running") == 0 ||
            strcmp(json_object_get_string(v), "interrupted") == 0);
    json_object_put(o);
    return same;
}

/* 1 if the file at path was written since DIR/batch.args, which a batch
 * without --resume writes anew: a checkpoint of a run without a row may
 * be older, of a batch with other options (it continues with its own). */
static int made_since_stamp(const batch *b, const char *path)
{
    char stamp[BATCH_PATH_MAX + 16];
    struct stat s, f;
    snprintf(stamp, sizeof stamp, "%s/batch.args", b->dir);
    if (stat(stamp, &s) != 0 || stat(path, &f) != 0) return 0;
    return f.st_mtim.tv_sec > s.st_mtim.tv_sec ||
           (f.st_mtim.tv_sec == s.st_mtim.tv_sec && f.st_mtim.tv_nsec >= s.st_mtim.tv_nsec);
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
    char ck[BATCH_PATH_MAX + 16], man[BATCH_PATH_MAX + 16];
    snprintf(ck, sizeof ck, "%s/drape.h5", frames);
    snprintf(man, sizeof man, "%s/ensemble.json", frames);
    if (jb->cont && ((access(ck, F_OK) == 0 && (!jb->rowless || made_since_stamp(b, ck)) &&
                      checkpoint_is_for(ck, jb->fabric)) ||
                     (access(man, F_OK) == 0 && (!jb->rowless || made_since_stamp(b, man)) &&
                      ensemble_is_for(man, jb->fabric, jb->sum)))) {
        /* the options are stored in the checkpoint or the ensemble's
         * manifest (batch.args made sure they are this batch's) */
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

    drape_cli_batch_row_free(jb->row);
    if (!(jb->row = drape_cli_batch_row_new())) goto nomem;
    drape_error_clear(&ign);
    if (out && drape_cli_csv_next(out, olen, &p, &hdr, out_path, &ign) == 1 &&
        drape_cli_csv_next(out, olen, &p, &r, out_path, &ign) == 1) {
        nf_hdr = hdr.n, nf_row = r.n;
        have_row = r.n == hdr.n;
    }
    if (have_row) {
        for (int i = 0; i < hdr.n; i++) {
            int c = drape_cli_batch_col(hdr.field[i]);
            if (c > COL_FILE && c < COL_ERROR && drape_cli_batch_row_set(jb->row, c, r.field[i]) != 0)
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
    if (drape_cli_batch_row_set(jb->row, COL_FILE, jb->fabric) != 0) goto nomem;
    if (drape_cli_batch_row_set(jb->row, COL_ERROR, full) != 0) goto nomem;
    if (!have_row && drape_cli_batch_row_set(jb->row, drape_cli_batch_col("status"), "error") != 0) goto nomem;
    for (int i = 0; i < N_COLS; i++)
        if (!jb->row[i] && drape_cli_batch_row_set(jb->row, i, "") != 0) goto nomem;
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

/* The progress line's pace: when this batch's loop started, and how many
 * fabrics were done before it (a --resume). */
static struct timespec progress_t0;
static int progress_done0;

static void progress_start(const batch *b)
{
    clock_gettime(CLOCK_MONOTONIC, &progress_t0);
    progress_done0 = b->n_done;
}

static void progress(const batch *b, int last)
{
    if (!b->progress) return;
    int left = b->n - b->n_done, ran = b->n_done - progress_done0;
    fprintf(stderr, "\rdrape batch: %d/%d done, %d failed, %d running, %d left", b->n_done, b->n,
            b->n_bad, b->n_running, left);
    if (left > 0 && ran > 0) { /* what is left, at this batch's pace so far */
        struct timespec tn;
        clock_gettime(CLOCK_MONOTONIC, &tn);
        double el = (double)(tn.tv_sec - progress_t0.tv_sec) +
                    1e-9 * (double)(tn.tv_nsec - progress_t0.tv_nsec);
        fprintf(stderr, ", about %.0f s to go", el * left / ran);
    }
    fputs(last ? "\n" : " ", stderr);
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

/* The file-name-safe stem of a fabric file name (NAME before -2, -3). */
static void base_name(const char *fabric, char nm[BATCH_NAME_MAX + 1])
{
    const char *base = strrchr(fabric, '/');
    base = base ? base + 1 : fabric;
    size_t n = strlen(base);
    if (n > 5 && strcmp(base + n - 5, ".yaml") == 0) n -= 5;
    else if (n > 4 && strcmp(base + n - 4, ".yml") == 0) n -= 4;
    if (n > BATCH_NAME_MAX) n = BATCH_NAME_MAX;
    for (size_t i = 0; i < n; i++) {
        char c = base[i];
        int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                 (c >= '0' && c <= '9') || c == '-' || c == '_' || (c == '.' && i > 0);
        nm[i] = ok ? c : '_';
    }
    nm[n] = 0;
    if (!n) snprintf(nm, BATCH_NAME_MAX + 1, "fabric");
}

/* 1 if name is job k's to take: no other named job has it (named[i], or
 * every job before k when named is NULL) and, on --resume, no row of
 * another fabric file was made under it (inputs.sum). */
static int name_free(const batch *b, int k, const unsigned char *named, const char *name)
{
    for (int i = 0; i < b->n; i++)
        if (i != k && (named ? named[i] : i < k) && strcmp(b->jobs[i].name, name) == 0) return 0;
    for (int i = 0; i < b->n_old; i++)
        if (b->old_name[i] && strcmp(b->old_name[i], name) == 0 &&
            strcmp(b->old_file[i], b->jobs[k].fabric) != 0)
            return 0;
    return 1;
}

/* Job k's NAME: its base name, then -2, -3, ... until free. */
static void make_name(batch *b, int k, const unsigned char *named)
{
    job *jb = &b->jobs[k];
    char nm[BATCH_NAME_MAX + 1];
    base_name(jb->fabric, nm);
    snprintf(jb->name, sizeof jb->name, "%s", nm);
    for (int dup = 2; !name_free(b, k, named, jb->name); dup++)
        snprintf(jb->name, sizeof jb->name, "%s-%d", nm, dup);
}

/* On --resume (inputs.sum read): a fabric whose row was made under a NAME
 * keeps it, so that its logs and frames are its own whatever the order of
 * the new command line; the others take theirs around every NAME kept or
 * recorded.  Before, NAMEs followed the command line's order alone, and a
 * new d2/a.yaml listed before a done d1/a.yaml took `a` and wrote over
 * d1/a.yaml's frames/a and logs/a.*.  Returns -1 out of memory. */
static int keep_names(batch *b)
{
    unsigned char *named = drape_calloc(b->n > 0 ? (size_t)b->n : 1, 1);
    if (!named) return -1;
    for (int k = 0; k < b->n; k++) {
        /* a NAME as base_name makes them (inputs.sum may be edited) */
        const char *old = drape_cli_batch_old_name(b, b->jobs[k].fabric);
        char stem[BATCH_NAME_MAX + 1];
        if (!old || strlen(old) > BATCH_NAME_MAX) continue;
        base_name(old, stem);
        if (strcmp(stem, old) != 0 || !name_free(b, k, named, old)) continue;
        snprintf(b->jobs[k].name, sizeof b->jobs[k].name, "%s", old);
        named[k] = 1;
    }
    for (int k = 0; k < b->n; k++)
        if (!named[k]) {
            make_name(b, k, named);
            named[k] = 1;
        }
    drape_free(named);
    return 0;
}

int drape_cli_batch(int argc, char **argv)
{
    /* the options passed on to every run, checked as run checks them
     * (drape_cli_run_option) */
#define BATCH_PASSED(X)                                                                  \
    X("integrator") X("rtol") X("atol") X("spacing") X("energy-form") X("t-max")         \
    X("max-steps") X("strain-limit") X("method") X("linear-solver") X("max-order")       \
    X("specimens") X("seed") X("fall-time") X("fall-step") X("fall-swing") X("fall-tol") \
    X("fall-fold-time") X("fall-retry") X("damping-shear") X("terms")
#define AS_OPTION(n) {n, required_argument, NULL, O_PASS},
#define AS_NAME(n) "--" n,
    enum { O_OUT = 1000, O_RESUME, O_FRAMES, O_PASS, N_OWN = 4 };
    static const struct option opts[] = {
        {"jobs", required_argument, NULL, 'j'},
        {"out", required_argument, NULL, O_OUT},
        {"resume", no_argument, NULL, O_RESUME},
        {"frames", no_argument, NULL, O_FRAMES},
        /* from here on (N_OWN) in the order of passed[] */
        BATCH_PASSED(AS_OPTION)
        {"quiet", no_argument, NULL, 'q'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0}};
    static const char *const passed[] = {BATCH_PASSED(AS_NAME)};
#undef AS_OPTION
#undef AS_NAME
#undef BATCH_PASSED
    batch b;
    memset(&b, 0, sizeof b);
    b.dir = BATCH_DEFAULT_DIR;
    long jobs = 1;
    int resume = 0, quiet = 0, c, li;
    run_args ra; /* the passed-on options' values: the scene is checked with --spacing */
    memset(&ra, 0, sizeof ra);
    if ((c = drape_cli_args_unambiguous(argc, argv, "j:qh", opts, "drape batch")) != 0) return c;
    while ((c = getopt_long(argc, argv, "j:qh", opts, &li)) != -1) {
        switch (c) {
        case 'j': {
            char *end;
            errno = 0;
            jobs = strtol(optarg, &end, 10);
            if (errno || *end || end == optarg || jobs < 0 || jobs > BATCH_MAX_JOBS)
                return usage_error("-j: expected 0..1024, got `%s'", optarg);
            break;
        }
        case O_OUT:
            if (!*optarg) return usage_error("%s", "--out: expected a directory, got an empty name");
            b.dir = optarg;
            break;
        case O_RESUME: resume = 1; break;
        case O_FRAMES: b.frames = 1; break;
        case O_PASS: {
            const char *name = passed[li - N_OWN];
            char why[512];
            if (drape_cli_run_option(&ra, name, optarg, why, sizeof why) != 0)
                return usage_error("%s", why);
            if (ra.method == DRAPE_METHOD_ANIMATE)
                return usage_error("%s", "--method animate: not in a batch (it writes a "
                                         "renderer's frames: `drape run --method animate "
                                         "--out DIR`)");
            int dup = -1;
            for (int i = 0; i < b.npass; i += 2)
                if (b.pass[i] == name) dup = i;
            if (dup >= 0) b.pass[dup + 1] = optarg; /* last one wins, as in run */
            else {
                b.pass[b.npass++] = name;
                b.pass[b.npass++] = optarg;
            }
            break;
        }
        case 'q': quiet = 1; break;
        case 'h': fputs(batch_usage, stdout); return 0;
        default:
            fputs("Try `drape batch --help'.\n", stderr);
            return drape_error_exit_status(DRAPE_E_USAGE);
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
     * dangling fabric is bad input for check, run and batch alike) */
    if (drape_scene_load(b.scene, &s, &err, NULL, NULL) != 0) goto fail;
    if (ra.spacing > 0.0) { /* as each run applies it */
        s.spacing = ra.spacing;
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
        make_name(&b, b.n, NULL);
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
    for (int k = 0; k < b.n; k++) b.jobs[k].sum = drape_cli_batch_file_sum(b.jobs[k].fabric);
    if (drape_cli_batch_check_stamp(&b, resume, &err) != 0) goto fail;
    if (resume && drape_cli_batch_read_sums(&b, &err) != 0) goto fail;
    if (resume && keep_names(&b) != 0) goto nomem;
    if (resume && drape_cli_batch_load_previous(&b, &err) != 0) goto fail;
    /* a fabric without a row whose run was stopped when the batch was
     * killed outright (its row only in logs/NAME.csv) continues from its
     * checkpoint or manifest, as an interrupted row's run does, if they
     * are of this fabric and its present text and were written since
     * batch.args, by a run of this batch's options (launch) */
    for (int k = 0; k < b.n; k++)
        if (resume && b.frames && !b.jobs[k].row) b.jobs[k].cont = b.jobs[k].rowless = 1;
    for (int k = 0; k < b.n; k++)
        if (b.jobs[k].state == JOB_DONE) {
            b.n_done++;
            b.n_bad += !drape_cli_batch_status_ok(drape_cli_batch_row_status(b.jobs[k].row));
        }
    if (drape_cli_batch_write_results(&b, &err) != 0) goto fail; /* also: DIR is writable */

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
    progress_start(&b);
    for (;;) {
        while (!got_sigint && !got_sigterm && b.n_running < jobs && next < b.n) {
            job *jb = &b.jobs[next++];
            if (jb->state != JOB_TODO) continue;
            drape_error e2;
            drape_error_clear(&e2);
            if (launch(&b, jb, &e2) != 0) { /* fork failed: an error row */
                char m[1024];
                drape_cli_batch_row_free(jb->row);
                if (!(jb->row = drape_cli_batch_row_new())) goto nomem;
                if (drape_cli_batch_row_set(jb->row, COL_FILE, jb->fabric) ||
                    drape_cli_batch_row_set(jb->row, drape_cli_batch_col("status"), "error") ||
                    drape_cli_batch_row_set(jb->row, COL_ERROR, drape_error_format(&e2, m, sizeof m)))
                    goto nomem;
                for (int i = 0; i < N_COLS; i++)
                    if (!jb->row[i] && drape_cli_batch_row_set(jb->row, i, "")) goto nomem;
                jb->state = JOB_DONE;
                b.n_done++, b.n_bad++;
                if (drape_cli_batch_write_results(&b, &err) != 0) break;
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
        b.n_bad += !drape_cli_batch_status_ok(drape_cli_batch_row_status(jb->row));
        if (drape_cli_batch_write_results(&b, &err) != 0) break;
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
    drape_cli_batch_free_record(&b);
    drape_free(b.jobs);
    return status;
}

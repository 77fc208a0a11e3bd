/* cli_batch_record.c: the record a `drape batch` keeps in its directory:
 * one row per fabric in DIR/results.csv, the sums of the fabric files the
 * rows were made from in DIR/inputs.sum, and the scene and options in
 * DIR/batch.args; and what --resume reads back from them (which rows are
 * done, which fabric files changed, whether the scene and options are the
 * same).  The processes that make the rows: cli_batch.c.  Contract:
 * docs/batch.md. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "cli_batch.h"
#include "cli_data.h"
#include "cli_io.h"
#include "cli_run.h"
#include "drape/alloc.h"
#include "drape/yamldoc.h"

/* ---- rows ------------------------------------------------------------------ */

int drape_cli_batch_col(const char *key)
{
    if (strcmp(key, "fabric_file") == 0) return COL_FILE;
    if (strcmp(key, "error") == 0) return COL_ERROR;
    for (int i = 0; i < N_RUN_KEYS; i++)
        if (strcmp(key, run_keys[i]) == 0) return i + 1;
    return -1;
}

void drape_cli_batch_row_free(char **row)
{
    if (!row) return;
    for (int i = 0; i < N_COLS; i++) drape_free(row[i]);
    drape_free(row);
}

char **drape_cli_batch_row_new(void)
{
    return drape_calloc(N_COLS, sizeof(char *));
}

/* Set a field (copy); line breaks become spaces so that every row is one
 * line (scripts/slurm/submit.sh merges row files line by line). */
int drape_cli_batch_row_set(char **row, int col, const char *s)
{
    char *t = drape_strdup(s ? s : "");
    if (!t) return -1;
    for (char *c = t; *c; c++)
        if (*c == '\n' || *c == '\r') *c = ' ';
    drape_free(row[col]);
    row[col] = t;
    return 0;
}

const char *drape_cli_batch_row_status(char **row)
{
    const char *s = row ? row[drape_cli_batch_col("status")] : NULL;
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

int drape_cli_batch_status_ok(const char *s)
{
    return strcmp(s, "equilibrium") == 0 || strcmp(s, "t_max") == 0;
}

/* ---- files ----------------------------------------------------------------- */

/* FNV-1a (64 bits) of a file's bytes: whether an input changed since a
 * row was made, not a digest against tampering.  0 if it cannot be read
 * (the run then reports the error itself). */
unsigned long long drape_cli_batch_file_sum(const char *given)
{
    char path[4096];
    drape_error e;
    drape_error_clear(&e);
    if (drape_cli_data_find(given, path, sizeof path, &e) != 0) return 0;
    unsigned long long h = 0;
    if (drape_cli_file_sum(path, DRAPE_YDOC_MAX_BYTES, &h, &e) != 0) return 0;
    return h;
}

/* the sum recorded for a row's fabric_file (0: none recorded) */
static unsigned long long old_sum_of(const batch *b, const char *field)
{
    for (int i = 0; i < b->n_old; i++)
        if (strcmp(b->old_file[i], field) == 0) return b->old_sum[i];
    return 0;
}

const char *drape_cli_batch_old_name(const batch *b, const char *fabric_file)
{
    for (int i = 0; i < b->n_old; i++)
        if (strcmp(b->old_file[i], fabric_file) == 0) return b->old_name[i];
    return NULL;
}

/* DIR/inputs.sum: "SUM:NAME<TAB>fabric_file" for every row, so that
 * --resume can tell a fabric file edited since its row was made, and can
 * give the fabric the NAME (logs/NAME.*, frames/NAME/) its row was made
 * under.  Lines of the form "SUM<TAB>fabric_file" (no NAME) are read too;
 * a reader that stops at the colon still gets the SUM. */
static int write_sums(const batch *b, drape_error *err)
{
    char path[BATCH_PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/inputs.sum", b->dir);
    drape_cli_afile a;
    if (drape_cli_afile_open(&a, path, err) != 0) return -1;
    for (int k = 0; k < b->n + b->n_extra; k++) {
        char **row = k < b->n ? b->jobs[k].row : b->extra[k - b->n];
        if (!row) continue;
        /* a row not (yet) made by this batch's run of the fabric (an old
         * error, interrupted or changed fabric's row kept until its new
         * run replaces it) keeps the sum of the text it was made from:
         * with the new sum, a --resume after this one was stopped would
         * take an edited fabric's old row as done */
        const job *jb = k < b->n ? &b->jobs[k] : NULL;
        unsigned long long h = jb && jb->state == JOB_DONE ? jb->sum
                                                          : old_sum_of(b, row[COL_FILE]);
        const char *nm = jb ? jb->name : drape_cli_batch_old_name(b, row[COL_FILE]);
        if (h && nm) fprintf(a.f, "%016llx:%s\t%s\n", h, nm, row[COL_FILE]);
        else if (h) fprintf(a.f, "%016llx\t%s\n", h, row[COL_FILE]);
    }
    return drape_cli_afile_commit(&a, err);
}

int drape_cli_batch_read_sums(batch *b, drape_error *err)
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
        if (nf) b->old_file = nf;
        unsigned long long *ns = nf ? drape_realloc(b->old_sum, (size_t)(b->n_old + 1) * sizeof *ns)
                                    : NULL;
        if (ns) b->old_sum = ns;
        char **nn = ns ? drape_realloc(b->old_name, (size_t)(b->n_old + 1) * sizeof *nn) : NULL;
        if (nn) b->old_name = nn;
        char *colon = strchr(line, ':');
        if (!nn || !(b->old_file[b->n_old] = drape_strdup(tab + 1))) {
            rc = drape_error_set(err, DRAPE_E_NOMEM, path, 0, 0, NULL, "out of memory");
            break;
        }
        b->old_name[b->n_old] = NULL;
        if (colon && colon[1] && !(b->old_name[b->n_old] = drape_strdup(colon + 1))) {
            drape_free(b->old_file[b->n_old]);
            rc = drape_error_set(err, DRAPE_E_NOMEM, path, 0, 0, NULL, "out of memory");
            break;
        }
        b->old_sum[b->n_old++] = strtoull(line, NULL, 16);
    }
    drape_free(text);
    return rc;
}

int drape_cli_batch_write_results(const batch *b, drape_error *err)
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

/* Lines x and y of batch.args say the same: the same text, or the same
 * option ("--spacing 5mm", "--spacing 0.5cm") with values that parse to
 * the same value (drape_cli_run_option_same). */
static int same_line(const char *x, const char *y)
{
    if (strcmp(x, y) == 0) return 1;
    const char *sx = strchr(x, ' '), *sy = strchr(y, ' ');
    if (strncmp(x, "--", 2) != 0 || !sx || !sy || sx - x != sy - y ||
        strncmp(x, y, (size_t)(sx - x)) != 0 || (size_t)(sx - x) >= 64)
        return 0;
    char name[64];
    memcpy(name, x, (size_t)(sx - x));
    name[sx - x] = 0;
    return drape_cli_run_option_same(name, sx + 1, sy + 1);
}

/* 1 if texts x and y hold the same lines (same_line) in any order, leaving
 * out those that start with skip (NULL: none). */
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
    }
    same = same && n[0] == n[1];
    /* each line of x matches one of y not matched before */
    char used[MAXL] = {0};
    for (int i = 0; same && i < n[0]; i++) {
        int hit = 0;
        for (int j = 0; j < n[1] && !hit; j++)
            if (!used[j] && same_line(l[0][i], l[1][j])) used[j] = hit = 1;
        same = hit;
    }
    drape_free(t[0]);
    drape_free(t[1]);
    return same;
}

/* DIR/batch.args records the scene and the options passed to the runs;
 * --resume refuses a directory made with other ones. */
int drape_cli_batch_check_stamp(const batch *b, int resume, drape_error *err)
{
    char path[BATCH_PATH_MAX], *want = NULL, *have = NULL;
    size_t wn = 0;
    int rc = -1;
    FILE *m = open_memstream(&want, &wn);
    if (!m) return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
    fprintf(m, "scene %s\n", b->scene);
    for (int i = 0; i + 1 < b->npass; i += 2) fprintf(m, "%s %s\n", b->pass[i], b->pass[i + 1]);
    if (b->frames) fputs("--frames\n", m);
    fprintf(m, "scene-sum %016llx\n", drape_cli_batch_file_sum(b->scene));
    if (fclose(m) != 0) {
        free(want);
        return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
    }
    snprintf(path, sizeof path, "%s/batch.args", b->dir);
    if (resume && access(path, F_OK) == 0) {
        if (!(have = drape_cli_read_file(path, 1 << 20, NULL, err))) goto out;
        /* the same lines in any order: `--seed 3 --spacing 5mm` is the
         * batch of `--spacing 5mm --seed 3` (each option occurs once), and
         * of `--spacing 0.5cm --seed 3` (values compared as parsed) */
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
        drape_error_set(err, DRAPE_E_USAGE, path, 0, 0, NULL,
                        "--resume: this batch was started with another scene "
                        "or other options; use the same ones (listed in this "
                        "file), or another --out");
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
int drape_cli_batch_load_previous(batch *b, drape_error *err)
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
        map[i] = drape_cli_batch_col(hdr.field[i]);
        have_status |= map[i] == drape_cli_batch_col("status");
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
        if (!(row = drape_cli_batch_row_new())) goto nomem;
        for (int i = 0; i < r.n; i++)
            if (map[i] >= 0 && drape_cli_batch_row_set(row, map[i], r.field[i]) != 0) goto nomem;
        for (int i = 0; i < N_COLS; i++)
            if (!row[i] && drape_cli_batch_row_set(row, i, "") != 0) goto nomem;
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
            if (b->frames && !changed && strcmp(drape_cli_batch_row_status(row), "interrupted") == 0) jb->cont = 1;
            if (!jb->row || (jb->state != JOB_DONE && status_done(drape_cli_batch_row_status(row)))) {
                /* a done row: kept; another (error, interrupted) or one of
                 * a changed file: kept in results.csv until the fabric's
                 * new run replaces it */
                drape_cli_batch_row_free(jb->row);
                jb->row = row;
                if (status_done(drape_cli_batch_row_status(row)) && !changed) {
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
        drape_cli_batch_row_free(row);
        row = NULL;
    }
    if (got < 0) goto out;
    rc = 0;
    goto out;
nomem:
    drape_error_set(err, DRAPE_E_NOMEM, b->results, 0, 0, NULL, "out of memory");
out:
    drape_cli_batch_row_free(row);
    drape_cli_csv_rec_free(&r);
    drape_cli_csv_rec_free(&hdr);
    drape_free(map);
    drape_free(text);
    return rc;
}

void drape_cli_batch_free_record(batch *b)
{
    for (int k = 0; k < b->n; k++) drape_cli_batch_row_free(b->jobs[k].row);
    for (int k = 0; k < b->n_extra; k++) drape_cli_batch_row_free(b->extra[k]);
    drape_free(b->extra);
    for (int k = 0; k < b->n_old; k++) {
        drape_free(b->old_file[k]);
        drape_free(b->old_name[k]);
    }
    drape_free(b->old_file);
    drape_free(b->old_name);
    drape_free(b->old_sum);
}

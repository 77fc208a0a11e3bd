/* cli_specimens.h: an ensemble's record in its --out DIR, between the
 * driver that runs the specimens (cli_specimens.c) and the files that let
 * `drape run --resume DIR` continue it (cli_specimens_record.c):
 *
 *   DIR/ensemble.json            the manifest: what the ensemble is (scene
 *                                and fabric with checksums of their texts,
 *                                the options as given, N, the first seed),
 *                                its id, and how far it got (status, parts,
 *                                cpu_s and wall_s of its ended parts)
 *   DIR/specimen-NNN/result.txt  a finished specimen's result: the lines
 *                                its process sent (cli_result.h's line
 *                                format and its @shadow line) after a few
 *                                @ lines of its own (ensemble id, seed,
 *                                exit status, CPU time)
 *
 * Both are written to a temporary name and renamed.  Contract:
 * docs/ensemble.md ("Resuming an ensemble"), docs/outputs.md.  Private to
 * src/cli_*.c. */
#ifndef DRAPE_CLI_SPECIMENS_H
#define DRAPE_CLI_SPECIMENS_H

#include <stddef.h>

#include "cli_run.h"
#include "drape/error.h"

#define ENS_FORMAT 1              /* the manifest's drape_ensemble */
#define ENS_RESULT "result.txt"   /* in DIR/specimen-NNN */

struct json_object;

/* The manifest, in memory. */
typedef struct ens_record {
    struct json_object *root; /* the manifest's JSON object (owned) */
    char dir[4096];           /* DIR */
    char path[4200];          /* DIR/ensemble.json */
    char id[64];              /* the ensemble's id */
    int n;                    /* specimens */
    unsigned long seed0;      /* the first one's seed */
    int resuming;             /* read back by --resume */
    char status[16];          /* as stored: running, interrupted, or the
                                 ensemble's status at its end */
    double cpu_s, wall_s;     /* of the parts that ended before */
} ens_record;

/* A new ensemble's manifest (not written yet): a's scene and fabric
 * (fabric_path: the one run, from --fabric or the scene; made absolute)
 * with their checksums, a's options as given, n, seed0, a new id.
 * 0, or -1 and err. */
int drape_cli_ens_record_new(ens_record *m, const char *dir, const run_args *a,
                             const char *fabric_path, int n, unsigned long seed0,
                             drape_error *err);
/* Write DIR/ensemble.json (atomically).  0, or -1 and err. */
int drape_cli_ens_record_write(const ens_record *m, drape_error *err);
/* The end of one part of the ensemble (finished or interrupted): its
 * status and the time of every part so far, written. */
int drape_cli_ens_record_end(ens_record *m, const char *status, double cpu_s, double wall_s,
                             drape_error *err);
void drape_cli_ens_record_free(ens_record *m);

/* Store specimen k's (0-based) result: the text its process sent (len
 * bytes), its exit status and CPU time, in DIR/specimen-NNN/result.txt.
 * 0, or -1 and err. */
int drape_cli_ens_result_store(const ens_record *m, int k, int exit_status, double cpu_s,
                               const char *text, size_t len, drape_error *err);
/* The stored text of specimen k (caller frees with drape_free), its exit
 * status and CPU time; NULL when there is none of this ensemble (none,
 * another ensemble's, another seed, unreadable).  A warning on stderr
 * names the file when it is this ensemble's but not usable: @seed not
 * the manifest's seed + k (both seeds given), @exit or @cpu_s damaged. */
char *drape_cli_ens_result_load(const ens_record *m, int k, int *exit_status, double *cpu_s);
/* Remove specimen k's stored result (a new ensemble in DIR). */
void drape_cli_ens_result_remove(const ens_record *m, int k);
/* 1 if DIR/specimen-NNN/drape.h5 is the checkpoint of this ensemble's
 * specimen k, interrupted (*cpu_s: its CPU time so far, 0 if not
 * stored); 0 otherwise, with a warning naming the file when it is this
 * ensemble's but of another seed or its cpu_s is not a CPU time (text,
 * inf, nan or negative): the specimen then runs from the start. */
int drape_cli_ens_checkpoint(const ens_record *m, int k, double *cpu_s);

/* The ensemble of a (cli_specimens.c).  m: its manifest when resumed
 * (m->resuming), else NULL (one is made when a->out_dir is set).
 * Returns the exit status. */
int drape_cli_specimens_drive(const run_args *a, ens_record *m);

#endif /* DRAPE_CLI_SPECIMENS_H */

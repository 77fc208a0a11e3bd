/* cli.h: private interface between the command-line files (main.c,
 * cli_*.c).  Only these files print or exit. */
#ifndef DRAPE_CLI_H
#define DRAPE_CLI_H

#include <stdio.h>

#include "drape/error.h"

#define DRAPE_VERSION "0.1.0"

/* Print "drape: <formatted error>" to stderr (cli_io.c). */
void drape_cli_print_error(const drape_error *e);
/* A prefix for the messages of this process, e.g. "specimen 3 (seed 4): "
 * in an ensemble's child; NULL or "" for none. */
void drape_cli_set_error_context(const char *ctx);
/* Warning callback for loaders: "drape: FILE:LINE:COL: key: warning: ...". */
void drape_cli_warn(void *ctx, const drape_error *w);

/* The keys of `drape run`'s result, in output order, as CSV column names
 * (JSON nests energy_J_*: energy_J {kinetic, ...}); NULL-terminated.  The
 * contract of issue 3 plus additions; batch uses it for results.csv. */
extern const char *const drape_cli_run_keys[];
int drape_cli_run_nkeys(void);

/* Subcommands: argc/argv start at the subcommand name; return the exit
 * status. */
int drape_cli_check(int argc, char **argv);
int drape_cli_run(int argc, char **argv);
int drape_cli_batch(int argc, char **argv);  /* cli_batch.c, docs/batch.md */
int drape_cli_import(int argc, char **argv); /* cli_import.c, docs/batch.md */
int drape_cli_bench(int argc, char **argv);  /* cli_bench.c, docs/performance.md */
int drape_cli_compare(int argc, char **argv); /* cli_compare.c, docs/ensemble.md */

#endif

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

struct option; /* <getopt.h> */
/* Before getopt_long(argc, argv, shortopts, opts, ...): a long option
 * abbreviated to a prefix of more than one of opts (`--fall-t`: fall-time,
 * fall-tol) is a bad command line.  getopt_long itself takes the first
 * match where the candidates share their has_arg, flag and val, as the
 * options that set a run's value do.  Prints "CMD: option `--fall-t' is
 * ambiguous; possibilities: --fall-time, --fall-tol" and "Try `CMD
 * --help'." (cmd: "drape run") and returns the exit status of a bad
 * command line; 0 when every option is an exact name, a unique prefix, or
 * unknown (getopt_long says so).  Option values are skipped as getopt_long
 * takes them (`--terms --x`: --x is the value); scanning stops at `--`,
 * and with a leading '+' in shortopts at the first non-option. */
int drape_cli_args_unambiguous(int argc, char *const argv[], const char *shortopts,
                               const struct option *opts, const char *cmd);

/* The keys of `drape run`'s result, in output order, as CSV column names
 * (JSON nests energy_J_*: energy_J {kinetic, ...}); NULL-terminated.  The
 * contract (keys are added, never renamed); batch uses it for results.csv. */
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

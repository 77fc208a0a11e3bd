/* cli_result.h: the result of `drape run` as a list of named fields, and
 * its three forms: JSON on stdout (built with json-c), a CSV header and
 * row (`--format csv`, batch's results.csv), and the line format an
 * ensemble's child process sends its parent (cli_specimens.c).
 * Private to src/cli_*.c.
 *
 * Keys are those of drape_cli_run_keys, in that order.  A key
 * "energy_J.kinetic" nests in JSON (energy_J: {kinetic: ...}) and is
 * flattened with '_' in CSV.  Two keys are structured: nodes_hist (JSON
 * object {"3": 2, "4": 6}; CSV "3:2;4:6") and specimens (JSON array of
 * one object per specimen; CSV the count).
 */
#ifndef DRAPE_CLI_RESULT_H
#define DRAPE_CLI_RESULT_H

#include <stdio.h>

#include "drape/ensemble.h"

#define DRAPE_CLI_RESULT_MAX 96
#define DRAPE_CLI_TEXT_MAX 128

typedef enum drape_cli_ftype {
    DRAPE_CLI_F_NUM,       /* double, NaN = null */
    DRAPE_CLI_F_INT,       /* integer in a double; NaN or < 0 = null */
    DRAPE_CLI_F_STR,       /* text (copied) */
    DRAPE_CLI_F_HIST,      /* the node histogram of the result */
    DRAPE_CLI_F_SPECIMENS  /* the specimens of the result */
} drape_cli_ftype;

/* One specimen's line in the `specimens` array. */
typedef struct drape_cli_specimen {
    unsigned long seed;
    int seed_unknown;  /* seed printed as null (a run resumed from a
                          checkpoint that did not store it) */
    char status[16];   /* equilibrium, t_max, failed, interrupted */
    double dc;         /* NaN if none */
    int nodes;         /* -1 if none */
    double r_min_m, r_max_m, cpu_s;
} drape_cli_specimen;

typedef struct drape_cli_field {
    char key[48];                    /* "energy_J.kinetic" nests in JSON */
    drape_cli_ftype type;
    double value;
    char text[DRAPE_CLI_TEXT_MAX];
    int is_null_text;                /* STR: print null */
} drape_cli_field;

typedef struct drape_cli_result {
    drape_cli_field f[DRAPE_CLI_RESULT_MAX];
    int n;
    int hist[DRAPE_ENSEMBLE_MAX_NODES + 1];   /* for DRAPE_CLI_F_HIST */
    drape_cli_specimen *spec;                /* for DRAPE_CLI_F_SPECIMENS (borrowed) */
    int n_spec;
} drape_cli_result;

void drape_cli_result_num(drape_cli_result *r, const char *key, double v);
void drape_cli_result_int(drape_cli_result *r, const char *key, double v);
/* s NULL prints null */
void drape_cli_result_str(drape_cli_result *r, const char *key, const char *s);
void drape_cli_result_hist(drape_cli_result *r, const char *key);
void drape_cli_result_specimens(drape_cli_result *r, const char *key);

/* The field named key, or NULL. */
const drape_cli_field *drape_cli_result_find(const drape_cli_result *r, const char *key);
/* Its number (NaN when absent, null or text). */
double drape_cli_result_get(const drape_cli_result *r, const char *key);

/* 1 if the fields are exactly drape_cli_run_keys, in order. */
int drape_cli_result_check_keys(const drape_cli_result *r);

/* JSON (one line) and CSV (header and row).  Return 0, or -1 when the
 * JSON cannot be built (out of memory). */
int drape_cli_result_print_json(FILE *out, const drape_cli_result *r);
void drape_cli_result_print_csv(FILE *out, const drape_cli_result *r);
/* A few lines for a person (cli_summary.c): `--format text`. */
void drape_cli_result_print_text(FILE *out, const drape_cli_result *r);

/* The child-to-parent line format: "key\ttype\tvalue\n" per field (numbers
 * with %.17g, so nothing is lost), structured fields left out.
 * drape_cli_result_read parses it into r (keys matched against
 * drape_cli_run_keys); returns 0, or -1 on a malformed line. */
void drape_cli_result_write(FILE *out, const drape_cli_result *r);
int drape_cli_result_read(const char *text, drape_cli_result *r);

/* One number of the line format, of result.txt's @ lines and of the
 * @shadow line: the token at s (up to a blank, tab, newline or the end)
 * read whole with drape_units_strtod.  Taken: a finite double (a denormal
 * too: %.17g writes it exactly) and printf's own text of a non-finite
 * value ("nan", "-nan", "inf", "-inf": null).  Refused: anything else
 * ("x", "1x", an empty token), a literal that overflows ("1e999") or
 * underflows to zero ("1e-400").  0 with *v and *end (past the token; end
 * may be NULL), or -1.  The one number reader of these files (a damaged
 * number read as 0 halved a mean). */
int drape_cli_result_parse_num(const char *s, const char **end, double *v);

#endif /* DRAPE_CLI_RESULT_H */

/* cli_data.h: where the command line finds drape's shipped data, the
 * default scene and the shipped fabrics and scenes (docs/install.md).  Private to src/main.c and src/cli_*.c.
 *
 * A relative path that names no file in the current directory is looked
 * up, in order, in
 *   1. $DRAPE_DATA, when set and not empty (it replaces 2 and 3: a staged
 *      `make install DESTDIR=...`, or a data tree elsewhere);
 *   2. the checkout the running binary was built in (the directory of
 *      /proc/self/exe when it holds scenes/cusick.yaml and a Makefile);
 *   3. the data directory compiled in, $(PREFIX)/share/drape.
 * An absolute path, or one that starts with ./ or ../, is taken as it is:
 * the current directory is the only place it can mean.  So in the checkout
 * `drape run` reads ./scenes/cusick.yaml as it always did, and anywhere
 * else the installed one; a scene's own fabric path is relative to the
 * scene file (scene.h), so the installed scenes find the installed
 * fabrics. */
#ifndef DRAPE_CLI_DATA_H
#define DRAPE_CLI_DATA_H

#include <stddef.h>
#include <stdio.h>

#include "drape/error.h"

#define DRAPE_CLI_DATA_DIRS_MAX 3

typedef struct drape_cli_data_dir {
    char path[4096];
    const char *origin; /* "DRAPE_DATA", "checkout of this binary", "compiled in" */
} drape_cli_data_dir;

/* The data directories in search order (after the current directory);
 * returns how many (0 to DRAPE_CLI_DATA_DIRS_MAX).  A directory is listed
 * whether or not it exists. */
int drape_cli_data_dirs(drape_cli_data_dir dirs[DRAPE_CLI_DATA_DIRS_MAX]);

/* The compiled-in data directory, $(PREFIX)/share/drape. */
const char *drape_cli_data_compiled(void);

/* Resolve a path given on the command line (or a built-in default such as
 * "scenes/cusick.yaml") as above into out[n].  Returns 0, or an E_IO error
 * naming the path and every place looked in. */
int drape_cli_data_find(const char *arg, char *out, size_t n, drape_error *err);

/* "data: ..." lines for `drape --version`: the search order and whether
 * each directory exists. */
void drape_cli_data_describe(FILE *f);

#endif /* DRAPE_CLI_DATA_H */

/* fuzz_common.h: shared by the libFuzzer harnesses of the YAML loaders.
 *
 * The loaders take a path (they report it in every message and resolve a
 * scene's fabric against its directory), so each input is written to a file
 * in a private directory under /dev/shm (a tmpfs: one open/write/close per
 * input, a few microseconds, small next to the parse) and loaded from there.
 * Nothing in src/ is added for fuzzing.
 *
 * Layout of the directory (made once per process):
 *   DIR/fabrics -> the source tree's fabrics/ (a symbolic link)
 *   DIR/scenes/input.yaml   a scene input (its `../fabrics/X.yaml` works)
 *   DIR/fabric-input.yaml   a fabric input
 * The source tree is found at build time (DRAPE_FUZZ_ROOT) or from the
 * environment variable of the same name.
 */
#ifndef DRAPE_FUZZ_COMMON_H
#define DRAPE_FUZZ_COMMON_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "drape/error.h"

#ifndef DRAPE_FUZZ_ROOT
#define DRAPE_FUZZ_ROOT "."
#endif

static char fz_dir[256];

static void fz_cleanup(void)
{
    char p[512];
    snprintf(p, sizeof p, "%s/fabrics", fz_dir);
    unlink(p);
    snprintf(p, sizeof p, "%s/scenes/input.yaml", fz_dir);
    unlink(p);
    snprintf(p, sizeof p, "%s/scenes", fz_dir);
    rmdir(p);
    snprintf(p, sizeof p, "%s/fabric-input.yaml", fz_dir);
    unlink(p);
    rmdir(fz_dir);
}

/* The private directory, made on first use. */
static const char *fz_workdir(void)
{
    if (fz_dir[0]) return fz_dir;
    const char *base = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
    snprintf(fz_dir, sizeof fz_dir, "%s/drape-fuzz-%ld", base, (long)getpid());
    char p[512], fab[512];
    mkdir(fz_dir, 0700);
    snprintf(p, sizeof p, "%s/scenes", fz_dir);
    mkdir(p, 0700);
    const char *root = getenv("DRAPE_FUZZ_ROOT");
    if (!root) root = DRAPE_FUZZ_ROOT;
    if (realpath(root, fab) == NULL) snprintf(fab, sizeof fab, "%s", root);
    strncat(fab, "/fabrics", sizeof fab - strlen(fab) - 1);
    snprintf(p, sizeof p, "%s/fabrics", fz_dir);
    if (symlink(fab, p) != 0) { /* an earlier run's link: keep it */ }
    atexit(fz_cleanup);
    return fz_dir;
}

/* Write the input to `path`; abort if that fails (a harness problem, not
 * a finding). */
static void fz_write(const char *path, const unsigned char *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!f || (n && fwrite(data, 1, n, f) != n) || fclose(f) != 0) {
        perror(path);
        abort();
    }
}

/* A rejection must be well formed: a kind that input can cause (never
 * E_INTERNAL, a bug by definition), a message, the file it is about, and
 * for invalid content (E_INPUT) the line. */
static void fz_check_error(const drape_error *e)
{
    char buf[4096];
    drape_error_format(e, buf, sizeof buf);
    int ok = e->msg[0] != 0 && e->file[0] != 0;
    switch (e->kind) {
    case DRAPE_E_IO: case DRAPE_E_SYNTAX: case DRAPE_E_NOMEM: break;
    case DRAPE_E_INPUT: ok = ok && e->line > 0; break;
    default: ok = 0; break;
    }
    if (!ok) {
        fprintf(stderr, "malformed rejection (kind %d): %s\n", (int)e->kind, buf);
        abort();
    }
}

/* A finite number in (lo, hi]. */
static void fz_check_range(const char *what, double v, double lo, double hi)
{
    if (!(v > lo && v <= hi) || !isfinite(v)) {
        fprintf(stderr, "accepted input with %s = %g\n", what, v);
        abort();
    }
}

/* Warnings are formatted (as the CLI does) and dropped. */
static void fz_warn(void *ctx, const drape_error *w)
{
    char buf[4096];
    (void)ctx;
    drape_error_format(w, buf, sizeof buf);
}

#endif

/* cli_data.c: the data directories of the command line (cli_data.h). */
#include "cli_data.h"

#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "datadir.gen.h" /* DRAPE_DATADIR, written by the Makefile from PREFIX */

const char *drape_cli_data_compiled(void) { return DRAPE_DATADIR; }

static int is_file(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0 && !S_ISDIR(st.st_mode);
}

/* The directory of the running binary if it is a drape checkout. */
static int checkout_dir(char *out, size_t n)
{
    char exe[4096];
    ssize_t len = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (len <= 0) return 0;
    exe[len] = '\0';
    char *slash = strrchr(exe, '/');
    if (!slash) return 0;
    *slash = '\0';
    char probe[4200];
    int r = snprintf(probe, sizeof probe, "%s/scenes/cusick.yaml", exe);
    if (r < 0 || (size_t)r >= sizeof probe || !is_file(probe)) return 0;
    snprintf(probe, sizeof probe, "%s/Makefile", exe);
    if (!is_file(probe)) return 0;
    if ((size_t)snprintf(out, n, "%s", exe) >= n) return 0;
    return 1;
}

int drape_cli_data_dirs(drape_cli_data_dir dirs[DRAPE_CLI_DATA_DIRS_MAX])
{
    int k = 0;
    const char *env = getenv("DRAPE_DATA");
    if (env && *env) {
        snprintf(dirs[k].path, sizeof dirs[k].path, "%s", env);
        dirs[k++].origin = "DRAPE_DATA";
        return k;
    }
    if (checkout_dir(dirs[k].path, sizeof dirs[k].path)) dirs[k++].origin = "checkout of this binary";
    snprintf(dirs[k].path, sizeof dirs[k].path, "%s", DRAPE_DATADIR);
    dirs[k++].origin = "compiled in";
    return k;
}

static int cwd_only(const char *p)
{
    return p[0] == '/' || strncmp(p, "./", 2) == 0 || strncmp(p, "../", 3) == 0 ||
           strcmp(p, ".") == 0 || strcmp(p, "..") == 0;
}

int drape_cli_data_find(const char *arg, char *out, size_t n, drape_error *err)
{
    if ((size_t)snprintf(out, n, "%s", arg) >= n)
        return drape_error_set(err, DRAPE_E_IO, arg, 0, 0, NULL, "path too long");
    if (cwd_only(arg) || access(arg, F_OK) == 0) return 0;
    drape_cli_data_dir dirs[DRAPE_CLI_DATA_DIRS_MAX];
    int nd = drape_cli_data_dirs(dirs);
    char looked[2048];
    size_t used = (size_t)snprintf(looked, sizeof looked, "the current directory");
    for (int i = 0; i < nd; i++) {
        char p[4200];
        int r = snprintf(p, sizeof p, "%s/%s", dirs[i].path, arg);
        if (r > 0 && (size_t)r < sizeof p && access(p, F_OK) == 0) {
            if ((size_t)r >= n)
                return drape_error_set(err, DRAPE_E_IO, arg, 0, 0, NULL, "path too long");
            memcpy(out, p, (size_t)r + 1);
            return 0;
        }
        if (used < sizeof looked)
            used += (size_t)snprintf(looked + used, sizeof looked - used, ", %s (%s)",
                                     dirs[i].path, dirs[i].origin);
    }
    return drape_error_set(err, DRAPE_E_IO, arg, 0, 0, NULL,
                           "cannot open: no such file (looked in %s; set DRAPE_DATA to "
                           "drape's data directory)", looked);
}

void drape_cli_data_describe(FILE *f)
{
    drape_cli_data_dir dirs[DRAPE_CLI_DATA_DIRS_MAX];
    int nd = drape_cli_data_dirs(dirs);
    fprintf(f, "data: relative paths not found in the current directory are looked up in:\n");
    for (int i = 0; i < nd; i++) {
        char probe[4200];
        int r = snprintf(probe, sizeof probe, "%s/scenes/cusick.yaml", dirs[i].path);
        int there = r > 0 && (size_t)r < sizeof probe && is_file(probe);
        fprintf(f, "  %s (%s)%s\n", dirs[i].path, dirs[i].origin,
                there ? "" : " [no scenes/cusick.yaml there]");
    }
}

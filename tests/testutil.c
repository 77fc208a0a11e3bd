/* testutil.c: helpers shared by the Check suites (see testutil.h). */
#include "testutil.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static char scratch[256];

static void remove_scratch(void)
{
    char cmd[300];
    if (scratch[0]) {
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", scratch);
        if (system(cmd) != 0) { /* nothing more to do */ }
    }
}

const char *tu_scratch_dir(void)
{
    if (!scratch[0]) {
        const char *tmp = getenv("TMPDIR");
        snprintf(scratch, sizeof scratch, "%s/drape-test-%ld", tmp ? tmp : "/tmp",
                 (long)getpid());
        mkdir(scratch, 0700);
        atexit(remove_scratch);
    }
    return scratch;
}

const char *tu_write_bytes(const char *name, const void *data, size_t n)
{
    static char paths[8][512];
    static int slot;
    char *p = paths[slot++ % 8];
    snprintf(p, 512, "%s/%s", tu_scratch_dir(), name);
    FILE *f = fopen(p, "wb");
    ck_assert_msg(f != NULL, "cannot write %s", p);
    if (n) ck_assert(fwrite(data, 1, n, f) == n);
    fclose(f);
    return p;
}

const char *tu_write_file(const char *name, const char *text)
{
    return tu_write_bytes(name, text, strlen(text));
}

const char *tu_src(const char *rel)
{
    static char paths[8][512];
    static int slot;
    char *p = paths[slot++ % 8];
    snprintf(p, 512, "../%s", rel);
    return p;
}

static void slurp(const char *path, char *buf, size_t cap)
{
    if (!buf || cap == 0) return;
    buf[0] = 0;
    FILE *f = fopen(path, "rb");
    if (!f) return;
    size_t n = fread(buf, 1, cap - 1, f);
    buf[n] = 0;
    fclose(f);
}

int tu_run_drape(const char *args, char *out, size_t outcap, char *err,
                 size_t errcap)
{
    const char *bin = getenv("DRAPE_BIN");
    char o[512], e[512], cmd[4096];
    snprintf(o, sizeof o, "%s/stdout.txt", tu_scratch_dir());
    snprintf(e, sizeof e, "%s/stderr.txt", tu_scratch_dir());
    snprintf(cmd, sizeof cmd, "%s %s >'%s' 2>'%s' </dev/null", bin ? bin : "../drape",
             args, o, e);
    int st = system(cmd);
    slurp(o, out, outcap);
    slurp(e, err, errcap);
    if (st == -1 || !WIFEXITED(st)) return -1;
    return WEXITSTATUS(st);
}

void tu_bad_header(const char *path, int *line, char *key, size_t nkey)
{
    *line = 0;
    key[0] = 0;
    FILE *f = fopen(path, "rb");
    if (!f) return;
    char buf[512];
    if (fgets(buf, sizeof buf, f) && strncmp(buf, "# expect ", 9) == 0) {
        char *p = buf + 9, *end;
        *line = (int)strtol(p, &end, 10);
        p = end + (*end == ' ');
        char *colon = strchr(p, ':');
        size_t n = colon ? (size_t)(colon - p) : 0;
        if (n >= nkey) n = nkey - 1;
        memcpy(key, p, n);
        key[n] = 0;
    }
    fclose(f);
}

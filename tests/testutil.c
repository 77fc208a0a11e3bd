/* testutil.c: helpers shared by the Check suites (see testutil.h). */
#include "testutil.h"

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* Most arguments tu_spawn_drape passes after argv[0]. */
#define TU_MAX_ARGS 62

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

const char *tu_drape_bin(void)
{
    const char *bin = getenv("DRAPE_BIN");
    return bin ? bin : "../drape";
}

void tu_read_file(const char *path, char *buf, size_t cap)
{
    if (!buf || cap == 0) return;
    buf[0] = 0;
    FILE *f = fopen(path, "rb");
    if (!f) return;
    size_t n = fread(buf, 1, cap - 1, f);
    buf[n] = 0;
    fclose(f);
}

int tu_run_drape_pty(const char *args, char *out, size_t outcap)
{
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "script -qec '%s %s' /dev/null", tu_drape_bin(), args);
    FILE *p = popen(cmd, "r");
    if (!p) return -1;
    size_t n = fread(out, 1, outcap - 1, p);
    out[n] = 0;
    int st = pclose(p);
    return st == -1 || !WIFEXITED(st) ? -1 : WEXITSTATUS(st);
}

int tu_run_drape(const char *args, char *out, size_t outcap, char *err,
                 size_t errcap)
{
    char o[512], e[512], cmd[4096];
    snprintf(o, sizeof o, "%s/stdout.txt", tu_scratch_dir());
    snprintf(e, sizeof e, "%s/stderr.txt", tu_scratch_dir());
    snprintf(cmd, sizeof cmd, "%s %s >'%s' 2>'%s' </dev/null", tu_drape_bin(), args,
             o, e);
    int st = system(cmd);
    tu_read_file(o, out, outcap);
    tu_read_file(e, err, errcap);
    if (st == -1 || !WIFEXITED(st)) return -1;
    return WEXITSTATUS(st);
}

pid_t tu_spawn_drape(const char *const args[], const char *out_path,
                     const char *err_path, int new_group)
{
    return tu_spawn_drape_hook(args, out_path, err_path, new_group, NULL, NULL);
}

/* The forked child's side of tu_spawn_drape_hook: never returns. */
static void exec_drape(const char *bin, const char *const av[], const char *out_path,
                       const char *err_path, int new_group, int (*before_exec)(void *),
                       void *arg)
{
    if (new_group) setpgid(0, 0);
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    if (!freopen(out_path ? out_path : "/dev/null", "w", stdout) ||
        !freopen(err_path ? err_path : "/dev/null", "w", stderr))
        _exit(99);
    if (before_exec && before_exec(arg) != 0) _exit(97);
    execv(bin, (char *const *)av);
    _exit(98);
}

pid_t tu_spawn_drape_hook(const char *const args[], const char *out_path,
                          const char *err_path, int new_group,
                          int (*before_exec)(void *), void *arg)
{
    const char *av[TU_MAX_ARGS + 2];
    int n = 1;
    av[0] = "drape";
    for (; args[n - 1]; n++) {
        ck_assert_msg(n <= TU_MAX_ARGS, "tu_spawn_drape: more than %d arguments", TU_MAX_ARGS);
        av[n] = args[n - 1];
    }
    av[n] = NULL;
    const char *bin = tu_drape_bin();
    fflush(NULL); /* nothing buffered is written twice */
    pid_t pid = fork();
    ck_assert_msg(pid >= 0, "fork: %s", strerror(errno));
    if (pid == 0) exec_drape(bin, av, out_path, err_path, new_group, before_exec, arg);
    if (new_group) setpgid(pid, pid);
    return pid;
}

int tu_child_ended(pid_t pid)
{
    siginfo_t si;
    memset(&si, 0, sizeof si);
    if (waitid(P_PID, (id_t)pid, &si, WEXITED | WNOHANG | WNOWAIT) != 0) return 1;
    return si.si_pid == pid;
}

static double seconds_since(const struct timespec *t0)
{
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (double)(now.tv_sec - t0->tv_sec) + 1e-9 * (double)(now.tv_nsec - t0->tv_nsec);
}

int tu_wait_file(pid_t pid, const char *path, double timeout_s)
{
    struct timespec t0, ms = {0, 1000 * 1000};
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (;;) {
        if (path && access(path, F_OK) == 0) return 0;
        if (tu_child_ended(pid)) /* (it may have written path and ended since) */
            return path && access(path, F_OK) == 0 ? 0 : TU_WAIT_ENDED;
        if (seconds_since(&t0) >= timeout_s) return path ? TU_WAIT_TIMEOUT : 0;
        nanosleep(&ms, NULL);
    }
}

int tu_signal_and_reap(pid_t pid, int sig, int group)
{
    if (sig) kill(group ? -pid : pid, sig);
    int ws = 0;
    ck_assert_int_eq(waitpid(pid, &ws, 0), pid);
    return ws;
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

/* check_testutil.c: the process helpers of testutil.c that the suites
 * spawning drape share (check_batch.c, check_run.c,
 * check_specimens_resume.c).  What they promise, checked on the drape
 * binary itself: a child that ended is reported and left to be reaped
 * (its exit status is still there), redirections reach the files, a new
 * process group is the child's own, a signal to it is delivered and
 * reaped, timeouts last at least as long as asked, and before_exec runs
 * in the process that becomes drape. */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "testutil.h"

#define CAP 4096

/* Monotonic seconds, measured here rather than by the helper. */
static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* A run of the hang scene that goes on for minutes unless signalled. */
static pid_t start_long_run(const char *dir, int new_group)
{
    const char *const a[] = {"run", "-q", "../scenes/hang.yaml", "--spacing", "5cm",
                             "--t-max", "600s", "--out", dir, NULL};
    return tu_spawn_drape(a, NULL, NULL, new_group);
}

/* drape with an unknown option exits 2 at once: tu_wait_file says it
 * ended, tu_child_ended too, and neither reaped it: the status is 2; its
 * message went to err_path, nothing to out_path. */
START_TEST(test_ended_child_not_reaped)
{
    char o_path[600], e_path[600], text[CAP];
    snprintf(o_path, sizeof o_path, "%s/tu.stdout", tu_scratch_dir());
    snprintf(e_path, sizeof e_path, "%s/tu.stderr", tu_scratch_dir());
    const char *const a[] = {"run", "--no-such-option", NULL};
    pid_t pid = tu_spawn_drape(a, o_path, e_path, 0);
    char never[600];
    snprintf(never, sizeof never, "%s/never-written", tu_scratch_dir());
    ck_assert_int_eq(tu_wait_file(pid, never, 30.0), TU_WAIT_ENDED);
    ck_assert_int_eq(tu_child_ended(pid), 1);
    int ws = tu_signal_and_reap(pid, 0, 0);
    ck_assert_msg(WIFEXITED(ws) && WEXITSTATUS(ws) == 2, "status %d", ws);
    tu_read_file(e_path, text, CAP);
    ck_assert_msg(strstr(text, "--no-such-option") != NULL, "stderr: %s", text);
    tu_read_file(o_path, text, CAP);
    ck_assert_str_eq(text, "");
}
END_TEST

/* A running child in a group of its own: the file it writes is seen, it
 * is not reported ended, a missing file times out no sooner than asked,
 * path NULL waits the whole time; SIGTERM to the group ends it with the
 * documented 143. */
START_TEST(test_running_child_group)
{
    char dir[600], first[700];
    snprintf(dir, sizeof dir, "%s/tu-long", tu_scratch_dir());
    snprintf(first, sizeof first, "%s/frame_000000.obj", dir);
    pid_t pid = start_long_run(dir, 1);
    ck_assert_int_eq(getpgid(pid), pid);
    ck_assert_int_eq(tu_wait_file(pid, first, 30.0), 0);
    ck_assert_int_eq(tu_child_ended(pid), 0);
    double t0 = now_s();
    ck_assert_int_eq(tu_wait_file(pid, tu_src("no-such-file"), 0.2), TU_WAIT_TIMEOUT);
    double t1 = now_s();
    ck_assert_int_eq(tu_wait_file(pid, NULL, 0.2), 0);
    double t2 = now_s();
    ck_assert_msg(t1 - t0 >= 0.2 && t2 - t1 >= 0.2, "waited %g s and %g s", t1 - t0, t2 - t1);
    int ws = tu_signal_and_reap(pid, SIGTERM, 1);
    ck_assert_msg(WIFEXITED(ws) && WEXITSTATUS(ws) == 143, "status %d", ws);
}
END_TEST

/* before_exec writes its own pid to a file: it is the pid returned, that
 * of the process that then runs drape; a non-zero return ends the child
 * with 97 before drape runs. */
static int write_pid(void *arg)
{
    FILE *f = fopen(arg, "w");
    if (!f) return -1;
    fprintf(f, "%ld\n", (long)getpid());
    return fclose(f) != 0;
}

static int refuse(void *arg)
{
    (void)arg;
    return 1;
}

START_TEST(test_before_exec)
{
    char pid_path[600], text[CAP];
    snprintf(pid_path, sizeof pid_path, "%s/tu.pid", tu_scratch_dir());
    const char *const a[] = {"--version", NULL};
    pid_t pid = tu_spawn_drape_hook(a, NULL, NULL, 0, write_pid, pid_path);
    int ws = tu_signal_and_reap(pid, 0, 0);
    ck_assert_msg(WIFEXITED(ws) && WEXITSTATUS(ws) == 0, "status %d", ws);
    tu_read_file(pid_path, text, CAP);
    ck_assert_int_eq(atol(text), (long)pid);
    pid = tu_spawn_drape_hook(a, NULL, NULL, 0, refuse, NULL);
    ws = tu_signal_and_reap(pid, 0, 0);
    ck_assert_msg(WIFEXITED(ws) && WEXITSTATUS(ws) == 97, "status %d", ws);
}
END_TEST

Suite *testutil_suite(void)
{
    Suite *s = suite_create("testutil");
    TCase *tc = tcase_create("process");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, test_ended_child_not_reaped);
    tcase_add_test(tc, test_running_child_group);
    tcase_add_test(tc, test_before_exec);
    suite_add_tcase(s, tc);
    return s;
}

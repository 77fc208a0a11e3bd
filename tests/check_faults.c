/* check_faults.c: resource faults met by the drape binary (issue 7, item
 * 6): a full disk while frames are written, a full stdout, an unwritable
 * output directory, and a missing fabric.  Each must end with the
 * documented I/O status (3), a message naming the file, no result on
 * stdout, and nothing of the run's own left behind: no drape.h5, no
 * temporary file, no OBJ frame (those written before the failure are
 * removed), and no output directory if the run created it; files that
 * were there before stay.
 *
 * A full disk is simulated with a file size limit (ulimit -f, SIGXFSZ
 * ignored so write() fails with EFBIG, as it fails with ENOSPC on a full
 * file system; inherited by drape): no mount or privilege needed.  The 16 KiB limit lets the
 * first OBJ frame (3.5 KiB for 7 x 7 particles) through and stops the HDF5
 * file at its first frame; before the fix in drape_h5_open (H5dont_atexit)
 * HDF5 1.10 crashed in its exit handler here (status 139). */
#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "testutil.h"

#define CAP 65536
static char out[CAP], err[CAP];

static const char *hang = "run ../scenes/hang.yaml --spacing 5cm --t-max 0.2s -q";

/* Absolute path of the drape binary the suite runs. */
static const char *drape_bin(void)
{
    static char bin[1024];
    const char *b = tu_drape_bin();
    if (b[0] == '/') return b;
    char cwd[512];
    ck_assert_ptr_nonnull(getcwd(cwd, sizeof cwd));
    snprintf(bin, sizeof bin, "%s/%s", cwd, b);
    return bin;
}

/* Run drape through a shell prefix (`prefix` is put before the binary). */
static int run_with(const char *prefix, const char *args)
{
    char wrapped[2048];
    const char *saved = getenv("DRAPE_BIN");
    char keep[1024] = "";
    if (saved) snprintf(keep, sizeof keep, "%s", saved);
    snprintf(wrapped, sizeof wrapped, "%s '%s'", prefix, drape_bin());
    setenv("DRAPE_BIN", wrapped, 1);
    int st = tu_run_drape(args, out, CAP, err, CAP);
    if (keep[0]) setenv("DRAPE_BIN", keep, 1);
    else unsetenv("DRAPE_BIN");
    return st;
}

/* Number of entries of dir whose name starts with `prefix`. */
static int count_files(const char *dir, const char *prefix)
{
    DIR *d = opendir(dir);
    ck_assert_ptr_nonnull(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        if (strncmp(e->d_name, prefix, strlen(prefix)) == 0) n++;
    closedir(d);
    return n;
}

static const char *new_dir(const char *name)
{
    static char p[600];
    snprintf(p, sizeof p, "%s/%s", tu_scratch_dir(), name);
    mkdir(p, 0700);
    return p;
}

/* Run `run --out DIR` under the file size limit `ulimit -f blocks` (512-byte
 * blocks) into DIR holding the user's keep.txt: the run must fail with exit 3,
 * print nothing on stdout, name `names` in its message and leave DIR as it
 * was (no drape*, frame_*, shadow*, only keep.txt).  The same run into a
 * directory it makes must remove it, and without the limit must succeed and
 * write drape.h5: the limit made the failure.  dir_stem names the three
 * directories.  Returns the first run's stderr (in err). */
static void assert_full_disk_leaves_nothing(const char *run, int blocks, const char *names,
                                            const char *dir_stem)
{
    char name[200], args[1024], keep[700], prefix[100], made[700];
    snprintf(name, sizeof name, "%s", dir_stem);
    const char *dir = new_dir(name);
    snprintf(keep, sizeof keep, "%s/keep.txt", dir);
    FILE *k = fopen(keep, "w");
    ck_assert_ptr_nonnull(k);
    fputs("the user's\n", k);
    fclose(k);
    snprintf(prefix, sizeof prefix, "ulimit -f %d; trap '' XFSZ; exec", blocks);
    snprintf(args, sizeof args, "%s --out '%s'", run, dir);
    int st = run_with(prefix, args);
    ck_assert_msg(st == 3, "status %d (want 3), stderr: %s", st, err);
    ck_assert_str_eq(out, "");
    ck_assert_msg(strncmp(err, "drape: ", 7) == 0 && strstr(err, names) != NULL, "message: %s",
                  err);
    ck_assert_int_eq(count_files(dir, "drape"), 0);
    ck_assert_int_eq(count_files(dir, "frame_"), 0);
    ck_assert_int_eq(count_files(dir, "shadow"), 0);
    ck_assert_int_eq(count_files(dir, "keep.txt"), 1);
    ck_assert_int_eq(count_files(dir, ""), 3); /* ., .., keep.txt */
    char first_err[CAP];
    snprintf(first_err, sizeof first_err, "%s", err);

    /* a directory the run created is removed with its contents */
    snprintf(made, sizeof made, "%s/made-by-drape-%s", tu_scratch_dir(), dir_stem);
    snprintf(args, sizeof args, "%s --out '%s'", run, made);
    st = run_with(prefix, args);
    ck_assert_msg(st == 3, "status %d (want 3), stderr: %s", st, err);
    ck_assert_msg(access(made, F_OK) != 0, "%s left behind", made);

    /* the same run without the limit succeeds */
    snprintf(name, sizeof name, "roomy-%s", dir_stem);
    const char *ok = new_dir(name);
    snprintf(args, sizeof args, "%s --out '%s'", run, ok);
    st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(st == 0, "status %d: %s", st, err);
    ck_assert_int_eq(count_files(ok, "drape.h5"), 1);
    snprintf(err, CAP, "%s", first_err);
}

START_TEST(test_disk_full_while_writing_frames)
{
    /* 32 blocks of 512 bytes (POSIX sh units) = 16 KiB: drape.h5 fails at
     * its fifth frame, after five OBJ frames (3.5 KiB each) were written */
    assert_full_disk_leaves_nothing(hang, 32, "drape.h5", "full");
    /* HDF5's message is quoted on one line */
    ck_assert_msg(strchr(err, '\n') == err + strlen(err) - 1, "message: %s", err);
}
END_TEST

/* A full disk met while drape.h5 takes a frame: the message says why
 * (HDF5's innermost message, docs/outputs.md), as it does for an OBJ frame
 * or for the file's closing.  Before the fix it read "HDF5: cannot write
 * /steps/000005" and no more: the closes on the failure path (H5Dclose,
 * H5Gclose) cleared HDF5's error stack before it was read.  Found by a
 * review that filled a small tmpfs at every size. */
START_TEST(test_disk_full_message_says_why)
{
    const char *dir = new_dir("full-why");
    char args[1024];
    snprintf(args, sizeof args, "%s --out '%s'", hang, dir);
    /* the 16 KiB limit of test_disk_full_while_writing_frames: drape.h5
     * fails at a frame, write() with EFBIG */
    int st = run_with("ulimit -f 32; trap '' XFSZ; exec", args);
    ck_assert_msg(st == 3, "status %d (want 3), stderr: %s", st, err);
    ck_assert_msg(strstr(err, "/steps/") != NULL, "not failed at a frame: %s", err);
    ck_assert_msg(strstr(err, strerror(EFBIG)) != NULL, "message without the reason: %s", err);
    ck_assert_msg(strchr(err, '\n') == err + strlen(err) - 1, "message: %s", err);
    ck_assert_int_eq(count_files(dir, "drape"), 0);
    ck_assert_int_eq(count_files(dir, "frame_"), 0);
}
END_TEST

/* A full disk met by the shadow picture of a single Cusick run, after
 * drape.h5 was closed: the run fails (exit 3) and, as for any I/O error,
 * leaves nothing of its own (docs/outputs.md, "Atomic files and
 * errors").  Before the fix drape.h5 and drape.xmf had already been
 * renamed into place and stayed (the frames went), and a directory the
 * run made stayed with them.  Found by a review filling a small tmpfs at
 * every size.  The 100 KiB limit lets drape.h5 (30 KiB at 3 cm), the
 * frame and shadow.svg through and stops shadow.png (150 KiB). */
START_TEST(test_disk_full_while_writing_shadow)
{
    assert_full_disk_leaves_nothing("run ../scenes/cusick.yaml --spacing 3cm --specimens 1 -q", 200,
                                    "shadow.png", "full-shadow");
    /* with the reason (cairo's own message was "error while writing to
     * output stream") */
    ck_assert_msg(strstr(err, strerror(EFBIG)) != NULL, "message without the reason: %s", err);
    ck_assert_int_eq(count_files(new_dir("roomy-full-shadow"), "shadow.png"), 1);
}
END_TEST

/* An output directory that exists but cannot be written into: the error
 * comes before any computation, names the directory, and nothing stays.
 * Root ignores permission bits, so a read-only directory of sysfs is used
 * then (skipped when there is none). */
START_TEST(test_unwritable_output_dir)
{
    const char *dir = new_dir("readonly");
    char probe[700];
    chmod(dir, 0555);
    snprintf(probe, sizeof probe, "%s/probe", dir);
    FILE *f = fopen(probe, "w");
    if (f) { /* root: try sysfs */
        fclose(f);
        unlink(probe);
        dir = "/sys/kernel";
        snprintf(probe, sizeof probe, "%s/drape-probe", dir);
        f = fopen(probe, "w");
        if (f || access(dir, F_OK) != 0) {
            if (f) {
                fclose(f);
                unlink(probe);
            }
            fprintf(stderr, "note: no unwritable directory; test_unwritable_output_dir skipped\n");
            return;
        }
    }
    char args[1024];
    snprintf(args, sizeof args, "%s --out '%s'", hang, dir);
    int st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(st == 3, "status %d (want 3), stderr: %s", st, err);
    ck_assert_str_eq(out, "");
    ck_assert_msg(strstr(err, dir) != NULL, "message: %s", err);
    ck_assert_int_eq(count_files(dir, "drape.h5"), 0);
    ck_assert_int_eq(count_files(dir, "frame_"), 0);
    /* a directory that cannot be made at all */
    snprintf(args, sizeof args, "%s --out /proc/drape-no-such/out", hang);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 3);
    ck_assert_ptr_nonnull(strstr(err, "/proc/drape-no-such/out"));
}
END_TEST

START_TEST(test_stdout_full)
{
    /* the result cannot be written: I/O status, not success */
    int st = run_with("sh -c 'exec \"$0\" \"$@\" >/dev/full'", hang);
    ck_assert_msg(st == 3, "status %d (want 3), stderr: %s", st, err);
    ck_assert_ptr_nonnull(strstr(err, "drape: "));
}
END_TEST

/* A result longer than stdout's buffer (4 KiB): an ensemble's JSON with
 * its specimens array.  Its first write failed inside fprintf, which
 * dropped the text; the fflush after it had nothing left to write and
 * succeeded, so drape exited 0 with the result lost (the README's
 * `--specimens 30` > file on a full disk).  Found by a review running
 * ensembles > /dev/full. */
START_TEST(test_stdout_full_long_result)
{
    const char *ens = "run ../scenes/hang.yaml --spacing 5cm --t-max 0.05s -q --method animate "
                      "--specimens 40 -j 1";
    int st = tu_run_drape(ens, out, CAP, err, CAP);
    ck_assert_msg(st == 0, "status %d: %s", st, err);
    ck_assert_msg(strlen(out) > 4096, "result only %zu bytes", strlen(out));
    st = run_with("sh -c 'exec \"$0\" \"$@\" >/dev/full'", ens);
    ck_assert_msg(st == 3, "status %d (want 3), stderr: %s", st, err);
    ck_assert_ptr_nonnull(strstr(err, "drape: <stdout>"));
    char csv[512];
    snprintf(csv, sizeof csv, "%s --format csv", ens);
    st = run_with("sh -c 'exec \"$0\" \"$@\" >/dev/full'", csv);
    ck_assert_msg(st == 3, "csv: status %d (want 3), stderr: %s", st, err);
}
END_TEST

/* The commands that print and return 0 without checking their output
 * (`drape check`, the help and version texts, compare) exited 0 with
 * stdout on a full disk: the output lost and nothing said.  Found by a
 * review of the output writers.  Every command's stdout is now checked
 * when it ends: I/O status 3 and a message; a command that failed keeps
 * its own status. */
START_TEST(test_stdout_full_every_command)
{
    static const char *const cmds[] = {
        "check ../fabrics/denim-wang.yaml ../scenes/hang.yaml", "--help", "--version", "help",
        "run --help", "batch --help", "check --help", "compare --help", NULL};
    for (int i = 0; cmds[i]; i++) {
        int st = tu_run_drape(cmds[i], out, CAP, err, CAP);
        ck_assert_msg(st == 0 && out[0], "drape %s: status %d: %s", cmds[i], st, err);
        st = run_with("sh -c 'exec \"$0\" \"$@\" >/dev/full'", cmds[i]);
        ck_assert_msg(st == 3, "drape %s >/dev/full: status %d (want 3), stderr: %s", cmds[i],
                      st, err);
        ck_assert_msg(strstr(err, "drape: <stdout>: cannot write"), "drape %s: %s", cmds[i], err);
    }
    /* a command that failed for its own reason keeps its status */
    ck_assert_int_eq(run_with("sh -c 'exec \"$0\" \"$@\" >/dev/full'",
                              "check /nonexistent-drape.yaml"), 3);
    ck_assert_int_eq(run_with("sh -c 'exec \"$0\" \"$@\" >/dev/full'",
                              "run --spacing 5kg ../scenes/hang.yaml"), 2);
}
END_TEST

START_TEST(test_missing_fabric)
{
    const char *p = tu_write_file("orphan.yaml",
                                  "scene: hang\n"
                                  "fabric: no-such-fabric.yaml\n"
                                  "specimen: {shape: rectangle, width: 30 cm, height: 30 cm}\n"
                                  "spacing: 5 cm\n"
                                  "end: {t_max: 0.05 s}\n");
    const char *dir = new_dir("orphan-out");
    char args[1024];
    snprintf(args, sizeof args, "run '%s' --out '%s' -q", p, dir);
    int st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(st == 3, "status %d (want 3), stderr: %s", st, err);
    ck_assert_str_eq(out, "");
    ck_assert_msg(strstr(err, "no-such-fabric.yaml") != NULL, "message: %s", err);
    ck_assert_int_eq(count_files(dir, "drape"), 0);
    ck_assert_int_eq(count_files(dir, "frame"), 0);
    snprintf(args, sizeof args, "check '%s'", p);
    st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(st == 3, "check: status %d (want 3), stderr: %s", st, err);
}
END_TEST

Suite *faults_suite(void); /* found by the runner */
Suite *faults_suite(void)
{
    Suite *s = suite_create("faults");
    TCase *tc = tcase_create("faults");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, test_disk_full_while_writing_frames);
    tcase_add_test(tc, test_disk_full_message_says_why);
    tcase_add_test(tc, test_disk_full_while_writing_shadow);
    tcase_add_test(tc, test_unwritable_output_dir);
    tcase_add_test(tc, test_stdout_full);
    tcase_add_test(tc, test_stdout_full_long_result);
    tcase_add_test(tc, test_stdout_full_every_command);
    tcase_add_test(tc, test_missing_fabric);
    suite_add_tcase(s, tc);
    return s;
}

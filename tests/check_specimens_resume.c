/* check_specimens_resume.c: `drape run --resume DIR` of an ensemble
 * (cli_specimens_record.c; docs/ensemble.md, "Resuming an ensemble").
 * An interruption is simulated by removing stored results (the fall
 * method's specimens are too short to be signalled reliably, and a
 * fall specimen that was interrupted runs again from the start: the same
 * as one never started), and made real with SIGTERM on a dynamic
 * ensemble, whose first specimen then continues from its checkpoint.
 * The resumed ensemble is compared with the uninterrupted one. */
#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <hdf5.h>
#include <json-c/json.h>

#include "testutil.h"

#define CAP (1 << 20)
static char out[CAP], err[CAP];

static double jnum(json_object *o, const char *key)
{
    json_object *v;
    if (!json_object_object_get_ex(o, key, &v) || !v) return NAN;
    return json_object_get_double(v);
}

static const char *jstr(json_object *o, const char *key)
{
    json_object *v;
    if (!json_object_object_get_ex(o, key, &v) || !v) return "(null)";
    return json_object_get_string(v);
}

static json_object *parse(const char *text)
{
    json_object *o = json_tokener_parse(text);
    ck_assert_msg(o != NULL, "not JSON: %s", text);
    return o;
}

/* Run a shell command made from fmt and the paths that follow; it must
 * succeed. */
static void sh(const char *fmt, ...)
{
    char cmd[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(cmd, sizeof cmd, fmt, ap);
    va_end(ap);
    ck_assert_msg(system(cmd) == 0, "%s", cmd);
}

static ino_t inode(const char *dir, const char *name)
{
    char p[1200];
    struct stat st;
    snprintf(p, sizeof p, "%s/%s", dir, name);
    ck_assert_msg(stat(p, &st) == 0, "%s missing", p);
    return st.st_ino;
}

/* Start `drape run` of a dynamic ensemble of 2 cusick specimens at 5 cm,
 * jobs (-j) at a time, into dir (see tu_spawn_drape for the rest). */
static pid_t start_dynamic(const char *dir, const char *jobs, const char *out_path,
                           const char *err_path, int new_group)
{
    const char *const a[] = {"run", "-q", "../scenes/cusick.yaml", "--spacing", "5cm",
                             "--method", "dynamic", "--specimens", "2", "-j", jobs,
                             "--out", dir, NULL};
    return tu_spawn_drape(a, out_path, err_path, new_group);
}

/* The resumed result is the uninterrupted one: every key but the times
 * (wall_s, cpu_s) the same text, each specimen's seed, status, dc, nodes
 * and radii too. */
static void assert_same_ensemble(json_object *ref, json_object *got)
{
    json_object_object_foreach(ref, key, val) {
        json_object *g;
        ck_assert_msg(json_object_object_get_ex(got, key, &g), "%s missing", key);
        if (strcmp(key, "wall_s") == 0 || strcmp(key, "cpu_s") == 0) continue;
        if (strcmp(key, "specimens") == 0) {
            int n = (int)json_object_array_length(val);
            ck_assert_int_eq((int)json_object_array_length(g), n);
            for (int k = 0; k < n; k++) {
                json_object *a = json_object_array_get_idx(val, (size_t)k);
                json_object *b = json_object_array_get_idx(g, (size_t)k);
                static const char *const keys[] = {"seed", "status", "dc", "nodes", "r_min_m",
                                                   "r_max_m", NULL};
                for (int i = 0; keys[i]; i++)
                    ck_assert_msg(strcmp(jstr(a, keys[i]), jstr(b, keys[i])) == 0,
                                  "specimen %d: %s %s, uninterrupted %s", k + 1, keys[i],
                                  jstr(b, keys[i]), jstr(a, keys[i]));
            }
            continue;
        }
        const char *x = val ? json_object_to_json_string(val) : "null";
        const char *y = g ? json_object_to_json_string(g) : "null";
        ck_assert_msg(strcmp(x, y) == 0, "%s: resumed %s, uninterrupted %s", key, y, x);
    }
}

/* A fall ensemble (3 cm: 0.1 s a specimen; its 4 specimens differ, 3 and
 * 1 node) with --out: the manifest and every specimen's result are kept;
 * its --resume is refused (finished: nothing to resume, exit 2, nothing
 * written).  Then specimen 2's result removed and specimen 4 never run,
 * the manifest saying interrupted: --resume runs those two only (the
 * others' stored results stay as they are), in CSV too, and gives the
 * uninterrupted result.  A resume from a directory whose result files
 * are all kept but whose manifest still says running (the ensemble was
 * killed before it printed) prints the result without running anything. */
START_TEST(test_resume_fall)
{
    char dir[600], args[1400], ref[CAP];
    snprintf(dir, sizeof dir, "%s/ens-fall", tu_scratch_dir());
    snprintf(args, sizeof args, "run -q ../scenes/cusick.yaml --spacing 3cm --specimens 4 -j 2 "
             "--out %s", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    memcpy(ref, out, sizeof ref);
    json_object *r = parse(ref);
    ck_assert_msg(jnum(r, "dc_sd") > 1e-4, "the specimens do not differ: %s", ref);
    sh("test -f %s/ensemble.json && test -f %s/specimen-004/result.txt", dir, dir);

    /* finished: refused, nothing written */
    sh("cp %s/ensemble.json %s/manifest.before", dir, dir);
    snprintf(args, sizeof args, "run --resume %s", dir);
    int st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(st == 2 && out[0] == 0 && strstr(err, "ensemble.json") &&
                      strstr(err, "nothing to resume"), "exit %d, %s", st, err);
    sh("cmp %s/ensemble.json %s/manifest.before", dir, dir);

    /* interrupted after specimens 1 and 3 */
    ino_t kept1 = inode(dir, "specimen-001/result.txt"), kept3 = inode(dir, "specimen-003/result.txt");
    ino_t frame1 = inode(dir, "specimen-001/frame_000000.obj");
    sh("rm %s/specimen-002/result.txt && rm -r %s/specimen-004", dir, dir);
    sh("sed -i 's/\"status\":\"equilibrium\"/\"status\":\"interrupted\"/' %s/ensemble.json && "
       "grep -q '\"status\":\"interrupted\"' %s/ensemble.json", dir, dir);
    snprintf(args, sizeof args, "run --resume %s -j 1 -q", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    json_object *g = parse(out);
    assert_same_ensemble(r, g);
    /* the stored specimens were not run again */
    ck_assert(inode(dir, "specimen-001/result.txt") == kept1);
    ck_assert(inode(dir, "specimen-003/result.txt") == kept3);
    ck_assert(inode(dir, "specimen-001/frame_000000.obj") == frame1);
    sh("test -f %s/specimen-004/result.txt && grep -q '\"parts\":2' %s/ensemble.json", dir, dir);
    /* the CPU time counts every part: at least that of the specimens */
    json_object *sp;
    ck_assert(json_object_object_get_ex(g, "specimens", &sp));
    double cpu = 0;
    for (int k = 0; k < 4; k++) cpu += jnum(json_object_array_get_idx(sp, (size_t)k), "cpu_s");
    ck_assert_msg(jnum(g, "cpu_s") >= 0.95 * cpu, "cpu_s %g, specimens %g", jnum(g, "cpu_s"), cpu);
    json_object_put(g);

    /* killed before it printed: every result kept, the manifest says
     * running; nothing runs (a specimen would write its frames again) */
    sh("sed -i 's/\"status\":\"equilibrium\"/\"status\":\"running\"/' %s/ensemble.json && "
       "grep -q '\"status\":\"running\"' %s/ensemble.json", dir, dir);
    ino_t frame4 = inode(dir, "specimen-004/frame_000000.obj");
    snprintf(args, sizeof args, "run --resume %s --format csv", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    ck_assert(inode(dir, "specimen-004/frame_000000.obj") == frame4);
    char *row = strchr(out, '\n');
    ck_assert_msg(row && strncmp(out, "fabric,scene,", 13) == 0, "%s", out);
    char dc[64];
    snprintf(dc, sizeof dc, ",%.10g,", jnum(r, "dc"));
    ck_assert_msg(strstr(row, dc), "dc %s not in %s", dc, row);
    json_object_put(r);
}
END_TEST

/* --resume refuses, naming the file, exit status as documented, and
 * writes nothing: a scene file edited since the ensemble started (1), a
 * fabric file too (1), a damaged manifest (3: cut short, a member of
 * another type, a value out of range), a directory of specimens
 * without a manifest (3), run options with --resume (2). */
START_TEST(test_resume_refused)
{
    char dir[600], args[1400], cwd[512];
    ck_assert_ptr_nonnull(getcwd(cwd, sizeof cwd));
    snprintf(dir, sizeof dir, "%s/ens-refused", tu_scratch_dir());
    const char *fabric = tu_write_file("resume-fabric.yaml", "");
    sh("cp ../fabrics/cotton-breen.yaml %s", fabric);
    char scene[600];
    snprintf(scene, sizeof scene, "%s/resume-scene.yaml", tu_scratch_dir());
    snprintf(args, sizeof args, "sed 's|^fabric: .*|fabric: %s|' ../scenes/cusick.yaml > %s",
             fabric, scene);
    ck_assert_int_eq(system(args), 0);
    snprintf(args, sizeof args, "run -q %s --spacing 3cm --specimens 3 -j 1 --out %s", scene, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    sh("rm %s/specimen-003/result.txt && cp %s/ensemble.json %s/../manifest.before", dir, dir,
       dir);
    snprintf(args, sizeof args, "run -q --resume %s", dir);

    /* the scene edited (a comment is an edit) */
    sh("cp %s %s.orig && echo '# edited' >> %s", scene, scene, scene);
    int st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(st == 1 && out[0] == 0 && strstr(err, scene) &&
                      strstr(err, "changed since the ensemble started"), "exit %d, %s", st, err);
    sh("test ! -e %s/specimen-003/result.txt && cmp %s/ensemble.json %s/../manifest.before", dir,
       dir, dir);
    sh("mv %s.orig %s", scene, scene);
    /* the fabric edited */
    sh("cp %s %s.orig && echo '# edited' >> %s", fabric, fabric, fabric);
    st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(st == 1 && out[0] == 0 && strstr(err, fabric) &&
                      strstr(err, "changed since the ensemble started"), "exit %d, %s", st, err);
    sh("mv %s.orig %s", fabric, fabric);
    /* run options with --resume */
    snprintf(args, sizeof args, "run --resume %s --spacing 2cm", dir);
    st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(st == 2 && strstr(err, "got `--spacing'"), "exit %d, %s", st, err);
    /* a damaged manifest */
    snprintf(args, sizeof args, "run -q --resume %s", dir);
    sh("head -c 100 %s/../manifest.before > %s/ensemble.json", dir, dir);
    st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(st == 3 && out[0] == 0 && strstr(err, "ensemble.json") &&
                      strstr(err, "cannot be resumed"), "exit %d, %s", st, err);
    sh("sed 's/\"specimens\":3/\"specimens\":\"3\"/' %s/../manifest.before > %s/ensemble.json",
       dir, dir);
    st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(st == 3 && strstr(err, "ensemble.json"), "exit %d, %s", st, err);
    /* parts out of range (its count at the end of the part overflowed an
     * int: undefined behaviour, found by a review under UBSan) */
    sh("sed 's/\"parts\":1/\"parts\":99999999999/' %s/../manifest.before > %s/ensemble.json "
       "&& grep -q 99999999999 %s/ensemble.json && cp %s/ensemble.json %s/../manifest.parts", dir,
       dir, dir, dir, dir);
    st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(st == 3 && out[0] == 0 && strstr(err, "ensemble.json") &&
                      strstr(err, "out of range"), "exit %d, %s", st, err);
    sh("cmp %s/ensemble.json %s/../manifest.parts && test ! -e %s/specimen-003/result.txt", dir,
       dir, dir);
    /* no manifest */
    sh("rm %s/ensemble.json", dir);
    st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(st == 3 && out[0] == 0 && strstr(err, "ensemble.json: --resume: no such file"),
                  "exit %d, %s", st, err);
    sh("test ! -e %s/specimen-003/result.txt", dir);
    /* restored, it resumes */
    sh("cp %s/../manifest.before %s/ensemble.json", dir, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    json_object *o = parse(out);
    ck_assert_int_eq((int)jnum(o, "specimens_failed"), 0);
    json_object_put(o);
}
END_TEST

/* A dynamic ensemble of 2 specimens, one at a time, stopped by SIGTERM
 * while its first specimen runs (once it wrote its third frame; 5 cm:
 * about 2 s a specimen): exit 143, the message says how to resume, the
 * first specimen's checkpoint kept, the second never started.  --resume
 * continues the first from its checkpoint (its first frame is not written
 * again) and runs the second: both reach equilibrium, with their seeds.
 * A continued specimen is not the uninterrupted one bit for bit (a
 * restart changes the step sizes), and this drape is near a bifurcation:
 * continued at most output points its DC is within 3e-5 of the
 * uninterrupted 0.44154, but stopped at frame 3 it settled at 0.44408,
 * the fold state of another seed (seeds 1 to 3 give 0.4415 to 0.4466).
 * So the check is that it reaches a drape of this scene, within 2 %. */
START_TEST(test_resume_dynamic_interrupted)
{
    char dir[600], wait_for[700], args[1400];
    snprintf(dir, sizeof dir, "%s/ens-dynamic", tu_scratch_dir());
    snprintf(wait_for, sizeof wait_for, "%s/specimen-001/frame_000002.obj", dir);
    char o_path[600], e_path[600];
    snprintf(o_path, sizeof o_path, "%s/sig.stdout", tu_scratch_dir());
    snprintf(e_path, sizeof e_path, "%s/sig.stderr", tu_scratch_dir());
    pid_t pid = start_dynamic(dir, "1", o_path, e_path, 0);
    ck_assert_file_appears(pid, wait_for, 30.0);
    int ws = tu_signal_and_reap(pid, SIGTERM, 0);
    tu_read_file(o_path, out, CAP);
    tu_read_file(e_path, err, CAP);
    ck_assert_msg(WIFEXITED(ws) && WEXITSTATUS(ws) == 143, "status %d, %s", ws, err);
    ck_assert_msg(strstr(out, "\"status\": \"interrupted\""), "%s", out);
    char hint[800];
    snprintf(hint, sizeof hint, "continue with `drape run --resume %s`", dir);
    ck_assert_msg(strstr(err, hint), "%s", err);
    sh("test -f %s/specimen-001/drape.h5 && test ! -e %s/specimen-002", dir, dir);
    sh("test ! -e %s/specimen-001/result.txt && grep -q '\"status\":\"interrupted\"' "
       "%s/ensemble.json", dir, dir);
    ino_t frame0 = inode(dir, "specimen-001/frame_000000.obj");

    snprintf(args, sizeof args, "run --resume %s -j 2", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    ck_assert(inode(dir, "specimen-001/frame_000000.obj") == frame0);
    json_object *g = parse(out), *sp;
    ck_assert_str_eq(jstr(g, "status"), "equilibrium");
    ck_assert_int_eq((int)jnum(g, "specimens_failed"), 0);
    ck_assert(json_object_object_get_ex(g, "specimens", &sp));
    double dc[2];
    for (int k = 0; k < 2; k++) {
        json_object *s = json_object_array_get_idx(sp, (size_t)k);
        ck_assert_int_eq((int)jnum(s, "seed"), k + 1);
        ck_assert_str_eq(jstr(s, "status"), "equilibrium");
        dc[k] = jnum(s, "dc");
    }
    /* the first specimen uninterrupted: the same run alone with its seed */
    ck_assert_msg(tu_run_drape("run -q ../scenes/cusick.yaml --spacing 5cm --method dynamic "
                               "--specimens 1 --seed 1", out, CAP, err, CAP) == 0, "%s", err);
    json_object *o = parse(out);
    ck_assert_close_rel(dc[0], jnum(o, "dc"), 0.02);
    json_object_put(o);
    json_object_put(g);
}
END_TEST

/* A result.txt cut short (or edited) is not a result: its specimen runs
 * again, with a warning naming the file.  Cut at a line's end before its
 * status line, a specimen was taken as failed (specimens_failed 1, and
 * kept so: never run again); cut after it, the ensemble's result had
 * nulls (method, terms, the energies...); its shadow's line cut short
 * drew a wrong outline.  Found by a review editing result.txt by hand. */
START_TEST(test_resume_damaged_result)
{
    char dir[600], args[1400], ref[CAP];
    snprintf(dir, sizeof dir, "%s/ens-damaged", tu_scratch_dir());
    snprintf(args, sizeof args, "run -q ../scenes/cusick.yaml --spacing 3cm --specimens 3 -j 2 "
             "--out %s", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    memcpy(ref, out, sizeof ref);
    json_object *r = parse(ref);
    /* 1: up to the line before its status; 2: up to its status line; 3:
     * its last 3 bytes (the @shadow line's last sample and newline) */
    sh("cd %s && n=$(grep -n '^status\t' specimen-001/result.txt | cut -d: -f1) && "
       "head -n $((n - 1)) specimen-001/result.txt > t && mv t specimen-001/result.txt && "
       "head -n $n specimen-002/result.txt > t && mv t specimen-002/result.txt && "
       "head -c -3 specimen-003/result.txt > t && mv t specimen-003/result.txt", dir);
    sh("sed -i 's/\"status\":\"equilibrium\"/\"status\":\"interrupted\"/' %s/ensemble.json", dir);
    snprintf(args, sizeof args, "run -q --resume %s -j 2", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    for (int k = 1; k <= 3; k++) {
        char name[700];
        snprintf(name, sizeof name, "%s/specimen-%03d/result.txt: warning: not a result", dir, k);
        ck_assert_msg(strstr(err, name), "no warning for specimen %d: %s", k, err);
    }
    json_object *g = parse(out);
    assert_same_ensemble(r, g);
    /* stored whole again */
    sh("cd %s && for k in 1 2 3; do f=specimen-00$k/result.txt; grep -q '^status\ts\t' $f && "
       "grep -q '^@shadow\t' $f && test \"$(tail -c 1 $f | od -An -c | tr -d ' ')\" = '\\n' "
       "|| exit 1; done", dir);
    json_object_put(g);
    json_object_put(r);
}
END_TEST

/* A dynamic ensemble whose process is killed outright (SIGKILL: it
 * records nothing, and its specimens stop at once, each leaving its
 * checkpoint) and resumed: the result's cpu_s counts the time the
 * specimens ran before too, as each specimen's cpu_s does (it counted
 * only that of the resumed part: 1.8 s against specimens of 2.0 and
 * 2.3 s).  Found by a review killing the ensemble with kill -9. */
START_TEST(test_resume_killed_cpu)
{
    char dir[600], wait_for[700], args[1400];
    snprintf(dir, sizeof dir, "%s/ens-killed", tu_scratch_dir());
    snprintf(wait_for, sizeof wait_for, "%s/specimen-001/frame_000002.obj", dir);
    /* in a group of its own: its specimens with it, to wait for them */
    pid_t pid = start_dynamic(dir, "2", NULL, NULL, 1);
    ck_assert_file_appears(pid, wait_for, 30.0);
    /* (a little CPU time in both specimens) */
    struct timespec more = {0, 300 * 1000 * 1000}, ts = {0, 1000 * 1000};
    nanosleep(&more, NULL);
    tu_signal_and_reap(pid, SIGKILL, 0);
    for (int i = 0; i < 30000 && kill(-pid, 0) == 0; i++) nanosleep(&ts, NULL);
    ck_assert_msg(kill(-pid, 0) != 0, "the specimens did not stop with the ensemble");
    sh("grep -q '\"status\":\"running\"' %s/ensemble.json && test -f %s/specimen-001/drape.h5 && "
       "test -f %s/specimen-002/drape.h5", dir, dir, dir);

    snprintf(args, sizeof args, "run -q --resume %s -j 2", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    json_object *g = parse(out), *sp;
    ck_assert_str_eq(jstr(g, "status"), "equilibrium");
    ck_assert(json_object_object_get_ex(g, "specimens", &sp));
    double cpu = 0;
    for (int k = 0; k < 2; k++) cpu += jnum(json_object_array_get_idx(sp, (size_t)k), "cpu_s");
    ck_assert_msg(jnum(g, "cpu_s") >= 0.95 * cpu, "cpu_s %g, specimens %g", jnum(g, "cpu_s"), cpu);
    json_object_put(g);
}
END_TEST

/* A second writer into a directory that an ensemble still writes (a cron
 * job's --resume while the last one runs, a second run with the same
 * --out): both ran every specimen into the same files and exited 0.  It
 * is now refused (exit 3) while the first holds the directory. */
START_TEST(test_dir_in_use)
{
    char dir[600], wait_for[700], args[1400];
    snprintf(dir, sizeof dir, "%s/ens-in-use", tu_scratch_dir());
    snprintf(wait_for, sizeof wait_for, "%s/specimen-001/frame_000002.obj", dir);
    sh("rm -rf %s", dir);
    pid_t pid = start_dynamic(dir, "1", NULL, NULL, 0);
    ck_assert_file_appears(pid, wait_for, 30.0);
    snprintf(args, sizeof args, "run -q --resume %s", dir);
    int st1 = tu_run_drape(args, out, CAP, err, CAP);
    int in_use1 = strstr(err, "another drape run is writing") != NULL;
    snprintf(args, sizeof args, "run -q ../scenes/cusick.yaml --spacing 5cm --method static "
             "--specimens 1 --out %s", dir);
    int st2 = tu_run_drape(args, out, CAP, err, CAP);
    int in_use2 = strstr(err, "another drape run is writing") != NULL;
    int running = !tu_child_ended(pid);
    tu_signal_and_reap(pid, SIGTERM, 0);
    ck_assert_msg(running, "the first run ended before the second ones were tried");
    ck_assert_msg(st1 == 3 && in_use1 && out[0] == 0, "--resume: exit %d", st1);
    ck_assert_msg(st2 == 3 && in_use2 && out[0] == 0, "second run: exit %d, %s", st2, err);
    /* the first run's directory and files are its own: its specimen 2 was
     * never started by the refused --resume */
    sh("test ! -e %s/specimen-002 && test ! -e %s/specimen-001/result.txt", dir, dir);
}
END_TEST

/* --resume DIR where DIR is missing or is not a directory: the error
 * names DIR itself (it named DIR/drape.h5, "no such file", as though DIR
 * were a directory without a checkpoint), exit 3, nothing written. */
START_TEST(test_resume_no_dir)
{
    char dir[600], file[600], args[1400], want[800];
    snprintf(dir, sizeof dir, "%s/no-such-dir", tu_scratch_dir());
    sh("rm -rf %s", dir);
    snprintf(args, sizeof args, "run --resume %s", dir);
    int st = tu_run_drape(args, out, CAP, err, CAP);
    snprintf(want, sizeof want, "drape: %s: --resume: cannot use this directory: ", dir);
    ck_assert_msg(st == 3 && out[0] == 0 && strncmp(err, want, strlen(want)) == 0 &&
                      strstr(err, "No such file or directory"), "exit %d, %s", st, err);
    sh("test ! -e %s", dir);
    snprintf(file, sizeof file, "%s/not-a-dir", tu_scratch_dir());
    sh("echo x > %s", file);
    snprintf(args, sizeof args, "run --resume %s", file);
    st = tu_run_drape(args, out, CAP, err, CAP);
    snprintf(want, sizeof want, "drape: %s: --resume: not a directory", file);
    ck_assert_msg(st == 3 && out[0] == 0 && strncmp(err, want, strlen(want)) == 0, "exit %d, %s",
                  st, err);
    sh("test \"$(cat %s)\" = x", file);
}
END_TEST

/* A fall ensemble of 3 specimens (3 cm) with --out, its result as the
 * reference, its manifest then set to interrupted (for the damaged
 * result files the tests below make). */
static void fall3(const char *dir, char *ref)
{
    char args[1400];
    sh("rm -rf %s", dir);
    snprintf(args, sizeof args, "run -q ../scenes/cusick.yaml --spacing 3cm --specimens 3 -j 2 "
             "--out %s", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    memcpy(ref, out, CAP);
    sh("sed -i 's/\"status\":\"equilibrium\"/\"status\":\"interrupted\"/' %s/ensemble.json && "
       "grep -q '\"status\":\"interrupted\"' %s/ensemble.json", dir, dir);
}

/* The warning that specimen k's result.txt is not used (why: its text). */
static void assert_rerun_warning(const char *dir, int k, const char *why)
{
    char name[800];
    snprintf(name, sizeof name, "drape: %s/specimen-%03d/result.txt: warning: %s", dir, k, why);
    ck_assert_msg(strstr(err, name), "no warning for specimen %d (%s): %s", k, why, err);
}

/* The @ lines of a stored result.txt out of range: @cpu_s 1e999 (read as
 * inf: the ensemble's cpu_s was inf, null in the result and `inf` in
 * ensemble.json, which was then not JSON), @cpu_s -1, @exit 999 and @exit
 * x (atoi).  Each such specimen runs again with a warning naming the
 * file; the result is the uninterrupted one with a finite cpu_s, and the
 * manifest stays JSON. */
START_TEST(test_resume_damaged_header)
{
    char dir[600], args[1400], ref[CAP], man[700];
    snprintf(dir, sizeof dir, "%s/ens-header", tu_scratch_dir());
    fall3(dir, ref);
    json_object *r = parse(ref);
    ino_t kept = inode(dir, "specimen-003/result.txt");
    sh("cd %s && sed -i 's/^@cpu_s\t.*/@cpu_s\t1e999/' specimen-001/result.txt && "
       "sed -i 's/^@exit\t.*/@exit\t999/' specimen-002/result.txt && "
       "grep -q '^@cpu_s\t1e999$' specimen-001/result.txt && "
       "grep -q '^@exit\t999$' specimen-002/result.txt", dir);
    snprintf(args, sizeof args, "run -q --resume %s -j 2", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    assert_rerun_warning(dir, 1, "@cpu_s is not a CPU time");
    assert_rerun_warning(dir, 2, "@exit is not an exit status");
    ck_assert_msg(!strstr(err, "specimen-003"), "%s", err);
    ck_assert(inode(dir, "specimen-003/result.txt") == kept);
    json_object *g = parse(out);
    assert_same_ensemble(r, g);
    ck_assert_msg(isfinite(jnum(g, "cpu_s")) && jnum(g, "cpu_s") >= 0, "%s", out);
    json_object_put(g);
    snprintf(man, sizeof man, "%s/ensemble.json", dir);
    json_object *m = json_object_from_file(man);
    ck_assert_msg(m != NULL, "%s is not JSON", man);
    ck_assert_msg(isfinite(jnum(m, "cpu_s")), "manifest cpu_s %g", jnum(m, "cpu_s"));
    json_object_put(m);
    /* stored again, with what ran */
    sh("cd %s && grep -q '^@exit\t0$' specimen-002/result.txt && "
       "! grep -q '^@cpu_s\t1e999$' specimen-001/result.txt", dir);

    /* the other two: a negative CPU time, an exit status that is text */
    sh("cd %s && sed -i 's/^@cpu_s\t.*/@cpu_s\t-1/' specimen-001/result.txt && "
       "sed -i 's/^@exit\t.*/@exit\tx/' specimen-002/result.txt && "
       "sed -i 's/\"status\":\"equilibrium\"/\"status\":\"interrupted\"/' ensemble.json", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    assert_rerun_warning(dir, 1, "@cpu_s is not a CPU time");
    assert_rerun_warning(dir, 2, "@exit is not an exit status");
    g = parse(out);
    assert_same_ensemble(r, g);
    json_object_put(g);
    json_object_put(r);
}
END_TEST

/* A stored result.txt of this ensemble whose @seed is not its specimen's
 * (the manifest's seed + k: here 5 in specimen 1 of seeds 1-3, or x in
 * specimen 2) was discarded and the specimen run again silently.  Now a
 * warning names the file and both seeds; one of another ensemble (its
 * @ensemble changed, specimen 3) is still run again without one.  The
 * result is the uninterrupted one, and the seeds that ran are stored. */
START_TEST(test_resume_result_seed)
{
    char dir[600], args[1400], ref[CAP];
    snprintf(dir, sizeof dir, "%s/ens-seed", tu_scratch_dir());
    fall3(dir, ref);
    sh("cd %s && sed -i 's/^@seed\t.*/@seed\t5/' specimen-001/result.txt && "
       "sed -i 's/^@seed\t.*/@seed\tx\x1b[2J/' specimen-002/result.txt && "
       "sed -i 's/^@ensemble\t.*/@ensemble\tanother/' specimen-003/result.txt && "
       "grep -q '^@seed\t5$' specimen-001/result.txt && grep -q '^@seed\tx.\\[2J$' "
       "specimen-002/result.txt && grep -q '^@ensemble\tanother$' specimen-003/result.txt",
       dir);
    ino_t old3 = inode(dir, "specimen-003/result.txt");
    snprintf(args, sizeof args, "run -q --resume %s -j 2", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    assert_rerun_warning(dir, 1, "@seed is 5, not this specimen's 1; the specimen runs again");
    assert_rerun_warning(dir, 2, "@seed is not a whole number, not this specimen's 2; the "
                                 "specimen runs again");
    ck_assert_msg(!strchr(err, '\x1b'), "the file's escape reached stderr: %s", err);
    ck_assert_msg(!strstr(err, "specimen-003"), "%s", err);
    ck_assert(inode(dir, "specimen-003/result.txt") != old3);
    json_object *r = parse(ref), *g = parse(out);
    assert_same_ensemble(r, g);
    json_object_put(g);
    json_object_put(r);
    sh("cd %s && grep -q '^@seed\t1$' specimen-001/result.txt && "
       "grep -q '^@seed\t2$' specimen-002/result.txt && "
       "! grep -q '^@ensemble\tanother$' specimen-003/result.txt", dir);
}
END_TEST

/* A stored number that is not one: dc `x` was read as 0 (strtod without
 * its end), and the ensemble's mean DC was two thirds of the true one;
 * r_min_m `0.25x` (a number and more), nodes `1e999` (an overflow).
 * Every number is read whole now: each such specimen runs again with a
 * warning naming its file, and the result is the uninterrupted one. */
START_TEST(test_resume_result_numbers)
{
    char dir[600], args[1400], ref[CAP];
    snprintf(dir, sizeof dir, "%s/ens-numbers", tu_scratch_dir());
    fall3(dir, ref);
    json_object *r = parse(ref);
    sh("cd %s && sed -i 's/^dc\tn\t.*/dc\tn\tx/' specimen-001/result.txt && "
       "sed -i 's/^r_min_m\tn\t.*/r_min_m\tn\t0.25x/' specimen-002/result.txt && "
       "sed -i 's/^nodes\ti\t.*/nodes\ti\t1e999/' specimen-003/result.txt && "
       "grep -q '^dc\tn\tx$' specimen-001/result.txt && "
       "grep -q '^r_min_m\tn\t0.25x$' specimen-002/result.txt && "
       "grep -q '^nodes\ti\t1e999$' specimen-003/result.txt", dir);
    snprintf(args, sizeof args, "run -q --resume %s -j 2", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    for (int k = 1; k <= 3; k++) assert_rerun_warning(dir, k, "not a result that can be used");
    json_object *g = parse(out);
    assert_same_ensemble(r, g);
    json_object_put(g);
    json_object_put(r);
}
END_TEST

/* The children of process pid (from /proc/PID/stat: the state after the
 * name in parentheses, then the parent's pid): their number, and in
 * *zombies how many have exited and wait to be reaped. */
static int children_of(pid_t pid, int *zombies)
{
    DIR *d = opendir("/proc");
    ck_assert_ptr_nonnull(d);
    int n = 0;
    *zombies = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (e->d_name[0] < '1' || e->d_name[0] > '9') continue;
        char path[300], buf[1024];
        snprintf(path, sizeof path, "/proc/%s/stat", e->d_name);
        FILE *f = fopen(path, "r");
        if (!f) continue; /* (gone meanwhile) */
        size_t len = fread(buf, 1, sizeof buf - 1, f);
        fclose(f);
        buf[len] = 0;
        char *rp = strrchr(buf, ')'), state;
        long ppid;
        if (rp && sscanf(rp + 1, " %c %ld", &state, &ppid) == 2 && ppid == (long)pid) {
            n++;
            *zombies += state == 'Z';
        }
    }
    closedir(d);
    return n;
}

static int count_files(const char *fmt, const char *dir, int n)
{
    int c = 0;
    for (int k = 1; k <= n; k++) {
        char p[800];
        snprintf(p, sizeof p, fmt, dir, k);
        c += access(p, F_OK) == 0;
    }
    return c;
}

/* DIR/ensemble.json says status `want`. */
static void assert_manifest_status(const char *dir, const char *want)
{
    char man[700];
    snprintf(man, sizeof man, "%s/ensemble.json", dir);
    json_object *m = json_object_from_file(man);
    ck_assert_msg(m != NULL, "%s not readable", man);
    ck_assert_str_eq(jstr(m, "status"), want);
    json_object_put(m);
}

/* A signal that arrives after every specimen finished, before the
 * ensemble reaped the last one (or while it writes its result), marked
 * the whole ensemble interrupted (exit 143, status interrupted, the
 * manifest too) although every specimen had its result.  Made
 * deterministic: the ensemble is stopped (SIGSTOP) while its specimens
 * run, they are left to end (zombies, not yet reaped), SIGTERM is sent
 * while it is stopped and it is continued (SIGCONT): the handler runs
 * before it reaps them.  Every specimen finished: status equilibrium,
 * exit 0, the manifest says equilibrium. */
START_TEST(test_signal_after_last_specimen)
{
    char dir[600], o_path[600], e_path[600];
    snprintf(dir, sizeof dir, "%s/ens-late-signal", tu_scratch_dir());
    snprintf(o_path, sizeof o_path, "%s/late.stdout", tu_scratch_dir());
    snprintf(e_path, sizeof e_path, "%s/late.stderr", tu_scratch_dir());
    sh("rm -rf %s", dir);
    const char *const a[] = {"run", "-q", "../scenes/cusick.yaml", "--spacing", "3cm",
                             "--specimens", "2", "-j", "2", "--out", dir, NULL};
    pid_t pid = tu_spawn_drape(a, o_path, e_path, 0);
    /* stopped where every specimen not stored yet is running (or done) */
    struct timespec ts = {0, 200 * 1000};
    int ws, zombies = 0, ready = 0;
    for (int i = 0; i < 200000 && !ready; i++) {
        kill(pid, SIGSTOP);
        ck_assert_int_eq(waitpid(pid, &ws, WUNTRACED), pid);
        ck_assert_msg(WIFSTOPPED(ws), "drape ended before its specimens were seen (%d)", ws);
        int nc = children_of(pid, &zombies);
        ready = nc > 0 && nc + count_files("%s/specimen-%03d/result.txt", dir, 2) == 2;
        if (!ready) {
            kill(pid, SIGCONT);
            nanosleep(&ts, NULL);
        }
    }
    ck_assert_msg(ready, "never caught the specimens running");
    /* the specimens end; the stopped ensemble cannot reap them */
    struct timespec ms = {0, 1000 * 1000};
    int nc = children_of(pid, &zombies);
    for (int i = 0; i < 120000 && zombies < nc; i++) {
        nanosleep(&ms, NULL);
        nc = children_of(pid, &zombies);
    }
    ck_assert_msg(zombies == nc, "%d of %d specimens ended", zombies, nc);
    kill(pid, SIGTERM); /* pending while it is stopped */
    ws = tu_signal_and_reap(pid, SIGCONT, 0);
    tu_read_file(o_path, out, CAP);
    tu_read_file(e_path, err, CAP);
    ck_assert_msg(WIFEXITED(ws) && WEXITSTATUS(ws) == 0, "status %d, %s", ws, err);
    ck_assert_msg(!strstr(err, "interrupted"), "%s", err);
    json_object *g = parse(out), *sp;
    ck_assert_str_eq(jstr(g, "status"), "equilibrium");
    ck_assert_int_eq((int)jnum(g, "specimens_failed"), 0);
    ck_assert(json_object_object_get_ex(g, "specimens", &sp));
    for (int k = 0; k < 2; k++)
        ck_assert_str_eq(jstr(json_object_array_get_idx(sp, (size_t)k), "status"), "equilibrium");
    json_object_put(g);
    assert_manifest_status(dir, "equilibrium");
    ck_assert_int_eq(count_files("%s/specimen-%03d/result.txt", dir, 2), 2);
}
END_TEST

/* A signal while the ensemble writes its result, after every specimen
 * was collected: the handlers were restored before the summary, so a
 * SIGTERM then killed drape with the result half printed and the
 * manifest still "running".  Now the summary is written whole, exit 0.
 * Made deterministic: stdout is a pipe of one page that is not read, so
 * drape blocks in the middle of its result (32 specimens: about 6 kB);
 * the signal is sent while it is blocked there, then the pipe is read. */
START_TEST(test_signal_while_summary_written)
{
    char dir[600], o_path[64], e_path[600];
    snprintf(dir, sizeof dir, "%s/ens-summary-signal", tu_scratch_dir());
    snprintf(e_path, sizeof e_path, "%s/summary.stderr", tu_scratch_dir());
    sh("rm -rf %s", dir);
    int fd[2];
    ck_assert_int_eq(pipe(fd), 0);
    int cap = fcntl(fd[1], F_SETPIPE_SZ, 4096);
    ck_assert_msg(cap >= 4096 && cap < 6000, "pipe of %d bytes", cap);
    snprintf(o_path, sizeof o_path, "/proc/self/fd/%d", fd[1]);
    const char *const a[] = {"run", "-q", "../scenes/cusick.yaml", "--spacing", "3cm",
                             "--method", "static", "--specimens", "32", "-j", "2",
                             "--out", dir, NULL};
    pid_t pid = tu_spawn_drape(a, o_path, e_path, 0);
    close(fd[1]);
    /* the pipe full: drape is writing its result */
    int avail = 0, ws;
    struct timespec ms = {0, 1000 * 1000};
    for (int i = 0; i < 120000 && avail < cap; i++) {
        ck_assert_int_eq(ioctl(fd[0], FIONREAD, &avail), 0);
        ck_assert_msg(waitpid(pid, &ws, WNOHANG) == 0, "drape ended with the pipe not full");
        if (avail < cap) nanosleep(&ms, NULL);
    }
    ck_assert_msg(avail >= cap, "the pipe never filled (%d bytes)", avail);
    ck_assert_int_eq(count_files("%s/specimen-%03d/result.txt", dir, 32), 32);
    kill(pid, SIGTERM);
    nanosleep(&ms, NULL);
    size_t len = 0;
    ssize_t got;
    while ((got = read(fd[0], out + len, CAP - 1 - len)) > 0) len += (size_t)got;
    out[len] = 0;
    close(fd[0]);
    ck_assert_int_eq(waitpid(pid, &ws, 0), pid);
    tu_read_file(e_path, err, CAP);
    ck_assert_msg(WIFEXITED(ws) && WEXITSTATUS(ws) == 0, "status %d, %s", ws, err);
    json_object *g = parse(out);
    ck_assert_str_eq(jstr(g, "status"), "equilibrium");
    ck_assert_int_eq((int)jnum(g, "specimens_failed"), 0);
    json_object_put(g);
    assert_manifest_status(dir, "equilibrium");
}
END_TEST

/* Temporaries NAME.tmp.PID of ensemble.json, shadow.svg, shadow.png and
 * the specimens' result.txt, left by a part killed outright while it
 * wrote them, stayed in DIR forever.  Once it holds DIR, an ensemble (new
 * or resumed) removes exactly those (NAME.tmp. and digits), and nothing
 * else: not other names, nor other suffixes.  So are the frames', drape.h5's
 * and drape.xmf's (NAME.PID.tmp) that a single run killed in DIR left
 * (before, an ensemble removed them only in its specimens' directories). */
START_TEST(test_resume_stale_tmp)
{
    static const char *const stale[] = {
        "ensemble.json.tmp.12345", "shadow.svg.tmp.1", "shadow.png.tmp.987654321",
        "specimen-001/result.txt.tmp.4242", "specimen-003/result.txt.tmp.7",
        /* a single run killed in DIR before the ensemble */
        "frame_000002.obj.4242.tmp", "drape.h5.77.tmp", "drape.xmf.9.tmp", NULL};
    static const char *const kept[] = {
        "ensemble.json.tmp.", "ensemble.json.tmp.12a", "shadow.svg.tmp.5.bak", "shadow.svg.tmp-5",
        "xshadow.png.tmp.5", "notes.tmp.5", "specimen-001/result.txt.tmp.x1",
        "specimen-002/frame.tmp.3", "specimen-001/result.txt.5.tmp", "drape.h5.77x.tmp",
        "frame_2.obj.5.tmp", NULL};
    char dir[600], args[1400], ref[CAP], p[900];
    snprintf(dir, sizeof dir, "%s/ens-stale", tu_scratch_dir());
    for (int pass = 0; pass < 2; pass++) { /* 0: --resume; 1: a new ensemble */
        if (pass == 0) fall3(dir, ref);
        for (int i = 0; stale[i]; i++) sh("echo stale > %s/%s", dir, stale[i]);
        for (int i = 0; kept[i]; i++) sh("echo kept > %s/%s", dir, kept[i]);
        sh("rm %s/specimen-002/result.txt", dir);
        if (pass == 0) snprintf(args, sizeof args, "run -q --resume %s -j 2", dir);
        else
            snprintf(args, sizeof args, "run -q ../scenes/cusick.yaml --spacing 3cm "
                     "--specimens 3 -j 2 --out %s", dir);
        ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
        json_object *g = parse(out), *r = parse(ref);
        assert_same_ensemble(r, g);
        json_object_put(g);
        json_object_put(r);
        for (int i = 0; stale[i]; i++) {
            snprintf(p, sizeof p, "%s/%s", dir, stale[i]);
            ck_assert_msg(access(p, F_OK) != 0, "pass %d: %s is still there", pass, p);
        }
        for (int i = 0; kept[i]; i++) {
            snprintf(p, sizeof p, "%s/%s", dir, kept[i]);
            ck_assert_msg(access(p, F_OK) == 0, "pass %d: %s was removed", pass, p);
        }
    }
}
END_TEST

/* The frames', drape.h5's and drape.xmf's temporaries (NAME.PID.tmp)
 * that a specimen killed outright left in its directory stayed there
 * through every --resume; the ensemble now removes them with the
 * others once it holds DIR, and keeps the look-alikes. */
START_TEST(test_resume_stale_specimen_tmp)
{
    static const char *const stale[] = {
        "specimen-001/frame_000002.obj.4242.tmp", "specimen-002/drape.h5.77.tmp",
        "specimen-003/drape.xmf.987654321.tmp", NULL};
    static const char *const kept[] = {
        "specimen-001/frame_000002.obj.tmp.4242", "specimen-002/drape.h5.77x.tmp",
        "specimen-003/frame_2.obj.5.tmp", "drape.h5.77.tmp.old", NULL};
    char dir[600], args[1400], ref[CAP], p[900];
    snprintf(dir, sizeof dir, "%s/ens-stale-specimen", tu_scratch_dir());
    fall3(dir, ref);
    for (int i = 0; stale[i]; i++) sh("echo stale > %s/%s", dir, stale[i]);
    for (int i = 0; kept[i]; i++) sh("echo kept > %s/%s", dir, kept[i]);
    sh("rm %s/specimen-002/result.txt", dir);
    snprintf(args, sizeof args, "run -q --resume %s -j 2", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    json_object *g = parse(out), *r = parse(ref);
    assert_same_ensemble(r, g);
    json_object_put(g);
    json_object_put(r);
    for (int i = 0; stale[i]; i++) {
        snprintf(p, sizeof p, "%s/%s", dir, stale[i]);
        ck_assert_msg(access(p, F_OK) != 0, "%s is still there", p);
    }
    for (int i = 0; kept[i]; i++) {
        snprintf(p, sizeof p, "%s/%s", dir, kept[i]);
        ck_assert_msg(access(p, F_OK) == 0, "%s was removed", p);
    }
}
END_TEST

/* A dynamic specimen's checkpoint was continued by --resume whatever seed
 * it stored: one whose seed is not the manifest's seed + k (here 5 for
 * specimen 1 of seeds 1, 2; or none stored, for specimen 2) was taken as
 * that specimen's, and the ensemble reported seed 1 for a run of another
 * seed.  Now such a specimen runs again from the start (its first frame
 * written again), with a warning naming the checkpoint. */
START_TEST(test_resume_checkpoint_seed)
{
    char dir[600], w1[700], w2[700], args[1400], h5[700];
    snprintf(dir, sizeof dir, "%s/ens-ck-seed", tu_scratch_dir());
    snprintf(w1, sizeof w1, "%s/specimen-001/frame_000001.obj", dir);
    snprintf(w2, sizeof w2, "%s/specimen-002/frame_000001.obj", dir);
    sh("rm -rf %s", dir);
    pid_t pid = start_dynamic(dir, "2", NULL, NULL, 0);
    ck_assert_file_appears(pid, w1, 30.0);
    ck_assert_file_appears(pid, w2, 30.0);
    int ws = tu_signal_and_reap(pid, SIGTERM, 0);
    ck_assert_msg(WIFEXITED(ws) && WEXITSTATUS(ws) == 143, "status %d", ws);
    /* specimen 1's checkpoint says seed 5; specimen 2's has none */
    snprintf(h5, sizeof h5, "%s/specimen-001/drape.h5", dir);
    hid_t f = H5Fopen(h5, H5F_ACC_RDWR, H5P_DEFAULT);
    ck_assert(f >= 0);
    /* (replaced: HDF5 1.10 cannot write an attribute opened in dense
     * storage, "can't locate open attribute") */
    ck_assert(H5Adelete_by_name(f, "run", "seed", H5P_DEFAULT) >= 0);
    hid_t sp1 = H5Screate(H5S_SCALAR);
    hid_t a = H5Acreate_by_name(f, "run", "seed", H5T_IEEE_F64LE, sp1, H5P_DEFAULT, H5P_DEFAULT,
                                H5P_DEFAULT);
    ck_assert(a >= 0);
    double five = 5.0;
    ck_assert(H5Awrite(a, H5T_NATIVE_DOUBLE, &five) >= 0);
    H5Aclose(a);
    H5Sclose(sp1);
    H5Fclose(f);
    snprintf(h5, sizeof h5, "%s/specimen-002/drape.h5", dir);
    f = H5Fopen(h5, H5F_ACC_RDWR, H5P_DEFAULT);
    ck_assert(f >= 0);
    ck_assert(H5Adelete_by_name(f, "run", "seed", H5P_DEFAULT) >= 0);
    H5Fclose(f);
    ino_t frame1 = inode(dir, "specimen-001/frame_000000.obj");
    ino_t frame2 = inode(dir, "specimen-002/frame_000000.obj");

    snprintf(args, sizeof args, "run -q --resume %s -j 2", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    char want[900];
    snprintf(want, sizeof want, "drape: %s/specimen-001/drape.h5: warning: the checkpoint's seed "
             "is 5, not this specimen's 1", dir);
    ck_assert_msg(strstr(err, want), "%s", err);
    snprintf(want, sizeof want, "drape: %s/specimen-002/drape.h5: warning: the checkpoint's seed "
             "is not stored", dir);
    ck_assert_msg(strstr(err, want), "%s", err);
    /* run again from the start: frame 0 written anew */
    ck_assert(inode(dir, "specimen-001/frame_000000.obj") != frame1);
    ck_assert(inode(dir, "specimen-002/frame_000000.obj") != frame2);
    json_object *g = parse(out), *sp;
    ck_assert_str_eq(jstr(g, "status"), "equilibrium");
    ck_assert(json_object_object_get_ex(g, "specimens", &sp));
    for (int k = 0; k < 2; k++) {
        json_object *o = json_object_array_get_idx(sp, (size_t)k);
        ck_assert_int_eq((int)jnum(o, "seed"), k + 1);
        ck_assert_str_eq(jstr(o, "status"), "equilibrium");
    }
    json_object_put(g);
}
END_TEST

/* Replace attribute name of group grp in the HDF5 file path by a double
 * (v) or a string (text, when not NULL). */
static void h5_set_attr(const char *path, const char *grp, const char *name, double v,
                        const char *text)
{
    hid_t f = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
    ck_assert_msg(f >= 0, "cannot open %s", path);
    /* deleted and created anew (HDF5 1.10 cannot write an attribute
     * opened in dense storage) */
    ck_assert(H5Adelete_by_name(f, grp, name, H5P_DEFAULT) >= 0);
    hid_t sp = H5Screate(H5S_SCALAR), t = H5Tcopy(text ? H5T_C_S1 : H5T_IEEE_F64LE);
    if (text) ck_assert(H5Tset_size(t, H5T_VARIABLE) >= 0);
    hid_t a = H5Acreate_by_name(f, grp, name, t, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    ck_assert(a >= 0);
    if (text)
        ck_assert(H5Awrite(a, t, &text) >= 0);
    else
        ck_assert(H5Awrite(a, H5T_NATIVE_DOUBLE, &v) >= 0);
    H5Aclose(a);
    H5Tclose(t);
    H5Sclose(sp);
    H5Fclose(f);
}

/* A dynamic specimen's checkpoint was continued by --resume whatever CPU
 * time it stored: inf made the ensemble's cpu_s inf (null in the result,
 * inf in ensemble.json, which was then not JSON), nan, a negative one or
 * a text were taken silently.  Now such a checkpoint is damaged: a
 * warning names it, and the specimen runs again from the start (its
 * frame 0 written anew).  The ensemble is interrupted by SIGTERM from a
 * shell once each of its 4 specimens wrote frame 1. */
START_TEST(test_resume_checkpoint_cpu)
{
    static const double bad[] = {INFINITY, NAN, -1.0, 0.0};
    static const char *const shown[] = {"inf", "nan", "-1", NULL};
    const char *bin = getenv("DRAPE_BIN") ? getenv("DRAPE_BIN") : "../drape";
    char dir[600], args[1400], h5[700], want[900], fr[64];
    snprintf(dir, sizeof dir, "%s/ens-ck-cpu", tu_scratch_dir());
    sh("rm -rf '%s'; '%s' run -q ../scenes/cusick.yaml --spacing 5cm --method dynamic "
       "--specimens 4 -j 4 --out '%s' >/dev/null 2>&1 & p=$!; i=0; "
       "while [ $i -lt 3000 ] && { [ ! -e '%s/specimen-001/frame_000001.obj' ] || "
       "[ ! -e '%s/specimen-002/frame_000001.obj' ] || "
       "[ ! -e '%s/specimen-003/frame_000001.obj' ] || "
       "[ ! -e '%s/specimen-004/frame_000001.obj' ]; }; do sleep 0.01; i=$((i+1)); done; "
       "kill -TERM $p; wait $p; test $? = 143",
       dir, bin, dir, dir, dir, dir, dir);
    ino_t frame0[4];
    for (int k = 0; k < 4; k++) {
        snprintf(h5, sizeof h5, "%s/specimen-%03d/drape.h5", dir, k + 1);
        h5_set_attr(h5, "stats", "cpu_s", bad[k], k == 3 ? "12" : NULL);
        snprintf(fr, sizeof fr, "specimen-%03d/frame_000000.obj", k + 1);
        frame0[k] = inode(dir, fr);
    }
    snprintf(args, sizeof args, "run -q --resume '%s' -j 2", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    for (int k = 0; k < 4; k++) {
        if (shown[k])
            snprintf(want, sizeof want, "drape: %s/specimen-%03d/drape.h5: warning: the "
                     "checkpoint's cpu_s is %s, not a CPU time", dir, k + 1, shown[k]);
        else
            snprintf(want, sizeof want, "drape: %s/specimen-%03d/drape.h5: warning: the "
                     "checkpoint's cpu_s is not a number", dir, k + 1);
        ck_assert_msg(strstr(err, want), "want '%s' in: %s", want, err);
        snprintf(fr, sizeof fr, "specimen-%03d/frame_000000.obj", k + 1);
        ck_assert_msg(inode(dir, fr) != frame0[k], "specimen %d continued", k + 1);
    }
    json_object *g = parse(out);
    ck_assert_str_eq(jstr(g, "status"), "equilibrium");
    double cpu = jnum(g, "cpu_s");
    ck_assert_msg(isfinite(cpu) && cpu > 0, "cpu_s %.17g", cpu);
    json_object_put(g);
    snprintf(h5, sizeof h5, "%s/ensemble.json", dir);
    g = json_object_from_file(h5);
    ck_assert_msg(g != NULL, "%s is not JSON", h5);
    cpu = jnum(g, "cpu_s");
    ck_assert_msg(isfinite(cpu) && cpu > 0, "ensemble.json cpu_s %.17g", cpu);
    json_object_put(g);
}
END_TEST

Suite *specimens_resume_suite(void)
{
    Suite *s = suite_create("specimens_resume");
    TCase *tc = tcase_create("cli");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, test_resume_fall);
    tcase_add_test(tc, test_resume_refused);
    tcase_add_test(tc, test_resume_dynamic_interrupted);
    tcase_add_test(tc, test_resume_damaged_result);
    tcase_add_test(tc, test_resume_killed_cpu);
    tcase_add_test(tc, test_dir_in_use);
    suite_add_tcase(s, tc);
    TCase *quick = tcase_create("quick"); /* no specimen runs, or small fall ones */
    tcase_set_timeout(quick, 120);
    tcase_add_test(quick, test_resume_no_dir);
    tcase_add_test(quick, test_resume_damaged_header);
    tcase_add_test(quick, test_resume_result_numbers);
    tcase_add_test(quick, test_signal_after_last_specimen);
    tcase_add_test(quick, test_signal_while_summary_written);
    tcase_add_test(quick, test_resume_stale_tmp);
    tcase_add_test(quick, test_resume_result_seed);
    tcase_add_test(quick, test_resume_stale_specimen_tmp);
    suite_add_tcase(s, quick);
    TCase *seed = tcase_create("seed"); /* the checkpoints' seeds */
    tcase_set_timeout(seed, 120);
    tcase_add_test(seed, test_resume_checkpoint_seed);
    suite_add_tcase(s, seed);
    TCase *ck_cpu = tcase_create("checkpoint_cpu"); /* the checkpoints' CPU times */
    tcase_set_timeout(ck_cpu, 120);
    tcase_add_test(ck_cpu, test_resume_checkpoint_cpu);
    suite_add_tcase(s, ck_cpu);
    return s;
}

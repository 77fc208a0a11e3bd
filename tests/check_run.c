/* check_run.c: `drape run` end to end through the binary: the result's
 * contract keys, a clean failure, and frames that parse back to the final
 * state (OBJ and HDF5 read independently of the writers' code). */
#include <dirent.h>
#include <fcntl.h>
#include <hdf5.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "testutil.h"

#define CAP 65536
static char out[CAP], err[CAP];

/* Number after "key": in a flat JSON text; NAN for null or absent. */
static double json_num(const char *json, const char *key)
{
    char pat[128];
    snprintf(pat, sizeof pat, "\"%s\": ", key);
    const char *p = strstr(json, pat);
    if (!p) return NAN;
    p += strlen(pat);
    if (strncmp(p, "null", 4) == 0) return NAN;
    return strtod(p, NULL);
}

static const char *small_hang = "run -q ../scenes/hang.yaml --spacing 5cm --t-max 0.1s";

START_TEST(test_contract_keys)
{
    char args[512];
    snprintf(args, sizeof args, "%s", small_hang);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
    static const char *keys[] = {
        "fabric", "scene", "integrator", "energy_form", "rtol", "atol", "spacing_m",
        "particles", "free_particles", "status", "t_end_s", "dc", "nodes", "r_min_m",
        "r_max_m", "tip_angle_deg", "bending_length_m", "flexural_rigidity_Nm",
        "energy_J", "kinetic", "stretch", "bend", "shear", "gravity", "max_strain",
        "wall_s", "steps", "rhs_evals", "jac_evals", "lin_setups", "nonlin_iters",
        "err_test_fails", "conv_fails"};
    for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++) {
        char pat[64];
        snprintf(pat, sizeof pat, "\"%s\": ", keys[i]);
        ck_assert_msg(strstr(out, pat) != NULL, "key %s missing in %s", keys[i], out);
    }
    ck_assert_ptr_nonnull(strstr(out, "\"status\": \"t_max\""));
    /* 30 cm square at 5 cm: 7 x 7 particles, two pinned */
    ck_assert_int_eq((int)json_num(out, "particles"), 49);
    ck_assert_int_eq((int)json_num(out, "free_particles"), 47);
    ck_assert_close_rel(json_num(out, "t_end_s"), 0.1, 1e-12);
    ck_assert_close_rel(json_num(out, "spacing_m"), 0.05, 1e-12);
    /* a hang scene has no drape coefficient and no cantilever */
    ck_assert(isnan(json_num(out, "dc")));
    ck_assert(isnan(json_num(out, "tip_angle_deg")));
    /* falling from rest: gravity energy went down, kinetic energy up */
    ck_assert(json_num(out, "gravity") < 0);
    ck_assert(json_num(out, "kinetic") > 0);

    /* CSV: header and one row with the same number of fields */
    snprintf(args, sizeof args, "%s --format csv", small_hang);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
    char *nl = strchr(out, '\n');
    ck_assert_ptr_nonnull(nl);
    int h = 0, r = 0;
    for (char *p = out; p < nl; p++) h += *p == ',';
    for (char *p = nl + 1; *p && *p != '\n'; p++) r += *p == ',';
    ck_assert_int_eq(h, r);
    ck_assert_ptr_nonnull(strstr(out, "energy_J_kinetic"));
}
END_TEST

START_TEST(test_failure_is_clean)
{
    char args[512];
    snprintf(args, sizeof args, "%s --max-steps 5", small_hang);
    int st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_int_eq(st, 4);
    ck_assert_ptr_nonnull(strstr(out, "\"status\": \"failed\""));
    ck_assert_msg(strstr(err, "cvode-bdf failed at t = ") != NULL, "%s", err);
    ck_assert_ptr_null(strstr(out, "nan"));
    ck_assert_ptr_null(strstr(out, "inf"));
}
END_TEST

/* Positions of an OBJ file, mapped back from Y-up: obj (X, Y, Z) = (x, z, -y). */
static int read_obj(const char *path, double *x, int cap)
{
    FILE *f = fopen(path, "r");
    if (!f) return -1;
    char line[512];
    int n = 0;
    while (fgets(line, sizeof line, f)) {
        double a, b, c;
        if (line[0] == 'v' && line[1] == ' ' && sscanf(line + 2, "%lf %lf %lf", &a, &b, &c) == 3) {
            if (n >= cap) break;
            x[3 * n] = a;
            x[3 * n + 1] = -c;
            x[3 * n + 2] = b;
            n++;
        }
    }
    fclose(f);
    return n;
}

START_TEST(test_frames_parse_back)
{
    char dir[600], args[1024], path[800];
    snprintf(dir, sizeof dir, "%s/run-out", tu_scratch_dir());
    snprintf(args, sizeof args, "%s --out '%s'", small_hang, dir);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);

    /* frames at 0, 1/30, 2/30, 3/30 s (the scene says every 1/30 s) */
    int n_obj = 0, n_tmp = 0;
    DIR *d = opendir(dir);
    ck_assert_ptr_nonnull(d);
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        n_obj += strncmp(e->d_name, "frame_", 6) == 0 && strstr(e->d_name, ".obj") != NULL;
        n_tmp += strstr(e->d_name, ".tmp") != NULL;
    }
    closedir(d);
    ck_assert_int_eq(n_obj, 4);
    ck_assert_int_eq(n_tmp, 0);

    /* HDF5: /final/positions is the final state; the last frame equals it */
    snprintf(path, sizeof path, "%s/drape.h5", dir);
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    ck_assert_msg(f >= 0, "cannot open %s", path);
    double xf[49 * 3], xs[49 * 3], xo[49 * 3];
    hid_t ds = H5Dopen2(f, "/final/positions", H5P_DEFAULT);
    ck_assert(ds >= 0);
    hid_t sp = H5Dget_space(ds);
    hsize_t dims[2];
    ck_assert_int_eq(H5Sget_simple_extent_ndims(sp), 2);
    H5Sget_simple_extent_dims(sp, dims, NULL);
    ck_assert_int_eq((int)dims[0], 49);
    ck_assert_int_eq((int)dims[1], 3);
    ck_assert(H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, xf) >= 0);
    H5Sclose(sp);
    H5Dclose(ds);
    ds = H5Dopen2(f, "/steps/000003/positions", H5P_DEFAULT);
    ck_assert(ds >= 0);
    ck_assert(H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, xs) >= 0);
    H5Dclose(ds);
    H5Fclose(f);
    for (int i = 0; i < 49 * 3; i++) ck_assert_msg(xs[i] == xf[i], "h5 frame 3 differs at %d", i);

    /* OBJ frame 3 carries the same positions to its printed precision */
    snprintf(path, sizeof path, "%s/frame_000003.obj", dir);
    ck_assert_int_eq(read_obj(path, xo, 49), 49);
    for (int i = 0; i < 49 * 3; i++) ck_assert_close_abs(xo[i], xf[i], 1e-8);
    /* the pinned corners (j = last row) did not move from z = 0 and the cloth fell */
    double zmin = 0;
    for (int i = 0; i < 49; i++) zmin = fmin(zmin, xf[3 * i + 2]);
    ck_assert(zmin < -0.01); /* free fall over 0.1 s alone gives 4.9 cm */
    /* the XDMF sidecar refers to the HDF5 file by a relative path */
    snprintf(path, sizeof path, "%s/drape.xmf", dir);
    FILE *x = fopen(path, "r");
    ck_assert_ptr_nonnull(x);
    size_t k = fread(out, 1, CAP - 1, x);
    out[k] = 0;
    fclose(x);
    ck_assert_ptr_nonnull(strstr(out, "drape.h5:/steps/000003/positions"));
}
END_TEST

START_TEST(test_output_dir_errors)
{
    /* an output path that is a file: I/O error, status 3, nothing printed */
    const char *file = tu_write_file("not-a-dir", "x");
    char args[1024];
    snprintf(args, sizeof args, "%s --out '%s'", small_hang, file);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 3);
    ck_assert_str_eq(out, "");
    ck_assert_ptr_nonnull(strstr(err, "not-a-dir"));

    /* a scene that asks for no output (the cantilever): said, and no empty
     * directory is left behind */
    {
        char dir[600];
        snprintf(dir, sizeof dir, "%s/nothing-asked", tu_scratch_dir());
        snprintf(args, sizeof args, "run -q ../scenes/cantilever.yaml --out '%s'", dir);
        ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
        ck_assert_msg(strstr(err, "output: warning: --out: the scene asks for no frames"), "%s",
                      err);
        ck_assert_msg(access(dir, F_OK) != 0, "%s was left behind", dir);
    }

    /* a directory where drape.h5 or drape.xmf is to be renamed at the end:
     * refused before the run (it was found at the end, the computation
     * lost and the frames left behind) */
    static const char *const block[] = {"drape.h5", "drape.xmf"};
    for (int k = 0; k < 2; k++) {
        char dir[600], cmd[1400];
        snprintf(dir, sizeof dir, "%s/blocked-%d", tu_scratch_dir(), k);
        snprintf(cmd, sizeof cmd, "rm -rf '%s' && mkdir -p '%s/%s'", dir, dir, block[k]);
        ck_assert_int_eq(system(cmd), 0);
        snprintf(args, sizeof args, "%s --out '%s'", small_hang, dir);
        ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 3);
        ck_assert_str_eq(out, "");
        ck_assert_msg(strstr(err, block[k]) && strstr(err, "in the way"), "%s", err);
        snprintf(cmd, sizeof cmd, "test \"$(ls '%s')\" = %s", dir, block[k]);
        ck_assert_msg(system(cmd) == 0, "%s holds more than %s", dir, block[k]);
    }
}
END_TEST

/* The default Cusick scene by the static method: a certified minimum with
 * the residual below its tolerance, a drape coefficient strictly between
 * "hanging straight down" (0) and "undeformed" (1), and the potential
 * energy below the flat state's (0: gravity is measured from z = 0). */
START_TEST(test_cusick_static_equilibrium)
{
    ck_assert_int_eq(tu_run_drape("run -q ../scenes/cusick.yaml --method static --specimens 1", out, CAP, err,
                                  CAP), 0);
    ck_assert_ptr_nonnull(strstr(out, "\"status\": \"equilibrium\""));
    ck_assert_ptr_nonnull(strstr(out, "\"certified\": \"minimum\""));
    ck_assert_ptr_nonnull(strstr(out, "\"method\": \"static\""));
    double dc = json_num(out, "dc");
    ck_assert_msg(dc > 0.0 && dc < 1.0, "dc = %g", dc);
    ck_assert(json_num(out, "max_force_rel") <= 1e-8);
    ck_assert(json_num(out, "min_pivot_N_m") > 0);
    double e = json_num(out, "stretch") + json_num(out, "bend") + json_num(out, "shear") +
               json_num(out, "gravity");
    ck_assert_msg(e < 0, "E_pot = %g J", e);
    /* the shadow lies between the support disk (r = 9 cm) and the specimen (15 cm) */
    ck_assert(json_num(out, "r_min_m") > 0.09 && json_num(out, "r_max_m") <= 0.15);
}
END_TEST

/* The default Cusick scene run the way it asks, in time with its own
 * integrator (arkode-imex) and tolerances, at 2 cm so that it fits in the
 * suite (about 25 s CPU; the 1 cm run is `make check-default`, in CI):
 * status equilibrium before t_max with the settle speed below the scene's
 * 1e-4 m/s, and the same drape as the static method finds: at 2 cm the
 * Cusick minimum is unique (docs/equilibrium.md), and the static solver is
 * an independent code path (Newton on the energy gradient, no time). */
START_TEST(test_cusick_dynamic_equilibrium)
{
    ck_assert_int_eq(tu_run_drape("run -q ../scenes/cusick.yaml --spacing 2cm --method dynamic "
                                  "--specimens 1", out, CAP, err, CAP), 0);
    ck_assert_ptr_nonnull(strstr(out, "\"integrator\": \"arkode-imex\""));
    double t_end = json_num(out, "t_end_s");
    ck_assert_msg(t_end > 0.2 && t_end < 20.0, "t_end_s = %g", t_end);
    ck_assert_double_lt(json_num(out, "mean_speed_m_s"), 1e-4);
    double dc_dyn = json_num(out, "dc");
    ck_assert_int_eq(tu_run_drape("run -q ../scenes/cusick.yaml --spacing 2cm --method static --specimens 1",
                                  out, CAP, err, CAP), 0);
    double dc_static = json_num(out, "dc");
    ck_assert_msg(fabs(dc_dyn - dc_static) < 0.005, "dynamic DC %.6f, static %.6f", dc_dyn,
                  dc_static);
}
END_TEST

/* ---- interruption and resume (issue 7) ----------------------------------- */

/* A 20 cm cotton square at 2 cm (121 particles), pinned at two corners,
 * damped (5/s) so it does not buckle: 2 s take ~1.4 s CPU; frames every
 * 0.05 s (41), OBJ and HDF5. */
#define IR_T_MAX 2.0
#define IR_FRAMES 41
#define IR_RTOL 1e-4
#define IR_ATOL 1e-7
#define IR_SIDE 0.2

static const char *ir_scene(void)
{
    char cwd[512], text[2048];
    ck_assert_ptr_nonnull(getcwd(cwd, sizeof cwd));
    snprintf(text, sizeof text,
             "scene: hang\n"
             "fabric: %s/../fabrics/cotton-breen.yaml\n"
             "specimen: {shape: rectangle, width: 20 cm, height: 20 cm}\n"
             "spacing: 2 cm\n"
             "pins: [[0, -1], [-1, -1]]\n"
             "damping: {air: 5 1/s}\n"
             "solver: {integrator: cvode-bdf, rtol: %g, atol: %g}\n"
             "end: {t_max: %g s}\n"
             "output: {frames: {every: 0.05 s, obj: true}, hdf5: true}\n",
             cwd, IR_RTOL, IR_ATOL, IR_T_MAX);
    return tu_write_file("interrupt.yaml", text);
}

/* 1: run_and_signal starts drape in a process group of its own and
 * signals the whole group, as a terminal's Ctrl-C or `timeout` do */
static int signal_group;

/* Runs `drape ARGS...` (NULL-terminated), sends sig once the file
 * wait_for exists (or, with wait_for NULL, after one second), and returns
 * the exit status (-1 if it did not exit); out and err (CAP) get its
 * stdout and stderr. */
static int run_and_signal(const char *wait_for, int sig, const char *const *args)
{
    char o_path[600], e_path[600];
    snprintf(o_path, sizeof o_path, "%s/sig.stdout", tu_scratch_dir());
    snprintf(e_path, sizeof e_path, "%s/sig.stderr", tu_scratch_dir());
    pid_t pid = tu_spawn_drape(args, o_path, e_path, signal_group);
    if (wait_for) ck_assert_file_appears(pid, wait_for, 30.0);
    else ck_assert_msg(tu_wait_file(pid, NULL, 1.0) == 0, "drape ended within 1 s");
    int ws = tu_signal_and_reap(pid, sig, signal_group);
    tu_read_file(o_path, out, CAP);
    tu_read_file(e_path, err, CAP);
    return WIFEXITED(ws) ? WEXITSTATUS(ws) : -1;
}

static int count_prefix(const char *dir, const char *prefix, const char *part)
{
    DIR *d = opendir(dir);
    ck_assert_ptr_nonnull(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        n += strncmp(e->d_name, prefix, strlen(prefix)) == 0 &&
             (!part || strstr(e->d_name, part) != NULL);
    closedir(d);
    return n;
}

static void h5_read(const char *path, const char *name, double *buf, int n)
{
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    ck_assert_msg(f >= 0, "cannot open %s", path);
    hid_t ds = H5Dopen2(f, name, H5P_DEFAULT);
    ck_assert_msg(ds >= 0, "%s: no %s", path, name);
    hid_t sp = H5Dget_space(ds);
    ck_assert_int_eq((int)H5Sget_simple_extent_npoints(sp), n);
    H5Sclose(sp);
    ck_assert(H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0);
    H5Dclose(ds);
    H5Fclose(f);
}

/* /stats attribute `status` of a drape.h5. */
static void h5_status(const char *path, char *buf, size_t n)
{
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    ck_assert_msg(f >= 0, "cannot open %s", path);
    hid_t a = H5Aopen_by_name(f, "stats", "status", H5P_DEFAULT, H5P_DEFAULT);
    ck_assert(a >= 0);
    hid_t t = H5Aget_type(a);
    char *s = NULL;
    ck_assert(H5Aread(a, t, &s) >= 0);
    snprintf(buf, n, "%s", s);
    H5free_memory(s);
    H5Tclose(t);
    H5Aclose(a);
    H5Fclose(f);
}

/* SIGINT after the first frame: status interrupted, exit 130, valid files;
 * --resume, stopped again by SIGTERM (143) after one more frame; --resume
 * to the end.  The result must be the uninterrupted run's: the same frame
 * times, the frames before the first interruption bit for bit (the same
 * computation), the final state within the tolerance (a restart changes
 * only the step sizes: the runs differ by less than their own global
 * errors, see below; a resume from a wrong time or without the
 * velocities is off by centimetres). */
/* A shorter run into the directory of a longer one: the longer run's
 * later frames are removed once the new run is complete (a renderer
 * loading frame_*.obj mixed the two runs), and drape says so. */
START_TEST(test_stale_frames_removed)
{
    char dir[600], args[1400];
    snprintf(dir, sizeof dir, "%s/stale", tu_scratch_dir());
    snprintf(args, sizeof args, "run -q ../scenes/hang.yaml --spacing 5cm --t-max 0.2s --out '%s'",
             dir);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
    int before = count_prefix(dir, "frame_", ".obj");
    ck_assert_int_eq(before, 7); /* 0 .. 0.2 s every 1/30 s */
    snprintf(args, sizeof args, "run -q ../scenes/hang.yaml --spacing 5cm --t-max 0.05s --out '%s'",
             dir);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
    ck_assert_int_eq(count_prefix(dir, "frame_", ".obj"), 3); /* 0, 1/30 s, 0.05 s */
    ck_assert_msg(strstr(err, "removed 4 frames of an earlier run (from frame_000003.obj)"), "%s",
                  err);
}
END_TEST

/* A signal stops the run within the output interval, not at its end: one
 * interval of 50 s of cloth motion (hours of stepping); SIGTERM once the
 * t = 0 frame exists must end the run with status interrupted at t = 0,
 * the last output point.  Without the check in the right-hand side the run
 * would go on to t = 50 s (and this test would time out). */
START_TEST(test_interrupt_within_interval)
{
    char cwd[512], text[2048], dir[600], wait_for[700];
    ck_assert_ptr_nonnull(getcwd(cwd, sizeof cwd));
    snprintf(text, sizeof text,
             "scene: hang\n"
             "fabric: %s/../fabrics/cotton-breen.yaml\n"
             "specimen: {shape: rectangle, width: 20 cm, height: 20 cm}\n"
             "spacing: 2 cm\n"
             "pins: [[0, -1], [-1, -1]]\n"
             "solver: {integrator: cvode-bdf, rtol: 1e-8, atol: 1e-11}\n"
             "end: {t_max: 100 s}\n"
             "output: {frames: {every: 50 s, obj: true}, hdf5: true}\n",
             cwd);
    const char *scene = tu_write_file("long-interval.yaml", text);
    snprintf(dir, sizeof dir, "%s/long-interval", tu_scratch_dir());
    snprintf(wait_for, sizeof wait_for, "%s/frame_000000.obj", dir);
    const char *a[] = {"run", "-q", scene, "--out", dir, NULL};
    int code = run_and_signal(wait_for, SIGTERM, a);
    ck_assert_msg(code == 143, "exit %d (want 143), stderr: %s", code, err);
    ck_assert_msg(strstr(out, "\"status\": \"interrupted\""), "%s", out);
    ck_assert_double_eq(json_num(out, "t_end_s"), 0.0);
}
END_TEST

/* Total energy (kinetic + potential, J) of a run's JSON result. */
static double json_energy(const char *json)
{
    return json_num(json, "kinetic") + json_num(json, "stretch") + json_num(json, "bend") +
           json_num(json, "shear") + json_num(json, "gravity");
}

/* arkode-imex on a limp strip that folds over its pinned middle row
 * (tests/hard/folded.yaml with the limp silk, air drag on, to 1.4 s).
 * Expected, independent of arkode-imex: a strip hanging under its own
 * weight stretches by about W g L / k, strain ~1e-5 (so below 1e-3), and
 * the total energy at the end matches that of arkode-dirk (another
 * method, same model) within 0.005 M g L.  With SUNDIALS' default Newton
 * tolerance the Newton error of each stage, evaluated again in the
 * implicit stretch, pumped energy into the stretch modes: strain 3.6e-3
 * and an end energy 0.077 M g L above arkode-dirk's. */
START_TEST(test_imex_limp_fold)
{
    const char *base = "run -q ../tests/hard/folded.yaml --fabric ../tests/hard/silk-limp.yaml "
                       "--t-max 1.4s --integrator";
    char args[512];
    snprintf(args, sizeof args, "%s arkode-dirk", base);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
    double e_dirk = json_energy(out);
    double mgl = json_num(out, "mass_kg") * 9.80665 * 0.4; /* the strip is 40 cm long */
    ck_assert_msg(isfinite(e_dirk) && mgl > 0, "%s", out);
    snprintf(args, sizeof args, "%s arkode-imex", base);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
    ck_assert_msg(strstr(out, "\"status\": \"t_max\""), "%s", out);
    double strain = json_num(out, "max_strain");
    ck_assert_msg(strain < 1e-3, "arkode-imex: strain %g on a limp strip under its own weight",
                  strain);
    double e_imex = json_energy(out);
    ck_assert_msg(fabs(e_imex - e_dirk) < 0.005 * mgl,
                  "energy at 1.4 s: arkode-imex %g J, arkode-dirk %g J (M g L = %g J)", e_imex,
                  e_dirk, mgl);
}
END_TEST

/* The static method stops at its next iteration: the default table scene
 * (3721 particles; its whole solve takes about 80 iterations and 8 s)
 * signalled after 1 s ends with status interrupted, exit 143, nothing
 * written, after fewer iterations than the same solve run to the end.
 * Before the stop flag reached the solver, the signal took effect only
 * when the solve returned, with every iteration done. */
START_TEST(test_interrupt_static)
{
    char dir[600];
    snprintf(dir, sizeof dir, "%s/static-interrupted", tu_scratch_dir());
    const char *a[] = {"run", "-q", "../scenes/table.yaml", "--method", "static", "--specimens",
                       "1", "--out", dir, NULL};
    int code = run_and_signal(NULL, SIGTERM, a);
    ck_assert_msg(code == 143, "exit %d (want 143), stderr: %s", code, err);
    ck_assert_msg(strstr(out, "\"status\": \"interrupted\""), "%s", out);
    ck_assert_msg(strstr(err, "during the static solve; nothing written"), "%s", err);
    ck_assert_msg(access(dir, F_OK) != 0, "%s was left behind", dir);
    double it_stopped = json_num(out, "iterations");
    ck_assert_int_eq(tu_run_drape("run -q ../scenes/table.yaml --method static --specimens 1", out, CAP, err,
                                  CAP),
                     0);
    double it_full = json_num(out, "iterations");
    ck_assert_msg(it_stopped >= 0 && it_stopped < it_full,
                  "interrupted after %g iterations, the whole solve takes %g", it_stopped,
                  it_full);
}
END_TEST

/* A static run whose rest state the certification calls a saddle says so
 * on stderr (exit 0 and "certified": "saddle" as before); one certified a
 * minimum does not.  Strips hung from one corner have a zero mode (their
 * turn about the vertical), labelled either way by roundoff
 * (docs/equilibrium.md, "Zero modes": six of these twelve were saddles
 * there): each result is checked for the warning exactly when it says
 * saddle, and both labels must occur among the twelve. */
START_TEST(test_static_saddle_warns)
{
    static const int wh[][2] = {{3, 8}, {3, 10}, {3, 12}, {4, 8},  {4, 10}, {4, 12},
                                {5, 8}, {5, 10}, {5, 12}, {6, 8}, {6, 10}, {6, 12}};
    int saddles = 0, minima = 0;
    char cwd[512]; /* the tests run in tests/ */
    ck_assert_ptr_nonnull(getcwd(cwd, sizeof cwd));
    for (size_t k = 0; k < sizeof wh / sizeof wh[0]; k++) {
        char text[1024], args[1200];
        snprintf(text, sizeof text,
                 "scene: hang\n"
                 "fabric: %s/../fabrics/cotton-breen.yaml\n"
                 "specimen: {shape: rectangle, width: %d cm, height: %d cm}\n"
                 "spacing: 1 cm\n"
                 "pins: [[0, -1]]\n"
                 "model: {energy_form: consistent, terms: [stretch, bend, shear, gravity]}\n"
                 "damping: {air: 0.5 1/s}\n"
                 "end: {t_max: 3 s}\n",
                 cwd, wh[k][0], wh[k][1]);
        snprintf(args, sizeof args, "run -q %s --method static", tu_write_file("strip.yaml", text));
        ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
        int saddle = strstr(out, "\"certified\": \"saddle\"") != NULL;
        ck_assert_msg(saddle || strstr(out, "\"certified\": \"minimum\""), "%s", out);
        int warned = strstr(err, "saddle point, not a stable drape") != NULL;
        ck_assert_msg(warned == saddle, "%d x %d cm: certified %s, stderr: %s", wh[k][0],
                      wh[k][1], saddle ? "saddle" : "minimum", err);
        saddles += saddle;
        minima += !saddle;
    }
    ck_assert_msg(saddles > 0 && minima > 0, "%d saddles, %d minima", saddles, minima);
}
END_TEST

/* An ensemble stops on SIGTERM sent to drape alone: the parent passes it
 * to the running specimens, prints the ensemble with status interrupted and
 * exits 143; no specimen counts as failed. */
START_TEST(test_interrupt_ensemble)
{
    const char *a[] = {"run", "-q", "../scenes/cusick.yaml", "--spacing", "2cm", "--method",
                       "dynamic", "--specimens", "4", "-j", "2", NULL};
    int code = run_and_signal(NULL, SIGTERM, a);
    ck_assert_msg(code == 143, "exit %d (want 143), stderr: %s", code, err);
    ck_assert_msg(strstr(out, "\"status\": \"interrupted\""), "%s", out);
    ck_assert_msg(strstr(err, "not resumable"), "%s", err);
    ck_assert_int_eq((int)json_num(out, "specimens_failed"), 0);
    /* what was run, from the parent when no specimen had finished (a 2 cm
     * dynamic specimen takes several seconds): these were null */
    ck_assert_msg(strstr(out, "\"fabric\": \"cotton-breen\"") &&
                      strstr(out, "\"scene\": \"cusick\""), "%s", out);
    ck_assert_msg(json_num(out, "spacing_m") == 0.02, "%s", out);
}
END_TEST

/* Ctrl-C or `timeout` signal the whole process group: each specimen gets
 * the signal from the terminal and again from the ensemble, which passes
 * it on.  The second one killed a specimen outright (its handler was reset
 * after the first), leaving DIR/specimen-00k/drape.h5.PID.tmp and counting
 * it failed: now every specimen stops at its next poll. */
START_TEST(test_interrupt_ensemble_group)
{
    char dir[600], cmd[1400];
    snprintf(dir, sizeof dir, "%s/ens-group", tu_scratch_dir());
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    ck_assert_int_eq(system(cmd), 0);
    const char *a[] = {"run", "-q", "../scenes/cusick.yaml", "--spacing", "2cm", "--method",
                       "dynamic", "--specimens", "2", "-j", "2", "--out", dir, NULL};
    signal_group = 1;
    int code = run_and_signal(NULL, SIGTERM, a);
    signal_group = 0;
    ck_assert_msg(code == 143, "exit %d (want 143), stderr: %s", code, err);
    ck_assert_msg(strstr(out, "\"status\": \"interrupted\""), "%s", out);
    ck_assert_msg(json_num(out, "specimens_failed") == 0, "%s", out);
    snprintf(cmd, sizeof cmd, "test -z \"$(find '%s' -name '*.tmp')\"", dir);
    ck_assert_msg(system(cmd) == 0, "temporary files left in %s", dir);
}
END_TEST

/* The links of test_out_no_symlink: at dir/NAME.PID.tmp of the process
 * that calls link_tmp_names (drape, once it execs), each to victim. */
typedef struct symlink_at {
    const char *dir, *victim;
} symlink_at;

static int link_tmp_names(void *arg)
{
    const symlink_at *s = arg;
    static const char *const names[] = {"frame_000000.obj", "drape.h5", "drape.xmf"};
    char l[800];
    for (int k = 0; k < 3; k++) {
        snprintf(l, sizeof l, "%s/%s.%ld.tmp", s->dir, names[k], (long)getpid());
        if (symlink(s->victim, l) != 0) return -1;
    }
    return 0;
}

/* A symbolic link at the name of a frame's or drape.h5's temporary file
 * (NAME.PID.tmp: predictable) is not written through: the file it points
 * to stays as it was, and the outputs are regular files. */
START_TEST(test_out_no_symlink)
{
    char dir[600], victim[600], cmd[4200];
    snprintf(dir, sizeof dir, "%s/symlinked", tu_scratch_dir());
    snprintf(victim, sizeof victim, "%s/victim.txt", tu_scratch_dir());
    snprintf(cmd, sizeof cmd, "rm -rf '%s' && mkdir -p '%s' && echo keep > '%s'", dir, dir,
             victim);
    ck_assert_int_eq(system(cmd), 0);
    const char *const a[] = {"run", "-q", "../scenes/hang.yaml", "--spacing", "5cm",
                             "--t-max", "0.05s", "--out", dir, NULL};
    symlink_at links = {dir, victim};
    pid_t pid = tu_spawn_drape_hook(a, NULL, NULL, 0, link_tmp_names, &links);
    int ws = tu_signal_and_reap(pid, 0, 0);
    ck_assert_msg(WIFEXITED(ws) && WEXITSTATUS(ws) == 0, "status %d", ws);
    snprintf(cmd, sizeof cmd, "test \"$(cat '%s')\" = keep && test -f '%s/drape.h5' && "
             "test ! -L '%s/drape.h5' && test ! -L '%s/frame_000000.obj' && "
             "test -z \"$(find '%s' -name '*.tmp')\"", victim, dir, dir, dir, dir);
    ck_assert_msg(system(cmd) == 0, "%s", cmd);
}
END_TEST

START_TEST(test_interrupt_and_resume)
{
    const char *scene = ir_scene();
    char dir[600], ref[600], wait_for[700], h5[700], h5ref[700], args[2048], st[64];
    snprintf(dir, sizeof dir, "%s/interrupted", tu_scratch_dir());
    snprintf(ref, sizeof ref, "%s/uninterrupted", tu_scratch_dir());
    snprintf(h5, sizeof h5, "%s/drape.h5", dir);
    snprintf(h5ref, sizeof h5ref, "%s/drape.h5", ref);
    const int n = 121;

    /* 1. SIGINT */
    snprintf(wait_for, sizeof wait_for, "%s/frame_000000.obj", dir);
    const char *a1[] = {"run", "-q", scene, "--out", dir, NULL};
    int code = run_and_signal(wait_for, SIGINT, a1);
    ck_assert_msg(code == 130, "exit %d (want 130), stderr: %s", code, err);
    ck_assert_msg(strstr(out, "\"status\": \"interrupted\""), "%s", out);
    ck_assert_msg(strstr(err, "--resume"), "%s", err);
    double t1 = json_num(out, "t_end_s");
    ck_assert(t1 >= 0.0 && t1 < IR_T_MAX);
    ck_assert_int_eq(count_prefix(dir, "", ".tmp"), 0);
    h5_status(h5, st, sizeof st);
    ck_assert_str_eq(st, "interrupted");
    int f1 = count_prefix(dir, "frame_", ".obj");
    double tf[IR_FRAMES];
    ck_assert_int_ge(f1, 1);
    h5_read(h5, "/times", tf, f1); /* as many HDF5 frames as OBJ files */
    ck_assert_close_abs(tf[f1 - 1], 0.05 * (f1 - 1), 1e-12);
    ck_assert(tf[f1 - 1] <= t1 + 1e-12);

    /* 2. resumed, then SIGTERM once it wrote a frame of its own */
    snprintf(wait_for, sizeof wait_for, "%s/frame_%06d.obj", dir, f1);
    const char *a2[] = {"run", "--resume", dir, NULL};
    code = run_and_signal(wait_for, SIGTERM, a2);
    ck_assert_msg(code == 143, "exit %d (want 143), stderr: %s", code, err);
    ck_assert_msg(strstr(out, "\"status\": \"interrupted\""), "%s", out);
    double t2 = json_num(out, "t_end_s");
    ck_assert(t2 > t1 && t2 < IR_T_MAX);

    /* 3. resumed to the end */
    snprintf(args, sizeof args, "run --resume '%s' --format json", dir);
    code = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(code == 0, "exit %d, stderr: %s", code, err);
    ck_assert_msg(strstr(out, "\"status\": \"t_max\""), "%s", out);
    ck_assert_close_rel(json_num(out, "t_end_s"), IR_T_MAX, 1e-12);
    h5_status(h5, st, sizeof st);
    ck_assert_str_eq(st, "t_max");
    ck_assert_int_eq(count_prefix(dir, "frame_", ".obj"), IR_FRAMES);
    ck_assert_int_eq(count_prefix(dir, "", ".tmp"), 0);
    double e0_resumed = json_num(out, "energy_total_start_J");
    double rise_resumed = json_num(out, "energy_max_rise_J");

    /* the uninterrupted run */
    snprintf(args, sizeof args, "run -q '%s' --out '%s'", scene, ref);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
    /* the energy balance of the resumed run covers the whole run, from the
     * flat start (it began again at the last resume, 6 mJ below) */
    ck_assert_msg(fabs(e0_resumed - json_num(out, "energy_total_start_J")) < 1e-12,
                  "start energy %g, uninterrupted %g", e0_resumed,
                  json_num(out, "energy_total_start_J"));
    ck_assert_msg(isfinite(rise_resumed) && rise_resumed <= 1e-9, "rise %g", rise_resumed);
    double tr[IR_FRAMES], a[3 * 121], b[3 * 121];
    h5_read(h5, "/times", tf, IR_FRAMES);
    h5_read(h5ref, "/times", tr, IR_FRAMES);
    for (int k = 0; k < IR_FRAMES; k++) ck_assert(tf[k] == tr[k]);
    for (int k = 0; k < f1; k++) {
        char name[64];
        snprintf(name, sizeof name, "/steps/%06d/positions", k);
        h5_read(h5, name, a, 3 * n);
        h5_read(h5ref, name, b, 3 * n);
        for (int i = 0; i < 3 * n; i++) ck_assert_msg(a[i] == b[i], "frame %d differs", k);
    }
    /* every later frame and the final state within the tolerance.  Both
     * runs keep the local error within rtol 1e-4, atol 1e-7 m, so each is
     * within its global error E of the exact motion and they differ by at
     * most 2 E.  E of the uninterrupted run, measured against rtol 1e-7,
     * atol 1e-10 m (6 s CPU, so not repeated here): 2.2e-3 m at the frames
     * (the fall), 6.3e-4 m at the end.  Measured differences: up to 1.1e-3
     * m at the frames when interrupted early in the fall, 8e-5 m at the
     * end.  A resume without the velocities (~1 m/s in the fall) is
     * centimetres off at the next frame. */
    const double tol_frame = 2.0 * 2.2e-3, tol = 2.0 * 6.3e-4;
    for (int k = f1; k < IR_FRAMES; k++) {
        char name[64];
        snprintf(name, sizeof name, "/steps/%06d/positions", k);
        h5_read(h5, name, a, 3 * n);
        h5_read(h5ref, name, b, 3 * n);
        double d = 0.0;
        for (int i = 0; i < 3 * n; i++) d = fmax(d, fabs(a[i] - b[i]));
        ck_assert_msg(d <= tol_frame, "frame %d off by %g m", k, d);
    }
    h5_read(h5, "/final/positions", a, 3 * n);
    h5_read(h5ref, "/final/positions", b, 3 * n);
    double dmax = 0.0;
    for (int i = 0; i < 3 * n; i++) dmax = fmax(dmax, fabs(a[i] - b[i]));
    ck_assert_msg(dmax <= tol, "final state off by %g m", dmax);
    /* the last OBJ frame is the final state too */
    char path[700];
    snprintf(path, sizeof path, "%s/frame_%06d.obj", dir, IR_FRAMES - 1);
    ck_assert_int_eq(read_obj(path, b, n), n);
    for (int i = 0; i < 3 * n; i++) ck_assert_close_abs(b[i], a[i], 1e-8);
}
END_TEST

/* --max-order reaches cvode-bdf and is reported (null for the integrators
 * that have no BDF order); bad values are usage errors; an interrupted run
 * resumes with the order it was started with.  BDF1 and BDF2 take
 * different steps on the same scene. */
START_TEST(test_max_order)
{
    char args[512];
    snprintf(args, sizeof args, "%s --integrator cvode-bdf --max-order 1", small_hang);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
    ck_assert_double_eq(json_num(out, "max_order"), 1.0);
    double steps1 = json_num(out, "steps");
    snprintf(args, sizeof args, "%s --integrator cvode-bdf", small_hang);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
    ck_assert_double_eq(json_num(out, "max_order"), 2.0); /* the default */
    double steps2 = json_num(out, "steps");
    ck_assert_msg(steps1 > 0 && steps2 > 0 && steps1 != steps2, "steps %g (BDF1) and %g (BDF2)",
                  steps1, steps2);
    snprintf(args, sizeof args, "%s --integrator arkode-erk --max-order 1", small_hang);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
    ck_assert_msg(strstr(out, "\"max_order\": null"), "%s", out);
    static const char *bad[] = {"0", "6", "2x", ""};
    for (int i = 0; i < 4; i++) {
        snprintf(args, sizeof args, "%s --max-order '%s'", small_hang, bad[i]);
        ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 2);
        ck_assert_msg(strstr(err, "--max-order"), "%s", err);
    }
    /* interrupted with --max-order 1, resumed: still BDF1 */
    const char *scene = ir_scene();
    char dir[600], wait_for[700];
    snprintf(dir, sizeof dir, "%s/interrupted-bdf1", tu_scratch_dir());
    snprintf(wait_for, sizeof wait_for, "%s/frame_000000.obj", dir);
    const char *a1[] = {"run", "-q", scene, "--max-order", "1", "--out", dir, NULL};
    int code = run_and_signal(wait_for, SIGINT, a1);
    ck_assert_msg(code == 130, "exit %d (want 130), stderr: %s", code, err);
    ck_assert_double_eq(json_num(out, "max_order"), 1.0);
    char resume[700];
    snprintf(resume, sizeof resume, "run --resume '%s'", dir);
    code = tu_run_drape(resume, out, CAP, err, CAP);
    ck_assert_msg(code == 0, "exit %d, stderr: %s", code, err);
    ck_assert_msg(strstr(out, "\"status\": \"t_max\""), "%s", out);
    ck_assert_double_eq(json_num(out, "max_order"), 1.0);
}
END_TEST

/* An interrupted animate run (issue 16) resumes with its own step, the one
 * its --substeps gave (stored in the checkpoint), not the scene's. */
START_TEST(test_animate_resume)
{
    const char *scene = ir_scene();
    char dir[600], wait_for[700];
    snprintf(dir, sizeof dir, "%s/interrupted-animate", tu_scratch_dir());
    snprintf(wait_for, sizeof wait_for, "%s/frame_000000.obj", dir);
    const char *a1[] = {"run", "-q", scene, "--method", "animate", "--substeps", "50",
                        "--out", dir, NULL};
    int code = run_and_signal(wait_for, SIGTERM, a1);
    ck_assert_msg(code == 143, "exit %d (want 143), stderr: %s", code, err);
    ck_assert_msg(strstr(out, "\"status\": \"interrupted\""), "%s", out);
    char resume[700];
    snprintf(resume, sizeof resume, "run --resume '%s'", dir);
    code = tu_run_drape(resume, out, CAP, err, CAP);
    ck_assert_msg(code == 0, "exit %d, stderr: %s", code, err);
    ck_assert_msg(strstr(out, "\"status\": \"t_max\""), "%s", out);
    ck_assert_msg(strstr(out, "\"integrator\": \"animate\""), "%s", out);
    ck_assert_double_eq(json_num(out, "substeps"), 50.0);
    ck_assert_double_eq_tol(json_num(out, "step_s"), 0.05 / 50, 1e-12);
    /* the two parts together: every step of 0.05 / 50 s to t_max, each
     * counted once (no output point leaves the grid: no equilibrium
     * checks) */
    ck_assert_msg(json_num(out, "steps") == round(IR_T_MAX / (0.05 / 50)), "steps %g, want %g",
                  json_num(out, "steps"), round(IR_T_MAX / (0.05 / 50)));
}
END_TEST

/* A resumed run counts each step once (docs/outputs.md): the interrupted
 * run reports the counters up to its last output point, the checkpoint
 * the resumed run starts from, not the steps after it that the stop threw
 * away and the resumed run takes again.  Independent count: animate's
 * fixed step h = 0.05 s / 100 on a grid that no output point leaves (no
 * equilibrium checks), so exactly t / h steps reach time t.  SIGTERM after
 * one second lands inside a frame interval (it counted the steps taken in
 * it twice). */
START_TEST(test_resume_counts_steps_once)
{
    const char *scene = ir_scene();
    const double h = 0.05 / 100;
    char dir[600], resume[700];
    snprintf(dir, sizeof dir, "%s/interrupted-count", tu_scratch_dir());
    const char *a1[] = {"run", "-q", scene, "--method", "animate", "--substeps", "100",
                        "--out", dir, NULL};
    int code = run_and_signal(NULL, SIGTERM, a1);
    ck_assert_msg(code == 143, "exit %d (want 143), stderr: %s", code, err);
    ck_assert_msg(strstr(out, "\"status\": \"interrupted\""), "%s", out);
    double t1 = json_num(out, "t_end_s");
    ck_assert(t1 > 0.0 && t1 < IR_T_MAX);
    ck_assert_double_eq_tol(json_num(out, "step_s"), h, 1e-15);
    ck_assert_msg(json_num(out, "steps") == round(t1 / h), "steps %g to t = %g s, want %g",
                  json_num(out, "steps"), t1, round(t1 / h));
    snprintf(resume, sizeof resume, "run --resume '%s'", dir);
    code = tu_run_drape(resume, out, CAP, err, CAP);
    ck_assert_msg(code == 0, "exit %d, stderr: %s", code, err);
    ck_assert_msg(strstr(out, "\"status\": \"t_max\""), "%s", out);
    ck_assert_msg(json_num(out, "steps") == round(IR_T_MAX / h), "steps %g, want %g",
                  json_num(out, "steps"), round(IR_T_MAX / h));
}
END_TEST

static int count_str(const char *text, const char *part)
{
    int n = 0;
    for (const char *p = strstr(text, part); p; p = strstr(p + 1, part)) n++;
    return n;
}

/* An interrupted run started with --seed reports that seed when resumed
 * (stored in /run as `seed`), at the top and in its specimen, not the
 * scene's; a checkpoint of an older drape, without the attribute, reports
 * null (the seed that ran is unknown). */
START_TEST(test_resume_seed)
{
    const char *scene = ir_scene();
    char dir[600], old[700], wait_for[700], args[1600];
    snprintf(dir, sizeof dir, "%s/interrupted-seed", tu_scratch_dir());
    snprintf(wait_for, sizeof wait_for, "%s/frame_000000.obj", dir);
    const char *a1[] = {"run", "-q", scene, "--seed", "7", "--out", dir, NULL};
    int code = run_and_signal(wait_for, SIGTERM, a1);
    ck_assert_msg(code == 143, "exit %d (want 143), stderr: %s", code, err);
    ck_assert_int_eq(count_str(out, "\"seed\": 7,"), 2);
    /* the same checkpoint as an older drape wrote it: no /run seed */
    snprintf(old, sizeof old, "%s/interrupted-seed-old", tu_scratch_dir());
    snprintf(args, sizeof args, "cp -R '%s' '%s'", dir, old);
    ck_assert_int_eq(system(args), 0);
    snprintf(args, sizeof args, "%s/drape.h5", old);
    hid_t f = H5Fopen(args, H5F_ACC_RDWR, H5P_DEFAULT);
    ck_assert(f >= 0);
    if (H5Aexists_by_name(f, "run", "seed", H5P_DEFAULT) > 0)
        ck_assert(H5Adelete_by_name(f, "run", "seed", H5P_DEFAULT) >= 0);
    H5Fclose(f);

    snprintf(args, sizeof args, "run --resume '%s'", dir);
    code = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(code == 0, "exit %d, stderr: %s", code, err);
    ck_assert_msg(strstr(out, "\"status\": \"t_max\""), "%s", out);
    ck_assert_msg(count_str(out, "\"seed\": 7,") == 2, "%s", out);

    snprintf(args, sizeof args, "run --resume '%s'", old);
    code = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(code == 0, "exit %d, stderr: %s", code, err);
    ck_assert_msg(strstr(out, "\"status\": \"t_max\""), "%s", out);
    ck_assert_msg(count_str(out, "\"seed\": null,") == 2, "%s", out);
}
END_TEST

/* shadow.svg of a resumed Cusick run: each specimen's <polygon> carries
 * data-seed; a run resumed from a checkpoint without its seed (an older
 * drape's) printed the scene's seed there (1, for a run of seed 7), where
 * its result says "seed": null.  It now leaves data-seed out; a
 * checkpoint that has the seed gives data-seed="7". */
START_TEST(test_resume_seed_shadow)
{
    char dir[600], old[700], wait_for[700], args[3000], svg[800];
    snprintf(dir, sizeof dir, "%s/interrupted-shadow", tu_scratch_dir());
    snprintf(wait_for, sizeof wait_for, "%s/frame_000000.obj", dir);
    const char *a1[] = {"run", "-q", "../scenes/cusick.yaml", "--spacing", "5cm", "--method",
                        "dynamic", "--specimens", "1", "--seed", "7", "--out", dir, NULL};
    int code = run_and_signal(wait_for, SIGTERM, a1);
    ck_assert_msg(code == 143, "exit %d (want 143), stderr: %s", code, err);
    snprintf(old, sizeof old, "%s/interrupted-shadow-old", tu_scratch_dir());
    snprintf(args, sizeof args, "rm -rf '%s' && cp -R '%s' '%s'", old, dir, old);
    ck_assert_int_eq(system(args), 0);
    snprintf(args, sizeof args, "%s/drape.h5", old);
    hid_t f = H5Fopen(args, H5F_ACC_RDWR, H5P_DEFAULT);
    ck_assert(f >= 0);
    ck_assert(H5Adelete_by_name(f, "run", "seed", H5P_DEFAULT) >= 0);
    H5Fclose(f);
    for (int pass = 0; pass < 2; pass++) {
        const char *d = pass ? old : dir;
        snprintf(args, sizeof args, "run -q --resume '%s'", d);
        code = tu_run_drape(args, out, CAP, err, CAP);
        ck_assert_msg(code == 0, "exit %d, stderr: %s", code, err);
        ck_assert_msg(count_str(out, pass ? "\"seed\": null," : "\"seed\": 7,") == 2, "%s", out);
        snprintf(svg, sizeof svg, "%s/shadow.svg", d);
        FILE *fs = fopen(svg, "r");
        ck_assert_msg(fs != NULL, "no %s", svg);
        size_t n = fread(out, 1, CAP - 1, fs);
        out[n] = 0;
        fclose(fs);
        ck_assert_int_eq(count_str(out, "<polygon class=\"shadow\""), 1);
        ck_assert_msg(count_str(out, "data-seed=") == (pass ? 0 : 1) &&
                          (pass || count_str(out, "data-seed=\"7\"") == 1),
                      "pass %d: %.200s", pass, strstr(out, "<polygon class=\"shadow\""));
    }
}
END_TEST

/* Stale temporaries of a single run killed outright (SIGKILL): the
 * frames', drape.h5's and drape.xmf's (NAME.PID.tmp), shadow.svg's and
 * shadow.png's (NAME.tmp.PID) stayed in DIR through every later run and
 * --resume.  A run that holds DIR removes exactly those names (the PIDs
 * here are of no live drape), keeps the look-alikes, and removes nothing
 * while another process holds DIR (its temporaries may be live). */
static const char *const run_stale[] = {
    "frame_000003.obj.4242.tmp", "frame_000000.obj.7.tmp", "drape.h5.987654321.tmp",
    "drape.xmf.4242.tmp", "shadow.svg.tmp.4242", "shadow.png.tmp.1", NULL};
static const char *const run_kept[] = {
    "frame_000003.obj.tmp.4242", "frame_3.obj.4242.tmp", "frame_00000x.obj.5.tmp",
    "frame_000003.obj.42x.tmp", "drape.h5.tmp.4242", "drape.h5..tmp", "drape.xmf.4242.tmp.bak",
    "xdrape.h5.4242.tmp", "shadow.svg.4242.tmp", "shadow.png.tmp.", "notes.4242.tmp", NULL};

static void plant_stale(const char *dir)
{
    char p[900];
    for (int k = 0; k < 2; k++)
        for (const char *const *n = k ? run_kept : run_stale; *n; n++) {
            snprintf(p, sizeof p, "%s/%s", dir, *n);
            FILE *f = fopen(p, "w");
            ck_assert_msg(f != NULL, "cannot create %s", p);
            fputs("stale\n", f);
            fclose(f);
        }
}

/* want_gone: the stale names removed (1) or all still there (0). */
static void check_stale(const char *dir, int want_gone, const char *what)
{
    char p[900];
    for (int k = 0; k < 2; k++)
        for (const char *const *n = k ? run_kept : run_stale; *n; n++) {
            snprintf(p, sizeof p, "%s/%s", dir, *n);
            int there = access(p, F_OK) == 0;
            ck_assert_msg(there == (k || !want_gone), "%s: %s %s", what, p,
                          there ? "is still there" : "was removed");
        }
}

START_TEST(test_run_stale_tmp)
{
    char dir[600], wait_for[700], args[2048];
    snprintf(dir, sizeof dir, "%s/run-stale", tu_scratch_dir());
    snprintf(args, sizeof args, "rm -rf '%s'", dir);
    ck_assert_int_eq(system(args), 0);
    snprintf(wait_for, sizeof wait_for, "%s/frame_000000.obj", dir);
    const char *a1[] = {"run", "-q", "../scenes/cusick.yaml", "--spacing", "5cm", "--method",
                        "dynamic", "--specimens", "1", "--out", dir, NULL};
    int code = run_and_signal(wait_for, SIGTERM, a1);
    ck_assert_msg(code == 143, "exit %d (want 143), stderr: %s", code, err);
    /* DIR held by another process: refused, nothing removed */
    plant_stale(dir);
    int fd = open(dir, O_RDONLY | O_DIRECTORY);
    ck_assert(fd >= 0 && flock(fd, LOCK_EX | LOCK_NB) == 0);
    snprintf(args, sizeof args, "run -q --resume '%s'", dir);
    code = tu_run_drape(args, out, CAP, err, CAP);
    close(fd);
    ck_assert_msg(code != 0 && strstr(err, dir), "exit %d, stderr: %s", code, err);
    check_stale(dir, 0, "held by another");
    /* --resume DIR, then a new run into DIR */
    code = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(code == 0, "exit %d, stderr: %s", code, err);
    check_stale(dir, 1, "--resume");
    plant_stale(dir);
    char man[700]; /* DIR is the new run's: an ensemble's manifest goes, and its temporaries */
    snprintf(man, sizeof man, "%s/ensemble.json.tmp.99", dir);
    FILE *fm = fopen(man, "w");
    ck_assert(fm != NULL);
    fclose(fm);
    snprintf(args, sizeof args, "%s --out '%s'", small_hang, dir);
    code = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(code == 0, "exit %d, stderr: %s", code, err);
    check_stale(dir, 1, "new run");
    ck_assert_msg(access(man, F_OK) != 0, "%s is still there", man);
}
END_TEST

/* --resume refuses what it cannot continue, with the documented statuses. */
START_TEST(test_resume_refusals)
{
    char dir[600], args[2048];
    /* a finished run: nothing to resume (2) */
    snprintf(dir, sizeof dir, "%s/finished", tu_scratch_dir());
    snprintf(args, sizeof args, "%s --t-max 0.05s --out '%s'", small_hang, dir);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
    snprintf(args, sizeof args, "run --resume '%s'", dir);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 2);
    ck_assert_msg(strstr(err, "nothing to resume") && strstr(err, "t_max"), "%s", err);
    ck_assert_str_eq(out, "");
    /* no drape.h5 (3) */
    snprintf(args, sizeof args, "run --resume '%s'", tu_scratch_dir());
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 3);
    ck_assert_msg(strstr(err, "drape.h5"), "%s", err);
    /* run options or a scene with it (2) */
    snprintf(args, sizeof args, "run --resume '%s' --spacing 1cm", dir);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 2);
    snprintf(args, sizeof args, "run --resume '%s' ../scenes/hang.yaml", dir);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 2);
}
END_TEST

/* A strain limit the falling cloth exceeds: status failed (4), a message
 * naming the time, the edge's particles with their lattice indices and
 * the term; the frames written are those before the fault only. */
START_TEST(test_strain_limit_stops_run)
{
    char dir[600], args[2048], path[700], st[64];
    snprintf(dir, sizeof dir, "%s/strained", tu_scratch_dir());
    snprintf(args, sizeof args, "%s --strain-limit 0.0005 --out '%s'", small_hang, dir);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 4);
    ck_assert_msg(strstr(out, "\"status\": \"failed\""), "%s", out);
    ck_assert_msg(strstr(err, "strain") && strstr(err, "stretch edge between particle") &&
                      strstr(err, "(i ") && strstr(err, "t = ") && strstr(err, "exceeds the limit 0.0005"),
                  "%s", err);
    double t_fail = json_num(out, "t_end_s");
    snprintf(path, sizeof path, "%s/drape.h5", dir);
    h5_status(path, st, sizeof st);
    ck_assert_str_eq(st, "failed");
    int nf = count_prefix(dir, "frame_", ".obj");
    double t[8];
    ck_assert(nf >= 1 && nf < 8);
    h5_read(path, "/times", t, nf);
    for (int k = 0; k < nf; k++) ck_assert_double_lt(t[k], t_fail);
    /* the same run with the default limit (0.2) passes */
    ck_assert_int_eq(tu_run_drape(small_hang, out, CAP, err, CAP), 0);
    snprintf(args, sizeof args, "%s --strain-limit -1", small_hang);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 2);
}
END_TEST

/* tests/bad through `drape run` (check_cli.c does `drape check`): fabric
 * files as --fabric of a good scene, scene files as the scene, yaml- files
 * both ways.  Non-zero documented status (1, 3 or 5), the line and key of
 * the file's "# expect LINE KEY:" header, nothing on stdout, and --out DIR
 * never created. */

static void expect_rejected(const char *name, const char *args, const char *dir, int line,
                            const char *key)
{
    char pat[300];
    int st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(st == 1 || st == 3 || st == 5, "%s: drape %s: status %d, stderr: %s", name,
                  args, st, err);
    ck_assert_msg(out[0] == 0, "%s: printed a result", name);
    ck_assert_msg(strncmp(err, "drape: ", 7) == 0, "%s: %s", name, err);
    if (line > 0) {
        snprintf(pat, sizeof pat, ".yaml:%d:", line);
        ck_assert_msg(strstr(err, pat) != NULL, "%s: want line %d in: %s", name, line, err);
    }
    if (key[0]) {
        snprintf(pat, sizeof pat, " %s: ", key);
        ck_assert_msg(strstr(err, pat) != NULL, "%s: want key `%s` in: %s", name, key, err);
    }
    struct stat sb;
    ck_assert_msg(stat(dir, &sb) != 0, "%s: %s was created", name, dir);
}

START_TEST(test_bad_corpus_run)
{
    DIR *d = opendir("bad");
    ck_assert_msg(d != NULL, "tests/bad missing");
    struct dirent *e;
    int n = 0;
    char dir[600];
    snprintf(dir, sizeof dir, "%s/bad-out", tu_scratch_dir());
    while ((e = readdir(d)) != NULL) {
        size_t len = strlen(e->d_name);
        if (len < 6 || strcmp(e->d_name + len - 5, ".yaml") != 0) continue;
        char path[600], key[256], args[2048];
        int line;
        snprintf(path, sizeof path, "bad/%s", e->d_name);
        tu_bad_header(path, &line, key, sizeof key);
        int fabric = strncmp(e->d_name, "fabric-", 7) == 0;
        int yaml = strncmp(e->d_name, "yaml-", 5) == 0;
        if (!fabric) {
            snprintf(args, sizeof args, "run '%s' --out '%s'", path, dir);
            expect_rejected(e->d_name, args, dir, line, key);
        }
        if (fabric || yaml) {
            snprintf(args, sizeof args, "run ../scenes/hang.yaml --spacing 5cm --fabric '%s' --out '%s'",
                     path, dir);
            expect_rejected(e->d_name, args, dir, line, key);
        }
        n++;
    }
    closedir(d);
    ck_assert_int_ge(n, 30);
}
END_TEST

Suite *run_suite(void)
{
    Suite *s = suite_create("run");
    TCase *tc = tcase_create("run");
    tcase_set_timeout(tc, 300);
    tcase_add_test(tc, test_contract_keys);
    tcase_add_test(tc, test_failure_is_clean);
    tcase_add_test(tc, test_frames_parse_back);
    tcase_add_test(tc, test_output_dir_errors);
    tcase_add_test(tc, test_cusick_static_equilibrium);
    tcase_add_test(tc, test_cusick_dynamic_equilibrium);
    tcase_add_test(tc, test_interrupt_within_interval);
    tcase_add_test(tc, test_interrupt_static);
    tcase_add_test(tc, test_static_saddle_warns);
    tcase_add_test(tc, test_interrupt_ensemble);
    tcase_add_test(tc, test_interrupt_ensemble_group);
    tcase_add_test(tc, test_stale_frames_removed);
    tcase_add_test(tc, test_out_no_symlink);
    tcase_add_test(tc, test_imex_limp_fold);
    tcase_add_test(tc, test_interrupt_and_resume);
    tcase_add_test(tc, test_resume_refusals);
    tcase_add_test(tc, test_resume_seed);
    tcase_add_test(tc, test_max_order);
    tcase_add_test(tc, test_animate_resume);
    tcase_add_test(tc, test_strain_limit_stops_run);
    tcase_add_test(tc, test_bad_corpus_run);
    suite_add_tcase(s, tc);
    tc = tcase_create("counts");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, test_resume_counts_steps_once);
    suite_add_tcase(s, tc);
    TCase *sh = tcase_create("seed_shadow"); /* a resumed run's shadow.svg */
    tcase_set_timeout(sh, 120);
    tcase_add_test(sh, test_resume_seed_shadow);
    suite_add_tcase(s, sh);
    TCase *st = tcase_create("stale_tmp"); /* a killed run's temporaries */
    tcase_set_timeout(st, 120);
    tcase_add_test(st, test_run_stale_tmp);
    suite_add_tcase(s, st);
    return s;
}

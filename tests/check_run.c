/* check_run.c: `drape run` end to end through the binary: the result's
 * contract keys, a clean failure, and frames that parse back to the final
 * state (OBJ and HDF5 read independently of the writers' code). */
#include <dirent.h>
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
}
END_TEST

/* The default Cusick scene by the static method: a certified minimum with
 * the residual below its tolerance, a drape coefficient strictly between
 * "hanging straight down" (0) and "undeformed" (1), and the potential
 * energy below the flat state's (0: gravity is measured from z = 0). */
START_TEST(test_cusick_static_equilibrium)
{
    ck_assert_int_eq(tu_run_drape("run -q ../scenes/cusick.yaml --method static", out, CAP, err,
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

Suite *run_suite(void)
{
    Suite *s = suite_create("run");
    TCase *tc = tcase_create("run");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, test_contract_keys);
    tcase_add_test(tc, test_failure_is_clean);
    tcase_add_test(tc, test_frames_parse_back);
    tcase_add_test(tc, test_output_dir_errors);
    tcase_add_test(tc, test_cusick_static_equilibrium);
    suite_add_tcase(s, tc);
    return s;
}

/* cli_check.c: `drape check FILE.yaml...`: validate fabric and scene files
 * and print an SI summary of each.  A file is a scene if its root mapping
 * has a `scene` key, otherwise a fabric.  Exit status 0 only if every file
 * is valid; otherwise that of the first failure. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "cli_data.h"
#include "drape/fabric.h"
#include "drape/lattice.h"
#include "drape/model.h"
#include "drape/scene.h"
#include "drape/units.h"
#include "drape/yamldoc.h"

static const char check_usage[] =
    "Usage: drape check FILE.yaml...\n"
    "\n"
    "Validate fabric and scene files.  For each valid file print an SI\n"
    "summary on stdout; errors go to stderr as FILE:LINE:COL: key: message.\n"
    "A scene is checked together with its fabric (path relative to the scene).\n"
    "Exit status 0 only if all files are valid.\n";

static void print_fabric(const drape_fabric *f)
{
    static const char *dn[2] = {"weft", "warp"};
    const double g = DRAPE_G_STANDARD;
    printf("  fabric               %s\n", f->name);
    printf("  weight_kg_m2         %.6g\n", f->weight);
    printf("  tensile_stiffness_N_m  warp %.6g, weft %.6g\n", f->k[DRAPE_WARP], f->k[DRAPE_WEFT]);
    for (int d = DRAPE_WARP; d >= DRAPE_WEFT; d--) {
        double B = drape_fabric_bending_rigidity(f, (drape_dir)d);
        printf("  %s: bending_rigidity_Nm %.6g, bending_length_m (B/Wg)^(1/3) %.6g\n",
               dn[d], B, cbrt(B / (f->weight * g)));
    }
    if (f->has_bias) {
        double B = drape_fit_slope(&f->bend_bias, 0.0);
        double Bs = 0.25 * (drape_fabric_bending_rigidity(f, DRAPE_WARP) +
                            drape_fabric_bending_rigidity(f, DRAPE_WEFT));
        printf("  bias: bending_rigidity_Nm %.6g, bending_length_m (B/Wg)^(1/3) %.6g; "
               "twist rigidity D66 = B_bias - (B_warp + B_weft)/4 = %.6g N.m\n",
               B, cbrt(B / (f->weight * g)), B - Bs);
    }
    printf("  shear_rigidity_N_m_rad %.6g (mean of warp and weft)\n",
           drape_fabric_shear_rigidity(f));
    printf("  bending M(K):   K_1/m      M_warp_N      M_weft_N%s   (N.m/m = N)\n",
           f->has_bias ? "      M_bias_N" : "");
    const double Ks[] = {0.0, 10.0, 40.0, 100.0, 250.0, 500.0};
    for (size_t i = 0; i < sizeof Ks / sizeof Ks[0]; i++) {
        printf("                %7.1f  %12.5e  %12.5e", Ks[i],
               drape_fit_value(&f->bend[DRAPE_WARP], Ks[i]),
               drape_fit_value(&f->bend[DRAPE_WEFT], Ks[i]));
        if (f->has_bias) printf("  %12.5e", drape_fit_value(&f->bend_bias, Ks[i]));
        putchar('\n');
    }
    printf("  shear F(gamma): gamma_rad  F_warp_N_m    F_weft_N_m    F_mean_N_m\n");
    const double gs[] = {0.0, 0.005, 0.00873, 0.05, 0.13, 0.3};
    for (size_t i = 0; i < sizeof gs / sizeof gs[0]; i++)
        printf("                %9.5f  %12.5e  %12.5e  %12.5e\n", gs[i],
               drape_fit_value(&f->shear[DRAPE_WARP], gs[i]),
               drape_fit_value(&f->shear[DRAPE_WEFT], gs[i]),
               drape_fit_value(&f->shear_mean, gs[i]));
}

static int check_fabric(const char *path)
{
    drape_error err;
    drape_error_clear(&err);
    drape_fabric f;
    if (drape_fabric_load(path, &f, &err, drape_cli_warn, NULL) != 0) {
        drape_cli_print_error(&err);
        return drape_error_exit_status(err.kind);
    }
    printf("%s: valid fabric\n", path);
    print_fabric(&f);
    return 0;
}

static const char *shape_name(drape_shape s)
{
    switch (s) {
    case DRAPE_SHAPE_RECTANGLE: return "rectangle";
    case DRAPE_SHAPE_CIRCLE: return "circle";
    case DRAPE_SHAPE_STRIP: return "strip";
    }
    return "?";
}

/* Per-term highest natural frequency at the initial state; with shear
 * damping beta (s) > 0, the damping ratio beta omega / 2 it gives the
 * fastest shear vibration. */
static void print_bounds(drape_model *m, const drape_lattice *L, double beta)
{
    static const struct { unsigned part; const char *name; } parts[] = {
        {DRAPE_PART_STRETCH, "stretch"},
        {DRAPE_PART_SHEAR, "shear"},
        {DRAPE_PART_BEND, "bend"}};
    unsigned have = drape_model_parts(m);
    printf("  omega_max_rad_s      (Gershgorin bound on M^-1 K at the initial state)\n");
    for (size_t i = 0; i < sizeof parts / sizeof parts[0]; i++) {
        if (!(have & parts[i].part)) {
            printf("    %-8s           off\n", parts[i].name);
            continue;
        }
        double w = 0.0;
        if (drape_model_omega_bound(m, parts[i].part, L->xinit, &w) != 0) {
            printf("    %-8s           (folded state)\n", parts[i].name);
            continue;
        }
        printf("    %-8s           %.4g  (explicit RK4 step limit ~ %.3g s)\n",
               parts[i].name, w, w > 0 ? 2.8 / w : INFINITY);
        if (parts[i].part == DRAPE_PART_SHEAR && beta > 0.0)
            printf("    shear damping      %.3g of critical at that frequency (beta omega / 2)\n",
                   0.5 * beta * w);
    }
}

static int check_scene(const char *path)
{
    drape_error err;
    drape_error_clear(&err);
    drape_scene s;
    drape_fabric f;
    drape_lattice *L = NULL;
    drape_model *m = NULL;
    int status = 0;
    if (drape_scene_load(path, &s, &err, drape_cli_warn, NULL) != 0) goto fail;
    if (drape_fabric_load(s.fabric_path, &f, &err, drape_cli_warn, NULL) != 0) goto fail;
    s.damping_shear = drape_scene_damping_shear(&s, &f); /* the fabric's unless the scene's */
    if (drape_scene_check_with_fabric(&s, &f, &err) != 0) goto fail;
    L = drape_lattice_new(&s, &f, &err);
    if (!L) goto fail;
    if (drape_lattice_check(L) != 0) {
        drape_error_set(&err, DRAPE_E_INTERNAL, path, 0, 0, NULL,
                        "lattice invariants violated (%d)", drape_lattice_check(L));
        goto fail;
    }
    drape_model_opts o;
    drape_model_opts_from_scene(&s, &o);
    m = drape_model_new(L, &f, &o, &err);
    if (!m) goto fail;

    printf("%s: valid scene\n", path);
    printf("  scene                %s\n", drape_scene_kind_name(s.kind));
    printf("  fabric_file          %s\n", s.fabric_path);
    printf("  specimen             %s", shape_name(s.shape));
    if (s.shape == DRAPE_SHAPE_CIRCLE) printf(", diameter_m %.6g", s.diameter);
    if (s.shape == DRAPE_SHAPE_RECTANGLE) printf(", width_m %.6g, height_m %.6g", s.width, s.height);
    if (s.shape == DRAPE_SHAPE_STRIP) {
        char dir[48];
        if (s.strip_oblique) snprintf(dir, sizeof dir, "%.6g deg from the warp", s.strip_angle);
        else snprintf(dir, sizeof dir, "%s", s.strip_dir == DRAPE_WARP ? "warp" : "weft");
        printf(", length_m %.6g, width_m %.6g, direction %s, overhang_m %.6g", s.length,
               s.width, dir, s.overhang);
    }
    printf("\n");
    printf("  spacing_m            %.6g\n", s.spacing);
    printf("  energy_form          %s\n", drape_energy_form_name(s.energy_form));
    printf("  integrator           %s, rtol %.3g, atol %.3g\n", s.integrator, s.rtol, s.atol);
    printf("  damping              air %.3g 1/s, edge %.3g N.s/m, shear %.3g s\n", s.damping_air,
           s.damping_edge, s.damping_shear);
    printf("  particles            %d (free %d, fixed %d)\n", L->n, L->n_free, L->n - L->n_free);
    printf("  elements             %d edges, %d hinges, %d corners\n", L->n_edges,
           L->n_hinges, L->n_corners);
    double wa = f.weight * L->area_nominal;
    printf("  mass_kg              %.6g (W x area %.6g kg, difference %+.3g %%)\n",
           L->mass_total, wa, 100.0 * (L->mass_total - wa) / wa);
    print_bounds(m, L, s.damping_shear);
    print_fabric(&f);
    goto out;
fail:
    drape_cli_print_error(&err);
    status = drape_error_exit_status(err.kind);
out:
    drape_model_free(m);
    drape_lattice_free(L);
    return status;
}

static int is_scene(const char *path, int *scene, drape_error *err)
{
    drape_ydoc *doc = drape_ydoc_load(path, err);
    if (!doc) return -1;
    *scene = drape_ynode_get(doc->root, "scene", NULL) != NULL;
    drape_ydoc_free(doc);
    return 0;
}

int drape_cli_check(int argc, char **argv)
{
    static const struct option opts[] = {{"help", no_argument, NULL, 'h'},
                                         {NULL, 0, NULL, 0}};
    int c;
    if ((c = drape_cli_args_unambiguous(argc, argv, "h", opts, "drape check")) != 0) return c;
    while ((c = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
        if (c == 'h') { fputs(check_usage, stdout); return 0; }
        fputs("Try `drape check --help'.\n", stderr); /* getopt named the option */
        return drape_error_exit_status(DRAPE_E_USAGE);
    }
    if (optind >= argc) {
        fputs(check_usage, stderr);
        return drape_error_exit_status(DRAPE_E_USAGE);
    }
    int status = 0;
    for (int i = optind; i < argc; i++) {
        drape_error err;
        drape_error_clear(&err);
        int scene = 0, st;
        char path[4096]; /* a shipped file may come from the data directories */
        if (drape_cli_data_find(argv[i], path, sizeof path, &err) != 0 ||
            is_scene(path, &scene, &err) != 0) {
            drape_cli_print_error(&err);
            st = drape_error_exit_status(err.kind);
        } else {
            st = scene ? check_scene(path) : check_fabric(path);
        }
        if (st != 0 && status == 0) status = st;
    }
    return status;
}

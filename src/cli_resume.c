/* cli_resume.c: --resume's reading of DIR/drape.h5 and the /run group
 * that makes it possible (cli_resume.h; docs/reliability.md). */
#include "cli_resume.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "cli_io.h"
#include "drape/alloc.h"
#include "drape/integrator.h"
#include "drape/yamldoc.h"



static const char *ck_text(const drape_h5_checkpoint *c, const char *key)
{
    const drape_kv *kv = drape_kv_find(c->run, c->n_run, key);
    return kv && kv->text ? kv->text : NULL;
}

static double ck_num(const drape_h5_checkpoint *c, const char *key)
{
    const drape_kv *kv = drape_kv_find(c->run, c->n_run, key);
    return kv && !kv->text ? kv->value : NAN;
}

/* A stored text must be the file's current text (the run continues on the
 * same inputs). */
static int same_input(const char *path, const char *stored, const char *what,
                      const char *h5, drape_error *err)
{
    drape_error e2;
    drape_error_clear(&e2);
    if (!stored)
        return drape_error_set(err, DRAPE_E_IO, h5, 0, 0, NULL,
                               "--resume: the %s text is not stored in the file", what);
    char *now = drape_cli_read_file(path, DRAPE_YDOC_MAX_BYTES, NULL, &e2);
    if (!now) {
        *err = e2;
        return -1;
    }
    int same = strcmp(now, stored) == 0;
    drape_free(now);
    if (!same)
        return drape_error_set(err, DRAPE_E_INPUT, path, 0, 0, NULL,
                               "--resume: this %s file changed since the run was interrupted "
                               "(%s keeps the old text as attribute %s_yaml); restore it, or "
                               "start a new run", what, h5, what);
    return 0;
}

int drape_cli_resume_load(const char *dir, resume_info *ri, drape_error *err)
{
    drape_h5_checkpoint *c = &ri->ck;
    snprintf(ri->h5_path, sizeof ri->h5_path, "%s/drape.h5", dir);
    if (drape_h5_checkpoint_read(ri->h5_path, c, err) != 0) {
        if (access(ri->h5_path, F_OK) != 0) {
            drape_error_clear(err);
            return drape_error_set(err, DRAPE_E_IO, ri->h5_path, 0, 0, NULL,
                                   "--resume: no such file (a run interrupted with --out DIR "
                                   "leaves it there)");
        }
        return -1;
    }
    const drape_kv *st = drape_kv_find(c->stats, c->n_stats, "status");
    const char *status = st && st->text ? st->text : "";
    if (strcmp(status, "interrupted") != 0)
        return drape_error_set(err, DRAPE_E_USAGE, ri->h5_path, 0, 0, NULL,
                               "--resume: the run ended with status %s, not interrupted: "
                               "nothing to resume", status[0] ? status : "(none)");
    const char *sp = ck_text(c, "scene_path"), *fp = ck_text(c, "fabric_path");
    const char *in = ck_text(c, "integrator"), *fo = ck_text(c, "energy_form");
    const char *ls = ck_text(c, "linear_solver");
    if (ck_num(c, "resume_format") != RUN_RESUME_FORMAT || !sp || !fp || !in || !fo || !ls)
        return drape_error_set(err, DRAPE_E_IO, ri->h5_path, 0, 0, NULL,
                               "--resume: no usable /run group (written by another version "
                               "of drape?)");
    if (strlen(sp) >= sizeof ri->scene_path || strlen(fp) >= sizeof ri->fabric_path)
        return drape_error_set(err, DRAPE_E_IO, ri->h5_path, 0, 0, NULL,
                               "--resume: stored input paths too long");
    snprintf(ri->scene_path, sizeof ri->scene_path, "%s", sp);
    snprintf(ri->fabric_path, sizeof ri->fabric_path, "%s", fp);
    snprintf(ri->integrator, sizeof ri->integrator, "%s", in);
    snprintf(ri->form, sizeof ri->form, "%s", fo);
    snprintf(ri->linsol, sizeof ri->linsol, "%s", ls);
    ri->rtol = ck_num(c, "rtol");
    ri->atol = ck_num(c, "atol");
    ri->spacing = ck_num(c, "spacing_m");
    ri->t_max = ck_num(c, "t_max_s");
    ri->strain_limit = ck_num(c, "strain_limit");
    ri->below_since = ck_num(c, "eq_below_since_s");
    ri->fixed_step = ck_num(c, "step_s");
    ri->terms = ck_num(c, "terms");
    ri->damping_shear = ck_num(c, "damping_shear_s");
    ri->seed = ck_num(c, "seed"); /* added: NaN (unknown) in older files */
    double ms = ck_num(c, "max_steps"), fr = ck_num(c, "frames"), h5 = ck_num(c, "hdf5");
    ri->ref.valid = ck_num(c, "energy_ref_valid") == 1.0;
    ri->ref.energy_J = ck_num(c, "energy_ref_J");
    ri->ref.scale_J = ck_num(c, "energy_scale_J");
    ri->ref.kinetic_J = ck_num(c, "energy_ref_kinetic_J");
    ri->ref.E.stretch = ck_num(c, "energy_ref_stretch_J");
    ri->ref.E.bend = ck_num(c, "energy_ref_bend_J");
    ri->ref.E.shear = ck_num(c, "energy_ref_shear_J");
    ri->ref.E.gravity = ck_num(c, "energy_ref_gravity_J");
    if (!(ri->rtol > 0) || !(ri->atol > 0) || !(ri->spacing > 0) || !(ri->t_max > 0) ||
        !(ri->strain_limit > 0) || !(ms >= 0) || !(fr >= 0 && fr < INT_MAX) ||
        !(h5 == 0 || h5 == 1) || isnan(ri->below_since) ||
        (!isnan(ri->seed) && !(ri->seed >= 0 && ri->seed <= (double)DRAPE_SCENE_SEED_MAX &&
                               ri->seed == floor(ri->seed))) ||
        (ri->ref.valid && !(isfinite(ri->ref.energy_J) && ri->ref.scale_J > 0)))
        return drape_error_set(err, DRAPE_E_IO, ri->h5_path, 0, 0, NULL,
                               "--resume: missing or invalid values in /run");
    ri->max_steps = (long)ms;
    double mo = ck_num(c, "max_order");
    ri->max_order = mo >= 1 && mo <= 5 ? (int)mo : 0;
    ri->frames = (int)fr;
    ri->had_h5 = h5 == 1;
    if (same_input(ri->scene_path, c->scene_yaml, "scene", ri->h5_path, err) != 0 ||
        same_input(ri->fabric_path, c->fabric_yaml, "fabric", ri->h5_path, err) != 0)
        return -1;
    return 0;
}

void drape_cli_resume_add_previous(const drape_h5_checkpoint *c, const char *key, long *v)
{
    const drape_kv *kv = drape_kv_find(c->stats, c->n_stats, key);
    if (kv && !kv->text && kv->value >= 0 && *v >= 0) *v += (long)kv->value;
}


static void kv_num(run_kv *k, const char *key, double v)
{
    k->kv[k->n++] = (drape_kv){key, NULL, v};
}

static void kv_str(run_kv *k, const char *key, const char *text)
{
    k->kv[k->n++] = (drape_kv){key, text, 0.0};
}

/* path made absolute against the working directory (kept as given when
 * that fails), so that --resume works from anywhere. */
static void abs_path(const char *path, char *out, size_t n)
{
    char cwd[PATH_MAX];
    if (path[0] != '/' && getcwd(cwd, sizeof cwd)) {
        int r = snprintf(out, n, "%s/%s", cwd, path);
        if (r >= 0 && (size_t)r < n) return;
    }
    snprintf(out, n, "%s", path);
}

void drape_cli_run_kv_fill(run_kv *k, const char *scene_path, const drape_scene *s,
                           const drape_sim_opts *so, const drape_sim_result *res, int frames,
                           int signal, double seed)
{
    k->n = 0;
    abs_path(scene_path, k->scene_abs, sizeof k->scene_abs);
    abs_path(s->fabric_path, k->fabric_abs, sizeof k->fabric_abs);
    kv_num(k, "resume_format", RUN_RESUME_FORMAT);
    kv_str(k, "method", "dynamic");
    kv_str(k, "scene_path", k->scene_abs);
    kv_str(k, "fabric_path", k->fabric_abs);
    kv_str(k, "integrator", so->integrator);
    kv_num(k, "rtol", so->rtol);
    kv_num(k, "atol", so->atol);
    kv_num(k, "spacing_m", s->spacing);
    kv_str(k, "energy_form", drape_energy_form_name(s->energy_form));
    kv_num(k, "t_max_s", so->t_max);
    kv_num(k, "strain_limit", so->strain_limit);
    kv_num(k, "max_steps", (double)so->max_steps);
    kv_num(k, "max_order", (double)so->max_order);
    kv_str(k, "linear_solver", drape_linsol_name(so->linsol));
    kv_num(k, "frames", frames);
    kv_num(k, "hdf5", s->out_hdf5 ? 1.0 : 0.0);
    kv_num(k, "eq_below_since_s", res->eq_below_since);
    kv_num(k, "energy_ref_valid", res->diag_ref.valid ? 1.0 : 0.0);
    kv_num(k, "energy_ref_J", res->diag_ref.energy_J);
    kv_num(k, "energy_scale_J", res->diag_ref.scale_J);
    kv_num(k, "energy_ref_kinetic_J", res->diag_ref.kinetic_J);
    kv_num(k, "energy_ref_stretch_J", res->diag_ref.E.stretch);
    kv_num(k, "energy_ref_bend_J", res->diag_ref.E.bend);
    kv_num(k, "energy_ref_shear_J", res->diag_ref.E.shear);
    kv_num(k, "energy_ref_gravity_J", res->diag_ref.E.gravity);
    kv_num(k, "signal", signal);
    kv_num(k, "step_s", so->fixed_step); /* animate's step */
    kv_num(k, "terms", (double)s->terms); /* the terms run, --terms included */
    kv_num(k, "damping_shear_s", s->damping_shear); /* --damping-shear included */
    kv_num(k, "seed", seed); /* the perturbation seed, --seed included; NaN unknown */
}
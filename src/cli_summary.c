/* cli_summary.c: a result of `drape run` as a few lines for a person
 * (`--format text`, the default when stdout is a terminal): what ran, the
 * drape coefficient with its interval and spread, the node histogram, the
 * modal node count, the convergence check where one ran, status and CPU.
 * Every number is read from the result's fields, the ones JSON and CSV
 * print (cli_result.h); nothing here computes a statistic of its own. */
#include "cli_result.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static const char *text_of(const drape_cli_result *r, const char *key)
{
    const drape_cli_field *f = drape_cli_result_find(r, key);
    return f && f->type == DRAPE_CLI_F_STR && !f->is_null_text ? f->text : NULL;
}

/* a length in the unit a lab reads: cm below 1 m */
static void length_text(char *buf, size_t n, double m)
{
    if (!isfinite(m)) snprintf(buf, n, "-");
    else snprintf(buf, n, "%.3g cm", 100.0 * m);
}

static void hist_lines(FILE *out, const drape_cli_result *r, int n_spec)
{
    int most = 0;
    for (int k = 0; k <= DRAPE_ENSEMBLE_MAX_NODES; k++)
        if (r->hist[k] > most) most = r->hist[k];
    if (most == 0) return;
    const int width = 30;
    fprintf(out, "  nodes (folds)      specimens\n");
    for (int k = 0; k <= DRAPE_ENSEMBLE_MAX_NODES; k++) {
        if (!r->hist[k]) continue;
        int bar = (r->hist[k] * width + most - 1) / most;
        fprintf(out, "  %6d%s           ", k, k == DRAPE_ENSEMBLE_MAX_NODES ? "+" : " ");
        for (int b = 0; b < bar; b++) fputc('#', out);
        fprintf(out, " %d (%.0f %%)\n", r->hist[k], n_spec > 0 ? 100.0 * r->hist[k] / n_spec : 0.0);
    }
}

void drape_cli_result_print_text(FILE *out, const drape_cli_result *r)
{
    const char *fabric = text_of(r, "fabric"), *scene = text_of(r, "scene");
    const char *method = text_of(r, "method"), *status = text_of(r, "status");
    const char *integ = text_of(r, "integrator"), *cert = text_of(r, "certified");
    char sp[32], buf[64];
    length_text(sp, sizeof sp, drape_cli_result_get(r, "spacing_m"));
    double particles = drape_cli_result_get(r, "particles");
    fprintf(out, "%s on the %s scene, spacing %s", fabric ? fabric : "?", scene ? scene : "?", sp);
    if (isfinite(particles)) fprintf(out, " (%.0f particles)", particles);
    if (method) fprintf(out, ", %s method", method);
    if (integ && (!method || strcmp(method, "fall") != 0)) fprintf(out, " (%s)", integ);
    fputc('\n', out);

    int n_spec = 0;
    for (int k = 0; k < r->n_spec; k++)
        if (isfinite(r->spec[k].dc)) n_spec++;
    double dc = drape_cli_result_get(r, "dc");
    if (isfinite(dc)) {
        double ci = drape_cli_result_get(r, "dc_ci95"), sd = drape_cli_result_get(r, "dc_sd");
        fprintf(out, "  drape coefficient  %.3f", dc);
        if (r->n_spec > 1 && isfinite(ci))
            fprintf(out, " +- %.3f (95 %% interval of the mean of %d specimens), sd %.3f", ci,
                    n_spec, sd);
        else if (r->n_spec > 1)
            fprintf(out, " (mean of %d specimens)", n_spec);
        fputc('\n', out);
        if (r->n_spec > 1) {
            hist_lines(out, r, n_spec);
            double mode = drape_cli_result_get(r, "nodes"), dcm = drape_cli_result_get(r, "dc_mode");
            if (isfinite(mode) && isfinite(dcm))
                fprintf(out, "  modal nodes        %.0f, their mean DC %.3f\n", mode, dcm);
        } else {
            double nodes = drape_cli_result_get(r, "nodes");
            if (isfinite(nodes)) fprintf(out, "  nodes (folds)      %.0f\n", nodes);
        }
        char a[32], b[32];
        length_text(a, sizeof a, drape_cli_result_get(r, "r_min_m"));
        length_text(b, sizeof b, drape_cli_result_get(r, "r_max_m"));
        fprintf(out, "  shadow radius      %s to %s%s\n", a, b, r->n_spec > 1 ? " (mean)" : "");
    }
    double tip = drape_cli_result_get(r, "tip_angle_deg");
    if (isfinite(tip)) {
        length_text(buf, sizeof buf, drape_cli_result_get(r, "bending_length_m"));
        fprintf(out, "  tip angle          %.2f deg, bending length %s, flexural rigidity %.3g N.m\n",
                tip, buf, drape_cli_result_get(r, "flexural_rigidity_Nm"));
    }
    if (!isfinite(dc) && !isfinite(tip)) {
        double te = drape_cli_result_get(r, "t_end_s"), st = drape_cli_result_get(r, "max_strain");
        double ek = drape_cli_result_get(r, "energy_J.kinetic"), sp_max = drape_cli_result_get(r, "max_speed_m_s");
        if (isfinite(te)) fprintf(out, "  ended at           %.3g s of simulated time\n", te);
        if (isfinite(st)) fprintf(out, "  largest strain     %.3g %%\n", 100.0 * st);
        if (isfinite(sp_max)) fprintf(out, "  largest speed      %.3g m/s at the end\n", sp_max);
        if (isfinite(ek)) fprintf(out, "  kinetic energy     %.3g J at the end\n", ek);
    }
    double delta = drape_cli_result_get(r, "dc_spacing_delta");
    if (isfinite(delta)) {
        double dci = drape_cli_result_get(r, "dc_spacing_delta_ci95");
        double p = drape_cli_result_get(r, "nodes_spacing_p");
        length_text(buf, sizeof buf, drape_cli_result_get(r, "spacing_coarse_m"));
        fprintf(out, "  spacing check      DC %+.4f", delta);
        if (isfinite(dci)) fprintf(out, " +- %.4f", dci);
        fprintf(out, " against %s, node histograms p = %.2f: %s\n", buf, p,
                fabs(delta) < 0.01 && !(p < 0.05)
                    ? "converged (refining changes the DC by less than 0.01)"
                    : "not converged: run again at a finer spacing");
    }
    fprintf(out, "  status             %s", status ? status : "?");
    if (cert) fprintf(out, ", rest state certified %s", cert);
    double failed = drape_cli_result_get(r, "specimens_failed");
    if (isfinite(failed) && failed > 0) fprintf(out, ", %.0f specimens failed", failed);
    fputc('\n', out);
    double cpu = drape_cli_result_get(r, "cpu_s"), wall = drape_cli_result_get(r, "wall_s");
    if (isfinite(cpu)) {
        fprintf(out, "  CPU                %.1f s", cpu);
        if (r->n_spec > 1) fprintf(out, " (%.2f s per specimen)", cpu / r->n_spec);
        if (isfinite(wall)) fprintf(out, ", %.1f s wall", wall);
        fputc('\n', out);
    }
}

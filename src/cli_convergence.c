/* cli_convergence.c: `drape run --convergence`, the answer to "is this
 * spacing fine enough?" (docs/model.md 6, "Converged in the spacing";
 * docs/convergence.md).
 *
 * The same specimens (scene, fabric, options, seeds) run first at the
 * spacing sqrt(2) coarser, as an ensemble of their own in a child process
 * whose result (JSON on a pipe) is read back; then the run itself, whose
 * result gains
 *   spacing_coarse_m       the coarser spacing, m
 *   dc_spacing_delta       mean DC at the spacing - mean DC at the coarser
 *   dc_spacing_delta_ci95  the 95 % half-width of that difference (Welch)
 *   nodes_spacing_p        the exact test of the two node histograms
 * The spacing is converged in the model's (docs/model.md) sense where refining it moves the
 * mean by less than 0.01 and leaves the histogram indistinguishable at
 * 5 %; a lab that sees |dc_spacing_delta| > 0.01 (or nodes_spacing_p <
 * 0.05) runs again at a finer spacing.  A loop above the ensemble: neither
 * ensemble knows of the other, and the run below receives only the coarse
 * statistics to report. */
#include "cli_run.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <json-c/json.h>

#include "cli.h"
#include "cli_specimens.h"
#include "drape/alloc.h"

void drape_cli_convergence_keys(drape_cli_result *r, const run_coarse *c,
                                const drape_ensemble_stats *st)
{
    double delta = NAN, ci = NAN, p = NAN;
    if (c && st && st->n > 0 && c->st.n > 0) {
        delta = st->dc_mean - c->st.dc_mean;
        ci = drape_ensemble_welch_ci95(&c->st, st);
        p = drape_ensemble_exact_p(c->st.hist, st->hist, DRAPE_ENSEMBLE_MAX_NODES + 1);
    }
    drape_cli_result_num(r, "spacing_coarse_m", c ? c->spacing_m : NAN);
    drape_cli_result_num(r, "dc_spacing_delta", delta);
    drape_cli_result_num(r, "dc_spacing_delta_ci95", ci);
    drape_cli_result_num(r, "nodes_spacing_p", p);
}

/* The specimens' DCs and node counts of a drape run result (an ensemble's
 * `specimens`, or a single run's own dc and nodes) into st.  -1 if the
 * text is not such a result. */
static int coarse_stats(const char *text, drape_ensemble_stats *st)
{
    json_object *o = json_tokener_parse(text), *sp = NULL, *v;
    if (!o || !json_object_is_type(o, json_type_object)) {
        json_object_put(o);
        return -1;
    }
    double *dc = NULL;
    int *nodes = NULL, n = 0, rc = -1;
    if (json_object_object_get_ex(o, "specimens", &sp) && json_object_is_type(sp, json_type_array)) {
        n = (int)json_object_array_length(sp);
        dc = drape_calloc((size_t)n + 1, sizeof *dc);
        nodes = drape_calloc((size_t)n + 1, sizeof *nodes);
        if (!dc || !nodes) goto out;
        for (int k = 0; k < n; k++) {
            json_object *e = json_object_array_get_idx(sp, (size_t)k);
            dc[k] = NAN;
            nodes[k] = -1;
            if (json_object_object_get_ex(e, "dc", &v) && v) dc[k] = json_object_get_double(v);
            if (json_object_object_get_ex(e, "nodes", &v) && v) nodes[k] = json_object_get_int(v);
        }
    } else {
        n = 1;
        dc = drape_calloc(1, sizeof *dc);
        nodes = drape_calloc(1, sizeof *nodes);
        if (!dc || !nodes) goto out;
        dc[0] = NAN;
        nodes[0] = -1;
        if (json_object_object_get_ex(o, "dc", &v) && v) dc[0] = json_object_get_double(v);
        if (json_object_object_get_ex(o, "nodes", &v) && v) nodes[0] = json_object_get_int(v);
    }
    drape_ensemble_stats_compute(dc, nodes, n, st);
    rc = 0;
out:
    drape_free(dc);
    drape_free(nodes);
    json_object_put(o);
    return rc;
}

int drape_cli_convergence_run(const run_args *a)
{
    drape_error err;
    drape_error_clear(&err);
    drape_scene s;
    if (drape_scene_load_flags(a->scene_path, a->fabric_path ? DRAPE_SCENE_LOAD_FABRIC_OVERRIDDEN : 0u,
                               &s, &err, NULL, NULL) != 0) {
        drape_cli_print_error(&err);
        return drape_error_exit_status(err.kind);
    }
    run_coarse c;
    memset(&c, 0, sizeof c);
    c.spacing_m = (a->spacing > 0 ? a->spacing : s.spacing) * sqrt(2.0);
    /* the coarse ensemble: these options at that spacing, recorded as
     * given (an ensemble's manifest lists its options) */
    run_args ca = *a;
    char spacing_text[64];
    snprintf(spacing_text, sizeof spacing_text, "%.17g m", c.spacing_m);
    ca.convergence = 0;
    ca.coarse = NULL;
    ca.spacing = c.spacing_m;
    ca.csv = 0;
    ca.text = 0; /* JSON on the pipe, whatever the terminal */
    ca.quiet = 1;
    ca.no_warnings = 1; /* the input's warnings once, from the fine ensemble */
    int g = 0;
    while (g < ca.n_given && strcmp(ca.given_name[g], "spacing") != 0) g++;
    if (g < RUN_GIVEN_MAX) {
        ca.given_name[g] = "spacing";
        ca.given_text[g] = spacing_text;
        if (g == ca.n_given) ca.n_given++;
    }
    if (!a->quiet && isatty(STDERR_FILENO))
        fprintf(stderr, "drape: --convergence: the specimens at %.4g cm first, then at %.4g cm\n",
                100.0 * c.spacing_m, 100.0 * c.spacing_m / sqrt(2.0));
    fflush(NULL);
    int fd[2];
    if (pipe(fd) != 0) {
        fprintf(stderr, "drape: --convergence: cannot make a pipe: %s\n", strerror(errno));
        return drape_error_exit_status(DRAPE_E_IO);
    }
    pid_t pid = fork();
    if (pid < 0) {
        fprintf(stderr, "drape: --convergence: cannot start the coarse ensemble: %s\n",
                strerror(errno));
        close(fd[0]);
        close(fd[1]);
        return drape_error_exit_status(DRAPE_E_IO);
    }
    if (pid == 0) {
        close(fd[0]);
        if (dup2(fd[1], STDOUT_FILENO) < 0) _exit(drape_error_exit_status(DRAPE_E_IO));
        close(fd[1]);
        int st = drape_cli_specimens_run(&ca);
        fflush(stdout);
        _exit(st);
    }
    close(fd[1]);
    size_t len = 0, cap = 0;
    char *text = NULL;
    int nomem = 0;
    for (;;) {
        if (len + 4097 > cap) {
            char *t = drape_realloc(text, cap = 2 * cap + 8192);
            if (!t) {
                nomem = 1;
                break;
            }
            text = t;
        }
        ssize_t k = read(fd[0], text + len, cap - len - 1);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) break;
        len += (size_t)k;
    }
    close(fd[0]);
    int wst = 0;
    while (waitpid(pid, &wst, 0) < 0 && errno == EINTR) {
    }
    int status = WIFEXITED(wst) ? WEXITSTATUS(wst) : 128 + (WIFSIGNALED(wst) ? WTERMSIG(wst) : 0);
    /* 0, or every specimen failed numerically (its result says so) */
    if (status != 0 && status != drape_error_exit_status(DRAPE_E_NUMERIC)) {
        fprintf(stderr, "drape: --convergence: the ensemble at the coarser spacing %.4g cm "
                "stopped (exit status %d)\n", 100.0 * c.spacing_m, status);
        drape_free(text);
        return status;
    }
    if (nomem || !text) {
        drape_free(text);
        fprintf(stderr, "drape: --convergence: out of memory\n");
        return drape_error_exit_status(DRAPE_E_NOMEM);
    }
    text[len] = 0;
    if (coarse_stats(text, &c.st) != 0) {
        drape_free(text);
        fprintf(stderr, "drape: --convergence: the coarse ensemble gave no result\n");
        return drape_error_exit_status(DRAPE_E_INTERNAL);
    }
    drape_free(text);
    run_args fa = *a;
    fa.convergence = 0;
    fa.coarse = &c;
    return drape_cli_specimens_run(&fa);
}

/* cli_compare.c: `drape compare REFERENCE.json OTHER.json`: are two drape
 * tests (results of `drape run`, one JSON object each, usually ensembles
 * of repeated specimens) distinguishable?  Prints one JSON object:
 *
 *   p_nodes      exact test of the two node-count histograms (Freeman-
 *                Halton, ensemble.h): small p = different distributions
 *   p_mean       Welch's t test of the mean DCs
 *   p_dc_dist    two-sample Kolmogorov-Smirnov test of the DC
 *                distributions (permutation p value, ensemble.h): means
 *                can agree while the rest states differ
 *   dc_diff      OTHER's mean DC minus REFERENCE's
 *   dc_diff_ci95 half-width of the 95 % interval of that difference
 *                (Welch): the uncertainty of both means, not only the
 *                reference's
 *   dc_in_ci95   1 when |dc_diff| <= REFERENCE's dc_ci95
 *   cpu_ratio    REFERENCE's CPU seconds per specimen / OTHER's
 *   same_case    1 when both files give fabric, scene, energy_form,
 *                terms and spacing_m and they agree; 0 when one of them
 *                differs (a warning on stderr names each difference);
 *                null when none differs but a file lacks one
 *
 * and the inputs' n, dc, dc_ci95, nodes_hist and those five keys.  A fast
 * method is judged against the accurate one by exactly these numbers
 * (docs/ensemble.md).  Exit status 0, or 1/3 for unreadable input; a
 * number outside the normal doubles anywhere in a file is refused at its
 * line and key (drape_cli_read_json_in_range, as `drape import` reads).
 */
#include <math.h>
#include <stdio.h>
#include <unistd.h>
#include <stdlib.h>
#include <string.h>

#include <json-c/json.h>

#include "cli.h"
#include "cli_io.h"
#include "drape/alloc.h"
#include "drape/ensemble.h"
#include "drape/scene.h"

static const char compare_usage[] =
    "Usage: drape compare [--format json|text] REFERENCE.json OTHER.json\n"
    "\n"
    "Compare two drape tests: the results of `drape run` (one JSON object\n"
    "each, e.g. ensembles of --specimens N).  Prints one JSON object with\n"
    "p_nodes (exact test of the node-count histograms), p_mean (Welch's t test\n"
    "of the mean DCs), p_dc_dist (Kolmogorov-Smirnov test of the DC\n"
    "distributions, by permutation), dc_diff (OTHER - REFERENCE) with\n"
    "dc_diff_ci95 (the 95 % half-width of that difference, Welch),\n"
    "dc_in_ci95 (|dc_diff| within REFERENCE's 95 % half-width), cpu_ratio\n"
    "(REFERENCE's CPU seconds per specimen over OTHER's), same_case (1 when\n"
    "both are of the same fabric, scene, energy_form, terms and spacing_m;\n"
    "0 when one differs, with a warning on stderr for each difference; null\n"
    "when a file does not say) and both inputs'\n"
    "n, dc, dc_sd, dc_ci95, nodes (the most frequent count), nodes_hist,\n"
    "cpu_per_specimen_s, fabric, scene, energy_form, terms, spacing_m, in the\n"
    "objects `reference` and `other`.  A p value below 0.05 means the two\n"
    "differ at the 5 % level (docs/ensemble.md).\n"
    "\n"
    "  --format json|text   JSON (the default when stdout is not a terminal),\n"
    "                       or a few lines for a person with the verdict in\n"
    "                       words (the default on a terminal)\n"
    "\n"
    "Exit status: 0 success, 1 a file is not a drape result, 2 bad command\n"
    "line, 3 a file cannot be read.\n";

typedef struct side {
    drape_ensemble_stats st;
    double dc[DRAPE_SCENE_SPECIMENS_MAX]; /* the specimens' finite DCs */
    int ndc;
    double cpu_per;
    json_object *hist;
    /* what was draped: fabric, scene, energy_form, terms (NULL where
     * missing or null) and spacing_m (NAN) */
    const char *what[4];
    double spacing_m;
} side;

static const char *const what_keys[4] = {"fabric", "scene", "energy_form", "terms"};


/* The number at key (NAN where it is null or missing); -1 with err set
 * where it is something else, or a node count that is not a whole
 * number >= 0.  where: "specimens[3]" or NULL (the top level). */
static int field(const char *path, json_object *o, const char *key, const char *where,
                 int count, double *out, drape_error *err)
{
    json_object *v;
    *out = NAN;
    if (!json_object_object_get_ex(o, key, &v) || !v) return 0;
    char k[64];
    snprintf(k, sizeof k, "%s%s%s", where ? where : "", where ? "." : "", key);
    if (!json_object_is_type(v, json_type_double) && !json_object_is_type(v, json_type_int))
        return drape_error_set(err, DRAPE_E_INPUT, path, 0, 0, k, "expected a number or null, "
                               "got %s", json_object_to_json_string(v));
    *out = json_object_get_double(v);
    if (count && !(*out >= 0.0 && *out == floor(*out) && *out <= DRAPE_ENSEMBLE_MAX_NODES))
        return drape_error_set(err, DRAPE_E_INPUT, path, 0, 0, k,
                               "expected a node count from 0 to %d, got %g",
                               DRAPE_ENSEMBLE_MAX_NODES, *out);
    if (!count && !isfinite(*out))
        return drape_error_set(err, DRAPE_E_INPUT, path, 0, 0, k, "expected a finite number");
    return 0;
}

/* The statistics of a result, from its specimens array (or, for a result
 * of one specimen written before ensembles, from dc and nodes). */
static int load(const char *path, side *s, json_object **keep, drape_error *err)
{
    json_object *o = drape_cli_read_json_in_range(path, (size_t)64 << 20, err);
    if (!o) return -1;
    if (!json_object_is_type(o, json_type_object)) {
        json_object_put(o);
        return drape_error_set(err, DRAPE_E_INPUT, path, 0, 0, NULL,
                               "not one JSON object (the output of `drape run`)");
    }
    *keep = o;
    json_object *sp;
    int n = 0;
    double dcs[DRAPE_SCENE_SPECIMENS_MAX];
    int nodes[DRAPE_SCENE_SPECIMENS_MAX];
    if (json_object_object_get_ex(o, "specimens", &sp) && sp) {
        if (!json_object_is_type(sp, json_type_array))
            return drape_error_set(err, DRAPE_E_INPUT, path, 0, 0, "specimens",
                                   "expected an array of specimens");
        int m = (int)json_object_array_length(sp);
        if (m > DRAPE_SCENE_SPECIMENS_MAX)
            return drape_error_set(err, DRAPE_E_INPUT, path, 0, 0, "specimens",
                                   "%d specimens: at most %d", m, DRAPE_SCENE_SPECIMENS_MAX);
        for (int k = 0; k < m; k++) {
            json_object *e = json_object_array_get_idx(sp, (size_t)k);
            char where[40];
            snprintf(where, sizeof where, "specimens[%d]", k);
            if (!e || !json_object_is_type(e, json_type_object))
                return drape_error_set(err, DRAPE_E_INPUT, path, 0, 0, where,
                                       "expected an object");
            double dc, nd;
            if (field(path, e, "dc", where, 0, &dc, err) != 0 ||
                field(path, e, "nodes", where, 1, &nd, err) != 0)
                return -1;
            dcs[n] = dc;
            nodes[n] = isfinite(nd) ? (int)nd : -1;
            n++;
        }
    } else {
        double dc, nd;
        if (field(path, o, "dc", NULL, 0, &dc, err) != 0 ||
            field(path, o, "nodes", NULL, 1, &nd, err) != 0)
            return -1;
        if (isfinite(dc)) {
            dcs[0] = dc;
            nodes[0] = isfinite(nd) ? (int)nd : -1;
            n = 1;
        }
    }
    double cpu;
    if (field(path, o, "cpu_s", NULL, 0, &cpu, err) != 0 ||
        field(path, o, "spacing_m", NULL, 0, &s->spacing_m, err) != 0)
        return -1;
    for (int k = 0; k < 4; k++) {
        json_object *v;
        s->what[k] = NULL;
        if (!json_object_object_get_ex(o, what_keys[k], &v) || !v) continue;
        if (!json_object_is_type(v, json_type_string))
            return drape_error_set(err, DRAPE_E_INPUT, path, 0, 0, what_keys[k],
                                   "expected a string or null, got %s",
                                   json_object_to_json_string(v));
        s->what[k] = json_object_get_string(v); /* lives as long as *keep */
    }
    drape_ensemble_stats_compute(dcs, nodes, n, &s->st);
    s->ndc = 0;
    /* the specimens the statistics count (a DC and a node count), for
     * the KS test too: one with a DC but no node count was in KS only */
    for (int k = 0; k < n; k++)
        if (isfinite(dcs[k]) && nodes[k] >= 0) s->dc[s->ndc++] = dcs[k];
    if (s->st.n == 0)
        return drape_error_set(err, DRAPE_E_INPUT, path, 0, 0, "specimens",
                               "no specimen with a drape coefficient and a node count");
    s->cpu_per = cpu / (n > 0 ? n : 1);
    return 0;
}

static json_object *dnum(double v)
{
    if (!isfinite(v)) return NULL;
    char b[40];
    snprintf(b, sizeof b, "%.6g", v);
    return json_object_new_double_s(v, b);
}

static json_object *side_json(const side *s)
{
    json_object *o = json_object_new_object(), *h = json_object_new_object();
    json_object_object_add(o, "n", json_object_new_int(s->st.n));
    json_object_object_add(o, "dc", dnum(s->st.dc_mean));
    json_object_object_add(o, "dc_sd", dnum(s->st.dc_sd));
    json_object_object_add(o, "dc_ci95", dnum(s->st.dc_ci95));
    json_object_object_add(o, "nodes", json_object_new_int(s->st.nodes_mode));
    for (int k = 0; k <= DRAPE_ENSEMBLE_MAX_NODES; k++) {
        if (!s->st.hist[k]) continue;
        char key[16];
        snprintf(key, sizeof key, "%d", k);
        json_object_object_add(h, key, json_object_new_int(s->st.hist[k]));
    }
    json_object_object_add(o, "nodes_hist", h);
    json_object_object_add(o, "cpu_per_specimen_s", dnum(s->cpu_per));
    for (int k = 0; k < 4; k++)
        json_object_object_add(o, what_keys[k],
                               s->what[k] ? json_object_new_string(s->what[k]) : NULL);
    json_object_object_add(o, "spacing_m", dnum(s->spacing_m));
    return o;
}

static void hist_text(const side *s, char *b, size_t cap)
{
    size_t n = 0;
    b[0] = 0;
    for (int k = 0; k <= DRAPE_ENSEMBLE_MAX_NODES && n + 1 < cap; k++) {
        if (!s->st.hist[k]) continue;
        int w = snprintf(b + n, cap - n, "%s%d: %d", n ? ", " : "{", k, s->st.hist[k]);
        if (w < 0 || (size_t)w >= cap - n) break;
        n += (size_t)w;
    }
    if (n + 2 < cap) snprintf(b + n, cap - n, n ? "}" : "{}");
}

static void dc_text(const side *s, char *b, size_t cap)
{
    if (!isfinite(s->st.dc_mean)) snprintf(b, cap, "none");
    else if (isfinite(s->st.dc_ci95)) snprintf(b, cap, "%.3f +- %.3f", s->st.dc_mean, s->st.dc_ci95);
    else snprintf(b, cap, "%.3f", s->st.dc_mean);
}

/* p as a person reads it; "n/a" where the test has nothing to go on */
static const char *p_text(double p, char *b, size_t cap)
{
    if (!isfinite(p)) snprintf(b, cap, "n/a");
    else snprintf(b, cap, "%.3g", p);
    return b;
}

/* The summary for a person (--format text): the two drape tests side by
 * side, the difference of the means and the verdict of the three tests
 * at the 5 % level in words. */
static void print_text(const char *ref, const char *oth, const side *a, const side *b,
                       double diff, double diff_ci, double p_nodes, double p_mean,
                       double p_dist, int same)
{
    char x[160], y[160], q[3][32];
    printf("reference  %s: %s, %s, spacing %.3g cm\n", ref, a->what[0] ? a->what[0] : "?",
           a->what[1] ? a->what[1] : "?", 100.0 * a->spacing_m);
    printf("other      %s: %s, %s, spacing %.3g cm\n", oth, b->what[0] ? b->what[0] : "?",
           b->what[1] ? b->what[1] : "?", 100.0 * b->spacing_m);
    printf("                     %-30s %s\n", "reference", "other");
    printf("  specimens          %-30d %d\n", a->st.n, b->st.n);
    dc_text(a, x, sizeof x);
    dc_text(b, y, sizeof y);
    printf("  drape coefficient  %-30s %s   (mean +- 95 %% interval)\n", x, y);
    hist_text(a, x, sizeof x);
    hist_text(b, y, sizeof y);
    printf("  nodes              %-30s %s   {nodes: specimens}\n", x, y);
    snprintf(x, sizeof x, "%.3g s", a->cpu_per);
    snprintf(y, sizeof y, "%.3g s", b->cpu_per);
    printf("  CPU per specimen   %-30s %s\n", x, y);
    if (isfinite(diff))
        printf("  difference         %+.4f +- %.4f (other - reference, 95 %% interval)\n", diff,
               isfinite(diff_ci) ? diff_ci : NAN);
    p_text(p_nodes, q[0], sizeof q[0]);
    p_text(p_mean, q[1], sizeof q[1]);
    p_text(p_dist, q[2], sizeof q[2]);
    int apart = (isfinite(p_nodes) && p_nodes < 0.05) || (isfinite(p_mean) && p_mean < 0.05) ||
                (isfinite(p_dist) && p_dist < 0.05);
    printf("  verdict            %s at the 5 %% level (p: node histograms %s, means %s, DC "
           "distributions %s)\n",
           apart ? "distinguished" : "not distinguished", q[0], q[1], q[2]);
    if (isfinite(diff))
        printf("                     the means differ by %s 0.01\n",
               fabs(diff) < 0.01 ? "less than" : "at least");
    if (!same) printf("  note               the two are not of the same case (warnings above)\n");
}

int drape_cli_compare(int argc, char **argv)
{
    /* --format json|text (or --format=...), anywhere before the files */
    int fmt = -1;
    for (int i = 1; i < argc; i++) {
        const char *v = NULL;
        int drop = 0;
        if (strcmp(argv[i], "--format") == 0) {
            if (i + 1 >= argc) {
                fputs("drape compare: --format: expected json or text\nTry `drape compare "
                      "--help'.\n", stderr);
                return drape_error_exit_status(DRAPE_E_USAGE);
            }
            v = argv[i + 1];
            drop = 2;
        } else if (strncmp(argv[i], "--format=", 9) == 0) {
            v = argv[i] + 9;
            drop = 1;
        } else if (strcmp(argv[i], "--") == 0) {
            break;
        }
        if (!drop) continue;
        if (strcmp(v, "json") == 0) fmt = 0;
        else if (strcmp(v, "text") == 0) fmt = 1;
        else {
            fprintf(stderr, "drape compare: --format: expected json or text, got `%s'\nTry "
                    "`drape compare --help'.\n", v);
            return drape_error_exit_status(DRAPE_E_USAGE);
        }
        for (int k = i; k + drop <= argc; k++) argv[k] = argv[k + drop];
        argc -= drop;
        i--;
    }
    if (fmt < 0) fmt = isatty(STDOUT_FILENO) ? 1 : 0;
    if (argc == 2 && (strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "--help") == 0)) {
        fputs(compare_usage, stdout);
        return 0;
    }
    for (int i = 1; i < argc; i++)
        if (argv[i][0] == '-' && argv[i][1] != 0) {
            fprintf(stderr, "drape compare: unrecognized option '%s'\nTry `drape compare "
                    "--help'.\n", argv[i]);
            return drape_error_exit_status(DRAPE_E_USAGE);
        }
    if (argc != 3) {
        fputs("drape: compare: expected two result files\nTry `drape compare --help'.\n", stderr);
        return drape_error_exit_status(DRAPE_E_USAGE);
    }
    drape_error err;
    drape_error_clear(&err);
    side a, b;
    json_object *ja = NULL, *jb = NULL;
    int status = 0;
    if (load(argv[1], &a, &ja, &err) != 0 || load(argv[2], &b, &jb, &err) != 0) {
        drape_cli_print_error(&err);
        status = drape_error_exit_status(err.kind);
        goto out;
    }
    /* two drape tests of different things can be compared (two fabrics),
     * but a fast method is judged against its reference on the same
     * fabric, scene and lattice: say where they differ */
    int same = 1, unknown = 0;
    for (int k = 0; k < 4; k++)
        if (!a.what[k] || !b.what[k])
            unknown = 1;
        else if (strcmp(a.what[k], b.what[k]) != 0) {
            fprintf(stderr, "drape: compare: warning: %s differs: '%s' in %s, '%s' in %s\n",
                    what_keys[k], a.what[k], argv[1], b.what[k], argv[2]);
            same = 0;
        }
    if (!isfinite(a.spacing_m) || !isfinite(b.spacing_m))
        unknown = 1;
    else if (fabs(a.spacing_m - b.spacing_m) > 1e-9 * fmax(a.spacing_m, b.spacing_m)) {
        fprintf(stderr, "drape: compare: warning: spacing_m differs: %g m in %s, %g m in %s\n",
                a.spacing_m, argv[1], b.spacing_m, argv[2]);
        same = 0;
    }
    double diff = b.st.dc_mean - a.st.dc_mean;
    double p_nodes = drape_ensemble_exact_p(a.st.hist, b.st.hist, DRAPE_ENSEMBLE_MAX_NODES + 1);
    double p_mean = drape_ensemble_welch_p(&a.st, &b.st);
    double p_dist = drape_ensemble_ks_p(a.dc, a.ndc, b.dc, b.ndc);
    double diff_ci = drape_ensemble_welch_ci95(&a.st, &b.st);
    if (fmt == 1) {
        print_text(argv[1], argv[2], &a, &b, diff, diff_ci, p_nodes, p_mean, p_dist, same);
        if (fflush(stdout) != 0) status = drape_error_exit_status(DRAPE_E_IO);
        goto out;
    }
    json_object *o = json_object_new_object();
    json_object_object_add(o, "p_nodes", dnum(p_nodes));
    json_object_object_add(o, "p_mean", dnum(p_mean));
    json_object_object_add(o, "p_dc_dist", dnum(p_dist));
    json_object_object_add(o, "dc_diff", dnum(diff));
    json_object_object_add(o, "dc_diff_ci95", dnum(diff_ci));
    json_object_object_add(o, "dc_in_ci95",
                           isfinite(a.st.dc_ci95) ? json_object_new_int(fabs(diff) <= a.st.dc_ci95)
                                                  : NULL);
    json_object_object_add(o, "cpu_ratio", dnum(a.cpu_per / b.cpu_per));
    json_object_object_add(o, "same_case",
                           same && unknown ? NULL : json_object_new_int(same));
    json_object_object_add(o, "reference", side_json(&a));
    json_object_object_add(o, "other", side_json(&b));
    printf("%s\n", json_object_to_json_string_ext(o, JSON_C_TO_STRING_SPACED |
                                                      JSON_C_TO_STRING_NOSLASHESCAPE));
    json_object_put(o);
    if (fflush(stdout) != 0) status = drape_error_exit_status(DRAPE_E_IO);
out:
    if (ja) json_object_put(ja);
    if (jb) json_object_put(jb);
    return status;
}

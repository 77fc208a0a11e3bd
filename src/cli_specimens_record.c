/* cli_specimens_record.c: the record an ensemble keeps in its --out DIR
 * (cli_specimens.h): the manifest DIR/ensemble.json written when it
 * starts and at the end of each part, each finished specimen's result in
 * DIR/specimen-NNN/result.txt, and `drape run --resume DIR`, which reads
 * them back, refuses a directory whose inputs changed, and continues the
 * ensemble (cli_specimens.c runs it).  Contract: docs/ensemble.md,
 * "Resuming an ensemble"; docs/outputs.md. */
#include "cli_specimens.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <json-c/json.h>

#include "cli.h"
#include "cli_io.h"
#include "cli_result.h"
#include "drape/alloc.h"
#include "drape/output.h"
#include "drape/scene.h"
#include "drape/yamldoc.h"

#define ENS_MANIFEST_MAX (1 << 20)
#define ENS_RESULT_MAX (16 << 20)

/* ---- the manifest ------------------------------------------------------------ */

/* path made absolute against the working directory (as the single run's
 * checkpoint stores it), so that --resume works from anywhere */
static int absolute(const char *path, char *out, size_t n, drape_error *err)
{
    char cwd[PATH_MAX];
    int r;
    if (path[0] == '/') r = snprintf(out, n, "%s", path);
    else if (getcwd(cwd, sizeof cwd)) r = snprintf(out, n, "%s/%s", cwd, path);
    else
        return drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL,
                               "cannot make the path absolute: %s", strerror(errno));
    if (r < 0 || (size_t)r >= n)
        return drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "path too long");
    return 0;
}

static void set_paths(ens_record *m, const char *dir)
{
    snprintf(m->dir, sizeof m->dir, "%s", dir);
    snprintf(m->path, sizeof m->path, "%s/" DRAPE_ENSEMBLE_MANIFEST, dir);
}

static int add(json_object *o, const char *key, json_object *v)
{
    if (!v) return -1;
    json_object_object_add(o, key, v);
    return 0;
}

/* a time in seconds, printed as drape prints numbers (%.10g) */
static json_object *seconds(double v)
{
    char buf[32];
    snprintf(buf, sizeof buf, "%.10g", v);
    return json_object_new_double_s(v, buf);
}

static int add_sum(json_object *o, const char *key, const char *path, drape_error *err)
{
    unsigned long long sum;
    if (drape_cli_file_sum(path, DRAPE_YDOC_MAX_BYTES, &sum, err) != 0) return -1;
    char hex[24];
    snprintf(hex, sizeof hex, "%016llx", sum);
    return add(o, key, json_object_new_string(hex)) == 0
               ? 0
               : drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
}

int drape_cli_ens_record_new(ens_record *m, const char *dir, const run_args *a,
                             const char *fabric_path, int n, unsigned long seed0,
                             drape_error *err)
{
    memset(m, 0, sizeof *m);
    set_paths(m, dir);
    m->n = n;
    m->seed0 = seed0;
    snprintf(m->status, sizeof m->status, "running");
    /* the id tells this ensemble's results and checkpoints from those an
     * earlier one left in DIR */
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    snprintf(m->id, sizeof m->id, "%llx-%lx-%lx", (unsigned long long)ts.tv_sec,
             (unsigned long)ts.tv_nsec, (unsigned long)getpid());
    char scene[PATH_MAX], fabric[PATH_MAX];
    if (absolute(a->scene_path, scene, sizeof scene, err) != 0 ||
        absolute(fabric_path, fabric, sizeof fabric, err) != 0)
        return -1;
    json_object *o = m->root = json_object_new_object(), *opts = json_object_new_object();
    if (!o || !opts) {
        json_object_put(opts);
        return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
    }
    int bad = add(o, "drape_ensemble", json_object_new_int(ENS_FORMAT));
    bad |= add(o, "id", json_object_new_string(m->id));
    bad |= add(o, "scene", json_object_new_string(scene));
    if (bad) goto nomem;
    if (add_sum(o, "scene_sum", scene, err) != 0) return -1;
    bad |= add(o, "fabric", json_object_new_string(fabric));
    bad |= add(o, "fabric_given", json_object_new_boolean(a->fabric_path != NULL));
    if (bad) goto nomem;
    if (add_sum(o, "fabric_sum", fabric, err) != 0) return -1;
    for (int i = 0; i < a->n_given; i++) {
        char name[48];
        snprintf(name, sizeof name, "--%s", a->given_name[i]);
        bad |= add(opts, name, json_object_new_string(a->given_text[i]));
    }
    json_object_object_add(o, "options", opts);
    bad |= add(o, "specimens", json_object_new_int(n));
    bad |= add(o, "seed", json_object_new_int64((int64_t)seed0));
    bad |= add(o, "status", json_object_new_string(m->status));
    bad |= add(o, "parts", json_object_new_int(0));
    bad |= add(o, "cpu_s", seconds(0.0));
    bad |= add(o, "wall_s", seconds(0.0));
    if (!bad) return 0;
nomem:
    return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
}

int drape_cli_ens_record_write(const ens_record *m, drape_error *err)
{
    const char *text =
        json_object_to_json_string_ext(m->root, JSON_C_TO_STRING_PRETTY | JSON_C_TO_STRING_NOSLASHESCAPE);
    if (!text) return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
    drape_cli_afile af;
    if (drape_cli_afile_open(&af, m->path, err) != 0) return -1;
    if (fputs(text, af.f) == EOF || fputc('\n', af.f) == EOF) {
        int e = errno;
        drape_cli_afile_abort(&af);
        return drape_error_set(err, DRAPE_E_IO, m->path, 0, 0, NULL, "cannot write: %s",
                               strerror(e));
    }
    return drape_cli_afile_commit(&af, err);
}

int drape_cli_ens_record_end(ens_record *m, const char *status, double cpu_s, double wall_s,
                             drape_error *err)
{
    json_object *parts;
    int np = json_object_object_get_ex(m->root, "parts", &parts) ? json_object_get_int(parts) : 0;
    int bad = add(m->root, "status", json_object_new_string(status));
    bad |= add(m->root, "parts", json_object_new_int(np + 1));
    bad |= add(m->root, "cpu_s", seconds(cpu_s));
    bad |= add(m->root, "wall_s", seconds(wall_s));
    if (bad) return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
    snprintf(m->status, sizeof m->status, "%s", status);
    return drape_cli_ens_record_write(m, err);
}

void drape_cli_ens_record_free(ens_record *m)
{
    json_object_put(m->root);
    m->root = NULL;
}

/* ---- one specimen's result ------------------------------------------------------ */

static void result_path(const ens_record *m, int k, char *out, size_t n)
{
    snprintf(out, n, "%s/specimen-%03d/" ENS_RESULT, m->dir, k + 1);
}

int drape_cli_ens_result_store(const ens_record *m, int k, int exit_status, double cpu_s,
                               const char *text, size_t len, drape_error *err)
{
    char dir[4200], path[4300];
    snprintf(dir, sizeof dir, "%s/specimen-%03d", m->dir, k + 1);
    /* (a specimen that wrote nothing removed the directory it made) */
    if (drape_cli_ensure_dir(dir, NULL, err) != 0) return -1;
    result_path(m, k, path, sizeof path);
    drape_cli_afile af;
    if (drape_cli_afile_open(&af, path, err) != 0) return -1;
    fprintf(af.f, "@ensemble\t%s\n@seed\t%lu\n@exit\t%d\n@cpu_s\t%.17g\n", m->id,
            m->seed0 + (unsigned long)k, exit_status, cpu_s);
    if ((len && fwrite(text, 1, len, af.f) != len) || ferror(af.f)) {
        int e = errno;
        drape_cli_afile_abort(&af);
        return drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "cannot write: %s",
                               strerror(e));
    }
    return drape_cli_afile_commit(&af, err);
}

/* The value of the line "@name\tVALUE\n" at *p (advanced past it), NUL
 * terminated in place; NULL if *p is not that line. */
static char *at_line(char **p, const char *name)
{
    size_t nl = strlen(name);
    if ((*p)[0] != '@' || strncmp(*p + 1, name, nl) != 0 || (*p)[1 + nl] != '\t') return NULL;
    char *v = *p + 2 + nl, *end = strchr(v, '\n');
    if (!end) return NULL;
    *end = 0;
    *p = end + 1;
    return v;
}

/* A stored time (CPU or wall) that can be added up: finite and >= 0 (an inf made
 * the ensemble's cpu_s inf, and ensemble.json invalid JSON). */
static int is_seconds(double v)
{
    return isfinite(v) && v >= 0;
}

char *drape_cli_ens_result_load(const ens_record *m, int k, int *exit_status, double *cpu_s)
{
    char path[4300];
    result_path(m, k, path, sizeof path);
    if (access(path, F_OK) != 0) return NULL;
    drape_error e;
    drape_error_clear(&e);
    size_t len = 0;
    char *text = drape_cli_read_file(path, ENS_RESULT_MAX, &len, &e);
    if (!text) {
        drape_cli_print_error(&e);
        return NULL;
    }
    if (strlen(text) != len) { /* (a NUL byte) */
        drape_free(text);
        return NULL;
    }
    char *p = text, *id = at_line(&p, "ensemble"), *seed = id ? at_line(&p, "seed") : NULL;
    char *ex = seed ? at_line(&p, "exit") : NULL, *cpu = ex ? at_line(&p, "cpu_s") : NULL;
    if (!cpu || strcmp(id, m->id) != 0) {
        drape_free(text);
        return NULL; /* another ensemble's, or not one at all: run it */
    }
    /* this ensemble's, of another specimen's seed (moved or edited) */
    unsigned long want = m->seed0 + (unsigned long)k;
    int digits = *seed && strspn(seed, "0123456789") == strlen(seed);
    if (!digits || strtoul(seed, NULL, 10) != want) {
        /* the stored text is shown only when it is a number: a damaged
         * file's control characters do not reach the terminal */
        fprintf(stderr, "drape: %s: warning: @seed is %.40s, not this specimen's %lu; the "
                "specimen runs again\n", path, digits ? seed : "not a whole number", want);
        drape_free(text);
        return NULL;
    }
    /* this ensemble's specimen: its exit status and CPU time must be ones
     * (a damaged @cpu_s 1e999 made the ensemble's cpu_s inf, and
     * ensemble.json invalid JSON) */
    const char *e1, *e2, *bad = NULL;
    double xv, cv;
    if (drape_cli_result_parse_num(ex, &e1, &xv) != 0 || *e1 || xv != floor(xv) ||
        !(xv >= 0 && xv <= 255))
        bad = "@exit is not an exit status (an integer from 0 to 255)";
    else if (drape_cli_result_parse_num(cpu, &e2, &cv) != 0 || *e2 || !is_seconds(cv))
        bad = "@cpu_s is not a CPU time (a finite number of seconds, >= 0)";
    if (bad) {
        fprintf(stderr, "drape: %s: warning: %s; the specimen runs again\n", path, bad);
        drape_free(text);
        return NULL;
    }
    *exit_status = (int)xv;
    *cpu_s = cv;
    memmove(text, p, strlen(p) + 1);
    return text;
}

void drape_cli_ens_result_remove(const ens_record *m, int k)
{
    char path[4300];
    result_path(m, k, path, sizeof path);
    unlink(path);
}

int drape_cli_ens_checkpoint(const ens_record *m, int k, double *cpu_s)
{
    char path[4300];
    snprintf(path, sizeof path, "%s/specimen-%03d/drape.h5", m->dir, k + 1);
    *cpu_s = 0.0;
    if (access(path, F_OK) != 0) return 0;
    drape_h5_checkpoint c;
    drape_error e;
    drape_error_clear(&e);
    int ok = 0;
    if (drape_h5_checkpoint_read(path, &c, &e) == 0) {
        const drape_kv *st = drape_kv_find(c.stats, c.n_stats, "status");
        const drape_kv *id = drape_kv_find(c.run, c.n_run, "ensemble_id");
        const drape_kv *cpu = drape_kv_find(c.stats, c.n_stats, "cpu_s");
        const drape_kv *sd = drape_kv_find(c.run, c.n_run, "seed");
        ok = st && st->text && strcmp(st->text, "interrupted") == 0 && id && id->text &&
             strcmp(id->text, m->id) == 0;
        /* this ensemble's, and of this specimen's seed (else another
         * specimen's run would be reported as this one) */
        unsigned long want = m->seed0 + (unsigned long)k;
        if (ok && !(sd && !sd->text && sd->value == (double)want)) {
            if (sd && !sd->text && !isnan(sd->value))
                fprintf(stderr, "drape: %s: warning: the checkpoint's seed is %.17g, not this "
                        "specimen's %lu; the specimen runs again from the start\n", path,
                        sd->value, want);
            else
                fprintf(stderr, "drape: %s: warning: the checkpoint's seed is not stored (this "
                        "specimen's is %lu); the specimen runs again from the start\n", path,
                        want);
            ok = 0;
        }
        /* its CPU time so far, if stored, must be one (an inf made the
         * ensemble's cpu_s inf, and ensemble.json invalid JSON) */
        if (ok && cpu && (cpu->text || !is_seconds(cpu->value))) {
            if (cpu->text)
                fprintf(stderr, "drape: %s: warning: the checkpoint's cpu_s is not a number; "
                        "the specimen runs again from the start\n", path);
            else
                fprintf(stderr, "drape: %s: warning: the checkpoint's cpu_s is %.17g, not a "
                        "CPU time (a finite number of seconds, >= 0); the specimen runs "
                        "again from the start\n", path, cpu->value);
            ok = 0;
        }
        if (ok && cpu) *cpu_s = cpu->value;
    }
    drape_h5_checkpoint_free(&c);
    return ok;
}

/* ---- --resume -------------------------------------------------------------------- */

/* The manifest's member key of type t, or NULL. */
static json_object *member(json_object *o, const char *key, json_type t)
{
    json_object *v;
    return json_object_object_get_ex(o, key, &v) && v && json_object_is_type(v, t) ? v : NULL;
}

static int damaged(const char *path, const char *what, drape_error *err)
{
    return drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL,
                           "--resume: not an ensemble's manifest that this drape can read "
                           "(%s); the ensemble cannot be resumed: run it again", what);
}

/* A stored input must still have the text the ensemble started with. */
static int same_input(const char *manifest, const char *file, json_object *sum,
                      const char *what, drape_error *err)
{
    unsigned long long now;
    if (drape_cli_file_sum(file, DRAPE_YDOC_MAX_BYTES, &now, err) != 0) return -1;
    char hex[24];
    snprintf(hex, sizeof hex, "%016llx", now);
    if (strcmp(hex, json_object_get_string(sum)) != 0)
        return drape_error_set(err, DRAPE_E_INPUT, file, 0, 0, NULL,
                               "--resume: this %s file changed since the ensemble started "
                               "(its checksum differs from %s_sum in %s): the specimens run "
                               "before and after would differ; restore it, or start a new "
                               "ensemble", what, what, manifest);
    return 0;
}

/* Read DIR/ensemble.json into m and the run's options into ra. */
static int read_manifest(const char *dir, ens_record *m, run_args *ra, drape_error *err)
{
    memset(m, 0, sizeof *m);
    set_paths(m, dir);
    if (access(m->path, F_OK) != 0)
        return drape_error_set(err, DRAPE_E_IO, m->path, 0, 0, NULL,
                               "--resume: no such file: %s holds an ensemble's specimens but "
                               "not its manifest (an ensemble run with --out DIR writes it "
                               "when it starts; this one was run by an older drape, or the "
                               "file was removed): it cannot be resumed; run it again", dir);
    drape_error e2;
    drape_error_clear(&e2);
    m->root = drape_cli_read_json(m->path, ENS_MANIFEST_MAX, &e2);
    if (!m->root) {
        if (e2.kind == DRAPE_E_SYNTAX) return damaged(m->path, e2.msg, err);
        *err = e2;
        return -1;
    }
    json_object *o = m->root;
    json_object *fmt = member(o, "drape_ensemble", json_type_int);
    json_object *id = member(o, "id", json_type_string);
    json_object *scene = member(o, "scene", json_type_string);
    json_object *ssum = member(o, "scene_sum", json_type_string);
    json_object *fabric = member(o, "fabric", json_type_string);
    json_object *fsum = member(o, "fabric_sum", json_type_string);
    json_object *given = member(o, "fabric_given", json_type_boolean);
    json_object *opts = member(o, "options", json_type_object);
    json_object *n = member(o, "specimens", json_type_int);
    json_object *seed = member(o, "seed", json_type_int);
    json_object *status = member(o, "status", json_type_string);
    json_object *parts = member(o, "parts", json_type_int);
    json_object *cpu = member(o, "cpu_s", json_type_double);
    json_object *wall = member(o, "wall_s", json_type_double);
    if (!cpu) cpu = member(o, "cpu_s", json_type_int);
    if (!wall) wall = member(o, "wall_s", json_type_int);
    if (!fmt || !id || !scene || !ssum || !fabric || !fsum || !given || !opts || !n || !seed ||
        !status || !parts || !cpu || !wall)
        return damaged(m->path, "a member is missing or of another type", err);
    if (json_object_get_int(fmt) != ENS_FORMAT)
        return damaged(m->path, "drape_ensemble is not 1", err);
    int64_t nv = json_object_get_int64(n), sv = json_object_get_int64(seed);
    int64_t pv = json_object_get_int64(parts);
    if (nv < 2 || nv > DRAPE_SCENE_SPECIMENS_MAX || sv < 0 || pv < 0 || pv >= INT_MAX ||
        (uint64_t)sv + (uint64_t)nv - 1 > (uint64_t)DRAPE_SCENE_SEED_MAX ||
        strlen(json_object_get_string(id)) >= sizeof m->id ||
        strlen(json_object_get_string(status)) >= sizeof m->status ||
        json_object_get_string(scene)[0] != '/' || json_object_get_string(fabric)[0] != '/')
        return damaged(m->path, "a value out of range", err);
    snprintf(m->id, sizeof m->id, "%s", json_object_get_string(id));
    snprintf(m->status, sizeof m->status, "%s", json_object_get_string(status));
    m->n = (int)nv;
    m->seed0 = (unsigned long)sv;
    m->cpu_s = json_object_get_double(cpu);
    m->wall_s = json_object_get_double(wall);
    if (!is_seconds(m->cpu_s)) m->cpu_s = 0;
    if (!is_seconds(m->wall_s)) m->wall_s = 0;
    m->resuming = 1;
    /* the options, set as the command line set them */
    drape_cli_run_args_init(ra);
    json_object_object_foreach(opts, key, val) {
        char why[512];
        if (!json_object_is_type(val, json_type_string) || strncmp(key, "--", 2) != 0 ||
            ra->n_given == RUN_GIVEN_MAX ||
            drape_cli_run_option(ra, key, json_object_get_string(val), why, sizeof why) != 0)
            return damaged(m->path, "an option drape run does not take", err);
        ra->given_name[ra->n_given] = key + 2;
        ra->given_text[ra->n_given++] = json_object_get_string(val);
    }
    ra->scene_path = json_object_get_string(scene);
    ra->fabric_path = json_object_get_boolean(given) ? json_object_get_string(fabric) : NULL;
    ra->specimens = m->n;
    ra->has_seed = 1;
    ra->seed = m->seed0;
    ra->out_dir = dir;
    /* the inputs as they were */
    if (same_input(m->path, json_object_get_string(scene), ssum, "scene", err) != 0 ||
        same_input(m->path, json_object_get_string(fabric), fsum, "fabric", err) != 0)
        return -1;
    return 0;
}

int drape_cli_specimens_resume(const run_args *a)
{
    drape_error err;
    drape_error_clear(&err);
    ens_record m;
    run_args ra;
    int status;
    if (read_manifest(a->resume_dir, &m, &ra, &err) != 0) {
        drape_cli_print_error(&err);
        status = drape_error_exit_status(err.kind);
    } else {
        ra.csv = a->csv;
        ra.text = a->text;
        ra.quiet = a->quiet;
        ra.jobs = a->jobs;
        status = drape_cli_specimens_drive(&ra, &m);
    }
    drape_cli_ens_record_free(&m);
    return status;
}

/* cli_result.c: `drape run`'s result fields and their JSON, CSV and
 * child-to-parent forms (cli_result.h).  JSON is built with json-c;
 * numbers keep drape's %.10g text (json_object_new_double_s). */
#include "cli_result.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <json-c/json.h>

#include "cli.h"
#include "cli_io.h"
#include "drape/units.h"

static drape_cli_field *push(drape_cli_result *r, const char *key, drape_cli_ftype t)
{
    if (r->n >= DRAPE_CLI_RESULT_MAX) return NULL; /* caught by check_keys */
    drape_cli_field *f = &r->f[r->n++];
    memset(f, 0, sizeof *f);
    snprintf(f->key, sizeof f->key, "%s", key);
    f->type = t;
    f->value = NAN;
    return f;
}

void drape_cli_result_num(drape_cli_result *r, const char *key, double v)
{
    drape_cli_field *f = push(r, key, DRAPE_CLI_F_NUM);
    if (f) f->value = v;
}

void drape_cli_result_int(drape_cli_result *r, const char *key, double v)
{
    drape_cli_field *f = push(r, key, DRAPE_CLI_F_INT);
    if (f) f->value = v;
}

void drape_cli_result_str(drape_cli_result *r, const char *key, const char *s)
{
    drape_cli_field *f = push(r, key, DRAPE_CLI_F_STR);
    if (!f) return;
    if (s) snprintf(f->text, sizeof f->text, "%.*s", (int)sizeof f->text - 1, s); /* cut */
    else f->is_null_text = 1;
}

void drape_cli_result_hist(drape_cli_result *r, const char *key)
{
    push(r, key, DRAPE_CLI_F_HIST);
}

void drape_cli_result_specimens(drape_cli_result *r, const char *key)
{
    push(r, key, DRAPE_CLI_F_SPECIMENS);
}

/* "energy_J.kinetic" and "energy_J_kinetic" name the same field. */
static int same_key(const char *a, const char *b)
{
    for (; *a && *b; a++, b++)
        if (*a != *b && !((*a == '.' && *b == '_') || (*a == '_' && *b == '.'))) return 0;
    return !*a && !*b;
}

const drape_cli_field *drape_cli_result_find(const drape_cli_result *r, const char *key)
{
    for (int i = 0; i < r->n; i++)
        if (same_key(r->f[i].key, key)) return &r->f[i];
    return NULL;
}

double drape_cli_result_get(const drape_cli_result *r, const char *key)
{
    for (int i = 0; i < r->n; i++)
        if (same_key(r->f[i].key, key))
            return r->f[i].type == DRAPE_CLI_F_NUM || r->f[i].type == DRAPE_CLI_F_INT
                       ? r->f[i].value
                       : NAN;
    return NAN;
}

int drape_cli_result_check_keys(const drape_cli_result *r)
{
    if (r->n != drape_cli_run_nkeys()) return 0;
    for (int i = 0; i < r->n; i++)
        if (!same_key(r->f[i].key, drape_cli_run_keys[i])) return 0;
    return 1;
}

/* ---- JSON ------------------------------------------------------------------ */

static json_object *json_num(double v, int is_int)
{
    if (!isfinite(v) || (is_int && v < 0)) return NULL; /* null */
    char buf[40];
    if (is_int) return json_object_new_int64((int64_t)llround(v));
    snprintf(buf, sizeof buf, "%.10g", v);
    return json_object_new_double_s(v, buf);
}

static json_object *json_hist(const int *hist)
{
    json_object *o = json_object_new_object();
    if (!o) return NULL;
    for (int k = 0; k <= DRAPE_ENSEMBLE_MAX_NODES; k++) {
        if (!hist[k]) continue;
        char key[16];
        snprintf(key, sizeof key, "%d", k);
        json_object_object_add(o, key, json_object_new_int(hist[k]));
    }
    return o;
}

static json_object *json_specimens(const drape_cli_specimen *sp, int n)
{
    json_object *a = json_object_new_array();
    if (!a) return NULL;
    for (int k = 0; k < n; k++) {
        json_object *o = json_object_new_object();
        if (!o) {
            json_object_put(a);
            return NULL;
        }
        json_object_object_add(o, "seed", sp[k].seed_unknown
                                              ? NULL
                                              : json_object_new_int64((int64_t)sp[k].seed));
        json_object_object_add(o, "status", json_object_new_string(sp[k].status));
        json_object_object_add(o, "dc", json_num(sp[k].dc, 0));
        json_object_object_add(o, "nodes", json_num(sp[k].nodes, 1));
        json_object_object_add(o, "r_min_m", json_num(sp[k].r_min_m, 0));
        json_object_object_add(o, "r_max_m", json_num(sp[k].r_max_m, 0));
        json_object_object_add(o, "cpu_s", json_num(sp[k].cpu_s, 0));
        json_object_array_add(a, o);
    }
    return a;
}

static json_object *field_json(const drape_cli_result *r, const drape_cli_field *f)
{
    switch (f->type) {
    case DRAPE_CLI_F_NUM: return json_num(f->value, 0);
    case DRAPE_CLI_F_INT: return json_num(f->value, 1);
    case DRAPE_CLI_F_STR: return f->is_null_text ? NULL : json_object_new_string(f->text);
    case DRAPE_CLI_F_HIST: return json_hist(r->hist);
    case DRAPE_CLI_F_SPECIMENS: return json_specimens(r->spec, r->n_spec);
    }
    return NULL;
}

int drape_cli_result_print_json(FILE *out, const drape_cli_result *r)
{
    json_object *root = json_object_new_object();
    if (!root) return -1;
    for (int i = 0; i < r->n; i++) {
        const drape_cli_field *f = &r->f[i];
        const char *dot = strchr(f->key, '.');
        json_object *v = field_json(r, f);
        if (!dot) {
            json_object_object_add(root, f->key, v);
            continue;
        }
        char group[48];
        snprintf(group, sizeof group, "%.*s", (int)(dot - f->key), f->key);
        json_object *g = NULL;
        if (!json_object_object_get_ex(root, group, &g)) {
            g = json_object_new_object();
            json_object_object_add(root, group, g);
        }
        json_object_object_add(g, dot + 1, v);
    }
    fprintf(out, "%s\n",
            json_object_to_json_string_ext(root, JSON_C_TO_STRING_SPACED |
                                                     JSON_C_TO_STRING_NOSLASHESCAPE));
    json_object_put(root);
    return 0;
}

/* ---- CSV ------------------------------------------------------------------- */

static void csv_value(FILE *out, const drape_cli_result *r, const drape_cli_field *f)
{
    switch (f->type) {
    case DRAPE_CLI_F_STR:
        if (!f->is_null_text) drape_cli_csv_put(out, f->text);
        return;
    case DRAPE_CLI_F_HIST: {
        int first = 1;
        for (int k = 0; k <= DRAPE_ENSEMBLE_MAX_NODES; k++) {
            if (!r->hist[k]) continue;
            fprintf(out, "%s%d:%d", first ? "" : ";", k, r->hist[k]);
            first = 0;
        }
        return;
    }
    case DRAPE_CLI_F_SPECIMENS: fprintf(out, "%d", r->n_spec); return;
    case DRAPE_CLI_F_INT:
        if (isfinite(f->value) && f->value >= 0) fprintf(out, "%.0f", f->value);
        return;
    case DRAPE_CLI_F_NUM:
        if (isfinite(f->value)) fprintf(out, "%.10g", f->value);
        return;
    }
}

void drape_cli_result_print_csv(FILE *out, const drape_cli_result *r)
{
    for (int i = 0; i < r->n; i++) {
        if (i) fputc(',', out);
        for (const char *k = r->f[i].key; *k; k++) fputc(*k == '.' ? '_' : *k, out);
    }
    fputc('\n', out);
    for (int i = 0; i < r->n; i++) {
        if (i) fputc(',', out);
        csv_value(out, r, &r->f[i]);
    }
    fputc('\n', out);
}

/* ---- child to parent ------------------------------------------------------- */

/* A text in the parent-child protocol: backslash, tab, newline and
 * carriage return escaped (a fabric's name may hold any of them). */
static void write_text(FILE *out, const char *t)
{
    for (; *t; t++) {
        switch (*t) {
        case '\\': fputs("\\\\", out); break;
        case '\t': fputs("\\t", out); break;
        case '\n': fputs("\\n", out); break;
        case '\r': fputs("\\r", out); break;
        default: fputc(*t, out);
        }
    }
}

/* Undo write_text in place. */
static void unescape_text(char *t)
{
    char *o = t;
    for (; *t; t++) {
        if (*t != '\\' || !t[1]) { *o++ = *t; continue; }
        t++;
        *o++ = *t == 't' ? '\t' : *t == 'n' ? '\n' : *t == 'r' ? '\r' : *t;
    }
    *o = 0;
}

void drape_cli_result_write(FILE *out, const drape_cli_result *r)
{
    for (int i = 0; i < r->n; i++) {
        const drape_cli_field *f = &r->f[i];
        switch (f->type) {
        case DRAPE_CLI_F_NUM: fprintf(out, "%s\tn\t%.17g\n", f->key, f->value); break;
        case DRAPE_CLI_F_INT: fprintf(out, "%s\ti\t%.17g\n", f->key, f->value); break;
        case DRAPE_CLI_F_STR:
            if (f->is_null_text) fprintf(out, "%s\tz\t\n", f->key);
            else {
                fprintf(out, "%s\ts\t", f->key);
                write_text(out, f->text);
                fputc('\n', out);
            }
            break;
        default: break;
        }
    }
}

int drape_cli_result_parse_num(const char *s, const char **end, double *v)
{
    size_t n = strcspn(s, " \t\n");
    char buf[64];
    if (n == 0 || n >= sizeof buf) return -1;
    memcpy(buf, s, n);
    buf[n] = 0;
    char *e;
    int range;
    double x = drape_units_strtod(buf, &e, &range);
    if (e == buf || *e) return -1;
    /* (nan and inf are spelled with letters; an overflow or an underflow
     * to zero is a literal that lies outside the doubles) */
    const char *b = buf + (buf[0] == '-' || buf[0] == '+');
    if (range && !isalpha((unsigned char)*b) && !(isfinite(x) && x != 0.0)) return -1;
    *v = x;
    if (end) *end = s + n;
    return 0;
}

int drape_cli_result_read(const char *text, drape_cli_result *r)
{
    r->n = 0;
    const char *p = text;
    while (*p) {
        const char *nl = strchr(p, '\n');
        if (!nl) return -1;
        const char *t1 = memchr(p, '\t', (size_t)(nl - p));
        if (!t1 || nl - t1 < 3 || t1[2] != '\t') return -1;
        char key[48], val[2 * DRAPE_CLI_TEXT_MAX];
        int kl = (int)(t1 - p), vl = (int)(nl - (t1 + 3));
        if (kl <= 0 || kl >= (int)sizeof key || vl >= (int)sizeof val) return -1;
        memcpy(key, p, (size_t)kl);
        key[kl] = 0;
        memcpy(val, t1 + 3, (size_t)vl);
        val[vl] = 0;
        double x;
        const char *e;
        if ((t1[1] == 'n' || t1[1] == 'i') &&
            (drape_cli_result_parse_num(val, &e, &x) != 0 || *e))
            return -1; /* not a number, or more than one */
        switch (t1[1]) {
        case 'n': drape_cli_result_num(r, key, x); break;
        case 'i': drape_cli_result_int(r, key, x); break;
        case 's':
            unescape_text(val);
            drape_cli_result_str(r, key, val);
            break;
        case 'z': drape_cli_result_str(r, key, NULL); break;
        default: return -1;
        }
        p = nl + 1;
    }
    return 0;
}

/* yread.c: typed values from a parsed YAML document with file:line:key
 * errors (yread.h). */
#include "yread.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *drape_yread_kind(const drape_ynode *n)
{
    if (!n) return "nothing";
    switch (n->type) {
    case DRAPE_YNODE_MAPPING: return "a mapping";
    case DRAPE_YNODE_SEQUENCE: return "a sequence";
    default: return "a scalar";
    }
}

void drape_yread_path(char *out, size_t n, const char *parent, const char *key)
{
    if (parent && parent[0])
        snprintf(out, n, "%s.%s", parent, key);
    else
        snprintf(out, n, "%s", key);
}

void drape_yread_item_path(char *out, size_t n, const char *parent, size_t idx)
{
    snprintf(out, n, "%s[%zu]", parent, idx);
}

/* The message of fmt and ap as an error (or, with kind DRAPE_OK, a
 * warning) at line:column of r's file, into *e. */
static void set_at(const drape_yread *r, drape_error *e, drape_error_kind kind, int line,
                   int column, const char *path, const char *fmt, va_list ap)
{
    char msg[DRAPE_ERROR_MSG_MAX];
    vsnprintf(msg, sizeof msg, fmt, ap);
    drape_error_set(e, kind, r->doc->path, line, column, path, "%s", msg);
}

int drape_yread_error(const drape_yread *r, const drape_ynode *n, const char *path,
                      drape_error_kind kind, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    set_at(r, r->err, kind, n ? n->line : 0, n ? n->column : 0, path, fmt, ap);
    va_end(ap);
    return -1;
}

int drape_yread_key_error(const drape_yread *r, const drape_ynode *map, size_t idx,
                          const char *path, drape_error_kind kind, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    set_at(r, r->err, kind, map->key_line[idx], map->key_column[idx], path, fmt, ap);
    va_end(ap);
    return -1;
}

void drape_yread_warn(const drape_yread *r, const drape_ynode *n, const char *path,
                      const char *fmt, ...)
{
    drape_error w;
    va_list ap;
    if (!r->warn) return;
    drape_error_clear(&w);
    va_start(ap, fmt);
    set_at(r, &w, DRAPE_OK, n ? n->line : 0, n ? n->column : 0, path, fmt, ap);
    va_end(ap);
    r->warn(r->warn_ctx, &w);
}

int drape_yread_is_in(const char *s, const char *const *list)
{
    for (size_t i = 0; list[i]; i++)
        if (strcmp(s, list[i]) == 0) return 1;
    return 0;
}

/* "a, b, c" into buf. */
const char *drape_yread_name_list(const char *const *names, char *buf, size_t n)
{
    size_t k = 0;
    buf[0] = 0;
    for (size_t i = 0; names[i]; i++) {
        int r = snprintf(buf + k, n - k, "%s%s", i ? ", " : "", names[i]);
        if (r < 0 || (size_t)r >= n - k) break;
        k += (size_t)r;
    }
    return buf;
}

int drape_yread_want(const drape_yread *r, const drape_ynode *n, const char *path,
                     drape_ynode_type type, const char *expected)
{
    if (n->type == type) return 0;
    if (n->type == DRAPE_YNODE_SCALAR && !n->scalar[0])
        return drape_yread_error(r, n, path, DRAPE_E_INPUT, "expected %s, got an empty value",
                                 expected);
    if (n->type == DRAPE_YNODE_SCALAR)
        return drape_yread_error(r, n, path, DRAPE_E_INPUT, "expected %s, got a scalar (\"%s\")",
                                 expected, n->scalar);
    return drape_yread_error(r, n, path, DRAPE_E_INPUT, "expected %s, got %s", expected,
                             drape_yread_kind(n));
}

int drape_yread_want_map(const drape_yread *r, const drape_ynode *n, const char *path)
{
    return drape_yread_want(r, n, path, DRAPE_YNODE_MAPPING, "a mapping ({key: value, ...})");
}

/* Required key: its value, or an error at the mapping that lacks it. */
const drape_ynode *drape_yread_need(const drape_yread *r, const drape_ynode *map,
                                    const char *parent, const char *key, const char *example)
{
    const drape_ynode *v = drape_ynode_get(map, key, NULL);
    if (!v) {
        char path[DRAPE_YREAD_PATH_MAX];
        drape_yread_path(path, sizeof path, parent, key);
        drape_yread_error(r, map, path, DRAPE_E_INPUT,
                          "missing required key `%s` (for example `%s`)", key, example);
    }
    return v;
}

/* ------------------------------------------------------------------ */
/* Scalars                                                              */

int drape_yread_want_scalar(const drape_yread *r, const drape_ynode *n, const char *path,
                            const char *expected)
{
    return drape_yread_want(r, n, path, DRAPE_YNODE_SCALAR, expected);
}

/* "a positive length" (sign DRAPE_YREAD_*) into buf; returns buf. */
static const char *signed_noun(char *buf, size_t n, int sign, const char *noun)
{
    snprintf(buf, n, "a %s%s",
             sign == DRAPE_YREAD_POSITIVE      ? "positive "
             : sign == DRAPE_YREAD_NONNEGATIVE ? "non-negative "
                                               : "",
             noun);
    return buf;
}

static int sign_ok(double v, int sign)
{
    return (sign != DRAPE_YREAD_POSITIVE || v > 0.0) &&
           (sign != DRAPE_YREAD_NONNEGATIVE || v >= 0.0);
}

/* Parse a quantity of dimension dim; noun names it in messages
 * ("length", "time", ...). */
int drape_yread_quantity(const drape_yread *r, const drape_ynode *n, const char *path,
                         drape_dim dim, const char *noun, int sign, double *out)
{
    char expected[96], why[384];
    double v;
    signed_noun(expected, sizeof expected, sign, noun);
    if (drape_yread_want_scalar(r, n, path, expected)) return -1;
    if (drape_units_parse(n->scalar, dim, &v, why, sizeof why) != 0) {
        if (strncmp(why, "expected", 8) == 0)
            return drape_yread_error(r, n, path, DRAPE_E_INPUT, "%s", why);
        return drape_yread_error(r, n, path, DRAPE_E_INPUT,
                                 "expected %s, got \"%s\": %s", expected, n->scalar, why);
    }
    if (!isfinite(v) || !sign_ok(v, sign))
        return drape_yread_error(r, n, path, DRAPE_E_INPUT, "expected %s, got \"%s\"",
                                 expected, n->scalar);
    *out = v;
    return 0;
}

/* Optional quantity under key: leaves *out alone when absent. */
int drape_yread_opt_quantity(const drape_yread *r, const drape_ynode *map, const char *parent,
                             const char *key, drape_dim dim, const char *noun, int sign,
                             double *out, const drape_ynode **node)
{
    char path[DRAPE_YREAD_PATH_MAX];
    const drape_ynode *v = drape_ynode_get(map, key, NULL);
    if (node) *node = v;
    if (!v) return 0;
    drape_yread_path(path, sizeof path, parent, key);
    return drape_yread_quantity(r, v, path, dim, noun, sign, out);
}

int drape_yread_req_quantity(const drape_yread *r, const drape_ynode *map, const char *parent,
                             const char *key, drape_dim dim, const char *noun, int sign,
                             const char *example, double *out, const drape_ynode **node)
{
    const drape_ynode *v = drape_yread_need(r, map, parent, key, example);
    if (!v) return -1;
    return drape_yread_opt_quantity(r, map, parent, key, dim, noun, sign, out, node);
}

/* A plain number: decimal with an optional exponent, finite. */
int drape_yread_number(const drape_yread *r, const drape_ynode *n, const char *path, int sign,
                       double *out)
{
    char expected[64], *end = NULL;
    signed_noun(expected, sizeof expected, sign, "number");
    if (drape_yread_want_scalar(r, n, path, expected)) return -1;
    const char *s = n->scalar;
    int ok = s[0] != 0;
    for (const char *p = s; *p && ok; p++)
        if (!isdigit((unsigned char)*p) && !strchr(".eE+-", *p))
            ok = 0; /* no hex, inf, nan, units */
    int range = 0;
    double v = ok ? drape_units_strtod(s, &end, &range) : 0.0;
    if (!ok || end == s || *end != 0)
        return drape_yread_error(r, n, path, DRAPE_E_INPUT, "expected %s, got \"%s\"",
                                 expected, s);
    /* overflow, underflow to 0 and denormals alike (drape_units_strtod) */
    if (range)
        return drape_yread_error(r, n, path, DRAPE_E_INPUT,
                                 "number out of range: \"%s\"", s);
    if (!sign_ok(v, sign))
        return drape_yread_error(r, n, path, DRAPE_E_INPUT, "expected %s, got \"%s\"",
                                 expected, s);
    *out = v;
    return 0;
}

int drape_yread_unit(const drape_yread *r, const drape_ynode *n, const char *path,
                     drape_dim dim, const char *noun, double *scale)
{
    char why[256];
    drape_dim d;
    if (drape_yread_want_scalar(r, n, path, "a unit")) return -1;
    if (drape_units_parse_unit(n->scalar, scale, &d, why, sizeof why))
        return drape_yread_error(r, n, path, DRAPE_E_INPUT, "%s", why);
    if (!drape_units_dim_eq(d, dim))
        return drape_yread_error(r, n, path, DRAPE_E_INPUT,
                                 "`%s` is a unit of %s; expected a unit of %s", n->scalar,
                                 drape_units_dim_name(d), noun);
    return 0;
}

int drape_yread_text(const drape_yread *r, const drape_ynode *n, const char *path, int nonempty,
                     char *buf, size_t cap)
{
    if (drape_yread_want_scalar(r, n, path, "text")) return -1;
    size_t len = strlen(n->scalar);
    if (len >= cap)
        return drape_yread_error(r, n, path, DRAPE_E_INPUT,
                                 "too long (%zu bytes; at most %zu)", len, cap - 1);
    if (nonempty && len == 0)
        return drape_yread_error(r, n, path, DRAPE_E_INPUT, "must not be empty");
    memcpy(buf, n->scalar, len + 1);
    return 0;
}

/* One of names[]; *idx its index.  Suggests the nearest name. */
int drape_yread_enum(const drape_yread *r, const drape_ynode *n, const char *path,
                     const char *const *names, int *idx)
{
    char list[256], expected[300];
    drape_yread_name_list(names, list, sizeof list);
    snprintf(expected, sizeof expected, "one of %s", list);
    if (drape_yread_want_scalar(r, n, path, expected)) return -1;
    for (int i = 0; names[i]; i++)
        if (strcmp(n->scalar, names[i]) == 0) {
            *idx = i;
            return 0;
        }
    size_t best = (size_t)-1, limit = strlen(n->scalar) / 2;
    int bi = -1;
    if (limit < 2) limit = 2;
    for (int i = 0; names[i]; i++) {
        size_t d = drape_levenshtein(n->scalar, names[i]);
        if (d < best) {
            best = d;
            bi = i;
        }
    }
    /* a unique name that starts with the text ("cvode" -> "cvode-bdf") */
    if (n->scalar[0] && !(bi >= 0 && best <= limit)) {
        int hits = 0;
        for (int i = 0; names[i]; i++)
            if (strncmp(names[i], n->scalar, strlen(n->scalar)) == 0) {
                hits++;
                bi = i;
            }
        if (hits == 1) best = 0;
    }
    if (bi >= 0 && best <= limit)
        return drape_yread_error(r, n, path, DRAPE_E_INPUT,
                                 "expected %s, got \"%s\" (did you mean "
                                 "`%s`?)",
                                 expected, n->scalar, names[bi]);
    return drape_yread_error(r, n, path, DRAPE_E_INPUT, "expected %s, got \"%s\"",
                             expected, n->scalar);
}

int drape_yread_bool(const drape_yread *r, const drape_ynode *n, const char *path, int *out)
{
    const char *const t[] = {"true", "True", "TRUE", NULL};
    const char *const f[] = {"false", "False", "FALSE", NULL};
    if (drape_yread_want_scalar(r, n, path, "true or false")) return -1;
    if (!n->quoted && drape_yread_is_in(n->scalar, t)) {
        *out = 1;
        return 0;
    }
    if (!n->quoted && drape_yread_is_in(n->scalar, f)) {
        *out = 0;
        return 0;
    }
    return drape_yread_error(r, n, path, DRAPE_E_INPUT,
                             "expected true or false, got %s\"%s\"",
                             n->quoted ? "the quoted string " : "", n->scalar);
}

/* An integer written in decimal ("-1", "30"), within [lo, hi]. */
int drape_yread_long(const drape_yread *r, const drape_ynode *n, const char *path,
                     const char *expected, long lo, long hi, long *out)
{
    if (drape_yread_want_scalar(r, n, path, expected)) return -1;
    const char *s = n->scalar;
    size_t i = (s[0] == '-' || s[0] == '+') ? 1 : 0;
    int ok = s[i] != 0;
    for (; s[i]; i++)
        if (s[i] < '0' || s[i] > '9') ok = 0;
    long v = 0;
    if (ok) {
        char *end;
        errno = 0;
        v = strtol(s, &end, 10);
        if (errno == ERANGE || *end) ok = 0;
    }
    if (!ok || v < lo || v > hi)
        return drape_yread_error(r, n, path, DRAPE_E_INPUT, "expected %s, got \"%s\"",
                                 expected, s);
    *out = v;
    return 0;
}

/* ------------------------------------------------------------------ */
/* Keys that exist, but not here                                        */

/* For each key of map that is not in allowed[] but is listed in owners[],
 * report where it belongs.  `here` describes the mapping ("a cusick scene").
 * Other keys are left to drape_ynode_check_keys. */
int drape_yread_misplaced(const drape_yread *r, const drape_ynode *map, const char *parent,
                          const char *const *allowed, const drape_yread_owner *owners,
                          const char *here)
{
    for (size_t i = 0; i < map->n; i++) {
        if (drape_yread_is_in(map->keys[i], allowed)) continue;
        for (const drape_yread_owner *o = owners; o->key; o++) {
            if (strcmp(o->key, map->keys[i]) != 0) continue;
            char path[DRAPE_YREAD_PATH_MAX];
            drape_yread_path(path, sizeof path, parent, map->keys[i]);
            return drape_yread_key_error(r, map, i, path, DRAPE_E_INPUT,
                                         "`%s` is only allowed in %s, not in %s", map->keys[i],
                                         o->owner, here);
        }
    }
    return drape_ynode_check_keys(r->doc, map, parent, allowed, r->err);
}

/* ------------------------------------------------------------------ */
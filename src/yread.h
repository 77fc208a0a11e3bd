/* yread.h: typed values from a parsed YAML document (yamldoc.h), each
 * error naming the file, line, column and key path of the value at fault:
 * quantities with units and a sign (units.h), plain numbers, units, text,
 * names from a list (with a "did you mean"), booleans, integers, required
 * keys, and keys that belong elsewhere; warnings with the same position.
 * Used by the scene and fabric loaders (scene.c, fabric.c); not part of
 * the library's interface.  Every function returns 0 (or a node) on
 * success and -1 (or NULL) after filling r->err. */
#ifndef DRAPE_YREAD_H
#define DRAPE_YREAD_H

#include <stddef.h>

#include "drape/error.h"
#include "drape/units.h"
#include "drape/yamldoc.h"

#define DRAPE_YREAD_PATH_MAX DRAPE_ERROR_KEY_MAX

/* A reading of one document. */
typedef struct drape_yread {
    const drape_ydoc *doc;
    drape_error *err;
    unsigned flags; /* the caller's (the scene loader: DRAPE_SCENE_LOAD_*) */
    drape_warn_fn warn; /* NULL: warnings are dropped */
    void *warn_ctx;
} drape_yread;

/* Sign requirement of a quantity. */
enum { DRAPE_YREAD_ANY, DRAPE_YREAD_POSITIVE, DRAPE_YREAD_NONNEGATIVE };

/* A key allowed only in some other kind of mapping, and where. */
typedef struct drape_yread_owner {
    const char *key;
    const char *owner; /* "cantilever scenes", "circle specimens" */
} drape_yread_owner;

/* "a mapping", "a sequence", "a scalar" or "nothing" (n NULL). */
const char *drape_yread_kind(const drape_ynode *n);

/* parent.key (key alone when parent is empty) into out. */
void drape_yread_path(char *out, size_t n, const char *parent, const char *key);

/* parent[idx] into out ("bending.warp[1]"). */
void drape_yread_item_path(char *out, size_t n, const char *parent, size_t idx);

/* Error at the position of n. */
int drape_yread_error(const drape_yread *r, const drape_ynode *n, const char *path,
                      drape_error_kind kind, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

/* Error at the position of the idx-th key of map. */
int drape_yread_key_error(const drape_yread *r, const drape_ynode *map, size_t idx,
                          const char *path, drape_error_kind kind, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 6, 7)))
#endif
    ;

/* Warning (kind DRAPE_OK) at the position of n, passed to r->warn; nothing
 * when r->warn is NULL. */
void drape_yread_warn(const drape_yread *r, const drape_ynode *n, const char *path,
                      const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* 1 if s is one of the NULL-terminated list. */
int drape_yread_is_in(const char *s, const char *const *list);

/* "a, b, c" into buf; returns buf. */
const char *drape_yread_name_list(const char *const *names, char *buf, size_t n);

/* A node of the given type; expected describes it in the message
 * ("expected a list of pieces, got a mapping"; a scalar is quoted, an
 * empty one named "an empty value"). */
int drape_yread_want(const drape_yread *r, const drape_ynode *n, const char *path,
                     drape_ynode_type type, const char *expected);
int drape_yread_want_map(const drape_yread *r, const drape_ynode *n, const char *path);
int drape_yread_want_scalar(const drape_yread *r, const drape_ynode *n, const char *path,
                            const char *expected);

/* Required key: its value, or an error at the mapping that lacks it. */
const drape_ynode *drape_yread_need(const drape_yread *r, const drape_ynode *map,
                                    const char *parent, const char *key, const char *example);

/* A quantity of dimension dim and sign DRAPE_YREAD_*; noun names it in
 * messages ("length", "time", ...). */
int drape_yread_quantity(const drape_yread *r, const drape_ynode *n, const char *path,
                         drape_dim dim, const char *noun, int sign, double *out);

/* Optional quantity under key: *out left alone when absent; *node (if
 * node) the value or NULL. */
int drape_yread_opt_quantity(const drape_yread *r, const drape_ynode *map, const char *parent,
                             const char *key, drape_dim dim, const char *noun, int sign,
                             double *out, const drape_ynode **node);

/* Required quantity under key (example: a value for the message). */
int drape_yread_req_quantity(const drape_yread *r, const drape_ynode *map, const char *parent,
                             const char *key, drape_dim dim, const char *noun, int sign,
                             const char *example, double *out, const drape_ynode **node);

/* A plain number without a unit ("0.5", "-1.2e-3"; no hex, inf, nan or
 * fraction), finite, of sign DRAPE_YREAD_*. */
int drape_yread_number(const drape_yread *r, const drape_ynode *n, const char *path, int sign,
                       double *out);

/* A unit alone ("gf.cm/cm") of dimension dim: *scale its SI factor.  noun
 * names the dimension in messages ("curvature (1/m, 1/cm)"). */
int drape_yread_unit(const drape_yread *r, const drape_ynode *n, const char *path,
                     drape_dim dim, const char *noun, double *scale);

/* Text copied into buf (capacity cap, NUL included); nonempty: "" is an
 * error. */
int drape_yread_text(const drape_yread *r, const drape_ynode *n, const char *path, int nonempty,
                     char *buf, size_t cap);

/* One of names[]; *idx its index.  Suggests the nearest name. */
int drape_yread_enum(const drape_yread *r, const drape_ynode *n, const char *path,
                     const char *const *names, int *idx);

/* true or false (unquoted). */
int drape_yread_bool(const drape_yread *r, const drape_ynode *n, const char *path, int *out);

/* An integer written in decimal ("-1", "30"), within [lo, hi]. */
int drape_yread_long(const drape_yread *r, const drape_ynode *n, const char *path,
                     const char *expected, long lo, long hi, long *out);

/* For each key of map that is not in allowed[] but is listed in owners[],
 * report where it belongs.  `here` describes the mapping ("a cusick
 * scene").  Other keys are left to drape_ynode_check_keys. */
int drape_yread_misplaced(const drape_yread *r, const drape_ynode *map, const char *parent,
                          const char *const *allowed, const drape_yread_owner *owners,
                          const char *here);

#endif /* DRAPE_YREAD_H */

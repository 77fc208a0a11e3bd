/* yamldoc.h: a YAML document as a small tree, built with libyaml's event
 * parser, with the source position of every node kept for error messages.
 *
 * drape's input files are plain YAML 1.1 mappings, sequences and scalars.
 * The loader rejects what drape's files never need and what makes errors
 * unclear: anchors and aliases, tags, more than one document, nesting deeper
 * than DRAPE_YDOC_MAX_DEPTH, duplicate keys in a mapping, more than
 * DRAPE_YDOC_MAX_KEYS keys in one mapping, non-scalar keys,
 * files that are empty or contain NUL bytes or invalid UTF-8.
 */
#ifndef DRAPE_YAMLDOC_H
#define DRAPE_YAMLDOC_H

#include <stddef.h>

#include "drape/error.h"

#define DRAPE_YDOC_MAX_DEPTH 32
/* keys of one mapping: the duplicate search is linear per key, and no
 * drape mapping has more than a few dozen */
#define DRAPE_YDOC_MAX_KEYS 1024
#define DRAPE_YDOC_MAX_BYTES (16L * 1024 * 1024) /* refuse larger files */

typedef enum drape_ynode_type {
    DRAPE_YNODE_SCALAR,
    DRAPE_YNODE_SEQUENCE,
    DRAPE_YNODE_MAPPING
} drape_ynode_type;

typedef struct drape_ynode drape_ynode;
struct drape_ynode {
    drape_ynode_type type;
    int line, column;     /* 1-based position of the node's start */
    char *scalar;         /* SCALAR: its text (NUL-terminated) */
    int quoted;           /* SCALAR: 1 if written in quotes */
    size_t n;             /* SEQUENCE/MAPPING: number of items/pairs */
    drape_ynode **items;  /* SEQUENCE: items; MAPPING: values */
    char **keys;          /* MAPPING: keys, parallel to items */
    int *key_line, *key_column; /* MAPPING: position of each key */
};

typedef struct drape_ydoc {
    char *path;           /* file name as given, for messages */
    char *dir;            /* directory part of path ("." if none) */
    drape_ynode *root;    /* never NULL after a successful load */
} drape_ydoc;

/* Load `path`.  On success returns a new document (caller frees with
 * drape_ydoc_free); on failure returns NULL and fills err (kind E_IO for a
 * file that cannot be read, E_SYNTAX for malformed YAML, with libyaml's
 * problem mark converted to 1-based line and column). */
drape_ydoc *drape_ydoc_load(const char *path, drape_error *err);

/* Parse a document held in memory; `name` is used in messages. */
drape_ydoc *drape_ydoc_load_string(const char *name, const char *text,
                                   size_t len, drape_error *err);

void drape_ydoc_free(drape_ydoc *doc); /* NULL is a no-op */

/* Value of `key` in mapping `map`, or NULL if absent (or map is not a
 * mapping).  The index of the pair is stored in *idx if idx is not NULL. */
const drape_ynode *drape_ynode_get(const drape_ynode *map, const char *key,
                                   size_t *idx);

/* Check that every key of `map` is one of `allowed` (NULL-terminated list).
 * On an unknown key sets err (E_INPUT) with the key's position, key path
 * `path.key`, and the nearest allowed key as a suggestion ("did you mean
 * `spacing`?"), and returns -1.  `path` is the key path of the mapping ("" for
 * the root). */
int drape_ynode_check_keys(const drape_ydoc *doc, const drape_ynode *map,
                           const char *path, const char *const *allowed,
                           drape_error *err);

/* Error at a node: sets err with doc->path and the node's position (node
 * may be NULL: then line and column are 0).  Returns -1. */
int drape_ynode_error(drape_error *err, const drape_ydoc *doc,
                      const drape_ynode *node, const char *keypath,
                      drape_error_kind kind, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 6, 7)))
#endif
    ;

/* Edit distance between two strings (for "did you mean"). */
size_t drape_levenshtein(const char *a, const char *b);

#endif /* DRAPE_YAMLDOC_H */

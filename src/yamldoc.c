/* yamldoc.c: load a YAML file into a small tree (see yamldoc.h).
 *
 * The tree is built from libyaml's event stream (yaml_parser_parse); drape
 * does no YAML parsing of its own.  Before libyaml sees the text, the bytes
 * are checked: drape's inputs are UTF-8 text, so a NUL byte, a C0 control
 * character other than tab/LF/CR, DEL, or a byte sequence that is not
 * well-formed UTF-8 (overlong forms, surrogates, code points above
 * U+10FFFF; Unicode 15, table 3-7) is reported as binary data at its byte
 * offset.  libyaml's marks are 0-based; every position stored or reported
 * here is 1-based.
 *
 * Rejected (E_SYNTAX unless noted): malformed YAML, empty file or document,
 * binary data, files above DRAPE_YDOC_MAX_BYTES, more than one document,
 * anchors and aliases, explicit tags, nesting deeper than
 * DRAPE_YDOC_MAX_DEPTH, non-scalar or empty keys, a root that is not a
 * mapping, NUL escapes ("\0") in scalars; duplicate keys (E_INPUT).
 *
 * A scalar's `quoted` flag is 1 for every non-plain style (single or double
 * quotes, literal or folded blocks).
 */
#include "drape/yamldoc.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include <yaml.h>

#include "drape/alloc.h"

/* ---------------------------------------------------------------- tree */

static void node_free(drape_ynode *n)
{
    if (!n) return;
    if (n->type == DRAPE_YNODE_SCALAR) {
        drape_free(n->scalar);
    } else {
        for (size_t i = 0; i < n->n; i++) {
            node_free(n->items[i]);
            if (n->keys) drape_free(n->keys[i]);
        }
        drape_free(n->items);
        drape_free(n->keys);
        drape_free(n->key_line);
        drape_free(n->key_column);
    }
    drape_free(n);
}

void drape_ydoc_free(drape_ydoc *doc)
{
    if (!doc) return;
    node_free(doc->root);
    drape_free(doc->path);
    drape_free(doc->dir);
    drape_free(doc);
}

/* Room for one more item: capacities run 4, 8, 16, ... so growth is needed
 * when n is 0 or a power of two >= 4. */
static int needs_growth(size_t n)
{
    return n == 0 || (n >= 4 && (n & (n - 1)) == 0);
}

static int grow(void **p, size_t n, size_t size)
{
    size_t cap = n == 0 ? 4 : 2 * n;
    void *q = drape_realloc(*p, cap * size);
    if (!q) return -1;
    *p = q;
    return 0;
}

/* Append an item (and for a mapping its key, which is then owned by the
 * map).  Returns -1 on allocation failure (nothing changed). */
static int node_append(drape_ynode *c, drape_ynode *item, char *key,
                       int kline, int kcol)
{
    if (needs_growth(c->n)) {
        if (grow((void **)&c->items, c->n, sizeof *c->items)) return -1;
        if (c->type == DRAPE_YNODE_MAPPING) {
            if (grow((void **)&c->keys, c->n, sizeof *c->keys) ||
                grow((void **)&c->key_line, c->n, sizeof *c->key_line) ||
                grow((void **)&c->key_column, c->n, sizeof *c->key_column))
                return -1;
        }
    }
    c->items[c->n] = item;
    if (c->type == DRAPE_YNODE_MAPPING) {
        c->keys[c->n] = key;
        c->key_line[c->n] = kline;
        c->key_column[c->n] = kcol;
    }
    c->n++;
    return 0;
}

/* -------------------------------------------------------------- loading */

typedef struct frame {
    drape_ynode *node;
    char *key;          /* mapping: key waiting for its value (owned) */
    int key_line, key_col;
} frame;

typedef struct builder {
    const char *name;
    drape_error *err;
    drape_ynode *root;
    frame st[DRAPE_YDOC_MAX_DEPTH + 1];
    int sp;             /* number of open collections */
    int ndocs;
} builder;

static int b_error(builder *b, drape_error_kind kind, int line, int col,
                   const char *key, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 6, 7)))
#endif
    ;

static int b_error(builder *b, drape_error_kind kind, int line, int col,
                   const char *key, const char *fmt, ...)
{
    char msg[DRAPE_ERROR_MSG_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return drape_error_set(b->err, kind, b->name, line, col, key, "%s", msg);
}

static int b_nomem(builder *b)
{
    return drape_error_set(b->err, DRAPE_E_NOMEM, b->name, 0, 0, NULL,
                           "out of memory while reading the file");
}

/* Key path of the position being parsed ("bending.warp[1]"), plus `last`
 * (a key of the innermost mapping) if not NULL. */
static void b_path(const builder *b, const char *last, char *out, size_t n)
{
    size_t k = 0;
    out[0] = 0;
#define PUT(...)                                                            \
    do {                                                                    \
        int r_ = snprintf(out + k, n - k, __VA_ARGS__);                     \
        if (r_ > 0) k += (size_t)r_ < n - k ? (size_t)r_ : n - k - 1;       \
    } while (0)
    for (int i = 0; i < b->sp; i++) {
        const drape_ynode *c = b->st[i].node;
        int top = i == b->sp - 1;
        if (c->type == DRAPE_YNODE_MAPPING) {
            const char *key = NULL;
            if (top) key = last ? last : b->st[i].key;
            else if (c->n > 0) key = c->keys[c->n - 1];
            if (key) PUT("%s%s", k ? "." : "", key);
        } else if (c->type == DRAPE_YNODE_SEQUENCE) {
            size_t idx = top ? c->n : c->n - 1;
            PUT("[%zu]", idx);
        }
    }
#undef PUT
}

/* Attach a new node to the innermost open collection (or make it the
 * root).  On failure the node is freed. */
static int b_attach(builder *b, drape_ynode *node)
{
    if (b->sp == 0) {
        b->root = node;
        return 0;
    }
    frame *f = &b->st[b->sp - 1];
    if (f->node->type == DRAPE_YNODE_SEQUENCE) {
        if (node_append(f->node, node, NULL, 0, 0)) {
            node_free(node);
            return b_nomem(b);
        }
        return 0;
    }
    if (!f->key) {
        char path[DRAPE_ERROR_KEY_MAX];
        b_path(b, NULL, path, sizeof path);
        int line = node->line, col = node->column;
        node_free(node);
        return b_error(b, DRAPE_E_SYNTAX, line, col, path,
                       "a mapping key must be a plain scalar, not a %s",
                       "sequence or mapping");
    }
    if (node_append(f->node, node, f->key, f->key_line, f->key_col)) {
        node_free(node);
        return b_nomem(b);
    }
    f->key = NULL;
    return 0;
}

static drape_ynode *node_new(drape_ynode_type type, const yaml_mark_t *m)
{
    drape_ynode *n = drape_calloc(1, sizeof *n);
    if (!n) return NULL;
    n->type = type;
    n->line = (int)m->line + 1;
    n->column = (int)m->column + 1;
    return n;
}

/* Anchors and explicit tags are refused on every node. */
static int b_check_props(builder *b, const yaml_event_t *ev,
                         const yaml_char_t *anchor, const yaml_char_t *tag)
{
    int line = (int)ev->start_mark.line + 1;
    int col = (int)ev->start_mark.column + 1;
    char path[DRAPE_ERROR_KEY_MAX];
    if (anchor) {
        b_path(b, NULL, path, sizeof path);
        return b_error(b, DRAPE_E_SYNTAX, line, col, path,
                       "YAML anchors and aliases are not accepted (anchor "
                       "`&%s`); write the value out", (const char *)anchor);
    }
    if (tag) {
        b_path(b, NULL, path, sizeof path);
        return b_error(b, DRAPE_E_SYNTAX, line, col, path,
                       "explicit YAML tags are not accepted (tag `%s`)",
                       (const char *)tag);
    }
    return 0;
}

static int b_collection_start(builder *b, const yaml_event_t *ev,
                              drape_ynode_type type)
{
    const yaml_char_t *anchor, *tag;
    if (type == DRAPE_YNODE_MAPPING) {
        anchor = ev->data.mapping_start.anchor;
        tag = ev->data.mapping_start.tag;
    } else {
        anchor = ev->data.sequence_start.anchor;
        tag = ev->data.sequence_start.tag;
    }
    if (b_check_props(b, ev, anchor, tag)) return -1;
    if (b->sp >= DRAPE_YDOC_MAX_DEPTH) {
        char path[DRAPE_ERROR_KEY_MAX];
        b_path(b, NULL, path, sizeof path);
        return b_error(b, DRAPE_E_SYNTAX, (int)ev->start_mark.line + 1,
                       (int)ev->start_mark.column + 1, path,
                       "nesting deeper than %d levels", DRAPE_YDOC_MAX_DEPTH);
    }
    drape_ynode *n = node_new(type, &ev->start_mark);
    if (!n) return b_nomem(b);
    if (b_attach(b, n)) return -1;
    frame *f = &b->st[b->sp++];
    f->node = n;
    f->key = NULL;
    return 0;
}

static int b_scalar(builder *b, const yaml_event_t *ev)
{
    const char *v = (const char *)ev->data.scalar.value;
    size_t len = ev->data.scalar.length;
    int line = (int)ev->start_mark.line + 1;
    int col = (int)ev->start_mark.column + 1;
    int plain = ev->data.scalar.style == YAML_PLAIN_SCALAR_STYLE;
    char path[DRAPE_ERROR_KEY_MAX];
    if (b_check_props(b, ev, ev->data.scalar.anchor, ev->data.scalar.tag))
        return -1;
    if (memchr(v, 0, len)) {
        b_path(b, NULL, path, sizeof path);
        return b_error(b, DRAPE_E_SYNTAX, line, col, path,
                       "NUL character in a string");
    }
    frame *f = b->sp ? &b->st[b->sp - 1] : NULL;
    if (f && f->node->type == DRAPE_YNODE_MAPPING && !f->key) {
        /* a key */
        const drape_ynode *m = f->node;
        if (len == 0 && plain) {
            b_path(b, NULL, path, sizeof path);
            return b_error(b, DRAPE_E_SYNTAX, line, col, path,
                           "empty mapping key");
        }
        /* the duplicate search below is linear per key: bound the keys of
         * one mapping so a large file cannot make the load quadratic (no
         * drape mapping has more than a few dozen keys) */
        if (m->n >= DRAPE_YDOC_MAX_KEYS) {
            b_path(b, NULL, path, sizeof path);
            return b_error(b, DRAPE_E_SYNTAX, line, col, path,
                           "more than %d keys in one mapping", DRAPE_YDOC_MAX_KEYS);
        }
        for (size_t i = 0; i < m->n; i++) {
            if (strcmp(m->keys[i], v) == 0) {
                b_path(b, v, path, sizeof path);
                return b_error(b, DRAPE_E_INPUT, line, col, path,
                               "duplicate key `%s` (first given at line %d, "
                               "column %d)", v, m->key_line[i],
                               m->key_column[i]);
            }
        }
        f->key = drape_strdup(v);
        if (!f->key) return b_nomem(b);
        f->key_line = line;
        f->key_col = col;
        return 0;
    }
    drape_ynode *n = node_new(DRAPE_YNODE_SCALAR, &ev->start_mark);
    if (!n) return b_nomem(b);
    n->scalar = drape_strdup(v);
    if (!n->scalar) {
        drape_free(n);
        return b_nomem(b);
    }
    n->quoted = !plain;
    return b_attach(b, n);
}

/* Bytes of the line break at s (n bytes available), 0 if none.  The breaks
 * are libyaml's (its IS_BREAK and SKIP_LINE): CR LF, CR, LF, NEL (U+0085),
 * LS (U+2028) and PS (U+2029), each one break, so that lines drape counts
 * itself agree with the lines libyaml reports (an old-Mac file of CR-only
 * lines is not all "line 1"). */
static size_t line_break_len(const unsigned char *s, size_t n)
{
    if (s[0] == '\r') return n >= 2 && s[1] == '\n' ? 2 : 1;
    if (s[0] == '\n') return 1;
    if (n >= 2 && s[0] == 0xC2 && s[1] == 0x85) return 2;
    if (n >= 3 && s[0] == 0xE2 && s[1] == 0x80 && (s[2] == 0xA8 || s[2] == 0xA9))
        return 3;
    return 0;
}

/* 1-based line and column of byte offset `off` (column in bytes). */
static void offset_position(const char *text, size_t off, int *line, int *col)
{
    const unsigned char *s = (const unsigned char *)text;
    int l = 1, c = 1;
    size_t i = 0;
    while (i < off) {
        size_t k = line_break_len(s + i, off - i);
        if (k) { l++; c = 1; i += k; }
        else { c++; i++; }
    }
    *line = l;
    *col = c;
}

static int b_libyaml_error(builder *b, const yaml_parser_t *p,
                           const char *text)
{
    const char *problem = p->problem ? p->problem : "malformed YAML";
    if (p->error == YAML_MEMORY_ERROR) return b_nomem(b);
    if (p->error == YAML_READER_ERROR) {
        int line, col;
        offset_position(text, p->problem_offset, &line, &col);
        return b_error(b, DRAPE_E_SYNTAX, line, col, NULL,
                       "%s at byte %zu", problem, p->problem_offset + 1);
    }
    if (p->context)
        return b_error(b, DRAPE_E_SYNTAX, (int)p->problem_mark.line + 1,
                       (int)p->problem_mark.column + 1, NULL,
                       "%s (%s at line %d, column %d)", problem, p->context,
                       (int)p->context_mark.line + 1,
                       (int)p->context_mark.column + 1);
    return b_error(b, DRAPE_E_SYNTAX, (int)p->problem_mark.line + 1,
                   (int)p->problem_mark.column + 1, NULL, "%s", problem);
}

/* Length of the well-formed UTF-8 sequence at s (n bytes available), or 0.
 * Unicode 15, table 3-7. */
static size_t utf8_len(const unsigned char *s, size_t n)
{
    unsigned char c = s[0];
    size_t k;
    unsigned char lo = 0x80, hi = 0xBF;
    if (c < 0x80) return 1;
    if (c >= 0xC2 && c <= 0xDF) k = 2;
    else if (c == 0xE0) { k = 3; lo = 0xA0; }
    else if (c >= 0xE1 && c <= 0xEC) k = 3;
    else if (c == 0xED) { k = 3; hi = 0x9F; }
    else if (c >= 0xEE && c <= 0xEF) k = 3;
    else if (c == 0xF0) { k = 4; lo = 0x90; }
    else if (c >= 0xF1 && c <= 0xF3) k = 4;
    else if (c == 0xF4) { k = 4; hi = 0x8F; }
    else return 0;
    if (n < k) return 0;
    if (s[1] < lo || s[1] > hi) return 0;
    for (size_t i = 2; i < k; i++)
        if (s[i] < 0x80 || s[i] > 0xBF) return 0;
    return k;
}

static int check_bytes(builder *b, const char *text, size_t len)
{
    const unsigned char *s = (const unsigned char *)text;
    size_t i = 0;
    while (i < len) {
        const char *what = NULL;
        char buf[48];
        size_t k = 1;
        if (s[i] == 0) {
            what = "NUL byte";
        } else if ((s[i] < 0x20 && s[i] != '\t' && s[i] != '\n' &&
                    s[i] != '\r') || s[i] == 0x7F) {
            snprintf(buf, sizeof buf, "control character 0x%02X", s[i]);
            what = buf;
        } else if ((k = utf8_len(s + i, len - i)) == 0) {
            snprintf(buf, sizeof buf, "byte 0x%02X is not valid UTF-8", s[i]);
            what = buf;
        }
        if (what) {
            int line, col;
            offset_position(text, i, &line, &col);
            return b_error(b, DRAPE_E_SYNTAX, line, col, NULL,
                           "binary data at byte %zu (%s); drape reads UTF-8 "
                           "text", i + 1, what);
        }
        i += k;
    }
    return 0;
}

static char *dir_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    if (!slash) return drape_strdup(".");
    size_t n = slash == path ? 1 : (size_t)(slash - path);
    char *d = drape_malloc(n + 1);
    if (!d) return NULL;
    memcpy(d, path, n);
    d[n] = 0;
    return d;
}

drape_ydoc *drape_ydoc_load_string(const char *name, const char *text,
                                   size_t len, drape_error *err)
{
    builder b;
    yaml_parser_t parser;
    int parser_ok = 0, done = 0, rc = -1;
    drape_ydoc *doc = NULL;

    memset(&b, 0, sizeof b);
    b.name = name ? name : "<string>";
    b.err = err;

    if (len > (size_t)DRAPE_YDOC_MAX_BYTES) {
        b_error(&b, DRAPE_E_SYNTAX, 0, 0, NULL,
                "file too large (%zu bytes; the limit is %ld)", len,
                (long)DRAPE_YDOC_MAX_BYTES);
        goto out;
    }
    if (check_bytes(&b, text, len)) goto out;
    if (!yaml_parser_initialize(&parser)) {
        b_nomem(&b);
        goto out;
    }
    parser_ok = 1;
    yaml_parser_set_input_string(&parser, (const unsigned char *)text, len);
    while (!done) {
        yaml_event_t ev;
        if (!yaml_parser_parse(&parser, &ev)) {
            b_libyaml_error(&b, &parser, text);
            goto out;
        }
        int r = 0;
        switch (ev.type) {
        case YAML_STREAM_END_EVENT:
            done = 1;
            break;
        case YAML_DOCUMENT_START_EVENT:
            if (++b.ndocs > 1)
                r = b_error(&b, DRAPE_E_SYNTAX,
                            (int)ev.start_mark.line + 1,
                            (int)ev.start_mark.column + 1, NULL,
                            "more than one YAML document in the file; drape "
                            "reads exactly one");
            break;
        case YAML_ALIAS_EVENT: {
            char path[DRAPE_ERROR_KEY_MAX];
            b_path(&b, NULL, path, sizeof path);
            r = b_error(&b, DRAPE_E_SYNTAX, (int)ev.start_mark.line + 1,
                        (int)ev.start_mark.column + 1, path,
                        "YAML anchors and aliases are not accepted (alias "
                        "`*%s`); write the value out",
                        (const char *)ev.data.alias.anchor);
            break;
        }
        case YAML_SCALAR_EVENT:
            r = b_scalar(&b, &ev);
            break;
        case YAML_SEQUENCE_START_EVENT:
            r = b_collection_start(&b, &ev, DRAPE_YNODE_SEQUENCE);
            break;
        case YAML_MAPPING_START_EVENT:
            r = b_collection_start(&b, &ev, DRAPE_YNODE_MAPPING);
            break;
        case YAML_SEQUENCE_END_EVENT:
        case YAML_MAPPING_END_EVENT:
            if (b.sp > 0) b.sp--;
            break;
        default:
            break;
        }
        yaml_event_delete(&ev);
        if (r) goto out;
    }

    if (b.ndocs == 0 || !b.root) {
        b_error(&b, DRAPE_E_SYNTAX, len ? 1 : 0, len ? 1 : 0, NULL,
                "empty file: no YAML document");
        goto out;
    }
    if (b.root->type != DRAPE_YNODE_MAPPING) {
        if (b.root->type == DRAPE_YNODE_SCALAR && !b.root->quoted &&
            b.root->scalar[0] == 0)
            b_error(&b, DRAPE_E_SYNTAX, b.root->line, b.root->column, NULL,
                    "empty document");
        else
            b_error(&b, DRAPE_E_SYNTAX, b.root->line, b.root->column, NULL,
                    "the top level must be a mapping (`key: value` lines), "
                    "not a %s", b.root->type == DRAPE_YNODE_SEQUENCE
                                    ? "sequence" : "scalar");
        goto out;
    }
    doc = drape_calloc(1, sizeof *doc);
    if (!doc) { b_nomem(&b); goto out; }
    doc->path = drape_strdup(b.name);
    doc->dir = dir_of(b.name);
    if (!doc->path || !doc->dir) { b_nomem(&b); goto out; }
    doc->root = b.root;
    b.root = NULL;
    rc = 0;
out:
    if (parser_ok) yaml_parser_delete(&parser);
    for (int i = 0; i < DRAPE_YDOC_MAX_DEPTH + 1; i++) drape_free(b.st[i].key);
    node_free(b.root);
    if (rc) {
        drape_ydoc_free(doc);
        return NULL;
    }
    return doc;
}

drape_ydoc *drape_ydoc_load(const char *path, drape_error *err)
{
    FILE *fp = NULL;
    char *buf = NULL;
    size_t len = 0, cap = 0;
    drape_ydoc *doc = NULL;
    const size_t limit = (size_t)DRAPE_YDOC_MAX_BYTES;

    if (!path || !path[0]) {
        drape_error_set(err, DRAPE_E_IO, NULL, 0, 0, NULL,
                        "no file name given");
        goto out;
    }
    fp = fopen(path, "rb");
    if (!fp) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "cannot open: %s",
                        strerror(errno));
        goto out;
    }
    for (;;) {
        if (len == cap) {
            if (cap > limit) {
                drape_error_set(err, DRAPE_E_SYNTAX, path, 0, 0, NULL,
                                "file too large (more than %ld bytes)",
                                (long)DRAPE_YDOC_MAX_BYTES);
                goto out;
            }
            size_t ncap = cap ? 2 * cap : 65536;
            if (ncap > limit + 1) ncap = limit + 1;
            char *nb = drape_realloc(buf, ncap + 1);
            if (!nb) {
                drape_error_set(err, DRAPE_E_NOMEM, path, 0, 0, NULL,
                                "out of memory while reading the file");
                goto out;
            }
            buf = nb;
            cap = ncap;
        }
        size_t got = fread(buf + len, 1, cap - len, fp);
        len += got;
        if (got == 0) break;
    }
    if (ferror(fp)) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "cannot read: %s",
                        strerror(errno));
        goto out;
    }
    if (len > limit) {
        drape_error_set(err, DRAPE_E_SYNTAX, path, 0, 0, NULL,
                        "file too large (more than %ld bytes)",
                        (long)DRAPE_YDOC_MAX_BYTES);
        goto out;
    }
    if (len == 0) {
        drape_error_set(err, DRAPE_E_SYNTAX, path, 0, 0, NULL,
                        "empty file: no YAML document");
        goto out;
    }
    buf[len] = 0;
    doc = drape_ydoc_load_string(path, buf, len, err);
out:
    if (fp) fclose(fp);
    drape_free(buf);
    return doc;
}

/* -------------------------------------------------------------- queries */

const drape_ynode *drape_ynode_get(const drape_ynode *map, const char *key,
                                   size_t *idx)
{
    if (!map || map->type != DRAPE_YNODE_MAPPING || !key) return NULL;
    for (size_t i = 0; i < map->n; i++) {
        if (strcmp(map->keys[i], key) == 0) {
            if (idx) *idx = i;
            return map->items[i];
        }
    }
    return NULL;
}

size_t drape_levenshtein(const char *a, const char *b)
{
    size_t na = strlen(a), nb = strlen(b);
    size_t small[64], *row = small;
    if (nb + 1 > sizeof small / sizeof small[0]) {
        row = drape_malloc((nb + 1) * sizeof *row);
        if (!row) return na > nb ? na : nb; /* an upper bound */
    }
    for (size_t j = 0; j <= nb; j++) row[j] = j;
    for (size_t i = 1; i <= na; i++) {
        size_t diag = row[0];
        row[0] = i;
        for (size_t j = 1; j <= nb; j++) {
            size_t up = row[j];
            size_t best = diag + (a[i - 1] != b[j - 1]);
            if (up + 1 < best) best = up + 1;
            if (row[j - 1] + 1 < best) best = row[j - 1] + 1;
            row[j] = best;
            diag = up;
        }
    }
    size_t d = row[nb];
    if (row != small) drape_free(row);
    return d;
}

int drape_ynode_error(drape_error *err, const drape_ydoc *doc,
                      const drape_ynode *node, const char *keypath,
                      drape_error_kind kind, const char *fmt, ...)
{
    char msg[DRAPE_ERROR_MSG_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return drape_error_set(err, kind, doc ? doc->path : NULL,
                           node ? node->line : 0, node ? node->column : 0,
                           keypath, "%s", msg);
}

int drape_ynode_check_keys(const drape_ydoc *doc, const drape_ynode *map,
                           const char *path, const char *const *allowed,
                           drape_error *err)
{
    if (!map || map->type != DRAPE_YNODE_MAPPING) return 0;
    for (size_t i = 0; i < map->n; i++) {
        const char *key = map->keys[i];
        const char *best = NULL;
        size_t bestd = (size_t)-1;
        int found = 0;
        for (const char *const *a = allowed; *a; a++) {
            if (strcmp(*a, key) == 0) { found = 1; break; }
            size_t d = drape_levenshtein(key, *a);
            if (d < bestd) { bestd = d; best = *a; }
        }
        if (found) continue;
        char kp[DRAPE_ERROR_KEY_MAX];
        snprintf(kp, sizeof kp, "%s%s%s", path ? path : "",
                 path && path[0] ? "." : "", key);
        size_t len = strlen(key), lim = len / 3 > 2 ? len / 3 : 2;
        const char *file = doc ? doc->path : NULL;
        if (best && bestd <= lim)
            return drape_error_set(err, DRAPE_E_INPUT, file, map->key_line[i],
                                   map->key_column[i], kp,
                                   "unknown key `%s`; did you mean `%s`?", key,
                                   best);
        char list[DRAPE_ERROR_MSG_MAX / 2];
        size_t k = 0;
        list[0] = 0;
        for (const char *const *a = allowed; *a; a++) {
            int r = snprintf(list + k, sizeof list - k, "%s%s",
                             k ? ", " : "", *a);
            if (r < 0 || (size_t)r >= sizeof list - k) break;
            k += (size_t)r;
        }
        return drape_error_set(err, DRAPE_E_INPUT, file, map->key_line[i],
                               map->key_column[i], kp,
                               "unknown key `%s` (expected one of: %s)", key,
                               list);
    }
    return 0;
}

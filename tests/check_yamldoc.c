/* check_yamldoc.c: the YAML tree loader (yamldoc.h).  Each rejection class
 * is tried on a small file; the expected line and column are counted by
 * hand in the text of the test (1-based). */
#include "drape/yamldoc.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "drape/alloc.h"
#include "testutil.h"

/* Load `text` from a scratch file and expect failure with the given kind,
 * position, key path (NULL: not checked) and message fragment. */
static void expect_fail(const char *text, size_t len, drape_error_kind kind,
                        int line, int col, const char *key,
                        const char *msg_part)
{
    drape_error err;
    drape_error_clear(&err);
    const char *p = tu_write_bytes("bad.yaml", text, len);
    drape_ydoc *doc = drape_ydoc_load(p, &err);
    char buf[1024];
    drape_error_format(&err, buf, sizeof buf);
    ck_assert_msg(doc == NULL, "accepted: %s", text);
    ck_assert_msg(err.kind == kind, "kind %d, expected %d: %s", err.kind, kind,
                  buf);
    ck_assert_str_eq(err.file, p);
    ck_assert_msg(err.line == line && err.column == col,
                  "at %d:%d, expected %d:%d: %s", err.line, err.column, line,
                  col, buf);
    if (key) ck_assert_msg(strcmp(err.key, key) == 0, "key `%s`, expected `%s`",
                           err.key, key);
    ck_assert_msg(strstr(err.msg, msg_part) != NULL, "message \"%s\" lacks \"%s\"",
                  err.msg, msg_part);
}

#define FAIL_TEXT(text, kind, line, col, key, part)                           \
    expect_fail(text, strlen(text), kind, line, col, key, part)

START_TEST(test_good_tree)
{
    const char *text =
        "# comment\n"
        "name: cotton\n"
        "size: {w: 1 cm, h: '2 cm'}\n"
        "list:\n"
        "  - 1\n"
        "  - [a, \"b\"]\n"
        "empty:\n"
        "text: |\n"
        "  two\n"
        "  lines\n";
    drape_error err;
    drape_error_clear(&err);
    const char *p = tu_write_file("good.yaml", text);
    drape_ydoc *doc = drape_ydoc_load(p, &err);
    ck_assert_msg(doc != NULL, "%s", err.msg);
    ck_assert_str_eq(doc->path, p);
    ck_assert_str_eq(doc->dir, tu_scratch_dir());
    const drape_ynode *r = doc->root;
    ck_assert_int_eq(r->type, DRAPE_YNODE_MAPPING);
    ck_assert_uint_eq(r->n, 5);
    ck_assert_int_eq(r->line, 2);
    ck_assert_int_eq(r->column, 1);
    ck_assert_str_eq(r->keys[0], "name");
    ck_assert_int_eq(r->key_line[1], 3);
    ck_assert_int_eq(r->key_column[1], 1);

    size_t idx = 99;
    const drape_ynode *name = drape_ynode_get(r, "name", &idx);
    ck_assert_uint_eq(idx, 0);
    ck_assert_int_eq(name->type, DRAPE_YNODE_SCALAR);
    ck_assert_str_eq(name->scalar, "cotton");
    ck_assert_int_eq(name->quoted, 0);
    ck_assert_int_eq(name->line, 2);
    ck_assert_int_eq(name->column, 7); /* "name: " is 6 bytes */

    const drape_ynode *size = drape_ynode_get(r, "size", NULL);
    ck_assert_int_eq(size->type, DRAPE_YNODE_MAPPING);
    ck_assert_int_eq(size->column, 7);
    const drape_ynode *h = drape_ynode_get(size, "h", NULL);
    ck_assert_str_eq(h->scalar, "2 cm");
    ck_assert_int_eq(h->quoted, 1);
    ck_assert_int_eq(h->line, 3);
    ck_assert_int_eq(h->column, 20); /* "size: {w: 1 cm, h: " is 19 bytes */
    ck_assert_int_eq(size->key_column[1], 17);

    const drape_ynode *list = drape_ynode_get(r, "list", NULL);
    ck_assert_int_eq(list->type, DRAPE_YNODE_SEQUENCE);
    ck_assert_uint_eq(list->n, 2);
    ck_assert_str_eq(list->items[0]->scalar, "1");
    ck_assert_int_eq(list->items[0]->line, 5);
    ck_assert_int_eq(list->items[0]->column, 5);
    ck_assert_int_eq(list->items[1]->type, DRAPE_YNODE_SEQUENCE);
    ck_assert_str_eq(list->items[1]->items[1]->scalar, "b");
    ck_assert_int_eq(list->items[1]->items[1]->quoted, 1);

    const drape_ynode *empty = drape_ynode_get(r, "empty", NULL);
    ck_assert_int_eq(empty->type, DRAPE_YNODE_SCALAR);
    ck_assert_str_eq(empty->scalar, "");
    ck_assert_str_eq(drape_ynode_get(r, "text", NULL)->scalar, "two\nlines\n");

    ck_assert_ptr_null(drape_ynode_get(r, "nam", NULL));
    ck_assert_ptr_null(drape_ynode_get(name, "x", NULL));
    ck_assert_ptr_null(drape_ynode_get(NULL, "x", NULL));
    drape_ydoc_free(doc);
    drape_ydoc_free(NULL);
}
END_TEST

START_TEST(test_many_items)
{
    /* 100 keys and a 100-item list exercise the array growth */
    char text[4096];
    size_t k = 0;
    for (int i = 0; i < 100; i++)
        k += (size_t)snprintf(text + k, sizeof text - k, "k%d: %d\n", i, i * i);
    k += (size_t)snprintf(text + k, sizeof text - k, "seq: [");
    for (int i = 0; i < 100; i++)
        k += (size_t)snprintf(text + k, sizeof text - k, "%s%d", i ? "," : "", i);
    snprintf(text + k, sizeof text - k, "]\n");
    drape_error err;
    drape_error_clear(&err);
    drape_ydoc *doc = drape_ydoc_load_string("mem", text, strlen(text), &err);
    ck_assert_msg(doc != NULL, "%s", err.msg);
    ck_assert_str_eq(doc->dir, ".");
    ck_assert_uint_eq(doc->root->n, 101);
    ck_assert_str_eq(drape_ynode_get(doc->root, "k77", NULL)->scalar, "5929");
    ck_assert_int_eq(drape_ynode_get(doc->root, "k77", NULL)->line, 78);
    const drape_ynode *seq = drape_ynode_get(doc->root, "seq", NULL);
    ck_assert_uint_eq(seq->n, 100);
    ck_assert_str_eq(seq->items[99]->scalar, "99");
    drape_ydoc_free(doc);
}
END_TEST

START_TEST(test_malformed)
{
    /* second ':' on line 1 at byte 5 */
    FAIL_TEXT("a: b: c\n", DRAPE_E_SYNTAX, 1, 5, NULL,
              "mapping values are not allowed");
    /* unterminated flow sequence: libyaml notices at the start of line 2 */
    FAIL_TEXT("a: [1, 2\nb: 3\n", DRAPE_E_SYNTAX, 2, 2, NULL,
              "while parsing a flow sequence at line 1, column 4");
    /* " b: 2" continues the plain scalar "1 b"; its ":" at 2:3 is illegal */
    FAIL_TEXT("a: 1\n b: 2\n", DRAPE_E_SYNTAX, 2, 3, NULL, "mapping values");
    /* unterminated quote */
    FAIL_TEXT("a: \"abc\n", DRAPE_E_SYNTAX, 2, 1, NULL, "quoted scalar");
    /* a tab used for indentation */
    FAIL_TEXT("a:\n\tb: 1\n", DRAPE_E_SYNTAX, 2, 1, NULL,
              "cannot start any token");
}
END_TEST

START_TEST(test_empty)
{
    FAIL_TEXT("", DRAPE_E_SYNTAX, 0, 0, NULL, "empty file");
    FAIL_TEXT("\n\n   \n", DRAPE_E_SYNTAX, 1, 1, NULL, "empty file");
    FAIL_TEXT("# only a comment\n", DRAPE_E_SYNTAX, 1, 1, NULL, "empty file");
    FAIL_TEXT("---\n", DRAPE_E_SYNTAX, 2, 1, NULL, "empty document");
    FAIL_TEXT("- 1\n- 2\n", DRAPE_E_SYNTAX, 1, 1, NULL,
              "top level must be a mapping");
    FAIL_TEXT("hello\n", DRAPE_E_SYNTAX, 1, 1, NULL, "not a scalar");
}
END_TEST

START_TEST(test_binary)
{
    /* NUL as byte 8: "a: 1\n" is 5 bytes, "b:" 2 more -> line 2, column 3 */
    static const char nul[] = "a: 1\nb:\0 2\n";
    expect_fail(nul, sizeof nul - 1, DRAPE_E_SYNTAX, 2, 3, NULL,
                "binary data at byte 8 (NUL byte)");
    /* 0xFF is never UTF-8: byte 4 */
    FAIL_TEXT("a: \xff\n", DRAPE_E_SYNTAX, 1, 4, NULL,
              "binary data at byte 4 (byte 0xFF is not valid UTF-8)");
    /* overlong '/' (C0 AF), a surrogate (ED A0 80), a truncated sequence */
    FAIL_TEXT("a: x\xC0\xAF\n", DRAPE_E_SYNTAX, 1, 5, NULL, "byte 5 (byte 0xC0");
    FAIL_TEXT("ab: \xED\xA0\x80\n", DRAPE_E_SYNTAX, 1, 5, NULL, "byte 5");
    FAIL_TEXT("a: \xE2\x82\n", DRAPE_E_SYNTAX, 1, 4, NULL, "not valid UTF-8");
    /* code point above U+10FFFF */
    FAIL_TEXT("a: \xF4\x90\x80\x80\n", DRAPE_E_SYNTAX, 1, 4, NULL, "UTF-8");
    /* a control character (BEL) on line 3 */
    FAIL_TEXT("a: 1\nb: 2\nc: \x07\n", DRAPE_E_SYNTAX, 3, 4, NULL,
              "byte 14 (control character 0x07)");
    /* a PNG header */
    static const unsigned char png[] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A,
                                        0x0A, 0, 0, 0, 0x0D};
    expect_fail((const char *)png, sizeof png, DRAPE_E_SYNTAX, 1, 1, NULL,
                "binary data at byte 1");
    /* valid multi-byte UTF-8 is fine: é (2 bytes), € (3), 😀 (4) */
    drape_error err;
    drape_error_clear(&err);
    const char *ok = "a: \xC3\xA9\xE2\x82\xAC\xF0\x9F\x98\x80\n";
    drape_ydoc *doc = drape_ydoc_load_string("ok", ok, strlen(ok), &err);
    ck_assert_msg(doc != NULL, "%s", err.msg);
    ck_assert_str_eq(drape_ynode_get(doc->root, "a", NULL)->scalar,
                     "\xC3\xA9\xE2\x82\xAC\xF0\x9F\x98\x80");
    drape_ydoc_free(doc);
    /* a NUL escape in a double-quoted string */
    FAIL_TEXT("a: \"x\\0y\"\n", DRAPE_E_SYNTAX, 1, 4, "a", "NUL character");
}
END_TEST

/* drape's own line count (the binary-data check runs before libyaml) uses
 * libyaml's line breaks: CR LF, CR, LF, NEL, LS, PS each end one line.  In
 * each file the bad byte is on line 3 at column 4 ("c: " is 3 bytes), and
 * libyaml's own error (a duplicate key) is on line 3 too. */
START_TEST(test_line_breaks)
{
    static const char *const brk[] = {"\r", "\r\n", "\n", "\xC2\x85",
                                      "\xE2\x80\xA8", "\xE2\x80\xA9"};
    for (size_t i = 0; i < sizeof brk / sizeof brk[0]; i++) {
        const char *b = brk[i];
        char text[128];
        snprintf(text, sizeof text, "a: 1%sb: 2%sc: \x07%s", b, b, b);
        size_t byte = 2 * (4 + strlen(b)) + 4;
        char part[64];
        snprintf(part, sizeof part, "byte %zu (control character 0x07)", byte);
        expect_fail(text, strlen(text), DRAPE_E_SYNTAX, 3, 4, NULL, part);
        snprintf(text, sizeof text, "a: 1%sb: 2%sa: 3%s", b, b, b);
        expect_fail(text, strlen(text), DRAPE_E_INPUT, 3, 1, "a", "duplicate key");
    }
}
END_TEST

START_TEST(test_too_large)
{
    size_t n = (size_t)DRAPE_YDOC_MAX_BYTES + 1;
    char *big = malloc(n);
    ck_assert_ptr_nonnull(big);
    memset(big, ' ', n);
    memcpy(big, "a: 1\n#", 6);
    expect_fail(big, n, DRAPE_E_SYNTAX, 0, 0, NULL, "too large");
    /* exactly at the limit is read */
    drape_error err;
    drape_error_clear(&err);
    const char *p = tu_write_bytes("limit.yaml", big, n - 1);
    drape_ydoc *doc = drape_ydoc_load(p, &err);
    ck_assert_msg(doc != NULL, "%s", err.msg);
    drape_ydoc_free(doc);
    free(big);
}
END_TEST

START_TEST(test_documents)
{
    FAIL_TEXT("a: 1\n---\nb: 2\n", DRAPE_E_SYNTAX, 2, 1, NULL,
              "more than one YAML document");
    FAIL_TEXT("---\na: 1\n...\n---\nb: 2\n", DRAPE_E_SYNTAX, 4, 1, NULL,
              "more than one");
    /* one explicit document is fine */
    drape_error err;
    drape_error_clear(&err);
    const char *t = "---\na: 1\n...\n";
    drape_ydoc *doc = drape_ydoc_load_string("one", t, strlen(t), &err);
    ck_assert_msg(doc != NULL, "%s", err.msg);
    ck_assert_int_eq(doc->root->line, 2);
    drape_ydoc_free(doc);
}
END_TEST

START_TEST(test_anchors_tags)
{
    FAIL_TEXT("a: &x 1\nb: *x\n", DRAPE_E_SYNTAX, 1, 4, "a",
              "YAML anchors and aliases are not accepted");
    FAIL_TEXT("b: *x\n", DRAPE_E_SYNTAX, 1, 4, "b",
              "YAML anchors and aliases are not accepted (alias `*x`)");
    FAIL_TEXT("base: &b {x: 1}\nother:\n  <<: *b\n", DRAPE_E_SYNTAX, 1, 7,
              "base", "anchor `&b`");
    FAIL_TEXT("a: !!str 1\n", DRAPE_E_SYNTAX, 1, 4, "a", "explicit YAML tags");
    FAIL_TEXT("a:\n  - !foo {b: 1}\n", DRAPE_E_SYNTAX, 2, 5, "a[0]",
              "tag `!foo`");
    FAIL_TEXT("!!map {a: 1}\n", DRAPE_E_SYNTAX, 1, 1, "", "explicit YAML tags");
}
END_TEST

static char *nested(int levels)
{
    /* "a: " then `levels` '[' (each one level below the root mapping) */
    char *t = malloc((size_t)(2 * levels + 8));
    size_t k = 0;
    memcpy(t, "a: ", 3);
    k = 3;
    for (int i = 0; i < levels; i++) t[k++] = '[';
    for (int i = 0; i < levels; i++) t[k++] = ']';
    t[k++] = '\n';
    t[k] = 0;
    return t;
}

START_TEST(test_depth)
{
    /* root mapping = level 1, so 31 brackets reach level 32: accepted */
    char *ok = nested(DRAPE_YDOC_MAX_DEPTH - 1);
    drape_error err;
    drape_error_clear(&err);
    drape_ydoc *doc = drape_ydoc_load_string("deep", ok, strlen(ok), &err);
    ck_assert_msg(doc != NULL, "%s", err.msg);
    drape_ydoc_free(doc);
    free(ok);
    /* the 32nd '[' is level 33, at column 3 + 32 */
    char *bad = nested(DRAPE_YDOC_MAX_DEPTH);
    FAIL_TEXT(bad, DRAPE_E_SYNTAX, 1, 3 + DRAPE_YDOC_MAX_DEPTH, NULL,
              "nesting deeper than 32 levels");
    free(bad);
}
END_TEST

START_TEST(test_duplicate_keys)
{
    FAIL_TEXT("a: 1\nb: 2\na: 3\n", DRAPE_E_INPUT, 3, 1, "a",
              "duplicate key `a` (first given at line 1, column 1)");
    FAIL_TEXT("x:\n  y: 1\n  z: [1]\n  y: {q: 2}\n", DRAPE_E_INPUT, 4, 3, "x.y",
              "first given at line 2");
    FAIL_TEXT("s:\n  - {p: 1, p: 2}\n", DRAPE_E_INPUT, 2, 12, "s[0].p",
              "duplicate key `p`");
    /* the duplicate search is linear per key: a mapping holds at most 1024
     * keys, so that a file of 160,000 keys (2 MB) is refused at once, not
     * after minutes of a quadratic search */
    static char many[1100 * 12];
    size_t n = 0;
    for (int k = 0; k < 1100; k++) n += (size_t)sprintf(many + n, "k%d: %d\n", k, k);
    expect_fail(many, n, DRAPE_E_SYNTAX, 1025, 1, NULL, "more than 1024 keys in one mapping");
    /* same key in different mappings is fine */
    drape_error err;
    drape_error_clear(&err);
    const char *t = "a: {x: 1}\nb: {x: 2}\n";
    drape_ydoc *doc = drape_ydoc_load_string("ok", t, strlen(t), &err);
    ck_assert_msg(doc != NULL, "%s", err.msg);
    drape_ydoc_free(doc);
}
END_TEST

START_TEST(test_bad_keys)
{
    FAIL_TEXT("? [1, 2]\n: 3\n", DRAPE_E_SYNTAX, 1, 3, NULL,
              "mapping key must be a plain scalar");
    FAIL_TEXT("a:\n  {b: 1}: 2\n", DRAPE_E_SYNTAX, 2, 3, "a",
              "mapping key must be a plain scalar");
    /* the empty key's position is just after the '?' */
    FAIL_TEXT("a: 1\n? \n: 2\n", DRAPE_E_SYNTAX, 2, 2, NULL, "empty mapping key");
}
END_TEST

START_TEST(test_io)
{
    drape_error err;
    drape_error_clear(&err);
    ck_assert_ptr_null(drape_ydoc_load("/nonexistent/x.yaml", &err));
    ck_assert_int_eq(err.kind, DRAPE_E_IO);
    ck_assert_str_eq(err.file, "/nonexistent/x.yaml");
    ck_assert_ptr_nonnull(strstr(err.msg, "cannot open"));
    drape_error_clear(&err);
    ck_assert_ptr_null(drape_ydoc_load(tu_scratch_dir(), &err));
    ck_assert_int_eq(err.kind, DRAPE_E_IO);
    ck_assert_str_eq(err.file, tu_scratch_dir());
    /* the first error wins */
    drape_error_set(&err, DRAPE_E_USAGE, "x", 1, 1, NULL, "first");
    ck_assert_ptr_null(drape_ydoc_load("/nonexistent/y.yaml", &err));
    ck_assert_int_eq(err.kind, DRAPE_E_IO);
}
END_TEST

START_TEST(test_check_keys)
{
    static const char *const allowed[] = {"spacing", "specimen", "solver",
                                          "end", NULL};
    const char *t = "spacing: 1 cm\nsolver:\n  rtol: 1\n  spacng: 2\n"
                    "x: 1\n";
    drape_error err;
    drape_error_clear(&err);
    drape_ydoc *doc = drape_ydoc_load_string("s.yaml", t, strlen(t), &err);
    ck_assert_msg(doc != NULL, "%s", err.msg);
    /* unknown key far from every allowed one: a list */
    ck_assert_int_eq(drape_ynode_check_keys(doc, doc->root, "", allowed, &err),
                     -1);
    ck_assert_int_eq(err.kind, DRAPE_E_INPUT);
    ck_assert_str_eq(err.file, "s.yaml");
    ck_assert_int_eq(err.line, 5);
    ck_assert_int_eq(err.column, 1);
    ck_assert_str_eq(err.key, "x");
    ck_assert_str_eq(err.msg, "unknown key `x` (expected one of: spacing, "
                     "specimen, solver, end)");
    /* a typo in a nested mapping: suggestion and key path */
    static const char *const solver_keys[] = {"rtol", "spacing", NULL};
    drape_error_clear(&err);
    const drape_ynode *solver = drape_ynode_get(doc->root, "solver", NULL);
    ck_assert_int_eq(drape_ynode_check_keys(doc, solver, "solver", solver_keys,
                                            &err), -1);
    ck_assert_int_eq(err.line, 4);
    ck_assert_int_eq(err.column, 3);
    ck_assert_str_eq(err.key, "solver.spacng");
    ck_assert_str_eq(err.msg, "unknown key `spacng`; did you mean `spacing`?");
    /* all keys known */
    static const char *const all[] = {"spacing", "solver", "x", NULL};
    drape_error_clear(&err);
    ck_assert_int_eq(drape_ynode_check_keys(doc, doc->root, "", all, &err), 0);
    ck_assert_int_eq(err.kind, DRAPE_OK);
    drape_ydoc_free(doc);

    /* the suggestion threshold is max(2, len/3): "tmx" -> "t_max" is 2
     * edits (suggested); "tolerance" vs "rtol" is 6 > 3 (not suggested) */
    static const char *const end_keys[] = {"t_max", "rtol", NULL};
    t = "tmx: 1\n";
    doc = drape_ydoc_load_string("e.yaml", t, strlen(t), &err);
    drape_error_clear(&err);
    drape_ynode_check_keys(doc, doc->root, "end", end_keys, &err);
    ck_assert_str_eq(err.msg, "unknown key `tmx`; did you mean `t_max`?");
    ck_assert_str_eq(err.key, "end.tmx");
    drape_ydoc_free(doc);
    t = "tolerance: 1\n";
    doc = drape_ydoc_load_string("e.yaml", t, strlen(t), &err);
    drape_error_clear(&err);
    drape_ynode_check_keys(doc, doc->root, "end", end_keys, &err);
    ck_assert_ptr_null(strstr(err.msg, "did you mean"));
    drape_ydoc_free(doc);
}
END_TEST

START_TEST(test_levenshtein)
{
    ck_assert_uint_eq(drape_levenshtein("kitten", "sitting"), 3);
    ck_assert_uint_eq(drape_levenshtein("", "abc"), 3);
    ck_assert_uint_eq(drape_levenshtein("abc", ""), 3);
    ck_assert_uint_eq(drape_levenshtein("spacing", "spacing"), 0);
    ck_assert_uint_eq(drape_levenshtein("spacng", "spacing"), 1);
    ck_assert_uint_eq(drape_levenshtein("flaw", "lawn"), 2);
    /* longer than the stack row: 100 'a' vs 99 'a' + 'b' -> 1 */
    char a[101], b[101];
    memset(a, 'a', 100); a[100] = 0;
    memset(b, 'a', 100); b[99] = 'b'; b[100] = 0;
    ck_assert_uint_eq(drape_levenshtein(a, b), 1);
}
END_TEST

START_TEST(test_ynode_error)
{
    const char *t = "a:\n  b: 7\n";
    drape_error err;
    drape_error_clear(&err);
    drape_ydoc *doc = drape_ydoc_load_string("n.yaml", t, strlen(t), &err);
    const drape_ynode *b =
        drape_ynode_get(drape_ynode_get(doc->root, "a", NULL), "b", NULL);
    ck_assert_int_eq(drape_ynode_error(&err, doc, b, "a.b", DRAPE_E_INPUT,
                                       "expected %s, got \"%s\"", "x", b->scalar),
                     -1);
    char buf[256];
    ck_assert_str_eq(drape_error_format(&err, buf, sizeof buf),
                     "n.yaml:2:6: a.b: expected x, got \"7\"");
    drape_error_clear(&err);
    drape_ynode_error(&err, doc, NULL, NULL, DRAPE_E_INPUT, "missing");
    ck_assert_int_eq(err.line, 0);
    ck_assert_str_eq(drape_error_format(&err, buf, sizeof buf),
                     "n.yaml: missing");
    drape_ydoc_free(doc);
}
END_TEST

START_TEST(test_alloc_failures)
{
    /* Make every allocation fail in turn: the loader must report E_NOMEM
     * and return NULL, never crash (run under valgrind for leaks). */
    const char *t = "a: {x: [1, 2, 3, 4, 5]}\nb: text\nc: [{d: 1}, {e: 2}]\n";
    const char *p = tu_write_file("alloc.yaml", t);
    drape_error err;
    drape_error_clear(&err);
    drape_alloc_fail_at(0);
    drape_ydoc *doc = drape_ydoc_load(p, &err);
    ck_assert_ptr_nonnull(doc);
    drape_ydoc_free(doc);
    long total = 0;
    drape_alloc_fail_at(1000000);
    doc = drape_ydoc_load(p, &err);
    total = drape_alloc_count();
    drape_ydoc_free(doc);
    ck_assert(total > 10);
    for (long n = 1; n <= total; n++) {
        drape_error_clear(&err);
        drape_alloc_fail_at(n);
        doc = drape_ydoc_load(p, &err);
        drape_alloc_fail_at(0);
        ck_assert_msg(doc == NULL, "allocation %ld of %ld failed but the load "
                      "succeeded", n, total);
        ck_assert_int_eq(err.kind, DRAPE_E_NOMEM);
    }
}
END_TEST

Suite *yamldoc_suite(void); /* found by the runner */
Suite *yamldoc_suite(void)
{
    Suite *s = suite_create("yamldoc");
    TCase *tc = tcase_create("yamldoc");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, test_good_tree);
    tcase_add_test(tc, test_many_items);
    tcase_add_test(tc, test_malformed);
    tcase_add_test(tc, test_empty);
    tcase_add_test(tc, test_binary);
    tcase_add_test(tc, test_line_breaks);
    tcase_add_test(tc, test_too_large);
    tcase_add_test(tc, test_documents);
    tcase_add_test(tc, test_anchors_tags);
    tcase_add_test(tc, test_depth);
    tcase_add_test(tc, test_duplicate_keys);
    tcase_add_test(tc, test_bad_keys);
    tcase_add_test(tc, test_io);
    tcase_add_test(tc, test_check_keys);
    tcase_add_test(tc, test_levenshtein);
    tcase_add_test(tc, test_ynode_error);
    tcase_add_test(tc, test_alloc_failures);
    suite_add_tcase(s, tc);
    return s;
}

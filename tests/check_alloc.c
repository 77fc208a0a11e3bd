/* check_alloc.c: allocation-failure walks (issue 7, item 4) that the
 * per-module suites do not already make.
 *
 * A walk counts the allocations N of a successful call, then repeats the
 * call with allocation n failing (and, by the hook's contract, every later
 * one) for n = 1..N: each must fail cleanly (-1 or NULL, E_NOMEM, the file
 * named in the error), and a last call must succeed again.  Already walked elsewhere: yamldoc on one small text
 * (check_yamldoc), fabrics/cotton-breen.yaml (check_fabric),
 * scenes/cusick.yaml (check_scene), the lattice of a circle, a pinned hang
 * and a strip built by hand (check_lattice), the model, outputs, observers
 * and integrators (their suites).  Added here: every shipped fabric and
 * scene file (the KES path included), a document that grows mappings and
 * sequences through several doublings, drape_ydoc_load_string, the whole
 * path of `drape check SCENE` (scene, its fabric, the combined check, the
 * lattice) for every shipped scene, and the table lattice with each subset
 * of energy terms.
 *
 * Leaks ("no leak" of the issue) are found by running this suite under
 * valgrind (scripts/valgrind.sh, CK_FORK=no, every leak an error) and
 * under LeakSanitizer (scripts/asan.sh).  glibc's own count of bytes in use
 * (mallinfo2) was tried here and dropped: tcache keeps freed blocks counted
 * as in use, and Check's fork mode allocates per assertion. */
#include <dirent.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "drape/alloc.h"
#include "drape/fabric.h"
#include "drape/lattice.h"
#include "drape/scene.h"
#include "drape/yamldoc.h"
#include "testutil.h"

/* One call under test: 0 on success (everything it made freed again), -1
 * with err set on failure. */
typedef int (*step_fn)(const char *path, drape_error *err);

/* Walk every allocation of step(arg); returns N.  `what` names the walk in
 * messages. */
static long walk_as(const char *what, const char *arg, step_fn step)
{
    const char *path = what;
    drape_error err;
    char buf[2048];
    /* it works, and how many allocations it makes */
    drape_error_clear(&err);
    ck_assert_msg(step(arg, &err) == 0, "%s: %s", path,
                  drape_error_format(&err, buf, sizeof buf));
    drape_alloc_fail_at(LONG_MAX);
    drape_error_clear(&err);
    int rc = step(arg, &err);
    long total = drape_alloc_count();
    drape_alloc_fail_at(0);
    ck_assert_int_eq(rc, 0);
    ck_assert_msg(total > 0, "%s: no allocation to fail", path);

    for (long n = 1; n <= total; n++) {
        drape_error_clear(&err);
        drape_alloc_fail_at(n);
        rc = step(arg, &err);
        drape_alloc_fail_at(0);
        drape_error_format(&err, buf, sizeof buf);
        ck_assert_msg(rc == -1, "%s: allocation %ld of %ld failed, the call "
                      "succeeded", path, n, total);
        ck_assert_msg(err.kind == DRAPE_E_NOMEM, "%s: allocation %ld of %ld: "
                      "kind %d: %s", path, n, total, (int)err.kind, buf);
        ck_assert_msg(err.file[0] != 0 && err.msg[0] != 0,
                      "%s: allocation %ld: no file or message: %s", path, n, buf);
    }
    /* and it still works */
    drape_error_clear(&err);
    ck_assert_int_eq(step(arg, &err), 0);
    return total;
}

static long walk(const char *path, step_fn step) { return walk_as(path, path, step); }

/* Call walk() for every .yaml file of a source directory. */
static int walk_dir(const char *dir, step_fn step)
{
    char path[600];
    int n = 0;
    DIR *d = opendir(tu_src(dir));
    ck_assert_msg(d != NULL, "cannot open %s", dir);
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        size_t len = strlen(e->d_name);
        if (len < 6 || strcmp(e->d_name + len - 5, ".yaml") != 0) continue;
        snprintf(path, sizeof path, "../%s/%s", dir, e->d_name);
        walk(path, step);
        n++;
    }
    closedir(d);
    return n;
}

/* ------------------------------------------------------------- steps */

static int step_ydoc(const char *path, drape_error *err)
{
    drape_ydoc *doc = drape_ydoc_load(path, err);
    if (!doc) return -1;
    drape_ydoc_free(doc);
    return 0;
}

static int step_ydoc_string(const char *text, drape_error *err)
{
    drape_ydoc *doc = drape_ydoc_load_string("dir/text.yaml", text,
                                             strlen(text), err);
    if (!doc) return -1;
    ck_assert_str_eq(doc->dir, "dir");
    drape_ydoc_free(doc);
    return 0;
}

static int step_fabric(const char *path, drape_error *err)
{
    drape_fabric f;
    return drape_fabric_load(path, &f, err, NULL, NULL);
}

static int n_warnings;
static void count_warning(void *ctx, const drape_error *w)
{
    (void)ctx;
    (void)w;
    n_warnings++;
}

static int step_scene(const char *path, drape_error *err)
{
    drape_scene s;
    return drape_scene_load(path, &s, err, count_warning, NULL);
}

/* What `drape check SCENE` does up to the model (src/cli_check.c). */
static int step_check_scene(const char *path, drape_error *err)
{
    drape_scene s;
    drape_fabric f;
    if (drape_scene_load(path, &s, err, count_warning, NULL) ||
        drape_fabric_load(s.fabric_path, &f, err, count_warning, NULL) ||
        drape_scene_check_with_fabric(&s, &f, err))
        return -1;
    drape_lattice *L = drape_lattice_new(&s, &f, err);
    if (!L) return -1;
    ck_assert_int_eq(drape_lattice_check(L), 0);
    drape_lattice_free(L);
    return 0;
}

/* ------------------------------------------------------------- tests */

/* The hook as the walks use it: allocation n and every later one fail,
 * the count restarts at each call of drape_alloc_fail_at. */
START_TEST(test_hook)
{
    drape_alloc_fail_at(2);
    void *a = drape_malloc(10);
    void *b = drape_malloc(10);
    char *c = drape_strdup("x");
    drape_alloc_fail_at(0);
    ck_assert_ptr_nonnull(a);
    ck_assert_ptr_null(b);
    ck_assert_ptr_null(c); /* every later allocation fails too */
    ck_assert_int_eq(drape_alloc_count(), 0);
    void *d = drape_calloc(2, 8);
    ck_assert_ptr_nonnull(d);
    ck_assert_int_eq(drape_alloc_count(), 1);
    drape_free(d);
    drape_free(a);
}
END_TEST

START_TEST(test_ydoc_shipped_files)
{
    ck_assert_int_ge(walk_dir("fabrics", step_ydoc), 2);
    ck_assert_int_ge(walk_dir("scenes", step_ydoc), 4);
}
END_TEST

/* Mappings and sequences that grow through 4 -> 8 -> 16 -> 32 -> 64 items
 * (each growth reallocates items, keys and both position arrays), long
 * keys, long scalars and deep nesting. */
static char big[65536];

static const char *big_document(void)
{
    size_t k = 0;
#define PUT(...) k += (size_t)snprintf(big + k, sizeof big - k, __VA_ARGS__)
    for (int i = 0; i < 40; i++) PUT("key_%02d: %d\n", i, i);
    PUT("seq: [");
    for (int i = 0; i < 70; i++) PUT("%s%d", i ? ", " : "", i);
    PUT("]\n");
    PUT("block:\n");
    for (int i = 0; i < 20; i++) PUT("  - {a: %d, b: [x, y], c: {d: e}}\n", i);
    PUT("a_key_that_is_longer_than_sixty_four_characters_so_that_levenshtein_"
        "allocates: 1\n");
    PUT("text: \"");
    for (int i = 0; i < 300; i++) PUT("word ");
    PUT("\"\n");
    PUT("deep: ");
    for (int i = 0; i < 25; i++) PUT("[");
    PUT("1");
    for (int i = 0; i < 25; i++) PUT("]");
    PUT("\n");
#undef PUT
    ck_assert(k < sizeof big - 1);
    return big;
}

START_TEST(test_ydoc_growth)
{
    const char *text = big_document();
    const char *p = tu_write_file("big.yaml", text);
    long n = walk(p, step_ydoc);
    ck_assert_int_gt(n, 600); /* about 2 per scalar, 4-5 per collection */
    walk_as("drape_ydoc_load_string", text, step_ydoc_string);
    /* check_keys on a mapping with a long unknown key (levenshtein's row
     * allocation failing falls back to a bound, never an error of its own) */
    drape_error err;
    drape_error_clear(&err);
    drape_ydoc *doc = drape_ydoc_load(p, &err);
    ck_assert_ptr_nonnull(doc);
    static const char *const allowed[] = {
        "a_key_that_is_longer_than_sixty_four_characters_so_that_levenshtein_"
        "allocatez", NULL};
    for (int n_fail = 1; n_fail <= 2; n_fail++) {
        drape_error_clear(&err);
        drape_alloc_fail_at(n_fail);
        int rc = drape_ynode_check_keys(doc, doc->root, "", allowed, &err);
        drape_alloc_fail_at(0);
        ck_assert_int_eq(rc, -1);
        ck_assert_int_eq(err.kind, DRAPE_E_INPUT);
        ck_assert_str_eq(err.key, "key_00");
    }
    drape_ydoc_free(doc);
}
END_TEST

START_TEST(test_fabric_shipped_files)
{
    ck_assert_int_ge(walk_dir("fabrics", step_fabric), 2);
}
END_TEST

START_TEST(test_scene_shipped_files)
{
    ck_assert_int_ge(walk_dir("scenes", step_scene), 4);
}
END_TEST

START_TEST(test_check_path_shipped_scenes)
{
    ck_assert_int_ge(walk_dir("scenes", step_check_scene), 4);
}
END_TEST

/* The table lattice (not walked in check_lattice) with every subset of the
 * elastic terms: the element arrays that are empty are not allocated, so
 * each subset fails at different places. */
static drape_scene lat_scene;
static drape_fabric lat_fabric;

static int step_lattice(const char *unused, drape_error *err)
{
    (void)unused;
    drape_lattice *L = drape_lattice_new(&lat_scene, &lat_fabric, err);
    if (!L) return -1;
    ck_assert_int_eq(drape_lattice_check(L), 0);
    drape_lattice_free(L);
    return 0;
}

START_TEST(test_lattice_table_terms)
{
    drape_error err;
    drape_error_clear(&err);
    ck_assert_int_eq(drape_scene_load(tu_src("scenes/table.yaml"), &lat_scene,
                                      &err, NULL, NULL), 0);
    ck_assert_int_eq(drape_fabric_load(lat_scene.fabric_path, &lat_fabric, &err,
                                       NULL, NULL), 0);
    lat_scene.spacing = 0.04; /* 60 cm cloth: 16 x 16 particles */
    long prev = -1;
    int differ = 0;
    for (unsigned t = 0; t < 8; t++) {
        lat_scene.terms = DRAPE_TERM_GRAVITY | (t & 1 ? DRAPE_TERM_STRETCH : 0) |
                          (t & 2 ? DRAPE_TERM_BEND : 0) |
                          (t & 4 ? DRAPE_TERM_SHEAR : 0);
        long n = walk("table.yaml (terms)", step_lattice);
        differ += prev >= 0 && n != prev;
        prev = n;
    }
    ck_assert_msg(differ > 0, "every subset of terms allocates alike");
}
END_TEST

Suite *alloc_suite(void); /* found by the runner */
Suite *alloc_suite(void)
{
    Suite *s = suite_create("alloc");
    TCase *tc = tcase_create("alloc");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, test_hook);
    tcase_add_test(tc, test_ydoc_shipped_files);
    tcase_add_test(tc, test_ydoc_growth);
    tcase_add_test(tc, test_fabric_shipped_files);
    tcase_add_test(tc, test_scene_shipped_files);
    tcase_add_test(tc, test_check_path_shipped_scenes);
    tcase_add_test(tc, test_lattice_table_terms);
    suite_add_tcase(s, tc);
    return s;
}

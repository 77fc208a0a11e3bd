/* alloc.h: the one allocation choke point of drape.
 *
 * Every heap allocation of the library goes through these functions so that
 * tests can make the n-th allocation fail (drape_alloc_fail_at) and walk
 * every failure path of the loaders and builders.  drape_free(NULL) is a
 * no-op, like free().
 */
#ifndef DRAPE_ALLOC_H
#define DRAPE_ALLOC_H

#include <stddef.h>

/* malloc/calloc/realloc work-alikes; return NULL on failure (or when the
 * test hook says so).  drape_calloc checks n * size for overflow. */
void *drape_malloc(size_t size);
void *drape_calloc(size_t n, size_t size);
void *drape_realloc(void *p, size_t size);
void drape_free(void *p);
/* strdup through the choke point; caller frees with drape_free. */
char *drape_strdup(const char *s);

/* Test hook: the n-th allocation from now on (1-based) and every later one
 * fail; n = 0 disables the hook.  Returns nothing; see
 * drape_alloc_count() for the number of allocations made since the last
 * call of drape_alloc_fail_at. */
void drape_alloc_fail_at(long n);
long drape_alloc_count(void);

#endif /* DRAPE_ALLOC_H */

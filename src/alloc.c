/* alloc.c: the allocation choke point (see alloc.h). */
#include "drape/alloc.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static long fail_at;    /* 0: never fail */
static long count;      /* allocations since the last drape_alloc_fail_at */

static int should_fail(void)
{
    count++;
    return fail_at > 0 && count >= fail_at;
}

void drape_alloc_fail_at(long n)
{
    fail_at = n;
    count = 0;
}

long drape_alloc_count(void) { return count; }

void *drape_malloc(size_t size)
{
    if (should_fail()) return NULL;
    return malloc(size ? size : 1);
}

void *drape_calloc(size_t n, size_t size)
{
    if (size && n > SIZE_MAX / size) return NULL;
    if (should_fail()) return NULL;
    return calloc(n ? n : 1, size ? size : 1);
}

void *drape_realloc(void *p, size_t size)
{
    if (should_fail()) return NULL;
    return realloc(p, size ? size : 1);
}

void drape_free(void *p) { free(p); }

char *drape_strdup(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = drape_malloc(n);
    if (d) memcpy(d, s, n);
    return d;
}

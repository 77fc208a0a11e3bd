/* error.c: error values (see error.h). */
#include "drape/error.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

void drape_error_clear(drape_error *e)
{
    if (e) memset(e, 0, sizeof *e);
}

static void copy(char *dst, size_t n, const char *src)
{
    if (!src) { dst[0] = 0; return; }
    snprintf(dst, n, "%s", src);
}

int drape_error_set(drape_error *e, drape_error_kind kind, const char *file,
                    int line, int column, const char *key, const char *fmt,
                    ...)
{
    if (!e || e->kind != DRAPE_OK) return -1;
    e->kind = kind;
    copy(e->file, sizeof e->file, file);
    e->line = line;
    e->column = column;
    copy(e->key, sizeof e->key, key);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(e->msg, sizeof e->msg, fmt, ap);
    va_end(ap);
    return -1;
}

char *drape_error_format(const drape_error *e, char *buf, size_t n)
{
    size_t k = 0;
    if (n == 0) return buf;
    buf[0] = 0;
#define PUT(...)                                                            \
    do {                                                                    \
        int r_ = snprintf(buf + k, n - k, __VA_ARGS__);                     \
        if (r_ > 0) k += (size_t)r_ < n - k ? (size_t)r_ : n - k - 1;       \
    } while (0)
    if (e->file[0]) {
        PUT("%s:", e->file);
        if (e->line > 0) {
            PUT("%d:", e->line);
            if (e->column > 0) PUT("%d:", e->column);
        }
        PUT(" ");
    }
    if (e->key[0]) PUT("%s: ", e->key);
    PUT("%s", e->msg);
#undef PUT
    return buf;
}

int drape_error_exit_status(drape_error_kind kind)
{
    switch (kind) {
    case DRAPE_OK: return 0;
    case DRAPE_E_SYNTAX:
    case DRAPE_E_INPUT: return 1;
    case DRAPE_E_USAGE: return 2;
    case DRAPE_E_IO: return 3;
    case DRAPE_E_NUMERIC: return 4;
    case DRAPE_E_NOMEM: return 5;
    case DRAPE_E_INTERNAL: return 70;
    }
    return 70;
}

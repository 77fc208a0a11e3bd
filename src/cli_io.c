/* cli_io.c: file helpers shared by the command-line files: a small
 * RFC 4180 CSV reader and writer, whole-file reading, and atomic file
 * replacement (write a temporary file next to the target, flush, fsync,
 * rename).  Used by `drape batch` (results.csv, the rows of `drape run`)
 * and `drape import` (KES-F tables, fabric YAML files).
 *
 * CSV (RFC 4180, https://www.rfc-editor.org/rfc/rfc4180): records end with
 * LF or CRLF; fields are separated by commas; a field may be enclosed in
 * double quotes, inside which commas, line breaks and doubled quotes ("")
 * are literal.  Accepted beyond the RFC: LF alone, CR alone (old Mac
 * Excel's export; the RFC allows no CR outside quotes), a missing final
 * line break, a UTF-8 byte order mark at the start.  Lines are counted
 * for messages with each of LF, CR LF and CR one break.  Rejected: a quote inside an
 * unquoted field, text after a closing quote, an unterminated quote, NUL
 * bytes.  There is no CSV library among the Debian -dev packages drape
 * builds on, hence this reader (docs/batch.md). */
#include "cli_io.h"

#include "cli.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <fnmatch.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <stdint.h>
#include <sys/file.h>
#include <sys/stat.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif
#include <unistd.h>

#include <json-c/json.h>

#include "drape/alloc.h"
#include "drape/units.h"

/* ---- whole files ----------------------------------------------------------- */

char *drape_cli_read_file(const char *path, size_t max, size_t *len,
                          drape_error *err)
{
    FILE *f = fopen(path, "rb");
    char *buf = NULL;
    size_t n = 0, cap = 4096;
    if (!f) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "cannot open: %s",
                        strerror(errno));
        return NULL;
    }
    buf = drape_malloc(cap);
    if (!buf) goto nomem;
    for (;;) {
        if (n + 1 >= cap) {
            if (cap > max) {
                drape_error_set(err, DRAPE_E_INPUT, path, 0, 0, NULL,
                                "file larger than %zu bytes", max);
                goto fail;
            }
            char *nb = drape_realloc(buf, cap * 2);
            if (!nb) goto nomem;
            buf = nb;
            cap *= 2;
        }
        size_t k = fread(buf + n, 1, cap - n - 1, f);
        n += k;
        if (k == 0) break;
    }
    if (ferror(f)) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "read error");
        goto fail;
    }
    if (n > max) {
        drape_error_set(err, DRAPE_E_INPUT, path, 0, 0, NULL,
                        "file larger than %zu bytes", max);
        goto fail;
    }
    fclose(f);
    buf[n] = 0;
    if (len) *len = n;
    return buf;
nomem:
    drape_error_set(err, DRAPE_E_NOMEM, path, 0, 0, NULL, "out of memory");
fail:
    fclose(f);
    drape_free(buf);
    return NULL;
}

/* ---- atomic replacement ------------------------------------------------------ */

int drape_cli_file_sum(const char *path, size_t max, unsigned long long *sum,
                       drape_error *err)
{
    size_t len = 0;
    char *text = drape_cli_read_file(path, max, &len, err);
    if (!text) return -1;
    unsigned long long h = 14695981039346656037ULL;
    for (size_t i = 0; i < len; i++) {
        h ^= (unsigned char)text[i];
        h *= 1099511628211ULL;
    }
    drape_free(text);
    *sum = h ? h : 1;
    return 0;
}

int drape_cli_afile_open(drape_cli_afile *a, const char *path, drape_error *err)
{
    memset(a, 0, sizeof *a);
    int r1 = snprintf(a->path, sizeof a->path, "%s", path);
    int r2 = snprintf(a->tmp, sizeof a->tmp, "%s.tmp.%ld", path, (long)getpid());
    if (r1 < 0 || (size_t)r1 >= sizeof a->path || r2 < 0 || (size_t)r2 >= sizeof a->tmp)
        return drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "path too long");
    /* O_EXCL: never write through a stale temporary or a symlink */
    unlink(a->tmp);
    int fd = open(a->tmp, O_WRONLY | O_CREAT | O_EXCL, 0666);
    if (fd < 0 || !(a->f = fdopen(fd, "w"))) {
        int e = errno;
        if (fd >= 0) close(fd);
        unlink(a->tmp);
        return drape_error_set(err, DRAPE_E_IO, a->tmp, 0, 0, NULL,
                               "cannot create: %s", strerror(e));
    }
    return 0;
}

int drape_cli_afile_commit(drape_cli_afile *a, drape_error *err)
{
    int e = 0;
    if (fflush(a->f) != 0 || ferror(a->f)) e = errno ? errno : EIO;
    if (!e && fsync(fileno(a->f)) != 0 && errno != EINVAL) e = errno;
    if (fclose(a->f) != 0 && !e) e = errno ? errno : EIO;
    a->f = NULL;
    if (!e && rename(a->tmp, a->path) != 0) e = errno;
    if (e) {
        unlink(a->tmp);
        return drape_error_set(err, DRAPE_E_IO, a->path, 0, 0, NULL,
                               "cannot write: %s", strerror(e));
    }
    return 0;
}

void drape_cli_afile_abort(drape_cli_afile *a)
{
    if (a->f) {
        fclose(a->f);
        a->f = NULL;
    }
    if (a->tmp[0]) unlink(a->tmp);
}

/* ---- line breaks ------------------------------------------------------------ */

/* 1 if t[i] is the last byte of a line break: LF, or a CR not followed by
 * LF (old Mac files).  LF, CR LF and CR alone each end one line, as
 * libyaml and drape's YAML messages count them (docs/fabrics.md).  t[len]
 * may be read when it is a NUL terminator (len = SIZE_MAX: NUL-terminated). */
static int line_ends_at(const char *t, size_t i, size_t len)
{
    return t[i] == '\n' || (t[i] == '\r' && !(i + 1 < len && t[i + 1] == '\n'));
}

/* ---- CSV ------------------------------------------------------------------- */

void drape_cli_csv_rec_free(drape_cli_csv_rec *r)
{
    if (!r) return;
    for (int i = 0; i < r->n; i++) drape_free(r->field[i]);
    drape_free(r->field);
    drape_free(r->col);
    memset(r, 0, sizeof *r);
}

/* Append one field (bytes s[0..n)) to r. */
static int rec_push(drape_cli_csv_rec *r, const char *s, size_t n, int col)
{
    char **nf = drape_realloc(r->field, (size_t)(r->n + 1) * sizeof *nf);
    if (!nf) return -1;
    r->field = nf;
    int *nc = drape_realloc(r->col, (size_t)(r->n + 1) * sizeof *nc);
    if (!nc) return -1;
    r->col = nc;
    char *t = drape_malloc(n + 1);
    if (!t) return -1;
    memcpy(t, s, n);
    t[n] = 0;
    r->field[r->n] = t;
    r->col[r->n] = col;
    r->n++;
    return 0;
}

int drape_cli_csv_next(const char *text, size_t len, drape_cli_csv_pos *p,
                       drape_cli_csv_rec *r, const char *file, drape_error *err)
{
    memset(r, 0, sizeof *r);
    if (p->line == 0) { /* first call */
        p->line = 1;
        p->col = 1;
        if (len >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0) p->off = 3;
    }
    if (p->off >= len) return 0;
    r->line = p->line;
    char *buf = NULL; /* unquoted text of the current field */
    size_t cap = 0;
    for (;;) { /* one field per iteration */
        size_t n = 0;
        int col = p->col;
        const char *c = text + p->off;
        if (p->off < len && *c == '"') {
            int qline = p->line, qcol = p->col;
            p->off++, p->col++;
            for (;;) {
                if (p->off >= len) {
                    drape_error_set(err, DRAPE_E_INPUT, file, qline, qcol, NULL,
                                    "unterminated quoted field");
                    goto fail;
                }
                char ch = text[p->off];
                if (ch == '"') {
                    if (p->off + 1 < len && text[p->off + 1] == '"') {
                        p->off += 2, p->col += 2;
                    } else {
                        p->off++, p->col++;
                        break;
                    }
                } else if (ch == 0) {
                    drape_error_set(err, DRAPE_E_INPUT, file, p->line, p->col, NULL,
                                    "NUL byte in a CSV file");
                    goto fail;
                } else {
                    if (line_ends_at(text, p->off, len)) p->line++, p->col = 0;
                    p->off++, p->col++;
                }
                if (n + 1 >= cap) {
                    size_t nc = cap ? cap * 2 : 64;
                    char *nb = drape_realloc(buf, nc);
                    if (!nb) goto nomem;
                    buf = nb, cap = nc;
                }
                buf[n++] = ch;
            }
            if (p->off < len && text[p->off] != ',' && text[p->off] != '\n' &&
                text[p->off] != '\r') {
                drape_error_set(err, DRAPE_E_INPUT, file, p->line, p->col, NULL,
                                "text after the closing quote of a field "
                                "(a quote inside a quoted field is written \"\")");
                goto fail;
            }
            if (rec_push(r, n ? buf : "", n, col) != 0) goto nomem;
        } else {
            size_t start = p->off;
            while (p->off < len && text[p->off] != ',' && text[p->off] != '\n' &&
                   text[p->off] != '\r') {
                if (text[p->off] == '"') {
                    drape_error_set(err, DRAPE_E_INPUT, file, p->line, p->col, NULL,
                                    "quote inside an unquoted field (enclose the "
                                    "field in quotes and double the quote)");
                    goto fail;
                }
                if (text[p->off] == 0) {
                    drape_error_set(err, DRAPE_E_INPUT, file, p->line, p->col, NULL,
                                    "NUL byte in a CSV file");
                    goto fail;
                }
                p->off++, p->col++;
            }
            if (rec_push(r, text + start, p->off - start, col) != 0) goto nomem;
        }
        if (p->off >= len) break;
        if (text[p->off] == ',') {
            p->off++, p->col++;
            continue;
        }
        /* end of record: LF, CR LF or CR */
        p->off += line_ends_at(text, p->off, len) ? 1 : 2;
        p->line++, p->col = 1;
        break;
    }
    drape_free(buf);
    return 1;
nomem:
    drape_error_set(err, DRAPE_E_NOMEM, file, p->line, 0, NULL, "out of memory");
fail:
    drape_free(buf);
    drape_cli_csv_rec_free(r);
    return -1;
}

void drape_cli_csv_put(FILE *out, const char *s)
{
    if (!s) return;
    int quote = s[0] == ' ' || (s[0] && s[strlen(s) - 1] == ' ');
    for (const char *c = s; *c && !quote; c++)
        quote = *c == ',' || *c == '"' || *c == '\n' || *c == '\r';
    if (!quote) {
        fputs(s, out);
        return;
    }
    fputc('"', out);
    for (const char *c = s; *c; c++) {
        if (*c == '"') fputc('"', out);
        fputc(*c, out);
    }
    fputc('"', out);
}

void drape_cli_stop_with_parent(pid_t parent)
{
#ifdef __linux__
    /* SIGTERM when the parent dies, even of SIGKILL: the child then stops
     * at its next output point as if interrupted (its checkpoint stays)
     * instead of running on unseen with its result lost */
    if (prctl(PR_SET_PDEATHSIG, SIGTERM) == 0 && getppid() != parent) raise(SIGTERM);
#else
    (void)parent; /* no such request in POSIX: the child runs on */
#endif
}

pid_t drape_cli_fork_pipe(int *fd)
{
    int fds[2];
    if (pipe(fds) != 0) return -1;
    fflush(stdout);
    fflush(stderr);
    pid_t parent = getpid();
    pid_t pid = fork();
    if (pid < 0) {
        int e = errno;
        close(fds[0]);
        close(fds[1]);
        errno = e;
        return -1;
    }
    if (pid == 0) {
        drape_cli_stop_with_parent(parent);
        close(fds[0]);
        *fd = fds[1];
        return 0;
    }
    close(fds[1]);
    *fd = fds[0];
    return pid;
}

int drape_cli_ensure_dir(const char *dir, int *created, drape_error *err)
{
    struct stat st;
    if (created) *created = 0;
    if (stat(dir, &st) == 0) {
        if (S_ISDIR(st.st_mode)) return 0;
        return drape_error_set(err, DRAPE_E_IO, dir, 0, 0, NULL, "--out: not a directory");
    }
    if (mkdir(dir, 0777) != 0)
        return drape_error_set(err, DRAPE_E_IO, dir, 0, 0, NULL,
                               "--out: cannot create directory: %s", strerror(errno));
    if (created) *created = 1;
    return 0;
}

int drape_cli_lock_dir(const char *dir, int *held, drape_error *err)
{
    if (held) *held = 0;
    /* kept open (and locked) until the process exits */
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return 0; /* not readable (mode -wx): unguarded, the writes will tell */
    if (flock(fd, LOCK_EX | LOCK_NB) == 0) {
        if (held) *held = 1;
        return 0;
    }
    int e = errno;
    close(fd);
    if (e == EWOULDBLOCK)
        return drape_error_set(err, DRAPE_E_IO, dir, 0, 0, NULL,
                               "--out: another drape run is writing into this directory "
                               "(a run, an ensemble or a --resume that has not ended): "
                               "wait for it, or give another --out");
    /* a file system without flock on directories (NFS emulates flock by
     * byte-range locks, which need a file open for writing: EBADF,
     * ENOLCK): the run goes on unguarded, as before the guard */
    (void)err;
    return 0;
}

/* 1 if s is a temporary name of form: NAME, then ".tmp.PID" or
 * ".PID.tmp", with NAME matching the pattern name and PID digits. */
static int is_stale_tmp(const char *s, const char *name, drape_cli_tmp_form form)
{
    char stem[NAME_MAX + 1];
    size_t len = strlen(s);
    if (len > NAME_MAX) return 0;
    memcpy(stem, s, len + 1);
    if (form == DRAPE_CLI_TMP_PID_FIRST) { /* NAME.PID.tmp */
        if (len < 4 || strcmp(stem + len - 4, ".tmp") != 0) return 0;
        stem[len -= 4] = 0;
    }
    char *dot = strrchr(stem, '.'), *pid = dot ? dot + 1 : NULL;
    if (!pid || !*pid || strspn(pid, "0123456789") != strlen(pid)) return 0;
    *dot = 0;
    if (form == DRAPE_CLI_TMP_PID_LAST) { /* NAME.tmp.PID */
        size_t n = strlen(stem);
        if (n < 4 || strcmp(stem + n - 4, ".tmp") != 0) return 0;
        stem[n - 4] = 0;
    }
    return fnmatch(name, stem, 0) == 0;
}

int drape_cli_remove_stale_tmp(const char *dir, const char *name, drape_cli_tmp_form form)
{
    DIR *d = opendir(dir);
    if (!d) return 0;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (!is_stale_tmp(e->d_name, name, form)) continue;
        char path[4400];
        struct stat st;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (lstat(path, &st) == 0 && !S_ISDIR(st.st_mode) && unlink(path) == 0) n++;
    }
    closedir(d);
    return n;
}

int drape_cli_check_target(const char *dir, const char *name, drape_error *err)
{
    char path[4200];
    struct stat st;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    if (lstat(path, &st) == 0 && S_ISDIR(st.st_mode))
        return drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL,
                               "--out: a directory is in the way of the output file");
    return 0;
}

/* ---- messages (only the command line prints: STYLE.md 6) ---------------- */

/* Set by an ensemble's child process: "specimen 3 (seed 4): " */
static char error_context[96];

void drape_cli_set_error_context(const char *ctx)
{
    snprintf(error_context, sizeof error_context, "%s", ctx ? ctx : "");
}

void drape_cli_print_error(const drape_error *e)
{
    char buf[2048];
    fprintf(stderr, "drape: %s%s\n", error_context, drape_error_format(e, buf, sizeof buf));
}

void drape_cli_warn(void *ctx, const drape_error *w)
{
    (void)ctx;
    char buf[2048];
    drape_error tmp = *w;
    tmp.msg[0] = 0; /* location and key only; the text follows "warning:" */
    drape_error_format(&tmp, buf, sizeof buf);
    fprintf(stderr, "drape: %s%swarning: %s\n", error_context, buf, w->msg);
}

/* ---- JSON --------------------------------------------------------------- */

/* Line and column (1-based) of byte off of a NUL-terminated text, lines
 * ending as line_ends_at says. */
static void line_col(const char *text, size_t off, int *line, int *col)
{
    *line = 1, *col = 1;
    for (size_t i = 0; i < off && text[i]; i++) {
        if (line_ends_at(text, i, SIZE_MAX)) (*line)++, *col = 1;
        else (*col)++;
    }
}

/* Skip blanks and comments (// and / * * /); return the offset of the next
 * other character. */
static size_t skip_blank(const char *t, size_t i, size_t n)
{
    while (i < n) {
        if (t[i] == ' ' || t[i] == '\t' || t[i] == '\n' || t[i] == '\r') i++;
        else if (t[i] == '/' && i + 1 < n && t[i + 1] == '/') {
            while (i < n && t[i] != '\n') i++;
        } else if (t[i] == '/' && i + 1 < n && t[i + 1] == '*') {
            const char *e = strstr(t + i + 2, "*/");
            if (!e) return i;
            i = (size_t)(e - t) + 2;
        } else break;
    }
    return i;
}

static struct json_object *read_json(const char *path, size_t max, int in_range,
                                     drape_error *err);

/* The scan of json_numbers_in_range: one open object or array, with the
 * key or index of the value in it being read. */
#define JSON_SCAN_DEPTH 64 /* more than json_tokener_new_ex's 32 */
typedef struct json_frame {
    char kind;    /* '{' or '[' */
    int want_key; /* in an object, the next string is a key */
    long index;   /* in an array */
    char key[64];
} json_frame;

/* The key path of the value being read: "bending[2][2]", "specimens[3].dc". */
static void json_key_path(const json_frame *f, int depth, char *buf, size_t n)
{
    size_t k = 0;
    buf[0] = 0;
    for (int d = 0; d < depth && k < n; d++) {
        int w = f[d].kind == '[' ? snprintf(buf + k, n - k, "[%ld]", f[d].index)
                                 : snprintf(buf + k, n - k, "%s%s", k ? "." : "", f[d].key);
        k += w > 0 ? (size_t)w : 0;
    }
}

/* End (offset of the closing quote) of the string whose opening quote q
 * is at t[i] (json-c takes '...' too). */
static size_t json_string_end(const char *t, size_t i, size_t n)
{
    char q = t[i];
    for (i++; i < n && t[i] != q; i++)
        if (t[i] == '\\') i++;
    return i;
}

/* Every number literal of a JSON text json-c has accepted (t[n] == 0),
 * checked on its own text with drape_units_strtod: the first that
 * overflows, underflows or is denormal (json-c would give inf, 0 or the
 * denormal) is an E_INPUT error at path:line:column with its key path. */
static int json_numbers_in_range(const char *t, size_t n, const char *path, drape_error *err)
{
    json_frame f[JSON_SCAN_DEPTH];
    int depth = 0;
    for (size_t i = skip_blank(t, 0, n); i < n; i = skip_blank(t, i, n)) {
        json_frame *top = depth > 0 && depth <= JSON_SCAN_DEPTH ? &f[depth - 1] : NULL;
        char c = t[i];
        if (c == '{' || c == '[') {
            if (depth < JSON_SCAN_DEPTH)
                f[depth] = (json_frame){.kind = c, .want_key = c == '{', .index = 0, .key = ""};
            depth++, i++;
        } else if (c == '}' || c == ']') {
            depth--, i++;
        } else if (c == ',') {
            if (top && top->kind == '[') top->index++;
            if (top && top->kind == '{') top->want_key = 1;
            i++;
        } else if (c == ':') {
            if (top) top->want_key = 0;
            i++;
        } else if (c == '"' || c == '\'') {
            size_t e = json_string_end(t, i, n);
            if (top && top->kind == '{' && top->want_key)
                snprintf(top->key, sizeof top->key, "%.*s", (int)(e - i - 1), t + i + 1);
            i = e + 1;
        } else if (c == '-' || (c >= '0' && c <= '9')) {
            char *end;
            int range;
            if (c == '-' && !(t[i + 1] >= '0' && t[i + 1] <= '9') && t[i + 1] != '.') {
                i++; /* -Infinity, -NaN: a word follows */
                continue;
            }
            drape_units_strtod(t + i, &end, &range);
            if (range) {
                int line, col;
                char key[DRAPE_ERROR_KEY_MAX];
                line_col(t, i, &line, &col);
                json_key_path(f, depth < JSON_SCAN_DEPTH ? depth : JSON_SCAN_DEPTH, key, sizeof key);
                return drape_error_set(err, DRAPE_E_INPUT, path, line, col, key[0] ? key : NULL,
                                       "number out of range: \"%.*s\" (a magnitude from %.1e to "
                                       "%.1e, or 0)", (int)(end - (t + i)), t + i, DBL_MIN,
                                       DBL_MAX);
            }
            i = end > t + i ? (size_t)(end - t) : i + 1;
        } else {
            i++; /* true, false, null, NaN, Infinity */
        }
    }
    return 0;
}

struct json_object *drape_cli_read_json(const char *path, size_t max, drape_error *err)
{
    return read_json(path, max, 0, err);
}

struct json_object *drape_cli_read_json_in_range(const char *path, size_t max, drape_error *err)
{
    return read_json(path, max, 1, err);
}

/* json-c ends a // comment at LF only, so in a file whose lines end in CR
 * alone (old Mac) a comment ran to the end of the file ("unexpected end of
 * file").  A lone CR that ends a // comment outside strings becomes LF:
 * one byte for one, so every offset stays, and line_col counts both as
 * one break. */
static void comments_end_at_lf(char *t, size_t n)
{
    size_t i = 0;
    while (i < n) {
        if (t[i] == '"' || t[i] == '\'') {
            i = json_string_end(t, i, n) + 1;
        } else if (t[i] == '/' && i + 1 < n && t[i + 1] == '*') {
            const char *e = strstr(t + i + 2, "*/");
            i = e ? (size_t)(e - t) + 2 : n;
        } else if (t[i] == '/' && i + 1 < n && t[i + 1] == '/') {
            while (i < n && t[i] != '\n' && t[i] != '\r') i++;
            if (i < n && line_ends_at(t, i, n)) t[i] = '\n';
        } else {
            i++;
        }
    }
}

static struct json_object *read_json(const char *path, size_t max, int in_range, drape_error *err)
{
    size_t len;
    json_object *root = NULL;
    char *text = drape_cli_read_file(path, max, &len, err);
    if (!text) return NULL;
    if (strlen(text) != len) {
        drape_error_set(err, DRAPE_E_SYNTAX, path, 0, 0, NULL, "NUL byte: not a JSON text file");
        goto out;
    }
    comments_end_at_lf(text, len);
    json_tokener *tok = json_tokener_new_ex(32);
    if (!tok) {
        drape_error_set(err, DRAPE_E_NOMEM, path, 0, 0, NULL, "out of memory");
        goto out;
    }
    root = json_tokener_parse_ex(tok, text, (int)len);
    enum json_tokener_error je = json_tokener_get_error(tok);
    size_t end = json_tokener_get_parse_end(tok);
    json_tokener_free(tok);
    int line, col;
    if (!root || je != json_tokener_success) {
        line_col(text, end, &line, &col);
        drape_error_set(err, DRAPE_E_SYNTAX, path, line, col, NULL, "not valid JSON: %s",
                        je == json_tokener_continue ? "unexpected end of file"
                                                    : json_tokener_error_desc(je));
        json_object_put(root);
        root = NULL;
        goto out;
    }
    size_t rest = skip_blank(text, end, len);
    if (rest < len) {
        line_col(text, rest, &line, &col);
        drape_error_set(err, DRAPE_E_SYNTAX, path, line, col, NULL,
                        "text after the end of the JSON object");
        json_object_put(root);
        root = NULL;
    } else if (in_range && json_numbers_in_range(text, len, path, err) != 0) {
        json_object_put(root);
        root = NULL;
    }
out:
    drape_free(text);
    return root;
}

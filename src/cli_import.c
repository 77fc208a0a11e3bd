/* cli_import.c: `drape import arcsim MATERIAL.json...` and `drape import
 * kes TABLE.csv`: turn a lab's own fabric data into drape fabric files.
 *
 * arcsim: an ARCSim material file (the format in which Wang, O'Brien &
 * Ramamoorthi 2011 published their measured fabrics: `density` kg/m^2,
 * `stretching` 6 x 4 and `bending` 3 x 5 samples) becomes a fabric with
 * piecewise fits, by exactly the mapping used for the shipped *-wang
 * fabrics (docs/fabric-library.md, "The Wang et al. 2011 fabrics"):
 *
 *   weight                 = density                                  (A1)
 *   k_weft = 2 d0, k_warp = 2 d2, d = stretching[0] (zero strain)     (A2)
 *   F(gamma) = d3 gamma, both directions                              (A3)
 *   M(K) = K ke(K) / 4, ke linear in K between the samples of row 0
 *   (warp) or row 2 (weft) at K = 0, 10, 20, 30, 40 1/m, constant
 *   beyond; on [K_i, K_i+1] with s_i = (ke_i+1 - ke_i) / (10 1/m):
 *   poly = [0, (ke_i - s_i K_i) / 4, s_i / 4]; beyond: [0, ke_4 / 4]  (A4)
 *
 * The JSON is read with json-c (comments are accepted, as by ARCSim's
 * JsonCpp reader); every number in it must be a normal double or 0
 * (drape_cli_read_json_in_range: 1e400, 1e-400, 1e-310 refused at
 * file:line:column with their key).
 *
 * kes: a CSV table of KES-F summary values, one fabric per row, becomes
 * one fabric file per row with a `kes:` block (docs/fabrics.md, "KES-F
 * summary values"); the loader builds the curves.
 *
 * Every output is written to a temporary file, loaded back with
 * drape_fabric_load, and only then renamed into place; if any input is
 * bad, no file is written (docs/batch.md, "Importers"). */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <stdint.h>
#include <sys/stat.h>
#include <unistd.h>

#include <json-c/json.h>

#include "cli.h"
#include "cli_io.h"
#include "drape/alloc.h"
#include "drape/units.h"
#include "drape/fabric.h"

static const char import_usage[] =
    "Usage: drape import arcsim MATERIAL.json... [OPTIONS]\n"
    "       drape import kes TABLE.csv [OPTIONS]\n"
    "\n"
    "Write drape fabric files (YAML) from other formats:\n"
    "  arcsim   ARCSim material files (Wang et al. 2011 measured data:\n"
    "           density kg/m^2, stretching 6x4, bending 3x5 N.m); one fabric\n"
    "           per file, named after the file (docs/fabric-library.md)\n"
    "  kes      a CSV table of KES-F summary values, one fabric per row;\n"
    "           columns: name, weight_g_m2, k_warp_N_m, k_weft_N_m,\n"
    "           B_warp, B_weft (gf.cm^2/cm), 2HB_warp, 2HB_weft (gf.cm/cm),\n"
    "           G_warp, G_weft (gf/cm/deg), 2HG_warp, 2HG_weft (gf/cm),\n"
    "           optional 2HG5_warp, 2HG5_weft (gf/cm), description, source\n"
    "\n"
    "Options:\n"
    "  --out-dir DIR    write the files into DIR (default: the current directory)\n"
    "  --name NAME      fabric name (arcsim, one input file only)\n"
    "  --force          replace existing files\n"
    "  -h, --help       show this help\n"
    "\n"
    "Each file is checked by loading it before it is put in place; if any\n"
    "input is invalid, nothing is written.  The paths written are printed on\n"
    "stdout.  Exit status: 0 success, 1 invalid input, 2 bad command line,\n"
    "3 I/O error.\n";

#define IMPORT_MAX_INPUT (4L * 1024 * 1024) /* bytes of one input file */
#define IMPORT_NAME_MAX 100                 /* fabric names (and file names) */
#define IMPORT_TEXT_MAX 3000                /* description / source from input */
#define IMPORT_PATH_MAX 4096

/* One output: its text is written to a temporary file at once, committed
 * at the end. */
typedef struct output {
    drape_cli_afile a;
    char label[IMPORT_PATH_MAX]; /* "FILE" or "FILE:LINE" for messages */
    char name[IMPORT_NAME_MAX + 1];
} output;

typedef struct importer {
    const char *dir;
    int force;
    output *out;
    int n, cap;
    drape_error first; /* first error: sets the exit status */
    int n_err;
} importer;

static void report(importer *im, const drape_error *e)
{
    drape_cli_print_error(e);
    if (im->n_err++ == 0) im->first = *e;
}

/* ---- YAML text helpers ---------------------------------------------------- */

/* Polynomial coefficients: 12 significant digits.  They are sums and
 * quotients of the input samples (6 to 9 digits in the Wang files), so this
 * drops only rounding noise (relative 1e-12 at most), far below the
 * loader's 1e-6 continuity tolerance. */
static void fmt_coef(char *buf, size_t n, double v)
{
    snprintf(buf, n, "%.12g", v);
}

/* Shortest %g that reads back to the same double (numbers copied from
 * the input). */
static void fmt_num(char *buf, size_t n, double v)
{
    for (int prec = 15; prec <= 17; prec++) {
        snprintf(buf, n, "%.*g", prec, v);
        if (strtod(buf, NULL) == v) return;
    }
}

/* Length of the valid UTF-8 sequence at c (1-4), or 0 where the byte there
 * does not start one (RFC 3629: no overlong forms, no surrogates, at most
 * U+10FFFF). */
static int utf8_len(const unsigned char *c)
{
    if (c[0] < 0x80) return 1;
    int n = c[0] >= 0xc2 && c[0] <= 0xdf ? 2 : c[0] >= 0xe0 && c[0] <= 0xef ? 3
            : c[0] >= 0xf0 && c[0] <= 0xf4 ? 4 : 0;
    for (int k = 1; k < n; k++)
        if ((c[k] & 0xc0) != 0x80) return 0;
    if ((c[0] == 0xe0 && c[1] < 0xa0) || (c[0] == 0xed && c[1] > 0x9f) ||
        (c[0] == 0xf0 && c[1] < 0x90) || (c[0] == 0xf4 && c[1] > 0x8f))
        return 0;
    return n;
}

static int utf8_valid(const char *s)
{
    for (const unsigned char *c = (const unsigned char *)s; *c;) {
        int n = utf8_len(c);
        if (!n) return 0;
        c += n;
    }
    return 1;
}

/* YAML double-quoted scalar; a byte that is not UTF-8 (a file name's, say)
 * as \xHH (YAML reads it as the code point U+00HH). */
static void put_quoted(FILE *f, const char *s)
{
    fputc('"', f);
    for (const unsigned char *c = (const unsigned char *)s; *c;) {
        int n = utf8_len(c);
        if (*c == '"' || *c == '\\') fprintf(f, "\\%c", *c);
        else if (*c == '\n') fputs("\\n", f);
        else if (*c == '\t') fputs("\\t", f);
        else if (*c < 0x20 || *c == 0x7f || n == 0) fprintf(f, "\\x%02x", *c);
        else fwrite(c, 1, (size_t)n, f);
        c += n ? n : 1;
    }
    fputc('"', f);
}

/* Text for a comment line: control characters and bytes that are not
 * UTF-8 as '?'. */
static void put_comment_text(FILE *f, const char *s)
{
    for (const unsigned char *c = (const unsigned char *)s; *c;) {
        int n = utf8_len(c);
        if (*c < 0x20 || *c == 0x7f || n == 0) fputc('?', f);
        else fwrite(c, 1, (size_t)n, f);
        c += n ? n : 1;
    }
}

/* 1 for an integer that json-c clamped to its 64-bit range when it parsed
 * it (99999999999999999999999 reads as 2^64 - 1 and -1e23 as -2^63): the
 * number in the file is not the one it holds. */
static int json_int_clamped(json_object *v)
{
    if (!json_object_is_type(v, json_type_int)) return 0;
    int64_t i = json_object_get_int64(v);
    return i == INT64_MAX || i == INT64_MIN || json_object_get_uint64(v) == UINT64_MAX;
}

static const char *base_name(const char *path)
{
    const char *b = strrchr(path, '/');
    return b ? b + 1 : path;
}

/* A fabric name is also a file name: letters, digits, '.', '_', '-', not
 * starting with '.' or '-'. */
static int name_ok(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n > IMPORT_NAME_MAX || s[0] == '.' || s[0] == '-') return 0;
    for (size_t i = 0; i < n; i++) {
        char c = s[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
              (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-'))
            return 0;
    }
    return 1;
}

/* ---- outputs ----------------------------------------------------------------- */

/* Start an output DIR/NAME.yaml; the caller writes into o->a.f and then
 * calls finish_output.  NULL (error reported) if the file exists (without
 * --force), the name is taken by an earlier output, or it cannot be
 * created. */
static output *start_output(importer *im, const char *name, const char *label,
                            const char *efile, int eline, const char *ekey)
{
    char path[IMPORT_PATH_MAX];
    drape_error e;
    drape_error_clear(&e);
    for (int i = 0; i < im->n; i++)
        if (strcmp(im->out[i].name, name) == 0) {
            drape_error_set(&e, DRAPE_E_INPUT, efile, eline, 0, ekey,
                            "fabric `%s` is also made from %s; names must be unique",
                            name, im->out[i].label);
            report(im, &e);
            return NULL;
        }
    if (snprintf(path, sizeof path, "%s/%s.yaml", im->dir, name) >= (int)sizeof path) {
        drape_error_set(&e, DRAPE_E_IO, im->dir, 0, 0, NULL, "path too long");
        report(im, &e);
        return NULL;
    }
    struct stat st;
    if (lstat(path, &st) == 0 && (!im->force || !S_ISREG(st.st_mode))) {
        /* --force replaces files, never a directory, link or device: all
         * outputs are checked before any is written */
        drape_error_set(&e, DRAPE_E_IO, path, 0, 0, NULL,
                        S_ISREG(st.st_mode) ? "exists (made from %s); use --force to replace it"
                                            : "exists and is not a regular file (made from %s); "
                                              "not replaced",
                        label);
        report(im, &e);
        return NULL;
    }
    if (im->n == im->cap) {
        int nc = im->cap ? im->cap * 2 : 8;
        output *no = drape_realloc(im->out, (size_t)nc * sizeof *no);
        if (!no) {
            drape_error_set(&e, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
            report(im, &e);
            return NULL;
        }
        im->out = no, im->cap = nc;
    }
    output *o = &im->out[im->n];
    memset(o, 0, sizeof *o);
    snprintf(o->label, sizeof o->label, "%s", label);
    snprintf(o->name, sizeof o->name, "%s", name);
    if (drape_cli_afile_open(&o->a, path, &e) != 0) {
        report(im, &e);
        return NULL;
    }
    im->n++;
    return o;
}

/* Flush the output and load it back as a fabric; on failure remove it and
 * report at (efile, eline). */
static int finish_output(importer *im, output *o, const char *efile, int eline)
{
    drape_error e, le;
    drape_error_clear(&e);
    drape_error_clear(&le);
    drape_fabric f;
    if (fflush(o->a.f) != 0 || ferror(o->a.f)) {
        drape_error_set(&e, DRAPE_E_IO, o->a.tmp, 0, 0, NULL, "cannot write: %s", strerror(errno));
    } else if (drape_fabric_load(o->a.tmp, &f, &le, NULL, NULL) != 0) {
        char buf[1024];
        le.file[0] = 0; /* the temporary's name means nothing to the user */
        drape_error_set(&e, le.kind == DRAPE_E_NOMEM ? DRAPE_E_NOMEM : DRAPE_E_INPUT,
                        efile, eline, 0, NULL, "the fabric made from it does not load: %s",
                        drape_error_format(&le, buf, sizeof buf));
    }
    if (e.kind == DRAPE_OK) return 0;
    report(im, &e);
    drape_cli_afile_abort(&o->a);
    im->n--; /* o is the last output */
    return -1;
}

/* ---- arcsim ------------------------------------------------------------------ */

/* Bending samples of ARCSim (docs/fabric-library.md, "Curvature scale"):
 * ke is given at K = 0, 10, 20, 30, 40 1/m and clamped beyond. */
#define ARC_NK 5
#define ARC_DK 10.0 /* 1/m between samples */

typedef struct arcsim_mat {
    double density;
    double stretch[6][4];
    double bend[3][ARC_NK];
} arcsim_mat;

static const char *json_type_word(json_object *v)
{
    switch (json_object_get_type(v)) {
    case json_type_null: return "null";
    case json_type_boolean: return "a boolean";
    case json_type_double:
    case json_type_int: return "a number";
    case json_type_object: return "an object";
    case json_type_array: return "an array";
    case json_type_string: return "a string";
    }
    return "something else";
}

/* rows x cols matrix of finite numbers at key; out[r * cols + c]. */
static int json_matrix(json_object *root, const char *key, int rows, int cols,
                       double *out, const char *file, drape_error *e)
{
    json_object *m;
    char kp[64];
    if (!json_object_object_get_ex(root, key, &m))
        return drape_error_set(e, DRAPE_E_INPUT, file, 0, 0, key, "missing key");
    if (!json_object_is_type(m, json_type_array) || (int)json_object_array_length(m) != rows)
        return drape_error_set(e, DRAPE_E_INPUT, file, 0, 0, key,
                               "expected an array of %d rows of %d numbers, got %s%s",
                               rows, cols, json_type_word(m),
                               json_object_is_type(m, json_type_array) ? " of another length" : "");
    for (int r = 0; r < rows; r++) {
        json_object *row = json_object_array_get_idx(m, (size_t)r);
        snprintf(kp, sizeof kp, "%s[%d]", key, r);
        if (!json_object_is_type(row, json_type_array) || (int)json_object_array_length(row) != cols)
            return drape_error_set(e, DRAPE_E_INPUT, file, 0, 0, kp,
                                   "expected an array of %d numbers, got %s%s", cols,
                                   json_type_word(row),
                                   json_object_is_type(row, json_type_array) ? " of another length" : "");
        for (int c = 0; c < cols; c++) {
            json_object *v = json_object_array_get_idx(row, (size_t)c);
            snprintf(kp, sizeof kp, "%s[%d][%d]", key, r, c);
            if (!json_object_is_type(v, json_type_double) && !json_object_is_type(v, json_type_int))
                return drape_error_set(e, DRAPE_E_INPUT, file, 0, 0, kp,
                                       "expected a number, got %s", json_type_word(v));
            double x = json_object_get_double(v);
            if (!isfinite(x) || json_int_clamped(v))
                return drape_error_set(e, DRAPE_E_INPUT, file, 0, 0, kp,
                                       "expected a finite number%s",
                                       isfinite(x) ? " (this integer is out of range)" : "");
            out[r * cols + c] = x;
        }
    }
    return 0;
}

static int arcsim_read(const char *path, arcsim_mat *m, drape_error *e)
{
    int rc = -1;
    json_object *v;
    json_object *root = drape_cli_read_json_in_range(path, IMPORT_MAX_INPUT, e);
    if (!root) return -1;
    if (!json_object_is_type(root, json_type_object)) {
        drape_error_set(e, DRAPE_E_INPUT, path, 0, 0, NULL,
                        "expected a JSON object with density, stretching and bending, got %s",
                        json_type_word(root));
        goto out;
    }
    if (!json_object_object_get_ex(root, "density", &v)) {
        drape_error_set(e, DRAPE_E_INPUT, path, 0, 0, "density", "missing key");
        goto out;
    }
    if (!json_object_is_type(v, json_type_double) && !json_object_is_type(v, json_type_int)) {
        drape_error_set(e, DRAPE_E_INPUT, path, 0, 0, "density",
                        "expected a number (kg/m^2), got %s", json_type_word(v));
        goto out;
    }
    m->density = json_object_get_double(v);
    if (json_int_clamped(v)) {
        drape_error_set(e, DRAPE_E_INPUT, path, 0, 0, "density",
                        "this integer is out of range");
        goto out;
    }
    if (!(m->density > 0) || !isfinite(m->density)) {
        drape_error_set(e, DRAPE_E_INPUT, path, 0, 0, "density",
                        "must be a positive areal density (kg/m^2), got %g", m->density);
        goto out;
    }
    if (json_matrix(root, "stretching", 6, 4, &m->stretch[0][0], path, e) != 0) goto out;
    if (json_matrix(root, "bending", 3, ARC_NK, &m->bend[0][0], path, e) != 0) goto out;
    static const char *const what[4] = {"k_u/2 (tension along u)", "coupling",
                                        "k_v/2 (tension along v)", "shear stiffness"};
    for (int c = 0; c < 4; c++) {
        if (c == 1) continue; /* the Poisson-type coupling is dropped, any sign */
        if (!(m->stretch[0][c] > 0)) {
            char kp[32];
            snprintf(kp, sizeof kp, "stretching[0][%d]", c);
            drape_error_set(e, DRAPE_E_INPUT, path, 0, 0, kp,
                            "%s must be positive, got %g", what[c], m->stretch[0][c]);
            goto out;
        }
    }
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < ARC_NK; c++)
            if (!(m->bend[r][c] > 0)) {
                char kp[32];
                snprintf(kp, sizeof kp, "bending[%d][%d]", r, c);
                drape_error_set(e, DRAPE_E_INPUT, path, 0, 0, kp,
                                "bending stiffness ke must be positive (N.m), got %g",
                                m->bend[r][c]);
                goto out;
            }
    rc = 0;
out:
    json_object_put(root);
    return rc;
}

/* Bending pieces (A4) of one row: knots K_i = i * ARC_DK. */
static void arcsim_pieces(const double ke[ARC_NK], double c1[ARC_NK], double c2[ARC_NK])
{
    for (int i = 0; i + 1 < ARC_NK; i++) {
        double K = i * ARC_DK, s = (ke[i + 1] - ke[i]) / ARC_DK;
        c1[i] = (ke[i] - s * K) / 4.0;
        c2[i] = s / 4.0;
    }
    c1[ARC_NK - 1] = ke[ARC_NK - 1] / 4.0;
    c2[ARC_NK - 1] = 0.0;
}

static void arcsim_write_fit(FILE *f, const double ke[ARC_NK])
{
    double c1[ARC_NK], c2[ARC_NK];
    char a[40], b[40];
    arcsim_pieces(ke, c1, c2);
    for (int i = 0; i < ARC_NK; i++) {
        fmt_coef(a, sizeof a, c1[i]);
        if (i + 1 < ARC_NK) {
            fmt_coef(b, sizeof b, c2[i]);
            fprintf(f, "    - {from: %g, to: %g, poly: [0, %s, %s]}\n", i * ARC_DK,
                    (i + 1) * ARC_DK, a, b);
        } else {
            fprintf(f, "    - {from: %g, poly: [0, %s]}\n", i * ARC_DK, a);
        }
    }
}

/* "# Caution" lines: intervals where dM/dK < 0.  On piece i, dM/dK =
 * c1 + 2 c2 K is linear in K: negative somewhere iff at an end. */
static int arcsim_softening(FILE *f, const char *dir, const double ke[ARC_NK])
{
    double c1[ARC_NK], c2[ARC_NK];
    int any = 0;
    arcsim_pieces(ke, c1, c2);
    for (int i = 0; i + 1 < ARC_NK; i++) {
        double K0 = i * ARC_DK, K1 = K0 + ARC_DK;
        if (c1[i] + 2 * c2[i] * K0 < 0 || c1[i] + 2 * c2[i] * K1 < 0) {
            if (f) {
                fprintf(f, "#   %s: dM/dK < 0 somewhere on [%g, %g] 1/m (M at the knots:", dir, K0, K1);
                for (int k = 0; k < ARC_NK; k++)
                    fprintf(f, "%s %.3g", k ? "," : "", k * ARC_DK * ke[k] / 4.0);
                fputs(" N.m/m)\n", f);
            }
            any = 1;
        }
    }
    return any;
}

static void arcsim_write(FILE *f, const char *name, const char *path, const arcsim_mat *m)
{
    char w[40], kw[40], kf[40], G[40];
    const char *file = base_name(path);
    fmt_num(w, sizeof w, m->density);
    fmt_num(kw, sizeof kw, 2.0 * m->stretch[0][2]);
    fmt_num(kf, sizeof kf, 2.0 * m->stretch[0][0]);
    fmt_num(G, sizeof G, m->stretch[0][3]);
    fprintf(f, "# %s: ARCSim material file ", name);
    put_comment_text(f, file);
    fputs(", converted by `drape import arcsim`.\n"
          "# Conversion (from ARCSim's code, docs/fabric-library.md), as for the\n"
          "# shipped *-wang fabrics:\n"
          "#   weight            = density (kg/m^2, used as mass per area by ARCSim)\n"
          "#   tensile_stiffness = 2 x stretching[0][0] (u, taken as weft) and\n"
          "#                       2 x stretching[0][2] (v, taken as warp), N/m;\n"
          "#                       stretching[0] is the zero-strain sample\n"
          "#   shear             = F = G gamma, G = stretching[0][3] N/m per rad\n"
          "#   bending           = M(K) = K ke(K) / 4, ke the bending table row for\n"
          "#                       hinges along u (row 0: warp bent) or v (row 2:\n"
          "#                       weft bent), linear in K between K = 0,10,20,30,40 1/m,\n"
          "#                       constant beyond 40 1/m (ARCSim clamps). Each piece is\n"
          "#                       [0, (ke_i - s_i K_i)/4, s_i/4], s_i = dke/dK on it.\n"
          "#                       bias: the same through row 1 (hinges at 45 degrees)\n"
          "#   The pieces meet in value but not in slope: loading this file\n"
          "#   warns about slope jumps at the knots.\n", f);
    static const char *const rowname[3] = {"warp (row 0)", "bias (row 1)", "weft (row 2)"};
    fputs("# Table rows (N.m):\n", f);
    for (int r = 0; r < 3; r++) {
        fprintf(f, "#   %s:", rowname[r]);
        for (int k = 0; k < ARC_NK; k++) {
            char t[40];
            fmt_num(t, sizeof t, m->bend[r][k]);
            fprintf(f, " %s", t);
        }
        fputc('\n', f);
    }
    if (arcsim_softening(NULL, "", m->bend[0]) || arcsim_softening(NULL, "", m->bend[1]) ||
        arcsim_softening(NULL, "", m->bend[2])) {
        fputs("# Caution: the measured table softens at large curvature, so the moment\n"
              "# falls with curvature over part of the range (negative tangent stiffness):\n", f);
        arcsim_softening(f, "warp", m->bend[0]);
        arcsim_softening(f, "weft", m->bend[2]);
        arcsim_softening(f, "bias", m->bend[1]);
    }
    fprintf(f, "fabric: %s\n", name);
    fputs("description: ", f);
    char d[IMPORT_PATH_MAX + 200];
    snprintf(d, sizeof d, "ARCSim material %s (the data format of Wang et al. 2011), "
             "converted by drape import arcsim", file);
    put_quoted(f, d);
    fputs("\nsource: ", f);
    snprintf(d, sizeof d,
             "Numbers: ARCSim material file %s. Format and meaning: Wang H, O'Brien JF, "
             "Ramamoorthi R (2011) Data-driven elastic models for cloth: modeling and "
             "measurement. ACM Trans Graph 30(4):71; ARCSim (Narain, Samii, O'Brien 2012) "
             "src/conf.cpp, dde.cpp, physics.cpp. weight = density; u = weft, v = warp "
             "(assumed); k_weft = 2*stretching[0][0], k_warp = 2*stretching[0][2]; shear "
             "F = G*gamma, G = stretching[0][3]; bending M(K) = K*ke(K)/4 through "
             "bending[0] (warp), bending[1] (bias) and bending[2] (weft) at K = "
             "0,10,20,30,40 1/m, constant beyond. Assumed: the u/v to weft/warp mapping, "
             "the factor 1/4, dropped Poisson coupling stretching[0][1] and the nonlinear "
             "rows 1-5. See "
             "docs/fabric-library.md.", file);
    put_quoted(f, d);
    fprintf(f, "\nweight: %s kg/m^2\n", w);
    fprintf(f, "tensile_stiffness: {warp: %s N/m, weft: %s N/m}   # 2 x stretching[0][2], "
               "2 x stretching[0][0]; v = warp assumed\n", kw, kf);
    fputs("bending:\n  units: {curvature: 1/m, moment: N.m/m}\n", f);
    fputs("  warp:   # bending[0]: hinges along u, warp yarns bent; factor 1/4 assumed\n", f);
    arcsim_write_fit(f, m->bend[0]);
    fputs("  weft:   # bending[2]: hinges along v, weft yarns bent; factor 1/4 assumed\n", f);
    arcsim_write_fit(f, m->bend[2]);
    /* the model's bias term needs B_bias >= (B_warp + B_weft) / 4 */
    if (m->bend[1][0] >= 0.25 * (m->bend[0][0] + m->bend[2][0])) {
        fputs("  bias:   # bending[1]: hinges at 45 degrees, a strip cut on the bias; factor "
              "1/4 assumed\n", f);
        arcsim_write_fit(f, m->bend[1]);
    } else {
        fputs("  # bias: left out: bending[1][0] is below (bending[0][0] + bending[2][0]) / 4,\n"
              "  # softer than the warp and weft hinges alone make a strip cut at 45 degrees\n"
              "  # (drape's bias term adds a twist rigidity, which cannot be negative)\n", f);
    }
    fputs("shear:\n  units: {angle: rad, force: N/m}\n", f);
    fprintf(f, "  warp:   # G = stretching[0][3]; ARCSim has one shear term for both directions\n"
               "    - {from: 0, poly: [0, %s]}\n  weft:\n    - {from: 0, poly: [0, %s]}\n", G, G);
}

static void import_arcsim(importer *im, int nfiles, char **files, const char *name_opt)
{
    for (int i = 0; i < nfiles; i++) {
        const char *path = files[i];
        drape_error e;
        drape_error_clear(&e);
        arcsim_mat m;
        if (arcsim_read(path, &m, &e) != 0) {
            report(im, &e);
            continue;
        }
        char name[IMPORT_NAME_MAX + 1];
        if (name_opt) {
            snprintf(name, sizeof name, "%s", name_opt);
        } else {
            const char *b = base_name(path);
            size_t n = strlen(b);
            if (n > 5 && strcasecmp(b + n - 5, ".json") == 0) n -= 5;
            if (n > IMPORT_NAME_MAX) n = IMPORT_NAME_MAX;
            for (size_t k = 0; k < n; k++) {
                char c = b[k];
                int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                         (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
                name[k] = ok ? c : '-';
            }
            name[n] = 0;
            if (!name_ok(name)) {
                drape_error_set(&e, DRAPE_E_USAGE, path, 0, 0, NULL,
                                "cannot make a fabric name from this file name; use --name");
                report(im, &e);
                continue;
            }
        }
        output *o = start_output(im, name, path, path, 0, NULL);
        if (!o) continue;
        arcsim_write(o->a.f, name, path, &m);
        finish_output(im, o, path, 0);
    }
}

/* ---- kes --------------------------------------------------------------------- */

enum kes_col {
    K_NAME, K_WEIGHT, K_KWARP, K_KWEFT, K_BWARP, K_BWEFT, K_HBWARP, K_HBWEFT,
    K_GWARP, K_GWEFT, K_HGWARP, K_HGWEFT, K_HG5WARP, K_HG5WEFT, K_DESC, K_SOURCE,
    K_NCOL
};

static const struct kes_column {
    const char *name;
    const char *unit;     /* accepted as "name (unit)"; NULL: text */
    const char *yunit;    /* unit written to the YAML */
    int required;
    int positive;         /* > 0, else >= 0 */
} kes_cols[K_NCOL] = {
    {"name", NULL, NULL, 1, 0},
    {"weight_g_m2", "g/m^2", "g/m^2", 1, 1},
    {"k_warp_N_m", "N/m", "N/m", 1, 1},
    {"k_weft_N_m", "N/m", "N/m", 1, 1},
    {"B_warp", "gf.cm^2/cm", "gf.cm^2/cm", 1, 1},
    {"B_weft", "gf.cm^2/cm", "gf.cm^2/cm", 1, 1},
    {"2HB_warp", "gf.cm/cm", "gf.cm/cm", 0, 0},
    {"2HB_weft", "gf.cm/cm", "gf.cm/cm", 0, 0},
    {"G_warp", "gf/cm/deg", "gf/cm/deg", 1, 1},
    {"G_weft", "gf/cm/deg", "gf/cm/deg", 1, 1},
    {"2HG_warp", "gf/cm", "gf/cm", 0, 0},
    {"2HG_weft", "gf/cm", "gf/cm", 0, 0},
    {"2HG5_warp", "gf/cm", "gf/cm", 0, 0},
    {"2HG5_weft", "gf/cm", "gf/cm", 0, 0},
    {"description", NULL, NULL, 0, 0},
    {"source", NULL, NULL, 0, 0},
};

/* Trim blanks in place. */
static char *trim(char *s)
{
    while (*s == ' ' || *s == '\t') s++;
    size_t n = strlen(s);
    while (n && (s[n - 1] == ' ' || s[n - 1] == '\t')) s[--n] = 0;
    return s;
}

/* A plain decimal number: [+-]digits[.digits][(e|E)[+-]digits] (at least
 * one digit in the mantissa); written to the YAML as it is. */
static int plain_number(const char *s)
{
    const char *c = s;
    int digits = 0;
    if (*c == '+' || *c == '-') c++;
    while (*c >= '0' && *c <= '9') c++, digits++;
    if (*c == '.') {
        c++;
        while (*c >= '0' && *c <= '9') c++, digits++;
    }
    if (!digits) return 0;
    if (*c == 'e' || *c == 'E') {
        c++;
        if (*c == '+' || *c == '-') c++;
        if (!(*c >= '0' && *c <= '9')) return 0;
        while (*c >= '0' && *c <= '9') c++;
    }
    return *c == 0;
}

/* Map the header onto kes_cols: colidx[k] = field index or -1. */
static int kes_header(const drape_cli_csv_rec *h, int colidx[K_NCOL], const char *file,
                      drape_error *e)
{
    for (int k = 0; k < K_NCOL; k++) colidx[k] = -1;
    for (int i = 0; i < h->n; i++) {
        char *t = trim(h->field[i]);
        char *par = strchr(t, '(');
        const char *unit = NULL;
        if (par) { /* "B_warp (gf.cm^2/cm)" */
            char *close = strchr(par, ')');
            if (!close || close[1]) {
                return drape_error_set(e, DRAPE_E_INPUT, file, h->line, h->col[i], t,
                                       "expected `name` or `name (unit)`");
            }
            *close = 0;
            unit = trim(par + 1);
            *par = 0;
            t = trim(t);
        }
        int k = 0;
        while (k < K_NCOL && strcasecmp(t, kes_cols[k].name) != 0) k++;
        if (k == K_NCOL) {
            char list[512] = "";
            for (int j = 0; j < K_NCOL; j++) {
                strcat(list, j ? ", " : "");
                strcat(list, kes_cols[j].name);
            }
            return drape_error_set(e, DRAPE_E_INPUT, file, h->line, h->col[i], t,
                                   "unknown column; the columns are %s", list);
        }
        if (colidx[k] >= 0)
            return drape_error_set(e, DRAPE_E_INPUT, file, h->line, h->col[i], t,
                                   "column given twice");
        if (unit && (!kes_cols[k].unit || strcmp(unit, kes_cols[k].unit) != 0))
            return drape_error_set(e, DRAPE_E_INPUT, file, h->line, h->col[i], t,
                                   "unit `%s`: this column is %s%s", unit,
                                   kes_cols[k].unit ? "in " : "text",
                                   kes_cols[k].unit ? kes_cols[k].unit : "");
        colidx[k] = i;
    }
    for (int k = 0; k < K_NCOL; k++)
        if (kes_cols[k].required && colidx[k] < 0)
            return drape_error_set(e, DRAPE_E_INPUT, file, h->line, 0, kes_cols[k].name,
                                   "missing column");
    return 0;
}

/* Validate one row and write its fabric. */
static void kes_row(importer *im, const char *file, const drape_cli_csv_rec *r,
                    const int colidx[K_NCOL])
{
    drape_error e;
    drape_error_clear(&e);
    char *cell[K_NCOL];
    double v[K_NCOL];
    for (int k = 0; k < K_NCOL; k++) {
        cell[k] = colidx[k] >= 0 ? trim(r->field[colidx[k]]) : NULL;
        if (cell[k] && !cell[k][0]) cell[k] = NULL; /* empty cell: absent */
        v[k] = NAN;
    }
#define ROW_ERR(k, ...)                                                                     \
    do {                                                                                    \
        drape_error_set(&e, DRAPE_E_INPUT, file, r->line,                                   \
                        colidx[k] >= 0 ? r->col[colidx[k]] : 0, kes_cols[k].name, __VA_ARGS__); \
        report(im, &e);                                                                     \
        return;                                                                             \
    } while (0)
    for (int k = 0; k < K_NCOL; k++) {
        if (!cell[k]) {
            if (kes_cols[k].required) ROW_ERR(k, "empty; this column is required");
            continue;
        }
        if (!kes_cols[k].unit) {
            if (strlen(cell[k]) > IMPORT_TEXT_MAX)
                ROW_ERR(k, "longer than %d bytes", IMPORT_TEXT_MAX);
            if (!utf8_valid(cell[k])) ROW_ERR(k, "not valid UTF-8 (save the table as UTF-8)");
            continue;
        }
        if (!plain_number(cell[k])) ROW_ERR(k, "expected a number in %s, got \"%s\"",
                                            kes_cols[k].unit, cell[k]);
        int range;
        v[k] = drape_units_strtod(cell[k], NULL, &range);
        if (range)
            ROW_ERR(k, "number out of range: %s", cell[k]);
        if (kes_cols[k].positive ? !(v[k] > 0) : !(v[k] >= 0))
            ROW_ERR(k, "must be %s, got %s", kes_cols[k].positive ? "positive" : "non-negative",
                    cell[k]);
    }
    if (!name_ok(cell[K_NAME]))
        ROW_ERR(K_NAME, "\"%s\" is not usable as a fabric and file name (letters, digits, "
                "'.', '_', '-', at most %d, not starting with '.' or '-')",
                cell[K_NAME], IMPORT_NAME_MAX);
    for (int d = 0; d < 2; d++) {
        int hg = d ? K_HGWEFT : K_HGWARP, hg5 = d ? K_HG5WEFT : K_HG5WARP;
        if (cell[hg5] && !(cell[hg] && v[hg] > 0))
            ROW_ERR(hg5, "2HG5 needs a positive 2HG in the same direction");
        if (cell[hg5] && v[hg5] < v[hg])
            ROW_ERR(hg5, "2HG5 (hysteresis at 5 deg) is smaller than 2HG (at 0.5 deg); "
                    "the construction needs 2HG5 >= 2HG");
    }
#undef ROW_ERR
    char label[IMPORT_PATH_MAX];
    snprintf(label, sizeof label, "%s:%d", file, r->line);
    output *o = start_output(im, cell[K_NAME], label, file, r->line, "name");
    if (!o) return;
    FILE *f = o->a.f;
    fprintf(f, "# %s: KES-F summary values from ", cell[K_NAME]);
    put_comment_text(f, label);
    fputs(", converted by `drape import kes`.\n"
          "# The bending and shear curves are built from B, 2HB, G, 2HG (2HG5) by\n"
          "# drape's KES construction (docs/fabrics.md, \"KES-F summary values\").\n", f);
    fprintf(f, "fabric: %s\n", cell[K_NAME]);
    if (cell[K_DESC]) {
        fputs("description: ", f);
        put_quoted(f, cell[K_DESC]);
        fputc('\n', f);
    }
    char src[IMPORT_TEXT_MAX + IMPORT_PATH_MAX + 64];
    snprintf(src, sizeof src, "%s%sKES-F summary values from %s, converted by drape import kes.",
             cell[K_SOURCE] ? cell[K_SOURCE] : "", cell[K_SOURCE] ? "\n" : "", label);
    fputs("source: ", f);
    put_quoted(f, src);
    fputc('\n', f);
    fprintf(f, "weight: %s g/m^2\nk_warp: %s N/m\nk_weft: %s N/m\nkes:\n", cell[K_WEIGHT],
            cell[K_KWARP], cell[K_KWEFT]);
    for (int d = 0; d < 2; d++) {
        static const int cols[2][5] = {{K_BWARP, K_HBWARP, K_GWARP, K_HGWARP, K_HG5WARP},
                                       {K_BWEFT, K_HBWEFT, K_GWEFT, K_HGWEFT, K_HG5WEFT}};
        static const char *const key[5] = {"B", "2HB", "G", "2HG", "2HG5"};
        fprintf(f, "  %s: {", d ? "weft" : "warp");
        int first = 1;
        for (int j = 0; j < 5; j++) {
            int k = cols[d][j];
            if (!cell[k]) continue;
            fprintf(f, "%s%s: %s %s", first ? "" : ", ", key[j], cell[k], kes_cols[k].yunit);
            first = 0;
        }
        fputs("}\n", f);
    }
    finish_output(im, o, file, r->line);
}

static void import_kes(importer *im, const char *file)
{
    drape_error e;
    drape_error_clear(&e);
    size_t len;
    char *text = drape_cli_read_file(file, IMPORT_MAX_INPUT, &len, &e);
    drape_cli_csv_pos p = {0, 0, 0};
    drape_cli_csv_rec h = {0, NULL, NULL, 0}, r = {0, NULL, NULL, 0};
    int colidx[K_NCOL], got, rows = 0;
    if (!text) goto fail;
    if (strlen(text) != len) {
        drape_error_set(&e, DRAPE_E_SYNTAX, file, 0, 0, NULL, "NUL byte: not a CSV text file");
        goto fail;
    }
    /* header: the first record that is not a blank line */
    while ((got = drape_cli_csv_next(text, len, &p, &h, file, &e)) == 1 && h.n == 1 &&
           !trim(h.field[0])[0])
        drape_cli_csv_rec_free(&h);
    if (got < 0) goto fail;
    if (got == 0) {
        drape_error_set(&e, DRAPE_E_INPUT, file, 0, 0, NULL, "empty table: expected a header "
                        "line and one row per fabric");
        goto fail;
    }
    if (kes_header(&h, colidx, file, &e) != 0) goto fail;
    while ((got = drape_cli_csv_next(text, len, &p, &r, file, &e)) == 1) {
        /* a blank line, or a row of empty cells (spreadsheets save those) */
        int blank = 1;
        for (int k = 0; k < r.n && blank; k++) blank = !trim(r.field[k])[0];
        if (blank) {
            drape_cli_csv_rec_free(&r);
            continue;
        }
        rows++;
        if (r.n != h.n) {
            drape_error e2;
            drape_error_clear(&e2);
            drape_error_set(&e2, DRAPE_E_INPUT, file, r.line, 0, NULL,
                            "%d fields, the header has %d", r.n, h.n);
            report(im, &e2);
        } else {
            kes_row(im, file, &r, colidx);
        }
        drape_cli_csv_rec_free(&r);
    }
    if (got < 0) goto fail;
    if (rows == 0) {
        drape_error_set(&e, DRAPE_E_INPUT, file, 0, 0, NULL, "no rows after the header");
        goto fail;
    }
    goto out;
fail:
    report(im, &e);
out:
    drape_cli_csv_rec_free(&h);
    drape_cli_csv_rec_free(&r);
    drape_free(text);
}

/* ---- command ------------------------------------------------------------------ */

static int usage_error(const char *fmt, const char *a)
{
    fputs("drape: import: ", stderr);
    fprintf(stderr, fmt, a);
    fputs("\nTry `drape import --help'.\n", stderr);
    return drape_error_exit_status(DRAPE_E_USAGE);
}

int drape_cli_import(int argc, char **argv)
{
    enum { O_OUTDIR = 1000, O_NAME, O_FORCE };
    static const struct option opts[] = {
        {"out-dir", required_argument, NULL, O_OUTDIR},
        {"name", required_argument, NULL, O_NAME},
        {"force", no_argument, NULL, O_FORCE},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0}};
    importer im;
    memset(&im, 0, sizeof im);
    im.dir = ".";
    const char *name = NULL;
    int c;
    if ((c = drape_cli_args_unambiguous(argc, argv, "h", opts, "drape import")) != 0) return c;
    while ((c = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
        switch (c) {
        case O_OUTDIR:
            if (!*optarg) return usage_error("%s", "--out-dir: expected a directory, got an empty name");
            im.dir = optarg;
            break;
        case O_NAME: name = optarg; break;
        case O_FORCE: im.force = 1; break;
        case 'h': fputs(import_usage, stdout); return 0;
        default:
            fputs("Try `drape import --help'.\n", stderr);
            return drape_error_exit_status(DRAPE_E_USAGE);
        }
    }
    if (optind >= argc) return usage_error("%s", "missing the format: arcsim or kes");
    const char *fmt = argv[optind++];
    int nin = argc - optind;
    if (strcmp(fmt, "arcsim") && strcmp(fmt, "kes"))
        return usage_error("unknown format `%s'; expected arcsim or kes", fmt);
    if (nin < 1) return usage_error("%s", "missing input file");
    if (strcmp(fmt, "kes") == 0 && nin > 1)
        return usage_error("%s", "kes: one table at a time");
    if (name && (strcmp(fmt, "arcsim") || nin > 1))
        return usage_error("%s", "--name: only with one arcsim file");
    if (name && !name_ok(name))
        return usage_error("--name: `%s' is not usable as a fabric and file name "
                           "(letters, digits, '.', '_', '-')", name);
    struct stat st;
    if (stat(im.dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
        fprintf(stderr, "drape: %s: --out-dir: not a directory\n", im.dir);
        return drape_error_exit_status(DRAPE_E_IO);
    }

    if (strcmp(fmt, "arcsim") == 0) import_arcsim(&im, nin, argv + optind, name);
    else import_kes(&im, argv[optind]);

    /* all or nothing */
    int status = 0;
    if (im.n_err) {
        for (int i = 0; i < im.n; i++) drape_cli_afile_abort(&im.out[i].a);
        fprintf(stderr, "drape: import: %d error%s; no file written\n", im.n_err,
                im.n_err == 1 ? "" : "s");
        status = drape_error_exit_status(im.first.kind);
    } else {
        for (int i = 0; i < im.n; i++) {
            drape_error e;
            drape_error_clear(&e);
            if (drape_cli_afile_commit(&im.out[i].a, &e) != 0) {
                drape_cli_print_error(&e);
                if (!status) status = drape_error_exit_status(e.kind);
                continue;
            }
            printf("%s\n", im.out[i].a.path);
        }
    }
    drape_free(im.out);
    return status;
}

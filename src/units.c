/* units.c: quantities with units (see units.h, docs/model.md section 1).
 *
 * Grammar (whitespace allowed before the number, between number and unit,
 * and at the end):
 *
 *   quantity = number [unit]
 *   number   = decimal ["/" udecimal]          ("1/30": a fraction)
 *   decimal  = ["+"|"-"] (digits ["." [digits]] | "." digits)
 *              [("e"|"E") ["+"|"-"] digits]
 *   unit     = factor {("." | "*" | "/") factor}  |  "/" factor ...
 *   factor   = symbol ["^" ["+"|"-"] digits]
 *
 * Operators are applied left to right, each to the one factor after it, so
 * "gf/cm/deg" is gf / (cm deg) and "N.s/m" is N s / m.  A unit that starts
 * with "/" is read as "1/..." ("5/s" = 5 1/s).  A fraction needs its
 * denominator right after the slash ("1/30 s"); "2 1/s" is the number 2 and
 * the unit 1/s.
 *
 * Scales (exact by definition): 1 gf = 1 g x 9.80665 m/s^2 (standard
 * gravity, CGPM 1901), 1 kgf = 9.80665 N, 1 deg = pi/180 rad, 1 min = 60 s,
 * 1 h = 3600 s.  Angles are dimensionless, so "gf/cm/deg" (the KES-F shear
 * rigidity unit) is a force per length with scale 0.980665 x 180/pi.
 */
#include "drape/units.h"

#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

const drape_dim DRAPE_DIM_NONE = {0, 0, 0};
const drape_dim DRAPE_DIM_LENGTH = {0, 1, 0};
const drape_dim DRAPE_DIM_TIME = {0, 0, 1};
const drape_dim DRAPE_DIM_RATE = {0, 0, -1};
const drape_dim DRAPE_DIM_SPEED = {0, 1, -1};
const drape_dim DRAPE_DIM_CURVATURE = {0, -1, 0};
const drape_dim DRAPE_DIM_AREAL_DENSITY = {1, -2, 0};
const drape_dim DRAPE_DIM_FORCE = {1, 1, -2};
const drape_dim DRAPE_DIM_FORCE_PER_LENGTH = {1, 0, -2};
const drape_dim DRAPE_DIM_MOMENT = {1, 2, -2};
const drape_dim DRAPE_DIM_DAMPING = {1, 0, -1};

/* Largest |exponent| of a base unit accepted in a unit expression; keeps
 * the signed char exponents far from overflow. */
#define UNITS_MAX_EXP 12

typedef struct unit_symbol {
    const char *name;
    double scale; /* SI value of one unit */
    signed char kg, m, s;
} unit_symbol;

static const unit_symbol symbols[] = {
    {"m", 1.0, 0, 1, 0},
    {"cm", 1e-2, 0, 1, 0},
    {"mm", 1e-3, 0, 1, 0},
    {"um", 1e-6, 0, 1, 0},
    {"km", 1e3, 0, 1, 0},
    {"s", 1.0, 0, 0, 1},
    {"ms", 1e-3, 0, 0, 1},
    {"us", 1e-6, 0, 0, 1},
    {"min", 60.0, 0, 0, 1},
    {"h", 3600.0, 0, 0, 1},
    {"kg", 1.0, 1, 0, 0},
    {"g", 1e-3, 1, 0, 0},
    {"mg", 1e-6, 1, 0, 0},
    {"N", 1.0, 1, 1, -2},
    {"mN", 1e-3, 1, 1, -2},
    {"gf", DRAPE_GRAM_FORCE, 1, 1, -2},
    {"kgf", 1e3 * DRAPE_GRAM_FORCE, 1, 1, -2},
    {"rad", 1.0, 0, 0, 0},
    {"deg", M_PI / 180.0, 0, 0, 0},
    {"1", 1.0, 0, 0, 0},
};

static void say(char *why, size_t nwhy, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static void say(char *why, size_t nwhy, const char *fmt, ...)
{
    if (!why || nwhy == 0) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, nwhy, fmt, ap);
    va_end(ap);
}

int drape_units_dim_eq(drape_dim a, drape_dim b)
{
    return a.kg == b.kg && a.m == b.m && a.s == b.s;
}

typedef struct dim_info {
    const drape_dim *dim;
    const char *name; /* for "expected a NAME" */
    const char *article;
    const char *si;   /* SI unit */
} dim_info;

static const dim_info dim_infos[] = {
    {&DRAPE_DIM_NONE, "dimensionless number", "a", "1 or rad"},
    {&DRAPE_DIM_LENGTH, "length", "a", "m"},
    {&DRAPE_DIM_TIME, "time", "a", "s"},
    {&DRAPE_DIM_RATE, "rate", "a", "1/s"},
    {&DRAPE_DIM_SPEED, "speed", "a", "m/s"},
    {&DRAPE_DIM_CURVATURE, "curvature", "a", "1/m"},
    {&DRAPE_DIM_AREAL_DENSITY, "areal density", "an", "kg/m^2"},
    {&DRAPE_DIM_FORCE, "force or moment per width", "a", "N or N.m/m"},
    {&DRAPE_DIM_FORCE_PER_LENGTH, "force per length", "a", "N/m"},
    {&DRAPE_DIM_MOMENT, "moment", "a", "N.m"},
    {&DRAPE_DIM_DAMPING, "damping coefficient", "a", "N.s/m"},
    {NULL, NULL, NULL, NULL},
};

static const dim_info *dim_lookup(drape_dim d)
{
    for (const dim_info *p = dim_infos; p->dim; p++)
        if (drape_units_dim_eq(*p->dim, d)) return p;
    return NULL;
}

/* Base-unit spelling of a dimension, "kg/m^2", "kg.m/s^2", into buf. */
static const char *dim_base_units(drape_dim d, char *buf, size_t n)
{
    const char *sym[3] = {"kg", "m", "s"};
    int e[3] = {d.kg, d.m, d.s};
    size_t k = 0;
    buf[0] = 0;
    int any_num = 0;
    for (int i = 0; i < 3; i++) {
        if (e[i] <= 0) continue;
        int r = snprintf(buf + k, n - k, "%s%s", any_num ? "." : "", sym[i]);
        if (r > 0 && (size_t)r < n - k) k += (size_t)r;
        if (e[i] != 1) {
            r = snprintf(buf + k, n - k, "^%d", e[i]);
            if (r > 0 && (size_t)r < n - k) k += (size_t)r;
        }
        any_num = 1;
    }
    if (!any_num) {
        int r = snprintf(buf + k, n - k, "1");
        if (r > 0 && (size_t)r < n - k) k += (size_t)r;
    }
    for (int i = 0; i < 3; i++) {
        if (e[i] >= 0) continue;
        int r = snprintf(buf + k, n - k, "/%s", sym[i]);
        if (r > 0 && (size_t)r < n - k) k += (size_t)r;
        if (e[i] != -1) {
            r = snprintf(buf + k, n - k, "^%d", -e[i]);
            if (r > 0 && (size_t)r < n - k) k += (size_t)r;
        }
    }
    return buf;
}

const char *drape_units_dim_name(drape_dim dim)
{
    static char buf[64];
    const dim_info *p = dim_lookup(dim);
    if (p) return p->name;
    snprintf(buf, sizeof buf, "kg^%d m^%d s^%d", dim.kg, dim.m, dim.s);
    return buf;
}

/* Scan a decimal number at s; return the number of bytes it spans (0 if
 * none).  Only the grammar above is accepted (no hex, inf, nan). */
static size_t scan_decimal(const char *s, int allow_sign)
{
    size_t i = 0, digits = 0;
    if (allow_sign && (s[i] == '+' || s[i] == '-')) i++;
    while (isdigit((unsigned char)s[i])) { i++; digits++; }
    if (s[i] == '.') {
        i++;
        while (isdigit((unsigned char)s[i])) { i++; digits++; }
    }
    if (digits == 0) return 0;
    if (s[i] == 'e' || s[i] == 'E') {
        size_t j = i + 1;
        if (s[j] == '+' || s[j] == '-') j++;
        if (isdigit((unsigned char)s[j])) {
            while (isdigit((unsigned char)s[j])) j++;
            i = j;
        }
    }
    return i;
}

/* strtod on exactly n bytes of s.  A literal strtod cannot represent as a
 * normal double (it overflows to inf, underflows to 0, or lands among the
 * denormals below DBL_MIN) gives NAN, refused by the caller as out of
 * range: no quantity drape reads is meant to be 1e-400 or 1e-310, and
 * taking it as 0 would pass checks such as "non-negative".  An exact zero
 * ("0", "0e-400") is zero. */
double drape_units_strtod(const char *s, char **end, int *range)
{
    errno = 0;
    double v = strtod(s, end);
    *range = errno == ERANGE || !isfinite(v) || (v != 0.0 && fabs(v) < DBL_MIN);
    return v;
}

static double to_double(const char *s, size_t n)
{
    char buf[128];
    if (n >= sizeof buf) return NAN; /* absurdly long literal */
    memcpy(buf, s, n);
    buf[n] = 0;
    int range;
    double v = drape_units_strtod(buf, NULL, &range);
    return range ? NAN : v;
}

/* A nonzero result that underflowed in arithmetic (below DBL_MIN). */
static int underflowed(double r)
{
    return r == 0.0 || fabs(r) < DBL_MIN;
}

static const unit_symbol *symbol_lookup(const char *s, size_t n)
{
    for (size_t i = 0; i < sizeof symbols / sizeof symbols[0]; i++)
        if (strlen(symbols[i].name) == n && memcmp(symbols[i].name, s, n) == 0)
            return &symbols[i];
    return NULL;
}

/* Parse a unit expression of exactly `len` bytes. */
static int parse_unit_n(const char *u, size_t len, double *scale,
                        drape_dim *dim, char *why, size_t nwhy)
{
    double sc = 1.0;
    int e[3] = {0, 0, 0};
    size_t i = 0;
    int sign = 1; /* +1: multiply the next factor, -1: divide by it */
    if (len == 0) {
        say(why, nwhy, "empty unit");
        return -1;
    }
    if (u[0] == '/') { sign = -1; i = 1; } /* "/s" = "1/s" */
    for (;;) {
        /* symbol: a run of letters, or the digit "1" */
        size_t start = i;
        char sym[8];
        const unit_symbol *us = NULL;
        if (i < len && u[i] == '1') {
            i++;
        } else if (i + 1 < len && (unsigned char)u[i] == 0xC2 &&
                   (unsigned char)u[i + 1] == 0xB5) {
            /* UTF-8 micro sign: "µm" = "um" */
            i += 2;
            while (i < len && isalpha((unsigned char)u[i])) i++;
        } else {
            while (i < len && isalpha((unsigned char)u[i])) i++;
        }
        if (i == start) {
            if (i < len)
                say(why, nwhy, "unexpected \"%.*s\" in unit \"%.*s\"",
                    (int)(len - i), u + i, (int)len, u);
            else
                say(why, nwhy, "unit \"%.*s\" ends with an operator",
                    (int)len, u);
            return -1;
        }
        if (i - start >= 2 && (unsigned char)u[start] == 0xC2) {
            size_t n = i - start - 1;
            if (n < sizeof sym) {
                sym[0] = 'u';
                memcpy(sym + 1, u + start + 2, n - 1);
                us = symbol_lookup(sym, n);
            }
        } else {
            us = symbol_lookup(u + start, i - start);
        }
        if (!us) {
            say(why, nwhy, "unknown unit \"%.*s\" (known: m cm mm um km, s ms us "
                "min h, kg g mg, N mN gf kgf, rad deg, 1)",
                (int)(i - start), u + start);
            return -1;
        }
        int p = 1;
        if (i < len && u[i] == '^') {
            size_t j = i + 1;
            int psign = 1;
            if (j < len && (u[j] == '+' || u[j] == '-')) {
                psign = u[j] == '-' ? -1 : 1;
                j++;
            }
            if (j >= len || !isdigit((unsigned char)u[j])) {
                say(why, nwhy, "expected an integer power after '^' in unit "
                    "\"%.*s\"", (int)len, u);
                return -1;
            }
            long v = 0;
            while (j < len && isdigit((unsigned char)u[j])) {
                v = v * 10 + (u[j] - '0');
                if (v > UNITS_MAX_EXP) {
                    say(why, nwhy, "power too large in unit \"%.*s\"",
                        (int)len, u);
                    return -1;
                }
                j++;
            }
            p = psign * (int)v;
            i = j;
        }
        p *= sign;
        sc *= pow(us->scale, p);
        e[0] += us->kg * p;
        e[1] += us->m * p;
        e[2] += us->s * p;
        for (int k = 0; k < 3; k++) {
            if (e[k] > UNITS_MAX_EXP || e[k] < -UNITS_MAX_EXP) {
                say(why, nwhy, "power too large in unit \"%.*s\"", (int)len,
                    u);
                return -1;
            }
        }
        if (i >= len) break;
        if (u[i] == '.' || u[i] == '*') sign = 1;
        else if (u[i] == '/') sign = -1;
        else {
            say(why, nwhy, "unexpected \"%.*s\" in unit \"%.*s\"",
                (int)(len - i), u + i, (int)len, u);
            return -1;
        }
        i++;
    }
    if (!isfinite(sc) || sc == 0.0) {
        say(why, nwhy, "unit \"%.*s\" is out of range", (int)len, u);
        return -1;
    }
    *scale = sc;
    dim->kg = (signed char)e[0];
    dim->m = (signed char)e[1];
    dim->s = (signed char)e[2];
    return 0;
}

static int is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

int drape_units_parse_unit(const char *unit, double *scale, drape_dim *dim,
                           char *why, size_t nwhy)
{
    size_t b = 0, e;
    if (!unit) unit = "";
    e = strlen(unit);
    while (b < e && is_space(unit[b])) b++;
    while (e > b && is_space(unit[e - 1])) e--;
    return parse_unit_n(unit + b, e - b, scale, dim, why, nwhy);
}

int drape_units_parse(const char *text, drape_dim dim, double *si, char *why,
                      size_t nwhy)
{
    if (!text) text = "";
    size_t len = strlen(text), b = 0, e = len;
    while (b < e && is_space(text[b])) b++;
    while (e > b && is_space(text[e - 1])) e--;
    const char *s = text + b;
    size_t n = e - b;
    if (n == 0) {
        say(why, nwhy, "expected a quantity, got an empty value");
        return -1;
    }
    /* the number is parsed from a bounded copy so scans never run past e */
    char num[128];
    size_t nn = n < sizeof num - 1 ? n : sizeof num - 1;
    memcpy(num, s, nn);
    num[nn] = 0;
    size_t k = scan_decimal(num, 1);
    if (k == 0) {
        say(why, nwhy, "not a number: \"%.*s\"", (int)n, s);
        return -1;
    }
    double v = to_double(num, k);
    if (num[k] == '/' && isdigit((unsigned char)num[k + 1])) {
        size_t k2 = scan_decimal(num + k + 1, 0);
        double d = to_double(num + k + 1, k2);
        if (d == 0.0) {
            say(why, nwhy, "division by zero in \"%.*s\"", (int)n, s);
            return -1;
        }
        if (v != 0.0 && isfinite(d) && underflowed(v / d)) v = NAN;
        else v /= d;
        k += 1 + k2;
    }
    if (!isfinite(v)) {
        say(why, nwhy, "number out of range: \"%.*s\" (a magnitude from %.1e "
            "to %.1e, or 0)", (int)n, s, DBL_MIN, DBL_MAX);
        return -1;
    }
    size_t u = k;
    while (u < n && is_space(s[u])) u++;
    double scale = 1.0;
    drape_dim got = DRAPE_DIM_NONE;
    int has_unit = u < n;
    if (has_unit) {
        if (u == k && !isalpha((unsigned char)s[u]) && s[u] != '/' &&
            (unsigned char)s[u] != 0xC2) {
            say(why, nwhy, "not a number: \"%.*s\"", (int)n, s);
            return -1;
        }
        char uwhy[256];
        if (parse_unit_n(s + u, n - u, &scale, &got, uwhy, sizeof uwhy)) {
            say(why, nwhy, "%s in \"%.*s\"", uwhy, (int)n, s);
            return -1;
        }
    } else {
        got = dim; /* a bare number is SI */
    }
    if (!drape_units_dim_eq(got, dim)) {
        const dim_info *want = dim_lookup(dim), *have = dim_lookup(got);
        char wb[64], hb[64];
        const char *wsi = want ? want->si : dim_base_units(dim, wb, sizeof wb);
        if (have)
            say(why, nwhy, "expected %s %s (%s), got %.*s, %s %s (%s)",
                want ? want->article : "a", want ? want->name : "quantity in",
                wsi, (int)(n - u), s + u, have->article, have->name,
                have->si);
        else
            say(why, nwhy, "expected %s %s (%s), got %.*s (%s)",
                want ? want->article : "a", want ? want->name : "quantity in",
                wsi, (int)(n - u), s + u,
                dim_base_units(got, hb, sizeof hb));
        return -1;
    }
    double r = v * scale;
    if (!isfinite(r) || (v != 0.0 && underflowed(r))) {
        say(why, nwhy, "quantity out of range: \"%.*s\" (in SI, a magnitude "
            "from %.1e to %.1e, or 0)", (int)n, s, DBL_MIN, DBL_MAX);
        return -1;
    }
    *si = r;
    return 0;
}

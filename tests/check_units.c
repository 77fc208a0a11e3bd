/* check_units.c: quantities with units (units.h).  Expected values are
 * hand-computed from the unit definitions (1 gf = 9.80665e-3 N, 1 deg =
 * pi/180 rad), written out as arithmetic next to each case. */
#include "drape/units.h"

#include <math.h>
#include <string.h>

#include "testutil.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

typedef struct qcase {
    const char *text;
    const drape_dim *dim;
    double expect;
} qcase;

static const qcase good[] = {
    {"20 mg/cm^2", &DRAPE_DIM_AREAL_DENSITY, 20e-6 / 1e-4},  /* 0.2 kg/m^2 */
    {"20mg/cm^2", &DRAPE_DIM_AREAL_DENSITY, 20e-6 / 1e-4},
    {"200 g/m^2", &DRAPE_DIM_AREAL_DENSITY, 200e-3 / 1.0},   /* 0.2 */
    {"0.2 kg/m^2", &DRAPE_DIM_AREAL_DENSITY, 0.2},
    {"0.2 kg.m^-2", &DRAPE_DIM_AREAL_DENSITY, 0.2},
    {"0.2", &DRAPE_DIM_AREAL_DENSITY, 0.2},                  /* bare: SI */
    {"10000 N/m", &DRAPE_DIM_FORCE_PER_LENGTH, 10000.0},
    {"1e4 N/m", &DRAPE_DIM_FORCE_PER_LENGTH, 10000.0},
    {"5 gf/cm", &DRAPE_DIM_FORCE_PER_LENGTH, 5 * 9.80665e-3 / 1e-2},
    {"1 kgf/m", &DRAPE_DIM_FORCE_PER_LENGTH, 9.80665},
    {"3 mN/mm", &DRAPE_DIM_FORCE_PER_LENGTH, 3e-3 / 1e-3},
    {"1 cm", &DRAPE_DIM_LENGTH, 0.01},
    {"5mm", &DRAPE_DIM_LENGTH, 0.005},
    {"5 mm", &DRAPE_DIM_LENGTH, 0.005},
    {"  5 mm  ", &DRAPE_DIM_LENGTH, 0.005},
    {"250 um", &DRAPE_DIM_LENGTH, 250e-6},
    {"250 \xC2\xB5m", &DRAPE_DIM_LENGTH, 250e-6},            /* µm */
    {"0.5 km", &DRAPE_DIM_LENGTH, 500.0},
    {"-3 cm", &DRAPE_DIM_LENGTH, -0.03},
    {".5 m", &DRAPE_DIM_LENGTH, 0.5},
    {"2. m", &DRAPE_DIM_LENGTH, 2.0},
    {"2 1/s", &DRAPE_DIM_RATE, 2.0},
    {"2/s", &DRAPE_DIM_RATE, 2.0},
    {"6 1/min", &DRAPE_DIM_RATE, 6.0 / 60.0},
    {"1/30 s", &DRAPE_DIM_TIME, 1.0 / 30.0},
    {"1/30s", &DRAPE_DIM_TIME, 1.0 / 30.0},
    {"3/4", &DRAPE_DIM_NONE, 0.75},
    {"20 ms", &DRAPE_DIM_TIME, 0.02},
    {"100 us", &DRAPE_DIM_TIME, 1e-4},
    {"100 \xC2\xB5s", &DRAPE_DIM_TIME, 1e-4},                  /* µs */
    {"2 min", &DRAPE_DIM_TIME, 120.0},
    {"1.5 h", &DRAPE_DIM_TIME, 5400.0},
    {"0.02 N.s/m", &DRAPE_DIM_DAMPING, 0.02},
    {"0.02 N*s/m", &DRAPE_DIM_DAMPING, 0.02},
    {"0.02 kg/s", &DRAPE_DIM_DAMPING, 0.02},
    {"1e-5 m/s", &DRAPE_DIM_SPEED, 1e-5},
    {"1E-5 m/s", &DRAPE_DIM_SPEED, 1e-5},
    {"36 km/h", &DRAPE_DIM_SPEED, 36e3 / 3600.0},            /* 10 m/s */
    {"0.3 1/cm", &DRAPE_DIM_CURVATURE, 0.3 / 1e-2},          /* 30 1/m */
    {"0.3 /cm", &DRAPE_DIM_CURVATURE, 30.0},
    {"90 deg", &DRAPE_DIM_NONE, 90 * M_PI / 180},
    {"0.5 rad", &DRAPE_DIM_NONE, 0.5},
    {"7 1", &DRAPE_DIM_NONE, 7.0},
    {"2 gf.cm/cm", &DRAPE_DIM_FORCE, 2 * 9.80665e-3 * 1e-2 / 1e-2},
    {"2 N.m/m", &DRAPE_DIM_FORCE, 2.0},
    {"0.085 gf.cm^2/cm", &DRAPE_DIM_MOMENT, 0.085 * 9.80665e-3 * 1e-4 / 1e-2},
    {"0.9 gf/cm/deg", &DRAPE_DIM_FORCE_PER_LENGTH,
     0.9 * 9.80665e-3 / 1e-2 / (M_PI / 180)},
    {"9.81 m/s^2", &(drape_dim){0, 1, -2}, 9.81},
    /* tiny but normal values pass; an exact zero is zero */
    {"1e-12 m", &DRAPE_DIM_LENGTH, 1e-12},
    {"1e-300 m", &DRAPE_DIM_LENGTH, 1e-300},
    {"0e-400 m", &DRAPE_DIM_LENGTH, 0.0},
    {"0 m", &DRAPE_DIM_LENGTH, 0.0},
};

START_TEST(test_good)
{
    const qcase *c = &good[_i];
    double v = -12345;
    char why[256] = "";
    int rc = drape_units_parse(c->text, *c->dim, &v, why, sizeof why);
    ck_assert_msg(rc == 0, "\"%s\" rejected: %s", c->text, why);
    ck_assert_msg(fabs(v - c->expect) <= 1e-14 * fabs(c->expect),
                  "\"%s\" -> %.17g, expected %.17g", c->text, v, c->expect);
}
END_TEST

typedef struct ucase {
    const char *unit;
    double scale;
    drape_dim dim;
} ucase;

static const ucase units[] = {
    {"gf.cm/cm", 9.80665e-3 * 1e-2 / 1e-2, {1, 1, -2}},     /* N.m/m = N */
    {"gf.cm^2/cm", 9.80665e-3 * 1e-4 / 1e-2, {1, 2, -2}},   /* N.m */
    {"gf/cm", 9.80665e-3 / 1e-2, {1, 0, -2}},
    {"gf/cm/deg", 9.80665e-3 / 1e-2 * 180 / M_PI, {1, 0, -2}},
    {"1/cm", 100.0, {0, -1, 0}},
    {"rad", 1.0, {0, 0, 0}},
    {"deg", M_PI / 180, {0, 0, 0}},
    {"mg/cm^2", 1e-6 / 1e-4, {1, -2, 0}},
    {"  N.s/m ", 1.0, {1, 0, -1}},
    {"cm^-1", 100.0, {0, -1, 0}},
    {"m^+2", 1.0, {0, 2, 0}},
    {"1", 1.0, {0, 0, 0}},
};

START_TEST(test_unit_only)
{
    const ucase *c = &units[_i];
    double sc = 0;
    drape_dim d = {9, 9, 9};
    char why[256] = "";
    ck_assert_msg(drape_units_parse_unit(c->unit, &sc, &d, why, sizeof why) == 0,
                  "\"%s\": %s", c->unit, why);
    ck_assert_msg(fabs(sc - c->scale) <= 1e-14 * c->scale,
                  "\"%s\" scale %.17g, expected %.17g", c->unit, sc, c->scale);
    ck_assert_msg(drape_units_dim_eq(d, c->dim), "\"%s\" dim %d %d %d", c->unit,
                  d.kg, d.m, d.s);
}
END_TEST

typedef struct bcase {
    const char *text;
    const drape_dim *dim;
    const char *why_contains;
} bcase;

static const bcase bad[] = {
    {"", &DRAPE_DIM_LENGTH, "empty"},
    {"   ", &DRAPE_DIM_LENGTH, "empty"},
    {"x", &DRAPE_DIM_LENGTH, "not a number: \"x\""},
    {"abc mm", &DRAPE_DIM_LENGTH, "not a number"},
    {"inf", &DRAPE_DIM_LENGTH, "not a number"},
    {"nan m", &DRAPE_DIM_LENGTH, "not a number"},
    {"0x10", &DRAPE_DIM_LENGTH, "unknown unit \"x\""},
    {"1.2.3 m", &DRAPE_DIM_LENGTH, "not a number"},
    {"1,5 m", &DRAPE_DIM_LENGTH, "not a number"},
    {"- 5 m", &DRAPE_DIM_LENGTH, "not a number"},
    {"1e999 m", &DRAPE_DIM_LENGTH, "out of range"},
    {"1e308 km", &DRAPE_DIM_LENGTH, "out of range"},
    {"1/0 s", &DRAPE_DIM_TIME, "division by zero"},
    /* underflow is refused like overflow, not read as 0 (or a denormal) */
    {"1e-400 m", &DRAPE_DIM_LENGTH, "number out of range"},
    {"-1e-400 m", &DRAPE_DIM_LENGTH, "number out of range"},
    {"1e-400", &DRAPE_DIM_NONE, "number out of range"},
    {"1e-310 m", &DRAPE_DIM_LENGTH, "number out of range"},
    {"1e-400/3 s", &DRAPE_DIM_TIME, "number out of range"},
    {"1/1e308 s", &DRAPE_DIM_TIME, "number out of range"},
    {"1e-306 mm", &DRAPE_DIM_LENGTH, "quantity out of range"},
    {"1e-306 um", &DRAPE_DIM_LENGTH, "quantity out of range"},
    {"5 furlong", &DRAPE_DIM_LENGTH, "unknown unit \"furlong\""},
    {"5 M", &DRAPE_DIM_LENGTH, "unknown unit \"M\""},
    {"5 mm xyz", &DRAPE_DIM_LENGTH, "unexpected \" xyz\""},
    {"5 mm mm", &DRAPE_DIM_LENGTH, "unexpected"},
    {"5 m^", &DRAPE_DIM_LENGTH, "integer power"},
    {"5 m^x", &DRAPE_DIM_LENGTH, "integer power"},
    {"5 m^99", &DRAPE_DIM_LENGTH, "power too large"},
    {"5 m/", &DRAPE_DIM_LENGTH, "ends with an operator"},
    {"5 m..s", &DRAPE_DIM_LENGTH, "unexpected"},
    {"5 m)", &DRAPE_DIM_LENGTH, "unexpected"},
    {"20 mg/cm^2", &DRAPE_DIM_LENGTH,
     "expected a length (m), got mg/cm^2, an areal density (kg/m^2)"},
    {"1 cm", &DRAPE_DIM_TIME, "expected a time (s), got cm, a length (m)"},
    {"2 1/s", &DRAPE_DIM_TIME, "expected a time"},
    {"10 N", &DRAPE_DIM_FORCE_PER_LENGTH, "expected a force per length (N/m)"},
    {"1 kg.m", &DRAPE_DIM_LENGTH, "got kg.m (kg.m)"},
    {"90 deg", &DRAPE_DIM_LENGTH, "got deg, a dimensionless number"},
};

START_TEST(test_bad)
{
    const bcase *c = &bad[_i];
    double v = 42.0;
    char why[256] = "";
    int rc = drape_units_parse(c->text, *c->dim, &v, why, sizeof why);
    ck_assert_msg(rc == -1, "\"%s\" accepted as %.17g", c->text, v);
    ck_assert_msg(v == 42.0, "\"%s\": output written on failure", c->text);
    ck_assert_msg(strstr(why, c->why_contains) != NULL,
                  "\"%s\": reason \"%s\" lacks \"%s\"", c->text, why,
                  c->why_contains);
}
END_TEST

START_TEST(test_bad_unit_only)
{
    double sc;
    drape_dim d;
    char why[256];
    ck_assert_int_eq(drape_units_parse_unit("", &sc, &d, why, sizeof why), -1);
    ck_assert_int_eq(drape_units_parse_unit("gf.", &sc, &d, why, sizeof why), -1);
    ck_assert_int_eq(drape_units_parse_unit("5 cm", &sc, &d, why, sizeof why), -1);
    ck_assert_int_eq(drape_units_parse_unit("inch", &sc, &d, why, sizeof why), -1);
    ck_assert_ptr_nonnull(strstr(why, "unknown unit \"inch\""));
    /* a NULL or zero-size reason buffer is allowed */
    ck_assert_int_eq(drape_units_parse("x", DRAPE_DIM_NONE, &sc, NULL, 0), -1);
}
END_TEST

START_TEST(test_dim_names)
{
    ck_assert_str_eq(drape_units_dim_name(DRAPE_DIM_LENGTH), "length");
    ck_assert_str_eq(drape_units_dim_name(DRAPE_DIM_TIME), "time");
    ck_assert_str_eq(drape_units_dim_name(DRAPE_DIM_AREAL_DENSITY),
                     "areal density");
    ck_assert_str_eq(drape_units_dim_name((drape_dim){1, -1, -2}),
                     "kg^1 m^-1 s^-2");
    ck_assert(drape_units_dim_eq(DRAPE_DIM_FORCE, (drape_dim){1, 1, -2}));
    ck_assert(!drape_units_dim_eq(DRAPE_DIM_FORCE, DRAPE_DIM_MOMENT));
    /* the named constants agree with the unit table */
    double v;
    ck_assert_int_eq(drape_units_parse("1 gf", DRAPE_DIM_FORCE, &v, NULL, 0), 0);
    ck_assert_close_rel(v, DRAPE_GRAM_FORCE, 1e-15);
    ck_assert_close_rel(DRAPE_GRAM_FORCE, DRAPE_G_STANDARD / 1000, 1e-15);
}
END_TEST

Suite *units_suite(void); /* found by the runner */
Suite *units_suite(void)
{
    Suite *s = suite_create("units");
    TCase *tc = tcase_create("units");
    tcase_add_loop_test(tc, test_good, 0, (int)(sizeof good / sizeof good[0]));
    tcase_add_loop_test(tc, test_unit_only, 0,
                        (int)(sizeof units / sizeof units[0]));
    tcase_add_loop_test(tc, test_bad, 0, (int)(sizeof bad / sizeof bad[0]));
    tcase_add_test(tc, test_bad_unit_only);
    tcase_add_test(tc, test_dim_names);
    suite_add_tcase(s, tc);
    return s;
}

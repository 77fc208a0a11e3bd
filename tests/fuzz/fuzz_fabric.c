/* fuzz_fabric.c: libFuzzer harness of the fabric loader (drape_fabric_load,
 * and through it yamldoc, units and fit).  Built by scripts/fuzz.sh with
 * clang -fsanitize=fuzzer,address,undefined; see docs/reliability.md.
 *
 * Each input is a fabric file.  Besides crashes, leaks and undefined
 * behaviour, the harness aborts on (fuzz_common.h):
 *   - a rejection that is not well formed (no message or file, E_INPUT
 *     without a line, or an E_INTERNAL/E_NUMERIC kind);
 *   - an accepted fabric whose weight or tensile stiffness is not a finite
 *     positive number, or whose initial rigidities or fitted curves are not
 *     finite where `drape check` evaluates them. */
#define _XOPEN_SOURCE 700 /* realpath */
#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "drape/alloc.h"
#include "drape/fabric.h"
#include "drape/fit.h"
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void check_curve(const char *what, const drape_fit *f, double xmax)
{
    for (int k = 0; k <= 64; k++) {
        double x = xmax * k / 64.0;
        double v = drape_fit_value(f, x), s = drape_fit_slope(f, x);
        if (!isfinite(v) || !isfinite(s)) {
            fprintf(stderr, "%s not finite at %g: %g, slope %g\n", what, x, v, s);
            abort();
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[512];
    snprintf(path, sizeof path, "%s/fabric-input.yaml", fz_workdir());
    fz_write(path, data, size);

    drape_fabric f;
    drape_error err;
    drape_error_clear(&err);
    drape_alloc_fail_at(0);
    if (drape_fabric_load(path, &f, &err, fz_warn, NULL) != 0) {
        fz_check_error(&err);
        return 0;
    }
    fz_check_range("weight", f.weight, 0.0, HUGE_VAL);
    fz_check_range("k_weft", f.k[DRAPE_WEFT], 0.0, HUGE_VAL);
    fz_check_range("k_warp", f.k[DRAPE_WARP], 0.0, HUGE_VAL);
    fz_check_range("bending rigidity weft",
                   drape_fabric_bending_rigidity(&f, DRAPE_WEFT), -HUGE_VAL, HUGE_VAL);
    fz_check_range("bending rigidity warp",
                   drape_fabric_bending_rigidity(&f, DRAPE_WARP), -HUGE_VAL, HUGE_VAL);
    fz_check_range("shear rigidity", drape_fabric_shear_rigidity(&f), -HUGE_VAL, HUGE_VAL);
    /* the ranges `drape check` prints: K to 500 1/m, gamma to 0.3 rad */
    check_curve("bending weft", &f.bend[DRAPE_WEFT], 500.0);
    check_curve("bending warp", &f.bend[DRAPE_WARP], 500.0);
    check_curve("shear weft", &f.shear[DRAPE_WEFT], 0.3);
    check_curve("shear warp", &f.shear[DRAPE_WARP], 0.3);
    check_curve("shear mean", &f.shear_mean, 0.3);
    return 0;
}

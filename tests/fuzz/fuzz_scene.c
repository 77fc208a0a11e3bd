/* fuzz_scene.c: libFuzzer harness of the scene loader and what `drape check`
 * does with a scene: drape_scene_load, the fabric it names (when that is a
 * file of the source tree's fabrics/), drape_scene_check_with_fabric and,
 * for lattices of at most FZ_MAX_PARTICLES, drape_lattice_new and
 * drape_lattice_check.  Built by scripts/fuzz.sh with
 * clang -fsanitize=fuzzer,address,undefined; see docs/reliability.md.
 *
 * The input is written to DIR/scenes/input.yaml, so the shipped scenes'
 * `fabric: ../fabrics/cotton-breen.yaml` resolves to the real fabrics.  A
 * fabric path outside DIR/fabrics is not loaded (it could name a FIFO or
 * /dev/zero: legitimate for a user, useless or blocking for a fuzzer).
 *
 * Besides crashes, leaks and undefined behaviour, the harness aborts on a
 * rejection that is not well formed (fuzz_common.h), on an accepted scene
 * with a spacing, t_max, tolerance or size that is not finite and
 * positive, on a lattice that drape_lattice_estimate sizes differently from
 * drape_lattice_new, and on a lattice that fails drape_lattice_check or has
 * a mass or position that is not finite. */
#define _XOPEN_SOURCE 700 /* realpath */
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include "drape/alloc.h"
#include "drape/fabric.h"
#include "drape/lattice.h"
#include "drape/scene.h"
#include "fuzz_common.h"

#define FZ_MAX_PARTICLES 20000

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* 1 if `path` is a regular file under DIR/fabrics. */
static int fabric_allowed(const char *path)
{
    char want[PATH_MAX], real[PATH_MAX], p[600];
    snprintf(p, sizeof p, "%s/fabrics", fz_workdir());
    if (!realpath(p, want) || !realpath(path, real)) return 0;
    size_t n = strlen(want);
    if (strncmp(real, want, n) != 0 || real[n] != '/') return 0;
    struct stat st;
    return stat(real, &st) == 0 && S_ISREG(st.st_mode);
}

static void check_lattice(const drape_scene *s, const drape_fabric *f)
{
    long ni, nj, np;
    if (drape_lattice_estimate(s, &ni, &nj, &np) != 0) {
        fprintf(stderr, "a checked scene has no lattice estimate\n");
        abort();
    }
    if (np > FZ_MAX_PARTICLES) return;
    drape_error err;
    drape_error_clear(&err);
    drape_lattice *L = drape_lattice_new(s, f, &err);
    if (!L) {
        fz_check_error(&err);
        return;
    }
    int bad = drape_lattice_check(L);
    if (bad || L->n <= 0 || L->n != np || L->ni != ni || L->nj != nj) {
        fprintf(stderr, "lattice: %d invariants violated; n %d (estimate %ld), "
                "%d x %d (estimate %ld x %ld)\n", bad, L->n, np, L->ni, L->nj, ni, nj);
        abort();
    }
    fz_check_range("mass_total", L->mass_total, 0.0, HUGE_VAL);
    for (int k = 0; k < 3 * L->n; k++)
        if (!isfinite(L->xinit[k])) {
            fprintf(stderr, "lattice: xinit[%d] = %g\n", k, L->xinit[k]);
            abort();
        }
    drape_lattice_free(L);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[512];
    snprintf(path, sizeof path, "%s/scenes/input.yaml", fz_workdir());
    fz_write(path, data, size);

    drape_scene s;
    drape_fabric f;
    drape_error err;
    drape_error_clear(&err);
    drape_alloc_fail_at(0);
    if (drape_scene_load(path, &s, &err, fz_warn, NULL) != 0) {
        fz_check_error(&err);
        return 0;
    }
    fz_check_range("spacing", s.spacing, 0.0, HUGE_VAL);
    fz_check_range("t_max", s.t_max, 0.0, HUGE_VAL);
    fz_check_range("rtol", s.rtol, 0.0, 1.0);
    fz_check_range("atol", s.atol, 0.0, HUGE_VAL);
    switch (s.shape) {
    case DRAPE_SHAPE_RECTANGLE:
        fz_check_range("width", s.width, 0.0, HUGE_VAL);
        fz_check_range("height", s.height, 0.0, HUGE_VAL);
        break;
    case DRAPE_SHAPE_CIRCLE:
        fz_check_range("diameter", s.diameter, 0.0, HUGE_VAL);
        break;
    case DRAPE_SHAPE_STRIP:
        fz_check_range("width", s.width, 0.0, HUGE_VAL);
        fz_check_range("length", s.length, 0.0, HUGE_VAL);
        break;
    default:
        abort();
    }
    if (!fabric_allowed(s.fabric_path)) return 0;
    drape_error_clear(&err);
    if (drape_fabric_load(s.fabric_path, &f, &err, fz_warn, NULL) != 0) {
        fz_check_error(&err);
        return 0;
    }
    if (drape_scene_check_with_fabric(&s, &f, &err) != 0) {
        fz_check_error(&err);
        return 0;
    }
    check_lattice(&s, &f);
    return 0;
}

/* output.h: frame files of a run (docs/outputs.md).
 *
 * Two writers, both opaque handles that borrow the lattice (it must
 * outlive them) and write every file under a temporary name in the target
 * directory (NAME.PID.tmp), renaming it to NAME only when it is complete,
 * so a reader never sees a partial file.  The directory must exist.  All
 * errors are E_IO (or E_NOMEM) with the path in the message.
 *
 *  - OBJ: one Wavefront OBJ per frame, `frame_000000.obj`, ...: `v`
 *    positions (Y-up: OBJ (X, Y, Z) = drape (x, z, -y)), `vt` from the
 *    rest lattice, `vn` area-weighted vertex normals, quad faces `f a/a/a`
 *    (1-based particle id + 1), a header comment with time, units, names.
 *
 *  - HDF5: `drape.h5` (SI units, drape axes, z up) and its XDMF sidecar
 *    `drape.xmf` for ParaView, written when the run closes:
 *      /mesh/rest_positions [n][3] f64, /mesh/quads [nq][4] i32 (0-based
 *      particle ids, counter-clockwise from +z at rest), /mesh/fixed [n] u8,
 *      /mesh/grid_ij [n][2] i32; attributes sigma_m, area_nominal_m2
 *      /steps/NNNNNN/positions [n][3] f64 (attribute time_s; the group has
 *      it too), /steps/NNNNNN/velocities [n][3] when given
 *      /times [frames] f64 (s), /energies/{kinetic,stretch,bend,shear,
 *      gravity} [frames] f64 (J)
 *      /final/positions, /final/velocities, attribute time_s
 *      /stats: one attribute per key (f64 or string)
 *      root attributes: fabric_yaml, scene_yaml (full texts), creator,
 *      format ("drape-h5 1"), units.
 *    drape.xmf: a temporal collection of Uniform grids, one per frame,
 *    Quadrilateral topology from drape.h5:/mesh/quads, XYZ geometry from
 *    drape.h5:/steps/NNNNNN/positions (paths relative to the .xmf).
 */
#ifndef DRAPE_OUTPUT_H
#define DRAPE_OUTPUT_H

#include <stdio.h>

#include "drape/error.h"
#include "drape/lattice.h"
#include "drape/model.h"

/* ---- OBJ ---------------------------------------------------------------- */

typedef struct drape_obj drape_obj;

/* Prepare OBJ output into directory dir (must exist) for lattice L:
 * faces, texture coordinates, workspaces.  fabric and scene are names for
 * the header comment (may be NULL).  Returns NULL with err set (E_IO if dir
 * is not a writable directory, E_NOMEM).  Caller frees with drape_obj_free
 * (the frames stay) or drape_obj_discard. */
drape_obj *drape_obj_new(const char *dir, const drape_lattice *L,
                         const char *fabric, const char *scene,
                         drape_error *err);
void drape_obj_free(drape_obj *o);
/* Remove every file this handle wrote (a failed run leaves no frame of its
 * own behind), then free it.  NULL is a no-op. */
void drape_obj_discard(drape_obj *o);
/* Number of distinct files written so far. */
int drape_obj_written(const drape_obj *o);

/* After a complete run whose last frame was first - 1: remove the frames
 * first, first + 1, ... that an earlier, longer run left in the directory
 * (a renderer loading frame_*.obj would mix the two runs), up to the
 * first number that does not exist.  Returns how many were removed. */
int drape_obj_remove_stale(drape_obj *o, int first);

/* Write positions x (3n, m) at time t_s as DIR/frame_%06d.obj (frame >= 0).
 * Returns 0 or -1 with err set. */
int drape_obj_frame(drape_obj *o, int frame, double t_s, const double *x,
                    drape_error *err);

/* The same to an explicit path (renamed into place from PATH.PID.tmp). */
int drape_obj_write(drape_obj *o, const char *path, double t_s,
                    const double *x, drape_error *err);

/* ---- HDF5 + XDMF -------------------------------------------------------- */

typedef struct drape_h5 drape_h5;

/* A statistic for /stats: a string when text != NULL, else the number. */
typedef struct drape_kv {
    const char *key;
    const char *text;
    double value;
} drape_kv;

/* What drape_h5_close stores besides the frames.  Every pointer may be
 * NULL (then that part is left out). */
typedef struct drape_h5_final {
    double t_s;               /* time of the final state */
    const double *x, *v;      /* final positions and velocities, 3n */
    const drape_kv *stats;    /* n_stats key/value pairs -> /stats */
    int n_stats;
    const char *fabric_yaml;  /* full text of the fabric file */
    const char *scene_yaml;   /* full text of the scene file */
    /* the run's options and resume state -> /run */
    const drape_kv *run;
    int n_run;
} drape_h5_final;

/* Create DIR/drape.h5 (under a temporary name) and write /mesh.  Switches
 * off HDF5's automatic error printing (H5Eset_auto2).  Returns NULL with
 * err set.  Finish with drape_h5_close or drape_h5_discard. */
drape_h5 *drape_h5_open(const char *dir, const drape_lattice *L,
                        drape_error *err);

/* Append a frame: positions x (3n), velocities v (3n, may be NULL), the
 * kinetic energy and the potential energies by term (E may be NULL: NaN is
 * stored).  Returns 0 or -1 with err set. */
int drape_h5_frame(drape_h5 *h, double t_s, const double *x, const double *v,
                   double kinetic_J, const drape_energies *E,
                   drape_error *err);

/* Number of frames written so far. */
int drape_h5_frames(const drape_h5 *h);

/* Write /times, /energies, fin (may be NULL), close the file, write the
 * XDMF sidecar and rename both into place.  Frees h in every case; on
 * failure removes the temporary files and returns -1 with err set.
 * Same as drape_h5_finish followed by drape_h5_commit. */
int drape_h5_close(drape_h5 *h, const drape_h5_final *fin, drape_error *err);

/* The first half of drape_h5_close: everything but the renames.  Both
 * files are complete under their temporary names; h stays valid only for
 * drape_h5_commit (which puts them in place) or drape_h5_discard (which
 * removes them), so that a run can write its other files first and keep
 * none when one of them fails.  On failure frees h, removes the temporary
 * files and returns -1 with err set. */
int drape_h5_finish(drape_h5 *h, const drape_h5_final *fin, drape_error *err);

/* Rename a finished h's files into place (drape.h5, then drape.xmf) and
 * free h, in every case; -1 with err set (temporaries removed) on
 * failure. */
int drape_h5_commit(drape_h5 *h, drape_error *err);

/* Close without keeping anything (temporary files removed); NULL is a
 * no-op. */
void drape_h5_discard(drape_h5 *h);

/* ---- reading back (drape run --resume) ---------------------------------- */

/* What a finished or interrupted run left in a drape.h5: /final, the
 * attributes of /run and /stats, the input texts.  Every pointer is owned
 * (drape_h5_checkpoint_free). */
typedef struct drape_h5_checkpoint {
    int n;                 /* particles (rows of /final/positions) */
    double t_s;            /* /final time_s */
    double *x, *v;         /* /final/positions, /final/velocities, 3n each */
    int frames;            /* entries of /times */
    drape_kv *run;         /* attributes of /run (none if absent) */
    int n_run;
    drape_kv *stats;       /* attributes of /stats */
    int n_stats;
    char *fabric_yaml, *scene_yaml; /* root attributes, NULL if absent */
} drape_h5_checkpoint;

/* Read path (a drape.h5).  Returns 0, or -1 with err set (E_IO naming the
 * file: missing, not HDF5, no /final; E_NOMEM).  c is always initialised:
 * free it with drape_h5_checkpoint_free in every case. */
int drape_h5_checkpoint_read(const char *path, drape_h5_checkpoint *c,
                             drape_error *err);
void drape_h5_checkpoint_free(drape_h5_checkpoint *c);

/* The pair named key of kv[0..n), or NULL. */
const drape_kv *drape_kv_find(const drape_kv *kv, int n, const char *key);

/* Append every frame of the drape.h5 at path (positions, velocities,
 * times, energies; same number of particles) to h, in order: a resumed
 * run keeps the frames of the interrupted one.  0 or -1 with err set. */
int drape_h5_copy_frames(drape_h5 *h, const char *path, drape_error *err);

/* ---- shadow picture (output_svg.c) --------------------------------------- */

/* One specimen's shadow outline: its outer radius r[k] at angle
 * theta_k = 2 pi k / n around (cx, cy) (drape_dc_radii), m. */
typedef struct drape_svg_specimen {
    unsigned long seed;
    double dc;          /* NaN: the specimen failed (no outline drawn) */
    int nodes;
    double cx, cy;
    const double *r;    /* borrowed; NULL when failed */
    int n;
    double node_threshold_m; /* prominence of a node (drape_shadow) */
    int seed_unknown;   /* 1: seed not known (a run resumed from a checkpoint
                           that did not store it): no data-seed */
} drape_svg_specimen;

/* What the picture shows besides the outlines. */
typedef struct drape_svg_scene {
    const char *title;        /* first legend line, e.g. fabric and scene */
    int table;                /* 0: Cusick (circle on a disk), 1: table */
    double specimen_d_m;      /* Cusick: specimen diameter */
    double support_d_m;       /* Cusick: support disk diameter */
    double width_m, height_m; /* table: the rectangle */
    int table_round;          /* table: 1 round, 0 square */
    double table_size_m;      /* table: side or diameter */
    double dc_mean, dc_ci95;  /* NaN when unknown */
    int n_failed;
    const int *hist;          /* node histogram, hist_n bins */
    int hist_n;
} drape_svg_scene;

/* Write the top view as SVG 1.1 to f: the specimen's outline at rest
 * (dashed), the support disk or table top (grey), each specimen's shadow
 * as one <polygon class="shadow"> (data-seed unless seed_unknown,
 * data-dc, data-nodes), its
 * nodes as small circles, and a legend with the mean DC +- its 95 %
 * half-width and the node histogram.  Returns 0, or -1 when f reports a
 * write error. */
int drape_svg_shadow_write(FILE *f, const drape_svg_scene *sc,
                           const drape_svg_specimen *sp, int n);

/* The same picture as PNG (output_png.c): the SVG text svg[0..len)
 * rendered by librsvg at DRAPE_PNG_DPI (its size in mm from the SVG), or
 * at fewer dots an inch where its longer side would exceed
 * DRAPE_PNG_MAX_SIDE pixels, and encoded by cairo, written to f.  path
 * only names the file in errors.  Returns 0, or -1 with err set (an SVG
 * librsvg cannot read or that has no size, a write error). */
#define DRAPE_PNG_DPI 150.0
#define DRAPE_PNG_MAX_SIDE 3000.0
int drape_png_from_svg(const char *svg, size_t len, FILE *f, const char *path,
                       drape_error *err);

#endif /* DRAPE_OUTPUT_H */

/* output_png.c: the shadow picture as PNG (output.h).
 *
 * The picture is drawn once, as SVG (output_svg.c); the PNG is that SVG
 * rendered by librsvg into a cairo image surface and encoded by cairo's
 * PNG writer (librsvg2-dev, Debian 12: librsvg 2.54, cairo 1.16), so the
 * two files cannot disagree and drape holds no image encoder of its own.
 *
 * Size: the SVG gives its width and height in mm; at DRAPE_PNG_DPI (150,
 * 5.9 pixels a mm) the default Cusick picture (436 x 324 mm with its
 * legend) is 2575 x 1914 pixels, about 0.5 MB, enough to read a fold's
 * node marker (1.6 mm) and the legend's 3 mm text.  A larger picture is
 * drawn at fewer dots an inch, its longer side DRAPE_PNG_MAX_SIDE pixels
 * (the table's, 980 x 870 mm, would be 5799 x 5153 pixels at 150 dpi: a
 * 120 MB image in memory for a 0.5 MB file).  The background is the SVG's own white rectangle.
 *
 * librsvg's calls: rsvg_handle_new_from_data, rsvg_handle_set_dpi,
 * rsvg_handle_get_intrinsic_size_in_pixels (2.52), rsvg_handle_render_document
 * (2.46); cairo_surface_write_to_png_stream.  A GError is turned into the
 * drape_error's message and freed.
 */
#include "drape/output.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <cairo.h>
#include <librsvg/rsvg.h>

/* cairo's PNG writer hands the encoded bytes here; a failed write keeps
 * its errno for the message (cairo's own says only "error while writing
 * to output stream"). */
typedef struct png_out {
    FILE *f;
    int errnum;
} png_out;

static cairo_status_t png_sink(void *closure, const unsigned char *data, unsigned int len)
{
    png_out *o = closure;
    errno = 0;
    if (fwrite(data, 1, len, o->f) == len) return CAIRO_STATUS_SUCCESS;
    if (!o->errnum) o->errnum = errno ? errno : EIO;
    return CAIRO_STATUS_WRITE_ERROR;
}

int drape_png_from_svg(const char *svg, size_t len, FILE *f, const char *path, drape_error *err)
{
    int rc = -1;
    GError *gerr = NULL;
    RsvgHandle *h = NULL;
    cairo_surface_t *s = NULL;
    cairo_t *cr = NULL;

    h = rsvg_handle_new_from_data((const guint8 *)svg, (gsize)len, &gerr);
    if (!h) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "cannot read the picture: %s",
                        gerr ? gerr->message : "librsvg failed");
        goto out;
    }
    rsvg_handle_set_dpi(h, DRAPE_PNG_DPI);
    double w = 0.0, hgt = 0.0;
    int sized = rsvg_handle_get_intrinsic_size_in_pixels(h, &w, &hgt);
    double longer = w > hgt ? w : hgt;
    if (sized && longer > DRAPE_PNG_MAX_SIDE) { /* a larger scene: fewer dots an inch */
        rsvg_handle_set_dpi(h, DRAPE_PNG_DPI * DRAPE_PNG_MAX_SIDE / longer);
        sized = rsvg_handle_get_intrinsic_size_in_pixels(h, &w, &hgt);
    }
    if (!sized || !(w >= 1.0) || !(hgt >= 1.0) || w > DRAPE_PNG_MAX_SIDE + 1.0 ||
        hgt > DRAPE_PNG_MAX_SIDE + 1.0) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL,
                        "the picture has no usable size (%g x %g pixels)", w, hgt);
        goto out;
    }
    int wi = (int)ceil(w), hi = (int)ceil(hgt);
    s = cairo_image_surface_create(CAIRO_FORMAT_RGB24, wi, hi);
    if (cairo_surface_status(s) != CAIRO_STATUS_SUCCESS) {
        drape_error_set(err, DRAPE_E_NOMEM, path, 0, 0, NULL, "cannot make a %d x %d image: %s",
                        wi, hi, cairo_status_to_string(cairo_surface_status(s)));
        goto out;
    }
    cr = cairo_create(s);
    /* white under the SVG's own white background, for pixels it leaves
     * (the rounding up to whole pixels) */
    cairo_set_source_rgb(cr, 1.0, 1.0, 1.0);
    cairo_paint(cr);
    RsvgRectangle vp = {0.0, 0.0, w, hgt};
    if (!rsvg_handle_render_document(h, cr, &vp, &gerr)) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "cannot draw the picture: %s",
                        gerr ? gerr->message : "librsvg failed");
        goto out;
    }
    cairo_surface_flush(s);
    png_out o = {f, 0};
    cairo_status_t st = cairo_surface_write_to_png_stream(s, png_sink, &o);
    if (st != CAIRO_STATUS_SUCCESS) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "cannot write: %s",
                        o.errnum ? strerror(o.errnum) : cairo_status_to_string(st));
        goto out;
    }
    rc = 0;
out:
    if (gerr) g_error_free(gerr);
    if (cr) cairo_destroy(cr);
    if (s) cairo_surface_destroy(s);
    if (h) g_object_unref(h);
    return rc;
}

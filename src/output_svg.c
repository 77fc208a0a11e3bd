/* output_svg.c: the shadow picture of a drape test (output.h,
 * docs/outputs.md).
 *
 * What an image-analysis drape meter shows: the top view, the specimen at
 * rest and its support, and the shadow outline of every specimen
 * overlaid, with the folds (nodes) marked.  Plain SVG 1.1 text (a vector
 * format, written as text; no image encoder).  Coordinates: 1 SVG unit =
 * 1 mm, x to the right, the fabric's y (warp) upwards, centred on the
 * support.  Outline k of a specimen is the polygon
 *     (cx + r_k cos theta_k, cy + r_k sin theta_k),  theta_k = 2 pi k / n,
 * the sampled outer radius of its shadow (drape_dc_radii); nodes are the
 * samples drape_nodes_find marks with the same prominence threshold as
 * the node count.
 */
#include "drape/output.h"

#include <math.h>
#include <stdio.h>

#include "drape/drape.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define SVG_MARGIN_MM 12.0
#define SVG_LEGEND_MM 100.0 /* legend column width */
/* half extent of the drawing up to which the legend keeps its size in mm
 * (the Cusick test's 30 cm specimen with its margin: 162 mm) */
#define SVG_LEGEND_REF_MM 170.0
#define SVG_MAX_NODES 64

/* A distinct hue per specimen, evenly spread (golden angle). */
static void hue(int k, char *out, size_t n)
{
    double h = fmod(k * 137.508, 360.0);
    snprintf(out, n, "hsl(%.0f,70%%,40%%)", h);
}

static void text_escaped(FILE *f, const char *s)
{
    for (; s && *s; s++) {
        if (*s == '<') fputs("&lt;", f);
        else if (*s == '>') fputs("&gt;", f);
        else if (*s == '&') fputs("&amp;", f);
        else if (*s == '"') fputs("&quot;", f);
        /* C0 controls but tab, LF, CR are not XML 1.0 characters, not
         * even as references */
        else if ((unsigned char)*s < 0x20 && *s != '\t' && *s != '\n' && *s != '\r')
            fputc(' ', f);
        /* nor are the noncharacters U+FFFE, U+FFFF (EF BF BE, EF BF BF),
         * which YAML's "\uFFFE" escape makes: shown as U+FFFD */
        else if ((unsigned char)s[0] == 0xEF && (unsigned char)s[1] == 0xBF &&
                 ((unsigned char)s[2] == 0xBE || (unsigned char)s[2] == 0xBF)) {
            fputs("\xEF\xBF\xBD", f);
            s += 2;
        }
        else fputc(*s, f);
    }
}

int drape_svg_shadow_write(FILE *f, const drape_svg_scene *sc,
                           const drape_svg_specimen *sp, int n)
{
    /* half extent of the drawing, mm: the specimen at rest (the table's
     * rectangle: its longer side), or an outline that reaches beyond it */
    double half = sc->table ? 0.5 * 1e3 * fmax(sc->width_m, sc->height_m)
                            : 0.5 * 1e3 * sc->specimen_d_m;
    for (int k = 0; k < n; k++)
        for (int j = 0; sp[k].r && j < sp[k].n; j++)
            if (1e3 * sp[k].r[j] > half) half = 1e3 * sp[k].r[j];
    half += SVG_MARGIN_MM;
    /* the legend grows with a drawing larger than the Cusick test's, so
     * that it keeps its size against the drawing (in a PNG too) */
    double ls = fmax(1.0, half / SVG_LEGEND_REF_MM);
    /* the legend column fits its bold 4 mm title (about 2.6 mm a character) */
    double legend = SVG_LEGEND_MM;
    size_t tl = 0;
    for (const char *c = sc->title; c && *c; c++) tl += ((unsigned char)*c & 0xC0) != 0x80;
    if (8.0 + 2.6 * (double)tl > legend) legend = 8.0 + 2.6 * (double)tl;
    legend *= ls;
    double w = 2.0 * half + legend, h = 2.0 * half;
    if (h < 80.0 * ls) h = 80.0 * ls;
    fprintf(f, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
               "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" "
               "width=\"%.1fmm\" height=\"%.1fmm\" viewBox=\"%.2f %.2f %.2f %.2f\">\n",
            w, h, -half, -half, w, h);
    fputs("<title>drape: shadows of the specimens, top view (1 unit = 1 mm)</title>\n", f);
    fprintf(f, "<rect x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\" fill=\"white\"/>\n",
            -half, -half, w, h);
    /* y up: flip the drawing group, not the legend */
    fputs("<g transform=\"scale(1,-1)\">\n", f);
    if (sc->table) {
        double tw = 1e3 * sc->width_m, th = 1e3 * sc->height_m, ts = 1e3 * sc->table_size_m;
        fprintf(f, "<rect class=\"specimen\" x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\" "
                   "fill=\"none\" stroke=\"black\" stroke-width=\"0.4\" stroke-dasharray=\"3,2\"/>\n",
                -0.5 * tw, -0.5 * th, tw, th);
        if (sc->table_round)
            fprintf(f, "<circle class=\"support\" cx=\"0\" cy=\"0\" r=\"%.2f\" fill=\"#bbb\"/>\n",
                    0.5 * ts);
        else
            fprintf(f, "<rect class=\"support\" x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\" "
                       "fill=\"#bbb\"/>\n", -0.5 * ts, -0.5 * ts, ts, ts);
    } else {
        fprintf(f, "<circle class=\"specimen\" cx=\"0\" cy=\"0\" r=\"%.2f\" fill=\"none\" "
                   "stroke=\"black\" stroke-width=\"0.4\" stroke-dasharray=\"3,2\"/>\n",
                0.5e3 * sc->specimen_d_m);
        fprintf(f, "<circle class=\"support\" cx=\"0\" cy=\"0\" r=\"%.2f\" fill=\"#bbb\"/>\n",
                0.5e3 * sc->support_d_m);
    }
    for (int k = 0; k < n; k++) {
        if (!sp[k].r || !isfinite(sp[k].dc)) continue;
        char col[32];
        hue(k, col, sizeof col);
        fputs("<polygon class=\"shadow\"", f);
        if (!sp[k].seed_unknown) fprintf(f, " data-seed=\"%lu\"", sp[k].seed);
        fprintf(f, " data-dc=\"%.4f\" data-nodes=\"%d\" fill=\"%s\" fill-opacity=\"0.06\" "
                   "stroke=\"%s\" stroke-width=\"0.5\" points=\"",
                sp[k].dc, sp[k].nodes, col, col);
        for (int j = 0; j < sp[k].n; j++) {
            double th = 2.0 * M_PI * j / sp[k].n;
            fprintf(f, "%s%.2f,%.2f", j ? " " : "", 1e3 * (sp[k].cx + sp[k].r[j] * cos(th)),
                    1e3 * (sp[k].cy + sp[k].r[j] * sin(th)));
        }
        fputs("\"/>\n", f);
        int peaks[SVG_MAX_NODES];
        int np = drape_nodes_find(sp[k].r, sp[k].n, sp[k].node_threshold_m, peaks, SVG_MAX_NODES);
        if (np > SVG_MAX_NODES) np = SVG_MAX_NODES;
        for (int q = 0; q < np; q++) {
            double th = 2.0 * M_PI * peaks[q] / sp[k].n, r = sp[k].r[peaks[q]];
            fprintf(f, "<circle class=\"node\" cx=\"%.2f\" cy=\"%.2f\" r=\"1.6\" fill=\"%s\"/>\n",
                    1e3 * (sp[k].cx + r * cos(th)), 1e3 * (sp[k].cy + r * sin(th)), col);
        }
    }
    fputs("</g>\n", f);
    /* legend: at the drawing's top right, its own units scaled by ls */
    double lx = 0.0, ly = 0.0;
    fprintf(f, "<g class=\"legend\" transform=\"translate(%.2f %.2f) scale(%.4g)\" "
               "font-family=\"sans-serif\" font-size=\"4\" fill=\"black\">\n",
            half + 4.0 * ls, -half + 8.0 * ls, ls);
    fprintf(f, "<text x=\"%.2f\" y=\"%.2f\" font-weight=\"bold\">", lx, ly);
    text_escaped(f, sc->title);
    fputs("</text>\n", f);
    ly += 7.0;
    int n_ok = 0;
    for (int k = 0; k < n; k++) n_ok += sp[k].r && isfinite(sp[k].dc);
    fprintf(f, "<text x=\"%.2f\" y=\"%.2f\">%d specimen%s", lx, ly, n, n == 1 ? "" : "s");
    if (sc->n_failed) fprintf(f, ", %d failed", sc->n_failed);
    fputs("</text>\n", f);
    ly += 6.0;
    if (isfinite(sc->dc_mean)) {
        if (isfinite(sc->dc_ci95))
            fprintf(f, "<text x=\"%.2f\" y=\"%.2f\">DC = %.3f &#177; %.3f (95 %%)</text>\n", lx, ly,
                    sc->dc_mean, sc->dc_ci95);
        else
            fprintf(f, "<text x=\"%.2f\" y=\"%.2f\">DC = %.3f</text>\n", lx, ly, sc->dc_mean);
        ly += 8.0;
    }
    fprintf(f, "<text x=\"%.2f\" y=\"%.2f\">nodes: specimens</text>\n", lx, ly);
    ly += 5.0;
    int maxc = 1;
    for (int k = 0; k < sc->hist_n; k++)
        if (sc->hist[k] > maxc) maxc = sc->hist[k];
    for (int k = 0; k < sc->hist_n; k++) {
        if (!sc->hist[k]) continue;
        double bar = 30.0 * sc->hist[k] / maxc;
        fprintf(f, "<text x=\"%.2f\" y=\"%.2f\">%d</text>\n", lx, ly + 3.0, k);
        fprintf(f, "<rect class=\"hist\" x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"3.5\" "
                   "fill=\"#46a\"/>\n", lx + 8.0, ly, bar);
        fprintf(f, "<text x=\"%.2f\" y=\"%.2f\">%d</text>\n", lx + 10.0 + bar, ly + 3.0,
                sc->hist[k]);
        ly += 5.0;
    }
    ly += 3.0;
    fprintf(f, "<text x=\"%.2f\" y=\"%.2f\" font-size=\"3\">grey: support; dashed: specimen "
               "at rest</text>\n", lx, ly);
    fprintf(f, "<text x=\"%.2f\" y=\"%.2f\" font-size=\"3\">dots: nodes; one colour per "
               "specimen (%d drawn)</text>\n", lx, ly + 4.0, n_ok);
    fputs("</g>\n</svg>\n", f);
    return ferror(f) ? -1 : 0;
}

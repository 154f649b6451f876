/* raycast's march compiled from C: the same rays, segments, brick walk and compositing as the
 * numba kernels in march.py (1D TFs), march2d.py (2D TFs: value x gradient magnitude) and
 * march_mixed.py (label volumes: a TF per label, blended across label boundaries, `march_labels`;
 * multi-channel volumes: a TF per channel, their depths added, `march_channels`; read their
 * docstrings for the why of each step), ported line by line so that both draw the same image up to
 * float rounding.
 *
 * Why C beside numba: numba does not vectorize a ray's samples on this kind of CPU (no gathers in
 * its assembly; benchmarks/packet_probe.py), while C with AVX2 gathers reaches about twice numba's
 * samples per second. Built with AVX2 and FMA (`-mavx2 -mfma`), a run of post-classified samples
 * in visible bricks is sampled eight at a time (`run_values8`): positions in double, the trilinear
 * interpolation in single precision, classification and compositing one sample at a time in
 * double so that early termination stops where the scalar march stops. A 2D TF's samples also
 * read the gradient eight at a time (`gradient_length8`: three 32-bit gathers per pair of x
 * neighbours give their six int16 components). Without AVX2 every sample goes through `value`,
 * as in numba.
 *
 * Threads: the caller's thread and `threads - 1` POSIX threads take tiles (or pixels) from a shared
 * counter until none is left, and are joined before the call returns (nothing survives a fork).
 */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <string.h>
#ifdef __AVX2__
#include <immintrin.h>
#endif

#define TILE 8
#define MAX_OPACITY (1.0 - 1e-6)
#define MAX_RUN 64
#define SLIVER 1e-9
#define INLINE static inline __attribute__((always_inline))
/* Python's min and max of two floats (libm's fmin and fmax are calls, not instructions) */
#define MIN(a, b) ((b) < (a) ? (b) : (a))
#define MAX(a, b) ((b) > (a) ? (b) : (a))

typedef struct {
    const void *values; /* (nz, ny, nx) C order; uint8 with 4 bytes readable past the end, or float32 */
    int64_t nx, ny, nz;
    int32_t is_float;
} Grid;

typedef struct {
    const int8_t *distance; /* (nbz, nby, nbx): `EmptyBricks.distance` */
    int64_t nbx, nby, nbz;
    int64_t size;
} Bricks;

typedef struct {
    const double *inverse; /* 4 x 4, row-major */
    int64_t width, height;
    double grid_origin[3], spacing[3], view_dir[3];
    double far_depth;
    const double *phases; /* one per pixel */
    const double *planes; /* (n_planes, 4) */
    int64_t n_planes;
} View;

typedef struct {
    int32_t preintegrated, cap;
    const double *post; /* (n_post, 4) */
    const float *post32; /* the same, single precision (the vector path's opacity) */
    int64_t n_post;
    const float *table; /* (n_table, n_table, 4) */
    int64_t n_table;
    double step, lo, scale;
    /* a 2D TF (`march2d.Table2D`) where two_d: table2d (n_gradient, n_value, 4) holds (r, g, b,
     * extinction per unit length) at value lo + i / scale and gradient magnitude j / g_scale, kinds
     * (n_value - 1 entries, 3 bytes readable past them) each interval's `interval_kinds`; the grid
     * points' gradients (nz, ny, nx, 3) are int16 times gradient_unit (`march2d.Gradients2D`) */
    int32_t two_d;
    const float *table2d;
    int64_t n_value, n_gradient;
    double g_scale;
    const int8_t *kinds;
    const int16_t *gradients;
    double gradient_unit;
    /* a label volume (`march_labels.LabelClassification`) where labelled: labels (nz, ny, nx), 16-bit
     * where labels_wide else 8-bit; lookup (n_lookup) each label's class, -1 hidden (labels past it
     * hidden too); post holds the classes' tables one after the other, n_post entries each */
    int32_t labelled, labels_wide;
    const void *labels;
    const int32_t *lookup;
    int64_t n_lookup;
    const int16_t *cells; /* per cell its corners' class, else MIXED (`volren.model.labels.cell_classes`) */
    /* a multi-channel volume (`march_inputs.ChannelClassification`) where n_channels > 0: channels
     * (n_channels, nz, ny, nx) of the grid's type, post (n_channels, n_post, 4) each channel's (r, g,
     * b, depth per step) at value channel_lo[c] + i / channel_scale[c] */
    int64_t n_channels;
    const void *channels;
    const double *channel_lo, *channel_scale;
} Classes;

#define MIXED (-2)

/* which march a call runs: a 1D TF's, a 2D TF's, a label volume's (`Classes.labelled`) or a
 * multi-channel volume's (`Classes.n_channels`) */
#define KIND_1D 0
#define KIND_2D 1
#define KIND_LABELS 2
#define KIND_CHANNELS 3

#define TRANSPARENT 0
#define FLAT 1

typedef struct {
    double ox, oy, oz, dx, dy, dz, ix, iy, iz, t0, first, last;
    int64_t ns;
} IndexRay;

/* ---- sample placement (volren.kernels.sample_placement) ---- */

INLINE void ray_segments(double length, double h, double phase, int64_t *count, double *first, double *last) {
    if (!(length > SLIVER * h)) {
        *count = 0, *first = 0.0, *last = 0.0;
        return;
    }
    double f = phase > 0.0 ? phase * h : h;
    if (length <= f + SLIVER * h) {
        *count = 1, *first = length, *last = length;
        return;
    }
    double rest = length - f;
    double full = floor(rest / h);
    double rem = rest - full * h;
    if (rem > SLIVER * h)
        *count = (int64_t)full + 2, *first = f, *last = rem;
    else
        *count = (int64_t)full + 1, *first = f, *last = h;
}

INLINE void ray_segment(double t0, double first, double last, double h, int64_t count, int64_t k, double *tk,
                        double *lk) {
    if (k == 0) {
        *tk = t0, *lk = first;
        return;
    }
    *tk = t0 + first + (double)(k - 1) * h;
    *lk = k == count - 1 ? last : h;
}

/* Python's x % 1.0 (a result in [0, 1)), as numba computes it */
INLINE double mod1(double x) {
    double r = fmod(x, 1.0);
    if (r != 0.0 && r < 0.0) r += 1.0;
    return r;
}

/* ---- the march's helpers (march.py) ---- */

INLINE int64_t first_segment_past(double t, double t0, double first, double inv_h, int pre) {
    if (!(t > t0 + first)) return 0;
    return (int64_t)ceil((t - t0 - first) * inv_h + (pre ? 1.0 : 0.5) - 1e-9);
}

INLINE int64_t middles_before(double t, double t0, double first, double last, double h, double inv_h,
                              int64_t ns) {
    if (ns == 0 || !(t > t0 + 0.5 * first)) return 0;
    int64_t c = (int64_t)ceil((t - t0 - first) * inv_h + 0.5);
    if (c < 1) c = 1;
    if (c >= ns) return ns;
    if (c == ns - 1 && ns >= 2 && t0 + first + (double)(ns - 2) * h + 0.5 * last < t) return ns;
    return c;
}

INLINE int64_t clamp_index(double p, int64_t n) {
    int64_t i = (int64_t)p;
    if (i > n - 2) i = n - 2;
    return i < 0 ? 0 : i;
}

INLINE double fetch(const Grid *g, int is_float, int64_t at) {
    return is_float ? (double)((const float *)g->values)[at] : (double)((const uint8_t *)g->values)[at];
}

INLINE double value(const Grid *g, int is_float, double px, double py, double pz) {
    int64_t nx = g->nx, nxy = g->nx * g->ny;
    int64_t i = clamp_index(px, g->nx), j = clamp_index(py, g->ny), k = clamp_index(pz, g->nz);
    double fx = px - (double)i, fy = py - (double)j, fz = pz - (double)k;
    int64_t at = k * nxy + j * nx + i;
    double v000 = fetch(g, is_float, at), v001 = fetch(g, is_float, at + 1);
    double v010 = fetch(g, is_float, at + nx), v011 = fetch(g, is_float, at + nx + 1);
    double v100 = fetch(g, is_float, at + nxy), v101 = fetch(g, is_float, at + nxy + 1);
    double v110 = fetch(g, is_float, at + nxy + nx), v111 = fetch(g, is_float, at + nxy + nx + 1);
    double x00 = v000 + fx * (v001 - v000);
    double x10 = v010 + fx * (v011 - v010);
    double x01 = v100 + fx * (v101 - v100);
    double x11 = v110 + fx * (v111 - v110);
    double y0 = x00 + fy * (x10 - x00);
    double y1 = x01 + fy * (x11 - x01);
    return y0 + fz * (y1 - y0);
}

INLINE double box_exit(const IndexRay *r, double lx, double ly, double lz, double hx, double hy, double hz) {
    double te = INFINITY;
    if (r->dx > 0.0)
        te = MIN(te, (hx - r->ox) * r->ix);
    else if (r->dx < 0.0)
        te = MIN(te, (lx - r->ox) * r->ix);
    if (r->dy > 0.0)
        te = MIN(te, (hy - r->oy) * r->iy);
    else if (r->dy < 0.0)
        te = MIN(te, (ly - r->oy) * r->iy);
    if (r->dz > 0.0)
        te = MIN(te, (hz - r->oz) * r->iz);
    else if (r->dz < 0.0)
        te = MIN(te, (lz - r->oz) * r->iz);
    return te;
}

/* where position x (in entries) lies in a table of n entries: clamped to [0, n - 1], the entry i0
 * before it (at most n - 2) and, returned, the weight of entry i0 + 1 */
INLINE double table_entry(double x, int64_t n, int64_t *i0_out) {
    double f = MIN(MAX(x, 0.0), (double)n - 1.0);
    int64_t i0 = (int64_t)f;
    if (i0 > n - 2) i0 = n - 2;
    *i0_out = i0;
    return f - (double)i0;
}

/* post-classified opacity at value s (per step), interpolated in the table between entries i0 and
 * i0 + 1 with weight w (both returned for the colour) */
INLINE double post_alpha(const Classes *c, double s, int64_t *i0_out, double *w_out) {
    const double *post = c->post;
    int64_t i0;
    double w = table_entry((s - c->lo) * c->scale, c->n_post, &i0);
    *i0_out = i0, *w_out = w;
    return post[4 * i0 + 3] + w * (post[4 * i0 + 7] - post[4 * i0 + 3]);
}

/* post-classified colour and opacity at value s (opacity per step), interpolated in the table */
INLINE double post_lookup(const Classes *c, double s, double *r, double *g, double *b) {
    int64_t i0;
    double w;
    double a = post_alpha(c, s, &i0, &w);
    const double *p = c->post + 4 * i0;
    *r = p[0] + w * (p[4] - p[0]);
    *g = p[1] + w * (p[5] - p[1]);
    *b = p[2] + w * (p[6] - p[2]);
    return a;
}

/* `_classify`: premultiplied (r, g, b, a) of a segment `length` long */
INLINE void classify(const Classes *c, double s, double sb, double length, double out[4]) {
    out[0] = out[1] = out[2] = out[3] = 0.0;
    if (!(isfinite(s) && isfinite(sb))) return;
    double h = c->step;
    if (c->preintegrated) {
        int64_t n = c->n_table;
        int64_t i0, j0;
        double wi = table_entry((s - c->lo) * c->scale, n, &i0), wj = table_entry((sb - c->lo) * c->scale, n, &j0);
        double w00 = (1.0 - wi) * (1.0 - wj), w01 = (1.0 - wi) * wj, w10 = wi * (1.0 - wj), w11 = wi * wj;
        const float *t00 = c->table + 4 * (i0 * n + j0), *t01 = t00 + 4, *t10 = t00 + 4 * n, *t11 = t10 + 4;
        double a = w00 * t00[3] + w01 * t01[3] + w10 * t10[3] + w11 * t11[3];
        if (a <= 0.0) return;
        double r = w00 * t00[0] + w01 * t01[0] + w10 * t10[0] + w11 * t11[0];
        double g = w00 * t00[1] + w01 * t01[1] + w10 * t10[1] + w11 * t11[1];
        double b = w00 * t00[2] + w01 * t01[2] + w10 * t10[2] + w11 * t11[2];
        if (length != h) {
            double a2 = -expm1(length / h * log1p(-MIN(a, MAX_OPACITY)));
            double f = a2 / a;
            out[0] = r * f, out[1] = g * f, out[2] = b * f, out[3] = a2;
            return;
        }
        out[0] = r, out[1] = g, out[2] = b, out[3] = a;
        return;
    }
    double r, g, b;
    double a = post_lookup(c, s, &r, &g, &b);
    if (a <= 0.0) return;
    if (length != h) a = -expm1(length / h * log1p(-MIN(a, MAX_OPACITY)));
    out[0] = r * a, out[1] = g * a, out[2] = b * a, out[3] = a;
}

typedef struct {
    double r, g, b, a;
} Pixel;

/* one post-classified segment of length lk at value s composited onto p; 1 once p is opaque */
INLINE int composite_one(const Classes *c, double s, double lk, Pixel *p, double term) {
    if (!isfinite(s)) return 0;
    int64_t i0;
    double w;
    double ca = post_alpha(c, s, &i0, &w);
    if (ca <= 0.0) return 0;
    if (lk != c->step) ca = -expm1(lk / c->step * log1p(-MIN(ca, MAX_OPACITY)));
    const double *q = c->post + 4 * i0;
    double tr = (1.0 - p->a) * ca;
    p->r += tr * (q[0] + w * (q[4] - q[0]));
    p->g += tr * (q[1] + w * (q[5] - q[1]));
    p->b += tr * (q[2] + w * (q[6] - q[2]));
    p->a += tr;
    return p->a >= term;
}

/* `_gradient_length`: |trilinear interpolant of the grid points' gradient vectors| at index point p */
INLINE double gradient_length(const Grid *g, const Classes *c, double px, double py, double pz) {
    const int64_t nx = g->nx, nxy = g->nx * g->ny;
    int64_t i = clamp_index(px, g->nx), j = clamp_index(py, g->ny), k = clamp_index(pz, g->nz);
    double fx = px - (double)i, fy = py - (double)j, fz = pz - (double)k;
    const int16_t *q = c->gradients + 3 * (k * nxy + j * nx + i);
    const int64_t sy = 3 * nx, sz = 3 * nxy;
    double total = 0.0;
    for (int a = 0; a < 3; a++) {
        double x00 = q[a] + fx * ((double)q[3 + a] - q[a]);
        double x10 = q[sy + a] + fx * ((double)q[sy + 3 + a] - q[sy + a]);
        double x01 = q[sz + a] + fx * ((double)q[sz + 3 + a] - q[sz + a]);
        double x11 = q[sz + sy + a] + fx * ((double)q[sz + sy + 3 + a] - q[sz + sy + a]);
        double y0 = x00 + fy * (x10 - x00), y1 = x01 + fy * (x11 - x01);
        double v = y0 + fz * (y1 - y0);
        total += v * v;
    }
    return sqrt(total) * c->gradient_unit;
}

/* `_bilinear`: channel ch of the 2D table between rows j0 (t0) and j0 + 1 (t1), entries i0, i0 + 1 */
INLINE double bilinear(const float *t0, const float *t1, double wi, double wj, int ch) {
    double a0 = t0[ch] + wi * ((double)t0[4 + ch] - t0[ch]);
    double a1 = t1[ch] + wi * ((double)t1[4 + ch] - t1[ch]);
    return a0 + wj * (a1 - a0);
}

/* `_segment_rgba` composited onto p: a 2D-TF segment lk long at value s, index point (px, py, pz)
 * (whose gradient is read where the table needs it); 1 once p is opaque */
INLINE int composite_one_2d(const Grid *g, const Classes *c, double s, double px, double py, double pz, double lk,
                            Pixel *p, double term) {
    if (!isfinite(s)) return 0;
    const int64_t nv = c->n_value, ng = c->n_gradient;
    int64_t i0, j0;
    double wi = table_entry((s - c->lo) * c->scale, nv, &i0);
    int kind = c->kinds[i0];
    if (kind == TRANSPARENT) return 0;
    double wj = table_entry(kind == FLAT ? 0.0 : gradient_length(g, c, px, py, pz) * c->g_scale, ng, &j0);
    const float *t0 = c->table2d + 4 * (j0 * nv + i0), *t1 = t0 + 4 * nv;
    double tau = bilinear(t0, t1, wi, wj, 3);
    if (!(tau > 0.0)) return 0;
    double alpha = -expm1(-tau * lk), tr = 1.0 - p->a;
    p->r += tr * (bilinear(t0, t1, wi, wj, 0) * alpha);
    p->g += tr * (bilinear(t0, t1, wi, wj, 1) * alpha);
    p->b += tr * (bilinear(t0, t1, wi, wj, 2) * alpha);
    p->a += tr * alpha;
    return p->a >= term;
}

/* the class of the label at offset `at` (`march_labels.label_sample`) */
INLINE int32_t label_class(const Classes *c, int64_t at) {
    int64_t label = c->labels_wide ? ((const uint16_t *)c->labels)[at] : ((const uint8_t *)c->labels)[at];
    return label < c->n_lookup ? c->lookup[label] : -1;
}

/* `march_labels.label_sample` composited onto p: a segment lk long at value s, index point (px, py,
 * pz), its cell's corner classes blended by their trilinear weights; 1 once p is opaque */
INLINE int composite_labels(const Grid *g, const Classes *c, double s, double px, double py, double pz, double lk,
                            Pixel *p, double term) {
    if (!isfinite(s)) return 0;
    const int64_t nx = g->nx, nxy = g->nx * g->ny, n = c->n_post;
    int64_t i = clamp_index(px, g->nx), j = clamp_index(py, g->ny), k = clamp_index(pz, g->nz);
    const int64_t at = k * nxy + j * nx + i;
    const int32_t cell = c->cells[at];
    int64_t i0;
    double w = table_entry((s - c->lo) * c->scale, n, &i0);
    double h = c->step, ca, cr, cg, cb;
    if (cell != MIXED) { /* the fast path: one class at all eight corners */
        if (cell < 0) return 0;
        const double *q = c->post + 4 * (cell * n + i0);
        ca = q[3] + w * (q[7] - q[3]);
        if (ca <= 0.0) return 0;
        if (lk != h) ca = -expm1(lk / h * log1p(-MIN(ca, MAX_OPACITY)));
        cr = q[0] + w * (q[4] - q[0]), cg = q[1] + w * (q[5] - q[1]), cb = q[2] + w * (q[6] - q[2]);
    } else {
        const int64_t corner[8] = {at, at + 1, at + nx, at + nx + 1, at + nxy, at + nxy + 1, at + nxy + nx,
                                   at + nxy + nx + 1};
        double fx = px - (double)i, fy = py - (double)j, fz = pz - (double)k;
        double depth = 0.0, er = 0.0, eg = 0.0, eb = 0.0; /* tau h, and tau h times colour, summed */
        /* each class's log transparency and colour, looked up once however many corners it has: the
         * same numbers as per corner, so the sums (in corner order) are numba's to the bit */
        int32_t seen[8];
        double seen_log[8], seen_rgb[8][3];
        int n_seen = 0;
        for (int q = 0; q < 8; q++) {
            int32_t cls = label_class(c, corner[q]);
            if (cls < 0) continue;
            double wq = (q & 1 ? fx : 1.0 - fx) * (q & 2 ? fy : 1.0 - fy) * (q & 4 ? fz : 1.0 - fz);
            if (wq <= 0.0) continue;
            int e = 0;
            while (e < n_seen && seen[e] != cls) e++;
            if (e == n_seen) {
                const double *row = c->post + 4 * (cls * n + i0);
                double a = row[3] + w * (row[7] - row[3]);
                seen[e] = cls;
                seen_log[e] = a <= 0.0 ? 0.0 : log1p(-MIN(a, MAX_OPACITY)); /* 0: adds nothing */
                seen_rgb[e][0] = row[0] + w * (row[4] - row[0]);
                seen_rgb[e][1] = row[1] + w * (row[5] - row[1]);
                seen_rgb[e][2] = row[2] + w * (row[6] - row[2]);
                n_seen++;
            }
            if (seen_log[e] == 0.0) continue;
            double d = -wq * seen_log[e];
            depth += d;
            er += d * seen_rgb[e][0];
            eg += d * seen_rgb[e][1];
            eb += d * seen_rgb[e][2];
        }
        if (depth <= 0.0) return 0;
        ca = -expm1(-depth * (lk / h));
        cr = er / depth, cg = eg / depth, cb = eb / depth;
    }
    double tr = (1.0 - p->a) * ca;
    p->r += tr * cr;
    p->g += tr * cg;
    p->b += tr * cb;
    p->a += tr;
    return p->a >= term;
}

/* channel ch of a multi-channel volume as a grid */
INLINE Grid channel_grid(const Grid *g, int is_float, const Classes *c, int64_t ch) {
    Grid one = *g;
    const int64_t at = ch * g->nx * g->ny * g->nz;
    one.values = is_float ? (const void *)((const float *)c->channels + at) : (const void *)((const uint8_t *)c->channels + at);
    return one;
}

/* `march_channels.channel_sample` composited onto p: a segment lk long at index point (px, py, pz),
 * every channel looked up at its own value, the depths added; 1 once p is opaque */
INLINE int composite_channels(const Grid *g, int is_float, const Classes *c, double px, double py, double pz,
                              double lk, Pixel *p, double term) {
    const int64_t n = c->n_post;
    double depth = 0.0, er = 0.0, eg = 0.0, eb = 0.0;
    for (int64_t ch = 0; ch < c->n_channels; ch++) {
        Grid one = channel_grid(g, is_float, c, ch);
        double s = value(&one, is_float, px, py, pz);
        if (!isfinite(s)) continue;
        int64_t i0;
        double w = table_entry((s - c->channel_lo[ch]) * c->channel_scale[ch], n, &i0);
        const double *e = c->post + 4 * (ch * n + i0);
        double d = e[3] + w * (e[7] - e[3]);
        if (d <= 0.0) continue;
        depth += d;
        er += d * (e[0] + w * (e[4] - e[0]));
        eg += d * (e[1] + w * (e[5] - e[1]));
        eb += d * (e[2] + w * (e[6] - e[2]));
    }
    if (depth <= 0.0) return 0;
    double ca = -expm1(-depth * (lk / c->step));
    double tr = (1.0 - p->a) * ca;
    p->r += tr * (er / depth);
    p->g += tr * (eg / depth);
    p->b += tr * (eb / depth);
    p->a += tr;
    return p->a >= term;
}

/* one post-classified segment at index point (px, py, pz): a 1D or 2D TF's, a label volume's or a
 * multi-channel volume's */
INLINE int composite_at(const Grid *g, int is_float, int kind, const Classes *c, double px, double py, double pz,
                        double lk, Pixel *p, double term) {
    if (kind == KIND_CHANNELS) return composite_channels(g, is_float, c, px, py, pz, lk, p, term);
    double s = value(g, is_float, px, py, pz);
    if (kind == KIND_LABELS) return composite_labels(g, c, s, px, py, pz, lk, p, term);
    return kind == KIND_2D ? composite_one_2d(g, c, s, px, py, pz, lk, p, term) : composite_one(c, s, lk, p, term);
}

#ifdef __AVX2__
/* the cells of 8 samples: their fractions along each axis, and the offset of their first corner */
typedef struct {
    __m256 f[3];
    __m256i at;
} Cells8;

/* the values at the middles of 8 whole segments kk0 .. kk0 + 7 (tm = base + kk h): positions in
 * double (as the scalar march), cell indices clamped as `value` clamps them (so every read lies in
 * the array, whatever a lane's position), the interpolation in single precision */
INLINE __m256 run_values8(const Grid *g, int is_float, const IndexRay *ray, double base, double h, int64_t kk0,
                          Cells8 *cells) {
    const double k = (double)kk0;
    const __m256d lanes_lo = _mm256_set_pd(k + 3.0, k + 2.0, k + 1.0, k), lanes_hi = _mm256_set_pd(k + 7.0, k + 6.0, k + 5.0, k + 4.0);
    const __m256d vh = _mm256_set1_pd(h), vbase = _mm256_set1_pd(base);
    /* tm = base + kk h for each segment kk, the same whichever lane and chunk it falls in */
    __m256d t_lo = _mm256_fmadd_pd(lanes_lo, vh, vbase), t_hi = _mm256_fmadd_pd(lanes_hi, vh, vbase);
    __m256 f[3];
    __m256i cell[3];
    const double o[3] = {ray->ox, ray->oy, ray->oz}, d[3] = {ray->dx, ray->dy, ray->dz};
    const int64_t n[3] = {g->nx, g->ny, g->nz};
    for (int a = 0; a < 3; a++) {
        __m256d p_lo = _mm256_fmadd_pd(t_lo, _mm256_set1_pd(d[a]), _mm256_set1_pd(o[a]));
        __m256d p_hi = _mm256_fmadd_pd(t_hi, _mm256_set1_pd(d[a]), _mm256_set1_pd(o[a]));
        __m128i i_lo = _mm256_cvttpd_epi32(p_lo), i_hi = _mm256_cvttpd_epi32(p_hi);
        __m256i i = _mm256_set_m128i(i_hi, i_lo);
        i = _mm256_max_epi32(_mm256_min_epi32(i, _mm256_set1_epi32((int)(n[a] - 2))), _mm256_setzero_si256());
        __m128 fl = _mm256_cvtpd_ps(_mm256_sub_pd(p_lo, _mm256_cvtepi32_pd(_mm256_castsi256_si128(i))));
        __m128 fh = _mm256_cvtpd_ps(_mm256_sub_pd(p_hi, _mm256_cvtepi32_pd(_mm256_extracti128_si256(i, 1))));
        f[a] = _mm256_set_m128(fh, fl);
        cell[a] = i;
    }
    const int nx = (int)g->nx, nxy = (int)(g->nx * g->ny);
    __m256i at = _mm256_add_epi32(cell[0], _mm256_add_epi32(_mm256_mullo_epi32(cell[1], _mm256_set1_epi32(nx)),
                                                           _mm256_mullo_epi32(cell[2], _mm256_set1_epi32(nxy))));
    cells->f[0] = f[0], cells->f[1] = f[1], cells->f[2] = f[2], cells->at = at;
    __m256i at_y = _mm256_add_epi32(at, _mm256_set1_epi32(nx)), at_z = _mm256_add_epi32(at, _mm256_set1_epi32(nxy));
    __m256i at_yz = _mm256_add_epi32(at_z, _mm256_set1_epi32(nx));
    __m256 v000, v001, v010, v011, v100, v101, v110, v111;
    if (is_float) {
        const float *v = (const float *)g->values;
        v000 = _mm256_i32gather_ps(v, at, 4), v001 = _mm256_i32gather_ps(v + 1, at, 4);
        v010 = _mm256_i32gather_ps(v, at_y, 4), v011 = _mm256_i32gather_ps(v + 1, at_y, 4);
        v100 = _mm256_i32gather_ps(v, at_z, 4), v101 = _mm256_i32gather_ps(v + 1, at_z, 4);
        v110 = _mm256_i32gather_ps(v, at_yz, 4), v111 = _mm256_i32gather_ps(v + 1, at_yz, 4);
    } else { /* one 32-bit read per pair of neighbours along x: bytes 0 and 1 */
        const int *v = (const int *)g->values;
        const __m256i byte = _mm256_set1_epi32(0xff);
        __m256i p0 = _mm256_i32gather_epi32(v, at, 1), p1 = _mm256_i32gather_epi32(v, at_y, 1);
        __m256i p2 = _mm256_i32gather_epi32(v, at_z, 1), p3 = _mm256_i32gather_epi32(v, at_yz, 1);
        v000 = _mm256_cvtepi32_ps(_mm256_and_si256(p0, byte));
        v001 = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(p0, 8), byte));
        v010 = _mm256_cvtepi32_ps(_mm256_and_si256(p1, byte));
        v011 = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(p1, 8), byte));
        v100 = _mm256_cvtepi32_ps(_mm256_and_si256(p2, byte));
        v101 = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(p2, 8), byte));
        v110 = _mm256_cvtepi32_ps(_mm256_and_si256(p3, byte));
        v111 = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(p3, 8), byte));
    }
    __m256 x00 = _mm256_fmadd_ps(f[0], _mm256_sub_ps(v001, v000), v000);
    __m256 x10 = _mm256_fmadd_ps(f[0], _mm256_sub_ps(v011, v010), v010);
    __m256 x01 = _mm256_fmadd_ps(f[0], _mm256_sub_ps(v101, v100), v100);
    __m256 x11 = _mm256_fmadd_ps(f[0], _mm256_sub_ps(v111, v110), v110);
    __m256 y0 = _mm256_fmadd_ps(f[1], _mm256_sub_ps(x10, x00), x00);
    __m256 y1 = _mm256_fmadd_ps(f[1], _mm256_sub_ps(x11, x01), x01);
    return _mm256_fmadd_ps(f[2], _mm256_sub_ps(y1, y0), y0);
}

/* The post-classified colour (r, g, b) and opacity a of 8 whole segments at values s, interpolated in
 * the single-precision table (`Classes.post32`) as `post_alpha` and `composite_one` do in double;
 * opacity 0 where a value is not finite. Returns the lanes with opacity above 0 as a bit mask (the
 * colours are looked up only when some lane has any). */
INLINE __m256 finite8(__m256 s) {
    return _mm256_and_ps(_mm256_cmp_ps(s, s, _CMP_ORD_Q),
                         _mm256_cmp_ps(_mm256_andnot_ps(_mm256_set1_ps(-0.0f), s), _mm256_set1_ps(INFINITY), _CMP_LT_OQ));
}

/* `table_entry` of 8 positions x in single precision (NaN at entry 0): the weights, the entries in *i0 */
INLINE __m256 table_entry8(__m256 x, int64_t n, __m256i *i0) {
    __m256 f = _mm256_min_ps(_mm256_max_ps(x, _mm256_setzero_ps()), _mm256_set1_ps((float)(n - 1))); /* NaN -> 0 */
    *i0 = _mm256_min_epi32(_mm256_cvttps_epi32(f), _mm256_set1_epi32((int)(n - 2)));
    return _mm256_sub_ps(f, _mm256_cvtepi32_ps(*i0));
}

/* value s's position in the table whose entry 0 is at c->lo, c->scale entries per unit */
INLINE __m256 value_position8(const Classes *c, __m256 s) {
    return _mm256_mul_ps(_mm256_sub_ps(s, _mm256_set1_ps((float)c->lo)), _mm256_set1_ps((float)c->scale));
}

INLINE int run_classes8(const Classes *c, __m256 s, float r[8], float g[8], float b[8], float a[8]) {
    const __m256 zero = _mm256_setzero_ps();
    const float *post = c->post32;
    __m256 finite = finite8(s);
    __m256i i0;
    __m256 w = table_entry8(value_position8(c, s), c->n_post, &i0);
    __m256i at = _mm256_slli_epi32(i0, 2); /* four floats per entry */
    __m256 a0 = _mm256_i32gather_ps(post + 3, at, 4), a1 = _mm256_i32gather_ps(post + 7, at, 4);
    __m256 ca = _mm256_and_ps(_mm256_fmadd_ps(w, _mm256_sub_ps(a1, a0), a0), finite);
    int visible = _mm256_movemask_ps(_mm256_cmp_ps(ca, zero, _CMP_GT_OQ));
    if (!visible) return 0;
    _mm256_storeu_ps(a, ca);
    __m256 c0 = _mm256_i32gather_ps(post, at, 4), c1 = _mm256_i32gather_ps(post + 4, at, 4);
    _mm256_storeu_ps(r, _mm256_fmadd_ps(w, _mm256_sub_ps(c1, c0), c0));
    c0 = _mm256_i32gather_ps(post + 1, at, 4), c1 = _mm256_i32gather_ps(post + 5, at, 4);
    _mm256_storeu_ps(g, _mm256_fmadd_ps(w, _mm256_sub_ps(c1, c0), c0));
    c0 = _mm256_i32gather_ps(post + 2, at, 4), c1 = _mm256_i32gather_ps(post + 6, at, 4);
    _mm256_storeu_ps(b, _mm256_fmadd_ps(w, _mm256_sub_ps(c1, c0), c0));
    return visible;
}

/* `run_classes8` for a label volume: the classes of the 8 samples' cells (`Classes.cells`), each
 * lane looked up in its class's table; the lanes in cells of several classes (MIXED) in *mixed, to be
 * composited one at a time (`composite_labels`), and the other lanes with opacity above 0 returned */
INLINE int run_label_classes8(const Classes *c, __m256 s, const Cells8 *cells, float r[8], float g[8], float b[8],
                              float a[8], int *mixed) {
    const __m256 zero = _mm256_setzero_ps();
    const float *post = c->post32;
    __m256i cls = _mm256_i32gather_epi32((const int *)c->cells, cells->at, 2);
    cls = _mm256_srai_epi32(_mm256_slli_epi32(cls, 16), 16); /* the int16 at each cell, sign extended */
    __m256 finite = finite8(s);
    *mixed = _mm256_movemask_ps(_mm256_and_ps(finite, _mm256_castsi256_ps(_mm256_cmpeq_epi32(cls, _mm256_set1_epi32(MIXED)))));
    __m256 shown = _mm256_and_ps(finite, _mm256_castsi256_ps(_mm256_cmpgt_epi32(cls, _mm256_set1_epi32(-1))));
    if (!_mm256_movemask_ps(shown)) return 0;
    __m256i i0;
    __m256 w = table_entry8(value_position8(c, s), c->n_post, &i0);
    __m256i row = _mm256_mullo_epi32(_mm256_max_epi32(cls, _mm256_setzero_si256()), _mm256_set1_epi32((int)c->n_post));
    __m256i at = _mm256_slli_epi32(_mm256_add_epi32(row, i0), 2); /* four floats per entry */
    __m256 a0 = _mm256_i32gather_ps(post + 3, at, 4), a1 = _mm256_i32gather_ps(post + 7, at, 4);
    __m256 ca = _mm256_and_ps(_mm256_fmadd_ps(w, _mm256_sub_ps(a1, a0), a0), shown);
    int visible = _mm256_movemask_ps(_mm256_cmp_ps(ca, zero, _CMP_GT_OQ));
    if (!visible) return 0;
    _mm256_storeu_ps(a, ca);
    __m256 c0 = _mm256_i32gather_ps(post, at, 4), c1 = _mm256_i32gather_ps(post + 4, at, 4);
    _mm256_storeu_ps(r, _mm256_fmadd_ps(w, _mm256_sub_ps(c1, c0), c0));
    c0 = _mm256_i32gather_ps(post + 1, at, 4), c1 = _mm256_i32gather_ps(post + 5, at, 4);
    _mm256_storeu_ps(g, _mm256_fmadd_ps(w, _mm256_sub_ps(c1, c0), c0));
    c0 = _mm256_i32gather_ps(post + 2, at, 4), c1 = _mm256_i32gather_ps(post + 6, at, 4);
    _mm256_storeu_ps(b, _mm256_fmadd_ps(w, _mm256_sub_ps(c1, c0), c0));
    return visible;
}

INLINE __m256 low16(__m256i x) { return _mm256_cvtepi32_ps(_mm256_srai_epi32(_mm256_slli_epi32(x, 16), 16)); }
INLINE __m256 high16(__m256i x) { return _mm256_cvtepi32_ps(_mm256_srai_epi32(x, 16)); }

/* `gradient_length` of 8 samples in single precision. Per row of x neighbours (y, z corners) three
 * 32-bit gathers at int16 offsets 3 at, 3 at + 2 and 3 at + 4 hold the six components of the pair:
 * (g0, g1 of x), (g2 of x, g0 of x + 1), (g1, g2 of x + 1), all inside the array. */
INLINE __m256 gradient_length8(const Grid *g, const Classes *c, const Cells8 *cells) {
    const int nx = (int)g->nx, nxy = (int)(g->nx * g->ny);
    const int *base = (const int *)c->gradients;
    __m256i row = cells->at;
    const __m256i rows[4] = {row, _mm256_add_epi32(row, _mm256_set1_epi32(nx)),
                             _mm256_add_epi32(row, _mm256_set1_epi32(nxy)),
                             _mm256_add_epi32(row, _mm256_set1_epi32(nxy + nx))};
    __m256 x[4][3]; /* per row, per component: interpolated along x */
    for (int r = 0; r < 4; r++) {
        __m256i at3 = _mm256_add_epi32(rows[r], _mm256_add_epi32(rows[r], rows[r]));
        __m256i p0 = _mm256_i32gather_epi32(base, at3, 2);
        __m256i p1 = _mm256_i32gather_epi32(base, _mm256_add_epi32(at3, _mm256_set1_epi32(2)), 2);
        __m256i p2 = _mm256_i32gather_epi32(base, _mm256_add_epi32(at3, _mm256_set1_epi32(4)), 2);
        __m256 a0 = low16(p0), a1 = high16(p0), a2 = low16(p1), b0 = high16(p1), b1 = low16(p2), b2 = high16(p2);
        x[r][0] = _mm256_fmadd_ps(cells->f[0], _mm256_sub_ps(b0, a0), a0);
        x[r][1] = _mm256_fmadd_ps(cells->f[0], _mm256_sub_ps(b1, a1), a1);
        x[r][2] = _mm256_fmadd_ps(cells->f[0], _mm256_sub_ps(b2, a2), a2);
    }
    __m256 total = _mm256_setzero_ps();
    for (int a = 0; a < 3; a++) {
        __m256 y0 = _mm256_fmadd_ps(cells->f[1], _mm256_sub_ps(x[1][a], x[0][a]), x[0][a]);
        __m256 y1 = _mm256_fmadd_ps(cells->f[1], _mm256_sub_ps(x[3][a], x[2][a]), x[2][a]);
        __m256 v = _mm256_fmadd_ps(cells->f[2], _mm256_sub_ps(y1, y0), y0);
        total = _mm256_fmadd_ps(v, v, total);
    }
    return _mm256_mul_ps(_mm256_sqrt_ps(total), _mm256_set1_ps((float)c->gradient_unit));
}

/* 1 - exp(-x) of x >= 0 (NaN-free) in single precision, to a few units in the last place: the
 * series where x is small (1 - exp(-x) would cancel), else exp(-x) as Cephes' expf computes it
 * (Moshier 1992: 2^n times a degree-5 polynomial on [-ln 2 / 2, ln 2 / 2]) */
INLINE __m256 opacity8(__m256 x) {
    const __m256 one = _mm256_set1_ps(1.0f);
    __m256 series = _mm256_fnmadd_ps(_mm256_mul_ps(x, _mm256_set1_ps(0.2f)), one, one); /* 1 - x/5 */
    series = _mm256_fnmadd_ps(_mm256_mul_ps(x, _mm256_set1_ps(0.25f)), series, one);
    series = _mm256_fnmadd_ps(_mm256_mul_ps(x, _mm256_set1_ps(1.0f / 3.0f)), series, one);
    series = _mm256_fnmadd_ps(_mm256_mul_ps(x, _mm256_set1_ps(0.5f)), series, one);
    series = _mm256_mul_ps(x, series);
    __m256 y = _mm256_max_ps(_mm256_sub_ps(_mm256_setzero_ps(), x), _mm256_set1_ps(-87.0f));
    __m256 n = _mm256_round_ps(_mm256_mul_ps(y, _mm256_set1_ps(1.44269504088896341f)),
                               _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
    __m256 r = _mm256_fnmadd_ps(n, _mm256_set1_ps(0.693359375f), y);
    r = _mm256_fnmadd_ps(n, _mm256_set1_ps(-2.12194440e-4f), r);
    __m256 q = _mm256_set1_ps(1.9875691500e-4f);
    q = _mm256_fmadd_ps(q, r, _mm256_set1_ps(1.3981999507e-3f));
    q = _mm256_fmadd_ps(q, r, _mm256_set1_ps(8.3334519073e-3f));
    q = _mm256_fmadd_ps(q, r, _mm256_set1_ps(4.1665795894e-2f));
    q = _mm256_fmadd_ps(q, r, _mm256_set1_ps(1.6666665459e-1f));
    q = _mm256_fmadd_ps(q, r, _mm256_set1_ps(5.0000001201e-1f));
    __m256 e = _mm256_add_ps(_mm256_fmadd_ps(_mm256_mul_ps(q, r), r, r), one);
    __m256i bits = _mm256_slli_epi32(_mm256_add_epi32(_mm256_cvtps_epi32(n), _mm256_set1_epi32(127)), 23);
    e = _mm256_mul_ps(e, _mm256_castsi256_ps(bits));
    return _mm256_blendv_ps(_mm256_sub_ps(one, e), series, _mm256_cmp_ps(x, _mm256_set1_ps(0.0625f), _CMP_LT_OQ));
}

/* `run_classes8` for a multi-channel volume: the 8 whole segments' channels each interpolated
 * (`run_values8`) and looked up in their tables, the depths added; the colour (r, g, b, not
 * premultiplied) and opacity 1 - exp(-depth); the lanes with opacity above 0 returned */
INLINE int run_channel_classes8(const Grid *g, int is_float, const Classes *c, const IndexRay *ray, double base,
                                double h, int64_t kk, float r[8], float gr[8], float b[8], float a[8]) {
    const __m256 zero = _mm256_setzero_ps();
    const float *post = c->post32;
    const int64_t n = c->n_post;
    __m256 depth = zero, er = zero, eg = zero, eb = zero;
    for (int64_t ch = 0; ch < c->n_channels; ch++) {
        Grid one = channel_grid(g, is_float, c, ch);
        Cells8 cells;
        __m256 s = run_values8(&one, is_float, ray, base, h, kk, &cells);
        __m256 finite = finite8(s);
        __m256i i0;
        __m256 pos = _mm256_mul_ps(_mm256_sub_ps(s, _mm256_set1_ps((float)c->channel_lo[ch])),
                                   _mm256_set1_ps((float)c->channel_scale[ch]));
        __m256 w = table_entry8(pos, n, &i0);
        __m256i at = _mm256_slli_epi32(_mm256_add_epi32(i0, _mm256_set1_epi32((int)(ch * n))), 2);
        __m256 d0 = _mm256_i32gather_ps(post + 3, at, 4), d1 = _mm256_i32gather_ps(post + 7, at, 4);
        __m256 d = _mm256_and_ps(_mm256_max_ps(_mm256_fmadd_ps(w, _mm256_sub_ps(d1, d0), d0), zero), finite);
        if (!_mm256_movemask_ps(_mm256_cmp_ps(d, zero, _CMP_GT_OQ))) continue;
        depth = _mm256_add_ps(depth, d);
        __m256 c0 = _mm256_i32gather_ps(post, at, 4), c1 = _mm256_i32gather_ps(post + 4, at, 4);
        er = _mm256_fmadd_ps(d, _mm256_fmadd_ps(w, _mm256_sub_ps(c1, c0), c0), er);
        c0 = _mm256_i32gather_ps(post + 1, at, 4), c1 = _mm256_i32gather_ps(post + 5, at, 4);
        eg = _mm256_fmadd_ps(d, _mm256_fmadd_ps(w, _mm256_sub_ps(c1, c0), c0), eg);
        c0 = _mm256_i32gather_ps(post + 2, at, 4), c1 = _mm256_i32gather_ps(post + 6, at, 4);
        eb = _mm256_fmadd_ps(d, _mm256_fmadd_ps(w, _mm256_sub_ps(c1, c0), c0), eb);
    }
    __m256 live = _mm256_cmp_ps(depth, zero, _CMP_GT_OQ);
    int visible = _mm256_movemask_ps(live);
    if (!visible) return 0;
    __m256 inv = _mm256_and_ps(_mm256_div_ps(_mm256_set1_ps(1.0f), depth), live);
    _mm256_storeu_ps(a, opacity8(depth));
    _mm256_storeu_ps(r, _mm256_mul_ps(er, inv));
    _mm256_storeu_ps(gr, _mm256_mul_ps(eg, inv));
    _mm256_storeu_ps(b, _mm256_mul_ps(eb, inv));
    return visible;
}

/* channel ch of the 2D table, bilinear at entries e (of (j0, i0)) with weights wi, wj */
INLINE __m256 bilinear8(const float *table, int64_t nv, __m256i e, __m256 wi, __m256 wj, int ch) {
    __m256 t00 = _mm256_i32gather_ps(table + ch, e, 4), t01 = _mm256_i32gather_ps(table + 4 + ch, e, 4);
    __m256 t10 = _mm256_i32gather_ps(table + 4 * nv + ch, e, 4), t11 = _mm256_i32gather_ps(table + 4 * nv + 4 + ch, e, 4);
    __m256 a0 = _mm256_fmadd_ps(wi, _mm256_sub_ps(t01, t00), t00), a1 = _mm256_fmadd_ps(wi, _mm256_sub_ps(t11, t10), t10);
    return _mm256_fmadd_ps(wj, _mm256_sub_ps(a1, a0), a0);
}

/* `run_classes8` for a 2D TF: colour (r, g, b, not premultiplied) and opacity of 8 whole segments
 * (h long) at values s in `cells`, the gradient read only where some lane's interval needs it; the
 * lanes with extinction above 0 as a bit mask */
INLINE int run_classes8_2d(const Grid *g, const Classes *c, __m256 s, const Cells8 *cells, float r[8], float gr[8],
                           float b[8], float alpha[8]) {
    const __m256 zero = _mm256_setzero_ps();
    const int64_t nv = c->n_value, ng = c->n_gradient;
    __m256 finite = finite8(s);
    __m256i i0, j0;
    __m256 wi = table_entry8(value_position8(c, s), nv, &i0);
    __m256i kind = _mm256_and_si256(_mm256_i32gather_epi32((const int *)c->kinds, i0, 1), _mm256_set1_epi32(0xff));
    __m256 live = _mm256_and_ps(finite, _mm256_castsi256_ps(_mm256_cmpgt_epi32(kind, _mm256_set1_epi32(TRANSPARENT))));
    int lanes = _mm256_movemask_ps(live);
    if (!lanes) return 0;
    __m256 fj = zero; /* FLAT intervals read row 0 */
    __m256 graded = _mm256_and_ps(live, _mm256_castsi256_ps(_mm256_cmpgt_epi32(kind, _mm256_set1_epi32(FLAT))));
    if (_mm256_movemask_ps(graded))
        fj = _mm256_and_ps(_mm256_mul_ps(gradient_length8(g, c, cells), _mm256_set1_ps((float)c->g_scale)), graded);
    __m256 wj = table_entry8(fj, ng, &j0);
    __m256i e = _mm256_slli_epi32(_mm256_add_epi32(_mm256_mullo_epi32(j0, _mm256_set1_epi32((int)nv)), i0), 2);
    const float *table = c->table2d;
    __m256 t = _mm256_and_ps(bilinear8(table, nv, e, wi, wj, 3), live);
    int visible = _mm256_movemask_ps(_mm256_cmp_ps(t, zero, _CMP_GT_OQ));
    if (!visible) return 0;
    _mm256_storeu_ps(alpha, opacity8(_mm256_mul_ps(t, _mm256_set1_ps((float)c->step))));
    _mm256_storeu_ps(r, bilinear8(table, nv, e, wi, wj, 0));
    _mm256_storeu_ps(gr, bilinear8(table, nv, e, wi, wj, 1));
    _mm256_storeu_ps(b, bilinear8(table, nv, e, wi, wj, 2));
    return visible;
}
#endif

/* `_composite_post`: the post-classified segments [ka, kb) composited onto p; returns how many
 * were sampled (up to the one that made p opaque) */
INLINE int64_t composite_post(const Grid *g, int is_float, int kind, const Classes *c, const IndexRay *ray,
                              int64_t ka, int64_t kb, Pixel *p, double term) {
    double h = c->step, t0 = ray->t0, first = ray->first, last = ray->last;
    int64_t ns = ray->ns;
    double base = t0 + first - 0.5 * h;
    int64_t kk = ka;
    double tk, lk;
    if (kk == 0 && kk < kb) { /* the first segment, cut by the box */
        ray_segment(t0, first, last, h, ns, 0, &tk, &lk);
        double tm = tk + 0.5 * lk;
        if (composite_at(g, is_float, kind, c, ray->ox + tm * ray->dx, ray->oy + tm * ray->dy, ray->oz + tm * ray->dz,
                         lk, p, term))
            return 1;
        kk = 1;
    }
#ifdef __AVX2__
    /* every whole segment (h long) eight at a time, the last chunk's lanes past the run masked: a
     * segment's colour is the same whichever run and chunk holds it, so skipping changes no pixel.
     * A label volume's samples in cells of several classes are composited one at a time. */
    int64_t whole_end = kb < ns - 1 ? kb : ns - 1; /* segments [kk, whole_end) are h long */
    float cr[8], cg[8], cb[8], ca[8];
    for (int64_t k0 = kk; k0 < whole_end; k0 += 8) {
        kk = k0;
        int lanes = whole_end - kk < 8 ? (1 << (whole_end - kk)) - 1 : 0xff;
        int mixed = 0, visible;
        if (kind == KIND_CHANNELS) {
            visible = lanes & run_channel_classes8(g, is_float, c, ray, base, h, kk, cr, cg, cb, ca);
        } else {
            Cells8 cells;
            __m256 s = run_values8(g, is_float, ray, base, h, kk, &cells);
            visible = lanes & (kind == KIND_LABELS ? run_label_classes8(c, s, &cells, cr, cg, cb, ca, &mixed)
                               : kind == KIND_2D   ? run_classes8_2d(g, c, s, &cells, cr, cg, cb, ca)
                                                   : run_classes8(c, s, cr, cg, cb, ca));
        }
        mixed &= lanes;
        int todo = visible | mixed;
        while (todo) { /* front to back over the lanes with opacity */
            int j = __builtin_ctz(todo);
            todo &= todo - 1;
            if (kind == KIND_LABELS && (mixed >> j & 1)) {
                double tm = base + (double)(kk + j) * h;
                double px = ray->ox + tm * ray->dx, py = ray->oy + tm * ray->dy, pz = ray->oz + tm * ray->dz;
                if (composite_labels(g, c, value(g, is_float, px, py, pz), px, py, pz, h, p, term)) return kk + j + 1 - ka;
                continue;
            }
            double tr = (1.0 - p->a) * ca[j];
            p->r += tr * cr[j];
            p->g += tr * cg[j];
            p->b += tr * cb[j];
            p->a += tr;
            if (p->a >= term) return kk + j + 1 - ka;
        }
    }
    kk = kk > whole_end ? kk : whole_end; /* past the whole segments, where the chunks ended */
#endif
    for (; kk < kb; kk++) {
        double tm;
        if (kk == 0 || kk == ns - 1) {
            ray_segment(t0, first, last, h, ns, kk, &tk, &lk);
            tm = tk + 0.5 * lk;
        } else {
            lk = h;
            tm = base + (double)kk * h;
        }
        if (composite_at(g, is_float, kind, c, ray->ox + tm * ray->dx, ray->oy + tm * ray->dy, ray->oz + tm * ray->dz,
                         lk, p, term))
            return kk + 1 - ka;
    }
    return kb - ka;
}

/* `_cut_face`: the TF's colour at value s, and whether it is visible */
INLINE int cut_face(const Classes *c, double s, double *r, double *g, double *b) {
    if (!isfinite(s)) return 0;
    double a = post_lookup(c, s, r, g, b);
    return a > 0.0;
}

/* `_pixel_ray`: pixel (xx, row at NDC y ny_)'s ray in grid-index space and where it meets the box */
INLINE int pixel_ray(const View *v, double xx, double ny_, double ux, double uy, double uz, IndexRay *ray,
                     double w[3], double *t_in, double *t_out) {
    const double *inv = v->inverse;
    double nx_ = (xx + 0.5) / (double)v->width * 2.0 - 1.0;
    double wn = inv[12] * nx_ + inv[13] * ny_ - inv[14] + inv[15];
    double wf = inv[12] * nx_ + inv[13] * ny_ + inv[14] + inv[15];
    double n0 = (inv[0] * nx_ + inv[1] * ny_ - inv[2] + inv[3]) / wn;
    double n1 = (inv[4] * nx_ + inv[5] * ny_ - inv[6] + inv[7]) / wn;
    double n2 = (inv[8] * nx_ + inv[9] * ny_ - inv[10] + inv[11]) / wn;
    double wx = (inv[0] * nx_ + inv[1] * ny_ + inv[2] + inv[3]) / wf - n0;
    double wy = (inv[4] * nx_ + inv[5] * ny_ + inv[6] + inv[7]) / wf - n1;
    double wz = (inv[8] * nx_ + inv[9] * ny_ + inv[10] + inv[11]) / wf - n2;
    double norm = sqrt(wx * wx + wy * wy + wz * wz);
    wx /= norm, wy /= norm, wz /= norm;
    w[0] = wx, w[1] = wy, w[2] = wz;
    double o[3] = {(n0 - v->grid_origin[0]) / v->spacing[0], (n1 - v->grid_origin[1]) / v->spacing[1],
                   (n2 - v->grid_origin[2]) / v->spacing[2]};
    double d[3] = {wx / v->spacing[0], wy / v->spacing[1], wz / v->spacing[2]};
    double i[3], u[3] = {ux, uy, uz};
    double ti = -INFINITY, to = INFINITY;
    int miss = 0;
    for (int a = 0; a < 3; a++) {
        i[a] = d[a] != 0.0 ? 1.0 / d[a] : INFINITY;
        if (d[a] == 0.0) {
            if (o[a] < 0.0 || o[a] > u[a]) miss = 1;
        } else {
            double ta = (0.0 - o[a]) * i[a], tb = (u[a] - o[a]) * i[a];
            ti = MAX(ti, MIN(ta, tb));
            to = MIN(to, MAX(ta, tb));
        }
    }
    ray->ox = o[0], ray->oy = o[1], ray->oz = o[2];
    ray->dx = d[0], ray->dy = d[1], ray->dz = d[2];
    ray->ix = i[0], ray->iy = i[1], ray->iz = i[2];
    *t_in = ti, *t_out = to;
    return miss;
}

/* `clip_entry` (volren.kernels.clip_planes) */
INLINE int64_t clip_entry(const IndexRay *r, const View *v, double *t0, double *t1) {
    int64_t entering = -1;
    for (int64_t p = 0; p < v->n_planes; p++) {
        const double *q = v->planes + 4 * p;
        double at_origin = q[0] * r->ox + q[1] * r->oy + q[2] * r->oz + q[3];
        double rate = q[0] * r->dx + q[1] * r->dy + q[2] * r->dz;
        if (rate > 0.0) {
            if (-at_origin / rate > *t0) {
                *t0 = -at_origin / rate;
                entering = p;
            }
        } else if (rate < 0.0) {
            *t1 = MIN(*t1, -at_origin / rate);
        } else if (at_origin < 0.0) {
            *t1 = MIN(*t1, *t0);
            return -1;
        }
    }
    return entering;
}

/* a march's counts (march.py's COUNTS): samples taken, distance jumps, segments skipped in empty
 * bricks before the ray stopped, rays that became opaque before their last segment */
typedef struct {
    int64_t samples, jumps, skipped, terminated;
} Counts;

/* The brick walk (a 3D DDA) along a ray from index point (x, y, z): per axis the brick, the next
 * crossing, the crossings' spacing, the step, and the step's offset in the brick array. */
typedef struct {
    int64_t brick[3], step[3], count[3], offset_step[3], offset;
    double next[3], spacing[3];
} Walk;

INLINE void walk_start(Walk *w, const Bricks *br, int shift, const IndexRay *r, int64_t nx, int64_t ny, int64_t nz,
                       double t) {
    const int64_t B = br->size;
    int64_t b[3] = {clamp_index(r->ox + t * r->dx, nx), clamp_index(r->oy + t * r->dy, ny),
                    clamp_index(r->oz + t * r->dz, nz)};
    const double o[3] = {r->ox, r->oy, r->oz}, d[3] = {r->dx, r->dy, r->dz}, inv[3] = {r->ix, r->iy, r->iz};
    w->count[0] = br->nbx, w->count[1] = br->nby, w->count[2] = br->nbz;
    for (int a = 0; a < 3; a++) {
        b[a] = shift >= 0 ? b[a] >> shift : b[a] / B;
        w->brick[a] = b[a];
        w->next[a] = d[a] != 0.0 ? ((double)((b[a] + (d[a] > 0.0)) * B) - o[a]) * inv[a] : INFINITY;
        w->spacing[a] = (double)B * fabs(inv[a]);
        w->step[a] = d[a] > 0.0 ? 1 : -1;
    }
    w->offset_step[0] = w->step[0], w->offset_step[1] = w->step[1] * br->nbx;
    w->offset_step[2] = w->step[2] * br->nbx * br->nby;
    w->offset = (b[2] * br->nby + b[1]) * br->nbx + b[0];
}

INLINE double walk_exit(const Walk *w) { return MIN(w->next[0], MIN(w->next[1], w->next[2])); }

/* into the next brick; 0 once the walk leaves the grid. The axis crossed first (ties to x, then y)
 * is chosen without a branch to mispredict. */
INLINE int walk_step(Walk *w) {
    int ax = w->next[1] < w->next[0] ? 1 : 0;
    ax = w->next[2] < w->next[ax] ? 2 : ax;
    w->brick[ax] += w->step[ax];
    w->next[ax] += w->spacing[ax];
    w->offset += w->offset_step[ax];
    return (uint64_t)w->brick[ax] < (uint64_t)w->count[ax];
}

/* Where a jump out of the box of empty bricks around the walk's brick lands (every brick within
 * d - 1 of it is empty): the first segment whose key point lies past the box's exit. */
INLINE int64_t past_empty_box(const Walk *w, const IndexRay *ray, int d, int64_t B, double inv_h, int pre) {
    double e = (double)(d - 1);
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = ((double)w->brick[a] - e) * (double)B;
        hi[a] = ((double)w->brick[a] + 1 + e) * (double)B;
    }
    double tb = box_exit(ray, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    return first_segment_past(tb, ray->t0, ray->first, inv_h, pre);
}

/* A run's segments from ra to the last whose middle lies before t composited onto p
 * (`composite_post`); returns the segment after them, adds the samples to *taken and, once p is
 * opaque, sets *stop to the segment after the one that made it so. */
INLINE int64_t flush_run(const Grid *g, int is_float, int kind, const Classes *c, const IndexRay *ray, int64_t ra,
                         double t, double inv_h, Pixel *p, double term, int64_t *taken, int64_t *stop) {
    int64_t kb = middles_before(t, ray->t0, ray->first, ray->last, c->step, inv_h, ray->ns);
    int64_t n = kb > ra ? composite_post(g, is_float, kind, c, ray, ra, kb, p, term) : 0;
    *taken += n;
    if (p->a >= term) *stop = ra + n;
    return kb;
}

/* The post-classified ray's walk: empty bricks passed in a tight loop (or their empty box left in
 * one jump), and each run of visible bricks composited whole (`composite_post`) once the walk
 * leaves it, so that a brick costs a step and a read, not a segment count. The segments composited
 * are those whose middles lie in visible bricks, as numba's `_ray` takes them. */
INLINE void walk_post(const Grid *g, int is_float, int kind, const Bricks *br, int shift, const Classes *c,
                      const IndexRay *ray, double t1, double term, Pixel *p, Counts *counts) {
    const int8_t *empty = br->distance;
    const double h = c->step, inv_h = 1.0 / h, span = MAX_RUN * h;
    const double t0 = ray->t0, first = ray->first, last = ray->last;
    const int64_t ns = ray->ns, B = br->size;
    int64_t k = 0, taken = 0, jumps = 0, stop = ns;
    Walk w;
    while (k < ns) {
        double tk, lk;
        ray_segment(t0, first, last, h, ns, k, &tk, &lk);
        double t_entry = tk + 0.5 * lk; /* where the walk (re)starts: segment k's middle */
        walk_start(&w, br, shift, ray, g->nx, g->ny, g->nz, t_entry);
        int d = empty[w.offset];
        int restart = 0;
        for (;;) {
            while (d != 0) { /* empty bricks */
                if (d > 1) { /* empty bricks all around: leave their box in one jump if that skips */
                    int64_t kk = first_segment_past(t_entry, t0, first, inv_h, 0);
                    k = kk > k ? kk : k;
                    int64_t kn = past_empty_box(&w, ray, d, B, inv_h, 0);
                    if (kn > k) {
                        k = kn;
                        jumps++;
                        restart = 1;
                        break;
                    }
                }
                double te = walk_exit(&w);
                if (te >= t1 || !walk_step(&w)) goto done; /* no segment's middle lies further on */
                t_entry = te;
                d = empty[w.offset];
            }
            if (restart) break;
            /* a run of visible bricks from t_entry */
            int64_t ra = first_segment_past(t_entry, t0, first, inv_h, 0);
            ra = ra > k ? ra : k;
            double run_t0 = t_entry, run_te = t_entry;
            int inside = 1;
            while (d == 0) {
                run_te = walk_exit(&w);
                if (run_te >= t1) {
                    inside = 0;
                    break;
                }
                if (run_te - run_t0 >= span) { /* a long run: an opaque ray stops within it, walk no further first */
                    int64_t kb = flush_run(g, is_float, kind, c, ray, ra, run_te, inv_h, p, term, &taken, &stop);
                    if (p->a >= term) goto done;
                    ra = kb > ra ? kb : ra;
                    run_t0 = run_te;
                }
                t_entry = run_te;
                if (!walk_step(&w)) {
                    inside = 0;
                    break;
                }
                d = empty[w.offset];
            }
            int64_t kb = flush_run(g, is_float, kind, c, ray, ra, run_te, inv_h, p, term, &taken, &stop);
            if (p->a >= term) goto done;
            k = kb > k ? kb : k;
            if (!inside || k >= ns) goto done;
        }
    }
done:
    counts->samples += taken;
    counts->jumps += jumps;
    counts->skipped += stop - taken;
    counts->terminated += stop < ns;
}

/* The pre-integrated ray's walk: the segments starting in visible bricks (classified over the cells
 * a segment can reach from them) looked up by their two end values, the back value carried to the
 * next segment; empty bricks passed, or their empty box left in one jump. */
INLINE void walk_pre(const Grid *g, int is_float, const Bricks *br, int shift, const Classes *c, const IndexRay *ray,
                     double term, Pixel *p, Counts *counts) {
    const int8_t *empty = br->distance;
    const double h = c->step, inv_h = 1.0 / h;
    const double t0 = ray->t0, first = ray->first, last = ray->last;
    const double ox = ray->ox, oy = ray->oy, oz = ray->oz, dx = ray->dx, dy = ray->dy, dz = ray->dz;
    const int64_t ns = ray->ns, B = br->size;
    int64_t k = 0, taken = 0, jumps = 0, stop = ns, visited = 0;
    double sb = 0.0; /* the value at segment k's front, when have_front */
    int have_front = 0;
    double cl[4];
    Walk w;
    while (k < ns) {
        double tk, lk;
        ray_segment(t0, first, last, h, ns, k, &tk, &lk);
        walk_start(&w, br, shift, ray, g->nx, g->ny, g->nz, tk);
        int d = empty[w.offset];
        int restart = 0;
        for (;;) {
            if (d > 1) { /* empty bricks all around: leave their box in one jump if that skips */
                int64_t kn = past_empty_box(&w, ray, d, B, inv_h, 1);
                if (kn > k) {
                    k = kn;
                    have_front = 0;
                    jumps++;
                    restart = 1;
                    break;
                }
            }
            double te = walk_exit(&w);
            if (d == 0) {
                while (k < ns) {
                    ray_segment(t0, first, last, h, ns, k, &tk, &lk);
                    if (tk >= te) break;
                    double s;
                    if (!have_front) {
                        s = value(g, is_float, ox + tk * dx, oy + tk * dy, oz + tk * dz);
                        taken++;
                    } else {
                        s = sb;
                    }
                    double tb = tk + lk;
                    sb = value(g, is_float, ox + tb * dx, oy + tb * dy, oz + tb * dz);
                    have_front = 1;
                    taken++;
                    k++;
                    visited++;
                    classify(c, s, sb, lk, cl);
                    if (cl[3] > 0.0) {
                        double tr = 1.0 - p->a;
                        p->r += tr * cl[0];
                        p->g += tr * cl[1];
                        p->b += tr * cl[2];
                        p->a += tr * cl[3];
                        if (p->a >= term) {
                            stop = k;
                            k = ns;
                            break;
                        }
                    }
                }
            } else { /* an empty brick: its segments add nothing */
                int64_t kn = first_segment_past(te, t0, first, inv_h, 1);
                if (kn > k) {
                    k = kn;
                    have_front = 0;
                }
            }
            if (k >= ns || !walk_step(&w)) break;
            d = empty[w.offset];
        }
        if (!restart) break;
    }
    counts->samples += taken;
    counts->jumps += jumps;
    counts->skipped += stop - visited;
    counts->terminated += stop < ns;
}

/* `_ray`: one pixel's ray, clipped, cut into segments and walked front to back through the bricks */
INLINE Pixel march_ray(const Grid *g, int is_float, int kind, const Bricks *br, int shift, const View *v, int64_t xx,
                       double ny_, double phase, const Classes *c, double term, Counts *counts) {
    const double h = c->step;
    const int64_t nx = g->nx, ny = g->ny, nz = g->nz;
    IndexRay ray;
    double w[3], t_in, t_out;
    int miss = pixel_ray(v, (double)xx, ny_, nx - 1.0, ny - 1.0, nz - 1.0, &ray, w, &t_in, &t_out);
    const double ox = ray.ox, oy = ray.oy, oz = ray.oz, dx = ray.dx, dy = ray.dy, dz = ray.dz;
    Pixel p = {0.0, 0.0, 0.0, 0.0};
    double t_far = v->far_depth / (w[0] * v->view_dir[0] + w[1] * v->view_dir[1] + w[2] * v->view_dir[2]);
    double t0 = MAX(t_in, 0.0), t1 = MIN(t_out, t_far);
    int64_t entering = clip_entry(&ray, v, &t0, &t1);
    if (c->cap && entering >= 0 && !miss && t1 > t0) {
        double cr, cg, cb;
        if (cut_face(c, value(g, is_float, ox + t0 * dx, oy + t0 * dy, oz + t0 * dz), &cr, &cg, &cb)) {
            counts->samples += 1;
            return (Pixel){cr, cg, cb, 1.0};
        }
    }
    int64_t ns = 0;
    double first = 0.0, last = 0.0;
    if (!miss && t1 > t0) ray_segments(t1 - t0, h, mod1(phase - t0 / h), &ns, &first, &last);
    ray.t0 = t0, ray.first = first, ray.last = last, ray.ns = ns;
    if (c->preintegrated && kind == KIND_1D)
        walk_pre(g, is_float, br, shift, c, &ray, term, &p, counts);
    else
        walk_post(g, is_float, kind, br, shift, c, &ray, t1, term, &p, counts);
    return p;
}

INLINE void store(float *out, int64_t q, Pixel p) {
    double a = MIN(MAX(p.a, 0.0), 1.0);
    out[4 * q] = (float)MIN(MAX(p.r, 0.0), a);
    out[4 * q + 1] = (float)MIN(MAX(p.g, 0.0), a);
    out[4 * q + 2] = (float)MIN(MAX(p.b, 0.0), a);
    out[4 * q + 3] = (float)a;
}

static int brick_shift(int64_t brick) {
    for (int q = 0; q < 7; q++)
        if ((int64_t)1 << q == brick) return q;
    return -1;
}

/* ---- the work shared among threads ---- */

typedef struct {
    const Grid *grid;
    const Bricks *bricks;
    const View *view;
    const Classes *classes;
    double term;
    const int64_t *items; /* tiles, or pixels */
    int64_t n_items;
    int listed;           /* items are pixels (out[q] is items[q]'s), else tiles */
    float *out;
    int64_t *counts;      /* (n, 4) `Counts`: per tile, or per listed pixel */
    int64_t chunk;        /* items taken at a time */
    int64_t next;         /* the next item to take (atomic) */
} Work;

static void run_item(Work *w, int is_float, int kind, int shift, int64_t q) {
    const View *v = w->view;
    const int64_t width = v->width, height = v->height;
    Counts counts = {0, 0, 0, 0};
    if (w->listed) {
        int64_t px = w->items[q], yy = px / width;
        double ny_ = 1.0 - ((double)yy + 0.5) / (double)height * 2.0;
        Pixel p = march_ray(w->grid, is_float, kind, w->bricks, shift, v, px - yy * width, ny_, v->phases[px], w->classes,
                            w->term, &counts);
        store(w->out, q, p);
        memcpy(w->counts + 4 * q, &counts, sizeof counts);
        return;
    }
    int64_t tile = w->items[q], tiles_x = (width + TILE - 1) / TILE;
    int64_t x0 = (tile % tiles_x) * TILE, y0 = (tile / tiles_x) * TILE;
    int64_t y1 = y0 + TILE < height ? y0 + TILE : height, x1 = x0 + TILE < width ? x0 + TILE : width;
    for (int64_t yy = y0; yy < y1; yy++) {
        double ny_ = 1.0 - ((double)yy + 0.5) / (double)height * 2.0;
        for (int64_t xx = x0; xx < x1; xx++) {
            int64_t px = yy * width + xx;
            Pixel p = march_ray(w->grid, is_float, kind, w->bricks, shift, v, xx, ny_, v->phases[px], w->classes, w->term,
                                &counts);
            store(w->out, px, p);
        }
    }
    memcpy(w->counts + 4 * tile, &counts, sizeof counts);
}

static void *worker(void *arg) {
    Work *w = (Work *)arg;
    const int shift = brick_shift(w->bricks->size);
    for (;;) {
        int64_t start = __atomic_fetch_add(&w->next, w->chunk, __ATOMIC_RELAXED);
        if (start >= w->n_items) break;
        int64_t end = start + w->chunk < w->n_items ? start + w->chunk : w->n_items;
        const int is_float = w->grid->is_float;
        const Classes *c = w->classes;
        const int kind = c->labelled ? KIND_LABELS : c->n_channels > 0 ? KIND_CHANNELS : c->two_d ? KIND_2D : KIND_1D;
        for (int64_t q = start; q < end; q++) { /* each combination compiled apart (always_inline) */
            if (is_float) {
                switch (kind) {
                    case KIND_LABELS: run_item(w, 1, KIND_LABELS, shift, q); break;
                    case KIND_CHANNELS: run_item(w, 1, KIND_CHANNELS, shift, q); break;
                    case KIND_2D: run_item(w, 1, KIND_2D, shift, q); break;
                    default: run_item(w, 1, KIND_1D, shift, q);
                }
            } else {
                switch (kind) {
                    case KIND_LABELS: run_item(w, 0, KIND_LABELS, shift, q); break;
                    case KIND_CHANNELS: run_item(w, 0, KIND_CHANNELS, shift, q); break;
                    case KIND_2D: run_item(w, 0, KIND_2D, shift, q); break;
                    default: run_item(w, 0, KIND_1D, shift, q);
                }
            }
        }
    }
    return NULL;
}

#define MAX_THREADS 256

static int run(Work *w, int threads) {
    pthread_t ids[MAX_THREADS];
    int started = 0;
    if (threads > MAX_THREADS) threads = MAX_THREADS;
    for (int t = 1; t < threads; t++) {
        if (pthread_create(&ids[started], NULL, worker, w) != 0) break;
        started++;
    }
    worker(w);
    for (int t = 0; t < started; t++) pthread_join(ids[t], NULL);
    return 0;
}

/* the tiles `tiles` (indices of the image's TILE x TILE tiles, row-major) into out ((height * width, 4));
 * counts[tile]: `Counts`; numba's `march` */
int march_tiles(const Grid *grid, const Bricks *bricks, const View *view, const Classes *classes, double term,
                const int64_t *tiles, int64_t n_tiles, float *out, int64_t *counts, int threads) {
    Work w = {grid, bricks, view, classes, term, tiles, n_tiles, 0, out, counts, 1, 0};
    return run(&w, threads);
}

/* the listed pixels (row-major indices): out[q] and counts[q] are pixels[q]'s: numba's `march_pixels` */
int march_pixels(const Grid *grid, const Bricks *bricks, const View *view, const Classes *classes, double term,
                 const int64_t *pixels, int64_t n_pixels, float *out, int64_t *counts, int threads, int64_t chunk) {
    Work w = {grid, bricks, view, classes, term, pixels, n_pixels, 1, out, counts, chunk > 0 ? chunk : 16, 0};
    return run(&w, threads);
}

/* whether the library was built with the vector path */
int has_vector_path(void) {
#ifdef __AVX2__
    return 1;
#else
    return 0;
#endif
}

/* tetra's cell walk compiled from C: the same entries, exits, segments and compositing as the numba
 * kernel `traversal.cast_rays` (read its module docstring and `traversal.py` for the why of each
 * step), ported line by line so that both draw the same image up to float rounding.
 *
 * Why C beside numba: the C walk reads the cells it steps through from one record each (`Cell`: planes,
 * gradient, neighbours and flags in three cache lines), where the numba kernel reads six arrays; it tests a
 * cell's four exit faces in one AVX2 vector; it reads both length layers of a pre-integration table entry side
 * by side; and it finds each pixel's entry faces itself, in its threads: 1.8-2.3x numba's frames
 * (`benchmarks.tetra_walk`; what helped and what did not: docs/tetra-benchmark.md).
 *
 * Threads: the caller's thread and `threads - 1` POSIX threads take blocks of rays from a shared
 * counter until none is left, and are joined before the call returns (nothing survives a fork).
 */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#ifdef __AVX2__
#include <immintrin.h>
#endif

#define COMPOSITE 0
#define MAXIMUM 1
#define MINIMUM 2
#define AVERAGE 3
#define MAX_ENTRIES 512
#define RAY_BLOCK 16
#define PARALLEL 1e-12
#define MAX_THREADS 256
#define CELL_BLOCK 4096 /* cells a thread takes at a time where it prepares them */
#define INLINE static inline __attribute__((always_inline))
#define MIN(a, b) ((b) < (a) ? (b) : (a))
#define MAX(a, b) ((b) > (a) ? (b) : (a))

/* flags of a `Cell` */
#define USABLE 1u    /* neither flat nor non-finite (the others are holes) */
#define WALKABLE 2u  /* a walk may run through it at positive length */
#define VISIBLE 4u   /* the TF gives it some opacity */

/* One tetrahedron as the walk reads it at each step (`walk_native.CellRecords`), 192 bytes:
 * inward unit face planes (N, D) with a = N . o + D the signed distance, component by component
 * (plane[k][f]: component k of face f, so that one vector holds a component of all four faces),
 * the linear field's gradient, the cell across each face (-1: none), and the flags above. */
typedef struct {
    double plane[4][4];
    double gradient[3];
    int32_t neighbor[4];
    uint32_t flags;
    uint32_t pad[5];
} Cell;

typedef struct {
    const Cell *cells;
    const double *values;   /* (m, 4) corner values: the first is the field at `corner` */
    const double *corner;   /* (m, 3) */
    const uint8_t *boundary; /* (m, 4) faces where a walk enters the walked cells */
    double on_plane;        /* a ray closer than this to a face plane lies in it */
} Mesh;

/* A frame's projected entry faces (`entry_bins.EntryFaces`) and their lists per tile of pixels (`entry_bins.bin_tiles`):
 * a ray's candidate cells are those of the faces whose triangle covers its pixel (`covers`). */
typedef struct {
    const int64_t *boxes;   /* (k, 5) whole, x0, x1, y0, y1 */
    const double *edges;    /* (k, 3, 3) each edge's line in pixels, positive inside */
    const int64_t *cells;   /* (k,) the cell of each face */
    const int64_t *tile_offsets, *tile_members; /* tile b's faces: tile_members[tile_offsets[b]:tile_offsets[b + 1]] */
    int64_t width, tile;
    double margin;
} Faces;

typedef struct {
    const double *origins, *directions, *far; /* (n, 3), (n, 3), (n,) */
    const int64_t *pixels;                    /* (n,) ray q's pixel, whose faces come first; NULL: none */
    const Faces *faces;
    const int64_t *offsets, *candidates;      /* then these cells: candidates[offsets[q]:offsets[q + 1]] */
    const double *planes;                     /* (n_planes, 4) the kept half-spaces */
    int64_t n_planes;
    int32_t cap;                              /* draw cut faces where rays enter through a plane */
} Rays;

typedef struct {
    const double *depth;    /* (n, n) optical depth per unit length */
    const double *ratio;    /* (n, n, layers, 3) colour per unit opacity */
    int64_t n, layers;
    double lo, scale, lmax;
} Table;

typedef struct {
    const double *cx, *crgb, *ox, *oa; /* colour and opacity control points (`tf_eval.PackedTF`) */
    int64_t nc, no;
} TF;

typedef struct {
    int32_t on;
    double ambient, diffuse, specular, power, gradient_threshold, lx, ly, lz;
} Shade;

typedef struct {
    int32_t mode;
    double termination;
    int64_t max_steps;
} Options;

/* `worker(work)` on the caller's thread and up to `threads - 1` POSIX threads (no more than there are chunks of
 * `chunk` of the `items`), all joined before it returns */
static void run_threads(void *(*worker)(void *), void *work, int threads, int64_t items, int64_t chunk) {
    pthread_t ids[MAX_THREADS];
    int started = 0;
    if (threads > MAX_THREADS) threads = MAX_THREADS;
    for (int t = 1; t < threads && (int64_t)t * chunk < items; t++) {
        if (pthread_create(&ids[started], NULL, worker, work) != 0) break;
        started++;
    }
    worker(work);
    for (int t = 0; t < started; t++) pthread_join(ids[t], NULL);
}

/* ---------------------------------------------------------------- the TF, shading, clipping */

/* k with xs[k] <= s < xs[k + 1] (numpy's searchsorted(side="right") - 1); xs[0] <= s < xs[n - 1] */
INLINE int64_t find_interval(const double *xs, int64_t n, double s) {
    int64_t lo = 0, hi = n;
    while (lo < hi) {
        int64_t mid = (lo + hi) / 2;
        if (xs[mid] <= s) lo = mid + 1;
        else hi = mid;
    }
    return lo - 1;
}

static double tf_opacity(const TF *tf, double s) {
    const double *xs = tf->ox, *ys = tf->oa;
    int64_t n = tf->no;
    if (s <= xs[0]) return ys[0];
    if (s >= xs[n - 1]) return ys[n - 1];
    int64_t k = find_interval(xs, n, s);
    double w = (s - xs[k]) / (xs[k + 1] - xs[k]);
    return ys[k] + (ys[k + 1] - ys[k]) * w;
}

static void tf_color(const TF *tf, double s, double rgb[3]) {
    const double *xs = tf->cx, *c = tf->crgb;
    int64_t n = tf->nc;
    if (s <= xs[0]) {
        for (int i = 0; i < 3; i++) rgb[i] = c[i];
        return;
    }
    if (s >= xs[n - 1]) {
        for (int i = 0; i < 3; i++) rgb[i] = c[3 * (n - 1) + i];
        return;
    }
    int64_t k = find_interval(xs, n, s);
    double w = (s - xs[k]) / (xs[k + 1] - xs[k]);
    for (int i = 0; i < 3; i++) rgb[i] = c[3 * k + i] + (c[3 * (k + 1) + i] - c[3 * k + i]) * w;
}

/* `shading.blinn_phong_factors`: (diffuse factor, specular term) */
INLINE void blinn_phong(double gx, double gy, double gz, double hx, double hy, double hz, const Shade *sp,
                        double *diffuse, double *specular) {
    double mag = sqrt(gx * gx + gy * gy + gz * gz);
    if (!(mag > sp->gradient_threshold) || !isfinite(mag)) {
        *diffuse = 1.0;
        *specular = 0.0;
        return;
    }
    double nx = -gx / mag, ny = -gy / mag, nz = -gz / mag;
    double ndl = nx * sp->lx + ny * sp->ly + nz * sp->lz;
    if (ndl < 0.0) {
        nx = -nx, ny = -ny, nz = -nz, ndl = -ndl;
    }
    double ndh = nx * hx + ny * hy + nz * hz;
    *diffuse = sp->ambient + sp->diffuse * ndl;
    *specular = sp->specular * pow(MAX(ndh, 0.0), sp->power);
}

INLINE double clamp01(double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); }

/* `shading.headlight_half_vector` */
INLINE void half_vector(double lx, double ly, double lz, double dx, double dy, double dz, double h[3]) {
    double hx = lx - dx, hy = ly - dy, hz = lz - dz;
    double n = sqrt(hx * hx + hy * hy + hz * hz);
    if (n > 0.0) {
        h[0] = hx / n, h[1] = hy / n, h[2] = hz / n;
    } else {
        h[0] = h[1] = h[2] = 0.0;
    }
}

/* `cut_faces.cut_face`: the face's colour into rgb; 0 where it is not visible */
static int cut_face(const TF *tf, double s, double nx, double ny, double nz, const Shade *sp, double dx, double dy,
                    double dz, double rgb[3]) {
    if (!isfinite(s) || !(tf_opacity(tf, s) > 0.0)) return 0;
    tf_color(tf, s, rgb);
    if (sp->on) {
        double scale = 1.0 + 4.0 * sp->gradient_threshold, h[3], k, spec;
        half_vector(sp->lx, sp->ly, sp->lz, dx, dy, dz, h);
        blinn_phong(nx * scale, ny * scale, nz * scale, h[0], h[1], h[2], sp, &k, &spec);
        for (int i = 0; i < 3; i++) rgb[i] = clamp01(rgb[i] * k + spec);
    }
    return 1;
}

/* `clip_planes.clip_entry`: (t0, t1) narrowed to the kept region; the plane the ray enters through, or -1 */
INLINE int64_t clip_entry(const double o[3], const double d[3], const double *planes, int64_t n, double *t0,
                          double *t1) {
    int64_t entering = -1;
    for (int64_t p = 0; p < n; p++) {
        const double *pl = planes + 4 * p;
        double at_origin = pl[0] * o[0] + pl[1] * o[1] + pl[2] * o[2] + pl[3];
        double rate = pl[0] * d[0] + pl[1] * d[1] + pl[2] * d[2];
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

/* ---------------------------------------------------------------- segments */

INLINE double bilinear(const double *t, int64_t n, int64_t stride, int64_t i0, int64_t j0, double fi, double fj) {
    const double *a = t + (i0 * n + j0) * stride;
    const double *b = a + n * stride;
    return (1.0 - fi) * ((1.0 - fj) * a[0] + fj * a[stride]) + fi * ((1.0 - fj) * b[0] + fj * b[stride]);
}

/* `traversal.integrate_segment`: premultiplied (r, g, b, alpha) of a segment from the 3D table. The colour ratios
 * are laid out (n, n, layers, 3) (`walk_native.cast_rays`), so that the two length layers of an entry are six
 * doubles in a row; alpha is 1 - exp(-depth), whose absolute error (1e-16) is expm1's at three quarters of its
 * cost (libm's exp is table-driven, its expm1 is not). */
INLINE void integrate_segment(const Table *tab, double s_front, double s_back, double length, double rgba[4]) {
    const int64_t n = tab->n, layers = tab->layers;
    double x = MIN(MAX((s_front - tab->lo) * tab->scale, 0.0), n - 1.0);
    double y = MIN(MAX((s_back - tab->lo) * tab->scale, 0.0), n - 1.0);
    int64_t i0 = MIN((int64_t)x, n - 2), j0 = MIN((int64_t)y, n - 2);
    double fi = x - i0, fj = y - j0;
    const double w00 = (1.0 - fi) * (1.0 - fj), w01 = (1.0 - fi) * fj, w10 = fi * (1.0 - fj), w11 = fi * fj;
    const double *dp = tab->depth + i0 * n + j0;
    double depth = length * (w00 * dp[0] + w01 * dp[1] + w10 * dp[n] + w11 * dp[n + 1]);
    double alpha = 1.0 - exp(-depth);
    double u = MIN(MAX(layers * length / tab->lmax - 1.0, 0.0), layers - 1.0);
    int64_t k0 = MIN((int64_t)u, layers - 2); /* the layers k0 and k0 + 1, w = 1 at the last */
    double w = u - k0;
    const int64_t entry = 3 * layers, row = n * entry;
    const double *p00 = tab->ratio + i0 * row + j0 * entry + 3 * k0, *p01 = p00 + entry, *p10 = p00 + row,
                 *p11 = p10 + entry;
    double v[6];
    for (int i = 0; i < 6; i++) v[i] = w00 * p00[i] + w01 * p01[i] + w10 * p10[i] + w11 * p11[i];
    for (int c = 0; c < 3; c++) rgba[c] = ((1.0 - w) * v[c] + w * v[3 + c]) * alpha;
    rgba[3] = alpha;
}

/* ---------------------------------------------------------------- the walk */

/* (a, b) of face f of cell c: the ray is inside the face's half-space where a + b t >= 0 (the sums in
 * numba's order, without fused multiply-adds, so that both walks round alike) */
INLINE void plane_ab(const Cell *c, int f, const double o[3], const double d[3], double *a, double *b) {
    *a = c->plane[0][f] * o[0] + c->plane[1][f] * o[1] + c->plane[2][f] * o[2] + c->plane[3][f];
    *b = c->plane[0][f] * d[0] + c->plane[1][f] * d[1] + c->plane[2][f] * d[2];
}

/* `traversal._symbolic_inside` */
INLINE int symbolic_inside(const Cell *c, int f) {
    for (int k = 0; k < 3; k++)
        if (c->plane[k][f] != 0.0) return c->plane[k][f] > 0.0;
    return 0;
}

/* `traversal._exit`: the face the ray leaves cell c through (its parameter in *t_out), or -1; one face after
 * another, as numba does */
INLINE int exit_face_scalar(const Cell *c, const double o[3], const double d[3], double on_plane, double *t_out) {
    double best = INFINITY;
    int face = -1;
    for (int f = 0; f < 4; f++) {
        double a, b;
        plane_ab(c, f, o, d, &a, &b);
        if (b < -PARALLEL) {
            if (-a / b < best) {
                best = -a / b;
                face = f;
            }
        } else if (b <= PARALLEL && fabs(a) <= on_plane && !symbolic_inside(c, f)) {
            *t_out = -INFINITY;
            return f;
        }
    }
    *t_out = best;
    return face;
}

#ifdef __AVX2__
/* `exit_face_scalar` with the four faces in one vector: the same a, b and -a / b bit for bit (multiplies and adds
 * apart, in the same order), the first face of the least parameter, and the rare face the ray lies in left to the
 * scalar path. */
INLINE int exit_face(const Cell *c, const double o[3], const double d[3], double on_plane, double *t_out) {
    const __m256d nx = _mm256_load_pd(c->plane[0]), ny = _mm256_load_pd(c->plane[1]),
                  nz = _mm256_load_pd(c->plane[2]), dd = _mm256_load_pd(c->plane[3]);
    __m256d a = _mm256_add_pd(_mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(nx, _mm256_set1_pd(o[0])),
                                                          _mm256_mul_pd(ny, _mm256_set1_pd(o[1]))),
                                            _mm256_mul_pd(nz, _mm256_set1_pd(o[2]))),
                              dd);
    __m256d b = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(nx, _mm256_set1_pd(d[0])), _mm256_mul_pd(ny, _mm256_set1_pd(d[1]))),
                              _mm256_mul_pd(nz, _mm256_set1_pd(d[2])));
    const __m256d sign = _mm256_set1_pd(-0.0);
    __m256d flat = _mm256_and_pd(_mm256_cmp_pd(_mm256_andnot_pd(sign, b), _mm256_set1_pd(PARALLEL), _CMP_LE_OQ),
                                 _mm256_cmp_pd(_mm256_andnot_pd(sign, a), _mm256_set1_pd(on_plane), _CMP_LE_OQ));
    if (__builtin_expect(_mm256_movemask_pd(flat) != 0, 0)) return exit_face_scalar(c, o, d, on_plane, t_out);
    __m256d leaving = _mm256_cmp_pd(b, _mm256_set1_pd(-PARALLEL), _CMP_LT_OQ);
    __m256d t = _mm256_blendv_pd(_mm256_set1_pd(INFINITY), _mm256_div_pd(_mm256_xor_pd(a, sign), b), leaving);
    __m256d m = _mm256_min_pd(t, _mm256_permute_pd(t, 0x5));
    m = _mm256_min_pd(m, _mm256_permute2f128_pd(m, m, 0x01));
    int at = _mm256_movemask_pd(_mm256_and_pd(_mm256_cmp_pd(t, m, _CMP_EQ_OQ), leaving));
    if (at == 0) {
        *t_out = INFINITY;
        return -1;
    }
    *t_out = _mm256_cvtsd_f64(m);
    return __builtin_ctz(at);
}
#else
#define exit_face exit_face_scalar
#endif

/* `entry_bins._covers`: whether pixel centre (x, y) lies in face i's box and within the margin of its triangle */
INLINE int covers(const Faces *f, int64_t i, int64_t x, int64_t y) {
    const int64_t *b = f->boxes + 5 * i;
    if (!(b[1] <= x && x <= b[2] && b[3] <= y && y <= b[4])) return 0;
    if (b[0]) return 1;
    const double *e = f->edges + 9 * i;
    for (int k = 0; k < 3; k++)
        if (e[3 * k] * (double)x + e[3 * k + 1] * (double)y + e[3 * k + 2] < -f->margin) return 0;
    return 1;
}

/* `traversal._entries` for candidate cell t: inserts its entry into the sorted lists (count, dropped updated) */
INLINE void entry(const Rays *rays, const Mesh *mesh, int64_t q, int64_t t, const double o[3], const double d[3],
                  double *ts, int64_t *ids, double *svals, int64_t *count, int64_t *dropped) {
    const double tmax = rays->far[q], on_plane = mesh->on_plane;
    const Cell *c = mesh->cells + t;
    const uint8_t *boundary = mesh->boundary + 4 * t;
    double t0 = -1.0;
    int inside_at_origin = 1;
    for (int f = 0; f < 4; f++) {
        double a, b;
        plane_ab(c, f, o, d, &a, &b);
        if (a < -on_plane) inside_at_origin = 0;
        if (!boundary[f] || !(b > PARALLEL)) continue;
        double t_hit = -a / b;
        if (!(0.0 <= t_hit && t_hit <= tmax) || (t0 >= 0.0 && t_hit >= t0)) continue;
        int on_triangle = 1;
        for (int g = 0; g < 4; g++) {
            if (g == f) continue;
            double ag, bg;
            plane_ab(c, g, o, d, &ag, &bg);
            if (ag + bg * t_hit < -on_plane) on_triangle = 0;
        }
        if (on_triangle) t0 = t_hit;
    }
    if (inside_at_origin) t0 = 0.0;
    if (t0 < 0.0) return;
    const double *g = c->gradient, *p = mesh->corner + 3 * t;
    double s0 = mesh->values[4 * t] + g[0] * (o[0] + t0 * d[0] - p[0]) + g[1] * (o[1] + t0 * d[1] - p[1]) +
                g[2] * (o[2] + t0 * d[2] - p[2]);
    if (*count == MAX_ENTRIES) {
        (*dropped)++;
        return;
    }
    int64_t i = *count;
    while (i > 0 && ts[i - 1] > t0) {
        ts[i] = ts[i - 1], ids[i] = ids[i - 1], svals[i] = svals[i - 1];
        i--;
    }
    ts[i] = t0, ids[i] = t, svals[i] = s0;
    (*count)++;
}

/* ray q's entries sorted by t into ts, ids, svals, from the faces covering its pixel (in face order, as
 * `entry_bins.bin_triangles` lists them) and then its listed cells; their count (*dropped: those past MAX_ENTRIES) */
static int64_t entries(const Rays *rays, const Mesh *mesh, int64_t q, const double o[3], const double d[3],
                       double *ts, int64_t *ids, double *svals, int64_t *dropped) {
    int64_t count = 0;
    *dropped = 0;
    if (rays->pixels != NULL) {
        const Faces *f = rays->faces;
        const int64_t px = rays->pixels[q], x = px % f->width, y = px / f->width;
        const int64_t b = (y / f->tile) * ((f->width + f->tile - 1) / f->tile) + x / f->tile;
        for (int64_t k = f->tile_offsets[b]; k < f->tile_offsets[b + 1]; k++) {
            int64_t i = f->tile_members[k];
            if (covers(f, i, x, y)) entry(rays, mesh, q, f->cells[i], o, d, ts, ids, svals, &count, dropped);
        }
    }
    for (int64_t k = rays->offsets[q]; k < rays->offsets[q + 1]; k++)
        entry(rays, mesh, q, rays->candidates[k], o, d, ts, ids, svals, &count, dropped);
    return count;
}

typedef struct {
    const Rays *rays;
    const Mesh *mesh;
    const Table *table;
    const TF *tf;
    const Shade *sp;
    const Options *options;
    int64_t n;
    double *out;     /* (n, 4) */
    int64_t *stats;  /* (n, 4) cell steps, cells integrated, walks cut, entries dropped; NULL: not kept */
    int64_t *totals; /* (5,) their sums and the rays that took a step */
    int64_t next;    /* the next block of rays to take (atomic) */
} Work;

/* ray q's pixel into out[q]: composites clipped to valid premultiplied colours (0 <= rgb <= alpha <= 1), as
 * `TetraRenderer._pixels` clips numba's; its counters added to `sums` (`Work.totals`) and kept in w->stats */
static void cast_ray(const Work *w, int64_t q, double *ts, int64_t *ids, double *svals, int64_t sums[5]) {
    const Rays *rays = w->rays;
    const Mesh *mesh = w->mesh;
    const Cell *cells = mesh->cells;
    const Shade *sp = w->sp;
    const int mode = w->options->mode;
    const double termination = w->options->termination, on_plane = mesh->on_plane;
    const int64_t max_steps = w->options->max_steps;
    double *out = w->out + 4 * q;
    int64_t none[4], *stats = w->stats != NULL ? w->stats + 4 * q : none;
    for (int c = 0; c < 4; c++) out[c] = 0.0, stats[c] = 0;
    if (rays->pixels == NULL && rays->offsets[q + 1] == rays->offsets[q]) return;
    const double o[3] = {rays->origins[3 * q], rays->origins[3 * q + 1], rays->origins[3 * q + 2]};
    const double d[3] = {rays->directions[3 * q], rays->directions[3 * q + 1], rays->directions[3 * q + 2]};
    /* the part of the ray the clip region keeps, the far plane included */
    double keep0 = 0.0, keep1 = rays->far[q];
    int64_t entering = clip_entry(o, d, rays->planes, rays->n_planes, &keep0, &keep1);
    if (!(keep1 > keep0)) return;
    int face_pending = rays->cap && entering >= 0 && mode == COMPOSITE;
    int64_t dropped;
    int64_t count = entries(rays, mesh, q, o, d, ts, ids, svals, &dropped);
    stats[3] = dropped;
    sums[3] += dropped;
    if (count == 0) return;
    double h[3];
    half_vector(sp->lx, sp->ly, sp->lz, d[0], d[1], d[2], h);
    double cr = 0.0, cg = 0.0, cb = 0.0, trans = 1.0, best = 0.0, integral = 0.0, total = 0.0;
    int found = 0, done = 0;
    int64_t steps = 0, integrated = 0, cut = 0;
    double t_done = -INFINITY;
    for (int64_t e = 0; e < count && !done; e++) {
        if (ts[e] < t_done) continue;
        if (ts[e] >= keep1) break;
        int64_t t = ids[e];
        double t_in = ts[e], s_in = svals[e], t_out = t_in;
        int64_t walked = 0;
        for (;;) {
            const Cell *c = cells + t;
            int face = exit_face(c, o, d, on_plane, &t_out);
            if (face < 0) break;
            if (t_out < t_in) t_out = t_in;
            if (t_out > keep1) t_out = keep1;
            if (t_out > t_in && !(c->flags & WALKABLE)) {
                t_out = t_in; /* the ray leaves the walked cells here */
                break;
            }
            /* the field is linear in the cell: exact along the ray from the entry value */
            const double *g = c->gradient;
            double slope = g[0] * d[0] + g[1] * d[1] + g[2] * d[2];
            double s_out = s_in + slope * (t_out - t_in);
            double t_kept = MAX(t_in, keep0);
            double s_kept = t_kept > t_in ? s_in + slope * (t_kept - t_in) : s_in;
            double length = t_out - t_kept;
            steps++;
            walked++;
            if (face_pending && t_in <= keep0 && keep0 < t_out) { /* the cell where the ray enters through a plane */
                face_pending = 0;
                const double *pn = rays->planes + 4 * entering;
                double rgb[3];
                if (cut_face(w->tf, s_kept, pn[0], pn[1], pn[2], sp, d[0], d[1], d[2], rgb)) {
                    cr = rgb[0], cg = rgb[1], cb = rgb[2], trans = 0.0; /* opaque: nothing behind it shows */
                    done = 1;
                    break;
                }
            }
            if (length > 0.0) {
                if (mode != COMPOSITE) {
                    if (mode == AVERAGE) {
                        integral += 0.5 * (s_kept + s_out) * length;
                        total += length;
                    } else {
                        double v = mode == MAXIMUM ? MAX(s_kept, s_out) : MIN(s_kept, s_out);
                        if (!found || (mode == MAXIMUM && v > best) || (mode == MINIMUM && v < best)) best = v;
                    }
                    found = 1;
                } else if (c->flags & VISIBLE) {
                    double rgba[4];
                    integrate_segment(w->table, s_kept, s_out, length, rgba);
                    if (sp->on) {
                        double diffuse, specular;
                        blinn_phong(g[0], g[1], g[2], h[0], h[1], h[2], sp, &diffuse, &specular);
                        for (int i = 0; i < 3; i++) rgba[i] = MIN(rgba[i] * diffuse + specular * rgba[3], rgba[3]);
                    }
                    cr += trans * rgba[0];
                    cg += trans * rgba[1];
                    cb += trans * rgba[2];
                    trans *= 1.0 - rgba[3];
                    integrated++;
                    if (1.0 - trans >= termination) {
                        done = 1;
                        break;
                    }
                }
            }
            if (t_out >= keep1) {
                done = 1;
                break;
            }
            int32_t nb = c->neighbor[face];
            if (nb < 0 || !(cells[nb].flags & USABLE)) break;
            if (walked >= max_steps) {
                cut++;
                break;
            }
            t = nb;
            t_in = t_out;
            s_in = s_out;
        }
        t_done = t_out;
    }
    stats[0] = steps, stats[1] = integrated, stats[2] = cut;
    sums[0] += steps, sums[1] += integrated, sums[2] += cut, sums[4] += steps > 0;
    if (mode != COMPOSITE) {
        if (found) {
            out[0] = mode == AVERAGE ? integral / total : best;
            out[1] = 1.0;
        }
    } else {
        double a = MIN(MAX(1.0 - trans, 0.0), 1.0);
        out[0] = MIN(MIN(MAX(cr, 0.0), 1.0), a), out[1] = MIN(MIN(MAX(cg, 0.0), 1.0), a);
        out[2] = MIN(MIN(MAX(cb, 0.0), 1.0), a), out[3] = a;
    }
}

static void *worker(void *arg) {
    Work *w = (Work *)arg;
    double ts[MAX_ENTRIES], svals[MAX_ENTRIES];
    int64_t ids[MAX_ENTRIES];
    int64_t sums[5] = {0, 0, 0, 0, 0};
    for (;;) {
        int64_t start = __atomic_fetch_add(&w->next, RAY_BLOCK, __ATOMIC_RELAXED);
        if (start >= w->n) break;
        int64_t end = MIN(start + RAY_BLOCK, w->n);
        for (int64_t q = start; q < end; q++) cast_ray(w, q, ts, ids, svals, sums);
    }
    for (int k = 0; k < 5; k++) __atomic_fetch_add(&w->totals[k], sums[k], __ATOMIC_RELAXED);
    return NULL;
}

/* n rays through the mesh: numba's `traversal.cast_rays`, out (n, 4) (composites clipped) and stats (n, 4) as it
 * writes them (stats NULL: not kept); totals (5,) += the sums of the stats and the rays that took a step */
int cast_rays(const Rays *rays, const Mesh *mesh, const Table *table, const TF *tf, const Shade *sp,
              const Options *options, int64_t n, double *out, int64_t *stats, int64_t *totals, int threads) {
    Work w = {rays, mesh, table, tf, sp, options, n, out, stats, totals, 0};
    run_threads(worker, &w, threads, n, RAY_BLOCK);
    return 0;
}

/* ---------------------------------------------------------------- the face planes */

typedef struct {
    const double *points; /* (p, 3) */
    const int64_t *tets;  /* (m, 4) */
    int64_t m;
    double *out;          /* (m, 4, 4) */
    int64_t next;         /* the next block of cells to take (atomic) */
} Planes;

/* face f's corners (opposite corner f), as `model.tet_mesh.FACE_VERTICES` */
static const int FACES[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

static void cell_planes(const double *points, const int64_t *tet, double *out) {
    for (int f = 0; f < 4; f++) {
        int64_t a = tet[FACES[f][0]], b = tet[FACES[f][1]], c = tet[FACES[f][2]], s;
        if (a > b) s = a, a = b, b = s;
        if (b > c) s = b, b = c, c = s;
        if (a > b) s = a, a = b, b = s;
        const double *pa = points + 3 * a, *pb = points + 3 * b, *pc = points + 3 * c, *po = points + 3 * tet[f];
        double ux = pb[0] - pa[0], uy = pb[1] - pa[1], uz = pb[2] - pa[2];
        double vx = pc[0] - pa[0], vy = pc[1] - pa[1], vz = pc[2] - pa[2];
        double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
        double side = nx * (po[0] - pa[0]) + ny * (po[1] - pa[1]) + nz * (po[2] - pa[2]);
        double sigma = side > 0.0 ? 1.0 : -1.0;
        double length = sqrt(nx * nx + ny * ny + nz * nz);
        double scale = sigma / (length > 0.0 ? length : 1.0);
        double ix = nx * scale, iy = ny * scale, iz = nz * scale;
        double *p = out + 4 * f;
        p[0] = ix, p[1] = iy, p[2] = iz;
        p[3] = -(ix * pa[0] + iy * pa[1] + iz * pa[2]);
    }
}

static void *planes_worker(void *arg) {
    Planes *w = (Planes *)arg;
    for (;;) {
        int64_t start = __atomic_fetch_add(&w->next, CELL_BLOCK, __ATOMIC_RELAXED);
        if (start >= w->m) break;
        int64_t end = MIN(start + CELL_BLOCK, w->m);
        for (int64_t t = start; t < end; t++) cell_planes(w->points, w->tets + 4 * t, w->out + 16 * t);
    }
    return NULL;
}

/* `tet_planes.packed_face_planes`: the (m, 4, 4) inward unit face planes of the cells */
int packed_planes(const double *points, const int64_t *tets, int64_t m, double *out, int threads) {
    Planes w = {points, tets, m, out, 0};
    run_threads(planes_worker, &w, threads, m, CELL_BLOCK);
    return 0;
}

/* ---------------------------------------------------------------- the cell records */

typedef struct {
    const double *planes;    /* (m, 4, 4) face by face, as `packed_planes` writes them */
    const double *gradients; /* (m, 3) */
    const int64_t *neighbors; /* (m, 4) */
    const uint8_t *usable;   /* (m,) */
    int64_t m;
    Cell *out;
    int64_t next; /* the next block of cells to take (atomic) */
} Fill;

static void *fill_worker(void *arg) {
    Fill *w = (Fill *)arg;
    for (;;) {
        int64_t start = __atomic_fetch_add(&w->next, CELL_BLOCK, __ATOMIC_RELAXED);
        if (start >= w->m) break;
        int64_t end = MIN(start + CELL_BLOCK, w->m);
        for (int64_t t = start; t < end; t++) {
            Cell *c = w->out + t;
            memset(c, 0, sizeof *c);
            for (int f = 0; f < 4; f++) {
                for (int k = 0; k < 4; k++) c->plane[k][f] = w->planes[16 * t + 4 * f + k];
                c->neighbor[f] = (int32_t)w->neighbors[4 * t + f];
            }
            for (int k = 0; k < 3; k++) c->gradient[k] = w->gradients[3 * t + k];
            c->flags = w->usable[t] ? USABLE : 0u;
        }
    }
    return NULL;
}

/* the walk's records of m cells (flags: USABLE only; `walk_native.CellRecords` sets the others) */
int fill_cells(const double *planes, const double *gradients, const int64_t *neighbors, const uint8_t *usable,
               int64_t m, Cell *out, int threads) {
    Fill w = {planes, gradients, neighbors, usable, m, out, 0};
    run_threads(fill_worker, &w, threads, m, CELL_BLOCK);
    return 0;
}

/* bytes of a `Cell` (the Python side checks its layout against it) */
int64_t cell_bytes(void) { return (int64_t)sizeof(Cell); }

/* rotoprint._native: the DLP path's hot kernels in C, built with the machine's compiler at
 * install (setuptools; optional: without a compiler the numba kernels are used).
 *
 * - fill():      the binary fibre fill of a cross-section (slicing/_kernels.fill_jit, the same
 *                crossings, operations and sort).
 * - section():   a mesh's cross-section at height z (same operations, in the same order, as
 *                slicing/_kernels.section_kernel and _sections.section_numpy).
 * - coverage():  exact area coverage into uint8 grey levels (masks/_coverage_kernels:
 *                accumulate_jit then resolve_grey_jit, the same floating-point operations),
 *                rounded so that the window's grey sum is the exact area to 1/2 level; made
 *                row by row (one row's accumulator in cache, not the window's).
 * - window_stats(): a window's grey sum and the bounding box of its non-zero pixels.
 * - thumb_rgb():  a thumbnail's resized, coloured pixels (io/formats/_common.thumbnail_png's
 *                operations in the same order).
 * - png_grey():  an 8-bit greyscale PNG of a mostly empty image given as a window at (r0, c0)
 *                of an otherwise black (H, W) image, optionally mirrored. Rows equal to the
 *                row above are filtered "Up" (all zero) and rows outside the window are zero:
 *                runs of such rows are copied from deflate chunks compressed once per
 *                (width, filter byte, run length 2^k) and byte-aligned by a sync flush, except
 *                short runs and runs of up to 1024 Up rows, which are deflated with the other
 *                rows; those are left unfiltered ("None"); zlib's run-length strategy.
 *
 * - preload():   dlopen a shared library with the GIL released (the fast ``dlp`` entry loads
 *                numpy's core extension this way on the second core while the first one goes on
 *                importing; numpy's own import then finds it loaded).
 *
 * All of them release the GIL. Inputs are buffers (numpy arrays); the Python side (the
 * validating public functions) checks shapes, dtypes and contiguity before calling.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

/* ------------------------------------------------------------------------ section */

static PyObject *
native_section(PyObject *self, PyObject *args)
{
    Py_buffer V, F, FE, faces, start, end, se, ee;
    double z;
    if (!PyArg_ParseTuple(args, "y*y*y*y*dw*w*w*w*", &V, &F, &FE, &faces, &z, &start, &end, &se, &ee))
        return NULL;
    const double *v = (const double *)V.buf;
    const int64_t *f = (const int64_t *)F.buf;
    const int64_t *fe = (const int64_t *)FE.buf;
    const int64_t *fi = (const int64_t *)faces.buf;
    double *st = (double *)start.buf, *en = (double *)end.buf;
    int64_t *sev = (int64_t *)se.buf, *eev = (int64_t *)ee.buf;
    Py_ssize_t n = faces.len / (Py_ssize_t)sizeof(int64_t);
    Py_ssize_t nf = F.len / (Py_ssize_t)(3 * sizeof(int64_t));
    Py_ssize_t nv = V.len / (Py_ssize_t)(3 * sizeof(double));
    int bad = 0;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t k = 0; k < n && !bad; k++) {
        int64_t face = fi[k];
        if (face < 0 || face >= nf) { bad = 1; break; }
        int64_t vid[3] = {f[3 * face], f[3 * face + 1], f[3 * face + 2]};
        if (vid[0] < 0 || vid[0] >= nv || vid[1] < 0 || vid[1] >= nv || vid[2] < 0 || vid[2] >= nv) { bad = 1; break; }
        int ab[3];
        for (int s = 0; s < 3; s++) ab[s] = v[3 * vid[s] + 2] >= z;
        for (int s = 0; s < 3; s++) {
            int nx = (s + 1) % 3;
            int64_t va = vid[s], vb = vid[nx], lo, hi;
            double *out;
            if (!ab[s] && ab[nx]) {        /* from below to above: the segment ends here */
                lo = va; hi = vb; out = en + 2 * k; eev[k] = fe[3 * face + s];
            } else if (ab[s] && !ab[nx]) { /* from above to below: the segment starts here */
                lo = vb; hi = va; out = st + 2 * k; sev[k] = fe[3 * face + s];
            } else {
                continue;
            }
            double zl = v[3 * lo + 2];
            double t = (z - zl) / (v[3 * hi + 2] - zl);
            out[0] = v[3 * lo] + t * (v[3 * hi] - v[3 * lo]);
            out[1] = v[3 * lo + 1] + t * (v[3 * hi + 1] - v[3 * lo + 1]);
        }
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&V); PyBuffer_Release(&F); PyBuffer_Release(&FE); PyBuffer_Release(&faces);
    PyBuffer_Release(&start); PyBuffer_Release(&end); PyBuffer_Release(&se); PyBuffer_Release(&ee);
    if (bad) {
        PyErr_SetString(PyExc_IndexError, "face or vertex index out of range");
        return NULL;
    }
    Py_RETURN_NONE;
}

/* ------------------------------------------------------------------------ coverage */

static inline double
piece_cover(double a, double b, long k)
{
    /* mean over x in [a, b] of clamp(k + 1 - x, 0, 1), a <= b */
    if (b - a <= 0.0) {
        double t = k + 1.0 - a;
        return t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    }
    double left = (b < (double)k ? b : (double)k) - a;
    if (left < 0.0) left = 0.0;
    double lo = a > (double)k ? a : (double)k;
    double hi = b < k + 1.0 ? b : k + 1.0;
    double mid = 0.0;
    if (hi > lo) mid = (hi - lo) * (k + 1.0 - 0.5 * (lo + hi));
    return (left + mid) / (b - a);
}

/* One segment as the accumulation sees it: oriented downwards (ya < yb), ``sign`` its
 * winding, rows r0 <= r < r1 of the window that it crosses. */
typedef struct {
    double xa, ya, xb, yb, sign, slope;
    long r0, r1;
} cseg;

/* Add segment ``g``'s coverage of row ``r`` (which it crosses) into ``row`` (width + 1). */
static inline void
add_row(const cseg *g, long r, long width, double *row)
{
    double ya = g->ya, yb = g->yb, xa = g->xa, xb = g->xb;
    double top = ya > r ? ya : (double)r;
    double bot = yb < r + 1.0 ? yb : r + 1.0;
    if (bot <= top) return;
    double xt, xbm;
    if (top == ya) xt = xa;
    else if (top == yb) xt = xb;
    else xt = xa + (top - ya) * g->slope;
    if (bot == yb) xbm = xb;
    else xbm = xa + (bot - ya) * g->slope;
    double d = g->sign * (bot - top);
    double a = xt <= xbm ? xt : xbm;
    double b = xt <= xbm ? xbm : xt;
    double fa = floor(a), fb = floor(b);
    if (fb < 0.0) { row[0] += d; return; }
    if (fa >= width) return;
    long k0 = fa > 0.0 ? (long)fa : 0;
    long k1 = fb < width - 1 ? (long)fb : width - 1;
    for (long k = k0; k <= k1; k++) {
        double c = d * piece_cover(a, b, k);
        row[k] += c;
        row[k + 1] -= c;
    }
    row[k1 + 1] += d;
}

/* masks/coverage.COVERAGE_SNAP: coverage this close to 0 or 1 is 0 or 1 */
#define COVERAGE_SNAP 1e-12

/* The coverage of a window, row by row: each row's accumulator (width + 1 doubles, kept in
 * cache) gets the contributions of the segments crossing it, in segment order -- the same
 * additions into each cell, in the same order, as accumulating segment by segment into a
 * whole (height, width + 1) array (masks/_coverage_kernels.accumulate_jit) -- and is then
 * resolved into grey levels (sum-preserving rounding: the rounding error carried in
 * row-major order, |carry| <= 1/2 level; resolve_grey_jit's operations). Returns -1 when
 * out of memory. */
static int
coverage_rows(const double *x0s, const double *y0s, const double *x1s, const double *y1s, Py_ssize_t n,
              long height, long width, uint8_t *out, uint8_t *tail)
{
    cseg *segs = (cseg *)malloc((size_t)(n > 0 ? n : 1) * sizeof(cseg));
    Py_ssize_t *first = (Py_ssize_t *)calloc((size_t)height + 1, sizeof(Py_ssize_t));
    Py_ssize_t *order = (Py_ssize_t *)malloc((size_t)(n > 0 ? n : 1) * sizeof(Py_ssize_t));
    Py_ssize_t *act = (Py_ssize_t *)malloc((size_t)(n > 0 ? n : 1) * sizeof(Py_ssize_t));
    Py_ssize_t *act2 = (Py_ssize_t *)malloc((size_t)(n > 0 ? n : 1) * sizeof(Py_ssize_t));
    double *row = (double *)calloc((size_t)width + 1, sizeof(double));
    int rc = (segs && first && order && act && act2 && row) ? 0 : -1;
    Py_ssize_t m = 0;
    if (rc == 0) {
        for (Py_ssize_t s = 0; s < n; s++) {
            double ya = y0s[s] + 0.5, yb = y1s[s] + 0.5;
            if (ya == yb) continue;
            double xa = x0s[s] + 0.5, xb = x1s[s] + 0.5, sign = 1.0;
            if (ya > yb) {
                double t;
                sign = -1.0;
                t = xa; xa = xb; xb = t;
                t = ya; ya = yb; yb = t;
            }
            if (yb <= 0.0 || ya >= height) continue;
            cseg *g = &segs[m];
            g->xa = xa; g->ya = ya; g->xb = xb; g->yb = yb; g->sign = sign;
            g->slope = (xb - xa) / (yb - ya);
            g->r0 = ya > 0.0 ? (long)floor(ya) : 0;
            g->r1 = yb < height ? (long)ceil(yb) : height;
            if (g->r1 <= g->r0) continue;
            first[g->r0 + 1]++;
            m++;
        }
        /* segments by first row, in segment order within a row (a stable counting sort) */
        for (long r = 0; r < height; r++) first[r + 1] += first[r];
        Py_ssize_t *pos = (Py_ssize_t *)malloc((size_t)height * sizeof(Py_ssize_t));
        if (pos == NULL) {
            rc = -1;
        } else {
            for (long r = 0; r < height; r++) pos[r] = first[r];
            for (Py_ssize_t i = 0; i < m; i++) order[pos[segs[i].r0]++] = i;
            free(pos);
        }
    }
    double carry = 0.0;
    Py_ssize_t na = 0;
    for (long r = 0; rc == 0 && r < height; r++) {
        /* the segments crossing row r, in segment order: those still active merged with
         * those starting here */
        Py_ssize_t i = 0, j = first[r], je = first[r + 1], nb = 0;
        while (i < na || j < je) {
            Py_ssize_t k;
            if (j >= je || (i < na && act[i] < order[j])) k = act[i++];
            else k = order[j++];
            if (segs[k].r1 > r) act2[nb++] = k;
        }
        Py_ssize_t *t = act; act = act2; act2 = t;
        na = nb;
        for (Py_ssize_t q = 0; q < na; q++) add_row(&segs[act[q]], r, width, row);
        uint8_t *o = out + r * width;
        double run = 0.0;
        for (long k = 0; k < width; k++) {
            run += row[k];
            row[k] = 0.0;
            double v = fabs(run);
            if (v > 1.0 - COVERAGE_SNAP) {
                o[k] = 255;
            } else if (v < COVERAGE_SNAP) { /* outside, or a residue of the running sum */
                o[k] = 0;
            } else {
                double x = v * 255.0;
                double qv = floor(x + carry + 0.5);
                if (qv < 0.0) qv = 0.0;
                else if (qv > 255.0) qv = 255.0;
                carry += x - qv;
                o[k] = (uint8_t)qv;
            }
        }
        run += row[width];
        row[width] = 0.0;
        double v = fabs(run);
        tail[r] = v >= 1.0 ? 255 : (uint8_t)floor(v * 255.0 + 0.5);
    }
    free(segs); free(first); free(order); free(act); free(act2); free(row);
    return rc;
}

static PyObject *
native_coverage(PyObject *self, PyObject *args)
{
    /* coverage(x0, y0, x1, y1, height, width, out[height * width] uint8, tail[height] uint8) */
    Py_buffer X0, Y0, X1, Y1, OUT, TAIL;
    long h, w;
    if (!PyArg_ParseTuple(args, "y*y*y*y*llw*w*", &X0, &Y0, &X1, &Y1, &h, &w, &OUT, &TAIL))
        return NULL;
    Py_ssize_t n = X0.len / (Py_ssize_t)sizeof(double);
    int rc = -1;
    if (h > 0 && w > 0) {
        Py_BEGIN_ALLOW_THREADS
        rc = coverage_rows((const double *)X0.buf, (const double *)Y0.buf, (const double *)X1.buf,
                           (const double *)Y1.buf, n, h, w, (uint8_t *)OUT.buf, (uint8_t *)TAIL.buf);
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&X0); PyBuffer_Release(&Y0); PyBuffer_Release(&X1); PyBuffer_Release(&Y1);
    PyBuffer_Release(&OUT); PyBuffer_Release(&TAIL);
    if (rc) return PyErr_NoMemory();
    Py_RETURN_NONE;
}

/* window_stats(window uint8 (hh * ww), hh, ww) -> (sum, first row, last row + 1, first column,
 * last column + 1) of the non-zero pixels ((sum, 0, 0, 0, 0) when all are zero): one pass. */
static PyObject *
native_window_stats(PyObject *self, PyObject *args)
{
    Py_buffer W;
    long hh, ww;
    if (!PyArg_ParseTuple(args, "y*ll", &W, &hh, &ww)) return NULL;
    if (hh < 0 || ww < 0 || W.len < (Py_ssize_t)hh * ww) {
        PyBuffer_Release(&W);
        PyErr_SetString(PyExc_ValueError, "window_stats: buffer smaller than the window");
        return NULL;
    }
    unsigned long long total = 0;
    long r0 = -1, r1 = 0, c0 = ww, c1 = 0;
    Py_BEGIN_ALLOW_THREADS
    const uint8_t *p = (const uint8_t *)W.buf;
    for (long r = 0; r < hh; r++) {
        const uint8_t *q = p + r * ww;
        long a = 0;
        while (a < ww && q[a] == 0) a++;
        if (a == ww) continue;
        long b = ww - 1;
        while (q[b] == 0) b--;
        unsigned long long rs = 0;
        for (long k = a; k <= b; k++) rs += q[k];
        total += rs;
        if (r0 < 0) r0 = r;
        r1 = r + 1;
        if (a < c0) c0 = a;
        if (b + 1 > c1) c1 = b + 1;
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&W);
    if (r0 < 0) return Py_BuildValue("(Kllll)", total, 0L, 0L, 0L, 0L);
    return Py_BuildValue("(Kllll)", total, r0, r1, c0, c1);
}

/* ------------------------------------------------------------------------ thumbnails */

/* thumb_rgb(crop uint8 (ch * cw), ch, cw, nh, nw, out uint8 (nh * nw * 3), c0r, c1r, c0g, c1g,
 * c0b, c1b): io/formats/_common._area_resize of ``crop`` to (nh, nw) -- rows first, then
 * columns; a box average over each output pixel's span of whole input pixels when
 * shrinking (sums of doubles in index order, as numpy's add.reduceat, then divided by the
 * span), the nearest input pixel when growing -- then each channel k
 * rint(c0k + (c1k - c0k) * (g / 255.0)): thumbnail_png's operations, in the same order. */
static PyObject *
native_thumb_rgb(PyObject *self, PyObject *args)
{
    Py_buffer C, OUT;
    long ch, cw, nh, nw;
    int c0[3], c1[3];
    if (!PyArg_ParseTuple(args, "y*llllw*iiiiii", &C, &ch, &cw, &nh, &nw, &OUT, &c0[0], &c1[0], &c0[1], &c1[1],
                          &c0[2], &c1[2]))
        return NULL;
    if (ch <= 0 || cw <= 0 || nh <= 0 || nw <= 0 || C.len < (Py_ssize_t)ch * cw || OUT.len < (Py_ssize_t)nh * nw * 3) {
        PyBuffer_Release(&C); PyBuffer_Release(&OUT);
        PyErr_SetString(PyExc_ValueError, "thumb_rgb: buffers smaller than the sizes");
        return NULL;
    }
    double *t = (double *)malloc((size_t)nh * (size_t)cw * sizeof(double));
    double *line = (double *)malloc((size_t)nw * sizeof(double));
    if (t == NULL || line == NULL) {
        free(t); free(line);
        PyBuffer_Release(&C); PyBuffer_Release(&OUT);
        return PyErr_NoMemory();
    }
    const uint8_t *a = (const uint8_t *)C.buf;
    uint8_t *out = (uint8_t *)OUT.buf;
    Py_BEGIN_ALLOW_THREADS
    if (nh >= ch && nw >= cw) {
        /* growing both ways: every output pixel is an input level v, whose colour is the
         * same operations on (double)v: a table of the 256 */
        uint8_t lut[256][3];
        for (int v = 0; v < 256; v++) {
            double g = (double)v / 255.0;
            for (int k = 0; k < 3; k++) {
                double x = (double)(c1[k] - c0[k]) * g;
                x = (double)c0[k] + x;
                lut[v][k] = (uint8_t)rint(x);
            }
        }
        for (long i = 0; i < nh; i++) {
            long r = (long)(((long long)i * ch) / nh);
            if (r > ch - 1) r = ch - 1;
            const uint8_t *src = a + r * cw;
            uint8_t *o = out + i * nw * 3;
            for (long j = 0; j < nw; j++) {
                long c = (long)(((long long)j * cw) / nw);
                if (c > cw - 1) c = cw - 1;
                const uint8_t *l = lut[src[c]];
                o[3 * j] = l[0]; o[3 * j + 1] = l[1]; o[3 * j + 2] = l[2];
            }
        }
        nh = 0; /* done */
    }
    /* rows */
    for (long i = 0; i < nh; i++) {
        double *ti = t + i * cw;
        if (nh >= ch) {
            long r = (long)(((long long)i * ch) / nh);
            if (r > ch - 1) r = ch - 1;
            for (long c = 0; c < cw; c++) ti[c] = (double)a[r * cw + c];
        } else {
            long e0 = (long)(((long long)i * ch + nh / 2) / nh);
            long e1 = (long)(((long long)(i + 1) * ch + nh / 2) / nh);
            for (long c = 0; c < cw; c++) ti[c] = (double)a[e0 * cw + c];
            for (long r = e0 + 1; r < e1; r++)
                for (long c = 0; c < cw; c++) ti[c] += (double)a[r * cw + c];
            double n = (double)(e1 - e0);
            for (long c = 0; c < cw; c++) ti[c] = ti[c] / n;
        }
    }
    /* columns, then the colours */
    for (long i = 0; i < nh; i++) {
        const double *ti = t + i * cw;
        for (long j = 0; j < nw; j++) {
            if (nw >= cw) {
                long c = (long)(((long long)j * cw) / nw);
                if (c > cw - 1) c = cw - 1;
                line[j] = ti[c];
            } else {
                long e0 = (long)(((long long)j * cw + nw / 2) / nw);
                long e1 = (long)(((long long)(j + 1) * cw + nw / 2) / nw);
                double sum = ti[e0];
                for (long c = e0 + 1; c < e1; c++) sum += ti[c];
                line[j] = sum / (double)(e1 - e0);
            }
        }
        uint8_t *o = out + i * nw * 3;
        for (long j = 0; j < nw; j++) {
            double g = line[j] / 255.0;
            for (int k = 0; k < 3; k++) {
                double x = (double)(c1[k] - c0[k]) * g;
                x = (double)c0[k] + x;
                o[3 * j + k] = (uint8_t)rint(x);
            }
        }
    }
    Py_END_ALLOW_THREADS
    free(t); free(line);
    PyBuffer_Release(&C); PyBuffer_Release(&OUT);
    Py_RETURN_NONE;
}

/* ------------------------------------------------------------------------ PNG */

#define ADLER_MOD 65521u
#define MAX_RUN_BITS 20

typedef struct {
    size_t len;
    unsigned char *data;
} chunk_t;

/* Cached sync-flushed deflate chunks of 2^k rows of [fbyte, 0 * width]. */
typedef struct cache_entry {
    long width;
    int fbyte;
    int level;
    chunk_t runs[MAX_RUN_BITS];
    struct cache_entry *next;
} cache_entry;

static cache_entry *g_cache = NULL;
static pthread_mutex_t g_cache_lock = PTHREAD_MUTEX_INITIALIZER;

typedef struct {
    unsigned char *buf;
    size_t len, cap;
    int oom;
} outbuf;

static void
ob_reserve(outbuf *o, size_t extra)
{
    if (o->oom || o->len + extra <= o->cap) return;
    size_t cap = o->cap ? o->cap : 4096;
    while (cap < o->len + extra) cap *= 2;
    unsigned char *p = (unsigned char *)realloc(o->buf, cap);
    if (p == NULL) { o->oom = 1; return; }
    o->buf = p;
    o->cap = cap;
}

static void
ob_put(outbuf *o, const void *src, size_t n)
{
    ob_reserve(o, n);
    if (o->oom) return;
    memcpy(o->buf + o->len, src, n);
    o->len += n;
}

static void
ob_be32(outbuf *o, uint32_t v)
{
    unsigned char b[4] = {(unsigned char)(v >> 24), (unsigned char)(v >> 16), (unsigned char)(v >> 8), (unsigned char)v};
    ob_put(o, b, 4);
}

/* Deflate ``n`` bytes (raw stream, run-length strategy) and sync-flush, appending to ``o``. */
static int
deflate_sync(z_stream *zs, const unsigned char *src, size_t n, outbuf *o)
{
    zs->next_in = (Bytef *)src;
    zs->avail_in = (uInt)n;
    for (;;) {
        ob_reserve(o, 65536);
        if (o->oom) return -1;
        zs->next_out = o->buf + o->len;
        zs->avail_out = (uInt)(o->cap - o->len);
        int rc = deflate(zs, Z_SYNC_FLUSH);
        o->len = o->cap - zs->avail_out;
        if (rc != Z_OK && rc != Z_BUF_ERROR) return -1;
        if (zs->avail_in == 0 && zs->avail_out != 0) return 0;
    }
}

static int
make_run_chunk(long width, int fbyte, int level, int k, chunk_t *out)
{
    size_t rows = (size_t)1 << k, rowlen = (size_t)width + 1;
    unsigned char *raw = (unsigned char *)calloc(rows * rowlen, 1);
    if (raw == NULL) return -1;
    if (fbyte) /* (rows of zeros: calloc's pages stay untouched, unmapped until deflate reads them) */
        for (size_t r = 0; r < rows; r++) raw[r * rowlen] = (unsigned char)fbyte;
    z_stream zs;
    memset(&zs, 0, sizeof zs);
    if (deflateInit2(&zs, level, Z_DEFLATED, -15, 9, Z_RLE) != Z_OK) { free(raw); return -1; }
    outbuf o = {0};
    int rc = deflate_sync(&zs, raw, rows * rowlen, &o);
    deflateEnd(&zs);
    free(raw);
    if (rc || o.oom) { free(o.buf); return -1; }
    out->data = o.buf;
    out->len = o.len;
    return 0;
}

/* The cached chunk for 2^k rows; built on first use (under the lock). */
static const chunk_t *
run_chunk(long width, int fbyte, int level, int k)
{
    const chunk_t *res = NULL;
    pthread_mutex_lock(&g_cache_lock);
    cache_entry *e = g_cache;
    while (e && !(e->width == width && e->fbyte == fbyte && e->level == level)) e = e->next;
    if (e == NULL) {
        e = (cache_entry *)calloc(1, sizeof *e);
        if (e) {
            e->width = width; e->fbyte = fbyte; e->level = level;
            e->next = g_cache;
            g_cache = e;
        }
    }
    if (e) {
        if (e->runs[k].data == NULL) make_run_chunk(width, fbyte, level, k, &e->runs[k]);
        if (e->runs[k].data) res = &e->runs[k];
    }
    pthread_mutex_unlock(&g_cache_lock);
    return res;
}

typedef struct {
    uint32_t a, b;
} adler_t;

static inline void
adler_pattern_rows(adler_t *ad, long width, int fbyte, size_t rows)
{
    /* ``rows`` rows of [fbyte, 0 * width]: a += fbyte, then b gains a (width + 1) times. */
    uint64_t a = ad->a, b = ad->b, wl = (uint64_t)(width + 1) % ADLER_MOD;
    for (size_t r = 0; r < rows; r++) {
        a = (a + (uint64_t)fbyte) % ADLER_MOD;
        b = (b + a * wl) % ADLER_MOD;
    }
    ad->a = (uint32_t)a;
    ad->b = (uint32_t)b;
}

static int
emit_pattern_run(outbuf *o, adler_t *ad, long width, int fbyte, int level, size_t rows)
{
    adler_pattern_rows(ad, width, fbyte, rows);
    for (int k = MAX_RUN_BITS - 1; k >= 0 && rows; k--) {
        size_t m = (size_t)1 << k;
        while (rows >= m) {
            const chunk_t *c = run_chunk(width, fbyte, level, k);
            if (c == NULL) return -1;
            ob_put(o, c->data, c->len);
            rows -= m;
        }
    }
    return o->oom ? -1 : 0;
}

static void
put_chunk(outbuf *o, const char *type, const unsigned char *data, size_t n)
{
    ob_be32(o, (uint32_t)n);
    ob_put(o, type, 4);
    if (n) ob_put(o, data, n);
    uLong crc = crc32(0L, (const Bytef *)type, 4);
    if (n) crc = crc32(crc, data, (uInt)n);
    ob_be32(o, (uint32_t)crc);
}

/* The (width + 1) bytes of image row ``y`` (filter byte slot left at 0), into ``row``. */
static void
image_row(unsigned char *row, const uint8_t *win, long width, long height, long r0, long c0, long hh, long ww,
          int mirror_x, int mirror_y, long y)
{
    memset(row, 0, (size_t)width + 1);
    long src_r = mirror_y ? (height - 1 - y) : y;
    if (src_r < r0 || src_r >= r0 + hh) return;
    const uint8_t *s = win + (src_r - r0) * ww;
    unsigned char *d = row + 1;
    if (!mirror_x) {
        memcpy(d + c0, s, (size_t)ww);
    } else {
        long x0 = width - c0 - ww; /* the window's first image column after the flip */
        for (long i = 0; i < ww; i++) d[x0 + i] = s[ww - 1 - i];
    }
}

static int
is_zero(const unsigned char *p, size_t n)
{
    static const unsigned char zeros[4096] = {0};
    while (n) {
        size_t m = n < sizeof zeros ? n : sizeof zeros;
        if (memcmp(p, zeros, m)) return 0;
        p += m;
        n -= m;
    }
    return 1;
}

/* Adler-32 of ``n`` bytes continued from ``ad`` (the same value as zlib's adler32()): eight
 * bytes at a time, and a word of eight equal bytes v (the runs of 0 and 255 that most mask
 * rows are) in closed form -- b += 8 a + 36 v, a += 8 v -- instead of byte by byte. The sums
 * stay below 2^64 between the reductions (every 4096 bytes: a < 2^21, b < 2^33). */
static void
adler_update(adler_t *ad, const unsigned char *p, size_t n)
{
    uint64_t a = ad->a, b = ad->b;
    while (n) {
        size_t block = n < 4096 ? n : 4096;
        n -= block;
        while (block >= 8) {
            uint64_t w;
            memcpy(&w, p, 8);
            uint64_t v = w & 0xff;
            if (w == v * 0x0101010101010101ULL) {
                b += 8 * a + 36 * v;
                a += 8 * v;
            } else {
                for (int i = 0; i < 8; i++) { a += p[i]; b += a; }
            }
            p += 8;
            block -= 8;
        }
        while (block--) { a += *p++; b += a; }
        a %= ADLER_MOD;
        b %= ADLER_MOD;
    }
    ad->a = (uint32_t)a;
    ad->b = (uint32_t)b;
}

static int
flush_content(z_stream *zs, adler_t *ad, outbuf *fb, outbuf *z)
{
    adler_update(ad, fb->buf, fb->len);
    int rc = deflate_sync(zs, fb->buf, fb->len, z);
    fb->len = 0;
    return rc ? -1 : 0;
}

static int
fb_reserve(outbuf *fb, size_t n)
{
    ob_reserve(fb, n);
    return fb->oom ? -1 : 0;
}

/* Rows shorter than this run of pattern rows go into the content stream (no chunk switch). */
#define MIN_CACHED_RUN 16
/* Runs of Up rows (equal to the row above) up to this long go into the content stream too: a
 * run of copied chunks (each flushed, with its own Huffman header) deflates again in the zip
 * 1.2x worse than one stream (a 400-row square layer of the SL1S: 231 vs 198 bytes), but
 * deflating the rows costs about 1 ms per 400 rows, so longer runs (a full field of an
 * inverted mask) are still copied. */
#define MAX_UP_RUN_IN_STREAM 1024

static int
finish_run(z_stream *zs, adler_t *ad, outbuf *fb, outbuf *z, long width, int fbyte, int level, size_t *run_n)
{
    size_t n = *run_n, rowlen = (size_t)width + 1;
    *run_n = 0;
    if (n >= (fbyte == 2 ? (size_t)MAX_UP_RUN_IN_STREAM + 1 : (size_t)MIN_CACHED_RUN)) {
        if (fb->len && flush_content(zs, ad, fb, z)) return -1;
        return emit_pattern_run(z, ad, width, fbyte, level, n);
    }
    if (fb_reserve(fb, n * rowlen)) return -1;
    memset(fb->buf + fb->len, 0, n * rowlen);
    for (size_t r = 0; r < n; r++) fb->buf[fb->len + r * rowlen] = (unsigned char)fbyte;
    fb->len += n * rowlen;
    if (fb->len >= ((size_t)1 << 22)) return flush_content(zs, ad, fb, z);
    return 0;
}

static int
encode_png(const uint8_t *win, long width, long height, long r0, long c0, long hh, long ww, int mirror_x,
           int mirror_y, int level, outbuf *o)
{
    static const unsigned char sig[8] = {137, 80, 78, 71, 13, 10, 26, 10};
    ob_put(o, sig, 8);
    unsigned char ihdr[13] = {0};
    for (int i = 0; i < 4; i++) {
        ihdr[i] = (unsigned char)((uint32_t)width >> (24 - 8 * i));
        ihdr[4 + i] = (unsigned char)((uint32_t)height >> (24 - 8 * i));
    }
    ihdr[8] = 8; /* bit depth; colour type 0 (grey), deflate, filter method 0, no interlace */
    put_chunk(o, "IHDR", ihdr, 13);

    outbuf z = {0};
    const unsigned char zhead[2] = {0x78, 0x01};
    ob_put(&z, zhead, 2);
    adler_t ad = {1, 0};
    size_t rowlen = (size_t)width + 1;
    unsigned char *prev = (unsigned char *)calloc(rowlen, 1);
    unsigned char *cur = (unsigned char *)calloc(rowlen, 1);
    outbuf fb = {0}; /* content rows (filtered) not yet deflated */
    z_stream zs;
    memset(&zs, 0, sizeof zs);
    int zs_ok = deflateInit2(&zs, level, Z_DEFLATED, -15, 9, Z_RLE) == Z_OK;
    int rc = (prev && cur && zs_ok) ? 0 : -1;
    /* pending run of pattern rows */
    int run_f = -1;
    size_t run_n = 0;
    /* the image rows that can differ from zero */
    long lo = mirror_y ? height - r0 - hh : r0, hi = lo + hh;
    for (long y = 0; y < height && rc == 0; y++) {
        int fbyte, pattern;
        if (y < lo || y >= hi) {
            memset(cur, 0, rowlen);
            pattern = 1;
            fbyte = 0;
        } else {
            image_row(cur, win, width, height, r0, c0, hh, ww, mirror_x, mirror_y, y);
            if (is_zero(cur + 1, (size_t)width)) {
                pattern = 1; fbyte = 0;             /* filter None: all zero */
            } else if (y > 0 && memcmp(cur + 1, prev + 1, (size_t)width) == 0) {
                pattern = 1; fbyte = 2;             /* filter Up: all zero after the byte */
            } else {
                pattern = 0; fbyte = 0;             /* content: filter None */
            }
        }
        if (pattern) {
            if (run_n && run_f != fbyte) rc = finish_run(&zs, &ad, &fb, &z, width, run_f, level, &run_n);
            run_f = fbyte;
            run_n++;
        } else {
            if (run_n) rc = finish_run(&zs, &ad, &fb, &z, width, run_f, level, &run_n);
            if (rc == 0 && fb_reserve(&fb, rowlen)) rc = -1;
            if (rc) break;
            unsigned char *d = fb.buf + fb.len;
            d[0] = 0; /* filter None: runs of 0 and 255 stay runs (smaller than Sub, Up, Paeth) */
            memcpy(d + 1, cur + 1, (size_t)width);
            fb.len += rowlen;
            if (fb.len >= ((size_t)1 << 22)) rc = flush_content(&zs, &ad, &fb, &z);
        }
        unsigned char *t = prev; prev = cur; cur = t;
    }
    if (rc == 0 && run_n) rc = finish_run(&zs, &ad, &fb, &z, width, run_f, level, &run_n);
    if (rc == 0 && fb.len) rc = flush_content(&zs, &ad, &fb, &z);
    if (zs_ok) deflateEnd(&zs);
    free(prev); free(cur); free(fb.buf);
    if (rc == 0) {
        const unsigned char fin[2] = {0x03, 0x00}; /* an empty final block (fixed Huffman) */
        ob_put(&z, fin, 2);
        ob_be32(&z, (ad.b << 16) | ad.a);
        if (z.oom) rc = -1;
    }
    if (rc == 0) put_chunk(o, "IDAT", z.buf, z.len);
    free(z.buf);
    if (rc == 0) put_chunk(o, "IEND", NULL, 0);
    return (rc == 0 && !o->oom) ? 0 : -1;
}

static PyObject *
native_png_grey(PyObject *self, PyObject *args)
{
    /* png_grey(window uint8 (hh * ww), width, height, r0, c0, hh, ww, mirror_x, mirror_y, level) */
    Py_buffer W;
    long width, height, r0, c0, hh, ww;
    int mx, my, level;
    if (!PyArg_ParseTuple(args, "y*llllllppi", &W, &width, &height, &r0, &c0, &hh, &ww, &mx, &my, &level))
        return NULL;
    if (width <= 0 || height <= 0 || hh < 0 || ww < 0 || r0 < 0 || c0 < 0 || r0 + hh > height || c0 + ww > width
        || W.len < (Py_ssize_t)hh * ww || level < 0 || level > 9) {
        PyBuffer_Release(&W);
        PyErr_SetString(PyExc_ValueError, "png_grey: window outside the image or bad level");
        return NULL;
    }
    outbuf o = {0};
    int rc;
    Py_BEGIN_ALLOW_THREADS
    rc = encode_png((const uint8_t *)W.buf, width, height, r0, c0, hh, ww, mx, my, level, &o);
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&W);
    if (rc) {
        free(o.buf);
        return PyErr_NoMemory();
    }
    PyObject *res = PyBytes_FromStringAndSize((const char *)o.buf, (Py_ssize_t)o.len);
    free(o.buf);
    return res;
}

/* ------------------------------------------------------------------------ shells */

static int64_t
uf_find(int64_t *parent, int64_t x)
{
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

static PyObject *
native_shell_labels(PyObject *self, PyObject *args)
{
    /* shell_labels(face_edges (F * 3) int64, n_edges, labels (F) int64 out) -> number of shells.
     * Faces sharing an edge are one shell; shells are numbered by their lowest face index. */
    Py_buffer FE, L;
    long long n_edges;
    if (!PyArg_ParseTuple(args, "y*Lw*", &FE, &n_edges, &L)) return NULL;
    Py_ssize_t nf = FE.len / (Py_ssize_t)(3 * sizeof(int64_t));
    const int64_t *fe = (const int64_t *)FE.buf;
    int64_t *lab = (int64_t *)L.buf;
    int64_t *parent = (int64_t *)malloc(sizeof(int64_t) * (size_t)(nf > 0 ? nf : 1));
    int64_t *edge_face = (int64_t *)malloc(sizeof(int64_t) * (size_t)(n_edges > 0 ? n_edges : 1));
    long long count = 0;
    int bad = 0;
    if (parent == NULL || edge_face == NULL) {
        free(parent); free(edge_face);
        PyBuffer_Release(&FE); PyBuffer_Release(&L);
        return PyErr_NoMemory();
    }
    Py_BEGIN_ALLOW_THREADS
    for (int64_t e = 0; e < n_edges; e++) edge_face[e] = -1;
    for (Py_ssize_t f = 0; f < nf; f++) parent[f] = f;
    for (Py_ssize_t f = 0; f < nf && !bad; f++) {
        for (int k = 0; k < 3; k++) {
            int64_t e = fe[3 * f + k];
            if (e < 0 || e >= n_edges) { bad = 1; break; }
            if (edge_face[e] < 0) { edge_face[e] = f; continue; }
            int64_t a = uf_find(parent, edge_face[e]), b = uf_find(parent, f);
            if (a != b) { if (a < b) parent[b] = a; else parent[a] = b; }
        }
    }
    if (!bad) {
        /* the root of every set is its lowest face: number roots in order */
        for (Py_ssize_t f = 0; f < nf; f++) {
            int64_t r = uf_find(parent, f);
            if (r == f) lab[f] = count++;
            else lab[f] = lab[r];
        }
    }
    Py_END_ALLOW_THREADS
    free(parent); free(edge_face);
    PyBuffer_Release(&FE); PyBuffer_Release(&L);
    if (bad) {
        PyErr_SetString(PyExc_IndexError, "edge index out of range");
        return NULL;
    }
    return PyLong_FromLongLong(count);
}

/* ------------------------------------------------------------------------ vertices */

static inline uint64_t
mix64(uint64_t x)
{
    x ^= x >> 33; x *= 0xff51afd7ed558ccdULL;
    x ^= x >> 33; x *= 0xc4ceb9fe1a85ec53ULL;
    x ^= x >> 33;
    return x;
}

static PyObject *
native_merge_rows(PyObject *self, PyObject *args)
{
    /* merge_rows(rows (M * 3) float64, first (M) int64 out, inverse (M) int64 out) -> U.
     * Bit-identical rows get one id, numbered by first occurrence; first[:U] holds the row
     * index of each id's first occurrence. */
    Py_buffer R, FIRST, INV;
    if (!PyArg_ParseTuple(args, "y*w*w*", &R, &FIRST, &INV)) return NULL;
    Py_ssize_t m = R.len / (Py_ssize_t)(3 * sizeof(double));
    const uint64_t *rows = (const uint64_t *)R.buf;
    int64_t *first = (int64_t *)FIRST.buf, *inv = (int64_t *)INV.buf;
    size_t cap = 16;
    while (cap < (size_t)m * 2) cap <<= 1;
    int64_t *table = (int64_t *)malloc(cap * sizeof(int64_t));
    if (table == NULL) {
        PyBuffer_Release(&R); PyBuffer_Release(&FIRST); PyBuffer_Release(&INV);
        return PyErr_NoMemory();
    }
    int64_t u = 0;
    Py_BEGIN_ALLOW_THREADS
    memset(table, 0xff, cap * sizeof(int64_t)); /* -1: empty */
    for (Py_ssize_t i = 0; i < m; i++) {
        const uint64_t *r = rows + 3 * i;
        uint64_t h = mix64(r[0] ^ mix64(r[1] ^ mix64(r[2])));
        size_t slot = (size_t)h & (cap - 1);
        for (;;) {
            int64_t id = table[slot];
            if (id < 0) {
                table[slot] = u;
                first[u] = i;
                inv[i] = u++;
                break;
            }
            const uint64_t *q = rows + 3 * first[id];
            if (q[0] == r[0] && q[1] == r[1] && q[2] == r[2]) {
                inv[i] = id;
                break;
            }
            slot = (slot + 1) & (cap - 1);
        }
    }
    Py_END_ALLOW_THREADS
    free(table);
    PyBuffer_Release(&R); PyBuffer_Release(&FIRST); PyBuffer_Release(&INV);
    return PyLong_FromLongLong((long long)u);
}

static PyObject *
native_double_areas(PyObject *self, PyObject *args)
{
    /* double_areas(V (nv * 3) float64, F (nf * 3) int64, out (nf) float64): |(v1 - v0) x (v2 - v0)| */
    Py_buffer V, F, OUT;
    if (!PyArg_ParseTuple(args, "y*y*w*", &V, &F, &OUT)) return NULL;
    const double *v = (const double *)V.buf;
    const int64_t *f = (const int64_t *)F.buf;
    double *out = (double *)OUT.buf;
    Py_ssize_t nf = F.len / (Py_ssize_t)(3 * sizeof(int64_t));
    Py_ssize_t nv = V.len / (Py_ssize_t)(3 * sizeof(double));
    int bad = 0;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t k = 0; k < nf; k++) {
        int64_t a = f[3 * k], b = f[3 * k + 1], c = f[3 * k + 2];
        if (a < 0 || b < 0 || c < 0 || a >= nv || b >= nv || c >= nv) { bad = 1; break; }
        double ux = v[3 * b] - v[3 * a], uy = v[3 * b + 1] - v[3 * a + 1], uz = v[3 * b + 2] - v[3 * a + 2];
        double wx = v[3 * c] - v[3 * a], wy = v[3 * c + 1] - v[3 * a + 1], wz = v[3 * c + 2] - v[3 * a + 2];
        double cx = uy * wz - uz * wy, cy = uz * wx - ux * wz, cz = ux * wy - uy * wx;
        out[k] = sqrt(cx * cx + cy * cy + cz * cz);
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&V); PyBuffer_Release(&F); PyBuffer_Release(&OUT);
    if (bad) {
        PyErr_SetString(PyExc_IndexError, "vertex index out of range");
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyObject *
native_merge_keys(PyObject *self, PyObject *args)
{
    /* merge_keys(keys (M) int64, first (M) int64 out, ids (M) int64 out) -> U: as merge_rows
     * for single int64 keys. */
    Py_buffer K, FIRST, IDS;
    if (!PyArg_ParseTuple(args, "y*w*w*", &K, &FIRST, &IDS)) return NULL;
    Py_ssize_t m = K.len / (Py_ssize_t)sizeof(int64_t);
    const int64_t *keys = (const int64_t *)K.buf;
    int64_t *first = (int64_t *)FIRST.buf, *ids = (int64_t *)IDS.buf;
    size_t cap = 16;
    while (cap < (size_t)m * 2) cap <<= 1;
    int64_t *table = (int64_t *)malloc(cap * sizeof(int64_t));
    if (table == NULL) {
        PyBuffer_Release(&K); PyBuffer_Release(&FIRST); PyBuffer_Release(&IDS);
        return PyErr_NoMemory();
    }
    int64_t u = 0;
    Py_BEGIN_ALLOW_THREADS
    memset(table, 0xff, cap * sizeof(int64_t));
    for (Py_ssize_t i = 0; i < m; i++) {
        size_t slot = (size_t)mix64((uint64_t)keys[i]) & (cap - 1);
        for (;;) {
            int64_t id = table[slot];
            if (id < 0) { table[slot] = u; first[u] = i; ids[i] = u++; break; }
            if (keys[first[id]] == keys[i]) { ids[i] = id; break; }
            slot = (slot + 1) & (cap - 1);
        }
    }
    Py_END_ALLOW_THREADS
    free(table);
    PyBuffer_Release(&K); PyBuffer_Release(&FIRST); PyBuffer_Release(&IDS);
    return PyLong_FromLongLong((long long)u);
}

static PyObject *
native_first_two(PyObject *self, PyObject *args)
{
    /* first_two(ids (M) int64 in [0, n), n, a (n) int64 out, b (n) int64 out): the positions of
     * the first and second occurrence of every id (-1 where there is none). */
    Py_buffer IDS, A, B;
    long long n;
    if (!PyArg_ParseTuple(args, "y*Lw*w*", &IDS, &n, &A, &B)) return NULL;
    Py_ssize_t m = IDS.len / (Py_ssize_t)sizeof(int64_t);
    const int64_t *ids = (const int64_t *)IDS.buf;
    int64_t *a = (int64_t *)A.buf, *b = (int64_t *)B.buf;
    int bad = 0;
    Py_BEGIN_ALLOW_THREADS
    for (long long e = 0; e < n; e++) { a[e] = -1; b[e] = -1; }
    for (Py_ssize_t i = 0; i < m; i++) {
        int64_t e = ids[i];
        if (e < 0 || e >= n) { bad = 1; break; }
        if (a[e] < 0) a[e] = i;
        else if (b[e] < 0) b[e] = i;
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&IDS); PyBuffer_Release(&A); PyBuffer_Release(&B);
    if (bad) {
        PyErr_SetString(PyExc_IndexError, "id out of range");
        return NULL;
    }
    Py_RETURN_NONE;
}

/* --------------------------------------------------------------------------- fill */

/* slicing/_kernels._fibre_range: the fibres j0 <= j < j1 a span lv..hv of v crosses (the
 * range is empty unless j0 < n_fib); computed in double so that no value is converted to an
 * integer out of range. */
static int
fibre_range(double lv, double hv, long n_fib, long *j0, long *j1)
{
    double a = lv > 0.0 ? ceil(lv) : 0.0;
    double b = hv > 0.0 ? (hv < (double)n_fib ? ceil(hv) : (double)n_fib) : 0.0;
    if (!(a < (double)n_fib) || !(b > a)) return 0;
    *j0 = (long)a;
    *j1 = (long)b;
    return 1;
}

static PyObject *
native_fill(PyObject *self, PyObject *args)
{
    /* fill(ua, va, ub, vb, n_fib, n_samp, evenodd, out[n_fib * n_samp] uint8 zeroed): the
     * fibre fill of slicing/_kernels.fill_jit (bucket_crossings then _fill_spans: the same
     * crossings, the same floating-point operations, the same stable sort), 255 inside. */
    Py_buffer UA, VA, UB, VB, OUT;
    long n_fib, n_samp;
    int evenodd;
    if (!PyArg_ParseTuple(args, "y*y*y*y*llpw*", &UA, &VA, &UB, &VB, &n_fib, &n_samp, &evenodd, &OUT)) return NULL;
    const double *ua = (const double *)UA.buf, *va = (const double *)VA.buf;
    const double *ub = (const double *)UB.buf, *vb = (const double *)VB.buf;
    Py_ssize_t n_seg = UA.len / (Py_ssize_t)sizeof(double);
    uint8_t *out = (uint8_t *)OUT.buf;
    int64_t *per = (int64_t *)calloc((size_t)n_fib + 1, sizeof(int64_t));
    int64_t *start = (int64_t *)calloc((size_t)n_fib + 1, sizeof(int64_t));
    int64_t *pos = NULL;
    int8_t *sgn = NULL;
    int oom = per == NULL || start == NULL;
    if (!oom) {
        Py_BEGIN_ALLOW_THREADS
        /* pass 1: crossings per fibre, by a difference array over fibres */
        long jlo = n_fib, jhi = 0, j0, j1;
        for (Py_ssize_t s = 0; s < n_seg; s++) {
            double v0 = va[s], v1 = vb[s];
            if (v0 == v1) continue;
            double lv = v0 < v1 ? v0 : v1, hv = v0 < v1 ? v1 : v0;
            if (fibre_range(lv, hv, n_fib, &j0, &j1)) {
                per[j0] += 1;
                per[j1] -= 1;
                if (j0 < jlo) jlo = j0;
                if (j1 > jhi) jhi = j1;
            }
        }
        if (jhi < jlo) jhi = jlo;
        int64_t acc = 0, run = 0;
        for (long j = jlo; j < jhi; j++) {
            run += per[j];
            start[j] = acc;
            acc += run;
        }
        for (long j = jhi; j <= n_fib; j++) start[j] = acc;
        pos = (int64_t *)malloc((size_t)(acc > 0 ? acc : 1) * sizeof(int64_t));
        sgn = (int8_t *)malloc((size_t)(acc > 0 ? acc : 1));
        oom = pos == NULL || sgn == NULL;
        if (!oom) {
            int64_t *cur = per; /* per is not needed any more: the next free slot per fibre */
            memcpy(cur, start, (size_t)n_fib * sizeof(int64_t));
            /* pass 2: where each crossing counts from (first sample with u >= u_c), its sign */
            for (Py_ssize_t s = 0; s < n_seg; s++) {
                double v0 = va[s], v1 = vb[s];
                if (v0 == v1) continue;
                int sign;
                double lu, lv, hu, hv;
                if (v0 < v1) { sign = -1; lu = ua[s]; lv = v0; hu = ub[s]; hv = v1; }
                else { sign = 1; lu = ub[s]; lv = v1; hu = ua[s]; hv = v0; }
                if (!fibre_range(lv, hv, n_fib, &j0, &j1)) continue;
                double slope = (hu - lu) / (hv - lv);
                for (long j = j0; j < j1; j++) {
                    double u = lu + ((double)j - lv) * slope;
                    int64_t i = u <= 0.0 ? 0 : (u >= (double)n_samp ? (int64_t)n_samp : (int64_t)ceil(u));
                    int64_t k = cur[j];
                    pos[k] = i;
                    sgn[k] = (int8_t)sign;
                    cur[j] = k + 1;
                }
            }
            /* pass 3: each fibre's crossings sorted along it (stable insertion sort) */
            for (long j = jlo; j < jhi; j++) {
                int64_t a = start[j], b = start[j + 1];
                for (int64_t k = a + 1; k < b; k++) {
                    int64_t p = pos[k];
                    int8_t q = sgn[k];
                    int64_t m = k - 1;
                    while (m >= a && pos[m] > p) { pos[m + 1] = pos[m]; sgn[m + 1] = sgn[m]; m--; }
                    pos[m + 1] = p;
                    sgn[m + 1] = q;
                }
            }
            /* per fibre, the spans the fill rule puts inside */
            for (long j = jlo; j < jhi; j++) {
                uint8_t *row = out + (size_t)j * (size_t)n_samp;
                int64_t w = 0, prev = 0;
                for (int64_t k = start[j]; k < start[j + 1]; k++) {
                    int64_t i = pos[k];
                    int inside = evenodd ? (w & 1) != 0 : w != 0;
                    if (inside && i > prev) memset(row + prev, 255, (size_t)(i - prev));
                    w += sgn[k];
                    prev = i;
                }
                int inside = evenodd ? (w & 1) != 0 : w != 0;
                if (inside && prev < n_samp) memset(row + prev, 255, (size_t)(n_samp - prev));
            }
        }
        Py_END_ALLOW_THREADS
    }
    free(per); free(start); free(pos); free(sgn);
    PyBuffer_Release(&UA); PyBuffer_Release(&VA); PyBuffer_Release(&UB); PyBuffer_Release(&VB); PyBuffer_Release(&OUT);
    if (oom) return PyErr_NoMemory();
    Py_RETURN_NONE;
}

/* ------------------------------------------------------------------------ preload */

static PyObject *
native_preload(PyObject *self, PyObject *args)
{
    /* preload(path) -> bool: dlopen(path, RTLD_NOW | RTLD_LOCAL) without the GIL. The library
     * stays loaded (its handle is never closed: the import that follows uses it). False when
     * it cannot be loaded: the import that follows then says why. */
    PyObject *path;
    if (!PyArg_ParseTuple(args, "O&", PyUnicode_FSConverter, &path))
        return NULL;
    void *handle;
    Py_BEGIN_ALLOW_THREADS
    handle = dlopen(PyBytes_AS_STRING(path), RTLD_NOW | RTLD_LOCAL);
    Py_END_ALLOW_THREADS
    Py_DECREF(path);
    if (handle == NULL) {
        (void)dlerror(); /* (cleared: the import reports its own) */
        Py_RETURN_FALSE;
    }
    Py_RETURN_TRUE;
}

static PyMethodDef methods[] = {
    {"preload", native_preload, METH_VARARGS, "preload(path) -> bool"},
    {"fill", native_fill, METH_VARARGS, "fill(ua, va, ub, vb, n_fib, n_samp, evenodd, out)"},
    {"merge_keys", native_merge_keys, METH_VARARGS, "merge_keys(keys, first, ids) -> number of distinct keys"},
    {"first_two", native_first_two, METH_VARARGS, "first_two(ids, n, a, b)"},
    {"merge_rows", native_merge_rows, METH_VARARGS, "merge_rows(rows, first, inverse) -> number of distinct rows"},
    {"double_areas", native_double_areas, METH_VARARGS, "double_areas(V, F, out)"},
    {"shell_labels", native_shell_labels, METH_VARARGS, "shell_labels(face_edges, n_edges, labels) -> n_shells"},
    {"section", native_section, METH_VARARGS, "section(V, F, FE, faces, z, start, end, se, ee)"},
    {"coverage", native_coverage, METH_VARARGS, "coverage(x0, y0, x1, y1, height, width, out, tail)"},
    {"thumb_rgb", native_thumb_rgb, METH_VARARGS, "thumb_rgb(crop, ch, cw, nh, nw, out, c0r, c1r, c0g, c1g, c0b, c1b)"},
    {"window_stats", native_window_stats, METH_VARARGS, "window_stats(window, hh, ww) -> (sum, r0, r1, c0, c1)"},
    {"png_grey", native_png_grey, METH_VARARGS,
     "png_grey(window, width, height, r0, c0, hh, ww, mirror_x, mirror_y, level) -> bytes"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef moddef = {PyModuleDef_HEAD_INIT, "_native", "rotoprint's C kernels (see the source).", -1, methods,
                                     NULL, NULL, NULL, NULL};

PyMODINIT_FUNC
PyInit__native(void)
{
    return PyModule_Create(&moddef);
}

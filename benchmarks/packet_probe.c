// `python -m benchmarks.packet_probe`: one ray-marching loop (trilinear sample, 1D RGBA TF, front-to-back
// compositing, early termination), scalar and in packets of 8 rays with AVX2 gathers: what C reaches on this CPU.
#include <immintrin.h>
#include <stdint.h>
#include <stddef.h>

long march_scalar(const float *vol, int nx, int ny, int nz, const float *tf, int n, float lo, float scale,
                  const float *ox, const float *oy, const float *oz, int rays, float dx, float dy, float dz,
                  int nsteps, float *out) {
    long taken = 0;
    size_t sy = nx, sz = (size_t)nx * ny;
    for (int q = 0; q < rays; q++) {
        float r = 0, g = 0, b = 0, a = 0;
        for (int k = 0; k < nsteps; k++) {
            float x = ox[q] + k * dx, y = oy[q] + k * dy, z = oz[q] + k * dz;
            if (x < 0 || y < 0 || z < 0 || x >= nx - 1 || y >= ny - 1 || z >= nz - 1) continue;
            int i = (int)x, j = (int)y, kk = (int)z;
            float fx = x - i, fy = y - j, fz = z - kk;
            const float *p = vol + i + j * sy + kk * sz;
            float x00 = p[0] + fx * (p[1] - p[0]), x10 = p[sy] + fx * (p[sy + 1] - p[sy]);
            float x01 = p[sz] + fx * (p[sz + 1] - p[sz]), x11 = p[sz + sy] + fx * (p[sz + sy + 1] - p[sz + sy]);
            float y0 = x00 + fy * (x10 - x00), y1 = x01 + fy * (x11 - x01);
            float s = y0 + fz * (y1 - y0);
            taken++;
            float fi = (s - lo) * scale; fi = fi < 0 ? 0 : (fi > n - 1 ? n - 1 : fi);
            int i0 = (int)fi; if (i0 > n - 2) i0 = n - 2;
            float w = fi - i0;
            const float *t = tf + 4 * i0;
            float ca = t[3] + w * (t[7] - t[3]);
            if (ca <= 0) continue;
            float tr = (1 - a) * ca;
            r += tr * (t[0] + w * (t[4] - t[0])); g += tr * (t[1] + w * (t[5] - t[1]));
            b += tr * (t[2] + w * (t[6] - t[2])); a += tr;
            if (a >= 0.99f) break;
        }
        out[4 * q] = r; out[4 * q + 1] = g; out[4 * q + 2] = b; out[4 * q + 3] = a;
    }
    return taken;
}

int has_avx2(void) { return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"); }

__attribute__((target("avx2,fma"))) long march_avx2(const float *vol, int nx, int ny, int nz, const float *tf, int n, float lo, float scale,
                const float *ox, const float *oy, const float *oz, int rays, float dx, float dy, float dz,
                int nsteps, float *out) {
    long taken = 0;
    const int sy = nx, sz = nx * ny;
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    const __m256 ux = _mm256_set1_ps(nx - 1), uy = _mm256_set1_ps(ny - 1), uz = _mm256_set1_ps(nz - 1);
    const __m256 vlo = _mm256_set1_ps(lo), vsc = _mm256_set1_ps(scale), top = _mm256_set1_ps(n - 1);
    const __m256i n2 = _mm256_set1_epi32(n - 2), vsy = _mm256_set1_epi32(sy), vsz = _mm256_set1_epi32(sz);
    const __m256 term = _mm256_set1_ps(0.99f);
    for (int q = 0; q + 8 <= rays; q += 8) {
        __m256 r = zero, g = zero, b = zero, a = zero;
        __m256 px = _mm256_loadu_ps(ox + q), py = _mm256_loadu_ps(oy + q), pz = _mm256_loadu_ps(oz + q);
        const __m256 vdx = _mm256_set1_ps(dx), vdy = _mm256_set1_ps(dy), vdz = _mm256_set1_ps(dz);
        for (int k = 0; k < nsteps; k++) {
            __m256 x = px, y = py, z = pz;
            px = _mm256_add_ps(px, vdx); py = _mm256_add_ps(py, vdy); pz = _mm256_add_ps(pz, vdz);
            __m256 in = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(x, zero, _CMP_GE_OQ), _mm256_cmp_ps(y, zero, _CMP_GE_OQ)),
                                      _mm256_cmp_ps(z, zero, _CMP_GE_OQ));
            in = _mm256_and_ps(in, _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(x, ux, _CMP_LT_OQ), _mm256_cmp_ps(y, uy, _CMP_LT_OQ)),
                                                 _mm256_cmp_ps(z, uz, _CMP_LT_OQ)));
            __m256 alive = _mm256_cmp_ps(a, term, _CMP_LT_OQ);
            int am = _mm256_movemask_ps(alive);
            if (!am) break;
            int m = _mm256_movemask_ps(_mm256_and_ps(in, alive));
            if (!m) continue;
            taken += __builtin_popcount(m);
            __m256 mask = _mm256_and_ps(in, alive);
            x = _mm256_and_ps(x, in); y = _mm256_and_ps(y, in); z = _mm256_and_ps(z, in);  // dead lanes read (0,0,0)
            __m256i i = _mm256_cvttps_epi32(x), j = _mm256_cvttps_epi32(y), kk = _mm256_cvttps_epi32(z);
            __m256 fx = _mm256_sub_ps(x, _mm256_cvtepi32_ps(i)), fy = _mm256_sub_ps(y, _mm256_cvtepi32_ps(j)),
                   fz = _mm256_sub_ps(z, _mm256_cvtepi32_ps(kk));
            __m256i base = _mm256_add_epi32(i, _mm256_add_epi32(_mm256_mullo_epi32(j, vsy), _mm256_mullo_epi32(kk, vsz)));
            __m256i b1 = _mm256_add_epi32(base, vsy), b2 = _mm256_add_epi32(base, vsz), b3 = _mm256_add_epi32(b2, vsy);
            __m256 v000 = _mm256_i32gather_ps(vol, base, 4), v001 = _mm256_i32gather_ps(vol + 1, base, 4);
            __m256 v010 = _mm256_i32gather_ps(vol, b1, 4), v011 = _mm256_i32gather_ps(vol + 1, b1, 4);
            __m256 v100 = _mm256_i32gather_ps(vol, b2, 4), v101 = _mm256_i32gather_ps(vol + 1, b2, 4);
            __m256 v110 = _mm256_i32gather_ps(vol, b3, 4), v111 = _mm256_i32gather_ps(vol + 1, b3, 4);
            __m256 x00 = _mm256_fmadd_ps(fx, _mm256_sub_ps(v001, v000), v000), x10 = _mm256_fmadd_ps(fx, _mm256_sub_ps(v011, v010), v010);
            __m256 x01 = _mm256_fmadd_ps(fx, _mm256_sub_ps(v101, v100), v100), x11 = _mm256_fmadd_ps(fx, _mm256_sub_ps(v111, v110), v110);
            __m256 y0 = _mm256_fmadd_ps(fy, _mm256_sub_ps(x10, x00), x00), y1 = _mm256_fmadd_ps(fy, _mm256_sub_ps(x11, x01), x01);
            __m256 s = _mm256_fmadd_ps(fz, _mm256_sub_ps(y1, y0), y0);
            __m256 fi = _mm256_min_ps(_mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(s, vlo), vsc), zero), top);
            __m256i i0 = _mm256_min_epi32(_mm256_cvttps_epi32(fi), n2);
            __m256 w = _mm256_sub_ps(fi, _mm256_cvtepi32_ps(i0));
            __m256i t4 = _mm256_slli_epi32(i0, 2);
            __m256 a0 = _mm256_i32gather_ps(tf + 3, t4, 4), a1 = _mm256_i32gather_ps(tf + 7, t4, 4);
            __m256 ca = _mm256_and_ps(_mm256_fmadd_ps(w, _mm256_sub_ps(a1, a0), a0), mask);
            __m256 tr = _mm256_mul_ps(_mm256_sub_ps(one, a), ca);
            __m256 c0 = _mm256_i32gather_ps(tf, t4, 4), c1 = _mm256_i32gather_ps(tf + 4, t4, 4);
            r = _mm256_fmadd_ps(tr, _mm256_fmadd_ps(w, _mm256_sub_ps(c1, c0), c0), r);
            c0 = _mm256_i32gather_ps(tf + 1, t4, 4); c1 = _mm256_i32gather_ps(tf + 5, t4, 4);
            g = _mm256_fmadd_ps(tr, _mm256_fmadd_ps(w, _mm256_sub_ps(c1, c0), c0), g);
            c0 = _mm256_i32gather_ps(tf + 2, t4, 4); c1 = _mm256_i32gather_ps(tf + 6, t4, 4);
            b = _mm256_fmadd_ps(tr, _mm256_fmadd_ps(w, _mm256_sub_ps(c1, c0), c0), b);
            a = _mm256_add_ps(a, tr);
        }
        float R[8], G[8], B[8], A[8];
        _mm256_storeu_ps(R, r); _mm256_storeu_ps(G, g); _mm256_storeu_ps(B, b); _mm256_storeu_ps(A, a);
        for (int l = 0; l < 8; l++) { out[4 * (q + l)] = R[l]; out[4 * (q + l) + 1] = G[l]; out[4 * (q + l) + 2] = B[l]; out[4 * (q + l) + 3] = A[l]; }
    }
    return taken;
}

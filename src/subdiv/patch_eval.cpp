// Patch lookup by ptex coordinates and patch evaluation: bicubic B-spline (boundary rows and
// columns extrapolated) and Gregory (Bezier with rational interior points).
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "core/cpu.hpp"
#include "limn/mesh/topology.hpp"
#include "limn/subdiv/patches.hpp"

#if LIMN_X86_SIMD
#include <immintrin.h>
#endif

namespace limn {

namespace {

constexpr uint32_t kPatchBit = 0x80000000u;

// Uniform cubic B-spline basis and its derivative at t (double for the general path, float
// for the plain-patch fast path).
template <class T>
void bspline(T t, T w[4], T d[4]) {
  const T s = T(1) - t, t2 = t * t, t3 = t2 * t;
  w[0] = s * s * s / T(6);
  w[1] = (T(3) * t3 - T(6) * t2 + T(4)) / T(6);
  w[2] = (T(-3) * t3 + T(3) * t2 + T(3) * t + T(1)) / T(6);
  w[3] = t3 / T(6);
  d[0] = T(-0.5) * s * s;
  d[1] = T(1.5) * t2 - T(2) * t;
  d[2] = T(-1.5) * t2 + t + T(0.5);
  d[3] = T(0.5) * t2;
}

// Folds an extrapolated end point (2 * next - next-but-one) into the other weights.
void fold(double w[4], bool low, bool high) {
  if (low) w[1] += 2.0 * w[0], w[2] -= w[0], w[0] = 0.0;
  if (high) w[2] += 2.0 * w[3], w[1] -= w[3], w[3] = 0.0;
}

void bezier(double t, double w[4], double d[4]) {
  const double s = 1.0 - t;
  w[0] = s * s * s, w[1] = 3.0 * t * s * s, w[2] = 3.0 * t * t * s, w[3] = t * t * t;
  d[0] = -3.0 * s * s, d[1] = 3.0 * s * s - 6.0 * t * s, d[2] = 6.0 * t * s - 3.0 * t * t;
  d[3] = 3.0 * t * t;
}

struct Eval {
  double p[3] = {}, du[3] = {}, dv[3] = {};
  void add(const float* x, double w, double wu, double wv) {
    for (int c = 0; c < 3; ++c) p[c] += w * x[c], du[c] += wu * x[c], dv[c] += wv * x[c];
  }
};

// The limit basis over [0, 1] of a cubic curve with control points c0..c3 whose point c1 (at
// t = 0) is a semi-sharp vertex of sharpness s: while s > 0 the curve is subdivided once more
// around it (c1 keeps its place while s >= 1, a blend when 0 < s < 1, the smooth rule after),
// halving the interval that holds t, until t leaves the crease's reach; the rest is an
// ordinary B-spline segment of the control points reached.
void crease_basis(double t, double s, double w[4], double d[4]) {
  double A[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
  double scale = 1;
  auto apply = [&](const double M[4][4]) {
    double B[4][4] = {};
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        for (int k = 0; k < 4; ++k) B[i][j] += M[i][k] * A[k][j];
    std::copy(&B[0][0], &B[0][0] + 16, &A[0][0]);
  };
  for (int guard = 0; guard < 16 && s > 0; ++guard) {
    const double a = std::min(s, 1.0);  // weight of the sharp rule at c1
    // c1' = a c1 + (1 - a)(c0 + 6 c1 + c2) / 8
    const double v1[4] = {(1 - a) / 8, a + (1 - a) * 6 / 8, (1 - a) / 8, 0};
    const double e01[4] = {0.5, 0.5, 0, 0}, e12[4] = {0, 0.5, 0.5, 0}, e23[4] = {0, 0, 0.5, 0.5};
    const double v2[4] = {0, 1.0 / 8, 6.0 / 8, 1.0 / 8};
    double M[4][4];
    if (t < 0.5) {  // the half at the crease: (e01, c1', e12, c2'), crease still at index 1
      const double* rows[4] = {e01, v1, e12, v2};
      for (int i = 0; i < 4; ++i) std::copy(rows[i], rows[i] + 4, M[i]);
      apply(M);
      t *= 2, scale *= 2, s -= 1;
    } else {  // the far half: (c1', e12, c2', e23), an ordinary segment from here on
      const double* rows[4] = {v1, e12, v2, e23};
      for (int i = 0; i < 4; ++i) std::copy(rows[i], rows[i] + 4, M[i]);
      apply(M);
      t = 2 * t - 1, scale *= 2, s = 0;
    }
  }
  double b[4], db[4];
  bspline(t, b, db);
  for (int j = 0; j < 4; ++j) {
    w[j] = d[j] = 0;
    for (int i = 0; i < 4; ++i) w[j] += b[i] * A[i][j], d[j] += db[i] * A[i][j] * scale;
  }
}

// 16 control points, tensor-product weights: the hot loop of every scalar evaluation, kept in
// float with fixed trip counts so the compiler vectorises it; rows accumulated first.
void tensor(const uint32_t* cv, const float wu[4], const float du[4], const float wv[4],
            const float dv[4], const float* pts, float p[3], float pu[3], float pv[3]) {
  for (int c = 0; c < 3; ++c) p[c] = pu[c] = pv[c] = 0;
  for (int y = 0; y < 4; ++y) {
    float rp[3] = {}, ru[3] = {};
    for (int x = 0; x < 4; ++x) {
      const float* q = pts + 3 * size_t(cv[4 * y + x]);
      for (int c = 0; c < 3; ++c) rp[c] += wu[x] * q[c], ru[c] += du[x] * q[c];
    }
    for (int c = 0; c < 3; ++c)
      p[c] += wv[y] * rp[c], pu[c] += wv[y] * ru[c], pv[c] += dv[y] * rp[c];
  }
}

// A regular patch in general: boundary folding and single creases, weights in double.
void eval_regular(const uint32_t* cv, const PatchParam& pp, double s, double t, const float* pts,
                  Eval& e) {
  const uint8_t boundary = pp.boundary;
  double wu[4], du[4], wv[4], dv[4];
  bspline(s, wu, du), bspline(t, wv, dv);
  fold(wu, boundary & 8, boundary & 2), fold(du, boundary & 8, boundary & 2);
  fold(wv, boundary & 1, boundary & 4), fold(dv, boundary & 1, boundary & 4);
  if (pp.type == PatchType::single_crease) {
    // The crease runs along edge crease_edge: rows (v) or columns (u), mirrored for the far
    // edges so that the crease sits at the basis' t = 0.
    double* w = pp.crease_edge == 0 || pp.crease_edge == 2 ? wv : wu;
    double* d = pp.crease_edge == 0 || pp.crease_edge == 2 ? dv : du;
    const double x = pp.crease_edge == 0   ? t
                     : pp.crease_edge == 2 ? 1 - t
                     : pp.crease_edge == 3 ? s
                                           : 1 - s;
    double cw[4], cd[4];
    crease_basis(x, pp.sharpness, cw, cd);
    const bool mirror = pp.crease_edge == 1 || pp.crease_edge == 2;
    for (int i = 0; i < 4; ++i) {
      w[i] = mirror ? cw[3 - i] : cw[i];
      d[i] = mirror ? -cd[3 - i] : cd[i];
    }
  }
  float fu[4], fdu[4], fv[4], fdv[4];
  for (int i = 0; i < 4; ++i)
    fu[i] = float(wu[i]), fdu[i] = float(du[i]), fv[i] = float(wv[i]), fdv[i] = float(dv[i]);
  float p[3], pu[3], pv[3];
  tensor(cv, fu, fdu, fv, fdv, pts, p, pu, pv);
  for (int c = 0; c < 3; ++c) e.p[c] = p[c], e.du[c] = pu[c], e.dv[c] = pv[c];
}

// A Gregory patch's boundary Bezier slots (x, y) and the point each takes (corner * 5 + P/Ep/Em);
// the four interior slots blend Fp and Fm (eval_gregory, block_gregory_avx2).
constexpr int kGregoryBoundarySlot[12][3] = {{0, 0, 0},  {1, 0, 1},  {2, 0, 7},  {3, 0, 5},
                                             {0, 1, 2},  {3, 1, 6},  {0, 2, 16}, {3, 2, 12},
                                             {0, 3, 15}, {1, 3, 17}, {2, 3, 11}, {3, 3, 10}};

void eval_gregory(const uint32_t* cv, double s, double t, const float* pts, Eval& e) {
  double wu[4], du[4], wv[4], dv[4];
  bezier(s, wu, du), bezier(t, wv, dv);
  for (const auto& b : kGregoryBoundarySlot) {
    const int x = b[0], y = b[1];
    e.add(pts + 3 * size_t(cv[b[2]]), wu[x] * wv[y], du[x] * wv[y], wu[x] * dv[y]);
  }
  // Interior point of corner i: (a * Fp + (D - a) * Fm) / D with a and D linear in (s, t).
  struct Blend {
    int x, y, fp;
    double a, au, av, d, dd_u, dd_v;
  };
  const Blend blends[4] = {{1, 1, 3, s, 1, 0, s + t, 1, 1},
                           {2, 1, 8, t, 0, 1, t + 1.0 - s, -1, 1},
                           {2, 2, 13, 1.0 - s, -1, 0, 2.0 - s - t, -1, -1},
                           {1, 2, 18, 1.0 - t, 0, -1, 1.0 - t + s, 1, -1}};
  for (const Blend& b : blends) {
    double g = 0.5, gu = 0.0, gv = 0.0;
    if (b.d > 0.0) {
      g = b.a / b.d;
      gu = (b.au * b.d - b.a * b.dd_u) / (b.d * b.d);
      gv = (b.av * b.d - b.a * b.dd_v) / (b.d * b.d);
    }
    const double w = wu[b.x] * wv[b.y], w_u = du[b.x] * wv[b.y], w_v = wu[b.x] * dv[b.y];
    e.add(pts + 3 * size_t(cv[b.fp]), w * g, w_u * g + w * gu, w_v * g + w * gv);
    e.add(pts + 3 * size_t(cv[b.fp + 1]), w * (1 - g), w_u * (1 - g) - w * gu,
          w_v * (1 - g) - w * gv);
  }
}

// The common case, a regular patch away from boundaries and creases, all in float: rows
// accumulated, the derivatives scaled to ptex units.
inline void eval_plain(const uint32_t* cv, float s, float t, float scale, const float* pts,
                       float* p_out, float* du_out, float* dv_out) {
  float wu[4], du[4], wv[4], dv[4];
  bspline(s, wu, du), bspline(t, wv, dv);
  float p[3], pu[3], pv[3];
  tensor(cv, wu, du, wv, dv, pts, p, pu, pv);
  for (int c = 0; c < 3; ++c) {
    p_out[c] = p[c];
    if (du_out) du_out[c] = pu[c] * scale;
    if (dv_out) dv_out[c] = pv[c] * scale;
  }
}

constexpr int kLanes = 8;  // points per block of the AVX2 kernels

#if LIMN_X86_SIMD
// Up to 8 points of one regular (non-crease) patch at once, AVX2 lanes across the points: the
// 16 control points read once per block, each basis weight a vector over the points. Boundary
// folding is the same for every point, so it is done on the weight vectors.

// The cubic B-spline basis and its derivative, lane by lane.
__attribute__((target("avx2,fma"), always_inline)) inline void basis_avx2(__m256 a, __m256 w[4],
                                                                          __m256 d[4]) {
  const __m256 one = _mm256_set1_ps(1), sixth = _mm256_set1_ps(1.0f / 6);
  const __m256 three = _mm256_set1_ps(3);
  const __m256 a1 = _mm256_sub_ps(one, a), a2 = _mm256_mul_ps(a, a), a3 = _mm256_mul_ps(a2, a);
  w[0] = _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(a1, a1), a1), sixth);
  // (3a^3 - 6a^2 + 4) / 6 and (-3a^3 + 3a^2 + 3a + 1) / 6
  w[1] = _mm256_mul_ps(
      _mm256_fmadd_ps(three, a3, _mm256_fmadd_ps(_mm256_set1_ps(-6), a2, _mm256_set1_ps(4))),
      sixth);
  w[2] = _mm256_mul_ps(_mm256_fmadd_ps(_mm256_set1_ps(-3), a3,
                                       _mm256_fmadd_ps(three, a2, _mm256_fmadd_ps(three, a, one))),
                       sixth);
  w[3] = _mm256_mul_ps(a3, sixth);
  d[0] = _mm256_mul_ps(_mm256_set1_ps(-0.5f), _mm256_mul_ps(a1, a1));
  d[1] = _mm256_fmadd_ps(_mm256_set1_ps(1.5f), a2, _mm256_mul_ps(_mm256_set1_ps(-2), a));
  d[2] = _mm256_fmadd_ps(_mm256_set1_ps(-1.5f), a2, _mm256_add_ps(a, _mm256_set1_ps(0.5f)));
  d[3] = _mm256_mul_ps(_mm256_set1_ps(0.5f), a2);
}

// fold() on weight vectors.
__attribute__((target("avx2,fma"), always_inline)) inline void fold_avx2(__m256 w[4], bool low,
                                                                         bool high) {
  const __m256 two = _mm256_set1_ps(2), zero = _mm256_setzero_ps();
  if (low) w[1] = _mm256_fmadd_ps(two, w[0], w[1]), w[2] = _mm256_sub_ps(w[2], w[0]), w[0] = zero;
  if (high) w[2] = _mm256_fmadd_ps(two, w[3], w[2]), w[1] = _mm256_sub_ps(w[1], w[3]), w[3] = zero;
}

// Writes lane l's sums (position back at o, derivatives scaled to ptex units) to point idx[l]
// of the outputs, for the first n lanes.
__attribute__((target("avx2,fma"), always_inline)) inline void store_lanes_avx2(
    const __m256 p[3], const __m256 pu[3], const __m256 pv[3], const float o[3], float scale,
    const size_t* idx, int n, float* pos, float* du_out, float* dv_out) {
  alignas(32) float out[3][3][kLanes];  // position, du, dv; x y z; lanes
  const __m256 sc = _mm256_set1_ps(scale);
  for (int c = 0; c < 3; ++c) {
    _mm256_store_ps(out[0][c], _mm256_add_ps(p[c], _mm256_set1_ps(o[c])));
    _mm256_store_ps(out[1][c], _mm256_mul_ps(pu[c], sc));
    _mm256_store_ps(out[2][c], _mm256_mul_ps(pv[c], sc));
  }
  for (int l = 0; l < n; ++l) {
    const size_t at = 3 * size_t(idx[l]);
    for (int c = 0; c < 3; ++c) {
      pos[at + c] = out[0][c][l];
      if (du_out) du_out[at + c] = out[1][c][l];
      if (dv_out) dv_out[at + c] = out[2][c][l];
    }
  }
}

// sv, tv: kLanes patch coordinates (lanes past n padded with any value in [0, 1]); lane l's
// results go to point idx[l] of the outputs.
__attribute__((target("avx2,fma"))) void block_regular_avx2(const uint32_t* cv, uint8_t boundary,
                                                            const float* sv, const float* tv,
                                                            const size_t* idx, int n, float scale,
                                                            const float* pts, float* pos,
                                                            float* du_out, float* dv_out) {
  __m256 wu[4], du[4], wv[4], dv[4];
  basis_avx2(_mm256_loadu_ps(sv), wu, du);
  basis_avx2(_mm256_loadu_ps(tv), wv, dv);
  if (boundary) {
    fold_avx2(wu, boundary & 8, boundary & 2), fold_avx2(du, boundary & 8, boundary & 2);
    fold_avx2(wv, boundary & 1, boundary & 4), fold_avx2(dv, boundary & 1, boundary & 4);
  }
  // Rows first (u), then across rows (v); the three coordinates side by side, so that nine
  // independent accumulation chains hide the FMA latency. Control points are taken relative to
  // the patch's corner point (the weights sum to 1, the derivative weights to 0), which keeps
  // float sums from cancelling on tiny deep patches far from the origin.
  const float* origin = pts + 3 * size_t(cv[5]);
  const float o3[3] = {origin[0], origin[1], origin[2]};
  __m256 p[3], pu[3], pv[3];
  for (int c = 0; c < 3; ++c) p[c] = pu[c] = pv[c] = _mm256_setzero_ps();
  for (int y = 0; y < 4; ++y) {
    __m256 rp[3], ru[3];
    for (int c = 0; c < 3; ++c) rp[c] = ru[c] = _mm256_setzero_ps();
    for (int x = 0; x < 4; ++x) {
      const float* q = pts + 3 * size_t(cv[4 * y + x]);
      for (int c = 0; c < 3; ++c) {
        const __m256 qc = _mm256_set1_ps(q[c] - o3[c]);
        rp[c] = _mm256_fmadd_ps(wu[x], qc, rp[c]), ru[c] = _mm256_fmadd_ps(du[x], qc, ru[c]);
      }
    }
    for (int c = 0; c < 3; ++c) {
      p[c] = _mm256_fmadd_ps(wv[y], rp[c], p[c]);
      pu[c] = _mm256_fmadd_ps(wv[y], ru[c], pu[c]);
      pv[c] = _mm256_fmadd_ps(dv[y], rp[c], pv[c]);
    }
  }
  store_lanes_avx2(p, pu, pv, o3, scale, idx, n, pos, du_out, dv_out);
}

// The cubic Bezier basis and its derivative, lane by lane (bezier()'s).
__attribute__((target("avx2,fma"), always_inline)) inline void bezier_avx2(__m256 t, __m256 w[4],
                                                                           __m256 d[4]) {
  const __m256 one = _mm256_set1_ps(1), three = _mm256_set1_ps(3), six = _mm256_set1_ps(6);
  const __m256 s = _mm256_sub_ps(one, t), ss = _mm256_mul_ps(s, s), tt = _mm256_mul_ps(t, t);
  const __m256 ts = _mm256_mul_ps(t, s);
  w[0] = _mm256_mul_ps(ss, s), w[1] = _mm256_mul_ps(three, _mm256_mul_ps(t, ss));
  w[2] = _mm256_mul_ps(three, _mm256_mul_ps(tt, s)), w[3] = _mm256_mul_ps(tt, t);
  d[0] = _mm256_mul_ps(_mm256_set1_ps(-3), ss);
  d[1] = _mm256_fmsub_ps(three, ss, _mm256_mul_ps(six, ts));
  d[2] = _mm256_fmsub_ps(six, ts, _mm256_mul_ps(three, tt));
  d[3] = _mm256_mul_ps(three, tt);
}

// Adds point q (less o) weighted by w, w_u, w_v to the position and derivative sums.
__attribute__((target("avx2,fma"), always_inline)) inline void weigh_avx2(
    const float* q, const float o[3], __m256 w, __m256 w_u, __m256 w_v, __m256 p[3], __m256 pu[3],
    __m256 pv[3]) {
  for (int c = 0; c < 3; ++c) {
    const __m256 qc = _mm256_set1_ps(q[c] - o[c]);
    p[c] = _mm256_fmadd_ps(w, qc, p[c]), pu[c] = _mm256_fmadd_ps(w_u, qc, pu[c]);
    pv[c] = _mm256_fmadd_ps(w_v, qc, pv[c]);
  }
}

// Up to 8 points of one Gregory end cap at once, lanes across the points as block_regular_avx2:
// the Bezier basis and the rational interior blends (eval_gregory's, in float) as weight vectors,
// then the 20 points weighted, taken relative to the patch's first point.
__attribute__((target("avx2,fma"))) void block_gregory_avx2(const uint32_t* cv, const float* sv,
                                                            const float* tv, const size_t* idx,
                                                            int n, float scale, const float* pts,
                                                            float* pos, float* du_out,
                                                            float* dv_out) {
  const __m256 one = _mm256_set1_ps(1), zero = _mm256_setzero_ps();
  const __m256 s = _mm256_loadu_ps(sv), t = _mm256_loadu_ps(tv);
  __m256 wu[4], du[4], wv[4], dv[4];
  bezier_avx2(s, wu, du), bezier_avx2(t, wv, dv);
  const float* origin = pts + 3 * size_t(cv[0]);
  const float o3[3] = {origin[0], origin[1], origin[2]};
  __m256 p[3], pu[3], pv[3];
  for (int c = 0; c < 3; ++c) p[c] = pu[c] = pv[c] = zero;

  for (const auto& b : kGregoryBoundarySlot) {
    const int x = b[0], y = b[1];
    weigh_avx2(pts + 3 * size_t(cv[b[2]]), o3, _mm256_mul_ps(wu[x], wv[y]),
               _mm256_mul_ps(du[x], wv[y]), _mm256_mul_ps(wu[x], dv[y]), p, pu, pv);
  }
  // Interior point of corner i: (a Fp + (D - a) Fm) / D, a and D linear in (s, t); g = 1/2
  // where D = 0 (the corner itself, where the point's weight is 0 anyway).
  struct Blend {
    int x, y, fp;
    float a0, as, at, au, av, d0, ds, dt, dd_u, dd_v;
  };
  static constexpr Blend kBlends[4] = {{1, 1, 3, 0, 1, 0, 1, 0, 0, 1, 1, 1, 1},
                                       {2, 1, 8, 0, 0, 1, 0, 1, 1, -1, 1, -1, 1},
                                       {2, 2, 13, 1, -1, 0, -1, 0, 2, -1, -1, -1, -1},
                                       {1, 2, 18, 1, 0, -1, 0, -1, 1, 1, -1, 1, -1}};
  for (const Blend& b : kBlends) {
    const __m256 a = _mm256_fmadd_ps(
        _mm256_set1_ps(b.at), t, _mm256_fmadd_ps(_mm256_set1_ps(b.as), s, _mm256_set1_ps(b.a0)));
    const __m256 d = _mm256_fmadd_ps(
        _mm256_set1_ps(b.dt), t, _mm256_fmadd_ps(_mm256_set1_ps(b.ds), s, _mm256_set1_ps(b.d0)));
    const __m256 live = _mm256_cmp_ps(d, zero, _CMP_GT_OQ);
    const __m256 dsafe = _mm256_blendv_ps(one, d, live), inv = _mm256_div_ps(one, dsafe);
    const __m256 inv2 = _mm256_mul_ps(inv, inv);
    const __m256 g = _mm256_blendv_ps(_mm256_set1_ps(0.5f), _mm256_mul_ps(a, inv), live);
    const __m256 gu =
        _mm256_and_ps(live, _mm256_mul_ps(_mm256_fmsub_ps(_mm256_set1_ps(b.au), dsafe,
                                                          _mm256_mul_ps(a, _mm256_set1_ps(b.dd_u))),
                                          inv2));
    const __m256 gv =
        _mm256_and_ps(live, _mm256_mul_ps(_mm256_fmsub_ps(_mm256_set1_ps(b.av), dsafe,
                                                          _mm256_mul_ps(a, _mm256_set1_ps(b.dd_v))),
                                          inv2));
    const __m256 w = _mm256_mul_ps(wu[b.x], wv[b.y]), w_u = _mm256_mul_ps(du[b.x], wv[b.y]),
                 w_v = _mm256_mul_ps(wu[b.x], dv[b.y]);
    const __m256 h = _mm256_sub_ps(one, g);
    weigh_avx2(pts + 3 * size_t(cv[b.fp]), o3, _mm256_mul_ps(w, g),
               _mm256_fmadd_ps(w_u, g, _mm256_mul_ps(w, gu)),
               _mm256_fmadd_ps(w_v, g, _mm256_mul_ps(w, gv)), p, pu, pv);
    weigh_avx2(pts + 3 * size_t(cv[b.fp + 1]), o3, _mm256_mul_ps(w, h),
               _mm256_fmsub_ps(w_u, h, _mm256_mul_ps(w, gu)),
               _mm256_fmsub_ps(w_v, h, _mm256_mul_ps(w, gv)), p, pu, pv);
  }
  store_lanes_avx2(p, pu, pv, o3, scale, idx, n, pos, du_out, dv_out);
}

#endif  // LIMN_X86_SIMD

// One point of any patch, the scalar way.
void eval_point(const PatchTable& table, const float* pts, const PatchCoord& c, const PatchParam& p,
                float* pos, float* du, float* dv) {
  const size_t nr = table.regular_params.size();
  if (c.patch < nr && p.boundary == 0 && p.type == PatchType::regular) {
    eval_plain(&table.regular_points[16 * size_t(c.patch)], c.s, c.t, float(1u << p.depth), pts,
               pos, du, dv);
    return;
  }
  Eval e;
  if (c.patch < nr)
    eval_regular(&table.regular_points[16 * size_t(c.patch)], p, c.s, c.t, pts, e);
  else
    eval_gregory(&table.gregory_points[20 * (size_t(c.patch) - nr)], c.s, c.t, pts, e);
  const double scale = double(1u << p.depth);
  for (int k = 0; k < 3; ++k) {
    pos[k] = float(e.p[k]);
    if (du) du[k] = float(e.du[k] * scale);
    if (dv) dv[k] = float(e.dv[k] * scale);
  }
}

}  // namespace

PatchMap::PatchMap(const PatchTable& table) : table_(&table) {
  nodes_.assign(table.ptex_count, Node{{kNone, kNone, kNone, kNone}});
  const size_t nr = table.regular_params.size();
  for (size_t i = 0; i < table.patch_count(); ++i) {
    const PatchParam& p = i < nr ? table.regular_params[i] : table.gregory_params[i - nr];
    if (p.ptex >= table.ptex_count) throw std::logic_error("patch map: ptex face out of range");
    const uint32_t handle = kPatchBit | uint32_t(i);
    uint32_t node = p.ptex;
    if (p.depth == 0) {
      for (uint32_t& c : nodes_[node].child) c = handle;
      continue;
    }
    for (int l = p.depth - 1; l >= 0; --l) {
      const uint32_t q = ((p.u >> l) & 1u) | (((p.v >> l) & 1u) << 1);
      if (l == 0) {
        nodes_[node].child[q] = handle;
      } else {
        if (nodes_[node].child[q] == kNone) {
          nodes_[node].child[q] = uint32_t(nodes_.size());
          nodes_.push_back(Node{{kNone, kNone, kNone, kNone}});
        }
        if (nodes_[node].child[q] & kPatchBit) throw std::logic_error("patch map: patches overlap");
        node = nodes_[node].child[q];
      }
    }
  }
}

PatchCoord PatchMap::find(uint32_t ptex, double u, double v) const {
  if (ptex >= table_->ptex_count)
    throw InputError(fmt::format("patch map: ptex face {} out of range", ptex));
  u = std::clamp(u, 0.0, 1.0), v = std::clamp(v, 0.0, 1.0);
  uint32_t node = ptex;
  double x = u, y = v;
  for (int guard = 0; guard < 32; ++guard) {
    const uint32_t qx = x >= 0.5 ? 1u : 0u, qy = y >= 0.5 ? 1u : 0u;
    const uint32_t c = nodes_[node].child[qx | (qy << 1)];
    if (c == kNone) throw InputError(fmt::format("patch map: no patch at ptex face {}", ptex));
    if (c & kPatchBit) {
      const uint32_t i = c & ~kPatchBit;
      const size_t nr = table_->regular_params.size();
      const PatchParam& p = i < nr ? table_->regular_params[i] : table_->gregory_params[i - nr];
      const double scale = double(1u << p.depth);
      PatchCoord pc;
      pc.patch = i;
      pc.s = float(std::clamp(u * scale - p.u, 0.0, 1.0));
      pc.t = float(std::clamp(v * scale - p.v, 0.0, 1.0));
      return pc;
    }
    x = 2.0 * x - qx, y = 2.0 * y - qy;
    node = c;
  }
  throw std::logic_error("patch map: too deep");
}

void evaluate_patches(const PatchTable& table, std::span<const float> points,
                      std::span<const PatchCoord> coords, float* position, float* du, float* dv) {
  if (points.size() < 3 * table.point_count())
    throw InputError("evaluate patches: fewer points than the patch table needs");
  const size_t nr = table.regular_params.size(), np = table.patch_count();
  // Points of one plain or boundary regular patch go through the AVX2 block kernel 8 at a time:
  // within each window of 64 points they are grouped by patch first (a grid over a face
  // isolated around an extraordinary vertex meets each of its patches in short runs, row after
  // row).
  constexpr size_t kWindow = 64;
  const bool avx2 = cpu::features().avx2_fma;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, coords.size(), 1024), [&](const auto& range) {
    uint32_t group_patch[kWindow], group_size[kWindow];
    [[maybe_unused]] size_t members[kWindow][kWindow];  // read by the AVX2 kernel alone
    for (size_t w = range.begin(); w < range.end(); w += kWindow) {
      const size_t we = std::min(range.end(), w + kWindow);
      size_t groups = 0, last = 0;
      for (size_t i = w; i < we; ++i) {
        const PatchCoord& c = coords[i];
        if (c.patch >= np) throw InputError("evaluate patches: patch index out of range");
        const PatchParam& p =
            c.patch < nr ? table.regular_params[c.patch] : table.gregory_params[c.patch - nr];
        if (avx2 && c.patch < nr && p.type == PatchType::regular) {
          size_t g = last < groups && group_patch[last] == c.patch ? last : groups;
          for (size_t k = 0; g == groups && k < groups; ++k)
            if (group_patch[k] == c.patch) g = k;
          if (g == groups) group_patch[groups] = c.patch, group_size[groups++] = 0;
          members[g][group_size[g]++] = i;
          last = g;
          continue;
        }
        eval_point(table, points.data(), c, p, position + 3 * i, du ? du + 3 * i : nullptr,
                   dv ? dv + 3 * i : nullptr);
      }
#if LIMN_X86_SIMD  // else no groups: avx2 is false
      for (size_t g = 0; g < groups; ++g) {
        const uint32_t patch = group_patch[g];
        const PatchParam& p = table.regular_params[patch];
        const uint32_t* cv = &table.regular_points[16 * size_t(patch)];
        for (uint32_t k = 0; k < group_size[g]; k += kLanes) {
          const int n = int(std::min<uint32_t>(kLanes, group_size[g] - k));
          alignas(32) float sv[kLanes], tv[kLanes];
          for (int l = 0; l < kLanes; ++l) {
            const PatchCoord& c = coords[members[g][k + uint32_t(l < n ? l : n - 1)]];
            sv[l] = c.s, tv[l] = c.t;
          }
          block_regular_avx2(cv, p.boundary, sv, tv, &members[g][k], n, float(1u << p.depth),
                             points.data(), position, du, dv);
        }
      }
#endif
    }
  });
}

void evaluate_grids(const PatchTable& table, std::span<const float> points, int n, float* position,
                    float* du, float* dv) {
  if (n < 2 || n > 65536) throw InputError(fmt::format("evaluate grids: {} points per side", n));
  if (points.size() < 3 * table.point_count())
    throw InputError("evaluate grids: fewer points than the patch table needs");
  if (table.ptex_count == 0) return;
  const size_t nr = table.regular_params.size(), np = table.patch_count();
  const uint64_t m = uint64_t(n) - 1, per = uint64_t(n) * uint64_t(n);
  // Grid point i of a side lies at i / m; a patch at depth d, origin u0 holds the i with
  // u0 <= i 2^d / m < u0 + 1 (the far side's last point too), which is PatchMap::find's rule.
  auto range = [&](uint32_t o, uint32_t d, uint32_t& lo, uint32_t& hi) {
    const uint64_t cells = uint64_t(1) << d;
    lo = uint32_t((uint64_t(o) * m + cells - 1) >> d);  // ceil(o m / 2^d)
    const uint64_t end = (uint64_t(o) + 1) * m;         // i 2^d < end, or the last point
    hi = o + 1 == cells ? uint32_t(m) : uint32_t((end - 1) >> d);
  };
  const bool avx2 = cpu::features().avx2_fma;
  // One patch's grid points; sv, tv, idx: a block's lanes.
  auto one_patch = [&](size_t patch, float* sv, float* tv, size_t* idx) {
    const bool regular = patch < nr;
    const PatchParam& p = regular ? table.regular_params[patch] : table.gregory_params[patch - nr];
    uint32_t i0, i1, j0, j1;
    range(p.u, p.depth, i0, i1), range(p.v, p.depth, j0, j1);
    const float cells = float(1u << p.depth), inv = 1.0f / float(m);
    const bool block = avx2 && (regular ? p.type == PatchType::regular : true);
    [[maybe_unused]] const uint32_t* cv =
        regular ? &table.regular_points[16 * patch] : &table.gregory_points[20 * (patch - nr)];
    int lanes = 0;
    auto flush = [&] {
      if (lanes == 0) return;
      for (int l = lanes; l < kLanes; ++l) sv[l] = sv[0], tv[l] = tv[0];
#if LIMN_X86_SIMD  // else never a block: avx2 is false
      if (regular)
        block_regular_avx2(cv, p.boundary, sv, tv, idx, lanes, cells, points.data(), position, du,
                           dv);
      else
        block_gregory_avx2(cv, sv, tv, idx, lanes, cells, points.data(), position, du, dv);
#endif
      lanes = 0;
    };
    for (uint32_t j = j0; j <= j1; ++j)  // empty where the patch holds no grid line
      for (uint32_t i = i0; i <= i1; ++i) {
        const float s = std::clamp(float(i) * inv * cells - float(p.u), 0.0f, 1.0f);
        const float t = std::clamp(float(j) * inv * cells - float(p.v), 0.0f, 1.0f);
        const size_t o = size_t(p.ptex) * per + size_t(j) * size_t(n) + i;
        if (block) {
          sv[lanes] = s, tv[lanes] = t, idx[lanes++] = o;
          if (lanes == kLanes) flush();
          continue;
        }
        eval_point(table, points.data(), PatchCoord{uint32_t(patch), s, t}, p, position + 3 * o,
                   du ? du + 3 * o : nullptr, dv ? dv + 3 * o : nullptr);
      }
    flush();
  };
  // Threads taking ranges of a table built in one piece, which lists patches level by level,
  // write the same faces' grids at once (sharing cache lines: the car's grids took 1.4x as long
  // on 2 threads); so such tables are worked through by blocks of kBlockFaces ptex faces, each
  // block's patches in table order (a stable counting sort). Larger tables come from region
  // builds (cages over 32,768 faces; regions hold disjoint faces), where ranges of the table
  // keep threads apart and the sort's scattered reads cost more than they save (the 800k-quad
  // torus's grids took 1.1x as long).
  constexpr size_t kSortUpTo = size_t(1) << 18;
  constexpr uint32_t kBlockFaces = 16;
  if (np > kSortUpTo) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, np, 64), [&](const auto& r) {
      alignas(32) float sv[kLanes], tv[kLanes];
      size_t idx[kLanes];
      for (size_t patch = r.begin(); patch != r.end(); ++patch) one_patch(patch, sv, tv, idx);
    });
    return;
  }
  auto block_of = [&](size_t patch) {
    return (patch < nr ? table.regular_params[patch].ptex : table.gregory_params[patch - nr].ptex) /
           kBlockFaces;
  };
  const size_t blocks = (size_t(table.ptex_count) + kBlockFaces - 1) / kBlockFaces;
  std::vector<uint32_t> first(blocks + 1, 0), order(np);
  for (size_t patch = 0; patch < np; ++patch) ++first[block_of(patch) + 1];
  for (size_t b = 0; b < blocks; ++b) first[b + 1] += first[b];
  for (size_t patch = 0; patch < np; ++patch) order[first[block_of(patch)]++] = uint32_t(patch);
  for (size_t b = blocks; b > 0; --b) first[b] = first[b - 1];  // back to each block's start
  first[0] = 0;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks), [&](const auto& r) {
    alignas(32) float sv[kLanes], tv[kLanes];
    size_t idx[kLanes];
    for (size_t at = first[r.begin()]; at != first[r.end()]; ++at)
      one_patch(order[at], sv, tv, idx);
  });
}

}  // namespace limn

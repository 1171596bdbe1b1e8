// Stencil tables: applying them to points (an AVX2 kernel for three channels, chosen at run
// time), composing them, and a cage's positions pushed through a chain of them.
#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cstring>
#include <vector>

#include "core/cpu.hpp"
#include "core/parallel.hpp"
#include "limn/subdiv/refine.hpp"
#include "refine_levels.hpp"

#if LIMN_X86_SIMD
#include <immintrin.h>
#endif

namespace limn {

constexpr int kMaxChannels = 16;

namespace {

#if LIMN_X86_SIMD
// Three channels in one 4-wide double vector: one fused multiply-add per stencil entry, and
// the sum stays in double (a valence-360 vertex sums ~1000 terms). Chosen at run time, so the
// library still runs on x86-64 processors without AVX2.
// One point's three floats as four doubles (lane 3 zero), without reading past the point.
__attribute__((target("avx2,fma"), always_inline)) inline __m256d load3_avx2(const float* s) {
  double xy;
  std::memcpy(&xy, s, sizeof xy);
  return _mm256_cvtps_pd(_mm_insert_ps(_mm_castpd_ps(_mm_set_sd(xy)), _mm_load_ss(s + 2), 0x20));
}

__attribute__((target("avx2,fma"))) void apply3_avx2(const StencilTable& t, size_t b, size_t e,
                                                     const float* in, float* out) {
  const uint32_t* off = t.offsets.data();
  for (size_t i = b; i < e; ++i) {
    const uint32_t* idx = t.indices.data() + off[i];
    const float* w = t.row_weights(i);
    const uint32_t n = off[i + 1] - off[i];
    // Two accumulators halve the chain of dependent additions per stencil.
    __m256d a0 = _mm256_setzero_pd(), a1 = _mm256_setzero_pd();
    uint32_t j = 0;
    for (; j + 1 < n; j += 2) {
      a0 = _mm256_fmadd_pd(_mm256_set1_pd(double(w[j])), load3_avx2(in + 3 * size_t(idx[j])), a0);
      a1 = _mm256_fmadd_pd(_mm256_set1_pd(double(w[j + 1])),
                           load3_avx2(in + 3 * size_t(idx[j + 1])), a1);
    }
    if (j < n)
      a0 = _mm256_fmadd_pd(_mm256_set1_pd(double(w[j])), load3_avx2(in + 3 * size_t(idx[j])), a0);
    const __m256d acc = _mm256_add_pd(a0, a1);
    const __m128 r = _mm256_cvtpd_ps(acc);
    float* o = out + 3 * i;
    const double xy = _mm_cvtsd_f64(_mm_castps_pd(r));  // x and y, stored without alignment
    std::memcpy(o, &xy, sizeof xy);
    o[2] = _mm_cvtss_f32(_mm_movehl_ps(r, r));
  }
}
#endif

}  // namespace

namespace refine_detail {

// Applies stencils [b, e) serially; out gets table.size() points.
void apply_serial(const StencilTable& table, size_t b, size_t e, const float* in, float* out,
                  int channels) {
  const uint32_t* off = table.offsets.data();
  const size_t ch = size_t(channels);
  // Sums in double: a valence-360 vertex sums ~1000 terms, and float accumulation alone would
  // cost ~1e-6 of the model's size per level.
  if (channels == 3) {
#if LIMN_X86_SIMD
    if (cpu::features().avx2_fma) return apply3_avx2(table, b, e, in, out);
#endif
    for (size_t i = b; i < e; ++i) {
      const uint32_t* idx = table.indices.data() + off[i];
      const float* w = table.row_weights(i);
      double x = 0, y = 0, z = 0;
      for (uint32_t j = 0; j < off[i + 1] - off[i]; ++j) {
        const float* s = in + 3 * size_t(idx[j]);
        const double wj = w[j];
        x += wj * s[0], y += wj * s[1], z += wj * s[2];
      }
      float* o = out + 3 * i;
      o[0] = float(x), o[1] = float(y), o[2] = float(z);
    }
    return;
  }
  double acc[kMaxChannels];
  for (size_t i = b; i < e; ++i) {
    const uint32_t* idx = table.indices.data() + off[i];
    const float* w = table.row_weights(i);
    for (size_t k = 0; k < ch; ++k) acc[k] = 0.0;
    for (uint32_t j = 0; j < off[i + 1] - off[i]; ++j) {
      const float* s = in + size_t(idx[j]) * ch;
      const double wj = w[j];
      for (size_t k = 0; k < ch; ++k) acc[k] += wj * s[k];
    }
    float* o = out + i * ch;
    for (size_t k = 0; k < ch; ++k) o[k] = static_cast<float>(acc[k]);
  }
}

}  // namespace refine_detail

using namespace refine_detail;

void apply_stencils(const StencilTable& table, const float* in, float* out, int channels) {
  if (channels < 1 || channels > kMaxChannels)
    throw std::invalid_argument(
        fmt::format("apply_stencils: {} channels (1-{})", channels, kMaxChannels));
  parallel_range(table.size(), 4096,
                 [&](size_t b, size_t e) { apply_serial(table, b, e, in, out, channels); });
}

StencilTable compose_stencils(const StencilTable& outer, const StencilTable& inner) {
  const size_t n = outer.size();
  // Dense scratch over the source points, cleared through the touched list: merging without
  // sorting the terms keeps composition linear in the entries. One scratch per thread; two
  // passes (sizes, then entries in place) so the table is never held twice.
  size_t sources = 0;
  for (uint32_t i : inner.indices) sources = std::max(sources, size_t(i) + 1);
  struct Scratch {
    std::vector<double> acc;
    std::vector<uint8_t> seen;
    std::vector<uint32_t> touched;
  };
  tbb::enumerable_thread_specific<Scratch> scratch([&] {
    Scratch s;
    s.acc.assign(sources, 0.0);
    s.seen.assign(sources, 0);
    return s;
  });
  // Merges point p's terms into s.touched (sorted, exact cancellations dropped).
  auto merge = [&](Scratch& s, size_t p) {
    s.touched.clear();
    const float* ow = outer.row_weights(p);
    for (uint32_t j = outer.offsets[p]; j < outer.offsets[p + 1]; ++j) {
      const uint32_t q = outer.indices[j];
      const double w = ow[j - outer.offsets[p]];
      const float* iw = inner.row_weights(q);
      for (uint32_t k = inner.offsets[q]; k < inner.offsets[q + 1]; ++k) {
        const uint32_t src = inner.indices[k];
        if (!s.seen[src]) s.seen[src] = 1, s.touched.push_back(src);
        s.acc[src] += w * double(iw[k - inner.offsets[q]]);
      }
    }
    std::sort(s.touched.begin(), s.touched.end());
    size_t kept = 0;
    for (uint32_t src : s.touched) {
      s.seen[src] = 0;
      if (s.acc[src] != 0.0)
        s.touched[kept++] = src;  // exact cancellation: nothing to read
      else
        s.acc[src] = 0.0;
    }
    s.touched.resize(kept);
  };
  StencilTable out;
  // Up to a million points: one pass into per-chunk parts, then one copy.
  if (n < (size_t(1) << 20)) {
    const size_t chunk = 2048, chunks = (n + chunk - 1) / chunk;
    std::vector<StencilTable> parts(chunks);
    parallel_range(chunks, 1, [&](size_t cb, size_t ce) {
      Scratch& s = scratch.local();
      for (size_t c = cb; c < ce; ++c) {
        StencilTable& t = parts[c];
        for (size_t p = c * chunk; p < std::min(n, (c + 1) * chunk); ++p) {
          merge(s, p);
          for (uint32_t src : s.touched) {
            t.indices.push_back(src);
            t.weights.push_back(static_cast<float>(s.acc[src]));
            s.acc[src] = 0.0;
          }
          t.offsets.push_back(uint32_t(t.indices.size()));
        }
      }
    });
    out.offsets.reserve(n + 1);
    for (const StencilTable& t : parts) {
      const size_t base = out.indices.size();
      if (base + t.indices.size() > UINT32_MAX)
        throw InputError("composed stencils need more than 2^32 entries");
      for (size_t i = 1; i < t.offsets.size(); ++i)
        out.offsets.push_back(uint32_t(base + t.offsets[i]));
      out.indices.insert(out.indices.end(), t.indices.begin(), t.indices.end());
      out.weights.insert(out.weights.end(), t.weights.begin(), t.weights.end());
    }
    return out;
  }
  refill(out.offsets, n + 1, 0u);
  std::vector<uint32_t> sizes;
  refill(sizes, n, 0u);
  parallel_range(n, 4096, [&](size_t b, size_t e) {
    Scratch& s = scratch.local();
    for (size_t p = b; p < e; ++p) {
      merge(s, p);
      sizes[p] = uint32_t(s.touched.size());
      for (uint32_t src : s.touched) s.acc[src] = 0.0;
    }
  });
  size_t total = 0;
  for (size_t p = 0; p < n; ++p) {
    total += sizes[p];
    if (total > UINT32_MAX) throw InputError("composed stencils need more than 2^32 entries");
    out.offsets[p + 1] = uint32_t(total);
  }
  std::vector<uint32_t>().swap(sizes);
  refill(out.indices, total, 0u);
  refill(out.weights, total, 0.0f);
  parallel_range(n, 4096, [&](size_t b, size_t e) {
    Scratch& s = scratch.local();
    for (size_t p = b; p < e; ++p) {
      merge(s, p);
      uint32_t* ix = out.indices.data() + out.offsets[p];
      float* wt = out.weights.data() + out.offsets[p];
      for (size_t i = 0; i < s.touched.size(); ++i) {
        const uint32_t src = s.touched[i];
        ix[i] = src, wt[i] = static_cast<float>(s.acc[src]);
        s.acc[src] = 0.0;
      }
    }
  });
  return out;
}

namespace {

StencilTable compose_chain(const std::vector<StencilTable>& tables, int level) {
  if (level < 1 || level > int(tables.size()))
    throw InputError(fmt::format("cage_stencils: level {} not refined", level));
  StencilTable flat = tables[0];
  for (int k = 1; k < level; ++k) flat = compose_stencils(tables[size_t(k)], flat);
  return flat;
}

}  // namespace

StencilTable cage_stencils(const UniformRefinement& r, int level) {
  return compose_chain(r.stencils, level);
}

StencilTable cage_stencils(const SparseRefinement& r, int level) {
  return compose_chain(r.stencils, level);
}

namespace refine_detail {

std::vector<float> apply_chain(const std::vector<StencilTable>& tables, const Mesh& cage,
                               int level) {
  std::vector<float> cur = cage.positions, next;
  for (int k = 0; k < level; ++k) {
    refill(next, 3 * tables[size_t(k)].size(), 0.0f);
    apply_stencils(tables[size_t(k)], cur.data(), next.data(), 3);
    cur.swap(next);
  }
  return cur;
}

}  // namespace refine_detail

}  // namespace limn

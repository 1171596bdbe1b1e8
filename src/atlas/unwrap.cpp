#include "limn/atlas/unwrap.hpp"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "atlas/chart.hpp"
#include "atlas/pack.hpp"
#include "limn/simplify/surface.hpp"

namespace limn {

namespace {

// Least UV area over the area of its convex hull a chart may have: a chart with long arms or
// deep bays is cut, as it would leave packing space no other chart can use. Merges must keep a
// little more, since a merge saves only one seam.
constexpr double kMinFill = 0.55;
constexpr double kMinMergedFill = 0.6;

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void check_options(const UnwrapOptions& o) {
  if (!(o.max_stretch >= 1 && o.max_stretch <= 100))
    throw InputError(fmt::format("unwrap: max_stretch {}: must be 1-100", o.max_stretch));
  if (o.size < 16 || o.size > 16384)
    throw InputError(fmt::format("unwrap: size {}: must be 16-16384 texels", o.size));
  if (o.tiles < 1 || o.tiles > 100)
    throw InputError(fmt::format("unwrap: tiles {}: must be 1-100 (UDIM 1001-1100)", o.tiles));
  if (o.padding < 0 || 4 * o.padding >= o.size)
    throw InputError(fmt::format(
        "unwrap: padding {}: must be 0 or more and under a quarter of the size", o.padding));
  if (!(o.texels_per_unit >= 0 && std::isfinite(o.texels_per_unit)))
    throw InputError(
        fmt::format("unwrap: texels_per_unit {}: must be a number >= 0", o.texels_per_unit));
}

// Builds charts over disjoint face sets, maps them and judges the maps.
struct Charter {
  const VsaSurface& s;
  double max_stretch;
  double max_extent;  ///< longest side a chart may have (model units), so it fits in a tile
  atlas::ChartScratch scratch;
  uint32_t next_id = 0;
  size_t splits = 0;

  Charter(const VsaSurface& surface, double stretch, double extent)
      : s(surface),
        max_stretch(stretch),
        max_extent(extent),
        scratch{std::vector<uint32_t>(surface.face_count(), kNone),
                std::vector<uint32_t>(surface.mesh->corner_count(), kNone)} {}

  // The chart over `faces` with its map; false when the map is not good enough (a single face
  // always is). A kept chart is oriented for packing and holds its fill and stretch. Safe on
  // several threads for disjoint face sets with distinct ids.
  bool try_chart(std::vector<uint32_t> faces, uint32_t id, atlas::Chart& ch) {
    ch = atlas::build_chart(s, std::move(faces), id, scratch);
    atlas::ChartQuality q;
    if (ch.faces.size() == 1) {
      if (!atlas::conformal_map(s, ch)) atlas::planar_map(s, ch);
      q = atlas::chart_quality(s, ch);
    } else {
      // Normals spread over more than a hemisphere on average cannot flatten well: no need to
      // try.
      if (ch.euler != 1 || ch.normal_sum < 0.5 * ch.area || !atlas::conformal_map(s, ch))
        return false;
      q = atlas::chart_quality(s, ch);
      if (q.flipped != 0 || q.stretch_l2 > max_stretch || atlas::boundary_crosses(ch)) return false;
    }
    const atlas::ChartExtent e = atlas::orient_chart(ch);
    ch.fill = e.hull_area > 0 ? ch.area / e.hull_area : 1;
    ch.stretch_l2 = q.stretch_l2, ch.stretch_linf = q.stretch_linf;
    return ch.faces.size() == 1 || (ch.fill >= kMinFill && e.width <= max_extent);
  }

  // Charts over the face sets, each cut in two (along its sharpest feature) until its map is
  // good; every round tries all open sets at once.
  std::vector<atlas::Chart> chart_all(std::vector<std::vector<uint32_t>> open) {
    std::vector<atlas::Chart> charts;
    while (!open.empty()) {
      std::vector<atlas::Chart> tried(open.size());
      std::vector<uint8_t> kept(open.size());
      std::vector<std::vector<std::vector<uint32_t>>> pieces(open.size());
      tbb::parallel_for(size_t(0), open.size(), [&](size_t i) {
        kept[i] = try_chart(std::move(open[i]), next_id + uint32_t(i), tried[i]);
        if (!kept[i]) pieces[i] = atlas::split_faces(s, tried[i].faces);
      });
      next_id += uint32_t(open.size());
      open.clear();
      for (size_t i = 0; i < tried.size(); ++i) {
        if (kept[i]) {
          charts.push_back(std::move(tried[i]));
          continue;
        }
        ++splits;
        for (auto& piece : pieces[i]) open.push_back(std::move(piece));
      }
    }
    return charts;
  }
};

// Per face: its chart.
std::vector<uint32_t> face_labels(const std::vector<atlas::Chart>& charts, size_t faces) {
  std::vector<uint32_t> label(faces, kNone);
  for (uint32_t k = 0; k < charts.size(); ++k)
    for (uint32_t f : charts[k].faces) label[f] = k;
  return label;
}

// Smooths chart borders: a face with at most one neighbour in its own chart and more in another
// one moves there (a notch filled, a spike cut). Such a face is a leaf of its chart, so no chart
// falls apart; a few passes straighten the sawtooth borders a split leaves on a triangle mesh.
void smooth_borders(const VsaSurface& s, std::vector<uint32_t>& label, int passes) {
  const Mesh& mesh = *s.mesh;
  std::vector<uint32_t> size;
  for (uint32_t l : label) {
    if (l >= size.size()) size.resize(l + 1, 0);
    ++size[l];
  }
  for (int pass = 0; pass < passes; ++pass) {
    size_t moves = 0;
    for (uint32_t f = 0; f < label.size(); ++f) {
      uint32_t own = 0, other = kNone, other_count = 0;
      uint32_t seen[8], counts[8], kinds = 0;
      for (uint32_t c = mesh.face_offsets[f]; c < mesh.face_offsets[f + 1]; ++c) {
        const uint32_t g = s.across(c);
        if (g == kNone) continue;
        if (label[g] == label[f]) {
          ++own;
          continue;
        }
        uint32_t k = 0;
        while (k < kinds && seen[k] != label[g]) ++k;
        if (k == kinds) {
          if (kinds == 8) continue;
          seen[kinds] = label[g], counts[kinds++] = 0;
        }
        if (++counts[k] > other_count) other_count = counts[k], other = seen[k];
      }
      if (own > 1 || other_count <= own || size[label[f]] < 2) continue;
      --size[label[f]];
      ++size[other];
      label[f] = other;
      ++moves;
    }
    if (moves == 0) break;
  }
}

// Merges neighbouring charts while the merged map stays good and compact, the pairs sharing the
// longest borders first.
void merge_charts(Charter& charter, std::vector<atlas::Chart>& charts) {
  const VsaSurface& s = charter.s;
  for (int pass = 0; pass < 4; ++pass) {
    const std::vector<uint32_t> label = face_labels(charts, s.face_count());
    std::vector<std::pair<uint64_t, uint32_t>> pairs;  // (a << 32 | b, shared edges)
    {
      std::vector<uint64_t> keys;
      for (uint32_t c = 0; c < s.topo.corner_twin.size(); ++c) {
        const uint32_t tw = s.topo.corner_twin[c];
        if (tw >= kNonManifold || tw < c) continue;
        const uint32_t a = label[s.topo.corner_face[c]], b = label[s.topo.corner_face[tw]];
        if (a != b) keys.push_back(uint64_t(std::min(a, b)) << 32 | std::max(a, b));
      }
      std::sort(keys.begin(), keys.end());
      for (size_t i = 0; i < keys.size();) {
        size_t j = i;
        while (j < keys.size() && keys[j] == keys[i]) ++j;
        pairs.emplace_back(keys[i], uint32_t(j - i));
        i = j;
      }
    }
    std::stable_sort(pairs.begin(), pairs.end(),
                     [](const auto& x, const auto& y) { return x.second > y.second; });
    std::vector<uint8_t> touched(charts.size(), 0);
    size_t merges = 0;
    for (const auto& [key, shared] : pairs) {
      const uint32_t a = uint32_t(key >> 32), b = uint32_t(key);
      if (touched[a] || touched[b]) continue;
      std::vector<uint32_t> faces = charts[a].faces;
      faces.insert(faces.end(), charts[b].faces.begin(), charts[b].faces.end());
      atlas::Chart merged;
      if (!charter.try_chart(std::move(faces), charter.next_id++, merged)) continue;
      // A merge that leaves the chart much less convex than its hull costs more packing space
      // than the seam it saves.
      if (merged.fill < kMinMergedFill) continue;
      charts[a] = std::move(merged);
      charts[b].faces.clear();
      touched[a] = touched[b] = 1;
      ++merges;
    }
    std::erase_if(charts, [](const atlas::Chart& ch) { return ch.faces.empty(); });
    if (merges == 0) break;
  }
}

}  // namespace

UnwrapResult unwrap_mesh(const Mesh& mesh, const UnwrapOptions& o, std::string_view name) {
  check_options(o);
  const auto t0 = std::chrono::steady_clock::now();
  const VsaSurface s = prepare_surface(mesh, name);
  UnwrapResult result;
  UnwrapStats& st = result.stats;

  // Charts top-down, then their borders smoothed (and the charts that no longer map well cut
  // again), then neighbours merged while their maps stay good.
  // At a given density, a chart must also fit in half a tile with its padding: charts nearly a
  // tile long would each take a tile of their own.
  const double max_extent =
      o.texels_per_unit > 0 ? (o.size / 2 - 2 * o.padding - 2) / o.texels_per_unit : INFINITY;
  Charter charter(s, o.max_stretch, max_extent);
  std::vector<atlas::Chart> charts =
      charter.chart_all(atlas::label_pieces(s, std::vector<uint32_t>(s.face_count(), 0)));
  std::vector<uint32_t> label = face_labels(charts, s.face_count());
  smooth_borders(s, label, 4);
  charts = charter.chart_all(atlas::label_pieces(s, label));
  merge_charts(charter, charts);
  st.splits = charter.splits;
  double l2 = 0, area = 0;
  for (const atlas::Chart& ch : charts) {
    l2 += ch.area * ch.stretch_l2 * ch.stretch_l2;
    area += ch.area;
    st.stretch_linf = std::max(st.stretch_linf, ch.stretch_linf);
  }
  st.stretch_l2 = area > 0 ? std::sqrt(l2 / area) : 0;
  st.charts = charts.size();
  st.chart_ms = ms_since(t0);

  const auto t1 = std::chrono::steady_clock::now();
  const atlas::PackOptions po{o.size, o.tiles, o.padding, o.texels_per_unit};
  const atlas::Packing pack = atlas::pack_charts(charts, po);
  if (!pack.fits) {
    if (o.texels_per_unit > 0)
      throw InputError(fmt::format(
          "{}: {} texels per unit is too dense: the {} charts do not fit in {} tile{} of {}x{}",
          name, o.texels_per_unit, charts.size(), o.tiles, o.tiles == 1 ? "" : "s", o.size,
          o.size));
    throw InputError(fmt::format("{}: {} charts do not fit in {} tile{} of {}x{} at any density",
                                 name, charts.size(), o.tiles, o.tiles == 1 ? "" : "s", o.size,
                                 o.size));
  }
  st.pack_ms = ms_since(t1);
  st.tiles = pack.tiles;
  st.size = o.size;
  st.texels_per_unit = pack.texels_per_unit;
  const double texels = double(pack.tiles) * o.size * o.size;
  st.utilization = double(pack.taken) / texels;
  st.coverage = double(pack.covered) / texels;

  // The mesh with one UV per chart vertex, in tile units (u tile = index % 10, v tile = index /
  // 10).
  result.mesh = mesh;
  Mesh& out = result.mesh;
  out.uvs.clear();
  out.uv_indices.assign(mesh.corner_count(), 0);
  result.face_chart.assign(mesh.face_count(), 0);
  result.chart_tile.resize(charts.size());
  for (uint32_t k = 0; k < charts.size(); ++k) {
    const atlas::Chart& ch = charts[k];
    const atlas::Placement& p = pack.placements[k];
    result.chart_tile[k] = p.tile;
    const uint32_t base = uint32_t(out.uvs.size() / 2);
    const double tu = p.tile % 10, tv = p.tile / 10;
    for (size_t v = 0; v < ch.vertex_source.size(); ++v) {
      double texel[2];
      atlas::placed_texel(ch.uv[2 * v], ch.uv[2 * v + 1], pack.poses[k], p, pack.texels_per_unit,
                          o.padding, texel);
      out.uvs.push_back(float(tu + texel[0] / o.size));
      out.uvs.push_back(float(tv + texel[1] / o.size));
    }
    uint32_t slot = 0;
    for (uint32_t f : ch.faces) {
      result.face_chart[f] = k;
      for (uint32_t c = mesh.face_offsets[f]; c < mesh.face_offsets[f + 1]; ++c)
        out.uv_indices[c] = base + ch.corner_vertex[slot++];
    }
  }
  return result;
}

}  // namespace limn

// Anchors, chains, chain splitting, cluster polygons and their triangulation.
#include "simplify/polygonize.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "core/vec3.hpp"
#include "simplify/cluster_edit.hpp"
#include "simplify/triangulate.hpp"

namespace limn {

namespace {

double point_segment(Vec3d p, Vec3d a, Vec3d b) {
  const Vec3d ab = b - a, ap = p - a;
  const double l2 = dot(ab, ab);
  if (!(l2 > 0)) return length(ap);
  const double t = std::clamp(dot(ap, ab) / l2, 0.0, 1.0);
  return length(ap - t * ab);
}

inline uint64_t pair_key(uint32_t a, uint32_t b) {
  return a < b ? (uint64_t(a) << 32 | b) : (uint64_t(b) << 32 | a);
}

struct TriKey {
  uint32_t v[3];
  bool operator==(const TriKey& o) const {
    return v[0] == o.v[0] && v[1] == o.v[1] && v[2] == o.v[2];
  }
};
struct TriHash {
  size_t operator()(const TriKey& k) const {
    uint64_t h = k.v[0];
    h = h * 0x9E3779B97F4A7C15ull ^ k.v[1];
    h = h * 0x9E3779B97F4A7C15ull ^ k.v[2];
    return size_t(h ^ (h >> 29));
  }
};
TriKey tri_key(uint32_t a, uint32_t b, uint32_t c) {
  TriKey k{{a, b, c}};
  std::sort(k.v, k.v + 3);
  return k;
}

class Mesher {
 public:
  Mesher(const VsaSurface& s, const Partition& p, const MeshingOptions& o)
      : s_(s), m_(*s.mesh), p_(p), o_(o) {
    const double d = s.bbox.diagonal();
    eps_area_ = 1e-10 * d * d;
  }

  // Returns kNone on success, else a cluster that could not be meshed.
  uint32_t run(SimplifiedMesh& out) {
    chain_edges();
    trace_loops();
    build_chains();
    resolve_duplicates();
    return emit(out);
  }

 private:
  Vec3d pos(uint32_t v) const {
    const float* q = &m_.positions[3 * size_t(v)];
    return {q[0], q[1], q[2]};
  }
  uint32_t origin(uint32_t c) const { return m_.face_vertices[c]; }
  bool is_cb(uint32_t c) const {
    const uint32_t t = s_.topo.corner_twin[c];
    return t == kNone || p_.label[s_.topo.corner_face[c]] != p_.label[s_.topo.corner_face[t]];
  }

  void chain_edges() {
    const size_t nc = m_.corner_count(), nv = m_.vertex_count();
    cb_.assign(nc, 0);
    deg_.assign(nv, 0);
    for (uint32_t c = 0; c < nc; ++c) {
      if (!is_cb(c)) continue;
      cb_[c] = 1;
      const uint32_t t = s_.topo.corner_twin[c];
      if (t != kNone && t < c) continue;  // count each undirected edge once
      const uint32_t a = origin(c), b = origin(s_.topo.corner_next[c]);
      if (deg_[a] < 255) ++deg_[a];
      if (deg_[b] < 255) ++deg_[b];
    }
    anchor_.assign(nv, 0);
    for (size_t v = 0; v < nv; ++v)
      if (deg_[v] >= 3 || (deg_[v] > 0 && s_.vertex_kind[v] == 3)) anchor_[v] = 1;
  }

  // The boundary half-edge of the same cluster that follows boundary half-edge c around its
  // cluster: turn around c's end vertex through the cluster's faces.
  uint32_t next_boundary(uint32_t c) const {
    uint32_t d = s_.topo.corner_next[c];
    for (size_t guard = 0; !cb_[d]; ++guard) {
      if (guard > m_.corner_count()) throw std::logic_error("simplify: broken cluster boundary");
      d = s_.topo.corner_next[s_.topo.corner_twin[d]];
    }
    return d;
  }

  void trace_loops() {
    const size_t nc = m_.corner_count();
    std::vector<uint8_t> seen(nc, 0);
    loop_offsets_.assign(1, 0);
    loop_corners_.clear();
    loop_cluster_.clear();
    for (uint32_t c0 = 0; c0 < nc; ++c0) {
      if (!cb_[c0] || seen[c0]) continue;
      uint32_t c = c0;
      do {
        seen[c] = 1;
        loop_corners_.push_back(c);
        c = next_boundary(c);
      } while (c != c0);
      loop_offsets_.push_back(static_cast<uint32_t>(loop_corners_.size()));
      loop_cluster_.push_back(p_.label[s_.topo.corner_face[c0]]);
    }
  }

  size_t loop_count() const { return loop_cluster_.size(); }

  void build_chains() {
    const size_t nv = m_.vertex_count();
    // Loops that meet no anchor (an island cluster, a mesh-boundary loop inside one cluster) get
    // one at their first vertex; the loop on the other side sees it too.
    for (size_t l = 0; l < loop_count(); ++l) {
      bool any = false;
      for (uint32_t i = loop_offsets_[l]; i < loop_offsets_[l + 1] && !any; ++i)
        any = anchor_[origin(loop_corners_[i])];
      if (!any) {
        anchor_[origin(loop_corners_[loop_offsets_[l]])] = 1;
        ++stats_.forced_anchors;
      }
    }
    keep_.assign(nv, 0);
    for (size_t v = 0; v < nv; ++v) keep_[v] = anchor_[v];
    chain_of_edge_.assign(s_.topo.edge_count(), kNone);
    chain_offsets_.assign(1, 0);
    chain_verts_.clear();
    for (size_t l = 0; l < loop_count(); ++l) {
      const uint32_t b = loop_offsets_[l], n = loop_offsets_[l + 1] - b;
      uint32_t start = 0;
      while (!anchor_[origin(loop_corners_[b + start])]) ++start;
      for (uint32_t i = 0; i < n;) {
        // Piece from the anchor at position start+i to the next anchor.
        uint32_t j = i + 1;
        while (j < n && !anchor_[origin(loop_corners_[b + (start + j) % n])]) ++j;
        const uint32_t first = loop_corners_[b + (start + i) % n];
        if (chain_of_edge_[s_.topo.corner_edge[first]] == kNone) {
          const uint32_t id = static_cast<uint32_t>(chain_offsets_.size() - 1);
          for (uint32_t q = i; q < j; ++q) {
            const uint32_t c = loop_corners_[b + (start + q) % n];
            chain_verts_.push_back(origin(c));
            chain_of_edge_[s_.topo.corner_edge[c]] = id;
          }
          chain_verts_.push_back(origin(loop_corners_[b + (start + j) % n]));
          chain_offsets_.push_back(static_cast<uint32_t>(chain_verts_.size()));
          simplify_chain(id);
        }
        i = j;
      }
    }
    stats_.chains = chain_offsets_.size() - 1;
  }

  // Keeps the vertex of chain `id` between positions i and j (j - i >= 2) farthest from segment
  // ij (from point i when both ends coincide). Returns its position.
  uint32_t split_at_farthest(uint32_t id, uint32_t i, uint32_t j) {
    const uint32_t* v = &chain_verts_[chain_offsets_[id]];
    const Vec3d a = pos(v[i]), b = pos(v[j]);
    double best = -1;
    uint32_t k = i + 1;
    for (uint32_t q = i + 1; q < j; ++q) {
      const double d = point_segment(pos(v[q]), a, b);
      if (d > best) best = d, k = q;
    }
    keep_[v[k]] = 1;
    return k;
  }

  void simplify_chain(uint32_t id) {
    const uint32_t* v = &chain_verts_[chain_offsets_[id]];
    const uint32_t m = chain_offsets_[id + 1] - chain_offsets_[id] - 1;  // edges
    std::vector<std::pair<uint32_t, uint32_t>> stack;
    if (v[0] == v[m]) {
      // Closed: at least three segments, or the loop collapses to an edge.
      if (m < 3) return;
      const uint32_t k = split_at_farthest(id, 0, m);
      const uint32_t longer_i = k >= m - k ? 0 : k, longer_j = k >= m - k ? k : m;
      const uint32_t k2 = split_at_farthest(id, longer_i, longer_j);
      stack.push_back({0, std::min(k, k2)});
      stack.push_back({std::min(k, k2), std::max(k, k2)});
      stack.push_back({std::max(k, k2), m});
    } else {
      stack.push_back({0, m});
    }
    const double thr = o_.split_threshold;
    while (!stack.empty()) {
      const auto [i, j] = stack.back();
      stack.pop_back();
      if (j - i < 2) continue;
      const Vec3d a = pos(v[i]), b = pos(v[j]);
      const double len = length(b - a);
      double best = -1;
      uint32_t k = i + 1;
      for (uint32_t q = i + 1; q < j; ++q) {
        const double d = point_segment(pos(v[q]), a, b);
        if (d > best) best = d, k = q;
      }
      if (len > 0 && !(best > thr * len)) continue;
      keep_[v[k]] = 1;
      stack.push_back({i, k});
      stack.push_back({k, j});
    }
  }

  // Two chains whose kept vertices would give the same output edge: split one of them again.
  void resolve_duplicates() {
    for (int round = 0; round < 64; ++round) {
      std::unordered_map<uint64_t, std::array<uint32_t, 3>> seen;
      size_t conflicts = 0;
      for (uint32_t id = 0; id + 1 < chain_offsets_.size(); ++id) {
        const uint32_t* v = &chain_verts_[chain_offsets_[id]];
        const uint32_t m = chain_offsets_[id + 1] - chain_offsets_[id] - 1;
        uint32_t i = 0;
        for (uint32_t j = 1; j <= m; ++j) {
          if (!keep_[v[j]] && j < m) continue;
          const uint64_t key = pair_key(v[i], v[j]);
          auto [it, fresh] = seen.try_emplace(key, std::array<uint32_t, 3>{id, i, j});
          if (!fresh) {
            const auto [id2, i2, j2] = it->second;
            if (j - i >= 2 && j - i >= j2 - i2) {
              split_at_farthest(id, i, j);
              ++conflicts;
            } else if (j2 - i2 >= 2) {
              split_at_farthest(id2, i2, j2);
              ++conflicts;
            }
          }
          i = j;
        }
      }
      stats_.forced_splits += conflicts;
      if (conflicts == 0) return;
    }
  }

  // The kept vertices of loop l, in order.
  std::vector<uint32_t> loop_kept(size_t l) const {
    std::vector<uint32_t> out;
    for (uint32_t i = loop_offsets_[l]; i < loop_offsets_[l + 1]; ++i) {
      const uint32_t v = origin(loop_corners_[i]);
      if (keep_[v]) out.push_back(v);
    }
    return out;
  }

  double polygon_area(const std::vector<uint32_t>& q) const {
    Vec3d n{0, 0, 0};
    const Vec3d o = pos(q[0]);
    for (size_t i = 1; i + 1 < q.size(); ++i) {
      const Vec3d c = cross(pos(q[i]) - o, pos(q[i + 1]) - o);
      n = {n.x + c.x, n.y + c.y, n.z + c.z};
    }
    return 0.5 * length(n);
  }

  // Cuts hole loop H out of one of `pieces` (simple polygons of the same cluster) with two
  // junctions: a vertex the two share, or a bridge edge that is not yet an output edge. The piece
  // P becomes P[o1..o2] + H[h2..h1] and P[o2..o1] + H[h1..h2]: two simple polygons whose bridges
  // run once each way, so the cluster stays one oriented, edge-manifold surface with the hole.
  bool cut_hole(std::vector<std::vector<uint32_t>>& pieces, const std::vector<uint32_t>& H) {
    // First junction: the closest pair (a shared vertex has distance 0) over all pieces.
    size_t bp = kNone, o1 = 0, h1 = 0;
    double best = std::numeric_limits<double>::infinity();
    for (size_t pi = 0; pi < pieces.size(); ++pi) {
      const std::vector<uint32_t>& P = pieces[pi];
      for (size_t a = 0; a < P.size(); ++a)
        for (size_t b = 0; b < H.size(); ++b) {
          const bool shared = P[a] == H[b];
          if (!shared && used_edges_.count(pair_key(P[a], H[b]))) continue;
          const double d = shared ? -1.0 : length(pos(P[a]) - pos(H[b]));
          if (d < best) best = d, bp = pi, o1 = a, h1 = b;
        }
    }
    if (bp == kNone) return false;
    const std::vector<uint32_t> P = pieces[bp];
    const size_t np = P.size(), nh = H.size();
    // Second junction: from a vertex of P about opposite o1, the closest usable vertex of H
    // other than h1; trying other starting points of P when it has none.
    size_t o2 = kNone, h2 = kNone;
    for (size_t shift = 0; shift < np && o2 == kNone; ++shift) {
      for (int side = 0; side < 2 && o2 == kNone; ++side) {
        const size_t a = (o1 + np / 2 + (side ? np - shift : shift)) % np;
        if (a == o1) continue;
        double bd = std::numeric_limits<double>::infinity();
        for (size_t b = 0; b < nh; ++b) {
          if (b == h1) continue;
          const bool shared = P[a] == H[b];
          if (!shared && (used_edges_.count(pair_key(P[a], H[b])) ||
                          pair_key(P[a], H[b]) == pair_key(P[o1], H[h1])))
            continue;
          const double d = shared ? -1.0 : length(pos(P[a]) - pos(H[b]));
          if (d < bd) bd = d, o2 = a, h2 = b;
        }
      }
    }
    if (o2 == kNone) return false;
    auto piece = [&](size_t from_p, size_t to_p, size_t from_h, size_t to_h) {
      std::vector<uint32_t> out;
      for (size_t i = from_p;; i = (i + 1) % np) {
        out.push_back(P[i]);
        if (i == to_p) break;
      }
      for (size_t i = from_h;; i = (i + 1) % nh) {
        out.push_back(H[i]);
        if (i == to_h) break;
      }
      // A shared junction appears at both ends of its run; keep it once.
      if (out.back() == out.front()) out.pop_back();
      std::vector<uint32_t> dedup;
      for (uint32_t v : out)
        if (dedup.empty() || dedup.back() != v) dedup.push_back(v);
      return dedup;
    };
    std::vector<uint32_t> A = piece(o1, o2, h2, h1), B = piece(o2, o1, h1, h2);
    for (const auto& [x, y] : {std::pair{P[o1], H[h1]}, std::pair{P[o2], H[h2]}})
      if (x != y) {
        used_edges_.insert(pair_key(x, y));
        ++stats_.bridges;
      }
    if (A.size() < 3 || B.size() < 3) return false;
    pieces[bp] = std::move(A);
    pieces.push_back(std::move(B));
    return true;
  }

  bool triangulate(uint32_t k, const std::vector<uint32_t>& q, std::vector<uint32_t>& tris) {
    const uint32_t n = static_cast<uint32_t>(q.size());
    double pn[3];
    p_.proxy_normal(k, pn);
    const Vec3d proxy{pn[0], pn[1], pn[2]};
    auto ok = [&](uint32_t i, uint32_t j) {
      return q[i] != q[j] && !used_edges_.count(pair_key(q[i], q[j]));
    };
    auto weight = [&](uint32_t i, uint32_t j, uint32_t l) {
      const uint32_t a = q[i], b = q[j], c = q[l];
      constexpr double inf = std::numeric_limits<double>::infinity();
      if (a == b || b == c || a == c) return inf;
      const Vec3d x = cross(pos(b) - pos(a), pos(c) - pos(a));
      const double area = 0.5 * length(x);
      if (!(area > eps_area_)) return inf;
      // Triangles facing against the cluster's proxy would fold the surface.
      return dot(x, proxy) < 0 ? 11 * area : area;
    };
    std::vector<uint32_t> local;
    if (!triangulate_polygon(n, ok, weight, local)) {
      return false;
    }
    // Repeated vertices (bridges, pinches) can let two diagonals or triangles coincide. Each
    // diagonal (by positions) borders two triangles; distinct ones must join distinct vertices.
    std::unordered_set<uint64_t> positions, diag;
    std::unordered_set<TriKey, TriHash> own;
    for (size_t t = 0; t < local.size(); t += 3) {
      const uint32_t x[3] = {local[t], local[t + 1], local[t + 2]};
      // A triangle can repeat one elsewhere only if all its edges already exist, i.e. are
      // polygon sides; checked here rather than for every candidate inside the programme.
      const TriKey key = tri_key(q[x[0]], q[x[1]], q[x[2]]);
      if (used_tris_.count(key) || !own.insert(key).second) {
        return false;
      }
      for (int e = 0; e < 3; ++e) {
        const uint32_t i = std::min(x[e], x[(e + 1) % 3]), j = std::max(x[e], x[(e + 1) % 3]);
        if (j == i + 1 || (i == 0 && j == n - 1)) continue;
        if (positions.insert(pair_key(i, j)).second && !diag.insert(pair_key(q[i], q[j])).second) {
          return false;
        }
      }
    }
    for (uint64_t d : diag) used_edges_.insert(d);
    for (const TriKey& t : own) used_tris_.insert(t);
    tris.clear();
    for (uint32_t x : local) tris.push_back(q[x]);
    return true;
  }

  // Fan from an interior vertex of cluster k (one not on any chain) to every edge of loop q.
  bool fan(uint32_t k, const std::vector<uint32_t>& q, std::vector<uint32_t>& tris) {
    std::vector<uint32_t> faces{p_.any_face[k]};
    std::unordered_set<uint32_t> in_faces{faces[0]};
    for (size_t i = 0; i < faces.size(); ++i)
      for (uint32_t c = m_.face_offsets[faces[i]]; c < m_.face_offsets[faces[i] + 1]; ++c) {
        const uint32_t g = s_.across(c);
        if (g != kNone && p_.label[g] == k && in_faces.insert(g).second) faces.push_back(g);
      }
    Vec3d centre{0, 0, 0};
    for (uint32_t v : q) centre = {centre.x + pos(v).x, centre.y + pos(v).y, centre.z + pos(v).z};
    centre = {centre.x / double(q.size()), centre.y / double(q.size()),
              centre.z / double(q.size())};
    std::vector<std::pair<double, uint32_t>> candidates;
    std::unordered_set<uint32_t> seen;
    for (uint32_t f : faces)
      for (uint32_t v : m_.face(f))
        if (deg_[v] == 0 && !keep_[v] && seen.insert(v).second)
          candidates.push_back({length(pos(v) - centre), v});
    std::sort(candidates.begin(), candidates.end());
    for (size_t c = 0; c < std::min<size_t>(candidates.size(), 16); ++c) {
      const uint32_t P = candidates[c].second;
      bool good = true;
      for (size_t i = 0; i < q.size() && good; ++i) {
        const uint32_t a = q[i], b = q[(i + 1) % q.size()];
        const double area = 0.5 * length(cross(pos(a) - pos(P), pos(b) - pos(P)));
        good = area > eps_area_;
      }
      if (!good) continue;
      tris.clear();
      for (size_t i = 0; i < q.size(); ++i) {
        const uint32_t a = q[i], b = q[(i + 1) % q.size()];
        tris.insert(tris.end(), {P, a, b});
        used_edges_.insert(pair_key(P, a));
        used_tris_.insert(tri_key(P, a, b));
      }
      keep_[P] = 1;
      return true;
    }
    return false;
  }

  uint32_t emit(SimplifiedMesh& out) {
    const size_t K = p_.cluster_count();
    std::vector<std::vector<uint32_t>> cluster_loops(K);
    for (size_t l = 0; l < loop_count(); ++l)
      cluster_loops[loop_cluster_[l]].push_back(static_cast<uint32_t>(l));
    // Every chain segment is an output edge before any diagonal is chosen.
    for (uint32_t id = 0; id + 1 < chain_offsets_.size(); ++id) {
      const uint32_t* v = &chain_verts_[chain_offsets_[id]];
      const uint32_t m = chain_offsets_[id + 1] - chain_offsets_[id] - 1;
      uint32_t i = 0;
      for (uint32_t j = 1; j <= m; ++j)
        if (keep_[v[j]] || j == m) used_edges_.insert(pair_key(v[i], v[j])), i = j;
    }
    std::set<std::vector<uint32_t>> polygon_keys;
    std::vector<uint32_t> out_index(m_.vertex_count(), kNone);
    Mesh& mesh = out.mesh;
    auto add_face = [&](std::span<const uint32_t> vs, uint32_t k) {
      std::vector<uint32_t> ids;
      for (uint32_t v : vs) {
        if (out_index[v] == kNone) {
          const float* x = &m_.positions[3 * size_t(v)];
          out_index[v] = mesh.add_vertex(x[0], x[1], x[2]);
          out.vertex_source.push_back(v);
        }
        ids.push_back(out_index[v]);
      }
      mesh.add_face(ids);
      out.face_cluster.push_back(k);
    };
    std::vector<uint32_t> tris;
    for (uint32_t k = 0; k < K; ++k) {
      if (p_.size[k] == 0) continue;
      std::vector<std::vector<uint32_t>> loops;
      for (uint32_t l : cluster_loops[k]) loops.push_back(loop_kept(l));
      if (loops.empty()) {
        // A closed component in one cluster: no boundary at all. Split it.
        return k;
      }
      for (const auto& L : loops)
        if (L.size() < 3) {
          return k;
        }
      // A loop through the same vertex twice: since the cluster is edge-connected, the part
      // between the two visits bounds a hole that touches the rest of the boundary there. Such
      // parts become loops of their own and are cut in like any hole (the shared vertex is one
      // of the two junctions).
      for (size_t i = 0; i < loops.size(); ++i) {
        for (bool again = true; again;) {
          again = false;
          std::vector<uint32_t> inner;
          {
            std::vector<uint32_t>& q = loops[i];
            std::unordered_map<uint32_t, size_t> at;
            for (size_t j = 0; j < q.size(); ++j) {
              auto [it, fresh] = at.try_emplace(q[j], j);
              if (fresh) continue;
              const size_t a = it->second;
              inner.assign(q.begin() + ptrdiff_t(a), q.begin() + ptrdiff_t(j));
              q.erase(q.begin() + ptrdiff_t(a), q.begin() + ptrdiff_t(j));
              if (inner.size() < 3 || q.size() < 3) return k;
              again = true;
              break;
            }
          }
          // Appended only once `q` is no longer used: appending may move the loops.
          if (again) loops.push_back(std::move(inner));
        }
      }
      std::sort(loops.begin(), loops.end(),
                [](const auto& a, const auto& b) { return a.size() > b.size(); });
      std::vector<std::vector<uint32_t>> pieces{loops[0]};
      for (size_t h = 1; h < loops.size(); ++h)
        if (!cut_hole(pieces, loops[h])) {
          return k;
        }
      for (const std::vector<uint32_t>& q : pieces) {
        std::vector<uint32_t> key = q;
        std::sort(key.begin(), key.end());
        const bool simple = std::adjacent_find(key.begin(), key.end()) == key.end();
        if (o_.polygons && simple && polygon_area(q) > eps_area_) {
          const bool tri = key.size() == 3;
          const bool dup = tri ? used_tris_.count(tri_key(key[0], key[1], key[2])) > 0
                               : polygon_keys.count(key) > 0;
          if (!dup) {
            if (tri) used_tris_.insert(tri_key(key[0], key[1], key[2]));
            polygon_keys.insert(std::move(key));
            add_face(q, k);
            ++stats_.polygons;
            continue;
          }
        }
        if (triangulate(k, q, tris)) {
          ++stats_.triangulated;
        } else if (pieces.size() == 1 && simple && fan(k, q, tris)) {
          ++stats_.fans;
        } else {
          return k;
        }
        for (size_t t = 0; t < tris.size(); t += 3)
          add_face(std::span<const uint32_t>(&tris[t], 3), k);
      }
    }
    for (size_t v = 0; v < m_.vertex_count(); ++v) stats_.anchors += anchor_[v];
    stats_.kept_vertices = mesh.vertex_count();
    out.stats = stats_;
    return kNone;
  }

  const VsaSurface& s_;
  const Mesh& m_;
  const Partition& p_;
  const MeshingOptions& o_;
  double eps_area_ = 0;
  MeshingStats stats_;
  std::vector<uint8_t> cb_, deg_, anchor_, keep_;
  std::vector<uint32_t> loop_offsets_, loop_corners_, loop_cluster_;
  std::vector<uint32_t> chain_of_edge_, chain_offsets_, chain_verts_;
  std::unordered_set<uint64_t> used_edges_;
  std::unordered_set<TriKey, TriHash> used_tris_;
};

}  // namespace

SimplifiedMesh polygonize(const VsaSurface& s, Partition& p, const MeshingOptions& options) {
  size_t splits = 0;
  for (int attempt = 0; attempt < 256; ++attempt) {
    SimplifiedMesh out;
    Mesher mesher(s, p, options);
    const uint32_t bad = mesher.run(out);
    if (bad == kNone) {
      out.stats.cluster_splits = splits;
      return out;
    }
    if (split_cluster(s, p, bad) == kNone)
      throw std::runtime_error("simplify: cluster " + std::to_string(bad) +
                               " cannot be meshed and has a single face");
    ++splits;
  }
  throw std::runtime_error("simplify: no valid mesh after 256 cluster splits");
}

}  // namespace limn

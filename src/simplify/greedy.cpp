// Jin, Wu, Liu's local greedy optimiser of the L2,1 energy, driven by a queue of boundary edges.
#include "simplify/greedy.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "simplify/cluster_edit.hpp"

namespace limn {

namespace {

// |N + sign v| - |N| without the cancellation of subtracting two close norms:
// (|N + v|^2 - |N|^2) / (|N + v| + |N|).
inline double norm_change(const double* N, double n0, const double* v, double sign) {
  const double a[3] = {N[0] + sign * v[0], N[1] + sign * v[1], N[2] + sign * v[2]};
  const double na = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  const double den = na + n0;
  if (!(den > 0)) return 0;
  const double num = sign * 2 * (N[0] * v[0] + N[1] * v[1] + N[2] * v[2]) +
                     (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  return num / den;
}

// Longest walk around one vertex before the O(1) test gives up and searches.
constexpr int kMaxFan = 64;

}  // namespace

GreedyOptimizer::GreedyOptimizer(const VsaSurface& s, Partition& p, GreedyOptions options)
    : s_(s), p_(p), o_(std::move(options)) {
  const size_t ne = s.topo.edge_count(), nc = s.topo.corner_face.size();
  queued_.assign(ne, 0);
  listed_.assign(ne, 0);
  edge_stamp_.assign(ne, 0);
  visit_.assign(s.face_count(), 0);
  owner_.assign(s.face_count(), 0);
  grow_clusters();
  for (uint32_t c = 0; c < nc; ++c) {
    const uint32_t t = s.topo.corner_twin[c];
    if (t == kNone || t < c || !boundary(c)) continue;
    push(c);
    listed_[s.topo.corner_edge[c]] = 1;
    list_.push_back(c);
  }
}

void GreedyOptimizer::refresh_norms() {
  norm_.resize(p_.cluster_count());
  for (uint32_t k = 0; k < p_.cluster_count(); ++k) norm_[k] = p_.norm(k);
}

void GreedyOptimizer::grow_clusters() {
  const size_t K = p_.cluster_count();
  if (cluster_stamp_.size() >= K) return;
  const size_t old = cluster_stamp_.size();
  cluster_stamp_.resize(K, 0);
  checked_at_.resize(K, 0);
  stale_.resize(K, 0);
  checked_normal_.resize(3 * K, 0.0);
  for (size_t k = old; k < K; ++k) p_.proxy_normal(uint32_t(k), &checked_normal_[3 * k]);
}

bool GreedyOptimizer::boundary(uint32_t c) const {
  const uint32_t t = s_.topo.corner_twin[c];
  return t != kNone && p_.label[s_.topo.corner_face[c]] != p_.label[s_.topo.corner_face[t]];
}

void GreedyOptimizer::push(uint32_t c) {
  const uint32_t e = s_.topo.corner_edge[c];
  if (queued_[e]) return;
  queued_[e] = 1;
  queue_.push_back(c);
}

void GreedyOptimizer::touch(std::span<const uint32_t> faces) {
  grow_clusters();
  ++clock_;
  const Mesh& m = *s_.mesh;
  for (uint32_t f : faces) {
    cluster_stamp_[p_.label[f]] = clock_;
    // Relabelled from outside: a large change, whatever its normal says.
    checked_normal_[3 * size_t(p_.label[f])] = 2.0;
    for (uint32_t c = m.face_offsets[f]; c < m.face_offsets[f + 1]; ++c) {
      const uint32_t t = s_.topo.corner_twin[c];
      if (t == kNone) continue;
      cluster_stamp_[p_.label[s_.topo.corner_face[t]]] = clock_;
      if (!boundary(c)) continue;
      push(c);
      const uint32_t e = s_.topo.corner_edge[c];
      if (!listed_[e]) listed_[e] = 1, list_.push_back(c);
    }
  }
}

double GreedyOptimizer::gain(uint32_t f, uint32_t to) const {
  const double* v = &s_.vec[3 * size_t(f)];
  const uint32_t from = p_.label[f];
  return norm_change(&p_.N[3 * size_t(to)], norm_[to], v, +1.0) +
         norm_change(&p_.N[3 * size_t(from)], norm_[from], v, -1.0);
}

bool GreedyOptimizer::fan_in_cluster(uint32_t from_corner, uint32_t to_corner, uint32_t l) const {
  // Faces around the shared vertex, from the neighbour across `from_corner`'s edge to the one
  // across `to_corner`'s edge (which follows it in the face): all must be in cluster l.
  uint32_t t = s_.topo.corner_twin[from_corner];
  for (int step = 0; step < kMaxFan; ++step) {
    const uint32_t next = s_.rotate(t);
    if (next == kNone) return false;
    if (next == to_corner) return true;
    if (p_.label[s_.topo.corner_face[next]] != l) return false;
    t = next;
  }
  return false;
}

bool GreedyOptimizer::search_connected(uint32_t f, uint32_t l, std::span<const uint32_t> targets) {
  // One search wave per neighbour of f in l, grown in turn inside l without f. Waves that meet
  // are joined; when all are joined, l stays connected. When every wave of a joined set has run
  // out, that set is a part of l only f held on to: the move would disconnect l. Alternating
  // makes a cut-off part cost about its own size, however large the rest of l is.
  if (++generation_ == 0) std::fill(visit_.begin(), visit_.end(), 0u), generation_ = 1;
  const Mesh& m = *s_.mesh;
  const size_t n = targets.size();
  waves_.resize(n);
  parent_.resize(n);
  visit_[f] = generation_;
  owner_[f] = 0xFF;
  for (size_t i = 0; i < n; ++i) {
    waves_[i].clear();
    waves_[i].push_back(targets[i]);
    parent_[i] = static_cast<uint8_t>(i);
    visit_[targets[i]] = generation_;
    owner_[targets[i]] = static_cast<uint8_t>(i);
  }
  auto find = [&](uint8_t i) {
    while (parent_[i] != i) i = parent_[i];
    return i;
  };
  size_t groups = n, visited = n;
  std::vector<size_t>& head = heads_;
  head.assign(n, 0);
  for (;;) {
    for (size_t i = 0; i < n; ++i) {
      if (head[i] == waves_[i].size()) {
        // Wave i is spent; is every wave joined with it spent too?
        const uint8_t r = find(static_cast<uint8_t>(i));
        bool alive = false;
        for (size_t j = 0; j < n && !alive; ++j)
          alive = find(static_cast<uint8_t>(j)) == r && head[j] < waves_[j].size();
        if (!alive) {
          ++st_.refused_disconnect;
          return false;
        }
        continue;
      }
      const uint32_t g = waves_[i][head[i]++];
      for (uint32_t c = m.face_offsets[g]; c < m.face_offsets[g + 1]; ++c) {
        const uint32_t h = s_.across(c);
        if (h == kNone || p_.label[h] != l) continue;
        if (visit_[h] != generation_) {
          visit_[h] = generation_;
          owner_[h] = static_cast<uint8_t>(i);
          waves_[i].push_back(h);
          ++visited;
          continue;
        }
        if (owner_[h] == 0xFF) continue;  // f itself
        const uint8_t a = find(static_cast<uint8_t>(i)), b = find(owner_[h]);
        if (a != b) {
          parent_[a] = b;
          if (--groups == 1) return true;
        }
      }
    }
    if (visited > o_.search_budget) {
      ++st_.refused_budget;
      return false;
    }
  }
}

bool GreedyOptimizer::removable(uint32_t f) {
  const uint32_t l = p_.label[f];
  if (p_.size[l] < 2) return false;
  const Mesh& m = *s_.mesh;
  const uint32_t o = m.face_offsets[f], n = m.face_offsets[f + 1] - o;
  uint32_t in_mask = 0, count = 0;
  uint32_t targets_buf[8];
  const bool small = n <= 8;
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t g = s_.across(o + i);
    if (g != kNone && p_.label[g] == l) {
      if (small) in_mask |= 1u << i, targets_buf[count] = g;
      ++count;
    }
  }
  if (count == 0) return false;  // f alone in a cluster with other faces: never split further
  if (count == 1) {
    ++st_.local_checks;  // a path through f would need two neighbours of f in l
    return true;
  }
  if (small) {
    // Neighbours in l joined around a shared corner of f by faces all in l form one group.
    uint32_t links = 0;
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t j = i + 1 == n ? 0 : i + 1;
      if ((in_mask >> i & 1) && (in_mask >> j & 1) && fan_in_cluster(o + i, o + j, l)) ++links;
    }
    if (links + 1 >= count) {
      ++st_.local_checks;
      return true;
    }
    ++st_.search_checks;
    return search_connected(f, l, std::span<const uint32_t>(targets_buf, count));
  }
  std::vector<uint32_t> targets;
  if (count > 64) return false;  // a face with that many neighbours in l: not worth a search
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t g = s_.across(o + i);
    if (g != kNone && p_.label[g] == l) targets.push_back(g);
  }
  ++st_.search_checks;
  return search_connected(f, l, targets);
}

void GreedyOptimizer::apply(uint32_t f, uint32_t to, double drop) {
  const uint32_t from = p_.label[f];
  p_.move(s_, f, to);
  norm_[from] = p_.norm(from), norm_[to] = p_.norm(to);
  ++clock_;
  cluster_stamp_[from] = cluster_stamp_[to] = clock_;
  ++st_.moves;
  if (journaling_) journal_.push_back({f, from});
  if (o_.on_move) o_.on_move(f, from, to, drop);
  // The moved face's edges changed state; its neighbours' own moves may have become possible.
  const Mesh& m = *s_.mesh;
  for (uint32_t c = m.face_offsets[f]; c < m.face_offsets[f + 1]; ++c) {
    const uint32_t g = s_.across(c);
    if (g == kNone) continue;
    for (uint32_t d = m.face_offsets[g]; d < m.face_offsets[g + 1]; ++d) {
      if (s_.topo.corner_twin[d] == kNone || !boundary(d)) continue;
      push(d);
      const uint32_t e = s_.topo.corner_edge[d];
      if (!listed_[e]) listed_[e] = 1, list_.push_back(d);
    }
  }
}

void GreedyOptimizer::evaluate(uint32_t c) {
  const uint32_t t = s_.topo.corner_twin[c];
  if (t == kNone) return;
  const uint32_t fm = s_.topo.corner_face[c], fn = s_.topo.corner_face[t];
  const uint32_t k = p_.label[fm], l = p_.label[fn];
  if (k == l) return;
  ++st_.evaluations;
  edge_stamp_[s_.topo.corner_edge[c]] = clock_;
  // Gains in |N_k| + |N_l| of the two moves (E drops by twice the gain).
  double g1 = gain(fn, k), g2 = gain(fm, l);
  const double t1 = o_.min_gain * s_.area[fn], t2 = o_.min_gain * s_.area[fm];
  // Try the better move first; if its face cannot leave its cluster, the other.
  for (int attempt = 0; attempt < 2; ++attempt) {
    const bool first = g1 - t1 >= g2 - t2;
    const uint32_t f = first ? fn : fm, to = first ? k : l;
    const double g = first ? g1 : g2, thr = first ? t1 : t2;
    if (!(g > thr) || !(g > 0)) return;
    if (removable(f)) {
      apply(f, to, 2 * g);
      return;
    }
    (first ? g1 : g2) = -1;
  }
}

GreedyStats GreedyOptimizer::run() {
  grow_clusters();
  refresh_norms();
  st_ = GreedyStats{};
  st_.energy_before = p_.energy();
  for (;;) {
    while (head_ < queue_.size()) {
      const uint32_t c = queue_[head_++];
      queued_[s_.topo.corner_edge[c]] = 0;
      evaluate(c);
    }
    queue_.clear();
    head_ = 0;
    // Clusters whose proxy normal turned by more than the drift tolerance since their boundary
    // was last queued whole are stale: their boundary edges scored before the change are queued
    // again. Nothing stale: done, without touching the list.
    bool any = false;
    for (uint32_t k = 0; k < p_.cluster_count(); ++k) {
      stale_[k] = 0;
      if (cluster_stamp_[k] <= checked_at_[k]) continue;
      double n[3];
      p_.proxy_normal(k, n);
      double* r = &checked_normal_[3 * size_t(k)];
      const double d2 = (n[0] - r[0]) * (n[0] - r[0]) + (n[1] - r[1]) * (n[1] - r[1]) +
                        (n[2] - r[2]) * (n[2] - r[2]);
      if (d2 <= o_.drift * o_.drift && o_.drift > 0) continue;
      stale_[k] = 1;
      any = true;
      checked_at_[k] = clock_;
      r[0] = n[0], r[1] = n[1], r[2] = n[2];
    }
    if (!any) break;
    // Drop edges that are no longer on a boundary from the list on the way.
    size_t w = 0;
    for (size_t i = 0; i < list_.size(); ++i) {
      const uint32_t c = list_[i];
      const uint32_t e = s_.topo.corner_edge[c];
      if (!boundary(c)) {
        listed_[e] = 0;
        continue;
      }
      list_[w++] = c;
      const uint32_t k = p_.label[s_.topo.corner_face[c]];
      const uint32_t l = p_.label[s_.topo.corner_face[s_.topo.corner_twin[c]]];
      if ((stale_[k] || stale_[l]) &&
          std::max(cluster_stamp_[k], cluster_stamp_[l]) > edge_stamp_[e])
        push(c);
    }
    list_.resize(w);
    if (queue_.empty()) break;
    ++st_.rounds;
  }
  st_.energy_after = p_.energy();
  return st_;
}

void GreedyOptimizer::begin_journal() {
  journaling_ = true;
  journal_.clear();
}

void GreedyOptimizer::end_journal() {
  journaling_ = false;
  journal_.clear();
}

void GreedyOptimizer::rollback() {
  journaling_ = false;
  std::vector<uint32_t> faces;
  faces.reserve(journal_.size());
  for (size_t i = journal_.size(); i-- > 0;) {
    const auto [f, from] = journal_[i];
    p_.move(s_, f, from);
    faces.push_back(f);
  }
  journal_.clear();
  touch(faces);
}

std::pair<uint32_t, uint32_t> GreedyOptimizer::cheapest_merge(uint32_t exclude, double* cost) {
  std::pair<uint32_t, uint32_t> best{kNone, kNone};
  double least = std::numeric_limits<double>::infinity();
  for (uint32_t c : list_) {
    if (!boundary(c)) continue;
    const uint32_t k = p_.label[s_.topo.corner_face[c]];
    const uint32_t l = p_.label[s_.topo.corner_face[s_.topo.corner_twin[c]]];
    if (k == exclude || l == exclude) continue;
    const double e = merge_cost(p_, k, l);
    if (e < least) least = e, best = {std::min(k, l), std::max(k, l)};
  }
  if (cost) *cost = least;
  return best;
}

GreedyStats greedy_optimize(const VsaSurface& s, Partition& p, const GreedyOptions& options) {
  GreedyOptimizer g(s, p, options);
  return g.run();
}

}  // namespace limn

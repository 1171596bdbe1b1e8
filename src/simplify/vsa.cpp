// The VSA pipeline: seeding, optimisation with splits up to K or an error target, meshing.
#include "limn/simplify/vsa.hpp"

#include <algorithm>
#include <chrono>
#include <utility>

#include "core/timer.hpp"
#include "simplify/carry_attributes.hpp"
#include "simplify/cluster_edit.hpp"
#include "simplify/greedy.hpp"
#include "simplify/lloyd.hpp"
#include "simplify/polygonize.hpp"
#include "simplify/seeding.hpp"

namespace limn {

namespace {

void add(GreedyStats& a, const GreedyStats& b) {
  if (a.moves == 0 && a.evaluations == 0) a.energy_before = b.energy_before;
  a.moves += b.moves, a.evaluations += b.evaluations, a.rounds += b.rounds;
  a.local_checks += b.local_checks, a.search_checks += b.search_checks;
  a.refused_disconnect += b.refused_disconnect, a.refused_budget += b.refused_budget;
  a.energy_after = b.energy_after;
}

}  // namespace

Partition vsa_partition(const VsaSurface& s, const VsaOptions& options, VsaStats* stats) {
  VsaStats st;
  auto t = std::chrono::steady_clock::now();
  SeedingOptions so = options.seeding;
  so.clusters = std::max<size_t>(1, options.proxies);
  Partition p = seed_partition(s, so, &st.seeding);
  st.seeded = p.cluster_count();
  st.component_clusters = absorb_unassigned(s, p);
  st.seeding_ms = ms_since(t);
  t = std::chrono::steady_clock::now();

  const size_t K = std::min(so.clusters, s.face_count());
  const size_t cap =
      options.max_proxies ? options.max_proxies : std::max<size_t>(K, s.face_count() / 3);
  auto want_more = [&] {
    if (options.target_error > 0)
      return p.cluster_count() < cap && p.energy() > options.target_error * s.total_area;
    return options.fill && p.cluster_count() < K;
  };
  std::vector<uint32_t> touched;
  if (options.method == VsaMethod::greedy) {
    GreedyOptimizer g(s, p, options.greedy);
    add(st.greedy, g.run());
    while (want_more()) {
      const uint32_t k = worst_cluster(p);
      if (k == kNone || p.cluster_energy(k) <= 0) break;
      split_cluster(s, p, k, &touched);
      ++st.split_clusters;
      g.touch(touched);
      add(st.greedy, g.run());
    }
    // Teleports: b joins a (the cheapest merge), the worst cluster w is split and its new half
    // takes b's id; the optimiser then runs. Kept only if E dropped, else undone, and the next
    // worst cluster is tried; a few failures in a row end it.
    std::vector<uint32_t> merged, old_labels;
    std::vector<uint8_t> tried(p.cluster_count(), 0);
    size_t failures = 0;
    for (size_t tp = 0; tp < options.teleports && failures < 3; ++tp) {
      uint32_t w = kNone;
      double worst = 0;
      for (uint32_t k = 0; k < p.cluster_count(); ++k)
        if (!tried[k] && p.size[k] >= 2 && p.cluster_energy(k) > worst)
          worst = p.cluster_energy(k), w = k;
      if (w == kNone) break;
      double cost = 0;
      const auto [a, b] = g.cheapest_merge(w, &cost);
      if (a == kNone || !(cost < worst)) break;
      const double before = p.energy();
      const uint32_t w2 = split_cluster(s, p, w, &touched);
      merge_clusters(s, p, a, b, &merged);
      merge_clusters(s, p, b, w2);
      pop_empty_cluster(p);
      old_labels.assign(touched.size(), w);
      for (uint32_t f : merged) old_labels.push_back(b), touched.push_back(f);
      g.touch(touched);
      g.begin_journal();
      const GreedyStats gs = g.run();
      if (p.energy() < before * (1 - 1e-9)) {
        g.end_journal();
        add(st.greedy, gs);
        ++st.teleports;
        failures = 0;
        std::fill(tried.begin(), tried.end(), 0);
        continue;
      }
      g.rollback();
      for (size_t i = 0; i < touched.size(); ++i) p.label[touched[i]] = old_labels[i];
      p.recompute(s);
      g.touch(touched);
      add(st.greedy, g.run());
      tried[w] = 1;
      ++failures;
    }
  } else {
    for (;;) {
      while (want_more()) {
        const uint32_t k = worst_cluster(p);
        if (k == kNone || p.cluster_energy(k) <= 0) break;
        split_cluster(s, p, k, &touched);
        ++st.split_clusters;
      }
      const LloydStats ls = lloyd_optimize(s, p, options.lloyd);
      st.lloyd.iterations += ls.iterations;
      st.lloyd.energy.insert(st.lloyd.energy.end(), ls.energy.begin(), ls.energy.end());
      if (!(options.target_error > 0) || !want_more()) break;
    }
  }
  p.recompute(s);
  st.optimise_ms = ms_since(t);
  st.clusters = p.cluster_count();
  st.energy = p.energy();
  st.total_area = s.total_area;
  if (stats) *stats = st;
  return p;
}

VsaResult simplify_vsa(const Mesh& mesh, const VsaOptions& options, std::string_view name) {
  VsaResult r;
  auto t = std::chrono::steady_clock::now();
  const VsaSurface s = prepare_surface(mesh, name);
  const double prepare = ms_since(t);
  Partition p = vsa_partition(s, options, &r.stats);
  r.stats.prepare_ms = prepare;
  t = std::chrono::steady_clock::now();
  r.output = polygonize(s, p, options.meshing);
  carry_attributes(mesh, p.label, r.output);
  r.stats.meshing_ms = ms_since(t);
  r.stats.clusters = p.cluster_count();
  r.stats.energy = p.energy();
  r.labels = std::move(p.label);
  return r;
}

}  // namespace limn

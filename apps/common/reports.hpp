// The JSON reports of limn's jobs, shared by the CLI's --json and the Python module's result
// dicts, so both name and count the same things.
#pragma once

#include <nlohmann/json.hpp>

#include "limn/mesh/repair.hpp"
#include "limn/mesh/topology.hpp"
#include "limn/paint/material.hpp"
#include "limn/simplify/distance.hpp"
#include "limn/simplify/vsa.hpp"

namespace limn::reports {

/// `limn info`'s statistics of a mesh.
nlohmann::json stats_json(const MeshStats& s);

/// An octree texture's counts and sizes (`limn paint --stats`).
nlohmann::json texture_json(const OctreeTexture& t);
/// A material's: the colour texture's counts (texture_json), its height scale, and "rmh": the
/// RMH texture's counts and defaults (null without one).
nlohmann::json material_json(const MaterialTexture& m);

/// The counts of a repair (`limn repair`, `--repair`).
nlohmann::json repair_json(const RepairReport& r);

/// What VSA did, as `limn simplify --json` reports it: method and seeding, K asked and reached,
/// the energy (also per area and per squared bbox diagonal of `input`), counts in and out, and
/// the meshing's and the greedy optimiser's counters. Without the file names, the distance
/// report, the validity check and the timings, which the caller adds.
nlohmann::json simplify_json(const Mesh& input, const VsaOptions& options, const VsaResult& r);

/// The distance report of `limn simplify --distance`.
nlohmann::json distance_json(const SurfaceDistance& d);

/// VSA's phase timings in ms ("prepare", "seeding", "optimisation", "meshing").
nlohmann::json simplify_timings_json(const VsaStats& st);

}  // namespace limn::reports

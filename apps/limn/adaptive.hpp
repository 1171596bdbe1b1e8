// The adaptive limit surface as `limn subdivide --adaptive` and `limn render --adaptive` make
// it: a fixed depth, or a depth per vertex from a camera and a pixel tolerance (errors measured
// on a patch hierarchy, or estimated), and the patch table of that depth.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/patches.hpp"

namespace limn::cli {

struct AdaptiveOpts {
  int depth = -1, max_depth = 10, tess = 4;
  float tolerance = -1, tess_px = 0;
  std::string camera, resolution, errors = "auto";
  bool depth_colors = false, dynamic = false;  // dynamic: --tolerance was given
};

/// Registers --depth, --tolerance, --max-depth, --errors, --camera, --resolution, --tess,
/// --tess-px and --depth-colors on `cmd`, writing into `a` (which must outlive the command).
/// `render`: the help texts of `limn render` (screen-space tessellation by default, colours per
/// patch), else those of `limn subdivide`.
void add_adaptive_options(CLI::App& cmd, AdaptiveOpts& a, bool render);

/// "ex,ey,ez,tx,ty,tz,fovy_deg" -> camera (image size kept from `c`).
Camera parse_camera(const std::string& s, Camera c);
/// "WxH" -> w, h (1-32768 each).
void parse_resolution(const std::string& s, int& w, int& h);

/// Checks the options before any work; sets the image size (1280x720 unless --resolution).
void check_adaptive(const AdaptiveOpts& a, int& w, int& h);

struct AdaptiveSurface {
  PatchTable table;           ///< the patches drawn or tessellated
  PatchHierarchy hierarchy;   ///< measured errors: where the table's points come from
  bool measured = false;      ///< errors measured on the hierarchy (table is a selection)
  std::vector<float> points;  ///< the table's (or hierarchy's) points
  Camera cam;                 ///< the camera the depths were chosen for
  int width = 0, height = 0, depth = 3;
  PatchStats stats;  ///< patches by level
  VertexErrorModel model;
  std::vector<uint8_t> vdepth;  ///< per cage vertex (dynamic)
  std::vector<float> estimate;  ///< estimated screen error per cage vertex, pixels
};

/// Builds the surface of `cage` for the options (checked by check_adaptive); timings (ms) go
/// into `timings` under their phase names.
AdaptiveSurface build_adaptive(const Mesh& cage, const AdaptiveOpts& a, int width, int height,
                               Stopwatch& sw, nlohmann::json& timings);

}  // namespace limn::cli

// limn-view-check: the viewer tests' image checks (no Python or ImageMagick needed): a screenshot
// is not blank, and a colour (shaded: matched by direction in RGB, not exact value) is present in
// it or absent from it. Exit 0 when the checks pass, 1 when one fails, 2 for bad input.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>

#include "limn/mesh/mesh.hpp"
#include "limn/render/image.hpp"

namespace {

bool parse_rgb(const std::string& s, double rgb[3]) {
  std::stringstream in(s);
  std::string item;
  int k = 0;
  for (; std::getline(in, item, ','); ++k) {
    size_t used = 0;
    try {
      if (k > 2) return false;
      rgb[k] = std::stod(item, &used);
    } catch (const std::exception&) {
      return false;
    }
    if (used != item.size() || !(rgb[k] >= 0 && rgb[k] <= 1)) return false;
  }
  return k == 3 && rgb[0] + rgb[1] + rgb[2] > 0;
}

// Lit surfaces scale a colour (diffuse) and add a little white (specular): a pixel shows `c`
// when it points the same way in RGB and is not too dark.
size_t count_like(const std::vector<uint8_t>& rgba, const double c[3], double min_cos) {
  const double cn = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  size_t n = 0;
  for (size_t i = 0; i + 3 < rgba.size(); i += 4) {
    const double p[3] = {rgba[i] / 255.0, rgba[i + 1] / 255.0, rgba[i + 2] / 255.0};
    const double pn = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    if (pn < 0.25 * cn) continue;
    if ((p[0] * c[0] + p[1] * c[1] + p[2] * c[2]) / (pn * cn) >= min_cos) ++n;
  }
  return n;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"limn-view-check: checks a viewer screenshot", "limn-view-check"};
  std::string image, present, absent;
  size_t min_pixels = 100, max_pixels = 10, min_colors = 16;
  double min_cos = 0.97;
  app.add_option("IMAGE", image, "PNG screenshot")->required();
  app.add_option("--present", present, "r,g,b (0-1) that must cover at least --min-pixels");
  app.add_option("--absent", absent, "r,g,b (0-1) that may cover at most --max-pixels");
  app.add_option("--min-pixels", min_pixels, "Default 100");
  app.add_option("--max-pixels", max_pixels, "Default 10");
  app.add_option("--min-colors", min_colors, "Distinct colours a non-blank image has (default 16)");
  app.add_option("--min-cos", min_cos, "How close in direction a pixel must be (default 0.97)");
  try {
    app.parse(argc, argv);
    int w = 0, h = 0;
    const std::vector<uint8_t> rgba = limn::read_png(image, w, h);
    std::map<uint32_t, size_t> colors;
    for (size_t i = 0; i + 3 < rgba.size(); i += 4)
      ++colors[uint32_t(rgba[i]) | uint32_t(rgba[i + 1]) << 8 | uint32_t(rgba[i + 2]) << 16];
    size_t most = 0;
    for (const auto& [c, n] : colors) most = std::max(most, n);
    const size_t pixels = size_t(w) * size_t(h);
    const double other = pixels ? 1.0 - double(most) / double(pixels) : 0.0;
    std::printf("%s: %dx%d, %zu colours, %.1f%% not the background\n", image.c_str(), w, h,
                colors.size(), 100 * other);
    bool ok = true;
    if (colors.size() < min_colors || other < 0.01) {
      std::printf("  FAIL: blank (fewer than %zu colours or under 1%% of pixels drawn)\n",
                  min_colors);
      ok = false;
    }
    double c[3];
    if (!present.empty()) {
      if (!parse_rgb(present, c)) throw limn::InputError("--present " + present + ": r,g,b in 0-1");
      const size_t n = count_like(rgba, c, min_cos);
      std::printf("  %zu pixels like %s (need >= %zu)\n", n, present.c_str(), min_pixels);
      ok = ok && n >= min_pixels;
    }
    if (!absent.empty()) {
      if (!parse_rgb(absent, c)) throw limn::InputError("--absent " + absent + ": r,g,b in 0-1");
      const size_t n = count_like(rgba, c, min_cos);
      std::printf("  %zu pixels like %s (allow <= %zu)\n", n, absent.c_str(), max_pixels);
      ok = ok && n <= max_pixels;
    }
    std::printf("  %s\n", ok ? "ok" : "FAILED");
    return ok ? 0 : 1;
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "limn-view-check: error: %s\n", e.what());
    return 2;
  }
}

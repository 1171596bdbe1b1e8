// Stroke scripts: a strict JSON reader (every field checked, unknown keys refused so a typo never
// passes silently) and the runner.
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "limn/mesh/file.hpp"
#include "limn/paint/strokes.hpp"

namespace limn {

namespace {

using nlohmann::json;

constexpr size_t kMaxCommands = 1000000, kMaxPoints = 10000000;
constexpr double kMaxDabs = 1e7;

class Reader {
 public:
  Reader(std::string_view name, int depth) : name_(name), depth_(depth) {}

  [[noreturn]] void fail(const std::string& where, const std::string& why) const {
    throw InputError(name_ + ": " + where + ": " + why);
  }

  double number(const json& j, const std::string& where) const {
    if (!j.is_number()) fail(where, "expected a number");
    const double v = j.get<double>();
    if (!std::isfinite(v)) fail(where, "not a finite number");
    return v;
  }
  double number_in(const json& j, const std::string& where, double lo, double hi) const {
    const double v = number(j, where);
    if (v < lo || v > hi)
      fail(where, "must be in [" + fmt(lo) + ", " + fmt(hi) + "], got " + fmt(v));
    return v;
  }
  static std::string fmt(double v) {
    std::string s = std::to_string(v);
    while (s.size() > 1 && s.back() == '0') s.pop_back();
    if (!s.empty() && s.back() == '.') s.pop_back();
    return s;
  }
  int integer_in(const json& j, const std::string& where, int lo, int hi) const {
    if (!j.is_number_integer() &&
        !(j.is_number() && std::floor(number(j, where)) == number(j, where)))
      fail(where, "expected an integer");
    const double v = number(j, where);
    if (v < lo || v > hi)
      fail(where, "must be " + std::to_string(lo) + "-" + std::to_string(hi) + ", got " + fmt(v));
    return int(v);
  }
  std::string text(const json& j, const std::string& where) const {
    if (!j.is_string()) fail(where, "expected a string");
    return j.get<std::string>();
  }
  void vec(const json& j, const std::string& where, size_t n, float* out) const {
    if (!j.is_array() || j.size() != n)
      fail(where, "expected an array of " + std::to_string(n) + " numbers");
    for (size_t k = 0; k < n; ++k) {
      const double v = number(j[k], where + "[" + std::to_string(k) + "]");
      if (std::fabs(v) > 1e30) fail(where, "a coordinate is too large");
      out[k] = float(v);
    }
  }
  void keys(const json& j, const std::string& where, const std::set<std::string>& allowed) const {
    for (auto it = j.begin(); it != j.end(); ++it)
      if (!allowed.count(it.key())) fail(where, "unknown key '" + it.key() + "'");
  }

  PaintCamera camera(const json& j) const {
    const std::string w = "camera";
    if (!j.is_object()) fail(w, "expected an object");
    keys(j, w, {"eye", "target", "up", "fovy", "width", "height"});
    for (const char* k : {"eye", "target", "fovy", "width", "height"})
      if (!j.contains(k)) fail(w, std::string("missing '") + k + "'");
    PaintCamera c;
    vec(j["eye"], w + ".eye", 3, c.eye);
    vec(j["target"], w + ".target", 3, c.target);
    if (j.contains("up")) vec(j["up"], w + ".up", 3, c.up);
    c.fovy_deg = float(number_in(j["fovy"], w + ".fovy", 1e-3, 179.0));
    c.width = integer_in(j["width"], w + ".width", 1, 32768);
    c.height = integer_in(j["height"], w + ".height", 1, 32768);
    if (!c.valid()) fail(w, "degenerate (the eye is at the target or up lies along the view)");
    return c;
  }

  void color(const json& j, const std::string& where, float out[4]) const {
    if (!j.is_array() || (j.size() != 3 && j.size() != 4))
      fail(where, "expected [r, g, b] or [r, g, b, a] with numbers in [0, 1]");
    out[3] = 1;
    for (size_t k = 0; k < j.size(); ++k)
      out[k] = float(number_in(j[k], where + "[" + std::to_string(k) + "]", 0, 1));
  }

  BlendMode blend(const json& j, const std::string& where) const {
    const std::string s = text(j, where);
    if (s == "mix") return BlendMode::mix;
    if (s == "add") return BlendMode::add;
    if (s == "multiply") return BlendMode::multiply;
    if (s == "erase") return BlendMode::erase;
    fail(where, "'" + s + "' is not a blend mode (mix, add, multiply, erase)");
  }

  // A material channel: a value in [0, 1] (mixed in at opacity 1), or {"value", "blend",
  // "opacity"}.
  ChannelPaint channel_paint(const json& j, const std::string& where) const {
    ChannelPaint p;
    p.on = true;
    if (j.is_number()) {
      p.value = float(number_in(j, where, 0, 1));
      return p;
    }
    if (!j.is_object())
      fail(where, "expected a number in [0, 1] or {\"value\", \"blend\", \"opacity\"}");
    keys(j, where, {"value", "blend", "opacity"});
    if (j.contains("value")) p.value = float(number_in(j["value"], where + ".value", 0, 1));
    if (j.contains("blend")) p.blend = blend(j["blend"], where + ".blend");
    if (!j.contains("value") && p.blend != BlendMode::erase) fail(where, "missing 'value'");
    if (j.contains("opacity")) p.opacity = float(number_in(j["opacity"], where + ".opacity", 0, 1));
    return p;
  }

  // The brush fields a stroke or fill may carry. An entry that paints a material channel paints
  // colour only when it gives one.
  void brush_fields(const json& e, const std::string& w, StrokeCommand& c) const {
    for (int k = 0; k < kMaterialChannels; ++k) {
      const char* name = channel_name(MaterialChannel(k));
      if (e.contains(name)) c.brush.material[k] = channel_paint(e[name], w + "." + name);
    }
    c.brush.paint_color = !c.brush.paints_material() || e.contains("color");
    if (e.contains("color")) color(e["color"], w + ".color", c.brush.color);
    if (e.contains("opacity"))
      c.brush.opacity = float(number_in(e["opacity"], w + ".opacity", 0, 1));
    if (e.contains("blend")) c.brush.blend = blend(e["blend"], w + ".blend");
    if (e.contains("depth")) {
      c.brush.depth = integer_in(e["depth"], w + ".depth", 1, octree::kMaxDepth);
      c.depth_given = true;
    }
  }

  std::vector<double> points(const json& j, const std::string& where, size_t dim) {
    if (!j.is_array() || j.empty()) fail(where, "expected a non-empty array of points");
    if (j.size() > kMaxPoints || total_points_ + j.size() > kMaxPoints)
      fail(where, "more than 10 million points in the file");
    total_points_ += j.size();
    std::vector<double> out;
    out.reserve(dim * j.size());
    for (size_t i = 0; i < j.size(); ++i) {
      const std::string wi = where + "[" + std::to_string(i) + "]";
      if (!j[i].is_array() || j[i].size() != dim)
        fail(wi, "expected [" + std::string(dim == 3 ? "x, y, z" : "x, y") + "]");
      for (size_t k = 0; k < dim; ++k) {
        const double v = number(j[i][k], wi);
        if (std::fabs(v) > 1e30) fail(wi, "a coordinate is too large");
        out.push_back(v);
      }
    }
    return out;
  }

  StrokeCommand command(const json& e, size_t index, bool has_camera) {
    const std::string w = "strokes[" + std::to_string(index) + "]";
    if (!e.is_object()) fail(w, "expected an object");
    StrokeCommand c;
    c.brush.depth = depth_;
    const std::string type = e.contains("type") ? text(e["type"], w + ".type") : "stroke";
    if (type == "stroke") {
      keys(e, w,
           {"type", "points", "radius", "color", "opacity", "hardness", "space", "spacing", "blend",
            "depth", "falloff_angle", "roughness", "metallic", "height"});
      if (!e.contains("points")) fail(w, "missing 'points'");
      if (!e.contains("radius")) fail(w, "missing 'radius'");
      const std::string space = e.contains("space") ? text(e["space"], w + ".space") : "world";
      if (space != "world" && space != "screen")
        fail(w + ".space", "'" + space + "' is not 'world' or 'screen'");
      c.screen = space == "screen";
      if (c.screen && !has_camera) fail(w, "screen-space points need a 'camera' in the file");
      c.brush.radius = float(number(e["radius"], w + ".radius"));
      if (!(c.brush.radius > 0) || c.brush.radius > 1e30f)
        fail(w + ".radius", "must be a positive number");
      brush_fields(e, w, c);
      if (e.contains("hardness"))
        c.brush.hardness = float(number_in(e["hardness"], w + ".hardness", 0, 1));
      if (e.contains("spacing"))
        c.brush.spacing = float(number_in(e["spacing"], w + ".spacing", 1e-3, 10));
      if (e.contains("falloff_angle"))
        c.brush.falloff_angle_deg =
            float(number_in(e["falloff_angle"], w + ".falloff_angle", 0, 90));
      const std::vector<double> p = points(e["points"], w + ".points", c.screen ? 2 : 3);
      if (c.screen) {
        c.pixels = p;
      } else {
        c.points.assign(p.begin(), p.end());
        for (size_t i = 0; i < p.size(); ++i) c.points[i] = float(p[i]);
      }
      // Dab count along the polyline, before any work.
      const size_t dim = c.screen ? 2 : 3, n = p.size() / dim;
      double len = 0;
      for (size_t i = 1; i < n; ++i) {
        double l2 = 0;
        for (size_t k = 0; k < dim; ++k)
          l2 += (p[i * dim + k] - p[(i - 1) * dim + k]) * (p[i * dim + k] - p[(i - 1) * dim + k]);
        len += std::sqrt(l2);
      }
      dabs_ += len / (double(c.brush.spacing) * c.brush.radius) + double(n);
      if (dabs_ > kMaxDabs)
        fail(w,
             "the file asks for more than 10 million dabs (radius * spacing too small for the "
             "strokes' length)");
      check_brush(c.brush, (name_ + ": " + w).c_str());
    } else if (type == "fill") {
      keys(e, w, {"type", "color", "opacity", "blend", "depth", "roughness", "metallic", "height"});
      if (!e.contains("color") && (!e.contains("blend") || e["blend"] != "erase") &&
          !e.contains("roughness") && !e.contains("metallic") && !e.contains("height"))
        fail(w, "missing 'color' (or a material channel)");
      c.type = StrokeCommand::Type::fill;
      brush_fields(e, w, c);
      c.fill_refines = c.depth_given;
      check_brush(c.brush, (name_ + ": " + w).c_str());
    } else if (type == "pick") {
      keys(e, w, {"type", "point", "pixel"});
      c.type = StrokeCommand::Type::pick;
      if (e.contains("point") == e.contains("pixel"))
        fail(w, "give exactly one of 'point' and 'pixel'");
      if (e.contains("point")) {
        c.points.resize(3);
        vec(e["point"], w + ".point", 3, c.points.data());
      } else {
        if (!has_camera) fail(w, "'pixel' needs a 'camera' in the file");
        float px[2];
        vec(e["pixel"], w + ".pixel", 2, px);
        c.screen = true;
        c.pixels = {px[0], px[1]};
      }
    } else if (type == "undo" || type == "redo") {
      keys(e, w, {"type"});
      c.type = type == "undo" ? StrokeCommand::Type::undo : StrokeCommand::Type::redo;
    } else {
      fail(w + ".type", "'" + type + "' is not one of stroke, fill, pick, undo, redo");
    }
    return c;
  }

  StrokeScript script(std::string_view text_in) {
    json j;
    try {
      j = json::parse(text_in.begin(), text_in.end());
    } catch (const json::parse_error& e) {
      std::string m = e.what();
      const size_t at = m.find("] ");
      if (at != std::string::npos) m = m.substr(at + 2);
      throw InputError(name_ + ": not valid JSON: " + m);
    }
    if (!j.is_object()) fail("top level", "expected an object with a 'strokes' array");
    keys(j, "top level", {"strokes", "camera", "version"});
    if (j.contains("version") && integer_in(j["version"], "version", 1, 1) != 1)
      fail("version", "unsupported");
    StrokeScript s;
    if (j.contains("camera")) s.camera = camera(j["camera"]);
    if (!j.contains("strokes") || !j["strokes"].is_array())
      fail("top level", "expected a 'strokes' array");
    const json& a = j["strokes"];
    if (a.size() > kMaxCommands) fail("strokes", "more than a million entries");
    s.commands.reserve(a.size());
    for (size_t i = 0; i < a.size(); ++i)
      s.commands.push_back(command(a[i], i, s.camera.has_value()));
    return s;
  }

 private:
  std::string name_;
  int depth_;
  size_t total_points_ = 0;
  double dabs_ = 0;
};

}  // namespace

StrokeScript parse_strokes(std::string_view json_text, std::string_view name, int depth) {
  if (depth < 1 || depth > octree::kMaxDepth)
    throw InputError("--depth " + std::to_string(depth) + ": must be 1-" +
                     std::to_string(octree::kMaxDepth));
  Reader r(name, depth);
  return r.script(json_text);
}

StrokeScript read_strokes(const std::filesystem::path& path, int depth) {
  const std::string data = read_file(path);
  return parse_strokes(data, path.string(), depth);
}

ScriptResult run_strokes(MaterialTexture& m, const PaintSurface& s, const StrokeScript& script,
                         PaintHistory& history, MaterialDefaults defaults) {
  ScriptResult r;
  const PaintCamera* cam = script.camera ? &*script.camera : nullptr;
  for (size_t i = 0; i < script.commands.size(); ++i) {
    const StrokeCommand& c = script.commands[i];
    switch (c.type) {
      case StrokeCommand::Type::stroke: {
        MaterialPainter p(m, s, &history, defaults);
        p.begin(c.brush, cam);
        if (c.screen)
          p.stroke_screen(c.pixels);
        else
          p.stroke_world(c.points);
        r.strokes.push_back(p.end());
        break;
      }
      case StrokeCommand::Type::fill: {
        if (c.brush.paints_material()) m.ensure_rmh(s, defaults);
        history.begin(m);
        StrokeStats st;
        try {
          st.samples_changed = fill(m, s, c.brush, c.fill_refines ? c.brush.depth : 0, defaults);
        } catch (...) {
          history.end(m);
          throw;
        }
        history.end(m);
        r.strokes.push_back(st);
        break;
      }
      case StrokeCommand::Type::pick: {
        PickResult pr;
        pr.command = i;
        MaterialPick mp;
        if (c.screen) {
          if (!cam) throw InputError("pick: 'pixel' needs a camera");
          mp = pick_screen(m, s, *cam, c.pixels[0], c.pixels[1]);
        } else {
          mp = pick_world(m, s, c.points.data(), INFINITY);
        }
        pr.found = mp.found;
        std::copy_n(mp.rgba, 4, pr.rgba);
        std::copy_n(mp.channels, 3, pr.channels);
        r.picks.push_back(pr);
        break;
      }
      case StrokeCommand::Type::undo:
        r.undos += history.undo(m);
        break;
      case StrokeCommand::Type::redo:
        r.redos += history.redo(m);
        break;
    }
  }
  return r;
}

}  // namespace limn

#include "script.hpp"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "limn/io/mesh_io.hpp"

namespace limn::view {

namespace {

using nlohmann::json;

[[noreturn]] void fail(const Action& a, std::string_view what) {
  throw InputError(fmt::format("{}: {}", a.where, what));
}

double number(const Action& a, const json& v, const char* key, double lo, double hi) {
  if (!v.is_number()) fail(a, fmt::format("'{}' must be a number", key));
  const double x = v.get<double>();
  if (!std::isfinite(x) || x < lo || x > hi)
    fail(a, fmt::format("'{}' {} is outside [{}, {}]", key, x, lo, hi));
  return x;
}

int integer(const Action& a, const json& v, const char* key, int lo, int hi) {
  if (!v.is_number_integer()) fail(a, fmt::format("'{}' must be an integer", key));
  const auto x = v.get<long long>();
  if (x < lo || x > hi) fail(a, fmt::format("'{}' {} is outside [{}, {}]", key, x, lo, hi));
  return int(x);
}

bool boolean(const Action& a, const json& v, const char* key) {
  if (!v.is_boolean()) fail(a, fmt::format("'{}' must be true or false", key));
  return v.get<bool>();
}

std::string text(const Action& a, const json& v, const char* key) {
  if (!v.is_string() || v.get<std::string>().empty())
    fail(a, fmt::format("'{}' must be a non-empty string", key));
  return v.get<std::string>();
}

void pair(const Action& a, const json& v, const char* key, double lo, double hi, double& x,
          double& y) {
  if (!v.is_array() || v.size() != 2) fail(a, fmt::format("'{}' must be [x, y]", key));
  x = number(a, v[0], key, lo, hi);
  y = number(a, v[1], key, lo, hi);
}

void parse_stroke(Action& a, const json& v) {
  if (!v.is_object()) fail(a, "'stroke' must be an object");
  Brush& b = a.brush;
  b.radius = 12.0f;
  bool has_points = false;
  for (const auto& [key, value] : v.items()) {
    if (key == "points") {
      if (!value.is_array() || value.empty())
        fail(a, "'points' must be a non-empty array of [x, y] pixels");
      for (const json& p : value) {
        double x = 0, y = 0;
        pair(a, p, "points", -1e6, 1e6, x, y);
        a.points.push_back(x), a.points.push_back(y);
      }
      has_points = true;
    } else if (key == "radius") {
      b.radius = float(number(a, value, "radius", 0.01, 10000));
    } else if (key == "color") {
      if (!value.is_array() || value.size() < 3 || value.size() > 4)
        fail(a, "'color' must be [r, g, b] or [r, g, b, a] in [0, 1]");
      b.color[3] = 1;
      for (size_t k = 0; k < value.size(); ++k)
        b.color[k] = float(number(a, value[k], "color", 0, 1));
    } else if (key == "opacity") {
      b.opacity = float(number(a, value, "opacity", 0, 1));
    } else if (key == "hardness") {
      b.hardness = float(number(a, value, "hardness", 0, 1));
    } else if (key == "spacing") {
      b.spacing = float(number(a, value, "spacing", 1e-3, 10));
    } else if (key == "depth") {
      b.depth = integer(a, value, "depth", 1, octree::kMaxDepth);
    } else if (key == "blend") {
      b.blend = parse_blend(text(a, value, "blend"), a.where);
    } else if (key == "live") {
      if (!value.is_boolean()) fail(a, "'live' must be true or false");
      a.live = value.get<bool>();
    } else if (key == "paint_color") {
      b.paint_color = boolean(a, value, "paint_color");
    } else if (key == "roughness" || key == "metallic" || key == "height") {
      // A material channel: its value (mixed in at opacity 1), or {"value", "blend", "opacity"}.
      ChannelPaint& c = b.material[key == "roughness" ? 0 : key == "metallic" ? 1 : 2];
      c.on = true;
      if (value.is_object()) {
        for (const auto& [k, x] : value.items()) {
          if (k == "value")
            c.value = float(number(a, x, (key + ".value").c_str(), 0, 1));
          else if (k == "blend")
            c.blend = parse_blend(text(a, x, (key + ".blend").c_str()), a.where);
          else if (k == "opacity")
            c.opacity = float(number(a, x, (key + ".opacity").c_str(), 0, 1));
          else
            fail(a, fmt::format("unknown {} key '{}'", key, k));
        }
      } else {
        c.value = float(number(a, value, key.c_str(), 0, 1));
      }
    } else {
      fail(a, fmt::format("unknown stroke key '{}'", key));
    }
  }
  if (!has_points) fail(a, "a stroke needs 'points'");
  check_brush(b, a.where.c_str());
}

void parse_surface(Action& a, const json& v) {
  if (!v.is_object() || v.empty()) fail(a, "'surface' must be an object of settings");
  SurfaceChange& s = a.surface;
  for (const auto& [key, value] : v.items()) {
    if (key == "dynamic") {
      s.dynamic = boolean(a, value, "dynamic");
    } else if (key == "depth") {
      s.depth = integer(a, value, "depth", 0, 10);
    } else if (key == "max_depth") {
      s.max_depth = integer(a, value, "max_depth", 1, 10);
    } else if (key == "tolerance") {
      s.tolerance_px = float(number(a, value, "tolerance", 0.05, 100));
    } else if (key == "tess_px") {
      s.tess_px = float(number(a, value, "tess_px", 1, 256));
    } else {
      fail(a, fmt::format("unknown surface key '{}'", key));
    }
  }
}

Action parse_action(const json& v, std::string where) {
  Action a;
  a.where = std::move(where);
  if (!v.is_object() || v.size() != 1) fail(a, "an action is an object with exactly one key");
  const std::string& key = v.begin().key();
  const json& value = v.begin().value();
  using K = Action::Kind;
  if (key == "orbit") {
    a.kind = K::orbit;
    pair(a, value, "orbit", -3600, 3600, a.x, a.y);
  } else if (key == "pan") {
    a.kind = K::pan;
    pair(a, value, "pan", -1e5, 1e5, a.x, a.y);
  } else if (key == "zoom") {
    a.kind = K::zoom;
    a.x = number(a, value, "zoom", 1e-3, 1e3);
    if (!(a.x > 0)) fail(a, "'zoom' must be positive");
  } else if (key == "frame") {
    a.kind = K::frame;
    boolean(a, value, "frame");
  } else if (key == "mode") {
    a.kind = K::mode;
    a.mode = parse_mode(text(a, value, "mode"), a.where);
  } else if (key == "display") {
    a.kind = K::display;
    a.display = parse_display(text(a, value, "display"), a.where);
  } else if (key == "surface") {
    a.kind = K::surface;
    parse_surface(a, value);
  } else if (key == "wireframe" || key == "depth_colors" || key == "filtered" || key == "ui") {
    a.kind = key == "wireframe"  ? K::wireframe
             : key == "ui"       ? K::ui
             : key == "filtered" ? K::filtered
                                 : K::depth_colors;
    a.flag = boolean(a, value, key.c_str());
  } else if (key == "stroke") {
    a.kind = K::stroke;
    parse_stroke(a, value);
  } else if (key == "undo" || key == "redo") {
    a.kind = key == "undo" ? K::undo : K::redo;
    if (!boolean(a, value, key.c_str())) fail(a, fmt::format("'{}' must be true", key));
  } else if (key == "save_texture" || key == "load_texture" || key == "export" ||
             key == "screenshot") {
    a.kind = key == "save_texture"   ? K::save_texture
             : key == "load_texture" ? K::load_texture
             : key == "export"       ? K::export_mesh
                                     : K::screenshot;
    a.path = text(a, value, key.c_str());
    if (a.kind == K::screenshot && a.path.extension() != ".png")
      fail(a, "a screenshot must be a .png file");
    if ((a.kind == K::save_texture || a.kind == K::load_texture) && a.path.extension() != ".lot")
      fail(a, "a texture file must end in .lot");
  } else if (key == "simplify") {
    a.kind = K::simplify;
    if (!value.is_object() || value.size() != 1 || !value.contains("proxies"))
      fail(a, "'simplify' must be {\"proxies\": K}");
    a.count = size_t(integer(a, value["proxies"], "proxies", 1, 1 << 24));
  } else if (key == "frames") {
    a.kind = K::frames;
    a.count = size_t(integer(a, value, "frames", 1, 100000));
  } else {
    fail(a, fmt::format("unknown action '{}'", key));
  }
  return a;
}

}  // namespace

const char* mode_name(Mode m) {
  switch (m) {
    case Mode::view:
      return "view";
    case Mode::paint:
      return "paint";
    case Mode::simplify:
      return "simplify";
  }
  return "?";
}

const char* display_name(Display d) {
  switch (d) {
    case Display::cage:
      return "cage";
    case Display::surface:
      return "surface";
    case Display::painted:
      return "painted";
    case Display::clusters:
      return "clusters";
    case Display::simplified:
      return "simplified";
  }
  return "?";
}

Mode parse_mode(std::string_view s, std::string_view what) {
  for (Mode m : {Mode::view, Mode::paint, Mode::simplify})
    if (s == mode_name(m)) return m;
  throw InputError(fmt::format("{}: mode '{}': expected view, paint or simplify", what, s));
}

Display parse_display(std::string_view s, std::string_view what) {
  for (Display d :
       {Display::cage, Display::surface, Display::painted, Display::clusters, Display::simplified})
    if (s == display_name(d)) return d;
  throw InputError(fmt::format(
      "{}: display '{}': expected cage, surface, painted, clusters or simplified", what, s));
}

BlendMode parse_blend(std::string_view s, std::string_view what) {
  if (s == "mix") return BlendMode::mix;
  if (s == "add") return BlendMode::add;
  if (s == "multiply") return BlendMode::multiply;
  if (s == "erase") return BlendMode::erase;
  throw InputError(fmt::format("{}: blend '{}': expected mix, add, multiply or erase", what, s));
}

std::vector<Action> parse_script(std::string_view text, std::string_view name) {
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::parse_error& e) {
    throw InputError(fmt::format("{}: not valid JSON (byte {})", name, e.byte));
  }
  const json* list = &doc;
  if (doc.is_object()) {
    if (doc.size() != 1 || !doc.contains("actions"))
      throw InputError(
          fmt::format("{}: expected an array of actions or {{\"actions\": [...]}}", name));
    list = &doc["actions"];
  }
  if (!list->is_array()) throw InputError(fmt::format("{}: expected an array of actions", name));
  std::vector<Action> out;
  for (size_t i = 0; i < list->size(); ++i)
    out.push_back(parse_action((*list)[i], fmt::format("{}: action {}", name, i + 1)));
  return out;
}

std::vector<Action> read_script(const std::filesystem::path& path) {
  return parse_script(read_file(path), path.string());
}

}  // namespace limn::view

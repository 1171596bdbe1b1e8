#include "viewer.hpp"

#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <fmt/format.h>
#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "limn/render/gl_context.hpp"
#include "limn/render/image.hpp"
#include "orbit.hpp"

namespace limn::view {

namespace {

std::string g_glfw_error;

void on_glfw_error(int code, const char* what) {
  g_glfw_error = fmt::format("GLFW error {}: {}", code, what ? what : "?");
}

class Viewer {
 public:
  Viewer(Scene& scene, const ViewerOptions& o);
  ~Viewer();
  Viewer(const Viewer&) = delete;
  Viewer& operator=(const Viewer&) = delete;
  void run();

 private:
  void frame();
  bool script_step();  // false once the scripted run is over
  void apply(const Action& a);
  void panel();
  void mouse();
  void keys();
  void set_mode(Mode m);
  void screenshot(const std::filesystem::path& path);
  void report(const std::exception& e);
  // The 3D view's part of the window: right of the panel while it shows (so the panel hides
  // none of the model), the whole window without it. Re-frames a framed view whose area changed.
  void update_view_area();
  void frame_view();  // frames the cage in the view area
  int view_w() const { return std::max(fb_w_ - view_x_, 1); }
  // Runs f; interactively an error becomes the status line (the session goes on), in a script
  // it ends the run.
  template <class F>
  void guard(F f) {
    if (o_.scripted) return f();
    try {
      f();
    } catch (const std::exception& e) {
      report(e);
      if (scene_.stroking()) scene_.end_stroke();
    }
  }
  static void on_scroll(GLFWwindow* w, double dx, double dy);

  Scene& scene_;
  ViewerOptions o_;
  GLFWwindow* window_ = nullptr;
  bool imgui_ = false;
  OrbitCamera orbit_;
  int fb_w_ = 1, fb_h_ = 1;
  double px_scale_ = 1;     // framebuffer pixels per window coordinate
  int view_x_ = 0;          // framebuffer pixels left of the 3D view (the panel's)
  double panel_right_ = 0;  // the panel's right edge, framebuffer pixels (last drawn)
  bool framed_ = true;      // the view is as frame_view left it (no orbit, pan or zoom since)
  int framed_w_ = 0, framed_h_ = 0;

  Mode mode_ = Mode::view;
  Display display_ = Display::surface;
  SurfaceSettings surface_;
  int max_depth_edit_ = 8, depth_edit_ = 3;  // applied on release (both rebuild tables)
  DrawOptions draw_;
  bool ui_ = true;
  float background_[4] = {0.16f, 0.17f, 0.19f, 1};

  Brush brush_;
  int blend_ = 0;
  std::string texture_path_ = "painting.lot", export_path_ = "simplified.obj";
  int proxies_ = 50;
  StrokeStats last_stroke_;

  // Mouse drags.
  double last_x_ = 0, last_y_ = 0;
  int drag_button_ = -1;
  double scroll_ = 0;

  // Stats.
  FrameStats stats_;
  double select_ms_ = 0;  // of the last view change that changed the depths
  double frame_ms_ = 0, smooth_ms_ = 0;
  std::chrono::steady_clock::time_point last_frame_ = std::chrono::steady_clock::now();
  std::string status_;
  bool status_error_ = false;
  std::string renderer_;

  // Scripted mode.
  size_t next_action_ = 0, wait_frames_ = 0, frames_left_ = 0;
  const Action* stroke_ = nullptr;  // the scripted stroke under way (live: one point a frame)
  size_t stroke_next_ = 0, strokes_ = 0;
  std::chrono::steady_clock::time_point stroke_t0_;
  void end_scripted_stroke();
  bool pending_shot_ = false;
  std::filesystem::path shot_path_;
};

Viewer::Viewer(Scene& scene, const ViewerOptions& o) : scene_(scene), o_(o), ui_(o.ui) {
  glfwSetErrorCallback(on_glfw_error);
  if (!glfwInit())
    throw std::runtime_error(fmt::format("cannot open a window (no display? {})", g_glfw_error));
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_SAMPLES, std::clamp(o.samples, 0, 16));
  const std::string title = fmt::format("limn-view - {}", scene.name());
  window_ = glfwCreateWindow(o.width, o.height, title.c_str(), nullptr, nullptr);
  if (!window_) {
    glfwTerminate();
    throw std::runtime_error(
        fmt::format("cannot create an OpenGL 4.5 core window ({})", g_glfw_error));
  }
  glfwMakeContextCurrent(window_);
  // Scripts run as fast as the driver draws; people get frames paced to the display.
  glfwSwapInterval(o.scripted ? 0 : 1);
  glfwSetWindowUserPointer(window_, this);
  // Installed before ImGui's, which chains to it.
  glfwSetScrollCallback(window_, on_scroll);
  renderer_ = reinterpret_cast<const char*>(glGetString(GL_RENDERER));

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini left in the working directory
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(window_, true);
  ImGui_ImplOpenGL3_Init("#version 450 core");
  imgui_ = true;
  // GLFW unloads the GL driver at exit; keep it so LeakSanitizer can name what it keeps.
  keep_gl_libraries_loaded();

  glfwGetFramebufferSize(window_, &fb_w_, &fb_h_);
  frame_view();  // in the whole window until the panel has a size
  display_ = scene.is_cage() ? Display::surface : Display::cage;
  max_depth_edit_ = surface_.max_depth, depth_edit_ = surface_.depth;
  brush_.radius = 16.0f;
  brush_.color[0] = 0.9f, brush_.color[1] = 0.35f, brush_.color[2] = 0.1f, brush_.color[3] = 1;
  brush_.hardness = 0.6f;
  frames_left_ = o.frames;
  // Painting's one-time work runs while the user looks at the model, not in the first stroke.
  scene_.prepare_paint_in_background();
}

Viewer::~Viewer() {
  if (window_) scene_.release_gl();
  if (imgui_) {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  if (window_) glfwDestroyWindow(window_);
  glfwTerminate();
}

void Viewer::on_scroll(GLFWwindow* w, double, double dy) {
  static_cast<Viewer*>(glfwGetWindowUserPointer(w))->scroll_ += dy;
}

void Viewer::report(const std::exception& e) {
  status_ = e.what(), status_error_ = true;
  std::fprintf(stderr, "limn-view: %s\n", e.what());
}

void Viewer::set_mode(Mode m) {
  if (mode_ == Mode::paint && scene_.stroking()) last_stroke_ = scene_.end_stroke();
  mode_ = m;
  // Each mode shows what it works on; the display can still be changed by hand.
  if (m == Mode::paint) display_ = Display::painted;
  if (m == Mode::simplify) display_ = scene_.simplified() ? Display::clusters : Display::painted;
  if (m == Mode::view) display_ = scene_.is_cage() ? Display::surface : Display::cage;
}

void Viewer::apply(const Action& a) {
  using K = Action::Kind;
  switch (a.kind) {
    case K::orbit:
      orbit_.orbit(a.x, a.y), framed_ = false;
      break;
    case K::pan:
      orbit_.pan(a.x, a.y), framed_ = false;
      break;
    case K::zoom:
      orbit_.zoom(a.x), framed_ = false;
      break;
    case K::frame:
      frame_view();
      break;
    case K::mode:
      set_mode(a.mode);
      break;
    case K::display:
      display_ = a.display;
      break;
    case K::surface: {
      const SurfaceChange& c = a.surface;
      if (c.dynamic) surface_.dynamic = *c.dynamic;
      if (c.depth) surface_.depth = depth_edit_ = *c.depth;
      if (c.max_depth) surface_.max_depth = max_depth_edit_ = *c.max_depth;
      if (c.tolerance_px) surface_.tolerance_px = *c.tolerance_px;
      if (c.tess_px) surface_.tess_px = *c.tess_px;
      display_ = Display::surface;
      break;
    }
    case K::wireframe:
      draw_.outline = a.flag;
      break;
    case K::depth_colors:
      draw_.depth_colors = a.flag;
      break;
    case K::filtered:
      draw_.texture_nearest = !a.flag;
      break;
    case K::ui:
      ui_ = a.flag;
      break;
    case K::stroke: {
      // Script points are window pixels, as the mouse's are.
      // A live stroke is fed a point a frame by script_step; the others go at once.
      scene_.begin_stroke(a.brush, orbit_.camera(), true);
      stroke_ = &a, stroke_next_ = 0;
      stroke_t0_ = std::chrono::steady_clock::now();
      display_ = Display::painted;
      if (a.live) break;
      for (size_t i = 0; i + 1 < a.points.size(); i += 2)
        scene_.stroke_to(a.points[i] - view_x_, a.points[i + 1]);
      end_scripted_stroke();
      break;
    }
    case K::undo:
      scene_.undo();
      break;
    case K::redo:
      scene_.redo();
      break;
    case K::save_texture:
      scene_.save_texture(a.path);
      break;
    case K::load_texture:
      scene_.load_texture(a.path);
      break;
    case K::simplify:
      proxies_ = int(a.count);
      scene_.simplify(a.count);
      display_ = Display::clusters;
      break;
    case K::export_mesh:
      scene_.export_simplified(a.path);
      break;
    case K::screenshot:
      pending_shot_ = true;
      shot_path_ = a.path;
      break;
    case K::frames:
      wait_frames_ = a.count;
      break;
  }
}

// Ends the scripted stroke (stroke_) and reports where its time went beside the library's.
void Viewer::end_scripted_stroke() {
  last_stroke_ = scene_.end_stroke();
  const double wall =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - stroke_t0_)
          .count();
  const StrokeTimes& t = scene_.stroke_times();
  const StrokeStats lib = scene_.replay_stroke();
  const double viewer = t.paint_ms + t.upload_ms;
  std::fprintf(stderr,
               "limn-view: stroke %zu (%s, %zu points%s): %zu dabs in %.1f ms: "
               "painting %.2f ms, texture uploads %.2f ms (%zu, %zu words), frames %.1f ms; "
               "the library alone: %zu dabs in %.2f ms; viewer/library %.2fx\n",
               ++strokes_, stroke_->live ? "live" : "scripted", stroke_->points.size() / 2,
               stroke_->live ? ", one a frame" : " at once", last_stroke_.dabs, wall, t.paint_ms,
               t.upload_ms, t.uploads, t.upload_words, wall - viewer, lib.dabs, lib.ms,
               lib.ms > 0 ? viewer / lib.ms : 0.0);
  stroke_ = nullptr;
}

bool Viewer::script_step() {
  if (stroke_) {  // a live stroke: one point a frame; the frame after the last ends it
    if (stroke_next_ + 1 < stroke_->points.size()) {
      scene_.stroke_to(stroke_->points[stroke_next_] - view_x_, stroke_->points[stroke_next_ + 1]);
      stroke_next_ += 2;
    } else {
      end_scripted_stroke();
    }
    return true;
  }
  if (wait_frames_ > 0) {
    --wait_frames_;
    return true;
  }
  if (next_action_ < o_.script.size()) {
    apply(o_.script[next_action_++]);
    return true;
  }
  if (frames_left_ > 0) {
    --frames_left_;
    return true;
  }
  if (!o_.screenshot.empty()) {
    pending_shot_ = true;
    shot_path_ = o_.screenshot;
    o_.screenshot.clear();
    return true;
  }
  return false;
}

void Viewer::screenshot(const std::filesystem::path& path) {
  std::vector<uint8_t> rgba(size_t(fb_w_) * size_t(fb_h_) * 4);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, fb_w_, fb_h_, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  // GL rows run bottom to top, PNG rows top to bottom.
  const size_t row = size_t(fb_w_) * 4;
  for (int y = 0; y < fb_h_ / 2; ++y)
    std::swap_ranges(rgba.begin() + ptrdiff_t(size_t(y) * row),
                     rgba.begin() + ptrdiff_t(size_t(y + 1) * row),
                     rgba.begin() + ptrdiff_t(size_t(fb_h_ - 1 - y) * row));
  for (size_t i = 3; i < rgba.size(); i += 4) rgba[i] = 255;  // the window is opaque
  write_png(path, fb_w_, fb_h_, rgba);
  // Where the view and the model are, in window pixels: what the tests check the framing by.
  const Camera cam = orbit_.camera();
  const Mesh& cage = scene_.cage();
  double lo[2] = {1e30, 1e30}, hi[2] = {-1e30, -1e30};
  for (size_t v = 0; v < cage.vertex_count(); ++v) {
    double x, y;
    if (!cam.project(&cage.positions[3 * v], x, y)) continue;
    lo[0] = std::min(lo[0], x + view_x_), hi[0] = std::max(hi[0], x + view_x_);
    lo[1] = std::min(lo[1], y), hi[1] = std::max(hi[1], y);
  }
  std::fprintf(stderr, "limn-view: wrote %s (%dx%d), view x %d-%d, cage x %.0f-%.0f y %.0f-%.0f\n",
               path.string().c_str(), fb_w_, fb_h_, view_x_, fb_w_, lo[0], hi[0], lo[1], hi[1]);
}

void Viewer::frame_view() {
  orbit_.frame(scene_.cage(), view_w(), std::max(fb_h_, 1));
  framed_ = true, framed_w_ = view_w(), framed_h_ = fb_h_;
}

void Viewer::update_view_area() {
  // At most two thirds of the window go to the panel: a narrow window shares it.
  view_x_ = ui_ ? std::clamp(int(std::ceil(panel_right_)), 0, 2 * fb_w_ / 3) : 0;
  orbit_.resize(view_w(), std::max(fb_h_, 1));
  if (framed_ && (view_w() != framed_w_ || fb_h_ != framed_h_)) frame_view();
}

void Viewer::mouse() {
  ImGuiIO& io = ImGui::GetIO();
  double x = 0, y = 0;
  glfwGetCursorPos(window_, &x, &y);
  x *= px_scale_, y *= px_scale_;
  const double dx = x - last_x_, dy = y - last_y_;
  last_x_ = x, last_y_ = y;
  const double scroll = std::exchange(scroll_, 0.0);
  const bool over_ui = io.WantCaptureMouse;
  if (!over_ui && scroll != 0) orbit_.zoom(std::pow(0.9, scroll)), framed_ = false;

  if (drag_button_ >= 0 && glfwGetMouseButton(window_, drag_button_) != GLFW_PRESS) {
    if (drag_button_ == GLFW_MOUSE_BUTTON_LEFT && scene_.stroking())
      last_stroke_ = scene_.end_stroke();
    drag_button_ = -1;
  }
  if (drag_button_ < 0 && !over_ui)
    for (int b : {GLFW_MOUSE_BUTTON_LEFT, GLFW_MOUSE_BUTTON_RIGHT, GLFW_MOUSE_BUTTON_MIDDLE})
      if (glfwGetMouseButton(window_, b) == GLFW_PRESS) {
        drag_button_ = b;
        if (b == GLFW_MOUSE_BUTTON_LEFT && mode_ == Mode::paint) {
          display_ = Display::painted;
          scene_.begin_stroke(brush_, orbit_.camera());
          scene_.stroke_to(x - view_x_, y);
        }
        return;
      }
  if (drag_button_ < 0 || (dx == 0 && dy == 0)) return;
  const bool shift = glfwGetKey(window_, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ||
                     glfwGetKey(window_, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
  // Left orbits (paints in paint mode), right orbits in paint mode and pans otherwise, middle
  // and shift-drags pan.
  if (drag_button_ == GLFW_MOUSE_BUTTON_LEFT && mode_ == Mode::paint) {
    if (scene_.stroking()) scene_.stroke_to(x - view_x_, y);
  } else if (drag_button_ == GLFW_MOUSE_BUTTON_MIDDLE || shift ||
             (drag_button_ == GLFW_MOUSE_BUTTON_RIGHT && mode_ != Mode::paint)) {
    orbit_.pan(dx, dy), framed_ = false;
  } else {
    orbit_.orbit(-0.4 * dx, 0.4 * dy), framed_ = false;
  }
}

void Viewer::keys() {
  ImGuiIO& io = ImGui::GetIO();
  if (io.WantCaptureKeyboard) return;
  if (io.KeyCtrl && ImGui::IsKeyPressed(GLFW_KEY_Z)) {
    io.KeyShift ? scene_.redo() : scene_.undo();
  } else if (io.KeyCtrl && ImGui::IsKeyPressed(GLFW_KEY_Y)) {
    scene_.redo();
  } else if (ImGui::IsKeyPressed(GLFW_KEY_F, false)) {
    frame_view();
  } else if (ImGui::IsKeyPressed(GLFW_KEY_W, false)) {
    draw_.outline = !draw_.outline;
  } else if (ImGui::IsKeyPressed(GLFW_KEY_TAB, false)) {
    ui_ = !ui_;
  } else if (ImGui::IsKeyPressed(GLFW_KEY_F12, false)) {
    // The next free limn-view-NNN.png in the working directory.
    for (int i = 1; i < 100000; ++i) {
      std::filesystem::path p = fmt::format("limn-view-{:03}.png", i);
      std::error_code ec;
      if (!std::filesystem::exists(p, ec)) {
        pending_shot_ = true, shot_path_ = p;
        status_ = "wrote " + p.string(), status_error_ = false;
        break;
      }
    }
  }
}

void Viewer::panel() {
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::Begin("limn-view", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
  const Mesh& cage = scene_.cage();
  ImGui::Text("%s: %zu vertices, %zu faces", scene_.name().c_str(), cage.vertex_count(),
              cage.face_count());
  ImGui::TextDisabled("%s", renderer_.c_str());
  ImGui::PushItemWidth(160);
  ImGui::Text("frame %.2f ms (%.0f fps)", smooth_ms_, smooth_ms_ > 0 ? 1000.0 / smooth_ms_ : 0.0);
  ImGui::Text("draw: gpu %.2f ms, cpu %.2f ms", stats_.draw.gpu_ms, stats_.draw.cpu_ms);
  const auto triangles = static_cast<unsigned long long>(stats_.draw.triangles);
  if (stats_.patches) {
    ImGui::Text("patches %zu (%zu end caps), deepest %d", stats_.regular + stats_.gregory,
                stats_.gregory, stats_.deepest);
    ImGui::Text("%llu triangles, re-selection %.2f ms", triangles, select_ms_);
  } else {
    ImGui::Text("%zu polygons, %llu triangles", stats_.draw.patches, triangles);
  }
  if (const size_t words = scene_.texture_words())
    ImGui::Text("texture %zu words, last update sent %zu", words, scene_.texture_upload_words());
  ImGui::Separator();

  int mode = int(mode_);
  ImGui::RadioButton("View", &mode, int(Mode::view));
  ImGui::SameLine();
  ImGui::RadioButton("Paint", &mode, int(Mode::paint));
  ImGui::SameLine();
  ImGui::RadioButton("Simplify", &mode, int(Mode::simplify));
  if (mode != int(mode_)) set_mode(Mode(mode));
  int display = int(display_);
  const char* displays[] = {"cage", "surface", "painted", "clusters", "simplified"};
  if (ImGui::Combo("display", &display, displays, scene_.simplified() ? 5 : 3))
    display_ = Display(display);
  ImGui::Checkbox("wireframe (W)", &draw_.outline);
  ImGui::SameLine();
  ImGui::Checkbox("depth colours", &draw_.depth_colors);

  if (ImGui::CollapsingHeader("Surface", ImGuiTreeNodeFlags_DefaultOpen)) {
    if (ImGui::Checkbox("dynamic depth", &surface_.dynamic)) display_ = Display::surface;
    if (surface_.dynamic) {
      ImGui::SliderFloat("tolerance px", &surface_.tolerance_px, 0.1f, 10.0f, "%.2f",
                         ImGuiSliderFlags_Logarithmic);
      ImGui::SliderInt("max depth", &max_depth_edit_, 1, 10);
      if (ImGui::IsItemDeactivatedAfterEdit()) surface_.max_depth = max_depth_edit_;
    } else {
      ImGui::SliderInt("depth", &depth_edit_, 0, 8);
      if (ImGui::IsItemDeactivatedAfterEdit()) surface_.depth = depth_edit_;
    }
    ImGui::SliderFloat("px per segment", &surface_.tess_px, 2.0f, 32.0f, "%.1f");
  }

  if (ImGui::CollapsingHeader("Paint", mode_ == Mode::paint ? ImGuiTreeNodeFlags_DefaultOpen : 0)) {
    ImGui::SliderFloat("radius px", &brush_.radius, 1.0f, 200.0f, "%.0f",
                       ImGuiSliderFlags_Logarithmic);
    ImGui::ColorEdit4("colour", brush_.color);
    ImGui::SliderFloat("opacity", &brush_.opacity, 0.0f, 1.0f);
    ImGui::SliderFloat("hardness", &brush_.hardness, 0.0f, 1.0f);
    const char* blends[] = {"mix", "add", "multiply", "erase"};
    if (ImGui::Combo("blend", &blend_, blends, 4)) brush_.blend = BlendMode(blend_);
    ImGui::SliderInt("brush depth", &brush_.depth, 4, 14);
    // The material the brush carries: each channel on or off, with its value, blend and opacity.
    ImGui::Checkbox("paint colour", &brush_.paint_color);
    for (int k = 0; k < kMaterialChannels; ++k) {
      ChannelPaint& c = brush_.material[k];
      ImGui::PushID(k);
      ImGui::Checkbox(channel_name(MaterialChannel(k)), &c.on);
      if (c.on) {
        ImGui::SameLine();
        ImGui::SetNextItemWidth(90);
        ImGui::SliderFloat("##value", &c.value, 0.0f, 1.0f, "%.2f");
        ImGui::SameLine();
        ImGui::SetNextItemWidth(70);
        int channel_blend = int(c.blend);
        if (ImGui::Combo("##blend", &channel_blend, blends, 4)) c.blend = BlendMode(channel_blend);
        ImGui::SameLine();
        ImGui::SetNextItemWidth(70);
        ImGui::SliderFloat("##opacity", &c.opacity, 0.0f, 1.0f, "%.2f");
      }
      ImGui::PopID();
    }
    bool filtered = !draw_.texture_nearest;
    if (ImGui::Checkbox("filtered", &filtered)) draw_.texture_nearest = !filtered;
    if (ImGui::Button("Undo")) scene_.undo();
    ImGui::SameLine();
    if (ImGui::Button("Redo")) scene_.redo();
    ImGui::SameLine();
    ImGui::Text("%zu / %zu", scene_.undo_count(), scene_.redo_count());
    ImGui::InputText("texture", &texture_path_);
    if (ImGui::Button("Save .lot")) {
      try {
        scene_.save_texture(texture_path_);
        status_ = "saved " + texture_path_, status_error_ = false;
      } catch (const std::exception& e) {
        report(e);
      }
    }
    ImGui::SameLine();
    if (ImGui::Button("Load .lot")) {
      try {
        scene_.load_texture(texture_path_);
        display_ = Display::painted;
        status_ = "loaded " + texture_path_, status_error_ = false;
      } catch (const std::exception& e) {
        report(e);
      }
    }
    if (last_stroke_.dabs) {
      // The painting itself, apart from the drag's length and the frames drawn meanwhile.
      const StrokeTimes& t = scene_.stroke_times();
      ImGui::Text("last stroke: %zu dabs (%zu missed)", last_stroke_.dabs,
                  last_stroke_.dabs_missed);
      ImGui::Text("  painting %.1f ms (%.2f a dab), uploads %.1f ms", t.paint_ms,
                  t.paint_ms / double(last_stroke_.dabs), t.upload_ms);
    }
  }

  if (ImGui::CollapsingHeader("Simplify",
                              mode_ == Mode::simplify ? ImGuiTreeNodeFlags_DefaultOpen : 0)) {
    ImGui::InputInt("proxies K", &proxies_);
    proxies_ = std::clamp(proxies_, 1, 100000);
    if (ImGui::Button("Run")) {
      try {
        scene_.simplify(size_t(proxies_));
        display_ = Display::clusters;
        status_.clear();
      } catch (const std::exception& e) {
        report(e);
      }
    }
    if (const VsaResult* r = scene_.simplified()) {
      ImGui::SameLine();
      ImGui::Text("%zu clusters, %zu polygons, E %.3g, %.0f ms", r->stats.clusters,
                  r->output.mesh.face_count(), r->stats.energy, scene_.simplify_ms());
      ImGui::InputText("output", &export_path_);
      if (ImGui::Button("Export")) {
        try {
          scene_.export_simplified(export_path_);
          status_ = "wrote " + export_path_, status_error_ = false;
        } catch (const std::exception& e) {
          report(e);
        }
      }
    }
  }
  if (!status_.empty()) {
    if (status_error_)
      ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.4f, 1.0f), "%s", status_.c_str());
    else
      ImGui::TextUnformatted(status_.c_str());
  }
  ImGui::PopItemWidth();
  panel_right_ = double(ImGui::GetWindowPos().x + ImGui::GetWindowSize().x) * px_scale_;
  ImGui::End();
}

void Viewer::frame() {
  glfwGetFramebufferSize(window_, &fb_w_, &fb_h_);
  int win_w = 1, win_h = 1;
  glfwGetWindowSize(window_, &win_w, &win_h);
  px_scale_ = win_w > 0 ? double(fb_w_) / win_w : 1.0;

  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  if (ui_) panel();
  update_view_area();
  if (!scene_.stroking()) guard([&] { scene_.warm_up_paint(); });
  if (!o_.scripted) {
    guard([&] { mouse(); });
    guard([&] { keys(); });
    if (mode_ == Mode::paint && !ImGui::GetIO().WantCaptureMouse) {
      // The brush's footprint follows the cursor.
      const ImVec2 m = ImGui::GetMousePos();
      ImGui::GetForegroundDrawList()->AddCircle(m, float(brush_.radius / px_scale_),
                                                IM_COL32(255, 255, 255, 180), 48, 1.5f);
    }
  }
  ImGui::Render();

  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glViewport(0, 0, fb_w_, fb_h_);
  glClearColor(background_[0], background_[1], background_[2], background_[3]);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glViewport(view_x_, 0, view_w(), fb_h_);
  if (fb_w_ > 0 && fb_h_ > 0) {
    DrawOptions d = draw_;
    d.pixels_per_segment = surface_.tess_px;
    guard([&] { stats_ = scene_.draw(display_, orbit_.camera(), surface_, d); });
    if (stats_.reselected) select_ms_ = stats_.select_ms;
  }
  glViewport(0, 0, fb_w_, fb_h_);
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  if (pending_shot_) {
    pending_shot_ = false;
    screenshot(shot_path_);
  }
  glfwSwapBuffers(window_);
  // A live stroke's frames are timed apart from its painting: a software driver (llvmpipe)
  // would otherwise still be drawing on the same cores while the next dabs are painted.
  if (stroke_) glFinish();

  const auto now = std::chrono::steady_clock::now();
  frame_ms_ = std::chrono::duration<double, std::milli>(now - last_frame_).count();
  last_frame_ = now;
  smooth_ms_ = smooth_ms_ > 0 ? 0.9 * smooth_ms_ + 0.1 * frame_ms_ : frame_ms_;
}

void Viewer::run() {
  while (!glfwWindowShouldClose(window_)) {
    glfwPollEvents();
    if (o_.scripted) {
      glfwGetFramebufferSize(window_, &fb_w_, &fb_h_);
      update_view_area();
      if (!script_step()) break;
      frame();
      continue;
    }
    frame();
  }
}

}  // namespace

void run_viewer(Scene& scene, const ViewerOptions& options) {
  Viewer v(scene, options);
  v.run();
}

}  // namespace limn::view

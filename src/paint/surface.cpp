// The painted surface: fanned triangles, face normals and the Embree 3 scene behind ray casts,
// closest points and the box queries that decide where the octree may refine.
#include "limn/paint/surface.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "geometry.hpp"
#include "limn/paint/texture.hpp"
#include "surface_impl.hpp"

namespace limn {

using namespace paint_detail;

namespace {

struct Frame {
  V3 f, r, u;
  double tan_half = 0, aspect = 1;
};

bool camera_frame(const PaintCamera& c, Frame& fr) {
  const V3 eye = v3(c.eye), target = v3(c.target), up = v3(c.up);
  V3 f = target - eye;
  const float lf = length(f);
  if (!(lf > 0) || !std::isfinite(lf)) return false;
  f = (1.0f / lf) * f;
  V3 r = cross(f, up);
  const float lr = length(r);
  if (!(lr > 1e-6f * std::max(1.0f, length(up)))) return false;
  r = (1.0f / lr) * r;
  fr.f = f, fr.r = r, fr.u = cross(r, f);
  if (!(c.fovy_deg > 0 && c.fovy_deg < 180) || c.width < 1 || c.height < 1) return false;
  fr.tan_half = std::tan(double(c.fovy_deg) * 3.14159265358979323846 / 360.0);
  fr.aspect = double(c.width) / double(c.height);
  return true;
}

}  // namespace

bool PaintCamera::valid() const {
  Frame fr;
  return camera_frame(*this, fr);
}

bool PaintCamera::ray(double px, double py, float dir[3]) const {
  Frame fr;
  if (!camera_frame(*this, fr)) return false;
  const double x = (2.0 * px / width - 1.0) * fr.tan_half * fr.aspect;
  const double y = (1.0 - 2.0 * py / height) * fr.tan_half;
  const V3 d = fr.f + float(x) * fr.r + float(y) * fr.u;
  const float l = length(d);
  dir[0] = d.x / l, dir[1] = d.y / l, dir[2] = d.z / l;
  return true;
}

bool PaintCamera::project(const float p[3], double& px, double& py) const {
  Frame fr;
  if (!camera_frame(*this, fr)) return false;
  const V3 d = v3(p) - v3(eye);
  const double z = dot(d, fr.f);
  if (!(z > 0)) return false;
  const double x = dot(d, fr.r) / z, y = dot(d, fr.u) / z;
  px = (x / (fr.tan_half * fr.aspect) + 1.0) * 0.5 * width;
  py = (1.0 - y / fr.tan_half) * 0.5 * height;
  return true;
}

double PaintCamera::world_per_pixel(const float p[3]) const {
  Frame fr;
  if (!camera_frame(*this, fr)) return 0;
  const double z = std::max(double(dot(v3(p) - v3(eye), fr.f)), 1e-9);
  return 2.0 * z * fr.tan_half / height;
}

PaintSurface::PaintSurface(const Mesh& mesh) : impl_(std::make_unique<Impl>()) {
  validate(mesh, "mesh");
  std::vector<uint32_t> tris;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const auto v = mesh.face(f);
    for (size_t i = 1; i + 1 < v.size(); ++i) {
      tris.insert(tris.end(), {v[0], v[i], v[i + 1]});
      faces_.push_back(uint32_t(f));
    }
  }
  if (tris.empty()) throw InputError("mesh: no faces to paint on");
  const size_t nt = tris.size() / 3;
  corners_.resize(9 * nt);
  normals_.resize(3 * nt);
  for (size_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k)
      std::copy_n(&mesh.positions[3 * size_t(tris[3 * t + size_t(k)])], 3,
                  &corners_[9 * t + 3 * size_t(k)]);
    const V3 a = v3(&corners_[9 * t]), b = v3(&corners_[9 * t + 3]), c = v3(&corners_[9 * t + 6]);
    const V3 n = cross(b - a, c - a);
    const float l = length(n);
    if (l > 0 && std::isfinite(l)) {
      normals_[3 * t] = n.x / l, normals_[3 * t + 1] = n.y / l, normals_[3 * t + 2] = n.z / l;
    }
  }
  bounds_ = bounding_box(mesh);
  tags_.resize(nt);
  back_.resize(nt);
  for (size_t t = 0; t < nt; ++t) {
    const float* n = &normals_[3 * t];
    tags_[t] = uint8_t(octree::tag_for_normal(n));
    uint16_t back = 0;
    for (int k = 0; k <= octree::kTagCount; ++k)
      back = uint16_t(back | octree::side_for_normal(k, n) << k);
    back_[t] = back;
  }

  impl_->device = embree().rtcNewDevice(nullptr);
  if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
  impl_->ray16 =
      embree().rtcGetDeviceProperty(impl_->device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0;
  impl_->scene = embree().rtcNewScene(impl_->device);
  embree().rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
  // Watertight: a ray through a shared vertex or edge must not slip between the triangles (a
  // missed occluder would paint through it, a missed pick would drop a dab).
  embree().rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
  RTCGeometry g = embree().rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  float* vb = static_cast<float*>(embree().rtcSetNewGeometryBuffer(
      g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.vertex_count()));
  std::copy(mesh.positions.begin(), mesh.positions.end(), vb);
  unsigned* ib = static_cast<unsigned*>(embree().rtcSetNewGeometryBuffer(
      g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), nt));
  std::copy(tris.begin(), tris.end(), ib);
  embree().rtcCommitGeometry(g);
  embree().rtcAttachGeometry(impl_->scene, g);
  embree().rtcReleaseGeometry(g);
  embree().rtcCommitScene(impl_->scene);
}

PaintSurface::~PaintSurface() = default;

namespace {

struct ClosestQuery {
  const PaintSurface* s;
  V3 p;
  float best;
  uint32_t tri;
  V3 q;
};

bool closest_callback(RTCPointQueryFunctionArguments* args) {
  auto* q = static_cast<ClosestQuery*>(args->userPtr);
  const uint32_t t = args->primID;
  const V3 c = closest_on_triangle(q->p, v3(q->s->corner(t, 0)), v3(q->s->corner(t, 1)),
                                   v3(q->s->corner(t, 2)));
  const float d = length(q->p - c);
  if (d < q->best || (d == q->best && t < q->tri)) {
    q->best = d, q->tri = t, q->q = c;
    args->query->radius = std::nextafter(d, INFINITY);
    return true;
  }
  return false;
}

// Sorts out[first..] and drops repeats (a triangle a BVH query meets in several leaves): through a
// bitmap of all n triangles when the list is long enough that scanning n / 64 words costs less
// than sorting it (a dab's list: thousands of the mesh's triangles), else by sorting. The
// same list either way.
void sort_unique(std::vector<uint32_t>& out, size_t first, size_t n) {
  const size_t k = out.size() - first;
  if (k < 64 || n / 64 > 4 * k) {
    std::sort(out.begin() + std::ptrdiff_t(first), out.end());
    out.erase(std::unique(out.begin() + std::ptrdiff_t(first), out.end()), out.end());
    return;
  }
  thread_local std::vector<uint64_t> bits;
  if (bits.size() < (n + 63) / 64) bits.assign((n + 63) / 64, 0);
  for (size_t i = first; i < out.size(); ++i) bits[out[i] >> 6] |= uint64_t(1) << (out[i] & 63);
  out.resize(first);
  for (size_t w = 0; w < (n + 63) / 64; ++w) {
    for (uint64_t b = bits[w]; b; b &= b - 1)
      out.push_back(uint32_t(64 * w) + uint32_t(std::countr_zero(b)));
    bits[w] = 0;
  }
}

struct GatherQuery {
  std::vector<uint32_t>* out;
};

bool gather_callback(RTCPointQueryFunctionArguments* args) {
  static_cast<GatherQuery*>(args->userPtr)->out->push_back(args->primID);
  return false;
}

struct BoxQuery {
  const PaintSurface* s;
  std::vector<uint32_t>* out;
  paint_detail::V3 c;
  float h, slack;
};

bool candidate_callback(RTCPointQueryFunctionArguments* args) {
  const BoxQuery& q = *static_cast<const BoxQuery*>(args->userPtr);
  if (!q.s->degenerate(args->primID)) q.out->push_back(args->primID);
  return false;
}

bool box_callback(RTCPointQueryFunctionArguments* args) {
  const BoxQuery& q = *static_cast<const BoxQuery*>(args->userPtr);
  const uint32_t t = args->primID;
  if (q.s->degenerate(t)) return false;
  using paint_detail::v3;
  const paint_detail::V3 a = v3(q.s->corner(t, 0)), b = v3(q.s->corner(t, 1)),
                         d = v3(q.s->corner(t, 2));
  // CellBoxes::filter's test, so the same triangles as filtering triangles_near's answer.
  if (paint_detail::tri_meets_box(q.c, q.h, a, b, d, q.slack)) q.out->push_back(t);
  return false;
}

}  // namespace

bool PaintSurface::closest_point(const float p[3], float max_dist, SurfaceHit& hit) const {
  ClosestQuery q{this, v3(p), std::nextafter(max_dist, INFINITY), UINT32_MAX, {}};
  RTCPointQuery pq;
  pq.x = p[0], pq.y = p[1], pq.z = p[2];
  pq.time = 0;
  pq.radius = q.best;
  RTCPointQueryContext ctx;
  rtcInitPointQueryContext(&ctx);
  embree().rtcPointQuery(impl_->scene, &pq, &ctx, &closest_callback, &q);
  if (q.tri == UINT32_MAX || q.best > max_dist) return false;
  hit.p[0] = q.q.x, hit.p[1] = q.q.y, hit.p[2] = q.q.z;
  std::copy_n(normal(q.tri), 3, hit.n);
  hit.triangle = q.tri;
  hit.distance = q.best;
  return true;
}

bool PaintSurface::intersect(const float org[3], const float dir[3], float tnear, float tfar,
                             SurfaceHit& hit) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  rh.ray.org_x = org[0], rh.ray.org_y = org[1], rh.ray.org_z = org[2];
  rh.ray.dir_x = dir[0], rh.ray.dir_y = dir[1], rh.ray.dir_z = dir[2];
  rh.ray.tnear = tnear, rh.ray.tfar = tfar;
  rh.ray.time = 0, rh.ray.mask = 0xffffffffu, rh.ray.id = 0, rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  embree().rtcIntersect1(impl_->scene, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  hit.distance = rh.ray.tfar;
  for (int k = 0; k < 3; ++k) hit.p[k] = org[k] + rh.ray.tfar * dir[k];
  hit.triangle = rh.hit.primID;
  std::copy_n(normal(rh.hit.primID), 3, hit.n);
  return true;
}

bool PaintSurface::occluded(const float org[3], const float dir[3], float tnear, float tfar) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay r;
  r.org_x = org[0], r.org_y = org[1], r.org_z = org[2];
  r.dir_x = dir[0], r.dir_y = dir[1], r.dir_z = dir[2];
  r.tnear = tnear, r.tfar = tfar;
  r.time = 0, r.mask = 0xffffffffu, r.id = 0, r.flags = 0;
  embree().rtcOccluded1(impl_->scene, &ctx, &r);
  return r.tfar == -INFINITY;
}

namespace {

// One packet of up to K rays (count = m); idle lanes repeat the last ray, masked off.
template <size_t K, class Packet, class Trace>
void occluded_packets(size_t count, const float* org, const float* dir, const float* tnear,
                      const float* tfar, uint8_t* occluded, Trace&& trace) {
  for (size_t g = 0; g < count; g += K) {
    const size_t m = std::min(K, count - g);
    Packet r;
    alignas(64) int valid[K];
    for (size_t i = 0; i < K; ++i) {
      const size_t k = g + std::min(i, m - 1);
      valid[i] = i < m ? -1 : 0;
      r.org_x[i] = org[3 * k], r.org_y[i] = org[3 * k + 1], r.org_z[i] = org[3 * k + 2];
      r.dir_x[i] = dir[3 * k], r.dir_y[i] = dir[3 * k + 1], r.dir_z[i] = dir[3 * k + 2];
      r.tnear[i] = tnear[k], r.tfar[i] = tfar[k];
      r.time[i] = 0, r.mask[i] = 0xffffffffu, r.id[i] = unsigned(i), r.flags[i] = 0;
    }
    trace(valid, &r);
    for (size_t i = 0; i < m; ++i) occluded[g + i] = r.tfar[i] == -INFINITY ? 1 : 0;
  }
}

}  // namespace

void PaintSurface::occluded_many(size_t count, const float* org, const float* dir,
                                 const float* tnear, const float* tfar, uint8_t* occluded) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  RTCScene scene = impl_->scene;
  if (impl_->ray16)
    occluded_packets<16, RTCRay16>(
        count, org, dir, tnear, tfar, occluded,
        [&](const int* valid, RTCRay16* r) { embree().rtcOccluded16(valid, scene, &ctx, r); });
  else
    occluded_packets<8, RTCRay8>(
        count, org, dir, tnear, tfar, occluded,
        [&](const int* valid, RTCRay8* r) { embree().rtcOccluded8(valid, scene, &ctx, r); });
}

void PaintSurface::triangles_near(const float c[3], float r, std::vector<uint32_t>& out) const {
  const size_t first = out.size();
  GatherQuery q{&out};
  RTCPointQuery pq;
  pq.x = c[0], pq.y = c[1], pq.z = c[2];
  pq.time = 0;
  pq.radius = r;
  RTCPointQueryContext ctx;
  rtcInitPointQueryContext(&ctx);
  embree().rtcPointQuery(impl_->scene, &pq, &ctx, &gather_callback, &q);
  auto it = std::remove_if(out.begin() + std::ptrdiff_t(first), out.end(),
                           [&](uint32_t t) { return degenerate(t); });
  out.erase(it, out.end());
  sort_unique(out, first, triangle_count());
}

namespace {

// The ball query both box queries make, `callback` deciding what each candidate adds.
void ask_box(RTCScene scene, BoxQuery& q, RTCPointQueryFunction callback) {
  RTCPointQuery pq;
  pq.x = q.c.x, pq.y = q.c.y, pq.z = q.c.z;
  pq.time = 0;
  pq.radius = (q.h + q.slack) * 1.7320508f * 1.0001f;  // the ball around the grown box
  RTCPointQueryContext ctx;
  rtcInitPointQueryContext(&ctx);
  embree().rtcPointQuery(scene, &pq, &ctx, callback, &q);
}

}  // namespace

void PaintSurface::triangles_in_box(const float c[3], float h, float slack,
                                    std::vector<uint32_t>& out) const {
  const size_t first = out.size();
  BoxQuery q{this, &out, {c[0], c[1], c[2]}, h, slack};
  ask_box(impl_->scene, q, &box_callback);
  sort_unique(out, first, triangle_count());
}

void PaintSurface::box_candidates(const float c[3], float h, float slack,
                                  std::vector<uint32_t>& out) const {
  BoxQuery q{this, &out, {c[0], c[1], c[2]}, h, slack};
  ask_box(impl_->scene, q, &candidate_callback);
}

}  // namespace limn

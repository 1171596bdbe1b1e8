// Surface-to-surface distances through Embree point queries.
#include "limn/simplify/distance.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include "core/embree.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "core/closest_point.hpp"
#include "core/vec3.hpp"

namespace limn {

namespace {

using P3 = Vec3d;

// A BVH over a mesh's faces (fanned into triangles) for closest-point queries.
class ClosestPoint {
 public:
  explicit ClosestPoint(const Mesh& m) : m_(m) {
    for (size_t f = 0; f < m.face_count(); ++f) {
      const auto v = m.face(f);
      for (size_t i = 1; i + 1 < v.size(); ++i) tris_.insert(tris_.end(), {v[0], v[i], v[i + 1]});
    }
    device_ = embree().rtcNewDevice(nullptr);
    if (!device_) throw std::runtime_error("Embree: cannot create a device");
    scene_ = embree().rtcNewScene(device_);
    RTCGeometry g = embree().rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    float* vb = static_cast<float*>(embree().rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.vertex_count()));
    std::copy(m.positions.begin(), m.positions.end(), vb);
    unsigned* ib = static_cast<unsigned*>(embree().rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), tris_.size() / 3));
    std::copy(tris_.begin(), tris_.end(), ib);
    embree().rtcCommitGeometry(g);
    embree().rtcAttachGeometry(scene_, g);
    embree().rtcReleaseGeometry(g);
    embree().rtcCommitScene(scene_);
  }
  ~ClosestPoint() {
    embree().rtcReleaseScene(scene_);
    embree().rtcReleaseDevice(device_);
  }
  ClosestPoint(const ClosestPoint&) = delete;
  ClosestPoint& operator=(const ClosestPoint&) = delete;

  // Distance from p to the mesh. Thread-safe.
  double distance(P3 p) const {
    Query q{this, p, std::numeric_limits<double>::infinity()};
    RTCPointQuery pq;
    pq.x = static_cast<float>(p.x), pq.y = static_cast<float>(p.y), pq.z = static_cast<float>(p.z);
    pq.time = 0;
    pq.radius = std::numeric_limits<float>::infinity();
    RTCPointQueryContext ctx;
    rtcInitPointQueryContext(&ctx);
    embree().rtcPointQuery(scene_, &pq, &ctx, &ClosestPoint::callback, &q);
    return q.best;
  }

 private:
  struct Query {
    const ClosestPoint* self;
    P3 p;
    double best;
  };
  P3 vertex(uint32_t v) const {
    const float* x = &m_.positions[3 * size_t(v)];
    return {x[0], x[1], x[2]};
  }
  static bool callback(RTCPointQueryFunctionArguments* args) {
    Query* q = static_cast<Query*>(args->userPtr);
    const uint32_t* t = &q->self->tris_[3 * size_t(args->primID)];
    const P3 c = closest_on_triangle(q->p, q->self->vertex(t[0]), q->self->vertex(t[1]),
                                     q->self->vertex(t[2]));
    const P3 d = q->p - c;
    const double dist = std::sqrt(dot(d, d));
    if (dist < q->best) {
      q->best = dist;
      // Embree's radius is float; round up so the true closest triangle is never culled.
      args->query->radius = std::nextafter(static_cast<float>(dist), INFINITY);
      return true;
    }
    return false;
  }

  const Mesh& m_;
  std::vector<uint32_t> tris_;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
};

struct Acc {
  double max = 0, sum2 = 0;
};

template <class PointAt>
Acc measure(const ClosestPoint& cp, size_t n, PointAt&& point_at) {
  return tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, n, 1024), Acc{},
      [&](const tbb::blocked_range<size_t>& r, Acc a) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
          const double d = cp.distance(point_at(i));
          a.max = std::max(a.max, d);
          a.sum2 += d * d;
        }
        return a;
      },
      [](Acc a, Acc b) {
        return Acc{std::max(a.max, b.max), a.sum2 + b.sum2};
      });
}

}  // namespace

SurfaceDistance surface_distance(const Mesh& simplified, const Mesh& reference, size_t samples,
                                 uint64_t seed) {
  SurfaceDistance r;
  const double diag = bounding_box(reference).diagonal();
  if (simplified.face_count() == 0 || reference.face_count() == 0 || !(diag > 0)) return r;
  // Area-uniform samples on the simplified surface: systematic positions along the cumulative
  // area of its (fanned) triangles, uniform within each triangle.
  std::vector<uint32_t> tris;
  std::vector<double> cum;
  double total = 0;
  auto P = [&](uint32_t v) {
    const float* x = &simplified.positions[3 * size_t(v)];
    return P3{x[0], x[1], x[2]};
  };
  for (size_t f = 0; f < simplified.face_count(); ++f) {
    const auto v = simplified.face(f);
    for (size_t i = 1; i + 1 < v.size(); ++i) {
      const P3 a = P(v[0]), b = P(v[i]), c = P(v[i + 1]);
      const P3 u = b - a, w = c - a;
      const P3 x = cross(u, w);
      total += 0.5 * std::sqrt(dot(x, x));
      tris.insert(tris.end(), {v[0], v[i], v[i + 1]});
      cum.push_back(total);
    }
  }
  std::vector<P3> pts;
  pts.reserve(samples + simplified.vertex_count());
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (size_t i = 0; i < samples && total > 0; ++i) {
    const double at = (double(i) + 0.5) / double(samples) * total;
    const size_t t = std::min<size_t>(
        size_t(std::lower_bound(cum.begin(), cum.end(), at) - cum.begin()), cum.size() - 1);
    double u = uni(rng), v = uni(rng);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const P3 a = P(tris[3 * t]), b = P(tris[3 * t + 1]), c = P(tris[3 * t + 2]);
    pts.push_back(a + u * (b - a) + v * (c - a));
  }
  const size_t area_samples = pts.size();
  for (size_t v = 0; v < simplified.vertex_count(); ++v) pts.push_back(P(uint32_t(v)));

  {
    const ClosestPoint to_ref(reference);
    const Acc area = measure(to_ref, area_samples, [&](size_t i) { return pts[i]; });
    const Acc verts =
        measure(to_ref, pts.size() - area_samples, [&](size_t i) { return pts[area_samples + i]; });
    r.max_to_reference = std::max(area.max, verts.max) / diag;
    r.rms_to_reference = area_samples ? std::sqrt(area.sum2 / double(area_samples)) / diag : 0;
  }
  {
    std::vector<uint8_t> used(reference.vertex_count(), 0);
    for (uint32_t v : reference.face_vertices) used[v] = 1;
    std::vector<P3> rv;
    for (size_t v = 0; v < reference.vertex_count(); ++v)
      if (used[v]) {
        const float* x = &reference.positions[3 * v];
        rv.push_back({x[0], x[1], x[2]});
      }
    const ClosestPoint to_simplified(simplified);
    const Acc back = measure(to_simplified, rv.size(), [&](size_t i) { return rv[i]; });
    r.max_from_reference = back.max / diag;
  }
  r.hausdorff = std::max(r.max_to_reference, r.max_from_reference);
  r.samples = area_samples;
  return r;
}

}  // namespace limn

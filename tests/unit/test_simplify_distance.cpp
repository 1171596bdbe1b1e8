// surface_distance (what `limn simplify --json` reports as Hausdorff and RMS) against an
// independent brute force: the exact minimum over every triangle of the other mesh of a
// point-to-triangle distance written differently from limn's (projection onto the plane and an
// inside test, else the nearest of the three edges), in double, no BVH (a sort by x and bounding
// spheres skip only triangles that cannot be nearer). What the function
// documents is checked piece by piece:
// - max_from_reference is over the reference's vertices only, so it is exact and compared tightly;
// - with samples = 0 only the simplified mesh's vertices are measured, so max_to_reference is
//   exact too (this isolates Embree's closest-point query from the sampling);
// - with samples > 0, max_to_reference must lie within the sup of the distance over the
//   simplified surface (bracketed by a dense barycentric lattice and the distance being
//   1-Lipschitz) and RMS must equal the area integral of d^2 (a fine midpoint quadrature);
// - two planar cases with closed-form answers (a parallel offset, a tilted square).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <vector>

#include "limn/io/mesh_io.hpp"
#include "limn/simplify/distance.hpp"
#include "limn/simplify/vsa.hpp"
#include "simplify_oracle.hpp"

namespace limn {
namespace {

namespace fs = std::filesystem;
const fs::path kModels = LIMN_SHARED_MODELS;

struct D3 {
  double x = 0, y = 0, z = 0;
};
D3 operator-(D3 a, D3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
D3 operator+(D3 a, D3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
D3 operator*(double s, D3 a) {
  return {s * a.x, s * a.y, s * a.z};
}
double dot(D3 a, D3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
D3 cross(D3 a, D3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double norm(D3 a) {
  return std::sqrt(dot(a, a));
}

double point_segment(D3 p, D3 a, D3 b) {
  const D3 ab = b - a;
  const double l2 = dot(ab, ab);
  const double t = l2 > 0 ? std::clamp(dot(p - a, ab) / l2, 0.0, 1.0) : 0.0;
  return norm(p - (a + t * ab));
}

// The closest point of a triangle is the foot of the perpendicular when that foot lies inside
// (three same-side tests against the normal), else it is on the boundary.
double point_triangle(D3 p, D3 a, D3 b, D3 c) {
  const D3 n = cross(b - a, c - a);
  const double nn = dot(n, n);
  if (nn > 0) {
    const double h = dot(p - a, n) / nn;
    const D3 q = p - h * n;
    if (dot(cross(b - a, q - a), n) >= 0 && dot(cross(c - b, q - b), n) >= 0 &&
        dot(cross(a - c, q - c), n) >= 0)
      return std::abs(h) * std::sqrt(nn);
  }
  return std::min({point_segment(p, a, b), point_segment(p, b, c), point_segment(p, c, a)});
}

struct Tri {
  D3 a, b, c;
};

D3 position(const Mesh& m, uint32_t v) {
  const float* x = &m.positions[3 * size_t(v)];
  return {x[0], x[1], x[2]};
}

// Faces fanned from their first corner, as distance.hpp documents.
std::vector<Tri> fan(const Mesh& m) {
  std::vector<Tri> t;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto v = m.face(f);
    for (size_t i = 1; i + 1 < v.size(); ++i)
      t.push_back({position(m, v[0]), position(m, v[i]), position(m, v[i + 1])});
  }
  return t;
}

// Brute force over the triangles, in double. Two shortcuts skip only triangles that provably
// cannot be nearer than the best distance so far (each triangle lies within its bounding sphere,
// and every sphere's radius is at most rmax), so the answer is still the exact minimum over all
// triangles: the search starts from the previous query's nearest triangle, and walks the
// triangles in order of their centres' x outwards from p.x, stopping where |c.x - p.x| >= best +
// rmax.
class BruteDistance {
 public:
  explicit BruteDistance(const Mesh& m) : tris_(fan(m)) {
    std::sort(tris_.begin(), tris_.end(),
              [](const Tri& s, const Tri& t) { return centre(s).x < centre(t).x; });
    for (const Tri& t : tris_) {
      const D3 c = centre(t);
      centres_.push_back(c);
      xs_.push_back(c.x);
      radii_.push_back(std::max({norm(t.a - c), norm(t.b - c), norm(t.c - c)}));
      rmax_ = std::max(rmax_, radii_.back());
    }
  }
  double operator()(D3 p) {
    double best = exact(p, last_);
    auto visit = [&](size_t i) {
      if (norm(p - centres_[i]) - radii_[i] >= best) return;
      const double d = exact(p, i);
      if (d < best) best = d, last_ = i;
    };
    const size_t mid = size_t(std::lower_bound(xs_.begin(), xs_.end(), p.x) - xs_.begin());
    for (size_t i = mid; i < xs_.size() && xs_[i] - p.x < best + rmax_; ++i) visit(i);
    for (size_t i = mid; i-- > 0 && p.x - xs_[i] < best + rmax_;) visit(i);
    return best;
  }

 private:
  static D3 centre(const Tri& t) { return (1.0 / 3.0) * (t.a + t.b + t.c); }
  double exact(D3 p, size_t i) const {
    return point_triangle(p, tris_[i].a, tris_[i].b, tris_[i].c);
  }

  std::vector<Tri> tris_;
  std::vector<D3> centres_;
  std::vector<double> xs_, radii_;
  double rmax_ = 0;
  size_t last_ = 0;
};

double diagonal(const Mesh& m) {
  D3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const D3 p = position(m, uint32_t(v));
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  return norm(hi - lo);
}

// Largest distance from a vertex of `from` (used by a face) to the surface `to`.
double max_over_vertices(const Mesh& from, const Mesh& to) {
  BruteDistance d(to);
  std::vector<uint8_t> used(from.vertex_count(), 0);
  for (uint32_t v : from.face_vertices) used[v] = 1;
  double mx = 0;
  for (size_t v = 0; v < from.vertex_count(); ++v)
    if (used[v]) mx = std::max(mx, d(position(from, uint32_t(v))));
  return mx;
}

struct SurfaceIntegral {
  double lattice_max = 0;  ///< max of d over the lattice points (a lower bound of the sup)
  double sup_bound = 0;    ///< an upper bound of the sup of d over the surface
  double rms = 0;          ///< sqrt(integral of d^2 / area), midpoint rule on n^2 sub-triangles
};

// d from points of `surface` to `to`: each triangle cut into n x n sub-triangles. Any point of a
// sub-triangle lies within its longest edge (the triangle's longest edge / n) of a lattice point,
// and d is 1-Lipschitz, so sup d <= lattice max + that edge.
SurfaceIntegral integrate(const Mesh& surface, const Mesh& to, int n) {
  BruteDistance d(to);
  SurfaceIntegral r;
  double area = 0, sum2 = 0;
  for (const Tri& t : fan(surface)) {
    const D3 u = t.b - t.a, w = t.c - t.a;
    auto at = [&](double s, double q) { return t.a + s * u + q * w; };
    const double edge = std::max({norm(u), norm(w), norm(t.c - t.b)}) / n;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const double di = d(at(double(i) / n, double(j) / n));
        r.lattice_max = std::max(r.lattice_max, di);
        r.sup_bound = std::max(r.sup_bound, di + edge);
      }
    const double a = 0.5 * norm(cross(u, w));
    const double sub = a / (double(n) * n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; i + j < n; ++j) {
        // Upward sub-triangle (i, j), (i+1, j), (i, j+1); downward one beside it.
        const double up = d(at((3 * i + 1) / (3.0 * n), (3 * j + 1) / (3.0 * n)));
        sum2 += sub * up * up;
        if (i + j + 2 <= n) {
          const double down = d(at((3 * i + 2) / (3.0 * n), (3 * j + 2) / (3.0 * n)));
          sum2 += sub * down * down;
        }
      }
    area += a;
  }
  r.rms = std::sqrt(sum2 / area);
  return r;
}

// Vertex-only distances must be exact: the only differences allowed are Embree's float query
// point and the float bounding-box diagonal (relative ~1e-7).
constexpr double kExact = 1e-6;

// `rms_tolerance` (relative) covers the Monte Carlo error of 200000 samples (the RMS of d^2 is
// heavy-tailed on fandisk's fanned polygons: up to ~0.5% seen across seeds, ~0.1% on the
// sphere) plus the midpoint rule's (~0.15% at n = 24, from n = 64); the quantity it guards is
// the area weighting and the normalisation, whose errors are far larger.
void expect_matches_brute_force(const Mesh& simplified, const Mesh& reference,
                                double rms_tolerance) {
  const double diag = diagonal(reference);
  ASSERT_GT(diag, 0);
  const double from_ref = max_over_vertices(reference, simplified) / diag;
  const double to_ref_vertices = max_over_vertices(simplified, reference) / diag;

  // samples = 0: vertices only, both ways.
  const SurfaceDistance v = surface_distance(simplified, reference, 0);
  EXPECT_EQ(v.samples, 0u);
  EXPECT_NEAR(v.max_from_reference, from_ref, kExact * std::max(from_ref, 1e-3));
  EXPECT_NEAR(v.max_to_reference, to_ref_vertices, kExact * std::max(to_ref_vertices, 1e-3));
  EXPECT_EQ(v.hausdorff, std::max(v.max_from_reference, v.max_to_reference));
  EXPECT_EQ(v.rms_to_reference, 0);

  // The default sampling (the CLI's 200000 samples).
  const SurfaceIntegral in = integrate(simplified, reference, 24);
  const SurfaceDistance s = surface_distance(simplified, reference);
  EXPECT_EQ(s.samples, 200000u);
  EXPECT_NEAR(s.max_from_reference, from_ref, kExact * std::max(from_ref, 1e-3));
  // Samples are points of the surface, so their max is at most the sup; with the vertices
  // included it is at least the vertices' max; and 200000 of them come within a lattice edge of
  // the sup (the lattice max is itself below the sup).
  EXPECT_LE(s.max_to_reference, in.sup_bound / diag * (1 + kExact));
  EXPECT_GE(s.max_to_reference, to_ref_vertices * (1 - kExact));
  EXPECT_GE(s.max_to_reference, (2 * in.lattice_max - in.sup_bound) / diag * (1 - kExact));
  EXPECT_EQ(s.hausdorff, std::max(s.max_from_reference, s.max_to_reference));
  EXPECT_NEAR(s.rms_to_reference, in.rms / diag, rms_tolerance * in.rms / diag)
      << "brute-force RMS " << in.rms / diag;
  ::testing::Test::RecordProperty("hausdorff", std::to_string(s.hausdorff));
  ::testing::Test::RecordProperty("rms_limn", std::to_string(s.rms_to_reference));
  ::testing::Test::RecordProperty("rms_brute", std::to_string(in.rms / diag));
}

TEST(SimplifyDistance, CoarseSphereInscribedInAFineOneMatchesBruteForce) {
  // Every coarse vertex lies on the fine sphere's circumscribed sphere, so the coarse surface
  // pokes in and out of the fine polyhedron: both one-sided distances are nonzero.
  const Mesh fine = test::uv_sphere(40, 80, 1.0f);
  const Mesh coarse = test::uv_sphere(6, 10, 1.0f);
  expect_matches_brute_force(coarse, fine, 0.005);
}

TEST(SimplifyDistance, FandiskSimplifiedOutputMatchesBruteForce) {
  const Mesh m = read_mesh(kModels / "tri" / "fandisk.obj");
  for (bool polygons : {false, true}) {
    SCOPED_TRACE(polygons ? "polygons (fanned)" : "triangles");
    VsaOptions o;
    o.proxies = 30;
    o.meshing.polygons = polygons;
    const VsaResult r = simplify_vsa(m, o, "fandisk");
    expect_matches_brute_force(r.output.mesh, m, 0.01);
  }
}

// Closed forms on the unit square (the reference: an 8 x 8 grid scaled to [0,1]^2, so its
// bounding-box diagonal is sqrt 2).
Mesh unit_grid() {
  Mesh g = test::grid_mesh(8);
  for (float& x : g.positions) x /= 8.0f;
  return g;
}

Mesh square(float z0, float z1) {
  Mesh s;
  s.add_vertex(0, 0, z0);
  s.add_vertex(1, 0, z0);
  s.add_vertex(1, 1, z1);
  s.add_vertex(0, 1, z1);
  s.add_face({0, 1, 2, 3});
  return s;
}

TEST(SimplifyDistance, AParallelOffsetIsItsHeightEverywhere) {
  const double h = 0.125, diag = std::sqrt(2.0);
  const SurfaceDistance d = surface_distance(square(0.125f, 0.125f), unit_grid(), 50000, 7);
  EXPECT_NEAR(d.max_to_reference, h / diag, 1e-7);
  EXPECT_NEAR(d.max_from_reference, h / diag, 1e-7);
  EXPECT_NEAR(d.rms_to_reference, h / diag, 1e-7);
  EXPECT_NEAR(d.hausdorff, h / diag, 1e-7);
  EXPECT_EQ(d.samples, 50000u);
}

TEST(SimplifyDistance, ATiltedSquareHasItsClosedFormDistances) {
  // The square z = a y over [0,1]^2: a point (x, y, a y) is a y above the plane, its foot inside
  // the reference; so max = a, and over area-uniform samples (y uniform) RMS = a / sqrt 3. A
  // reference vertex (x, y, 0) is a y / sqrt(1 + a^2) from the tilted plane, its foot at
  // y / (1 + a^2) inside the square: max a / sqrt(1 + a^2).
  const double a = 0.5, diag = std::sqrt(2.0);
  const SurfaceDistance d = surface_distance(square(0, 0.5f), unit_grid());
  EXPECT_NEAR(d.max_to_reference, a / diag, 1e-7);
  EXPECT_NEAR(d.max_from_reference, a / std::sqrt(1 + a * a) / diag, 1e-7);
  // Monte Carlo over 200000 samples: d^2 has a relative standard deviation of ~0.9, so the RMS
  // is within ~0.1% (1 sigma) of the integral; 0.5% is 5 sigma.
  EXPECT_NEAR(d.rms_to_reference, a / std::sqrt(3.0) / diag, 0.005 * a / std::sqrt(3.0) / diag);
  EXPECT_NEAR(d.hausdorff, a / diag, 1e-7);
}

}  // namespace
}  // namespace limn

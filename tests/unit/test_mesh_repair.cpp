// repair_mesh against CGAL's Polygon Mesh Processing: shuffled, flipped, welded-apart and
// non-manifold versions of the shared meshes must come out as a polygon mesh by CGAL's
// is_polygon_soup_a_polygon_mesh, without non-manifold vertices by duplicate_non_manifold_vertices,
// closed pieces outward by is_outward_oriented, with the surface area and the vertex positions of
// the input; and beside CGAL's own soup repair (repair_polygon_soup + orient_polygon_soup) on the
// same soups. Small cases built on purpose check each count and that attributes follow.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/manifoldness.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Surface_mesh.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <tuple>

#include "bad_input.hpp"
#include "cli_runner.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/mesh/repair.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/mesh/topology.hpp"
#include "limn/mesh/weld.hpp"
#include "soups.hpp"

namespace limn {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
using Polygons = std::vector<std::vector<std::size_t>>;
using test::broken;
using test::Pos;
using test::pos;
using test::shuffled;
using test::welded_apart;

void to_soup(const Mesh& m, std::vector<Point>& points, Polygons& polygons) {
  points.clear();
  polygons.clear();
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const Pos p = pos(m, uint32_t(v));
    points.emplace_back(p[0], p[1], p[2]);
  }
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto fv = m.face(f);
    polygons.emplace_back(fv.begin(), fv.end());
  }
}

// Area by CGAL (triangulated fans for polygons, so any arity works).
double soup_area(const std::vector<Point>& points, const Polygons& polygons) {
  double a = 0;
  for (const auto& p : polygons)
    for (size_t i = 1; i + 1 < p.size(); ++i)
      a += std::sqrt(
          CGAL::to_double(CGAL::squared_area(points[p[0]], points[p[i]], points[p[i + 1]])));
  return a;
}

double mesh_area(const Mesh& m) {
  std::vector<Point> points;
  Polygons polygons;
  to_soup(m, points, polygons);
  return soup_area(points, polygons);
}

std::set<Pos> referenced_positions(const Mesh& m) {
  std::set<Pos> s;
  for (const uint32_t v : m.face_vertices) s.insert(pos(m, v));
  return s;
}

// Faces as sorted position triples... of any arity: the sorted list of their corner positions.
std::multiset<std::vector<Pos>> face_keys(const Mesh& m) {
  std::multiset<std::vector<Pos>> s;
  for (size_t f = 0; f < m.face_count(); ++f) {
    std::vector<Pos> k;
    for (const uint32_t v : m.face(f)) k.push_back(pos(m, v));
    std::sort(k.begin(), k.end());
    s.insert(k);
  }
  return s;
}

// Everything repair promises, checked by CGAL where CGAL can tell: a polygon mesh (manifold,
// consistently oriented), no non-manifold vertex, closed triangle pieces outward.
void expect_clean(const Mesh& out) {
  ASSERT_NO_THROW(validate(out));
  std::vector<Point> points;
  Polygons polygons;
  to_soup(out, points, polygons);
  ASSERT_TRUE(PMP::is_polygon_soup_a_polygon_mesh(polygons));
  SurfaceMesh sm;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, sm);
  ASSERT_TRUE(CGAL::is_valid_polygon_mesh(sm));
  EXPECT_EQ(sm.number_of_faces(), out.face_count());
  EXPECT_EQ(sm.number_of_vertices(), out.vertex_count()) << "unreferenced vertices left";
  EXPECT_EQ(PMP::duplicate_non_manifold_vertices(sm), 0u);
  std::vector<SurfaceMesh> pieces;
  PMP::split_connected_components(sm, pieces);
  for (const SurfaceMesh& piece : pieces) {
    if (CGAL::is_closed(piece) && CGAL::is_triangle_mesh(piece)) {
      EXPECT_TRUE(PMP::is_outward_oriented(piece));
    }
  }
  // No duplicate faces (equal corner position sets) and no repeated vertex.
  const auto keys = face_keys(out);
  EXPECT_EQ(std::set<std::vector<Pos>>(keys.begin(), keys.end()).size(), keys.size());
}

const char* kSharedMeshes[] = {"spot.obj", "fandisk.obj", "blade.off", "ogre.obj"};

RepairOptions exact_weld() {
  RepairOptions o;
  o.weld_tolerance = 0;
  return o;
}

Mesh shared(const char* name) {
  return read_mesh(std::filesystem::path(LIMN_SHARED_MODELS) / "tri" / name);
}

// A shared mesh repaired once (equal positions welded only): what the broken versions break.
Mesh clean_shared(const char* name) {
  return repair_mesh(shared(name), exact_weld());
}

// ---- shared meshes ----

TEST(Repair, SharedMeshesShuffledAndFlippedComeBackOriented) {
  std::mt19937 rng(7);
  for (const char* name : kSharedMeshes) {
    SCOPED_TRACE(name);
    const RepairOptions exact = exact_weld();
    const Mesh clean = clean_shared(name);
    std::vector<uint8_t> flipped;
    const Mesh soup = shuffled(clean, rng, flipped, 0.3);
    RepairReport r;
    const Mesh out = repair_mesh(soup, exact, &r);
    expect_clean(out);
    EXPECT_EQ(face_keys(out), face_keys(clean));
    EXPECT_EQ(referenced_positions(out), referenced_positions(clean));
    EXPECT_NEAR(mesh_area(out), mesh_area(clean), 1e-9 * mesh_area(clean));
    EXPECT_EQ(r.non_manifold_edges + r.split_vertices + r.degenerate_faces + r.duplicate_faces, 0u);
    // Closed single pieces must be turned back exactly: as many flips as were made.
    if (r.components == 1 && r.closed_components == 1) {
      EXPECT_EQ(r.flipped_faces, size_t(std::count(flipped.begin(), flipped.end(), 1)));
    }
  }
}

TEST(Repair, SharedMeshInsideOutIsTurnedOutward) {
  RepairOptions exact;
  exact.weld_tolerance = 0;
  std::mt19937 rng(3);
  std::vector<uint8_t> flipped;
  const Mesh soup = shuffled(shared("fandisk.obj"), rng, flipped, 1.0);
  RepairReport r;
  const Mesh out = repair_mesh(soup, exact, &r);
  expect_clean(out);
  EXPECT_EQ(r.flipped_faces, soup.face_count());
  EXPECT_EQ(r.closed_components, 1u);
}

TEST(Repair, SharedMeshesWeldedApartComeBackConnected) {
  std::mt19937 rng(11);
  for (const char* name : kSharedMeshes) {
    SCOPED_TRACE(name);
    const RepairOptions exact = exact_weld();
    const Mesh clean = clean_shared(name);
    const Mesh soup = welded_apart(clean, rng);
    RepairReport r;
    const Mesh out = repair_mesh(soup, exact, &r);
    expect_clean(out);
    EXPECT_EQ(out.vertex_count(), clean.vertex_count());
    EXPECT_EQ(face_keys(out), face_keys(clean));
    EXPECT_EQ(referenced_positions(out), referenced_positions(clean));
    EXPECT_EQ(r.welded_vertices + out.vertex_count() - r.split_vertices, soup.vertex_count());
  }
}

TEST(Repair, NonManifoldSharedMeshesBesideCgal) {
  std::mt19937 rng(5);
  for (const char* name : kSharedMeshes) {
    SCOPED_TRACE(name);
    const RepairOptions exact = exact_weld();
    const Mesh clean = clean_shared(name);
    std::vector<uint8_t> flipped;
    double duplicate_area = 0;
    const Mesh soup = shuffled(broken(clean, rng, 12, 8, 6, duplicate_area), rng, flipped, 0.2);
    RepairReport r;
    const Mesh out = repair_mesh(soup, exact, &r);
    expect_clean(out);
    // Brute force: edges (by end positions) of three or more distinct, non-degenerate faces. The
    // fins make 12 (fewer where one sits on a boundary edge); the copy may add its own where it
    // happens to meet the original along an edge.
    std::map<std::pair<Pos, Pos>, int> edge_faces;
    std::set<std::vector<Pos>> seen;
    for (size_t f = 0; f < soup.face_count(); ++f) {
      std::vector<Pos> k;
      for (const uint32_t v : soup.face(f)) k.push_back(pos(soup, v));
      std::vector<Pos> s = k;
      std::sort(s.begin(), s.end());
      if (std::adjacent_find(s.begin(), s.end()) != s.end() || !seen.insert(s).second) continue;
      for (size_t i = 0; i < k.size(); ++i)
        ++edge_faces[{std::min(k[i], k[(i + 1) % k.size()]),
                      std::max(k[i], k[(i + 1) % k.size()])}];
    }
    size_t non_manifold = 0;
    for (const auto& [e, n] : edge_faces) non_manifold += n > 2;
    EXPECT_GE(non_manifold, 6u);
    EXPECT_EQ(r.non_manifold_edges, non_manifold);
    EXPECT_EQ(r.duplicate_faces, 8u);
    EXPECT_EQ(r.degenerate_faces, 6u);
    EXPECT_GE(r.split_vertices, 1u);  // at least the vertex the two copies share
    // Area: all but the duplicates' (the degenerate faces have none).
    EXPECT_NEAR(mesh_area(out), mesh_area(soup) - duplicate_area, 1e-6 * mesh_area(out));
    EXPECT_EQ(referenced_positions(out), referenced_positions(soup));

    // CGAL's soup repair on the same soup: the same faces survive, the same area.
    std::vector<Point> points;
    Polygons polygons;
    to_soup(soup, points, polygons);
    PMP::repair_polygon_soup(points, polygons);
    PMP::orient_polygon_soup(points, polygons);
    ASSERT_TRUE(PMP::is_polygon_soup_a_polygon_mesh(polygons));
    EXPECT_EQ(polygons.size(), out.face_count());
    EXPECT_NEAR(soup_area(points, polygons), mesh_area(out), 1e-9 * mesh_area(out));
    RecordProperty(std::string("cgal_points_") + name, std::to_string(points.size()));
    RecordProperty(std::string("limn_vertices_") + name, std::to_string(out.vertex_count()));
  }
}

// ---- small cases built on purpose ----

TEST(Repair, CleanMeshIsReturnedUnchanged) {
  for (const char* shape : {"cube", "torus", "cage"}) {
    SCOPED_TRACE(shape);
    const Mesh m = make_shape(shape);
    RepairReport r;
    const Mesh out = repair_mesh(m, {}, &r);
    EXPECT_FALSE(r.changed());
    EXPECT_EQ(out.positions, m.positions);
    EXPECT_EQ(out.face_offsets, m.face_offsets);
    EXPECT_EQ(out.face_vertices, m.face_vertices);
    EXPECT_EQ(out.crease_edges.size(), m.crease_edges.size());
    EXPECT_EQ(out.corner_vertices, m.corner_vertices);
    EXPECT_EQ(out.hole_faces, m.hole_faces);
  }
}

TEST(Repair, WeldsWithinToleranceOnly) {
  Mesh m;  // two triangles whose shared edge's ends differ by 1e-7 of the diagonal
  m.add_vertex(0, 0, 0), m.add_vertex(1, 0, 0), m.add_vertex(0, 1, 0);
  m.add_vertex(1, 1e-7f, 0), m.add_vertex(1e-7f, 1, 0), m.add_vertex(1, 1, 0);
  m.add_face({0, 1, 2}), m.add_face({3, 5, 4});
  RepairReport r;
  Mesh out = repair_mesh(m, {}, &r);  // default 1e-6 of the diagonal
  EXPECT_EQ(r.welded_vertices, 2u);
  EXPECT_EQ(out.vertex_count(), 4u);
  expect_clean(out);
  RepairOptions exact;
  exact.weld_tolerance = 0;
  out = repair_mesh(m, exact, &r);
  EXPECT_EQ(r.welded_vertices, 0u);
  EXPECT_EQ(out.vertex_count(), 6u);
  // weld_map_within against brute force on random clustered points.
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(0, 1), jitter(-0.004f, 0.004f);
  std::vector<float> xyz;
  for (int i = 0; i < 300; ++i) {
    const float c[3] = {u(rng), u(rng), u(rng)};
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) xyz.push_back(c[k] + jitter(rng));
  }
  const double tol = 0.01;
  const std::vector<uint32_t> g = weld_map_within(xyz, tol);
  const size_t n = xyz.size() / 3;
  std::vector<uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  const auto root = [&](size_t i) {
    while (parent[i] != i) i = parent[i];
    return i;
  };
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < i; ++j) {
      double d2 = 0;
      for (int k = 0; k < 3; ++k) d2 += std::pow(double(xyz[3 * i + k]) - xyz[3 * j + k], 2);
      if (d2 <= tol * tol)
        parent[std::max(root(i), root(j))] = uint32_t(std::min(root(i), root(j)));
    }
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < i; ++j) ASSERT_EQ(g[i] == g[j], root(i) == root(j)) << i << " " << j;
}

TEST(Repair, PinchedPolygonIsSplitIntoLoops) {
  Mesh m;  // a b c a d e: two triangles joined at a, written as one hexagon
  m.add_vertex(0, 0, 0), m.add_vertex(1, 0, 0), m.add_vertex(1, 1, 0);
  m.add_vertex(-1, 0, 0), m.add_vertex(-1, -1, 0);
  m.face_vertices = {0, 1, 2, 0, 3, 4};
  m.face_offsets = {0, 6};
  EXPECT_THROW(validate(m), RepairableError);
  RepairReport r;
  const Mesh out = repair_mesh(m, {}, &r);
  EXPECT_EQ(r.split_faces, 1u);
  EXPECT_EQ(out.face_count(), 2u);
  EXPECT_EQ(r.split_vertices, 1u);  // the two loops meet only at a: a bowtie, split
  expect_clean(out);
  EXPECT_NEAR(mesh_area(out), 1.0, 1e-6);
}

TEST(Repair, FinsBowtiesAndMoebius) {
  {  // three triangles on one edge
    Mesh m;
    m.add_vertex(0, 0, 0), m.add_vertex(1, 0, 0);
    m.add_vertex(0.5f, 1, 0), m.add_vertex(0.5f, -1, 0), m.add_vertex(0.5f, 0, 1);
    m.add_face({0, 1, 2}), m.add_face({1, 0, 3}), m.add_face({0, 1, 4});
    RepairReport r;
    const Mesh out = repair_mesh(m, {}, &r);
    EXPECT_EQ(r.non_manifold_edges, 1u);
    expect_clean(out);
    EXPECT_EQ(out.face_count(), 3u);
  }
  {  // a strip of 8 quads closed with a half twist
    Mesh m;
    const int n = 8;
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n, w = 0.3 * std::cos(a / 2), h = 0.3 * std::sin(a / 2);
      m.add_vertex(float((1 + w) * std::cos(a)), float((1 + w) * std::sin(a)), float(h));
      m.add_vertex(float((1 - w) * std::cos(a)), float((1 - w) * std::sin(a)), float(-h));
    }
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t j = (i + 1) % n;
      if (j == 0)
        m.add_face({2 * i, 2 * i + 1, 0, 1});  // the twist: the ends swap sides
      else
        m.add_face({2 * i, 2 * i + 1, 2 * j + 1, 2 * j});
    }
    RepairReport r;
    const Mesh out = repair_mesh(m, {}, &r);
    EXPECT_EQ(r.unorientable_edges, 1u);
    expect_clean(out);
  }
}

TEST(Repair, AttributesFollowTheirCornersVerticesAndFaces) {
  Mesh m = make_crease_cage();
  // Per-vertex colours that name their vertex.
  for (size_t v = 0; v < m.vertex_count(); ++v)
    m.colors.insert(m.colors.end(), {float(v) / float(m.vertex_count()), 0.5f, 0.25f, 1});
  std::mt19937 rng(9);
  std::vector<uint8_t> flipped;
  Mesh soup = shuffled(m, rng, flipped, 0.5);
  // shuffled() renumbers vertices and corners: carry the attributes by position.
  std::map<Pos, std::array<float, 4>> color_at;
  for (size_t v = 0; v < m.vertex_count(); ++v)
    color_at[pos(m, uint32_t(v))] = {m.colors[4 * v], m.colors[4 * v + 1], m.colors[4 * v + 2],
                                     m.colors[4 * v + 3]};
  soup.colors.resize(4 * soup.vertex_count());
  for (size_t v = 0; v < soup.vertex_count(); ++v) {
    const auto c = color_at[pos(soup, uint32_t(v))];
    std::copy(c.begin(), c.end(), &soup.colors[4 * v]);
  }
  // A corner's UV: (its corner in the soup, its vertex in m).
  soup.uvs.clear();
  std::map<Pos, uint32_t> vertex_at;
  for (size_t v = 0; v < m.vertex_count(); ++v) vertex_at[pos(m, uint32_t(v))] = uint32_t(v);
  for (size_t c = 0; c < soup.corner_count(); ++c) {
    soup.uvs.push_back(float(c));
    soup.uvs.push_back(float(vertex_at[pos(soup, soup.face_vertices[c])]));
    soup.uv_indices.push_back(uint32_t(c));
  }
  for (size_t i = 0; i < m.corner_vertices.size(); ++i)  // tags by position too
    for (uint32_t x = 0; x < soup.vertex_count(); ++x)
      if (pos(soup, x) == pos(m, m.corner_vertices[i])) {
        soup.corner_vertices.push_back(x);
        soup.corner_sharpness.push_back(m.corner_sharpness[i]);
      }
  for (size_t e = 0; e < m.crease_sharpness.size(); ++e) {
    const uint32_t a = m.crease_edges[2 * e], b = m.crease_edges[2 * e + 1];
    for (uint32_t x = 0; x < soup.vertex_count(); ++x)
      for (uint32_t y = 0; y < soup.vertex_count(); ++y)
        if (pos(soup, x) == pos(m, a) && pos(soup, y) == pos(m, b)) {
          soup.crease_edges.insert(soup.crease_edges.end(), {x, y});
          soup.crease_sharpness.push_back(m.crease_sharpness[e]);
        }
  }
  RepairReport r;
  const Mesh out = repair_mesh(soup, {}, &r);
  expect_clean(out);
  EXPECT_EQ(r.flipped_faces,
            std::min<size_t>(std::count(flipped.begin(), flipped.end(), 1),
                             m.face_count() - std::count(flipped.begin(), flipped.end(), 1)));
  for (size_t c = 0; c < out.corner_count(); ++c) {
    const uint32_t v = out.face_vertices[c];
    const float* uv = &out.uvs[2 * out.uv_indices[c]];
    EXPECT_EQ(uv[1], float(vertex_at[pos(out, v)]));
    EXPECT_EQ(pos(soup, soup.face_vertices[size_t(uv[0])]), pos(out, v));
    EXPECT_EQ(out.colors[4 * v], color_at[pos(out, v)][0]);
  }
  // Creases: the same edges by position with the same sharpness.
  std::multiset<std::tuple<Pos, Pos, float>> want, got;
  for (size_t e = 0; e < m.crease_sharpness.size(); ++e) {
    const Pos a = pos(m, m.crease_edges[2 * e]), b = pos(m, m.crease_edges[2 * e + 1]);
    want.insert({std::min(a, b), std::max(a, b), m.crease_sharpness[e]});
  }
  for (size_t e = 0; e < out.crease_sharpness.size(); ++e) {
    const Pos a = pos(out, out.crease_edges[2 * e]), b = pos(out, out.crease_edges[2 * e + 1]);
    got.insert({std::min(a, b), std::max(a, b), out.crease_sharpness[e]});
  }
  EXPECT_EQ(got, want);
  std::multiset<std::pair<Pos, float>> want_corners, got_corners;
  for (size_t i = 0; i < m.corner_vertices.size(); ++i)
    want_corners.insert({pos(m, m.corner_vertices[i]), m.corner_sharpness[i]});
  for (size_t i = 0; i < out.corner_vertices.size(); ++i)
    got_corners.insert({pos(out, out.corner_vertices[i]), out.corner_sharpness[i]});
  EXPECT_EQ(got_corners, want_corners);
}

TEST(Repair, HolesFollowTheirFaces) {
  Mesh m = make_crease_cage();
  ASSERT_FALSE(m.hole_faces.empty());
  std::vector<Pos> hole_centres;
  const auto centre = [](const Mesh& x, size_t f) {
    Pos c{0, 0, 0};
    for (const uint32_t v : x.face(f))
      for (int k = 0; k < 3; ++k) c[k] += pos(x, v)[k];
    return c;
  };
  std::set<Pos> want;
  for (const uint32_t f : m.hole_faces) want.insert(centre(m, f));
  // Insert a duplicate of face 0 up front: every face index after it moves by one.
  Mesh soup;
  soup.positions = m.positions;
  soup.add_face(m.face(0));
  for (size_t f = 0; f < m.face_count(); ++f) soup.add_face(m.face(f));
  for (const uint32_t f : m.hole_faces) soup.hole_faces.push_back(f + 1);
  RepairReport r;
  const Mesh out = repair_mesh(soup, {}, &r);
  EXPECT_EQ(r.duplicate_faces, 1u);
  std::set<Pos> got;
  for (const uint32_t f : out.hole_faces) got.insert(centre(out, f));
  EXPECT_EQ(got, want);
}

TEST(Repair, RandomSmallSoupsComeOutClean) {
  // What the fuzz target checks, over many random soups: a few vertices (some at equal
  // positions) and up to 30 faces of 3-6 corners drawn from them with repeats: pinches, fins,
  // bowties, duplicates and disagreeing faces all occur.
  std::mt19937 rng(17);
  size_t changed = 0;
  for (int round = 0; round < 3000; ++round) {
    Mesh m;
    const int nv = 4 + int(rng() % 9);
    for (int v = 0; v < nv; ++v) {
      const int q = int(rng() % 27);
      m.add_vertex(float(q % 3), float(q / 3 % 3), float(q / 9));  // on a 3x3x3 grid: repeats
    }
    const int nf = 1 + int(rng() % 30);
    for (int f = 0; f < nf; ++f) {
      const int n = 3 + int(rng() % 4);
      for (int k = 0; k < n; ++k) m.face_vertices.push_back(uint32_t(rng() % uint32_t(nv)));
      m.face_offsets.push_back(uint32_t(m.face_vertices.size()));
    }
    RepairReport r;
    const Mesh out = repair_mesh(m, {}, &r);
    changed += r.changed();
    if (out.face_count() == 0) continue;
    SCOPED_TRACE(round);
    ASSERT_NO_THROW(validate(out));
    const MeshStats st = analyze(out, build_topology(out));
    ASSERT_EQ(st.non_manifold_edges, 0u);
    ASSERT_EQ(st.non_manifold_vertices, 0u);
    ASSERT_EQ(st.inconsistent_edges, 0u);
    ASSERT_EQ(st.unreferenced_vertices, 0u);
    std::vector<Point> points;
    Polygons polygons;
    to_soup(out, points, polygons);
    ASSERT_TRUE(PMP::is_polygon_soup_a_polygon_mesh(polygons));
  }
  EXPECT_GT(changed, 2000u);
}

TEST(Repair, BadInputIsRefused) {
  Mesh m = make_cube();
  RepairOptions o;
  o.weld_tolerance = 0.5;
  EXPECT_THROW(repair_mesh(m, o), InputError);
  o.weld_tolerance = std::nan("");
  EXPECT_THROW(repair_mesh(m, o), InputError);
  Mesh bad = m;
  bad.positions[4] = NAN;
  EXPECT_THROW(repair_mesh(bad), InputError);
  bad = m;
  bad.face_vertices[3] = 99;
  EXPECT_THROW(repair_mesh(bad), InputError);
  EXPECT_EQ(repair_mesh(Mesh{}).face_count(), 0u);
  // A hostile 200,000-gon that pinches at every other corner stays fast (no quadratic loop).
  Mesh big;
  big.add_vertex(0, 0, 0);
  std::vector<uint32_t> f;
  for (uint32_t i = 0; i < 100000; ++i) {
    f.push_back(0);
    const float a = float(i) * 1e-4f;
    f.push_back(big.add_vertex(std::cos(a), std::sin(a), 0));
  }
  big.face_vertices = f;
  big.face_offsets = {0, uint32_t(f.size())};
  RepairReport r;
  EXPECT_EQ(repair_mesh(big, {}, &r).face_count(), 0u);  // every loop is a 2-corner spike
  EXPECT_EQ(r.degenerate_faces, 1u);
}

}  // namespace
}  // namespace limn

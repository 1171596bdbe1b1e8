// Gregory end caps (OpenSubdiv 3.5's Far GREGORY_BASIS: limit position P, edge points Ep/Em from
// the limit tangent masks, face points Fp/Fm from Loop et al. 2009), their rows shared between the
// end caps around a corner fan, emitted once their level is gone.
#include "patch_builder.hpp"

namespace limn::patch_detail {

void GregoryCap::finish_topology(uint32_t first, uint32_t count) {
  // The union of the corners and rings in the order met, deduplicated through the slot map (a
  // stale slot never names a matching entry: the support's ids are distinct).
  support.clear();
  if (slots.size() < count) slots.resize(count);
  auto take = [&](uint32_t id) {
    if (id - first >= count) throw std::logic_error("patches: end-cap point off level");
    const uint32_t s = slots[id - first];
    if (s < support.size() && support[s] == id) return;
    slots[id - first] = uint32_t(support.size());
    support.push_back(id);
  };
  for (const Corner& k : c) {
    take(k.v);
    for (const uint32_t id : k.ring) take(id);
  }
  for (int i = 0; i < 4; ++i)
    for (Terms* t : {&p[i], &ep[i], &em[i]}) t->reset(support, slots.data(), first, count);
  const double pi = std::numbers::pi;
  for (Corner& k : c) {
    k.valence = k.faces + (k.boundary ? 1 : 0);
    k.regular = (k.faces << (k.boundary ? 1 : 0)) == 4 && !k.sharp;
    const double angle = k.regular ? 0.5 * pi : (k.boundary ? pi : 2.0 * pi) / std::max(k.faces, 1);
    k.cos_angle = k.regular ? 0.0 : std::cos(angle);
  }
  for (int i = 0; i < 4; ++i) {
    Corner& k = c[i];
    const Corner &next = c[(i + 1) & 3], &prev = c[(i + 3) & 3];
    k.fp_regular = k.regular && next.regular;
    k.fm_regular = k.regular && prev.regular;
    if (!k.boundary) continue;
    k.ep_on_boundary = k.face_in_ring == 0;
    k.em_on_boundary = k.face_in_ring == k.faces - 1;
    if (k.faces > 1) {
      // One of the corner's patch edges is a boundary: its two face points coincide.
      if (k.ep_on_boundary) k.fp_regular = k.fm_regular, k.fp_copied = !k.fp_regular;
      if (k.em_on_boundary) k.fm_regular = k.fp_regular, k.fm_copied = !k.fm_regular;
    } else {
      k.fp_regular = k.fm_regular = true;
    }
  }
}

// Tangent scale of OpenSubdiv's Gregory points: 16/n / (c + 5 + sqrt((c + 9)(c + 1))), c =
// cos(2 pi / n) (its table for n < 30 holds the same values).
double tangent_coefficient(int n) {
  const double ct = std::cos(2.0 * std::numbers::pi / n);
  return 16.0 / n / (ct + 5.0 + std::sqrt((ct + 9.0) * (ct + 1.0)));
}

void GregoryCap::edge_points(int i) {
  const Corner& k = c[i];
  const uint32_t v = k.v, next = c[(i + 1) & 3].v, prev = c[(i + 3) & 3].v;
  const std::vector<uint32_t>& r = k.ring;
  if (k.regular && !k.boundary) {
    p[i].add(v, 4.0 / 9.0);
    for (int m = 0; m < 4; ++m) p[i].add(r[2 * m], 1.0 / 9.0), p[i].add(r[2 * m + 1], 1.0 / 36.0);
    const int e_p = 2 * k.face_in_ring, e_m = 2 * ((k.face_in_ring + 1) & 3);
    const int o_p = 2 * ((k.face_in_ring + 2) & 3), o_m = 2 * ((k.face_in_ring + 3) & 3);
    ep[i].add(v, 4.0 / 9.0), ep[i].add(r[e_p], 2.0 / 9.0), ep[i].add(r[e_m], 1.0 / 9.0);
    ep[i].add(r[o_m], 1.0 / 9.0), ep[i].add(r[e_p + 1], 1.0 / 18.0);
    ep[i].add(r[o_m + 1], 1.0 / 18.0);
    em[i].add(v, 4.0 / 9.0), em[i].add(r[e_m], 2.0 / 9.0), em[i].add(r[e_p], 1.0 / 9.0);
    em[i].add(r[o_p], 1.0 / 9.0), em[i].add(r[e_p + 1], 1.0 / 18.0);
    em[i].add(r[e_m + 1], 1.0 / 18.0);
  } else if (k.regular) {  // regular boundary: two faces
    Terms& on = k.ep_on_boundary ? ep[i] : em[i];
    Terms& in = k.ep_on_boundary ? em[i] : ep[i];
    p[i].add(v, 2.0 / 3.0), p[i].add(r[0], 1.0 / 6.0), p[i].add(r[4], 1.0 / 6.0);
    on.add(v, 2.0 / 3.0), on.add(r[k.ep_on_boundary ? 0 : 4], 1.0 / 3.0);
    in.add(v, 4.0 / 9.0), in.add(r[2], 2.0 / 9.0), in.add(r[0], 1.0 / 9.0);
    in.add(r[4], 1.0 / 9.0), in.add(r[1], 1.0 / 18.0), in.add(r[3], 1.0 / 18.0);
  } else if (k.sharp || (k.boundary && k.faces == 1)) {
    // A sharp corner interpolates; a smooth one-face boundary follows its crease curve.
    if (k.sharp) {
      p[i].add(v, 1.0);
    } else {
      p[i].add(v, 4.0 / 6.0), p[i].add(next, 1.0 / 6.0), p[i].add(prev, 1.0 / 6.0);
    }
    ep[i].add(v, 2.0 / 3.0), ep[i].add(next, 1.0 / 3.0);
    em[i].add(v, 2.0 / 3.0), em[i].add(prev, 1.0 / 3.0);
  } else if (!k.boundary) {
    // Smooth interior: the limit position, and the limit tangent along each patch edge scaled
    // by OpenSubdiv's eigenvalue coefficient.
    const int n = k.valence;
    const double pc = 1.0 / (n * (n + 5.0)), tc = tangent_coefficient(n) * 0.5 / (n + 5.0);
    const double th = 2.0 * std::numbers::pi / n;
    std::vector<double> w(2 * size_t(n), 0.0);  // tangent along ring edge 0
    for (int m = 0; m < n; ++m) {
      const int mp = (m + n - 1) % n, mn = (m + 1) % n;
      const double cm = tc * std::cos(th * m);
      w[2 * mp] += 2 * cm, w[2 * mp + 1] += cm, w[2 * m] += 4 * cm, w[2 * m + 1] += cm;
      w[2 * mn] += 2 * cm;
    }
    p[i].add(v, n / (n + 5.0)), ep[i].add(v, n / (n + 5.0)), em[i].add(v, n / (n + 5.0));
    for (int m = 0; m < 2 * n; ++m) {
      const double pw = (m & 1) ? pc : 4 * pc;
      // Ep is the tangent rotated onto edge face_in_ring, Em onto the next edge.
      const int sp = (m + 2 * (n - k.face_in_ring)) % (2 * n);
      const int sm = (m + 2 * (2 * n - k.face_in_ring - 1)) % (2 * n);
      p[i].add(r[m], pw);
      ep[i].add(r[m], pw + w[sp]);
      em[i].add(r[m], pw + w[sm]);
    }
  } else {
    // Smooth boundary with three or more faces.
    const int nf = k.faces, n = k.valence, N = 2 * n - 1;
    const double th = std::numbers::pi / nf, ct = std::cos(th), st = std::sin(th);
    const double d = 1.0 / (3.0 * nf + ct);
    std::vector<double> pw(2 * size_t(n), 0.0), tw(2 * size_t(n), 0.0);
    pw[0] = 4.0 / 6.0, pw[1] = 1.0 / 6.0, pw[N] = 1.0 / 6.0;
    const double alpha0 = -((1.0 + 2.0 * ct) * std::sqrt(1.0 + ct)) * d / std::sqrt(1.0 - ct);
    tw[0] = -4.0 * st * d / 3.0, tw[1] = alpha0 / 3.0, tw[2] = st * d / 3.0, tw[N] = alpha0 / 3.0;
    for (int m = 1; m < n - 1; ++m) {
      tw[1 + 2 * m] = 4.0 * std::sin(th * m) * d / 3.0;
      tw[2 + 2 * m] = (std::sin(th * m) + std::sin(th * (m + 1))) * d / 3.0;
    }
    // Weight index 0 is the corner, index m >= 1 ring point m - 1.
    auto put = [&](Terms& out, const std::vector<double>& wt) {
      out.add(v, wt[0]);
      for (int m = 1; m <= N; ++m) out.add(r[size_t(m) - 1], wt[size_t(m)]);
    };
    put(p[i], pw);
    auto along = [&](int edge, Terms& out) {
      const double a = th * edge, ca = std::cos(a), sa = std::sin(a);
      std::vector<double> wt(2 * size_t(n));
      for (int m = 0; m <= N; ++m) wt[size_t(m)] = tw[size_t(m)] * sa;
      wt[0] += pw[0];
      wt[1] += pw[1] + ca / 6.0;
      wt[size_t(N)] += pw[size_t(N)] - ca / 6.0;
      put(out, wt);
    };
    if (k.ep_on_boundary)
      ep[i].add(v, 2.0 / 3.0), ep[i].add(r[0], 1.0 / 3.0);
    else
      along(k.face_in_ring, ep[i]);
    if (k.em_on_boundary)
      em[i].add(v, 2.0 / 3.0), em[i].add(r[size_t(N) - 1], 1.0 / 3.0);
    else
      along((k.face_in_ring + 1) % n, em[i]);
  }
}

uint32_t GregoryCap::emit_face_point(int i, bool plus, uint32_t p_row, uint32_t e_near,
                                     uint32_t e_far, StencilTable& table,
                                     detail::SharedWeights& shared) const {
  const Corner& k = c[i];
  const int far = plus ? (i + 1) & 3 : (i + 3) & 3;
  uint32_t ids[8];  // at most 3 corner points and 4 ring points
  float row[8];
  uint32_t terms = 0;
  auto put = [&](uint32_t id, double w) {
    if (w != 0.0) ids[terms] = id, row[terms++] = float(w);
  };
  if (plus ? k.fp_regular : k.fm_regular) {
    put(k.v, 4.0 / 9.0), put(c[(i + 3) & 3].v, 2.0 / 9.0), put(c[(i + 1) & 3].v, 2.0 / 9.0);
    put(c[(i + 2) & 3].v, 1.0 / 9.0);
  } else if (k.sharp && c[far].sharp) {
    // Between two sharp corners OpenSubdiv's face point is the near edge point (its converter
    // gives that row two entries: the edge point's).
    put(kCapRef | e_near, 1.0);
  } else {
    // Loop et al.'s face point: the corner's limit point and the two edge points meeting the
    // patch edge, and the rotation of the ring across it.
    const double cn = k.cos_angle, cf = c[far].cos_angle, sign = plus ? 1.0 : -1.0;
    put(kCapRef | p_row, cf / 3.0);
    put(kCapRef | e_near, (3.0 - 2.0 * cn - cf) / 3.0);
    put(kCapRef | e_far, 2.0 * cn / 3.0);
    const int n = k.valence, edge = plus ? k.face_in_ring : (k.face_in_ring + 1) % n;
    const int prev = (edge + n - 1) % n, next = (edge + 1) % n;
    put(k.ring[2 * size_t(prev)], -sign / 9.0);
    put(k.ring[2 * size_t(prev) + 1], -sign / 18.0);
    put(k.ring[2 * size_t(edge) + 1], sign / 18.0);
    put(k.ring[2 * size_t(next)], sign / 9.0);
  }
  table.indices.insert(table.indices.end(), ids, ids + terms);
  table.weight_offsets.push_back(shared.add(table.weights, row, terms));
  table.offsets.push_back(uint32_t(table.indices.size()));
  return uint32_t(table.size() - 1);
}

void Builder::reserve_caps(size_t caps) {
  PatchTable& out = out_;
  reserve_more(out.gregory_points, 20 * caps);
  // Rows and entries at the rate of the end caps so far; before any, the rate every shared cage
  // shows (8.0-8.3 corner rows of about 60 entries and 8 face rows of about 40 per end cap: a
  // corner's three points are shared by the end caps around it). The margin is smaller than the
  // patches': a rate too low doubles an array, too high is held to the end.
  const size_t made = out.gregory_points.size() / 20;
  auto rate = [&](size_t so_far, size_t first_guess_x4) {
    return made ? (so_far * caps + made - 1) / made : (first_guess_x4 * caps + 3) / 4;
  };
  auto room_caps = [](auto& v, size_t more) {
    if (v.capacity() < v.size() + more) v.reserve(v.size() + more + more / 16);
  };
  for (StencilTable* g : {&out.gregory_stencils, &out.gregory_face_stencils}) {
    const bool corner = g == &out.gregory_stencils;
    const size_t rows = rate(g->size(), corner ? 33 : 32);
    room_caps(g->offsets, rows), room_caps(g->weight_offsets, rows);
    room_caps(g->indices, rate(g->indices.size(), corner ? 240 : 160));
    // One shared row per corner row of the level (emit_cap empties it at the level's first).
    if (corner && shared_.capacity() < rows) shared_.reserve(rows + rows / 16);
  }
}

void Builder::emit_pending_caps() {
  GregoryCap& cap = cap_;
  size_t first = 0;
  for (const PendingLevel& pl : pending_levels_) {
    reserve_caps(pl.caps_end - first);
    for (size_t e = first; e < pl.caps_end; ++e) {
      cap.reset();
      uint32_t a[4];
      for (int i = 0; i < 4; ++i) {
        const PendingCorner& pc = pending_corners_[4 * e + size_t(i)];
        GregoryCap::Corner& cc = cap.c[i];
        a[i] = pc.a;
        cc.v = pl.first_point + pc.a;
        cc.fan = pc.fan, cc.fan_at = int(pc.fan_at), cc.faces = int(pc.faces);
        cc.face_in_ring = int(pc.face_in_ring), cc.boundary = pc.boundary, cc.sharp = pc.sharp;
        // The kept ring turned by ring_rot faces (a boundary ring's last point is never turned:
        // boundary rings are shared only unturned).
        cc.ring.resize(2 * size_t(pc.faces) + pc.boundary);
        pending_rings_.copy(pc.ring_at, cc.ring.size(), cc.ring.data());
        std::rotate(cc.ring.begin(), cc.ring.begin() + 2 * long(pc.ring_rot),
                    cc.ring.begin() + 2 * long(pc.faces));
      }
      cap.finish_topology(pl.first_point, pl.points);
      uint32_t ids[20];
      emit_cap(pl.level, pl.points, a, ids);
      out_.gregory_points.insert(out_.gregory_points.end(), ids, ids + 20);
    }
    first = pl.caps_end;
  }
  pending_corners_.release(), pending_rings_.release(), release(pending_levels_);
  std::unordered_map<uint64_t, std::pair<uint32_t, uint32_t>>().swap(long_fans_);
}

void Builder::emit_cap(size_t k, uint32_t count, const uint32_t a[4], uint32_t ids[20]) {
  GregoryCap& cap = cap_;
  StencilTable& corners = out_.gregory_stencils;
  if (shared_level_ != k) {
    shared_head_.assign(count, kNone);
    shared_.clear();
    shared_level_ = k;
  }
  auto find = [&](uint32_t v, uint32_t fan, uint32_t to) {
    for (uint32_t e = shared_head_[v]; e != kNone; e = shared_[e].next)
      if (shared_[e].fan == fan && shared_[e].to == to) return shared_[e].row;
    return kNone;
  };
  uint32_t rows[4][3];  // P, Ep, Em of each corner
  for (int i = 0; i < 4; ++i) {
    const GregoryCap::Corner& c = cap.c[i];
    // Ep runs along ring edge face_in_ring, Em along the next; an interior fan's ring starts at
    // the patch's face, so its edges are counted from the fan's smallest face (not by their far
    // ends: two edges may join the same two points).
    auto edge = [&](int m) {
      return uint32_t(c.boundary ? m : (m - c.fan_at + 2 * c.faces) % c.faces);
    };
    const uint32_t to[3] = {kNone, edge(c.face_in_ring), edge(c.face_in_ring + 1)};
    bool made = false;
    for (int j = 0; j < 3; ++j) {
      rows[i][j] = find(a[i], c.fan, to[j]);
      if (rows[i][j] != kNone) continue;
      if (!made) cap.edge_points(i), made = true;
      const Terms& t = j == 0 ? cap.p[i] : j == 1 ? cap.ep[i] : cap.em[i];
      rows[i][j] = cap.emit_row(t, corners, corner_weights_[j]);
      shared_.push_back({c.fan, to[j], rows[i][j], shared_head_[a[i]]});
      shared_head_[a[i]] = uint32_t(shared_.size() - 1);
    }
  }
  StencilTable& faces = out_.gregory_face_stencils;
  for (int i = 0; i < 4; ++i) {
    const GregoryCap::Corner& c = cap.c[i];
    const int next = (i + 1) & 3, prev = (i + 3) & 3;
    uint32_t fp = kNone, fm = kNone;
    // On a boundary patch edge both face points are the same point.
    if (!c.fp_copied)
      fp = cap.emit_face_point(i, true, rows[i][0], rows[i][1], rows[next][2], faces,
                               face_weights_[0]);
    if (!c.fm_copied)
      fm = cap.emit_face_point(i, false, rows[i][0], rows[i][2], rows[prev][1], faces,
                               face_weights_[1]);
    if (c.fp_copied) fp = fm;
    if (c.fm_copied) fm = fp;
    ids[5 * i] = rows[i][0], ids[5 * i + 1] = rows[i][1], ids[5 * i + 2] = rows[i][2];
    ids[5 * i + 3] = kCapRef | fp, ids[5 * i + 4] = kCapRef | fm;
  }
}

// End-cap points come after every level's, corner points first: their ids, counted from 0 in
// each table and marked kCapRef where they could be taken for something else, become global.
void resolve_cap_points(PatchTable& t) {
  const uint64_t corners = t.level_offsets.back(), faces = corners + t.gregory_stencils.size();
  if (faces + t.gregory_face_stencils.size() >= kCapRef)
    throw InputError("patches: more than 2^31 points");
  for (uint32_t& p : t.gregory_points)
    p = uint32_t(p & kCapRef ? faces + (p & ~kCapRef) : corners + p);
  for (uint32_t& p : t.gregory_face_stencils.indices)
    if (p & kCapRef) p = uint32_t(corners + (p & ~kCapRef));
}

}  // namespace limn::patch_detail

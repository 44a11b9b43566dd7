// The fast backend's manipulators (sim/manipulators.h): grab forces joined to the gathered
// forces and the first Jacobi guess, the position passes (spheres and planes as one range
// kernel over vertex slots, then the pins), and the render buffers in logical ids.
#include <algorithm>
#include <cmath>

#include "fast/fast_sim.h"

namespace crumple::fast {

namespace {
// Its loops use the step's pass grain (parallel.h): a few shape tests per vertex are as cheap as
// a force pass's item.

/// Spheres then planes, in list order, on the vertex slots [begin, end). Float, like the rest of
/// the backend; each vertex is independent, so any thread count gives the same bits.
void constrain_range(Vertices& V, const Manipulators& m, int begin, int end) {
  for (const KinematicSphere& s : m.spheres) {
    const float cx = float(s.center[0]), cy = float(s.center[1]), cz = float(s.center[2]), R = float(s.radius);
    for (int v = begin; v < end; ++v) {
      if (!(V.mass(v) > 0)) continue;
      Float4 &p = V.xm[v], &u = V.vm[v];
      const float dx = p.x - cx, dy = p.y - cy, dz = p.z - cz;
      const float r = std::sqrt(dx * dx + dy * dy + dz * dz);
      if (!(r < R) || r == 0) continue;  // a vertex at the very centre has no outward ray
      const float ux = dx / r, uy = dy / r, uz = dz / r;
      p.x = cx + R * ux, p.y = cy + R * uy, p.z = cz + R * uz;
      const float in = u.x * ux + u.y * uy + u.z * uz;
      if (in < 0) u.x -= in * ux, u.y -= in * uy, u.z -= in * uz;
    }
  }
  for (const KinematicPlane& p : m.planes) {
    const double len = std::sqrt(p.normal[0] * p.normal[0] + p.normal[1] * p.normal[1] + p.normal[2] * p.normal[2]);
    const float nx = float(p.normal[0] / len), ny = float(p.normal[1] / len), nz = float(p.normal[2] / len);
    const float ox = float(p.point[0]), oy = float(p.point[1]), oz = float(p.point[2]);
    for (int v = begin; v < end; ++v) {
      if (!(V.mass(v) > 0)) continue;
      Float4 &p = V.xm[v], &u = V.vm[v];
      const float d = (p.x - ox) * nx + (p.y - oy) * ny + (p.z - oz) * nz;
      if (!(d < 0)) continue;
      p.x -= d * nx, p.y -= d * ny, p.z -= d * nz;
      const float in = u.x * nx + u.y * ny + u.z * nz;
      if (in < 0) u.x -= in * nx, u.y -= in * ny, u.z -= in * nz;
    }
  }
}
}  // namespace

void FastSimulator::set_manipulators(const Manipulators& m) { manip_ = m; }

int FastSimulator::live_slot(int id) const {
  if (id < 0 || id >= topo_.V.size()) return -1;
  const int v = topo_.V.phys[id];
  return topo_.V.mass(v) > 0 ? v : -1;
}

// The force joins f (what explicit_velocity and the sweeps read) and the first guess g, which
// gather_forces made linear in f: h F / (m + 2 sum W_e) for the bounded predictor,
// h F / m for the explicit one (DECISIONS.md D1), as the reference's predictor has it.
void FastSimulator::add_grab_forces() {
  const Vertices& V = topo_.V;
  VertexForces& f = step_.forces;
  const double h = params_.h();
  for (const Grab& g : manip_.grabs) {
    const int v = live_slot(g.vertex);
    if (v < 0) continue;
    const double m = V.mass(v), row = m + double(f.ksum[v]);  // ksum: sum of W_e, from gather_forces
    const Float4 p = V.xm[v], u = V.vm[v];
    const std::array<double, 3> F = grab_force(g, {p.x, p.y, p.z}, {u.x, u.y, u.z}, row, h);
    f.fx[v] += float(F[0]), f.fy[v] += float(F[1]), f.fz[v] += float(F[2]);
    const double gain = params_.predictor == Predictor::Bounded ? h / (m + 2 * double(f.ksum[v])) : h / m;
    step_.g[v].x += float(gain * F[0]), step_.g[v].y += float(gain * F[1]), step_.g[v].z += float(gain * F[2]);
  }
}

void FastSimulator::apply_manipulators() {
  if (!manip_.spheres.empty() || !manip_.planes.empty())
    par_.run(topo_.V.size(), kPassGrain, [&](int b, int e) { constrain_range(topo_.V, manip_, b, e); });
  Vertices& V = topo_.V;
  for (const Pin& p : manip_.pins) {
    const int v = live_slot(p.vertex);
    if (v < 0) continue;
    V.xm[v] = Float4{float(p.target[0]), float(p.target[1]), float(p.target[2]), V.mass(v)};
    V.vm[v] = Float4{0, 0, 0, V.mass(v)};
  }
}

/// Slots ahead whose buffer lines the vertex copy fetches for writing: a write at an id's place
/// misses its line, and a missed store holds its store-buffer entry until the line arrives, so
/// without the fetch the loop stalls once the buffer is full of misses.
constexpr int kRenderAhead = 16;

// The buffers are per logical id while the state is in slots: the vertex copy runs over slots
// (rows read in order, each written to its id's place), the triangles in fixed blocks of ids,
// each block's live triangles counted first so that every block writes its own range (the same
// buffer on any thread count).
void FastSimulator::render(RenderBuffers& out, bool triangles) {
  if (!normals_valid_) {  // the same normals the next step would compute first
    compute_normals();
    normals_valid_ = true;
  }
  const Vertices& V = topo_.V;
  // Every id is one slot's, so the loop writes every entry (a free id's as zeros): the buffers
  // are resized, not cleared first (a serial fill of both, every frame, that the loop rewrites).
  out.positions.resize(3 * std::size_t(V.size()));
  out.normals.resize(3 * std::size_t(V.size()));
  par_.run(V.size(), kPassGrain, [&](int b, int e) {
    for (int v = b; v < e; ++v) {
      if (v + kRenderAhead < e) {
        const std::size_t ahead = std::size_t(V.lid[v + kRenderAhead]);
        __builtin_prefetch(&out.positions[3 * ahead], 1), __builtin_prefetch(&out.normals[3 * ahead], 1);
      }
      const bool live = V.mass(v) > 0;
      const std::size_t id = std::size_t(V.lid[v]);
      const Float4 p = live ? V.xm[v] : Float4{}, nv = live ? V.nr[v] : Float4{};
      float* x = &out.positions[3 * id];
      float* n = &out.normals[3 * id];
      x[0] = p.x, x[1] = p.y, x[2] = p.z;
      n[0] = nv.x, n[1] = nv.y, n[2] = nv.z;
    }
  });
  if (triangles) render_triangles(out.triangles);
}

void FastSimulator::render_triangles(std::vector<std::uint32_t>& out) {
  constexpr int kAhead = 16;  ///< ids ahead whose triangle record is prefetched (a random slot)
  const Triangles& T = topo_.T;
  const int n = T.size(), blocks = Parallel::blocks_of(n, kReduceBlock);
  // Fixed blocks of ids, each block's triangles at its offset: the buffer does not depend on
  // threads. A block's live triangles are its ids less its free ones (the free list holds
  // exactly the dead triangles' ids, Topology::check), counted from the free list rather than
  // from every id's slot read at random.
  std::vector<std::size_t>& start = render_scratch_;
  start.assign(std::size_t(blocks) + 1, 0);
  for (int id : T.free_ids) ++start[std::size_t(id / kReduceBlock) + 1];
  for (int b = 0; b < blocks; ++b)
    start[b + 1] = start[b] + std::size_t(std::min(n, (b + 1) * kReduceBlock) - b * kReduceBlock) - start[b + 1];
  out.resize(3 * start[blocks]);
  par_.run_blocks(n, kReduceBlock, [&](int b, int begin, int end) {
    std::uint32_t* to = out.data() + 3 * start[b];
    for (int id = begin; id < end; ++id) {
      if (id + kAhead < end) __builtin_prefetch(&T[T.phys[id + kAhead]]);
      const Face& f = T[T.phys[id]];
      if (f.e[0] < 0) continue;  // dead: kNoFace, which has no sides (a live face has all three)
      for (int c : f.v) *to++ = std::uint32_t(topo_.V.lid[c]);
    }
  });
}

}  // namespace crumple::fast

// The approximate implicit step with the axial Jacobian (MODEL.md §3): each spring's block of
// the implicit velocity step is W_e = h^2 kappa_e u u^T + h c_e I [Eq 5, D17] instead of the
// paper's (h^2 kappa_e + h c_e) I, so a vertex's row is a 3 x 3 system. Same structure as the
// isotropic gather and sweep (kernels.cpp): per vertex over its spring list in list order, no
// scatter, one summation order on any thread count. The blocks are recomputed from the packed
// positions where they are needed rather than stored per edge: a neighbour's position row is
// one load, a stored block six floats per spring.
#include <cmath>

#include "fast/kernels.h"

namespace crumple::fast {

namespace {
/// W_e of the spring between rows p (this vertex) and o (its neighbour), as a d d^T + iso I with
/// d = x_p - x_o (u u^T = d d^T / |d|^2; a spring of zero length keeps only its viscosity).
struct SpringBlock {
  float a, iso, dx, dy, dz;
};
inline SpringBlock spring_block(const Float4& p, const Float4& o, const StepConstants& c) {
  const float dx = p.x - o.x, dy = p.y - o.y, dz = p.z - o.z;
  const float l2 = dx * dx + dy * dy + dz * dz, msum = p.w + o.w;
  return {l2 > 0 ? c.axial * msum / l2 : 0.0f, c.viscous * msum, dx, dy, dz};
}
struct Vec {
  float x = 0, y = 0, z = 0;
};
/// sum += W (x, y, z).
inline void add_times(const SpringBlock& W, float x, float y, float z, Vec& sum) {
  const float s = W.a * (W.dx * x + W.dy * y + W.dz * z);
  sum.x += s * W.dx + W.iso * x;
  sum.y += s * W.dy + W.iso * y;
  sum.z += s * W.dz + W.iso * z;
}
inline void add_block(const SpringBlock& W, Block3& S) {
  S.xx += W.a * W.dx * W.dx + W.iso, S.yy += W.a * W.dy * W.dy + W.iso, S.zz += W.a * W.dz * W.dz + W.iso;
  S.xy += W.a * W.dx * W.dy, S.xz += W.a * W.dx * W.dz, S.yz += W.a * W.dy * W.dz;
}
/// Solves (d I + s S) x = r, symmetric positive definite for d > 0 and s >= 0, by LDL^T (no
/// pivoting needed: the matrix is definite; backward stable, which Cramer's rule is not when
/// a stiff spring makes the row ill-conditioned).
inline Vec solve_row(float d, float s, const Block3& S, const Vec& r) {
  const float a11 = d + s * S.xx, a22 = d + s * S.yy, a33 = d + s * S.zz;
  const float a21 = s * S.xy, a31 = s * S.xz, a32 = s * S.yz;
  const float d1 = a11, l21 = a21 / d1, l31 = a31 / d1;
  const float d2 = a22 - l21 * a21, l32 = (a32 - l31 * a21) / d2;
  const float d3 = a33 - l31 * a31 - l32 * l32 * d2;
  const float y1 = r.x, y2 = r.y - l21 * y1, y3 = r.z - l31 * y1 - l32 * y2;
  Vec x;
  x.z = y3 / d3;
  x.y = y2 / d2 - l32 * x.z;
  x.x = y1 / d1 - l21 * x.y - l31 * x.z;
  return x;
}
}  // namespace

void axial_blocks(const Topology& m, const VertexForces& f, const StepConstants& c, Block3* wsum, Float4* g,
                  int begin, int end) {
  const Vertices& V = m.V;
  for (int v = begin; v < end; ++v) {
    const Float4 self = V.xm[v], vel = V.vm[v];
    const float mass = self.w;
    const std::int32_t* nbrs = &V.nbrs[V.spring_list[v].at];
    Block3 S;
    Vec j;  // sum of W_e (v_o - v_v)
    for (int k = 0, n = V.spring_list[v].count; k < n; ++k) {
      const int o = nbrs[k];
      const SpringBlock W = spring_block(self, V.xm[o], c);
      add_block(W, S);
      add_times(W, V.vm[o].x - vel.x, V.vm[o].y - vel.y, V.vm[o].z - vel.z, j);
    }
    wsum[v] = S;
    const float d = mass > 0 ? mass : 1.0f;  // a dead slot: an identity row
    if (c.bounded) {
      // Bounded predictor (DECISIONS.md D1): the row with twice its off-diagonal blocks.
      const Vec r{c.h * f.fx[v] + j.x, c.h * f.fy[v] + j.y, c.h * (f.fz[v] + mass * c.gravity) + j.z};
      const Vec dv = solve_row(d, 2.0f, S, r);
      g[v] = Float4{vel.x + dv.x, vel.y + dv.y, vel.z - c.h * c.gravity + dv.z, mass};
    } else {
      const float inv = c.h / d;
      g[v] = Float4{vel.x + f.fx[v] * inv, vel.y + f.fy[v] * inv, vel.z + f.fz[v] * inv, mass};
    }
  }
}

void axial_sweep(const Topology& m, const VertexForces& f, const Block3* wsum, const StepConstants& c,
                 const Float4* g, Float4* g_next, int begin, int end) {
  const Vertices& V = m.V;
  for (int v = begin; v < end; ++v) {
    const Float4 self = V.xm[v], vel = V.vm[v];
    const float mass = self.w;
    const std::int32_t* nbrs = &V.nbrs[V.spring_list[v].at];
    Vec sum;  // sum of W_e g_o
    for (int k = 0, n = V.spring_list[v].count; k < n; ++k) {
      const int o = nbrs[k];
      add_times(spring_block(self, V.xm[o], c), g[o].x, g[o].y, g[o].z, sum);
    }
    const Vec r{mass * vel.x + c.h * f.fx[v] + sum.x, mass * vel.y + c.h * f.fy[v] + sum.y,
                mass * vel.z + c.h * f.fz[v] + sum.z};
    const Vec x = solve_row(mass > 0 ? mass : 1.0f, 1.0f, wsum[v], r);
    g_next[v] = Float4{x.x, x.y, x.z, mass};
  }
}

}  // namespace crumple::fast

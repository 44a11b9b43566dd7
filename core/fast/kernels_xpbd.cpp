// XPBD with small steps on the fast backend (MODEL.md §3; docs/DECISIONS.md D19): the kernels of
// FastSimulator::integrate_xpbd (fast_xpbd.cpp). The step works in displacements d = x* - x
// (in the guess rows' x, y, z, the inverse mass in w) rather than in positions: a substep moves a
// vertex by ~1e-4 of the sheet, and float positions would keep only ~3 digits of it, while the
// displacement keeps all of them and v = d / h comes out as precise as the reference's.
#include <cmath>

#include "fast/kernels.h"

namespace crumple::fast {

void viscous_guess(const Topology& m, const StepConstants& c, Float4* g, int begin, int end) {
  const Vertices& V = m.V;
  for (int v = begin; v < end; ++v) {
    const Float4 self = V.vm[v];
    const std::int32_t* nbrs = &V.nbrs[V.spring_list[v].at];
    float ks = 0, jx = 0, jy = 0, jz = 0;  // sum W_e and sum W_e (v_o - v), W_e = h c_e I
    for (int k = 0, n = V.spring_list[v].count; k < n; ++k) {
      const Float4 o = V.vm[nbrs[k]];
      const float w = c.implicit * (self.w + o.w);
      ks += w;
      jx += w * (o.x - self.x), jy += w * (o.y - self.y), jz += w * (o.z - self.z);
    }
    if (c.bounded) {  // the bounded predictor (D1) with no force but gravity's acceleration
      const float inv = 1.0f / (self.w + 2.0f * ks + (self.w > 0 ? 0.0f : 1.0f));
      g[v] = Float4{self.x + jx * inv, self.y + jy * inv, self.z - c.h * c.gravity + (c.h * self.w * c.gravity + jz) * inv,
                    self.w};
    } else {
      g[v] = self;  // the explicit predictor with no force: v
    }
  }
}

void take_velocity(const Float4* g, const float correction[3], Vertices& V, int begin, int end) {
  for (int v = begin; v < end; ++v) {
    const float mass = V.vm[v].w, on = mass > 0 ? 1.0f : 0.0f;
    V.vm[v] = Float4{on * (g[v].x - correction[0]), on * (g[v].y - correction[1]), on * (g[v].z - correction[2]), mass};
  }
}

void xpbd_predict(const Vertices& V, const VertexForces& f, const StepConstants& c, Float4* disp, int begin,
                  int end) {
  for (int v = begin; v < end; ++v) {
    const Float4 vel = V.vm[v];
    const float w = vel.w > 0 ? 1.0f / vel.w : 0.0f;
    disp[v] = Float4{c.h * (vel.x + c.h * f.fx[v] * w), c.h * (vel.y + c.h * f.fy[v] * w),
                     c.h * (vel.z + c.h * f.fz[v] * w), w};
  }
}

void xpbd_project(const Edges& E, const Vertices& V, const XpbdConstants& c, const std::int32_t* slots,
                  Float4* disp, int begin, int end) {
  for (int k = begin; k < end; ++k) {
    const int e = slots[k], a = E[e].a, b = E[e].b;
    const Float4 pa = V.xm[a], pb = V.xm[b];
    Float4& da = disp[a];
    Float4& db = disp[b];
    if (da.w + db.w == 0) continue;  // both ends pinned
    // The spring's vector at the predicted positions, in units of 1/unit (a power of two:
    // exact, D20): (x_a - x_b) + (d_a - d_b), the small displacements added last.
    const float dx = ((pa.x - pb.x) + (da.x - db.x)) * c.unit, dy = ((pa.y - pb.y) + (da.y - db.y)) * c.unit,
                dz = ((pa.z - pb.z) + (da.z - db.z)) * c.unit;
    const float lt = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!(lt > 0)) continue;
    // C = |x_a - x_b| - l0, alpha~ = 1 / (kappa_e h^2) [Eq 5], one iteration from lambda = 0.
    const float tilde = 1.0f / (c.kappa * (pa.w + pb.w) * c.h2);
    const float dlambda = -(lt - E[e].l0 * c.unit) / c.unit / (da.w + db.w + tilde);
    const float ux = dx / lt, uy = dy / lt, uz = dz / lt;
    da.x += da.w * dlambda * ux, da.y += da.w * dlambda * uy, da.z += da.w * dlambda * uz;
    db.x -= db.w * dlambda * ux, db.y -= db.w * dlambda * uy, db.z -= db.w * dlambda * uz;
  }
}

void displacement_to_velocity(float h, Float4* g, int begin, int end) {
  const float inv = 1.0f / h;
  for (int v = begin; v < end; ++v) g[v] = Float4{g[v].x * inv, g[v].y * inv, g[v].z * inv, g[v].w};
}

}  // namespace crumple::fast

#include "fast/kernels.h"

#include <cmath>

#include "model/random.h"

namespace crumple::fast {

void triangle_areas(Topology& m, int begin, int end) {
  const std::int32_t *__restrict v0 = m.T.v0.data(), *__restrict v1 = m.T.v1.data(), *__restrict v2 = m.T.v2.data();
  const float *__restrict x = m.V.x.data(), *__restrict y = m.V.y.data(), *__restrict z = m.V.z.data();
  const std::uint8_t* __restrict alive = m.T.alive.data();
  float *__restrict ax = m.T.ax.data(), *__restrict ay = m.T.ay.data(), *__restrict az = m.T.az.data();
  for (int t = begin; t < end; ++t) {
    const int a = v0[t], b = v1[t], c = v2[t];
    const float ux = x[b] - x[a], uy = y[b] - y[a], uz = z[b] - z[a];
    const float wx = x[c] - x[a], wy = y[c] - y[a], wz = z[c] - z[a];
    const float on = alive[t] ? 1.0f : 0.0f;
    ax[t] = on * (uy * wz - uz * wy);
    ay[t] = on * (uz * wx - ux * wz);
    az[t] = on * (ux * wy - uy * wx);
  }
}

void vertex_normals(Topology& m, int begin, int end) {
  const int stride = m.V.stride_t;
  const std::int32_t* __restrict tris = m.V.tris.data();
  const std::uint16_t* __restrict count = m.V.n_tris.data();
  const float *__restrict ax = m.T.ax.data(), *__restrict ay = m.T.ay.data(), *__restrict az = m.T.az.data();
  float *__restrict nx = m.V.nx.data(), *__restrict ny = m.V.ny.data(), *__restrict nz = m.V.nz.data();
  for (int v = begin; v < end; ++v) {
    float sx = 0, sy = 0, sz = 0;
    const std::int32_t* list = tris + std::size_t(v) * stride;
    for (int k = 0; k < count[v]; ++k) {
      const int t = list[k] >> 2;
      sx += ax[t];
      sy += ay[t];
      sz += az[t];
    }
    const float len = std::sqrt(sx * sx + sy * sy + sz * sz);
    const float inv = len > 0 ? 1.0f / len : 0.0f;
    nx[v] = sx * inv;
    ny[v] = sy * inv;
    nz[v] = sz * inv;
  }
}

void edge_forces(Topology& m, const StepConstants& c, int begin, int end) {
  const std::int32_t *__restrict A = m.E.a.data(), *__restrict B = m.E.b.data();
  const std::int32_t *__restrict WL = m.E.wl.data(), *__restrict WR = m.E.wr.data();
  const float *__restrict l0 = m.E.l0.data(), *__restrict msum = m.E.msum.data();
  const std::uint8_t* __restrict flags = m.E.flags.data();
  const float *__restrict x = m.V.x.data(), *__restrict y = m.V.y.data(), *__restrict z = m.V.z.data();
  const float *__restrict vx = m.V.vx.data(), *__restrict vy = m.V.vy.data(), *__restrict vz = m.V.vz.data();
  const float *__restrict nx = m.V.nx.data(), *__restrict ny = m.V.ny.data(), *__restrict nz = m.V.nz.data();
  float *__restrict fx = m.E.fx.data(), *__restrict fy = m.E.fy.data(), *__restrict fz = m.E.fz.data();
  float *__restrict kb = m.E.kb.data();
  float *__restrict bx = m.E.bx.data(), *__restrict by = m.E.by.data(), *__restrict bz = m.E.bz.data();
  const float quarter = c.balanced ? 0.25f : 0.0f;
  for (int e = begin; e < end; ++e) {
    const int a = A[e], b = B[e];
    const float dx = x[a] - x[b], dy = y[a] - y[b], dz = z[a] - z[b];
    const float lt = std::sqrt(dx * dx + dy * dy + dz * dz);
    const float inv = lt > 0 ? 1.0f / lt : 0.0f;
    // Hookean spring with kappa_e = kappa (m_a + m_b) [Eq 5], damping along the axis (§2).
    const float rel = ((vx[a] - vx[b]) * dx + (vy[a] - vy[b]) * dy + (vz[a] - vz[b]) * dz) * inv;
    const float s = (-c.kappa * (lt - l0[e]) - c.damping * rel) * msum[e] * inv;
    fx[e] = s * dx;
    fy[e] = s * dy;
    fz[e] = s * dz;
    // Bending [Eq 8-9] for mesh edges with two wings: k = s C_beta B, B = (1 - n_rl)|e|/2.
    const bool hinge = (flags[e] & kMesh) && WL[e] >= 0 && WR[e] >= 0;
    const int l = hinge ? WL[e] : a, r = hinge ? WR[e] : a;
    const float nrl = nx[r] * nx[l] + ny[r] * ny[l] + nz[r] * nz[l];
    const float Bmag = (1.0f - nrl) * lt * 0.5f;
    const float gx = (x[r] + nx[r]) - (x[l] + nx[l]), gy = (y[r] + ny[r]) - (y[l] + ny[l]),
                gz = (z[r] + nz[r]) - (z[l] + nz[l]);
    const float ox = x[r] - x[l], oy = y[r] - y[l], oz = z[r] - z[l];
    const float gap = std::sqrt(gx * gx + gy * gy + gz * gz) - std::sqrt(ox * ox + oy * oy + oz * oz);
    const float sign = gap > 0 ? 1.0f : (gap < 0 ? -1.0f : 0.0f);
    const float k = hinge ? sign * c.bend * msum[e] * Bmag : 0.0f;
    kb[e] = k;
    // Mean of f_i = -k n_i, f_j = -k n_j, f_r = k n_r, f_l = k n_l (removed in the balanced form).
    bx[e] = quarter * k * (nx[r] + nx[l] - nx[a] - nx[b]);
    by[e] = quarter * k * (ny[r] + ny[l] - ny[a] - ny[b]);
    bz[e] = quarter * k * (nz[r] + nz[l] - nz[a] - nz[b]);
  }
}

void gather_forces(Topology& m, const StepConstants& c, int begin, int end) {
  Vertices& V = m.V;
  const int se = V.stride_e, st = V.stride_t;
  const std::int32_t *__restrict A = m.E.a.data(), *__restrict B = m.E.b.data();
  const float *__restrict efx = m.E.fx.data(), *__restrict efy = m.E.fy.data(), *__restrict efz = m.E.fz.data();
  const float *__restrict kb = m.E.kb.data(), *__restrict msum = m.E.msum.data();
  const float *__restrict bx = m.E.bx.data(), *__restrict by = m.E.by.data(), *__restrict bz = m.E.bz.data();
  const std::int32_t* __restrict te[3] = {m.T.e0.data(), m.T.e1.data(), m.T.e2.data()};
  for (int v = begin; v < end; ++v) {
    float fx = 0, fy = 0, fz = 0, ks = 0, jx = 0, jy = 0, jz = 0, kn = 0, mx = 0, my = 0, mz = 0;
    const std::int32_t* springs = &V.springs[std::size_t(v) * se];
    for (int k = 0; k < V.n_springs[v]; ++k) {
      const int e = springs[k] >> 1;
      const bool is_b = springs[k] & 1;
      const float sg = is_b ? -1.0f : 1.0f;
      const int o = is_b ? A[e] : B[e];
      const float kap = c.kappa * msum[e];
      fx += sg * efx[e];
      fy += sg * efy[e];
      fz += sg * efz[e];
      ks += kap;
      jx += kap * (V.vx[o] - V.vx[v]);
      jy += kap * (V.vy[o] - V.vy[v]);
      jz += kap * (V.vz[o] - V.vz[v]);
      kn -= kb[e];  // hinge role: f = -k n_v - mean
      mx += bx[e];
      my += by[e];
      mz += bz[e];
    }
    const std::int32_t* tris = &V.tris[std::size_t(v) * st];
    for (int k = 0; k < V.n_tris[v]; ++k) {
      const int t = tris[k] >> 2, corner = tris[k] & 3;
      const int e = te[corner == 2 ? 0 : corner + 1][t];  // the edge opposite v: v is its wing
      kn += kb[e];  // wing role: f = +k n_v - mean
      mx += bx[e];
      my += by[e];
      mz += bz[e];
    }
    const float mass = V.m[v];
    fx += kn * V.nx[v] - mx;
    fy += kn * V.ny[v] - my;
    fz += kn * V.nz[v] - mz - mass * c.gravity;
    V.fx[v] = fx;
    V.fy[v] = fy;
    V.fz[v] = fz;
    V.ksum[v] = ks;
    const float dead = mass > 0 ? 0.0f : 1.0f;
    if (c.bounded) {
      // Bounded predictor (DECISIONS.md D1): the row with its Gershgorin diagonal, g exact.
      const float inv = 1.0f / (mass + 2.0f * c.h2 * ks + dead);
      V.gx[v] = V.vx[v] + (c.h * fx + c.h2 * jx) * inv;
      V.gy[v] = V.vy[v] + (c.h * fy + c.h2 * jy) * inv;
      V.gz[v] = V.vz[v] - c.h * c.gravity + (c.h * (fz + mass * c.gravity) + c.h2 * jz) * inv;
    } else {
      const float inv = 1.0f / (mass + dead);
      V.gx[v] = V.vx[v] + c.h * fx * inv;
      V.gy[v] = V.vy[v] + c.h * fy * inv;
      V.gz[v] = V.vz[v] + c.h * fz * inv;
    }
  }
}

void jacobi_sweep(Topology& m, const StepConstants& c, int begin, int end) {
  Vertices& V = m.V;
  const int se = V.stride_e;
  const std::int32_t *__restrict A = m.E.a.data(), *__restrict B = m.E.b.data();
  const float* __restrict msum = m.E.msum.data();
  for (int v = begin; v < end; ++v) {
    float sx = 0, sy = 0, sz = 0;
    const std::int32_t* springs = &V.springs[std::size_t(v) * se];
    for (int k = 0; k < V.n_springs[v]; ++k) {
      const int e = springs[k] >> 1;
      const int o = (springs[k] & 1) ? A[e] : B[e];
      const float kap = c.kappa * msum[e];
      sx += kap * V.gx[o];
      sy += kap * V.gy[o];
      sz += kap * V.gz[o];
    }
    const float mass = V.m[v];
    const float inv = 1.0f / (mass + c.h2 * V.ksum[v] + (mass > 0 ? 0.0f : 1.0f));
    V.hx[v] = (mass * V.vx[v] + c.h * V.fx[v] + c.h2 * sx) * inv;
    V.hy[v] = (mass * V.vy[v] + c.h * V.fy[v] + c.h2 * sy) * inv;
    V.hz[v] = (mass * V.vz[v] + c.h * V.fz[v] + c.h2 * sz) * inv;
  }
}

void explicit_velocity(Topology& m, const StepConstants& c, int begin, int end) {
  Vertices& V = m.V;
  for (int v = begin; v < end; ++v) {
    const float inv = V.m[v] > 0 ? c.h / V.m[v] : 0.0f;
    V.gx[v] = V.vx[v] + V.fx[v] * inv;
    V.gy[v] = V.vy[v] + V.fy[v] * inv;
    V.gz[v] = V.vz[v] + V.fz[v] * inv;
  }
}

void momentum_drift(const Topology& m, const StepConstants& c, int begin, int end, double out[3]) {
  const Vertices& V = m.V;
  double sx = 0, sy = 0, sz = 0;
  for (int v = begin; v < end; ++v) {
    sx += double(V.m[v]) * (double(V.gx[v]) - V.vx[v]) - double(c.h) * V.fx[v];
    sy += double(V.m[v]) * (double(V.gy[v]) - V.vy[v]) - double(c.h) * V.fy[v];
    sz += double(V.m[v]) * (double(V.gz[v]) - V.vz[v]) - double(c.h) * V.fz[v];
  }
  out[0] = sx;
  out[1] = sy;
  out[2] = sz;
}

void advance(Topology& m, const StepConstants& c, const float corr[3], const float center[3], float radius,
             int begin, int end) {
  Vertices& V = m.V;
  float *__restrict x = V.x.data(), *__restrict y = V.y.data(), *__restrict z = V.z.data();
  float *__restrict vx = V.vx.data(), *__restrict vy = V.vy.data(), *__restrict vz = V.vz.data();
  const float *__restrict gx = V.gx.data(), *__restrict gy = V.gy.data(), *__restrict gz = V.gz.data();
  const float* __restrict mass = V.m.data();
  const bool sphere = radius > 0;
  for (int v = begin; v < end; ++v) {
    const float on = mass[v] > 0 ? 1.0f : 0.0f;
    float ux = on * (gx[v] - corr[0]), uy = on * (gy[v] - corr[1]), uz = on * (gz[v] - corr[2]);
    float px = x[v] + c.h * ux, py = y[v] + c.h * uy, pz = z[v] + c.h * uz;
    if (sphere) {
      // The manipulation sphere (§8): onto the sphere, outward velocity removed.
      const float dx = px - center[0], dy = py - center[1], dz = pz - center[2];
      const float r = std::sqrt(dx * dx + dy * dy + dz * dz);
      const bool out = r > radius;
      const float inv = r > 0 ? 1.0f / r : 0.0f;
      const float nx = dx * inv, ny = dy * inv, nz = dz * inv;
      px = out ? center[0] + radius * nx : px;
      py = out ? center[1] + radius * ny : py;
      pz = out ? center[2] + radius * nz : pz;
      const float radial = ux * nx + uy * ny + uz * nz;
      const float cut = (out && radial > 0) ? radial : 0.0f;
      ux -= cut * nx;
      uy -= cut * ny;
      uz -= cut * nz;
    }
    x[v] = px;
    y[v] = py;
    z[v] = pz;
    vx[v] = ux;
    vy[v] = uy;
    vz[v] = uz;
  }
}

void adapt_test(const Topology& m, const AdaptConstants& c, std::uint8_t* out, int begin, int end) {
  const Vertices& V = m.V;
  const Edges& E = m.E;
  for (int e = begin; e < end; ++e) {
    std::uint8_t decision = 0;
    const std::uint8_t f = E.flags[e];
    const int a = E.a[e], b = E.b[e];
    if (c.fracture && f == (kAlive | kMesh | kBreakable) && E.l0[e] >= c.floor_length) {
      const float dx = V.x[a] - V.x[b], dy = V.y[a] - V.y[b], dz = V.z[a] - V.z[b];
      const float lt = std::sqrt(dx * dx + dy * dy + dz * dz);
      if (lt < E.l0[e]) {
        // [Eq 6] P = 1/4 c (1 - phi n_ij)(1 + phi n_rl), c = 1 - lt/l0; per step (MODEL.md §4).
        const float comp = 1.0f - lt / E.l0[e];
        const float nij = V.nx[a] * V.nx[b] + V.ny[a] * V.ny[b] + V.nz[a] * V.nz[b];
        const int l = E.wl[e], r = E.wr[e];
        const float nrl = (l >= 0 && r >= 0) ? V.nx[r] * V.nx[l] + V.ny[r] * V.ny[l] + V.nz[r] * V.nz[l] : 1.0f;
        float P = 0.25f * comp * (1 - c.phi * nij) * (1 + c.phi * nrl);
        P = P < 0 ? 0 : (P > 1 ? 1 : P);
        const float Pstep = c.step_exponent == 1.0f ? P : 1.0f - std::pow(1.0f - P, c.step_exponent);
        const float u = float(uniform(c.seed, c.step, std::uint32_t(e), Draw::Fracture));  // exact
        decision = (Pstep > 0 && u < Pstep) ? 1 : 0;
      }
    }
    if (c.restoration && (f & kAlive) && !(f & kMesh) && E.record[e] >= 0) {
      const SplitRecord& s = m.records[E.record[e]];
      const int l = s.k[2], r = s.k[3];
      const float nrl = (l >= 0 && r >= 0) ? V.nx[r] * V.nx[l] + V.ny[r] * V.ny[l] + V.nz[r] * V.nz[l] : 1.0f;
      decision = (1.0f - nrl) * 0.5f >= c.epsilon ? 2 : 0;  // [Eq 10]
    }
    out[e] = decision;
  }
}

}  // namespace crumple::fast

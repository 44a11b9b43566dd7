#include "bullet_sheet.h"

#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <limits>

namespace crumple::bench {

struct BulletSheet::Parts {
  btSoftBodyRigidBodyCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btSoftRigidDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
};

BulletSheet::BulletSheet(int n, int piterations) : p_(std::make_unique<Parts>()) {
  const btVector3 gravity(0, 0, btScalar(-9.81));
  p_->world.setGravity(gravity);
  btSoftBodyWorldInfo& info = p_->world.getWorldInfo();  // broadphase/dispatcher set by the world
  info.m_gravity = gravity;
  info.m_sparsesdf.Initialize();
  // Nodes iy * n + ix at (ix, iy) / (n - 1); links along x and y, and with gendiags the diagonal
  // of each quad's triangulation (alternating per quad, like make_grid's union jack).
  body_ = btSoftBodyHelpers::CreatePatch(info, btVector3(0, 0, 0), btVector3(1, 0, 0),
                                         btVector3(0, 1, 0), btVector3(1, 1, 0), n, n,
                                         /*fixeds=*/0, /*gendiags=*/true);
  body_->m_cfg.piterations = piterations;
  body_->setTotalMass(1);    // scales the inverse masses: the sheet weighs 1, like crumple's
  body_->setMass(0, 0);      // corner (0,0) pinned
  body_->setMass(n - 1, 0);  // corner (1,0) pinned
  p_->world.addSoftBody(body_);
}

BulletSheet::~BulletSheet() {
  p_->world.removeSoftBody(body_);
  delete body_;
}

void BulletSheet::frame() { p_->world.stepSimulation(btScalar(1.0 / 60.0), 1, btScalar(1.0 / 60.0)); }

double BulletSheet::max_abs_coordinate() const {
  double m = 0;
  for (int i = 0; i < body_->m_nodes.size(); ++i) {
    const btVector3& x = body_->m_nodes[i].m_x;
    for (int k = 0; k < 3; ++k) {
      const double c = x[k];
      if (!std::isfinite(c)) return std::numeric_limits<double>::infinity();
      m = std::fmax(m, std::fabs(c));
    }
  }
  return m;
}

int BulletSheet::nodes() const { return body_->m_nodes.size(); }
int BulletSheet::links() const { return body_->m_links.size(); }
int BulletSheet::faces() const { return body_->m_faces.size(); }
int BulletSheet::piterations() const { return body_->m_cfg.piterations; }

}  // namespace crumple::bench

// The embedding configuration on the paper's fixed step: what embedding_params() was before the
// default became adaptive (docs/DECISIONS.md D28). For the API tests that count steps per frame
// or read the approximate implicit method's row, which the default's per-frame substep choice
// and symplectic Euler would change.
#pragma once

#include "model/params.h"

namespace crumple::test {

inline Params fixed_step_params() {
  Params p = paper_params();
  p.scene = Scene::Free;
  p.squeeze = 1.0;
  return p;
}

}  // namespace crumple::test

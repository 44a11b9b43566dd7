// Ways into a crumple::Sheet that only the library's own tools take (not installed, not API):
// the `crumple` command hands over the mesh it read from an OBJ file in double precision (the
// public SheetDesc takes float arrays, which would round the reference backend's input), and
// the benchmarks wrap a simulator restored from their prepared state. Everything after that,
// the frame loop included, goes through the public Sheet.
#pragma once

#include <memory>

#include "crumple/crumple.h"
#include "mesh/input_mesh.h"
#include "sim/simulator.h"

namespace crumple {

struct SheetAccess {
  /// Sheet::create on an already-read mesh (desc's grid and arrays are ignored): the same
  /// checks and errors, std::bad_alloc passed on.
  static Sheet create(const InputMesh& mesh, const SheetDesc& desc);
  /// A sheet around `sim`, whose parameters are `params` and whose scene has size `size`
  /// (make_scene(mesh, params).size, for the instability check); its frame count starts at 0.
  static Sheet adopt(std::unique_ptr<Simulator> sim, const Params& params, double size);
};

}  // namespace crumple

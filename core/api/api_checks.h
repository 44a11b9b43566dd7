// The embedding API's checks of what a caller passes (api/sheet.cpp): each returns an empty
// string or one line naming the first problem, in the command's wording where the command has
// the same check.
#pragma once

#include <string>

#include "crumple/crumple.h"
#include "mesh/input_mesh.h"

namespace crumple::api {

/// The sheet's input mesh from the desc (grid or caller's arrays); throws InputError.
InputMesh input_mesh(const SheetDesc& desc);
/// Parameters, backend and threads of a desc.
std::string check_desc(const SheetDesc& desc);
/// Every manipulator against a sheet of `vertex_ids` vertex ids.
std::string check_manipulators(const Manipulators& m, int vertex_ids);

}  // namespace crumple::api

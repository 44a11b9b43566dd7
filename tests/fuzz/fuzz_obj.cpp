// Fuzz target: OBJ text -> parse_obj (which validates) -> validate_mesh. Whatever the bytes,
// the only way out is a mesh or an InputError; any other exception, a crash, a sanitizer report,
// a hang or an outsized allocation is a finding. Built with clang -fsanitize=fuzzer by
// scripts/fuzz.sh, and with replay_main.cpp by the normal build (ctest fuzz_obj_replay).
#include <cstddef>
#include <cstdint>
#include <string>

#include "mesh/input_mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const crumple::InputMesh mesh =
        crumple::parse_obj(std::string(reinterpret_cast<const char*>(data), size), "fuzz.obj");
    crumple::validate_mesh(mesh, "fuzz.obj");
  } catch (const crumple::InputError&) {
  }
  return 0;
}

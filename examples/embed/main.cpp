// Embeds crumple in a frame loop: a 64 x 64 sheet lies on a table, a ball rises under it and
// a hand (a grab spring) drags one corner in and up, for 300 frames at 60 Hz (or as many as the
// first argument says). Prints the frame time every 50 frames and the final counts.
#include <crumple/crumple.h>

#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::atoi(argv[1]) : 300;
  if (frames < 1 || frames > 100000) {
    std::fprintf(stderr, "embed: error: the frame count must be a whole number in [1, 100000]\n");
    return 2;
  }
  // A 64 x 64 grid, fast backend, run in this thread's oneTBB arena, the default configuration
  // (its substeps chosen each frame: docs/DECISIONS.md D28).
  crumple::SheetDesc desc;
  desc.params.gravity = 2.0;  // m/s^2: what the default (soft) springs hang from
  std::string error;
  std::optional<crumple::Sheet> made = crumple::Sheet::try_create(desc, error);
  if (!made) {
    std::fprintf(stderr, "embed: error: %s\n", error.c_str());
    return 1;
  }
  crumple::Sheet& sheet = *made;
  crumple::Manipulators& hands = sheet.manipulators();
  hands.planes.push_back({{0, 0, -0.05}, {0, 0, 1}});  // the table, just under the sheet
  hands.spheres.push_back({{0.5, 0.5, -0.3}, 0.2});  // the ball, under the table at first
  const int corner = sheet.nearest_vertex({1, 1, 0});
  hands.grabs.push_back({corner, {1, 1, 0}, 5.0});  // k = 5 N/m

  std::printf("crumple %s, %s backend, %d vertices, %d triangles\n", crumple::version(), sheet.backend(),
              sheet.live_vertices(), sheet.live_triangles());
  double total_ms = 0;
  long splits = 0, restores = 0, uploads = 0;
  for (int frame = 1; frame <= frames; ++frame) {
    hands.spheres[0].center[2] += 0.001;  // the ball rises through the table, 0.3 over the run
    hands.grabs[0].target = {1.0 - 0.0015 * frame, 1.0 - 0.0015 * frame, 0.0003 * frame};
    crumple::FrameEvents ev;
    if (std::string e = sheet.try_step(1.0 / 60, &ev); !e.empty()) {
      std::fprintf(stderr, "embed: error: %s\n", e.c_str());
      return 1;
    }
    total_ms += ev.ms;
    splits += ev.splits;
    restores += ev.restores;
    uploads += ev.topology_changed;  // a renderer re-uploads the triangles only then
    if (frame % 50 == 0)
      std::printf("frame %3d: %.3f ms, %d vertices, %d triangles, generation %llu\n", frame, ev.ms,
                  sheet.live_vertices(), sheet.live_triangles(),
                  static_cast<unsigned long long>(sheet.topology_generation()));
  }
  const float* c = &sheet.positions()[3 * corner];
  std::printf("%d frames: %.3f ms/frame, %ld splits, %ld restores, %ld index uploads, %d vertices, "
              "%d triangles, corner at (%.3f, %.3f, %.3f)\n",
              frames, total_ms / frames, splits, restores, uploads, sheet.live_vertices(), sheet.live_triangles(), c[0],
              c[1], c[2]);
  return 0;
}

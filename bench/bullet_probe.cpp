// crumple_bullet_probe: which Bullet piterations keep the hanging sheet of bench_bullet.cpp
// bounded? For each N and piterations = 1, 2, ... steps F frames and reports the largest
// |coordinate| (bounded: <= 1e3 and finite at every checked frame).
// Usage: crumple_bullet_probe [frames=300] [min_piterations=1] [max_piterations=6] [N ...]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "bullet_sheet.h"

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::atoi(argv[1]) : 300;
  const int min_pit = argc > 2 ? std::atoi(argv[2]) : 1;
  const int max_pit = argc > 3 ? std::atoi(argv[3]) : 6;
  std::vector<int> sizes;
  for (int i = 4; i < argc; ++i) sizes.push_back(std::atoi(argv[i]));
  if (sizes.empty()) sizes = {32, 64, 128, 256};
  for (int n : sizes) {
    for (int pit = min_pit; pit <= max_pit; ++pit) {
      crumple::bench::BulletSheet sheet(n, pit);
      double worst = 0;
      int first_bad = -1;
      const auto t0 = std::chrono::steady_clock::now();
      for (int f = 1; f <= frames; ++f) {
        sheet.frame();
        const double m = sheet.max_abs_coordinate();
        worst = m > worst ? m : worst;
        if (!sheet.bounded()) {
          first_bad = f;
          break;
        }
      }
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      std::printf("N=%4d piterations=%d nodes=%d links=%d faces=%d: %s max|x|=%.4g  %.3f ms/frame\n",
                  n, pit, sheet.nodes(), sheet.links(), sheet.faces(),
                  first_bad < 0 ? "bounded" : "UNBOUNDED", worst,
                  ms / (first_bad < 0 ? frames : first_bad));
      if (first_bad >= 0) std::printf("         left the bound at frame %d\n", first_bad);
      std::fflush(stdout);
      if (first_bad < 0) break;  // the smallest bounded piterations for this N
    }
  }
}

// The vertex budget (Params::max_vertices, --max-vertices; docs/DECISIONS.md D22).
#include <algorithm>
#include <cmath>

#include "support/fixtures.h"

namespace crumple::test {
namespace {

class Budget : public EachBackend {};

// churn_params (a squeezed free sheet that grows fast and churns) with a vertex budget.
Params churning(int max_vertices) {
  Params p = churn_params();
  p.max_vertices = max_vertices;
  return p;
}

// Catches: a budget that is not applied (the unbudgeted control run passes 700 vertices), applied
// after the splits (one step's splits overshoot it), or that stops the sheet (no split once
// reached: restores free room, so splits must go on), and a truncation that breaks mass or
// momentum conservation or the topology.
TEST_P(Budget, CrumpleStaysWithinTheBudgetAndConserves) {
  const int budget = 700;
  auto control = make(make_grid(24), churning(0));
  int control_peak = 0;
  for (int step = 0; step < 200; ++step) {
    control->step();
    control_peak = std::max(control_peak, control->totals().vertices);
  }
  ASSERT_GT(control_peak, budget + 100);  // without it the sheet outgrows the budget

  auto sim = make(make_grid(24), churning(budget));
  const Totals t0 = sim->totals();
  int peak = 0;
  long splits_at_budget = 0;
  double worst_mass = 0, worst_p = 0;
  for (int step = 0; step < 400; ++step) {
    const bool full = sim->totals().vertices >= budget - 10;
    const StepEvents ev = sim->step();
    if (full) splits_at_budget += ev.splits;
    const Totals t = sim->totals();
    ASSERT_LE(t.vertices, budget) << "step " << step;
    peak = std::max(peak, t.vertices);
    worst_mass = std::max(worst_mass, std::abs(t.mass - t0.mass));
    for (int d = 0; d < 3; ++d) worst_p = std::max(worst_p, std::abs(t.momentum[d] - t0.momentum[d]));
  }
  EXPECT_EQ(sim->check_topology(), "");
  EXPECT_GE(peak, budget - 10);
  EXPECT_GT(splits_at_budget, 10);
  const double eps = GetParam() == "reference" ? 1e-12 : 1e-5;  // as in Runs.MassAndMomentum...
  EXPECT_LT(worst_mass, eps);
  EXPECT_LT(worst_p, eps);
}

CRUMPLE_FOR_EACH_BACKEND(Budget);

}  // namespace
}  // namespace crumple::test

// planCalibration (calibration/plan_pipeline.hpp): the one plan pipeline robocal plan and
// robocald share fills a plan's summary with its predicted errors and its forecast.
#include <catch2/catch.hpp>

#include "fixtures.hpp"

#include <robocal/calibration/plan_pipeline.hpp>

using namespace robocal;
using namespace robocal::test;

TEST_CASE(
    "the plan pipeline: a grid plan with its predicted errors and forecast, a check without") {
  CellConfig cell = gridCell();
  cell.connections = {{0, 0}, {1, 1}, {2, 2}};  // three connections: rank 36, quick
  const PlannedCell grid = planCalibration(nominal(), cell, {PlanKind::kGrid, {}});
  const PlanSummary& s = grid.plan.summary;
  CHECK(s.rank == 36);
  CHECK(grid.work_poses > 0);
  CHECK(grid.whole_poses > 0);
  CHECK(s.predicted_work_volume_error_mm > 0);
  // What the plan does not cover costs more than where it measures.
  CHECK(s.predicted_whole_range_error_mm > s.predicted_work_volume_error_mm);
  CHECK(s.noise_sigma_mm == DesignOptions{}.noise_sigma_mm);
  CHECK(grid.forecast);
  CHECK(s.predicted_deflection_mm > 0);
  CHECK(s.predicted_change_mm > 0);

  // A noisier bar predicts a larger error from the same plan.
  PlanRequest noisy{PlanKind::kGrid, {}};
  noisy.design.noise_sigma_mm = 2 * DesignOptions{}.noise_sigma_mm;
  CHECK(planCalibration(nominal(), cell, noisy).plan.summary.predicted_work_volume_error_mm ==
        Approx(2 * s.predicted_work_volume_error_mm).epsilon(1e-6));

  // Planned for a fit that also identifies the twist: the same points, predicted with it.
  PlanRequest twisted{PlanKind::kGrid, {}};
  twisted.design.compliance = true;
  const PlanSummary& t = planCalibration(nominal(), cell, twisted).plan.summary;
  CHECK(t.points == s.points);
  CHECK(t.predicted_work_volume_error_mm > s.predicted_work_volume_error_mm);
  CHECK(t.predicted_whole_range_error_mm > s.predicted_whole_range_error_mm);

  // A check is judged, not fitted: no predicted error; its forecast only with a nominal model.
  const PlannedCell check = planCalibration(nominal(), gridCell(), {PlanKind::kCheck, {}});
  CHECK(check.plan.purpose == PlanPurpose::kCheck);
  CHECK(check.plan.summary.predicted_work_volume_error_mm < 0);
  CHECK(check.forecast);
  Model calibrated = nominal();
  calibrated.provenance = ModelProvenance{};
  CHECK_FALSE(planCalibration(calibrated, gridCell(), {PlanKind::kCheck, {}}).forecast);
}

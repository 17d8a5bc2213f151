// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/calibration_eval.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>

namespace bayon {
namespace {

CalibrationEntry BrownBeyer(double c, double dc, double k1) {
  CalibrationEntry entry;
  entry.camera =
      Camera::Create(CameraModelId::kBrownBeyer, 1750, 1800, 1200, 0.02);
  entry.camera.camera_id = 1;
  entry.camera.params[brown::kC] = c;
  entry.camera.params[brown::kDc] = dc;
  entry.camera.params[brown::kK1] = k1;
  return entry;
}

const ParameterError& Find(const CalibrationEvaluation& e,
                           const std::string& name) {
  for (const ParameterError& p : e.parameters) {
    if (p.name == name) return p;
  }
  throw std::runtime_error("no parameter " + name);
}

TEST(CalibrationEval, BrownBeyerComparesTheEffectiveCameraConstant) {
  const CalibrationEntry truth = BrownBeyer(35.01, 0.0, 1e-4);
  CalibrationEntry estimate = BrownBeyer(35.0, 0.012, 1.2e-4);
  estimate.std_devs.assign(estimate.camera.params.size(), 0.0);
  estimate.std_devs[brown::kDc] = 0.001;
  estimate.std_devs[brown::kK1] = 1e-5;
  const CalibrationEvaluation e = EvaluateCalibration(estimate, truth);
  ASSERT_EQ(e.parameters.size(), 10u);
  EXPECT_NEAR(Find(e, "c+dc").error, 0.002, 1e-12);
  EXPECT_NEAR(Find(e, "c+dc").ratio, 2.0, 1e-9);
  EXPECT_NEAR(Find(e, "K1").ratio, 2.0, 1e-6);
  EXPECT_EQ(Find(e, "B2").sigma, 0);
  EXPECT_NEAR(e.max_abs_ratio, 2.0, 1e-6);
  EXPECT_NE(CalibrationTable(e).find("c+dc"), std::string::npos);
}

TEST(CalibrationEval, CovarianceGivesTheSigmaOfTheSum) {
  const CalibrationEntry truth = BrownBeyer(35.0, 0.0, 0.0);
  CalibrationEntry estimate = BrownBeyer(35.0, 0.003, 0.0);
  const size_t n = estimate.camera.params.size();
  estimate.covariance.assign(n * n, 0.0);
  estimate.covariance[brown::kC * n + brown::kC] = 4e-6;
  estimate.covariance[brown::kDc * n + brown::kDc] = 4e-6;
  estimate.covariance[brown::kC * n + brown::kDc] = -3e-6;
  estimate.covariance[brown::kDc * n + brown::kC] = -3e-6;
  const CalibrationEvaluation e = EvaluateCalibration(estimate, truth);
  // var(c + dc) = 4e-6 + 4e-6 - 2 * 3e-6 = 2e-6.
  EXPECT_NEAR(Find(e, "c+dc").sigma, std::sqrt(2e-6), 1e-12);
}

TEST(CalibrationEval, DifferentModelsCompareFocalAndPrincipalPoint) {
  const CalibrationEntry truth = BrownBeyer(35.0, 0.0, 0.0);
  CalibrationEntry estimate;
  estimate.camera =
      Camera::Create(CameraModelId::kSimpleRadial, 1760, 1800, 1200);
  estimate.camera.camera_id = 1;
  const CalibrationEvaluation e = EvaluateCalibration(estimate, truth);
  EXPECT_NEAR(Find(e, "focal_px").error, 10.0, 1e-9);
  EXPECT_NEAR(Find(e, "cx_px").error, 0.0, 1e-9);

  // Several cameras pair by id; a missing one is refused.
  CalibrationEntry other = estimate;
  other.camera.camera_id = 2;
  EXPECT_THROW(EvaluateCalibrations({estimate, other}, {truth, truth}),
               InputError);
}

}  // namespace
}  // namespace bayon

// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/cost_functions.h"

#include "ext/adjustment/adjustment_block.h"
#include "ext/core/camera.h"
#include "ext/synth/synthetic_camera.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <memory>
#include <vector>

namespace bayon {
namespace {

using RowMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Every parameter block's Jacobian against central differences; relative
// tolerance on the block's largest entry.
void ExpectJacobiansMatchFiniteDifferences(ceres::CostFunction* cost,
                                           std::vector<std::vector<double>> x,
                                           double tolerance) {
  const int num_residuals = cost->num_residuals();
  const std::vector<int32_t>& sizes = cost->parameter_block_sizes();
  ASSERT_EQ(sizes.size(), x.size());
  std::vector<double*> parameters;
  for (auto& block : x) parameters.push_back(block.data());
  std::vector<RowMatrix> analytic(x.size());
  std::vector<double*> jacobians;
  for (size_t b = 0; b < x.size(); ++b) {
    analytic[b].resize(num_residuals, sizes[b]);
    jacobians.push_back(analytic[b].data());
  }
  Eigen::VectorXd residual(num_residuals);
  ASSERT_TRUE(
      cost->Evaluate(parameters.data(), residual.data(), jacobians.data()));
  for (size_t b = 0; b < x.size(); ++b) {
    RowMatrix numeric(num_residuals, sizes[b]);
    for (int k = 0; k < sizes[b]; ++k) {
      const double original = x[b][k];
      const double h = 1e-6 * std::max(1.0, std::abs(original));
      Eigen::VectorXd plus(num_residuals), minus(num_residuals);
      x[b][k] = original + h;
      ASSERT_TRUE(cost->Evaluate(parameters.data(), plus.data(), nullptr));
      x[b][k] = original - h;
      ASSERT_TRUE(cost->Evaluate(parameters.data(), minus.data(), nullptr));
      x[b][k] = original;
      numeric.col(k) = (plus - minus) / (2 * h);
    }
    const double scale = std::max(1e-12, numeric.cwiseAbs().maxCoeff());
    EXPECT_LT((analytic[b] - numeric).cwiseAbs().maxCoeff() / scale, tolerance)
        << "parameter block " << b << "\nanalytic\n"
        << analytic[b] << "\nnumeric\n"
        << numeric;
  }
}

std::vector<Camera> TestCameras() {
  SyntheticCameraOptions options;
  std::vector<Camera> cameras = {SyntheticCamera(options)};
  for (const CameraModelInfo& info : CameraModels()) {
    if (!IsColmapCameraModel(info.id)) continue;
    Camera camera = Camera::Create(info.id, 900, 1000, 700);
    const size_t first_extra = info.focal_idxs.size() + 2;
    const double extras[] = {
        -0.05, 0.01, 0.001, -0.0007, 0.002, 0.01, 0.002, 0.0005};
    for (size_t i = first_extra; i < camera.params.size(); ++i) {
      camera.params[i] = extras[i - first_extra];
    }
    cameras.push_back(camera);
  }
  return cameras;
}

TEST(CostFunctions, ReprojectionIsZeroAtTruthAndMatchesFiniteDifferences) {
  const Rigid3d cam_from_world =
      LookAt(Eigen::Vector3d(8, -3, 2), Eigen::Vector3d(0, 0, 1));
  const Eigen::Vector3d point(0.4, -0.3, 1.7);
  const Eigen::Quaterniond q = cam_from_world.rotation;
  const Eigen::Vector3d center = cam_from_world.Center();
  for (const Camera& camera : TestCameras()) {
    SCOPED_TRACE(camera.ModelName());
    const ImageFrame frame = camera.DefaultFrame();
    const Eigen::Vector2d observed =
        camera.ImgFromCam(cam_from_world * point, &frame);
    ASSERT_TRUE(observed.allFinite());
    // Weighting: sigma0 / sigma = 2 scales the residual by 2.
    const Eigen::Matrix2d sqrt_information = 2 * Eigen::Matrix2d::Identity();
    std::unique_ptr<ceres::CostFunction> cost(CreateReprojectionCost(
        camera.model_id, observed, sqrt_information, frame));
    std::vector<std::vector<double>> x = {{q.w(), q.x(), q.y(), q.z()},
                                          {center.x(), center.y(), center.z()},
                                          {point.x(), point.y(), point.z()},
                                          camera.params};
    std::vector<double*> parameters;
    for (auto& block : x) parameters.push_back(block.data());
    Eigen::Vector2d residual;
    ASSERT_TRUE(cost->Evaluate(parameters.data(), residual.data(), nullptr));
    EXPECT_LT(residual.norm(), 1e-8);
    // A shifted observation gives the weighted shift.
    std::unique_ptr<ceres::CostFunction> shifted(
        CreateReprojectionCost(camera.model_id,
                               observed + Eigen::Vector2d(0.5, -0.25),
                               sqrt_information,
                               frame));
    ASSERT_TRUE(shifted->Evaluate(parameters.data(), residual.data(), nullptr));
    EXPECT_NEAR(residual.x(), -1.0, 1e-8);
    EXPECT_NEAR(residual.y(), 0.5, 1e-8);
    ExpectJacobiansMatchFiniteDifferences(cost.get(), x, 1e-5);
  }
}

TEST(CostFunctions, PointPriorAndDistanceMatchFiniteDifferences) {
  Eigen::Matrix3d sqrt_information = Eigen::Matrix3d::Identity() * 100;
  sqrt_information(0, 1) = 5;
  std::unique_ptr<ceres::CostFunction> prior(
      PointPriorCost::Create(Eigen::Vector3d(1, 2, 3), sqrt_information));
  ExpectJacobiansMatchFiniteDifferences(prior.get(), {{1.1, 2.2, 2.9}}, 1e-6);
  std::vector<double> at_prior = {1, 2, 3};
  double* parameters[] = {at_prior.data()};
  Eigen::Vector3d residual;
  ASSERT_TRUE(prior->Evaluate(parameters, residual.data(), nullptr));
  EXPECT_LT(residual.norm(), 1e-12);

  std::unique_ptr<ceres::CostFunction> distance(DistanceCost::Create(2.0, 50));
  ExpectJacobiansMatchFiniteDifferences(
      distance.get(), {{0.1, 0.2, 0.3}, {0.4, 0.1, 2.2}}, 1e-6);
  std::vector<double> a = {0, 0, 0}, b = {0, 2, 0};
  double* ab[] = {a.data(), b.data()};
  double r;
  ASSERT_TRUE(distance->Evaluate(ab, &r, nullptr));
  EXPECT_NEAR(r, 0, 1e-12);
}

TEST(CostFunctions, RotationManifoldTurnsTheCameraAxes) {
  const Eigen::Quaterniond q = Eigen::Quaterniond(
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  const double x[4] = {q.w(), q.x(), q.y(), q.z()};
  const double delta[3] = {0.01, -0.02, 0.03};
  RotationManifold manifold;
  double moved[4];
  ASSERT_TRUE(manifold.Plus(x, delta, moved));
  // Plus is Exp(delta) * R: a rotation of the camera frame by |delta|.
  const Eigen::Matrix3d expected =
      Eigen::AngleAxisd(Eigen::Vector3d(0.01, -0.02, 0.03).norm(),
                        Eigen::Vector3d(0.01, -0.02, 0.03).normalized())
          .toRotationMatrix() *
      q.toRotationMatrix();
  const Eigen::Quaterniond result(moved[0], moved[1], moved[2], moved[3]);
  EXPECT_LT((result.toRotationMatrix() - expected).norm(), 1e-12);
  double back[3];
  ASSERT_TRUE(manifold.Minus(moved, x, back));
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(back[k], delta[k], 1e-12);
}

}  // namespace
}  // namespace bayon

// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/precision.h"

#include "ext/adjustment/adjustment.h"
#include "ext/adjustment/bundle_solver.h"
#include "ext/adjustment/cost_functions.h"
#include "ext/synth/points_scene.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <random>

namespace bayon {
namespace {

// A small ring block: 6 images, 40 points, the true BROWN_BEYER camera with
// dc, dx0, dy0 and K1 estimated.
AdjustmentBlock SmallBlock(double noise_px, unsigned seed) {
  PointsSceneOptions options;
  options.num_views = 6;
  options.num_points = 60;
  options.max_view_angle_deg = 80;
  options.keypoint_noise_px = noise_px;
  options.seed = seed;
  const SyntheticTruth truth = SynthesizePointsScene(options);
  AdjustmentBlock block = BlockFromScene(truth.noisy_scene, noise_px);
  for (int k : {brown::kDc, brown::kDx0, brown::kDy0, brown::kK1}) {
    block.cameras[0].free[k] = true;
  }
  return block;
}

// Dense Jacobian of all free parameters (tangent space) in the order
// images (rotation, centre), points, camera; fixed columns dropped.
Eigen::MatrixXd DenseJacobian(AdjustmentBlock* block,
                              Eigen::VectorXd* residual) {
  std::vector<ResidualTerm> terms = BuildResidualTerms(block);
  // Column offsets of each free tangent parameter.
  std::map<double*, std::vector<int>> columns;
  int num_columns = 0;
  auto add = [&](double* pointer, const std::vector<bool>& free) {
    std::vector<int> cols;
    for (bool f : free) cols.push_back(f ? num_columns++ : -1);
    columns[pointer] = cols;
  };
  for (BlockImage& image : block->images) {
    add(image.rotation.data(), std::vector<bool>(3, !image.rotation_fixed));
    add(image.center.data(),
        {!image.center_fixed[0],
         !image.center_fixed[1],
         !image.center_fixed[2]});
  }
  for (BlockPoint& point : block->points) {
    add(point.xyz.data(), {!point.fixed[0], !point.fixed[1], !point.fixed[2]});
  }
  for (BlockCamera& camera : block->cameras) {
    add(camera.camera.params.data(), camera.free);
  }
  int num_rows = 0;
  for (const ResidualTerm& term : terms) num_rows += term.num_residuals();
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(num_rows, num_columns);
  residual->resize(num_rows);
  RotationManifold manifold;
  int row = 0;
  for (const ResidualTerm& term : terms) {
    const int m = term.num_residuals();
    std::vector<Eigen::Matrix<double, -1, -1, Eigen::RowMajor>> ambient(
        term.parameters.size());
    std::vector<double*> pointers;
    const std::vector<int32_t>& sizes = term.cost->parameter_block_sizes();
    for (size_t b = 0; b < term.parameters.size(); ++b) {
      ambient[b].resize(m, sizes[b]);
      pointers.push_back(ambient[b].data());
    }
    Eigen::VectorXd r(m);
    term.cost->Evaluate(term.parameters.data(), r.data(), pointers.data());
    residual->segment(row, m) = r;
    for (size_t b = 0; b < term.parameters.size(); ++b) {
      Eigen::MatrixXd tangent = ambient[b];
      if (sizes[b] == 4) {
        Eigen::Matrix<double, 4, 3, Eigen::RowMajor> plus;
        manifold.PlusJacobian(term.parameters[b], plus.data());
        tangent = ambient[b] * plus;
      }
      const std::vector<int>& cols = columns.at(term.parameters[b]);
      for (size_t k = 0; k < cols.size(); ++k) {
        if (cols[k] >= 0) J.block(row, cols[k], m, 1) += tangent.col(k);
      }
    }
    row += m;
  }
  return J;
}

// Moves a copy of the first point of image 0 100 times farther along its
// ray and observes it, exactly, in images 0 and 1 (60 degrees apart on the
// ring): its rays meet at about half a degree. Returns its index; `copied`
// is the point it was made from.
int AddDistantPoint(double sigma_px, AdjustmentBlock* block, int* copied) {
  int a = -1;
  for (const BlockObservation& o : block->observations) {
    if (o.image_idx == 0) {
      a = o.point_idx;
      break;
    }
  }
  *copied = a;
  if (a < 0) return -1;
  BlockPoint far = block->points[a];
  far.point3D_id = 1000000;
  const Eigen::Vector3d c0 = block->images[0].center;
  far.xyz = c0 + 100 * (far.xyz - c0);
  block->points.push_back(far);
  const int far_idx = static_cast<int>(block->points.size()) - 1;
  for (int i : {0, 1}) {
    const BlockImage& image = block->images[i];
    BlockObservation o;
    o.image_idx = i;
    o.point_idx = far_idx;
    o.sigma_px = sigma_px;
    o.xy = block->cameras[image.camera_idx].camera.ImgFromCam(
        image.CamFromWorld() * far.xyz, &image.frame);
    block->observations.push_back(o);
  }
  return far_idx;
}

TEST(Precision, MatchesTheDenseInverseWithControl) {
  AdjustmentBlock block = SmallBlock(0.5, 3);
  // Datum by three fixed points and one weighted point.
  for (int p = 0; p < 3; ++p) block.points[p].fixed = {true, true, true};
  block.points[3].weighted = true;
  block.points[3].given_xyz = block.points[3].xyz + Eigen::Vector3d(0.01, 0, 0);
  block.points[3].given_sigma = Eigen::Vector3d(0.02, 0.02, 0.02);
  BundleSolverOptions solver_options;
  solver_options.num_threads = 1;
  ASSERT_TRUE(SolveBundle(solver_options, &block).usable);

  const AdjustmentPrecision precision = ComputePrecision(&block, {});
  Eigen::VectorXd residual;
  const Eigen::MatrixXd J = DenseJacobian(&block, &residual);
  const Eigen::MatrixXd Q = (J.transpose() * J).inverse();
  // n - u: 2 per observation + 3 prior rows, unknowns = free columns.
  EXPECT_EQ(precision.num_observations, J.rows());
  EXPECT_EQ(precision.num_unknowns, J.cols());
  EXPECT_EQ(precision.redundancy, J.rows() - J.cols());
  const double s0 = std::sqrt(residual.squaredNorm() / (J.rows() - J.cols()));
  EXPECT_NEAR(precision.sigma0, s0, 1e-9 * s0);
  // Sum of redundancy numbers = r.
  const Eigen::MatrixXd Qvv =
      Eigen::MatrixXd::Identity(J.rows(), J.rows()) - J * Q * J.transpose();
  EXPECT_NEAR(Qvv.trace(), precision.redundancy, 1e-6);
  double sum_r = 0;
  for (const ObservationStatistics& s : precision.observations) {
    if (s.valid) sum_r += s.redundancy.sum();
  }
  for (const Eigen::Vector3d& r : precision.control_redundancy)
    sum_r += r.sum();
  EXPECT_NEAR(sum_r, precision.redundancy, 1e-6);

  // Point 10's covariance: its columns follow 6 images x 6 columns and the
  // points before it (three fixed points have no columns).
  const int col = 6 * 6 + 3 * (10 - 3);
  const Eigen::Matrix3d expected = s0 * s0 * Q.block<3, 3>(col, col);
  EXPECT_LT((precision.point_covariance[10] - expected).norm(),
            1e-6 * expected.norm());
  // Image 2's centre.
  const Eigen::Matrix3d centre = s0 * s0 * Q.block<3, 3>(2 * 6 + 3, 2 * 6 + 3);
  EXPECT_LT(
      (precision.image_covariance[2].bottomRightCorner<3, 3>() - centre).norm(),
      1e-6 * centre.norm());
  // The camera's estimated parameters are the last four columns.
  const Eigen::Matrix4d camera = s0 * s0 * Q.bottomRightCorner<4, 4>();
  const Eigen::MatrixXd& C = precision.camera_covariance[0];
  EXPECT_NEAR(C(brown::kDc, brown::kDc), camera(0, 0), 1e-6 * camera(0, 0));
  EXPECT_NEAR(C(brown::kK1, brown::kDx0),
              camera(3, 1),
              1e-6 * std::sqrt(camera(3, 3) * camera(1, 1)));
}

// A free network's minimal datum: image 0 held, one centre coordinate of
// image 3 held. Returns whether the block was solved.
bool SolveInMinimalDatum(AdjustmentBlock* block) {
  block->images[0].rotation_fixed = true;
  block->images[0].center_fixed = {true, true, true};
  block->images[3].center_fixed = {true, false, false};
  BundleSolverOptions solver_options;
  solver_options.num_threads = 1;
  return SolveBundle(solver_options, block).usable;
}

TEST(Precision, FreeNetworkGivesTheInnerConstraintCovariance) {
  AdjustmentBlock block = SmallBlock(0.5, 5);
  ASSERT_TRUE(SolveInMinimalDatum(&block));
  PrecisionOptions options;
  options.inner_constraints = true;
  const AdjustmentPrecision precision = ComputePrecision(&block, options);
  EXPECT_EQ(precision.datum_defect, 7);

  // Dense reference: all parameters free, N singular with a 7-dimensional
  // null space; the inner-constraint cofactor over the points is
  // Q_E = (N + B B^T)^-1 - G (B^T G)^-1 (B^T G)^-T G^T ... computed here
  // directly as the constrained solution of [N B; B^T 0].
  AdjustmentBlock free_block = block;
  free_block.images[0].rotation_fixed = false;
  free_block.images[0].center_fixed = {false, false, false};
  free_block.images[3].center_fixed = {false, false, false};
  Eigen::VectorXd residual;
  const Eigen::MatrixXd J = DenseJacobian(&free_block, &residual);
  const Eigen::MatrixXd N = J.transpose() * J;
  const int u = static_cast<int>(N.rows());
  // B: similarity motions restricted to the tie points (columns after the
  // 6 images x 6 parameters, before the camera's 4).
  const int num_points = static_cast<int>(block.points.size());
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (const BlockPoint& p : block.points) origin += p.xyz;
  origin /= num_points;
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(u, 7);
  for (int p = 0; p < num_points; ++p) {
    const Eigen::Vector3d x = block.points[p].xyz - origin;
    Eigen::Matrix3d skew;
    skew << 0, -x.z(), x.y(), x.z(), 0, -x.x(), -x.y(), x.x(), 0;
    B.block<3, 3>(36 + 3 * p, 0).setIdentity();
    B.block<3, 3>(36 + 3 * p, 3) = -skew;
    B.block<3, 1>(36 + 3 * p, 6) = x;
  }
  Eigen::MatrixXd bordered = Eigen::MatrixXd::Zero(u + 7, u + 7);
  bordered.topLeftCorner(u, u) = N;
  bordered.topRightCorner(u, 7) = B;
  bordered.bottomLeftCorner(7, u) = B.transpose();
  const Eigen::MatrixXd inverse = bordered.inverse();
  const Eigen::MatrixXd Q_E = inverse.topLeftCorner(u, u);
  const double s2 = precision.sigma0 * precision.sigma0;
  // The seven null-space columns of N are those motions (J B_full = 0).
  for (int p : {0, 7, 20}) {
    const Eigen::Matrix3d expected =
        s2 * Q_E.block<3, 3>(36 + 3 * p, 36 + 3 * p);
    EXPECT_LT((precision.point_covariance[p] - expected).norm(),
              1e-5 * expected.norm())
        << "point " << p << "\n"
        << precision.point_covariance[p] << "\n"
        << expected;
  }
  for (int i : {0, 3, 5}) {
    const Eigen::Matrix<double, 6, 6> expected =
        s2 * Q_E.block<6, 6>(6 * i, 6 * i);
    EXPECT_LT((precision.image_covariance[i] - expected).norm(),
              1e-5 * expected.norm())
        << "image " << i;
  }
  const Eigen::Matrix4d expected_camera = s2 * Q_E.bottomRightCorner<4, 4>();
  EXPECT_NEAR(precision.camera_covariance[0](brown::kDc, brown::kDc),
              expected_camera(0, 0),
              1e-5 * expected_camera(0, 0));
  // Sum of the point variances is the minimum over all datums: the trace
  // with image 0 fixed is larger.
  PrecisionOptions minimal;
  const AdjustmentPrecision fixed = ComputePrecision(&block, minimal);
  double trace_inner = 0, trace_fixed = 0;
  for (int p = 0; p < num_points; ++p) {
    trace_inner += precision.point_covariance[p].trace();
    trace_fixed += fixed.point_covariance[p].trace();
  }
  EXPECT_LT(trace_inner, trace_fixed);
}

// A tie point whose two rays meet at a fraction of a degree slides along
// them; over all tie points, its variance would enter the centroid of the
// inner constraints and every covariance of the network with it.
TEST(Precision, FreeNetworkDatumLeavesOutPointsSeenFromOneDirection) {
  AdjustmentBlock block = SmallBlock(0.5, 5);
  // The camera as given: with the principal point free and no rolled
  // stations, any ray that fixes a relative rotation would also sharpen it.
  std::fill(block.cameras[0].free.begin(), block.cameras[0].free.end(), false);
  ASSERT_TRUE(SolveInMinimalDatum(&block));
  PrecisionOptions options;
  options.inner_constraints = true;
  const AdjustmentPrecision before = ComputePrecision(&block, options);

  // A point of image 0 moved 100 times farther along its ray, and seen once
  // more from the next station, 60 degrees round the ring. Its observations
  // are weak (50 px), so that it adds next to nothing to the orientations
  // (a point that far off fixes the relative rotation of the two images).
  int a = -1;
  const int far_idx = AddDistantPoint(50, &block, &a);
  ASSERT_GE(a, 0);
  ASSERT_TRUE(SolveInMinimalDatum(&block));
  EXPECT_LT(block.IntersectionAnglesDeg()[far_idx],
            kMinDatumIntersectionAngleDeg);
  EXPECT_FALSE(InnerConstraintPoints(block)[far_idx]);
  const AdjustmentPrecision after = ComputePrecision(&block, options);
  EXPECT_EQ(after.num_datum_points, before.num_datum_points);
  // Its own depth is that poor ...
  EXPECT_GT(after.point_covariance[far_idx].trace(),
            1e4 * after.point_covariance[a].trace());
  // ... and the others' precision keeps its figures.
  for (int i = 0; i < static_cast<int>(block.images.size()); ++i) {
    const double s_before =
        before.image_covariance[i].bottomRightCorner<3, 3>().trace();
    const double s_after =
        after.image_covariance[i].bottomRightCorner<3, 3>().trace();
    EXPECT_NEAR(std::sqrt(s_after / s_before), 1.0, 0.05) << "image " << i;
  }
  for (int p : {1, 17, 33}) {
    EXPECT_NEAR(std::sqrt(after.point_covariance[p].trace() /
                          before.point_covariance[p].trace()),
                1.0,
                0.05)
        << "point " << p;
  }
}

// A point seen twice has all its redundancy across the epipolar line: the
// coordinate along it is not controlled, and its normalised residual would
// be the solver's last digits over a vanishing root. Data snooping must
// leave such a point alone (it took both observations of every one).
TEST(Precision, ACoordinateWithoutRedundancyIsNotTested) {
  PointsSceneOptions scene_options;
  scene_options.num_points = 300;
  scene_options.alternate_roll_deg = 90;
  scene_options.num_distant_points = 8;
  scene_options.keypoint_noise_px = 0.3;
  const SyntheticTruth truth = SynthesizePointsScene(scene_options);
  AdjustmentBlock block = BlockFromScene(truth.noisy_scene, 0.3);
  block.images[0].rotation_fixed = true;
  block.images[0].center_fixed = {true, true, true};
  block.images[4].center_fixed = {true, false, false};
  AdjustmentOptions options;
  options.self_calibration = SelfCalibration::kNone;
  options.solver.num_threads = 1;
  const AdjustmentResult result = RunAdjustment(options, &block);
  const std::vector<double> angles = block.IntersectionAnglesDeg();
  int num_distant = 0, num_untested = 0;
  for (size_t o = 0; o < block.observations.size(); ++o) {
    const BlockObservation& observation = block.observations[o];
    if (angles[observation.point_idx] >= kMinDatumIntersectionAngleDeg) {
      continue;
    }
    ++num_distant;
    EXPECT_TRUE(observation.active) << "observation " << o;
    const ObservationStatistics& stats = result.precision.observations[o];
    for (int k = 0; k < 2; ++k) {
      if (stats.redundancy(k) < kMinTestableRedundancy) {
        EXPECT_EQ(stats.normalized(k), 0.0);
        ++num_untested;
      }
    }
  }
  EXPECT_EQ(num_distant, 2 * scene_options.num_distant_points);
  // One coordinate of each carries its point's redundancy.
  EXPECT_EQ(num_untested, num_distant);
}

}  // namespace
}  // namespace bayon

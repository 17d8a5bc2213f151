// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/precision.h"

#include "ext/adjustment/cost_functions.h"
#include "ext/colmap/calibration_json.h"
#include "ext/core/errors.h"

#include <Eigen/Dense>

#include <cmath>
#include <map>
#include <unordered_map>

namespace bayon {
namespace {

using RowMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

enum class BlockKind { kRotation, kCenter, kPoint, kIntrinsics };

// One parameter block in the tangent space of its manifold.
struct ParamBlock {
  BlockKind kind;
  int owner = -1;  // image, point or camera index
  int size = 0;    // tangent size (3 for rotations, ambient otherwise)
  int ambient = 0;
  std::vector<bool> free;
  bool eliminated = false;  // a point block, eliminated by the Schur step
  int offset = -1;          // kept blocks: offset in the reduced system
  int point_slot = -1;      // eliminated blocks: index of the point system
};

struct TermJacobian {
  std::vector<int> blocks;         // ParamBlock ids
  std::vector<Eigen::MatrixXd> J;  // residuals x tangent, fixed columns zero
  Eigen::VectorXd residual;        // whitened
  int eliminated = -1;             // position in `blocks` of the point block
};

// The eliminated point systems.
struct PointSystem {
  int block = -1;
  Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d N_inverse = Eigen::Matrix3d::Zero();
  // N_bj for the kept blocks b observing the point.
  std::map<int, Eigen::MatrixXd> N_kept;
  // M_j = N_bj N_jj^-1, per kept block.
  std::map<int, Eigen::MatrixXd> M;
  // Cofactors in the datum of the solution: Q_jj and Q_bj per kept block.
  Eigen::Matrix3d Q = Eigen::Matrix3d::Zero();
  std::map<int, Eigen::MatrixXd> Q_kept;
};

// Pseudo-inverse of a small symmetric positive semi-definite matrix,
// ignoring rows and columns of fixed coordinates (which are zero).
Eigen::Matrix3d InverseOfPointBlock(const Eigen::Matrix3d& N,
                                    const std::vector<bool>& free) {
  Eigen::Matrix3d regular = N;
  for (int k = 0; k < 3; ++k) {
    if (!free[k]) {
      regular.row(k).setZero();
      regular.col(k).setZero();
      regular(k, k) = 1;
    }
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(regular);
  const Eigen::Vector3d values = eigen.eigenvalues();
  const double threshold = 1e-12 * std::max(values.maxCoeff(), 1e-300);
  Eigen::Vector3d inverse_values;
  for (int k = 0; k < 3; ++k) {
    inverse_values(k) = values(k) > threshold ? 1.0 / values(k) : 0.0;
  }
  Eigen::Matrix3d inverse = eigen.eigenvectors() * inverse_values.asDiagonal() *
                            eigen.eigenvectors().transpose();
  for (int k = 0; k < 3; ++k) {
    if (!free[k]) {
      inverse.row(k).setZero();
      inverse.col(k).setZero();
    }
  }
  return inverse;
}

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// Rows of the similarity null space (dt, domega, ds) for a position.
Eigen::Matrix<double, 3, 7> PositionNullSpace(const Eigen::Vector3d& x) {
  Eigen::Matrix<double, 3, 7> g;
  g.leftCols<3>().setIdentity();
  g.middleCols<3>(3) = -Skew(x);
  g.col(6) = x;
  return g;
}

class PrecisionComputer {
 public:
  PrecisionComputer(AdjustmentBlock* block, const PrecisionOptions& options)
      : block_(block), options_(options) {}

  AdjustmentPrecision Compute() {
    terms_ = BuildResidualTerms(block_);
    MapParameterBlocks();
    EvaluateJacobians();
    AccumulateNormalEquations();
    InvertReducedSystem();
    RecoverPointCofactors();
    CountAndSigma0();
    if (options_.inner_constraints) ComputeInnerConstraintTransform();
    ExtractCovariances();
    if (options_.compute_residual_cofactors) ComputeResidualCofactors();
    return std::move(result_);
  }

 private:
  int AddBlock(double* pointer,
               BlockKind kind,
               int owner,
               int size,
               int ambient,
               std::vector<bool> free) {
    auto it = block_ids_.find(pointer);
    if (it != block_ids_.end()) return it->second;
    ParamBlock param;
    param.kind = kind;
    param.owner = owner;
    param.size = size;
    param.ambient = ambient;
    param.free = std::move(free);
    const int id = static_cast<int>(params_.size());
    params_.push_back(std::move(param));
    block_ids_[pointer] = id;
    return id;
  }

  void MapParameterBlocks() {
    // Points in distance observations cannot be eliminated on their own.
    std::map<double*, bool> coupled;
    for (const ResidualTerm& term : terms_) {
      if (term.type == TermType::kDistance) {
        for (double* p : term.parameters) coupled[p] = true;
      }
    }
    for (size_t t = 0; t < terms_.size(); ++t) {
      const ResidualTerm& term = terms_[t];
      if (term.type == TermType::kReprojection) {
        const BlockObservation& observation = block_->observations[term.index];
        BlockImage& image = block_->images[observation.image_idx];
        BlockCamera& camera = block_->cameras[image.camera_idx];
        AddBlock(term.parameters[0],
                 BlockKind::kRotation,
                 observation.image_idx,
                 3,
                 4,
                 std::vector<bool>(3, !image.rotation_fixed));
        AddBlock(term.parameters[1],
                 BlockKind::kCenter,
                 observation.image_idx,
                 3,
                 3,
                 {!image.center_fixed[0],
                  !image.center_fixed[1],
                  !image.center_fixed[2]});
        AddPointBlock(term.parameters[2], observation.point_idx, coupled);
        const int n = static_cast<int>(camera.free.size());
        AddBlock(term.parameters[3],
                 BlockKind::kIntrinsics,
                 image.camera_idx,
                 n,
                 n,
                 camera.free);
      } else if (term.type == TermType::kPointPrior) {
        AddPointBlock(term.parameters[0], term.index, coupled);
      } else {
        const BlockDistance& distance = block_->distances[term.index];
        AddPointBlock(term.parameters[0], distance.point_a, coupled);
        AddPointBlock(term.parameters[1], distance.point_b, coupled);
      }
    }
    num_kept_ = 0;
    for (ParamBlock& param : params_) {
      if (param.eliminated) {
        param.point_slot = static_cast<int>(points_.size());
        PointSystem system;
        system.block = static_cast<int>(&param - params_.data());
        points_.push_back(std::move(system));
      } else {
        param.offset = num_kept_;
        num_kept_ += param.size;
      }
    }
  }

  void AddPointBlock(double* pointer,
                     int point_idx,
                     const std::map<double*, bool>& coupled) {
    const BlockPoint& point = block_->points[point_idx];
    const int id =
        AddBlock(pointer,
                 BlockKind::kPoint,
                 point_idx,
                 3,
                 3,
                 {!point.fixed[0], !point.fixed[1], !point.fixed[2]});
    params_[id].eliminated = coupled.count(pointer) == 0;
  }

  void EvaluateJacobians() {
    RotationManifold rotation_manifold;
    jacobians_.resize(terms_.size());
    for (size_t t = 0; t < terms_.size(); ++t) {
      const ResidualTerm& term = terms_[t];
      const int num_residuals = term.num_residuals();
      std::vector<RowMatrix> ambient(term.parameters.size());
      std::vector<double*> jacobian_ptrs(term.parameters.size());
      TermJacobian& jacobian = jacobians_[t];
      for (size_t b = 0; b < term.parameters.size(); ++b) {
        const int id = block_ids_.at(term.parameters[b]);
        jacobian.blocks.push_back(id);
        ambient[b].resize(num_residuals, params_[id].ambient);
        jacobian_ptrs[b] = ambient[b].data();
        if (params_[id].eliminated) jacobian.eliminated = static_cast<int>(b);
      }
      jacobian.residual.resize(num_residuals);
      if (!term.cost->Evaluate(term.parameters.data(),
                               jacobian.residual.data(),
                               jacobian_ptrs.data())) {
        throw RunFailure(
            "the adjusted block cannot be evaluated (a point behind a camera)");
      }
      for (size_t b = 0; b < term.parameters.size(); ++b) {
        const ParamBlock& param = params_[jacobian.blocks[b]];
        Eigen::MatrixXd tangent;
        if (param.kind == BlockKind::kRotation) {
          RowMatrix plus_jacobian(4, 3);
          rotation_manifold.PlusJacobian(term.parameters[b],
                                         plus_jacobian.data());
          tangent = ambient[b] * plus_jacobian;
        } else {
          tangent = ambient[b];
        }
        for (int k = 0; k < param.size; ++k) {
          if (!param.free[k]) tangent.col(k).setZero();
        }
        jacobian.J.push_back(std::move(tangent));
      }
    }
  }

  void AccumulateNormalEquations() {
    N_kk_.setZero(num_kept_, num_kept_);
    for (const TermJacobian& jacobian : jacobians_) {
      PointSystem* point = nullptr;
      if (jacobian.eliminated >= 0) {
        point =
            &points_[params_[jacobian.blocks[jacobian.eliminated]].point_slot];
        const Eigen::MatrixXd& J_j = jacobian.J[jacobian.eliminated];
        point->N += J_j.transpose() * J_j;
      }
      for (size_t a = 0; a < jacobian.blocks.size(); ++a) {
        if (static_cast<int>(a) == jacobian.eliminated) continue;
        const ParamBlock& pa = params_[jacobian.blocks[a]];
        for (size_t b = 0; b < jacobian.blocks.size(); ++b) {
          if (static_cast<int>(b) == jacobian.eliminated) continue;
          const ParamBlock& pb = params_[jacobian.blocks[b]];
          N_kk_.block(pa.offset, pb.offset, pa.size, pb.size) +=
              jacobian.J[a].transpose() * jacobian.J[b];
        }
        if (point != nullptr) {
          Eigen::MatrixXd& N_aj = point->N_kept[jacobian.blocks[a]];
          if (N_aj.size() == 0) N_aj.setZero(pa.size, 3);
          N_aj += jacobian.J[a].transpose() * jacobian.J[jacobian.eliminated];
        }
      }
    }
  }

  // The parameter that carries most of the eigenvector of the smallest
  // eigenvalue of the (scaled) reduced normal matrix, named for the user.
  std::string WeakestParameter(const Eigen::MatrixXd& scaled) const {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scaled);
    if (eigen.info() != Eigen::Success) return "unknown";
    Eigen::Index row = 0;
    eigen.eigenvectors().col(0).cwiseAbs().maxCoeff(&row);
    for (const ParamBlock& param : params_) {
      if (param.eliminated || row < param.offset ||
          row >= param.offset + param.size) {
        continue;
      }
      const int k = static_cast<int>(row - param.offset);
      switch (param.kind) {
        case BlockKind::kRotation:
          return StrCat(
              "the rotation of image '", block_->images[param.owner].name, "'");
        case BlockKind::kCenter:
          return StrCat("coordinate ",
                        "XYZ"[k],
                        " of the projection centre of image '",
                        block_->images[param.owner].name,
                        "'");
        case BlockKind::kIntrinsics: {
          const Camera& camera = block_->cameras[param.owner].camera;
          const std::vector<std::string> names =
              ParameterNames(camera.model_id);
          return StrCat(
              "parameter ",
              k < static_cast<int>(names.size()) ? names[k] : std::to_string(k),
              " of camera ",
              camera.camera_id);
        }
        case BlockKind::kPoint:
          return StrCat("object point ", param.owner);
      }
    }
    return "unknown";
  }

  void InvertReducedSystem() {
    // Schur complement of the eliminated points.
    Eigen::MatrixXd S = N_kk_;
    for (PointSystem& point : points_) {
      const ParamBlock& param = params_[point.block];
      point.N_inverse = InverseOfPointBlock(point.N, param.free);
      for (auto& [b, N_bj] : point.N_kept) {
        point.M[b] = N_bj * point.N_inverse;
      }
      for (const auto& [a, M_a] : point.M) {
        const ParamBlock& pa = params_[a];
        for (const auto& [b, N_bj] : point.N_kept) {
          const ParamBlock& pb = params_[b];
          S.block(pa.offset, pb.offset, pa.size, pb.size) -=
              M_a * N_bj.transpose();
        }
      }
    }
    // Fixed parameters: unit rows so that the matrix stays regular; their
    // cofactors are zeroed after the inversion.
    std::vector<bool> free(num_kept_, true);
    for (const ParamBlock& param : params_) {
      if (param.eliminated) continue;
      for (int k = 0; k < param.size; ++k) {
        if (!param.free[k]) free[param.offset + k] = false;
      }
    }
    for (int i = 0; i < num_kept_; ++i) {
      if (free[i]) continue;
      S.row(i).setZero();
      S.col(i).setZero();
      S(i, i) = 1;
    }
    // Jacobi scaling: parameters range from radians to mm^-6.
    Eigen::VectorXd scale(num_kept_);
    for (int i = 0; i < num_kept_; ++i) {
      scale(i) = S(i, i) > 0 ? 1.0 / std::sqrt(S(i, i)) : 1.0;
    }
    const Eigen::MatrixXd scaled = scale.asDiagonal() * S * scale.asDiagonal();
    Eigen::LLT<Eigen::MatrixXd> llt(scaled);
    bool regular = llt.info() == Eigen::Success;
    if (regular && num_kept_ > 0) {
      // A Cholesky factor can exist for a numerically singular matrix; a
      // tiny pivot means a datum defect or an undetermined parameter.
      const Eigen::VectorXd diagonal = llt.matrixL().toDenseMatrix().diagonal();
      const double ratio = diagonal.minCoeff() / diagonal.maxCoeff();
      regular = ratio > 1e-7;
    }
    if (!regular) {
      throw RunFailure(StrCat(
          "the normal equations are singular: the datum is not defined or a "
          "parameter cannot be determined (check the control points, the "
          "minimum datum, or the self-calibration parameters); the weakest "
          "parameter: ",
          WeakestParameter(scaled)));
    }
    Q_kk_ = scale.asDiagonal() *
            llt.solve(Eigen::MatrixXd::Identity(num_kept_, num_kept_)) *
            scale.asDiagonal();
    for (int i = 0; i < num_kept_; ++i) {
      if (free[i]) continue;
      Q_kk_.row(i).setZero();
      Q_kk_.col(i).setZero();
    }
  }

  void CountAndSigma0() {
    int n = 0, n_image = 0;
    double vtpv = 0;
    for (size_t t = 0; t < terms_.size(); ++t) {
      if (terms_[t].type == TermType::kPointPrior) {
        // Coordinates held fixed carry no weight in a partly weighted point.
        const BlockPoint& point = block_->points[terms_[t].index];
        for (int k = 0; k < 3; ++k) n += !point.fixed[k];
      } else {
        n += terms_[t].num_residuals();
      }
      if (terms_[t].type == TermType::kReprojection) {
        n_image += terms_[t].num_residuals();
      }
      vtpv += jacobians_[t].residual.squaredNorm();
    }
    int u = 0;
    for (const ParamBlock& param : params_) {
      for (bool f : param.free) u += f;
    }
    result_.num_observations = n;
    result_.num_image_coordinates = n_image;
    // A free network holds seven parameters to fix its datum; they are
    // unknowns of the problem all the same, and the defect is seven.
    result_.datum_defect = options_.inner_constraints ? 7 : 0;
    result_.num_unknowns = u + result_.datum_defect;
    result_.redundancy =
        result_.num_observations - result_.num_unknowns + result_.datum_defect;
    result_.vtpv = vtpv;
    if (result_.redundancy <= 0) {
      throw RunFailure(StrCat("no redundancy: ",
                              n,
                              " observations for ",
                              result_.num_unknowns,
                              " unknowns"));
    }
    result_.sigma0 = std::sqrt(vtpv / result_.redundancy);
  }

  // G rows of a block (tangent size x 7), about the centroid `origin`.
  Eigen::MatrixXd NullSpaceRows(const ParamBlock& param) const {
    switch (param.kind) {
      case BlockKind::kRotation: {
        const BlockImage& image = block_->images[param.owner];
        const Eigen::Matrix3d R =
            image.CamFromWorld().rotation.toRotationMatrix();
        Eigen::MatrixXd g = Eigen::MatrixXd::Zero(3, 7);
        g.middleCols<3>(3) = -R;
        return g;
      }
      case BlockKind::kCenter:
        return PositionNullSpace(block_->images[param.owner].center - origin_);
      case BlockKind::kPoint:
        return PositionNullSpace(block_->points[param.owner].xyz - origin_);
      case BlockKind::kIntrinsics:
        return Eigen::MatrixXd::Zero(param.size, 7);
    }
    return Eigen::MatrixXd();
  }

  bool IsDatumPoint(const ParamBlock& param) const {
    return param.kind == BlockKind::kPoint && param.eliminated &&
           datum_points_[param.owner];
  }

  // See the header: Q_E = S Q S^T restricted to the diagonal blocks needed.
  void ComputeInnerConstraintTransform() {
    datum_points_ = InnerConstraintPoints(*block_);
    origin_.setZero();
    int count = 0;
    for (const PointSystem& point : points_) {
      const ParamBlock& param = params_[point.block];
      if (!IsDatumPoint(param)) continue;
      origin_ += block_->points[param.owner].xyz;
      ++count;
    }
    if (count < 3) {
      throw RunFailure(
          StrCat("a free network needs three or more tie points whose rays "
                 "intersect at ",
                 kMinDatumIntersectionAngleDeg,
                 " deg or more; there are ",
                 count));
    }
    result_.num_datum_points = count;
    origin_ /= count;
    Eigen::Matrix<double, 7, 7> A = Eigen::Matrix<double, 7, 7>::Zero();
    for (const PointSystem& point : points_) {
      const ParamBlock& param = params_[point.block];
      if (!IsDatumPoint(param)) continue;
      const Eigen::MatrixXd g = NullSpaceRows(param);
      A += g.transpose() * g;
    }
    const Eigen::Matrix<double, 7, 7> A_inverse = A.inverse();
    // K = sum_j H_j M_j^T (7 x kept), H_j = A^-1 G_j^T.
    Eigen::MatrixXd K = Eigen::MatrixXd::Zero(7, num_kept_);
    H_.assign(points_.size(), Eigen::Matrix<double, 7, 3>::Zero());
    for (size_t j = 0; j < points_.size(); ++j) {
      const ParamBlock& param = params_[points_[j].block];
      if (!IsDatumPoint(param)) continue;
      H_[j] = A_inverse * NullSpaceRows(param).transpose();
      for (const auto& [b, M_b] : points_[j].M) {
        const ParamBlock& pb = params_[b];
        K.middleCols(pb.offset, pb.size) += H_[j] * M_b.transpose();
      }
    }
    HQ_kept_ = -K * Q_kk_;
    HQ_point_.assign(points_.size(), Eigen::Matrix<double, 7, 3>::Zero());
    HQH_.setZero();
    for (size_t j = 0; j < points_.size(); ++j) {
      HQ_point_[j] = PointColumnsOfHQ(j);
      HQH_ += HQ_point_[j] * H_[j].transpose();
    }
    G_kept_.setZero(num_kept_, 7);
    for (const ParamBlock& param : params_) {
      if (param.eliminated) continue;
      G_kept_.middleRows(param.offset, param.size) = NullSpaceRows(param);
    }
  }

  // (H Q) for the columns of point j: H_j N_jj^-1 + K Q_kk M_j.
  Eigen::Matrix<double, 7, 3> PointColumnsOfHQ(size_t j) const {
    Eigen::Matrix<double, 7, 3> hq = H_[j] * points_[j].N_inverse;
    for (const auto& [b, M_b] : points_[j].M) {
      const ParamBlock& pb = params_[b];
      hq -= HQ_kept_.middleCols(pb.offset, pb.size) * M_b;
    }
    return hq;
  }

  // Q_jj and, for the inner-constraint datum, its S-transformation.
  Eigen::Matrix3d PointCofactor(size_t j) const {
    const PointSystem& point = points_[j];
    Eigen::Matrix3d Q = MinimalPointCofactor(point);
    if (options_.inner_constraints) {
      const Eigen::MatrixXd g = NullSpaceRows(params_[point.block]);
      const Eigen::Matrix3d gHQ = g * HQ_point_[j];
      Q += -gHQ - gHQ.transpose() + g * HQH_ * g.transpose();
    }
    return Q;
  }

  // Q_ab of two kept blocks, S-transformed for the inner-constraint datum.
  Eigen::MatrixXd KeptCofactor(const ParamBlock& pa,
                               const ParamBlock& pb) const {
    Eigen::MatrixXd Q = Q_kk_.block(pa.offset, pb.offset, pa.size, pb.size);
    if (options_.inner_constraints) {
      const Eigen::MatrixXd g_a = G_kept_.middleRows(pa.offset, pa.size);
      const Eigen::MatrixXd g_b = G_kept_.middleRows(pb.offset, pb.size);
      Q += -g_a * HQ_kept_.middleCols(pb.offset, pb.size) -
           (g_b * HQ_kept_.middleCols(pa.offset, pa.size)).transpose() +
           g_a * HQH_ * g_b.transpose();
    }
    return Q;
  }

  // Per camera parameter, the largest correlation with a parameter of an
  // exterior orientation of an image of that camera.
  void ComputeExteriorCorrelations() {
    result_.camera_exterior_correlation.resize(block_->cameras.size());
    for (size_t c = 0; c < block_->cameras.size(); ++c) {
      result_.camera_exterior_correlation[c].setZero(
          block_->cameras[c].free.size());
    }
    for (const ParamBlock& intrinsics : params_) {
      if (intrinsics.kind != BlockKind::kIntrinsics) continue;
      const Eigen::VectorXd var_i =
          KeptCofactor(intrinsics, intrinsics).diagonal();
      Eigen::VectorXd& best =
          result_.camera_exterior_correlation[intrinsics.owner];
      for (const ParamBlock& exterior : params_) {
        if (exterior.kind != BlockKind::kRotation &&
            exterior.kind != BlockKind::kCenter) {
          continue;
        }
        if (block_->images[exterior.owner].camera_idx != intrinsics.owner) {
          continue;
        }
        const Eigen::VectorXd var_e =
            KeptCofactor(exterior, exterior).diagonal();
        const Eigen::MatrixXd Q = KeptCofactor(intrinsics, exterior);
        for (int i = 0; i < intrinsics.size; ++i) {
          for (int e = 0; e < exterior.size; ++e) {
            const double d = var_i(i) * var_e(e);
            if (d <= 0) continue;
            best(i) = std::max(best(i), std::abs(Q(i, e)) / std::sqrt(d));
          }
        }
      }
    }
  }

  void ExtractCovariances() {
    const double s2 = result_.sigma0 * result_.sigma0;
    result_.point_covariance.assign(block_->points.size(),
                                    Eigen::Matrix3d::Zero());
    result_.image_covariance.assign(block_->images.size(),
                                    Eigen::Matrix<double, 6, 6>::Zero());
    result_.camera_covariance.resize(block_->cameras.size());
    for (size_t c = 0; c < block_->cameras.size(); ++c) {
      const int n = static_cast<int>(block_->cameras[c].free.size());
      result_.camera_covariance[c].setZero(n, n);
    }
    for (size_t j = 0; j < points_.size(); ++j) {
      const ParamBlock& param = params_[points_[j].block];
      result_.point_covariance[param.owner] = s2 * PointCofactor(j);
    }
    for (const ParamBlock& param : params_) {
      if (param.eliminated) continue;
      const Eigen::MatrixXd C = s2 * KeptCofactor(param, param);
      switch (param.kind) {
        case BlockKind::kRotation:
          result_.image_covariance[param.owner].topLeftCorner<3, 3>() = C;
          break;
        case BlockKind::kCenter:
          result_.image_covariance[param.owner].bottomRightCorner<3, 3>() = C;
          break;
        case BlockKind::kPoint:
          result_.point_covariance[param.owner] = C;
          break;
        case BlockKind::kIntrinsics:
          result_.camera_covariance[param.owner] = C;
          break;
      }
    }
    // Rotation-centre correlations of each image.
    std::map<int, std::pair<int, int>> image_blocks;
    for (const ParamBlock& param : params_) {
      if (param.kind == BlockKind::kRotation) {
        image_blocks[param.owner].first =
            static_cast<int>(&param - params_.data());
      } else if (param.kind == BlockKind::kCenter) {
        image_blocks[param.owner].second =
            static_cast<int>(&param - params_.data());
      }
    }
    for (const auto& [image, ids] : image_blocks) {
      const Eigen::Matrix3d Q =
          KeptCofactor(params_[ids.first], params_[ids.second]);
      result_.image_covariance[image].topRightCorner<3, 3>() = s2 * Q;
      result_.image_covariance[image].bottomLeftCorner<3, 3>() =
          s2 * Q.transpose();
    }
    ComputeExteriorCorrelations();
  }

  // Q_xx of the parameters of one term (datum-independent use only).
  Eigen::MatrixXd TermCofactor(const TermJacobian& jacobian) const {
    int size = 0;
    for (int id : jacobian.blocks) size += params_[id].size;
    Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(size, size);
    const PointSystem* point =
        jacobian.eliminated >= 0
            ? &points_[params_[jacobian.blocks[jacobian.eliminated]].point_slot]
            : nullptr;
    int row = 0;
    for (size_t a = 0; a < jacobian.blocks.size(); ++a) {
      const ParamBlock& pa = params_[jacobian.blocks[a]];
      int col = 0;
      for (size_t b = 0; b < jacobian.blocks.size(); ++b) {
        const ParamBlock& pb = params_[jacobian.blocks[b]];
        const bool a_point = static_cast<int>(a) == jacobian.eliminated;
        const bool b_point = static_cast<int>(b) == jacobian.eliminated;
        Eigen::MatrixXd Q_ab;
        if (!a_point && !b_point) {
          Q_ab = Q_kk_.block(pa.offset, pb.offset, pa.size, pb.size);
        } else if (a_point && b_point) {
          Q_ab = MinimalPointCofactor(*point);
        } else if (!a_point) {
          Q_ab = KeptPointCofactor(jacobian.blocks[a], *point);
        } else {
          Q_ab = KeptPointCofactor(jacobian.blocks[b], *point).transpose();
        }
        Q.block(row, col, pa.size, pb.size) = Q_ab;
        col += pb.size;
      }
      row += pa.size;
    }
    return Q;
  }

  // Q_jj = N_jj^-1 + M_j^T Q_kk M_j and Q_bj = -sum_c Q_bc M_c, once per
  // point (every observation of the point needs them).
  void RecoverPointCofactors() {
    for (PointSystem& point : points_) {
      point.Q = point.N_inverse;
      for (const auto& [b, M_b] : point.M) {
        const ParamBlock& pb = params_[b];
        Eigen::MatrixXd Q_b = Eigen::MatrixXd::Zero(pb.size, 3);
        for (const auto& [c, M_c] : point.M) {
          const ParamBlock& pc = params_[c];
          Q_b.noalias() -=
              Q_kk_.block(pb.offset, pc.offset, pb.size, pc.size) * M_c;
        }
        point.Q.noalias() -= M_b.transpose() * Q_b;
        point.Q_kept[b] = std::move(Q_b);
      }
    }
  }

  const Eigen::Matrix3d& MinimalPointCofactor(const PointSystem& point) const {
    return point.Q;
  }

  // Q_kj for the rows of kept block `id` (zero when the block does not
  // observe the point).
  Eigen::MatrixXd KeptPointCofactor(int id, const PointSystem& point) const {
    auto it = point.Q_kept.find(id);
    if (it != point.Q_kept.end()) return it->second;
    return Eigen::MatrixXd::Zero(params_[id].size, 3);
  }

  void ComputeResidualCofactors() {
    result_.observations.assign(block_->observations.size(), {});
    result_.control_residual.assign(block_->points.size(),
                                    Eigen::Vector3d::Zero());
    result_.control_redundancy.assign(block_->points.size(),
                                      Eigen::Vector3d::Zero());
    result_.distance_residual.assign(block_->distances.size(), 0.0);
    result_.distance_redundancy.assign(block_->distances.size(), 0.0);
    for (size_t t = 0; t < terms_.size(); ++t) {
      const ResidualTerm& term = terms_[t];
      const TermJacobian& jacobian = jacobians_[t];
      Eigen::MatrixXd J(term.num_residuals(), 0);
      for (const Eigen::MatrixXd& J_b : jacobian.J) {
        Eigen::MatrixXd wider(J.rows(), J.cols() + J_b.cols());
        wider << J, J_b;
        J = std::move(wider);
      }
      const Eigen::MatrixXd Q = TermCofactor(jacobian);
      const Eigen::VectorXd q_lhat = (J * Q * J.transpose()).diagonal();
      const Eigen::VectorXd redundancy =
          (Eigen::VectorXd::Ones(q_lhat.size()) - q_lhat)
              .cwiseMax(0.0)
              .cwiseMin(1.0);
      if (term.type == TermType::kReprojection) {
        const BlockObservation& observation = block_->observations[term.index];
        ObservationStatistics& stats = result_.observations[term.index];
        stats.valid = true;
        stats.residual_px =
            ObservationSqrtInformation(observation, block_->sigma0_px)
                .inverse() *
            jacobian.residual;
        stats.redundancy = redundancy;
        for (int k = 0; k < 2; ++k) {
          if (!stats.Testable(k)) continue;
          stats.normalized(k) = jacobian.residual(k) /
                                (result_.sigma0 * std::sqrt(redundancy(k)));
        }
      } else if (term.type == TermType::kPointPrior) {
        const BlockPoint& point = block_->points[term.index];
        result_.control_residual[term.index] = point.xyz - point.given_xyz;
        result_.control_redundancy[term.index] = redundancy;
        for (int k = 0; k < 3; ++k) {
          if (point.fixed[k]) result_.control_redundancy[term.index](k) = 0;
        }
      } else {
        const BlockDistance& distance = block_->distances[term.index];
        result_.distance_residual[term.index] =
            jacobian.residual(0) * distance.sigma_m / block_->sigma0_px;
        result_.distance_redundancy[term.index] = redundancy(0);
      }
    }
  }

  AdjustmentBlock* block_;
  PrecisionOptions options_;
  AdjustmentPrecision result_;
  std::vector<ResidualTerm> terms_;
  std::unordered_map<double*, int> block_ids_;
  std::vector<ParamBlock> params_;
  std::vector<TermJacobian> jacobians_;
  std::vector<PointSystem> points_;
  int num_kept_ = 0;
  Eigen::MatrixXd N_kk_;
  Eigen::MatrixXd Q_kk_;
  // Inner constraints.
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  std::vector<bool> datum_points_;  // InnerConstraintPoints of the block
  std::vector<Eigen::Matrix<double, 7, 3>> H_;
  Eigen::MatrixXd HQ_kept_;
  std::vector<Eigen::Matrix<double, 7, 3>> HQ_point_;
  Eigen::Matrix<double, 7, 7> HQH_ = Eigen::Matrix<double, 7, 7>::Zero();
  Eigen::MatrixXd G_kept_;
};

}  // namespace

AdjustmentPrecision ComputePrecision(AdjustmentBlock* block,
                                     const PrecisionOptions& options) {
  return PrecisionComputer(block, options).Compute();
}

Eigen::MatrixXd CorrelationFromCovariance(const Eigen::MatrixXd& covariance) {
  const Eigen::Index n = covariance.rows();
  Eigen::MatrixXd correlation = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) {
      const double d = covariance(i, i) * covariance(j, j);
      if (d > 0) correlation(i, j) = covariance(i, j) / std::sqrt(d);
    }
  }
  return correlation;
}

}  // namespace bayon

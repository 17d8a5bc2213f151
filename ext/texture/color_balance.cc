// SPDX-License-Identifier: BSD-3-Clause
#include "ext/texture/color_balance.h"

#include "ext/core/errors.h"
#include "ext/core/union_find.h"

#include <Eigen/Dense>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>

namespace bayon {
namespace {

// Two photographs' mean colours of one face, in [0, 1].
struct ColorPair {
  int j, k;
  Eigen::Vector3f mj, mk;
  // 1 / (views of the face - 1): each observation of a face counts alike,
  // however many photographs see the face.
  float weight;
};

std::vector<ColorPair> OverlapPairs(
    const std::vector<std::vector<FaceColor>>& faces,
    int num_images,
    const ColorBalanceOptions& options,
    ColorBalanceReport* report) {
  const size_t max_faces = static_cast<size_t>(options.max_faces);
  const size_t stride = (faces.size() + max_faces - 1) / max_faces;
  std::vector<ColorPair> pairs;
  std::vector<const FaceColor*> usable;
  for (size_t f = 0; f < faces.size(); f += stride) {
    usable.clear();
    for (const FaceColor& c : faces[f]) {
      if (c.image < 0 || c.image >= num_images) {
        ThrowInputError("exposure balance: face ",
                        f,
                        " names photograph ",
                        c.image,
                        " of ",
                        num_images);
      }
      if (c.color.maxCoeff() < options.saturated) usable.push_back(&c);
    }
    if (usable.size() < 2) continue;
    ++report->num_faces;
    const float weight = 1.0f / static_cast<float>(usable.size() - 1);
    for (size_t a = 0; a < usable.size(); ++a) {
      for (size_t b = a + 1; b < usable.size(); ++b) {
        pairs.push_back({usable[a]->image,
                         usable[b]->image,
                         usable[a]->color / 255.0f,
                         usable[b]->color / 255.0f,
                         weight});
      }
    }
  }
  report->num_pairs = static_cast<int>(pairs.size());
  return pairs;
}

// Residual of one pair in one channel under the corrections x = (a, b).
double Residual(const ColorPair& p,
                int channel,
                const Eigen::VectorXd& x,
                int num_images) {
  return x[p.j] * p.mj[channel] + x[num_images + p.j] - x[p.k] * p.mk[channel] -
         x[num_images + p.k];
}

// Robust standard deviation: 1.4826 times the median absolute value.
double RobustSigma(std::vector<double> values) {
  if (values.empty()) return 0.0;
  for (double& v : values) v = std::abs(v);
  const auto middle = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), middle, values.end());
  return 1.4826 * *middle;
}

std::vector<double> Residuals(const std::vector<ColorPair>& pairs,
                              int channel,
                              const Eigen::VectorXd& x,
                              int num_images) {
  std::vector<double> r(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) {
    r[i] = Residual(pairs[i], channel, x, num_images);
  }
  return r;
}

// One channel's gains (x[0, n)) and offsets (x[n, 2n)): Huber-weighted
// least squares with the mean gain held at 1 and the mean offset at 0
// (Lagrange multipliers), and a faint pull to the identity for a
// photograph that overlaps none.
Eigen::VectorXd SolveChannel(const std::vector<ColorPair>& pairs,
                             int channel,
                             int n,
                             const ColorBalanceOptions& options) {
  Eigen::VectorXd x(2 * n);
  x << Eigen::VectorXd::Ones(n), Eigen::VectorXd::Zero(n);
  for (int iteration = 0; iteration < options.num_iterations; ++iteration) {
    const std::vector<double> r = Residuals(pairs, channel, x, n);
    const double threshold = std::max(options.huber_k * RobustSigma(r), 1e-6);
    Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(2 * n + 2, 2 * n + 2);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(2 * n + 2);
    std::vector<double> data_weight(n, 0.0);  // of each photograph's pairs
    for (size_t i = 0; i < pairs.size(); ++i) {
      const ColorPair& p = pairs[i];
      const double w =
          p.weight * std::min(1.0, threshold / std::max(std::abs(r[i]), 1e-12));
      data_weight[p.j] += w;
      data_weight[p.k] += w;
      const int index[4] = {p.j, n + p.j, p.k, n + p.k};
      const double row[4] = {p.mj[channel], 1.0, -p.mk[channel], -1.0};
      for (int a = 0; a < 4; ++a) {
        for (int b = 0; b < 4; ++b) {
          kkt(index[a], index[b]) += w * row[a] * row[b];
        }
      }
    }
    // The prior (Brown and Lowe's gain compensation): each photograph's
    // gain near 1 and offset near 0, weighed like its overlaps, in units
    // of the colours' noise. Without it a group of photographs can agree
    // by all turning flat (gain near 0, offset the mean colour), which
    // the overlaps alone barely pay for.
    const double noise = options.sigma_noise / 255.0;
    const double gain_prior = std::pow(noise / options.sigma_gain, 2);
    const double offset_prior =
        std::pow(noise / (options.sigma_offset / 255.0), 2);
    const double ridge = 1e-6 * std::max(kkt.trace() / (2 * n), 1e-12);
    for (int i = 0; i < n; ++i) {
      kkt(i, i) += ridge + gain_prior * data_weight[i];
      rhs[i] += ridge + gain_prior * data_weight[i];
      kkt(n + i, n + i) += ridge + offset_prior * data_weight[i];
    }
    for (int i = 0; i < n; ++i) {
      kkt(2 * n, i) = kkt(i, 2 * n) = 1.0 / n;                  // mean gain
      kkt(2 * n + 1, n + i) = kkt(n + i, 2 * n + 1) = 1.0 / n;  // mean offset
    }
    rhs[2 * n] = 1.0;
    x = kkt.partialPivLu().solve(rhs).head(2 * n);
  }
  return x;
}

}  // namespace

void ColorBalanceOptions::Check() const {
  CheckOption(num_iterations >= 1, "num_iterations", ">= 1", num_iterations);
  CheckOption(huber_k > 0, "huber_k", "> 0", huber_k);
  CheckOption(max_faces >= 1, "max_faces", ">= 1", max_faces);
  CheckOption(sigma_noise > 0, "sigma_noise", "> 0", sigma_noise);
  CheckOption(sigma_gain > 0, "sigma_gain", "> 0", sigma_gain);
  CheckOption(sigma_offset > 0, "sigma_offset", "> 0", sigma_offset);
  CheckOption(
      saturated > 0 && saturated <= 255, "saturated", "in (0, 255]", saturated);
}

std::vector<GainOffset> BalanceExposures(
    const std::vector<std::vector<FaceColor>>& faces,
    int num_images,
    const ColorBalanceOptions& options,
    ColorBalanceReport* report) {
  options.Check();
  ColorBalanceReport local;
  if (report == nullptr) report = &local;
  *report = ColorBalanceReport();
  std::vector<GainOffset> corrections(num_images);
  const std::vector<ColorPair> pairs =
      OverlapPairs(faces, num_images, options, report);
  if (pairs.empty()) return corrections;
  // The photographs linked by shared faces, group by group: the overlaps
  // fix only the ratios within a group, so each group keeps its own mean
  // gain 1 and mean offset 0, and a photograph in no pair stays as it is
  // (one mean over all would let the groups trade their gains freely).
  UnionFind linked(num_images);
  for (const ColorPair& p : pairs) linked.Union(p.j, p.k);
  std::map<size_t, std::vector<int>> members;  // by root: the photographs
  std::vector<int> index_in_group(num_images);
  for (int j = 0; j < num_images; ++j) {
    std::vector<int>& group = members[linked.Find(j)];
    index_in_group[j] = static_cast<int>(group.size());
    group.push_back(j);
  }
  std::map<size_t, std::vector<ColorPair>> groups;  // by root, group indices
  for (ColorPair p : pairs) {
    const size_t r = linked.Find(p.j);
    p.j = index_in_group[p.j];
    p.k = index_in_group[p.k];
    groups[r].push_back(p);
  }
  std::vector<double> before[3], after[3];
  for (const auto& [r, group] : groups) {
    const std::vector<int>& images = members.at(r);
    const int n = static_cast<int>(images.size());
    Eigen::VectorXd start(2 * n);
    start << Eigen::VectorXd::Ones(n), Eigen::VectorXd::Zero(n);
    for (int c = 0; c < 3; ++c) {
      const Eigen::VectorXd x = SolveChannel(group, c, n, options);
      for (int i = 0; i < n; ++i) {
        corrections[images[i]].gain[c] = static_cast<float>(x[i]);
        corrections[images[i]].offset[c] = static_cast<float>(255.0 * x[n + i]);
      }
      for (double v : Residuals(group, c, start, n)) before[c].push_back(v);
      for (double v : Residuals(group, c, x, n)) after[c].push_back(v);
    }
  }
  report->num_groups = static_cast<int>(groups.size());
  for (int c = 0; c < 3; ++c) {
    report->sigma_before += 255.0 * RobustSigma(before[c]) / 3.0;
    report->sigma_after += 255.0 * RobustSigma(after[c]) / 3.0;
  }
  return corrections;
}

cv::Mat ApplyGainOffset(const cv::Mat& bgr, const GainOffset& correction) {
  CHECK_EQ(bgr.type(), CV_8UC3);
  std::vector<cv::Mat> channels;
  cv::split(bgr, channels);
  for (int c = 0; c < 3; ++c) {
    channels[c].convertTo(
        channels[c], CV_8U, correction.gain[c], correction.offset[c]);
  }
  cv::Mat corrected;
  cv::merge(channels, corrected);
  return corrected;
}

void SeamLevelingOptions::Check() const {
  CheckOption(smoothness > 0, "smoothness", "> 0", smoothness);
  CheckOption(regularization > 0, "regularization", "> 0", regularization);
  CheckOption(
      samples_per_edge >= 1, "samples_per_edge", ">= 1", samples_per_edge);
}

namespace {

// The adjustments of the normal equations, by conjugate gradients (the
// system is a graph Laplacian plus the border terms: large, sparse, well
// enough conditioned by the regularisation).
Eigen::MatrixXd SolveLevelling(const Eigen::SparseMatrix<double>& normal,
                               const Eigen::MatrixXd& rhs,
                               SeamLevelingReport* report) {
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>,
                           Eigen::Lower | Eigen::Upper>
      solver;
  solver.setMaxIterations(1000);
  solver.setTolerance(1e-4);
  solver.compute(normal);
  Eigen::MatrixXd g(rhs.rows(), 3);
  for (int c = 0; c < 3; ++c) {
    g.col(c) = solver.solve(rhs.col(c));
    report->solver_iterations = std::max(report->solver_iterations,
                                         static_cast<int>(solver.iterations()));
    report->solver_error = std::max(report->solver_error, solver.error());
  }
  if (solver.info() != Eigen::Success) {
    LOG(WARNING) << "seam levelling: conjugate gradients stopped after "
                 << report->solver_iterations << " iterations at relative "
                 << "residual " << report->solver_error;
  }
  return g;
}

}  // namespace

std::vector<std::array<Eigen::Vector3f, 3>> LevelSeams(
    const TriangleMesh& mesh,
    const std::vector<int>& chart,
    const std::vector<TwoFaceEdge>& edges,
    const FaceColorAt& color_at,
    const SeamLevelingOptions& options,
    SeamLevelingReport* report) {
  options.Check();
  CHECK_EQ(chart.size(), mesh.NumFaces());
  SeamLevelingReport local;
  if (report == nullptr) report = &local;
  *report = SeamLevelingReport();
  const int num_faces = static_cast<int>(mesh.NumFaces());
  std::vector<std::array<Eigen::Vector3f, 3>> adjustment(
      num_faces,
      {Eigen::Vector3f::Zero(),
       Eigen::Vector3f::Zero(),
       Eigen::Vector3f::Zero()});

  // One unknown per (vertex, chart): the keys of all face corners, sorted.
  auto key = [&](int face, int k) {
    return (static_cast<uint64_t>(mesh.faces[face][k]) << 32) |
           static_cast<uint32_t>(chart[face]);
  };
  std::vector<uint64_t> keys;
  keys.reserve(3 * num_faces);
  for (int face = 0; face < num_faces; ++face) {
    if (chart[face] < 0) continue;
    for (int k = 0; k < 3; ++k) keys.push_back(key(face, k));
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  const int n = static_cast<int>(keys.size());
  report->num_unknowns = n;
  auto unknown = [&](int face, int k) {
    return static_cast<int>(
        std::lower_bound(keys.begin(), keys.end(), key(face, k)) -
        keys.begin());
  };
  auto corner_of = [&](int face, int vertex) {
    for (int k = 0; k < 3; ++k) {
      if (mesh.faces[face][k] == vertex) return k;
    }
    return -1;
  };

  // Normal equations from triplets (duplicates are summed).
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 3);
  // The chart borders: at samples along each edge, the two sides' colours
  // plus their interpolated adjustments should agree.
  struct Sample {
    int index[4];
    double coefficient[4];
    Eigen::Vector3f difference;  // side g minus side f
  };
  std::vector<Sample> samples;
  for (const TwoFaceEdge& e : edges) {
    if (chart[e.f] < 0 || chart[e.g] < 0 || chart[e.f] == chart[e.g]) {
      continue;
    }
    const int fa = corner_of(e.f, e.a), fb = corner_of(e.f, e.b);
    const int ga = corner_of(e.g, e.a), gb = corner_of(e.g, e.b);
    if (fa < 0 || fb < 0 || ga < 0 || gb < 0) continue;
    const size_t num_samples = samples.size();
    for (int s = 0; s < options.samples_per_edge; ++s) {
      const double t = (s + 0.5) / options.samples_per_edge;
      Eigen::Vector3d bf = Eigen::Vector3d::Zero(), bg = bf;
      bf[fa] = bg[ga] = 1.0 - t;
      bf[fb] = bg[gb] = t;
      Eigen::Vector3f cf, cg;
      if (!color_at(e.f, bf, &cf) || !color_at(e.g, bg, &cg)) continue;
      samples.push_back({{unknown(e.f, fa),
                          unknown(e.f, fb),
                          unknown(e.g, ga),
                          unknown(e.g, gb)},
                         {1.0 - t, t, -(1.0 - t), -t},
                         cg - cf});
    }
    report->num_seam_edges += samples.size() > num_samples;
  }
  // A border edge's samples weigh 1 together.
  const double sample_weight = 1.0 / options.samples_per_edge;
  for (const Sample& s : samples) {
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        triplets.emplace_back(
            s.index[a],
            s.index[b],
            sample_weight * s.coefficient[a] * s.coefficient[b]);
      }
      rhs.row(s.index[a]) += sample_weight * s.coefficient[a] *
                             s.difference.cast<double>().transpose();
    }
  }
  // Within a chart: neighbouring vertices change alike. An inner edge is
  // met from both its faces, so each meeting weighs half.
  const double half = 0.5 * options.smoothness;
  for (int face = 0; face < num_faces; ++face) {
    if (chart[face] < 0) continue;
    for (int k = 0; k < 3; ++k) {
      const int u = unknown(face, k), v = unknown(face, (k + 1) % 3);
      triplets.emplace_back(u, u, half);
      triplets.emplace_back(v, v, half);
      triplets.emplace_back(u, v, -half);
      triplets.emplace_back(v, u, -half);
    }
  }
  for (int i = 0; i < n; ++i) {
    triplets.emplace_back(i, i, options.regularization);
  }
  if (samples.empty()) return adjustment;
  Eigen::SparseMatrix<double> normal(n, n);
  normal.setFromTriplets(triplets.begin(), triplets.end());
  triplets.clear();
  triplets.shrink_to_fit();

  const Eigen::MatrixXd g = SolveLevelling(normal, rhs, report);

  double before = 0, after = 0;
  for (const Sample& s : samples) {
    Eigen::Vector3d shift = Eigen::Vector3d::Zero();
    for (int a = 0; a < 4; ++a) {
      shift += s.coefficient[a] * g.row(s.index[a]).transpose();
    }
    before += s.difference.cwiseAbs().mean();
    after += (s.difference.cast<double>() - shift).cwiseAbs().mean();
  }
  report->difference_before = before / samples.size();
  report->difference_after = after / samples.size();

  for (int face = 0; face < num_faces; ++face) {
    if (chart[face] < 0) continue;
    for (int k = 0; k < 3; ++k) {
      adjustment[face][k] = g.row(unknown(face, k)).transpose().cast<float>();
    }
  }
  return adjustment;
}

}  // namespace bayon

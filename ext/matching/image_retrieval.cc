// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/image_retrieval.h"

#include "ext/core/errors.h"
#include "ext/core/parallel.h"
#include "ext/core/progress.h"
#include "ext/features/sift.h"
#include "ext/image/image_io.h"
#include "ext/matching/descriptor_matcher.h"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <set>

namespace bayon {

void RetrievalOptions::Register(OptionRegistry* r) {
  r->Add("max_image_size",
         &max_image_size,
         "Long side the photographs are reduced to, px");
  r->Add(
      "max_num_features", &max_num_features, "SIFT descriptors per photograph");
  r->Add(
      "vocabulary_size", &vocabulary_size, "Visual words learnt from the set");
  r->Add(
      "shortlist_size", &shortlist_size, "Candidates matched per photograph");
}

void RetrievalOptions::Check() const {
  CheckOption(max_image_size >= 64, "max_image_size", ">= 64", max_image_size);
  CheckOption(
      max_num_features >= 10, "max_num_features", ">= 10", max_num_features);
  CheckOption(vocabulary_size >= 2, "vocabulary_size", ">= 2", vocabulary_size);
  CheckOption(shortlist_size >= 1, "shortlist_size", ">= 1", shortlist_size);
}

namespace {

// A photograph's SIFT descriptors at the reduced size.
FeatureDescriptors Describe(const std::string& file,
                            const RetrievalOptions& options) {
  SiftOptions sift;
  sift.max_image_size = options.max_image_size;
  sift.max_num_features = options.max_num_features;
  return DetectSiftFeatures(ReadImageGrayFloat(file), sift).descriptors;
}

// k-means centres (k x 128) of every `stride`-th descriptor of each
// photograph, k-means++ started from OpenCV's generator at a fixed seed.
// The samples are sorted first, so that neither the run nor the order of
// the photographs changes the vocabulary.
UnitDescriptors LearnVocabulary(
    const std::vector<FeatureDescriptors>& descriptors, int k) {
  int total = 0;
  for (const FeatureDescriptors& d : descriptors) {
    total += static_cast<int>(d.rows());
  }
  constexpr int kMaxSamples = 50000;
  const int stride = std::max(1, total / kMaxSamples);
  std::vector<std::vector<uint8_t>> rows;
  for (const FeatureDescriptors& d : descriptors) {
    for (int i = 0; i < d.rows(); i += stride) {
      rows.emplace_back(d.row(i).data(), d.row(i).data() + 128);
    }
  }
  std::sort(rows.begin(), rows.end());
  FeatureDescriptors sorted(rows.size(), 128);
  for (size_t r = 0; r < rows.size(); ++r) {
    std::copy(rows[r].begin(), rows[r].end(), sorted.row(r).data());
  }
  UnitDescriptors unit = ToUnitDescriptors(sorted);
  const cv::Mat samples(
      static_cast<int>(unit.rows()), 128, CV_32F, unit.data());
  k = std::min(k, std::max(2, samples.rows / 20));
  cv::theRNG().state = 0x5eed;
  cv::Mat labels, centers;
  cv::kmeans(samples,
             k,
             labels,
             cv::TermCriteria(
                 cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 20, 1e-4),
             1,
             cv::KMEANS_PP_CENTERS,
             centers);
  return Eigen::Map<const UnitDescriptors>(
      centers.ptr<float>(), centers.rows, 128);
}

// Word counts: each descriptor's nearest centre,
// argmax_c (d . c - |c|^2 / 2).
Eigen::VectorXd CountWords(const UnitDescriptors& descriptors,
                           const UnitDescriptors& vocabulary) {
  Eigen::VectorXd counts = Eigen::VectorXd::Zero(vocabulary.rows());
  if (descriptors.rows() == 0) return counts;
  const Eigen::VectorXf half_norms =
      0.5f * vocabulary.rowwise().squaredNorm().transpose();
  const UnitDescriptors scores = descriptors * vocabulary.transpose();
  for (int i = 0; i < scores.rows(); ++i) {
    Eigen::Index word = 0;
    (scores.row(i) - half_norms.transpose()).maxCoeff(&word);
    counts(word) += 1;
  }
  return counts;
}

// The cosines of the photographs' tf-idf weighted word histograms.
// (The bytes give the vocabulary's sample its order; `unit` are the same
// descriptors as unit vectors.)
Eigen::MatrixXd WordSimilarities(
    const std::vector<FeatureDescriptors>& descriptors,
    const std::vector<UnitDescriptors>& unit,
    const RetrievalOptions& options) {
  const int n = static_cast<int>(descriptors.size());
  const UnitDescriptors vocabulary =
      LearnVocabulary(descriptors, options.vocabulary_size);
  const int k = static_cast<int>(vocabulary.rows());
  Eigen::MatrixXd histograms(k, n);
  for (int i = 0; i < n; ++i) {
    histograms.col(i) = CountWords(unit[i], vocabulary);
  }
  // tf-idf: term frequency times log(n / photographs with the word).
  for (int w = 0; w < k; ++w) {
    const int seen = static_cast<int>((histograms.row(w).array() > 0).count());
    const double idf = seen > 0 ? std::log(static_cast<double>(n) / seen) : 0;
    histograms.row(w) *= idf;
  }
  for (int i = 0; i < n; ++i) {
    const double norm = histograms.col(i).norm();
    if (norm > 0) histograms.col(i) /= norm;
  }
  return histograms.transpose() * histograms;
}

}  // namespace

std::vector<int> MostSimilar(const Eigen::MatrixXd& similarity, int i, int k) {
  std::vector<int> others;
  for (int j = 0; j < similarity.cols(); ++j) {
    if (j != i) others.push_back(j);
  }
  std::stable_sort(others.begin(), others.end(), [&](int a, int b) {
    return similarity(i, a) > similarity(i, b);
  });
  others.resize(std::min<size_t>(others.size(), std::max(k, 0)));
  return others;
}

Eigen::MatrixXd ImageSimilarities(const std::vector<std::string>& image_files,
                                  const RetrievalOptions& options) {
  options.Check();
  const int n = static_cast<int>(image_files.size());
  std::vector<FeatureDescriptors> descriptors(n);
  std::vector<UnitDescriptors> unit(n);
  {
    Progress progress("Describing photographs for retrieval", n, "images");
    ParallelFor(n, options.num_threads, [&](int i) {
      descriptors[i] = Describe(image_files[i], options);
      unit[i] = ToUnitDescriptors(descriptors[i]);
      progress.Add();
    });
    progress.Finish();
  }
  Eigen::MatrixXd similarity = Eigen::MatrixXd::Identity(n, n);
  if (n < 2) return similarity;
  // Words only where they have something to leave out.
  const Eigen::MatrixXd words =
      n - 1 > options.shortlist_size
          ? WordSimilarities(descriptors, unit, options)
          : Eigen::MatrixXd::Ones(n, n);

  // The shortlist: for each photograph its most alike by words.
  std::set<std::pair<int, int>> shortlist;
  for (int i = 0; i < n; ++i) {
    for (int j : MostSimilar(words, i, options.shortlist_size)) {
      shortlist.insert({std::min(i, j), std::max(i, j)});
    }
  }
  const std::vector<std::pair<int, int>> pairs(shortlist.begin(),
                                               shortlist.end());
  Progress progress("Matching shortlisted photographs", pairs.size(), "pairs");
  std::vector<double> shares(pairs.size(), 0.0);
  ParallelFor(pairs.size(), options.num_threads, [&](int k) {
    const auto [i, j] = pairs[k];
    const size_t matched =
        MatchDescriptors(unit[i], unit[j], DescriptorMatchingOptions()).size();
    const double fewer =
        static_cast<double>(std::min(unit[i].rows(), unit[j].rows()));
    shares[k] = fewer > 0 ? matched / fewer : 0.0;
    progress.Add();
  });
  progress.Finish();
  for (size_t k = 0; k < pairs.size(); ++k) {
    const auto [i, j] = pairs[k];
    similarity(i, j) = similarity(j, i) = shares[k];
  }
  return similarity;
}

}  // namespace bayon

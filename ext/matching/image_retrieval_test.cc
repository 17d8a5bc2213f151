// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/image_retrieval.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "tests/testing.h"

namespace bayon {
namespace {

// The index of the photograph most like photograph i.
int MostAlike(const Eigen::MatrixXd& similarity, int i) {
  int best = -1;
  for (int j = 0; j < similarity.cols(); ++j) {
    if (j != i && (best < 0 || similarity(i, j) > similarity(i, best))) {
      best = j;
    }
  }
  return best;
}

// fountain-P11's photographs were taken along the facade in name order:
// each one looks most like a neighbour along that line, whichever order the
// files are given in.
TEST(ImageRetrieval, FacadeNeighboursAreMostAlikeInAnyOrder) {
  BAYON_REQUIRE_DATA("fountain-P11");
  std::vector<std::string> files;
  for (int i = 0; i <= 10; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "fountain-P11/images/%04d.jpg", i);
    files.push_back(testing::DataPath(name));
  }
  RetrievalOptions options;
  options.num_threads = 2;
  const Eigen::MatrixXd similarity = ImageSimilarities(files, options);
  ASSERT_EQ(similarity.rows(), 11);
  EXPECT_TRUE(similarity.isApprox(similarity.transpose()));
  EXPECT_LE(similarity.maxCoeff(), 1 + 1e-9);
  EXPECT_GE(similarity.minCoeff(), 0);
  for (int i = 0; i <= 10; ++i) {
    const int best = MostAlike(similarity, i);
    EXPECT_LE(std::abs(best - i), 2) << "photograph " << i << ": " << best;
  }
  // A shortlist by visual words of 4 per photograph: the neighbours still
  // on it.
  RetrievalOptions shortlisted = options;
  shortlisted.shortlist_size = 4;
  const Eigen::MatrixXd similarity_words =
      ImageSimilarities(files, shortlisted);
  for (int i = 0; i <= 10; ++i) {
    EXPECT_EQ(MostAlike(similarity_words, i), MostAlike(similarity, i))
        << "photograph " << i;
    EXPECT_LE((similarity_words.row(i).array() > 0).count(), 11 - 4)
        << "photograph " << i << ": some pairs are not on any shortlist";
  }
  // Reversed: the same neighbours.
  std::vector<std::string> reversed(files.rbegin(), files.rend());
  const Eigen::MatrixXd similarity_reversed =
      ImageSimilarities(reversed, options);
  for (int i = 0; i <= 10; ++i) {
    EXPECT_EQ(10 - MostAlike(similarity_reversed, 10 - i),
              MostAlike(similarity, i))
        << "photograph " << i;
  }
}

TEST(ImageRetrieval, RefusesBadOptionsAndFiles) {
  RetrievalOptions options;
  options.vocabulary_size = 1;
  EXPECT_THROW(options.Check(), InputError);
  EXPECT_THROW(ImageSimilarities({"/nonexistent/a.png", "/nonexistent/b.png"},
                                 RetrievalOptions()),
               InputError);
}

}  // namespace
}  // namespace bayon

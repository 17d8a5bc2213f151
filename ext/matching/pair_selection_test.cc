// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/pair_selection.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>

#include <set>

#include "tests/testing.h"

namespace bayon {
namespace {

// Five images whose ids do not follow their names.
std::vector<DatabaseImage> FiveImages() {
  std::vector<DatabaseImage> images;
  const char* names[] = {"c.png", "a.png", "e.png", "b.png", "d.png"};
  for (int i = 0; i < 5; ++i) {
    DatabaseImage image;
    image.image_id = i + 1;
    image.name = names[i];
    images.push_back(image);
  }
  return images;
}

std::set<std::pair<image_t, image_t>> AsSet(
    const std::vector<std::pair<image_t, image_t>>& pairs) {
  std::set<std::pair<image_t, image_t>> set(pairs.begin(), pairs.end());
  EXPECT_EQ(set.size(), pairs.size()) << "repeated pairs";
  for (const auto& [a, b] : pairs) EXPECT_LT(a, b);
  return set;
}

// Auto matches every pair up to its limit, then the most similar ones;
// retrieval ignores the names: images that look alike are paired whatever
// their order.
TEST(PairSelection, AutoAndRetrievalFollowSimilarityNotNames) {
  // Similar: ids 1-2, 2-3, 3-4, 4-5 (a chain in id order, which the names
  // scramble); everything else unlike.
  Eigen::MatrixXd similarity = Eigen::MatrixXd::Identity(5, 5);
  for (int i = 0; i + 1 < 5; ++i) {
    similarity(i, i + 1) = similarity(i + 1, i) = 0.5 + 0.1 * i;
  }
  PairingOptions options;
  EXPECT_EQ(options.mode, PairingMode::kAuto);
  EXPECT_FALSE(UsesRetrieval(options, 5));
  EXPECT_EQ(SelectImagePairs(FiveImages(), options).size(), 10u);
  options.max_exhaustive_images = 4;
  EXPECT_TRUE(UsesRetrieval(options, 5));
  options.retrieval_neighbors = 1;
  const auto chain =
      AsSet(SelectImagePairs(FiveImages(), options, &similarity));
  const std::set<std::pair<image_t, image_t>> expected = {
      {1, 2}, {2, 3}, {3, 4}, {4, 5}};
  EXPECT_EQ(chain, expected);
  options.mode = PairingMode::kRetrieval;
  options.max_exhaustive_images = 50;
  EXPECT_TRUE(UsesRetrieval(options, 5));
  EXPECT_EQ(AsSet(SelectImagePairs(FiveImages(), options, &similarity)),
            expected);
  // Two neighbours each: the chain and its second links.
  options.retrieval_neighbors = 2;
  EXPECT_GT(SelectImagePairs(FiveImages(), options, &similarity).size(), 4u);
  options.retrieval_neighbors = 0;
  EXPECT_THROW(options.Check(), InputError);
}

TEST(PairSelection, RingWrapsAroundInNameOrder) {
  PairingOptions options;
  options.mode = PairingMode::kRing;
  options.num_neighbors = 1;
  // Name order a(2) b(4) c(1) d(5) e(3), then back to a.
  const auto ring = AsSet(SelectImagePairs(FiveImages(), options));
  const std::set<std::pair<image_t, image_t>> expected = {
      {2, 4}, {1, 4}, {1, 5}, {3, 5}, {2, 3}};
  EXPECT_EQ(ring, expected);
  options.num_neighbors = 2;
  EXPECT_EQ(SelectImagePairs(FiveImages(), options).size(), 10u);
  options.mode = PairingMode::kSequential;
  options.num_neighbors = 1;
  EXPECT_EQ(SelectImagePairs(FiveImages(), options).size(), 4u);
  options.num_neighbors = 2;
  EXPECT_EQ(SelectImagePairs(FiveImages(), options).size(), 7u);  // 4 + 3
  options.mode = PairingMode::kExhaustive;
  EXPECT_EQ(SelectImagePairs(FiveImages(), options).size(), 10u);
  // A ring with more neighbours than images repeats nothing.
  options.mode = PairingMode::kRing;
  options.num_neighbors = 7;
  EXPECT_EQ(SelectImagePairs(FiveImages(), options).size(), 10u);
}

TEST(PairSelection, ListFileWithLineNumbersInErrors) {
  const std::string dir = testing::TempDir("pair_list");
  PairingOptions options;
  options.mode = PairingMode::kList;
  options.pair_list_path = dir + "/pairs.txt";
  WriteFileAtomically(options.pair_list_path,
                      "# pairs\n\na.png b.png\nb.png a.png\r\ne.png c.png\n");
  const auto pairs = SelectImagePairs(FiveImages(), options);
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(pairs[0], std::make_pair(image_t{2}, image_t{4}));
  EXPECT_EQ(pairs[1], std::make_pair(image_t{1}, image_t{3}));
  const auto expect_error = [&](const std::string& text,
                                const std::string& message) {
    WriteFileAtomically(options.pair_list_path, text);
    try {
      SelectImagePairs(FiveImages(), options);
      ADD_FAILURE() << "no error for " << text;
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find(message), std::string::npos)
          << error.what();
    }
  };
  expect_error("a.png b.png\nz.png a.png\n", "pairs.txt:2: image 'z.png'");
  expect_error("a.png\n", "pairs.txt:1: expected two image names");
  expect_error("a.png b.png c.png\n", "pairs.txt:1: expected two");
  expect_error("a.png a.png\n", "with itself");
  options.pair_list_path.clear();
  EXPECT_THROW(options.Check(), InputError);
  EXPECT_STREQ(PairingModeName(PairingMode::kRetrieval), "retrieval");
}

}  // namespace
}  // namespace bayon

// The texel search's shrink (run/budget_search.hpp): a chart's border keeps its own colour, whatever
// its gutter holds, and a texel with no chart under it takes the mean of all it covers. Rate control's
// quality search (run/texture_bytes.hpp): the lowest quality that reaches a target, in a few measures.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>

#include "run/budget_search.hpp"
#include "run/texture_bytes.hpp"

namespace tightex {
namespace {

TEST(BudgetSearch, ShrinkKeepsAChartsBorderFromItsGutter) {
  // A 12 x 12 image: a red chart in columns 0..4 (its border column 4 shares each 3 x 3 footprint of
  // the shrunk image with gutter texels), a blue gutter beyond.
  Image image(12, 12, Rgba8{0, 0, 255, 255});
  std::vector<uint8_t> inside(144, 0);
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 5; ++x) image.at(x, y) = {255, 0, 0, 255}, inside[size_t(y * 12 + x)] = 1;
  const Image small = shrink_image(image, inside, 4, 4);
  ASSERT_EQ(small.width, 4);
  ASSERT_EQ(small.height, 4);
  for (int y = 0; y < 4; ++y) {
    EXPECT_EQ(small.at(0, y), (Rgba8{255, 0, 0, 255}));
    EXPECT_EQ(small.at(1, y), (Rgba8{255, 0, 0, 255})) << "the chart's border took its gutter's colour";
    EXPECT_EQ(small.at(3, y), (Rgba8{0, 0, 255, 255}));
  }
  // Without a mask, the same texel is the footprint's mean: 2 of its 3 columns red.
  const Image plain = shrink_image(image, {}, 4, 4);
  EXPECT_EQ(plain.at(1, 0), (Rgba8{170, 0, 85, 255}));
}

TEST(BudgetSearch, ShrinkByAFractionWeighsTexelsByTheirOverlap) {
  // 3 texels into 2: the middle one is half in each new texel.
  Image image(3, 1);
  image.at(0, 0) = {0, 0, 0, 255}, image.at(1, 0) = {90, 90, 90, 255}, image.at(2, 0) = {180, 180, 180, 255};
  const Image small = shrink_image(image, {}, 2, 1);
  EXPECT_EQ(small.at(0, 0).r, 30);   // (0 * 1 + 90 * 0.5) / 1.5
  EXPECT_EQ(small.at(1, 0).r, 150);  // (90 * 0.5 + 180 * 1) / 1.5
}

TEST(BudgetSearch, ShrinkRoundsAMeanHalfwayBetweenLevelsUp) {
  // 2 texels into 1: means of 0.5, 254.5 and 3 (exact) per channel.
  Image image(2, 1);
  image.at(0, 0) = {0, 254, 3, 255}, image.at(1, 0) = {1, 255, 3, 255};
  EXPECT_EQ(shrink_image(image, {}, 1, 1).at(0, 0), (Rgba8{1, 255, 3, 255}));
}

/// A codec's PSNR over its quality: rising, steeper towards the top, a little flat step in the middle.
double codec_curve(int q) { return 28 + 0.12 * q + 6 * std::pow(q / 100.0, 6) + (q >= 60 && q < 63 ? -0.05 : 0); }

TEST(QualitySearch, FindsTheLowestQualityReachingTheTargetInFewRounds) {
  for (const double target : {29.0, 35.0, 38.5, 41.0, 45.9}) {
    int expected = 101;  // by brute force
    for (int q = 100; q >= 1; --q)
      if (codec_curve(q) >= target) expected = q;
    for (const int hint : {0, 1, 10, 50, 90, 100, expected - 5, expected + 3}) {
      std::map<int, int> measured;
      int rounds = 0;
      const int q = lowest_quality_reaching(
          [&](const std::vector<int>& qualities) {
            ++rounds;
            std::vector<double> psnr;
            for (const int quality : qualities) ++measured[quality], psnr.push_back(codec_curve(quality));
            return psnr;
          },
          target, hint);
      EXPECT_EQ(q, expected) << target << " from " << hint;
      EXPECT_LE(rounds, 7) << target << " from " << hint;
      if (std::abs(hint - expected) <= 5) EXPECT_LE(rounds, 4) << target << " from " << hint;
      for (const auto& [quality, times] : measured) EXPECT_EQ(times, 1) << "quality " << quality << " measured again";
    }
  }
}

/// A search whose PSNR is `curve` of each quality, one quality a round.
int search(const std::function<double(int)>& curve, double target, int hint, int* rounds) {
  return lowest_quality_reaching(
      [&](const std::vector<int>& qualities) {
        ++*rounds;
        std::vector<double> psnr;
        for (const int q : qualities) psnr.push_back(curve(q));
        return psnr;
      },
      target, hint);
}

TEST(QualitySearch, NoQualityReachingTheTargetGives101) {
  int rounds = 0;
  EXPECT_EQ(search([](int q) { return 30.0 + q / 100.0; }, 40, 80, &rounds), 101);
  EXPECT_LE(rounds, 3);
  rounds = 0;
  EXPECT_EQ(search([](int) { return 50.0; }, 40, 0, &rounds), 1);
  EXPECT_EQ(search([](int q) { return 30.0 + q / 10.0; }, 38, 1, &rounds), 80);
}

}  // namespace
}  // namespace tightex

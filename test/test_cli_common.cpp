// The command line's own parsers (cli/common.hpp): values typed on the command line become library
// inputs here, and every refusal names the flag.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "common.hpp"
#include "fivebar/error.hpp"

namespace fivebar::cli {
namespace {

TEST(Shard, ParseRules) {
  EXPECT_EQ(parse_shard("0/4"), (std::pair<std::uint64_t, std::uint64_t>{0, 4}));
  EXPECT_EQ(parse_shard("3/4"), (std::pair<std::uint64_t, std::uint64_t>{3, 4}));
  for (const char* bad : {"4/4", "1", "/2", "a/b", "1/0", "-1/3", "1/2x"}) {
    EXPECT_THAT([&] { parse_shard(bad); }, ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("--shard"))) << bad;
  }
}

TEST(Ellipse, ParsesFiveNumbersIntoCentreAxesAndRadians) {
  const Ellipse e = parse_ellipse("6.25, 15.5,15,12,90");
  EXPECT_EQ(e.center, Vec2(6.25, 15.5));
  EXPECT_EQ(e.axes, Vec2(15, 12));
  EXPECT_DOUBLE_EQ(e.angle, std::numbers::pi / 2);
  for (const char* bad : {"1,2,3,4", "1,2,3,4,5,6", "1,2,0,4,0", "1,2,-3,4,0", "1,2,x,4,0", "1,2,3,4,nan", "1e13,0,1,1,0"}) {
    EXPECT_THAT([&] { parse_ellipse(bad); }, ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("--ellipse")))
        << bad;
  }
}

TEST(Point, CoordinatesObeyTheDesignFilesRange) {
  EXPECT_EQ(parse_point_mm("1e12,-1e12", "--point"), (std::array<double, 2>{1e12, -1e12}));
  EXPECT_THAT([] { parse_point_mm("1e200,0", "--point"); },
              ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("--point '1e200,0': coordinate 1e+200 mm")));
}

}  // namespace
}  // namespace fivebar::cli

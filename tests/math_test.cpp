// Tests of the small math helpers against the standard library.
#include "renderer/math.h"
#include "renderer/rng.h"

#include <gtest/gtest.h>

namespace glaze {
namespace {

TEST(FastAtan2, AgreesWithStdAtan2EverywhereIncludingEdges) {
  Pcg32 rng(1);
  for (int k = 0; k < 1000000; ++k) {
    const float scale = std::ldexp(1.0f, int(rng.next_uint() % 60) - 30);
    const float y = (rng.next_float() - 0.5f) * scale, x = (rng.next_float() - 0.5f) * scale;
    ASSERT_NEAR(fast_atan2(y, x), std::atan2(double(y), double(x)), 3e-7) << y << ", " << x;
  }
  const float values[] = {0.0f, -0.0f, 1.0f, -1.0f, 1e-30f, -1e30f, 0.41421356f, 1e-45f};
  for (float y : values)
    for (float x : values) {
      EXPECT_NEAR(fast_atan2(y, x), std::atan2(y, x), 3e-7) << y << ", " << x;
      EXPECT_EQ(std::signbit(fast_atan2(y, x)), std::signbit(std::atan2(y, x))) << y << ", " << x;
    }
}

// sin_cos_turns replaces libm's sincosf in the path tracer's SIMD lanes: within 1e-6 of
// the double-precision functions over a whole turn and beyond, with exact quarter turns.
TEST(SinCosTurns, AgreesWithStdSinCosOverAWholeTurn) {
  for (int k = 0; k <= 200000; ++k) {
    const float t = -0.5f + 2.0f * k / 200000.0f;
    float s = 0.0f, c = 0.0f;
    sin_cos_turns(t, &s, &c);
    ASSERT_NEAR(s, std::sin(2.0 * kPiD * t), 1e-6) << t;
    ASSERT_NEAR(c, std::cos(2.0 * kPiD * t), 1e-6) << t;
  }
  const float quarter[][3] = {{0.0f, 0.0f, 1.0f}, {0.25f, 1.0f, 0.0f}, {0.5f, 0.0f, -1.0f}, {0.75f, -1.0f, 0.0f}};
  for (const auto& q : quarter) {
    float s = 0.0f, c = 0.0f;
    sin_cos_turns(q[0], &s, &c);
    EXPECT_EQ(s, q[1]) << q[0];
    EXPECT_EQ(c, q[2]) << q[0];
  }
}

TEST(Frame, IsOrthonormalWithTheNormalAsZ) {
  Pcg32 rng(2);
  for (int k = 0; k < 1000; ++k) {
    const Vec3 n = Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f).normalized();
    const Frame frame = Frame::from_normal(n);
    EXPECT_NEAR(frame.s.dot(frame.t), 0.0f, 1e-6f);
    EXPECT_NEAR(frame.s.norm(), 1.0f, 1e-6f);
    EXPECT_NEAR(frame.s.cross(frame.t).dot(n), 1.0f, 1e-5f);  // right-handed
    const Vec3 v = Vec3(0.3f, -0.2f, 0.9f);
    EXPECT_LT((frame.to_world(frame.to_local(v)) - v).norm(), 1e-5f);
    EXPECT_NEAR(frame.to_local(n).z(), 1.0f, 1e-6f);
  }
}

}  // namespace
}  // namespace glaze

#include "renderer/procedural_environment.h"

#include "renderer/checked_math.h"
#include "renderer/error.h"
#include "renderer/memory_budget.h"
#include "renderer/latlong.h"

#include <tbb/parallel_for.h>

#include <functional>

namespace glaze {
namespace {

// An axis-aligned room around the origin; the ray from the origin along d leaves it
// through one face.
struct Room {
  Vec3 low, high;

  enum class Face { floor, ceiling, wall_negative_x, wall_positive_x, wall_negative_z, wall_positive_z };
  struct Hit {
    Face face;
    Vec3 point;
  };

  Hit exit(const Vec3& d) const {
    float t_best = std::numeric_limits<float>::infinity();
    Face face = Face::floor;
    auto consider = [&](float component, float bound_low, float bound_high, Face face_low, Face face_high) {
      if (component == 0.0f) return;
      const float t = (component > 0.0f ? bound_high : bound_low) / component;
      if (t < t_best) {
        t_best = t;
        face = component > 0.0f ? face_high : face_low;
      }
    };
    consider(d.x(), low.x(), high.x(), Face::wall_negative_x, Face::wall_positive_x);
    consider(d.y(), low.y(), high.y(), Face::floor, Face::ceiling);
    consider(d.z(), low.z(), high.z(), Face::wall_negative_z, Face::wall_positive_z);
    return {face, t_best * d};
  }
};

float smoothstep(float edge0, float edge1, float x) {
  const float t = clamp01((x - edge0) / (edge1 - edge0));
  return t * t * (3.0f - 2.0f * t);
}

bool inside(float value, float low, float high) { return value >= low && value <= high; }

RGB office(const Vec3& d) {
  const Room room{Vec3(-5.0f, -1.2f, -4.0f), Vec3(5.0f, 1.8f, 4.0f)};
  const auto [face, p] = room.exit(d);
  const float height = (p.y() - room.low.y()) / (room.high.y() - room.low.y());
  const RGB wall = RGB(0.55f, 0.52f, 0.47f) * (0.75f + 0.35f * height);  // brighter near the lights
  switch (face) {
    case Room::Face::ceiling: {
      // 6 x 4 panels of 0.6 x 1.2 m on a 1.5 x 2 m grid.
      for (int ix = 0; ix < 6; ++ix) {
        for (int iz = 0; iz < 4; ++iz) {
          const float cx = -3.75f + 1.5f * ix, cz = -3.0f + 2.0f * iz;
          if (inside(p.x(), cx - 0.3f, cx + 0.3f) && inside(p.z(), cz - 0.6f, cz + 0.6f)) return {26.0f, 25.0f, 22.0f};
        }
      }
      return {0.42f, 0.42f, 0.40f};
    }
    case Room::Face::floor: {
      const bool dark_tile =
          (static_cast<int>(std::floor(p.x() / 0.5f)) + static_cast<int>(std::floor(p.z() / 0.5f))) % 2 != 0;
      return RGB(0.24f, 0.18f, 0.12f) * (dark_tile ? 0.85f : 1.15f);
    }
    case Room::Face::wall_negative_z:  // window: overcast sky, brighter towards the top
      if (inside(p.x(), -2.5f, 2.5f) && inside(p.y(), -0.3f, 1.4f))
        return RGB(2.6f, 3.1f, 4.0f) * (0.8f + 0.4f * (p.y() + 0.3f) / 1.7f);
      return wall;
    case Room::Face::wall_positive_x:  // a wooden door
      if (inside(p.z(), 1.0f, 2.0f) && p.y() < 0.9f) return {0.30f, 0.17f, 0.08f};
      return wall;
    default:
      return wall;
  }
}

RGB blue_room(const Vec3& d) {
  const Room room{Vec3(-3.0f, -1.0f, -3.0f), Vec3(3.0f, 2.0f, 3.0f)};
  const auto [face, p] = room.exit(d);
  const RGB albedo(0.30f, 0.40f, 0.90f);                  // blue paint
  const RGB ambient = albedo * RGB(0.45f, 0.38f, 0.36f);  // light bounced from both spots
  // A projector spot: a disc of light on a wall, bright in the middle, soft at the rim.
  auto spot = [](float du, float dv, float radius) {
    const float r = std::sqrt(du * du + dv * dv) / radius;
    return (1.0f - smoothstep(0.8f, 1.0f, r)) * (1.0f - 0.4f * r * r);
  };
  switch (face) {
    case Room::Face::wall_negative_z:  // the white projector's spot
      return ambient + albedo * RGB(32.0f, 32.0f, 32.0f) * spot(p.x() + 0.8f, p.y() - 0.5f, 0.6f);
    case Room::Face::wall_positive_x:  // the red projector's spot
      return ambient + albedo * RGB(48.0f, 3.0f, 2.0f) * spot(p.z() - 0.6f, p.y() - 0.7f, 0.5f);
    case Room::Face::floor:
      return ambient * 0.6f;
    default:
      return ambient;
  }
}

}  // namespace

const std::vector<std::string>& procedural_environment_names() {
  static const std::vector<std::string> names = {"constant", "office", "blue-room"};
  return names;
}

Image make_procedural_environment(const std::string& name, int width, int height) {
  if (width <= 0 || height <= 0) {
    throw Error("procedural environment '" + name + "': resolution must be positive, got " + std::to_string(width) +
                "x" + std::to_string(height));
  }
  require_memory(saturating_mul(uint64_t(width) * uint64_t(height), sizeof(RGB)),
                 "procedural environment " + std::to_string(width) + "x" + std::to_string(height));
  std::function<RGB(const Vec3&)> radiance;
  if (name == "constant") {
    Image image(width, height);
    std::fill(image.pixels.begin(), image.pixels.end(), 1.0f);
    return image;
  } else if (name == "office") {
    radiance = office;
  } else if (name == "blue-room") {
    radiance = blue_room;
  } else {
    std::string known;
    for (const std::string& n : procedural_environment_names()) known += (known.empty() ? "" : ", ") + n;
    throw Error("unknown procedural environment '" + name + "' (known: " + known + ")");
  }

  Image image(width, height);
  constexpr int kSubsamples = 3;
  tbb::parallel_for(0, height, [&](int j) {
    for (int i = 0; i < width; ++i) {
      RGB sum = RGB::Zero();
      for (int sj = 0; sj < kSubsamples; ++sj) {
        for (int si = 0; si < kSubsamples; ++si) {
          const Vec2 uv((i + (si + 0.5f) / kSubsamples) / width, (j + (sj + 0.5f) / kSubsamples) / height);
          sum += radiance(latlong_to_direction(uv));
        }
      }
      image.set(i, j, sum / float(kSubsamples * kSubsamples));
    }
  });
  return image;
}

}  // namespace glaze

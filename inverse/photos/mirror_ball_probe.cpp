#include "inverse/photos/mirror_ball_probe.h"

#include "renderer/error.h"
#include "renderer/latlong.h"
#include "renderer/image_lookup.h"
#include "renderer/memory_budget.h"
#include "renderer/output_folder.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace glaze {

Mat3 probe_to_board() {
  Mat3 m;
  m << 1, 0, 0,  //
      0, 0, -1,  //
      0, 1, 0;
  return m;
}

std::optional<BallReflection> ball_point_reflecting(const Vec3d& origin, const Vec3d& direction,
                                                    const MirrorBall& ball) {
  const Vec3d to_origin = origin - ball.center;
  const double distance = to_origin.norm(), r = ball.radius;
  if (!(distance > r)) return std::nullopt;
  const Vec3d e1 = to_origin / distance;
  // e2: the plane's second axis, towards `direction` (any perpendicular when it is e1).
  Vec3d across = direction - direction.dot(e1) * e1;
  if (across.norm() < 1e-12) across = e1.unitOrthogonal();
  const Vec3d e2 = across.normalized();
  const double delta = std::atan2(direction.dot(e2), direction.dot(e1));  // in [0, pi]
  // The normal at angle a from e1 (towards e2) sees the origin at angle
  // beta(a) = -atan2(r sin a, D - r cos a); it reflects `direction` when it bisects the
  // two: f(a) = 2a - delta - beta(a) = 0. The visible cap ends at the outline,
  // a_max = acos(r / D), where f = a_max + pi/2 - delta: beyond, the ball hides it.
  const double a_max = std::acos(r / distance);
  if (delta > a_max + 0.5 * kPiD) return std::nullopt;
  // f' = 2 - beta' >= 2 on the cap: f is increasing, so Newton's steps, kept inside the
  // bracket [lo, hi] by bisecting when one would leave it, find its one root.
  double lo = 0.0, hi = a_max, a = 0.5 * delta;
  for (int iteration = 0; iteration < 60; ++iteration) {
    const double s = std::sin(a), c = std::cos(a);
    const double denominator = distance * distance - 2.0 * r * distance * c + r * r;
    const double f = 2.0 * a - delta + std::atan2(r * s, distance - r * c);
    const double slope = 2.0 + (r * distance * c - r * r) / denominator;
    (f > 0.0 ? hi : lo) = a;
    double next = a - f / slope;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool converged = std::abs(next - a) < 1e-14;
    a = next;
    if (converged) break;
  }
  BallReflection reflection;
  reflection.normal = std::cos(a) * e1 + std::sin(a) * e2;
  reflection.point = ball.center + r * reflection.normal;
  const Vec3d back = (origin - reflection.point).normalized();
  reflection.cos_incidence = std::clamp(reflection.normal.dot(back), 0.0, 1.0);
  reflection.direction = (2.0 * reflection.cos_incidence * reflection.normal - back).normalized();
  return reflection;
}

namespace {

// The distance between segments [p0, p1] and [q0, q1] (Ericson, Real-Time Collision
// Detection, 5.1.9).
double segment_distance(const Vec3d& p0, const Vec3d& p1, const Vec3d& q0, const Vec3d& q1) {
  const Vec3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  const double c = d1.dot(r), b = d1.dot(d2), denominator = a * e - b * b;
  double s = denominator > 1e-12 * a * e ? std::clamp((b * f - c * e) / denominator, 0.0, 1.0) : 0.0;
  double t = (b * s + f) / e;
  if (t < 0.0) {
    t = 0.0;
    s = std::clamp(-c / a, 0.0, 1.0);
  } else if (t > 1.0) {
    t = 1.0;
    s = std::clamp((b - c) / a, 0.0, 1.0);
  }
  return ((p0 + s * d1) - (q0 + t * d2)).norm();
}

// What one view needs per lookup, worked out once.
struct ViewGeometry {
  const ProbeView* view;
  Eigen::Affine3d world_to_camera;
  Vec3d origin;
  Vec3d tripod_foot;                // the capsule's axis runs from here up to the origin
  Vec3d axis;                       // unit, from the ball's centre towards the origin
  double sin_outline, cos_outline;  // of the angle between the axis and the normals on the ball's outline
};

// The camera-space point of world point p, in the camera's float type.
Vec3 to_camera(const ViewGeometry& g, const Vec3d& p) { return (g.world_to_camera * p).cast<float>(); }

// What one view saw in board direction d, and its weight: 0 when it did not see it.
struct ViewSample {
  double weight = 0.0;
  RGB radiance = RGB::Zero();
  bool saturated = false;  // seen, but through a saturated pixel
};

ViewSample sample_view(const ViewGeometry& g, const Vec3d& d, const MirrorBall& ball,
                       const MirrorBallProbeOptions& options) {
  ViewSample sample;
  const std::optional<BallReflection> hit = ball_point_reflecting(g.origin, d, ball);
  if (!hit || !(hit->cos_incidence > 0.0)) return sample;
  // The camera's and tripod's own reflection.
  constexpr double kFar = 1e3;  // metres: the reflected ray as a segment
  if (segment_distance(hit->point, hit->point + kFar * d, g.tripod_foot, g.origin) < options.camera_radius_m)
    return sample;
  const PinholeCamera& camera = g.view->camera;
  const std::optional<Vec2> film = camera.project(to_camera(g, hit->point));
  if (!film) return sample;
  // The outline's point on the same radial line: the plane of the ball's centre, the
  // camera and the point projects onto the line through their images.
  const Vec3d radial = hit->normal - hit->normal.dot(g.axis) * g.axis;
  if (radial.norm() > 1e-12) {
    const Vec3d outline_normal = g.cos_outline * g.axis + g.sin_outline * radial.normalized();
    const std::optional<Vec2> outline = camera.project(to_camera(g, ball.center + ball.radius * outline_normal));
    if (!outline || double((*film - *outline).norm()) < options.rim_margin_px) return sample;
  }
  const float x = film->x(), y = film->y();
  if (!(x >= 0.5f && y >= 0.5f && x <= camera.width - 0.5f && y <= camera.height - 0.5f)) return sample;
  // Catmull-Rom rather than bilinear: a lamp's reflection spans a pixel or two of the
  // ball, and the narrower blur keeps it in its own directions (office probe 2.6% ->
  // 1.2% in the tests; docs/notes/light-probe.md). Its undershoot beside a step is cut
  // at zero.
  const Image& image = g.view->radiance;
  const CubicFootprint at = catmull_rom_footprint(x, y, image.width, image.height);
  const std::vector<float>& alpha = g.view->alpha;
  if (!alpha.empty())
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i)
        if (at.wx[i] * at.wy[j] != 0.0f && !(alpha[size_t(at.y[j]) * image.width + at.x[i]] > 0.0f)) {
          sample.saturated = true;
          return sample;
        }
  sample.radiance = catmull_rom(image, at).max(0.0f);
  if (!sample.radiance.isFinite().all()) return sample;
  sample.weight = hit->cos_incidence;
  return sample;
}

void check_inputs(const std::vector<ProbeView>& views, const MirrorBall& ball, const MirrorBallProbeOptions& options) {
  if (views.empty()) throw Error("the light probe needs at least one photograph of the mirror ball (probe_NNN/)");
  if (!(ball.radius > 0.0 && std::isfinite(ball.radius) && ball.center.allFinite()))
    throw Error("the mirror ball's radius must be positive and its centre finite (radius " +
                std::to_string(ball.radius) + ")");
  if (options.width < 2 || options.height < 1)
    throw Error("the light probe's resolution must be at least 2x1 (got " + std::to_string(options.width) + "x" +
                std::to_string(options.height) + ")");
  if (options.samples_per_side < 0)
    throw Error("the light probe's directions per texel side must be 0 (automatic) or more");
  if (!(options.reflectance > 0.0f).all() || !options.reflectance.isFinite().all())
    throw Error("the mirror ball's reflectance must be positive in every channel");
  for (const ProbeView& view : views) {
    const Image& image = view.radiance;
    if (image.width != view.camera.width || image.height != view.camera.height)
      throw Error(view.name + ": the photograph is " + std::to_string(image.width) + "x" +
                  std::to_string(image.height) + " but its camera " + std::to_string(view.camera.width) + "x" +
                  std::to_string(view.camera.height) + ": register the probe photos with the same camera");
    if (!view.alpha.empty() && view.alpha.size() != size_t(image.width) * image.height)
      throw Error(view.name + ": the alpha channel does not match the photograph's size");
    if ((view.camera.position().cast<double>() - ball.center).norm() <= ball.radius)
      throw Error(view.name + ": the camera stands inside the mirror ball: check the ball's centre and radius");
  }
}

// Fills the texels with covered[t] == 0 ring by ring from the others: each takes the mean
// of its filled neighbours (8-connected, u wrapping, and across the poles).
void fill_uncovered(Image& map, const std::vector<float>& covered) {
  const int width = map.width, height = map.height;
  std::vector<char> filled(covered.size());
  for (size_t t = 0; t < covered.size(); ++t) filled[t] = covered[t] > 0.0f;
  for (bool changed = true; changed;) {
    changed = false;
    std::vector<std::pair<size_t, RGB>> ring;
    for (int j = 0; j < height; ++j)
      for (int i = 0; i < width; ++i) {
        if (filled[size_t(j) * width + i]) continue;
        RGB sum = RGB::Zero();
        int count = 0;
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            int jj = j + dj, ii = i + di;
            if (jj < 0 || jj >= height) {  // across the pole: the opposite meridian
              jj = jj < 0 ? 0 : height - 1;
              ii += width / 2;
            }
            ii = ((ii % width) + width) % width;
            const size_t n = size_t(jj) * width + ii;
            if (filled[n]) sum += map.at(ii, jj), ++count;
          }
        if (count > 0) ring.emplace_back(size_t(j) * width + i, sum / float(count));
      }
    for (const auto& [t, value] : ring) {
      map.set(int(t % width), int(t / width), value);
      filled[t] = 1;
      changed = true;
    }
  }
}

}  // namespace

MirrorBallProbe build_mirror_ball_probe(const std::vector<ProbeView>& views, const MirrorBall& ball,
                                        const MirrorBallProbeOptions& options) {
  check_inputs(views, ball, options);
  const int width = options.width, height = options.height;
  const int n = options.samples_per_side > 0 ? options.samples_per_side
                                             : std::max({1, (256 + width - 1) / width, (128 + height - 1) / height});
  const size_t texels = size_t(width) * height, view_count = views.size();
  require_memory(texels * (3 * sizeof(float) + sizeof(float) + 2 * view_count * sizeof(double)),
                 "building the light probe");

  std::vector<ViewGeometry> geometry;
  for (const ProbeView& view : views) {
    ViewGeometry g;
    g.view = &view;
    g.world_to_camera = view.camera.camera_to_world.cast<double>().inverse(Eigen::Isometry);
    g.origin = view.camera.position().cast<double>();
    g.tripod_foot = Vec3d(g.origin.x(), g.origin.y(), ball.center.z() - options.tripod_depth_m);
    if (g.tripod_foot.z() > g.origin.z()) g.tripod_foot = g.origin;
    const double distance = (g.origin - ball.center).norm();
    g.axis = (g.origin - ball.center) / distance;
    g.cos_outline = ball.radius / distance;
    g.sin_outline = std::sqrt(1.0 - g.cos_outline * g.cos_outline);
    geometry.push_back(g);
  }

  MirrorBallProbe probe;
  probe.to_world = probe_to_board();
  probe.map = Image(width, height);
  probe.covered.assign(texels, 0.0f);
  // Per texel and view: the sum over its directions of sin(theta) times the view's
  // weight, and sin(theta) where the view sees it (the contributions, summed in order).
  std::vector<double> view_weight(texels * view_count, 0.0), view_seen(texels * view_count, 0.0);
  const Eigen::Matrix3d to_world = probe.to_world.cast<double>();
  tbb::parallel_for(0, height, [&](int j) {
    std::vector<ViewSample> samples(view_count);
    for (int i = 0; i < width; ++i) {
      const size_t t = size_t(j) * width + i;
      RGBd sum = RGBd::Zero();
      double area = 0.0;
      bool saturated = false;
      for (int sj = 0; sj < n; ++sj)
        for (int si = 0; si < n; ++si) {
          const Vec2 uv((i + (si + 0.5f) / n) / width, (j + (sj + 0.5f) / n) / height);
          float sin_theta = 0.0f;
          const Vec3d d = to_world * latlong_to_direction(uv, &sin_theta).cast<double>();
          double total = 0.0;
          RGBd radiance = RGBd::Zero();
          for (size_t v = 0; v < view_count; ++v) {
            samples[v] = sample_view(geometry[v], d.normalized(), ball, options);
            total += samples[v].weight;
            radiance += samples[v].weight * samples[v].radiance.cast<double>();
          }
          if (!(total > 0.0)) {
            for (const ViewSample& sample : samples) saturated = saturated || sample.saturated;
            continue;
          }
          // Each direction is the views' weighted mean; the texel, its directions' mean
          // over the solid angle they stand for.
          sum += sin_theta * radiance / total;
          area += sin_theta;
          for (size_t v = 0; v < view_count; ++v) {
            view_weight[t * view_count + v] += sin_theta * samples[v].weight / total;
            if (samples[v].weight > 0.0) view_seen[t * view_count + v] += sin_theta;
          }
        }
      // A texel with directions that every view saw saturated holds a lower bound only.
      if (area > 0.0 && !saturated) {
        probe.map.set(i, j, (sum / area / options.reflectance.cast<double>()).cast<float>());
        probe.covered[t] = 1.0f;
      }
    }
  });

  const double sphere = 4.0 * kPiD;
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i)
      if (probe.covered[size_t(j) * width + i] > 0.0f)
        probe.covered_fraction += latlong_texel_solid_angle(j, width, height) / sphere;
  if (probe.covered_fraction == 0.0) {
    std::string names;
    for (const ProbeView& view : views) names += (names.empty() ? "" : ", ") + view.name;
    throw Error("the light probe: no photograph (" + names +
                ") shows the mirror ball where it is expected: check the ball's centre and radius, the probe "
                "photos' registration, and that they are not saturated");
  }
  // The sub-directions' sin(theta) sums to (texel solid angle) / (d theta d phi) per n^2.
  const double per_direction = (kPiD / (height * n)) * (2.0 * kPiD / (width * n));
  double total_weight = 0.0;
  for (size_t v = 0; v < view_count; ++v) {
    ProbeViewContribution contribution;
    contribution.name = views[v].name;
    for (size_t t = 0; t < texels; ++t) {
      contribution.weight_share += view_weight[t * view_count + v] * per_direction;
      contribution.covered_fraction += view_seen[t * view_count + v] * per_direction / sphere;
    }
    total_weight += contribution.weight_share;
    probe.views.push_back(contribution);
  }
  for (ProbeViewContribution& contribution : probe.views) contribution.weight_share /= total_weight;
  fill_uncovered(probe.map, probe.covered);
  return probe;
}

ProbeFiles write_mirror_ball_probe(OutputFolder& out, const MirrorBallProbe& probe, const std::string& map_name,
                                   const std::string& mask_name) {
  std::ostringstream to_world;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) to_world << (r + c > 0 ? " " : "") << probe.to_world(r, c);
  ProbeFiles files;
  files.map = out.write_image(map_name, probe.map, {{"glaze:to_world", to_world.str()}});
  Image mask(probe.map.width, probe.map.height);
  for (size_t t = 0; t < probe.covered.size(); ++t)
    for (int c = 0; c < 3; ++c) mask.pixels[3 * t + c] = probe.covered[t];
  files.mask = out.write_image(mask_name, mask);
  return files;
}

LatlongResample resample_into_probe_frame(const Image& map, const std::vector<float>& covered, const Mat3& to_world,
                                          int width, int height) {
  if (map.width <= 0 || map.height <= 0 || width <= 0 || height <= 0)
    throw Error("resampling a lighting map into the probe's frame: empty map or resolution");
  if (!covered.empty() && covered.size() != size_t(map.width) * map.height)
    throw Error("resampling a lighting map into the probe's frame: its coverage does not match its size");
  const int n = std::max({1, (map.width + width - 1) / width, (map.height + height - 1) / height});
  // Probe frame -> the map's frame.
  const Mat3 probe_to_map = to_world.transpose() * probe_to_board();
  LatlongResample out{Image(width, height), std::vector<float>(size_t(width) * height, 1.0f)};
  tbb::parallel_for(0, height, [&](int j) {
    for (int i = 0; i < width; ++i) {
      RGBd sum = RGBd::Zero();
      double area = 0.0;
      bool known = true;
      for (int sj = 0; sj < n; ++sj)
        for (int si = 0; si < n; ++si) {
          float sin_theta = 0.0f;
          const Vec2 uv((i + (si + 0.5f) / n) / width, (j + (sj + 0.5f) / n) / height);
          const Vec2 source = direction_to_latlong(probe_to_map * latlong_to_direction(uv, &sin_theta));
          sum += sin_theta * bilinear(map, bilinear_footprint(source, map.width, map.height, Wrap::repeat, Wrap::clamp))
                                 .cast<double>();
          area += sin_theta;
          if (!covered.empty()) known = known && covered[texel_of(source, map.width, map.height)] > 0.0f;
        }
      out.map.set(i, j, (sum / area).cast<float>());
      out.covered[size_t(j) * width + i] = known ? 1.0f : 0.0f;
    }
  });
  return out;
}

ReflectanceRatio reflectance_ratio(const Image& probe, const std::vector<float>& probe_covered, const Image& absolute,
                                   const std::vector<float>& absolute_covered) {
  const size_t texels = size_t(probe.width) * probe.height;
  if (absolute.width != probe.width || absolute.height != probe.height)
    throw Error("the reflectance estimate needs the lighting on the probe's texels: the probe is " +
                std::to_string(probe.width) + "x" + std::to_string(probe.height) + ", the estimate " +
                std::to_string(absolute.width) + "x" + std::to_string(absolute.height) +
                " (resample it into the probe's frame first)");
  if ((!probe_covered.empty() && probe_covered.size() != texels) ||
      (!absolute_covered.empty() && absolute_covered.size() != texels))
    throw Error("the reflectance estimate: a coverage mask does not match its map's size");
  std::vector<size_t> both;
  std::vector<double> area;
  for (size_t t = 0; t < texels; ++t) {
    const bool known =
        (probe_covered.empty() || probe_covered[t] > 0.0f) && (absolute_covered.empty() || absolute_covered[t] > 0.0f);
    if (!known) continue;
    const int j = int(t / probe.width);
    both.push_back(t);
    area.push_back(latlong_texel_solid_angle(j, probe.width, probe.height));
  }
  ReflectanceRatio result;
  result.texels = both.size();
  if (both.empty())
    throw Error("the reflectance estimate: the probe and the lighting estimate cover no direction in common");
  for (int c = 0; c < 3; ++c) {
    std::vector<double> p(both.size()), a(both.size());
    for (size_t k = 0; k < both.size(); ++k) {
      p[k] = probe.pixels[3 * both[k] + c];
      a[k] = absolute.pixels[3 * both[k] + c];
    }
    // Least squares, then Huber reweighting (k = 1.345 MADs) until the factor settles.
    std::vector<double> weight = area, residual(both.size());
    double factor = 0.0;
    for (int iteration = 0; iteration < 50; ++iteration) {
      double pa = 0.0, aa = 0.0;
      for (size_t k = 0; k < both.size(); ++k) pa += weight[k] * p[k] * a[k], aa += weight[k] * a[k] * a[k];
      if (!(aa > 0.0)) throw Error("the reflectance estimate: the lighting estimate is black where both are known");
      const double next = pa / aa;
      const bool settled = std::abs(next - factor) <= 1e-10 * std::abs(next);
      factor = next;
      if (settled) break;
      for (size_t k = 0; k < both.size(); ++k) residual[k] = std::abs(p[k] - factor * a[k]);
      std::vector<double> sorted = residual;
      std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
      const double scale = 1.4826 * sorted[sorted.size() / 2];
      const double threshold = 1.345 * scale;
      for (size_t k = 0; k < both.size(); ++k)
        weight[k] = area[k] * (residual[k] > threshold && threshold > 0.0 ? threshold / residual[k] : 1.0);
    }
    double squared = 0.0, probe_squared = 0.0;
    for (size_t k = 0; k < both.size(); ++k) {
      squared += area[k] * (p[k] - factor * a[k]) * (p[k] - factor * a[k]);
      probe_squared += area[k] * p[k] * p[k];
    }
    result.reflectance[c] = factor;
    result.relative_rms[c] = probe_squared > 0.0 ? std::sqrt(squared / probe_squared) : 0.0;
  }
  return result;
}

}  // namespace glaze

#include "inverse/photos/sphere_outline.h"

#include "renderer/error.h"
#include "renderer/environment.h"
#include "renderer/material.h"
#include "renderer/memory_budget.h"

#include <ceres/ceres.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

namespace glaze {
namespace {

struct TangentSphere {
  Vec3d center;
  double radius;
};

// A coated sphere's rim as the image shows it. At the outline the coat mirrors the
// background just behind it (the Fresnel factor is 1 at grazing), so the image does not
// step there; inside, at depth e from the outline, n.v grows as sqrt(2 e / R): the
// Fresnel factor falls, the mirrored direction turns away from the background's and the
// diffuse term rises, each by an amount proportional to sqrt(e) at first. Across the
// outline (x > 0 outside, pixels) the profile is therefore
//   b0 + b1 x + a sqrt(max(0, -x)) + c max(0, -x),
// seen through the pixels' area, the image's blur and the bilinear lookup: about a
// Gaussian of variance 1/12 + blur^2 + 1/6 along any direction. The two hinges, blurred
// so, are tabulated once; b0, b1, a and c are linear, and the outline is where the
// fit is best (outline_offset).
// The Gaussian is sampled every `tap` pixels out to 4 sigma either side, its taps summing
// to 1 (gaussian_taps); RimMirror's mirror is seen through the same.
std::vector<double> gaussian_taps(double sigma, double tap) {
  const int taps = int(std::ceil(4.0 * sigma / tap));
  std::vector<double> weight(2 * taps + 1);
  double total = 0.0;
  for (int k = -taps; k <= taps; ++k) {
    const double z = k * tap / sigma;
    total += weight[k + taps] = std::exp(-0.5 * z * z);
  }
  for (double& w : weight) w /= total;
  return weight;
}

class RimProfile {
 public:
  explicit RimProfile(double blur) : sigma_(std::sqrt(1.0 / 12.0 + blur * blur + 1.0 / 6.0)) {
    root_.resize(kTable + 1), ramp_.resize(kTable + 1);
    constexpr double kTap = 1.0 / 64.0;
    const std::vector<double> weight = gaussian_taps(sigma_, kTap);  // the same for every x
    const int taps = int(weight.size() / 2);
    for (int i = 0; i <= kTable; ++i) {
      const double x = -kReach + 2.0 * kReach * i / kTable;
      double root = 0.0, ramp = 0.0;
      for (int k = -taps; k <= taps; ++k) {
        const double w = weight[k + taps], inside = std::max(0.0, k * kTap - x);
        root += w * std::sqrt(inside), ramp += w * inside;
      }
      root_[i] = root, ramp_[i] = ramp;
    }
  }
  double root(double x) const { return lookup(root_, x, std::sqrt(std::max(0.0, -x))); }
  double ramp(double x) const { return lookup(ramp_, x, std::max(0.0, -x)); }
  double sigma() const { return sigma_; }  // of the Gaussian the hinges are seen through, pixels

 private:
  static constexpr double kReach = 8.0;  // pixels: beyond, the blur no longer matters
  static constexpr int kTable = 2048;
  static double lookup(const std::vector<double>& table, double x, double far) {
    if (!(std::abs(x) < kReach)) return far;
    const double u = (x + kReach) / (2.0 * kReach) * kTable;
    const int i = std::min(int(u), kTable - 1);
    return table[i] + (u - i) * (table[i + 1] - table[i]);
  }
  double sigma_;
  std::vector<double> root_, ramp_;
};

// What the outline is looked for in: the view's colour channels (or its mask), blurred,
// with the pixels near a saturated one marked unusable. Edges are found and weighed on
// their log (an edge's strength is its contrast, whatever the exposure), in the channel
// where the sphere and the background differ most (a red sphere before a grey wall of
// its luminance), and placed on the linear values, where a pixel straddling the outline
// mixes the two sides in proportion to their areas.
class EdgeImage {
 public:
  EdgeImage(const SphereView& view, double blur) : width_(view.image.width), height_(view.image.height), rim_(blur) {
    const size_t count = size_t(width_) * size_t(height_);
    const int channels = view.mask.empty() ? 3 : 1;
    // The channels, blurred and not, the luminance and two byte masks.
    require_memory(uint64_t(count) * (8 * channels + 4 + 2), view.name + ": locating the sphere");
    std::vector<cv::Mat> linear(channels);
    cv::Mat luminance(height_, width_, CV_32F), unusable(height_, width_, CV_8U, cv::Scalar(0));
    for (cv::Mat& channel : linear) channel.create(height_, width_, CV_32F);
    float* lum = luminance.ptr<float>();
    if (!view.mask.empty()) {
      float* mask = linear[0].ptr<float>();
      for (size_t i = 0; i < count; ++i) lum[i] = mask[i] = view.mask[i] > 0.5f ? 1.0f : 1e-2f;
    } else {
      float* rgb[3] = {linear[0].ptr<float>(), linear[1].ptr<float>(), linear[2].ptr<float>()};
      for (size_t i = 0; i < count; ++i) {
        const float* p = &view.image.pixels[3 * i];
        for (int c = 0; c < 3; ++c) rgb[c][i] = std::isfinite(p[c]) ? std::max(p[c], 0.0f) : 0.0f;
        lum[i] = 0.2126f * rgb[0][i] + 0.7152f * rgb[1][i] + 0.0722f * rgb[2][i];
        unusable.ptr<uint8_t>()[i] = !view.alpha.empty() && view.alpha[i] <= 0.0f;
      }
    }
    // Black pixels (underexposed in every exposure) are floored at a thousandth of the
    // median luminance, so that their log stays finite and their noise makes no edges.
    std::vector<float> sorted(luminance.begin<float>(), luminance.end<float>());
    std::nth_element(sorted.begin(), sorted.begin() + count / 2, sorted.end());
    floor_ = std::max(1e-3f * sorted[count / 2], std::numeric_limits<float>::min());
    linear_.resize(channels);
    for (int c = 0; c < channels; ++c) cv::GaussianBlur(linear[c], linear_[c], cv::Size(0, 0), blur);
    // The circle candidates' image: the log luminance, at most 480 pixels across:
    // the Hough transform is most of the time, and the candidates are only seeds.
    hough_scale_ = std::max(1.0, std::max(width_, height_) / 480.0);
    cv::GaussianBlur(luminance, luminance, cv::Size(0, 0), blur);
    cv::resize(luminance, hough_,
               cv::Size(int(std::lround(width_ / hough_scale_)), int(std::lround(height_ / hough_scale_))), 0, 0,
               cv::INTER_AREA);
    cv::max(hough_, floor_, hough_);
    cv::log(hough_, hough_);
    cv::dilate(unusable, unusable_, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(5, 5)));
  }

  bool is_mask() const { return linear_.size() == 1; }
  const RimProfile& rim() const { return rim_; }
  int channels() const { return int(linear_.size()); }
  int width() const { return width_; }
  int height() const { return height_; }
  // The log luminance reduced by hough_scale() (film pixels per pixel).
  const cv::Mat& hough_image() const { return hough_; }
  double hough_scale() const { return hough_scale_; }

  // The blurred linear value (or its log) of `channel` at film point (x, y) (pixel (i, j)
  // has its centre at (i + 0.5, j + 0.5)), bilinear; nothing off the image or near a
  // saturated pixel.
  std::optional<double> linear_at(int channel, const Vec2d& p) const { return at(linear_[channel], p); }
  std::optional<double> log_at(int channel, const Vec2d& p) const {
    const auto value = linear_at(channel, p);
    if (!value) return std::nullopt;
    return std::log(std::max(*value, double(floor_)));
  }

 private:
  std::optional<double> at(const cv::Mat& image, const Vec2d& p) const {
    const double u = p.x() - 0.5, v = p.y() - 0.5;
    if (!(u >= 0.0 && v >= 0.0 && u < width_ - 1 && v < height_ - 1)) return std::nullopt;
    const int i = int(u), j = int(v);
    if (unusable_.at<uint8_t>(j, i)) return std::nullopt;
    const double a = u - i, b = v - j;
    const auto f = [&](int di, int dj) { return double(image.at<float>(j + dj, i + di)); };
    return (1 - b) * ((1 - a) * f(0, 0) + a * f(1, 0)) + b * ((1 - a) * f(0, 1) + a * f(1, 1));
  }

  int width_, height_;
  RimProfile rim_;
  float floor_ = 0.0f;
  std::vector<cv::Mat> linear_;
  double hough_scale_ = 1.0;
  cv::Mat hough_, unusable_;
};

// Where the linear profile of `channel` through film point `p` along `n` crosses halfway
// from its level `kSide` pixels outside offset `t` to its level as far inside: the
// crossing nearest t, if any. A mask's boundary, a step, lies there.
std::optional<double> halfway_crossing(const EdgeImage& image, int channel, const Vec2d& p, const Vec2d& n, double t) {
  constexpr double kSide = 1.5, kStep = 0.125;
  const auto inside = image.linear_at(channel, p + (t - kSide) * n),
             outside = image.linear_at(channel, p + (t + kSide) * n);
  if (!inside || !outside) return std::nullopt;
  const double middle = 0.5 * (*outside + *inside);
  std::optional<double> crossing;
  auto previous = inside;
  for (double s = t - kSide + kStep; s <= t + kSide + 1e-9; s += kStep) {
    const auto value = image.linear_at(channel, p + s * n);
    if (!value) return std::nullopt;
    if ((*previous - middle) * (*value - middle) <= 0.0 && *previous != *value) {
      const double at = s - kStep + kStep * (middle - *previous) / (*value - *previous);
      if (!crossing || std::abs(at - t) < std::abs(*crossing - t)) crossing = at;
    }
    previous = value;
  }
  return crossing;
}

// What the coat mirrors just inside the outline, which RimProfile's hinges take to be
// smooth. A ray that meets the sphere at n.v = mu is turned from its way by 2 asin(mu),
// so the rim's first pixels mirror the lighting over tens of degrees beyond the outline,
// compressed into a pixel or two: a detailed background (a landscape's ground, seen past
// the sphere and mirrored in its rim) puts detail there that the hinges cannot follow,
// and it moves each part of the outline its own way, the same in every round
// (docs/notes/sphere-outline.md, "The rim's mirror"). Where the lighting is known (the
// light probe) the mirror is predicted instead: F(mu) L(r(mu)), traced along one outline
// point's normal (in the plane of its grazing ray and the sphere's centre) in steps of mu
// that turn the mirrored direction by about 2 pixels' angle, and scaled by the view's
// radiance over the lighting's (background_scale).
struct RimMirror {
  std::vector<double> offsets;  // along the normal from the outline point, pixels (< 0: inside)
  std::vector<double> spans;    // each offset's share of the profile (the trapezoid rule's)
  std::vector<double> fresnel;  // the coat's Fresnel factor there
  std::vector<Vec3> mirrored;   // the direction the coat mirrors there (board frame)
  const Environment* lighting = nullptr;
  RGBd scale = RGBd::Zero();  // the view's radiance over the lighting's

  bool empty() const { return offsets.empty() || lighting == nullptr; }

  // F L(mirrored) - L at the outline in `channel`, times the scale: zero outside the
  // outline, seen through a Gaussian of `sigma` pixels (the hinges' own), on a grid of
  // kGrid steps a pixel from -reach to reach (entry i at offset -reach + i / kGrid).
  static constexpr int kGrid = 32;
  std::vector<double> profile(int channel, double sigma, double reach) const {
    // The continuous profile is spread onto the grid (linearly, its mass kept), which
    // runs on inwards as far as the Gaussian reaches: what lies deeper than the grid
    // blurs into its inner end. Then it is blurred.
    const std::vector<double> kernel = gaussian_taps(sigma, 1.0 / kGrid);
    const int taps = int(kernel.size() / 2), cells = int(std::lround(2.0 * reach * kGrid));
    std::vector<double> spread(cells + taps + 1, 0.0);
    const double outline = lighting->eval(mirrored.front())[channel];
    for (size_t j = 0; j < offsets.size(); ++j) {
      const double u = (offsets[j] + reach) * kGrid + taps;
      if (!(u >= 0.0 && u < cells + taps)) continue;
      const int i = int(u);
      const double mass = scale[channel] * (fresnel[j] * lighting->eval(mirrored[j])[channel] - outline) * spans[j];
      spread[i] += (1.0 - (u - i)) * mass, spread[i + 1] += (u - i) * mass;
    }
    // A mass spread over a cell of 1 / kGrid pixels: its density is kGrid times it.
    std::vector<double> blurred(cells + 1, 0.0);
    for (int i = 0; i <= cells; ++i)
      for (int k = std::max(-taps, -i - taps); k <= std::min(taps, cells - i); ++k)
        blurred[i] += kGrid * spread[i + taps + k] * kernel[k + taps];
    return blurred;
  }
};

// How far to either side of a candidate outline outline_offset reads the profile
// (kRimSamples * kRimSpacing) and how far from where the edge was seen it searches. 2
// pixels either side: the blur's reach, and not much deeper inside, where the mirrored
// lighting's own detail (compressed towards the rim) departs from the hinges. Measured on
// two renders and four simulated shoots: 1 pixel put the radius 0.5% low, 3 pixels 0.27%
// high on one render, 1.5 and 2 pixels within 0.12% on all six
// (docs/notes/sphere-outline.md).
constexpr int kRimSamples = 8;
constexpr double kRimSpacing = 0.25, kRimSearch = 1.5;
constexpr double kRimExtent = kRimSamples * kRimSpacing + kRimSearch;

// The coat's Fresnel factor at normal incidence that the rim's mirror is modelled with:
// a dielectric of index 1.5. Near the outline, where the mirror matters, F is within
// R0 of 1 whatever the coat's R0 is.
constexpr float kNominalCoatR0 = 0.04f;

// Where a coated sphere's outline lies on the linear profile of `channel` through film
// point `p` along `n`, near offset t: the offset u whose rim profile (RimProfile, plus the
// rim's mirror where `mirror` is traced) fits the profile best over 2 pixels either side,
// searched 1.5 pixels either side of t.
std::optional<double> outline_offset(const EdgeImage& image, int channel, const Vec2d& p, const Vec2d& n, double t,
                                     const RimMirror& mirror) {
  constexpr double kStep = 1.0 / RimMirror::kGrid;
  Eigen::Matrix<double, 2 * kRimSamples + 1, 1> values;
  for (int k = -kRimSamples; k <= kRimSamples; ++k) {
    const auto value = image.linear_at(channel, p + (t + k * kRimSpacing) * n);
    if (!value) return std::nullopt;
    values[k + kRimSamples] = *value;
  }
  // The mirror is known, not fitted: its detail is what the hinges cannot follow, and
  // its smooth part is nearly theirs (a free coefficient on it made the fit ill-posed).
  const std::vector<double> mirrored =
      mirror.empty() ? std::vector<double>{} : mirror.profile(channel, image.rim().sigma(), kRimExtent);
  // The misfit of the best b0, b1, a, c with the outline at offset t + d.
  const auto misfit = [&](int step) {
    const double d = step * kStep;
    Eigen::Matrix<double, 2 * kRimSamples + 1, 4> basis;
    Eigen::Matrix<double, 2 * kRimSamples + 1, 1> rest = values;
    for (int k = -kRimSamples; k <= kRimSamples; ++k) {
      const double x = k * kRimSpacing - d;
      basis.row(k + kRimSamples) << 1.0, x, image.rim().root(x), image.rim().ramp(x);
      // x lies on the mirror's grid: k kRimSpacing and d are whole steps of it.
      const size_t cell = size_t(std::lround((x + kRimExtent) * RimMirror::kGrid));
      if (!mirrored.empty()) rest[k + kRimSamples] -= mirrored[cell];
    }
    const Eigen::Matrix4d normal = basis.transpose() * basis;
    const Eigen::Vector4d fitted = normal.ldlt().solve(basis.transpose() * rest);
    return (rest - basis * fitted).squaredNorm();
  };
  const int steps = int(std::lround(kRimSearch / kStep));
  std::vector<double> cost(2 * steps + 1);
  for (int i = -steps; i <= steps; ++i) cost[i + steps] = misfit(i);
  const int best = int(std::min_element(cost.begin(), cost.end()) - cost.begin());
  if (best == 0 || best == 2 * steps) return std::nullopt;  // no minimum within the search
  // A parabola through the best and its neighbours.
  const double below = cost[best - 1], at = cost[best], above = cost[best + 1];
  const double curvature = below - 2.0 * at + above;
  const double shift = curvature > 0.0 ? 0.5 * (below - above) / curvature : 0.0;
  return t + (best - steps + shift) * kStep;
}

// The strongest edge across film point `p` along the unit normal `n`, within `reach`
// pixels: its offset along n, or nothing where no step of at least `min_contrast` (log
// a pixel) is there. The log's steepest place finds it; the linear profile of the channel
// where it is steepest places it at sub-pixel precision: for a coated sphere, where the
// rim's profile fits it best (outline_offset); for a mask, where it crosses halfway
// between its levels on either side, which is the outline of a pixel-averaged, blurred
// step.
std::optional<double> find_edge(const EdgeImage& image, const Vec2d& p, const Vec2d& n, double reach,
                                const SphereOutlineOptions& options, const RimMirror& mirror = {}) {
  constexpr double h = 0.5;  // sample spacing, pixels; the derivative spans 2h = 1 pixel
  const int steps = int(std::ceil(reach / h));
  std::vector<double> slope(2 * steps + 1, 0.0), profile(2 * steps + 3);
  std::vector<int> channel(2 * steps + 1, 0);
  for (int c = 0; c < image.channels(); ++c) {
    for (int k = -steps - 1; k <= steps + 1; ++k) {
      const auto value = image.log_at(c, p + k * h * n);
      if (!value) return std::nullopt;  // a profile cut by the image's edge or a saturated pixel
      profile[k + steps + 1] = *value;
    }
    for (int k = 0; k <= 2 * steps; ++k) {
      const double step = std::abs(profile[k + 2] - profile[k]) / (2 * h);
      if (step > slope[k]) slope[k] = step, channel[k] = c;
    }
  }
  const auto peak = std::max_element(slope.begin(), slope.end());
  if (*peak < options.min_contrast) return std::nullopt;
  const int strongest = channel[peak - slope.begin()];
  // The levels are taken about the crossing found last, which starts at the log's peak:
  // that peak lies towards the darker side, where a pixel's log changes most.
  std::optional<double> crossing = double(peak - slope.begin() - steps) * h;
  // A coated sphere's rim is no step (RimProfile); a mask's boundary is.
  if (!image.is_mask()) return outline_offset(image, strongest, p, n, *crossing, mirror);
  for (int pass = 0; pass < 3 && crossing; ++pass) crossing = halfway_crossing(image, strongest, p, n, *crossing);
  return crossing;
}

Vec3d to_double(const Vec3& v) { return v.cast<double>(); }

// The ray through film point (x, y), in double precision.
std::pair<Vec3d, Vec3d> film_ray(const PinholeCamera& camera, const Vec2d& film) {
  const Ray ray = camera.generate_ray(float(film.x()), float(film.y()));
  return {to_double(ray.origin), to_double(ray.direction).normalized()};
}

// The rim's mirror (RimMirror) inside outline point `p` of `sphere` (outward normal `n`)
// to `depth` pixels inside, under `lighting` scaled by `scale`. The rays in the plane of
// p's grazing ray and the centre meet the sphere at n.v = mu where they pass the centre at
// R sqrt(1 - mu^2); each is reflected exactly and where it meets the sphere is projected
// through the lens. Empty when the camera is inside the sphere or a point is behind it.
RimMirror trace_rim_mirror(const PinholeCamera& camera, const TangentSphere& sphere, const Vec2d& p, const Vec2d& n,
                           double depth, const Environment& lighting, const RGBd& scale) {
  const Vec3d origin = to_double(camera.position()), to_center = sphere.center - origin;
  const double distance = to_center.norm(), R = sphere.radius;
  if (!(distance > R && R > 0.0)) return {};
  const Vec3d axis = to_center / distance, grazing = film_ray(camera, p).second;
  const Vec3d outward = (grazing - grazing.dot(axis) * axis).normalized();
  const Eigen::Affine3f world_to_camera = camera.camera_to_world.inverse();
  // mu in steps that turn the mirrored direction (by 2 asin mu) about 2 pixels' angle.
  const double step = 1.0 / std::max(double(camera.fl_x), 1.0);
  RimMirror mirror;
  mirror.lighting = &lighting;
  mirror.scale = scale;
  for (double mu = 0.0; mu <= 1.0; mu += step) {
    const double sine = R * std::sqrt(1.0 - mu * mu) / distance, cosine = std::sqrt(1.0 - sine * sine);
    const Vec3d direction = cosine * axis + sine * outward;
    const Vec3d hit = origin + (distance * cosine - R * mu) * direction;
    const Vec3d normal = (hit - sphere.center) / R;
    const auto seen = camera.project(world_to_camera * hit.cast<float>());
    if (!seen) return {};
    const double offset = (seen->cast<double>() - p).dot(n);
    mirror.offsets.push_back(offset);
    mirror.fresnel.push_back(schlick_fresnel(double(kNominalCoatR0), mu));
    mirror.mirrored.push_back((direction - 2.0 * direction.dot(normal) * normal).cast<float>());
    if (offset < -depth) break;
  }
  // The trapezoid rule's weights over the offsets, which run inwards from 0.
  const size_t count = mirror.offsets.size();
  mirror.spans.assign(count, 0.0);
  for (size_t j = 0; j + 1 < count; ++j) {
    const double gap = 0.5 * (mirror.offsets[j] - mirror.offsets[j + 1]);
    mirror.spans[j] += gap, mirror.spans[j + 1] += gap;
  }
  return mirror;
}

// The outline points (film) and their outward normals (film, unit).
struct OutlineSamples {
  std::vector<Vec2d> points, normals;
};

OutlineSamples outline_samples(const PinholeCamera& camera, const Vec3d& center, double radius, int count) {
  OutlineSamples samples;
  samples.points = sphere_outline(camera, center, radius, count);
  const std::vector<Vec2d> outer = sphere_outline(camera, center, radius * 1.001, count);
  if (outer.size() != samples.points.size()) return {};
  for (size_t k = 0; k < outer.size(); ++k) {
    const Vec2d n = outer[k] - samples.points[k];
    samples.normals.push_back(n.norm() > 0.0 ? Vec2d(n.normalized()) : Vec2d::Zero());
  }
  return samples;
}

// The sphere's radius in view's pixels, roughly (its outline's mean distance from its centre).
double outline_radius_px(const std::vector<Vec2d>& outline) {
  if (outline.empty()) return 0.0;
  Vec2d mean = Vec2d::Zero();
  for (const Vec2d& p : outline) mean += p;
  mean /= double(outline.size());
  double sum = 0.0;
  for (const Vec2d& p : outline) sum += (p - mean).norm();
  return sum / double(outline.size());
}

// A cone from a camera's position: the rays through a circle in its film.
struct Cone {
  Vec3d apex, axis;  // axis unit
  double half_angle;
};

Cone circle_cone(const PinholeCamera& camera, const Vec2d& centre, double radius) {
  const auto [apex, axis] = film_ray(camera, centre);
  double sum = 0.0;
  constexpr int kPoints = 16;
  for (int k = 0; k < kPoints; ++k) {
    const double phi = 2.0 * M_PI * k / kPoints;
    const auto [o, d] = film_ray(camera, centre + radius * Vec2d(std::cos(phi), std::sin(phi)));
    sum += std::acos(std::clamp(d.dot(axis), -1.0, 1.0));
  }
  return {apex, axis, sum / kPoints};
}

// The sphere both cones are tangent to, from the closest approach of their axes; nothing
// when they do not meet in front of both cameras or disagree about its size.
std::optional<TangentSphere> intersect_cones(const Cone& a, const Cone& b) {
  const Vec3d w = a.apex - b.apex;
  const double c = a.axis.dot(b.axis), d = a.axis.dot(w), e = b.axis.dot(w), denominator = 1.0 - c * c;
  if (denominator < 1e-6) return std::nullopt;  // parallel axes
  const double ta = (c * e - d) / denominator, tb = (e - c * d) / denominator;
  if (!(ta > 0.0 && tb > 0.0)) return std::nullopt;
  const Vec3d pa = a.apex + ta * a.axis, pb = b.apex + tb * b.axis, center = 0.5 * (pa + pb);
  const double ra = (center - a.apex).norm() * std::sin(a.half_angle);
  const double rb = (center - b.apex).norm() * std::sin(b.half_angle);
  const double radius = 0.5 * (ra + rb);
  if (std::abs(ra - rb) > 0.3 * radius || (pa - pb).norm() > radius) return std::nullopt;
  return TangentSphere{center, radius};
}

// Circle candidates in a view (film coordinates, pixels): Hough circles on its blurred
// log luminance (reduced to at most 480 pixels across) scaled to 8 bits.
std::vector<Vec3d> circle_candidates(const EdgeImage& image) {
  const cv::Mat& reduced = image.hough_image();
  const double scale = image.hough_scale();
  std::vector<float> sorted(reduced.begin<float>(), reduced.end<float>());
  std::sort(sorted.begin(), sorted.end());
  const float low = sorted[sorted.size() / 200], high = sorted[sorted.size() - 1 - sorted.size() / 200];
  cv::Mat bytes;
  reduced.convertTo(bytes, CV_8U, 255.0 / std::max(high - low, 1e-6f), -255.0 * low / std::max(high - low, 1e-6f));
  const int size = std::min(bytes.cols, bytes.rows);
  std::vector<cv::Vec3f> circles;
  // Canny's upper threshold 60 (a quarter of the range over a Sobel tap), a low vote
  // threshold: the candidates are only seeds, and the pairs of views weed them out. The
  // eight with the most votes are kept, spheres from 1/30 to 1/2 of the picture.
  cv::HoughCircles(bytes, circles, cv::HOUGH_GRADIENT, 1.0, size / 10.0, 60.0, 15.0, size / 30, size / 2);
  std::vector<Vec3d> candidates;
  for (size_t k = 0; k < std::min<size_t>(circles.size(), 8); ++k)
    candidates.emplace_back((circles[k][0] + 0.5) * scale, (circles[k][1] + 0.5) * scale, circles[k][2] * scale);
  return candidates;
}

// The fraction of the sphere's outline in `view` where an edge lies within `reach`.
double outline_support(const EdgeImage& image, const PinholeCamera& camera, const TangentSphere& sphere, double reach,
                       const SphereOutlineOptions& options) {
  const OutlineSamples samples = outline_samples(camera, sphere.center, sphere.radius, 32);
  if (samples.points.empty()) return 0.0;
  int found = 0;
  for (size_t k = 0; k < samples.points.size(); ++k)
    found += find_edge(image, samples.points[k], samples.normals[k], reach, options).has_value();
  return double(found) / double(samples.points.size());
}

// A ray through an outline edge, which grazes the sphere. Its residual is the angle
// between the ray and the sphere's tangent cone from its origin, in the view's pixels:
// > 0 where the ray passes outside the sphere.
struct ConeResidual {
  Vec3d origin, direction;
  double pixels_per_radian;

  template <typename T>
  bool operator()(const T* center, const T* radius, T* residual) const {
    const T d[3] = {center[0] - origin.x(), center[1] - origin.y(), center[2] - origin.z()};
    const T distance = ceres::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(radius[0] > T(0.0) && radius[0] < distance)) return false;
    const T cross[3] = {d[1] * direction.z() - d[2] * direction.y(), d[2] * direction.x() - d[0] * direction.z(),
                        d[0] * direction.y() - d[1] * direction.x()};
    const T sine = ceres::sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2] + T(1e-30));
    const T cosine = d[0] * direction.x() + d[1] * direction.y() + d[2] * direction.z();
    residual[0] = (ceres::atan2(sine, cosine) - ceres::asin(radius[0] / distance)) * pixels_per_radian;
    return true;
  }
};

// One view's outline edges: the rays through them.
struct ViewEdges {
  std::vector<Vec2d> film;
  std::vector<Vec3d> origins, directions;
  int samples = 0;
};

// A view's radiance over `lighting`'s, per channel, where the view sees the lighting
// itself: the background around the sphere's outline (from 3 pixels out to half a radius),
// the median of the ratios over 64 directions at each of 4 distances. Nothing where fewer
// than a quarter of them can be read, or where the lighting does not explain the
// background's variation: the logs of the ratios must scatter (median absolute deviation)
// by less than half as much as the background's own logs, or by under 5% where the
// background is nearly even. Otherwise the background is not the lighting at infinity (a
// table or a wall nearby, another lighting) and the rim's mirror is not predicted from it.
std::optional<RGBd> background_scale(const EdgeImage& image, const PinholeCamera& camera, const TangentSphere& sphere,
                                     const Environment& lighting) {
  constexpr int kAngles = 64, kRings = 4;
  const OutlineSamples outline = outline_samples(camera, sphere.center, sphere.radius, kAngles);
  if (outline.points.empty() || image.is_mask()) return std::nullopt;
  const double radius_px = outline_radius_px(outline.points);
  std::array<std::vector<double>, 3> ratios, levels;
  for (size_t k = 0; k < outline.points.size(); ++k)
    for (int ring = 0; ring < kRings; ++ring) {
      const Vec2d film = outline.points[k] + (3.0 + 0.5 * radius_px * ring / (kRings - 1)) * outline.normals[k];
      const RGB light = lighting.eval(film_ray(camera, film).second.cast<float>());
      for (int c = 0; c < 3; ++c) {
        const auto value = image.linear_at(c, film);
        if (!(value && *value > 0.0 && light[c] > 0.0f)) continue;
        ratios[c].push_back(std::log(*value / light[c]));
        levels[c].push_back(std::log(*value));
      }
    }
  // The median of `logs`, and their median absolute deviation from it.
  const auto median_and_spread = [](std::vector<double> logs) {
    std::nth_element(logs.begin(), logs.begin() + logs.size() / 2, logs.end());
    const double median = logs[logs.size() / 2];
    for (double& value : logs) value = std::abs(value - median);
    std::nth_element(logs.begin(), logs.begin() + logs.size() / 2, logs.end());
    return std::pair{median, logs[logs.size() / 2]};
  };
  RGBd scale;
  for (int c = 0; c < 3; ++c) {
    if (ratios[c].size() < kAngles * kRings / 4) return std::nullopt;
    const auto [median, spread] = median_and_spread(ratios[c]);
    if (spread > std::max(0.05, 0.5 * median_and_spread(levels[c]).second)) return std::nullopt;
    scale[c] = std::exp(median);
  }
  return scale;
}

// One view's outline edges, looked for around `sphere`'s outline; with the rim's mirror
// where `lighting` is given (the view's radiance is `scale` times it).
ViewEdges detect_edges(const EdgeImage& image, const PinholeCamera& camera, const TangentSphere& sphere, double reach,
                       const SphereOutlineOptions& options, const Environment* lighting, const RGBd& scale) {
  ViewEdges edges;
  const OutlineSamples samples = outline_samples(camera, sphere.center, sphere.radius, options.outline_samples);
  edges.samples = int(samples.points.size());
  // The mirror reaches as deep as outline_offset's samples and search, and as far beyond
  // them as RimMirror::profile's Gaussian reaches.
  const double depth = kRimExtent + 4.0 * image.rim().sigma();
  for (size_t k = 0; k < samples.points.size(); ++k) {
    const RimMirror mirror =
        lighting ? trace_rim_mirror(camera, sphere, samples.points[k], samples.normals[k], depth, *lighting, scale)
                 : RimMirror{};
    const auto offset = find_edge(image, samples.points[k], samples.normals[k], reach, options, mirror);
    if (!offset) continue;
    const Vec2d film = samples.points[k] + *offset * samples.normals[k];
    const auto [origin, direction] = film_ray(camera, film);
    edges.film.push_back(film);
    edges.origins.push_back(origin);
    edges.directions.push_back(direction);
  }
  return edges;
}

double residual_px(const ViewEdges& edges, size_t k, const TangentSphere& sphere, double pixels_per_radian) {
  const ConeResidual cost{edges.origins[k], edges.directions[k], pixels_per_radian};
  double residual = std::numeric_limits<double>::quiet_NaN();
  cost(sphere.center.data(), &sphere.radius, &residual);
  return residual;
}

// Centre and radius by least squares over every view's edges that `keep` accepts.
template <typename Keep>
TangentSphere fit_cones(const std::vector<ViewEdges>& views, const std::vector<SphereView>& input,
                        const TangentSphere& seed, Keep keep, std::string* summary_line) {
  TangentSphere sphere = seed;
  ceres::Problem problem;
  for (size_t v = 0; v < views.size(); ++v)
    for (size_t k = 0; k < views[v].origins.size(); ++k) {
      if (!keep(v, k)) continue;
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ConeResidual, 1, 3, 1>(new ConeResidual{
                                   views[v].origins[k], views[v].directions[k], double(input[v].camera.fl_x)}),
                               new ceres::CauchyLoss(1.0), sphere.center.data(), &sphere.radius);
    }
  ceres::Solver::Options solver;
  solver.minimizer_type = ceres::TRUST_REGION;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = 100;
  solver.function_tolerance = 1e-12;
  solver.gradient_tolerance = 1e-12;
  solver.parameter_tolerance = 1e-12;
  solver.num_threads = 1;  // four parameters; one thread keeps results bit-identical
  solver.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  *summary_line = summary.BriefReport();
  // A round without edges, or a failed solve, keeps the sphere it started from.
  if (problem.NumResidualBlocks() == 0 || !summary.IsSolutionUsable() || !sphere.center.allFinite() ||
      !std::isfinite(sphere.radius))
    return seed;
  return sphere;
}

std::string millimetres(const TangentSphere& sphere) {
  std::ostringstream text;
  text.precision(1);
  text << std::fixed << "centre (" << 1e3 * sphere.center.x() << ", " << 1e3 * sphere.center.y() << ", "
       << 1e3 * sphere.center.z() << ") mm, radius " << 1e3 * sphere.radius << " mm";
  return text.str();
}

// The sphere of the two views' circles that all views' images support best.
TangentSphere initial_sphere(const std::vector<SphereView>& views, const std::vector<EdgeImage>& images,
                             const SphereOutlineOptions& options) {
  std::vector<std::vector<Cone>> cones(views.size());
  for (size_t v = 0; v < views.size(); ++v) {
    for (const Vec3d& circle : circle_candidates(images[v]))
      cones[v].push_back(circle_cone(views[v].camera, circle.head<2>(), circle.z()));
    if (cones[v].empty())
      throw Error(views[v].name + ": no round outline found that could be the sphere; check that the sphere is " +
                  "whole in the picture, in focus and stands out from the background, or give the view a mask");
  }
  std::optional<TangentSphere> best;
  double best_score = -1.0;
  for (size_t a = 0; a < views.size(); ++a)
    for (size_t b = a + 1; b < views.size(); ++b)
      for (const Cone& ca : cones[a])
        for (const Cone& cb : cones[b]) {
          const auto sphere = intersect_cones(ca, cb);
          if (!sphere) continue;
          // Each view adds at most 1: stop once the rest cannot beat the best. Two nearly
          // parallel cones meet far away in a sphere larger than any picture: one whose
          // outline is not wholly in a view's picture is not the sphere the views show
          // whole (and its edge search would reach across millions of pixels).
          double score = 0.0;
          for (size_t v = 0; v < views.size() && score + double(views.size() - v) > best_score; ++v) {
            const std::vector<Vec2d> outline = sphere_outline(views[v].camera, sphere->center, sphere->radius, 16);
            const double radius_px = outline_radius_px(outline);
            const double picture = std::hypot(views[v].camera.width, views[v].camera.height);
            if (outline.empty() || !(radius_px < picture)) {
              score = -1.0;
              break;
            }
            score += outline_support(images[v], views[v].camera, *sphere, std::max(3.0, 0.1 * radius_px), options);
          }
          if (score > best_score) best_score = score, best = sphere;
        }
  if (!best || best_score < options.min_found * double(views.size()))
    throw Error("the views (" + views.front().name + " .. " + views.back().name +
                ") do not agree on a sphere: no two views' round outlines span cones that meet in one sphere " +
                "the others show; check the views' registration and that the sphere did not move, or give masks");
  return *best;
}

}  // namespace

std::vector<Vec2d> sphere_outline(const PinholeCamera& camera, const Vec3d& center, double radius, int points) {
  const Vec3d origin = to_double(camera.position()), d = center - origin;
  const double distance = d.norm();
  if (!(distance > radius && radius > 0.0)) return {};
  // The rays that graze the sphere touch it on a circle: tangent length L from the camera,
  // its plane L^2 / distance along the axis, its radius L r / distance.
  const Vec3d axis = d / distance;
  const double tangent2 = distance * distance - radius * radius;
  const Vec3d circle_center = origin + axis * (tangent2 / distance);
  const double circle_radius = std::sqrt(tangent2) * radius / distance;
  const Vec3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
  const Eigen::Affine3f world_to_camera = camera.camera_to_world.inverse();
  std::vector<Vec2d> outline;
  for (int k = 0; k < points; ++k) {
    const double phi = 2.0 * M_PI * k / points;
    const Vec3d p = circle_center + circle_radius * (std::cos(phi) * e1 + std::sin(phi) * e2);
    const auto film = camera.project(world_to_camera * p.cast<float>());
    if (!film) return {};
    outline.push_back(film->cast<double>());
  }
  return outline;
}

SphereFit locate_sphere(const std::vector<SphereView>& views, const SphereOutlineOptions& options,
                        const Environment* lighting) {
  if (views.size() < 2)
    throw Error((views.empty() ? std::string("the shoot") : views.front().name) +
                ": a sphere is located from its outline in at least 2 views; photograph it from another position");
  std::vector<EdgeImage> images;
  for (const SphereView& view : views) {
    const size_t pixels = size_t(view.image.width) * size_t(view.image.height);
    if (pixels == 0 || (!view.alpha.empty() && view.alpha.size() != pixels) ||
        (!view.mask.empty() && view.mask.size() != pixels))
      throw Error(view.name + ": the image, its alpha and its mask must have the same, non-zero size");
    images.emplace_back(view, options.blur_pixels);
  }
  TangentSphere sphere = initial_sphere(views, images, options);
  // The views' radiance over the lighting's, where the lighting models their rims' mirror:
  // read off each round's sphere, as the seed's outline may lie a few pixels off.
  std::vector<std::optional<RGBd>> scales(views.size());

  std::vector<ViewEdges> edges(views.size());
  std::string summary;
  const auto everything = [](size_t, size_t) { return true; };
  for (int round = 0; round < options.refinements; ++round) {
    for (size_t v = 0; v < views.size(); ++v) {
      if (lighting) scales[v] = background_scale(images[v], views[v].camera, sphere, *lighting);
      const double radius_px = outline_radius_px(sphere_outline(views[v].camera, sphere.center, sphere.radius, 16));
      const double reach = std::max(1.5, 0.1 * radius_px / double(1 << round));
      edges[v] = detect_edges(images[v], views[v].camera, sphere, reach, options, scales[v] ? lighting : nullptr,
                              scales[v].value_or(RGBd::Zero()));
    }
    sphere = fit_cones(edges, views, sphere, everything, &summary);
  }
  // The robust loss has weighed the edges; the last fit leaves out those beyond three
  // robust standard deviations (a reflection's edge, the background's), and at least
  // half a pixel so that a clean fit keeps them all.
  std::vector<double> magnitudes;
  for (size_t v = 0; v < views.size(); ++v)
    for (size_t k = 0; k < edges[v].origins.size(); ++k)
      magnitudes.push_back(std::abs(residual_px(edges[v], k, sphere, views[v].camera.fl_x)));
  if (magnitudes.empty()) throw Error(views.front().name + ": no edge of the sphere's outline found in any view");
  std::nth_element(magnitudes.begin(), magnitudes.begin() + magnitudes.size() / 2, magnitudes.end());
  const double limit = std::max(0.5, 3.0 * 1.4826 * magnitudes[magnitudes.size() / 2]);
  const auto inlier = [&](size_t v, size_t k) {
    return std::abs(residual_px(edges[v], k, sphere, views[v].camera.fl_x)) < limit;
  };
  std::vector<std::vector<bool>> used(views.size());
  for (size_t v = 0; v < views.size(); ++v)
    for (size_t k = 0; k < edges[v].origins.size(); ++k) used[v].push_back(inlier(v, k));
  sphere = fit_cones(
      edges, views, sphere, [&](size_t v, size_t k) { return bool(used[v][k]); }, &summary);

  SphereFit fit;
  fit.center = sphere.center;
  fit.radius = sphere.radius;
  fit.solver_summary = summary;
  double sum_px = 0.0, sum_mm = 0.0;
  int total = 0;
  for (size_t v = 0; v < views.size(); ++v) {
    SphereViewFit share;
    share.name = views[v].name;
    share.samples = edges[v].samples;
    share.rim_mirror = scales[v].has_value();
    share.lighting_scale = scales[v].value_or(RGBd::Zero());
    double sum = 0.0, sum2 = 0.0;
    for (size_t k = 0; k < edges[v].origins.size(); ++k) {
      if (!used[v][k]) continue;
      const double r = residual_px(edges[v], k, sphere, views[v].camera.fl_x);
      const Vec3d to_center = sphere.center - edges[v].origins[k];
      const double mm = 1e3 * (to_center.cross(edges[v].directions[k]).norm() - sphere.radius);
      sum += r, sum2 += r * r, sum_mm += mm * mm;
      share.edges.push_back(edges[v].film[k]);
      ++share.points;
    }
    if (share.points > 0) share.rms_px = std::sqrt(sum2 / share.points), share.mean_signed_px = sum / share.points;
    share.outline = sphere_outline(views[v].camera, sphere.center, sphere.radius);
    sum_px += sum2, total += share.points;
    fit.views.push_back(std::move(share));
  }
  fit.rms_px = std::sqrt(sum_px / std::max(total, 1));
  fit.rms_mm = std::sqrt(sum_mm / std::max(total, 1));

  for (size_t v = 0; v < views.size(); ++v) {
    const SphereViewFit& share = fit.views[v];
    std::vector<double> others;
    for (size_t w = 0; w < views.size(); ++w)
      if (w != v) others.push_back(fit.views[w].rms_px);
    std::sort(others.begin(), others.end());
    const double typical = others[others.size() / 2];
    const bool too_few = share.points < options.min_found * std::max(share.samples, 1);
    if (too_few || share.rms_px > std::max(options.disagreement * typical, 1.0)) {
      std::ostringstream text;
      text.precision(2);
      text << std::fixed << share.name << ": the view disagrees with the others about the sphere ("
           << millimetres(sphere) << "): ";
      if (too_few)
        text << "only " << share.points << " of " << share.samples
             << " places on the outline they give it show an edge in this view";
      else
        text << "its edges lie " << share.rms_px << " px RMS from that sphere's outline, against " << typical
             << " px in the other views";
      text << "; check that the sphere is whole in the picture and did not move between the views, and the view's "
              "registration (its board photo), or leave the view out";
      throw Error(text.str());
    }
  }
  return fit;
}

}  // namespace glaze

#include "inverse/joint_fit.h"

#include "inverse/cross_view.h"
#include "renderer/error.h"
#include "renderer/material.h"
#include "renderer/shading.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>

namespace glaze {
namespace {

// Brent's minimisation (golden sections with parabolic steps) of f on [a, b], from x
// inside it with f(x) = fx and the two points w, v nearest it (fw, fv: the grid's
// neighbours of its best point), to `tolerance` relative plus a tenth of it absolute. With
// three points known the first step is already the parabola's.
template <typename Function>
double minimise_bracketed(Function&& f, double a, double b, double x, double fx, double w, double fw, double v,
                          double fv, double tolerance) {
  constexpr double kGolden = 0.3819660112501051;
  // A parabolic step is taken only when under half the step before last: both start at
  // the bracket's width, so that the first two steps may be parabolic.
  double step = b - a, previous_step = b - a;
  for (int iteration = 0; iteration < 100; ++iteration) {
    const double middle = 0.5 * (a + b), reach = tolerance * (std::abs(x) + 0.1);
    if (std::abs(x - middle) <= 2.0 * reach - 0.5 * (b - a)) break;
    bool parabolic = false;
    if (std::abs(previous_step) > reach && w != x && v != x && v != w) {
      // The parabola through (x, w, v); its step is taken when it falls inside the
      // bracket and is under half the step before last.
      const double r = (x - w) * (fx - fv);
      double q = (x - v) * (fx - fw), p = (x - v) * q - (x - w) * r;
      q = 2.0 * (q - r);
      if (q > 0.0) p = -p;
      q = std::abs(q);
      if (std::abs(p) < std::abs(0.5 * q * previous_step) && p > q * (a - x) && p < q * (b - x)) {
        previous_step = step, step = p / q, parabolic = true;
        if (x + step - a < 2.0 * reach || b - (x + step) < 2.0 * reach) step = x < middle ? reach : -reach;
      }
    }
    if (!parabolic) previous_step = (x < middle ? b : a) - x, step = kGolden * previous_step;
    const double u = std::abs(step) >= reach ? x + step : x + (step > 0.0 ? reach : -reach);
    const double fu = f(u);
    if (fu <= fx) {
      (u < x ? b : a) = x;
      v = w, fv = fw, w = x, fw = fx, x = u, fx = fu;
    } else {
      (u < x ? a : b) = u;
      if (fu <= fw || w == x)
        v = w, fv = fw, w = u, fw = fu;
      else if (fu <= fv || v == x || v == w)
        v = u, fv = fu;
    }
  }
  return x;
}

// The grid's best point and its neighbours as a bracket, then Brent's method in it.
template <typename Function>
double minimise_on(Function&& f, const std::vector<double>& grid, double tolerance) {
  std::vector<double> values(grid.size());
  size_t best = 0;
  for (size_t i = 0; i < grid.size(); ++i) {
    values[i] = f(grid[i]);
    if (!std::isfinite(values[i])) values[i] = INFINITY;  // never kept, never a start
    if (values[i] < values[best]) best = i;
  }
  const size_t low = best > 0 ? best - 1 : 0, high = std::min(best + 1, grid.size() - 1);
  // w: the better neighbour, v: the other (at an end of the grid, v is the best point
  // itself, and the first step is a golden section).
  const bool low_better = low != best && (high == best || values[low] <= values[high]);
  const size_t w = low_better ? low : high, v = low_better ? high : low;
  return minimise_bracketed(f, grid[low], grid[high], grid[best], values[best], grid[w], values[w], grid[v], values[v],
                            tolerance);
}

// The searches for R0 stop at 1e-4 relative plus 1e-5 (R0 is asked to 1e-3).
constexpr double kR0Tolerance = 1e-4;
// Full-band captures: passes go on while one moves R0 by kJointPassTolerance or more, up
// to JointFitOptions::max_passes. Two passes are usually consistent, but where the first
// pass is far off its bands are too, and R0 takes more passes to settle
// (docs/notes/joint-passes.md, "Passes until R0 settles"). Rd settles more slowly
// (fit_joint_full_band says why): the later passes keep R0 and go on while one moves Rd by
// kJointPassRdTolerance or more.

// Band-limited captures: the grid on which step 2 integrates the views' mirror estimates
// for L_00 (CrossViewSystem::lighting reads their interpolant at its texels' centres).
// The grid must resolve the interpolant, not sample it again: a source smaller than a
// texel (studio_small_03's lamps, empty_warehouse_01's, St Fagans' window panes) is
// counted by whether a texel centre falls on its peak, an error that more pixels on the
// object do not reduce. At 1024 x 512 that error is small beside what remains, the views'
// own sampling of those sources, which shrinks with their resolution, and a finer grid
// changes little (docs/notes/small-sources.md, "Step 2's L00: integrate the interpolant,
// do not sample it again"); the grid's cost is in docs/notes/fit-timings.md.
constexpr int kMirrorIntegralWidth = 1024, kMirrorIntegralHeight = 512;

// The views' pairing, once the data are known to constrain the problem (fit_joint's throws).
CrossViewSystem pair_views(const LightingData& data, const SampleSet& samples, const LightingFitOptions& options,
                           const JointFitOptions& joint) {
  const size_t count = data.observed.size();
  if (count < size_t(sh_count(data.lmax)) + 4)
    throw Error("the joint fit needs more samples than unknowns (" + std::to_string(sh_count(data.lmax) + 4) +
                "), got " + std::to_string(count));
  // The views must see directions in common, as the map-consistent solve needs them.
  check_lighting_options(options);
  const double several_views = multi_view_fraction(data, options.solve_width, options.solve_height);
  if (several_views < kMapConsistentFraction)
    throw Error("only " + std::to_string(int(100 * several_views)) +
                "% of the reflected directions are seen from two or more views: material and lighting cannot be "
                "separated; the joint fit needs views from several directions");
  return CrossViewSystem(data, samples, data.noise_free && joint.band_limited_diffuse);
}

// The map-consistent solve for the full-band captures' Rd, on the grid turned by
// kGridTurns fractions of a texel in azimuth. Which texel holds which part of a sharp
// source changes what the texels' values and gradients can represent, and with it the
// misfit's least point: on full-band captures, turning the grid by a fraction of a texel
// moves Rd by more than its bounds. Rd minimises the misfit summed over the turned grids
// instead (the edges' placement averaged out, as in cycle spinning). That also makes the
// coarser 64 x 32 grid the better one (the default: more samples and views per texel pin
// F better, and turning takes away its larger texels' placement error); see
// docs/notes/turned-solve-grid.md. The lighting is solved on the unturned grid.
constexpr int kGridTurns = 4;

const std::string kTurnedSolve =
    "the map-consistent lighting solve at " + std::to_string(kGridTurns) + " turns of its grid";

std::string rd_method(const JointFitOptions& joint) {
  return joint.band_limited_diffuse ? "L_00 of the views' mirror estimates (band-limited diffuse)"
                                    : kTurnedSolve + " (full-band diffuse)";
}

// One line on what the solver did: rounds and evaluations (summed over the passes).
std::string brief_report(const JointFit& fit, const CrossViewSystem& cross, const JointFitOptions& joint) {
  return "joint: " + std::to_string(fit.iterations) + " rounds, " + std::to_string(fit.evaluations) +
         " evaluations over " + std::to_string(cross.pair_count()) + " view pairs, " +
         (fit.converged ? "converged" : "NOT converged") + "; Rd from " + rd_method(joint);
}

// The map-consistent systems (above) of one set of observations: the kGridTurns turns
// where Rd is solved on them, the unturned grid alone (`turned` false) where only the
// lighting is.
class TurnedMapSystems {
 public:
  TurnedMapSystems(const LightingData& data, const LightingFitOptions& options, bool turned) {
    const int turns = turned ? kGridTurns : 1;
    for (int turn = 0; turn < turns; ++turn)
      systems_.emplace_back(data, options.solve_width, options.solve_height, options.ridge, double(turn) / kGridTurns);
  }
  const MapConsistentSystem& unturned() const { return systems_.front(); }

  // Step 2 for full-band captures (joint_fit.h): Rd per channel at R0, where the summed
  // misfit is least (a grid over Rd's bounds, then Brent's method). Needs `turned`.
  RGB Rd(double R0) const {
    if (systems_.size() != size_t(kGridTurns)) throw Error("internal: Rd asked of the unturned solve grid alone");
    const ParameterSpec& rd_bounds = parameter_spec(MaterialParameter::Rd);
    std::vector<MapConsistentSystem::Profile> profiles;
    for (const MapConsistentSystem& system : systems_) profiles.push_back(system.profile(R0));
    std::vector<double> levels;
    for (int i = 0; i <= 20; ++i) levels.push_back(rd_bounds.lower + (rd_bounds.upper - rd_bounds.lower) * i / 20.0);
    RGB Rd;
    for (int c = 0; c < 3; ++c) {
      auto channel = [&](double value) {
        double sum = 0.0;
        for (const MapConsistentSystem::Profile& profile : profiles) sum += profile.squared_error(value, c);
        return sum;
      };
      Rd[c] = float(minimise_on(channel, levels, 1e-4));
    }
    return Rd;
  }

 private:
  std::vector<MapConsistentSystem> systems_;
};

// The lighting at the fit's material. pair_views made sure the map-consistent solve
// applies, so fit_lighting takes `system`; its rms, of that model at the result, is the
// joint fit's (as --mode lighting reports).
void solve_lighting(JointFit& fit, const LightingData& data, const LightingFitOptions& options,
                    const MapConsistentSystem& system) {
  fit.lighting = fit_lighting(data, fit.R0, fit.Rd, options, &system);
  fit.rms = fit.lighting.rms;
}

// One joint fit of `data` on `cross` (built on the same data object); the searches for R0
// stop at `tolerance` relative (minimise_bracketed).
JointFit joint_pass(const LightingData& data, CrossViewSystem& cross, const LightingFitOptions& options,
                    const JointFitOptions& joint, double tolerance, const FitObserver& observer) {
  const ParameterSpec& r0_bounds = parameter_spec(MaterialParameter::R0);
  const ParameterSpec& rd_bounds = parameter_spec(MaterialParameter::Rd);
  std::vector<double> grid;  // R0 from 0 to 1, finest where coats are (0.02-0.06)
  for (double R0 : {0.0,  0.005, 0.01, 0.015, 0.02, 0.025, 0.03, 0.035, 0.04, 0.045, 0.05, 0.06, 0.07,
                    0.08, 0.1,   0.12, 0.15,  0.2,  0.25,  0.3,  0.4,   0.5,  0.6,   0.8,  1.0})
    if (R0 >= r0_bounds.lower && R0 <= r0_bounds.upper) grid.push_back(R0);

  JointFit fit;
  std::string rounds;
  // The robust misfit, keeping the fit at the lowest point evaluated since `best` was
  // last reset: the searches end there, so its diffuse field is not computed again.
  struct {
    double R0 = NAN;
    CrossViewSystem::Fit fit{INFINITY, {}};
  } best;
  auto misfit = [&](double R0) {
    ++fit.evaluations;
    CrossViewSystem::Fit at = cross.fit(R0);
    const double cost = at.cost;
    if (cost < best.fit.cost) best.R0 = R0, best.fit = std::move(at);
    return cost;
  };
  // Band-limited captures take Rd from the views' mirror estimates, not the turned grids.
  const TurnedMapSystems systems(data, options, !joint.band_limited_diffuse);
  // Step 2 at R0: Rd per channel (see joint_fit.h); `lighting` receives the views' own
  // lighting when that is what Rd came from.
  auto diffuse_reflectance = [&](double R0, const Eigen::MatrixXd& d, Eigen::MatrixXd* lighting) {
    RGB Rd;
    if (joint.band_limited_diffuse) {
      *lighting = cross.lighting(R0, d, kMirrorIntegralWidth, kMirrorIntegralHeight);
      const double diffuse_per_Rd = ShadingCoefficients<double>(R0).diffuse;
      for (int c = 0; c < 3; ++c)
        Rd[c] = float(std::clamp(d(0, c) / (diffuse_per_Rd * (*lighting)(0, c)), double(rd_bounds.lower),
                                 double(rd_bounds.upper)));
    } else {
      Rd = systems.Rd(R0);
    }
    return Rd;
  };
  // A start near the answer (the later passes of fit_joint_full_band) skip round 0.
  const bool warm = joint.start_R0.has_value();
  double R0 = warm ? std::clamp(*joint.start_R0, double(r0_bounds.lower), double(r0_bounds.upper)) : 0.04;
  double last_step = INFINITY;
  Eigen::MatrixXd lighting, d;
  for (int round = warm ? 1 : 0; round < joint.max_rounds; ++round) {
    // Round 0 is plain least squares over the whole range; each later round sets the
    // robust scale at the last R0 and searches again.
    if (round > 0) cross.calibrate(R0);
    best.fit.cost = INFINITY;  // the misfit changes with the scale
    const double previous = R0;
    if (round == 0) {
      // A start: every fourth pair is plenty for plain least squares.
      cross.use_every(4);
      R0 = minimise_on(misfit, grid, tolerance);
      cross.use_every(1);
    } else {
      // Near the last R0 (the scale changes the misfit, rarely its minimum by much): after
      // round 0's least squares within 25%, later within four times the last round's
      // step (at least 2%), five points (later three: the ends and the last R0) and
      // Brent's method between the best one's neighbours; the whole grid again when the
      // minimum is at the bracket's edge.
      const double reach = round == 1 ? 0.25 * R0 + 0.002 : std::max(4.0 * last_step, 0.02 * R0 + 0.0005);
      const double low = std::max(double(r0_bounds.lower), R0 - reach);
      const double high = std::min(double(r0_bounds.upper), R0 + reach);
      R0 = minimise_on(
          misfit,
          round == 1 ? std::vector{low, 0.5 * (low + R0), R0, 0.5 * (R0 + high), high} : std::vector{low, R0, high},
          tolerance);
      if (std::abs(R0 - low) < 1e-6 * high || std::abs(R0 - high) < 1e-6 * high)
        R0 = minimise_on(misfit, grid, tolerance);
    }
    ++fit.iterations;
    // The search's fit at R0 when it kept it (a tie can leave another point kept), and
    // after round 0, which searched on a quarter of the pairs, the fit on all of them.
    const CrossViewSystem::Fit at = round > 0 && best.R0 == R0 ? best.fit : cross.fit(R0);
    d = at.d;
    char line[160];
    std::snprintf(line, sizeof line, "round %2d: R0 %.5f, robust misfit %.6g, %d evaluations so far\n", round, R0,
                  at.cost, fit.evaluations);
    rounds += line;
    if (observer) {
      FitIterate iterate;
      iterate.iteration = round;
      iterate.R0 = float(R0);
      iterate.Rd = diffuse_reflectance(R0, at.d, &lighting);
      iterate.cost = at.cost;
      observer(iterate);
    }
    last_step = std::abs(R0 - previous);
    if (round > 0 && last_step < 5e-5) {
      fit.converged = true;
      break;
    }
  }
  fit.R0 = float(R0);
  fit.Rd = diffuse_reflectance(R0, d, &lighting);
  solve_lighting(fit, data, options, systems.unturned());
  // With a band-limited diffuse term L_lm is the diffuse field's: d / (21/(20 pi) (1 - R0)
  // Rd), exact where d is, and consistent with Rd when Rd met its bound (a matte coat,
  // where the views' mirror estimates leave much of the sphere unseen); for a black
  // channel, the views' mirror estimates.
  if (joint.band_limited_diffuse) {
    const double diffuse_per_Rd = ShadingCoefficients<double>(R0).diffuse;
    for (int c = 0; c < 3; ++c) {
      const double per_L = diffuse_per_Rd * fit.Rd[c];
      for (int i = 0; i < lighting.rows(); ++i)
        fit.lighting.coefficients.values[i][c] = per_L > 1e-3 ? d(i, c) / per_L : lighting(i, c);
    }
  }

  const std::string method = rd_method(joint);
  fit.brief_report = brief_report(fit, cross, joint);
  fit.full_report = "Joint fit (inverse/joint_fit.h)\n" + std::to_string(cross.pair_count()) +
                    " sample pairs between views; R0 from their robust misfit, searched on [" +
                    std::to_string(r0_bounds.lower) + ", " + std::to_string(r0_bounds.upper) + "]:\n" + rounds +
                    "Rd from " + method + "\n" + fit.brief_report + "\n";
  return fit;
}

// A later pass of fit_joint_full_band once R0 has settled: Rd and the lighting again at
// that R0, on the observations less the bands the last pass predicted. No search for R0:
// the views' misfit costs most of a pass, and searched again it returned R0 unchanged to
// 1e-5 (red sphere in the blue room, path-traced, passes 3-5).
JointFit rd_pass(const LightingData& data, const LightingFitOptions& options, const JointFit& last) {
  const TurnedMapSystems systems(data, options, true);
  JointFit fit;
  fit.R0 = last.R0;
  fit.Rd = systems.Rd(last.R0);
  solve_lighting(fit, data, options, systems.unturned());
  fit.converged = last.converged;
  fit.full_report = "R0 kept; Rd from " + kTurnedSolve + "\n";
  return fit;
}

}  // namespace

JointFit fit_joint(const LightingData& data, const SampleSet& samples, const LightingFitOptions& options,
                   const JointFitOptions& joint, const FitObserver& observer) {
  CrossViewSystem cross = pair_views(data, samples, options, joint);
  return joint_pass(data, cross, options, joint, kR0Tolerance, observer);
}

JointFit fit_joint_full_band(LightingData& data, const SampleSet& samples, int diffuse_lmax,
                             const LightingFitOptions& options, JointFitOptions joint, const FitObserver& observer) {
  if (joint.band_limited_diffuse || diffuse_lmax <= data.lmax || joint.max_passes <= 1)
    return fit_joint(data, samples, options, joint, observer);
  // The first pass only predicts the bands, for which round 1's R0 is close enough (a
  // round 2 typically moves it by under 1e-4; round 0 alone, plain least squares on a
  // quarter of the pairs, is not: docs/notes/joint-passes.md, "Passes until R0 settles"),
  // and searched to a tenth of the usual precision (1e-3 relative);
  // the later passes are the ones that converge.
  JointFitOptions first_options = joint;
  first_options.max_rounds = std::min(joint.max_rounds, 2);
  // The views' pairing depends on the samples' geometry only, and its noise model on the
  // captured observations (not on what the later passes take off them): all passes share
  // it. It reads `data`, whose observations the later passes replace in place.
  CrossViewSystem cross = pair_views(data, samples, options, joint);
  JointFit fit = joint_pass(data, cross, options, first_options, 10 * kR0Tolerance, observer);
  fit.passes = 1;
  std::string report;
  // Each pass takes off the captured observations the bands that the last one's lighting
  // and material predict, and fits again from its R0, until a pass moves R0 by under
  // kJointPassTolerance and Rd by under kJointPassRdTolerance: the bands and the fit are
  // then consistent with each other.
  for (;;) {
    const JointFit last = std::move(fit);
    take_off_diffuse_bands(data, samples, predict_diffuse_bands(last.lighting.map, diffuse_lmax, last.R0, last.Rd));
    // R0 settles first; Rd then still moves, as the bands are predicted from the last
    // Rd (the mirror fixes the lighting's detail whatever Rd is, so the bands' diffuse
    // radiance goes with Rd) and each pass takes back about nine tenths of the error of
    // the one before, until Rd is at the fit's own error (docs/notes/joint-passes.md,
    // "Passes until Rd settles too"). The first
    // pass has no step to judge by (and searched R0 coarsely), so the second always
    // searches again.
    if (last.passes > 1 && last.pass_step < kJointPassTolerance) {
      fit = rd_pass(data, options, last);
    } else {
      joint.start_R0 = last.R0;
      fit = joint_pass(data, cross, options, joint, kR0Tolerance, observer);
    }
    fit.passes = last.passes + 1;
    fit.iterations += last.iterations, fit.evaluations += last.evaluations;
    char line[200];
    std::snprintf(line, sizeof line,
                  "pass %d: R0 %.5f, Rd %.4f %.4f %.4f; pass %d with bands %d-%d predicted from its "
                  "lighting:\n",
                  last.passes, last.R0, last.Rd[0], last.Rd[1], last.Rd[2], fit.passes, data.lmax + 1, diffuse_lmax);
    report += last.full_report + line;
    fit.pass_step = std::abs(double(fit.R0) - double(last.R0));
    fit.pass_Rd_step = (fit.Rd - last.Rd).abs().maxCoeff();
    if (fit.passes_settled() || fit.passes >= joint.max_passes) break;
  }
  // Not settled: the bands taken off and the fit are not yet consistent with each other,
  // and R0 and Rd may be off by about their last steps.
  const bool settled = fit.passes_settled();
  fit.converged = fit.converged && settled;
  char passes[200];
  std::snprintf(passes, sizeof passes,
                "; diffuse bands %d-%d from the last pass's lighting (%d passes, %s R0 by %.5f and Rd by %.5f)",
                data.lmax + 1, diffuse_lmax, fit.passes, settled ? "the last moved" : "NOT settled: the last moved",
                fit.pass_step, fit.pass_Rd_step);
  fit.brief_report = brief_report(fit, cross, joint) + passes;
  fit.full_report = report + fit.full_report + "All passes: " + fit.brief_report + "\n";
  return fit;
}

}  // namespace glaze

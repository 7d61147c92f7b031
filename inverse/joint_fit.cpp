#include "inverse/joint_fit.h"

#include "renderer/error.h"
#include "renderer/material.h"

#include <ceres/ceres.h>

#include <array>
#include <utility>
#include <vector>
#include <cmath>

namespace glaze {
namespace {

// The system's profiles at the R0 values asked for last: Ceres' central differences
// ask for R0 and R0 +- h while the Rd vary, so a handful covers an iteration, and each
// costs one pass over the texels. (One Ceres thread: no locking.)
class ProfileCache {
 public:
  explicit ProfileCache(const MapConsistentSystem& system) : system_(system) {}
  const MapConsistentSystem::Profile& at(double R0) {
    for (const auto& [key, profile] : entries_)
      if (key == R0) return profile;
    if (entries_.size() == kSize) entries_.erase(entries_.begin());
    entries_.emplace_back(R0, system_.profile(R0));
    return entries_.back().second;
  }

 private:
  static constexpr size_t kSize = 4;
  const MapConsistentSystem& system_;
  std::vector<std::pair<double, MapConsistentSystem::Profile>> entries_;
};

// One residual per channel: the square root of the channel's least-squares misfit for
// material (R0, Rd_c), minimised over its lighting. The channels share only R0.
struct JointMisfit {
  ProfileCache* profiles;
  bool operator()(const double* const material, double* residuals) const {
    const MapConsistentSystem::Profile& profile = profiles->at(material[0]);
    for (int c = 0; c < 3; ++c) residuals[c] = std::sqrt(profile.squared_error(material[1 + c], c));
    return true;
  }
};

// Bounded Levenberg-Marquardt over (R0, Rd) from `material`, which it updates.
ceres::Solver::Summary solve_material(ProfileCache& profiles, std::array<double, 4>& material, int max_iterations,
                                      const FitObserver& observer) {
  const ParameterSpec& r0_bounds = parameter_spec(MaterialParameter::R0);
  const ParameterSpec& rd_bounds = parameter_spec(MaterialParameter::Rd);
  ceres::Problem problem;
  problem.AddResidualBlock(new ceres::NumericDiffCostFunction<JointMisfit, ceres::CENTRAL, 3, 4>(new JointMisfit{&profiles}),
                           nullptr, material.data());
  problem.SetParameterLowerBound(material.data(), 0, r0_bounds.lower);
  problem.SetParameterUpperBound(material.data(), 0, r0_bounds.upper);
  for (int c = 1; c <= 3; ++c) {
    problem.SetParameterLowerBound(material.data(), c, rd_bounds.lower);
    problem.SetParameterUpperBound(material.data(), c, rd_bounds.upper);
  }
  ceres::Solver::Options solver;
  solver.minimizer_type = ceres::TRUST_REGION;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = max_iterations;
  solver.function_tolerance = 1e-12;
  solver.gradient_tolerance = 1e-14;
  solver.parameter_tolerance = 1e-10;
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  FitObserverCallback report(observer, [&](FitIterate& iterate) {
    iterate.R0 = float(material[0]);
    iterate.Rd = RGB(float(material[1]), float(material[2]), float(material[3]));
  });
  if (observer) {
    solver.update_state_every_iteration = true;
    solver.callbacks.push_back(&report);
  }
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  return summary;

}

}  // namespace

JointFit fit_joint(const LightingData& data, const LightingFitOptions& options, int max_iterations,
                   const FitObserver& observer) {
  const size_t count = data.observed.size();
  if (count < size_t(sh_count(data.lmax)) + 4)
    throw Error("the joint fit needs more samples than unknowns (" + std::to_string(sh_count(data.lmax) + 4) + "), got " +
                std::to_string(count));
  // Probe the views: the lighting fit reports how many directions several views see.
  const LightingFit probe = fit_lighting(data, 0.04f, RGB::Constant(0.5f), options);
  if (!probe.map_consistent)
    throw Error("only " + std::to_string(int(100 * probe.multi_view_fraction)) +
                "% of the reflected directions are seen from two or more views: material and lighting cannot be "
                "separated; the joint fit needs views from several directions");
  const MapConsistentSystem system(data, options.solve_width, options.solve_height, options.ridge);
  ProfileCache profiles(system);

  // Start from the best of a coarse grid: for each R0 the channels separate, so each
  // channel's Rd is chosen on its own.
  std::array<double, 4> material{0.04, 0.5, 0.5, 0.5};
  double best = INFINITY;
  for (double R0 : {0.01, 0.02, 0.04, 0.07, 0.12, 0.2, 0.35, 0.6}) {
    std::array<double, 4> candidate{R0, 0, 0, 0};
    double total = 0.0;
    const MapConsistentSystem::Profile& profile = profiles.at(R0);
    for (int c = 0; c < 3; ++c) {
      double channel_best = INFINITY;
      for (double Rd : {0.02, 0.1, 0.25, 0.45, 0.65, 0.85, 1.0}) {
        const double error = profile.squared_error(Rd, c);
        if (error < channel_best) channel_best = error, candidate[1 + c] = Rd;
      }
      total += channel_best;
    }
    if (total < best) best = total, material = candidate;
  }

  const ceres::Solver::Summary summary = solve_material(profiles, material, max_iterations, observer);

  JointFit fit;
  fit.R0 = float(material[0]);
  fit.Rd = RGB(float(material[1]), float(material[2]), float(material[3]));
  fit.iterations = int(summary.iterations.size()) - 1;
  fit.converged = summary.termination_type == ceres::CONVERGENCE;
  fit.brief_report = summary.BriefReport();
  fit.full_report = summary.FullReport();
  fit.rms = std::sqrt(2.0 * summary.final_cost / (3.0 * count));
  fit.lighting = fit_lighting(data, fit.R0, fit.Rd, options);
  return fit;
}

}  // namespace glaze

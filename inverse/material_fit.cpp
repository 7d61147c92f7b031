#include "inverse/material_fit.h"

#include "inverse/diffuse_solve.h"
#include "inverse/footprint.h"
#include "renderer/error.h"
#include "renderer/shading.h"
#include "renderer/sh.h"

#include <ceres/ceres.h>
#include <tbb/parallel_for.h>

#include <cmath>

namespace glaze {

std::vector<ShadingTerms> shading_terms(const SampleSet& samples, const CaptureSet& captures, const RayTracer& tracer,
                                        const Environment& environment, int lmax, int footprint) {
  if (footprint < 1 || footprint > 16) throw Error("the pixel footprint must be 1 to 16 rays per side");
  const ShDiffuseSum diffuse_sum(environment.sh(lmax));
  std::vector<ShadingTerms> terms(samples.samples.size());
  tbb::parallel_for(size_t(0), samples.samples.size(), [&](size_t k) {
    // The mirror term averaged over the footprint's rays; E, smooth across a pixel, at the
    // normal seen through its centre.
    for_each_model_pixel(samples, k, captures, tracer, footprint,
                         [&](const Vec3& centre_normal, const std::vector<FootprintRay>& rays, float weight) {
                           const RGB E = diffuse_sum(centre_normal);
                           const float share = weight / rays.size();
                           for (const FootprintRay& ray : rays) {
                             const RGB L = environment.eval(reflect(ray.view, ray.normal));
                             const float mu = ray.normal.dot(ray.view);
                             for (int c = 0; c < 3; ++c) {
                               ShadingBasis<float> basis(mu, L[c], E[c]);
                               terms[k][c] += (basis *= share);
                             }
                           }
                         });
  });
  return terms;
}

RobustLoss RobustLoss::parse(const std::string& name, double scale) {
  RobustLoss loss;
  if (name == "none")
    loss.kind = Kind::none;
  else if (name == "huber")
    loss.kind = Kind::huber;
  else if (name == "cauchy")
    loss.kind = Kind::cauchy;
  else
    throw Error("unknown loss '" + name + "' (known: none, huber, cauchy)");
  if (loss.kind != Kind::none && !(scale > 0.0 && std::isfinite(scale)))
    throw Error("the loss scale must be a positive number");
  loss.scale = scale;
  return loss;
}

RGB predict(const ShadingTerms& terms, float R0, const RGB& Rd) {
  RGB result;
  for (int c = 0; c < 3; ++c) result[c] = ShadingCoefficients<float>(R0, Rd[c]).radiance(terms[c]);
  return result;
}

namespace {

// rho(s) / s for the squared residual s: 1 for least squares, and the robust losses'
// ratio, which is smooth and bounded so that r sqrt(rho / s) keeps Jets finite at r = 0.
template <typename T>
T loss_ratio(const RobustLoss& loss, const T& s) {
  const double d2 = loss.scale * loss.scale;
  switch (loss.kind) {
    case RobustLoss::Kind::huber:
      if (s <= T(d2)) return T(1);
      return (T(2 * loss.scale) * sqrt(s) - T(d2)) / s;
    case RobustLoss::Kind::cauchy: {
      const T x = s / T(d2);
      if (x < T(1e-8)) return T(1) - x / T(2);
      return log(T(1) + x) / x;
    }
    case RobustLoss::Kind::none:
      break;
  }
  return T(1);
}

// d rho / d s: the IRLS weight of a residual.
double loss_weight(const RobustLoss& loss, double s) {
  const double d2 = loss.scale * loss.scale;
  switch (loss.kind) {
    case RobustLoss::Kind::huber:
      return s <= d2 ? 1.0 : loss.scale / std::sqrt(s);
    case RobustLoss::Kind::cauchy:
      return 1.0 / (1.0 + s / d2);
    case RobustLoss::Kind::none:
      break;
  }
  return 1.0;
}

// The nested model's residuals for a given R0 with a robust loss: all samples x 3
// channels, each sqrt(weight) (o - s - Rd b) robustified, with Rd the inner solve of its
// group (IRLS). Without a robust loss MomentResidual computes the same objective faster.
class NestedResidual {
 public:
  NestedResidual(std::span<const Sample> samples, std::span<const ShadingTerms> terms, std::span<const int> group,
                 int groups, std::span<const float> weights, const RobustLoss& loss)
      : samples_(samples), terms_(terms), group_(group), groups_(groups), weights_(weights), loss_(loss) {}

  int residual_count() const { return int(samples_.size()) * 3; }

  template <typename T>
  bool operator()(const T* const R0, T* residuals) const {
    const std::vector<double> robust = robust_weights(scalar(R0[0]));
    const std::vector<DiffuseNormalEquations<T>> inner = solve(R0[0], robust);
    for (size_t k = 0; k < samples_.size(); ++k) {
      const Sample& sample = samples_[k];
      const auto& equations = inner[group_of(k)];
      for (int c = 0; c < 3; ++c) {
        const T r = T(sample.observed[c]) - prediction(R0[0], equations.solve(c), k, c);
        residuals[3 * k + c] = T(std::sqrt(base_weight(k))) * r * sqrt(loss_ratio(loss_, r * r));
      }
    }
    return true;
  }

  // The inner solve at R0, with the robust weights of its converged IRLS.
  std::vector<DiffuseNormalEquations<double>> inner_solve(double R0) const { return solve(R0, robust_weights(R0)); }

 private:
  static double scalar(double x) { return x; }
  template <typename J>
  static double scalar(const J& x) {
    return x.a;
  }

  int group_of(size_t k) const { return group_.empty() ? 0 : group_[k]; }
  double base_weight(size_t k) const { return weights_.empty() ? 1.0 : weights_[k]; }

  template <typename T>
  T prediction(const T& R0, const T& Rd, size_t k, int c) const {
    return ShadingCoefficients<T>(R0, Rd).radiance(terms_[k][c]);
  }

  // Per group and channel, the weighted normal equations at R0 (robust weights fixed).
  template <typename T>
  std::vector<DiffuseNormalEquations<T>> solve(const T& R0, const std::vector<double>& robust) const {
    std::vector<DiffuseNormalEquations<T>> equations(groups_);
    const ShadingCoefficients<T> per_unit_Rd(R0);
    for (size_t k = 0; k < samples_.size(); ++k) {
      const Sample& sample = samples_[k];
      for (int c = 0; c < 3; ++c) {
        const T specular = per_unit_Rd.specular_radiance(terms_[k][c]);
        const T basis = per_unit_Rd.diffuse_radiance(terms_[k][c]);
        equations[group_of(k)].add(c, base_weight(k) * robust[3 * k + c], double(sample.observed[c]), specular, basis);
      }
    }
    return equations;
  }

  // IRLS for the robust loss at a fixed R0: weights rho'(r^2) from the residuals of the
  // previous inner solve, a few rounds (all 1 without a robust loss).
  std::vector<double> robust_weights(double R0) const {
    std::vector<double> robust(residual_count(), 1.0);
    if (loss_.kind == RobustLoss::Kind::none) return robust;
    for (int round = 0; round < 8; ++round) {
      const std::vector<DiffuseNormalEquations<double>> equations = solve(R0, robust);
      for (size_t k = 0; k < samples_.size(); ++k)
        for (int c = 0; c < 3; ++c) {
          const double r = samples_[k].observed[c] - prediction(R0, equations[group_of(k)].solve(c), k, c);
          robust[3 * k + c] = loss_weight(loss_, r * r);
        }
    }
    return robust;
  }

  std::span<const Sample> samples_;
  std::span<const ShadingTerms> terms_;
  std::span<const int> group_;
  int groups_;
  std::span<const float> weights_;
  RobustLoss loss_;
};

// Least squares without a robust loss, in closed form. Per group and channel, sample k's
// residual is linear in z = (1, q, q Rd) with q = 1 - R0 (shading.h's ShadingCoefficients,
// s = K Rd q with K = 21/(20 pi)):
//   r_k = (o - L) + q gL - q Rd K gE = v_k . z,   v_k = (o - L, gL, -K gE),
// so sum_k w_k r_k^2 = z^T M z with M = sum_k w_k v_k v_k^T. Factoring M = U^T U turns that
// sum into the three residuals U z: exactly the per-sample objective and its Jacobian,
// at a cost per evaluation independent of the number of samples.
class MomentResidual {
 public:
  MomentResidual(std::span<const Sample> samples, std::span<const ShadingTerms> terms, std::span<const int> group,
                 int groups, std::span<const float> weights)
      : moments_(size_t(groups) * 3, Eigen::Matrix3d::Zero()) {
    for (size_t k = 0; k < samples.size(); ++k) {
      const double w = weights.empty() ? 1.0 : weights[k];
      for (int c = 0; c < 3; ++c) {
        const ShadingBasis<float>& b = terms[k][c];
        const Eigen::Vector3d v(double(samples[k].observed[c]) - b.L, b.gL, -kDiffuseNormalisation * b.gE);
        moments_[size_t(group.empty() ? 0 : group[k]) * 3 + c] += w * v * v.transpose();
      }
    }
    for (const Eigen::Matrix3d& m : moments_) {
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(m);
      factors_.push_back(eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() * eigen.eigenvectors().transpose());
    }
  }

  int residual_count() const { return int(moments_.size()) * 3; }

  template <typename T>
  bool operator()(const T* const R0, T* residuals) const {
    const T q = ShadingCoefficients<T>(R0[0]).transmittance;
    for (size_t group = 0; group < moments_.size() / 3; ++group) {
      const DiffuseNormalEquations<T> equations = equations_of(group, q);
      for (int c = 0; c < 3; ++c) {
        const T z[3] = {T(1), q, q * equations.solve(c)};
        const Eigen::Matrix3d& U = factors_[group * 3 + c];
        for (int i = 0; i < 3; ++i)
          residuals[(group * 3 + c) * 3 + i] = T(U(i, 0)) * z[0] + T(U(i, 1)) * z[1] + T(U(i, 2)) * z[2];
      }
    }
    return true;
  }

  std::vector<DiffuseNormalEquations<double>> inner_solve(double R0) const {
    std::vector<DiffuseNormalEquations<double>> all;
    const double q = ShadingCoefficients<double>(R0).transmittance;
    for (size_t group = 0; group < moments_.size() / 3; ++group) all.push_back(equations_of(group, q));
    return all;
  }

 private:
  // The inner solve's normal equations from the moments: with b = q K gE = -q v_3 and
  // o - s = v_1 + q v_2, sum w b (o - s) = -q (M_31 + q M_32) and sum w b^2 = q^2 M_33.
  template <typename T>
  DiffuseNormalEquations<T> equations_of(size_t group, const T& q) const {
    DiffuseNormalEquations<T> equations;
    for (int c = 0; c < 3; ++c) {
      const Eigen::Matrix3d& m = moments_[group * 3 + c];
      equations.numerator[c] = -q * (T(m(2, 0)) + q * T(m(2, 1)));
      equations.denominator[c] = q * q * T(m(2, 2));
    }
    return equations;
  }

  std::vector<Eigen::Matrix3d> moments_;  // per group and channel
  std::vector<Eigen::Matrix3d> factors_;  // U with U^T U = M
};

// Sum of squared residuals at R0, for the starting-point search.
template <typename Residual>
double sum_of_squares(const Residual& residual, double R0) {
  std::vector<double> residuals(residual.residual_count());
  residual(&R0, residuals.data());
  double sum = 0.0;
  for (double r : residuals) sum += r * r;
  return sum;
}

// The outer search over R0 for either residual: the best of a coarse grid (the objective
// need not be convex), then Ceres from there.
template <typename Residual>
MaterialFit solve_outer(const Residual& residual, const MaterialFitOptions& options) {
  const ParameterSpec& bounds = parameter_spec(MaterialParameter::R0);
  double R0 = bounds.lower, best = INFINITY;
  for (int i = 0; i <= 40; ++i) {
    const double candidate = bounds.lower + (bounds.upper - bounds.lower) * i / 40.0;
    const double cost = sum_of_squares(residual, candidate);
    if (cost < best) best = cost, R0 = candidate;
  }
  ceres::Problem problem;
  problem.AddResidualBlock(
      new ceres::AutoDiffCostFunction<Residual, ceres::DYNAMIC, 1>(new Residual(residual), residual.residual_count()),
      nullptr, &R0);
  problem.SetParameterLowerBound(&R0, 0, bounds.lower);
  problem.SetParameterUpperBound(&R0, 0, bounds.upper);
  ceres::Solver::Options solver;
  solver.minimizer_type = ceres::TRUST_REGION;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = 1e-15;
  solver.gradient_tolerance = 1e-15;
  solver.parameter_tolerance = 1e-12;
  solver.num_threads = 1;  // one residual block: nothing to spread; keeps results bit-identical
  solver.logging_type = ceres::SILENT;
  FitObserverCallback report(options.observer, [&](FitIterate& iterate) {
    iterate.R0 = float(R0);
    const auto equations = residual.inner_solve(R0);
    for (int c = 0; c < 3; ++c) iterate.Rd[c] = float(equations.front().solve(c));
  });
  if (options.observer) {
    solver.update_state_every_iteration = true;
    solver.callbacks.push_back(&report);
  }
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);

  MaterialFit fit;
  fit.R0 = static_cast<float>(R0);
  fit.iterations = static_cast<int>(summary.iterations.size()) - 1;
  fit.converged = summary.termination_type == ceres::CONVERGENCE;
  fit.brief_report = summary.BriefReport();
  fit.full_report = summary.FullReport();
  for (const auto& equations : residual.inner_solve(R0)) {
    RGB Rd, unclamped;
    RGBd constraint;
    for (int c = 0; c < 3; ++c) {
      Rd[c] = float(equations.solve(c));
      unclamped[c] = float(equations.unclamped(c));
      constraint[c] = equations.denominator[c];
    }
    fit.Rd.push_back(Rd);
    fit.Rd_unclamped.push_back(unclamped);
    fit.constraint.push_back(constraint);
  }
  return fit;
}

}  // namespace

MaterialFit fit_material(std::span<const Sample> samples, std::span<const ShadingTerms> terms,
                         std::span<const int> group, int groups, std::span<const float> weights,
                         const MaterialFitOptions& options) {
  if (samples.empty()) throw Error("no samples to fit");
  if (terms.size() != samples.size() || (!group.empty() && group.size() != samples.size()) ||
      (!weights.empty() && weights.size() != samples.size()))
    throw Error("fit_material: per-sample arrays differ in length");
  for (float w : weights)
    if (!(w >= 0.0f && std::isfinite(w))) throw Error("fit_material: sample weights must be finite and non-negative");
  double light = 0.0;
  for (const Sample& s : samples) light += s.observed.abs().sum();
  if (!(light > 1e-12 * samples.size()))
    throw Error(
        "the images are black wherever the object is seen: there is no light to fit a material to "
        "(check the exposure and that the object is lit)");

  const int group_count = group.empty() ? 1 : groups;
  MaterialFit fit =
      options.loss.kind == RobustLoss::Kind::none
          ? solve_outer(MomentResidual(samples, terms, group, group_count, weights), options)
          : solve_outer(NestedResidual(samples, terms, group, group_count, weights, options.loss), options);
  double squared = 0.0;
  for (size_t k = 0; k < samples.size(); ++k) {
    const RGB r = samples[k].observed - predict(terms[k], fit.R0, fit.Rd[group.empty() ? 0 : group[k]]);
    squared += r.cast<double>().square().sum();
  }
  fit.rms = std::sqrt(squared / (3.0 * samples.size()));
  return fit;
}

}  // namespace glaze

// fit_progress.h: how the material and joint fits report their iterates while they run, so that
// a caller can show them (`glaze invert-fit --preview` re-renders each view at them).
// The report is optional and costs nothing when no observer is set.
#pragma once

#include "renderer/math.h"

#include <ceres/iteration_callback.h>

#include <functional>

namespace glaze {

struct FitIterate {
  int iteration = 0;  // Ceres' iteration number (0: the starting point); the joint fit's round
  float R0 = 0.0f;
  RGB Rd = RGB::Zero();
  double cost = 0.0;  // Ceres' cost (half the sum of squared residuals)
};

// Called on the solver's thread after every iteration; it should return quickly.
using FitObserver = std::function<void(const FitIterate&)>;

// The Ceres side: `current` turns the parameter values (current at every iteration, as
// the solver is told with update_state_every_iteration) into R0 and Rd.
class FitObserverCallback : public ceres::IterationCallback {
 public:
  FitObserverCallback(const FitObserver& observer, std::function<void(FitIterate&)> current)
      : observer_(observer), current_(std::move(current)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    FitIterate iterate;
    iterate.iteration = summary.iteration;
    iterate.cost = summary.cost;
    current_(iterate);
    observer_(iterate);
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const FitObserver& observer_;
  std::function<void(FitIterate&)> current_;
};

}  // namespace glaze

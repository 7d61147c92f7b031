#include "renderer/quadrature.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace glaze {

QuadratureRule gauss_legendre(int n, double a, double b) {
  if (n < 1) throw std::invalid_argument("gauss_legendre: n must be >= 1");
  QuadratureRule rule;
  rule.nodes.resize(n);
  rule.weights.resize(n);
  const double half_width = 0.5 * (b - a);
  const double mid = 0.5 * (b + a);
  // Roots of P_n by Newton's method from Tricomi's initial guess; symmetric pairs.
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double x = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
    double derivative = 1.0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      double p0 = 1.0, p1 = x;  // P_0, P_1
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      derivative = n * (x * p1 - p0) / (x * x - 1.0);  // P_n'(x)
      const double step = p1 / derivative;
      x -= step;
      if (std::abs(step) < 1e-16) break;
    }
    const double weight = 2.0 / ((1.0 - x * x) * derivative * derivative);
    rule.nodes[i] = mid - half_width * x;
    rule.nodes[n - 1 - i] = mid + half_width * x;
    rule.weights[i] = rule.weights[n - 1 - i] = half_width * weight;
  }
  return rule;
}

}  // namespace glaze

// quadrature.h: Gauss-Legendre rules. An n-point rule integrates polynomials of degree
// 2n-1 exactly, which is how glaze computes the SH kernel coefficients h_l for any l
// (the integrand is a polynomial) and the per-row integrals of the SH projection.
#pragma once

#include <vector>

namespace glaze {

struct QuadratureRule {
  std::vector<double> nodes;
  std::vector<double> weights;
};

// n-point Gauss-Legendre rule on [a, b] (n >= 1), nodes ascending.
QuadratureRule gauss_legendre(int n, double a = -1.0, double b = 1.0);

}  // namespace glaze

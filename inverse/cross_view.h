// cross_view.h: the coat's Fresnel factor measured by comparing views (the joint fit's
// first step, docs/design.md §5).
//
// Each view sees the environment mirrored in the coat: sample k of a view observes
//   o_k = F(n.v) L(r_k) + c_k . d,     d = 21/(20 pi) (1 - R0) Rd L_lm  (the diffuse field)
// and another view sees the same direction r_k elsewhere on the object, at another n.v.
// Interpolating the other view's samples around r_k (on its own pixel grid, the finest
// resolution the data has) gives a second estimate of L(r_k), and
//   o_a - c_a . d  =  F_a  sum_j w_j (o_j - c_j . d) / F_j
// must hold for the true R0 and d whatever the lighting is: L is eliminated, not
// discretised. For a fixed R0 this is linear in d, so the misfit profile is a function
// of R0 alone; its minimum is the coat. (What fixes R0 is the change of F with n.v near
// grazing, where the coat becomes a mirror of strength ~1: the lighting's absolute scale
// comes with it.)
//
// The interpolation is quadratic, and it compares like with like: a pixel records the
// mean of F L over its footprint, which on the reflected directions is a patch of about
// the same solid angle at every n.v but stretched by 1/n.v along the tilt, so that a
// grazing pixel averages the lighting's curvature over a longer patch than a pixel seen
// near the normal. With L = L0 + g.u + u^T H u / 2 around r, pixel j records
// L(u_j) + tr(H S_j) / 2 (S_j: its footprint's covariance) and sample a records
// L0 + tr(H S_a) / 2. The weights w_j over the other view's 3 x 3 pixels nearest r (or
// 5 x 5, below) are the least-squares quadratic's through their records, evaluated at
// sample a's own footprint: second-order exact, where linear interpolation on a triangle
// leaves sum_j w_j u_j^T H u_j / 2 + tr(H (sum_j w_j S_j - S_a)) / 2, an error that
// changes with n.v as F does and so biases R0 under small bright sources
// (docs/notes/cross-view-comparison.md, "Linear against quadratic interpolation").
//
// The comparison multiplies the other view's noise by F_a / F_j: up to about 9 where
// sample a is grazing (F ~ 0.35) and the other view sees r head-on (F = R0). Those are
// the pairs that fix R0 (the change of F between the two views is largest), and their
// noise is the other view's, where the mirror is a few percent of a pixel's level. Where
// the other view sees r nearer its normal than sample a does (F_j < F_a, whatever R0 is)
// the quadratic goes through its 5 x 5 pixels instead (on captures with noise; noise-free
// ones keep 3 x 3, as nothing is there to average): 25 records for six unknowns, the
// same second-order exactness, and the weights' sum of squares (the factor on that
// view's noise variance) 0.14-0.15 against 0.38-0.56 through 3 x 3. The other pairs keep
// 3 x 3: their noise is sample a's own. So do those where the quadratic does not fit the
// 25 pixels to within their noise (cross_view.cpp, kGoodness): across a small lamp's
// reflection the wider quadratic smooths it by an amount that changes with n.v as F
// does, and biases R0 (docs/notes/studio-lamps.md). The price of 5 x 5 is a wider patch
// for the quadratic, which smooths a map's detail at low resolutions; 3 x 3 everywhere,
// 5 x 5 everywhere and 7 x 7 were measured against it (docs/notes/cross-view-comparison.md,
// "5 x 5 stencils where the other view sees the direction nearer its normal").
//
// Where the lighting has detail finer than the sample spacing (a window's edge, a small
// lamp) no interpolation is right and the equation does not hold. Where the other view
// sees r nearer grazing than sample a does, its pixels span more of the directions than
// sample a's footprint, and no quadratic through them recovers the detail that sample a
// records: on captures with noise such a pair is left out where the quadratic misfits
// the 3 x 3 pixels by more than their noise (the same test). A robust loss would only
// down-weight it, and with the loss's scale set by the noise a misfit of a few noise
// levels still pulls, with the sign that F's change with n.v gives it, so that R0 comes
// out high wherever the views see a lamp near their normals. Where the other view sees
// r nearer its normal, its pixels are the finer ones and sample a records their mean,
// which the quadratic's value at sample a's footprint follows even across a lamp's edge:
// those pairs are kept (leaving them out too took R0 from +0.003 to +0.005-0.008 under
// small lamps, docs/notes/photo-shoots.md). The misfits that remain are outliers, which
// a robust reweighting (Cauchy's) down-weights; on noise-free captures with a
// band-limited diffuse term, where they are the only misfit, a trimming then drops them
// (cross_view.cpp, kTrim).
#pragma once

#include "inverse/lighting_fit.h"
#include "inverse/noise_model.h"
#include "inverse/samples.h"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace glaze {

class ReflectedMesh;  // cross_view.cpp

class CrossViewSystem {
 public:
  // Pairs every sample with each other view that reflects its direction; `samples` must be
  // pixel samples (the pixel grid is the interpolation mesh). Throws glaze::Error when no
  // two views see a common direction. The pairs' noise is the captures' (data.noise,
  // noise_model.h); noise-free captures (data.noise_free) keep every pair's quadratic on
  // 3 x 3 pixels (nothing to average: see above). `trim`: the diffuse field is trimmed
  // (cross_view.cpp), for captures that the model fits up to the interpolation's error:
  // noise-free, with a band-limited diffuse term.
  CrossViewSystem(const LightingData& data, const SampleSet& samples, bool trim);
  // The meshes refer to the grids: not copied.
  CrossViewSystem(const CrossViewSystem&) = delete;
  CrossViewSystem& operator=(const CrossViewSystem&) = delete;

  ~CrossViewSystem();

  // The robust misfit at R0 (Cauchy loss of the pair residuals, each divided by its
  // noise), minimised over the diffuse field d by iteratively reweighted least squares;
  // with `trim` d is then trimmed and the misfit taken at it.
  struct Fit {
    double cost = 0.0;
    Eigen::MatrixXd d;  // per channel (columns)
  };
  Fit fit(double R0) const;

  // Sets the robust scale from the residuals' median absolute deviation at R0 (first the
  // least-squares fit's, then the robust fit's; at least 0.1% of the pixel's level). Before it:
  // least squares.
  void calibrate(double R0);

  // The lighting's SH coefficients (columns: channels) at (R0, d): each view's mirror
  // estimates (o - c.d) / F, interpolated on its mesh at the centres of a width x height
  // lat-long grid and combined across views by their sampling density (the inverse of
  // the interpolating triangle's solid angle; a view where F < 0.01 is left out), integrated
  // against Y_lm;
  // directions no view reflects take the SH reconstruction itself (the fixed point
  // L = sum_seen Omega Y L + sum_unseen Omega Y Y^T L). `seen` receives the fraction of the
  // sphere's solid angle some view reflects.
  Eigen::MatrixXd lighting(double R0, const Eigen::MatrixXd& d, int width, int height, double* seen = nullptr) const;

  // Uses every stride-th pair only (1: all), for a quick first estimate.
  void use_every(size_t stride) { stride_ = std::max<size_t>(stride, 1); }

  size_t pair_count() const { return pairs_.size(); }

 private:
  // The other view's samples around a sample's direction and their interpolation weights
  // (sum 1): its 3 x 3 or 5 x 5 pixels nearest the direction (above), or the three
  // corners of the triangle that holds it where too few of those exist, at the edge of
  // the object.
  static constexpr int kWidestStencil = 25;
  struct Stencil {
    uint32_t count = 0;
    std::array<uint32_t, kWidestStencil> member;
    std::array<float, kWidestStencil> weight;
  };
  // Sample `sample` of view a and the other view's stencil, stored flat at `first` in
  // members_ and weights_ (all stencils are 3 x 3 on noise-free captures, about half on
  // captures with noise: a 5 x 5 slot for each would more than double the pairs' memory).
  struct Pair {
    uint32_t sample;
    uint32_t count;
    size_t first;
  };
  // Replaces the stencil's linear weights on its triangle by the quadratic's on the 5 x 5
  // pixels around the corner nearest r (`with_noise`: where the other view sees r nearer
  // its normal than `sample` does and the quadratic fits them: see above), else or where
  // that fails on the 3 x 3; leaves it as it is where too few pixels exist or their
  // quadratic is ill-conditioned. False where the pair is left out: `with_noise`, the
  // other view sees r nearer grazing, and the 3 x 3 pixels' quadratic misfits them by
  // more than their noise (the lighting has detail there that the other view's pixels do
  // not resolve). `steps`: per sample, the change of its reflected direction per pixel
  // along the film's x and y.
  bool interpolate_quadratically(const ReflectedMesh& mesh, const SampleSet& samples,
                                 const std::vector<std::array<Vec3, 2>>& steps, uint32_t sample, bool with_noise,
                                 Stencil& s) const;
  // The quadratic's weights on the (2 reach + 1)^2 pixels around `corner` (the other
  // view's sample nearest r), written to `s` where `fitted`; `degenerate` where too few
  // pixels exist or their quadratic is ill-conditioned, `unresolved` where (`test_fit`)
  // it misfits them by more than their noise (data.noise). Either leaves `s` as it is.
  enum class StencilFit { fitted, degenerate, unresolved };
  StencilFit quadratic_weights(const ReflectedMesh& mesh, const SampleSet& samples,
                               const std::vector<std::array<Vec3, 2>>& steps, uint32_t sample, uint32_t corner,
                               int reach, bool test_fit, Stencil& s) const;
  // Per sample, 1 / F(n.v) at R0: computed once per R0, read by every pair.
  std::vector<double> inverse_fresnel(double R0) const;
  // The residual's data and diffuse parts of pair p at the R0 of `inverse_F`, and its
  // noise weight.
  void pair_terms(const Pair& p, const std::vector<double>& inverse_F, Eigen::Ref<Eigen::VectorXd> x,
                  Eigen::Ref<Eigen::Vector3d> y, Eigen::Ref<Eigen::Vector3d> weight) const;
  // pair_terms of every pair in use (each stride_-th) at one R0. A fit reads them four
  // times (three reweighted solves and the residuals), so they are formed once, for the
  // terms of one R0 held meanwhile: summing over the stencils is much of a joint fit's time
  // (docs/notes/fit-timings.md). x is held in float: its rounding, 6e-8 of |x|, is far
  // below the residuals it explains (at least 1e-5 of a pixel's level on noise-free
  // captures); y, a difference of nearly equal observations, in double.
  struct PairTerms {
    Eigen::MatrixXf x;                                   // n_ x pairs in use
    Eigen::Matrix<double, Eigen::Dynamic, 3> y, weight;  // pairs in use x channels
  };
  PairTerms pair_terms(double R0) const;
  // The robust fit (fit) on one R0's pair terms.
  Fit fit(const PairTerms& terms) const;
  // Weighted least squares for d; pair weights: the inverse noise variance, times the
  // robust weight of the pair's residual at `reweight_at` when given: Cauchy's, or
  // Welsch's where `trim`; c2 is the loss's width squared, in units of the noise model.
  Eigen::MatrixXd solve(const PairTerms& terms, const Eigen::MatrixXd* reweight_at, double c2, bool trim = false) const;
  // Per pair in use, its residual's squared norm in units of its noise.
  std::vector<double> normalised_residuals(const PairTerms& terms, const Eigen::MatrixXd& d) const;
  // The same for the pairs in use [first, first + X.cols()), whose x is X (in double).
  static Eigen::ArrayXd normalised_residuals(const PairTerms& terms, Eigen::Index first, const Eigen::MatrixXd& X,
                                             const Eigen::MatrixXd& d);

  const LightingData& data_;
  int n_;
  std::vector<PixelGrid> grids_;       // per view
  std::vector<ReflectedMesh> meshes_;  // per view, on its grid
  std::vector<Pair> pairs_;
  std::vector<uint32_t> members_;
  std::vector<float> weights_;
  bool trim_;
  double scale_ = INFINITY;  // robust scale of the normalised residuals
  size_t stride_ = 1;
};

}  // namespace glaze

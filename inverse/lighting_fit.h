// lighting_fit.h: lighting from an object of known material (docs/design.md §5, paper section 6).
//
// 1. The SH part: with the material known, every observation is linear in the lighting's
//    SH coefficients L_lm, through both terms of the shading model:
//      o = F(n.v) sum L_lm Y_lm(r)  +  21/(20 pi) Rd (1 - R0) g(n.v) sum Lambda_l h_l L_lm Y_lm(n)
//    (a pixel: the mean over its footprint). Linear least squares per channel, with a
//    ridge term (documented below) for views that leave it ill-posed.
// 2. The high-resolution part: subtract the predicted diffuse term from each observation,
//    divide by F(n.v), and splat the result into a lat-long map along the reflected
//    direction. Each texel weights its samples by their reliability: the captures' noise
//    amplified by 1/F, and the lighting's own variation within the texel, which every
//    sample shares (a random-effects mean, lighting_fit.cpp). Texels no sample reaches
//    take the SH reconstruction and are marked uncovered.
//
// Everything material-independent is gathered in one pass (LightingData): the normal
// equations for any (R0, Rd) are then assembled from moments in O(lmax^4), which the
// joint fit relies on.
#pragma once

#include "inverse/samples.h"
#include "renderer/environment.h"
#include "renderer/image.h"
#include "renderer/sh.h"

#include <Eigen/Dense>

#include <cstddef>
#include <vector>

namespace glaze {

// Per sample, per SH index i, the model row is ShadingCoefficients(R0, Rd).radiance({a_i,
// b_i, c_i}) (shading.h's affine form with L -> Y_i(r), gL -> g Y_i(r), gE -> g Lambda_l
// h_l Y_i(n)).
struct LightingData {
  int lmax = 0;
  int footprint = 1;  // rays per side of each pixel's model (footprint.h)
  // The observations' diffuse bands lmax+1 .. diffuse_lmax were taken off them
  // (DiffuseBandsAbove below); lmax when none were.
  int diffuse_lmax = 0;
  // Moments over samples of the row parts a, b, c (shared by the channels) ...
  Eigen::MatrixXd aa, ab, ac, bb, bc, cc;
  // ... and their products with the observations, one column per channel.
  Eigen::MatrixXd ao, bo, co;
  Eigen::Vector3d oo = Eigen::Vector3d::Zero();  // sum of the squared observations, per channel
  // The rows themselves (row-major, sh_count per sample), as the moments above were formed
  // from them: c is what the splat and the map-consistent solve need, a and b what the
  // observations' moments need again when the observations change
  // (take_off_diffuse_bands), which then need no ray traced.
  std::vector<float> a, b, c;
  // What the diffuse rows c were formed from: per model pixel of a sample (one for a pixel
  // sample, up to four for a point), its centre's normal and its share times its rays'
  // mean g(n.v); c = sum over them of share_g Lambda_l h_l Y(normal). Sample k's are
  // first_tap[k] .. first_tap[k + 1] - 1.
  std::vector<Vec3> tap_normal;
  std::vector<float> tap_share_g;
  std::vector<size_t> first_tap;
  // Per sample: the reflected direction through the pixel centre and n.v there.
  std::vector<Vec3> reflected;
  std::vector<float> mu;
  std::vector<RGB> observed;
  // Per sample and channel: the variance of the captured observation's noise
  // (noise_model.h), which take_off_diffuse_bands leaves as it is; for `noise_free`
  // captures (glaze's sh integrator is deterministic) the model's floor alone.
  std::vector<RGB> noise;
  bool noise_free = false;
  std::vector<int> frame;
  // Fraction of a 32 x 16 lat-long grid of normal directions that samples cover.
  double normal_coverage = 0.0;

  // Sample k's rows.
  Eigen::Map<const Eigen::VectorXf> a_row(size_t k) const { return row(a, k); }
  Eigen::Map<const Eigen::VectorXf> b_row(size_t k) const { return row(b, k); }
  Eigen::Map<const Eigen::VectorXf> c_row(size_t k) const { return row(c, k); }

 private:
  Eigen::Map<const Eigen::VectorXf> row(const std::vector<float>& rows, size_t k) const {
    const int n = sh_count(lmax);
    return {&rows[k * n], n};
  }
};

// The diffuse term's bands above a fit's lmax, predicted from a lighting estimate. A fit
// at lmax models the diffuse sum up to lmax only, which is exact for glaze's `sh`
// captures but not for photographs or the path tracer, whose diffuse term has every
// band: under small bright sources the bands above 4 carry about 5% of it (the kernel's
// h_l decay slowly, sh.h), as much as a diffuse object's whole mirror reflection.
struct DiffuseBandsAbove {
  ShCoefficients lighting;           // its bands lmax+1 .. lighting.lmax are used
  RGBd per_lighting = RGBd::Zero();  // 21/(20 pi) (1 - R0) Rd: radiance per unit of g E(n)
};

// The samples' model rows at lmax, each pixel modelled by footprint x footprint rays
// (footprint.h), their moments, and the observations' noise (estimate_noise; for
// `noise_free` captures its floor).
LightingData gather_lighting_data(const SampleSet& samples, const CaptureSet& captures, const RayTracer& tracer,
                                  int lmax, int footprint, bool noise_free);

// Replaces the observations of `data` (gathered from these samples) by the captured ones
// less the diffuse radiance of the bands `above`, so that what remains is what the fit's
// lmax models. Only what depends on the observations is formed again (observed, ao, bo,
// co, oo), from the stored rows and taps: no ray is traced.
void take_off_diffuse_bands(LightingData& data, const SampleSet& samples, const DiffuseBandsAbove& above);

// The bands up to diffuse_lmax of a recovered lighting map (SH-projected), under the
// material (R0, Rd). The prediction needs the map's detail more than its level: a joint
// fit's lighting too bright by s comes with an Rd too dark by about 1/s, and the bands'
// diffuse radiance is their product.
DiffuseBandsAbove predict_diffuse_bands(const Image& map, int diffuse_lmax, float R0, const RGB& Rd);

struct LightingFitOptions {
  // Ridge (Tikhonov) weight, relative to the mean diagonal of the normal equations. Tiny:
  // it leaves well-posed problems unchanged and keeps ill-posed ones (a single view, few
  // normals) finite, pulling unseen coefficients towards 0 instead of towards noise.
  double ridge = 1e-6;
  int width = 256, height = 128;  // of the high-resolution map
  // Of the map solved together with L_lm (0: the SH-only least squares alone).
  int solve_width = 64, solve_height = 32;
};

struct LightingFit {
  ShCoefficients coefficients;
  double condition = 0.0;  // of the least-squares system before the ridge (worst channel)
  double rms = 0.0;        // of the solved model's residuals (the solve map and L_lm) over samples and channels
  Image map;               // lat-long, world frame (docs/design.md §3)
  // Per texel: 1 if samples that see the mirror (F >= 0.01) reached it or lie within 3
  // degrees of its centre, 0 where it holds the SH reconstruction (lighting_fit.cpp).
  std::vector<float> covered;
  double covered_fraction = 0.0;
  double mirror_share = 0.0;                 // fraction of the observed light the mirror term carries
  RGBd channel_mirror_share = RGBd::Zero();  // the same per channel
  // Fraction of the solve map's covered texels that two or more views reflect into; the
  // map-consistent solve needs several views per direction to separate the mirror from
  // the diffuse term, and falls back to the SH-only least squares below one half.
  double multi_view_fraction = 0.0;
  bool map_consistent = false;  // which solve gave L_lm
};

// The lighting as a map, solved together with its SH coefficients (one channel).
//
// The SH-only least squares models the mirror term with lmax-4 lighting, but the mirror
// sees the full-resolution environment, and in the dark channels of a coloured object,
// where the mirror dominates, its unmodelled high frequencies leak into L_lm. Here the
// unknowns are instead, on the texels of a coarse lat-long map that reflected rays reach
// (several samples each: the map is coarser than the samples), the lighting's value T_t
// at the texel's centre and its gradient G_t across the texel, so that sample k sees
// T_t + G_t . delta_k, delta_k its offset from the centre in texels. The gradient
// matters to the joint fit: without it the lighting's variation within a texel, seen by
// each view at other offsets and other n.v, reads as a change of Fresnel factor and
// biases R0, Rd and the scale. Second-order terms do not help: six unknowns per texel
// leave too little to pin F (docs/notes/lighting-map.md, "Why the SH least squares is
// not enough"). Texels no ray reaches hold the SH reconstruction, and L_lm is the map's
// own projection (of the T_t), so it is consistent by construction:
//   L = sum_covered Omega_t Y(t) T_t + sum_uncovered Omega_t Y(t) Y(t)^T L
//     => L = G P T,  G = (I - P_u Y_u^T)^-1,  P = [Omega_t Y(t)] over covered texels.
// Sample k predicts o_k = F_k (T_t + G_t . delta_k) + d_k . L, d_k = 21/(20 pi) Rd (1 - R0)
// c_k, linear in the unknowns. The normal matrix is block diagonal (3 x 3 per texel: the
// mirror) plus rank 50 (the diffuse coupling), solved exactly by the Woodbury identity.
// Everything material-independent is summed per texel once, so a solve for another
// (R0, Rd) costs O(texels x 50^2), whatever the number of samples: the joint fit solves
// it at every step.
//
// The texels' edges fall where the lat-long grid puts them, and under sharp bright
// sources (a window's frame) where they cut the source changes what the value and
// gradient of a texel can represent: `turn` (0 <= turn < 1) turns the grid by that
// fraction of a texel in azimuth, so that the joint fit can average over where the edges
// fall (joint_fit.cpp, TurnedMapSystems).
class MapConsistentSystem {
 public:
  MapConsistentSystem(const LightingData& data, int width, int height, double ridge, double turn = 0.0);
  struct Solution {
    Eigen::VectorXd map;   // T on the covered texels (the value at each texel's centre)
    Eigen::VectorXd L;     // L_lm
    double squared_error;  // the regularised least-squares minimum, sum over samples
  };
  Solution solve(double R0, double Rd, int channel) const;

  // The minimum squared error alone, for one R0 and any Rd of each channel: what depends
  // on R0 is formed once here (O(texels x 50^2)); each Rd then costs O(50^3), whatever
  // the number of texels. (The joint fit evaluates thousands of materials.)
  class Profile {
   public:
    // Equals solve(R0, Rd, channel).squared_error.
    double squared_error(double Rd, int channel) const;

   private:
    friend class MapConsistentSystem;
    double diffuse_per_Rd = 0.0;     // 21/(20 pi) (1 - R0): s = diffuse_per_Rd Rd
    Eigen::MatrixXd EE, EQ, QQ, cc;  // E'^T B^-1 E', E'^T B^-1 Qx^T, Qx B^-1 Qx^T, sum c c^T
    Eigen::MatrixXd vE, vQ, co;      // per channel (columns): E'^T B^-1 b1, Qx B^-1 b1, sum c o
    Eigen::Vector3d bb, oo;          // b1^T B^-1 b1, sum o^2
  };
  Profile profile(double R0) const;

 private:
  // B (per texel 3 x 3, with the ridge) and E' = sum F phi c^T at this R0.
  std::vector<Eigen::Matrix3d> blocks(double q) const;
  int n_;
  double ridge_;
  // Per covered texel, phi = (1, delta): sums of phi phi^T, g phi phi^T, g^2 phi phi^T;
  // of phi o^T and g phi o^T (columns: channels); and, three rows per texel, of phi c^T
  // and g phi c^T.
  std::vector<Eigen::Matrix3d> phi_phi_, g_phi_phi_, gg_phi_phi_, phi_o_, g_phi_o_;
  Eigen::MatrixXd phi_c_, g_phi_c_;
  Eigen::MatrixXd cc_, co_;                       // sum c c^T, sum c o
  Eigen::Vector3d oo_ = Eigen::Vector3d::Zero();  // sum o^2
  Eigen::MatrixXd Q_;                             // G P
};

// Throws glaze::Error for map sizes over 4096x2048 or a ridge outside (0, 1].
void check_lighting_options(const LightingFitOptions& options);

// The fraction of the width x height solve map's texels that samples reach whose covered
// texels two or more views reflect into (LightingFit::multi_view_fraction); 0 for an
// empty map. It depends on the samples' geometry alone.
double multi_view_fraction(const LightingData& data, int width, int height);
// The least fraction at which fit_lighting takes the map-consistent solve.
inline constexpr double kMapConsistentFraction = 0.5;

// Throws glaze::Error with fewer samples than unknowns. `built`, when given, is the
// map-consistent system of (data, options.solve_width, options.solve_height,
// options.ridge) that the caller already has (the joint fit's), used instead of building
// it again.
LightingFit fit_lighting(const LightingData& data, float R0, const RGB& Rd, const LightingFitOptions& options,
                         const MapConsistentSystem* built = nullptr);

// For captures whose diffuse term has every band (photographs, the path tracer): a first
// fit, then a second on the observations less the bands lmax+1 .. diffuse_lmax that the
// first one's map predicts (above); `data`, gathered from `samples`, receives the
// second's observations. One correction, not an iteration: a third fit barely moves
// L_lm (docs/notes/lighting-map.md, "The second fit for full-band captures").
// diffuse_lmax <= data.lmax: fit_lighting alone.
LightingFit fit_lighting_full_band(LightingData& data, const SampleSet& samples, int diffuse_lmax, float R0,
                                   const RGB& Rd, const LightingFitOptions& options);

// Relative RMSE of the recovered map against a known environment, both box-filtered to
// width x height cells (solid-angle weighted), over the cells whose every map texel
// samples cover; `cells` receives how many were compared.
double map_error(const LightingFit& fit, const Environment& truth, int width, int height, int* cells = nullptr);

// The SH coefficients alone (step 1), for one channel's material; `condition` receives the
// system's condition number, `squared_error` the sum over samples of the squared residual.
Eigen::VectorXd solve_sh_lighting(const LightingData& data, float R0, float Rd, int channel, double ridge,
                                  double* condition, double* squared_error = nullptr);

}  // namespace glaze

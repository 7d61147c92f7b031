#include "inverse/lighting_fit.h"

#include "inverse/footprint.h"
#include "inverse/noise_model.h"
#include "renderer/error.h"
#include "renderer/latlong.h"
#include "renderer/material.h"
#include "renderer/shading.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

namespace glaze {
namespace {

// Samples are gathered in fixed chunks whose sums are added in order: the moments do not
// depend on the thread count.
constexpr size_t kSampleChunk = 2048;

// The moments of a set of rows: with the observations' alone, those of the rows among
// themselves (aa ... cc) are empty.
struct Moments {
  Eigen::MatrixXd aa, ab, ac, bb, bc, cc, ao, bo, co;
  Eigen::Vector3d oo = Eigen::Vector3d::Zero();
  Moments(int n, bool observations_only)
      : aa(Eigen::MatrixXd::Zero(observations_only ? 0 : n, observations_only ? 0 : n)),
        ab(aa),
        ac(aa),
        bb(aa),
        bc(aa),
        cc(aa),
        ao(Eigen::MatrixXd::Zero(n, 3)),
        bo(ao),
        co(ao) {}
  Moments& operator+=(const Moments& m) {
    aa += m.aa, ab += m.ab, ac += m.ac, bb += m.bb, bc += m.bc, cc += m.cc, ao += m.ao, bo += m.bo, co += m.co,
        oo += m.oo;
    return *this;
  }
};

// The moments of all samples, chunk by chunk: chunk(first, A, B, C, O) fills the chunk's
// rows as columns of A, B, C and its observations as rows of O (sized for it), and the
// moments are then matrix products, which Eigen vectorises: A, B and C are stacked, so
// that those among the rows are the lower half of one symmetric product (a rank update),
// with a quarter fewer multiplications than the six products apart. With
// `observations_only` those of the rows among themselves are not formed.
using ChunkRows = Eigen::Ref<Eigen::MatrixXd>;
template <typename Chunk>
Moments sum_moments(size_t count, int n, bool observations_only, Chunk&& chunk) {
  const size_t chunks = (count + kSampleChunk - 1) / kSampleChunk;
  std::vector<Moments> partial(chunks, Moments(n, observations_only));
  tbb::parallel_for(size_t(0), chunks, [&](size_t index) {
    const size_t first = index * kSampleChunk, rows = std::min(count, first + kSampleChunk) - first;
    Eigen::MatrixXd stacked = Eigen::MatrixXd::Zero(3 * n, Eigen::Index(rows)), O(rows, 3);
    chunk(first, stacked.topRows(n), stacked.middleRows(n, n), stacked.bottomRows(n), O);
    Moments& m = partial[index];
    const Eigen::MatrixXd with_observations = stacked * O;
    m.ao = with_observations.topRows(n), m.bo = with_observations.middleRows(n, n),
    m.co = with_observations.bottomRows(n);
    m.oo = O.colwise().squaredNorm().transpose();
    if (observations_only) return;
    Eigen::MatrixXd lower = Eigen::MatrixXd::Zero(3 * n, 3 * n);
    lower.selfadjointView<Eigen::Lower>().rankUpdate(stacked);
    // Its blocks: on the diagonal, symmetric from their lower halves; below it, B A^T, ...
    auto block = [&](int row, int column) { return lower.block(row * n, column * n, n, n); };
    m.aa = block(0, 0).template selfadjointView<Eigen::Lower>(),
    m.bb = block(1, 1).template selfadjointView<Eigen::Lower>();
    m.cc = block(2, 2).template selfadjointView<Eigen::Lower>();
    m.ab = block(1, 0).transpose(), m.ac = block(2, 0).transpose(), m.bc = block(2, 1).transpose();
  });
  Moments total(n, observations_only);
  for (const Moments& m : partial) total += m;
  return total;
}

void set_observations(LightingData& data, std::vector<RGB> observations, const Moments& moments) {
  data.observed = std::move(observations);
  data.ao = moments.ao, data.bo = moments.bo, data.co = moments.co, data.oo = moments.oo;
}

}  // namespace

LightingData gather_lighting_data(const SampleSet& samples, const CaptureSet& captures, const RayTracer& tracer,
                                  int lmax, int footprint, bool noise_free) {
  if (footprint < 1 || footprint > 16) throw Error("the pixel footprint must be 1 to 16 rays per side");
  LightingData data;
  data.lmax = lmax;
  data.footprint = footprint;
  data.diffuse_lmax = lmax;
  const int n = sh_count(lmax);
  const size_t count = samples.samples.size();
  std::vector<double> kernel(n);  // Lambda_l h_l, per SH index
  for (int l = 0; l <= lmax; ++l)
    for (int m = -l; m <= l; ++m) kernel[sh_index(l, m)] = sh_lambda(l) * sh_kernel_coefficient(l);
  for (auto* rows : {&data.a, &data.b, &data.c}) rows->assign(count * n, 0.0f);
  // The taps are formed per chunk, then joined in sample order.
  std::vector<std::vector<Vec3>> chunk_tap_normal((count + kSampleChunk - 1) / kSampleChunk);
  std::vector<std::vector<float>> chunk_tap_share_g(chunk_tap_normal.size());
  std::vector<size_t> taps_of(count);
  data.reflected.resize(count);
  data.mu.resize(count);
  data.frame.resize(count);
  std::vector<RGB> observations(count);
  const Moments moments =
      sum_moments(count, n, false, [&](size_t first, ChunkRows A, ChunkRows B, ChunkRows C, Eigen::MatrixXd& O) {
        std::vector<float> basis(n), g(size_t(footprint) * footprint);
        std::vector<double> sum_Y(n), sum_gY(n);
        std::vector<Vec3> reflected(g.size());
        std::vector<Vec3>& tap_normal = chunk_tap_normal[first / kSampleChunk];
        std::vector<float>& tap_share_g = chunk_tap_share_g[first / kSampleChunk];
        tap_normal.reserve(size_t(O.rows())), tap_share_g.reserve(size_t(O.rows()));  // one per pixel sample
        for (Eigen::Index r = 0; r < O.rows(); ++r) {
          const size_t k = first + size_t(r);
          for_each_model_pixel(samples, k, captures, tracer, footprint,
                               [&](const Vec3& centre_normal, const std::vector<FootprintRay>& rays, float weight) {
                                 // Per ray, its mirror direction and g(n.v); their basis sums over the rays.
                                 double sum_g = 0.0;
                                 for (size_t ray = 0; ray < rays.size(); ++ray) {
                                   g[ray] = float(coat_transmittance_g(rays[ray].normal.dot(rays[ray].view)));
                                   reflected[ray] = reflect(rays[ray].view, rays[ray].normal);
                                   sum_g += g[ray];
                                 }
                                 sh_sum(lmax, std::span(reflected).first(rays.size()), std::span(g).first(rays.size()),
                                        sum_Y, sum_gY);
                                 sh_eval<float>(lmax, centre_normal, basis);
                                 const double share = weight / rays.size(), share_g = share * sum_g;
                                 for (int i = 0; i < n; ++i) {
                                   A(i, r) += share * sum_Y[i];
                                   B(i, r) += share * sum_gY[i];
                                   C(i, r) += share_g * basis[i] * kernel[i];  // share g Lambda h Y(n)
                                 }
                                 tap_normal.push_back(centre_normal);
                                 tap_share_g.push_back(float(share_g));
                                 ++taps_of[k];
                               });
          // The rows are kept as floats, and the moments formed from the kept values, so
          // that moments formed again later (take_off_diffuse_bands) agree with these.
          for (int i = 0; i < n; ++i) {
            data.a[k * n + i] = float(A(i, r)), data.b[k * n + i] = float(B(i, r)), data.c[k * n + i] = float(C(i, r));
            A(i, r) = data.a[k * n + i], B(i, r) = data.b[k * n + i], C(i, r) = data.c[k * n + i];
          }
          const Sample& s = samples.samples[k];
          O.row(r) = s.observed.cast<double>().matrix().transpose();
          observations[k] = s.observed;
          data.reflected[k] = reflect(s.view, s.normal);
          data.mu[k] = s.mu;
          data.frame[k] = s.frame;
        }
      });
  data.first_tap.assign(count + 1, 0);
  for (size_t k = 0; k < count; ++k) data.first_tap[k + 1] = data.first_tap[k] + taps_of[k];
  for (size_t chunk = 0; chunk < chunk_tap_normal.size(); ++chunk) {
    data.tap_normal.insert(data.tap_normal.end(), chunk_tap_normal[chunk].begin(), chunk_tap_normal[chunk].end());
    data.tap_share_g.insert(data.tap_share_g.end(), chunk_tap_share_g[chunk].begin(), chunk_tap_share_g[chunk].end());
  }
  set_observations(data, std::move(observations), moments);
  data.noise_free = noise_free;
  data.noise = estimate_noise(data.observed, samples, noise_free);
  data.aa = moments.aa, data.ab = moments.ab, data.ac = moments.ac;
  data.bb = moments.bb, data.bc = moments.bc, data.cc = moments.cc;

  std::vector<uint8_t> seen(32 * 16, 0);
  for (const Sample& s : samples.samples) {
    const Vec2 uv = direction_to_latlong(s.normal);
    seen[texel_of(uv, 32, 16)] = 1;
  }
  // Cells weighted by their solid angle (sin theta), so that the poles do not count double.
  double covered = 0.0, total_area = 0.0;
  for (int j = 0; j < 16; ++j)
    for (int i = 0; i < 32; ++i) {
      const double area = std::sin(kPiD * (j + 0.5) / 16);
      total_area += area;
      if (seen[j * 32 + i]) covered += area;
    }
  data.normal_coverage = covered / total_area;
  return data;
}

void take_off_diffuse_bands(LightingData& data, const SampleSet& samples, const DiffuseBandsAbove& above) {
  const int n = sh_count(data.lmax);
  const size_t count = samples.samples.size();
  if (data.observed.size() != count || data.a.size() != count * n || data.b.size() != count * n ||
      data.c.size() != count * n || data.first_tap.size() != count + 1 ||
      data.tap_normal.size() != data.first_tap.back() || data.tap_share_g.size() != data.first_tap.back())
    throw Error("internal: the diffuse bands are taken off data gathered from other samples (" +
                std::to_string(data.observed.size()) + " against " + std::to_string(count) + ")");
  // E(n) of the bands above lmax alone.
  std::optional<ShDiffuseSum> above_sum;
  if (above.lighting.lmax > data.lmax) {
    ShCoefficients bands = above.lighting;
    std::fill(bands.values.begin(), bands.values.begin() + n, RGBd::Zero());
    above_sum.emplace(bands);
  }
  // The observations are replaced last, with their moments, so that `data` stays whole
  // when an exception leaves.
  std::vector<RGB> observations(count);
  const Moments moments =
      sum_moments(count, n, true, [&](size_t first, ChunkRows A, ChunkRows B, ChunkRows C, Eigen::MatrixXd& O) {
        // E_above at the chunk's taps, all at once (SIMD lanes of normals).
        const size_t first_tap = data.first_tap[first], taps = data.first_tap[first + size_t(O.rows())] - first_tap;
        std::vector<RGB> E_tap(above_sum ? taps : 0);
        if (above_sum) (*above_sum)(std::span(data.tap_normal).subspan(first_tap, taps), E_tap);
        for (Eigen::Index r = 0; r < O.rows(); ++r) {
          const size_t k = first + size_t(r);
          A.col(r) = data.a_row(k).cast<double>(), B.col(r) = data.b_row(k).cast<double>(),
          C.col(r) = data.c_row(k).cast<double>();
          // sum share_g E_above(normal) over the taps: the bands' share of the diffuse rows.
          RGBd E_above = RGBd::Zero();
          for (size_t tap = data.first_tap[k]; above_sum && tap < data.first_tap[k + 1]; ++tap)
            E_above += double(data.tap_share_g[tap]) * E_tap[tap - first_tap].cast<double>();
          const RGB observed =
              (samples.samples[k].observed.cast<double>() - above.per_lighting * E_above).cast<float>();
          O.row(r) = observed.cast<double>().matrix().transpose();
          observations[k] = observed;
        }
      });
  set_observations(data, std::move(observations), moments);
  data.diffuse_lmax = above_sum ? above.lighting.lmax : data.lmax;
}

Eigen::VectorXd solve_sh_lighting(const LightingData& data, float R0, float Rd, int channel, double ridge,
                                  double* condition, double* squared_error) {
  // Row = a - q b + s c (shading.h's affine form).
  const ShadingCoefficients<double> shading(R0, Rd);
  const double q = shading.transmittance, s = shading.diffuse;
  const Eigen::MatrixXd normal = data.aa - q * (data.ab + data.ab.transpose()) + s * (data.ac + data.ac.transpose()) +
                                 q * q * data.bb - q * s * (data.bc + data.bc.transpose()) + s * s * data.cc;
  const Eigen::VectorXd rhs = data.ao.col(channel) - q * data.bo.col(channel) + s * data.co.col(channel);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(normal);
  const double largest = eigen.eigenvalues().maxCoeff(), smallest = std::max(eigen.eigenvalues().minCoeff(), 0.0);
  if (condition) *condition = smallest > 0.0 ? std::sqrt(largest / smallest) : INFINITY;
  const double lambda = ridge * normal.diagonal().mean();
  const Eigen::MatrixXd regularised = normal + lambda * Eigen::MatrixXd::Identity(normal.rows(), normal.cols());
  const Eigen::VectorXd L = regularised.ldlt().solve(rhs);
  // sum (o - row.L)^2 = sum o^2 - 2 L.rhs + L^T N L, from the moments.
  if (squared_error) *squared_error = std::max(0.0, data.oo[channel] - 2.0 * L.dot(rhs) + L.dot(normal * L));
  return L;
}

MapConsistentSystem::MapConsistentSystem(const LightingData& data, int width, int height, double ridge, double turn)
    : n_(sh_count(data.lmax)), ridge_(ridge) {
  // Texel and in-texel offset (in texels, each in [-1/2, 1/2)) of a reflected direction,
  // on the grid turned by `turn` texels in azimuth. The azimuth is wrapped in texels and
  // in double, where a direction just short of the turned grid's seam stays in its last
  // column (in float, u - turn / width + 1 can round onto 1).
  auto locate = [&](const Vec3& direction, Eigen::Vector3d& phi) {
    const Vec2 uv = direction_to_latlong(direction);
    double x = double(uv.x()) * width - turn;
    if (x < 0.0) x += width;
    const int column = std::min(int(x), width - 1);
    const int t = texel_of(uv, width, height) / width * width + column;
    phi = Eigen::Vector3d(1.0, x - (column + 0.5), uv.y() * height - (t / width + 0.5));
    return t;
  };
  const size_t count = data.observed.size();
  std::vector<int> texel(count);
  std::vector<Eigen::Vector3d> offset(count);
  tbb::parallel_for(size_t(0), count, [&](size_t k) { texel[k] = locate(data.reflected[k], offset[k]); });
  // The covered texels in the order samples first reach them, and each one's samples in
  // sample order (a counting sort): the texels are then summed in parallel, each by one
  // thread in a fixed order, so that the sums do not depend on the thread count.
  std::vector<int> index(size_t(width) * height, -1);
  std::vector<int> covered;
  for (int t : texel)
    if (index[t] < 0) index[t] = int(covered.size()), covered.push_back(t);
  const int m = int(covered.size());
  std::vector<size_t> start(size_t(m) + 1, 0), members(count);
  for (int t : texel) ++start[size_t(index[t]) + 1];
  for (int i = 0; i < m; ++i) start[i + 1] += start[i];
  {
    std::vector<size_t> next(start.begin(), start.end() - 1);
    for (size_t k = 0; k < count; ++k) members[next[size_t(index[texel[k]])]++] = k;
  }
  for (auto* sums : {&phi_phi_, &g_phi_phi_, &gg_phi_phi_}) sums->assign(size_t(m), Eigen::Matrix3d::Zero());
  for (auto* sums : {&phi_o_, &g_phi_o_}) sums->assign(size_t(m), Eigen::Matrix3d::Zero());
  phi_c_ = Eigen::MatrixXd::Zero(3 * m, n_), g_phi_c_ = phi_c_;
  tbb::parallel_for(0, m, [&](int i) {
    // The texel's samples as rows: phi, g phi, c and o; its sums are matrix products.
    const Eigen::Index rows = Eigen::Index(start[i + 1] - start[i]);
    Eigen::MatrixX3d phi(rows, 3), g_phi(rows, 3), o(rows, 3);
    Eigen::MatrixXd c(rows, n_);
    for (Eigen::Index r = 0; r < rows; ++r) {
      const size_t k = members[start[i] + size_t(r)];
      const double g = coat_transmittance_g(double(data.mu[k]));
      phi.row(r) = offset[k].transpose();
      g_phi.row(r) = g * offset[k].transpose();
      o.row(r) = data.observed[k].cast<double>().matrix().transpose();
      c.row(r) = data.c_row(k).transpose().cast<double>();
    }
    phi_phi_[i].noalias() = phi.transpose() * phi;
    g_phi_phi_[i].noalias() = phi.transpose() * g_phi;
    gg_phi_phi_[i].noalias() = g_phi.transpose() * g_phi;
    phi_o_[i].noalias() = phi.transpose() * o;
    g_phi_o_[i].noalias() = g_phi.transpose() * o;
    phi_c_.middleRows<3>(3 * i).noalias() = phi.transpose() * c;
    g_phi_c_.middleRows<3>(3 * i).noalias() = g_phi.transpose() * c;
  });
  cc_ = data.cc, co_ = data.co, oo_ = data.oo;
  // Projection weights of the texels (solid angle times the basis at the centre; the
  // gradient integrates to zero over a texel), and Q = G P with G = (I - P_u Y_u^T)^-1
  // for the uncovered texels.
  Eigen::MatrixXd P(n_, m), uncovered = Eigen::MatrixXd::Zero(n_, n_);
  std::vector<float> basis(n_);
  for (int t = 0; t < width * height; ++t) {
    const int j = t / width;
    const double solid_angle = latlong_texel_solid_angle(j, width, height);
    sh_eval<float>(data.lmax, latlong_to_direction(Vec2(float((t % width + 0.5 + turn) / width), (j + 0.5f) / height)),
                   basis);
    const Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXf>(basis.data(), n_).cast<double>();
    if (index[t] >= 0)
      P.col(index[t]) = solid_angle * y;
    else
      uncovered += solid_angle * y * y.transpose();
  }
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n_, n_);
  Q_ = (I - uncovered + ridge * I).ldlt().solve(P);
}

std::vector<Eigen::Matrix3d> MapConsistentSystem::blocks(double q) const {
  const size_t m = phi_phi_.size();
  std::vector<Eigen::Matrix3d> B(m);
  double trace = 0.0;
  for (size_t t = 0; t < m; ++t) {
    B[t] = phi_phi_[t] - 2.0 * q * g_phi_phi_[t] + q * q * gg_phi_phi_[t];
    trace += B[t](0, 0);
  }
  // A texel's gradient is undetermined by fewer than three samples off a line: the ridge
  // keeps every block invertible and such a gradient at 0.
  const double ridge = ridge_ * std::max(trace / double(std::max<size_t>(m, 1)), 1e-30);
  for (Eigen::Matrix3d& block : B) block += ridge * Eigen::Matrix3d::Identity();
  return B;
}

MapConsistentSystem::Profile MapConsistentSystem::profile(double R0) const {
  const ShadingCoefficients<double> per_unit_Rd(R0);
  const double q = per_unit_Rd.transmittance;
  const int m = int(phi_phi_.size()), n = n_;
  const std::vector<Eigen::Matrix3d> B = blocks(q);
  const Eigen::MatrixXd E = phi_c_ - q * g_phi_c_;  // E' (3m x n): E = s E'
  Eigen::MatrixXd B_inverse_E(3 * m, n), b1(3 * m, 3), B_inverse_b1(3 * m, 3);
  Eigen::VectorXd value_weight(m);                          // (B_t^-1)_00
  Eigen::MatrixXd value_rows_E(m, n), value_rows_b1(m, 3);  // the value rows of B^-1 E', B^-1 b1
  for (int t = 0; t < m; ++t) {
    const Eigen::Matrix3d inverse = B[t].inverse();
    B_inverse_E.middleRows<3>(3 * t) = inverse * E.middleRows<3>(3 * t);
    b1.middleRows<3>(3 * t) = phi_o_[t] - q * g_phi_o_[t];
    B_inverse_b1.middleRows<3>(3 * t) = inverse * b1.middleRows<3>(3 * t);
    value_weight[t] = inverse(0, 0);
    value_rows_E.row(t) = B_inverse_E.row(3 * t);
    value_rows_b1.row(t) = B_inverse_b1.row(3 * t);
  }
  Profile p;
  p.diffuse_per_Rd = per_unit_Rd.diffuse;
  p.EE = E.transpose() * B_inverse_E;
  p.EQ = value_rows_E.transpose() * Q_.transpose();
  p.QQ = Q_ * value_weight.asDiagonal() * Q_.transpose();
  p.cc = cc_;
  p.vE = B_inverse_E.transpose() * b1;
  p.vQ = Q_ * value_rows_b1;
  p.co = co_;
  for (int c = 0; c < 3; ++c) p.bb[c] = b1.col(c).dot(B_inverse_b1.col(c));
  p.oo = oo_;
  return p;
}

double MapConsistentSystem::Profile::squared_error(double Rd, int channel) const {
  // With s = diffuse_per_Rd Rd, U = [s E', Qx^T], rhs = b1 + s Qx^T co:
  //   rhs.x = rhs^T B^-1 rhs - w^T K^-1 w,  w = U^T B^-1 rhs,  K = C^-1 + U^T B^-1 U,
  // every term a product of the R0-only matrices above with powers of s.
  const double s = diffuse_per_Rd * Rd;
  const int n = int(cc.rows());
  const Eigen::VectorXd co_c = co.col(channel);
  Eigen::VectorXd w(2 * n);
  w.head(n) = s * (vE.col(channel) + s * EQ * co_c);
  w.tail(n) = vQ.col(channel) + s * QQ * co_c;
  Eigen::MatrixXd K(2 * n, 2 * n);
  K.topLeftCorner(n, n) = s * s * (EE - cc);
  K.topRightCorner(n, n) = s * EQ + Eigen::MatrixXd::Identity(n, n);
  K.bottomLeftCorner(n, n) = K.topRightCorner(n, n).transpose();
  K.bottomRightCorner(n, n) = QQ;
  const double rhs_B_rhs = bb[channel] + 2.0 * s * vQ.col(channel).dot(co_c) + s * s * co_c.dot(QQ * co_c);
  return std::max(0.0, oo[channel] - (rhs_B_rhs - w.dot(K.partialPivLu().solve(w))));
}

MapConsistentSystem::Solution MapConsistentSystem::solve(double R0, double Rd, int channel) const {
  // Unknowns: per covered texel its value and its gradient (x = [T, Gu, Gv] per texel);
  // L = Q T. With F_k = 1 - q g_k, the per-texel blocks come from the gathered sums.
  const ShadingCoefficients<double> shading(R0, Rd);
  const double q = shading.transmittance, diffuse_scale = shading.diffuse;
  const int m = int(phi_phi_.size()), n = n_;
  // sum d d^T and sum o d are the gathered moments of c, scaled.
  const Eigen::MatrixXd M = diffuse_scale * diffuse_scale * cc_;
  const Eigen::VectorXd b2 = diffuse_scale * co_.col(channel);
  // N = B + U C U^T with B block diagonal (sum F^2 phi phi^T per texel), U = [E, Qx^T]
  // (E: sum F phi d^T per texel; Qx: Q on the value unknowns, 0 on the gradients),
  // C = [[0, I], [I, M]], C^-1 = [[-M, I], [I, 0]]: solved by the Woodbury identity.
  const std::vector<Eigen::Matrix3d> B = blocks(q);
  Eigen::MatrixXd U(3 * m, 2 * n);
  U.leftCols(n) = diffuse_scale * (phi_c_ - q * g_phi_c_);
  U.rightCols(n).setZero();
  Eigen::VectorXd rhs(3 * m);
  for (int t = 0; t < m; ++t) {
    U.block(3 * t, n, 1, n) = Q_.col(t).transpose();
    rhs.segment<3>(3 * t) = phi_o_[t].col(channel) - q * g_phi_o_[t].col(channel);
    rhs[3 * t] += Q_.col(t).dot(b2);
  }
  Eigen::MatrixXd B_inverse_U(3 * m, 2 * n);
  Eigen::VectorXd B_inverse_rhs(3 * m);
  for (int t = 0; t < m; ++t) {
    const Eigen::LDLT<Eigen::Matrix3d> block(B[t]);
    B_inverse_U.middleRows<3>(3 * t) = block.solve(U.middleRows<3>(3 * t));
    B_inverse_rhs.segment<3>(3 * t) = block.solve(rhs.segment<3>(3 * t));
  }
  Eigen::MatrixXd inner = U.transpose() * B_inverse_U;
  inner.topLeftCorner(n, n) -= M;
  inner.topRightCorner(n, n) += Eigen::MatrixXd::Identity(n, n);
  inner.bottomLeftCorner(n, n) += Eigen::MatrixXd::Identity(n, n);
  const Eigen::VectorXd x = B_inverse_rhs - B_inverse_U * inner.fullPivLu().solve(U.transpose() * B_inverse_rhs);
  Solution solution;
  solution.map.resize(m);
  for (int t = 0; t < m; ++t) solution.map[t] = x[3 * t];
  solution.L = Q_ * solution.map;
  // The minimum of the regularised least squares, sum (o - prediction)^2 + ridge |x|^2,
  // which at the solution of its normal equations is sum o^2 - rhs.x. (The ridge term is
  // part of the objective the joint fit minimises on purpose: dropping it measurably
  // worsens the joint estimates.)
  solution.squared_error = std::max(0.0, oo_[channel] - rhs.dot(x));
  return solution;
}

namespace {

// A sample estimates the lighting only where its F is at least 0.01: below that the
// mirror carries under 1% of what it saw, and (o - diffuse) / F is the diffuse model's
// residual amplified a hundredfold or more (a matte coat, R0 near 0, seen near the
// normal), not the lighting. The floor is per sample, not per texel: the splat's weights
// tend to equal ones where the lighting varies within a texel (splat_samples), so that
// one sample at F = 1e-6 beside one at F = 0.5 would put its residual times 1e6 into the
// texel's mean (a sphere of R0 = 0 gave L00 -726 for a true 8.6 that way, through the
// bands the first fit's map predicts for the second).
constexpr double kMinMirrorFresnel = 0.01;
// Lat-long texels shrink towards the poles (by sin theta) while the samples' density on
// the sphere of directions does not, so there many texels fall between samples although
// the directions all around them are seen: the SH reconstruction in those, as for
// directions no view sees, would speckle the poles with lmax-4 ringing of the bright
// lights nearby, which errs in the map's bands and, through the diffuse bands it predicts,
// in the joint fit's Rd (docs/notes/lighting-map.md, "Texels between samples"). Such a
// texel takes the samples within kBetweenSamples of its centre instead, in the smallest
// disc (doubled from a texel's height) that holds enough; only directions with no sample
// that near are unseen.
constexpr double kBetweenSamples = 3.0 * kPiD / 180.0;

// The splat's texels: each one's estimate (splat_samples) times its mirror weight (its
// samples' sum of F^2), and that weight, kept as prefix sums along each row, so that the
// sum over any run of a row's texels costs two lookups whatever the map's resolution.
// Texels pooled in a disc (estimate_near) are weighted by their mirror weight, as the
// samples were before splat_samples; the sums stay within the samples' F^2 (at most 1
// each) times the lighting, whereas the noise weights span the square of the range of
// the pixels' levels. Filled in two steps: each texel's own values (set), then the rows'
// prefix sums (sum_rows), in place.
class SplatRows {
 public:
  SplatRows(int width, int height)
      : width_(width),
        height_(height),
        sum_(size_t(width + 1) * height, RGBd::Zero()),
        mirror_weight_(sum_.size(), 0.0) {}

  // Texel t's estimate and mirror weight (t = j width + i; each texel once, before sum_rows).
  void set(size_t t, const RGBd& estimate, double mirror_weight) {
    const size_t slot = t + t / width_ + 1;  // row j holds width + 1 prefix sums
    sum_[slot] = mirror_weight * estimate, mirror_weight_[slot] = mirror_weight;
  }

  void sum_rows() {
    tbb::parallel_for(0, height_, [&](int j) {
      const size_t row = size_t(j) * (width_ + 1);
      for (int i = 0; i < width_; ++i) {
        sum_[row + i + 1] += sum_[row + i];
        mirror_weight_[row + i + 1] += mirror_weight_[row + i];
      }
    });
  }

  // The discs around row j's texels that estimate_near tries: radius 1, 2, 4, ... texel
  // heights, up to kBetweenSamples (at least one); per disc, its rows and in each the
  // texels on either side of the centre's column that it holds. The same for every
  // texel of the row.
  struct Run {
    int row, columns;
  };
  std::vector<std::vector<Run>> discs(int j) const {
    const double row_angle = kPiD / height_, column_angle = 2.0 * kPiD / width_;
    const int reach = std::max(1, int(kBetweenSamples / row_angle + 1e-9));
    const double theta = (j + 0.5) * row_angle;
    std::vector<std::vector<Run>> all;
    for (int rows = 1;; rows = std::min(2 * rows, reach)) {
      const double radius = rows * row_angle;
      std::vector<Run>& disc = all.emplace_back();
      for (int y = std::max(0, j - rows); y <= std::min(height_ - 1, j + rows); ++y) {
        // Texel centres within `radius`: cos(d) = cos(theta - theta') - sin(theta)
        // sin(theta') (1 - cos(dphi)) >= cos(radius) bounds the longitude difference dphi.
        const double other = (y + 0.5) * row_angle;
        const double room =
            std::max(0.0, (std::cos(theta - other) - std::cos(radius)) / (std::sin(theta) * std::sin(other)));
        disc.push_back({y, room >= 2.0 ? width_ : int(std::acos(1.0 - room) / column_angle + 1e-9)});
      }
      if (rows == reach) return all;
    }
  }

  // Texel (i, j)'s mirror estimate: its own, else the mean of those in the smallest of
  // `discs` (discs(j)) that holds a sample; none when no disc does.
  std::optional<RGBd> estimate_near(int i, int j, const std::vector<std::vector<Run>>& discs) const {
    RGBd s = RGBd::Zero();
    double w = 0.0;
    add_run(j, i, 1, s, w);
    if (w > 0.0) return RGBd(s / w);
    for (const std::vector<Run>& disc : discs) {
      s = RGBd::Zero(), w = 0.0;
      for (const Run& run : disc) add_run(run.row, i - run.columns, std::min(2 * run.columns + 1, width_), s, w);
      if (w > 0.0) return RGBd(s / w);
    }
    return std::nullopt;
  }

 private:
  // Adds the sums over `count` (<= width) texels of row y from column `first` on,
  // wrapping around.
  void add_run(int y, int first, int count, RGBd& s, double& w) const {
    first = ((first % width_) + width_) % width_;
    const size_t row = size_t(y) * (width_ + 1);
    const int end = first + count;
    auto add = [&](int from, int to) {
      s += sum_[row + to] - sum_[row + from];
      w += mirror_weight_[row + to] - mirror_weight_[row + from];
    };
    if (end <= width_) {
      add(first, end);
    } else {
      add(first, width_);
      add(0, end - width_);
    }
  }

  int width_, height_;
  std::vector<RGBd> sum_;              // per row, width + 1 prefix sums
  std::vector<double> mirror_weight_;  // the same for the mirror weights
};

// The splat: sample k estimates the lighting along its mirror direction r_k by
//   x_k = (o_k - diffuse_k) / F_k,   whose noise has variance v_k = noise / F_k^2
// (the division amplifies the captures' noise by 1/F). A texel's value is the mean of the
// lighting over the texel, but x_k is the lighting at one direction in it (at most over
// the pixel's footprint, smaller than the texel): the lighting's variation within the
// texel, of variance tau^2, is a second error of every sample alike, whatever its F. The
// best linear unbiased mean of the texel's samples weights them by 1 / (v_k + tau^2) (a
// random-effects model): by F^2 where the lighting is smooth across the texel, equally
// where its detail outweighs the noise. tau^2 is estimated per texel and channel from
// its own samples by the method of moments (DerSimonian and Laird, 1986):
//   tau^2 = max(0, (Q - (n - 1)) / (S1 - S2 / S1)),   Q = sum (x_k - m)^2 / v_k,
// m the samples' mean weighted by 1 / v_k, S1 and S2 the sums of 1 / v_k and 1 / v_k^2.
// Why it matters: by F^2 alone, a grazing view (F up to 1, against R0 ~ 0.04 head-on)
// decides every texel it reaches, although there its samples are the sparsest (the
// mirror's directions spread fastest near the silhouette), so that a texel's share of a
// source smaller than their spacing would be decided by a few samples, hit or missed
// (docs/notes/lighting-map.md, "The reliability-weighted map").
//
// `noise` is the mean over the texel's samples of the captures' noise model, not each
// sample's own: the model's floor follows the pixel's level (noise_model.h), which in a
// channel that only the mirror lights is the lighting itself, so that a sample's own
// would weigh a small source's samples down against the dark ones around it
// (docs/notes/lighting-map.md, "The reliability-weighted map").
// tau^2 takes whatever the noise model leaves out: on point samples, which have no pixel
// grid to estimate the noise on (noise_model.h), the captures' noise, so that their
// weights tend to equal ones; and the diffuse model's error divided by F, which pulls the
// weights towards equal ones where F is small, as in a one-fit map of full-band captures
// (lighting_fit.h: the second fit takes the bands off).
SplatRows splat_samples(const LightingData& data, float R0, const std::vector<RGBd>& mirror,
                        const std::vector<size_t>& texel_of_sample, int width, int height) {
  const size_t count = mirror.size(), texels = size_t(width) * height;
  // The samples by texel, in sample order within each (a counting sort): each texel's
  // sums are then formed from its own samples, in parallel over texels and whatever the
  // thread count the same, with per-texel storage only for the sort and the results.
  std::vector<uint32_t> first(texels + 1, 0);
  for (size_t k = 0; k < count; ++k) ++first[texel_of_sample[k] + 1];
  for (size_t t = 0; t < texels; ++t) first[t + 1] += first[t];
  std::vector<uint32_t> order(count);
  {
    std::vector<uint32_t> next(first.begin(), first.end() - 1);
    for (size_t k = 0; k < count; ++k) order[next[texel_of_sample[k]]++] = uint32_t(k);
  }
  SplatRows splat(width, height);
  tbb::parallel_for(size_t(0), texels, [&](size_t t) {
    // The texel's samples that see enough of the mirror (kMinMirrorFresnel), with their F.
    thread_local std::vector<std::pair<uint32_t, double>> seen;
    seen.clear();
    RGBd noise = RGBd::Zero();
    for (uint32_t i = first[t]; i < first[t + 1]; ++i) {
      const uint32_t k = order[i];
      const double F = schlick_fresnel(double(R0), double(data.mu[k]));
      if (!(F >= kMinMirrorFresnel)) continue;
      seen.emplace_back(k, F);
      noise += data.noise[k].cast<double>();
    }
    if (seen.empty()) return;
    const double n = double(seen.size());
    noise = (noise / n).max(std::numeric_limits<double>::min());
    // The sums of the weights 1 / v_k and of their squares, and their weighted mean.
    RGBd S1 = RGBd::Zero(), S2 = RGBd::Zero(), mean = RGBd::Zero();
    for (const auto& [k, F] : seen) {
      const RGBd w = F * F / noise;
      S1 += w, S2 += w.square(), mean += w * mirror[k] / F;
    }
    mean /= S1;
    RGBd tau2 = RGBd::Zero();
    if (seen.size() >= 2) {
      RGBd Q = RGBd::Zero();
      for (const auto& [k, F] : seen) Q += (mirror[k] / F - mean).square() * (F * F / noise);
      const RGBd denominator = S1 - S2 / S1;
      for (int c = 0; c < 3; ++c)
        if (denominator[c] > 0.0) tau2[c] = std::max(0.0, (Q[c] - (n - 1.0)) / denominator[c]);
    }
    RGBd sum = RGBd::Zero(), weight = RGBd::Zero();
    double mirror_weight = 0.0;
    for (const auto& [k, F] : seen) {
      const RGBd w = (noise / (F * F) + tau2).inverse();
      sum += w * mirror[k] / F, weight += w, mirror_weight += F * F;
    }
    // Left unset (to the discs or the SH reconstruction) where the noise overflows.
    if (const RGBd estimate = sum / weight; estimate.allFinite()) splat.set(t, estimate, mirror_weight);
  });
  splat.sum_rows();
  return splat;
}

}  // namespace

void check_lighting_options(const LightingFitOptions& options) {
  if (options.width < 1 || options.height < 1 || options.width > 4096 || options.height > 2048 ||
      options.solve_width > 4096 || options.solve_height > 2048)
    throw Error("lighting maps are at most 4096x2048");
  if (!(options.ridge > 0.0 && options.ridge <= 1.0)) throw Error("the ridge weight must be in (0, 1]");
}

double multi_view_fraction(const LightingData& data, int width, int height) {
  if (width <= 0 || height <= 0) return 0.0;
  // Which views reflect into each texel of the map.
  std::vector<int> first_view(size_t(width) * height, -1);
  std::vector<uint8_t> several(first_view.size(), 0);
  for (size_t k = 0; k < data.reflected.size(); ++k) {
    const Vec2 uv = direction_to_latlong(data.reflected[k]);
    const size_t t = texel_of(uv, width, height);
    if (first_view[t] < 0)
      first_view[t] = data.frame[k];
    else if (first_view[t] != data.frame[k])
      several[t] = 1;
  }
  const double covered = double(std::count_if(first_view.begin(), first_view.end(), [](int v) { return v >= 0; }));
  return covered > 0 ? std::count(several.begin(), several.end(), 1) / covered : 0.0;
}

LightingFit fit_lighting(const LightingData& data, float R0, const RGB& Rd, const LightingFitOptions& options,
                         const MapConsistentSystem* built) {
  const int n = sh_count(data.lmax);
  const size_t count = data.observed.size();
  if (data.noise.size() != count) throw Error("lighting recovery needs the captures' noise model (estimate_noise)");
  if (count < size_t(n))
    throw Error("lighting recovery needs at least " + std::to_string(n) + " samples for lmax " +
                std::to_string(data.lmax) + ", got " + std::to_string(count));
  check_lighting_options(options);
  LightingFit fit;
  fit.coefficients = ShCoefficients(data.lmax);
  Eigen::MatrixXd L(n, 3);
  fit.multi_view_fraction = multi_view_fraction(data, options.solve_width, options.solve_height);
  fit.map_consistent = fit.multi_view_fraction >= kMapConsistentFraction;
  std::optional<MapConsistentSystem> own;
  if (fit.map_consistent && !built) own.emplace(data, options.solve_width, options.solve_height, options.ridge);
  const MapConsistentSystem* system = fit.map_consistent ? (built ? built : &*own) : nullptr;
  std::array<double, 3> condition{}, squared{};
  tbb::parallel_for(0, 3, [&](int c) {  // the channels are independent
    L.col(c) = solve_sh_lighting(data, R0, Rd[c], c, options.ridge, &condition[c], &squared[c]);
    if (system) {
      const MapConsistentSystem::Solution solution = system->solve(R0, Rd[c], c);
      L.col(c) = solution.L, squared[c] = solution.squared_error;
    }
  });
  fit.condition = *std::max_element(condition.begin(), condition.end());
  fit.rms = std::sqrt((squared[0] + squared[1] + squared[2]) / (3.0 * double(count)));
  for (int i = 0; i < n; ++i) fit.coefficients.values[i] = RGBd(L(i, 0), L(i, 1), L(i, 2));

  // The high-resolution part: (o - diffuse) / F splatted along r (splat_samples).
  const int width = options.width, height = options.height;
  RGBd mirror_light = RGBd::Zero(), all_light = RGBd::Zero();
  double mirror_total = 0.0;
  // Each sample's mirror part and texel in parallel, then their sums in sample order, so
  // that the map does not depend on the thread count.
  std::vector<RGBd> mirror(count);
  std::vector<size_t> texel_of_sample(count);
  const Eigen::Vector3d diffuse_per_L = ShadingCoefficients<double>(R0).diffuse * Rd.cast<double>().matrix();
  tbb::parallel_for(size_t(0), count, [&](size_t k) {
    const Eigen::Vector3d diffuse = diffuse_per_L.cwiseProduct(L.transpose() * data.c_row(k).cast<double>());
    mirror[k] = data.observed[k].cast<double>() - diffuse.array();
    texel_of_sample[k] = texel_of(direction_to_latlong(data.reflected[k]), width, height);
  });
  for (size_t k = 0; k < count; ++k) {
    mirror_light += mirror[k].max(0.0);
    mirror_total += std::max(0.0, mirror[k].sum());
    all_light += data.observed[k].cast<double>();
  }
  fit.mirror_share = all_light.sum() > 0.0 ? mirror_total / all_light.sum() : 0.0;
  for (int c = 0; c < 3; ++c) fit.channel_mirror_share[c] = all_light[c] > 0.0 ? mirror_light[c] / all_light[c] : 0.0;
  fit.map = Image(width, height);
  fit.covered.assign(size_t(width) * height, 0.0f);
  const SplatRows splat = splat_samples(data, R0, mirror, texel_of_sample, width, height);
  tbb::parallel_for(0, height, [&](int j) {  // each texel writes only its own value
    const auto discs = splat.discs(j);
    for (int i = 0; i < width; ++i) {
      const size_t texel = size_t(j) * width + i;
      if (const std::optional<RGBd> seen = splat.estimate_near(i, j, discs)) {
        fit.map.set(i, j, seen->cast<float>().max(0.0));
        fit.covered[texel] = 1.0f;
      } else {
        const Vec3 direction = latlong_to_direction(Vec2((i + 0.5f) / width, (j + 0.5f) / height));
        fit.map.set(i, j, fit.coefficients.eval(direction).max(0.0f));
      }
    }
  });
  fit.covered_fraction = std::count(fit.covered.begin(), fit.covered.end(), 1.0f) / (double(width) * height);
  return fit;
}

double map_error(const LightingFit& fit, const Environment& truth, int width, int height, int* cells) {
  const Image& map = fit.map;
  if (map.width % width != 0 || map.height % height != 0)
    throw Error("the recovered map (" + std::to_string(map.width) + "x" + std::to_string(map.height) +
                ") is not a multiple of the comparison grid " + std::to_string(width) + "x" + std::to_string(height));
  const int sx = map.width / width, sy = map.height / height;
  constexpr int kTruthSamples = 16;  // per side of a cell: the truth box-filtered finely
  double squared = 0.0, reference = 0.0;
  int compared = 0;
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      RGBd recovered = RGBd::Zero();
      double area = 0.0;
      bool all_covered = true;
      for (int y = j * sy; y < (j + 1) * sy; ++y)
        for (int x = i * sx; x < (i + 1) * sx; ++x) {
          const double sin_theta = std::sin(kPiD * (y + 0.5) / map.height);
          all_covered = all_covered && fit.covered[size_t(y) * map.width + x] > 0.0f;
          recovered += sin_theta * map.at(x, y).cast<double>();
          area += sin_theta;
        }
      if (!all_covered) continue;
      recovered /= area;
      // Solid-angle weighted mean of the true lighting over the cell.
      RGBd expected = RGBd::Zero();
      double total = 0.0;
      for (int b = 0; b < kTruthSamples; ++b)
        for (int a = 0; a < kTruthSamples; ++a) {
          const Vec2 uv((i + (a + 0.5f) / kTruthSamples) / width, (j + (b + 0.5f) / kTruthSamples) / height);
          float sin_theta = 0.0f;
          const Vec3 direction = latlong_to_direction(uv, &sin_theta);
          expected += sin_theta * truth.eval(direction).cast<double>();
          total += sin_theta;
        }
      expected /= total;
      squared += (recovered - expected).square().sum();
      reference += expected.square().sum();
      ++compared;
    }
  if (cells) *cells = compared;
  return reference > 0.0 ? std::sqrt(squared / reference) : 0.0;
}

DiffuseBandsAbove predict_diffuse_bands(const Image& map, int diffuse_lmax, float R0, const RGB& Rd) {
  const Environment recovered(map, EnvironmentOptions{}, "the recovered lighting");
  return {recovered.sh(diffuse_lmax), ShadingCoefficients<double>(R0).diffuse * Rd.cast<double>()};
}

LightingFit fit_lighting_full_band(LightingData& data, const SampleSet& samples, int diffuse_lmax, float R0,
                                   const RGB& Rd, const LightingFitOptions& options) {
  if (diffuse_lmax <= data.lmax) return fit_lighting(data, R0, Rd, options);
  // The first fit's map only predicts the bands: the SH-only least squares under it does
  // as well there as the map-consistent solve, at a fraction of the cost: the second fit
  // ends at the same L_lm either way (docs/notes/lighting-map.md, "The second fit for
  // full-band captures").
  LightingFitOptions first_options = options;
  first_options.solve_width = 0;
  const LightingFit first = fit_lighting(data, R0, Rd, first_options);
  const DiffuseBandsAbove above = predict_diffuse_bands(first.map, diffuse_lmax, R0, Rd);
  take_off_diffuse_bands(data, samples, above);
  return fit_lighting(data, R0, Rd, options);
}

}  // namespace glaze

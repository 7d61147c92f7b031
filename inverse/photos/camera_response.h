// camera_response.h: the camera response of 8-bit photographs, recovered from exposure
// brackets, and the weights that keep saturated and underexposed codes out of the merge.
//
// An 8-bit JPEG or PNG stores f(exposure), where f is the camera's unknown, monotone
// tone curve. Debevec and Malik (1997) recover g = ln f^-1 from pixels seen at several
// known exposures: least squares over g(Z_ij) = ln E_i + ln t_j with a hat weight and a
// smoothness term on g'', here over all brackets of a shoot at once (each with its own
// exposure times: OpenCV's CalibrateDebevec takes one bracket), on sample pixels, then
// refined by regressing the codes on the samples' exposures (Debevec and Malik's
// regression, of g on the noisy codes, is biased where g is steep), and with the ripple
// that a bracket in constant steps leaves free settled by the curve's smoothness alone.
// On the synthetic brackets of the tests it is several times as accurate as OpenCV's
// CalibrateDebevec and CalibrateRobertson, and a plain Robertson et al. (2003) iteration
// did not settle (docs/notes/hdr-merge.md). 16-bit and raw photos are linear: their
// response is the identity.
#pragma once

#include "inverse/photos/bracket.h"

#include <nlohmann/json.hpp>

#include <array>
#include <span>
#include <string>
#include <vector>

namespace glaze {

// Codes at or below `low` are underexposed, at or above `high` saturated (the top 2% of
// the range: JPEG ringing spreads a clipped 255 a few codes down).
struct CodeLimits {
  int low = 0, high = 0, max = 0;
  bool saturated(const uint16_t* rgb) const { return rgb[0] >= high || rgb[1] >= high || rgb[2] >= high; }
};
CodeLimits code_limits(int bits);

// The hat weight of a code: 0 at and beyond `low` and `high`, 1 midway between them.
std::vector<float> hat_weights(const CodeLimits& limits);

enum class ResponseMethod { kDebevec, kLinear };
std::string method_name(ResponseMethod method);

struct CameraResponse {
  ResponseMethod method = ResponseMethod::kLinear;
  int bits = 8;
  // Per channel and code: ln of the exposure that gives the code, relative to the
  // middle code's (g(2^(bits-1)) = 0). Empty for a linear response.
  std::array<std::vector<double>, 3> log_exposure;
  // Per channel: the codes seen in enough samples to fix the curve there.
  std::array<std::array<int, 2>, 3> well_constrained{};
  size_t samples = 0;  // sample pixels the recovery used

  // Per channel, code -> linear exposure: exp(g) for a recovered response, code / max for
  // a linear one.
  std::array<std::vector<float>, 3> linear_table() const;
};

// Codes of a bracket at sample pixels, all that the recovery needs of it.
struct ResponseSamples {
  std::vector<double> exposures;  // one per exposure
  std::vector<uint16_t> codes;    // samples x exposures x 3
};
// Every pixel of a photo of at most max_samples pixels, else about max_samples spread
// evenly over the scene's range of exposure.
ResponseSamples sample_bracket(const BracketPhotos& photos, int max_samples = 16384);

// Recovers the response of 8-bit photos jointly from all brackets' samples. Throws
// glaze::Error when the brackets do not constrain it (fewer than two distinct exposures).
CameraResponse recover_response(std::span<const ResponseSamples> brackets);

// The identity response of linear photos with `bits` per code.
CameraResponse linear_response(int bits);

// The response as JSON (docs/guide.md: `glaze hdr-merge`), and read back from such a file.
nlohmann::json response_json(const CameraResponse& response);
CameraResponse read_response(const std::string& path);

}  // namespace glaze

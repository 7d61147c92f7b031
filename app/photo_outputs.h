// photo_outputs.h: what the photograph commands (hdr-merge, captures) write of a merge:
// the response curve (response.json and a plot) and each bracket's HDR image, with the
// same names and report entries in both.
#pragma once

#include "inverse/photos/bracket.h"
#include "inverse/photos/camera_response.h"
#include "inverse/photos/hdr_merge.h"
#include "renderer/output_folder.h"

#include <nlohmann/json.hpp>

#include <string>

namespace glaze {

// "12.345%"
std::string percent_text(double fraction);

// Writes response.json and response.png into `out` (nothing for a linear response) and
// names the file in report["response_file"].
void write_response(OutputFolder& out, const CameraResponse& response, nlohmann::json& report);

// Writes NAME.exr (R, G, B and A: 0 where saturated in every exposure) for `bracket`,
// says so on stderr, and returns its report entry: name, folder, image, exposures (file,
// exposure, shift), saturated and underexposed fractions.
nlohmann::json write_merged(OutputFolder& out, const Bracket& bracket, const MergedBracket& merged,
                            const CameraResponse& response);

}  // namespace glaze

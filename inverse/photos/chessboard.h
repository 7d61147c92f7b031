// chessboard.h: the inner corners of a chessboard in a photograph (docs/design.md §7),
// found by OpenCV's calib3d and refined to a fraction of a pixel.
//
// The photograph may be HDR or 8-bit: its luminance is scaled so that the 99th
// percentile is white and encoded as sRGB, a tone curve that keeps the board's edges
// sharp whatever the exposure (the corners, the saddle points of the pattern, do not
// move under a tone curve).
//
// The corners come in the board's own order, the same whatever side the photograph was
// taken from: corner (i, j) at index j * cols + i, i along a row of `cols` corners and j
// along a column of `rows`, seen from the front with i growing to the right and j
// upwards, and with the corner square diagonally outside corner (0, 0) black. A board
// with one count even and the other odd has exactly one such corner, and that fixes the
// world frame of registration.h.
#pragma once

#include "inverse/photos/shoot.h"
#include "renderer/image.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace glaze {

// The corners of `board` in `photo` (linear RGB), in glaze's film coordinates (pixel
// (i, j) has its centre at (i + 0.5, j + 0.5)). Throws glaze::Error naming `file` when
// the board is not found, saying what to check.
std::vector<Eigen::Vector2d> find_board_corners(const Image& photo, const BoardSpec& board, const std::string& file);

}  // namespace glaze

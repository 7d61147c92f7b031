// chessboard.cpp: chessboard corners through OpenCV, in the board's own order.
#include "inverse/photos/chessboard.h"

#include "renderer/error.h"
#include "renderer/memory_budget.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace glaze {

namespace {

// The photograph's luminance, scaled so that its 99th percentile is 1, clamped and
// sRGB-encoded to [0, 255] (float: cornerSubPix refines on it without 8-bit steps).
cv::Mat grey_for_detection(const Image& photo, const std::string& file) {
  const size_t count = size_t(photo.width) * size_t(photo.height);
  require_memory(count * (2 * sizeof(float) + 1), "finding the chessboard in " + file);
  std::vector<float> luminance(count);
  for (size_t k = 0; k < count; ++k) {
    const float* p = &photo.pixels[3 * k];
    const float y = 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2];
    luminance[k] = std::isfinite(y) ? std::max(y, 0.0f) : 0.0f;
  }
  std::vector<float> sorted = luminance;
  const auto percentile = sorted.begin() + std::ptrdiff_t(0.99 * double(count - 1));
  std::nth_element(sorted.begin(), percentile, sorted.end());
  const float white = *percentile;
  if (!(white > 0.0f))
    throw Error(file +
                ": the photo is black (its 99th percentile is 0): no chessboard can be found in it; "
                "check the exposure");
  cv::Mat grey(photo.height, photo.width, CV_32F);
  for (int y = 0; y < photo.height; ++y) {
    float* row = grey.ptr<float>(y);
    for (int x = 0; x < photo.width; ++x) {
      const float v = std::min(luminance[size_t(y) * photo.width + x] / white, 1.0f);
      row[x] = 255.0f * (v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f);
    }
  }
  return grey;
}

// The grey level at the centre of the square between corners (i, j) and (i + 1, j + 1).
float square_grey(const cv::Mat& grey, const std::vector<cv::Point2f>& corners, int cols, int i, int j) {
  const cv::Point2f centre = 0.25f * (corners[j * cols + i] + corners[j * cols + i + 1] + corners[(j + 1) * cols + i] +
                                      corners[(j + 1) * cols + i + 1]);
  const int x = std::clamp(int(std::lround(centre.x)), 0, grey.cols - 1);
  const int y = std::clamp(int(std::lround(centre.y)), 0, grey.rows - 1);
  return grey.at<float>(y, x);
}

// Reorders OpenCV's corners (row by row, starting at either end) into the board's order
// (chessboard.h): first so that, in the image (y down), rows run upwards when columns run
// to the right, which is the board seen from its front; then turned by 180 degrees
// unless the squares on the diagonal of corner (0, 0) are the dark ones.
std::vector<cv::Point2f> board_order(const std::vector<cv::Point2f>& found, const cv::Mat& grey,
                                     const BoardSpec& board) {
  const int cols = board.cols, rows = board.rows;
  const auto at = [&](const std::vector<cv::Point2f>& c, int i, int j) { return c[j * cols + i]; };
  const cv::Point2f along_row = at(found, cols - 1, 0) - at(found, 0, 0);
  const cv::Point2f along_column = at(found, 0, rows - 1) - at(found, 0, 0);
  const bool mirrored = along_row.x * along_column.y - along_row.y * along_column.x > 0.0f;
  std::vector<cv::Point2f> corners(found.size());
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < cols; ++i) corners[j * cols + i] = at(found, i, mirrored ? rows - 1 - j : j);
  // The squares of corner (0, 0)'s colour are those (i, j) with i + j even.
  double even = 0.0, odd = 0.0;
  for (int j = 0; j + 1 < rows; ++j)
    for (int i = 0; i + 1 < cols; ++i) ((i + j) % 2 ? odd : even) += square_grey(grey, corners, cols, i, j);
  if (even > odd) std::reverse(corners.begin(), corners.end());
  return corners;
}

// The half-width of cornerSubPix's window: half way to the closest neighbouring corner.
// The larger the window, the more edge pixels average the noise out; beyond half way it
// would take in the next corner.
int half_window(const std::vector<cv::Point2f>& corners, const BoardSpec& board) {
  float spacing = INFINITY;
  for (int j = 0; j < board.rows; ++j)
    for (int i = 0; i < board.cols; ++i) {
      const cv::Point2f p = corners[j * board.cols + i];
      if (i + 1 < board.cols) spacing = std::min(spacing, float(cv::norm(corners[j * board.cols + i + 1] - p)));
      if (j + 1 < board.rows) spacing = std::min(spacing, float(cv::norm(corners[(j + 1) * board.cols + i] - p)));
    }
  return std::clamp(int(spacing / 2.0f), 2, 20);
}

}  // namespace

std::vector<Eigen::Vector2d> find_board_corners(const Image& photo, const BoardSpec& board, const std::string& file) {
  const cv::Mat grey = grey_for_detection(photo, file);
  cv::Mat grey8;
  grey.convertTo(grey8, CV_8U);  // rounds and saturates
  const cv::Size pattern(board.cols, board.rows);
  std::vector<cv::Point2f> found;
  // findChessboardCorners with cornerSubPix: on glaze's renders of a board it places the
  // corners about 20% closer to the truth than findChessboardCornersSB with its accuracy
  // flag (docs/notes/registration.md).
  const bool ok =
      cv::findChessboardCorners(grey8, pattern, found, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
  if (!ok || found.size() != size_t(board.cols) * board.rows)
    throw Error(file + ": the chessboard of " + std::to_string(board.cols) + " x " + std::to_string(board.rows) +
                " inner corners was not found; check that shoot.json's board.inner_corners counts the corners where "
                "four squares meet (not the squares), that the whole board is in the picture with a white margin "
                "around it, and that it is in focus and neither over- nor underexposed");
  const int half = half_window(found, board);
  cv::cornerSubPix(grey, found, cv::Size(half, half), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 100, 1e-4));
  const std::vector<cv::Point2f> ordered = board_order(found, grey, board);
  std::vector<Eigen::Vector2d> corners;
  corners.reserve(ordered.size());
  // OpenCV puts pixel centres at integers, glaze at i + 0.5.
  for (const cv::Point2f& p : ordered) corners.emplace_back(double(p.x) + 0.5, double(p.y) + 0.5);
  return corners;
}

}  // namespace glaze

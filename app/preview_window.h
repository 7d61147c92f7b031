// preview_window.h: a GLFW window (OpenGL 3.3 core) that shows an 8-bit sRGB picture,
// scaled to fit and centred (pixel for pixel when the window has the picture's size),
// and hands mouse and key input to its owner. Used by `glaze preview` and by
// `glaze invert-fit --preview`; only built with GLAZE_PREVIEW.
//
// The picture is one texture drawn by one full-window triangle; its bytes are the
// display transform's (display.h), so the window shows exactly what a saved PNG holds.
#pragma once

#include <cstdint>
#include <exception>
#include <functional>
#include <span>
#include <string>
#include <vector>

struct GLFWwindow;

namespace glaze {

// Throws glaze::Error naming DISPLAY when no window can be opened here: DISPLAY unset,
// or its X server not reachable (checked before long work starts, to fail at once).
// `instead` names what to run without a window, for the message.
void require_display(const std::string& instead);

class PreviewWindow {
 public:
  // Opens a window of width x height (shrunk to fit the screen). Throws glaze::Error
  // naming DISPLAY when there is no display to open it on.
  PreviewWindow(const std::string& title, int width, int height);
  ~PreviewWindow();
  PreviewWindow(const PreviewWindow&) = delete;
  PreviewWindow& operator=(const PreviewWindow&) = delete;

  bool should_close() const;
  void close();
  void set_title(const std::string& title);
  // Picture pixels per screen unit of mouse motion, for a width x height picture drawn
  // as draw() draws it (1:1 unless shrunk to fit; HiDPI framebuffers accounted for).
  double picture_pixels_per_screen_unit(int width, int height) const;

  // Draws the picture (row-major RGB, row 0 at the top) into the back buffer.
  void draw(int width, int height, std::span<const uint8_t> rgb);
  // What the back buffer holds now (the drawn frame, before present()): RGB rows from
  // the top, and its size.
  std::vector<uint8_t> read_back(int& width, int& height) const;
  void present();
  // Handles pending input, waiting for some at most `timeout` seconds. An exception
  // thrown by a handler is rethrown here (never through GLFW's C code).
  void wait_events(double timeout);

  // Input, called from wait_events(). Drag: the cursor moved by (dx, dy) window pixels
  // with `button` held (0 left, 1 right, 2 middle); GLFW's modifier bits in `mods`.
  std::function<void(int key, int mods)> on_key;
  std::function<void(double dx, double dy, int button, int mods)> on_drag;
  std::function<void(double steps)> on_scroll;

 private:
  template <typename Handler>
  void guarded(Handler&& handler);

  GLFWwindow* window_ = nullptr;
  unsigned texture_ = 0, program_ = 0, vertex_array_ = 0;
  int texture_width_ = 0, texture_height_ = 0;
  double cursor_x_ = 0, cursor_y_ = 0;
  std::exception_ptr handler_failure_;
};

}  // namespace glaze

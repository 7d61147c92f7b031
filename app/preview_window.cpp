#include "app/preview_window.h"

#include "renderer/error.h"

#define GL_GLEXT_PROTOTYPES
#define GLFW_INCLUDE_GLCOREARB
#include <GLFW/glfw3.h>

#include <algorithm>
#include <cstdlib>
#include <utility>

namespace glaze {
namespace {

std::string last_glfw_error() {
  const char* description = nullptr;
  glfwGetError(&description);
  return description ? description : "no reason given";
}

GLuint compile(GLenum type, const char* source) {
  const GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[1024] = {};
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    throw Error(std::string("preview: the OpenGL driver rejected a shader: ") + log);
  }
  return shader;
}

// A triangle that covers the window; the fragment shader maps window pixels to picture
// texels itself (letterboxed, centred), so that at scale 1 each texel is one pixel.
constexpr const char* kVertexShader = R"(#version 330 core
void main() {
  vec2 corner = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
})";

constexpr const char* kFragmentShader = R"(#version 330 core
uniform sampler2D picture;
uniform vec2 window_size;
uniform vec2 picture_size;
out vec4 colour;
void main() {
  float scale = min(1.0, min(window_size.x / picture_size.x, window_size.y / picture_size.y));
  vec2 shown = picture_size * scale;
  vec2 origin = floor((window_size - shown) * 0.5);
  // Window y grows upwards; picture row 0 is the top.
  vec2 p = vec2(gl_FragCoord.x, window_size.y - gl_FragCoord.y) - origin;
  if (any(lessThan(p, vec2(0.0))) || any(greaterThanEqual(p, shown))) {
    colour = vec4(0.12, 0.12, 0.12, 1.0);
    return;
  }
  colour = vec4(texture(picture, p / shown).rgb, 1.0);
})";

PreviewWindow& owner(GLFWwindow* window) { return *static_cast<PreviewWindow*>(glfwGetWindowUserPointer(window)); }

// Shrinks width x height, keeping the aspect, to the primary monitor's work area.
void fit_to_screen(int& width, int& height) {
  if (GLFWmonitor* monitor = glfwGetPrimaryMonitor()) {
    int x, y, w, h;
    glfwGetMonitorWorkarea(monitor, &x, &y, &w, &h);
    if (w > 0 && h > 0) {
      const double shrink = std::min({1.0, double(w) / width, double(h) / height});
      width = std::max(1, int(width * shrink)), height = std::max(1, int(height * shrink));
    }
  }
}

}  // namespace

// Runs an input handler; what it throws is kept for wait_events() to rethrow.
template <typename Handler>
void PreviewWindow::guarded(Handler&& handler) {
  if (handler_failure_) return;
  try {
    handler();
  } catch (...) {
    handler_failure_ = std::current_exception();
  }
}

namespace {}  // namespace

namespace {

// glfwInit, or a glaze::Error that names DISPLAY.
void initialise_glfw(const std::string& instead) {
  const char* display = std::getenv("DISPLAY");
  if (!display || !*display)
    throw Error(
        "cannot open a window: DISPLAY is not set (no X display). Run it on a desktop, over ssh -X, or "
        "headless under xvfb-run; without a window: " +
        instead);
  if (!glfwInit())
    throw Error("cannot open a window on DISPLAY=" + std::string(display) + ": " + last_glfw_error() +
                " (is the X server running and reachable? headless: xvfb-run)");
}

}  // namespace

void require_display(const std::string& instead) {
  initialise_glfw(instead);  // connects to the X server
  glfwTerminate();
}

PreviewWindow::PreviewWindow(const std::string& title, int width, int height) {
  initialise_glfw("glaze render");
  // From here on the constructor may still throw: release GLFW then.
  struct TerminateOnThrow {
    PreviewWindow& self;
    bool armed = true;
    ~TerminateOnThrow() {
      if (!armed) return;
      if (self.window_) glfwDestroyWindow(self.window_);
      glfwTerminate();
    }
  } guard{*this};
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_SCALE_TO_MONITOR, GLFW_FALSE);
  fit_to_screen(width, height);
  window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!window_) {
    const std::string reason = last_glfw_error();
    throw Error("cannot open an OpenGL 3.3 core window: " + reason +
                " (the preview needs OpenGL 3.3; Mesa's llvmpipe has it)");
  }
  glfwMakeContextCurrent(window_);
  glfwSwapInterval(1);
  glfwSetWindowUserPointer(window_, this);
  glfwGetCursorPos(window_, &cursor_x_, &cursor_y_);

  glfwSetKeyCallback(window_, [](GLFWwindow* w, int key, int, int action, int mods) {
    PreviewWindow& self = owner(w);
    if (action != GLFW_RELEASE && self.on_key) self.guarded([&] { self.on_key(key, mods); });
  });
  glfwSetCursorPosCallback(window_, [](GLFWwindow* w, double x, double y) {
    PreviewWindow& self = owner(w);
    const double dx = x - self.cursor_x_, dy = y - self.cursor_y_;
    self.cursor_x_ = x, self.cursor_y_ = y;
    for (int button : {GLFW_MOUSE_BUTTON_LEFT, GLFW_MOUSE_BUTTON_RIGHT, GLFW_MOUSE_BUTTON_MIDDLE}) {
      if (glfwGetMouseButton(w, button) == GLFW_PRESS && self.on_drag) {
        int mods = 0;
        if (glfwGetKey(w, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS || glfwGetKey(w, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS)
          mods |= GLFW_MOD_SHIFT;
        if (glfwGetKey(w, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS || glfwGetKey(w, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS)
          mods |= GLFW_MOD_CONTROL;
        self.guarded([&] { self.on_drag(dx, dy, button, mods); });
        break;
      }
    }
  });
  glfwSetScrollCallback(window_, [](GLFWwindow* w, double, double y) {
    PreviewWindow& self = owner(w);
    if (self.on_scroll) self.guarded([&] { self.on_scroll(y); });
  });

  const GLuint vertex = compile(GL_VERTEX_SHADER, kVertexShader),
               fragment = compile(GL_FRAGMENT_SHADER, kFragmentShader);
  program_ = glCreateProgram();
  glAttachShader(program_, vertex);
  glAttachShader(program_, fragment);
  glLinkProgram(program_);
  glDeleteShader(vertex);
  glDeleteShader(fragment);
  GLint linked = 0;
  glGetProgramiv(program_, GL_LINK_STATUS, &linked);
  if (!linked) throw Error("preview: the OpenGL driver could not link the display shader");
  glGenVertexArrays(1, &vertex_array_);
  glGenTextures(1, &texture_);
  glBindTexture(GL_TEXTURE_2D, texture_);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  guard.armed = false;
}

PreviewWindow::~PreviewWindow() {
  if (!window_) return;
  glDeleteTextures(1, &texture_);
  glDeleteVertexArrays(1, &vertex_array_);
  glDeleteProgram(program_);
  glfwDestroyWindow(window_);
  glfwTerminate();
}

bool PreviewWindow::should_close() const { return glfwWindowShouldClose(window_); }
double PreviewWindow::picture_pixels_per_screen_unit(int width, int height) const {
  int window_width, window_height, framebuffer_width, framebuffer_height;
  glfwGetWindowSize(window_, &window_width, &window_height);
  glfwGetFramebufferSize(window_, &framebuffer_width, &framebuffer_height);
  // The shader's scale: framebuffer pixels per picture pixel, at most 1.
  const double scale = std::min({1.0, double(framebuffer_width) / width, double(framebuffer_height) / height});
  const double framebuffer_per_screen = double(framebuffer_width) / std::max(window_width, 1);
  return framebuffer_per_screen / std::max(scale, 1e-6);
}

void PreviewWindow::close() { glfwSetWindowShouldClose(window_, GLFW_TRUE); }
void PreviewWindow::set_title(const std::string& title) { glfwSetWindowTitle(window_, title.c_str()); }

void PreviewWindow::draw(int width, int height, std::span<const uint8_t> rgb) {
  if (rgb.size() != size_t(width) * height * 3) throw Error("preview: picture size mismatch");
  glBindTexture(GL_TEXTURE_2D, texture_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  if (width != texture_width_ || height != texture_height_) {
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, width, height, 0, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
    texture_width_ = width, texture_height_ = height;
  } else {
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
  }
  int window_width, window_height;
  glfwGetFramebufferSize(window_, &window_width, &window_height);
  // Nearest texels at 1:1 (exact), linear when shrunk to fit.
  const bool exact = window_width >= width && window_height >= height;
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, exact ? GL_NEAREST : GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glViewport(0, 0, window_width, window_height);
  glUseProgram(program_);
  glUniform1i(glGetUniformLocation(program_, "picture"), 0);
  glUniform2f(glGetUniformLocation(program_, "window_size"), float(window_width), float(window_height));
  glUniform2f(glGetUniformLocation(program_, "picture_size"), float(width), float(height));
  glActiveTexture(GL_TEXTURE0);
  glBindVertexArray(vertex_array_);
  glDrawArrays(GL_TRIANGLES, 0, 3);
}

std::vector<uint8_t> PreviewWindow::read_back(int& width, int& height) const {
  glfwGetFramebufferSize(window_, &width, &height);
  std::vector<uint8_t> rows(size_t(width) * height * 3);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, rows.data());
  // OpenGL's rows run bottom-up.
  std::vector<uint8_t> top_down(rows.size());
  const size_t stride = size_t(width) * 3;
  for (int y = 0; y < height; ++y)
    std::copy_n(&rows[size_t(height - 1 - y) * stride], stride, &top_down[size_t(y) * stride]);
  return top_down;
}

void PreviewWindow::present() { glfwSwapBuffers(window_); }

void PreviewWindow::wait_events(double timeout) {
  if (timeout > 0)
    glfwWaitEventsTimeout(timeout);
  else
    glfwPollEvents();
  if (handler_failure_) std::rethrow_exception(std::exchange(handler_failure_, nullptr));
}

}  // namespace glaze

#include "ui/gui/screenshot.hpp"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <stb_image_write.h>

#include <algorithm>
#include <stdexcept>

namespace piezo::gui {

Image read_framebuffer(int w, int h) {
  std::vector<unsigned char> px(static_cast<std::size_t>(w) * h * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
  // OpenGL's origin is bottom-left; images go top-down.
  Image img{w, h, std::vector<unsigned char>(px.size())};
  const std::size_t row = static_cast<std::size_t>(w) * 4;
  for (int y = 0; y < h; ++y)
    std::copy_n(&px[static_cast<std::size_t>(h - 1 - y) * row], row,
                &img.rgba[static_cast<std::size_t>(y) * row]);
  return img;
}

void write_png(const Image& img, const std::string& path) {
  if (!stbi_write_png(path.c_str(), img.width, img.height, 4, img.rgba.data(), img.width * 4))
    throw std::runtime_error("screenshot: cannot write " + path);
}

}  // namespace piezo::gui

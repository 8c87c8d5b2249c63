#pragma once
// Reads the current OpenGL framebuffer back and writes it as a PNG. Reading
// must happen on the thread that owns the GL context, right after rendering;
// encoding and writing may run elsewhere (the PNG export does it on the task
// thread, since compressing a full window takes longer than a frame).
#include <string>
#include <vector>

namespace piezo::gui {

struct Image {
  int width = 0, height = 0;
  std::vector<unsigned char> rgba;  // rows top-down
};

Image read_framebuffer(int width, int height);

// Throws std::runtime_error naming the file on failure.
void write_png(const Image& img, const std::string& path);

inline void save_framebuffer_png(const std::string& path, int width, int height) {
  write_png(read_framebuffer(width, height), path);
}

}  // namespace piezo::gui

#pragma once
// Reads the current OpenGL framebuffer back and writes it as a PNG.
#include <string>

namespace piezo::gui {
// Throws std::runtime_error naming the file on failure.
void save_framebuffer_png(const std::string& path, int width, int height);
}  // namespace piezo::gui

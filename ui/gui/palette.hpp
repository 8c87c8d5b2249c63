#pragma once
// Plot colours, shared by the windows and by the GUI test's pixel checks
// (tests/gui): a colour changed here is changed in both. Curves are opaque;
// region shading is translucent over the plot background, so the test
// composites it the way OpenGL does (blend_over).
#include <imgui.h>

#include <string_view>

namespace piezo::gui {

inline constexpr ImU32 kColPlotBg = IM_COL32(20, 22, 28, 255);
inline constexpr ImU32 kColMeasured = IM_COL32(255, 200, 40, 255);  // amber
inline constexpr ImU32 kColOriginal = IM_COL32(80, 160, 255, 255);  // blue
inline constexpr ImU32 kColUpdated = IM_COL32(60, 220, 120, 255);   // green
inline constexpr ImU32 kColFft = IM_COL32(200, 120, 255, 255);      // violet
inline constexpr ImU32 kColXspec = IM_COL32(255, 110, 110, 255);    // red

// Diagnosis residual ln(Z_meas/Z_model): the base refit, the model with the
// added effects, and the ±2σ noise of the measurement.
inline constexpr ImU32 kColResidual = IM_COL32(0, 230, 230, 255);        // cyan
inline constexpr ImU32 kColResidualAfter = IM_COL32(255, 90, 200, 255);  // pink
inline constexpr ImU32 kColNoiseBand = IM_COL32(150, 150, 150, 255);     // grey

// Regions of the misfit, shaded by their dominant kind (update/gap_regions.hpp).
// Regions whose misfit is at the noise get a faint neutral shade so that the
// region boundaries stay visible.
inline constexpr ImU32 kColRegionShift = IM_COL32(255, 150, 0, 110);   // orange
inline constexpr ImU32 kColRegionWidth = IM_COL32(255, 60, 60, 110);   // red
inline constexpr ImU32 kColRegionLevel = IM_COL32(60, 120, 255, 110);  // blue
inline constexpr ImU32 kColRegionResonance = IM_COL32(240, 220, 0, 110);  // yellow: an extra resonance (issue 21)
inline constexpr ImU32 kColRegionPhase = IM_COL32(200, 80, 255, 110);  // violet
inline constexpr ImU32 kColRegionNoise = IM_COL32(255, 255, 255, 14);  // neutral

// The shade of a region by its dominant kind (GapRegion::kind).
inline ImU32 region_colour(std::string_view kind) {
  if (kind == "frequency shift") return kColRegionShift;
  if (kind == "peak width/height") return kColRegionWidth;
  if (kind == "level") return kColRegionLevel;
  if (kind == "phase" || kind == "phase slope") return kColRegionPhase;
  if (kind == "extra resonance") return kColRegionResonance;
  return kColRegionNoise;
}

struct Rgb {
  int r, g, b;
};

constexpr Rgb rgb_of(ImU32 c) {
  return {static_cast<int>((c >> IM_COL32_R_SHIFT) & 0xff),
          static_cast<int>((c >> IM_COL32_G_SHIFT) & 0xff),
          static_cast<int>((c >> IM_COL32_B_SHIFT) & 0xff)};
}

// `top` (translucent) drawn over the opaque `bottom`, as GL_SRC_ALPHA /
// GL_ONE_MINUS_SRC_ALPHA blending does.
constexpr Rgb blend_over(ImU32 top, ImU32 bottom) {
  const int a = static_cast<int>((top >> IM_COL32_A_SHIFT) & 0xff);
  const Rgb t = rgb_of(top), b = rgb_of(bottom);
  return {b.r + (t.r - b.r) * a / 255, b.g + (t.g - b.g) * a / 255, b.b + (t.b - b.b) * a / 255};
}

}  // namespace piezo::gui

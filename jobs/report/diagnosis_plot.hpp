#pragma once
// The gap diagnosis as a PNG (`piezobench diagnose --plot`): the top panel
// shows |Z| measured against the model before (base refit: material +
// damping) and after (with the effects the diagnosis added) on log axes; the
// panels below it the residual ln(Z_meas/Z_model) before and after — its
// magnitude in dB, then its phase in degrees (where a lead resistance or a
// channel skew shows) — each over the ±1σ band of the measurement's own
// noise. The misfit regions of the diagnosis (capacitive band, resonances,
// anti-resonances, bands between, tail) are shaded alternately in every panel
// and named; the title carries the verdict. A Figure of plot_spec.hpp, drawn
// by Cairo (plot_cairo.hpp).
#include <filesystem>
#include <string>

#include "jobs/report/plot_cairo.hpp"
#include "update/gap_diagnosis.hpp"

namespace piezo::jobs::report {

struct DiagnosisPlotOptions {
  int width = 1200, height = 800;
  std::string title = "Gap diagnosis";  // large; the verdict is appended
  std::string subtitle;  // e.g. the captures; the verdict's numbers follow on a line of their own
};

// Where the panels lie on a figure of this size (the plot areas, inside the
// axes), top to bottom: |Z|, the residual of |Z| in dB, the residual of the
// phase; with a subtitle (as `diagnose --plot` draws it).
struct DiagnosisPlotLayout {
  PixelRect z, db, deg;
};
DiagnosisPlotLayout diagnosis_plot_layout(int width, int height);

// Colours of the plot, public so that tests and docs can find them in the image.
namespace diagnosis_palette {
inline constexpr Colour kMeasured{20, 30, 120, 255};   // navy
inline constexpr Colour kBefore{230, 110, 0, 255};     // orange, dashed
inline constexpr Colour kAfter{40, 170, 60, 255};      // green
inline constexpr Colour kSigma{150, 150, 150, 110};    // translucent grey band
inline constexpr Colour kRegionA{205, 222, 246, 255};  // light blue
inline constexpr Colour kRegionB{246, 234, 200, 255};  // light sand
}  // namespace diagnosis_palette

// Throws std::invalid_argument when the diagnosis holds no curves.
Figure diagnosis_figure(const update::GapDiagnosis& d,
                                const DiagnosisPlotOptions& opt = {});
// Throws std::runtime_error naming the file when it cannot be written.
void write_diagnosis_png(const update::GapDiagnosis& d, const DiagnosisPlotOptions& opt,
                         const std::filesystem::path& file);

}  // namespace piezo::jobs::report

#pragma once
// The gap diagnosis as a plot (update/gap_diagnosis.hpp): the residual
// ln(Z_meas/Z_model) of the base refit over frequency — |Z| in dB or phase in
// degrees — with the measurement's ±2σ, the residual after the added effects
// when there are any, and the misfit regions shaded by their dominant kind
// (palette.hpp), each with its share of χ² in the hover read-out. Frequency
// in kHz.
#include "ui/gui/plot_widget.hpp"
#include "jobs/pipeline/pipeline.hpp"  // update::GapDiagnosis

namespace piezo::gui {

PlotSpec residual_plot_spec(const update::GapDiagnosis& d, bool phase);

}  // namespace piezo::gui

#include "jobs/text/user_message.hpp"

#include <algorithm>
#include <cctype>

namespace piezo::jobs {

const std::vector<std::string_view>& internal_function_names() {
  static const std::vector<std::string_view> names = {
      "a_from_d31", "add_in_quadrature", "analytic_ring", "apply_channel2_response", "assess_impedance", "average_shots",
      "band_from_replicates", "band_from_sigma", "bar_vibrator", "block_header", "bootstrap_over_shots",
      "bvd_start_from_circle", "check_shots", "circuit_mode_figures", "circumferential_modes", "cmcm_equations", "compute_stats",
      "conductance_peak", "cross_spectra", "d_form_sensitivity", "d_param", "debye_network_fit",
      "debye_network_for_loss", "deskew_channel", "deskew_impedance", "deskew_record", "element_split",
      "eps_s33_from", "eps_t33_from_low_z", "estimate_noise_std", "extract_features", "find_features",
      "find_preset", "fit_admittance_circle", "fit_bvd", "fit_equivalent_circuit", "fit_fixture", "fit_gap",
      "fit_output_error", "fit_port_model", "fit_prony_charge", "form_sensitivity", "forward_difference_jacobian",
      "frequency_grid", "gauss_legendre", "impedance_fft", "impedance_from_charge", "impedance_prony",
      "impedance_shot_ensemble", "impedance_stepped_sine", "impedance_xspec", "kramers_kronig_check",
      "largest_drop_order", "levenberg_marquardt", "lock_in", "lossy_capacitance", "make_grid",
      "make_sim_bench", "make_window", "mean_record", "mode_figures", "mode_shape_cmcm", "mode_shape_unknown_name",
      "open_bench", "open_transport", "open_usbtmc", "parasitic_branch", "parse_disturbances",
      "parse_ohm_at_hz", "phase_slope_delay", "predict_output_error", "prepare_divider", "probe_capture",
      "prony_ss", "rayleigh_fit", "rayleigh_from_damping", "rayleigh_from_two_modes", "read_impedance_file",
      "read_impedance_table", "recorded_transfer", "recorded_transfers", "render_raster", "render_svg",
      "reported_impedance",
      "run_measurement", "scan_effects", "select_order", "select_shard", "sensitivity_params", "solve_tsvd",
      "stabilization_chart", "to_d_form", "to_e_form", "to_e_form_unchecked", "torsion_frequency_hz",
      "tube_admittances", "update_cmcm",
      "update_lm", "vector_fit", "write_impedance_csv", "write_touchstone_s1p", "xcorr_delay"};
  return names;
}

namespace {

bool ident_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// Length of an internal name followed by ": " at s[0], or 0.
std::size_t internal_prefix(std::string_view s) {
  std::size_t i = 0;
  bool qualified = false;
  for (;;) {
    const std::size_t start = i;
    while (i < s.size() && ident_char(s[i])) ++i;
    if (i == start) return 0;
    if (s.substr(i, 2) == "::") {
      qualified = true;
      i += 2;
      continue;
    }
    break;
  }
  if (s.substr(i, 2) != ": ") return 0;
  if (qualified) return i + 2;
  const auto& names = internal_function_names();
  return std::find(names.begin(), names.end(), s.substr(0, i)) != names.end() ? i + 2 : 0;
}

}  // namespace

std::string user_message(std::string_view what) {
  std::string out;
  out.reserve(what.size());
  bool clause_start = true;
  std::size_t i = 0;
  while (i < what.size()) {
    if (clause_start) {
      // Several in a row ("prony_ss: select_order: ...").
      while (std::size_t n = internal_prefix(what.substr(i))) i += n;
      clause_start = false;
      if (i >= what.size()) break;
    }
    const char c = what[i];
    out += c;
    ++i;
    if (c == '(' || ((c == ':' || c == ';') && i < what.size() && what[i] == ' ')) {
      if (c != '(') out += what[i++];
      clause_start = true;
    }
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out.empty() ? std::string(what) : out;
}

}  // namespace piezo::jobs

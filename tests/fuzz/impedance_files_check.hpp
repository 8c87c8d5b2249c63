#pragma once
// Shared by the harnesses of dsp/impedance_files/ (fuzz_touchstone,
// fuzz_hp4294a, fuzz_e4990a, fuzz_bode100, fuzz_impedance_table, fuzz_hioki,
// fuzz_labone; fuzz_impedance_columns uses check_imported): the input is
// a file's text, read by one reader (forced) and by read_impedance_any (the
// format detected). Documented rejection: std::invalid_argument.
//
// An accepted curve promises: at least one point; as many impedances as
// frequencies; finite frequencies >= 0, strictly ascending; finite Z with a
// finite |Z|; uncertainties empty or one finite σ >= 0 per point for |Z| and
// phase; the reader's format, a format name and a quantity; a magnitude-only
// curve holds |Z| + 0j; notes, format name and quantity are valid UTF-8
// (they go into JSON). When the content
// is detected as that reader's format, read_impedance_any gives the same
// curve, bit for bit, or refuses it too.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>

#include "dsp/impedance_files/read_any.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace piezo::fuzz {

inline void check_imported(const dsp::ImportedImpedance& c, const char* who) {
  const std::size_t n = c.f_hz.size();
  FUZZ_CHECK(n >= 1 && c.z_ohm.size() == n, "%s: %zu frequencies, %zu impedances", who, n,
             c.z_ohm.size());
  FUZZ_CHECK((c.abs_sigma_ohm.empty() && c.phase_sigma_rad.empty()) ||
                 (c.abs_sigma_ohm.size() == n && c.phase_sigma_rad.size() == n),
             "%s: %zu |Z| sigmas, %zu phase sigmas for %zu points", who, c.abs_sigma_ohm.size(),
             c.phase_sigma_rad.size(), n);
  for (std::size_t i = 0; i < n; ++i) {
    FUZZ_CHECK(std::isfinite(c.f_hz[i]) && c.f_hz[i] >= 0, "%s: f[%zu] = %g", who, i, c.f_hz[i]);
    FUZZ_CHECK(i == 0 || c.f_hz[i] > c.f_hz[i - 1], "%s: f[%zu] = %g not above f[%zu] = %g", who, i,
               c.f_hz[i], i - 1, c.f_hz[i - 1]);
    FUZZ_CHECK(std::isfinite(c.z_ohm[i].real()) && std::isfinite(c.z_ohm[i].imag()) &&
                   std::isfinite(std::abs(c.z_ohm[i])),
               "%s: Z[%zu] = %g%+gj", who, i, c.z_ohm[i].real(), c.z_ohm[i].imag());
    if (!c.abs_sigma_ohm.empty())
      FUZZ_CHECK(std::isfinite(c.abs_sigma_ohm[i]) && c.abs_sigma_ohm[i] >= 0 &&
                     std::isfinite(c.phase_sigma_rad[i]) && c.phase_sigma_rad[i] >= 0,
                 "%s: sigma[%zu] = %g, %g", who, i, c.abs_sigma_ohm[i], c.phase_sigma_rad[i]);
  }
  FUZZ_CHECK(!c.format_name.empty() && !c.quantity.empty(), "%s: no format name or quantity", who);
  if (c.magnitude_only)
    for (std::size_t i = 0; i < n; ++i)
      FUZZ_CHECK(c.z_ohm[i].imag() == 0 && c.z_ohm[i].real() >= 0,
                 "%s: magnitude-only Z[%zu] = %g%+gj is not |Z| + 0j", who, i, c.z_ohm[i].real(),
                 c.z_ohm[i].imag());
  // Notes, names and quantity go into JSON: valid UTF-8.
  const auto utf8 = [](const std::string& s) {
    for (std::size_t i = 0; i < s.size();) {
      const auto b = static_cast<unsigned char>(s[i]);
      const std::size_t k = b < 0x80 ? 1 : (b >> 5) == 6 ? 2 : (b >> 4) == 14 ? 3 : (b >> 3) == 30 ? 4 : 0;
      if (k == 0 || i + k > s.size()) return false;
      for (std::size_t j = 1; j < k; ++j)
        if ((static_cast<unsigned char>(s[i + j]) & 0xC0) != 0x80) return false;
      i += k;
    }
    return true;
  };
  FUZZ_CHECK(utf8(c.format_name) && utf8(c.quantity), "%s: format name or quantity not UTF-8", who);
  for (const auto& note : c.notes) FUZZ_CHECK(utf8(note), "%s: a note is not UTF-8", who);
}

// One harness: `format`'s reader on the text, then read_impedance_any.
inline int run_impedance_reader(const std::uint8_t* data, std::size_t size,
                                dsp::ImpedanceFileFormat format, const char* name) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  dsp::ImportedImpedance forced, any;
  bool forced_ok = true, any_ok = true;
  try {
    std::istringstream in(text);
    forced = dsp::read_impedance_any(in, name, format);
  } catch (const std::invalid_argument& e) {
    forced_ok = false;
    if (std::getenv("PIEZO_FUZZ_DEBUG")) std::fprintf(stderr, "%s: refused: %s\n", name, e.what());
  }
  if (forced_ok) {
    check_imported(forced, dsp::to_string(format));
    FUZZ_CHECK(forced.format == format, "%s reader returned format %s", dsp::to_string(format),
               dsp::to_string(forced.format));
  }
  const auto detected = dsp::detect_impedance_format(text, name);
  try {
    std::istringstream in(text);
    any = dsp::read_impedance_any(in, name);
  } catch (const std::invalid_argument&) {
    any_ok = false;
  }
  if (any_ok) {
    check_imported(any, "read_impedance_any");
    FUZZ_CHECK(any.format == detected, "detected %s, read as %s", dsp::to_string(detected),
               dsp::to_string(any.format));
  }
  if (detected == format) {
    FUZZ_CHECK(forced_ok == any_ok, "%s reader %s, read_impedance_any %s", dsp::to_string(format),
               forced_ok ? "accepted" : "refused", any_ok ? "accepted" : "refused");
    if (forced_ok)
      FUZZ_CHECK(forced.f_hz == any.f_hz && forced.size() == any.size() &&
                     std::memcmp(forced.z_ohm.data(), any.z_ohm.data(),
                                 forced.size() * sizeof(forced.z_ohm[0])) == 0 &&
                     forced.notes == any.notes,
                 "%s reader and read_impedance_any differ", dsp::to_string(format));
  }
  return 0;
}

}  // namespace piezo::fuzz

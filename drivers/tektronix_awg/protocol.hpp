#pragma once
// Tektronix AWG5000 / AWG7000 series (AWG5002/5012/5014 and their B/C
// versions; AWG7051/7052/7101/7102, AWG7061B/7062B/7121B/7122B, AWG7082C/7122C):
// what the tektronix_awg driver and its simulated twin agree on. The model
// table and the command table are data; the driver's logic holds no model
// names. Command forms follow the "AWG5000 and AWG7000 Series Arbitrary
// Waveform Generators Programmer Manual" (Tektronix 077-0061-xx), as its
// command syntax is reproduced in Tektronix's own tm_devices package
// (commands/gen_*/awg5k-7k: wlist, awgcontrol, source, trigger modules); we
// have not held the manual itself. Nothing here has met a real instrument.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace piezo::drivers::tektronix_awg {

struct Model {
  std::string_view idn_model;  // field 2 of *IDN?, compared exactly ("AWG5012" is not "AWG5012B")
  int channels;
  double min_sample_rate_hz;
  double max_sample_rate_hz;  // one channel, no interleave
  std::size_t min_points;     // waveform length
  std::size_t max_points;     // standard memory (option 01 doubles it; *IDN? does not say)
  int dac_bits;               // resolution while both markers are output
  // Selects that resolution with SOURce1:DAC:RESolution; 0 = fixed, nothing sent.
  // The AWG7000's 10-bit mode takes the marker bits for data, so 8 bits are chosen.
  int select_dac_bits;
  double min_amplitude_vpp;  // SOURce1:VOLTage:AMPLitude, specified into 50 ohm
  double max_amplitude_vpp;
  double max_offset_v;  // |SOURce1:VOLTage:OFFSet|, into 50 ohm
};

// Rates, lengths and levels: AWG5000 from the AWG5000 Technical Reference's
// specification tables as another driver quotes them (qudi-iqo-modules,
// tektronix_awg5014c.py: 10 MS/s..1.2 GS/s, 250..16.2 M points, 20 mV..4.5 Vpp,
// offset ±2.25 V); AWG7000 levels from tm_devices' signal-generation notes
// (50 mV..2 Vpp, ±0.5 V; option 02/06 direct outputs allow 0.5..1 Vpp and no
// offset, which *IDN? does not reveal). The AWG7000 minimum length (960) is a
// conservative guess we could not confirm; the waveforms here are thousands of points.
// clang-format off
inline constexpr Model kModels[] = {
    // idn    ch  min rate max rate  min pts  max pts    bits sel  min A  max A  |offset|
    {"AWG5002", 2, 10e6, 600e6, 250, 16'200'000, 14, 0, 0.02, 4.5, 2.25},
    {"AWG5012", 2, 10e6, 1.2e9, 250, 16'200'000, 14, 0, 0.02, 4.5, 2.25},
    {"AWG5014", 4, 10e6, 1.2e9, 250, 16'200'000, 14, 0, 0.02, 4.5, 2.25},
    {"AWG5002B", 2, 10e6, 600e6, 250, 16'200'000, 14, 0, 0.02, 4.5, 2.25},
    {"AWG5012B", 2, 10e6, 1.2e9, 250, 16'200'000, 14, 0, 0.02, 4.5, 2.25},
    {"AWG5014B", 4, 10e6, 1.2e9, 250, 16'200'000, 14, 0, 0.02, 4.5, 2.25},
    {"AWG5002C", 2, 10e6, 600e6, 250, 16'200'000, 14, 0, 0.02, 4.5, 2.25},
    {"AWG5012C", 2, 10e6, 1.2e9, 250, 16'200'000, 14, 0, 0.02, 4.5, 2.25},
    {"AWG5014C", 4, 10e6, 1.2e9, 250, 16'200'000, 14, 0, 0.02, 4.5, 2.25},
    {"AWG7051", 1, 10e6, 5e9, 960, 32'400'000, 8, 8, 0.05, 2.0, 0.5},
    {"AWG7052", 2, 10e6, 5e9, 960, 32'400'000, 8, 8, 0.05, 2.0, 0.5},
    {"AWG7101", 1, 10e6, 10e9, 960, 32'400'000, 8, 8, 0.05, 2.0, 0.5},
    {"AWG7102", 2, 10e6, 10e9, 960, 32'400'000, 8, 8, 0.05, 2.0, 0.5},
    {"AWG7061B", 1, 10e6, 6e9, 960, 32'400'000, 8, 8, 0.05, 2.0, 0.5},
    {"AWG7062B", 2, 10e6, 6e9, 960, 32'400'000, 8, 8, 0.05, 2.0, 0.5},
    {"AWG7121B", 1, 10e6, 12e9, 960, 32'400'000, 8, 8, 0.05, 2.0, 0.5},
    {"AWG7122B", 2, 10e6, 12e9, 960, 32'400'000, 8, 8, 0.05, 2.0, 0.5},
    {"AWG7082C", 2, 10e6, 8e9, 960, 32'400'000, 8, 8, 0.05, 2.0, 0.5},
    {"AWG7122C", 2, 10e6, 12e9, 960, 32'400'000, 8, 8, 0.05, 2.0, 0.5},
};
// clang-format on

// "TEKTRONIX,AWG5014C,B051234,SCPI:99.0 FW:4.6.0.7": the row for field 2 when
// field 1 is Tektronix (any case); nullptr otherwise.
const Model* find_model(std::string_view idn);

// Command table (channel 1). Long forms as the manual writes them.
inline constexpr std::string_view kStop = "AWGControl:STOP";
inline constexpr std::string_view kRun = "AWGControl:RUN";
inline constexpr std::string_view kRunState =
    "AWGControl:RSTate?";  // 0 stopped, 1 waiting for trigger, 2 running
inline constexpr std::string_view kRunModeTriggered =
    "AWGControl:RMODe TRIGgered";  // one waveform per trigger
// External source: with nothing at TRIGger IN only *TRG starts a burst (the
// internal source would be the free-running trigger timer).
inline constexpr std::string_view kTriggerExternal = "TRIGger:SEQuence:SOURce EXTernal";
inline constexpr std::string_view kTrigger =
    "*TRG";  // = TRIGger:SEQuence:IMMediate (force trigger)
inline constexpr std::string_view kListSize = "WLISt:SIZE?";
inline constexpr std::string_view kListName = "WLISt:NAME? ";  // + index, reply quoted
inline constexpr std::string_view kWaveformDelete = "WLISt:WAVeform:DELete ";  // + "name"
inline constexpr std::string_view kWaveformNew = "WLISt:WAVeform:NEW ";  // + "name",<points>,REAL
inline constexpr std::string_view kWaveformData =
    "WLISt:WAVeform:DATA ";                                       // + "name",0,<points>,<block>
inline constexpr std::string_view kAssign = "SOURce1:WAVeform ";  // + "name"
inline constexpr std::string_view kSampleRate =
    "SOURce1:FREQuency ";  // the sampling clock, all channels
inline constexpr std::string_view kDacResolution = "SOURce1:DAC:RESolution ";
inline constexpr std::string_view kAmplitude = "SOURce1:VOLTage:AMPLitude ";  // Vpp into 50 ohm
inline constexpr std::string_view kOffset = "SOURce1:VOLTage:OFFSet ";
inline constexpr std::string_view kMarkerDelay = "SOURce1:MARKer1:DELay 0";
inline constexpr std::string_view kMarkerLow = "SOURce1:MARKer1:VOLTage:LOW 0";
// 1 V into 50 ohm (2 V into the DAQ's high-impedance AUX input): a TTL-ish edge.
inline constexpr std::string_view kMarkerHigh = "SOURce1:MARKer1:VOLTage:HIGH 1";
inline constexpr std::string_view kOutputOn = "OUTPut1:STATe ON";
inline constexpr std::string_view kOutputOff = "OUTPut1:STATe OFF";
inline constexpr std::string_view kWaveformName = "PIEZO";

// REAL waveform data (WLISt:WAVeform:DATA on a waveform created with type
// REAL; the manual's "waveform data format" table for real data): 5 bytes per
// point, an IEEE 754 float32, little-endian, normalised to [-1, 1] (output =
// offset + amplitude/2 · value), then one marker byte with marker 1 in bit 6
// and marker 2 in bit 7.
inline constexpr std::size_t kRealPointBytes = 5;
inline constexpr std::uint8_t kMarker1Bit = 0x40;
inline constexpr std::uint8_t kMarker2Bit = 0x80;

struct RealPoints {
  std::vector<float> values;
  std::vector<std::uint8_t> markers;  // the marker byte as sent
};

// Encodes `values` (already float32) with `markers` (same length).
std::vector<std::uint8_t> encode_real_points(std::span<const float> values,
                                             std::span<const std::uint8_t> markers);
// Decodes a REAL block; nullopt if its length is not a whole number of points.
std::optional<RealPoints> decode_real_points(std::span<const std::uint8_t> block);

// Marker 1 is the DAQ's trigger: high from the first point for half the
// waveform, so its one rising edge is at t = 0 of the burst and it is low
// again (the idle level) well before the waveform ends.
std::vector<std::uint8_t> trigger_markers(std::size_t points);

}  // namespace piezo::drivers::tektronix_awg

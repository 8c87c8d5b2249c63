#pragma once
// Keysight 33500B / 33600A "Trueform" waveform generators: the SCPI commands
// this driver uses, after the 33500 Series Operating and Service Guide
// (programming reference chapter). Kept as data so that model differences
// (e.g. channel count, max sample rate) stay out of the driver's logic.
#include <string_view>

namespace piezo::drivers::keysight33500 {

struct Model {
  std::string_view idn_model;  // field 2 of *IDN?
  int channels;
  double max_sample_rate_hz;
  std::size_t max_arb_points;
};

inline constexpr Model kModels[] = {
    {"33521B", 1, 250e6, 1'000'000}, {"33522B", 2, 250e6, 1'000'000},
    {"33611A", 1, 1e9, 4'000'000},   {"33612A", 2, 1e9, 4'000'000},
};

// Command table (channel 1; `%s` = arb name, blocks are float32 in [-1, 1]).
inline constexpr std::string_view kClearVolatile = "SOURce1:DATA:VOLatile:CLEar";
inline constexpr std::string_view kByteOrderSwapped = "FORMat:BORDer SWAPped";  // little-endian floats
inline constexpr std::string_view kArbDataPrefix = "SOURce1:DATA:ARBitrary ";  // + name + "," + block
inline constexpr std::string_view kSelectArb = "SOURce1:FUNCtion:ARBitrary ";
inline constexpr std::string_view kFunctionArb = "SOURce1:FUNCtion ARB";
inline constexpr std::string_view kArbRate = "SOURce1:FUNCtion:ARBitrary:SRATe ";
inline constexpr std::string_view kLoadHighZ = "OUTPut1:LOAD INFinity";
inline constexpr std::string_view kVoltagePp = "SOURce1:VOLTage ";
inline constexpr std::string_view kOffset = "SOURce1:VOLTage:OFFSet 0";
inline constexpr std::string_view kBurstTriggered = "SOURce1:BURSt:MODE TRIGgered";
inline constexpr std::string_view kBurstOneCycle = "SOURce1:BURSt:NCYCles 1";
inline constexpr std::string_view kBurstOn = "SOURce1:BURSt:STATe ON";
inline constexpr std::string_view kTriggerBus = "TRIGger1:SOURce BUS";
inline constexpr std::string_view kSyncOn = "OUTPut:SYNC ON";
inline constexpr std::string_view kOutputOn = "OUTPut1 ON";
inline constexpr std::string_view kOutputOff = "OUTPut1 OFF";
inline constexpr std::string_view kTrigger = "*TRG";
inline constexpr std::string_view kArbName = "PIEZO";

}  // namespace piezo::drivers::keysight33500

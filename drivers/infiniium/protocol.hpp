#pragma once
// Keysight (Agilent) Infiniium oscilloscopes used as a two-channel digitizer,
// after the Infiniium 9000/90000 Series Programmer's Reference: acquisition
// (:ACQuire), channel (:CHANnel<n>), timebase, trigger and waveform
// (:WAVeform, WORD format, IEEE 488.2 definite-length blocks) commands.
#include <string_view>

namespace piezo::drivers::infiniium {

struct Model {
  std::string_view idn_prefix;  // start of field 2 of *IDN?
  double max_sample_rate_hz;
  std::size_t max_points;
};

inline constexpr Model kModels[] = {
    {"DSO9", 20e9, 10'000'000}, {"MSO9", 20e9, 10'000'000},
    {"DSOS", 20e9, 50'000'000}, {"MSOS", 20e9, 50'000'000},
    {"DSO90", 40e9, 10'000'000},
};

inline constexpr std::string_view kHeaderOff = ":SYSTem:HEADer OFF";
inline constexpr std::string_view kRealTime = ":ACQuire:MODE RTIMe";
inline constexpr std::string_view kSampleRate = ":ACQuire:SRATe:ANALog ";
inline constexpr std::string_view kPoints = ":ACQuire:POINts:ANALog ";
inline constexpr std::string_view kRefLeft = ":TIMebase:REFerence LEFT";
inline constexpr std::string_view kPosition = ":TIMebase:POSition ";
inline constexpr std::string_view kEdgeMode = ":TRIGger:MODE EDGE";
inline constexpr std::string_view kTrigAux = ":TRIGger:EDGE:SOURce AUX";
inline constexpr std::string_view kTrigChan1 = ":TRIGger:EDGE:SOURce CHANnel1";
inline constexpr std::string_view kSlopePos = ":TRIGger:EDGE:SLOPe POSitive";
inline constexpr std::string_view kWordFormat = ":WAVeform:FORMat WORD";
inline constexpr std::string_view kLsbFirst = ":WAVeform:BYTeorder LSBFirst";
inline constexpr std::string_view kStreamingOff = ":WAVeform:STReaming OFF";
inline constexpr std::string_view kSingle = ":SINGle";
inline constexpr std::string_view kAcqDone = ":ADER?";

}  // namespace piezo::drivers::infiniium

#pragma once
// Red Pitaya STEMlab 125-14: what the redpitaya driver and its simulated twin
// (drivers/sim/sim_redpitaya.*) agree on. One SCPI server (TCP port 5000)
// is both the generator (fast analog output 1) and the two-channel
// acquisition (IN1 = v1, IN2 = v2), so one address serves both bench roles.
//
// Command forms follow Red Pitaya's SCPI documentation
// (redpitaya.readthedocs.io, "Acquisition" and "Signal generator" command
// lists) and the SCPI server's own sources (RedPitaya/RedPitaya,
// scpi-server/src/acquire.cpp and scpi-parser-ext.cpp), as far as we could
// read them; nothing here has met a real board.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace piezo::drivers::redpitaya {

// The board, as data. *IDN? names the SCPI server generation
// ("REDPITAYA,INSTR2020,0,01-02"), not the board: a STEMlab 125-10 or a
// SDRlab 122-16 answers the same and would be scaled as a 125-14.
struct Board {
  std::string_view name;
  double adc_rate_hz;          // undecimated ADC clock
  std::size_t buffer_samples;  // acquisition buffer per channel (ACQ:SOURn:DATA? returns all of it)
  int adc_bits;
  std::size_t arb_points;  // generator buffer (SOUR1:TRAC:DATA:DATA)
  double dac_rate_hz;      // the generator's clock: at most one buffer point per clock
  double max_output_v;     // |amplitude| + |offset| into a high-impedance load
};
inline constexpr Board kStemlab125_14 = {"STEMlab 125-14", 125e6, 16384, 14, 16384, 125e6, 1.0};

// *IDN? field 2 values of the server generations we know of (scpi-server
// sources: INSTR2014 before OS 2.00, INSTR2020, INSTR2023); field 1 is REDPITAYA.
inline constexpr std::string_view kIdnModels[] = {"INSTR2014", "INSTR2020", "INSTR2023"};
bool accepts_idn(std::string_view idn);

// ACQ:DEC: the decimations the original FPGA image offers (newer ones
// accept more); sample rate = adc_rate_hz / decimation.
inline constexpr unsigned kDecimations[] = {1, 8, 64, 1024, 8192, 65536};

struct RateChoice {
  unsigned decimation;
  double sample_rate_hz;  // the actual rate
};
// The largest decimation whose rate is at least `wanted_hz` (1e-9 relative
// slack): never samples slower than the plan asked. nullopt above 125 MS/s
// or for a non-positive rate.
std::optional<RateChoice> choose_decimation(double wanted_hz, const Board& b = kStemlab125_14);

// ACQ:SOURn:GAIN: the input jumpers' ranges (LV ±1 V, HV ±20 V), as data.
struct Gain {
  std::string_view name;
  double range_v;  // ±range_v full scale
};
inline constexpr Gain kGains[] = {{"LV", 1.0}, {"HV", 20.0}};
// The smallest gain whose range covers ±range_v; nullptr if none does.
const Gain* gain_for_range(double range_v);

// ACQ:TRig:DLY: with delay 0 the trigger sits at sample 8192 of the
// 16384-sample data buffer; a delay d moves it to sample 8192 - d (d samples
// more after the trigger). So p pretrigger samples need d = 8192 - p.
long trigger_delay_for(std::size_t pretrigger, const Board& b = kStemlab125_14);

// Command table (generator channel 1, inputs 1 and 2).
inline constexpr std::string_view kOutputOff = "OUTPUT1:STATE OFF";
inline constexpr std::string_view kOutputOn = "OUTPUT1:STATE ON";
inline constexpr std::string_view kFuncArb = "SOUR1:FUNC ARBITRARY";
inline constexpr std::string_view kArbData = "SOUR1:TRAC:DATA:DATA ";  // + v0,v1,... in [-1, 1]
inline constexpr std::string_view kFrequency = "SOUR1:FREQ:FIX ";  // + Hz: one period = the buffer
inline constexpr std::string_view kAmplitude = "SOUR1:VOLT ";      // + V, peak, high-impedance load
inline constexpr std::string_view kOffset = "SOUR1:VOLT:OFFS 0";
inline constexpr std::string_view kBurstMode = "SOUR1:BURS:STAT BURST";
inline constexpr std::string_view kBurstOneCycle = "SOUR1:BURS:NCYC 1";
inline constexpr std::string_view kBurstOneRepetition = "SOUR1:BURS:NOR 1";
inline constexpr std::string_view kGenTriggerSource = "SOUR1:TRig:SOUR INT";
inline constexpr std::string_view kGenTrigger = "SOUR1:TRig:INT";  // one burst now
inline constexpr std::string_view kAcqReset = "ACQ:RST";  // also resets the format to ASCII
inline constexpr std::string_view kDecimation = "ACQ:DEC ";
inline constexpr std::string_view kFormatBin = "ACQ:DATA:FORMAT BIN";
inline constexpr std::string_view kUnitsVolts = "ACQ:DATA:UNITS VOLTS";
inline constexpr std::string_view kTriggerDelay = "ACQ:TRig:DLY ";
inline constexpr std::string_view kAcqStart = "ACQ:START";
inline constexpr std::string_view kTriggerOnGenerator = "ACQ:TRig AWG_PE";
inline constexpr std::string_view kTriggerState = "ACQ:TRig:STAT?";  // WAIT | TD
inline constexpr std::string_view kBufferFilled = "ACQ:TRig:FILL?";  // 0 | 1 (OS 2.00 and later)
// "ACQ:SOUR" + n + ":GAIN " + LV|HV and "ACQ:SOUR" + n + ":DATA?"
std::string gain_command(int input, std::string_view gain);
std::string data_query(int input);

// SOUR1:TRAC:DATA:DATA's parameter: the samples as comma-separated decimal
// floats, each printed so that it reads back as the same float32 (%.9g).
std::string encode_arb_list(std::span<const float> values);
// Its inverse (for the twin): nullopt on an empty list, a non-number or more than `max_points`.
std::optional<std::vector<float>> decode_arb_list(std::span<const std::string> params,
                                                  std::size_t max_points);

// ACQ:SOURn:DATA? with ACQ:DATA:FORMAT BIN and ACQ:DATA:UNITS VOLTS: an IEEE
// 488.2 definite-length block of float32 values, most significant byte first
// (the server byte-swaps each value with htonl: scpi-parser-ext.cpp,
// resultBufferFloatBin). The reply line then ends in "\r\n". One stored
// version of that function casts each value through uint8_t before the swap,
// which would deliver whole volts only: if a real board returns integers,
// look at its server version before at this driver.
std::vector<std::uint8_t> encode_float_block_payload(std::span<const float> values);
// nullopt if the payload is not a whole number of float32 values.
std::optional<std::vector<float>> decode_float_block_payload(std::span<const std::uint8_t> payload);

}  // namespace piezo::drivers::redpitaya

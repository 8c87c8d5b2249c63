#pragma once
// Model-to-model USBTMC deviations, as data. Each entry names its public
// source; add a device here rather than an `if` in the transport.
#include <cstdint>
#include <span>

namespace piezo::drivers::usbtmc {

struct UsbTmcQuirk {
  std::uint16_t vid = 0;
  std::uint16_t pid = 0;
  const char* model = "";
  // The device answers a REQUEST_DEV_DEP_MSG_IN with the whole response in
  // one transfer (header in the first packet only), whatever TransferSize
  // was asked; so ask for the largest size. (Linux usbtmc "rigol_quirk".)
  bool whole_message_per_request = false;
  const char* source = "";
};

std::span<const UsbTmcQuirk> quirk_table();
const UsbTmcQuirk* find_quirk(std::uint16_t vid, std::uint16_t pid);  // nullptr if none

}  // namespace piezo::drivers::usbtmc

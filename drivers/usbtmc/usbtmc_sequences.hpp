#pragma once
// The USBTMC class-request sequences (spec 4.2.1.2 - 4.2.1.7): device clear
// and the bulk-OUT / bulk-IN aborts, with their PENDING polling, the bulk-IN
// draining they require and the CLEAR_FEATURE(ENDPOINT_HALT) that ends them.
// They run over any UsbTmcEndpoints; UsbIoError passes through to the caller.
#include <chrono>
#include <cstdint>
#include <string>

#include "drivers/usbtmc/usbtmc_endpoints.hpp"

namespace piezo::drivers::usbtmc {

struct SequencePolicy {
  std::chrono::milliseconds control_timeout{1000};
  std::chrono::milliseconds poll_interval{10};  // between CHECK_*_STATUS while PENDING
  int max_polls = 200;
  // Draining bulk-IN: each read waits at most this long (data should already be queued).
  std::chrono::milliseconds drain_timeout{300};
  int max_drain_reads = 100;  // as Linux's USBTMC_MAX_READS_TO_CLEAR_BULK_IN
};

// INITIATE_CLEAR, CHECK_CLEAR_STATUS until not PENDING (draining bulk-IN when
// the device says it holds data), then clear the bulk-OUT halt. Throws
// TransportError(Protocol) on a refusing status, (Timeout) when the device
// stays PENDING past max_polls.
void run_clear(UsbTmcEndpoints& ep, const SequencePolicy& p);

// Aborts the bulk-IN transfer answering REQUEST_DEV_DEP_MSG_IN `tag`.
// Returns what happened, for the caller's error message.
std::string run_abort_bulk_in(UsbTmcEndpoints& ep, std::uint8_t tag, const SequencePolicy& p);

// Aborts bulk-OUT transfer `tag`, then clears the bulk-OUT halt.
std::string run_abort_bulk_out(UsbTmcEndpoints& ep, std::uint8_t tag, const SequencePolicy& p);

// Reads and discards bulk-IN data until a short packet (or a timeout).
void drain_bulk_in(UsbTmcEndpoints& ep, const SequencePolicy& p);

}  // namespace piezo::drivers::usbtmc

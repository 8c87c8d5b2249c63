#include "drivers/usbtmc/usbtmc_sequences.hpp"

#include <array>
#include <thread>
#include <vector>

#include "drivers/transport.hpp"

namespace piezo::drivers::usbtmc {

namespace {
ClassReply class_request(UsbTmcEndpoints& ep, const ControlSetup& s, const SequencePolicy& p) {
  std::array<std::uint8_t, 64> buf{};
  const std::size_t n = ep.control_in(s, buf.data(), p.control_timeout);
  return parse_class_reply(static_cast<Request>(s.request), std::span(buf.data(), n));
}

[[noreturn]] void refused(Request r, Status s) {
  throw TransportError(TransportError::Kind::Protocol,
                       "USBTMC " + to_string(r) + " answered " + to_string(s));
}

[[noreturn]] void still_pending(Request r, int polls) {
  throw TransportError(
      TransportError::Kind::Timeout,
      "USBTMC " + to_string(r) + " still PENDING after " + std::to_string(polls) + " polls");
}

void pause(const SequencePolicy& p) {
  if (p.poll_interval.count() > 0) std::this_thread::sleep_for(p.poll_interval);
}
}  // namespace

void drain_bulk_in(UsbTmcEndpoints& ep, const SequencePolicy& p) {
  const std::size_t size = ep.max_packet_size() * 8;
  std::vector<std::uint8_t> buf(size);
  for (int i = 0; i < p.max_drain_reads; ++i) {
    std::size_t n = 0;
    try {
      n = ep.bulk_in(buf.data(), size, p.drain_timeout);
    } catch (const UsbIoError& e) {
      if (e.code() == UsbIoError::Code::Timeout) return;  // nothing (more) queued
      throw;
    }
    if (n < size) return;  // short packet: the device's transfer ended
  }
}

void run_clear(UsbTmcEndpoints& ep, const SequencePolicy& p) {
  const std::uint8_t ifc = ep.interface_number();
  const ClassReply init = class_request(ep, initiate_clear(ifc), p);
  if (init.status != Status::Success) refused(Request::InitiateClear, init.status);
  for (int poll = 0;; ++poll) {
    if (poll == p.max_polls) still_pending(Request::CheckClearStatus, poll);
    const ClassReply r = class_request(ep, check_clear_status(ifc), p);
    if (r.status == Status::Success) break;
    if (r.status != Status::Pending) refused(Request::CheckClearStatus, r.status);
    if (r.in_fifo_has_data)
      drain_bulk_in(ep, p);  // spec 4.2.1.7: read until a short packet, then check again
    else
      pause(p);
  }
  ep.clear_halt(ep.bulk_out_address());  // spec 4.2.1.7: the host clears the bulk-OUT halt
}

std::string run_abort_bulk_in(UsbTmcEndpoints& ep, std::uint8_t tag, const SequencePolicy& p) {
  const std::uint8_t in = ep.bulk_in_address();
  const ClassReply init = class_request(ep, initiate_abort_bulk_in(tag, in), p);
  // FAILED: no transfer in progress and the bulk-IN FIFO is empty; nothing to do.
  // TRANSFER_NOT_IN_PROGRESS: the device is on another bTag; leave it alone.
  if (init.status == Status::Failed || init.status == Status::TransferNotInProgress)
    return "no bulk-IN transfer to abort (" + to_string(init.status) + ")";
  if (init.status != Status::Success) refused(Request::InitiateAbortBulkIn, init.status);
  for (int poll = 0;; ++poll) {
    if (poll == p.max_polls) still_pending(Request::CheckAbortBulkInStatus, poll);
    drain_bulk_in(ep, p);  // spec 4.2.1.5: read until the short packet that ends the transfer
    const ClassReply r = class_request(ep, check_abort_bulk_in_status(in), p);
    if (r.status == Status::Success) return "bulk-IN transfer aborted";
    if (r.status != Status::Pending) refused(Request::CheckAbortBulkInStatus, r.status);
    if (!r.in_fifo_has_data) pause(p);
  }
}

std::string run_abort_bulk_out(UsbTmcEndpoints& ep, std::uint8_t tag, const SequencePolicy& p) {
  const std::uint8_t out = ep.bulk_out_address();
  const ClassReply init = class_request(ep, initiate_abort_bulk_out(tag, out), p);
  if (init.status == Status::Failed || init.status == Status::TransferNotInProgress)
    return "no bulk-OUT transfer to abort (" + to_string(init.status) + ")";
  if (init.status != Status::Success) refused(Request::InitiateAbortBulkOut, init.status);
  for (int poll = 0;; ++poll) {
    if (poll == p.max_polls) still_pending(Request::CheckAbortBulkOutStatus, poll);
    const ClassReply r = class_request(ep, check_abort_bulk_out_status(out), p);
    if (r.status == Status::Success) break;
    if (r.status != Status::Pending) refused(Request::CheckAbortBulkOutStatus, r.status);
    pause(p);
  }
  ep.clear_halt(out);  // spec 4.2.1.3: the host clears the bulk-OUT halt after the abort
  return "bulk-OUT transfer aborted";
}

}  // namespace piezo::drivers::usbtmc

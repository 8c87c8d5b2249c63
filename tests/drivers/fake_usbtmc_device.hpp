#pragma once
// FakeUsbTmcDevice: a scripted USBTMC instrument behind the UsbTmcEndpoints
// interface, for tests (no hardware). It parses the host's bulk-OUT headers
// strictly (recording violations), answers queries from a reply table,
// cuts replies into transfers and packets as a device would (short or
// zero-length packet at the end of each transfer), and can misbehave on
// request: stay silent, stall, time out, send a wrong bTag, ignore the
// requested TransferSize, answer class requests with scripted statuses.
#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include "drivers/usbtmc/usbtmc_endpoints.hpp"

namespace piezo::testing {

namespace ut = piezo::drivers::usbtmc;

class FakeUsbTmcDevice final : public ut::UsbTmcEndpoints {
 public:
  struct Config {
    std::size_t max_packet = 64;
    std::uint8_t interface = 0;
    std::uint8_t ep_out = 0x02;
    std::uint8_t ep_in = 0x81;
    // Largest payload per DEV_DEP_MSG_IN transfer (besides the host's
    // TransferSize); smaller than a reply -> several transfers, EOM on the last.
    std::size_t max_reply_transfer = 1 << 20;
    // Rigol-like: the whole reply in one transfer, whatever was requested.
    bool ignore_requested_size = false;
  };

  // Shared with the test after the transport takes ownership of the fake:
  // the test keeps a reference to this state.
  struct State {
    Config cfg;
    std::map<std::string, std::string> replies;  // message -> reply
    // Misbehaviour switches.
    bool silent = false;     // accept requests, never answer
    bool wrong_tag = false;  // answer with bTag + 1
    bool stall_bulk_in = false;
    bool stall_bulk_out = false;
    bool bulk_out_times_out = false;
    bool keep_in_fifo_on_clear = false;             // stale data survive INITIATE_CLEAR
    std::deque<ut::Status> check_clear_script;      // then SUCCESS (or PENDING while data)
    std::deque<ut::Status> check_abort_in_script;   // then SUCCESS
    std::deque<ut::Status> check_abort_out_script;  // then SUCCESS
    ut::Status initiate_clear_status = ut::Status::Success;

    // Records.
    std::vector<std::vector<std::uint8_t>> out_transfers;  // raw bulk-OUT writes
    std::vector<std::string> messages;                     // complete host messages
    std::vector<ut::Header> requests;                      // REQUEST_DEV_DEP_MSG_IN headers
    std::vector<ut::ControlSetup> controls;
    std::vector<std::uint8_t> halts_cleared;
    std::vector<std::size_t> in_read_sizes;  // `max` of each bulk_in call
    std::vector<std::string> log;            // event order, e.g. "ctrl INITIATE_CLEAR"
    std::vector<std::string> violations;     // host broke the spec

    // Device internals.
    std::string partial;                         // DEV_DEP_MSG_OUT payload so far
    std::string reply;                           // reply not yet sent
    std::deque<std::vector<std::uint8_t>> fifo;  // bulk-IN packets queued
    std::uint8_t last_out_tag = 0;
    std::uint8_t last_request_tag = 0;
  };

  explicit FakeUsbTmcDevice(State& s) : s_(s) {}

  std::uint8_t interface_number() const override { return s_.cfg.interface; }
  std::uint8_t bulk_out_address() const override { return s_.cfg.ep_out; }
  std::uint8_t bulk_in_address() const override { return s_.cfg.ep_in; }
  std::size_t max_packet_size() const override { return s_.cfg.max_packet; }

  void bulk_out(std::span<const std::uint8_t> bytes, std::chrono::milliseconds timeout) override;
  std::size_t bulk_in(std::uint8_t* buf, std::size_t max,
                      std::chrono::milliseconds timeout) override;
  std::size_t control_in(const ut::ControlSetup& setup, std::uint8_t* buf,
                         std::chrono::milliseconds timeout) override;
  void clear_halt(std::uint8_t endpoint) override;

  // Queues one DEV_DEP_MSG_IN transfer carrying `payload` (tests use it to
  // plant stale data or odd transfers directly).
  static void queue_transfer(State& s, std::uint8_t tag, const std::string& payload, bool eom);

 private:
  void on_request(const ut::Header& h);
  State& s_;
};

}  // namespace piezo::testing

#include "drivers/sim/loopback_transport.hpp"

#include <algorithm>

namespace piezo::drivers::sim {

void LoopbackTransport::send(std::span<const std::uint8_t> bytes) {
  if (closed_) throw TransportError(TransportError::Kind::Closed, name_ + ": instrument closed the connection");
  // The instrument has dropped the link: the bytes go nowhere (a socket's
  // first send after its peer closed succeeds too); the next read fails.
  if (close_pending_) return;
  framer_.feed(bytes);
  while (auto msg = framer_.next()) {
    Reply r = dev_->handle(*msg);
    out_.insert(out_.end(), r.bytes.begin(), r.bytes.end());
    if (r.close_connection) close_pending_ = true;
  }
}

std::size_t LoopbackTransport::receive(std::uint8_t* buf, std::size_t max, bool* eom) {
  *eom = false;
  if (out_.empty()) {
    if (close_pending_ || closed_) {
      closed_ = true;
      throw TransportError(TransportError::Kind::Closed, name_ + ": instrument closed the connection");
    }
    // Nothing will ever arrive in-process: this is what a timeout looks like.
    throw TransportError(TransportError::Kind::Timeout,
                         name_ + ": no reply within " + std::to_string(timeout_.count()) + " ms");
  }
  std::size_t n = std::min(max, out_.size());
  std::copy_n(out_.begin(), n, buf);
  out_.erase(out_.begin(), out_.begin() + static_cast<std::ptrdiff_t>(n));
  return n;
}

}  // namespace piezo::drivers::sim

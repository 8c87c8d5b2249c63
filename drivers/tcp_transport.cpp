#include "drivers/tcp_transport.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace piezo::drivers {

namespace {
std::string errno_text() { return std::strerror(errno); }
}  // namespace

TcpTransport::TcpTransport(const std::string& host, std::uint16_t port,
                           std::chrono::milliseconds timeout)
    : host_(host), port_(port), timeout_(timeout) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* res = nullptr;
  int rc = ::getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &res);
  if (rc != 0)
    throw TransportError(TransportError::Kind::Io,
                         address() + ": cannot resolve host: " + gai_strerror(rc));
  std::string last = "no address";
  for (addrinfo* ai = res; ai; ai = ai->ai_next) {
    int fd = ::socket(ai->ai_family, ai->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, ai->ai_protocol);
    if (fd < 0) continue;
    if (::connect(fd, ai->ai_addr, ai->ai_addrlen) != 0 && errno != EINPROGRESS) {
      last = errno_text();
      ::close(fd);
      continue;
    }
    pollfd p{fd, POLLOUT, 0};
    int pr = ::poll(&p, 1, static_cast<int>(timeout_.count()));
    int soerr = 0;
    socklen_t len = sizeof soerr;
    if (pr == 1) ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &soerr, &len);
    if (pr != 1 || soerr != 0) {
      last = pr == 0 ? "connection timed out" : std::strerror(soerr ? soerr : errno);
      ::close(fd);
      continue;
    }
    int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    fd_ = fd;
    break;
  }
  ::freeaddrinfo(res);
  if (fd_ < 0)
    throw TransportError(TransportError::Kind::Io, address() + ": cannot connect: " + last);
}

TcpTransport::~TcpTransport() {
  if (fd_ >= 0) ::close(fd_);
}

std::string TcpTransport::address() const { return "tcp://" + host_ + ":" + std::to_string(port_); }

void TcpTransport::send(std::span<const std::uint8_t> bytes) {
  std::size_t off = 0;
  while (off < bytes.size()) {
    pollfd p{fd_, POLLOUT, 0};
    int pr = ::poll(&p, 1, static_cast<int>(timeout_.count()));
    if (pr == 0)
      throw TransportError(TransportError::Kind::Timeout, address() + ": send timed out");
    if (pr < 0) {
      if (errno == EINTR) continue;
      throw TransportError(TransportError::Kind::Io, address() + ": poll: " + errno_text());
    }
    ssize_t n = ::send(fd_, bytes.data() + off, bytes.size() - off, MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EAGAIN || errno == EINTR) continue;
      // A peer that closed with our bytes unread answers with a reset (EPIPE or
      // ECONNRESET, which of them depends on timing): the same event as a clean close.
      if (errno == EPIPE || errno == ECONNRESET)
        throw TransportError(TransportError::Kind::Closed,
                             address() + ": instrument closed the connection (send: " + errno_text() + ")");
      throw TransportError(TransportError::Kind::Io, address() + ": send: " + errno_text());
    }
    off += static_cast<std::size_t>(n);
  }
}

std::size_t TcpTransport::receive(std::uint8_t* buf, std::size_t max, bool* eom) {
  *eom = false;
  for (;;) {
    pollfd p{fd_, POLLIN, 0};
    int pr = ::poll(&p, 1, static_cast<int>(timeout_.count()));
    if (pr == 0)
      throw TransportError(TransportError::Kind::Timeout,
                           address() + ": no reply within " + std::to_string(timeout_.count()) + " ms");
    if (pr < 0) {
      if (errno == EINTR) continue;
      throw TransportError(TransportError::Kind::Io, address() + ": poll: " + errno_text());
    }
    ssize_t n = ::recv(fd_, buf, max, 0);
    if (n == 0)
      throw TransportError(TransportError::Kind::Closed, address() + ": instrument closed the connection");
    if (n < 0) {
      if (errno == EAGAIN || errno == EINTR) continue;
      // A close with unread data in the peer's buffer arrives as a reset rather
      // than EOF (timing decides): the same event, the same words.
      if (errno == ECONNRESET)
        throw TransportError(TransportError::Kind::Closed,
                             address() + ": instrument closed the connection (recv: " + errno_text() + ")");
      throw TransportError(TransportError::Kind::Io, address() + ": recv: " + errno_text());
    }
    return static_cast<std::size_t>(n);
  }
}

void TcpTransport::clear() {
  std::uint8_t buf[4096];
  for (;;) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, 0) != 1) return;
    if (::recv(fd_, buf, sizeof buf, 0) <= 0) return;
  }
}

}  // namespace piezo::drivers

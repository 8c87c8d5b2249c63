#include "drivers/sim/tcp_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "drivers/scpi_parse.hpp"

namespace piezo::drivers::sim {

TcpServer::TcpServer(std::shared_ptr<ScpiDevice> dev, const std::string& host, std::uint16_t port)
    : dev_(std::move(dev)) {
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
  int one = 1;
  ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  if (::inet_pton(AF_INET, host.c_str(), &a.sin_addr) != 1) {
    ::close(listen_fd_);
    throw std::runtime_error("sim-instrument: '" + host + "' is not an IPv4 address");
  }
  if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(listen_fd_, 4) != 0) {
    std::string e = std::strerror(errno);
    ::close(listen_fd_);
    throw std::runtime_error("sim-instrument: cannot listen on " + host + ":" + std::to_string(port) + ": " + e);
  }
  socklen_t len = sizeof a;
  ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&a), &len);
  port_ = ntohs(a.sin_port);
}

TcpServer::~TcpServer() {
  stop();
  if (listen_fd_ >= 0) ::close(listen_fd_);
}

void TcpServer::start() { thread_ = std::thread([this] { serve(); }); }

void TcpServer::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void TcpServer::serve() {
  while (!stop_) {
    pollfd p{listen_fd_, POLLIN, 0};
    if (::poll(&p, 1, 100) != 1) continue;
    int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) continue;
    int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    serve_client(fd);
    ::close(fd);
  }
}

void TcpServer::serve_client(int fd) {
  scpi::InputFramer framer;
  std::uint8_t buf[65536];
  while (!stop_) {
    pollfd p{fd, POLLIN, 0};
    int pr = ::poll(&p, 1, 100);
    if (pr == 0) continue;
    if (pr < 0) return;
    ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) return;
    framer.feed(std::span<const std::uint8_t>(buf, static_cast<std::size_t>(n)));
    while (auto msg = framer.next()) {
      Reply r = dev_->handle(*msg);
      std::size_t off = 0;
      while (off < r.bytes.size()) {
        ssize_t w = ::send(fd, r.bytes.data() + off, r.bytes.size() - off, MSG_NOSIGNAL);
        if (w <= 0) return;
        off += static_cast<std::size_t>(w);
      }
      if (r.close_connection) return;
    }
  }
}

}  // namespace piezo::drivers::sim

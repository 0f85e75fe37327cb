#include "ivoa/core/receive_buffer.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>

#include <charconv>
#include <filesystem>
#include <regex>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/flag_checks.hpp"

namespace ivoa {
namespace {

bool is_udp_socket_on_port(int fd, int port) {
  struct stat st {};
  if (fstat(fd, &st) != 0 || !S_ISSOCK(st.st_mode)) return false;
  int type = 0;
  socklen_t len = sizeof(type);
  if (getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &len) != 0 || type != SOCK_DGRAM) return false;
  sockaddr_in address{};
  len = sizeof(address);
  if (getsockname(fd, reinterpret_cast<sockaddr*>(&address), &len) != 0 || address.sin_family != AF_INET) return false;
  return ntohs(address.sin_port) == port;
}

int receive_buffer(int fd) {
  int bytes = 0;
  socklen_t len = sizeof(bytes);
  getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &bytes, &len);
  return bytes;
}

}  // namespace

int udpm_port(const std::string& url) {
  static const std::regex udpm(R"(udpm://[^:/?]*(:(\d+))?.*)");
  std::smatch m;
  if (!std::regex_match(url, m, udpm)) return 0;
  if (!m[2].matched) return 7667;
  // from_chars, not stoi: a port too long for an int must not throw here.
  const std::string digits = m[2].str();
  int port = 0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), port);
  const bool valid = error == std::errc() && end == digits.data() + digits.size() && port > 0 && port <= 65535;
  return valid ? port : 0;
}

ReceiveBufferResult force_receive_buffer(int port, int bytes) {
  ReceiveBufferResult result;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd", error)) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    const int fd = std::stoi(name);
    if (!is_udp_socket_on_port(fd, port)) continue;
    ++result.sockets;
    // The kernel books twice the size set, so compare against 2 * bytes.
    if (receive_buffer(fd) < 2 * static_cast<int64_t>(bytes) &&
        setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &bytes, sizeof(bytes)) != 0)
      setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof(bytes));  // capped at net.core.rmem_max
    result.bytes = receive_buffer(fd);
    result.as_asked = result.bytes >= 2 * static_cast<int64_t>(bytes);
  }
  return result;
}

void add_socket_buffer_option(CLI::App& app, double& mb) {
  app.add_option("--socket-buffer-mb", mb,
                 "kernel receive buffer for LCM's udpm socket, past net.core.rmem_max where permitted "
                 "(CAP_NET_ADMIN); 0 = as LCM sets it")
      ->capture_default_str()
      ->check(ivoa::number_in(0.0, 1000.0));  // the kernel takes an int of bytes, and books twice that
}

void enlarge_receive_buffer(Bus& bus, double mb) {
  const int port = udpm_port(bus.url());
  if (port == 0 || mb <= 0) return;
  bus.handle(0);  // udpm joins the multicast group (and opens its socket) on the first handle
  const ReceiveBufferResult r = force_receive_buffer(port, static_cast<int>(mb * 1e6));
  if (r.sockets == 0) spdlog::warn("found no UDP socket on port {} to enlarge its receive buffer", port);
  else if (r.as_asked)
    spdlog::info("kernel receive buffer of LCM's socket: {:.0f} MB ({:.0f} MB as the kernel books it)", mb,
                 r.bytes / 1e6);
  else
    spdlog::warn(
        "kernel receive buffer of LCM's socket is {:.0f} MB as the kernel books it, less than the {:.0f} MB "
        "asked: raise net.core.rmem_max, or give the process CAP_NET_ADMIN; kept off the CPU for long, it "
        "can lose images in the kernel",
        r.bytes / 1e6, mb);
}

}  // namespace ivoa

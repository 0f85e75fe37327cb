#pragma once
// A bigger kernel receive buffer for LCM's multicast socket than LCM can
// get. LCM 1.3.1 asks for recv_buf_size with SO_RCVBUF, which the kernel
// caps at net.core.rmem_max (4 MB on a stock host, 8 MB effective): at
// 120 MB/s of images that is ~65 ms of traffic, and a process kept off the
// CPU longer than that (a busy 2-core robot) loses whole images in the
// kernel before LCM sees them: the logger, and every process that takes
// images (the detector, monitor and introspection count such losses as
// frames_missed). This finds LCM's socket among the process's
// descriptors (the UDP socket bound to the URL's port) and enlarges it:
// past rmem_max with SO_RCVBUFFORCE where that is permitted
// (CAP_NET_ADMIN), else up to rmem_max. It never shrinks the buffer.
#include <string>

namespace CLI {
class App;
}

namespace ivoa {
class Bus;

struct ReceiveBufferResult {
  int sockets = 0;        // UDP sockets found on the port
  int bytes = 0;          // the kernel's buffer size afterwards (it books double what was asked)
  bool as_asked = false;  // the buffer is at least the size asked for
};

// The port of a udpm:// URL (LCM's default 7667 if it names none); 0 for other URLs
// and for a port outside 1-65535.
int udpm_port(const std::string& url);

ReceiveBufferResult force_receive_buffer(int port, int bytes);

// What the logger and the image-taking processes ask for: at 120 MB/s of
// images about half a second off the CPU.
inline constexpr double kDefaultSocketBufferMb = 64;

// --socket-buffer-mb (default: `mb`), for the processes that take images.
void add_socket_buffer_option(CLI::App& app, double& mb);

// Gives the socket of `bus` (udpm only; it opens on the first handle, which
// this does) `mb` MB, and says what it got.
void enlarge_receive_buffer(Bus& bus, double mb);

}  // namespace ivoa

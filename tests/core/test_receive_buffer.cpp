// Enlarging LCM's socket buffer: the port comes from the URL, and the
// socket bound to it gets the size asked for where that is permitted,
// and is never made smaller.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include "ivoa/core/receive_buffer.hpp"

namespace ivoa {
namespace {

// A UDP socket on a free loopback port, as LCM's receive socket would be.
struct BoundSocket {
  int fd = socket(AF_INET, SOCK_DGRAM, 0);
  int port = 0;
  BoundSocket() {
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address));
    socklen_t len = sizeof(address);
    getsockname(fd, reinterpret_cast<sockaddr*>(&address), &len);
    port = ntohs(address.sin_port);
  }
  ~BoundSocket() { close(fd); }
  int buffer() const {
    int bytes = 0;
    socklen_t len = sizeof(bytes);
    getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &bytes, &len);
    return bytes;
  }
};

TEST(ReceiveBuffer, PortComesFromTheUdpmUrl) {
  EXPECT_EQ(udpm_port("udpm://239.255.76.67:7671?ttl=0&recv_buf_size=16777216"), 7671);
  EXPECT_EQ(udpm_port("udpm://239.255.76.67"), 7667);
  EXPECT_EQ(udpm_port("memq://"), 0);
  EXPECT_EQ(udpm_port("file:///tmp/x.lcmlog?speed=0"), 0);
  EXPECT_EQ(udpm_port("udpm://239.255.76.67:99999999999999999999"), 0);
  EXPECT_EQ(udpm_port("udpm://239.255.76.67:70000"), 0);
  EXPECT_EQ(udpm_port("udpm://239.255.76.67:0"), 0);
}

TEST(ReceiveBuffer, TheSocketOnThePortGetsTheSizeWherePermitted) {
  BoundSocket s;
  ASSERT_GT(s.port, 0);
  const ReceiveBufferResult r = force_receive_buffer(s.port, 32'000'000);
  EXPECT_EQ(r.sockets, 1);
  EXPECT_EQ(r.bytes, s.buffer());
  if (!r.as_asked) GTEST_SKIP() << "no CAP_NET_ADMIN and a small net.core.rmem_max here: buffer " << r.bytes;
  EXPECT_GE(s.buffer(), 64'000'000);  // the kernel books double
}

TEST(ReceiveBuffer, ABufferAlreadyLargerIsLeftAlone) {
  BoundSocket s;
  const int before = s.buffer();
  const ReceiveBufferResult r = force_receive_buffer(s.port, before / 4);
  EXPECT_EQ(s.buffer(), before);
  EXPECT_TRUE(r.as_asked);
}

}  // namespace
}  // namespace ivoa

// Enlarging LCM's socket buffer: the port comes from the URL, and the
// socket bound to it gets the size asked for where that is permitted.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include "ivoa/logger/receive_buffer.hpp"

namespace ivoa::logger {
namespace {

TEST(ReceiveBuffer, PortComesFromTheUdpmUrl) {
  EXPECT_EQ(udpm_port("udpm://239.255.76.67:7671?ttl=0&recv_buf_size=16777216"), 7671);
  EXPECT_EQ(udpm_port("udpm://239.255.76.67"), 7667);
  EXPECT_EQ(udpm_port("memq://"), 0);
  EXPECT_EQ(udpm_port("file:///tmp/x.lcmlog?speed=0"), 0);
}

TEST(ReceiveBuffer, TheSocketOnThePortGetsTheSizeWherePermitted) {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0);
  socklen_t len = sizeof(address);
  getsockname(fd, reinterpret_cast<sockaddr*>(&address), &len);
  const int port = ntohs(address.sin_port);

  const ReceiveBufferResult r = force_receive_buffer(port, 32'000'000);
  EXPECT_EQ(r.sockets, 1);
  int bytes = 0;
  len = sizeof(bytes);
  getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &bytes, &len);
  close(fd);
  EXPECT_EQ(r.bytes, bytes);
  if (!r.permitted) GTEST_SKIP() << "no CAP_NET_ADMIN here: SO_RCVBUFFORCE refused";
  EXPECT_GE(bytes, 32'000'000);
}

}  // namespace
}  // namespace ivoa::logger

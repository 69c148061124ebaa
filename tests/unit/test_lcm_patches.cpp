// The project's patches to LCM 1.3.1 (third_party/lcm/patches), each by the
// datagrams it is about: a real udpm (or mpudpm) receiver of the patched
// liblcm, in a private network namespace of this test process (root), fed
// crafted datagrams from raw sockets. Each test fails (or crashes) without
// its patch.
// After the datagrams under test, a message on another channel is sent from
// the same socket; once it has arrived, everything sent before it has been
// handled by the receiver (datagrams of one socket arrive in order on loopback).
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <netinet/in.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "tests/support.hpp"

namespace afford {
namespace {

using Bytes = std::vector<std::uint8_t>;
constexpr int kPort = 7471;
constexpr std::uint32_t kShort = 0x4c433032, kLong = 0x4c433033;

void put32(Bytes& b, std::uint32_t v) {
  for (int i = 3; i >= 0; --i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void put16(Bytes& b, std::uint16_t v) {
  b.push_back(static_cast<std::uint8_t>(v >> 8));
  b.push_back(static_cast<std::uint8_t>(v));
}
Bytes pattern(std::size_t n, std::uint8_t seed) {
  Bytes b(n);
  for (std::size_t i = 0; i < n; ++i) b[i] = static_cast<std::uint8_t>(seed + i * 7);
  return b;
}

// A fragment datagram; `channel` only in fragment 0.
Bytes fragment(std::uint32_t seqno, std::uint32_t size, std::uint32_t offset, std::uint16_t no, std::uint16_t count,
               const std::string& channel, const Bytes& payload) {
  Bytes b;
  put32(b, kLong);
  put32(b, seqno);
  put32(b, size);
  put32(b, offset);
  put16(b, no);
  put16(b, count);
  if (no == 0) {
    b.insert(b.end(), channel.begin(), channel.end());
    b.push_back(0);
  }
  b.insert(b.end(), payload.begin(), payload.end());
  return b;
}

// One sender: a socket of its own (LCM reassembles per sender address).
class Sender {
 public:
  Sender() {
    fd_ = socket(AF_INET, SOCK_DGRAM, 0);
    const unsigned char ttl = 0, loop = 1;
    setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl);
    setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop);
    to_.sin_family = AF_INET;
    to_.sin_port = htons(kPort);
    inet_pton(AF_INET, "239.255.76.67", &to_.sin_addr);
  }
  ~Sender() { close(fd_); }
  void send(const Bytes& b) {
    ASSERT_EQ(sendto(fd_, b.data(), b.size(), 0, reinterpret_cast<const sockaddr*>(&to_), sizeof to_),
              static_cast<ssize_t>(b.size()));
  }
  // A whole message in fragments of at most `per` payload bytes, as an LCM sender cuts it.
  void sendFragmented(std::uint32_t seqno, const std::string& channel, const Bytes& data, std::uint32_t per = 60000) {
    const std::uint32_t first = per - static_cast<std::uint32_t>(channel.size() + 1);
    const auto count = static_cast<std::uint16_t>(1 + (data.size() - first + per - 1) / per);
    std::uint32_t offset = 0;
    for (std::uint16_t no = 0; no < count; ++no) {
      const std::uint32_t len = std::min<std::uint32_t>(no == 0 ? first : per, static_cast<std::uint32_t>(data.size()) - offset);
      send(fragment(seqno, static_cast<std::uint32_t>(data.size()), offset, no, count, channel,
                    Bytes(data.begin() + offset, data.begin() + offset + len)));
      offset += len;
    }
  }
  void sendShort(const std::string& channel, const Bytes& payload, bool terminate = true) {
    Bytes b;
    put32(b, kShort);
    put32(b, seqno_++);
    b.insert(b.end(), channel.begin(), channel.end());
    if (terminate) b.push_back(0);
    b.insert(b.end(), payload.begin(), payload.end());
    send(b);
  }

 private:
  int fd_ = -1;
  sockaddr_in to_{};
  std::uint32_t seqno_ = 1;
};

class LcmPatches : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // A network namespace of this process's own: loopback with a multicast route, nothing leaves it.
    ASSERT_EQ(unshare(CLONE_NEWNET), 0) << "unshare(CLONE_NEWNET) needs root: " << std::strerror(errno);
    ASSERT_EQ(std::system("ip link set lo up multicast on && ip route add 224.0.0.0/4 dev lo"), 0);
  }

  // A receiver of the patched liblcm on `options`, taking channels BAD and SYNC.
  void listen(const std::string& options) {
    lcm_ = std::make_unique<lcm::LCM>("udpm://239.255.76.67:" + std::to_string(kPort) + "?ttl=0" + options);
    ASSERT_TRUE(lcm_->good());
    lcm_->subscribe("BAD", &LcmPatches::onBad, this);
    lcm_->subscribe("SYNC", &LcmPatches::onSync, this);
  }
  void onBad(const lcm::ReceiveBuffer* rb, const std::string&) {
    const auto* d = static_cast<const std::uint8_t*>(rb->data);
    bad_.emplace_back(d, d + rb->data_size);
  }
  void onSync(const lcm::ReceiveBuffer* rb, const std::string&) {
    if (rb->data_size == 4) synced_ = static_cast<const std::uint8_t*>(rb->data)[3];
  }
  // Everything `s` sent so far has been handled once its SYNC message has come back.
  void sync(Sender& s) {
    const std::uint8_t mark = ++mark_;
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    // Said again while unheard: a full socket buffer may have dropped it (recovery from loss only).
    while (synced_ != mark && std::chrono::steady_clock::now() < until) {
      s.sendShort("SYNC", {0, 0, 0, mark});
      lcm_->handleTimeout(100);
    }
    ASSERT_EQ(synced_, mark) << "the receiver did not hear the SYNC message (did its receive thread die?)";
    while (lcm_->handleTimeout(0) > 0) {
    }
  }

  std::unique_ptr<lcm::LCM> lcm_;
  std::vector<Bytes> bad_;
  std::uint8_t mark_ = 0, synced_ = 0;
};

// Until LCM's receive thread has read every datagram waiting at port kPort (the kernel's receive queue of
// its socket, /proc/net/udp, is empty); false after 10 s. Datagrams of one socket are read in order, so
// once the last one sent is read, every one before it has been handled by the receive thread.
bool receiveQueueDrained() {
  char port[8];
  std::snprintf(port, sizeof port, ":%04X", kPort);
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < until) {
    std::ifstream in("/proc/net/udp");
    bool waiting = false;
    for (std::string line; std::getline(in, line);) {
      std::istringstream fields(line);
      std::string sl, local, remote, st, queues;
      fields >> sl >> local >> remote >> st >> queues;
      if (local.size() > 5 && local.substr(local.size() - 5) == port && queues.size() == 17)
        waiting = waiting || std::stoul(queues.substr(9), nullptr, 16) > 0;  // tx_queue:rx_queue, in hex
    }
    if (!waiting) return true;
    std::this_thread::yield();
  }
  return false;
}

long residentKb() {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

// 0001: LCM 1.3.1 copied ~4 GB here (upstream issue 628) and the receive thread died.
TEST_F(LcmPatches, AFragmentShorterThanItsHeaderIsDroppedAfterAFirstFragment) {
  listen("");
  Sender s;
  for (std::size_t n : {8, 12, 16, 19}) {
    s.send(fragment(9, 200000, 0, 0, 4, "BAD", pattern(1000, 1)));
    Bytes b = fragment(9, 200000, 1000, 1, 4, "", {});  // an offset that makes the wrapped size pass
    b.resize(n);
    s.send(b);
  }
  sync(s);
  EXPECT_TRUE(bad_.empty());
}

// 0001: a channel name running to the datagram's end made the payload size negative.
TEST_F(LcmPatches, AChannelNameThatDoesNotEndInTheDatagramIsDropped) {
  listen("");
  Sender s;
  // A dropped datagram's buffer is received into again: zeros after "BAD" would end the name there.
  s.sendShort("ZZ", Bytes(2000, 0));
  s.sendShort("BAD", {}, /*terminate=*/false);
  Bytes first = fragment(3, 100000, 0, 0, 2, "BAD", {});
  first.pop_back();  // no terminating zero
  s.send(first);
  sync(s);
  EXPECT_TRUE(bad_.empty());
}

// 0002: an offset near 4 GB wrapped the 32-bit range check.
TEST_F(LcmPatches, AFragmentWhoseOffsetWrapsIsDropped) {
  listen("");
  Sender s;
  s.send(fragment(5, 200000, 0, 0, 4, "BAD", pattern(1000, 2)));
  s.send(fragment(5, 200000, 0xFFFFFFF0u, 1, 4, "", pattern(3000, 3)));
  s.send(fragment(6, 200000, 0, 0, 0, "BAD", pattern(100, 4)));     // zero fragments
  s.send(fragment(7, 200000, 0, 9, 4, "", pattern(100, 5)));        // a fragment number beyond the count
  sync(s);
  EXPECT_TRUE(bad_.empty());
}

// 0003: a fragment taken twice made a message complete with another missing.
TEST_F(LcmPatches, EachFragmentCountsOnceAndOverlapsAreDropped) {
  listen("");
  Sender s;
  const Bytes data = pattern(150000, 6);
  const std::uint32_t first = 60000 - 4;
  s.send(fragment(11, 150000, 0, 0, 3, "BAD", Bytes(data.begin(), data.begin() + first)));
  const Bytes second(data.begin() + first, data.begin() + first + 60000);
  s.send(fragment(11, 150000, first, 1, 3, "", second));
  s.send(fragment(11, 150000, first, 1, 3, "", second));  // again
  sync(s);
  EXPECT_TRUE(bad_.empty()) << "completed without its third fragment";
  s.send(fragment(11, 150000, first + 60000, 2, 3, "", Bytes(data.begin() + first + 60000, data.end())));
  sync(s);
  ASSERT_EQ(bad_.size(), 1u);
  EXPECT_EQ(bad_[0], data);

  // Every fragment once, but one overlapping another (their sizes add up to more than the
  // message), or one short (less): the message is not passed on with bytes it never got.
  const Bytes third(data.begin() + first + 60000, data.end());
  s.send(fragment(12, 150000, 0, 0, 3, "BAD", Bytes(data.begin(), data.begin() + first)));
  s.send(fragment(12, 150000, first - 1000, 1, 3, "", Bytes(data.begin() + first - 1000, data.begin() + first + 60000)));
  s.send(fragment(12, 150000, first + 60000, 2, 3, "", third));
  s.send(fragment(13, 150000, 0, 0, 3, "BAD", Bytes(data.begin(), data.begin() + first)));
  s.send(fragment(13, 150000, first, 1, 3, "", Bytes(second.begin(), second.end() - 1000)));
  s.send(fragment(13, 150000, first + 60000, 2, 3, "", third));
  sync(s);
  EXPECT_EQ(bad_.size(), 1u) << "a message whose fragments overlap or leave a gap was passed on";
}

// 0005: the store's bounds hold with the new message in it.
TEST_F(LcmPatches, IncompleteMessagesHoldAtMostTheFragmentBufferTogether) {
  listen("&max_message_size=100000&fragment_buffer_size=150000");
  Sender a, b;
  const Bytes data = pattern(100000, 7);
  const std::uint32_t first = 60000 - 4;
  a.send(fragment(1, 100000, 0, 0, 2, "BAD", Bytes(data.begin(), data.begin() + first)));
  b.send(fragment(1, 100000, 0, 0, 2, "BAD", Bytes(data.begin(), data.begin() + first)));  // evicts a's
  a.send(fragment(1, 100000, first, 1, 2, "", Bytes(data.begin() + first, data.end())));
  b.send(fragment(1, 100000, first, 1, 2, "", Bytes(data.begin() + first, data.end())));
  sync(a);
  sync(b);
  ASSERT_EQ(bad_.size(), 1u) << "both incomplete messages were kept, beyond fragment_buffer_size";
  EXPECT_EQ(bad_[0], data);
}

// 0005: an incomplete message expires after fragment_timeout_ms.
TEST_F(LcmPatches, AnIncompleteMessageExpires) {
  listen("&fragment_timeout_ms=50");
  Sender s;
  const Bytes data = pattern(100000, 8);
  const std::uint32_t first = 60000 - 4;
  s.send(fragment(2, 100000, 0, 0, 2, "BAD", Bytes(data.begin(), data.begin() + first)));
  sync(s);
  // The behaviour under test is time itself: the rest arrives well after the timeout.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  s.send(fragment(2, 100000, first, 1, 2, "", Bytes(data.begin() + first, data.end())));
  sync(s);
  EXPECT_TRUE(bad_.empty()) << "a message completed after its first fragment had expired";
}

// 0005: sparse claims of huge messages from many senders stay bounded in memory.
TEST_F(LcmPatches, SparseClaimsOfHugeMessagesStayWithinTheFragmentBuffer) {
  listen("&fragment_buffer_size=2097152&max_message_size=1048576");
  std::vector<std::unique_ptr<Sender>> senders;
  for (int i = 0; i < 64; ++i) senders.push_back(std::make_unique<Sender>());
  sync(*senders[0]);
  const long before = residentKb();
  for (int round = 0; round < 4; ++round)
    for (auto& s : senders) {
      const std::uint32_t size = 1040000;
      s->send(fragment(static_cast<std::uint32_t>(round), size, 0, 0, 17, "BAD", pattern(100, 9)));
      for (std::uint32_t k = 1; k < 17; ++k)
        s->send(fragment(static_cast<std::uint32_t>(round), size, k * 61000, static_cast<std::uint16_t>(k), 17, "", {1}));
      sync(*s);  // each sender's datagrams handled before the next one's (the socket buffer holds a few hundred)
    }
  const long grown = residentKb() - before;
  // The store holds 2 MB; twice that leaves room for the receive buffers' own growth.
  EXPECT_LT(grown, 4 * 1024) << "64 senders' incomplete 1 MB messages made the receiver " << grown << " kB larger";
  EXPECT_TRUE(bad_.empty());
}

// 0004: a message of a size the process cannot allocate is dropped, not written through a null pointer.
// In a child whose address space is capped just above what it uses; the child says how it ended.
TEST_F(LcmPatches, AMessageThatCannotBeAllocatedIsDropped) {
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    close(ready[0]);
    bad_.clear();
    listen("");  // LCM's own 256 MB limit
    std::ifstream in("/proc/self/status");
    long vm_kb = 0;
    for (std::string line; std::getline(in, line);)
      if (line.rfind("VmSize:", 0) == 0) vm_kb = std::stol(line.substr(7));
    rlimit cap{};
    cap.rlim_cur = cap.rlim_max = static_cast<rlim_t>(vm_kb + 96 * 1024) * 1024;  // 96 MB more: no 200 MB block
    if (setrlimit(RLIMIT_AS, &cap) != 0) _exit(3);
    if (write(ready[1], "r", 1) != 1) _exit(3);
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(15);
    while (synced_ == 0 && std::chrono::steady_clock::now() < until) lcm_->handleTimeout(100);
    _exit(synced_ != 0 && bad_.empty() ? 0 : 4);
  }
  close(ready[1]);
  char c = 0;
  ASSERT_EQ(read(ready[0], &c, 1), 1) << "the child did not start listening";
  close(ready[0]);
  Sender s;
  const std::uint32_t size = 200u << 20;
  s.send(fragment(30, size, 0, 0, 4000, "BAD", pattern(1000, 20)));
  s.send(fragment(30, size, 65000, 1, 4000, "", pattern(1000, 21)));
  int status = 0;
  // SYNC, said again while the child has not ended (it ends once it has one): recovery from loss only.
  for (int i = 0; i < 150 && waitpid(child, &status, WNOHANG) == 0; ++i) {
    s.sendShort("SYNC", {0, 0, 0, 1});
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  if (waitpid(child, &status, WNOHANG) == 0) {
    ASSERT_EQ(waitpid(child, &status, 0), child);
  }
  ASSERT_TRUE(WIFEXITED(status)) << "the receiver died of signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  EXPECT_EQ(WEXITSTATUS(status), 0) << "3: could not cap its memory; 4: no SYNC, or the message was passed on";
}

// 0008: the bytes of received messages waiting to be handled are bounded.
TEST_F(LcmPatches, MessagesWaitingToBeHandledHoldAtMostTheReceiveQueue) {
  listen("&receive_queue_size=150000");
  Sender s;
  for (int i = 0; i < 10; ++i) s.sendShort("BAD", pattern(50000, static_cast<std::uint8_t>(i)));
  ASSERT_TRUE(receiveQueueDrained()) << "LCM's receive thread did not read the datagrams";
  sync(s);  // only now handled: what waited, and the SYNC (said again once there is room)
  EXPECT_GE(bad_.size(), 1u);
  EXPECT_LE(bad_.size(), 3u) << "more than 150000 bytes of messages waited to be handled";
}

// 0009: a datagram too short to be LCM made an mpudpm receiver unlock a mutex it did not hold (glib aborts).
TEST_F(LcmPatches, AnMpudpmReceiverLivesThroughDatagramsTooShortOrWithoutMagic) {
  lcm::LCM receiver("mpudpm://239.255.76.67:7480?ttl=0&nports=4");
  ASSERT_TRUE(receiver.good());
  int heard = 0;
  struct Counter {
    int* n;
    void on(const lcm::ReceiveBuffer*, const std::string&) { ++*n; }
  } counter{&heard};
  receiver.subscribe("SYNC", &Counter::on, &counter);
  receiver.handleTimeout(50);
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  const unsigned char ttl = 0;
  setsockopt(fd, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl);
  for (int port = 7480; port < 7484; ++port) {
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(static_cast<std::uint16_t>(port));
    inet_pton(AF_INET, "239.255.76.67", &to.sin_addr);
    for (const Bytes& b : {Bytes{'a', 'b', 'c', 'd'}, Bytes(40, 'x')})  // too short; no magic
      sendto(fd, b.data(), b.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
  }
  close(fd);
  lcm::LCM sender("mpudpm://239.255.76.67:7480?ttl=0&nports=4");
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (heard == 0 && std::chrono::steady_clock::now() < until) {
    const std::uint8_t one = 1;
    sender.publish("SYNC", &one, 1);
    receiver.handleTimeout(100);
  }
  EXPECT_GT(heard, 0) << "the mpudpm receiver stopped receiving";
}

// 0006: max_message_size drops a larger message, short or fragmented.
TEST_F(LcmPatches, AMessageLargerThanMaxMessageSizeIsDropped) {
  listen("&max_message_size=70000");
  Sender s;
  s.sendFragmented(20, "BAD", pattern(69000, 10));
  s.sendFragmented(21, "BAD", pattern(100000, 11));
  sync(s);
  ASSERT_EQ(bad_.size(), 1u);
  EXPECT_EQ(bad_[0].size(), 69000u);
  listen("&max_message_size=1000");
  s.sendShort("BAD", pattern(2000, 12));
  s.sendShort("BAD", pattern(900, 13));
  sync(s);
  ASSERT_EQ(bad_.size(), 2u);
  EXPECT_EQ(bad_[1].size(), 900u);
}

// Datagrams the kernel dropped at this namespace's sockets bound to port kPort (the last column of
// /proc/net/udp): full receive buffers, and since 0010 the socket filter.
long socketDrops() {
  char port[8];
  std::snprintf(port, sizeof port, ":%04X", kPort);
  std::ifstream in("/proc/net/udp");
  long drops = 0;
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    std::vector<std::string> f;
    for (std::string w; fields >> w;) f.push_back(w);
    if (f.size() > 12 && f[1].size() > 5 && f[1].substr(f[1].size() - 5) == port) drops += std::stol(f.back());
  }
  return drops;
}

// Channels a handler took, by name.
struct Taken {
  std::map<std::string, int> by_channel;
  void on(const lcm::ReceiveBuffer*, const std::string& channel) { ++by_channel[channel]; }
};

// 0010: every process on a port was woken for every datagram of the port, and LCM dropped those of
// channels nobody here took only then, in user space. Now the kernel drops them at the socket.
TEST_F(LcmPatches, TheKernelDropsShortMessagesOfChannelsNotSubscribed) {
  listen("");  // BAD and SYNC
  Taken taken;
  // Names of 1 to 9 bytes: the filter compares a name and its NUL in words, half words and bytes.
  for (int n = 1; n <= 9; ++n) lcm_->subscribe(std::string(n, 'K'), &Taken::on, &taken);
  Sender s;
  sync(s);
  const long before = socketDrops();
  for (int n = 1; n <= 9; ++n) {
    s.sendShort(std::string(n, 'K'), pattern(40, 1));                   // taken
    s.sendShort(std::string(n - 1, 'K') + "J", pattern(40, 2));         // last byte differs
    s.sendShort(std::string(n, 'K') + "J", pattern(40, 3));             // one byte longer
    s.sendShort(std::string(n, 'K'), {}, false);                        // no NUL, ends in the name
  }
  for (int i = 0; i < 20; ++i) s.sendShort("OTHER", pattern(100, static_cast<std::uint8_t>(i)));
  s.sendShort("BA", pattern(10, 4));
  s.sendShort("BAD", pattern(10, 5));
  s.sendFragmented(30, "OTHER", pattern(70000, 6));  // fragments pass the kernel; LCM drops the message
  sync(s);
  EXPECT_EQ(socketDrops() - before, 9 * 3 + 20 + 1) << "datagrams of channels not subscribed reached LCM";
  for (int n = 1; n <= 9; ++n) EXPECT_EQ(taken.by_channel[std::string(n, 'K')], 1) << n << " K";
  EXPECT_EQ(taken.by_channel.size(), 9u);
  ASSERT_EQ(bad_.size(), 1u);
  EXPECT_EQ(bad_[0].size(), 10u);
}

// 0010: a subscription by pattern takes every channel, so nothing is dropped while it stands.
TEST_F(LcmPatches, ASubscriptionByPatternTakesEveryChannelUntilItIsGone) {
  listen("");
  Taken all;
  lcm::Subscription* sub = lcm_->subscribe("OTH.*", &Taken::on, &all);
  Sender s;
  sync(s);
  long before = socketDrops();
  for (int i = 0; i < 10; ++i) s.sendShort(i % 2 ? "OTHER" : "ELSE", pattern(20, 1));
  sync(s);
  EXPECT_EQ(socketDrops() - before, 0);
  EXPECT_EQ(all.by_channel["OTHER"], 5);
  EXPECT_EQ(all.by_channel.count("ELSE"), 0u);
  lcm_->unsubscribe(sub);
  before = socketDrops();
  for (int i = 0; i < 10; ++i) s.sendShort(i % 2 ? "OTHER" : "ELSE", pattern(20, 1));
  sync(s);
  EXPECT_EQ(socketDrops() - before, 10) << "the filter did not come back when the pattern went";
  EXPECT_EQ(all.by_channel["OTHER"], 5);
  // A pattern that is not a regular expression is refused, and leaves the filter as it was.
  EXPECT_EQ(lcm_subscribe(lcm_->getUnderlyingLCM(), "OTH[", [](const lcm_recv_buf_t*, const char*, void*) {}, nullptr),
            nullptr);
  before = socketDrops();
  s.sendShort("OTHER", pattern(20, 1));
  sync(s);
  EXPECT_EQ(socketDrops() - before, 1);
}

// The threads of this process, by id.
std::vector<std::string> threadsNow() {
  std::vector<std::string> ids;
  for (const auto& e : std::filesystem::directory_iterator("/proc/self/task")) ids.push_back(e.path().filename());
  std::sort(ids.begin(), ids.end());
  return ids;
}
// How often thread `id` of this process has gone to sleep (its voluntary context switches).
long sleepsOf(const std::string& id) {
  std::ifstream in("/proc/self/task/" + id + "/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("voluntary_ctxt_switches:", 0) == 0) return std::stol(line.substr(24));
  return -1;
}

// 0011: a receiver's receive thread was woken for every datagram of a stream. With receive_batch_ms it
// empties the socket, then waits the period before waiting again: a stream wakes it once per period, and
// every message still arrives.
TEST_F(LcmPatches, AReceiverWithReceiveBatchMsTakesAStreamInBatches) {
  constexpr int kMessages = 200;
  // A receiver without the option paces the stream: each message is sent once it has taken the one before.
  lcm::LCM pace("udpm://239.255.76.67:" + std::to_string(kPort) + "?ttl=0");
  ASSERT_TRUE(pace.good());
  Taken paced;
  pace.subscribe("PACE", &Taken::on, &paced);
  const std::vector<std::string> before = threadsNow();
  constexpr int kPeriodMs = 250;
  listen("&receive_batch_ms=" + std::to_string(kPeriodMs));
  Taken taken;
  lcm_->subscribe("PACE", &Taken::on, &taken)->setQueueCapacity(kMessages);  // a batch is queued at once
  std::vector<std::string> started;
  const std::vector<std::string> after = threadsNow();
  std::set_difference(after.begin(), after.end(), before.begin(), before.end(), std::back_inserter(started));
  ASSERT_EQ(started.size(), 1u) << "the receiver's receive thread";
  Sender s;
  sync(s);
  const long sleeps = sleepsOf(started[0]);
  const auto began = std::chrono::steady_clock::now();
  for (int i = 0; i < kMessages; ++i) {
    s.sendShort("PACE", pattern(30, static_cast<std::uint8_t>(i)));
    while (paced.by_channel["PACE"] == i && pace.handleTimeout(10000) > 0) {
    }
    ASSERT_EQ(paced.by_channel["PACE"], i + 1) << "the pacing receiver did not hear message " << i;
  }
  sync(s);
  const long woken = sleepsOf(started[0]) - sleeps;
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - began);
  EXPECT_EQ(taken.by_channel["PACE"], kMessages);
  // Once per period the stream lasted and the waits of sync(): a handful alone; on a busy machine also the waits
  // for the queue's lock (20-30 seen with both cores taken). Never once per datagram (unpatched: about 208).
  EXPECT_LT(woken, kMessages / 4) << "the receive thread slept " << woken << " times for " << kMessages
                                  << " datagrams in " << ms.count() << " ms";
}

// 0012: a udpm receiver was handed the datagrams of every multicast group that any socket of the host had
// joined on its port (Linux's IP_MULTICAST_ALL): a second bus on the same port with another address was heard
// by every process of the first, which dropped its messages one warning line each.
TEST_F(LcmPatches, AReceiverHearsOnlyItsOwnGroupNotAnotherOnItsPort) {
  listen("");  // 239.255.76.67, BAD and SYNC
  lcm::LCM other("udpm://239.255.76.68:" + std::to_string(kPort) + "?ttl=0");
  ASSERT_TRUE(other.good());
  Taken heard;
  other.subscribe("BAD", &Taken::on, &heard);  // (its socket joins 239.255.76.68 on the port)
  const Bytes message = pattern(40, 3);
  for (int i = 0; i < 5; ++i) {
    other.publish("BAD", message.data(), static_cast<unsigned>(message.size()));
    while (heard.by_channel["BAD"] == i && other.handleTimeout(10000) > 0) {
    }
  }
  ASSERT_EQ(heard.by_channel["BAD"], 5) << "the other bus did not hear itself";
  Sender s;
  ASSERT_TRUE(receiveQueueDrained());
  sync(s);
  EXPECT_TRUE(bad_.empty()) << bad_.size() << " messages of the bus at 239.255.76.68 heard on 239.255.76.67";
}

// 0007: a data length of 0x7FFFFFFF overflowed 'datalen + 1' and the reader wrote through a null pointer.
TEST(LcmEventLog, AnEventClaimingTheLargestLengthIsRefused) {
  const std::string file = test::tempDir("lcm-eventlog") + "/huge.lcm";
  Bytes b;
  put32(b, 0xEDA1DA01u);
  for (int i = 0; i < 16; ++i) b.push_back(0);  // event number, time
  put32(b, 3);
  put32(b, 0x7FFFFFFFu);
  for (char c : std::string("BAD")) b.push_back(static_cast<std::uint8_t>(c));
  b.resize(3000, 0xAB);
  std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
  lcm::LogFile log(file, "r");
  ASSERT_TRUE(log.good());
  EXPECT_EQ(log.readNextEvent(), nullptr);
}

}  // namespace
}  // namespace afford

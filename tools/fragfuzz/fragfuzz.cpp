// afford-fragfuzz: a raw-UDP fuzzer of LCM's datagram layer, for tests
// (tests/fragments). It speaks LCM's UDP multicast packet format itself, with
// no LCM library, and sends --datagrams crafted datagrams to a bus from
// --senders sockets (each one a sender LCM keys its reassembly by):
//
//   short      a first fragment on a channel the processes take, then from the
//              same socket a fragment datagram shorter than the 20-byte header
//              (LCM 1.3.1 wraps the size and copies ~4 GB: upstream issue 628)
//   wrapped    a first fragment, then a fragment whose offset + size wraps 32 bits
//   overlap    every fragment of a message, some sent twice, some overlapping,
//              leaving holes, or claiming another fragment count
//   sparse     first fragments claiming huge messages (up to 4 GB), then a few
//              one-byte fragments spread over them, never completed
//   oversized  first fragments claiming more than the bus's largest message,
//              zero fragments, or a fragment number beyond the count
//   channel    short messages and first fragments whose channel name runs past
//              the datagram's end, or past LCM's 63 bytes
//   junk       random datagrams with either magic, or none
//   complete   whole fragmented messages of random bytes on the run's channels,
//              up to the bus's largest (they reach the edge, which refuses them)
//
// Usage: afford-fragfuzz --group 239.255.76.67 --port 7667 --datagrams 100000
//        [--seed S] [--kinds short,wrapped,...] [--senders 64] [--max-message BYTES] [--rate 20000]
// Sends only to the group given, with multicast TTL 0 (nothing leaves the host).
#include <CLI/CLI.hpp>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "afford/protocol.hpp"

namespace {

constexpr std::uint32_t kMagicShort = 0x4c433032;  // "LC02"
constexpr std::uint32_t kMagicLong = 0x4c433033;   // "LC03"
constexpr std::size_t kLongHeader = 20;
constexpr std::uint32_t kFragmentPayload = 65487;  // LCM's largest fragment payload on Linux

using Bytes = std::vector<std::uint8_t>;

void put32(Bytes& b, std::uint32_t v) {
  for (int i = 3; i >= 0; --i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void put16(Bytes& b, std::uint16_t v) {
  b.push_back(static_cast<std::uint8_t>(v >> 8));
  b.push_back(static_cast<std::uint8_t>(v));
}

struct Fragment {
  std::uint32_t seqno = 0, msg_size = 0, offset = 0;
  std::uint16_t number = 0, count = 1;
};
// A fragment datagram: header, for fragment 0 the channel and its NUL, then payload.
Bytes fragment(const Fragment& f, const std::string& channel, const Bytes& payload, bool terminate = true) {
  Bytes b;
  put32(b, kMagicLong);
  put32(b, f.seqno);
  put32(b, f.msg_size);
  put32(b, f.offset);
  put16(b, f.number);
  put16(b, f.count);
  if (f.number == 0) {
    b.insert(b.end(), channel.begin(), channel.end());
    if (terminate) b.push_back(0);
  }
  b.insert(b.end(), payload.begin(), payload.end());
  return b;
}
Bytes shortMessage(std::uint32_t seqno, const std::string& channel, const Bytes& payload, bool terminate = true) {
  Bytes b;
  put32(b, kMagicShort);
  put32(b, seqno);
  b.insert(b.end(), channel.begin(), channel.end());
  if (terminate) b.push_back(0);
  b.insert(b.end(), payload.begin(), payload.end());
  return b;
}

class Fuzzer {
 public:
  Fuzzer(const std::string& group, int port, int senders, std::uint64_t seed, std::uint32_t max_message, double rate)
      : rng_(seed), max_message_(max_message), rate_(rate) {
    std::memset(&dest_, 0, sizeof dest_);
    dest_.sin_family = AF_INET;
    dest_.sin_port = htons(static_cast<std::uint16_t>(port));
    if (inet_pton(AF_INET, group.c_str(), &dest_.sin_addr) != 1) throw std::runtime_error("--group: not an IPv4 address");
    if ((ntohl(dest_.sin_addr.s_addr) >> 28) != 0xE) throw std::runtime_error("--group: not a multicast address");
    for (int i = 0; i < senders; ++i) {
      const int fd = socket(AF_INET, SOCK_DGRAM, 0);
      if (fd < 0) throw std::runtime_error("socket: " + std::string(std::strerror(errno)));
      const unsigned char ttl = 0, loop = 1;  // never beyond this host
      setsockopt(fd, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl);
      setsockopt(fd, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop);
      const int sndbuf = 4 << 20;
      setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &sndbuf, sizeof sndbuf);
      sockets_.push_back(fd);
    }
    channels_ = afford::channelNames();
  }
  ~Fuzzer() {
    for (int fd : sockets_) close(fd);
  }

  void run(const std::vector<std::string>& kinds, long datagrams) {
    while (sent_ < datagrams) {
      const std::string& kind = kinds[pick(kinds.size())];
      const long before = sent_;
      if (kind == "short") shortFragment();
      else if (kind == "wrapped") wrapped();
      else if (kind == "overlap") overlap();
      else if (kind == "sparse") sparse();
      else if (kind == "oversized") oversized();
      else if (kind == "channel") badChannel();
      else if (kind == "junk") junk();
      else if (kind == "complete") complete();
      by_kind_[kind] += sent_ - before;
    }
  }
  void report() const {
    std::printf("afford-fragfuzz: %ld datagrams sent (%ld failed sends) from %zu senders:", sent_, failed_,
                sockets_.size());
    for (const auto& [k, n] : by_kind_) std::printf(" %s %ld", k.c_str(), n);
    std::printf("\n");
  }

 private:
  std::size_t pick(std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(rng_()); }
  int sender() { return sockets_[pick(sockets_.size())]; }
  const std::string& channel() { return channels_[pick(channels_.size())]; }
  Bytes random(std::size_t n) {
    Bytes b(n);
    for (auto& x : b) x = static_cast<std::uint8_t>(rng_());
    return b;
  }
  void send(int fd, const Bytes& b) {
    ++sent_;
    if (sendto(fd, b.data(), b.size(), 0, reinterpret_cast<const sockaddr*>(&dest_), sizeof dest_) < 0) {
      ++failed_;
      if (errno == ENOBUFS || errno == EAGAIN) usleep(200);  // the host's queues are full: let them drain
    }
    // Paced at --rate: the datagrams are to reach the receivers, not the kernel's drop counters.
    if (sent_ % 64 == 0) {
      const auto due = start_ + std::chrono::duration<double>(static_cast<double>(sent_) / rate_);
      std::this_thread::sleep_until(due);
    }
  }
  // A first fragment of a message of `size` bytes in `count` fragments.
  Fragment first(std::uint32_t size, std::uint16_t count) {
    Fragment f;
    f.seqno = u32();
    f.msg_size = size;
    f.count = count;
    return f;
  }

  void shortFragment() {
    const int fd = sender();
    Fragment f = first(200000, 4);
    send(fd, fragment(f, channel(), random(1000)));
    f.number = static_cast<std::uint16_t>(1 + pick(3));
    f.offset = static_cast<std::uint32_t>(pick(200000));
    Bytes b = fragment(f, "", random(0));
    b.resize(pick(kLongHeader));  // 0..19 bytes: shorter than the header
    if (b.size() < 4) b = {0x4c, 0x43, 0x30, 0x33};
    send(fd, b);
  }
  void wrapped() {
    const int fd = sender();
    Fragment f = first(200000, 4);
    send(fd, fragment(f, channel(), random(500)));
    f.number = static_cast<std::uint16_t>(1 + pick(3));
    f.offset = 0xFFFFFFFFu - static_cast<std::uint32_t>(pick(2000));
    send(fd, fragment(f, "", random(1 + pick(3000))));
  }
  void overlap() {
    const int fd = sender();
    const std::uint16_t count = static_cast<std::uint16_t>(2 + pick(6));
    const std::uint32_t size = static_cast<std::uint32_t>(count) * 1000;
    Fragment f = first(size, count);
    const std::string ch = channel();
    send(fd, fragment(f, ch, random(1000 - ch.size() - 1)));
    for (std::uint16_t n = 1; n < count; ++n) {
      Fragment g = f;
      g.number = n;
      g.offset = n * 1000 - static_cast<std::uint32_t>(pick(3) == 0 ? pick(900) : 0);  // sometimes overlapping
      if (pick(5) == 0) g.count = static_cast<std::uint16_t>(count + 1);                // another count
      const int times = pick(4) == 0 ? 2 : 1;                                          // sometimes twice
      for (int t = 0; t < times; ++t) send(fd, fragment(g, "", random(pick(6) == 0 ? 400 : 1000)));
    }
  }
  void sparse() {
    const int fd = sender();
    const std::uint32_t sizes[] = {max_message_ + 1, 1u << 20, 16u << 20, 256u << 20, 0xFFFFFFFFu,
                                   static_cast<std::uint32_t>(max_message_ / 2 + pick(max_message_ / 2))};
    const std::uint32_t size = sizes[pick(std::size(sizes))];
    const std::uint16_t count = static_cast<std::uint16_t>(std::min<std::uint64_t>(65535, size / kFragmentPayload + 1));
    Fragment f = first(size, count);
    send(fd, fragment(f, channel(), random(64)));
    const int n = 1 + static_cast<int>(pick(16));
    for (int i = 0; i < n; ++i) {
      Fragment g = f;
      g.number = static_cast<std::uint16_t>(1 + pick(std::max<std::size_t>(1, count - 1)));
      g.offset = static_cast<std::uint32_t>(pick(size));
      send(fd, fragment(g, "", random(1)));
    }
  }
  void oversized() {
    const int fd = sender();
    Fragment f = first(max_message_ + 1 + static_cast<std::uint32_t>(pick(1 << 20)), 40);
    switch (pick(3)) {
      case 0: break;
      case 1: f.count = 0; break;
      default: f.number = static_cast<std::uint16_t>(f.count + pick(100)); f.offset = 0; break;
    }
    send(fd, fragment(f, channel(), random(100)));
  }
  void badChannel() {
    const int fd = sender();
    const std::string ch = pick(2) ? std::string(64 + pick(200), 'C') : channel();
    if (pick(2)) {
      send(fd, shortMessage(u32(), ch, {}, /*terminate=*/false));  // the name runs to the datagram's end
    } else {
      Fragment f = first(100000, 2);
      send(fd, fragment(f, ch, {}, /*terminate=*/pick(2) == 0));
    }
  }
  void junk() {
    Bytes b = random(pick(4) == 0 ? pick(65000) : pick(64));
    if (b.size() >= 4 && pick(3)) {
      const std::uint32_t m = pick(2) ? kMagicShort : kMagicLong;
      for (int i = 0; i < 4; ++i) b[i] = static_cast<std::uint8_t>(m >> (8 * (3 - i)));
    }
    send(sender(), b);
  }
  void complete() {
    const int fd = sender();
    const std::string ch = channel();
    // Up to the bus's largest message: whole ones reach the subscribers' queues (bounded by protocol.bus.queue_bytes).
    const std::uint32_t size = pick(2) ? 70000 + static_cast<std::uint32_t>(pick(60000))
                                       : static_cast<std::uint32_t>(pick(max_message_ - 1000)) + 1000;
    const Bytes body = random(size);
    const std::uint16_t count = static_cast<std::uint16_t>((size + ch.size() + 1 + kFragmentPayload - 1) / kFragmentPayload);
    Fragment f = first(size, count);
    std::uint32_t offset = 0;
    for (std::uint16_t n = 0; n < count; ++n) {
      f.number = n;
      f.offset = offset;
      const std::uint32_t room = n == 0 ? kFragmentPayload - static_cast<std::uint32_t>(ch.size() + 1) : kFragmentPayload;
      const std::uint32_t len = std::min(room, size - offset);
      send(fd, fragment(f, ch, Bytes(body.begin() + offset, body.begin() + offset + len)));
      offset += len;
    }
  }

  std::mt19937_64 rng_;
  std::uint32_t max_message_;
  double rate_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  sockaddr_in dest_{};
  std::vector<int> sockets_;
  std::vector<std::string> channels_;
  long sent_ = 0, failed_ = 0;
  std::map<std::string, long> by_kind_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"afford-fragfuzz: crafted LCM datagrams (fragments above all) sent to a bus, for tests",
               "afford-fragfuzz"};
  std::string group = "239.255.76.67", kinds_text = "short,wrapped,overlap,sparse,oversized,channel,junk,complete";
  int port = 7667, senders = 64;
  long datagrams = 100000;
  std::uint64_t seed = 1;
  std::uint32_t max_message = 1 << 20;
  double rate = 20000;
  app.add_option("--group", group, "multicast group of the bus")->capture_default_str();
  app.add_option("--port", port, "UDP port of the bus")->capture_default_str()->check(CLI::Range(1, 65535));
  app.add_option("--datagrams", datagrams, "how many datagrams to send")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--seed", seed, "seed of the datagrams")->capture_default_str();
  app.add_option("--kinds", kinds_text, "comma-separated kinds (see the file comment)")->capture_default_str();
  app.add_option("--senders", senders, "sockets to send from")->capture_default_str()->check(CLI::Range(1, 1000));
  app.add_option("--max-message", max_message, "the bus's largest message (protocol.bus.max_message_bytes)")
      ->capture_default_str()->check(CLI::Range(1024u, 1u << 30));
  app.add_option("--rate", rate, "datagrams per second")->capture_default_str()->check(CLI::Range(1.0, 1e7));
  CLI11_PARSE(app, argc, argv);
  const std::vector<std::string> known = {"short",     "wrapped", "overlap", "sparse",
                                          "oversized", "channel", "junk",    "complete"};
  std::vector<std::string> kinds;
  std::stringstream in(kinds_text);
  for (std::string k; std::getline(in, k, ',');) {
    if (std::find(known.begin(), known.end(), k) == known.end()) {
      std::fprintf(stderr, "afford-fragfuzz: --kinds: unknown kind '%s'\n", k.c_str());
      return 2;
    }
    kinds.push_back(k);
  }
  if (kinds.empty()) {
    std::fprintf(stderr, "afford-fragfuzz: --kinds: none given\n");
    return 2;
  }
  try {
    Fuzzer f(group, port, senders, seed, max_message, rate);
    f.run(kinds, datagrams);
    f.report();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "afford-fragfuzz: %s\n", e.what());
    return 1;
  }
  return 0;
}

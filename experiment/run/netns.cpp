#include "experiment/run/netns.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <net/if.h>
#include <net/route.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace afford {

nlohmann::json out(const NetnsMode& m) { return m == NetnsMode::On ? "on" : m == NetnsMode::Off ? "off" : "auto"; }

void in(const nlohmann::json& j, const std::string& path, const codec::Context& c, NetnsMode& m) {
  const std::string s = j.is_string() ? j.get<std::string>() : std::string();
  if (s == "auto" || s == "on" || s == "off")
    m = s == "on" ? NetnsMode::On : s == "off" ? NetnsMode::Off : NetnsMode::Auto;
  else
    c.fail(path, "expected \"auto\", \"on\" or \"off\", got " + (j.is_string() ? "\"" + s + "\"" : codec::kindOf(j)));
}
namespace {

void writeFile(const std::string& path, const std::string& text) {
  std::ofstream f(path);
  f << text;
}

void setUpLoopback() {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, "lo", IFNAMSIZ - 1);
  if (ioctl(fd, SIOCGIFFLAGS, &ifr) < 0) {
    close(fd);
    throw std::runtime_error(std::string("cannot read loopback flags: ") + std::strerror(errno));
  }
  ifr.ifr_flags |= IFF_UP | IFF_MULTICAST;
  if (ioctl(fd, SIOCSIFFLAGS, &ifr) < 0) {
    close(fd);
    throw std::runtime_error(std::string("cannot bring loopback up: ") + std::strerror(errno));
  }
  rtentry rt{};
  auto* dst = reinterpret_cast<sockaddr_in*>(&rt.rt_dst);
  dst->sin_family = AF_INET;
  dst->sin_addr.s_addr = inet_addr("224.0.0.0");
  auto* mask = reinterpret_cast<sockaddr_in*>(&rt.rt_genmask);
  mask->sin_family = AF_INET;
  mask->sin_addr.s_addr = inet_addr("240.0.0.0");
  rt.rt_flags = RTF_UP;
  char dev[] = "lo";
  rt.rt_dev = dev;
  if (ioctl(fd, SIOCADDRT, &rt) < 0 && errno != EEXIST) {
    close(fd);
    throw std::runtime_error(std::string("cannot add the multicast route on loopback: ") + std::strerror(errno));
  }
  close(fd);
}

bool enterPrivateNamespace(std::string& why) {
  if (unshare(CLONE_NEWNET) == 0) return true;
  const int first = errno;
  // Without root: a user namespace that maps us to root inside it.
  const uid_t uid = getuid();
  const gid_t gid = getgid();
  if (unshare(CLONE_NEWUSER | CLONE_NEWNET) == 0) {
    writeFile("/proc/self/setgroups", "deny");
    writeFile("/proc/self/uid_map", "0 " + std::to_string(uid) + " 1");
    writeFile("/proc/self/gid_map", "0 " + std::to_string(gid) + " 1");
    return true;
  }
  why = std::string("unshare(CLONE_NEWNET): ") + std::strerror(first) + "; with a user namespace: " + std::strerror(errno);
  return false;
}

}  // namespace

bool loopbackMulticastRoute() {
  std::ifstream f("/proc/net/route");
  std::string line;
  std::getline(f, line);  // header
  while (std::getline(f, line)) {
    std::istringstream s(line);
    std::string iface, dest, gateway, flags, refcnt, use, metric, mask;
    s >> iface >> dest >> gateway >> flags >> refcnt >> use >> metric >> mask;
    // /proc/net/route is in host byte order on little-endian: 224.0.0.0 = 000000E0, 240.0.0.0 = 000000F0
    if (iface == "lo" && dest == "000000E0" && mask == "000000F0") return true;
  }
  return false;
}

std::string prepareNetwork(NetnsMode mode) {
  if (mode == NetnsMode::Off) {
    if (!loopbackMulticastRoute())
      throw std::runtime_error(
          "--netns off needs a multicast route on loopback (ip link set lo multicast on; "
          "ip route add 224.0.0.0/4 dev lo); without it packets could leave this machine");
    return "current network namespace (multicast routed via lo, ttl=0)";
  }
  std::string why;
  if (enterPrivateNamespace(why)) {
    setUpLoopback();
    return "private network namespace (loopback only)";
  }
  if (mode == NetnsMode::On) throw std::runtime_error("cannot enter a private network namespace: " + why);
  if (loopbackMulticastRoute()) return "current network namespace (multicast routed via lo, ttl=0)";
  throw std::runtime_error("cannot keep multicast on this machine: " + why +
                           "; and this namespace has no multicast route on loopback. Run as root, or add "
                           "'ip route add 224.0.0.0/4 dev lo' and use --netns off");
}

}  // namespace afford

#include "experiment/watch/server.hpp"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>
#include <httplib.h>
#include <sodium.h>

#include <chrono>
#include <stdexcept>
#include <thread>

namespace afford {

using Clock = std::chrono::steady_clock;
constexpr std::size_t kBodyBytes = 64 * 1024;  // a request's body, at most (a control request is a few bytes)

// httplib's server for what it is good at, reading a request and writing its answer; the connections are
// the stage's, which hands it one whole request at a time.
class WatchServer::Http : public httplib::Server {
 public:
  bool serve(httplib::Stream& stream, bool close_connection, bool& closed) {
    return process_request(stream, close_connection, closed, nullptr);
  }
  // An event stream goes on while this is set (httplib's own sign that its server is running).
  void running(int listener) { svr_sock_ = listener; }
};

bool isLoopback(const std::string& address) {
  if (address == "localhost" || address == "::1") return true;
  in_addr a{};
  return inet_pton(AF_INET, address.c_str(), &a) == 1 && (ntohl(a.s_addr) >> 24) == 127;
}

std::string newToken() {
  if (sodium_init() < 0) throw std::runtime_error("libsodium cannot start");
  unsigned char bytes[16];
  randombytes_buf(bytes, sizeof bytes);
  char hex[2 * sizeof bytes + 1];
  sodium_bin2hex(hex, sizeof hex, bytes, sizeof bytes);
  return hex;
}

WatchServer::WatchServer(WatchState& state, WatchServerOptions options, PlaybackControls* controls)
    : state_(state), options_(std::move(options)), controls_(controls), server_(std::make_unique<Http>()) {
  if (!isLoopback(options_.bind) && options_.token.empty())
    throw std::runtime_error("--bind " + options_.bind + ": not loopback, so a token is required");
}

WatchServer::~WatchServer() { stop(); }

bool WatchServer::authorised(const std::string& query_token, const std::string& header) const {
  if (options_.token.empty()) return true;
  const std::string& t = options_.token;
  auto same = [&](const std::string& given) {
    return given.size() == t.size() && sodium_memcmp(given.data(), t.data(), t.size()) == 0;
  };
  const std::string bearer = "Bearer ";
  return same(query_token) || (header.rfind(bearer, 0) == 0 && same(header.substr(bearer.size())));
}

namespace {
void error(httplib::Response& res, int status, const std::string& why) {
  res.status = status;
  res.set_content(why + "\n", "text/plain; charset=utf-8");
}

// Why cpp-httplib, or the connections' stage, refused a request (they answer with a status and no words).
std::string refusal(int status) {
  switch (status) {
    case 400:
      return "a malformed request: its request line or header fields (at most 100 fields of 16 KB), or a body "
             "without a Content-Length (POST /control needs one, even of 0)";
    case 404:
      return "no such page: afford watch serves /, /state, /events and, playing a log, POST /control";
    case 413: return "the request's body is larger than afford watch takes (64 KB)";
    case 414: return "the request's address is too long";
    case 431: return "the request's head is larger than afford watch takes (64 KB)";
    default: return std::string("refused: ") + httplib::detail::status_message(status);
  }
}
}  // namespace

void WatchServer::routes() {
  httplib::Server& s = *server_;
  s.Get("/", [](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(watchPage(), "text/html; charset=utf-8");
  });
  s.Get("/state", [this](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(state_.snapshot(true), "application/json");
  });
  s.Post("/control", [this](const httplib::Request& req, httplib::Response& res) {
    if (!controls_) return error(res, 404, "a live run has no playback controls (afford watch --log LOG has)");
    const std::string why = controls_->control(req.get_param_value("command"), req.get_param_value("value"));
    if (!why.empty()) return error(res, 400, why);
    res.set_content("{\"ok\":true}", "application/json");
  });
  s.Get("/events", [this](const httplib::Request&, httplib::Response& res) {
    if (streams_.fetch_add(1) >= options_.most_streams) {
      streams_.fetch_sub(1);
      return error(res, 503, "too many pages follow this run already (" + std::to_string(options_.most_streams) + ")");
    }
    res.set_header("Cache-Control", "no-store");
    struct Stream {
      std::uint64_t seen = ~std::uint64_t{0}, curves = ~std::uint64_t{0};
      std::uint64_t sent = 0;  // the version it was sent last (0: none yet)
      Clock::time_point next = Clock::now(), next_curves = Clock::now();
    };
    auto stream = std::make_shared<Stream>();
    sentNow(std::nullopt, stream->sent);
    const auto gap = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / options_.most_per_second));
    res.set_chunked_content_provider(
        "text/event-stream",
        [this, stream, gap](std::size_t, httplib::DataSink& sink) {
          if (stopping_) return false;
          std::this_thread::sleep_until(stream->next);  // pacing the page, not the run
          const std::uint64_t v = state_.wait(stream->seen, Clock::now() + std::chrono::seconds(15));
          if (stopping_) return false;
          if (v == stream->seen) return sink.write(": still here\n\n", 14);  // a dead socket shows on writing
          stream->seen = v;
          stream->next = Clock::now() + gap;
          // The curves (the largest part, and the page's costliest to draw) at most once a second.
          const std::uint64_t curves = state_.curvesVersion();
          const bool with_curves = curves != stream->curves && Clock::now() >= stream->next_curves;
          if (with_curves) stream->curves = curves, stream->next_curves = Clock::now() + std::chrono::seconds(1);
          const std::string event = "event: state\ndata: " + state_.snapshot(with_curves) + "\n\n";
          if (!sink.write(event.data(), event.size())) return false;
          sentNow(stream->sent, v);
          stream->sent = v;
          return true;
        },
        [this, stream](bool) {
          sentNow(stream->sent, std::nullopt);  // gone: not waited for
          streams_.fetch_sub(1);
        });
  });
  s.set_error_handler(httplib::Server::HandlerWithResponse([](const httplib::Request&, httplib::Response& res) {
    if (!res.body.empty()) return httplib::Server::HandlerResponse::Unhandled;  // ours, saying why already
    error(res, res.status, refusal(res.status));
    return httplib::Server::HandlerResponse::Handled;
  }));
  s.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
    try {
      std::rethrow_exception(ep);
    } catch (const std::exception& e) {
      error(res, 500, e.what());
    } catch (...) {
      error(res, 500, "an unknown error");
    }
  });
}

void WatchServer::start() {
  httplib::Server& s = *server_;
  s.set_payload_max_length(kBodyBytes);
  s.set_keep_alive_timeout(options_.timeout_s);  // (what its answers say of the connection: the stage's)
  routes();
  const int listener = listenOn(options_.bind, options_.port, port_);
  server_->running(listener);
  StageOptions o;
  o.timeout_s = options_.timeout_s;
  o.workers = options_.most_streams + 4;  // every stream a worker, and a few for the rest
  o.most_connections = options_.most_connections;
  o.body_bytes = kBodyBytes;
  o.requests_per_connection = CPPHTTPLIB_KEEPALIVE_MAX_COUNT;  // (as its answers say)
  o.streamed_path = "/events";
  StageHooks hooks;
  // The token, from the request's head alone: a request without it never reaches a worker.
  hooks.check = [this](const httplib::Request& req) {
    if (authorised(req.get_param_value("token"), req.get_header_value("Authorization"))) return Verdict{};
    return Verdict{401, "a token is required: the address afford watch printed at its start has it"};
  };
  hooks.serve = [this](httplib::Stream& stream, bool close, bool& closed) { return server_->serve(stream, close, closed); };
  hooks.why = refusal;
  stage_ = std::make_unique<ConnectionStage>(listener, o, std::move(hooks));
  stage_->start();
}

void WatchServer::sentNow(std::optional<std::uint64_t> was, std::optional<std::uint64_t> now) {
  std::lock_guard<std::mutex> lock(sent_mutex_);
  if (was) sent_.erase(sent_.find(*was));
  if (now) sent_.insert(*now);
  sent_cv_.notify_all();
}

void WatchServer::flush(std::chrono::milliseconds most) {
  const std::uint64_t now = state_.version();
  std::unique_lock<std::mutex> lock(sent_mutex_);
  sent_cv_.wait_for(lock, most, [&] { return sent_.empty() || *sent_.begin() >= now; });
}

void WatchServer::stop() {
  if (stopping_.exchange(true)) return;
  state_.wakeAll();
  server_->running(-1);  // INVALID_SOCKET: the streams end
  if (stage_) stage_->stop();
}

std::vector<std::string> WatchServer::urls() const {
  const std::string tail = ":" + std::to_string(port_) + "/" + (options_.token.empty() ? "" : "?token=" + options_.token);
  auto url = [&](const std::string& a) { return "http://" + (a.find(':') != std::string::npos ? "[" + a + "]" : a) + tail; };
  const bool any4 = options_.bind == "0.0.0.0", any6 = options_.bind == "::";
  if (!any4 && !any6) return {url(options_.bind)};
  std::vector<std::string> others, loopback;
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) == 0) {
    for (const ifaddrs* i = list; i; i = i->ifa_next) {
      if (!i->ifa_addr || !(i->ifa_flags & IFF_UP)) continue;
      const int family = i->ifa_addr->sa_family;
      if (family != AF_INET && (family != AF_INET6 || !any6)) continue;
      char text[INET6_ADDRSTRLEN] = {};
      const void* at = family == AF_INET ? static_cast<const void*>(&reinterpret_cast<const sockaddr_in*>(i->ifa_addr)->sin_addr)
                                         : static_cast<const void*>(&reinterpret_cast<const sockaddr_in6*>(i->ifa_addr)->sin6_addr);
      if (!inet_ntop(family, at, text, sizeof text)) continue;
      if (family == AF_INET6 && IN6_IS_ADDR_LINKLOCAL(&reinterpret_cast<const sockaddr_in6*>(i->ifa_addr)->sin6_addr))
        continue;  // (opens only with its interface named)
      ((i->ifa_flags & IFF_LOOPBACK) ? loopback : others).push_back(url(text));
    }
    freeifaddrs(list);
  }
  others.insert(others.end(), loopback.begin(), loopback.end());
  if (others.empty()) others.push_back(url(any4 ? "127.0.0.1" : "::1"));
  return others;
}

}  // namespace afford

#include "experiment/watch/connections.hpp"

#include <httplib.h>
#include <netdb.h>
#include <poll.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/ioctl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace afford {

struct ConnectionStage::Conn {
  int fd = -1;
  Queue queue = Queue::Reading;
  Clock::time_point deadline{};
  bool queued = false;            // in queues_[queue] (at) and in the epoll set
  std::list<Conn*>::iterator at;
  std::string in;                 // what has come of its next request (and, after it, of the next)
  std::size_t line = 0;           // where the line being looked for in `in` starts
  int lines = 0;                  // lines of the head seen
  std::size_t head = 0;           // the head's length, once its blank line is in
  std::size_t length = 0;         // the whole request's (head and body), once the head is in
  bool streamed = false;          // an event stream: its worker writes it as it goes
  bool ended = false;             // the client has sent all it will (it may still read the answer)
  int served = 0;                 // requests answered
  std::string out;                // a response, or what its client has not taken yet
  std::size_t sent = 0;
  bool keep = false;              // once `out` is sent: wait for the next request (else close)
};

namespace {

using Clock = std::chrono::steady_clock;

// A worker's view of one request: its bytes, already read; the answer gathered to be sent by the stage, or
// (an event stream) written as it goes, each write within the timeout.
class RequestStream final : public httplib::Stream {
 public:
  RequestStream(int fd, const std::string& in, std::size_t length, bool streamed, int timeout_s, std::string& out)
      : fd_(fd), in_(in), length_(length), streamed_(streamed), timeout_(std::chrono::seconds(timeout_s)), out_(out) {}

  bool is_readable() const override { return at_ < length_; }
  bool is_writable() const override { return !streamed_ || ready(POLLOUT, Clock::now() + timeout_); }
  ssize_t read(char* ptr, size_t size) override {
    const std::size_t n = std::min(size, length_ - at_);
    std::memcpy(ptr, in_.data() + at_, n);
    at_ += n;
    return static_cast<ssize_t>(n);
  }
  ssize_t write(const char* ptr, size_t size) override {
    if (!streamed_) return out_.append(ptr, size), static_cast<ssize_t>(size);
    const auto deadline = Clock::now() + timeout_;
    for (std::size_t done = 0; done < size;) {
      const ssize_t n = send(fd_, ptr + done, size - done, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n > 0) {
        done += static_cast<std::size_t>(n);
      } else if (n < 0 && errno != EINTR && (errno != EAGAIN || !ready(POLLOUT, deadline))) {
        return -1;  // gone, or not taking what it asked for (the slow reader's drop)
      }
    }
    return static_cast<ssize_t>(size);
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    httplib::detail::get_remote_ip_and_port(fd_, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    httplib::detail::get_local_ip_and_port(fd_, ip, port);
  }
  socket_t socket() const override { return fd_; }

 private:
  bool ready(short events, Clock::time_point deadline) const {
    for (;;) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      if (left <= 0) return false;
      pollfd p{fd_, events, 0};
      const int r = poll(&p, 1, static_cast<int>(left));
      if (r > 0) return (p.revents & (POLLERR | POLLHUP | POLLNVAL)) == 0;
      if (r < 0 && errno != EINTR) return false;
    }
  }

  int fd_;
  const std::string& in_;
  std::size_t length_, at_ = 0;
  bool streamed_;
  Clock::duration timeout_;
  std::string& out_;
};

// The head as httplib parses it (its request line split, its path and query decoded, each field that ends
// with CRLF), for the stage's checks.
httplib::Request parseHead(const std::string& in, std::size_t head) {
  httplib::Request req;
  std::size_t eol = in.find('\n');
  std::size_t end = eol > 0 && in[eol - 1] == '\r' ? eol - 1 : eol;
  int part = 0;
  httplib::detail::split(in.data(), in.data() + end, ' ', [&](const char* b, const char* e) {
    (part == 0 ? req.method : part == 1 ? req.target : req.version).assign(b, e);
    ++part;
  });
  req.target = req.target.substr(0, req.target.find('#'));
  const std::size_t q = req.target.find('?');
  req.path = httplib::detail::decode_url(req.target.substr(0, q), false);
  if (q != std::string::npos) httplib::detail::parse_query_text(req.target.substr(q + 1), req.params);
  for (std::size_t at = eol + 1; at < head;) {
    eol = in.find('\n', at);
    if (eol > at && in[eol - 1] == '\r')
      httplib::detail::parse_header(in.data() + at, in.data() + eol - 1, [&](std::string&& k, std::string&& v) {
        req.headers.emplace(std::move(k), std::move(v));
      });
    at = eol + 1;
  }
  return req;
}

// The body's length the head states (all its Content-Length fields the same number), or -1.
long long statedLength(const httplib::Request& req) {
  long long length = 0;
  const auto fields = req.headers.equal_range("Content-Length");
  for (auto f = fields.first; f != fields.second; ++f) {
    const std::string& v = f->second;
    if (v.empty() || v.size() > 12 || v.find_first_not_of("0123456789") != std::string::npos) return -1;
    if (f != fields.first && std::stoll(v) != length) return -1;
    length = std::stoll(v);
  }
  return length;
}

std::string response(int status, const std::string& why) {
  const std::string body = why + "\n";
  return "HTTP/1.1 " + std::to_string(status) + " " + httplib::detail::status_message(status) +
         "\r\nContent-Type: text/plain; charset=utf-8\r\nContent-Length: " + std::to_string(body.size()) +
         "\r\nConnection: close\r\n\r\n" + body;
}

// Sends what it can of c's response now, without waiting; false if the connection is gone.
bool sendSome(int fd, const std::string& out, std::size_t& sent) {
  while (sent < out.size()) {
    const ssize_t n = send(fd, out.data() + sent, out.size() - sent, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      sent += static_cast<std::size_t>(n);
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else {
      return n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK);
    }
  }
  return true;
}

void control(int epoll, int op, int fd, std::uint32_t events) {
  epoll_event e{};
  e.events = events;
  e.data.fd = fd;
  epoll_ctl(epoll, op, fd, &e);
}

constexpr std::uint32_t kEvents[3] = {EPOLLIN | EPOLLRDHUP, EPOLLOUT, EPOLLIN | EPOLLRDHUP};
constexpr auto kLinger = std::chrono::seconds(2);  // a refused client's bytes still coming are read and dropped
constexpr int kAcceptsAtOnce = 256;                // then the connections already held have their turn

}  // namespace

int listenOn(const std::string& host, int port, int& bound) {
  const std::string where = (host.find(':') != std::string::npos ? "[" + host + "]" : host) + ":" + std::to_string(port);
  addrinfo hints{}, *found = nullptr;
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE;
  if (const int e = getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found); e != 0)
    throw std::runtime_error("cannot serve on " + where + ": " + gai_strerror(e));
  int fd = -1, error = 0;
  for (addrinfo* a = found; a && fd < 0; a = a->ai_next) {
    fd = socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) {
      error = errno;
      continue;
    }
    // SO_REUSEADDR (a restart binds while the last one's connections close), never SO_REUSEPORT: a second
    // server on a port in use must fail, not share its connections.
    const int yes = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    // A backlog for bursts of thousands (the kernel caps it at net.core.somaxconn): a connection it has no
    // room for waits a second for its client to try again.
    if (bind(fd, a->ai_addr, a->ai_addrlen) != 0 || ::listen(fd, 65535) != 0) {
      error = errno;
      ::close(fd);
      fd = -1;
    }
  }
  freeaddrinfo(found);
  if (fd < 0)
    throw std::runtime_error("cannot serve on " + where + ": " + std::strerror(error) +
                             (error == EADDRINUSE ? " (another afford watch, or another server, has this port)" : ""));
  sockaddr_storage addr{};
  socklen_t len = sizeof addr;
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  bound = ntohs(addr.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6*>(&addr)->sin6_port
                                           : reinterpret_cast<sockaddr_in*>(&addr)->sin_port);
  return fd;
}

ConnectionStage::ConnectionStage(int listener, StageOptions options, StageHooks hooks)
    : listener_(listener), options_(std::move(options)), hooks_(std::move(hooks)), most_connections_(options_.most_connections) {
  // Within the process's file limit, leaving room for the workers' connections and the rest of the process.
  rlimit files{};
  if (getrlimit(RLIMIT_NOFILE, &files) == 0 && files.rlim_cur != RLIM_INFINITY) {
    const rlim_t others = static_cast<rlim_t>(options_.workers) + 64;
    most_connections_ = std::min<std::size_t>(most_connections_, files.rlim_cur > 2 * others ? files.rlim_cur - others : others);
  }
}

ConnectionStage::~ConnectionStage() {
  stop();
  if (listener_ >= 0) ::close(listener_);
}

void ConnectionStage::start() {
  epoll_ = epoll_create1(EPOLL_CLOEXEC);
  wake_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (epoll_ < 0 || wake_ < 0) throw std::runtime_error(std::string("afford watch: no epoll: ") + std::strerror(errno));
  control(epoll_, EPOLL_CTL_ADD, listener_, EPOLLIN);
  control(epoll_, EPOLL_CTL_ADD, wake_, EPOLLIN);
  pool_ = std::make_unique<httplib::ThreadPool>(static_cast<std::size_t>(options_.workers));
  running_ = true;
  thread_ = std::thread([this] { loop(); });
}

void ConnectionStage::stop() {
  if (!running_) return;
  running_ = false;
  stopping_ = true;
  const std::uint64_t one = 1;
  if (write(wake_, &one, sizeof one) < 0) { /* the loop also sees stopping_ at its next wake-up */ }
  thread_.join();
  {
    std::lock_guard<std::mutex> lock(returned_mutex_);
    closed_ = true;  // a worker's connection from now on is closed by the worker
  }
  takeReturned();
  pool_->shutdown();
  for (auto& [fd, c] : conns_) ::close(fd);
  conns_.clear();
  for (auto& q : queues_) q.clear();
  held_ = 0;
  ::close(listener_), ::close(epoll_), ::close(wake_);
  listener_ = epoll_ = wake_ = -1;
}

StageCounts ConnectionStage::counts() const { return {held_, dropped_, refused_, paused_, wakeups_}; }

void ConnectionStage::loop() {
  epoll_event events[256];
  while (!stopping_) {
    const int n = epoll_wait(epoll_, events, 256, waitMs(Clock::now()));
    ++wakeups_;
    for (int i = 0; i < n && !stopping_; ++i) {
      const int fd = events[i].data.fd;
      if (fd == wake_) {
        std::uint64_t count;
        while (read(wake_, &count, sizeof count) > 0) {
        }
        takeReturned();
      } else if (fd == listener_) {
        acceptAll();
      } else if (const auto it = conns_.find(fd); it != conns_.end()) {
        Conn& c = *it->second;
        if (c.queue == Queue::Reading) onReadable(c);
        else if (c.queue == Queue::Flushing) onWritable(c);
        else onDraining(c);
      }
    }
    const auto now = Clock::now();
    expire(now);
    if (accept_paused_ && now >= resume_at_) resumeAccepting();
  }
}

void ConnectionStage::acceptAll() {
  for (int i = 0; i < kAcceptsAtOnce; ++i) {
    const int fd = accept4(listener_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EINTR || errno == ECONNABORTED) continue;
      if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
        if (makeRoom()) continue;         // a file freed: the new connection is taken
        pauseAccepting(Clock::now());     // none to free: wait for one, not spinning on the listener
      }
      return;
    }
    if (conns_.size() >= most_connections_) makeRoom();
    auto c = std::make_unique<Conn>();
    c->fd = fd;
    Conn& ref = *c;
    conns_.emplace(fd, std::move(c));
    held_ = conns_.size();
    enter(ref, Queue::Reading);
  }
}

void ConnectionStage::onReadable(Conn& c) {
  char buf[16384];
  for (;;) {
    // Up to the head's bound until the head is in, then up to the request's end (what follows waits in the kernel).
    const std::size_t limit = c.head ? c.length : options_.head_bytes + 1;
    const std::size_t room = std::min(sizeof buf, limit - std::min(limit, c.in.size()));
    if (room == 0) break;
    const ssize_t n = recv(c.fd, buf, room, 0);
    if (n > 0) {
      c.in.append(buf, static_cast<std::size_t>(n));
      account(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
    if (n < 0 || c.in.empty()) return close(c);  // the client is gone
    c.ended = true;  // its side closed after a request: answered if the request is whole
    break;
  }
  const int fd = c.fd;
  scan(c);
  if (const auto it = conns_.find(fd); it != conns_.end() && it->second->queue == Queue::Reading && it->second->ended)
    close(*it->second);  // it left before its request was whole
  shed();
}

// Looks for the end of the head as httplib's reader does: lines end with '\n', and the head with the first
// line after the request line that is CRLF alone. Then the body, if any, and the request goes to a worker.
void ConnectionStage::scan(Conn& c) {
  for (std::size_t eol; !c.head && (eol = c.in.find('\n', c.line)) != std::string::npos; c.line = eol + 1) {
    if (c.lines++ > 0 && eol == c.line + 1 && c.in[c.line] == '\r') {
      c.head = eol + 1;
      const int fd = c.fd;
      examineHead(c);
      if (!conns_.count(fd) || c.queue != Queue::Reading) return;  // refused
    }
  }
  if (!c.head) {
    if (c.in.size() > options_.head_bytes) refuse(c, 431, hooks_.why(431));
  } else if (c.in.size() >= c.length) {
    dispatch(c);
  }
}

void ConnectionStage::examineHead(Conn& c) {
  const httplib::Request req = parseHead(c.in, c.head);
  if (Verdict r = hooks_.check(req); r.status != 0) return refuse(c, r.status, r.why);
  // A body is framed by its Content-Length alone (what httplib would read without one waits for the client).
  const long long body = statedLength(req);
  if (body < 0 || req.has_header("Transfer-Encoding") ||
      (httplib::detail::expect_content(req) && !req.has_header("Content-Length")))
    return refuse(c, 400, hooks_.why(400));
  if (static_cast<unsigned long long>(body) > options_.body_bytes) return refuse(c, 413, hooks_.why(413));
  c.length = c.head + static_cast<std::size_t>(body);
  c.streamed = req.path == options_.streamed_path;
  if (c.in.size() < c.length && req.get_header_value("Expect") == "100-continue") {
    // A client waiting for leave to send its body has it (as httplib would give it; it says it again).
    static const std::string go = "HTTP/1.1 100 Continue\r\n\r\n";
    std::size_t sent = 0;
    sendSome(c.fd, go, sent);
  }
}

void ConnectionStage::refuse(Conn& c, int status, const std::string& why) {
  ++refused_;
  account(-static_cast<std::int64_t>(c.in.size()));
  c.in.clear();
  c.out = response(status, why);
  c.sent = 0;
  c.keep = false;
  account(static_cast<std::int64_t>(c.out.size()));
  if (!sendSome(c.fd, c.out, c.sent)) return close(c);
  if (c.sent == c.out.size()) return finish(c);
  enter(c, Queue::Flushing);
}

void ConnectionStage::dispatch(Conn& c) {
  epoll_ctl(epoll_, EPOLL_CTL_DEL, c.fd, nullptr);
  queues_[static_cast<int>(c.queue)].erase(c.at);
  c.queued = false;
  account(-static_cast<std::int64_t>(c.in.size()));
  Conn* mine = conns_[c.fd].release();
  conns_.erase(mine->fd);
  held_ = conns_.size();
  pool_->enqueue([this, mine] { work(mine); });
}

// A worker's: the request, then the connection back to the stage (or closed).
void ConnectionStage::work(Conn* c) {
  std::string out;
  bool ok = false, closed = false;
  const bool last = ++c->served >= options_.requests_per_connection;
  {
    RequestStream stream(c->fd, c->in, c->length, c->streamed, options_.timeout_s, out);
    try {
      ok = hooks_.serve(stream, last, closed);
    } catch (...) {
      ok = false;  // (the server's handlers answer their own exceptions; nothing leaves a worker)
    }
  }
  c->in.erase(0, c->length);
  c->line = 0, c->lines = 0, c->head = 0, c->length = 0;
  c->keep = ok && !closed && !last && !c->streamed && !c->ended;
  c->out = std::move(out);
  c->sent = 0;
  if (!sendSome(c->fd, c->out, c->sent)) c->keep = false, c->out.clear();
  comeBack(c);
}

void ConnectionStage::comeBack(Conn* c) {
  {
    std::lock_guard<std::mutex> lock(returned_mutex_);
    if (!closed_) {
      returned_.push_back(c);
      c = nullptr;
    }
  }
  if (c) {
    ::close(c->fd);
    delete c;
    return;
  }
  const std::uint64_t one = 1;
  if (write(wake_, &one, sizeof one) < 0) { /* the eventfd's count is full: the stage is awake already */ }
}

void ConnectionStage::takeReturned() {
  std::vector<Conn*> back;
  {
    std::lock_guard<std::mutex> lock(returned_mutex_);
    back.swap(returned_);
  }
  for (Conn* raw : back) {
    if (stopping_) {
      ::close(raw->fd);
      delete raw;
      continue;
    }
    if (conns_.size() >= most_connections_) makeRoom();
    Conn& c = *raw;
    conns_.emplace(c.fd, std::unique_ptr<Conn>(raw));
    held_ = conns_.size();
    if (c.sent == c.out.size()) c.out.clear(), c.sent = 0;
    account(static_cast<std::int64_t>(c.in.size() + c.out.size()));
    if (!c.out.empty()) {
      enter(c, Queue::Flushing);
      shed();
    } else if (c.keep) {
      enter(c, Queue::Reading);
      scan(c);  // a request that came behind the last one may be whole already
    } else {
      finish(c);
    }
  }
}

void ConnectionStage::onWritable(Conn& c) {
  if (!sendSome(c.fd, c.out, c.sent)) return close(c);
  if (c.sent < c.out.size()) return;
  account(-static_cast<std::int64_t>(c.out.size()));
  c.out.clear();
  c.sent = 0;
  if (!c.keep) return finish(c);
  enter(c, Queue::Reading);
  scan(c);
}

void ConnectionStage::onDraining(Conn& c) {
  char buf[16384];
  for (;;) {
    const ssize_t n = recv(c.fd, buf, sizeof buf, 0);
    if (n > 0) continue;
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return;
    return close(c);  // all read: the refusal reached it
  }
}

// A connection done with: closed at once if nothing of its client is left unread, else after its client's
// bytes still coming are read (closing on unread bytes would reset the connection, the answer lost with it).
void ConnectionStage::finish(Conn& c) {
  int unread = 0;
  if (c.in.empty() && ioctl(c.fd, FIONREAD, &unread) == 0 && unread == 0) return close(c);
  account(-static_cast<std::int64_t>(c.in.size() + c.out.size()));
  c.in.clear(), c.out.clear(), c.sent = 0;
  shutdown(c.fd, SHUT_WR);
  enter(c, Queue::Closing);
}

void ConnectionStage::enter(Conn& c, Queue q) {
  if (c.queued) queues_[static_cast<int>(c.queue)].erase(c.at);
  control(epoll_, c.queued ? EPOLL_CTL_MOD : EPOLL_CTL_ADD, c.fd, kEvents[static_cast<int>(q)]);
  c.queued = true;
  c.queue = q;
  c.deadline = Clock::now() + (q == Queue::Closing ? std::chrono::duration_cast<Clock::duration>(kLinger)
                                                   : std::chrono::duration_cast<Clock::duration>(
                                                         std::chrono::seconds(options_.timeout_s)));
  auto& queue = queues_[static_cast<int>(q)];
  c.at = queue.insert(queue.end(), &c);
}

void ConnectionStage::drop(Conn& c) {
  ++dropped_;
  close(c);
}

void ConnectionStage::close(Conn& c) {
  account(-static_cast<std::int64_t>(c.in.size() + c.out.size()));
  if (c.queued) queues_[static_cast<int>(c.queue)].erase(c.at);
  const int fd = c.fd;
  ::close(fd);  // (closing takes it out of the epoll set)
  conns_.erase(fd);
  held_ = conns_.size();
  resumeAccepting();
}

// Drops the oldest connection still waiting for its request (then the oldest refused one draining, then the
// oldest response its client is slow to take); false if none is held.
bool ConnectionStage::makeRoom() {
  for (Queue q : {Queue::Reading, Queue::Closing, Queue::Flushing}) {
    auto& queue = queues_[static_cast<int>(q)];
    if (!queue.empty()) return drop(*queue.front()), true;
  }
  return false;
}

// Over the bytes' bound: the oldest connections holding bytes are dropped until within it.
void ConnectionStage::shed() {
  for (Queue q : {Queue::Reading, Queue::Closing, Queue::Flushing}) {
    auto& queue = queues_[static_cast<int>(q)];
    for (auto it = queue.begin(); bytes_ > options_.most_bytes && it != queue.end();) {
      Conn& c = **it++;
      if (!c.in.empty() || !c.out.empty()) drop(c);
    }
  }
}

void ConnectionStage::expire(Clock::time_point now) {
  for (auto& queue : queues_)
    while (!queue.empty() && queue.front()->deadline <= now) drop(*queue.front());
}

int ConnectionStage::waitMs(Clock::time_point now) const {
  Clock::time_point next = Clock::time_point::max();
  for (const auto& queue : queues_)
    if (!queue.empty()) next = std::min(next, queue.front()->deadline);
  if (accept_paused_) next = std::min(next, resume_at_);
  if (next == Clock::time_point::max()) return -1;
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(next - now).count() + 1;
  return static_cast<int>(std::clamp<long long>(ms, 0, 60'000));
}

void ConnectionStage::pauseAccepting(Clock::time_point now) {
  if (accept_paused_) return;
  ++paused_;
  accept_paused_ = true;
  resume_at_ = now + std::chrono::milliseconds(100);
  control(epoll_, EPOLL_CTL_MOD, listener_, 0);
}

void ConnectionStage::resumeAccepting() {
  if (!accept_paused_) return;
  accept_paused_ = false;
  control(epoll_, EPOLL_CTL_MOD, listener_, EPOLLIN);
}

void ConnectionStage::account(std::int64_t bytes) { bytes_ = static_cast<std::size_t>(static_cast<std::int64_t>(bytes_) + bytes); }

}  // namespace afford

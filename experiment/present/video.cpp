#include "experiment/present/video.hpp"

#include "afford/file_lock.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <vector>

#include "afford/auth.hpp"
#include "afford/config.hpp"
#include "afford/process_main.hpp"
#include "experiment/replay/replay.hpp"
#include "viewer/feed.hpp"
#include "viewer/step_order.hpp"
#include "viewer/viewer.hpp"

extern char** environ;

namespace afford {
namespace fs = std::filesystem;

namespace {

// The output's format from its name (checked by prepareOutput: .mp4 or .gif, any case).
std::string formatOf(const fs::path& out) {
  std::string ext = out.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext.substr(1);
}

// ffmpeg reading raw BGR frames on its standard input, writing `file` as `format`.
class Encoder {
 public:
  Encoder(const std::string& ffmpeg, int width, int height, int fps, const std::string& format, const fs::path& file) {
    std::vector<std::string> args = {ffmpeg, "-hide_banner", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt",
                                     "bgr24", "-s", std::to_string(width) + "x" + std::to_string(height), "-r",
                                     std::to_string(fps), "-i", "pipe:0"};
    if (format == "mp4")  // H.264 in 4:2:0 wants even sides; any player opens it
      args.insert(args.end(), {"-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libx264", "-pix_fmt", "yuv420p",
                               "-movflags", "+faststart"});
    else  // a palette per frame: nothing held across frames, however long the run
      args.insert(args.end(), {"-vf", "split[a][b];[a]palettegen=stats_mode=single[p];[b][p]paletteuse=new=1"});
    args.insert(args.end(), {"-f", format, "-y", file.string()});
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error(std::string("cannot make a pipe: ") + std::strerror(errno));
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[0], 0);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    const int rc = posix_spawnp(&pid_, ffmpeg.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(fds[0]);
    if (rc != 0) {
      ::close(fds[1]);
      throw std::runtime_error("cannot start " + ffmpeg + ": " + std::strerror(rc) +
                               " (install Debian's ffmpeg: scripts/setup.sh)");
    }
    in_ = fds[1];
  }
  ~Encoder() {
    if (in_ >= 0) ::close(in_);
    if (pid_ > 0) waitpid(pid_, nullptr, 0);
  }
  // False if ffmpeg has stopped reading (it said why on standard error).
  bool write(const cv::Mat& frame) {
    const auto* p = frame.data;
    std::size_t left = frame.total() * frame.elemSize();
    while (left > 0) {
      const ssize_t n = ::write(in_, p, left);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return false;
      p += n, left -= static_cast<std::size_t>(n);
    }
    return true;
  }
  // ffmpeg's exit status once its input is closed.
  int finish() {
    ::close(in_);
    in_ = -1;
    int status = 0;
    while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

 private:
  pid_t pid_ = -1;
  int in_ = -1;
};

// SIGPIPE ignored while frames go to ffmpeg (a dead encoder is a write error, not the end of this process).
struct NoSigpipe {
  struct sigaction old {};
  NoSigpipe() {
    struct sigaction ignore {};
    ignore.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &ignore, &old);
  }
  ~NoSigpipe() { sigaction(SIGPIPE, &old, nullptr); }
};

}  // namespace

VideoResult renderVideo(const VideoOptions& o, spdlog::logger& log) {
  if (o.every < 1) throw std::runtime_error("--every must be at least 1");
  if (o.fps < 1 || o.fps > 240) throw std::runtime_error("--fps must be within 1..240");
  prepareOutput(o.out, "--out", {".mp4", ".gif"});  // before any work: a name ffmpeg can write, its folder made
  const std::string format = formatOf(o.out);
  if (fs::exists(o.out)) throw std::runtime_error("--out " + o.out.string() + " exists: afford never overwrites a file");
  const fs::path partial = o.out.string() + ".partial";
  // Held while ffmpeg writes it (a kernel lock): a render killed half-way leaves a partial file the next one takes
  // over, and two renders of one file at once are refused, naming it.
  HeldFile held;
  holdPartial(held, partial.string(), "afford render");
  const std::shared_ptr<const BusKey> key = o.bus_key.empty() ? nullptr : busKeyFrom(o.bus_key);
  const ProtocolConfig protocol = loadProtocol(o.config_dir.empty() ? defaultConfigDir() : o.config_dir);
  // The run's messages in step order: each frame pairs a step's own messages, however the log interleaves them.
  StepOrderedLog<RecordedLogStream, RunSelector> in(
      [&](spdlog::logger& l) { return std::make_unique<RecordedLogStream>(o.log, l, key.get()); },
      [&](spdlog::logger& l) { return std::make_unique<RunSelector>(o.run_id, o.log.string(), l); }, protocol, log);
  Viewer viewer;
  ViewFeed feed(viewer, protocol, o.run_id);
  VideoResult r;
  NoSigpipe no_sigpipe;
  std::unique_ptr<Encoder> encoder;
  std::int64_t drawn = -1;  // the step last drawn
  auto draw = [&] {         // the viewer's state, a step complete
    const cv::Mat frame = viewer.render();
    if (!encoder) {
      r.width = frame.cols, r.height = frame.rows;
      encoder = std::make_unique<Encoder>(o.ffmpeg, frame.cols, frame.rows, o.fps, format, partial);
    }
    if (!encoder->write(frame)) throw std::runtime_error(o.ffmpeg + " stopped taking frames (its message above)");
    drawn = viewer.step();
    if (r.first_step < 0) r.first_step = drawn;
    r.last_step = drawn;
    ++r.frames;
  };
  auto due = [&] { return viewer.step() >= 0 && (drawn < 0 || viewer.step() - drawn >= o.every); };
  try {
    LogEvent e;
    StepKey at;
    std::string why;
    while (in.next(e, at) && (o.max_frames <= 0 || r.frames < o.max_frames)) {
      // Ctrl-C (when the command installed the stop handlers): the partial file is removed below.
      if (stopRequested()) throw std::runtime_error("interrupted: " + o.out.string() + " not written");
      ++r.events;
      // A message of a later step: the step shown is complete (the messages come in step order).
      if (due() && at.step > viewer.step()) draw();
      if (!feed.take(e, why) && r.refused++ < 10) log.warn("{}: {}: skipped", e.channel, why);
    }
    if (due() && (o.max_frames <= 0 || r.frames < o.max_frames)) draw();
    if (!encoder) in.selector().check(in.cut(), in.stream().counts().key);  // no RUN_CONFIG: why (a key that does not fit?)
    if (!encoder) throw std::runtime_error(o.log.string() + ": no scene of " +
                                           (o.run_id.empty() ? "any run" : "run '" + o.run_id + "'") + " to draw");
    if (const int status = encoder->finish(); status != 0)
      throw std::runtime_error(o.ffmpeg + " failed (exit status " + std::to_string(status) + ")");
    encoder.reset();
    fs::rename(partial, o.out);
  } catch (...) {
    encoder.reset();
    std::error_code ec;
    fs::remove(partial, ec);
    throw;
  }
  r.run_id = feed.shown();
  r.malformed = in.stream().counts().malformed;
  r.untagged = in.stream().counts().untagged;
  return r;
}

}  // namespace afford

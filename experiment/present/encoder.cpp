#include "experiment/present/encoder.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <vector>

extern char** environ;

namespace afford {

std::string formatOf(const std::filesystem::path& out) {
  std::string ext = out.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext.substr(1);
}

Encoder::Encoder(const std::string& ffmpeg, int width, int height, int fps, const std::string& format,
                 const std::filesystem::path& file) {
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

Encoder::~Encoder() {
  if (in_ >= 0) ::close(in_);
  if (pid_ > 0) waitpid(pid_, nullptr, 0);
}

bool Encoder::write(const cv::Mat& frame) {
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

int Encoder::finish() {
  ::close(in_);
  in_ = -1;
  int status = 0;
  while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
  }
  pid_ = -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

NoSigpipe::NoSigpipe() {
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  sigaction(SIGPIPE, &ignore, &old);
}
NoSigpipe::~NoSigpipe() { sigaction(SIGPIPE, &old, nullptr); }

VideoFile::VideoFile(std::filesystem::path out, std::string ffmpeg, int fps, const std::string& who)
    : out_(std::move(out)), ffmpeg_(std::move(ffmpeg)), fps_(fps) {
  if (fps < 1 || fps > 240) throw std::runtime_error("--fps must be within 1..240");
  prepareOutput(out_, "--out", {".mp4", ".gif"});  // before any work: a name ffmpeg can write, its folder made
  format_ = formatOf(out_);
  if (std::filesystem::exists(out_))
    throw std::runtime_error("--out " + out_.string() + " exists: afford never overwrites a file");
  partial_ = out_.string() + ".partial";
  holdPartial(held_, partial_.string(), who);
}

VideoFile::~VideoFile() {
  if (done_) return;
  encoder_.reset();
  std::error_code ec;
  std::filesystem::remove(partial_, ec);
}

void VideoFile::write(const cv::Mat& frame) {
  if (!encoder_) {
    width_ = frame.cols, height_ = frame.rows;
    encoder_ = std::make_unique<Encoder>(ffmpeg_, width_, height_, fps_, format_, partial_);
  }
  if (!encoder_->write(frame)) throw std::runtime_error(ffmpeg_ + " stopped taking frames (its message above)");
}

void VideoFile::finish() {
  if (!encoder_) throw std::logic_error("VideoFile::finish: no frame written");
  if (const int status = encoder_->finish(); status != 0)
    throw std::runtime_error(ffmpeg_ + " failed (exit status " + std::to_string(status) + ")");
  encoder_.reset();
  std::filesystem::rename(partial_, out_);
  done_ = true;
}

}  // namespace afford

// ffmpeg fed raw frames on a pipe, for afford render's videos (video.hpp) and a table run's primitives
// (primitive_video.hpp).
#pragma once
#include <signal.h>
#include <sys/types.h>

#include <filesystem>
#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "afford/file_lock.hpp"

namespace afford {

// The output's format from its name: "mp4" or "gif" (prepareOutput has checked it is one of them, any case).
std::string formatOf(const std::filesystem::path& out);

// ffmpeg reading raw BGR frames of width x height on its standard input, writing `file` as `format`.
class Encoder {
 public:
  // Throws std::runtime_error when ffmpeg cannot be started (naming the package that gives it).
  Encoder(const std::string& ffmpeg, int width, int height, int fps, const std::string& format,
          const std::filesystem::path& file);
  ~Encoder();
  Encoder(const Encoder&) = delete;
  Encoder& operator=(const Encoder&) = delete;
  // False if ffmpeg has stopped reading (it said why on standard error).
  bool write(const cv::Mat& frame);
  // ffmpeg's exit status once its input is closed.
  int finish();

 private:
  pid_t pid_ = -1;
  int in_ = -1;
};

// SIGPIPE ignored while frames go to ffmpeg (a dead encoder is a write error, not the end of this process).
struct NoSigpipe {
  struct sigaction old {};
  NoSigpipe();
  ~NoSigpipe();
  NoSigpipe(const NoSigpipe&) = delete;
  NoSigpipe& operator=(const NoSigpipe&) = delete;
};

// A video (.mp4 or .gif) written under a partial name beside `out` and renamed when ffmpeg has finished: an
// existing `out` is refused and never overwritten, the partial file is held while written (a second writer
// of it is refused, naming it; one killed half-way leaves a partial file the next takes over), and a VideoFile
// destroyed before finish() leaves nothing. Throws std::runtime_error saying what was wrong.
class VideoFile {
 public:
  VideoFile(std::filesystem::path out, std::string ffmpeg, int fps, const std::string& who);
  ~VideoFile();
  VideoFile(const VideoFile&) = delete;
  VideoFile& operator=(const VideoFile&) = delete;
  // The first frame's size is the video's.
  void write(const cv::Mat& frame);
  bool started() const { return encoder_ != nullptr; }
  int width() const { return width_; }
  int height() const { return height_; }
  // ffmpeg finishes and the file takes its name.
  void finish();

 private:
  std::filesystem::path out_, partial_;
  std::string ffmpeg_, format_;
  int fps_ = 25, width_ = 0, height_ = 0;
  HeldFile held_;
  NoSigpipe no_sigpipe_;
  std::unique_ptr<Encoder> encoder_;
  bool done_ = false;
};

}  // namespace afford

#include "predictors/predictors.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <unistd.h>
#include <zlib.h>

#include <iterator>
#include <limits>
#include <sstream>

#include "afford/checksum.hpp"
#include "afford/names.hpp"
#include "afford/rng.hpp"
#include "afford/snapshot.hpp"
#include "afford/version.hpp"

namespace afford {

Predictors::Predictors(const PredictorsParams& params)
    : config_(params.component.predictors),
      focus_side_(params.component.focus_side),
      seed_(params.component.seed),
      world_(params.world),
      input_size_(focus_side_ * focus_side_ * 3) {
  affordance_ = makeAffordance(params.component);
  const int dim = input_size_ + 1;
  for (int a = 0; a < kNumActions; ++a) {
    what_.emplace_back(input_size_, dim, true);
    where_.emplace_back(2, takesPlace(world_, a) ? 5 : 3, false);
  }
  if (params.keeps_memory) memory_ = std::make_unique<Memory>(config_.memory, focus_side_);
}

Prediction Predictors::see(const std::vector<std::uint8_t>& focus_image, std::int64_t step) {
  Prediction p = predict(focus_image);
  if (memory_) {
    p.remembered = true;
    p.look = memory_->see(focus_image, step);
    p.tried_ago = memory_->triedAgo(p.look, step);
  }
  return p;
}

Prediction Predictors::predict(const std::vector<std::uint8_t>& focus_image) const {
  const SparseInput x = focusInput(focus_image);
  Prediction p;
  affordance_->predict(FocusView{focus_image, x}, p.affordance, p.learning_progress);
  // A predictor that diverged (a learning rate too large for it) fails the run here, saying so, rather than
  // publishing numbers every reader drops (the run would stall until its processes' silence fails it).
  for (int a = 0; a < kNumActions; ++a)
    for (const auto& [name, v] : {std::pair{"affordance", p.affordance[a]}, {"learning progress", p.learning_progress[a]}})
      if (!std::isfinite(v))
        throw std::runtime_error(std::string("the ") + name + " prediction of " + std::string(actionName(world_, a)) +
                                 " is not finite (" + std::to_string(v) + "): its predictor diverged; is its "
                                 "learning rate (predictors.*.learning_rate) too large?");
  return p;
}

SparseInput Predictors::whereInput(int action, double x, double y, double tx, double ty) const {
  return takesPlace(world_, action) ? denseInput({tx, ty, x, y}) : denseInput({x, y});
}

TrainingReport Predictors::train(const Experience& e, std::int64_t step, int look) {
  TrainingReport r = trainAffordance(e, step, look);
  trainEffects(r.effect_updates);
  return r;
}

TrainingReport Predictors::trainAffordance(const Experience& e, std::int64_t step, int look) {
  const int a = e.action;
  const SparseInput x = focusInput(e.before_image);
  TrainingReport r;
  r.action = a;
  r.affordance = e.affordance;
  const Learned learned = affordance_->learn(FocusView{e.before_image, x}, a, e.affordance);
  r.affordance_before = learned.before;
  r.affordance_after = learned.after;
  r.learning_progress = learned.learning_progress;
  ++executed_[a];
  if (e.affordance) ++successes_[a];
  r.effect_trained = e.affordance;
  if (!memory_) {
    if (e.affordance) r.effect_updates.push_back(std::make_shared<const Experience>(e));
    return r;
  }
  if (look < 0) throw std::invalid_argument("an experience to remember needs the look of its focus (Predictors::see)");
  auto kept = std::make_shared<Experience>(e);
  if (!kept->affordance) kept->after_image.clear();  // nothing learns from the look after a failure
  kept->before_input = x;
  Memory::Ref ref = kept;
  memory_->record(look, step, ref);
  if (e.affordance) r.effect_updates.push_back(ref);
  const std::vector<Memory::Ref> more = replay(step, e.affordance);
  r.effect_updates.insert(r.effect_updates.end(), more.begin(), more.end());
  return r;
}

std::vector<Memory::Ref> Predictors::replay(std::int64_t step, bool own_effect) {
  // Replay (docs/model.md#replay): at every step, after the update of the step's own action if there was one,
  // remembered experiences of any look and action drawn by (seed, step): each one delta-rule step of its
  // affordance predictor; and forward-model updates from experiences whose effect was seen, for trainEffects,
  // making up effects_ratio with the step's own.
  const ReplayConfig& replay = config_.replay;
  if (!memory_ || !replay.enabled) return {};
  for (const Memory::Ref& m : memory_->sample(replay.sampling, seed_, step, 0, static_cast<std::size_t>(replay.ratio), false)) {
    affordance_->relearn(FocusView{m->before_image, m->before_input}, m->action, m->affordance);
    ++replayed_;
  }
  // Step t's share of effects_ratio: floor((t + 1) r) - floor(t r), which adds up to r per step.
  const auto share = static_cast<int>(std::floor(static_cast<double>(step + 1) * replay.effects_ratio) -
                                      std::floor(static_cast<double>(step) * replay.effects_ratio));
  const int more = std::max(0, share - (own_effect ? 1 : 0));
  std::vector<Memory::Ref> effects =
      memory_->sample(replay.sampling, seed_, step, 1, static_cast<std::size_t>(more), true);
  replayed_effects_ += static_cast<std::int64_t>(effects.size());
  return effects;
}

void Predictors::trainEffects(const std::vector<Memory::Ref>& updates) {
  for (const Memory::Ref& e : updates) trainEffects(*e);
}

void Predictors::trainEffects(const Experience& e) {
  if (!e.affordance) return;  // effect predictors learn from successes only
  const int a = e.action;
  Eigen::VectorXd target(input_size_);
  for (int i = 0; i < input_size_; ++i) target[i] = e.after_image[i] / 255.0;
  LastOutput& last = last_what_[static_cast<std::size_t>(a)];
  if (last.valid && last.image == e.before_image) {
    what_[a].train(inputOf(e), last.y, target, config_.what_effect_learning_rate, second_);
  } else {
    what_[a].train(inputOf(e), target, config_.what_effect_learning_rate, second_);
    ++what_outputs_;
  }
  last.valid = false;
  where_[a].train(whereInput(a, e.before_x, e.before_y, e.target_x, e.target_y), Eigen::Vector2d(e.after_x, e.after_y),
                  config_.where_effect_learning_rate);
}

std::vector<PerAction> Predictors::table(const std::vector<std::vector<std::uint8_t>>& probes) const {
  std::vector<PerAction> out;
  for (const auto& img : probes) out.push_back(predict(img).affordance);
  return out;
}

std::vector<double> Predictors::whatEffect(int action, const std::vector<std::uint8_t>& focus_image) const {
  LastOutput& last = last_what_[static_cast<std::size_t>(action)];
  if (!last.valid || last.image != focus_image) {
    last.y = what_[action].output(focusInput(focus_image), second_);
    last.image = focus_image;
    last.valid = true;
    ++what_outputs_;
  }
  return std::vector<double>(last.y.data(), last.y.data() + last.y.size());
}

std::array<double, 2> Predictors::whereEffect(int action, double x, double y, double tx, double ty) const {
  const Eigen::VectorXd p = where_[action].output(whereInput(action, x, y, tx, ty));
  return {p[0], p[1]};
}

namespace {
constexpr char kMagic[8] = {'A', 'F', 'F', 'O', 'R', 'D', 'C', 'K'};
// A checkpoint as written since issue 13: this magic, the size of the plain
// checkpoint (uint64), then the plain checkpoint (kMagic ...) deflated by zlib.
constexpr char kPackedMagic[8] = {'A', 'F', 'F', 'O', 'R', 'D', 'C', 'Z'};
// 1: weights and counters; 2: then a byte saying whether a memory follows, and the memory;
// 3: as 2, with the affordance component's kind (a length, then the name) after the header;
// 4: as 3, then the release that wrote it (a length, then afford --version), 0.2.0 on.
constexpr std::uint32_t kVersion = 4;
constexpr std::uint32_t kMostNameBytes = 64;
}  // namespace

template <class F>
void Predictors::forEachWeightArray(F&& f) const {
  for (int a = 0; a < kNumActions; ++a) {
    for (const StateArray& s : affordance_->state(a)) f(s.data, s.size);
    f(const_cast<double*>(what_[a].weights().data()), static_cast<std::size_t>(what_[a].weights().size()));
    f(const_cast<double*>(where_[a].weights().data()), static_cast<std::size_t>(where_[a].weights().size()));
  }
}

namespace {

// The plain checkpoint's bytes fed to zlib's deflate as they come, piece by
// piece (the weight arrays where they lie): no copy of the whole checkpoint
// is made, only the deflated bytes are kept.
class Deflater {
 public:
  explicit Deflater(const std::string& path) : path_(path) {
    if (deflateInit(&z_, Z_BEST_SPEED) != Z_OK) throw std::runtime_error("cannot compress checkpoint " + path_);
  }
  ~Deflater() { deflateEnd(&z_); }
  Deflater(const Deflater&) = delete;
  Deflater& operator=(const Deflater&) = delete;

  void write(const void* data, std::size_t n) {
    plain_ += n;
    const auto* p = static_cast<const Bytef*>(data);
    while (n > 0) {  // zlib takes at most a uInt at a time
      const auto part = static_cast<uInt>(std::min<std::size_t>(n, 1u << 30));
      z_.next_in = const_cast<Bytef*>(p);
      z_.avail_in = part;
      pump(Z_NO_FLUSH);
      p += part;
      n -= part;
    }
  }
  // The deflated bytes, once the plain ones are all written.
  const std::string& finish() {
    z_.next_in = nullptr;
    z_.avail_in = 0;
    pump(Z_FINISH);
    return packed_;
  }
  std::uint64_t plainSize() const { return plain_; }

 private:
  void pump(int flush) {
    for (;;) {
      z_.next_out = out_.data();
      z_.avail_out = static_cast<uInt>(out_.size());
      const int r = deflate(&z_, flush);
      if (r == Z_STREAM_ERROR) throw std::runtime_error("cannot compress checkpoint " + path_);
      packed_.append(reinterpret_cast<const char*>(out_.data()), out_.size() - z_.avail_out);
      // Room left: deflate took all the input (Z_NO_FLUSH), or said the end (Z_FINISH).
      if (flush == Z_FINISH ? r == Z_STREAM_END : z_.avail_out != 0) return;
    }
  }
  std::string path_, packed_;
  std::vector<Bytef> out_ = std::vector<Bytef>(std::size_t{1} << 18);
  z_stream z_{};
  std::uint64_t plain_ = 0;
};

}  // namespace

namespace {

// The plain checkpoint, inflated from `file` as it is read (a streambuf for loadFrom's istream).
class Inflater : public std::streambuf {
 public:
  explicit Inflater(std::istream& file) : file_(file) {
    if (inflateInit(&z_) != Z_OK) broken_ = true;
  }
  ~Inflater() override { inflateEnd(&z_); }
  Inflater(const Inflater&) = delete;
  Inflater& operator=(const Inflater&) = delete;
  bool broken() const { return broken_; }
  std::uint64_t produced() const { return produced_; }

 protected:
  int_type underflow() override {
    while (!broken_ && !ended_) {
      if (z_.avail_in == 0) {
        file_.read(reinterpret_cast<char*>(in_.data()), static_cast<std::streamsize>(in_.size()));
        z_.next_in = in_.data();
        z_.avail_in = static_cast<uInt>(file_.gcount());
        if (z_.avail_in == 0) {  // the file ended before the deflated stream did
          broken_ = true;
          break;
        }
      }
      z_.next_out = reinterpret_cast<Bytef*>(out_.data());
      z_.avail_out = static_cast<uInt>(out_.size());
      const int r = inflate(&z_, Z_NO_FLUSH);
      if (r == Z_STREAM_END) ended_ = true;
      else if (r != Z_OK && r != Z_BUF_ERROR) broken_ = true;
      const std::size_t n = out_.size() - z_.avail_out;
      if (n > 0) {
        produced_ += n;
        setg(out_.data(), out_.data(), out_.data() + n);
        return traits_type::to_int_type(out_[0]);
      }
    }
    return traits_type::eof();
  }

 private:
  std::istream& file_;
  z_stream z_{};
  std::vector<Bytef> in_ = std::vector<Bytef>(std::size_t{1} << 16);
  std::vector<char> out_ = std::vector<char>(std::size_t{1} << 18);
  std::uint64_t produced_ = 0;
  bool broken_ = false, ended_ = false;
};

}  // namespace

template <class Out>
void Predictors::writePlain(Out& raw, const std::string& checksum, const std::string& memory) const {
  raw.write(kMagic, sizeof kMagic);
  const std::uint32_t header[2] = {kVersion, static_cast<std::uint32_t>(input_size_)};
  raw.write(header, sizeof header);
  for (const std::string& name : {config_.affordance_kind, std::string(affordVersion())}) {
    const auto size = static_cast<std::uint32_t>(name.size());
    raw.write(&size, sizeof size);
    raw.write(name.data(), name.size());
  }
  forEachWeightArray([&](const double* d, std::size_t n) { raw.write(d, n * sizeof(double)); });
  raw.write(executed_.data(), sizeof executed_);
  raw.write(successes_.data(), sizeof successes_);
  const char has_memory = memory_ ? 1 : 0;
  raw.write(&has_memory, 1);
  if (memory_) {
    raw.write(&replayed_, sizeof replayed_);
    raw.write(&replayed_effects_, sizeof replayed_effects_);
    raw.write(memory.data(), memory.size());
  }
  raw.write(checksum.data(), checksum.size());
}

namespace {
// What a plain checkpoint writer is given: the byte count only.
struct Counter {
  std::uint64_t n = 0;
  void write(const void*, std::size_t size) { n += size; }
};
// ... or a snapshot.
struct ToSnapshot {
  SnapshotWriter& w;
  void write(const void* data, std::size_t size) { w.bytes(data, size); }
};
// A plain checkpoint read from a snapshot: exactly its `size` bytes, in chunks.
class FromSnapshot : public std::streambuf {
 public:
  FromSnapshot(SnapshotReader& r, std::uint64_t size) : r_(r), left_(size) {}
  std::uint64_t left() const { return left_ + static_cast<std::uint64_t>(egptr() - gptr()); }

 protected:
  int_type underflow() override {
    if (left_ == 0) return traits_type::eof();
    const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(left_, buffer_.size()));
    r_.bytes("predictors' weights", buffer_.data(), n);
    left_ -= n;
    setg(buffer_.data(), buffer_.data(), buffer_.data() + n);
    return traits_type::to_int_type(buffer_[0]);
  }

 private:
  SnapshotReader& r_;
  std::uint64_t left_;
  std::vector<char> buffer_ = std::vector<char>(std::size_t{1} << 16);
};

std::string memoryBytes(const Memory* memory) {
  if (!memory) return "";
  std::ostringstream out(std::ios::binary);
  memory->save(out);
  return out.str();
}
}  // namespace

void Predictors::save(SnapshotWriter& w) const {
  const std::string memory = memoryBytes(memory_.get());
  const std::string sum = weightsChecksum();
  Counter size;
  writePlain(size, sum, memory);
  w.i64(static_cast<std::int64_t>(size.n));
  ToSnapshot out{w};
  writePlain(out, sum, memory);
}

std::uint64_t Predictors::forwardModelBytes(int focus_side, WorldKind world) {
  const std::uint64_t input = 3ull * static_cast<std::uint64_t>(focus_side) * static_cast<std::uint64_t>(focus_side);
  std::uint64_t doubles = 0;
  for (int a = 0; a < kNumActions; ++a) doubles += input * (input + 1) + 2ull * (takesPlace(world, a) ? 5 : 3);  // what_, where_
  return doubles * sizeof(double);
}

void Predictors::load(SnapshotReader& r) {
  const auto size = static_cast<std::uint64_t>(r.within("predictors' weights", 0, std::int64_t{1} << 40));
  FromSnapshot plain(r, size);
  std::istream in(&plain);
  try {
    loadFrom(in, r.path());
  } catch (const std::runtime_error& e) {
    r.refuse("predictors' weights", e.what());
  }
  if (plain.left() != 0) r.refuse("predictors' weights", "more bytes than the weights of this run's predictors");
}

void Predictors::save(const std::string& path, const std::string& checksum) const {
  // The checkpoint's bytes, deflated as they are written: most of the forward
  // models' weights stay at their start, and a checkpoint shrinks about
  // twentyfold, losslessly.
  Deflater raw(path);
  writePlain(raw, checksum.empty() ? weightsChecksum() : checksum, memoryBytes(memory_.get()));
  const std::string& packed = raw.finish();
  // A file of this process's own, renamed into place: a reader never sees half
  // a checkpoint, and two writers of the same path do not clobber each other.
  const std::string tmp = path + ".tmp." + std::to_string(getpid());
  std::error_code ec;
  const auto parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw std::runtime_error("cannot write checkpoint " + tmp + ": " + std::strerror(errno));
    const std::uint64_t size = raw.plainSize();
    out.write(kPackedMagic, sizeof kPackedMagic);
    out.write(reinterpret_cast<const char*>(&size), sizeof size);
    out.write(packed.data(), static_cast<std::streamsize>(packed.size()));
    out.close();  // (what is still buffered is written here: a full disk says so now, not never)
    if (!out) {
      const int err = errno;
      std::filesystem::remove(tmp, ec);
      throw std::runtime_error("cannot write checkpoint " + tmp + ": " + std::strerror(err));
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) throw std::runtime_error("cannot rename " + tmp + " to " + path + ": " + std::strerror(errno));
}

void Predictors::load(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error("checkpoint " + path + ": cannot be read");
  char packed_magic[sizeof kPackedMagic];
  file.read(packed_magic, sizeof packed_magic);
  if (file && std::memcmp(packed_magic, kPackedMagic, sizeof kPackedMagic) == 0) {
    std::uint64_t size = 0;
    file.read(reinterpret_cast<char*>(&size), sizeof size);
    if (!file || size > (std::uint64_t{1} << 34))
      throw std::runtime_error("checkpoint " + path + ": truncated or of an impossible size");
    // Inflated as it is read, into the weights where they lie (no copy of the whole checkpoint is made). A
    // stream that ends early, breaks, or holds more or less than it says is refused.
    Inflater plain(file);
    std::istream in(&plain);
    bool whole = false;
    try {
      loadFrom(in, path);
      whole = in.peek() == std::char_traits<char>::eof() && !plain.broken() && plain.produced() == size;
    } catch (const std::runtime_error&) {
      in.clear();
      in.ignore(std::numeric_limits<std::streamsize>::max());  // the rest, to tell a whole stream from a broken one
      if (!plain.broken() && plain.produced() == size) throw;  // the data was whole: its content is refused
    }
    if (!whole) throw std::runtime_error("checkpoint " + path + ": its compressed data is corrupt or truncated");
    return;
  }
  file.clear();
  file.seekg(0);  // a checkpoint written before compression (format 1 or 2, plain)
  loadFrom(file, path);
}

void Predictors::loadFrom(std::istream& in, const std::string& path) {
  for (LastOutput& last : last_what_) last.valid = false;
  char magic[8];
  std::uint32_t header[2];
  in.read(magic, sizeof magic);
  in.read(reinterpret_cast<char*>(header), sizeof header);
  if (!in || std::memcmp(magic, kMagic, sizeof magic) != 0)
    throw std::runtime_error("checkpoint " + path + ": not an afford predictors checkpoint");
  if (header[0] < 1 || header[0] > kVersion)
    throw std::runtime_error("checkpoint " + path + ": format version " + std::to_string(header[0]) + ", expected 1 to " +
                             std::to_string(kVersion));
  if (header[1] != static_cast<std::uint32_t>(input_size_))
    throw std::runtime_error("checkpoint " + path + ": focus images of " + std::to_string(header[1]) +
                             " values, this run uses " + std::to_string(input_size_));
  const auto name = [&](const char* what) {
    std::uint32_t size = 0;
    in.read(reinterpret_cast<char*>(&size), sizeof size);
    if (!in || size > kMostNameBytes) throw std::runtime_error("checkpoint " + path + ": truncated, or not " + what);
    std::string s(size, '\0');
    in.read(s.data(), size);
    return s;
  };
  const std::string kind = header[0] >= 3 ? name("a component's name") : "paper";
  written_by_ = header[0] >= 4 ? name("a release's name") : "0.1.0 or earlier";
  if (kind != config_.affordance_kind)
    throw std::runtime_error("checkpoint " + path + ": its affordance predictor is '" + printable(kind) +
                             "', this run's predictors.affordance.kind is '" + config_.affordance_kind + "'");
  forEachWeightArray([&](double* d, std::size_t n) {
    in.read(reinterpret_cast<char*>(d), static_cast<std::streamsize>(n * sizeof(double)));
  });
  in.read(reinterpret_cast<char*>(executed_.data()), sizeof executed_);
  in.read(reinterpret_cast<char*>(successes_.data()), sizeof successes_);
  char has_memory = 0;
  if (header[0] >= 2) in.read(&has_memory, 1);
  if (!in) throw std::runtime_error("checkpoint " + path + ": truncated");
  if (has_memory) {
    // The memory travels with the weights (issue 11); an agent that kept one is restored with it, whatever this
    // run's configuration does with it.
    if (!memory_) memory_ = std::make_unique<Memory>(config_.memory, focus_side_);
    in.read(reinterpret_cast<char*>(&replayed_), sizeof replayed_);
    in.read(reinterpret_cast<char*>(&replayed_effects_), sizeof replayed_effects_);
    memory_->load(in, "checkpoint " + path);
  } else if (memory_) {
    throw std::runtime_error("checkpoint " + path + ": it holds no memory, and this run's predictors keep one "
                             "(predictors.replay, motivation.revisit): was it saved by another configuration?");
  }
  std::string sum(16, '\0');
  in.read(sum.data(), 16);
  if (!in) throw std::runtime_error("checkpoint " + path + ": truncated");
  if (sum != weightsChecksum()) throw std::runtime_error("checkpoint " + path + ": checksum mismatch (corrupt file)");
}

std::string Predictors::weightsChecksum() const {
  Fnv1a h;
  forEachWeightArray([&](const double* d, std::size_t n) { h.add(d, sizeof(double) * n); });
  if (memory_) {
    h.add(&replayed_, sizeof replayed_);
    h.add(&replayed_effects_, sizeof replayed_effects_);
    memory_->hash(h);
  }
  return h.hex();
}

}  // namespace afford

#include "experiment/design/truth_store.hpp"

#include <mujoco/mujoco.h>

#include <fcntl.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "afford/checksum.hpp"
#include "afford/file_lock.hpp"
#include "afford/version.hpp"
#include "afford/yaml_reader.hpp"
#include "environment/table/truth.hpp"

namespace afford {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Holds the lock file `path` (made if missing) once the file held is the one the path names: a holder removes it
// as it lets go, so one that waited may hold a file no longer there, and takes the new one.
bool holdCurrent(HeldFile& held, const std::string& path, bool wait) {
  for (;;) {
    if (!(wait ? held.hold(path, HeldFile::Mode::Exclusive, O_RDWR | O_CREAT)
               : held.tryHold(path, HeldFile::Mode::Exclusive, O_RDWR | O_CREAT)))
      return false;
    struct stat mine {}, named {};
    if (::fstat(held.fd(), &mine) == 0 && ::stat(path.c_str(), &named) == 0 && mine.st_ino == named.st_ino &&
        mine.st_dev == named.st_dev)
      return true;
    held.release();
  }
}

// The lock file removed while still held (declared after the HeldFile, so it goes first), and the folder made for
// the estimate if it holds nothing.
struct LockRemoval {
  std::string lock;
  std::filesystem::path made;
  LockRemoval(const LockRemoval&) = delete;
  LockRemoval& operator=(const LockRemoval&) = delete;
  ~LockRemoval() {
    std::error_code ec;
    std::filesystem::remove(lock, ec);
    if (!made.empty() && std::filesystem::is_empty(made, ec)) std::filesystem::remove(made, ec);
  }
};

// A stored table is read only up to this size (one of a hundred objects is about 60 kB).
constexpr std::uintmax_t kMostTableBytes = 4u << 20;

json tableJson(const table::TruthTable& t, const std::vector<int>& objects) {
  json rows = json::array();
  for (int i : objects) {
    json row{{"object", t.objects[static_cast<std::size_t>(i)]}};
    for (int a = 0; a < table::kTableActions; ++a) {
      const table::TruthCell& c = t.cells[static_cast<std::size_t>(i)][static_cast<std::size_t>(a)];
      row[table::tableActionName(a)] = {{"successes", c.successes}, {"trials", c.trials}, {"rate", c.rate()},
                                        {"low", c.low()}, {"high", c.high()}};
    }
    rows.push_back(row);
  }
  return rows;
}

}  // namespace

StoredTruth storedTruth(const YAML::Node& node, const RunConfig& cfg, const TruthRequest& a,
                        const std::function<void(const std::string&)>& log_warning,
                        const std::function<void(int, int)>& progress) {
  const table::TableWorldConfig& tw = cfg.table;
  const int trials = a.trials > 0 ? a.trials : tw.truth_trials;
  std::vector<int> objects = a.objects;
  if (objects.empty())
    for (std::size_t i = 0; i < tw.spec.objects.size(); ++i) objects.push_back(static_cast<int>(i));
  // The table's section without the truth a run is given (table.objects[i].affordance): the same world.
  YAML::Node table = YAML::Clone(node["table"]);
  if (table["objects"].IsSequence())
    for (YAML::Node o : table["objects"]) o.remove("affordance");
  Fnv1a h;
  std::string key_text = emitYaml(table) + "\nseed " + std::to_string(a.seed) + "\ntrials " + std::to_string(trials) +
                         "\nobjects ";
  for (int i : objects) key_text += std::to_string(i) + ",";
  key_text += "\ncode " + a.code + "\nmujoco " + std::to_string(mj_version());
  h.add(key_text.data(), key_text.size());
  StoredTruth out;
  const fs::path file = fs::path(a.out) / (a.experiment + "-" + h.hex() + ".json");
  out.file = file.string();
  // A stored table: `path`'s, if it holds one of a row an object (else why not, when `say`).
  const auto read = [&](const fs::path& path, bool say) {
    std::error_code size_error;
    const auto size = fs::file_size(path, size_error);
    if (size_error) return false;
    if (size > kMostTableBytes) {
      if (say)
        log_warning(path.string() + ": " + std::to_string(size) + " bytes, more than a truth table holds (" +
                    std::to_string(kMostTableBytes) + "); estimating again");
      return false;
    }
    std::ifstream in(path);
    try {
      const json stored = json::parse(in);
      if (stored.at("key").get<std::string>() != h.hex()) throw std::runtime_error("its key is another world's");
      out.rows = stored.at("table");
      if (!out.rows.is_array() || out.rows.size() != objects.size()) throw std::runtime_error("not one row an object");
      out.file = path.string();
      return true;
    } catch (const std::exception& e) {
      if (say) log_warning(path.string() + ": not a truth table (" + e.what() + "); estimating again");
      return false;
    }
  };
  if (!a.fresh && read(file, true)) return out;
  // The same world estimated under another experiment's name (table-extrinsic extends table): the digest says so.
  std::error_code listing;
  if (!a.fresh)
    for (const auto& e : fs::directory_iterator(a.out, listing)) {
      const std::string name = e.path().filename().string(), tail = "-" + h.hex() + ".json";
      if (e.path() != file && name.size() > tail.size() && name.compare(name.size() - tail.size(), tail.size(), tail) == 0 &&
          read(e.path(), false))
        return out;
    }
  // One estimate of a world at a time in a folder (the workers of a study share one): a second process waits for
  // the first's lock, then reads what it wrote. The lock file is removed when the estimate ends, however it ends,
  // and a folder made for it removed again unless a table was written: an interrupted estimate leaves nothing.
  const fs::path dir = file.parent_path();
  const bool made = !fs::exists(dir);
  fs::create_directories(dir);
  HeldFile estimating;
  const std::string lock = file.string() + ".lock";
  if (!holdCurrent(estimating, lock, false)) {
    if (errno != EWOULDBLOCK) throw std::runtime_error("cannot create " + lock + ": " + std::strerror(errno));
    log_warning("another process is estimating this truth (it holds " + lock + "): waiting for it");
    if (!holdCurrent(estimating, lock, true)) throw std::runtime_error("cannot lock " + lock + ": " + std::strerror(errno));
  }
  const LockRemoval removal{lock, made ? dir : fs::path()};
  if (!a.fresh && read(file, false)) return out;  // written by a process that held the lock meanwhile
  const table::TruthTable t = table::estimateTruth(tw.spec, tw.primitives, tw.truth, a.seed, trials, objects, progress);
  out.rows = tableJson(t, objects);
  out.estimated = true;
  const json stored{{"experiment", a.experiment}, {"seed", a.seed}, {"trials", trials}, {"afford", affordVersion()},
                    {"mujoco", mj_version()}, {"key", h.hex()}, {"table", out.rows}};
  const fs::path tmp = file.string() + ".part";  // (written under the lock: no other writer of it)
  {
    std::ofstream f(tmp);
    f << stored.dump(2) << "\n";
    if (!f) throw std::runtime_error("cannot write " + tmp.string());
  }
  fs::rename(tmp, file);
  return out;
}

std::string truthSetting(const YAML::Node& node, const json& rows) {
  YAML::Node objects = YAML::Clone(node["table"]["objects"]);
  if (!objects.IsSequence() || objects.size() != rows.size())
    throw std::invalid_argument("the truth has " + std::to_string(rows.size()) + " rows for the table's objects");
  for (std::size_t i = 0; i < rows.size(); ++i) {
    YAML::Node affordance(YAML::NodeType::Sequence);
    for (int a = 0; a < table::kTableActions; ++a) affordance.push_back(rows[i].at(table::tableActionName(a)).at("rate").get<double>());
    affordance.SetStyle(YAML::EmitterStyle::Flow);
    objects[i]["affordance"] = affordance;
  }
  YAML::Emitter e;
  e.SetMapFormat(YAML::Flow);
  e.SetSeqFormat(YAML::Flow);
  e.SetDoublePrecision(17);
  e << objects;
  return std::string("table.objects=") + e.c_str();
}

}  // namespace afford

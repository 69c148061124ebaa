#include "afford/drop_log.hpp"

#include <algorithm>
#include <cctype>
#include <vector>

namespace afford {

namespace {
// A reason without its numbers: drops that differ only in a serial, a step or a size are of one kind.
std::string kindOf(const std::string& channel, const std::string& why) {
  std::string k = channel + ": ";
  bool in_number = false;
  for (char c : why) {
    const bool digit = std::isdigit(static_cast<unsigned char>(c)) != 0;
    if (digit && !in_number) k += '#';
    if (!digit) k += c;
    in_number = digit;
  }
  return k;
}
}  // namespace

DropLog::Kind& DropLog::kind(const std::string& key, const std::string& example) {
  const bool other = !kinds_.count(key) && kinds_.size() >= static_cast<std::size_t>(kKinds);
  Kind& k = kinds_[other ? "other" : key];
  if (k.example.empty()) k.example = other ? "other reasons" : example;
  return k;
}

void DropLog::unsaid(Kind& k, Clock::time_point now) {
  if (unsaid_++ == 0) first_unsaid_ = now;
  ++k.unsaid;
  if (now - last_line_ >= delay_) {
    summarise("so far");
    delay_ = std::min<Clock::duration>(delay_ * 2, kLongestDelay);
  }
}

void DropLog::drop(const std::string& channel, const std::string& why) {
  const auto now = Clock::now();
  Kind& k = kind(kindOf(channel, why), channel + ": " + why);
  if (k.said < kSaidPerKind && said_ < kSaidAtMost) {
    ++k.said;
    ++said_;
    last_line_ = now;
    log_->warn("{}: dropped message: {}{}", channel, why,
               k.said == kSaidPerKind || said_ == kSaidAtMost ? " (more drops are counted and summarised)" : "");
    return;
  }
  unsaid(k, now);
}

void DropLog::keyMismatch(const std::string& channel, KeyMismatch m) {
  const auto now = Clock::now();
  const std::string hint = keyHint(m);
  if (hinted_.insert(m).second) {
    last_line_ = now;
    log_->warn("{} (first on {}: such messages are dropped, and counted below)", hint, channel);
    return;
  }
  unsaid(kind(hint, hint), now);
}

void DropLog::summarise(const char* when) {
  if (unsaid_ == 0) return;
  std::vector<std::pair<std::int64_t, const Kind*>> by_count;
  for (const auto& [key, k] : kinds_)
    if (k.unsaid > 0) by_count.emplace_back(k.unsaid, &k);
  std::sort(by_count.begin(), by_count.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::string kinds;
  for (std::size_t i = 0; i < by_count.size() && i < 4; ++i)
    kinds += (i ? "; " : "") + std::to_string(by_count[i].first) + " like \"" + by_count[i].second->example + "\"";
  if (by_count.size() > 4) kinds += "; and " + std::to_string(by_count.size() - 4) + " other kind(s)";
  const double seconds = std::chrono::duration<double>(Clock::now() - first_unsaid_).count();
  log_->warn("dropped {} more message(s) in {:.1f} s ({}): {}", unsaid_, seconds, when, kinds);
  for (auto& [key, k] : kinds_) k.unsaid = 0;
  unsaid_ = 0;
  last_line_ = Clock::now();
}

void DropLog::flush() {
  summarise("until now");
  kinds_.clear();
  said_ = 0;
  delay_ = kFirstDelay;
}

}  // namespace afford

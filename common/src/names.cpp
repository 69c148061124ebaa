#include "afford/names.hpp"

#include <cstdio>

namespace afford {

std::string runIdProblem(const std::string& id, int max_bytes) {
  if (id.empty()) return "is empty";
  if (static_cast<long>(id.size()) > max_bytes)
    return "has " + std::to_string(id.size()) + " bytes, more than " + std::to_string(max_bytes) +
           " (protocol.limits.run_id_bytes)";
  if (id[0] == '.' || id[0] == '-') return std::string("begins with '") + id[0] + "'";
  for (unsigned char c : id) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                    c == '_' || c == '-';
    if (!ok) {
      char shown[8];
      std::snprintf(shown, sizeof shown, c >= 0x20 && c < 0x7f ? "'%c'" : "\\x%02x", c);
      return std::string("has the character ") + shown + " (letters, digits, '.', '_' and '-' only)";
    }
  }
  return "";
}

std::string printable(const std::string& text, std::size_t max_bytes) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (out.size() >= max_bytes) return out + "...";
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    }
  }
  return out;
}

bool insideFolder(const std::filesystem::path& path, const std::filesystem::path& root) {
  std::error_code ec;
  const std::filesystem::path p = std::filesystem::weakly_canonical(std::filesystem::absolute(path, ec), ec);
  if (ec) return false;
  const std::filesystem::path r = std::filesystem::weakly_canonical(std::filesystem::absolute(root, ec), ec);
  if (ec) return false;
  const std::filesystem::path rel = p.lexically_relative(r);
  // Strictly inside: not the root itself, and not climbing out of it.
  return !rel.empty() && rel != "." && *rel.begin() != "..";
}

}  // namespace afford

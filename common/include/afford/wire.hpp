// The wire check that runs before LCM's decode (docs/processes-and-channels.md).
// LCM 1.3.1's generated decode sizes its vectors from counts read off the wire
// before it checks that the bytes are there, and its array sizes wrap for
// large counts: one hostile datagram can crash a process or make it allocate
// gigabytes. checkWire walks an encoding with bounds checks only: the
// fingerprint, every field, every count against the bytes left and against a
// maximum of its own, and no trailing byte. The walk of each type and the
// struct of its maxima are generated from lcmtypes/*.lcm by afford-lcmwire
// (tools/lcmwire) into "afford/wire_bounds.hpp"; afford/bounds.hpp gives the
// maxima of a run.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <string>
#include <vector>

namespace afford::wire {

// The most a count or a string may hold. No default constructor on purpose:
// a bounds struct that forgets a member does not compile.
struct Max {
  explicit constexpr Max(std::int64_t v) : value(v) {}
  std::int64_t value;
};

// Where a size field sits in an encoding (for fuzzing).
struct SizeField {
  std::size_t offset;   // of its first byte, fingerprint included
  int width;            // bytes, big-endian, signed
  std::string field;    // its path, e.g. "n_actions", "trained[0].run_id"
  std::int64_t max;     // the largest value accepted on the wire
  bool is_string = false;  // a string's length: it counts the NUL, and so does max
};

// Elements of a multi-dimensional array: the product of its dimensions, or -1
// when a dimension is negative or the product overflows.
constexpr std::int64_t product(std::initializer_list<std::int64_t> dims) {
  for (std::int64_t d : dims)
    if (d <= 0) return d == 0 ? 0 : -1;
  std::int64_t n = 1;
  for (std::int64_t d : dims) {
    if (n > std::numeric_limits<std::int64_t>::max() / d) return -1;
    n *= d;
  }
  return n;
}

// A bounds-checked walk over one encoded message; keeps the first failure.
class Cursor {
 public:
  Cursor(const void* data, std::size_t size, std::vector<SizeField>* sizes = nullptr);

  bool fingerprint(std::int64_t expected, const char* type);
  // Skip `count` elements of `element_bytes` each.
  bool primitive(const char* field, std::size_t element_bytes, std::int64_t count);
  // A signed big-endian count of `width` bytes: 0 <= value <= max.value.
  bool size(const char* field, int width, Max max, std::int64_t& value);
  // Length with the NUL in [1, bytes left], at most max.value bytes before it,
  // ending with the NUL and holding no other: LCM's decode keeps a NUL inside
  // the string, its encode stops at it.
  bool string(const char* field, Max max);

  // One element of array `field` (a string or a nested struct) at `index`:
  // inside `scan`, errors and recorded sizes are named field[i][j]...
  // For a nested struct that is not an array, `index` is empty.
  template <class Scan>
  bool element(const char* field, std::initializer_list<std::int64_t> index, Scan&& scan) {
    enter(field, index);
    const bool ok = scan();
    leave();
    return ok;
  }

  std::size_t offset() const { return offset_; }
  std::size_t left() const { return size_ - offset_; }
  const std::string& error() const { return error_; }
  bool failed() const { return failed_; }

 private:
  struct Segment {
    const char* field;
    std::size_t first_index, n_index;  // into indices_
  };
  void enter(const char* field, std::initializer_list<std::int64_t> index);
  void leave();
  std::string path(const char* field) const;  // "trained[0].run_id"
  bool fail(const std::string& what);
  bool need(const char* field, std::size_t bytes);  // fails naming field when fewer are left
  std::int64_t read(int width) const;               // signed big-endian at offset_
  void record(std::size_t at, int width, const char* field, std::int64_t max, bool is_string);

  const unsigned char* data_;
  std::size_t size_;
  std::size_t offset_ = 0;
  std::vector<SizeField>* sizes_;
  std::vector<Segment> segments_;
  std::vector<std::int64_t> indices_;
  std::string error_;
  bool failed_ = false;
};

// Specialised for every type by the generated "afford/wire_bounds.hpp":
// type (the struct of maxima), kName, kMessage, kSerial, scan().
template <class Msg>
struct Bounds;

// Is the whole buffer one Msg within `b`? Fingerprint, every field, and no
// trailing byte. On failure `why` names the field.
template <class Msg>
bool checkWire(const void* data, std::size_t size, const typename Bounds<Msg>::type& b, std::string& why,
               std::vector<SizeField>* sizes = nullptr) {
  Cursor c(data, size, sizes);
  if (!c.fingerprint(Msg::getHash(), Bounds<Msg>::kName) || !Bounds<Msg>::scan(c, b)) {
    why = c.error();
    return false;
  }
  if (c.left() != 0) {
    why = std::to_string(c.left()) + " trailing byte" + (c.left() == 1 ? "" : "s") + " after the last field of " +
          Bounds<Msg>::kName;
    return false;
  }
  why.clear();
  return true;
}

// ---- Cursor ------------------------------------------------------------------------

inline Cursor::Cursor(const void* data, std::size_t size, std::vector<SizeField>* sizes)
    : data_(static_cast<const unsigned char*>(data)), size_(data ? size : 0), sizes_(sizes) {}

inline bool Cursor::fingerprint(std::int64_t expected, const char* type) {
  if (failed_) return false;
  if (left() < 8)
    return fail(std::string("fingerprint of ") + type + ": 8 bytes needed, " + std::to_string(left()) + " left");
  const std::int64_t got = read(8);
  if (got != expected) {
    auto hex = [](std::int64_t v) {
      static const char* digits = "0123456789abcdef";
      std::string s = "0x";
      for (int shift = 60; shift >= 0; shift -= 4) s += digits[(static_cast<std::uint64_t>(v) >> shift) & 0xf];
      return s;
    };
    return fail("fingerprint " + hex(got) + " is not " + type + "'s " + hex(expected));
  }
  offset_ += 8;
  return true;
}

inline bool Cursor::primitive(const char* field, std::size_t element_bytes, std::int64_t count) {
  if (failed_) return false;
  if (count < 0) return fail("field " + path(field) + ": its element count overflows");
  const auto n = static_cast<std::uint64_t>(count);
  if (element_bytes != 0 && n > left() / element_bytes) {
    if (n > std::numeric_limits<std::uint64_t>::max() / element_bytes)
      return fail("field " + path(field) + ": " + std::to_string(n) + " elements of " +
                  std::to_string(element_bytes) + " bytes needed, " + std::to_string(left()) + " bytes left");
    return fail("field " + path(field) + ": " + std::to_string(n * element_bytes) + " bytes needed, " +
                std::to_string(left()) + " left");
  }
  offset_ += static_cast<std::size_t>(n * element_bytes);
  return true;
}

inline bool Cursor::size(const char* field, int width, Max max, std::int64_t& value) {
  if (failed_ || !need(field, static_cast<std::size_t>(width))) return false;
  const std::int64_t v = read(width);
  record(offset_, width, field, max.value, false);
  if (v < 0) return fail("field " + path(field) + " = " + std::to_string(v) + " is negative");
  if (v > max.value)
    return fail("field " + path(field) + " = " + std::to_string(v) + " exceeds its maximum " +
                std::to_string(max.value));
  value = v;
  offset_ += static_cast<std::size_t>(width);
  return true;
}

inline bool Cursor::string(const char* field, Max max) {
  if (failed_ || !need(field, 4)) return false;
  const std::int64_t length = read(4);  // counts the NUL
  const std::int64_t wire_max =
      max.value < std::numeric_limits<std::int64_t>::max() ? max.value + 1 : max.value;
  record(offset_, 4, field, wire_max, true);
  const std::size_t after = left() - 4;  // bytes after the length
  if (length < 1)
    return fail("field " + path(field) + ": string length " + std::to_string(length) +
                " is below 1 (it counts the NUL)");
  if (static_cast<std::uint64_t>(length) > after)
    return fail("field " + path(field) + ": " + std::to_string(length) + " bytes needed, " + std::to_string(after) +
                " left");
  if (length - 1 > max.value)
    return fail("field " + path(field) + ": " + std::to_string(length - 1) + " bytes exceed its maximum " +
                std::to_string(max.value));
  const auto end = offset_ + 4 + static_cast<std::size_t>(length);
  if (data_[end - 1] != 0) return fail("field " + path(field) + ": the string does not end with a NUL");
  if (std::memchr(data_ + offset_ + 4, 0, static_cast<std::size_t>(length - 1)) != nullptr)
    return fail("field " + path(field) + ": the string holds a NUL before its end");
  offset_ = end;
  return true;
}

inline void Cursor::enter(const char* field, std::initializer_list<std::int64_t> index) {
  segments_.push_back({field, indices_.size(), index.size()});
  indices_.insert(indices_.end(), index.begin(), index.end());
}

inline void Cursor::leave() {
  indices_.resize(segments_.back().first_index);
  segments_.pop_back();
}

inline std::string Cursor::path(const char* field) const {
  std::string p;
  for (const Segment& s : segments_) {
    if (!p.empty()) p += '.';
    p += s.field;
    for (std::size_t i = 0; i < s.n_index; ++i) p += '[' + std::to_string(indices_[s.first_index + i]) + ']';
  }
  if (field && *field) {
    if (!p.empty()) p += '.';
    p += field;
  }
  return p;
}

inline bool Cursor::fail(const std::string& what) {
  if (!failed_) error_ = what;
  failed_ = true;
  return false;
}

inline bool Cursor::need(const char* field, std::size_t bytes) {
  if (left() >= bytes) return true;
  return fail("field " + path(field) + ": " + std::to_string(bytes) + " bytes needed, " + std::to_string(left()) +
              " left");
}

inline std::int64_t Cursor::read(int width) const {
  std::uint64_t u = 0;
  for (int i = 0; i < width; ++i) u = (u << 8) | data_[offset_ + static_cast<std::size_t>(i)];
  if (width < 8 && (u >> (8 * width - 1)) != 0) u |= ~std::uint64_t{0} << (8 * width);  // sign-extend
  return static_cast<std::int64_t>(u);
}

inline void Cursor::record(std::size_t at, int width, const char* field, std::int64_t max, bool is_string) {
  if (sizes_) sizes_->push_back({at, width, path(field), max, is_string});
}

}  // namespace afford::wire

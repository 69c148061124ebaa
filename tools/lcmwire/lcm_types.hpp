// afford-lcmwire's reading of the .lcm language (lcm_types.cpp): the types
// of the given files, checked against the project's message rules, for the
// writers of lcmwire.cpp. A host tool of the build: the standard library only.
#pragma once
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace lcmwire {


class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The largest constant array dimension (and product of a field's constant
// dimensions): a message of more elements would exceed any bus's largest message.
inline constexpr std::int64_t kMaxConstantDimension = 1 << 20;

// Throws Error("file:line: what").
[[noreturn]] void fail(const std::string& file, int line, const std::string& what);


// Encoded bytes of each primitive type (a string is a length and its bytes).
extern const std::map<std::string, int> kPrimitiveBytes;
bool isPrimitive(const std::string& type);
bool isCountType(const std::string& type);

struct Struct;

struct Dim {
  std::string field;      // the earlier integer field holding the size; empty for a constant
  std::int64_t size = 0;  // a constant dimension
};

struct Field {
  std::string type;  // as written: a primitive, "name" or "package.name"
  std::string name;
  std::vector<Dim> dims;
  int line = 0;
  const Struct* nested = nullptr;  // the struct type, once resolved
};

struct Struct {
  std::string file;
  int line = 0;
  std::string package;  // "" or "a.b"
  std::string name;
  std::vector<Field> fields;
  bool part = false;  // some other type has a field of this type
  std::string full() const { return package.empty() ? name : package + "." + name; }
};


const Field* findField(const Struct& s, const std::string& name);
// Carries run_id, step, serial, prev_digest first.
bool carriesSerial(const Struct& s);

// The C++ type lcm-gen makes of it ("::afford::scene_t"), and its header ("afford/scene_t.hpp").
std::string cppType(const Struct& s);
std::string lcmHeader(const Struct& s);

// The types of the files, parsed, resolved and checked (the message rules); throws Error "file:line: what".
std::vector<Struct> readTypes(const std::vector<std::string>& files);

}  // namespace lcmwire

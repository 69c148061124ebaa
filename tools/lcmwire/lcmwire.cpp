// afford-lcmwire: reads the project's .lcm files and writes wire_bounds.hpp,
// the bounds check of every type's encoding (afford/wire.hpp) that runs
// before LCM's decode: one struct of maxima and one straight-line scan per type.
//
//   afford-lcmwire --out build/lcmgen/cpp/afford/wire_bounds.hpp lcmtypes/*.lcm
//
// With --python-out FILE it also writes each type's conversion to a Python
// dict (pybind11), for the Python package.
//
// It fails with "file:line: what" on anything it does not understand and on
// the project's message rules: a message type (one that is
// no other type's field) begins with `string run_id; int64_t step;` and ends
// with `int64_t digest;`; a field `serial` is the third, an int64_t, and
// `int64_t prev_digest;` follows it; a dimension names an earlier integer
// field or is a constant of at most kMaxConstantDimension (also their product).
// A host tool of the build: the standard library only.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The largest constant array dimension (and product of a field's constant
// dimensions): a message of more elements would exceed any bus's largest message.
constexpr std::int64_t kMaxConstantDimension = 1 << 20;

[[noreturn]] void fail(const std::string& file, int line, const std::string& what) {
  throw Error(file + ":" + std::to_string(line) + ": " + what);
}

// ---- the .lcm language ----------------------------------------------------------------

struct Token {
  enum Kind { kWord, kNumber, kPunct, kEnd } kind = kEnd;
  std::string text;
  int line = 0;
};

std::string describe(const Token& t) { return t.kind == Token::kEnd ? "end of file" : "'" + t.text + "'"; }

bool wordStart(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool wordChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.'; }
bool digit(char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }

std::vector<Token> lex(const std::string& file, const std::string& text) {
  std::vector<Token> out;
  int line = 1;
  std::size_t i = 0;
  const std::size_t n = text.size();
  while (i < n) {
    const char c = text[i];
    if (c == '\n') {
      ++line, ++i;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
    } else if (c == '/' && i + 1 < n && text[i + 1] == '/') {
      while (i < n && text[i] != '\n') ++i;
    } else if (c == '/' && i + 1 < n && text[i + 1] == '*') {
      const int start = line;
      i += 2;
      while (i + 1 < n && !(text[i] == '*' && text[i + 1] == '/')) line += text[i++] == '\n';
      if (i + 1 >= n) fail(file, start, "unterminated /* comment");
      i += 2;
    } else if (wordStart(c)) {
      const std::size_t s = i;
      while (i < n && wordChar(text[i])) ++i;
      out.push_back({Token::kWord, text.substr(s, i - s), line});
    } else if (digit(c) || (c == '.' && i + 1 < n && digit(text[i + 1]))) {
      const std::size_t s = i;
      const bool hex = c == '0' && i + 1 < n && (text[i + 1] == 'x' || text[i + 1] == 'X');
      while (i < n) {
        const char d = text[i];
        const char prev = i > s ? text[i - 1] : '\0';
        const bool exponent_sign = !hex && (d == '+' || d == '-') && (prev == 'e' || prev == 'E');
        if (!(std::isalnum(static_cast<unsigned char>(d)) || d == '.' || d == '_' || exponent_sign)) break;
        ++i;
      }
      out.push_back({Token::kNumber, text.substr(s, i - s), line});
    } else if (std::string("{}[];=,-+").find(c) != std::string::npos) {
      out.push_back({Token::kPunct, std::string(1, c), line});
      ++i;
    } else {
      fail(file, line, std::string("unexpected character '") + c + "'");
    }
  }
  out.push_back({Token::kEnd, "", line});
  return out;
}

// Encoded bytes of each primitive type (a string is a length and its bytes).
const std::map<std::string, int> kPrimitiveBytes = {
    {"int8_t", 1}, {"int16_t", 2}, {"int32_t", 4}, {"int64_t", 8}, {"byte", 1},
    {"boolean", 1}, {"float", 4},  {"double", 8},  {"string", 0}};

bool isPrimitive(const std::string& type) { return kPrimitiveBytes.count(type) != 0; }
bool isCountType(const std::string& type) {
  return type == "int8_t" || type == "int16_t" || type == "int32_t" || type == "int64_t";
}

bool isIdentifier(const std::string& s) {
  if (s.empty() || !wordStart(s[0])) return false;
  return std::all_of(s.begin(), s.end(), [](char c) { return wordChar(c) && c != '.'; });
}
bool isDottedName(const std::string& s) {
  std::stringstream in(s);
  std::string part;
  int parts = 0;
  while (std::getline(in, part, '.')) {
    if (!isIdentifier(part)) return false;
    ++parts;
  }
  return parts > 0 && s.back() != '.';
}

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

class Parser {
 public:
  Parser(std::string file, std::vector<Token> tokens) : file_(std::move(file)), tokens_(std::move(tokens)) {}

  void parse(std::vector<Struct>& out) {
    bool seen_package = false, seen_struct = false;
    std::string package;
    while (peek().kind != Token::kEnd) {
      const Token t = next();
      if (t.text == "package" && t.kind == Token::kWord) {
        if (seen_package) fail(file_, t.line, "a second package statement");
        if (seen_struct) fail(file_, t.line, "the package statement must come before the structs");
        const Token name = next();
        if (name.kind != Token::kWord || !isDottedName(name.text))
          fail(file_, name.line, "expected a package name, got " + describe(name));
        expect(";");
        package = name.text;
        seen_package = true;
      } else if (t.text == "struct" && t.kind == Token::kWord) {
        out.push_back(parseStruct(t.line, package));
        seen_struct = true;
      } else if (t.text == "enum" && t.kind == Token::kWord) {
        fail(file_, t.line, "enum is not supported (use consts)");
      } else {
        fail(file_, t.line, "expected 'package' or 'struct', got " + describe(t));
      }
    }
    if (!seen_struct) fail(file_, peek().line, "no struct in this file");
  }

 private:
  const Token& peek() const { return tokens_[pos_]; }
  Token next() {
    const Token t = tokens_[pos_];
    if (t.kind != Token::kEnd) ++pos_;
    return t;
  }
  bool accept(const char* text) {
    if (peek().kind == Token::kPunct && peek().text == text) return ++pos_, true;
    return false;
  }
  void expect(const char* text) {
    if (!accept(text)) fail(file_, peek().line, std::string("expected '") + text + "', got " + describe(peek()));
  }
  std::string identifier(const char* what) {
    const Token t = next();
    if (t.kind != Token::kWord || !isIdentifier(t.text))
      fail(file_, t.line, std::string("expected ") + what + ", got " + describe(t));
    return t.text;
  }

  Struct parseStruct(int line, const std::string& package) {
    Struct s;
    s.file = file_;
    s.line = line;
    s.package = package;
    s.name = identifier("a struct name");
    expect("{");
    std::map<std::string, int> declared;  // field and const names -> line
    auto declare = [&](const std::string& name, int at) {
      const auto [it, fresh] = declared.emplace(name, at);
      if (!fresh)
        fail(file_, at, "'" + name + "' is declared twice (first at line " + std::to_string(it->second) + ")");
    };
    while (!accept("}")) {
      if (peek().kind == Token::kEnd) fail(file_, line, "struct " + s.name + " is not closed with '}'");
      if (peek().kind == Token::kWord && peek().text == "const") {
        next();
        parseConst(declare);
      } else {
        parseMember(s, declare);
      }
    }
    accept(";");
    return s;
  }

  template <class Declare>
  void parseConst(Declare& declare) {
    const Token type = next();
    const bool integer = isCountType(type.text) || type.text == "byte";
    if (type.kind != Token::kWord || !(integer || type.text == "float" || type.text == "double"))
      fail(file_, type.line, "a const of type " + describe(type) + " is not supported");
    do {
      const int at = peek().line;
      const std::string name = identifier("a const name");
      declare(name, at);
      expect("=");
      std::string value;
      if (accept("-")) value = "-";
      else accept("+");
      const Token number = next();
      if (number.kind != Token::kNumber) fail(file_, number.line, "expected a number, got " + describe(number));
      value += number.text;
      if (!validConst(type.text, value)) fail(file_, number.line, "'" + value + "' is not a valid " + type.text);
    } while (accept(","));
    expect(";");
  }

  static bool validConst(const std::string& type, const std::string& value) {
    errno = 0;
    char* end = nullptr;
    if (type == "float" || type == "double") {
      std::strtod(value.c_str(), &end);
      return *end == '\0' && errno == 0;
    }
    const long long v = std::strtoll(value.c_str(), &end, 0);
    if (*end != '\0' || errno != 0) return false;
    const int bits = 8 * kPrimitiveBytes.at(type);
    if (bits == 64) return true;
    const long long hi = (1LL << (bits - 1)) - 1;
    return v >= -hi - 1 && v <= (type == "byte" ? 255 : hi);
  }

  template <class Declare>
  void parseMember(Struct& s, Declare& declare) {
    const Token type = next();
    if (type.kind != Token::kWord || !(isPrimitive(type.text) || isDottedName(type.text)))
      fail(file_, type.line, "expected a field type, got " + describe(type));
    do {
      Field f;
      f.type = type.text;
      f.line = peek().line;
      f.name = identifier("a field name");
      declare(f.name, f.line);
      while (accept("[")) {
        const Token d = next();
        Dim dim;
        if (d.kind == Token::kWord && isIdentifier(d.text)) {
          dim.field = d.text;
        } else if (d.kind == Token::kNumber && std::all_of(d.text.begin(), d.text.end(), digit)) {
          // The generated scan multiplies constant dimensions: keep every product far from overflow.
          if (d.text.size() > 7 || std::stoll(d.text) > kMaxConstantDimension)
            fail(file_, d.line, "constant dimension " + d.text + " of field '" + f.name + "' is larger than " +
                                    std::to_string(kMaxConstantDimension) + ", the most lcmwire accepts");
          dim.size = std::stoll(d.text);
          std::int64_t product = dim.size;
          for (const Dim& earlier : f.dims) product *= earlier.field.empty() ? earlier.size : 1;
          if (product > kMaxConstantDimension)
            fail(file_, d.line, "the constant dimensions of field '" + f.name + "' hold " + std::to_string(product) +
                                    " elements, more than " + std::to_string(kMaxConstantDimension) +
                                    ", the most lcmwire accepts");
        } else {
          fail(file_, d.line, "dimension " + describe(d) + " of field '" + f.name +
                                  "' must name an earlier integer field or be a constant");
        }
        f.dims.push_back(dim);
        expect("]");
      }
      s.fields.push_back(f);
    } while (accept(","));
    expect(";");
  }

  std::string file_;
  std::vector<Token> tokens_;
  std::size_t pos_ = 0;
};

// ---- meaning and project rules ---------------------------------------------------------

const Field* findField(const Struct& s, const std::string& name) {
  for (const Field& f : s.fields)
    if (f.name == name) return &f;
  return nullptr;
}

bool is(const Field& f, const char* type, const char* name) {
  return f.type == type && f.name == name && f.dims.empty();
}

// Carries run_id, step, serial, prev_digest first.
bool carriesSerial(const Struct& s) {
  return s.fields.size() >= 4 && is(s.fields[0], "string", "run_id") && is(s.fields[1], "int64_t", "step") &&
         is(s.fields[2], "int64_t", "serial") && is(s.fields[3], "int64_t", "prev_digest");
}

void resolve(std::vector<Struct>& all) {
  std::map<std::string, Struct*> by_name;
  for (Struct& s : all) {
    if (s.package != all.front().package)
      fail(s.file, s.line, "package '" + s.package + "' differs from '" + all.front().package + "' of " +
                               all.front().file + " (one package for all types)");
    const auto [it, fresh] = by_name.emplace(s.full(), &s);
    if (!fresh)
      fail(s.file, s.line, "struct " + s.name + " is already defined at " + it->second->file + ":" +
                               std::to_string(it->second->line));
  }
  for (Struct& s : all) {
    for (std::size_t i = 0; i < s.fields.size(); ++i) {
      Field& f = s.fields[i];
      if (!isPrimitive(f.type)) {
        const std::string full =
            f.type.find('.') != std::string::npos || s.package.empty() ? f.type : s.package + "." + f.type;
        const auto it = by_name.find(full);
        if (it == by_name.end()) fail(s.file, f.line, "unknown type '" + f.type + "' of field '" + f.name + "'");
        f.nested = it->second;
        it->second->part = true;
      }
      for (const Dim& d : f.dims) {
        if (d.field.empty()) continue;
        const auto earlier = std::find_if(s.fields.begin(), s.fields.begin() + static_cast<std::ptrdiff_t>(i),
                                          [&](const Field& g) { return g.name == d.field; });
        const std::string what = "dimension '" + d.field + "' of field '" + f.name + "' ";
        if (earlier == s.fields.begin() + static_cast<std::ptrdiff_t>(i)) {
          if (findField(s, d.field)) fail(s.file, f.line, what + "names a later field (it must be declared earlier)");
          fail(s.file, f.line, what + "is neither an earlier field nor a constant");
        }
        if (!isCountType(earlier->type) || !earlier->dims.empty())
          fail(s.file, f.line, what + "names '" + earlier->type + " " + earlier->name +
                                   (earlier->dims.empty() ? "" : "[...]") +
                                   "', not a scalar integer field (int8_t, int16_t, int32_t or int64_t)");
      }
    }
  }
  // A type may not hold itself, directly or not.
  std::map<const Struct*, int> state;  // 1: on the path, 2: done
  auto visit = [&](auto& self, const Struct* s) -> void {
    if (state[s] == 2) return;
    if (state[s] == 1) fail(s->file, s->line, "struct " + s->name + " contains itself");
    state[s] = 1;
    for (const Field& f : s->fields)
      if (f.nested) self(self, f.nested);
    state[s] = 2;
  };
  for (const Struct& s : all) visit(visit, &s);

  for (const Struct& s : all) {
    if (const Field* serial = findField(s, "serial")) {
      if (s.fields.size() < 3 || &s.fields[2] != serial || !is(*serial, "int64_t", "serial"))
        fail(s.file, serial->line, "field 'serial' must be the third field, `int64_t serial;`");
      if (s.fields.size() < 4 || !is(s.fields[3], "int64_t", "prev_digest"))
        fail(s.file, serial->line, "field 'serial' must be followed by `int64_t prev_digest;`");
    }
    if (s.part) continue;
    if (s.fields.size() < 2 || !is(s.fields[0], "string", "run_id") || !is(s.fields[1], "int64_t", "step"))
      fail(s.file, s.fields.empty() ? s.line : s.fields[0].line,
           "message type " + s.name + " must begin with `string run_id; int64_t step;`");
    if (s.fields.size() < 3 || !is(s.fields.back(), "int64_t", "digest"))
      fail(s.file, s.fields.back().line, "message type " + s.name + " must end with `int64_t digest;`");
  }
}

// ---- the header -------------------------------------------------------------------------

std::string cppType(const Struct& s) {
  std::string t = "::";
  for (char c : s.package) t += c == '.' ? std::string("::") : std::string(1, c);
  return (s.package.empty() ? t : t + "::") + s.name;
}

std::string lcmHeader(const Struct& s) {
  std::string h = s.package;
  std::replace(h.begin(), h.end(), '.', '/');
  return (h.empty() ? "" : h + "/") + s.name + ".hpp";
}

std::string quoted(const std::string& s) { return "\"" + s + "\""; }

// Member declarations of a bounds struct with their comments, aligned.
struct Member {
  std::string declaration, comment;
};

std::vector<Member> boundsMembers(const Struct& s) {
  std::vector<Member> out;
  for (const Field& f : s.fields) {
    if (f.type == "string") {
      out.push_back({"Max " + f.name + ";", f.dims.empty() ? "bytes of " + f.name : "bytes of each of " + f.name});
    } else if (f.nested) {
      out.push_back({f.nested->name + "_bounds " + f.name + ";", f.dims.empty() ? f.name : "each of " + f.name});
    } else {
      std::vector<std::string> uses;  // the arrays this field sizes
      for (const Field& g : s.fields)
        for (std::size_t k = 0; k < g.dims.size(); ++k)
          if (g.dims[k].field == f.name)
            uses.push_back(g.dims.size() == 1 ? g.name
                                              : g.name + " (dimension " + std::to_string(k + 1) + " of " +
                                                    std::to_string(g.dims.size()) + ")");
      if (uses.empty()) continue;
      std::string comment = "elements of ";
      for (std::size_t k = 0; k < uses.size(); ++k) comment += (k ? ", " : "") + uses[k];
      out.push_back({"Max " + f.name + ";", comment});
    }
  }
  return out;
}

std::string dimExpr(const Dim& d) { return d.field.empty() ? std::to_string(d.size) : d.field + "_value"; }

void writeScan(std::ostream& o, const Struct& s, const std::set<std::string>& counts) {
  const std::string type = cppType(s);
  o << "// Every field of " << s.name
    << (s.part ? " (a part: encoded without a fingerprint).\n" : " after the fingerprint.\n");
  o << "inline bool Bounds<" << type << ">::scan(Cursor& c, const " << s.name << "_bounds& b) {\n";
  bool uses_b = false;
  for (const Field& f : s.fields)
    if (counts.count(f.name)) o << "  std::int64_t " << f.name << "_value = 0;\n";
  for (const Field& f : s.fields) {
    const std::string name = quoted(f.name);
    if (f.type != "string" && !f.nested) {
      const int bytes = kPrimitiveBytes.at(f.type);
      if (counts.count(f.name)) {
        o << "  if (!c.size(" << name << ", " << bytes << ", b." << f.name << ", " << f.name
          << "_value)) return false;\n";
        uses_b = true;
        continue;
      }
      std::string count = "1";
      if (f.dims.size() == 1) {
        count = dimExpr(f.dims[0]);
      } else if (f.dims.size() > 1) {
        count = "product({";
        for (std::size_t k = 0; k < f.dims.size(); ++k) count += (k ? ", " : "") + dimExpr(f.dims[k]);
        count += "})";
      }
      o << "  if (!c.primitive(" << name << ", " << bytes << ", " << count << ")) return false;\n";
      continue;
    }
    uses_b = true;
    const std::string one = f.type == "string" ? "c.string(\"\", b." + f.name + ")"
                                               : "Bounds<" + cppType(*f.nested) + ">::scan(c, b." + f.name + ")";
    if (f.dims.empty()) {
      if (f.type == "string")
        o << "  if (!c.string(" << name << ", b." << f.name << ")) return false;\n";
      else
        o << "  if (!c.element(" << name << ", {}, [&] { return " << one << "; })) return false;\n";
      continue;
    }
    std::string indent = "  ", index;
    for (std::size_t k = 0; k < f.dims.size(); ++k) {
      const std::string i = "i" + std::to_string(k);
      o << indent << "for (std::int64_t " << i << " = 0; " << i << " < " << dimExpr(f.dims[k]) << "; ++" << i
        << ")\n";
      indent += "  ";
      index += (k ? ", " : "") + i;
    }
    o << indent << "if (!c.element(" << name << ", {" << index << "}, [&] { return " << one
      << "; })) return false;\n";
  }
  if (!uses_b) o << "  (void)b;\n";
  o << "  return true;\n}\n";
}

void writeHeader(std::ostream& o, const std::vector<const Struct*>& order, const std::vector<std::string>& files) {
  o << "// Generated by afford-lcmwire (tools/lcmwire) from " << files.size()
    << " .lcm files: do not edit.\n// The wire bounds of every type: see afford/wire.hpp.\n";
  o << "#pragma once\n#include <cstdint>\n#include <tuple>\n\n#include \"afford/wire.hpp\"\n";
  std::vector<std::string> headers;
  for (const Struct* s : order) headers.push_back(lcmHeader(*s));
  std::sort(headers.begin(), headers.end());
  for (const std::string& h : headers) o << "#include \"" << h << "\"\n";
  o << "\nnamespace afford::wire {\n";
  for (const Struct* s : order) {
    std::set<std::string> counts;
    for (const Field& f : s->fields)
      for (const Dim& d : f.dims)
        if (!d.field.empty()) counts.insert(d.field);
    const bool serial = carriesSerial(*s);
    std::string kind = serial ? "message with a serial" : "message";
    if (s->part) {
      kind = "part of";
      const char* sep = " ";
      for (const Struct* user : order)
        if (std::any_of(user->fields.begin(), user->fields.end(), [&](const Field& f) { return f.nested == s; }))
          kind += sep + user->name, sep = ", ";
    }
    o << "\n// " << s->name << " (" << kind << "): " << std::filesystem::path(s->file).filename().string() << "\n";
    const std::vector<Member> members = boundsMembers(*s);
    if (members.empty()) {
      o << "struct " << s->name << "_bounds {};  // no variable-length field\n";
    } else {
      std::size_t width = 0;
      for (const Member& m : members) width = std::max(width, m.declaration.size());
      o << "struct " << s->name << "_bounds {\n";
      for (const Member& m : members)
        o << "  " << m.declaration << std::string(width - m.declaration.size() + 2, ' ') << "// " << m.comment << "\n";
      o << "};\n";
    }
    o << "template <>\nstruct Bounds<" << cppType(*s) << "> {\n"
      << "  using type = " << s->name << "_bounds;\n"
      << "  static constexpr const char* kName = \"" << s->name << "\";\n"
      << "  static constexpr bool kMessage = " << (s->part ? "false" : "true") << ";\n"
      << "  static constexpr bool kSerial = " << (serial ? "true" : "false") << ";\n"
      << "  static bool scan(Cursor& c, const " << s->name << "_bounds& b);\n"
      << "};\n";
    writeScan(o, *s, counts);
  }
  auto list = [&](const char* name, const char* comment, auto keep) {
    std::vector<const Struct*> picked;
    for (const Struct* s : order)
      if (keep(*s)) picked.push_back(s);
    std::sort(picked.begin(), picked.end(), [](const Struct* a, const Struct* b) { return a->name < b->name; });
    const std::string open = std::string("using ") + name + " = std::tuple<";
    o << "\n// " << comment << "\n" << open;
    for (std::size_t k = 0; k < picked.size(); ++k)
      o << (k ? ",\n" + std::string(open.size(), ' ') : "") << cppType(*picked[k]);
    o << ">;\n";
  };
  list("MessageTypes", "Every message type (no other type's field), by name.", [](const Struct& s) { return !s.part; });
  list("SerialTypes", "The message types that carry a serial (run_id, step, serial, prev_digest first).",
       [](const Struct& s) { return !s.part && carriesSerial(s); });
  o << "\n}  // namespace afford::wire\n";
}

// ---- the Python conversions -------------------------------------------------------------

// The C++ element type lcm-gen uses for a primitive.
std::string cppElement(const std::string& type) {
  if (type == "byte") return "uint8_t";
  if (type == "boolean") return "int8_t";
  if (type == "string") return "std::string";
  return type;
}

// An expression for dimension d of a field of message `m`.
std::string memberDim(const Dim& d) { return d.field.empty() ? std::to_string(d.size) : "m." + d.field; }

// toPython(const T&): a dict of the message's fields, for the Python package
// (python/afford): numbers and strings as Python values, booleans as bool,
// arrays of numbers as numpy arrays of their type (bool for boolean), arrays
// of strings and of structs as lists, a struct as a dict.
void writePython(std::ostream& o, const std::vector<const Struct*>& order, const std::vector<std::string>& files) {
  o << "// Generated by afford-lcmwire (tools/lcmwire) from " << files.size()
    << " .lcm files: do not edit.\n// Every message type as a Python dict (python/afford).\n";
  o << "#pragma once\n#include <pybind11/numpy.h>\n#include <pybind11/pybind11.h>\n\n#include <cstdint>\n"
       "#include <string>\n\n";
  std::vector<std::string> headers;
  for (const Struct* s : order) headers.push_back(lcmHeader(*s));
  std::sort(headers.begin(), headers.end());
  for (const std::string& h : headers) o << "#include \"" << h << "\"\n";
  o << R"(
namespace afford::python {
namespace py = pybind11;

// An array of n values (of a vector or a C array) as a numpy array of E.
template <class E, class A>
py::array_t<E> array1(const A& a, std::int64_t n) {
  py::array_t<E> out(static_cast<py::ssize_t>(n));
  auto w = out.template mutable_unchecked<1>();
  for (std::int64_t i = 0; i < n; ++i) w(i) = static_cast<E>(a[static_cast<std::size_t>(i)]);
  return out;
}
template <class E, class A>
py::array_t<E> array2(const A& a, std::int64_t n0, std::int64_t n1) {
  py::array_t<E> out({static_cast<py::ssize_t>(n0), static_cast<py::ssize_t>(n1)});
  auto w = out.template mutable_unchecked<2>();
  for (std::int64_t i = 0; i < n0; ++i)
    for (std::int64_t j = 0; j < n1; ++j) w(i, j) = static_cast<E>(a[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)]);
  return out;
}
)";
  for (const Struct* s : order) o << "py::dict toPython(const " << cppType(*s) << "& m);\n";
  for (const Struct* s : order) {
    o << "\ninline py::dict toPython(const " << cppType(*s) << "& m) {\n  py::dict d;\n";
    for (const Field& f : s->fields) {
      const std::string key = "d[\"" + f.name + "\"]";
      if (f.dims.empty()) {
        if (f.nested)
          o << "  " << key << " = toPython(m." << f.name << ");\n";
        else if (f.type == "boolean")
          o << "  " << key << " = py::bool_(m." << f.name << " != 0);\n";
        else if (f.type == "string")
          o << "  " << key << " = py::str(m." << f.name << ");\n";
        else
          o << "  " << key << " = m." << f.name << ";\n";
        continue;
      }
      if (f.dims.size() > 2) fail(s->file, f.line, "a field of more than two dimensions has no Python conversion");
      if (f.nested || f.type == "string") {
        if (f.dims.size() != 1) fail(s->file, f.line, "an array of strings or structs of two dimensions has no Python conversion");
        o << "  {\n    py::list l;\n    for (std::int64_t i = 0; i < " << memberDim(f.dims[0]) << "; ++i) l.append("
          << (f.nested ? "toPython(m." + f.name + "[static_cast<std::size_t>(i)])"
                       : "py::str(m." + f.name + "[static_cast<std::size_t>(i)])")
          << ");\n    " << key << " = l;\n  }\n";
        continue;
      }
      const std::string element = f.type == "boolean" ? "bool" : cppElement(f.type);
      if (f.dims.size() == 1)
        o << "  " << key << " = array1<" << element << ">(m." << f.name << ", " << memberDim(f.dims[0]) << ");\n";
      else
        o << "  " << key << " = array2<" << element << ">(m." << f.name << ", " << memberDim(f.dims[0]) << ", "
          << memberDim(f.dims[1]) << ");\n";
    }
    o << "  return d;\n}\n";
  }
  o << "\n}  // namespace afford::python\n";
}

// Parts before the types that hold them; otherwise by name.
std::vector<const Struct*> emitOrder(const std::vector<Struct>& all) {
  std::vector<const Struct*> sorted;
  for (const Struct& s : all) sorted.push_back(&s);
  std::sort(sorted.begin(), sorted.end(), [](const Struct* a, const Struct* b) { return a->name < b->name; });
  std::vector<const Struct*> out;
  std::set<const Struct*> done;
  auto visit = [&](auto& self, const Struct* s) -> void {
    if (!done.insert(s).second) return;
    for (const Field& f : s->fields)
      if (f.nested) self(self, f.nested);
    out.push_back(s);
  };
  for (const Struct* s : sorted) visit(visit, s);
  return out;
}

// Written whole or not at all (a temporary file, then renamed).
void writeFile(const std::string& path, const std::string& text) {
  const std::filesystem::path out(path);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  const std::filesystem::path tmp = out.string() + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    f << text;
    if (!f.flush()) throw Error(path + ": cannot write");
  }
  std::filesystem::rename(tmp, out);
}

int usage(const char* what) {
  std::cerr << "afford-lcmwire: " << what << "\nusage: afford-lcmwire --out wire_bounds.hpp [--python-out to_python.hpp] FILE.lcm...\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string out_path, python_path;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out") {
      if (++i == argc) return usage("--out needs a path");
      out_path = argv[i];
    } else if (a == "--python-out") {
      if (++i == argc) return usage("--python-out needs a path");
      python_path = argv[i];
    } else if (a == "--help" || a == "-h") {
      return usage("writes the wire bounds of the given .lcm types");
    } else if (!a.empty() && a[0] == '-') {
      return usage(("unknown option " + a).c_str());
    } else {
      files.push_back(a);
    }
  }
  if (out_path.empty()) return usage("no --out");
  if (files.empty()) return usage("no .lcm file");
  try {
    std::vector<Struct> all;
    for (const std::string& file : files) {
      std::ifstream in(file, std::ios::binary);
      if (!in) throw Error(file + ": cannot read the file");
      std::stringstream text;
      text << in.rdbuf();
      Parser(file, lex(file, text.str())).parse(all);
    }
    resolve(all);
    std::stringstream header;
    writeHeader(header, emitOrder(all), files);
    writeFile(out_path, header.str());
    if (!python_path.empty()) {
      std::stringstream python;
      writePython(python, emitOrder(all), files);
      writeFile(python_path, python.str());
    }
  } catch (const Error& e) {
    std::cerr << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "afford-lcmwire: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

// afford-lcmwire's reading of the .lcm language (lcm_types.hpp).
#include "lcm_types.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

namespace lcmwire {

void fail(const std::string& file, int line, const std::string& what) {
  throw Error(file + ":" + std::to_string(line) + ": " + what);
}

const std::map<std::string, int> kPrimitiveBytes = {
    {"int8_t", 1}, {"int16_t", 2}, {"int32_t", 4}, {"int64_t", 8}, {"byte", 1},
    {"boolean", 1}, {"float", 4},  {"double", 8},  {"string", 0}};

bool isPrimitive(const std::string& type) { return kPrimitiveBytes.count(type) != 0; }
bool isCountType(const std::string& type) {
  return type == "int8_t" || type == "int16_t" || type == "int32_t" || type == "int64_t";
}

namespace {

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

bool is(const Field& f, const char* type, const char* name) {
  return f.type == type && f.name == name && f.dims.empty();
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

}  // namespace

const Field* findField(const Struct& s, const std::string& name) {
  for (const Field& f : s.fields)
    if (f.name == name) return &f;
  return nullptr;
}

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

// Carries run_id, step, serial, prev_digest first.
bool carriesSerial(const Struct& s) {
  return s.fields.size() >= 4 && is(s.fields[0], "string", "run_id") && is(s.fields[1], "int64_t", "step") &&
         is(s.fields[2], "int64_t", "serial") && is(s.fields[3], "int64_t", "prev_digest");
}

std::vector<Struct> readTypes(const std::vector<std::string>& files) {
  std::vector<Struct> all;
  for (const std::string& file : files) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw Error(file + ": cannot read the file");
    std::stringstream text;
    text << in.rdbuf();
    Parser(file, lex(file, text.str())).parse(all);
  }
  resolve(all);
  return all;
}

}  // namespace lcmwire

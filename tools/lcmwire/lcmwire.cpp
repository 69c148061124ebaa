// afford-lcmwire: reads the project's .lcm files and writes wire_bounds.hpp,
// the bounds check of every type's encoding (afford/wire.hpp) that runs
// before LCM's decode: one struct of maxima and one straight-line scan per type.
//
//   afford-lcmwire --out build/lcmgen/cpp/afford/wire_bounds.hpp lcmtypes/*.lcm
//
// With --python-out FILE it also writes each type's conversion to a Python
// dict (pybind11), for the Python package; with --json-out FILE, each type's
// JSON Schema and its conversion to JSON (nlohmann::json), for `afford export`'s
// MCAP files (json_out.cpp).
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


#include "json_out.hpp"
#include "lcm_types.hpp"

namespace {

using namespace lcmwire;

// ---- the header -------------------------------------------------------------------------

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

// Written whole or not at all (a temporary file, then renamed); a file that
// already holds the text is left as it is (what includes it is not rebuilt).
void writeFile(const std::string& path, const std::string& text) {
  const std::filesystem::path out(path);
  {
    std::ifstream had(out, std::ios::binary);
    std::stringstream old;
    if (had && (old << had.rdbuf()) && old.str() == text) return;
  }
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
  std::cerr << "afford-lcmwire: " << what << "\nusage: afford-lcmwire --out wire_bounds.hpp [--python-out to_python.hpp] "
               "[--json-out json_messages.hpp] FILE.lcm...\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string out_path, python_path, json_path;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out") {
      if (++i == argc) return usage("--out needs a path");
      out_path = argv[i];
    } else if (a == "--python-out") {
      if (++i == argc) return usage("--python-out needs a path");
      python_path = argv[i];
    } else if (a == "--json-out") {
      if (++i == argc) return usage("--json-out needs a path");
      json_path = argv[i];
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
    const std::vector<Struct> all = readTypes(files);
    std::stringstream header;
    writeHeader(header, emitOrder(all), files);
    writeFile(out_path, header.str());
    if (!python_path.empty()) {
      std::stringstream python;
      writePython(python, emitOrder(all), files);
      writeFile(python_path, python.str());
    }
    if (!json_path.empty()) {
      std::stringstream json;
      writeJsonMessages(json, emitOrder(all), files);
      writeFile(json_path, json.str());
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

// One conversion to JSON and one from it for every structure the experiment
// keeps in a file: each structure declares its keys once, in a visit(V&), and
// both directions come from that declaration (summary.json, a run's kept
// outcome, an experiment's stored request). Reading is strict: a key of the
// wrong type, a missing one or an unknown one throws SummaryError naming its
// path (systems.IMP.runs[2].seed) and the file.
//
// In a visit(V& v):
//   v("key", field)        always written; on reading it must be there
//   v.since("key", field)  always written; on reading it may be absent (files
//                          of earlier versions), the field keeping its default
//   v.since("key", field, absent)  ... absent: the field is `absent`
//   visitNullable(v, "key", optional_field)  always written, null when empty
//   V::kReads              true when the visit reads (a visit that maps a
//                          field through a temporary writes it back then)
// std::optional<T>: the key is absent when empty; Nullable<T>: the key is
// always there, null when empty.
#pragma once
#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace afford {

struct SummaryError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

template <class T>
struct Nullable {
  std::optional<T> value;
  Nullable() = default;
  Nullable(T v) : value(std::move(v)) {}  // NOLINT: a value is a present one
  explicit operator bool() const { return value.has_value(); }
  const T& operator*() const { return *value; }
};

namespace codec {

template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};
template <class T>
struct IsMap : std::false_type {};
template <class T>
struct IsMap<std::map<std::string, T>> : std::true_type {};
template <class T>
struct IsOptional : std::false_type {};
template <class T>
struct IsOptional<std::optional<T>> : std::true_type {};
template <class T>
struct IsNullable : std::false_type {};
template <class T>
struct IsNullable<Nullable<T>> : std::true_type {};

inline std::string join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

inline std::string kindOf(const nlohmann::json& j) {
  if (j.is_null()) return "null";
  if (j.is_boolean()) return "a boolean";
  if (j.is_number_integer()) return "an integer";
  if (j.is_number()) return "a number";
  if (j.is_string()) return "a string";
  if (j.is_array()) return "a list";
  return "a map";
}

struct Context {
  std::string what;  // the file (or "summary.json")
  [[noreturn]] void fail(const std::string& path, const std::string& problem) const {
    throw SummaryError(what + ": key '" + (path.empty() ? std::string("<top>") : path) + "': " + problem);
  }
};

// ---- to JSON

template <class T>
nlohmann::json out(const T& value);

struct Writer {
  static constexpr bool kReads = false;
  nlohmann::json& j;
  template <class T>
  void operator()(const char* key, const T& value) {
    if constexpr (IsOptional<T>::value) {
      if (value) j[key] = out(*value);
    } else {
      j[key] = out(value);
    }
  }
  template <class T>
  void since(const char* key, const T& value) {
    (*this)(key, value);
  }
  template <class T, class D>
  void since(const char* key, const T& value, const D&) {
    (*this)(key, value);
  }
};

template <class T>
nlohmann::json out(const T& value) {
  if constexpr (std::is_arithmetic_v<T> || std::is_same_v<T, std::string>) {
    return nlohmann::json(value);
  } else if constexpr (IsVector<T>::value) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& e : value) a.push_back(out(e));
    return a;
  } else if constexpr (IsMap<T>::value) {
    nlohmann::json o = nlohmann::json::object();
    for (const auto& [k, e] : value) o[k] = out(e);
    return o;
  } else if constexpr (IsNullable<T>::value) {
    return value ? out(*value) : nlohmann::json(nullptr);
  } else {
    nlohmann::json o = nlohmann::json::object();
    Writer w{o};
    const_cast<T&>(value).visit(w);  // visit() only reads through a Writer
    return o;
  }
}

// ---- from JSON

template <class T>
void in(const nlohmann::json& j, const std::string& path, const Context& c, T& value);

struct Reader {
  static constexpr bool kReads = true;
  const nlohmann::json& j;
  std::string path;
  const Context& c;
  std::set<std::string> known;
  template <class T>
  void operator()(const char* key, T& value) {
    known.insert(key);
    const auto it = j.find(key);
    if constexpr (IsOptional<T>::value) {
      value.reset();
      if (it == j.end()) return;
      value.emplace();
      in(*it, join(path, key), c, *value);
    } else {
      if (it == j.end()) c.fail(join(path, key), "missing");
      in(*it, join(path, key), c, value);
    }
  }
  template <class T>
  void since(const char* key, T& value) {
    known.insert(key);
    if (const auto it = j.find(key); it != j.end()) in(*it, join(path, key), c, value);
  }
  // ... and when absent, `absent` (what files of earlier versions meant by leaving it out).
  template <class T, class D>
  void since(const char* key, T& value, const D& absent) {
    known.insert(key);
    if (const auto it = j.find(key); it != j.end())
      in(*it, join(path, key), c, value);
    else
      value = absent;
  }
  void unknownKeys() const {
    for (const auto& [key, v] : j.items())
      if (!known.count(key)) c.fail(join(path, key), "unknown key");
  }
};

template <class T>
void in(const nlohmann::json& j, const std::string& path, const Context& c, T& value) {
  const auto expect = [&](bool ok, const char* kind) {
    if (!ok) c.fail(path, std::string("expected ") + kind + ", got " + kindOf(j));
  };
  if constexpr (std::is_same_v<T, bool>) {
    expect(j.is_boolean(), "a boolean");
    value = j.get<bool>();
  } else if constexpr (std::is_integral_v<T>) {
    expect(j.is_number_integer(), "an integer");
    value = j.get<T>();
  } else if constexpr (std::is_floating_point_v<T>) {
    expect(j.is_number(), "a number");
    value = j.get<T>();
  } else if constexpr (std::is_same_v<T, std::string>) {
    expect(j.is_string(), "a string");
    value = j.get<std::string>();
  } else if constexpr (IsVector<T>::value) {
    expect(j.is_array(), "a list");
    value.assign(j.size(), {});
    for (std::size_t i = 0; i < j.size(); ++i) in(j[i], path + "[" + std::to_string(i) + "]", c, value[i]);
  } else if constexpr (IsMap<T>::value) {
    expect(j.is_object(), "a map");
    value.clear();
    for (const auto& [k, e] : j.items()) in(e, join(path, k), c, value[k]);
  } else if constexpr (IsNullable<T>::value) {
    value.value.reset();
    if (!j.is_null()) in(j, path, c, value.value.emplace());
  } else {
    expect(j.is_object(), "a map");
    Reader r{j, path, c, {}};
    value.visit(r);
    r.unknownKeys();
  }
}

}  // namespace codec

// An optional field kept as a key that is always there, null when empty (a file's format that says
// "none" explicitly): visit it through this.
template <class V, class T>
void visitNullable(V& v, const char* key, std::optional<T>& field) {
  Nullable<T> n;
  if (field) n = *field;
  v(key, n);
  if constexpr (V::kReads) field = n.value;
}

// A structure with visit() as JSON, and back (strict: SummaryError naming the key and `what`).
template <class T>
nlohmann::json toJsonOf(const T& value) {
  return codec::out(value);
}
template <class T>
T fromJsonOf(const nlohmann::json& j, const std::string& what) {
  T value;
  codec::in(j, "", codec::Context{what}, value);
  return value;
}

}  // namespace afford

// Strict reading of JSON files and configs: every value type-checked, numbers finite and in
// range, unknown keys refused, and every error naming the source and the key path, as in
//   cell.json: margins.table_clearance_mm: expected a number, got string
// Templated on the error type: each module throws its own (FormatError, ConfigError, ...).
#pragma once

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstddef>
#include <limits>
#include <set>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace robocal::jsonread {

using Json = nlohmann::json;

// The path of `key` inside the object at `where` ("" is the top level).
inline std::string keyPath(const std::string& where, const std::string& key) {
  return where.empty() ? key : where + "." + key;
}
// The path of element `i` of the array at `where`.
inline std::string indexPath(const std::string& where, std::size_t i) {
  return where + "[" + std::to_string(i) + "]";
}

// What a value is, for "expected X, got Y": a number as written, anything else by its type. An
// array or object is never dumped (that recursed once per level of a hostile file).
inline std::string got(const Json& v) {
  return v.is_number() ? v.dump() : std::string(v.type_name());
}

// The JSON value of a file's or a request's text. An empty text says so and what was expected (a
// file emptied by a full disk, a wrong path); a syntax error says where in words, without the
// library's "[json.exception.parse_error.101]" prefix. Numbers too large for a double are refused
// as syntax. Throws Error("<source>: ...").
template <typename Error>
Json parseText(const std::string& text, const std::string& source, const std::string& expected) {
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    throw Error(source + ": empty: expected " + expected);
  try {
    return Json::parse(text);
  } catch (const Json::exception& e) {
    std::string why = e.what();
    if (!why.empty() && why.front() == '[') why.erase(0, why.find("] ") + 2);
    throw Error(source + ": not valid JSON: " + why);
  }
}

// Checks single values; every failure throws Error("<source>: <path>: <problem>"), or
// Error("<path>: <problem>") with an empty source (a caller that adds the source itself).
template <typename Error>
class Reader {
 public:
  explicit Reader(const std::string& source) : prefix_(source.empty() ? "" : source + ": ") {}

  [[noreturn]] void fail(const std::string& path, const std::string& problem) const {
    throw Error(prefix_ + path + ": " + problem);
  }

  const Json& object(const Json& v, const std::string& path) const {
    if (!v.is_object()) fail(path, "expected an object, got " + got(v));
    return v;
  }
  const Json& array(const Json& v, const std::string& path) const {
    if (!v.is_array()) fail(path, "expected an array, got " + got(v));
    return v;
  }
  // An array of exactly `count` elements.
  const Json& array(const Json& v, const std::string& path, std::size_t count) const {
    array(v, path);
    if (v.size() != count)
      fail(path, "expected " + std::to_string(count) + " entries, got " + std::to_string(v.size()));
    return v;
  }
  // `key` of the object `obj` (at `where`), which must be there.
  const Json& member(const Json& obj, const std::string& where, const std::string& key) const {
    object(obj, where.empty() ? "top level" : where);
    const auto it = obj.find(key);
    if (it == obj.end()) fail(keyPath(where, key), "missing");
    return *it;
  }

  double number(const Json& v, const std::string& path) const {
    if (!v.is_number()) fail(path, "expected a number, got " + got(v));
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail(path, "not a finite number");
    return d;
  }
  double number(const Json& v, const std::string& path, double lo, double hi) const {
    const double d = number(v, path);
    if (!(d >= lo && d <= hi))
      fail(path, "must be from " + Json(lo).dump() + " to " + Json(hi).dump());
    return d;
  }
  // A whole number written as one (1, not 1.0) from lo to hi (by default, all that Int holds).
  template <typename Int = int, typename = std::enable_if_t<std::is_integral_v<Int>>>
  Int integer(const Json& v, const std::string& path, long long lo = lowest<Int>(),
              long long hi = highest<Int>()) const {
    if (!v.is_number_integer()) fail(path, "expected a whole number, got " + got(v));
    // A value above LLONG_MAX is stored unsigned: it is out of every range here.
    const bool too_big = v.is_number_unsigned() && v.get<unsigned long long>() > kMaxLongLong;
    const long long i = too_big ? 0 : v.get<long long>();
    if (too_big || i < lo || i > hi)
      fail(path, "must be from " + std::to_string(lo) + " to " + std::to_string(hi));
    return static_cast<Int>(i);
  }
  std::string string(const Json& v, const std::string& path) const {
    if (!v.is_string()) fail(path, "expected a string, got " + got(v));
    return v.get<std::string>();
  }
  bool boolean(const Json& v, const std::string& path) const {
    if (!v.is_boolean()) fail(path, "expected true or false, got " + got(v));
    return v.get<bool>();
  }
  std::vector<std::string> strings(const Json& v, const std::string& path) const {
    if (!v.is_array()) fail(path, "expected a list of strings, got " + got(v));
    std::vector<std::string> out;
    for (std::size_t i = 0; i < v.size(); ++i) out.push_back(string(v[i], indexPath(path, i)));
    return out;
  }

 private:
  static constexpr unsigned long long kMaxLongLong = std::numeric_limits<long long>::max();
  template <typename Int>
  static constexpr long long lowest() {
    return std::is_signed_v<Int> ? static_cast<long long>(std::numeric_limits<Int>::min()) : 0;
  }
  template <typename Int>
  static constexpr long long highest() {
    return static_cast<unsigned long long>(std::numeric_limits<Int>::max()) > kMaxLongLong
               ? std::numeric_limits<long long>::max()
               : static_cast<long long>(std::numeric_limits<Int>::max());
  }

  std::string prefix_;
};

// The members of one JSON object: each key read at most once through find/require/get, and
// finish() refuses every key that was not (a misspelt key would otherwise silently keep its
// default). `where` is the object's path ("" at the top level).
template <typename Error>
class Object {
 public:
  Object(Reader<Error> reader, const Json& obj, std::string where)
      : r_(std::move(reader)), obj_(obj), where_(std::move(where)) {
    r_.object(obj_, where_.empty() ? "top level" : where_);
  }

  const Reader<Error>& reader() const { return r_; }
  std::string path(const std::string& key) const { return keyPath(where_, key); }
  [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
    r_.fail(path(key), problem);
  }

  // The member, or nullptr when absent.
  const Json* find(const std::string& key) {
    used_.insert(key);
    const auto it = obj_.find(key);
    return it == obj_.end() ? nullptr : &*it;
  }
  const Json& require(const std::string& key) {
    const Json* v = find(key);
    if (!v) fail(key, "missing");
    return *v;
  }

  // Optional members: `out` keeps its value (the default) when the key is absent.
  void get(const std::string& key, std::string& out) {
    if (const Json* v = find(key)) out = r_.string(*v, path(key));
  }
  void get(const std::string& key, bool& out) {
    if (const Json* v = find(key)) out = r_.boolean(*v, path(key));
  }
  void get(const std::string& key, double& out) {
    if (const Json* v = find(key)) out = r_.number(*v, path(key));
  }
  void get(const std::string& key, double& out, double lo, double hi) {
    if (const Json* v = find(key)) out = r_.number(*v, path(key), lo, hi);
  }
  void get(const std::string& key, int& out) {
    if (const Json* v = find(key)) out = r_.template integer<int>(*v, path(key));
  }
  template <typename Int, typename = std::enable_if_t<std::is_integral_v<Int>>>
  void get(const std::string& key, Int& out, long long lo, long long hi) {
    if (const Json* v = find(key)) out = r_.template integer<Int>(*v, path(key), lo, hi);
  }
  void get(const std::string& key, std::vector<std::string>& out) {
    if (const Json* v = find(key)) out = r_.strings(*v, path(key));
  }

  void finish(const std::string& problem = "unknown key") const {
    for (const auto& item : obj_.items())
      if (!used_.count(item.key())) fail(item.key(), problem);
  }

 private:
  Reader<Error> r_;
  const Json& obj_;
  std::string where_;
  std::set<std::string> used_;
};

}  // namespace robocal::jsonread

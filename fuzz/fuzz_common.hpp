// Shared by the libFuzzer harnesses: a failed property or an undocumented exception is a crash
// (abort), so that libFuzzer saves the input as a reproducer.
#pragma once

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <optional>
#include <string>
#include <utility>

namespace robocal::fuzz {

[[noreturn]] inline void fail(const char* what, const std::string& detail = {}) {
  std::fprintf(stderr, "\nFUZZ PROPERTY FAILED: %s%s%s\n", what, detail.empty() ? "" : ": ",
               detail.c_str());
  std::abort();
}

inline void check(bool ok, const char* what, const std::string& detail = {}) {
  if (!ok) fail(what, detail);
}

// Runs one input. `body` catches the parser's documented error itself; any other exception
// escaping it is a bug in the parser (or a property the harness found broken).
template <typename Body>
int guarded(const uint8_t* data, size_t size, Body&& body) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  try {
    body(input);
  } catch (const std::exception& e) {
    fail("undocumented exception escaped the parser", e.what());
  } catch (...) {
    fail("a non-std exception escaped the parser");
  }
  return 0;
}

// Numbers equal within a relative tolerance (0 = exactly), for values that went through a
// writer that rounds.
inline bool close(double a, double b, double abs_tol, double rel_tol) {
  if (a == b) return true;
  return std::abs(a - b) <= abs_tol + rel_tol * std::max(std::abs(a), std::abs(b));
}

// Two JSON documents with the same structure and numbers equal within tolerance (integers and
// floating-point numbers compare as numbers). `path` names the first difference on failure.
template <typename A, typename B>
bool sameJson(const A& a, const B& b, double abs_tol, double rel_tol, std::string& path) {
  if (a.is_number() && b.is_number()) {
    if (close(a.template get<double>(), b.template get<double>(), abs_tol, rel_tol)) return true;
    path += ": " + a.dump() + " != " + b.dump();
    return false;
  }
  if (a.type() != b.type()) {
    path += ": " + std::string(a.type_name()) + " != " + b.type_name();
    return false;
  }
  if (a.is_array()) {
    if (a.size() != b.size()) {
      path += ": sizes " + std::to_string(a.size()) + " != " + std::to_string(b.size());
      return false;
    }
    for (std::size_t i = 0; i < a.size(); ++i) {
      std::string sub = path + "[" + std::to_string(i) + "]";
      if (!sameJson(a[i], b[i], abs_tol, rel_tol, sub)) return path = sub, false;
    }
    return true;
  }
  if (a.is_object()) {
    if (a.size() != b.size()) {
      path += ": key counts differ";
      return false;
    }
    for (auto it = a.begin(); it != a.end(); ++it) {
      std::string sub = path + "." + it.key();
      const auto other = b.find(it.key());
      if (other == b.end()) return path = sub + ": missing", false;
      if (!sameJson(it.value(), *other, abs_tol, rel_tol, sub)) return path = sub, false;
    }
    return true;
  }
  if (a == b) return true;
  path += ": " + a.dump() + " != " + b.dump();
  return false;
}

// The round trip every file reader's harness makes: `read` the input, and when it is accepted
// (anything else must be the reader's documented `Error`), `write` it back and read that, which
// must succeed. Returns the value read first and the value read again; nothing when the input is
// rejected.
template <typename Error, typename Read, typename Write>
auto readWriteRead(const std::string& input, Read&& read, Write&& write, const char* what)
    -> std::optional<std::pair<decltype(read(input)), decltype(read(input))>> {
  using Value = decltype(read(input));
  std::optional<Value> first;
  try {
    first = read(input);
  } catch (const Error&) {
    return std::nullopt;
  }
  const auto written = write(*first);
  try {
    return std::pair<Value, Value>(std::move(*first), read(written));
  } catch (const Error& e) {
    fail(what, e.what());
  }
}

}  // namespace robocal::fuzz

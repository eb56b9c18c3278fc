// The one lookup between a wire enum and its spelling, both ways, over a table of
// {value, "name"} pairs (each enum's table is next to its functions).
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string_view>
#include <utility>

namespace robocal::proto {

template <typename E, std::size_t N>
const char* wireName(const std::array<std::pair<E, const char*>, N>& table, E value,
                     const char* unknown) {
  for (const auto& [v, name] : table)
    if (v == value) return name;
  return unknown;
}

template <typename E, std::size_t N>
std::optional<E> wireValue(const std::array<std::pair<E, const char*>, N>& table,
                           std::string_view name) {
  for (const auto& [v, n] : table)
    if (name == n) return v;
  return std::nullopt;
}

}  // namespace robocal::proto

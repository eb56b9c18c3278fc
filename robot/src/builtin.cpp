#include <robocal/robot/builtin.hpp>

#include <robocal/robot/puma560.hpp>

#include <array>

namespace robocal {
namespace {

using MakeModel = Model (*)();
constexpr std::array<MakeModel, 1> kBuiltins = {&puma560NominalModel};

}  // namespace

std::optional<Model> builtinNominalModel(const std::string& name) {
  for (MakeModel make : kBuiltins) {
    Model m = make();
    if (m.name == name) return m;
  }
  return std::nullopt;
}

std::string builtinNominalNames() {
  std::string names;
  for (MakeModel make : kBuiltins) names += (names.empty() ? "\"" : ", \"") + make().name + "\"";
  return names;
}

}  // namespace robocal

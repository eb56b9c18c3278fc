// The drivers configuration file (config/drivers.json, docs/drivers.md). parseDriversConfig
// returns a validated DriversConfig or throws ConfigError. Properties: the configuration written
// back as JSON reads again to the same JSON; a validated configuration gives working dialects
// (regular expressions compile, command templates expand).
#include "fuzz_common.hpp"

#include <robocal/drivers/config.hpp>
#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/protocol.hpp>

using namespace robocal::drivers;
using robocal::fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return robocal::fuzz::guarded(data, size, [](const std::string& text) {
    const auto both = robocal::fuzz::readWriteRead<ConfigError>(
        text, [](const std::string& t) { return parseDriversConfig(t, "drivers.json"); },
        [](const DriversConfig& c) { return toJson(c).dump(); },
        "written configuration does not read back");
    if (!both) return;
    const auto& [config, again] = *both;
    const nlohmann::json written = toJson(config);
    check(toJson(again) == written, "configuration changed on a round trip", written.dump());

    const ValDialect val(config.val);
    (void)val.moveCommand({0, -90, 90, 0, 45, 0});
    (void)val.speedCommand(50);
    (void)val.errorMessage("*Position out of range*");
    const BarDialect bar(config.bar);
    (void)bar.parse("+0.01234 MM");
  });
}

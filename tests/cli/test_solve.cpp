#include <catch2/catch.hpp>

#include "cli_helpers.hpp"

#include <robocal/formats/model_json.hpp>
#include <robocal/formats/samples_csv.hpp>

#include <fstream>
#include <nlohmann/json.hpp>

using namespace robocal;
using namespace robocal::test;
using Catch::Matchers::Contains;

namespace {
// Nine simulated shells and a 150 mm-extension validation set of the same true robot.
void simulate(const TempDir& dir) {
  REQUIRE(runRobocal("simulate --model " + kModel + " --seed 5 --points-per-shell 60 --out " +
                     (dir / "s.csv") + " --truth-out " + (dir / "t.json"))
              .exit_code == 0);
  REQUIRE(runRobocal("simulate --model " + kModel + " --truth " + (dir / "t.json") +
                     " --seed 6 --points-per-shell 40 --extension-mm 150 --out " + (dir / "v.csv"))
              .exit_code == 0);
}
}  // namespace

TEST_CASE("robocal solve --json fits, validates and writes a model others can read") {
  TempDir dir;
  simulate(dir);
  const auto r = runRobocal("solve --model " + kModel + " " + (dir / "s.csv") + " --out " +
                            (dir / "cal.json") + " --validate " + (dir / "v.csv") + " --truth " +
                            (dir / "t.json") + " --json");
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  const auto j = nlohmann::json::parse(r.output);
  CHECK(j["rank"] == 36);
  CHECK(j["n"].get<int>() > 500);
  CHECK(j["rms_before_mm"].get<double>() > 0.3);
  CHECK(j["rms_mm"].get<double>() < 0.1);
  CHECK(j["validation_rms_mm"].get<double>() < 0.12);
  CHECK(j["iterations"].get<int>() >= 1);
  CHECK(j["redundant"].size() == 18);
  CHECK(j["truth_calibrated_rms_mm"].get<double>() <
        0.25 * j["truth_nominal_rms_mm"].get<double>());
  // The calibrated model reads back in the model format.
  const Model cal = loadModelFile(dir / "cal.json");
  CHECK((toParams(cal) - toParams(loadModelFile(kModel))).norm() > 0);
}

TEST_CASE("robocal solve --report writes the figures and report.json") {
  TempDir dir;
  simulate(dir);
  const auto r = runRobocal("solve --model " + kModel + " " + (dir / "s.csv") + " --validate " +
                            (dir / "v.csv") + " --report " + (dir / "rep"));
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.output, Contains("rank: 36 of 54"));
  for (const char* f : {"residuals_vs_longitude.svg", "residual_histogram.svg",
                        "validation_vs_longitude.svg", "validation_histogram.svg"}) {
    const std::string svg = readTextFile(dir / ("rep/" + std::string(f)));
    CHECK_THAT(svg, Contains("<svg") && Contains("</svg>"));
  }
  const auto report = nlohmann::json::parse(readTextFile(dir / "rep/report.json"));
  const auto& fig = report["figures"];
  CHECK(fig["residuals_vs_longitude"]["series"].size() == 9);  // one series per shell
  const double sigma = fig["residual_histogram"]["sigma_mm"];
  CHECK(sigma == Approx(report["summary"]["rms_mm"].get<double>()).epsilon(0.05));
  int binned = 0;
  for (const auto& b : fig["residual_histogram"]["bins"]) binned += b["count"].get<int>();
  CHECK(binned == report["summary"]["n"].get<int>());
  CHECK(fig.contains("validation_histogram"));
}

TEST_CASE("robocal solve names an outlier by file and line, and drops it only when asked") {
  TempDir dir;
  simulate(dir);
  // Bump line 40's bar length by 2 mm.
  std::string text = readTextFile(dir / "s.csv");
  size_t pos = 0;
  for (int line = 1; line < 40; ++line) pos = text.find('\n', pos) + 1;
  const size_t end = text.find('\n', pos);
  const size_t comma = text.rfind(',', end);
  const double length = std::stod(text.substr(comma + 1, end - comma - 1));
  text.replace(comma + 1, end - comma - 1, std::to_string(length + 2.0));
  std::ofstream(dir / "s.csv") << text;

  auto r = runRobocal("solve --model " + kModel + " " + (dir / "s.csv") + " --json");
  REQUIRE(r.exit_code == 0);
  auto j = nlohmann::json::parse(r.output);
  REQUIRE(j["outliers"].size() >= 1);
  CHECK(j["outliers"][0]["line"] == 40);
  CHECK(j["dropped"] == 0);
  const double rms_kept = j["rms_mm"];
  r = runRobocal("solve --model " + kModel + " " + (dir / "s.csv") + " --drop-outliers --json");
  REQUIRE(r.exit_code == 0);
  j = nlohmann::json::parse(r.output);
  CHECK(j["dropped"].get<int>() >= 1);
  CHECK(j["rms_mm"].get<double>() < rms_kept);
}

TEST_CASE("robocal solve: empty and broken inputs give clear errors") {
  TempDir dir;
  std::ofstream(dir / "empty.csv") << "";
  std::ofstream(dir / "header.csv") << kSamplesHeader << "\n";
  auto r = runRobocal("solve --model " + kModel + " " + (dir / "empty.csv"));
  CHECK(r.exit_code != 0);
  CHECK_THAT(r.output, Contains("empty.csv: empty"));
  r = runRobocal("solve --model " + kModel + " " + (dir / "header.csv"));
  CHECK(r.exit_code != 0);
  CHECK_THAT(r.output, Contains("no samples"));
  r = runRobocal("solve --model " + kModel);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("no samples file given"));
}

TEST_CASE("robocal solve on one shell reports the rank and solves what is identifiable") {
  TempDir dir;
  REQUIRE(
      runRobocal("simulate --model " + kModel + " --connections B2C2 --out " + (dir / "one.csv"))
          .exit_code == 0);
  const auto r = runRobocal("solve --model " + kModel + " " + (dir / "one.csv") + " --json");
  REQUIRE(r.exit_code == 0);
  const auto j = nlohmann::json::parse(r.output);
  CHECK(j["rank"].get<int>() < 36);
  CHECK(j["redundant"].size() == 54 - j["rank"].get<size_t>());
  CHECK(j["rms_mm"].get<double>() < 0.1);
}

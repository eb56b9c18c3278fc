#include <catch2/catch.hpp>

#include "cli_helpers.hpp"

#include <robocal/formats/model_json.hpp>
#include <robocal/formats/result_verdict.hpp>
#include <robocal/formats/samples_csv.hpp>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

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
  const auto r =
      runRobocal("solve --model " + kModel + " " + (dir / "s.csv") + " --validate " +
                 (dir / "v.csv") + " --report " + (dir / "rep") + " --out " + (dir / "cal.json"));
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.output, Contains("rank: 36 of 54"));
  for (const char* f :
       {"residuals_vs_longitude.svg", "residual_histogram.svg", "shell_rms.svg",
        "validation_vs_longitude.svg", "validation_histogram.svg", "validation_shell_rms.svg"}) {
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
  CHECK(fig["shell_rms"]["shells"].size() == 9);
  // One page with the numbers, the tables and the figures, nothing fetched from elsewhere.
  const std::string html = readTextFile(dir / "rep/summary.html");
  CHECK_THAT(html, Contains("<!DOCTYPE html>") && Contains("<td class='l'>L0.x</td>") &&
                       Contains("B3C3 +150 mm") && Contains("href='shell_rms.svg'") &&
                       Contains("<svg"));
  // The evidence the terminal prints beside the verdict is on the page too.
  CHECK_THAT(html, Contains(">model adequacy<") && Contains(">gravity compliance<") &&
                       Contains(">approach<"));
  CHECK_THAT(r.output, Contains("model adequacy: "));
  // One verdict: the page's box, the terminal's last block and report.json's object are one
  // rendering each of the same verdict, with the accuracy, the model written and the next step.
  const ResultVerdict verdict = resultVerdictFromJson(report["verdict"]);
  CHECK(verdict.usable);
  CHECK(verdict.rank == 36);
  REQUIRE(verdict.work_volume_rms_mm);
  REQUIRE(verdict.whole_range_rms_mm);
  CHECK(*verdict.work_volume_rms_mm < *verdict.whole_range_rms_mm);
  CHECK(std::filesystem::equivalent(verdict.model_file, dir / "cal.json"));
  CHECK_THAT(verdict.next_command,
             Contains("robocal compensate --model ") && Contains("cal.json --targets"));
  CHECK_THAT(html, Contains(resultVerdictHtml(verdict)));
  CHECK_THAT(r.output, Contains(resultVerdictText(verdict)));
  // The work-volume map is written, shown and linked.
  CHECK_THAT(readTextFile(dir / "rep/work_volume.svg"), Contains("</svg>"));
  CHECK_THAT(html, Contains("href='work_volume.svg'"));
  auto count = [&](const std::string& what) {
    size_t n = 0;
    for (size_t at = html.find(what); at != std::string::npos; at = html.find(what, at + 1)) ++n;
    return n;
  };
  CHECK(count("http") == count("http://www.w3.org/2000/svg"));  // no external assets
  CHECK(html.find("src=") == std::string::npos);
}

TEST_CASE("robocal solve names an outlier by file and line, and drops it only when asked") {
  TempDir dir;
  simulate(dir);
  // Bump line 40's bar length by 2 mm (the header is line 1).
  std::vector<Sample> samples = loadSamplesFile(dir / "s.csv");
  samples[40 - 2].length_mm += 2.0;
  saveSamplesFile(dir / "s.csv", samples);

  // Kept, the outlier makes the fit unusable (exit 3), and the problem names it and the fix.
  auto r = runRobocal("solve --model " + kModel + " " + (dir / "s.csv") + " --json", false);
  REQUIRE(r.exit_code == 3);
  auto j = nlohmann::json::parse(r.output);
  REQUIRE(j["outliers"].size() >= 1);
  CHECK(j["outliers"][0]["line"] == 40);
  CHECK(j["dropped"] == 0);
  REQUIRE(j["problems"].size() == 1);
  CHECK_THAT(j["problems"][0].get<std::string>(),
             Contains("kept in the fit") && Contains("s.csv:40") && Contains("--drop-outliers"));
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
  CHECK(r.exit_code == 3);  // not usable as a calibration, but fitted and reported
  const auto j = nlohmann::json::parse(r.output.substr(0, r.output.find('\n')));
  CHECK(j["rank"].get<int>() < 36);
  CHECK(j["redundant"].size() == 54 - j["rank"].get<size_t>());
  CHECK(j["rms_mm"].get<double>() < 0.1);
  CHECK(j["problems"].size() == 1);
}

TEST_CASE("robocal solve prints the parameter table and the residual per shell") {
  TempDir dir;
  simulate(dir);
  auto r = runRobocal("solve --model " + kModel + " " + (dir / "s.csv"));
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.output, Contains("  name       unit        nominal     calibrated       change    "
                                "1-sigma\n  L0.x       mm        -550.0000"));
  CHECK_THAT(r.output, Contains("  J1.gain    gain       1.000000"));
  CHECK_THAT(r.output, Contains("  L0.rz      deg         0.00000        0.00000     +0.00000      "
                                "fixed\n"));
  CHECK_THAT(r.output, Contains("  shell  connection        n   RMS (mm)   max (mm)  mean (mm)  "
                                "RMS/median\n      1  B1C1"));
  CHECK_THAT(r.output, Contains("worst shells: "));

  // The JSON has the same tables, with the unit in every key.
  r = runRobocal("solve --model " + kModel + " " + (dir / "s.csv") + " --json");
  REQUIRE(r.exit_code == 0);
  const auto j = nlohmann::json::parse(r.output);
  REQUIRE(j["parameter_table"].size() == 54);
  const auto& l0x = j["parameter_table"][0];
  CHECK(l0x["name"] == "L0.x");
  CHECK(l0x["unit"] == "mm");
  CHECK(l0x["nominal_mm"] == -550.0);
  CHECK(l0x["change_mm"].get<double>() ==
        Approx(l0x["calibrated_mm"].get<double>() - l0x["nominal_mm"].get<double>()));
  CHECK(l0x["sigma_mm"].get<double>() > 0);
  int estimated = 0;
  for (const auto& p : j["parameter_table"]) {
    estimated += p["estimated"].get<bool>();
    if (!p["estimated"].get<bool>()) CHECK(p["sigma_" + p["unit"].get<std::string>()].is_null());
  }
  CHECK(estimated == 36);
  CHECK(j["parameter_table"][7]["name"] == "J1.gain");
  CHECK(j["parameter_table"][7].contains("sigma_gain"));
  REQUIRE(j["shells"].size() == 9);
  CHECK(j["shells"][0]["connection"] == "B1C1");
  CHECK(j["worst_shells"].size() == 3);
  CHECK(j["problems"].empty());
}

TEST_CASE("robocal solve names a bad shell among good ones") {
  TempDir dir;
  simulate(dir);
  // Shell 4's lengths get three times the noise: its RMS stands out, as a loose chuck's would.
  std::vector<Sample> samples = loadSamplesFile(dir / "s.csv");
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 0.25);
  for (Sample& s : samples)
    if (s.shell == 4) s.length_mm += noise(rng);
  saveSamplesFile(dir / "s.csv", samples);
  const auto r = runRobocal("solve --model " + kModel + " " + (dir / "s.csv") + " --json", false);
  const auto j = nlohmann::json::parse(r.output);
  INFO(j["problems"].dump());
  CHECK(r.exit_code == 3);  // the noisy shell's worst points are outliers, kept
  CHECK(j["problems"].size() == 1);
  CHECK(j["worst_shells"][0] == 4);
  for (const auto& shell : j["shells"]) CHECK(shell["stands_out"] == (shell["shell"] == 4));
}

TEST_CASE("robocal solve refuses to write a model from data that cannot calibrate") {
  TempDir dir;
  simulate(dir);
  const std::string text = readTextFile(dir / "s.csv");
  size_t end = 0;
  for (int line = 0; line < 6; ++line) end = text.find('\n', end) + 1;  // header + 5 samples
  std::ofstream(dir / "five.csv") << text.substr(0, end);

  SECTION("5 samples") {
    const auto r = runRobocal("solve --model " + kModel + " " + (dir / "five.csv") + " --out " +
                              (dir / "cal.json"));
    INFO(r.output);
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.output, Contains("refused") && Contains("rank 5 of the 36") &&
                             Contains("no model written") && Contains("--allow-partial"));
    // The verdict's block says the same, and what to do next.
    CHECK_THAT(r.output, Contains("verdict: NOT USABLE as a calibration (rank 5 of 36):") &&
                             Contains("model: none written") &&
                             Contains("next: robocal solve --model ") &&
                             Contains("Put right what the first problem says"));
    CHECK_FALSE(std::filesystem::exists(dir / "cal.json"));
  }
  SECTION("2 shells") {
    REQUIRE(runRobocal("simulate --model " + kModel + " --connections B1C1,B2C2 --out " +
                       (dir / "two.csv"))
                .exit_code == 0);
    const auto r = runRobocal("solve --model " + kModel + " " + (dir / "two.csv") + " --out " +
                              (dir / "cal.json"));
    INFO(r.output);
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.output, Contains("of the 36 independent parameters") &&
                             Contains("2 of the 9 connections (B1C1,B2C2)"));
    CHECK_FALSE(std::filesystem::exists(dir / "cal.json"));
  }
  SECTION("a predicted error above the nominal model's") {
    // Full rank, but 6 points a shell with 1.5 mm of noise pin nothing.
    REQUIRE(runRobocal("simulate --model " + kModel +
                       " --seed 3 --noise-mm 1.5 --points-per-shell 6 --out " + (dir / "noisy.csv"))
                .exit_code == 0);
    const auto r = runRobocal("solve --model " + kModel + " " + (dir / "noisy.csv") + " --out " +
                              (dir / "cal.json"));
    INFO(r.output);
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.output, Contains("rank: 36 of 54") &&
                             Contains("exceeds the nominal model's error on these samples"));
    CHECK_FALSE(std::filesystem::exists(dir / "cal.json"));
  }
  SECTION("--allow-partial writes it, with a warning kept in its provenance") {
    const auto r = runRobocal("solve --model " + kModel + " " + (dir / "five.csv") + " --out " +
                              (dir / "cal.json") + " --allow-partial");
    INFO(r.output);
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.output,
               Contains("warning") && Contains("rank 5 of the 36") && Contains("written anyway"));
    const Model cal = loadModelFile(dir / "cal.json");
    REQUIRE(cal.provenance);
    REQUIRE(cal.provenance->warnings.size() >= 1);
    CHECK_THAT(cal.provenance->warnings[0], Contains("rank 5 of the 36"));
    CHECK(cal.provenance->rank == 5);
  }
}

TEST_CASE("the calibrated model says where it came from") {
  TempDir dir;
  simulate(dir);
  const auto r = runRobocal("solve --model " + kModel + " " + (dir / "s.csv") + " --out " +
                            (dir / "cal.json") + " --json");
  REQUIRE(r.exit_code == 0);
  const auto j = nlohmann::json::parse(r.output);
  const Model nominal = loadModelFile(kModel);
  const Model cal = loadModelFile(dir / "cal.json");
  CHECK_THAT(cal.name, Contains(nominal.name + " calibrated 20"));
  REQUIRE(cal.provenance);
  const ModelProvenance& p = *cal.provenance;
  CHECK(p.run_id.empty());
  CHECK(p.date_utc.size() == 20);  // 2026-12-01T20:42:54Z
  CHECK(p.nominal_name == nominal.name);
  CHECK(p.samples_files == std::vector<std::string>{dir / "s.csv"});
  CHECK(p.samples == j["n"].get<size_t>());
  CHECK(p.rms_mm == j["rms_mm"].get<double>());
  CHECK(p.rank == 36);
  CHECK(p.expected_rank == 36);
  CHECK_FALSE(p.robocal_version.empty());
  CHECK(p.warnings.empty());
}

TEST_CASE("robocal solve --truth judges against the true robot, backlash and compliance included") {
  TempDir dir;
  REQUIRE(runRobocal("simulate --model " + kModel +
                     " --seed 5 --points-per-shell 60 --realism typical --noise-mm 0.01 --out " +
                     (dir / "s.csv") + " --truth-out " + (dir / "t.json"))
              .exit_code == 0);
  // The same truth's geometry alone, as solve judged until 2026-12-07.
  nlohmann::json rigid = nlohmann::json::parse(std::ifstream(dir / "t.json"));
  REQUIRE(rigid.contains("realism"));
  rigid.erase("realism");
  std::ofstream(dir / "rigid.json") << rigid.dump();
  const auto judged = [&](const std::string& truth) {
    const auto r = runRobocal("solve --model " + kModel + " " + (dir / "s.csv") + " --truth " +
                              (dir / truth) + " --json --allow-partial");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    return nlohmann::json::parse(r.output)["truth_calibrated_rms_mm"].get<double>();
  };
  const double true_robot_mm = judged("t.json");
  const double geometry_mm = judged("rigid.json");
  INFO("against the true robot " << true_robot_mm << " mm, its geometry alone " << geometry_mm);
  // The fit absorbs the twist into the offsets: against the geometry alone it looks far off.
  CHECK(true_robot_mm < 0.12);
  CHECK(geometry_mm > 2 * true_robot_mm);
}

TEST_CASE("robocal solve takes the approach the samples record, and says when they record none") {
  TempDir dir;
  simulate(dir);  // the simulator's own grid: straight from point to point, recorded as 0
  std::vector<Sample> samples = loadSamplesFile(dir / "s.csv");
  REQUIRE(samples[0].approach_deg);
  CHECK(*samples[0].approach_deg == 0);
  for (Sample& s : samples) s.approach_deg = 0.02;  // as robocald and simulate --plan write them
  saveSamplesFile(dir / "up.csv", samples);
  for (Sample& s : samples) s.approach_deg.reset();  // a file from before the record
  saveSamplesFile(dir / "unrecorded.csv", samples);

  // Recorded: the model takes it with no option, and compensate reaches targets the same way.
  auto r = runRobocal("solve --model " + kModel + " " + (dir / "up.csv") + " --out " +
                      (dir / "up.json"));
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  CHECK(r.output.find("do not record how") == std::string::npos);
  REQUIRE(loadModelFile(dir / "up.json").provenance);
  CHECK(loadModelFile(dir / "up.json").provenance->approach_deg == Approx(0.02));
  std::ofstream(dir / "poses.csv")
      << "name,x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg\nhome,0,0,250,0,135,0\n";
  r = runRobocal("compensate --model " + (dir / "up.json") + " --targets " + (dir / "poses.csv") +
                 " --out " + (dir / "up-targets.csv"));
  REQUIRE(r.exit_code == 0);
  std::stringstream written;
  written << std::ifstream(dir / "up-targets.csv").rdbuf();
  CHECK_THAT(written.str(), Contains(",1,1,1,1,1,1,"));  // each joint up from its pre-point

  // An option that contradicts the record is refused, nothing written.
  r = runRobocal("solve --model " + kModel + " " + (dir / "up.csv") + " --approach-deg 0 --out " +
                 (dir / "never.json"));
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("the samples record 0.0200 deg"));
  CHECK_FALSE(std::filesystem::exists(dir / "never.json"));

  // Not recorded: the fit goes on assuming none, and says so and what to do.
  r = runRobocal("solve --model " + kModel + " " + (dir / "unrecorded.csv") + " --out " +
                 (dir / "plain.json"));
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.output, Contains("samples do not record how their points were approached"));
  CHECK_THAT(r.output, Contains("--approach-deg D"));
  CHECK(loadModelFile(dir / "plain.json").provenance->approach_deg == 0);
}

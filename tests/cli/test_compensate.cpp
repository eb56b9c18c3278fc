// robocal compensate and robocal accuracy, run as a user runs them.
#include <catch2/catch.hpp>

#include "cli_helpers.hpp"

#include <robocal/formats/samples_csv.hpp>

#include <robocal/formats/csv.hpp>
#include <robocal/formats/program.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

using namespace robocal::test;
using Catch::Matchers::Contains;

namespace {

void writeFile(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST_CASE("[cli] robocal compensate returns a program's own joints when nothing was calibrated") {
  TempDir dir;
  const char* rows[] = {"a,12.3456789012,-33.25,-171.5,-20.125,40.5,100.0000000001",
                        "b,-45,60,-140,20,45,30", "c,0.5,10,-170,10,-60,-200"};
  std::string program = "name,j1,j2,j3,j4,j5,j6\n";
  for (const char* r : rows) program += std::string(r) + "\n";
  writeFile(dir / "program.csv", program);
  const RunResult r = runRobocal("compensate --model " + kModel + " --nominal " + kModel +
                                 " --targets " + dir / "program.csv" + " --out " + dir / "out.csv");
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.output, Contains("3 ok, 0 not ok"));
  const std::string out = readFile(dir / "out.csv");
  std::istringstream lines(out);
  std::string line;
  std::getline(lines, line);
  CHECK(line == "name,j1,j2,j3,j4,j5,j6,a1,a2,a3,a4,a5,a6,predicted_error_mm,status,config,note");
  for (const char* row : rows) {
    REQUIRE(std::getline(lines, line));
    const auto got = robocal::csv::splitFields(line);
    const auto want = robocal::csv::splitFields(row);
    CHECK(got[0] == want[0]);
    for (int j = 1; j <= 6; ++j)
      CHECK(std::abs(*robocal::csv::number(got[j]) - *robocal::csv::number(want[j])) < 1e-9);
    for (int j = 7; j <= 12; ++j) CHECK(got[j].empty());  // no approach recorded, none assumed
    CHECK(got[14] == "ok");
  }
}

TEST_CASE(
    "[cli] compensate refuses targets in other units, an empty file and its own input as --out") {
  TempDir dir;
  const std::string base = "compensate --model " + kModel + " --nominal " + kModel + " --targets ";
  // Joints in radians: refused, the conversion named, nothing written.
  writeFile(dir / "rad.csv",
            "j1,j2,j3,j4,j5,j6\n-0.0427,0.5939,-3.3735,0.1,0.2,0.3\n"
            "0.1,0.6,-3.1,0.2,-0.4,1.5\n");
  // A refusal: the exit status and the words, and nothing written.
  const auto refused = [&](const std::string& targets, int exit_code, const std::string& words) {
    const RunResult run = runRobocal(base + dir / targets + " --out " + dir / "never.csv");
    INFO(run.output);
    CHECK(run.exit_code == exit_code);
    CHECK_THAT(run.output, Contains(words));
    CHECK_FALSE(std::filesystem::exists(dir / "never.csv"));
    return run;
  };
  CHECK_THAT(refused("rad.csv", 2, "as if in radians").output, Contains("nothing was written"));
  // Poses in metres.
  writeFile(dir / "m.csv", "x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg\n0.1,0.2,0.25,0,135,0\n");
  refused("m.csv", 2, "as if in metres");
  RunResult r;
  // A user sure of the units says so: the file is taken as written.
  r = runRobocal(base + dir / "m.csv" + " --units-as-given --out " + dir / "given.csv");
  CHECK(r.exit_code != 2);
  CHECK(std::filesystem::exists(dir / "given.csv"));
  // No targets: an error, not "0 targets".
  writeFile(dir / "empty.csv", "j1,j2,j3,j4,j5,j6\n");
  refused("empty.csv", 1, "no targets");
  // --out naming the targets file (here through another spelling of its path): refused, kept.
  const std::string targets = "j1,j2,j3,j4,j5,j6\n10,45,-170,0,30,0\n";
  writeFile(dir / "t.csv", targets);
  r = runRobocal(base + dir / "t.csv" + " --out " + dir.path.string() + "/./t.csv");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("is the --targets file"));
  CHECK(readFile(dir / "t.csv") == targets);
  // Its own output given back as targets is recognised.
  REQUIRE(runRobocal(base + dir / "t.csv" + " --out " + dir / "out.csv").exit_code == 0);
  r = runRobocal(base + dir / "out.csv" + " --out " + dir / "again.csv");
  CHECK(r.exit_code == 1);
  CHECK_THAT(r.output, Contains("this is robocal compensate's output"));
}

TEST_CASE("[cli] a model without a recorded nominal: the built-in of its name, else --nominal") {
  TempDir dir;
  writeFile(dir / "program.csv", "name,j1,j2,j3,j4,j5,j6\nb,-45,60,-140,20,45,30\n");
  const std::string targets = " --targets " + dir / "program.csv";
  // The PUMA's nominal file is a model robocal carries: found by its name.
  RunResult r = runRobocal("compensate --model " + kModel + targets + " --out " + dir / "puma.csv");
  INFO(r.output);
  CHECK(r.exit_code == 0);
  CHECK_THAT(r.output, Contains("nominal: the built-in \"PUMA 560"));
  // Another arm's nominal is not compensated against the PUMA's: refused until named.
  const std::string rx160 = ROBOCAL_SOURCE_DIR "/config/rx160.json";
  r = runRobocal("compensate --model " + rx160 + targets + " --out " + dir / "never.csv");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("does not record the nominal") && Contains("give --nominal"));
  CHECK_FALSE(std::ifstream(dir / "never.csv").good());
  r = runRobocal("accuracy --calibrated " + rx160);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("Staubli RX160") && Contains("give --nominal"));
  r = runRobocal("compensate --model " + rx160 + " --nominal " + rx160 + targets + " --out " +
                 dir / "rx160.csv");
  CHECK(r.exit_code == 0);
  CHECK(std::ifstream(dir / "rx160.csv").good());
}

TEST_CASE("[cli] robocal compensate and accuracy on a simulated calibration") {
  TempDir dir;
  REQUIRE(runRobocal("simulate --model " + kModel + " --seed 3 --points-per-shell 40 --out " +
                     dir / "s.csv" + " --truth-out " + dir / "truth.json")
              .exit_code == 0);
  REQUIRE(runRobocal("solve --model " + kModel + " " + dir / "s.csv" + " --out " + dir / "cal.json")
              .exit_code == 0);
  SECTION("accuracy over the reference work volume, with the truth") {
    const RunResult r =
        runRobocal("accuracy --nominal " + kModel + " --calibrated " + dir / "cal.json" +
                   " --truth " + dir / "truth.json" + " --json --svg " + dir / "map.svg");
    REQUIRE(r.exit_code == 0);
    const auto j = nlohmann::json::parse(r.output);
    // Every pose solved; those where the calibration's shells did not reach (joint 2 past the
    // 0-49 deg they measured) say so, with the joint.
    CHECK(j["solved"] == 200);
    int outside = 0;
    for (const auto& p : j["per_pose"])
      if (p["status"] == "outside_measured") {
        ++outside;
        CHECK_THAT(p["note"].get<std::string>(), Contains("the calibration measured it over"));
      } else {
        CHECK(p["status"] == "ok");
      }
    CHECK(j["ok"] == 200 - outside);
    const double nominal = j["nominal_commanded_position_error_mm"]["rms"];
    const double compensated = j["compensated_commanded_position_error_mm"]["rms"];
    CHECK(compensated < nominal / 5);
    CHECK(j["predicted_position_error_mm"]["rms"].get<double>() > 0);
    CHECK(j["per_pose"].size() == 200);
    CHECK(j["per_pose"][0]["approach"].is_null());  // none recorded, none assumed
    // Beyond the work volume: the whole range, with the truth, and the options exclusive.
    const RunResult whole =
        runRobocal("accuracy --nominal " + kModel + " --calibrated " + dir / "cal.json" +
                   " --truth " + dir / "truth.json" + " --whole-range 30 --json");
    REQUIRE(whole.exit_code == 0);
    const auto w = nlohmann::json::parse(whole.output);
    CHECK_THAT(w["poses_from"].get<std::string>(), Contains("whole range: 30 joint vectors"));
    CHECK(w["per_pose"].size() == 30);
    CHECK(w["compensated_commanded_position_error_mm"]["rms"].get<double>() > compensated);
    CHECK(runRobocal("accuracy --calibrated " + dir / "cal.json" + " --whole-range 30 --cell " +
                     ROBOCAL_SOURCE_DIR "/config/cell.json")
              .exit_code == 2);
    CHECK_THAT(readFile(dir / "map.svg"), Contains("<svg"));
  }
  SECTION("compensate writes VAL II points, and malformed rows are named") {
    writeFile(dir / "poses.csv",
              "name,x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg\nhome,0,0,250,0,135,0\n"
              "away,5000,0,0,0,0,0\n");
    RunResult r = runRobocal("compensate --model " + dir / "cal.json" + " --nominal " + kModel +
                             " --targets " + dir / "poses.csv" + " --out " + dir / "p.val2" +
                             " --format val2-move");
    INFO(r.output);
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.output, Contains("poses.csv:3: away: unreachable"));
    const std::string val2 = readFile(dir / "p.val2");
    CHECK_THAT(val2, Contains("DO MOVE #PPOINT("));
    CHECK_THAT(val2, Contains("; away: unreachable"));

    r = runRobocal("compensate --model " + dir / "cal.json" + " --nominal " + kModel +
                   " --targets " + dir / "poses.csv" + " --out " + dir / "p.lc" +
                   " --format vplus-locations");
    CHECK(r.exit_code == 3);
    const std::string lc = readFile(dir / "p.lc");
    CHECK_THAT(lc, Contains("\n.LOCATIONS\n#home "));
    CHECK_THAT(lc, Contains("\n; away: unreachable"));
    // A name the controller would not take: refused with its line, nothing written.
    writeFile(dir / "named.csv",
              "name,x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg\nhome 2,0,0,250,0,135,0\n");
    r = runRobocal("compensate --model " + dir / "cal.json" + " --nominal " + kModel +
                   " --targets " + dir / "named.csv" + " --out " + dir / "never.as" +
                   " --format as-joints");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Contains("named.csv:2: 'home 2' is not a location name"));
    CHECK_FALSE(std::ifstream(dir / "never.as").good());

    writeFile(dir / "bad.csv", "x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg\n1,2,3,4,5\n");
    r = runRobocal("compensate --model " + dir / "cal.json" + " --nominal " + kModel +
                   " --targets " + dir / "bad.csv" + " --out " + dir / "never.csv");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Contains("bad.csv:2: expected 6 fields, got 5"));
    CHECK_FALSE(std::ifstream(dir / "never.csv").good());
  }
  SECTION("a calibration that approached its points from below reaches the targets so too") {
    // Samples from before the approach was recorded with them: the option says it.
    std::vector<robocal::Sample> unrecorded = robocal::loadSamplesFile(dir / "s.csv");
    for (robocal::Sample& s : unrecorded) s.approach_deg.reset();
    robocal::saveSamplesFile(dir / "s-unrecorded.csv", unrecorded);
    REQUIRE(runRobocal("solve --model " + kModel + " " + dir / "s-unrecorded.csv" +
                       " --approach-deg 0.02" + " --out " + dir / "up.json")
                .exit_code == 0);
    CHECK(nlohmann::json::parse(readFile(dir / "up.json"))["provenance"]["approach_deg"] == 0.02);
    writeFile(dir / "poses.csv",
              "name,x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg\nhome,0,0,250,0,135,0\n");
    RunResult r = runRobocal("compensate --model " + dir / "up.json" + " --targets " +
                             dir / "poses.csv" + " --out " + dir / "up.csv");
    INFO(r.output);
    CHECK_THAT(r.output, Contains("from a pre-point 0.02 deg below it in every joint (as the "
                                  "calibration reached its points)"));
    CHECK_THAT(readFile(dir / "up.csv"), Contains(",1,1,1,1,1,1,"));
    r = runRobocal("compensate --model " + dir / "up.json" + " --targets " + dir / "poses.csv" +
                   " --out " + dir / "up.val2" + " --format val2-move");
    const std::string val2 = readFile(dir / "up.val2");
    CHECK_THAT(val2, Contains("; each target follows its approach pre-point, 0.0200 deg below"));
    CHECK(std::count(val2.begin(), val2.end(), '#') == 2);  // pre-point and target
    r = runRobocal("accuracy --nominal " + kModel + " --calibrated " + dir / "up.json" +
                   " --truth " + dir / "truth.json" + " --json");
    const auto j = nlohmann::json::parse(r.output);
    CHECK(j["per_pose"][0]["approach"] == nlohmann::json::array({1, 1, 1, 1, 1, 1}));
    CHECK(runRobocal("solve --model " + kModel + " " + dir / "s-unrecorded.csv" +
                     " --approach-deg 2" + " --out " + dir / "never.json")
              .exit_code == 2);
  }
}

TEST_CASE("[cli] compensate and accuracy use the nominal the calibration started from") {
  TempDir dir;
  // A controller whose model is not robocal's built-in PUMA: link 2 half a millimetre longer.
  nlohmann::json edited = nlohmann::json::parse(readFile(kModel));
  edited["name"] = "our PUMA";
  edited["links"][2]["x"] = edited["links"][2]["x"].get<double>() + 0.5;
  writeFile(dir / "ours.json", edited.dump(2));
  REQUIRE(runRobocal("simulate --model " + dir / "ours.json" +
                     " --seed 4 --points-per-shell 30 --out " + dir / "s.csv")
              .exit_code == 0);
  REQUIRE(runRobocal("solve --model " + dir / "ours.json" + " " + dir / "s.csv" + " --out " +
                     dir / "cal.json")
              .exit_code == 0);
  const auto cal = nlohmann::json::parse(readFile(dir / "cal.json"));
  CHECK(cal["provenance"]["nominal_parameters"]["L2.x"] == edited["links"][2]["x"]);
  // A program point where the calibration measured: the joints of a sample (columns j1..j6).
  std::istringstream samples(readFile(dir / "s.csv"));
  std::string row;
  std::getline(samples, row);
  std::getline(samples, row);
  const auto fields = robocal::csv::splitFields(row);
  std::string joints;
  for (int j = 6; j < 12; ++j) joints += "," + std::string(fields[j]);
  writeFile(dir / "program.csv",
            "name,j1,j2,j3,j4,j5,j6\nmeasured" + joints + "\nelsewhere,10,-40,-160,5,30,0\n");
  const std::string compensate =
      "compensate --model " + dir / "cal.json" + " --targets " + dir / "program.csv";

  // Joint 2 at -40 deg is far outside what the shells measured: written, with the status saying so.
  RunResult r = runRobocal(compensate + " --out " + dir / "recorded.csv");
  INFO(r.output);
  CHECK(r.exit_code == 3);
  CHECK_THAT(r.output, Contains("nominal: \"our PUMA\", the one") && Contains("1 ok, 1 not ok") &&
                           Contains("elsewhere: outside_measured: joint 2 at -"));
  r = runRobocal(compensate + " --nominal " + dir / "ours.json" + " --out " + dir / "same.csv");
  CHECK(r.exit_code == 3);
  CHECK(readFile(dir / "same.csv") == readFile(dir / "recorded.csv"));

  r = runRobocal(compensate + " --nominal " + kModel + " --out " + dir / "never.csv");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("is not the nominal") && Contains("L2.x is"));
  CHECK_FALSE(std::ifstream(dir / "never.csv").good());
  r = runRobocal("accuracy --calibrated " + dir / "cal.json" + " --nominal " + kModel);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("L2.x is"));
  r = runRobocal("accuracy --calibrated " + dir / "cal.json" + " --json");
  CHECK(r.exit_code == 0);
}

TEST_CASE("[cli] a true robot that is not its model: simulate --realism, judged by accuracy") {
  TempDir dir;
  double compensated_rms[2] = {0, 0};
  const char* realism[2] = {"ideal", "typical"};
  for (int k = 0; k < 2; ++k) {
    const std::string s = dir / (std::string(realism[k]) + ".csv");
    const std::string t = dir / (std::string(realism[k]) + "-truth.json");
    const std::string cal = dir / (std::string(realism[k]) + "-cal.json");
    const RunResult sim =
        runRobocal("simulate --model " + kModel + " --seed 5 --points-per-shell 60 --realism " +
                   realism[k] + " --out " + s + " --truth-out " + t);
    INFO(sim.output);
    REQUIRE(sim.exit_code == 0);
    CHECK((sim.output.find("realism: backlash up to 0.01 deg") != std::string::npos) == (k == 1));
    CHECK(nlohmann::json::parse(readFile(t)).contains("realism") == (k == 1));
    REQUIRE(runRobocal("solve --model " + kModel + " " + s + " --out " + cal).exit_code == 0);
    const RunResult acc =
        runRobocal("accuracy --calibrated " + cal + " --truth " + t + " --json", false);
    REQUIRE(acc.exit_code == 0);
    compensated_rms[k] =
        nlohmann::json::parse(acc.output)["compensated_commanded_position_error_mm"]["rms"];
  }
  INFO("compensated RMS: ideal " << compensated_rms[0] << " mm, typical " << compensated_rms[1]);
  // Backlash, compliance, warm-up and the LVDT's errors are error the model cannot remove (a
  // calibration with no approach, judged from either side as its targets are reached: 1.2x).
  CHECK(compensated_rms[1] > 1.15 * compensated_rms[0]);
}

TEST_CASE(
    "[cli] compensate with a model's compliance: the twist corrected, the work tool's "
    "payload weighs more") {
  TempDir dir;
  nlohmann::json model = nlohmann::json::parse(readFile(kModel));
  model["compliance"]["compliance_deg_per_nm"] = {0, 0.0007, 0.0015, 0, 0, 0};
  writeFile(dir / "compliant.json", model.dump());
  writeFile(dir / "program.csv",
            "name,j1,j2,j3,j4,j5,j6\na,10,30,-160,20,40,30\n"
            "b,-40,100,-20,0,60,0\n");
  // The joint-2 correction of each row of a compensate run (deg).
  const auto corrections = [&](const std::string& more) {
    const RunResult r =
        runRobocal("compensate --model " + dir / "compliant.json" + " --nominal " + kModel +
                   " --targets " + dir / "program.csv" + " --out " + dir / "out.csv" + more);
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    std::istringstream lines(readFile(dir / "out.csv"));
    std::string line;
    std::getline(lines, line);
    std::vector<double> out;
    for (const double nominal_j2 : {30.0, 100.0}) {
      REQUIRE(std::getline(lines, line));
      out.push_back(*robocal::csv::number(robocal::csv::splitFields(line)[2]) - nominal_j2);
    }
    return out;
  };
  const std::vector<double> fixture = corrections("");
  const std::vector<double> heavy = corrections(" --payload-kg 10 --payload-com 0,0,120");
  for (size_t i = 0; i < fixture.size(); ++i) {
    CHECK(std::abs(fixture[i]) > 0.002);  // the twist under the arm's own weight, taken out
    CHECK(std::abs(heavy[i]) > std::abs(fixture[i]) + 0.002);
  }

  SECTION("a payload for a rigid model, or a bad centre, is refused and says why") {
    RunResult r = runRobocal("compensate --model " + kModel + " --targets " + dir / "program.csv" +
                             " --out " + dir / "rigid.csv --payload-kg 5");
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.output, Contains("puma560-paper.json carries no compliance"));
    r = runRobocal("compensate --model " + dir / "compliant.json" + " --nominal " + kModel +
                   " --targets " + dir / "program.csv" + " --out " + dir / "bad.csv" +
                   " --payload-com 0,60");
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.output, Contains("--payload-com: expected x,y,z in mm"));
  }
}

TEST_CASE("[cli] robocal compensate --program writes the program with its locations corrected") {
  TempDir dir;
  REQUIRE(runRobocal("simulate --model " + kModel + " --seed 3 --points-per-shell 40 --out " +
                     dir / "s.csv")
              .exit_code == 0);
  REQUIRE(runRobocal("solve --model " + kModel + " " + dir / "s.csv" + " --out " + dir / "cal.json")
              .exit_code == 0);
  const std::string samples = ROBOCAL_SOURCE_DIR "/tests/formats/programs/";
  struct Case {
    const char* file;
    const char* dialect;
    robocal::ProgramDialect parsed_as;
    bool undefined;
  };
  for (const Case& c : {Case{"pick_place.as", "as", robocal::ProgramDialect::kAs, true},
                        Case{"pick_place.v2", "vplus", robocal::ProgramDialect::kVplus, false},
                        Case{"pick_place.pg", "val2", robocal::ProgramDialect::kVal2, false}}) {
    INFO(c.file);
    const std::string in = samples + c.file, out = dir / (std::string("out-") + c.file);
    const RunResult r = runRobocal("compensate --model " + dir / "cal.json" + " --program " + in +
                                   " --dialect " + c.dialect + " --out " + out);
    INFO(r.output);
    // The sample's #not_taught is used and never defined: named with its line, the rest written.
    if (c.undefined) {
      CHECK(r.exit_code == 3);
      CHECK_THAT(r.output, Contains(in + ":11: #not_taught is used but not defined"));
    }
    REQUIRE(std::filesystem::exists(out));
    // The same joints through the targets CSV: the program's locations are those corrections.
    const robocal::ProgramFile before = robocal::parseProgram(readFile(in), c.parsed_as, in);
    const robocal::ProgramFile after = robocal::parseProgram(readFile(out), c.parsed_as, out);
    REQUIRE(after.locations.size() == before.locations.size());
    std::string csv = "name,j1,j2,j3,j4,j5,j6\n";
    for (const auto& loc : before.locations) {
      csv += "x";
      for (int j = 0; j < 6; ++j) csv += "," + std::to_string(loc.joints_deg[j]);
      csv += "\n";
    }
    writeFile(dir / "targets.csv", csv);
    runRobocal("compensate --model " + dir / "cal.json" + " --targets " + dir / "targets.csv" +
               " --approach-deg 0 --out " + dir / "want.csv");
    std::istringstream want(readFile(dir / "want.csv"));
    std::string line;
    std::getline(want, line);  // header
    for (const auto& loc : after.locations) {
      REQUIRE(std::getline(want, line));
      const auto f = robocal::csv::splitFields(line);
      if (f[1].empty()) continue;  // not corrected: kept as it was
      for (int j = 0; j < 6; ++j)
        CHECK(std::abs(loc.joints_deg[j] - *robocal::csv::number(f[j + 1])) < 1e-6);
    }
    CHECK(after.locations[0].joints_deg != before.locations[0].joints_deg);  // a real correction
  }
  // A program with targets, a dialect without a program, and an unknown dialect: usage errors.
  for (const std::string& bad :
       {" --program " + samples + "pick_place.as --targets x.csv --dialect as",
        std::string(" --targets x.csv --dialect as"),
        " --program " + samples + "pick_place.as --dialect kuka",
        " --program " + samples + "pick_place.as --dialect as --format val2"}) {
    INFO(bad);
    CHECK(runRobocal("compensate --model " + dir / "cal.json" + bad + " --out " + dir / "bad")
              .exit_code == 2);
  }
}

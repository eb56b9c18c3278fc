#include <catch2/catch.hpp>

#include <robocal/formats/model_json.hpp>
#include <robocal/formats/report.hpp>
#include <robocal/robot/puma560.hpp>

#include <nlohmann/json.hpp>

using namespace robocal;
using Catch::Matchers::Contains;

namespace {
std::string shipped() {
  return readTextFile(ROBOCAL_SOURCE_DIR "/config/puma560.json");
}

// The shipped model with one edit applied to its JSON.
std::string edited(const std::function<void(nlohmann::json&)>& edit) {
  nlohmann::json j = nlohmann::json::parse(shipped());
  edit(j);
  return j.dump();
}
}  // namespace

TEST_CASE("config/puma560.json is the PUMA 560 derived from its DH table") {
  const Model file = parseModel(shipped(), "puma560.json");
  CHECK(toParams(file).isApprox(toParams(puma560NominalModel()), 1e-12));
  for (int b = 0; b < kBallCount; ++b) CHECK(file.balls_mm[b] == puma560NominalModel().balls_mm[b]);
  CHECK(file.joints[1].min_deg == -45);
  CHECK(file.joints[5].max_deg == 266);
  // The reference cell's chucks are placed about 600 mm apart (docs/accuracy.md, "Chucks placed
  // apart"); the paper's compact fixture, 150 mm, is config/puma560-paper.json, the built-in's.
  CHECK((file.chucks_mm[0] - file.chucks_mm[1]).norm() == Approx(600).epsilon(0.001));
  CHECK((file.chucks_mm[1] - file.chucks_mm[2]).norm() == Approx(600).epsilon(0.001));
  const Model paper = loadModelFile(ROBOCAL_SOURCE_DIR "/config/puma560-paper.json");
  CHECK(toParams(paper).isApprox(toParams(file), 1e-12));
  for (int c = 0; c < kChuckCount; ++c)
    CHECK(paper.chucks_mm[c] == puma560NominalModel().chucks_mm[c]);
}

TEST_CASE("a model survives the round trip through its file format exactly") {
  Model m = puma560NominalModel();
  m.links[3].ry_deg = 0.0123456789012345;
  m.joints[4].gain = 1.000321;
  const Model back = parseModel(formatModel(m));
  CHECK(toParams(back) == toParams(m));
  CHECK(back.name == m.name);
  CHECK(back.links[3].name == m.links[3].name);
  CHECK(back.chucks_mm[2] == m.chucks_mm[2]);
  // A joint's rated speed and torque, when known; absent from the file when not.
  m.joints[1].velocity_deg_per_s = 180.5;
  m.joints[1].effort_nm = 150;
  const std::string text = formatModel(m);
  const Model rated = parseModel(text);
  CHECK(rated.joints[1].velocity_deg_per_s == 180.5);
  CHECK(rated.joints[1].effort_nm == 150);
  CHECK(rated.joints[0].velocity_deg_per_s == 0);
  CHECK(nlohmann::json::parse(text)["joints"][0].count("velocity_deg_per_s") == 0);
}

TEST_CASE("a calibrated model's provenance survives the round trip, older files have none") {
  Model m = puma560NominalModel();
  CHECK_FALSE(parseModel(shipped()).provenance);  // a file without one reads as before
  CHECK(formatModel(m).find("provenance") == std::string::npos);
  ModelProvenance p;
  p.run_id = "20261201-204254";
  p.date_utc = "2026-12-01T20:42:54Z";
  p.nominal_name = m.name;
  p.samples_files = {"/var/lib/robocald/runs/20261201-204254/samples.csv"};
  p.samples = 1612;
  p.rms_mm = 0.0299123456789;
  p.rank = 36;
  p.expected_rank = 36;
  p.robocal_version = "0.1.0";
  p.warnings = {"a warning"};
  m.provenance = p;
  const Model back = parseModel(formatModel(m));
  REQUIRE(back.provenance);
  const ModelProvenance& q = *back.provenance;
  CHECK(q.run_id == p.run_id);
  CHECK(q.date_utc == p.date_utc);
  CHECK(q.nominal_name == p.nominal_name);
  CHECK(q.samples_files == p.samples_files);
  CHECK(q.samples == p.samples);
  CHECK(q.rms_mm == p.rms_mm);
  CHECK(q.rank == p.rank);
  CHECK(q.expected_rank == p.expected_rank);
  CHECK(q.robocal_version == p.robocal_version);
  CHECK(q.warnings == p.warnings);
  CHECK(formatModel(back) == formatModel(m));
  // Keys a later version may add are ignored; the known ones are checked.
  CHECK(parseModel(edited([](auto& j) {
          j["provenance"] = {{"rank", 30}, {"new_key", 1}};
        })).provenance->rank == 30);
  CHECK_THROWS_WITH(parseModel(edited([](auto& j) { j["provenance"] = "x"; }), "m.json"),
                    Contains("m.json: provenance: expected an object"));
  CHECK_THROWS_WITH(parseModel(edited([](auto& j) {
                      j["provenance"] = {{"rank", 3.5}};
                    })),
                    Contains("provenance.rank: expected a whole number"));
  CHECK_THROWS_WITH(parseModel(edited([](auto& j) {
                      j["provenance"] = {{"samples_files", {1}}};
                    })),
                    Contains("provenance.samples_files[0]: expected a string"));
}

TEST_CASE("the calibrated model is named after its nominal and the day, with its provenance") {
  FitAssessment fit;
  fit.nominal = puma560NominalModel();
  fit.calibrated = fit.nominal;
  fit.samples.resize(12);
  fit.fit.after.rms_mm = 0.031;
  fit.fit.identifiability.rank = 33;
  fit.problems = {"rank 33 of the 36"};
  const auto made = std::chrono::system_clock::from_time_t(1796157774);  // 2026-12-01T20:42:54Z
  const Model m = calibratedModel(fit, {"run-7", {"s.csv"}}, made);
  CHECK(m.name == fit.nominal.name + " calibrated 2026-12-01");
  REQUIRE(m.provenance);
  CHECK(m.provenance->run_id == "run-7");
  CHECK(m.provenance->date_utc == "2026-12-01T20:42:54Z");
  CHECK(m.provenance->samples_files == std::vector<std::string>{"s.csv"});
  CHECK(m.provenance->samples == 12);
  CHECK(m.provenance->rms_mm == 0.031);
  CHECK(m.provenance->rank == 33);
  CHECK(m.provenance->expected_rank == 36);
  CHECK(m.provenance->robocal_version == std::string(robocalVersion()));
  CHECK(m.provenance->warnings == fit.problems);
}

TEST_CASE("bad model files name the key and the problem") {
  CHECK_THROWS_WITH(parseModel("{", "m.json"), Contains("m.json: not valid JSON"));
  // In words: no library prefix; an empty file says it is empty and what was expected.
  CHECK_THROWS_WITH(parseModel("{", "m.json"), !Contains("json.exception"));
  CHECK_THROWS_WITH(parseModel(" \n", "m.json"),
                    Contains("m.json: empty: expected a model (docs/model-format.md)"));
  CHECK_THROWS_WITH(parseModel("[]", "m.json"), Contains("expected an object"));
  CHECK_THROWS_WITH(parseModel(edited([](auto& j) { j.erase("links"); }), "m.json"),
                    Contains("m.json: links: missing"));
  CHECK_THROWS_WITH(parseModel(edited([](auto& j) { j["links"].erase(6); })),
                    Contains("links: expected 7 entries, got 6"));
  CHECK_THROWS_WITH(parseModel(edited([](auto& j) { j["links"][3]["ry"] = "12"; })),
                    Contains("links[3].ry: expected a number, got string"));
  CHECK_THROWS_WITH(parseModel(edited([](auto& j) { j["joints"][2].erase("gain"); })),
                    Contains("joints[2].gain: missing"));
  CHECK_THROWS_WITH(parseModel(edited([](auto& j) { j["joints"][0]["gain"] = 0; })),
                    Contains("joints[0].gain: must not be zero"));
  CHECK_THROWS_WITH(parseModel(edited([](auto& j) { j["joints"][3]["velocity_deg_per_s"] = -1; })),
                    Contains("joints[3].velocity_deg_per_s: expected 0 (not known) to 100000"));
  CHECK_THROWS_WITH(parseModel(edited([](auto& j) { j["joints"][3]["effort_nm"] = 2e6; })),
                    Contains("joints[3].effort_nm: expected 0 (not known) to 1000000 (N m)"));
  CHECK_THROWS_WITH(parseModel(edited([](auto& j) {
                      j["balls"][1] = {1, 2};
                    })),
                    Contains("balls[1]: expected [x, y, z]"));
  CHECK_THROWS_WITH(parseModel(edited([](auto& j) { j["chucks"] = 5; })),
                    Contains("chucks: expected an array"));
  // JSON text has no NaN; an overflowing literal is refused with its text, and a non-finite
  // value handed in as parsed JSON is refused with its key.
  std::string text = edited([](auto& j) { j["links"][0]["x"] = 123456.0; });
  text.replace(text.find("123456.0"), 8, "1e999");
  CHECK_THROWS_WITH(parseModel(text, "m.json"),
                    Contains("m.json: not valid JSON") && Contains("1e999"));
  nlohmann::json j = nlohmann::json::parse(shipped());
  j["links"][0]["x"] = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH(modelFromJson(j, "m.json"),
                    Contains("m.json: links[0].x: not a finite number"));
}

TEST_CASE("a deeply nested value in an error is described, not dumped (found with fuzz_model)") {
  // The message dumped the value: 200000 levels of arrays overflowed the stack.
  const std::string deep = std::string(200000, '[') + std::string(200000, ']');
  std::string text = edited([](auto& j) { j["balls"][1] = "deep"; });
  text.replace(text.find("\"deep\""), 6, deep);
  CHECK_THROWS_WITH(parseModel(text, "m.json"),
                    Contains("balls[1]: expected [x, y, z] in mm, got an array of 1"));
  CHECK_THROWS_WITH(parseModel(edited([](auto& j) {
                      j["balls"][1] = {1, 2};
                    })),
                    Contains("got an array of 2"));
  CHECK_THROWS_WITH(parseModel(edited([](auto& j) { j["balls"][1] = "here"; })),
                    Contains("got \"here\""));
}

TEST_CASE("reading a missing file says which file") {
  CHECK_THROWS_WITH(loadModelFile("/nonexistent/model.json"),
                    Contains("/nonexistent/model.json: cannot open"));
}

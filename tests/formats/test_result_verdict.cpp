// The verdict's one JSON object and its renderings: what RESULT carries is what the text and the
// page say, and a client reading the object back renders the same text.
#include <robocal/formats/result_verdict.hpp>

#include <catch2/catch.hpp>

using namespace robocal;
using Catch::Matchers::Contains;

namespace {

ResultVerdict notUsable() {
  ResultVerdict v;
  v.usable = false;
  v.problems = {"rank 20 of the 36 <independent> parameters: measure more shells",
                "too few samples"};
  v.rank = 20;
  v.expected_rank = 36;
  v.whole_range_rms_mm = 1.2346;
  v.accuracy_note = "work volume: out of reach";
  v.model_file = "/var/lib/robocald/runs/x/calibrated-set1.json";
  v.next_command = "robocal start";
  v.next_why = "Put right what the first problem says.";
  return v;
}

}  // namespace

TEST_CASE("a verdict reads back from its JSON as it was written") {
  const ResultVerdict v = notUsable();
  const nlohmann::json j = resultVerdictJson(v);
  CHECK(j["class"] == "VERDICT");
  CHECK(j["predicted_position_error_mm"]["work_volume_rms"].is_null());
  CHECK(j["predicted_position_error_mm"]["whole_range_rms"] == 1.2346);
  const ResultVerdict back = resultVerdictFromJson(j);
  CHECK(back.usable == v.usable);
  CHECK(back.problems == v.problems);
  CHECK(back.rank == 20);
  CHECK(back.expected_rank == 36);
  CHECK_FALSE(back.work_volume_rms_mm);
  REQUIRE(back.whole_range_rms_mm);
  CHECK(*back.whole_range_rms_mm == 1.2346);
  CHECK(back.model_file == v.model_file);
  CHECK(back.next_command == v.next_command);
  CHECK(back.next_why == v.next_why);
  CHECK(resultVerdictText(back) == resultVerdictText(v));
  // Not an object, or keys of the wrong type: defaults, not a throw (a client of another version).
  CHECK_FALSE(resultVerdictFromJson(nlohmann::json("usable")).usable);
  CHECK(resultVerdictFromJson({{"problems", 3}, {"model_file", 7}}).model_file.empty());
}

TEST_CASE("the verdict's text and page say the same: usable or not, why, accuracy, model, next") {
  const ResultVerdict v = notUsable();
  const std::string text = resultVerdictText(v);
  CHECK(text.rfind("verdict: NOT USABLE as a calibration (rank 20 of 36):\n", 0) == 0);
  CHECK_THAT(text, Contains("  - too few samples\n") &&
                       Contains("not computed in the work volume, 1.235 mm RMS over the arm's "
                                "whole range (work volume: out of reach)") &&
                       Contains("written with its problems as warnings") &&
                       Contains("next: robocal start"));
  const std::string html = resultVerdictHtml(v);
  CHECK_THAT(html, Contains("class='verdict bad'") && Contains("&lt;independent&gt;") &&  // escaped
                       Contains("1.235 mm RMS over the arm&#39;s whole range") &&
                       Contains("<code>robocal start</code>"));
  CHECK(html.find("<independent>") == std::string::npos);

  ResultVerdict ok;
  ok.usable = true;
  ok.rank = ok.expected_rank = 36;
  ok.work_volume_rms_mm = 0.0205;
  ok.whole_range_rms_mm = 0.24;
  CHECK(resultVerdictText(ok).rfind("verdict: usable as a calibration (rank 36 of 36)\n", 0) == 0);
  CHECK_THAT(resultVerdictText(ok),
             Contains("0.021 mm RMS in the work volume") && Contains("model: none written"));
  CHECK_THAT(resultVerdictHtml(ok), Contains("class='verdict ok'"));
}

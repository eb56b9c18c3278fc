// The frames JSON and the DH table (frames.hpp), read back as another tool would: the JSON's
// matrices multiplied with nothing of robocal's conventions give the model's forward kinematics;
// the DH table's rows, base and tool give them to the error it states.
#include <catch2/catch.hpp>

#include <robocal/formats/frames.hpp>
#include <robocal/kinematics/units.hpp>

#include "urdf_fk.hpp"

#include <sstream>

using namespace robocal;
using namespace robocal::test;

namespace {

Eigen::Isometry3d fromRows(const nlohmann::json& rows) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) t.matrix()(r, c) = rows[r][c].get<double>();
  return t;
}

Eigen::Isometry3d rz(double deg) {
  return Eigen::Isometry3d(Eigen::AngleAxisd(degToRad(deg), Eigen::Vector3d::UnitZ()));
}

// The tool frame from the frames JSON alone.
Eigen::Isometry3d framesToolPose(const nlohmann::json& f, const JointsDeg& readings) {
  Eigen::Isometry3d t = fromRows(f["links"][0]["matrix"]);
  for (int k = 0; k < kJointCount; ++k) {
    const auto& j = f["joints"][k];
    t = t * rz(j["offset_deg"].get<double>() + j["gain"].get<double>() * readings[k]) *
        fromRows(f["links"][k + 1]["matrix"]);
  }
  return t;
}

// A "# name (4x4, row-major, mm): a b c d | e f g h | ..." comment of the DH file.
Eigen::Isometry3d commentMatrix(const std::string& text, const std::string& name) {
  const auto at = text.find("# " + name + " (4x4");
  REQUIRE(at != std::string::npos);
  std::string line = text.substr(text.find(':', at) + 1, text.find('\n', at) - text.find(':', at));
  for (char& ch : line)
    if (ch == '|') ch = ' ';
  std::istringstream in(line);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) in >> t.matrix()(r, c);
  REQUIRE(in);
  return t;
}

// The tool frame from the DH file alone.
Eigen::Isometry3d dhFileToolPose(const std::string& text, const JointsDeg& readings) {
  Eigen::Isometry3d t = commentMatrix(text, "base");
  std::istringstream in(text);
  std::string line;
  int k = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("joint,", 0) == 0) continue;
    for (char& ch : line)
      if (ch == ',') ch = ' ';
    std::istringstream row(line);
    int joint;
    double theta, d, a, alpha, gain;
    row >> joint >> theta >> d >> a >> alpha >> gain;
    REQUIRE(joint == k + 1);
    t = t * rz(theta + gain * readings[k]) * Eigen::Translation3d(a, 0, d) *
        Eigen::AngleAxisd(degToRad(alpha), Eigen::Vector3d::UnitX());
    ++k;
  }
  REQUIRE(k == kJointCount);
  return t * commentMatrix(text, "tool");
}

}  // namespace

TEST_CASE("frames JSON: its matrices alone give the model's forward kinematics") {
  std::mt19937_64 rng(7);
  Model m = calibratedLike(rng);
  m.joints[1].gain = 1.0007;  // a gain, which the JSON carries per joint
  const nlohmann::json f = nlohmann::json::parse(modelFramesJson(m, dhFromModel(m)).dump());
  CHECK(f["format"] == "robocal-frames 1");
  const Kinematics kin(m);
  for (int c = 0; c < 200; ++c) {
    const JointsDeg q = randomReadings(m, rng);
    const Eigen::Isometry3d want = kin.toolPose(q), got = framesToolPose(f, q);
    CHECK((want.translation() - got.translation()).norm() < kPositionTolMm);
    CHECK(angleBetween(want.linear(), got.linear()) < kAngleTolRad);
  }
  // The quaternions are the matrices'; the axes at zero are the chain's.
  for (const auto& link : f["links"]) {
    const auto& qj = link["quaternion_wxyz"];
    const Eigen::Quaterniond q(qj[0], qj[1], qj[2], qj[3]);
    CHECK(angleBetween(q.toRotationMatrix(), fromRows(link["matrix"]).linear()) < kAngleTolRad);
  }
  const auto frames = Kinematics(toParams(m)).chainFrames(JointsDeg::Zero());
  for (int k = 0; k < kJointCount; ++k) {
    const auto& axis = f["joints"][k]["axis_at_zero"];
    CHECK(Eigen::Vector3d(axis[0], axis[1], axis[2]).dot(frames[2 * k].linear().col(2)) ==
          Approx(1.0));
  }
  CHECK(f["dh"]["rows"].size() == 6);
}

TEST_CASE("DH table file: read back alone, it gives the model to the error it states") {
  std::mt19937_64 rng(8);
  for (const Model& m : {puma560NominalModel(), calibratedLike(rng)}) {
    INFO(m.name);
    const DhTable dh = dhFromModel(m);
    const std::string text = dhTableCsv(m, dh, "m.json");
    CHECK_THAT(text, Catch::Matchers::Contains(dhErrorSummary(dh)));
    const Kinematics kin(toParams(m));
    double worst_mm = 0;
    for (int c = 0; c < 200; ++c) {
      const JointsDeg q = randomReadings(m, rng);
      worst_mm = std::max(
          worst_mm, (kin.toolPose(q).translation() - dhFileToolPose(text, q).translation()).norm());
    }
    // The file's printed digits (1e-6 mm, 1e-9 deg) add less than 1 um to the stated error.
    CHECK(worst_mm <= dh.max_position_error_mm + 1e-3);
    if (m.name == puma560NominalModel().name) CHECK(worst_mm < 1e-3);
  }
}

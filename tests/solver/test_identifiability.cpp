#include <catch2/catch.hpp>

#include <robocal/robot/puma560.hpp>
#include <robocal/sim/measurements.hpp>
#include <robocal/solver/identifiability.hpp>
#include <robocal/solver/problem.hpp>

#include <algorithm>

using namespace robocal;

namespace {

// Jacobian of noise-free shells of the given connections, poses from the model itself.
Eigen::MatrixXd shellJacobian(const Model& model, const std::string& connections) {
  std::mt19937_64 rng(1);
  std::vector<Sample> samples;
  for (const Connection& c : parseConnections(connections)) {
    ShellRequest req;
    req.connection = c;
    req.radius_mm = kDefaultBarMm;
    req.points = 60;
    const auto poses = shellPoses(model, req, rng);
    const auto shell = measureShell(model, req, poses.poses, MeasurementNoise{0, 0}, rng);
    samples.insert(samples.end(), shell.begin(), shell.end());
  }
  Eigen::VectorXd r;
  Eigen::MatrixXd jac;
  evaluateProblem(model, toParams(model), samples, r, &jac);
  return jac;
}

bool contains(const std::vector<int>& v, const std::string& name) {
  return std::find(v.begin(), v.end(), paramIndexByName(name)) != v.end();
}

}  // namespace

TEST_CASE("all nine connections identify 36 of the 54 parameters") {
  const auto id = analyzeIdentifiability(shellJacobian(puma560NominalModel(), "all"));
  CHECK(id.expected == 36);
  CHECK(id.rank == 36);
  CHECK(id.redundant.size() == 18);
  CHECK(id.identified.size() == 36);
  CHECK(id.vanishing.empty());
  CHECK(id.gap > 1e6);  // the rank is decided by a clear gap, not by the threshold's exact value
  // Joint offsets and gains are kept in the identified basis; their twins in the links are not.
  CHECK(contains(id.identified, "J1.offset"));
  CHECK(contains(id.redundant, "L0.rz"));
}

TEST_CASE(
    "one ball measured from three chucks identifies 33: the last link's orientation is lost") {
  const auto id = analyzeIdentifiability(shellJacobian(puma560NominalModel(), "B2C1,B2C2,B2C3"));
  CHECK(id.rank == 33);
  CHECK(id.redundant.size() == 21);
}

TEST_CASE("a ball on joint 6's axis loses joint 6's offset") {
  Model m = puma560NominalModel();
  m.balls_mm[0] = Eigen::Vector3d(0, 0, 100);
  const auto id = analyzeIdentifiability(shellJacobian(m, "B1C1,B1C2,B1C3"));
  CHECK(id.rank < 33);
  CHECK(contains(id.vanishing, "J6.offset"));
  CHECK(contains(id.vanishing, "J6.gain"));
  CHECK(contains(id.redundant, "J6.offset"));
  // The other balls restore it when all nine connections are used.
  CHECK(analyzeIdentifiability(shellJacobian(m, "all")).rank == 36);
}

TEST_CASE("the rank does not depend on the units of the parameters") {
  Eigen::MatrixXd jac = shellJacobian(puma560NominalModel(), "B1C1,B2C2,B3C3,B1C2,B2C3,B3C1");
  const int rank = analyzeIdentifiability(jac).rank;
  // Express translations in metres and angles in micro-radians: columns scale by 1e3 and 1e-6.
  for (int i = 0; i < kParamCount; ++i)
    jac.col(i) *= paramKind(i) == ParamKind::kTranslation ? 1e3 : 1e-6;
  CHECK(analyzeIdentifiability(jac).rank == rank);
  CHECK(rank == 36);
}

TEST_CASE("triangular factor keeps the singular values") {
  const Eigen::MatrixXd jac = shellJacobian(puma560NominalModel(), "B1C1,B2C2");
  const Eigen::MatrixXd r = triangularFactor(jac);
  CHECK(r.rows() == kParamCount);
  Eigen::JacobiSVD<Eigen::MatrixXd> a(jac), b(r);
  CHECK(a.singularValues().isApprox(b.singularValues(), 1e-9));
}

TEST_CASE("the analysis' singular values are those of the scaled Jacobian") {
  for (const char* connections : {"all", "B1C1,B2C2", "B2C1,B2C2,B2C3"}) {
    const Eigen::MatrixXd jac = shellJacobian(puma560NominalModel(), connections);
    const Identifiability id = analyzeIdentifiability(jac);
    Eigen::MatrixXd scaled = jac;
    for (Eigen::Index c = 0; c < scaled.cols(); ++c) scaled.col(c).normalize();
    Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(scaled).singularValues();
    sv /= sv[0];
    REQUIRE(id.singular_values.size() == sv.size());
    INFO(connections);
    // The identifiable ones to 1e-9 relative; the redundant ones are rounding, below 1e-12.
    for (int i = 0; i < id.rank; ++i) CHECK(id.singular_values[i] == Approx(sv[i]).epsilon(1e-9));
    for (Eigen::Index i = id.rank; i < sv.size(); ++i) {
      CHECK(id.singular_values[i] < 1e-12);
      CHECK(sv[i] < 1e-12);
    }
  }
}

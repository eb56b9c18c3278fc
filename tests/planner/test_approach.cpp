// approachStages: every joint brought up into a pose from below, with the bar's length kept
// within a bound at every pre-point (the daemon's connection check on a big arm).
#include <catch2/catch.hpp>

#include <robocal/formats/model_json.hpp>
#include <robocal/planner/plan.hpp>
#include <robocal/robot/puma560.hpp>

#include <random>
#include <set>

using namespace robocal;

namespace {

// Checks the stages against their contract and returns the bar change of the largest.
double checkStages(const Kinematics& kin, const Eigen::Vector3d& ball, const Eigen::Vector3d& chuck,
                   const JointsDeg& q, double step_deg, double max_change_mm,
                   const std::vector<JointsDeg>& stages, const std::vector<int>& left_out) {
  const double at_q = kin.barLength(q, ball, chuck);
  std::set<int> stepped;
  double largest = 0;
  for (const JointsDeg& pre : stages) {
    const double change = std::abs(kin.barLength(pre, ball, chuck) - at_q);
    CHECK(change <= max_change_mm + 1e-12);
    largest = std::max(largest, change);
    for (int j = 0; j < kJointCount; ++j) {
      if (pre[j] == q[j]) continue;
      CHECK(pre[j] == Approx(q[j] - step_deg));  // a group steps back exactly step_deg
      CHECK(stepped.insert(j).second);           // each joint in one group only
    }
  }
  for (int j : left_out) {
    JointsDeg alone = q;
    alone[j] -= step_deg;
    CHECK(std::abs(kin.barLength(alone, ball, chuck) - at_q) > max_change_mm);
    CHECK(stepped.insert(j).second);
  }
  CHECK(stepped.size() == static_cast<std::size_t>(kJointCount));  // every joint accounted for
  return largest;
}

}  // namespace

TEST_CASE("approach stages: one pre-point when it keeps the bar, groups of joints when not") {
  const Model rx160 = loadModelFile(ROBOCAL_SOURCE_DIR "/config/rx160.json");
  const Kinematics kin(rx160);
  const Eigen::Vector3d ball = rx160.balls_mm[2], chuck = rx160.chucks_mm[0];
  // The RX160 reaching over a chuck, as at shell 7's connect pose of its main job (B3C1, 45 deg
  // latitude).
  JointsDeg q;
  q << -10.063, -46.566, -113.323, -52.106, 18.305, -108.864;
  const double step = 0.02;
  std::vector<int> left_out;

  // A generous bound: the planner's own pre-point, one stage.
  const auto generous = approachStages(kin, ball, chuck, q, step, 5.0, left_out);
  REQUIRE(generous.size() == 1);
  CHECK(generous[0] == approachPrePoint(kin, ball, chuck, q, step));
  CHECK(left_out.empty());

  // The check's 0.4 mm against this arm's reach: the single pre-point would move the bar more.
  const JointsDeg single = approachPrePoint(kin, ball, chuck, q, step);
  const double single_change =
      std::abs(kin.barLength(single, ball, chuck) - kin.barLength(q, ball, chuck));
  REQUIRE(single_change > 0.2);  // no joint can undo the step here (over the chuck)
  const double bound = 0.5 * single_change;
  const auto staged = approachStages(kin, ball, chuck, q, step, bound, left_out);
  CHECK(staged.size() >= 2);
  checkStages(kin, ball, chuck, q, step, bound, staged, left_out);

  // A bound below any joint's own step: nothing can be approached, every moving joint left out.
  const auto none = approachStages(kin, ball, chuck, q, step, 1e-9, left_out);
  checkStages(kin, ball, chuck, q, step, 1e-9, none, left_out);
  CHECK(left_out.size() >= 5);
}

TEST_CASE("approach pre-point: every joint a step back, one joint at most a degree further") {
  // Over random poses and connections, also where the bar's length hardly depends on any joint
  // and Newton's step to keep the ball on the shell would run off (the shipped plan once had a
  // pre-point 47,864 deg back in joint 2).
  const Model puma = loadModelFile(ROBOCAL_SOURCE_DIR "/config/puma560-paper.json");
  const Kinematics kin(puma);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> angle(-180, 180);
  const double step = 0.02;
  int further = 0;
  for (int trial = 0; trial < 5000; ++trial) {
    JointsDeg q;
    for (int j = 0; j < kJointCount; ++j) q[j] = angle(rng);
    const Eigen::Vector3d ball = puma.balls_mm[trial % 3], chuck = puma.chucks_mm[(trial / 3) % 3];
    const JointsDeg pre = approachPrePoint(kin, ball, chuck, q, step);
    const JointsDeg back = q - pre;
    INFO("trial " << trial << ": back " << back.transpose());
    REQUIRE(back.minCoeff() >= step - 1e-9);
    REQUIRE(back.maxCoeff() <= 1.0 + 1e-9);
    further += back.maxCoeff() > step + 1e-9;
  }
  CHECK(further > 1000);  // the joint that keeps the ball on the shell does step further
}

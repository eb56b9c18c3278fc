// Compensation (compensation/): corrected readings reach the target in the calibrated model, keep
// the nominal solution's configuration, come back unchanged when the models agree, and make the
// true robot of a simulation much more accurate over the work volume.
#include <catch2/catch.hpp>

#include <robocal/compensation/accuracy.hpp>
#include <robocal/compensation/accuracy_report.hpp>
#include <robocal/compensation/targets.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/formats/program.hpp>
#include <robocal/planner/cell_json.hpp>
#include <robocal/robot/puma560.hpp>
#include <robocal/robot/puma_ik.hpp>
#include <robocal/sim/measurements.hpp>
#include <robocal/solver/calibrate.hpp>

#include <random>

using namespace robocal;
using Catch::Matchers::Contains;

namespace {

Model perturbed(unsigned seed) {
  std::mt19937_64 rng(seed);
  return perturbModel(puma560NominalModel(), PerturbationSigmas{}, rng);
}

// Readings inside the limits and away from the singularities, as a program would hold.
std::vector<JointsDeg> programJoints(int count, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<JointsDeg> out;
  while (static_cast<int>(out.size()) < count) {
    JointsDeg q;
    q << 40 * u(rng), 45 + 40 * u(rng), -135 + 40 * u(rng), 60 * u(rng), 45 + 30 * u(rng),
        90 * u(rng);
    out.push_back(q);
  }
  return out;
}

// A calibration of a perturbed robot from simulated shells (all nine connections, two radii).
Model calibrate(const Model& nominal, const Model& truth, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::vector<Sample> samples;
  for (const ShellRequest& req : shellRequests(allConnections(), {0.0, 150.0}, 40)) {
    const auto poses = shellPoses(nominal, req, rng).poses;
    const auto more = measureShell(truth, req, poses, MeasurementNoise{}, rng);
    samples.insert(samples.end(), more.begin(), more.end());
  }
  const SolveResult fit = solveCalibration(nominal, samples);
  Model calibrated = withParams(nominal, fit.params);
  calibrated.covariance = fit.covariance;
  return calibrated;
}

}  // namespace

TEST_CASE("a program's joints come back unchanged when the calibrated model is the nominal") {
  const Model nominal = puma560NominalModel();
  const Compensator comp(nominal, nominal);
  for (const JointsDeg& q : programJoints(50, 3)) {
    const CompensatedTarget t = comp.forNominalJoints(q);
    INFO(q.transpose());
    REQUIRE(t.status == CompensationStatus::kOk);
    CHECK((t.joints_deg - q).cwiseAbs().maxCoeff() < 1e-9);
  }
}

TEST_CASE(
    "corrected readings reach the target in the calibrated model, in the same configuration") {
  const Model nominal = puma560NominalModel();
  const Model truth = perturbed(7);
  CompensationOptions options;
  options.tool = poseFromXyzZyx(10, -20, 150, 0, 15, 0);  // a tool centre point off the axis
  const Compensator comp(nominal, truth, options);
  const Kinematics true_kin(truth);
  int changed = 0;
  for (const JointsDeg& q : programJoints(40, 5)) {
    const CompensatedTarget t = comp.forNominalJoints(q);
    INFO(q.transpose());
    REQUIRE(t.status == CompensationStatus::kOk);
    CHECK(t.config == PumaIk(nominal).configOf(q));
    // The true robot (here the calibrated model itself) puts the tool where the program meant.
    const PoseDifference d =
        poseDifference(true_kin.toolPose(t.joints_deg) * options.tool, comp.nominalToolPose(q));
    CHECK(d.position_mm < 1e-4);
    CHECK(d.angle_deg < 1e-6 * 57.3);
    CHECK(t.position_residual_mm == Approx(d.position_mm).margin(1e-9));
    // Compensation moves the joints by about the model error, not by whole turns.
    const double shift = (t.joints_deg - q).cwiseAbs().maxCoeff();
    CHECK(shift < 1.0);
    changed += shift > 1e-3;
  }
  CHECK(changed > 30);
}

TEST_CASE("poses get a status that says why they cannot be compensated") {
  const Model nominal = puma560NominalModel();
  const Compensator comp(nominal, perturbed(2));
  SECTION("out of reach") {
    const CompensatedTarget t = comp.forPose(poseFromXyzZyx(2000, 0, 300, 0, 135, 0));
    CHECK(t.status == CompensationStatus::kUnreachable);
    CHECK_THAT(t.reason, Contains("reach"));
  }
  SECTION("near the wrist singularity") {
    JointsDeg q;
    q << 10, 60, -140, 20, 0.5, 30;  // joint 5 half a degree from zero
    const CompensatedTarget t = comp.forNominalJoints(q);
    CHECK(t.status == CompensationStatus::kNearSingularity);
    CHECK_THAT(t.reason, Contains("wrist singularity"));
  }
  SECTION("a requested configuration the limits forbid") {
    JointsDeg q;
    q << 10, 60, -140, 20, 45, 30;
    const Eigen::Isometry3d pose = comp.nominalToolPose(q);
    const CompensatedTarget t = comp.forPose(pose, ArmConfig{true, true, false});
    CHECK(t.status != CompensationStatus::kOk);
    CHECK_FALSE(t.reason.empty());
  }
  SECTION("the first configuration that is ok is chosen without one") {
    JointsDeg q;
    q << 10, 60, -140, 20, 45, 30;
    const CompensatedTarget t = comp.forPose(comp.nominalToolPose(q));
    CHECK(t.status == CompensationStatus::kOk);
    CHECK(t.position_residual_mm < 1e-4);
  }
}

TEST_CASE("over the work volume, compensation makes a simulated robot at least 10x more accurate") {
  const Model nominal = puma560NominalModel();
  const Model truth = perturbed(11);
  const Model calibrated = calibrate(nominal, truth, 11);
  const Compensator comp(nominal, calibrated);
  WorkVolume work;
  work.poses = 60;
  const auto poses = workVolumePoses(work, comp);
  REQUIRE(poses.size() == 60);
  const TrueRobot true_robot{truth, Realism::ideal()};
  const AccuracyReport r = assessAccuracy(comp, poses, &true_robot);
  CHECK(r.ok == 60);
  INFO(accuracyText(r));
  CHECK(r.nominal_position_mm.rms > 0.3);
  CHECK(r.compensated_position_mm.rms < r.nominal_position_mm.rms / 10);
  CHECK(r.compensated_position_mm.p95 < 0.25);
  // The compensation adds nothing to the calibrated model's own error (the IK is exact).
  CHECK(r.compensated_position_mm.rms <= 1.1 * r.calibrated_model_position_mm.rms);
  CHECK(r.compensated_orientation_deg.rms < r.nominal_orientation_deg.rms);
  // The covariance's prediction is of the size of the true error.
  CHECK(r.predicted_position_mm.rms > r.compensated_position_mm.rms / 3);
  CHECK(r.predicted_position_mm.rms < r.compensated_position_mm.rms * 5);
  const auto json = accuracyJson(r);
  CHECK(json["compensated_commanded_position_error_mm"]["rms"].get<double>() ==
        Approx(r.compensated_position_mm.rms));
  const std::string svg = accuracySvg(r);
  CHECK_THAT(svg, Contains("true error, compensated joints"));
  CHECK_THAT(svg, Contains("x (mm)"));
}

TEST_CASE("beyond the work volume: the arm's whole range, predicted and true, side by side") {
  const Model nominal = puma560NominalModel();
  const auto arm = makeArm(nominal);
  const auto joints = wholeRangeJoints(*arm, 300, 5);
  REQUIRE(joints.size() == 300);
  CHECK(joints == wholeRangeJoints(*arm, 300, 5));  // a seed draws the same vectors
  double lowest_j1 = 1e9, highest_j1 = -1e9;
  for (const JointsDeg& q : joints) {
    for (int j = 0; j < kJointCount; ++j) {
      CHECK(q[j] >= nominal.joints[j].min_deg);
      CHECK(q[j] <= nominal.joints[j].max_deg);
    }
    CHECK(std::abs(std::sin(q[4] * M_PI / 180)) >= std::sin(5 * M_PI / 180) - 1e-12);
    lowest_j1 = std::min(lowest_j1, q[0]);
    highest_j1 = std::max(highest_j1, q[0]);
  }
  CHECK(highest_j1 - lowest_j1 > 0.8 * (nominal.joints[0].max_deg - nominal.joints[0].min_deg));

  // A calibration on the reference shells: well predicted and well compensated where it measured,
  // less so over the whole range, and the statistics say so.
  const Model truth = perturbed(11);
  const Model calibrated = calibrate(nominal, truth, 11);
  const Compensator comp(nominal, calibrated);
  const PredictedAccuracy predicted = predictedAccuracy(nominal, calibrated, WorkVolume{});
  REQUIRE(predicted.work_volume_rms_mm);
  const double whole_mm = predicted.whole_range["predicted_position_error_mm"]["rms"];
  CHECK(whole_mm > 2 * *predicted.work_volume_rms_mm);
  CHECK_THAT(predicted.text, Contains("the arm's whole range: 200 joint vectors"));
  const TrueRobot true_robot{truth, Realism::ideal()};
  const AccuracyReport at_joints =
      assessAccuracyAtJoints(comp, wholeRangeJoints(comp.nominalArm(), 60, 2), &true_robot);
  CHECK(at_joints.solved > 40);
  CHECK(at_joints.compensated_position_mm.rms < at_joints.nominal_position_mm.rms);
  // Each target is where the nominal model puts the drawn joints.
  const PoseDifference d =
      poseDifference(at_joints.poses[0].target.target,
                     comp.nominalToolPose(wholeRangeJoints(comp.nominalArm(), 60, 2)[0]));
  CHECK(d.position_mm < 1e-9);
}

TEST_CASE("accuracy reaches each target in the configuration its file asks for") {
  const Model nominal = puma560NominalModel();
  const Compensator comp(nominal, perturbed(4));
  const PumaIk ik(nominal);
  // Poses of joint vectors of both shoulders; each judged in the configuration it was drawn in.
  std::vector<Eigen::Isometry3d> poses;
  std::vector<std::optional<ArmConfig>> configs;
  for (const JointsDeg& q : wholeRangeJoints(comp.nominalArm(), 40, 3)) {
    poses.push_back(comp.nominalToolPose(q));
    configs.push_back(ik.configOf(q));
  }
  REQUIRE(std::count_if(configs.begin(), configs.end(), [](const auto& c) { return c->left; }) > 5);
  REQUIRE(std::count_if(configs.begin(), configs.end(), [](const auto& c) { return !c->left; }) >
          5);
  const AccuracyReport asked = assessAccuracy(comp, poses, nullptr, configs);
  const AccuracyReport free_choice = assessAccuracy(comp, poses);
  int differs = 0;
  for (size_t i = 0; i < poses.size(); ++i) {
    CHECK(asked.poses[i].target.config == *configs[i]);
    differs += !(free_choice.poses[i].target.config == *configs[i]);
  }
  CHECK(differs > 0);  // without the column, the best configuration is taken instead
  CHECK_THROWS_AS(assessAccuracy(comp, poses, nullptr, {configs[0]}), std::invalid_argument);
}

TEST_CASE("a work volume out of the arm's reach is refused, not looped on") {
  const Model nominal = puma560NominalModel();
  const Compensator comp(nominal, nominal);
  WorkVolume far;
  far.box_min_mm = {3000, 3000, 3000};
  far.box_max_mm = {3100, 3100, 3100};
  far.poses = 5;
  CHECK_THROWS_WITH(workVolumePoses(far, comp), Contains("reachable"));
}

TEST_CASE("the cell file's work_volume is read and checked, errors naming the key") {
  const CellConfig c = parseCell(
      R"({"work_volume": {"box_min_mm": [-100, -100, 200], "box_max_mm": [100, 100, 300],
          "rz_range_deg": [-10, 10], "poses": 30, "seed": 4}})",
      "c.json");
  CHECK(c.work_volume.box_max_mm[2] == 300);
  CHECK(c.work_volume.rz_range_deg[0] == -10);
  CHECK(c.work_volume.ry_range_deg[0] == 120);  // default kept
  CHECK(c.work_volume.poses == 30);
  CHECK_THROWS_WITH(parseCell(R"({"work_volume": {"box_min_mm": [0, 0]}})", "c.json"),
                    Contains("c.json: work_volume.box_min_mm: expected 3 numbers"));
  CHECK_THROWS_WITH(parseCell(R"({"work_volume": {"box_min_mm": [0, 0, 500]}})", "c.json"),
                    Contains("work_volume.box_max_mm[2]"));
  CHECK_THROWS_WITH(parseCell(R"({"work_volume": {"poses": 0}})", "c.json"),
                    Contains("work_volume.poses"));
  CHECK_THROWS_WITH(parseCell(R"({"work_volume": {"size": 3}})", "c.json"),
                    Contains("work_volume.size"));
}

TEST_CASE("targets files: both forms, and malformed rows named by file:line") {
  const TargetFile poses = parseTargets(
      "# a comment\nname,x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg,config\n"
      "p1, 10, 20, 300, 0, 135, 0,\np2,0,0,250,5,130,-5,right-up-noflip\n",
      "t.csv");
  REQUIRE(poses.targets.size() == 2);
  CHECK_FALSE(poses.joints_form);
  CHECK(poses.targets[0].name == "p1");
  CHECK(poses.targets[0].line == 3);
  CHECK(poses.targets[0].pose->translation().isApprox(Eigen::Vector3d(10, 20, 300)));
  CHECK_FALSE(poses.targets[0].config);
  CHECK(*poses.targets[1].config == ArmConfig{});
  const TargetFile joints = parseTargets("j1,j2,j3,j4,j5,j6\n1,2,3,4,5,6\n", "j.csv");
  CHECK(joints.joints_form);
  CHECK_FALSE(joints.has_names);
  CHECK((*joints.targets[0].nominal_joints)[5] == 6);

  CHECK_THROWS_WITH(parseTargets("j1,j2,j3,j4,j5,j6\n1,2,x3,4,5,6\n", "j.csv"),
                    Contains("j.csv:2: column 'j3': not a finite number: 'x3'"));
  CHECK_THROWS_WITH(parseTargets("j1,j2,j3,j4,j5,j6\n1,2,3\n", "j.csv"),
                    Contains("j.csv:2: expected 6 fields, got 3"));
  CHECK_THROWS_WITH(parseTargets("j1,j2,j3,j4,j5\n", "j.csv"),
                    Contains("j.csv:1: the header has no column 'j6'"));
  CHECK_THROWS_WITH(parseTargets("x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg,j1\n", "m.csv"),
                    Contains("m.csv:1: the header has pose columns"));
  CHECK_THROWS_WITH(parseTargets("x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg,speed\n", "m.csv"),
                    Contains("m.csv:1: unknown column 'speed'"));
  CHECK_THROWS_WITH(
      parseTargets("x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg,config\n1,2,3,4,5,6,up\n", "m.csv"),
      Contains("m.csv:2: column 'config': unknown arm configuration 'up'"));
  CHECK_THROWS_WITH(parseTargets("\n# nothing\n", "e.csv"), Contains("e.csv: empty"));
}

TEST_CASE("a targets file in another unit, with no targets, or compensate's own output is named") {
  // Joints in radians, positions in metres, angles in radians: each said, with the conversion.
  const auto problem = [](const std::string& text) {
    return targetsUnitsProblem(parseTargets(text, "t.csv")).value_or("");
  };
  CHECK_THAT(problem("j1,j2,j3,j4,j5,j6\n-0.0427,0.5939,-3.3735,0.1,0.2,0.3\n"
                     "0.1,0.6,-3.1,0.2,-0.4,1.5\n"),
             Contains("as if in radians (first at t.csv:2)") && Contains("x 57.2958"));
  CHECK_THAT(problem("x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg\n0.1,0.2,0.3,0,135,0\n"),
             Contains("as if in metres") && Contains("x 1000"));
  CHECK_THAT(problem("x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg\n100,200,300,0,2.356,0\n"
                     "150,200,300,0.1,2.2,-0.1\n"),
             Contains("every target angle lies within +/-2.36, as if in radians"));
  // Programs in the right units pass, a single pose too; a home at all zeros is no radians.
  CHECK(problem("j1,j2,j3,j4,j5,j6\n10,45,-170,0,30,0\n-5,50,-160,10,-30,90\n").empty());
  CHECK(problem("j1,j2,j3,j4,j5,j6\n0,0,0,0,0,0\n0,0,0,0,0,0\n").empty());
  CHECK(problem("x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg\n100,200,300,0,135,0\n").empty());

  CHECK_THROWS_WITH(parseTargets("j1,j2,j3,j4,j5,j6\n", "e.csv"),
                    Contains("e.csv: no targets: a header and no rows"));
  CHECK_THROWS_WITH(
      parseTargets(
          "name,j1,j2,j3,j4,j5,j6,a1,a2,a3,a4,a5,a6,predicted_error_mm,status,config,note\n",
          "out.csv"),
      Contains("out.csv:1: this is robocal compensate's output"));
}

TEST_CASE("the output never commands a target that cannot be reached") {
  const Model nominal = puma560NominalModel();
  const Compensator comp(nominal, perturbed(4));
  const TargetFile file = parseTargets(
      "name,x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg\nnear,0,0,250,0,135,0\nfar,3000,0,0,0,0,0\n",
      "t.csv");
  std::vector<CompensatedTarget> results;
  for (const Target& t : file.targets) results.push_back(compensateTarget(comp, t));
  REQUIRE(results[0].ok());
  REQUIRE(results[1].status == CompensationStatus::kUnreachable);
  const std::string csv = formatCompensated(file, results, OutputFormat::kCsv);
  CHECK_THAT(csv, Contains("name,j1,j2,j3,j4,j5,j6,a1,a2,a3,a4,a5,a6,predicted_error_mm,status,"
                           "config,note\n"));
  CHECK_THAT(csv, Contains("\nfar,,,,,,,,,,,,,"));
  CHECK_THAT(csv, Contains(",unreachable,"));
  const std::string moves = formatCompensated(file, results, OutputFormat::kVal2Moves);
  CHECK_THAT(moves, Contains("DO MOVE #PPOINT("));
  CHECK_THAT(moves, Contains("; far: unreachable"));
  CHECK(moves.find("DO MOVE") == moves.rfind("DO MOVE"));     // one move only
  CHECK_THAT(moves, Contains("\n; near\nDO MOVE #PPOINT("));  // every target named
  const std::string points = formatCompensated(file, results, OutputFormat::kVal2Points);
  CHECK_THAT(points, Contains("\n#PPOINT("));
}

TEST_CASE("targets are reached as the calibration reached its points: up from a pre-point") {
  const Model nominal = puma560NominalModel();
  Model calibrated = perturbed(4);
  const TargetFile file = parseTargets(
      "name,x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg\nnear,0,0,250,0,135,0\nfar,3000,0,0,0,0,0\n",
      "t.csv");
  const auto compensateAll = [&](const Compensator& comp) {
    std::vector<CompensatedTarget> results;
    for (const Target& t : file.targets) results.push_back(compensateTarget(comp, t));
    return results;
  };
  // Without an approach recorded: none assumed, no pre-points, a1..a6 empty.
  const Compensator plain(nominal, calibrated);
  CHECK(plain.approachDeg() == 0);
  const auto without = compensateAll(plain);
  REQUIRE(without[0].ok());
  CHECK_FALSE(without[0].hasApproach());
  CHECK(formatCompensated(file, without, OutputFormat::kVal2Moves, 0).find("pre-point") ==
        std::string::npos);

  // The calibration's approach is recorded in the model, and survives its file.
  ModelProvenance p;
  p.approach_deg = 0.02;
  calibrated.provenance = p;
  calibrated = parseModel(formatModel(calibrated), "c.json");
  REQUIRE(calibrated.provenance);
  CHECK(calibrated.provenance->approach_deg == 0.02);
  const Compensator comp(nominal, calibrated);
  CHECK(comp.approachDeg() == 0.02);
  const auto with = compensateAll(comp);
  REQUIRE(with[0].ok());
  CHECK(with[0].joints_deg == without[0].joints_deg);  // the target itself does not change
  CHECK(with[0].approach == std::array<int, 6>{1, 1, 1, 1, 1, 1});
  CHECK((with[0].joints_deg - with[0].pre_point_deg).maxCoeff() == Approx(0.02));
  CHECK((with[0].joints_deg - with[0].pre_point_deg).minCoeff() == Approx(0.02));
  CHECK_FALSE(with[1].hasApproach());  // unreachable: nothing to approach

  const std::string csv = formatCompensated(file, with, OutputFormat::kCsv, comp.approachDeg());
  CHECK_THAT(csv, Contains(",1,1,1,1,1,1,"));
  const std::string moves =
      formatCompensated(file, with, OutputFormat::kVal2Moves, comp.approachDeg());
  CHECK_THAT(moves, Contains("pre-point, 0.0200 deg below it in every joint"));
  // The pre-point's move, then the target's: two moves for the one reachable target.
  const auto first = moves.find("DO MOVE #PPOINT(");
  const auto second = moves.find("DO MOVE #PPOINT(", first + 1);
  REQUIRE(second != std::string::npos);
  CHECK(moves.find("DO MOVE #PPOINT(", second + 1) == std::string::npos);
  char pre[32];
  std::snprintf(pre, sizeof pre, "#PPOINT(%.4f,", with[0].pre_point_deg[0]);
  CHECK(moves.find(pre) == first + 8);

  // A points list keeps one point a target: its pre-point is a comment.
  const std::string points =
      formatCompensated(file, with, OutputFormat::kVal2Points, comp.approachDeg());
  CHECK_THAT(points, Contains("\n; pre-point #PPOINT("));
  // Two header lines, the target's name, its pre-point comment, the target, the unreachable one's.
  CHECK(std::count(points.begin(), points.end(), '\n') == 6);
  CHECK_THAT(points, Contains("\n; near\n; pre-point #PPOINT("));
  CHECK(points.find("\n#PPOINT(") != std::string::npos);

  // An explicit 0 turns it off; a pre-point below a joint's limit is refused, not commanded.
  CompensationOptions off;
  off.approach_deg = 0;
  CHECK_FALSE(compensateAll(Compensator(nominal, calibrated, off))[0].hasApproach());
  Model tight = calibrated;
  for (int j = 0; j < kJointCount; ++j) tight.joints[j].min_deg = with[0].joints_deg[j] - 0.01;
  const auto limited = compensateAll(Compensator(nominal, tight));
  CHECK(limited[0].status == CompensationStatus::kOutsideLimits);
  CHECK_THAT(limited[0].reason, Contains("approach pre-point puts joint 1"));
  // A target that every solution puts past a joint's limits names the joint and the limits.
  Model narrow = nominal;
  narrow.joints[2].min_deg = 40;
  narrow.joints[2].max_deg = 41;
  const CompensatedTarget past = Compensator(narrow, calibrated).forPose(with[0].target);
  CHECK(past.status == CompensationStatus::kOutsideLimits);
  CHECK_THAT(past.reason, Contains("joint 3 at") && Contains("(40 to 41 deg)"));
}

TEST_CASE("a V+ or AS location file holds every reachable target and its pre-point by name") {
  const Model nominal = puma560NominalModel();
  Model calibrated = perturbed(4);
  ModelProvenance p;
  p.approach_deg = 0.02;
  calibrated.provenance = p;
  const Compensator comp(nominal, calibrated);
  // Named, unnamed (line 3: p3) and unreachable targets.
  const TargetFile file = parseTargets(
      "name,x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg\nnear,0,0,250,0,135,0\n,50,0,250,0,135,0\n"
      "far,3000,0,0,0,0,0\n",
      "t.csv");
  std::vector<CompensatedTarget> results;
  for (const Target& t : file.targets) results.push_back(compensateTarget(comp, t));
  REQUIRE(results[0].ok());
  REQUIRE(results[1].ok());
  REQUIRE(results[2].status == CompensationStatus::kUnreachable);
  for (const auto& [format, dialect] :
       {std::pair{OutputFormat::kVplusLocations, ProgramDialect::kVplus},
        std::pair{OutputFormat::kAsJoints, ProgramDialect::kAs}}) {
    const std::string text = formatCompensated(file, results, format, comp.approachDeg());
    // robocal's own program reader takes it as a file of that dialect, and only of that one.
    const ProgramFile back = parseProgram(text, dialect, "out");
    CHECK_THROWS_AS(parseProgram(text, dialect == ProgramDialect::kAs ? ProgramDialect::kVplus
                                                                      : ProgramDialect::kAs),
                    FormatError);
    REQUIRE(back.locations.size() == 4);  // two targets, each with its pre-point
    const std::vector<std::pair<std::string, JointsDeg>> expected = {
        {"#near_pre", results[0].pre_point_deg},
        {"#near", results[0].joints_deg},
        {"#p3_pre", results[1].pre_point_deg},
        {"#p3", results[1].joints_deg}};
    for (size_t k = 0; k < expected.size(); ++k) {
      CHECK(back.locations[k].name == expected[k].first);
      CHECK((back.locations[k].joints_deg - expected[k].second).cwiseAbs().maxCoeff() < 5e-7);
    }
    CHECK_THAT(text, Contains("\n; far: unreachable: "));  // named, never commanded
    CHECK(text.find("#far") == std::string::npos);
  }
  // A name no controller takes, or one defined twice, is refused with the targets file's line.
  const auto refused = [&](const std::string& csv) {
    const TargetFile bad = parseTargets(csv, "bad.csv");
    std::vector<CompensatedTarget> r;
    for (const Target& t : bad.targets) r.push_back(compensateTarget(comp, t));
    return formatCompensated(bad, r, OutputFormat::kAsJoints, comp.approachDeg());
  };
  CHECK_THROWS_WITH(refused("name,x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg\n2nd pick,0,0,250,0,135,0\n"),
                    Contains("bad.csv:2: '2nd pick' is not a location name"));
  CHECK_THROWS_WITH(refused("name,x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg\na_pre,0,0,250,0,135,0\n"
                            "a,50,0,250,0,135,0\n"),
                    Contains("bad.csv:3: location #a_pre would be defined twice"));
}

TEST_CASE("a calibrated model's covariance survives its file, and a bad one is refused") {
  const Model nominal = puma560NominalModel();
  Model m = calibrate(nominal, perturbed(9), 9);
  REQUIRE(m.covariance);
  const Model back = parseModel(formatModel(m), "m.json");
  REQUIRE(back.covariance);
  const double scale = m.covariance->cwiseAbs().maxCoeff();
  CHECK((*back.covariance - *m.covariance).cwiseAbs().maxCoeff() < 1e-12 * scale);
  // The predicted error is the same from the file as from the fit.
  const JointsDeg q = programJoints(1, 1)[0];
  CHECK(Compensator(nominal, back).predictedPositionError(q) ==
        Approx(Compensator(nominal, m).predictedPositionError(q)).epsilon(1e-9));
  // A refit's parameters do not inherit it.
  CHECK_FALSE(withParams(m, toParams(m)).covariance);

  auto json = modelToJson(m);
  json["covariance"]["parameters"][3] = "J7.offset";
  CHECK_THROWS_WITH(parseModel(json.dump(), "m.json"),
                    Contains("covariance.parameters[3]: unknown parameter \"J7.offset\""));
  json = modelToJson(m);
  json["covariance"]["matrix"][1][0] = 1.0;
  CHECK_THROWS_WITH(parseModel(json.dump(), "m.json"), Contains("not symmetric"));
}

TEST_CASE("an identified twist's covariance survives its file and widens the predicted errors") {
  const Model nominal = puma560NominalModel();
  const Model rigid = calibrate(nominal, perturbed(9), 9);
  REQUIRE(nominal.compliance);  // the shipped PUMA carries its load, with no twist
  Model m = rigid;
  m.compliance = nominal.compliance;
  m.compliance->deg_per_nm[1] = 0.0007;
  // Joint 2's twist known to 0.0002 deg/(N m), independent of the 54 here.
  Eigen::MatrixXd cov =
      Eigen::MatrixXd::Zero(twistCovarianceIndex(kJointCount), twistCovarianceIndex(kJointCount));
  cov.topLeftCorner(kParamCount, kParamCount) = *rigid.covariance;
  constexpr double kTwistSigma = 0.0002;
  cov(twistCovarianceIndex(1), twistCovarianceIndex(1)) = kTwistSigma * kTwistSigma;
  m.covariance = cov;
  const Model back = parseModel(formatModel(m), "m.json");
  REQUIRE(back.covariance);
  REQUIRE(back.covariance->rows() == cov.rows());
  CHECK((*back.covariance - cov).cwiseAbs().maxCoeff() < 1e-12 * cov.cwiseAbs().maxCoeff());
  CHECK(modelToJson(m)["covariance"]["parameters"].back() == "J2.compliance");
  Model twisted_only = m;
  twisted_only.covariance = cov.topLeftCorner(kParamCount, kParamCount);
  for (const JointsDeg& q : programJoints(5, 4)) {
    // The twist's own part: the ball's change per deg/(N m), by differences of the model.
    Model plus = m, minus = m;
    plus.compliance->deg_per_nm[1] += 1e-5;
    minus.compliance->deg_per_nm[1] -= 1e-5;
    const Eigen::Vector3d per_twist = (Kinematics(plus).ballPosition(q, Eigen::Vector3d::Zero()) -
                                       Kinematics(minus).ballPosition(q, Eigen::Vector3d::Zero())) /
                                      2e-5;
    // The covariance as filed, without the priors of what the fit left unidentified.
    CompensationOptions as_filed;
    as_filed.priors = UnidentifiedPriors::none();
    const double without = Compensator(nominal, twisted_only, as_filed).predictedPositionError(q);
    const double with = Compensator(nominal, back, as_filed).predictedPositionError(q);
    INFO(q.transpose() << ": " << without << " -> " << with << " mm");
    CHECK(with == Approx(std::hypot(without, kTwistSigma * per_twist.norm())).epsilon(1e-4));
    CHECK(Compensator(nominal, back).predictedOrientationError(q) >
          Compensator(nominal, twisted_only).predictedOrientationError(q));
  }
  // A twist's covariance needs the model's compliance, in memory as in a file; nothing but 54 or
  // 60 rows is a covariance.
  Model no_load = m;
  no_load.compliance.reset();
  CHECK_THROWS_AS(Compensator(nominal, no_load), std::invalid_argument);
  Model odd = rigid;
  odd.covariance = Eigen::MatrixXd::Identity(kParamCount + 1, kParamCount + 1);
  CHECK_THROWS_AS(Compensator(nominal, odd), std::invalid_argument);
  // A seventh joint has none.
  auto json = modelToJson(m);
  json.erase("compliance");
  CHECK_THROWS_WITH(parseModel(json.dump(), "m.json"),
                    Contains("covariance.parameters: a joint's twist (\"J<n>.compliance\") in a "
                             "model without a \"compliance\" object"));
  json = modelToJson(m);
  json["covariance"]["parameters"].back() = "J7.compliance";
  CHECK_THROWS_WITH(parseModel(json.dump(), "m.json"),
                    Contains("unknown parameter \"J7.compliance\""));
}

TEST_CASE("error the fit found the model does not contain widens every predicted position error") {
  const Model nominal = puma560NominalModel();
  const Model fitted = calibrate(nominal, perturbed(9), 9);
  Model m = fitted;
  if (!m.provenance) m.provenance = ModelProvenance{};
  m.provenance->unmodelled_mm = 0.03;  // along the bar: sqrt(3) times it in 3D
  const Model back = parseModel(formatModel(m), "m.json");
  REQUIRE(back.provenance);
  CHECK(back.provenance->unmodelled_mm == 0.03);
  for (const JointsDeg& q : programJoints(5, 3)) {
    const double rigid = Compensator(nominal, fitted).predictedPositionError(q);
    const double widened = Compensator(nominal, back).predictedPositionError(q);
    CHECK(widened * widened == Approx(rigid * rigid + 3 * 0.03 * 0.03).epsilon(1e-9));
  }
  auto json = modelToJson(m);
  json["provenance"]["unmodelled_mm"] = -0.1;
  CHECK_THROWS_WITH(parseModel(json.dump(), "m.json"),
                    Contains("provenance.unmodelled_mm: expected 0 or more (mm)"));
}

TEST_CASE("error statistics: RMS, nearest-rank p95 and max") {
  std::vector<double> v;
  for (int i = 1; i <= 100; ++i) v.push_back(i);
  const ErrorStats s = errorStats(v);
  CHECK(s.count == 100);
  CHECK(s.p95 == 95);
  CHECK(s.max == 100);
  CHECK(s.rms == Approx(std::sqrt(338350.0 / 100)));
  CHECK(errorStats({}).count == 0);
}

#include <robocal/solver/problem.hpp>

namespace robocal {

void evaluateProblem(const Model& fixtures, const ParamVector& params,
                     const std::vector<Sample>& samples, Eigen::VectorXd& residuals,
                     Eigen::MatrixXd* jacobian) {
  const Kinematics kin(params);
  const Eigen::Index n = static_cast<Eigen::Index>(samples.size());
  residuals.resize(n);
  if (jacobian) jacobian->resize(n, kParamCount);
  ParamRow gradient;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Sample& s = samples[i];
    const Eigen::Vector3d& ball = fixtures.balls_mm[s.ball_index];
    const Eigen::Vector3d& chuck = fixtures.chucks_mm[s.chuck_index];
    if (jacobian) {
      residuals[i] = s.length_mm - kin.barLengthGradient(s.joints_deg, ball, chuck, gradient);
      jacobian->row(i) = -gradient;
    } else {
      residuals[i] = s.length_mm - kin.barLength(s.joints_deg, ball, chuck);
    }
  }
}

}  // namespace robocal

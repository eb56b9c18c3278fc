// How many of the 54 parameters a set of measurements identifies: the numerical rank of the
// column-scaled Jacobian, the singular-value gap that decides it, and which parameters are
// redundant (paper Section 6, Table I).
#pragma once

#include <robocal/kinematics/model.hpp>

#include <Eigen/Core>
#include <vector>

namespace robocal {

// N = 5 R + 3 P + 6 independent parameters for R revolute and P prismatic joints.
constexpr int expectedIndependentParams(int revolute, int prismatic) {
  return 5 * revolute + 3 * prismatic + 6;
}

struct Identifiability {
  int rank = 0;
  int expected = expectedIndependentParams(kJointCount, 0);
  // Singular values of the column-scaled Jacobian divided by the largest, descending.
  Eigen::VectorXd singular_values;
  double threshold = 0;         // relative singular values at or below this count as zero
  double gap = 0;               // sigma[rank-1] / sigma[rank]: how clearly the rank is decided
  std::vector<int> vanishing;   // parameters whose Jacobian column is zero
  std::vector<int> redundant;   // parameters left unidentified (vanishing ones included)
  std::vector<int> identified;  // the others; a basis of the identifiable directions
};

// Relative singular value below which a direction is not identified. Exact redundancies sit
// near 1e-15; the weakest identifiable direction of a sensible data set is above 1e-6.
inline constexpr double kRankThreshold = 1e-9;

// Analyses an m x 54 Jacobian. Columns are scaled to unit norm first, so the rank does not
// depend on units. Redundant parameters are chosen in a fixed priority order: joint offsets and
// gains are kept first, then link translations, then link angles, each in chain order.
Identifiability analyzeIdentifiability(const Eigen::MatrixXd& jacobian);

// The upper-triangular 54 x 54 factor R of J = QR. Stacking the R of several data sets gives a
// matrix with the same singular values as stacking their Jacobians, for far fewer rows.
Eigen::MatrixXd triangularFactor(const Eigen::MatrixXd& jacobian);

}  // namespace robocal

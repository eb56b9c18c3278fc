#include <robocal/solver/identifiability.hpp>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>

namespace robocal {
namespace {

// Joint parameters first, then link translations, then link angles.
std::vector<int> priorityOrder() {
  std::vector<int> order;
  for (int j = 0; j < kJointCount; ++j) order.push_back(jointParamIndex(j));
  for (int j = 0; j < kJointCount; ++j) order.push_back(jointParamIndex(j) + 1);
  for (int part : {0, 3})
    for (int k = 0; k < kLinkCount; ++k)
      for (int c = 0; c < 3; ++c) order.push_back(linkParamIndex(k) + part + c);
  return order;
}

}  // namespace

Eigen::MatrixXd triangularFactor(const Eigen::MatrixXd& jacobian) {
  if (jacobian.rows() <= jacobian.cols()) return jacobian;
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(jacobian);
  return qr.matrixQR().topRows(jacobian.cols()).triangularView<Eigen::Upper>();
}

Identifiability analyzeIdentifiability(const Eigen::MatrixXd& jacobian) {
  Identifiability out;
  out.threshold = kRankThreshold;
  if (jacobian.rows() == 0 || jacobian.cols() == 0) {
    for (int i = 0; i < jacobian.cols(); ++i) out.redundant.push_back(i);
    return out;
  }
  const Eigen::Index cols = jacobian.cols();
  Eigen::VectorXd norms = jacobian.colwise().norm();
  const double largest_norm = norms.maxCoeff();
  Eigen::MatrixXd scaled = jacobian;
  for (Eigen::Index c = 0; c < cols; ++c) {
    if (!(norms[c] > 1e-12 * largest_norm)) {
      out.vanishing.push_back(static_cast<int>(c));
      scaled.col(c).setZero();
    } else {
      scaled.col(c) /= norms[c];
    }
  }
  const Eigen::MatrixXd r = triangularFactor(scaled);  // same singular values, 54 rows
  // Jacobi: the singular values to eps * sigma_max, which the rank threshold (1e-9) needs.
  // (Eigen 3.4.0's BDCSVD, four times cheaper, reads out of bounds in perturbCol0 on the
  // exactly redundant columns of some connection sets: ASan caught it in robocal identify
  // --table.)
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(r);
  out.singular_values = svd.singularValues();
  if (out.singular_values.size() == 0 || out.singular_values[0] <= 0) return out;
  out.singular_values /= out.singular_values[0];
  while (out.rank < out.singular_values.size() && out.singular_values[out.rank] > out.threshold)
    ++out.rank;
  if (out.rank < out.singular_values.size())
    out.gap = out.singular_values[out.rank - 1] / std::max(out.singular_values[out.rank], 1e-300);

  // Greedy basis in priority order: accept a column when it adds a direction that the columns
  // accepted so far do not span (relative residual above the rank threshold, as sqrt because
  // projection residuals behave like singular values).
  Eigen::MatrixXd q(r.rows(), 0);
  for (int index : priorityOrder()) {
    if (static_cast<int>(out.identified.size()) == out.rank) break;
    Eigen::VectorXd v = r.col(index);
    if (v.norm() == 0) continue;
    for (int pass = 0; pass < 2; ++pass) v -= q * (q.transpose() * v);
    if (v.norm() > 1e-6) {
      q.conservativeResize(Eigen::NoChange, q.cols() + 1);
      q.col(q.cols() - 1) = v.normalized();
      out.identified.push_back(index);
    }
  }
  std::sort(out.identified.begin(), out.identified.end());
  for (int i = 0; i < kParamCount; ++i)
    if (!std::binary_search(out.identified.begin(), out.identified.end(), i))
      out.redundant.push_back(i);
  return out;
}

}  // namespace robocal

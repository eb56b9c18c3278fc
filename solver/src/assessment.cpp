#include <robocal/solver/assessment.hpp>
#include <robocal/solver/verdict.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <tuple>

namespace robocal {
namespace {

std::vector<Connection> connectionsOf(const std::vector<Sample>& samples) {
  std::vector<Connection> out;
  for (const Connection& c : allConnections())
    if (std::any_of(samples.begin(), samples.end(), [&](const Sample& s) {
          return s.ball_index == c.ball_index && s.chuck_index == c.chuck_index;
        }))
      out.push_back(c);
  return out;
}

std::vector<ParameterRow> parameterTable(const Model& nominal, const SolveResult& fit) {
  const ParamVector start = toParams(nominal);
  ParamVector sigma;
  for (int i = 0; i < kParamCount; ++i) sigma[i] = std::sqrt(std::max(0.0, fit.covariance(i, i)));
  std::vector<ParameterRow> rows;
  for (int i = 0; i < kParamCount; ++i) {
    ParameterRow row;
    row.index = i;
    row.nominal = paramInterfaceValue(start, i);
    row.calibrated = paramInterfaceValue(fit.params, i);
    row.estimated = std::binary_search(fit.free_params.begin(), fit.free_params.end(), i);
    row.sigma = row.estimated ? paramInterfaceValue(sigma, i) : 0.0;
    rows.push_back(row);
  }
  return rows;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t mid = v.size() / 2;
  return v.size() % 2 ? v[mid] : 0.5 * (v[mid - 1] + v[mid]);
}

}  // namespace

ShellTable shellTable(const std::vector<Sample>& samples, const Eigen::VectorXd& residuals) {
  // A shell is its number, connection and extension (files of other runs may reuse numbers).
  std::map<std::tuple<int, int, int, double>, std::vector<double>> groups;
  for (size_t i = 0; i < samples.size(); ++i) {
    const Sample& s = samples[i];
    groups[{s.shell, s.ball_index, s.chuck_index, s.extension_mm}].push_back(
        residuals[static_cast<Eigen::Index>(i)]);
  }
  ShellTable table;
  std::vector<double> rms;
  for (const auto& [key, r] : groups) {
    ShellResiduals shell;
    std::tie(shell.shell, shell.connection.ball_index, shell.connection.chuck_index,
             shell.extension_mm) = key;
    shell.stats = residualStats(Eigen::Map<const Eigen::VectorXd>(r.data(), r.size()));
    rms.push_back(shell.stats.rms_mm);
    table.shells.push_back(shell);
  }
  const double typical = median(rms);
  for (ShellResiduals& shell : table.shells) {
    shell.rms_to_median = typical > 0 ? shell.stats.rms_mm / typical : 1.0;
    shell.stands_out = table.shells.size() > 1 && shell.rms_to_median >= kShellStandsOut;
  }
  table.worst.resize(table.shells.size());
  std::iota(table.worst.begin(), table.worst.end(), 0);
  std::stable_sort(table.worst.begin(), table.worst.end(), [&](int a, int b) {
    return table.shells[a].stats.rms_mm > table.shells[b].stats.rms_mm;
  });
  table.worst.resize(std::min<size_t>(table.worst.size(), kWorstShellsNamed));
  return table;
}

const Eigen::MatrixXd& calibratedCovariance(const FitAssessment& a) {
  return a.compliance && a.compliance->covariance.size() > 0 ? a.compliance->covariance
                                                             : a.fit.covariance;
}

FitAssessment assessFit(const Model& nominal, std::vector<Sample> samples,
                        const AssessOptions& options) {
  FitAssessment a;
  a.nominal = nominal;
  a.outlier_sigmas = options.outlier_sigmas;
  // The start of the fit: the nominal, with the identified compliance when it is identified.
  Model start = nominal;
  const auto fitSamples = [&](const std::vector<Sample>& fitted) {
    if (!options.identify_compliance || !nominal.compliance)
      return solveCalibration(nominal, fitted, options.solve);
    a.compliance.emplace();
    SolveResult fit = solveWithCompliance(nominal, fitted, options.solve, *a.compliance);
    start.compliance = a.compliance->compliance;
    return fit;
  };
  a.fit = fitSamples(samples);
  const std::vector<Outlier> outliers = findOutliers(a.fit.residuals, options.outlier_sigmas);
  for (const Outlier& o : outliers)
    a.outliers.push_back({samples[o.index], o.residual_mm, o.robust_sigmas});
  if (options.drop_outliers && !outliers.empty()) {
    std::vector<Sample> kept;
    size_t next = 0;
    for (size_t i = 0; i < samples.size(); ++i) {
      if (next < outliers.size() && outliers[next].index == i)
        ++next;
      else
        kept.push_back(samples[i]);
    }
    samples.swap(kept);
    a.outliers_dropped = true;
    a.fit = fitSamples(samples);
  }
  a.samples = std::move(samples);
  a.calibrated = withParams(start, a.fit.params);
  a.calibrated.provenance.reset();  // the nominal's, if it had one, is not this model's

  // With the twist's uncertainty when the fit looked for one (the calibrated model's covariance).
  const std::vector<double> errors =
      predictedBallErrors(a.calibrated, calibratedCovariance(a), a.samples);
  double sum = 0;
  for (double e : errors) {
    sum += e * e;
    a.predicted_ball_error_max_mm = std::max(a.predicted_ball_error_max_mm, e);
  }
  a.predicted_ball_error_rms_mm = std::sqrt(sum / std::max<size_t>(1, errors.size()));
  a.bar_to_endpoint_factor = barToEndpointErrorFactor(a.calibrated, a.samples);
  a.parameters = parameterTable(nominal, a.fit);
  a.shells = shellTable(a.samples, a.fit.residuals);
  a.connections = connectionsOf(a.samples);
  a.adequacy = testAdequacy(a.calibrated, a.samples, a.fit.residuals, a.fit.sigma_mm);
  a.problems = fitProblems(a, options.verdict);

  if (options.validation) {
    const HeldOutSamples& held = *options.validation;
    ValidationResult v;
    v.description = held.description;
    v.samples = held.samples;
    v.residuals = sampleResiduals(held.predictor ? *held.predictor : a.calibrated, v.samples);
    v.stats = residualStats(v.residuals);
    v.shells = shellTable(v.samples, v.residuals);
    a.validation = std::move(v);
  }
  if (options.truth)
    a.truth = compareWithTruth(nominal, a.calibrated, options.truth,
                               a.validation ? a.validation->samples : a.samples);
  return a;
}

}  // namespace robocal

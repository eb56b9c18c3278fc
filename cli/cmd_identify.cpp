// robocal identify: which parameters shells of given connections identify (paper Table I).
#include "args.hpp"

#include <robocal/formats/model_json.hpp>
#include <robocal/sim/measurements.hpp>
#include <robocal/solver/identifiability.hpp>
#include <robocal/solver/problem.hpp>

#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>

namespace robocal::cli {
namespace {

constexpr const char* kHelp = R"(usage: robocal identify --model M [--connections LIST] [--json]
       robocal identify --model M --table [--json]

Numerical rank of the 54-column Jacobian of the bar lengths for shells of the given connections
(poses from the nominal model, as robocal simulate makes them), the expected N = 5R + 3P + 6,
the singular-value gap that decides the rank, and the parameters left unidentified.
--table runs the paper's Table I rows and every one of the 511 combinations of connections.

  --model FILE          model (model format)                          required
  --connections LIST    all, or e.g. B1C1,B1C2,B1C3                    [all]
  --bar-mm L            bar length at zero deflection                  [150]
  --extension-mm E      extension bar length                           [0]
  --points-per-shell N  grid points per shell                          [90]
  --seed N              seed for the tool orientations                 [1]
  --json                one JSON object instead of text
)";

nlohmann::json names(const std::vector<int>& indices) {
  nlohmann::json out = nlohmann::json::array();
  for (int i : indices) out.push_back(paramName(i));
  return out;
}

std::string joinNames(const std::vector<int>& indices) {
  std::string out;
  for (int i : indices) out += (out.empty() ? "" : " ") + paramName(i);
  return out.empty() ? "none" : out;
}

// The Jacobian of one shell per connection, as an upper-triangular factor, and the sample count.
struct ShellFactor {
  Eigen::MatrixXd r;
  size_t samples = 0;
};

ShellFactor shellFactor(const Model& model, const Connection& c, const Args& args,
                        std::mt19937_64& rng) {
  ShellRequest req;
  req.connection = c;
  req.extension_mm = args.number("extension-mm", 0);
  req.radius_mm = args.number("bar-mm", kDefaultBarMm) + req.extension_mm;
  req.points = static_cast<int>(args.integer("points-per-shell", 90));
  if (req.radius_mm <= 0 || req.points < 1)
    throw UsageError("shell radius and points must be positive");
  const ShellPoses poses = shellPoses(model, req, rng);
  const MeasurementNoise exact{0.0, 0.0};
  const auto samples = measureShell(model, req, poses.poses, exact, rng);
  Eigen::VectorXd residuals;
  Eigen::MatrixXd jac;
  evaluateProblem(model, toParams(model), samples, residuals, &jac);
  return {triangularFactor(jac), samples.size()};
}

Identifiability analyzeSet(const std::vector<const ShellFactor*>& set) {
  Eigen::Index rows = 0;
  for (const auto* f : set) rows += f->r.rows();
  Eigen::MatrixXd stacked(rows, kParamCount);
  rows = 0;
  for (const auto* f : set) {
    stacked.middleRows(rows, f->r.rows()) = f->r;
    rows += f->r.rows();
  }
  return analyzeIdentifiability(stacked);
}

nlohmann::json resultJson(const Identifiability& id, const std::vector<Connection>& cs,
                          size_t samples) {
  nlohmann::json sv = nlohmann::json::array();
  for (Eigen::Index i = 0; i < id.singular_values.size(); ++i) sv.push_back(id.singular_values[i]);
  return {{"class", "IDENTIFY"},
          {"connections", connectionList(cs)},
          {"samples", samples},
          {"rank", id.rank},
          {"parameters", kParamCount},
          {"expected", id.expected},
          {"threshold", id.threshold},
          {"gap", id.gap},
          {"singular_values", sv},
          {"vanishing", names(id.vanishing)},
          {"redundant", names(id.redundant)}};
}

void printResult(const Identifiability& id, const std::vector<Connection>& cs, size_t samples) {
  std::printf("connections: %s (%zu shells, %zu samples)\n", connectionList(cs).c_str(), cs.size(),
              samples);
  std::printf("rank: %d of %d parameters (expected N = 5R + 3P + 6 = %d)\n", id.rank, kParamCount,
              id.expected);
  const auto& s = id.singular_values;
  if (id.rank > 0 && id.rank < s.size())
    std::printf("gap: relative singular value %d = %.3g, %d = %.3g (ratio %.3g; threshold %.0e)\n",
                id.rank, s[id.rank - 1], id.rank + 1, s[id.rank], id.gap, id.threshold);
  std::printf("vanishing columns: %s\n", joinNames(id.vanishing).c_str());
  std::printf("not identified (%zu): %s\n", id.redundant.size(), joinNames(id.redundant).c_str());
}

int runTable(const Model& model, const Args& args, std::mt19937_64& rng) {
  const auto all = allConnections();
  std::vector<ShellFactor> factors;
  for (const auto& c : all) factors.push_back(shellFactor(model, c, args, rng));
  struct Row {
    std::vector<Connection> connections;
    Identifiability id;
  };
  std::vector<Row> rows;
  for (unsigned mask = 1; mask < (1u << all.size()); ++mask) {
    Row row;
    std::vector<const ShellFactor*> set;
    for (size_t i = 0; i < all.size(); ++i)
      if (mask & (1u << i)) {
        row.connections.push_back(all[i]);
        set.push_back(&factors[i]);
      }
    row.id = analyzeSet(set);
    rows.push_back(std::move(row));
  }
  auto find = [&](const std::string& list) -> const Row& {
    const auto cs = parseConnections(list);
    for (const Row& r : rows)
      if (r.connections == cs) return r;
    throw std::logic_error("no row " + list);
  };
  // The paper's rows: one ball to three chucks, all nine, and subsets of six.
  const std::vector<std::string> paper = {"B1C1,B1C2,B1C3", "B2C1,B2C2,B2C3", "B3C1,B3C2,B3C3",
                                          "all"};
  std::map<int, std::map<size_t, int>> by_rank;  // rank -> subset size -> count
  for (const Row& r : rows) ++by_rank[r.id.rank][r.connections.size()];
  int six_total = 0, six_full = 0;
  for (const Row& r : rows)
    if (r.connections.size() == 6) {
      ++six_total;
      six_full += r.id.rank == r.id.expected;
    }

  if (args.flag("json")) {
    nlohmann::json out = {{"class", "IDENTIFY_TABLE"},
                          {"paper_rows", nlohmann::json::array()},
                          {"combinations", nlohmann::json::array()}};
    for (const auto& p : paper) {
      const Row& r = find(p);
      out["paper_rows"].push_back({{"connections", connectionList(r.connections)},
                                   {"rank", r.id.rank},
                                   {"redundant", names(r.id.redundant)}});
    }
    for (const Row& r : rows)
      out["combinations"].push_back(
          {{"connections", connectionList(r.connections)}, {"rank", r.id.rank}, {"gap", r.id.gap}});
    out["six_of_nine"] = {{"total", six_total}, {"rank_36", six_full}};
    std::printf("%s\n", out.dump().c_str());
    return 0;
  }
  std::printf("Table I (paper rows), %ld points per shell, radius %.0f mm\n",
              args.integer("points-per-shell", 90),
              args.number("bar-mm", kDefaultBarMm) + args.number("extension-mm", 0));
  for (const auto& p : paper) {
    const Row& r = find(p);
    std::printf("  %-44s rank %2d  gap %.2g\n", connectionList(r.connections).c_str(), r.id.rank,
                r.id.gap);
  }
  std::printf("  any six of nine: %d of %d subsets reach rank %d\n\n", six_full, six_total,
              rows.front().id.expected);
  std::printf("Every combination, grouped by rank (count by number of connections):\n");
  for (const auto& [rank, sizes] : by_rank) {
    std::printf("rank %2d:", rank);
    for (const auto& [size, count] : sizes) std::printf("  %zu conn x%d", size, count);
    std::printf("\n");
  }
  for (const auto& [rank, sizes] : by_rank) {
    std::printf("\n-- rank %d --\n", rank);
    for (const Row& r : rows)
      if (r.id.rank == rank) std::printf("  %s\n", connectionList(r.connections).c_str());
  }
  return 0;
}

int run(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"model", "connections", "bar-mm", "extension-mm", "points-per-shell", "seed"},
                  {"json", "table", "help"});
  if (args.flag("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  const Model model = loadModelFile(args.required("model"));
  std::mt19937_64 rng(args.integer("seed", 1) * 7919 + 1);
  if (args.flag("table")) return runTable(model, args, rng);

  const auto connections = parseConnections(args.get("connections", "all"));
  std::vector<ShellFactor> factors;
  std::vector<const ShellFactor*> set;
  size_t samples = 0;
  for (const auto& c : connections) factors.push_back(shellFactor(model, c, args, rng));
  for (const auto& f : factors) {
    set.push_back(&f);
    samples += f.samples;
  }
  const Identifiability id = analyzeSet(set);
  if (args.flag("json"))
    std::printf("%s\n", resultJson(id, connections, samples).dump().c_str());
  else
    printResult(id, connections, samples);
  return 0;
}

const RegisterCommand registered({"identify", "identifiability: rank of the Jacobian (Table I)",
                                  run});

}  // namespace
}  // namespace robocal::cli

// Test helper: simulated ball-bar data for the solver's tests: shells planned on the nominal
// PUMA 560, measured on a perturbed true robot with Gaussian noise.
#pragma once

#include <robocal/robot/puma560.hpp>
#include <robocal/sim/measurements.hpp>

#include <random>
#include <string>
#include <vector>

namespace robocal::test {

struct Shells {
  std::vector<ShellRequest> requests;
  std::vector<std::vector<ShellPose>> poses;
};

// Poses of the nominal model on shells of the given connections (radius kDefaultBarMm + extension).
inline Shells planShells(const Model& nominal, const std::string& connections, double extension_mm,
                         int points, unsigned seed) {
  std::mt19937_64 rng(seed);
  Shells out;
  out.requests = shellRequests(parseConnections(connections), {extension_mm}, points);
  for (const ShellRequest& req : out.requests)
    out.poses.push_back(shellPoses(nominal, req, rng).poses);
  return out;
}

inline std::vector<Sample> measure(const Model& truth, const Shells& shells, double noise_mm,
                                   unsigned seed) {
  std::mt19937_64 rng(seed);
  std::vector<Sample> all;
  for (size_t i = 0; i < shells.requests.size(); ++i) {
    auto s = measureShell(truth, shells.requests[i], shells.poses[i], {noise_mm, 0}, rng);
    all.insert(all.end(), s.begin(), s.end());
  }
  return all;
}

inline Model perturbed(double factor, unsigned seed) {
  std::mt19937_64 rng(seed);
  return perturbModel(puma560NominalModel(), PerturbationSigmas{}.scaled(factor), rng);
}

}  // namespace robocal::test

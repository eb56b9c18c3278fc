// The plan of an ISO 9283-style performance test with the ball-bar (docs/iso9283.md): one bar
// connection (the cell's first, at its first extension), five poses on its shell: P1 the safe
// point whose ball is nearest the centre of the cell's work volume, P2..P5 the safe points nearest
// the corners of a square `spread_deg` of latitude and longitude about it (the standard puts
// P2..P5 on a diagonal plane of its test cube about P1; the bar keeps them on the shell). Visited
// P1, P2, ..., P5 for warmup_cycles + cycles cycles, each pose reached the same way in every
// cycle (the same vias and approach pre-point), so what differs between cycles is the robot and
// the bar. The revisits and the reference pose of calibration plans are left out: every pose is a
// revisit here. No I/O; the plan passes checkPlan like any other.
#pragma once

#include <robocal/planner/plan.hpp>

namespace robocal {

inline constexpr int kIsoPoseCount = 5;

// Throws PlanError when the settings are out of range or the shell holds no five safe poses.
Plan planIsoTest(const Model& model, const CellConfig& cell, const IsoTestSettings& settings = {});

}  // namespace robocal

// ValController's motion through vias: a path program written line by line, then executed and
// watched as a move (val.hpp, asyncMovePath).
#include <robocal/drivers/val.hpp>

#include <boost/asio/post.hpp>

#include <cmath>

namespace robocal::drivers {

double ValController::pathCommandTimeout(const std::vector<Joints6>& steps) const {
  const ValConfig& c = dialect_.config();
  if (!last_joints_ || !speed_percent_) return std::max(c.move_timeout_s, c.motion_timeout_s);
  const double speed_deg_s = c.slowest_joint_speed_deg_s * *speed_percent_ / 100.0;
  double travel_deg = 0;
  Joints6 from = *last_joints_;
  for (const Joints6& to : steps) {
    travel_deg += maxJointDiffDeg(to, from);
    from = to;
  }
  return c.move_timeout_s + travel_deg / speed_deg_s;
}

void ValController::asyncMovePath(const std::vector<Joints6>& steps, WhereHandler handler,
                                  ProgressHandler progress) {
  const auto fail = [&](const std::string& why) {
    boost::asio::post(io_,
                      [handler, why] { handler(std::make_exception_ptr(DriverError(why)), {}); });
  };
  if (!offersPaths())
    return fail("the controller's dialect (" + dialect_.config().dialect +
                ") has no path program (val.path_execute_command is empty)");
  if (steps.empty()) return fail("a path needs at least one step");
  for (const Joints6& step : steps)
    for (double v : step)
      if (!std::isfinite(v)) return fail("a path step has a joint angle that is not a number");
  auto lines = std::make_shared<std::vector<std::string>>(dialect_.pathCommands(steps));
  sendPathLines(lines, 0, steps.back(), pathCommandTimeout(steps), std::move(handler),
                std::move(progress));
}

void ValController::sendPathLines(std::shared_ptr<std::vector<std::string>> lines, std::size_t next,
                                  Joints6 target, double timeout_s, WhereHandler handler,
                                  ProgressHandler progress) {
  if (next + 1 == lines->size()) {
    // The program is written. The watch sees the arm once more before anything moves (a stop
    // asked for while the lines went out ends it here), then the execute command: a motion,
    // watched as one.
    return asyncWhere(
        [this, lines, target, timeout_s, handler, progress](std::exception_ptr e, WhereReply w) {
          if (e) return handler(e, {});
          if (progress) progress(w);
          asyncMotionCommand(lines->back(), timeout_s, target, handler, progress);
        });
  }
  asyncCommand((*lines)[next], dialect_.config().command_timeout_s,
               [this, lines, next, target, timeout_s, handler, progress](std::exception_ptr e,
                                                                         std::vector<std::string>) {
                 if (e) return leaveEditor(lines, next, e, handler);
                 sendPathLines(lines, next + 1, target, timeout_s, handler, progress);
               });
}

// A program line refused: the editor is left (best effort) so that what follows is read as
// monitor commands again, not as program lines; nothing was executed.
void ValController::leaveEditor(std::shared_ptr<std::vector<std::string>> lines, std::size_t failed,
                                std::exception_ptr error, WhereHandler handler) {
  const std::size_t end_edit = lines->size() - 2;
  if (failed == 0 || failed >= end_edit) return handler(error, {});
  asyncCommand(
      (*lines)[end_edit], dialect_.config().command_timeout_s,
      [error, handler](std::exception_ptr, std::vector<std::string>) { handler(error, {}); });
}

WhereReply ValController::movePath(const std::vector<Joints6>& steps,
                                   const ProgressHandler& progress) {
  const ValConfig& c = dialect_.config();
  return runSync<WhereReply>([&](WhereHandler h) { asyncMovePath(steps, std::move(h), progress); },
                             static_cast<double>(steps.size() + 2) * c.command_timeout_s +
                                 pathCommandTimeout(steps) + c.motion_timeout_s +
                                 2 * c.where_timeout_s + 1);
}

}  // namespace robocal::drivers

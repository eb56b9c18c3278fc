#include "run_context.hpp"

#include <robocal/drivers/errors.hpp>

#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdio>
#include <limits>

namespace robocal::daemon {
namespace {

using json = nlohmann::json;

std::int64_t monotonicMicros(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::microseconds>(t.time_since_epoch()).count();
}

// Readings go into window_ while one lives (also when a fault ends the window early: nothing
// collects while idle).
struct Collecting {
  bool& flag;
  explicit Collecting(bool& f) : flag(f) { flag = true; }
  ~Collecting() { flag = false; }
};

std::chrono::steady_clock::duration fromSeconds(double seconds) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(seconds));
}

proto::BarKind wireKind(drivers::BarLineKind kind) {
  switch (kind) {
    case drivers::BarLineKind::kReading:
      return proto::BarKind::kReading;
    case drivers::BarLineKind::kOverRange:
      return proto::BarKind::kOverRange;
    case drivers::BarLineKind::kNoProbe:
      return proto::BarKind::kNoProbe;
    case drivers::BarLineKind::kDeviceError:
    case drivers::BarLineKind::kGarbage:
      break;
  }
  return proto::BarKind::kDeviceError;
}

}  // namespace

RunContext::RunContext(const DaemonConfig& c, const Model& m, const std::optional<CellConfig>& cell,
                       RunController::Publish p, RunStore& s, RunShared& sh, CellIo& cell_io)
    : config(c), nominal(m), store(s), shared(sh), io(cell_io), publish(std::move(p)), cell_(cell) {
  io.onBarLine([this](const drivers::BarReading& r) { onBarLine(r); });
}

// ------------------------------------------------------------------------ state and events

void RunContext::setState(proto::RunState to, const std::string& reason) {
  const proto::RunState from = shared.with([&](RunData& d) {
    const proto::RunState was = d.state;
    d.state = to;
    d.state_reason = reason;
    d.starting = false;
    return was;
  });
  spdlog::info("state {} -> {}{}{}", proto::runStateName(from), proto::runStateName(to),
               reason.empty() ? "" : ": ", reason);
  publish(proto::toJson(proto::State{from, to, reason}), false);
}

void RunContext::event(RunDir& dir, json ev) {
  dir.logEvent(ev);
  proto::Event e{ev.value("event", ""), std::move(ev)};
  e.details.erase("event");
  publish(proto::toJson(e), false);
}

std::string RunContext::stopReason(const std::string& fallback) const {
  return shared.with(
      [&](const RunData& d) { return d.stop_reason.empty() ? fallback : d.stop_reason; });
}

void RunContext::checkpoint() {
  if (shared.abort_requested) throw StopRun{StopRun::kAbort, stopReason("abort requested")};
  if (shared.pause_requested) throw StopRun{StopRun::kPause, stopReason("pause requested")};
}

void RunContext::updateProgress(int done, int total, double time_left_s) {
  const proto::Progress p = shared.with([&](RunData& d) {
    d.points_done = done;
    d.points_total = total;
    d.eta_s = time_left_s;
    return proto::Progress{d.shell_number, d.shells_total, d.connection_name,
                           done,           total,          time_left_s};
  });
  publish(proto::toJson(p), false);
}

// ------------------------------------------------------------------------ devices

void RunContext::connectDevices() {
  const DeviceState now = io.connect();
  shared.with([&](RunData& d) { d.devices = now; });
}

void RunContext::ensureDevices() {
  connectDevices();
  const DeviceState now = shared.with([](const RunData& d) { return d.devices; });
  if (!now.bar_connected) throw StopRun{StopRun::kFault, "ball-bar reader: " + now.bar_error};
  if (!now.val_connected) throw StopRun{StopRun::kFault, "VAL II controller: " + now.val_error};
}

void RunContext::reportLinkFaults(RunDir& dir) {
  const std::map<std::string, long> now = io.faultCounts();
  json ev = {{"event", "link_faults"}};
  for (const auto& [name, count] : now)
    if (count > link_faults_reported_[name]) ev[name] = count - link_faults_reported_[name];
  link_faults_reported_ = now;
  if (ev.size() > 1) event(dir, ev);
}

// ------------------------------------------------------------------------ the bar

void RunContext::onBarLine(const drivers::BarReading& r) {
  last_reading_ = r;
  if (r.kind == drivers::BarLineKind::kReading) {
    recent_readings_mm_.push_back(r.value_mm);
    if (recent_readings_mm_.size() > kReferenceReadings) recent_readings_mm_.pop_front();
  }
  if (detached_reference_mm_) detached_.add(r, *detached_reference_mm_);
  if (collecting_ && r.kind == drivers::BarLineKind::kReading) window_.push_back(r.value_mm);
  if (steady_ && r.kind == drivers::BarLineKind::kReading)
    steady_->add(std::chrono::duration<double>(r.time - dwell_start_).count(), r.value_mm);
  proto::Bar b{r.sequence, wireKind(r.kind), std::nullopt, std::nullopt, monotonicMicros(r.time)};
  if (r.kind == drivers::BarLineKind::kReading) {
    b.deflection_mm = r.value_mm;
    if (bar_offset_mm_ > 0) b.length_mm = bar_offset_mm_ + r.value_mm;
  }
  shared.with([&](RunData& d) { d.latest_bar = b; });
  publish(proto::toJson(b), true);
}

std::optional<double> RunContext::recentReadingMm() const {
  if (recent_readings_mm_.empty()) return std::nullopt;
  std::vector<double> v(recent_readings_mm_.begin(), recent_readings_mm_.end());
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

void RunContext::setAttachment(const BarAttachment& a) {
  store.setBarAttachment(a);
  shared.with([&](RunData& d) { d.attachment = a; });
}

BarAttachment RunContext::attachment() const {
  return shared.with([](const RunData& d) { return d.attachment; });
}

std::optional<double> RunContext::watchBar() {
  return watchBar(config.bar_hard_limit_mm);
}

std::optional<double> RunContext::watchBar(double hard_limit_mm) {
  if (!io.barConnected()) throw StopRun{StopRun::kFault, "ball-bar reader disconnected"};
  if (io.barStale())
    throw StopRun{StopRun::kFault, "no ball-bar reading for " +
                                       std::to_string(config.drivers.bar.stale_after_s) + " s"};
  if (!last_reading_) return std::nullopt;
  if (last_reading_->kind != drivers::BarLineKind::kReading)
    throw StopRun{StopRun::kFault,
                  std::string("ball-bar reports ") + drivers::barLineKindName(last_reading_->kind)};
  const double d = last_reading_->value_mm;
  if (std::abs(d) > hard_limit_mm)
    throw StopRun{StopRun::kFault, "bar deflection " + std::to_string(d) +
                                       " mm past the hard limit " + std::to_string(hard_limit_mm) +
                                       " mm"};
  if (std::abs(d) > config.bar_soft_limit_mm) return d;
  return std::nullopt;
}

void RunContext::DetachedChange::add(const drivers::BarReading& r, double reference_mm) {
  if (r.kind == drivers::BarLineKind::kOverRange) {
    over_range = true;
    return;
  }
  if (r.kind != drivers::BarLineKind::kReading) return;
  change_mm = r.value_mm - reference_mm;
  readings_past = std::abs(change_mm) > threshold_mm ? readings_past + 1 : 0;
}

void RunContext::watchDetached() {
  if (!detached_reference_mm_ || (!detached_.over_range && detached_.readings_past < 2)) return;
  BarAttachment doubt = attachment();
  doubt.maybe_attached = true;
  setAttachment(doubt);  // the next start or resume asks to detach it first
  char buf[64];
  std::snprintf(buf, sizeof buf,
                detached_.over_range ? "from %+.3f mm to over range" : "by %+.3f mm",
                detached_.over_range ? *detached_reference_mm_ : detached_.change_mm);
  throw DetachedBarMoved{{StopRun::kFault, std::string("the ball-bar reading changed ") + buf +
                                               " while the robot moved with the bar believed "
                                               "detached: check that the bar is off the robot"}};
}

// ------------------------------------------------------------------------ moves and time

void RunContext::spin(double seconds, bool watch_bar) {
  spinUntil(Clock::now() + fromSeconds(seconds), watch_bar);
}

// Each slice ends at the deadline, not 10 ms after the last check: no overshoot past the
// event loop's wake-up.
void RunContext::spinUntil(Clock::time_point until, bool watch_bar) {
  for (auto now = Clock::now(); now < until; now = Clock::now()) {
    checkpoint();
    io.poll(std::min(until, now + std::chrono::milliseconds(10)));
    if (watch_bar) watchBar();
  }
}

std::optional<double> RunContext::measuredNoiseMm() const {
  // Fewer degrees of freedom than this: the measured noise is too uncertain to judge by.
  constexpr std::size_t kMinStillDof = 20;
  if (still_noise_.dof() < kMinStillDof || still_noise_.mm() <= 0) return std::nullopt;
  return still_noise_.mm();
}

std::optional<double> RunContext::adaptiveNoiseMm() const {
  if (config.dwell_mode != "adaptive" || !audit_.trusted()) return std::nullopt;
  if (config.bar_noise_mm > 0) return config.bar_noise_mm;
  return measuredNoiseMm();
}

RunContext::Dwell RunContext::dwell(Clock::time_point motion_end, bool adaptive_allowed) {
  const auto until = motion_end + fromSeconds(config.settle_s);
  Dwell d;
  const std::optional<double> noise =
      adaptive_allowed ? adaptiveNoiseMm() : std::optional<double>{};
  if (!noise) {
    spinUntil(until, true);
    return d;
  }
  d.adaptive = true;
  d.noise_mm = *noise;
  SteadyCriteria criteria;
  criteria.noise_mm = *noise;
  criteria.window_s = config.adaptive_window_s;
  SteadyWindow steady(criteria);
  struct Feeding {  // also when a fault ends the dwell: no reading is fed to a window gone
    SteadyWindow*& slot;
    Feeding(SteadyWindow*& s, SteadyWindow& w) : slot(s) { slot = &w; }
    ~Feeding() { slot = nullptr; }
  };
  dwell_start_ = motion_end;
  {
    const Feeding feeding(steady_, steady);
    for (auto now = Clock::now(); now < until && !d.steady; now = Clock::now()) {
      checkpoint();
      io.poll(std::min(until, now + std::chrono::milliseconds(10)));
      watchBar();
      d.steady = steady.steady();
    }
  }
  // An audit compares a whole window with the fixed dwell's: steady too late for one, the dwell
  // ends (it saved little) and the audit waits for the next steady dwell.
  const long every = config.adaptive_audit_every;
  const bool room = Clock::now() + fromSeconds(config.bar_window_s) <= until;
  if (!d.steady || every <= 0 || !room || steady_dwells_++ % every != 0) {
    d.ended_early = d.steady;
    return d;
  }
  // Audited: the window the adaptive dwell would have read, then on to settle_s.
  clearWindow();
  {
    const Collecting collect(collecting_);
    spinUntil(std::min(until, Clock::now() + fromSeconds(config.bar_window_s)), true);
  }
  if (!window_.empty()) {
    d.audited = true;
    d.audit_readings = window_.size();
    for (double v : window_) d.audit_mean_mm += v;
    d.audit_mean_mm /= static_cast<double>(window_.size());
  }
  spinUntil(until, true);
  return d;
}

DwellAudit::Verdict RunContext::audit(const Dwell& d, const Measurement& m) {
  // Judged by the noise measured, whatever bar_noise_mm says: a figure set too high must not
  // blind the audit that is there to catch it.
  return audit_.add(d.audit_mean_mm, d.audit_readings, m.deflection_mm, m.readings,
                    measuredNoiseMm().value_or(d.noise_mm));
}

JointsDeg RunContext::move(const JointsDeg& target, bool bar_attached) {
  return move(target, bar_attached, config.bar_hard_limit_mm);
}

JointsDeg RunContext::move(const JointsDeg& target, bool bar_attached, double hard_limit_mm) {
  return move(std::vector<JointsDeg>{target}, bar_attached, hard_limit_mm);
}

JointsDeg RunContext::moveThrough(const std::vector<JointsDeg>& path) {
  return move(path, true, config.bar_hard_limit_mm);
}

JointsDeg RunContext::move(const std::vector<JointsDeg>& path, bool bar_attached,
                           double hard_limit_mm) {
  checkpoint();
  if (bar_attached) watchBar(hard_limit_mm);  // nothing starts with the bar already in fault
  // Believed detached, the reference is the median of the last readings, and a change counts
  // when two readings in a row show it: one glitch of a free bar is not an attached bar.
  struct Reference {
    std::optional<double>& slot;
    ~Reference() { slot.reset(); }
  } const reference{detached_reference_mm_};
  if (!bar_attached && last_reading_ && last_reading_->kind == drivers::BarLineKind::kReading) {
    detached_reference_mm_ = recentReadingMm();
    detached_ = DetachedChange{config.detached_change_mm};
  }
  return io
      .moveThrough(path,
                   [&] {
                     checkpoint();
                     if (bar_attached)
                       watchBar(hard_limit_mm);
                     else
                       watchDetached();
                     return false;
                   })
      .joints_deg;
}

RunContext::Moved RunContext::moveRecentring(const std::vector<JointsDeg>& path) {
  checkpoint();
  if (const auto d = watchBar()) return {io.where(), d};
  std::optional<double> past_soft;
  const CellIo::MoveOutcome out = io.moveThrough(path, [&] {
    checkpoint();
    past_soft = watchBar();
    return past_soft.has_value();
  });
  return {out.joints_deg, out.stopped ? past_soft : std::nullopt};
}

RunContext::Followed RunContext::moveWatchingForBar(const JointsDeg& target,
                                                    std::optional<double> reference_mm,
                                                    double wait_s) {
  Followed f;
  try {
    f.joints_deg = move(target, false);
  } catch (const DetachedBarMoved&) {
    f.followed = true;
    f.joints_deg = io.where();
  }
  forgetReading();
  spin(wait_s, false);
  const std::optional<double> now_mm = recentReadingMm();
  f.over_range = last_reading_ && last_reading_->kind == drivers::BarLineKind::kOverRange;
  f.change_mm = reference_mm && now_mm ? *now_mm - *reference_mm : 0;
  f.followed = f.followed || f.over_range || std::abs(f.change_mm) > config.detached_change_mm;
  return f;
}

void RunContext::clearWindow() {
  // Readings still queued from before (the run thread was late, e.g. on a loaded machine) may be
  // of the arm in motion: delivered now, they stay out of the window.
  io.poll(Clock::now());
  watchBar();  // what they say of the bar counts as any reading's does
  window_.clear();
}

RunContext::Measurement RunContext::measureHere(double window_s) {
  Measurement m;
  clearWindow();
  const Collecting collect(collecting_);
  m.bar_window_start = Clock::now();
  m.joints_deg = io.where();
  m.where_end = Clock::now();
  spinUntil(m.bar_window_start + fromSeconds(window_s), true);
  // The window may have passed while WHERE was answered: the bar is checked in any case.
  checkpoint();
  watchBar();
  const auto deadline = Clock::now() + fromSeconds(config.drivers.bar.stale_after_s);
  while (window_.empty() && Clock::now() < deadline) spin(0.02, true);
  if (window_.empty()) throw StopRun{StopRun::kFault, "no ball-bar reading to record"};
  double sum = 0, lo = window_.front(), hi = window_.front();
  for (double v : window_) {
    sum += v;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  m.deflection_mm = sum / static_cast<double>(window_.size());
  m.spread_mm = hi - lo;
  if (window_.size() > 1) {
    double squares = 0;
    for (double v : window_) squares += (v - m.deflection_mm) * (v - m.deflection_mm);
    m.noise_mm = std::sqrt(squares / static_cast<double>(window_.size() - 1));
  }
  m.readings = window_.size();
  return m;
}

// ------------------------------------------------------------------------ the operator

void RunContext::waitConfirm(RunDir& dir, const proto::Prompt& prompt,
                             const std::function<void(double)>& on_nudge) {
  const int shell = prompt.shell;
  // At a connect prompt the bar is off the robot: its reading now is the free bar's, which a
  // nudge request is compared with (RunController::nudge).
  const std::optional<double> free_mm =
      prompt.action == proto::PromptAction::kConnect ? recentReadingMm() : std::nullopt;
  const int seen = shared.with([&](RunData& d) {
    d.prompt = prompt;
    d.prompt_shell = shell;
    d.nudge_mm.reset();
    d.nudged_mm = 0;
    d.free_bar_mm = free_mm;
    return d.confirms;
  });
  setState(proto::RunState::kAwaitingConfirm, prompt.message);
  const json object = proto::toJson(prompt);
  dir.logEvent({{"event", "prompt"}, {"prompt", object}});
  publish(object, false);
  while (true) {
    checkpoint();
    std::optional<double> nudge;
    const bool confirmed = shared.with([&](RunData& d) {
      if (d.confirms != seen) {
        d.prompt.reset();
        return true;
      }
      nudge.swap(d.nudge_mm);
      return false;
    });
    if (confirmed) break;
    if (nudge && on_nudge) {
      on_nudge(*nudge);
      event(dir, {{"event", "nudged"}, {"shell", shell}, {"mm", *nudge}});
    }
    if (!io.poll(Clock::now() + std::chrono::milliseconds(20)))
      shared.waitFor(std::chrono::milliseconds(20));
  }
  dir.logEvent({{"event", "confirmed"}, {"shell", shell}});
}

void RunContext::waitDetach(RunDir& dir, int shell, const std::string& message) {
  bar_offset_mm_ = 0;
  const BarAttachment was = attachment();
  proto::Prompt prompt{proto::PromptAction::kDetach, shell, {}, {}, {}, message};
  if (was.ball > 0) {
    prompt.ball = was.ball;
    prompt.chuck = was.chuck;
    prompt.extension_mm = was.extension_mm;
  }
  waitConfirm(dir, prompt);
  setAttachment({});
  // The reading that moves are watched against (the bar believed detached) is one taken after
  // the detach, once the readings are steady: one from before it, or still in a buffer when the
  // operator confirmed, differs by the deflection the bar had while attached and would stop the
  // next move for nothing (seen under load in the faults test).
  forgetReading();
  std::optional<double> previous;
  const auto deadline = Clock::now() + fromSeconds(1.5);
  while (Clock::now() < deadline) {
    spin(0.1, false);
    if (!last_reading_ || last_reading_->kind != drivers::BarLineKind::kReading) continue;
    if (previous &&
        std::abs(last_reading_->value_mm - *previous) <= 0.2 * config.detached_change_mm)
      break;
    previous = last_reading_->value_mm;
  }
}

}  // namespace robocal::daemon

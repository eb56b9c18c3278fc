// robocal-cellsim: command-line options of the simulated cell (see cellsim.hpp, docs/drivers.md).
#include "cellsim.hpp"

#include <robocal/build_info.hpp>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

namespace {

constexpr const char* kHelp =
    R"(usage: robocal-cellsim --model TRUTH.json [options] | --version | --help

A simulated robot cell on two pseudo-terminals: a VAL II controller and a ball-bar reader.
Prints "val PATH", "bar PATH" (and "control PATH"), then "ready". Control commands, one per
line on the control socket or stdin: status | events | connect B1C2 [extension_mm=E] [bar_mm=L|here] |
connect none | estop | reset | fault garbage|drop [val] | fault noprobe [off] | fault loose [off] | fault error [TEXT] |
fault stall val|bar S | fault disconnect val|bar S | quit

  --model FILE               the true robot: a truth file (robocal simulate --truth-out; a
                             model file with an optional "realism" object)       required
  --realism R                ideal | typical | a realism file: overrides the truth file's
                             (docs/realism.md)                                 [the file's]
  --config FILE              drivers config: the dialects to speak               [defaults]
  --val-link PATH            symlink to the VAL II pty (replaced on reconnect)
  --bar-link PATH            symlink to the ball-bar reader pty
  --control PATH             unix socket for control commands
  --stdin-control            read control commands from stdin, replies on stdout
  --time-scale F             motion runs F times faster                           [1]
  --joint-speed-deg-s V      joint speed at SPEED 100                             [60]
  --speed PERCENT            monitor speed at start                               [50]
  --blend-deg B              a path program's blend at each via, degrees of the largest joint's
                             travel (an assumption: docs/cell-time.md); 0: no corner cut [2]
  --start-joints A,B,C,D,E,F joint readings at start, deg                  [0,45,-90,0,45,0]
  --quantum-deg Q            joint-reading quantisation                           [0.01]
  --noise-mm S               LVDT noise, standard deviation                       [0.001]
  --seed N                   random seed                                          [1]
  --connect B1C2|none        bar connection at start                              [none]
  --bar-mm L|here            bar length at zero deflection, without extension     [100]
  --extension-mm E           extension bar                                        [0]
  --range-mm R               LVDT travel each way; past it: over range, "broken"  [1.5]
Settling (docs/settling.md; an assumption, not a measurement; in cell time, --time-scale applies):
after each move the bar reads A exp(-t/tau) cos(2 pi f t) on top of the true length,
A = amplitude x tool travel / 100 mm, at most the maximum
  --settle-amplitude-mm-per-100mm A   0: no ringing                            [0.02]
  --settle-max-amplitude-mm M                                                  [0.1]
  --settle-time-constant-s TAU                                                 [0.3]
  --settle-frequency-hz F                                                      [8]
  --bar-mode polled|streamed override the config's bar.mode
  --stream-hz F              streamed readings per second                         [20]
  --val-no-echo              the controller does not echo what it is sent
  --val-eol crlf|cr|lf       the controller's line ending                         [crlf]
  --val-column-width N       WHERE column width                                   [10]
  --val-decimals N           WHERE decimals                                       [3]
  --val-hand                 WHERE prints a HAND column (--val-hand-blank: without value)
  --val-baud B, --bar-baud B the devices' baud rates; a driver at another sees garble [9600]
The controller's dialect is the config's val.dialect (val2, vplus, kawasaki-as); with two
prompts configured the second (VAL's "*") shows while a move runs.
  --val-sync-moves           DO MOVE's prompt comes back when the motion ends
  --val-completion-lines     "DO motion completed." when a move ends (kawasaki-as: always)
  --val-boot-question        just booted: asks "Load VAL from floppy (Y/N)?" until answered
Faults (0 = off):
  --bar-garbage-every N      garbage bytes in / a cut-off of every Nth bar line
  --bar-drop-every N         every Nth bar line is not sent
  --bar-stall-after N        after N bar lines, silence for --stall-s
  --val-garbage-every N      garbage bytes in the last line of every Nth reply with lines
  --val-drop-every N         the last line of every Nth reply with lines is lost
  --val-stall-after N        after N commands, the controller hangs for --stall-s
  --stall-s S                                                                     [2]
  --val-disconnect-after N   after N commands the controller's port goes away...
  --bar-disconnect-after N   after N lines the reader's port goes away...
  --reconnect-after-s S      ...and comes back (a new pty, the link updated)      [1]
  --val-error-on-command N   the Nth command gets an error reply                  
  --val-error-text TEXT                                          [Position out of range]
  --estop-on-move N          E-stop halfway through the Nth move
  --bar-no-probe             the reader reports NO PROBE
  --verbose                  log the controller's commands on stderr
)";

double number(const std::string& key, const std::string& v) {
  try {
    std::size_t used = 0;
    const double d = std::stod(v, &used);
    if (used != v.size()) throw std::invalid_argument("");
    return d;
  } catch (const std::exception&) {
    throw std::invalid_argument("--" + key + ": '" + v + "' is not a number");
  }
}

}  // namespace

int main(int argc, char** argv) {
  using robocal::cellsim::Options;
  Options o;
  try {
    std::map<std::string, std::string> v;
    const std::map<std::string, bool> known = {{"model", true},
                                               {"realism", true},
                                               {"config", true},
                                               {"val-link", true},
                                               {"bar-link", true},
                                               {"control", true},
                                               {"stdin-control", false},
                                               {"time-scale", true},
                                               {"joint-speed-deg-s", true},
                                               {"speed", true},
                                               {"blend-deg", true},
                                               {"start-joints", true},
                                               {"quantum-deg", true},
                                               {"noise-mm", true},
                                               {"seed", true},
                                               {"connect", true},
                                               {"bar-mm", true},
                                               {"extension-mm", true},
                                               {"range-mm", true},
                                               {"settle-amplitude-mm-per-100mm", true},
                                               {"settle-max-amplitude-mm", true},
                                               {"settle-time-constant-s", true},
                                               {"settle-frequency-hz", true},
                                               {"bar-mode", true},
                                               {"stream-hz", true},
                                               {"val-no-echo", false},
                                               {"val-eol", true},
                                               {"val-column-width", true},
                                               {"val-decimals", true},
                                               {"val-hand", false},
                                               {"val-hand-blank", false},
                                               {"val-baud", true},
                                               {"val-sync-moves", false},
                                               {"val-completion-lines", false},
                                               {"val-boot-question", false},
                                               {"bar-baud", true},
                                               {"bar-garbage-every", true},
                                               {"bar-drop-every", true},
                                               {"val-garbage-every", true},
                                               {"val-drop-every", true},
                                               {"bar-stall-after", true},
                                               {"val-stall-after", true},
                                               {"stall-s", true},
                                               {"val-disconnect-after", true},
                                               {"bar-disconnect-after", true},
                                               {"reconnect-after-s", true},
                                               {"val-error-on-command", true},
                                               {"val-error-text", true},
                                               {"estop-on-move", true},
                                               {"bar-no-probe", false},
                                               {"verbose", false},
                                               {"help", false},
                                               {"version", false}};
    for (int i = 1; i < argc; ++i) {
      std::string a = argv[i];
      if (a.rfind("--", 0) != 0) throw std::invalid_argument("unexpected argument '" + a + "'");
      a = a.substr(2);
      const auto k = known.find(a);
      if (k == known.end()) throw std::invalid_argument("unknown option --" + a);
      if (k->second) {
        if (i + 1 >= argc) throw std::invalid_argument("--" + a + " needs a value");
        v[a] = argv[++i];
      } else {
        v[a] = "1";
      }
    }
    if (v.count("help")) {
      std::fputs(kHelp, stdout);
      return 0;
    }
    if (v.count("version")) {
      std::printf("robocal-cellsim %s\n", robocal::build::kVersion);
      return 0;
    }
    const auto has = [&](const char* k) { return v.count(k) > 0; };
    const auto num = [&](const char* k, double fallback) {
      return has(k) ? number(k, v[k]) : fallback;
    };
    const auto count = [&](const char* k) { return static_cast<long>(num(k, 0)); };
    if (!has("model")) throw std::invalid_argument("--model is required (e.g. truth.json)");
    o.model_path = v["model"];
    if (has("realism")) o.realism = v["realism"];
    if (has("config")) o.config_path = v["config"];
    if (has("val-link")) o.val_link = v["val-link"];
    if (has("bar-link")) o.bar_link = v["bar-link"];
    if (has("control")) o.control_path = v["control"];
    o.stdin_control = has("stdin-control");
    o.time_scale = num("time-scale", o.time_scale);
    o.joint_speed_deg_s = num("joint-speed-deg-s", o.joint_speed_deg_s);
    o.speed_percent = num("speed", o.speed_percent);
    o.blend_deg = num("blend-deg", o.blend_deg);
    if (o.blend_deg < 0) throw std::invalid_argument("--blend-deg must not be negative");
    if (o.time_scale <= 0 || o.joint_speed_deg_s <= 0 || o.speed_percent <= 0 ||
        o.speed_percent > 100)
      throw std::invalid_argument(
          "--time-scale, --joint-speed-deg-s and --speed must be positive "
          "(speed at most 100)");
    if (has("start-joints")) {
      std::stringstream ss(v["start-joints"]);
      std::string item;
      int i = 0;
      while (std::getline(ss, item, ',')) {
        if (i >= 6) throw std::invalid_argument("--start-joints: give six angles");
        o.start_joints_deg[i++] = number("start-joints", item);
      }
      if (i != 6) throw std::invalid_argument("--start-joints: give six angles");
    }
    o.quantum_deg = num("quantum-deg", o.quantum_deg);
    o.noise_mm = num("noise-mm", o.noise_mm);
    o.seed = static_cast<unsigned long>(num("seed", 1));
    if (has("connect")) o.connection = v["connect"];
    if (has("bar-mm")) {
      if (v["bar-mm"] == "here")
        o.bar_here = true;
      else
        o.bar_mm = number("bar-mm", v["bar-mm"]);
    }
    o.extension_mm = num("extension-mm", o.extension_mm);
    o.range_mm = num("range-mm", o.range_mm);
    auto& settle = o.settling;
    settle.amplitude_mm_per_100mm =
        num("settle-amplitude-mm-per-100mm", settle.amplitude_mm_per_100mm);
    settle.max_amplitude_mm = num("settle-max-amplitude-mm", settle.max_amplitude_mm);
    settle.time_constant_s = num("settle-time-constant-s", settle.time_constant_s);
    settle.frequency_hz = num("settle-frequency-hz", settle.frequency_hz);
    if (settle.amplitude_mm_per_100mm < 0 || settle.max_amplitude_mm < 0)
      throw std::invalid_argument(
          "--settle-amplitude-mm-per-100mm and --settle-max-amplitude-mm must not be negative");
    if (settle.time_constant_s <= 0 || settle.frequency_hz < 0)
      throw std::invalid_argument(
          "--settle-time-constant-s must be positive, --settle-frequency-hz not negative");
    if (has("bar-mode")) o.bar_mode = v["bar-mode"];
    o.stream_hz = num("stream-hz", o.stream_hz);
    if (o.stream_hz <= 0) throw std::invalid_argument("--stream-hz must be positive");
    o.val_echo = !has("val-no-echo");
    o.val_sync_moves = has("val-sync-moves");
    o.val_completion_lines = has("val-completion-lines");
    o.val_boot_question = has("val-boot-question");
    if (has("val-eol")) {
      const std::string e = v["val-eol"];
      if (e == "crlf")
        o.val_eol = "\r\n";
      else if (e == "cr")
        o.val_eol = "\r";
      else if (e == "lf")
        o.val_eol = "\n";
      else
        throw std::invalid_argument("--val-eol: crlf, cr or lf");
    }
    o.where_layout.column_width = static_cast<int>(num("val-column-width", 10));
    o.where_layout.decimals = static_cast<int>(num("val-decimals", 3));
    o.where_layout.hand_column = has("val-hand") || has("val-hand-blank");
    o.where_layout.hand_blank = has("val-hand-blank");
    o.val_baud = static_cast<int>(num("val-baud", 9600));
    o.bar_baud = static_cast<int>(num("bar-baud", 9600));
    o.bar_garbage_every = count("bar-garbage-every");
    o.bar_drop_every = count("bar-drop-every");
    o.val_garbage_every = count("val-garbage-every");
    o.val_drop_every = count("val-drop-every");
    o.bar_stall_after = count("bar-stall-after");
    o.val_stall_after = count("val-stall-after");
    o.stall_s = num("stall-s", o.stall_s);
    o.val_disconnect_after = count("val-disconnect-after");
    o.bar_disconnect_after = count("bar-disconnect-after");
    o.reconnect_after_s = num("reconnect-after-s", o.reconnect_after_s);
    o.val_error_on_command = count("val-error-on-command");
    if (has("val-error-text")) o.val_error_text = v["val-error-text"];
    o.estop_on_move = count("estop-on-move");
    o.bar_no_probe = has("bar-no-probe");
    o.verbose = has("verbose");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "robocal-cellsim: %s (see --help)\n", e.what());
    return 2;
  }
  try {
    return robocal::cellsim::run(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "robocal-cellsim: error: %s\n", e.what());
    return 1;
  }
}

#include <robocal/drivers/diagnose.hpp>

#include <algorithm>

namespace robocal::drivers {

const char* verdictName(Verdict v) {
  switch (v) {
    case Verdict::kOk:
      return "ok";
    case Verdict::kNoPort:
      return "no port";
    case Verdict::kNoAnswer:
      return "no answer";
    case Verdict::kGarbled:
      return "garbled answer";
    case Verdict::kUnparseable:
      return "unparseable answer";
    case Verdict::kDeviceError:
      return "device error";
    case Verdict::kQuestion:
      return "controller asks a question";
  }
  return "?";
}

namespace {

std::string settings(const SerialConfig& s) {
  return std::to_string(s.baud) + " baud, " + std::to_string(s.data_bits) + " data bits, parity " +
         s.parity + ", " + std::to_string(s.stop_bits) + " stop bit(s), flow control " +
         s.flow_control;
}

std::string joinLines(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += "\n    " + l;
  return out;
}

// The controller waits for an answer: the operator gives it, never robocal.
Diagnosis asking(const std::string& port, const std::string& question,
                 const std::string& received) {
  return {Verdict::kQuestion,
          "The controller on " + port + " is asking \"" + question +
              "\" instead of showing its prompt: it has just been switched on, or a command "
              "(HERE, POINT) waits for an answer. Answer it on the controller's own terminal (or "
              "with `robocal term --val " +
              port + "`); robocal never answers a question for you. Then probe again.",
          received,
          {},
          {}};
}

}  // namespace

Diagnosis diagnoseVal(boost::asio::io_context& io, const ValConfig& config) {
  Diagnosis d;
  const ValDialect dialect(config);
  std::string port;
  // 1. The port, and whether anything answers an empty line with the prompt.
  {
    SerialLink link(io, config.serial);
    try {
      link.open();
    } catch (const PortError& e) {
      return {Verdict::kNoPort, e.what(), "", {}, {}};
    }
    port = link.describe();
    ValReplyCollector wake(dialect, "");
    const auto deadline = deadlineAfter(config.connect_timeout_s);
    try {
      link.write(config.send_line_ending, deadline);
      std::string chunk;
      // A tentative prompt ("*") ends the wake-up once the line has been quiet a moment.
      while (!wake.complete()) {
        const auto until =
            wake.tentative()
                ? std::min(deadline, Clock::now() + std::chrono::milliseconds(kPromptQuietMs))
                : deadline;
        if (!link.readSome(chunk, until)) {
          wake.quiet();
          break;
        }
        wake.feed(chunk);
        chunk.clear();
      }
    } catch (const DriverError& e) {
      return {Verdict::kNoPort, e.what(), "", {}, {}};
    }
    d.received = escapeBytes(wake.raw().substr(0, 200));
    if (!wake.question().empty()) return asking(port, wake.question(), d.received);
    if (!wake.complete()) {
      if (wake.raw().empty())
        return {Verdict::kNoAnswer,
                "Nothing came back from the controller on " + port + " within " +
                    formatFixed(config.connect_timeout_s, 1) +
                    " s. Check that the controller is switched on and shows its prompt (" +
                    dialect.describePrompts() +
                    ") on its own terminal, that the cable goes into its terminal (TTY) "
                    "port and is a null-modem cable, and that it runs at " +
                    settings(config.serial) + ".",
                "",
                {},
                {}};
      if (!looksLikeText(wake.raw()))
        return {Verdict::kGarbled,
                "The controller on " + port +
                    " sends characters back, but garbled: the baud rate or parity does not match "
                    "the controller (robocal uses " +
                    settings(config.serial) +
                    "). Set val.serial.baud to the controller's rate. Some USB-serial adapters "
                    "also garble these controllers: try another adapter.",
                d.received,
                {},
                {}};
      return {Verdict::kUnparseable,
              "The controller on " + port +
                  " answers, but never shows a prompt robocal waits for (" +
                  dialect.describePrompts() +
                  "). Add what it shows to val.prompt, or choose its val.dialect.",
              d.received,
              {},
              {}};
    }
  }
  // 2. WHERE through the driver.
  ValController val(io, config);
  std::vector<std::string> lines;
  try {
    val.connect();
    lines = val.command(config.where_command, config.where_timeout_s);
    d.where = parseWhere(lines, config);
  } catch (const QuestionError& e) {
    return asking(port, e.controllerMessage(), "");
  } catch (const ControllerError& e) {
    return {Verdict::kDeviceError,
            "The controller on " + port + " refused \"" + config.where_command +
                "\": " + e.controllerMessage() + ".",
            "",
            {},
            {}};
  } catch (const ProtocolError& e) {
    return {Verdict::kUnparseable,
            "The controller on " + port + " answered \"" + config.where_command +
                "\", but not in a form robocal reads: " + e.what() +
                ". Its answer:" + joinLines(lines) +
                "\nSet val.joint_headers (and val.location_headers) to the names it prints.",
            "",
            {},
            {}};
  } catch (const DriverError& e) {
    return {Verdict::kNoAnswer, e.what(), "", {}, {}};
  }
  d.verdict = Verdict::kOk;
  d.message = "The controller on " + port + " answers at " + settings(config.serial) + ".";
  return d;
}

Diagnosis diagnoseBar(boost::asio::io_context& io, const BarConfig& config, double listen_s,
                      const std::function<void(const BarReading&)>& on_reading) {
  Diagnosis d;
  BarReader bar(io, config);
  try {
    bar.connect();
  } catch (const PortError& e) {
    return {Verdict::kNoPort, e.what(), "", {}, {}};
  }
  const std::string port = bar.link().describe();
  const auto deadline = deadlineAfter(listen_s);
  try {
    do {
      const BarReading r = bar.read();
      d.reading = r;
      if (on_reading) on_reading(r);
    } while (Clock::now() < deadline);
  } catch (const StaleReadingError& e) {
    // Readable lines that do not fit the format point at the format; only non-text at the baud.
    const std::string& g = bar.stats().last_text_garbage.empty() ? bar.stats().last_garbage
                                                                 : bar.stats().last_text_garbage;
    if (d.reading) {
      return {Verdict::kNoAnswer,
              "The ball-bar reader on " + port + " gave readings, then stopped: " + e.what(),
              "",
              {},
              d.reading};
    }
    if (!g.empty() && !isPrintableText(g))
      return {Verdict::kGarbled,
              "The ball-bar reader on " + port +
                  " sends characters, but garbled: the baud rate or parity does not match the "
                  "reader (robocal uses " +
                  settings(config.serial) + "). Set bar.serial.baud to the reader's rate.",
              escapeBytes(g),
              {},
              {}};
    if (!g.empty())
      return {
          Verdict::kUnparseable,
          "The ball-bar reader on " + port + " sends \"" + g +
              "\", which does not match the configured line format (bar.format \"" + config.format +
              "\"" +
              (config.value_regex.empty() ? std::string("")
                                          : ", bar.value_regex \"" + config.value_regex + "\"") +
              "). Set bar.format or bar.value_regex to fit it.",
          g,
          {},
          {}};
    return {Verdict::kNoAnswer, std::string(e.what()), "", {}, {}};
  } catch (const DriverError& e) {
    return {Verdict::kNoPort, e.what(), "", {}, d.reading};
  }
  const BarReading& r = *d.reading;
  if (r.kind == BarLineKind::kNoProbe)
    return {Verdict::kDeviceError,
            "The ball-bar reader on " + port +
                " answers but reports no probe: plug the LVDT cable into the reader.",
            r.line,
            {},
            d.reading};
  if (r.kind == BarLineKind::kDeviceError)
    return {Verdict::kDeviceError,
            "The ball-bar reader on " + port + " answers with an error: \"" + r.line + "\".",
            r.line,
            {},
            d.reading};
  d.verdict = Verdict::kOk;
  d.message = "The ball-bar reader on " + port + " answers at " + settings(config.serial) +
              (config.mode == "polled" ? " (polled with \"" + config.poll_command + "\")"
                                       : std::string(" (streaming)")) +
              (r.kind == BarLineKind::kOverRange
                   ? "; it reads OVER RANGE: the bar is stretched or compressed past its travel"
                   : "") +
              ".";
  if (bar.stats().garbage_lines > 0)
    d.message += " " + std::to_string(bar.stats().garbage_lines) +
                 " line(s) could not be read and were skipped (last: \"" +
                 escapeBytes(bar.stats().last_garbage) + "\").";
  return d;
}

}  // namespace robocal::drivers

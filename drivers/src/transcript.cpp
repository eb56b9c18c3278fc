#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/transcript.hpp>

#include <nlohmann/json.hpp>

#include <stdexcept>

namespace robocal::drivers {

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

const char* kindName(ValErrorKind kind) {
  switch (kind) {
    case ValErrorKind::kPowerOff:
      return "power_off";
    case ValErrorKind::kOutOfRange:
      return "out_of_range";
    case ValErrorKind::kOther:
      break;
  }
  return "other";
}

std::string numbersText(const std::array<double, 6>& values) {
  std::string s;
  for (double v : values) {
    s.push_back(' ');
    s += formatFixed(v == 0 ? 0.0 : v, 3);  // no "-0.000"
  }
  return s;
}

ValReplyCollector collect(const ValDialect& dialect, const std::string& command,
                          const std::string& bytes, bool bytewise) {
  ValReplyCollector c(dialect, command);
  if (bytewise)
    for (char b : bytes) c.feed(std::string_view(&b, 1));
  else
    c.feed(bytes);
  c.quiet();  // the next command, or the end of the session: the line was quiet
  return c;
}

}  // namespace

nlohmann::json valDialectJson(const ValConfig& config) {
  nlohmann::json j = toJson(config);
  j.erase("serial");
  for (auto it = j.begin(); it != j.end();) {
    const std::string& key = it.key();
    if (endsWith(key, "_s") || endsWith(key, "_deg") || key == "still_polls" ||
        key == "where_retries")
      it = j.erase(it);
    else
      ++it;
  }
  return j;
}

std::vector<std::string> splitAfterLineEndings(std::string_view bytes) {
  std::vector<std::string> out;
  std::string piece;
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    piece.push_back(bytes[i]);
    const bool cr_alone = bytes[i] == '\r' && (i + 1 == bytes.size() || bytes[i + 1] != '\n');
    if (bytes[i] == '\n' || cr_alone) out.push_back(std::move(piece)), piece.clear();
  }
  if (!piece.empty()) out.push_back(std::move(piece));
  return out;
}

// ------------------------------------------------------------------------- TranscriptRecorder

TranscriptRecorder::TranscriptRecorder(ValConfig config, std::vector<std::string> header)
    : dialect_(std::move(config)), header_(std::move(header)) {}

void TranscriptRecorder::command(const std::string& text) {
  if (text.find_first_of("\r\n") != std::string::npos)
    throw std::invalid_argument("a transcript command holds a line ending: " + escapeBytes(text));
  entries_.push_back({true, text, ""});
  live_.reset();
  live_.emplace(dialect_, text);
}

// A reply ending in a tentative prompt ("*", which may also begin an error line) is over for the
// person typing; bytes that still come belong to it.
bool TranscriptRecorder::awaitingReply() const {
  return live_ && !live_->complete() && !live_->tentative();
}

void TranscriptRecorder::received(std::string_view bytes) {
  if (bytes.empty()) return;
  if (live_ && !live_->complete()) {
    entries_.back().bytes.append(bytes);
    live_->feed(bytes);
    return;
  }
  // The LF of a CR LF whose CR completed the last reply belongs to that reply.
  if (bytes.front() == '\n' && !entries_.empty() && entries_.back().exchange &&
      endsWith(entries_.back().bytes, "\r")) {
    entries_.back().bytes.push_back('\n');
    bytes.remove_prefix(1);
    if (bytes.empty()) return;
  }
  if (entries_.empty() || entries_.back().exchange) entries_.push_back({false, "", ""});
  entries_.back().bytes.append(bytes);
}

TranscriptRecorder::Verdict TranscriptRecorder::judge(const Entry& e) const {
  // The replayer's checks (tests/drivers/transcripts.cpp): complete whole and byte by byte, the
  // same lines both ways unless there were errors, errors both ways or neither.
  Verdict v;
  const ValReplyCollector whole = collect(dialect_, e.command, e.bytes, false);
  const ValReplyCollector bytes = collect(dialect_, e.command, e.bytes, true);
  if (!whole.complete() || !bytes.complete()) {
    v.reason = "no prompt (" + dialect_.describePrompts() +
               ") came back before the next command or the end of the session";
    return v;
  }
  if (whole.errors().empty() != bytes.errors().empty() ||
      (whole.errors().empty() && whole.lines() != bytes.lines())) {
    v.reason =
        "the reply reads differently one byte at a time (a line starting with the prompt?), so "
        "the driver may misread it: check val.prompt";
    return v;
  }
  v.replayable = true;
  if (!whole.errors().empty()) {
    const std::string& message = whole.errors().front();
    const char* kind = kindName(dialect_.classify(message));
    v.todo = "# TODO expectation: the controller said \"" + message +
             "\", which robocal reads as " + kind + ": check the kind\n";
    v.expected = std::string("! ") + kind;
    return v;
  }
  v.expected = "= lines " + std::to_string(whole.lines().size());
  const ValConfig& c = dialect_.config();
  if (toUpper(trim(e.command)) != toUpper(trim(c.where_command))) {
    v.todo = "# TODO expectation\n";
    return v;
  }
  try {
    const WhereReply w = parseWhere(whole.lines(), c);
    v.todo =
        "# TODO expectation: robocal reads the values below; check them against the "
        "controller's display, then add\n#   = joints" +
        numbersText(w.joints_deg) + "\n";
    if (w.location) v.todo += "#   = location" + numbersText(*w.location) + "\n";
  } catch (const ProtocolError& err) {
    v.todo = std::string("# TODO expectation: robocal cannot read this WHERE (") + err.what() +
             "): fix the val keys, or add \"! parse\"\n";
  }
  return v;
}

void TranscriptRecorder::write(const Entry& e, std::string& out) const {
  if (!e.exchange) {
    for (const auto& piece : splitAfterLineEndings(e.bytes))
      out += "# unsolicited: " + escapeBytes(piece) + "\n";
    return;
  }
  const Verdict v = judge(e);
  const std::string prefix = v.replayable ? "" : "# ";
  if (!v.replayable) out += "# not replayable: " + v.reason + "\n";
  out += prefix + (e.command.empty() ? ">" : "> " + e.command) + "\n";
  for (const auto& piece : splitAfterLineEndings(e.bytes))
    out += prefix + "< " + escapeBytes(piece) + "\n";
  if (v.replayable) out += v.todo + v.expected + "\n";
}

std::string TranscriptRecorder::text() const {
  std::string out;
  for (const auto& h : header_) out += h.empty() ? "#\n" : "# " + h + "\n";
  out +=
      "# Each exchange has what robocal's reply collector sees (= lines N, or ! and the error "
      "kind);\n# add what the controller meant under its TODO (= joints, = location, ! parse: "
      "tests/drivers/transcripts/README.md).\n";
  out += "@val " + valDialectJson(dialect_.config()).dump() + "\n";
  for (const auto& e : entries_) write(e, out);
  return out;
}

int TranscriptRecorder::replayableExchanges() const {
  int n = 0;
  for (const auto& e : entries_) n += e.exchange && judge(e).replayable;
  return n;
}

int TranscriptRecorder::unreplayableExchanges() const {
  int n = 0;
  for (const auto& e : entries_) n += e.exchange && !judge(e).replayable;
  return n;
}

// --------------------------------------------------------------------------------- ScreenText

std::string ScreenText::feed(std::string_view bytes) {
  std::string out;
  for (char c : bytes) {
    const bool lf_after_cr = c == '\n' && after_cr_;
    after_cr_ = c == '\r';
    if (lf_after_cr) continue;
    const auto u = static_cast<unsigned char>(c);
    if (c == '\r' || c == '\n')
      out.push_back('\n');
    else if (c == '\t' || (u >= 0x20 && u < 0x7f))
      out.push_back(c);
    else
      out += escapeBytes(std::string_view(&c, 1));
  }
  return out;
}

}  // namespace robocal::drivers

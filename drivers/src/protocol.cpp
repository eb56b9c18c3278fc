#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/protocol.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

namespace robocal::drivers {

// ---------------------------------------------------------------------------------------------
// Lines and text

void LineSplitter::feed(std::string_view bytes, std::vector<std::string>& lines) {
  for (char c : bytes) {
    if (c == '\n') {
      if (after_cr_) {  // second half of a CR LF
        after_cr_ = false;
        continue;
      }
      lines.push_back(std::move(pending_));
      pending_.clear();
    } else if (c == '\r') {
      lines.push_back(std::move(pending_));
      pending_.clear();
      after_cr_ = true;
      continue;
    } else {
      pending_.push_back(c);
    }
    after_cr_ = false;
  }
}

std::string LineSplitter::takePending() {
  std::string out = std::move(pending_);
  pending_.clear();
  return out;
}

void LineSplitter::clear() {
  pending_.clear();
  after_cr_ = false;
}

std::string trim(std::string_view text) {
  const auto space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  std::size_t b = 0, e = text.size();
  while (b < e && space(text[b])) ++b;
  while (e > b && space(text[e - 1])) --e;
  return std::string(text.substr(b, e - b));
}

std::string toUpper(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

bool isPrintableText(std::string_view text) {
  return std::all_of(text.begin(), text.end(), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return (u >= 0x20 && u < 0x7f) || u == '\t';
  });
}

bool looksLikeText(std::string_view bytes) {
  std::string without_endings;
  for (char c : bytes)
    if (c != '\r' && c != '\n') without_endings.push_back(c);
  return isPrintableText(without_endings);
}

std::string escapeBytes(std::string_view bytes) {
  std::string out;
  for (char c : bytes) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '\r')
      out += "\\r";
    else if (c == '\n')
      out += "\\n";
    else if (c == '\t')
      out += "\\t";
    else if (c == '\\')
      out += "\\\\";
    else if (u < 0x20 || u >= 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02X", u);
      out += buf;
    } else
      out.push_back(c);
  }
  return out;
}

std::string unescapeBytes(std::string_view text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '\\' || i + 1 >= text.size()) {
      out.push_back(text[i]);
      continue;
    }
    const char n = text[++i];
    if (n == 'r')
      out.push_back('\r');
    else if (n == 'n')
      out.push_back('\n');
    else if (n == 't')
      out.push_back('\t');
    else if (n == '\\')
      out.push_back('\\');
    else if (n == 'x' && i + 2 < text.size()) {
      const std::string hex(text.substr(i + 1, 2));
      out.push_back(static_cast<char>(std::strtol(hex.c_str(), nullptr, 16)));
      i += 2;
    } else {
      out.push_back('\\');
      out.push_back(n);
    }
  }
  return out;
}

std::optional<double> parseNumber(std::string_view token) {
  if (token.empty() || token.size() > 64) return std::nullopt;
  const std::string s(token);
  // Only plain decimals: sign, digits, one point (no hex, inf, nan or exponents).
  std::size_t i = (s[0] == '+' || s[0] == '-') ? 1 : 0;
  bool digit = false, point = false;
  for (; i < s.size(); ++i) {
    if (std::isdigit(static_cast<unsigned char>(s[i])))
      digit = true;
    else if (s[i] == '.' && !point)
      point = true;
    else
      return std::nullopt;
  }
  if (!digit) return std::nullopt;
  return std::strtod(s.c_str(), nullptr);
}

double maxJointDiffDeg(const Joints6& a, const Joints6& b) {
  double m = 0;
  for (int i = 0; i < 6; ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}

std::string formatFixed(double value, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  std::string s = buf;
  // "-0.000" reads badly and some controllers reject it.
  if (s.find_first_not_of("-0.") == std::string::npos && s[0] == '-') s.erase(0, 1);
  return s;
}

// ---------------------------------------------------------------------------------------------
// Templates

std::vector<std::string> templateFields(const std::string& text) {
  std::vector<std::string> fields;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '}') throw ProtocolError("a '}' without its '{' in \"" + text + "\"", text);
    if (text[i] != '{') continue;
    const std::size_t close = text.find('}', i);
    if (close == std::string::npos)
      throw ProtocolError("a '{' without its '}' in \"" + text + "\"", text);
    const std::string name = text.substr(i + 1, close - i - 1);
    if (name.empty()) throw ProtocolError("an empty field {} in \"" + text + "\"", text);
    fields.push_back(name);
    i = close;
  }
  return fields;
}

std::string expandTemplate(const std::string& text,
                           const std::map<std::string, std::string>& fields) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '{') {
      out.push_back(text[i]);
      continue;
    }
    const std::size_t close = text.find('}', i);
    const std::string name = text.substr(i + 1, close - i - 1);
    const auto it = fields.find(name);
    if (it == fields.end())
      throw ProtocolError("no value for the field {" + name + "} of \"" + text + "\"", text);
    out += it->second;
    i = close;
  }
  return out;
}

std::regex templateRegex(const std::string& text, std::vector<std::string>& fields) {
  fields.clear();
  std::string re = R"(^\s*)";
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '{') {
      const std::size_t close = text.find('}', i);
      fields.push_back(text.substr(i + 1, close - i - 1));
      re += R"(\s*([+-]?\d*\.?\d+|[+-]?\d+\.)\s*)";
      i = close;
    } else if (c == ' ') {
      re += R"(\s+)";
      while (i + 1 < text.size() && text[i + 1] == ' ') ++i;
    } else if (std::isalnum(static_cast<unsigned char>(c))) {
      re.push_back(c);
    } else {
      re += '\\';
      re.push_back(c);
    }
  }
  re += R"(\s*$)";
  return std::regex(re, std::regex::ECMAScript | std::regex::icase);
}

// ---------------------------------------------------------------------------------------------
// VAL II

namespace {
std::regex compile(const std::string& pattern, bool icase, const std::string& key) {
  try {
    auto flags = std::regex::ECMAScript;
    if (icase) flags |= std::regex::icase;
    return std::regex(pattern, flags);
  } catch (const std::regex_error& e) {
    throw ConfigError(key + ": not a valid regular expression (" + e.what() + ")");
  }
}
}  // namespace

ValDialect::ValDialect(ValConfig config)
    : config_(std::move(config)),
      error_re_(compile(config_.error_regex, false, "val.error_regex")),
      power_off_re_(compile(config_.power_off_regex, true, "val.power_off_regex")),
      out_of_range_re_(compile(config_.out_of_range_regex, true, "val.out_of_range_regex")),
      ignore_re_(compile(config_.ignore_regex, true, "val.ignore_regex")),
      question_re_(compile(config_.question_regex, false, "val.question_regex")) {}

namespace {
// {j1}..{j6} of a command template, at the configured decimals.
std::map<std::string, std::string> jointFields(const Joints6& j, int decimals) {
  std::map<std::string, std::string> fields;
  for (int i = 0; i < 6; ++i) fields["j" + std::to_string(i + 1)] = formatFixed(j[i], decimals);
  return fields;
}
}  // namespace

std::string ValDialect::moveCommand(const Joints6& j) const {
  return expandTemplate(config_.move_joints_command, jointFields(j, config_.joint_decimals));
}

std::vector<std::string> ValDialect::pathCommands(const std::vector<Joints6>& steps) const {
  if (config_.path_execute_command.empty()) return {};
  std::vector<std::string> lines{config_.path_edit_command};
  for (const Joints6& j : steps)
    lines.push_back(expandTemplate(config_.path_move_line, jointFields(j, config_.joint_decimals)));
  lines.push_back(config_.path_end_edit);
  lines.push_back(config_.path_execute_command);
  return lines;
}

std::string ValDialect::speedCommand(double percent) const {
  std::string s = formatFixed(percent, 2);
  while (s.find('.') != std::string::npos && (s.back() == '0' || s.back() == '.')) {
    const bool dot = s.back() == '.';
    s.pop_back();
    if (dot) break;
  }
  return expandTemplate(config_.speed_command, {{"speed", s}});
}

std::optional<std::string> ValDialect::errorMessage(const std::string& line) const {
  if (line.size() > kMaxRegexLineBytes) return std::nullopt;
  std::smatch m;
  if (!std::regex_match(line, m, error_re_)) return std::nullopt;
  std::string msg = trim(m[1].str());
  if (msg.empty()) msg = trim(line);
  return msg;
}

ValErrorKind ValDialect::classify(const std::string& message) const {
  if (std::regex_search(message, power_off_re_)) return ValErrorKind::kPowerOff;
  if (std::regex_search(message, out_of_range_re_)) return ValErrorKind::kOutOfRange;
  return ValErrorKind::kOther;
}

const std::string& ValDialect::mostSevere(const std::vector<std::string>& messages) const {
  const std::string* best = &messages.front();
  for (const auto& m : messages)
    if (classify(m) < classify(*best)) best = &m;
  return *best;
}

void ValDialect::throwError(const std::string& command, const std::string& message) const {
  const std::string what = "the controller refused \"" + command + "\": " + message;
  switch (classify(message)) {
    case ValErrorKind::kPowerOff:
      throw ArmPowerOffError(what + " (arm power is off: E-stop pressed or power not enabled)",
                             message);
    case ValErrorKind::kOutOfRange:
      throw OutOfRangeError(what + " (target outside the arm's reach or joint limits)", message);
    case ValErrorKind::kOther:
      break;
  }
  throw ControllerError(what, message);
}

bool ValDialect::isPrompt(std::string_view text) const {
  const std::string t = trim(text);
  for (const auto& p : config_.prompt)
    if (t == trim(p)) return true;
  return false;
}

bool ValDialect::isPromptThen(const std::string& line, const std::string& rest) const {
  const std::string t = trim(line);
  for (const auto& p : config_.prompt) {
    const std::string prompt = trim(p);
    if (t.size() > prompt.size() && t.compare(0, prompt.size(), prompt) == 0 &&
        trim(t.substr(prompt.size())) == rest)
      return true;
  }
  return false;
}

bool ValDialect::couldStartError(std::string_view prompt) const {
  return std::regex_match(trim(prompt) + "Arm power off", error_re_);
}

bool ValDialect::isIgnored(const std::string& line) const {
  return !config_.ignore_regex.empty() && line.size() <= kMaxRegexLineBytes &&
         std::regex_search(line, ignore_re_);
}

bool ValDialect::isQuestion(std::string_view text) const {
  const std::string t = trim(text);
  return !t.empty() && t.size() <= kMaxRegexLineBytes && !isPrompt(t) &&
         std::regex_search(t, question_re_);
}

std::string ValDialect::describePrompts() const {
  std::string out;
  for (const auto& p : config_.prompt) out += (out.empty() ? "'" : " or '") + p + "'";
  return out;
}

std::string ValDialect::formatError(const std::string& message) {
  return "*" + message + "*";
}

ValReplyCollector::ValReplyCollector(const ValDialect& dialect, std::string command)
    : dialect_(dialect), command_(toUpper(trim(command))) {}

bool ValReplyCollector::feed(std::string_view bytes) {
  raw_.append(bytes);
  std::vector<std::string> got;
  splitter_.feed(bytes, got);
  for (const auto& l : got) {
    if (complete_) {
      rest_ += l + "\n";
      continue;
    }
    ++line_endings_;
    line(l);
  }
  if (complete_ && !got.empty()) {
    rest_ += splitter_.pending();
    splitter_.clear();
  }
  // A prompt without a line ending ends the reply once a line has ended since the command was
  // sent: before that it may be the prompt the controller echoes in front of the command.
  tentative_ = false;
  if (!complete_ && (line_endings_ > 0 || command_.empty()) &&
      dialect_.isPrompt(splitter_.pending())) {
    prompt_ = trim(splitter_.pending());
    if (dialect_.couldStartError(prompt_))
      tentative_ = true;  // "*" now, "*Arm power off*" a byte later?
    else
      complete_ = true;
  }
  // A question waits for an answer with no line ending after it; nothing else will come.
  if (!complete_ && dialect_.isQuestion(splitter_.pending())) {
    question_ = trim(splitter_.pending());
    complete_ = true;
  }
  return complete_;
}

bool ValReplyCollector::quiet() {
  if (tentative_) {
    complete_ = true;
    tentative_ = false;
  }
  return complete_;
}

void ValReplyCollector::line(const std::string& text) {
  std::string t = trim(text);
  if (t.empty()) return;
  if (dialect_.isPrompt(t)) {
    // A prompt alone on a line ends the reply unless it is the very first line: that is the
    // previous command's prompt (a controller that ends its prompt with a line ending).
    if (echo_seen_ || line_endings_ > 1 || command_.empty()) {
      prompt_ = t;
      complete_ = true;
    }
    return;
  }
  if (!echo_seen_) {
    const std::string u = toUpper(t);
    if (u == command_ || dialect_.isPromptThen(u, command_)) {
      echo_seen_ = true;
      return;
    }
  }
  if (dialect_.isIgnored(t)) {
    ++ignored_;
    return;
  }
  if (auto msg = dialect_.errorMessage(t)) {
    errors_.push_back(*msg);
    return;
  }
  lines_.push_back(t);
}

namespace {

struct Token {
  std::string text;
  double centre;
};

std::vector<Token> tokens(const std::string& line) {
  std::vector<Token> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const std::size_t b = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > b) out.push_back({line.substr(b, i - b), 0.5 * static_cast<double>(b + i - 1)});
  }
  return out;
}

int indexOf(const std::vector<Token>& toks, const std::string& name) {
  for (std::size_t i = 0; i < toks.size(); ++i)
    if (toUpper(toks[i].text) == toUpper(name)) return static_cast<int>(i);
  return -1;
}

// Values of the named columns, read from the first non-empty line after the header.
std::optional<std::array<double, 6>> readBlock(const std::vector<std::string>& lines,
                                               const std::vector<std::string>& names,
                                               const char* what, bool required) {
  for (std::size_t h = 0; h < lines.size(); ++h) {
    const auto head = tokens(lines[h]);
    std::array<int, 6> col{};
    bool all = true;
    for (int k = 0; k < 6; ++k) all = all && (col[k] = indexOf(head, names[k])) >= 0;
    if (!all) continue;
    std::size_t v = h + 1;
    while (v < lines.size() && trim(lines[v]).empty()) ++v;
    if (v >= lines.size()) {
      if (!required) return std::nullopt;
      throw ProtocolError(std::string("the WHERE reply has the ") + what +
                              " header but no line of numbers under it",
                          lines[h]);
    }
    const auto vals = tokens(lines[v]);
    // Which header each value belongs to: by position when the counts agree, otherwise to the
    // header whose column centre is nearest (a blank HAND column, for instance).
    std::vector<int> owner(vals.size());
    for (std::size_t i = 0; i < vals.size(); ++i) {
      if (vals.size() == head.size()) {
        owner[i] = static_cast<int>(i);
        continue;
      }
      double best = std::numeric_limits<double>::max();
      for (std::size_t k = 0; k < head.size(); ++k) {
        const double d = std::abs(head[k].centre - vals[i].centre);
        if (d < best) best = d, owner[i] = static_cast<int>(k);
      }
    }
    std::array<double, 6> out{};
    for (int k = 0; k < 6; ++k) {
      int found = -1;
      for (std::size_t i = 0; i < vals.size(); ++i)
        if (owner[i] == col[k]) {
          if (found >= 0)
            throw ProtocolError(std::string("the WHERE reply's ") + what +
                                    " line has two values under " + names[k] + ": " + lines[v],
                                lines[v]);
          found = static_cast<int>(i);
        }
      if (found < 0) {
        if (!required) return std::nullopt;
        throw ProtocolError(std::string("the WHERE reply's ") + what + " line has no value under " +
                                names[k] + ": \"" + lines[v] + "\"",
                            lines[v]);
      }
      const auto num = parseNumber(vals[found].text);
      if (!num) {
        if (!required) return std::nullopt;
        throw ProtocolError(std::string("the WHERE reply's ") + what + " value under " + names[k] +
                                " is not a number: \"" + vals[found].text + "\"",
                            lines[v]);
      }
      out[k] = *num;
    }
    return out;
  }
  if (!required) return std::nullopt;
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : " ") + n;
  throw ProtocolError(std::string("the WHERE reply has no ") + what + " header line naming " + list,
                      "");
}

}  // namespace

WhereReply parseWhere(const std::vector<std::string>& lines, const ValConfig& config) {
  WhereReply r;
  r.joints_deg = *readBlock(lines, config.joint_headers, "joint", true);
  r.location = readBlock(lines, config.location_headers, "location", false);
  return r;
}

std::vector<std::string> formatWhere(const ValConfig& config, const WhereLayout& layout,
                                     const Location6& location, const Joints6& joints) {
  const auto cell = [&](const std::string& s) {
    std::string out(static_cast<std::size_t>(std::max(1, layout.column_width - int(s.size()))),
                    ' ');
    return out + s;
  };
  std::string h1, v1, h2, v2;  // location block, joint block
  for (int k = 0; k < 6; ++k) {
    h1 += cell(config.location_headers[k]);
    v1 += cell(formatFixed(location[k], layout.decimals));
    h2 += cell(config.joint_headers[k]);
    v2 += cell(formatFixed(joints[k], layout.decimals));
  }
  if (layout.hand_column) {
    h1 += cell("HAND");
    if (!layout.hand_blank) v1 += cell(formatFixed(0, layout.decimals));
  }
  if (layout.joints_first) return {h2, v2, h1, v1};
  return {h1, v1, h2, v2};
}

// ---------------------------------------------------------------------------------------------
// Bar

const char* barLineKindName(BarLineKind kind) {
  switch (kind) {
    case BarLineKind::kReading:
      return "reading";
    case BarLineKind::kOverRange:
      return "over range";
    case BarLineKind::kNoProbe:
      return "no probe";
    case BarLineKind::kDeviceError:
      return "device error";
    case BarLineKind::kGarbage:
      return "garbage";
  }
  return "?";
}

BarDialect::BarDialect(BarConfig config)
    : config_(std::move(config)),
      value_re_(compile(
          config_.value_regex.empty() ? barPresetRegex(config_.format) : config_.value_regex,
          config_.ignore_case, "bar.value_regex")),
      over_range_re_(
          compile(config_.over_range_regex, config_.ignore_case, "bar.over_range_regex")),
      no_probe_re_(compile(config_.no_probe_regex, config_.ignore_case, "bar.no_probe_regex")),
      error_re_(compile(config_.error_regex, config_.ignore_case, "bar.error_regex")) {}

BarLine BarDialect::parse(const std::string& line) const {
  BarLine out;
  if (line.size() > kMaxRegexLineBytes || !isPrintableText(line) || trim(line).empty()) return out;
  std::smatch m;
  if (std::regex_search(line, no_probe_re_)) {
    out.kind = BarLineKind::kNoProbe;
  } else if (std::regex_search(line, over_range_re_)) {
    out.kind = BarLineKind::kOverRange;
  } else if (std::regex_search(line, error_re_)) {
    out.kind = BarLineKind::kDeviceError;
  } else if (std::regex_match(line, m, value_re_) && m.size() > 1) {
    const auto v = parseNumber(trim(m[1].str()));
    if (!v) return out;
    out.value_mm = *v * config_.unit_scale_mm;
    out.kind = (config_.range_mm > 0 && std::abs(out.value_mm) > config_.range_mm)
                   ? BarLineKind::kOverRange
                   : BarLineKind::kReading;
  }
  return out;
}

std::string formatBarReading(const std::string& format, double value) {
  char buf[64];
  if (format == "mitutoyo")
    std::snprintf(buf, sizeof buf, "01A%+09.4f", value);
  else if (format == "gn")
    std::snprintf(buf, sizeof buf, "GN01,%+010.4f", value);
  else
    std::snprintf(buf, sizeof buf, "%+.5f MM", value);
  return buf;
}

std::string formatBarStatus(BarLineKind kind, bool under) {
  switch (kind) {
    case BarLineKind::kOverRange:
      return under ? "UNDER RANGE" : "OVER RANGE";
    case BarLineKind::kNoProbe:
      return "NO PROBE";
    case BarLineKind::kDeviceError:
      return "ERR 1";
    default:
      return "";
  }
}

}  // namespace robocal::drivers

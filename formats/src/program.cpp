#include <robocal/formats/csv.hpp>
#include <robocal/formats/program.hpp>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <map>
#include <set>

namespace robocal {
namespace {

bool isNameChar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.';
}

std::string upper(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

// The line without its ending (and without a Ctrl-Z that ends the file).
std::string_view content(const std::string& line) {
  std::string_view v(line);
  while (!v.empty() && (v.back() == '\n' || v.back() == '\r' || v.back() == '\x1a'))
    v.remove_suffix(1);
  return v;
}

// The code of a line: up to its ';' comment.
std::string_view code(std::string_view line) {
  return line.substr(0, std::min(line.size(), line.find(';')));
}

struct Token {
  std::size_t begin, end;
};

std::vector<Token> tokens(std::string_view s, std::string_view separators) {
  std::vector<Token> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && separators.find(s[i]) != std::string_view::npos) ++i;
    const std::size_t b = i;
    while (i < s.size() && separators.find(s[i]) == std::string_view::npos) ++i;
    if (i > b) out.push_back({b, i});
  }
  return out;
}

// The first six numbers of `list` (at `offset` in the line), separated by `separators`; nullopt
// when fewer than six or one is not a number.
std::optional<ProgramLocation> sixValues(std::string_view list, std::size_t offset,
                                         std::string_view separators) {
  const auto t = tokens(list, separators);
  if (t.size() < kJointCount) return std::nullopt;
  ProgramLocation loc;
  for (int k = 0; k < kJointCount; ++k) {
    const auto v = csv::number(list.substr(t[k].begin, t[k].end - t[k].begin));
    if (!v) return std::nullopt;
    loc.joints_deg[k] = *v;
  }
  loc.begin = offset + t[0].begin;
  loc.end = offset + t[kJointCount - 1].end;
  return loc;
}

}  // namespace

std::optional<ProgramDialect> parseProgramDialect(const std::string& word) {
  if (word == "val2") return ProgramDialect::kVal2;
  if (word == "vplus") return ProgramDialect::kVplus;
  if (word == "as") return ProgramDialect::kAs;
  return std::nullopt;
}

const char* programDialectName(ProgramDialect dialect) {
  switch (dialect) {
    case ProgramDialect::kVal2:
      return "VAL II";
    case ProgramDialect::kVplus:
      return "V+";
    case ProgramDialect::kAs:
      return "Kawasaki AS";
  }
  return "?";
}

ProgramFile parseProgram(const std::string& text, ProgramDialect dialect,
                         const std::string& source) {
  ProgramFile file;
  file.dialect = dialect;
  file.source = source;
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t nl = text.find('\n', at);
    const std::size_t end = nl == std::string::npos ? text.size() : nl + 1;
    file.lines.push_back(text.substr(at, end - at));
    at = end;
  }
  const bool as = dialect == ProgramDialect::kAs;
  const std::string location_block = as ? ".JOINTS" : ".LOCATIONS";
  const std::string foreign_block = as ? ".LOCATIONS" : ".JOINTS";
  const std::string literal_open = as ? "#[" : "#PPOINT(";
  const std::string foreign_literal = as ? "#PPOINT(" : "#[";
  const char literal_close = as ? ']' : ')';
  std::string block;  // the block a line is in ("" outside any)
  std::vector<ProgramReference> references;
  std::set<std::string> defined;
  for (std::size_t i = 0; i < file.lines.size(); ++i) {
    const int line_no = static_cast<int>(i) + 1;
    const std::string where = source + ":" + std::to_string(line_no) + ": ";
    const std::string_view line = content(file.lines[i]);
    const std::string_view c = code(line);
    const auto words = tokens(c, " \t");
    if (words.empty()) continue;
    const std::string first = upper(c.substr(words[0].begin, words[0].end - words[0].begin));
    if (first[0] == '.') {
      if (first == foreign_block)
        throw FormatError(where + first + " is a " + (as ? "V+ or VAL II" : "Kawasaki AS") +
                          " location block: this file is not " + programDialectName(dialect) +
                          " (--dialect)");
      block = first == ".END" ? "" : first;
      continue;
    }
    if (block == location_block) {
      if (first[0] != '#') continue;  // a transformation (x y z o a t): not a joint location
      ProgramLocation loc;
      std::optional<ProgramLocation> values;
      if (first.size() > 1) values = sixValues(c.substr(words[0].end), words[0].end, " \t");
      if (!values)
        throw FormatError(where + "a location line is '#name' and six joint values (deg), got '" +
                          std::string(line) + "'");
      loc = *values;
      loc.name = std::string(c.substr(words[0].begin, words[0].end - words[0].begin));
      loc.line = line_no;
      if (!defined.insert(loc.name).second)
        throw FormatError(where + "location " + loc.name + " is defined twice");
      file.locations.push_back(loc);
      continue;
    }
    if (!block.empty() && block != ".PROGRAM") continue;  // other data blocks are not ours
    const std::string code_upper = upper(c);
    if (const auto f = code_upper.find(foreign_literal); f != std::string::npos)
      throw FormatError(where + std::string(c.substr(f, foreign_literal.size())) + " is " +
                        (as ? "V+ or VAL II" : "Kawasaki AS") + " syntax: this file is not " +
                        programDialectName(dialect) + " (--dialect)");
    for (std::size_t h = c.find('#'); h != std::string_view::npos; h = c.find('#', h + 1)) {
      if (code_upper.compare(h, literal_open.size(), literal_open) == 0) {
        const std::size_t open = h + literal_open.size();
        const std::size_t close = c.find(literal_close, open);
        std::optional<ProgramLocation> values;
        if (close != std::string_view::npos)
          values = sixValues(c.substr(open, close - open), open, ", \t");
        if (!values)
          throw FormatError(where + "a joint literal " + literal_open + "..." + literal_close +
                            " holds six joint values (deg): '" + std::string(line) + "'");
        ProgramLocation loc = *values;
        loc.name = std::string(c.substr(h, close + 1 - h));
        loc.line = line_no;
        loc.literal = true;
        file.locations.push_back(loc);
        h = close;
        continue;
      }
      // A reference: # and a name that starts with a letter (`.PROGRAM p() #9744` is no name).
      std::size_t e = h + 1;
      if (e >= c.size() || !std::isalpha(static_cast<unsigned char>(c[e]))) continue;
      while (e < c.size() && isNameChar(c[e])) ++e;
      if (e < c.size() && c[e] == '[') e = std::min(c.size(), c.find(']', e) + 1);
      references.push_back({std::string(c.substr(h, e - h)), line_no});
    }
  }
  for (const ProgramReference& r : references)
    if (!defined.count(r.name)) file.undefined.push_back(r);
  return file;
}

std::string rewriteProgram(const ProgramFile& file,
                           const std::vector<std::optional<JointsDeg>>& corrected) {
  if (corrected.size() != file.locations.size())
    throw std::invalid_argument("rewriteProgram: one corrected value per location");
  std::vector<std::string> lines = file.lines;
  // Right to left within a line, so that the earlier positions stay valid.
  std::vector<std::size_t> order(file.locations.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const ProgramLocation &x = file.locations[a], &y = file.locations[b];
    return x.line != y.line ? x.line < y.line : x.begin > y.begin;
  });
  for (std::size_t k : order) {
    if (!corrected[k]) continue;
    const ProgramLocation& loc = file.locations[k];
    std::string values;
    char buf[32];
    for (int j = 0; j < kJointCount; ++j) {
      std::snprintf(buf, sizeof buf, "%.6f", (*corrected[k])[j]);
      values += (j ? (loc.literal ? "," : " ") : "") + std::string(buf);
    }
    lines[static_cast<std::size_t>(loc.line - 1)].replace(loc.begin, loc.end - loc.begin, values);
  }
  std::string out;
  for (const std::string& l : lines) out += l;
  return out;
}

}  // namespace robocal

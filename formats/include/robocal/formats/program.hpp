// Controller program files, read and rewritten with corrected joint locations
// (docs/programs.md): everything but the numbers of a location stays byte for byte. No I/O.
//
// What each dialect's grammar rests on (docs/programs.md has the sources; "guessed" means no public
// file showed it):
// - Kawasaki AS (seen in public backup files): blocks `.KEYWORD` ... `.END`; programs
//   `.PROGRAM name(...)`; joint locations in the `.JOINTS` block, one per line,
//   `#name v1 v2 ... vn` (6 values, or more with external axes: those after the sixth are kept as
//   they are); joint literals `#[v1,v2,...]` inside program lines; `;` starts a comment.
// - Adept/Staubli V+ and Unimation VAL II (guessed from V+'s manual and the AS heir): programs
//   `.PROGRAM` ... `.END`; precision points `#name v1 ... v6` in a `.LOCATIONS` block (its lines
//   without `#`, transformations, are kept as they are); literals
//   `#PPOINT(v1, ..., v6)` inside program lines; `;` comments.
// Values are degrees. A rewritten location keeps its name and the separators before it; its six
// joint values are written with 6 decimals, single-space (section lines) or comma (literals)
// separated. Line endings (LF or CR LF) and a trailing Ctrl-Z are kept.
//
// Errors (FormatError, with source:line): a file of another dialect (an AS `.JOINTS` block given
// as V+, a `.LOCATIONS` block or `#PPOINT` given as AS), a location line that is not a name and at
// least six numbers, a location defined twice. A location a program line uses but the file does
// not define is not an error of the file: it is listed (undefined) so the caller can name it and
// still write the rest.
#pragma once

#include <robocal/formats/error.hpp>
#include <robocal/kinematics/model.hpp>

#include <optional>
#include <string>
#include <vector>

namespace robocal {

enum class ProgramDialect { kVal2, kVplus, kAs };
// "val2", "vplus", "as"; nullopt for another word.
std::optional<ProgramDialect> parseProgramDialect(const std::string& word);
const char* programDialectName(ProgramDialect dialect);

struct ProgramLocation {
  std::string name;  // "#p1", or "#[...]" / "#PPOINT(...)" for a literal
  int line = 0;      // 1-based
  JointsDeg joints_deg = JointsDeg::Zero();
  bool literal = false;  // a joint literal inside a program line
  // Where its six values are in the line: [begin, end) of the text they replace.
  std::size_t begin = 0, end = 0;
};

struct ProgramReference {
  std::string name;  // "#p1"
  int line = 0;
};

struct ProgramFile {
  ProgramDialect dialect = ProgramDialect::kAs;
  std::string source;
  std::vector<std::string> lines;  // each with its line ending ("\n", "\r\n", or none at the end)
  std::vector<ProgramLocation> locations;
  std::vector<ProgramReference> undefined;  // used by a program line, defined nowhere
};

ProgramFile parseProgram(const std::string& text, ProgramDialect dialect,
                         const std::string& source = "program");

// The file with location k's joints replaced by corrected[k] where it has a value (nullopt: the
// location's line is kept as it was). corrected.size() must be locations.size().
std::string rewriteProgram(const ProgramFile& file,
                           const std::vector<std::optional<JointsDeg>>& corrected);

}  // namespace robocal

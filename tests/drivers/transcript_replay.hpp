// The transcript replayer of tests/drivers/transcripts.cpp, for other tests: replays a transcript's
// text (format: transcripts/README.md) through the protocol parsers, each VAL II reply whole and
// one byte at a time, checking its expectations with Catch2 (`file` names it in the messages).
// Returns the number of expectations checked.
#pragma once

#include <string>

namespace robocal::test {

int replayTranscript(const std::string& text, const std::string& file);

}  // namespace robocal::test

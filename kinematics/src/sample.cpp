#include <robocal/kinematics/sample.hpp>

#include <stdexcept>
#include <vector>

namespace robocal {

std::string connectionName(const Connection& c) {
  return "B" + std::to_string(c.ball_index + 1) + "C" + std::to_string(c.chuck_index + 1);
}

std::string connectionList(const std::vector<Connection>& connections) {
  std::string out;
  for (const Connection& c : connections) out += (out.empty() ? "" : ",") + connectionName(c);
  return out;
}

std::vector<Connection> allConnections() {
  std::vector<Connection> all;
  for (int b = 0; b < kBallCount; ++b)
    for (int c = 0; c < kChuckCount; ++c) all.push_back({b, c});
  return all;
}

std::vector<Connection> parseConnections(const std::string& text) {
  if (text == "all") return allConnections();
  std::vector<Connection> out;
  size_t start = 0;
  while (start <= text.size()) {
    size_t comma = text.find(',', start);
    if (comma == std::string::npos) comma = text.size();
    const std::string item = text.substr(start, comma - start);
    const bool ok = item.size() == 4 && (item[0] == 'B' || item[0] == 'b') &&
                    (item[2] == 'C' || item[2] == 'c') && item[1] >= '1' &&
                    item[1] < '1' + kBallCount && item[3] >= '1' && item[3] < '1' + kChuckCount;
    if (!ok)
      throw std::invalid_argument("bad connection '" + item +
                                  "': expected B<ball 1-3>C<chuck 1-3>, e.g. B1C2, or 'all'");
    const Connection c{item[1] - '1', item[3] - '1'};
    for (const Connection& seen : out)
      if (seen == c) throw std::invalid_argument("connection " + item + " given twice");
    out.push_back(c);
    start = comma + 1;
  }
  return out;
}

}  // namespace robocal

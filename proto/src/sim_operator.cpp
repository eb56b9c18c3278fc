#include <robocal/proto/sim_operator.hpp>

#include <cstdio>

namespace robocal::proto {

std::vector<std::string> answerPrompt(Client& client, const nlohmann::json& prompt,
                                      const CellsimControl& control, const std::string& token,
                                      double bar_mm) {
  std::vector<std::string> actions;
  const int shell = prompt.value("shell", 0);
  std::string command = "connect none";
  if (prompt.value("action", "") == "connect") {
    char buf[160];
    std::snprintf(buf, sizeof buf, "connect B%dC%d extension_mm=%g bar_mm=%g",
                  prompt.value("ball", 0), prompt.value("chuck", 0),
                  prompt.value("extension_mm", 0.0), bar_mm);
    command = buf;
  }
  for (int attempt = 0;; ++attempt) {
    const std::string reply = control(command);
    actions.push_back(command + " -> " + reply);
    if (reply.rfind("ok", 0) == 0) break;
    // "does not fit: ... move the ball by -1.234 mm along the bar ...": ask robocald to move it.
    const auto at = reply.find("move the ball by ");
    if (attempt >= 4 || at == std::string::npos)
      throw ClientError("the simulated operator cannot connect the bar: " + reply);
    const double mm = std::stod(reply.substr(at + 17));
    client.send({{"cmd", "nudge"}, {"shell", shell}, {"mm", mm}, {"token", token}});
    actions.push_back("nudge " + std::to_string(mm) + " mm");
    while (true) {
      const auto o = client.read(30.0);
      if (!o) throw ClientError("robocald did not carry out the nudge within 30 s");
      if (o->value("class", "") == "ERROR")
        throw ClientError("robocald refused the nudge: " + o->value("message", ""));
      if (o->value("class", "") == "EVENT" && o->value("event", "") == "nudged") break;
    }
  }
  client.send({{"cmd", "confirm"}, {"shell", shell}, {"token", token}});
  return actions;
}

}  // namespace robocal::proto

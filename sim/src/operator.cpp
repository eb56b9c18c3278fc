#include <robocal/sim/operator.hpp>

#include <cstdio>

namespace robocal::sim {

using proto::ClientError;

std::vector<std::string> answerPrompt(proto::Client& client, const proto::Prompt& prompt,
                                      const CellsimControl& control, const std::string& token,
                                      double bar_mm) {
  std::vector<std::string> actions;
  const int shell = prompt.shell;
  std::string command = "connect none";
  if (prompt.action == proto::PromptAction::kConnect) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "connect B%dC%d extension_mm=%g bar_mm=%g",
                  prompt.ball.value_or(0), prompt.chuck.value_or(0),
                  prompt.extension_mm.value_or(0.0), bar_mm);
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
      const std::string cls = proto::objectClass(*o);
      if (cls == proto::Error::kClass)
        throw ClientError("robocald refused the nudge: " +
                          proto::parseObject<proto::Error>(*o).message);
      if (cls == proto::Event::kClass && proto::parseObject<proto::Event>(*o).event == "nudged")
        break;
    }
  }
  client.send({{"cmd", "confirm"}, {"shell", shell}, {"token", token}});
  return actions;
}

}  // namespace robocal::sim

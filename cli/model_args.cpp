#include "model_args.hpp"

#include <robocal/formats/csv.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/robot/builtin.hpp>

#include <cmath>
#include <cstdio>

namespace robocal::cli {

Model nominalFor(const Args& args, const Model& calibrated, const char* command,
                 const char* model_key) {
  const std::string model_path = args.get(model_key, "");
  const std::optional<Model> recorded = recordedNominal(calibrated);
  if (args.has("nominal")) {
    const std::string path = args.get("nominal", "");
    Model given = loadModelFile(path);
    if (given.compliance) given.compliance->deg_per_nm = {};  // the controller's model is rigid
    if (recorded) {
      if (const auto difference = parameterDifference(given, *recorded))
        throw UsageError("--nominal " + path + " is not the nominal " + model_path +
                         " was calibrated from (recorded in it): " + *difference +
                         "; compensating against another nominal gives wrong joints. Leave "
                         "--nominal out to use the recorded one");
    }
    return given;
  }
  if (recorded) {
    std::fprintf(stderr, "robocal %s: nominal: \"%s\", the one %s was calibrated from\n", command,
                 recorded->name.c_str(), model_path.c_str());
    return *recorded;
  }
  // No record: the built-in model of the name it was fitted from (or its own name, when it is a
  // nominal model itself); any other arm's nominal must be named.
  const std::string from =
      calibrated.provenance ? calibrated.provenance->nominal_name : calibrated.name;
  const std::optional<Model> builtin = builtinNominalModel(from);
  if (!builtin)
    throw UsageError(model_path +
                     " does not record the nominal it was calibrated from (a nominal " +
                     "model, or one fitted before robocal recorded it), and \"" + from +
                     "\" is not a model robocal carries (" + builtinNominalNames() +
                     "): give --nominal FILE, the controller's model the calibration started from");
  std::fprintf(stderr,
               "robocal %s: nominal: the built-in \"%s\" (%s does not record its nominal: a "
               "nominal model, or one fitted before robocal recorded it; --nominal names yours)\n",
               command, builtin->name.c_str(), model_path.c_str());
  return *builtin;
}

std::optional<double> approachDegArg(const Args& args) {
  if (!args.has("approach-deg")) return std::nullopt;
  const double deg = args.number("approach-deg", 0);
  if (!(deg >= 0 && deg <= 1)) throw UsageError("--approach-deg must be 0 to 1 (deg)");
  return deg;
}

void applyPayloadArgs(const Args& args, Model& model) {
  if (!args.has("payload-kg") && !args.has("payload-com")) return;
  if (!model.compliance || !model.compliance->twists())
    throw UsageError(
        "--payload-kg/--payload-com: the model " + args.get("model", "") +
        " carries no compliance (its joints' twist under gravity): a payload changes nothing "
        "without it (robocal solve --compliance)");
  GravityLoad& load = model.compliance->load;
  if (args.has("payload-kg")) {
    load.payload_kg = args.number("payload-kg", 0);
    if (!(load.payload_kg >= 0 && load.payload_kg <= 1000))
      throw UsageError("--payload-kg must be 0 to 1000 (kg), got " + args.get("payload-kg", ""));
  }
  if (args.has("payload-com")) {
    const std::string text = args.get("payload-com", "");
    const UsageError bad("--payload-com: expected x,y,z in mm (the last link's frame), got \"" +
                         text + "\"");
    const auto fields = csv::splitFields(text);
    if (fields.size() != 3) throw bad;
    for (int i = 0; i < 3; ++i) {
      const auto v = csv::number(fields[i]);
      if (!v || std::abs(*v) > 1e4) throw bad;
      load.payload_com_mm[i] = *v;
    }
  }
}

}  // namespace robocal::cli

// A health verdict (health.hpp) as text and as JSON, the same for `robocal health` and for a
// client of robocald's check run, next to the fit's report (report.hpp). No I/O.
#pragma once

#include <robocal/solver/health.hpp>

#include <nlohmann/json.hpp>
#include <string>

namespace robocal {

// Exit status of `robocal health` (docs/health-check.md): 0 pass, 4 warn, 5 fail.
inline constexpr int kHealthExitPass = 0;
inline constexpr int kHealthExitWarn = 4;
inline constexpr int kHealthExitFail = 5;
int healthExitStatus(HealthStatus status);

// The verdict for a person: "health check: PASS" and the reason, the samples, the residuals
// against the reference with the ratio and its expected scatter, the residual per shell, what
// moved (with the parameters the data cannot tell it from) and the RMS left after refitting it.
// Lines end with a newline.
std::string healthVerdictText(const HealthVerdict& verdict);

// The verdict as one object: status ("pass", "warn", "fail"), reason, samples, connections,
// extensions_mm, rms_mm, mean_mm, max_abs_mm, reference_rms_mm, reference ("baseline",
// "calibration", "fallback"), rms_ratio, ratio_scatter, warn_ratio, fail_ratio, noise_mm,
// check_level_mm, model_covariance, moved (name,
// unit, change_<unit>, sigma_<unit>, prior_sigma_<unit>, significance, prior_ratio, text,
// equivalent), refit_rms_mm, refit_ratio, worst_shells, shells (docs/health-check.md).
nlohmann::ordered_json healthVerdictJson(const HealthVerdict& verdict);

}  // namespace robocal

#pragma once
// The pass strategy (Strategy::passes); see passes.cpp. Internal to tom::builder.

#include "parallel.h"
#include "tom/builder/builder.h"

namespace tom::build_detail {

struct Builder;

/// Substitutes until no legal substitution is left, in passes that may each remove up to
/// `fraction` of the live vertices. `foresight` lets the team foresee the loop's verdicts and
/// costs; the result is the same either way.
void run_passes(Builder& b, float fraction, bool foresight, detail::Team& team, BuildStats& stats, const std::function<void(double)>& progress = {});

} // namespace tom::build_detail

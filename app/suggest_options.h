#pragma once
/// \file suggest_options.h
/// `pandora suggest`'s options turned into the library's SuggestOptions: the selection by camera
/// id, per-camera limits ("one value, or one per selected camera"), mounts and zoom ranges ("ID:"
/// prefixes), keep-out boxes, the objective. Every error names the option the user typed.

#include "app/commands.h"
#include "app/session/session.h"
#include "suggest/suggest.h"

namespace pandora::app {

/// The session of a suggest run: the scene file, --rig and --disable.
session::SessionOptions SuggestSessionOptions(const SuggestArgs& args);

SuggestOptions SuggestOptionsFromArgs(const SuggestArgs& args, const Scene& scene, const Rig& rig);

/// The enabled PTZ camera `id` of `rig` (its index), or InputError naming `option` with the rig's
/// PTZ cameras as the hint.
int PtzCameraOption(const Rig& rig, const std::string& option, const std::string& id);

/// SampleTargets over the study region, or over the study's region `region` when it is not empty
/// (InputError naming `option` and the study's regions when there is none of that name).
std::vector<TargetPoint> SampleTargetsInRegion(const Scene& scene, const std::string& option, const std::string& region,
                                               int points, const std::vector<std::string>& surfaces, bool with_region,
                                               std::uint64_t seed);

}  // namespace pandora::app
